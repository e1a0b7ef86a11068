//! Least squares `min ||A x − b||` by column-pivoted QR or thin SVD (never the normal equations).

use std::fmt;

use faer::diag::Diag;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::qr::col_pivoting;
use faer::linalg::svd::{self, ComputeSvdVectors};
use faer::{ColRef, Conj, Mat, MatRef, Par};
use rayon::prelude::*;

use crate::error::{LstsqError, SolveError};

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

    /// Solves `min ||A x − b||` for rows that stand for `rows` rows of a taller system: `[A | b]`
    /// a triangular factor of that system's (an orthogonal transform of it, as
    /// [`LinearSystem::compressed`](crate::LinearSystem::compressed) makes), so the minimiser and
    /// the residual sum of squares are the taller system's. What counts rows is counted by `rows`:
    /// the rank tolerance, the residual variance `RSS / (rows − cols)` and with it the standard
    /// errors, the residual RMS and [`LstsqFit::rows`].
    ///
    /// The provided method solves and then rescales those statistics (its rank tolerance is the
    /// factor's); the crate's solvers take `rows` into the rank tolerance as well.
    fn solve_standing_for(
        &self,
        a: MatRef<'_, f64>,
        b: ColRef<'_, f64>,
        rows: usize,
    ) -> Result<LstsqFit, SolveError> {
        let fit = self.solve(a, b)?;
        Ok(fit.standing_for(rows))
    }
}

impl LstsqFit {
    /// The fit's statistics counted by `rows` rows instead of its own (see
    /// [`LstsqSolver::solve_standing_for`]).
    fn standing_for(mut self, rows: usize) -> Self {
        if rows == self.rows || rows <= self.cols {
            return self;
        }
        let variance = self.rss / (rows - self.cols) as f64;
        let ratio = if self.residual_variance > 0.0 {
            (variance / self.residual_variance).sqrt()
        } else {
            0.0
        };
        self.std_errors.iter_mut().for_each(|e| *e *= ratio);
        self.residual_variance = variance;
        self.residual_rms = (self.rss / rows as f64).sqrt();
        self.rows = rows;
        self
    }
}

impl<S: LstsqSolver + ?Sized> LstsqSolver for &S {
    fn name(&self) -> &'static str {
        (**self).name()
    }
    fn solve(&self, a: MatRef<'_, f64>, b: ColRef<'_, f64>) -> Result<LstsqFit, SolveError> {
        (**self).solve(a, b)
    }
    fn solve_standing_for(
        &self,
        a: MatRef<'_, f64>,
        b: ColRef<'_, f64>,
        rows: usize,
    ) -> Result<LstsqFit, SolveError> {
        (**self).solve_standing_for(a, b, rows)
    }
}

impl<S: LstsqSolver + ?Sized> LstsqSolver for Box<S> {
    fn name(&self) -> &'static str {
        (**self).name()
    }
    fn solve(&self, a: MatRef<'_, f64>, b: ColRef<'_, f64>) -> Result<LstsqFit, SolveError> {
        (**self).solve(a, b)
    }
    fn solve_standing_for(
        &self,
        a: MatRef<'_, f64>,
        b: ColRef<'_, f64>,
        rows: usize,
    ) -> Result<LstsqFit, SolveError> {
        (**self).solve_standing_for(a, b, rows)
    }
}

/// Householder QR with column pivoting (faer's `col_pivoting`).
///
/// The factorisations run sequentially (`Par::Seq`), so that the solver may be called from inside
/// a rayon loop; a system of at least 4096 rows is first reduced to its triangular factor by
/// unpivoted QR of blocks of rows on rayon's threads (a tall system then costs one pass over its
/// rows and no copy of the matrix).
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

/// Thin singular value decomposition `A = U Σ Vᵀ` (faer), run sequentially, after the same
/// reduction of tall systems as [`QrSolver`] (the SVD of the triangular factor has the singular
/// values and right vectors of `A`).
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

/// The column-scaled system, reduced for tall systems, and the scales.
///
/// The least-squares problem `min ||A D⁻¹ y − b||` (`D` the column norms) is replaced by the
/// smaller `min ||S y − c||` with the same minimiser, the same singular values and a residual
/// that differs by a constant: `[S | c]` is the triangular factor of a QR factorisation of
/// `[A D⁻¹ | b]` (for systems of at least [`REDUCE_ROWS`] rows), or `[A D⁻¹ | b]` itself.
struct Scaled {
    a: Mat<f64>,
    b: Vec<f64>,
    norms: Vec<f64>,
}

/// Systems with at least this many rows are reduced to their triangular factor, in parallel
/// blocks of rows, before the pivoted QR or SVD: those then work on `(cols + 1)²` numbers instead
/// of a scaled copy of the whole system.
pub(crate) const REDUCE_ROWS: usize = 4096;

/// Rows of one block of the parallel reduction.
const REDUCE_BLOCK: usize = 2048;

/// The `cols × cols` triangular factor `R` of a Householder QR of `m` (`rows × cols`, taken by
/// value and overwritten), or `m` itself when it has no more rows than columns. The same
/// least-squares problem, since the factor `Q` is orthogonal. Sequential (`Par::Seq`).
pub fn triangular_factor(mut m: Mat<f64>) -> Mat<f64> {
    let (rows, cols) = m.shape();
    if rows <= cols {
        return m;
    }
    let par = Par::Seq;
    let block = faer::linalg::qr::no_pivoting::factor::recommended_block_size::<f64>(rows, cols);
    let mut q_coeff = Mat::<f64>::zeros(block, cols);
    let mut mem = MemBuffer::new(faer::linalg::qr::no_pivoting::factor::qr_in_place_scratch::<f64>(
        rows,
        cols,
        block,
        par,
        Default::default(),
    ));
    faer::linalg::qr::no_pivoting::factor::qr_in_place(
        m.as_mut(),
        q_coeff.as_mut(),
        par,
        MemStack::new(&mut mem),
        Default::default(),
    );
    Mat::from_fn(cols, cols, |i, j| if j >= i { m[(i, j)] } else { 0.0 })
}

/// The triangular factor of `[A D⁻¹ | b]` (`D = diag(norms)`): QR of consecutive blocks of rows
/// in parallel, their factors stacked and reduced again until at most [`REDUCE_BLOCK`] rows
/// remain.
fn reduce_rows(a: MatRef<'_, f64>, b: ColRef<'_, f64>, norms: &[f64]) -> Mat<f64> {
    let (rows, n) = a.shape();
    let blocks: Vec<Mat<f64>> = (0..rows.div_ceil(REDUCE_BLOCK))
        .into_par_iter()
        .map(|k| {
            let first = k * REDUCE_BLOCK;
            let len = REDUCE_BLOCK.min(rows - first);
            let mut m = Mat::<f64>::zeros(len, n + 1);
            for (j, &norm) in norms.iter().enumerate() {
                let src = a.col(j).subrows(first, len);
                m.col_mut(j)
                    .iter_mut()
                    .zip(src.iter())
                    .for_each(|(d, s)| *d = s / norm);
            }
            m.col_mut(n).copy_from(b.subrows(first, len));
            triangular_factor(m)
        })
        .collect();
    let mut stacked = stack(&blocks, n + 1);
    while stacked.nrows() > REDUCE_BLOCK {
        let ones = vec![1.0; n];
        let (a, b) = (stacked.get(.., ..n), stacked.col(n));
        stacked = reduce_rows(a, b, &ones);
    }
    stacked
}

/// Runs `f` (a factorisation) on a thread pool of its own.
///
/// Measured on the project's 2-core benchmark machine (`docs/performance.md`): after faer's
/// factorisation kernels have run on a thread (they pick AVX-512 at run time), plain floating-point
/// code on that thread runs about 2.7 times slower for the rest of the process (the close-return
/// scan: 0.27 ms before, 0.82 ms after, also with one thread; an AVX `vzeroall` does not undo it).
/// Keeping the factorisations on their own threads leaves the caller's threads and rayon's global
/// pool unaffected (0.29 ms).
pub fn on_factor_pool<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    static POOL: std::sync::OnceLock<Option<rayon::ThreadPool>> = std::sync::OnceLock::new();
    let pool = POOL.get_or_init(|| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(rayon::current_num_threads())
            .thread_name(|i| format!("hb-solve-factor-{i}"))
            .build()
            .ok()
    });
    match pool {
        Some(pool) => pool.install(f),
        None => f(),
    }
}

/// The rows of `blocks` one after another.
fn stack(blocks: &[Mat<f64>], cols: usize) -> Mat<f64> {
    let total = blocks.iter().map(|m| m.nrows()).sum();
    let mut out = Mat::<f64>::zeros(total, cols);
    let mut at = 0;
    for m in blocks {
        out.get_mut(at..at + m.nrows(), ..).copy_from(m);
        at += m.nrows();
    }
    out
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
        return Err(SolveError::Lstsq(LstsqError::Underdetermined {
            rows: m,
            cols: n,
        }));
    }
    if let Some(row) = b.iter().position(|v| !v.is_finite()) {
        return Err(SolveError::Lstsq(LstsqError::NonFiniteInput {
            what: "right-hand side",
            row,
        }));
    }
    let mut norms = Vec::with_capacity(n);
    for c in 0..n {
        let col = a.col(c);
        if let Some(row) = col.iter().position(|v| !v.is_finite()) {
            return Err(SolveError::Lstsq(LstsqError::NonFiniteInput {
                what: "matrix",
                row,
            }));
        }
        // The plain sum of squares, or a scaled one when that over- or underflows.
        let plain: f64 = col.iter().map(|v| v * v).sum();
        let norm = if plain.is_finite() && plain > f64::MIN_POSITIVE / f64::EPSILON {
            plain.sqrt()
        } else {
            let big = col.iter().fold(0.0_f64, |acc, v| acc.max(v.abs()));
            if big == 0.0 {
                0.0
            } else {
                let inv = 1.0 / big;
                big * col.iter().map(|v| (v * inv) * (v * inv)).sum::<f64>().sqrt()
            }
        };
        // A zero column stays zero: the rank check then names it.
        norms.push(if norm > 0.0 { norm } else { 1.0 });
    }
    let reduced = if m >= REDUCE_ROWS {
        reduce_rows(a, b, &norms)
    } else {
        Mat::from_fn(m, n + 1, |i, j| if j < n { a[(i, j)] / norms[j] } else { b[i] })
    };
    Ok(Scaled {
        a: reduced.get(.., ..n).to_owned(),
        b: reduced.col(n).iter().copied().collect(),
        norms,
    })
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
    .map_err(|_| SolveError::Lstsq(LstsqError::SvdNoConvergence))?;
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
    SolveError::Lstsq(LstsqError::RankDeficient {
        rank,
        unknowns: cols,
        rows,
        column,
        suspect: format!("column {column}"),
    })
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
    m: usize,
) -> LstsqFit {
    let n = a.ncols();
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
        self.solve_standing_for(a, b, a.nrows())
    }

    fn solve_standing_for(
        &self,
        a: MatRef<'_, f64>,
        b: ColRef<'_, f64>,
        rows: usize,
    ) -> Result<LstsqFit, SolveError> {
        on_factor_pool(|| self.solve_here(a, b, rows.max(a.nrows())))
    }
}

impl QrSolver {
    fn solve_here(&self, a: MatRef<'_, f64>, b: ColRef<'_, f64>, m: usize) -> Result<LstsqFit, SolveError> {
        let sc = prepare(a, b)?;
        let n = a.ncols();
        // The factorisation works on the (possibly reduced) scaled system of `ms` rows.
        let ms = sc.a.nrows();
        let par = Par::Seq;
        let block = faer::linalg::qr::no_pivoting::factor::recommended_block_size::<f64>(ms, n);
        let mut qr = sc.a;
        let mut q_coeff = Mat::<f64>::zeros(block, n);
        let mut fwd = vec![0usize; n];
        let mut bwd = vec![0usize; n];
        let mut mem = MemBuffer::new(col_pivoting::factor::qr_in_place_scratch::<usize, f64>(
            ms,
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

        let mut rhs = Mat::from_fn(ms, 1, |i, _| sc.b[i]);
        let mut mem = MemBuffer::new(col_pivoting::solve::solve_lstsq_in_place_scratch::<usize, f64>(
            ms, n, block, 1, par,
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
        Ok(finish(a, b, &x, &gram_inv, &sc.norms, condition, m))
    }
}

impl LstsqSolver for SvdSolver {
    fn name(&self) -> &'static str {
        "svd"
    }

    fn solve(&self, a: MatRef<'_, f64>, b: ColRef<'_, f64>) -> Result<LstsqFit, SolveError> {
        self.solve_standing_for(a, b, a.nrows())
    }

    fn solve_standing_for(
        &self,
        a: MatRef<'_, f64>,
        b: ColRef<'_, f64>,
        rows: usize,
    ) -> Result<LstsqFit, SolveError> {
        on_factor_pool(|| self.solve_here(a, b, rows.max(a.nrows())))
    }
}

impl SvdSolver {
    fn solve_here(&self, a: MatRef<'_, f64>, b: ColRef<'_, f64>, m: usize) -> Result<LstsqFit, SolveError> {
        let sc = prepare(a, b)?;
        let n = a.ncols();
        let SvdParts { s, u, v } = svd_seq(sc.a.as_ref())?;
        let (rank, condition, imin) = rank_of(&s, self.tol.value(m, n));
        if rank < n {
            return Err(rank_error(rank, m, n, heaviest(v.as_ref(), imin)));
        }
        let mut x = vec![0.0; n];
        let mut gram_inv = vec![0.0; n];
        for (k, &sk) in s.iter().enumerate() {
            let coef = u.col(k).iter().zip(&sc.b).map(|(ui, bi)| ui * bi).sum::<f64>() / sk;
            for c in 0..n {
                let vck = v[(c, k)];
                x[c] += vck * coef;
                gram_inv[c] += vck * vck / (sk * sk);
            }
        }
        Ok(finish(a, b, &x, &gram_inv, &sc.norms, condition, m))
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
                Err(SolveError::Lstsq(LstsqError::RankDeficient {
                    rank: 3,
                    unknowns: 4,
                    suspect,
                    ..
                })) => {
                    assert_eq!(suspect, "column 3", "{}", solver.name())
                }
                other => panic!("{}: {other:?}", solver.name()),
            }
            assert!(matches!(
                solver.solve(dup.as_ref(), b.as_ref()),
                Err(SolveError::Lstsq(LstsqError::RankDeficient {
                    rank: 3,
                    unknowns: 4,
                    ..
                }))
            ));
        }
    }

    #[test]
    fn rejects_bad_input() {
        let (mut a, b) = small();
        let qr = QrSolver::default();
        assert!(matches!(
            qr.solve(a.get(..3, ..), b.get(..3)),
            Err(SolveError::Lstsq(LstsqError::Underdetermined {
                rows: 3,
                cols: 3
            }))
        ));
        a[(4, 1)] = f64::NAN;
        assert!(matches!(
            qr.solve(a.as_ref(), b.as_ref()),
            Err(SolveError::Lstsq(LstsqError::NonFiniteInput {
                what: "matrix",
                row: 4
            }))
        ));
        assert!(QrSolver::new(RankTolerance::Relative(1.5)).is_err());
        assert!(SvdSolver::new(RankTolerance::Relative(f64::NAN)).is_err());
    }

    /// A tall system, reduced by blocks, gives the least-squares fit of all its rows: residuals
    /// orthogonal to every column, the residual sum of squares of the rows, both solvers agreeing.
    #[test]
    fn tall_systems_reduced_by_blocks_give_the_same_fit() {
        let m = 3 * REDUCE_ROWS + 17;
        let a = Mat::from_fn(m, 4, |i, j| {
            let t = i as f64 * 0.01;
            [1.0, t.sin(), (3.0 * t).cos(), 1e3 * (0.5 * t).sin() * t.cos()][j]
        });
        let noise = |i: usize| ((i * 7919) % 1000) as f64 / 1000.0 - 0.5;
        let b = Col::from_fn(m, |i| {
            0.5 * a[(i, 0)] - 2.0 * a[(i, 1)] + a[(i, 3)] * 1e-3 + 0.01 * noise(i)
        });
        // The minimiser is characterised by orthogonal residuals; the solvers must also agree.
        for solver in [&QrSolver::default() as &dyn LstsqSolver, &SvdSolver::default()] {
            let fit = solver.solve(a.as_ref(), b.as_ref()).unwrap();
            // Normal equations: Aᵀ(b − A x) = 0 at the minimiser.
            let r: Vec<f64> = (0..m)
                .map(|i| b[i] - (0..4).map(|j| a[(i, j)] * fit.solution[j]).sum::<f64>())
                .collect();
            for j in 0..4 {
                let norm = (0..m).map(|i| a[(i, j)] * a[(i, j)]).sum::<f64>().sqrt();
                let g = (0..m).map(|i| a[(i, j)] * r[i]).sum::<f64>();
                let rn = r.iter().map(|v| v * v).sum::<f64>().sqrt();
                assert!(g.abs() < 1e-10 * norm * rn, "{} column {j}: {g}", solver.name());
            }
            let rss: f64 = r.iter().map(|v| v * v).sum();
            assert!((fit.rss - rss).abs() < 1e-12 * rss);
            assert_eq!(fit.rows, m);
        }
        let qr = QrSolver::default().solve(a.as_ref(), b.as_ref()).unwrap();
        let svd = SvdSolver::default().solve(a.as_ref(), b.as_ref()).unwrap();
        for j in 0..4 {
            assert!((qr.solution[j] - svd.solution[j]).abs() < 1e-12 * qr.solution[j].abs().max(1.0));
            assert!((qr.std_errors[j] - svd.std_errors[j]).abs() < 1e-9 * qr.std_errors[j]);
        }
        assert!((qr.condition - svd.condition).abs() < 1e-9 * qr.condition);
    }
}
