//! The vocabulary of the model's terms, the lists of terms users write, and the column layout of
//! every system defined once.
//!
//! The model is `x'' + Σ_i c_i g_i = 0`, each term `g_i` a product of three factors: a drive
//! factor (`1`, `cos(kt)`, `sin(kt)` for harmonic `k` of the drive, `t` standing for the drive's
//! phase `W t`, or `p`, the measured drive `p(t)`, a signal recorded beside the state), a function
//! of `x` (`1`, a basis function, or `x` itself) and a function of `x'` (`1`, `x'`, `sign(x')`,
//! `x'*|x'|`, `x'^3`). A term is named by its factors joined by `*`, drive factor first: `x'`,
//! `cos(t)*sin(x)`, `sin(2t)*cos(x)`, `cos(3t)`, `x^2*x'`, `p`, `p*cos(x)`.
//!
//! The measured drive `p` is data, not a function of time: its samples come with the record's
//! ([`crate::MeasuredDrive`], given to the identification with them), and a term that holds it is
//! balanced from them by the weak form.
//!
//! Two forms of a term: [`Term`] names its function of `x` by its index in a basis (what the
//! assemblies and the model evaluate); [`TermSpec`] names it by itself ([`XFunction`]: `cos(2x)`,
//! `x^3`, `hat3`), so that a list of terms ([`TermList`]) can be written, parsed, saved and read
//! without a basis, and resolved against one ([`TermList::resolve`]).
//!
//! # The grammar of a term list ([`TermList::parse`])
//!
//! ```text
//! list    := item (',' item)*
//! item    := factor ('*' factor)*           a product; braces multiply out
//! factor  := atom | '{' item (',' item)* '}'
//! atom    := '1'
//!          | 'cos(' [n] 't)' | 'sin(' [n] 't)'                    drive harmonic n >= 1
//!          | 'p'                                                  the measured drive
//!          | 'cos(' [n] 'x)' | 'sin(' [n] 'x)' | 'x' ['^' n] | 'hat' i   a function of x
//!          | "x'" ['^3'] | "sign(x')" | "|x'|"                      x', x'^3, sign(x'); |x'| only in x'*|x'|
//! ```
//!
//! White space is ignored. A product holds at most one drive factor and one function of `x`, and
//! its factors in `x'` must make one of `x'`, `sign(x')`, `x'*|x'|` (in either order) or `x'^3`.
//! `{1,cos(t),sin(t)}*{cos(x),sin(x)}` is the six products `cos(x)`, `sin(x)`, `cos(t)*cos(x)`,
//! `cos(t)*sin(x)`, `sin(t)*cos(x)`, `sin(t)*sin(x)`, in this order (the leftmost set varies
//! slowest). Every term may appear once. Printing a list ([`fmt::Display`]) and parsing it again
//! gives the same list.
//!
//! [`columns`] gives the unknowns of a [`ModelForm`] on a basis, in the order every assembly,
//! solver, bootstrap and saved model uses.

use std::fmt;
use std::str::FromStr;

use hb_basis::{Basis, BasisKind, Domain, Harmonic, Hat, Polynomial};
use serde::{Deserialize, Serialize};

use crate::error::TermError;

/// The highest drive harmonic a term may name.
pub const MAX_DRIVE_HARMONIC: u32 = 64;

/// The most terms a list may hold (braces multiply quickly).
pub const MAX_TERMS: usize = 4096;

/// The drive factor of a term: `1`, `cos(k t)` or `sin(k t)` for harmonic `k >= 1` of the drive,
/// or the measured drive `p`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DriveFactor {
    /// No drive factor.
    One,
    /// `cos(k t)`.
    Cos(u32),
    /// `sin(k t)`.
    Sin(u32),
    /// `p`: the measured drive `p(t)`, a signal recorded with the state (a shaker's base
    /// acceleration, a motor's torque), used as it was measured instead of a function of the
    /// drive's phase.
    Measured,
}

impl DriveFactor {
    /// The harmonic `k` of the drive (0 for [`DriveFactor::One`] and [`DriveFactor::Measured`],
    /// which are no function of the drive's phase).
    pub fn harmonic(&self) -> u32 {
        match *self {
            Self::One | Self::Measured => 0,
            Self::Cos(k) | Self::Sin(k) => k,
        }
    }

    /// Whether the factor is the measured drive `p`.
    pub fn is_measured(&self) -> bool {
        *self == Self::Measured
    }

    /// Whether the factor is a function of the drive's phase (`cos(kt)`, `sin(kt)`), so that a
    /// term holding it needs the drive's period and phase.
    pub fn needs_phase(&self) -> bool {
        matches!(self, Self::Cos(_) | Self::Sin(_))
    }

    /// The factor at the drive's phase `θ = W t` with the measured drive `p` at the same
    /// instant: `1`, `cos(kθ)`, `sin(kθ)` or `p` (each factor reads only what it depends on).
    pub fn eval(&self, phase: f64, measured: f64) -> f64 {
        match *self {
            Self::One => 1.0,
            Self::Cos(k) => (f64::from(k) * phase).cos(),
            Self::Sin(k) => (f64::from(k) * phase).sin(),
            Self::Measured => measured,
        }
    }
}

/// The factor in the displacement `x` of a term.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PositionFactor {
    /// No function of `x`.
    One,
    /// Function `i` of the basis.
    Basis(usize),
    /// `x` itself, a linear stiffness beside the basis (on the line only); named `k*x`.
    Linear,
}

/// The factor in the velocity `x'` of a term.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
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
        }
    }

    /// Its derivative in `v`: `0`, `1`, `0` (away from `v = 0`), `2|v|`, `3v²`.
    #[inline]
    pub fn eval_deriv(&self, v: f64) -> f64 {
        match self {
            Self::One | Self::Sign => 0.0,
            Self::Linear => 1.0,
            Self::Quadratic => 2.0 * v.abs(),
            Self::Cubic => 3.0 * v * v,
        }
    }

    /// The factor on one side of `x' = 0` (`side` = 1 or −1, see `pendulum_sim::Branch`):
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

    /// The factor's name, `None` for [`VelocityFactor::One`].
    pub fn name(&self) -> Option<&'static str> {
        match self {
            Self::One => None,
            Self::Linear => Some("x'"),
            Self::Sign => Some("sign(x')"),
            Self::Quadratic => Some("x'*|x'|"),
            Self::Cubic => Some("x'^3"),
        }
    }
}

/// One term of the model: the product of a drive factor, a function of `x` and a function of `x'`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Term {
    /// The drive factor.
    pub drive: DriveFactor,
    /// The function of `x`.
    pub position: PositionFactor,
    /// The function of `x'`.
    pub velocity: VelocityFactor,
}

impl Term {
    /// `x'`, the linear damping.
    pub const DAMPING: Self = Self {
        drive: DriveFactor::One,
        position: PositionFactor::One,
        velocity: VelocityFactor::Linear,
    };

    /// The drive factor alone (`cos(kt)` or `sin(kt)`, an external forcing).
    pub const fn drive(drive: DriveFactor) -> Self {
        Self {
            drive,
            position: PositionFactor::One,
            velocity: VelocityFactor::One,
        }
    }

    /// Basis function `i` times a drive factor (`One` for the autonomous term).
    pub const fn basis(drive: DriveFactor, i: usize) -> Self {
        Self {
            drive,
            position: PositionFactor::Basis(i),
            velocity: VelocityFactor::One,
        }
    }

    /// The term's name with the basis functions' `names`, e.g. `cos(t)*sin(x)`.
    pub fn name(&self, names: &[String]) -> String {
        self.display(names).to_string()
    }

    /// The term shown with the basis functions' `names`.
    pub fn display<'a>(&'a self, names: &'a [String]) -> impl fmt::Display + 'a {
        TermName { term: self, names }
    }
}

/// Writes the name of a term from its factors' names, `1` for the empty product.
fn write_name(
    f: &mut fmt::Formatter<'_>,
    drive: DriveFactor,
    position: Option<&dyn fmt::Display>,
    velocity: VelocityFactor,
) -> fmt::Result {
    let mut first = true;
    let mut sep = |f: &mut fmt::Formatter<'_>| -> fmt::Result {
        if !std::mem::take(&mut first) {
            f.write_str("*")?;
        }
        Ok(())
    };
    match drive {
        DriveFactor::One => {}
        DriveFactor::Measured => {
            sep(f)?;
            f.write_str("p")?;
        }
        DriveFactor::Cos(k) | DriveFactor::Sin(k) => {
            sep(f)?;
            let trig = if matches!(drive, DriveFactor::Cos(_)) {
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
    if let Some(p) = position {
        sep(f)?;
        write!(f, "{p}")?;
    }
    if let Some(v) = velocity.name() {
        sep(f)?;
        f.write_str(v)?;
    }
    if first {
        f.write_str("1")?;
    }
    Ok(())
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
        write_name(f, self.term.drive, position, self.term.velocity)
    }
}

// ---------------------------------------------------------------------------------------------
// Terms named without a basis.

/// A function of `x` named by itself, as the bases of `hb-basis` name theirs.
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
}

impl fmt::Display for XFunction {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Cos(1) => f.write_str("cos(x)"),
            Self::Sin(1) => f.write_str("sin(x)"),
            Self::Cos(k) => write!(f, "cos({k}x)"),
            Self::Sin(k) => write!(f, "sin({k}x)"),
            Self::Power(1) => f.write_str("x"),
            Self::Power(n) => write!(f, "x^{n}"),
            Self::Hat(i) => write!(f, "hat{i}"),
        }
    }
}

/// A term with its function of `x` named by itself (`sin(2t)*cos(x)`, `x^2*x'`), independent of
/// any basis; [`TermList::resolve`] turns it into a [`Term`] of a basis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TermSpec {
    /// The drive factor.
    pub drive: DriveFactor,
    /// The function of `x`, if any.
    pub function: Option<XFunction>,
    /// The function of `x'`.
    pub velocity: VelocityFactor,
}

impl fmt::Display for TermSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let position = self.function.as_ref().map(|x| x as &dyn fmt::Display);
        write_name(f, self.drive, position, self.velocity)
    }
}

impl FromStr for TermSpec {
    type Err = TermError;

    /// One term (a product without braces or commas), e.g. `cos(t)*sin(x)`.
    fn from_str(text: &str) -> Result<Self, TermError> {
        let list = TermList::parse(text)?;
        match list.terms() {
            [one] => Ok(*one),
            _ => Err(TermError::TermSyntax {
                spec: text.to_owned(),
                at: text.chars().count() + 1,
                found: format!("{} terms", list.len()),
                expected: "one term",
            }),
        }
    }
}

/// An ordered list of distinct terms named without a basis, as a user writes it: what
/// [`ModelForm::from_terms`] takes. See the module documentation for the grammar of
/// [`TermList::parse`].
///
/// ```
/// use hb_model::TermList;
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
/// # Ok::<(), hb_model::TermError>(())
/// ```
#[derive(Debug, Clone, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(try_from = "Vec<String>", into = "Vec<String>")]
pub struct TermList {
    terms: Vec<TermSpec>,
}

impl TermList {
    /// Parses a list of terms (grammar in the module documentation).
    ///
    /// Errors: [`TermError::TermSyntax`] and [`TermError::TermProduct`] with the position (a
    /// 1-based character index into `spec`), [`TermError::DuplicateTerm`],
    /// [`TermError::TooManyTerms`], and [`TermError::InvalidParameter`] for a drive harmonic
    /// above [`MAX_DRIVE_HARMONIC`].
    pub fn parse(spec: &str) -> Result<Self, TermError> {
        let products = Parser::new(spec).list()?;
        let mut terms: Vec<TermSpec> = Vec::with_capacity(products.len());
        for product in products {
            let term = product.term(spec)?;
            if terms.contains(&term) {
                return Err(TermError::DuplicateTerm {
                    term: term.to_string(),
                    at: product.at,
                });
            }
            terms.push(term);
        }
        Self::new(terms)
    }

    /// A list of `terms`: at least one, at most [`MAX_TERMS`], none twice, drive harmonics at most
    /// [`MAX_DRIVE_HARMONIC`] and every number in a name at least 1 (`x^0`, `cos(0t)` are not
    /// terms).
    pub fn new(terms: Vec<TermSpec>) -> Result<Self, TermError> {
        if terms.is_empty() {
            return Err(TermError::TermSyntax {
                spec: String::new(),
                at: 1,
                found: "nothing".to_owned(),
                expected: "at least one term",
            });
        }
        if terms.len() > MAX_TERMS {
            return Err(TermError::TooManyTerms {
                count: terms.len(),
                max: MAX_TERMS,
            });
        }
        for (i, t) in terms.iter().enumerate() {
            let k = t.drive.harmonic();
            if k > MAX_DRIVE_HARMONIC || (k == 0 && t.drive.needs_phase()) {
                return Err(TermError::DriveHarmonicOutOfRange { harmonic: k });
            }
            if let Some(XFunction::Cos(0) | XFunction::Sin(0) | XFunction::Power(0)) = t.function {
                return Err(TermError::TermSyntax {
                    spec: t.to_string(),
                    at: 1,
                    found: "0".to_owned(),
                    expected: "a whole number at least 1",
                });
            }
            if terms[..i].contains(t) {
                return Err(TermError::DuplicateTerm {
                    term: t.to_string(),
                    at: i + 1,
                });
            }
        }
        Ok(Self { terms })
    }

    /// The terms, in order.
    pub fn terms(&self) -> &[TermSpec] {
        &self.terms
    }

    /// Number of terms.
    pub fn len(&self) -> usize {
        self.terms.len()
    }

    /// Never true: a list has at least one term.
    pub fn is_empty(&self) -> bool {
        self.terms.is_empty()
    }

    /// The terms' names, in order.
    pub fn names(&self) -> Vec<String> {
        self.terms.iter().map(ToString::to_string).collect()
    }

    /// The highest drive harmonic named (0 when no term has a drive factor of the drive's phase).
    pub fn drive_harmonics(&self) -> u32 {
        self.terms.iter().map(|t| t.drive.harmonic()).max().unwrap_or(0)
    }

    /// Whether a term has the measured drive `p` as its drive factor.
    pub fn has_measured_drive(&self) -> bool {
        self.measured_term().is_some()
    }

    /// The first term whose drive factor is the measured drive `p`, if any.
    pub fn measured_term(&self) -> Option<&TermSpec> {
        self.terms.iter().find(|t| t.drive.is_measured())
    }

    /// The first term whose drive factor is a function of the drive's phase (`cos(kt)`,
    /// `sin(kt)`), if any: such a term needs the drive's period and phase.
    pub fn phase_term(&self) -> Option<&TermSpec> {
        self.terms.iter().find(|t| t.drive.needs_phase())
    }

    /// The smallest basis of `hb-basis` that holds every function of `x` named: `harmonic:K` for
    /// `cos(kx)`, `sin(kx)` up to `k = K`, `poly:D` for powers up to `x^D`, `hat:N` for hats up to
    /// `hat{N−1}` (at least 3); `None` when no term names a function of `x`.
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

    /// Checks that every function of `x` named lives on `domain` (`x^3` is not a function of an
    /// angle; `cos(x)` and hats are not functions on the line).
    pub fn check_domain(&self, domain: Domain) -> Result<(), TermError> {
        match self
            .terms
            .iter()
            .find(|t| t.function.is_some_and(|f| f.domain() != domain))
        {
            Some(t) => Err(TermError::TermNotAllowed {
                term: t.to_string(),
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

    /// The terms on `basis`: each function of `x` found by its name among the basis' functions.
    ///
    /// Errors: [`TermError::TermNotAllowed`] for a function of another domain than the basis',
    /// [`TermError::TermNotInBasis`] for a function the basis lacks.
    pub fn resolve<B: Basis + ?Sized>(&self, basis: &B) -> Result<Vec<Term>, TermError> {
        self.check_domain(basis.domain())?;
        let names = basis.names();
        self.terms
            .iter()
            .map(|t| {
                let position = match t.function {
                    None => PositionFactor::One,
                    Some(f) => {
                        let name = f.to_string();
                        let i = names.iter().position(|n| *n == name).ok_or_else(|| {
                            TermError::TermNotInBasis {
                                term: t.to_string(),
                                function: name,
                                basis: names.clone(),
                            }
                        })?;
                        PositionFactor::Basis(i)
                    }
                };
                Ok(Term {
                    drive: t.drive,
                    position,
                    velocity: t.velocity,
                })
            })
            .collect()
    }
}

impl fmt::Display for TermList {
    /// The names joined by `, `: a list [`TermList::parse`] reads back as the same list.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, t) in self.terms.iter().enumerate() {
            if i > 0 {
                f.write_str(", ")?;
            }
            write!(f, "{t}")?;
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

    /// One name per term, each parsed as one term.
    fn try_from(names: Vec<String>) -> Result<Self, TermError> {
        let terms = names
            .iter()
            .map(|n| n.parse::<TermSpec>())
            .collect::<Result<Vec<_>, _>>()?;
        Self::new(terms)
    }
}

// ---------------------------------------------------------------------------------------------
// The parser.

/// One factor as written, before the factors of a product are combined.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Atom {
    One,
    Drive(DriveFactor),
    X(XFunction),
    /// `x'` to a power (1 or 3).
    Velocity(u32),
    /// `|x'|`.
    Abs,
    /// `sign(x')`.
    Sign,
}

/// A product of atoms (each with its position), and the position of the item it came from.
#[derive(Debug, Clone)]
struct Product {
    atoms: Vec<(Atom, usize)>,
    at: usize,
}

impl Product {
    /// The term of the product.
    fn term(&self, spec: &str) -> Result<TermSpec, TermError> {
        let mut drive: Option<DriveFactor> = None;
        let mut function: Option<XFunction> = None;
        let (mut power, mut abs, mut sign, mut first_velocity) = (0u32, 0u32, 0u32, None);
        let clash = |at: usize, why: &'static str| TermError::TermProduct {
            spec: spec.to_owned(),
            at,
            why,
        };
        for &(atom, at) in &self.atoms {
            match atom {
                Atom::One => {}
                Atom::Drive(d) => {
                    if drive.replace(d).is_some() {
                        return Err(clash(at, "a term has at most one drive factor"));
                    }
                }
                Atom::X(f) => {
                    if function.replace(f).is_some() {
                        return Err(clash(
                            at,
                            "a term has at most one function of x (a product of two is not a basis function)",
                        ));
                    }
                }
                Atom::Velocity(p) => {
                    power = power.saturating_add(p);
                    first_velocity.get_or_insert(at);
                }
                Atom::Abs => {
                    abs += 1;
                    first_velocity.get_or_insert(at);
                }
                Atom::Sign => {
                    sign += 1;
                    first_velocity.get_or_insert(at);
                }
            }
        }
        let velocity = match (power, abs, sign) {
            (0, 0, 0) => VelocityFactor::One,
            (1, 0, 0) => VelocityFactor::Linear,
            (1, 1, 0) => VelocityFactor::Quadratic,
            (3, 0, 0) => VelocityFactor::Cubic,
            (0, 0, 1) => VelocityFactor::Sign,
            _ => {
                return Err(clash(
                    first_velocity.unwrap_or(self.at),
                    "the factors in x' of a term must make one of x', sign(x'), x'*|x'|, x'^3",
                ));
            }
        };
        Ok(TermSpec {
            drive: drive.unwrap_or(DriveFactor::One),
            function,
            velocity,
        })
    }
}

/// What a factor may be, for the errors.
const FACTOR: &str =
    "a factor: 1, cos(kt), sin(kt), p, cos(kx), sin(kx), x, x^n, hatN, x', x'^3, sign(x'), |x'| or {..}";

/// A recursive-descent parser over the characters of a spec with white space removed (each
/// character keeps its 1-based position in the spec).
struct Parser<'a> {
    spec: &'a str,
    chars: Vec<(usize, char)>,
    next: usize,
    end: usize,
}

impl<'a> Parser<'a> {
    fn new(spec: &'a str) -> Self {
        let chars: Vec<(usize, char)> = spec
            .chars()
            .enumerate()
            .filter(|(_, c)| !c.is_whitespace())
            .map(|(i, c)| (i + 1, c))
            .collect();
        Self {
            spec,
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

    fn error(&self, expected: &'static str) -> TermError {
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
            expected,
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
                    expected: "a whole number below 2^32",
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

    fn atom(&mut self) -> Result<Atom, TermError> {
        if self.eat("sign(") {
            self.expect("x')", "x') after sign(")?;
            return Ok(Atom::Sign);
        }
        for (name, cos) in [("cos(", true), ("sin(", false)] {
            if self.eat(name) {
                let k = match self.peek() {
                    Some(c) if c.is_ascii_digit() => self.positive("a harmonic")?,
                    _ => 1,
                };
                let atom = if self.eat("t") {
                    Atom::Drive(if cos {
                        DriveFactor::Cos(k)
                    } else {
                        DriveFactor::Sin(k)
                    })
                } else if self.eat("x") {
                    Atom::X(if cos { XFunction::Cos(k) } else { XFunction::Sin(k) })
                } else {
                    return Err(self.error("t (the drive's phase) or x, as in cos(2t) or sin(x)"));
                };
                self.expect(")", "')'")?;
                return Ok(atom);
            }
        }
        if self.eat("hat") {
            return match self.number()? {
                Some(i) => Ok(Atom::X(XFunction::Hat(i))),
                None => Err(self.error("the hat's node, as in hat3")),
            };
        }
        if self.eat("|x'|") {
            return Ok(Atom::Abs);
        }
        if self.eat("p") {
            return Ok(Atom::Drive(DriveFactor::Measured));
        }
        if self.eat("x'") {
            if self.eat("^") {
                let at = self.next;
                return match self.positive("a power of x' (3)")? {
                    1 => Ok(Atom::Velocity(1)),
                    3 => Ok(Atom::Velocity(3)),
                    _ => {
                        self.next = at;
                        Err(self.error("3: the powers of x' are x' and x'^3 (x'*|x'| for the even one)"))
                    }
                };
            }
            return Ok(Atom::Velocity(1));
        }
        if self.eat("x") {
            if self.eat("^") {
                return Ok(Atom::X(XFunction::Power(self.positive("a power of x")?)));
            }
            return Ok(Atom::X(XFunction::Power(1)));
        }
        if self.peek() == Some('1') {
            let at = self.next;
            if self.number()? == Some(1) {
                return Ok(Atom::One);
            }
            self.next = at;
            return Err(self.error("1, the only number that is a factor"));
        }
        Err(self.error(FACTOR))
    }
}
