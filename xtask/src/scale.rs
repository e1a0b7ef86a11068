//! `cargo xtask scale`: `hbid identify` end to end on records of growing length, with wall time,
//! peak memory (`/usr/bin/time -v`) and the slope of the cost against the record length.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, bail};

/// One timed run of `hbid identify`.
#[derive(Debug, Clone)]
struct Run {
    wall: f64,
    peak_mib: f64,
    stages: Vec<(String, f64)>,
    /// Largest |identified − true| over the seven coefficients.
    error: f64,
    /// The coefficients, in the truth's order.
    coefficients: Vec<f64>,
}

/// One timed run of `hbid simulate`.
#[derive(Debug, Clone, Copy)]
struct Made {
    samples: usize,
    wall: f64,
    peak_mib: f64,
    bytes: u64,
}

/// Runs the study and writes the report to `out`: `hbid identify` on records of `sizes` samples
/// (both methods, the record read whole below 256 MiB), the windowed method on records of
/// `stream_sizes` read in chunks (`--stream`), and `hbid simulate` making those and records of
/// `simulate_sizes` samples.
pub fn run(
    out: &Path,
    data: &Path,
    sizes: &[usize],
    repeats: usize,
    simulate_sizes: &[usize],
    stream_sizes: &[usize],
) -> anyhow::Result<()> {
    if sizes.is_empty() || repeats == 0 {
        bail!("give at least one size and one repeat");
    }
    let time = Path::new("/usr/bin/time");
    if !time.exists() {
        bail!("/usr/bin/time (GNU time, Debian package `time`) is needed for the peak memory");
    }
    let hbid = build_hbid()?;
    std::fs::create_dir_all(data).with_context(|| format!("{}", data.display()))?;
    let methods = ["windowed", "upo"];
    let mut rows: Vec<(usize, &str, Run)> = Vec::new();
    let mut made = Vec::new();
    for &n in sizes {
        let record = data.join(format!("pendulum_{n}.npy"));
        made.push(simulate(time, &hbid, n, &record)?);
        for method in methods {
            let mut runs: Vec<Run> = (0..repeats)
                .map(|_| identify(time, &hbid, &record, method, &["--no-stream"]))
                .collect::<anyhow::Result<_>>()?;
            runs.sort_by(|a, b| a.wall.total_cmp(&b.wall));
            let median = runs[runs.len() / 2].clone();
            eprintln!(
                "{n:>10} samples  {method:<8} {:>7.3} s  {:>6.0} MiB",
                median.wall, median.peak_mib
            );
            rows.push((n, method, median));
        }
    }
    let mut streamed: Vec<(usize, Run)> = Vec::new();
    for &n in stream_sizes {
        let kept = sizes.contains(&n);
        let record = if kept {
            data.join(format!("pendulum_{n}.npy"))
        } else {
            let record = data.join(format!("pendulum_{n}_simulated.npy"));
            made.push(simulate(time, &hbid, n, &record)?);
            record
        };
        let runs: anyhow::Result<Vec<Run>> = (0..repeats)
            .map(|_| identify(time, &hbid, &record, "windowed", &["--stream"]))
            .collect();
        if !kept {
            std::fs::remove_file(&record).ok();
        }
        let mut runs = runs?;
        runs.sort_by(|a, b| a.wall.total_cmp(&b.wall));
        let median = runs[runs.len() / 2].clone();
        eprintln!(
            "{n:>10} samples  streamed {:>7.3} s  {:>6.0} MiB",
            median.wall, median.peak_mib
        );
        streamed.push((n, median));
    }
    for &n in simulate_sizes
        .iter()
        .filter(|n| !stream_sizes.contains(n) || sizes.contains(n))
    {
        let record = data.join(format!("pendulum_{n}_simulated.npy"));
        let result = simulate(time, &hbid, n, &record);
        std::fs::remove_file(&record).ok();
        made.push(result?);
    }
    made.sort_by_key(|m| m.samples);
    made.dedup_by_key(|m| m.samples);
    let mut report = render(&rows, sizes, repeats)?;
    render_streamed(&mut report, &rows, &streamed, repeats)?;
    render_simulate(&mut report, &made)?;
    if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent)?;
    }
    std::fs::write(out, report).with_context(|| format!("{}", out.display()))?;
    eprintln!("wrote {}", out.display());
    Ok(())
}

/// Builds the release `hbid` (whatever profile this xtask was built in: `cargo xtask` uses the
/// test profile) and returns its path, `<target>/release/hbid`.
pub(crate) fn build_hbid() -> anyhow::Result<PathBuf> {
    let status = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
        .args(["build", "--release", "-p", "hbid"])
        .status()
        .context("cargo build")?;
    if !status.success() {
        bail!("cargo build --release -p hbid failed");
    }
    let exe = std::env::current_exe()?;
    let target = exe
        .parent()
        .and_then(Path::parent)
        .context("xtask is not in a cargo target folder")?;
    let hbid = target
        .join("release")
        .join(format!("hbid{}", std::env::consts::EXE_SUFFIX));
    if !hbid.exists() {
        bail!("expected the release hbid at {}", hbid.display());
    }
    Ok(hbid)
}

/// `hbid simulate` of `n` samples of the paper's pendulum into `record`, under GNU time.
fn simulate(time: &Path, hbid: &Path, n: usize, record: &Path) -> anyhow::Result<Made> {
    eprintln!("simulating {n} samples -> {}", record.display());
    let out = Command::new(time)
        .arg("-v")
        .arg(hbid)
        .args(["simulate", "--quiet", "--samples", &n.to_string(), "--out"])
        .arg(record)
        .output()
        .context("running hbid simulate")?;
    let err = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() {
        bail!("hbid simulate of {n} samples failed:\n{err}");
    }
    let (wall, peak_mib) = wall_and_peak(&err)?;
    let bytes = std::fs::metadata(record)
        .with_context(|| format!("{}", record.display()))?
        .len();
    Ok(Made {
        samples: n,
        wall,
        peak_mib,
        bytes,
    })
}

/// The wall time (s) and the peak resident memory (MiB) in what `time -v` printed.
fn wall_and_peak(err: &str) -> anyhow::Result<(f64, f64)> {
    let field = |name: &str| -> anyhow::Result<String> {
        err.lines()
            .find_map(|l| l.trim().strip_prefix(name).map(|v| v.trim().to_owned()))
            .with_context(|| format!("no '{name}' in the output of time -v"))
    };
    let wall = parse_clock(&field("Elapsed (wall clock) time (h:mm:ss or m:ss):")?)?;
    let peak_kib: f64 = field("Maximum resident set size (kbytes):")?.parse()?;
    Ok((wall, peak_kib / 1024.0))
}

/// The section on `hbid simulate`.
fn render_simulate(s: &mut String, made: &[Made]) -> anyhow::Result<()> {
    writeln!(s, "\n## `hbid simulate`\n")?;
    writeln!(
        s,
        "The records above, and longer ones only simulated (removed after), each one run of \
         `hbid simulate --samples N --out FILE.npy` under `/usr/bin/time -v`. The record is \
         written as it is integrated, so the memory does not grow with it.\n"
    )?;
    writeln!(
        s,
        "| samples | wall time | per 10^6 samples | peak memory | file |\n| ---: | ---: | ---: | ---: | ---: |"
    )?;
    for m in made {
        writeln!(
            s,
            "| {} | {:.2} s | {:.3} s | {:.0} MiB | {:.0} MiB |",
            m.samples,
            m.wall,
            m.wall / (m.samples as f64 / 1e6),
            m.peak_mib,
            m.bytes as f64 / (1024.0 * 1024.0)
        )?;
    }
    Ok(())
}

/// `hbid identify` with its defaults (1000 bootstrap resamples included) under GNU time.
fn identify(time: &Path, hbid: &Path, record: &Path, method: &str, extra: &[&str]) -> anyhow::Result<Run> {
    let out = Command::new(time)
        .arg("-v")
        .arg(hbid)
        .args(["identify", "--quiet", "--timings", "--json", "--method", method])
        .args(extra)
        .arg(record)
        .output()
        .context("running hbid identify")?;
    let err = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() {
        bail!(
            "hbid identify --method {method} {} failed:\n{err}",
            record.display()
        );
    }
    let (wall, peak_mib) = wall_and_peak(&err)?;
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).context("hbid identify --json")?;
    let truth = crate::identification::truth()?;
    let coefficients = truth
        .coefficients()
        .iter()
        .map(|t| {
            json["coefficients"][&t.name]
                .as_f64()
                .with_context(|| format!("no coefficient {}", t.name))
        })
        .collect::<anyhow::Result<Vec<f64>>>()?;
    let error = truth
        .coefficients()
        .iter()
        .zip(&coefficients)
        .fold(0.0_f64, |m, (t, v)| m.max((v - t.value).abs()));
    let stages = err
        .lines()
        .filter_map(|l| {
            let mut it = l.split_whitespace();
            let (name, secs, unit) = (it.next()?, it.next()?, it.next()?);
            (unit == "s" && it.next().is_none())
                .then(|| secs.parse().ok().map(|s| (name.to_owned(), s)))
                .flatten()
        })
        .collect();
    Ok(Run {
        wall,
        peak_mib,
        stages,
        error,
        coefficients,
    })
}

/// The records read in chunks: time, memory, error, and against the same record read whole.
fn render_streamed(
    s: &mut String,
    rows: &[(usize, &str, Run)],
    streamed: &[(usize, Run)],
    repeats: usize,
) -> anyhow::Result<()> {
    if streamed.is_empty() {
        return Ok(());
    }
    writeln!(s, "\n## Read in chunks (`--stream`)\n")?;
    writeln!(
        s,
        "The windowed method with the record's file read {} rows at a time (`hbid identify FILE \
         --stream`, the default for files of 256 MiB or more: 10^7 samples of these records are 229 \
         MiB), each chunk's windows assembled and compressed while the next chunk is read and \
         conditioned (`hb_pipeline::stream`); the median of {repeats} runs. The last column is the largest \
         difference of a coefficient from the same record read whole (above), over the largest \
         coefficient.\n",
        hb_pipeline::stream::CHUNK_ROWS
    )?;
    writeln!(
        s,
        "| samples | wall time | per 10^6 samples | peak memory | largest coefficient error | against the record read whole |\n| ---: | ---: | ---: | ---: | ---: | ---: |"
    )?;
    for (n, run) in streamed {
        let whole = rows.iter().find(|r| r.0 == *n && r.1 == "windowed").map(|r| &r.2);
        let against = whole.map_or("—".to_owned(), |w| {
            let scale = w.coefficients.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            let d = w
                .coefficients
                .iter()
                .zip(&run.coefficients)
                .fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
            format!("{:.1e}", d / scale)
        });
        writeln!(
            s,
            "| {n} | {:.2} s | {:.3} s | {:.0} MiB | {:.1e} | {against} |",
            run.wall,
            run.wall / (*n as f64 / 1e6),
            run.peak_mib,
            run.error
        )?;
    }
    if streamed.len() >= 2 {
        let lx: Vec<f64> = streamed.iter().map(|(n, _)| (*n as f64).ln()).collect();
        let ly: Vec<f64> = streamed.iter().map(|(_, r)| r.wall.ln()).collect();
        let (_, slope) = line_fit(&lx, &ly);
        writeln!(
            s,
            "\nThe slope of log(time) against log(samples) over these sizes: {slope:.3}. The peak memory is \
             two chunks' columns and windows' rows, at most 65 536 compressed blocks of the \
             regression, and what glibc's heap keeps of the chunks' freed buffers, which grows from \
             10^7 to 10^8 samples (`docs/performance.md`; 10^9 was not run)."
        )?;
    }
    Ok(())
}

/// `m:ss.ss` or `h:mm:ss` as seconds.
fn parse_clock(text: &str) -> anyhow::Result<f64> {
    text.split(':')
        .try_fold(0.0, |acc, part| Ok(acc * 60.0 + part.parse::<f64>()?))
        .map_err(|e: std::num::ParseFloatError| anyhow::anyhow!("clock '{text}': {e}"))
}

/// Least-squares line `y = a + b x`.
fn line_fit(x: &[f64], y: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    let b = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    (my - b * mx, b)
}

fn render(rows: &[(usize, &str, Run)], sizes: &[usize], repeats: usize) -> anyhow::Result<String> {
    let mut s = String::new();
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    writeln!(s, "# Scale: `hbid identify` on long records\n")?;
    writeln!(
        s,
        "Written by `cargo xtask scale` (records: the paper's pendulum from `hbid simulate`, \
         25 samples per forcing period, saved as `.npy` f8 with columns t, theta, omega). Each \
         run is `hbid identify FILE --method M --no-stream` (the record read whole) with its \
         defaults, 1000 bootstrap resamples included, under `/usr/bin/time -v`; the median wall time of {repeats} runs and its peak \
         resident memory. {cores} cores; load average at the end: {}.\n",
        load.split_whitespace().take(3).collect::<Vec<_>>().join(" ")
    )?;
    writeln!(
        s,
        "| samples | method | wall time | per 10^6 samples | peak memory | largest coefficient error |\n| ---: | --- | ---: | ---: | ---: | ---: |"
    )?;
    for (n, method, run) in rows {
        writeln!(
            s,
            "| {n} | {method} | {:.3} s | {:.3} s | {:.0} MiB | {:.1e} |",
            run.wall,
            run.wall / (*n as f64 / 1e6),
            run.peak_mib,
            run.error
        )?;
    }
    writeln!(
        s,
        "\nThe error is the largest |identified − true| of the seven coefficients of the harmonic basis \
         K = 1 (noise-free records). The windowed method's stays at its quadrature floor whatever the \
         length; the paper's method (close returns at e = 3 %) keeps a bias from the approximate \
         closure of its orbits, which more data does not remove (its bootstrap intervals then do not cover the truth either). GNU time reports wall \
         time in hundredths of a second."
    )?;
    writeln!(s, "\n## Cost against record length\n")?;
    writeln!(
        s,
        "Fits over every size: the slope of log(time) against log(samples) (1 is linear), and the \
         line time = a + b · samples (b in seconds per 10^6 samples; a is the fixed cost: \
         process start, thread pool, plans).\n"
    )?;
    writeln!(
        s,
        "| method | log-log slope | b (s per 10^6) | a (s) | peak memory per 10^6 samples (largest) |\n| --- | ---: | ---: | ---: | ---: |"
    )?;
    for method in ["windowed", "upo"] {
        let pts: Vec<(f64, &Run)> = rows
            .iter()
            .filter(|r| r.1 == method)
            .map(|r| (r.0 as f64, &r.2))
            .collect();
        if pts.len() < 2 {
            continue;
        }
        let lx: Vec<f64> = pts.iter().map(|p| p.0.ln()).collect();
        let ly: Vec<f64> = pts.iter().map(|p| p.1.wall.ln()).collect();
        let (_, slope) = line_fit(&lx, &ly);
        let x: Vec<f64> = pts.iter().map(|p| p.0 / 1e6).collect();
        let y: Vec<f64> = pts.iter().map(|p| p.1.wall).collect();
        let (a, b) = line_fit(&x, &y);
        let (n_max, big) = pts.last().map(|p| (p.0, p.1)).context("no runs")?;
        writeln!(
            s,
            "| {method} | {slope:.3} | {b:.3} | {a:.3} | {:.1} MiB |",
            big.peak_mib / (n_max / 1e6)
        )?;
    }
    let largest = sizes.iter().copied().max().unwrap_or(0);
    writeln!(s, "\n## Stages at {largest} samples (`--timings`)\n")?;
    writeln!(s, "| stage | windowed | upo |\n| --- | ---: | ---: |")?;
    let stages_of = |method: &str| -> Vec<(String, f64)> {
        rows.iter()
            .find(|r| r.0 == largest && r.1 == method)
            .map(|r| r.2.stages.clone())
            .unwrap_or_default()
    };
    let (w, u) = (stages_of("windowed"), stages_of("upo"));
    let mut names: Vec<&String> = u.iter().map(|(n, _)| n).collect();
    for (n, _) in &w {
        if !names.contains(&n) {
            names.insert(names.len().saturating_sub(1), n);
        }
    }
    for name in names {
        let get = |v: &[(String, f64)]| {
            v.iter()
                .find(|(n, _)| n == name)
                .map_or("—".to_owned(), |(_, t)| format!("{t:.3} s"))
        };
        writeln!(s, "| {name} | {} | {} |", get(&w), get(&u))?;
    }
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clocks_and_lines() {
        assert_eq!(parse_clock("0:03.52").unwrap(), 3.52);
        assert_eq!(parse_clock("1:02:03").unwrap(), 3723.0);
        assert!(parse_clock("x:1").is_err());
        let (a, b) = line_fit(&[1.0, 2.0, 3.0], &[3.0, 5.0, 7.0]);
        assert!((a - 1.0).abs() < 1e-12 && (b - 2.0).abs() < 1e-12);
    }
}
