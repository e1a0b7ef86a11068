//! The true equations of the systems of several coordinates in the identification's form, and the
//! names of their terms, written here once.
//!
//! Each equation is normalised so that its own acceleration has the coefficient 1 (divided by
//! the constant part of that coefficient, where the mass matrix makes it depend on the state):
//!
//! ```text
//! q_i'' + Σ_k c_k g_k(t, q, q', q'') = 0,
//! ```
//!
//! the terms `g_k` named in the identification's grammar (factors joined by `*`, a drive factor
//! first; the other coordinates' accelerations are terms like any other). A drive on the right
//! of the physical equation (a torque, a base acceleration) stands with a negative coefficient.
//! [`NormalisedEquation`] lists them; the systems give theirs (`normalised_equations`).

use std::borrow::Cow;

use serde::Serialize;

/// One equation `q_i'' + Σ_k c_k g_k = 0`: the name of its own acceleration and its terms with
/// their coefficients (every term of the system's form, a zero coefficient included).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NormalisedEquation {
    /// The acceleration whose coefficient is 1, e.g. `q1''`.
    pub acceleration: &'static str,
    /// `(name, coefficient)` of every other term, in a fixed order (a name written here once, or
    /// made of them, such as a drive harmonic's `sin(2t)*cos(q1)`).
    pub terms: Vec<(Cow<'static, str>, f64)>,
}

impl NormalisedEquation {
    /// The coefficient of the term named `name`, if the equation has it.
    pub fn coefficient(&self, name: &str) -> Option<f64> {
        self.terms.iter().find(|(n, _)| n == name).map(|&(_, c)| c)
    }
}

/// `q1''`.
pub const Q1_DD: &str = "q1''";
/// `q2''`.
pub const Q2_DD: &str = "q2''";
/// `q1'`.
pub const Q1_D: &str = "q1'";
/// `q2'`.
pub const Q2_D: &str = "q2'";
/// `q1''*cos(q2)` (a torque-driven arm: `q2` is the elbow angle).
pub const Q1_DD_COS_Q2: &str = "q1''*cos(q2)";
/// `q2''*cos(q2)`.
pub const Q2_DD_COS_Q2: &str = "q2''*cos(q2)";
/// `sin(q2)*q1'*q2'`.
pub const SIN_Q2_Q1_D_Q2_D: &str = "sin(q2)*q1'*q2'";
/// `sin(q2)*q2'^2`.
pub const SIN_Q2_Q2_D_SQ: &str = "sin(q2)*q2'^2";
/// `sin(q2)*q1'^2`.
pub const SIN_Q2_Q1_D_SQ: &str = "sin(q2)*q1'^2";
/// `sin(q1)`.
pub const SIN_Q1: &str = "sin(q1)";
/// `sin(q2)`.
pub const SIN_Q2: &str = "sin(q2)";
/// `sin(q1+q2)`.
pub const SIN_Q1_PLUS_Q2: &str = "sin(q1+q2)";
/// `sign(q1')` (dry friction; `sign(0) = 0`).
pub const SIGN_Q1_D: &str = "sign(q1')";
/// `sign(q2')`.
pub const SIGN_Q2_D: &str = "sign(q2')";
/// `tau1`, the torque at joint 1.
pub const TAU1: &str = "tau1";
/// `tau2`, the torque at joint 2.
pub const TAU2: &str = "tau2";
/// `q1''*cos(q1-q2)` (a base-excited double pendulum: absolute angles).
pub const Q1_DD_COS_Q1_MINUS_Q2: &str = "q1''*cos(q1-q2)";
/// `q2''*cos(q1-q2)`.
pub const Q2_DD_COS_Q1_MINUS_Q2: &str = "q2''*cos(q1-q2)";
/// `sin(q1-q2)*q1'^2`.
pub const SIN_Q1_MINUS_Q2_Q1_D_SQ: &str = "sin(q1-q2)*q1'^2";
/// `sin(q1-q2)*q2'^2`.
pub const SIN_Q1_MINUS_Q2_Q2_D_SQ: &str = "sin(q1-q2)*q2'^2";
/// `sin(t)*cos(q1)`: the base's acceleration `−f sin(t)` acting on link 1.
pub const SIN_T_COS_Q1: &str = "sin(t)*cos(q1)";
/// `sin(t)*cos(q2)`.
pub const SIN_T_COS_Q2: &str = "sin(t)*cos(q2)";
/// `x1''` (two masses on a line).
pub const X1_DD: &str = "x1''";
/// `x2''`.
pub const X2_DD: &str = "x2''";
/// `x1'`.
pub const X1_D: &str = "x1'";
/// `x2'`.
pub const X2_D: &str = "x2'";
/// `x1`.
pub const X1: &str = "x1";
/// `x2`.
pub const X2: &str = "x2";
/// `x1^3`.
pub const X1_CUBED: &str = "x1^3";
/// `x2^3`.
pub const X2_CUBED: &str = "x2^3";
/// `(x1-x2)^3`, the cubic part of the coupling spring.
pub const X1_MINUS_X2_CUBED: &str = "(x1-x2)^3";
/// `p`, the measured drive (a base acceleration).
pub const P: &str = "p";
