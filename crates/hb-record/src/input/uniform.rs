//! The checks a record must pass before identification: time stamps on a uniform grid
//! `t0 + n · dt` (each within [`GRID_TOLERANCE`] of its grid time), split into pieces at gaps,
//! isolated glitches repaired on request. (The forcing period need not be a whole number of
//! steps: the command line resamples the record once, `circle_signal::resample_pieces`.)
//!
//! The grid is fitted in four steps, each robust to what the previous one could not see:
//!
//! 1. a first step, the median of the steps (at most 100 001 of them, evenly spread);
//! 2. the step refined as the mean of the "single" steps (within half a step of the estimate),
//!    until it settles; runs of single steps telescope, so the rounding of the stamps inside a
//!    run cancels;
//! 3. the runs of single steps linked into one index sequence (the gap between two runs rounded
//!    to whole steps), and a least-squares line fitted to their stamps;
//! 4. every stamp indexed by the line (`n = round((t − t0) / dt)`) and the line fitted again to
//!    the stamps within the tolerance of their grid time, until it no longer changes.
//!
//! Then each stamp is judged against the final line: it fits when it is within the tolerance of
//! its grid time; it is in place when its "level" `n − i` (grid index less position) does not go
//! down from the previous good stamp's, and does not stand above the level of the stamps that
//! follow. A level going up is a gap; any other stamp is a glitch.

use super::{InputError, Location, Record, StampFault, median, printed_decimals};

/// Largest distance of a time stamp from its grid time `t0 + n · dt`, in steps, for it to fit.
///
/// A quarter of a step: a stamp that fits is then at least three quarters of a step from any
/// other grid time, so its index is never in doubt, and the tolerance covers stamps printed with
/// a resolution up to half a step (a DAQ at 2048 Hz printing 4 decimals is off by up to a tenth
/// of a step) plus the jitter of a clock.
pub const GRID_TOLERANCE: f64 = 0.25;

/// More stamps than this fraction of the record (and at least [`UNRESOLVED_MIN`]) off the grid
/// or repeated are not glitches: the stamps do not resolve the samples.
const UNRESOLVED_FRACTION: f64 = 0.05;

/// See [`UNRESOLVED_FRACTION`].
const UNRESOLVED_MIN: usize = 3;

/// Steps, evenly spread, whose median is the first estimate of the step.
const MEDIAN_STEPS: usize = 100_001;

/// The largest grid index a stamp may have (from the first stamp of the first run).
const MAX_INDEX: f64 = (1u64 << 52) as f64;

/// Refits of the line before it is taken as it stands.
const MAX_REFITS: usize = 50;

/// How to fit a record's time stamps to a grid.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct GridOptions {
    /// Replace each isolated glitch (a stamp off the grid, repeated or going backwards, whose
    /// neighbours on both sides fit the grid one step away) by its grid time, and report it in
    /// [`GridRecord::repaired`]. Without it, such a stamp is an error.
    pub repair: bool,
}

/// A time stamp replaced by its grid time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimeRepair {
    /// Where the stamp is.
    pub at: Location,
    /// The stamp as read.
    pub was: f64,
    /// Its grid time.
    pub now: f64,
}

/// A run of samples without gaps.
#[derive(Debug, Clone, PartialEq)]
pub struct Piece {
    /// The grid index of its first sample: that sample is at `t0 + first · dt`.
    pub first: usize,
    /// The samples, one step apart.
    pub samples: Vec<f64>,
}

/// A record on a uniform time grid `t0 + n · dt`, in pieces separated by gaps (missing samples).
#[derive(Debug, Clone, PartialEq)]
pub struct GridRecord {
    /// Time of the first sample (its grid time, the stamp as fitted).
    pub t0: f64,
    /// Sampling step.
    pub dt: f64,
    /// The pieces, in order; the first starts at index 0, and each next one at least two steps
    /// after the end of the previous one. A single piece when there is no gap.
    pub pieces: Vec<Piece>,
    /// The stamps replaced by their grid time, in order (empty unless repair was asked for).
    pub repaired: Vec<TimeRepair>,
}

impl GridRecord {
    /// Fits the record's time stamps to a uniform grid (see the module docs and
    /// [`GRID_TOLERANCE`]), splits it at gaps, and repairs isolated glitches if asked.
    ///
    /// Errors: fewer than 2 samples; time decreasing in most steps; stamps that do not resolve
    /// the samples ([`InputError::TimeUnresolved`]); a glitch not repaired
    /// ([`InputError::TimeGlitch`]), the first in the record.
    pub fn fit(record: Record, options: &GridOptions) -> Result<Self, InputError> {
        let Record { t, theta, lines, .. } = record;
        let n = t.len();
        if n < 2 {
            return Err(InputError::TooFewSamples { found: n, needed: 2 });
        }
        let at = |i: usize| match lines.as_ref().and_then(|lines| lines.get(i)) {
            Some(&line) => Location::Line(line),
            None => Location::Sample(i + 1),
        };
        let unresolved = |off: usize| InputError::TimeUnresolved {
            off,
            total: n,
            decimals: printed_decimals(&t),
        };

        let dt0 = first_step(&t);
        if dt0.is_nan() || dt0 <= 0.0 {
            if dt0 == 0.0 {
                return Err(unresolved(t.windows(2).filter(|w| w[1] == w[0]).count()));
            }
            let i = (1..n).find(|&i| t[i] <= t[i - 1]).unwrap_or(1);
            return Err(InputError::TimeNotIncreasing {
                at: at(i),
                t: t[i],
                previous: t[i - 1],
            });
        }
        let dt = refine_step(&t, dt0);
        let runs = single_runs(&t, dt);
        let Some(&(start, _)) = runs.first() else {
            return Err(unresolved(n));
        };
        let origin = t[start];
        let tau = |i: usize| t[i] - origin;
        let starts = link(&t, &runs, dt);
        let mut line = least_squares(|f| {
            for (&(s, e), &k) in runs.iter().zip(&starts) {
                for i in s..=e {
                    f(k + (i - s) as f64, tau(i));
                }
            }
        })
        .ok_or_else(|| unresolved(n))?;
        for _ in 0..MAX_REFITS {
            let next = least_squares(|f| {
                for i in 0..n {
                    let (k, fits) = line.locate(tau(i));
                    if fits {
                        f(k, tau(i));
                    }
                }
            });
            match next {
                Some(next) if next != line => line = next,
                _ => break,
            }
        }
        if !(line.b.is_finite() && line.b > 0.0) {
            return Err(unresolved(n));
        }

        // Grid times increase with the index: those of every stamp's index (and of the indices
        // next to them, where glitches are repaired) are finite when the extreme ones are.
        let (lowest, highest) = (0..n).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), i| {
            let k = line.locate(tau(i)).0;
            (lo.min(k), hi.max(k))
        });
        if !(origin + line.at(lowest - 1.0)).is_finite() || !(origin + line.at(highest + 1.0)).is_finite() {
            return Err(InputError::TimeOverflow {
                at: at(n - 1),
                t: t[n - 1],
            });
        }

        let judged = judge(&t, |i| line.locate(tau(i)));
        if judged.good == 0
            || (judged.unresolved >= UNRESOLVED_MIN
                && judged.unresolved as f64 > UNRESOLVED_FRACTION * n as f64)
        {
            return Err(unresolved(judged.unresolved));
        }

        // Every glitch repaired, or the first one that cannot be is an error.
        let index = |i: usize| line.locate(tau(i)).0;
        let bad = &judged.bad;
        let mut fixed = Vec::with_capacity(bad.len());
        for (p, &i) in bad.iter().enumerate() {
            let prev_good = i > 0 && (p == 0 || bad[p - 1] != i - 1);
            let next_good = i + 1 < n && bad.get(p + 1) != Some(&(i + 1));
            let isolated = (i == 0 || prev_good)
                && (i + 1 == n || next_good)
                && (i == 0 || i + 1 == n || index(i + 1) - index(i - 1) == 2.0);
            if !(isolated && options.repair) {
                let fault = match i.checked_sub(1).map(|j| t[j]) {
                    Some(previous) if t[i] == previous => StampFault::Repeated,
                    Some(previous) if t[i] < previous => StampFault::Backwards { previous },
                    _ => StampFault::OffGrid,
                };
                return Err(InputError::TimeGlitch {
                    at: at(i),
                    t: t[i],
                    fault,
                    expected: origin + line.at(expected_index(bad, p, n, index)),
                    dt: line.b,
                    isolated,
                });
            }
            fixed.push(if prev_good {
                index(i - 1) + 1.0
            } else {
                index(i + 1) - 1.0
            });
        }
        let final_index = |i: usize| match bad.binary_search(&i) {
            Ok(p) => fixed[p],
            Err(_) => index(i),
        };
        let k0 = final_index(0);
        let t0 = origin + line.at(k0);
        let repaired = bad
            .iter()
            .zip(&fixed)
            .map(|(&i, &k)| TimeRepair {
                at: at(i),
                was: t[i],
                now: t0 + (k - k0) * line.b,
            })
            .collect();

        // Pieces, split from the end so that each sample moves once.
        let mut starts = vec![(0, 0)];
        let mut previous = k0;
        for i in 1..n {
            let k = final_index(i);
            if k - previous >= 2.0 {
                starts.push((i, (k - k0) as usize));
            }
            previous = k;
        }
        let mut theta = theta;
        let mut pieces: Vec<Piece> = starts
            .iter()
            .rev()
            .map(|&(i, first)| Piece {
                first,
                samples: theta.split_off(i),
            })
            .collect();
        pieces.reverse();
        Ok(Self {
            t0,
            dt: line.b,
            pieces,
            repaired,
        })
    }

    /// The number of samples in all pieces.
    pub fn sample_count(&self) -> usize {
        self.pieces.iter().map(|p| p.samples.len()).sum()
    }
}

/// The line `τ = a + n · b` through the stamps, `τ` counted from the first stamp of the first
/// run of single steps.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Line {
    a: f64,
    b: f64,
}

impl Line {
    /// The grid index nearest to `tau`, and whether `tau` is within the tolerance of it (never
    /// for an index beyond 2^52, where whole numbers are no longer exact).
    fn locate(self, tau: f64) -> (f64, bool) {
        let k = ((tau - self.a) / self.b).round();
        let off = tau - self.a - k * self.b;
        (k, off.abs() <= GRID_TOLERANCE * self.b && k.abs() <= MAX_INDEX)
    }

    /// The grid time of index `k`.
    fn at(self, k: f64) -> f64 {
        self.a + k * self.b
    }
}

/// The median of at most [`MEDIAN_STEPS`] steps, evenly spread.
fn first_step(t: &[f64]) -> f64 {
    let stride = (t.len() - 1).div_ceil(MEDIAN_STEPS).max(1);
    let mut steps: Vec<f64> = (0..t.len() - 1)
        .step_by(stride)
        .map(|i| t[i + 1] - t[i])
        .collect();
    median(&mut steps).unwrap_or(f64::NAN)
}

/// Whether the step from `a` to `b` is a single step of about `dt`.
fn single(a: f64, b: f64, dt: f64) -> bool {
    ((b - a) / dt - 1.0).abs() <= 0.5
}

/// The maximal runs `(first, last)` of at least two samples with single steps between them.
fn single_runs(t: &[f64], dt: f64) -> Vec<(usize, usize)> {
    let mut runs = Vec::new();
    let mut start = None;
    for i in 0..t.len() - 1 {
        if single(t[i], t[i + 1], dt) {
            start.get_or_insert(i);
        } else if let Some(s) = start.take() {
            runs.push((s, i));
        }
    }
    if let Some(s) = start {
        runs.push((s, t.len() - 1));
    }
    runs
}

/// The mean single step (runs telescoped), from `dt` until it settles.
fn refine_step(t: &[f64], mut dt: f64) -> f64 {
    for _ in 0..8 {
        let (span, steps) = single_runs(t, dt)
            .iter()
            .fold((0.0, 0usize), |(span, steps), &(s, e)| {
                (span + (t[e] - t[s]), steps + (e - s))
            });
        if steps == 0 {
            break;
        }
        let next = span / steps as f64;
        if next == dt {
            break;
        }
        dt = next;
    }
    dt
}

/// The grid index of the first sample of each run, consistent across the runs (any one may be
/// shifted by the same whole number).
///
/// From the longest run outwards, each time to the neighbour run nearer in time: its index is
/// that of the line fitted to the runs linked so far, so that each gap is measured against the
/// longest baseline there is.
fn link(t: &[f64], runs: &[(usize, usize)], dt: f64) -> Vec<f64> {
    let longest = (0..runs.len())
        .max_by_key(|&r| (runs[r].1 - runs[r].0, std::cmp::Reverse(r)))
        .unwrap_or(0);
    let origin = t[runs[longest].0];
    let mut moments = Moments::default();
    let add = |moments: &mut Moments, (s, e): (usize, usize), k: f64| {
        for (j, &ti) in t[s..=e].iter().enumerate() {
            moments.add(k + j as f64, ti - origin);
        }
    };
    let mut starts = vec![0.0; runs.len()];
    add(&mut moments, runs[longest], 0.0);
    let (mut lo, mut hi) = (longest, longest);
    while lo > 0 || hi + 1 < runs.len() {
        let line = moments.line().unwrap_or(Line { a: 0.0, b: dt });
        let index = |i: usize| ((t[i] - origin - line.a) / line.b).round();
        let left = (lo > 0).then(|| t[runs[lo].0] - t[runs[lo - 1].1]);
        let right = (hi + 1 < runs.len()).then(|| t[runs[hi + 1].0] - t[runs[hi].1]);
        let go_left = match (left, right) {
            (Some(l), Some(r)) => l <= r,
            (l, _) => l.is_some(),
        };
        let r = if go_left { lo - 1 } else { hi + 1 };
        let (s, e) = runs[r];
        starts[r] = if go_left {
            index(e) - (e - s) as f64
        } else {
            index(s)
        };
        add(&mut moments, runs[r], starts[r]);
        if go_left {
            lo = r;
        } else {
            hi = r;
        }
    }
    starts
}

/// Sums of the points `(n, τ)` of a least-squares line, added one at a time.
#[derive(Debug, Default)]
struct Moments {
    count: usize,
    n: Sum,
    tau: Sum,
    nn: Sum,
    ntau: Sum,
}

impl Moments {
    fn add(&mut self, k: f64, tau: f64) {
        self.count += 1;
        self.n.add(k);
        self.tau.add(tau);
        self.nn.add(k * k);
        self.ntau.add(k * tau);
    }

    /// The line through the points so far; `None` for fewer than two distinct indices.
    fn line(&self) -> Option<Line> {
        let count = self.count as f64;
        let (n, tau) = (self.n.value(), self.tau.value());
        let sxx = self.nn.value() - n * n / count;
        let sxy = self.ntau.value() - n * tau / count;
        if sxx.is_nan() || sxx <= 0.0 {
            return None;
        }
        let b = sxy / sxx;
        Some(Line {
            a: (tau - b * n) / count,
            b,
        })
    }
}

/// The least-squares line through the points `(n, τ)` that `visit` hands to its argument (it is
/// called twice, and must hand the same points); `None` for fewer than two distinct indices.
fn least_squares(visit: impl Fn(&mut dyn FnMut(f64, f64))) -> Option<Line> {
    let (mut count, mut sum_n, mut sum_t) = (0usize, Sum::default(), Sum::default());
    visit(&mut |k, tau| {
        count += 1;
        sum_n.add(k);
        sum_t.add(tau);
    });
    if count < 2 {
        return None;
    }
    let (mean_n, mean_t) = (sum_n.value() / count as f64, sum_t.value() / count as f64);
    let (mut sxx, mut sxy) = (Sum::default(), Sum::default());
    visit(&mut |k, tau| {
        let dk = k - mean_n;
        sxx.add(dk * dk);
        sxy.add(dk * (tau - mean_t));
    });
    let (sxx, sxy) = (sxx.value(), sxy.value());
    if sxx.is_nan() || sxx <= 0.0 {
        return None;
    }
    let b = sxy / sxx;
    Some(Line {
        a: mean_t - b * mean_n,
        b,
    })
}

/// A compensated (Neumaier) sum: exact to a few roundings whatever the number of terms.
#[derive(Debug, Default, Clone, Copy)]
struct Sum {
    sum: f64,
    compensation: f64,
}

impl Sum {
    fn add(&mut self, x: f64) {
        let t = self.sum + x;
        self.compensation += if self.sum.abs() >= x.abs() {
            (self.sum - t) + x
        } else {
            (x - t) + self.sum
        };
        self.sum = t;
    }

    fn value(self) -> f64 {
        self.sum + self.compensation
    }
}

/// The stamps judged against the line.
struct Judged {
    /// The samples whose stamps are glitches, in order.
    bad: Vec<usize>,
    /// How many glitches are off the grid or repeat the previous stamp.
    unresolved: usize,
    /// How many stamps are good.
    good: usize,
}

/// Judges every stamp by its grid index `locate(i)` and whether it fits (see the module docs).
///
/// With `g_i = n_i − i` its level, a stamp that fits is anchored when a neighbour that fits has
/// the same level. A stamp is good when it fits, its level is not below the last good stamp's,
/// and, unless it is anchored, not above the next anchored stamp's level either.
fn judge(t: &[f64], locate: impl Fn(usize) -> (f64, bool)) -> Judged {
    let n = t.len();
    let level = |i: usize| {
        let (k, fits) = locate(i);
        (k - i as f64, fits)
    };
    let anchored = |i: usize| {
        let (g, fits) = level(i);
        fits && ((i > 0 && level(i - 1) == (g, true)) || (i + 1 < n && level(i + 1) == (g, true)))
    };
    let mut judged = Judged {
        bad: Vec::new(),
        unresolved: 0,
        good: 0,
    };
    let mut last: Option<f64> = None;
    // The next anchored stamp after the current one (n when there is none).
    let mut ahead = 0;
    for i in 0..n {
        let (g, fits) = level(i);
        let good = fits
            && last.is_none_or(|l| g >= l)
            && (anchored(i) || {
                if ahead <= i {
                    ahead = i + 1;
                    while ahead < n && !anchored(ahead) {
                        ahead += 1;
                    }
                }
                ahead == n || g <= level(ahead).0
            });
        if good {
            last = Some(g);
            judged.good += 1;
        } else {
            judged.bad.push(i);
            if !fits || (i > 0 && t[i] == t[i - 1]) {
                judged.unresolved += 1;
            }
        }
    }
    judged
}

/// The grid index sample `bad[p]` would have, counted from its nearest good neighbour (the one
/// before it if any).
fn expected_index(bad: &[usize], p: usize, n: usize, index: impl Fn(usize) -> f64) -> f64 {
    let i = bad[p];
    let mut first = p;
    while first > 0 && bad[first - 1] == bad[first] - 1 {
        first -= 1;
    }
    if bad[first] > 0 {
        let j = bad[first] - 1;
        return index(j) + (i - j) as f64;
    }
    let mut last = p;
    while last + 1 < bad.len() && bad[last + 1] == bad[last] + 1 {
        last += 1;
    }
    let j = (bad[last] + 1).min(n - 1);
    index(j) - (j as f64 - i as f64)
}

#[cfg(test)]
mod tests {
    use super::super::*;
    use proptest::prelude::*;

    /// A record with these stamps (line numbers from 2, after a header) and values 0, 1, 2, ….
    fn record(t: Vec<f64>) -> Record {
        Record {
            theta: (0..t.len()).map(|i| i as f64).collect(),
            lines: Some((0..t.len() as u64).map(|i| i + 2).collect()),
            t,
            drive: None,
        }
    }

    fn fit(t: Vec<f64>) -> Result<GridRecord, InputError> {
        GridRecord::fit(record(t), &GridOptions::default())
    }

    fn repair(t: Vec<f64>) -> Result<GridRecord, InputError> {
        GridRecord::fit(record(t), &GridOptions { repair: true })
    }

    /// `n` stamps `t0 + i · dt` printed with `decimals` decimals.
    fn printed(n: usize, t0: f64, dt: f64, decimals: usize) -> Vec<f64> {
        (0..n)
            .map(|i| format!("{:.*}", decimals, t0 + i as f64 * dt).parse().unwrap())
            .collect()
    }

    #[test]
    fn exact_grid_is_one_piece() {
        let u = fit((0..100).map(|n| 10.0 + n as f64 * 0.04).collect()).unwrap();
        assert!((u.dt - 0.04).abs() < 1e-15 && (u.t0 - 10.0).abs() < 1e-13);
        assert_eq!(u.pieces.len(), 1);
        assert_eq!(u.pieces[0].first, 0);
        assert_eq!(
            u.pieces[0].samples,
            (0..100).map(|i| i as f64).collect::<Vec<_>>()
        );
        assert!(u.repaired.is_empty());
        assert_eq!(u.sample_count(), 100);
        assert!(matches!(fit(vec![0.0]), Err(InputError::TooFewSamples { .. })));
        assert_eq!(fit(vec![3.0, 3.5]).unwrap().dt, 0.5);
    }

    /// The bound on the error of a least-squares step from stamps at grid indices `indices`,
    /// each off by at most `e`: `e · Σ|n − n̄| / Σ(n − n̄)²`.
    fn step_bound(indices: &[usize], e: f64) -> f64 {
        let count = indices.len() as f64;
        let mean = indices.iter().sum::<usize>() as f64 / count;
        let sxx: f64 = indices.iter().map(|&k| (k as f64 - mean).powi(2)).sum();
        let sabs: f64 = indices.iter().map(|&k| (k as f64 - mean).abs()).sum();
        e * sabs / sxx
    }

    #[test]
    fn stamps_printed_to_4_decimals_at_2048_hz_fit() {
        // One minute at 2048 Hz: each stamp is off by up to 0.1 step.
        let dt = 1.0 / 2048.0;
        let n = 2048 * 60;
        let u = fit(printed(n, 0.0, dt, 4)).unwrap();
        let error = (u.dt - dt).abs() / dt;
        assert!(error < 1e-9, "relative error of the step {error:e}");
        assert!(u.t0.abs() < 0.1 * dt, "{}", u.t0);
        assert_eq!((u.pieces.len(), u.sample_count()), (1, n));
        // From any start, the step is within the bound of least squares.
        let indices: Vec<usize> = (0..n).collect();
        for t0 in [12.3456, 3.7, -1.23456789] {
            let u = fit(printed(n, t0, dt, 4)).unwrap();
            let bound = step_bound(&indices, 0.5e-4);
            assert!(
                (u.dt - dt).abs() <= bound,
                "{t0}: {} vs {dt}, bound {bound:e}",
                u.dt
            );
            assert!((u.t0 - t0).abs() < 0.1 * dt, "{}", u.t0);
        }
    }

    #[test]
    fn stamps_printed_too_coarsely_ask_for_the_step() {
        for (rate, decimals) in [(2048.0, 3), (1500.0, 3), (300.0, 2)] {
            let t = printed(4096, 1.0, 1.0 / rate, decimals);
            match fit(t) {
                Err(e @ InputError::TimeUnresolved { .. }) => {
                    let text = e.to_string();
                    assert!(
                        text.contains(&format!("written with {decimals} decimals")),
                        "{text}"
                    );
                    assert!(text.contains("give its step"), "{text}");
                }
                other => panic!("{rate} Hz, {decimals} decimals: {other:?}"),
            }
        }
        // Stamps that the decimals write exactly fit, however few the decimals.
        assert!(fit(printed(4096, 1.0, 1e-3, 3)).is_ok());
    }

    #[test]
    fn a_backwards_stamp_names_its_line() {
        let mut t: Vec<f64> = (0..50).map(|i| i as f64 * 0.1).collect();
        t[20] = 1.85; // between samples 18 and 19
        match fit(t.clone()) {
            Err(
                e @ InputError::TimeGlitch {
                    at: Location::Line(22),
                    fault: StampFault::Backwards { previous },
                    isolated: true,
                    ..
                },
            ) => {
                assert!((previous - 1.9).abs() < 1e-12);
                let text = e.to_string();
                assert!(text.starts_with("line 22: time 1.85 does not increase"), "{text}");
                assert!(
                    text.contains("this sample is at 2:") && text.contains("can be repaired"),
                    "{text}"
                );
            }
            other => panic!("{other:?}"),
        }
        let u = repair(t).unwrap();
        assert_eq!(u.pieces.len(), 1);
        assert_eq!(u.repaired.len(), 1);
        let r = u.repaired[0];
        assert_eq!((r.at, r.was), (Location::Line(22), 1.85));
        assert!((r.now - 2.0).abs() < 1e-12, "{r:?}");
    }

    #[test]
    fn repair_fixes_isolated_glitches_of_every_kind() {
        let grid = |n: usize| -> Vec<f64> { (0..n).map(|i| 5.0 + i as f64 * 0.01).collect() };
        let cases: [(usize, f64, StampFault); 5] = [
            (30, 5.3045, StampFault::OffGrid), // off the grid by 0.45 step
            (30, 5.35, StampFault::OffGrid),   // on the grid, five steps ahead
            (30, 5.29, StampFault::Repeated),  // the previous stamp again
            (0, 4.996, StampFault::OffGrid),   // the first stamp, 0.4 step early
            (99, 5.0, StampFault::Backwards { previous: 5.98 }), // the last
        ];
        for (i, glitch, fault) in cases {
            let mut t = grid(100);
            let truth = t[i];
            t[i] = glitch;
            match fit(t.clone()) {
                Err(InputError::TimeGlitch {
                    at,
                    fault: f,
                    isolated: true,
                    expected,
                    ..
                }) => {
                    assert_eq!(at, Location::Line(i as u64 + 2), "{glitch}");
                    assert!((expected - truth).abs() < 1e-9, "{glitch}: {expected}");
                    match (fault, f) {
                        (StampFault::Backwards { previous: a }, StampFault::Backwards { previous: b }) => {
                            assert!((a - b).abs() < 1e-12)
                        }
                        _ => assert_eq!(f, fault, "{glitch}"),
                    }
                }
                other => panic!("{glitch}: {other:?}"),
            }
            let u = repair(t).unwrap();
            assert_eq!(u.pieces.len(), 1, "{glitch}");
            assert_eq!(u.pieces[0].samples.len(), 100);
            assert_eq!(u.repaired.len(), 1);
            assert!(
                (u.repaired[0].now - truth).abs() < 1e-9,
                "{glitch}: {:?}",
                u.repaired
            );
            assert!((u.t0 - 5.0).abs() < 1e-9 && (u.dt - 0.01).abs() < 1e-12);
        }
    }

    #[test]
    fn non_isolated_glitches_fail_even_with_repair() {
        let grid = || -> Vec<f64> { (0..100).map(|i| i as f64 * 0.5).collect() };
        let mut two = grid();
        (two[40], two[41]) = (20.2, 20.7); // two neighbours off the grid
        let mut swapped = grid();
        swapped.swap(60, 61);
        let mut beside_a_gap = grid();
        beside_a_gap.remove(70);
        beside_a_gap[70] += 0.15; // the sample after the gap is off the grid
        for (t, line) in [(two, 42), (swapped, 62), (beside_a_gap, 72)] {
            for options in [GridOptions::default(), GridOptions { repair: true }] {
                match GridRecord::fit(record(t.clone()), &options) {
                    Err(e @ InputError::TimeGlitch { isolated: false, .. }) => {
                        assert!(e.to_string().starts_with(&format!("line {line}:")), "{e}");
                        assert!(e.to_string().contains("cannot be repaired"), "{e}");
                    }
                    other => panic!("line {line}: {other:?}"),
                }
            }
        }
        // A clock that starts again: everything after is backwards.
        let mut reset = grid();
        for v in &mut reset[50..] {
            *v -= 20.0;
        }
        assert!(matches!(
            repair(reset),
            Err(InputError::TimeGlitch {
                at: Location::Line(52),
                fault: StampFault::Backwards { .. },
                isolated: false,
                ..
            })
        ));
        // Time going down all along.
        assert!(matches!(
            fit((0..10).map(|i| -(i as f64)).collect()),
            Err(InputError::TimeNotIncreasing {
                at: Location::Line(3),
                ..
            })
        ));
    }

    #[test]
    fn a_duplicate_stamp_is_a_glitch() {
        let mut t: Vec<f64> = (0..64).map(|i| i as f64 / 64.0).collect();
        t[10] = t[9];
        match fit(t.clone()) {
            Err(InputError::TimeGlitch {
                at: Location::Line(12),
                fault: StampFault::Repeated,
                ..
            }) => {}
            other => panic!("{other:?}"),
        }
        let u = repair(t).unwrap();
        assert_eq!((u.pieces.len(), u.repaired[0].at), (1, Location::Line(12)));
        assert!((u.repaired[0].now - 10.0 / 64.0).abs() < 1e-12);
    }

    /// Stamps near the largest floating-point numbers: a grid was fitted, but the repaired time
    /// of the middle stamp overflowed (found by the fuzz target `grid_fit`).
    #[test]
    fn stamps_whose_grid_overflows_are_refused() {
        let t = vec![
            -1.2089666594180364e308,
            4.104138993080699e-207,
            -1.1843625389819756e308,
        ];
        for options in [GridOptions::default(), GridOptions { repair: true }] {
            match GridRecord::fit(record(t.clone()), &options) {
                Err(e @ InputError::TimeOverflow { .. }) => {
                    assert!(
                        e.to_string()
                            .starts_with("line 4: time -1.1843625389819756e308 is too far"),
                        "{e}"
                    )
                }
                other => panic!("{options:?}: {other:?}"),
            }
        }
        // Large stamps whose grid stays finite fit.
        let large: Vec<f64> = (0..10).map(|i| 1e307 + f64::from(i) * 1e305).collect();
        let u = fit(large).unwrap();
        assert!((u.dt / 1e305 - 1.0).abs() < 1e-12 && (u.t0 / 1e307 - 1.0).abs() < 1e-12);
    }

    #[test]
    fn gaps_split_the_record() {
        // Samples 0..100, then 103..200, then 250..300, stamped at 0.001 s printed to 5 decimals.
        let kept: Vec<usize> = (0..100).chain(103..200).chain(250..300).collect();
        let t: Vec<f64> = kept
            .iter()
            .map(|&k| format!("{:.5}", 7.0 + k as f64 * 0.001).parse().unwrap())
            .collect();
        let u = fit(t).unwrap();
        let firsts: Vec<usize> = u.pieces.iter().map(|p| p.first).collect();
        assert_eq!(firsts, vec![0, 103, 250]);
        let lengths: Vec<usize> = u.pieces.iter().map(|p| p.samples.len()).collect();
        assert_eq!(lengths, vec![100, 97, 50]);
        assert_eq!(u.pieces[1].samples[0], 100.0);
        assert!((u.dt - 0.001).abs() < 1e-12 && (u.t0 - 7.0).abs() < 1e-9);
        // A gap of two steps at the start too.
        let u = fit(vec![0.0, 2.0, 3.0, 4.0, 5.0]).unwrap();
        assert_eq!(u.pieces.iter().map(|p| p.first).collect::<Vec<_>>(), vec![0, 2]);
    }

    #[test]
    fn a_step_given_is_one_piece() {
        let opts = ReadOptions {
            dt: Some(0.125),
            ..Default::default()
        };
        let r = read_bytes(b"1\n2\n3\n4\n", &opts).unwrap();
        let u = GridRecord::fit(r, &GridOptions::default()).unwrap();
        assert_eq!((u.t0, u.dt, u.pieces.len()), (0.0, 0.125, 1));
    }

    /// Fits stamps `t0 + n · dt` printed with the fewest decimals whose half unit is within 0.2
    /// step, plus `extra`, at the indices of `runs` (lengths and the gaps after them), and checks
    /// that the fit finds every sample's index and a step within the bound of least squares on
    /// errors of at most half a unit ([`step_bound`]).
    fn check_fit(t0: f64, dt: f64, extra: usize, runs: &[(usize, usize)]) -> Result<(), TestCaseError> {
        let decimals = ((2.5 / dt).log10().ceil().max(0.0) as usize + extra).min(12);
        let unit = 10f64.powi(-(decimals as i32));
        let mut indices = Vec::new();
        let mut firsts = Vec::new();
        let mut k = 0;
        for (len, gap) in runs {
            firsts.push(k);
            indices.extend(k..k + len);
            k += len + gap;
        }
        let t: Vec<f64> = indices
            .iter()
            .map(|&k| format!("{:.*}", decimals, t0 + k as f64 * dt).parse().unwrap())
            .collect();
        let theta: Vec<f64> = (0..t.len()).map(|i| (i as f64).sin()).collect();
        let rec = Record {
            t,
            theta: theta.clone(),
            lines: None,
            drive: None,
        };
        let u =
            GridRecord::fit(rec, &GridOptions::default()).map_err(|e| TestCaseError::fail(e.to_string()))?;
        prop_assert_eq!(u.pieces.iter().map(|p| p.first).collect::<Vec<_>>(), firsts);
        let joined: Vec<f64> = u.pieces.iter().flat_map(|p| p.samples.iter().copied()).collect();
        prop_assert_eq!(joined, theta);
        prop_assert!(u.repaired.is_empty());
        // Half a unit, and the rounding of the numbers themselves; the arithmetic of the fit.
        let e = 0.5 * unit + 1e-15 * (t0.abs() + k as f64 * dt);
        let bound = step_bound(&indices, e) + 1e-12 * dt;
        let off = (u.dt - dt).abs();
        prop_assert!(
            off <= bound,
            "step {} vs {dt}: off by {off:e}, bound {bound:e}",
            u.dt
        );
        Ok(())
    }

    proptest! {
        /// Rounding of up to 0.2 step, gaps up to 60 samples between runs of at least 20.
        #[test]
        fn fit_recovers_the_grid(
            t0 in -1e3..1e3f64,
            dt in 1e-5..10.0f64,
            extra in 0..2usize,
            runs in proptest::collection::vec((20..400usize, 2..60usize), 1..6),
        ) {
            check_fit(t0, dt, extra, &runs)?;
        }

        /// Any stamps at all: an error or a consistent grid, never a panic.
        #[test]
        fn fit_never_panics(
            t in proptest::collection::vec(
                prop_oneof![-1e3..1e3f64, Just(0.0), Just(1.0), -1e300..1e300f64, (0..40u32).prop_map(|k| k as f64 * 0.25)],
                0..40,
            ),
            repair in proptest::bool::ANY,
        ) {
            let n = t.len();
            if let Ok(u) = GridRecord::fit(record(t), &GridOptions { repair }) {
                prop_assert!(u.dt > 0.0 && u.dt.is_finite() && u.t0.is_finite());
                prop_assert_eq!(u.sample_count(), n);
                prop_assert_eq!(u.pieces[0].first, 0);
                prop_assert!(u.pieces.iter().all(|p| p.first as f64 <= 2f64.powi(53)));
                for w in u.pieces.windows(2) {
                    prop_assert!(w[1].first > w[0].first + w[0].samples.len());
                }
                prop_assert!(repair || u.repaired.is_empty());
            }
        }

        /// Rounding of up to 0.002 step, gaps up to 5000 samples between runs of at least 20.
        #[test]
        fn fit_recovers_long_gaps(
            t0 in -1e3..1e3f64,
            dt in 1e-5..10.0f64,
            extra in 2..4usize,
            runs in proptest::collection::vec((20..400usize, 2..5000usize), 1..8),
        ) {
            check_fit(t0, dt, extra, &runs)?;
        }
    }
}
