//! `cargo xtask real-records`: records shaped like real rigs' (made by `hbid simulate`), each
//! identified by one `hbid identify` command with no preprocessing, the truth beside the result;
//! writes `docs/real-records.md`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anyhow::{Context, bail};

/// One rig: how its record is made and how it is identified.
struct Rig {
    name: &'static str,
    what: &'static str,
    /// `hbid simulate`'s options, in parts joined in order (a rig built on another shares its parts).
    simulate: &'static [&'static [&'static str]],
    identify: &'static [&'static str],
    /// Rewrites the record as another acquisition program would write it (after simulation).
    rewrite: Option<fn(&str) -> String>,
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
            identify: &["--method", "windowed", "--forcing-frequency", "1.02"],
            rewrite: None,
        },
        Rig {
            name: "pendulum-500hz-upo",
            what: "the same record, by the paper's method (close returns)",
            simulate: &[PENDULUM],
            identify: &["--method", "upo", "--forcing-frequency", "1.02"],
            rewrite: None,
        },
        Rig {
            name: "pendulum-unknown-drive",
            what: "the same record, the drive frequency estimated (searched from 0.5 to 2 Hz)",
            simulate: &[PENDULUM],
            identify: &["--method", "windowed", "--forcing-frequency", "auto:0.5..2"],
            rewrite: None,
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
            identify: &["--method", "windowed", "--forcing-frequency", "1.02", "--repair"],
            rewrite: None,
        },
        Rig {
            name: "pendulum-headerless",
            what: "the first record written as a DAQ might: no header, angle first, time second, separated by spaces",
            simulate: &[PENDULUM],
            identify: &["--method", "windowed", "--forcing-frequency", "1.02"],
            rewrite: Some(headerless_swapped),
        },
        Rig {
            name: "duffing-2048hz",
            what: "two-well Duffing oscillator (c = 0.25, a = −1, b = 1, f = 0.3), 2048 Hz, 6.5 Hz shaker (315.08 samples per period), stamps to 0.1 ms, displacement to 6 decimals, 120 s",
            simulate: &[&[
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
            ]],
            identify: &[
                "--signal",
                "line",
                "--method",
                "windowed",
                "--forcing-frequency",
                "6.5",
            ],
            rewrite: None,
        },
        Rig {
            name: "free-decay",
            what: "the pendulum with its drive off, started whirling (5 turns) then swinging down, 500 Hz, 4096 counts, 60 s",
            simulate: &[&[
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
            ]],
            identify: &["--method", "windowed", "--forcing", "none"],
            rewrite: None,
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
struct Row {
    term: String,
    truth: f64,
    found: f64,
}

/// Runs `hbid` with `args`, failing with its stderr.
fn hbid(exe: &Path, args: &[String]) -> anyhow::Result<(String, String)> {
    let out = Command::new(exe)
        .arg("--quiet")
        .args(args)
        .output()
        .with_context(|| format!("running {}", exe.display()))?;
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    if !out.status.success() {
        bail!("hbid {}: {stderr}", args.join(" "));
    }
    Ok((String::from_utf8_lossy(&out.stdout).into_owned(), stderr))
}

pub fn run(out: &Path, data: &Path) -> anyhow::Result<()> {
    let exe = crate::scale::build_hbid()?;
    std::fs::create_dir_all(data).with_context(|| format!("{}", data.display()))?;
    let mut report = String::new();
    writeln!(
        report,
        "# Real records\n\n\
         Records shaped like real rigs' — any sampling rate, DAQ time stamps, encoder counts, an encoder zero away \
         from the bottom, bit errors, gaps, an unknown drive frequency, no drive — made by `hbid simulate` and each \
         identified by one `hbid identify` command, with no preprocessing. The truth is the simulated equation \
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
        let mut simulate: Vec<String> = vec!["simulate".into()];
        let options: Vec<&str> = rig.simulate.concat();
        simulate.extend(options.iter().map(|s| s.to_string()));
        simulate.extend([
            "--truth".into(),
            truth_path.display().to_string(),
            "--out".into(),
            record.display().to_string(),
        ]);
        hbid(&exe, &simulate)?;
        if let Some(rewrite) = rig.rewrite {
            let text = std::fs::read_to_string(&record)?;
            std::fs::write(&record, rewrite(&text))?;
        }
        let truth: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&truth_path)?)?;
        let file_name = format!("{}.csv", rig.name);
        let mut identify: Vec<String> = vec!["identify".into(), record.display().to_string()];
        identify.extend(rig.identify.iter().map(|s| s.to_string()));
        identify.extend(["--bootstrap".into(), "0".into(), "--json".into()]);
        let started = Instant::now();
        let (stdout, stderr) = hbid(&exe, &identify)?;
        let seconds = started.elapsed().as_secs_f64();
        let found: serde_json::Value = serde_json::from_str(&stdout)?;
        let coefficients = truth["coefficients"]
            .as_object()
            .context("truth without coefficients")?;
        let rows: Vec<Row> = coefficients
            .iter()
            .filter_map(|(term, value)| {
                let found = found["coefficients"][term].as_f64()?;
                Some(Row {
                    term: term.clone(),
                    truth: value.as_f64().unwrap_or(f64::NAN),
                    found,
                })
            })
            .collect();
        if rows.is_empty() {
            bail!("{}: no coefficient of the truth was identified", rig.name);
        }
        let scale = rows.iter().map(|r| r.truth.abs()).fold(0.0, f64::max);
        let error = |r: &Row| {
            let reference = if r.truth == 0.0 { scale } else { r.truth.abs() };
            (r.found - r.truth).abs() / reference
        };
        let worst = rows.iter().map(error).fold(0.0, f64::max);
        writeln!(report, "## {}\n\n{}.\n", rig.name, rig.what)?;
        writeln!(
            report,
            "```\nhbid simulate {}\nhbid identify {file_name} {}\n```\n",
            options.join(" "),
            rig.identify.join(" ")
        )?;
        for line in stderr.lines().filter(|l| !l.trim().is_empty()) {
            writeln!(report, "> {}\n", line.trim())?;
        }
        writeln!(
            report,
            "| term | truth | identified | relative error |\n| --- | ---: | ---: | ---: |"
        )?;
        for r in &rows {
            writeln!(
                report,
                "| `{}` | {:.6} | {:.6} | {:.1e} |",
                r.term,
                r.truth,
                r.found,
                error(r)
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
