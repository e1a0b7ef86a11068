//! The period of a free oscillation, from the record alone: the time unit of a record with no
//! drive.
//!
//! The period is the strongest line of the spectrum of the record less its trend, found among the
//! lines that stand well above the spectrum around them, and refined between the bins of the
//! transform. Zero crossings of the position or of its velocity would be simpler, but an encoder's
//! counts defeat them: near rest a quantised record toggles between two counts every few samples,
//! and each toggle is a crossing (a 4096-count log of a 1.3 Hz decay at 1 kHz, 769 samples a
//! period, gave 17 to 18 samples by the crossings of its velocity). A spectral line is an average
//! over the whole record: the toggles, the quantisation and the decay of the swing spread their
//! power over every frequency and leave the line where it is.

use std::f64::consts::{LN_2, PI, TAU};
use std::fmt;
use std::ops::Range;

use hb_fft::{Complex, Planner};

use crate::{CircleError, Domain};

/// Why a record shows no oscillation whose period can be measured.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum NoOscillationReason {
    /// Fewer samples (on the circle: in the part of the record that swings) than the estimate
    /// needs.
    TooShort {
        /// Samples measured.
        samples: usize,
        /// Samples needed.
        needed: usize,
    },
    /// The record less its straight-line trend does not move.
    AtRest,
    /// No line of the spectrum stands above the spectrum around it by more than noise alone
    /// would.
    Noise {
        /// The largest ratio of a line's power to the median power around it.
        prominence: f64,
        /// The ratio a line must pass.
        needed: f64,
    },
    /// The strongest line is slower than two periods in the samples measured.
    TooFewPeriods {
        /// Its period, in samples.
        period: f64,
        /// Samples measured.
        samples: usize,
    },
}

impl fmt::Display for NoOscillationReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::TooShort { samples, needed } => {
                write!(f, "{samples} samples measured, at least {needed} are needed")
            }
            Self::AtRest => f.write_str("the record less its trend does not move"),
            Self::Noise { prominence, needed } => write!(
                f,
                "no line of its spectrum stands out of the noise (the strongest is {prominence:.3} times the \
                 median power around it, {needed:.3} is needed)"
            ),
            Self::TooFewPeriods { period, samples } => write!(
                f,
                "its strongest line has a period of {period:.1} samples, fewer than two periods in the {samples} \
                 samples measured"
            ),
        }
    }
}

/// The period of a free oscillation and how well the record shows it (see [`measure`](Self::measure)).
#[derive(Debug, Clone, PartialEq)]
pub struct OscillationPeriod {
    /// The period, in samples.
    pub samples: f64,
    /// The samples it was measured on: the whole record on the line; on the circle the part
    /// that swings (after the last whole turn, when the record starts whirling).
    pub measured: Range<usize>,
    /// The power of the line over the median power of the spectrum around it (within an octave
    /// either side): how far the oscillation stands out of the noise and the trend. Noise alone
    /// reaches [`OscillationPeriod::needed_prominence`] anywhere in the spectrum with
    /// probability about `10⁻⁶`.
    pub prominence: f64,
}

impl OscillationPeriod {
    /// Fewest samples measured: a spectrum of fewer has too few bins beside a line to tell it from
    /// noise.
    pub const MIN_SAMPLES: usize = 32;

    /// The probability that noise alone makes a line of the prominence needed, anywhere in the
    /// spectrum.
    pub const FALSE_LINE: f64 = 1e-6;

    /// The period of the oscillation of `x`, in samples, and how well the record shows it.
    ///
    /// The record is read as follows:
    ///
    /// 1. isolated spikes (bit errors) are removed by a median of three samples (on the circle,
    ///    the one of three angles closest to the other two), so that a spike of half a turn is not
    ///    unwrapped into a false turn (a record in which no oscillation survives the median, one
    ///    of four samples a period or faster, is measured as read);
    /// 2. on the circle the angle is unwrapped, and only the part after its last whole turn is
    ///    measured: a swing about the bottom spans less than a turn, so a decay that starts
    ///    whirling is measured on its swings;
    /// 3. its least-squares straight line (the zero offset, a drift) is removed, and its spectrum
    ///    taken with a window flat over the middle half of the samples and tapered by a cosine
    ///    over the first and last quarter (a Tukey window);
    /// 4. a line of the spectrum is the largest power within the window's main lobe (so that the
    ///    side lobes of a stronger line are not lines), and it counts when its power is at least
    ///    [`needed_prominence`](Self::needed_prominence) times the median power within an octave
    ///    either side (its own lobe left out), the level noise alone passes with probability
    ///    [`FALSE_LINE`](Self::FALSE_LINE) anywhere in the spectrum: a smooth trend or drift, whose
    ///    spectrum falls steadily, does not count, however strong;
    /// 5. the strongest line that counts is refined to the maximum of the transform between its
    ///    neighbouring bins (the transform evaluated directly, golden-section search).
    ///
    /// The line of a decaying oscillation is as wide as its decay is fast, and its centre is the
    /// oscillation's frequency. An oscillator whose period changes with its amplitude (a pendulum's
    /// large swings, a hardening spring) has its line spread between the periods of its swings:
    /// the maximum lies between the periods of its largest and its smallest swings, at those of
    /// the swings that hold most of the power of the record as the window weighs it (squared
    /// amplitude times duration, the first and last quarter of the record tapered). It is not the
    /// mean spacing of the swings, but a period of the swings in the record.
    ///
    /// Errors when a sample is not finite, and [`CircleError::NoOscillation`] (with its
    /// [`NoOscillationReason`]) when fewer than [`MIN_SAMPLES`](Self::MIN_SAMPLES) swing, when
    /// the record does not move, when no line stands out of the noise, or when the strongest line
    /// has fewer than two periods in the samples measured.
    ///
    /// ```
    /// use circle_signal::{Domain, OscillationPeriod};
    ///
    /// // A decaying oscillation of period 37.5 samples, rounded to steps of 0.01.
    /// let x: Vec<f64> = (0..2000)
    ///     .map(|n| {
    ///         let t = n as f64;
    ///         let swing = (-t / 500.0).exp() * (std::f64::consts::TAU * t / 37.5).sin();
    ///         (100.0 * swing).round() / 100.0
    ///     })
    ///     .collect();
    /// let found = OscillationPeriod::measure(&x, Domain::Line)?;
    /// assert!((found.samples - 37.5).abs() < 0.05);
    /// assert_eq!(found.measured, 0..2000);
    /// assert!(found.prominence > OscillationPeriod::needed_prominence(1000));
    /// # Ok::<(), circle_signal::CircleError>(())
    /// ```
    pub fn measure(x: &[f64], domain: Domain) -> Result<Self, CircleError> {
        if let Some((index, &value)) = x.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(CircleError::NonFinite { index, value });
        }
        if x.len() < Self::MIN_SAMPLES {
            return Err(CircleError::NoOscillation {
                len: x.len(),
                reason: NoOscillationReason::TooShort {
                    samples: x.len(),
                    needed: Self::MIN_SAMPLES,
                },
            });
        }
        // An oscillation of four samples a period or faster does not pass the median of three:
        // such a record is measured as read.
        Self::measure_read(&median_of_three(x, domain), domain)
            .or_else(|despiked| Self::measure_read(x, domain).map_err(|_| despiked))
    }

    /// [`measure`](Self::measure) from step 2 on, `x` finite.
    fn measure_read(x: &[f64], domain: Domain) -> Result<Self, CircleError> {
        let n = x.len();
        let fail = |reason| CircleError::NoOscillation { len: n, reason };
        let too_short = |samples| {
            fail(NoOscillationReason::TooShort {
                samples,
                needed: Self::MIN_SAMPLES,
            })
        };
        let (measured, mut s) = match domain {
            Domain::Line => (0..n, x.to_vec()),
            Domain::Circle => {
                let position = crate::unwrap(x);
                let start = swinging_tail(&position);
                (start..n, position[start..].to_vec())
            }
        };
        let m = s.len();
        if m < Self::MIN_SAMPLES {
            return Err(too_short(m));
        }
        let moved = remove_line(&mut s);
        let scale = s.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
        if scale <= 1e-12 * moved.max(f64::MIN_POSITIVE) {
            return Err(fail(NoOscillationReason::AtRest));
        }
        taper(&mut s);
        let len = fast_len(m);
        let power = power_spectrum(&s, len);
        // Bins 0 and 1 hold the mean and the trend's leakage: lines from two periods in the samples
        // measured on (bin `2 m / len` and up; the search starts at bin 2).
        let band = 2..power.len();
        if band.len() < 2 {
            return Err(too_short(m));
        }
        // The window's main lobe, in bins of the padded transform, with room to spare.
        let lobe = (2 * len).div_ceil(m) + 1;
        let background = background(&power, band.clone(), lobe);
        let needed = Self::needed_prominence(band.len());
        if power[band.clone()].iter().all(|&p| p == 0.0) {
            return Err(fail(NoOscillationReason::AtRest));
        }
        let mut best: Option<usize> = None;
        let mut most = 0.0_f64;
        for k in band.clone() {
            // A line: the maximum of its main lobe (the side lobes of a stronger line, each
            // beside a larger one, are not) that stands out of the spectrum around it.
            let lobe_range = k.saturating_sub(lobe)..(k + lobe + 1).min(power.len());
            if lobe_range.into_iter().any(|j| j != k && power[j] >= power[k]) {
                continue;
            }
            let ratio = power[k] / background[k - band.start];
            if !ratio.is_finite() {
                continue;
            }
            most = most.max(ratio);
            if ratio >= needed && best.is_none_or(|b| power[k] > power[b]) {
                best = Some(k);
            }
        }
        let Some(k) = best else {
            return Err(fail(NoOscillationReason::Noise {
                prominence: most,
                needed,
            }));
        };
        let prominence = power[k] / background[k - band.start];
        let bin = refine(&s, len, k);
        let samples = len as f64 / bin;
        if samples > m as f64 / 2.0 {
            return Err(fail(NoOscillationReason::TooFewPeriods {
                period: samples,
                samples: m,
            }));
        }
        Ok(Self {
            samples,
            measured,
            prominence,
        })
    }

    /// The ratio of a line's power to the median power around it that noise alone passes with
    /// probability [`FALSE_LINE`](Self::FALSE_LINE) somewhere among `bins` bins of a spectrum:
    /// `(ln bins − ln FALSE_LINE) / ln 2`. The power of white noise in one bin is exponential, its
    /// median `ln 2` times its mean, and the largest of `bins` such powers exceeds
    /// `mean · (ln bins + t)` with probability about `e^(−t)`.
    pub fn needed_prominence(bins: usize) -> f64 {
        ((bins.max(1) as f64).ln() - Self::FALSE_LINE.ln()) / LN_2
    }

    /// The number of periods in the samples measured.
    pub fn periods(&self) -> f64 {
        self.measured.len() as f64 / self.samples
    }
}

/// The period, in samples, of the oscillation of `x`: [`OscillationPeriod::measure`]'s period.
///
/// It is what a record without a drive offers as its unit of time: windows "of k oscillation
/// periods" for the weak form of a free decay.
///
/// ```
/// use circle_signal::{Domain, oscillation_period};
///
/// // A decaying oscillation of period 37.5 samples about a drifting offset.
/// let x: Vec<f64> = (0..2000)
///     .map(|n| {
///         let t = n as f64;
///         0.3 + 1e-4 * t + (-t / 900.0).exp() * (std::f64::consts::TAU * t / 37.5).sin()
///     })
///     .collect();
/// let p = oscillation_period(&x, Domain::Line)?;
/// assert!((p - 37.5).abs() < 0.05);
/// # Ok::<(), circle_signal::CircleError>(())
/// ```
pub fn oscillation_period(x: &[f64], domain: Domain) -> Result<f64, CircleError> {
    OscillationPeriod::measure(x, domain).map(|p| p.samples)
}

/// Every sample replaced by the median of itself and its two neighbours: an isolated spike is
/// gone, a monotonic stretch is untouched. On the circle the median of three angles is the one opposite the longest of the
/// three distances between them, the one closest to the other two.
fn median_of_three(x: &[f64], domain: Domain) -> Vec<f64> {
    let n = x.len();
    let median = |a: f64, b: f64, c: f64| {
        let (ab, bc, ac) = (
            domain.distance(a, b),
            domain.distance(b, c),
            domain.distance(a, c),
        );
        if ac >= ab && ac >= bc {
            b
        } else if ab >= bc {
            c
        } else {
            a
        }
    };
    // An end sample has one neighbour: its median is with that neighbour and the straight line
    // through the next two.
    let beyond = |a: f64, b: f64| match domain {
        Domain::Circle => a + crate::wrap(a - b),
        Domain::Line => 2.0 * a - b,
    };
    let mut out = Vec::with_capacity(n);
    out.push(median(x[0], x[1], beyond(x[1], x[2])));
    out.extend(x.windows(3).map(|w| median(w[0], w[1], w[2])));
    out.push(median(beyond(x[n - 2], x[n - 3]), x[n - 2], x[n - 1]));
    out
}

/// The first sample of the longest tail of the unwrapped angle that spans less than a turn: a
/// swing about the bottom never spans a turn, so a decay that starts whirling has its swings (and
/// at most one turn of the whirl) in this tail.
fn swinging_tail(position: &[f64]) -> usize {
    let (mut low, mut high) = (f64::INFINITY, f64::NEG_INFINITY);
    for (i, &p) in position.iter().enumerate().rev() {
        low = low.min(p);
        high = high.max(p);
        if high - low >= TAU {
            return i + 1;
        }
    }
    0
}

/// Removes the least-squares straight line from `s`; returns the largest magnitude of `s` before,
/// the scale rounding is judged by.
fn remove_line(s: &mut [f64]) -> f64 {
    let m = s.len() as f64;
    let mid = (m - 1.0) / 2.0;
    let mean = s.iter().sum::<f64>() / m;
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (i, &v) in s.iter().enumerate() {
        let t = i as f64 - mid;
        sxy += t * (v - mean);
        sxx += t * t;
    }
    let slope = sxy / sxx;
    let largest = s.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
    for (i, v) in s.iter_mut().enumerate() {
        *v -= mean + slope * (i as f64 - mid);
    }
    largest
}

/// The fraction of the samples measured that the window tapers, half at each end.
const TAPER: f64 = 0.5;

/// The Tukey window: a cosine taper over the first and last quarter of the samples, one between.
/// It weighs every swing of the middle half alike (a Hann window would weigh the middle of the
/// record most and hide the large swings at the start of a decay), and its transform falls as the
/// cube of the distance from its main lobe, which is about two bins wide either side. A shorter
/// taper would weigh more of the record alike, but the transform of its short edges is broad:
/// the leakage of a strong slow trend through them makes false lines a tenth of the record's
/// length apart.
fn taper(s: &mut [f64]) {
    let m = s.len();
    let edge = ((TAPER / 2.0 * m as f64).round() as usize).max(1);
    for i in 0..edge.min(m / 2) {
        let w = 0.5 - 0.5 * (PI * (i as f64 + 0.5) / edge as f64).cos();
        s[i] *= w;
        s[m - 1 - i] *= w;
    }
}

/// The smallest `2^a 3^b 5^c` at least `m`: a length the transform is fast at.
fn fast_len(m: usize) -> usize {
    let mut best = usize::MAX;
    let mut p2 = 1usize;
    while p2 < 2 * m {
        let mut p3 = p2;
        while p3 < 2 * m {
            let mut p5 = p3;
            while p5 < m {
                p5 *= 5;
            }
            best = best.min(p5);
            p3 *= 3;
        }
        p2 *= 2;
    }
    best
}

/// `|X_k|²` for `k = 0..=len/2`, `X` the transform of `s` padded with zeros to `len`.
fn power_spectrum(s: &[f64], len: usize) -> Vec<f64> {
    let fft = Planner::new().forward(len);
    let mut input = fft.make_input_vec();
    input[..s.len()].copy_from_slice(s);
    let mut bins = fft.make_output_vec();
    fft.process(&mut input, &mut bins)
        .expect("buffers made by the plan have its lengths");
    bins.iter().map(Complex::norm_sqr).collect()
}

/// Per bin of `band`, the median of `power` around it: over the bins within an octave either side
/// (`k / 2` to `2 k`, and at least `lobe + 8` bins either side), kept in the band, less the
/// `lobe` bins either side of the bin itself, where a line of its own lies. Taken at every bin
/// below 64 and at four centres per octave above, each bin reading the nearest centre: the level
/// of the spectrum around each bin, which no single line moves. Infinite where too few bins are
/// left for a median.
fn background(power: &[f64], band: Range<usize>, lobe: usize) -> Vec<f64> {
    const EXACT: usize = 64;
    const PER_OCTAVE: f64 = 4.0;
    let last = (band.end - 1) as f64;
    let mut centres: Vec<f64> = (band.start..band.end.min(EXACT)).map(|k| k as f64).collect();
    let exact = centres.len();
    if band.end > EXACT {
        let octaves = (last / EXACT as f64).log2();
        let more = (octaves * PER_OCTAVE).ceil() as usize + 1;
        centres.extend((0..more).map(|j| EXACT as f64 * 2f64.powf(j as f64 / PER_OCTAVE)));
    }
    let mut scratch = Vec::new();
    let medians: Vec<f64> = centres
        .iter()
        .map(|&c| {
            let centre = c.round() as usize;
            let reach = lobe + 8;
            let from = ((c / 2.0).floor() as usize)
                .min(centre.saturating_sub(reach))
                .max(band.start);
            let to = ((2.0 * c).ceil() as usize).max(centre + reach).min(band.end - 1) + 1;
            scratch.clear();
            scratch.extend(
                (from..to)
                    .filter(|&j| j.abs_diff(centre) > lobe)
                    .map(|j| power[j]),
            );
            if scratch.len() < 4 {
                return f64::INFINITY;
            }
            let mid = scratch.len() / 2;
            *scratch.select_nth_unstable_by(mid, f64::total_cmp).1
        })
        .collect();
    band.map(|k| {
        let index = if k < EXACT {
            k - centres[0] as usize
        } else {
            exact + ((k as f64 / EXACT as f64).log2() * PER_OCTAVE).round() as usize
        };
        medians[index.min(medians.len() - 1)]
    })
    .collect()
}

/// The bin (in units of `1 / len` cycles per sample) between `k − 1` and `k + 1` where `|X|²` of
/// `s` is largest: the transform evaluated directly, by golden-section search down to a
/// thousandth of a bin, then the vertex of the parabola through three values a thousandth of a bin
/// apart (a line is smooth on that scale).
fn refine(s: &[f64], len: usize, k: usize) -> f64 {
    let power = |bin: f64| {
        let step = -TAU * bin / len as f64;
        let rotate = Complex::from_polar(1.0, step);
        let mut sum = Complex::new(0.0, 0.0);
        let mut phasor = Complex::new(1.0, 0.0);
        for (i, &v) in s.iter().enumerate() {
            // Renewed now and then, so that rounding does not pile up over a long record.
            if i % 1024 == 0 {
                phasor = Complex::from_polar(1.0, step * i as f64);
            }
            sum += phasor * v;
            phasor *= rotate;
        }
        sum.norm_sqr()
    };
    const FINE: f64 = 1e-3;
    let golden = (5f64.sqrt() - 1.0) / 2.0;
    let (mut a, mut b) = (k as f64 - 1.0, k as f64 + 1.0);
    let mut c = b - golden * (b - a);
    let mut d = a + golden * (b - a);
    let (mut pc, mut pd) = (power(c), power(d));
    while b - a > FINE {
        if pc >= pd {
            b = d;
            d = c;
            pd = pc;
            c = b - golden * (b - a);
            pc = power(c);
        } else {
            a = c;
            c = d;
            pc = pd;
            d = a + golden * (b - a);
            pd = power(d);
        }
    }
    let mid = (a + b) / 2.0;
    let (left, centre, right) = (power(mid - FINE), power(mid), power(mid + FINE));
    let curvature = left - 2.0 * centre + right;
    if centre >= left && centre >= right && curvature < 0.0 {
        mid + 0.5 * FINE * (left - right) / curvature
    } else {
        mid
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wrap;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn periods_on_the_line_and_on_the_circle() {
        // A pendulum-like free decay seen by an encoder (wrapped), about a zero offset of 3 rad so
        // that it crosses ±π, with a little noise from a fixed sequence.
        let period = 123.4;
        let x: Vec<f64> = (0..5000)
            .map(|n| {
                let t = n as f64;
                let wobble = 0.01 * (t * 12.9898).sin();
                wrap(3.0 + 1.5 * (-t / 3000.0).exp() * (std::f64::consts::TAU * t / period).cos() + wobble)
            })
            .collect();
        let p = oscillation_period(&x, Domain::Circle).unwrap();
        assert!((p - period).abs() < 0.05, "{p}");
        // On the line the same samples are read as they are: the wrap makes jumps of 2π, and the
        // estimate is of another signal, but still an estimate (no error, no NaN).
        assert!(oscillation_period(&x, Domain::Line).unwrap().is_finite());
    }

    #[test]
    fn a_decay_that_starts_whirling_is_measured_on_its_swings() {
        // Four thousand samples of whirling, slowing down, then swings of period 80 samples.
        let mut theta: Vec<f64> = (0..4000)
            .map(|n| 0.3 * n as f64 - 3e-5 * (n * n) as f64)
            .collect();
        let top = theta[3999];
        theta.extend((1..4000).map(|n| top + 0.8 * (std::f64::consts::TAU * n as f64 / 80.0).sin()));
        let x: Vec<f64> = theta.iter().map(|&t| wrap(t)).collect();
        let p = oscillation_period(&x, Domain::Circle).unwrap();
        assert!((p - 80.0).abs() < 0.01, "{p}");
    }

    #[test]
    fn too_few_periods_noise_rest_and_bad_samples() {
        let no_oscillation = |x: &[f64]| match OscillationPeriod::measure(x, Domain::Line) {
            Err(CircleError::NoOscillation { reason, .. }) => reason,
            other => panic!("{other:?}"),
        };
        let ramp: Vec<f64> = (0..100).map(|n| n as f64).collect();
        assert_eq!(no_oscillation(&ramp), NoOscillationReason::AtRest);
        assert_eq!(no_oscillation(&[0.3; 500]), NoOscillationReason::AtRest);
        // Under two periods: 1.6 periods of 63 samples.
        let one: Vec<f64> = (0..100).map(|n| (n as f64 * 0.1).sin()).collect();
        assert!(matches!(
            no_oscillation(&one),
            NoOscillationReason::TooFewPeriods { period, samples: 100 } if (period - 62.8).abs() < 5.0
        ));
        // White noise has no line: its strongest stays under the prominence needed.
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let noise: Vec<f64> = (0..20_000).map(|_| rng.random::<f64>() - 0.5).collect();
        assert!(matches!(
            no_oscillation(&noise),
            NoOscillationReason::Noise { prominence, needed } if prominence < needed
        ));
        // Four periods of eight samples are enough; 31 samples are not.
        let short: Vec<f64> = (0..32).map(|n| (TAU * n as f64 / 8.0).cos()).collect();
        let p = oscillation_period(&short, Domain::Line).unwrap();
        assert!((p - 8.0).abs() < 0.05, "{p}");
        assert_eq!(
            no_oscillation(&short[..31]),
            NoOscillationReason::TooShort {
                samples: 31,
                needed: 32
            }
        );
        assert!(matches!(
            oscillation_period(&[0.0, f64::NAN, 1.0], Domain::Line),
            Err(CircleError::NonFinite { index: 1, .. })
        ));
    }

    /// A 1 kHz encoder log of a 1.3 Hz pendulum's free decay: 4096 counts per turn, the swing
    /// decaying from 80 counts to 3 over 45 s, a zero offset, four bit errors of 2048 counts (half
    /// a turn). Near rest the record toggles between two counts every few samples.
    fn encoder_decay() -> (Vec<f64>, f64) {
        let period = 1000.0 / 1.3;
        let count = TAU / 4096.0;
        let samples = 45_000;
        let decay = (80.0_f64 / 3.0).ln() / samples as f64;
        let mut x: Vec<f64> = (0..samples)
            .map(|n| {
                let t = n as f64;
                let angle = 80.0 * count * (-decay * t).exp() * (TAU * t / period).cos() - 0.7;
                wrap((angle / count).round() * count)
            })
            .collect();
        for i in [4_321, 17_000, 29_876, 44_000] {
            x[i] = wrap(x[i] + 2048.0 * count);
        }
        (x, period)
    }

    #[test]
    fn a_quantised_decay_with_half_turn_spikes() {
        let (x, period) = encoder_decay();
        let p = oscillation_period(&x, Domain::Circle).unwrap();
        assert!((p / period - 1.0).abs() < 1e-4, "{p} against {period}");
        // The last 8 s, a swing of 3 to 5 counts, one spike.
        let p = oscillation_period(&x[37_000..], Domain::Circle).unwrap();
        assert!((p / period - 1.0).abs() < 1e-3, "{p} against {period}");
    }

    #[test]
    fn a_displacement_with_a_wandering_offset() {
        // The same decay as a displacement on the line (spikes included), its offset wandering
        // by a random walk of 0.3 counts a step (about 60 counts over the record).
        let (x, period) = encoder_decay();
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut offset = 0.0;
        let drifting: Vec<f64> = x
            .iter()
            .map(|&v| {
                offset += 0.3 * (TAU / 4096.0) * (rng.random::<f64>() - 0.5) * 12f64.sqrt();
                v + offset
            })
            .collect();
        let found = OscillationPeriod::measure(&drifting, Domain::Line).unwrap();
        assert!(
            (found.samples / period - 1.0).abs() < 1e-3,
            "{found:?} against {period}"
        );
        assert!((found.periods() - 45_000.0 / period).abs() < 0.1, "{found:?}");
    }

    #[test]
    fn a_period_that_changes_with_amplitude() {
        // A decay whose period grows from 50 samples in its large swings to 60 in its small ones:
        // the line's maximum lies between.
        let (big, small) = (50.0, 60.0);
        let mut phase = 0.0;
        let x: Vec<f64> = (0..6000)
            .map(|n| {
                let amplitude = (-(n as f64) / 1500.0).exp();
                phase += TAU / (small - (small - big) * amplitude);
                amplitude * phase.sin()
            })
            .collect();
        let p = oscillation_period(&x, Domain::Line).unwrap();
        assert!(big < p && p < small, "{p}");
    }

    #[test]
    fn an_oscillation_faster_than_the_median_is_measured_as_read() {
        // Four samples a period: the median of three flattens it, the record as read has it.
        let x: Vec<f64> = (0..200).map(|n| (TAU * n as f64 / 4.0 + 0.3).sin()).collect();
        let p = oscillation_period(&x, Domain::Line).unwrap();
        assert!((p - 4.0).abs() < 1e-4, "{p}");
    }
}
