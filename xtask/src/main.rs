//! Project automation. `cargo xtask reproduce` runs the paper (Liang & Feeny, "Parametric
//! Identification of a Base-Excited Single Pendulum") end to end from nothing and writes a report
//! with its figures beside the paper's numbers.
#![allow(clippy::print_stderr, clippy::print_stdout)]

mod accuracy;
mod benchmarks;
mod dfki;
mod double_pendulum;
mod identification;
mod real_records;
mod reproduce;
mod scale;
mod timings;
mod weak_sindy;

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};

use clap::{Parser, Subcommand};

#[derive(Debug, Parser)]
#[command(name = "xtask", about = "Project automation")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run the paper end to end: simulate, embed, extract orbits, identify, validate; write the report.
    Reproduce {
        /// Folder of the report (created if missing).
        #[arg(long, default_value = "docs/reproduction")]
        out: PathBuf,
        /// A smaller run (shorter record and validation) that checks the pipeline in seconds.
        #[arg(long)]
        quick: bool,
    },
    /// Noise and record-length studies of both identification methods, and the coverage of the
    /// bootstrap intervals; writes the report with its figures (in a folder named after it).
    Accuracy {
        /// The report (its figures go to the folder of the same name without extension).
        #[arg(long, default_value = "docs/accuracy.md")]
        out: PathBuf,
        /// Shorter records and fewer seeds: checks the studies in seconds.
        #[arg(long)]
        quick: bool,
    },
    /// `hbid identify` (both methods, defaults) on records of growing length: wall time, peak
    /// memory and the cost slope; writes a Markdown report.
    Scale {
        /// The report.
        #[arg(long, default_value = "docs/scale.md")]
        out: PathBuf,
        /// Where the simulated records are kept (made once, reused).
        #[arg(long, default_value = "target/scale")]
        data: PathBuf,
        /// Record lengths in samples.
        #[arg(
            long,
            value_delimiter = ',',
            default_value = "100000,300000,1000000,3000000,10000000"
        )]
        sizes: Vec<usize>,
        /// Runs per size and method (the median is reported).
        #[arg(long, default_value_t = 3)]
        repeats: usize,
        /// Further lengths that are only simulated (`hbid simulate` writes its record as it
        /// integrates: its memory does not grow with the record); each file is removed after.
        /// The flag alone gives none.
        #[arg(long, value_delimiter = ',', num_args = 0.., default_value = "100000000")]
        simulate_sizes: Vec<usize>,
        /// Lengths identified with the record read in chunks (`--stream`), the windowed method;
        /// a length only simulated is made once for both. The flag alone gives none.
        #[arg(long, value_delimiter = ',', num_args = 0.., default_value = "1000000,10000000,100000000")]
        stream_sizes: Vec<usize>,
    },
    /// Records shaped like real rigs' (`hbid simulate`), each identified by one `hbid identify`
    /// command with the truth beside the result; writes a Markdown report.
    RealRecords {
        /// The report.
        #[arg(long, default_value = "docs/real-records.md")]
        out: PathBuf,
        /// Where the simulated records are written.
        #[arg(long, default_value = "target/real-records")]
        data: PathBuf,
    },
    /// The field's public benchmarks (Silverbox, EMPS, the DFKI double pendulum) by their
    /// protocols: identified on the training part, scored by a free run on the test parts; writes
    /// `docs/benchmarks.md`.
    Benchmarks {
        /// The report.
        #[arg(long, default_value = "docs/benchmarks.md")]
        doc: PathBuf,
        /// Also write `benchmarks.json` (coefficients and scores) into this folder.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Where the records cut from the benchmarks' files and the models are written.
        #[arg(long, default_value = "target/benchmarks")]
        work: PathBuf,
        /// Also run the peers with this Python interpreter (`pip install -r
        /// xtask/peers/requirements.txt`): sysidentpy's polynomial NARX by FROLS in its published
        /// configuration on Silverbox and EMPS (about 2 minutes and 10 GB of memory for its
        /// degree-3 Silverbox model), and pysindy's SINDy on the DFKI double pendulum (about 3
        /// minutes, most of it its free runs at the protocol's tolerance).
        #[arg(long, value_name = "PYTHON")]
        peer: Option<String>,
    },
    /// Model selection beside pysindy's weak-form SINDy on the same forced records at four noise
    /// levels; writes its section into `docs/accuracy.md` (needs Python with pysindy:
    /// `pip install -r xtask/peers/requirements.txt`).
    WeakSindy {
        /// The page the section is written into (between its markers, or appended).
        #[arg(long, default_value = "docs/accuracy.md")]
        out: PathBuf,
        /// Where the simulated records are written.
        #[arg(long, default_value = "target/weak-sindy")]
        data: PathBuf,
        /// The Python interpreter that has pysindy.
        #[arg(long, default_value = "python3")]
        python: String,
    },
}

/// Runs `hbid --quiet` with `args`: its stdout and stderr, failing with its stderr.
pub(crate) fn run_hbid(exe: &Path, args: &[String]) -> anyhow::Result<(String, String)> {
    let out = std::process::Command::new(exe)
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

/// Runs `hbid` with `args`: its stdout as JSON, failing with its stderr.
pub(crate) fn hbid(exe: &Path, args: &[String]) -> anyhow::Result<serde_json::Value> {
    let (stdout, _) = run_hbid(exe, args)?;
    serde_json::from_str(&stdout).with_context(|| format!("hbid {}: its JSON", args.join(" ")))
}

/// A figure of a table with `decimals` decimals, a dash where there is none.
pub(crate) fn shown(v: Option<f64>, decimals: usize) -> String {
    v.map_or_else(|| "—".to_owned(), |v| format!("{v:.decimals$}"))
}

/// How this xtask was built, for the generated pages that report wall times: `cargo xtask` runs
/// in the test profile so that it shares one build with `cargo test` (see README.md).
pub fn build_profile() -> &'static str {
    if cfg!(debug_assertions) {
        "test-profile build: opt-level 2, debug assertions on"
    } else {
        "release build"
    }
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Reproduce { out, quick } => reproduce::run(&out, quick),
        Command::Accuracy { out, quick } => accuracy::run(&out, quick),
        Command::Scale {
            out,
            data,
            sizes,
            repeats,
            simulate_sizes,
            stream_sizes,
        } => scale::run(&out, &data, &sizes, repeats, &simulate_sizes, &stream_sizes),
        Command::RealRecords { out, data } => real_records::run(&out, &data),
        Command::Benchmarks { doc, out, work, peer } => {
            benchmarks::run(&doc, out.as_deref(), &work, peer.as_deref())
        }
        Command::WeakSindy { out, data, python } => weak_sindy::run(&out, &data, &python),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
