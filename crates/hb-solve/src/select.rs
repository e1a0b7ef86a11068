//! Model selection: which terms of a library of candidates the data support.
//!
//! Backward elimination scored by cross-validation over contiguous blocks of segments. The
//! segments of the system (in the order of their first sample) are split into `F` contiguous
//! folds; a model (a subset of the columns) is fitted `F` times, each time without one fold, and
//! scored by the fraction of the held-out folds' right-hand side it leaves unexplained:
//!
//! ```text
//! CV(S) = Σ_f ‖A_f,S c_S^(−f) − b_f‖² / Σ_f ‖b_f‖².
//! ```
//!
//! Starting from the whole library, every step removes the term whose removal leaves the lowest
//! `CV`, until one term is left: a nested path of models. The chosen model is the smallest on the
//! path whose `CV` is within the allowance of the best one:
//! `CV ≤ CV_min + max(SE_min, tolerance)`, `SE_min` being the standard error over folds of the
//! best model's score (the one-standard-error rule) and `tolerance` a floor on the unexplained
//! fraction that a term must remove to be kept (without noise the standard error is tiny, and
//! a spurious term that soaks up a discretisation error of `1e-9` would otherwise be kept).
//!
//! Why contiguous folds: overlapping windows and orbits found in the same stretch share samples,
//! so their equations' errors are correlated; a fold of consecutive segments holds out a stretch
//! of the record, and a term survives only if it predicts stretches it was not fitted on. Why
//! not t-statistics: the least-squares standard errors assume independent rows, which windows
//! that share samples are not (they come out too small by the overlap factor), and without noise
//! they measure the discretisation error, not the term's support.
//!
//! Cost: one QR factor `R_f` of `[A_f | b_f]` per fold (one pass over the system); every fit of
//! the path is then a small Cholesky solve on the folds' `(cols + 1)²` moments, so that a library
//! of 40 terms costs ~40² tiny solves, negligible beside the assembly.

use faer::Mat;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{LstsqError, SelectError, SolveError};

use crate::system::LinearSystem;

/// Parameters of [`select_terms`]; [`SelectParams::new`] validates.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "SelectParamsRaw")]
pub struct SelectParams {
    folds: usize,
    tolerance: f64,
}

#[derive(Deserialize)]
struct SelectParamsRaw {
    folds: usize,
    tolerance: f64,
}

impl TryFrom<SelectParamsRaw> for SelectParams {
    type Error = SolveError;
    fn try_from(raw: SelectParamsRaw) -> Result<Self, SolveError> {
        Self::new(raw.folds, raw.tolerance)
    }
}

impl Default for SelectParams {
    fn default() -> Self {
        Self {
            folds: Self::DEFAULT_FOLDS,
            tolerance: Self::DEFAULT_TOLERANCE,
        }
    }
}

impl SelectParams {
    /// Default number of folds (fewer when the system has fewer segments).
    pub const DEFAULT_FOLDS: usize = 10;
    /// Default floor of the allowance, as a fraction of the held-out right-hand side's power: a
    /// term is kept only if the smaller model without it leaves more than this much more
    /// unexplained. See `docs/identification.md` for the measurements behind the value.
    pub const DEFAULT_TOLERANCE: f64 = 1e-6;

    /// `folds >= 2` folds; `0 <= tolerance < 1`.
    pub fn new(folds: usize, tolerance: f64) -> Result<Self, SolveError> {
        if folds < 2 {
            return Err(SolveError::InvalidParameter {
                name: "selection folds",
                value: folds as f64,
                why: "must be at least 2",
            });
        }
        if !(0.0..1.0).contains(&tolerance) {
            return Err(SolveError::InvalidParameter {
                name: "selection tolerance",
                value: tolerance,
                why: "must be a fraction of the right-hand side's power in [0, 1)",
            });
        }
        Ok(Self { folds, tolerance })
    }

    /// The number of folds.
    pub fn folds(&self) -> usize {
        self.folds
    }

    /// The floor of the allowance.
    pub fn tolerance(&self) -> f64 {
        self.tolerance
    }
}

/// One model of the elimination path.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SelectionStep {
    /// The term removed to reach this model (`None` for the whole library).
    pub removed: Option<String>,
    /// Terms in the model.
    pub size: usize,
    /// Its cross-validated unexplained fraction `CV`.
    pub unexplained: f64,
    /// The standard error of `CV` over the folds.
    pub std_error: f64,
}

/// A term the selection dropped, and why.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DroppedTerm {
    /// The term's name.
    pub name: String,
    /// The cross-validated unexplained fraction of the model just without it.
    pub unexplained_without: f64,
    /// Of the model just with it.
    pub unexplained_with: f64,
}

impl DroppedTerm {
    /// Why it was dropped, in words.
    pub fn reason(&self, allowance: f64) -> String {
        let change = self.unexplained_without - self.unexplained_with;
        if change <= 0.0 {
            format!(
                "held-out fit better without it (unexplained {:.3e} -> {:.3e})",
                self.unexplained_with, self.unexplained_without
            )
        } else {
            format!(
                "removes only {change:.2e} of the held-out unexplained fraction (model within the allowance {allowance:.2e} of the best)"
            )
        }
    }
}

/// The outcome of [`select_terms`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Selection {
    /// The kept terms' column indices in the system, in column order.
    pub kept: Vec<usize>,
    /// The kept terms' names, in column order.
    pub kept_names: Vec<String>,
    /// The dropped terms, in the order they were removed.
    pub dropped: Vec<DroppedTerm>,
    /// The whole elimination path, from the whole library down to one term.
    pub path: Vec<SelectionStep>,
    /// Folds used.
    pub folds: usize,
    /// The allowance `max(SE_min, tolerance)` the chosen model is within of the best.
    pub allowance: f64,
}

/// Selects the terms of `system`'s columns that the data support (see the module docs).
///
/// Needs at least two segments (fewer folds than [`SelectParams::folds`] are used when there are
/// fewer segments).
pub fn select_terms(system: &LinearSystem, params: &SelectParams) -> Result<Selection, SolveError> {
    let cols = system.unknowns();
    let names = system.names();
    let blocks = system.blocks();
    if blocks.len() < 2 {
        return Err(SolveError::Lstsq(LstsqError::TooFewOrbits {
            found: blocks.len(),
            needed: 2,
        }));
    }
    let folds = params.folds.min(blocks.len());
    let moments = FoldMoments::new(system, folds);

    let mut active: Vec<usize> = (0..cols).collect();
    let first = moments
        .score(&active)
        .ok_or(SolveError::Select(SelectError::SelectionUndetermined { folds }))?;
    let mut path = vec![SelectionStep {
        removed: None,
        size: cols,
        unexplained: first.0,
        std_error: first.1,
    }];
    let mut removed_order: Vec<usize> = Vec::new();
    while active.len() > 1 {
        let best = (0..active.len())
            .filter_map(|i| {
                let mut trial = active.clone();
                trial.remove(i);
                moments.score(&trial).map(|s| (i, s))
            })
            .min_by(|a, b| a.1.0.total_cmp(&b.1.0));
        let Some((i, (cv, se))) = best else { break };
        let gone = active.remove(i);
        removed_order.push(gone);
        path.push(SelectionStep {
            removed: Some(names[gone].clone()),
            size: active.len(),
            unexplained: cv,
            std_error: se,
        });
    }

    let best = path
        .iter()
        .min_by(|a, b| a.unexplained.total_cmp(&b.unexplained))
        .cloned()
        .unwrap_or_else(|| path[0].clone());
    let allowance = best.std_error.max(params.tolerance);
    // The smallest model within the allowance (the path's models are nested, sizes decreasing).
    let chosen = path
        .iter()
        .rposition(|s| s.unexplained <= best.unexplained + allowance)
        .unwrap_or(0);
    let dropped_cols = &removed_order[..chosen];
    let mut kept: Vec<usize> = (0..cols).filter(|c| !dropped_cols.contains(c)).collect();
    kept.sort_unstable();
    let dropped = dropped_cols
        .iter()
        .enumerate()
        .map(|(k, &c)| DroppedTerm {
            name: names[c].clone(),
            unexplained_without: path[k + 1].unexplained,
            unexplained_with: path[k].unexplained,
        })
        .collect();
    Ok(Selection {
        kept_names: kept.iter().map(|&c| names[c].clone()).collect(),
        kept,
        dropped,
        path,
        folds,
        allowance,
    })
}

/// Per fold: the triangular factor of its column-scaled `[A_f | b_f]` (so that `‖A_f c − b_f‖²`
/// is `‖R_f [c; −1]‖²` exactly) and its Gram matrix `R_fᵀ R_f`; and their sum over folds.
pub(crate) struct FoldMoments {
    cols: usize,
    factors: Vec<Mat<f64>>,
    grams: Vec<Mat<f64>>,
    total: Mat<f64>,
}

impl FoldMoments {
    pub(crate) fn new(system: &LinearSystem, folds: usize) -> Self {
        let a = system.matrix();
        let b = system.rhs();
        let cols = a.ncols();
        let norms: Vec<f64> = (0..cols)
            .map(|c| {
                let n = a.col(c).iter().map(|v| v * v).sum::<f64>().sqrt();
                if n > 0.0 { n } else { 1.0 }
            })
            .collect();
        let mut order: Vec<usize> = (0..system.blocks().len()).collect();
        order.sort_by_key(|&i| system.blocks()[i].segment.start());
        let n = order.len();
        // Each fold's factor and Gram matrix, the folds in parallel on the factorisations' own
        // pool (faer's kernels slow the plain arithmetic of the thread they ran on; see
        // `on_factor_pool`). Each fold's factor is sequential, so the results are those of one
        // fold after another, to the bit.
        let fold = |f: usize| {
            let members = &order[f * n / folds..(f + 1) * n / folds];
            let rows: usize = members.iter().map(|&i| system.blocks()[i].rows).sum();
            let mut m = Mat::<f64>::zeros(rows, cols + 1);
            let mut at = 0;
            for &i in members {
                let block = &system.blocks()[i];
                let len = block.rows;
                for (c, norm) in norms.iter().enumerate() {
                    let src = a.col(c).subrows(block.first_row, len);
                    m.col_mut(c)
                        .subrows_mut(at, len)
                        .iter_mut()
                        .zip(src.iter())
                        .for_each(|(d, s)| *d = s / norm);
                }
                m.col_mut(cols)
                    .subrows_mut(at, len)
                    .copy_from(b.subrows(block.first_row, len));
                at += len;
            }
            let r = crate::lstsq::triangular_factor(m);
            let g = r.transpose() * &r;
            (r, g)
        };
        let (factors, grams): (Vec<Mat<f64>>, Vec<Mat<f64>>) =
            crate::lstsq::on_factor_pool(|| (0..folds).into_par_iter().map(fold).unzip());
        let mut total = Mat::<f64>::zeros(cols + 1, cols + 1);
        for g in &grams {
            total += g;
        }
        Self {
            cols,
            factors,
            grams,
            total,
        }
    }

    /// `(CV, SE)` of the model with columns `active`; `None` when a training set does not
    /// determine it.
    pub(crate) fn score(&self, active: &[usize]) -> Option<(f64, f64)> {
        let k = active.len();
        let rhs = self.cols;
        let mut fractions = Vec::with_capacity(self.grams.len());
        let (mut lost, mut power) = (0.0, 0.0);
        for (gram, factor) in self.grams.iter().zip(&self.factors) {
            let train = |i: usize, j: usize| self.total[(i, j)] - gram[(i, j)];
            let g = Mat::from_fn(k, k, |i, j| train(active[i], active[j]));
            let r: Vec<f64> = active.iter().map(|&i| train(i, rhs)).collect();
            let c = cholesky_solve(g, r)?;
            // Held-out residual ‖R_f [c; −1]‖² and power ‖b_f‖² = ‖R_f e_rhs‖².
            let (mut res, mut pow) = (0.0, 0.0);
            for row in 0..factor.nrows() {
                let mut v = -factor[(row, rhs)];
                for (&col, &cv) in active.iter().zip(&c) {
                    v += factor[(row, col)] * cv;
                }
                res += v * v;
                pow += factor[(row, rhs)] * factor[(row, rhs)];
            }
            lost += res;
            power += pow;
            if pow > 0.0 {
                fractions.push(res / pow);
            }
        }
        if power <= 0.0 {
            return None;
        }
        let cv = lost / power;
        let m = fractions.len() as f64;
        let mean = fractions.iter().sum::<f64>() / m;
        let var = fractions.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (m - 1.0).max(1.0);
        Some((cv, (var / m).sqrt()))
    }
}

/// Solves `G c = r` for a symmetric positive definite `G` by Cholesky; `None` when a pivot is
/// below `1e-13` of the largest diagonal entry (the training set does not determine `c`).
fn cholesky_solve(mut g: Mat<f64>, mut y: Vec<f64>) -> Option<Vec<f64>> {
    let n = g.nrows();
    let largest = (0..n).map(|i| g[(i, i)]).fold(0.0_f64, f64::max);
    for j in 0..n {
        let mut pivot = g[(j, j)];
        for k in 0..j {
            pivot -= g[(j, k)] * g[(j, k)];
        }
        if pivot.is_nan() || pivot <= 1e-13 * largest {
            return None;
        }
        let pivot = pivot.sqrt();
        g[(j, j)] = pivot;
        for i in j + 1..n {
            let mut v = g[(i, j)];
            for k in 0..j {
                v -= g[(i, k)] * g[(j, k)];
            }
            g[(i, j)] = v / pivot;
        }
    }
    for i in 0..n {
        for k in 0..i {
            y[i] -= g[(i, k)] * y[k];
        }
        y[i] /= g[(i, i)];
    }
    for i in (0..n).rev() {
        for k in i + 1..n {
            y[i] -= g[(k, i)] * y[k];
        }
        y[i] /= g[(i, i)];
    }
    Some(y)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::system::Block;
    use circle_signal::{SampleClock, Segment};
    use faer::Col;
    use faer::prelude::SolveLstsq;

    /// `n` segments of 9 rows; columns: three true terms, two spurious ones (a smooth function
    /// and a near-copy of a true column plus a little of its own), rhs = the true combination
    /// plus `noise` times a deterministic pseudo-random sequence.
    fn library(n: usize, noise: f64) -> LinearSystem {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let rows = 9 * n;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut draw = || -> f64 { StandardNormal.sample(&mut rng) };
        let columns: Vec<[f64; 5]> = (0..rows)
            .map(|i| {
                let t = i as f64 * 0.37;
                [
                    t.sin(),
                    (1.7 * t).cos() + 0.2 * draw(),
                    draw(),
                    (0.3 * t).cos() * draw(),
                    t.sin() + 0.05 * draw(),
                ]
            })
            .collect();
        let matrix = Mat::from_fn(rows, 5, |i, j| columns[i][j]);
        let rhs = Col::from_fn(rows, |i| {
            2.0 * matrix[(i, 0)] - 0.7 * matrix[(i, 1)] + 0.05 * matrix[(i, 2)] + noise * draw()
        });
        let clock = SampleClock::nondimensional(25).unwrap();
        let blocks = (0..n)
            .map(|k| Block {
                segment: Segment::new(10 * ((k * 7) % n), 1, &clock, 0.0, usize::MAX).unwrap(),
                first_row: 9 * k,
                rows: 9,
                harmonics: 4,
                winding: 0,
                rotation_rate: 0.0,
                group: None,
            })
            .collect();
        let names = ["a", "b", "small", "spurious", "near a"]
            .map(String::from)
            .to_vec();
        LinearSystem::from_parts(matrix, rhs, names, blocks)
    }

    #[test]
    fn keeps_exactly_the_true_terms() {
        for noise in [0.0, 1e-3, 1e-2] {
            let s = select_terms(&library(200, noise), &SelectParams::default()).unwrap();
            assert_eq!(s.kept_names, ["a", "b", "small"], "noise {noise}: {s:?}");
            let mut dropped: Vec<&str> = s.dropped.iter().map(|d| d.name.as_str()).collect();
            dropped.sort_unstable();
            assert_eq!(dropped, ["near a", "spurious"]);
            assert_eq!(s.path.len(), 5);
            assert_eq!(s.path[0].size, 5);
        }
    }

    /// A term below the noise is not supported: `small` (t-statistic about 1 at noise 2) is
    /// dropped, the others kept.
    #[test]
    fn a_term_below_the_noise_is_dropped() {
        let s = select_terms(&library(200, 2.0), &SelectParams::default()).unwrap();
        assert!(s.kept_names.iter().any(|n| n == "a") && s.kept_names.iter().any(|n| n == "b"));
        assert!(s.dropped.iter().any(|d| d.name == "small"), "{s:?}");
    }

    /// The path's scores are those of a direct cross-validation by stacked least squares.
    #[test]
    fn scores_match_direct_cross_validation() {
        let system = library(60, 1e-2);
        let moments = FoldMoments::new(&system, 4);
        let active = [0, 1, 3];
        let (cv, _) = moments.score(&active).unwrap();
        // Direct: fold f holds blocks 15f..15f+15 in start order.
        let mut order: Vec<usize> = (0..60).collect();
        order.sort_by_key(|&i| system.blocks()[i].segment.start());
        let (a, b) = (system.matrix(), system.rhs());
        let rows_of = |set: &[usize]| -> Vec<usize> {
            set.iter()
                .flat_map(|&i| {
                    let bl = system.blocks()[i];
                    bl.first_row..bl.first_row + bl.rows
                })
                .collect()
        };
        let (mut lost, mut power) = (0.0, 0.0);
        for f in 0..4 {
            let held: Vec<usize> = order[15 * f..15 * f + 15].to_vec();
            let train: Vec<usize> = order.iter().copied().filter(|i| !held.contains(i)).collect();
            let tr = rows_of(&train);
            let m = Mat::from_fn(tr.len(), 3, |i, j| a[(tr[i], active[j])]);
            let y = Mat::from_fn(tr.len(), 1, |i, _| b[tr[i]]);
            let c = m.qr().solve_lstsq(&y);
            for r in rows_of(&held) {
                let pred: f64 = (0..3).map(|j| a[(r, active[j])] * c[(j, 0)]).sum();
                lost += (pred - b[r]).powi(2);
                power += b[r] * b[r];
            }
        }
        let direct = lost / power;
        assert!((cv - direct).abs() <= 1e-9 * direct, "{cv} vs {direct}");
    }

    #[test]
    fn params_are_validated() {
        assert!(SelectParams::new(1, 0.0).is_err());
        assert!(SelectParams::new(5, 1.0).is_err());
        assert!(SelectParams::new(5, f64::NAN).is_err());
        assert!(serde_json::from_str::<SelectParams>(r#"{"folds":0,"tolerance":0.1}"#).is_err());
        let p = SelectParams::new(3, 0.5).unwrap();
        assert_eq!((p.folds(), p.tolerance()), (3, 0.5));
    }

    #[test]
    fn a_redundant_library_is_an_error() {
        let mut s = library(50, 0.0);
        let copy: Vec<f64> = s.column(0).to_vec();
        s.matrix_mut_for_tests()
            .col_mut(3)
            .iter_mut()
            .zip(&copy)
            .for_each(|(d, v)| *d = 2.0 * v);
        assert!(matches!(
            select_terms(&s, &SelectParams::default()),
            Err(SolveError::Select(SelectError::SelectionUndetermined { .. }))
        ));
    }
}
