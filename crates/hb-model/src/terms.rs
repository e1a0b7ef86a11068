//! The vocabulary of the model's terms, the lists of terms users write, and the column layout of
//! every system defined once.
//!
//! An equation of a system of `n` coordinates `q_1 … q_n` is `q_i'' + Σ_k c_k g_k = 0`, one per
//! coordinate `i` (its *own* coordinate); a record of one coordinate is the case `n = 1`, its
//! coordinate written `x`. Each term `g_k` is a product of
//!
//! - a drive factor: `1`, `cos(kt)`, `sin(kt)` for harmonic `k` of the drive (`t` standing for the
//!   drive's phase `W t`), or a measured drive (`p` for the one drive of a one-coordinate record,
//!   otherwise the drive's column by name), a signal recorded beside the state;
//! - a function of the own coordinate (`1`, a basis function: `cos(kx)`, `sin(kx)`, `x^n`, `hatN`);
//! - a function of the own velocity (`1`, `x'`, `x'^2`, `sign(x')`, `x'*|x'|`, `x'^3`);
//! - and, with several coordinates, factors in the others ([`Coupling`]): `cos` or `sin` of a
//!   whole combination of angles (`cos(theta1-theta2)`, `sin(q1+q2)`, `sin(theta1)` in the
//!   equation of `theta2`), powers of positions on the line (`x2`, `x1^2`), functions of other
//!   velocities (`theta2'`, `theta2'^2`, `sign(q2')`), and one acceleration times functions of the
//!   positions (`theta2''*cos(theta1-theta2)`, or the own one with a function of the state,
//!   `q1''*cos(q2)`: a mass matrix that depends on the state).
//!
//! A term is named by its factors joined by `*`: an acceleration first, then the drive factor, the
//! functions of the positions in the order of the coordinates, then the velocities in that order:
//! `x'`, `cos(t)*sin(x)`, `sin(2t)*cos(x)`, `x^2*x'`, `p*cos(x)`, `theta2''*cos(theta1-theta2)`,
//! `sin(q2)*q1'*q2'`.
//!
//! A measured drive is data, not a function of time: its samples come with the record's, and a
//! term that holds it is balanced from them by the weak form.
//!
//! Two forms of a term: [`Term`] names its function of the own coordinate by its index in a basis
//! (what the assemblies and the model evaluate); [`TermSpec`] names it by itself ([`XFunction`]:
//! `cos(2x)`, `x^3`, `hat3`), so that a list of terms ([`TermList`]) can be written, parsed, saved
//! and read without a basis, and resolved against one ([`TermList::resolve`]). A list is written
//! in the [`Names`] of a record (its coordinates and drives) for the equation of one coordinate;
//! [`TermList::parse`] uses those of a one-coordinate record (`x`, and `p`).
//!
//! # The grammar of a term list ([`TermList::parse`], [`TermList::parse_in`])
//!
//! ```text
//! list    := item (',' item)*
//! item    := factor ('*' factor)*           a product; braces multiply out
//! factor  := atom | '{' item (',' item)* '}'
//! atom    := '1'
//!          | 'cos(' [n] 't)' | 'sin(' [n] 't)'                   drive harmonic n >= 1
//!          | DRIVE                                               a measured drive (p, or its name)
//!          | 'cos(' combo ')' | 'sin(' combo ')'                 of a whole combination of angles
//!          | Q ['^' n] | 'hat' i                                 a position's power, a hat (own)
//!          | Q "'" ['^' n] | "sign(" Q "')" | "|" Q "'|"         a velocity: Q', Q'^2, Q'^3, sign, |Q'|
//!          | Q "''"                                              an acceleration
//! combo   := [n] Q (('+' | '-') [n] Q)*                          e.g. 2x, theta1-theta2, q1+q2
//! ```
//!
//! `Q` is a coordinate's name (`x` for one coordinate). White space is ignored. A product holds
//! at most one drive factor, one function of each coordinate alone, one of each combination, one
//! acceleration, and its factors in a velocity must make one of `Q'`, `Q'^2`, `sign(Q')`,
//! `Q'*|Q'|` (in either order) or `Q'^3`. Powers of one position multiply (`x*x` is `x^2`). An
//! acceleration multiplies functions of the positions only, and the own one alone is not a term
//! (it is the equation's normalisation). `cos` of a combination whose first coefficient is
//! negative is written with the signs turned (`cos(q2-q1)` is `cos(q1-q2)`); `sin` of one is
//! refused (it is `−sin` of the turned one). `{1,cos(t),sin(t)}*{cos(x),sin(x)}` is the six
//! products `cos(x)`, `sin(x)`, `cos(t)*cos(x)`, `cos(t)*sin(x)`, `sin(t)*cos(x)`,
//! `sin(t)*sin(x)`, in this order (the leftmost set varies slowest). Every term may appear once.
//! Printing a list ([`fmt::Display`]) and parsing it again gives the same list.
//!
//! [`columns`](crate::columns) gives the unknowns of a [`ModelForm`](crate::ModelForm) on a basis,
//! in the order every assembly, solver, bootstrap and saved model uses.

use std::fmt;
use std::str::FromStr;
use std::sync::Arc;

use hb_basis::{Basis, BasisKind, Domain, Harmonic, Hat, Polynomial};
use serde::{Deserialize, Serialize};

use crate::error::TermError;

/// The highest drive harmonic a term may name.
pub const MAX_DRIVE_HARMONIC: u32 = 64;

/// The most terms a list may hold (braces multiply quickly).
pub const MAX_TERMS: usize = 4096;

/// The most coordinates (equations) a system may have.
pub const MAX_COORDINATES: usize = 8;

/// The most measured drives a record may carry.
pub const MAX_DRIVES: usize = 16;

/// The most factors in other coordinates (and accelerations) one term may have.
pub const MAX_COUPLING: usize = 4;

/// The largest whole coefficient of a coordinate in a combination of angles, and the largest
/// power of a position or harmonic of an angle a factor in another coordinate may have.
pub const MAX_COUPLING_ORDER: u32 = 64;

/// The drive factor of a term: `1`, `cos(k t)` or `sin(k t)` for harmonic `k >= 1` of the drive,
/// or a measured drive.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DriveFactor {
    /// No drive factor.
    One,
    /// `cos(k t)`.
    Cos(u32),
    /// `sin(k t)`.
    Sin(u32),
    /// A measured drive `p(t)` (the drive of this index among the record's), a signal recorded
    /// with the state (a shaker's base acceleration, a motor's torque), used as it was measured
    /// instead of a function of the drive's phase.
    Measured(u8),
}

impl DriveFactor {
    /// `p`, the one measured drive of a one-coordinate record (drive 0).
    pub const MEASURED: Self = Self::Measured(0);

    /// The harmonic `k` of the drive (0 for [`DriveFactor::One`] and [`DriveFactor::Measured`],
    /// which are no function of the drive's phase).
    pub fn harmonic(&self) -> u32 {
        match *self {
            Self::One | Self::Measured(_) => 0,
            Self::Cos(k) | Self::Sin(k) => k,
        }
    }

    /// Whether the factor is a measured drive.
    pub fn is_measured(&self) -> bool {
        matches!(self, Self::Measured(_))
    }

    /// The index of the measured drive, if the factor is one.
    pub fn measured_index(&self) -> Option<usize> {
        match *self {
            Self::Measured(d) => Some(usize::from(d)),
            _ => None,
        }
    }

    /// Whether the factor is a function of the drive's phase (`cos(kt)`, `sin(kt)`), so that a
    /// term holding it needs the drive's period and phase.
    pub fn needs_phase(&self) -> bool {
        matches!(self, Self::Cos(_) | Self::Sin(_))
    }

    /// The factor at the drive's phase `θ = W t` with the measured drive at the same instant:
    /// `1`, `cos(kθ)`, `sin(kθ)` or the drive's value (each factor reads only what it depends
    /// on).
    pub fn eval(&self, phase: f64, measured: f64) -> f64 {
        match *self {
            Self::One => 1.0,
            Self::Cos(k) => (f64::from(k) * phase).cos(),
            Self::Sin(k) => (f64::from(k) * phase).sin(),
            Self::Measured(_) => measured,
        }
    }
}

/// The factor in the own coordinate `x` of a term.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PositionFactor {
    /// No function of `x`.
    One,
    /// Function `i` of the basis.
    Basis(usize),
    /// `x` itself, a linear stiffness beside the basis (on the line only); named `k*x`.
    Linear,
}

/// A function of a velocity `v` (the own `x'`, or another coordinate's).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum VelocityFactor {
    /// No function of `x'`.
    One,
    /// `x'` (viscous damping).
    Linear,
    /// `sign(x')` (dry, Coulomb friction; `sign(0) = 0`).
    Sign,
    /// `x'*|x'|` (quadratic drag).
    Quadratic,
    /// `x'^3`.
    Cubic,
    /// `x'^2` (a centrifugal or Coriolis force: even in the velocity).
    Square,
}

impl VelocityFactor {
    /// The factor at velocity `v`.
    #[inline]
    pub fn eval(&self, v: f64) -> f64 {
        match self {
            Self::One => 1.0,
            Self::Linear => v,
            Self::Sign => {
                if v > 0.0 {
                    1.0
                } else if v < 0.0 {
                    -1.0
                } else {
                    // 0 at 0, NaN for NaN.
                    v * 0.0
                }
            }
            Self::Quadratic => v * v.abs(),
            Self::Cubic => v * v * v,
            Self::Square => v * v,
        }
    }

    /// Its derivative in `v`: `0`, `1`, `0` (away from `v = 0`), `2|v|`, `3v²`, `2v`.
    #[inline]
    pub fn eval_deriv(&self, v: f64) -> f64 {
        match self {
            Self::One | Self::Sign => 0.0,
            Self::Linear => 1.0,
            Self::Quadratic => 2.0 * v.abs(),
            Self::Cubic => 3.0 * v * v,
            Self::Square => 2.0 * v,
        }
    }

    /// The factor on one side of `x' = 0` (`side` = 1 or −1, see `circle_signal::system::Branch`):
    /// `sign(x')` is `side` and `x'*|x'|` is `side · x'²`, smooth in `v` across 0; the others as
    /// [`eval`](Self::eval). `None`: [`eval`](Self::eval).
    #[inline]
    pub fn eval_on(&self, side: Option<f64>, v: f64) -> f64 {
        match (self, side) {
            (Self::Sign, Some(s)) => s,
            (Self::Quadratic, Some(s)) => s * v * v,
            _ => self.eval(v),
        }
    }

    /// The derivative in `v` of [`eval_on`](Self::eval_on).
    #[inline]
    pub fn eval_deriv_on(&self, side: Option<f64>, v: f64) -> f64 {
        match (self, side) {
            (Self::Quadratic, Some(s)) => 2.0 * s * v,
            _ => self.eval_deriv(v),
        }
    }

    /// Whether the factor is not smooth at `x' = 0` (`sign(x')`, `x'*|x'|`).
    pub fn switches(&self) -> bool {
        matches!(self, Self::Sign | Self::Quadratic)
    }

    /// Whether the factor is linear in `x'` (`x'` itself), so that a term holding it is the time
    /// derivative of an antiderivative of the rest.
    pub fn is_linear(&self) -> bool {
        *self == Self::Linear
    }

    /// The factor's name for the own coordinate `x`, `None` for [`VelocityFactor::One`].
    pub fn name(&self) -> Option<&'static str> {
        match self {
            Self::One => None,
            Self::Linear => Some("x'"),
            Self::Sign => Some("sign(x')"),
            Self::Quadratic => Some("x'*|x'|"),
            Self::Cubic => Some("x'^3"),
            Self::Square => Some("x'^2"),
        }
    }

    /// The factor's name for the velocity of the coordinate named `q`.
    fn write_for(&self, f: &mut fmt::Formatter<'_>, q: &str) -> fmt::Result {
        match self {
            Self::One => f.write_str("1"),
            Self::Linear => write!(f, "{q}'"),
            Self::Sign => write!(f, "sign({q}')"),
            Self::Quadratic => write!(f, "{q}'*|{q}'|"),
            Self::Cubic => write!(f, "{q}'^3"),
            Self::Square => write!(f, "{q}'^2"),
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Names.

/// The names a list of terms is written in: the coordinates that have equations, in order, and
/// the measured drives, in order. Names are identifiers (a letter or `_`, then letters, digits,
/// `_`), distinct, none of the grammar's own words (`t`, `cos`, `sin`, `sign`, `hatN`).
///
/// The default is a one-coordinate record's: the coordinate `x` and the drive `p`.
///
/// ```
/// use hb_model::Names;
///
/// let names = Names::new(["theta1", "theta2"], ["tau1"])?;
/// assert_eq!(names.coordinate("theta2"), Some(1));
/// assert_eq!(names.drive("tau1"), Some(0));
/// assert!(Names::new(["t"], Vec::<String>::new()).is_err());
/// assert!(Names::new(["q", "q"], Vec::<String>::new()).is_err());
/// # Ok::<(), hb_model::TermError>(())
/// ```
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Names {
    coordinates: Arc<[String]>,
    drives: Arc<[String]>,
}

impl Default for Names {
    fn default() -> Self {
        ONE_COORDINATE.clone()
    }
}

/// A one-coordinate record's names, made once.
static ONE_COORDINATE: std::sync::LazyLock<Names> = std::sync::LazyLock::new(|| Names {
    coordinates: Arc::from(vec!["x".to_owned()]),
    drives: Arc::from(vec!["p".to_owned()]),
});

/// Whether `name` is one of the grammar's own words.
fn reserved(name: &str) -> bool {
    matches!(name, "t" | "cos" | "sin" | "sign")
        || name
            .strip_prefix("hat")
            .is_some_and(|rest| rest.is_empty() || rest.chars().all(|c| c.is_ascii_digit()))
}

/// Whether `name` is an identifier of the grammar.
fn identifier(name: &str) -> bool {
    let mut chars = name.chars();
    chars.next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

impl Names {
    /// The names of `coordinates` (1 to [`MAX_COORDINATES`]) and `drives` (at most
    /// [`MAX_DRIVES`]), checked: identifiers, distinct across both lists, none a word of the
    /// grammar.
    pub fn new<C, D>(coordinates: C, drives: D) -> Result<Self, TermError>
    where
        C: IntoIterator,
        C::Item: Into<String>,
        D: IntoIterator,
        D::Item: Into<String>,
    {
        let coordinates: Vec<String> = coordinates.into_iter().map(Into::into).collect();
        let drives: Vec<String> = drives.into_iter().map(Into::into).collect();
        if coordinates.is_empty() || coordinates.len() > MAX_COORDINATES {
            return Err(TermError::BadName {
                name: coordinates.join(","),
                why: "a system has 1 to 8 coordinates",
            });
        }
        if drives.len() > MAX_DRIVES {
            return Err(TermError::BadName {
                name: drives.join(","),
                why: "a record has at most 16 measured drives",
            });
        }
        for (i, name) in coordinates.iter().chain(&drives).enumerate() {
            let why = if !identifier(name) {
                Some("a name is a letter or _ followed by letters, digits or _ (it is written in terms)")
            } else if reserved(name) {
                Some("t, cos, sin, sign and hatN are words of the term grammar")
            } else if coordinates.iter().chain(&drives).take(i).any(|n| n == name) {
                Some("named twice (a column is a coordinate or a drive, once)")
            } else {
                None
            };
            if let Some(why) = why {
                return Err(TermError::BadName {
                    name: name.clone(),
                    why,
                });
            }
        }
        Ok(Self {
            coordinates: Arc::from(coordinates),
            drives: Arc::from(drives),
        })
    }

    /// The coordinates' names, in order.
    pub fn coordinates(&self) -> &[String] {
        &self.coordinates
    }

    /// The measured drives' names, in order.
    pub fn drives(&self) -> &[String] {
        &self.drives
    }

    /// The index of the coordinate named `name`.
    pub fn coordinate(&self, name: &str) -> Option<usize> {
        self.coordinates.iter().position(|n| n == name)
    }

    /// The index of the drive named `name`.
    pub fn drive(&self, name: &str) -> Option<usize> {
        self.drives.iter().position(|n| n == name)
    }

    /// Whether these are a one-coordinate record's names (`x`, and `p` or no drive): the
    /// spelling of every list before several coordinates.
    pub fn is_default(&self) -> bool {
        self.coordinates.len() == 1
            && self.coordinates[0] == "x"
            && (self.drives.is_empty() || (self.drives.len() == 1 && self.drives[0] == "p"))
    }

    fn coordinate_name(&self, c: usize) -> &str {
        self.coordinates.get(c).map_or("?", String::as_str)
    }

    fn drive_name(&self, d: usize) -> &str {
        self.drives.get(d).map_or("?", String::as_str)
    }
}

// ---------------------------------------------------------------------------------------------
// Factors in other coordinates.

/// A whole combination `Σ a_c q_c` of the coordinates (an angle on the circle when they all are):
/// the argument of `cos(theta1-theta2)`, `sin(q1+q2)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Combination([i8; MAX_COORDINATES]);

impl Combination {
    /// The combination with these coefficients (coordinate `c` has `coefficients[c]`, the rest
    /// 0); `None` when every coefficient is 0, one is out of `±MAX_COUPLING_ORDER` or there are
    /// too many.
    pub fn new(coefficients: &[i32]) -> Option<Self> {
        if coefficients.len() > MAX_COORDINATES || coefficients.iter().all(|&a| a == 0) {
            return None;
        }
        let mut out = [0i8; MAX_COORDINATES];
        for (slot, &a) in out.iter_mut().zip(coefficients) {
            if a.unsigned_abs() > MAX_COUPLING_ORDER {
                return None;
            }
            *slot = a as i8;
        }
        Some(Self(out))
    }

    /// The coefficient of coordinate `c`.
    pub fn coefficient(&self, c: usize) -> i32 {
        self.0.get(c).map_or(0, |&a| i32::from(a))
    }

    /// The coordinates with a non-zero coefficient and their coefficients.
    pub fn terms(&self) -> impl Iterator<Item = (usize, i32)> + '_ {
        self.0
            .iter()
            .enumerate()
            .filter(|(_, a)| **a != 0)
            .map(|(c, &a)| (c, i32::from(a)))
    }

    /// `Σ a_c q_c`.
    #[inline]
    pub fn eval(&self, q: &[f64]) -> f64 {
        self.terms().map(|(c, a)| f64::from(a) * q[c]).sum()
    }

    /// The single coordinate and coefficient of a combination of one coordinate.
    fn single(&self) -> Option<(usize, i32)> {
        let mut terms = self.terms();
        match (terms.next(), terms.next()) {
            (Some(one), None) => Some(one),
            _ => None,
        }
    }

    /// Whether the first non-zero coefficient is negative.
    fn leads_negative(&self) -> bool {
        self.terms().next().is_some_and(|(_, a)| a < 0)
    }

    fn negated(&self) -> Self {
        Self(self.0.map(|a| -a))
    }

    fn first(&self) -> usize {
        self.terms().next().map_or(0, |(c, _)| c)
    }

    fn write(&self, f: &mut fmt::Formatter<'_>, names: &Names) -> fmt::Result {
        for (i, (c, a)) in self.terms().enumerate() {
            let name = names.coordinate_name(c);
            match (i, a) {
                (0, 1) => f.write_str(name)?,
                (0, -1) => write!(f, "-{name}")?,
                (0, a) => write!(f, "{a}{name}")?,
                (_, 1) => write!(f, "+{name}")?,
                (_, -1) => write!(f, "-{name}")?,
                (_, a) if a > 0 => write!(f, "+{a}{name}")?,
                (_, a) => write!(f, "-{}{name}", -a)?,
            }
        }
        Ok(())
    }
}

/// A factor of a term in coordinates other than the equation's own (or in several, or an
/// acceleration).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Factor {
    /// `cos` (`sine == false`) or `sin` of a combination of angles.
    Trig {
        /// Whether the function is the sine.
        sine: bool,
        /// The argument.
        combination: Combination,
    },
    /// `q_c^n` of a position on the line.
    Power {
        /// The coordinate.
        coordinate: u8,
        /// The power, at least 1.
        power: u8,
    },
    /// A function of the velocity `q_c'`.
    Velocity {
        /// The coordinate.
        coordinate: u8,
        /// The function (never [`VelocityFactor::One`]).
        function: VelocityFactor,
    },
    /// The acceleration `q_c''`.
    Acceleration {
        /// The coordinate.
        coordinate: u8,
    },
}

impl Factor {
    /// Where the factor goes in a name: accelerations, positions by their first coordinate, then
    /// velocities by coordinate.
    fn order_key(&self) -> (u8, usize, u8, Combination, bool, u8) {
        match *self {
            Factor::Acceleration { coordinate } => (0, usize::from(coordinate), 0, ZERO, false, 0),
            Factor::Power { coordinate, power } => (1, usize::from(coordinate), 0, ZERO, false, power),
            Factor::Trig { sine, combination } => {
                let width = combination.terms().count() as u8;
                (1, combination.first(), width, combination, sine, 0)
            }
            Factor::Velocity { coordinate, function } => {
                (2, usize::from(coordinate), 0, ZERO, false, function as u8)
            }
        }
    }

    /// Whether the factor depends on the velocities.
    pub fn has_velocity(&self) -> bool {
        matches!(self, Factor::Velocity { .. })
    }

    /// The factor's value at positions `q` (on the circle, any branch) and velocities `v`
    /// (accelerations are 1: the caller multiplies by them).
    #[inline]
    pub fn eval(&self, q: &[f64], v: &[f64]) -> f64 {
        match *self {
            Factor::Trig { sine, combination } => {
                let a = combination.eval(q);
                if sine { a.sin() } else { a.cos() }
            }
            Factor::Power { coordinate, power } => q[usize::from(coordinate)].powi(i32::from(power)),
            Factor::Velocity { coordinate, function } => function.eval(v[usize::from(coordinate)]),
            Factor::Acceleration { .. } => 1.0,
        }
    }

    /// The factor's partial derivative in the position of coordinate `c` (0 for a velocity or
    /// an acceleration).
    #[inline]
    pub fn eval_dq(&self, q: &[f64], c: usize) -> f64 {
        match *self {
            Factor::Trig { sine, combination } => {
                let a = f64::from(combination.coefficient(c));
                if a == 0.0 {
                    return 0.0;
                }
                let arg = combination.eval(q);
                if sine { a * arg.cos() } else { -a * arg.sin() }
            }
            Factor::Power { coordinate, power } if usize::from(coordinate) == c => {
                f64::from(power) * q[c].powi(i32::from(power) - 1)
            }
            _ => 0.0,
        }
    }

    fn write(&self, f: &mut fmt::Formatter<'_>, names: &Names) -> fmt::Result {
        match *self {
            Factor::Trig { sine, combination } => {
                f.write_str(if sine { "sin(" } else { "cos(" })?;
                combination.write(f, names)?;
                f.write_str(")")
            }
            Factor::Power { coordinate, power } => {
                let q = names.coordinate_name(usize::from(coordinate));
                if power == 1 {
                    f.write_str(q)
                } else {
                    write!(f, "{q}^{power}")
                }
            }
            Factor::Velocity { coordinate, function } => {
                function.write_for(f, names.coordinate_name(usize::from(coordinate)))
            }
            Factor::Acceleration { coordinate } => {
                write!(f, "{}''", names.coordinate_name(usize::from(coordinate)))
            }
        }
    }
}

const ZERO: Combination = Combination([0; MAX_COORDINATES]);

/// The factors of a term in other coordinates than the equation's own, and its acceleration, if
/// any: empty for every term of a one-coordinate record. Kept in the order of a name, so that
/// equal products compare equal.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Coupling {
    factors: [Option<Factor>; MAX_COUPLING],
}

impl Coupling {
    /// No factor in another coordinate.
    pub const NONE: Self = Self {
        factors: [None; MAX_COUPLING],
    };

    /// The coupling of `factors` (at most [`MAX_COUPLING`]), in the order of a name.
    pub fn new(mut factors: Vec<Factor>) -> Option<Self> {
        if factors.len() > MAX_COUPLING {
            return None;
        }
        factors.sort_by_key(Factor::order_key);
        let mut out = Self::NONE;
        for (slot, f) in out.factors.iter_mut().zip(factors) {
            *slot = Some(f);
        }
        Some(out)
    }

    /// The factors, in the order of a name.
    pub fn factors(&self) -> impl Iterator<Item = &Factor> + '_ {
        self.factors.iter().flatten()
    }

    /// Whether the term has no factor in another coordinate (nor an acceleration).
    pub fn is_empty(&self) -> bool {
        self.factors[0].is_none()
    }

    /// The coordinate whose acceleration the term holds, if any.
    pub fn acceleration(&self) -> Option<usize> {
        self.factors().find_map(|f| match *f {
            Factor::Acceleration { coordinate } => Some(usize::from(coordinate)),
            _ => None,
        })
    }

    /// Whether a factor depends on a velocity.
    pub fn has_velocity(&self) -> bool {
        self.factors().any(Factor::has_velocity)
    }

    /// Whether a factor switches at rest (`sign(q')`, `q'*|q'|` of another coordinate).
    pub fn switches(&self) -> bool {
        self.factors()
            .any(|f| matches!(f, Factor::Velocity { function, .. } if function.switches()))
    }

    /// The product of the factors at `(q, v)` (an acceleration counts 1).
    #[inline]
    pub fn eval(&self, q: &[f64], v: &[f64]) -> f64 {
        self.factors().map(|f| f.eval(q, v)).product()
    }

    /// Every coordinate a factor reads (positions, velocities or the acceleration).
    pub fn coordinates(&self) -> Vec<usize> {
        let mut out: Vec<usize> = Vec::new();
        for f in self.factors() {
            match *f {
                Factor::Trig { combination, .. } => out.extend(combination.terms().map(|(c, _)| c)),
                Factor::Power { coordinate, .. }
                | Factor::Velocity { coordinate, .. }
                | Factor::Acceleration { coordinate } => out.push(usize::from(coordinate)),
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    }
}

// ---------------------------------------------------------------------------------------------
// Terms.

/// One term of the model: the product of a drive factor, a function of the own coordinate `x`,
/// a function of its velocity `x'`, and factors in the other coordinates ([`Coupling`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Term {
    /// The drive factor.
    pub drive: DriveFactor,
    /// The function of `x`.
    pub position: PositionFactor,
    /// The function of `x'`.
    pub velocity: VelocityFactor,
    /// The factors in other coordinates and the acceleration ([`Coupling::NONE`] for a term of
    /// one coordinate).
    pub coupling: Coupling,
}

impl Term {
    /// `x'`, the linear damping.
    pub const DAMPING: Self = Self {
        drive: DriveFactor::One,
        position: PositionFactor::One,
        velocity: VelocityFactor::Linear,
        coupling: Coupling::NONE,
    };

    /// The drive factor alone (`cos(kt)` or `sin(kt)`, an external forcing).
    pub const fn drive(drive: DriveFactor) -> Self {
        Self {
            drive,
            position: PositionFactor::One,
            velocity: VelocityFactor::One,
            coupling: Coupling::NONE,
        }
    }

    /// Basis function `i` times a drive factor (`One` for the autonomous term).
    pub const fn basis(drive: DriveFactor, i: usize) -> Self {
        Self {
            drive,
            position: PositionFactor::Basis(i),
            velocity: VelocityFactor::One,
            coupling: Coupling::NONE,
        }
    }

    /// The term's name with the basis functions' `names`, e.g. `cos(t)*sin(x)`, in a
    /// one-coordinate record's names.
    pub fn name(&self, names: &[String]) -> String {
        self.display(names).to_string()
    }

    /// The term shown with the basis functions' `names`.
    pub fn display<'a>(&'a self, names: &'a [String]) -> impl fmt::Display + 'a {
        TermName { term: self, names }
    }
}

struct TermName<'a> {
    term: &'a Term,
    names: &'a [String],
}

impl fmt::Display for TermName<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let owned;
        let position: Option<&dyn fmt::Display> = match self.term.position {
            PositionFactor::One => None,
            PositionFactor::Basis(i) => {
                owned = self.names.get(i).cloned().unwrap_or_else(|| format!("phi{i}(x)"));
                Some(&owned)
            }
            PositionFactor::Linear => Some(&"k*x"),
        };
        let parts = Parts {
            drive: self.term.drive,
            own: position,
            velocity: self.term.velocity,
            coupling: &self.term.coupling,
            names: &ONE_COORDINATE,
            own_index: 0,
        };
        parts.write(f)
    }
}

/// The factors of a term as they are written.
struct Parts<'a> {
    drive: DriveFactor,
    own: Option<&'a dyn fmt::Display>,
    velocity: VelocityFactor,
    coupling: &'a Coupling,
    names: &'a Names,
    own_index: usize,
}

impl Parts<'_> {
    /// Writes the name: the acceleration, the drive factor, the positions in the order of the
    /// coordinates (the own function among them), then the velocities (the own one among them);
    /// `1` for the empty product.
    fn write(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut first = true;
        let mut sep = |f: &mut fmt::Formatter<'_>| -> fmt::Result {
            if !std::mem::take(&mut first) {
                f.write_str("*")?;
            }
            Ok(())
        };
        let factors: Vec<&Factor> = self.coupling.factors().collect();
        for factor in factors
            .iter()
            .filter(|g| matches!(g, Factor::Acceleration { .. }))
        {
            sep(f)?;
            factor.write(f, self.names)?;
        }
        match self.drive {
            DriveFactor::One => {}
            DriveFactor::Measured(d) => {
                sep(f)?;
                f.write_str(self.names.drive_name(usize::from(d)))?;
            }
            DriveFactor::Cos(k) | DriveFactor::Sin(k) => {
                sep(f)?;
                let trig = if matches!(self.drive, DriveFactor::Cos(_)) {
                    "cos"
                } else {
                    "sin"
                };
                if k == 1 {
                    write!(f, "{trig}(t)")?;
                } else {
                    write!(f, "{trig}({k}t)")?;
                }
            }
        }
        // Positions: those of coordinates before the own one, the own function, the rest.
        let positions: Vec<&&Factor> = factors
            .iter()
            .filter(|g| matches!(g, Factor::Trig { .. } | Factor::Power { .. }))
            .collect();
        let position_first = |g: &Factor| match *g {
            Factor::Trig { combination, .. } => combination.first(),
            Factor::Power { coordinate, .. } => usize::from(coordinate),
            _ => usize::MAX,
        };
        let mut own_written = self.own.is_none();
        for g in &positions {
            if !own_written && position_first(g) >= self.own_index {
                sep(f)?;
                write!(f, "{}", self.own.expect("not written yet"))?;
                own_written = true;
            }
            sep(f)?;
            g.write(f, self.names)?;
        }
        if !own_written {
            sep(f)?;
            write!(f, "{}", self.own.expect("not written yet"))?;
        }
        // Velocities likewise.
        let mut own_written = self.velocity == VelocityFactor::One;
        for g in factors.iter().filter(|g| g.has_velocity()) {
            let Factor::Velocity { coordinate, .. } = **g else {
                continue;
            };
            if !own_written && usize::from(coordinate) >= self.own_index {
                sep(f)?;
                self.velocity
                    .write_for(f, self.names.coordinate_name(self.own_index))?;
                own_written = true;
            }
            sep(f)?;
            g.write(f, self.names)?;
        }
        if !own_written {
            sep(f)?;
            self.velocity
                .write_for(f, self.names.coordinate_name(self.own_index))?;
        }
        if first {
            f.write_str("1")?;
        }
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------------
// Terms named without a basis.

/// A function of the own coordinate `x` named by itself, as the bases of `hb-basis` name theirs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum XFunction {
    /// `cos(kx)`, `k >= 1` (the harmonic basis of order `K >= k`).
    Cos(u32),
    /// `sin(kx)`, `k >= 1`.
    Sin(u32),
    /// `x^n`, `n >= 1` (the polynomial basis of degree `D >= n`, on the line).
    Power(u32),
    /// `hat i`, the hat of node `i` (a hat basis of more than `i` nodes).
    Hat(u32),
}

impl XFunction {
    /// The domain the function belongs to: the circle for `cos`, `sin` and hats, the line for
    /// powers of `x`.
    pub fn domain(&self) -> Domain {
        match self {
            Self::Power(_) => Domain::Line,
            _ => Domain::Circle,
        }
    }

    /// The smallest basis of `hb-basis` that holds the function.
    pub fn smallest_basis(&self) -> Result<BasisKind, TermError> {
        let n = |v: u32| v as usize;
        Ok(match *self {
            Self::Cos(k) | Self::Sin(k) => Harmonic::new(n(k))?.into(),
            Self::Power(d) => Polynomial::new(n(d))?.into(),
            Self::Hat(i) => Hat::new((n(i) + 1).max(3))?.into(),
        })
    }

    /// The function shown with the own coordinate named `q`.
    pub fn display_for<'a>(&'a self, q: &'a str) -> impl fmt::Display + 'a {
        XName { function: self, q }
    }
}

struct XName<'a> {
    function: &'a XFunction,
    q: &'a str,
}

impl fmt::Display for XName<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let q = self.q;
        match *self.function {
            XFunction::Cos(1) => write!(f, "cos({q})"),
            XFunction::Sin(1) => write!(f, "sin({q})"),
            XFunction::Cos(k) => write!(f, "cos({k}{q})"),
            XFunction::Sin(k) => write!(f, "sin({k}{q})"),
            XFunction::Power(1) => f.write_str(q),
            XFunction::Power(n) => write!(f, "{q}^{n}"),
            XFunction::Hat(i) => write!(f, "hat{i}"),
        }
    }
}

impl fmt::Display for XFunction {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.display_for("x"))
    }
}

/// A term with its function of the own coordinate named by itself (`sin(2t)*cos(x)`,
/// `x^2*x'`), independent of any basis; [`TermList::resolve`] turns it into a [`Term`] of a
/// basis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TermSpec {
    /// The drive factor.
    pub drive: DriveFactor,
    /// The function of the own coordinate, if any.
    pub function: Option<XFunction>,
    /// The function of the own velocity.
    pub velocity: VelocityFactor,
    /// The factors in other coordinates and the acceleration ([`Coupling::NONE`] for a term of
    /// one coordinate).
    pub coupling: Coupling,
}

impl TermSpec {
    /// A term of one coordinate: a drive factor, a function of `x` and one of `x'`.
    pub const fn of_one(drive: DriveFactor, function: Option<XFunction>, velocity: VelocityFactor) -> Self {
        Self {
            drive,
            function,
            velocity,
            coupling: Coupling::NONE,
        }
    }

    /// The term's name in `names`, for the equation of coordinate `own`.
    pub fn display_in<'a>(&'a self, names: &'a Names, own: usize) -> impl fmt::Display + 'a {
        SpecName {
            spec: self,
            names,
            own,
        }
    }

    /// Whether the term has a factor in another coordinate or an acceleration.
    pub fn is_coupled(&self) -> bool {
        !self.coupling.is_empty()
    }
}

struct SpecName<'a> {
    spec: &'a TermSpec,
    names: &'a Names,
    own: usize,
}

impl fmt::Display for SpecName<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let q = self.names.coordinate_name(self.own);
        let function = self.spec.function.map(|x| x.display_for(q).to_string());
        let own = function.as_ref().map(|s| s as &dyn fmt::Display);
        Parts {
            drive: self.spec.drive,
            own,
            velocity: self.spec.velocity,
            coupling: &self.spec.coupling,
            names: self.names,
            own_index: self.own,
        }
        .write(f)
    }
}

impl fmt::Display for TermSpec {
    /// The name in a one-coordinate record's names (`x`, `p`).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.display_in(&ONE_COORDINATE, 0))
    }
}

impl FromStr for TermSpec {
    type Err = TermError;

    /// One term (a product without braces or commas) in a one-coordinate record's names, e.g.
    /// `cos(t)*sin(x)`.
    fn from_str(text: &str) -> Result<Self, TermError> {
        let list = TermList::parse(text)?;
        match list.terms() {
            [one] => Ok(*one),
            _ => Err(TermError::TermSyntax {
                spec: text.to_owned(),
                at: text.chars().count() + 1,
                found: format!("{} terms", list.len()),
                expected: "one term".into(),
            }),
        }
    }
}

/// An ordered list of distinct terms named without a basis, as a user writes it, in the
/// [`Names`] of a record for the equation of one of its coordinates: what
/// [`ModelForm::from_terms`](crate::ModelForm::from_terms) takes. See the module documentation
/// for the grammar of [`TermList::parse`].
///
/// ```
/// use hb_model::{Names, TermList};
///
/// let terms = TermList::parse("x', sign(x'), x'*|x'|, {1,cos(t),sin(t),cos(2t),sin(2t)}*{cos(x),sin(x)}")?;
/// assert_eq!(terms.len(), 13);
/// assert_eq!(terms.names()[3..6], ["cos(x)", "sin(x)", "cos(t)*cos(x)"]);
/// // The smallest basis that holds every function of x named.
/// assert_eq!(terms.smallest_basis()?.unwrap().to_string(), "harmonic (K = 1)");
/// // Printing and parsing again is the identity.
/// assert_eq!(TermList::parse(&terms.to_string())?, terms);
/// // Errors say where.
/// let e = TermList::parse("x', cos(t)*foo").unwrap_err();
/// assert!(e.to_string().contains("character 12"), "{e}");
///
/// // A double pendulum's first equation, in the names of its record.
/// let names = Names::new(["theta1", "theta2"], Vec::<String>::new())?;
/// let first = TermList::parse_in(
///     "theta2''*cos(theta1-theta2), sin(theta1-theta2)*theta2'^2, sin(theta1), sin(t)*cos(theta1), theta1'",
///     &names,
///     0,
/// )?;
/// assert_eq!(first.names()[1], "sin(theta1-theta2)*theta2'^2");
/// assert_eq!(first.terms()[0].coupling.acceleration(), Some(1));
/// # Ok::<(), hb_model::TermError>(())
/// ```
#[derive(Debug, Clone, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(try_from = "Vec<String>", into = "Vec<String>")]
pub struct TermList {
    terms: Vec<TermSpec>,
    names: Names,
    own: usize,
}

impl TermList {
    /// Parses a list of terms in a one-coordinate record's names (`x`, `p`; grammar in the
    /// module documentation).
    ///
    /// Errors: [`TermError::TermSyntax`] and [`TermError::TermProduct`] with the position (a
    /// 1-based character index into `spec`), [`TermError::DuplicateTerm`],
    /// [`TermError::TooManyTerms`], and [`TermError::DriveHarmonicOutOfRange`] for a drive
    /// harmonic above [`MAX_DRIVE_HARMONIC`].
    pub fn parse(spec: &str) -> Result<Self, TermError> {
        Self::parse_in(spec, &Names::default(), 0)
    }

    /// Parses a list of terms for the equation of coordinate `own` of a record with `names`.
    ///
    /// Errors: those of [`TermList::parse`], and [`TermError::BadName`] for an `own` that is not
    /// a coordinate.
    pub fn parse_in(spec: &str, names: &Names, own: usize) -> Result<Self, TermError> {
        check_own(names, own)?;
        if spec.trim().is_empty() {
            return Err(TermError::TermSyntax {
                spec: spec.to_owned(),
                at: 1,
                found: "no term".to_owned(),
                expected: "at least one term: an equation without terms has nothing to fit".into(),
            });
        }
        let products = Parser::new(spec, names).list()?;
        let mut terms: Vec<TermSpec> = Vec::with_capacity(products.len());
        for product in products {
            let term = product.term(spec, own)?;
            if terms.contains(&term) {
                return Err(TermError::DuplicateTerm {
                    term: term.display_in(names, own).to_string(),
                    at: product.at,
                });
            }
            terms.push(term);
        }
        Self::new_in(terms, names.clone(), own)
    }

    /// A list of `terms` of one coordinate (see [`TermList::new_in`]).
    pub fn new(terms: Vec<TermSpec>) -> Result<Self, TermError> {
        Self::new_in(terms, Names::default(), 0)
    }

    /// A list of `terms` for the equation of coordinate `own` of a record with `names`: at
    /// least one, at most [`MAX_TERMS`], none twice, drive harmonics at most
    /// [`MAX_DRIVE_HARMONIC`], every number in a name at least 1 (`x^0`, `cos(0t)` are not
    /// terms), every coordinate and drive named, and no term the own acceleration alone.
    pub fn new_in(terms: Vec<TermSpec>, names: Names, own: usize) -> Result<Self, TermError> {
        check_own(&names, own)?;
        if terms.is_empty() {
            return Err(TermError::TermSyntax {
                spec: String::new(),
                at: 1,
                found: "nothing".to_owned(),
                expected: "at least one term".into(),
            });
        }
        if terms.len() > MAX_TERMS {
            return Err(TermError::TooManyTerms {
                count: terms.len(),
                max: MAX_TERMS,
            });
        }
        let n = names.coordinates().len();
        for (i, t) in terms.iter().enumerate() {
            let k = t.drive.harmonic();
            if k > MAX_DRIVE_HARMONIC || (k == 0 && t.drive.needs_phase()) {
                return Err(TermError::DriveHarmonicOutOfRange { harmonic: k });
            }
            let named = t.display_in(&names, own).to_string();
            if let Some(XFunction::Cos(0) | XFunction::Sin(0) | XFunction::Power(0)) = t.function {
                return Err(TermError::TermSyntax {
                    spec: named,
                    at: 1,
                    found: "0".to_owned(),
                    expected: "a whole number at least 1".into(),
                });
            }
            if let Some(d) = t.drive.measured_index()
                && d >= names.drives().len()
            {
                return Err(TermError::UnknownName {
                    term: named,
                    what: "measured drive",
                });
            }
            let unknown_coordinate = t.coupling.coordinates().iter().any(|&c| c >= n);
            if unknown_coordinate {
                return Err(TermError::UnknownName {
                    term: named,
                    what: "coordinate",
                });
            }
            if let Some(why) = coupling_problem(t, own) {
                return Err(TermError::InvalidTerm { term: named, why });
            }
            if terms[..i].contains(t) {
                return Err(TermError::DuplicateTerm {
                    term: named,
                    at: i + 1,
                });
            }
        }
        Ok(Self { terms, names, own })
    }

    /// The terms, in order.
    pub fn terms(&self) -> &[TermSpec] {
        &self.terms
    }

    /// The names the list is written in.
    pub fn names_in(&self) -> &Names {
        &self.names
    }

    /// The coordinate whose equation the list is for.
    pub fn own(&self) -> usize {
        self.own
    }

    /// Number of terms.
    pub fn len(&self) -> usize {
        self.terms.len()
    }

    /// Never true: a list has at least one term.
    pub fn is_empty(&self) -> bool {
        self.terms.is_empty()
    }

    /// The name of term `i`.
    pub fn name(&self, i: usize) -> String {
        self.terms[i].display_in(&self.names, self.own).to_string()
    }

    /// The terms' names, in order.
    pub fn names(&self) -> Vec<String> {
        (0..self.terms.len()).map(|i| self.name(i)).collect()
    }

    /// The highest drive harmonic named (0 when no term has a drive factor of the drive's phase).
    pub fn drive_harmonics(&self) -> u32 {
        self.terms.iter().map(|t| t.drive.harmonic()).max().unwrap_or(0)
    }

    /// Whether a term has a measured drive as its drive factor.
    pub fn has_measured_drive(&self) -> bool {
        self.measured_term().is_some()
    }

    /// The first term whose drive factor is a measured drive, if any.
    pub fn measured_term(&self) -> Option<String> {
        self.terms
            .iter()
            .position(|t| t.drive.is_measured())
            .map(|i| self.name(i))
    }

    /// The measured drives the terms name, by index, in increasing order.
    pub fn measured_drives(&self) -> Vec<usize> {
        let mut out: Vec<usize> = self
            .terms
            .iter()
            .filter_map(|t| t.drive.measured_index())
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }

    /// The first term whose drive factor is a function of the drive's phase (`cos(kt)`,
    /// `sin(kt)`), if any: such a term needs the drive's period and phase.
    pub fn phase_term(&self) -> Option<String> {
        self.terms
            .iter()
            .position(|t| t.drive.needs_phase())
            .map(|i| self.name(i))
    }

    /// Whether a term reads another coordinate or an acceleration.
    pub fn is_coupled(&self) -> bool {
        self.terms.iter().any(TermSpec::is_coupled)
    }

    /// The same terms read in other `names` for the equation of `own` (names of the same
    /// coordinates and drives, in the same order), checked as [`TermList::new_in`] checks.
    pub fn with_names(&self, names: Names, own: usize) -> Result<Self, TermError> {
        Self::new_in(self.terms.clone(), names, own)
    }

    /// The smallest basis of `hb-basis` that holds every function of the own coordinate named:
    /// `harmonic:K` for `cos(kx)`, `sin(kx)` up to `k = K`, `poly:D` for powers up to `x^D`,
    /// `hat:N` for hats up to `hat{N−1}` (at least 3); `None` when no term names a function of
    /// it.
    ///
    /// Errors: [`TermError::MixedBases`] when the functions come from two kinds of basis.
    pub fn smallest_basis(&self) -> Result<Option<BasisKind>, TermError> {
        let mut best: Option<(XFunction, BasisKind)> = None;
        for f in self.terms.iter().filter_map(|t| t.function) {
            let basis = f.smallest_basis()?;
            best = Some(match best {
                None => (f, basis),
                Some((g, current)) => {
                    let larger = match (current, basis) {
                        (BasisKind::Harmonic(a), BasisKind::Harmonic(b)) => {
                            (b.order() > a.order()).then_some(basis)
                        }
                        (BasisKind::Polynomial(a), BasisKind::Polynomial(b)) => {
                            (b.degree() > a.degree()).then_some(basis)
                        }
                        (BasisKind::Hat(a), BasisKind::Hat(b)) => (b.nodes() > a.nodes()).then_some(basis),
                        _ => {
                            return Err(TermError::MixedBases {
                                first: g.to_string(),
                                second: f.to_string(),
                            });
                        }
                    };
                    match larger {
                        Some(b) => (f, b),
                        None => (g, current),
                    }
                }
            });
        }
        Ok(best.map(|(_, b)| b))
    }

    /// Checks that every function of the own coordinate named lives on `domain` (`x^3` is not a
    /// function of an angle; `cos(x)` and hats are not functions on the line).
    pub fn check_domain(&self, domain: Domain) -> Result<(), TermError> {
        match self
            .terms
            .iter()
            .position(|t| t.function.is_some_and(|f| f.domain() != domain))
        {
            Some(i) => Err(TermError::TermNotAllowed {
                term: self.name(i),
                domain,
                why: match domain {
                    Domain::Circle => {
                        "x is an angle known modulo 2π: functions of it are cos(kx), sin(kx) or hats"
                    }
                    Domain::Line => {
                        "cos(kx), sin(kx) and hats are functions of an angle; on the line use powers of x"
                    }
                },
            }),
            None => Ok(()),
        }
    }

    /// Checks every function of a position against the coordinates' `domains` (one per
    /// coordinate of the names): the own one's as [`check_domain`](Self::check_domain), and a
    /// `cos`/`sin` of a combination only of angles, a power only of positions on the line.
    pub fn check_domains(&self, domains: &[Domain]) -> Result<(), TermError> {
        if let Some(&own) = domains.get(self.own) {
            self.check_domain(own)?;
        }
        for (i, t) in self.terms.iter().enumerate() {
            for factor in t.coupling.factors() {
                let bad = match *factor {
                    Factor::Trig { combination, .. } => combination
                        .terms()
                        .find(|&(c, _)| domains.get(c) == Some(&Domain::Line))
                        .map(|(c, _)| (c, Domain::Line)),
                    Factor::Power { coordinate, .. } => {
                        let c = usize::from(coordinate);
                        (domains.get(c) == Some(&Domain::Circle)).then_some((c, Domain::Circle))
                    }
                    _ => None,
                };
                if let Some((_, domain)) = bad {
                    return Err(TermError::TermNotAllowed {
                        term: self.name(i),
                        domain,
                        why: match domain {
                            Domain::Circle => "an angle is known modulo 2π: functions of it are cos and sin",
                            Domain::Line => "cos and sin are functions of angles; on the line use powers",
                        },
                    });
                }
            }
        }
        Ok(())
    }

    /// The terms on `basis` (a basis of the own coordinate): each function of it found by its
    /// name among the basis' functions; the factors in other coordinates kept.
    ///
    /// Errors: [`TermError::TermNotAllowed`] for a function of another domain than the basis',
    /// [`TermError::TermNotInBasis`] for a function the basis lacks.
    pub fn resolve<B: Basis + ?Sized>(&self, basis: &B) -> Result<Vec<Term>, TermError> {
        self.check_domain(basis.domain())?;
        let names = basis.names();
        self.terms
            .iter()
            .enumerate()
            .map(|(i, t)| {
                let position = match t.function {
                    None => PositionFactor::One,
                    Some(f) => {
                        let name = f.to_string();
                        let j = names.iter().position(|n| *n == name).ok_or_else(|| {
                            TermError::TermNotInBasis {
                                term: self.name(i),
                                function: f.display_for(self.names.coordinate_name(self.own)).to_string(),
                                basis: names.clone(),
                            }
                        })?;
                        PositionFactor::Basis(j)
                    }
                };
                Ok(Term {
                    drive: t.drive,
                    position,
                    velocity: t.velocity,
                    coupling: t.coupling,
                })
            })
            .collect()
    }
}

/// Checks that `own` is a coordinate of `names`.
fn check_own(names: &Names, own: usize) -> Result<(), TermError> {
    if own >= names.coordinates().len() {
        return Err(TermError::BadName {
            name: format!("coordinate {}", own + 1),
            why: "the equation's own coordinate is not among the names",
        });
    }
    Ok(())
}

/// Why a term's factors in other coordinates (and its acceleration) do not make a term of the
/// equation of `own`, if they do not.
fn coupling_problem(t: &TermSpec, own: usize) -> Option<&'static str> {
    let mut accelerations = 0;
    for f in t.coupling.factors() {
        match *f {
            Factor::Acceleration { .. } => accelerations += 1,
            Factor::Velocity { coordinate, function } => {
                if usize::from(coordinate) == own {
                    return Some("the own velocity is a factor of its own, not one in another coordinate");
                }
                if function == VelocityFactor::One {
                    return Some("a velocity factor of 1");
                }
            }
            Factor::Power { coordinate, power } => {
                if usize::from(coordinate) == own {
                    return Some("a function of the own coordinate alone is a factor of its own");
                }
                if power == 0 || u32::from(power) > MAX_COUPLING_ORDER {
                    return Some("the power of a position must be between 1 and 64");
                }
            }
            Factor::Trig { combination, .. } => {
                if combination.single().is_some_and(|(c, _)| c == own) {
                    return Some("a function of the own coordinate alone is a factor of its own");
                }
            }
        }
    }
    if accelerations > 1 {
        return Some("a term holds at most one acceleration");
    }
    if let Some(c) = t.coupling.acceleration() {
        if t.drive != DriveFactor::One || t.velocity != VelocityFactor::One || t.coupling.has_velocity() {
            return Some(
                "an acceleration multiplies functions of the positions only (no drive factor, no velocity): the \
                 weak form moves its derivative onto them",
            );
        }
        let positions = t.function.is_some()
            || t.coupling
                .factors()
                .any(|f| matches!(f, Factor::Trig { .. } | Factor::Power { .. }));
        if c == own && !positions {
            return Some(
                "the own acceleration alone is the equation's normalisation (q'' + Σ c g = 0), not a term",
            );
        }
    }
    None
}

impl fmt::Display for TermList {
    /// The names joined by `, `: a list [`TermList::parse_in`] reads back as the same list.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, t) in self.terms.iter().enumerate() {
            if i > 0 {
                f.write_str(", ")?;
            }
            write!(f, "{}", t.display_in(&self.names, self.own))?;
        }
        Ok(())
    }
}

impl FromStr for TermList {
    type Err = TermError;

    fn from_str(spec: &str) -> Result<Self, TermError> {
        Self::parse(spec)
    }
}

impl From<TermList> for Vec<String> {
    fn from(list: TermList) -> Self {
        list.names()
    }
}

impl TryFrom<Vec<String>> for TermList {
    type Error = TermError;

    /// One name per term of one coordinate, each parsed as one term.
    fn try_from(names: Vec<String>) -> Result<Self, TermError> {
        let terms = names
            .iter()
            .map(|n| n.parse::<TermSpec>())
            .collect::<Result<Vec<_>, _>>()?;
        Self::new(terms)
    }
}

impl TermList {
    /// A list from one name per term, in `names` for the equation of `own` (how a saved system
    /// reads its equations' terms back).
    pub fn from_names_in(terms: &[String], names: &Names, own: usize) -> Result<Self, TermError> {
        let mut specs = Vec::with_capacity(terms.len());
        for text in terms {
            let one = Self::parse_in(text, names, own)?;
            match one.terms() {
                [t] => specs.push(*t),
                _ => {
                    return Err(TermError::TermSyntax {
                        spec: text.clone(),
                        at: text.chars().count() + 1,
                        found: format!("{} terms", one.len()),
                        expected: "one term".into(),
                    });
                }
            }
        }
        Self::new_in(specs, names.clone(), own)
    }
}

// ---------------------------------------------------------------------------------------------
// The parser.

/// One factor as written, before the factors of a product are combined.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Atom {
    One,
    Drive(DriveFactor),
    /// `cos` or `sin` of a combination of coordinates (a harmonic of one among them).
    Trig {
        sine: bool,
        combination: Combination,
    },
    /// A position to a power.
    Power {
        coordinate: usize,
        power: u32,
    },
    /// A hat of the own coordinate.
    Hat(u32),
    /// A velocity to a power (1, 2 or 3).
    Velocity {
        coordinate: usize,
        power: u32,
    },
    /// `|q'|`.
    Abs(usize),
    /// `sign(q')`.
    Sign(usize),
    /// `q''`.
    Acceleration(usize),
}

/// A product of atoms (each with its position), and the position of the item it came from.
#[derive(Debug, Clone)]
struct Product {
    atoms: Vec<(Atom, usize)>,
    at: usize,
}

/// The factors in one velocity: its power, `|q'|`s and `sign(q')`s, and where the first was.
#[derive(Debug, Clone, Copy, Default)]
struct VelocityParts {
    power: u32,
    abs: u32,
    sign: u32,
    at: Option<usize>,
}

/// Why `sin` of a combination that leads with a minus is refused: the order is the coordinates'
/// (`sin(theta1-theta2)` leads with a minus when theta2 is listed first).
const SIN_TURNED: &str = "sin of a combination that starts with a minus, the coordinates taken in the order they \
                          are listed, is −sin of the turned one: write it turned (sin(b-a) for \
                          sin(a-b)), its coefficient then of the other sign, or list the coordinates in the other \
                          order";

impl Product {
    /// The term of the product, for the equation of coordinate `own`.
    fn term(&self, spec: &str, own: usize) -> Result<TermSpec, TermError> {
        let clash = |at: usize, why: &'static str| TermError::TermProduct {
            spec: spec.to_owned(),
            at,
            why,
        };
        let mut drive: Option<DriveFactor> = None;
        let mut own_function: Option<XFunction> = None;
        // Powers of positions by coordinate, functions of combinations, hats.
        let mut powers = [0u32; MAX_COORDINATES];
        let mut power_at = [0usize; MAX_COORDINATES];
        let mut trig: Vec<(bool, Combination, usize)> = Vec::new();
        let mut velocities = [VelocityParts::default(); MAX_COORDINATES];
        let mut acceleration: Option<(usize, usize)> = None;
        for &(atom, at) in &self.atoms {
            match atom {
                Atom::One => {}
                Atom::Drive(d) => {
                    if drive.replace(d).is_some() {
                        return Err(clash(at, "a term has at most one drive factor"));
                    }
                }
                Atom::Hat(i) => {
                    if own_function.replace(XFunction::Hat(i)).is_some() {
                        return Err(clash(
                            at,
                            "a term has at most one function of x (a product of two is not a basis function)",
                        ));
                    }
                }
                Atom::Power { coordinate, power } => {
                    powers[coordinate] = powers[coordinate].saturating_add(power);
                    if power_at[coordinate] == 0 {
                        power_at[coordinate] = at;
                    }
                }
                Atom::Trig { sine, combination } => {
                    if trig.iter().any(|&(_, c, _)| c == combination) {
                        return Err(clash(
                            at,
                            "a term has at most one function of x (a product of two is not a basis function)",
                        ));
                    }
                    trig.push((sine, combination, at));
                }
                Atom::Velocity { coordinate, power } => {
                    let v = &mut velocities[coordinate];
                    v.power = v.power.saturating_add(power);
                    v.at.get_or_insert(at);
                }
                Atom::Abs(c) => {
                    velocities[c].abs += 1;
                    velocities[c].at.get_or_insert(at);
                }
                Atom::Sign(c) => {
                    velocities[c].sign += 1;
                    velocities[c].at.get_or_insert(at);
                }
                Atom::Acceleration(c) => {
                    if acceleration.replace((c, at)).is_some() {
                        return Err(clash(at, "a term holds at most one acceleration"));
                    }
                }
            }
        }
        let mut coupling: Vec<Factor> = Vec::new();
        // The functions of each coordinate alone: at most one each; the own one is the term's
        // function of x.
        for (c, &power) in powers.iter().enumerate() {
            if power == 0 {
                continue;
            }
            let at = power_at[c];
            if trig
                .iter()
                .any(|&(_, comb, _)| comb.single().is_some_and(|(d, _)| d == c))
            {
                return Err(clash(
                    at,
                    "a term has at most one function of x (a product of two is not a basis function)",
                ));
            }
            if c == own {
                if own_function.replace(XFunction::Power(power)).is_some() {
                    return Err(clash(
                        at,
                        "a term has at most one function of x (a product of two is not a basis function)",
                    ));
                }
            } else {
                if power > MAX_COUPLING_ORDER {
                    return Err(clash(at, "the power of a position must be between 1 and 64"));
                }
                coupling.push(Factor::Power {
                    coordinate: c as u8,
                    power: power as u8,
                });
            }
        }
        for &(sine, combination, at) in &trig {
            match combination.single() {
                Some((c, k)) if c == own => {
                    let k = k.unsigned_abs();
                    if sine && combination.leads_negative() {
                        return Err(clash(at, SIN_TURNED));
                    }
                    let f = if sine {
                        XFunction::Sin(k)
                    } else {
                        XFunction::Cos(k)
                    };
                    if own_function.replace(f).is_some() {
                        return Err(clash(
                            at,
                            "a term has at most one function of x (a product of two is not a basis function)",
                        ));
                    }
                }
                _ => {
                    let combination = if combination.leads_negative() {
                        if sine {
                            return Err(clash(at, SIN_TURNED));
                        }
                        combination.negated()
                    } else {
                        combination
                    };
                    if let Some((c, _)) = combination.single()
                        && trig
                            .iter()
                            .filter(|&&(_, comb, _)| comb.single().is_some_and(|(d, _)| d == c))
                            .count()
                            > 1
                    {
                        return Err(clash(
                            at,
                            "a term has at most one function of each coordinate (a product of two is one function)",
                        ));
                    }
                    coupling.push(Factor::Trig { sine, combination });
                }
            }
        }
        let mut own_velocity = VelocityFactor::One;
        for (c, v) in velocities.iter().enumerate() {
            let function = match (v.power, v.abs, v.sign) {
                (0, 0, 0) => continue,
                (1, 0, 0) => VelocityFactor::Linear,
                (1, 1, 0) => VelocityFactor::Quadratic,
                (2, 0, 0) => VelocityFactor::Square,
                (3, 0, 0) => VelocityFactor::Cubic,
                (0, 0, 1) => VelocityFactor::Sign,
                _ => {
                    return Err(clash(
                        v.at.unwrap_or(self.at),
                        "the factors in x' of a term must make one of x', x'^2, sign(x'), x'*|x'|, x'^3",
                    ));
                }
            };
            if c == own {
                own_velocity = function;
            } else {
                coupling.push(Factor::Velocity {
                    coordinate: c as u8,
                    function,
                });
            }
        }
        if let Some((c, _)) = acceleration {
            coupling.push(Factor::Acceleration { coordinate: c as u8 });
        }
        let coupling = Coupling::new(coupling).ok_or_else(|| {
            clash(
                self.at,
                "a term has at most 4 factors in other coordinates and accelerations",
            )
        })?;
        let term = TermSpec {
            drive: drive.unwrap_or(DriveFactor::One),
            function: own_function,
            velocity: own_velocity,
            coupling,
        };
        if let Some(why) = coupling_problem(&term, own) {
            return Err(clash(acceleration.map_or(self.at, |(_, at)| at), why));
        }
        Ok(term)
    }
}

/// What a factor may be, for the errors.
const FACTOR: &str = "a factor: 1, cos(kt), sin(kt), a measured drive, cos(..), sin(..) of a coordinate or a \
                      combination, x, x^n, hatN, x', x'^2, x'^3, sign(x'), |x'|, x'' or {..}";

/// A recursive-descent parser over the characters of a spec with white space removed (each
/// character keeps its 1-based position in the spec).
struct Parser<'a> {
    spec: &'a str,
    names: &'a Names,
    chars: Vec<(usize, char)>,
    next: usize,
    end: usize,
}

impl<'a> Parser<'a> {
    fn new(spec: &'a str, names: &'a Names) -> Self {
        let chars: Vec<(usize, char)> = spec
            .chars()
            .enumerate()
            .filter(|(_, c)| !c.is_whitespace())
            .map(|(i, c)| (i + 1, c))
            .collect();
        Self {
            spec,
            names,
            chars,
            next: 0,
            end: spec.chars().count() + 1,
        }
    }

    fn peek(&self) -> Option<char> {
        self.chars.get(self.next).map(|&(_, c)| c)
    }

    /// Position of the next character (one past the end at the end).
    fn at(&self) -> usize {
        self.chars.get(self.next).map_or(self.end, |&(at, _)| at)
    }

    fn error(&self, expected: impl Into<std::borrow::Cow<'static, str>>) -> TermError {
        let found = match self.peek() {
            None => "the end".to_owned(),
            Some(_) => {
                let rest: String = self.chars[self.next..].iter().map(|&(_, c)| c).take(12).collect();
                format!("'{rest}'")
            }
        };
        TermError::TermSyntax {
            spec: self.spec.to_owned(),
            at: self.at(),
            found,
            expected: expected.into(),
        }
    }

    /// Consumes `text` if it comes next.
    fn eat(&mut self, text: &str) -> bool {
        let n = text.chars().count();
        let matches = self.next + n <= self.chars.len()
            && self.chars[self.next..self.next + n]
                .iter()
                .map(|&(_, c)| c)
                .eq(text.chars());
        if matches {
            self.next += n;
        }
        matches
    }

    fn expect(&mut self, text: &str, expected: &'static str) -> Result<(), TermError> {
        if self.eat(text) {
            Ok(())
        } else {
            Err(self.error(expected))
        }
    }

    /// A whole number, if one comes next.
    fn number(&mut self) -> Result<Option<u32>, TermError> {
        let start = self.next;
        let at = self.at();
        let mut value: u64 = 0;
        while let Some(d) = self.peek().and_then(|c| c.to_digit(10)) {
            value = value * 10 + u64::from(d);
            if value > u64::from(u32::MAX) {
                self.next = start;
                return Err(TermError::TermSyntax {
                    spec: self.spec.to_owned(),
                    at,
                    found: "a number too large".to_owned(),
                    expected: "a whole number below 2^32".into(),
                });
            }
            self.next += 1;
        }
        Ok((self.next > start).then_some(value as u32))
    }

    /// A whole number at least 1 (the position of a 0 for the error).
    fn positive(&mut self, expected: &'static str) -> Result<u32, TermError> {
        let at = self.next;
        match self.number()? {
            Some(0) => {
                self.next = at;
                Err(self.error("a whole number at least 1"))
            }
            Some(n) => Ok(n),
            None => Err(self.error(expected)),
        }
    }

    /// An identifier, if one comes next (its text; the position stays before it when none).
    fn identifier(&mut self) -> Option<String> {
        let start = self.next;
        match self.peek() {
            Some(c) if c.is_ascii_alphabetic() || c == '_' => {}
            _ => return None,
        }
        while self.peek().is_some_and(|c| c.is_ascii_alphanumeric() || c == '_') {
            self.next += 1;
        }
        Some(self.chars[start..self.next].iter().map(|&(_, c)| c).collect())
    }

    /// A coordinate's name (the position of the name for the error).
    fn coordinate(&mut self, expected: &'static str) -> Result<usize, TermError> {
        let at = self.next;
        if let Some(name) = self.identifier()
            && let Some(c) = self.names.coordinate(&name)
        {
            return Ok(c);
        }
        self.next = at;
        Err(self.error(expected))
    }

    /// `list := item (',' item)*` to the end of the spec.
    fn list(&mut self) -> Result<Vec<Product>, TermError> {
        let mut out = self.item()?;
        while self.eat(",") {
            out.extend(self.item()?);
            if out.len() > MAX_TERMS {
                return Err(TermError::TooManyTerms {
                    count: out.len(),
                    max: MAX_TERMS,
                });
            }
        }
        if self.peek().is_some() {
            return Err(self.error("',' between terms, '*' between factors, or the end"));
        }
        Ok(out)
    }

    /// `item := factor ('*' factor)*`: the products of one item (several with braces).
    fn item(&mut self) -> Result<Vec<Product>, TermError> {
        let at = self.at();
        let mut out = self.factor()?;
        while self.eat("*") {
            let right = self.factor()?;
            let count = out.len().saturating_mul(right.len());
            if count > MAX_TERMS {
                return Err(TermError::TooManyTerms {
                    count,
                    max: MAX_TERMS,
                });
            }
            out = out
                .iter()
                .flat_map(|l| {
                    right.iter().map(move |r| Product {
                        atoms: l.atoms.iter().chain(&r.atoms).copied().collect(),
                        at,
                    })
                })
                .collect();
        }
        for p in &mut out {
            p.at = at;
        }
        Ok(out)
    }

    /// `factor := atom | '{' item (',' item)* '}'`.
    fn factor(&mut self) -> Result<Vec<Product>, TermError> {
        if self.eat("{") {
            let mut out = self.item()?;
            while self.eat(",") {
                out.extend(self.item()?);
                if out.len() > MAX_TERMS {
                    return Err(TermError::TooManyTerms {
                        count: out.len(),
                        max: MAX_TERMS,
                    });
                }
            }
            self.expect("}", "',' or '}'")?;
            return Ok(out);
        }
        let at = self.at();
        let atom = self.atom()?;
        Ok(vec![Product {
            atoms: vec![(atom, at)],
            at,
        }])
    }

    /// The argument of `cos(..)` or `sin(..)` after its parenthesis: `[n] t` (a drive factor) or
    /// a combination of coordinates, then `)`.
    fn trig(&mut self, sine: bool) -> Result<Atom, TermError> {
        let mut coefficients = [0i32; MAX_COORDINATES];
        let mut first = true;
        loop {
            let negative = if first || self.eat("+") {
                false
            } else if self.eat("-") {
                true
            } else {
                break;
            };
            let k = match self.peek() {
                Some(c) if c.is_ascii_digit() => self.positive("a harmonic")?,
                _ => 1,
            };
            let at = self.next;
            match self.identifier().as_deref() {
                Some("t") if first => {
                    self.expect(")", "')'")?;
                    return Ok(Atom::Drive(if sine {
                        DriveFactor::Sin(k)
                    } else {
                        DriveFactor::Cos(k)
                    }));
                }
                Some(name) if self.names.coordinate(name).is_some() => {
                    let c = self.names.coordinate(name).expect("checked");
                    let k = i64::from(k) * if negative { -1 } else { 1 };
                    let sum = i64::from(coefficients[c]) + k;
                    if sum.unsigned_abs() > u64::from(MAX_COUPLING_ORDER) {
                        self.next = at;
                        return Err(self.error("a coefficient of at most 64"));
                    }
                    coefficients[c] = sum as i32;
                }
                _ => {
                    self.next = at;
                    let names = self.names.coordinates();
                    return Err(match (first, names) {
                        (true, [x]) if x == "x" => {
                            self.error("t (the drive's phase) or x, as in cos(2t) or sin(x)")
                        }
                        (true, [x]) => self.error(format!(
                            "t (the drive's phase) or the coordinate {x}, as in cos(2t) or sin({x})"
                        )),
                        (true, _) => self.error(format!(
                            "t (the drive's phase) or a coordinate ({}), as in cos(2t) or sin({}-{})",
                            names.join(", "),
                            names[0],
                            names[1]
                        )),
                        (false, _) => self.error(format!("a coordinate's name ({})", names.join(", "))),
                    });
                }
            }
            first = false;
        }
        let at = self.next;
        self.expect(")", "')', '+' or '-'")?;
        let combination = Combination::new(&coefficients).ok_or_else(|| {
            self.next = at;
            self.error("a combination whose coefficients are not all 0")
        })?;
        Ok(Atom::Trig { sine, combination })
    }

    fn atom(&mut self) -> Result<Atom, TermError> {
        if self.eat("sign(") {
            let at = self.next;
            let c = self.coordinate("x') after sign(")?;
            if !self.eat("')") {
                self.next = at;
                return Err(self.error("x') after sign("));
            }
            return Ok(Atom::Sign(c));
        }
        for (name, sine) in [("cos(", false), ("sin(", true)] {
            if self.eat(name) {
                return self.trig(sine);
            }
        }
        if self.eat("|") {
            let at = self.next;
            let c = self.coordinate("x'| after |")?;
            if !self.eat("'|") {
                self.next = at;
                return Err(self.error("x'| after |"));
            }
            return Ok(Atom::Abs(c));
        }
        if self.peek() == Some('1') {
            let at = self.next;
            if self.number()? == Some(1) {
                return Ok(Atom::One);
            }
            self.next = at;
            return Err(self.error("1, the only number that is a factor"));
        }
        let at = self.next;
        let Some(name) = self.identifier() else {
            return Err(self.error(FACTOR));
        };
        if let Some(c) = self.names.coordinate(&name) {
            if self.eat("''") {
                return Ok(Atom::Acceleration(c));
            }
            if self.eat("'") {
                if self.eat("^") {
                    let at = self.next;
                    return match self.positive("a power of x' (2 or 3)")? {
                        p @ 1..=3 => Ok(Atom::Velocity {
                            coordinate: c,
                            power: p,
                        }),
                        _ => {
                            self.next = at;
                            Err(self.error(
                                "2 or 3: the powers of x' are x', x'^2 and x'^3 (x'*|x'| for the signed square)",
                            ))
                        }
                    };
                }
                return Ok(Atom::Velocity {
                    coordinate: c,
                    power: 1,
                });
            }
            if self.eat("^") {
                return Ok(Atom::Power {
                    coordinate: c,
                    power: self.positive("a power of x")?,
                });
            }
            return Ok(Atom::Power {
                coordinate: c,
                power: 1,
            });
        }
        if let Some(d) = self.names.drive(&name) {
            return Ok(Atom::Drive(DriveFactor::Measured(d as u8)));
        }
        if let Some(rest) = name.strip_prefix("hat")
            && !rest.is_empty()
            && rest.chars().all(|c| c.is_ascii_digit())
        {
            self.next = at + 3;
            return match self.number()? {
                Some(i) => Ok(Atom::Hat(i)),
                None => Err(self.error("the hat's node, as in hat3")),
            };
        }
        if name == "hat" {
            return Err(self.error("the hat's node, as in hat3"));
        }
        self.next = at;
        Err(self.error(FACTOR))
    }
}
