//! The model's form: which terms it has (a preset of the paper's families, or a list of terms),
//! the harmonics per segment it was balanced over, and the layout of its unknowns
//! ([`columns`]), which every assembly fills and every reader of a system assumes.

use hb_basis::{Basis, Domain};
use serde::{Deserialize, Serialize};

use crate::error::{ModelError, TermError};
use crate::terms::{
    Coupling, DriveFactor, MAX_DRIVE_HARMONIC, PositionFactor, Term, TermList, TermSpec, VelocityFactor,
};

/// The longest name of a measured drive's column a form keeps.
const MAX_COLUMN_NAME: usize = 256;

/// Which harmonics `j` of each orbit give equations (paper eq. 15: `j = 1..M`, plus the mean).
///
/// Harmonic `j` of a period-`k` orbit has `j / k` times the forcing frequency. Harmonics at or above
/// the Nyquist frequency of the segment (`j >= L/2` for `L = kP` samples) are never used.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", try_from = "HarmonicsRaw")]
#[non_exhaustive]
pub enum Harmonics {
    /// `j = 1..=M` for every orbit, whatever its period (the paper's fixed `M`).
    Fixed(usize),
    /// Every `j` with `j / k <= cap`: the same band of frequencies, up to `cap` times the drive
    /// frequency, for every orbit (`M_k = floor(cap k)`). Saved as `forcing_cap`, the name files
    /// have always had.
    #[serde(rename = "forcing_cap")]
    DriveCap(f64),
}

impl Harmonics {
    /// The default, [`Harmonics::DriveCap`]`(3.0)`: every orbit is balanced over the same band of
    /// frequencies, up to three times the forcing frequency. See `docs/identification.md` for the
    /// measurements behind the choice.
    pub const DEFAULT: Self = Self::DriveCap(3.0);

    /// Checks the value: `M >= 1`, or a cap `>= 1` (so that a period-1 orbit has a harmonic).
    pub fn validate(self) -> Result<Self, ModelError> {
        match self {
            Self::Fixed(0) => Err(ModelError::InvalidParameter {
                name: "harmonics M",
                value: 0.0,
                why: "must be at least 1",
            }),
            Self::DriveCap(c) if !(c.is_finite() && c >= 1.0) => Err(ModelError::InvalidParameter {
                name: "harmonic cap",
                value: c,
                why: "must be finite and at least 1 (times the forcing frequency)",
            }),
            ok => Ok(ok),
        }
    }

    /// The band widened to reach drive harmonic `highest`: a cap below `highest` forcing
    /// harmonics is raised to it, so that a term driven at `highest` times the forcing frequency
    /// is balanced at its own frequency (a band that stops short of it sees such a term only
    /// through a window's leakage, or not at all, and a selection drops it as if it were absent).
    /// A cap already above, a fixed `M` and `highest = 0` are left as they are.
    ///
    /// ```
    /// use hb_model::Harmonics;
    ///
    /// assert_eq!(Harmonics::DriveCap(2.0).reaching(3), Harmonics::DriveCap(3.0));
    /// assert_eq!(Harmonics::DriveCap(3.0).reaching(2), Harmonics::DriveCap(3.0));
    /// assert_eq!(Harmonics::Fixed(6).reaching(5), Harmonics::Fixed(6));
    /// ```
    pub fn reaching(self, highest: u32) -> Self {
        match self {
            Self::DriveCap(c) if c < f64::from(highest) => Self::DriveCap(f64::from(highest)),
            other => other,
        }
    }

    /// Number of harmonics `M_k` used for a period-`k` orbit of `len` samples.
    pub fn count(self, period: usize, len: usize) -> usize {
        let below_nyquist = len.saturating_sub(1) / 2;
        let m = match self {
            Self::Fixed(m) => m,
            // A small allowance so that e.g. cap 1.0 with k = 3 gives exactly 3.
            Self::DriveCap(c) => (c * period as f64 + 1e-9).floor() as usize,
        };
        m.min(below_nyquist)
    }
}

/// The serialised form of [`Harmonics`], validated on reading.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(rename_all = "snake_case")]
enum HarmonicsRaw {
    Fixed(usize),
    #[serde(rename = "forcing_cap")]
    DriveCap(f64),
}

impl TryFrom<HarmonicsRaw> for Harmonics {
    type Error = ModelError;

    fn try_from(raw: HarmonicsRaw) -> Result<Self, ModelError> {
        match raw {
            HarmonicsRaw::Fixed(m) => Self::Fixed(m),
            HarmonicsRaw::DriveCap(c) => Self::DriveCap(c),
        }
        .validate()
    }
}

impl Default for Harmonics {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// An external forcing term `d_1 p(t) = F_c cos(W t) + F_s sin(W t)` (paper eq. 2).
///
/// Its coefficients have the same meaning whether identified or known: they are the coefficients of
/// the terms `cos(t)` and `sin(t)` in the model's sum, which stands on the same side as `x''`:
/// `x'' + c_r x' + ... + F_c cos(W t) + F_s sin(W t) = 0`. An oscillator written
/// `x'' + 0.1 x' + 2 x = cos t` has `F_c = −1`, `F_s = 0`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Forcing {
    /// No external forcing term (the pendulum: `d_1 = 0`).
    #[default]
    None,
    /// `F_c` and `F_s` are unknowns (terms `cos(t)`, `sin(t)`).
    Identified,
    /// `F_c` and `F_s` are known (a measured forcing) and moved to the right-hand side.
    Known {
        /// `F_c`, the coefficient of `cos(W t)`.
        cos: f64,
        /// `F_s`, the coefficient of `sin(W t)`.
        sin: f64,
    },
}

/// The terms of the model: a preset (paper eq. 2 specialised as in eq. 6) or a list of terms.
///
/// The presets are
///
/// `c_r x' + [k x] + Σ_i q_i φ_i(x) + [Σ_i Σ_k (n_ik cos kW t + p_ik sin kW t) φ_i(x)] + [Σ_k (F_ck cos kW t + F_sk sin kW t)] = −x''`
///
/// with the drive harmonics `k = 1..H` (`H = 1` unless [`ModelForm::with_drive_harmonics`]). The
/// default is the paper's eq. 6 for the pendulum: damping, autonomous and parametric terms, no
/// external forcing, no separate linear stiffness, `H = 1`.
///
/// [`ModelForm::from_terms`] gives the terms instead, in their order, any product of a drive
/// factor, a function of `x` and a function of `x'` ([`TermList`]); a known forcing
/// ([`ModelForm::with_forcing`]`(Forcing::Known { .. })`) may be added to a list, the other
/// preset switches may not (checked when the form is used: `hb_solve::IdentifyParamsBuilder::build`,
/// [`crate::IdentifiedModel::new`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "ModelFormRaw", into = "ModelFormRaw")]
pub struct ModelForm {
    parametric: bool,
    forcing: Forcing,
    linear_stiffness: bool,
    drive_harmonics: u32,
    terms: Option<TermList>,
    drive_column: Option<String>,
}

/// The serialised form of [`ModelForm`] (the same field names as ever, and the drive harmonics,
/// the term list and the measured drive's column, absent from forms saved before them),
/// validated on reading.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct ModelFormRaw {
    parametric: bool,
    forcing: Forcing,
    linear_stiffness: bool,
    #[serde(default = "one")]
    drive_harmonics: u32,
    #[serde(default)]
    terms: Option<TermList>,
    #[serde(default)]
    drive_column: Option<String>,
}

/// [`ModelForm`] as saved by format version 3 (its binary layout: no measured drive's column),
/// read by [`crate::IdentifiedModel::from_bytes`].
#[derive(Debug, Clone, Serialize, Deserialize)]
pub(crate) struct ModelFormV3 {
    parametric: bool,
    forcing: Forcing,
    linear_stiffness: bool,
    drive_harmonics: u32,
    terms: Option<TermList>,
}

impl From<ModelFormV3> for ModelFormRaw {
    fn from(v3: ModelFormV3) -> Self {
        Self {
            parametric: v3.parametric,
            forcing: v3.forcing,
            linear_stiffness: v3.linear_stiffness,
            drive_harmonics: v3.drive_harmonics,
            terms: v3.terms,
            drive_column: None,
        }
    }
}

impl TryFrom<ModelFormV3> for ModelForm {
    type Error = ModelError;

    fn try_from(v3: ModelFormV3) -> Result<Self, ModelError> {
        ModelFormRaw::from(v3).try_into()
    }
}

fn one() -> u32 {
    1
}

/// [`ModelForm`] as saved by format version 2 (its binary layout), read by
/// [`crate::IdentifiedModel::from_bytes`].
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
pub(crate) struct ModelFormV2 {
    parametric: bool,
    forcing: Forcing,
    linear_stiffness: bool,
}

impl From<ModelFormV2> for ModelForm {
    fn from(v2: ModelFormV2) -> Self {
        Self {
            parametric: v2.parametric,
            forcing: v2.forcing,
            linear_stiffness: v2.linear_stiffness,
            drive_harmonics: 1,
            terms: None,
            drive_column: None,
        }
    }
}

impl From<ModelForm> for ModelFormRaw {
    fn from(f: ModelForm) -> Self {
        Self {
            parametric: f.parametric,
            forcing: f.forcing,
            linear_stiffness: f.linear_stiffness,
            drive_harmonics: f.drive_harmonics,
            terms: f.terms,
            drive_column: f.drive_column,
        }
    }
}

impl TryFrom<ModelFormRaw> for ModelForm {
    type Error = ModelError;

    fn try_from(raw: ModelFormRaw) -> Result<Self, ModelError> {
        Self {
            parametric: raw.parametric,
            forcing: raw.forcing,
            linear_stiffness: raw.linear_stiffness,
            drive_harmonics: raw.drive_harmonics,
            terms: raw.terms,
            drive_column: raw.drive_column,
        }
        .validate()
    }
}

impl Default for ModelForm {
    fn default() -> Self {
        Self::parametric()
    }
}

impl ModelForm {
    /// Paper eq. 6: damping, autonomous and parametric terms.
    pub fn parametric() -> Self {
        Self {
            parametric: true,
            forcing: Forcing::None,
            linear_stiffness: false,
            drive_harmonics: 1,
            terms: None,
            drive_column: None,
        }
    }

    /// A non-parametric oscillator with external forcing (e.g. Duffing): damping, autonomous terms
    /// and the forcing given.
    pub fn externally_forced(forcing: Forcing) -> Self {
        Self {
            parametric: false,
            forcing,
            linear_stiffness: false,
            drive_harmonics: 1,
            terms: None,
            drive_column: None,
        }
    }

    /// The terms of `list`, in its order (no preset term, no external forcing unless a known one
    /// is added with [`with_forcing`](Self::with_forcing)).
    ///
    /// ```
    /// use hb_model::{ModelForm, TermList, term_names};
    ///
    /// let form = ModelForm::from_terms(TermList::parse("x', sign(x'), {1, sin(t), sin(2t)}*sin(x)")?);
    /// let names = term_names(&hb_basis::Harmonic::new(1)?, &form);
    /// assert_eq!(names, ["x'", "sign(x')", "sin(x)", "sin(t)*sin(x)", "sin(2t)*sin(x)"]);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn from_terms(list: TermList) -> Self {
        Self {
            parametric: false,
            forcing: Forcing::None,
            linear_stiffness: false,
            drive_harmonics: 1,
            terms: Some(list),
            drive_column: None,
        }
    }

    /// The same form with the name of the record's column its measured drive `p` was read from
    /// (kept with the model, so that whoever simulates it knows which signal drives it). Only a
    /// term list with a term in `p` has one (checked when the form is used).
    pub fn with_drive_column(mut self, column: impl Into<String>) -> Self {
        self.drive_column = Some(column.into());
        self
    }

    /// The same form with this external forcing.
    pub fn with_forcing(mut self, forcing: Forcing) -> Self {
        self.forcing = forcing;
        self
    }

    /// The same form with a linear stiffness term `k*x`.
    pub fn with_linear_stiffness(mut self) -> Self {
        self.linear_stiffness = true;
        self
    }

    /// The same form without the parametric terms `cos(kt)*B`, `sin(kt)*B`.
    pub fn without_parametric_terms(mut self) -> Self {
        self.parametric = false;
        self
    }

    /// The same preset with the drive harmonics `k = 1..h`: the parametric terms `cos(kt)*B`,
    /// `sin(kt)*B` and an identified forcing `cos(kt)`, `sin(kt)` for each (`1 <= h <=`
    /// [`MAX_DRIVE_HARMONIC`]; a known forcing stays the first harmonic's). `h = 1` is the paper's.
    pub fn with_drive_harmonics(mut self, h: u32) -> Self {
        self.drive_harmonics = h;
        self
    }

    /// Whether the parametric terms `cos(kt)*B` (`n_i`) and `sin(kt)*B` (`p_i`) are in the preset,
    /// for each basis function `B` (false for a term list).
    pub fn is_parametric(&self) -> bool {
        self.parametric
    }

    /// The external forcing term.
    pub fn forcing(&self) -> Forcing {
        self.forcing
    }

    /// Whether a linear stiffness term `k*x` is in the model (on the line only; meaningful only
    /// when the basis does not already contain `x`, otherwise the system is rank deficient and
    /// identification says so).
    pub fn has_linear_stiffness(&self) -> bool {
        self.linear_stiffness
    }

    /// The drive harmonics `H` of the preset (1 for a term list, whose terms say their own).
    pub fn drive_harmonics(&self) -> u32 {
        self.drive_harmonics
    }

    /// The highest multiple `k` of the drive's frequency in a term's drive factor (`cos(kt)`,
    /// `sin(kt)`): a list's highest, a preset's `H` when it has parametric terms or an identified
    /// forcing, 1 for a known forcing alone, 0 without any (the measured drive `p` counts 0: it is
    /// balanced as measured).
    pub fn highest_drive_harmonic(&self) -> u32 {
        if let Some(list) = &self.terms {
            return list.drive_harmonics();
        }
        let forcing = match self.forcing {
            Forcing::None => 0,
            Forcing::Known { .. } => 1,
            Forcing::Identified => self.drive_harmonics,
        };
        let parametric = if self.parametric { self.drive_harmonics } else { 0 };
        forcing.max(parametric)
    }

    /// The list of terms, when the form is one.
    pub fn terms(&self) -> Option<&TermList> {
        self.terms.as_ref()
    }

    /// The form's terms on `basis` as a list, in column order: the list itself for a form made
    /// from one, a preset's columns ([`columns`]) named by their factors otherwise. A known
    /// forcing stays with the form (it is not a term).
    ///
    /// ```
    /// use hb_model::{Forcing, ModelForm};
    ///
    /// let form = ModelForm::parametric().with_forcing(Forcing::Identified);
    /// let list = form.term_list(&hb_basis::Harmonic::new(1)?)?;
    /// assert_eq!(list.to_string(), "x', cos(t)*cos(x), sin(t)*cos(x), cos(x), cos(t)*sin(x), sin(t)*sin(x), sin(x), cos(t), sin(t)");
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    ///
    /// Errors: those of [`columns`], and `ModelError::Term(TermError::InvalidForm)` for the linear stiffness
    /// `k*x` of a preset, which has no name of its own in a list.
    pub fn term_list<B: Basis + ?Sized>(&self, basis: &B) -> Result<TermList, ModelError> {
        if let Some(list) = &self.terms {
            list.resolve(basis)?;
            return Ok(list.clone());
        }
        let names = basis.names();
        let specs = columns(basis, self)?
            .iter()
            .map(|t| {
                let function = match t.position {
                    PositionFactor::One => None,
                    PositionFactor::Basis(i) => names
                        .get(i)
                        .and_then(|n| n.parse::<TermSpec>().ok())
                        .and_then(|s| s.function),
                    PositionFactor::Linear => None,
                };
                match (t.position, function) {
                    (PositionFactor::One, _) | (_, Some(_)) => Ok(TermSpec {
                        drive: t.drive,
                        function,
                        velocity: t.velocity,
                        coupling: t.coupling,
                    }),
                    _ => Err(ModelError::Term(TermError::InvalidForm {
                        why: "the linear stiffness k*x of a preset has no name in a list of terms: \
                              list the terms, with x on the polynomial basis",
                    })),
                }
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(TermList::new(specs)?)
    }

    /// Whether a term of the form has the measured drive `p` (a term list only).
    pub fn has_measured_drive(&self) -> bool {
        self.terms.as_ref().is_some_and(TermList::has_measured_drive)
    }

    /// The record's column the measured drive `p` was read from, when given.
    pub fn drive_column(&self) -> Option<&str> {
        self.drive_column.as_deref()
    }

    /// Checks the form: a known forcing finite, a drive column only with a term in `p`, the drive
    /// harmonics in `1..=64`, and a list of terms without the presets' switches.
    pub fn validate(self) -> Result<Self, ModelError> {
        if let Forcing::Known { cos, sin } = self.forcing {
            for (name, value) in [
                ("known forcing cos coefficient", cos),
                ("known forcing sin coefficient", sin),
            ] {
                if !value.is_finite() {
                    return Err(ModelError::InvalidParameter {
                        name,
                        value,
                        why: "must be finite",
                    });
                }
            }
        }
        if let Some(column) = &self.drive_column {
            if !self.has_measured_drive() {
                return Err(ModelError::Term(TermError::InvalidForm {
                    why: "a measured drive's column is named but no term has the factor p",
                }));
            }
            if column.is_empty() || column.chars().count() > MAX_COLUMN_NAME {
                return Err(ModelError::Term(TermError::InvalidForm {
                    why: "the measured drive's column name must have 1 to 256 characters",
                }));
            }
        }
        if !(1..=MAX_DRIVE_HARMONIC).contains(&self.drive_harmonics) {
            return Err(ModelError::InvalidParameter {
                name: "drive harmonics H",
                value: f64::from(self.drive_harmonics),
                why: "must be between 1 and 64",
            });
        }
        if let Some(list) = &self.terms {
            let why = if self.parametric {
                Some("a term list says its parametric terms itself")
            } else if self.linear_stiffness {
                Some("a term list says its terms itself (x, the first power, on the polynomial basis)")
            } else if self.drive_harmonics != 1 {
                Some("a term list says its drive harmonics itself")
            } else if self.forcing == Forcing::Identified {
                Some("a term list says its forcing terms itself (cos(t), sin(t))")
            } else if matches!(self.forcing, Forcing::Known { .. })
                && list.terms().iter().any(|t| {
                    t.function.is_none()
                        && t.velocity == VelocityFactor::One
                        && matches!(t.drive, DriveFactor::Cos(1) | DriveFactor::Sin(1))
                })
            {
                Some("a known forcing is cos(t) and sin(t) already; the list names them too")
            } else {
                None
            };
            if let Some(why) = why {
                return Err(ModelError::Term(TermError::InvalidForm { why }));
            }
        }
        Ok(self)
    }
}

// ---------------------------------------------------------------------------------------------
// Column layout.

/// The column families of the assemblies and of a model's evaluation: the paper's (eq. 6 and an
/// external forcing at the drive's first harmonic), each with a fast path, and any other product
/// of factors.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Column {
    /// `c_r`, term `x'`.
    Damping,
    /// `n_i`, term `cos(t)*φ_i`.
    CosT(usize),
    /// `p_i`, term `sin(t)*φ_i`.
    SinT(usize),
    /// `q_i`, term `φ_i`.
    Auto(usize),
    /// `F_c`, term `cos(t)`.
    ForcingCos,
    /// `F_s`, term `sin(t)`.
    ForcingSin,
    /// `k`, term `k*x`.
    Stiffness,
    /// Any other term.
    Product(Term),
}

impl Column {
    /// The column family of `term`.
    pub fn of(term: &Term) -> Column {
        use DriveFactor as D;
        use PositionFactor as X;
        use VelocityFactor as V;
        if !term.coupling.is_empty() {
            return Column::Product(*term);
        }
        match (term.drive, term.position, term.velocity) {
            (D::One, X::One, V::Linear) => Column::Damping,
            (D::Cos(1), X::Basis(i), V::One) => Column::CosT(i),
            (D::Sin(1), X::Basis(i), V::One) => Column::SinT(i),
            (D::One, X::Basis(i), V::One) => Column::Auto(i),
            (D::Cos(1), X::One, V::One) => Column::ForcingCos,
            (D::Sin(1), X::One, V::One) => Column::ForcingSin,
            (D::One, X::Linear, V::One) => Column::Stiffness,
            _ => Column::Product(*term),
        }
    }

    /// Whether the column is one of the paper's families (every layout before general terms).
    pub fn is_paper(&self) -> bool {
        !matches!(self, Column::Product(_))
    }
}

/// The unknowns of a preset form with `functions` basis functions, in column order: `x'`; then
/// for each basis function `B` the terms `cos(kt)*B`, `sin(kt)*B` for `k = 1..H` (if parametric)
/// and `B` (the paper's order n, p, q); then `cos(kt)`, `sin(kt)` for `k = 1..H` (identified
/// forcing) and `k*x` (linear stiffness).
fn preset_columns(functions: usize, form: &ModelForm) -> Vec<Term> {
    let h = form.drive_harmonics();
    let mut t = vec![Term::DAMPING];
    for i in 0..functions {
        if form.is_parametric() {
            for k in 1..=h {
                t.push(Term::basis(DriveFactor::Cos(k), i));
                t.push(Term::basis(DriveFactor::Sin(k), i));
            }
        }
        t.push(Term::basis(DriveFactor::One, i));
    }
    if form.forcing() == Forcing::Identified {
        for k in 1..=h {
            t.push(Term::drive(DriveFactor::Cos(k)));
            t.push(Term::drive(DriveFactor::Sin(k)));
        }
    }
    if form.has_linear_stiffness() {
        t.push(Term {
            drive: DriveFactor::One,
            position: PositionFactor::Linear,
            velocity: VelocityFactor::One,
            coupling: Coupling::NONE,
        });
    }
    t
}

/// The unknowns of a model on `basis` with `form`, in column order: the form's term list resolved
/// on the basis ([`TermList::resolve`]), or for a preset form `x'`; then for each basis function
/// `B` the terms `cos(kt)*B`, `sin(kt)*B` for drive harmonics `k = 1..H` (if parametric) and `B`
/// (the paper's order n, p, q); then `cos(kt)`, `sin(kt)` (identified forcing) and `k*x` (linear
/// stiffness). With `H = 1` (the default) this is the paper's layout.
///
/// Errors: those of [`TermList::resolve`], and `ModelError::Term(TermError::TermNotAllowed)` for `k*x` on the
/// circle.
pub fn columns<B: Basis + ?Sized>(basis: &B, form: &ModelForm) -> Result<Vec<Term>, TermError> {
    check_form(basis.domain(), form)?;
    match form.terms() {
        Some(list) => list.resolve(basis),
        None => Ok(preset_columns(basis.len(), form)),
    }
}

/// The column families of `terms`.
pub fn column_families(terms: &[Term]) -> Vec<Column> {
    terms.iter().map(Column::of).collect()
}

/// The names of the unknowns of a model on `basis` with `form`, in column order (see
/// [`columns`]; a term list's own names when it does not resolve on the basis).
pub fn term_names<B: Basis + ?Sized>(basis: &B, form: &ModelForm) -> Vec<String> {
    match form.terms() {
        Some(list) => list.names(),
        None => {
            let names = basis.names();
            preset_columns(names.len(), form)
                .iter()
                .map(|t| t.name(&names))
                .collect()
        }
    }
}

/// Checks that the form's terms exist on the basis' domain.
pub fn check_form(domain: Domain, form: &ModelForm) -> Result<(), TermError> {
    if form.has_linear_stiffness() && domain == Domain::Circle {
        return Err(TermError::TermNotAllowed {
            term: "k*x".to_owned(),
            domain,
            why: "x is an angle known modulo 2π; put sin(x) or hats in the basis instead",
        });
    }
    if let Some(list) = form.terms() {
        list.check_domain(domain)?;
    }
    Ok(())
}
