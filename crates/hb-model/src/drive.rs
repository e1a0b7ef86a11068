//! The measured drive `p(t)`: one type for what a term in `p` is balanced from (its samples on
//! the record's grid) and for what a model in `p` is simulated with (the same samples,
//! interpolated).

use std::fmt;
use std::sync::Arc;

use crate::error::ModelError;

/// A measured drive `p(t)` (the factor `p` of a term: a shaker's base acceleration, a motor's
/// torque), sampled with a record on its grid `start_time + n · step`: sample `n` of the drive
/// and of the record at the same time, NaN where the record has gaps.
///
/// Identification balances a term in `p` from the samples themselves ([`MeasuredDrive::samples`];
/// a non-finite sample is refused where a segment reaches it). A model in `p` is simulated with
/// [`MeasuredDrive::at`]: the cubic Hermite spline whose slopes are the central differences
/// (Catmull–Rom; one-sided at the ends), which passes through every sample and has a continuous
/// first derivative, so that an integrator's error control sees no kink. It is NaN outside the
/// recorded span and next to a gap, so that a model never runs on a drive that was not measured.
///
/// The samples are shared, not copied, when the drive is cloned (a record holds millions), and
/// are data, not settings: nothing saves them with a model or a request.
///
/// ```
/// use hb_model::MeasuredDrive;
///
/// // cos t sampled at 0.01 from t = 2: the spline is within 1e-7 between samples.
/// let p: Vec<f64> = (0..1000).map(|n| (2.0 + 0.01 * n as f64).cos()).collect();
/// let drive = MeasuredDrive::new(p, 2.0, 0.01)?;
/// assert!((drive.at(3.005) - 3.005f64.cos()).abs() < 1e-7);
/// assert!(drive.at(1.0).is_nan() && drive.at(20.0).is_nan());
/// // The ends are in the span, to a rounding.
/// assert!((drive.at(2.0 + 999.0 * 0.01 + 1e-15) - (2.0 + 9.99f64).cos()).abs() < 1e-12);
/// # Ok::<(), hb_model::ModelError>(())
/// ```
#[derive(Clone, PartialEq)]
pub struct MeasuredDrive {
    samples: Arc<[f64]>,
    start_time: f64,
    step: f64,
}

impl MeasuredDrive {
    /// The drive's `samples` at `start_time + n · step`: at least 2, `start_time` finite and
    /// `step` positive and finite.
    pub fn new(samples: impl Into<Arc<[f64]>>, start_time: f64, step: f64) -> Result<Self, ModelError> {
        let samples = samples.into();
        if !start_time.is_finite() {
            return Err(ModelError::InvalidParameter {
                name: "measured drive's start time",
                value: start_time,
                why: "must be finite",
            });
        }
        if !(step.is_finite() && step > 0.0) {
            return Err(ModelError::InvalidParameter {
                name: "measured drive's step",
                value: step,
                why: "must be positive and finite",
            });
        }
        if samples.len() < 2 {
            return Err(ModelError::DriveTooShort { len: samples.len() });
        }
        Ok(Self {
            samples,
            start_time,
            step,
        })
    }

    /// The samples, one per sample of the record.
    pub fn samples(&self) -> &[f64] {
        &self.samples
    }

    /// The number of samples (at least 2).
    pub fn len(&self) -> usize {
        self.samples.len()
    }

    /// Never true: a drive has at least two samples.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The time of the first sample.
    pub fn start_time(&self) -> f64 {
        self.start_time
    }

    /// The sampling step.
    pub fn step(&self) -> f64 {
        self.step
    }

    /// The time of the last sample.
    pub fn end_time(&self) -> f64 {
        self.start_time + (self.samples.len() - 1) as f64 * self.step
    }

    /// The same samples from another grid's origin (a record's grid after resampling keeps its
    /// samples; a piece of a record starts elsewhere).
    pub fn starting_at(&self, start_time: f64) -> Result<Self, ModelError> {
        Self::new(self.samples.clone(), start_time, self.step)
    }

    /// The drive at time `t`: the spline through the samples, NaN outside the recorded span and
    /// where a sample it needs is not finite.
    pub fn at(&self, t: f64) -> f64 {
        let p = &self.samples[..];
        let last = p.len() - 1;
        let u = (t - self.start_time) / self.step;
        // An integrator's stage at the span's end may sit a rounding of the times past it: that
        // is the end (a few ulps of the times, in samples).
        let slack = 8.0 * f64::EPSILON * ((t.abs() + self.start_time.abs()) / self.step + last as f64);
        if !(u >= -slack && u <= last as f64 + slack) {
            return f64::NAN;
        }
        let u = u.clamp(0.0, last as f64);
        let i = (u.floor() as usize).min(last - 1);
        let s = u - i as f64;
        let slope = |j: usize| match j {
            0 => p[1] - p[0],
            j if j == last => p[last] - p[last - 1],
            j => 0.5 * (p[j + 1] - p[j - 1]),
        };
        let (p0, p1, m0, m1) = (p[i], p[i + 1], slope(i), slope(i + 1));
        let (s2, s3) = (s * s, s * s * s);
        (2.0 * s3 - 3.0 * s2 + 1.0) * p0
            + (s3 - 2.0 * s2 + s) * m0
            + (-2.0 * s3 + 3.0 * s2) * p1
            + (s3 - s2) * m1
    }
}

impl fmt::Debug for MeasuredDrive {
    /// The grid and the number of samples, not the samples.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("MeasuredDrive")
            .field("len", &self.samples.len())
            .field("start_time", &self.start_time)
            .field("step", &self.step)
            .finish()
    }
}
