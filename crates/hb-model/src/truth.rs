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
//! # Example
//!
//! ```
//! use hb_model::truth::TrueEquation;
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
use pendulum_sim::{Duffing, Losses, Pendulum, RecordFrame};

use crate::error::ModelError;
use crate::form::{ModelForm, columns};
use crate::model::IdentifiedModel;
use crate::terms::{DriveFactor, TermList, TermSpec, VelocityFactor, XFunction};

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
/// use hb_model::truth::pendulum_model;
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
