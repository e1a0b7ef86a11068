//! Loading a record the way every analysis subcommand does.

use std::f64::consts::{PI, TAU};
use std::ops::Range;
use std::path::PathBuf;

use anyhow::Context;
use circle_signal::{
    Domain, SampleClock, Spike, SpikeParams, find_and_repair_spikes, find_spikes, resample_pieces,
};
use clap::Args;
use clap::builder::{PossibleValuesParser, TypedValueParser};
use embedding::AmiParams;
use hb_basis::{BasisKind, Harmonic, Polynomial};
use hb_solve::{DriveEstimate, DriveSearch, Forcing, ModelForm, PeriodRange, estimate_forcing_period};
use hbid::input::{
    AngleRange, Column, GridOptions, GridRecord, InputError, ReadOptions, Role, angle_range, read_path,
};
use hbid::pipeline::{EmbedOptions, Record, SearchOptions};

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
}

/// What drives the record, as the command line gives it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DriveSpec {
    /// A known forcing period.
    Period(f64),
    /// A forcing period to estimate from the record, within this range if given.
    Auto(Option<PeriodRange>),
    /// No drive: a free oscillation, whose mean period is the unit of the windows.
    Free,
}

/// Where a record's time unit for the analysis came from.
#[derive(Debug, Clone, PartialEq)]
pub enum DriveFound {
    /// The forcing period given.
    Given,
    /// Estimated from the record.
    Estimated(Box<DriveEstimate>),
    /// No drive: the mean period of the free oscillation, in samples.
    Free {
        /// The measured mean period, in samples (the clock's period is its nearest whole number).
        samples: f64,
    },
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

/// A record ready for analysis.
#[derive(Debug)]
pub struct Data {
    /// The record's clock: forcing period, step `T / P`, time of the first sample.
    pub clock: SampleClock,
    /// Samples per forcing period `P`.
    pub p: usize,
    /// The samples (wrapped into [-π, π) for a signal on the circle; NaN in the gaps).
    pub x: Vec<f64>,
    /// The ranges of `x` that hold data: one without gaps.
    pub pieces: Vec<Range<usize>>,
    /// What the samples are.
    pub domain: Domain,
    /// Where the forcing period came from.
    pub drive: DriveFound,
    /// The samples per forcing period of the record as read, when it was resampled to `p`.
    pub resampled_from: Option<f64>,
}

impl Data {
    /// One line describing the record, for the readable outputs.
    pub fn summary(&self) -> String {
        let samples: usize = self.pieces.iter().map(Range::len).sum();
        let mut line = format!(
            "{samples} samples from t = {} in steps of {} ({} per {})",
            self.clock.start_time(),
            self.clock.step(),
            self.p,
            match self.drive {
                DriveFound::Free { .. } => "oscillation period",
                _ => "forcing period",
            }
        );
        if let Some(from) = self.resampled_from {
            line.push_str(&format!(", resampled from {from:.6} per period"));
        }
        if self.pieces.len() > 1 {
            line.push_str(&format!(", in {} pieces (gaps)", self.pieces.len()));
        }
        line
    }

    /// The longest piece (the whole record without gaps).
    pub fn longest(&self) -> &[f64] {
        &self.x[circle_signal::longest_piece(&self.pieces)]
    }

    /// The record as the pipeline takes it.
    pub fn record(&self) -> anyhow::Result<Record<'_>> {
        Ok(Record::with_pieces(
            &self.x,
            self.pieces.clone(),
            self.clock,
            self.domain,
        )?)
    }
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
        let column = |s: &Option<String>| s.as_deref().map(str::parse::<Column>).transpose();
        let options = ReadOptions {
            time: column(&self.time_col)?,
            angle: column(&self.angle_col)?,
            dt: self.dt,
        };
        let name = self.file.display().to_string();
        let record = read_path(&self.file, &options)
            .map_err(naming_options)
            .with_context(|| name.clone())?;
        let grid = GridRecord::fit(record, &GridOptions { repair: self.repair })
            .map_err(naming_options)
            .with_context(|| name.clone())?;
        for r in &grid.repaired {
            eprintln!(
                "note: {}: time {} replaced by its grid time {}",
                r.at, r.was, r.now
            );
        }
        let (t0, dt) = (grid.t0, grid.dt);
        // One grid for every piece, NaN in the gaps.
        let mut x: Vec<f64> = Vec::new();
        let mut pieces = Vec::with_capacity(grid.pieces.len());
        for piece in grid.pieces {
            x.resize(piece.first, f64::NAN);
            pieces.push(piece.first..piece.first + piece.samples.len());
            x.extend(piece.samples);
        }
        if pieces.len() > 1 {
            let missing = x.len() - pieces.iter().map(Range::len).sum::<usize>();
            eprintln!(
                "note: {} gap(s) in the time stamps ({missing} samples missing): the record is analysed in {} pieces",
                pieces.len() - 1,
                pieces.len()
            );
        }
        if self.signal == Domain::Circle {
            let present: Vec<f64> = pieces.iter().flat_map(|r| x[r.clone()].iter().copied()).collect();
            if present.iter().any(|v| !(-PI..PI).contains(v)) {
                if angle_range(&present) == AngleRange::Unwrapped {
                    eprintln!("note: values outside [-π, π): read as an unwrapped angle and wrapped");
                }
                for r in &pieces {
                    for v in &mut x[r.clone()] {
                        *v = circle_signal::wrap(*v);
                    }
                }
            }
        }
        self.spikes(&mut x, &pieces)?;
        let longest = circle_signal::longest_piece(&pieces);
        let (period, found) = match drive {
            DriveSpec::Period(t) => (t, DriveFound::Given),
            DriveSpec::Free => {
                let samples = circle_signal::oscillation_period(&x[longest.clone()], self.signal)
                    .context("--forcing none: the period of the free oscillation")?;
                let whole = samples.round().max(2.0);
                (whole * dt, DriveFound::Free { samples })
            }
            DriveSpec::Auto(range) => {
                let mut search = DriveSearch::builder();
                if let Some(range) = range {
                    search = search.range(range);
                }
                let search = search.build()?;
                let basis = default_basis(self.signal);
                let form = match self.signal {
                    Domain::Circle => ModelForm::parametric(),
                    Domain::Line => ModelForm::parametric().with_forcing(Forcing::Identified),
                };
                let piece_t0 = t0 + longest.start as f64 * dt;
                let estimate = estimate_forcing_period(
                    &x[longest.clone()],
                    dt,
                    piece_t0,
                    self.signal,
                    &search,
                    &basis,
                    &form,
                    &mut *progress,
                )
                .context("estimating the forcing period")?;
                (estimate.period, DriveFound::Estimated(Box::new(estimate)))
            }
        };
        if !(period.is_finite() && period > 0.0) {
            return Err(naming_options(InputError::BadForcingPeriod { period }));
        }
        let clock = SampleClock::from_step(period, dt)
            .map_err(anyhow::Error::from)
            .and_then(|c| Ok(c.with_start_time(t0)?))
            .context("--forcing-period")?;
        let (clock, x, pieces, resampled_from) = match clock.whole_samples_per_period() {
            Some(_) => (clock, x, pieces, None),
            None => {
                let r = resample_pieces(&x, &pieces, &clock, self.signal)
                    .context("resampling onto a whole number of samples per forcing period")?;
                (r.clock, r.samples, r.pieces, Some(clock.samples_per_period()))
            }
        };
        let p = clock.require_whole()?;
        Ok(Data {
            clock,
            p,
            x,
            pieces,
            domain: self.signal,
            drive: found,
            resampled_from,
        })
    }
}

impl InputArgs {
    /// Finds the isolated spikes (bit errors) of every piece; with `--repair` replaces them and
    /// lists them, without it warns with their count. Pieces too short for the test are left as
    /// they are.
    fn spikes(&self, x: &mut [f64], pieces: &[Range<usize>]) -> anyhow::Result<()> {
        let params = SpikeParams::default();
        let mut found: Vec<Spike> = Vec::new();
        for r in pieces.iter().filter(|r| r.len() >= SpikeParams::MIN_SAMPLES) {
            let piece = &mut x[r.clone()];
            let spikes = if self.repair {
                find_and_repair_spikes(piece, self.signal, &params)?
            } else {
                find_spikes(piece, self.signal, &params)?
            };
            found.extend(spikes.iter().map(|s| Spike {
                index: s.index + r.start,
                ..*s
            }));
        }
        if found.is_empty() {
            return Ok(());
        }
        let list: Vec<String> = found
            .iter()
            .take(5)
            .map(|s| format!("sample {} ({:+.4})", s.index + 1, s.size))
            .collect();
        let more = if found.len() > 5 { ", ..." } else { "" };
        if self.repair {
            eprintln!(
                "note: {} isolated spike(s) replaced by the local prediction: {}{more}",
                found.len(),
                list.join(", ")
            );
        } else {
            eprintln!(
                "warning: {} isolated spike(s) (bit errors?) in the record: {}{more}; run with --repair to replace them",
                found.len(),
                list.join(", ")
            );
        }
        Ok(())
    }
}

/// The basis of the unknown functions when none is chosen: harmonic:1 on the circle, poly:3 on
/// the line.
pub fn default_basis(domain: Domain) -> BasisKind {
    match domain {
        Domain::Circle => BasisKind::from(Harmonic::new(1).expect("order 1 is valid")),
        Domain::Line => BasisKind::from(Polynomial::new(3).expect("degree 3 is valid")),
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
