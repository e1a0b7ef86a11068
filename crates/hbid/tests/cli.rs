//! The `hbid` binary as a user runs it.
use crate::support::hbid;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn scratch(name: &str) -> PathBuf {
    crate::support::scratch("cli", name)
}

fn read_rows(path: &Path) -> (String, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header = lines.next().unwrap().to_owned();
    let rows = lines
        .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
        .collect();
    (header, rows)
}

/// `text` (a header line, then rows) with each row `i` (from 0) replaced by `edit(i, row)`, or
/// left out where that gives `None`: a logger's faults written into a record.
fn rows_edited(text: &str, mut edit: impl FnMut(usize, &str) -> Option<String>) -> String {
    let mut lines = text.lines();
    let mut out = format!("{}\n", lines.next().unwrap());
    for (i, line) in lines.enumerate() {
        if let Some(row) = edit(i, line) {
            out.push_str(&row);
            out.push('\n');
        }
    }
    out
}

fn assert_clean_failure(out: &Output, mentions: &str) {
    assert!(!out.status.success(), "expected failure");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "panic: {err}");
    assert_eq!(err.trim().lines().count(), 1, "one line expected: {err}");
    assert!(
        err.to_lowercase().contains(mentions),
        "'{mentions}' not in: {err}"
    );
}

/// The error line of a command that failed (without a panic); its other lines are notes.
fn error_line(out: &Output, args: &[&str]) -> String {
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && !err.contains("panicked"),
        "{args:?}: {err}"
    );
    err.lines()
        .find(|l| l.starts_with("error:"))
        .expect("an error line")
        .to_owned()
}

#[test]
fn simulate_matches_reference_fixture() {
    let dir = scratch("ref");
    let out_path = dir.join("ref.csv");
    let out = hbid(&[
        "simulate",
        "--transient-periods",
        "0",
        "--samples",
        "201",
        "--unwrapped",
        "--rtol",
        "1e-12",
        "--out",
        out_path.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let (header, ours) = read_rows(&out_path);
    assert_eq!(header, "t,theta,omega");
    let fixture =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/fixtures/reference_trajectory.csv");
    let (_, reference) = read_rows(&fixture);
    assert_eq!(ours.len(), reference.len());
    let worst = ours
        .iter()
        .zip(&reference)
        .map(|(a, b)| (a[1] - b[1]).abs())
        .fold(0.0, f64::max);
    assert!(worst <= 1e-8, "largest theta error {worst:e}");
}

#[test]
fn simulate_wraps_and_starts_after_transient() {
    let dir = scratch("wrap");
    let p = dir.join("w.csv");
    let out = hbid(&[
        "simulate",
        "--samples",
        "500",
        "--transient-periods",
        "20",
        "--out",
        p.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    let (_, rows) = read_rows(&p);
    assert_eq!(rows.len(), 500);
    assert!((rows[0][0] - 20.0 * std::f64::consts::TAU).abs() < 1e-12);
    let pi = std::f64::consts::PI;
    assert!(rows.iter().all(|r| (-pi..pi).contains(&r[1])));
}

#[test]
fn noise_is_seeded() {
    let dir = scratch("noise");
    let run = |seed: &str, name: &str| {
        let p = dir.join(name);
        let out = hbid(&[
            "simulate",
            "--samples",
            "300",
            "--transient-periods",
            "5",
            "--noise",
            "0.05",
            "--seed",
            seed,
            "--out",
            p.to_str().unwrap(),
        ]);
        assert!(out.status.success());
        read_rows(&p).1
    };
    let clean = {
        let p = dir.join("clean.csv");
        assert!(
            hbid(&[
                "simulate",
                "--samples",
                "300",
                "--transient-periods",
                "5",
                "--out",
                p.to_str().unwrap()
            ])
            .status
            .success()
        );
        read_rows(&p).1
    };
    let a = run("7", "a.csv");
    let b = run("7", "b.csv");
    let c = run("8", "c.csv");
    assert_eq!(a, b);
    assert_ne!(a, c);
    // The noise has about the requested size, and omega is untouched.
    let diffs: Vec<f64> = a
        .iter()
        .zip(&clean)
        .map(|(n, c)| circle_signal::wrap(n[1] - c[1]))
        .collect();
    let sd = (diffs.iter().map(|d| d * d).sum::<f64>() / diffs.len() as f64).sqrt();
    assert!((sd - 0.05).abs() < 0.01, "noise sd {sd}");
    assert!(a.iter().zip(&clean).all(|(n, c)| n[2] == c[2]));
}

#[test]
fn bad_options_fail_cleanly_without_output() {
    let dir = scratch("bad");
    let target = dir.join("never.csv");
    let t = target.to_str().unwrap();
    for (args, mentions) in [
        (vec!["--samples", "0"], "samples"),
        (vec!["--samples-per-period", "0"], "--samples-per-period 0"),
        (vec!["--r", "0"], "r"),
        (vec!["--rtol", "-1e-6"], "rtol"),
        (vec!["--noise", "-1"], "noise"),
    ] {
        let mut all = vec!["simulate"];
        all.extend(args);
        all.extend(["--out", t]);
        assert_clean_failure(&hbid(&all), mentions);
        assert!(!target.exists());
    }
    let missing = dir.join("no/such/folder/x.csv");
    assert_clean_failure(
        &hbid(&["simulate", "--out", missing.to_str().unwrap()]),
        "does not exist",
    );
    assert!(!missing.exists());
    // Nothing half-written is left in the folder either.
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
}

/// The true coefficients of the paper's pendulum with the harmonic basis K = 1, by term name.
fn pendulum_truth() -> Vec<(String, f64)> {
    pendulum_sim::truth::pendulum_model::<hb_basis::Harmonic>(&pendulum_sim::Pendulum::paper())
        .unwrap()
        .coefficients()
        .iter()
        .map(|c| (c.name.clone(), c.value))
        .collect()
}

/// The true coefficients of the Duffing record: the model stands as
/// x'' + c x' + q1 x + q2 x² + q3 x³ + F_c cos(t) + F_s sin(t) + ... = 0.
const DUFFING_TRUTH: [(&str, f64); 6] = [
    ("x'", 0.3),
    ("x", -1.0),
    ("x^2", 0.0),
    ("x^3", 1.0),
    ("cos(t)", -0.5),
    ("sin(t)", 0.0),
];

fn paper_dataset() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/fixtures/paper_dataset.csv")
        .to_str()
        .unwrap()
        .to_owned()
}

#[test]
fn embed_json_on_the_paper_data_set() {
    let out = hbid(&["embed", &paper_dataset(), "--json", "--max-dim", "6"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["delay"], 5);
    // Lags 0 to two forcing periods (25 samples each).
    assert_eq!(v["ami"].as_array().unwrap().len(), 51);
    let fnn: Vec<f64> = v["fnn"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_f64().unwrap())
        .collect();
    assert_eq!(fnn.len(), 6);
    assert!(fnn.windows(2).all(|w| w[1] <= w[0] + 1e-12), "{fnn:?}");
    assert_eq!(v["embedding_dimension"], 4);
}

#[test]
fn upos_json_counts_are_consistent() {
    let out = hbid(&["upos", &paper_dataset(), "--json", "--max-period", "6"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let segments = v["segments"].as_u64().unwrap();
    let by_period: u64 = v["by_period"]
        .as_object()
        .unwrap()
        .values()
        .map(|n| n.as_u64().unwrap())
        .sum();
    let distinct: u64 = v["distinct_by_period"]
        .as_object()
        .unwrap()
        .values()
        .map(|n| n.as_u64().unwrap())
        .sum();
    assert_eq!(segments, by_period);
    assert_eq!(v["distinct_orbits"].as_u64().unwrap(), distinct);
    assert!(distinct <= segments && segments > 0);
    let orbits = v["orbits"].as_array().unwrap();
    assert_eq!(orbits.len() as u64, segments);
    let eps = 0.03 * std::f64::consts::TAU;
    assert!(
        orbits
            .iter()
            .all(|o| o["error"].as_f64().unwrap() < eps && o["period"].as_u64().unwrap() <= 6)
    );
}

#[test]
fn analysis_options_are_checked() {
    let data = paper_dataset();
    for (args, mentions) in [
        (vec!["embed", &data, "--bins", "1"], "bins"),
        (vec!["embed", &data, "--max-dim", "0"], "max-dim"),
        (vec!["upos", &data, "--tolerance", "0"], "tolerance"),
        (vec!["upos", &data, "--tolerance", "0.5"], "tolerance"),
        (vec!["upos", &data, "--max-period", "0"], "--max-period 0"),
        (vec!["upos", &data, "--drive-period", "-1"], "drive-period"),
        (vec!["upos", &data, "--drive-frequency", "0"], "drive-frequency"),
        // The old names still work.
        (vec!["upos", &data, "--forcing-period", "-1"], "drive-period"),
        (
            vec!["upos", &data, "--drive-period", "auto:2..x"],
            "'x' is not a number",
        ),
        (
            vec!["upos", &data, "--drive-period", "auto:3"],
            "expected a number, auto, auto:a..b or none",
        ),
        (vec!["upos", "/no/such/file.csv"], "no/such/file.csv"),
        (vec!["upos", "/tmp"], "folder"),
    ] {
        assert_clean_failure(&hbid(&args), mentions);
    }
}

#[test]
fn bad_files_name_the_problem() {
    let dir = scratch("badfiles");
    for (name, content, mentions) in [
        ("empty.csv", "", "empty"),
        ("header.csv", "t,theta\n", "no data"),
        ("cell.csv", "t,theta\n0,1\n0.25,x\n", "line 3"),
        ("nan.csv", "t,theta\n0,1\n0.25,nan\n", "line 3"),
        ("ragged.csv", "t,theta\n0,1\n0.25\n", "line 3"),
        (
            "decreasing.csv",
            "t,theta\n0,1\n0.25,1\n0.2,1\n",
            "does not increase",
        ),
        (
            "glitch.csv",
            "t,theta\n0,1\n0.25,1\n0.6,1\n0.75,1\n1,1\n",
            "line 4: time 0.6 does not fit the grid",
        ),
        (
            "mixed.csv",
            "t,theta\n0,1\n0.25;1\n",
            "line 3: cells separated by semicolons",
        ),
        (
            "short.csv",
            "t,theta\n0,1\n0.25132741228718347,1\n0.5026548245743669,1\n",
            "short",
        ),
    ] {
        let p = dir.join(name);
        std::fs::write(&p, content).unwrap();
        assert_clean_failure(&hbid(&["upos", p.to_str().unwrap(), "--delay", "5"]), mentions);
    }
    let garbage = dir.join("garbage.bin");
    std::fs::write(&garbage, [0u8, 159, 146, 150, 255, 0, 1, 2]).unwrap();
    assert_clean_failure(&hbid(&["upos", garbage.to_str().unwrap()]), "line");
}

/// A record where no window of the weak form fits says so in one line, naming the window and
/// the longest stretch, and writes no model: one too short, and one whose logger dropped every
/// seventh row (gaps a window never spans), of one coordinate and of two.
#[test]
fn a_record_no_window_fits_is_named_and_writes_nothing() {
    let dir = scratch("nowindow");
    let model = dir.join("model.json");
    // `hbid identify` of `record` with `options` fails in one error line that says `mentions`
    // and names --window, and writes no model.
    let refused = |record: &Path, options: &[&str], mentions: &str| {
        let mut args = vec![
            "identify",
            record.to_str().unwrap(),
            "--quiet",
            "--save-model",
            model.to_str().unwrap(),
        ];
        args.extend_from_slice(options);
        let line = error_line(&hbid(&args), &args);
        assert!(line.contains(mentions), "'{mentions}' not in: {line}");
        assert!(line.contains("--window"), "{line}");
        assert!(!model.exists(), "a model was written");
    };
    // Every seventh row of a text with a header line dropped.
    let drop_sevenths = |text: &str| rows_edited(text, |i, row| (i % 7 != 3).then(|| row.to_owned()));
    let paper: String = std::iter::once("t,theta".to_owned())
        .chain(
            paper_rows()
                .into_iter()
                .take(3000)
                .map(|(t, x)| format!("{t},{x}")),
        )
        .collect::<Vec<_>>()
        .join("\n");
    let short = dir.join("short.csv");
    std::fs::write(&short, paper.lines().take(61).collect::<Vec<_>>().join("\n")).unwrap();
    refused(
        &short,
        &[],
        "no window fits in the record: it has 60 samples, and a window of 3 drive periods holds 76",
    );
    let dropped = dir.join("dropped.csv");
    std::fs::write(&dropped, drop_sevenths(&paper)).unwrap();
    let gaps = "no window fits between the record's gaps: its longest stretch without one has 6 samples";
    refused(&dropped, &[], gaps);
    // A system: the double pendulum's two angles, the same rows dropped from both.
    let dp = dir.join("dp.csv");
    let out = hbid(&[
        "simulate",
        "--system",
        "double-pendulum",
        "--samples",
        "3000",
        "--out",
        dp.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    std::fs::write(&dp, drop_sevenths(&std::fs::read_to_string(&dp).unwrap())).unwrap();
    refused(&dp, &["--coords", "theta1,theta2"], gaps);
}

/// A rig's record too short for the close-return search's longest period (here because its
/// drive, 1.3 Hz at 500 Hz, is not given: one drive period of 2π s is 3142 samples) is told in
/// one line that names the samples needed and the options that change them, and nothing is
/// written.
#[test]
fn a_record_too_short_for_the_orbit_or_delay_search_is_named_and_writes_nothing() {
    let dir = scratch("noorbit");
    // A rig's record of `samples` at 500 Hz under a 1.3 Hz drive.
    let rig = |name: &str, samples: &str| {
        simulated(
            &dir,
            name,
            &[
                "--drive-frequency",
                "1.3",
                "--sample-rate",
                "500",
                "--samples",
                samples,
            ],
        )
    };
    let record = rig("rig.csv", "20000");
    let model = dir.join("model.json");
    let report = dir.join("rep");
    for args in [
        vec![
            "identify",
            record.to_str().unwrap(),
            "--method",
            "upo",
            "--save-model",
            model.to_str().unwrap(),
        ],
        vec!["upos", record.to_str().unwrap()],
        vec![
            "report",
            record.to_str().unwrap(),
            "--out",
            report.to_str().unwrap(),
        ],
    ] {
        let line = error_line(&hbid(&args), &args);
        for mentions in [
            "too short for the close-return search: orbits of up to 16 drive periods need 50359 samples",
            "one drive period is 3142 samples",
            "--max-period",
            "--drive-frequency",
        ] {
            assert!(line.contains(mentions), "{args:?}: '{mentions}' not in: {line}");
        }
        assert!(!model.exists() && !report.exists(), "{args:?} wrote a file");
    }
    // Shorter still, the delay's search (two drive periods of lags) is what does not fit: each
    // command names what its user can give.
    let short = rig("short.csv", "3000");
    for (args, remedy) in [
        (
            vec!["identify", short.to_str().unwrap(), "--method", "upo"],
            "give the delay itself (--delay)",
        ),
        (
            vec!["upos", short.to_str().unwrap()],
            "give the delay itself (--delay)",
        ),
        (vec!["embed", short.to_str().unwrap()], "give a smaller --max-lag"),
        // The report draws the curve whatever the delay.
        (
            vec![
                "report",
                short.to_str().unwrap(),
                "--out",
                report.to_str().unwrap(),
            ],
            "give a longer record",
        ),
    ] {
        let line = error_line(&hbid(&args), &args);
        for mentions in [
            "too short for the delay's search: the mutual information is taken to a lag of 6284 samples",
            "the record has 2872",
            remedy,
            "one drive period is 3142 samples",
        ] {
            assert!(line.contains(mentions), "{args:?}: '{mentions}' not in: {line}");
        }
        assert!(!report.exists(), "{args:?} wrote a file");
    }
}

/// The paper's data set as `(t, theta)` rows.
fn paper_rows() -> Vec<(String, String)> {
    std::fs::read_to_string(paper_dataset())
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with('t'))
        .map(|l| {
            let (t, theta) = l.split_once(',').unwrap();
            (t.to_owned(), theta.to_owned())
        })
        .collect()
}

#[test]
fn reads_records_as_acquisition_programs_write_them() {
    let dir = scratch("daq");
    let rows = paper_rows();
    let reference = hbid(&["embed", &paper_dataset(), "--json", "--max-dim", "4"]);
    assert!(reference.status.success());
    let spaced: String = std::iter::once("   t        theta\n".to_owned())
        .chain(rows.iter().map(|(t, x)| format!("  {t}  \t {x}\n")))
        .collect();
    // No header, the angle first, tabs.
    let swapped: String = rows.iter().map(|(t, x)| format!("{x}\t{t}\n")).collect();
    for (name, text) in [("spaced.txt", spaced), ("swapped.tsv", swapped)] {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let out = hbid(&["embed", path.to_str().unwrap(), "--json", "--max-dim", "4"]);
        assert!(
            out.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert_eq!(out.stdout, reference.stdout, "{name}");
        assert!(
            out.stderr.is_empty(),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

#[test]
fn a_time_stamp_glitch_is_named_and_repaired() {
    let dir = scratch("glitch");
    let mut rows = paper_rows();
    // Sample 1000, on line 1001 of a file with a header: a third of a step late.
    let t: f64 = rows[999].0.parse().unwrap();
    let late = t + std::f64::consts::TAU / 25.0 / 3.0;
    rows[999].0 = late.to_string();
    let text: String = std::iter::once("t,theta\n".to_owned())
        .chain(rows.iter().map(|(t, x)| format!("{t},{x}\n")))
        .collect();
    let path = dir.join("glitch.csv");
    std::fs::write(&path, text).unwrap();
    let path = path.to_str().unwrap();
    let out = hbid(&["embed", path, "--json", "--max-dim", "4"]);
    assert_clean_failure(&out, "line 1001: time");
    assert_clean_failure(&out, "run with --repair");
    let repaired = hbid(&["embed", path, "--json", "--max-dim", "4", "--repair"]);
    assert!(
        repaired.status.success(),
        "{}",
        String::from_utf8_lossy(&repaired.stderr)
    );
    let note = String::from_utf8_lossy(&repaired.stderr);
    let now: f64 = note
        .trim()
        .strip_prefix(&format!(
            "note: line 1001: time {late} replaced by its grid time "
        ))
        .unwrap_or_else(|| panic!("{note}"))
        .parse()
        .unwrap();
    assert!((now - t).abs() < 1e-9, "{now} vs {t}");
    let reference = hbid(&["embed", &paper_dataset(), "--json", "--max-dim", "4"]);
    assert_same_analysis(&repaired.stdout, &reference.stdout, 1e-9);
}

/// Two JSON results with the same analysis: equal but for the record's description, whose
/// fitted start time may differ by `start_tolerance` (a repaired stamp, or a record read with
/// `--dt`, moves the fitted grid's origin, which no analysis sees).
fn assert_same_analysis(a: &[u8], b: &[u8], start_tolerance: f64) {
    let mut a: serde_json::Value = serde_json::from_slice(a).unwrap();
    let mut b: serde_json::Value = serde_json::from_slice(b).unwrap();
    let (ra, rb) = (a["record"].take(), b["record"].take());
    assert_eq!(a, b);
    for key in [
        "samples",
        "step",
        "samples_per_period",
        "period",
        "pieces",
        "signal",
    ] {
        assert_eq!(ra[key], rb[key], "record's {key}");
    }
    let (sa, sb) = (ra["start"].as_f64().unwrap(), rb["start"].as_f64().unwrap());
    assert!((sa - sb).abs() <= start_tolerance, "start {sa} vs {sb}");
}

#[test]
fn identify_json_recovers_the_pendulum_and_saves_the_model() {
    let dir = scratch("identify");
    let model_path = dir.join("model.json");
    let out = hbid(&[
        "identify",
        &paper_dataset(),
        "--method",
        "upo",
        "--json",
        "--save-model",
        model_path.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["method"], "upo");
    assert_eq!(v["basis"], "harmonic:1");
    for (name, value) in &pendulum_truth() {
        let got = v["coefficients"][name]
            .as_f64()
            .unwrap_or_else(|| panic!("no {name}"));
        assert!((got - value).abs() < 0.005, "{name}: {got} vs {value}");
        assert!(v["std_errors"][name].as_f64().unwrap() > 0.0);
    }
    assert!(v["orbits_used"].as_u64().unwrap() > 0 && v["rows"].as_u64().unwrap() > 7);
    assert!(v["condition_number"].as_f64().unwrap() >= 1.0);
    let saved = std::fs::read_to_string(&model_path).unwrap();
    let model = hb_model::IdentifiedModel::<hb_basis::BasisKind>::from_json(&saved).unwrap();
    assert_eq!(model.damping(), v["coefficients"]["x'"].as_f64().unwrap());
}

#[test]
fn identify_refuses_bad_options_and_too_few_orbits() {
    let data = paper_dataset();
    for (args, mentions) in [
        (vec!["identify", &data, "--basis", "bogus:3"], "bogus"),
        (vec!["identify", &data, "--basis", "harmonic:0"], "harmonic"),
        (vec!["identify", &data, "--basis", ""], "harmonic:k"),
        (vec!["identify", &data, "--harmonics", "0"], "harmonics"),
        (vec!["identify", &data, "--tolerance", "0.7"], "tolerance"),
        (
            vec!["identify", &data, "--method", "upo", "--tolerance", "0.0001"],
            "too few segments (orbits or windows): 0 found but at least",
        ),
        (vec!["identify", &data, "--method", "magic"], "magic"),
    ] {
        let out = hbid(&args);
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr).to_lowercase();
        assert!(!err.contains("panicked"), "{err}");
        assert!(err.contains(mentions), "'{mentions}' not in {err}");
    }
}

/// A chaotic Duffing oscillator, x'' + 0.3 x' − x + x³ = 0.5 cos(1.2 t), written as a record with
/// 50 samples per forcing period.
fn duffing_record(dir: &Path) -> PathBuf {
    struct Duffing;
    impl pendulum_sim::SecondOrderSystem for Duffing {
        fn acceleration(&self, t: f64, x: f64, v: f64) -> f64 {
            0.5 * (1.2 * t).cos() - 0.3 * v + x - x * x * x
        }
        fn jacobian(&self, _t: f64, x: f64, _v: f64) -> [f64; 2] {
            [1.0 - 3.0 * x * x, -0.3]
        }
    }
    let period = std::f64::consts::TAU / 1.2;
    let cfg = pendulum_sim::SimulationConfig::paper()
        .with_drive_period(period)
        .unwrap()
        .with_samples_per_period(50)
        .unwrap()
        .with_samples(50 * 800)
        .unwrap()
        .with_transient_periods(100)
        .with_tolerances(pendulum_sim::Tolerances::relative(1e-12).unwrap());
    let traj = pendulum_sim::simulate(&Duffing, &cfg).unwrap();
    let path = dir.join("duffing.csv");
    let mut text = String::from("t,theta\n");
    for (t, x) in traj.t.iter().zip(&traj.theta) {
        text.push_str(&format!("{t},{x}\n"));
    }
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn identify_a_duffing_oscillator_on_the_line() {
    let dir = scratch("duffing");
    let record = duffing_record(&dir);
    let period = (std::f64::consts::TAU / 1.2).to_string();
    let out = hbid(&[
        "identify",
        record.to_str().unwrap(),
        "--signal",
        "line",
        "--forcing-period",
        &period,
        "--json",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["basis"], "poly:3");
    let c = &v["coefficients"];
    // The model stands as x'' + c x' + q1 x + q2 x² + q3 x³ + F_c cos(t) + F_s sin(t) + ... = 0.
    let worst = DUFFING_TRUTH
        .iter()
        .map(|(n, t)| (c[*n].as_f64().unwrap() - t).abs())
        .fold(0.0, f64::max);
    // Measured: 0.010 (the weak form does far better on the same record).
    assert!(worst < 0.02, "largest error {worst:e}: {c}");
}

#[test]
fn report_writes_markdown_figures_and_model() {
    let dir = scratch("report");
    let out_dir = dir.join("rep");
    let out = hbid(&[
        "report",
        &paper_dataset(),
        "--out",
        out_dir.to_str().unwrap(),
        "--validation-periods",
        "300",
        "--bootstrap",
        "100",
        "--quiet",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = std::fs::read_to_string(out_dir.join("README.md")).unwrap();
    for needle in [
        "Delay (first minimum",
        "| period | segments |",
        "`sin(t)*cos(x)`",
        "Lyapunov",
        "energy distance",
    ] {
        assert!(text.contains(needle), "{needle} missing");
    }
    for file in [
        "ami.png",
        "fnn.png",
        "section_record.png",
        "section_model_upo.png",
        "section_model_windowed.png",
        "model_upo.json",
        "model_windowed.json",
    ] {
        assert!(
            std::fs::metadata(out_dir.join(file)).unwrap().len() > 100,
            "{file}"
        );
    }
    let file = dir.join("plain");
    std::fs::write(&file, "x").unwrap();
    assert_clean_failure(
        &hbid(&["report", &paper_dataset(), "--out", file.to_str().unwrap()]),
        "not a folder",
    );
}

/// A record in seconds read without its drive: the paper's period of 2π seconds fits neither
/// method's model, whose free runs blow up. The report is still written, with each model's
/// coefficients and what stopped its validation, and says so on stderr; identify's warning says
/// that no drive was given and how to give it.
#[test]
fn report_states_a_model_that_cannot_be_run_freely() {
    let dir = scratch("report-unrunnable");
    let record = simulated(
        &dir,
        "seconds.csv",
        &[
            "--drive-frequency",
            "1.3",
            "--sample-rate",
            "500",
            "--samples",
            "52000",
        ],
    );
    let r = record.to_str().unwrap();
    let out_dir = dir.join("rep");
    let out = hbid(&[
        "report",
        r,
        "--out",
        out_dir.to_str().unwrap(),
        "--validation-periods",
        "50",
        "--bootstrap",
        "0",
        "--quiet",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("warning: the model of the windowed method cannot be run freely"),
        "{stderr}"
    );
    let text = std::fs::read_to_string(out_dir.join("README.md")).unwrap();
    assert!(
        text.contains("| windowed | cannot be run freely (below) |"),
        "{text}"
    );
    assert!(
        text.contains("**Not validated:** the model of the windowed method cannot be run freely"),
        "{text}"
    );
    // Why the run stopped, from the simulation's own error.
    assert!(text.contains("steps before t ="), "{text}");
    assert!(text.contains("`sin(t)*cos(x)`"), "{text}");
    assert!(out_dir.join("model_windowed.json").exists());
    assert!(!out_dir.join("section_model_windowed.png").exists());

    let out = hbid(&["identify", r, "--bootstrap", "0", "--quiet"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains(
            "no drive was given, so its period is 2π in the record's time unit (the paper's non-dimensional \
             time): for a record in seconds give --drive-frequency in hertz, or --drive-frequency auto"
        ),
        "{stderr}"
    );
    // Too short for windows of 2π seconds: the warning of too few windows says why.
    let short = simulated(
        &dir,
        "short.csv",
        &[
            "--drive-frequency",
            "1.3",
            "--sample-rate",
            "500",
            "--samples",
            "20000",
        ],
    );
    let out = hbid(&["identify", short.to_str().unwrap(), "--bootstrap", "0", "--quiet"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("no drive was given, so the windows' unit is the paper's period of 2π"),
        "{stderr}"
    );
    // Given, the same record is described.
    let out = hbid(&[
        "identify",
        r,
        "--drive-frequency",
        "auto",
        "--bootstrap",
        "0",
        "--quiet",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success() && !stderr.contains("warning"), "{stderr}");
}

/// `--method` given, the report identifies by that method alone (both otherwise).
#[test]
fn report_identifies_by_the_method_given() {
    let dir = scratch("report-method");
    let out_dir = dir.join("rep");
    let out = hbid(&[
        "report",
        &paper_dataset(),
        "--out",
        out_dir.to_str().unwrap(),
        "--method",
        "windowed",
        "--validation-periods",
        "50",
        "--bootstrap",
        "0",
        "--quiet",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = std::fs::read_to_string(out_dir.join("README.md")).unwrap();
    assert_eq!(text.matches("## Identified model: ").count(), 1, "{text}");
    assert!(text.contains("## Identified model: windowed"), "{text}");
    assert!(out_dir.join("model_windowed.json").exists());
    assert!(!out_dir.join("model_upo.json").exists());
}

#[test]
fn interrupt_leaves_no_file() {
    // A long simulation, interrupted while it runs (Ctrl-C, a scheduler's termination, a closed
    // terminal): neither the output nor a temporary remains.
    for signal in ["-INT", "-TERM", "-HUP"] {
        let dir = scratch(&format!("interrupt{signal}"));
        let target = dir.join("long.csv");
        let mut child = Command::new(env!("CARGO_BIN_EXE_hbid"))
            .args([
                "simulate",
                "--samples",
                "30000000",
                "--quiet",
                "--out",
                target.to_str().unwrap(),
            ])
            .spawn()
            .unwrap();
        std::thread::sleep(std::time::Duration::from_millis(400));
        let pid = child.id().to_string();
        let sent = Command::new("kill").args([signal, &pid]).status().unwrap();
        assert!(sent.success());
        let status = child.wait().unwrap();
        assert_eq!(status.code(), Some(130), "{signal}: {status:?}");
        assert_eq!(
            std::fs::read_dir(&dir).unwrap().count(),
            0,
            "{signal}: something was left in {}",
            dir.display()
        );
    }
}

#[test]
fn reads_standard_input_and_npy() {
    use std::io::Write;
    let text = std::fs::read_to_string(paper_dataset()).unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_hbid"))
        .args(["upos", "-", "--json", "--max-period", "4"])
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    child.stdin.take().unwrap().write_all(text.as_bytes()).unwrap();
    let piped = child.wait_with_output().unwrap();
    assert!(piped.status.success());
    let from_file = hbid(&["upos", &paper_dataset(), "--json", "--max-period", "4"]);
    assert_same_analysis(&piped.stdout, &from_file.stdout, 0.0);

    // The same angle column as a 1-D float64 .npy with --dt: the same orbits (t0 = 0 here, which
    // the close-return search does not see).
    let theta: Vec<f64> = text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with('t'))
        .map(|l| l.split(',').nth(1).unwrap().parse().unwrap())
        .collect();
    let mut header = format!(
        "{{'descr': '<f8', 'fortran_order': False, 'shape': ({},), }}",
        theta.len()
    );
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend_from_slice(&(header.len() as u16).to_le_bytes());
    bytes.extend_from_slice(header.as_bytes());
    for v in &theta {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    let dir = scratch("npy");
    let npy = dir.join("theta.npy");
    std::fs::write(&npy, bytes).unwrap();
    let dt = (std::f64::consts::TAU / 25.0).to_string();
    let out = hbid(&[
        "upos",
        npy.to_str().unwrap(),
        "--dt",
        &dt,
        "--json",
        "--max-period",
        "4",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_same_analysis(&out.stdout, &from_file.stdout, f64::INFINITY);
    assert_clean_failure(&hbid(&["upos", npy.to_str().unwrap()]), "--dt");
}

#[test]
fn windowed_method_with_intervals() {
    let out = hbid(&[
        "identify",
        &paper_dataset(),
        "--method",
        "windowed",
        "--json",
        "--bootstrap",
        "200",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["method"], "windowed");
    for (name, value) in &pendulum_truth() {
        let got = v["coefficients"][name].as_f64().unwrap();
        assert!((got - value).abs() < 1e-5, "{name}: {got} vs {value}");
        let interval = v["intervals"][name].as_array().unwrap();
        let (lo, hi) = (interval[0].as_f64().unwrap(), interval[1].as_f64().unwrap());
        assert!(lo <= got && got <= hi, "{name}: {got} outside [{lo}, {hi}]");
    }
    assert_eq!(v["interval_level"], 0.95);
    // Seeded: the same intervals again.
    let again = hbid(&[
        "identify",
        &paper_dataset(),
        "--method",
        "windowed",
        "--json",
        "--bootstrap",
        "200",
    ]);
    assert_eq!(out.stdout, again.stdout);
}

#[test]
fn windowed_method_recovers_duffing_on_the_line() {
    let dir = scratch("duffing-weak");
    let record = duffing_record(&dir);
    let period = (std::f64::consts::TAU / 1.2).to_string();
    let out = hbid(&[
        "identify",
        record.to_str().unwrap(),
        "--signal",
        "line",
        "--forcing-period",
        &period,
        "--method",
        "windowed",
        "--bootstrap",
        "0",
        "--json",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let c = &v["coefficients"];
    let worst = DUFFING_TRUTH
        .iter()
        .map(|(n, t)| (c[*n].as_f64().unwrap() - t).abs())
        .fold(0.0, f64::max);
    // The issue expects about 1e-8.
    assert!(worst < 1e-7, "largest error {worst:e}: {c}");
    assert!(v["intervals"].is_null());
}

#[test]
fn simulate_writes_npy_that_identify_reads_like_the_csv() {
    let dir = scratch("npy-out");
    let (csv, npy) = (dir.join("r.csv"), dir.join("r.npy"));
    for p in [&csv, &npy] {
        let out = hbid(&["simulate", "--samples", "6000", "--out", p.to_str().unwrap()]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    }
    let bytes = std::fs::read(&npy).unwrap();
    assert!(bytes.starts_with(b"\x93NUMPY"));
    // The permissions of any file the user writes (0o666 less the umask), not owner-only.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let plain = dir.join("plain");
        std::fs::write(&plain, b"x").unwrap();
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&npy), mode(&plain));
    }
    // f8 little-endian, 6000 × 3, and the payload is exactly that.
    let header = String::from_utf8_lossy(&bytes[10..128]);
    assert!(
        header.contains("'<f8'") && header.contains("(6000, 3, )"),
        "{header}"
    );
    assert_eq!(bytes.len() % 16, 0, "payload after a 16-byte-aligned header");
    assert_eq!(bytes.len() - 6000 * 3 * 8, 128);
    // Same numbers as the CSV (which prints the shortest round-trip decimal).
    let (_, rows) = read_rows(&csv);
    for (i, row) in rows.iter().enumerate().step_by(997) {
        for (j, v) in row.iter().enumerate() {
            let at = 128 + 8 * (3 * i + j);
            let got = f64::from_le_bytes(bytes[at..at + 8].try_into().unwrap());
            assert_eq!(got, *v, "row {i} column {j}");
        }
    }
    let id = |p: &Path| {
        hbid(&[
            "identify",
            p.to_str().unwrap(),
            "--method",
            "upo",
            "--json",
            "--bootstrap",
            "0",
            "--timings",
        ])
    };
    let (a, b) = (id(&csv), id(&npy));
    assert!(b.status.success(), "{}", String::from_utf8_lossy(&b.stderr));
    assert_eq!(a.stdout, b.stdout);
    // --timings lists the stages on stderr.
    let err = String::from_utf8_lossy(&b.stderr);
    for stage in ["read", "delay", "segments", "assemble", "solve", "total"] {
        assert!(
            err.lines().any(|l| l.trim_start().starts_with(stage)),
            "{stage}: {err}"
        );
    }
}

/// `hbid simulate` with `args` into `dir/name`; panics with stderr if it fails.
fn simulated(dir: &Path, name: &str, args: &[&str]) -> PathBuf {
    let path = dir.join(name);
    let mut all = vec!["simulate", "--quiet"];
    all.extend(args);
    all.extend(["--out", path.to_str().unwrap()]);
    let out = hbid(&all);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    path
}

/// [`simulated`] with `--truth`: the record and its truth file, read (`NAME.truth.json` in `dir`).
fn simulated_with_truth(dir: &Path, name: &str, args: &[&str]) -> (PathBuf, serde_json::Value) {
    let truth = dir.join(format!("{name}.truth.json"));
    let record = simulated(dir, name, &[args, &["--truth", truth.to_str().unwrap()]].concat());
    let truth = serde_json::from_str(&std::fs::read_to_string(&truth).unwrap()).unwrap();
    (record, truth)
}

/// A record of 6400 samples of `system` (`hbid simulate --system`) in `dir`, and its truth.
fn simulated_system(dir: &Path, name: &str, system: &str) -> (PathBuf, serde_json::Value) {
    simulated_with_truth(dir, name, &["--system", system, "--samples", "6400"])
}

/// Without the rig options the record is what it always was: the same bytes as with every new
/// option at its default, the header `t,theta,omega`, numbers printed in their shortest
/// round-trip form, the first stamp after the transient, and equal seeds giving equal records.
#[test]
fn simulate_default_layout_is_unchanged() {
    let dir = scratch("default-layout");
    let base = [
        "--samples",
        "300",
        "--transient-periods",
        "5",
        "--noise",
        "0.05",
        "--seed",
        "7",
    ];
    let plain = simulated(&dir, "plain.csv", &base);
    let mut explicit = base.to_vec();
    explicit.extend([
        "--system",
        "pendulum",
        "--forcing",
        "drive",
        "--time-origin",
        "drive",
        "--phase",
        "0",
        "--f",
        "1.52",
        "--c",
        "0.03",
        "--r",
        "0.8333",
        "--samples-per-period",
        "25",
    ]);
    let spelled = simulated(&dir, "spelled.csv", &explicit);
    let again = simulated(&dir, "again.csv", &base);
    let text = std::fs::read_to_string(&plain).unwrap();
    assert_eq!(text, std::fs::read_to_string(&spelled).unwrap());
    assert_eq!(text, std::fs::read_to_string(&again).unwrap());
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("t,theta,omega"));
    for line in lines.clone() {
        for cell in line.split(',') {
            let v: f64 = cell.parse().unwrap();
            assert_eq!(v.to_string(), cell, "not the shortest form: {line}");
        }
    }
    assert_eq!(lines.count(), 300);
    let (_, rows) = read_rows(&plain);
    assert!((rows[0][0] - 5.0 * std::f64::consts::TAU).abs() < 1e-12);
}

/// A 500 Hz record of a 1.02 Hz drive by a 4096-count encoder: stamps to the given decimals, every
/// angle on the count grid, duration × rate rows; raw counts are the same readings as integers.
#[test]
fn simulate_a_500_hz_rig_with_a_4096_count_encoder() {
    let dir = scratch("rig");
    let rig = [
        "--drive-frequency",
        "1.02",
        "--sample-rate",
        "500",
        "--counts",
        "4096",
        "--duration",
        "20",
        "--time-decimals",
        "3",
        "--decimals",
        "7",
        "--time-origin",
        "first-sample",
        "--zero-offset",
        "0.25",
        "--transient-periods",
        "20",
    ];
    let radians = simulated(&dir, "rig.csv", &rig);
    let text = std::fs::read_to_string(&radians).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "t,theta,omega");
    assert_eq!(lines.len() - 1, 10_000);
    let q = std::f64::consts::TAU / 4096.0;
    let pi = std::f64::consts::PI;
    for (n, line) in lines[1..].iter().enumerate() {
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(cells[0].split_once('.').unwrap().1.len(), 3, "{line}");
        assert_eq!(cells[1].split_once('.').unwrap().1.len(), 7, "{line}");
        let t: f64 = cells[0].parse().unwrap();
        assert!((t - n as f64 * 0.002).abs() < 1e-9, "{line}");
        let theta: f64 = cells[1].parse().unwrap();
        assert!((-pi..pi).contains(&theta), "{line}");
        // Seven decimals hold the count's angle to 5e-8 rad, 3.3e-5 of a count.
        let k = theta / q;
        assert!((k - k.round()).abs() < 4e-5, "{line}: {k} counts");
    }
    let mut raw = rig.to_vec();
    raw.push("--raw-counts");
    let counts = simulated(&dir, "counts.csv", &raw);
    let text = std::fs::read_to_string(&counts).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("t,count,omega"));
    let (_, angles) = read_rows(&radians);
    let mut seen = std::collections::BTreeSet::new();
    for (line, row) in lines.zip(&angles) {
        let k: u32 = line.split(',').nth(1).unwrap().parse().expect("an integer count");
        assert!(k < 4096);
        seen.insert(k);
        assert!(
            circle_signal::circle_distance(f64::from(k) * q, row[1]) < 1e-6,
            "{line}"
        );
    }
    // The .npy holds the numbers the CSV's reader gets, decimals and counts included.
    for args in [rig.to_vec(), raw.clone()] {
        let csv = read_rows(&simulated(&dir, "same.csv", &args)).1;
        let bytes = std::fs::read(simulated(&dir, "same.npy", &args)).unwrap();
        let start = 10 + usize::from(u16::from_le_bytes([bytes[8], bytes[9]]));
        let values: Vec<f64> = bytes[start..]
            .chunks_exact(8)
            .map(|b| f64::from_le_bytes(b.try_into().unwrap()))
            .collect();
        assert_eq!(values, csv.concat());
    }
    // A whirling pendulum goes all the way round.
    let (lo, hi) = (*seen.first().unwrap(), *seen.last().unwrap());
    assert!(lo < 64 && hi >= 4032, "counts {lo} to {hi}");
}

/// The truth file is the equation `hbid identify` recovers from the record, term for term, in
/// the record's seconds, with a drive phase and an encoder offset: for the pendulum and for the
/// Duffing oscillator.
#[test]
fn simulate_truth_is_what_identify_recovers() {
    let dir = scratch("truth");
    let cases = [
        (
            vec![
                "--drive-frequency",
                "1.02",
                "--zero-offset",
                "0.3",
                "--phase",
                "1.0",
            ],
            vec!["--forcing-period", "0.9803921568627451"],
        ),
        (
            vec![
                "--system",
                "duffing",
                "--drive-frequency",
                "6.5",
                "--phase",
                "0.7",
                "--transient-periods",
                "100",
            ],
            vec![
                "--forcing-period",
                "0.15384615384615385",
                "--signal",
                "line",
                "--angle-col",
                "x",
            ],
        ),
    ];
    for (i, (sim, id)) in cases.into_iter().enumerate() {
        let truth_path = dir.join(format!("truth{i}.json"));
        let mut args = sim.clone();
        args.extend([
            "--samples-per-period",
            "50",
            "--samples",
            "40000",
            "--time-origin",
            "first-sample",
            "--rtol",
            "1e-12",
            "--truth",
            truth_path.to_str().unwrap(),
        ]);
        let record = simulated(&dir, &format!("record{i}.csv"), &args);
        let truth: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&truth_path).unwrap()).unwrap();
        let mut all = vec!["identify", record.to_str().unwrap()];
        all.extend(id);
        all.extend(["--method", "windowed", "--bootstrap", "0", "--json"]);
        let out = hbid(&all);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let found: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let (want, got) = (
            truth["coefficients"].as_object().unwrap(),
            found["coefficients"].as_object().unwrap(),
        );
        let names = |m: &serde_json::Map<String, serde_json::Value>| {
            m.keys().cloned().collect::<std::collections::BTreeSet<_>>()
        };
        assert_eq!(names(want), names(got), "{sim:?}");
        assert_eq!(truth["identify"]["basis"], found["basis"]);
        let scale = want
            .values()
            .map(|v| v.as_f64().unwrap().abs())
            .fold(0.0, f64::max);
        let worst = want
            .iter()
            .map(|(n, v)| (v.as_f64().unwrap() - got[n].as_f64().unwrap()).abs())
            .fold(0.0, f64::max);
        // Measured: 1.5e-7 (pendulum, scale 56) and 7e-6 (Duffing, scale 1668).
        assert!(
            worst < 1e-6 * scale,
            "{sim:?}: largest error {worst:e} of {scale}"
        );
        // A drive phase and an offset show as the rotated terms.
        let nonzero = want.values().filter(|v| v.as_f64().unwrap() != 0.0).count();
        assert_eq!(nonzero, if i == 0 { 7 } else { 5 }, "{want:?}");
    }
}

#[test]
fn simulate_rig_options_combine_or_fail_cleanly() {
    let dir = scratch("rig-bad");
    let target = dir.join("never.csv");
    let truth = dir.join("never.json");
    let t = target.to_str().unwrap();
    for (args, mentions) in [
        (vec!["--bit-errors", "0.01"], "--bit-errors needs --counts"),
        (vec!["--counts", "4096", "--bit-errors", "-0.1"], "bit error rate"),
        (vec!["--counts", "512", "--bit-errors", "0.1"], "1024"),
        (
            vec!["--drive-frequency", "1.02", "--sample-rate", "0"],
            "--sample-rate",
        ),
        (vec!["--drive-frequency", "0"], "--drive-frequency 0"),
        (vec!["--sample-rate", "500"], "needs --drive-frequency"),
        (
            vec![
                "--drive-frequency",
                "1",
                "--sample-rate",
                "500",
                "--samples-per-period",
                "50",
            ],
            "give one",
        ),
        (vec!["--samples", "100", "--duration", "2"], "--duration both set"),
        (vec!["--duration", "-1"], "--duration"),
        (vec!["--duration", "0.1"], "shorter than one sample step"),
        (vec!["--raw-counts"], "--raw-counts needs --counts"),
        (
            vec!["--counts", "64", "--raw-counts", "--unwrapped"],
            "--unwrapped",
        ),
        (vec!["--counts", "1"], "counts per turn"),
        (vec!["--zero-offset", "inf"], "zero offset"),
        (vec!["--system", "duffing", "--counts", "4096"], "pendulum only"),
        (vec!["--system", "duffing", "--r", "1"], "--r"),
        (vec!["--a", "-1"], "--system duffing"),
        (vec!["--forcing", "none", "--f", "1"], "--drive none"),
        (vec!["--gaps", "3"], "k:len"),
        (vec!["--gaps", "3:0"], "gap length"),
        (vec!["--gaps", "100:100", "--samples", "1000"], "too few"),
        (
            vec![
                "--drive-frequency",
                "1.02",
                "--sample-rate",
                "500",
                "--time-decimals",
                "2",
            ],
            "--time-decimals 2",
        ),
        (vec!["--phase", "nan"], "--phase"),
        (vec!["--angle-range", "positive", "--unwrapped"], "--angle-range"),
    ] {
        let mut all = vec!["simulate", "--samples", "1000"];
        if args.contains(&"--samples") || args.contains(&"--duration") {
            all.truncate(1);
        }
        all.extend(args.iter().copied());
        all.extend(["--truth", truth.to_str().unwrap(), "--out", t]);
        assert_clean_failure(&hbid(&all), &mentions.to_lowercase());
        assert!(!target.exists() && !truth.exists(), "{args:?} left a file");
    }
    let folder = dir.join("sub");
    std::fs::create_dir(&folder).unwrap();
    assert_clean_failure(
        &hbid(&["simulate", "--truth", folder.to_str().unwrap(), "--out", t]),
        "folder",
    );
    assert!(!target.exists());
    std::fs::remove_dir(&folder).unwrap();
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
}

/// Bit errors are spikes of 64 to 512 counts on a few samples, the same for a seed; gaps remove
/// runs of samples; the positive range holds the same angles in [0, 2π).
#[test]
fn simulate_bit_errors_gaps_and_ranges() {
    let dir = scratch("rig-effects");
    let base = [
        "--samples",
        "20000",
        "--transient-periods",
        "5",
        "--counts",
        "4096",
        "--raw-counts",
    ];
    let clean = read_rows(&simulated(&dir, "clean.csv", &base)).1;
    let mut flipped_args = base.to_vec();
    flipped_args.extend(["--bit-errors", "0.01", "--seed", "4"]);
    let flipped = read_rows(&simulated(&dir, "flipped.csv", &flipped_args)).1;
    assert_eq!(
        flipped,
        read_rows(&simulated(&dir, "flipped2.csv", &flipped_args)).1
    );
    let mut hits = 0;
    for (a, b) in clean.iter().zip(&flipped) {
        assert_eq!((a[0], a[2]), (b[0], b[2]), "time and velocity untouched");
        if a[1] != b[1] {
            hits += 1;
            let d = (b[1] - a[1]).rem_euclid(4096.0);
            let d = d.min(4096.0 - d);
            assert!([64.0, 128.0, 256.0, 512.0].contains(&d), "spike of {d} counts");
        }
    }
    // Binomial(20000, 0.01): 200 ± 14.
    assert!((130..270).contains(&hits), "{hits} bit errors");

    let gapped = read_rows(&simulated(
        &dir,
        "gapped.csv",
        &[
            "--samples",
            "2000",
            "--transient-periods",
            "5",
            "--gaps",
            "3:50",
            "--seed",
            "9",
        ],
    ))
    .1;
    assert_eq!(gapped.len(), 1850);
    let h = std::f64::consts::TAU / 25.0;
    let jumps: Vec<f64> = gapped
        .windows(2)
        .map(|w| (w[1][0] - w[0][0]) / h)
        .filter(|s| (s - 1.0).abs() > 1e-6)
        .collect();
    assert_eq!(jumps.len(), 3, "{jumps:?}");
    assert!(jumps.iter().all(|s| (s - 51.0).abs() < 1e-6), "{jumps:?}");

    let signed = read_rows(&simulated(
        &dir,
        "signed.csv",
        &["--samples", "3000", "--transient-periods", "5"],
    ))
    .1;
    let positive = read_rows(&simulated(
        &dir,
        "positive.csv",
        &[
            "--samples",
            "3000",
            "--transient-periods",
            "5",
            "--angle-range",
            "positive",
        ],
    ))
    .1;
    let tau = std::f64::consts::TAU;
    assert!(positive.iter().all(|r| (0.0..tau).contains(&r[1])));
    assert!(positive.iter().any(|r| r[1] > std::f64::consts::PI));
    for (s, p) in signed.iter().zip(&positive) {
        assert!(circle_signal::circle_distance(s[1], p[1]) < 1e-12);
    }
}

/// A free decay starts at once (no transient), loses amplitude, and its truth has no drive; the
/// Duffing oscillator writes t,x,v and visits both wells.
#[test]
fn simulate_free_decay_and_duffing() {
    let dir = scratch("decay");
    let truth = dir.join("decay.json");
    let decay = read_rows(&simulated(
        &dir,
        "decay.csv",
        &[
            "--forcing",
            "none",
            "--theta0",
            "2.5",
            "--drive-frequency",
            "1.02",
            "--samples",
            "5000",
            "--truth",
            truth.to_str().unwrap(),
        ],
    ))
    .1;
    assert_eq!(decay[0][0], 0.0);
    assert!((decay[0][1] - 2.5).abs() < 1e-12);
    let amplitude = |rows: &[Vec<f64>]| rows.iter().map(|r| r[1].abs()).fold(0.0, f64::max);
    let (first, last) = (amplitude(&decay[..500]), amplitude(&decay[4500..]));
    assert!(last < 0.8 * first, "amplitude {first} -> {last}");
    let t: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&truth).unwrap()).unwrap();
    let w = std::f64::consts::TAU * 1.02;
    let c = &t["coefficients"];
    assert_eq!(c["sin(t)*cos(x)"], 0.0);
    assert!((c["x'"].as_f64().unwrap() - 0.03 * w).abs() < 1e-12);
    assert!((c["sin(x)"].as_f64().unwrap() - w * w / (0.8333 * 0.8333)).abs() < 1e-9);
    assert_eq!(t["forcing"], "none");

    let duffing = simulated(
        &dir,
        "duffing.csv",
        &["--system", "duffing", "--samples", "20000"],
    );
    let text = std::fs::read_to_string(&duffing).unwrap();
    assert!(text.starts_with("t,x,v\n"));
    let rows = read_rows(&duffing).1;
    let left = rows.iter().filter(|r| r[1] < 0.0).count();
    assert!(
        left > 2000 && left < 18_000,
        "{left} of 20000 samples in the left well"
    );
}

/// The largest error of an identification against a truth file, relative to each nonzero true
/// coefficient (and to the largest one for the terms whose truth is zero; a term left out of the
/// model counts as zero).
fn worst_relative_error(truth: &Path, identified: &[u8]) -> f64 {
    let truth: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(truth).unwrap()).unwrap();
    let found: serde_json::Value = serde_json::from_slice(identified).unwrap();
    let want = truth["coefficients"].as_object().unwrap();
    let scale = want
        .values()
        .map(|v| v.as_f64().unwrap().abs())
        .fold(0.0, f64::max);
    want.iter()
        .map(|(name, v)| {
            let v = v.as_f64().unwrap();
            match found["coefficients"][name].as_f64() {
                Some(got) => (got - v).abs() / if v == 0.0 { scale } else { v.abs() },
                // A term left out of the model is right only if its truth is zero.
                None if v == 0.0 => 0.0,
                None => f64::INFINITY,
            }
        })
        .fold(0.0, f64::max)
}

/// Records as rigs write them (a sampling rate in no whole ratio to the drive, stamps to 1 ms,
/// encoder counts, faults, no drive) identified by one command each, without preprocessing.
#[test]
fn rig_records_are_identified_without_preprocessing() {
    let dir = scratch("rigs");
    let rig = [
        "--drive-frequency",
        "1.02",
        "--sample-rate",
        "500",
        "--counts",
        "4096",
        "--duration",
        "120",
        "--time-origin",
        "first-sample",
        "--time-decimals",
        "3",
    ];
    let identify = |record: &Path, options: &[&str]| {
        let mut all = vec!["identify", record.to_str().unwrap(), "--method", "windowed"];
        all.extend(options);
        all.extend(["--bootstrap", "0", "--json"]);
        let out = hbid(&all);
        assert!(
            out.status.success(),
            "{options:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        out
    };
    let truth = dir.join("plain.json");
    let mut args = rig.to_vec();
    args.extend(["--truth", truth.to_str().unwrap()]);
    let plain = simulated(&dir, "plain.csv", &args);
    // 490.196 samples per forcing period, resampled once at the input.
    let out = identify(&plain, &["--forcing-frequency", "1.02"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("resampled"));
    let worst = worst_relative_error(&truth, &out.stdout);
    assert!(worst < 1e-4, "known drive: {worst:e}");
    // The drive estimated from the record.
    let out = identify(&plain, &["--forcing-frequency", "auto:0.5..2"]);
    let note = String::from_utf8_lossy(&out.stderr).into_owned();
    let estimate: f64 = note
        .split("(frequency ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no estimate in: {note}"));
    assert!((estimate / 1.02 - 1.0).abs() < 1e-5, "{estimate}");
    assert!(worst_relative_error(&truth, &out.stdout) < 1e-4);

    // Encoder zero away from the bottom, angles in [0, 2π), bit errors and gaps.
    let truth = dir.join("faulty.json");
    let mut args = rig.to_vec();
    args.extend([
        "--zero-offset",
        "0.7",
        "--phase",
        "1.3",
        "--angle-range",
        "positive",
        "--bit-errors",
        "2e-4",
        "--gaps",
        "2:150",
        "--seed",
        "3",
        "--truth",
        truth.to_str().unwrap(),
    ]);
    let faulty = simulated(&dir, "faulty.csv", &args);
    // The bit errors (2e-4 per sample) are few: replaced by default, and a note says so.
    let default = identify(&faulty, &["--forcing-frequency", "1.02"]);
    let text = String::from_utf8_lossy(&default.stderr).into_owned();
    assert!(text.contains("2 gap(s)") && text.contains("3 pieces"), "{text}");
    assert!(
        text.contains("spike(s) replaced by the local prediction (by default"),
        "{text}"
    );
    assert!(!text.contains("unwrapped angle"), "{text}");
    let repaired = identify(&faulty, &["--forcing-frequency", "1.02", "--repair"]);
    let text = String::from_utf8_lossy(&repaired.stderr).into_owned();
    assert!(text.contains("replaced by the local prediction"), "{text}");
    let (by_default, asked) = (
        worst_relative_error(&truth, &default.stdout),
        worst_relative_error(&truth, &repaired.stdout),
    );
    assert!(by_default < 1e-4 && asked < 1e-4, "{by_default:e}, {asked:e}");

    // A free decay: no drive, windows in periods of the free oscillation.
    let truth = dir.join("free.json");
    let free = simulated(
        &dir,
        "free.csv",
        &[
            "--forcing",
            "none",
            "--drive-frequency",
            "1.02",
            "--sample-rate",
            "500",
            "--counts",
            "4096",
            "--theta0",
            "0",
            "--omega0",
            "20",
            "--duration",
            "60",
            "--time-origin",
            "first-sample",
            "--truth",
            truth.to_str().unwrap(),
        ],
    );
    let out = identify(&free, &["--forcing", "none"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("no drive"));
    let found: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(found["coefficients"].as_object().unwrap().len(), 3, "{found}");
    assert!(worst_relative_error(&truth, &out.stdout) < 1e-3);
    let upo = hbid(&[
        "identify",
        free.to_str().unwrap(),
        "--method",
        "upo",
        "--forcing",
        "none",
    ]);
    assert_clean_failure(&upo, "no periodic orbits");
}

/// The fit's measure on the line: the right model explains the windowed acceleration to
/// rounding; without its forcing the same record warns, and in the JSON `explained` says how
/// little.
#[test]
fn a_model_without_its_drive_is_told_by_its_fit() {
    let dir = scratch("fit-quality");
    let record = duffing_record(&dir);
    let period = (std::f64::consts::TAU / 1.2).to_string();
    let run = |forcing: &str| {
        let out = hbid(&[
            "identify",
            record.to_str().unwrap(),
            "--signal",
            "line",
            "--method",
            "windowed",
            "--forcing-period",
            &period,
            "--forcing",
            forcing,
            "--json",
            "--quiet",
        ]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        (v, String::from_utf8_lossy(&out.stderr).into_owned())
    };
    let (good, err) = run("identified");
    assert!(
        good["unexplained"].as_f64().unwrap() < 1e-9,
        "{}",
        good["unexplained"]
    );
    assert!(good["warning"].is_null() && !err.contains("warning"), "{err}");
    assert_eq!(good["residual_spectrum"].as_array().unwrap().len(), 7);
    let (bad, err) = run("none");
    let explained = bad["explained"].as_f64().unwrap();
    assert!(explained < 0.99, "{explained}");
    assert!(err.contains("likely missing terms"), "{err}");
}

/// `--measured` is for the line: an angle's velocity is refused before anything runs.
#[test]
fn measured_velocity_needs_the_line() {
    let dir = scratch("measured");
    let record = duffing_record(&dir);
    let out = hbid(&["identify", record.to_str().unwrap(), "--measured", "velocity"]);
    assert_clean_failure(&out, "needs --signal line");
}

/// The value of a term named as the identification names it (factors joined by `*`, `t` the
/// drive's phase `wt`, `kt` its k-th harmonic) at `(x, v)`: an independent reading of the names.
fn term_value(name: &str, wt: f64, x: f64, v: f64) -> f64 {
    let drive = |f: &str| -> Option<f64> {
        let (cos, rest) = match (f.strip_prefix("cos("), f.strip_prefix("sin(")) {
            (Some(rest), _) => (true, rest),
            (_, Some(rest)) => (false, rest),
            _ => return None,
        };
        let k = rest.strip_suffix("t)")?;
        let k: f64 = if k.is_empty() { 1.0 } else { k.parse().ok()? };
        Some(if cos { (k * wt).cos() } else { (k * wt).sin() })
    };
    name.split('*')
        .map(|f| match f {
            "x'" => v,
            "|x'|" => v.abs(),
            "x'^3" => v.powi(3),
            "sign(x')" => {
                if v == 0.0 {
                    0.0
                } else {
                    v.signum()
                }
            }
            "x" => x,
            "x^2" => x * x,
            "x^3" => x.powi(3),
            "sin(x)" => x.sin(),
            "cos(x)" => x.cos(),
            other => drive(other).unwrap_or_else(|| panic!("unknown factor {other}")),
        })
        .product()
}

/// A rig's friction, drag, cubic damping and drive harmonics reach the truth file, in the
/// record's seconds, and the record satisfies the equation the file writes (the acceleration
/// from differences of the written velocity against the terms, away from reversals of the
/// velocity, where friction jumps): for the pendulum and the Duffing oscillator.
#[test]
fn simulate_real_machine_terms_flow_into_the_truth() {
    let dir = scratch("real-machine");
    let rig = [
        "--drive-frequency",
        "1.02",
        "--sample-rate",
        "400",
        "--duration",
        "12",
        "--rtol",
        "1e-12",
        "--friction",
        "0.02",
        "--drag",
        "0.01",
        "--cubic-damping",
        "0.002",
        "--drive-harmonic",
        "2:0.1:0.5",
        "--drive-harmonic",
        "3:0.05",
        "--transient-periods",
        "20",
    ];
    let w = std::f64::consts::TAU * 1.02;
    for system in ["pendulum", "duffing"] {
        let truth_path = dir.join(format!("{system}.json"));
        let mut args = rig.to_vec();
        args.extend(["--system", system, "--truth", truth_path.to_str().unwrap()]);
        let record = simulated(&dir, &format!("{system}.csv"), &args);
        let truth: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&truth_path).unwrap()).unwrap();
        let coefficients = truth["coefficients"].as_object().unwrap();
        let c = |name: &str| {
            coefficients
                .get(name)
                .unwrap_or_else(|| panic!("{system}: no {name} in {coefficients:?}"))
                .as_f64()
                .unwrap()
        };
        assert!((c("sign(x')") - 0.02 * w * w).abs() < 1e-12);
        assert_eq!(c("x'*|x'|"), 0.01);
        assert!((c("x'^3") - 0.002 / w).abs() < 1e-15);
        let extra: Vec<&str> = truth["identify"]["extra_terms"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_str().unwrap())
            .collect();
        let (want_extra, drive_2t) = match system {
            "pendulum" => (
                vec![
                    "sign(x')",
                    "x'*|x'|",
                    "x'^3",
                    "cos(2t)*cos(x)",
                    "sin(2t)*cos(x)",
                    "cos(2t)*sin(x)",
                    "sin(2t)*sin(x)",
                    "cos(3t)*cos(x)",
                    "sin(3t)*cos(x)",
                    "cos(3t)*sin(x)",
                    "sin(3t)*sin(x)",
                ],
                // −f ρ W² sin(2t + 0.5) cos x: its sin(2t)*cos(x) part.
                ("sin(2t)*cos(x)", -1.52 * 0.1 * w * w * 0.5f64.cos()),
            ),
            _ => (
                vec![
                    "sign(x')", "x'*|x'|", "x'^3", "cos(2t)", "sin(2t)", "cos(3t)", "sin(3t)",
                ],
                // −f ρ W² cos(2t + 0.5): its cos(2t) part.
                ("cos(2t)", -0.3 * 0.1 * w * w * 0.5f64.cos()),
            ),
        };
        assert_eq!(extra, want_extra);
        assert!((c(drive_2t.0) - drive_2t.1).abs() < 1e-12 * w * w);
        assert_eq!(truth["parameters"]["losses"]["friction"], 0.02);
        assert_eq!(truth["parameters"]["drive_harmonics"][1]["k"], 3);
        assert!(truth["equation"].as_str().unwrap().contains("sign(x')"));

        let (_, rows) = read_rows(&record);
        let h = 1.0 / 400.0;
        let (mut worst, mut scale, mut checked): (f64, f64, usize) = (0.0, 0.0, 0);
        for n in 2..rows.len() - 2 {
            let v: Vec<f64> = (n - 2..=n + 2).map(|m| rows[m][2]).collect();
            if !(v.iter().all(|&u| u > 0.0) || v.iter().all(|&u| u < 0.0)) {
                continue;
            }
            let acc = (v[0] - 8.0 * v[1] + 8.0 * v[3] - v[4]) / (12.0 * h);
            let terms: f64 = coefficients
                .iter()
                .map(|(name, value)| {
                    value.as_f64().unwrap() * term_value(name, w * rows[n][0], rows[n][1], v[2])
                })
                .sum();
            worst = worst.max((acc + terms).abs());
            scale = scale.max(acc.abs());
            checked += 1;
        }
        assert!(checked > 4_500, "{system}: {checked} samples checked");
        assert!(worst < 1e-5 * scale, "{system}: residual {worst:e} of {scale:e}");
    }
}

#[test]
fn simulate_real_machine_options_fail_cleanly() {
    let dir = scratch("real-machine-bad");
    let target = dir.join("never.csv");
    let truth = dir.join("never.json");
    for (args, mentions) in [
        (vec!["--friction", "-0.1"], "--friction"),
        (vec!["--friction", "nan"], "friction"),
        (vec!["--drag", "-1"], "--drag"),
        (vec!["--cubic-damping", "inf"], "--cubic-damping"),
        (vec!["--drive-harmonic", "2"], "k:ratio[:phase]"),
        (vec!["--drive-harmonic", "2:0.1:0:1"], "k:ratio[:phase]"),
        (vec!["--drive-harmonic", "1:0.1"], "2..=16"),
        (vec!["--drive-harmonic", "17:0.1"], "2..=16"),
        (vec!["--drive-harmonic", "x:0.1"], "not a whole number"),
        (vec!["--drive-harmonic", "2:-0.1"], "ratio"),
        (vec!["--drive-harmonic", "2:0.1:phase"], "not a number"),
        (
            vec!["--drive-harmonic", "2:0.1", "--drive-harmonic", "2:0.2"],
            "more than once",
        ),
        (
            vec!["--drive", "none", "--drive-harmonic", "2:0.1"],
            "--drive none",
        ),
        (vec!["--system", "duffing", "--friction", "-1"], "--friction"),
    ] {
        let mut all = vec!["simulate", "--samples", "1000"];
        all.extend(args.iter().copied());
        all.extend([
            "--truth",
            truth.to_str().unwrap(),
            "--out",
            target.to_str().unwrap(),
        ]);
        assert_clean_failure(&hbid(&all), &mentions.to_lowercase());
        assert!(!target.exists() && !truth.exists(), "{args:?} left a file");
    }
}

/// `hbid report` measures each model's valid prediction time from the record's own states: a line
/// per model, every window in `prediction.json`, and a figure.
#[test]
fn report_measures_the_valid_prediction_time() {
    let dir = scratch("report-prediction");
    let record = simulated(&dir, "record.csv", &["--samples", "8000"]);
    let out_dir = dir.join("rep");
    let out = hbid(&[
        "report",
        record.to_str().unwrap(),
        "--out",
        out_dir.to_str().unwrap(),
        "--validation-periods",
        "100",
        "--bootstrap",
        "0",
        "--quiet",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = std::fs::read_to_string(out_dir.join("README.md")).unwrap();
    assert!(text.contains("## How long do the models predict the record?"));
    assert!(
        text.contains("| upo |") && text.contains("| windowed |"),
        "{text}"
    );
    assert!(std::fs::metadata(out_dir.join("prediction.png")).unwrap().len() > 100);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("prediction.json")).unwrap()).unwrap();
    // 10 % of the spread of a whirling pendulum's angle, nearly 2π.
    let tolerance = json["tolerance"].as_f64().unwrap();
    assert!((0.6..=0.6284).contains(&tolerance), "{tolerance}");
    let period = json["forcing_period"].as_f64().unwrap();
    let models = json["models"].as_array().unwrap();
    assert_eq!(models.len(), 2);
    for model in models {
        let windows = model["windows"].as_array().unwrap();
        assert_eq!(windows.len(), 32);
        let mut times: Vec<f64> = windows
            .iter()
            .map(|w| w["valid_time"].as_f64().unwrap() / period)
            .collect();
        assert!(
            times.iter().all(|&t| (0.0..=40.0 + 1e-9).contains(&t)),
            "{times:?}"
        );
        times.sort_by(f64::total_cmp);
        let median = model["periods"]["median"].as_f64().unwrap();
        assert!((median - 0.5 * (times[15] + times[16])).abs() < 1e-9);
        // A model of the chaotic pendulum follows it for more than a period, and not forever.
        assert!(median > 1.0 && median < 40.0, "{median}");
        let lyapunov = model["lyapunov_per_unit_time"].as_f64().unwrap();
        let in_lyapunov = model["lyapunov_times"]["median"].as_f64().unwrap();
        assert!((in_lyapunov - median * period * lyapunov).abs() < 1e-9 * in_lyapunov);
    }
}

/// `--terms` chooses the model: a rig pendulum with friction, drag and a second drive harmonic is
/// identified with exactly its terms, printed, keyed and saved in the order of the list, each near
/// its truth; the saved model loads with the same terms; `report` takes the same list.
#[test]
fn terms_choose_the_model_and_flow_into_json_and_saved_model() {
    let dir = scratch("terms");
    let (record, truth) = simulated_with_truth(
        &dir,
        "rig.csv",
        &[
            "--friction",
            "0.05",
            "--drag",
            "0.05",
            "--drive-harmonic",
            "2:0.1",
            "--samples",
            "40000",
        ],
    );
    let list = "x', sign(x'), x'*|x'|, sin(x), {sin(t),sin(2t)}*cos(x)";
    let names = [
        "x'",
        "sign(x')",
        "x'*|x'|",
        "sin(x)",
        "sin(t)*cos(x)",
        "sin(2t)*cos(x)",
    ];
    let model_path = dir.join("model.json");
    let out = hbid(&[
        "identify",
        record.to_str().unwrap(),
        "--method",
        "windowed",
        "--terms",
        list,
        "--bootstrap",
        "0",
        "--json",
        "--quiet",
        "--save-model",
        model_path.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let terms: Vec<&str> = v["terms"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t.as_str().unwrap())
        .collect();
    assert_eq!(terms, names);
    for name in names {
        let want = truth["coefficients"][name].as_f64().unwrap();
        let got = v["coefficients"][name].as_f64().unwrap();
        assert!((got - want).abs() < 0.05 * want.abs(), "{name}: {got} vs {want}");
    }
    assert!(v["explained"].as_f64().unwrap() > 0.999);
    let saved = std::fs::read_to_string(&model_path).unwrap();
    let model = hb_model::IdentifiedModel::<hb_basis::BasisKind>::from_json(&saved).unwrap();
    let saved_names: Vec<&str> = model.coefficients().iter().map(|c| c.name.as_str()).collect();
    assert_eq!(saved_names, names);
    // The table prints the same names.
    let out = hbid(&[
        "identify",
        record.to_str().unwrap(),
        "--method",
        "windowed",
        "--terms",
        list,
        "--bootstrap",
        "0",
        "--quiet",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let table = String::from_utf8_lossy(&out.stdout);
    for name in names {
        assert!(
            table.lines().any(|l| l.starts_with(&format!("{name} "))),
            "{name}: {table}"
        );
    }
}

/// `--drive-harmonics H` adds cos(kt)*B and sin(kt)*B for k up to H to the default model; a bad
/// list or a drive term on a free record is named on one line, before any work.
#[test]
fn drive_harmonics_and_bad_term_lists() {
    let dir = scratch("terms-bad");
    let record = simulated(
        &dir,
        "rig.csv",
        &["--drive-harmonic", "2:0.1", "--samples", "20000"],
    );
    let r = record.to_str().unwrap();
    let out = hbid(&[
        "identify",
        r,
        "--method",
        "windowed",
        "--drive-harmonics",
        "2",
        "--bootstrap",
        "0",
        "--json",
        "--quiet",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let terms: Vec<&str> = v["terms"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t.as_str().unwrap())
        .collect();
    for name in [
        "x'",
        "sin(x)",
        "sin(t)*cos(x)",
        "sin(2t)*cos(x)",
        "cos(2t)*sin(x)",
    ] {
        assert!(terms.contains(&name), "{name} not in {terms:?}");
    }
    assert!(!terms.iter().any(|t| t.contains("3t")), "{terms:?}");
    let f = v["coefficients"]["sin(2t)*cos(x)"].as_f64().unwrap();
    assert!((f + 0.152).abs() < 0.01, "{f}");
    for (list, mentions) in [
        ("x', x'", "x'"),
        ("x', cos(t)*sin(t)", "cos(t)*sin(t)"),
        ("x', sin(x", "sin(x"),
        ("x', {cos(x),sin(x)", "{"),
        ("", "term"),
    ] {
        let out = hbid(&["identify", r, "--terms", list, "--quiet"]);
        assert_clean_failure(&out, mentions);
    }
    let out = hbid(&["identify", r, "--drive-harmonics", "0", "--quiet"]);
    assert_clean_failure(&out, "--drive-harmonics");
    let out = hbid(&[
        "identify",
        r,
        "--terms",
        "x', sin(x)",
        "--basis",
        "hat:8",
        "--quiet",
    ]);
    assert_clean_failure(&out, "sin(x)");
}

/// The candidate library of the selection tests: the rig pendulum's terms among 18.
const SELECT_LIBRARY: &str =
    "x', sign(x'), x'*|x'|, x'^3, {1,cos(t),sin(t),cos(2t),sin(2t),cos(3t),sin(3t)}*{cos(x),sin(x)}";

/// A rig pendulum (friction, drag, a second drive harmonic, 4096 counts) at `samples_per_period`,
/// 40000 samples: the record and its truth file.
fn rig_for_selection(dir: &Path, samples_per_period: &str) -> (PathBuf, serde_json::Value) {
    simulated_with_truth(
        dir,
        &format!("rig-{samples_per_period}.csv"),
        &[
            "--friction",
            "0.05",
            "--drag",
            "0.05",
            "--drive-harmonic",
            "2:0.1",
            "--counts",
            "4096",
            "--samples-per-period",
            samples_per_period,
            "--samples",
            "40000",
        ],
    )
}

fn strings(v: &serde_json::Value) -> Vec<&str> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap())
        .collect()
}

/// `--select` on a rig pendulum with 18 candidates keeps exactly the six terms of its truth, in
/// the library's order, and refits them alone. At 25 samples per period the three nearly
/// collinear functions of x' carry the weak form's discretisation bias (measured 3.1e-2 on x',
/// 1.0e-2 on sign(x'), 6.3e-3 on x'*|x'|; the other terms 2.5e-4 at most); at 50 samples per
/// period every coefficient is within 2e-2 (measured 5.3e-3 at most). The table prints the
/// equation, the kept terms and a line per dropped term; the saved model has the kept terms only.
#[test]
fn select_keeps_exactly_the_true_terms_of_a_rig() {
    let dir = scratch("select-rig");
    for (samples_per_period, velocity_bound, other_bound) in [("25", 4e-2, 1e-3), ("50", 2e-2, 2e-2)] {
        let (record, truth) = rig_for_selection(&dir, samples_per_period);
        let r = record.to_str().unwrap();
        let coefficients = truth["coefficients"].as_object().unwrap();
        let library = hb_model::TermList::parse(SELECT_LIBRARY).unwrap().names();
        // The truth's nonzero terms, in the library's order; its extra terms are candidates too.
        let true_terms: Vec<&str> = library
            .iter()
            .map(String::as_str)
            .filter(|n| {
                coefficients
                    .get(*n)
                    .and_then(|v| v.as_f64())
                    .is_some_and(|v| v != 0.0)
            })
            .collect();
        assert_eq!(
            true_terms,
            [
                "x'",
                "sign(x')",
                "x'*|x'|",
                "sin(x)",
                "sin(t)*cos(x)",
                "sin(2t)*cos(x)"
            ]
        );
        for extra in strings(&truth["identify"]["extra_terms"]) {
            assert!(library.iter().any(|n| n == extra), "{extra}");
        }
        let model_path = dir.join(format!("model-{samples_per_period}.json"));
        let out = hbid(&[
            "identify",
            r,
            "--method",
            "windowed",
            "--terms",
            SELECT_LIBRARY,
            "--select",
            "--bootstrap",
            "0",
            "--json",
            "--quiet",
            "--save-model",
            model_path.to_str().unwrap(),
        ]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let selection = &v["selection"];
        assert_eq!(strings(&selection["library"]), library);
        assert_eq!(
            strings(&selection["kept"]),
            true_terms,
            "{samples_per_period}: {selection}"
        );
        assert_eq!(strings(&v["terms"]), true_terms);
        let dropped: Vec<&str> = selection["dropped"]
            .as_array()
            .unwrap()
            .iter()
            .map(|d| d["term"].as_str().unwrap())
            .collect();
        assert_eq!(dropped.len(), 12);
        assert!(
            dropped
                .iter()
                .all(|d| !true_terms.contains(d) && library.iter().any(|n| n == d))
        );
        for name in &true_terms {
            let want = coefficients[*name].as_f64().unwrap();
            let got = v["coefficients"][*name].as_f64().unwrap();
            let bound = if name.contains("x'") {
                velocity_bound
            } else {
                other_bound
            };
            let relative = (got - want).abs() / want.abs();
            assert!(
                relative < bound,
                "{samples_per_period} per period, {name}: {got} vs {want} ({relative:.2e})"
            );
        }
        let saved = std::fs::read_to_string(&model_path).unwrap();
        let model = hb_model::IdentifiedModel::<hb_basis::BasisKind>::from_json(&saved).unwrap();
        let saved_names: Vec<&str> = model.coefficients().iter().map(|c| c.name.as_str()).collect();
        assert_eq!(saved_names, true_terms);
        if samples_per_period != "25" {
            continue;
        }
        let out = hbid(&[
            "identify",
            r,
            "--method",
            "windowed",
            "--terms",
            SELECT_LIBRARY,
            "--select",
            "--bootstrap",
            "0",
            "--quiet",
        ]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let table = String::from_utf8_lossy(&out.stdout);
        let lines: Vec<&str> = table.lines().collect();
        let equation = lines[0];
        assert!(
            equation.starts_with("x'' + 0.03") && equation.ends_with(" = 0"),
            "{equation}"
        );
        assert!(equation.contains(" - 1.52 sin(t)*cos(x) "), "{equation}");
        let mut at = 0;
        for name in &true_terms {
            let here = equation[at..]
                .find(&format!(" {name}"))
                .unwrap_or_else(|| panic!("{name}: {equation}"));
            at += here + 1;
        }
        for name in &true_terms {
            assert!(
                lines.iter().any(|l| l.starts_with(&format!("{name} "))),
                "{name}: {table}"
            );
        }
        let from = lines.iter().position(|l| l.starts_with("dropped:")).unwrap();
        assert_eq!(lines.len(), from + 1 + 12, "{table}");
        for (line, name) in lines[from + 1..].iter().zip(&dropped) {
            assert!(
                line.starts_with(&format!("{name} ")) && line.contains(" vs "),
                "{line}"
            );
        }
    }
}

/// The JSON's `selection`: null without `--select`; with it, from the default model (no
/// `--terms`), the library is the default's terms, and every key is there with its type. `report
/// --select` writes the selection into its README.
#[test]
fn select_json_shape_and_report() {
    let dir = scratch("select-json");
    let record = simulated(&dir, "record.csv", &["--samples", "6000"]);
    let r = record.to_str().unwrap();
    let run = |extra: &[&str]| -> serde_json::Value {
        let mut args = vec![
            "identify",
            r,
            "--method",
            "windowed",
            "--bootstrap",
            "0",
            "--json",
            "--quiet",
        ];
        args.extend(extra);
        let out = hbid(&args);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let plain = run(&[]);
    assert!(plain["selection"].is_null());
    let v = run(&["--select", "--select-folds", "5", "--select-tolerance", "1e-5"]);
    let s = v["selection"].as_object().unwrap();
    let mut keys: Vec<&str> = s.keys().map(String::as_str).collect();
    keys.sort_unstable();
    assert_eq!(keys, ["allowance", "dropped", "folds", "kept", "library", "path"]);
    assert_eq!(strings(&s["library"]), strings(&plain["terms"]));
    assert_eq!(strings(&s["kept"]), ["x'", "sin(t)*cos(x)", "sin(x)"]);
    assert_eq!(strings(&v["terms"]), strings(&s["kept"]));
    assert_eq!(s["folds"], 5);
    assert!(s["allowance"].as_f64().unwrap() >= 1e-5);
    for d in s["dropped"].as_array().unwrap() {
        let mut keys: Vec<&str> = d.as_object().unwrap().keys().map(String::as_str).collect();
        keys.sort_unstable();
        assert_eq!(keys, ["term", "unexplained_with", "unexplained_without"]);
        assert!(d["unexplained_without"].as_f64().unwrap() >= 0.0);
        assert!(d["unexplained_with"].as_f64().unwrap() >= 0.0);
    }
    let path = s["path"].as_array().unwrap();
    assert_eq!(path.len(), 7);
    assert!(path[0]["removed"].is_null());
    for (i, step) in path.iter().enumerate() {
        assert_eq!(step["terms"], 7 - i);
        assert!(step["unexplained"].as_f64().unwrap() >= 0.0 && step["std_error"].as_f64().unwrap() >= 0.0);
    }
    assert_eq!(s["dropped"][0]["term"], path[1]["removed"]);

    let out_dir = dir.join("rep");
    let out = hbid(&[
        "report",
        r,
        "--out",
        out_dir.to_str().unwrap(),
        "--validation-periods",
        "50",
        "--bootstrap",
        "0",
        "--select",
        "--quiet",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = std::fs::read_to_string(out_dir.join("README.md")).unwrap();
    // A section per method; the weak form keeps the paper's three terms.
    assert_eq!(text.matches("Model selection kept ").count(), 2, "{text}");
    assert!(
        text.contains("Model selection kept 3 of 7 candidate terms"),
        "{text}"
    );
    assert!(text.contains("| dropped term |"), "{text}");
    assert!(
        text.contains("\n    x'' + 0.03 x' - 1.52 sin(t)*cos(x) + 1.44 sin(x) = 0\n"),
        "{text}"
    );
    let saved = std::fs::read_to_string(out_dir.join("model_windowed.json")).unwrap();
    let model = hb_model::IdentifiedModel::<hb_basis::BasisKind>::from_json(&saved).unwrap();
    assert_eq!(model.coefficients().len(), 3);
}

/// Bad selection options fail on one line before any work, and a selection the folds cannot
/// determine says so on one line.
#[test]
fn bad_selection_options_fail_on_one_line() {
    let dir = scratch("select-bad");
    let record = simulated(&dir, "record.csv", &["--samples", "2000"]);
    let r = record.to_str().unwrap();
    for (extra, mentions) in [
        (&["--select-folds", "1"][..], "--select-folds"),
        (&["--select-folds", "0"], "--select-folds"),
        (&["--select-tolerance", "1"], "--select-tolerance"),
        (&["--select-tolerance", "-0.1"], "--select-tolerance"),
        (&["--select-tolerance", "nan"], "--select-tolerance"),
    ] {
        let mut args = vec!["identify", r, "--select", "--quiet"];
        args.extend(extra);
        assert_clean_failure(&hbid(&args), mentions);
    }
    // The options mean nothing without --select.
    let out = hbid(&["identify", r, "--select-folds", "3", "--quiet"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--select"));
    // Four windows of one period, 5 equations each: enough for the 13 candidates, not with one
    // of two folds held out.
    let short = dir.join("short.csv");
    let text = std::fs::read_to_string(&record).unwrap();
    let lines: Vec<&str> = text.lines().filter(|l| !l.starts_with('#')).take(102).collect();
    std::fs::write(&short, lines.join("\n") + "\n").unwrap();
    let library = "x', sign(x'), x'*|x'|, {1,cos(t),sin(t),cos(2t),sin(2t)}*{cos(x),sin(x)}";
    let base = [
        "identify",
        short.to_str().unwrap(),
        "--method",
        "windowed",
        "--window-periods",
        "1",
        "--terms",
        library,
        "--bootstrap",
        "0",
        "--quiet",
    ];
    let out = hbid(&base);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let mut args = base.to_vec();
    args.extend(["--select", "--select-folds", "2"]);
    assert_clean_failure(&hbid(&args), "model selection");
}

/// A vibrometer's velocity or an accelerometer's acceleration of a chaotic two-well Duffing
/// oscillator, identified with the displacement's model (no constant term): the integrated
/// record's offset and, for the acceleration, its slope are found by the model, and the
/// coefficients come out as from the displacement. (Removing the least-squares line alone
/// left them 15 % wrong on a 300-period record: its true displacement has a trend.)
#[test]
fn velocity_and_acceleration_records_give_the_displacements_model() {
    let dir = scratch("measured-drift");
    let truth_path = dir.join("truth.json");
    let record = simulated(
        &dir,
        "duffing.csv",
        &[
            "--system",
            "duffing",
            "--samples-per-period",
            "100",
            "--samples",
            "20000",
            "--truth",
            truth_path.to_str().unwrap(),
        ],
    );
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&truth_path).unwrap()).unwrap();
    let truth: Vec<(String, f64)> = truth["coefficients"]
        .as_object()
        .unwrap()
        .iter()
        .map(|(k, v)| (k.clone(), v.as_f64().unwrap()))
        .collect();
    // x'' = -Σ c g(t, x, x'), t being the drive's phase (the record's time from the drive's zero).
    let (_, rows) = read_rows(&record);
    let mut velocity = String::from("t,v\n");
    let mut acceleration = String::from("t,a\n");
    for r in &rows {
        let a: f64 = -truth
            .iter()
            .map(|(name, c)| c * term_value(name, r[0], r[1], r[2]))
            .sum::<f64>();
        velocity.push_str(&format!("{},{}\n", r[0], r[2]));
        acceleration.push_str(&format!("{},{a}\n", r[0]));
    }
    let terms = "x', x, x^3, cos(t), sin(t)";
    for (name, text, measured, col, tolerance) in [
        ("velocity.csv", velocity, "velocity", "v", 1e-6),
        ("acceleration.csv", acceleration, "acceleration", "a", 1e-4),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let out = hbid(&[
            "identify",
            path.to_str().unwrap(),
            "--signal",
            "line",
            "--measured",
            measured,
            "--angle-col",
            col,
            "--method",
            "windowed",
            "--terms",
            terms,
            "--bootstrap",
            "0",
            "--json",
            "--quiet",
        ]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("drift of the integrated record"), "{err}");
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        for name in ["x'", "x", "x^3", "cos(t)"] {
            let want = truth.iter().find(|(n, _)| n == name).unwrap().1;
            let got = v["coefficients"][name].as_f64().unwrap();
            assert!(
                (got - want).abs() < tolerance * want.abs(),
                "{measured} {name}: {got} vs {want}"
            );
        }
    }
}

/// The coefficients of `hbid identify --json` on `args`, with its list of terms and the whole JSON.
fn identify_json(
    args: &[&str],
) -> (
    Vec<String>,
    serde_json::Map<String, serde_json::Value>,
    serde_json::Value,
) {
    let mut all = vec!["identify", "--quiet", "--bootstrap", "0", "--json"];
    all.extend(args);
    let out = hbid(&all);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let terms = v["terms"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t.as_str().unwrap().to_owned())
        .collect();
    let coefficients = v["coefficients"].as_object().unwrap().clone();
    (terms, coefficients, v)
}

/// `hbid simulate --write-drive` writes the drive as it enters the equation: for the Duffing
/// oscillator `f [cos t + Σ ρ_k cos(k t + φ_k)]` at each stamp, a fourth column `p` (in `.npy`
/// too), the other columns unchanged.
#[test]
fn simulate_writes_the_drive_beside_the_record() {
    let dir = scratch("write-drive");
    let common = [
        "--system",
        "duffing",
        "--drive-harmonic",
        "3:0.2:0.4",
        "--samples",
        "400",
        "--transient-periods",
        "3",
    ];
    let with: Vec<&str> = common.iter().copied().chain(["--write-drive"]).collect();
    let (header, rows) = read_rows(&simulated(&dir, "with.csv", &with));
    let (plain_header, plain) = read_rows(&simulated(&dir, "plain.csv", &common));
    assert_eq!((header.as_str(), plain_header.as_str()), ("t,x,v,p", "t,x,v"));
    for (row, plain) in rows.iter().zip(&plain) {
        assert_eq!(&row[..3], &plain[..]);
        let t = row[0];
        let want = 0.3 * (t.cos() + 0.2 * (3.0 * t + 0.4).cos());
        assert!((row[3] - want).abs() < 1e-12, "{} vs {want}", row[3]);
    }
    let npy = simulated(&dir, "with.npy", &with);
    let bytes = std::fs::read(npy).unwrap();
    let header = String::from_utf8_lossy(&bytes[..128]);
    assert!(header.contains("'shape': (400, 4, )"), "{header}");
}

/// `--forcing-col`: the measured drive `p` in place of cos(t), sin(t). On the two-well Duffing
/// oscillator with second and third drive harmonics and 0.2 % sensor noise, the default terms on
/// the line (`x'`, `{1,p}*{x,x^2,x^3}`, `p`) give the stiffness within 1e-3 (measured 1e-4 at
/// most) with no drive harmonic named, and `--select` keeps exactly the four true terms; on the rig
/// pendulum (friction, drag, a second drive harmonic, 4096 counts) `--select` from nine candidates
/// keeps exactly its five terms, each within 2e-2 (5e-3 at most measured, 50 per period). A record
/// in seconds sampled at no whole number per period, with gaps, keeps the drive aligned: the
/// coefficient of `p` is −1 within 1e-6.
#[test]
fn a_measured_drive_column_identifies_duffing_and_the_rig() {
    let dir = scratch("forcing-col");
    let duffing = simulated(
        &dir,
        "duffing.csv",
        &[
            "--system",
            "duffing",
            "--drive-harmonic",
            "2:0.1",
            "--drive-harmonic",
            "3:0.05",
            "--samples-per-period",
            "25",
            "--samples",
            "10000",
            "--noise",
            "0.005919",
            "--write-drive",
        ],
    );
    let d = duffing.to_str().unwrap();
    let model = dir.join("duffing-model.json");
    let base = ["--signal", "line", "--method", "windowed", "--forcing-col", "p"];
    let mut args: Vec<&str> = vec![d];
    args.extend(base);
    args.extend(["--save-model", model.to_str().unwrap()]);
    let (terms, c, v) = identify_json(&args);
    assert_eq!(
        terms,
        ["x'", "x", "x^2", "x^3", "p*x", "p*x^2", "p*x^3", "p"],
        "the default terms with a measured drive"
    );
    assert_eq!(v["drive_column"], "p");
    for (name, want) in [("x", -1.0), ("x^3", 1.0)] {
        let got = c[name].as_f64().unwrap();
        assert!((got - want).abs() < 1e-3, "{name}: {got}");
    }
    assert!((c["p"].as_f64().unwrap() + 1.0).abs() < 1e-2);
    let saved = std::fs::read_to_string(&model).unwrap();
    assert!(saved.contains("\"drive_column\": \"p\""), "{saved}");
    let mut args: Vec<&str> = vec![d, "--select"];
    args.extend(base);
    let (terms, c, v) = identify_json(&args);
    assert_eq!(terms, ["x'", "x", "x^3", "p"], "{}", v["selection"]);
    for (name, want) in [("x", -1.0), ("x^3", 1.0)] {
        let got = c[name].as_f64().unwrap();
        assert!((got - want).abs() < 1e-3, "{name}: {got}");
    }

    let rig = simulated(
        &dir,
        "rig.csv",
        &[
            "--friction",
            "0.05",
            "--drag",
            "0.05",
            "--drive-harmonic",
            "2:0.1",
            "--counts",
            "4096",
            "--samples-per-period",
            "50",
            "--samples",
            "30000",
            "--write-drive",
        ],
    );
    let (terms, c, _) = identify_json(&[
        rig.to_str().unwrap(),
        "--method",
        "windowed",
        "--forcing-col",
        "p",
        "--select",
        "--terms",
        "x', sign(x'), x'*|x'|, x'^3, {1,p}*{cos(x),sin(x)}, p",
    ]);
    let truth = [
        ("x'", 0.03),
        ("sign(x')", 0.05),
        ("x'*|x'|", 0.05),
        ("sin(x)", 1.0 / (0.8333 * 0.8333)),
        ("p*cos(x)", -1.0),
    ];
    assert_eq!(terms, truth.map(|(n, _)| n));
    for (name, want) in truth {
        let got = c[name].as_f64().unwrap();
        assert!((got - want).abs() < 2e-2 * want.abs(), "{name}: {got} vs {want}");
    }

    let seconds = simulated(
        &dir,
        "seconds.csv",
        &[
            "--system",
            "duffing",
            "--drive-harmonic",
            "3:0.1",
            "--drive-frequency",
            "1.3",
            "--sample-rate",
            "61.7",
            "--duration",
            "200",
            "--gaps",
            "2:40",
            "--time-decimals",
            "5",
            "--write-drive",
        ],
    );
    let (_, c, v) = identify_json(&[
        seconds.to_str().unwrap(),
        "--signal",
        "line",
        "--method",
        "windowed",
        "--forcing-frequency",
        "1.3",
        "--forcing-col",
        "4",
        "--terms",
        "x', x, x^3, p",
    ]);
    let w = std::f64::consts::TAU * 1.3;
    assert!((c["p"].as_f64().unwrap() + 1.0).abs() < 1e-6, "{c:?}");
    assert!((c["x"].as_f64().unwrap() + w * w).abs() < 1e-5 * w * w, "{c:?}");
    assert_eq!(v["drive_column"], "4");
}

/// Every misuse of a measured drive is one line naming what to change.
#[test]
fn measured_drive_misuse_is_one_clear_line() {
    let dir = scratch("forcing-col-bad");
    let record = simulated(
        &dir,
        "d.csv",
        &["--system", "duffing", "--samples", "3000", "--write-drive"],
    );
    let r = record.to_str().unwrap();
    let windowed = ["--signal", "line", "--method", "windowed", "--quiet"];
    let run = |extra: &[&str]| {
        let mut all = vec!["identify", r];
        all.extend(windowed);
        all.extend(extra);
        hbid(&all)
    };
    assert_clean_failure(&run(&["--drive-col", "q"]), "--drive-col");
    assert_clean_failure(&run(&["--forcing-col", "x"]), "both");
    assert_clean_failure(&run(&["--forcing-col", "9"]), "--drive-col");
    assert_clean_failure(&run(&["--terms", "x', x, x^3, p"]), "--drive-col");
    assert_clean_failure(
        &run(&["--forcing-col", "p", "--terms", "x', x, x^3, cos(t)"]),
        "no term",
    );
    assert_clean_failure(
        &run(&["--forcing-col", "p", "--drive-harmonics", "2"]),
        "--drive-harmonics",
    );
    assert_clean_failure(
        &run(&[
            "--forcing-col",
            "p",
            "--forcing",
            "none",
            "--no-parametric",
            "--forcing-period",
            "6.283185307179586",
        ]),
        "no term",
    );
    let upo = hbid(&[
        "identify",
        r,
        "--signal",
        "line",
        "--method",
        "upo",
        "--drive-col",
        "p",
        "--quiet",
    ]);
    assert_clean_failure(&upo, "weak form");
    let report = hbid(&[
        "report",
        r,
        "--signal",
        "line",
        "--forcing-col",
        "p",
        "--out",
        dir.join("report").to_str().unwrap(),
        "--quiet",
    ]);
    assert_clean_failure(&report, "report");
    assert!(!dir.join("report").exists(), "no report folder for a refused run");
    // A broken drive cell names its line.
    let text = std::fs::read_to_string(&record).unwrap();
    let broken: String = text
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if i == 100 {
                let mut cells: Vec<&str> = l.split(',').collect();
                cells[3] = "nan";
                cells.join(",") + "\n"
            } else {
                format!("{l}\n")
            }
        })
        .collect();
    let bad = dir.join("bad.csv");
    std::fs::write(&bad, broken).unwrap();
    let out = hbid(&[
        "identify",
        bad.to_str().unwrap(),
        "--forcing-col",
        "p",
        "--signal",
        "line",
        "--method",
        "windowed",
        "--quiet",
    ]);
    assert_clean_failure(&out, "line 101");
}

/// The coefficients of a `--truth` file.
fn truth_coefficients(path: &Path) -> Vec<(String, f64)> {
    let truth: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    truth["coefficients"]
        .as_object()
        .unwrap()
        .iter()
        .map(|(k, v)| (k.clone(), v.as_f64().unwrap()))
        .collect()
}

/// A noise-free pendulum record of 20000 samples at 32 per period whose orbit segments overlap:
/// with f = 0.95 and c = 0.05 a chaotic transient of 85 periods settles on a periodic orbit, and
/// close returns find 120 segments in its first 2700 samples, orbits of several periods a few
/// samples apart in one passage. A block of one segment over the median gap between starts made
/// runs of 64 and no resample; the runs follow the overlap of the segments now, and the
/// identification gives every coefficient within 1.2e-2 with its intervals.
#[test]
fn overlapping_orbit_segments_are_identified_with_intervals() {
    let dir = scratch("overlap");
    let truth = dir.join("truth.json");
    let record = simulated(
        &dir,
        "h.csv",
        &[
            "--samples",
            "20000",
            "--samples-per-period",
            "32",
            "--f",
            "0.95",
            "--c",
            "0.05",
            "--truth",
            truth.to_str().unwrap(),
        ],
    );
    let out = hbid(&[
        "identify",
        record.to_str().unwrap(),
        "--method",
        "upo",
        "--basis",
        "harmonic:1",
        "--json",
        "--quiet",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let segments = v["orbits_used"].as_u64().unwrap();
    assert!(segments > 100, "{segments}");
    for (name, want) in truth_coefficients(&truth) {
        let got = v["coefficients"][&name].as_f64().unwrap();
        assert!((got - want).abs() < 1.2e-2, "{name}: {got} vs {want}");
        let interval = &v["intervals"][&name];
        let (lo, hi) = (interval[0].as_f64().unwrap(), interval[1].as_f64().unwrap());
        assert!(lo <= got && got <= hi && lo < hi, "{name}: {got} in [{lo}, {hi}]");
    }
    assert!(v["no_intervals"].is_null());
}

/// Too few segments for two runs of the bootstrap's block give the model, its standard errors and
/// one line saying why there are no intervals, never a failed identification: three windows of
/// three periods over five periods (each sample shared by 1.8 of them) cannot be resampled in
/// runs of two.
#[test]
fn an_identification_never_fails_for_its_intervals() {
    let dir = scratch("no-intervals");
    let record = simulated(&dir, "short.csv", &["--samples", "150"]);
    let run = |json: bool| {
        let mut args = vec![
            "identify",
            record.to_str().unwrap(),
            "--method",
            "windowed",
            "--quiet",
        ];
        if json {
            args.push("--json");
        }
        let out = hbid(&args);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        out
    };
    let v: serde_json::Value = serde_json::from_slice(&run(true).stdout).unwrap();
    assert_eq!(v["orbits_used"], 3);
    assert!(v["intervals"].is_null());
    let why = v["no_intervals"].as_str().unwrap();
    assert!(why.contains("two runs of 2"), "{why}");
    for (name, value) in &pendulum_truth() {
        let got = v["coefficients"][name].as_f64().unwrap();
        assert!((got - value).abs() < 1e-3, "{name}: {got} vs {value}");
        assert!(v["std_errors"][name].as_f64().unwrap() > 0.0);
    }
    let table = String::from_utf8(run(false).stdout).unwrap();
    let lines: Vec<&str> = table
        .lines()
        .filter(|l| l.starts_with("no intervals: "))
        .collect();
    assert_eq!(lines.len(), 1, "{table}");
    assert!(table.contains("sin(t)*cos(x)"), "{table}");
}

/// A two-well Duffing oscillator driven with 12 % and 14 % second and third harmonics, and a
/// library with `cos(3t)`, `sin(3t)` selected from with the default harmonics: the band reaches
/// the library's third drive harmonic, and the selection keeps `cos(3t)` (the weak form's own
/// band of two harmonics dropped it in silence).
#[test]
fn the_default_band_reaches_the_librarys_drive_harmonics() {
    let dir = scratch("band");
    let truth = dir.join("truth.json");
    let record = simulated(
        &dir,
        "duffing.csv",
        &[
            "--system",
            "duffing",
            "--drive-harmonic",
            "2:0.12",
            "--drive-harmonic",
            "3:0.14",
            "--samples",
            "10000",
            "--truth",
            truth.to_str().unwrap(),
        ],
    );
    let out = hbid(&[
        "identify",
        record.to_str().unwrap(),
        "--signal",
        "line",
        "--method",
        "windowed",
        "--terms",
        "x', x, x^3, 1, cos(t), sin(t), cos(2t), sin(2t), cos(3t), sin(3t)",
        "--select",
        "--json",
        "--quiet",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        strings(&v["selection"]["kept"]),
        ["x'", "x", "x^3", "cos(t)", "cos(2t)", "cos(3t)"]
    );
    for (name, want) in truth_coefficients(&truth) {
        if let Some(got) = v["coefficients"][&name].as_f64() {
            assert!((got - want).abs() < 1e-6, "{name}: {got} vs {want}");
        } else {
            assert_eq!(want, 0.0, "{name} dropped");
        }
    }
}

/// A pendulum driven by a torque, `x'' + 0.75 x' + 2.25 sin x = 3.375 cos t` (Baker and
/// Gollub's chaotic pendulum in the drive's time), which the default circle library has no term
/// for: by either method the identification says that the library does not describe the record,
/// with the share explained held out beside the one in sample, in the table (marked above the
/// coefficients), the JSON and the warning. The paper's pendulum is not marked.
#[test]
fn a_drive_the_library_cannot_express_marks_the_table() {
    use pendulum_sim::{SecondOrderSystem, SimulationConfig, simulate};
    struct Torque;
    impl SecondOrderSystem for Torque {
        fn acceleration(&self, t: f64, x: f64, v: f64) -> f64 {
            -0.75 * v - 2.25 * x.sin() + 3.375 * t.cos()
        }
        fn jacobian(&self, _t: f64, x: f64, _v: f64) -> [f64; 2] {
            [-2.25 * x.cos(), -0.75]
        }
    }
    let dir = scratch("torque");
    let config = SimulationConfig::paper().with_samples(10_000).unwrap();
    let trajectory = simulate(&Torque, &config).unwrap();
    let torque = dir.join("torque.csv");
    let mut text = String::from("t,theta\n");
    for (t, x) in trajectory.t.iter().zip(trajectory.wrapped()) {
        text.push_str(&format!("{t},{x}\n"));
    }
    std::fs::write(&torque, text).unwrap();
    let pendulum = simulated(&dir, "pendulum.csv", &["--samples", "10000"]);
    let run = |record: &Path, method: &str, json: bool| {
        let mut args = vec![
            "identify",
            record.to_str().unwrap(),
            "--method",
            method,
            "--bootstrap",
            "0",
            "--quiet",
        ];
        if json {
            args.push("--json");
        }
        let out = hbid(&args);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        out
    };
    for method in ["upo", "windowed"] {
        let out = run(&torque, method, true);
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let (explained, held) = (
            v["explained"].as_f64().unwrap(),
            v["held_out_explained"].as_f64().unwrap(),
        );
        assert!(explained < 0.4 && held < 0.4, "{method}: {explained} {held}");
        let warning = v["warning"].as_str().unwrap();
        assert!(
            warning.contains("the library does not describe the record"),
            "{warning}"
        );
        assert!(String::from_utf8_lossy(&out.stderr).contains(warning));
        let table = String::from_utf8(run(&torque, method, false).stdout).unwrap();
        let marked = table
            .lines()
            .position(|l| l.starts_with("NOT A DESCRIPTION OF THE RECORD: "))
            .unwrap_or_else(|| panic!("{method}: not marked:\n{table}"));
        let header = table.lines().position(|l| l.starts_with("term ")).unwrap();
        assert!(marked < header, "{table}");
        assert!(table.contains("of stretches it was not fitted on"), "{table}");

        let out = run(&pendulum, method, true);
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert!(v["warning"].is_null(), "{method}: {}", v["warning"]);
        let (explained, held) = (
            v["explained"].as_f64().unwrap(),
            v["held_out_explained"].as_f64().unwrap(),
        );
        assert!(held > 0.95 && explained > 0.95, "{method}: {explained} {held}");
        let table = String::from_utf8(run(&pendulum, method, false).stdout).unwrap();
        assert!(!table.contains("NOT A DESCRIPTION"), "{table}");
    }
}

/// The systems of two coordinates write their documented columns as CSV and `.npy` (the same
/// numbers), and the angles of a rig in seconds sampled in no whole ratio to the drive.
#[test]
fn simulate_systems_write_their_columns() {
    let dir = scratch("systems-columns");
    for (system, extra, header) in [
        ("double-pendulum", vec![], "t,theta1,theta2,omega1,omega2"),
        (
            "double-pendulum",
            vec![
                "--drive-frequency",
                "1.02",
                "--sample-rate",
                "100",
                "--write-drive",
            ],
            "t,theta1,theta2,omega1,omega2,p",
        ),
        ("arm", vec![], "t,q1,q2,v1,v2,tau1,tau2"),
        ("coupled-duffing", vec![], "t,x1,x2,v1,v2,a"),
    ] {
        let mut args = vec!["--system", system, "--samples", "400"];
        args.extend(extra.iter().copied());
        let csv = simulated(&dir, &format!("{system}.csv"), &args);
        let npy = simulated(&dir, &format!("{system}.npy"), &args);
        let (head, rows) = read_rows(&csv);
        assert_eq!(head, header);
        let width = header.split(',').count();
        assert!(rows.len() == 400 && rows.iter().all(|r| r.len() == width));
        let bytes = std::fs::read(&npy).unwrap();
        let text = String::from_utf8_lossy(&bytes[10..128]);
        assert!(text.contains(&format!("(400, {width}, )")), "{text}");
        for (i, row) in rows.iter().enumerate().step_by(97) {
            for (j, v) in row.iter().enumerate() {
                let at = 128 + 8 * (width * i + j);
                assert_eq!(f64::from_le_bytes(bytes[at..at + 8].try_into().unwrap()), *v);
            }
        }
        if extra.contains(&"--sample-rate") {
            assert!((rows[1][0] - rows[0][0] - 0.01).abs() < 1e-12);
            assert!(
                rows.iter()
                    .all(|r| (-std::f64::consts::PI..std::f64::consts::PI).contains(&r[2]))
            );
        }
    }
}

/// An option of another system, or a bad value of a system's own, fails on one line naming the
/// flag (and the systems it belongs to), leaving no file.
#[test]
fn simulate_system_options_fail_cleanly() {
    let dir = scratch("systems-bad");
    let target = dir.join("never.csv");
    let truth = dir.join("never.json");
    for (args, mentions) in [
        (vec!["--mu", "0.3"], "--mu is the double pendulum's mass ratio"),
        (
            vec!["--system", "arm", "--r", "1"],
            "--system pendulum or --system double-pendulum",
        ),
        (
            vec!["--system", "double-pendulum", "--torque1", "0.4:10"],
            "--torque1",
        ),
        (vec!["--system", "arm", "--torque1", "0.4"], "a:omega[:phase]"),
        (
            vec!["--system", "arm", "--drive-frequency", "1"],
            "--drive-frequency",
        ),
        (
            vec!["--system", "coupled-duffing", "--counts", "4096"],
            "angle encoder",
        ),
        (vec!["--system", "double-pendulum", "--x0", "1"], "--q0"),
        (
            vec!["--system", "double-pendulum", "--q0", "1"],
            "--q0 1: give two numbers",
        ),
        (vec!["--system", "double-pendulum", "--q0", "1,x"], "not a number"),
        (
            vec!["--system", "coupled-duffing", "--coupling", "nan"],
            "--coupling",
        ),
        (
            vec!["--system", "arm", "--joint-friction", "-1,0"],
            "--joint-friction",
        ),
        (vec!["--system", "arm", "--sample-rate", "0"], "--sample-rate 0"),
        (vec!["--jitter", "-0.1"], "--jitter"),
        // A massless first link: the mass matrix is singular with the links in line.
        (
            vec!["--system", "double-pendulum", "--mu", "1"],
            "must lie in [0, 1)",
        ),
    ] {
        let mut all = vec!["simulate", "--samples", "500"];
        all.extend(args.iter().copied());
        all.extend([
            "--truth",
            truth.to_str().unwrap(),
            "--out",
            target.to_str().unwrap(),
        ]);
        assert_clean_failure(&hbid(&all), &mentions.to_lowercase());
        assert!(!target.exists() && !truth.exists(), "{args:?} left a file");
    }
}

/// Columns of a system given by their positions need names for the terms: the error names the
/// option whose list holds the position and how to name it.
#[test]
fn system_columns_by_position_are_named_by_the_option_that_gives_them() {
    let dir = scratch("systems-positions");
    let arm = simulated(&dir, "arm.csv", &["--system", "arm", "--samples", "2000"]);
    let r = arm.to_str().unwrap();
    let out = hbid(&[
        "identify",
        r,
        "--coords",
        "q1,q2",
        "--drive-col",
        "6,7",
        "--window",
        "1.885",
    ]);
    assert_clean_failure(&out, "--drive-col: the name `6` cannot be used");
    assert_clean_failure(
        &out,
        "needs a name for the terms to call it by: name=column (tau1=6)",
    );
    let out = hbid(&[
        "identify",
        r,
        "--coords",
        "q1,3",
        "--drive-col",
        "tau1,tau2",
        "--window",
        "1.885",
    ]);
    assert_clean_failure(&out, "--coords: the name `3` cannot be used");
    // A drive no equation's terms name is a mistake, not a column read for nothing.
    let out = hbid(&[
        "identify",
        r,
        "--coords",
        "q1,q2",
        "--drive-col",
        "tau1,tau2,v1",
        "--window",
        "1.885",
        "--terms",
        "q1: sin(q1), q1', tau1; q2: sin(q1+q2), q2', tau2",
    ]);
    assert_clean_failure(&out, "--drive-col: the drive 'v1' is in no equation's terms");
    // Windows shorter than two samples per unit are refused, in time as in samples.
    let out = hbid(&[
        "identify",
        r,
        "--coords",
        "q1,q2",
        "--drive-col",
        "tau1,tau2",
        "--window",
        "1e-9",
    ]);
    assert_clean_failure(
        &out,
        "it needs at least 2 (a longer --window, or fewer --window-periods)",
    );
    let out = hbid(&[
        "identify",
        r,
        "--coords",
        "q1,q2",
        "--drive-col",
        "tau1=6,tau2=7",
        "--window",
        "1.885",
        "--bootstrap",
        "0",
        "--quiet",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
}

/// A drive harmonic at or above half the samples per period is refused by name: sampled, it is
/// a lower harmonic's alias and its coefficient would be anything.
#[test]
fn a_drive_harmonic_the_sampling_cannot_resolve_is_refused() {
    let dir = scratch("aliased-harmonic");
    let record = simulated(&dir, "p.csv", &["--samples", "3000"]);
    let r = record.to_str().unwrap();
    for method in ["windowed", "upo"] {
        let out = hbid(&[
            "identify",
            r,
            "--method",
            method,
            "--terms",
            "sin(x), sin(13t)*cos(x), x'",
        ]);
        assert_clean_failure(
            &out,
            "the term `sin(13t)*cos(x)` has the drive's harmonic 13, which 25 samples per drive period cannot resolve",
        );
    }
    let out = hbid(&[
        "identify",
        r,
        "--terms",
        "sin(x), sin(12t)*cos(x), x'",
        "--bootstrap",
        "0",
        "--quiet",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
}

/// The spikes of a system's record are named by their column, every coordinate's alike.
#[test]
fn a_systems_spikes_are_named_by_their_column() {
    let dir = scratch("system-spikes");
    let record = simulated(
        &dir,
        "dp.csv",
        &[
            "--system",
            "double-pendulum",
            "--samples",
            "6400",
            "--counts",
            "4096",
            "--bit-errors",
            "0.002",
        ],
    );
    let out = hbid(&[
        "identify",
        record.to_str().unwrap(),
        "--coords",
        "theta1,theta2",
        "--bootstrap",
        "0",
        "--quiet",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    for column in ["theta1", "theta2"] {
        assert!(
            stderr
                .lines()
                .any(|l| l.starts_with(&format!("warning: {column}: "))
                    && (l.contains("isolated spike(s)") || l.contains("outlying sample(s)"))),
            "{stderr}"
        );
    }
    assert!(!stderr.contains("coordinate 2"), "{stderr}");
}

/// Angles in an encoder's counts or in degrees: read as radians they are nonsense, and the
/// wrap says what they are; with --angle-unit they are the radians' record to the printed digit.
#[test]
fn angles_in_counts_or_degrees_are_read_in_their_unit() {
    let dir = scratch("angle-units");
    let rig = [
        "--drive-frequency",
        "1.02",
        "--sample-rate",
        "500",
        "--samples",
        "20000",
    ];
    let radians = simulated(&dir, "rad.csv", &[&rig[..], &["--counts", "4096"]].concat());
    let truth = dir.join("counts.json");
    let counts = simulated(
        &dir,
        "counts.csv",
        &[
            &rig[..],
            &[
                "--counts",
                "4096",
                "--raw-counts",
                "--truth",
                truth.to_str().unwrap(),
            ],
        ]
        .concat(),
    );
    let hint: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&truth).unwrap()).unwrap();
    assert_eq!(hint["identify"]["angle_unit"], "counts:4096");
    let (head, rows) = read_rows(&counts);
    assert_eq!(head, "t,count,omega");
    let degrees = dir.join("deg.csv");
    let (_, rad_rows) = read_rows(&radians);
    let text: String = rad_rows
        .iter()
        .map(|r| format!("{},{}\n", r[0], r[1].to_degrees()))
        .collect();
    std::fs::write(&degrees, format!("t,theta\n{text}")).unwrap();
    assert!(
        rows.iter()
            .all(|r| (0.0..4096.0).contains(&r[1]) && r[1].fract() == 0.0)
    );
    let identify = |file: &Path, extra: &[&str]| {
        let mut args = vec![
            "identify",
            file.to_str().unwrap(),
            "--drive-frequency",
            "1.02",
            "--bootstrap",
            "0",
        ];
        args.extend(extra);
        hbid(&args)
    };
    let sin = |out: &Output| -> String {
        String::from_utf8_lossy(&out.stdout)
            .lines()
            .find(|l| l.starts_with("sin(x) "))
            .unwrap_or_default()
            .to_owned()
    };
    let reference = identify(&radians, &[]);
    assert!(reference.status.success());
    for (file, extra, unit) in [
        (&counts, &["--angle-col", "count"][..], "counts:4096"),
        (&degrees, &[][..], "deg"),
    ] {
        let out = identify(file, extra);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            stderr.contains(&format!("read as radians; give --angle-unit {unit}")),
            "{stderr}"
        );
        let out = identify(file, &[extra, &["--angle-unit", unit][..]].concat());
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        assert_eq!(sin(&out), sin(&reference), "{unit}");
        assert!(!String::from_utf8_lossy(&out.stderr).contains("warning"));
    }
    assert_clean_failure(
        &identify(&degrees, &["--angle-unit", "deg", "--signal", "line"]),
        "--angle-unit deg: is the unit of angles on the circle",
    );
    assert_clean_failure(
        &identify(&degrees, &["--angle-unit", "grad"]),
        "rad, deg or counts:n",
    );
}

/// A system's angles in degrees: the wrap is warned of by each column's name, and read in
/// degrees they give the radians' coefficients to the printed digit.
#[test]
fn a_systems_angles_in_degrees_are_named_and_read() {
    let dir = scratch("system-degrees");
    let (radians, hint) = simulated_system(&dir, "dp.csv", "double-pendulum");
    let terms = hint["identify"]["terms"].as_str().unwrap().to_owned();
    let (head, rows) = read_rows(&radians);
    let text: String = rows
        .iter()
        .map(|r| {
            let cells: Vec<String> = std::iter::once(r[0].to_string())
                .chain(r[1..5].iter().map(|v| v.to_degrees().to_string()))
                .collect();
            cells.join(",") + "\n"
        })
        .collect();
    let degrees = dir.join("deg.csv");
    std::fs::write(&degrees, format!("{head}\n{text}")).unwrap();
    let identify = |file: &Path, extra: &[&str]| {
        let mut args = vec![
            "identify",
            file.to_str().unwrap(),
            "--coords",
            "theta1,theta2",
            "--terms",
            &terms,
        ];
        args.extend(["--bootstrap", "0"]);
        args.extend(extra);
        hbid(&args)
    };
    let read_as_radians = identify(&degrees, &[]);
    let stderr = String::from_utf8_lossy(&read_as_radians.stderr);
    for column in ["theta1", "theta2"] {
        assert!(
            stderr.contains(&format!("warning: {column} jumps by about"))
                && stderr.contains("--angle-unit deg"),
            "{stderr}"
        );
    }
    let reference = identify(&radians, &["--quiet"]);
    let read = identify(&degrees, &["--angle-unit", "deg", "--quiet"]);
    assert!(read.status.success(), "{}", String::from_utf8_lossy(&read.stderr));
    assert_eq!(read.stdout, reference.stdout);
}

/// The drive's period estimated on a system searches its first coordinate alone: where that
/// fails, the error says so and how to give the drive.
#[test]
fn a_systems_drive_search_says_what_it_searched() {
    let dir = scratch("system-drive-auto");
    let record = simulated(
        &dir,
        "dp.csv",
        &[
            "--system",
            "double-pendulum",
            "--drive-frequency",
            "2",
            "--sample-rate",
            "200",
            "--samples",
            "8000",
        ],
    );
    let out = hbid(&[
        "identify",
        record.to_str().unwrap(),
        "--coords",
        "theta1,theta2",
        "--drive-frequency",
        "auto:1..3",
        "--bootstrap",
        "0",
        "--quiet",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(
        stderr.contains("searched on the first coordinate alone")
            && stderr.contains("--drive-frequency or --drive-period"),
        "{stderr}"
    );
}

/// A model of one coordinate compared with a record whose several coordinates are named is
/// refused, not run against the first of them.
#[test]
fn compare_refuses_a_model_of_one_coordinate_on_several() {
    let dir = scratch("compare-one-on-two");
    let pendulum = simulated(&dir, "p.csv", &["--samples", "3000"]);
    let double = simulated(
        &dir,
        "dp.csv",
        &["--system", "double-pendulum", "--samples", "3000"],
    );
    let model = dir.join("p.json");
    let out = hbid(&[
        "identify",
        pendulum.to_str().unwrap(),
        "--bootstrap",
        "0",
        "--quiet",
        "--save-model",
        model.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let out = hbid(&[
        "compare",
        model.to_str().unwrap(),
        double.to_str().unwrap(),
        "--coords",
        "theta1,theta2",
    ]);
    assert_clean_failure(&out, "--coords theta1,theta2: the model has one coordinate");
    let out = hbid(&[
        "compare",
        model.to_str().unwrap(),
        double.to_str().unwrap(),
        "--angle-col",
        "theta1",
        "--quiet",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
}

/// A seed gives one record, its encoders' errors, gaps and jitter included; gaps drop the same
/// rows of every column.
#[test]
fn simulate_systems_are_seeded_and_gapped_row_by_row() {
    let dir = scratch("systems-seeded");
    let rig = [
        "--system",
        "arm",
        "--samples",
        "2000",
        "--counts",
        "4096",
        "--bit-errors",
        "0.01",
        "--noise",
        "0.002",
        "--jitter",
        "0.0001",
        "--time-decimals",
        "5",
    ];
    let with = |seed: &str, name: &str, more: &[&str]| {
        let mut args = rig.to_vec();
        args.extend(["--seed", seed]);
        args.extend(more);
        std::fs::read_to_string(simulated(&dir, name, &args)).unwrap()
    };
    let a = with("3", "a.csv", &[]);
    assert_eq!(a, with("3", "b.csv", &[]));
    assert_ne!(a, with("4", "c.csv", &[]));
    let gapped = with("3", "d.csv", &["--gaps", "2:100"]);
    let rows: Vec<&str> = a.lines().collect();
    let kept: Vec<&str> = gapped.lines().collect();
    assert_eq!(kept.len(), rows.len() - 200);
    // Every kept row is the whole row of the record without gaps (stamps and columns alike).
    let mut at = 0;
    for row in &kept {
        let found = rows[at..].iter().position(|r| r == row);
        assert!(found.is_some(), "{row} is not a row of the record without gaps");
        at += found.unwrap_or(0) + 1;
    }
}

/// `identify` with the truth's options recovers the truth of a noise-free, whirling double
/// pendulum at 64 samples per drive period (non-dimensional time).
#[test]
fn double_pendulum_truth_is_what_identify_recovers() {
    let dir = scratch("double-pendulum-truth");
    let truth = dir.join("truth.json");
    let record = simulated(
        &dir,
        "dp.csv",
        &[
            "--system",
            "double-pendulum",
            "--samples",
            "6400",
            "--truth",
            truth.to_str().unwrap(),
        ],
    );
    // Measured: 1.0e-5 (the coupled terms read velocities of the windows' Fourier series, up to
    // 32 times the drive frequency); the bound is the one a system's identification promises.
    let worst = system_round_trip(&record, &truth);
    assert!(worst < 1e-4, "worst relative error {worst:e}");
}

/// The same pendulum as a rig records it: seconds, 500 Hz under a 1.3 Hz drive with a second
/// harmonic out of phase, 4096-count encoders, angles in [0, 2π); and a lighter, shorter second
/// link at 200 Hz under a 1 Hz drive. Each physical term within 1 % of the truth.
#[test]
fn double_pendulum_rigs_are_identified_within_a_percent() {
    let dir = scratch("double-pendulum-rig");
    for (name, rig) in [
        (
            "rig.csv",
            &[
                "--drive-frequency",
                "1.3",
                "--sample-rate",
                "500",
                "--drive-harmonic",
                "2:0.3:0.5",
                "--counts",
                "4096",
                "--angle-range",
                "positive",
            ][..],
        ),
        (
            "light.csv",
            &[
                "--mu",
                "0.3",
                "--length-ratio",
                "0.7",
                "--drive-frequency",
                "1",
                "--sample-rate",
                "200",
                "--counts",
                "4096",
            ][..],
        ),
    ] {
        let truth = dir.join(format!("{name}.json"));
        let mut args = vec!["--system", "double-pendulum", "--duration", "60"];
        args.extend(rig);
        args.extend(["--truth", truth.to_str().unwrap()]);
        let record = simulated(&dir, name, &args);
        // Measured: 2.5e-4 (the rig, cos(2t)*cos(theta1)) and 1e-5 (the light link).
        let worst = system_round_trip(&record, &truth);
        assert!(worst < 1e-2, "{name}: worst relative error {worst:e}");
    }
}

/// `identify` with the truth's options (`--drive-col a`, windows in time) recovers the truth of
/// the noise-free coupled Duffing oscillators.
#[test]
fn coupled_duffing_truth_is_what_identify_recovers() {
    let dir = scratch("coupled-duffing-truth");
    let (record, hint) = simulated_system(&dir, "cd.csv", "coupled-duffing");
    assert_eq!(hint["identify"]["drive_col"], "a=6");
    // Measured: 1.7e-7; ten times that.
    let worst = system_round_trip(&record, &dir.join("cd.csv.truth.json"));
    assert!(worst < 2e-6, "worst relative error {worst:e}");
}

/// The largest relative error of the coefficients `hbid identify` gives with the truth's
/// `identify.args` on `record`, against the truth's, every term of the truth identified.
fn system_round_trip(record: &Path, truth: &Path) -> f64 {
    system_round_trip_with(record, truth, &[])
}

/// [`system_round_trip`] with the further options `extra`.
fn system_round_trip_with(record: &Path, truth: &Path, extra: &[&str]) -> f64 {
    let truth: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(truth).unwrap()).unwrap();
    let hint: Vec<String> = serde_json::from_value(truth["identify"]["args"].clone()).unwrap();
    let mut args = vec![record.to_str().unwrap()];
    args.extend(hint.iter().map(String::as_str));
    args.extend(extra);
    let mut all = vec!["identify", "--quiet", "--bootstrap", "0", "--json"];
    all.extend(args);
    let out = hbid(&all);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let identified: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let mut worst: f64 = 0.0;
    for (coordinate, equation) in truth["equations"].as_object().unwrap() {
        let expected = equation["coefficients"].as_object().unwrap();
        let got = identified["equations"][coordinate]["coefficients"]
            .as_object()
            .unwrap();
        assert_eq!(got.len(), expected.len(), "{coordinate}");
        for (term, value) in expected {
            let (e, g) = (value.as_f64().unwrap(), got[term].as_f64().unwrap());
            worst = worst.max((g - e).abs() / e.abs());
        }
    }
    worst
}

/// A logger that drops rows (one or two at a time, about one row in sixty) leaves no stretch
/// long enough for a window: the error says so and names the bridge. Bridged, the coupled
/// Duffing oscillators (their base acceleration measured: a drive column bridged too) and the
/// whirling double pendulum (angles bridged across their wraps), at 128 samples per drive
/// period, give their truth nearly as well as the whole record, and a report says what was
/// bridged (measured: worst relative error 1.6e-5 and 3.1e-5 bridged, against 1e-9 and 3.5e-6
/// whole; a drive sampled at ten samples per period of its fastest tone, the simulator's default
/// for the Duffing pair, gave 3e-3).
#[test]
fn a_loggers_dropped_rows_are_bridged_and_the_truth_recovered() {
    let dir = scratch("bridged");
    for (system, coords, rate, bound) in [
        ("coupled-duffing", "x1,x2", "128", 1e-4),
        ("double-pendulum", "theta1,theta2", "128", 1e-4),
    ] {
        let name = format!("{system}.csv");
        let (record, _) = simulated_with_truth(
            &dir,
            &name,
            &[
                "--system",
                system,
                "--samples-per-period",
                rate,
                "--samples",
                "12800",
            ],
        );
        let truth = dir.join(format!("{name}.truth.json"));
        let whole = system_round_trip(&record, &truth);
        let text = std::fs::read_to_string(&record).unwrap();
        let mut dropped = 0;
        let kept = rows_edited(&text, |i, row| {
            let drop = i % 97 == 50 || (i % 131 == 70 || i % 131 == 71);
            dropped += usize::from(drop);
            (!drop).then(|| row.to_owned())
        });
        assert!(dropped > 100, "{dropped}");
        let path = dir.join(format!("{system}-dropped.csv"));
        std::fs::write(&path, kept).unwrap();
        let out = hbid(&["identify", path.to_str().unwrap(), "--coords", coords, "--quiet"]);
        assert!(!out.status.success());
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            stderr.contains("no window fits between the record's gaps") && stderr.contains("--bridge-gaps"),
            "{stderr}"
        );
        let bridged = system_round_trip_with(&path, &truth, &["--bridge-gaps", "2"]);
        // The report says so: its samples are not all the file's.
        let report = dir.join(format!("{system}-report"));
        let out = hbid(&[
            "report",
            path.to_str().unwrap(),
            "--coords",
            coords,
            "--bridge-gaps",
            "2",
            "--quiet",
            "--out",
            report.to_str().unwrap(),
        ]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let readme = std::fs::read_to_string(report.join("README.md")).unwrap();
        assert!(readme.contains("missing sample(s) bridged"), "{readme}");
        assert!(
            bridged < bound,
            "{system}: worst relative error {bridged:e} bridged, {whole:e} whole"
        );
    }
}

/// A logger that writes a row with a missing value (an empty cell, `NaN`, `NA`, in one angle or
/// the other, about one row in forty) is refused, the error naming its line and the option;
/// with `--skip-missing` those rows are a logger's dropped rows (a note counts them), and
/// bridged the whirling double pendulum gives its truth as from dropped rows (worst relative
/// error below 1e-4; measured 6.2e-5, against 3.5e-6 whole); a record read in chunks refuses it,
/// and a missing value in a column not read changes nothing (the note counts only the others).
#[test]
fn rows_with_a_missing_value_are_left_out_and_bridged_on_request() {
    let dir = scratch("missing");
    let (record, _) = simulated_with_truth(
        &dir,
        "dp.csv",
        &[
            "--system",
            "double-pendulum",
            "--samples-per-period",
            "128",
            "--samples",
            "12800",
        ],
    );
    let truth = dir.join("dp.csv.truth.json");
    let text = std::fs::read_to_string(&record).unwrap();
    let mut blanked = 0;
    let out = rows_edited(&text, |i, line| {
        let mut cells: Vec<String> = line.split(',').map(str::to_owned).collect();
        // omega1 (column 4) is not read: its missing cells are no row's loss.
        if i % 7 == 3 {
            cells[3] = String::new();
        }
        let marker = match (i % 97, i % 131) {
            (50, _) => Some((1, "")),
            (_, 70) => Some((2, "NaN")),
            (20, _) => Some((2, "NA")),
            _ => None,
        };
        if let Some((c, m)) = marker {
            cells[c] = m.to_owned();
            blanked += 1;
        }
        Some(cells.join(","))
    });
    assert!(blanked > 200, "{blanked}");
    let path = dir.join("dp-missing.csv");
    std::fs::write(&path, out).unwrap();
    let identify = |extra: &[&str]| {
        let mut args = vec!["identify", path.to_str().unwrap(), "--coords", "theta1,theta2"];
        args.extend(extra);
        hbid(&args)
    };
    let refused = identify(&["--quiet"]);
    assert!(!refused.status.success());
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert!(
        stderr.contains("line 22: 'NA' in column 'theta2' is not a number")
            && stderr.contains("--skip-missing"),
        "{stderr}"
    );
    assert_clean_failure(
        &identify(&["--skip-missing", "--stream"]),
        "rows with a missing value are left out (--skip-missing) of a file read whole",
    );
    let noted = identify(&["--skip-missing", "--bridge-gaps", "1", "--bootstrap", "0"]);
    assert!(
        noted.status.success(),
        "{}",
        String::from_utf8_lossy(&noted.stderr)
    );
    let stderr = String::from_utf8_lossy(&noted.stderr);
    assert!(
        stderr.contains(&format!(
            "note: {blanked} row(s) with a missing value in a column read left out, as a logger's dropped rows: \
             line 22, line 52,"
        )),
        "{stderr}"
    );
    let bridged = system_round_trip_with(&path, &truth, &["--skip-missing", "--bridge-gaps", "1"]);
    assert!(bridged < 1e-4, "worst relative error {bridged:e}");
    // The report reads the record the same way and says which rows it left out.
    let report = dir.join("report");
    let out = hbid(&[
        "report",
        path.to_str().unwrap(),
        "--coords",
        "theta1,theta2",
        "--skip-missing",
        "--bridge-gaps",
        "1",
        "--quiet",
        "--out",
        report.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let readme = std::fs::read_to_string(report.join("README.md")).unwrap();
    assert!(
        readme.contains(&format!(
            "{blanked} row(s) with a missing value in a column read left out"
        )),
        "{readme}"
    );
}

/// `compare` through a logger's dropped rows: the coupled Duffing pair identified on the first
/// half of its record, run on the second half with one row in 97 dropped. Unbridged, each
/// piece starts a run of its own from its first samples, which are not scored; bridged, one run
/// goes through the whole range and scores every sample the whole half's run scores but the
/// bridged ones, which were not measured (counted apart; the text says so). The run is driven
/// through the gaps by the bridged drive (the cubic's, about 1e-5 off the truth here, where the
/// drive has content up to three times its frequency): over the first 5 s the RMSE is 2.0e-6
/// (largest error 5.9e-6; 2.2e-6 and 1.7e-5 when the bridged samples were scored) against
/// 5.0e-7 on the whole half (measured); later the pair's own sensitivity grows both.
#[test]
fn compare_runs_through_bridged_gaps_on_a_half_the_model_did_not_see() {
    let dir = scratch("compare-bridged");
    let truth_path = dir.join("truth.json");
    let record = simulated(
        &dir,
        "cd.csv",
        &[
            "--system",
            "coupled-duffing",
            "--drive-frequency",
            "1",
            "--sample-rate",
            "100",
            "--duration",
            "200",
            "--truth",
            truth_path.to_str().unwrap(),
        ],
    );
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&truth_path).unwrap()).unwrap();
    let hint: Vec<String> = serde_json::from_value(truth["identify"]["args"].clone()).unwrap();
    let text = std::fs::read_to_string(&record).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let half = (lines.len() - 1) / 2;
    let (first, second, dropped) = (
        dir.join("first.csv"),
        dir.join("second.csv"),
        dir.join("dropped.csv"),
    );
    std::fs::write(&first, lines[..=half].join("\n") + "\n").unwrap();
    let rows = &lines[half + 1..];
    std::fs::write(&second, [&lines[..1], rows].concat().join("\n") + "\n").unwrap();
    let kept: Vec<&str> = rows
        .iter()
        .enumerate()
        .filter(|(i, _)| i % 97 != 50)
        .map(|(_, r)| *r)
        .collect();
    std::fs::write(&dropped, [&lines[..1], &kept[..]].concat().join("\n") + "\n").unwrap();
    let model = dir.join("model.json");
    let mut args = vec!["identify", first.to_str().unwrap(), "--quiet", "--bootstrap", "0"];
    args.extend(hint.iter().map(String::as_str));
    args.extend(["--save-model", model.to_str().unwrap()]);
    let out = hbid(&args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let compare = |file: &Path, extra: &[&str]| {
        let mut args = vec![
            "compare",
            model.to_str().unwrap(),
            file.to_str().unwrap(),
            "--range",
            "0..500",
            "--quiet",
            "--json",
        ];
        args.extend(extra);
        hbid(&args)
    };
    let scores = |out: &Output| -> Vec<(f64, u64, u64, u64)> {
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        v["ranges"]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| {
                (
                    r["rmse"].as_f64().unwrap(),
                    r["scored"].as_u64().unwrap(),
                    r["skipped_pieces"].as_u64().unwrap(),
                    r["bridged"].as_u64().unwrap(),
                )
            })
            .collect()
    };
    let whole = scores(&compare(&second, &[]));
    let unbridged = scores(&compare(&dropped, &[]));
    let bridge = compare(&dropped, &["--bridge-gaps", "1"]);
    let bridged = scores(&bridge);
    // Rows 50, 147, ... of the half dropped: those within the range, less the state's 8.
    let dropped_in_range = (0..500u64).filter(|i| i % 97 == 50).count() as u64;
    for (((w, ws, _, wb), (b, bs, bp, bb)), (_, us, _, ub)) in whole.iter().zip(&bridged).zip(&unbridged) {
        assert_eq!((wb, ub), (&0, &0), "nothing bridged, nothing counted as bridged");
        assert_eq!(*bb, dropped_in_range, "every bridged sample counted");
        assert_eq!(
            (bs + bb, bp),
            (*ws, &0),
            "one run, the bridged samples not scored"
        );
        assert!(
            us < ws,
            "unbridged, each piece's first samples set its state: {us} scored"
        );
        assert!(*w < 1e-6 && *b < 1e-5, "RMSE {b:e} bridged, {w:e} whole");
    }
    let text = hbid(&[
        "compare",
        model.to_str().unwrap(),
        dropped.to_str().unwrap(),
        "--range",
        "0..500",
        "--quiet",
        "--bridge-gaps",
        "1",
    ]);
    assert!(text.status.success(), "{}", String::from_utf8_lossy(&text.stderr));
    let said = format!(
        "range 0..500: {dropped_in_range} sample(s) bridged into gaps (--bridge-gaps) were run through, not scored"
    );
    assert!(
        String::from_utf8_lossy(&text.stdout).contains(&said),
        "{}",
        String::from_utf8_lossy(&text.stdout)
    );
    // A range whose samples after the state's are all bridged has nothing measured to score
    // (the record's own warnings of its outliers come first).
    let out = hbid(&[
        "compare",
        model.to_str().unwrap(),
        dropped.to_str().unwrap(),
        "--bridge-gaps",
        "1",
        "--range",
        "47..51",
        "--init",
        "3",
        "--quiet",
    ]);
    assert!(!out.status.success());
    assert_eq!(
        String::from_utf8_lossy(&out.stderr).trim().lines().last(),
        Some(
            "error: --range 47..51: holds no measured sample to score after the 3 that set the state: the 1 \
             sample(s) left are bridged (--bridge-gaps)"
        )
    );
}

/// Many time-stamp repairs are not a page of notes: the first five are printed, the rest
/// counted in one note, and the other notes follow in their order.
#[test]
fn many_time_stamp_repairs_are_counted_after_the_first_five() {
    let dir = scratch("repairs");
    let record = simulated(&dir, "r.csv", &["--samples", "4000"]);
    let text = std::fs::read_to_string(&record).unwrap();
    // Eight stamps, 300 rows apart from the line `from` (after the header's 0), 0.4 step late:
    // isolated glitches.
    let t = |l: &str| l.split(',').next().unwrap().parse::<f64>().unwrap();
    let dt = {
        let rows: Vec<&str> = text.lines().skip(1).take(2).collect();
        t(rows[1]) - t(rows[0])
    };
    let glitched = |name: &str, from: usize| {
        let edited = rows_edited(&text, |i, row| {
            // Row `i` is the record's line `i + 1` after the header's 0.
            let line = i + 1;
            if line < from || !(line - from).is_multiple_of(300) || line >= from + 300 * 8 {
                return Some(row.to_owned());
            }
            let mut cells: Vec<&str> = row.split(',').collect();
            let late = format!("{}", t(row) + 0.4 * dt);
            cells[0] = &late;
            Some(cells.join(","))
        });
        let path = dir.join(name);
        std::fs::write(&path, edited).unwrap();
        path
    };
    let path = glitched("glitches.csv", 300);
    let later = glitched("later.csv", 1300);
    let out = hbid(&["identify", path.to_str().unwrap(), "--repair", "--bootstrap", "0"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stderr = String::from_utf8_lossy(&out.stderr);
    let notes: Vec<&str> = stderr.lines().filter(|l| l.starts_with("note: ")).collect();
    let first = notes
        .iter()
        .position(|l| l.contains("replaced by its grid time"))
        .unwrap();
    for (k, note) in notes[first..first + 5].iter().enumerate() {
        assert!(
            note.starts_with(&format!("note: line {}: time ", 300 * (k + 1) + 1)),
            "{stderr}"
        );
    }
    assert_eq!(
        notes[first + 5],
        "note: 3 more time stamp(s) replaced by their grid times (8 in all; Python's `read` lists every one in \
         `time_repairs`)"
    );
    assert!(
        !notes[first + 6..]
            .iter()
            .any(|l| l.contains("replaced by its grid time")),
        "{stderr}"
    );
    // Two records, the second's repairs at later lines: each one's counted on their own.
    let both = hbid(&[
        "identify",
        path.to_str().unwrap(),
        later.to_str().unwrap(),
        "--repair",
        "--bootstrap",
        "0",
    ]);
    assert!(both.status.success(), "{}", String::from_utf8_lossy(&both.stderr));
    let stderr = String::from_utf8_lossy(&both.stderr);
    let shown = stderr
        .lines()
        .filter(|l| l.contains("replaced by its grid time"))
        .count();
    let counted: Vec<&str> = stderr
        .lines()
        .filter(|l| l.contains("more time stamp(s)"))
        .collect();
    assert_eq!(shown, 10, "{stderr}");
    assert_eq!(counted.len(), 2, "{stderr}");
    assert!(
        counted
            .iter()
            .all(|l| l.contains("3 more time stamp(s) replaced by their grid times (8 in all")),
        "{stderr}"
    );
    // Of several records, each note names its record: the repairs (line 301 is in both) and
    // their count.
    for (file, line) in [(&path, 301), (&later, 1301)] {
        let file = file.to_str().unwrap();
        assert!(
            stderr.contains(&format!("note: {file}: line {line}: time ")),
            "{stderr}"
        );
        assert!(
            stderr.contains(&format!("note: {file}: 3 more time stamp(s) replaced")),
            "{stderr}"
        );
    }
    // A command that fails after the repairs still counts those it did not print, before its
    // error.
    let failed = hbid(&[
        "identify",
        path.to_str().unwrap(),
        "--repair",
        "--window-periods",
        "100000",
    ]);
    let stderr = String::from_utf8_lossy(&failed.stderr);
    let lines: Vec<&str> = stderr.lines().collect();
    assert!(
        !failed.status.success() && !stderr.contains("panicked"),
        "{stderr}"
    );
    assert!(lines.last().unwrap().starts_with("error: "), "{stderr}");
    assert!(
        lines[..lines.len() - 1]
            .iter()
            .any(|l| l.starts_with("note: 3 more time stamp(s) replaced")),
        "{stderr}"
    );
}

/// Bridging is refused, in one line, where it cannot hold: a gap longer than a cubic through
/// four samples stands for, a record read in chunks (a gap at a chunk's edge would not be
/// bridged), and a velocity record integrated piece by piece.
#[test]
fn bridging_gaps_is_refused_where_it_cannot_hold() {
    let dir = scratch("bridge-refused");
    let record = simulated(&dir, "r.csv", &["--samples", "3000", "--gaps", "20:1"]);
    let identify = |extra: &[&str]| {
        let mut args = vec!["identify", record.to_str().unwrap(), "--quiet"];
        args.extend(extra);
        hbid(&args)
    };
    assert_clean_failure(&identify(&["--bridge-gaps", "5"]), "--bridge-gaps 5: at most 4");
    assert_clean_failure(
        &identify(&["--bridge-gaps", "1", "--stream"]),
        "a gap is bridged (--bridge-gaps) within one chunk's reading",
    );
    assert_clean_failure(
        &identify(&["--bridge-gaps", "1", "--signal", "line", "--measured", "velocity"]),
        "integrated piece by piece",
    );
}

/// Two masses on the line with a cubic coupling spring on a base whose acceleration is measured:
/// from the first half of the record, `--select` over the default library of the line keeps
/// exactly the terms of the truth, each within 1e-5 of its value; the model saved from it runs
/// 20 s of the second half within an NRMSE of 1e-2 on each coordinate.
#[test]
fn coupled_oscillators_are_selected_and_predict_the_other_half() {
    let dir = scratch("coupled-select");
    let truth_path = dir.join("truth.json");
    let record = simulated(
        &dir,
        "cd.csv",
        &[
            "--system",
            "coupled-duffing",
            "--drive-frequency",
            "1",
            "--sample-rate",
            "100",
            "--duration",
            "200",
            "--truth",
            truth_path.to_str().unwrap(),
        ],
    );
    let text = std::fs::read_to_string(&record).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let half = (lines.len() - 1) / 2;
    let (first, second) = (dir.join("first.csv"), dir.join("second.csv"));
    std::fs::write(&first, lines[..=half].join("\n") + "\n").unwrap();
    std::fs::write(
        &second,
        [&lines[..1], &lines[half + 1..]].concat().join("\n") + "\n",
    )
    .unwrap();
    let model = dir.join("model.json");
    let out = hbid(&[
        "identify",
        first.to_str().unwrap(),
        "--coords",
        "x1,x2",
        "--signal",
        "line",
        "--drive-col",
        "a",
        "--window",
        "3",
        "--select",
        "--bootstrap",
        "0",
        "--quiet",
        "--json",
        "--save-model",
        model.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let identified: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&truth_path).unwrap()).unwrap();
    for (coordinate, equation) in truth["equations"].as_object().unwrap() {
        let expected = equation["coefficients"].as_object().unwrap();
        let got = identified["equations"][coordinate]["coefficients"]
            .as_object()
            .unwrap();
        let mut kept: Vec<&String> = got.keys().collect();
        let mut true_terms: Vec<&String> = expected.keys().collect();
        kept.sort();
        true_terms.sort();
        assert_eq!(kept, true_terms, "{coordinate}: the terms kept");
        for (term, value) in expected {
            let (want, have) = (value.as_f64().unwrap(), got[term].as_f64().unwrap());
            // Measured: 1.2e-10 relative at most.
            assert!(
                (have - want).abs() <= 1e-5 * want.abs(),
                "{coordinate}: {term} {have} against {want}"
            );
        }
    }
    let out = hbid(&[
        "compare",
        model.to_str().unwrap(),
        second.to_str().unwrap(),
        "--range",
        "0..2000",
        "--quiet",
        "--json",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let ranges = report["ranges"].as_array().unwrap();
    assert_eq!(ranges.len(), 2);
    for range in ranges {
        // Measured: 6.6e-4 on each coordinate.
        let nrmse = range["nrmse"].as_f64().unwrap();
        assert!(nrmse < 1e-2, "{}: NRMSE {nrmse}", range["coordinate"]);
    }
}

/// Every bad input of a system the issue lists is a one-line error naming the option (and the
/// column), never a panic or a table: a coordinate missing or named twice, a term naming an
/// unknown column, an equation without terms, a drive that is also a coordinate, the own
/// acceleration as a bare term, a mass matrix singular at the record's states (a column the copy
/// of another), records with other columns in one fit, a column chosen twice, a drive named as a
/// coordinate, and velocities, which no fit reads.
#[test]
fn a_systems_bad_inputs_are_one_line_errors() {
    let dir = scratch("system-bad-inputs");
    let record = simulated(
        &dir,
        "dp.csv",
        &["--system", "double-pendulum", "--samples", "3200"],
    );
    let duffing = simulated(
        &dir,
        "cd.csv",
        &["--system", "coupled-duffing", "--samples", "3200"],
    );
    // The same record with a copy of theta1's column, as a duplicated encoder channel is logged.
    let text = std::fs::read_to_string(&record).unwrap();
    let mut lines = text.lines();
    let mut copied = format!("{},copy\n", lines.next().unwrap());
    for line in lines {
        let theta1 = line.split(',').nth(1).unwrap();
        copied.push_str(&format!("{line},{theta1}\n"));
    }
    let copy = dir.join("copy.csv");
    std::fs::write(&copy, copied).unwrap();
    // The copy logged with its own noise (a second encoder on the same shaft), 1e-4 rad of
    // seeded uniform noise: the matrix is not singular at any state, only nearly.
    let mut seed = 7_u64;
    let mut noise = || {
        seed = seed
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 3.5e-4
    };
    let mut lines = text.lines();
    let mut noisy = format!("{},copy\n", lines.next().unwrap());
    for line in lines {
        let theta1: f64 = line.split(',').nth(1).unwrap().parse().unwrap();
        noisy.push_str(&format!("{line},{}\n", theta1 + noise()));
    }
    let noisy_copy = dir.join("noisy-copy.csv");
    std::fs::write(&noisy_copy, noisy).unwrap();
    let h = std::f64::consts::TAU / 64.0;
    let mut motions = "t,theta1,theta2\n".to_owned();
    for n in 0..20_000 {
        let t = n as f64 * h;
        motions.push_str(&format!(
            "{t},{},{}\n",
            0.5 * t.sin() + 0.3 * (2.3 * t + 0.4).sin(),
            0.3 * (0.37 * t).sin() + 0.02 * (3.1 * t).sin()
        ));
    }
    let unphysical = dir.join("unphysical.csv");
    std::fs::write(&unphysical, motions).unwrap();
    // The same record with its angles' columns in the other order (header and values).
    let swapped: String = text
        .lines()
        .map(|line| {
            let mut cells: Vec<&str> = line.split(',').collect();
            cells.swap(1, 2);
            cells.join(",") + "\n"
        })
        .collect();
    let swapped_path = dir.join("swapped.csv");
    std::fs::write(&swapped_path, swapped).unwrap();
    let (record, duffing, copy, noisy_copy, unphysical, swapped) = (
        record.to_str().unwrap(),
        duffing.to_str().unwrap(),
        copy.to_str().unwrap(),
        noisy_copy.to_str().unwrap(),
        unphysical.to_str().unwrap(),
        swapped_path.to_str().unwrap(),
    );
    let cases: [(&[&str], &str); 14] = [
        (&[record, "--coords", "theta1,theta3"], "--coords"),
        (&[record, "--coords", "theta1,theta1"], "named twice"),
        (
            &[record, "--coords", "theta1=theta1,theta2=2"],
            "column 2 is chosen twice, as two angle columns",
        ),
        // A name in both lists is the drive's to change.
        (
            &[
                record,
                "--coords",
                "theta1,theta2",
                "--drive-col",
                "theta1=omega1",
            ],
            "--drive-col: the name `theta1` cannot be used: named twice",
        ),
        // Velocities set a free run's state; the fit reads none.
        (
            &[
                record,
                "--coords",
                "theta1,theta2",
                "--velocity-col",
                "omega1,omega2",
            ],
            "--velocity-col: sets the state of a free run",
        ),
        (
            &[record, "--coords", "theta1,theta2", "--terms", "sin(theta3)"],
            "a coordinate (theta1, theta2)",
        ),
        (
            &[
                record,
                "--coords",
                "theta1,theta2",
                "--terms",
                "theta1: sin(theta1); theta2:",
            ],
            "an equation without terms",
        ),
        (
            &[record, "--coords", "theta1,theta2", "--drive-col", "theta2"],
            "is a coordinate (--coords) too",
        ),
        (
            &[
                record,
                "--coords",
                "theta1,theta2",
                "--terms",
                "theta1: theta1'', sin(theta1); theta2: sin(theta2)",
            ],
            "own acceleration alone",
        ),
        (
            &[
                copy,
                "--coords",
                "theta1,copy",
                "--terms",
                "theta1: copy'', sin(theta1); copy: theta1'', sin(copy)",
            ],
            "mass matrix is singular",
        ),
        (
            &[
                noisy_copy,
                "--coords",
                "theta1,copy",
                "--terms",
                "theta1: copy''*cos(theta1-copy), sin(theta1); copy: theta1''*cos(theta1-copy), sin(copy)",
            ],
            "mass matrix is nearly singular",
        ),
        // Two motions no pendulum makes, theta1's inertia fitted as 1 − 1.02 cos(theta2): it
        // crosses zero between states, never zero at one.
        (
            &[
                unphysical,
                "--coords",
                "theta1,theta2",
                "--terms",
                "theta1: theta1''*cos(theta2), sin(theta1); theta2: sin(theta2)",
            ],
            "its determinant changing sign",
        ),
        (&[record, duffing, "--coords", "theta1,theta2"], "--coords"),
        // Chosen by position, the second record's header names the other angle there.
        (
            &[record, swapped, "--coords", "theta1=2,theta2=3"],
            "--coords: column 2 is 'theta2' in",
        ),
    ];
    for (args, mentions) in cases {
        let mut all = vec!["identify"];
        all.extend_from_slice(args);
        all.extend_from_slice(&["--bootstrap", "0"]);
        let out = hbid(&all);
        let err = String::from_utf8_lossy(&out.stderr);
        // The record's own notes (spikes found, kept) may come before; the error is one line.
        let errors: Vec<&str> = err.lines().filter(|l| l.starts_with("error")).collect();
        assert!(
            !out.status.success() && !err.contains("panicked"),
            "{args:?}: {err}"
        );
        assert_eq!(errors.len(), 1, "{args:?}: one error line expected: {err}");
        assert!(
            errors[0].contains(mentions),
            "{args:?}: '{mentions}' not in: {err}"
        );
        assert!(
            err.trim_end().ends_with(errors[0]),
            "{args:?}: the error is not the last line: {err}"
        );
        assert!(out.stdout.is_empty(), "{args:?} printed a result");
    }
}

/// `hbid report` reads its record whole (it runs its models along it and draws it): `--stream`,
/// an option it shares with `identify`, is refused in one line rather than ignored, and no
/// report is written.
#[test]
fn the_report_refuses_to_read_in_chunks() {
    let dir = scratch("report-stream");
    let record = dir.join("pendulum.npy");
    let out = hbid(&["simulate", "--samples", "4000", "--out", record.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let report = dir.join("report");
    let out = hbid(&[
        "report",
        record.to_str().unwrap(),
        "--stream",
        "--out",
        report.to_str().unwrap(),
        "--quiet",
    ]);
    assert_clean_failure(&out, "stream");
    assert!(!report.exists(), "a report was written");
    // identify's outputs, which the report would accept and not write, are refused too.
    let saved = dir.join("m.json");
    for (extra, mentions) in [
        (&["--save-model", saved.to_str().unwrap()][..], "--save-model"),
        (&["--json"], "--json"),
    ] {
        let mut args = vec![
            "report",
            record.to_str().unwrap(),
            "--out",
            report.to_str().unwrap(),
            "--quiet",
        ];
        args.extend_from_slice(extra);
        assert_clean_failure(&hbid(&args), mentions);
        assert!(!report.exists() && !saved.exists(), "{extra:?} wrote something");
    }
    // Measured velocities, which the report of one coordinate does not start its runs from.
    let csv = dir.join("pendulum.csv");
    let out = hbid(&["simulate", "--samples", "4000", "--out", csv.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let out = hbid(&[
        "report",
        csv.to_str().unwrap(),
        "--velocity-col",
        "omega",
        "--out",
        report.to_str().unwrap(),
        "--quiet",
    ]);
    assert_clean_failure(
        &out,
        "--velocity-col omega: the report of one coordinate runs its models",
    );
    assert!(!report.exists(), "a report was written");
    std::fs::remove_dir_all(&dir).ok();
}

/// Too few bootstrap resamples for the confidence level name the count and how many are needed;
/// a level out of range names the level.
#[test]
fn too_few_resamples_name_the_bootstrap_option() {
    let data = paper_dataset();
    let out = hbid(&["identify", &data, "--bootstrap", "20"]);
    assert_clean_failure(
        &out,
        "--bootstrap 20: too few resamples for --level 0.95: at least 40",
    );
    let out = hbid(&["identify", &data, "--bootstrap", "200", "--level", "1.5"]);
    assert_clean_failure(&out, "--level 1.5");
    // Beyond what a percentile needs, each resample's coefficients kept: refused, not an abort
    // on the memory.
    let out = hbid(&["identify", &data, "--bootstrap", "1000000000000"]);
    assert_clean_failure(&out, "--bootstrap 1000000000000: too many: at most 10^6");
}

/// Standard output that cannot be written (a full device) is a one-line error, not a panic's
/// backtrace, for the table and for JSON alike.
#[test]
fn an_unwritable_standard_output_is_a_one_line_error() {
    let Ok(full) = std::fs::OpenOptions::new().write(true).open("/dev/full") else {
        return;
    };
    for json in [false, true] {
        let data = paper_dataset();
        let mut args = vec!["identify", data.as_str(), "--bootstrap", "0", "--quiet"];
        if json {
            args.push("--json");
        }
        let out = Command::new(env!("CARGO_BIN_EXE_hbid"))
            .args(&args)
            .stdout(full.try_clone().unwrap())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{err}");
        assert!(!err.contains("panicked"), "{err}");
        assert_eq!(
            err.trim(),
            "error: cannot write the standard output: No space left on device (os error 28)"
        );
    }
}

/// The arm with a passive shoulder (`--torque1 none`): its truth's identify options leave out
/// the torque that is a column of zeros, and identify the record; the elbow's torque comes out
/// as the truth has it.
#[test]
fn a_passive_joints_torque_is_not_in_the_truths_options() {
    let dir = scratch("passive-joint");
    let (record, truth) = simulated_with_truth(
        &dir,
        "arm.csv",
        &["--system", "arm", "--torque1", "none", "--samples", "5000"],
    );
    let hint = &truth["identify"];
    let terms = hint["terms"].as_str().unwrap();
    assert!(!terms.contains("tau1") && terms.contains("tau2"), "{terms}");
    let mut args = vec!["identify", record.to_str().unwrap(), "--bootstrap", "0", "--json"];
    let given: Vec<&str> = hint["args"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a.as_str().unwrap())
        .collect();
    args.extend(given);
    let out = hbid(&args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let found: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let tau2 = found["equations"]["q2"]["coefficients"]["tau2"].as_f64().unwrap();
    let expected = truth["equations"]["q2"]["coefficients"]["tau2"].as_f64().unwrap();
    assert!(
        (tau2 - expected).abs() < 1e-3 * expected.abs(),
        "{tau2} against {expected}"
    );
}

/// A step given for a record whose header has its own time column replaces the stamps: a
/// warning says so (a wrong step would otherwise pass unseen); a record without one gets none.
#[test]
fn a_step_that_replaces_the_records_stamps_is_warned_of() {
    // The paper's record identified with its step given: what it says on stderr.
    let with_step = |record: &str| {
        let out = hbid(&[
            "identify",
            record,
            "--dt",
            "0.25132741228718347",
            "--bootstrap",
            "0",
            "--quiet",
        ]);
        let err = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(out.status.success(), "{err}");
        err
    };
    let data = paper_dataset();
    let err = with_step(&data);
    assert!(
        err.contains(
            "the record has a time column 't', whose stamps --dt replaces (not read): give --time-col t"
        ),
        "{err}"
    );
    let dir = scratch("step-without-stamps");
    let text = std::fs::read_to_string(&data).unwrap();
    // The angles alone, without the comments, the header and the stamps.
    let angles: String = text
        .lines()
        .filter(|l| !l.starts_with('#'))
        .skip(1)
        .map(|l| l.split(',').nth(1).unwrap().to_owned() + "\n")
        .collect();
    let bare = dir.join("angles.csv");
    std::fs::write(&bare, angles).unwrap();
    let err = with_step(bare.to_str().unwrap());
    assert!(!err.contains("time column"), "{err}");
}

/// One coordinate as several: two records whose headers name other columns at the angle's
/// position are refused when it is chosen by position, and joined when chosen by name.
#[test]
fn records_of_one_angle_with_other_columns_at_its_position_are_refused() {
    let dir = scratch("one-angle-other-columns");
    let first = simulated(&dir, "a.csv", &["--samples", "3000"]);
    let text = std::fs::read_to_string(&first).unwrap();
    let swapped: String = text
        .lines()
        .map(|line| {
            let c: Vec<&str> = line.split(',').collect();
            [c[0], c[2], c[1]].join(",") + "\n"
        })
        .collect();
    let second = dir.join("b.csv");
    std::fs::write(&second, swapped).unwrap();
    let (a, b) = (first.to_str().unwrap(), second.to_str().unwrap());
    let out = hbid(&["identify", a, b, "--angle-col", "2", "--bootstrap", "0"]);
    assert_clean_failure(&out, "--angle-col: column 2 is 'omega' in");
    let out = hbid(&["identify", a, b, "--angle-col", "theta", "--bootstrap", "0"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
}

/// Of several records, the one too short to resample is named, and the message says once what
/// failed: a drive period of no whole number of samples, the resampling, the length it needs.
#[test]
fn the_record_that_fails_among_several_is_named() {
    let dir = scratch("several-one-fails");
    let rig = ["--drive-frequency", "1.3", "--sample-rate", "500"];
    let long = simulated(&dir, "long.csv", &[&rig[..], &["--samples", "3000"]].concat());
    let short = simulated(&dir, "short.csv", &[&rig[..], &["--samples", "129"]].concat());
    let run = |records: &[&Path]| {
        let mut args = vec!["identify"];
        args.extend(records.iter().map(|p| p.to_str().unwrap()));
        args.extend(["--drive-frequency", "1.3", "--bootstrap", "0", "--quiet"]);
        let out = hbid(&args);
        assert!(!out.status.success());
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let alone = run(&[&short]);
    assert_eq!(
        alone.matches("resampling onto a whole number").count(),
        1,
        "{alone}"
    );
    assert!(alone.contains("at least 130 are needed"), "{alone}");
    assert!(!alone.contains("short.csv"), "{alone}");
    let together = run(&[&long, &short]);
    let named = format!(
        "error: {}: a drive period of no whole number of samples",
        short.display()
    );
    assert!(together.contains(&named), "{together}");
    // The error names the record that failed; the other's notes name theirs.
    let error = together.lines().find(|l| l.starts_with("error: ")).unwrap();
    assert!(!error.contains("long.csv"), "{together}");
    assert!(
        together.contains(&format!(
            "note: {}: 384.615385 samples per period",
            long.display()
        )),
        "{together}"
    );
}

/// A term in the drive's phase with windows of a given length names those options, which leave
/// the record's drive out, and the one that counts windows in drive periods.
#[test]
fn a_drive_term_with_windows_of_a_given_length_names_the_options() {
    let data = paper_dataset();
    let out = hbid(&[
        "identify",
        &data,
        "--terms",
        "sin(t)*cos(x), sin(x), x'",
        "--window-samples",
        "75",
        "--quiet",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(
        err.contains("the term `sin(t)*cos(x)` has a drive factor"),
        "{err}"
    );
    assert!(
        err.contains("--window-samples") && err.contains("--window-periods"),
        "{err}"
    );
    assert!(!err.contains("the record has no periodic drive"), "{err}");
}
