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

use crate::dop853::{Dop853, OdeSystem, Stepper, Tolerances, sample_on_grid};
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
pub(crate) const SCAN_POINTS: usize = 8;
/// Scan points of a stick per step: a stuck step is at most this many scan spacings long.
pub(crate) const STICK_SCANS_PER_STEP: f64 = 64.0;

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
        let after = first_event(t0, t1, SCAN_POINTS, |t| s * self.ode.interpolate(t)[1] <= 0.0)?;
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
        let after = first_event(t0, t1, scans, free)?;
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
    /// for each point in order, as [`Dop853::sample_grid`] does; a sink that breaks ends it there.
    pub(crate) fn sample_grid(
        &mut self,
        t_first: f64,
        dt: f64,
        count: usize,
        sink: impl FnMut(usize, f64, &[f64; N]) -> std::ops::ControlFlow<()>,
    ) -> Result<(), SimError> {
        sample_on_grid(self, t_first, dt, count, sink)
    }
}

impl<O: Switched<N>, const N: usize> Stepper<N> for Flow<O, N> {
    fn now(&self) -> f64 {
        self.t()
    }
    fn state(&self) -> [f64; N] {
        *self.y()
    }
    fn advance(&mut self, t_limit: f64) -> Result<f64, SimError> {
        self.step(t_limit)
    }
    fn state_at(&mut self, t: f64) -> [f64; N] {
        self.interpolate(t)
    }
}

/// The first time in a step `[t0, t1]` at which `hit` holds: looked for at `scans` equally spaced
/// points after `t0` (the last one `t1` itself), then located by bisection between the last point
/// where it does not hold and the first where it does, to the last bit of the time. `None` when it
/// holds at none of the points.
pub(crate) fn first_event(t0: f64, t1: f64, scans: usize, mut hit: impl FnMut(f64) -> bool) -> Option<f64> {
    let mut before = t0;
    let mut after = None;
    for j in 1..=scans {
        let tj = if j == scans {
            t1
        } else {
            t0 + (t1 - t0) * j as f64 / scans as f64
        };
        if hit(tj) {
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
        if hit(mid) {
            after = mid;
        } else {
            before = mid;
        }
    }
    Some(after)
}

/// The spacing of `f64` at `|t|` (at least at 1).
pub(crate) fn ulp(t: f64) -> f64 {
    let a = t.abs().max(1.0);
    f64::from_bits(a.to_bits() + 1) - a
}
