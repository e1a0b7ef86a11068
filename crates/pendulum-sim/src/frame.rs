//! A system seen in a record's own time unit and coordinate, and its true coefficients in the
//! identification's form.
//!
//! The systems of this crate run in non-dimensional time `τ` (drive period `2π`). A rig's record
//! has its own time `t` (seconds) and, for an encoder, its own zero. A [`RecordFrame`] says how
//! the two relate:
//!
//! ```text
//! τ = rate · t + phase,        x = θ − offset,
//! ```
//!
//! with `rate = 2π f_drive` for a drive of `f_drive` Hz (the drive's period is `1 / f_drive` s),
//! `phase` the drive's phase at `t = 0`, and `offset` how far the encoder's zero is from the
//! system's `θ = 0`. Then `dx/dt = rate · dθ/dτ` and `d²x/dt² = rate² · d²θ/dτ²`, so the system
//! `θ'' = F(τ, θ, θ')` reads, in the record's frame,
//!
//! ```text
//! ẍ = rate² · F(rate · t + phase, x + offset, ẋ / rate).
//! ```
//!
//! [`InFrame`] integrates that equation directly (its velocity is in the record's time unit), and
//! [`TrueCoefficients`] writes it in the identification's form `ẍ + Σ c_i g_i(t, x, ẋ) = 0`, the
//! terms named as the identification names them, `t` in a term standing for the drive's phase
//! `rate · t` of the record's time: damping scales with `rate`, stiffness and drive with `rate²`,
//! a drive phase turns `sin(t)` into `sin(t)` and `cos(t)` parts, and an offset turns `sin(x)`
//! into `sin(x)` and `cos(x)` parts. A rig's [`Losses`](crate::Losses) scale with the power of
//! the velocity they hold: `μ sign(x')` with `W²` (the sign does not change), `d x'|x'|` not at
//! all, `c₃ x'^3` with `1/W`; harmonic `k` of the drive is named `cos(kt)`, `sin(kt)` (`2t`,
//! `3t`, …) and its phase at the record's `t = 0` is `k φ + φ_k`.
//!
//! # Example
//!
//! ```
//! use pendulum_sim::{Pendulum, RecordFrame, TrueCoefficients};
//!
//! // The paper's pendulum on a rig driven at 1.02 Hz, time in seconds.
//! let frame = RecordFrame::nondimensional().with_drive_frequency(1.02)?;
//! let truth = Pendulum::paper().coefficients(&frame)?;
//! let w = std::f64::consts::TAU * 1.02;
//! let damping = truth.iter().find(|(name, _)| name == "x'").unwrap().1;
//! assert!((damping - 0.03 * w).abs() < 1e-15);
//! let drive = truth.iter().find(|(name, _)| name == "sin(t)*cos(x)").unwrap().1;
//! assert!((drive + 1.52 * w * w).abs() < 1e-12);
//! # Ok::<(), pendulum_sim::SimError>(())
//! ```

use std::f64::consts::TAU;

use crate::{Branch, Duffing, Pendulum, SecondOrderSystem, SimError};

/// How a record's time and coordinate relate to a system's non-dimensional ones:
/// `τ = rate · t + phase`, `x = θ − offset` (see the [module documentation](self)).
///
/// Built from [`RecordFrame::nondimensional`] (`rate = 1`, `phase = 0`, `offset = 0`: the
/// system's own frame) by the validating setters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RecordFrame {
    rate: f64,
    phase: f64,
    offset: f64,
}

impl Default for RecordFrame {
    fn default() -> Self {
        Self::nondimensional()
    }
}

impl RecordFrame {
    /// The system's own frame: non-dimensional time, no drive phase, no offset.
    pub fn nondimensional() -> Self {
        Self {
            rate: 1.0,
            phase: 0.0,
            offset: 0.0,
        }
    }

    /// `dτ/dt` (positive and finite): the drive's angular frequency in the record's time unit.
    pub fn with_rate(mut self, rate: f64) -> Result<Self, SimError> {
        if !(rate.is_finite() && rate > 0.0) {
            return Err(SimError::InvalidParameter {
                name: "time scale",
                value: rate,
                why: "must be positive and finite",
            });
        }
        self.rate = rate;
        Ok(self)
    }

    /// Time in seconds for a drive of `hz` Hz (positive and finite): `rate = 2π · hz`.
    pub fn with_drive_frequency(self, hz: f64) -> Result<Self, SimError> {
        if !(hz.is_finite() && hz > 0.0) {
            return Err(SimError::InvalidParameter {
                name: "drive frequency",
                value: hz,
                why: "must be positive and finite",
            });
        }
        self.with_rate(TAU * hz)
    }

    /// The drive's phase (radians, finite) at the record's `t = 0`.
    pub fn with_phase(mut self, phase: f64) -> Result<Self, SimError> {
        if !phase.is_finite() {
            return Err(SimError::InvalidParameter {
                name: "drive phase",
                value: phase,
                why: "must be finite",
            });
        }
        self.phase = phase;
        Ok(self)
    }

    /// How far (finite, in the coordinate's unit) the record's zero is from the system's: the
    /// record holds `x = θ − offset`.
    pub fn with_offset(mut self, offset: f64) -> Result<Self, SimError> {
        if !offset.is_finite() {
            return Err(SimError::InvalidParameter {
                name: "zero offset",
                value: offset,
                why: "must be finite",
            });
        }
        self.offset = offset;
        Ok(self)
    }

    /// `dτ/dt`.
    pub fn rate(&self) -> f64 {
        self.rate
    }
    /// The drive's phase at `t = 0`.
    pub fn phase(&self) -> f64 {
        self.phase
    }
    /// The coordinate's offset.
    pub fn offset(&self) -> f64 {
        self.offset
    }
    /// The drive's period in the record's time unit, `2π / rate`.
    pub fn forcing_period(&self) -> f64 {
        TAU / self.rate
    }
    /// The system's time `τ = rate · t + phase` at the record's time `t`.
    pub fn system_time(&self, t: f64) -> f64 {
        self.rate * t + self.phase
    }
}

/// A system in a record's frame: `ẍ = rate² · F(rate · t + phase, x + offset, ẋ / rate)`, so
/// that its solutions are the system's, in the record's time unit and coordinate.
///
/// ```
/// use pendulum_sim::{simulate, InFrame, Pendulum, RecordFrame, SimulationConfig};
///
/// // The paper's pendulum driven at 1.02 Hz, sampled at 500 Hz, time in seconds.
/// let frame = RecordFrame::nondimensional().with_drive_frequency(1.02)?;
/// let config = SimulationConfig::paper()
///     .with_forcing_period(frame.forcing_period())?
///     .with_sample_step(1.0 / 500.0)?
///     .with_transient_periods(5)
///     .with_samples(1000)?;
/// let record = simulate(&InFrame::new(Pendulum::paper(), frame), &config)?;
/// assert!((record.t[1] - record.t[0] - 0.002).abs() < 1e-12);
/// # Ok::<(), pendulum_sim::SimError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InFrame<S> {
    system: S,
    frame: RecordFrame,
}

impl<S> InFrame<S> {
    /// `system` seen in `frame`.
    pub fn new(system: S, frame: RecordFrame) -> Self {
        Self { system, frame }
    }
    /// The system.
    pub fn system(&self) -> &S {
        &self.system
    }
    /// The frame.
    pub fn frame(&self) -> &RecordFrame {
        &self.frame
    }
}

impl<S: SecondOrderSystem> SecondOrderSystem for InFrame<S> {
    #[inline]
    fn acceleration(&self, t: f64, x: f64, v: f64) -> f64 {
        let RecordFrame { rate, phase, offset } = self.frame;
        rate * rate * self.system.acceleration(rate * t + phase, x + offset, v / rate)
    }

    #[inline]
    fn jacobian(&self, t: f64, x: f64, v: f64) -> [f64; 2] {
        let RecordFrame { rate, phase, offset } = self.frame;
        let [jx, jv] = self.system.jacobian(rate * t + phase, x + offset, v / rate);
        [rate * rate * jx, rate * jv]
    }

    fn switches_at_rest(&self) -> bool {
        self.system.switches_at_rest()
    }

    /// The branch is the same in both frames: `rate > 0` keeps the sign of the velocity.
    #[inline]
    fn acceleration_on(&self, branch: Branch, t: f64, x: f64, v: f64) -> f64 {
        let RecordFrame { rate, phase, offset } = self.frame;
        rate * rate
            * self
                .system
                .acceleration_on(branch, rate * t + phase, x + offset, v / rate)
    }

    #[inline]
    fn jacobian_on(&self, branch: Branch, t: f64, x: f64, v: f64) -> [f64; 2] {
        let RecordFrame { rate, phase, offset } = self.frame;
        let [jx, jv] = self
            .system
            .jacobian_on(branch, rate * t + phase, x + offset, v / rate);
        [rate * rate * jx, rate * jv]
    }
}

/// A system whose equation is known: its coefficients in the identification's form.
///
/// The identification writes a model as `ẍ + Σ c_i g_i(t, x, ẋ) = 0`, each term `g_i` named by
/// its factors joined by `*`, the drive factor first (`x'`, `sin(x)`, `sin(t)*cos(x)`, `x^3`,
/// `cos(t)`), `t` in a term standing for the drive's phase in the record's time. This gives the
/// `(name, c_i)` of the system in a [`RecordFrame`]; every term of an identification's layout
/// not listed has the coefficient 0.
pub trait TrueCoefficients {
    /// The coefficients of the system's equation in `frame`, by term name.
    fn coefficients(&self, frame: &RecordFrame) -> Result<Vec<(String, f64)>, SimError>;
}

/// `-0.0` read as `0.0`, so that an absent term prints as `0`.
fn plain(v: f64) -> f64 {
    v + 0.0
}

/// The name of harmonic `k` of the drive's phase: `t`, `2t`, `3t`, ...
fn harmonic(k: u32) -> String {
    if k == 1 { "t".to_owned() } else { format!("{k}t") }
}

/// The terms of the [`Losses`](crate::Losses) in a frame of rate `w`, those that are not zero:
/// `sign(x')` = `μ W²`, `x'*|x'|` = `d` and `x'^3` = `c₃ / W` (the velocity in the record's unit
/// is `W` times the system's, the acceleration `W²` times).
fn loss_terms(losses: &crate::Losses, w: f64) -> Vec<(String, f64)> {
    [
        ("sign(x')", losses.friction(), losses.friction() * (w * w)),
        ("x'*|x'|", losses.drag(), losses.drag()),
        ("x'^3", losses.cubic_damping(), losses.cubic_damping() / w),
    ]
    .into_iter()
    .filter(|&(_, given, _)| given != 0.0)
    .map(|(name, _, value)| (name.to_owned(), plain(value)))
    .collect()
}

impl TrueCoefficients for Pendulum {
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
    /// `sin(kt)*sin(x)` of `−f ρ_k W² sin(k t + k φ + φ_k) cos(x + o)` (`t` standing for the
    /// drive's phase `W t`, so the `k`-th harmonic's phase at the record's `t = 0` is `k φ + φ_k`).
    fn coefficients(&self, frame: &RecordFrame) -> Result<Vec<(String, f64)>, SimError> {
        let w = frame.rate;
        let w2 = w * w;
        let stiffness = w2 / (self.r() * self.r());
        let drive = -(self.f() * w2);
        let (sin_phi, cos_phi) = frame.phase.sin_cos();
        let (sin_o, cos_o) = frame.offset.sin_cos();
        let terms = [
            ("x'", self.c() * w),
            ("cos(t)*cos(x)", drive * sin_phi * cos_o),
            ("sin(t)*cos(x)", drive * cos_phi * cos_o),
            ("cos(x)", stiffness * sin_o),
            ("cos(t)*sin(x)", -drive * sin_phi * sin_o),
            ("sin(t)*sin(x)", -drive * cos_phi * sin_o),
            ("sin(x)", stiffness * cos_o),
        ];
        let mut out: Vec<(String, f64)> = terms.iter().map(|&(n, v)| (n.to_owned(), plain(v))).collect();
        out.extend(loss_terms(self.losses(), w));
        for h in self.drive_harmonics().iter().filter(|h| h.ratio() != 0.0) {
            let k = harmonic(h.k());
            let drive_k = drive * h.ratio();
            let (sin_psi, cos_psi) = (f64::from(h.k()) * frame.phase + h.phase()).sin_cos();
            out.extend([
                (format!("cos({k})*cos(x)"), plain(drive_k * sin_psi * cos_o)),
                (format!("sin({k})*cos(x)"), plain(drive_k * cos_psi * cos_o)),
                (format!("cos({k})*sin(x)"), plain(-drive_k * sin_psi * sin_o)),
                (format!("sin({k})*sin(x)"), plain(-drive_k * cos_psi * sin_o)),
            ]);
        }
        Ok(out)
    }
}

impl TrueCoefficients for Duffing {
    /// The terms of the polynomial basis that the equation uses: `x'` = `c W`, `x` = `a W²`,
    /// `x^3` = `b W²`, and the drive `−f W² cos(t + φ)` as `cos(t)` = `−f W² cos φ` and
    /// `sin(t)` = `f W² sin φ`; `x^2` and the parametric terms are 0.
    ///
    /// Then, for a rig, the losses that are not zero (`sign(x')` = `μ W²`, `x'*|x'|` = `d`,
    /// `x'^3` = `c₃ / W`) and for each harmonic `k` of the forcing with a non-zero ratio `ρ_k`
    /// the terms `cos(kt)` = `−f ρ_k W² cos ψ` and `sin(kt)` = `f ρ_k W² sin ψ`, `ψ = k φ + φ_k`.
    ///
    /// Errors: a non-zero offset (a shifted displacement needs a constant term, which the
    /// identification's form has not).
    fn coefficients(&self, frame: &RecordFrame) -> Result<Vec<(String, f64)>, SimError> {
        if frame.offset != 0.0 {
            return Err(SimError::InvalidParameter {
                name: "zero offset",
                value: frame.offset,
                why: "must be 0 for a displacement on the line: a shift adds a constant term",
            });
        }
        let w = frame.rate;
        let w2 = w * w;
        let drive = -(self.f() * w2);
        let (sin_phi, cos_phi) = frame.phase.sin_cos();
        let terms = [
            ("x'", self.c() * w),
            ("x", self.a() * w2),
            ("x^3", self.b() * w2),
            ("cos(t)", drive * cos_phi),
            ("sin(t)", -drive * sin_phi),
        ];
        let mut out: Vec<(String, f64)> = terms.iter().map(|&(n, v)| (n.to_owned(), plain(v))).collect();
        out.extend(loss_terms(self.losses(), w));
        for h in self.drive_harmonics().iter().filter(|h| h.ratio() != 0.0) {
            let k = harmonic(h.k());
            let drive_k = drive * h.ratio();
            let (sin_psi, cos_psi) = (f64::from(h.k()) * frame.phase + h.phase()).sin_cos();
            out.extend([
                (format!("cos({k})"), plain(drive_k * cos_psi)),
                (format!("sin({k})"), plain(-drive_k * sin_psi)),
            ]);
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{DriveHarmonic, DriveHarmonics, Losses, SimulationConfig, Tolerances, simulate};

    /// The value of a named term at `(t, x, v)` of the record: `t` in a name is the drive's phase
    /// `rate · t`. An independent reading of the names, term by term.
    fn term(name: &str, wt: f64, x: f64, v: f64) -> f64 {
        // `cos(kt)` or `sin(kt)` as (is it a cosine, k).
        let drive = |f: &str| -> Option<(bool, f64)> {
            let (cos, rest) = match (f.strip_prefix("cos("), f.strip_prefix("sin(")) {
                (Some(rest), _) => (true, rest),
                (_, Some(rest)) => (false, rest),
                _ => return None,
            };
            let k = rest.strip_suffix("t)")?;
            let k = if k.is_empty() { 1.0 } else { k.parse().ok()? };
            Some((cos, k))
        };
        let factor = |f: &str| match f {
            "x'" => v,
            "|x'|" => v.abs(),
            "x'^3" => v * v * v,
            "sign(x')" => {
                if v > 0.0 {
                    1.0
                } else if v < 0.0 {
                    -1.0
                } else {
                    0.0
                }
            }
            "x" => x,
            "x^2" => x * x,
            "x^3" => x * x * x,
            "sin(x)" => x.sin(),
            "cos(x)" => x.cos(),
            other => match drive(other) {
                Some((true, k)) => (k * wt).cos(),
                Some((false, k)) => (k * wt).sin(),
                None => panic!("unknown factor {other}"),
            },
        };
        name.split('*').map(factor).product()
    }

    /// `−Σ c_i g_i`: the acceleration the coefficients give.
    fn from_terms(terms: &[(String, f64)], rate: f64, t: f64, x: f64, v: f64) -> f64 {
        -terms
            .iter()
            .map(|(n, c)| c * term(n, rate * t, x, v))
            .sum::<f64>()
    }

    fn frames() -> Vec<RecordFrame> {
        let base = RecordFrame::nondimensional();
        vec![
            base,
            base.with_drive_frequency(1.02).unwrap(),
            base.with_drive_frequency(6.5).unwrap().with_phase(2.3).unwrap(),
            base.with_rate(0.4)
                .unwrap()
                .with_phase(-1.1)
                .unwrap()
                .with_offset(0.7)
                .unwrap(),
        ]
    }

    #[test]
    fn frame_setters_validate() {
        let f = RecordFrame::nondimensional();
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(f.with_rate(bad).is_err(), "{bad}");
            assert!(f.with_drive_frequency(bad).is_err(), "{bad}");
        }
        assert!(f.with_phase(f64::NAN).is_err());
        assert!(f.with_offset(f64::INFINITY).is_err());
        let g = f.with_drive_frequency(2.0).unwrap();
        assert_eq!(g.rate(), 4.0 * std::f64::consts::PI);
        assert!((g.forcing_period() - 0.5).abs() < 1e-15);
    }

    /// In its own frame the pendulum's coefficients are `c`, `−f` and `1/r²`, bit for bit.
    #[test]
    fn own_frame_is_the_equation_as_written() {
        let p = Pendulum::paper();
        let got = p.coefficients(&RecordFrame::nondimensional()).unwrap();
        let want = [
            ("x'", 0.03),
            ("cos(t)*cos(x)", 0.0),
            ("sin(t)*cos(x)", -1.52),
            ("cos(x)", 0.0),
            ("cos(t)*sin(x)", 0.0),
            ("sin(t)*sin(x)", 0.0),
            ("sin(x)", 1.0 / (0.8333 * 0.8333)),
        ];
        let got: Vec<(&str, f64)> = got.iter().map(|(n, v)| (n.as_str(), *v)).collect();
        assert_eq!(got, want);
        assert!(got.iter().all(|(_, v)| v.is_sign_positive() || *v != 0.0));
        let d = Duffing::two_well()
            .coefficients(&RecordFrame::nondimensional())
            .unwrap();
        let d: Vec<(&str, f64)> = d.iter().map(|(n, v)| (n.as_str(), *v)).collect();
        assert_eq!(
            d,
            [
                ("x'", 0.25),
                ("x", -1.0),
                ("x^3", 1.0),
                ("cos(t)", -0.3),
                ("sin(t)", 0.0)
            ]
        );
    }

    /// A rig's losses and drive harmonics.
    fn rig_extras() -> (Losses, DriveHarmonics) {
        let losses = Losses::none()
            .with_friction(0.04)
            .unwrap()
            .with_drag(0.02)
            .unwrap()
            .with_cubic_damping(0.003)
            .unwrap();
        let harmonics = DriveHarmonics::new(&[
            DriveHarmonic::new(2, 0.1, 0.7).unwrap(),
            DriveHarmonic::new(3, 0.05, -2.0).unwrap(),
        ])
        .unwrap();
        (losses, harmonics)
    }

    /// The coefficients, read term by term, give the acceleration of the system in the frame,
    /// with and without a rig's losses and drive harmonics.
    #[test]
    fn coefficients_are_the_framed_equation() {
        let (losses, harmonics) = rig_extras();
        for (pendulum, duffing) in [
            (
                Pendulum::new(1.3, 0.07, 0.9).unwrap(),
                Duffing::new(0.15, -1.2, 0.8, 0.4).unwrap(),
            ),
            (
                Pendulum::new(1.3, 0.07, 0.9)
                    .unwrap()
                    .with_losses(losses)
                    .with_drive_harmonics(harmonics),
                Duffing::new(0.15, -1.2, 0.8, 0.4)
                    .unwrap()
                    .with_losses(losses)
                    .with_drive_harmonics(harmonics),
            ),
        ] {
            framed_equation(pendulum, duffing);
        }
    }

    fn framed_equation(pendulum: Pendulum, duffing: Duffing) {
        for frame in frames() {
            let rate = frame.rate();
            let p_terms = pendulum.coefficients(&frame).unwrap();
            let framed = InFrame::new(pendulum, frame);
            let d_terms = (frame.offset() == 0.0).then(|| duffing.coefficients(&frame).unwrap());
            let framed_d = InFrame::new(duffing, frame);
            for i in 0..100 {
                let i = f64::from(i);
                let (t, x, v) = (0.013 * i - 0.4, -3.0 + 0.061 * i, rate * (0.7 * i).sin());
                let want = framed.acceleration(t, x, v);
                let got = from_terms(&p_terms, rate, t, x, v);
                assert!(
                    (got - want).abs() <= 1e-12 * (1.0 + want.abs()),
                    "{frame:?}: {got} vs {want}"
                );
                if let Some(d_terms) = &d_terms {
                    let want = framed_d.acceleration(t, x, v);
                    let got = from_terms(d_terms, rate, t, x, v);
                    assert!(
                        (got - want).abs() <= 1e-12 * (1.0 + want.abs()),
                        "{frame:?}: {got} vs {want}"
                    );
                }
            }
        }
        let shifted = RecordFrame::nondimensional().with_offset(0.1).unwrap();
        assert!(duffing.coefficients(&shifted).is_err());
    }

    /// The new terms by name, in seconds with no offset: friction scales with `W²`, drag not at
    /// all, cubic damping with `1/W`, and the `k`-th harmonic's phase at `t = 0` is `k φ + φ_k`.
    #[test]
    fn rig_terms_in_seconds() {
        let (losses, harmonics) = rig_extras();
        let frame = RecordFrame::nondimensional()
            .with_drive_frequency(1.02)
            .unwrap()
            .with_phase(0.4)
            .unwrap();
        let w = frame.rate();
        let pendulum = Pendulum::paper()
            .with_losses(losses)
            .with_drive_harmonics(harmonics);
        let got = pendulum.coefficients(&frame).unwrap();
        let value = |name: &str| {
            got.iter()
                .find(|(n, _)| n == name)
                .unwrap_or_else(|| panic!("no {name} in {got:?}"))
                .1
        };
        assert_eq!(got.len(), 7 + 3 + 8);
        assert!((value("sign(x')") - 0.04 * w * w).abs() < 1e-14 * w * w);
        assert_eq!(value("x'*|x'|"), 0.02);
        assert!((value("x'^3") - 0.003 / w).abs() < 1e-18);
        let drive2 = -1.52 * 0.1 * w * w;
        let psi2: f64 = 2.0 * 0.4 + 0.7;
        assert!((value("cos(2t)*cos(x)") - drive2 * psi2.sin()).abs() < 1e-12);
        assert!((value("sin(2t)*cos(x)") - drive2 * psi2.cos()).abs() < 1e-12);
        // No offset: the harmonics have no `sin(x)` parts.
        assert_eq!(value("cos(2t)*sin(x)"), 0.0);
        assert_eq!(value("sin(3t)*sin(x)"), 0.0);
        let duffing = Duffing::two_well()
            .with_losses(losses)
            .with_drive_harmonics(harmonics);
        let got = duffing.coefficients(&frame).unwrap();
        let value = |name: &str| got.iter().find(|(n, _)| n == name).unwrap().1;
        let drive3 = -0.3 * 0.05 * w * w;
        let psi3: f64 = 3.0 * 0.4 - 2.0;
        assert!((value("cos(3t)") - drive3 * psi3.cos()).abs() < 1e-12);
        assert!((value("sin(3t)") + drive3 * psi3.sin()).abs() < 1e-12);
        // Zero losses and harmonics of zero amplitude add no terms.
        let bare = Pendulum::paper()
            .with_losses(Losses::none().with_drag(0.0).unwrap())
            .with_drive_harmonics(DriveHarmonics::new(&[DriveHarmonic::new(2, 0.0, 1.0).unwrap()]).unwrap());
        assert_eq!(
            bare.coefficients(&frame).unwrap(),
            Pendulum::paper().coefficients(&frame).unwrap()
        );
    }

    #[test]
    fn framed_jacobian_matches_finite_differences() {
        let frame = RecordFrame::nondimensional()
            .with_drive_frequency(1.02)
            .unwrap()
            .with_phase(0.4)
            .unwrap()
            .with_offset(-0.3)
            .unwrap();
        let s = InFrame::new(Pendulum::paper(), frame);
        let (t, x, v) = (0.31, 2.1, -4.0);
        let e = 1e-6;
        let dx = (s.acceleration(t, x + e, v) - s.acceleration(t, x - e, v)) / (2.0 * e);
        let dv = (s.acceleration(t, x, v + e) - s.acceleration(t, x, v - e)) / (2.0 * e);
        let [jx, jv] = s.jacobian(t, x, v);
        assert!((jx - dx).abs() < 1e-6 * dx.abs().max(1.0), "{jx} vs {dx}");
        assert!((jv - dv).abs() < 1e-6 * dv.abs().max(1.0), "{jv} vs {dv}");
    }

    /// A record simulated in seconds satisfies the scaled equation: the acceleration from central
    /// differences of the written velocity, plus the terms at the sample, is zero to the
    /// differences' accuracy; and it is the non-dimensional simulation at `τ = rate · t`.
    #[test]
    fn a_record_in_seconds_satisfies_the_scaled_equation() {
        let hz = 1.02;
        let frame = RecordFrame::nondimensional().with_drive_frequency(hz).unwrap();
        let rate = frame.rate();
        let tol = Tolerances::relative(1e-12).unwrap();
        let fs = 500.0;
        let config = SimulationConfig::paper()
            .with_forcing_period(1.0 / hz)
            .unwrap()
            .with_sample_step(1.0 / fs)
            .unwrap()
            .with_transient_periods(3)
            .with_samples(2000)
            .unwrap()
            .with_tolerances(tol);
        let pendulum = Pendulum::paper();
        let record = simulate(&InFrame::new(pendulum, frame), &config).unwrap();
        let terms = pendulum.coefficients(&frame).unwrap();
        let h = 1.0 / fs;
        let mut worst: f64 = 0.0;
        let mut scale: f64 = 0.0;
        let v = &record.omega;
        for n in 2..record.len() - 2 {
            // The fourth-order central difference of the velocity.
            let acc = (v[n - 2] - 8.0 * v[n - 1] + 8.0 * v[n + 1] - v[n + 2]) / (12.0 * h);
            let residual = acc - from_terms(&terms, rate, record.t[n], record.theta[n], v[n]);
            worst = worst.max(residual.abs());
            scale = scale.max(acc.abs());
        }
        // The difference errs by h^4 x^(6) / 30 (a whirling pendulum sampled at 500 Hz).
        assert!(worst < 1e-6 * scale, "residual {worst:e} of {scale:e}");
        // The same motion as the non-dimensional pendulum sampled at τ = rate · t.
        let nd = SimulationConfig::paper()
            .with_sample_step(rate * h)
            .unwrap()
            .with_transient_periods(3)
            .with_samples(2000)
            .unwrap()
            .with_tolerances(tol);
        let tau = simulate(&pendulum, &nd).unwrap();
        for n in (0..2000).step_by(97) {
            assert!((tau.t[n] - rate * record.t[n]).abs() < 1e-9);
            assert!((tau.theta[n] - record.theta[n]).abs() < 1e-7, "sample {n}");
            assert!((rate * tau.omega[n] - record.omega[n]).abs() < 1e-6, "sample {n}");
        }
    }
    /// A rig's record in seconds, with every loss and two drive harmonics, satisfies the
    /// equation its true coefficients write, at every sample whose neighbours lie on one side of
    /// `x' = 0` (the acceleration jumps by `2 μ W²` there, which no difference resolves).
    #[test]
    fn a_rig_record_in_seconds_satisfies_its_true_equation() {
        let (losses, harmonics) = rig_extras();
        let hz = 1.02;
        let frame = RecordFrame::nondimensional().with_drive_frequency(hz).unwrap();
        let rate = frame.rate();
        let fs = 500.0;
        let config = SimulationConfig::paper()
            .with_forcing_period(1.0 / hz)
            .unwrap()
            .with_sample_step(1.0 / fs)
            .unwrap()
            .with_transient_periods(3)
            .with_samples(3000)
            .unwrap()
            .with_tolerances(Tolerances::relative(1e-12).unwrap());
        for (rig, terms) in [
            {
                let p = Pendulum::paper()
                    .with_losses(losses)
                    .with_drive_harmonics(harmonics);
                (
                    simulate(&InFrame::new(p, frame), &config).unwrap(),
                    p.coefficients(&frame).unwrap(),
                )
            },
            {
                let d = Duffing::two_well()
                    .with_losses(losses)
                    .with_drive_harmonics(harmonics);
                (
                    simulate(&InFrame::new(d, frame), &config).unwrap(),
                    d.coefficients(&frame).unwrap(),
                )
            },
        ] {
            let h = 1.0 / fs;
            let v = &rig.omega;
            let (mut worst, mut scale, mut checked): (f64, f64, usize) = (0.0, 0.0, 0);
            for n in 2..rig.len() - 2 {
                let one_side =
                    v[n - 2..=n + 2].iter().all(|&w| w > 0.0) || v[n - 2..=n + 2].iter().all(|&w| w < 0.0);
                if !one_side {
                    continue;
                }
                let acc = (v[n - 2] - 8.0 * v[n - 1] + 8.0 * v[n + 1] - v[n + 2]) / (12.0 * h);
                let residual = acc - from_terms(&terms, rate, rig.t[n], rig.theta[n], v[n]);
                worst = worst.max(residual.abs());
                scale = scale.max(acc.abs());
                checked += 1;
            }
            assert!(checked > 2900, "{checked} samples checked");
            assert!(worst < 1e-6 * scale, "residual {worst:e} of {scale:e}");
        }
    }
}
