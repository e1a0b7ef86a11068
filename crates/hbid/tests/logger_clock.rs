//! A rig's record with the time stamps of a real logger, through the command line: a 500 Hz
//! record printed to 1 ms whose clock slips by a millisecond for tens of thousands of samples at
//! a time (single steps of 1 and 3 ms where it slips) with two stamps 7 ms early (a step of -5 ms,
//! then one of +9 ms), and records whose stamps jitter.
use crate::support::hbid;
use std::path::{Path, PathBuf};

fn scratch(name: &str) -> PathBuf {
    crate::support::scratch("logger", name)
}

/// The drive of the simulated rig, in Hz.
const DRIVE: &str = "1.02";

/// A 500 Hz pendulum rig driven at 1.02 Hz for 120 s (60 000 samples, stamps printed to 1 ms):
/// its rows `(t, theta)` as printed and its true coefficients.
fn rig(dir: &Path) -> (Vec<(f64, String)>, serde_json::Map<String, serde_json::Value>) {
    let (record, truth) = (dir.join("rig.csv"), dir.join("truth.json"));
    let out = hbid(&[
        "simulate",
        "--quiet",
        "--drive-frequency",
        DRIVE,
        "--sample-rate",
        "500",
        "--duration",
        "120",
        "--time-origin",
        "first-sample",
        "--time-decimals",
        "3",
        "--truth",
        truth.to_str().unwrap(),
        "--out",
        record.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = std::fs::read_to_string(&record).unwrap();
    let mut lines = text.lines();
    assert!(lines.next().unwrap().starts_with("t,theta"));
    let rows = lines
        .map(|l| {
            let mut cells = l.split(',');
            let t = cells.next().unwrap().parse().unwrap();
            (t, cells.next().unwrap().to_owned())
        })
        .collect();
    let truth: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&truth).unwrap()).unwrap();
    (rows, truth["coefficients"].as_object().unwrap().clone())
}

/// Writes `t,theta` with the stamps `t` printed to `decimals` and the angles as simulated.
fn write(path: &Path, t: &[f64], rows: &[(f64, String)], decimals: usize) -> String {
    let text: String = std::iter::once("t,theta\n".to_owned())
        .chain(
            t.iter()
                .zip(rows)
                .map(|(t, (_, x))| format!("{t:.decimals$},{x}\n")),
        )
        .collect();
    std::fs::write(path, text).unwrap();
    path.to_str().unwrap().to_owned()
}

/// `hbid identify` by the weak form at the rig's drive, with `extra` options: the coefficients
/// and the text on standard error.
fn identify(path: &str, extra: &[&str]) -> (Option<serde_json::Map<String, serde_json::Value>>, String) {
    let mut args = vec![
        "identify",
        path,
        "--method",
        "windowed",
        "--forcing-frequency",
        DRIVE,
        "--bootstrap",
        "0",
        "--json",
    ];
    args.extend(extra);
    let out = hbid(&args);
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!err.contains("panicked"), "{err}");
    let found = out.status.success().then(|| {
        let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        json["coefficients"].as_object().unwrap().clone()
    });
    (found, err)
}

/// How the identified coefficients `got` differ from the true `want`, over the largest true
/// coefficient: `(drive amplitude, drive phase in radians, every other term)`. The grid's
/// origin is known to the stamps' accuracy only: it turns the drive term `sin(t)*cos(x)` into
/// `cos(t)*cos(x)` by the phase of the origin's offset, and leaves its amplitude.
fn errors(
    want: &serde_json::Map<String, serde_json::Value>,
    got: &serde_json::Map<String, serde_json::Value>,
) -> (f64, f64, f64) {
    assert_eq!(
        want.keys().collect::<Vec<_>>(),
        got.keys().collect::<Vec<_>>(),
        "the same terms"
    );
    let value = |m: &serde_json::Map<String, serde_json::Value>, name: &str| m[name].as_f64().unwrap();
    let scale = want
        .values()
        .map(|v| v.as_f64().unwrap().abs())
        .fold(0.0, f64::max);
    let (sin, cos) = ("sin(t)*cos(x)", "cos(t)*cos(x)");
    assert_eq!(value(want, cos), 0.0, "the truth's drive is in phase");
    let amplitude = (value(got, sin).hypot(value(got, cos)) - value(want, sin).abs()) / scale;
    let phase = (value(got, cos) / value(got, sin)).atan();
    let rest = want
        .keys()
        .filter(|name| ![sin, cos].contains(&name.as_str()))
        .map(|name| (value(want, name) - value(got, name)).abs())
        .fold(0.0, f64::max)
        / scale;
    (amplitude.abs(), phase, rest)
}

/// The phase of the drive over `seconds`.
fn phase_of(seconds: f64) -> f64 {
    std::f64::consts::TAU * DRIVE.parse::<f64>().unwrap() * seconds
}

#[test]
fn a_slipping_logger_clock_is_read_with_repair() {
    let dir = scratch("slips");
    let (rows, truth) = rig(&dir);
    // 24 147 stamps 1 ms behind the grid in two runs; two stamps 7 ms early, three apart, in the
    // second run.
    let late = [10_000..22_000, 35_000..47_147];
    let early = [40_000, 40_003];
    let t: Vec<f64> = rows
        .iter()
        .enumerate()
        .map(|(i, (t, _))| {
            let behind = if late.iter().any(|r| r.contains(&i)) {
                1e-3
            } else {
                0.0
            };
            let glitch = if early.contains(&i) { 7e-3 } else { 0.0 };
            t - behind - glitch
        })
        .collect();
    let path = write(&dir.join("logger.csv"), &t, &rows, 3);
    let steps: Vec<i64> = t
        .windows(2)
        .map(|w| ((w[1] - w[0]) * 1e3).round() as i64)
        .filter(|&s| s != 2)
        .collect();
    assert_eq!(steps, [1, 3, 1, -5, 9, -5, 9, 3]);

    // Without repair: refused, naming both glitches.
    let (found, err) = identify(&path, &[]);
    assert!(found.is_none(), "{err}");
    assert!(
        err.contains(&format!(
            "line 40002: time {:.3} does not increase (previous sample at {:.3})",
            t[40_000], t[39_999]
        )),
        "{err}"
    );
    assert!(
        err.contains(
            "; 1 more glitch: line 40005: an isolated glitch, which can be repaired; run with --repair"
        ),
        "{err}"
    );

    // With repair: the slips noted where they are, the glitches repaired.
    let (found, err) = identify(&path, &["--repair"]);
    let found = found.unwrap_or_else(|| panic!("{err}"));
    assert!(!err.contains("warning"), "{err}");
    let grid = err
        .lines()
        .find(|l| l.starts_with("note: the time stamps deviate from the even grid of step 0.002 "))
        .unwrap_or_else(|| panic!("{err}"));
    assert!(
        grid.contains(
            "slips 4 time(s), at line 10002 (-0.001), line 22002 (+0.001), line 35002 (-0.001), line 47149 (+0.001)"
        ) && grid.contains("within their printed resolution of 0.001"),
        "{grid}"
    );
    for (line, i) in [(40_002, 40_000), (40_005, 40_003)] {
        let prefix = format!("note: line {line}: time {:.3} replaced by its grid time ", t[i]);
        let now: f64 = err
            .lines()
            .find_map(|l| l.strip_prefix(&prefix))
            .unwrap_or_else(|| panic!("{prefix} in {err}"))
            .parse()
            .unwrap();
        // The grid lies within the 1 ms the stamps are off their samples' times (up to 1.5 ms
        // with the printing of the simulated times themselves).
        assert!((now - rows[i].0).abs() < 1.5e-3, "{now} vs {}", rows[i].0);
    }

    // The coefficients: the equation as simulated, the drive's phase moved by the offset of the
    // grid's origin, which the stamps give to within their 1 ms band.
    let (amplitude, phase, rest) = errors(&truth, &found);
    // Measured: 4.4e-6, 2.6e-3 rad (0.40 ms), 5.4e-6.
    assert!(
        amplitude < 2e-5 && rest < 2e-5,
        "{amplitude:e} {rest:e}: {found:?}"
    );
    assert!(phase.abs() < phase_of(1e-3), "{phase:e} rad");
}

/// Seeded normal numbers (splitmix64 and Box–Muller).
fn normals(seed: u64, n: usize) -> Vec<f64> {
    let mut state = seed;
    let mut uniform = move || {
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n)
        .map(|_| {
            let (u, v) = (1.0 - uniform(), uniform());
            (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
        })
        .collect()
}

#[test]
fn jittering_stamps_are_noted_with_their_deviation() {
    let dir = scratch("jitter");
    let (rows, truth) = rig(&dir);
    for (level, seed) in [(0.04, 1), (0.1, 2)] {
        // The samples on their grid, the stamps jittering by `level` of the 2 ms step (RMS),
        // printed to 7 decimals.
        let t: Vec<f64> = rows
            .iter()
            .zip(normals(seed, rows.len()))
            .map(|((t, _), z)| t + level * 2e-3 * z)
            .collect();
        let path = write(&dir.join(format!("jitter{seed}.csv")), &t, &rows, 7);
        let (found, err) = identify(&path, &[]);
        let found = found.unwrap_or_else(|| panic!("{level}: {err}"));
        let kind = if level > 0.05 { "warning" } else { "note" };
        let grid = err
            .lines()
            .find(|l| {
                l.starts_with(&format!(
                    "{kind}: the time stamps deviate from the even grid of step 0.002 "
                ))
            })
            .unwrap_or_else(|| panic!("{level}: {err}"));
        let rms: f64 = grid
            .split_once("(RMS ")
            .and_then(|(_, rest)| rest.split_once(" %"))
            .map(|(number, _)| number.parse().unwrap())
            .unwrap_or_else(|| panic!("{grid}"));
        assert!((rms / (100.0 * level) - 1.0).abs() < 0.05, "{grid}");
        assert!(
            grid.contains("more than their printed resolution of 0.0000001 explains"),
            "{grid}"
        );
        assert_eq!(
            grid.contains("which moves them by as much"),
            level > 0.05,
            "{grid}"
        );
        // The samples are on their grid; its origin is that of the stamps, to four standard
        // errors of a least-squares intercept, `4 σ √(4 / n)`. Measured: 5.5e-8, 9.6e-7 rad
        // (bound 1.7e-5), 6.6e-8 at 4 %; 1.4e-7, 2.0e-6 rad (bound 4.2e-5), 1.8e-7 at 10 %.
        let (amplitude, phase, rest) = errors(&truth, &found);
        let origin = 4.0 * level * 2e-3 * (4.0 / rows.len() as f64).sqrt();
        assert!(
            amplitude < 1e-6 && rest < 1e-6,
            "{level}: {amplitude:e} {rest:e}: {found:?}"
        );
        assert!(
            phase.abs() < phase_of(origin),
            "{level}: {phase:e} rad, {origin:e} s"
        );
    }
    // Jitter of 30 % of the step: refused, saying by how much the stamps scatter.
    let t: Vec<f64> = rows
        .iter()
        .zip(normals(3, rows.len()))
        .map(|((t, _), z)| t + 0.3 * 2e-3 * z)
        .collect();
    let (found, err) = identify(&write(&dir.join("jitter3.csv"), &t, &rows, 7), &[]);
    assert!(found.is_none(), "{err}");
    assert!(
        err.contains("time stamps are off the grid of the others")
            && err.contains("scattering about the grid by"),
        "{err}"
    );
    assert!(err.contains("give its step with --dt"), "{err}");
}
