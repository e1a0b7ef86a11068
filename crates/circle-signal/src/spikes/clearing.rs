//! Which repairs could clear the residuals around them: a test, per sample, of every repair
//! starting there, made without thresholds, choices or a change of the record.
//!
//! Why: a sample or run is flagged only if its repair leaves at most [`CLEARED`] of the energy of
//! the residuals around it (see "Isolating the outlier" on [`find_spikes`](super::find_spikes)).
//! A noise-free record of a fast motion sampled finely (a whirling double pendulum at 64 samples
//! per drive period) has its smooth motion's residual stand out of its block at a fifth of its
//! samples; the search weighed local thresholds at each, and candidates around tens of thousands
//! of peaks, to reject nearly all of them by that test in the end. Here the test is made for
//! every repair at once, in closed form: replacing samples by their prediction moves them by `δ`,
//! and the residuals `r_k` within two samples by `δ` times the weights of the moved samples in
//! their predictions; if no repair that starts near a sample could pass it, the sample is
//! passed. Most repairs are settled before that by a bound of what any move of their samples
//! can take from the residuals' energy, their squared distance to a cubic (from their fourth
//! differences, [`INVERSE_GRAMS`]): a smooth motion's residuals are nearly a cubic locally.
//!
//! The residuals are taken from the record unwrapped over the block's reach. Where a step of the
//! record on the circle reaches π/4 (π/5 with runs of 4: a run's prediction unwraps the step
//! across it and its neighbours), or a residual or a move a radian, the local unwrapping of the
//! search could differ from this one: every repair of such a block counts as one that could
//! clear. So does every repair of a block whose residuals' squares could overflow (the search
//! then compares infinities), and every repair near the ends of the record (their predictions and
//! gains differ there). Each energy is summed over its own window (sums from a block's first
//! residual would lose a small energy's digits to a large one before it), and rounding is allowed
//! for generously: a repair counts as one that could clear when it leaves at most [`CLEARED`] of
//! the energy plus a millionth of it and a margin of a thousand times the rounding of the
//! record's values.

use std::f64::consts::PI;
use std::sync::LazyLock;

use super::{CLEARED, Geometry, MAX_RUN, run_cubic};

/// Samples per block: a block's repairs are tested together, once per state of the record.
const BLOCK: usize = 64;

/// The first sample a repair tested here may start at, and the samples it must end before the
/// record's end: its residuals' energy window, two samples on each side of the residuals it
/// reaches, and the samples those residuals' predictions read, all inside the record.
const MARGIN: usize = 10;

/// Residuals the energy of a repair spans beyond its samples on each side.
const REACH: usize = 4;

/// The weight of a move of a sample `d` away in a residual: 1 for the sample itself, `−2/3` for
/// its neighbours, `1/6` for the next.
const STENCIL: [f64; 3] = [1.0, -2.0 / 3.0, 1.0 / 6.0];

/// Per sample of the record, whether a repair starting there could clear its residuals.
pub(super) struct Clearing {
    n: usize,
    max_run: usize,
    /// One bit per sample: a repair starting there (the sample alone, or a run of up to
    /// `max_run`) could clear; valid in the blocks `known` holds.
    could: Vec<u64>,
    /// One bit per block: `could` holds the block's samples for the record as it stands.
    known: Vec<u64>,
    /// Scratch: the record unwrapped over a block's reach, its centred residuals, their squares
    /// and their fourth differences.
    unwrapped: Vec<f64>,
    residuals: Vec<f64>,
    squares: Vec<f64>,
    fourth: Vec<f64>,
}

impl Clearing {
    /// Nothing tested yet, for a record of `n` samples and runs of up to `max_run`.
    pub(super) fn new(n: usize, max_run: usize) -> Self {
        let blocks = n.div_ceil(BLOCK);
        Self {
            n,
            max_run,
            could: vec![0; blocks],
            known: vec![0; blocks.div_ceil(64)],
            unwrapped: Vec::new(),
            residuals: Vec::new(),
            squares: Vec::new(),
            fourth: Vec::new(),
        }
    }

    /// Whether a repair starting at a sample of `from ..= to` could clear the residuals around
    /// it, in the record `x` as it stands, and whether a block had to be tested to say so (the
    /// rest are read from the bits held).
    pub(super) fn could_clear<G: Geometry>(&mut self, x: &[f64], from: usize, to: usize) -> (bool, bool) {
        let to = to.min(self.n - 1);
        let mut tested = false;
        if from > to {
            return (false, tested);
        }
        for b in from / BLOCK..=to / BLOCK {
            if self.known[b / 64] >> (b % 64) & 1 == 0 {
                tested = true;
                self.could[b] = self.test_block::<G>(x, b);
                self.known[b / 64] |= 1 << (b % 64);
            }
            let lo = from.max(b * BLOCK) - b * BLOCK;
            let hi = to.min(b * BLOCK + BLOCK - 1) - b * BLOCK;
            let mask = (u64::MAX >> (63 - hi)) & (u64::MAX << lo);
            if self.could[b] & mask != 0 {
                return (true, tested);
            }
        }
        (false, tested)
    }

    /// Sample `j` was changed: the repairs whose residuals it reaches are tested again when next
    /// asked for.
    pub(super) fn changed(&mut self, j: usize) {
        let (a, b) = (
            j.saturating_sub(REACH + 2 + self.max_run + 2),
            (j + REACH + 4).min(self.n - 1),
        );
        for block in a / BLOCK..=b / BLOCK {
            self.known[block / 64] &= !(1 << (block % 64));
        }
    }

    /// The bits of block `b`: which of its samples start a repair that could clear.
    fn test_block<G: Geometry>(&mut self, x: &[f64], b: usize) -> u64 {
        let n = self.n;
        let max_run = self.max_run;
        let (first, end) = (b * BLOCK, ((b + 1) * BLOCK).min(n));
        // Repairs inside the record: starting at MARGIN or later, their longest run ending
        // MARGIN samples before the end. The others count as able to clear.
        let (from, to) = (
            first.max(MARGIN),
            end.min((n + 1).saturating_sub(max_run + MARGIN)),
        );
        let all = |a: usize, b: usize| (a..b).fold(0u64, |m, k| m | 1 << (k - first));
        if from >= to {
            return all(first, end);
        }
        let bits = all(first, from) | all(to, end);
        let (lo_start, hi_start) = (from, to - 1);
        // The samples the tested repairs read: residuals REACH beyond each repair's samples,
        // and the two samples beyond those that their predictions read.
        let lo = lo_start - REACH - 2;
        let hi = hi_start + max_run - 1 + REACH + 2;
        let len = hi + 1 - lo;
        let circle = G::DOMAIN == crate::Domain::Circle;
        self.unwrapped.resize(len, 0.0);
        let u = &mut self.unwrapped[..len];
        // A run's prediction unwraps the step across it and its two neighbours: `max_run + 1`
        // steps of less than this stay within half a turn (π/4 for single samples and runs of up
        // to 3, π/5 for runs of 4).
        let quarter = PI / (max_run as f64 + 1.0).max(4.0);
        let (mut at, mut steep) = (x[lo], false);
        u[0] = at;
        for (slot, w) in u[1..].iter_mut().zip(x[lo..=hi].windows(2)) {
            let step = G::diff(w[1] - w[0]);
            steep |= circle && step.abs() >= quarter;
            at += step;
            *slot = at;
        }
        if steep || !at.is_finite() || u.iter().any(|v| !v.is_finite()) {
            return all(first, end);
        }
        self.residuals.resize(len, 0.0);
        let r = &mut self.residuals[..len];
        // The first and last two have no centred residual here (nothing reads them).
        for k in [0, 1, len - 2, len - 1] {
            r[k] = 0.0;
        }
        // (A sixth by multiplication: these residuals are within rounding of the search's,
        // which `tol` allows for.)
        for (k, w) in (2..).zip(u.windows(5)) {
            r[k] = w[2] - (4.0 * (w[1] + w[3]) - w[0] - w[4]) * (1.0 / 6.0);
        }
        if circle && r[2..len - 2].iter().any(|v| v.abs() > 1.0) {
            return all(first, end);
        }
        let scale = u.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        // What rounding can make of a residual, with a thousandfold margin.
        let tol = 1e3 * 16.0 * f64::EPSILON * (1.0 + scale);
        // The residuals' squares (each repair's energy summed over its own window: sums from
        // the block's first residual would lose a small energy's digits to a large one before
        // it), and their fourth differences where the tested repairs reach. Residuals so large
        // that their squares, or a repair's, could overflow count as able to clear (the search's
        // test then compares infinities).
        self.squares.resize(len, 0.0);
        for (q, &v) in self.squares.iter_mut().zip(r.iter()) {
            *q = v * v;
        }
        let total: f64 = self.squares.iter().sum();
        if total.is_nan() || total >= 1e290 {
            return all(first, end);
        }
        self.fourth.resize(len, 0.0);
        for (k, w) in (2..).zip(r.windows(5)) {
            self.fourth[k] = w[0] + w[4] - 4.0 * (w[1] + w[3]) + 6.0 * w[2];
        }
        // The longest run's bound holds every shorter one's (their residuals are a part of its),
        // and the single sample's energy is the least (its window is a part of every longer
        // one's): most starts are settled at once, the others tested run by run.
        let (fourth, squares) = (&self.fourth[..], &self.squares[..]);
        let starts = (from - lo, to - lo);
        let open = match max_run {
            1 => screen::<1>(fourth, squares, starts, tol),
            2 => screen::<2>(fourth, squares, starts, tol),
            3 => screen::<3>(fourth, squares, starts, tol),
            _ => screen::<MAX_RUN>(fourth, squares, starts, tol),
        };
        let grams = &*INVERSE_GRAMS;
        let most = |s: usize, len: usize| -> f64 {
            let (e, g) = (&self.fourth[s..s + len], &grams[len - 1]);
            (0..len)
                .map(|i| e[i] * (0..len).map(|j| g[i][j] * e[j]).sum::<f64>())
                .sum()
        };
        let mut bits = bits;
        let mut open = open;
        while open != 0 {
            let k = open.trailing_zeros() as usize;
            open &= open - 1;
            let s = from - lo + k;
            for len in 1..=max_run {
                let before: f64 = self.squares[s - REACH..s + len + REACH].iter().sum();
                let slack = slack(before, tol);
                if most(s, len) >= (1.0 - CLEARED) * before - slack
                    && self.repair_clears(s, len, circle, before, slack)
                {
                    bits |= 1 << (from + k - first);
                    break;
                }
            }
        }
        bits
    }

    /// Whether replacing the `len` samples from `a` (in the scratch) by their prediction leaves
    /// at most [`CLEARED`] of `before`, the energy of the residuals from `REACH` before its first
    /// sample to `REACH` after its last (with `slack` for rounding).
    fn repair_clears(&self, a: usize, len: usize, circle: bool, before: f64, slack: f64) -> bool {
        let (u, r) = (&self.unwrapped, &self.residuals);
        let sq = |v: f64| v * v;
        let b = a + len - 1;
        // The moves of the repaired samples: to their prediction.
        let mut moves = [0.0; MAX_RUN];
        if len == 1 {
            moves[0] = -r[a];
        } else {
            for (p, m) in moves.iter_mut().enumerate().take(len) {
                let w = run_cubic(len, p).weights;
                let pred = w[0] * u[a - 2] + w[1] * u[a - 1] + w[2] * u[b + 1] + w[3] * u[b + 2];
                *m = pred - u[a + p];
            }
        }
        if circle && moves[..len].iter().any(|m| m.abs() > 1.0) {
            return true;
        }
        let mut after = before;
        for (k, &rk) in r.iter().enumerate().take(b + 3).skip(a - 2) {
            let mut moved = rk;
            for (p, &m) in moves.iter().enumerate().take(len) {
                let d = k.abs_diff(a + p);
                if d <= 2 {
                    moved += STENCIL[d] * m;
                }
            }
            after += sq(moved) - sq(rk);
        }
        after <= CLEARED * before + slack
    }
}

/// The starts `starts.0 .. starts.1` (in the scratch; at most 64) whose repairs, of up to `M`
/// samples, are not settled by the bound of the longest run against the single sample's energy,
/// as bits from the first: in one loop without branches over the starts.
fn screen<const M: usize>(fourth: &[f64], squares: &[f64], starts: (usize, usize), tol: f64) -> u64 {
    let g = INVERSE_GRAMS[M - 1];
    // Below this energy the slack's margin grows faster than half the energy.
    let settled_above = (128.0 * tol) * (128.0 * tol);
    let mut open = 0u64;
    for s in starts.0..starts.1 {
        let least: f64 = squares[s - REACH..=s + REACH].iter().sum();
        let e: [f64; M] = std::array::from_fn(|i| fourth[s + i]);
        let most: f64 = (0..M)
            .map(|i| e[i] * (0..M).map(|j| g[i][j] * e[j]).sum::<f64>())
            .sum();
        let settled = least > settled_above && most < (1.0 - CLEARED) * least - slack(least, tol);
        open |= u64::from(!settled) << (s - starts.0);
    }
    open
}

/// What rounding can make of an energy `e` of residuals each within `tol` of its value, and of
/// the same energy after a repair, with a wide margin: a millionth of it and 64 times `tol`
/// times its square root.
fn slack(e: f64, tol: f64) -> f64 {
    1e-6 * e + 64.0 * tol * (e.sqrt() + tol)
}

/// Per run length `m` (index `m − 1`), the inverse of the Gram matrix of the `m` fourth
/// differences centred on a run's samples, over the `m + 4` residuals they span: `e G e` with
/// `e` those differences is the squared distance of those residuals to the cubics, the most any
/// move of the run's samples can take from their energy (a move's residuals are orthogonal to
/// the cubics there: its weights in the predictions sum to 0 against every power up to the
/// third).
static INVERSE_GRAMS: LazyLock<[[[f64; MAX_RUN]; MAX_RUN]; MAX_RUN]> =
    LazyLock::new(|| std::array::from_fn(|l| inverse_gram(l + 1)));

/// The inverse of the Gram matrix of `m` consecutive fourth differences (see
/// [`INVERSE_GRAMS`]), in the first `m` rows and columns.
pub(super) fn inverse_gram(m: usize) -> [[f64; MAX_RUN]; MAX_RUN] {
    const FOURTH: [f64; 5] = [1.0, -4.0, 6.0, -4.0, 1.0];
    // Differences i and j overlap at lag |i − j| (< 5).
    let gram = |i: usize, j: usize| -> f64 {
        let lag = i.abs_diff(j);
        (0..5usize.saturating_sub(lag))
            .map(|k| FOURTH[k] * FOURTH[k + lag])
            .sum()
    };
    // Gauss–Jordan on [G | I]; G is positive definite, no pivoting needed.
    let mut a = [[0.0; 2 * MAX_RUN]; MAX_RUN];
    for (i, row) in a.iter_mut().enumerate().take(m) {
        for (j, v) in row.iter_mut().enumerate().take(m) {
            *v = gram(i, j);
        }
        row[m + i] = 1.0;
    }
    for c in 0..m {
        let p = a[c][c];
        a[c].iter_mut().for_each(|v| *v /= p);
        let pivot = a[c];
        for (row, r) in a.iter_mut().enumerate().take(m) {
            if row != c {
                let f = r[c];
                r.iter_mut().zip(&pivot).for_each(|(v, q)| *v -= f * q);
            }
        }
    }
    let mut out = [[0.0; MAX_RUN]; MAX_RUN];
    for i in 0..m {
        out[i][..m].copy_from_slice(&a[i][m..2 * m]);
    }
    out
}
