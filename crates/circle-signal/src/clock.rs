//! The sampling clock: how a record is sampled relative to its drive.

use std::f64::consts::TAU;

use serde::{Deserialize, Serialize};

use crate::CircleError;

/// How a record is sampled relative to its drive: drive period `T`, sample step `h`, and the
/// absolute time `t_0` of sample 0, so that sample `n` is at `t_n = t_0 + n h`.
///
/// The one description of time that every stage takes, made once from the record and the forcing
/// period. The forcing angular frequency is `W = 2π / T`; the paper's non-dimensional time is
/// `T = 2π` (`W = 1`). The number of samples per drive period, `T / h`, need not be whole
/// ([`samples_per_period`](Self::samples_per_period) gives it exactly, e.g. 490.196 for a drive of
/// 1.02 Hz sampled at 500 Hz); the stages that cut the record into whole drive periods (close
/// returns, periodic windows, the paper's Fourier rows) ask for
/// [`whole_samples_per_period`](Self::whole_samples_per_period) and say so when there is none.
///
/// A ratio within [`WHOLE_TOLERANCE`](Self::WHOLE_TOLERANCE) (relative) of a whole number `P` is
/// taken as `P`, and the step is then exactly `T / P`: a time column printed to a few decimals
/// gives the same clock as the exact grid.
///
/// Validated when constructed and when deserialised.
///
/// # Example
///
/// ```
/// use circle_signal::SampleClock;
///
/// // The paper: 25 samples per non-dimensional drive period 2π.
/// let paper = SampleClock::nondimensional(25)?;
/// assert_eq!(paper.whole_samples_per_period(), Some(25));
/// assert!((paper.step() - std::f64::consts::TAU / 25.0).abs() < 1e-15);
///
/// // A rig: 500 Hz sampling, 1.02 Hz drive, time in seconds.
/// let rig = SampleClock::from_step(1.0 / 1.02, 1.0 / 500.0)?;
/// assert!((rig.samples_per_period() - 490.196).abs() < 1e-3);
/// assert_eq!(rig.whole_samples_per_period(), None);
/// # Ok::<(), circle_signal::CircleError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "ClockRaw", into = "ClockRaw")]
pub struct SampleClock {
    drive_period: f64,
    step: f64,
    start_time: f64,
    /// `Some(P)` when `T = P h` (within the tolerance, and then exactly `h = T / P`).
    whole: Option<usize>,
}

impl SampleClock {
    /// Relative tolerance within which `T / h` is taken as a whole number of samples.
    pub const WHOLE_TOLERANCE: f64 = 1e-6;

    /// `P >= 2` samples per drive period of length `T > 0` (in the data's time unit): step
    /// `h = T / P`, `t_0 = 0`. Set the time of sample 0 with [`with_start_time`](Self::with_start_time).
    pub fn new(drive_period: f64, samples_per_period: usize) -> Result<Self, CircleError> {
        check_period(drive_period)?;
        if samples_per_period < 2 {
            return Err(CircleError::InvalidParameter {
                name: "samples per forcing period",
                value: samples_per_period as f64,
                why: "must be at least 2",
            });
        }
        Ok(Self {
            drive_period,
            step: drive_period / samples_per_period as f64,
            start_time: 0.0,
            whole: Some(samples_per_period),
        })
    }

    /// A drive period `T > 0` sampled every `h > 0` (same time unit), with at least two samples
    /// per period and `t_0 = 0`. When `T / h` is within [`WHOLE_TOLERANCE`](Self::WHOLE_TOLERANCE)
    /// of a whole `P`, this is [`SampleClock::new`]`(T, P)`.
    pub fn from_step(drive_period: f64, step: f64) -> Result<Self, CircleError> {
        check_period(drive_period)?;
        if !(step.is_finite() && step > 0.0) {
            return Err(CircleError::InvalidParameter {
                name: "sample step",
                value: step,
                why: "must be positive and finite",
            });
        }
        let ratio = drive_period / step;
        if ratio.is_nan() || ratio < 2.0 - 2.0 * Self::WHOLE_TOLERANCE {
            return Err(CircleError::InvalidParameter {
                name: "samples per forcing period",
                value: ratio,
                why: "must be at least 2 (the forcing period over the sample step)",
            });
        }
        let whole = ratio.round();
        if (ratio - whole).abs() <= Self::WHOLE_TOLERANCE * ratio && whole <= usize::MAX as f64 {
            return Self::new(drive_period, whole as usize);
        }
        Ok(Self {
            drive_period,
            step,
            start_time: 0.0,
            whole: None,
        })
    }

    /// The paper's non-dimensional time: drive period `2π`, `P` samples per period, `t_0 = 0`.
    pub fn nondimensional(samples_per_period: usize) -> Result<Self, CircleError> {
        Self::new(TAU, samples_per_period)
    }

    /// The same clock with sample 0 at time `t_0` (finite).
    pub fn with_start_time(mut self, start_time: f64) -> Result<Self, CircleError> {
        if !start_time.is_finite() {
            return Err(CircleError::InvalidParameter {
                name: "start time",
                value: start_time,
                why: "must be finite",
            });
        }
        self.start_time = start_time;
        Ok(self)
    }

    /// The drive's period `T`, in the record's time unit.
    pub fn drive_period(&self) -> f64 {
        self.drive_period
    }

    /// The drive's frequency `1 / T`, in cycles per time unit (hertz for seconds).
    pub fn drive_frequency(&self) -> f64 {
        1.0 / self.drive_period
    }

    /// The drive's angular frequency `W = 2π / T`, in radians per time unit.
    pub fn drive_angular_frequency(&self) -> f64 {
        TAU / self.drive_period
    }

    /// Sample step `h`.
    pub fn step(&self) -> f64 {
        self.step
    }

    /// Time `t_0` of sample 0.
    pub fn start_time(&self) -> f64 {
        self.start_time
    }

    /// Absolute time of sample `n`, `t_0 + n h`.
    pub fn time(&self, n: usize) -> f64 {
        self.start_time + n as f64 * self.step
    }

    /// Samples per drive period, `T / h`, whole or not.
    pub fn samples_per_period(&self) -> f64 {
        match self.whole {
            Some(p) => p as f64,
            None => self.drive_period / self.step,
        }
    }

    /// `P` when a drive period is a whole number of samples, `None` otherwise.
    pub fn whole_samples_per_period(&self) -> Option<usize> {
        self.whole
    }

    /// `P` when a drive period is a whole number of samples, or
    /// [`CircleError::NotWholePeriod`]: for the stages that cut a record into whole periods.
    pub fn require_whole(&self) -> Result<usize, CircleError> {
        self.whole.ok_or(CircleError::NotWholePeriod {
            samples_per_period: self.samples_per_period(),
        })
    }
}

fn check_period(drive_period: f64) -> Result<(), CircleError> {
    if drive_period.is_finite() && drive_period > 0.0 {
        Ok(())
    } else {
        Err(CircleError::InvalidParameter {
            name: "forcing period",
            value: drive_period,
            why: "must be positive and finite",
        })
    }
}

/// The serialised form: `samples_per_period` for a whole clock (so that the step is exactly
/// `T / P` again), `step` otherwise (every field is written, for formats without field names).
#[derive(Debug, Clone, Serialize, Deserialize)]
struct ClockRaw {
    forcing_period: f64,
    #[serde(default)]
    samples_per_period: Option<usize>,
    #[serde(default)]
    step: Option<f64>,
    #[serde(default)]
    start_time: f64,
}

impl From<SampleClock> for ClockRaw {
    fn from(c: SampleClock) -> Self {
        Self {
            forcing_period: c.drive_period,
            samples_per_period: c.whole,
            step: c.whole.is_none().then_some(c.step),
            start_time: c.start_time,
        }
    }
}

impl TryFrom<ClockRaw> for SampleClock {
    type Error = CircleError;

    fn try_from(raw: ClockRaw) -> Result<Self, CircleError> {
        let clock = match (raw.samples_per_period, raw.step) {
            (Some(p), None) => Self::new(raw.forcing_period, p)?,
            (None, Some(h)) => Self::from_step(raw.forcing_period, h)?,
            _ => {
                return Err(CircleError::InvalidParameter {
                    name: "clock",
                    value: f64::NAN,
                    why: "needs exactly one of samples_per_period and step",
                });
            }
        };
        clock.with_start_time(raw.start_time)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn whole_and_not() {
        let c = SampleClock::new(2.0, 8).unwrap().with_start_time(1.0).unwrap();
        assert_eq!(c.step(), 0.25);
        assert_eq!(c.time(4), 2.0);
        assert_eq!(c.require_whole(), Ok(8));
        // A step printed to a few decimals snaps to the whole grid.
        let s = SampleClock::from_step(1.0, 0.1000000001).unwrap();
        assert_eq!(s, SampleClock::new(1.0, 10).unwrap());
        let r = SampleClock::from_step(1.0 / 1.02, 0.002).unwrap();
        assert!(matches!(
            r.require_whole(),
            Err(CircleError::NotWholePeriod { .. })
        ));
        assert!((r.samples_per_period() - 500.0 / 1.02).abs() < 1e-9);
    }

    #[test]
    fn rejects_bad_values() {
        assert!(SampleClock::new(0.0, 8).is_err());
        assert!(SampleClock::new(f64::NAN, 8).is_err());
        assert!(SampleClock::new(1.0, 1).is_err());
        assert!(SampleClock::from_step(1.0, 0.0).is_err());
        assert!(SampleClock::from_step(1.0, 0.6).is_err());
        assert!(
            SampleClock::new(1.0, 4)
                .unwrap()
                .with_start_time(f64::INFINITY)
                .is_err()
        );
    }

    #[test]
    fn serde_validates() {
        let c = SampleClock::new(TAU, 25).unwrap().with_start_time(-3.5).unwrap();
        let json = serde_json::to_string(&c).unwrap();
        assert_eq!(serde_json::from_str::<SampleClock>(&json).unwrap(), c);
        let r = SampleClock::from_step(1.0, 0.3).unwrap();
        let back: SampleClock = serde_json::from_str(&serde_json::to_string(&r).unwrap()).unwrap();
        assert_eq!(back, r);
        for bad in [
            r#"{"forcing_period":1.0,"samples_per_period":1}"#,
            r#"{"forcing_period":-1.0,"samples_per_period":8}"#,
            r#"{"forcing_period":1.0,"step":0.0}"#,
            r#"{"forcing_period":1.0}"#,
        ] {
            assert!(serde_json::from_str::<SampleClock>(bad).is_err(), "{bad}");
        }
    }
}
