//! Fourier coefficients of sampled segments with planned real FFTs.
//!
//! Conventions (method notes section 2): a segment of `L` samples `s_0 .. s_{L−1}` is expanded as
//! `s_n ≈ a_0/2 + Σ_j (a_j cos(2π j n / L) + b_j sin(2π j n / L))`. With the DFT
//! `S_j = Σ_n s_n e^{−2πi j n / L}`, `a_j = 2 Re(S_j) / L` and `b_j = −2 Im(S_j) / L` for
//! `0 <= j < L/2`; for even `L` the Nyquist term `j = L/2` is halved (`a = Re(S_j) / L`, `b = 0`).
//! For a segment spanning `k` forcing periods, harmonic `j` has `j / k` times the forcing
//! frequency.

use std::fmt;

use hb_fft::{Complex, Forward, Inverse, Planner};

use crate::error::BasisError;

/// A complex number of `f64`, the element of a spectrum.
pub type Complex64 = Complex<f64>;

/// The sine and cosine coefficients `(a_j, b_j)` of harmonic `j` of a length-`len` segment, from its
/// DFT bin `S_j` (halved at the Nyquist frequency of an even length).
#[inline]
pub fn coefficients_from_bin(bin: Complex64, j: usize, len: usize) -> (f64, f64) {
    let scale = if 2 * j == len { 1.0 } else { 2.0 } / len as f64;
    if 2 * j == len {
        (bin.re * scale, 0.0)
    } else {
        (bin.re * scale, -bin.im * scale)
    }
}

/// The DFT of one real segment: bins `S_0 ..= S_{L/2}` (the others follow by symmetry).
#[derive(Debug, Clone, Copy)]
pub struct Spectrum<'a> {
    bins: &'a [Complex64],
    len: usize,
}

impl<'a> Spectrum<'a> {
    /// A spectrum view of `bins` (`len / 2 + 1` of them) of a real segment of `len` samples.
    pub fn new(bins: &'a [Complex64], len: usize) -> Result<Self, BasisError> {
        if bins.len() != len / 2 + 1 {
            return Err(BasisError::LengthMismatch {
                what: "spectrum",
                expected: len / 2 + 1,
                found: bins.len(),
            });
        }
        Ok(Self { bins, len })
    }

    /// Length `L` of the transformed segment.
    pub fn segment_len(&self) -> usize {
        self.len
    }

    /// The stored bins `S_0 ..= S_{L/2}`.
    pub fn bins(&self) -> &'a [Complex64] {
        self.bins
    }

    /// Bin `S_j` for any integer `j`, using `S_{j+L} = S_j` and `S_{−j} = conj(S_j)`.
    #[inline]
    pub fn bin(&self, j: isize) -> Complex64 {
        let l = self.len as isize;
        let j = j.rem_euclid(l) as usize;
        if j <= self.len / 2 {
            self.bins[j]
        } else {
            self.bins[self.len - j].conj()
        }
    }

    /// `(a_j, b_j)` of harmonic `j`, or `None` above the Nyquist harmonic `L/2`.
    #[inline]
    pub fn coefficients(&self, j: usize) -> Option<(f64, f64)> {
        (j <= self.len / 2).then(|| coefficients_from_bin(self.bins[j], j, self.len))
    }

    /// Bins `j` of the DFTs of the modulated segments `s_n cos(φ + 2π m n / L)` and
    /// `s_n sin(φ + 2π m n / L)`, by the shift theorem (exact, no new transform):
    ///
    /// `(e^{iφ} S_{j−m} + e^{−iφ} S_{j+m}) / 2` and `(e^{iφ} S_{j−m} − e^{−iφ} S_{j+m}) / 2i`.
    ///
    /// `phasor` is `e^{iφ}` (`Complex64::from_polar(1.0, φ)`), computed once by the caller for all
    /// `j`. With `m = k` and `φ = W t_start` this gives the Fourier coefficients of `φ_i(x) cos(W t)`
    /// and `φ_i(x) sin(W t)` over a period-`k` segment (paper eqs. 13-14) from those of `φ_i(x)`.
    #[inline]
    pub fn modulated_bins(&self, j: isize, m: isize, phasor: Complex64) -> (Complex64, Complex64) {
        let lo = phasor * self.bin(j - m);
        let hi = phasor.conj() * self.bin(j + m);
        let cos_bin = (lo + hi) * 0.5;
        // (lo − hi) / 2i = −i (lo − hi) / 2
        let d = lo - hi;
        let sin_bin = Complex64::new(d.im, -d.re) * 0.5;
        (cos_bin, sin_bin)
    }
}

/// A planned real FFT for one segment length, with its own input, output and scratch buffers, to
/// be reused across every segment of that length (no allocation per transform).
///
/// Cloning shares the plan and copies the buffers, so each worker thread can own a clone.
#[derive(Clone)]
pub struct FourierPlan {
    fft: Forward,
    input: Vec<f64>,
    bins: Vec<Complex64>,
    scratch: Vec<Complex64>,
    /// The inverse transform and its scratch, planned on the first [`FourierPlan::derivative`].
    inverse: Option<(Inverse, Vec<Complex64>)>,
}

impl fmt::Debug for FourierPlan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("FourierPlan")
            .field("len", &self.len())
            .finish_non_exhaustive()
    }
}

impl FourierPlan {
    /// A plan for segments of `len >= 2` samples.
    pub fn new(len: usize) -> Result<Self, BasisError> {
        Self::with_planner(len, &mut Planner::new())
    }

    fn with_planner(len: usize, planner: &mut Planner) -> Result<Self, BasisError> {
        if len < 2 {
            return Err(BasisError::TooSmall {
                name: "segment length",
                value: len,
                min: 2,
            });
        }
        let fft = planner.forward(len);
        let input = fft.make_input_vec();
        let bins = fft.make_output_vec();
        let scratch = fft.make_scratch_vec();
        Ok(Self {
            fft,
            input,
            bins,
            scratch,
            inverse: None,
        })
    }

    /// The segment length `L` this plan transforms.
    pub fn len(&self) -> usize {
        self.input.len()
    }

    /// Always false: a plan has at least two samples.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The highest harmonic a segment of this length resolves, `L / 2`.
    pub fn max_harmonic(&self) -> usize {
        self.len() / 2
    }

    /// The DFT of `signal` (`L` finite samples).
    pub fn transform(&mut self, signal: &[f64]) -> Result<Spectrum<'_>, BasisError> {
        let len = self.len();
        if signal.len() != len {
            return Err(BasisError::LengthMismatch {
                what: "segment",
                expected: len,
                found: signal.len(),
            });
        }
        if let Some((index, &value)) = signal.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(BasisError::NonFinite { index, value });
        }
        self.input.copy_from_slice(signal);
        // The buffers were made by the plan itself, so their lengths are right.
        self.fft
            .process_with_scratch(&mut self.input, &mut self.bins, &mut self.scratch)
            .map_err(|_| BasisError::LengthMismatch {
                what: "FFT buffers",
                expected: len,
                found: len,
            })?;
        Ok(Spectrum {
            bins: &self.bins,
            len,
        })
    }

    /// The derivative, with respect to the sample index `n`, of the trigonometric interpolant of
    /// `signal` (`L` finite samples) truncated to harmonics `1..=cutoff`, at every sample:
    ///
    /// `out_n = Σ_{j=1}^{cutoff} (2πj/L) (b_j cos(2πjn/L) − a_j sin(2πjn/L))`
    ///
    /// (divide by the sample step for a time derivative). `cutoff` is lowered to `(L − 1) / 2`
    /// when above: the Nyquist harmonic of an even length has no derivative the samples
    /// determine. Exact (to rounding) for a trigonometric polynomial of degree at most `cutoff`;
    /// one forward and one inverse real FFT (the inverse planned on first use).
    pub fn derivative(&mut self, signal: &[f64], cutoff: usize, out: &mut [f64]) -> Result<(), BasisError> {
        let len = self.len();
        if out.len() != len {
            return Err(BasisError::LengthMismatch {
                what: "derivative output",
                expected: len,
                found: out.len(),
            });
        }
        self.transform(signal)?;
        let cutoff = cutoff.min((len - 1) / 2);
        let step = std::f64::consts::TAU / len as f64;
        for (j, bin) in self.bins.iter_mut().enumerate() {
            *bin = if (1..=cutoff).contains(&j) {
                // i ω_j S_j, and 1/L for the inverse transform.
                let w = step * j as f64 / len as f64;
                Complex64::new(-w * bin.im, w * bin.re)
            } else {
                Complex64::new(0.0, 0.0)
            };
        }
        let (inverse, scratch) = self.inverse.get_or_insert_with(|| {
            let inverse = Planner::new().inverse(len);
            let scratch = inverse.make_scratch_vec();
            (inverse, scratch)
        });
        // The bins were made by the forward plan of the same length, and bins 0 and L/2 are zero.
        inverse
            .process_with_scratch(&mut self.bins, out, scratch)
            .map_err(|_| BasisError::LengthMismatch {
                what: "inverse FFT buffers",
                expected: len,
                found: out.len(),
            })
    }

    /// The coefficients `a_0 ..= a_M` into `a` and `b_0 ..= b_M` into `b` (`M = a.len() − 1`, at
    /// most `L / 2`; `b_0 = 0`).
    pub fn coefficients(&mut self, signal: &[f64], a: &mut [f64], b: &mut [f64]) -> Result<(), BasisError> {
        if a.len() != b.len() {
            return Err(BasisError::LengthMismatch {
                what: "b",
                expected: a.len(),
                found: b.len(),
            });
        }
        let max = self.max_harmonic();
        if a.len() > max + 1 {
            return Err(BasisError::HarmonicOutOfRange {
                requested: a.len() - 1,
                len: self.len(),
                max,
            });
        }
        let spectrum = self.transform(signal)?;
        for (j, (aj, bj)) in a.iter_mut().zip(b.iter_mut()).enumerate() {
            (*aj, *bj) = coefficients_from_bin(spectrum.bins[j], j, spectrum.len);
        }
        Ok(())
    }
}

/// A cache of [`FourierPlan`]s, one per segment length, sharing one FFT planner.
///
/// Period-`k` segments have `k P` samples, so a close-return search over periods `1..=16` needs at
/// most 16 plans. Cloning copies the plans (sharing the FFTs) and starts a fresh planner.
#[derive(Default)]
pub struct FourierPlanner {
    planner: Planner,
    plans: Vec<FourierPlan>,
}

impl fmt::Debug for FourierPlanner {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let lens: Vec<usize> = self.plans.iter().map(FourierPlan::len).collect();
        f.debug_struct("FourierPlanner")
            .field("lengths", &lens)
            .finish_non_exhaustive()
    }
}

impl Clone for FourierPlanner {
    fn clone(&self) -> Self {
        Self {
            planner: Planner::new(),
            plans: self.plans.clone(),
        }
    }
}

impl FourierPlanner {
    /// An empty cache.
    pub fn new() -> Self {
        Self::default()
    }

    /// The plan for segments of `len` samples, made on first use.
    pub fn plan(&mut self, len: usize) -> Result<&mut FourierPlan, BasisError> {
        let pos = match self.plans.iter().position(|p| p.len() == len) {
            Some(pos) => pos,
            None => {
                let plan = FourierPlan::with_planner(len, &mut self.planner)?;
                self.plans.push(plan);
                self.plans.len() - 1
            }
        };
        Ok(&mut self.plans[pos])
    }

    /// Number of lengths planned so far.
    pub fn len(&self) -> usize {
        self.plans.len()
    }

    /// Whether no length has been planned yet.
    pub fn is_empty(&self) -> bool {
        self.plans.is_empty()
    }
}

/// One-shot coefficients `a_0 ..= a_M`, `b_0 ..= b_M` of a segment (plans a transform each call;
/// use a [`FourierPlan`] to transform many segments).
pub fn fourier_coefficients(signal: &[f64], harmonics: usize) -> Result<(Vec<f64>, Vec<f64>), BasisError> {
    let mut plan = FourierPlan::new(signal.len())?;
    let mut a = vec![0.0; harmonics + 1];
    let mut b = vec![0.0; harmonics + 1];
    plan.coefficients(signal, &mut a, &mut b)?;
    Ok((a, b))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::TAU;

    #[test]
    fn pure_tones() {
        let l = 24;
        let s: Vec<f64> = (0..l)
            .map(|n| {
                let t = TAU * n as f64 / l as f64;
                0.5 + 2.0 * (3.0 * t).cos() - 1.5 * (5.0 * t).sin() + 0.25 * (12.0 * t).cos()
            })
            .collect();
        let (a, b) = fourier_coefficients(&s, 12).unwrap();
        let mut want_a = [0.0; 13];
        let mut want_b = [0.0; 13];
        want_a[0] = 1.0;
        want_a[3] = 2.0;
        want_b[5] = -1.5;
        want_a[12] = 0.25;
        for j in 0..=12 {
            assert!((a[j] - want_a[j]).abs() < 1e-13, "a_{j} = {}", a[j]);
            assert!((b[j] - want_b[j]).abs() < 1e-13, "b_{j} = {}", b[j]);
        }
    }

    #[test]
    fn rejects_bad_input() {
        assert!(matches!(FourierPlan::new(1), Err(BasisError::TooSmall { .. })));
        let mut p = FourierPlan::new(8).unwrap();
        assert!(matches!(
            p.transform(&[0.0; 7]),
            Err(BasisError::LengthMismatch { .. })
        ));
        let mut s = [0.0; 8];
        s[3] = f64::NAN;
        assert!(matches!(
            p.transform(&s),
            Err(BasisError::NonFinite { index: 3, .. })
        ));
        let (mut a, mut b) = ([0.0; 6], [0.0; 6]);
        assert!(matches!(
            p.coefficients(&[0.0; 8], &mut a, &mut b),
            Err(BasisError::HarmonicOutOfRange {
                requested: 5,
                max: 4,
                ..
            })
        ));
    }

    #[test]
    fn derivative_of_a_trigonometric_polynomial() {
        for l in [24, 25] {
            let w = TAU / l as f64;
            let s: Vec<f64> = (0..l)
                .map(|n| {
                    let t = w * n as f64;
                    0.5 + 2.0 * (3.0 * t).cos() - 1.5 * (5.0 * t).sin() + 0.25 * (9.0 * t).cos()
                })
                .collect();
            let mut plan = FourierPlan::new(l).unwrap();
            let mut d = vec![0.0; l];
            plan.derivative(&s, 11, &mut d).unwrap();
            // Truncated at 5: the 9th harmonic is left out.
            let mut d5 = vec![0.0; l];
            plan.derivative(&s, 5, &mut d5).unwrap();
            for n in 0..l {
                let t = w * n as f64;
                let full =
                    -6.0 * w * (3.0 * t).sin() - 7.5 * w * (5.0 * t).cos() - 2.25 * w * (9.0 * t).sin();
                assert!(
                    (d[n] - full).abs() < 1e-13,
                    "L {l}, n {n}: {} against {full}",
                    d[n]
                );
                assert!((d5[n] - full - 2.25 * w * (9.0 * t).sin()).abs() < 1e-13);
            }
            // The plan still transforms after an inverse.
            let (a, _) = fourier_coefficients(&s, 3).unwrap();
            assert!((a[3] - 2.0).abs() < 1e-13);
            assert!(plan.derivative(&s, 3, &mut d[..l - 1]).is_err());
        }
    }

    #[test]
    fn planner_reuses_plans() {
        let mut cache = FourierPlanner::new();
        cache.plan(25).unwrap();
        cache.plan(50).unwrap();
        cache.plan(25).unwrap();
        assert_eq!(cache.len(), 2);
        let mut copy = cache.clone();
        assert_eq!(copy.plan(50).unwrap().len(), 50);
    }
}
