//! The identified equation of motion: coefficients, statistics, and its evaluation as a system
//! that `pendulum_sim` simulates.

use circle_signal::system::{Branch, SecondOrderSystem};
use circle_signal::wrap;
use hb_basis::{Basis, BasisKind, Domain};
use serde::{Deserialize, Serialize};

use circle_signal::SampleClock;

use crate::drive::MeasuredDrive;
use crate::error::{ModelError, ModelIoError, TermError};
use crate::form::{Column, Forcing, Harmonics, ModelForm, column_families, columns, term_names};
use crate::terms::{DriveFactor, Factor, PositionFactor, Term, TermList, VelocityFactor};

/// One identified coefficient.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Coefficient {
    /// The term's name (`x'`, `cos(t)*sin(x)`, `hat3`, `k*x`, ...).
    pub name: String,
    /// Its value.
    pub value: f64,
    /// Its standard error (0 for a model built from given values).
    pub std_error: f64,
}

/// How a model was identified.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FitSummary {
    /// The least-squares solver (`qr`, `svd`).
    pub solver: String,
    /// Harmonics per orbit.
    pub harmonics: Harmonics,
    /// The record's sampling clock.
    pub clock: SampleClock,
    /// Equations (rows of the stacked system).
    pub rows: usize,
    /// Unknowns.
    pub unknowns: usize,
    /// Orbit segments used.
    pub segments: usize,
    /// Of which whirling (non-zero winding number).
    pub whirling_segments: usize,
    /// 2-norm condition number of the column-scaled system matrix.
    pub condition: f64,
    /// Residual root mean square of the equations, `sqrt(RSS / rows)`.
    pub residual_rms: f64,
    /// Residual variance `s² = RSS / (rows − unknowns)`.
    pub residual_variance: f64,
}

/// An identified equation of motion `x'' + Σ_i c_i g_i(t, x, x') = 0` (paper eq. 2 / eq. 6 for
/// the presets):
///
/// `x'' = −( c_r x' + k x + Σ_i [q_i + n_i cos(W t) + p_i sin(W t)] φ_i(x) + F_c cos(W t) + F_s sin(W t) )`
///
/// with the terms its [`ModelForm`] has (any product of a drive factor, a function of `x` and a
/// function of `x'` for a term list). On the circle the basis is evaluated at `wrap(x)`. It
/// implements [`SecondOrderSystem`], so it can be simulated and its Lyapunov exponents estimated
/// with the same code as the true system; `t` is the absolute time of the record's clock.
///
/// Saved with [`to_json`](Self::to_json) (for people: coefficients as an object keyed by term
/// name) or [`to_bytes`](Self::to_bytes) (postcard, after a magic number and a version).
///
/// A model with the measured drive `p` (see [`crate::DriveFactor::Measured`]) records the name of
/// the column it came from ([`ModelForm::drive_column`]) but not its samples: to simulate it, give
/// it the recorded drive with [`with_measured_drive`](Self::with_measured_drive), which it
/// interpolates over the recorded span. Without it, or outside that span, its acceleration is
/// NaN (an integrator stops there with a non-finite state); [`needs_measured_drive`](Self::needs_measured_drive)
/// (Self::needs_measured_drive) tells before any simulation.
#[derive(Debug, Clone, PartialEq)]
pub struct IdentifiedModel<B = BasisKind> {
    pub(crate) basis: B,
    pub(crate) form: ModelForm,
    pub(crate) forcing_frequency: f64,
    pub(crate) coefficients: Vec<Coefficient>,
    pub(crate) summary: Option<FitSummary>,
    eval: Evaluation,
    /// The recorded drives, by the index of a term's measured drive factor (empty until given).
    drives: Vec<MeasuredDrive>,
}

/// The coefficients arranged for evaluation: the paper's families by basis function (the
/// arithmetic of every model before general terms, kept so that their simulations do not move by
/// a rounding), or any terms one by one.
#[derive(Debug, Clone, PartialEq)]
enum Evaluation {
    Paper(PaperEvaluation),
    General(GeneralEvaluation),
}

/// The paper's families.
#[derive(Debug, Clone, PartialEq)]
struct PaperEvaluation {
    damping: f64,
    cos_t: Vec<f64>,
    sin_t: Vec<f64>,
    auto: Vec<f64>,
    forcing: (f64, f64),
    stiffness: f64,
}

/// Any terms: `Σ c D(t) F(x) V(x') C(q, q')` over the columns (`C` the factors in other
/// coordinates), and the known forcing.
#[derive(Debug, Clone, PartialEq)]
struct GeneralEvaluation {
    terms: Vec<(f64, Term)>,
    /// The highest drive harmonic of a term.
    harmonics: usize,
    forcing: (f64, f64),
    /// The measured drives a term reads, by index (empty when none does).
    measured: Vec<usize>,
    /// Whether a term has a factor in another coordinate or an acceleration.
    coupled: bool,
    /// The coordinates of the names the terms are written in.
    coordinates: usize,
}

/// The highest drive harmonic is at most [`crate::MAX_DRIVE_HARMONIC`]; this holds `cos(kθ)` and
/// `sin(kθ)` for `k = 0..=64`.
const DRIVE_TABLE: usize = 65;

impl GeneralEvaluation {
    /// `(cos kθ, sin kθ)` for `k = 0..=harmonics`.
    fn drive_table(&self, phase: f64) -> ([f64; DRIVE_TABLE], [f64; DRIVE_TABLE]) {
        let (mut c, mut s) = ([0.0; DRIVE_TABLE], [0.0; DRIVE_TABLE]);
        c[0] = 1.0;
        for k in 1..=self.harmonics.min(DRIVE_TABLE - 1) {
            (s[k], c[k]) = (k as f64 * phase).sin_cos();
        }
        (c, s)
    }
}

/// What [`IdentifiedModel::general_sum`] does with the terms in an acceleration.
enum Mass<'a> {
    /// Adds each to its coordinate's entry of the mass row, besides the sum of the others.
    With(&'a mut [f64]),
    /// Adds each to the mass row, and evaluates no other term.
    Only(&'a mut [f64]),
}

/// The most measured drives read at one instant without an allocation.
const DRIVES: usize = crate::terms::MAX_DRIVES;

/// A drive factor from the table of its harmonics and the measured drives' values.
#[inline]
fn drive_value(d: DriveFactor, c: &[f64; DRIVE_TABLE], s: &[f64; DRIVE_TABLE], p: &[f64; DRIVES]) -> f64 {
    match d {
        DriveFactor::One => 1.0,
        DriveFactor::Cos(k) => c[k as usize],
        DriveFactor::Sin(k) => s[k as usize],
        DriveFactor::Measured(i) => p[usize::from(i)],
    }
}

/// A function of `x` (or its derivative) from the basis' values.
#[inline]
fn position_value(p: PositionFactor, phi: &[f64], x: f64, deriv: bool) -> f64 {
    match (p, deriv) {
        (PositionFactor::One, false) => 1.0,
        (PositionFactor::One, true) => 0.0,
        (PositionFactor::Basis(i), _) => phi[i],
        (PositionFactor::Linear, false) => x,
        (PositionFactor::Linear, true) => 1.0,
    }
}

/// Bases with at most this many functions are evaluated in a stack buffer (no allocation per call).
const STACK: usize = 64;

impl<B: Basis> IdentifiedModel<B> {
    /// A model with given coefficient `values` in the order of [`crate::term_names`] (e.g. the
    /// true system, to compare with an identified one), drive angular frequency `W` and no fit
    /// summary.
    pub fn new(basis: B, form: ModelForm, drive_frequency: f64, values: &[f64]) -> Result<Self, ModelError> {
        let form = form.validate()?;
        let layout = columns(&basis, &form)?;
        let names = term_names(&basis, &form);
        if values.len() != layout.len() {
            return Err(ModelError::Io(ModelIoError::ModelMismatch {
                expected: names,
                found: (0..values.len()).map(|i| format!("value {i}")).collect(),
            }));
        }
        let coefficients = names
            .into_iter()
            .zip(values)
            .map(|(name, &value)| Coefficient {
                name,
                value,
                std_error: 0.0,
            })
            .collect();
        Self::from_coefficients(basis, form, drive_frequency, coefficients, None)
    }

    /// A model of `coefficients` (named as the layout of `basis` and `form` names them, in its
    /// order or a list's), drive angular frequency `drive_frequency` and fit `summary`:
    /// checks the names against the basis and form and arranges the values for evaluation.
    pub fn from_coefficients(
        basis: B,
        form: ModelForm,
        drive_frequency: f64,
        coefficients: Vec<Coefficient>,
        summary: Option<FitSummary>,
    ) -> Result<Self, ModelError> {
        if !(drive_frequency.is_finite() && drive_frequency > 0.0) {
            return Err(ModelError::InvalidParameter {
                name: "forcing frequency",
                value: drive_frequency,
                why: "must be positive and finite",
            });
        }
        // In a preset every basis function has a column of its own besides the damping's: a
        // basis with as many functions as there are coefficients cannot match them, and its
        // names (one string per function, whatever size a file claims) are not listed. A list of
        // terms may name a few functions of a larger basis (`x', sin(x)` on cos(x), sin(x)), but
        // not more than a list holds.
        if form.terms().is_none() && basis.len() >= coefficients.len() {
            return Err(ModelError::InvalidParameter {
                name: "basis size",
                value: basis.len() as f64,
                why: "must be less than the number of coefficients (one per basis function, and the damping)",
            });
        }
        if form.terms().is_some() && basis.len() > crate::MAX_TERMS {
            return Err(ModelError::InvalidParameter {
                name: "basis size",
                value: basis.len() as f64,
                why: "must be at most 4096 functions for a model of listed terms",
            });
        }
        let names = basis.names();
        let terms = columns(&basis, &form)?;
        let expected: Vec<String> = term_names(&basis, &form);
        let layout = column_families(&terms);
        if coefficients.len() != expected.len()
            || coefficients.iter().zip(&expected).any(|(c, e)| &c.name != e)
        {
            return Err(ModelError::Io(ModelIoError::ModelMismatch {
                expected,
                found: coefficients.iter().map(|c| c.name.clone()).collect(),
            }));
        }
        if let Some(c) = coefficients
            .iter()
            .find(|c| !c.value.is_finite() || !c.std_error.is_finite())
        {
            return Err(ModelError::Io(ModelIoError::NonFiniteModelValue {
                name: c.name.clone(),
            }));
        }
        let forcing = match form.forcing() {
            Forcing::Known { cos, sin } => (cos, sin),
            _ => (0.0, 0.0),
        };
        let eval = if layout.iter().all(Column::is_paper) {
            let n = names.len();
            let mut eval = PaperEvaluation {
                damping: 0.0,
                cos_t: vec![0.0; n],
                sin_t: vec![0.0; n],
                auto: vec![0.0; n],
                forcing,
                stiffness: 0.0,
            };
            for (&t, c) in layout.iter().zip(&coefficients) {
                match t {
                    Column::Damping => eval.damping = c.value,
                    Column::CosT(i) => eval.cos_t[i] = c.value,
                    Column::SinT(i) => eval.sin_t[i] = c.value,
                    Column::Auto(i) => eval.auto[i] = c.value,
                    Column::ForcingCos => eval.forcing.0 = c.value,
                    Column::ForcingSin => eval.forcing.1 = c.value,
                    Column::Stiffness => eval.stiffness = c.value,
                    Column::Product(_) => {}
                }
            }
            Evaluation::Paper(eval)
        } else {
            Evaluation::General(GeneralEvaluation {
                terms: coefficients
                    .iter()
                    .map(|c| c.value)
                    .zip(terms.iter().copied())
                    .collect(),
                harmonics: terms
                    .iter()
                    .map(|t| t.drive.harmonic() as usize)
                    .max()
                    .unwrap_or(0),
                forcing,
                measured: form.terms().map(TermList::measured_drives).unwrap_or_default(),
                coupled: terms.iter().any(|t| !t.coupling.is_empty()),
                coordinates: form.terms().map_or(1, |l| l.names_in().coordinates().len()),
            })
        };
        Ok(Self {
            basis,
            form,
            forcing_frequency: drive_frequency,
            coefficients,
            summary,
            eval,
            drives: Vec::new(),
        })
    }

    /// The model with the recorded drive for its terms in the measured drive `p` (the one drive
    /// of a one-coordinate record), so that it can be simulated over the drive's span (the
    /// record's own time).
    ///
    /// Errors: [`TermError::InvalidForm`] for a model without a term in `p`.
    pub fn with_measured_drive(self, signal: MeasuredDrive) -> Result<Self, ModelError> {
        self.with_measured_drives(vec![signal])
    }

    /// The model with the recorded drives of its record, in the order of its names' drives (a
    /// term's measured drive factor is an index into them).
    ///
    /// Errors: [`TermError::InvalidForm`] for a model without a term in a measured drive, or
    /// fewer drives than its terms read.
    pub fn with_measured_drives(mut self, signals: Vec<MeasuredDrive>) -> Result<Self, ModelError> {
        if !self.form.has_measured_drive() {
            return Err(ModelError::Term(TermError::InvalidForm {
                why: "a drive signal is for a model with a term in the measured drive p",
            }));
        }
        let needed = self
            .form
            .terms()
            .map(TermList::measured_drives)
            .and_then(|d| d.last().copied())
            .map_or(0, |d| d + 1);
        if signals.len() < needed {
            return Err(ModelError::Term(TermError::InvalidForm {
                why: "fewer recorded drives than the model's terms read",
            }));
        }
        self.drives = signals;
        Ok(self)
    }

    /// The recorded drive given with [`with_measured_drive`](Self::with_measured_drive) (the
    /// first of [`with_measured_drives`](Self::with_measured_drives)), if any.
    pub fn measured_drive(&self) -> Option<&MeasuredDrive> {
        self.drives.first()
    }

    /// The recorded drives given, in order.
    pub fn measured_drives(&self) -> &[MeasuredDrive] {
        &self.drives
    }

    /// Whether the model needs a measured drive to be simulated: it has a term in a measured
    /// drive and none was given.
    pub fn needs_measured_drive(&self) -> bool {
        self.form.has_measured_drive() && self.drives.is_empty()
    }

    /// The measured drives at `t` that a term reads (NaN without a signal, or outside its
    /// span); the others 0.
    #[inline]
    fn measured(&self, e: &GeneralEvaluation, t: f64) -> [f64; DRIVES] {
        let mut out = [0.0; DRIVES];
        for &d in &e.measured {
            out[d] = self.drives.get(d).map_or(f64::NAN, |signal| signal.at(t));
        }
        out
    }

    /// The damping coefficient `c_r` (term `x'`; 0 when the model has no such term).
    pub fn damping(&self) -> f64 {
        match &self.eval {
            Evaluation::Paper(e) => e.damping,
            Evaluation::General(e) => e
                .terms
                .iter()
                .find(|(_, t)| *t == Term::DAMPING)
                .map_or(0.0, |&(c, _)| c),
        }
    }

    /// All identified coefficients, in column order.
    pub fn coefficients(&self) -> &[Coefficient] {
        &self.coefficients
    }

    /// The coefficient of the term `name`, if the model has it.
    pub fn coefficient(&self, name: &str) -> Option<&Coefficient> {
        self.coefficients.iter().find(|c| c.name == name)
    }

    /// The basis.
    pub fn basis(&self) -> &B {
        &self.basis
    }

    /// Circle or line.
    pub fn domain(&self) -> Domain {
        self.basis.domain()
    }

    /// The model form.
    pub fn form(&self) -> &ModelForm {
        &self.form
    }

    /// Forcing angular frequency `W`.
    pub fn drive_angular_frequency(&self) -> f64 {
        self.forcing_frequency
    }

    /// How the model was identified (`None` for a model built from given values).
    pub fn summary(&self) -> Option<&FitSummary> {
        self.summary.as_ref()
    }

    fn point(&self, x: f64) -> f64 {
        match self.basis.domain() {
            Domain::Circle => wrap(x),
            Domain::Line => x,
        }
    }

    /// Calls `f` with `φ(x)` (or `φ'(x)`) in a buffer, on the stack for small bases.
    fn with_basis<R>(&self, x: f64, deriv: bool, f: impl FnOnce(&[f64]) -> R) -> R {
        let n = self.basis.len();
        let mut stack = [0.0; STACK];
        let mut heap = Vec::new();
        let buf: &mut [f64] = if n <= STACK {
            &mut stack[..n]
        } else {
            heap.resize(n, 0.0);
            &mut heap
        };
        if deriv {
            self.basis.eval_deriv(x, buf)
        } else {
            self.basis.eval(x, buf)
        }
        f(buf)
    }

    /// The autonomous part `f_anl(x) = k x + Σ_i q_i φ_i(x)` (eq. 2, 5): every term without a
    /// drive factor or a function of `x'`.
    pub fn autonomous(&self, x: f64) -> f64 {
        let xe = self.point(x);
        match &self.eval {
            Evaluation::Paper(e) => e.stiffness * xe + self.with_basis(xe, false, |phi| dot(&e.auto, phi)),
            Evaluation::General(e) => self.with_basis(xe, false, |phi| {
                e.terms
                    .iter()
                    .filter(|(_, t)| {
                        t.drive == DriveFactor::One
                            && t.velocity == VelocityFactor::One
                            && t.coupling.is_empty()
                    })
                    .map(|&(c, t)| c * position_value(t.position, phi, xe, false))
                    .sum()
            }),
        }
    }

    /// The parametric parts `(Σ_i n_i φ_i(x), Σ_i p_i φ_i(x))`, the factors of `cos(W t)` and
    /// `sin(W t)` (eq. 4 times the forcing): the terms of a basis function times the drive's first
    /// harmonic, without a function of `x'`.
    pub fn parametric(&self, x: f64) -> (f64, f64) {
        let xe = self.point(x);
        match &self.eval {
            Evaluation::Paper(e) => {
                self.with_basis(xe, false, |phi| (dot(&e.cos_t, phi), dot(&e.sin_t, phi)))
            }
            Evaluation::General(e) => self.with_basis(xe, false, |phi| {
                let mut out = (0.0, 0.0);
                for &(c, t) in e.terms.iter().filter(|(_, t)| t.coupling.is_empty()) {
                    if let (PositionFactor::Basis(i), VelocityFactor::One) = (t.position, t.velocity) {
                        match t.drive {
                            DriveFactor::Cos(1) => out.0 += c * phi[i],
                            DriveFactor::Sin(1) => out.1 += c * phi[i],
                            _ => {}
                        }
                    }
                }
                out
            }),
        }
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

impl<B: Basis> IdentifiedModel<B> {
    #[inline]
    fn acceleration_side(&self, side: Option<f64>, t: f64, x: f64, v: f64) -> f64 {
        let xe = self.point(x);
        match &self.eval {
            Evaluation::Paper(e) => {
                let (s, c) = (self.forcing_frequency * t).sin_cos();
                let basis_part = self.with_basis(xe, false, |phi| {
                    phi.iter()
                        .enumerate()
                        .map(|(i, &p)| p * (e.auto[i] + e.cos_t[i] * c + e.sin_t[i] * s))
                        .sum::<f64>()
                });
                -(e.damping * v + e.stiffness * xe + basis_part + e.forcing.0 * c + e.forcing.1 * s)
            }
            Evaluation::General(e) if e.coupled => {
                // One equation of a system is simulated with the system.
                if e.coordinates != 1 {
                    return f64::NAN;
                }
                // One coordinate with its own acceleration times a function of x: the mass
                // `1 + Σ c f(x)` divides the rest.
                let mut mass = [1.0];
                let rest = self.general_sum(e, &|_| side, t, &[x], &[v], Mass::With(&mut mass));
                -rest / mass[0]
            }
            Evaluation::General(e) => {
                let (dc, ds) = e.drive_table(self.forcing_frequency * t);
                let p = self.measured(e, t);
                let sum = self.with_basis(xe, false, |phi| {
                    e.terms
                        .iter()
                        .map(|&(coefficient, term)| {
                            coefficient
                                * drive_value(term.drive, &dc, &ds, &p)
                                * position_value(term.position, phi, xe, false)
                                * term.velocity.eval_on(side, v)
                        })
                        .sum::<f64>()
                });
                -(sum + e.forcing.0 * dc[1] + e.forcing.1 * ds[1])
            }
        }
    }

    /// `Σ c D(t) F(x_own) V(v_own) C(q, v)` over the terms without an acceleration factor, at the
    /// state `(q, v)` of the whole system (positions as measured, not wrapped), with the known
    /// forcing; the terms with the acceleration of coordinate `j` add their `c D F V C` to
    /// `mass[j]`. `side(c)` is the branch of coordinate `c`'s velocity (its sign's
    /// value) for the factors that switch at rest, `None` for their plain value. With
    /// [`Mass::Only`] only the terms with an acceleration are evaluated (0 is returned).
    fn general_sum(
        &self,
        e: &GeneralEvaluation,
        side: &dyn Fn(usize) -> Option<f64>,
        t: f64,
        q: &[f64],
        v: &[f64],
        mass: Mass<'_>,
    ) -> f64 {
        let (mass, rest) = match mass {
            Mass::With(m) => (m, true),
            Mass::Only(m) => (m, false),
        };
        let own = self.own();
        let xe = self.point(q[own]);
        // What the terms evaluated read: the mass row alone often reads no drive and no
        // function of the own angle (a factor of 1 is 1 whatever the tables); the whole
        // equation reads everything (the known forcing too).
        let evaluated = |term: &Term| rest || term.coupling.acceleration().is_some();
        let reads =
            |f: &dyn Fn(&Term) -> bool| rest || e.terms.iter().any(|(_, term)| evaluated(term) && f(term));
        let (dc, ds) = if reads(&|term| matches!(term.drive, DriveFactor::Cos(_) | DriveFactor::Sin(_))) {
            e.drive_table(self.forcing_frequency * t)
        } else {
            ([0.0; DRIVE_TABLE], [0.0; DRIVE_TABLE])
        };
        let p = if reads(&|term| term.drive.is_measured()) {
            self.measured(e, t)
        } else {
            [0.0; DRIVES]
        };
        let own_side = side(own);
        let mut body = |phi: &[f64]| {
            let mut sum = 0.0;
            for &(coefficient, term) in &e.terms {
                if !evaluated(&term) {
                    continue;
                }
                let mut value = coefficient
                    * drive_value(term.drive, &dc, &ds, &p)
                    * position_value(term.position, phi, xe, false)
                    * term.velocity.eval_on(own_side, v[own]);
                for factor in term.coupling.factors() {
                    value *= match *factor {
                        Factor::Velocity { coordinate, function } => {
                            let c = usize::from(coordinate);
                            function.eval_on(side(c), v[c])
                        }
                        other => other.eval(q, v),
                    };
                }
                match term.coupling.acceleration() {
                    Some(j) => mass[j] += value,
                    None => sum += value,
                }
            }
            sum
        };
        let sum = if reads(&|term| matches!(term.position, PositionFactor::Basis(_))) {
            self.with_basis(xe, false, body)
        } else {
            body(&[])
        };
        if !rest {
            return 0.0;
        }
        sum + e.forcing.0 * dc[1] + e.forcing.1 * ds[1]
    }

    /// The equation at a state of the whole system: writes its row of the mass matrix into
    /// `mass` (the own coordinate's 1 plus the terms in an acceleration, one entry per
    /// coordinate) and returns the sum of its other terms, so that `mass · q'' = −rest`. `q` are
    /// the positions (angles in any branch), `v` the velocities, `sides[c]` the value a factor
    /// `sign(q_c')` takes (±1 on a branch, a held value while `q_c` sticks; `None`: the sign of
    /// `v[c]`). A model needs its measured drives (NaN without).
    ///
    /// ```
    /// use hb_basis::{BasisKind, Harmonic};
    /// use hb_model::{IdentifiedModel, ModelForm, Names, TermList};
    ///
    /// // θ1'' + 0.5 θ2''cos(θ1−θ2) + 2 sin θ1 = 0, the first equation of a two-link system.
    /// let names = Names::new(["theta1", "theta2"], Vec::<String>::new())?;
    /// let terms = TermList::parse_in("theta2''*cos(theta1-theta2), sin(theta1)", &names, 0)?;
    /// let model = IdentifiedModel::new(
    ///     BasisKind::from(Harmonic::new(1)?), ModelForm::from_terms(terms), 1.0, &[0.5, 2.0],
    /// )?;
    /// let mut row = [0.0; 2];
    /// let rest = model.equation_at(0.0, &[0.3, -0.2], &[0.0, 0.0], None, &mut row);
    /// assert_eq!(row, [1.0, 0.5 * 0.5f64.cos()]);
    /// assert!((rest - 2.0 * 0.3f64.sin()).abs() < 1e-15);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn equation_at(&self, t: f64, q: &[f64], v: &[f64], sides: Option<&[f64]>, mass: &mut [f64]) -> f64 {
        mass.fill(0.0);
        let own = self.own();
        mass[own] = 1.0;
        let side = |c: usize| sides.and_then(|s| s.get(c).copied());
        match &self.eval {
            Evaluation::Paper(_) => {
                let a = match side(own) {
                    Some(s) => self.acceleration_side(Some(s), t, q[own], v[own]),
                    None => self.acceleration_side(None, t, q[own], v[own]),
                };
                -a
            }
            Evaluation::General(e) => self.general_sum(e, &side, t, q, v, Mass::With(mass)),
        }
    }

    /// The row of the mass matrix [`equation_at`](Self::equation_at) writes into `mass`, the
    /// same numbers, without the rest of the equation (the terms without an acceleration are not
    /// evaluated).
    pub fn mass_row_at(&self, t: f64, q: &[f64], v: &[f64], sides: Option<&[f64]>, mass: &mut [f64]) {
        mass.fill(0.0);
        mass[self.own()] = 1.0;
        let side = |c: usize| sides.and_then(|s| s.get(c).copied());
        if let Evaluation::General(e) = &self.eval {
            self.general_sum(e, &side, t, q, v, Mass::Only(mass));
        }
    }

    /// The coordinate whose equation this is (0 for a one-coordinate model).
    pub fn own(&self) -> usize {
        self.form.terms().map_or(0, TermList::own)
    }

    /// Whether a term has a factor in another coordinate, or an acceleration: the model is then
    /// one equation of a system, simulated with it.
    pub fn is_coupled(&self) -> bool {
        matches!(&self.eval, Evaluation::General(e) if e.coupled)
    }

    /// Whether a factor of the equation switches at rest in the velocity of coordinate `c`
    /// (`sign(q_c')`, `q_c'*|q_c'|`), with a non-zero coefficient.
    pub fn switches_in(&self, c: usize) -> bool {
        match &self.eval {
            Evaluation::Paper(_) => false,
            Evaluation::General(e) => e.terms.iter().any(|(k, term)| {
                *k != 0.0
                    && ((c == self.own() && term.velocity.switches())
                        || term.coupling.factors().any(|f| {
                            matches!(*f, Factor::Velocity { coordinate, function }
                                if usize::from(coordinate) == c && function.switches())
                        }))
            }),
        }
    }

    #[inline]
    fn jacobian_side(&self, side: Option<f64>, t: f64, x: f64, v: f64) -> [f64; 2] {
        let xe = self.point(x);
        match &self.eval {
            Evaluation::Paper(e) => {
                let (s, c) = (self.forcing_frequency * t).sin_cos();
                let d = self.with_basis(xe, true, |dphi| {
                    dphi.iter()
                        .enumerate()
                        .map(|(i, &p)| p * (e.auto[i] + e.cos_t[i] * c + e.sin_t[i] * s))
                        .sum::<f64>()
                });
                [-(e.stiffness + d), -e.damping]
            }
            Evaluation::General(e) if e.coupled => {
                // By central differences of the acceleration: the mass divides the rest.
                let a = |x: f64, v: f64| self.acceleration_side(side, t, x, v);
                let hx = 1e-6 * x.abs().max(1.0);
                let hv = 1e-6 * v.abs().max(1.0);
                [
                    (a(x + hx, v) - a(x - hx, v)) / (2.0 * hx),
                    (a(x, v + hv) - a(x, v - hv)) / (2.0 * hv),
                ]
            }
            Evaluation::General(e) => {
                let (dc, ds) = e.drive_table(self.forcing_frequency * t);
                let p = self.measured(e, t);
                let (dx, dv) = self.with_basis(xe, false, |phi| {
                    self.with_basis(xe, true, |dphi| {
                        let (mut dx, mut dv) = (0.0, 0.0);
                        for &(coefficient, term) in &e.terms {
                            let cd = coefficient * drive_value(term.drive, &dc, &ds, &p);
                            if term.position != PositionFactor::One {
                                dx += cd
                                    * position_value(term.position, dphi, xe, true)
                                    * term.velocity.eval_on(side, v);
                            }
                            if term.velocity != VelocityFactor::One {
                                dv += cd
                                    * position_value(term.position, phi, xe, false)
                                    * term.velocity.eval_deriv_on(side, v);
                            }
                        }
                        (dx, dv)
                    })
                });
                [-dx, -dv]
            }
        }
    }
}

/// Every model runs through the integrators of `pendulum_sim`; one with `sign(x')` or `x'*|x'|`
/// terms switches at rest, and its branches take `sign(x')` as the branch's sign.
impl<B: Basis> SecondOrderSystem for IdentifiedModel<B> {
    #[inline]
    fn acceleration(&self, t: f64, x: f64, v: f64) -> f64 {
        self.acceleration_side(None, t, x, v)
    }

    #[inline]
    fn jacobian(&self, t: f64, x: f64, v: f64) -> [f64; 2] {
        self.jacobian_side(None, t, x, v)
    }

    fn switches_at_rest(&self) -> bool {
        match &self.eval {
            Evaluation::Paper(_) => false,
            Evaluation::General(_) => self.switches_in(0),
        }
    }

    #[inline]
    fn acceleration_on(&self, branch: Branch, t: f64, x: f64, v: f64) -> f64 {
        self.acceleration_side(Some(branch.sign()), t, x, v)
    }

    #[inline]
    fn jacobian_on(&self, branch: Branch, t: f64, x: f64, v: f64) -> [f64; 2] {
        self.jacobian_side(Some(branch.sign()), t, x, v)
    }
}
