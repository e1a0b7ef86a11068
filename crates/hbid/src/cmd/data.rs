//! The options every analysis subcommand shares: the record and the close-return search, as
//! command-line arguments that become the application layer's options.

use std::path::PathBuf;

use circle_signal::Measured;
use clap::Args;
use hb_pipeline::{
    AngleUnit, ColumnList, DriveFrequency, DrivePeriod, OrbitOptions, RecordOptions, SignalList, Source,
};
use upo_search::CloseReturns;

/// A value among `names`, read by its type's `FromStr`: the help lists the names, a bad one is
/// refused by clap with them.
pub fn choice<T>(names: &'static [&'static str]) -> impl clap::builder::TypedValueParser<Value = T>
where
    T: std::str::FromStr + Clone + Send + Sync + 'static,
    T::Err: Into<Box<dyn std::error::Error + Send + Sync>>,
{
    use clap::builder::TypedValueParser;
    clap::builder::PossibleValuesParser::new(names).try_map(|s| s.parse::<T>())
}

/// The record's options shared by the analysis subcommands.
#[derive(Debug, Args)]
pub struct InputArgs {
    /// The record: text (cells separated by commas, semicolons, spaces or tabs; header with columns t and theta, a row of units under it passed, or headerless time and angle in either order) or .npy; `-` reads standard input. `identify` takes several records of the same columns and one fit: each is conditioned on its own and they are joined, a gap between each two.
    #[arg(required = true, num_args = 1.., value_name = "FILE")]
    pub files: Vec<PathBuf>,
    /// Time column, by header name or 1-based position.
    #[arg(long, value_name = "NAME|N")]
    pub time_col: Option<String>,
    /// Angle (or displacement) column, by header name or 1-based position: a record of one
    /// coordinate (its terms name it x).
    #[arg(long, value_name = "NAME|N", conflicts_with = "coords")]
    pub angle_col: Option<String>,
    /// The columns that each get an equation, by header name: a system of several coordinates
    /// (a double pendulum's theta1,theta2; a chain's x1,x2,x3), one time base. Terms name the
    /// coordinates by these names (sin(theta1), theta2''*cos(theta1-theta2), x1^2*x2, q1'*q2').
    #[arg(long, value_name = "A,B[,..]")]
    pub coords: Option<ColumnList>,
    /// Sampling step, for records without a time column (the first sample is at t = 0).
    #[arg(long, allow_hyphen_values = true)]
    pub dt: Option<f64>,
    /// Measured drives: columns of the record (by header name or 1-based position; several
    /// separated by commas), such as a shaker's base acceleration or a motor's torques, sampled
    /// with the coordinates; they get no equation. With one coordinate and one drive, terms name
    /// it `p` (`p`, `p*cos(x)`, `p*x'`); otherwise by its column's name (tau1, tau2*cos(q1)).
    /// Without --terms the one-coordinate default model has it in place of cos(t) and sin(t):
    /// x', {1,p}*B and (with --forcing identified, the default on the line) p, B the basis. The
    /// weak form balances it at every sample as measured, of any waveform; windows are still
    /// counted in drive periods (--drive-period, or --drive-period none for periods of the
    /// oscillation, or --window in the record's time).
    #[arg(long, value_name = "NAME|N[,..]", visible_alias = "forcing-col")]
    pub drive_col: Option<ColumnList>,
    /// Fix isolated time-stamp glitches (a stamp off the grid, repeated or going backwards, between
    /// two that fit) and encoder spikes, and list each fix on stderr.
    #[arg(long)]
    pub repair: bool,
    /// The coordinates' measured velocities (a motor driver's, a tachometer's): columns of the
    /// record, one per coordinate in their order (NAME=COLUMN names one). `compare` starts each
    /// free run from the first sample's measured state, every sample scored (unless --init says otherwise);
    /// so does `report`. `identify` refuses it: the fit reads no velocities.
    #[arg(long, value_name = "NAME|N[,..]")]
    pub velocity_col: Option<ColumnList>,
    /// Keep every isolated spike in the record (warned of) instead of replacing them by the local
    /// prediction when they are few (at most one per 1000 samples; the default, said in a note).
    #[arg(long, conflicts_with = "repair")]
    pub no_repair: bool,
    /// Bridge every gap of at most N missing samples (N at most 4), between pieces of at least 7
    /// samples, by the cubic through the two samples on each side, in every column (angles across
    /// their wraps), so that the pieces are analysed as one: a logger's dropped rows (a note counts
    /// them). A bridged sample of a sine of amplitude A and angular frequency ω is off by at most A
    /// (ω dt)^4 times 1/6, 1/2, 3/2 or 3 for N = 1, 2, 3 or 4, and carries at most 1.61 times one
    /// sample's noise; an angle that moves too far across a gap to tell its turn leaves it a gap; 0
    /// bridges none (a displacement record only, not with --stream).
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub bridge_gaps: usize,
    /// Leave out every row with a missing value in a column read (an empty cell, NA, null, NaN,
    /// ...), as if the logger had not written it: its time is a gap's (with --dt the rows keep
    /// their places), which --bridge-gaps may bridge; a note counts them and names the first.
    /// Without it such a value is an error naming its line (not with --stream).
    #[arg(long)]
    pub skip_missing: bool,
    /// An angle on the circle (wrapped into [-π, π), unwrapped per orbit, circle metric) or a
    /// displacement on the line (no wrapping, plain differences): circle or line, for every
    /// coordinate or one per coordinate of --coords (circle,line).
    #[arg(long, value_name = "circle|line[,..]", default_value_t = SignalList::default())]
    pub signal: SignalList,
    /// What the sensor measured, on the line: the displacement, or its velocity (a laser
    /// vibrometer) or acceleration (an accelerometer), integrated here to the displacement less
    /// its mean (velocity) or least-squares linear trend (acceleration). `identify` then finds
    /// the offset (and, for an acceleration, the slope) that the model explains best, piece by
    /// piece; with a constant term `1` in the model the offset is left to the model (its
    /// polynomial terms are then those of the displacement less its mean).
    #[arg(long, default_value_t = Measured::Displacement, value_parser = choice::<Measured>(&["displacement", "velocity", "acceleration"]))]
    pub measured: Measured,
    /// The unit of the angles on the circle, and of their measured velocities (per time unit):
    /// rad, deg, or counts:N for an encoder's N counts per turn (4096 counts from 0 to 4095, say);
    /// converted to radians as they are read.
    #[arg(long, value_name = "rad|deg|counts:N", default_value_t = AngleUnit::Radians)]
    pub angle_unit: AngleUnit,
    /// Drive period in the time unit of the data, any number of sampling steps (default 2π, the
    /// paper's non-dimensional time); `auto` or `auto:A..B` estimates it from the record (within
    /// periods A to B); `none`: no drive, a free oscillation (windows in periods of the
    /// oscillation).
    #[arg(
        long,
        value_name = "T|auto[:A..B]|none",
        visible_alias = "forcing-period",
        conflicts_with = "drive_frequency",
        allow_hyphen_values = true
    )]
    pub drive_period: Option<DrivePeriod>,
    /// Drive frequency in cycles per time unit of the data (Hz for time in seconds), instead of
    /// the period; `auto` or `auto:A..B` estimates it from the record (within frequencies A to
    /// B); `none`: no drive.
    #[arg(
        long,
        value_name = "HZ|auto[:A..B]|none",
        visible_alias = "forcing-frequency",
        allow_hyphen_values = true
    )]
    pub drive_frequency: Option<DriveFrequency>,
}

impl InputArgs {
    /// The record's options.
    pub fn options(&self) -> RecordOptions {
        RecordOptions {
            time_col: self.time_col.clone(),
            angle_col: self.angle_col.clone(),
            coords: self.coords.clone(),
            dt: self.dt,
            drive_col: self.drive_col.clone(),
            repair: self.repair,
            no_repair: self.no_repair,
            bridge_gaps: self.bridge_gaps,
            skip_missing: self.skip_missing,
            velocity_col: self.velocity_col.clone(),
            signal: self.signal.clone(),
            measured: self.measured,
            drive_period: self.drive_period.clone(),
            drive_frequency: self.drive_frequency.clone(),
            angle_unit: self.angle_unit,
        }
    }

    /// Where the samples come from: the one record (a command that reads one).
    pub fn source(&self) -> anyhow::Result<Source<'_>> {
        match &self.files[..] {
            [file] => Ok(Source::Path(file)),
            _ => anyhow::bail!("this command reads one record; only `identify` joins several"),
        }
    }

    /// The one record's path (a command that reads one).
    pub fn file(&self) -> &std::path::Path {
        &self.files[0]
    }

    /// Where the samples of every record come from.
    pub fn sources(&self) -> Vec<Source<'_>> {
        self.files.iter().map(|f| Source::Path(f)).collect()
    }
}

/// The close-return options shared by `upos`, `identify` and `report`.
#[derive(Debug, Args)]
pub struct SearchArgs {
    /// Close-return tolerance as a fraction of the span of the data (2π for an angle), in (0, 0.5).
    #[arg(long, default_value_t = CloseReturns::DEFAULT_TOLERANCE, allow_hyphen_values = true)]
    pub tolerance: f64,
    /// Longest orbit period searched, in drive periods.
    #[arg(long, default_value_t = CloseReturns::DEFAULT_MAX_PERIOD)]
    pub max_period: usize,
    /// Dimension of the delay vectors compared.
    #[arg(long, default_value_t = CloseReturns::DEFAULT_DIMENSION)]
    pub dim: usize,
    /// Delay in samples (default: the first minimum of the average mutual information, 16 boxes).
    #[arg(long)]
    pub delay: Option<usize>,
}

impl SearchArgs {
    /// The search's options.
    pub fn options(&self) -> OrbitOptions {
        OrbitOptions {
            tolerance: self.tolerance,
            max_period: self.max_period,
            dim: self.dim,
            delay: self.delay,
        }
    }
}
