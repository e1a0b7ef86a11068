//! Loading a record the way every analysis subcommand does.

use std::f64::consts::{PI, TAU};
use std::path::PathBuf;

use anyhow::Context;
use circle_signal::{Domain, SampleClock};
use clap::Args;
use clap::builder::{PossibleValuesParser, TypedValueParser};
use embedding::AmiParams;
use hbid::input::{
    AngleRange, Column, GridOptions, GridRecord, InputError, ReadOptions, Role, angle_range, read_path,
};
use hbid::pipeline::{Record, SearchOptions};

/// The command-line values of a [`Domain`]: `circle` or `line` (`linear` too where `also_linear`,
/// the name classic embedding tools give plain differences).
pub fn domain_parser(also_linear: bool) -> impl TypedValueParser<Value = Domain> {
    let names: &[&str] = if also_linear {
        &["circle", "line", "linear"]
    } else {
        &["circle", "line"]
    };
    PossibleValuesParser::new(names).map(|name| name.parse::<Domain>().unwrap_or_default())
}

/// The input options shared by the analysis subcommands.
#[derive(Debug, Args)]
pub struct InputArgs {
    /// The record: text (cells separated by commas, semicolons, spaces or tabs; header with columns t and theta, or headerless time and angle in either order) or .npy; `-` reads standard input.
    pub file: PathBuf,
    /// Time column, by header name or 1-based position.
    #[arg(long, value_name = "NAME|N")]
    pub time_col: Option<String>,
    /// Angle (or displacement) column, by header name or 1-based position.
    #[arg(long, value_name = "NAME|N")]
    pub angle_col: Option<String>,
    /// Sampling step, for records without a time column (the first sample is at t = 0).
    #[arg(long, allow_hyphen_values = true)]
    pub dt: Option<f64>,
    /// Fix isolated time-stamp glitches (a stamp off the grid, repeated or going backwards, between
    /// two that fit) and encoder spikes, and list each fix on stderr.
    #[arg(long)]
    pub repair: bool,
    /// Forcing period in the time unit of the data (2π for the paper's non-dimensional time).
    #[arg(long, default_value_t = TAU, allow_hyphen_values = true)]
    pub forcing_period: f64,
    /// An angle on the circle (wrapped into [-π, π), unwrapped per orbit, circle metric) or a
    /// displacement on the line (no wrapping, plain differences): circle or line.
    #[arg(long, default_value = "circle", value_parser = domain_parser(false))]
    pub signal: Domain,
}

/// A record ready for analysis.
#[derive(Debug)]
pub struct Data {
    /// The record's clock: forcing period, step `T / P`, time of the first sample.
    pub clock: SampleClock,
    /// Samples per forcing period `P`.
    pub p: usize,
    /// The samples (wrapped into [-π, π) for a signal on the circle).
    pub x: Vec<f64>,
    /// What the samples are.
    pub domain: Domain,
}

impl Data {
    /// One line describing the record, for the readable outputs.
    pub fn summary(&self) -> String {
        format!(
            "{} samples from t = {} in steps of {} ({} per forcing period)",
            self.x.len(),
            self.clock.start_time(),
            self.clock.step(),
            self.p
        )
    }

    /// The record as the pipeline takes it.
    pub fn record(&self) -> anyhow::Result<Record<'_>> {
        Ok(Record::new(&self.x, self.clock, self.domain)?)
    }
}

impl InputArgs {
    /// Reads, checks and (on the circle) wraps the record.
    pub fn load(&self) -> anyhow::Result<Data> {
        let column = |s: &Option<String>| s.as_deref().map(str::parse::<Column>).transpose();
        let options = ReadOptions {
            time: column(&self.time_col)?,
            angle: column(&self.angle_col)?,
            dt: self.dt,
        };
        let record = read_path(&self.file, &options)
            .map_err(naming_options)
            .with_context(|| format!("{}", self.file.display()))?;
        let grid = GridRecord::fit(record, &GridOptions { repair: self.repair })
            .map_err(naming_options)
            .with_context(|| format!("{}", self.file.display()))?;
        for r in &grid.repaired {
            eprintln!(
                "note: {}: time {} replaced by its grid time {}",
                r.at, r.was, r.now
            );
        }
        if let [first, second, ..] = &grid.pieces[..] {
            let end = first.first + first.samples.len();
            anyhow::bail!(
                "{}: the time stamps have {} gap(s) (missing samples; the first: {} samples after t = {}); records with gaps cannot be analysed yet",
                self.file.display(),
                grid.pieces.len() - 1,
                second.first - end,
                grid.t0 + (end - 1) as f64 * grid.dt,
            );
        }
        let p = grid
            .samples_per_period(self.forcing_period)
            .map_err(naming_options)?;
        let clock = SampleClock::new(self.forcing_period, p)?.with_start_time(grid.t0)?;
        let mut x = grid
            .pieces
            .into_iter()
            .next()
            .map(|p| p.samples)
            .unwrap_or_default();
        if self.signal == Domain::Circle && x.iter().any(|v| !(-PI..PI).contains(v)) {
            if angle_range(&x) == AngleRange::Unwrapped {
                eprintln!("note: values outside [-π, π): read as an unwrapped angle and wrapped");
            }
            for v in &mut x {
                *v = circle_signal::wrap(*v);
            }
        }
        Ok(Data {
            clock,
            p,
            x,
            domain: self.signal,
        })
    }
}

/// An input error with the options of this command line that set what it is about, which the
/// library does not know.
#[derive(Debug)]
struct WithOptions {
    error: InputError,
    /// Appended to the error's text.
    options: &'static str,
}

impl std::fmt::Display for WithOptions {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}{}", self.error, self.options)
    }
}

impl std::error::Error for WithOptions {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        self.error.source()
    }
}

/// The error, naming the options that set what it is about, if any.
fn naming_options(error: InputError) -> anyhow::Error {
    let options = match &error {
        InputError::NeedStep => " with --dt",
        InputError::BadStep { .. } => " (--dt)",
        InputError::TimeTwice => " (--dt, --time-col)",
        InputError::MissingColumn { role: Role::Time, .. } => "; choose one with --time-col",
        InputError::MissingColumn {
            role: Role::Angle, ..
        } => "; choose one with --angle-col",
        InputError::BadForcingPeriod { .. } => " (--forcing-period)",
        InputError::TimeGlitch { isolated: true, .. } => "; run with --repair to fix isolated glitches",
        InputError::TimeGlitch { isolated: false, .. } | InputError::TimeUnresolved { .. } => " with --dt",
        _ => return error.into(),
    };
    WithOptions { error, options }.into()
}

/// The close-return options shared by `upos`, `identify` and `report`.
#[derive(Debug, Args)]
pub struct SearchArgs {
    /// Close-return tolerance as a fraction of the span of the data (2π for an angle), in (0, 0.5).
    #[arg(long, default_value_t = 0.03, allow_hyphen_values = true)]
    pub tolerance: f64,
    /// Longest orbit period searched, in forcing periods.
    #[arg(long, default_value_t = 16)]
    pub max_period: usize,
    /// Dimension of the delay vectors compared.
    #[arg(long, default_value_t = 2)]
    pub dim: usize,
    /// Delay in samples (default: the first minimum of the average mutual information, 16 boxes).
    #[arg(long)]
    pub delay: Option<usize>,
}

impl SearchArgs {
    /// The search's options, validated.
    pub fn options(&self) -> anyhow::Result<SearchOptions> {
        Ok(SearchOptions::default()
            .with_tolerance(self.tolerance)?
            .with_max_period(self.max_period)?
            .with_dimension(self.dim)?)
    }

    /// The close-return search on `data` with `delay`, validated.
    pub fn close_returns(&self, data: &Data, delay: usize) -> anyhow::Result<upo_search::CloseReturns> {
        Ok(self.options()?.close_returns(&data.record()?, delay)?)
    }

    /// The delay: the one given, or the first minimum of the AMI. The search's options are checked
    /// first, so that a bad option fails before any work.
    pub fn delay(&self, data: &Data) -> anyhow::Result<usize> {
        self.close_returns(data, self.delay.unwrap_or(1))?;
        Ok(match self.delay {
            Some(d) => d,
            None => ami(&data.x, &AmiParams::new(data.domain))?.1,
        })
    }
}

/// The AMI curve of `x` and its first minimum, the default delay of every later stage.
pub fn ami(x: &[f64], params: &AmiParams) -> anyhow::Result<(embedding::AmiCurve, usize)> {
    let curve = embedding::average_mutual_information(x, params)?;
    let delay = curve
        .delay()
        .context("choose the delay with --delay, or raise --max-lag")?;
    Ok((curve, delay))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn input_errors_name_the_options_that_fix_them() {
        let glitch = |isolated| InputError::TimeGlitch {
            at: hbid::input::Location::Line(7),
            t: 1.5,
            fault: hbid::input::StampFault::OffGrid,
            expected: 1.25,
            dt: 0.25,
            isolated,
        };
        let missing = |role| InputError::MissingColumn {
            role,
            wanted: Column::Position(3),
            found: Vec::new(),
            width: 2,
        };
        for (error, option) in [
            (InputError::NeedStep, "--dt"),
            (InputError::BadStep { dt: 0.0 }, "--dt"),
            (InputError::TimeTwice, "--time-col"),
            (missing(Role::Time), "--time-col"),
            (missing(Role::Angle), "--angle-col"),
            (InputError::BadForcingPeriod { period: -1.0 }, "--forcing-period"),
            (glitch(true), "run with --repair to fix isolated glitches"),
            (glitch(false), "give its step with --dt"),
            (
                InputError::TimeUnresolved {
                    off: 900,
                    total: 1000,
                    decimals: Some(3),
                },
                "give its step with --dt",
            ),
        ] {
            let text = error.to_string();
            let named = format!("{:#}", naming_options(error));
            assert!(named.starts_with(&text) && named.contains(option), "{named}");
        }
        assert_eq!(
            naming_options(InputError::NeedStep).to_string(),
            "the input has a single column: give its sampling step with --dt"
        );
    }
}
