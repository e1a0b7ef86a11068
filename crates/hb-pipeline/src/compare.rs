//! A saved model against a record it was not fitted to: the model driven by the record's own
//! input and run freely from an initial state the record's first samples give, its output
//! compared with the measured one, as system identification scores a model on held-out data
//! (`hbid compare`, `hbid simulate --model --input`, Python's `hbid.compare` and
//! `Model.simulate`).
//!
//! The record is read and conditioned as for an identification ([`condition_source`]: its grid,
//! gaps, wrapping, spikes, integration), but never resampled: the model runs on the record's own
//! grid in its own time unit, the unit of the record it was identified from. A model with terms
//! in the measured drive `p` reads it from the record's drive column between samples through
//! [`MeasuredDrive`]'s spline (C¹, so that the integrator's error control sees no kink; linear
//! interpolation would put a kink at every sample); a model with a periodic drive runs on the
//! record's clock, so the drive's phase is the one it was identified with.
//!
//! A record whose first rows a logger stamped before it settled to its rate (steps of 1.5 or 2
//! of its later ones: the identification leaves them out, see [`hb_record::prepare::LeadIn`]) is
//! compared from its first row all the same: the free run covers the record as given. Those rows
//! are run through at their own stamps (a free run needs no even grid; the measured drives are
//! then the spline on those stamps, [`MeasuredDrive::at_stamps`]), the rest on the grid, and the
//! ranges count them as the record's first rows, so that the samples are the file's rows for a
//! record without gaps; a notice says so ([`Notice::UnevenStart`]). `skip_unsettled` leaves them
//! out, as an identification does, the ranges then counting the grid's samples.
//!
//! Each range is run piece by piece (a gap has no measured drive to run on, so the model starts
//! again after it): on each piece the initial state is the one whose free run best matches its
//! first `init` samples ([`fit_initial_state`]), or the state given for the first piece; the
//! scores count the samples after them. They are the field's usual three: the RMSE in the
//! record's unit, the NRMSE (the RMSE over the standard deviation of the measured output) and the
//! fit percentage `100 (1 − ‖y − ŷ‖ / ‖y − ȳ‖)`. On the circle differences are the shortest arcs.
//! A run that stops (the model blows up) is a result: its range is scored `None` and says where.

use std::fmt;
use std::str::FromStr;

use circle_signal::{Domain, Measured, wrap};
use hb_model::{IdentifiedModel, IdentifiedSystem, MeasuredDrive};
use hb_record::prepare::{Channel, GridData};
use pendulum_sim::multi::{self, MultiState, OneCoordinate};
use pendulum_sim::{Tolerances, fit_initial_state, free_run, free_run_reporting};
use serde::{Deserialize, Serialize};

use crate::error::RunError;
use crate::observe::{Notice, Observer, Stage};
use crate::options::{OptionError, from_object, optional_text, text};
use crate::record::{AngleUnit, ColumnList, RecordOptions, Source, condition_source};

/// A range of samples of the record, `A..B` (0-based, `B` excluded), or `A..` to the record's
/// end: the grid's samples, after the rows a logger stamped before it settled, when the record
/// has them (see the [module documentation](self)). For a record without gaps the samples are
/// the file's rows; a record whose gaps were bridged (`bridge_gaps`) counts the samples bridged
/// among them, which hold no row of the file (or a row left out for a missing value,
/// `skip_missing`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SampleRange {
    /// The first sample.
    pub start: usize,
    /// One past the last sample (`None`: the record's end).
    pub end: Option<usize>,
}

impl SampleRange {
    /// The whole record.
    pub const ALL: SampleRange = SampleRange { start: 0, end: None };

    /// The range on a record of `len` samples, `[start, end)`, or why it does not fit.
    fn on(self, len: usize) -> Result<std::ops::Range<usize>, OptionError> {
        let end = self.end.unwrap_or(len);
        if end > len {
            return Err(OptionError::value(
                "range",
                self,
                format!("ends past the record's {len} samples"),
            ));
        }
        if self.start >= end {
            return Err(OptionError::value("range", self, "holds no sample of the record"));
        }
        Ok(self.start..end)
    }
}

impl FromStr for SampleRange {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let s = s.trim();
        let (a, b) = s
            .split_once("..")
            .ok_or_else(|| format!("'{s}' is not a range of samples A..B (or A.. to the end)"))?;
        let number = |t: &str| {
            t.trim()
                .parse::<usize>()
                .map_err(|_| format!("'{t}' in '{s}' is not a sample index"))
        };
        let start = if a.trim().is_empty() { 0 } else { number(a)? };
        let end = if b.trim().is_empty() {
            None
        } else {
            Some(number(b)?)
        };
        if let Some(end) = end
            && end <= start
        {
            return Err(format!("'{s}' is empty: the end must come after the start"));
        }
        Ok(Self { start, end })
    }
}

impl fmt::Display for SampleRange {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.end {
            Some(end) => write!(f, "{}..{}", self.start, end),
            None => write!(f, "{}..", self.start),
        }
    }
}

impl Serialize for SampleRange {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

impl<'de> Deserialize<'de> for SampleRange {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let text = String::deserialize(d)?;
        text.parse().map_err(serde::de::Error::custom)
    }
}

/// Numbers given as one or a list, written `a,b,c` (from Python a number or a list): a state
/// component per coordinate.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Values(pub Vec<f64>);

impl Values {
    /// The one value of a one-coordinate state.
    pub fn one(&self) -> Option<f64> {
        match self.0[..] {
            [v] => Some(v),
            _ => None,
        }
    }
}

impl From<f64> for Values {
    fn from(v: f64) -> Self {
        Self(vec![v])
    }
}

impl FromStr for Values {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        s.split(',')
            .map(|v| {
                v.trim()
                    .parse::<f64>()
                    .map_err(|_| format!("'{}' is not a number", v.trim()))
            })
            .collect::<Result<Vec<_>, _>>()
            .map(Self)
    }
}

impl fmt::Display for Values {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let texts: Vec<String> = self.0.iter().map(ToString::to_string).collect();
        f.write_str(&texts.join(","))
    }
}

/// Every option of `hbid compare` (and of Python's `hbid.compare`), by the command line's names
/// with `_` for `-`. The record's options are those of `hbid identify` that say how to read it;
/// its signal defaults to the model's.
///
/// Defaults: the whole record as one range; `init` one period of the model's drive in samples,
/// at most a tenth of the range and at least 8 (the state is best set by a stretch as long as
/// the motion's own time scale, and must leave most of the range to score); the state fitted,
/// not given; the integrator's `rtol = 1e-10`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct CompareOptions {
    /// The time column of a file, by header name or 1-based position.
    #[serde(with = "optional_text")]
    pub time_col: Option<String>,
    /// The measured output's column (angle or displacement), by header name or 1-based position.
    #[serde(with = "optional_text")]
    pub angle_col: Option<String>,
    /// The sampling step, for records without time stamps (the first sample at t = 0).
    pub dt: Option<f64>,
    /// The columns of the coordinates of a system's record, in the order of the model's
    /// coordinates (default: the model's names).
    #[serde(with = "optional_text")]
    pub coords: Option<ColumnList>,
    /// The columns of the measured drives, for a model with terms in them (`p`, or a system's
    /// drives in the order of its names).
    #[serde(with = "optional_text")]
    pub drive_col: Option<ColumnList>,
    /// Replace isolated time-stamp glitches and every encoder spike.
    pub repair: bool,
    /// Keep every spike (a warning) instead of replacing them when few.
    pub no_repair: bool,
    /// Bridge every gap of at most this many missing samples by the cubic through its
    /// neighbours, in every column (see [`RecordOptions::bridge_gaps`]): a free run then goes on
    /// through it, driven by the bridged drives; the bridged samples, not measured, are not
    /// scored ([`RangeScore::bridged`] counts them).
    pub bridge_gaps: usize,
    /// Leave out every row with a missing value in a column read, as a logger's dropped row (see
    /// [`RecordOptions::skip_missing`]).
    pub skip_missing: bool,
    /// The columns of the coordinates' measured velocities: each piece's free run then starts
    /// from its first sample's measured state (positions and these velocities), every sample
    /// scored unless «init» says otherwise; with «x0» and «v0», every piece but the range's
    /// first.
    #[serde(with = "optional_text")]
    pub velocity_col: Option<ColumnList>,
    /// An angle on the circle or a displacement on the line (default: the model's).
    #[serde(with = "optional_text")]
    pub signal: Option<Domain>,
    /// What the sensor measured: the displacement, or its velocity or acceleration.
    #[serde(with = "text")]
    pub measured: Measured,
    /// The unit of the angles on the circle (and of their measured velocities): `rad`, `deg` or
    /// `counts:N`, converted to radians as they are read.
    #[serde(with = "text")]
    pub angle_unit: AngleUnit,
    /// The ranges of samples compared, each scored on its own (default: the whole record).
    pub range: Vec<SampleRange>,
    /// Samples at the start of each range (and after each gap) that set the initial state and
    /// are not scored.
    pub init: Option<usize>,
    /// The initial position, instead of fitting it (with `v0`; the first piece of each range):
    /// one per coordinate of a system, in its order.
    #[serde(with = "optional_text")]
    pub x0: Option<Values>,
    /// The initial velocity, in the record's time unit (with `x0`): one per coordinate.
    #[serde(with = "optional_text")]
    pub v0: Option<Values>,
    /// Relative tolerance of the integrator (the absolute one is rtol/10).
    pub rtol: f64,
    /// Leave out the record's first rows that a logger stamped before it settled to its rate,
    /// as an identification does: the ranges then count the samples of the grid from its first
    /// (by default the comparison covers the record from its first row; see the [module
    /// documentation](self)).
    pub skip_unsettled: bool,
}

impl Default for CompareOptions {
    fn default() -> Self {
        Self {
            time_col: None,
            angle_col: None,
            dt: None,
            coords: None,
            drive_col: None,
            repair: false,
            no_repair: false,
            bridge_gaps: 0,
            skip_missing: false,
            velocity_col: None,
            signal: None,
            measured: Measured::Displacement,
            angle_unit: AngleUnit::Radians,
            range: Vec::new(),
            init: None,
            x0: None,
            v0: None,
            rtol: CompareRequest::DEFAULT_RTOL,
            skip_unsettled: false,
        }
    }
}

/// A compare request, every option checked ([`CompareRequest::new`], or
/// [`CompareRequest::from_json`] from Python's keyword arguments).
#[derive(Debug, Clone, PartialEq)]
pub struct CompareRequest {
    options: CompareOptions,
    tolerances: Tolerances,
}

impl CompareRequest {
    /// The integrator's default relative tolerance.
    pub const DEFAULT_RTOL: f64 = pendulum_sim::Tolerances::DEFAULT_RTOL;
    /// The fewest samples that set an initial state.
    pub const MIN_INIT: usize = 2;

    /// Checks `options`.
    pub fn new(options: CompareOptions) -> Result<Self, OptionError> {
        let o = &options;
        if !(o.rtol.is_finite() && o.rtol > 0.0 && o.rtol <= 1e-2) {
            return Err(OptionError::value("rtol", o.rtol, "must be in (0, 0.01]"));
        }
        if let Some(init) = o.init
            && init < Self::MIN_INIT
        {
            return Err(OptionError::value(
                "init",
                init,
                format!("must be at least {}: a state has two components", Self::MIN_INIT),
            ));
        }
        match (&o.x0, &o.v0) {
            (Some(_), None) | (None, Some(_)) => {
                return Err(OptionError::new(
                    if o.x0.is_some() { "x0" } else { "v0" },
                    "give the initial state whole, «x0» with «v0», or neither to fit it to the record",
                ));
            }
            (Some(x), Some(v)) => {
                for (name, values) in [("x0", x), ("v0", v)] {
                    if let Some(bad) = values.0.iter().find(|v| !v.is_finite()) {
                        return Err(OptionError::value(name, bad, "the initial state must be finite"));
                    }
                }
                if x.0.len() != v.0.len() {
                    return Err(OptionError::new(
                        "v0",
                        "give as many initial velocities as positions («x0»), one per coordinate",
                    ));
                }
            }
            _ => {}
        }
        let record = o.record_options(Domain::Line);
        if o.measured != Measured::Displacement && o.signal == Some(Domain::Circle) {
            return Err(OptionError::value(
                "measured",
                o.measured,
                "a velocity or acceleration record is integrated to a displacement on the line: needs «signal=line»",
            ));
        }
        // The velocity columns are counted against the system's coordinates, known once the
        // model is read, unless the coordinates are named here.
        let velocities_counted = o.coords.is_some();
        RecordOptions {
            velocity_col: if velocities_counted {
                record.velocity_col.clone()
            } else {
                None
            },
            // Checked against the model's domains when the record is read.
            angle_unit: AngleUnit::Radians,
            ..record
        }
        .check_columns()?;
        let tolerances =
            Tolerances::new(o.rtol, o.rtol / 10.0).map_err(|e| OptionError::value("rtol", o.rtol, e))?;
        Ok(Self { options, tolerances })
    }

    /// A request from a JSON object of option names (Python's keyword arguments).
    pub fn from_json(value: serde_json::Value) -> Result<Self, OptionError> {
        Self::new(from_object::<CompareOptions>(value)?)
    }

    /// The options as given.
    pub fn options(&self) -> &CompareOptions {
        &self.options
    }
}

impl CompareOptions {
    /// The record's options of an identification that reads the record the same way.
    fn record_options(&self, signal: Domain) -> RecordOptions {
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
            signal: signal.into(),
            measured: self.measured,
            drive_period: None,
            drive_frequency: None,
            angle_unit: self.angle_unit,
        }
    }
}

/// The scores of one range.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RangeScore {
    /// The coordinate scored, for a system of several (each range has one entry per
    /// coordinate); absent for a record of one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub coordinate: Option<String>,
    /// The range compared, `[start, end)` samples of the grid.
    pub range: [usize; 2],
    /// Samples that set the initial state of each piece whose state is fitted (not scored); the
    /// piece that starts from a state given (`x0`, `v0`) or measured (`velocity_col`) scores all
    /// of its samples, unless `init` was given. A range whose pieces all start so has 0 (or the
    /// `init` given).
    pub init: usize,
    /// Samples scored.
    pub scored: usize,
    /// Samples of the range after each piece's `init` that were bridged into gaps
    /// (`bridge_gaps`): run through, not scored (they were not measured).
    pub bridged: usize,
    /// Root mean square of the measured output less the simulated one, in the record's unit
    /// (`None` when the model's run stopped before the range's end).
    pub rmse: Option<f64>,
    /// The RMSE over the standard deviation of the measured output.
    pub nrmse: Option<f64>,
    /// `100 (1 − ‖y − ŷ‖ / ‖y − ȳ‖)`.
    pub fit_percent: Option<f64>,
    /// The largest difference.
    pub max_error: Option<f64>,
    /// The initial state `(x, x')` of each piece run, and the RMS of its fit to the first samples
    /// (0 for a given state).
    pub initial_states: Vec<[f64; 3]>,
    /// Pieces of the range too short to run (at most `init` samples), not scored.
    pub skipped_pieces: usize,
    /// Where and why the model's run stopped, if it did.
    pub stopped: Option<String>,
}

/// The times of a compared record's samples: the grid's `t0 + n · dt`, after the rows a logger
/// stamped before it settled, at their own stamps, when they are compared.
#[derive(Debug, Clone, PartialEq)]
struct Clock {
    /// The stamps of the rows before the grid (empty when there are none).
    lead: Vec<f64>,
    t0: f64,
    dt: f64,
}

impl Clock {
    /// The time of sample `i`.
    fn time(&self, i: usize) -> f64 {
        match self.lead.get(i) {
            Some(&t) => t,
            None => self.t0 + (i - self.lead.len()) as f64 * self.dt,
        }
    }

    /// The times of the samples `range`.
    fn times(&self, range: std::ops::Range<usize>) -> Vec<f64> {
        range.map(|i| self.time(i)).collect()
    }

    /// Whether sample `start` is before the grid (its run is not on an even grid).
    fn uneven(&self, start: usize) -> bool {
        start < self.lead.len()
    }
}

/// The record of `source` as compared: conditioned ([`condition_source`]), and, unless
/// `skip_unsettled`, with the rows a logger stamped before it settled ahead of its grid, their
/// note (that they are left out) replaced by [`Notice::UnevenStart`].
fn compared_record(
    source: Source<'_>,
    record: &RecordOptions,
    skip_unsettled: bool,
    observer: &mut dyn Observer,
) -> Result<(GridData, Clock), RunError> {
    /// Passes everything on but the note of a left-out start, which it keeps.
    struct Relay<'o> {
        inner: &'o mut dyn Observer,
        held: Option<Notice>,
    }
    impl Observer for Relay<'_> {
        fn stage(&mut self, stage: Stage) {
            self.inner.stage(stage);
        }
        fn progress(&mut self, done: usize, total: usize) {
            self.inner.progress(done, total);
        }
        fn notice(&mut self, notice: &Notice) {
            match notice {
                Notice::Record(hb_record::prepare::Note::Unsettled(run))
                    if run.end == hb_record::input::RecordEnd::Start && self.held.is_none() =>
                {
                    self.held = Some(notice.clone());
                }
                _ => self.inner.notice(notice),
            }
        }
    }
    let mut relay = Relay {
        inner: observer,
        held: None,
    };
    let mut grid = condition_source(source, record, &mut relay)?;
    let Relay {
        inner: observer,
        held,
    } = relay;
    let lead = grid.lead_in.take().filter(|_| !skip_unsettled);
    let Some(lead) = lead else {
        if let Some(held) = held {
            observer.notice(&held);
        }
        let clock = Clock {
            lead: Vec::new(),
            t0: grid.t0,
            dt: grid.dt,
        };
        return Ok((grid, clock));
    };
    observer.notice(&Notice::UnevenStart(lead.run.clone()));
    let k = lead.len();
    let ahead = |first: &[f64], rest: &mut Vec<f64>| {
        let mut all = Vec::with_capacity(first.len() + rest.len());
        all.extend_from_slice(first);
        all.append(rest);
        *rest = all;
    };
    ahead(&lead.x, &mut grid.x);
    for (c, first) in grid.others.iter_mut().zip(&lead.others) {
        ahead(first, &mut c.x);
    }
    for (d, first) in grid.drives.iter_mut().zip(&lead.drives) {
        ahead(first, d);
    }
    for (v, first) in grid.velocities.iter_mut().zip(&lead.velocities) {
        ahead(first, v);
    }
    // The grid's first piece starts at its sample 0: the rows before it join it.
    for (i, piece) in grid.pieces.iter_mut().enumerate() {
        *piece = if i == 0 { 0 } else { piece.start + k }..piece.end + k;
    }
    for b in &mut grid.bridged {
        *b = b.start + k..b.end + k;
    }
    let clock = Clock {
        lead: lead.t,
        t0: grid.t0,
        dt: grid.dt,
    };
    Ok((grid, clock))
}

/// One piece of a range as run: the measured and simulated output at each of its samples.
#[derive(Debug, Clone, PartialEq)]
pub struct RunPiece {
    /// The grid's index of the first sample.
    pub start: usize,
    /// The times.
    pub t: Vec<f64>,
    /// The measured output: NaN at the samples bridged into gaps (`bridge_gaps`), which were
    /// not measured (the run goes on through them; they are not scored).
    pub measured: Vec<f64>,
    /// The simulated position (on the circle, on the turn of the measured angle: unwrapped
    /// along the run, then shifted by whole turns).
    pub x: Vec<f64>,
    /// The simulated velocity.
    pub v: Vec<f64>,
    /// Samples at the start that set the initial state.
    pub init: usize,
}

/// What `hbid compare` reports; its serialisation is the JSON of `hbid compare --json`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CompareReport {
    /// The record's samples that hold data (those bridged into gaps among them).
    pub samples: usize,
    /// The sampling step (of the grid).
    pub step: f64,
    /// The record's first rows, stamped before its logger settled to its rate, that the free run
    /// passes at their own stamps: the first samples of the ranges (0 when there are none, or
    /// with `skip_unsettled`).
    pub unsettled_rows: usize,
    /// Circle or line.
    #[serde(serialize_with = "text::serialize")]
    pub signal: Domain,
    /// Whether the model was driven by the record's measured drive.
    pub measured_drive: bool,
    /// The coordinates of a system, in order (absent for a record of one).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub coordinates: Vec<String>,
    /// One score per range, in the order given (for a system one per range and coordinate, the
    /// coordinates of each range in order).
    pub ranges: Vec<RangeScore>,
    /// The runs of each entry of `ranges`, piece by piece (for plots and files; not in the
    /// JSON).
    #[serde(skip)]
    pub runs: Vec<Vec<RunPiece>>,
    /// The domain of each coordinate of a system, in order (empty for a record of one: its
    /// `signal`; not in the JSON, which has `signal`).
    #[serde(skip)]
    pub domains: Vec<Domain>,
}

/// Runs `model` freely on the ranges of the record of `source` and scores it against the
/// measurement (see the [module documentation](self)).
///
/// Errors: the record's ([`RunError::Read`], [`RunError::Prepare`]); an option that does not fit
/// the model or the record (a model on the circle and a record on the line, a model in `p` and no
/// drive column, a drive column for a model without `p`, a range past the record's end); a
/// simulation that cannot start ([`RunError::Simulation`]).
pub fn compare(
    system: &IdentifiedSystem,
    source: Source<'_>,
    request: &CompareRequest,
    observer: &mut dyn Observer,
) -> Result<CompareReport, RunError> {
    match system.equations() {
        // One coordinate in the names of one (`x`, the drive `p`); one with drives of their own
        // names (two measured drives) is run as the system it is.
        [model] if system.is_one_model() => compare_one(model, source, request, observer),
        _ => compare_system(system, source, request, observer),
    }
}

/// [`compare`] of a model of one coordinate.
fn compare_one(
    model: &IdentifiedModel,
    source: Source<'_>,
    request: &CompareRequest,
    observer: &mut dyn Observer,
) -> Result<CompareReport, RunError> {
    let o = &request.options;
    if let Some(x0) = &o.x0
        && x0.one().is_none()
    {
        return Err(
            OptionError::value("x0", x0, "the model has one coordinate: give one initial state").into(),
        );
    }
    if let Some(coords) = &o.coords
        && coords.len() != 1
    {
        return Err(OptionError::value(
            "coords",
            coords,
            format!(
                "the model has one coordinate, the record's {} are named: name its one column («angle_col»)",
                coords.len()
            ),
        )
        .into());
    }
    // Before the signal's check, which would send the user to «signal» and back.
    crate::integrated::check_model(model, o.measured)?;
    let domain = o.signal.unwrap_or_else(|| model.domain());
    if domain != model.domain() {
        return Err(OptionError::value(
            "signal",
            domain,
            format!(
                "the model's signal is {}: compare it with a record of the same kind",
                model.domain()
            ),
        )
        .into());
    }
    // A drive given as an array is Python's `drive=`, even when its name comes with it.
    let named = !matches!(source, Source::Arrays { .. });
    // A velocity or acceleration record is read as measured and integrated here, with the
    // constants the model's equation holds best with (`integrated`); its first rows stamped
    // before the logger settled are left out (a run through them would start before the
    // integral does).
    let integrate = o.measured != Measured::Displacement;
    let mut options = o.record_options(domain);
    options.measured = Measured::Displacement;
    let (mut grid, clock) = compared_record(source, &options, o.skip_unsettled || integrate, observer)?;
    let measured_drive = check_drive(model, &grid, named)?;
    if integrate {
        let found = crate::integrated::integrate(model, &mut grid, o.measured)?;
        if let (Some(_), Some(&(start, end))) = (&o.x0, found.left_out.first()) {
            return Err(OptionError::new(
                "x0",
                format!(
                    "is the state at a range's first sample, but pieces too short to integrate were left out \
                     (the first {start}..{end}), and a range's first piece may now start after its first sample: \
                     let each piece's state be fitted («init»), or give a record whose pieces are each at least {} \
                     samples",
                    crate::integrated::MIN_SAMPLES
                ),
            )
            .into());
        }
        for notice in crate::integrated::notices(o.measured, &found) {
            observer.notice(&notice);
        }
    }
    observer.stage(Stage::Simulate);
    let len = grid.x.len();
    let ranges: Vec<std::ops::Range<usize>> = if o.range.is_empty() {
        vec![SampleRange::ALL.on(len)?]
    } else {
        o.range.iter().map(|r| r.on(len)).collect::<Result<_, _>>()?
    };
    one_start_for_a_given_state(o, &ranges)?;
    let period = std::f64::consts::TAU / model.drive_angular_frequency() / grid.dt;
    let mut scores = Vec::with_capacity(ranges.len());
    let mut runs = Vec::with_capacity(ranges.len());
    let total: usize = ranges.iter().map(|r| r.len()).sum();
    let mut done = 0;
    // A state measured sets every piece's start, a state given the first piece's: their samples
    // are all scored (`RunPiece::init` 0); the pieces after a gap fit theirs.
    let measured_state = o.x0.is_none() && !grid.velocities.is_empty();
    for range in &ranges {
        let init = o.init.unwrap_or_else(|| {
            if measured_state {
                0
            } else {
                default_init(period, range.len())
            }
        });
        let (score, pieces) = run_range(model, &grid, &clock, range.clone(), init, request, &mut |run| {
            observer.progress(done + run, total);
        })?;
        if score.scored == 0 && score.bridged > 0 && score.stopped.is_none() {
            return Err(all_bridged(range, init, score.bridged).into());
        }
        if score.scored == 0 && score.stopped.is_none() {
            return Err(nothing_left(range, init, &grid.pieces).into());
        }
        done += range.len();
        observer.progress(done, total);
        scores.push(score);
        runs.push(pieces);
    }
    observer.stage(Stage::Compare);
    Ok(CompareReport {
        samples: grid.pieces.iter().map(|p| p.len()).sum(),
        step: grid.dt,
        unsettled_rows: clock.lead.len(),
        signal: domain,
        measured_drive,
        coordinates: Vec::new(),
        ranges: scores,
        runs,
        domains: Vec::new(),
    })
}

/// Where each of a record's columns `given` (the `option` naming the system's `what`) goes among
/// the system's `names`, and the list under those names: by name when every one has one of the
/// system's names (in any order); in the order given when none has and none was named
/// (`NAME=COLUMN`) otherwise, each then called by the system's name of its place. A name the
/// system does not have, or a list of both kinds, is refused: a name would otherwise be taken for
/// another coordinate by its place.
fn placed(
    option: &'static str,
    what: &str,
    given: &ColumnList,
    names: &[String],
) -> Result<(ColumnList, Vec<usize>), OptionError> {
    let found: Vec<Option<usize>> = given
        .names()
        .iter()
        .map(|g| names.iter().position(|n| n == g))
        .collect();
    if found.iter().all(Option::is_some) {
        return Ok((given.clone(), found.into_iter().flatten().collect()));
    }
    let entries = || given.names().iter().zip(given.columns()).zip(&found);
    if let Some(((name, _), _)) = entries().find(|((n, c), f)| f.is_none() && n != c) {
        return Err(OptionError::value(
            option,
            given,
            format!(
                "'{name}' is not one of the system's {what} ({}): name each as the system does, or give the \
                 columns alone, in that order",
                names.join(", ")
            ),
        ));
    }
    if let Some(((known, _), _)) = entries().find(|(_, f)| f.is_some()) {
        let ((stray, _), _) = entries().find(|(_, f)| f.is_none()).expect("not all found");
        return Err(OptionError::value(
            option,
            given,
            format!(
                "'{known}' is one of the system's {what} and '{stray}' is not: name each as the system does \
                 ({}; NAME=COLUMN), or none (the columns are then taken in that order)",
                names.join(", ")
            ),
        ));
    }
    let renamed = names
        .iter()
        .zip(given.columns())
        .map(|(n, c)| format!("{n}={c}"))
        .collect::<Vec<_>>()
        .join(",")
        .parse::<ColumnList>()
        .map_err(|e| OptionError::new(option, e))?;
    Ok((renamed, (0..given.len()).collect()))
}

/// The measured velocities' columns `given` in the order of the record's coordinates, the `k`-th
/// of which is the system's `coordinate_of[k]`-th: by name when named (`NAME=COLUMN`, each one of
/// the system's coordinate `names`), as given otherwise (in the order of `coords`). A name that is
/// not a coordinate's is refused ([`placed`]'s rule), not taken for a coordinate by its place.
fn velocities_in_record_order(
    given: &ColumnList,
    names: &[String],
    coordinate_of: &[usize],
) -> Result<ColumnList, OptionError> {
    let named = given.names().iter().zip(given.columns()).any(|(n, c)| n != c);
    if !named || given.len() != coordinate_of.len() {
        return Ok(given.clone());
    }
    let (_, by_name) = placed("velocity_col", "coordinates", given, names)?;
    coordinate_of
        .iter()
        .map(|c| {
            let k = by_name.iter().position(|b| b == c).expect("a permutation");
            format!("{}={}", given.names()[k], given.columns()[k])
        })
        .collect::<Vec<_>>()
        .join(",")
        .parse::<ColumnList>()
        .map_err(|e| OptionError::new("velocity_col", e))
}

/// That the columns a system was saved with (positions, where it was identified by them) are not
/// the wrong ones in the record of `header`: a header that names the system's coordinates (or, `drives`,
/// its drives) elsewhere than at the saved columns is refused, rather than its columns taken by
/// their place. `record` chooses the columns as saved.
fn saved_columns_named_elsewhere(
    header: &hb_record::input::Header,
    record: &RecordOptions,
    names: &hb_model::Names,
    saved: &hb_model::Columns,
    drives: bool,
) -> Result<(), RunError> {
    let (option, own, columns) = if drives {
        ("drive_col", names.drives(), &saved.drives)
    } else {
        ("coords", names.coordinates(), &saved.coordinates)
    };
    if columns == own {
        return Ok(());
    }
    let list = |v: &[String]| {
        v.join(",")
            .parse::<ColumnList>()
            .map_err(|e| OptionError::new(option, e))
    };
    let by_name = if drives {
        RecordOptions {
            drive_col: Some(list(own)?),
            velocity_col: None,
            ..record.clone()
        }
    } else {
        RecordOptions {
            coords: Some(list(own)?),
            drive_col: None,
            velocity_col: None,
            ..record.clone()
        }
    };
    let (Some(at_saved), Some(_)) = (
        header.chosen(&record.read_options()?),
        header.chosen(&by_name.read_options()?),
    ) else {
        return Ok(());
    };
    let from = if drives { names.coordinates().len() } else { 0 };
    let there = &at_saved[from..(from + own.len()).min(at_saved.len())];
    if there == own {
        return Ok(());
    }
    Err(OptionError::new(
        option,
        format!(
            "the model read {} from the columns {} where it was identified; this record's header names {} there \
             and has columns named {}: choose them («{option}» {} picks them by name)",
            own.join(", "),
            columns.join(", "),
            there.join(", "),
            own.join(", "),
            own.join(","),
        ),
    )
    .into())
}

/// Puts a record's coordinates (with their measured velocities) and drives, read in the order
/// their columns were given, in the system's order: the `k`-th read is the system's
/// `coordinate_of[k]`-th, the `k`-th drive its `drive_of[k]`-th.
fn in_system_order(grid: &mut GridData, coordinate_of: &[usize], drive_of: &[usize]) {
    fn permute<T>(items: Vec<T>, to: &[usize]) -> Vec<T> {
        let mut slots: Vec<Option<T>> = std::iter::repeat_with(|| None).take(items.len()).collect();
        for (item, &k) in items.into_iter().zip(to) {
            slots[k] = Some(item);
        }
        slots.into_iter().map(|s| s.expect("a permutation")).collect()
    }
    if coordinate_of.iter().enumerate().any(|(k, &c)| k != c) {
        let mut channels = vec![Channel {
            x: std::mem::take(&mut grid.x),
            domain: grid.domain,
        }];
        channels.append(&mut grid.others);
        let mut channels = permute(channels, coordinate_of).into_iter();
        let first = channels.next().expect("a coordinate");
        (grid.x, grid.domain) = (first.x, first.domain);
        grid.others = channels.collect();
        if !grid.velocities.is_empty() {
            grid.velocities = permute(std::mem::take(&mut grid.velocities), coordinate_of);
        }
    }
    if drive_of.iter().enumerate().any(|(k, &d)| k != d) {
        grid.drives = permute(std::mem::take(&mut grid.drives), drive_of);
    }
}

/// [`compare`] of a system of several coordinates: the record's columns are the system's
/// coordinates and drives by name unless `coords` and `drive_col` say otherwise (given with the
/// system's names, in any order, they are put in the system's order by name); each range is
/// run piece by piece from the state given, or fitted to every coordinate's first `init`
/// samples ([`pendulum_sim::multi::fit_initial_state`]); each coordinate is scored on its own.
fn compare_system(
    system: &IdentifiedSystem,
    source: Source<'_>,
    request: &CompareRequest,
    observer: &mut dyn Observer,
) -> Result<CompareReport, RunError> {
    let o = &request.options;
    let names = system.names();
    let n = system.coordinates();
    let domains = system.domains().to_vec();
    if let Some(signal) = o.signal
        && domains.iter().any(|&d| d != signal)
    {
        return Err(OptionError::value(
            "signal",
            signal,
            "the system's coordinates have their own domains: leave out «signal»",
        )
        .into());
    }
    if let Some(x0) = &o.x0
        && x0.0.len() != n
    {
        return Err(OptionError::value(
            "x0",
            x0,
            format!("give one initial position per coordinate of the system ({n})"),
        )
        .into());
    }
    // The system's own columns, each under the name its terms give it.
    // What reads one coordinate's record is refused, not ignored (a system of one coordinate
    // reads its angle's column from «angle_col» too).
    if o.angle_col.is_some() && (n > 1 || o.coords.is_some()) {
        return Err(OptionError::new(
            "angle_col",
            format!(
                "reads the angle of a model of one coordinate; this one has {n} ({}): give their columns with «coords»",
                names.coordinates().join(", ")
            ),
        )
        .into());
    }
    if o.measured != Measured::Displacement {
        return Err(OptionError::new(
            "measured",
            "is for a record of one coordinate, not a system of several («coords»)",
        )
        .into());
    }
    let columns = system.columns();
    let as_columns = |names: &[String], columns: &[String]| {
        names
            .iter()
            .zip(columns)
            .map(|(n, c)| format!("{n}={c}"))
            .collect::<Vec<_>>()
            .join(",")
            .parse::<ColumnList>()
            .map_err(|e| OptionError::new("coords", e))
    };
    let coords = match (&o.coords, &o.angle_col) {
        (Some(c), _) => c.clone(),
        (None, Some(angle)) => as_columns(names.coordinates(), std::slice::from_ref(angle))?,
        (None, None) => as_columns(names.coordinates(), &columns.coordinates)?,
    };
    if coords.len() != n {
        return Err(OptionError::value(
            "coords",
            &coords,
            format!(
                "the system has {n} coordinates ({})",
                names.coordinates().join(", ")
            ),
        )
        .into());
    }
    // The system's coordinate each of the record's is, by its name when it has the system's.
    // One coordinate saved without its column (identified from the record's default angle
    // column) is read from the record's default column again.
    let default_angle =
        n == 1 && o.coords.is_none() && o.angle_col.is_none() && columns.coordinates == names.coordinates();
    let (coords, coordinate_of) = match default_angle {
        true => (None, vec![0]),
        false => {
            let (coords, of) = placed("coords", "coordinates", &coords, names.coordinates())?;
            (Some(coords), of)
        }
    };
    let velocity_col = match &o.velocity_col {
        Some(v) => Some(velocities_in_record_order(
            v,
            names.coordinates(),
            &coordinate_of,
        )?),
        None => None,
    };
    let drives_needed = system.has_measured_drive();
    let drive_col = match (&o.drive_col, drives_needed) {
        (Some(d), true) => Some(d.clone()),
        (None, true) => Some(as_columns(names.drives(), &columns.drives)?),
        (Some(_), false) => {
            return Err(OptionError::new(
                "drive_col",
                "the system has no term in a measured drive: it runs on its own drive, leave out «drive_col»",
            )
            .into());
        }
        (None, false) => None,
    };
    if let Some(d) = &drive_col
        && d.len() != names.drives().len()
    {
        return Err(OptionError::value(
            "drive_col",
            d,
            format!(
                "the system reads {} drive(s) ({})",
                names.drives().len(),
                names.drives().join(", ")
            ),
        )
        .into());
    }
    let (drive_col, drive_of) = match drive_col {
        Some(d) => {
            let (d, of) = placed("drive_col", "drives", &d, names.drives())?;
            (Some(d), of)
        }
        None => (None, Vec::new()),
    };
    let record = RecordOptions {
        time_col: o.time_col.clone(),
        angle_col: None,
        coords,
        dt: o.dt,
        drive_col,
        repair: o.repair,
        no_repair: o.no_repair,
        bridge_gaps: o.bridge_gaps,
        skip_missing: o.skip_missing,
        velocity_col,
        signal: coordinate_of
            .iter()
            .map(|&c| domains[c].to_string())
            .collect::<Vec<_>>()
            .join(",")
            .parse()
            .map_err(|e: String| OptionError::new("signal", e))?,
        measured: o.measured,
        angle_unit: o.angle_unit,
        drive_period: None,
        drive_frequency: None,
    };
    // A text file's header, read once for both checks.
    if let Source::Path(path) = &source
        && (o.coords.is_none() || o.drive_col.is_none() && drives_needed)
        && let Some(header) = hb_record::input::Header::of(path)
    {
        if o.coords.is_none() && !default_angle {
            saved_columns_named_elsewhere(&header, &record, names, &columns, false)?;
        }
        if o.drive_col.is_none() && drives_needed {
            saved_columns_named_elsewhere(&header, &record, names, &columns, true)?;
        }
    }
    let (mut grid, clock) = compared_record(source, &record, o.skip_unsettled, observer)?;
    in_system_order(&mut grid, &coordinate_of, &drive_of);
    observer.stage(Stage::Simulate);
    let len = grid.x.len();
    let ranges: Vec<std::ops::Range<usize>> = if o.range.is_empty() {
        vec![SampleRange::ALL.on(len)?]
    } else {
        o.range.iter().map(|r| r.on(len)).collect::<Result<_, _>>()?
    };
    one_start_for_a_given_state(o, &ranges)?;
    let period = std::f64::consts::TAU / system.drive_angular_frequency() / grid.dt;
    let given = o.x0.clone().zip(o.v0.clone());
    let columns: Vec<&[f64]> = std::iter::once(grid.x.as_slice())
        .chain(grid.others.iter().map(|c| c.x.as_slice()))
        .collect();
    let mut scores = Vec::with_capacity(ranges.len() * n);
    let mut runs = Vec::with_capacity(ranges.len() * n);
    let total: usize = ranges.iter().map(|r| r.len()).sum();
    let mut done = 0;
    let measured_state = given.is_none() && !grid.velocities.is_empty();
    for range in &ranges {
        // A state measured sets every piece's start, a state given the first piece's: their
        // samples are all scored (`RunPiece::init` 0); the pieces after a gap fit theirs,
        // unless measured.
        let init = o.init.unwrap_or_else(|| {
            if measured_state {
                0
            } else {
                default_init(period, range.len())
            }
        });
        let mut pieces: Vec<Vec<RunPiece>> = vec![Vec::new(); n];
        let (mut skipped, mut stopped) = (0, None);
        let mut states = Vec::new();
        let mut first_piece = true;
        for piece in &grid.pieces {
            let (start, end) = (piece.start.max(range.start), piece.end.min(range.end));
            if start >= end {
                continue;
            }
            // The state given is the state at the range's first sample (or, for a range that
            // starts in a gap, at the first after it).
            let state_given = given.as_ref().filter(|_| first_piece);
            first_piece = false;
            // A piece that starts from a state given or measured scores every sample (unless
            // «init» says otherwise); one whose state is fitted, all but its first `init`.
            let measured_state = state_given.is_none() && !grid.velocities.is_empty();
            let init = match state_given.is_some() || measured_state {
                true => o.init.unwrap_or(0),
                false => init,
            };
            // A fit needs a sample beyond its own; a measured state needs none.
            let needed = if measured_state { init } else { init.max(1) };
            if state_given.is_none() && end - start <= needed {
                skipped += 1;
                continue;
            }
            let times = clock.times(start..end);
            let uneven = clock.uneven(start);
            let driven = match drives_needed {
                true => system.clone().with_measured_drives(
                    grid.drives
                        .iter()
                        .map(|p| match uneven {
                            true => MeasuredDrive::at_stamps(p[start..end].to_vec(), &times),
                            false => MeasuredDrive::new(p[start..end].to_vec(), times[0], grid.dt),
                        })
                        .collect::<Result<Vec<_>, _>>()?,
                )?,
                false => system.clone(),
            };
            let measured: Vec<&[f64]> = columns.iter().map(|c| &c[start..end]).collect();
            let state = match state_given {
                Some((x, v)) => MultiState::new(&x.0, &v.0).map(|s| (s, 0.0)),
                None if measured_state => {
                    let q: Vec<f64> = measured.iter().map(|m| m[0]).collect();
                    let v: Vec<f64> = grid.velocities.iter().map(|v| v[start]).collect();
                    MultiState::new(&q, &v).map(|s| (s, 0.0))
                }
                None => {
                    let first: Vec<&[f64]> = measured.iter().map(|m| &m[..init]).collect();
                    multi::fit_initial_state(&driven, &first, &domains, &times[..init], request.tolerances)
                        .map(|fit| (fit.state, fit.rms))
                }
            };
            let run = match state {
                Ok((state, rms)) => {
                    let mut row: Vec<f64> = state.q().to_vec();
                    row.extend_from_slice(state.v());
                    row.push(rms);
                    states.push(row);
                    // The samples run so far, of all the ranges', told as they go.
                    let before = done + (start - range.start);
                    multi::free_run_reporting(&driven, &times, &state, request.tolerances, &mut |run| {
                        observer.progress(before + run, total);
                    })?
                }
                Err(why) => pendulum_sim::MultiFreeRun {
                    q: vec![vec![f64::NAN; times.len()]; n],
                    v: vec![vec![f64::NAN; times.len()]; n],
                    stopped: Some(why),
                },
            };
            if let (None, Some(why)) = (&stopped, &run.stopped) {
                stopped = Some(format!("the system's run from sample {start} stopped: {why}"));
            }
            for (c, (q, v)) in run.q.into_iter().zip(run.v).enumerate() {
                let y = measured[c];
                let mut x = q;
                if domains[c] == Domain::Circle {
                    for (xi, yi) in x.iter_mut().zip(y) {
                        if xi.is_finite() {
                            *xi = yi + wrap(*xi - yi);
                        }
                    }
                }
                pieces[c].push(RunPiece {
                    start,
                    t: times.clone(),
                    measured: unmeasured(y, start, &grid.bridged),
                    x,
                    v,
                    init,
                });
            }
        }
        if pieces[0].is_empty() && stopped.is_none() {
            return Err(nothing_left(range, init, &grid.pieces).into());
        }
        let after_init = |measured: bool| -> usize {
            pieces[0]
                .iter()
                .map(|p| {
                    let rest = &p.measured[p.init.min(p.measured.len())..];
                    rest.iter().filter(|y| y.is_nan() != measured).count()
                })
                .sum()
        };
        if after_init(true) == 0 && after_init(false) > 0 && stopped.is_none() {
            return Err(all_bridged(range, init, after_init(false)).into());
        }
        for (c, coordinate_pieces) in pieces.into_iter().enumerate() {
            let states_c: Vec<[f64; 3]> = states.iter().map(|s| [s[c], s[n + c], s[2 * n]]).collect();
            let mut entry = score(
                &coordinate_pieces,
                domains[c],
                [range.start, range.end],
                init,
                skipped,
                states_c,
                stopped.clone(),
            );
            entry.coordinate = Some(names.coordinates()[c].clone());
            scores.push(entry);
            runs.push(coordinate_pieces);
        }
        done += range.len();
        observer.progress(done, total);
    }
    observer.stage(Stage::Compare);
    Ok(CompareReport {
        samples: grid.pieces.iter().map(|p| p.len()).sum(),
        step: grid.dt,
        unsettled_rows: clock.lead.len(),
        signal: domains[0],
        measured_drive: drives_needed,
        coordinates: names.coordinates().to_vec(),
        ranges: scores,
        runs,
        domains: domains.clone(),
    })
}

/// The default samples of the initial state: one drive period (see [`CompareOptions`]).
pub(crate) fn default_init(period_samples: f64, range: usize) -> usize {
    let period = if period_samples.is_finite() {
        period_samples.round().min(1e9) as usize
    } else {
        8
    };
    period.min(range / 10).max(8)
}

/// Checks that the record's drive and the model agree: a drive column for a model in `p`, none
/// for a model without. `named`: the record is a file whose drive is named by `drive_col`, not
/// samples given with their drive (Python's `drive=`), as the messages say. Returns whether the
/// model runs on the record's drive.
fn check_drive(model: &IdentifiedModel, grid: &GridData, named: bool) -> Result<bool, RunError> {
    match (grid.drives.first(), model.form().has_measured_drive()) {
        (Some(_), true) => Ok(true),
        (None, true) if named => Err(OptionError::new(
            "drive_col",
            "the model has terms in the measured drive p: name the record's drive column with «drive_col=»",
        )
        .into()),
        (None, true) => Err(OptionError::new(
            "drive",
            "the model has terms in the measured drive p: give its samples with «drive=»",
        )
        .into()),
        (Some(_), false) => Err(OptionError::new(
            if named { "drive_col" } else { "drive" },
            format!(
                "the model has no term in the measured drive p: it runs on its own drive, leave out «{}»",
                if named { "drive_col" } else { "drive" }
            ),
        )
        .into()),
        _ => Ok(false),
    }
}

/// `model` driven by the record's drive over one piece `[start, end)` of its grid: the spline
/// through that piece's samples alone, so that it ends at the piece's ends and no gap's NaN
/// reaches it.
pub(crate) fn driven_on(
    model: &IdentifiedModel,
    grid: &GridData,
    start: usize,
    end: usize,
) -> Result<IdentifiedModel, RunError> {
    match grid.drives.first() {
        Some(p) if model.form().has_measured_drive() => {
            let signal =
                MeasuredDrive::new(p[start..end].to_vec(), grid.t0 + start as f64 * grid.dt, grid.dt)?;
            Ok(model.clone().with_measured_drive(signal)?)
        }
        _ => Ok(model.clone()),
    }
}

/// `model` driven by the record's drive over the samples `[start, start + times.len())`, at the
/// uneven `times` of a logger's first rows: [`driven_on`] off the grid.
fn driven_at(
    model: &IdentifiedModel,
    grid: &GridData,
    start: usize,
    times: &[f64],
) -> Result<IdentifiedModel, RunError> {
    match grid.drives.first() {
        Some(p) if model.form().has_measured_drive() => {
            let signal = MeasuredDrive::at_stamps(p[start..start + times.len()].to_vec(), times)?;
            Ok(model.clone().with_measured_drive(signal)?)
        }
        _ => Ok(model.clone()),
    }
}

/// The difference of a simulated and a measured output, as the domain measures it.
pub(crate) fn difference(domain: Domain, simulated: f64, measured: f64) -> f64 {
    match domain {
        Domain::Circle => wrap(simulated - measured),
        Domain::Line => simulated - measured,
    }
}

/// One range run piece by piece and scored.
fn run_range(
    model: &IdentifiedModel,
    grid: &GridData,
    clock: &Clock,
    range: std::ops::Range<usize>,
    init: usize,
    request: &CompareRequest,
    progress: &mut dyn FnMut(usize),
) -> Result<(RangeScore, Vec<RunPiece>), RunError> {
    let o = &request.options;
    let domain = grid.domain;
    let mut pieces = Vec::new();
    let mut skipped = 0;
    let mut stopped = None;
    let mut states = Vec::new();
    let mut first_piece = true;
    for piece in &grid.pieces {
        let (start, end) = (piece.start.max(range.start), piece.end.min(range.end));
        if start >= end {
            continue;
        }
        // The state given is the state at the range's first sample (or, for a range that starts
        // in a gap, at the first after it): its piece is run whatever its length.
        let given = match (
            o.x0.as_ref().and_then(Values::one),
            o.v0.as_ref().and_then(Values::one),
        ) {
            (Some(x), Some(v)) if first_piece => Some([x, v]),
            _ => None,
        };
        first_piece = false;
        let measured_state = given.is_none() && !grid.velocities.is_empty();
        // A piece that starts from a state given or measured scores every sample (unless
        // «init» says otherwise); one whose state is fitted, all but its first `init`.
        let init = match given.is_some() || measured_state {
            true => o.init.unwrap_or(0),
            false => init,
        };
        if given.is_none() && end - start <= init {
            skipped += 1;
            continue;
        }
        let y = &grid.x[start..end];
        let t0 = clock.time(start);
        let times = clock.times(start..end);
        let uneven = clock.uneven(start);
        let model = &match uneven {
            true => driven_at(model, grid, start, &times)?,
            false => driven_on(model, grid, start, end)?,
        };
        // Off the grid, the run of one coordinate is that of the system of one coordinate,
        // sampled at the stamps.
        let one = OneCoordinate(model);
        let state = match given {
            Some(state) => Ok((state, 0.0)),
            None if measured_state => Ok(([y[0], grid.velocities[0][start]], 0.0)),
            None if uneven => {
                multi::fit_initial_state(&one, &[&y[..init]], &[domain], &times[..init], request.tolerances)
                    .map(|fit| ([fit.state.q()[0], fit.state.v()[0]], fit.rms))
            }
            None => fit_initial_state(model, &y[..init], t0, grid.dt, domain, request.tolerances)
                .map(|fit| (fit.state, fit.rms)),
        };
        let run = match state {
            Ok((state, fit_rms)) => {
                states.push([state[0], state[1], fit_rms]);
                // The range's samples run so far, told as they go.
                let before = start - range.start;
                let progress = &mut |run: usize| progress(before + run);
                if uneven {
                    let run = multi::free_run_reporting(
                        &one,
                        &times,
                        &MultiState::new(&[state[0]], &[state[1]])?,
                        request.tolerances,
                        progress,
                    )?;
                    let (mut q, mut v) = (run.q, run.v);
                    pendulum_sim::FreeRun {
                        x: q.swap_remove(0),
                        v: v.swap_remove(0),
                        stopped: run.stopped,
                    }
                } else {
                    free_run_reporting(model, t0, grid.dt, y.len(), state, request.tolerances, progress)?
                }
            }
            // No state from which the model runs through the first samples: the piece has no run.
            Err(why) => pendulum_sim::FreeRun {
                x: vec![f64::NAN; y.len()],
                v: vec![f64::NAN; y.len()],
                stopped: Some(why),
            },
        };
        if let (None, Some(why)) = (&stopped, &run.stopped) {
            stopped = Some(format!("the model's run from sample {start} stopped: {why}"));
        }
        let mut x = run.x;
        if domain == Domain::Circle {
            // On the turn of each measured sample, so that plots and files read as the record.
            for (xi, yi) in x.iter_mut().zip(y) {
                if xi.is_finite() {
                    *xi = yi + wrap(*xi - yi);
                }
            }
        }
        pieces.push(RunPiece {
            start,
            t: times,
            measured: unmeasured(y, start, &grid.bridged),
            x,
            v: run.v,
            init,
        });
    }
    let score = score(
        &pieces,
        domain,
        [range.start, range.end],
        init,
        skipped,
        states,
        stopped,
    );
    Ok((score, pieces))
}

/// The error of a range that `init` samples setting the state leave nothing to score, its
/// samples in the record's `pieces` between gaps.
fn nothing_left(
    range: &std::ops::Range<usize>,
    init: usize,
    pieces: &[std::ops::Range<usize>],
) -> OptionError {
    let within = pieces
        .iter()
        .filter(|p| p.start < range.end && p.end > range.start)
        .count();
    let why = match within {
        0 | 1 => format!("the range has {} sample(s)", range.len()),
        _ => "its pieces between gaps are no longer".to_owned(),
    };
    OptionError::value(
        "init",
        init,
        format!(
            "leaves no sample of the range {}..{} to score: {why}",
            range.start, range.end
        ),
    )
}

/// That a state given (`x0`, `v0`), the state at a range's first sample, is not asked to start
/// ranges that start at different samples.
fn one_start_for_a_given_state(
    o: &CompareOptions,
    ranges: &[std::ops::Range<usize>],
) -> Result<(), OptionError> {
    let Some(first) = ranges.first().filter(|_| o.x0.is_some()) else {
        return Ok(());
    };
    match ranges.iter().find(|r| r.start != first.start) {
        Some(other) => Err(OptionError::new(
            "x0",
            format!(
                "is the state at the first sample of a range, and the ranges start at samples {} and {}: compare \
                 them one command each, or start each from the record («init», or its measured velocities, \
                 «velocity_col»)",
                first.start, other.start
            ),
        )),
        None => Ok(()),
    }
}

/// The error of a range whose samples after the `init` that set the state are all bridged (the
/// `bridged` left): nothing measured to score.
fn all_bridged(range: &std::ops::Range<usize>, init: usize, bridged: usize) -> OptionError {
    OptionError::value(
        "range",
        format!("{}..{}", range.start, range.end),
        format!(
            "holds no measured sample to score after the {init} that set the state: the {bridged} sample(s) left \
             are bridged («bridge_gaps»)"
        ),
    )
}

/// The measured samples `y` from the grid's sample `start`, NaN at those `bridged` into gaps.
fn unmeasured(y: &[f64], start: usize, bridged: &[std::ops::Range<usize>]) -> Vec<f64> {
    let mut out = y.to_vec();
    let end = start + y.len();
    for b in bridged.iter().filter(|b| b.start < end && b.end > start) {
        out[b.start.max(start) - start..b.end.min(end) - start].fill(f64::NAN);
    }
    out
}

/// The scores of the pieces of a range, over the samples after each one's `init` that were
/// measured (those bridged into gaps are counted, not scored).
fn score(
    pieces: &[RunPiece],
    domain: Domain,
    range: [usize; 2],
    init: usize,
    skipped_pieces: usize,
    initial_states: Vec<[f64; 3]>,
    stopped: Option<String>,
) -> RangeScore {
    let all = || {
        pieces.iter().flat_map(|p| {
            p.measured[p.init.min(p.measured.len())..]
                .iter()
                .zip(&p.x[p.init.min(p.x.len())..])
                .map(|(&y, &x)| (y, x))
        })
    };
    let scored: Vec<(f64, f64)> = all().filter(|(y, _)| !y.is_nan()).collect();
    let bridged = all().filter(|(y, _)| y.is_nan()).count();
    let n = scored.len();
    let finite = n > 0 && scored.iter().all(|(_, x)| x.is_finite());
    let (rmse, nrmse, fit, max) = if finite {
        // The measured output's spread about its mean: on the circle the shortest arcs from the
        // circular mean (a whirling angle's unwrapped spread would grow with every turn).
        let spread = match domain {
            Domain::Line => {
                let mean = scored.iter().map(|p| p.0).sum::<f64>() / n as f64;
                (scored.iter().map(|p| (p.0 - mean).powi(2)).sum::<f64>() / n as f64).sqrt()
            }
            Domain::Circle => {
                let (s, c) = scored
                    .iter()
                    .fold((0.0, 0.0), |(s, c), p| (s + p.0.sin(), c + p.0.cos()));
                let mean = s.atan2(c);
                (scored.iter().map(|p| wrap(p.0 - mean).powi(2)).sum::<f64>() / n as f64).sqrt()
            }
        };
        let errors: Vec<f64> = scored.iter().map(|&(y, x)| difference(domain, x, y)).collect();
        let rmse = (errors.iter().map(|e| e * e).sum::<f64>() / n as f64).sqrt();
        let max = errors.iter().fold(0.0f64, |m, e| m.max(e.abs()));
        let nrmse = (spread > 0.0).then(|| rmse / spread);
        (Some(rmse), nrmse, nrmse.map(|r| 100.0 * (1.0 - r)), Some(max))
    } else {
        (None, None, None, None)
    };
    RangeScore {
        coordinate: None,
        range,
        // What the pieces run left unscored: a range whose pieces all start from a state given or
        // measured fitted none.
        init: pieces.iter().map(|p| p.init).max().unwrap_or(init),
        scored: n,
        bridged,
        rmse,
        nrmse,
        fit_percent: fit,
        max_error: max,
        initial_states,
        skipped_pieces,
        stopped,
    }
}

/// Reads a model saved by `hbid identify --save-model` (compact binary, or JSON text).
///
/// Errors: [`RunError::ModelFile`] naming the file, for a file that cannot be read or is not a
/// model.
pub fn read_model(path: &std::path::Path) -> Result<IdentifiedSystem, RunError> {
    let named = |why: String| RunError::ModelFile {
        path: path.display().to_string(),
        why,
    };
    let bytes = std::fs::read(path).map_err(|e| named(e.to_string()))?;
    if bytes.starts_with(&hb_model::MODEL_MAGIC) {
        return IdentifiedSystem::from_bytes(&bytes).map_err(|e| named(crate::options::chain(&e)));
    }
    let text =
        String::from_utf8(bytes).map_err(|_| named("neither a binary model nor JSON text".to_owned()))?;
    IdentifiedSystem::from_json(&text).map_err(|e| named(crate::options::chain(&e)))
}

/// A model's free run over a record, as `hbid simulate --model --input` writes it: the time, the
/// simulated positions and velocities at every sample of the ranges run (piece by piece, each
/// from the state its first samples give).
#[derive(Debug, Clone, PartialEq)]
pub struct ModelRun {
    /// The columns: `t,x,v` for one coordinate, `t`, the coordinates, then their velocities
    /// (`omega1`, ... on the circle, `v1`, ... on the line; `<name>'` for other names) for a
    /// system.
    pub columns: Vec<String>,
    /// One row per sample, in order; none in the gaps.
    pub rows: Vec<Vec<f64>>,
    /// Where and why the run stopped, if it did (its later rows are NaN).
    pub stopped: Option<String>,
}

impl ModelRun {
    /// Writes the run as CSV with its columns' header, or as a samples × columns `.npy` array (by
    /// the file's extension), atomically; numbers in full precision.
    pub fn write(&self, path: &std::path::Path) -> Result<(), crate::output::OutputError> {
        use npyz::WriterBuilder;
        use std::io::Write;
        let npy = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("npy"));
        crate::output::write_atomically(path, |w: &mut dyn Write| {
            if npy {
                let mut writer = npyz::WriteOptions::<f64>::new()
                    .default_dtype()
                    .shape(&[self.rows.len() as u64, self.columns.len() as u64])
                    .writer(w)
                    .begin_nd()?;
                for row in &self.rows {
                    writer.extend(row.iter().copied())?;
                }
                return writer.finish();
            }
            writeln!(w, "{}", self.columns.join(","))?;
            for row in &self.rows {
                let cells: Vec<String> = row.iter().map(ToString::to_string).collect();
                writeln!(w, "{}", cells.join(","))?;
            }
            Ok(())
        })
    }
}

/// Runs `system` on the record of `source` as [`compare`] does and returns the simulated output.
pub fn model_run(
    system: &IdentifiedSystem,
    source: Source<'_>,
    request: &CompareRequest,
    observer: &mut dyn Observer,
) -> Result<ModelRun, RunError> {
    let report = compare(system, source, request, observer)?;
    let stopped = report.ranges.iter().find_map(|r| r.stopped.clone());
    let n = system.coordinates();
    if n == 1 {
        let rows = report
            .runs
            .iter()
            .flatten()
            .flat_map(|p| (0..p.t.len()).map(move |i| vec![p.t[i], p.x[i], p.v[i]]))
            .collect();
        return Ok(ModelRun {
            columns: ["t", "x", "v"].map(String::from).to_vec(),
            rows,
            stopped,
        });
    }
    let names = system.names().coordinates();
    let mut columns = vec!["t".to_owned()];
    columns.extend(names.iter().cloned());
    columns.extend(names.iter().map(|q| format!("{q}'")));
    // The entries of each range are its coordinates in order, their pieces alike.
    let mut rows = Vec::new();
    for entries in report.runs.chunks(n) {
        for (p, piece) in entries[0].iter().enumerate() {
            for i in 0..piece.t.len() {
                let mut row = vec![piece.t[i]];
                row.extend(entries.iter().map(|e| e[p].x[i]));
                row.extend(entries.iter().map(|e| e[p].v[i]));
                rows.push(row);
            }
        }
    }
    Ok(ModelRun {
        columns,
        rows,
        stopped,
    })
}

/// Runs `model` from `state = (x, x')` at `t[0]` over the times `t`, an even grid (stamps within
/// 10⁻⁶ of a step of `t[0] + n · dt`), driven by `drive` (one sample per time, for a model with
/// terms in `p`): what Python's `Model.simulate(t=..., drive=...)` returns. The run is not
/// fitted to anything: no record's output is involved.
///
/// Errors: options that do not fit (`t` not an even grid, fewer than 2 times, a drive missing,
/// of another length or for a model without `p`, a tolerance out of range), and a simulation
/// that cannot start.
pub fn run_on_times(
    model: &IdentifiedModel,
    t: &[f64],
    drive: Option<&[f64]>,
    state: [f64; 2],
    rtol: f64,
) -> Result<ModelRun, RunError> {
    let dt = even_step(t)?;
    let tolerances = Tolerances::new(rtol, rtol / 10.0).map_err(|e| OptionError::value("rtol", rtol, e))?;
    let model = match (drive, model.form().has_measured_drive()) {
        (Some(p), true) => {
            if p.len() != t.len() {
                return Err(OptionError::new(
                    "drive",
                    format!(
                        "{} drive samples for {} times: give one per time",
                        p.len(),
                        t.len()
                    ),
                )
                .into());
            }
            finite_drive(p, "p")?;
            model
                .clone()
                .with_measured_drive(MeasuredDrive::new(p.to_vec(), t[0], dt)?)?
        }
        (None, true) => {
            return Err(OptionError::new(
                "drive",
                "the model has terms in the measured drive p: give its samples at the times t",
            )
            .into());
        }
        (Some(_), false) => {
            return Err(OptionError::new(
                "drive",
                "the model has no term in the measured drive p: it runs on its own drive",
            )
            .into());
        }
        (None, false) => model.clone(),
    };
    let run = free_run(&model, t[0], dt, t.len(), state, tolerances)?;
    let rows = (0..t.len()).map(|n| vec![t[n], run.x[n], run.v[n]]).collect();
    Ok(ModelRun {
        columns: ["t", "x", "v"].map(String::from).to_vec(),
        rows,
        stopped: run.stopped.map(|why| format!("the model's run stopped: {why}")),
    })
}

/// A measured drive given for a run: every sample finite (a NaN would stop the run with a
/// misleading reason, a step too small or a singular mass matrix, where it enters).
fn finite_drive(p: &[f64], name: &str) -> Result<(), RunError> {
    match p.iter().position(|v| !v.is_finite()) {
        Some(i) => Err(OptionError::new(
            "drive",
            format!(
                "sample {i} of the drive {name} is {}: every sample must be finite",
                p[i]
            ),
        )
        .into()),
        None => Ok(()),
    }
}

/// The step of the times `t`, an even grid (stamps within 10⁻⁶ of a step of `t[0] + n · dt`) of
/// at least 2 finite, increasing times.
fn even_step(t: &[f64]) -> Result<f64, RunError> {
    if t.len() < 2 {
        return Err(OptionError::new("t", format!("{} time(s): at least 2 are needed", t.len())).into());
    }
    if let Some(bad) = t.iter().find(|v| !v.is_finite()) {
        return Err(OptionError::value("t", bad, "every time must be finite").into());
    }
    let dt = (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64;
    if !(dt > 0.0 && dt.is_finite()) {
        return Err(OptionError::new("t", "the times must increase").into());
    }
    if let Some(n) = (0..t.len()).find(|&n| (t[n] - (t[0] + n as f64 * dt)).abs() > 1e-6 * dt) {
        return Err(OptionError::new(
            "t",
            format!(
                "time {} (index {n}) is off the even grid of step {dt}: a model runs on a record's grid (read the record with hbid.read to fit its stamps)",
                t[n]
            ),
        )
        .into());
    }
    Ok(dt)
}

/// Runs `system` from the state `(x0, v0)` (one position and one velocity per coordinate) at
/// `t[0]` over the times `t`, an even grid, driven by `drives` (one series per drive of the
/// system's names, one sample per time, for a system with terms in measured drives; read
/// between samples from [`MeasuredDrive`]'s spline): what Python's `Model.simulate(t=...,
/// drive=..., x0=[...], v0=[...])` returns. The columns are those of [`model_run`]: `t`, the
/// coordinates, then their velocities (`t,x,v` for a system of one coordinate, run by
/// [`run_on_times`]). Nothing is fitted: no record's output is involved.
///
/// Errors: as [`run_on_times`], and a state or drives that are not one per coordinate or drive
/// of the system.
pub fn run_system_on_times(
    system: &IdentifiedSystem,
    t: &[f64],
    drives: &[&[f64]],
    x0: &[f64],
    v0: &[f64],
    rtol: f64,
) -> Result<ModelRun, RunError> {
    let n = system.coordinates();
    for (name, values) in [("x0", x0), ("v0", v0)] {
        if values.len() != n {
            return Err(OptionError::new(
                name,
                format!(
                    "{} value(s) for a system of {n} coordinate(s) ({}): give one per coordinate",
                    values.len(),
                    system.names().coordinates().join(", ")
                ),
            )
            .into());
        }
        if let Some(bad) = values.iter().find(|v| !v.is_finite()) {
            return Err(OptionError::value(name, bad, "the initial state must be finite").into());
        }
    }
    if let [model] = system.equations()
        && system.is_one_model()
    {
        let drive = match drives {
            [] => None,
            [p] => Some(*p),
            _ => {
                return Err(OptionError::new(
                    "drive",
                    format!("{} drives for a model of one measured drive p", drives.len()),
                )
                .into());
            }
        };
        return run_on_times(model, t, drive, [x0[0], v0[0]], rtol);
    }
    let dt = even_step(t)?;
    let tolerances = Tolerances::new(rtol, rtol / 10.0).map_err(|e| OptionError::value("rtol", rtol, e))?;
    let names = system.names();
    let driven = match (drives.is_empty(), system.has_measured_drive()) {
        (_, true) => {
            if drives.len() != names.drives().len() {
                return Err(OptionError::new(
                    "drive",
                    format!(
                        "{} drive(s) for a system that reads {} ({}): give one series per drive",
                        drives.len(),
                        names.drives().len(),
                        names.drives().join(", ")
                    ),
                )
                .into());
            }
            let mut splines = Vec::with_capacity(drives.len());
            for (p, name) in drives.iter().zip(names.drives()) {
                if p.len() != t.len() {
                    return Err(OptionError::new(
                        "drive",
                        format!(
                            "{} samples of the drive {name} for {} times: give one per time",
                            p.len(),
                            t.len()
                        ),
                    )
                    .into());
                }
                finite_drive(p, name)?;
                splines.push(MeasuredDrive::new(p.to_vec(), t[0], dt)?);
            }
            system.clone().with_measured_drives(splines)?
        }
        (true, false) => system.clone(),
        (false, false) => {
            return Err(OptionError::new(
                "drive",
                "the system has no term in a measured drive: it runs on its own drive",
            )
            .into());
        }
    };
    let state = MultiState::new(x0, v0)?;
    let run = multi::free_run(&driven, t, &state, tolerances)?;
    let mut columns = vec!["t".to_owned()];
    columns.extend(names.coordinates().iter().cloned());
    columns.extend(names.coordinates().iter().map(|q| format!("{q}'")));
    let rows = (0..t.len())
        .map(|i| {
            let mut row = vec![t[i]];
            row.extend(run.q.iter().map(|q| q[i]));
            row.extend(run.v.iter().map(|v| v[i]));
            row
        })
        .collect();
    Ok(ModelRun {
        columns,
        rows,
        stopped: run.stopped.map(|why| format!("the system's run stopped: {why}")),
    })
}
