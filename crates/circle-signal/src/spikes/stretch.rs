//! The sweep's statistics and the local scale's levels over a stretch of the record, each
//! computed once and patched where a repair changes the record.
//!
//! Why: every sample whose statistic exceeds its block threshold needs the local scales around it
//! (see "Scale and threshold" on [`find_spikes`](super::find_spikes)), and computing them from the
//! residuals each time takes some ten thousand operations: about 200 residuals, three statistics
//! at each position, 16 partners per level, three selections. Where the smooth motion's own
//! residual stands out of its block (the paper's noise-free chaotic record at 25 samples per
//! period: a fifth of its samples) that was `3.2 · 10¹⁰` instructions, seconds, per 10⁶ samples
//! (`docs/spikes.md`). Here each residual and
//! statistic is computed once per stretch of a few thousand samples, and each level once, where
//! a window asks for it (with a few hundred positions ahead); the partners' maxima by a sliding
//! maximum; and a lower bound of the local scale, the `r`-th largest of the
//! maxima of the blocks of [`LEVEL_BLOCK`] levels inside the window (`r` of those blocks hold `r`
//! distinct levels at least that large), settles most of those samples without a selection.

use super::{Geometry, LOCAL_PARTNERS, MAX_RUN, SUM_GAINS, centred_residuals, gain, predict};

/// Levels per block of the blocks' maxima.
pub(super) const LEVEL_BLOCK: usize = 8;

/// Positions a stretch spans past the ones asked for (the sweep moves forward).
const AHEAD: usize = 4096;

/// Positions past the ones asked for whose levels are computed with them (the sweep moves
/// forward).
const LEVELS_AHEAD: usize = 256;

/// Positions a stretch starts before the ones asked for: the sweep steps back to two samples
/// before a repair, and a local window reaches about fifty positions behind its outlier.
const BEHIND: usize = 128;

// The partners' maxima are taken by doubling: the partners on a side are a power of two.
const _: () = assert!(LOCAL_PARTNERS.is_power_of_two());

/// The statistics of positions `lo .. hi` (those of [`Stretch::stats`]) and, once asked for, the
/// levels of the local scale and their blocks' maxima where the statistics reach every partner.
pub(super) struct Stretch {
    n: usize,
    max_run: usize,
    /// The nearest partner of a level, in positions: `2 max_run + 3`.
    gap: usize,
    /// How far a level's partners reach: `gap + LOCAL_PARTNERS − 1`.
    margin: usize,
    lo: usize,
    hi: usize,
    /// The last position a stretch need reach for the current sweep (exclusive).
    horizon: usize,
    stats: Vec<[f64; MAX_RUN]>,
    /// The positions `from .. to` whose levels (and the maxima of the blocks in them) are
    /// computed: inside the level range, every block of [`LEVEL_BLOCK`] positions they touch
    /// whole (as far as the level range goes). Empty when none are.
    computed: (usize, usize),
    /// Per position from `lo` (valid in [`level_range`](Self::level_range)).
    levels: Vec<[f64; MAX_RUN]>,
    /// Per block of [`LEVEL_BLOCK`] positions from `lo / LEVEL_BLOCK`: the largest level of the
    /// block's positions in the level range.
    maxima: Vec<[f64; MAX_RUN]>,
    /// Scratch: residuals, the statistics padded with the partners' reach, and their largest
    /// over `LOCAL_PARTNERS` consecutive positions.
    residuals: Vec<f64>,
    padded: Vec<[f64; MAX_RUN]>,
    partners: Vec<[f64; MAX_RUN]>,
}

impl Stretch {
    pub(super) fn new(n: usize, max_run: usize) -> Self {
        let gap = 2 * max_run + 3;
        Self {
            n,
            max_run,
            gap,
            margin: gap + LOCAL_PARTNERS - 1,
            lo: 0,
            hi: 0,
            horizon: n,
            stats: Vec::new(),
            computed: (0, 0),
            levels: Vec::new(),
            maxima: Vec::new(),
            residuals: Vec::new(),
            padded: Vec::new(),
            partners: Vec::new(),
        }
    }

    /// The positions the current sweep can ask for end before `horizon`: a stretch goes no
    /// further (a sweep around a few spikes would otherwise compute thousands of positions for
    /// each).
    pub(super) fn set_horizon(&mut self, horizon: usize) {
        self.horizon = horizon.min(self.n);
    }

    /// The positions whose levels are held: all of the stretch's whose partners it holds.
    fn level_range(&self) -> (usize, usize) {
        let lo = if self.lo == 0 { 0 } else { self.lo + self.margin };
        let hi = if self.hi == self.n {
            self.n
        } else {
            self.hi.saturating_sub(self.margin)
        };
        (lo, hi.max(lo))
    }

    /// The statistics of position `p` (see [`statistics`]).
    #[inline]
    pub(super) fn stats<G: Geometry>(&mut self, x: &[f64], p: usize) -> [f64; MAX_RUN] {
        if !(self.lo..self.hi).contains(&p) {
            self.refill::<G>(x, p, p);
        }
        self.stats[p - self.lo]
    }

    /// The first position held and the statistics of the positions held from it.
    pub(super) fn held(&self) -> (usize, &[[f64; MAX_RUN]]) {
        (self.lo, &self.stats)
    }

    /// Makes the levels of positions `a ..= b` (and their blocks' maxima) available: computed
    /// where they are asked for, with [`LEVELS_AHEAD`] positions more (a sweep asks for the
    /// windows of samples here and there; computing the whole stretch's levels at the first
    /// such sample cost a double pendulum's search an eighth of its time).
    pub(super) fn ensure_levels<G: Geometry>(&mut self, x: &[f64], a: usize, b: usize) {
        let (lo, hi) = self.level_range();
        if a < lo || b >= hi {
            self.refill::<G>(x, a, b);
        }
        let (lo, hi) = self.level_range();
        let (from, to) = self.computed;
        if from <= a && b < to {
            return;
        }
        // Whole blocks, within the level range.
        let down = |p: usize| (p / LEVEL_BLOCK * LEVEL_BLOCK).max(lo);
        let up = |p: usize| p.div_ceil(LEVEL_BLOCK).saturating_mul(LEVEL_BLOCK).min(hi);
        let (want_from, want_to) = (down(a), up(b + 1 + LEVELS_AHEAD));
        if from < to && want_from <= to && from <= want_to {
            // Next to the levels computed: the missing parts.
            if want_from < from {
                self.compute_levels(want_from, from);
            }
            if to < want_to {
                self.compute_levels(to, want_to);
            }
            self.computed = (from.min(want_from), to.max(want_to));
        } else {
            self.compute_levels(want_from, want_to);
            self.computed = (want_from, want_to);
        }
    }

    /// Whether the levels of positions `a ..= b` are held.
    pub(super) fn holds_levels(&self, a: usize, b: usize) -> bool {
        let (from, to) = self.computed;
        from <= a && b < to
    }

    /// The levels of positions `from .. to` (made available by
    /// [`ensure_levels`](Self::ensure_levels); none when `from .. to` is empty, wherever it is).
    #[inline]
    pub(super) fn levels(&self, (from, to): (usize, usize)) -> &[[f64; MAX_RUN]] {
        if from < to {
            &self.levels[from - self.lo..to - self.lo]
        } else {
            &[]
        }
    }

    /// Whether at least `rank` of the blocks `left.0 .. left.1` and `right.0 .. right.1` have a
    /// largest level of width `m` that `holds`: then so does the `rank`-th largest level of any
    /// positions that include the blocks' (for `holds` true of every level above one that holds),
    /// since the blocks hold `rank` distinct levels at least as large.
    pub(super) fn blocks_hold(
        &self,
        left: (usize, usize),
        right: (usize, usize),
        m: usize,
        rank: usize,
        holds: impl Fn(f64) -> bool,
    ) -> bool {
        let first = self.lo / LEVEL_BLOCK;
        let count: usize = [left, right]
            .into_iter()
            .filter(|&(a, b)| a < b)
            .map(|(a, b)| {
                self.maxima[a - first..b - first]
                    .iter()
                    .filter(|most| holds(most[m - 1]))
                    .count()
            })
            .sum();
        count >= rank
    }

    /// A new stretch holding at least positions `a ..= b` with their levels' partners.
    fn refill<G: Geometry>(&mut self, x: &[f64], a: usize, b: usize) {
        let n = self.n;
        debug_assert!(a <= b && b < n, "positions {a} ..= {b} of {n}");
        let lo = a.saturating_sub(BEHIND + self.margin) / LEVEL_BLOCK * LEVEL_BLOCK;
        let ahead = (lo + AHEAD).min(self.horizon.max(b + 1));
        let hi = (b + 1 + self.margin).max(ahead).min(n);
        self.lo = lo;
        self.hi = hi;
        // The residuals the statistics reach: up to MAX_RUN − 1 positions past the last.
        residuals::<G>(x, lo, (hi + MAX_RUN - 1).min(n), &mut self.residuals);
        self.stats.clear();
        // Inside the record (`2 ≤ p`, `p + MAX_RUN + 2 ≤ n`) every sum is there: those positions
        // in one loop over the residuals without a test per position (most of a stretch).
        let inside = (lo.max(2), (n + 1).saturating_sub(MAX_RUN + 2).min(hi));
        if inside.0 < inside.1 {
            let (max_run, residuals) = (self.max_run, &self.residuals);
            self.stats
                .extend((lo..inside.0).map(|p| statistics(residuals, lo, p, n, max_run)));
            let r = &residuals[inside.0 - lo..inside.1 - lo + MAX_RUN - 1];
            self.stats
                .extend(r.windows(MAX_RUN).map(|w| inside_sums(w, max_run)));
            self.stats
                .extend((inside.1..hi).map(|p| statistics(residuals, lo, p, n, max_run)));
        } else {
            self.stats
                .extend((lo..hi).map(|p| statistics(&self.residuals, lo, p, n, self.max_run)));
        }
        self.computed = (0, 0);
    }

    /// Samples `a ..= b` of `x` were changed: the statistics and levels they reach are
    /// computed again.
    pub(super) fn patch<G: Geometry>(&mut self, x: &[f64], a: usize, b: usize) {
        let n = self.n;
        // The residuals a change reaches: two samples on each side inside the record, and the
        // first or last two from up to four samples in; a statistic holds up to max_run of them.
        let from = if a <= 4 { 0 } else { a - 2 - (self.max_run - 1) };
        let to = if b + 5 >= n { n - 1 } else { b + 2 };
        let (from, to) = (from.max(self.lo), to.min(self.hi.saturating_sub(1)));
        if from > to {
            return;
        }
        residuals::<G>(x, from, (to + MAX_RUN).min(n), &mut self.residuals);
        for p in from..=to {
            self.stats[p - self.lo] = statistics(&self.residuals, from, p, n, self.max_run);
        }
        // The levels computed that these statistics reach (the computed range holds whole
        // blocks, so the blocks' maxima read only levels computed).
        let (lo, hi) = self.computed;
        let (pa, pb) = (
            from.saturating_sub(self.margin).max(lo),
            (to + 1 + self.margin).min(hi),
        );
        if pa < pb {
            self.compute_levels(pa, pb);
        }
    }

    /// The levels of positions `pa .. pb` (inside the level range) and the maxima of the blocks
    /// they touch: the statistic of width `m`, counted at most as large as the largest of its
    /// partners `gap .. gap + LOCAL_PARTNERS` positions away on either side (positions whose
    /// statistic the local scale does not take count as 0: the first two, and those whose sum
    /// reaches past the last centred residual).
    fn compute_levels(&mut self, pa: usize, pb: usize) {
        let (n, margin, gap) = (self.n, self.margin, self.gap);
        if self.levels.len() != self.stats.len() {
            self.levels.clear();
            self.levels.resize(self.stats.len(), [0.0; MAX_RUN]);
        }
        // Positions pa − margin .. pb + margin: the statistics where the local scale takes them
        // (positions 2 ..= n − 2 − m for width m) and the stretch holds them, 0 elsewhere.
        let len = pb - pa + 2 * margin;
        self.padded.clear();
        self.padded.resize(len, [0.0; MAX_RUN]);
        let first = 2.max(self.lo).max(pa.saturating_sub(margin));
        let end = (n - 2).min(self.hi).min(pb + margin);
        if first < end {
            self.padded[first + margin - pa..end + margin - pa]
                .copy_from_slice(&self.stats[first - self.lo..end - self.lo]);
            for p in first.max(n - 2 - self.max_run)..end {
                for (m, v) in self.padded[p + margin - pa].iter_mut().enumerate() {
                    if p + m + 1 > n - 2 {
                        *v = 0.0;
                    }
                }
            }
        }
        // The largest of each LOCAL_PARTNERS consecutive ones, by doubling. A statistic that is
        // not a number (a record whose differences overflow) counts as 0 there, as `f64::max`
        // from 0 leaves it out.
        self.partners.clear();
        self.partners.extend(
            self.padded
                .iter()
                .map(|v| v.map(|s| if s >= 0.0 { s } else { 0.0 })),
        );
        let mut width = 1;
        while width < LOCAL_PARTNERS {
            for k in 0..len - width {
                self.partners[k] = larger(self.partners[k], self.partners[k + width]);
            }
            width *= 2;
        }
        let levels = &mut self.levels[pa - self.lo..pb - self.lo];
        let own = &self.padded[margin..];
        let (left, right) = (&self.partners[..], &self.partners[margin + gap..]);
        for (((level, own), left), right) in levels.iter_mut().zip(own).zip(left).zip(right) {
            let partner = larger(*left, *right);
            // The smaller of the two, the partner's where the statistic is not a number (as
            // `f64::min` has it).
            *level = std::array::from_fn(|m| if own[m] < partner[m] { own[m] } else { partner[m] });
        }
        let (lo, hi) = self.level_range();
        let first_block = self.lo / LEVEL_BLOCK;
        let blocks = self.hi.div_ceil(LEVEL_BLOCK) - first_block;
        if self.maxima.len() != blocks {
            self.maxima.clear();
            self.maxima.resize(blocks, [0.0; MAX_RUN]);
        }
        for block in pa / LEVEL_BLOCK..pb.div_ceil(LEVEL_BLOCK) {
            let (from, to) = ((block * LEVEL_BLOCK).max(lo), ((block + 1) * LEVEL_BLOCK).min(hi));
            let mut most = [0.0_f64; MAX_RUN];
            for level in &self.levels[from - self.lo..to - self.lo] {
                most = larger(most, *level);
            }
            self.maxima[block - first_block] = most;
        }
    }
}

/// The larger of each pair, of numbers (without the cost of `f64::max`'s care for what is not
/// one).
#[inline]
fn larger(a: [f64; MAX_RUN], b: [f64; MAX_RUN]) -> [f64; MAX_RUN] {
    std::array::from_fn(|m| if b[m] > a[m] { b[m] } else { a[m] })
}

/// The residuals of samples `from .. to` of `x` (one-sided at its ends), into `out`.
fn residuals<G: Geometry>(x: &[f64], from: usize, to: usize, out: &mut Vec<f64>) {
    let n = x.len();
    let (inside_from, inside_to) = (from.clamp(2, n - 2), to.clamp(2, n - 2));
    out.clear();
    out.extend((from..inside_from.min(to)).map(|j| predict::<G>(x, j).0));
    centred_residuals::<G>(x, inside_from, inside_to, out);
    out.extend((inside_to.max(from)..to).map(|j| predict::<G>(x, j).0));
}

/// The statistics of a position inside the record (see [`statistics`]) from the `MAX_RUN`
/// residuals from its own: every sum is there, the same sums without the tests, each width's
/// division one lane of a vector's.
#[inline(always)]
fn inside_sums(r: &[f64], max_run: usize) -> [f64; MAX_RUN] {
    let &[r0, r1, r2, r3] = r else {
        unreachable!("MAX_RUN residuals");
    };
    let (s1, s2) = (r0, r0 + r1);
    let s3 = s2 + r2;
    let s4 = s3 + r3;
    let sums = [s1.abs(), s2.abs(), s3.abs(), s4.abs()];
    std::array::from_fn(|m| if m < max_run { sums[m] / SUM_GAINS[m] } else { 0.0 })
}

/// The statistics of sample `p` by width `m` (index `m − 1`) from the residuals of positions
/// `first ..` of a record of `n` samples: its weighted residual (`m = 1`), and inside the record
/// the sums of the centred residuals of `p ..= p + m − 1` over their noise gains for white noise
/// (`m` up to `max_run`; 0 where the record ends), which a run of `m` samples from `p` makes
/// about as large as a single spike of its size makes its own residual.
#[inline]
fn statistics(residuals: &[f64], first: usize, p: usize, n: usize, max_run: usize) -> [f64; MAX_RUN] {
    if p >= 2 && p + MAX_RUN + 2 <= n {
        return inside_sums(&residuals[p - first..p - first + MAX_RUN], max_run);
    }
    let r = |j: usize| residuals[j - first];
    let mut out = [0.0; MAX_RUN];
    out[0] = r(p).abs() / gain(n, p);
    if p < 2 {
        return out;
    }
    let mut sum = 0.0;
    for m in 1..=max_run {
        let j = p + m - 1;
        if j + 3 > n {
            break;
        }
        sum += r(j);
        if m >= 2 {
            out[m - 1] = sum.abs() / SUM_GAINS[m - 1];
        }
    }
    out
}
