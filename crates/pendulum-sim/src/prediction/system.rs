//! The valid prediction time of a system of several coordinates ([`MultiSystem`]): the
//! one-coordinate test of the [parent module](super) with every coordinate watched at once.
//!
//! A record of a double pendulum holds two angles; a model of it is one system, so it is started
//! from the record's whole state (every coordinate and its velocity, each from its own local
//! fit, [`estimate_system_state`]) and followed until **any** coordinate leaves its own
//! tolerance (the configured fraction of that coordinate's spread): a model that predicts one
//! link and loses the other does not predict the record. The crossing is interpolated linearly
//! in the largest ratio of distance to tolerance over the coordinates, which for one coordinate
//! is the one-coordinate interpolation exactly; the windows, their starts, the horizon, gaps
//! and a failing integration are handled as there.
//!
//! # Example
//!
//! ```
//! use circle_signal::{SampleClock, wrap};
//! use pendulum_sim::multi::{self, MultiConfig, MultiState};
//! use pendulum_sim::prediction::{SystemPredictionRecord, system_prediction_starts, system_valid_prediction_times};
//! use pendulum_sim::{DoublePendulum, Domain, PredictionConfig};
//!
//! let pendulum = DoublePendulum::whirling();
//! let config = MultiConfig::new(MultiState::at_rest(&[2.0, 0.0])?)
//!     .with_samples_per_period(64)?
//!     .with_transient_periods(50)
//!     .with_samples(64 * 40)?;
//! let run = multi::simulate(&pendulum, &config)?;
//! let wrapped: Vec<Vec<f64>> = run.q.iter().map(|q| q.iter().map(|&x| wrap(x)).collect()).collect();
//! let clock = SampleClock::nondimensional(64)?.with_start_time(run.t[0])?;
//! let record = SystemPredictionRecord::new(&[&wrapped[0], &wrapped[1]], clock, &[Domain::Circle; 2])?;
//! let settings = PredictionConfig::default().with_windows(4)?.with_horizon(10.0)?;
//! let starts = system_prediction_starts(&record, &settings)?;
//! let times = system_valid_prediction_times(&pendulum, &record, &starts, &settings)?;
//! // The true system stays with its own record for drive periods.
//! assert!(times.in_periods().unwrap().median > 1.0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use circle_signal::{Domain, SampleClock};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::{FIT_DEGREE, PredictionConfig, PredictionRecord, TimeSummary, local_fit};
use crate::error::SimError;
use crate::multi::{MAX_COORDINATES, MultiState, MultiSystem, free_run};

/// A record of several coordinates on one clock as the prediction test reads it: each coordinate
/// a [`PredictionRecord`] of its own (its domain and its spread), all of one length.
#[derive(Debug, Clone, PartialEq)]
pub struct SystemPredictionRecord<'a> {
    coordinates: Vec<PredictionRecord<'a>>,
}

impl<'a> SystemPredictionRecord<'a> {
    /// The coordinates `samples` (`1..=`[`MAX_COORDINATES`] of them, of one length; NaN marks a
    /// missing sample) taken on `clock`, coordinate `c` in `domains[c]`. Each must move (see
    /// [`PredictionRecord::new`]).
    pub fn new(samples: &[&'a [f64]], clock: SampleClock, domains: &[Domain]) -> Result<Self, SimError> {
        if samples.is_empty() || samples.len() > MAX_COORDINATES {
            return Err(SimError::InvalidParameter {
                name: "coordinates",
                value: samples.len() as f64,
                why: "must lie in 1..=8",
            });
        }
        if domains.len() != samples.len() {
            return Err(SimError::InvalidParameter {
                name: "domains",
                value: domains.len() as f64,
                why: "must be one per coordinate",
            });
        }
        if let Some(other) = samples.iter().find(|s| s.len() != samples[0].len()) {
            return Err(SimError::InvalidParameter {
                name: "coordinate samples",
                value: other.len() as f64,
                why: "must be as many as the first coordinate's",
            });
        }
        let coordinates = samples
            .iter()
            .zip(domains)
            .map(|(s, &domain)| PredictionRecord::new(s, clock, domain))
            .collect::<Result<_, _>>()?;
        Ok(Self { coordinates })
    }

    /// Each coordinate as a record of its own.
    pub fn coordinates(&self) -> &[PredictionRecord<'a>] {
        &self.coordinates
    }

    /// The number of samples.
    pub fn len(&self) -> usize {
        self.coordinates[0].samples.len()
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The clock.
    pub fn clock(&self) -> &SampleClock {
        &self.coordinates[0].clock
    }

    /// Whether every coordinate has sample `n`.
    fn finite_at(&self, n: usize) -> bool {
        self.coordinates.iter().all(|c| c.samples[n].is_finite())
    }

    /// Whether every coordinate has a state estimate at `n` with `m` samples each side.
    fn has_state(&self, n: usize, m: usize) -> bool {
        self.coordinates
            .iter()
            .all(|c| local_fit(c.samples, n, m, c.domain).is_some())
    }

    /// The largest distance of `q` from sample `n` relative to each coordinate's tolerance
    /// `deltas[c]`, and the coordinate where it is largest.
    fn ratio(&self, q: impl Iterator<Item = f64>, n: usize, deltas: &[f64]) -> (f64, usize) {
        q.zip(&self.coordinates)
            .zip(deltas)
            .enumerate()
            .map(|(c, ((q, record), delta))| (record.distance(q, n) / delta, c))
            .fold((0.0, 0), |best, r| if r.0 > best.0 { r } else { best })
    }
}

/// The state of every coordinate at sample `index`, each from its local polynomial fit (see
/// [`super::estimate_state`]), velocities in the record's time unit.
///
/// Errors: [`SimError::NoStateEstimate`] when any coordinate's sample is missing or has fewer
/// than five samples around it.
pub fn estimate_system_state(
    record: &SystemPredictionRecord<'_>,
    index: usize,
    config: &PredictionConfig,
) -> Result<MultiState, SimError> {
    let m = config.half_width(record.clock());
    let step = record.clock().step();
    let (mut q, mut v) = (Vec::new(), Vec::new());
    for c in &record.coordinates {
        let [x, dxdn] = local_fit(c.samples, index, m, c.domain).ok_or(SimError::NoStateEstimate {
            index,
            needed: FIT_DEGREE + 1,
        })?;
        q.push(x);
        v.push(dxdn / step);
    }
    MultiState::new(&q, &v)
}

/// Where the default windows start, as [`super::prediction_starts`] places them, those where
/// some coordinate has no state estimate skipped.
///
/// Errors: [`SimError::RecordTooShort`] when no start has a state estimate.
pub fn system_prediction_starts(
    record: &SystemPredictionRecord<'_>,
    config: &PredictionConfig,
) -> Result<Vec<usize>, SimError> {
    let m = config.half_width(record.clock());
    super::spread_starts(record.len(), record.clock(), config, |n| record.has_state(n, m))
}

/// One window's prediction of a system.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SystemWindowPrediction {
    /// The sample the window starts at.
    pub start: usize,
    /// Its time.
    pub start_time: f64,
    /// The state the system started from.
    pub state: MultiState,
    /// How long the system stayed within the tolerance of every coordinate, in the record's time
    /// unit.
    pub valid_time: f64,
    /// Whether the window ended first (the horizon, the record's end or a gap): the valid time
    /// is then a lower bound.
    pub censored: bool,
    /// The coordinate that left its tolerance first (`None` for a censored window, or where the
    /// system's integration failed).
    pub left: Option<usize>,
}

/// The system integrated from `state` at sample `start` ([`free_run`] at the record's times, in
/// stretches of one, two, four… drive periods, each from the state where the one before ended)
/// and compared with every coordinate of the record sample by sample until one leaves its
/// tolerance, the horizon passes, or the record ends or has a gap in any coordinate.
///
/// A system whose integration fails (a singular mass matrix, a blow-up, a step size that
/// collapses) has left the record: its valid time ends at the last sample it reached.
///
/// Errors: a start outside the record or missing in a coordinate, a state of another number of
/// coordinates or not finite.
pub fn predict_system_window<S: MultiSystem + ?Sized>(
    system: &S,
    record: &SystemPredictionRecord<'_>,
    start: usize,
    state: &MultiState,
    config: &PredictionConfig,
) -> Result<SystemWindowPrediction, SimError> {
    let len = record.len();
    if start >= len || !record.finite_at(start) {
        return Err(SimError::NoStateEstimate {
            index: start,
            needed: FIT_DEGREE + 1,
        });
    }
    if state.coordinates() != record.coordinates.len() {
        return Err(SimError::InvalidParameter {
            name: "initial state",
            value: state.coordinates() as f64,
            why: "must have as many coordinates as the record",
        });
    }
    let clock = record.clock();
    let t0 = clock.time(start);
    let window = |valid_time: f64, censored: bool, left: Option<usize>| SystemWindowPrediction {
        start,
        start_time: t0,
        state: state.clone(),
        valid_time,
        censored,
        left,
    };
    let deltas: Vec<f64> = record
        .coordinates
        .iter()
        .map(|c| config.tolerance * c.spread)
        .collect();
    let (mut previous, first) = record.ratio(state.q().iter().copied(), start, &deltas);
    if previous > 1.0 {
        return Ok(window(0.0, false, Some(first)));
    }
    // The window ends at the horizon, the record's end, or before a gap in any coordinate.
    let mut last = start.saturating_add(config.horizon_samples(clock)).min(len - 1);
    if let Some(n) = (start + 1..=last).find(|&n| !record.finite_at(n)) {
        last = n - 1;
    }
    // Stretches that double in length from one drive period, each from the state where the one
    // before ended: a window that leaves the record early does not pay for its whole horizon.
    let mut from = start;
    let mut current = state.clone();
    let mut stretch = (clock.samples_per_period().round() as usize).max(1);
    while from < last {
        let to = from.saturating_add(stretch).min(last);
        let times: Vec<f64> = (from..=to).map(|n| clock.time(n)).collect();
        let run = free_run(system, &times, &current, config.tolerances)?;
        for (i, n) in (from + 1..=to).enumerate() {
            if run.q.iter().chain(&run.v).any(|x| !x[i + 1].is_finite()) {
                return Ok(window(clock.time(n - 1) - t0, false, None));
            }
            let (ratio, c) = record.ratio(run.q.iter().map(|q| q[i + 1]), n, &deltas);
            if ratio > 1.0 {
                // Linear in the ratio between the last sample within the tolerance and this one.
                let fraction = (1.0 - previous) / (ratio - previous);
                let crossing = clock.time(n - 1) + fraction * clock.step();
                return Ok(window(crossing - t0, false, Some(c)));
            }
            previous = ratio;
        }
        let end = to - from;
        let q: Vec<f64> = run.q.iter().map(|q| q[end]).collect();
        let v: Vec<f64> = run.v.iter().map(|v| v[end]).collect();
        current = MultiState::new(&q, &v)?;
        from = to;
        stretch = stretch.saturating_mul(2);
    }
    Ok(window(clock.time(last) - t0, true, None))
}

/// The valid prediction times of a system on a record's windows.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SystemPredictionTimes {
    /// Each window, in the order of the starts.
    pub windows: Vec<SystemWindowPrediction>,
    /// Each coordinate's tolerance in its record's unit.
    pub tolerances: Vec<f64>,
    /// The record's drive period, the unit of [`in_periods`](Self::in_periods).
    #[serde(alias = "forcing_period")]
    pub drive_period: f64,
}

impl SystemPredictionTimes {
    /// The summary in the record's time unit.
    pub fn summary(&self) -> Option<TimeSummary> {
        TimeSummary::of(self.windows.iter().map(|w| (w.valid_time, w.censored)))
    }

    /// The summary in drive periods.
    pub fn in_periods(&self) -> Option<TimeSummary> {
        let t = self.drive_period;
        TimeSummary::of(self.windows.iter().map(|w| (w.valid_time / t, w.censored)))
    }

    /// How many windows ended because coordinate `c` left its tolerance first.
    pub fn left_by(&self, c: usize) -> usize {
        self.windows.iter().filter(|w| w.left == Some(c)).count()
    }
}

/// The valid prediction time of `system` from each of `starts` (e.g.
/// [`system_prediction_starts`]), the state at each estimated from the record
/// ([`estimate_system_state`]). Windows run in parallel; the result does not depend on the
/// number of threads.
///
/// Errors: a start outside the record or without a state estimate, no start at all, a system of
/// another number of coordinates than the record.
pub fn system_valid_prediction_times<S: MultiSystem + Sync + ?Sized>(
    system: &S,
    record: &SystemPredictionRecord<'_>,
    starts: &[usize],
    config: &PredictionConfig,
) -> Result<SystemPredictionTimes, SimError> {
    if starts.is_empty() {
        return Err(SimError::RecordTooShort {
            len: record.len(),
            needed: 2 * config.half_width(record.clock()) + 1,
        });
    }
    if system.coordinates() != record.coordinates.len() {
        return Err(SimError::InvalidParameter {
            name: "system",
            value: system.coordinates() as f64,
            why: "must have as many coordinates as the record",
        });
    }
    let windows = starts
        .par_iter()
        .map(|&start| {
            let state = estimate_system_state(record, start, config)?;
            predict_system_window(system, record, start, &state, config)
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(SystemPredictionTimes {
        windows,
        tolerances: record
            .coordinates
            .iter()
            .map(|c| config.tolerance * c.spread)
            .collect(),
        drive_period: record.clock().drive_period(),
    })
}
