//! Loading a record the way every analysis subcommand does.

use std::f64::consts::TAU;
use std::path::PathBuf;

use anyhow::Context;
use circle_signal::{Domain, Measured};
use clap::Args;
use clap::builder::{PossibleValuesParser, TypedValueParser};
use embedding::AmiParams;
use hb_solve::PeriodRange;
use hbid::input::{Column, InputError, ReadOptions, Role, read_path};
use hbid::pipeline::{EmbedOptions, SearchOptions};
use hbid::prepare::{Note, PrepareError, PrepareOptions, condition};

pub use hbid::prepare::{Data, DriveFound, DriveSpec};

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
    /// Forcing period in the time unit of the data, any number of sampling steps (default 2π, the
    /// paper's non-dimensional time); `auto` or `auto:A..B` estimates it from the record (within
    /// periods A to B).
    #[arg(
        long,
        value_name = "T|auto[:A..B]",
        conflicts_with = "forcing_frequency",
        allow_hyphen_values = true
    )]
    pub forcing_period: Option<String>,
    /// Forcing frequency in cycles per time unit of the data (Hz for time in seconds), instead of
    /// the period; `auto` or `auto:A..B` estimates it from the record (within frequencies A to B).
    #[arg(long, value_name = "HZ|auto[:A..B]", allow_hyphen_values = true)]
    pub forcing_frequency: Option<String>,
    /// An angle on the circle (wrapped into [-π, π), unwrapped per orbit, circle metric) or a
    /// displacement on the line (no wrapping, plain differences): circle or line.
    #[arg(long, default_value = "circle", value_parser = domain_parser(false))]
    pub signal: Domain,
    /// What the sensor measured, on the line: the displacement, or its velocity (a laser
    /// vibrometer) or acceleration (an accelerometer), integrated here to the displacement less
    /// its mean (velocity) or least-squares linear trend (acceleration). `identify` then finds
    /// the offset (and, for an acceleration, the slope) that the model explains best, piece by
    /// piece; with a constant term `1` in the model the offset is left to the model (its
    /// polynomial terms are then those of the displacement less its mean).
    #[arg(long, value_enum, default_value_t = MeasuredArg::Displacement)]
    pub measured: MeasuredArg,
}

/// What the sensor measured.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum MeasuredArg {
    /// The displacement (or angle).
    Displacement,
    /// Its velocity.
    Velocity,
    /// Its acceleration.
    Acceleration,
}

impl From<MeasuredArg> for Measured {
    fn from(m: MeasuredArg) -> Self {
        match m {
            MeasuredArg::Displacement => Measured::Displacement,
            MeasuredArg::Velocity => Measured::Velocity,
            MeasuredArg::Acceleration => Measured::Acceleration,
        }
    }
}

/// Parses `T`, `auto` or `auto:A..B` of `--forcing-period` (or of `--forcing-frequency` when
/// `frequency`).
pub fn parse_drive(text: &str, frequency: bool) -> anyhow::Result<DriveSpec> {
    let option = if frequency {
        "--forcing-frequency"
    } else {
        "--forcing-period"
    };
    let number = |s: &str| -> anyhow::Result<f64> {
        let v: f64 = s
            .trim()
            .parse()
            .map_err(|_| anyhow::anyhow!("{option} '{text}': '{}' is not a number", s.trim()))?;
        if !(v.is_finite() && v > 0.0) {
            anyhow::bail!("{option} '{text}': {v} must be positive and finite");
        }
        Ok(v)
    };
    let text_trim = text.trim();
    if let Some(rest) = text_trim.strip_prefix("auto") {
        if rest.is_empty() {
            return Ok(DriveSpec::Auto(None));
        }
        let range = rest
            .strip_prefix(':')
            .and_then(|r| r.split_once(".."))
            .ok_or_else(|| anyhow::anyhow!("{option} '{text}': expected auto or auto:A..B"))?;
        let (a, b) = (number(range.0)?, number(range.1)?);
        let range = if frequency {
            PeriodRange::frequencies(a, b)
        } else {
            PeriodRange::periods(a, b)
        }
        .with_context(|| format!("{option} '{text}'"))?;
        return Ok(DriveSpec::Auto(Some(range)));
    }
    let v = number(text_trim)?;
    Ok(DriveSpec::Period(if frequency { 1.0 / v } else { v }))
}

impl InputArgs {
    /// The drive of the record: the forcing period or frequency given (default 2π), its estimate,
    /// or none when `free` (asked for with `--forcing none`) and neither is given.
    pub fn drive(&self, free: bool) -> anyhow::Result<DriveSpec> {
        Ok(match (&self.forcing_period, &self.forcing_frequency) {
            (Some(t), _) => parse_drive(t, false)?,
            (None, Some(f)) => parse_drive(f, true)?,
            (None, None) if free => DriveSpec::Free,
            (None, None) => DriveSpec::Period(TAU),
        })
    }

    /// Reads, checks and (on the circle) wraps the record, with a drive (a forcing period, given or
    /// estimated).
    pub fn load(&self) -> anyhow::Result<Data> {
        self.load_with(self.drive(false)?, &mut |_, _| {})
    }

    /// Reads, checks and (on the circle) wraps the record; finds its clock by `drive`, resampling
    /// it onto a whole number of samples per forcing period when needed. `progress` follows the
    /// estimate of the drive, if any.
    pub fn load_with(
        &self,
        drive: DriveSpec,
        progress: &mut dyn FnMut(usize, usize),
    ) -> anyhow::Result<Data> {
        self.load_with_drive_column(drive, None, progress)
    }

    /// [`load_with`](Self::load_with), reading the measured drive from `drive_column` too (its
    /// text as `--forcing-col` gives it).
    pub fn load_with_drive_column(
        &self,
        drive: DriveSpec,
        drive_column: Option<&str>,
        progress: &mut dyn FnMut(usize, usize),
    ) -> anyhow::Result<Data> {
        let column = |s: Option<&str>| s.map(str::parse::<Column>).transpose();
        let options = ReadOptions {
            time: column(self.time_col.as_deref())?,
            angle: column(self.angle_col.as_deref())?,
            dt: self.dt,
            drive: column(drive_column).context("--forcing-col")?,
        };
        let name = self.file.display().to_string();
        let record = read_path(&self.file, &options)
            .map_err(naming_options)
            .with_context(|| name.clone())?;
        let options = PrepareOptions::new(self.signal)
            .with_repair(self.repair)
            .with_measured(self.measured.into());
        let grid = condition(record, &options, &mut print_note).map_err(|e| match e {
            PrepareError::Input(e) => naming_options(e).context(name.clone()),
            e @ PrepareError::MeasuredOnCircle(_) => anyhow::Error::new(e).context(format!(
                "--measured {} needs --signal line",
                Measured::from(self.measured)
            )),
            e => e.into(),
        })?;
        grid.with_drive(drive, progress).map_err(naming_drive_options)
    }
}

/// Prints a note on the record as the command line shows it.
fn print_note(note: &Note) {
    if let Note::Spikes { repaired: false, .. } = note {
        eprintln!("warning: {note}; run with --repair to replace them");
    } else if note.is_warning() {
        eprintln!("warning: {note}");
    } else {
        eprintln!("note: {note}");
    }
}

/// An error of the drive or the clock, naming the options that set what it is about.
fn naming_drive_options(error: PrepareError) -> anyhow::Error {
    match error {
        PrepareError::Input(e) => naming_options(e),
        PrepareError::FreePeriod(e) => {
            anyhow::Error::new(e).context("--forcing none: the period of the free oscillation")
        }
        PrepareError::DriveEstimate(e) => anyhow::Error::new(e).context("estimating the forcing period"),
        PrepareError::Clock(e) => anyhow::Error::new(e).context("--forcing-period"),
        PrepareError::Resample(e) => {
            anyhow::Error::new(e).context("resampling onto a whole number of samples per forcing period")
        }
        e => e.into(),
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
        InputError::MissingColumn {
            role: Role::Drive, ..
        } => " (--forcing-col)",
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
            None => {
                let max_lag = EmbedOptions::default().max_lag(data.p);
                ami(
                    data.longest(),
                    &AmiParams::new(data.domain).with_max_lag(max_lag)?,
                )?
                .1
            }
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
            others: Vec::new(),
            other_count: 0,
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
                    scatter: None,
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
