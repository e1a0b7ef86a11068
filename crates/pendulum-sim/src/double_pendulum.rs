//! The base-excited double pendulum, with known truth: [`DoublePendulum`].

use serde::{Deserialize, Serialize};

use crate::equations::{
    NormalisedEquation, Q1_D, Q1_DD, Q1_DD_COS_Q1_MINUS_Q2, Q2_D, Q2_DD, Q2_DD_COS_Q1_MINUS_Q2, SIN_Q1,
    SIN_Q1_MINUS_Q2_Q1_D_SQ, SIN_Q1_MINUS_Q2_Q2_D_SQ, SIN_Q2, SIN_T_COS_Q1, SIN_T_COS_Q2,
};
use crate::error::{SimError, finite, invalid, non_negative, positive};
use crate::machine::DriveHarmonics;
use crate::multi::{MultiSystem, SingularMass, solve2};

/// A double pendulum whose pivot is shaken horizontally, in the non-dimensional time of the
/// paper's pendulum (drive period `2π`):
///
/// ```text
/// θ1'' + μλ θ2'' cos(θ1−θ2) + μλ θ2'² sin(θ1−θ2) + ω² sin θ1 − f sin(t) cos θ1 + c1 θ1' = 0
/// θ2'' + (1/λ) θ1'' cos(θ1−θ2) − (1/λ) θ1'² sin(θ1−θ2) + (ω²/λ) sin θ2 − (f/λ) sin(t) cos θ2 + c2 θ2' = 0
/// ```
///
/// `θ1`, `θ2` are the absolute angles of the links from the downward vertical (coordinates
/// `q1`, `q2`). Two point masses `m1` (at the end of link 1, length `l1`) and `m2` (at the end of
/// link 2, length `l2`), `μ = m2/(m1+m2)`, `λ = l2/l1`; the pivot's horizontal acceleration is
/// `−f sin t` in units of `l1 Ω²` (`Ω` the drive's angular frequency) and `ω² = g/(l1 Ω²)`. From
/// the Lagrangian, divided by `(m1+m2) l1² Ω²`,
///
/// ```text
/// L = ½ θ1'² + ½ μλ² θ2'² + μλ θ1'θ2' cos(θ1−θ2) + ω² cos θ1 + μλ ω² cos θ2
///     + f sin(t) (sin θ1 + μλ sin θ2),
/// ```
///
/// (the last line the potential of the inertial force `m f sin t` in the pivot's frame), the
/// equation of `θ1` is its Euler–Lagrange equation as it stands and that of `θ2` the same divided
/// by `μλ²`: each normalised so that its own acceleration has the coefficient 1, the form the
/// identification fits. The damping is written in that form too: `c1 θ1'` in the first equation,
/// `c2 θ2'` in the second (absolute angular velocities, a drag on each link rather than a damper in
/// each joint). With `μ = 0` link 1 is exactly the paper's pendulum
/// `x'' + c x' + (1/r²) sin x − f sin(t) cos x = 0` with `c = c1`, `1/r² = ω²`, and link 2 a
/// pendulum hanging from it.
///
/// The mass matrix of the two equations, `[[1, μλ cos Δ], [cos(Δ)/λ, 1]]` (`Δ = θ1 − θ2`), has
/// the determinant `1 − μ cos² Δ ≥ 1 − μ`: never singular for `μ < 1`; `μ = 1` (a massless first
/// bob) is allowed and is singular where the links are aligned, which stops a run
/// ([`SingularMass`]).
///
/// Construct with [`DoublePendulum::new`] (validated) or [`DoublePendulum::whirling`];
/// deserialising validates as the constructor does.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "DoublePendulumRaw", into = "DoublePendulumRaw")]
pub struct DoublePendulum {
    mu: f64,
    lambda: f64,
    omega2: f64,
    f: f64,
    c1: f64,
    c2: f64,
    harmonics: DriveHarmonics,
}

/// The serialised form of [`DoublePendulum`].
#[derive(Serialize, Deserialize)]
struct DoublePendulumRaw {
    mu: f64,
    lambda: f64,
    omega2: f64,
    f: f64,
    c1: f64,
    c2: f64,
    #[serde(default, skip_serializing_if = "DriveHarmonics::is_empty")]
    harmonics: DriveHarmonics,
}

impl TryFrom<DoublePendulumRaw> for DoublePendulum {
    type Error = SimError;
    fn try_from(raw: DoublePendulumRaw) -> Result<Self, SimError> {
        Ok(Self::new(raw.mu, raw.lambda, raw.omega2, raw.f, raw.c1, raw.c2)?
            .with_drive_harmonics(raw.harmonics))
    }
}

impl From<DoublePendulum> for DoublePendulumRaw {
    fn from(p: DoublePendulum) -> Self {
        Self {
            mu: p.mu,
            lambda: p.lambda,
            omega2: p.omega2,
            f: p.f,
            c1: p.c1,
            c2: p.c2,
            harmonics: p.harmonics,
        }
    }
}

impl DoublePendulum {
    /// The whirling set `(μ, λ, ω², f, c1, c2) = (0.5, 1, 0.8, 0.6, 0.05, 0.05)`: equal masses
    /// and lengths; both links wind irregularly, with velocities small enough for 64 samples per
    /// drive period (see [`DoublePendulum::whirling`]).
    pub const WHIRLING: (f64, f64, f64, f64, f64, f64) = (0.5, 1.0, 0.8, 0.6, 0.05, 0.05);

    /// Mass ratio `μ = m2/(m1+m2)` in `[0, 1]`, length ratio `λ = l2/l1 > 0`, `ω² = g/(l1 Ω²) ≥ 0`,
    /// base-acceleration amplitude `f` and dampings `c1`, `c2` (finite, either sign).
    pub fn new(mu: f64, lambda: f64, omega2: f64, f: f64, c1: f64, c2: f64) -> Result<Self, SimError> {
        if !(mu.is_finite() && (0.0..=1.0).contains(&mu)) {
            return Err(invalid("mu", mu, "must lie in [0, 1]"));
        }
        Ok(Self {
            mu: mu + 0.0,
            lambda: positive("lambda", lambda)?,
            omega2: non_negative("omega2", omega2)?,
            f: finite("f", f)?,
            c1: finite("c1", c1)?,
            c2: finite("c2", c2)?,
            harmonics: DriveHarmonics::none(),
        })
    }

    /// The same pendulum whose base acceleration has the harmonics `harmonics` of the drive
    /// beside its fundamental: the drive becomes `f (sin t + Σ ρ_k sin(k t + φ_k))`, as a real
    /// shaker's does.
    pub fn with_drive_harmonics(mut self, harmonics: DriveHarmonics) -> Self {
        self.harmonics = harmonics;
        self
    }

    /// The drive's harmonics beyond the fundamental ([`DriveHarmonics::none`] unless
    /// [`with_drive_harmonics`](Self::with_drive_harmonics) gave some).
    pub fn drive_harmonics(&self) -> &DriveHarmonics {
        &self.harmonics
    }

    /// The chaotic whirling double pendulum [`DoublePendulum::WHIRLING`]. From `θ = (2, 0)` at
    /// rest, over 160 drive periods at `rtol = 1e-10` (`cargo run --release -p pendulum-sim
    /// --example multi`), link 1 passes over the top 50 times (net +1.5 turns, its continuous angle
    /// over 54 rad) and link 2 94 times (net +5.5 turns, over 93 rad), in both halves of the run,
    /// with `|θ1'| ≤ 3.2` and `|θ2'| ≤ 4.6`: at 64 samples per period no angle moves more than
    /// 0.45 rad between samples. Over 640 periods, and from rest at `(0.5, −1)` or `(3, 3)`, both
    /// links keep whirling (30–70 and 80–125 passages per 160 periods). A neighbouring set with a
    /// lighter, shorter link 2, `(0.2, 0.5, 0.5, 0.6, 0.05, 0.05)`, whirls too, but its link 2
    /// reaches `|θ2'| ≈ 7` (0.7 rad between samples at 64 per period).
    pub fn whirling() -> Self {
        let (mu, lambda, omega2, f, c1, c2) = Self::WHIRLING;
        Self {
            mu,
            lambda,
            omega2,
            f,
            c1,
            c2,
            harmonics: DriveHarmonics::none(),
        }
    }

    /// The mass ratio `μ`.
    pub fn mu(&self) -> f64 {
        self.mu
    }
    /// The length ratio `λ`.
    pub fn lambda(&self) -> f64 {
        self.lambda
    }
    /// `ω² = g/(l1 Ω²)`.
    pub fn omega2(&self) -> f64 {
        self.omega2
    }
    /// The base-acceleration amplitude `f`.
    pub fn f(&self) -> f64 {
        self.f
    }
    /// The damping `c1` of the first equation.
    pub fn c1(&self) -> f64 {
        self.c1
    }
    /// The damping `c2` of the second equation.
    pub fn c2(&self) -> f64 {
        self.c2
    }

    /// The drive as it enters the equations at time `t`, `f sin t` (plus `f Σ ρ_k sin(k t + φ_k)`
    /// of its [harmonics](Self::drive_harmonics)): the pivot's acceleration is its negative, and
    /// the equation of link `i` holds it as `−f sin(t) cos θi` (divided by `λ` for link 2).
    #[inline]
    pub fn drive(&self, t: f64) -> f64 {
        if self.harmonics.has_terms() {
            self.f * (t.sin() + self.harmonics.sin_sum(t))
        } else {
            self.f * t.sin()
        }
    }

    /// The energy of the undamped, undriven pendulum divided by `(m1+m2) l1² Ω²`, zero hanging at
    /// rest: `E = ½ θ1'² + ½ μλ² θ2'² + μλ θ1'θ2' cos(θ1−θ2) + ω² (1 − cos θ1) + μλ ω² (1 − cos θ2)`.
    /// Conserved when `f = c1 = c2 = 0`.
    pub fn energy(&self, q: &[f64], v: &[f64]) -> f64 {
        let ml = self.mu * self.lambda;
        0.5 * v[0] * v[0]
            + 0.5 * ml * self.lambda * v[1] * v[1]
            + ml * v[0] * v[1] * (q[0] - q[1]).cos()
            + self.omega2 * (1.0 - q[0].cos())
            + ml * self.omega2 * (1.0 - q[1].cos())
    }

    /// The two equations in the identification's form (see [`crate::equations`]): equation 1
    /// `q1'' + μλ q2''*cos(q1-q2) + μλ sin(q1-q2)*q2'^2 + ω² sin(q1) − f sin(t)*cos(q1) + c1 q1'`,
    /// equation 2 `q2'' + (1/λ) q1''*cos(q1-q2) − (1/λ) sin(q1-q2)*q1'^2 + (ω²/λ) sin(q2) −
    /// (f/λ) sin(t)*cos(q2) + c2 q2'`.
    ///
    /// A harmonic `ρ_k sin(k t + φ_k)` of the drive adds `−f ρ_k cos φ_k sin(kt)*cos(qi)` and
    /// `−f ρ_k sin φ_k cos(kt)*cos(qi)` (divided by `λ` for link 2), both written even where one
    /// is 0.
    pub fn normalised_equations(&self) -> Vec<NormalisedEquation> {
        let ml = self.mu * self.lambda;
        let il = 1.0 / self.lambda;
        let mut equations = vec![
            NormalisedEquation {
                acceleration: Q1_DD,
                terms: vec![
                    (Q2_DD_COS_Q1_MINUS_Q2.into(), ml),
                    (SIN_Q1_MINUS_Q2_Q2_D_SQ.into(), ml),
                    (SIN_Q1.into(), self.omega2),
                    (SIN_T_COS_Q1.into(), -self.f),
                    (Q1_D.into(), self.c1),
                ],
            },
            NormalisedEquation {
                acceleration: Q2_DD,
                terms: vec![
                    (Q1_DD_COS_Q1_MINUS_Q2.into(), il),
                    (SIN_Q1_MINUS_Q2_Q1_D_SQ.into(), -il),
                    (SIN_Q2.into(), self.omega2 * il),
                    (SIN_T_COS_Q2.into(), -self.f * il),
                    (Q2_D.into(), self.c2),
                ],
            },
        ];
        for h in self.harmonics.iter() {
            let (k, (sp, cp)) = (h.k(), h.phase().sin_cos());
            for (i, scale) in [(1, 1.0), (2, il)] {
                equations[i - 1].terms.extend([
                    (
                        format!("sin({k}t)*cos(q{i})").into(),
                        -self.f * h.ratio() * cp * scale,
                    ),
                    (
                        format!("cos({k}t)*cos(q{i})").into(),
                        -self.f * h.ratio() * sp * scale,
                    ),
                ]);
            }
        }
        equations
    }
}

impl MultiSystem for DoublePendulum {
    fn coordinates(&self) -> usize {
        2
    }

    #[inline]
    fn accelerations(&self, t: f64, q: &[f64], v: &[f64], acc: &mut [f64]) -> Result<(), SingularMass> {
        let ml = self.mu * self.lambda;
        let il = 1.0 / self.lambda;
        let (sd, cd) = (q[0] - q[1]).sin_cos();
        let (s1, c1) = q[0].sin_cos();
        let (s2, c2) = q[1].sin_cos();
        let drive = self.drive(t);
        let r1 = -ml * sd * v[1] * v[1] - self.omega2 * s1 + drive * c1 - self.c1 * v[0];
        let r2 = il * (sd * v[0] * v[0] - self.omega2 * s2 + drive * c2) - self.c2 * v[1];
        let [a1, a2] = solve2([[1.0, ml * cd], [il * cd, 1.0]], [r1, r2], t)?;
        acc[0] = a1;
        acc[1] = a2;
        Ok(())
    }
}
