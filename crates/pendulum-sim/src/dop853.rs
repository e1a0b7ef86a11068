//! The Dormand–Prince 8(5,3) integrator with dense output, for small systems `y' = f(t, y)`.

// Stage and component loops index several arrays in step; iterators would hide the formulas.
#![allow(clippy::needless_range_loop)]

use std::ops::ControlFlow;

use crate::error::SimError;
use crate::tableau::{A, B, BHH, C, D, E5, STAGES, STAGES_EXT};

/// A first-order system `y' = f(t, y)` of fixed size `N`.
pub trait OdeSystem<const N: usize> {
    /// Writes `f(t, y)` into `dy`.
    fn rhs(&self, t: f64, y: &[f64; N], dy: &mut [f64; N]);
}

/// Error tolerances of the adaptive step: a component's local error is held below
/// `atol + rtol · |y|` (in the mixed 5th/3rd-order norm of DOP853). Deserialising validates as
/// [`Tolerances::new`] does.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(try_from = "TolerancesRaw", into = "TolerancesRaw")]
pub struct Tolerances {
    rtol: f64,
    atol: f64,
}

/// The serialised form of [`Tolerances`].
#[derive(serde::Serialize, serde::Deserialize)]
struct TolerancesRaw {
    rtol: f64,
    atol: f64,
}

impl TryFrom<TolerancesRaw> for Tolerances {
    type Error = SimError;
    fn try_from(raw: TolerancesRaw) -> Result<Self, SimError> {
        Self::new(raw.rtol, raw.atol)
    }
}

impl From<Tolerances> for TolerancesRaw {
    fn from(t: Tolerances) -> Self {
        Self {
            rtol: t.rtol,
            atol: t.atol,
        }
    }
}

impl Tolerances {
    /// The smallest relative tolerance accepted: 100 ulp of 1. Below it the error estimate is
    /// dominated by rounding and the step size collapses.
    pub const MIN_RTOL: f64 = 100.0 * f64::EPSILON;

    /// Relative tolerance `rtol` in `[MIN_RTOL, 1)`, absolute tolerance `atol >= 0` (finite).
    pub fn new(rtol: f64, atol: f64) -> Result<Self, SimError> {
        if !(rtol.is_finite() && (Self::MIN_RTOL..1.0).contains(&rtol)) {
            return Err(SimError::InvalidParameter {
                name: "rtol",
                value: rtol,
                why: "must lie in [2.2e-14, 1)",
            });
        }
        if !(atol.is_finite() && atol >= 0.0) {
            return Err(SimError::InvalidParameter {
                name: "atol",
                value: atol,
                why: "must be finite and >= 0",
            });
        }
        Ok(Self { rtol, atol })
    }

    /// `rtol` with `atol = rtol / 10`: the default pairing of this crate.
    pub fn relative(rtol: f64) -> Result<Self, SimError> {
        Self::new(rtol, rtol * 0.1)
    }

    /// The relative tolerance.
    pub fn rtol(&self) -> f64 {
        self.rtol
    }
    /// The absolute tolerance.
    pub fn atol(&self) -> f64 {
        self.atol
    }
}

impl Tolerances {
    /// The relative tolerance every simulation and free run uses unless told otherwise, the one
    /// place it is written: `1e-10` (the absolute one a tenth of it).
    pub const DEFAULT_RTOL: f64 = 1e-10;
}

impl Default for Tolerances {
    /// `rtol = `[`Tolerances::DEFAULT_RTOL`]` = 1e-10`, `atol = 1e-11`.
    fn default() -> Self {
        Self {
            rtol: Self::DEFAULT_RTOL,
            atol: 1e-11,
        }
    }
}

const SAFETY: f64 = 0.9;
const MIN_FACTOR: f64 = 0.2;
const MAX_FACTOR: f64 = 10.0;
/// The error estimator is of order 7: step factors scale with err^(-1/8).
const ERROR_EXPONENT: f64 = -1.0 / 8.0;

/// Counters of the work done.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Stats {
    /// Accepted steps.
    pub accepted: usize,
    /// Rejected steps.
    pub rejected: usize,
    /// Evaluations of the right-hand side.
    pub evaluations: usize,
}

/// An adaptive DOP853 integration that moves forward in time, one accepted step at a time, and
/// can evaluate its 7th-order interpolant anywhere inside the last step.
#[derive(Debug, Clone)]
pub struct Dop853<S, const N: usize> {
    sys: S,
    tol: Tolerances,
    max_steps: usize,
    t: f64,
    y: [f64; N],
    f: [f64; N],
    h: f64,
    t_old: f64,
    y_old: [f64; N],
    h_last: f64,
    k: [[f64; N]; STAGES_EXT],
    dense: [[f64; N]; 7],
    dense_ready: bool,
    stats: Stats,
}

impl<S: OdeSystem<N>, const N: usize> Dop853<S, N> {
    /// Starts at `(t0, y0)`; the first step size is chosen automatically (Hairer's rule).
    pub fn new(sys: S, t0: f64, y0: [f64; N], tol: Tolerances) -> Result<Self, SimError> {
        if !t0.is_finite() {
            return Err(SimError::InvalidParameter {
                name: "t0",
                value: t0,
                why: "must be finite",
            });
        }
        if let Some(&v) = y0.iter().find(|v| !v.is_finite()) {
            return Err(SimError::InvalidParameter {
                name: "initial state",
                value: v,
                why: "must be finite",
            });
        }
        let mut f = [0.0; N];
        sys.rhs(t0, &y0, &mut f);
        let mut me = Self {
            sys,
            tol,
            max_steps: usize::MAX,
            t: t0,
            y: y0,
            f,
            h: 0.0,
            t_old: t0,
            y_old: y0,
            h_last: 0.0,
            k: [[0.0; N]; STAGES_EXT],
            dense: [[0.0; N]; 7],
            dense_ready: false,
            stats: Stats {
                evaluations: 1,
                ..Stats::default()
            },
        };
        if f.iter().any(|v| !v.is_finite()) {
            return Err(SimError::NonFinite { t: t0 });
        }
        me.h = me.initial_step();
        Ok(me)
    }

    /// Limits the number of accepted plus rejected steps (default: unlimited).
    pub fn with_max_steps(mut self, max_steps: usize) -> Self {
        self.max_steps = max_steps;
        self
    }

    /// Current time.
    pub fn t(&self) -> f64 {
        self.t
    }
    /// Current state.
    pub fn y(&self) -> &[f64; N] {
        &self.y
    }
    /// Work counters.
    pub fn stats(&self) -> Stats {
        self.stats
    }
    /// The system being integrated.
    pub fn system(&self) -> &S {
        &self.sys
    }

    /// The system being integrated, to change its mode between steps.
    pub(crate) fn system_mut(&mut self) -> &mut S {
        &mut self.sys
    }

    /// The step size the controller proposes for the next step.
    pub(crate) fn proposed_step(&self) -> f64 {
        self.h
    }

    /// Restarts at `(t, y)` inside the last step (an event located there): the state, the time and
    /// the right-hand side are replaced, the proposed step size is kept, and no interpolation is
    /// possible until the next step.
    pub(crate) fn restart(&mut self, t: f64, y: [f64; N]) -> Result<(), SimError> {
        if y.iter().any(|v| !v.is_finite()) {
            return Err(SimError::NonFinite { t });
        }
        self.t = t;
        self.t_old = t;
        self.y = y;
        self.y_old = y;
        self.sys.rhs(t, &self.y, &mut self.f);
        self.stats.evaluations += 1;
        self.dense_ready = false;
        self.h_last = 0.0;
        Ok(())
    }

    /// Replaces the current state (e.g. after renormalising a tangent vector) and restarts from it;
    /// the step size is kept.
    pub fn set_state(&mut self, y: [f64; N]) -> Result<(), SimError> {
        if y.iter().any(|v| !v.is_finite()) {
            return Err(SimError::NonFinite { t: self.t });
        }
        self.y = y;
        self.sys.rhs(self.t, &self.y, &mut self.f);
        self.stats.evaluations += 1;
        self.dense_ready = false;
        self.h_last = 0.0;
        Ok(())
    }

    fn rms_scaled(&self, v: &[f64; N], scale: &[f64; N]) -> f64 {
        (v.iter().zip(scale).map(|(a, s)| (a / s).powi(2)).sum::<f64>() / N as f64).sqrt()
    }

    fn initial_step(&mut self) -> f64 {
        let scale: [f64; N] = std::array::from_fn(|i| self.tol.atol + self.y[i].abs() * self.tol.rtol);
        let d0 = self.rms_scaled(&self.y, &scale);
        let d1 = self.rms_scaled(&self.f, &scale);
        let h0 = if d0 < 1e-5 || d1 < 1e-5 {
            1e-6
        } else {
            0.01 * d0 / d1
        };
        let y1: [f64; N] = std::array::from_fn(|i| self.y[i] + h0 * self.f[i]);
        let mut f1 = [0.0; N];
        self.sys.rhs(self.t + h0, &y1, &mut f1);
        self.stats.evaluations += 1;
        let df: [f64; N] = std::array::from_fn(|i| f1[i] - self.f[i]);
        let d2 = self.rms_scaled(&df, &scale) / h0;
        let h1 = if d1 <= 1e-15 && d2 <= 1e-15 {
            (h0 * 1e-3).max(1e-6)
        } else {
            (0.01 / d1.max(d2)).powf(1.0 / 8.0)
        };
        let h = (100.0 * h0).min(h1);
        if h.is_finite() && h > 0.0 { h } else { 1e-6 }
    }

    /// Takes one accepted step, not going past `t_limit` (> current time).
    ///
    /// Returns the new time. After it, [`Dop853::interpolate`] is valid on `[t_old, t]`.
    pub fn step(&mut self, t_limit: f64) -> Result<f64, SimError> {
        debug_assert!(t_limit > self.t);
        let mut h = self.h;
        let mut rejected = false;
        loop {
            if self.stats.accepted + self.stats.rejected >= self.max_steps {
                return Err(SimError::TooManySteps {
                    t: self.t,
                    steps: self.max_steps,
                });
            }
            let min_step = 10.0 * (next_up(self.t.abs()) - self.t.abs());
            if h < min_step {
                return Err(SimError::StepSizeTooSmall { t: self.t, h });
            }
            let mut t_new = self.t + h;
            if t_new >= t_limit {
                t_new = t_limit;
            }
            let h_try = t_new - self.t;

            // Stages.
            self.k[0] = self.f;
            for s in 1..STAGES {
                let ys = self.combine(s, h_try);
                let mut ks = [0.0; N];
                self.sys.rhs(self.t + C[s] * h_try, &ys, &mut ks);
                self.k[s] = ks;
            }
            let y_new = self.combine(STAGES, h_try);
            let mut f_new = [0.0; N];
            self.sys.rhs(t_new, &y_new, &mut f_new);
            self.stats.evaluations += STAGES;
            self.k[STAGES] = f_new;

            let err = self.error_norm(h_try, &y_new);
            if err.is_finite() && err < 1.0 {
                let factor = if err == 0.0 {
                    MAX_FACTOR
                } else {
                    MAX_FACTOR.min(SAFETY * err.powf(ERROR_EXPONENT))
                };
                let factor = if rejected { factor.min(1.0) } else { factor };
                // Keep the proposal of the unclamped step: clamping to t_limit is not a verdict on h.
                self.h = h.max(h_try) * factor;
                self.t_old = self.t;
                self.y_old = self.y;
                self.h_last = h_try;
                self.t = t_new;
                self.y = y_new;
                self.f = f_new;
                self.dense_ready = false;
                self.stats.accepted += 1;
                return Ok(self.t);
            }
            self.stats.rejected += 1;
            rejected = true;
            h = if err.is_finite() {
                h_try * MIN_FACTOR.max(SAFETY * err.powf(ERROR_EXPONENT))
            } else {
                h_try * 0.25
            };
        }
    }

    /// `y + h Σ_j a_sj k_j` for stage `s` (row 12 of `A` is `b`).
    #[inline]
    fn combine(&self, s: usize, h: f64) -> [f64; N] {
        let mut acc = [0.0; N];
        for &(j, a) in A[s] {
            for (acc_i, k_ji) in acc.iter_mut().zip(&self.k[j]) {
                *acc_i += a * k_ji;
            }
        }
        std::array::from_fn(|i| self.y[i] + h * acc[i])
    }

    fn error_norm(&self, h: f64, y_new: &[f64; N]) -> f64 {
        let mut err5 = 0.0;
        let mut err3 = 0.0;
        for i in 0..N {
            let scale = self.tol.atol + self.y[i].abs().max(y_new[i].abs()) * self.tol.rtol;
            let e5: f64 = E5.iter().map(|&(j, e)| e * self.k[j][i]).sum();
            // e3 = b - bhh, with b at stages 0..11 and a zero weight at stage 12.
            let e3: f64 = B.iter().map(|&(j, b)| b * self.k[j][i]).sum::<f64>()
                - BHH.iter().map(|&(j, e)| e * self.k[j][i]).sum::<f64>();
            err5 += (e5 / scale).powi(2);
            err3 += (e3 / scale).powi(2);
        }
        if err5 == 0.0 && err3 == 0.0 {
            return 0.0;
        }
        h.abs() * err5 / ((err5 + 0.01 * err3) * N as f64).sqrt()
    }

    fn prepare_dense(&mut self) {
        let h = self.h_last;
        for s in STAGES + 1..STAGES_EXT {
            let mut acc = [0.0; N];
            for &(j, a) in A[s] {
                for (acc_i, k_ji) in acc.iter_mut().zip(&self.k[j]) {
                    *acc_i += a * k_ji;
                }
            }
            let ys: [f64; N] = std::array::from_fn(|i| self.y_old[i] + h * acc[i]);
            let mut ks = [0.0; N];
            self.sys.rhs(self.t_old + C[s] * h, &ys, &mut ks);
            self.k[s] = ks;
        }
        self.stats.evaluations += STAGES_EXT - STAGES - 1;
        let f_old = self.k[0];
        for i in 0..N {
            let dy = self.y[i] - self.y_old[i];
            self.dense[0][i] = dy;
            self.dense[1][i] = h * f_old[i] - dy;
            self.dense[2][i] = 2.0 * dy - h * (self.f[i] + f_old[i]);
        }
        for (row, drow) in D.iter().enumerate() {
            for i in 0..N {
                self.dense[3 + row][i] = h * drow.iter().map(|&(j, d)| d * self.k[j][i]).sum::<f64>();
            }
        }
        self.dense_ready = true;
    }

    /// The dense-output value at `t` within the last accepted step `[t_old, t]`.
    ///
    /// At the step's end it returns the step's own solution exactly.
    ///
    /// # Panics
    /// If no step has been taken since the start or the last [`Dop853::set_state`].
    pub fn interpolate(&mut self, t: f64) -> [f64; N] {
        assert!(self.h_last > 0.0, "interpolate needs an accepted step");
        if t == self.t {
            return self.y;
        }
        if !self.dense_ready {
            self.prepare_dense();
        }
        let x = (t - self.t_old) / self.h_last;
        let mut y = [0.0; N];
        for (idx, row) in self.dense.iter().rev().enumerate() {
            let w = if idx % 2 == 0 { x } else { 1.0 - x };
            for i in 0..N {
                y[i] = (y[i] + row[i]) * w;
            }
        }
        std::array::from_fn(|i| y[i] + self.y_old[i])
    }

    /// Integrates up to exactly `t_end` (no-op if already there).
    pub fn advance_to(&mut self, t_end: f64) -> Result<(), SimError> {
        while self.t < t_end {
            self.step(t_end)?;
        }
        Ok(())
    }

    /// Integrates over a grid `t_first + n · dt`, `n = 0..count`, calling `sink(n, t_n, y(t_n))` for
    /// each point in order, from dense output (or exactly at a step's end). Grid times are computed
    /// by multiplication, never by accumulating `dt`, so the last point is exactly where it should
    /// be. `t_first` must not be before the current time.
    pub fn sample_grid(
        &mut self,
        t_first: f64,
        dt: f64,
        count: usize,
        sink: impl FnMut(usize, f64, &[f64; N]),
    ) -> Result<(), SimError> {
        let mut sink = sink;
        sample_on_grid(self, t_first, dt, count, |n, t, y| {
            sink(n, t, y);
            ControlFlow::Continue(())
        })
    }
}

/// An integration that moves forward one accepted step at a time, with an interpolant inside the
/// last step: [`Dop853`] itself, and the flows across the switches of dry friction built on it.
/// The samplers below are written once for all of them.
pub(crate) trait Stepper<const N: usize> {
    /// The current time.
    fn now(&self) -> f64;
    /// The current state.
    fn state(&self) -> [f64; N];
    /// Takes one accepted step, not going past `t_limit` (> current time); returns the new time.
    fn advance(&mut self, t_limit: f64) -> Result<f64, SimError>;
    /// The interpolated state at `t` inside the last step.
    fn state_at(&mut self, t: f64) -> [f64; N];
}

impl<S: OdeSystem<N>, const N: usize> Stepper<N> for Dop853<S, N> {
    fn now(&self) -> f64 {
        self.t
    }
    fn state(&self) -> [f64; N] {
        self.y
    }
    fn advance(&mut self, t_limit: f64) -> Result<f64, SimError> {
        self.step(t_limit)
    }
    fn state_at(&mut self, t: f64) -> [f64; N] {
        self.interpolate(t)
    }
}

/// [`Dop853::sample_grid`] for any [`Stepper`]: the grid's step and start checked, then
/// [`sample_at_times`] at `t_first + n · dt`.
pub(crate) fn sample_on_grid<St: Stepper<N> + ?Sized, const N: usize>(
    stepper: &mut St,
    t_first: f64,
    dt: f64,
    count: usize,
    sink: impl FnMut(usize, f64, &[f64; N]) -> ControlFlow<()>,
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
    if t_first < stepper.now() {
        return Err(SimError::InvalidParameter {
            name: "t_first",
            value: t_first,
            why: "must not be before the current time",
        });
    }
    sample_at_times(stepper, count, |n| t_first + n as f64 * dt, sink)
}

/// Integrates up to the last of the times `time(n)`, `n = 0..count` (non-decreasing, the first
/// not before the current time), calling `sink(n, t_n, y(t_n))` for each in order, from dense
/// output (or exactly at a step's end). The step sequence depends only on the last time. A sink
/// that breaks ends the integration there (the caller knows why; `Ok` is returned).
pub(crate) fn sample_at_times<St: Stepper<N> + ?Sized, const N: usize>(
    stepper: &mut St,
    count: usize,
    time: impl Fn(usize) -> f64,
    mut sink: impl FnMut(usize, f64, &[f64; N]) -> ControlFlow<()>,
) -> Result<(), SimError> {
    if count == 0 {
        return Ok(());
    }
    let t_end = time(count - 1);
    let mut n = 0;
    // A sample exactly at the current time needs no step.
    while n < count && time(n) == stepper.now() {
        let y = stepper.state();
        if sink(n, stepper.now(), &y).is_break() {
            return Ok(());
        }
        n += 1;
    }
    while n < count {
        let t_new = stepper.advance(t_end)?;
        while n < count {
            let tn = time(n);
            if tn > t_new {
                break;
            }
            let y = stepper.state_at(tn);
            if y.iter().any(|v| !v.is_finite()) {
                return Err(SimError::NonFinite { t: tn });
            }
            if sink(n, tn, &y).is_break() {
                return Ok(());
            }
            n += 1;
        }
    }
    Ok(())
}

/// The next representable `f64` above a non-negative finite `x`.
fn next_up(x: f64) -> f64 {
    f64::from_bits(x.to_bits() + 1)
}
