//! Systems of several coordinates: `n` second-order equations with inertial coupling (a double
//! pendulum, a chain of oscillators), and their simulation by the integrator and the sticking
//! logic of the one-coordinate systems.
//!
//! # The form
//!
//! A [`MultiSystem`] of `n` coordinates (`1 ≤ n ≤` [`MAX_COORDINATES`]) gives its accelerations
//! solved for, `q'' = A(t, q, q')`: a mechanical system `M(q) q'' = f(t, q, q')` solves its mass
//! matrix `M` (which does not depend on the velocities) at every evaluation, and says
//! [`SingularMass`] where `M` cannot be solved. It is integrated as the first-order system of size
//! `2n` with state `y = (q_1 … q_n, q_1' … q_n')` by the same [`Dop853`] (dispatched on `n` to
//! the const size `2n`), and sampled as every one-coordinate system is: on a whole grid or at any
//! step ([`simulate`], [`poincare_section`]), or at given times from one state, stopping with its
//! reason ([`free_run`]).
//!
//! # Dry friction, one coordinate at a time
//!
//! A coordinate `c` whose equation has terms in `sign(q_c')` or `|q_c'|` (dry friction, quadratic
//! drag) says so ([`MultiSystem::switches_at_rest`]); the integration then generalises the
//! one-coordinate rule of [`SecondOrderSystem::switches_at_rest`](crate::SecondOrderSystem::switches_at_rest) (Filippov's convention), with
//! every coordinate in one of three modes:
//!
//! - on a branch `s_c = ±1`: `sign(q_c') = s_c` and `|q_c'| = s_c q_c'`
//!   ([`MultiSystem::accelerations_with_signs`]), smooth, so DOP853 keeps its order; every
//!   `q_c' = 0` is looked for on the step's dense output at eight points and located by
//!   bisection to the last bit of the time, the step cut there;
//! - stuck: `q_c' = 0` held exactly, `q_c'' = 0`, while the others move. The accelerations are
//!   affine in the signs (each sign in terms of its own, never a product of two), because `M` does
//!   not depend on the velocities: `A(s) = A(0) + Σ_c s_c D_c`. So the value `σ_c` that holds the
//!   coordinate (the friction force it needs, as a fraction of the friction there is) solves the
//!   linear equations `A_c(σ) = 0` for the stuck coordinates (one equation each, evaluated at
//!   `σ = 0` and at each unit sign), and the others move under `A(σ)`: Filippov's sliding motion;
//! - from `q_c' = 0`, the branch `s` starts only if it accelerates away from rest on its own side
//!   (`s A_c > 0` with `sign(q_c') = s`, the other coordinates in their modes); if neither does,
//!   the coordinate sticks. For a dissipative friction this is `|σ_c| > 1`: the force needed to
//!   hold it exceeds the friction. While stuck that test is made along the step at points no
//!   further apart than the step the controller proposed when the coordinate stopped (and at
//!   least eight per step while other coordinates move), the release then bisected.
//!
//! Decisions are made one coordinate at a time: an event changes the mode of the coordinate that
//! caused it (and of any other that reached rest at the same instant), in the order of the
//! coordinates. A smooth system (no coordinate switches) runs through exactly the steps of
//! [`Dop853`] alone, and a one-coordinate system ([`OneCoordinate`]) through exactly the steps and
//! numbers of the one-coordinate simulation.
//!
//! # Example
//!
//! ```
//! use pendulum_sim::{DoublePendulum, MultiConfig, MultiState, multi};
//!
//! let pendulum = DoublePendulum::whirling();
//! let config = MultiConfig::new(MultiState::at_rest(&[2.0, 0.0])?)
//!     .with_samples_per_period(64)?
//!     .with_transient_periods(0)
//!     .with_samples(640)?;
//! let trajectory = multi::simulate(&pendulum, &config)?;
//! assert_eq!(trajectory.coordinates(), 2);
//! assert_eq!(trajectory.q[1].len(), 640);
//! // One coordinate as the one-coordinate simulation gives it (continuous; wrap it to display).
//! let link2 = trajectory.coordinate(1);
//! assert_eq!(link2.theta, trajectory.q[1]);
//! # Ok::<(), pendulum_sim::SimError>(())
//! ```

// Coordinate loops index several arrays in step; iterators would hide the formulas.
#![allow(clippy::needless_range_loop)]

use std::cell::Cell;
use std::ops::ControlFlow;

use serde::{Deserialize, Serialize};

use crate::dop853::{Dop853, OdeSystem, Stepper, Tolerances, sample_at_times, sample_on_grid};
use crate::error::{SimError, invalid};
use crate::free_run::steps_for;
use crate::simulate::{SimulationConfig, Trajectory};
use crate::switching::{Mode, SCAN_POINTS, STICK_SCANS_PER_STEP, first_event, ulp};
use crate::system::Branch;
use circle_signal::Domain;

pub use circle_signal::system::{MAX_COORDINATES, MultiSystem, OneCoordinate, SingularMass};

impl From<SingularMass> for SimError {
    fn from(e: SingularMass) -> Self {
        SimError::SingularMass {
            t: e.t,
            pivot: e.pivot,
        }
    }
}

/// A number of coordinates, checked to lie in `1..=MAX_COORDINATES`.
fn checked_coordinates(n: usize) -> Result<usize, SimError> {
    if (1..=MAX_COORDINATES).contains(&n) {
        Ok(n)
    } else {
        Err(invalid("coordinates", n as f64, "must lie in 1..=8"))
    }
}

/// The state of a system of several coordinates: its angles (or displacements) `q` and their
/// velocities `q'`, as many of each (`1..=`[`MAX_COORDINATES`]), all finite.
///
/// Serialised as `{"q": […], "v": […]}`; deserialising validates as [`MultiState::new`] does.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "MultiStateRaw", into = "MultiStateRaw")]
pub struct MultiState {
    q: Vec<f64>,
    v: Vec<f64>,
}

/// The serialised form of [`MultiState`].
#[derive(Serialize, Deserialize)]
struct MultiStateRaw {
    q: Vec<f64>,
    v: Vec<f64>,
}

impl TryFrom<MultiStateRaw> for MultiState {
    type Error = SimError;
    fn try_from(raw: MultiStateRaw) -> Result<Self, SimError> {
        Self::new(&raw.q, &raw.v)
    }
}

impl From<MultiState> for MultiStateRaw {
    fn from(s: MultiState) -> Self {
        Self { q: s.q, v: s.v }
    }
}

impl MultiState {
    /// The state `(q, q')`: as many velocities as coordinates, `1..=8` of them, all finite.
    pub fn new(q: &[f64], v: &[f64]) -> Result<Self, SimError> {
        checked_coordinates(q.len())?;
        if v.len() != q.len() {
            return Err(invalid(
                "velocities",
                v.len() as f64,
                "must be as many as the coordinates",
            ));
        }
        if let Some(&bad) = q.iter().find(|x| !x.is_finite()) {
            return Err(invalid("initial coordinate", bad, "must be finite"));
        }
        if let Some(&bad) = v.iter().find(|x| !x.is_finite()) {
            return Err(invalid("initial velocity", bad, "must be finite"));
        }
        Ok(Self {
            q: q.to_vec(),
            v: v.to_vec(),
        })
    }

    /// The state at `q` with every velocity zero.
    pub fn at_rest(q: &[f64]) -> Result<Self, SimError> {
        Self::new(q, &vec![0.0; q.len()])
    }

    /// The coordinates `q`.
    pub fn q(&self) -> &[f64] {
        &self.q
    }
    /// The velocities `q'`.
    pub fn v(&self) -> &[f64] {
        &self.v
    }
    /// The number of coordinates.
    pub fn coordinates(&self) -> usize {
        self.q.len()
    }

    /// The first-order state `(q, q')`.
    fn first_order(&self) -> Vec<f64> {
        self.q.iter().chain(&self.v).copied().collect()
    }
}

/// How to sample a simulation of several coordinates: the grid, transient, drive period, phase
/// and tolerances of [`SimulationConfig`] (see there; its defaults are the paper's,
/// [`SimulationConfig::paper`]), from an initial [`MultiState`] at `t = 0`.
///
/// Deserialising validates every field as the `with_*` setters do; the form is that of
/// [`SimulationConfig`] with `initial` a [`MultiState`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "MultiConfigRaw", into = "MultiConfigRaw")]
pub struct MultiConfig {
    /// The sampling; its one-coordinate initial state is not used.
    sampling: SimulationConfig,
    initial: MultiState,
}

/// The serialised form of [`MultiConfig`].
#[derive(Serialize, Deserialize)]
struct MultiConfigRaw {
    samples: usize,
    samples_per_period: usize,
    #[serde(default)]
    sample_step: Option<f64>,
    transient_periods: usize,
    initial: MultiState,
    forcing_period: f64,
    phase: f64,
    tolerances: Tolerances,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    max_steps: Option<usize>,
}

impl TryFrom<MultiConfigRaw> for MultiConfig {
    type Error = SimError;
    fn try_from(raw: MultiConfigRaw) -> Result<Self, SimError> {
        let config = Self::new(raw.initial)
            .with_samples(raw.samples)?
            .with_samples_per_period(raw.samples_per_period)?
            .with_transient_periods(raw.transient_periods)
            .with_drive_period(raw.forcing_period)?
            .with_phase(raw.phase)?
            .with_tolerances(raw.tolerances);
        let config = match raw.max_steps {
            Some(steps) => config.with_max_steps(steps)?,
            None => config,
        };
        match raw.sample_step {
            Some(h) => config.with_sample_step(h),
            None => Ok(config),
        }
    }
}

impl From<MultiConfig> for MultiConfigRaw {
    fn from(c: MultiConfig) -> Self {
        let s = &c.sampling;
        Self {
            samples: s.samples(),
            samples_per_period: s.samples_per_period(),
            sample_step: s.whole_samples_per_period().is_none().then(|| s.sample_step()),
            transient_periods: s.transient_periods(),
            initial: c.initial.clone(),
            forcing_period: s.drive_period(),
            phase: s.phase(),
            tolerances: s.tolerances(),
            max_steps: s.max_steps,
        }
    }
}

impl MultiConfig {
    /// The paper's sampling ([`SimulationConfig::paper`]: 30000 samples, 25 per period `2π`, 200
    /// transient periods, `rtol = 1e-10`) from `initial`.
    pub fn new(initial: MultiState) -> Self {
        Self {
            sampling: SimulationConfig::paper(),
            initial,
        }
    }

    /// The sampling of `sampling` (its one-coordinate initial state is not used) from `initial`.
    pub fn from_sampling(sampling: SimulationConfig, initial: MultiState) -> Self {
        Self { sampling, initial }
    }

    /// Number of samples kept (`>= 1`).
    pub fn with_samples(mut self, samples: usize) -> Result<Self, SimError> {
        self.sampling = self.sampling.with_samples(samples)?;
        Ok(self)
    }
    /// Samples per forcing period `P` (`>= 1`), the step `T / P`; see
    /// [`SimulationConfig::with_samples_per_period`].
    pub fn with_samples_per_period(mut self, p: usize) -> Result<Self, SimError> {
        self.sampling = self.sampling.with_samples_per_period(p)?;
        Ok(self)
    }
    /// Samples every `h`, whatever the ratio `T / h`; see [`SimulationConfig::with_sample_step`].
    pub fn with_sample_step(mut self, h: f64) -> Result<Self, SimError> {
        self.sampling = self.sampling.with_sample_step(h)?;
        Ok(self)
    }
    /// Forcing periods integrated and dropped before the first sample.
    pub fn with_transient_periods(mut self, periods: usize) -> Self {
        self.sampling = self.sampling.with_transient_periods(periods);
        self
    }
    /// The forcing period `T` in the system's time unit.
    pub fn with_drive_period(mut self, period: f64) -> Result<Self, SimError> {
        self.sampling = self.sampling.with_drive_period(period)?;
        Ok(self)
    }
    /// Phase of the sampling grid as a fraction of the forcing period, in `[0, 1)`.
    pub fn with_phase(mut self, phase: f64) -> Result<Self, SimError> {
        self.sampling = self.sampling.with_phase(phase)?;
        Ok(self)
    }
    /// Integration tolerances.
    pub fn with_tolerances(mut self, tolerances: Tolerances) -> Self {
        self.sampling = self.sampling.with_tolerances(tolerances);
        self
    }
    /// The most steps of the integration ([`SimulationConfig::with_max_steps`]; at least 1).
    pub fn with_max_steps(mut self, steps: usize) -> Result<Self, SimError> {
        self.sampling = self.sampling.with_max_steps(steps)?;
        Ok(self)
    }
    /// The initial state at `t = 0`.
    pub fn with_initial(mut self, initial: MultiState) -> Self {
        self.initial = initial;
        self
    }

    /// The sampling (grid, transient, period, phase, tolerances).
    pub fn sampling(&self) -> &SimulationConfig {
        &self.sampling
    }
    /// The initial state.
    pub fn initial(&self) -> &MultiState {
        &self.initial
    }
    /// Number of samples.
    pub fn samples(&self) -> usize {
        self.sampling.samples()
    }
    /// Time of the kept sample `n`, as [`SimulationConfig::sample_time`].
    pub fn sample_time(&self, n: usize) -> f64 {
        self.sampling.sample_time(n)
    }
}

/// A sampled trajectory of a system of several coordinates: absolute times and, per coordinate,
/// the continuous (unwrapped) coordinate and its velocity (`q[c][i]` at `t[i]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MultiTrajectory {
    /// Sample times.
    pub t: Vec<f64>,
    /// Each coordinate, continuous (wrap an angle for display or an encoder).
    pub q: Vec<Vec<f64>>,
    /// Each coordinate's velocity.
    pub v: Vec<Vec<f64>>,
}

impl MultiTrajectory {
    fn with_capacity(n: usize, samples: usize) -> Result<Self, SimError> {
        let mut series = crate::reserve_series(1 + 2 * n, samples)?;
        let v = series.split_off(1 + n);
        let q = series.split_off(1);
        let t = series.pop().expect("the times");
        Ok(Self { t, q, v })
    }

    /// Number of coordinates.
    pub fn coordinates(&self) -> usize {
        self.q.len()
    }
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }
    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }
    /// Coordinate `c` as a one-coordinate [`Trajectory`] (a copy).
    ///
    /// # Panics
    /// If `c` is not below [`coordinates`](Self::coordinates).
    pub fn coordinate(&self, c: usize) -> Trajectory {
        Trajectory {
            t: self.t.clone(),
            theta: self.q[c].clone(),
            omega: self.v[c].clone(),
        }
    }
}

/// A free run of a system of several coordinates at given times.
#[derive(Debug, Clone, PartialEq)]
pub struct MultiFreeRun {
    /// Each coordinate at each time (continuous); NaN from where the run stopped.
    pub q: Vec<Vec<f64>>,
    /// Each coordinate's velocity at each time; NaN from where the run stopped.
    pub v: Vec<Vec<f64>>,
    /// Why the integration stopped before the last time, if it did: a singular mass matrix
    /// ([`SimError::SingularMass`]), a state that is not finite, a step size that collapsed, the
    /// step budget; the error says where.
    pub stopped: Option<SimError>,
}

impl MultiFreeRun {
    /// Samples with a finite state: all of them, or those before the run stopped.
    pub fn finite_len(&self) -> usize {
        let len = self.q.first().map_or(0, Vec::len);
        (0..len)
            .take_while(|&i| {
                self.q.iter().all(|q| q[i].is_finite()) && self.v.iter().all(|v| v[i].is_finite())
            })
            .count()
    }
}

/// Simulates `system` from `config`'s initial state and samples it as `config` says, as
/// [`crate::simulate`] does for one coordinate.
///
/// Errors: [`SimError::InvalidParameter`] when the initial state has not as many coordinates as
/// the system, or the system's number is outside `1..=8`; the integration's errors
/// ([`SimError::SingularMass`], [`SimError::StepSizeTooSmall`], [`SimError::NonFinite`]).
pub fn simulate<S: MultiSystem + ?Sized>(
    system: &S,
    config: &MultiConfig,
) -> Result<MultiTrajectory, SimError> {
    simulate_with_progress(system, config, |_, _| {})
}

/// [`simulate`], calling `progress(done, total)` about a hundred times along the way (samples
/// done out of the total; the transient counts as no samples).
pub fn simulate_with_progress<S: MultiSystem + ?Sized>(
    system: &S,
    config: &MultiConfig,
    progress: impl FnMut(usize, usize),
) -> Result<MultiTrajectory, SimError> {
    let n = {
        let system: &dyn MultiSystem = &system;
        matching_coordinates(system, &config.initial)?
    };
    let mut traj = MultiTrajectory::with_capacity(n, config.sampling.samples())?;
    simulate_each(system, config, progress, |_, t, q, v| {
        traj.t.push(t);
        for c in 0..n {
            traj.q[c].push(q[c]);
            traj.v[c].push(v[c]);
        }
    })?;
    Ok(traj)
}

/// [`simulate_with_progress`] without the trajectory: `sample(i, t_i, q, q')` is called for each
/// sample in order with the coordinates and their velocities, the same numbers [`simulate`] keeps,
/// so a record of any length is made in constant memory.
///
/// Errors: as [`simulate`].
pub fn simulate_each<S: MultiSystem + ?Sized>(
    system: &S,
    config: &MultiConfig,
    progress: impl FnMut(usize, usize),
    mut sample: impl FnMut(usize, f64, &[f64], &[f64]),
) -> Result<(), SimError> {
    simulate_while(system, config, progress, |n, t, q, v| {
        sample(n, t, q, v);
        ControlFlow::Continue(())
    })
}

/// [`simulate_each`] until `sample` breaks: the integration ends at that sample (see
/// [`crate::simulate_while`]). `Ok` either way.
pub fn simulate_while<S: MultiSystem + ?Sized>(
    system: &S,
    config: &MultiConfig,
    mut progress: impl FnMut(usize, usize),
    mut sample: impl FnMut(usize, f64, &[f64], &[f64]) -> ControlFlow<()>,
) -> Result<(), SimError> {
    let system: &dyn MultiSystem = &system;
    let n = matching_coordinates(system, &config.initial)?;
    let sampling = &config.sampling;
    let samples = sampling.samples();
    let report_every = (samples / 100).max(1);
    progress(0, samples);
    let times = Times::Grid {
        first: sampling.first_sample_time(),
        step: sampling.sample_step(),
        count: samples,
    };
    // As for one coordinate: no stop at the end of the transient, so the step sequence depends
    // only on the end time; the sample times are the config's, by multiplication.
    let mut stopped = false;
    integrate(
        system,
        0.0,
        &config.initial.first_order(),
        sampling.tolerances(),
        sampling.step_budget(),
        &times,
        &mut |i, y| {
            let flow = sample(i, sampling.sample_time(i), &y[..n], &y[n..2 * n]);
            stopped = flow.is_break();
            if !stopped && (i + 1) % report_every == 0 {
                progress(i + 1, samples);
            }
            flow
        },
    )?;
    if !stopped {
        progress(samples, samples);
    }
    Ok(())
}

/// The stroboscopic (Poincaré) section: the state once per forcing period at the phase of
/// `config` (its samples-per-period and sample-step settings are ignored), as a trajectory with
/// one sample per period; coordinates as integrated (continuous).
pub fn poincare_section<S: MultiSystem + ?Sized>(
    system: &S,
    config: &MultiConfig,
) -> Result<MultiTrajectory, SimError> {
    let strobe = config.clone().with_samples_per_period(1)?;
    simulate(system, &strobe)
}

/// Integrates `system` from `state` at `times[0]` and samples it at each of `times` (finite,
/// non-decreasing; a record's own time stamps), as [`crate::free_run`] does for one coordinate:
/// where the integration cannot go on (a singular mass matrix, a state that is not finite, a step
/// size that collapses, the step budget of a thousand steps per sample runs out) the run stops,
/// says why ([`MultiFreeRun::stopped`]) and its later samples are NaN.
///
/// Errors: [`SimError::InvalidParameter`] for times that are not finite or decrease, or a state
/// with not as many coordinates as the system.
pub fn free_run<S: MultiSystem + ?Sized>(
    system: &S,
    times: &[f64],
    state: &MultiState,
    tolerances: Tolerances,
) -> Result<MultiFreeRun, SimError> {
    free_run_reporting(system, times, state, tolerances, &mut |_| {})
}

/// [`free_run`], telling `progress` how many of the samples are done as it goes (at most
/// [`PROGRESS_REPORTS`] times, and once all are): a stiff system's run can take minutes, which
/// a front end shows.
///
/// ```
/// use pendulum_sim::{CoupledDuffing, MultiState, Tolerances, multi};
///
/// let system = CoupledDuffing::two_wells();
/// let times: Vec<f64> = (0..1000).map(|i| i as f64 * 0.05).collect();
/// let state = MultiState::new(&[0.1, -0.2], &[0.0, 0.0])?;
/// let mut told = Vec::new();
/// let run = multi::free_run_reporting(&system, &times, &state, Tolerances::default(), &mut |done| told.push(done))?;
/// assert!(run.stopped.is_none());
/// assert_eq!(told.last(), Some(&1000));
/// assert!(told.windows(2).all(|w| w[0] < w[1]) && told.len() <= multi::PROGRESS_REPORTS + 1);
/// # Ok::<(), pendulum_sim::SimError>(())
/// ```
pub fn free_run_reporting<S: MultiSystem + ?Sized>(
    system: &S,
    times: &[f64],
    state: &MultiState,
    tolerances: Tolerances,
    progress: &mut dyn FnMut(usize),
) -> Result<MultiFreeRun, SimError> {
    let system: &dyn MultiSystem = &system;
    let n = matching_coordinates(system, state)?;
    if let Some(&bad) = times.iter().find(|t| !t.is_finite()) {
        return Err(invalid("sample time", bad, "must be finite"));
    }
    if let Some(w) = times.windows(2).find(|w| w[1] < w[0]) {
        return Err(invalid(
            "sample time",
            w[1],
            "must not be before the one before it",
        ));
    }
    let count = times.len();
    let mut q = vec![vec![f64::NAN; count]; n];
    let mut v = vec![vec![f64::NAN; count]; n];
    if count == 0 {
        return Ok(MultiFreeRun { q, v, stopped: None });
    }
    let budget = steps_for(count);
    let every = count.div_ceil(PROGRESS_REPORTS).max(1);
    let outcome = integrate(
        system,
        times[0],
        &state.first_order(),
        tolerances,
        budget,
        &Times::At(times),
        &mut |i, y| {
            for c in 0..n {
                q[c][i] = y[c];
                v[c][i] = y[n + c];
            }
            if (i + 1) % every == 0 || i + 1 == count {
                progress(i + 1);
            }
            ControlFlow::Continue(())
        },
    );
    Ok(MultiFreeRun {
        q,
        v,
        stopped: outcome.err(),
    })
}

/// The most times [`free_run_reporting`] tells its progress before the end.
pub const PROGRESS_REPORTS: usize = 200;

/// The system's number of coordinates, checked against `state`'s.
fn matching_coordinates(system: &dyn MultiSystem, state: &MultiState) -> Result<usize, SimError> {
    let n = checked_coordinates(system.coordinates())?;
    if state.coordinates() != n {
        return Err(invalid(
            "initial state",
            state.coordinates() as f64,
            "must have as many coordinates as the system",
        ));
    }
    Ok(n)
}

/// Where a run is sampled.
enum Times<'t> {
    /// `first + i · step`, `i = 0..count`.
    Grid { first: f64, step: f64, count: usize },
    /// At each of these.
    At(&'t [f64]),
}

/// Integrates from `(t0, y0)` (`y0 = (q, q')`, of the system's size) and calls `sink(i, y)` at
/// each sample time: the first-order state's const size `2n` chosen at run time.
fn integrate(
    system: &dyn MultiSystem,
    t0: f64,
    y0: &[f64],
    tolerances: Tolerances,
    max_steps: usize,
    times: &Times,
    sink: &mut dyn FnMut(usize, &[f64]) -> ControlFlow<()>,
) -> Result<(), SimError> {
    let args = (system, t0, y0, tolerances, max_steps, times);
    match system.coordinates() {
        1 => run::<2>(args, sink),
        2 => run::<4>(args, sink),
        3 => run::<6>(args, sink),
        4 => run::<8>(args, sink),
        5 => run::<10>(args, sink),
        6 => run::<12>(args, sink),
        7 => run::<14>(args, sink),
        8 => run::<16>(args, sink),
        n => Err(invalid("coordinates", n as f64, "must lie in 1..=8")),
    }
}

type RunArgs<'a, 't> = (
    &'a dyn MultiSystem,
    f64,
    &'a [f64],
    Tolerances,
    usize,
    &'a Times<'t>,
);

/// [`integrate`] at the const size `N = 2n`.
fn run<const N: usize>(
    (system, t0, y0, tolerances, max_steps, times): RunArgs<'_, '_>,
    sink: &mut dyn FnMut(usize, &[f64]) -> ControlFlow<()>,
) -> Result<(), SimError> {
    let y0: [f64; N] = std::array::from_fn(|i| y0[i]);
    let mut flow = MultiFlow::<N>::new(system, t0, y0, tolerances, max_steps)?;
    match *times {
        Times::Grid { first, step, count } => {
            sample_on_grid(&mut flow, first, step, count, |i, _, y| sink(i, y))
        }
        Times::At(at) => sample_at_times(&mut flow, at.len(), |i| at[i], |i, _, y| sink(i, y)),
    }
}

/// A system in its coordinates' modes, as the first-order system `(q, q')' = (q', A)` of the
/// integrator. A singular mass matrix makes the accelerations NaN (so the integrator rejects the
/// step) and is remembered, so that the integration's failure can say why.
struct Coupled<'a> {
    system: &'a dyn MultiSystem,
    n: usize,
    /// Whether any coordinate switches at rest (else the system is evaluated as it stands).
    switching: bool,
    modes: [Mode; MAX_COORDINATES],
    singular: Cell<Option<SingularMass>>,
}

impl<const N: usize> OdeSystem<N> for Coupled<'_> {
    #[inline]
    fn rhs(&self, t: f64, y: &[f64; N], dy: &mut [f64; N]) {
        let n = self.n;
        let (q, v) = y.split_at(n);
        let (dq, acc) = dy.split_at_mut(n);
        dq.copy_from_slice(v);
        if let Err(e) = self.accelerations(&self.modes, t, q, v, acc) {
            self.singular.set(Some(e));
            acc.fill(f64::NAN);
        }
    }
}

impl Coupled<'_> {
    /// The accelerations with every coordinate in its mode: on a branch with its sign; stuck with
    /// the held values that keep the stuck coordinates' accelerations at zero (then exactly zero).
    fn accelerations(
        &self,
        modes: &[Mode; MAX_COORDINATES],
        t: f64,
        q: &[f64],
        v: &[f64],
        acc: &mut [f64],
    ) -> Result<(), SingularMass> {
        let n = self.n;
        if !self.switching {
            return self.system.accelerations(t, q, v, acc);
        }
        let mut signs = [0.0; MAX_COORDINATES];
        let mut stuck = [0; MAX_COORDINATES];
        let mut k = 0;
        for c in 0..n {
            match modes[c] {
                Mode::Slip(branch) => signs[c] = branch.sign(),
                Mode::Stuck => {
                    stuck[k] = c;
                    k += 1;
                }
                Mode::Smooth => {}
            }
        }
        if k == n {
            acc.fill(0.0);
            return Ok(());
        }
        self.system.accelerations_with_signs(t, q, v, &signs[..n], acc)?;
        if k == 0 {
            return Ok(());
        }
        // The accelerations are affine in the signs: D_j = A(s + e_j) − A(s) for stuck j.
        let mut columns = [[0.0; MAX_COORDINATES]; MAX_COORDINATES];
        for (j, column) in columns.iter_mut().enumerate().take(k) {
            let mut unit = signs;
            unit[stuck[j]] = 1.0;
            let mut a = [0.0; MAX_COORDINATES];
            self.system
                .accelerations_with_signs(t, q, v, &unit[..n], &mut a[..n])?;
            for i in 0..n {
                column[i] = a[i] - acc[i];
            }
        }
        // Held values σ: Σ_j D_j[stuck i] σ_j = −A(s)[stuck i].
        let mut matrix = [[0.0; MAX_COORDINATES]; MAX_COORDINATES];
        let mut rhs = [0.0; MAX_COORDINATES];
        for i in 0..k {
            for j in 0..k {
                matrix[i][j] = columns[j][stuck[i]];
            }
            rhs[i] = -acc[stuck[i]];
        }
        let held = solve_held(k, &mut matrix, &mut rhs);
        for j in 0..k {
            if held[j] != 0.0 {
                for i in 0..n {
                    acc[i] += held[j] * columns[j][i];
                }
            }
        }
        for &c in &stuck[..k] {
            acc[c] = 0.0;
        }
        Ok(())
    }

    /// The mode of coordinate `c` at rest (`y`'s velocity of `c` taken as zero), `preferred`
    /// tried first: a branch `s` on which it accelerates away from rest on its own side, the
    /// others in `modes`; or stuck.
    fn leaving_rest(
        &self,
        modes: &[Mode; MAX_COORDINATES],
        c: usize,
        preferred: Branch,
        t: f64,
        y: &[f64],
    ) -> Result<Mode, SingularMass> {
        let n = self.n;
        let q = &y[..n];
        let mut v = [0.0; MAX_COORDINATES];
        v[..n].copy_from_slice(&y[n..2 * n]);
        v[c] = 0.0;
        let mut trial = *modes;
        let mut acc = [0.0; MAX_COORDINATES];
        for branch in [preferred, preferred.reversed()] {
            trial[c] = Mode::Slip(branch);
            self.accelerations(&trial, t, q, &v[..n], &mut acc[..n])?;
            if branch.sign() * acc[c] > 0.0 {
                return Ok(Mode::Slip(branch));
            }
        }
        Ok(Mode::Stuck)
    }
}

/// Solves `m x = r` for a 2×2 mass matrix (in an equation's normalised form or symmetric). The
/// matrix cannot be solved where its determinant, relative to the product of its diagonal, is not
/// above a few rounding errors (singular, or not positive definite). The solution is by Gaussian
/// elimination with partial pivoting, backward stable (Cramer's rule is not, for an
/// ill-conditioned matrix).
#[inline]
pub(crate) fn solve2(m: [[f64; 2]; 2], r: [f64; 2], t: f64) -> Result<[f64; 2], SingularMass> {
    let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    let pivot = det / (m[0][0] * m[1][1]).abs();
    // NaN (a state that is not finite) is not a singular matrix: it passes on as NaN.
    if pivot <= 4.0 * f64::EPSILON {
        return Err(SingularMass { t, pivot });
    }
    let (top, bottom, r_top, r_bottom) = if m[1][0].abs() > m[0][0].abs() {
        (m[1], m[0], r[1], r[0])
    } else {
        (m[0], m[1], r[0], r[1])
    };
    let l = bottom[0] / top[0];
    let x1 = (r_bottom - l * r_top) / (bottom[1] - l * top[1]);
    let x0 = (r_top - top[1] * x1) / top[0];
    Ok([x0, x1])
}

/// Solves the `k × k` system `matrix · σ = rhs` by Gaussian elimination with partial pivoting.
/// An unknown whose pivot is zero (no value of its sign moves the stuck equations) is zero.
fn solve_held(
    k: usize,
    matrix: &mut [[f64; MAX_COORDINATES]; MAX_COORDINATES],
    rhs: &mut [f64; MAX_COORDINATES],
) -> [f64; MAX_COORDINATES] {
    for col in 0..k {
        let pivot_row = (col..k)
            .max_by(|&a, &b| matrix[a][col].abs().total_cmp(&matrix[b][col].abs()))
            .unwrap_or(col);
        matrix.swap(col, pivot_row);
        rhs.swap(col, pivot_row);
        let p = matrix[col][col];
        if p == 0.0 {
            continue;
        }
        for row in col + 1..k {
            let factor = matrix[row][col] / p;
            if factor != 0.0 {
                for j in col..k {
                    matrix[row][j] -= factor * matrix[col][j];
                }
                rhs[row] -= factor * rhs[col];
            }
        }
    }
    let mut sigma = [0.0; MAX_COORDINATES];
    for row in (0..k).rev() {
        let p = matrix[row][row];
        if p == 0.0 {
            continue;
        }
        let known: f64 = (row + 1..k).map(|j| matrix[row][j] * sigma[j]).sum();
        sigma[row] = (rhs[row] - known) / p;
    }
    sigma
}

/// The adaptive DOP853 integration of a system of several coordinates across their `q_c' = 0`
/// (see the [module documentation](self)): one accepted step at a time, each ending at the
/// step's end or at an event, with dense output inside it.
struct MultiFlow<'a, const N: usize> {
    ode: Dop853<Coupled<'a>, N>,
    /// An event located in the last step: its time, the state there and the modes after it.
    pending: Option<(f64, [f64; N], [Mode; MAX_COORDINATES])>,
    /// Per stuck coordinate: the largest spacing of the test for its release.
    scan_step: [f64; MAX_COORDINATES],
}

impl<'a, const N: usize> MultiFlow<'a, N> {
    /// Starts at `(t0, y0)` in the modes of that state, decided one coordinate at a time.
    fn new(
        system: &'a dyn MultiSystem,
        t0: f64,
        y0: [f64; N],
        tolerances: Tolerances,
        max_steps: usize,
    ) -> Result<Self, SimError> {
        let n = N / 2;
        let mut coupled = Coupled {
            system,
            n,
            switching: (0..n).any(|c| system.switches_at_rest(c)),
            modes: [Mode::Smooth; MAX_COORDINATES],
            singular: Cell::new(None),
        };
        let mut modes = [Mode::Smooth; MAX_COORDINATES];
        if y0.iter().all(|x| x.is_finite()) {
            for c in (0..n).filter(|&c| system.switches_at_rest(c)) {
                modes[c] = Branch::of(y0[n + c]).map_or(Mode::Stuck, Mode::Slip);
            }
            for c in 0..n {
                if modes[c] == Mode::Stuck {
                    modes[c] = coupled.leaving_rest(&modes, c, Branch::Forward, t0, &y0)?;
                }
            }
            // A mass matrix that cannot be solved at the start is the reason, not its NaN.
            let mut acc = [0.0; MAX_COORDINATES];
            coupled.accelerations(&modes, t0, &y0[..n], &y0[n..], &mut acc[..n])?;
        }
        // Coordinates at rest start with the step a motion from there would take: the time scale
        // of the test for their release.
        let start = modes.map(|m| {
            if m == Mode::Stuck {
                Mode::Slip(Branch::Forward)
            } else {
                m
            }
        });
        coupled.modes = start;
        let mut ode = Dop853::new(coupled, t0, y0, tolerances)?.with_max_steps(max_steps);
        let scan_step = [ode.proposed_step(); MAX_COORDINATES];
        if start != modes {
            ode.system_mut().modes = modes;
            ode.restart(t0, y0)?;
        }
        Ok(Self {
            ode,
            pending: None,
            scan_step,
        })
    }

    /// The current time: the end of the last step, or its event.
    fn t(&self) -> f64 {
        self.pending.map_or(self.ode.t(), |(t, ..)| t)
    }

    /// The current state.
    fn y(&self) -> [f64; N] {
        match &self.pending {
            Some((_, y, _)) => *y,
            None => *self.ode.y(),
        }
    }

    /// Restarts at the event of the last step, if any, in the modes after it.
    fn apply_pending(&mut self) -> Result<(), SimError> {
        if let Some((t, y, modes)) = self.pending.take() {
            self.ode.system_mut().modes = modes;
            self.ode.restart(t, y)?;
        }
        Ok(())
    }

    /// Takes one accepted step, not going past `t_limit`, and stops at the first event inside
    /// it.
    fn step(&mut self, t_limit: f64) -> Result<f64, SimError> {
        self.apply_pending()?;
        let n = N / 2;
        let t0 = self.ode.t();
        let modes = self.ode.system().modes;
        let mut limit = t_limit;
        for c in 0..n {
            if modes[c] == Mode::Stuck {
                limit = limit.min(t0 + STICK_SCANS_PER_STEP * self.scan_step[c]);
            }
        }
        let limit = if limit > t0 { limit } else { t_limit };
        let t1 = match self.ode.step(limit) {
            Ok(t1) => t1,
            Err(e) => return Err(self.ode.system().singular.take().map_or(e, SimError::from)),
        };
        // A rejected attempt inside the step may have met a singular matrix; the step did not.
        self.ode.system().singular.set(None);
        let all_stuck = (0..n).all(|c| modes[c] == Mode::Stuck);
        let mut first: Option<(f64, usize)> = None;
        for c in 0..n {
            let event = match modes[c] {
                Mode::Smooth => None,
                Mode::Slip(branch) => {
                    let s = branch.sign();
                    first_event(t0, t1, SCAN_POINTS, |t| s * self.ode.interpolate(t)[n + c] <= 0.0)
                }
                Mode::Stuck => {
                    let scans = ((t1 - t0) / self.scan_step[c])
                        .ceil()
                        .clamp(1.0, STICK_SCANS_PER_STEP) as usize;
                    // While other coordinates move, the force that holds this one changes
                    // within the step as fast as they do.
                    let scans = if all_stuck { scans } else { scans.max(SCAN_POINTS) };
                    let ode = &mut self.ode;
                    first_event(t0, t1, scans, |t| {
                        let y = ode.interpolate(t);
                        !matches!(
                            ode.system().leaving_rest(&modes, c, Branch::Forward, t, &y),
                            Ok(Mode::Stuck)
                        )
                    })
                }
            };
            if let Some(te) = event
                && first.is_none_or(|(tf, _)| te < tf)
            {
                first = Some((te, c));
            }
        }
        let Some((te, c)) = first else {
            return Ok(t1);
        };
        let mut y = self.ode.interpolate(te);
        let mut next = modes;
        let coupled = self.ode.system();
        match modes[c] {
            Mode::Slip(branch) => {
                y[n + c] = 0.0;
                // A slip shorter than the resolution of the time cannot leave rest: a stick.
                next[c] = if te - t0 <= 16.0 * ulp(t0) {
                    Mode::Stuck
                } else {
                    coupled.leaving_rest(&next, c, branch.reversed(), te, &y)?
                };
            }
            _ => next[c] = coupled.leaving_rest(&next, c, Branch::Forward, te, &y)?,
        }
        let mut stopped = [false; MAX_COORDINATES];
        stopped[c] = next[c] == Mode::Stuck && modes[c] != Mode::Stuck;
        // Others that reached rest at the same instant.
        for d in (0..n).filter(|&d| d != c) {
            if let Mode::Slip(branch) = next[d]
                && branch.sign() * y[n + d] <= 0.0
            {
                y[n + d] = 0.0;
                next[d] = coupled.leaving_rest(&next, d, branch.reversed(), te, &y)?;
                stopped[d] = next[d] == Mode::Stuck;
            }
        }
        let proposed = self.ode.proposed_step();
        for d in 0..n {
            if stopped[d] {
                self.scan_step[d] = proposed;
            }
        }
        self.pending = Some((te, y, next));
        Ok(te)
    }

    /// The dense-output value at `t` between the last step's start and [`MultiFlow::t`].
    fn interpolate(&mut self, t: f64) -> [f64; N] {
        match &self.pending {
            Some((te, y, _)) if *te == t => *y,
            _ => self.ode.interpolate(t),
        }
    }
}

impl<const N: usize> Stepper<N> for MultiFlow<'_, N> {
    fn now(&self) -> f64 {
        self.t()
    }
    fn state(&self) -> [f64; N] {
        self.y()
    }
    fn advance(&mut self, t_limit: f64) -> Result<f64, SimError> {
        self.step(t_limit)
    }
    fn state_at(&mut self, t: f64) -> [f64; N] {
        self.interpolate(t)
    }
}

/// An initial state of a system of several coordinates fitted to a record's first samples.
#[derive(Debug, Clone, PartialEq)]
pub struct MultiInitialState {
    /// The state `(q, q')` at the first sample.
    pub state: MultiState,
    /// Root mean square, over the coordinates and samples, of the free run's positions less the
    /// samples it was fitted to.
    pub rms: f64,
    /// The samples it was fitted to.
    pub samples: usize,
}

/// The state at `times[0]` whose free run of `system` over `times` best matches `samples` (one
/// slice per coordinate, as many as `times`) in the least-squares sense, positions compared as
/// each coordinate's [`Domain`] measures them (the shortest arc on the circle): the
/// one-coordinate [`crate::fit_initial_state`] for `n` coordinates.
///
/// The search starts from the first samples and the slopes of the quadratics through the first
/// few, and takes Levenberg–Marquardt steps with a central-difference Jacobian (`2n` unknowns);
/// a state whose run stops inside the samples counts as infinitely bad.
///
/// Errors: [`SimError::RecordTooShort`] for fewer than 2 samples, [`SimError::InvalidParameter`]
/// for samples of another count or not finite, and [`SimError::NonFinite`] when no state tried
/// has a run that reaches the last sample.
pub fn fit_initial_state<S: MultiSystem + ?Sized>(
    system: &S,
    samples: &[&[f64]],
    domains: &[Domain],
    times: &[f64],
    tolerances: Tolerances,
) -> Result<MultiInitialState, SimError> {
    use nalgebra::{DMatrix, DVector};
    let n = checked_coordinates(samples.len())?;
    let len = times.len();
    if len < 2 {
        return Err(SimError::RecordTooShort { len, needed: 2 });
    }
    if domains.len() != n || system.coordinates() != n {
        return Err(invalid(
            "coordinates",
            n as f64,
            "samples, domains and the system must have as many",
        ));
    }
    if let Some(s) = samples.iter().find(|s| s.len() != len) {
        return Err(invalid("samples", s.len() as f64, "must be one per time"));
    }
    if let Some(&bad) = samples.iter().flat_map(|s| s.iter()).find(|v| !v.is_finite()) {
        return Err(invalid("sample", bad, "must be finite"));
    }
    // Each coordinate unwrapped, so that the slopes and the residuals see continuous angles.
    let y: Vec<Vec<f64>> = samples
        .iter()
        .zip(domains)
        .map(|(s, &domain)| {
            let mut y = Vec::with_capacity(len);
            y.push(s[0]);
            for i in 1..len {
                let step = match domain {
                    Domain::Circle => circle_signal::wrap(s[i] - s[i - 1]),
                    Domain::Line => s[i] - s[i - 1],
                };
                y.push(y[i - 1] + step);
            }
            y
        })
        .collect();
    let duration = times[len - 1] - times[0];
    if !(duration.is_finite() && duration > 0.0) {
        return Err(invalid("times", duration, "must span a positive, finite time"));
    }
    let scales: Vec<f64> = y
        .iter()
        .map(|y| {
            let spread = y.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b))
                - y.iter().fold(f64::INFINITY, |a, &b| a.min(b));
            spread.max(y[0].abs() * 1e-3).max(f64::MIN_POSITIVE.sqrt())
        })
        .collect();
    let residuals = |p: &[f64]| -> Option<Vec<f64>> {
        let state = MultiState::new(&p[..n], &p[n..]).ok()?;
        let run = free_run(system, times, &state, tolerances).ok()?;
        if run.stopped.is_some() {
            return None;
        }
        let r: Vec<f64> = (0..n)
            .flat_map(|c| run.q[c].iter().zip(&y[c]).map(|(a, b)| a - b).collect::<Vec<_>>())
            .collect();
        r.iter().all(|v| v.is_finite()).then_some(r)
    };
    let cost = |r: &[f64]| r.iter().map(|v| v * v).sum::<f64>();
    // The first guess: the first samples, and the slope at the first of the quadratic through
    // the first three (the line through two).
    let mut p: Vec<f64> = y.iter().map(|y| y[0]).collect();
    for y in &y {
        let slope = if len >= 3 {
            let (h1, h2) = (times[1] - times[0], times[2] - times[0]);
            let (d1, d2) = ((y[1] - y[0]) / h1, (y[2] - y[0]) / h2);
            (d1 * h2 - d2 * h1) / (h2 - h1)
        } else {
            (y[1] - y[0]) / (times[1] - times[0])
        };
        p.push(if slope.is_finite() { slope } else { 0.0 });
    }
    let mut r = match residuals(&p) {
        Some(r) => r,
        None => {
            p[n..].fill(0.0);
            residuals(&p).ok_or(SimError::NonFinite { t: times[0] })?
        }
    };
    let mut best = cost(&r);
    let mut lambda = 1e-3;
    let k = 2 * n;
    for _ in 0..50 {
        let mut jac = DMatrix::<f64>::zeros(r.len(), k);
        let mut ok = true;
        for j in 0..k {
            let scale = if j < n {
                scales[j]
            } else {
                scales[j - n] / duration
            };
            let h = 1e-6 * p[j].abs().max(scale);
            let (mut up, mut down) = (p.clone(), p.clone());
            up[j] += h;
            down[j] -= h;
            match (residuals(&up), residuals(&down)) {
                (Some(a), Some(b)) => {
                    for i in 0..r.len() {
                        jac[(i, j)] = (a[i] - b[i]) / (2.0 * h);
                    }
                }
                _ => ok = false,
            }
        }
        if !ok {
            break;
        }
        let jtj = jac.transpose() * &jac;
        let g = jac.transpose() * DVector::from_column_slice(&r);
        let mut improved = false;
        for _ in 0..20 {
            let mut a = jtj.clone();
            for j in 0..k {
                a[(j, j)] += lambda * jtj[(j, j)].max(f64::MIN_POSITIVE);
            }
            let Some(delta) = a.lu().solve(&(-&g)) else {
                lambda *= 10.0;
                continue;
            };
            let trial: Vec<f64> = p.iter().zip(delta.iter()).map(|(a, d)| a + d).collect();
            match residuals(&trial) {
                Some(rt) if cost(&rt) < best => {
                    let gain = best - cost(&rt);
                    p = trial;
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
    Ok(MultiInitialState {
        state: MultiState::new(&p[..n], &p[n..])?,
        rms: (best / (n * len) as f64).sqrt(),
        samples: len,
    })
}
