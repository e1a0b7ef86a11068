//! Confidence intervals for every coefficient by a seeded bootstrap over segments.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::qr::no_pivoting::factor;
use faer::{Col, Mat, Par};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::{LinearSystem, LstsqSolver, SolveError};

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
    /// As many consecutive segments as cover, on average, one segment's length:
    /// `ceil(median length / median gap between consecutive starts)`, at least 1 (3 for the
    /// default windows of three periods stepped by one).
    #[default]
    Auto,
    /// A given number `>= 1` of consecutive segments (1: every segment drawn on its own).
    Segments(usize),
}

/// Parameters of [`bootstrap`]; build with [`BootstrapParams::builder`], which validates.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BootstrapParams {
    resamples: usize,
    level: f64,
    seed: u64,
    block: ResampleBlock,
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
    /// tail of the interval holds at least one resample; a block of at least one segment.
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

/// Percentile bootstrap over the segments of an assembled system (either method).
///
/// A resample draws `ceil(n / ℓ)` runs of `ℓ` consecutive segments (ordered by their first
/// sample; `ℓ` from [`ResampleBlock`]) with replacement, stacks their rows, and solves with
/// `solver`; the interval of each coefficient is between the `(1 − level) / 2` and
/// `(1 + level) / 2` quantiles (linear interpolation) of its `B` resampled values. Whole segments'
/// row blocks are resampled because the rows of one segment share its data and are not
/// independent.
///
/// Each segment's block `[A_s | b_s]` is reduced once to its triangular QR factor (at most
/// `unknowns + 1` rows, the same least-squares problem since `Q` is orthogonal), so that a
/// resample stacks small factors instead of every row. Resamples run in parallel; resample `r`
/// draws from the ChaCha8 stream `r` of `seed`, so results do not depend on the number of threads.
///
/// Resamples that do not determine every unknown are left out; more than a tenth of them is an
/// error ([`SolveError::BootstrapFailed`]).
pub fn bootstrap<S: LstsqSolver + ?Sized>(
    system: &LinearSystem,
    solver: &S,
    params: &BootstrapParams,
) -> Result<Bootstrap, SolveError> {
    let estimate = system.solve(solver)?.solution;
    let blocks = system.blocks();
    let mut order: Vec<usize> = (0..blocks.len()).collect();
    order.sort_by_key(|&i| blocks[i].segment.start);
    let reduced: Vec<Mat<f64>> = order
        .par_iter()
        .map(|&i| reduce(system, blocks[i].first_row, blocks[i].rows()))
        .collect();
    let n = reduced.len();
    let ell = match params.block {
        ResampleBlock::Segments(l) => l,
        ResampleBlock::Auto => auto_block(system),
    }
    .clamp(1, n.max(1));
    let draws = n.div_ceil(ell);
    let cols = system.unknowns();

    let outcomes: Vec<Option<Vec<f64>>> = (0..params.resamples)
        .into_par_iter()
        .map(|r| {
            let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
            rng.set_stream(r as u64);
            let mut picked = Vec::with_capacity(draws * ell);
            for _ in 0..draws {
                let s = rng.random_range(0..=n - ell);
                picked.extend(s..s + ell);
            }
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
                Err(SolveError::RankDeficient { .. } | SolveError::Underdetermined { .. }) => Ok(None),
                Err(e) => Err(e),
            }
        })
        .collect::<Result<_, SolveError>>()?;

    let failed = outcomes.iter().filter(|o| o.is_none()).count();
    let allowed = params.resamples / 10;
    if failed > allowed {
        return Err(SolveError::BootstrapFailed {
            failed,
            resamples: params.resamples,
            allowed,
        });
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

/// The `q` quantile of sorted `v` by linear interpolation between order statistics.
fn quantile(v: &[f64], q: f64) -> f64 {
    let pos = q * (v.len() - 1) as f64;
    let lo = pos.floor() as usize;
    let hi = (lo + 1).min(v.len() - 1);
    let frac = pos - lo as f64;
    v[lo] + frac * (v[hi] - v[lo])
}

/// `ceil(median length / median gap)` over the segments ordered by start, at least 1.
fn auto_block(system: &LinearSystem) -> usize {
    let mut starts: Vec<usize> = system.blocks().iter().map(|b| b.segment.start).collect();
    let mut lens: Vec<usize> = system.blocks().iter().map(|b| b.segment.len).collect();
    if starts.len() < 2 {
        return 1;
    }
    starts.sort_unstable();
    lens.sort_unstable();
    let mut gaps: Vec<usize> = starts.windows(2).map(|w| w[1] - w[0]).collect();
    gaps.sort_unstable();
    let gap = gaps[gaps.len() / 2].max(1);
    lens[lens.len() / 2].div_ceil(gap).max(1)
}

/// The block `[A_s | b_s]` of `rows` rows from `first`, reduced to its R factor when it has more
/// than `unknowns + 1` rows.
fn reduce(system: &LinearSystem, first: usize, rows: usize) -> Mat<f64> {
    let (a, b) = (system.matrix(), system.rhs());
    let cols = a.ncols() + 1;
    let mut m = Mat::from_fn(rows, cols, |i, j| {
        if j + 1 < cols {
            a[(first + i, j)]
        } else {
            b[first + i]
        }
    });
    if rows <= cols {
        return m;
    }
    let par = Par::Seq;
    let block = factor::recommended_block_size::<f64>(rows, cols);
    let mut q_coeff = Mat::<f64>::zeros(block, cols);
    let mut mem = MemBuffer::new(factor::qr_in_place_scratch::<f64>(
        rows,
        cols,
        block,
        par,
        Default::default(),
    ));
    factor::qr_in_place(
        m.as_mut(),
        q_coeff.as_mut(),
        par,
        MemStack::new(&mut mem),
        Default::default(),
    );
    Mat::from_fn(cols, cols, |i, j| if j >= i { m[(i, j)] } else { 0.0 })
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
}
