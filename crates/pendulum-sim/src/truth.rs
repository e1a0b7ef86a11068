//! The true equation of the simulated systems in the identification's terms, written once: what
//! `hbid simulate --truth` writes, what the tests compare identified models with, and the model
//! the true system is measured as ([`Equation::model`]).
//!
//! The identification writes a model as `ẍ + Σ c_i g_i(t, x, ẋ) = 0`, each term `g_i` a
//! product of a drive factor, a function of `x` and a function of `ẋ` ([`TermSpec`]), `t` in a
//! term standing for the drive's phase in the record's time. A system of `pendulum_sim` seen in a
//! record's frame ([`RecordFrame`]: `τ = rate · t + phase`, `x = θ − offset`) has the equation
//! `ẍ = rate² · F(rate · t + phase, x + offset, ẋ / rate)`: damping scales with `rate`, stiffness
//! and drive with `rate²`, a drive phase turns `sin(t)` into `sin(t)` and `cos(t)` parts, and an
//! offset turns `sin(x)` into `sin(x)` and `cos(x)` parts. A rig's losses scale with the power of
//! the velocity they hold: `μ sign(x')` with `W²`, `d x'|x'|` not at all, `c₃ x'^3` with `1/W`;
//! harmonic `k` of the drive has its phase `k φ + φ_k` at the record's `t = 0`.
//!
//! A system of several coordinates gives its equations in the same grammar itself
//! (`pendulum_sim`'s `normalised_equations`, written in the simulator's names `q1`, `x2`, `tau1`);
//! [`system_equations`] reads them into a record's names and frame by the same rules, term by
//! term: a coefficient scales with `rate` to the power two less the degree of its velocities and
//! twice its accelerations, and a `cos` or `sin` of the drive's phase or of the angles is
//! turned by the frame's phase and offset into its `cos` and `sin` parts.
//!
//! # Example
//!
//! ```
//! use pendulum_sim::truth::TrueEquation;
//! use pendulum_sim::{Pendulum, RecordFrame};
//!
//! // The paper's pendulum on a rig driven at 1.02 Hz, time in seconds.
//! let frame = RecordFrame::nondimensional().with_drive_frequency(1.02)?;
//! let truth = Pendulum::paper().equation(&frame)?;
//! let w = std::f64::consts::TAU * 1.02;
//! assert!((truth.value("x'").unwrap() - 0.03 * w).abs() < 1e-15);
//! assert!((truth.value("sin(t)*cos(x)").unwrap() + 1.52 * w * w).abs() < 1e-12);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use hb_basis::Basis;
use hb_model::terms::{Coupling, DriveFactor, Factor, Names, TermList, TermSpec, VelocityFactor, XFunction};
use hb_model::{IdentifiedModel, ModelError, ModelForm, TermError, columns};

use crate::{Duffing, Losses, NormalisedEquation, Pendulum, RecordFrame};

/// An equation `ẍ + Σ c_i g_i = 0`: its terms, in order, and their coefficients.
#[derive(Debug, Clone, PartialEq)]
pub struct Equation {
    terms: TermList,
    values: Vec<f64>,
}

impl Equation {
    /// The equation of `terms` with their coefficients (as many as the terms).
    pub fn new(terms: Vec<(TermSpec, f64)>) -> Result<Self, ModelError> {
        let (specs, values): (Vec<TermSpec>, Vec<f64>) = terms.into_iter().unzip();
        Ok(Self {
            terms: TermList::new(specs)?,
            values,
        })
    }

    /// The equation of `terms` with their coefficients for the equation of coordinate `own` of a
    /// record with `names`.
    pub fn new_in(terms: Vec<(TermSpec, f64)>, names: Names, own: usize) -> Result<Self, ModelError> {
        let (specs, values): (Vec<TermSpec>, Vec<f64>) = terms.into_iter().unzip();
        Ok(Self {
            terms: TermList::new_in(specs, names, own)?,
            values,
        })
    }

    /// The terms, in order.
    pub fn terms(&self) -> &TermList {
        &self.terms
    }

    /// The coefficients, in the order of the terms.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// Every term's name (as the identification prints it) with its coefficient.
    pub fn named(&self) -> Vec<(String, f64)> {
        self.terms
            .names()
            .into_iter()
            .zip(self.values.iter().copied())
            .collect()
    }

    /// The coefficient of the term named `name`, if the equation has it.
    pub fn value(&self, name: &str) -> Option<f64> {
        self.terms
            .names()
            .iter()
            .position(|n| n == name)
            .map(|i| self.values[i])
    }

    /// The equation as a model on `basis` with drive angular frequency `w` (radians per time
    /// unit), every standard error 0: in the layout of `preset` when every term of the equation
    /// is one of the preset's columns on the basis (the others 0), so that the true system is
    /// evaluated with the arithmetic of the identified models of that preset; as a list of its
    /// own terms otherwise (a rig's losses and drive harmonics included, never dropped).
    pub fn model<B: Basis>(
        &self,
        basis: B,
        preset: &ModelForm,
        w: f64,
    ) -> Result<IdentifiedModel<B>, ModelError> {
        let names = basis.names();
        if let Ok(layout) = columns(&basis, preset) {
            let layout: Vec<String> = layout.iter().map(|t| t.name(&names)).collect();
            let own = self.terms.names();
            if own.iter().all(|n| layout.contains(n)) {
                let values: Vec<f64> = layout
                    .iter()
                    .map(|n| own.iter().position(|o| o == n).map_or(0.0, |i| self.values[i]))
                    .collect();
                return IdentifiedModel::new(basis, preset.clone(), w, &values);
            }
        }
        IdentifiedModel::new(basis, ModelForm::from_terms(self.terms.clone()), w, &self.values)
    }
}

/// The true model of `pendulum` in its own frame (non-dimensional time, drive angular frequency
/// one) on the harmonic basis of order one in the paper's layout ([`ModelForm::parametric`]):
/// `x'` is `c`, `sin(t)*cos(x)` is `−f`, `sin(x)` is `1/r²` and the other parametric terms 0,
/// bit for bit, and a rig's losses and drive harmonics are terms of their own (then as a list of
/// terms): the reference every identified pendulum model is compared with.
///
/// ```
/// use hb_basis::Harmonic;
/// use pendulum_sim::truth::pendulum_model;
/// use pendulum_sim::Pendulum;
///
/// let truth = pendulum_model::<Harmonic>(&Pendulum::paper())?;
/// assert_eq!(truth.damping(), 0.03);
/// assert_eq!(truth.coefficient("sin(t)*cos(x)").unwrap().value, -1.52);
/// assert_eq!(truth.coefficient("sin(x)").unwrap().value, 1.0 / (0.8333 * 0.8333));
/// # Ok::<(), hb_model::ModelError>(())
/// ```
pub fn pendulum_model<B: Basis + From<hb_basis::Harmonic>>(
    pendulum: &Pendulum,
) -> Result<IdentifiedModel<B>, ModelError> {
    pendulum.equation(&RecordFrame::nondimensional())?.model(
        B::from(hb_basis::Harmonic::new(1)?),
        &ModelForm::parametric(),
        1.0,
    )
}

/// A system whose equation is known, in the identification's terms.
pub trait TrueEquation {
    /// The system's equation in `frame`.
    fn equation(&self, frame: &RecordFrame) -> Result<Equation, ModelError>;
}

/// `-0.0` read as `0.0`, so that an absent term prints as `0`.
fn plain(v: f64) -> f64 {
    v + 0.0
}

/// `a · b`, exactly 0 when `b` is (a part that the frame's phase or offset does not make, even
/// of an infinite `a`).
fn part(a: f64, b: f64) -> f64 {
    if b == 0.0 { 0.0 } else { a * b }
}

/// A term of a drive factor, a function of `x` and a function of `x'`.
fn term(drive: DriveFactor, function: Option<XFunction>, velocity: VelocityFactor) -> TermSpec {
    TermSpec::of_one(drive, function, velocity)
}

/// The terms of the losses in a frame of rate `w`, those that are not zero: `sign(x')` = `μ W²`,
/// `x'*|x'|` = `d` and `x'^3` = `c₃ / W` (the velocity in the record's unit is `W` times the
/// system's, the acceleration `W²` times).
fn loss_terms(losses: &Losses, w: f64) -> Vec<(TermSpec, f64)> {
    [
        (
            VelocityFactor::Sign,
            losses.friction(),
            losses.friction() * (w * w),
        ),
        (VelocityFactor::Quadratic, losses.drag(), losses.drag()),
        (
            VelocityFactor::Cubic,
            losses.cubic_damping(),
            losses.cubic_damping() / w,
        ),
    ]
    .into_iter()
    .filter(|&(_, given, _)| given != 0.0)
    .map(|(velocity, _, value)| (term(DriveFactor::One, None, velocity), plain(value)))
    .collect()
}

impl TrueEquation for Pendulum {
    /// The seven terms of the harmonic basis of order 1 with parametric terms, in the
    /// identification's column order: `x'`, `cos(t)*cos(x)`, `sin(t)*cos(x)`, `cos(x)`,
    /// `cos(t)*sin(x)`, `sin(t)*sin(x)`, `sin(x)`. In the system's own frame they are `c`, 0, `−f`,
    /// 0, 0, 0, `1/r²` (bit for bit); in a frame of rate `W`, drive phase `φ` and offset `o`,
    /// `x'` is `c W`, `sin(x)` and `cos(x)` are `(W²/r²)(cos o, sin o)`, and the drive
    /// `−f W² sin(t + φ) cos(x + o)` spreads over the four parametric terms.
    ///
    /// Then, for a rig, the losses that are not zero (`sign(x')` = `μ W²`, `x'*|x'|` = `d`,
    /// `x'^3` = `c₃ / W`) and for each harmonic `k` of the base acceleration with a non-zero
    /// ratio `ρ_k` the four terms `cos(kt)*cos(x)`, `sin(kt)*cos(x)`, `cos(kt)*sin(x)`,
    /// `sin(kt)*sin(x)` of `−f ρ_k W² sin(k t + k φ + φ_k) cos(x + o)`.
    fn equation(&self, frame: &RecordFrame) -> Result<Equation, ModelError> {
        use DriveFactor::{Cos, One, Sin};
        use VelocityFactor::{Linear, One as Still};
        let (cos_x, sin_x) = (Some(XFunction::Cos(1)), Some(XFunction::Sin(1)));
        let w = frame.rate();
        let w2 = w * w;
        let stiffness = w2 / (self.r() * self.r());
        let drive = -(self.f() * w2);
        let (sin_phi, cos_phi) = frame.phase().sin_cos();
        let (sin_o, cos_o) = frame.offset().sin_cos();
        let mut out: Vec<(TermSpec, f64)> = [
            (term(One, None, Linear), self.c() * w),
            (term(Cos(1), cos_x, Still), part(drive, sin_phi * cos_o)),
            (term(Sin(1), cos_x, Still), part(drive, cos_phi * cos_o)),
            (term(One, cos_x, Still), part(stiffness, sin_o)),
            (term(Cos(1), sin_x, Still), part(-drive, sin_phi * sin_o)),
            (term(Sin(1), sin_x, Still), part(-drive, cos_phi * sin_o)),
            (term(One, sin_x, Still), part(stiffness, cos_o)),
        ]
        .into_iter()
        .map(|(t, v)| (t, plain(v)))
        .collect();
        out.extend(loss_terms(self.losses(), w));
        for h in self.drive_harmonics().iter().filter(|h| h.ratio() != 0.0) {
            let k = h.k();
            let drive_k = drive * h.ratio();
            let (sin_psi, cos_psi) = (f64::from(k) * frame.phase() + h.phase()).sin_cos();
            out.extend([
                (term(Cos(k), cos_x, Still), plain(drive_k * sin_psi * cos_o)),
                (term(Sin(k), cos_x, Still), plain(drive_k * cos_psi * cos_o)),
                (term(Cos(k), sin_x, Still), plain(-drive_k * sin_psi * sin_o)),
                (term(Sin(k), sin_x, Still), plain(-drive_k * cos_psi * sin_o)),
            ]);
        }
        Equation::new(out)
    }
}

impl TrueEquation for Duffing {
    /// The terms of the polynomial basis that the equation uses: `x'` = `c W`, `x` = `a W²`,
    /// `x^3` = `b W²`, and the drive `−f W² cos(t + φ)` as `cos(t)` = `−f W² cos φ` and
    /// `sin(t)` = `f W² sin φ`.
    ///
    /// Then, for a rig, the losses that are not zero and for each harmonic `k` of the forcing
    /// with a non-zero ratio `ρ_k` the terms `cos(kt)` = `−f ρ_k W² cos ψ` and `sin(kt)` =
    /// `f ρ_k W² sin ψ`, `ψ = k φ + φ_k`.
    ///
    /// Errors: a non-zero offset (a shifted displacement needs a constant term, which the
    /// equation has not).
    fn equation(&self, frame: &RecordFrame) -> Result<Equation, ModelError> {
        use DriveFactor::{Cos, One, Sin};
        use VelocityFactor::{Linear, One as Still};
        if frame.offset() != 0.0 {
            return Err(ModelError::InvalidParameter {
                name: "zero offset",
                value: frame.offset(),
                why: "must be 0 for a displacement on the line: a shift adds a constant term",
            });
        }
        let w = frame.rate();
        let w2 = w * w;
        let drive = -(self.f() * w2);
        let (sin_phi, cos_phi) = frame.phase().sin_cos();
        let mut out: Vec<(TermSpec, f64)> = [
            (term(One, None, Linear), self.c() * w),
            (term(One, Some(XFunction::Power(1)), Still), self.a() * w2),
            (term(One, Some(XFunction::Power(3)), Still), self.b() * w2),
            (term(Cos(1), None, Still), drive * cos_phi),
            (term(Sin(1), None, Still), -drive * sin_phi),
        ]
        .into_iter()
        .map(|(t, v)| (t, plain(v)))
        .collect();
        out.extend(loss_terms(self.losses(), w));
        for h in self.drive_harmonics().iter().filter(|h| h.ratio() != 0.0) {
            let k = h.k();
            let drive_k = drive * h.ratio();
            let (sin_psi, cos_psi) = (f64::from(k) * frame.phase() + h.phase()).sin_cos();
            out.extend([
                (term(Cos(k), None, Still), plain(drive_k * cos_psi)),
                (term(Sin(k), None, Still), plain(-drive_k * sin_psi)),
            ]);
        }
        Equation::new(out)
    }
}

/// The true equations of a system of several coordinates, one per coordinate in order, read
/// from the simulator's `equations` (each `q_i'' + Σ c g = 0` in the simulator's names and
/// non-dimensional time) into a record's `names` (its coordinates and measured drives, in the
/// simulator's order) and `frame` (`τ = rate · t + phase`, each coordinate `x_c = q_c − offset`):
///
/// - a term's coefficient is multiplied by `rate^(2 − d)`, `d` the degree of its velocities
///   (`x'` 1, `x'^2` and `x'*|x'|` 2, `x'^3` 3, `sign(x')` 0) plus 2 for an acceleration and 2 for a
///   measured drive (written in the record as an acceleration is, `rate²` times the system's): a
///   damping scales with the rate, a stiffness or a drive with its square, a centrifugal term or
///   another coordinate's acceleration not at all;
/// - `cos(kt)`, `sin(kt)` of the drive's phase turn by `k · phase`, and `cos`, `sin` of an angle or
///   of a combination `Σ a_c q_c` by `offset · Σ a_c`, each into its `cos` and `sin` parts
///   (`sin(A + δ) = sin A cos δ + cos A sin δ`), a product into every product of its parts;
///   nothing turns by an angle of zero, so that a record in the simulator's own frame has the
///   simulator's terms and coefficients bit for bit;
/// - a power of a difference, `(x1-x2)^3`, which the grammar does not write, is written out by
///   the binomial theorem (`x1^3`, `x1^2*x2`, `x1*x2^2`, `x2^3`);
/// - terms that turn out equal are summed, in the order they first appear.
///
/// The simulator's names are those of its accelerations (`q1''` names `q1`) and, for the measured
/// drives, the terms that are a name alone other than a coordinate's (`tau1`, `p`), in the order
/// they first appear.
///
/// Errors: `names` with not as many coordinates or drives, a term the grammar does not read,
/// and an offset of a coordinate the term holds a power or a hat of (a shifted position on the
/// line needs lower powers, which the equation has not).
///
/// ```
/// use hb_model::Names;
/// use pendulum_sim::truth::system_equations;
/// use pendulum_sim::{DoublePendulum, RecordFrame};
///
/// let pendulum = DoublePendulum::whirling();
/// let names = Names::new(["theta1", "theta2"], Vec::<String>::new())?;
/// let frame = RecordFrame::nondimensional().with_drive_frequency(2.0)?;
/// let truth = system_equations(&pendulum.normalised_equations(), &names, &frame)?;
/// let w = std::f64::consts::TAU * 2.0;
/// assert_eq!(truth[0].value("theta1'"), Some(0.05 * w));
/// assert_eq!(truth[0].value("sin(theta1-theta2)*theta2'^2"), Some(0.5));
/// assert!((truth[1].value("sin(theta2)").unwrap() - 0.8 * w * w).abs() < 1e-12);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn system_equations(
    equations: &[NormalisedEquation],
    names: &Names,
    frame: &RecordFrame,
) -> Result<Vec<Equation>, ModelError> {
    let source = simulator_names(equations)?;
    if names.coordinates().len() != source.coordinates().len()
        || names.drives().len() != source.drives().len()
    {
        return Err(ModelError::Term(TermError::BadName {
            name: [names.coordinates(), names.drives()].concat().join(","),
            why: "a system's record names each of its coordinates and measured drives once",
        }));
    }
    equations
        .iter()
        .enumerate()
        .map(|(own, equation)| {
            let mut terms: Vec<(TermSpec, f64)> = Vec::new();
            for (name, value) in &equation.terms {
                let (name, value) = (name.as_ref(), *value);
                for (text, multiple) in written_out(name) {
                    let list = TermList::from_names_in(&[text], &source, own)?;
                    for (spec, factor) in in_frame(list.terms()[0], frame)? {
                        let v = value * multiple * factor;
                        match terms.iter_mut().find(|(s, _)| *s == spec) {
                            Some((_, sum)) => *sum += v,
                            None => terms.push((spec, v)),
                        }
                    }
                }
            }
            let terms = terms.into_iter().map(|(s, v)| (s, plain(v))).collect();
            Equation::new_in(terms, names.clone(), own)
        })
        .collect()
}

/// The names the simulator writes its equations in: the coordinates of the accelerations, the
/// measured drives the terms that are a name alone other than a coordinate's.
fn simulator_names(equations: &[NormalisedEquation]) -> Result<Names, ModelError> {
    let coordinates: Vec<&str> = equations
        .iter()
        .map(|e| e.acceleration.strip_suffix("''").unwrap_or(e.acceleration))
        .collect();
    let mut drives: Vec<&str> = Vec::new();
    for (name, _) in equations.iter().flat_map(|e| &e.terms) {
        let alone = name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
        let name = name.as_ref();
        if alone && !coordinates.contains(&name) && !drives.contains(&name) {
            drives.push(name);
        }
    }
    Ok(Names::new(coordinates, drives)?)
}

/// `name` as terms of the grammar with their multiples: itself, or a power of a sum or
/// difference of two names written out by the binomial theorem.
fn written_out(name: &str) -> Vec<(String, f64)> {
    let binomial = || -> Option<Vec<(String, f64)>> {
        let (inside, power) = name.strip_prefix('(')?.split_once(")^")?;
        let n: i32 = power.parse().ok().filter(|n| (1..=8).contains(n))?;
        let at = inside
            .char_indices()
            .skip(1)
            .find(|&(_, c)| c == '+' || c == '-')?
            .0;
        let (a, b) = (inside[..at].trim(), inside[at + 1..].trim());
        let sign = if inside[at..].starts_with('-') { -1.0 } else { 1.0 };
        let power_of = |q: &str, k: i32| match k {
            0 => None,
            1 => Some(q.to_owned()),
            k => Some(format!("{q}^{k}")),
        };
        let mut out = Vec::new();
        let mut choose = 1.0;
        for i in 0..=n {
            let parts: Vec<String> = [power_of(a, n - i), power_of(b, i)]
                .into_iter()
                .flatten()
                .collect();
            out.push((parts.join("*"), choose * f64::powi(sign, i)));
            choose = choose * f64::from(n - i) / f64::from(i + 1);
        }
        Some(out)
    };
    binomial().unwrap_or_else(|| vec![(name.to_owned(), 1.0)])
}

/// The degree of a velocity factor: how many velocities it multiplies (`sign` none).
fn velocity_degree(v: VelocityFactor) -> i32 {
    match v {
        VelocityFactor::One | VelocityFactor::Sign => 0,
        VelocityFactor::Linear => 1,
        VelocityFactor::Square | VelocityFactor::Quadratic => 2,
        VelocityFactor::Cubic => 3,
    }
}

/// A `cos` or `sin` a frame turns: which one, by how much.
#[derive(Clone, Copy)]
enum Turned {
    /// The drive factor, turned by `k · phase`.
    Drive(u32, f64),
    /// The function of the own coordinate, turned by `k · offset`.
    Own(u32, f64),
    /// The coupling factor of this index, turned by `offset · Σ a_c`.
    Coupling(usize, f64),
}

/// The term `spec` in `frame`: the terms it becomes with their factors.
fn in_frame(spec: TermSpec, frame: &RecordFrame) -> Result<Vec<(TermSpec, f64)>, ModelError> {
    let (rate, phase, offset) = (frame.rate(), frame.phase(), frame.offset());
    let factors: Vec<Factor> = spec.coupling.factors().copied().collect();
    let mut degree = velocity_degree(spec.velocity);
    if spec.drive.is_measured() {
        degree += 2;
    }
    let mut turned: Vec<Turned> = Vec::new();
    let shifted_line = || ModelError::InvalidParameter {
        name: "zero offset",
        value: offset,
        why: "must be 0 for a position on the line or a hat: a shift adds lower powers",
    };
    if let DriveFactor::Cos(k) | DriveFactor::Sin(k) = spec.drive {
        turned.push(Turned::Drive(k, f64::from(k) * phase));
    }
    match spec.function {
        Some(XFunction::Cos(k) | XFunction::Sin(k)) => turned.push(Turned::Own(k, f64::from(k) * offset)),
        Some(XFunction::Power(_) | XFunction::Hat(_)) if offset != 0.0 => return Err(shifted_line()),
        _ => {}
    }
    for (i, f) in factors.iter().enumerate() {
        match *f {
            Factor::Trig { combination, .. } => {
                let sum: i32 = combination.terms().map(|(_, a)| a).sum();
                turned.push(Turned::Coupling(i, offset * f64::from(sum)));
            }
            Factor::Power { .. } if offset != 0.0 => return Err(shifted_line()),
            Factor::Power { .. } => {}
            Factor::Velocity { function, .. } => degree += velocity_degree(function),
            Factor::Acceleration { .. } => degree += 2,
        }
    }
    // Each product of parts as (drive, own function, coupling factors, factor).
    let mut parts = vec![(spec.drive, spec.function, factors, rate.powi(2 - degree))];
    for turn in turned {
        let angle = match turn {
            Turned::Drive(_, a) | Turned::Own(_, a) | Turned::Coupling(_, a) => a,
        };
        if angle == 0.0 {
            continue;
        }
        let (sin_d, cos_d) = angle.sin_cos();
        let mut next = Vec::with_capacity(2 * parts.len());
        for (drive, function, factors, m) in parts {
            // Whether the factor is a sine, and the term with it made the other function.
            let (sine, flipped) = match turn {
                Turned::Drive(k, _) => {
                    let sine = matches!(drive, DriveFactor::Sin(_));
                    let other = if sine {
                        DriveFactor::Cos(k)
                    } else {
                        DriveFactor::Sin(k)
                    };
                    (sine, (other, function, factors.clone()))
                }
                Turned::Own(k, _) => {
                    let sine = matches!(function, Some(XFunction::Sin(_)));
                    let other = if sine {
                        XFunction::Cos(k)
                    } else {
                        XFunction::Sin(k)
                    };
                    (sine, (drive, Some(other), factors.clone()))
                }
                Turned::Coupling(i, _) => {
                    let Factor::Trig { sine, combination } = factors[i] else {
                        unreachable!("only a cos or sin of angles is turned")
                    };
                    let mut other = factors.clone();
                    other[i] = Factor::Trig {
                        sine: !sine,
                        combination,
                    };
                    (sine, (drive, function, other))
                }
            };
            // cos(A + δ) = cos A cos δ − sin A sin δ;  sin(A + δ) = sin A cos δ + cos A sin δ.
            let other_part = if sine { sin_d } else { -sin_d };
            next.push((drive, function, factors, m * cos_d));
            next.push((flipped.0, flipped.1, flipped.2, m * other_part));
        }
        parts = next;
    }
    parts
        .into_iter()
        .map(|(drive, function, factors, m)| {
            let coupling = Coupling::new(factors).ok_or(ModelError::Term(TermError::InvalidForm {
                why: "a term has too many factors in other coordinates",
            }))?;
            Ok((
                TermSpec {
                    drive,
                    function,
                    velocity: spec.velocity,
                    coupling,
                },
                m,
            ))
        })
        .collect()
}
