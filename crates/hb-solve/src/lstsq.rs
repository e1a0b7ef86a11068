//! Least squares `min ||A x − b||` by column-pivoted QR or thin SVD (never the normal equations).

use std::fmt;

use faer::diag::Diag;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::qr::col_pivoting;
use faer::linalg::svd::{self, ComputeSvdVectors};
use faer::{ColRef, Conj, Mat, MatRef, Par};

use crate::SolveError;

/// The relative threshold below which a singular value counts as zero.
///
/// A system is rank deficient when `σ_min <= tol · σ_max` for the singular values of the
/// column-scaled matrix.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RankTolerance {
    /// `tol = max(rows, cols) · ε` (ε = 2.2e-16), the LAPACK / NumPy convention for exact rank
    /// deficiency in floating point.
    Auto,
    /// A given `tol` in `[0, 1)`.
    Relative(f64),
}

impl RankTolerance {
    fn validate(self) -> Result<Self, SolveError> {
        match self {
            Self::Relative(t) if !(t.is_finite() && (0.0..1.0).contains(&t)) => {
                Err(SolveError::InvalidParameter {
                    name: "rank tolerance",
                    value: t,
                    why: "must be in [0, 1)",
                })
            }
            ok => Ok(ok),
        }
    }

    /// The threshold for a `rows × cols` system.
    pub fn value(self, rows: usize, cols: usize) -> f64 {
        match self {
            Self::Auto => rows.max(cols) as f64 * f64::EPSILON,
            Self::Relative(t) => t,
        }
    }
}

/// A least-squares solution with its statistics.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct LstsqFit {
    /// The minimiser `x`.
    pub solution: Vec<f64>,
    /// Standard error of each entry of `x`: `sqrt(s² [(AᵀA)⁻¹]_ii)` with `s² = RSS / (rows − cols)`,
    /// `(AᵀA)⁻¹` taken from the factorisation (never by forming `AᵀA`).
    pub std_errors: Vec<f64>,
    /// Numerical rank (equal to `cols`: rank-deficient systems are an error).
    pub rank: usize,
    /// 2-norm condition number `σ_max / σ_min` of the column-scaled matrix (every column of unit
    /// Euclidean norm), the one the factorisation works on.
    pub condition: f64,
    /// Residual sum of squares `||A x − b||²`.
    pub rss: f64,
    /// Residual variance `s² = RSS / (rows − cols)`.
    pub residual_variance: f64,
    /// Residual root mean square `sqrt(RSS / rows)`.
    pub residual_rms: f64,
    /// Rows of the system.
    pub rows: usize,
    /// Columns (unknowns).
    pub cols: usize,
}

/// A dense least-squares solver for tall systems (`rows > cols`).
///
/// Implementations scale every column of `A` to unit norm before factorising and undo the scaling
/// after; they report rank deficiency (with the column that weighs most in the weakest singular
/// direction) instead of returning a meaningless solution, and reject non-finite input.
pub trait LstsqSolver: fmt::Debug + Send + Sync {
    /// A short name (`qr`, `svd`), recorded in identified models.
    fn name(&self) -> &'static str;

    /// Solves `min ||A x − b||`.
    fn solve(&self, a: MatRef<'_, f64>, b: ColRef<'_, f64>) -> Result<LstsqFit, SolveError>;
}

impl<S: LstsqSolver + ?Sized> LstsqSolver for &S {
    fn name(&self) -> &'static str {
        (**self).name()
    }
    fn solve(&self, a: MatRef<'_, f64>, b: ColRef<'_, f64>) -> Result<LstsqFit, SolveError> {
        (**self).solve(a, b)
    }
}

impl<S: LstsqSolver + ?Sized> LstsqSolver for Box<S> {
    fn name(&self) -> &'static str {
        (**self).name()
    }
    fn solve(&self, a: MatRef<'_, f64>, b: ColRef<'_, f64>) -> Result<LstsqFit, SolveError> {
        (**self).solve(a, b)
    }
}

/// Householder QR with column pivoting (faer's `col_pivoting`), run sequentially
/// (`Par::Seq`) so that it may be called from inside a rayon loop.
///
/// Rank and condition come from the singular values of `R`, which are those of the scaled `A`;
/// `(AᵀA)⁻¹ = P R⁻¹ R⁻ᵀ Pᵀ` gives the standard errors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QrSolver {
    tol: RankTolerance,
}

impl Default for QrSolver {
    fn default() -> Self {
        Self {
            tol: RankTolerance::Auto,
        }
    }
}

impl QrSolver {
    /// The solver with a rank tolerance.
    pub fn new(tol: RankTolerance) -> Result<Self, SolveError> {
        Ok(Self { tol: tol.validate()? })
    }
}

/// Thin singular value decomposition `A = U Σ Vᵀ` (faer), run sequentially.
///
/// `x = V Σ⁻¹ Uᵀ b` and `(AᵀA)⁻¹ = V Σ⁻² Vᵀ`. faer's own `Svd::solve_lstsq` divides by every
/// singular value; here the rank is checked first against the [`RankTolerance`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SvdSolver {
    tol: RankTolerance,
}

impl Default for SvdSolver {
    fn default() -> Self {
        Self {
            tol: RankTolerance::Auto,
        }
    }
}

impl SvdSolver {
    /// The solver with a rank tolerance.
    pub fn new(tol: RankTolerance) -> Result<Self, SolveError> {
        Ok(Self { tol: tol.validate()? })
    }
}

/// The column-scaled copy of `A` and the scales.
struct Scaled {
    a: Mat<f64>,
    norms: Vec<f64>,
}

fn prepare(a: MatRef<'_, f64>, b: ColRef<'_, f64>) -> Result<Scaled, SolveError> {
    let (m, n) = a.shape();
    if b.nrows() != m {
        return Err(SolveError::InvalidParameter {
            name: "right-hand side length",
            value: b.nrows() as f64,
            why: "must equal the number of rows",
        });
    }
    if m <= n || n == 0 {
        return Err(SolveError::Underdetermined { rows: m, cols: n });
    }
    if let Some(row) = b.iter().position(|v| !v.is_finite()) {
        return Err(SolveError::NonFiniteInput {
            what: "right-hand side",
            row,
        });
    }
    let mut norms = Vec::with_capacity(n);
    for c in 0..n {
        let col = a.col(c);
        if let Some(row) = col.iter().position(|v| !v.is_finite()) {
            return Err(SolveError::NonFiniteInput { what: "matrix", row });
        }
        // Scaled sum of squares: no overflow for large entries.
        let big = col.iter().fold(0.0_f64, |acc, v| acc.max(v.abs()));
        let norm = if big == 0.0 {
            0.0
        } else {
            big * col.iter().map(|v| (v / big) * (v / big)).sum::<f64>().sqrt()
        };
        // A zero column stays zero: the rank check then names it.
        norms.push(if norm > 0.0 { norm } else { 1.0 });
    }
    let scaled = Mat::from_fn(m, n, |i, j| a[(i, j)] / norms[j]);
    Ok(Scaled { a: scaled, norms })
}

/// A thin SVD `A = U diag(s) Vᵀ`.
struct SvdParts {
    s: Vec<f64>,
    u: Mat<f64>,
    v: Mat<f64>,
}

/// The thin SVD of `a`, computed sequentially.
fn svd_seq(a: MatRef<'_, f64>) -> Result<SvdParts, SolveError> {
    let (m, n) = a.shape();
    let size = m.min(n);
    let par = Par::Seq;
    let mut s = Diag::<f64>::zeros(size);
    let mut u = Mat::zeros(m, size);
    let mut v = Mat::zeros(n, size);
    let thin = ComputeSvdVectors::Thin;
    let mut mem = MemBuffer::new(svd::svd_scratch::<f64>(m, n, thin, thin, par, Default::default()));
    svd::svd(
        a,
        s.as_mut(),
        Some(u.as_mut()),
        Some(v.as_mut()),
        par,
        MemStack::new(&mut mem),
        Default::default(),
    )
    .map_err(|_| SolveError::SvdNoConvergence)?;
    Ok(SvdParts {
        s: s.column_vector().iter().copied().collect(),
        u,
        v,
    })
}

/// Rank and condition from singular values; the index of the smallest.
fn rank_of(s: &[f64], tol: f64) -> (usize, f64, usize) {
    let smax = s.iter().copied().fold(0.0_f64, f64::max);
    let (imin, smin) =
        s.iter().copied().enumerate().fold(
            (0, f64::INFINITY),
            |acc, (i, v)| if v < acc.1 { (i, v) } else { acc },
        );
    let rank = s.iter().filter(|&&v| v > tol * smax).count();
    let cond = if smin > 0.0 { smax / smin } else { f64::INFINITY };
    (rank, cond, imin)
}

fn rank_error(rank: usize, rows: usize, cols: usize, column: usize) -> SolveError {
    SolveError::RankDeficient {
        rank,
        unknowns: cols,
        rows,
        column,
        suspect: format!("column {column}"),
    }
}

/// Index of the largest-magnitude entry of column `k` of `v`.
fn heaviest(v: MatRef<'_, f64>, k: usize) -> usize {
    v.col(k)
        .iter()
        .enumerate()
        .fold(
            (0, -1.0),
            |acc, (i, x)| if x.abs() > acc.1 { (i, x.abs()) } else { acc },
        )
        .0
}

/// Unscales, computes residuals and standard errors.
fn finish(
    a: MatRef<'_, f64>,
    b: ColRef<'_, f64>,
    x_scaled: &[f64],
    gram_inv_scaled: &[f64],
    norms: &[f64],
    condition: f64,
) -> LstsqFit {
    let (m, n) = a.shape();
    let solution: Vec<f64> = x_scaled.iter().zip(norms).map(|(x, s)| x / s).collect();
    let mut r: Vec<f64> = b.iter().copied().collect();
    for (c, &x) in solution.iter().enumerate() {
        for (ri, &aic) in r.iter_mut().zip(a.col(c).iter()) {
            *ri -= aic * x;
        }
    }
    let rss: f64 = r.iter().map(|v| v * v).sum();
    let residual_variance = rss / (m - n) as f64;
    let std_errors = gram_inv_scaled
        .iter()
        .zip(norms)
        .map(|(g, s)| (residual_variance * g).sqrt() / s)
        .collect();
    LstsqFit {
        solution,
        std_errors,
        rank: n,
        condition,
        rss,
        residual_variance,
        residual_rms: (rss / m as f64).sqrt(),
        rows: m,
        cols: n,
    }
}

impl LstsqSolver for QrSolver {
    fn name(&self) -> &'static str {
        "qr"
    }

    fn solve(&self, a: MatRef<'_, f64>, b: ColRef<'_, f64>) -> Result<LstsqFit, SolveError> {
        let sc = prepare(a, b)?;
        let (m, n) = a.shape();
        let par = Par::Seq;
        let block = faer::linalg::qr::no_pivoting::factor::recommended_block_size::<f64>(m, n);
        let mut qr = sc.a;
        let mut q_coeff = Mat::<f64>::zeros(block, n);
        let mut fwd = vec![0usize; n];
        let mut bwd = vec![0usize; n];
        let mut mem = MemBuffer::new(col_pivoting::factor::qr_in_place_scratch::<usize, f64>(
            m,
            n,
            block,
            par,
            Default::default(),
        ));
        let (_, perm) = col_pivoting::factor::qr_in_place(
            qr.as_mut(),
            q_coeff.as_mut(),
            &mut fwd,
            &mut bwd,
            par,
            MemStack::new(&mut mem),
            Default::default(),
        );
        // Split into the unit lower-trapezoidal Householder basis and the n × n factor R.
        let mut r = Mat::<f64>::zeros(n, n);
        r.copy_from_triangular_upper(qr.get(..n, ..n));
        for j in 0..n {
            for i in 0..j {
                qr[(i, j)] = 0.0;
            }
            qr[(j, j)] = 1.0;
        }

        // A_scaled P = Q R: R has the singular values of the scaled matrix.
        let SvdParts { s, v, .. } = svd_seq(r.as_ref())?;
        let (rank, condition, imin) = rank_of(&s, self.tol.value(m, n));
        let (perm_fwd, _) = perm.arrays();
        if rank < n {
            return Err(rank_error(rank, m, n, perm_fwd[heaviest(v.as_ref(), imin)]));
        }

        let mut rhs = Mat::from_fn(m, 1, |i, _| b[i]);
        let mut mem = MemBuffer::new(col_pivoting::solve::solve_lstsq_in_place_scratch::<usize, f64>(
            m, n, block, 1, par,
        ));
        col_pivoting::solve::solve_lstsq_in_place_with_conj(
            qr.as_ref(),
            q_coeff.as_ref(),
            r.as_ref(),
            perm,
            Conj::No,
            rhs.as_mut(),
            par,
            MemStack::new(&mut mem),
        );
        let x: Vec<f64> = (0..n).map(|i| rhs[(i, 0)]).collect();

        // diag((RᵀR)⁻¹) = squared row norms of R⁻¹, in pivoted order.
        let mut rinv = Mat::<f64>::identity(n, n);
        faer::linalg::triangular_solve::solve_upper_triangular_in_place(r.as_ref(), rinv.as_mut(), par);
        let mut gram_inv = vec![0.0; n];
        for (j, &orig) in perm_fwd.iter().enumerate() {
            gram_inv[orig] = (0..n).map(|k| rinv[(j, k)] * rinv[(j, k)]).sum();
        }
        Ok(finish(a, b, &x, &gram_inv, &sc.norms, condition))
    }
}

impl LstsqSolver for SvdSolver {
    fn name(&self) -> &'static str {
        "svd"
    }

    fn solve(&self, a: MatRef<'_, f64>, b: ColRef<'_, f64>) -> Result<LstsqFit, SolveError> {
        let sc = prepare(a, b)?;
        let (m, n) = a.shape();
        let SvdParts { s, u, v } = svd_seq(sc.a.as_ref())?;
        let (rank, condition, imin) = rank_of(&s, self.tol.value(m, n));
        if rank < n {
            return Err(rank_error(rank, m, n, heaviest(v.as_ref(), imin)));
        }
        let mut x = vec![0.0; n];
        let mut gram_inv = vec![0.0; n];
        for (k, &sk) in s.iter().enumerate() {
            let coef = u.col(k).iter().zip(b.iter()).map(|(ui, bi)| ui * bi).sum::<f64>() / sk;
            for c in 0..n {
                let vck = v[(c, k)];
                x[c] += vck * coef;
                gram_inv[c] += vck * vck / (sk * sk);
            }
        }
        Ok(finish(a, b, &x, &gram_inv, &sc.norms, condition))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::Col;

    fn small() -> (Mat<f64>, Col<f64>) {
        // Columns of very different scale; exact solution (1, −2, 3e-3).
        let a = Mat::from_fn(6, 3, |i, j| {
            let t = i as f64;
            [1.0, 1e3 * (t * 0.7).sin(), 1e-2 * t * t][j]
        });
        let x = [1.0, -2.0, 3e-3];
        let b = Col::from_fn(6, |i| (0..3).map(|j| a[(i, j)] * x[j]).sum());
        (a, b)
    }

    #[test]
    fn both_solvers_recover_an_exact_solution() {
        let (a, b) = small();
        for solver in [&QrSolver::default() as &dyn LstsqSolver, &SvdSolver::default()] {
            let fit = solver.solve(a.as_ref(), b.as_ref()).unwrap();
            assert!(
                (fit.solution[0] - 1.0).abs() < 1e-12,
                "{}: {:?}",
                solver.name(),
                fit.solution
            );
            assert!((fit.solution[1] + 2.0).abs() < 1e-12);
            // |b| ~ 2e3 against a column of norm 0.3: rounding allows ~eps |b| / |a_2| cond ~ 1e-11.
            assert!((fit.solution[2] - 3e-3).abs() < 1e-10, "{}", fit.solution[2]);
            assert!(fit.rss < 1e-20);
            assert_eq!(fit.rank, 3);
        }
    }

    #[test]
    fn zero_and_duplicate_columns_are_rank_deficient() {
        let (a, b) = small();
        let zero = Mat::from_fn(6, 4, |i, j| if j < 3 { a[(i, j)] } else { 0.0 });
        let dup = Mat::from_fn(6, 4, |i, j| if j < 3 { a[(i, j)] } else { 2.0 * a[(i, 0)] });
        for solver in [&QrSolver::default() as &dyn LstsqSolver, &SvdSolver::default()] {
            match solver.solve(zero.as_ref(), b.as_ref()) {
                Err(SolveError::RankDeficient {
                    rank: 3,
                    unknowns: 4,
                    suspect,
                    ..
                }) => {
                    assert_eq!(suspect, "column 3", "{}", solver.name())
                }
                other => panic!("{}: {other:?}", solver.name()),
            }
            assert!(matches!(
                solver.solve(dup.as_ref(), b.as_ref()),
                Err(SolveError::RankDeficient {
                    rank: 3,
                    unknowns: 4,
                    ..
                })
            ));
        }
    }

    #[test]
    fn rejects_bad_input() {
        let (mut a, b) = small();
        let qr = QrSolver::default();
        assert!(matches!(
            qr.solve(a.get(..3, ..), b.get(..3)),
            Err(SolveError::Underdetermined { rows: 3, cols: 3 })
        ));
        a[(4, 1)] = f64::NAN;
        assert!(matches!(
            qr.solve(a.as_ref(), b.as_ref()),
            Err(SolveError::NonFiniteInput {
                what: "matrix",
                row: 4
            })
        ));
        assert!(QrSolver::new(RankTolerance::Relative(1.5)).is_err());
        assert!(SvdSolver::new(RankTolerance::Relative(f64::NAN)).is_err());
    }
}
