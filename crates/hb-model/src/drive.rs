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
/// [`MeasuredDrive::at`]: the interpolating cubic spline of each run of finite samples (continuous
/// second derivative, not-a-knot ends; a parabola through a run of 3 samples, a line through 2).
/// It passes through every sample and has no kink for an integrator's error control to see, and,
/// unlike a local spline, it keeps the amplitude of a band-limited drive up to a good fraction of
/// the sampling rate: at a quarter of it the spline is within 2.5 % of a sinusoid's amplitude
/// between samples, where the Catmull–Rom spline (central-difference slopes) is 10 % off, a bias
/// a free run under a measured input carries through every resonance it drives. It is NaN
/// outside the recorded span and next to a gap, so that a model never runs on a drive that was
/// not measured.
///
/// A drive may also be sampled at uneven time stamps ([`MeasuredDrive::at_stamps`]: a logger's
/// first rows, stamped before it settled to its rate): the spline is then the interpolating
/// cubic spline on those knots, not-a-knot at its ends, as on the grid.
///
/// The samples are shared, not copied, when the drive is cloned (a record holds millions), and
/// are data, not settings: nothing saves them with a model or a request.
///
/// ```
/// use hb_model::MeasuredDrive;
///
/// // cos t sampled at 0.01 from t = 2: the spline is within 1e-9 between samples.
/// let p: Vec<f64> = (0..1000).map(|n| (2.0 + 0.01 * n as f64).cos()).collect();
/// let drive = MeasuredDrive::new(p, 2.0, 0.01)?;
/// assert!((drive.at(3.005) - 3.005f64.cos()).abs() < 1e-9);
/// assert!((drive.at(2.005) - 2.005f64.cos()).abs() < 1e-9);
/// assert!(drive.at(1.0).is_nan() && drive.at(20.0).is_nan());
/// // The ends are in the span, to a rounding.
/// assert!((drive.at(2.0 + 999.0 * 0.01 + 1e-15) - (2.0 + 9.99f64).cos()).abs() < 1e-12);
/// # Ok::<(), hb_model::ModelError>(())
/// ```
#[derive(Clone, PartialEq)]
pub struct MeasuredDrive {
    samples: Arc<[f64]>,
    /// The spline's second derivatives at the samples (times step² on a grid, as they are at
    /// uneven stamps; NaN where a sample is not finite), made once from the samples.
    curvatures: Arc<[f64]>,
    start_time: f64,
    step: f64,
    /// The samples' time stamps, when they are not on a grid (increasing, the first at
    /// `start_time`).
    stamps: Option<Arc<[f64]>>,
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
        let curvatures = curvatures(&samples).into();
        Ok(Self {
            samples,
            curvatures,
            start_time,
            step,
            stamps: None,
        })
    }

    /// The drive's `samples` at the time stamps `stamps` (one each, at least 2, finite and
    /// increasing), which need not be evenly spaced: the interpolating cubic spline on those
    /// knots (not-a-knot ends; NaN next to a sample that is not finite). [`step`](Self::step)
    /// is then the mean step.
    ///
    /// ```
    /// use hb_model::MeasuredDrive;
    ///
    /// // A cubic at uneven stamps is the spline itself.
    /// let f = |t: f64| 1.0 - 2.0 * t + 0.5 * t * t * t;
    /// let t = [0.0, 0.35, 0.7, 0.9, 1.1, 1.3, 1.5];
    /// let drive = MeasuredDrive::at_stamps(t.map(f).to_vec(), &t)?;
    /// assert!((drive.at(0.2) - f(0.2)).abs() < 1e-12 && (drive.at(1.4) - f(1.4)).abs() < 1e-12);
    /// assert!(drive.at(1.6).is_nan());
    /// # Ok::<(), hb_model::ModelError>(())
    /// ```
    pub fn at_stamps(samples: impl Into<Arc<[f64]>>, stamps: &[f64]) -> Result<Self, ModelError> {
        let samples = samples.into();
        if samples.len() < 2 {
            return Err(ModelError::DriveTooShort { len: samples.len() });
        }
        if stamps.len() != samples.len() {
            return Err(ModelError::InvalidParameter {
                name: "measured drive's time stamps",
                value: stamps.len() as f64,
                why: "must be one per sample",
            });
        }
        if let Some(&bad) = stamps.iter().find(|t| !t.is_finite()) {
            return Err(ModelError::InvalidParameter {
                name: "measured drive's time stamp",
                value: bad,
                why: "must be finite",
            });
        }
        if let Some(w) = stamps.windows(2).find(|w| w[1] <= w[0]) {
            return Err(ModelError::InvalidParameter {
                name: "measured drive's time stamp",
                value: w[1],
                why: "must come after the one before it",
            });
        }
        let n = stamps.len();
        let curvatures = uneven_curvatures(&samples, stamps).into();
        Ok(Self {
            samples,
            curvatures,
            start_time: stamps[0],
            step: (stamps[n - 1] - stamps[0]) / (n - 1) as f64,
            stamps: Some(stamps.into()),
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

    /// The sampling step (at uneven stamps, the mean step).
    pub fn step(&self) -> f64 {
        self.step
    }

    /// The samples' time stamps, when they are not on a grid ([`MeasuredDrive::at_stamps`]).
    pub fn stamps(&self) -> Option<&[f64]> {
        self.stamps.as_deref()
    }

    /// The time of the last sample.
    pub fn end_time(&self) -> f64 {
        match &self.stamps {
            Some(t) => t[t.len() - 1],
            None => self.start_time + (self.samples.len() - 1) as f64 * self.step,
        }
    }

    /// The same samples from another grid's origin (a record's grid after resampling keeps its
    /// samples; a piece of a record starts elsewhere).
    pub fn starting_at(&self, start_time: f64) -> Result<Self, ModelError> {
        if !start_time.is_finite() {
            return Err(ModelError::InvalidParameter {
                name: "measured drive's start time",
                value: start_time,
                why: "must be finite",
            });
        }
        let stamps = self
            .stamps
            .as_ref()
            .map(|t| t.iter().map(|s| s - self.start_time + start_time).collect());
        Ok(Self {
            start_time,
            stamps,
            ..self.clone()
        })
    }

    /// The drive at time `t`: the spline through the samples, NaN outside the recorded span and
    /// where a sample it needs is not finite.
    pub fn at(&self, t: f64) -> f64 {
        if let Some(stamps) = &self.stamps {
            return self.at_stamped(stamps, t);
        }
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
        if s == 0.0 {
            // On a sample (a run's last sample before a gap included).
            return if p[i].is_finite() { p[i] } else { f64::NAN };
        }
        let r = 1.0 - s;
        let m = &self.curvatures[..];
        // Between the samples: the line through them plus the curvatures' cubic corrections
        // (NaN where either sample, hence its curvature, is not finite).
        r * p[i] + s * p[i + 1] - s * r / 6.0 * ((1.0 + r) * m[i] + (1.0 + s) * m[i + 1])
    }
}

impl MeasuredDrive {
    /// [`MeasuredDrive::at`] of a drive at uneven `stamps`.
    fn at_stamped(&self, stamps: &[f64], t: f64) -> f64 {
        let p = &self.samples[..];
        let last = p.len() - 1;
        let (first, end) = (stamps[0], stamps[last]);
        // As on a grid: a rounding of the times past an end is the end.
        let slack = 8.0 * f64::EPSILON * (t.abs() + first.abs() + end.abs());
        if !(t >= first - slack && t <= end + slack) {
            return f64::NAN;
        }
        let t = t.clamp(first, end);
        // The interval [stamps[i], stamps[i+1]] that holds t.
        let i = stamps
            .partition_point(|&s| s <= t)
            .saturating_sub(1)
            .min(last - 1);
        let h = stamps[i + 1] - stamps[i];
        let s = (t - stamps[i]) / h;
        if s == 0.0 {
            return if p[i].is_finite() { p[i] } else { f64::NAN };
        }
        let r = 1.0 - s;
        let m = &self.curvatures[..];
        r * p[i] + s * p[i + 1] - s * r * h * h / 6.0 * ((1.0 + r) * m[i] + (1.0 + s) * m[i + 1])
    }
}

/// The second derivatives of the interpolating cubic spline on the knots `t` of each run of
/// finite samples, not-a-knot at the run's ends (a parabola through 3 samples, a line through
/// 2); NaN at the non-finite samples.
fn uneven_curvatures(p: &[f64], t: &[f64]) -> Vec<f64> {
    let mut m = vec![f64::NAN; p.len()];
    for run in finite_runs(p) {
        uneven_run_curvatures(&p[run.clone()], &t[run.clone()], &mut m[run]);
    }
    m
}

/// The runs of consecutive finite samples of `p`, in order.
fn finite_runs(p: &[f64]) -> impl Iterator<Item = std::ops::Range<usize>> + '_ {
    let mut start = 0;
    std::iter::from_fn(move || {
        start += p[start.min(p.len())..].iter().position(|v| v.is_finite())?;
        let end = p[start..]
            .iter()
            .position(|v| !v.is_finite())
            .map_or(p.len(), |k| start + k);
        let run = start..end;
        start = end;
        Some(run)
    })
}

/// [`uneven_curvatures`] of one run of finite samples, into `m`.
fn uneven_run_curvatures(p: &[f64], t: &[f64], m: &mut [f64]) {
    let n = p.len();
    let h = |i: usize| t[i + 1] - t[i];
    let slope = |i: usize| (p[i + 1] - p[i]) / h(i);
    match n {
        0 => {}
        1 | 2 => m.fill(0.0),
        3 => m.fill(2.0 * (slope(1) - slope(0)) / (t[2] - t[0])),
        _ => {
            // Inside: h[i-1] m[i-1] + 2 (h[i-1] + h[i]) m[i] + h[i] m[i+1] = 6 (slope[i] -
            // slope[i-1]); not-a-knot (the third derivative continuous at knots 1 and n-2):
            // m0 = ((h0 + h1) m1 - h0 m2) / h1 and its mirror at the end, eliminated into the
            // first and last rows. Thomas algorithm; row j is for the unknown m[j+1].
            let k = n - 2;
            let mut lower = vec![0.0; k];
            let mut diag = vec![0.0; k];
            let mut upper = vec![0.0; k];
            let mut d = vec![0.0; k];
            for j in 0..k {
                let i = j + 1;
                let (a, b) = (h(i - 1), h(i));
                lower[j] = a;
                diag[j] = 2.0 * (a + b);
                upper[j] = b;
                d[j] = 6.0 * (slope(i) - slope(i - 1));
            }
            let (h0, h1) = (h(0), h(1));
            diag[0] += h0 * (h0 + h1) / h1;
            upper[0] -= h0 * h0 / h1;
            lower[0] = 0.0;
            let (hb, ha) = (h(n - 2), h(n - 3));
            diag[k - 1] += hb * (hb + ha) / ha;
            lower[k - 1] -= hb * hb / ha;
            upper[k - 1] = 0.0;
            let mut c = vec![0.0; k];
            let mut x = vec![0.0; k];
            for j in 0..k {
                let (c_prev, x_prev) = if j > 0 { (c[j - 1], x[j - 1]) } else { (0.0, 0.0) };
                let denom = diag[j] - lower[j] * c_prev;
                c[j] = upper[j] / denom;
                x[j] = (d[j] - lower[j] * x_prev) / denom;
            }
            for j in (0..k - 1).rev() {
                x[j] -= c[j] * x[j + 1];
            }
            m[1..n - 1].copy_from_slice(&x);
            m[0] = ((h0 + h1) * m[1] - h0 * m[2]) / h1;
            m[n - 1] = ((hb + ha) * m[n - 2] - hb * m[n - 3]) / ha;
        }
    }
}

/// The second derivatives (in samples: times step²) of the interpolating cubic spline of each
/// run of finite samples, not-a-knot at the run's ends (a parabola through 3 samples, a line
/// through 2); NaN at the non-finite samples.
fn curvatures(p: &[f64]) -> Vec<f64> {
    let mut m = vec![f64::NAN; p.len()];
    for run in finite_runs(p) {
        run_curvatures(&p[run.clone()], &mut m[run]);
    }
    m
}

/// [`curvatures`] of one run of finite samples, into `m`.
fn run_curvatures(p: &[f64], m: &mut [f64]) {
    let n = p.len();
    match n {
        0 => {}
        1 | 2 => m.fill(0.0),
        3 => m.fill(p[0] - 2.0 * p[1] + p[2]),
        _ => {
            // Unit spacing: m[i-1] + 4 m[i] + m[i+1] = 6 (p[i-1] - 2 p[i] + p[i+1]) inside, and
            // not-a-knot (the third derivative continuous at samples 1 and n-2): m0 = 2 m1 - m2,
            // m[n-1] = 2 m[n-2] - m[n-3]. Eliminated, the unknowns m1 .. m[n-2] solve a
            // tridiagonal system whose first and last rows are 6 m1 = d1 and 6 m[n-2] = d[n-2]
            // (the n = 4 system is then diagonal too).
            let k = n - 2;
            let d = |i: usize| 6.0 * (p[i - 1] - 2.0 * p[i] + p[i + 1]);
            // Thomas algorithm; row j is for the unknown m[j+1].
            let mut c = vec![0.0; k];
            let mut x = vec![0.0; k];
            for j in 0..k {
                let inner = j > 0 && j < k - 1;
                let (lower, diag, upper) = if inner { (1.0, 4.0, 1.0) } else { (0.0, 6.0, 0.0) };
                let (c_prev, x_prev) = if j > 0 { (c[j - 1], x[j - 1]) } else { (0.0, 0.0) };
                let denom = diag - lower * c_prev;
                c[j] = upper / denom;
                x[j] = (d(j + 1) - lower * x_prev) / denom;
            }
            for j in (0..k - 1).rev() {
                x[j] -= c[j] * x[j + 1];
            }
            m[1..n - 1].copy_from_slice(&x);
            m[0] = 2.0 * m[1] - m[2];
            m[n - 1] = 2.0 * m[n - 2] - m[n - 3];
        }
    }
}

impl fmt::Debug for MeasuredDrive {
    /// The grid and the number of samples, not the samples.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("MeasuredDrive")
            .field("len", &self.samples.len())
            .field("start_time", &self.start_time)
            .field("step", &self.step)
            .field("stamped", &self.stamps.is_some())
            .finish()
    }
}
