//! `hbid compare` and `hbid simulate --model --input`: a saved model run freely under a held-out
//! record's measured input and scored against its measured output.
use crate::support::hbid_quiet as hbid;
use std::path::{Path, PathBuf};
use std::process::Output;

fn ok(args: &[&str]) -> Output {
    let out = hbid(args);
    assert!(
        out.status.success(),
        "hbid {}: {}",
        args.join(" "),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

fn scratch(name: &str) -> PathBuf {
    crate::support::scratch("compare", name)
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn json(out: &Output) -> serde_json::Value {
    serde_json::from_slice(&out.stdout).expect("JSON on stdout")
}

fn assert_clean_failure(out: &Output, mentions: &str) {
    assert!(!out.status.success(), "expected failure");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "panic: {err}");
    assert_eq!(err.trim().lines().count(), 1, "one line expected: {err}");
    assert!(err.contains(mentions), "'{mentions}' not in: {err}");
}

/// A one-well Duffing oscillator on a shaker (a periodic response), 2048 Hz, 6.5 Hz drive, its
/// drive written as the column p: a training record, and a held-out one from another state, at
/// another phase, with measurement noise of `noise` and `gaps`.
fn duffing_records(dir: &Path, noise: &str, gaps: Option<&str>) -> (PathBuf, PathBuf) {
    let common = [
        "simulate",
        "--system",
        "duffing",
        "--f",
        "0.1",
        "--drive-frequency",
        "6.5",
        "--sample-rate",
        "2048",
        "--time-origin",
        "first-sample",
        "--write-drive",
    ];
    let train = dir.join("train.csv");
    let test = dir.join("test.csv");
    let mut args = common.to_vec();
    args.extend(["--duration", "40", "--x0", "1", "--out", s(&train)]);
    ok(&args);
    let mut args = common.to_vec();
    args.extend([
        "--duration",
        "20",
        "--x0",
        "0.8",
        "--v0",
        "1",
        "--phase",
        "1",
        "--noise",
        noise,
        "--seed",
        "3",
        "--out",
        s(&test),
    ]);
    if let Some(gaps) = gaps {
        args.extend(["--gaps", gaps]);
    }
    ok(&args);
    (train, test)
}

#[test]
fn a_model_under_a_held_out_records_drive_reaches_its_noise_floor() {
    let dir = scratch("floor");
    let (train, test) = duffing_records(&dir, "0.001", Some("2:300"));
    let model = dir.join("m.json");
    ok(&[
        "identify",
        s(&train),
        "--signal",
        "line",
        "--drive-frequency",
        "6.5",
        "--drive-col",
        "p",
        "--terms",
        "x', x, x^3, p",
        "--bootstrap",
        "0",
        "--save-model",
        s(&model),
    ]);
    let plot = dir.join("compare.png");
    let out = ok(&[
        "compare",
        s(&model),
        s(&test),
        "--drive-col",
        "p",
        "--init",
        "100",
        "--json",
        "--plot",
        s(&plot),
    ]);
    let v = json(&out);
    assert_eq!(v["measured_drive"], true);
    let range = &v["ranges"][0];
    // Three pieces between the two gaps, each started from its first 100 samples.
    assert_eq!(range["initial_states"].as_array().unwrap().len(), 3, "{range}");
    let samples = v["samples"].as_u64().unwrap();
    assert_eq!(range["scored"].as_u64().unwrap(), samples - 300);
    // The noise is 1e-3: the model's free run is within it, over 130 drive periods.
    let rmse = range["rmse"].as_f64().unwrap();
    assert!((0.9e-3..1.15e-3).contains(&rmse), "RMSE {rmse}");
    let fit = range["fit_percent"].as_f64().unwrap();
    assert!(fit > 97.0, "fit {fit} %");
    let nrmse = range["nrmse"].as_f64().unwrap();
    assert!((fit - 100.0 * (1.0 - nrmse)).abs() < 1e-9);
    assert!(std::fs::metadata(&plot).unwrap().len() > 1000);
    // A short range away from the gaps is short, not cut by them.
    let short = hbid(&[
        "compare",
        s(&model),
        s(&test),
        "--drive-col",
        "p",
        "--range",
        "100..105",
    ]);
    let err = String::from_utf8_lossy(&short.stderr);
    assert!(!short.status.success() && !err.contains("panicked"), "{err}");
    assert!(
        err.trim_end().ends_with(
            "error: --init 8: leaves no sample of the range 100..105 to score: the range has 5 sample(s)"
        ),
        "{err}"
    );

    // Two ranges are scored on their own; the table names them.
    let out = ok(&[
        "compare",
        s(&model),
        s(&test),
        "--drive-col",
        "p",
        "--range",
        "0..5000",
        "--range",
        "5000..",
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("0..5000") && text.contains("fit %"), "{text}");

    // `simulate --model --input` writes the same free run: t, x, v at every sample of the pieces.
    let run = dir.join("run.csv");
    ok(&[
        "simulate",
        "--model",
        s(&model),
        "--input",
        s(&test),
        "--drive-col",
        "p",
        "--init",
        "100",
        "--out",
        s(&run),
    ]);
    let text = std::fs::read_to_string(&run).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("t,x,v"));
    let measured: Vec<Vec<f64>> = std::fs::read_to_string(&test)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
        .collect();
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), measured.len());
    let worst = rows
        .iter()
        .zip(&measured)
        .map(|(r, m)| {
            assert!((r[0] - m[0]).abs() < 1e-9, "times differ: {} {}", r[0], m[0]);
            (r[1] - m[1]).abs()
        })
        .fold(0.0, f64::max);
    assert!(worst < 6e-3, "largest difference {worst}");
}

#[test]
fn a_chaotic_pendulum_follows_its_record_for_some_periods_then_leaves_it() {
    let dir = scratch("chaos");
    let record = dir.join("p.csv");
    ok(&["simulate", "--samples", "8000", "--out", s(&record)]);
    let model = dir.join("p.bin");
    ok(&[
        "identify",
        s(&record),
        "--bootstrap",
        "0",
        "--save-model",
        s(&model),
    ]);
    // On the circle, the model's own drive on the record's clock: 4 drive periods are followed
    // closely, 200 are not (the attractor is chaotic), and the scores say so.
    let v = json(&ok(&[
        "compare",
        s(&model),
        s(&record),
        "--range",
        "1000..1125",
        "--range",
        "1000..6000",
        "--init",
        "25",
        "--json",
    ]));
    assert_eq!(v["signal"], "circle");
    assert_eq!(v["measured_drive"], false);
    let short = v["ranges"][0]["fit_percent"].as_f64().unwrap();
    let long = v["ranges"][1]["fit_percent"].as_f64().unwrap();
    assert!(short > 99.9, "short fit {short}");
    assert!(
        long < 50.0,
        "a chaotic record followed for 200 periods? fit {long}"
    );
    // Errors are the shortest arcs: never more than π.
    assert!(v["ranges"][1]["max_error"].as_f64().unwrap() <= std::f64::consts::PI + 1e-12);
}

#[test]
fn dry_friction_sticks_in_the_free_run() {
    // A mass with viscous and dry friction, no spring, under a shaker's drive with a harmonic:
    // it stops and sticks twice a cycle. The identified model, run under the held-out drive,
    // must stick too.
    let dir = scratch("friction");
    let common = [
        "simulate",
        "--system",
        "duffing",
        "--a",
        "0",
        "--b",
        "0",
        "--c",
        "0.5",
        "--f",
        "1",
        "--friction",
        "0.55",
        "--drive-harmonic",
        "2:0.5",
        "--drive-frequency",
        "2",
        "--sample-rate",
        "500",
        "--time-origin",
        "first-sample",
        "--transient-periods",
        "20",
        "--write-drive",
    ];
    let (train, test) = (dir.join("train.csv"), dir.join("test.csv"));
    let mut args = common.to_vec();
    args.extend(["--duration", "30", "--out", s(&train)]);
    ok(&args);
    let mut args = common.to_vec();
    args.extend(["--duration", "30", "--phase", "2", "--out", s(&test)]);
    ok(&args);
    let model = dir.join("m.json");
    // The identify command on the training record, with `extra` options.
    let identify = |extra: &[&'static str]| -> Vec<String> {
        let mut a: Vec<String> = [
            "identify",
            s(&train),
            "--signal",
            "line",
            "--drive-frequency",
            "2",
        ]
        .iter()
        .map(|a| a.to_string())
        .collect();
        a.extend(["--drive-col", "p", "--terms", "x', sign(x'), p"].map(String::from));
        a.extend(extra.iter().map(|e| e.to_string()));
        a
    };
    let mut weak = identify(&["--bootstrap", "0", "--save-model"]);
    weak.push(s(&model).to_owned());
    ok(&weak.iter().map(String::as_str).collect::<Vec<_>>());
    let v = json(&ok(&[
        "compare",
        s(&model),
        s(&test),
        "--drive-col",
        "p",
        "--json",
    ]));
    // The weak form's friction is biased where the body sticks (the friction force there is not
    // mu sign(x'), and the stick phases sit inside its windows): here sign(x') comes out about
    // 10 % low and the free run's position, an integral of the velocity, drifts by a tenth of
    // the record's spread (fit about 86 %; 96 % at mu = 0.45, which sticks for 0.4 % of the
    // time, and 32 % at mu = 0.65, which sticks for a quarter).
    let fit = v["ranges"][0]["fit_percent"].as_f64().unwrap();
    assert!(fit > 80.0, "fit {fit} %: {v}");
    let run = dir.join("run.csv");
    ok(&[
        "simulate",
        "--model",
        s(&model),
        "--input",
        s(&test),
        "--drive-col",
        "p",
        "--out",
        s(&run),
    ]);
    let stuck = |path: &Path| {
        std::fs::read_to_string(path)
            .unwrap()
            .lines()
            .skip(1)
            .filter(|l| l.split(',').nth(2).unwrap().parse::<f64>().unwrap() == 0.0)
            .count()
    };
    // The rig sticks for about 4 % of the time, and so does the model run freely.
    let (rig, model_run) = (stuck(&test), stuck(&run));
    assert!(rig > 300, "the rig does not stick: {rig}");
    assert!(
        (rig / 2..2 * rig).contains(&model_run),
        "the model sticks at {model_run} samples, the rig at {rig}"
    );

    // Refined by the free run's error on the training record, the friction loses its bias: the
    // record is noiseless, so the refined model's free run on the held-out record is exact to
    // the integrator's tolerance, where the weak form's was a tenth of the spread off.
    let refined = dir.join("refined.json");
    let mut refine = identify(&["--refine", "--json", "--save-model"]);
    refine.push(s(&refined).to_owned());
    let found = json(&ok(&refine.iter().map(String::as_str).collect::<Vec<_>>()));
    let r = &found["refinement"];
    let (before, after) = (
        r["rmse_before"].as_f64().unwrap(),
        r["rmse_after"].as_f64().unwrap(),
    );
    assert!(after < 1e-6 * before, "{r}");
    assert_eq!(r["converged"], true, "{r}");
    // The weak form's coefficients are kept beside, and its bootstrap does not describe these.
    let weak = r["start"]["sign(x')"].as_f64().unwrap();
    let friction = found["coefficients"]["sign(x')"].as_f64().unwrap();
    assert!(
        (weak / friction - 0.9).abs() < 0.05,
        "weak form {weak}, refined {friction}"
    );
    assert!(found["intervals"].is_null(), "{found}");
    assert!(
        found["no_intervals"].as_str().unwrap().contains("refined"),
        "{found}"
    );
    let v = json(&ok(&[
        "compare",
        s(&refined),
        s(&test),
        "--drive-col",
        "p",
        "--json",
    ]));
    let range = &v["ranges"][0];
    let rmse = range["rmse"].as_f64().unwrap();
    let fit = range["fit_percent"].as_f64().unwrap();
    assert!(rmse < 1e-6 && fit > 99.9999, "RMSE {rmse}, fit {fit} %");
    // A refinement whose state would take every sample is refused, and --refine-init alone too.
    // (The record's stick phases also raise a warning of outliers first.)
    let too_long = identify(&["--bootstrap", "0", "--refine", "--refine-init", "20000"]);
    let out = hbid(&too_long.iter().map(String::as_str).collect::<Vec<_>>());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && !err.contains("panicked"), "{err}");
    let errors: Vec<&str> = err.lines().filter(|l| l.starts_with("error")).collect();
    assert_eq!(errors.len(), 1, "{err}");
    assert!(errors[0].contains("longer than the 20000 samples"), "{err}");
    assert_clean_failure(&hbid(&["identify", s(&train), "--refine-init", "20"]), "--refine");
}

#[test]
fn bad_requests_are_refused_in_one_line() {
    let dir = scratch("bad");
    let (train, test) = duffing_records(&dir, "0", None);
    let model = dir.join("m.json");
    ok(&[
        "identify",
        s(&train),
        "--signal",
        "line",
        "--drive-frequency",
        "6.5",
        "--drive-col",
        "p",
        "--bootstrap",
        "0",
        "--save-model",
        s(&model),
    ]);
    let (m, t) = (s(&model), s(&test));
    assert_clean_failure(&hbid(&["compare", m, t]), "--drive-col");
    assert_clean_failure(
        &hbid(&["compare", m, t, "--drive-col", "p", "--range", "0..999999"]),
        "--range",
    );
    assert_clean_failure(
        &hbid(&["compare", m, t, "--drive-col", "p", "--range", "9..3"]),
        "--range",
    );
    assert_clean_failure(&hbid(&["compare", m, t, "--drive-col", "p", "--x0", "1"]), "--x0");
    // A range no longer than the samples that set its state says so, not that it has gaps.
    assert_clean_failure(
        &hbid(&[
            "compare",
            m,
            t,
            "--drive-col",
            "p",
            "--init",
            "8",
            "--range",
            "100..105",
        ]),
        "--init 8: leaves no sample of the range 100..105 to score: the range has 5 sample(s)",
    );
    assert_clean_failure(
        &hbid(&["compare", m, t, "--drive-col", "p", "--init", "1"]),
        "--init",
    );
    assert_clean_failure(
        &hbid(&["compare", m, t, "--drive-col", "p", "--signal", "circle"]),
        "--signal",
    );
    assert_clean_failure(&hbid(&["compare", t, t, "--drive-col", "p"]), t);
    // A figure is PNG or SVG, by its extension in any case; any other is refused before the run.
    let gif = dir.join("cmp.gif");
    assert_clean_failure(
        &hbid(&["compare", m, t, "--drive-col", "p", "--plot", s(&gif)]),
        "--plot",
    );
    assert!(!gif.exists());
    let upper = dir.join("cmp.SVG");
    ok(&["compare", m, t, "--drive-col", "p", "--plot", s(&upper)]);
    assert!(std::fs::read_to_string(&upper).unwrap().starts_with("<svg"));
    let out = dir.join("out.csv");
    assert_clean_failure(
        &hbid(&[
            "simulate",
            "--model",
            m,
            "--input",
            t,
            "--drive-col",
            "p",
            "--f",
            "2",
            "--out",
            s(&out),
        ]),
        "--f",
    );
    assert_clean_failure(&hbid(&["simulate", "--dt", "0.1", "--out", s(&out)]), "--dt");
    // A state given without --init 0 would be ignored: refused.
    assert_clean_failure(
        &hbid(&[
            "simulate",
            "--model",
            m,
            "--input",
            t,
            "--drive-col",
            "p",
            "--x0",
            "1",
            "--out",
            s(&out),
        ]),
        "--x0",
    );
    // An --init that leaves nothing of a range to score.
    assert_clean_failure(
        &hbid(&[
            "compare",
            m,
            t,
            "--drive-col",
            "p",
            "--range",
            "0..50",
            "--init",
            "60",
        ]),
        "--init",
    );
    // The report's orbits need a periodic drive.
    let report = dir.join("report");
    assert_clean_failure(
        &hbid(&[
            "report",
            t,
            "--signal",
            "line",
            "--drive-period",
            "none",
            "--window",
            "1",
            "--out",
            s(&report),
        ]),
        "periodic drive",
    );
    assert!(!out.exists(), "no output for a refused request");
}

/// The EMPS benchmark (`../shared/benchmarks/emps`): a positioning system with viscous and dry
/// friction under a measured force with no period.
fn emps(file: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/benchmarks/emps")
        .join(file)
}

#[test]
fn windows_in_seconds_for_a_drive_without_a_period() {
    let (train, test) = (emps("emps_train_txp.csv"), emps("emps_test_txp.csv"));
    let dir = scratch("emps");
    let terms = "1, x', sign(x'), p";
    let base = [
        "identify",
        s(&train),
        "--signal",
        "line",
        "--drive-col",
        "p",
        "--terms",
        terms,
        "--bootstrap",
        "0",
    ];
    // Windows in periods of the record's slow motion: one window, and a warning that says so.
    let mut args = base.to_vec();
    args.extend(["--drive-period", "none"]);
    let err = String::from_utf8_lossy(&ok(&args).stderr).into_owned();
    assert!(
        err.contains("only 1 window(s)") && err.contains("--window"),
        "{err}"
    );
    // Windows of 0.75 s: the benchmark's reference parameters (inverse dynamics, its document)
    // within 1 to 3 %.
    let model = dir.join("emps.json");
    let mut args = base.to_vec();
    args.extend(["--window", "0.75", "--json", "--save-model", s(&model)]);
    let out = ok(&args);
    assert!(!String::from_utf8_lossy(&out.stderr).contains("window(s)"));
    let v = json(&out);
    let c = |name: &str| v["coefficients"][name].as_f64().unwrap();
    let mass = -1.0 / c("p");
    for (name, value, reference, within) in [
        ("M", mass, 95.1089, 0.01),
        ("Fv", mass * c("x'"), 203.5034, 0.02),
        ("Fc", mass * c("sign(x')"), 20.3935, 0.02),
        ("offset", mass * c("1"), -3.1648, 0.03),
    ] {
        assert!(
            ((value - reference) / reference).abs() < within,
            "{name} = {value} against {reference}"
        );
    }
    assert_eq!(v["record"]["drive"], "windows");
    // The protocol: a free run under the test record's force, 20 samples for the state; the
    // benchmark's reference model scores about 8.4 mm.
    let v = json(&ok(&[
        "compare",
        s(&model),
        s(&test),
        "--drive-col",
        "p",
        "--init",
        "20",
        "--json",
    ]));
    let rmse = v["ranges"][0]["rmse"].as_f64().unwrap();
    assert!(rmse < 8.4e-3, "RMSE {rmse} m");
    // A periodic drive counts its windows in its periods.
    let mut args = base.to_vec();
    args.extend(["--window", "0.75", "--drive-frequency", "4"]);
    assert_clean_failure(&hbid(&args), "--window");
}

/// The width and height of a PNG, from its header.
fn png_size(path: &Path) -> (u32, u32) {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[1..4], b"PNG", "{}", path.display());
    let word = |at: usize| u32::from_be_bytes(bytes[at..at + 4].try_into().unwrap());
    (word(16), word(20))
}

/// A system's comparison is drawn one panel per coordinate, side by side, each named by it; on
/// the circle every curve is wrapped as the measured angle is.
#[test]
fn a_systems_comparison_is_drawn_coordinate_by_coordinate() {
    let dir = scratch("system-plot");
    let record = dir.join("dp.csv");
    let truth = dir.join("dp.json");
    ok(&[
        "simulate",
        "--system",
        "double-pendulum",
        "--samples",
        "3200",
        "--truth",
        s(&truth),
        "--out",
        s(&record),
    ]);
    let hint: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&truth).unwrap()).unwrap();
    let terms = hint["identify"]["terms"].as_str().unwrap();
    let model = dir.join("dp-model.json");
    ok(&[
        "identify",
        s(&record),
        "--coords",
        "theta1,theta2",
        "--terms",
        terms,
        "--bootstrap",
        "0",
        "--save-model",
        s(&model),
    ]);
    let plot = dir.join("dp.png");
    ok(&[
        "compare",
        s(&model),
        s(&record),
        "--range",
        "0..500",
        "--plot",
        s(&plot),
    ]);
    // Two panels of 640 × 600 (one figure is 900 × 650).
    assert_eq!(png_size(&plot), (1280, 600));
    // The saved system run from a given state: one value per coordinate by --q0, --dq0.
    let run = dir.join("run.csv");
    ok(&[
        "simulate",
        "--model",
        s(&model),
        "--input",
        s(&record),
        "--init",
        "0",
        "--q0",
        "0.5,-0.25",
        "--dq0",
        "0,0",
        "--out",
        s(&run),
    ]);
    let text = std::fs::read_to_string(&run).unwrap();
    let first: Vec<f64> = text
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .map(|c| c.parse().unwrap())
        .collect();
    assert!(
        (first[1] - 0.5).abs() < 1e-12 && (first[2] + 0.25).abs() < 1e-12,
        "{first:?}"
    );
    let out = hbid(&[
        "simulate",
        "--model",
        s(&model),
        "--input",
        s(&record),
        "--q0",
        "0.5,0",
        "--out",
        s(&run),
    ]);
    assert_clean_failure(&out, "--q0 sets the state of a saved --model with --init 0 only");
    // A system's state is --q0 and --dq0, both, one value per coordinate: said by their names.
    for (state, mentions) in [
        (&[][..], "--q0: --init 0 runs the system from --q0 and --dq0"),
        (&["--q0", "0.5,0"], "--dq0: give the initial velocities with --q0"),
        (
            &["--q0", "0.5", "--dq0", "0,0"],
            "--dq0 0,0: give as many initial velocities as positions (--q0: 1)",
        ),
        (
            &["--q0", "0.5", "--dq0", "0"],
            "--q0 0.5: give one value per coordinate of the system (2)",
        ),
    ] {
        let mut args = vec![
            "simulate",
            "--model",
            s(&model),
            "--input",
            s(&record),
            "--init",
            "0",
            "--out",
            s(&run),
        ];
        args.extend_from_slice(state);
        assert_clean_failure(&hbid(&args), mentions);
    }
}

/// A system's record is paired with the model by the names of its columns, in whatever order
/// `--coords`, `--drive-col` and `--velocity-col` give them: the robot arm's two joints and
/// torques named in the reverse order score as in order. Columns given alone are taken in the
/// model's order (positions too); a name the model does not have, or names of both kinds, are
/// refused in one line.
#[test]
fn a_systems_columns_are_paired_with_the_model_by_name() {
    let dir = scratch("system-by-name");
    let record = dir.join("arm.csv");
    let truth = dir.join("arm.json");
    ok(&[
        "simulate",
        "--system",
        "arm",
        "--samples",
        "6000",
        "--truth",
        s(&truth),
        "--out",
        s(&record),
    ]);
    // Scored on a record the model was not fitted to: the arm from another initial state.
    let held_out = dir.join("arm-test.csv");
    ok(&[
        "simulate",
        "--system",
        "arm",
        "--samples",
        "6000",
        "--q0",
        "0.5,-0.3",
        "--out",
        s(&held_out),
    ]);
    let header = std::fs::read_to_string(&held_out).unwrap();
    assert!(header.starts_with("t,q1,q2,v1,v2,tau1,tau2"), "{}", &header[..40]);
    let hint: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&truth).unwrap()).unwrap();
    let terms = hint["identify"]["terms"].as_str().unwrap();
    let window = hint["identify"]["window"].as_f64().unwrap().to_string();
    let model = dir.join("arm-model.json");
    ok(&[
        "identify",
        s(&record),
        "--coords",
        "q1,q2",
        "--drive-col",
        "tau1,tau2",
        "--window",
        &window,
        "--terms",
        terms,
        "--bootstrap",
        "0",
        "--save-model",
        s(&model),
    ]);
    let rmse = |extra: &[&str]| -> Vec<f64> {
        let mut args = vec![
            "compare",
            s(&model),
            s(&held_out),
            "--range",
            "2000..3000",
            "--json",
        ];
        args.extend_from_slice(extra);
        json(&ok(&args))["ranges"]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| r["rmse"].as_f64().unwrap())
            .collect()
    };
    let fitted = rmse(&[]);
    assert!(fitted.iter().all(|&e| e < 1e-3), "{fitted:?}");
    for extra in [
        &["--coords", "q2,q1"][..],
        &["--coords", "q2=3,q1=2"],
        &["--drive-col", "tau2,tau1"],
        &["--drive-col", "6,7"],
        &["--coords", "2,3", "--drive-col", "tau2=7,tau1=6"],
    ] {
        assert_eq!(rmse(extra), fitted, "{extra:?}");
    }
    let measured = rmse(&["--velocity-col", "v1,v2"]);
    assert!(measured.iter().all(|&e| e < 1e-3), "{measured:?}");
    assert_eq!(rmse(&["--velocity-col", "q2=v2,q1=v1"]), measured);
    assert_eq!(
        rmse(&["--coords", "q2,q1", "--velocity-col", "q1=v1,q2=v2"]),
        measured
    );
    // A name that is not a coordinate's is refused, not taken for another by its place; so are
    // the options of one coordinate's record.
    let refused = |extra: &[&str], mentions: &str| {
        let mut args = vec!["compare", s(&model), s(&held_out), "--range", "2000..3000"];
        args.extend_from_slice(extra);
        assert_clean_failure(&hbid(&args), mentions);
    };
    refused(
        &["--velocity-col", "q2=v2,Q1=v1"],
        "--velocity-col q2=v2,Q1=v1: 'Q1' is not one of the system's coordinates (q1, q2)",
    );
    refused(
        &["--angle-col", "q1"],
        "--angle-col: reads the angle of a model of one coordinate; this one has 2 (q1, q2)",
    );
    // A state given is that at a range's start: ranges that start elsewhere are refused, those
    // that start there scored in full.
    let state = ["--x0", "0.5,-0.3", "--v0", "0,0"];
    refused(
        &[&state[..], &["--range", "500..600"]].concat(),
        "--x0: is the state at the first sample of a range, and the ranges start at samples 2000 and 500",
    );
    let out = ok(&[
        &[
            "compare",
            s(&model),
            s(&held_out),
            "--range",
            "0..100",
            "--range",
            "0..200",
            "--json",
        ][..],
        &state[..],
    ]
    .concat());
    for r in json(&out)["ranges"].as_array().unwrap() {
        assert_eq!(r["init"], 0, "{r}");
        assert_eq!(
            r["scored"].as_u64().unwrap(),
            r["range"][1].as_u64().unwrap(),
            "{r}"
        );
    }
    // Positions in another order are the user's pairing: the joints swapped score badly.
    let swapped = rmse(&["--coords", "3,2"]);
    assert!(swapped.iter().all(|&e| e > 0.1), "{swapped:?}");
    // A model identified by position (the truth's own arguments, q1=2,q2=3 and tau1=6,tau2=7),
    // compared on the record with its columns in another order, its header naming them: refused
    // until the columns are chosen, then as in order.
    let positional = dir.join("arm-positions.json");
    let mut args: Vec<String> = [
        "identify",
        s(&record),
        "--bootstrap",
        "0",
        "--save-model",
        s(&positional),
    ]
    .map(String::from)
    .to_vec();
    args.extend(
        hint["identify"]["args"]
            .as_array()
            .unwrap()
            .iter()
            .map(|a| a.as_str().unwrap().to_owned()),
    );
    ok(&args.iter().map(String::as_str).collect::<Vec<_>>());
    let reordered: String = header
        .lines()
        .map(|line| {
            let c: Vec<&str> = line.split(',').collect();
            [c[0], c[2], c[1], c[4], c[3], c[6], c[5]].join(",") + "\n"
        })
        .collect();
    let reordered_path = dir.join("arm-reordered.csv");
    std::fs::write(&reordered_path, reordered).unwrap();
    let on = |extra: &[&str]| {
        let mut args = vec![
            "compare",
            s(&positional),
            s(&reordered_path),
            "--range",
            "2000..3000",
            "--json",
        ];
        args.extend_from_slice(extra);
        hbid(&args)
    };
    assert_clean_failure(
        &on(&[]),
        "--coords: the model read q1, q2 from the columns 2, 3 where it was identified; this record's header \
         names q2, q1 there",
    );
    assert_clean_failure(
        &on(&["--coords", "q1,q2"]),
        "--drive-col: the model read tau1, tau2 from the columns 6, 7",
    );
    let chosen = on(&["--coords", "q1,q2", "--drive-col", "tau1,tau2"]);
    assert!(
        chosen.status.success(),
        "{}",
        String::from_utf8_lossy(&chosen.stderr)
    );
    let scores: Vec<f64> = json(&chosen)["ranges"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["rmse"].as_f64().unwrap())
        .collect();
    assert!(scores.iter().all(|&e| e < 1e-3), "{scores:?}");
    // The saved system run over that record: its columns chosen as compare chooses them.
    let run = dir.join("arm-run.csv");
    let simulated = hbid(&[
        "simulate",
        "--model",
        s(&positional),
        "--input",
        s(&reordered_path),
        "--coords",
        "q1,q2",
        "--drive-col",
        "tau1,tau2",
        "--out",
        s(&run),
    ]);
    assert!(
        simulated.status.success(),
        "{}",
        String::from_utf8_lossy(&simulated.stderr)
    );
    assert!(
        std::fs::read_to_string(&run)
            .unwrap()
            .starts_with("t,q1,q2,q1',q2'\n")
    );
    for (extra, mentions) in [
        (
            &["--coords", "zz=2,yy=3"][..],
            "'zz' is not one of the system's coordinates (q1, q2)",
        ),
        (
            &["--coords", "q2,v1"],
            "'q2' is one of the system's coordinates and 'v1' is not",
        ),
        (
            &["--drive-col", "tau2=7,p=6"],
            "'p' is not one of the system's drives (tau1, tau2)",
        ),
    ] {
        let mut args = vec!["compare", s(&model), s(&record)];
        args.extend_from_slice(extra);
        assert_clean_failure(&hbid(&args), mentions);
    }
}

/// One coordinate under two measured drives of their own names: the model is saved as the
/// system it is (the one-model format has no names for them), read back, compared and run under
/// the record's drives by name.
#[test]
fn one_coordinate_under_two_named_drives_is_saved_compared_and_run() {
    let dir = scratch("two-drives");
    let base = dir.join("base.csv");
    ok(&[
        "simulate",
        "--samples",
        "3000",
        "--write-drive",
        "--out",
        s(&base),
    ]);
    // The shaker's drive as `u`, and a second measured series `w` the pendulum does not feel.
    let text = std::fs::read_to_string(&base).unwrap();
    let mut lines = text.lines();
    lines.next();
    let mut record = "t,theta,omega,u,w\n".to_owned();
    for line in lines {
        let t: f64 = line.split(',').next().unwrap().parse().unwrap();
        record.push_str(&format!("{line},{}\n", t.cos()));
    }
    let path = dir.join("two.csv");
    std::fs::write(&path, record).unwrap();
    let model = dir.join("model.json");
    ok(&[
        "identify",
        s(&path),
        "--drive-col",
        "u,w",
        "--bootstrap",
        "0",
        "--save-model",
        s(&model),
    ]);
    let saved: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&model).unwrap()).unwrap();
    assert_eq!(saved["drives"], serde_json::json!(["u", "w"]), "{saved}");
    let rmse = |extra: &[&str]| -> f64 {
        let mut args = vec!["compare", s(&model), s(&path), "--range", "0..100", "--json"];
        args.extend_from_slice(extra);
        json(&ok(&args))["ranges"][0]["rmse"].as_f64().unwrap()
    };
    // The record's own columns by default, or named; the drives by name in any order.
    let by_default = rmse(&[]);
    assert!(by_default < 1e-3, "{by_default}");
    assert_eq!(rmse(&["--angle-col", "theta", "--drive-col", "w,u"]), by_default);
    assert_clean_failure(
        &hbid(&["compare", s(&model), s(&path), "--drive-col", "u"]),
        "--drive-col u: the system reads 2 drive(s) (u, w)",
    );
    let run = dir.join("run.csv");
    ok(&[
        "simulate",
        "--model",
        s(&model),
        "--input",
        s(&path),
        "--out",
        s(&run),
    ]);
    let rows = std::fs::read_to_string(&run).unwrap();
    assert!(rows.starts_with("t,x,"), "{}", &rows[..20]);
    assert_eq!(rows.lines().count(), 3001);
    let report = dir.join("report");
    ok(&["report", "--model", s(&model), s(&path), "--out", s(&report)]);
    assert!(report.join("README.md").exists());
    // Identified by the drives' positions, the model keeps them, and runs on a record of the
    // same columns with no option.
    let positional = dir.join("positional.json");
    ok(&[
        "identify",
        s(&path),
        "--angle-col",
        "theta",
        "--drive-col",
        "u=4,w=5",
        "--bootstrap",
        "0",
        "--save-model",
        s(&positional),
    ]);
    let saved: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&positional).unwrap()).unwrap();
    assert_eq!(
        saved["columns"]["coordinates"],
        serde_json::json!(["theta"]),
        "{saved}"
    );
    assert_eq!(
        saved["columns"]["drives"],
        serde_json::json!(["4", "5"]),
        "{saved}"
    );
    let args = ["compare", s(&positional), s(&path), "--range", "0..100", "--json"];
    assert_eq!(
        json(&ok(&args))["ranges"][0]["rmse"].as_f64().unwrap(),
        by_default
    );
}

/// A held-out record of the velocity (a laser vibrometer's) is integrated with the offset the
/// model's equation holds best with, and scored as the displacement record is: the two-well
/// Duffing oscillator, whose wells make the offset matter (integrated with its mean taken out
/// alone, the run starts in the wrong well's field).
#[test]
fn a_velocity_record_is_compared_as_its_displacement() {
    let dir = scratch("velocity");
    let train = dir.join("train.csv");
    let test = dir.join("test.csv");
    ok(&[
        "simulate",
        "--system",
        "duffing",
        "--samples",
        "6000",
        "--out",
        s(&train),
    ]);
    ok(&[
        "simulate",
        "--system",
        "duffing",
        "--samples",
        "2000",
        "--x0",
        "0.5",
        "--out",
        s(&test),
    ]);
    let model = dir.join("m.json");
    ok(&[
        "identify",
        s(&train),
        "--signal",
        "line",
        "--bootstrap",
        "0",
        "--save-model",
        s(&model),
    ]);
    let rmse = |file: &Path, extra: &[&str]| -> (f64, String) {
        let mut args = vec!["compare", s(&model), s(file), "--range", "0..60", "--json"];
        args.extend_from_slice(extra);
        let out = ok(&args);
        (
            json(&out)["ranges"][0]["rmse"].as_f64().unwrap(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    let (displacement, _) = rmse(&test, &[]);
    // The record's velocity column as the measured output.
    let velocity = dir.join("velocity.csv");
    let text = std::fs::read_to_string(&test).unwrap();
    let rows: String = text
        .lines()
        .skip(1)
        .map(|l| {
            let cells: Vec<&str> = l.split(',').collect();
            format!("{},{}\n", cells[0], cells[2])
        })
        .collect();
    std::fs::write(&velocity, format!("t,v\n{rows}")).unwrap();
    let (integrated, _) = rmse(&velocity, &["--measured", "velocity"]);
    // Measured: 2.3e-8 on the displacement; 1.0e-5 on the velocity, the sixth-order integral of
    // a two-well motion's harmonics at 25 samples per period; the integral with its mean taken
    // out alone gave 6.6e-2 on this range.
    assert!(displacement < 1e-6, "{displacement}");
    assert!(integrated < 1e-4, "{integrated} against {displacement}");
    let out = hbid(&[
        "compare",
        s(&model),
        s(&velocity),
        "--measured",
        "velocity",
        "--range",
        "0..60",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("note: the velocity record integrated to the displacement, each piece's constants"),
        "{stderr}"
    );
    // A report of the saved model on the velocity record integrates it once, as compare does.
    let report = dir.join("report");
    ok(&[
        "report",
        "--model",
        s(&model),
        s(&velocity),
        "--measured",
        "velocity",
        "--signal",
        "line",
        "--out",
        s(&report),
    ]);
    let text = std::fs::read_to_string(report.join("README.md")).unwrap();
    assert!(
        text.contains("the velocity record integrated to the displacement"),
        "{text}"
    );
    // Two rows dropped 11 apart leave a piece of 10 samples, too short for its constants: left
    // out as a gap, and said so; the pieces around it are integrated each with their own.
    let gapped = dir.join("gapped.csv");
    let kept: String = rows
        .lines()
        .enumerate()
        .filter(|(i, _)| *i != 30 && *i != 41)
        .map(|(_, l)| format!("{l}\n"))
        .collect();
    std::fs::write(&gapped, format!("t,v\n{kept}")).unwrap();
    let out = ok(&[
        "compare",
        s(&model),
        s(&gapped),
        "--measured",
        "velocity",
        "--range",
        "0..200",
        "--json",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("1 piece(s) of fewer than 17 samples left out as gaps (the first 31..41)"),
        "{stderr}"
    );
    assert!(
        json(&out)["ranges"][0]["rmse"].as_f64().unwrap() < 1e-3,
        "{stderr}"
    );
    // A state given is a range's first sample's, which a left-out piece could put after it.
    let given = hbid(&[
        "compare",
        s(&model),
        s(&gapped),
        "--measured",
        "velocity",
        "--x0",
        "0.5",
        "--v0",
        "0",
    ]);
    let err = String::from_utf8_lossy(&given.stderr);
    assert!(!given.status.success() && !err.contains("panicked"), "{err}");
    assert!(
        err.lines().last().unwrap().starts_with(
            "error: --x0: is the state at a range's first sample, but pieces too short to integrate were left \
             out (the first 31..41)"
        ),
        "{err}"
    );
    // A record of one piece too short for its constants.
    let short = dir.join("short.csv");
    let first: String = rows.lines().take(16).map(|l| format!("{l}\n")).collect();
    std::fs::write(&short, format!("t,v\n{first}")).unwrap();
    assert_clean_failure(
        &hbid(&["compare", s(&model), s(&short), "--measured", "velocity"]),
        "--measured velocity: every piece of the record is shorter than 17 samples",
    );
    // A model on the circle is not compared with an integrated record.
    let pendulum = dir.join("pendulum.csv");
    ok(&["simulate", "--samples", "3000", "--out", s(&pendulum)]);
    let circle = dir.join("circle.json");
    ok(&[
        "identify",
        s(&pendulum),
        "--bootstrap",
        "0",
        "--save-model",
        s(&circle),
    ]);
    assert_clean_failure(
        &hbid(&["compare", s(&circle), s(&velocity), "--measured", "velocity"]),
        "a model on the circle is not compared with a velocity or acceleration record",
    );
    // Nor reported on one, refused before the record is read and with no report left.
    let refused = dir.join("refused");
    assert_clean_failure(
        &hbid(&[
            "report",
            "--model",
            s(&circle),
            s(&velocity),
            "--measured",
            "velocity",
            "--out",
            s(&refused),
        ]),
        "a model on the circle is not compared with a velocity or acceleration record",
    );
    assert!(!refused.exists());
}
