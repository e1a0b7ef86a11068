//! Band-limited resampling onto a grid with a whole number of samples per forcing period.
//!
//! Real sampling rates and drive frequencies are never in a whole ratio (a 1.02 Hz drive sampled
//! at 500 Hz gives 490.196 samples per period), while close returns, periodic windows and the
//! paper's Fourier rows cut the record into whole forcing periods. The record is therefore
//! resampled once, at the input, onto the nearest grid with whole `P` (the choice and its measured
//! cost are in `docs/identification.md`): every later stage sees an ordinary whole clock.

use std::f64::consts::PI;
use std::ops::Range;

use rayon::prelude::*;

use crate::{CircleError, Domain, SampleClock, wrap};

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
    // The whole record as one piece: the same outputs, `⌊(n − 1 − 2 half) / ratio⌋ + 1` of them.
    let whole = 0..n;
    let mut r = resample_columns(vec![(x.to_vec(), domain)], std::slice::from_ref(&whole), clock)?;
    Ok(Resampled {
        samples: r.columns.pop().unwrap_or_default(),
        clock: r.clock,
    })
}

/// A record with gaps, resampled piece by piece onto one grid (see [`resample_pieces`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ResampledPieces {
    /// The samples on the output grid, NaN outside the pieces (wrapped into `[−π, π)` on the
    /// circle).
    pub samples: Vec<f64>,
    /// The ranges of `samples` that hold data, in order.
    pub pieces: Vec<Range<usize>>,
    /// The output grid: whole `P`, first sample `RESAMPLE_HALF_WIDTH` input steps after the
    /// record's.
    pub clock: SampleClock,
}

/// [`resample_to_whole`] for a record in pieces: `x` on `clock`'s grid holds data in `pieces`
/// (sorted, disjoint ranges; anything between them, such as the NaN of a gap, is never read). Each
/// piece is interpolated on its own (no kernel reaches across a gap) onto the one output grid
/// `t'_m = t_0 + RESAMPLE_HALF_WIDTH · h + m · T / P`, so the output keeps one clock and the drive's
/// phase at every sample; each piece loses [`RESAMPLE_HALF_WIDTH`] input samples at both ends, and
/// pieces too short for the kernel are dropped. A whole clock returns the pieces unchanged.
///
/// Errors when no piece is long enough for the kernel, a sample of a piece is not finite, or the
/// pieces are out of order or out of bounds.
pub fn resample_pieces(
    x: &[f64],
    pieces: &[Range<usize>],
    clock: &SampleClock,
    domain: Domain,
) -> Result<ResampledPieces, CircleError> {
    let ResampledColumns {
        mut columns,
        pieces,
        clock,
    } = resample_columns(vec![(x.to_vec(), domain)], pieces, clock)?;
    Ok(ResampledPieces {
        samples: columns.pop().unwrap_or_default(),
        pieces,
        clock,
    })
}

/// Several columns of one record (the coordinates, drives and velocities of a system, sampled
/// together), resampled onto one grid (see [`resample_columns`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ResampledColumns {
    /// Each column's samples on the output grid, in the order given, NaN outside the pieces
    /// (wrapped into `[−π, π)` on the circle).
    pub columns: Vec<Vec<f64>>,
    /// The ranges of the output grid that hold data, in order (the same for every column).
    pub pieces: Vec<Range<usize>>,
    /// The output grid: whole `P`, first sample `RESAMPLE_HALF_WIDTH` input steps after the
    /// record's.
    pub clock: SampleClock,
}

/// [`resample_pieces`] for several columns sampled together, each in its own domain: every
/// column's samples are those [`resample_pieces`] gives it alone, bit for bit, at a fraction of
/// the cost of resampling them one by one, since the kernel's weights at an output sample (most
/// of the work: 128 taps of a degree-16 interpolant) depend on its position alone and are
/// computed once for up to three columns at a time. The columns are taken, not copied: each one's
/// storage holds its unwrapped and detrended samples while its outputs are made, and is dropped
/// after, so that the memory of a resampling beside the columns is at most three outputs however
/// many columns there are.
///
/// Errors as [`resample_pieces`] does, for the first column (in order) that has one; every
/// column must be as long as the first.
///
/// ```
/// use circle_signal::{Domain, SampleClock, resample_columns, resample_pieces};
///
/// let clock = SampleClock::from_step(1.0 / 1.3, 1.0 / 500.0)?;
/// let t = |n: usize| clock.time(n);
/// let angle: Vec<f64> = (0..3000).map(|n| circle_signal::wrap(8.0 * t(n))).collect();
/// let torque: Vec<f64> = (0..3000).map(|n| (8.0 * t(n)).cos()).collect();
/// let pieces = [0..3000];
/// let alone = resample_pieces(&torque, &pieces, &clock, Domain::Line)?;
/// let both = resample_columns(vec![(angle, Domain::Circle), (torque, Domain::Line)], &pieces, &clock)?;
/// assert_eq!(both.clock.whole_samples_per_period(), Some(385));
/// assert_eq!(both.columns[1], alone.samples);
/// # Ok::<(), circle_signal::CircleError>(())
/// ```
pub fn resample_columns(
    columns: Vec<(Vec<f64>, Domain)>,
    pieces: &[Range<usize>],
    clock: &SampleClock,
) -> Result<ResampledColumns, CircleError> {
    let len = columns.first().map_or(0, |(x, _)| x.len());
    for (x, _) in &columns {
        if x.len() != len {
            return Err(CircleError::LengthMismatch {
                expected: len,
                found: x.len(),
            });
        }
        crate::check_pieces(x, pieces)?;
    }
    if clock.whole_samples_per_period().is_some() {
        return Ok(ResampledColumns {
            columns: columns.into_iter().map(|(x, _)| x).collect(),
            pieces: pieces.to_vec(),
            clock: *clock,
        });
    }
    let half = RESAMPLE_HALF_WIDTH;
    let longest = pieces.iter().map(Range::len).max().unwrap_or(0);
    if longest < 2 * half + 2 {
        return Err(CircleError::TooShort {
            len: longest,
            needed: 2 * half + 2,
        });
    }
    let out_clock = whole_clock(clock)?;
    let ratio = out_clock.step() / clock.step();
    let kernel = Kernel::for_ratio(ratio);
    // Output m sits at input position u_m = half + m · ratio; a piece's outputs need
    // piece.start + half <= u_m <= piece.end − 1 − half.
    let out_pieces: Vec<(Range<usize>, Range<usize>)> = pieces
        .iter()
        .filter(|r| r.len() >= 2 * half + 2)
        .filter_map(|piece| {
            let first = (piece.start as f64 / ratio).ceil() as usize;
            let last = ((piece.end - 1 - 2 * half) as f64 / ratio).floor() as usize;
            (last >= first).then(|| (piece.clone(), first..last + 1))
        })
        .collect();
    let out_len = out_pieces.last().map_or(0, |(_, out)| out.end);
    // The columns a group at a time, each group's inputs dropped once its outputs are made: the
    // memory beside the record's columns is a group's outputs, as when one column at a time was
    // resampled with its copies.
    let mut outputs: Vec<Vec<f64>> = Vec::with_capacity(columns.len());
    let mut rest = columns.into_iter();
    loop {
        let mut group: Vec<(Vec<f64>, Domain)> = rest.by_ref().take(COLUMNS_TOGETHER).collect();
        if group.is_empty() {
            break;
        }
        let mut made: Vec<Vec<f64>> = vec![vec![f64::NAN; out_len]; group.len()];
        for (piece, out) in &out_pieces {
            let mut inputs: Vec<Detrended<'_>> = group
                .iter_mut()
                .map(|(x, domain)| Detrended::new(&mut x[piece.clone()], *domain))
                .collect();
            let mut targets: Vec<&mut [f64]> = made.iter_mut().map(|o| &mut o[out.clone()]).collect();
            interpolate(
                &mut inputs,
                piece.start as f64,
                ratio,
                &kernel,
                out.clone(),
                &mut targets,
            );
        }
        drop(group);
        outputs.append(&mut made);
    }
    Ok(ResampledColumns {
        columns: outputs,
        pieces: out_pieces.into_iter().map(|(_, out)| out).collect(),
        clock: out_clock,
    })
}

/// A column's samples over a piece, unwrapped on the circle and less the straight line through
/// the first and last of them, in place, with that line and the column's domain.
struct Detrended<'a> {
    y: &'a [f64],
    y0: f64,
    slope: f64,
    domain: Domain,
}

impl<'a> Detrended<'a> {
    /// `x` (at least two samples) made so, in place: the numbers [`unwrap`](crate::unwrap) and the
    /// subtraction give.
    fn new(x: &'a mut [f64], domain: Domain) -> Self {
        if domain == Domain::Circle {
            crate::unwrap_in_place(x);
        }
        let n = x.len();
        let (y0, slope) = (x[0], (x[n - 1] - x[0]) / (n - 1) as f64);
        for (m, v) in x.iter_mut().enumerate() {
            *v -= y0 + slope * m as f64;
        }
        Self {
            y: x,
            y0,
            slope,
            domain,
        }
    }
}

/// The output clock of a resampling: `P = round(T / h)` (at least 2), the first sample
/// [`RESAMPLE_HALF_WIDTH`] input steps after the record's.
fn whole_clock(clock: &SampleClock) -> Result<SampleClock, CircleError> {
    let p = clock.samples_per_period().round().max(2.0) as usize;
    SampleClock::new(clock.drive_period(), p)?
        .with_start_time(clock.start_time() + RESAMPLE_HALF_WIDTH as f64 * clock.step())
}

/// The number of taps of the interpolation kernel.
const TAPS: usize = 2 * RESAMPLE_HALF_WIDTH;

/// Degree of the Chebyshev interpolant of each tap's weight in the fractional position (see
/// [`Kernel`]): 16 brings it within about 1e-14 of the closed form (the interpolant converges
/// geometrically; beyond 14 only rounding is left).
const KERNEL_DEGREE: usize = 16;

/// Outputs per parallel task.
const CHUNK: usize = 4096;

/// Columns [`resample_columns`] resamples together, sharing the kernel's weights: a system's two
/// or three coordinates (with a drive) in one pass, and a robot arm's two angles, two torques and
/// two velocities in two, the memory beside the record's columns three outputs at most (what
/// resampling one column at a time with its copies took).
const COLUMNS_TOGETHER: usize = 3;

/// The kernel's weights as functions of the fractional part `φ ∈ [0, 1)` of the input position:
/// tap `k` (input sample `⌊u⌋ + 1 − half + k`) lies at distance `d = φ + half − 1 − k` and weighs
/// `fc · sinc(fc · d) · I₀(β √(1 − (d / half)²)) / I₀(β)`. Each tap's weight is an entire
/// function of `φ`, so its Chebyshev interpolant on `[0, 1]` at [`KERNEL_DEGREE`]` + 1` points
/// agrees with the closed form to rounding, and evaluates for all taps at once (one Clenshaw
/// recurrence, the taps in the inner loop) at a tenth of the closed form's cost (its Bessel series
/// and sine per tap).
struct Kernel {
    /// Chebyshev coefficients, degree-major: `coefficients[j][k]` of tap `k`.
    coefficients: Vec<[f64; TAPS]>,
}

impl Kernel {
    /// The kernel of a resampling whose output step is `ratio` input steps: its low-pass at
    /// [`CUTOFF`] of the coarser grid's Nyquist frequency.
    fn for_ratio(ratio: f64) -> Self {
        Self::new(CUTOFF * ratio.recip().min(1.0))
    }

    /// The kernel of cut-off `fc` (in cycles per input sample).
    fn new(fc: f64) -> Self {
        let nodes = KERNEL_DEGREE + 1;
        let angle = |i: usize, j: usize| PI * j as f64 * (i as f64 + 0.5) / nodes as f64;
        let norm = bessel_i0(KAISER_BETA);
        // The Chebyshev points of the first kind, mapped onto [0, 1].
        let phases: Vec<f64> = (0..nodes).map(|i| 0.5 * (1.0 + angle(i, 1).cos())).collect();
        let mut coefficients = vec![[0.0; TAPS]; nodes];
        let mut values = vec![0.0; nodes];
        for k in 0..TAPS {
            for (v, &phase) in values.iter_mut().zip(&phases) {
                *v = exact_weight(fc, phase + (RESAMPLE_HALF_WIDTH - 1) as f64 - k as f64, norm);
            }
            for (j, c) in coefficients.iter_mut().enumerate() {
                let sum: f64 = values
                    .iter()
                    .enumerate()
                    .map(|(i, v)| v * angle(i, j).cos())
                    .sum();
                c[k] = sum * if j == 0 { 1.0 } else { 2.0 } / nodes as f64;
            }
        }
        Self { coefficients }
    }

    /// The weights at fractional position `phase ∈ [0, 1)` into `w`.
    fn weights(&self, phase: f64, w: &mut [f64; TAPS]) {
        let t = 2.0 * phase - 1.0;
        let (mut b1, mut b2) = ([0.0; TAPS], [0.0; TAPS]);
        for c in self.coefficients[1..].iter().rev() {
            for k in 0..TAPS {
                let b0 = c[k] + 2.0 * t * b1[k] - b2[k];
                b2[k] = b1[k];
                b1[k] = b0;
            }
        }
        for k in 0..TAPS {
            w[k] = self.coefficients[0][k] + t * b1[k] - b2[k];
        }
        // The last tap at exactly `d = −half` is the window's end, where it is zero (the
        // interpolant continues it with the window's value there, 1 / I₀(β)).
        if phase == 0.0 {
            w[TAPS - 1] = 0.0;
        }
    }
}

/// The closed form of the weight at distance `d` (input samples) from the output position: the
/// sinc of cut-off `fc` under the Kaiser window of half-width [`RESAMPLE_HALF_WIDTH`], `norm`
/// being `I₀(β)`.
fn exact_weight(fc: f64, d: f64, norm: f64) -> f64 {
    let z = d / RESAMPLE_HALF_WIDTH as f64;
    let window = if z.abs() < 1.0 {
        bessel_i0(KAISER_BETA * (1.0 - z * z).sqrt()) / norm
    } else {
        0.0
    };
    fc * sinc(fc * d) * window
}

/// The Kaiser-windowed sinc interpolation of each of `columns` (all as long, at least
/// `2 · half + 2` samples; their first sample at input position `offset`) at the positions
/// `half + m · ratio` for `m` in `outputs`, all of which must keep the kernel inside them, with
/// `kernel` (built once per resampling, for all its pieces), into `targets` (one per column, as
/// long as `outputs`): the weights at each output once, for every column. The outputs are
/// computed in parallel, each on its own: the result depends neither on the number of threads
/// nor on the other columns.
fn interpolate(
    columns: &mut [Detrended<'_>],
    offset: f64,
    ratio: f64,
    kernel: &Kernel,
    outputs: Range<usize>,
    targets: &mut [&mut [f64]],
) {
    let half = RESAMPLE_HALF_WIDTH;
    let Some(n) = columns.first().map(|c| c.y.len()) else {
        return;
    };
    let columns = &*columns;
    let one = |j: usize, weights: &mut [f64; TAPS], out: &mut [&mut [f64]], at: usize| {
        // Position in the columns, clamped against rounding at the ends of the range.
        let u = (half as f64 + j as f64 * ratio - offset).clamp((half - 1) as f64, (n - 1 - half) as f64);
        let base = u.floor();
        kernel.weights(u - base, weights);
        let first = base as usize + 1 - half;
        let total: f64 = weights.iter().sum();
        for (c, out) in columns.iter().zip(out.iter_mut()) {
            let v: f64 = weights
                .iter()
                .zip(&c.y[first..first + TAPS])
                .map(|(w, y)| w * y)
                .sum();
            let value = v / total + c.y0 + c.slope * u;
            out[at] = match c.domain {
                Domain::Circle => wrap(value),
                Domain::Line => value,
            };
        }
    };
    // The outputs in chunks of CHUNK, each chunk's slice of every target together.
    let mut chunks: Vec<(usize, Vec<&mut [f64]>)> = outputs
        .clone()
        .step_by(CHUNK)
        .map(|start| (start, Vec::with_capacity(targets.len())))
        .collect();
    for target in targets.iter_mut() {
        for ((_, slices), slice) in chunks.iter_mut().zip(target.chunks_mut(CHUNK)) {
            slices.push(slice);
        }
    }
    chunks.into_par_iter().for_each(|(start, mut slices)| {
        let mut weights = [0.0; TAPS];
        let end = (start + CHUNK).min(outputs.end);
        for (at, j) in (start..end).enumerate() {
            one(j, &mut weights, &mut slices, at);
        }
    });
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
    fn kernel_matches_closed_form() {
        // The interpolated weights against the closed form, at cut-offs from the widest (a
        // finer output grid: 0.9) down, and phases across [0, 1) including 0.
        let norm = bessel_i0(KAISER_BETA);
        let mut worst: f64 = 0.0;
        for fc in [0.9, 0.9 / 1.0004, 0.5, 0.2] {
            let kernel = Kernel::new(fc);
            let mut w = [0.0; TAPS];
            for i in 0..997 {
                let phase = i as f64 / 997.0;
                kernel.weights(phase, &mut w);
                for (k, &wk) in w.iter().enumerate() {
                    let e = exact_weight(fc, phase + (RESAMPLE_HALF_WIDTH - 1) as f64 - k as f64, norm);
                    worst = worst.max((wk - e).abs());
                }
            }
        }
        // Rounding: the closed form's own error is about 1e-16, the interpolant's 7e-15.
        assert!(worst < 1e-14, "{worst}");
    }

    #[test]
    fn the_result_does_not_depend_on_the_number_of_threads() {
        // Long enough for several parallel chunks; a gap makes two pieces share one kernel.
        let clock = SampleClock::from_step(TAU, TAU / 97.3).unwrap();
        let f = |t: f64| t + 0.7 * (t + 0.3).sin();
        let whole: Vec<f64> = (0..3 * CHUNK).map(|n| wrap(f(clock.time(n)))).collect();
        let mut x = whole.clone();
        x[CHUNK..CHUNK + 300].fill(f64::NAN);
        let pieces = [0..CHUNK, CHUNK + 300..3 * CHUNK];
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let one = resample_to_whole(&whole, &clock, Domain::Circle).unwrap();
                let split = resample_pieces(&x, &pieces, &clock, Domain::Circle).unwrap();
                (one.samples, split.samples)
            })
        };
        let (one, two) = (run(1), run(2));
        assert!(one.0.len() > 2 * CHUNK, "{}", one.0.len());
        // Bit for bit (NaN in the gap compared by its bits too).
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&one.0), bits(&two.0));
        assert_eq!(bits(&one.1), bits(&two.1));
    }

    #[test]
    fn columns_resampled_together_are_each_column_resampled_alone() {
        // An angle through the wrap, a line signal, a constant and another angle, over two pieces (a gap of 300
        // samples), long enough for several parallel chunks: each column bit for bit what it
        // gives alone, on the same pieces and clock.
        let clock = SampleClock::from_step(TAU, TAU / 97.3).unwrap();
        let n = 3 * CHUNK;
        let angle: Vec<f64> = (0..n)
            .map(|i| wrap(1.3 * clock.time(i) + 0.4 * clock.time(i).sin()))
            .collect();
        let line: Vec<f64> = (0..n).map(|i| (0.7 * clock.time(i)).cos() * 3.0 + 1.0).collect();
        let constant = vec![0.25; n];
        let other: Vec<f64> = (0..n).map(|i| wrap(-0.6 * clock.time(i) + 2.0)).collect();
        // Four columns: two groups of those resampled together.
        let mut with_gap = [angle, line, constant, other];
        for column in &mut with_gap {
            column[CHUNK..CHUNK + 300].fill(f64::NAN);
        }
        let pieces = [0..CHUNK, CHUNK + 300..n];
        let domains = [Domain::Circle, Domain::Line, Domain::Line, Domain::Circle];
        assert!(domains.len() > COLUMNS_TOGETHER);
        let columns: Vec<(Vec<f64>, Domain)> = with_gap.iter().cloned().zip(domains).collect();
        let together = resample_columns(columns.clone(), &pieces, &clock).unwrap();
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        for (k, (x, domain)) in columns.iter().enumerate() {
            let alone = resample_pieces(x, &pieces, &clock, *domain).unwrap();
            assert_eq!(bits(&together.columns[k]), bits(&alone.samples), "column {k}");
            assert_eq!(together.pieces, alone.pieces);
            assert_eq!(together.clock, alone.clock);
        }
        assert_eq!(together.pieces.len(), 2);
        // Columns of other lengths, and a column with a NaN inside a piece, are refused.
        let short = vec![0.0; n - 1];
        assert!(matches!(
            resample_columns(vec![columns[0].clone(), (short, Domain::Line)], &pieces, &clock),
            Err(CircleError::LengthMismatch { .. })
        ));
        let mut bad = with_gap[1].clone();
        bad[10] = f64::NAN;
        assert!(matches!(
            resample_columns(vec![columns[0].clone(), (bad, Domain::Line)], &pieces, &clock),
            Err(CircleError::NonFinite { index: 10, .. })
        ));
        // No column: nothing to do, on the output grid.
        let none = resample_columns(Vec::new(), &pieces, &clock).unwrap();
        assert!(none.columns.is_empty());
        // A whole clock gives the columns back as they are.
        let whole = SampleClock::new(TAU, 97).unwrap();
        let same = resample_columns(columns.clone(), &pieces, &whole).unwrap();
        assert_eq!(bits(&same.columns[1]), bits(&columns[1].0));
        assert_eq!(same.pieces, pieces);
    }

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
    // Lists of one piece are what is meant here, not ranges to collect.
    #[allow(clippy::single_range_in_vec_init)]
    fn pieces_share_one_grid_and_match_the_whole_record() {
        // A record with a gap of 500 samples resampled in pieces: every output sample equals the
        // resampling of the whole (gapless) record at the same time, within the kernel's accuracy,
        // and the gap (plus the kernel's reach) holds NaN.
        let clock = SampleClock::from_step(TAU, TAU / 97.3).unwrap();
        let f = |t: f64| t + 0.7 * (t + 0.3).sin() + 0.2 * (3.0 * t).cos();
        let n = 6000;
        let full: Vec<f64> = (0..n).map(|i| wrap(f(clock.time(i)))).collect();
        let whole = resample_to_whole(&full, &clock, Domain::Circle).unwrap();
        let mut x = full.clone();
        x[2000..2500].fill(f64::NAN);
        let pieces = [0..2000, 2500..n];
        let r = resample_pieces(&x, &pieces, &clock, Domain::Circle).unwrap();
        assert_eq!(r.clock, whole.clock);
        assert_eq!(r.pieces.len(), 2);
        assert_eq!(r.pieces[0].start, 0);
        for (m, &v) in r.samples.iter().enumerate() {
            let inside = r.pieces.iter().any(|p| p.contains(&m));
            assert_eq!(v.is_nan(), !inside, "{m}");
            if inside {
                assert!(crate::circle_distance(v, f(r.clock.time(m))) < 1e-7, "{m}");
            }
        }
        // Each piece keeps its samples but the kernel's reach at both ends.
        let t = |i: usize| clock.time(i);
        let (a, b) = (&r.pieces[0], &r.pieces[1]);
        assert!(r.clock.time(a.end - 1) <= t(2000 - 1 - RESAMPLE_HALF_WIDTH) + 1e-9);
        assert!(r.clock.time(a.end) > t(2000 - 1 - RESAMPLE_HALF_WIDTH) - 1e-9);
        assert!(r.clock.time(b.start) >= t(2500 + RESAMPLE_HALF_WIDTH) - 1e-9);
        assert!(r.clock.time(b.start - 1) < t(2500 + RESAMPLE_HALF_WIDTH) + 1e-9);
        assert_eq!(r.samples.len(), b.end);
        // A piece too short for the kernel is dropped; bad pieces are errors.
        let r = resample_pieces(&x, &[0..2000, 2500..2600], &clock, Domain::Circle).unwrap();
        assert_eq!(r.pieces.len(), 1);
        assert!(matches!(
            resample_pieces(&x, &[0..100], &clock, Domain::Circle),
            Err(CircleError::TooShort { len: 100, .. })
        ));
        assert!(matches!(
            resample_pieces(&x, &[0..2001], &clock, Domain::Circle),
            Err(CircleError::NonFinite { index: 2000, .. })
        ));
        let (empty, beyond) = (5..5, 0..n + 1);
        for bad in [&[0..10, 5..20][..], &[empty], &[beyond]] {
            assert!(matches!(
                resample_pieces(&x, bad, &clock, Domain::Circle),
                Err(CircleError::BadPiece { .. })
            ));
        }
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
