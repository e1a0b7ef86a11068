//! Two Duffing oscillators on a line, coupled by a spring and shaken by a measured base
//! acceleration: [`CoupledDuffing`].

use serde::{Deserialize, Serialize};

use crate::equations::{
    NormalisedEquation, P, X1, X1_CUBED, X1_D, X1_DD, X1_MINUS_X2_CUBED, X2, X2_CUBED, X2_D, X2_DD,
};
use crate::error::SimError;
use crate::multi::{MultiSystem, SingularMass};
use crate::signal::{MeasuredSignal, SyntheticDrive};

/// The acceleration of the base of a [`CoupledDuffing`], a function of time: built in
/// ([`SyntheticDrive`]) or measured.
///
/// Serialised as `{"synthetic": {…}}` or `"measured"`; a measured one is the caller's and is never
/// serialised: deserialised, it is missing (NaN, see [`MeasuredSignal`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(from = "BaseAccelerationRaw", into = "BaseAccelerationRaw")]
pub enum BaseAcceleration {
    /// Sinusoids at incommensurate frequencies plus seeded band-limited noise.
    Synthetic(SyntheticDrive),
    /// A measured series, e.g. a spline through a record's samples.
    Measured(MeasuredSignal),
}

/// The serialised form of [`BaseAcceleration`].
#[derive(Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
enum BaseAccelerationRaw {
    Synthetic(SyntheticDrive),
    Measured,
}

impl From<BaseAccelerationRaw> for BaseAcceleration {
    fn from(raw: BaseAccelerationRaw) -> Self {
        match raw {
            BaseAccelerationRaw::Synthetic(d) => Self::Synthetic(d),
            BaseAccelerationRaw::Measured => Self::Measured(MeasuredSignal::missing()),
        }
    }
}

impl From<BaseAcceleration> for BaseAccelerationRaw {
    fn from(b: BaseAcceleration) -> Self {
        match b {
            BaseAcceleration::Synthetic(d) => Self::Synthetic(d),
            BaseAcceleration::Measured(_) => Self::Measured,
        }
    }
}

impl BaseAcceleration {
    /// A measured base acceleration `f(t)`.
    pub fn measured(f: impl Fn(f64) -> f64 + Send + Sync + 'static) -> Self {
        Self::Measured(MeasuredSignal::new(f))
    }

    /// The base acceleration at `t`.
    #[inline]
    pub fn at(&self, t: f64) -> f64 {
        match self {
            Self::Synthetic(d) => d.at(t),
            Self::Measured(m) => m.at(t),
        }
    }
}

/// Two masses on a line, each a Duffing oscillator tied to a moving base, coupled by a spring
/// with a cubic part, their displacements `x1`, `x2` relative to the base:
///
/// ```text
/// x1'' + c1 x1' + a1 x1 + b1 x1³ + k (x1 − x2) + k3 (x1 − x2)³ + p(t) = 0
/// x2'' + c2 x2' + a2 x2 + b2 x2³ − (k/ρ)(x1 − x2) − (k3/ρ)(x1 − x2)³ + p(t) = 0
/// ```
///
/// `p(t)` is the base's acceleration (each mass feels the inertial force `−m p` in the base's
/// frame), `ρ = m2/m1` the mass ratio (the spring pulls both masses with one force, so its
/// coefficient per unit mass is `k` in the first equation and `k/ρ` in the second), and the
/// oscillators' coefficients `c_i`, `a_i`, `b_i` are per unit mass of their own. With `a < 0 < b`
/// each oscillator has two wells. No inertial coupling: each equation's own acceleration has the
/// coefficient 1 and the mass matrix is the identity.
///
/// In the identification's form ([`normalised_equations`](Self::normalised_equations)) the
/// coupling spreads over the linear terms: equation 1 has `x1'` (`c1`), `x1` (`a1 + k`), `x2`
/// (`−k`), `x1^3` (`b1`), `(x1-x2)^3` (`k3`) and `p` (1); equation 2 has `x2'` (`c2`), `x2`
/// (`a2 + k/ρ`), `x1` (`−k/ρ`), `x2^3` (`b2`), `(x1-x2)^3` (`−k3/ρ`) and `p` (1).
///
/// Construct with [`CoupledDuffing::new`] (validated) or [`CoupledDuffing::two_wells`];
/// deserialising validates as the constructors do.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "CoupledDuffingRaw", into = "CoupledDuffingRaw")]
pub struct CoupledDuffing {
    c: [f64; 2],
    a: [f64; 2],
    b: [f64; 2],
    k: f64,
    k3: f64,
    mass_ratio: f64,
    drive: BaseAcceleration,
}

/// The serialised form of [`CoupledDuffing`].
#[derive(Serialize, Deserialize)]
struct CoupledDuffingRaw {
    c: [f64; 2],
    a: [f64; 2],
    b: [f64; 2],
    k: f64,
    #[serde(default)]
    k3: f64,
    #[serde(default = "equal_masses")]
    mass_ratio: f64,
    drive: BaseAcceleration,
}

fn equal_masses() -> f64 {
    1.0
}

impl TryFrom<CoupledDuffingRaw> for CoupledDuffing {
    type Error = SimError;
    fn try_from(raw: CoupledDuffingRaw) -> Result<Self, SimError> {
        Self::new(raw.c, raw.a, raw.b, raw.k, raw.k3, raw.drive)?.with_mass_ratio(raw.mass_ratio)
    }
}

impl From<CoupledDuffing> for CoupledDuffingRaw {
    fn from(d: CoupledDuffing) -> Self {
        Self {
            c: d.c,
            a: d.a,
            b: d.b,
            k: d.k,
            k3: d.k3,
            mass_ratio: d.mass_ratio,
            drive: d.drive,
        }
    }
}

impl CoupledDuffing {
    /// The two-well set: `c = (0.25, 0.2)`, `a = (−1, −0.8)`, `b = (1, 1.2)`, `k = 0.3`,
    /// `k3 = 0.05`, equal masses, shaken by [`SyntheticDrive::incommensurate`] with seed 1. See
    /// [`CoupledDuffing::two_wells`].
    pub const TWO_WELLS: ([f64; 2], [f64; 2], [f64; 2], f64, f64) =
        ([0.25, 0.2], [-1.0, -0.8], [1.0, 1.2], 0.3, 0.05);

    /// Dampings `c`, linear stiffnesses `a`, cubic stiffnesses `b` (one of each per oscillator),
    /// the coupling `k` and its cubic part `k3`, every one finite (either sign), equal masses, and
    /// the base acceleration `drive`.
    pub fn new(
        c: [f64; 2],
        a: [f64; 2],
        b: [f64; 2],
        k: f64,
        k3: f64,
        drive: BaseAcceleration,
    ) -> Result<Self, SimError> {
        let named = [
            ("c1", c[0]),
            ("c2", c[1]),
            ("a1", a[0]),
            ("a2", a[1]),
            ("b1", b[0]),
            ("b2", b[1]),
            ("k", k),
            ("k3", k3),
        ];
        for (name, value) in named {
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
            k,
            k3,
            mass_ratio: 1.0,
            drive,
        })
    }

    /// [`CoupledDuffing::TWO_WELLS`]: two two-well oscillators, not alike, coupled weakly and shaken
    /// by [`SyntheticDrive::incommensurate`]`(1)` (rms 0.25). From rest at `x = (1, −0.9)` over
    /// `t ≤ 1000` at `rtol = 1e-10` (`cargo run --release -p pendulum-sim --example multi`), `x1`
    /// crosses between its wells 96 times and `x2` 169 times, with `|x| ≤ 1.56` and `|x'| ≤ 1.27`.
    pub fn two_wells() -> Self {
        let (c, a, b, k, k3) = Self::TWO_WELLS;
        Self::new(
            c,
            a,
            b,
            k,
            k3,
            BaseAcceleration::Synthetic(SyntheticDrive::incommensurate(1)),
        )
        .expect("the built-in set is valid")
    }

    /// The mass ratio `ρ = m2/m1` (positive, finite; 1 unless set).
    pub fn with_mass_ratio(mut self, mass_ratio: f64) -> Result<Self, SimError> {
        if !(mass_ratio.is_finite() && mass_ratio > 0.0) {
            return Err(SimError::InvalidParameter {
                name: "mass ratio",
                value: mass_ratio,
                why: "must be positive and finite",
            });
        }
        self.mass_ratio = mass_ratio;
        Ok(self)
    }

    /// The system shaken by `drive` instead.
    pub fn with_drive(mut self, drive: BaseAcceleration) -> Self {
        self.drive = drive;
        self
    }

    /// The dampings `(c1, c2)`.
    pub fn c(&self) -> [f64; 2] {
        self.c
    }
    /// The linear stiffnesses `(a1, a2)`.
    pub fn a(&self) -> [f64; 2] {
        self.a
    }
    /// The cubic stiffnesses `(b1, b2)`.
    pub fn b(&self) -> [f64; 2] {
        self.b
    }
    /// The coupling `k`.
    pub fn k(&self) -> f64 {
        self.k
    }
    /// The coupling's cubic part `k3`.
    pub fn k3(&self) -> f64 {
        self.k3
    }
    /// The mass ratio `ρ = m2/m1`.
    pub fn mass_ratio(&self) -> f64 {
        self.mass_ratio
    }
    /// The base acceleration.
    pub fn drive(&self) -> &BaseAcceleration {
        &self.drive
    }

    /// The energy per unit mass of mass 1, `½ x1'² + ½ ρ x2'² + a1 x1²/2 + b1 x1⁴/4 + ρ (a2 x2²/2 +
    /// b2 x2⁴/4) + k (x1 − x2)²/2 + k3 (x1 − x2)⁴/4`, conserved without damping and drive.
    pub fn energy(&self, x: &[f64], v: &[f64]) -> f64 {
        let rho = self.mass_ratio;
        let d = x[0] - x[1];
        let well = |i: usize| 0.5 * self.a[i] * x[i] * x[i] + 0.25 * self.b[i] * x[i].powi(4);
        0.5 * v[0] * v[0]
            + 0.5 * rho * v[1] * v[1]
            + well(0)
            + rho * well(1)
            + 0.5 * self.k * d * d
            + 0.25 * self.k3 * d.powi(4)
    }

    /// The two equations in the identification's form (see the type's documentation and
    /// [`crate::equations`]).
    pub fn normalised_equations(&self) -> Vec<NormalisedEquation> {
        let rho = self.mass_ratio;
        vec![
            NormalisedEquation {
                acceleration: X1_DD,
                terms: vec![
                    (X1_D.into(), self.c[0]),
                    (X1.into(), self.a[0] + self.k),
                    (X2.into(), -self.k),
                    (X1_CUBED.into(), self.b[0]),
                    (X1_MINUS_X2_CUBED.into(), self.k3),
                    (P.into(), 1.0),
                ],
            },
            NormalisedEquation {
                acceleration: X2_DD,
                terms: vec![
                    (X2_D.into(), self.c[1]),
                    (X2.into(), self.a[1] + self.k / rho),
                    (X1.into(), -self.k / rho),
                    (X2_CUBED.into(), self.b[1]),
                    (X1_MINUS_X2_CUBED.into(), -self.k3 / rho),
                    (P.into(), 1.0),
                ],
            },
        ]
    }
}

impl MultiSystem for CoupledDuffing {
    fn coordinates(&self) -> usize {
        2
    }

    #[inline]
    fn accelerations(&self, t: f64, x: &[f64], v: &[f64], acc: &mut [f64]) -> Result<(), SingularMass> {
        let p = self.drive.at(t);
        let d = x[0] - x[1];
        let spring = self.k * d + self.k3 * d * d * d;
        acc[0] = -self.c[0] * v[0] - self.a[0] * x[0] - self.b[0] * x[0] * x[0] * x[0] - spring - p;
        acc[1] = -self.c[1] * v[1] - self.a[1] * x[1] - self.b[1] * x[1] * x[1] * x[1]
            + spring / self.mass_ratio
            - p;
        Ok(())
    }
}
