//! Parameters of identification: sampling clock, harmonics per orbit, model form.

use std::fmt;

use circle_signal::SampleClock;
use hb_model::{Harmonics, ModelForm};
use serde::{Deserialize, Serialize};

use crate::error::SolveError;

/// The default cap of the velocity series, in multiples of the forcing frequency.
const VELOCITY_CAP: f64 = 16.0;

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
/// `SolveError::Assembly(AssemblyError::NoiseCorrectionUnavailable)` rather than correct wrongly.
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

/// Everything identification needs besides the basis, the record ([`crate::Signals`], its
/// measured drives among them) and the segments: the settings.
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
}

impl IdentifyParams {
    /// The default harmonics of the velocity series, [`Harmonics::DriveCap`]`(VELOCITY_CAP)`:
    /// the velocity that the nonlinear functions of `x'` (`sign(x')`, `x'*|x'|`, `x'^3`) are
    /// evaluated at is the derivative of a segment's Fourier series up to this many times the
    /// forcing frequency (see `docs/identification.md` for the measurements behind the choice).
    pub const DEFAULT_VELOCITY_HARMONICS: Harmonics = Harmonics::DriveCap(VELOCITY_CAP);

    /// The default harmonics of the velocity series of an equation with terms in other
    /// coordinates or accelerations ([`hb_model::TermList::is_coupled`]),
    /// [`Harmonics::DriveCap`]`(32)`: their velocities multiply each other and the functions of
    /// the positions, and a double pendulum whirls with content well above 16 times the drive
    /// frequency. On the whirling double pendulum at 64 samples per period the largest
    /// coefficient error is 5.3e-4 at a cap of 16, 1.4e-4 at 20, 4e-5 at 24 and 9e-6 at 31 (its
    /// Nyquist frequency); see `docs/identification.md`.
    pub const SYSTEM_VELOCITY_HARMONICS: Harmonics = Harmonics::DriveCap(32.0);

    /// The default velocity harmonics of an identification of `form`:
    /// [`SYSTEM_VELOCITY_HARMONICS`](Self::SYSTEM_VELOCITY_HARMONICS) for a form with terms in
    /// other coordinates or accelerations, [`DEFAULT_VELOCITY_HARMONICS`](Self::DEFAULT_VELOCITY_HARMONICS)
    /// otherwise.
    pub fn default_velocity_harmonics_for(form: &ModelForm) -> Harmonics {
        if form.terms().is_some_and(hb_model::TermList::is_coupled) {
            Self::SYSTEM_VELOCITY_HARMONICS
        } else {
            Self::DEFAULT_VELOCITY_HARMONICS
        }
    }

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

    /// Validates and builds. A term with a drive harmonic `k` at or above half the clock's whole
    /// samples per period `P` (`2k >= P`) is refused
    /// ([`AssemblyError::DriveHarmonicAliased`](crate::error::AssemblyError::DriveHarmonicAliased)):
    /// sampled, it is the alias of harmonic `P − k`.
    pub fn build(self) -> Result<IdentifyParams, SolveError> {
        let highest = self.form.highest_drive_harmonic();
        if let Some(p) = self.clock.whole_samples_per_period()
            && 2 * highest as usize >= p
        {
            let what = match self.form.terms() {
                Some(list) => (0..list.len())
                    .find(|&i| list.terms()[i].drive.harmonic() == highest)
                    .map_or_else(|| "a term".to_owned(), |i| format!("the term `{}`", list.name(i))),
                None => format!("the default library (drive harmonics up to {highest})"),
            };
            return Err(crate::error::AssemblyError::DriveHarmonicAliased {
                what,
                harmonic: highest,
                samples_per_period: p,
            }
            .into());
        }
        Ok(IdentifyParams {
            clock: self.clock,
            harmonics: self.harmonics.validate()?,
            form: self.form.validate()?,
            noise: self.noise.validate()?,
            velocity_harmonics: self.velocity_harmonics.validate()?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::TAU;

    #[test]
    fn a_drive_harmonic_the_sampling_cannot_resolve_is_refused() {
        let names = hb_model::Names::new(["x"], Vec::<String>::new()).unwrap();
        let form = |spec: &str| ModelForm::from_terms(hb_model::TermList::parse_in(spec, &names, 0).unwrap());
        let clock = SampleClock::nondimensional(32).unwrap();
        // 15 is the highest harmonic 32 samples resolve; 16 is sampled as cos(πn), sin(πn) = 0.
        assert!(
            IdentifyParams::builder(clock)
                .form(form("sin(15t)*cos(x), sin(x)"))
                .build()
                .is_ok()
        );
        let e = IdentifyParams::builder(clock)
            .form(form("sin(x), sin(16t)*cos(x), x'"))
            .build()
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "the term `sin(16t)*cos(x)` has the drive's harmonic 16, which 32 samples per drive period cannot \
             resolve: a sampled harmonic is a lower one's alias from half the samples per period on (harmonics up \
             to 15 here)"
        );
        let e = IdentifyParams::builder(SampleClock::nondimensional(6).unwrap())
            .form(ModelForm::parametric().with_drive_harmonics(3))
            .build()
            .unwrap_err();
        assert!(
            e.to_string()
                .starts_with("the default library (drive harmonics up to 3) has"),
            "{e}"
        );
    }

    #[test]
    fn clock() {
        let c = SampleClock::nondimensional(25)
            .unwrap()
            .with_start_time(10.0)
            .unwrap();
        assert!((c.drive_angular_frequency() - 1.0).abs() < 1e-15);
        assert!((c.time(25) - (10.0 + TAU)).abs() < 1e-12);
        let c = SampleClock::new(0.5, 100).unwrap();
        assert!((c.drive_angular_frequency() - 4.0 * std::f64::consts::PI).abs() < 1e-12);
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
        assert_eq!(Harmonics::DriveCap(1.0).count(3, 75), 3);
        assert_eq!(Harmonics::DriveCap(2.5).count(2, 50), 5);
        assert_eq!(Harmonics::DriveCap(20.0).count(1, 25), 12);
        assert!(Harmonics::Fixed(0).validate().is_err());
        assert!(Harmonics::DriveCap(0.5).validate().is_err());
        assert!(Harmonics::DriveCap(f64::NAN).validate().is_err());
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
        let bad = ModelForm::externally_forced(hb_model::Forcing::Known {
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
        assert_eq!(h, Harmonics::DriveCap(2.0));
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
