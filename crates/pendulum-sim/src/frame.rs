//! A system seen in a record's own time unit and coordinate.
//!
//! The systems of this crate run in non-dimensional time `τ` (drive period `2π`). A rig's record
//! has its own time `t` (seconds) and, for an encoder, its own zero. A [`RecordFrame`] says how
//! the two relate:
//!
//! ```text
//! τ = rate · t + phase,        x = θ − offset,
//! ```
//!
//! with `rate = 2π f_drive` for a drive of `f_drive` Hz (the drive's period is `1 / f_drive` s),
//! `phase` the drive's phase at `t = 0`, and `offset` how far the encoder's zero is from the
//! system's `θ = 0`. Then `dx/dt = rate · dθ/dτ` and `d²x/dt² = rate² · d²θ/dτ²`, so the system
//! `θ'' = F(τ, θ, θ')` reads, in the record's frame,
//!
//! ```text
//! ẍ = rate² · F(rate · t + phase, x + offset, ẋ / rate).
//! ```
//!
//! [`InFrame`] integrates that equation directly (its velocity is in the record's time unit); a
//! system of several coordinates ([`MultiSystem`]) reads the same in every coordinate,
//! `q̈ = rate² · A(rate · t + phase, q + offset, q̇ / rate)`, the offset added to each. The
//! same equation in the identification's terms, `ẍ + Σ c_i g_i(t, x, ẋ) = 0`, is written once, in
//! [`truth`](crate::truth), from these systems and frames.
//!
//! # Example
//!
//! ```
//! use pendulum_sim::{InFrame, Pendulum, RecordFrame, SecondOrderSystem};
//!
//! // The paper's pendulum on a rig driven at 1.02 Hz, time in seconds: its acceleration is
//! // rate² times the system's at τ = rate · t.
//! let frame = RecordFrame::nondimensional().with_drive_frequency(1.02)?;
//! let rig = InFrame::new(Pendulum::paper(), frame);
//! let w = std::f64::consts::TAU * 1.02;
//! let a = rig.acceleration(0.3, 0.5, w * 0.2);
//! assert!((a - w * w * Pendulum::paper().acceleration(w * 0.3, 0.5, 0.2)).abs() < 1e-9);
//! # Ok::<(), pendulum_sim::SimError>(())
//! ```

use std::f64::consts::TAU;

use crate::error::SimError;
use crate::multi::{MAX_COORDINATES, MultiSystem, SingularMass};
use crate::system::{Branch, SecondOrderSystem};

/// How a record's time and coordinate relate to a system's non-dimensional ones:
/// `τ = rate · t + phase`, `x = θ − offset` (see the [module documentation](self)).
///
/// Built from [`RecordFrame::nondimensional`] (`rate = 1`, `phase = 0`, `offset = 0`: the
/// system's own frame) by the validating setters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RecordFrame {
    rate: f64,
    phase: f64,
    offset: f64,
}

impl Default for RecordFrame {
    fn default() -> Self {
        Self::nondimensional()
    }
}

impl RecordFrame {
    /// The system's own frame: non-dimensional time, no drive phase, no offset.
    pub fn nondimensional() -> Self {
        Self {
            rate: 1.0,
            phase: 0.0,
            offset: 0.0,
        }
    }

    /// `dτ/dt` (positive and finite): the drive's angular frequency in the record's time unit.
    pub fn with_rate(mut self, rate: f64) -> Result<Self, SimError> {
        if !(rate.is_finite() && rate > 0.0) {
            return Err(SimError::InvalidParameter {
                name: "time scale",
                value: rate,
                why: "must be positive and finite",
            });
        }
        self.rate = rate;
        Ok(self)
    }

    /// Time in seconds for a drive of `hz` Hz (positive and finite): `rate = 2π · hz`.
    pub fn with_drive_frequency(self, hz: f64) -> Result<Self, SimError> {
        if !(hz.is_finite() && hz > 0.0) {
            return Err(SimError::InvalidParameter {
                name: "drive frequency",
                value: hz,
                why: "must be positive and finite",
            });
        }
        self.with_rate(TAU * hz)
    }

    /// The drive's phase (radians, finite) at the record's `t = 0`.
    pub fn with_phase(mut self, phase: f64) -> Result<Self, SimError> {
        if !phase.is_finite() {
            return Err(SimError::InvalidParameter {
                name: "drive phase",
                value: phase,
                why: "must be finite",
            });
        }
        self.phase = phase;
        Ok(self)
    }

    /// How far (finite, in the coordinate's unit) the record's zero is from the system's: the
    /// record holds `x = θ − offset`.
    pub fn with_offset(mut self, offset: f64) -> Result<Self, SimError> {
        if !offset.is_finite() {
            return Err(SimError::InvalidParameter {
                name: "zero offset",
                value: offset,
                why: "must be finite",
            });
        }
        self.offset = offset;
        Ok(self)
    }

    /// `dτ/dt`.
    pub fn rate(&self) -> f64 {
        self.rate
    }
    /// The drive's phase at `t = 0`.
    pub fn phase(&self) -> f64 {
        self.phase
    }
    /// The coordinate's offset.
    pub fn offset(&self) -> f64 {
        self.offset
    }
    /// The drive's period in the record's time unit, `2π / rate`.
    pub fn drive_period(&self) -> f64 {
        TAU / self.rate
    }
    /// The system's time `τ = rate · t + phase` at the record's time `t`.
    pub fn system_time(&self, t: f64) -> f64 {
        self.rate * t + self.phase
    }
}

/// A system in a record's frame: `ẍ = rate² · F(rate · t + phase, x + offset, ẋ / rate)`, so
/// that its solutions are the system's, in the record's time unit and coordinate.
///
/// ```
/// use pendulum_sim::{simulate, InFrame, Pendulum, RecordFrame, SimulationConfig};
///
/// // The paper's pendulum driven at 1.02 Hz, sampled at 500 Hz, time in seconds.
/// let frame = RecordFrame::nondimensional().with_drive_frequency(1.02)?;
/// let config = SimulationConfig::paper()
///     .with_drive_period(frame.drive_period())?
///     .with_sample_step(1.0 / 500.0)?
///     .with_transient_periods(5)
///     .with_samples(1000)?;
/// let record = simulate(&InFrame::new(Pendulum::paper(), frame), &config)?;
/// assert!((record.t[1] - record.t[0] - 0.002).abs() < 1e-12);
/// # Ok::<(), pendulum_sim::SimError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InFrame<S> {
    system: S,
    frame: RecordFrame,
}

impl<S> InFrame<S> {
    /// `system` seen in `frame`.
    pub fn new(system: S, frame: RecordFrame) -> Self {
        Self { system, frame }
    }
    /// The system.
    pub fn system(&self) -> &S {
        &self.system
    }
    /// The frame.
    pub fn frame(&self) -> &RecordFrame {
        &self.frame
    }
}

impl<S: SecondOrderSystem> SecondOrderSystem for InFrame<S> {
    #[inline]
    fn acceleration(&self, t: f64, x: f64, v: f64) -> f64 {
        let RecordFrame { rate, phase, offset } = self.frame;
        rate * rate * self.system.acceleration(rate * t + phase, x + offset, v / rate)
    }

    #[inline]
    fn jacobian(&self, t: f64, x: f64, v: f64) -> [f64; 2] {
        let RecordFrame { rate, phase, offset } = self.frame;
        let [jx, jv] = self.system.jacobian(rate * t + phase, x + offset, v / rate);
        [rate * rate * jx, rate * jv]
    }

    fn switches_at_rest(&self) -> bool {
        self.system.switches_at_rest()
    }

    /// The branch is the same in both frames: `rate > 0` keeps the sign of the velocity.
    #[inline]
    fn acceleration_on(&self, branch: Branch, t: f64, x: f64, v: f64) -> f64 {
        let RecordFrame { rate, phase, offset } = self.frame;
        rate * rate
            * self
                .system
                .acceleration_on(branch, rate * t + phase, x + offset, v / rate)
    }

    #[inline]
    fn jacobian_on(&self, branch: Branch, t: f64, x: f64, v: f64) -> [f64; 2] {
        let RecordFrame { rate, phase, offset } = self.frame;
        let [jx, jv] = self
            .system
            .jacobian_on(branch, rate * t + phase, x + offset, v / rate);
        [rate * rate * jx, rate * jv]
    }
}

impl<S: MultiSystem> InFrame<S> {
    /// The accelerations of the system in the frame, by `accelerate` (the system's plain
    /// accelerations, or those with held signs): the state moved into the system's frame, the
    /// result scaled by `rate²`.
    #[inline]
    fn in_frame(
        &self,
        t: f64,
        q: &[f64],
        v: &[f64],
        acc: &mut [f64],
        accelerate: impl FnOnce(f64, &[f64], &[f64], &mut [f64]) -> Result<(), SingularMass>,
    ) -> Result<(), SingularMass> {
        let RecordFrame { rate, phase, offset } = self.frame;
        let n = q.len();
        let mut qs = [0.0; MAX_COORDINATES];
        let mut vs = [0.0; MAX_COORDINATES];
        for (slot, &x) in qs.iter_mut().zip(q) {
            *slot = x + offset;
        }
        for (slot, &x) in vs.iter_mut().zip(v) {
            *slot = x / rate;
        }
        accelerate(rate * t + phase, &qs[..n], &vs[..n], acc)?;
        for a in acc.iter_mut() {
            *a *= rate * rate;
        }
        Ok(())
    }
}

/// A system of several coordinates in a record's frame: `q̈ = rate² · A(rate · t + phase, q +
/// offset, q̇ / rate)`, each coordinate moved by the same offset. A singular mass matrix is
/// reported at the system's time.
impl<S: MultiSystem> MultiSystem for InFrame<S> {
    fn coordinates(&self) -> usize {
        self.system.coordinates()
    }

    #[inline]
    fn accelerations(&self, t: f64, q: &[f64], v: &[f64], acc: &mut [f64]) -> Result<(), SingularMass> {
        self.in_frame(t, q, v, acc, |tau, q, v, acc| {
            self.system.accelerations(tau, q, v, acc)
        })
    }

    fn switches_at_rest(&self, c: usize) -> bool {
        self.system.switches_at_rest(c)
    }

    /// The signs are the same in both frames: `rate > 0` keeps the sign of every velocity.
    #[inline]
    fn accelerations_with_signs(
        &self,
        t: f64,
        q: &[f64],
        v: &[f64],
        signs: &[f64],
        acc: &mut [f64],
    ) -> Result<(), SingularMass> {
        self.in_frame(t, q, v, acc, |tau, q, v, acc| {
            self.system.accelerations_with_signs(tau, q, v, signs, acc)
        })
    }
}
