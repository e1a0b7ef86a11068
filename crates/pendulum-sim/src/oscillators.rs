//! The two oscillators of this crate: the base-excited pendulum and the two-well Duffing
//! oscillator, each with a rig's losses and drive harmonics.

use serde::{Deserialize, Serialize};

use crate::error::SimError;
use crate::machine::{DriveHarmonics, Losses};
use crate::system::{Branch, SecondOrderSystem};

/// The horizontally base-excited pendulum, paper eq. 1 in non-dimensional time:
///
/// `x'' + c x' + (1/r²) sin x − f sin(t) cos x = 0`.
///
/// A real rig adds [`Losses`] (dry friction, quadratic drag, cubic damping) and
/// [`DriveHarmonics`] (harmonics of the base acceleration) with [`Pendulum::with_losses`] and
/// [`Pendulum::with_drive_harmonics`]:
///
/// `x'' + c x' + μ sign(x') + d x'|x'| + c₃ x'^3 + (1/r²) sin x − f [sin(t) + Σ ρ_k sin(k t + φ_k)] cos x = 0`.
///
/// Construct with [`Pendulum::new`] (validated) or [`Pendulum::paper`]. Serialised as `f`, `c`
/// and `r`, with `losses` and `drive_harmonics` only when there are any; deserialising validates
/// them as the constructors do.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "PendulumRaw", into = "PendulumRaw")]
pub struct Pendulum {
    f: f64,
    c: f64,
    r: f64,
    /// `1/r²`, cached for the right-hand side; derived from `r`, so never serialised.
    inv_r2: f64,
    losses: Losses,
    harmonics: DriveHarmonics,
}

/// The serialised form of [`Pendulum`].
#[derive(Serialize, Deserialize)]
struct PendulumRaw {
    f: f64,
    c: f64,
    r: f64,
    #[serde(default, skip_serializing_if = "Losses::is_none")]
    losses: Losses,
    #[serde(default, skip_serializing_if = "DriveHarmonics::is_empty")]
    drive_harmonics: DriveHarmonics,
}

impl TryFrom<PendulumRaw> for Pendulum {
    type Error = SimError;
    fn try_from(raw: PendulumRaw) -> Result<Self, SimError> {
        Ok(Self::new(raw.f, raw.c, raw.r)?
            .with_losses(raw.losses)
            .with_drive_harmonics(raw.drive_harmonics))
    }
}

impl From<Pendulum> for PendulumRaw {
    fn from(p: Pendulum) -> Self {
        Self {
            f: p.f,
            c: p.c,
            r: p.r,
            losses: p.losses,
            drive_harmonics: p.harmonics,
        }
    }
}

impl Pendulum {
    /// The paper's parameters: `f = 1.52`, `c = 0.03`, `r = 0.8333`.
    pub const PAPER: (f64, f64, f64) = (1.52, 0.03, 0.8333);

    /// A pendulum with forcing amplitude `f`, damping `c = 2ξ/r` and frequency ratio `r`.
    ///
    /// `f` and `c` must be finite (either sign is accepted), `r` finite and non-zero.
    pub fn new(f: f64, c: f64, r: f64) -> Result<Self, SimError> {
        for (name, value) in [("f", f), ("c", c), ("r", r)] {
            if !value.is_finite() {
                return Err(SimError::InvalidParameter {
                    name,
                    value,
                    why: "must be finite",
                });
            }
        }
        if r == 0.0 {
            return Err(SimError::InvalidParameter {
                name: "r",
                value: r,
                why: "must be non-zero",
            });
        }
        Ok(Self {
            f,
            c,
            r,
            inv_r2: 1.0 / (r * r),
            losses: Losses::none(),
            harmonics: DriveHarmonics::none(),
        })
    }

    /// The paper's pendulum (`f = 1.52`, `c = 0.03`, `r = 0.8333`).
    pub fn paper() -> Self {
        let (f, c, r) = Self::PAPER;
        Self {
            f,
            c,
            r,
            inv_r2: 1.0 / (r * r),
            losses: Losses::none(),
            harmonics: DriveHarmonics::none(),
        }
    }

    /// The pendulum with `losses` (validated when built) beside its viscous damping.
    pub fn with_losses(mut self, losses: Losses) -> Self {
        self.losses = losses;
        self
    }

    /// The pendulum whose base acceleration has the harmonics `harmonics` (validated when built)
    /// beside its fundamental `sin(t)`; their amplitudes are ratios to `f`.
    pub fn with_drive_harmonics(mut self, harmonics: DriveHarmonics) -> Self {
        self.harmonics = harmonics;
        self
    }

    /// The losses beyond viscous damping.
    pub fn losses(&self) -> &Losses {
        &self.losses
    }

    /// The harmonics of the base acceleration.
    pub fn drive_harmonics(&self) -> &DriveHarmonics {
        &self.harmonics
    }

    /// The drive at time `t` as it enters the equation: `f a(t)`, `a(t) = sin(t) + Σ ρ_k sin(k t +
    /// φ_k)` the base acceleration, the factor of `cos x` (a record's measured drive `p`, whose
    /// term `p*cos(x)` then has the coefficient −1).
    pub fn drive(&self, t: f64) -> f64 {
        self.f * (t.sin() + self.harmonics.sin_sum(t))
    }

    /// The energy `E = v²/2 + (1 − cos x)/r²` of the undamped, undriven pendulum; along a
    /// solution `dE/dt = −c v² − (μ |v| + d |v|³ + c₃ v⁴) + f a(t) cos(x) v`, `a(t)` the base
    /// acceleration.
    pub fn energy(&self, x: f64, v: f64) -> f64 {
        0.5 * v * v + self.inv_r2 * (1.0 - x.cos())
    }

    /// Forcing amplitude `f`.
    pub fn f(&self) -> f64 {
        self.f
    }
    /// Damping `c`.
    pub fn c(&self) -> f64 {
        self.c
    }
    /// Frequency ratio `r`.
    pub fn r(&self) -> f64 {
        self.r
    }
}

impl Pendulum {
    /// `F` without the [`Losses`]: `−c v − (1/r²) sin x + f a(t) cos x`.
    #[inline]
    fn ideal(&self, t: f64, x: f64, v: f64) -> f64 {
        let (s, c) = x.sin_cos();
        let a = -self.c * v - self.inv_r2 * s + self.f * t.sin() * c;
        if self.harmonics.has_terms() {
            a + self.f * self.harmonics.sin_sum(t) * c
        } else {
            a
        }
    }

    /// `∂F/∂x`.
    #[inline]
    fn stiffness_slope(&self, t: f64, x: f64) -> f64 {
        let (s, c) = x.sin_cos();
        let j = -self.inv_r2 * c - self.f * t.sin() * s;
        if self.harmonics.has_terms() {
            j - self.f * self.harmonics.sin_sum(t) * s
        } else {
            j
        }
    }
}

impl SecondOrderSystem for Pendulum {
    #[inline]
    fn acceleration(&self, t: f64, x: f64, v: f64) -> f64 {
        let a = self.ideal(t, x, v);
        if self.losses.is_none() {
            a
        } else {
            a - self.losses.force(v)
        }
    }

    #[inline]
    fn jacobian(&self, t: f64, x: f64, v: f64) -> [f64; 2] {
        let jv = if self.losses.is_none() {
            -self.c
        } else {
            -self.c - self.losses.force_slope(v)
        };
        [self.stiffness_slope(t, x), jv]
    }

    fn switches_at_rest(&self) -> bool {
        self.losses.switches_at_rest()
    }

    #[inline]
    fn acceleration_on(&self, branch: Branch, t: f64, x: f64, v: f64) -> f64 {
        self.ideal(t, x, v) - self.losses.force_on(branch, v)
    }

    #[inline]
    fn jacobian_on(&self, branch: Branch, t: f64, x: f64, v: f64) -> [f64; 2] {
        [
            self.stiffness_slope(t, x),
            -self.c - self.losses.force_slope_on(branch, v),
        ]
    }
}

/// The two-well Duffing oscillator in non-dimensional time (drive period `2π`):
///
/// `x'' + c x' + a x + b x³ = f cos(t)`.
///
/// With `a < 0 < b` the potential `a x²/2 + b x⁴/4` has two wells at `x = ±√(−a/b)` and a hump at
/// `x = 0`; [`Duffing::TWO_WELL`] (`c = 0.25`, `a = −1`, `b = 1`, `f = 0.3`, Guckenheimer & Holmes,
/// *Nonlinear Oscillations*, section 2.2, after Moon & Holmes' buckled beam) moves chaotically
/// between them. The drive stands on the right-hand side: in the identification's form
/// `x'' + Σ c_i g_i = 0` its term `cos(t)` has the coefficient `−f`.
///
/// A real rig adds [`Losses`] and [`DriveHarmonics`] (harmonics of the forcing) with
/// [`Duffing::with_losses`] and [`Duffing::with_drive_harmonics`]:
///
/// `x'' + c x' + μ sign(x') + d x'|x'| + c₃ x'^3 + a x + b x³ = f [cos(t) + Σ ρ_k cos(k t + φ_k)]`.
///
/// Construct with [`Duffing::new`] (validated) or [`Duffing::two_well`]. Serialised as `c`, `a`,
/// `b` and `f`, with `losses` and `drive_harmonics` only when there are any; deserialising
/// validates them as the constructors do.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "DuffingRaw", into = "DuffingRaw")]
pub struct Duffing {
    c: f64,
    a: f64,
    b: f64,
    f: f64,
    losses: Losses,
    harmonics: DriveHarmonics,
}

/// The serialised form of [`Duffing`].
#[derive(Serialize, Deserialize)]
struct DuffingRaw {
    c: f64,
    a: f64,
    b: f64,
    f: f64,
    #[serde(default, skip_serializing_if = "Losses::is_none")]
    losses: Losses,
    #[serde(default, skip_serializing_if = "DriveHarmonics::is_empty")]
    drive_harmonics: DriveHarmonics,
}

impl TryFrom<DuffingRaw> for Duffing {
    type Error = SimError;
    fn try_from(raw: DuffingRaw) -> Result<Self, SimError> {
        Ok(Self::new(raw.c, raw.a, raw.b, raw.f)?
            .with_losses(raw.losses)
            .with_drive_harmonics(raw.drive_harmonics))
    }
}

impl From<Duffing> for DuffingRaw {
    fn from(d: Duffing) -> Self {
        Self {
            c: d.c,
            a: d.a,
            b: d.b,
            f: d.f,
            losses: d.losses,
            drive_harmonics: d.harmonics,
        }
    }
}

impl Duffing {
    /// The classic chaotic two-well set `(c, a, b, f) = (0.25, −1, 1, 0.3)`.
    pub const TWO_WELL: (f64, f64, f64, f64) = (0.25, -1.0, 1.0, 0.3);

    /// `x'' + c x' + a x + b x³ = f cos(t)`, the parameters in the order of the equation.
    ///
    /// Every parameter must be finite; either sign is accepted (`a < 0 < b` gives two wells, `b < 0`
    /// a softening spring whose solutions may escape to infinity, which the integrator reports).
    pub fn new(c: f64, a: f64, b: f64, f: f64) -> Result<Self, SimError> {
        for (name, value) in [("c", c), ("a", a), ("b", b), ("f", f)] {
            if !value.is_finite() {
                return Err(SimError::InvalidParameter {
                    name,
                    value,
                    why: "must be finite",
                });
            }
        }
        Ok(Self {
            c,
            a,
            b,
            f,
            losses: Losses::none(),
            harmonics: DriveHarmonics::none(),
        })
    }

    /// The chaotic two-well oscillator [`Duffing::TWO_WELL`].
    pub fn two_well() -> Self {
        let (c, a, b, f) = Self::TWO_WELL;
        Self {
            c,
            a,
            b,
            f,
            losses: Losses::none(),
            harmonics: DriveHarmonics::none(),
        }
    }

    /// The oscillator with `losses` (validated when built) beside its viscous damping.
    pub fn with_losses(mut self, losses: Losses) -> Self {
        self.losses = losses;
        self
    }

    /// The oscillator whose forcing has the harmonics `harmonics` (validated when built) beside
    /// its fundamental `cos(t)`; their amplitudes are ratios to `f`.
    pub fn with_drive_harmonics(mut self, harmonics: DriveHarmonics) -> Self {
        self.harmonics = harmonics;
        self
    }

    /// The losses beyond viscous damping.
    pub fn losses(&self) -> &Losses {
        &self.losses
    }

    /// The harmonics of the forcing.
    pub fn drive_harmonics(&self) -> &DriveHarmonics {
        &self.harmonics
    }

    /// Damping `c`.
    pub fn c(&self) -> f64 {
        self.c
    }
    /// Linear stiffness `a` (negative for two wells).
    pub fn a(&self) -> f64 {
        self.a
    }
    /// Cubic stiffness `b`.
    pub fn b(&self) -> f64 {
        self.b
    }
    /// Drive amplitude `f`.
    pub fn f(&self) -> f64 {
        self.f
    }

    /// The forcing at time `t` as it enters the equation: `f [cos(t) + Σ ρ_k cos(k t + φ_k)]` (a
    /// record's measured drive `p`, whose term `p` then has the coefficient −1).
    pub fn drive(&self, t: f64) -> f64 {
        self.f * (t.cos() + self.harmonics.cos_sum(t))
    }

    /// The energy `E = v²/2 + a x²/2 + b x⁴/4` of the undamped, undriven oscillator; along a
    /// solution `dE/dt = −c v² − (μ |v| + d |v|³ + c₃ v⁴) + f [cos(t) + Σ ρ_k cos(k t + φ_k)] v`.
    pub fn energy(&self, x: f64, v: f64) -> f64 {
        0.5 * v * v + 0.5 * self.a * x * x + 0.25 * self.b * x.powi(4)
    }
}

impl Duffing {
    /// `F` without the [`Losses`].
    #[inline]
    fn ideal(&self, t: f64, x: f64, v: f64) -> f64 {
        let a = self.f * t.cos() - self.c * v - self.a * x - self.b * x * x * x;
        if self.harmonics.has_terms() {
            a + self.f * self.harmonics.cos_sum(t)
        } else {
            a
        }
    }
}

impl SecondOrderSystem for Duffing {
    #[inline]
    fn acceleration(&self, t: f64, x: f64, v: f64) -> f64 {
        let a = self.ideal(t, x, v);
        if self.losses.is_none() {
            a
        } else {
            a - self.losses.force(v)
        }
    }

    #[inline]
    fn jacobian(&self, _t: f64, x: f64, v: f64) -> [f64; 2] {
        let jv = if self.losses.is_none() {
            -self.c
        } else {
            -self.c - self.losses.force_slope(v)
        };
        [-self.a - 3.0 * self.b * x * x, jv]
    }

    fn switches_at_rest(&self) -> bool {
        self.losses.switches_at_rest()
    }

    #[inline]
    fn acceleration_on(&self, branch: Branch, t: f64, x: f64, v: f64) -> f64 {
        self.ideal(t, x, v) - self.losses.force_on(branch, v)
    }

    #[inline]
    fn jacobian_on(&self, branch: Branch, _t: f64, x: f64, v: f64) -> [f64; 2] {
        [
            -self.a - 3.0 * self.b * x * x,
            -self.c - self.losses.force_slope_on(branch, v),
        ]
    }
}
