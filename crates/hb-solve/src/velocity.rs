//! The velocity at a segment's samples, from the segment's Fourier series: what the terms
//! nonlinear in `x'` (`sign(x')`, `x'*|x'|`, `x'^3`) are evaluated at, in both methods.

use hb_basis::FourierPlan;

use crate::error::{AssemblyError, SolveError};

/// The fewest samples (the closing one included) a segment's velocity is estimated from.
const MIN_SAMPLES: usize = 9;

/// The trend taken out of a segment before its Fourier series is differentiated (see
/// [`velocity_series`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VelocityTrend {
    /// The line through both end samples: on an orbit, its rotation `w_ck τ` (plus the closure
    /// error); what is left is the oscillation of eq. 9, periodic up to the closure error. Exact
    /// for a periodic band-limited record. Harmonic balance uses it.
    Line,
    /// The quintic through both end samples with the slopes and curvatures there of a
    /// least-squares cubic fitted to each end's eighth of a forcing period (at least 4 samples):
    /// what is left vanishes at both ends with nearly zero slope and curvature, so that its
    /// periodic extension is nearly smooth where it joins, even for a window that is not
    /// periodic. The weak form uses it.
    Quintic,
}

/// The velocity at the `L + 1` samples of a continuous segment `x` (unwrapped on the circle, its
/// closing sample last) over `periods` forcing periods with sample step `step`, from its Fourier
/// series up to harmonic `harmonics` of the segment: what the terms nonlinear in `x'` are
/// evaluated at.
///
/// The segment less its `trend` is a sequence whose periodic extension is continuous (and, with
/// [`VelocityTrend::Quintic`], nearly smooth); the derivative of its trigonometric interpolant up
/// to `harmonics` ([`FourierPlan::derivative`], at most `(L − 1) / 2`) plus the trend's
/// derivative is the estimate; the closing sample is the periodic continuation of the series.
/// The Fourier series of a sequence whose periodic extension kinks converges slowly (the error
/// of the derivative falls as `1 / harmonics`), so the quintic trend matters for windows;
/// `docs/identification.md` measures both against the cut `harmonics`.
///
/// Errors: fewer than 9 samples, a step that is not positive and finite, a non-finite sample.
///
/// ```
/// use hb_solve::{VelocityTrend, velocity_series};
///
/// // x = 0.3 t + sin(t) over one period of 50 samples: periodic but for the rotation.
/// let h = std::f64::consts::TAU / 50.0;
/// let x: Vec<f64> = (0..=50).map(|n| 0.3 * n as f64 * h + (n as f64 * h).sin()).collect();
/// let v = velocity_series(&x, h, 1, 8, VelocityTrend::Line)?;
/// for (n, v) in v.iter().enumerate() {
///     assert!((v - 0.3 - (n as f64 * h).cos()).abs() < 1e-12);
/// }
/// // x = 0.3 t + sin(t) + 0.2 t², not periodic: the quintic trend keeps the error small.
/// let h = std::f64::consts::TAU / 200.0;
/// let x: Vec<f64> = (0..=200)
///     .map(|n| {
///         let t = n as f64 * h;
///         0.3 * t + t.sin() + 0.2 * t * t
///     })
///     .collect();
/// for (trend, tolerance) in [(VelocityTrend::Quintic, 1e-3), (VelocityTrend::Line, 0.2)] {
///     let v = velocity_series(&x, h, 1, 40, trend)?;
///     for (n, v) in v.iter().enumerate().skip(20).take(160) {
///         let t = n as f64 * h;
///         assert!((v - 0.3 - t.cos() - 0.4 * t).abs() < tolerance, "{trend:?} {n}: {v}");
///     }
/// }
/// # Ok::<(), hb_solve::SolveError>(())
/// ```
pub fn velocity_series(
    x: &[f64],
    step: f64,
    periods: usize,
    harmonics: usize,
    trend: VelocityTrend,
) -> Result<Vec<f64>, SolveError> {
    if x.len() < MIN_SAMPLES {
        return Err(SolveError::Assembly(AssemblyError::RecordTooShort {
            what: "the velocity series",
            len: x.len(),
            needed: MIN_SAMPLES,
        }));
    }
    if !(step.is_finite() && step > 0.0) {
        return Err(SolveError::InvalidParameter {
            name: "sample step",
            value: step,
            why: "must be positive and finite",
        });
    }
    if let Some((index, &value)) = x.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(SolveError::Assembly(AssemblyError::NonFiniteRecordSample {
            index,
            value,
        }));
    }
    let mut plan = FourierPlan::new(x.len() - 1)?;
    let (mut detrended, mut out) = (Vec::new(), Vec::new());
    let series = Series {
        periods,
        harmonics,
        step,
        trend,
    };
    velocity_into(
        &mut plan,
        &mut TrendTables::default(),
        x,
        series,
        &mut detrended,
        &mut out,
    )?;
    Ok(out)
}

/// Samples each end's cubic is fitted to, on a segment of `l` samples over `periods` forcing
/// periods: an eighth of a forcing period (at least 4 samples, at most a quarter of the segment).
fn end_fit_len(l: usize, periods: usize) -> usize {
    let quarter = (l / 4).max(2);
    (l / (8 * periods.max(1))).clamp(4.min(quarter), quarter)
}

/// The slope and curvature (per sample) at the first of `x`'s `m + 1` samples of the
/// least-squares cubic through them (a quadratic or a line when `m` is too small for a cubic),
/// by the normal equations `fit` of `m` holds; `x` runs from that end inwards (reversed at the
/// window's last sample).
fn end_slope<'a>(x: impl Iterator<Item = &'a f64> + Clone, fit: &EndFit) -> (f64, f64) {
    let EndFit {
        m,
        degree,
        ref powers,
        ref gram,
        ref factors,
    } = *fit;
    let mut rhs = [0.0; 4];
    let first = x.clone().next().copied().unwrap_or(f64::NAN);
    for (p, &v) in powers.iter().zip(x.take(m + 1)) {
        for r in 0..=degree {
            rhs[r] += p[r] * (v - first);
        }
    }
    // The elimination of the normal equations, on the right-hand side.
    for c in 0..=degree {
        for r in c + 1..=degree {
            rhs[r] -= factors[r][c] * rhs[c];
        }
    }
    let mut coef = [0.0; 4];
    for r in (0..=degree).rev() {
        let tail: f64 = (r + 1..=degree).map(|k| gram[r][k] * coef[k]).sum();
        coef[r] = (rhs[r] - tail) / gram[r][r];
    }
    // d/dn at s = 0 is c_1 / m, d²/dn² is 2 c_2 / m².
    let mf = m as f64;
    (coef[1] / mf, 2.0 * coef[2] / (mf * mf))
}

/// The least-squares fit of `Σ c_k s^k`, `k = 0..=degree`, `s = n / m`, to `m + 1` samples, as
/// far as it depends on `m` alone: the powers of `s` at each sample, and the normal equations
/// (the Gram matrix of 1, s, s², s³ on `m + 1 >= degree + 1` points, positive definite) after
/// Gaussian elimination with the factors it took.
#[derive(Debug, Clone, Default)]
struct EndFit {
    m: usize,
    degree: usize,
    powers: Vec<[f64; 4]>,
    gram: [[f64; 4]; 4],
    factors: [[f64; 4]; 4],
}

impl EndFit {
    fn new(m: usize) -> Self {
        let degree = m.min(3);
        let mut gram = [[0.0; 4]; 4];
        let powers: Vec<[f64; 4]> = (0..=m)
            .map(|n| {
                let s = n as f64 / m as f64;
                let mut p = [1.0; 4];
                for k in 1..=degree {
                    p[k] = p[k - 1] * s;
                }
                for r in 0..=degree {
                    for c in 0..=degree {
                        gram[r][c] += p[r] * p[c];
                    }
                }
                p
            })
            .collect();
        let mut factors = [[0.0; 4]; 4];
        for c in 0..=degree {
            for r in c + 1..=degree {
                let f = gram[r][c] / gram[c][c];
                factors[r][c] = f;
                let pivot_row = gram[c];
                for (g, p) in gram[r].iter_mut().zip(pivot_row).take(degree + 1).skip(c) {
                    *g -= f * p;
                }
            }
        }
        Self {
            m,
            degree,
            powers,
            gram,
            factors,
        }
    }
}

/// What a velocity estimate with the quintic trend computes from a window's length alone, kept
/// for the next window of that length (the weak form's windows mostly have one): the end fits,
/// and the trend's six Hermite functions and their derivatives at every sample.
#[derive(Debug, Clone, Default)]
pub(crate) struct TrendTables {
    /// The window's samples less one and the end fit's length the tables are for.
    at: Option<(usize, usize)>,
    fit: EndFit,
    /// `h0, h1, h2, k0, k1, k2` at `s = n / L`, `n = 0..=L`.
    value: Vec<[f64; 6]>,
    /// Their derivatives in `s`.
    slope: Vec<[f64; 6]>,
}

impl TrendTables {
    /// The tables of windows of `l + 1` samples whose ends are fitted over `m + 1`.
    fn make(&mut self, l: usize, m: usize) {
        if self.at == Some((l, m)) {
            return;
        }
        let lf = l as f64;
        self.fit = EndFit::new(m);
        self.value.clear();
        self.slope.clear();
        for n in 0..=l {
            let s = n as f64 / lf;
            let (s2, s3, s4, s5) = (s * s, s * s * s, s.powi(4), s.powi(5));
            self.value.push([
                1.0 - 10.0 * s3 + 15.0 * s4 - 6.0 * s5,
                s - 6.0 * s3 + 8.0 * s4 - 3.0 * s5,
                0.5 * s2 - 1.5 * s3 + 1.5 * s4 - 0.5 * s5,
                10.0 * s3 - 15.0 * s4 + 6.0 * s5,
                -4.0 * s3 + 7.0 * s4 - 3.0 * s5,
                0.5 * s3 - s4 + 0.5 * s5,
            ]);
            self.slope.push([
                -30.0 * s2 + 60.0 * s3 - 30.0 * s4,
                1.0 - 18.0 * s2 + 32.0 * s3 - 15.0 * s4,
                s - 4.5 * s2 + 6.0 * s3 - 2.5 * s4,
                30.0 * s2 - 60.0 * s3 + 30.0 * s4,
                -12.0 * s2 + 28.0 * s3 - 15.0 * s4,
                1.5 * s2 - 4.0 * s3 + 2.5 * s4,
            ]);
        }
        self.at = Some((l, m));
    }
}

/// What [`velocity_series`] is asked for, besides the samples.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Series {
    /// Forcing periods of the segment.
    pub(crate) periods: usize,
    /// Harmonics of the segment kept.
    pub(crate) harmonics: usize,
    /// Sample step.
    pub(crate) step: f64,
    pub(crate) trend: VelocityTrend,
}

/// [`velocity_series`] with a plan of length `L` and the caller's buffers.
pub(crate) fn velocity_into(
    plan: &mut FourierPlan,
    tables: &mut TrendTables,
    x: &[f64],
    series: Series,
    detrended: &mut Vec<f64>,
    out: &mut Vec<f64>,
) -> Result<(), SolveError> {
    let Series {
        periods,
        harmonics,
        step,
        trend,
    } = series;
    let l = x.len() - 1;
    let lf = l as f64;
    let (x0, xl) = (x[0], x[l]);
    // The slopes and curvatures (per sample) at both ends: the chord's, or a cubic's fitted to
    // each end.
    let ((d0, c0), (dl, cl)) = match trend {
        VelocityTrend::Line => (((xl - x0) / lf, 0.0), ((xl - x0) / lf, 0.0)),
        VelocityTrend::Quintic => {
            let m = end_fit_len(l, periods);
            tables.make(l, m);
            let (a, b) = (
                end_slope(x.iter(), &tables.fit),
                end_slope(x[l - m..].iter().rev(), &tables.fit),
            );
            (a, (-b.0, b.1))
        }
    };
    // The quintic Hermite trend through both ends with those slopes and curvatures (in s = n/L),
    // and its derivative in n.
    let (v1, v2) = (lf * d0, lf * dl);
    let (a1, a2) = (lf * lf * c0, lf * lf * cl);
    let weights = [x0, v1, a1, xl, v2, a2];
    let combine = |h: &[f64; 6]| {
        weights[0] * h[0]
            + weights[1] * h[1]
            + weights[2] * h[2]
            + weights[3] * h[3]
            + weights[4] * h[4]
            + weights[5] * h[5]
    };
    let value = |n: usize| combine(&tables.value[n]);
    let slope = |n: usize| combine(&tables.slope[n]) / lf;
    detrended.clear();
    match trend {
        // The chord exactly, so that a periodic record's oscillation comes out to rounding.
        VelocityTrend::Line => detrended.extend((0..l).map(|n| x[n] - x0 - d0 * n as f64)),
        VelocityTrend::Quintic => detrended.extend((0..l).map(|n| x[n] - value(n))),
    }
    out.resize(l + 1, 0.0);
    plan.derivative(detrended, harmonics, &mut out[..l])?;
    for (n, v) in out[..l].iter_mut().enumerate() {
        let trend_slope = match trend {
            VelocityTrend::Line => d0,
            VelocityTrend::Quintic => slope(n),
        };
        *v = (*v + trend_slope) / step;
    }
    // The rest's series is periodic: at the closing sample as at the first.
    out[l] = match trend {
        VelocityTrend::Line => out[0],
        VelocityTrend::Quintic => out[0] + (slope(l) - slope(0)) / step,
    };
    Ok(())
}

/// The acceleration at the `L + 1` samples of an orbit from its velocity `v` there (from
/// [`velocity_into`] with [`VelocityTrend::Line`]: the rotation's constant rate plus the
/// derivative of the oscillation's series, periodic): the derivative of the series of `v[..L]`,
/// all its harmonics (those of the velocity are already cut), in units of `step`; the closing
/// sample is the periodic continuation.
pub(crate) fn acceleration_into(
    plan: &mut FourierPlan,
    v: &[f64],
    step: f64,
    scratch: &mut Vec<f64>,
    out: &mut Vec<f64>,
) -> Result<(), SolveError> {
    let l = v.len() - 1;
    scratch.clear();
    scratch.extend_from_slice(&v[..l]);
    out.resize(l + 1, 0.0);
    plan.derivative(scratch, l, &mut out[..l])?;
    for a in &mut out[..l] {
        *a /= step;
    }
    out[l] = out[0];
    Ok(())
}

/// The mean of `sign(x')` over the cell of sample `n` (half a step on either side; the half
/// inside at the ends), with `x'` linear between the samples `v`: a step function sampled at its
/// points puts each jump at the nearest sample (an error of the order of the step in every
/// integral or Fourier coefficient of it), its cell means put it where the interpolated velocity
/// crosses zero. `periodic`: `v[0]` and `v[L]` are the same point (an orbit).
pub(crate) fn cell_sign(v: &[f64], n: usize, periodic: bool) -> f64 {
    let sign = |a: f64| hb_model::VelocityFactor::Sign.eval(a);
    // The mean of sign over a segment on which the velocity goes linearly from a to b.
    let half = |a: f64, b: f64| {
        if (a > 0.0 && b < 0.0) || (a < 0.0 && b > 0.0) {
            let before = a / (a - b);
            before * sign(a) + (1.0 - before) * sign(b)
        } else {
            // One sign throughout, but at an end where the velocity may be zero (NaN stays NaN).
            sign(a + b)
        }
    };
    let l = v.len() - 1;
    let left = match (n, periodic) {
        (0, true) => Some(v[l - 1]),
        (0, false) => None,
        _ => Some(v[n - 1]),
    };
    let right = match (n == l, periodic) {
        (true, true) => Some(v[1]),
        (true, false) => None,
        (false, _) => Some(v[n + 1]),
    };
    let here = v[n];
    match (left, right) {
        (Some(a), Some(b)) => 0.5 * (half(0.5 * (a + here), here) + half(here, 0.5 * (here + b))),
        (None, Some(b)) => half(here, 0.5 * (here + b)),
        (Some(a), None) => half(0.5 * (a + here), here),
        (None, None) => sign(here),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{PI, TAU};

    /// `∫_0^T w sign(v)` with `w = sin⁴(π τ / T)` and `v = sin(1.3 τ + 0.4)`, `T = 10`: by the
    /// trapezoid rule on `len` steps with the point values or the cell means of `sign(v)`, and
    /// by a fine midpoint rule (the reference).
    fn sign_integrals(len: usize) -> (f64, f64, f64) {
        let span = 10.0;
        let v = |t: f64| (1.3 * t + 0.4).sin();
        let w = |t: f64| (PI * t / span).sin().powi(4);
        let h = span / len as f64;
        let samples: Vec<f64> = (0..=len).map(|n| v(n as f64 * h)).collect();
        let (mut point, mut cell) = (0.0, 0.0);
        for n in 0..=len {
            let q = if n == 0 || n == len { 0.5 * h } else { h };
            let t = n as f64 * h;
            point += q * w(t) * hb_model::VelocityFactor::Sign.eval(samples[n]);
            cell += q * w(t) * cell_sign(&samples, n, false);
        }
        // The reference: between the crossings of v (1.3 τ + 0.4 = jπ), w by composite Simpson
        // on fine steps, with the sign of each piece.
        let mut cuts = vec![0.0];
        let mut j = 1.0;
        while (j * PI - 0.4) / 1.3 < span {
            cuts.push((j * PI - 0.4) / 1.3);
            j += 1.0;
        }
        cuts.push(span);
        let exact: f64 = cuts
            .windows(2)
            .map(|c| {
                let (a, b) = (c[0], c[1]);
                let steps = 20_000;
                let hs = (b - a) / steps as f64;
                let simpson: f64 = (0..=steps)
                    .map(|i| {
                        let f = w(a + i as f64 * hs);
                        match i {
                            0 => f,
                            i if i == steps => f,
                            i if i % 2 == 1 => 4.0 * f,
                            _ => 2.0 * f,
                        }
                    })
                    .sum::<f64>()
                    * hs
                    / 3.0;
                simpson * v(0.5 * (a + b)).signum()
            })
            .sum();
        (point - exact, cell - exact, exact)
    }

    /// Cell means put the jumps of `sign` where the interpolated velocity crosses zero: the
    /// integral's error is at least ten times below the point values' (whose error, of the order
    /// of the step, depends on where the crossings fall between samples) and falls with the step.
    #[test]
    fn cell_means_of_sign_put_the_jumps_between_samples() {
        let mut previous = f64::INFINITY;
        for len in [40, 80, 160, 320] {
            let (point, cell, _) = sign_integrals(len);
            assert!(
                cell.abs() < 0.1 * point.abs(),
                "{len}: cell {cell:e}, point {point:e}"
            );
            assert!(cell.abs() < previous, "{len}: {cell:e}");
            previous = cell.abs();
        }
        assert!(previous < 2e-4, "{previous:e}");
        // Away from a crossing the cell mean is the sign; over a whole cell across one it is the
        // fraction on either side.
        assert_eq!(cell_sign(&[1.0, 2.0, 3.0], 1, false), 1.0);
        assert!((cell_sign(&[-1.0, 1.0, 3.0], 1, false) - 1.0).abs() < 1e-15);
        assert!((cell_sign(&[-1.0, -1.0, 1.0], 1, false) + 1.0).abs() < 1e-15);
        assert_eq!(cell_sign(&[0.0, 0.0, 0.0], 1, false), 0.0);
        assert!(cell_sign(&[0.0, f64::NAN, 0.0], 1, false).is_nan());
        assert!((cell_sign(&[-3.0, 1.0, 5.0], 1, false) - 0.5).abs() < 1e-15);
        // Periodic: the neighbour of the first sample is the last but one.
        assert!((cell_sign(&[1.0, 2.0, -3.0, 1.0], 0, true) - 0.5).abs() < 1e-15);
    }

    /// A window that is not periodic: the quintic trend keeps the velocity's error (window-weighted
    /// RMS, relative) more than ten times below the line's, and it falls as harmonics are kept.
    #[test]
    fn trends_of_a_window() {
        let (l, k) = (300, 3);
        let h = 3.0 * TAU / l as f64;
        let x: Vec<f64> = (0..=l)
            .map(|n| {
                let t = n as f64 * h;
                0.7 * t + (t + 0.3).sin() + 0.4 * (2.3 * t).cos() + 0.01 * t * t
            })
            .collect();
        let truth = |n: usize| {
            let t = n as f64 * h;
            0.7 + (t + 0.3).cos() - 0.92 * (2.3 * t).sin() + 0.02 * t
        };
        let rms = |trend, harmonics| {
            let v = velocity_series(&x, h, k, harmonics, trend).unwrap();
            let (mut num, mut den) = (0.0, 0.0);
            for (n, v) in v.iter().enumerate() {
                let w = (PI * n as f64 / l as f64).sin().powi(4);
                num += w * (v - truth(n)).powi(2);
                den += w * truth(n).powi(2);
            }
            (num / den).sqrt()
        };
        let mut previous = f64::INFINITY;
        for harmonics in [24, 48, 96] {
            let (line, quintic) = (
                rms(VelocityTrend::Line, harmonics),
                rms(VelocityTrend::Quintic, harmonics),
            );
            assert!(
                quintic < 0.1 * line,
                "{harmonics}: quintic {quintic:e}, line {line:e}"
            );
            assert!(quintic < previous);
            previous = quintic;
        }
        assert!(rms(VelocityTrend::Quintic, 24) < 5e-4);
        // Errors of the input.
        assert!(velocity_series(&x[..5], h, k, 2, VelocityTrend::Line).is_err());
        assert!(velocity_series(&x, 0.0, k, 2, VelocityTrend::Line).is_err());
        let mut bad = x.clone();
        bad[7] = f64::NAN;
        assert!(velocity_series(&bad, h, k, 2, VelocityTrend::Line).is_err());
    }
}
