//! What a real machine adds to the ideal equations: losses beyond viscous damping, and a drive
//! that is not a clean sinusoid.
//!
//! [`Losses`] are the velocity-dependent forces on the left-hand side of the equation,
//!
//! ```text
//! μ sign(x') + d x'|x'| + c₃ x'^3,
//! ```
//!
//! dry (Coulomb) friction `μ`, quadratic (air) drag `d` and cubic damping `c₃`, all non-negative
//! (they take energy out of the motion). `sign(0) = 0`: at rest the friction force is whatever
//! holds the body, up to `μ` (see the crate documentation for how the integrators treat the
//! discontinuity at `x' = 0`).
//!
//! [`DriveHarmonics`] are the harmonics `k = 2, 3, …` of the drive, each with an amplitude
//! ratio `ρ_k` to the fundamental and a phase `φ_k`: the pendulum's base acceleration
//! `sin(t)` becomes `sin(t) + Σ ρ_k sin(k t + φ_k)`, the Duffing oscillator's forcing `cos(t)`
//! becomes `cos(t) + Σ ρ_k cos(k t + φ_k)`.
//!
//! Both are validated when built and when deserialised; their defaults ([`Losses::none`],
//! [`DriveHarmonics::none`]) leave a system exactly as it was.

use serde::{Deserialize, Serialize};

use crate::error::SimError;
use crate::system::Branch;

/// Velocity-dependent losses `μ sign(x') + d x'|x'| + c₃ x'^3` on the left-hand side of an
/// equation: dry (Coulomb) friction `μ`, quadratic drag `d` and cubic damping `c₃`, all
/// non-negative; `sign(0) = 0`, so at rest the friction holds the body up to `μ`.
///
/// Built from [`Losses::none`] by the validating setters; deserialising validates as they do.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(try_from = "LossesRaw", into = "LossesRaw")]
pub struct Losses {
    friction: f64,
    drag: f64,
    cubic: f64,
}

/// The serialised form of [`Losses`].
#[derive(Serialize, Deserialize)]
struct LossesRaw {
    #[serde(default)]
    friction: f64,
    #[serde(default)]
    drag: f64,
    #[serde(default)]
    cubic_damping: f64,
}

impl TryFrom<LossesRaw> for Losses {
    type Error = SimError;
    fn try_from(raw: LossesRaw) -> Result<Self, SimError> {
        Self::none()
            .with_friction(raw.friction)?
            .with_drag(raw.drag)?
            .with_cubic_damping(raw.cubic_damping)
    }
}

impl From<Losses> for LossesRaw {
    fn from(l: Losses) -> Self {
        Self {
            friction: l.friction,
            drag: l.drag,
            cubic_damping: l.cubic,
        }
    }
}

/// A loss coefficient: finite and non-negative.
fn loss(name: &'static str, value: f64) -> Result<f64, SimError> {
    if value.is_finite() && value >= 0.0 {
        // -0.0 is stored as 0.0, so that it prints and compares as no loss.
        Ok(value + 0.0)
    } else {
        Err(SimError::InvalidParameter {
            name,
            value,
            why: "must be finite and non-negative",
        })
    }
}

/// `sign(v)` with `sign(0) = 0`.
#[inline]
pub(crate) fn sign0(v: f64) -> f64 {
    if v > 0.0 {
        1.0
    } else if v < 0.0 {
        -1.0
    } else {
        0.0
    }
}

impl Losses {
    /// No losses beyond the system's viscous damping.
    pub fn none() -> Self {
        Self {
            friction: 0.0,
            drag: 0.0,
            cubic: 0.0,
        }
    }

    /// Dry (Coulomb) friction `μ sign(x')`, `μ` finite and non-negative.
    pub fn with_friction(mut self, mu: f64) -> Result<Self, SimError> {
        self.friction = loss("friction", mu)?;
        Ok(self)
    }

    /// Quadratic drag `d x'|x'|`, `d` finite and non-negative.
    pub fn with_drag(mut self, d: f64) -> Result<Self, SimError> {
        self.drag = loss("drag", d)?;
        Ok(self)
    }

    /// Cubic damping `c₃ x'^3`, `c₃` finite and non-negative.
    pub fn with_cubic_damping(mut self, c3: f64) -> Result<Self, SimError> {
        self.cubic = loss("cubic damping", c3)?;
        Ok(self)
    }

    /// The dry friction `μ`.
    pub fn friction(&self) -> f64 {
        self.friction
    }
    /// The quadratic drag `d`.
    pub fn drag(&self) -> f64 {
        self.drag
    }
    /// The cubic damping `c₃`.
    pub fn cubic_damping(&self) -> f64 {
        self.cubic
    }

    /// Whether every loss is zero.
    pub fn is_none(&self) -> bool {
        self.friction == 0.0 && self.drag == 0.0 && self.cubic == 0.0
    }

    /// Whether the force is not smooth at `x' = 0` (friction or drag present).
    pub(crate) fn switches_at_rest(&self) -> bool {
        self.friction != 0.0 || self.drag != 0.0
    }

    /// The force `μ sign(v) + d v|v| + c₃ v³`.
    #[inline]
    pub(crate) fn force(&self, v: f64) -> f64 {
        self.friction * sign0(v) + self.drag * v * v.abs() + self.cubic * v * v * v
    }

    /// `∂/∂v` of the force away from `v = 0`: `2 d |v| + 3 c₃ v²`.
    #[inline]
    pub(crate) fn force_slope(&self, v: f64) -> f64 {
        2.0 * self.drag * v.abs() + 3.0 * self.cubic * v * v
    }

    /// The force on a branch, `sign(v)` taken as the branch's sign `s` and `|v|` as `s v`:
    /// `μ s + d s v² + c₃ v³`, smooth in `v`.
    #[inline]
    pub(crate) fn force_on(&self, branch: Branch, v: f64) -> f64 {
        let s = branch.sign();
        self.friction * s + self.drag * s * v * v + self.cubic * v * v * v
    }

    /// `∂/∂v` of [`force_on`](Self::force_on): `2 d s v + 3 c₃ v²`.
    #[inline]
    pub(crate) fn force_slope_on(&self, branch: Branch, v: f64) -> f64 {
        2.0 * self.drag * branch.sign() * v + 3.0 * self.cubic * v * v
    }

    /// The power the losses take out of the motion at velocity `v`: `μ |v| + d |v|³ + c₃ v⁴ ≥ 0`.
    pub fn power(&self, v: f64) -> f64 {
        self.force(v) * v
    }
}

/// One harmonic of the drive: harmonic `k >= 2` of the fundamental, with amplitude ratio `ρ`
/// to it and phase `φ`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "HarmonicRaw", into = "HarmonicRaw")]
pub struct DriveHarmonic {
    k: u32,
    ratio: f64,
    phase: f64,
}

/// The serialised form of [`DriveHarmonic`].
#[derive(Serialize, Deserialize)]
struct HarmonicRaw {
    k: u32,
    ratio: f64,
    #[serde(default)]
    phase: f64,
}

impl TryFrom<HarmonicRaw> for DriveHarmonic {
    type Error = SimError;
    fn try_from(raw: HarmonicRaw) -> Result<Self, SimError> {
        Self::new(raw.k, raw.ratio, raw.phase)
    }
}

impl From<DriveHarmonic> for HarmonicRaw {
    fn from(h: DriveHarmonic) -> Self {
        Self {
            k: h.k,
            ratio: h.ratio,
            phase: h.phase,
        }
    }
}

impl DriveHarmonic {
    /// Harmonic `k` (`2..=`[`DriveHarmonics::MAX_HARMONIC`]) with amplitude ratio `ratio` to the
    /// fundamental (finite, non-negative: a negative amplitude is a phase of π) and phase `phase`
    /// (radians, finite).
    pub fn new(k: u32, ratio: f64, phase: f64) -> Result<Self, SimError> {
        if !(2..=DriveHarmonics::MAX_HARMONIC).contains(&k) {
            return Err(SimError::InvalidParameter {
                name: "drive harmonic",
                value: f64::from(k),
                why: "must lie in 2..=16 (harmonic 1 is the drive itself)",
            });
        }
        if !(ratio.is_finite() && ratio >= 0.0) {
            return Err(SimError::InvalidParameter {
                name: "drive harmonic ratio",
                value: ratio,
                why: "must be finite and non-negative",
            });
        }
        if !phase.is_finite() {
            return Err(SimError::InvalidParameter {
                name: "drive harmonic phase",
                value: phase,
                why: "must be finite",
            });
        }
        Ok(Self {
            k,
            ratio: ratio + 0.0,
            phase,
        })
    }

    /// The harmonic's number `k`.
    pub fn k(&self) -> u32 {
        self.k
    }
    /// Its amplitude ratio to the fundamental.
    pub fn ratio(&self) -> f64 {
        self.ratio
    }
    /// Its phase (radians).
    pub fn phase(&self) -> f64 {
        self.phase
    }
}

/// The harmonics `k = 2..=16` of a drive, each at most once, with an amplitude ratio `ρ_k` to
/// the fundamental and a phase `φ_k` (the pendulum's base acceleration `sin(t)` becomes
/// `sin(t) + Σ ρ_k sin(k t + φ_k)`). A fixed-size table, so that the systems stay `Copy`.
///
/// Deserialised from the list of its harmonics, validated as [`DriveHarmonics::new`] does.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(try_from = "Vec<DriveHarmonic>", into = "Vec<DriveHarmonic>")]
pub struct DriveHarmonics {
    /// `(ρ_k, φ_k)` at index `k − 2`; `ρ_k = 0` for an absent harmonic.
    table: [(f64, f64); TABLE],
    /// Which harmonics were given (a ratio of 0 included).
    given: [bool; TABLE],
    /// One past the index of the highest harmonic present (0 for none): the evaluation loop's end.
    end: usize,
}

const TABLE: usize = DriveHarmonics::MAX_HARMONIC as usize - 1;

impl TryFrom<Vec<DriveHarmonic>> for DriveHarmonics {
    type Error = SimError;
    fn try_from(list: Vec<DriveHarmonic>) -> Result<Self, SimError> {
        Self::new(&list)
    }
}

impl From<DriveHarmonics> for Vec<DriveHarmonic> {
    fn from(h: DriveHarmonics) -> Self {
        h.iter().collect()
    }
}

impl DriveHarmonics {
    /// The highest harmonic a drive may have.
    pub const MAX_HARMONIC: u32 = 16;

    /// A clean sinusoidal drive.
    pub fn none() -> Self {
        Self {
            table: [(0.0, 0.0); TABLE],
            given: [false; TABLE],
            end: 0,
        }
    }

    /// The drive with `harmonics` (each `k` at most once; a ratio of 0 is kept as a harmonic
    /// of zero amplitude, which adds nothing to the equation).
    pub fn new(harmonics: &[DriveHarmonic]) -> Result<Self, SimError> {
        let mut me = Self::none();
        for h in harmonics {
            let i = h.k as usize - 2;
            if me.given[i] {
                return Err(SimError::InvalidParameter {
                    name: "drive harmonic",
                    value: f64::from(h.k),
                    why: "given more than once",
                });
            }
            me.given[i] = true;
            me.table[i] = (h.ratio, h.phase);
        }
        me.end = me.given.iter().rposition(|&p| p).map_or(0, |i| i + 1);
        Ok(me)
    }

    /// The harmonics, by increasing `k`.
    pub fn iter(&self) -> impl Iterator<Item = DriveHarmonic> + '_ {
        (0..self.end).filter(|&i| self.given[i]).map(|i| DriveHarmonic {
            k: i as u32 + 2,
            ratio: self.table[i].0,
            phase: self.table[i].1,
        })
    }

    /// Whether no harmonic was given.
    pub fn is_empty(&self) -> bool {
        self.end == 0
    }

    /// Whether a harmonic is in the table (the evaluation loops have work).
    #[inline]
    pub(crate) fn has_terms(&self) -> bool {
        self.end > 0
    }

    /// Whether the drive has no harmonic of non-zero amplitude.
    pub fn is_none(&self) -> bool {
        self.table[..self.end].iter().all(|&(ratio, _)| ratio == 0.0)
    }

    /// `Σ ρ_k sin(k t + φ_k)`. Never inlined: the right-hand side of a drive without harmonics
    /// stays small enough to be inlined into the integrator's stages, where the sines and cosines
    /// the acceleration and its Jacobian share are computed once.
    #[inline(never)]
    pub(crate) fn sin_sum(&self, t: f64) -> f64 {
        self.table[..self.end]
            .iter()
            .zip(2..)
            .map(|(&(ratio, phase), k)| ratio * (f64::from(k) * t + phase).sin())
            .sum()
    }

    /// `Σ ρ_k cos(k t + φ_k)`, never inlined (see [`sin_sum`](Self::sin_sum)).
    #[inline(never)]
    pub(crate) fn cos_sum(&self, t: f64) -> f64 {
        self.table[..self.end]
            .iter()
            .zip(2..)
            .map(|(&(ratio, phase), k)| ratio * (f64::from(k) * t + phase).cos())
            .sum()
    }
}
