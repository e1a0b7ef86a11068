//! Drives as functions of time, for systems of several coordinates: a sum of sinusoids
//! ([`Sinusoid`]), a measured series the caller interpolates ([`MeasuredSignal`]), and a drive
//! that looks measured ([`SyntheticDrive`]: sinusoids at incommensurate frequencies plus seeded
//! band-limited noise).
//!
//! The integrators evaluate a drive between samples, at every stage of every step, so each is a
//! function of continuous time, never a table.

use std::fmt;
use std::sync::Arc;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::error::SimError;

/// A measured signal (a torque, a base acceleration) as the caller gives it: a function of time,
/// typically an interpolant of the recorded samples. Shared, never serialised: a system
/// deserialised without its measured signal has a *missing* one, which is NaN at every time (a run
/// then stops as non-finite), never zero.
#[derive(Clone)]
pub struct MeasuredSignal(Option<Arc<dyn Fn(f64) -> f64 + Send + Sync>>);

impl MeasuredSignal {
    /// The signal `f(t)`.
    pub fn new(f: impl Fn(f64) -> f64 + Send + Sync + 'static) -> Self {
        Self(Some(Arc::new(f)))
    }

    /// A signal whose samples are not there: NaN at every time.
    pub fn missing() -> Self {
        Self(None)
    }

    /// Whether the samples are missing.
    pub fn is_missing(&self) -> bool {
        self.0.is_none()
    }

    /// The signal at time `t` (NaN when missing).
    #[inline]
    pub fn at(&self, t: f64) -> f64 {
        match &self.0 {
            Some(f) => f(t),
            None => f64::NAN,
        }
    }
}

impl fmt::Debug for MeasuredSignal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(if self.is_missing() {
            "MeasuredSignal(missing)"
        } else {
            "MeasuredSignal(..)"
        })
    }
}

impl PartialEq for MeasuredSignal {
    /// The same function (the same shared closure), or both missing.
    fn eq(&self, other: &Self) -> bool {
        match (&self.0, &other.0) {
            (Some(a), Some(b)) => Arc::ptr_eq(a, b),
            (None, None) => true,
            _ => false,
        }
    }
}

/// `A sin(ω t + φ)`: amplitude, angular frequency and phase, all finite.
///
/// Deserialising validates as [`Sinusoid::new`] does (`phase` may be left out, 0).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "SinusoidRaw", into = "SinusoidRaw")]
pub struct Sinusoid {
    amplitude: f64,
    angular_frequency: f64,
    phase: f64,
}

/// The serialised form of [`Sinusoid`].
#[derive(Serialize, Deserialize)]
struct SinusoidRaw {
    amplitude: f64,
    angular_frequency: f64,
    #[serde(default)]
    phase: f64,
}

impl TryFrom<SinusoidRaw> for Sinusoid {
    type Error = SimError;
    fn try_from(raw: SinusoidRaw) -> Result<Self, SimError> {
        Self::new(raw.amplitude, raw.angular_frequency, raw.phase)
    }
}

impl From<Sinusoid> for SinusoidRaw {
    fn from(s: Sinusoid) -> Self {
        Self {
            amplitude: s.amplitude,
            angular_frequency: s.angular_frequency,
            phase: s.phase,
        }
    }
}

impl Sinusoid {
    /// `amplitude · sin(angular_frequency · t + phase)`, every parameter finite.
    pub fn new(amplitude: f64, angular_frequency: f64, phase: f64) -> Result<Self, SimError> {
        for (name, value) in [
            ("amplitude", amplitude),
            ("angular frequency", angular_frequency),
            ("phase", phase),
        ] {
            if !value.is_finite() {
                return Err(SimError::InvalidParameter {
                    name,
                    value,
                    why: "must be finite",
                });
            }
        }
        Ok(Self {
            amplitude,
            angular_frequency,
            phase,
        })
    }

    /// The value at `t`.
    #[inline]
    pub fn at(&self, t: f64) -> f64 {
        self.amplitude * (self.angular_frequency * t + self.phase).sin()
    }

    /// The amplitude `A`.
    pub fn amplitude(&self) -> f64 {
        self.amplitude
    }
    /// The angular frequency `ω`.
    pub fn angular_frequency(&self) -> f64 {
        self.angular_frequency
    }
    /// The phase `φ`.
    pub fn phase(&self) -> f64 {
        self.phase
    }
}

/// A drive that looks measured: a few sinusoids (at incommensurate frequencies, so that the sum
/// never repeats) plus seeded band-limited noise.
///
/// The noise is a random-phase multisine: [`NOISE_COMPONENTS`](Self::NOISE_COMPONENTS) sinusoids
/// of equal amplitude `σ √(2/K)`, at angular frequencies drawn uniformly in the band and with
/// uniform phases, from ChaCha8 seeded by the seed. Its spectrum lies in the band, its values are
/// close to Gaussian (a sum of many independent phases), its mean square over a long time is
/// `σ²`, and it is a smooth function of time that the integrator can evaluate anywhere; the
/// frequencies being random, it has no period.
///
/// Deserialising validates as [`SyntheticDrive::new`] does and draws the same noise from the seed.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(try_from = "SyntheticDriveRaw", into = "SyntheticDriveRaw")]
pub struct SyntheticDrive {
    tones: Vec<Sinusoid>,
    noise_rms: f64,
    band: [f64; 2],
    seed: u64,
    /// The noise's sinusoids, drawn from the seed; never serialised.
    noise: Vec<Sinusoid>,
}

/// The serialised form of [`SyntheticDrive`].
#[derive(Serialize, Deserialize)]
struct SyntheticDriveRaw {
    tones: Vec<Sinusoid>,
    noise_rms: f64,
    band: [f64; 2],
    seed: u64,
}

impl TryFrom<SyntheticDriveRaw> for SyntheticDrive {
    type Error = SimError;
    fn try_from(raw: SyntheticDriveRaw) -> Result<Self, SimError> {
        Self::new(raw.tones, raw.noise_rms, raw.band, raw.seed)
    }
}

impl From<SyntheticDrive> for SyntheticDriveRaw {
    fn from(d: SyntheticDrive) -> Self {
        Self {
            tones: d.tones,
            noise_rms: d.noise_rms,
            band: d.band,
            seed: d.seed,
        }
    }
}

impl PartialEq for SyntheticDrive {
    /// The same tones, noise level, band and seed (so the same noise).
    fn eq(&self, other: &Self) -> bool {
        self.tones == other.tones
            && self.noise_rms == other.noise_rms
            && self.band == other.band
            && self.seed == other.seed
    }
}

impl SyntheticDrive {
    /// Sinusoids in the noise.
    pub const NOISE_COMPONENTS: usize = 64;

    /// `tones` plus noise of root mean square `noise_rms` (finite, `>= 0`) in the band of angular
    /// frequencies `band = [low, high]` (`0 <= low < high`, finite), drawn from `seed`.
    pub fn new(tones: Vec<Sinusoid>, noise_rms: f64, band: [f64; 2], seed: u64) -> Result<Self, SimError> {
        if !(noise_rms.is_finite() && noise_rms >= 0.0) {
            return Err(SimError::InvalidParameter {
                name: "noise rms",
                value: noise_rms,
                why: "must be finite and non-negative",
            });
        }
        let [low, high] = band;
        if !(low.is_finite() && low >= 0.0) {
            return Err(SimError::InvalidParameter {
                name: "noise band",
                value: low,
                why: "its low edge must be finite and non-negative",
            });
        }
        if !(high.is_finite() && high > low) {
            return Err(SimError::InvalidParameter {
                name: "noise band",
                value: high,
                why: "its high edge must be finite and above the low edge",
            });
        }
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let k = Self::NOISE_COMPONENTS;
        let amplitude = noise_rms * (2.0 / k as f64).sqrt();
        let noise = (0..k)
            .map(|_| {
                let omega = low + (high - low) * rng.random::<f64>();
                let phase = std::f64::consts::TAU * rng.random::<f64>();
                Sinusoid {
                    amplitude,
                    angular_frequency: omega,
                    phase,
                }
            })
            .collect();
        Ok(Self {
            tones,
            noise_rms: noise_rms + 0.0,
            band,
            seed,
            noise,
        })
    }

    /// The built-in drive: `0.3 sin(t) + 0.15 sin(√2 t + 1) + 0.1 sin(φ t + 2)` (`φ` the golden
    /// ratio; no two frequencies in a rational ratio) plus noise of rms 0.03 in `[0.3, 3]`, from
    /// `seed`.
    pub fn incommensurate(seed: u64) -> Self {
        let golden = 0.5 * (1.0 + 5f64.sqrt());
        let tones = vec![
            Sinusoid {
                amplitude: 0.3,
                angular_frequency: 1.0,
                phase: 0.0,
            },
            Sinusoid {
                amplitude: 0.15,
                angular_frequency: std::f64::consts::SQRT_2,
                phase: 1.0,
            },
            Sinusoid {
                amplitude: 0.1,
                angular_frequency: golden,
                phase: 2.0,
            },
        ];
        Self::new(tones, 0.03, [0.3, 3.0], seed).expect("the built-in drive is valid")
    }

    /// The drive at `t`.
    #[inline]
    pub fn at(&self, t: f64) -> f64 {
        self.tones.iter().chain(&self.noise).map(|s| s.at(t)).sum()
    }

    /// The deterministic sinusoids.
    pub fn tones(&self) -> &[Sinusoid] {
        &self.tones
    }
    /// The noise's root mean square `σ`.
    pub fn noise_rms(&self) -> f64 {
        self.noise_rms
    }
    /// The noise's band of angular frequencies.
    pub fn band(&self) -> [f64; 2] {
        self.band
    }
    /// The seed of the noise.
    pub fn seed(&self) -> u64 {
        self.seed
    }
    /// The noise's sinusoids as drawn from the seed.
    pub fn noise_components(&self) -> &[Sinusoid] {
        &self.noise
    }
}
