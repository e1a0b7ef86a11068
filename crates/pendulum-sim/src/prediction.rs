//! Validation that needs no true equation: how long a model, started from the record's own state,
//! stays with the record (the valid prediction time), and for a free decay how its envelope
//! compares with the record's.
//!
//! A real record comes without the equation that made it, so an identified model cannot be
//! compared with the truth; it can be compared with the record. From a sample `n` of the record
//! the model is integrated from the record's own state there, and the **valid prediction time**
//! is how long its position stays within a tolerance `δ` of the record's (circle distances on the
//! circle):
//!
//! ```text
//! T_valid(n) = min { t − t_n : |x_model(t) − x_record(t)| > δ },
//! ```
//!
//! interpolated linearly between the two samples where the distance crosses `δ`. On a chaotic
//! attractor an error `ε` of the starting state grows like `ε e^{λ t}`, so `T_valid ≈ ln(δ/ε)/λ`:
//! a wrong model shortens it (its error grows from the first step), and the same measure of the
//! true model says how much the record itself allows. It is given in the record's time, in drive
//! periods, and in Lyapunov times `λ T_valid` when an exponent is given.
//!
//! Choices, each a default of [`PredictionConfig`] that scales with the record:
//!
//! - the state at the start: `x` and `x'` from a least-squares polynomial of degree 4 through the
//!   samples within `±T/12` of it (at least two samples each side: five samples, an
//!   interpolation, at 25 samples per period; a smoothing fit at higher rates), unwrapped on the
//!   circle; no derivative of the record is taken by differences;
//! - the tolerance: 10 % of the record's spread (the peak-to-peak range on the line; on the
//!   circle the shortest arc that holds every sample, `2π` for a whirling pendulum);
//! - 32 windows, their starts spread evenly over the record (leaving room for the horizon when
//!   the record is long enough), starts without a state estimate (at a gap) skipped;
//! - a horizon of 40 drive periods: a window that stays within `δ` for that long, or until the
//!   record ends or reaches a gap, counts as reaching its end (censored), and the summaries say
//!   how many did; a median with more than half censored is a lower bound.
//!
//! For a free decay there is no drive and the motion dies away, so prediction time says little;
//! [`decay_envelope`] compares the amplitude of each swing (peak to peak between successive
//! turning points) of the model, started from the record's first state, with the record's.
//!
//! # Example
//!
//! ```
//! use circle_signal::SampleClock;
//! use pendulum_sim::{
//!     Domain, Pendulum, PredictionConfig, PredictionRecord, SimulationConfig, prediction_starts, simulate,
//!     valid_prediction_times,
//! };
//!
//! let trajectory = simulate(&Pendulum::paper(), &SimulationConfig::paper().with_samples(3_000)?)?;
//! let x = trajectory.wrapped();
//! let clock = SampleClock::nondimensional(25)?.with_start_time(trajectory.t[0])?;
//! let record = PredictionRecord::new(&x, clock, Domain::Circle)?;
//! let config = PredictionConfig::default().with_windows(8)?;
//! let starts = prediction_starts(&record, &config)?;
//! let times = valid_prediction_times(&Pendulum::paper(), &record, &starts, &config, Some(0.187))?;
//! let periods = times.in_periods().unwrap();
//! // The true model stays with its own record for several drive periods.
//! assert!(periods.median > 3.0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::f64::consts::TAU;

use circle_signal::{Domain, SampleClock, circle_distance, wrap};
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use crate::dop853::Tolerances;
use crate::error::SimError;
use crate::simulate::FirstOrder;
use crate::switching::{Flow, OnMode};
use crate::system::SecondOrderSystem;

mod system;

pub use system::{
    SystemPredictionRecord, SystemPredictionTimes, SystemWindowPrediction, estimate_system_state,
    predict_system_window, system_prediction_starts, system_valid_prediction_times,
};

/// Degree of the local polynomial that gives the state at a sample.
const FIT_DEGREE: usize = 4;
/// Steps an integration of one window may take before it counts as a failure of the model.
const MAX_STEPS: usize = 2_000_000;

/// A record as the prediction test reads it: its samples (NaN where it has gaps), its clock and
/// what the samples are. Its spread is computed once.
#[derive(Debug, Clone, PartialEq)]
pub struct PredictionRecord<'a> {
    samples: &'a [f64],
    clock: SampleClock,
    domain: Domain,
    spread: f64,
}

impl<'a> PredictionRecord<'a> {
    /// `samples` taken on `clock` (sample `n` at `clock.time(n)`; the clock's forcing period is the
    /// drive's, or the free oscillation's for a record without a drive), in `domain`; a NaN marks
    /// a missing sample. The finite samples must not all be equal (a record that does not move
    /// has no spread to scale the tolerance with).
    pub fn new(samples: &'a [f64], clock: SampleClock, domain: Domain) -> Result<Self, SimError> {
        if let Some(&bad) = samples.iter().find(|v| v.is_infinite()) {
            return Err(SimError::InvalidParameter {
                name: "record sample",
                value: bad,
                why: "must be finite (NaN marks a missing sample)",
            });
        }
        let spread = spread(samples, domain);
        if spread.is_nan() || spread <= 0.0 {
            return Err(SimError::InvalidParameter {
                name: "record spread",
                value: spread,
                why: "must be positive: the record does not move",
            });
        }
        Ok(Self {
            samples,
            clock,
            domain,
            spread,
        })
    }

    /// The samples.
    pub fn samples(&self) -> &'a [f64] {
        self.samples
    }
    /// The clock.
    pub fn clock(&self) -> &SampleClock {
        &self.clock
    }
    /// Circle or line.
    pub fn domain(&self) -> Domain {
        self.domain
    }
    /// The spread of the finite samples: peak to peak on the line, the shortest arc holding
    /// every sample on the circle.
    pub fn spread(&self) -> f64 {
        self.spread
    }

    /// The distance between a model's position and sample `n`.
    fn distance(&self, model: f64, n: usize) -> f64 {
        match self.domain {
            Domain::Circle => circle_distance(model, self.samples[n]),
            Domain::Line => (model - self.samples[n]).abs(),
        }
    }
}

/// Peak to peak on the line; on the circle `2π` minus the widest empty arc between the wrapped
/// samples. NaN samples are skipped; 0 for fewer than two finite samples.
fn spread(samples: &[f64], domain: Domain) -> f64 {
    let finite = samples.iter().copied().filter(|v| v.is_finite());
    match domain {
        Domain::Line => {
            let (lo, hi) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            });
            if hi >= lo { hi - lo } else { 0.0 }
        }
        Domain::Circle => {
            let mut w: Vec<f64> = finite.map(wrap).collect();
            if w.len() < 2 {
                return 0.0;
            }
            w.sort_by(f64::total_cmp);
            let widest_gap = w
                .windows(2)
                .map(|p| p[1] - p[0])
                .fold(TAU - (w[w.len() - 1] - w[0]), f64::max);
            TAU - widest_gap
        }
    }
}

/// Settings of the prediction test (see the [module documentation](self) for the defaults and
/// why). Deserialising validates every field as the `with_*` setters do.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "PredictionConfigRaw", into = "PredictionConfigRaw")]
pub struct PredictionConfig {
    tolerance: f64,
    horizon: f64,
    windows: usize,
    fit_span: f64,
    tolerances: Tolerances,
}

/// The serialised form of [`PredictionConfig`].
#[derive(Serialize, Deserialize)]
struct PredictionConfigRaw {
    tolerance: f64,
    horizon_periods: f64,
    windows: usize,
    fit_span_periods: f64,
    tolerances: Tolerances,
}

impl TryFrom<PredictionConfigRaw> for PredictionConfig {
    type Error = SimError;
    fn try_from(raw: PredictionConfigRaw) -> Result<Self, SimError> {
        Ok(Self::default()
            .with_tolerance(raw.tolerance)?
            .with_horizon(raw.horizon_periods)?
            .with_windows(raw.windows)?
            .with_fit_span(raw.fit_span_periods)?
            .with_integration(raw.tolerances))
    }
}

impl From<PredictionConfig> for PredictionConfigRaw {
    fn from(c: PredictionConfig) -> Self {
        Self {
            tolerance: c.tolerance,
            horizon_periods: c.horizon,
            windows: c.windows,
            fit_span_periods: c.fit_span,
            tolerances: c.tolerances,
        }
    }
}

impl Default for PredictionConfig {
    fn default() -> Self {
        Self {
            tolerance: Self::DEFAULT_TOLERANCE,
            horizon: Self::DEFAULT_HORIZON,
            windows: Self::DEFAULT_WINDOWS,
            fit_span: Self::DEFAULT_FIT_SPAN,
            tolerances: Tolerances::default(),
        }
    }
}

fn invalid(name: &'static str, value: f64, why: &'static str) -> SimError {
    SimError::InvalidParameter { name, value, why }
}

impl PredictionConfig {
    /// The default tolerance: 10 % of the record's spread.
    pub const DEFAULT_TOLERANCE: f64 = 0.1;
    /// The default horizon: 40 drive periods.
    pub const DEFAULT_HORIZON: f64 = 40.0;
    /// The default number of windows.
    pub const DEFAULT_WINDOWS: usize = 32;
    /// The default half-width of the state's local fit: a twelfth of a drive period.
    pub const DEFAULT_FIT_SPAN: f64 = 1.0 / 12.0;

    /// The tolerance `δ` as a fraction of the record's spread, in `(0, 1]`.
    pub fn with_tolerance(mut self, fraction: f64) -> Result<Self, SimError> {
        if !(fraction > 0.0 && fraction <= 1.0) {
            return Err(invalid("prediction tolerance", fraction, "must lie in (0, 1]"));
        }
        self.tolerance = fraction;
        Ok(self)
    }

    /// The longest prediction followed, in drive periods (positive and finite).
    pub fn with_horizon(mut self, periods: f64) -> Result<Self, SimError> {
        if !(periods.is_finite() && periods > 0.0) {
            return Err(invalid(
                "prediction horizon",
                periods,
                "must be positive and finite",
            ));
        }
        self.horizon = periods;
        Ok(self)
    }

    /// The number of windows of [`prediction_starts`] (`>= 1`).
    pub fn with_windows(mut self, windows: usize) -> Result<Self, SimError> {
        if windows == 0 {
            return Err(invalid("prediction windows", 0.0, "must be at least 1"));
        }
        self.windows = windows;
        Ok(self)
    }

    /// The half-width of the local fit that gives the state at a start, in drive periods
    /// (positive and finite; at least two samples each side are used whatever it is).
    pub fn with_fit_span(mut self, periods: f64) -> Result<Self, SimError> {
        if !(periods.is_finite() && periods > 0.0) {
            return Err(invalid("fit span", periods, "must be positive and finite"));
        }
        self.fit_span = periods;
        Ok(self)
    }

    /// The tolerances of the model's integration (default `rtol = 1e-10`).
    pub fn with_integration(mut self, tolerances: Tolerances) -> Self {
        self.tolerances = tolerances;
        self
    }

    /// The tolerance as a fraction of the spread.
    pub fn tolerance(&self) -> f64 {
        self.tolerance
    }
    /// The horizon in drive periods.
    pub fn horizon(&self) -> f64 {
        self.horizon
    }
    /// The number of windows.
    pub fn windows(&self) -> usize {
        self.windows
    }

    /// Samples each side of the state's local fit on `clock`.
    fn half_width(&self, clock: &SampleClock) -> usize {
        let m = (self.fit_span * clock.samples_per_period()).round();
        if m.is_finite() && m >= 2.0 {
            m.min(1e6) as usize
        } else {
            2
        }
    }

    /// Samples of the horizon on `clock`.
    fn horizon_samples(&self, clock: &SampleClock) -> usize {
        let n = (self.horizon * clock.samples_per_period()).ceil();
        if n.is_finite() && n >= 1.0 {
            n.min(usize::MAX as f64 / 4.0) as usize
        } else {
            1
        }
    }
}

/// The local least-squares polynomial of degree 4 at sample `n` of `x` over `±m` samples, stopped
/// at the first missing sample each side, unwrapped on the circle: `(x̂, dx̂/dn)` in samples, or
/// `None` without `x_n` or with fewer than five samples.
fn local_fit(x: &[f64], n: usize, m: usize, domain: Domain) -> Option<[f64; 2]> {
    if n >= x.len() || !x[n].is_finite() {
        return None;
    }
    let step = |a: f64, b: f64| match domain {
        Domain::Circle => wrap(b - a),
        Domain::Line => b - a,
    };
    let mut points = vec![(0.0, x[n])];
    for dir in [-1i64, 1] {
        let mut value = x[n];
        for k in 1..=m as i64 {
            let j = n as i64 + dir * k;
            if j < 0 || j as usize >= x.len() || !x[j as usize].is_finite() {
                break;
            }
            value += step(x[(j - dir) as usize], x[j as usize]);
            points.push(((dir * k) as f64, value));
        }
    }
    if points.len() <= FIT_DEGREE {
        return None;
    }
    // Powers of u / m keep the columns of one size.
    let scale = m as f64;
    let a = DMatrix::from_fn(points.len(), FIT_DEGREE + 1, |i, k| {
        (points[i].0 / scale).powi(k as i32)
    });
    let b = DVector::from_iterator(points.len(), points.iter().map(|p| p.1 - x[n]));
    let coefficients = a.svd(true, true).solve(&b, 1e-12).ok()?;
    Some([x[n] + coefficients[0], coefficients[1] / scale])
}

/// The state `(x, x')` at sample `index` of the record, from the local polynomial fit (see the
/// [module documentation](self)); `x'` in the record's time unit. On the circle `x` lies on the
/// turn of the sample itself (within π of it).
///
/// Errors: [`SimError::NoStateEstimate`] when the sample is missing or fewer than five samples
/// around it are.
pub fn estimate_state(
    record: &PredictionRecord<'_>,
    index: usize,
    config: &PredictionConfig,
) -> Result<[f64; 2], SimError> {
    let m = config.half_width(&record.clock);
    let [x, dxdn] = local_fit(record.samples, index, m, record.domain).ok_or(SimError::NoStateEstimate {
        index,
        needed: FIT_DEGREE + 1,
    })?;
    Ok([x, dxdn / record.clock.step()])
}

/// Where the default windows start: `config.windows()` starts spread evenly from the first
/// sample with a full fit span to the last that leaves a horizon before the record's end (or,
/// for a record shorter than that, to the last with a full fit span), those without a state
/// estimate skipped.
///
/// Errors: [`SimError::RecordTooShort`] when no start has a state estimate.
pub fn prediction_starts(
    record: &PredictionRecord<'_>,
    config: &PredictionConfig,
) -> Result<Vec<usize>, SimError> {
    let m = config.half_width(&record.clock);
    spread_starts(record.samples.len(), &record.clock, config, |n| {
        local_fit(record.samples, n, m, record.domain).is_some()
    })
}

/// `config.windows()` starts spread evenly over a record of `len` samples on `clock` (see
/// [`prediction_starts`]), those where `has_state` says no state can be estimated skipped.
fn spread_starts(
    len: usize,
    clock: &SampleClock,
    config: &PredictionConfig,
    has_state: impl Fn(usize) -> bool,
) -> Result<Vec<usize>, SimError> {
    let m = config.half_width(clock);
    let room = config.horizon_samples(clock);
    let too_short = SimError::RecordTooShort {
        len,
        needed: 2 * m + 1,
    };
    if len < 2 * m + 1 {
        return Err(too_short);
    }
    let first = m;
    let last = if len > 2 * m + room {
        len - 1 - room
    } else {
        len - 1 - m
    };
    let w = config.windows;
    let mut starts: Vec<usize> = (0..w)
        .map(|i| {
            if w == 1 {
                first
            } else {
                first + ((last - first) as f64 * i as f64 / (w - 1) as f64).round() as usize
            }
        })
        .filter(|&n| has_state(n))
        .collect();
    starts.dedup();
    if starts.is_empty() {
        return Err(too_short);
    }
    Ok(starts)
}

/// One window's prediction.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct WindowPrediction {
    /// The sample the window starts at.
    pub start: usize,
    /// Its time.
    pub start_time: f64,
    /// The state `(x, x')` the model started from.
    pub state: [f64; 2],
    /// How long the model stayed within the tolerance, in the record's time unit.
    pub valid_time: f64,
    /// Whether the window ended first (the horizon, the record's end or a gap reached, or the
    /// model's integration failing is not this: a model that fails has left the record): the
    /// valid time is then a lower bound.
    pub censored: bool,
}

/// The model integrated from `state` at sample `start` and compared with the record sample by
/// sample until it leaves the tolerance, the horizon passes, or the record ends or has a gap.
///
/// A model whose integration fails (it blows up, or its step size collapses) has left the
/// record: its valid time ends at the last sample it reached.
pub fn predict_window<S: SecondOrderSystem>(
    system: &S,
    record: &PredictionRecord<'_>,
    start: usize,
    state: [f64; 2],
    config: &PredictionConfig,
) -> Result<WindowPrediction, SimError> {
    let len = record.samples.len();
    if start >= len || !record.samples[start].is_finite() {
        return Err(SimError::NoStateEstimate {
            index: start,
            needed: FIT_DEGREE + 1,
        });
    }
    if !(state[0].is_finite() && state[1].is_finite()) {
        return Err(invalid("initial state", state[0] + state[1], "must be finite"));
    }
    let clock = &record.clock;
    let delta = config.tolerance * record.spread;
    let t0 = clock.time(start);
    let last = start.saturating_add(config.horizon_samples(clock)).min(len - 1);
    let window = |valid_time: f64, censored: bool| WindowPrediction {
        start,
        start_time: t0,
        state,
        valid_time,
        censored,
    };
    let mut previous = record.distance(state[0], start);
    if previous > delta {
        return Ok(window(0.0, false));
    }
    let mut flow =
        Flow::new(FirstOrder(OnMode::new(system)), t0, state, config.tolerances)?.with_max_steps(MAX_STEPS);
    let t_end = clock.time(last);
    for n in start + 1..=last {
        let t = clock.time(n);
        if !record.samples[n].is_finite() {
            return Ok(window(clock.time(n - 1) - t0, true));
        }
        let mut failed = false;
        while flow.t() < t {
            if flow.step(t_end).is_err() {
                failed = true;
                break;
            }
        }
        let x = if failed { f64::NAN } else { flow.interpolate(t)[0] };
        if !x.is_finite() {
            return Ok(window(clock.time(n - 1) - t0, false));
        }
        let d = record.distance(x, n);
        if d > delta {
            // Linear in the distance between the last sample within δ and this one.
            let fraction = (delta - previous) / (d - previous);
            let crossing = clock.time(n - 1) + fraction * clock.step();
            return Ok(window(crossing - t0, false));
        }
        previous = d;
    }
    Ok(window(t_end - t0, true))
}

/// Median and quartiles of valid times (quantiles interpolated linearly between the sorted
/// values; a censored time counts as its lower bound).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TimeSummary {
    /// The median.
    pub median: f64,
    /// The lower quartile.
    pub lower_quartile: f64,
    /// The upper quartile.
    pub upper_quartile: f64,
    /// Windows summarised.
    pub windows: usize,
    /// Of which censored (the valid time is a lower bound).
    pub censored: usize,
}

impl TimeSummary {
    /// Whether more than half the windows are censored: the median is then a lower bound.
    pub fn median_is_lower_bound(&self) -> bool {
        2 * self.censored > self.windows
    }

    fn of(values: impl Iterator<Item = (f64, bool)>) -> Option<Self> {
        let (mut v, flags): (Vec<f64>, Vec<bool>) = values.unzip();
        if v.is_empty() {
            return None;
        }
        v.sort_by(f64::total_cmp);
        let q = |p: f64| {
            let pos = p * (v.len() - 1) as f64;
            let (lo, hi) = (pos.floor() as usize, pos.ceil() as usize);
            v[lo] + (pos - lo as f64) * (v[hi] - v[lo])
        };
        Some(Self {
            median: q(0.5),
            lower_quartile: q(0.25),
            upper_quartile: q(0.75),
            windows: v.len(),
            censored: flags.iter().filter(|&&c| c).count(),
        })
    }
}

/// The valid prediction times of a model on a record's windows.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PredictionTimes {
    /// Each window, in the order of the starts.
    pub windows: Vec<WindowPrediction>,
    /// The tolerance `δ` in the record's unit.
    pub tolerance: f64,
    /// The record's drive period (or free oscillation's), the unit of [`in_periods`](Self::in_periods).
    #[serde(alias = "forcing_period")]
    pub drive_period: f64,
    /// The largest Lyapunov exponent per unit time, if given.
    pub lyapunov: Option<f64>,
}

impl PredictionTimes {
    /// The summary in the record's time unit.
    pub fn summary(&self) -> Option<TimeSummary> {
        TimeSummary::of(self.windows.iter().map(|w| (w.valid_time, w.censored)))
    }

    /// The summary in drive periods.
    pub fn in_periods(&self) -> Option<TimeSummary> {
        let t = self.drive_period;
        TimeSummary::of(self.windows.iter().map(|w| (w.valid_time / t, w.censored)))
    }

    /// The summary in Lyapunov times `λ T_valid`, when a positive exponent was given.
    pub fn in_lyapunov_times(&self) -> Option<TimeSummary> {
        let l = self.lyapunov.filter(|l| *l > 0.0)?;
        TimeSummary::of(self.windows.iter().map(|w| (w.valid_time * l, w.censored)))
    }
}

/// The valid prediction time of `system` from each of `starts` (e.g. [`prediction_starts`]), the
/// state at each estimated from the record ([`estimate_state`]); `lyapunov`, the largest exponent
/// per unit time of the record, adds the times in Lyapunov times. Windows run in parallel; the
/// result does not depend on the number of threads.
///
/// Errors: a start outside the record or without a state estimate, or no start at all.
pub fn valid_prediction_times<S: SecondOrderSystem + Sync>(
    system: &S,
    record: &PredictionRecord<'_>,
    starts: &[usize],
    config: &PredictionConfig,
    lyapunov: Option<f64>,
) -> Result<PredictionTimes, SimError> {
    use rayon::prelude::*;
    if starts.is_empty() {
        return Err(SimError::RecordTooShort {
            len: record.samples.len(),
            needed: 2 * config.half_width(&record.clock) + 1,
        });
    }
    let windows = starts
        .par_iter()
        .map(|&start| {
            let state = estimate_state(record, start, config)?;
            predict_window(system, record, start, state, config)
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(PredictionTimes {
        windows,
        tolerance: config.tolerance * record.spread,
        drive_period: record.clock.drive_period(),
        lyapunov,
    })
}

/// The decay of a free oscillation, model against record: the amplitude of each swing.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DecayEnvelope {
    /// The sample the model started from.
    pub start: usize,
    /// The record's swings: the distance between successive turning points.
    pub record: Vec<f64>,
    /// The model's swings, started from the record's state at `start`.
    pub model: Vec<f64>,
    /// `(model − record) / record` for each swing both have (positive: the model decays more
    /// slowly), while the record's swing is above the floor.
    pub relative_errors: Vec<f64>,
}

impl DecayEnvelope {
    /// The median of the absolute relative errors, `None` with no swing compared.
    pub fn median_error(&self) -> Option<f64> {
        let mut e: Vec<f64> = self.relative_errors.iter().map(|e| e.abs()).collect();
        if e.is_empty() {
            return None;
        }
        e.sort_by(f64::total_cmp);
        let mid = e.len() / 2;
        Some(if e.len() % 2 == 1 {
            e[mid]
        } else {
            0.5 * (e[mid - 1] + e[mid])
        })
    }

    /// The largest absolute relative error, `None` with no swing compared.
    pub fn max_error(&self) -> Option<f64> {
        self.relative_errors.iter().map(|e| e.abs()).reduce(f64::max)
    }
}

/// The fraction of the record's spread below which swings are not compared (and below which a
/// turn of the motion is not a turning point).
pub const ENVELOPE_FLOOR: f64 = 0.02;

/// The swings of `x` (unwrapped on the circle): the local fit's value at every sample, and the
/// turning points of that smoothed motion found with a hysteresis of `floor` (a turn counts once
/// the motion has come back by `floor` from its extreme); each swing the distance between two
/// successive turning points.
fn swings(x: &[f64], m: usize, domain: Domain, floor: f64) -> Vec<f64> {
    let mut position: Vec<f64> = Vec::with_capacity(x.len());
    // The fit needs samples on both sides: the first and last few have none.
    for n in 0..x.len() {
        let Some([value, _]) = local_fit(x, n, m, domain) else {
            continue;
        };
        // Continuous on the circle: each value on the turn nearest the last.
        let value = match (domain, position.last()) {
            (Domain::Circle, Some(&p)) => p + wrap(value - p),
            _ => value,
        };
        position.push(value);
    }
    let mut turns = Vec::new();
    let (mut hi, mut lo) = (f64::NEG_INFINITY, f64::INFINITY);
    let mut rising: Option<bool> = None;
    for &p in &position {
        hi = hi.max(p);
        lo = lo.min(p);
        match rising {
            None => {
                if p - lo > floor {
                    rising = Some(true);
                    hi = p;
                } else if hi - p > floor {
                    rising = Some(false);
                    lo = p;
                }
            }
            Some(true) => {
                if hi - p > floor {
                    turns.push(hi);
                    rising = Some(false);
                    lo = p;
                }
            }
            Some(false) => {
                if p - lo > floor {
                    turns.push(lo);
                    rising = Some(true);
                    hi = p;
                }
            }
        }
    }
    turns.windows(2).map(|w| (w[1] - w[0]).abs()).collect()
}

/// The decay envelope of a free oscillation: the model started from the record's state at the
/// first sample with a state estimate and integrated at the record's times to its end (or its
/// first gap); the swings of both measured alike (the local fit's values, turning points with a
/// hysteresis of [`ENVELOPE_FLOOR`] of the spread) and compared swing by swing while the
/// record's is above that floor. A model whose integration fails is compared up to there.
pub fn decay_envelope<S: SecondOrderSystem>(
    system: &S,
    record: &PredictionRecord<'_>,
    config: &PredictionConfig,
) -> Result<DecayEnvelope, SimError> {
    let x = record.samples;
    let m = config.half_width(&record.clock);
    let start = (0..x.len())
        .find(|&n| local_fit(x, n, m, record.domain).is_some())
        .ok_or(SimError::RecordTooShort {
            len: x.len(),
            needed: FIT_DEGREE + 1,
        })?;
    let end = (start..x.len()).find(|&n| !x[n].is_finite()).unwrap_or(x.len());
    let state = estimate_state(record, start, config)?;
    let clock = &record.clock;
    let mut flow = Flow::new(
        FirstOrder(OnMode::new(system)),
        clock.time(start),
        state,
        config.tolerances,
    )?
    .with_max_steps(MAX_STEPS);
    let t_end = clock.time(end - 1);
    let mut model = vec![state[0]];
    'samples: for n in start + 1..end {
        let t = clock.time(n);
        while flow.t() < t {
            if flow.step(t_end).is_err() {
                break 'samples;
            }
        }
        let value = flow.interpolate(t)[0];
        if !value.is_finite() {
            break;
        }
        model.push(match record.domain {
            Domain::Circle => wrap(value),
            Domain::Line => value,
        });
    }
    let floor = ENVELOPE_FLOOR * record.spread;
    let record_swings = swings(&x[start..end], m, record.domain, floor);
    let model_swings = swings(&model, m, record.domain, floor);
    let relative_errors = record_swings
        .iter()
        .zip(&model_swings)
        .take_while(|(r, _)| **r > floor)
        .map(|(r, m)| (m - r) / r)
        .collect();
    Ok(DecayEnvelope {
        start,
        record: record_swings,
        model: model_swings,
        relative_errors,
    })
}
