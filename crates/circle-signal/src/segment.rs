//! Pieces of a record spanning whole forcing periods, and the sources that find them.

use serde::{Deserialize, Serialize};

use crate::{CircleError, SampleClock};

/// A piece of a sampled record spanning `k` whole forcing periods: `L = k P` samples from `start`,
/// and the closing sample `start + L` (the first sample of the next repetition), which exists.
///
/// The fields are private so that the invariant holds: a segment is made by
/// [`Segment::new`] against a clock with whole `P` and the record's length, by an
/// [`OrbitSource`]. A consumer checks that a segment belongs to its clock with
/// [`fits`](Self::fits).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "SegmentRaw")]
pub struct Segment {
    start: usize,
    period: usize,
    len: usize,
    error: f64,
}

impl Segment {
    /// The segment of `period >= 1` forcing periods of `clock` (whole samples per period) from
    /// sample `start` of a record of `record_len` samples, whose closing sample must lie in the
    /// record; `error >= 0` is how far it is from closing, in the source's metric.
    pub fn new(
        start: usize,
        period: usize,
        clock: &SampleClock,
        error: f64,
        record_len: usize,
    ) -> Result<Self, CircleError> {
        let p = clock.require_whole()?;
        let len = period
            .checked_mul(p)
            .filter(|_| period >= 1)
            .ok_or(CircleError::InvalidParameter {
                name: "segment period",
                value: period as f64,
                why: "must be at least 1 and k P must not overflow",
            })?;
        if start.checked_add(len).is_none_or(|end| end >= record_len) {
            return Err(CircleError::SegmentOutside {
                start,
                len,
                record: record_len,
            });
        }
        Self::checked(start, period, len, error)
    }

    fn checked(start: usize, period: usize, len: usize, error: f64) -> Result<Self, CircleError> {
        if error.is_nan() || error < 0.0 {
            return Err(CircleError::InvalidParameter {
                name: "segment error",
                value: error,
                why: "must not be negative or NaN",
            });
        }
        if period == 0 || !len.is_multiple_of(period) || len / period < 2 || start.checked_add(len).is_none()
        {
            return Err(CircleError::InvalidParameter {
                name: "segment length",
                value: len as f64,
                why: "must be k P samples with k >= 1 and P >= 2",
            });
        }
        Ok(Self {
            start,
            period,
            len,
            error,
        })
    }

    /// Index of the first sample.
    pub fn start(&self) -> usize {
        self.start
    }

    /// Period `k` in forcing periods.
    pub fn period(&self) -> usize {
        self.period
    }

    /// Number of samples, `k P` (the closing sample excluded).
    pub fn len(&self) -> usize {
        self.len
    }

    /// Always false: a segment spans at least two samples per period.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Index of the closing sample, `start + k P`.
    pub fn closing(&self) -> usize {
        self.start + self.len
    }

    /// Recurrence error `|S(start + L) − S(start)|` in the source's metric (radians for an angle
    /// on the circle).
    pub fn error(&self) -> f64 {
        self.error
    }

    /// Samples per forcing period `P` of the clock it was made with.
    pub fn samples_per_period(&self) -> usize {
        self.len / self.period
    }

    /// Whether the segment belongs to `clock` (same `P`) and its closing sample lies in a record
    /// of `record_len` samples.
    pub fn fits(&self, clock: &SampleClock, record_len: usize) -> bool {
        clock.whole_samples_per_period() == Some(self.samples_per_period()) && self.closing() < record_len
    }

    /// Duration `L h` of the segment on `clock` (`k T`).
    pub fn duration(&self, clock: &SampleClock) -> f64 {
        self.len as f64 * clock.step()
    }

    /// Fundamental angular frequency `Ω = 2π / (L h)` of the segment on `clock` (`W / k`).
    pub fn fundamental(&self, clock: &SampleClock) -> f64 {
        std::f64::consts::TAU / self.duration(clock)
    }
}

#[derive(Debug, Clone, Deserialize)]
struct SegmentRaw {
    start: usize,
    period: usize,
    len: usize,
    error: f64,
}

impl TryFrom<SegmentRaw> for Segment {
    type Error = CircleError;

    fn try_from(raw: SegmentRaw) -> Result<Self, CircleError> {
        Self::checked(raw.start, raw.period, raw.len, raw.error)
    }
}

/// Anything that yields segments of whole forcing periods of a sampled signal: close returns
/// (unstable periodic orbits, the paper's method) or plain windows (the weak form).
///
/// The interface between where periodic pieces come from and how they are balanced: it lives
/// below both, so that identification needs no particular source.
pub trait OrbitSource {
    /// What can go wrong.
    type Error: std::error::Error + Send + Sync + 'static;

    /// The clock the segments are cut on.
    fn clock(&self) -> &SampleClock;

    /// The segments of `signal` (a wrapped angle, or a displacement on the line).
    fn segments(&self, signal: &[f64]) -> Result<Vec<Segment>, Self::Error>;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn invariant_holds() {
        let clock = SampleClock::new(1.0, 10).unwrap();
        let s = Segment::new(5, 2, &clock, 0.1, 26).unwrap();
        assert_eq!((s.start(), s.period(), s.len(), s.closing()), (5, 2, 20, 25));
        assert!(s.fits(&clock, 26));
        assert!(!s.fits(&clock, 25));
        assert!(!s.fits(&SampleClock::new(1.0, 5).unwrap(), 26));
        assert!((s.fundamental(&clock) - std::f64::consts::PI).abs() < 1e-15);
        assert!(matches!(
            Segment::new(6, 2, &clock, 0.1, 26),
            Err(CircleError::SegmentOutside { .. })
        ));
        assert!(Segment::new(0, 0, &clock, 0.1, 26).is_err());
        assert!(Segment::new(0, 1, &clock, f64::NAN, 26).is_err());
        let odd = SampleClock::from_step(1.0, 0.3).unwrap();
        assert!(matches!(
            Segment::new(0, 1, &odd, 0.0, 26),
            Err(CircleError::NotWholePeriod { .. })
        ));
    }

    #[test]
    fn serde_validates() {
        let clock = SampleClock::new(1.0, 10).unwrap();
        let s = Segment::new(5, 2, &clock, 0.1, 26).unwrap();
        let back: Segment = serde_json::from_str(&serde_json::to_string(&s).unwrap()).unwrap();
        assert_eq!(back, s);
        for bad in [
            r#"{"start":0,"period":0,"len":20,"error":0.0}"#,
            r#"{"start":0,"period":3,"len":20,"error":0.0}"#,
            r#"{"start":0,"period":1,"len":20,"error":-1.0}"#,
        ] {
            assert!(serde_json::from_str::<Segment>(bad).is_err(), "{bad}");
        }
    }
}
