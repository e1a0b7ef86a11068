//! `cargo xtask weak-sindy`: model selection side by side with pysindy's weak-form SINDy on the
//! same forced records (a rig pendulum with Coulomb friction, quadratic drag and a second drive
//! harmonic, through a 4096-count encoder) at angle noise 0, 0.01, 0.05 and 0.1 rad, from the
//! same library of 18 candidate terms: `hbid identify --select` against `xtask/peers/weak_sindy.py`
//! at a range of STLSQ thresholds. Writes its section into `docs/accuracy.md` between markers
//! (`cargo xtask accuracy` keeps it).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anyhow::{Context, bail};

/// The markers of the section in `docs/accuracy.md`.
pub const START: &str = "<!-- weak-sindy: made by cargo xtask weak-sindy -->";
/// The end marker.
pub const END: &str = "<!-- weak-sindy: end -->";

/// The candidate library, as both tools are given it.
const LIBRARY: &[&str] = &[
    "x'",
    "sign(x')",
    "x'*|x'|",
    "x'^3",
    "cos(x)",
    "sin(x)",
    "cos(t)*cos(x)",
    "cos(t)*sin(x)",
    "sin(t)*cos(x)",
    "sin(t)*sin(x)",
    "cos(2t)*cos(x)",
    "cos(2t)*sin(x)",
    "sin(2t)*cos(x)",
    "sin(2t)*sin(x)",
    "cos(3t)*cos(x)",
    "cos(3t)*sin(x)",
    "sin(3t)*cos(x)",
    "sin(3t)*sin(x)",
];

/// The record: the rig's options of `hbid simulate`.
const RIG: &[&str] = &[
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
    "--seed",
    "1",
];

const NOISE: [f64; 4] = [0.0, 0.01, 0.05, 0.1];
/// STLSQ thresholds tried for the peer; pysindy's default is 0.1.
const THRESHOLDS: [f64; 6] = [0.002, 0.005, 0.01, 0.02, 0.05, 0.1];

/// A term's name in a Markdown table cell (`|` escaped).
fn cell(name: &str) -> String {
    name.replace('|', "\\|")
}

/// One tool's answer on one record.
struct Found {
    tool: String,
    /// Every candidate's coefficient (0 when dropped).
    terms: Vec<(String, f64)>,
    seconds: f64,
}

impl Found {
    fn kept(&self) -> impl Iterator<Item = &(String, f64)> {
        self.terms.iter().filter(|(_, c)| *c != 0.0)
    }
}

/// How an answer compares with the truth.
struct Score {
    true_kept: usize,
    false_kept: Vec<String>,
    missed: Vec<String>,
    /// The largest relative error of the true terms kept, and which.
    worst: (f64, String),
}

fn score(found: &Found, truth: &[(String, f64)]) -> Score {
    let is_true = |name: &str| truth.iter().any(|(n, v)| n == name && *v != 0.0);
    let false_kept: Vec<String> = found
        .kept()
        .filter(|(n, _)| !is_true(n))
        .map(|(n, _)| n.clone())
        .collect();
    let mut missed = Vec::new();
    let mut worst = (0.0, String::new());
    let mut true_kept = 0;
    for (name, value) in truth.iter().filter(|(_, v)| *v != 0.0) {
        match found.terms.iter().find(|(n, c)| n == name && *c != 0.0) {
            Some((_, c)) => {
                true_kept += 1;
                let e = ((c - value) / value).abs();
                if e > worst.0 {
                    worst = (e, name.clone());
                }
            }
            None => missed.push(name.clone()),
        }
    }
    Score {
        true_kept,
        false_kept,
        missed,
        worst,
    }
}

fn ours(exe: &Path, record: &Path) -> anyhow::Result<Found> {
    let args: Vec<String> = [
        "identify",
        &record.display().to_string(),
        "--method",
        "windowed",
        "--terms",
        &LIBRARY.join(", "),
        "--select",
        "--bootstrap",
        "0",
        "--json",
    ]
    .map(String::from)
    .to_vec();
    let started = Instant::now();
    let json: serde_json::Value = serde_json::from_str(&crate::run_hbid(exe, &args)?.0)?;
    let seconds = started.elapsed().as_secs_f64();
    let terms = LIBRARY
        .iter()
        .map(|&name| {
            (
                name.to_owned(),
                json["coefficients"][name].as_f64().unwrap_or(0.0),
            )
        })
        .collect();
    Ok(Found {
        tool: "hbid --select".to_owned(),
        terms,
        seconds,
    })
}

fn peer(python: &str, script: &Path, record: &Path, threshold: f64, out: &Path) -> anyhow::Result<Found> {
    let started = Instant::now();
    let status = Command::new(python)
        .arg(script)
        .args([
            "--record",
            &record.display().to_string(),
            "--circle",
            "--drive-frequency",
            "1",
        ])
        .args([
            "--terms",
            &LIBRARY.join(";"),
            "--threshold",
            &threshold.to_string(),
        ])
        .args(["--out", &out.display().to_string()])
        .status()
        .with_context(|| format!("running {python} {} (is pysindy installed?)", script.display()))?;
    if !status.success() {
        bail!("{} failed on {}", script.display(), record.display());
    }
    let seconds = started.elapsed().as_secs_f64();
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out)?)?;
    let terms = LIBRARY
        .iter()
        .map(|&name| (name.to_owned(), json["terms"][name].as_f64().unwrap_or(0.0)))
        .collect();
    Ok(Found {
        tool: format!("weak SINDy, λ = {threshold}"),
        terms,
        seconds,
    })
}

/// Writes `section` between the markers of `path` (appended if they are absent).
pub fn splice(path: &Path, section: &str) -> anyhow::Result<()> {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let block = format!("{START}\n{section}{END}\n");
    let new = match (text.find(START), text.find(END)) {
        (Some(a), Some(b)) if b > a => format!(
            "{}{block}{}",
            &text[..a],
            &text[b + END.len()..].trim_start_matches('\n')
        ),
        _ => format!("{}\n{block}", text.trim_end()),
    };
    std::fs::write(path, new).with_context(|| format!("cannot write {}", path.display()))
}

/// The section between the markers of `text`, markers included, if any.
pub fn kept_section(text: &str) -> Option<&str> {
    let a = text.find(START)?;
    let b = text.find(END)?;
    (b > a).then(|| &text[a..b + END.len()])
}

pub fn run(out: &Path, data: &Path, python: &str) -> anyhow::Result<()> {
    let exe = crate::scale::build_hbid()?;
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("peers/weak_sindy.py");
    std::fs::create_dir_all(data).with_context(|| format!("{}", data.display()))?;
    let version = Command::new(python)
        .args([
            "-c",
            "import pysindy, numpy; print(pysindy.__version__, numpy.__version__)",
        ])
        .output()
        .with_context(|| format!("running {python}"))?;
    if !version.status.success() {
        bail!(
            "{python} cannot import pysindy: install it with `{python} -m pip install -r xtask/peers/requirements.txt`, \
             or name another interpreter with --python"
        );
    }
    let version = String::from_utf8_lossy(&version.stdout).trim().to_owned();
    let mut section = String::new();
    writeln!(section, "## Model selection beside weak-form SINDy\n")?;
    writeln!(
        section,
        "Made by `cargo xtask weak-sindy` ({}; pysindy and numpy {version}). A rig pendulum \
         (`hbid simulate {}` and `--noise σ`, angle noise σ in rad after the encoder) with Coulomb friction, quadratic \
         drag and a 10 % second drive harmonic: `x'' + 0.03 x' + 0.05 sign(x') + 0.05 x'|x'| + 1.44 sin x − 1.52 \
         (sin t + 0.1 sin 2t) cos x = 0`, 600 forcing periods at 50 samples per period. Both tools choose from the \
         same {} candidates: `{}`.\n",
        crate::build_profile(),
        RIG.join(" "),
        LIBRARY.len(),
        LIBRARY.join(", ")
    )?;
    writeln!(
        section,
        "Ours: `hbid identify --method windowed --terms LIBRARY --select` (cross-validated backward elimination, \
         the kept terms refitted). The peer: `xtask/peers/weak_sindy.py`, pysindy's `WeakPDELibrary` (subdomains \
         of 3 forcing periods, one per period) with STLSQ on exactly these candidate columns, the velocity by \
         pysindy's smoothed finite differences, the drive as known columns. STLSQ needs a threshold λ: it is run at \
         {} and its best λ is shown, chosen knowing the truth (fewest wrong terms, then the smallest worst error) — \
         the peer at its best, a choice a user without the truth cannot make. \"worst error\" is the largest relative \
         error of the true terms kept.\n",
        THRESHOLDS.map(|t| t.to_string()).join(", ")
    )?;
    writeln!(
        section,
        "| noise σ (rad) | tool | true terms kept (of 6) | false terms kept | worst error (term) | seconds |"
    )?;
    writeln!(section, "| --- | --- | --- | --- | --- | --- |")?;
    let mut details = String::new();
    for sigma in NOISE {
        eprintln!("noise {sigma}");
        let record = data.join(format!("rig-noise-{sigma}.csv"));
        let truth_path = data.join(format!("rig-noise-{sigma}.truth.json"));
        let mut args: Vec<String> = vec!["simulate".into()];
        args.extend(RIG.iter().map(|s| s.to_string()));
        args.extend(["--noise".into(), sigma.to_string()]);
        args.extend(["--truth".into(), truth_path.display().to_string()]);
        args.extend(["--out".into(), record.display().to_string()]);
        crate::run_hbid(&exe, &args)?;
        let truth: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&truth_path)?)?;
        let truth: Vec<(String, f64)> = LIBRARY
            .iter()
            .map(|&n| (n.to_owned(), truth["coefficients"][n].as_f64().unwrap_or(0.0)))
            .collect();
        let mine = ours(&exe, &record)?;
        let mut best: Option<(Found, Score)> = None;
        let mut default = None;
        for threshold in THRESHOLDS {
            let found = peer(python, &script, &record, threshold, &data.join("sindy.json"))?;
            let s = score(&found, &truth);
            let wrong = s.false_kept.len() + s.missed.len();
            let better = best.as_ref().is_none_or(|(_, b)| {
                let bw = b.false_kept.len() + b.missed.len();
                wrong < bw || (wrong == bw && s.worst.0 < b.worst.0)
            });
            if threshold == 0.1 {
                default = Some((found.tool.clone(), score(&found, &truth), found.seconds));
            }
            if better {
                best = Some((found, s));
            }
        }
        let (best, best_score) = best.context("no threshold")?;
        let my_score = score(&mine, &truth);
        let mut row = |tool: &str, s: &Score, seconds: f64| -> anyhow::Result<()> {
            let mut false_kept = s
                .false_kept
                .iter()
                .map(|n| cell(n))
                .collect::<Vec<_>>()
                .join(", ");
            if false_kept.is_empty() {
                false_kept = "none".into();
            }
            let missed = if s.missed.is_empty() {
                String::new()
            } else {
                format!(
                    " (missed {})",
                    s.missed.iter().map(|n| cell(n)).collect::<Vec<_>>().join(", ")
                )
            };
            writeln!(
                section,
                "| {sigma} | {tool} | {}{missed} | {} {false_kept} | {:.1e} (`{}`) | {seconds:.1} |",
                s.true_kept,
                s.false_kept.len(),
                s.worst.0,
                cell(&s.worst.1)
            )?;
            Ok(())
        };
        row(&mine.tool, &my_score, mine.seconds)?;
        row(&format!("{} (best)", best.tool), &best_score, best.seconds)?;
        if let Some((tool, s, seconds)) = default
            && tool != best.tool
        {
            row(&format!("{tool} (pysindy's default)"), &s, seconds)?;
        }
        writeln!(details, "\nσ = {sigma} rad:\n")?;
        writeln!(details, "| term | truth | hbid --select | {} |", best.tool)?;
        writeln!(details, "| --- | --- | --- | --- |")?;
        for ((name, value), ((_, a), (_, b))) in truth.iter().zip(mine.terms.iter().zip(&best.terms)) {
            if *value != 0.0 || *a != 0.0 || *b != 0.0 {
                writeln!(details, "| `{}` | {value:.6} | {a:.6} | {b:.6} |", cell(name))?;
            }
        }
    }
    writeln!(
        section,
        "\nThe coefficients (0: dropped; terms dropped by both and false in the truth are not shown):"
    )?;
    section.push_str(&details);
    section.push('\n');
    splice(out, &section)?;
    eprintln!("section written to {}", out.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splice_replaces_or_appends_the_section() {
        let dir = std::env::temp_dir().join(format!("xtask-splice-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("page.md");
        std::fs::write(&path, "# Page\n\ntext\n").unwrap();
        splice(&path, "one\n").unwrap();
        let once = std::fs::read_to_string(&path).unwrap();
        assert!(once.starts_with("# Page\n\ntext\n") && once.contains(&format!("{START}\none\n{END}")));
        splice(&path, "two\n").unwrap();
        let twice = std::fs::read_to_string(&path).unwrap();
        assert!(!twice.contains("one\n") && twice.contains(&format!("{START}\ntwo\n{END}")));
        assert_eq!(twice.matches(START).count(), 1);
        assert_eq!(kept_section(&twice), Some(&format!("{START}\ntwo\n{END}")[..]));
    }

    #[test]
    fn scores_count_true_false_and_missed_terms() {
        let truth = vec![
            ("a".to_owned(), 1.0),
            ("b".to_owned(), 0.0),
            ("c".to_owned(), 2.0),
        ];
        let found = Found {
            tool: String::new(),
            terms: vec![
                ("a".to_owned(), 1.1),
                ("b".to_owned(), 0.3),
                ("c".to_owned(), 0.0),
            ],
            seconds: 0.0,
        };
        let s = score(&found, &truth);
        assert_eq!(
            (s.true_kept, s.false_kept.clone(), s.missed.clone()),
            (1, vec!["b".to_owned()], vec!["c".to_owned()])
        );
        assert!((s.worst.0 - 0.1).abs() < 1e-12 && s.worst.1 == "a");
    }
}
