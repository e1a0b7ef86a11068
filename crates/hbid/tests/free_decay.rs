//! A free decay as a rig logs it: a pendulum swinging at 1.3 Hz, sampled at 1 kHz by a 4096-count
//! encoder whose zero is off the bottom, the swing decaying from 80 counts to a few over 45 s
//! (viscous damping and a little dry friction), with bit errors, half-turn ones (2048 counts)
//! among them. Near rest the counts toggle every few samples: the period of the oscillation must
//! still be found, and the equation identified with windows of that period.
use crate::support::hbid;
use std::f64::consts::{PI, TAU};
use std::path::{Path, PathBuf};

use circle_signal::{Domain, OscillationPeriod, wrap};

fn scratch(name: &str) -> PathBuf {
    crate::support::scratch("free-decay", name)
}

/// The header and the rows of a CSV record (comment lines skipped).
fn read(path: &Path) -> (String, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header = lines.next().unwrap().to_owned();
    let rows = lines
        .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
        .collect();
    (header, rows)
}

/// The pendulum: its small-swing frequency is 1/r = 1 in model time τ = 2π · 1.3 Hz · t, so
/// 1.3 Hz; from 0.1227 rad (80 counts) at rest, damping c = 0.012 and dry friction μ = 10⁻⁴ (in
/// model time) bring the swing to 3 counts after 45 s.
const PENDULUM: [&str; 18] = [
    "--forcing",
    "none",
    "--r",
    "1",
    "--drive-frequency",
    "1.3",
    "--sample-rate",
    "1000",
    "--duration",
    "45",
    "--theta0",
    "0.1227",
    "--c",
    "0.012",
    "--friction",
    "1e-4",
    "--time-origin",
    "first-sample",
];

/// Samples of the encoder's record given a bit error of half a turn.
const HALF_TURN_ERRORS: [usize; 4] = [4_321, 17_003, 29_876, 41_234];

struct Decay {
    /// The encoder's record: counts, zero offset, bit errors, half-turn bit errors.
    record: PathBuf,
    /// Its true equation.
    truth: PathBuf,
    /// The angles of the record.
    angles: Vec<f64>,
    /// The true mean period in samples: the mean spacing of the upward zero crossings of the
    /// simulated angle without the encoder.
    period: f64,
}

fn simulate(dir: &Path, name: &str, extra: &[&str]) -> PathBuf {
    let out = dir.join(name);
    let mut args = vec!["simulate"];
    args.extend(PENDULUM);
    args.extend(extra);
    args.extend(["--out", out.to_str().unwrap()]);
    let run = hbid(&args);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    out
}

/// The free decay, clean and as the encoder logs it.
fn decay(dir: &Path) -> Decay {
    let clean = read(&simulate(dir, "clean.csv", &[])).1;
    let crossings: Vec<f64> = clean
        .windows(2)
        .enumerate()
        .filter(|(_, w)| w[0][1] < 0.0 && w[1][1] >= 0.0)
        .map(|(i, w)| i as f64 + w[0][1] / (w[0][1] - w[1][1]))
        .collect();
    assert!(crossings.len() > 50, "{} swings", crossings.len());
    let period = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;

    let truth = dir.join("truth.json");
    let logged = simulate(
        dir,
        "logged.csv",
        &[
            "--counts",
            "4096",
            "--zero-offset",
            "0.7",
            "--bit-errors",
            "1e-4",
            "--seed",
            "5",
            "--time-decimals",
            "3",
            "--truth",
            truth.to_str().unwrap(),
        ],
    );
    // Half a turn more at a few samples, as a flip of the encoder's top bit.
    let text = std::fs::read_to_string(&logged).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    let first = lines.iter().position(|l| l.starts_with('t')).unwrap() + 1;
    for &i in &HALF_TURN_ERRORS {
        let mut cells: Vec<String> = lines[first + i].split(',').map(str::to_owned).collect();
        let angle: f64 = cells[1].parse().unwrap();
        cells[1] = format!("{:?}", wrap(angle + PI));
        lines[first + i] = cells.join(",");
    }
    let record = dir.join("decay.csv");
    std::fs::write(&record, lines.join("\n") + "\n").unwrap();
    let angles: Vec<f64> = read(&record).1.iter().map(|r| r[1]).collect();
    let count = TAU / 4096.0;
    assert!(
        angles
            .iter()
            .all(|a| (a / count - (a / count).round()).abs() < 1e-6)
    );
    Decay {
        record,
        truth,
        angles,
        period,
    }
}

/// The period of the logged decay, against the mean spacing of the swings of the clean angle.
/// The swing's period changes by 0.09 % between 80 counts and rest (a pendulum's period grows by
/// `A²/16` at amplitude `A`): the strongest spectral line and the mean spacing of the swings
/// weigh the swings differently, so they may differ by that much; 10⁻³ is that spread. The
/// estimate is within 10⁻⁴ (769.38 samples against 769.43).
#[test]
fn the_period_of_a_quantised_decay_with_bit_errors() {
    let dir = scratch("period");
    let decay = decay(&dir);
    assert!(
        (decay.period / (1000.0 / 1.3) - 1.0).abs() < 2e-3,
        "{}",
        decay.period
    );
    let found = OscillationPeriod::measure(&decay.angles, Domain::Circle).unwrap();
    assert!(
        (found.samples / decay.period - 1.0).abs() < 1e-3,
        "{found:?} against {}",
        decay.period
    );
    assert_eq!(found.measured, 0..45_000);
    // The last 8 s alone: a swing of 5 counts down to 3.
    let tail = OscillationPeriod::measure(&decay.angles[37_000..], Domain::Circle).unwrap();
    assert!(
        (tail.samples / decay.period - 1.0).abs() < 1e-3,
        "{tail:?} against {}",
        decay.period
    );
}

/// The coefficient `name` of an identification, its standard error and its truth.
fn coefficient(found: &serde_json::Value, truth: &serde_json::Value, name: &str) -> (f64, f64, f64) {
    let got = found["coefficients"][name].as_f64().unwrap();
    let error = found["std_errors"][name].as_f64().unwrap();
    let want = truth["coefficients"][name].as_f64().unwrap();
    (got, error, want)
}

/// `hbid identify --method windowed --forcing none --repair` on the logged decay, with the
/// model of its truth (viscous damping, dry friction, the gravity of an encoder zero 0.7 rad off
/// the bottom): windows of the default three periods of the free oscillation, the period measured
/// from the record, the bit errors (half-turn ones too) replaced, the encoder's toggles near rest
/// left alone.
///
/// Tolerances: the fit reports standard errors of 1.0 % of the damping and 5.1 % of the friction
/// (the two are told apart only by the shape of the decay, exponential against linear), 7·10⁻⁵
/// of the stiffness; each coefficient must lie within three of its standard errors of the truth,
/// and the standard errors must stay that small (a fit spoilt by a bad repair has them twenty
/// times larger, 0.14 % of the acceleration unexplained). Found: damping −0.73 %, friction
/// +4.5 %, stiffness −1.7·10⁻⁶ and +2.0·10⁻⁶, 99.9996 % explained.
#[test]
fn a_quantised_decay_is_identified_with_windows_of_its_period() {
    let dir = scratch("identify");
    let decay = decay(&dir);
    let out = hbid(&[
        "identify",
        decay.record.to_str().unwrap(),
        "--method",
        "windowed",
        "--forcing",
        "none",
        "--repair",
        "--terms",
        "x', sign(x'), cos(x), sin(x)",
        "--bootstrap",
        "0",
        "--json",
    ]);
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{err}");
    // The four bit errors of the simulation and the four half-turn ones, and nothing else.
    assert!(err.contains("8 isolated spike(s) replaced"), "{err}");
    let period: f64 = err
        .split("periods of the free oscillation, ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no period in: {err}"));
    assert!(
        (period / decay.period - 1.0).abs() < 1e-3,
        "{period} against {}",
        decay.period
    );
    let found: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&decay.truth).unwrap()).unwrap();
    assert!(found["explained"].as_f64().unwrap() > 0.99999, "{found}");
    // The largest standard error each coefficient may have, relative to its truth.
    for (name, largest) in [
        ("sin(x)", 1e-4),
        ("cos(x)", 1e-4),
        ("x'", 0.015),
        ("sign(x')", 0.075),
    ] {
        let (got, error, want) = coefficient(&found, &truth, name);
        assert!(
            (got - want).abs() < 3.0 * error && error < largest * want.abs(),
            "{name}: {got} ± {error} against {want}"
        );
    }
}
