//! The `hbid` binary as a user runs it.
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn hbid(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hbid"))
        .args(args)
        .output()
        .expect("hbid runs")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("hbid-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
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
        (vec!["--samples-per-period", "0"], "samples per period"),
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
