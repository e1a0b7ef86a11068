//! Confidence intervals for every coefficient by a seeded bootstrap over segments.

use faer::{Col, Mat};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{BootstrapError, LstsqError, SolveError};

use crate::lstsq::{LstsqFit, LstsqSolver};

use crate::system::{Block, LinearSystem};

/// How many consecutive segments are drawn together.
///
/// Segments that share samples (overlapping windows, or orbits found in the same stretch of the
/// record) have correlated errors; drawing them one by one as if independent gives intervals that
/// are too narrow. A moving-block bootstrap draws runs of consecutive segments (in the order of
/// their first sample) instead.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum ResampleBlock {
    /// The moving-block length of Politis and White (2004, with the correction of Patton, Politis
    /// and White 2009) for the correlation that shared samples give: with `m` the mean number of
    /// segments that share a sample of the record (their total length over the length of their
    /// union: 1 for segments that do not overlap, about `k` for windows of `k` periods stepped by
    /// one period), the errors of segments `i` and `i + j` in the order of their first sample
    /// correlate like `1 − |j| / m` (a moving sum of `m` independent terms), and the block that
    /// minimises the error of the bootstrap's variance is
    /// `ℓ = ((m² − 1)² / (6 m²) · n)^(1/3)` for `n` segments (`n^(1/3)` growth, Hall, Horowitz
    /// and Jing 1995), taken at least `m` so that a run spans the correlation: `ceil` of the
    /// larger. Segments that do not overlap are drawn one by one; 248 windows of three periods
    /// give runs of 7.
    ///
    /// The length counts the segments that share samples, not the gaps between their starts: close
    /// returns find orbits of several periods in one passage, a few samples apart, and a length of
    /// one segment over the median gap between starts made runs of half the segments.
    #[default]
    Auto,
    /// A given number `>= 1` of consecutive segments (1: every segment drawn on its own).
    Segments(usize),
}

/// Parameters of [`bootstrap`]; build with [`BootstrapParams::builder`], which validates.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "BootstrapParamsRaw")]
pub struct BootstrapParams {
    resamples: usize,
    level: f64,
    seed: u64,
    block: ResampleBlock,
}

/// The serialised form of [`BootstrapParams`], built through its builder on reading.
#[derive(Debug, Clone, Copy, Deserialize)]
struct BootstrapParamsRaw {
    resamples: usize,
    level: f64,
    seed: u64,
    block: ResampleBlock,
}

impl TryFrom<BootstrapParamsRaw> for BootstrapParams {
    type Error = SolveError;

    fn try_from(raw: BootstrapParamsRaw) -> Result<Self, SolveError> {
        BootstrapParams::builder()
            .resamples(raw.resamples)
            .level(raw.level)
            .seed(raw.seed)
            .block(raw.block)
            .build()
    }
}

/// Builder of [`BootstrapParams`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BootstrapParamsBuilder {
    resamples: usize,
    level: f64,
    seed: u64,
    block: ResampleBlock,
}

impl Default for BootstrapParams {
    fn default() -> Self {
        Self {
            resamples: Self::DEFAULT_RESAMPLES,
            level: Self::DEFAULT_LEVEL,
            seed: 0,
            block: ResampleBlock::Auto,
        }
    }
}

impl BootstrapParams {
    /// The most resamples: each one's coefficients are kept, and a size the memory cannot hold
    /// would abort the process, not fail.
    pub const MAX_RESAMPLES: usize = 1_000_000;

    /// Default number of resamples: the 2.5 % and 97.5 % percentiles then move by about 2 % of the
    /// interval's width from one seed to another (their standard error for a normal law).
    pub const DEFAULT_RESAMPLES: usize = 1000;
    /// Default confidence level, 95 %.
    pub const DEFAULT_LEVEL: f64 = 0.95;

    /// A builder with the defaults: [`DEFAULT_RESAMPLES`](Self::DEFAULT_RESAMPLES),
    /// [`DEFAULT_LEVEL`](Self::DEFAULT_LEVEL), seed 0, [`ResampleBlock::Auto`].
    pub fn builder() -> BootstrapParamsBuilder {
        let d = Self::default();
        BootstrapParamsBuilder {
            resamples: d.resamples,
            level: d.level,
            seed: d.seed,
            block: d.block,
        }
    }

    /// Number of resamples.
    pub fn resamples(&self) -> usize {
        self.resamples
    }

    /// Confidence level of the intervals.
    pub fn level(&self) -> f64 {
        self.level
    }

    /// Seed of the random draws.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// Segments drawn together.
    pub fn block(&self) -> ResampleBlock {
        self.block
    }
}

impl BootstrapParamsBuilder {
    /// Number of resamples `B`.
    pub fn resamples(mut self, resamples: usize) -> Self {
        self.resamples = resamples;
        self
    }

    /// Confidence level in `(0, 1)`.
    pub fn level(mut self, level: f64) -> Self {
        self.level = level;
        self
    }

    /// Seed: the same seed gives the same intervals, whatever the number of threads.
    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// Segments drawn together.
    pub fn block(mut self, block: ResampleBlock) -> Self {
        self.block = block;
        self
    }

    /// Validates: level in `(0, 1)`; at least `max(20, 2 / (1 − level))` resamples, so that each
    /// tail of the interval holds at least one resample, and at most
    /// [`BootstrapParams::MAX_RESAMPLES`]; a
    /// block of at least one segment.
    pub fn build(self) -> Result<BootstrapParams, SolveError> {
        if !(self.level.is_finite() && self.level > 0.0 && self.level < 1.0) {
            return Err(SolveError::InvalidParameter {
                name: "confidence level",
                value: self.level,
                why: "must lie in (0, 1)",
            });
        }
        let needed = (2.0 / (1.0 - self.level)).ceil().max(20.0);
        if (self.resamples as f64) < needed {
            return Err(SolveError::InvalidParameter {
                name: "bootstrap resamples",
                value: self.resamples as f64,
                why: "too few for the confidence level: at least max(20, 2 / (1 - level)) are needed",
            });
        }
        if self.resamples > BootstrapParams::MAX_RESAMPLES {
            return Err(SolveError::InvalidParameter {
                name: "bootstrap resamples",
                value: self.resamples as f64,
                why: "too many: at most 10^6 (the percentiles of 10^4 move by about 0.2 % of the interval; each \
                      resample's coefficients are kept)",
            });
        }
        if self.block == ResampleBlock::Segments(0) {
            return Err(SolveError::InvalidParameter {
                name: "bootstrap block",
                value: 0.0,
                why: "must be at least one segment",
            });
        }
        Ok(BootstrapParams {
            resamples: self.resamples,
            level: self.level,
            seed: self.seed,
            block: self.block,
        })
    }
}

/// A percentile confidence interval of one coefficient.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Interval {
    /// The term's name.
    pub name: String,
    /// The estimate from all segments.
    pub estimate: f64,
    /// Lower end: the `(1 − level) / 2` quantile of the resampled estimates.
    pub lower: f64,
    /// Upper end: the `(1 + level) / 2` quantile.
    pub upper: f64,
    /// Standard deviation of the resampled estimates (a bootstrap standard error).
    pub std_error: f64,
}

impl Interval {
    /// Whether `value` lies in `[lower, upper]`.
    pub fn contains(&self, value: f64) -> bool {
        self.lower <= value && value <= self.upper
    }
}

/// The result of [`bootstrap`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct Bootstrap {
    /// Confidence level.
    pub level: f64,
    /// Resamples drawn.
    pub resamples: usize,
    /// Resamples that did not determine every unknown (left out of the percentiles).
    pub failed: usize,
    /// The seed.
    pub seed: u64,
    /// Consecutive segments drawn together.
    pub block: usize,
    /// One interval per unknown, in column order.
    pub intervals: Vec<Interval>,
}

impl Bootstrap {
    /// The interval of the term `name`.
    pub fn interval(&self, name: &str) -> Option<&Interval> {
        self.intervals.iter().find(|i| i.name == name)
    }
}

/// Largest condition number (of the column-scaled system) for which resamples are solved by
/// their normal equations around the estimate: each resample's correction then carries a relative
/// error of about `condition² · ε ≤ 2e-6`, far below the spread of the resamples.
pub const NORMAL_EQUATIONS_CONDITION: f64 = 1e5;

/// Percentile bootstrap over the segments of an assembled system (either method).
///
/// A resample draws `ceil(n / ℓ)` runs of `ℓ` consecutive segments (ordered by their first
/// sample; `ℓ` from [`ResampleBlock`]) with replacement, stacks their rows, and solves them by
/// least squares; the interval of each coefficient is between the `(1 − level) / 2` and
/// `(1 + level) / 2` quantiles (linear interpolation) of its `B` resampled values. Whole segments'
/// row blocks are resampled because the rows of one segment share its data and are not
/// independent.
///
/// How a resample is solved, in a time that does not grow with the rows of the system:
///
/// - when the whole system's condition number (column-scaled, from `solver`) is at most
///   [`NORMAL_EQUATIONS_CONDITION`], by the normal equations of the correction `δ = x − x̂` to the
///   estimate `x̂`: `(Σ Gₖ) δ = Σ gₖ` over the drawn runs, with `Gₖ = Σ Aₛᵀ Aₛ` and
///   `gₖ = Σ Aₛᵀ (bₛ − Aₛ x̂)` summed once, in parallel, for every run of `ℓ` consecutive
///   segments (Cholesky; `x̂ + δ` is the resample's least-squares solution);
/// - otherwise each segment's block `[Aₛ | bₛ]` is reduced once to its triangular QR factor and a
///   resample stacks the drawn factors and solves with `solver`.
///
/// Resamples run in parallel; resample `r` draws from the ChaCha8 stream `r` of `seed`, so results
/// do not depend on the number of threads. Resamples that do not determine every unknown are left
/// out; more than a tenth of them is an error (`SolveError::Bootstrap(BootstrapError::BootstrapFailed)`).
///
/// Memory: `(n − ℓ + 1) · u (u + 3) / 2` numbers for `u` unknowns (the run sums), or the reduced
/// factors, `n (u + 1)²` numbers, for ill-conditioned systems.
pub fn bootstrap<S: LstsqSolver + ?Sized>(
    system: &LinearSystem,
    solver: &S,
    params: &BootstrapParams,
) -> Result<Bootstrap, SolveError> {
    let fit = system.solve(solver)?;
    bootstrap_fit(system, &fit, solver, params)
}

/// [`bootstrap`] with the system's fit already computed: `fit = system.solve(solver)` (its
/// estimate and condition number are used; a fit of another shape is an error).
pub fn bootstrap_fit<S: LstsqSolver + ?Sized>(
    system: &LinearSystem,
    fit: &LstsqFit,
    solver: &S,
    params: &BootstrapParams,
) -> Result<Bootstrap, SolveError> {
    if fit.rows != system.equations() || fit.solution.len() != system.unknowns() {
        return Err(SolveError::InvalidParameter {
            name: "fit rows",
            value: fit.rows as f64,
            why: "the fit is not one of this system",
        });
    }
    let resampler = if fit.condition <= NORMAL_EQUATIONS_CONDITION {
        Resampler::Normal
    } else {
        Resampler::Stacked
    };
    bootstrap_with(system, solver, params, &fit.solution, resampler)
}

/// Why an identification has no bootstrap intervals ([`bootstrap_or_reason`]).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[non_exhaustive]
pub struct NoIntervals {
    /// The reason, in words (one line).
    pub reason: String,
}

impl std::fmt::Display for NoIntervals {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "no intervals: {}", self.reason)
    }
}

/// [`bootstrap_fit`] for an identification, which never fails for its intervals: the intervals,
/// or why there are none (too few segments for two runs of the block, too many resamples that do
/// not determine every unknown, ...), so that the model and its standard errors are still given.
pub fn bootstrap_or_reason<S: LstsqSolver + ?Sized>(
    system: &LinearSystem,
    fit: &LstsqFit,
    solver: &S,
    params: &BootstrapParams,
) -> Result<Bootstrap, NoIntervals> {
    bootstrap_fit(system, fit, solver, params).map_err(|e| NoIntervals {
        reason: match e {
            SolveError::Bootstrap(BootstrapError::TooFewSegmentsToResample { segments, block, .. }) => {
                let depth = overlap_depth(system);
                format!(
                    "the {segments} segment(s) share each sample {depth:.1}-fold on average (about {:.1} \
                     independent stretches of the record), and a moving-block bootstrap needs at least two \
                     runs of {block} consecutive segments; a longer record gives intervals",
                    segments as f64 / depth
                )
            }
            other => other.to_string(),
        },
    })
}

/// How resamples are solved (see [`bootstrap`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Resampler {
    Normal,
    Stacked,
}

fn bootstrap_with<S: LstsqSolver + ?Sized>(
    system: &LinearSystem,
    solver: &S,
    params: &BootstrapParams,
    estimate: &[f64],
    resampler: Resampler,
) -> Result<Bootstrap, SolveError> {
    let blocks = system.blocks();
    let mut order: Vec<usize> = (0..blocks.len()).collect();
    order.sort_by_key(|&i| blocks[i].segment.start());
    let n = order.len();
    let ell = match params.block {
        ResampleBlock::Segments(l) => l,
        ResampleBlock::Auto => auto_block(system),
    }
    .clamp(1, n.max(1));
    if n < 2 * ell {
        return Err(SolveError::Bootstrap(BootstrapError::TooFewSegmentsToResample {
            segments: n,
            block: ell,
            needed: 2 * ell,
        }));
    }
    let draws = n.div_ceil(ell);
    let draw_starts = |r: usize| {
        let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
        rng.set_stream(r as u64);
        (0..draws).map(move |_| rng.random_range(0..=n - ell))
    };

    let outcomes: Vec<Option<Vec<f64>>> = match resampler {
        Resampler::Normal => {
            let runs = RunMoments::new(system, &order, ell, estimate);
            (0..params.resamples)
                .into_par_iter()
                .map(|r| Ok(runs.solve(draw_starts(r), estimate)))
                .collect::<Result<_, SolveError>>()?
        }
        Resampler::Stacked => {
            let reduced: Vec<Mat<f64>> = crate::lstsq::on_factor_pool(|| {
                order
                    .par_iter()
                    .map(|&i| reduce(system, blocks[i].first_row, blocks[i].rows))
                    .collect()
            });
            let cols = system.unknowns();
            (0..params.resamples)
                .into_par_iter()
                .map(|r| {
                    let picked: Vec<usize> = draw_starts(r).flat_map(|s| s..s + ell).collect();
                    let rows: usize = picked.iter().map(|&i| reduced[i].nrows()).sum();
                    let mut a = Mat::<f64>::zeros(rows, cols);
                    let mut b = Col::<f64>::zeros(rows);
                    let mut at = 0;
                    for &i in &picked {
                        let m = &reduced[i];
                        for rr in 0..m.nrows() {
                            for c in 0..cols {
                                a[(at + rr, c)] = m[(rr, c)];
                            }
                            b[at + rr] = m[(rr, cols)];
                        }
                        at += m.nrows();
                    }
                    match solver.solve(a.as_ref(), b.as_ref()) {
                        Ok(fit) => Ok(Some(fit.solution)),
                        Err(
                            SolveError::Lstsq(LstsqError::RankDeficient { .. })
                            | SolveError::Lstsq(LstsqError::Underdetermined { .. }),
                        ) => Ok(None),
                        Err(e) => Err(e),
                    }
                })
                .collect::<Result<_, SolveError>>()?
        }
    };

    let failed = outcomes.iter().filter(|o| o.is_none()).count();
    let allowed = params.resamples / 10;
    if failed > allowed {
        return Err(SolveError::Bootstrap(BootstrapError::BootstrapFailed {
            failed,
            resamples: params.resamples,
            allowed,
        }));
    }
    let solutions: Vec<Vec<f64>> = outcomes.into_iter().flatten().collect();
    let (lo_q, hi_q) = ((1.0 - params.level) / 2.0, (1.0 + params.level) / 2.0);
    let intervals = system
        .names()
        .iter()
        .enumerate()
        .map(|(c, name)| {
            let mut v: Vec<f64> = solutions.iter().map(|s| s[c]).collect();
            v.sort_by(f64::total_cmp);
            let mean = v.iter().sum::<f64>() / v.len() as f64;
            let var = v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (v.len() - 1).max(1) as f64;
            Interval {
                name: name.clone(),
                estimate: estimate[c],
                lower: quantile(&v, lo_q),
                upper: quantile(&v, hi_q),
                std_error: var.sqrt(),
            }
        })
        .collect();
    Ok(Bootstrap {
        level: params.level,
        resamples: params.resamples,
        failed,
        seed: params.seed,
        block: ell,
        intervals,
    })
}

/// The column-scaled normal equations of every run of `ℓ` consecutive segments, about the
/// estimate: packed upper triangle of `Σ Aₛᵀ Aₛ`, then `Σ Aₛᵀ (bₛ − Aₛ x̂)`, one row of `width`
/// numbers per run start.
struct RunMoments {
    cols: usize,
    width: usize,
    norms: Vec<f64>,
    sums: Vec<f64>,
}

impl RunMoments {
    fn new(system: &LinearSystem, order: &[usize], ell: usize, estimate: &[f64]) -> Self {
        let a = system.matrix();
        let cols = a.ncols();
        let packed = cols * (cols + 1) / 2;
        let width = packed + cols;
        let norms: Vec<f64> = (0..cols)
            .map(|c| {
                let n = a.col(c).iter().map(|v| v * v).sum::<f64>().sqrt();
                if n > 0.0 { n } else { 1.0 }
            })
            .collect();
        let blocks = system.blocks();
        let columns: Vec<&[f64]> = (0..cols).map(|c| system.column(c)).collect();
        let rhs = system.rhs_slice();
        // One segment's moments, added into `out`: its rows scaled into `rows` (row-major), then
        // each entry of the packed Gram matrix as one pass over them.
        let moments = |k: usize, out: &mut [f64], rows: &mut Vec<f64>, resid: &mut Vec<f64>| {
            let block = &blocks[order[k]];
            let (first, len) = (block.first_row, block.rows);
            resid.clear();
            resid.extend_from_slice(&rhs[first..first + len]);
            rows.clear();
            rows.resize(len * cols, 0.0);
            for (c, col) in columns.iter().enumerate() {
                let (col, x, inv) = (&col[first..first + len], estimate[c], 1.0 / norms[c]);
                for (i, &v) in col.iter().enumerate() {
                    resid[i] -= v * x;
                    rows[i * cols + c] = v * inv;
                }
            }
            for (row, &r) in rows.chunks_exact(cols).zip(resid.iter()) {
                let mut at = 0;
                for c in 0..cols {
                    let rc = row[c];
                    let tail = &row[c..];
                    out[at..at + tail.len()]
                        .iter_mut()
                        .zip(tail)
                        .for_each(|(o, &v)| *o += rc * v);
                    at += tail.len();
                    out[packed + c] += rc * r;
                }
            }
        };
        let n = order.len();
        let starts = n + 1 - ell;
        let mut sums = vec![0.0; starts * width];
        // Chunks of ℓ run starts: the first run summed afresh, the others by sliding (adding the
        // segment that enters, subtracting the one that leaves), so that rounding cannot build up
        // over more than 2ℓ terms. A chunk computes the moments of its 2ℓ − 1 segments itself, so
        // most segments' moments are computed twice: the price of not holding n of them at once.
        sums.par_chunks_mut(ell * width)
            .enumerate()
            .for_each(|(chunk, out)| {
                let first = chunk * ell;
                let last = (first + out.len() / width - 1 + ell).min(n); // segments [first, last)
                let mut seg = vec![0.0; (last - first) * width];
                let (mut rows, mut resid) = (Vec::new(), Vec::new());
                for (k, m) in (first..last).zip(seg.chunks_mut(width)) {
                    moments(k, m, &mut rows, &mut resid);
                }
                let (head, rest) = out.split_at_mut(width);
                for m in seg.chunks(width).take(ell) {
                    head.iter_mut().zip(m).for_each(|(h, v)| *h += v);
                }
                let mut previous: &[f64] = head;
                for (j, run) in rest.chunks_mut(width).enumerate() {
                    let (leave, enter) = (
                        &seg[j * width..(j + 1) * width],
                        &seg[(j + ell) * width..(j + ell + 1) * width],
                    );
                    for (((o, p), e), l) in run.iter_mut().zip(previous).zip(enter).zip(leave) {
                        *o = p + e - l;
                    }
                    previous = run;
                }
            });
        Self {
            cols,
            width,
            norms,
            sums,
        }
    }

    /// The resample of the runs starting at `starts`: `None` if its normal matrix is not safely
    /// positive definite (a pivot below 1e-12 of the largest diagonal entry).
    fn solve(&self, starts: impl Iterator<Item = usize>, estimate: &[f64]) -> Option<Vec<f64>> {
        let (cols, width) = (self.cols, self.width);
        let mut total = vec![0.0; width];
        for s in starts {
            let run = &self.sums[s * width..(s + 1) * width];
            total.iter_mut().zip(run).for_each(|(t, v)| *t += v);
        }
        // Unpack into a full matrix and factor G = L Lᵀ in place (lower triangle).
        let mut g = vec![0.0; cols * cols];
        let mut at = 0;
        for c in 0..cols {
            for d in c..cols {
                g[d * cols + c] = total[at];
                at += 1;
            }
        }
        let largest = (0..cols).map(|c| g[c * cols + c]).fold(0.0_f64, f64::max);
        for j in 0..cols {
            let mut pivot = g[j * cols + j];
            for k in 0..j {
                pivot -= g[j * cols + k] * g[j * cols + k];
            }
            if pivot.is_nan() || pivot <= 1e-12 * largest {
                return None;
            }
            let pivot = pivot.sqrt();
            g[j * cols + j] = pivot;
            for i in j + 1..cols {
                let mut v = g[i * cols + j];
                for k in 0..j {
                    v -= g[i * cols + k] * g[j * cols + k];
                }
                g[i * cols + j] = v / pivot;
            }
        }
        // L y = g, then Lᵀ δ = y.
        let mut y: Vec<f64> = total[width - cols..].to_vec();
        for i in 0..cols {
            for k in 0..i {
                y[i] -= g[i * cols + k] * y[k];
            }
            y[i] /= g[i * cols + i];
        }
        for i in (0..cols).rev() {
            for k in i + 1..cols {
                y[i] -= g[k * cols + i] * y[k];
            }
            y[i] /= g[i * cols + i];
        }
        Some(
            estimate
                .iter()
                .zip(&y)
                .zip(&self.norms)
                .map(|((x, d), s)| x + d / s)
                .collect(),
        )
    }
}

/// The `q` quantile of sorted `v` by linear interpolation between order statistics.
fn quantile(v: &[f64], q: f64) -> f64 {
    let pos = q * (v.len() - 1) as f64;
    let lo = pos.floor() as usize;
    let hi = (lo + 1).min(v.len() - 1);
    let frac = pos - lo as f64;
    v[lo] + frac * (v[hi] - v[lo])
}

/// The mean number of segments that share a sample: the segments' total length over the length
/// of their union (1 for none, or for segments that do not overlap).
fn overlap_depth(system: &LinearSystem) -> f64 {
    let mut spans: Vec<(usize, usize)> = system.blocks().iter().map(Block::span).collect();
    spans.sort_unstable();
    let total: usize = spans.iter().map(|(a, b)| b - a).sum();
    let (mut union, mut open) = (0, None::<(usize, usize)>);
    for &(a, b) in &spans {
        open = match open {
            Some((s, e)) if a < e => Some((s, e.max(b))),
            Some((s, e)) => {
                union += e - s;
                Some((a, b))
            }
            None => Some((a, b)),
        };
    }
    if let Some((s, e)) = open {
        union += e - s;
    }
    if union == 0 {
        1.0
    } else {
        (total as f64 / union as f64).max(1.0)
    }
}

/// The block of [`ResampleBlock::Auto`] for `n` segments sharing samples `depth`-fold: the larger
/// of `ceil(depth)` and `ceil(((depth² − 1)² / (6 depth²) · n)^(1/3))`, at least 1.
fn politis_white_block(n: usize, depth: f64) -> usize {
    let m2 = depth * depth;
    let cube = (m2 - 1.0) * (m2 - 1.0) / (6.0 * m2) * n as f64;
    // A little below each whole number counts as it, so that 27^(1/3) or a depth of 3 are 3.
    let up = |v: f64| (v - 1e-9).ceil().max(1.0) as usize;
    up(depth).max(up(cube.cbrt()))
}

/// [`ResampleBlock::Auto`]'s block for `system`'s segments.
fn auto_block(system: &LinearSystem) -> usize {
    politis_white_block(system.blocks().len(), overlap_depth(system))
}

/// The block `[A_s | b_s]` of `rows` rows from `first`, reduced to its R factor when it has more
/// than `unknowns + 1` rows.
fn reduce(system: &LinearSystem, first: usize, rows: usize) -> Mat<f64> {
    let (a, b) = (system.matrix(), system.rhs());
    let cols = a.ncols() + 1;
    crate::lstsq::triangular_factor(Mat::from_fn(rows, cols, |i, j| {
        if j + 1 < cols {
            a[(first + i, j)]
        } else {
            b[first + i]
        }
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn params_are_validated() {
        assert!(BootstrapParams::builder().level(1.0).build().is_err());
        assert!(BootstrapParams::builder().level(f64::NAN).build().is_err());
        assert!(BootstrapParams::builder().resamples(19).build().is_err());
        // 99 % needs 200 resamples.
        assert!(
            BootstrapParams::builder()
                .level(0.99)
                .resamples(199)
                .build()
                .is_err()
        );
        assert!(
            BootstrapParams::builder()
                .level(0.99)
                .resamples(200)
                .build()
                .is_ok()
        );
        assert!(
            BootstrapParams::builder()
                .block(ResampleBlock::Segments(0))
                .build()
                .is_err()
        );
        let d = BootstrapParams::default();
        assert_eq!((d.resamples(), d.level(), d.seed()), (1000, 0.95, 0));
    }

    #[test]
    fn quantiles_interpolate() {
        let v = [0.0, 1.0, 2.0, 3.0, 4.0];
        assert_eq!(quantile(&v, 0.0), 0.0);
        assert_eq!(quantile(&v, 1.0), 4.0);
        assert!((quantile(&v, 0.625) - 2.5).abs() < 1e-15);
        assert_eq!(quantile(&[7.0], 0.3), 7.0);
    }

    /// A synthetic system of `n` segments of 5 rows and 3 unknowns, in shuffled order.
    fn synthetic(n: usize, scale: f64) -> LinearSystem {
        use crate::system::Block;
        use circle_signal::Segment;
        let rows = 5 * n;
        let noise = |i: usize| ((i * 7919 + 13) % 1009) as f64 / 1009.0 - 0.5;
        let matrix = Mat::from_fn(rows, 3, |i, j| {
            let t = i as f64 * 0.37;
            [1.0, scale * t.sin(), (2.0 * t).cos() + 0.3 * t.sin()][j]
        });
        let rhs = Col::from_fn(rows, |i| {
            0.5 * matrix[(i, 0)] - 2.0 / scale * matrix[(i, 1)] + matrix[(i, 2)] + 0.1 * noise(i)
        });
        let blocks = (0..n)
            .map(|k| {
                let s = (k * 17) % n; // segments listed out of time order
                Block {
                    segment: Segment::new(
                        10 * s,
                        1,
                        &circle_signal::SampleClock::nondimensional(25).unwrap(),
                        0.0,
                        usize::MAX,
                    )
                    .unwrap(),
                    first_row: 5 * k,
                    rows: 5,
                    harmonics: 2,
                    winding: 0,
                    rotation_rate: 0.0,
                    group: None,
                }
            })
            .collect();
        let names = ["a", "b", "c"].map(String::from).to_vec();
        LinearSystem::from_parts(matrix, rhs, names, blocks)
    }

    /// The normal-equation resamples are the stacked least-squares resamples, draw for draw.
    #[test]
    fn normal_equation_resamples_match_stacked_least_squares() {
        for (n, scale) in [(101, 1.0), (64, 1e4)] {
            let system = synthetic(n, scale);
            let solver = crate::QrSolver::default();
            let estimate = system.solve(&solver).unwrap().solution;
            for block in [
                ResampleBlock::Auto,
                ResampleBlock::Segments(1),
                ResampleBlock::Segments(7),
            ] {
                let params = BootstrapParams::builder()
                    .resamples(100)
                    .seed(7)
                    .block(block)
                    .build()
                    .unwrap();
                let fast = bootstrap_with(&system, &solver, &params, &estimate, Resampler::Normal).unwrap();
                let slow = bootstrap_with(&system, &solver, &params, &estimate, Resampler::Stacked).unwrap();
                assert_eq!((fast.block, fast.failed), (slow.block, slow.failed));
                for (f, s) in fast.intervals.iter().zip(&slow.intervals) {
                    let width = s.upper - s.lower;
                    assert!(width > 0.0);
                    for (a, b) in [(f.lower, s.lower), (f.upper, s.upper), (f.std_error, s.std_error)] {
                        assert!((a - b).abs() < 1e-9 * width, "{n} {block:?} {f:?} {s:?}");
                    }
                }
            }
        }
    }

    /// One segment, or fewer than two runs of the block, cannot be resampled: an error, not an
    /// interval of zero width around the estimate.
    #[test]
    fn too_few_segments_are_refused() {
        let solver = crate::QrSolver::default();
        for (n, block, ok) in [(1, 1, false), (2, 1, true), (5, 3, false), (6, 3, true)] {
            let system = synthetic(n, 1.0);
            let estimate = system.solve(&solver).unwrap().solution;
            let params = BootstrapParams::builder()
                .resamples(50)
                .block(ResampleBlock::Segments(block))
                .build()
                .unwrap();
            let got = bootstrap_with(&system, &solver, &params, &estimate, Resampler::Normal);
            match got {
                Ok(b) => assert!(ok, "{n} segments in runs of {block}: {b:?}"),
                Err(SolveError::Bootstrap(BootstrapError::TooFewSegmentsToResample {
                    segments,
                    block: l,
                    needed,
                })) => {
                    assert!(!ok && segments == n && l == block && needed == 2 * block)
                }
                Err(e) => panic!("{e}"),
            }
        }
    }

    /// A system of segments of `(start, periods)` at 25 samples per period (2 rows each).
    fn spans(segments: &[(usize, usize)]) -> LinearSystem {
        use crate::system::Block;
        use circle_signal::{SampleClock, Segment};
        let clock = SampleClock::nondimensional(25).unwrap();
        let rows = 2 * segments.len();
        let blocks = segments
            .iter()
            .enumerate()
            .map(|(i, &(start, k))| Block {
                segment: Segment::new(start, k, &clock, 0.0, usize::MAX).unwrap(),
                first_row: 2 * i,
                rows: 2,
                harmonics: 0,
                winding: 0,
                rotation_rate: 0.0,
                group: None,
            })
            .collect();
        let matrix = Mat::from_fn(rows, 1, |i, _| 1.0 + i as f64);
        let rhs = Col::from_fn(rows, |i| i as f64);
        LinearSystem::from_parts(matrix, rhs, vec!["a".into()], blocks)
    }

    /// Too few segments for two runs is a reason for no intervals, not a failure.
    #[test]
    fn too_few_segments_give_a_reason() {
        let solver = crate::QrSolver::default();
        let params = |block| {
            BootstrapParams::builder()
                .resamples(50)
                .block(block)
                .build()
                .unwrap()
        };
        let system = synthetic(5, 1.0);
        let fit = system.solve(&solver).unwrap();
        let why =
            bootstrap_or_reason(&system, &fit, &solver, &params(ResampleBlock::Segments(3))).unwrap_err();
        assert!(why.reason.contains("two runs of 3"), "{why}");
        assert!(
            why.to_string().starts_with("no intervals: the 5 segment(s)"),
            "{why}"
        );
        let ok = bootstrap_or_reason(&system, &fit, &solver, &params(ResampleBlock::Segments(1))).unwrap();
        assert_eq!(ok.block, 1);
    }

    #[test]
    fn auto_block_grows_with_the_cube_root_of_the_segments() {
        // 25-sample segments 10 samples apart: depth 25n / (10n + 15); ((m²−1)²/(6m²) n)^(1/3)
        // is 4.14 for 101 segments (depth 2.46), 2.57 for 27 and 2.61 for 28 (depth 2.37).
        assert_eq!(auto_block(&synthetic(101, 1.0)), 5);
        assert_eq!(auto_block(&synthetic(27, 1.0)), 3);
        assert_eq!(auto_block(&synthetic(28, 1.0)), 3);
        assert!((overlap_depth(&synthetic(101, 1.0)) - 2525.0 / 1025.0).abs() < 1e-12);
        // Windows of three periods stepped by one: depth 3n / (n + 2); 248 of them give 7.
        let windows: Vec<(usize, usize)> = (0..248).map(|s| (25 * s, 3)).collect();
        assert_eq!(auto_block(&spans(&windows)), 7);
        // Segments that share no sample are drawn one by one, however many.
        let apart: Vec<(usize, usize)> = (0..1000).map(|s| (30 * s, 1)).collect();
        assert_eq!(overlap_depth(&spans(&apart)), 1.0);
        assert_eq!(auto_block(&spans(&apart)), 1);
        // The block grows like n^(1/3) at a fixed depth: 8 times the windows, twice the block.
        let more: Vec<(usize, usize)> = (0..8 * 248).map(|s| (25 * s, 3)).collect();
        assert_eq!(auto_block(&spans(&more)), 14);
    }

    /// Close returns find orbits of several periods in one passage, a few samples apart: 20
    /// passages 500 samples apart, each with orbits of 1 to 6 periods one sample apart. The
    /// median gap between starts is one sample, and one median segment over it made runs of 100
    /// of the 120 segments, which cannot be resampled. Here the segments share a sample 3.4-fold
    /// (10500 samples over a union of 3100): runs of 6.
    #[test]
    fn orbits_found_in_one_passage_do_not_make_runs_of_half_the_record() {
        let passages: Vec<(usize, usize)> = (0..20)
            .flat_map(|p| (1..=6).map(move |k| (500 * p + k - 1, k)))
            .collect();
        let system = spans(&passages);
        assert!((overlap_depth(&system) - 10500.0 / 3100.0).abs() < 1e-12);
        assert_eq!(auto_block(&system), 6);
    }
}
