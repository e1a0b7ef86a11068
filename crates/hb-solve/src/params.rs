//! Parameters of identification: sampling clock, harmonics per orbit, model form.

use std::fmt;
use std::sync::Arc;

use serde::{Deserialize, Serialize};

pub use circle_signal::SampleClock;

use hb_basis::Basis;

use crate::SolveError;
use crate::terms::{
    DriveFactor, MAX_DRIVE_HARMONIC, PositionFactor, TermList, TermSpec, VelocityFactor, columns,
};

/// The default cap of the velocity series, in multiples of the forcing frequency.
const VELOCITY_CAP: f64 = 16.0;

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
    /// Every `j` with `j / k <= cap`: the same band of frequencies, up to `cap` times the forcing
    /// frequency, for every orbit (`M_k = floor(cap k)`).
    ForcingCap(f64),
}

impl Harmonics {
    /// The default, [`Harmonics::ForcingCap`]`(3.0)`: every orbit is balanced over the same band of
    /// frequencies, up to three times the forcing frequency. See `docs/identification.md` for the
    /// measurements behind the choice.
    pub const DEFAULT: Self = Self::ForcingCap(3.0);

    /// Checks the value: `M >= 1`, or a cap `>= 1` (so that a period-1 orbit has a harmonic).
    pub fn validate(self) -> Result<Self, SolveError> {
        match self {
            Self::Fixed(0) => Err(SolveError::InvalidParameter {
                name: "harmonics M",
                value: 0.0,
                why: "must be at least 1",
            }),
            Self::ForcingCap(c) if !(c.is_finite() && c >= 1.0) => Err(SolveError::InvalidParameter {
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
    /// use hb_solve::Harmonics;
    ///
    /// assert_eq!(Harmonics::ForcingCap(2.0).reaching(3), Harmonics::ForcingCap(3.0));
    /// assert_eq!(Harmonics::ForcingCap(3.0).reaching(2), Harmonics::ForcingCap(3.0));
    /// assert_eq!(Harmonics::Fixed(6).reaching(5), Harmonics::Fixed(6));
    /// ```
    pub fn reaching(self, highest: u32) -> Self {
        match self {
            Self::ForcingCap(c) if c < f64::from(highest) => Self::ForcingCap(f64::from(highest)),
            other => other,
        }
    }

    /// Number of harmonics `M_k` used for a period-`k` orbit of `len` samples.
    pub fn count(self, period: usize, len: usize) -> usize {
        let below_nyquist = len.saturating_sub(1) / 2;
        let m = match self {
            Self::Fixed(m) => m,
            // A small allowance so that e.g. cap 1.0 with k = 3 gives exactly 3.
            Self::ForcingCap(c) => (c * period as f64 + 1e-9).floor() as usize,
        };
        m.min(below_nyquist)
    }
}

/// The serialised form of [`Harmonics`], validated on reading.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(rename_all = "snake_case")]
enum HarmonicsRaw {
    Fixed(usize),
    ForcingCap(f64),
}

impl TryFrom<HarmonicsRaw> for Harmonics {
    type Error = SolveError;

    fn try_from(raw: HarmonicsRaw) -> Result<Self, SolveError> {
        match raw {
            HarmonicsRaw::Fixed(m) => Self::Fixed(m),
            HarmonicsRaw::ForcingCap(c) => Self::ForcingCap(c),
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
/// preset switches may not (checked when the form is used: [`IdentifyParamsBuilder::build`],
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
    type Error = SolveError;

    fn try_from(v3: ModelFormV3) -> Result<Self, SolveError> {
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
    type Error = SolveError;

    fn try_from(raw: ModelFormRaw) -> Result<Self, SolveError> {
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
    /// use hb_solve::{ModelForm, TermList, term_names};
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
    /// use hb_solve::{Forcing, ModelForm};
    ///
    /// let form = ModelForm::parametric().with_forcing(Forcing::Identified);
    /// let list = form.term_list(&hb_basis::Harmonic::new(1)?)?;
    /// assert_eq!(list.to_string(), "x', cos(t)*cos(x), sin(t)*cos(x), cos(x), cos(t)*sin(x), sin(t)*sin(x), sin(x), cos(t), sin(t)");
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    ///
    /// Errors: those of [`columns`], and [`SolveError::InvalidForm`] for the linear stiffness
    /// `k*x` of a preset, which has no name of its own in a list.
    pub fn term_list<B: Basis + ?Sized>(&self, basis: &B) -> Result<TermList, SolveError> {
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
                    }),
                    _ => Err(SolveError::InvalidForm {
                        why: "the linear stiffness k*x of a preset has no name in a list of terms: \
                              list the terms, with x on the polynomial basis",
                    }),
                }
            })
            .collect::<Result<Vec<_>, _>>()?;
        TermList::new(specs)
    }

    /// Whether a term of the form has the measured drive `p` (a term list only).
    pub fn has_measured_drive(&self) -> bool {
        self.terms.as_ref().is_some_and(TermList::has_measured_drive)
    }

    /// The record's column the measured drive `p` was read from, when given.
    pub fn drive_column(&self) -> Option<&str> {
        self.drive_column.as_deref()
    }

    pub(crate) fn validate(self) -> Result<Self, SolveError> {
        if let Forcing::Known { cos, sin } = self.forcing {
            for (name, value) in [
                ("known forcing cos coefficient", cos),
                ("known forcing sin coefficient", sin),
            ] {
                if !value.is_finite() {
                    return Err(SolveError::InvalidParameter {
                        name,
                        value,
                        why: "must be finite",
                    });
                }
            }
        }
        if let Some(column) = &self.drive_column {
            if !self.has_measured_drive() {
                return Err(SolveError::InvalidForm {
                    why: "a measured drive's column is named but no term has the factor p",
                });
            }
            if column.is_empty() || column.chars().count() > MAX_COLUMN_NAME {
                return Err(SolveError::InvalidForm {
                    why: "the measured drive's column name must have 1 to 256 characters",
                });
            }
        }
        if !(1..=MAX_DRIVE_HARMONIC).contains(&self.drive_harmonics) {
            return Err(SolveError::InvalidParameter {
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
                return Err(SolveError::InvalidForm { why });
            }
        }
        Ok(self)
    }
}

/// Correction of the bias that Gaussian noise on a measured angle puts into the trigonometric
/// terms.
///
/// A measured angle `y = x + n` with Gaussian noise `n ~ N(0, σ²)` gives
/// `E[cos(k y)] = e^{−k²σ²/2} cos(k x)` and `E[sin(k y)] = e^{−k²σ²/2} sin(k x)`: every column of
/// the system that holds a harmonic `cos(kx)` or `sin(kx)` of the angle (alone or times `cos(W t)`,
/// `sin(W t)`, the time being exact) is on average the true column shrunk by `e^{−k²σ²/2}`, and its
/// coefficient comes out inflated by `e^{k²σ²/2}` (2 % at `σ = 0.2` rad for `k = 1`). The
/// correction multiplies those columns by `e^{k²σ²/2}` after assembly, which removes the bias in
/// the mean. The derivative terms are linear in the data and need no correction.
///
/// It applies to bases on the circle whose functions are single harmonics (the harmonic basis);
/// with another basis, or on the line, identification fails with
/// [`SolveError::NoiseCorrectionUnavailable`] rather than correct wrongly.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", try_from = "NoiseCorrectionRaw")]
#[non_exhaustive]
pub enum NoiseCorrection {
    /// No correction (the default).
    #[default]
    None,
    /// The noise standard deviation `σ` of the angle, in radians, is known.
    Given {
        /// `σ >= 0`, radians.
        sigma: f64,
    },
    /// `σ` is estimated from the record's highest frequencies ([`crate::estimate_noise_sigma`]).
    Estimated,
}

/// The serialised form of [`NoiseCorrection`], validated on reading.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(rename_all = "snake_case")]
enum NoiseCorrectionRaw {
    None,
    Given { sigma: f64 },
    Estimated,
}

impl TryFrom<NoiseCorrectionRaw> for NoiseCorrection {
    type Error = SolveError;

    fn try_from(raw: NoiseCorrectionRaw) -> Result<Self, SolveError> {
        match raw {
            NoiseCorrectionRaw::None => Self::None,
            NoiseCorrectionRaw::Given { sigma } => Self::Given { sigma },
            NoiseCorrectionRaw::Estimated => Self::Estimated,
        }
        .validate()
    }
}

impl NoiseCorrection {
    /// Checks that a given `σ` is finite and not negative.
    pub fn validate(self) -> Result<Self, SolveError> {
        match self {
            Self::Given { sigma } if !(sigma.is_finite() && sigma >= 0.0) => {
                Err(SolveError::InvalidParameter {
                    name: "noise sigma",
                    value: sigma,
                    why: "must be finite and not negative (radians)",
                })
            }
            ok => Ok(ok),
        }
    }
}

/// Reads a correction as the command line gives it: `auto` ([`NoiseCorrection::Estimated`]),
/// `none`, or the standard deviation `σ` in radians ([`NoiseCorrection::Given`], checked).
///
/// ```
/// use hb_solve::NoiseCorrection;
///
/// assert_eq!("auto".parse::<NoiseCorrection>()?, NoiseCorrection::Estimated);
/// assert_eq!("0.01".parse::<NoiseCorrection>()?, NoiseCorrection::Given { sigma: 0.01 });
/// assert!("-1".parse::<NoiseCorrection>().is_err() && "x".parse::<NoiseCorrection>().is_err());
/// # Ok::<(), hb_solve::SolveError>(())
/// ```
impl std::str::FromStr for NoiseCorrection {
    type Err = SolveError;

    fn from_str(s: &str) -> Result<Self, SolveError> {
        match s.trim() {
            "auto" => Ok(Self::Estimated),
            "none" => Ok(Self::None),
            text => match text.parse::<f64>() {
                Ok(sigma) => Self::Given { sigma }.validate(),
                Err(_) => Err(SolveError::InvalidText {
                    name: "noise sigma",
                    text: text.to_owned(),
                    expected: "a number of radians, auto or none",
                }),
            },
        }
    }
}

/// The text [`str::parse`] reads back: `auto`, `none` or `σ`.
impl fmt::Display for NoiseCorrection {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::None => f.write_str("none"),
            Self::Estimated => f.write_str("auto"),
            Self::Given { sigma } => write!(f, "{sigma}"),
        }
    }
}

/// The samples of a measured drive `p(t)` (the factor `p` of a term), one per sample of the
/// record it was measured with and on the same grid (NaN where the record has gaps, which no
/// segment reaches): what a term in `p` is balanced from.
///
/// Shared, not copied, when the params are cloned. Its samples are data, not settings: they are
/// not serialised with the params (which then deserialise without them).
#[derive(Clone, PartialEq)]
pub struct DriveSamples {
    samples: Arc<[f64]>,
}

impl DriveSamples {
    /// The drive's `samples`, aligned with the record's (sample `n` of both at the same time).
    ///
    /// Errors: [`SolveError::RecordTooShort`] for no sample. Non-finite samples are refused where
    /// a segment reaches them ([`SolveError::NonFiniteDriveSample`]).
    pub fn new(samples: impl Into<Arc<[f64]>>) -> Result<Self, SolveError> {
        let samples = samples.into();
        if samples.is_empty() {
            return Err(SolveError::RecordTooShort {
                what: "a measured drive",
                len: 0,
                needed: 1,
            });
        }
        Ok(Self { samples })
    }

    /// The samples.
    pub fn as_slice(&self) -> &[f64] {
        &self.samples
    }

    /// The number of samples.
    pub fn len(&self) -> usize {
        self.samples.len()
    }

    /// Never true: there is at least one sample.
    pub fn is_empty(&self) -> bool {
        self.samples.is_empty()
    }
}

impl fmt::Debug for DriveSamples {
    /// The number of samples, not the samples (a record holds millions).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("DriveSamples")
            .field("len", &self.samples.len())
            .finish()
    }
}

/// Everything identification needs besides the basis, the record and the segments: the settings,
/// and the samples of a measured drive when a term has the factor `p`.
///
/// Build with [`IdentifyParams::builder`]; [`IdentifyParamsBuilder::build`] validates.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "IdentifyParamsRaw")]
pub struct IdentifyParams {
    clock: SampleClock,
    harmonics: Harmonics,
    form: ModelForm,
    #[serde(default)]
    noise: NoiseCorrection,
    #[serde(default = "default_velocity_harmonics")]
    velocity_harmonics: Harmonics,
    #[serde(skip)]
    drive: Option<DriveSamples>,
}

fn default_velocity_harmonics() -> Harmonics {
    IdentifyParams::DEFAULT_VELOCITY_HARMONICS
}

/// The serialised form of [`IdentifyParams`], built through its builder on reading.
#[derive(Debug, Clone, Deserialize)]
struct IdentifyParamsRaw {
    clock: SampleClock,
    harmonics: Harmonics,
    form: ModelForm,
    #[serde(default)]
    noise: NoiseCorrection,
    #[serde(default = "default_velocity_harmonics")]
    velocity_harmonics: Harmonics,
}

impl TryFrom<IdentifyParamsRaw> for IdentifyParams {
    type Error = SolveError;

    fn try_from(raw: IdentifyParamsRaw) -> Result<Self, SolveError> {
        IdentifyParams::builder(raw.clock)
            .harmonics(raw.harmonics)
            .form(raw.form)
            .noise_correction(raw.noise)
            .velocity_harmonics(raw.velocity_harmonics)
            .build()
    }
}

/// Builder of [`IdentifyParams`].
#[derive(Debug, Clone, PartialEq)]
pub struct IdentifyParamsBuilder {
    clock: SampleClock,
    harmonics: Harmonics,
    form: ModelForm,
    noise: NoiseCorrection,
    velocity_harmonics: Harmonics,
    drive: Option<DriveSamples>,
}

impl IdentifyParams {
    /// The default harmonics of the velocity series, [`Harmonics::ForcingCap`]`(VELOCITY_CAP)`:
    /// the velocity that the nonlinear functions of `x'` (`sign(x')`, `x'*|x'|`, `x'^3`) are
    /// evaluated at is the derivative of a segment's Fourier series up to this many times the
    /// forcing frequency (see `docs/identification.md` for the measurements behind the choice).
    pub const DEFAULT_VELOCITY_HARMONICS: Harmonics = Harmonics::ForcingCap(VELOCITY_CAP);

    /// A builder with the record's clock and the defaults: [`Harmonics::DEFAULT`],
    /// [`ModelForm::parametric`], no [`NoiseCorrection`] and
    /// [`DEFAULT_VELOCITY_HARMONICS`](Self::DEFAULT_VELOCITY_HARMONICS).
    pub fn builder(clock: SampleClock) -> IdentifyParamsBuilder {
        IdentifyParamsBuilder {
            clock,
            harmonics: Harmonics::DEFAULT,
            form: ModelForm::default(),
            noise: NoiseCorrection::None,
            velocity_harmonics: Self::DEFAULT_VELOCITY_HARMONICS,
            drive: None,
        }
    }

    /// The sampling clock.
    pub fn clock(&self) -> &SampleClock {
        &self.clock
    }

    /// The harmonics per orbit.
    pub fn harmonics(&self) -> Harmonics {
        self.harmonics
    }

    /// The model form.
    pub fn form(&self) -> &ModelForm {
        &self.form
    }

    /// The correction for noise on the angle.
    pub fn noise_correction(&self) -> NoiseCorrection {
        self.noise
    }

    /// The harmonics of the velocity series of a segment (see
    /// [`DEFAULT_VELOCITY_HARMONICS`](Self::DEFAULT_VELOCITY_HARMONICS)); used only by terms
    /// nonlinear in `x'`.
    pub fn velocity_harmonics(&self) -> Harmonics {
        self.velocity_harmonics
    }

    /// The samples of the measured drive `p`, when given.
    pub fn drive_samples(&self) -> Option<&DriveSamples> {
        self.drive.as_ref()
    }
}

impl IdentifyParamsBuilder {
    /// Harmonics per orbit.
    pub fn harmonics(mut self, harmonics: Harmonics) -> Self {
        self.harmonics = harmonics;
        self
    }

    /// Model form.
    pub fn form(mut self, form: ModelForm) -> Self {
        self.form = form;
        self
    }

    /// Correction for Gaussian noise on the angle (default: none).
    pub fn noise_correction(mut self, noise: NoiseCorrection) -> Self {
        self.noise = noise;
        self
    }

    /// Harmonics of the velocity series for the terms nonlinear in `x'` (default:
    /// [`IdentifyParams::DEFAULT_VELOCITY_HARMONICS`]).
    pub fn velocity_harmonics(mut self, harmonics: Harmonics) -> Self {
        self.velocity_harmonics = harmonics;
        self
    }

    /// The samples of the measured drive `p` of the form's terms, aligned with the record's
    /// (checked against the record and the segments by every assembly).
    pub fn drive_samples(mut self, drive: DriveSamples) -> Self {
        self.drive = Some(drive);
        self
    }

    /// Validates and builds.
    pub fn build(self) -> Result<IdentifyParams, SolveError> {
        Ok(IdentifyParams {
            clock: self.clock,
            harmonics: self.harmonics.validate()?,
            form: self.form.validate()?,
            noise: self.noise.validate()?,
            velocity_harmonics: self.velocity_harmonics.validate()?,
            drive: self.drive,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::TAU;

    #[test]
    fn clock() {
        let c = SampleClock::nondimensional(25)
            .unwrap()
            .with_start_time(10.0)
            .unwrap();
        assert!((c.forcing_frequency() - 1.0).abs() < 1e-15);
        assert!((c.time(25) - (10.0 + TAU)).abs() < 1e-12);
        let c = SampleClock::new(0.5, 100).unwrap();
        assert!((c.forcing_frequency() - 4.0 * std::f64::consts::PI).abs() < 1e-12);
        assert!((c.step() - 0.005).abs() < 1e-15);
        assert!(SampleClock::new(0.0, 25).is_err());
        assert!(SampleClock::new(1.0, 1).is_err());
        assert!(
            SampleClock::new(1.0, 25)
                .unwrap()
                .with_start_time(f64::NAN)
                .is_err()
        );
    }

    #[test]
    fn harmonic_counts() {
        assert_eq!(Harmonics::Fixed(12).count(1, 25), 12);
        assert_eq!(Harmonics::Fixed(12).count(1, 24), 11);
        assert_eq!(Harmonics::Fixed(3).count(16, 400), 3);
        assert_eq!(Harmonics::ForcingCap(1.0).count(3, 75), 3);
        assert_eq!(Harmonics::ForcingCap(2.5).count(2, 50), 5);
        assert_eq!(Harmonics::ForcingCap(20.0).count(1, 25), 12);
        assert!(Harmonics::Fixed(0).validate().is_err());
        assert!(Harmonics::ForcingCap(0.5).validate().is_err());
        assert!(Harmonics::ForcingCap(f64::NAN).validate().is_err());
    }

    #[test]
    fn params_validate() {
        let clock = SampleClock::nondimensional(25).unwrap();
        assert!(
            IdentifyParams::builder(clock)
                .harmonics(Harmonics::Fixed(0))
                .build()
                .is_err()
        );
        let bad = ModelForm::externally_forced(Forcing::Known {
            cos: f64::NAN,
            sin: 0.0,
        });
        assert!(IdentifyParams::builder(clock).form(bad).build().is_err());
        assert!(IdentifyParams::builder(clock).build().is_ok());
        for sigma in [-0.1, f64::NAN, f64::INFINITY] {
            let noise = NoiseCorrection::Given { sigma };
            assert!(
                IdentifyParams::builder(clock)
                    .noise_correction(noise)
                    .build()
                    .is_err()
            );
        }
        let noise = NoiseCorrection::Given { sigma: 0.1 };
        let params = IdentifyParams::builder(clock)
            .noise_correction(noise)
            .build()
            .unwrap();
        assert_eq!(params.noise_correction(), noise);
    }

    #[test]
    fn deserialising_validates() {
        let h: Harmonics = serde_json::from_str(r#"{"forcing_cap":2.0}"#).unwrap();
        assert_eq!(h, Harmonics::ForcingCap(2.0));
        for bad in [r#"{"fixed":0}"#, r#"{"forcing_cap":0.5}"#] {
            assert!(serde_json::from_str::<Harmonics>(bad).is_err(), "{bad}");
        }
        assert!(serde_json::from_str::<NoiseCorrection>(r#"{"given":{"sigma":-1.0}}"#).is_err());
        assert_eq!(
            serde_json::from_str::<NoiseCorrection>(r#""estimated""#).unwrap(),
            NoiseCorrection::Estimated
        );
        assert!(serde_json::from_str::<crate::WeakForm>(r#"{"window_order":1}"#).is_err());
        let b = crate::BootstrapParams::builder().resamples(100).build().unwrap();
        let json = serde_json::to_string(&b).unwrap();
        assert_eq!(serde_json::from_str::<crate::BootstrapParams>(&json).unwrap(), b);
        let bad = json.replace("0.95", "1.5");
        assert!(bad != json && serde_json::from_str::<crate::BootstrapParams>(&bad).is_err());
        let p = IdentifyParams::builder(SampleClock::nondimensional(25).unwrap())
            .build()
            .unwrap();
        let json = serde_json::to_string(&p).unwrap();
        assert_eq!(serde_json::from_str::<IdentifyParams>(&json).unwrap(), p);
        let bad = json.replace(r#""forcing_cap":3.0"#, r#""forcing_cap":0.0"#);
        assert!(bad != json && serde_json::from_str::<IdentifyParams>(&bad).is_err());
    }
}
