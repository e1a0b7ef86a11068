//! Band-limited resampling onto a grid with a whole number of samples per forcing period.
//!
//! Real sampling rates and drive frequencies are never in a whole ratio (a 1.02 Hz drive sampled
//! at 500 Hz gives 490.196 samples per period), while close returns, periodic windows and the
//! paper's Fourier rows cut the record into whole forcing periods. The record is therefore
//! resampled once, at the input, onto the nearest grid with whole `P` (the choice and its measured
//! cost are in `docs/identification.md`): every later stage sees an ordinary whole clock.

use std::f64::consts::PI;

use crate::{CircleError, Domain, SampleClock, unwrap, wrap};

/// Half the number of taps of the interpolation kernel: the output starts and ends this many
/// input samples inside the record.
pub const RESAMPLE_HALF_WIDTH: usize = 64;

/// Kaiser window shape: about 140 dB of stop-band attenuation, so that the pass-band gain is flat
/// to about 1e-7.
const KAISER_BETA: f64 = 14.0;

/// Fraction of the Nyquist frequency of the coarser grid kept by the anti-aliasing low-pass.
const CUTOFF: f64 = 0.9;

/// A record on a grid with a whole number of samples per forcing period.
#[derive(Debug, Clone, PartialEq)]
pub struct Resampled {
    /// The samples (wrapped into `[−π, π)` on the circle).
    pub samples: Vec<f64>,
    /// Their clock: whole `P`, first sample `RESAMPLE_HALF_WIDTH` input steps after the record's.
    pub clock: SampleClock,
}

/// Resamples `x`, sampled on `clock`, onto the grid of `P = round(T / h)` samples per forcing
/// period by Kaiser-windowed sinc interpolation (`2 ·` [`RESAMPLE_HALF_WIDTH`] taps, a low-pass at
/// 0.9 of the coarser grid's Nyquist frequency, weights normalised to unit sum), of the unwrapped
/// angle on the circle and of the signal itself on the line, less the straight line through its
/// first and last samples (added back after).
///
/// A clock that is already whole is returned with the samples unchanged. Errors when the record
/// is too short for the kernel or holds a non-finite sample.
///
/// ```
/// use circle_signal::{Domain, SampleClock, resample_to_whole};
///
/// // 1.02 Hz drive sampled at 500 Hz: 490.196 samples per period, resampled to 490.
/// let clock = SampleClock::from_step(1.0 / 1.02, 1.0 / 500.0)?;
/// let x: Vec<f64> = (0..5000).map(|n| (std::f64::consts::TAU * 1.02 * clock.time(n)).sin()).collect();
/// let r = resample_to_whole(&x, &clock, Domain::Line)?;
/// assert_eq!(r.clock.whole_samples_per_period(), Some(490));
/// for (j, &v) in r.samples.iter().enumerate() {
///     let exact = (std::f64::consts::TAU * 1.02 * r.clock.time(j)).sin();
///     assert!((v - exact).abs() < 1e-6);
/// }
/// # Ok::<(), circle_signal::CircleError>(())
/// ```
pub fn resample_to_whole(x: &[f64], clock: &SampleClock, domain: Domain) -> Result<Resampled, CircleError> {
    if clock.whole_samples_per_period().is_some() {
        return Ok(Resampled {
            samples: x.to_vec(),
            clock: *clock,
        });
    }
    if let Some((index, &value)) = x.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(CircleError::NonFinite { index, value });
    }
    let half = RESAMPLE_HALF_WIDTH;
    let n = x.len();
    if n < 2 * half + 2 {
        return Err(CircleError::TooShort {
            len: n,
            needed: 2 * half + 2,
        });
    }
    let p = clock.samples_per_period().round().max(2.0) as usize;
    let out_clock = SampleClock::new(clock.forcing_period(), p)?
        .with_start_time(clock.start_time() + half as f64 * clock.step())?;
    // Output sample j sits at input position u_j = half + j · ratio.
    let ratio = out_clock.step() / clock.step();
    let last = (n - 1 - half) as f64;
    let count = ((last - half as f64) / ratio).floor() as usize + 1;

    let mut y = match domain {
        Domain::Circle => unwrap(x),
        Domain::Line => x.to_vec(),
    };
    let (y0, slope) = (y[0], (y[n - 1] - y[0]) / (n - 1) as f64);
    for (m, v) in y.iter_mut().enumerate() {
        *v -= y0 + slope * m as f64;
    }
    let fc = CUTOFF * ratio.recip().min(1.0);
    let norm = bessel_i0(KAISER_BETA);
    let mut weights = vec![0.0; 2 * half];
    let samples = (0..count)
        .map(|j| {
            let u = half as f64 + j as f64 * ratio;
            let base = u.floor() as usize;
            let first = base + 1 - half;
            let mut total = 0.0;
            for (k, w) in weights.iter_mut().enumerate() {
                let d = u - (first + k) as f64;
                let z = d / half as f64;
                let window = if z.abs() < 1.0 {
                    bessel_i0(KAISER_BETA * (1.0 - z * z).sqrt()) / norm
                } else {
                    0.0
                };
                *w = fc * sinc(fc * d) * window;
                total += *w;
            }
            let v: f64 = weights
                .iter()
                .zip(&y[first..first + 2 * half])
                .map(|(w, y)| w * y)
                .sum();
            let value = v / total + y0 + slope * u;
            match domain {
                Domain::Circle => wrap(value),
                Domain::Line => value,
            }
        })
        .collect();
    Ok(Resampled {
        samples,
        clock: out_clock,
    })
}

/// `sin(πz) / (πz)`.
fn sinc(z: f64) -> f64 {
    if z.abs() < 1e-12 {
        1.0
    } else {
        (PI * z).sin() / (PI * z)
    }
}

/// The modified Bessel function `I_0` by its power series (converges fast for the window's
/// arguments, at most [`KAISER_BETA`]).
fn bessel_i0(x: f64) -> f64 {
    let q = 0.25 * x * x;
    let (mut term, mut sum) = (1.0, 1.0);
    for k in 1..200 {
        term *= q / (k * k) as f64;
        sum += term;
        if term < 1e-17 * sum {
            break;
        }
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::TAU;

    #[test]
    fn bessel_values() {
        assert!((bessel_i0(0.0) - 1.0).abs() < 1e-15);
        assert!((bessel_i0(1.0) - 1.266_065_877_752_008_4).abs() < 1e-14);
        assert!((bessel_i0(14.0) / 129_418.563_9 - 1.0).abs() < 1e-8);
    }

    #[test]
    fn whirling_angle_through_the_wrap() {
        // A whirling angle (one turn per forcing period plus a wobble) seen wrapped.
        let clock = SampleClock::from_step(TAU, TAU / 97.3).unwrap();
        let f = |t: f64| t + 0.7 * (t + 0.3).sin() + 0.2 * (3.0 * t).cos();
        let x: Vec<f64> = (0..4000).map(|n| wrap(f(clock.time(n)))).collect();
        let r = resample_to_whole(&x, &clock, Domain::Circle).unwrap();
        assert_eq!(r.clock.whole_samples_per_period(), Some(97));
        let worst = r
            .samples
            .iter()
            .enumerate()
            .map(|(j, &v)| crate::circle_distance(v, f(r.clock.time(j))))
            .fold(0.0, f64::max);
        assert!(worst < 1e-7, "{worst}");
        // The output covers the record less the kernel's reach at both ends.
        let end = r.clock.time(r.samples.len() - 1);
        assert!(end <= clock.time(4000 - 1 - RESAMPLE_HALF_WIDTH) + 1e-9);
        assert!(end + r.clock.step() > clock.time(4000 - 1 - RESAMPLE_HALF_WIDTH) - 1e-9);
    }

    #[test]
    fn errors_and_whole_clocks() {
        let whole = SampleClock::new(1.0, 10).unwrap();
        let x = vec![0.5; 50];
        assert_eq!(resample_to_whole(&x, &whole, Domain::Line).unwrap().samples, x);
        let odd = SampleClock::from_step(1.0, 0.0937).unwrap();
        assert!(matches!(
            resample_to_whole(&x, &odd, Domain::Line),
            Err(CircleError::TooShort { .. })
        ));
        let mut y = vec![0.5; 500];
        y[100] = f64::NAN;
        assert!(matches!(
            resample_to_whole(&y, &odd, Domain::Line),
            Err(CircleError::NonFinite { index: 100, .. })
        ));
    }
}
