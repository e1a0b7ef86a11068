//! Sampled trajectories, stroboscopic (Poincaré) sections and the largest Lyapunov exponent.

use std::f64::consts::TAU;
use std::ops::ControlFlow;

use crate::dop853::{OdeSystem, Tolerances};
use crate::error::SimError;
use crate::free_run::simulation_budget;
use crate::switching::{Flow, OnMode, Switched};
use crate::system::SecondOrderSystem;

/// A second-order system seen as the first-order system `(x, v)' = (v, F(t, x, v))`.
#[derive(Debug, Clone, Copy)]
pub struct FirstOrder<S>(pub S);

impl<S: SecondOrderSystem> OdeSystem<2> for FirstOrder<S> {
    #[inline]
    fn rhs(&self, t: f64, y: &[f64; 2], dy: &mut [f64; 2]) {
        *dy = [y[1], self.0.acceleration(t, y[0], y[1])];
    }
}

impl<S: SecondOrderSystem> Switched<2> for FirstOrder<OnMode<S>> {
    type System = S;
    fn on_mode(&self) -> &OnMode<S> {
        &self.0
    }
    fn on_mode_mut(&mut self) -> &mut OnMode<S> {
        &mut self.0
    }
}

/// A second-order system with its tangent-linear equation: state `(x, v, δx, δv)`.
#[derive(Debug, Clone, Copy)]
pub struct Tangent<S>(pub S);

impl<S: SecondOrderSystem> OdeSystem<4> for Tangent<S> {
    #[inline]
    fn rhs(&self, t: f64, y: &[f64; 4], dy: &mut [f64; 4]) {
        let [jx, jv] = self.0.jacobian(t, y[0], y[1]);
        *dy = [
            y[1],
            self.0.acceleration(t, y[0], y[1]),
            y[3],
            jx * y[2] + jv * y[3],
        ];
    }
}

impl<S: SecondOrderSystem> Switched<4> for Tangent<OnMode<S>> {
    type System = S;
    fn on_mode(&self) -> &OnMode<S> {
        &self.0
    }
    fn on_mode_mut(&mut self) -> &mut OnMode<S> {
        &mut self.0
    }
}

/// How to sample a simulation: the paper's settings by default ([`SimulationConfig::paper`]).
///
/// Samples are taken at `t_n = phase · T + n · T / P` for `n = n_0 .. n_0 + samples`, where
/// `n_0 = transient_periods · P`, `T` is the forcing period and `P` the samples per period; the
/// integration starts at `t = 0` from the initial state. So with `phase = 0` the first sample is at
/// `t = transient_periods · T`, at the forcing's phase zero.
///
/// With a sample step `h` instead ([`with_sample_step`](Self::with_sample_step)), any ratio `T / h`,
/// whole or not (a 1.02 Hz drive sampled at 500 Hz), sample `n = 0 .. samples` is at
/// `t_n = t_0 + n · h` with `t_0 = phase · T + transient_periods · T`, again by multiplication.
///
/// Deserialising validates every field as the `with_*` setters do.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(try_from = "SimulationConfigRaw", into = "SimulationConfigRaw")]
pub struct SimulationConfig {
    samples: usize,
    samples_per_period: usize,
    /// A sample step that overrides `T / P`, for any ratio of forcing period to step.
    sample_step: Option<f64>,
    transient_periods: usize,
    initial: [f64; 2],
    forcing_period: f64,
    phase: f64,
    tolerances: Tolerances,
    /// The most steps of the integration, when not [`SimulationConfig::step_budget`]'s default.
    pub(crate) max_steps: Option<usize>,
}

/// The serialised form of [`SimulationConfig`] (`sample_step` absent or `null` for the whole grid;
/// `max_steps` absent or `null` for the default budget).
#[derive(serde::Serialize, serde::Deserialize)]
struct SimulationConfigRaw {
    samples: usize,
    samples_per_period: usize,
    #[serde(default)]
    sample_step: Option<f64>,
    transient_periods: usize,
    initial: [f64; 2],
    forcing_period: f64,
    phase: f64,
    tolerances: Tolerances,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    max_steps: Option<usize>,
}

impl TryFrom<SimulationConfigRaw> for SimulationConfig {
    type Error = SimError;
    fn try_from(raw: SimulationConfigRaw) -> Result<Self, SimError> {
        let config = Self::paper()
            .with_samples(raw.samples)?
            .with_samples_per_period(raw.samples_per_period)?
            .with_transient_periods(raw.transient_periods)
            .with_initial(raw.initial[0], raw.initial[1])?
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

impl From<SimulationConfig> for SimulationConfigRaw {
    fn from(c: SimulationConfig) -> Self {
        Self {
            samples: c.samples,
            samples_per_period: c.samples_per_period,
            sample_step: c.sample_step,
            transient_periods: c.transient_periods,
            initial: c.initial,
            forcing_period: c.forcing_period,
            phase: c.phase,
            tolerances: c.tolerances,
            max_steps: c.max_steps,
        }
    }
}

fn invalid(name: &'static str, value: f64, why: &'static str) -> SimError {
    SimError::InvalidParameter { name, value, why }
}

/// A forcing period, checked to be positive and finite (the one rule every config shares).
pub(crate) fn checked_period(period: f64) -> Result<f64, SimError> {
    if period.is_finite() && period > 0.0 {
        Ok(period)
    } else {
        Err(invalid("forcing period", period, "must be positive and finite"))
    }
}

impl Default for SimulationConfig {
    fn default() -> Self {
        Self::paper()
    }
}

impl SimulationConfig {
    /// The paper's data set: 30000 samples, 25 per forcing period `2π`, after 200 periods of
    /// transient from `θ(0) = 0.1, θ'(0) = 0`, at `rtol = 1e-10` (`atol = 1e-11`).
    pub fn paper() -> Self {
        Self {
            samples: 30_000,
            samples_per_period: 25,
            sample_step: None,
            transient_periods: 200,
            initial: [0.1, 0.0],
            forcing_period: TAU,
            phase: 0.0,
            tolerances: Tolerances::default(),
            max_steps: None,
        }
    }

    /// The most steps (accepted and rejected) the integration may take, its transient included,
    /// instead of the default [`step_budget`](Self::step_budget); past it the simulation stops
    /// with [`SimError::TooManySteps`]. Raise it for a stiff system (`usize::MAX`: no limit).
    /// At least 1.
    pub fn with_max_steps(mut self, steps: usize) -> Result<Self, SimError> {
        if steps == 0 {
            return Err(invalid("max_steps", 0.0, "must be at least 1"));
        }
        self.max_steps = Some(steps);
        Ok(self)
    }

    /// The most steps the integration may take: the one given
    /// ([`with_max_steps`](Self::with_max_steps)), or by default 1000 for each sample step of
    /// the whole span (the transient included) plus 100000, far more than a smooth solution
    /// takes at any sampling rate, so that a runaway system (negative damping against a
    /// hardening spring, whose steps shrink as it grows) stops in seconds instead of grinding on.
    pub fn step_budget(&self) -> usize {
        self.max_steps
            .unwrap_or_else(|| simulation_budget(self.first_sample_time(), self.sample_step(), self.samples))
    }

    /// Number of samples kept (`>= 1`).
    pub fn with_samples(mut self, samples: usize) -> Result<Self, SimError> {
        if samples == 0 {
            return Err(invalid("samples", 0.0, "must be at least 1"));
        }
        self.samples = samples;
        Ok(self)
    }

    /// Samples per forcing period `P` (`>= 1`): the sample step is `T / P` (this replaces a step
    /// set by [`with_sample_step`](Self::with_sample_step)).
    pub fn with_samples_per_period(mut self, p: usize) -> Result<Self, SimError> {
        if p == 0 {
            return Err(invalid("samples per period", 0.0, "must be at least 1"));
        }
        self.samples_per_period = p;
        self.sample_step = None;
        Ok(self)
    }

    /// Samples every `h` (positive and finite, in the system's time unit), whatever the ratio of
    /// the forcing period to `h`: sample `n` is at `t_0 + n · h`, `t_0 = (phase + transient
    /// periods) · T`. Replaces the whole grid `T / P` until
    /// [`with_samples_per_period`](Self::with_samples_per_period) is called again.
    ///
    /// ```
    /// use pendulum_sim::{simulate, Pendulum, SimulationConfig};
    /// // 2π / 0.3 = 20.94... samples per forcing period.
    /// let cfg = SimulationConfig::paper()
    ///     .with_sample_step(0.3)?
    ///     .with_transient_periods(1)
    ///     .with_samples(50)?;
    /// let traj = simulate(&Pendulum::paper(), &cfg)?;
    /// assert_eq!(traj.t[10], std::f64::consts::TAU + 10.0 * 0.3);
    /// assert_eq!(cfg.whole_samples_per_period(), None);
    /// # Ok::<(), pendulum_sim::SimError>(())
    /// ```
    pub fn with_sample_step(mut self, h: f64) -> Result<Self, SimError> {
        if !(h.is_finite() && h > 0.0) {
            return Err(invalid("sample step", h, "must be positive and finite"));
        }
        self.sample_step = Some(h);
        Ok(self)
    }

    /// Forcing periods integrated and dropped before the first sample.
    pub fn with_transient_periods(mut self, periods: usize) -> Self {
        self.transient_periods = periods;
        self
    }

    /// Initial angle and angular velocity at `t = 0` (finite).
    pub fn with_initial(mut self, theta0: f64, omega0: f64) -> Result<Self, SimError> {
        if !theta0.is_finite() {
            return Err(invalid("theta0", theta0, "must be finite"));
        }
        if !omega0.is_finite() {
            return Err(invalid("omega0", omega0, "must be finite"));
        }
        self.initial = [theta0, omega0];
        Ok(self)
    }

    /// The forcing period `T` in the system's time unit (`2π` for the paper's non-dimensional time).
    pub fn with_drive_period(mut self, period: f64) -> Result<Self, SimError> {
        self.forcing_period = checked_period(period)?;
        Ok(self)
    }

    /// Phase of the sampling grid as a fraction of the forcing period, in `[0, 1)`.
    pub fn with_phase(mut self, phase: f64) -> Result<Self, SimError> {
        if !(0.0..1.0).contains(&phase) {
            return Err(invalid("phase", phase, "must lie in [0, 1)"));
        }
        self.phase = phase;
        Ok(self)
    }

    /// Integration tolerances.
    pub fn with_tolerances(mut self, tolerances: Tolerances) -> Self {
        self.tolerances = tolerances;
        self
    }

    /// Number of samples.
    pub fn samples(&self) -> usize {
        self.samples
    }
    /// Samples per forcing period `P` of the whole grid (not used while a sample step is set).
    pub fn samples_per_period(&self) -> usize {
        self.samples_per_period
    }
    /// `Some(P)` when samples are taken on the whole grid `T / P`, `None` when a sample step is
    /// set.
    pub fn whole_samples_per_period(&self) -> Option<usize> {
        self.sample_step.is_none().then_some(self.samples_per_period)
    }
    /// Phase of the sampling grid as a fraction of the forcing period.
    pub fn phase(&self) -> f64 {
        self.phase
    }
    /// Transient periods dropped.
    pub fn transient_periods(&self) -> usize {
        self.transient_periods
    }
    /// Initial `(θ, θ')`.
    pub fn initial(&self) -> [f64; 2] {
        self.initial
    }
    /// Forcing period.
    pub fn drive_period(&self) -> f64 {
        self.forcing_period
    }
    /// Tolerances.
    pub fn tolerances(&self) -> Tolerances {
        self.tolerances
    }
    /// Sampling step: the step set by [`with_sample_step`](Self::with_sample_step), or `T / P`.
    pub fn sample_step(&self) -> f64 {
        match self.sample_step {
            Some(h) => h,
            None => self.forcing_period / self.samples_per_period as f64,
        }
    }
    /// Time of the kept sample `n` (`n = 0` is the first sample after the transient), computed
    /// by one multiplication from the start of the integration at `t = 0`.
    pub fn sample_time(&self, n: usize) -> f64 {
        match self.sample_step {
            Some(h) => self.first_sample_time() + n as f64 * h,
            None => self.grid_time(self.transient_periods * self.samples_per_period + n),
        }
    }
    /// Time of the first kept sample.
    pub(crate) fn first_sample_time(&self) -> f64 {
        match self.sample_step {
            Some(_) => (self.phase + self.transient_periods as f64) * self.forcing_period,
            None => self.grid_time(self.transient_periods * self.samples_per_period),
        }
    }
    /// Time of sample `n` of the whole grid counted from the start of the integration (the
    /// transient included).
    fn grid_time(&self, n: usize) -> f64 {
        self.phase * self.forcing_period + n as f64 * self.forcing_period / self.samples_per_period as f64
    }
}

/// A sampled trajectory: absolute times, the continuous (unwrapped) angle and its velocity.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Trajectory {
    /// Sample times.
    pub t: Vec<f64>,
    /// The angle (or displacement), continuous.
    pub theta: Vec<f64>,
    /// Its time derivative.
    pub omega: Vec<f64>,
}

impl Trajectory {
    /// The angle wrapped into `[−π, π)`, as an encoder reports it.
    pub fn wrapped(&self) -> Vec<f64> {
        self.theta.iter().map(|&x| circle_signal::wrap(x)).collect()
    }
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }
    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }
}

/// Simulates `system` and samples it as `config` says.
///
/// ```
/// use pendulum_sim::{simulate, Pendulum, SimulationConfig};
/// let cfg = SimulationConfig::paper().with_samples(100)?.with_transient_periods(2);
/// let traj = simulate(&Pendulum::paper(), &cfg)?;
/// assert_eq!(traj.len(), 100);
/// assert!((traj.t[0] - 2.0 * std::f64::consts::TAU).abs() < 1e-12);
/// # Ok::<(), pendulum_sim::SimError>(())
/// ```
pub fn simulate<S: SecondOrderSystem>(system: &S, config: &SimulationConfig) -> Result<Trajectory, SimError> {
    simulate_with_progress(system, config, |_, _| {})
}

/// [`simulate`], calling `progress(done, total)` about a hundred times along the way (samples
/// done out of the total; the transient counts as no samples).
pub fn simulate_with_progress<S: SecondOrderSystem>(
    system: &S,
    config: &SimulationConfig,
    progress: impl FnMut(usize, usize),
) -> Result<Trajectory, SimError> {
    let [t, theta, omega]: [Vec<f64>; 3] = crate::reserve_series(3, config.samples)?
        .try_into()
        .expect("three series");
    let mut traj = Trajectory { t, theta, omega };
    simulate_each(system, config, progress, |_, t, theta, omega| {
        traj.t.push(t);
        traj.theta.push(theta);
        traj.omega.push(omega);
    })?;
    Ok(traj)
}

/// [`simulate_with_progress`] without the trajectory: `sample(n, t_n, x_n, x'_n)` is called for
/// each sample in order, the same numbers [`simulate`] keeps, so a record of any length is made in
/// constant memory (written as it comes, say).
///
/// ```
/// use pendulum_sim::{simulate, simulate_each, Pendulum, SimulationConfig};
/// let cfg = SimulationConfig::paper().with_samples(50)?;
/// let mut last = (0, 0.0);
/// simulate_each(&Pendulum::paper(), &cfg, |_, _| {}, |n, _, x, _| last = (n, x))?;
/// assert_eq!(last, (49, simulate(&Pendulum::paper(), &cfg)?.theta[49]));
/// # Ok::<(), pendulum_sim::SimError>(())
/// ```
pub fn simulate_each<S: SecondOrderSystem>(
    system: &S,
    config: &SimulationConfig,
    progress: impl FnMut(usize, usize),
    mut sample: impl FnMut(usize, f64, f64, f64),
) -> Result<(), SimError> {
    simulate_while(system, config, progress, |n, t, x, v| {
        sample(n, t, x, v);
        ControlFlow::Continue(())
    })
}

/// [`simulate_each`] until `sample` breaks: the integration ends at that sample (a record's
/// writer whose disk is full stops the simulation there rather than at its end). `Ok` either
/// way; the caller knows why it broke.
///
/// ```
/// use std::ops::ControlFlow;
/// use pendulum_sim::{simulate_while, Pendulum, SimulationConfig};
/// let cfg = SimulationConfig::paper().with_samples(50)?;
/// let mut seen = 0;
/// simulate_while(&Pendulum::paper(), &cfg, |_, _| {}, |n, _, _, _| {
///     seen = n + 1;
///     if n == 9 { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
/// })?;
/// assert_eq!(seen, 10);
/// # Ok::<(), pendulum_sim::SimError>(())
/// ```
pub fn simulate_while<S: SecondOrderSystem>(
    system: &S,
    config: &SimulationConfig,
    mut progress: impl FnMut(usize, usize),
    mut sample: impl FnMut(usize, f64, f64, f64) -> ControlFlow<()>,
) -> Result<(), SimError> {
    let t_first = config.first_sample_time();
    let budget = config.step_budget();
    let mut ode = Flow::new(
        FirstOrder(OnMode::new(system)),
        0.0,
        config.initial,
        config.tolerances,
    )?
    .with_max_steps(budget);
    let report_every = (config.samples / 100).max(1);
    progress(0, config.samples);
    // No stop at the end of the transient: the step sequence then depends only on the end time,
    // so runs that differ only in their output grid follow the same numerical trajectory.
    let mut stopped = false;
    ode.sample_grid(t_first, config.sample_step(), config.samples, |n, _, y| {
        // Absolute grid time computed from the absolute index: no drift over long records.
        let flow = sample(n, config.sample_time(n), y[0], y[1]);
        stopped = flow.is_break();
        if !stopped && (n + 1) % report_every == 0 {
            progress(n + 1, config.samples);
        }
        flow
    })?;
    if !stopped {
        progress(config.samples, config.samples);
    }
    Ok(())
}

/// The stroboscopic (Poincaré) section: the state once per forcing period, at the phase of
/// `config` (the samples-per-period and sample-step settings are ignored). Returns `(x, x')` pairs with `x` as
/// integrated (continuous); wrap it for display on the circle.
pub fn poincare_section<S: SecondOrderSystem>(
    system: &S,
    config: &SimulationConfig,
) -> Result<Vec<[f64; 2]>, SimError> {
    let strobe = SimulationConfig {
        samples_per_period: 1,
        sample_step: None,
        ..config.clone()
    };
    let traj = simulate(system, &strobe)?;
    Ok(traj
        .theta
        .into_iter()
        .zip(traj.omega)
        .map(|(x, v)| [x, v])
        .collect())
}

/// Settings of a largest-Lyapunov-exponent estimate by tangent-linear integration.
///
/// Deserialising validates every field as the `with_*` setters do.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(try_from = "LyapunovConfigRaw", into = "LyapunovConfigRaw")]
pub struct LyapunovConfig {
    transient_periods: usize,
    periods: usize,
    initial: [f64; 2],
    forcing_period: f64,
    tolerances: Tolerances,
}

/// The serialised form of [`LyapunovConfig`].
#[derive(serde::Serialize, serde::Deserialize)]
struct LyapunovConfigRaw {
    transient_periods: usize,
    periods: usize,
    initial: [f64; 2],
    forcing_period: f64,
    tolerances: Tolerances,
}

impl TryFrom<LyapunovConfigRaw> for LyapunovConfig {
    type Error = SimError;
    fn try_from(raw: LyapunovConfigRaw) -> Result<Self, SimError> {
        Ok(Self::default()
            .with_transient_periods(raw.transient_periods)
            .with_periods(raw.periods)?
            .with_initial(raw.initial[0], raw.initial[1])?
            .with_drive_period(raw.forcing_period)?
            .with_tolerances(raw.tolerances))
    }
}

impl From<LyapunovConfig> for LyapunovConfigRaw {
    fn from(c: LyapunovConfig) -> Self {
        Self {
            transient_periods: c.transient_periods,
            periods: c.periods,
            initial: c.initial,
            forcing_period: c.forcing_period,
            tolerances: c.tolerances,
        }
    }
}

impl Default for LyapunovConfig {
    /// 200 transient periods, then 2000 measured periods of `2π`, from `(0.1, 0)`, `rtol = 1e-10`.
    fn default() -> Self {
        Self {
            transient_periods: 200,
            periods: 2000,
            initial: [0.1, 0.0],
            forcing_period: TAU,
            tolerances: Tolerances::default(),
        }
    }
}

impl LyapunovConfig {
    /// Forcing periods measured (`>= 1`); the tangent vector is renormalised once per period.
    pub fn with_periods(mut self, periods: usize) -> Result<Self, SimError> {
        if periods == 0 {
            return Err(invalid("periods", 0.0, "must be at least 1"));
        }
        self.periods = periods;
        Ok(self)
    }
    /// Forcing periods integrated before measuring.
    pub fn with_transient_periods(mut self, periods: usize) -> Self {
        self.transient_periods = periods;
        self
    }
    /// Initial state (finite).
    pub fn with_initial(mut self, x0: f64, v0: f64) -> Result<Self, SimError> {
        if !(x0.is_finite() && v0.is_finite()) {
            return Err(invalid(
                "initial state",
                if x0.is_finite() { v0 } else { x0 },
                "must be finite",
            ));
        }
        self.initial = [x0, v0];
        Ok(self)
    }
    /// Forcing period `T` (positive).
    pub fn with_drive_period(mut self, period: f64) -> Result<Self, SimError> {
        self.forcing_period = checked_period(period)?;
        Ok(self)
    }
    /// Integration tolerances.
    pub fn with_tolerances(mut self, tolerances: Tolerances) -> Self {
        self.tolerances = tolerances;
        self
    }
    /// The initial state.
    pub(crate) fn initial(&self) -> [f64; 2] {
        self.initial
    }
    /// The forcing period.
    pub(crate) fn drive_period(&self) -> f64 {
        self.forcing_period
    }
}

/// A largest-Lyapunov-exponent estimate.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LyapunovEstimate {
    /// The exponent per unit time.
    pub per_unit_time: f64,
    /// The exponent per forcing period.
    pub per_period: f64,
    /// Periods measured.
    pub periods: usize,
    /// Time measured over.
    pub time: f64,
    /// Standard error per unit time, from the spread of the exponent over 10 equal blocks of
    /// periods (block means are nearly independent for a chaotic flow).
    pub standard_error: f64,
}

/// The largest Lyapunov exponent by integrating the tangent-linear equation beside the
/// trajectory and renormalising the tangent vector once per forcing period (Benettin's method).
///
/// `progress(done, total)` is called once per measured period.
pub fn largest_lyapunov<S: SecondOrderSystem>(
    system: &S,
    config: &LyapunovConfig,
    mut progress: impl FnMut(usize, usize),
) -> Result<LyapunovEstimate, SimError> {
    let period = config.forcing_period;
    let mut ode = Flow::new(
        FirstOrder(OnMode::new(system)),
        0.0,
        config.initial,
        config.tolerances,
    )?;
    let t_start = config.transient_periods as f64 * period;
    ode.advance_to(t_start)?;
    let [x, v] = *ode.y();
    let s = std::f64::consts::FRAC_1_SQRT_2;
    let mut tangent = Flow::new(
        Tangent(OnMode::new(system)),
        t_start,
        [x, v, s, s],
        config.tolerances,
    )?;
    let mut logs = Vec::with_capacity(config.periods);
    for p in 1..=config.periods {
        tangent.advance_to(t_start + p as f64 * period)?;
        let [x, v, dx, dv] = *tangent.y();
        let norm = dx.hypot(dv);
        if !(norm.is_finite() && norm > 0.0) {
            return Err(SimError::NonFinite { t: tangent.t() });
        }
        logs.push(norm.ln());
        tangent.set_state([x, v, dx / norm, dv / norm])?;
        progress(p, config.periods);
    }
    let total: f64 = logs.iter().sum();
    let time = config.periods as f64 * period;
    let blocks = 10.min(logs.len());
    let block_len = logs.len() / blocks;
    let means: Vec<f64> = logs
        .chunks_exact(block_len)
        .take(blocks)
        .map(|c| c.iter().sum::<f64>() / (c.len() as f64 * period))
        .collect();
    let mean = means.iter().sum::<f64>() / means.len() as f64;
    let standard_error = if means.len() > 1 {
        (means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / ((means.len() - 1) * means.len()) as f64)
            .sqrt()
    } else {
        f64::NAN
    };
    Ok(LyapunovEstimate {
        per_unit_time: total / time,
        per_period: total / config.periods as f64,
        periods: config.periods,
        time,
        standard_error,
    })
}
