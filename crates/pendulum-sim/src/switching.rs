//! Integration of a system that is not smooth at `x' = 0` (dry friction, `|x'|`): each side of
//! `x' = 0` on its own smooth branch, every `x' = 0` located, and at each the choice between a
//! reversal and a stick (Filippov's rule), with the saltation of the tangent vectors.
//!
//! A smooth system ([`SecondOrderSystem::switches_at_rest`] false) runs through [`Flow`] as
//! through [`Dop853`] itself: the same steps, the same numbers.
//!
//! For a switching system the motion is in one of three modes:
//!
//! - on a branch `s = ±1` ([`Mode::Slip`]): `F` with `sign(x') = s` and `|x'| = s x'`, smooth, so
//!   DOP853 keeps its order. After each accepted step the dense output's velocity is looked at at
//!   eight points of the step; at the first where `s x' <= 0` the zero is bracketed and located by
//!   bisection on the dense output (to the last bit of the time), the step is cut there and the
//!   integration restarts at the event with `x' = 0` exactly;
//! - at rest ([`Mode::Stuck`]): `x' = 0`, `x` constant, for as long as the friction can hold the
//!   body: from `x' = 0` a branch `s` can start only if `s F_s(t, x, 0) > 0` (it accelerates away
//!   from rest on its own side); if neither branch can, the body sticks. While stuck, that test is
//!   made at points no further apart than the step the controller proposed when the body stopped
//!   (the time scale the motion was resolved on), and the release located by bisection on `F`
//!   itself.
//!
//! At a reversal from `s` to `−s` the tangent vectors jump by the saltation matrix
//! `diag(1, F_{−s}/F_s)` (both at `x' = 0`); at the onset of a stick their velocity part is
//! zeroed (`diag(1, 0)`); at a release they are continuous.

use crate::dop853::{Dop853, OdeSystem, Tolerances};
use crate::error::SimError;
use crate::system::{Branch, SecondOrderSystem};

/// Where a system is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Mode {
    /// A smooth system: no switching.
    Smooth,
    /// Moving on a branch.
    Slip(Branch),
    /// At rest, held by friction.
    Stuck,
}

/// A system integrated on one mode.
#[derive(Debug, Clone, Copy)]
pub(crate) struct OnMode<S> {
    pub(crate) system: S,
    pub(crate) mode: Mode,
}

impl<S> OnMode<S> {
    /// `system`, its mode set when a [`Flow`] starts.
    pub(crate) fn new(system: S) -> Self {
        Self {
            system,
            mode: Mode::Smooth,
        }
    }
}

impl<S: SecondOrderSystem> SecondOrderSystem for OnMode<S> {
    #[inline]
    fn acceleration(&self, t: f64, x: f64, v: f64) -> f64 {
        match self.mode {
            Mode::Smooth => self.system.acceleration(t, x, v),
            Mode::Slip(branch) => self.system.acceleration_on(branch, t, x, v),
            Mode::Stuck => 0.0,
        }
    }

    #[inline]
    fn jacobian(&self, t: f64, x: f64, v: f64) -> [f64; 2] {
        match self.mode {
            Mode::Smooth => self.system.jacobian(t, x, v),
            Mode::Slip(branch) => self.system.jacobian_on(branch, t, x, v),
            Mode::Stuck => [0.0, 0.0],
        }
    }
}

/// A first-order form of a second-order system on a mode. Its state starts with `(x, v)`; any
/// further components come in pairs `(δx, δv)` of tangent vectors.
pub(crate) trait Switched<const N: usize>: OdeSystem<N> {
    /// The system.
    type System: SecondOrderSystem;
    /// The system on its mode.
    fn on_mode(&self) -> &OnMode<Self::System>;
    /// The same, to change the mode.
    fn on_mode_mut(&mut self) -> &mut OnMode<Self::System>;
}

/// The mode of a state `(t, x, v)` with no history: the branch of `v`, or at `v = 0` a branch
/// that accelerates away from rest on its own side, or stuck.
fn initial_mode<S: SecondOrderSystem>(system: &S, t: f64, x: f64, v: f64) -> Mode {
    match Branch::of(v) {
        Some(branch) => Mode::Slip(branch),
        None => leaving_rest(system, t, x, Branch::Forward),
    }
}

/// The mode at `x' = 0`, `preferred` tried first: a branch `s` that can start from rest
/// (`s F_s(t, x, 0) > 0`), or stuck.
fn leaving_rest<S: SecondOrderSystem>(system: &S, t: f64, x: f64, preferred: Branch) -> Mode {
    for branch in [preferred, preferred.reversed()] {
        if branch.sign() * system.acceleration_on(branch, t, x, 0.0) > 0.0 {
            return Mode::Slip(branch);
        }
    }
    Mode::Stuck
}

/// Multiplies the velocity part of every tangent vector (components 3, 5, ...) by `factor`.
fn scale_velocity_perturbations<const N: usize>(y: &mut [f64; N], factor: f64) {
    for v in y.iter_mut().skip(3).step_by(2) {
        *v *= factor;
    }
}

/// Points at which a slip's velocity is looked at in each step.
const SCAN_POINTS: usize = 8;
/// Scan points of a stick per step: a stuck step is at most this many scan spacings long.
const STICK_SCANS_PER_STEP: f64 = 64.0;

/// The adaptive DOP853 integration of a second-order system across `x' = 0` (see the
/// [module documentation](self)): one accepted step at a time, each ending at the step's end or
/// at an event, with dense output inside it.
#[derive(Debug, Clone)]
pub(crate) struct Flow<O, const N: usize> {
    ode: Dop853<O, N>,
    /// An event located in the last step: its time, the state there and the mode after it.
    pending: Option<(f64, [f64; N], Mode)>,
    /// While stuck: the largest spacing of the test for the release.
    scan_step: f64,
}

impl<O: Switched<N>, const N: usize> Flow<O, N> {
    /// Starts at `(t0, y0)` in the mode of that state.
    pub(crate) fn new(mut sys: O, t0: f64, y0: [f64; N], tol: Tolerances) -> Result<Self, SimError> {
        let on = sys.on_mode_mut();
        let mode = if on.system.switches_at_rest() && y0[1].is_finite() && y0[0].is_finite() {
            initial_mode(&on.system, t0, y0[0], y0[1])
        } else {
            Mode::Smooth
        };
        // A body at rest starts with the step a motion from there would take: the time scale of
        // the test for its release.
        on.mode = if mode == Mode::Stuck {
            Mode::Slip(Branch::Forward)
        } else {
            mode
        };
        let mut ode = Dop853::new(sys, t0, y0, tol)?;
        let scan_step = ode.proposed_step();
        if mode == Mode::Stuck {
            ode.system_mut().on_mode_mut().mode = Mode::Stuck;
            ode.restart(t0, y0)?;
        }
        Ok(Self {
            ode,
            pending: None,
            scan_step,
        })
    }

    /// Limits the number of accepted plus rejected steps (default: unlimited).
    pub(crate) fn with_max_steps(mut self, max_steps: usize) -> Self {
        self.ode = self.ode.with_max_steps(max_steps);
        self
    }

    /// The current time: the end of the last step, or its event.
    pub(crate) fn t(&self) -> f64 {
        self.pending.map_or(self.ode.t(), |(t, ..)| t)
    }

    /// The current state.
    pub(crate) fn y(&self) -> &[f64; N] {
        match &self.pending {
            Some((_, y, _)) => y,
            None => self.ode.y(),
        }
    }

    /// Restarts at the event of the last step, if any, in the mode after it.
    fn apply_pending(&mut self) -> Result<(), SimError> {
        if let Some((t, y, mode)) = self.pending.take() {
            self.ode.system_mut().on_mode_mut().mode = mode;
            self.ode.restart(t, y)?;
        }
        Ok(())
    }

    /// Takes one accepted step, not going past `t_limit` (> current time), and stops at the
    /// first event inside it. Returns the new time; [`Flow::interpolate`] is then valid between
    /// the step's start and it.
    pub(crate) fn step(&mut self, t_limit: f64) -> Result<f64, SimError> {
        self.apply_pending()?;
        let t0 = self.ode.t();
        let mode = self.ode.system().on_mode().mode;
        let limit = match mode {
            Mode::Stuck => t_limit.min(t0 + STICK_SCANS_PER_STEP * self.scan_step),
            _ => t_limit,
        };
        let limit = if limit > t0 { limit } else { t_limit };
        let t1 = self.ode.step(limit)?;
        let event = match mode {
            Mode::Smooth => None,
            Mode::Slip(branch) => self.reversal(branch, t0, t1),
            Mode::Stuck => self.release(t0, t1),
        };
        match event {
            Some((t, y, mode)) => {
                self.pending = Some((t, y, mode));
                Ok(t)
            }
            None => Ok(t1),
        }
    }

    /// The first `x' = 0` of a slip on `branch` in the step `[t0, t1]`, and what follows it.
    fn reversal(&mut self, branch: Branch, t0: f64, t1: f64) -> Option<(f64, [f64; N], Mode)> {
        let s = branch.sign();
        let mut before = t0;
        let mut after = None;
        for j in 1..=SCAN_POINTS {
            let tj = if j == SCAN_POINTS {
                t1
            } else {
                t0 + (t1 - t0) * j as f64 / SCAN_POINTS as f64
            };
            if s * self.ode.interpolate(tj)[1] <= 0.0 {
                after = Some(tj);
                break;
            }
            before = tj;
        }
        let mut after = after?;
        loop {
            let mid = before + 0.5 * (after - before);
            if mid <= before || mid >= after {
                break;
            }
            if s * self.ode.interpolate(mid)[1] > 0.0 {
                before = mid;
            } else {
                after = mid;
            }
        }
        let mut y = self.ode.interpolate(after);
        y[1] = 0.0;
        let system = &self.ode.system().on_mode().system;
        // A slip shorter than the resolution of the time cannot leave rest: a stick.
        let mode = if after - t0 <= 16.0 * ulp(t0) {
            Mode::Stuck
        } else {
            leaving_rest(system, after, y[0], branch.reversed())
        };
        match mode {
            Mode::Slip(next) => {
                let factor = system.acceleration_on(next, after, y[0], 0.0)
                    / system.acceleration_on(branch, after, y[0], 0.0);
                if factor.is_finite() {
                    scale_velocity_perturbations(&mut y, factor);
                }
            }
            _ => {
                scale_velocity_perturbations(&mut y, 0.0);
                self.scan_step = self.ode.proposed_step();
            }
        }
        Some((after, y, mode))
    }

    /// The release of a stick in the step `[t0, t1]`, and its branch.
    fn release(&mut self, t0: f64, t1: f64) -> Option<(f64, [f64; N], Mode)> {
        let y = *self.ode.y();
        let system = &self.ode.system().on_mode().system;
        let free = |t: f64| leaving_rest(system, t, y[0], Branch::Forward) != Mode::Stuck;
        let scans = ((t1 - t0) / self.scan_step)
            .ceil()
            .clamp(1.0, STICK_SCANS_PER_STEP) as usize;
        let mut before = t0;
        let mut after = None;
        for j in 1..=scans {
            let tj = if j == scans {
                t1
            } else {
                t0 + (t1 - t0) * j as f64 / scans as f64
            };
            if free(tj) {
                after = Some(tj);
                break;
            }
            before = tj;
        }
        let mut after = after?;
        loop {
            let mid = before + 0.5 * (after - before);
            if mid <= before || mid >= after {
                break;
            }
            if free(mid) {
                after = mid;
            } else {
                before = mid;
            }
        }
        let mode = leaving_rest(system, after, y[0], Branch::Forward);
        Some((after, y, mode))
    }

    /// The dense-output value at `t` between the last step's start and [`Flow::t`] (the state of
    /// an event exactly at its time).
    pub(crate) fn interpolate(&mut self, t: f64) -> [f64; N] {
        match &self.pending {
            Some((te, y, _)) if *te == t => *y,
            _ => self.ode.interpolate(t),
        }
    }

    /// Integrates up to exactly `t_end` (no-op if already there).
    pub(crate) fn advance_to(&mut self, t_end: f64) -> Result<(), SimError> {
        while self.t() < t_end {
            self.step(t_end)?;
        }
        Ok(())
    }

    /// Replaces the current state (e.g. after renormalising a tangent vector) and restarts from
    /// it, in the current mode; the step size is kept.
    pub(crate) fn set_state(&mut self, y: [f64; N]) -> Result<(), SimError> {
        self.apply_pending()?;
        self.ode.set_state(y)
    }

    /// Integrates over a grid `t_first + n · dt`, `n = 0..count`, calling `sink(n, t_n, y(t_n))`
    /// for each point in order, as [`Dop853::sample_grid`] does.
    pub(crate) fn sample_grid(
        &mut self,
        t_first: f64,
        dt: f64,
        count: usize,
        mut sink: impl FnMut(usize, f64, &[f64; N]),
    ) -> Result<(), SimError> {
        if count == 0 {
            return Ok(());
        }
        if !(dt > 0.0 && dt.is_finite()) {
            return Err(SimError::InvalidParameter {
                name: "dt",
                value: dt,
                why: "must be positive",
            });
        }
        if t_first < self.t() {
            return Err(SimError::InvalidParameter {
                name: "t_first",
                value: t_first,
                why: "must not be before the current time",
            });
        }
        let t_end = t_first + (count - 1) as f64 * dt;
        let mut n = 0;
        while n < count && t_first + n as f64 * dt == self.t() {
            let y = *self.y();
            sink(n, self.t(), &y);
            n += 1;
        }
        while n < count {
            let t_new = self.step(t_end)?;
            loop {
                let tn = t_first + n as f64 * dt;
                if n >= count || tn > t_new {
                    break;
                }
                let y = self.interpolate(tn);
                if y.iter().any(|v| !v.is_finite()) {
                    return Err(SimError::NonFinite { t: tn });
                }
                sink(n, tn, &y);
                n += 1;
            }
        }
        Ok(())
    }
}

/// The spacing of `f64` at `|t|` (at least at 1).
fn ulp(t: f64) -> f64 {
    let a = t.abs().max(1.0);
    f64::from_bits(a.to_bits() + 1) - a
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use proptest::prelude::*;

    use crate::dop853::Tolerances;

    use crate::frame::{InFrame, RecordFrame};

    use crate::machine::{DriveHarmonic, DriveHarmonics, Losses};

    use crate::oscillators::{Duffing, Pendulum};

    use crate::simulate::{SimulationConfig, simulate};

    use crate::validate::flow_with_jacobian;

    use super::*;

    fn friction(mu: f64) -> Losses {
        Losses::none().with_friction(mu).unwrap()
    }

    /// `x'' + ω² x + μ sign(x') = 0` from rest at `x0`: each half-cycle is a cosine of period
    /// `2π/ω` about `−μ s/ω²` (`s` the sign of the velocity), so the turning points fall at
    /// `t_n = nπ/ω` and lose `2μ/ω²` each, until the spring cannot overcome the friction
    /// (`ω² |x| <= μ`) and the body stays where it is.
    fn coulomb_closed_form(omega: f64, mu: f64, x0: f64, t: f64) -> [f64; 2] {
        let w2 = omega * omega;
        let mut start = x0;
        let mut t_n = 0.0;
        loop {
            if w2 * start.abs() <= mu {
                return [start, 0.0];
            }
            let s = -start.signum();
            let centre = -mu * s / w2;
            let half = PI / omega;
            if t <= t_n + half {
                let phase = omega * (t - t_n);
                return [
                    centre + (start - centre) * phase.cos(),
                    -(start - centre) * omega * phase.sin(),
                ];
            }
            start = 2.0 * centre - start;
            t_n += half;
        }
    }

    #[test]
    fn coulomb_oscillator_has_its_closed_form_decay() {
        let (omega, mu, x0) = (1.3, 0.05, 1.0);
        let system = Duffing::new(0.0, omega * omega, 0.0, 0.0)
            .unwrap()
            .with_losses(friction(mu));
        // Twenty half-cycles and some rest after: 17 swings, then stuck at 0.0118.
        let h = 0.01;
        let config = SimulationConfig::paper()
            .with_sample_step(h)
            .unwrap()
            .with_transient_periods(0)
            .with_initial(x0, 0.0)
            .unwrap()
            .with_samples(6_000)
            .unwrap()
            .with_tolerances(Tolerances::relative(1e-10).unwrap());
        let traj = simulate(&system, &config).unwrap();
        let mut worst: f64 = 0.0;
        for n in 0..traj.len() {
            let [x, v] = coulomb_closed_form(omega, mu, x0, traj.t[n]);
            worst = worst
                .max((traj.theta[n] - x).abs())
                .max((traj.omega[n] - v).abs());
        }
        // About 5 rtol (the example `friction` gives it at rtol 1e-6 to 1e-12).
        assert!(worst < 2e-9, "largest difference from the closed form {worst:e}");
        // Amplitude lost per full cycle: exactly 4μ/ω² (turning points at t = 2nπ/ω).
        let period = 2.0 * PI / omega;
        let at = |t: f64| {
            simulate(
                &system,
                &config
                    .clone()
                    .with_sample_step(t)
                    .unwrap()
                    .with_samples(2)
                    .unwrap(),
            )
            .unwrap()
            .theta[1]
        };
        for cycles in [1.0, 3.0, 7.0] {
            let lost = x0 - at(cycles * period);
            let want = cycles * 4.0 * mu / (omega * omega);
            assert!(
                (lost - want).abs() < 2e-9,
                "{cycles} cycles: lost {lost}, want {want}"
            );
        }
        // At rest for good: the velocity is exactly zero, the position constant.
        let rest = &traj.theta[5_000..];
        assert!(traj.omega[5_000..].iter().all(|&v| v == 0.0));
        assert!(rest.iter().all(|&x| x == rest[0]));
        let final_x = x0 - 17.0 * 2.0 * mu / (omega * omega);
        assert!((rest[0].abs() - final_x.abs()).abs() < 2e-9, "{}", rest[0]);
    }

    /// A driven oscillator whose friction holds it for part of each cycle, against the same
    /// oscillator with the friction regularised to `μ tanh(v/ε)` and integrated as a smooth
    /// (stiff) system: the two agree to `O(ε)`.
    #[test]
    fn stick_slip_matches_a_regularised_friction() {
        struct Regularised {
            system: Duffing,
            mu: f64,
            eps: f64,
        }
        impl SecondOrderSystem for Regularised {
            fn acceleration(&self, t: f64, x: f64, v: f64) -> f64 {
                self.system.acceleration(t, x, v) - self.mu * (v / self.eps).tanh()
            }
            fn jacobian(&self, t: f64, x: f64, v: f64) -> [f64; 2] {
                let [jx, jv] = self.system.jacobian(t, x, v);
                [jx, jv - self.mu / self.eps / (v / self.eps).cosh().powi(2)]
            }
        }
        let mu = 0.45;
        let smooth = Duffing::new(0.1, 1.0, 0.0, 0.5).unwrap();
        let rig = smooth.with_losses(friction(mu));
        let config = SimulationConfig::paper()
            .with_sample_step(0.05)
            .unwrap()
            .with_transient_periods(0)
            .with_initial(0.2, 0.0)
            .unwrap()
            .with_samples(800)
            .unwrap()
            .with_tolerances(Tolerances::relative(1e-11).unwrap());
        let traj = simulate(&rig, &config).unwrap();
        let stuck = traj.omega.iter().filter(|&&v| v == 0.0).count();
        assert!(stuck > 100, "{stuck} samples at rest: no test of sticking");
        // While stuck, friction holds the body: |F without friction| <= μ.
        for n in 0..traj.len() {
            if traj.omega[n] == 0.0 {
                let free = smooth.acceleration(traj.t[n], traj.theta[n], 0.0);
                assert!(free.abs() <= mu + 1e-9, "sample {n}: {free}");
            }
        }
        // The regularised solutions converge to the located one like 5 ε (example `friction`, down
        // to ε = 1e-7): checked at two ε a decade apart, with first-order convergence between them.
        // (The regularised system is stiff, its explicit integration costing like 1/ε.)
        let worst = |eps: f64| {
            let reference = simulate(
                &Regularised {
                    system: smooth,
                    mu,
                    eps,
                },
                &config,
            )
            .unwrap();
            traj.theta
                .iter()
                .zip(&reference.theta)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max)
        };
        let (coarse, fine) = (worst(1e-5), worst(1e-6));
        assert!(
            coarse < 10.0 * 1e-5 && fine < 10.0 * 1e-6,
            "largest differences from the regularised friction {coarse:e} (ε = 1e-5), {fine:e} (ε = 1e-6)"
        );
        assert!(
            coarse / fine > 5.0,
            "not converging like ε: {coarse:e} at ε = 1e-5, {fine:e} at 1e-6"
        );
    }

    /// The chaotic pendulum with every rig option, at two tolerances a thousand times apart, over
    /// three forcing periods (the paper's pendulum differs by 3e-9 there).
    #[test]
    fn a_rig_pendulum_converges_with_the_tolerance() {
        let losses = friction(0.02)
            .with_drag(0.01)
            .unwrap()
            .with_cubic_damping(0.002)
            .unwrap();
        let harmonics = DriveHarmonics::new(&[DriveHarmonic::new(2, 0.1, 0.3).unwrap()]).unwrap();
        let rig = Pendulum::paper()
            .with_losses(losses)
            .with_drive_harmonics(harmonics);
        let run = |rtol: f64| {
            simulate(
                &rig,
                &SimulationConfig::paper()
                    .with_transient_periods(0)
                    .with_samples(75)
                    .unwrap()
                    .with_tolerances(Tolerances::relative(rtol).unwrap()),
            )
            .unwrap()
        };
        let (loose, tight) = (run(1e-10), run(1e-13));
        let worst = loose
            .theta
            .iter()
            .zip(&tight.theta)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-8, "rtol 1e-10 against 1e-13 over 3 periods: {worst:e}");
    }

    /// The same rig in seconds and in its own time: the events do not depend on the frame (a
    /// pendulum on a periodic attractor, so that rounding is not amplified).
    #[test]
    fn a_rig_in_seconds_is_the_rig_in_its_own_time() {
        let rig = Pendulum::new(0.8, 0.1, 0.8333)
            .unwrap()
            .with_losses(friction(0.05).with_drag(0.02).unwrap());
        let frame = RecordFrame::nondimensional().with_drive_frequency(1.5).unwrap();
        let rate = frame.rate();
        let tol = Tolerances::relative(1e-12).unwrap();
        let seconds = simulate(
            &InFrame::new(rig, frame),
            &SimulationConfig::paper()
                .with_drive_period(frame.drive_period())
                .unwrap()
                .with_sample_step(0.01)
                .unwrap()
                .with_transient_periods(0)
                .with_samples(1_500)
                .unwrap()
                .with_tolerances(tol),
        )
        .unwrap();
        let own = simulate(
            &rig,
            &SimulationConfig::paper()
                .with_sample_step(0.01 * rate)
                .unwrap()
                .with_transient_periods(0)
                .with_samples(1_500)
                .unwrap()
                .with_tolerances(tol),
        )
        .unwrap();
        for n in (0..1_500).step_by(7) {
            assert!((own.theta[n] - seconds.theta[n]).abs() < 1e-9, "sample {n}");
            assert!(
                (rate * own.omega[n] - seconds.omega[n]).abs() < 1e-8,
                "sample {n}"
            );
        }
    }

    /// The variational equation with the saltation at every reversal and stick is the
    /// derivative of the flow, as finite differences of the flow give it.
    #[test]
    fn the_flow_derivative_crosses_reversals_and_sticks() {
        let tol = Tolerances::new(1e-13, 1e-14).unwrap();
        for (system, duration) in [
            // Reversals only.
            (
                Duffing::new(0.1, 1.0, 0.0, 1.5)
                    .unwrap()
                    .with_losses(friction(0.2)),
                9.0,
            ),
            // A stick on the way.
            (
                Duffing::new(0.1, 1.0, 0.0, 0.5)
                    .unwrap()
                    .with_losses(friction(0.3)),
                9.0,
            ),
            // Drag and friction on the chaotic pendulum.
            (
                Duffing::two_well().with_losses(friction(0.02).with_drag(0.05).unwrap()),
                12.0,
            ),
        ] {
            let z = [0.3, 0.4];
            let (_, m) = flow_with_jacobian(&system, 0.0, z, duration, tol).unwrap();
            let e = 1e-6;
            for (j, dz) in [[e, 0.0], [0.0, e]].iter().enumerate() {
                let plus = flow_with_jacobian(&system, 0.0, [z[0] + dz[0], z[1] + dz[1]], duration, tol)
                    .unwrap()
                    .0;
                let minus = flow_with_jacobian(&system, 0.0, [z[0] - dz[0], z[1] - dz[1]], duration, tol)
                    .unwrap()
                    .0;
                for i in 0..2 {
                    let fd = (plus[i] - minus[i]) / (2.0 * e);
                    assert!(
                        (m[(i, j)] - fd).abs() < 1e-4 * (1.0 + fd.abs()),
                        "{system:?}: M[{i},{j}] = {} vs {fd}",
                        m[(i, j)]
                    );
                }
            }
        }
    }

    /// A body that starts at rest where friction holds it never moves.
    #[test]
    fn held_at_rest_it_stays() {
        let system = Duffing::new(0.0, 1.0, 0.0, 0.0)
            .unwrap()
            .with_losses(friction(0.5));
        let traj = simulate(
            &system,
            &SimulationConfig::paper()
                .with_transient_periods(0)
                .with_initial(0.3, 0.0)
                .unwrap()
                .with_samples(100)
                .unwrap(),
        )
        .unwrap();
        assert!(traj.theta.iter().all(|&x| x == 0.3) && traj.omega.iter().all(|&v| v == 0.0));
    }

    fn pendulum_rig() -> impl Strategy<Value = (Pendulum, f64, f64)> {
        (
            0.0..0.1f64,
            0.5..1.5f64,
            0.0..0.2f64,
            0.0..0.2f64,
            0.0..0.1f64,
            -3.0..3.0f64,
            -3.0..3.0f64,
        )
            .prop_map(|(c, r, mu, d, c3, x0, v0)| {
                let losses = Losses::none()
                    .with_friction(mu)
                    .unwrap()
                    .with_drag(d)
                    .unwrap()
                    .with_cubic_damping(c3)
                    .unwrap();
                (Pendulum::new(0.0, c, r).unwrap().with_losses(losses), x0, v0)
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// Without a drive, every loss takes energy out: `E` never grows along a trajectory.
        #[test]
        fn free_energy_never_grows((pendulum, x0, v0) in pendulum_rig()) {
            let traj = simulate(
                &pendulum,
                &SimulationConfig::paper()
                    .with_sample_step(0.05)
                    .unwrap()
                    .with_transient_periods(0)
                    .with_initial(x0, v0)
                    .unwrap()
                    .with_samples(600)
                    .unwrap(),
            )
            .unwrap();
            let energy: Vec<f64> = traj
                .theta
                .iter()
                .zip(&traj.omega)
                .map(|(&x, &v)| pendulum.energy(x, v))
                .collect();
            for w in energy.windows(2) {
                prop_assert!(w[1] <= w[0] + 1e-9 * (1.0 + w[0]), "{} -> {}", w[0], w[1]);
            }
        }

        /// Away from `x' = 0` the Jacobian is the derivative of `F` (central differences), and
        /// each branch is `F` on its own side.
        #[test]
        fn jacobian_and_branches_away_from_rest(
            (pendulum, x, v) in pendulum_rig(),
            f in -2.0..2.0f64,
            ratio in 0.0..0.5f64,
            phase in -3.0..3.0f64,
            t in -10.0..10.0f64,
        ) {
            prop_assume!(v.abs() > 1e-3);
            let harmonics = DriveHarmonics::new(&[DriveHarmonic::new(3, ratio, phase).unwrap()]).unwrap();
            let p = Pendulum::new(f, pendulum.c(), pendulum.r())
                .unwrap()
                .with_losses(*pendulum.losses())
                .with_drive_harmonics(harmonics);
            let duffing = Duffing::new(pendulum.c(), -1.0, 1.0, f)
                .unwrap()
                .with_losses(*pendulum.losses())
                .with_drive_harmonics(harmonics);
            let branch = Branch::of(v).unwrap();
            for s in [&p as &dyn SecondOrderSystem, &duffing] {
                let e = 1e-6 * (1.0 + v.abs());
                let dx = (s.acceleration(t, x + e, v) - s.acceleration(t, x - e, v)) / (2.0 * e);
                let dv = (s.acceleration(t, x, v + e) - s.acceleration(t, x, v - e)) / (2.0 * e);
                let [jx, jv] = s.jacobian(t, x, v);
                prop_assert!((jx - dx).abs() < 1e-6 * (1.0 + dx.abs()), "{jx} vs {dx}");
                prop_assert!((jv - dv).abs() < 1e-6 * (1.0 + dv.abs()), "{jv} vs {dv}");
                let a = s.acceleration(t, x, v);
                prop_assert!((s.acceleration_on(branch, t, x, v) - a).abs() <= 1e-12 * (1.0 + a.abs()));
                prop_assert_eq!(s.jacobian_on(branch, t, x, v), s.jacobian(t, x, v));
            }
        }
    }
}
