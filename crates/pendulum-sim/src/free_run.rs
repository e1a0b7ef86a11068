//! Free-run simulation: a model integrated over a record's grid from one initial state, driven by
//! nothing but its own terms (a measured drive among them), as system identification scores a
//! model on held-out data.
//!
//! - [`free_run`] integrates a [`SecondOrderSystem`] from `(t_first, x, x')` and samples it at
//!   `t_first + n · dt`. Systems that switch at `x' = 0` (dry friction) stick and slip as in every
//!   other simulation of this crate. Where the integration cannot go on (the solution blows up,
//!   the drive was not measured there, the step budget runs out) the run stops, says why
//!   ([`FreeRun::stopped`]) and its later samples are NaN: a diverging model is a result, not an
//!   error.
//! - [`fit_initial_state`] finds the initial state whose free run best matches the first samples
//!   of a record (least squares on the position, Levenberg–Marquardt from a local polynomial's
//!   state), the state a model may take from the measured output before it runs on its own.
//!
//! # Example
//!
//! ```
//! use pendulum_sim::{Domain, Duffing, Tolerances, fit_initial_state, free_run};
//!
//! let duffing = Duffing::two_well();
//! let truth = free_run(&duffing, 0.0, 0.1, 400, [1.0, 0.0], Tolerances::default())?;
//! // The state is found again from the first 30 samples of the run...
//! let fit = fit_initial_state(&duffing, &truth.x[..30], 0.0, 0.1, Domain::Line, Tolerances::default())?;
//! assert!((fit.state[0] - 1.0).abs() < 1e-6 && fit.state[1].abs() < 1e-6);
//! // ...and the model run from it follows the record.
//! let run = free_run(&duffing, 0.0, 0.1, 400, fit.state, Tolerances::default())?;
//! assert!(run.stopped.is_none());
//! assert!((run.x[399] - truth.x[399]).abs() < 1e-3);
//! # Ok::<(), pendulum_sim::SimError>(())
//! ```

use circle_signal::{Domain, wrap};
use nalgebra::{DMatrix, DVector, Matrix2, Vector2};

use crate::dop853::Tolerances;
use crate::error::SimError;
use crate::simulate::FirstOrder;
use crate::switching::{Flow, OnMode};
use crate::system::SecondOrderSystem;

/// A free run sampled on a grid.
#[derive(Debug, Clone, PartialEq)]
pub struct FreeRun {
    /// The position at `t_first + n · dt` (unwrapped on the circle); NaN from where the run
    /// stopped.
    pub x: Vec<f64>,
    /// The velocity at the same times.
    pub v: Vec<f64>,
    /// Why the integration stopped before the last sample, if it did: the error says where.
    pub stopped: Option<SimError>,
}

impl FreeRun {
    /// Samples with a finite state: all of them, or those before the run stopped.
    pub fn finite_len(&self) -> usize {
        self.x
            .iter()
            .zip(&self.v)
            .take_while(|(x, v)| x.is_finite() && v.is_finite())
            .count()
    }
}

/// Steps allowed per sample of a free run (plus a fixed allowance): far more than a smooth
/// solution takes at any sampling rate, few enough that a runaway model stops in seconds.
const STEPS_PER_SAMPLE: usize = 1_000;
const STEPS_BASE: usize = 100_000;

/// The step budget of an integration from `t = 0` to the last of `samples` samples `step` apart
/// whose first is at `first` (a simulation with its transient): [`STEPS_PER_SAMPLE`] for each
/// sample step of the whole span, plus [`STEPS_BASE`]. A runaway system (negative damping against a
/// hardening spring, whose steps shrink as it grows) then stops with
/// [`SimError::TooManySteps`](crate::SimError::TooManySteps) instead of grinding on.
pub(crate) fn simulation_budget(first: f64, step: f64, samples: usize) -> usize {
    steps_for(samples.saturating_add(transient_samples(first, step)))
}

/// [`STEPS_PER_SAMPLE`] for each of `samples`, plus [`STEPS_BASE`]: the budget of a free run.
pub(crate) fn steps_for(samples: usize) -> usize {
    STEPS_BASE.saturating_add(STEPS_PER_SAMPLE.saturating_mul(samples))
}

/// The sample steps from `t = 0` to `first`.
fn transient_samples(first: f64, step: f64) -> usize {
    if step > 0.0 && first > 0.0 {
        // Saturates for an absurd ratio (`as` clamps to `usize::MAX`).
        (first / step).ceil() as usize
    } else {
        0
    }
}

fn invalid(name: &'static str, value: f64, why: &'static str) -> SimError {
    SimError::InvalidParameter { name, value, why }
}

/// Integrates `system` from `state = (x, x')` at `t_first` and samples it at
/// `t_first + n · dt`, `n = 0..count`. Systems that switch at `x' = 0` stick and slip as in every
/// other simulation of this crate; where the integration cannot go on (the solution blows up, the
/// drive was not measured there, the step budget runs out) the run stops, says why
/// ([`FreeRun::stopped`]) and its later samples are NaN: a diverging model is a result.
///
/// Errors: [`SimError::InvalidParameter`] for a non-finite `t_first` or state, or a step `dt`
/// that is not positive and finite. Everything that goes wrong during the integration is
/// reported in [`FreeRun::stopped`] instead.
pub fn free_run<S: SecondOrderSystem>(
    system: &S,
    t_first: f64,
    dt: f64,
    count: usize,
    state: [f64; 2],
    tolerances: Tolerances,
) -> Result<FreeRun, SimError> {
    free_run_reporting(system, t_first, dt, count, state, tolerances, &mut |_| {})
}

/// [`free_run`], telling `progress` how many of the samples are done as it goes (at most
/// [`PROGRESS_REPORTS`](crate::multi::PROGRESS_REPORTS) times, and once all are), as
/// [`multi::free_run_reporting`](crate::multi::free_run_reporting) does for a system.
///
/// ```
/// use pendulum_sim::{Pendulum, Tolerances, free_run_reporting};
///
/// let mut told = Vec::new();
/// let run = free_run_reporting(&Pendulum::paper(), 0.0, 0.25, 400, [0.1, 0.0], Tolerances::default(), &mut |done| {
///     told.push(done)
/// })?;
/// assert!(run.stopped.is_none());
/// assert_eq!(told.last(), Some(&400));
/// assert!(told.windows(2).all(|w| w[0] < w[1]));
/// # Ok::<(), pendulum_sim::SimError>(())
/// ```
pub fn free_run_reporting<S: SecondOrderSystem>(
    system: &S,
    t_first: f64,
    dt: f64,
    count: usize,
    state: [f64; 2],
    tolerances: Tolerances,
    progress: &mut dyn FnMut(usize),
) -> Result<FreeRun, SimError> {
    if !t_first.is_finite() {
        return Err(invalid("start time", t_first, "must be finite"));
    }
    if !(dt.is_finite() && dt > 0.0) {
        return Err(invalid("step", dt, "must be positive and finite"));
    }
    for (name, value) in [("initial position", state[0]), ("initial velocity", state[1])] {
        if !value.is_finite() {
            return Err(invalid(name, value, "must be finite"));
        }
    }
    let mut x = vec![f64::NAN; count];
    let mut v = vec![f64::NAN; count];
    if count == 0 {
        return Ok(FreeRun { x, v, stopped: None });
    }
    let budget = steps_for(count);
    let every = count.div_ceil(crate::multi::PROGRESS_REPORTS).max(1);
    let outcome = Flow::new(FirstOrder(OnMode::new(system)), t_first, state, tolerances).and_then(|flow| {
        flow.with_max_steps(budget)
            .sample_grid(t_first, dt, count, |n, _, y| {
                x[n] = y[0];
                v[n] = y[1];
                if (n + 1) % every == 0 || n + 1 == count {
                    progress(n + 1);
                }
                std::ops::ControlFlow::Continue(())
            })
    });
    Ok(FreeRun {
        x,
        v,
        stopped: outcome.err(),
    })
}

/// An initial state fitted to a record's first samples.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InitialState {
    /// `(x, x')` at the first sample.
    pub state: [f64; 2],
    /// Root mean square of the free run's position less the samples it was fitted to.
    pub rms: f64,
    /// The samples it was fitted to.
    pub samples: usize,
}

/// Iterations of the Levenberg–Marquardt search.
const MAX_ITERATIONS: usize = 50;
/// Samples of the polynomial that gives the first guess of the velocity.
const GUESS_SAMPLES: usize = 5;

/// The state `(x, x')` at `t_first` whose free run of `system` (sampled every `dt`) best matches
/// `samples` in the least-squares sense, positions compared as [`Domain`] measures them (the
/// shortest arc on the circle).
///
/// The search starts from the first sample and the slope of the quadratic through the first few,
/// and takes Levenberg–Marquardt steps with a central-difference Jacobian; a state whose run stops
/// inside the samples counts as infinitely bad. With two samples it solves for the state that
/// passes through both; with more it smooths their noise.
///
/// Errors: [`SimError::RecordTooShort`] for fewer than 2 samples, [`SimError::InvalidParameter`]
/// for a non-finite sample or time or a step that is not positive, and [`SimError::NonFinite`]
/// when no state tried has a run that reaches the last sample.
pub fn fit_initial_state<S: SecondOrderSystem>(
    system: &S,
    samples: &[f64],
    t_first: f64,
    dt: f64,
    domain: Domain,
    tolerances: Tolerances,
) -> Result<InitialState, SimError> {
    let n = samples.len();
    if n < 2 {
        return Err(SimError::RecordTooShort { len: n, needed: 2 });
    }
    if let Some(&bad) = samples.iter().find(|s| !s.is_finite()) {
        return Err(invalid("sample", bad, "must be finite"));
    }
    if !(dt.is_finite() && dt > 0.0) {
        return Err(invalid("step", dt, "must be positive and finite"));
    }
    if !t_first.is_finite() {
        return Err(invalid("start time", t_first, "must be finite"));
    }
    // The samples unwrapped, so that a polynomial and the differences see one continuous angle.
    let mut y = Vec::with_capacity(n);
    y.push(samples[0]);
    for i in 1..n {
        let step = match domain {
            Domain::Circle => wrap(samples[i] - samples[i - 1]),
            Domain::Line => samples[i] - samples[i - 1],
        };
        y.push(y[i - 1] + step);
    }
    let spread =
        y.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b)) - y.iter().fold(f64::INFINITY, |a, &b| a.min(b));
    let scale_x = spread.max(y[0].abs() * 1e-3).max(f64::MIN_POSITIVE.sqrt());
    let duration = (n - 1) as f64 * dt;
    let scale_v = scale_x / duration;

    let residuals = |s: [f64; 2]| -> Option<Vec<f64>> {
        let run = free_run(system, t_first, dt, n, s, tolerances).ok()?;
        if run.stopped.is_some() {
            return None;
        }
        let r: Vec<f64> = run.x.iter().zip(&y).map(|(a, b)| a - b).collect();
        r.iter().all(|v| v.is_finite()).then_some(r)
    };
    let cost = |r: &[f64]| r.iter().map(|v| v * v).sum::<f64>();

    let mut state = [y[0], velocity_guess(&y, dt)];
    let mut r = match residuals(state) {
        Some(r) => r,
        None => {
            // A run from the guessed velocity may blow up in a stiff model: try from rest.
            state[1] = 0.0;
            residuals(state).ok_or(SimError::NonFinite { t: t_first })?
        }
    };
    let mut best = cost(&r);
    let mut lambda = 1e-3;
    for _ in 0..MAX_ITERATIONS {
        let h = [
            1e-6 * state[0].abs().max(scale_x),
            1e-6 * state[1].abs().max(scale_v),
        ];
        let mut jac = DMatrix::<f64>::zeros(n, 2);
        let mut ok = true;
        for k in 0..2 {
            let (mut up, mut down) = (state, state);
            up[k] += h[k];
            down[k] -= h[k];
            match (residuals(up), residuals(down)) {
                (Some(a), Some(b)) => {
                    for i in 0..n {
                        jac[(i, k)] = (a[i] - b[i]) / (2.0 * h[k]);
                    }
                }
                _ => ok = false,
            }
        }
        if !ok {
            break;
        }
        let jt = jac.transpose();
        let jtj: Matrix2<f64> = (&jt * &jac).fixed_view::<2, 2>(0, 0).into_owned();
        let g: Vector2<f64> = (&jt * DVector::from_column_slice(&r))
            .fixed_rows::<2>(0)
            .into_owned();
        let mut improved = false;
        for _ in 0..20 {
            let mut a = jtj;
            for k in 0..2 {
                a[(k, k)] += lambda * jtj[(k, k)].max(f64::MIN_POSITIVE);
            }
            let Some(delta) = a.lu().solve(&(-g)) else {
                lambda *= 10.0;
                continue;
            };
            let trial = [state[0] + delta[0], state[1] + delta[1]];
            match residuals(trial) {
                Some(rt) if cost(&rt) < best => {
                    let gain = best - cost(&rt);
                    state = trial;
                    best = cost(&rt);
                    r = rt;
                    lambda = (lambda / 10.0).max(1e-12);
                    improved = gain > 1e-14 * best.max(f64::MIN_POSITIVE);
                    break;
                }
                _ => lambda *= 10.0,
            }
        }
        if !improved {
            break;
        }
    }
    Ok(InitialState {
        state,
        rms: (best / n as f64).sqrt(),
        samples: n,
    })
}

/// The slope at the first sample of the least-squares quadratic (a line with fewer than three
/// samples) through the first [`GUESS_SAMPLES`] samples.
fn velocity_guess(y: &[f64], dt: f64) -> f64 {
    let m = y.len().min(GUESS_SAMPLES);
    let degree = (m - 1).min(2);
    let a = DMatrix::from_fn(m, degree + 1, |i, k| (i as f64).powi(k as i32));
    let b = DVector::from_iterator(m, y[..m].iter().map(|v| v - y[0]));
    match a.svd(true, true).solve(&b, 1e-12) {
        Ok(c) if c[1].is_finite() => c[1] / dt,
        _ => (y[1] - y[0]) / dt,
    }
}
