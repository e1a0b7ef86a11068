//! A double pendulum driven by joint torques like a robot arm, with known truth:
//! [`TorqueDoublePendulum`] (the DFKI acrobot/pendubot), its [`ArmParameters`] and [`Torque`]s.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::equations::{
    NormalisedEquation, Q1_D, Q1_DD, Q1_DD_COS_Q2, Q2_D, Q2_DD, Q2_DD_COS_Q2, SIGN_Q1_D, SIGN_Q2_D, SIN_Q1,
    SIN_Q1_PLUS_Q2, SIN_Q2_Q1_D_Q2_D, SIN_Q2_Q1_D_SQ, SIN_Q2_Q2_D_SQ, TAU1, TAU2,
};
use crate::error::{SimError, invalid, non_negative, positive};
use crate::machine::sign0;
use crate::multi::{MultiSystem, SingularMass, solve2};
use crate::signal::{MeasuredSignal, Sinusoid};

/// The torque at one joint of a [`TorqueDoublePendulum`], in N m, a function of time in seconds.
///
/// Serialised as `"none"`, `{"sinusoids": […]}` or `"measured"`; a measured torque is the
/// caller's and is never serialised: deserialised, it is missing (NaN, see [`MeasuredSignal`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(from = "TorqueRaw", into = "TorqueRaw")]
pub enum Torque {
    /// No torque: a passive joint.
    None,
    /// `Σ A sin(ω t + φ)`.
    Sinusoids(Vec<Sinusoid>),
    /// A measured torque, e.g. a spline through a record's samples.
    Measured(MeasuredSignal),
}

/// The serialised form of [`Torque`].
#[derive(Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
enum TorqueRaw {
    None,
    Sinusoids(Vec<Sinusoid>),
    Measured,
}

impl From<TorqueRaw> for Torque {
    fn from(raw: TorqueRaw) -> Self {
        match raw {
            TorqueRaw::None => Self::None,
            TorqueRaw::Sinusoids(s) => Self::Sinusoids(s),
            TorqueRaw::Measured => Self::Measured(MeasuredSignal::missing()),
        }
    }
}

impl From<Torque> for TorqueRaw {
    fn from(t: Torque) -> Self {
        match t {
            Torque::None => Self::None,
            Torque::Sinusoids(s) => Self::Sinusoids(s),
            Torque::Measured(_) => Self::Measured,
        }
    }
}

impl Torque {
    /// `amplitude · sin(angular_frequency · t + phase)` (validated as [`Sinusoid::new`]).
    pub fn sinusoid(amplitude: f64, angular_frequency: f64, phase: f64) -> Result<Self, SimError> {
        Ok(Self::Sinusoids(vec![Sinusoid::new(
            amplitude,
            angular_frequency,
            phase,
        )?]))
    }

    /// A measured torque `f(t)`.
    pub fn measured(f: impl Fn(f64) -> f64 + Send + Sync + 'static) -> Self {
        Self::Measured(MeasuredSignal::new(f))
    }

    /// The torque at `t`.
    #[inline]
    pub fn at(&self, t: f64) -> f64 {
        match self {
            Self::None => 0.0,
            Self::Sinusoids(s) => s.iter().map(|s| s.at(t)).sum(),
            Self::Measured(m) => m.at(t),
        }
    }
}

/// The physical parameters of a two-link arm with a motor at each joint, in SI units, as the
/// DFKI double pendulum's model names them (see [`TorqueDoublePendulum`]). Plain data;
/// [`TorqueDoublePendulum::new`] validates them.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ArmParameters {
    /// Mass of link 1 (kg).
    pub m1: f64,
    /// Mass of link 2 (kg).
    pub m2: f64,
    /// Length of link 1 (m), from the shoulder to the elbow.
    pub l1: f64,
    /// Distance of link 1's centre of mass from the shoulder (m).
    pub r1: f64,
    /// Distance of link 2's centre of mass from the elbow (m).
    pub r2: f64,
    /// Inertia of link 1 about the shoulder's axis (kg m²).
    #[serde(rename = "I1")]
    pub i1: f64,
    /// Inertia of link 2 about the elbow's axis (kg m²).
    #[serde(rename = "I2")]
    pub i2: f64,
    /// Inertia of a motor's rotor (kg m²).
    #[serde(rename = "Ir")]
    pub ir: f64,
    /// The motors' gear ratio.
    pub gr: f64,
    /// Gravity (m/s²).
    pub g: f64,
    /// Viscous friction at the shoulder (N m s/rad).
    pub b1: f64,
    /// Viscous friction at the elbow (N m s/rad).
    pub b2: f64,
    /// Dry (Coulomb) friction at the shoulder (N m).
    pub cf1: f64,
    /// Dry (Coulomb) friction at the elbow (N m).
    pub cf2: f64,
}

impl ArmParameters {
    /// The published parameters of DFKI's design A.0 (`model_2.0_parameters.yml`, commit
    /// `a3fad8b` of `dfki-ric-underactuated-lab/double_pendulum`), to the last digit given.
    pub const DFKI_A0: Self = Self {
        m1: 0.5593806151425046,
        m2: 0.6043459469186889,
        l1: 0.3,
        r1: 0.3,
        r2: 0.18377686083653508,
        i1: 0.053470810264216295,
        i2: 0.02392374528789766,
        ir: 7.659297952841183e-05,
        gr: 6.0,
        g: 9.81,
        b1: 0.001,
        b2: 0.001,
        cf1: 0.093,
        cf2: 0.078,
    };
}

/// The physical parameters the arm's equations are linear in, in the published file's names:
/// `Ia = I1 + m2 l1²`, `I2`, `Ir`, `mr1 = m1 r1 + m2 l1`, `mr2 = m2 r2`, `b1`, `cf1`, `b2`, `cf2`
/// (`l1`, `g` and the gear ratio known).
pub const ARM_PARAMETERS: [&str; 9] = ["Ia", "I2", "Ir", "mr1", "mr2", "b1", "cf1", "b2", "cf2"];

/// A term's coefficient in the arm's torque form `A_i q_i'' + Σ a_k g_k − τ_i = 0`: a known
/// number, or a linear combination of [`ARM_PARAMETERS`] (serialised as a number or as an object
/// of a parameter's name to its factor, the form `hbid identify --tie` reads).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum ArmCoefficient {
    /// A known coefficient (a torque's −1).
    Fixed(f64),
    /// `Σ factor · parameter`.
    Linear(BTreeMap<&'static str, f64>),
}

/// The arm's equations with every coefficient written in [`ARM_PARAMETERS`]: the spec of a tied
/// fit (`hbid identify --tie`), written once here beside the equations it ties
/// ([`TorqueDoublePendulum::normalised_equations`] divides each equation by its own
/// acceleration's constant part, `A1 = Ia + I2 + (gr² + 1) Ir`, `A2 = I2 + gr² Ir`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ArmTie {
    /// [`ARM_PARAMETERS`].
    pub parameters: [&'static str; 9],
    /// Per coordinate (`q1`, `q2`), each term's coefficient, the own acceleration's among them.
    pub equations: BTreeMap<&'static str, BTreeMap<&'static str, ArmCoefficient>>,
}

impl ArmTie {
    /// The tie of an arm with link length `l1`, gravity `g` and gear ratio `gr` known, its dry
    /// friction `cf · coulomb · sign(q')` (`coulomb` is 1 for this simulator's `cf · sign(q')`,
    /// π/2 for the published model's `cf · atan(100 q')` beyond a slow speed).
    pub fn new(l1: f64, g: f64, gr: f64, coulomb: f64) -> Self {
        use ArmCoefficient::{Fixed, Linear};
        let lin = |parts: &[(&'static str, f64)]| Linear(parts.iter().copied().collect());
        let q1 = [
            (Q1_DD, lin(&[("Ia", 1.0), ("I2", 1.0), ("Ir", gr * gr + 1.0)])),
            (Q1_DD_COS_Q2, lin(&[("mr2", 2.0 * l1)])),
            (Q2_DD, lin(&[("I2", 1.0), ("Ir", -gr)])),
            (Q2_DD_COS_Q2, lin(&[("mr2", l1)])),
            (SIN_Q2_Q1_D_Q2_D, lin(&[("mr2", -2.0 * l1)])),
            (SIN_Q2_Q2_D_SQ, lin(&[("mr2", -l1)])),
            (SIN_Q1, lin(&[("mr1", g)])),
            (SIN_Q1_PLUS_Q2, lin(&[("mr2", g)])),
            (Q1_D, lin(&[("b1", 1.0)])),
            (SIGN_Q1_D, lin(&[("cf1", coulomb)])),
            (TAU1, Fixed(-1.0)),
        ];
        let q2 = [
            (Q2_DD, lin(&[("I2", 1.0), ("Ir", gr * gr)])),
            (Q1_DD, lin(&[("I2", 1.0), ("Ir", -gr)])),
            (Q1_DD_COS_Q2, lin(&[("mr2", l1)])),
            (SIN_Q2_Q1_D_SQ, lin(&[("mr2", l1)])),
            (SIN_Q1_PLUS_Q2, lin(&[("mr2", g)])),
            (Q2_D, lin(&[("b2", 1.0)])),
            (SIGN_Q2_D, lin(&[("cf2", coulomb)])),
            (TAU2, Fixed(-1.0)),
        ];
        Self {
            parameters: ARM_PARAMETERS,
            equations: [("q1", q1.into_iter().collect()), ("q2", q2.into_iter().collect())]
                .into_iter()
                .collect(),
        }
    }
}

/// A double pendulum driven by joint torques like a robot arm: the DFKI acrobot/pendubot
/// (Wiebe et al., IEEE RAM 31(2), 2024), its model `M(q) q'' + C(q, q') q' − G(q) + F(q') = τ` in
/// seconds, with `q1` the shoulder angle from the hanging position and `q2` the elbow angle
/// relative to link 1:
///
/// ```text
/// M11 = I1 + I2 + m2 l1² + 2 m2 l1 r2 cos q2 + (gr² + 1) Ir
/// M12 = M21 = I2 + m2 l1 r2 cos q2 − gr Ir
/// M22 = I2 + gr² Ir
/// (C q')1 = −m2 l1 r2 sin q2 (2 q1' q2' + q2'²),   (C q')2 = m2 l1 r2 sin q2 q1'²
/// −G1 = (m1 r1 + m2 l1) g sin q1 + m2 r2 g sin(q1 + q2),   −G2 = m2 r2 g sin(q1 + q2)
/// F1 = b1 q1' + cf1 sign(q1'),   F2 = b2 q2' + cf2 sign(q2')
/// ```
///
/// (the rotors' terms as the source writes them). The dry friction is `cf sign(q')`, not the
/// source's `cf atan(100 q')`: the identification's grammar has `sign(q')`, and a coordinate with
/// `cf > 0` sticks and slips by the integrators' rule for dry friction (a joint at rest stays
/// there while the torque that would move it is within its friction).
///
/// Written with `a = m2 l1 r2`, `K1 = I1 + I2 + m2 l1² + (gr² + 1) Ir` and `K2 = I2 + gr² Ir`
/// (the constant parts of each equation's own acceleration coefficient) and each equation divided
/// by its own, the form the identification fits ([`normalised_equations`](Self::normalised_equations)):
///
/// ```text
/// q1'' + (2a/K1) q1''cos q2 + (J/K1) q2'' + (a/K1) q2''cos q2 − (2a/K1) sin q2 q1'q2' − (a/K1) sin q2 q2'²
///      + (g mr1/K1) sin q1 + (g mr2/K1) sin(q1+q2) + (b1/K1) q1' + (cf1/K1) sign(q1') − (1/K1) tau1 = 0
/// q2'' + (J/K2) q1'' + (a/K2) q1''cos q2 + (a/K2) sin q2 q1'² + (g mr2/K2) sin(q1+q2)
///      + (b2/K2) q2' + (cf2/K2) sign(q2') − (1/K2) tau2 = 0
/// ```
///
/// with `J = I2 − gr Ir`, `mr1 = m1 r1 + m2 l1`, `mr2 = m2 r2`.
///
/// The parameters must be physical: masses non-negative, `l1 > 0`, the centres of mass at
/// non-negative distances, each link's inertia about its joint positive and at least that of its
/// mass at its centre of mass (`I1 ≥ m1 r1²`, `I2 ≥ m2 r2²`, the parallel-axis theorem), `Ir ≥ 0`,
/// `gr > 0`, `g ≥ 0`, frictions non-negative. Then `M` is symmetric positive definite at every
/// `q2` (its determinant is at least `I1 I2`), so no run meets a singular mass matrix.
///
/// Construct with [`TorqueDoublePendulum::new`] (validated) or [`TorqueDoublePendulum::dfki`],
/// torques set by [`with_torques`](Self::with_torques) (none by default). Serialised as the
/// [`ArmParameters`] (the published file's names, `I1`, `I2`, `Ir`) with `torque1` and `torque2`
/// (see [`Torque`]); deserialising validates as the constructor does.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "TorqueDoublePendulumRaw", into = "TorqueDoublePendulumRaw")]
pub struct TorqueDoublePendulum {
    parameters: ArmParameters,
    torques: [Torque; 2],
}

/// The serialised form of [`TorqueDoublePendulum`].
#[derive(Serialize, Deserialize)]
struct TorqueDoublePendulumRaw {
    #[serde(flatten)]
    parameters: ArmParameters,
    #[serde(default = "no_torque")]
    torque1: Torque,
    #[serde(default = "no_torque")]
    torque2: Torque,
}

fn no_torque() -> Torque {
    Torque::None
}

impl TryFrom<TorqueDoublePendulumRaw> for TorqueDoublePendulum {
    type Error = SimError;
    fn try_from(raw: TorqueDoublePendulumRaw) -> Result<Self, SimError> {
        Ok(Self::new(raw.parameters)?.with_torques(raw.torque1, raw.torque2))
    }
}

impl From<TorqueDoublePendulum> for TorqueDoublePendulumRaw {
    fn from(p: TorqueDoublePendulum) -> Self {
        let [torque1, torque2] = p.torques;
        Self {
            parameters: p.parameters,
            torque1,
            torque2,
        }
    }
}

impl TorqueDoublePendulum {
    /// The arm with `parameters`, validated (see the type's documentation), with no torques.
    pub fn new(parameters: ArmParameters) -> Result<Self, SimError> {
        let p = parameters;
        let m1 = non_negative("m1", p.m1)?;
        let m2 = non_negative("m2", p.m2)?;
        let l1 = positive("l1", p.l1)?;
        let r1 = non_negative("r1", p.r1)?;
        let r2 = non_negative("r2", p.r2)?;
        let i1 = positive("I1", p.i1)?;
        let i2 = positive("I2", p.i2)?;
        if i1 < m1 * r1 * r1 {
            return Err(invalid(
                "I1",
                i1,
                "must be at least m1 r1² (the inertia about the joint of the mass at its centre)",
            ));
        }
        if i2 < m2 * r2 * r2 {
            return Err(invalid(
                "I2",
                i2,
                "must be at least m2 r2² (the inertia about the joint of the mass at its centre)",
            ));
        }
        let parameters = ArmParameters {
            m1,
            m2,
            l1,
            r1,
            r2,
            i1,
            i2,
            ir: non_negative("Ir", p.ir)?,
            gr: positive("gr", p.gr)?,
            g: non_negative("g", p.g)?,
            b1: non_negative("b1", p.b1)?,
            b2: non_negative("b2", p.b2)?,
            cf1: non_negative("cf1", p.cf1)?,
            cf2: non_negative("cf2", p.cf2)?,
        };
        Ok(Self {
            parameters,
            torques: [Torque::None, Torque::None],
        })
    }

    /// The DFKI design A.0 with its published parameters ([`ArmParameters::DFKI_A0`]) and no
    /// torques.
    pub fn dfki() -> Self {
        Self::new(ArmParameters::DFKI_A0).expect("the published parameters are physical")
    }

    /// The arm with the torques `tau1` at the shoulder and `tau2` at the elbow.
    pub fn with_torques(mut self, tau1: Torque, tau2: Torque) -> Self {
        self.torques = [tau1, tau2];
        self
    }

    /// The parameters.
    pub fn parameters(&self) -> &ArmParameters {
        &self.parameters
    }

    /// The torques at the two joints.
    pub fn torques(&self) -> &[Torque; 2] {
        &self.torques
    }

    /// `(a, K1, K2, J, g mr1, g mr2)`: the combinations of the parameters the equations use.
    #[inline]
    fn combinations(&self) -> (f64, f64, f64, f64, f64, f64) {
        let p = &self.parameters;
        let a = p.m2 * p.l1 * p.r2;
        let k1 = p.i1 + p.i2 + p.m2 * p.l1 * p.l1 + (p.gr * p.gr + 1.0) * p.ir;
        let k2 = p.i2 + p.gr * p.gr * p.ir;
        let j = p.i2 - p.gr * p.ir;
        let gmr1 = p.g * (p.m1 * p.r1 + p.m2 * p.l1);
        let gmr2 = p.g * p.m2 * p.r2;
        (a, k1, k2, j, gmr1, gmr2)
    }

    /// The mass matrix `M(q)` (it depends on the elbow angle `q2` only).
    pub fn mass_matrix(&self, q2: f64) -> [[f64; 2]; 2] {
        let (a, k1, k2, j, ..) = self.combinations();
        let c = q2.cos();
        [[k1 + 2.0 * a * c, j + a * c], [j + a * c, k2]]
    }

    /// The energy `½ q'ᵀ M(q) q' + g mr1 (1 − cos q1) + g mr2 (1 − cos(q1 + q2))` (J, zero hanging
    /// at rest), conserved without friction and torques.
    pub fn energy(&self, q: &[f64], v: &[f64]) -> f64 {
        let (.., gmr1, gmr2) = self.combinations();
        let m = self.mass_matrix(q[1]);
        0.5 * (m[0][0] * v[0] * v[0] + 2.0 * m[0][1] * v[0] * v[1] + m[1][1] * v[1] * v[1])
            + gmr1 * (1.0 - q[0].cos())
            + gmr2 * (1.0 - (q[0] + q[1]).cos())
    }

    /// The two equations in the identification's form (see the type's documentation and
    /// [`crate::equations`]): equation 1 with the terms `q1''*cos(q2)`, `q2''`, `q2''*cos(q2)`,
    /// `sin(q2)*q1'*q2'`, `sin(q2)*q2'^2`, `sin(q1)`, `sin(q1+q2)`, `q1'`, `sign(q1')`, `tau1`;
    /// equation 2 with `q1''`, `q1''*cos(q2)`, `sin(q2)*q1'^2`, `sin(q1+q2)`, `q2'`, `sign(q2')`,
    /// `tau2`.
    pub fn normalised_equations(&self) -> Vec<NormalisedEquation> {
        let (a, k1, k2, j, gmr1, gmr2) = self.combinations();
        let p = &self.parameters;
        vec![
            NormalisedEquation {
                acceleration: Q1_DD,
                terms: vec![
                    (Q1_DD_COS_Q2.into(), 2.0 * a / k1),
                    (Q2_DD.into(), j / k1),
                    (Q2_DD_COS_Q2.into(), a / k1),
                    (SIN_Q2_Q1_D_Q2_D.into(), -2.0 * a / k1),
                    (SIN_Q2_Q2_D_SQ.into(), -a / k1),
                    (SIN_Q1.into(), gmr1 / k1),
                    (SIN_Q1_PLUS_Q2.into(), gmr2 / k1),
                    (Q1_D.into(), p.b1 / k1),
                    (SIGN_Q1_D.into(), p.cf1 / k1),
                    (TAU1.into(), -1.0 / k1),
                ],
            },
            NormalisedEquation {
                acceleration: Q2_DD,
                terms: vec![
                    (Q1_DD.into(), j / k2),
                    (Q1_DD_COS_Q2.into(), a / k2),
                    (SIN_Q2_Q1_D_SQ.into(), a / k2),
                    (SIN_Q1_PLUS_Q2.into(), gmr2 / k2),
                    (Q2_D.into(), p.b2 / k2),
                    (SIGN_Q2_D.into(), p.cf2 / k2),
                    (TAU2.into(), -1.0 / k2),
                ],
            },
        ]
    }

    /// The accelerations with the dry friction's signs `s` (`sign(q')` or held values).
    #[inline]
    fn solve(&self, t: f64, q: &[f64], v: &[f64], s: [f64; 2]) -> Result<[f64; 2], SingularMass> {
        let (a, k1, k2, j, gmr1, gmr2) = self.combinations();
        let p = &self.parameters;
        let (s2, c2) = q[1].sin_cos();
        let s1 = q[0].sin();
        let s12 = (q[0] + q[1]).sin();
        let r1 = self.torques[0].at(t) + a * s2 * (2.0 * v[0] * v[1] + v[1] * v[1])
            - gmr1 * s1
            - gmr2 * s12
            - p.b1 * v[0]
            - p.cf1 * s[0];
        let r2 = self.torques[1].at(t) - a * s2 * v[0] * v[0] - gmr2 * s12 - p.b2 * v[1] - p.cf2 * s[1];
        let m12 = j + a * c2;
        solve2([[k1 + 2.0 * a * c2, m12], [m12, k2]], [r1, r2], t)
    }
}

impl MultiSystem for TorqueDoublePendulum {
    fn coordinates(&self) -> usize {
        2
    }

    fn accelerations(&self, t: f64, q: &[f64], v: &[f64], acc: &mut [f64]) -> Result<(), SingularMass> {
        let [a1, a2] = self.solve(t, q, v, [sign0(v[0]), sign0(v[1])])?;
        acc[0] = a1;
        acc[1] = a2;
        Ok(())
    }

    fn switches_at_rest(&self, c: usize) -> bool {
        match c {
            0 => self.parameters.cf1 != 0.0,
            _ => self.parameters.cf2 != 0.0,
        }
    }

    fn accelerations_with_signs(
        &self,
        t: f64,
        q: &[f64],
        v: &[f64],
        signs: &[f64],
        acc: &mut [f64],
    ) -> Result<(), SingularMass> {
        // A joint without dry friction has no sign term: its entry of `signs` is not used.
        let s = [0, 1].map(|c| if self.switches_at_rest(c) { signs[c] } else { 0.0 });
        let [a1, a2] = self.solve(t, q, v, s)?;
        acc[0] = a1;
        acc[1] = a2;
        Ok(())
    }
}
