//! `cargo xtask real-records`: records shaped like real rigs' (made by `hbid simulate`), each
//! identified by one `hbid identify` command with no preprocessing, the truth beside the result;
//! writes `docs/real-records.md`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, bail};

/// One rig: how its record is made and how it is identified.
struct Rig {
    name: &'static str,
    what: &'static str,
    /// `hbid simulate`'s options, in parts joined in order (a rig built on another shares its parts);
    /// empty for a record that `hbid simulate` cannot make (`make` writes it).
    simulate: &'static [&'static [&'static str]],
    identify: &'static [&'static str],
    /// Rewrites the record as another acquisition program would write it (after simulation).
    rewrite: Option<fn(&str) -> String>,
    /// Writes a record that no option of `hbid simulate` makes (it has no truth file).
    make: Option<fn(&Path) -> anyhow::Result<()>>,
}

/// The pendulum at 500 Hz with a 1.02 Hz drive and a 4096-count encoder, stamps to 1 ms.
const PENDULUM: &[&str] = &[
    "--drive-frequency",
    "1.02",
    "--sample-rate",
    "500",
    "--counts",
    "4096",
    "--duration",
    "300",
    "--time-origin",
    "first-sample",
    "--time-decimals",
    "3",
];

fn rigs() -> Vec<Rig> {
    vec![
        Rig {
            name: "pendulum-500hz",
            what: "base-excited pendulum (the paper's parameters), 500 Hz, 1.02 Hz drive (490.196 samples per period), 4096-count encoder, stamps to 1 ms, 300 s",
            simulate: &[PENDULUM],
            identify: &["--drive-frequency", "1.02"],
            rewrite: None,
            make: None,
        },
        Rig {
            name: "pendulum-500hz-upo",
            what: "the same record, by the paper's method (close returns)",
            simulate: &[PENDULUM],
            identify: &["--method", "upo", "--drive-frequency", "1.02"],
            rewrite: None,
            make: None,
        },
        Rig {
            name: "pendulum-unknown-drive",
            what: "the same record, the drive frequency estimated (searched from 0.5 to 2 Hz)",
            simulate: &[PENDULUM],
            identify: &["--drive-frequency", "auto:0.5..2"],
            rewrite: None,
            make: None,
        },
        Rig {
            name: "pendulum-faulty",
            what: "the same rig with the encoder's zero 0.7 rad from the bottom, angles in [0, 2π), the record starting at drive phase 1.3, bit errors (rate 1e-4, ±64..512 counts) and 3 gaps of 200 samples",
            simulate: &[
                PENDULUM,
                &[
                    "--zero-offset",
                    "0.7",
                    "--phase",
                    "1.3",
                    "--angle-range",
                    "positive",
                    "--bit-errors",
                    "1e-4",
                    "--gaps",
                    "3:200",
                    "--seed",
                    "5",
                ],
            ],
            identify: &["--drive-frequency", "1.02", "--repair"],
            rewrite: None,
            make: None,
        },
        Rig {
            name: "pendulum-dropped-rows",
            what: "the first rig's record from a logger that drops one row in a hundred (1500 single rows at seeded random places): no stretch of the three drive periods a window needs is left whole, so the gaps are bridged, all but those beside a piece too short for the spike search (fewer than 7 samples between two dropped rows)",
            simulate: &[PENDULUM, &["--gaps", "1500:1", "--seed", "5"]],
            identify: &["--drive-frequency", "1.02", "--bridge-gaps", "1"],
            rewrite: None,
            make: None,
        },
        Rig {
            name: "pendulum-late-and-missing",
            what: "the first rig's record from a networked logger that stamps to 0.1 ms: one row in 500 dropped and the \
                   row after it stamped 0.6 ms (0.3 step) late, and rows whose angle it wrote as `NaN` (one in 700) or \
                   left empty (one in 900); the late stamps repaired onto their nearest free slot, the rows with a \
                   missing value left out as dropped rows, and every gap bridged",
            simulate: &[PENDULUM],
            identify: &[
                "--drive-frequency",
                "1.02",
                "--repair",
                "--skip-missing",
                "--bridge-gaps",
                "1",
            ],
            rewrite: Some(late_and_missing),
            make: None,
        },
        Rig {
            name: "pendulum-headerless",
            what: "the first record written as a DAQ might: no header, angle first, time second, separated by spaces",
            simulate: &[PENDULUM],
            identify: &["--drive-frequency", "1.02"],
            rewrite: Some(headerless_swapped),
            make: None,
        },
        Rig {
            name: "duffing-2048hz",
            what: "two-well Duffing oscillator (c = 0.25, a = −1, b = 1, f = 0.3), 2048 Hz, 6.5 Hz shaker (315.08 samples per period), stamps to 0.1 ms, displacement to 6 decimals, 120 s",
            simulate: &[DUFFING],
            identify: &["--signal", "line", "--drive-frequency", "6.5"],
            rewrite: None,
            make: None,
        },
        Rig {
            name: "free-decay",
            what: "the pendulum with its drive off, started whirling (5 turns) then swinging down, 500 Hz, 4096 counts, 60 s",
            simulate: &[&[
                "--drive",
                "none",
                "--drive-frequency",
                "1.02",
                "--sample-rate",
                "500",
                "--counts",
                "4096",
                "--x0",
                "0",
                "--v0",
                "20",
                "--duration",
                "60",
                "--time-origin",
                "first-sample",
            ]],
            identify: &["--drive-period", "none"],
            rewrite: None,
            make: None,
        },
        Rig {
            name: "decay-quantised",
            what: "a free decay logged at 1 kHz by a 4096-count encoder whose zero is 0.7 rad off: the swing decays \
                   from 80 counts to a few over 45 s at about 1.3 Hz, with dry friction, bit errors (rate 1e-4) and four \
                   half-turn (2048-count) spikes; near rest the quantised angle toggles between counts",
            simulate: &[DECAY],
            identify: &[
                "--drive-period",
                "none",
                "--repair",
                "--terms",
                "x', sign(x'), cos(x), sin(x)",
            ],
            rewrite: Some(half_turn_spikes),
            make: None,
        },
        Rig {
            name: "logger-slipping-clock",
            what: "the 500 Hz pendulum logged by a program whose clock slips: two runs of 30 000 stamps sit 1 ms \
                   behind the even grid (single steps of 1 and 3 ms at the slips), and two stamps, three apart, are \
                   7 ms early",
            simulate: &[PENDULUM],
            identify: &["--drive-frequency", "1.02", "--repair"],
            rewrite: Some(slipping_clock),
            make: None,
        },
        Rig {
            name: "logger-jitter",
            what: "the 500 Hz pendulum with stamps that jitter by 4 % of the step (Gaussian, seeded), printed to 1 µs",
            simulate: &[PENDULUM],
            identify: &["--drive-frequency", "1.02"],
            rewrite: Some(jittered_stamps),
            make: None,
        },
        Rig {
            name: "vibrometer",
            what: "the two-well Duffing oscillator measured by a laser vibrometer: its velocity only (column v), at \
                   2048 Hz, with white noise of 0.5 % of its range and seeded dropouts (runs of 1 to 3 samples read \
                   as 0, rate 2e-4), integrated to the displacement by `hbid`",
            simulate: &[DUFFING],
            identify: &[
                "--signal",
                "line",
                "--measured",
                "velocity",
                "--angle-col",
                "v",
                "--drive-frequency",
                "6.5",
                "--repair",
            ],
            rewrite: Some(vibrometer),
            make: None,
        },
        Rig {
            name: "overlapping-orbits",
            what: "a noise-free pendulum record (f = 0.95, c = 0.05) of 20 000 samples at 32 per drive period, by the \
                   paper's method: close returns find orbit segments that share most of their samples, so the \
                   bootstrap's blocks must be of segments far enough apart",
            simulate: &[&[
                "--samples",
                "20000",
                "--samples-per-period",
                "32",
                "--f",
                "0.95",
                "--c",
                "0.05",
            ]],
            identify: &["--method", "upo", "--basis", "harmonic:1", "--bootstrap", "200"],
            rewrite: None,
            make: None,
        },
        Rig {
            name: "duffing-drive-harmonics",
            what: "the Duffing rig with a shaker whose drive has 12 % and 14 % second and third harmonics, the terms \
                   selected from a library with the drive's first three harmonics (the default band reaches them)",
            simulate: &[
                DUFFING,
                &["--drive-harmonic", "2:0.12", "--drive-harmonic", "3:0.14"],
            ],
            identify: &[
                "--signal",
                "line",
                "--drive-frequency",
                "6.5",
                "--terms",
                "x', x, x^3, 1, cos(t), sin(t), cos(2t), sin(2t), cos(3t), sin(3t)",
                "--select",
            ],
            rewrite: None,
            make: None,
        },
        Rig {
            name: "inexpressible-drive",
            what: "a pendulum driven by a torque, `x'' + 0.75 x' + 2.25 sin x = 3.375 cos t` (Baker and Gollub's \
                   chaotic pendulum, 25 samples per drive period, 30 000 samples), which the default library of a \
                   base-excited pendulum has no term for: the identification must say that it does not describe the \
                   record. Written by `pendulum-sim` directly (`hbid simulate` has no torque drive); no truth in the \
                   library's terms",
            simulate: &[],
            identify: &[],
            rewrite: None,
            make: Some(torque_pendulum),
        },
    ]
}

/// The record without its header, angle before time, separated by spaces; the velocity dropped.
fn headerless_swapped(text: &str) -> String {
    text.lines()
        .skip(1)
        .filter_map(|line| {
            let cells: Vec<&str> = line.split(',').collect();
            (cells.len() >= 2).then(|| format!("{}   {}\n", cells[1], cells[0]))
        })
        .collect()
}

/// One row of a rig's table: a coefficient, its truth and what was identified.
/// The two-well Duffing oscillator (c = 0.25, a = −1, b = 1, f = 0.3) on a 6.5 Hz shaker at 2048 Hz,
/// stamps to 0.1 ms, displacement to 6 decimals, 120 s.
const DUFFING: &[&str] = &[
    "--system",
    "duffing",
    "--drive-frequency",
    "6.5",
    "--sample-rate",
    "2048",
    "--duration",
    "120",
    "--time-origin",
    "first-sample",
    "--time-decimals",
    "4",
    "--decimals",
    "6",
];

/// A free decay at 1 kHz from 80 counts of a 4096-count encoder, about 1.3 Hz, 45 s.
const DECAY: &[&str] = &[
    "--drive",
    "none",
    "--r",
    "1",
    "--drive-frequency",
    "1.3",
    "--sample-rate",
    "1000",
    "--duration",
    "45",
    "--x0",
    "0.1227",
    "--c",
    "0.012",
    "--friction",
    "1e-4",
    "--counts",
    "4096",
    "--zero-offset",
    "0.7",
    "--bit-errors",
    "1e-4",
    "--seed",
    "5",
    "--time-origin",
    "first-sample",
    "--time-decimals",
    "3",
];

/// The data rows of a CSV record (after its header), split into cells.
fn rows(text: &str) -> (String, Vec<Vec<String>>) {
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header = lines.next().unwrap_or_default().to_owned();
    let rows = lines.map(|l| l.split(',').map(str::to_owned).collect()).collect();
    (header, rows)
}

fn joined(header: &str, rows: &[Vec<String>]) -> String {
    let mut text = format!("{header}\n");
    for row in rows {
        text.push_str(&row.join(","));
        text.push('\n');
    }
    text
}

/// Four samples of the angle moved by half a turn, as an encoder's most significant bit flipping.
fn half_turn_spikes(text: &str) -> String {
    let (header, mut rows) = rows(text);
    for i in [4_321, 17_003, 29_876, 41_234] {
        if let Some(angle) = rows.get(i).and_then(|r| r[1].parse::<f64>().ok()) {
            rows[i][1] = format!("{:?}", circle_signal::wrap(angle + std::f64::consts::PI));
        }
    }
    joined(&header, &rows)
}

/// Stamps to 0.1 ms; one row in 500 dropped and the next stamped 0.6 ms late; the angle of one
/// row in 700 written `NaN` and of one in 900 left empty.
fn late_and_missing(text: &str) -> String {
    let (header, rows) = rows(text);
    let mut out = Vec::with_capacity(rows.len());
    for (i, mut row) in rows.into_iter().enumerate() {
        if i % 500 == 250 {
            continue;
        }
        let Ok(t) = row[0].parse::<f64>() else { continue };
        let late = if i % 500 == 251 { 6e-4 } else { 0.0 };
        row[0] = format!("{:.4}", t + late);
        if i % 700 == 350 {
            row[1] = "NaN".to_owned();
        } else if i % 900 == 450 {
            row[1] = String::new();
        }
        out.push(row);
    }
    joined(&header, &out)
}

/// The stamps of two runs 1 ms behind the grid, and two stamps, three apart, 7 ms early.
fn slipping_clock(text: &str) -> String {
    let (header, mut rows) = rows(text);
    let late = [20_000..50_000, 80_000..110_000];
    for (i, row) in rows.iter_mut().enumerate() {
        let Ok(t) = row[0].parse::<f64>() else { continue };
        let behind = if late.iter().any(|r| r.contains(&i)) {
            1e-3
        } else {
            0.0
        };
        let early = if i == 90_000 || i == 90_003 { 7e-3 } else { 0.0 };
        row[0] = format!("{:.3}", t - behind - early);
    }
    joined(&header, &rows)
}

/// Seeded standard normal numbers.
fn normals(seed: u64, n: usize) -> Vec<f64> {
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    (0..n).map(|_| StandardNormal.sample(&mut rng)).collect()
}

/// The stamps jittered by 4 % of the step (2 ms), printed to 1 µs.
fn jittered_stamps(text: &str) -> String {
    let (header, mut rows) = rows(text);
    let jitter = normals(11, rows.len());
    for (row, e) in rows.iter_mut().zip(jitter) {
        if let Ok(t) = row[0].parse::<f64>() {
            row[0] = format!("{:.6}", t + 0.04 * 2e-3 * e);
        }
    }
    joined(&header, &rows)
}

/// The velocity column only, with white noise of 0.5 % of its range and dropouts: runs of 1 to 3
/// samples read as 0 (rate 2e-4 per sample, seeded).
fn vibrometer(text: &str) -> String {
    let (header, rows) = rows(text);
    let column = header.split(',').position(|c| c == "v").unwrap_or(2);
    let v: Vec<f64> = rows
        .iter()
        .map(|r| r[column].parse().unwrap_or(f64::NAN))
        .collect();
    let range =
        v.iter().copied().fold(f64::NEG_INFINITY, f64::max) - v.iter().copied().fold(f64::INFINITY, f64::min);
    let noise = normals(12, v.len());
    let mut out: Vec<Vec<String>> = rows
        .iter()
        .zip(&v)
        .zip(noise)
        .map(|((r, v), e)| vec![r[0].clone(), format!("{:.6}", v + 0.005 * range * e)])
        .collect();
    let draws = normals(13, v.len());
    let mut i = 0;
    while i < out.len() {
        // A dropout starts where a normal number exceeds 3.54 (probability 2e-4).
        if draws[i] > 3.54 {
            let len = 1 + (draws[(i + 1) % out.len()].abs() * 10.0) as usize % 3;
            for row in out.iter_mut().skip(i).take(len) {
                row[1] = "0".into();
            }
            i += len;
        }
        i += 1;
    }
    joined("t,v", &out)
}

/// Baker and Gollub's chaotic pendulum, driven by a torque, written as `t,theta`.
fn torque_pendulum(path: &Path) -> anyhow::Result<()> {
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
    let config = SimulationConfig::paper().with_samples(30_000)?;
    let trajectory = simulate(&Torque, &config)?;
    let mut text = String::from("t,theta\n");
    for (t, x) in trajectory.t.iter().zip(trajectory.wrapped()) {
        writeln!(text, "{t},{x}")?;
    }
    std::fs::write(path, text)?;
    Ok(())
}

/// One row of a rig's table: a coefficient, its truth and what was identified.
struct Row {
    term: String,
    truth: f64,
    found: f64,
    /// The bootstrap interval, when one was asked for and could be had.
    interval: Option<[f64; 2]>,
}

/// The bootstrap interval of `term` in the JSON of `hbid identify`, if any.
fn found_interval(found: &serde_json::Value, term: &str) -> Option<[f64; 2]> {
    let pair = found["intervals"][term].as_array()?;
    Some([pair.first()?.as_f64()?, pair.get(1)?.as_f64()?])
}

pub fn run(out: &Path, data: &Path) -> anyhow::Result<()> {
    let exe = crate::scale::build_hbid()?;
    std::fs::create_dir_all(data).with_context(|| format!("{}", data.display()))?;
    let mut report = String::new();
    writeln!(
        report,
        "# Real records\n\n\
         Records shaped like real rigs' — any sampling rate, DAQ time stamps (printed to a fixed resolution, \
         jittering, from a clock that slips, with glitches), encoder counts, an encoder zero away from the bottom, \
         bit errors and half-turn spikes, a vibrometer's dropouts, gaps, a logger's dropped rows, an unknown drive frequency, drive \
         harmonics, no drive, and a drive the library cannot express — made by `hbid simulate` (the last one by \
         `pendulum-sim` directly) and each identified by one `hbid identify` command, with no preprocessing. The truth is the simulated equation \
         written in the record's own time unit (seconds), `x'' + Σ c_i g_i = 0`, from `hbid simulate --truth`. \
         Relative errors are to the largest coefficient of the model for the terms whose truth is zero.\n\n\
         Made by `cargo xtask real-records` ({}); the records are written to `{}` and not kept in the repository.\n",
        crate::build_profile(),
        data.display()
    )?;
    for rig in rigs() {
        eprintln!("{}", rig.name);
        let record: PathBuf = data.join(format!("{}.csv", rig.name));
        let truth_path = data.join(format!("{}.truth.json", rig.name));
        let options: Vec<&str> = rig.simulate.concat();
        if let Some(make) = rig.make {
            make(&record).with_context(|| format!("{}: writing the record", rig.name))?;
        } else {
            let mut simulate: Vec<String> = vec!["simulate".into()];
            simulate.extend(options.iter().map(|s| s.to_string()));
            simulate.extend([
                "--truth".into(),
                truth_path.display().to_string(),
                "--out".into(),
                record.display().to_string(),
            ]);
            crate::run_hbid(&exe, &simulate)?;
        }
        if let Some(rewrite) = rig.rewrite {
            let text = std::fs::read_to_string(&record)?;
            std::fs::write(&record, rewrite(&text))?;
        }
        let file_name = format!("{}.csv", rig.name);
        let mut identify: Vec<String> = vec!["identify".into(), record.display().to_string()];
        identify.extend(rig.identify.iter().map(|s| s.to_string()));
        if !rig.identify.contains(&"--bootstrap") {
            identify.extend(["--bootstrap".into(), "0".into()]);
        }
        identify.push("--json".into());
        let started = Instant::now();
        let (stdout, stderr) = crate::run_hbid(&exe, &identify)?;
        let seconds = started.elapsed().as_secs_f64();
        let found: serde_json::Value = serde_json::from_str(&stdout)?;
        writeln!(report, "## {}\n\n{}.\n", rig.name, rig.what)?;
        let simulated = if rig.make.is_some() {
            String::new()
        } else {
            format!("hbid simulate {}\n", options.join(" "))
        };
        writeln!(
            report,
            "```\n{simulated}hbid identify {file_name} {}\n```\n",
            rig.identify.join(" ")
        )?;
        for line in stderr.lines().filter(|l| !l.trim().is_empty()) {
            writeln!(report, "> {}\n", line.trim())?;
        }
        let share = |key: &str| {
            found[key]
                .as_f64()
                .map_or("none".to_owned(), |v| format!("{v:.6}"))
        };
        writeln!(
            report,
            "Share of the response explained: {} in sample, {} on stretches the fit did not see.\n",
            share("explained"),
            share("held_out_explained")
        )?;
        if rig.make.is_some() {
            let coefficients = found["coefficients"].as_object().context("no coefficients")?;
            writeln!(report, "| term | identified |\n| --- | ---: |")?;
            for (term, value) in coefficients {
                writeln!(report, "| `{term}` | {:.6} |", value.as_f64().unwrap_or(f64::NAN))?;
            }
            writeln!(report, "\nIdentification {seconds:.2} s (wall, with reading).\n")?;
            continue;
        }
        let truth: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&truth_path)?)?;
        let coefficients = truth["coefficients"]
            .as_object()
            .context("truth without coefficients")?;
        let rows: Vec<Row> = coefficients
            .iter()
            .filter_map(|(term, value)| {
                let value_found = found["coefficients"][term].as_f64().or_else(|| {
                    // A term that selection dropped is identified as 0.
                    found["selection"]["dropped"]
                        .as_array()?
                        .iter()
                        .any(|d| d["term"].as_str() == Some(term.as_str()))
                        .then_some(0.0)
                })?;
                let interval = found_interval(&found, term);
                Some(Row {
                    term: term.clone(),
                    truth: value.as_f64().unwrap_or(f64::NAN),
                    found: value_found,
                    interval,
                })
            })
            .collect();
        if rows.is_empty() {
            bail!("{}: no coefficient of the truth was identified", rig.name);
        }
        let missing: Vec<String> = coefficients
            .iter()
            .filter(|(term, value)| {
                value.as_f64().is_some_and(|v| v != 0.0) && !rows.iter().any(|r| &r.term == *term)
            })
            .map(|(term, value)| format!("`{term}` ({})", value.as_f64().unwrap_or(f64::NAN)))
            .collect();
        let scale = rows.iter().map(|r| r.truth.abs()).fold(0.0, f64::max);
        let error = |r: &Row| {
            let reference = if r.truth == 0.0 { scale } else { r.truth.abs() };
            (r.found - r.truth).abs() / reference
        };
        let worst = rows.iter().map(error).fold(0.0, f64::max);
        let intervals = rows.iter().any(|r| r.interval.is_some());
        if intervals {
            writeln!(
                report,
                "| term | truth | identified | relative error | bootstrap interval | holds the truth |\n\
                 | --- | ---: | ---: | ---: | ---: | :---: |"
            )?;
        } else {
            writeln!(
                report,
                "| term | truth | identified | relative error |\n| --- | ---: | ---: | ---: |"
            )?;
        }
        for r in &rows {
            write!(
                report,
                "| `{}` | {:.6} | {:.6} | {:.1e} |",
                r.term,
                r.truth,
                r.found,
                error(r)
            )?;
            match (intervals, r.interval) {
                (true, Some([lo, hi])) => writeln!(
                    report,
                    " [{lo:.6}, {hi:.6}] | {} |",
                    if lo <= r.truth && r.truth <= hi {
                        "yes"
                    } else {
                        "no"
                    }
                )?,
                (true, None) => writeln!(report, " | |")?,
                (false, _) => writeln!(report)?,
            }
        }
        if !missing.is_empty() {
            writeln!(
                report,
                "\nTerms of the truth that the model does not have: {}.",
                missing.join(", ")
            )?;
        }
        writeln!(
            report,
            "\nLargest relative error **{worst:.1e}**; identification {seconds:.2} s (wall, with reading).\n"
        )?;
    }
    if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent)?;
    }
    std::fs::write(out, report).with_context(|| format!("{}", out.display()))?;
    eprintln!("wrote {}", out.display());
    Ok(())
}
