//! The stacked linear system `A λ = β` every assembly fills, its layout by segment, and the checks
//! that come before any work.

use circle_signal::Segment;
use faer::{Col, ColRef, Mat, MatMut, MatRef};
use hb_basis::{Basis, Domain};
use serde::{Deserialize, Serialize};

use hb_model::{Column, Term, columns, term_names};

use crate::error::{AssemblyError, LstsqError, SolveError};
use crate::lstsq::{LstsqFit, LstsqSolver};
use crate::params::IdentifyParams;
use crate::signals::Signals;
use hb_model::form::column_families;

/// Where one segment's equations sit in the stacked system, and what was found on it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Block {
    /// The segment.
    pub segment: Segment,
    /// Its first row (for the harmonic rows, the mean equation; then `cos j`, `sin j` for
    /// `j = 1..=harmonics`).
    pub first_row: usize,
    /// Its number of rows (`2 M_k + 1` for the harmonic rows).
    pub rows: usize,
    /// Harmonics `M_k` balanced (0 for an assembly that does not balance harmonics).
    pub harmonics: usize,
    /// Net turns `m` of the orbit (0 on the line and for oscillating orbits).
    pub winding: i64,
    /// Rotation rate `w_ck = m W / k` (radians per unit time).
    pub rotation_rate: f64,
    /// For a block of a [compressed](LinearSystem::compressed) system, the consecutive segments
    /// whose rows it holds reduced together (`segment` is the first of them); `None` for a
    /// segment's own rows.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub group: Option<Group>,
}

/// The consecutive segments a block of a [compressed](LinearSystem::compressed) system stands
/// for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Group {
    /// How many (at least 1).
    pub segments: usize,
    /// How many of them whirl (net turns other than 0).
    pub whirling: usize,
    /// One past the last sample any of them spans (`start + len` at most).
    pub end: usize,
}

impl Block {
    /// The segments the block stands for: 1, or its group's.
    pub fn segments(&self) -> usize {
        self.group.map_or(1, |g| g.segments)
    }

    /// How many of those whirl.
    pub fn whirling(&self) -> usize {
        self.group.map_or(usize::from(self.winding != 0), |g| g.whirling)
    }

    /// The samples `start .. end` its segments span (`end` one past the last segment's
    /// `start + len`).
    pub fn span(&self) -> (usize, usize) {
        let start = self.segment.start();
        (start, self.group.map_or(start + self.segment.len(), |g| g.end))
    }
}

/// What a [compressed](LinearSystem::compressed) system keeps of the rows it no longer holds:
/// their number, and per line of the residual spectrum (rows grouped by the reduced fraction
/// `j / k` of their harmonic, as [`crate::fit_quality`] groups them) the triangular factor of
/// their `[A | b]`, from which that line's residual at any coefficients follows exactly (a Gram
/// matrix would lose the small residual of a good fit to cancellation).
#[derive(Debug, Clone)]
struct Standing {
    rows: usize,
    lines: Vec<SpectrumLine>,
}

/// One line of a compressed system's residual spectrum.
#[derive(Debug, Clone)]
pub(crate) struct SpectrumLine {
    /// The reduced fraction `(j, k)` (`(0, 1)` for the mean rows).
    pub(crate) key: (usize, usize),
    /// Rows `F` with `Fᵀ F = [A | b]ᵀ [A | b]` of its rows (a triangular factor, or some of its
    /// columns).
    pub(crate) factor: Mat<f64>,
    /// How many rows.
    pub(crate) rows: usize,
}

impl SpectrumLine {
    /// Adds `more` rows (`[a | b]`, `factor`'s width) and `count` rows stood for.
    fn absorb(&mut self, more: MatRef<'_, f64>, count: usize) {
        let (held, cols) = self.factor.shape();
        let mut m = Mat::<f64>::zeros(held + more.nrows(), cols);
        m.get_mut(..held, ..).copy_from(&self.factor);
        m.get_mut(held.., ..).copy_from(more);
        self.factor = crate::lstsq::triangular_factor(m);
        self.rows += count;
    }
}

fn merge_lines(lines: &mut Vec<SpectrumLine>, line: &SpectrumLine) {
    match lines.iter_mut().find(|l| l.key == line.key) {
        Some(l) => l.absorb(line.factor.as_ref(), line.rows),
        None => lines.push(line.clone()),
    }
}

/// The key of row `r` of a block of `k`-period segments' harmonic rows: the reduced fraction of
/// its harmonic `j = ⌈r / 2⌉` over `k`.
pub(crate) fn line_key(r: usize, k: usize) -> (usize, usize) {
    let j = r.div_ceil(2);
    let g = gcd(j, k);
    if j == 0 { (0, 1) } else { (j / g, k / g) }
}

fn gcd(a: usize, b: usize) -> usize {
    if b == 0 { a.max(1) } else { gcd(b, a % b) }
}

/// Most blocks a system is assembled into before its segments' rows are compressed in groups:
/// above it, [`crate::Identifier::systems`] assembles a record's segments in chunks and reduces
/// each group of `⌈segments / MAX_BLOCKS⌉` consecutive segments to its triangular factor, so that
/// the rows held do not grow with the record (see [`LinearSystem::compressed`]).
pub const MAX_BLOCKS: usize = 1 << 16;

/// Groups of segments a long record's systems are assembled in at a time before they are
/// compressed ([`crate::Identifier::systems`]): 2048 groups, a few megabytes of rows per equation.
pub const COMPRESS_CHUNK: usize = 2048;

/// The stacked system `A λ = β` (paper eq. 16) with the names of its unknowns.
///
/// For a period-`k` segment of `L = kP` samples with fundamental `Ω = W / k`, rotation rate `w_ck`
/// and the Fourier coefficients (hb-basis conventions) `u_j, v_j` of its oscillation, `c_ij, d_ij`
/// of `φ_i(x)`, `e_ij, f_ij` of `φ_i(x) cos(W t)` and `g_ij, h_ij` of `φ_i(x) sin(W t)` (absolute
/// time `t`), the rows are (paper eq. 15, method notes section 4):
///
/// ```text
/// mean:   c_r w_ck        + Σ_i [ n_i e_i0/2 + p_i g_i0/2 + q_i c_i0/2 ] = 0
/// cos j:  c_r (jΩ) v_j    + Σ_i [ n_i e_ij   + p_i g_ij   + q_i c_ij   ] = (jΩ)² u_j
/// sin j: −c_r (jΩ) u_j    + Σ_i [ n_i f_ij   + p_i h_ij   + q_i d_ij   ] = (jΩ)² v_j
/// ```
///
/// and likewise for the forcing terms `cos(t)`, `sin(t)` (the Fourier coefficients of
/// `cos(W t)`, `sin(W t)`) and `k*x` (those of `x`). A known forcing is subtracted from the
/// right-hand side.
#[derive(Debug, Clone)]
pub struct LinearSystem {
    matrix: Mat<f64>,
    rhs: Col<f64>,
    names: Vec<String>,
    blocks: Vec<Block>,
    standing: Option<Standing>,
}

impl LinearSystem {
    /// The matrix `A` (rows × unknowns).
    pub fn matrix(&self) -> MatRef<'_, f64> {
        self.matrix.as_ref()
    }

    /// The right-hand side `β`.
    pub fn rhs(&self) -> ColRef<'_, f64> {
        self.rhs.as_ref()
    }

    /// The names of the unknowns, in column order.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// One block per segment, in the order given.
    pub fn blocks(&self) -> &[Block] {
        &self.blocks
    }

    /// Number of rows held (of a [compressed](Self::compressed) system, its factors' rows).
    pub fn rows(&self) -> usize {
        self.matrix.nrows()
    }

    /// Number of equations the system stands for: its rows, or those of the system it was
    /// compressed from.
    pub fn equations(&self) -> usize {
        self.standing.as_ref().map_or(self.rows(), |s| s.rows)
    }

    /// Number of segments its blocks stand for.
    pub fn segments(&self) -> usize {
        self.blocks.iter().map(Block::segments).sum()
    }

    /// Number of those that whirl.
    pub fn whirling_segments(&self) -> usize {
        self.blocks.iter().map(Block::whirling).sum()
    }

    /// Whether the system holds triangular factors of groups of segments' rows
    /// ([`compressed`](Self::compressed)) rather than the rows themselves.
    pub fn is_compressed(&self) -> bool {
        self.standing.is_some()
    }

    /// The same least-squares problem in fewer rows: each run of `group` consecutive blocks (in
    /// the order held) replaced by the triangular factor `R` of its rows' `[A | b]`, at most
    /// `unknowns + 1` rows. Since `[A_g | b_g] = Q R` with `Q` orthonormal,
    /// `‖A_g x − b_g‖² = ‖R [x; −1]‖²` for every `x` and every subset of columns: the minimiser,
    /// the residual sum of squares, the columns' norms, the condition number, each group's share
    /// of a held-out fold and of a bootstrap resample are the rows' own, to rounding. What
    /// counts rows counts those the system stands for ([`equations`](Self::equations)); the
    /// residual spectrum of [`crate::fit_quality`] comes from each line's Gram matrix, kept.
    ///
    /// A group is a block of its own ([`Block::group`]): held-out folds and bootstrap runs then
    /// take groups of segments where they took segments (the bootstrap's run length is found
    /// for the groups as it was for the segments, from how many share a sample).
    ///
    /// Errors: [`SolveError::InvalidParameter`] for a `group` of 0.
    pub fn compressed(self, group: usize) -> Result<LinearSystem, SolveError> {
        if group == 0 {
            return Err(SolveError::InvalidParameter {
                name: "group",
                value: 0.0,
                why: "must be at least one segment",
            });
        }
        let cols = self.unknowns();
        let mut lines = self.standing.as_ref().map_or_else(Vec::new, |s| s.lines.clone());
        if self.standing.is_none() {
            self.add_lines(&mut lines);
        }
        let runs: Vec<&[Block]> = self.blocks.chunks(group).collect();
        let factors: Vec<Mat<f64>> = crate::lstsq::on_factor_pool(|| {
            use rayon::prelude::*;
            runs.par_iter()
                .map(|run| {
                    let rows: usize = run.iter().map(|b| b.rows).sum();
                    let mut m = Mat::<f64>::zeros(rows, cols + 1);
                    let mut at = 0;
                    for b in run.iter() {
                        for c in 0..cols {
                            m.col_mut(c)
                                .subrows_mut(at, b.rows)
                                .copy_from(self.matrix.col(c).subrows(b.first_row, b.rows));
                        }
                        m.col_mut(cols)
                            .subrows_mut(at, b.rows)
                            .copy_from(self.rhs.subrows(b.first_row, b.rows));
                        at += b.rows;
                    }
                    crate::lstsq::triangular_factor(m)
                })
                .collect()
        });
        let total: usize = factors.iter().map(|f| f.nrows()).sum();
        let mut matrix = Mat::<f64>::zeros(total, cols);
        let mut rhs = Col::<f64>::zeros(total);
        let mut blocks = Vec::with_capacity(runs.len());
        let mut at = 0;
        for (run, f) in runs.iter().zip(&factors) {
            let len = f.nrows();
            matrix.get_mut(at..at + len, ..).copy_from(f.get(.., ..cols));
            rhs.subrows_mut(at, len).copy_from(f.col(cols));
            let first = run[0];
            blocks.push(Block {
                first_row: at,
                rows: len,
                group: Some(Group {
                    segments: run.iter().map(Block::segments).sum(),
                    whirling: run.iter().map(Block::whirling).sum(),
                    end: run.iter().map(|b| b.span().1).max().unwrap_or(0),
                }),
                ..first
            });
            at += len;
        }
        Ok(Self {
            matrix,
            rhs,
            standing: Some(Standing {
                rows: self.equations(),
                lines,
            }),
            names: self.names,
            blocks,
        })
    }

    /// Adds the factors of this (uncompressed) system's harmonic rows to `lines`, by line.
    fn add_lines(&self, lines: &mut Vec<SpectrumLine>) {
        let cols = self.unknowns();
        // Each line's rows, row-major.
        let mut gathered: Vec<((usize, usize), Vec<f64>)> = Vec::new();
        for block in &self.blocks {
            if block.harmonics == 0 || block.rows != 2 * block.harmonics + 1 {
                continue;
            }
            let k = block.segment.period();
            for r in 0..block.rows {
                let key = line_key(r, k);
                let at = block.first_row + r;
                let rows = match gathered.iter().position(|(l, _)| *l == key) {
                    Some(i) => &mut gathered[i].1,
                    None => {
                        gathered.push((key, Vec::new()));
                        &mut gathered.last_mut().expect("just pushed").1
                    }
                };
                rows.extend((0..cols).map(|c| self.matrix[(at, c)]));
                rows.push(self.rhs[at]);
            }
        }
        for (key, rows) in gathered {
            let count = rows.len() / (cols + 1);
            let m = Mat::from_fn(count, cols + 1, |i, j| rows[i * (cols + 1) + j]);
            let line = SpectrumLine {
                key,
                factor: crate::lstsq::triangular_factor(m),
                rows: count,
            };
            merge_lines(lines, &line);
        }
    }

    /// The systems of consecutive parts of one record's segments, one after the other: their
    /// rows stacked, their blocks in order. The parts must have the same unknowns; compressed
    /// parts give a compressed system standing for all their rows.
    ///
    /// Errors: [`SolveError::InvalidParameter`] for no part or parts with other unknowns.
    pub fn joined(parts: Vec<LinearSystem>) -> Result<LinearSystem, SolveError> {
        let Some(first) = parts.first() else {
            return Err(SolveError::InvalidParameter {
                name: "parts",
                value: 0.0,
                why: "at least one system must be joined",
            });
        };
        let names = first.names.clone();
        let cols = first.unknowns();
        if let Some(i) = parts.iter().position(|p| p.names != names) {
            return Err(SolveError::InvalidParameter {
                name: "part",
                value: i as f64,
                why: "every part must have the same unknowns",
            });
        }
        let total: usize = parts.iter().map(LinearSystem::rows).sum();
        let compressed = parts.iter().any(LinearSystem::is_compressed);
        let mut matrix = Mat::<f64>::zeros(total, cols);
        let mut rhs = Col::<f64>::zeros(total);
        let mut blocks = Vec::with_capacity(parts.iter().map(|p| p.blocks.len()).sum());
        let (mut at, mut rows) = (0, 0);
        let mut lines: Vec<SpectrumLine> = Vec::new();
        for part in &parts {
            let len = part.rows();
            matrix.get_mut(at..at + len, ..).copy_from(&part.matrix);
            rhs.subrows_mut(at, len).copy_from(&part.rhs);
            blocks.extend(part.blocks.iter().map(|b| Block {
                first_row: b.first_row + at,
                ..*b
            }));
            rows += part.equations();
            if compressed {
                match &part.standing {
                    Some(s) => s.lines.iter().for_each(|l| merge_lines(&mut lines, l)),
                    None => part.add_lines(&mut lines),
                }
            }
            at += len;
        }
        Ok(Self {
            matrix,
            rhs,
            names,
            blocks,
            standing: compressed.then_some(Standing { rows, lines }),
        })
    }

    /// The lines of a compressed system's residual spectrum, `None` for a system that holds its
    /// rows.
    pub(crate) fn spectrum_lines(&self) -> Option<&[SpectrumLine]> {
        self.standing.as_ref().map(|s| s.lines.as_slice())
    }

    /// Number of unknowns.
    pub fn unknowns(&self) -> usize {
        self.matrix.ncols()
    }

    /// The system of the unknowns `columns` only (indices into [`names`](Self::names), kept in
    /// the order given): the same rows, blocks and right-hand side. A column of the stacked
    /// system depends on its own term only, so this is the system a model of those terms alone
    /// assembles (what model selection refits).
    ///
    /// Errors: [`SolveError::InvalidParameter`] for no column, an index out of range or one
    /// given twice.
    pub fn with_columns(&self, columns: &[usize]) -> Result<LinearSystem, SolveError> {
        let bad = |value: f64, why| SolveError::InvalidParameter {
            name: "column index",
            value,
            why,
        };
        if columns.is_empty() {
            return Err(bad(0.0, "at least one column must be kept"));
        }
        for (i, &c) in columns.iter().enumerate() {
            if c >= self.unknowns() {
                return Err(bad(c as f64, "must be less than the number of unknowns"));
            }
            if columns[..i].contains(&c) {
                return Err(bad(c as f64, "each column may be kept once"));
            }
        }
        let matrix = Mat::from_fn(self.rows(), columns.len(), |r, j| self.matrix[(r, columns[j])]);
        // A compressed system's lines keep the kept columns' entries and the right-hand side's.
        let standing = self.standing.as_ref().map(|s| {
            let cols = self.unknowns();
            let keep: Vec<usize> = columns.iter().copied().chain([cols]).collect();
            Standing {
                rows: s.rows,
                lines: s
                    .lines
                    .iter()
                    .map(|l| SpectrumLine {
                        key: l.key,
                        factor: Mat::from_fn(l.factor.nrows(), keep.len(), |i, j| l.factor[(i, keep[j])]),
                        rows: l.rows,
                    })
                    .collect(),
            }
        });
        Ok(Self {
            matrix,
            rhs: self.rhs.clone(),
            names: columns.iter().map(|&c| self.names[c].clone()).collect(),
            blocks: self.blocks.clone(),
            standing,
        })
    }

    /// A system from its parts (every assembly builds the same type).
    pub(crate) fn from_parts(
        matrix: Mat<f64>,
        rhs: Col<f64>,
        names: Vec<String>,
        blocks: Vec<Block>,
    ) -> Self {
        Self {
            matrix,
            rhs,
            names,
            blocks,
            standing: None,
        }
    }

    /// Column `c` of the matrix, contiguous.
    pub(crate) fn column(&self, c: usize) -> &[f64] {
        self.matrix.col_as_slice(c)
    }

    /// The right-hand side, contiguous (an owned column always is).
    pub(crate) fn rhs_slice(&self) -> &[f64] {
        self.rhs
            .as_ref()
            .try_as_col_major()
            .map_or(&[][..], |c| c.as_slice())
    }

    /// The matrix, for tests that build a degenerate system.
    #[cfg(test)]
    pub(crate) fn matrix_mut_for_tests(&mut self) -> faer::MatMut<'_, f64> {
        self.matrix.as_mut()
    }

    /// Multiplies column `c` by `factor` (the noise correction).
    pub(crate) fn scale_column(&mut self, c: usize, factor: f64) {
        self.matrix.col_mut(c).iter_mut().for_each(|v| *v *= factor);
        if let Some(s) = &mut self.standing {
            for l in &mut s.lines {
                l.factor.col_mut(c).iter_mut().for_each(|v| *v *= factor);
            }
        }
    }

    /// Solves by least squares; a rank deficiency names the suspect term.
    pub fn solve<S: LstsqSolver + ?Sized>(&self, solver: &S) -> Result<LstsqFit, SolveError> {
        let fit = match &self.standing {
            Some(s) => solver.solve_standing_for(self.matrix(), self.rhs(), s.rows),
            None => solver.solve(self.matrix(), self.rhs()),
        };
        fit.map_err(|e| match e {
            SolveError::Lstsq(LstsqError::RankDeficient {
                rank,
                unknowns,
                rows,
                column,
                suspect,
            }) => {
                // The solver knows columns by index; give the term's name.
                let suspect = self.names.get(column).cloned().unwrap_or(suspect);
                SolveError::Lstsq(LstsqError::RankDeficient {
                    rank,
                    unknowns,
                    rows,
                    column,
                    suspect,
                })
            }
            other => other,
        })
    }
}

/// What both assemblies check and count before any work.
pub(crate) struct Layout {
    pub(crate) domain: Domain,
    /// The basis functions' names.
    pub(crate) names: Vec<String>,
    /// The unknowns, in column order.
    pub(crate) terms: Vec<Term>,
    /// Their column families, the assemblies' view of them.
    pub(crate) columns: Vec<Column>,
    /// Harmonics `M_k` per segment.
    pub(crate) counts: Vec<usize>,
    /// Total equations.
    pub(crate) rows: usize,
    /// The unknowns' names, as the form names them.
    pub(crate) term_names: Vec<String>,
}

/// Checks the model form against the basis and the segments against the signal, and counts the
/// equations (enough of them for the unknowns).
pub(crate) fn layout<B: Basis + ?Sized>(
    basis: &B,
    signals: &Signals<'_>,
    segments: &[Segment],
    params: &IdentifyParams,
) -> Result<Layout, SolveError> {
    let domain = basis.domain();
    if let Some(record) = signals.domain(signals.own_index())
        && record != domain
    {
        return Err(SolveError::Assembly(AssemblyError::DomainMismatch {
            record,
            basis: domain,
        }));
    }
    let names = basis.names();
    let terms = columns(basis, params.form())?;
    let columns = column_families(&terms);
    let (counts, rows) = plan_rows(signals.own(), segments, params)?;
    check_drive(signals, segments, params)?;
    check_coordinates(signals, &terms, segments, params)?;
    check_enough(segments.len(), rows, terms.len(), params)?;
    Ok(Layout {
        domain,
        names,
        term_names: term_names(basis, params.form()),
        terms,
        columns,
        counts,
        rows,
    })
}

impl Layout {
    /// The names of the unknowns, in column order.
    pub(crate) fn term_names(&self) -> Vec<String> {
        self.term_names.clone()
    }
}

/// One segment's share of the stacked system.
pub(crate) struct RowJob<'a> {
    /// Index of the segment in the caller's order.
    pub(crate) index: usize,
    /// The segment.
    pub(crate) segment: Segment,
    /// Harmonics `M_k` balanced on it.
    pub(crate) harmonics: usize,
    /// Its first row in the stacked system.
    pub(crate) first_row: usize,
    /// Its `2 M_k + 1` rows of `A`.
    pub(crate) a: MatMut<'a, f64>,
    /// Its entries of `β`.
    pub(crate) b: &'a mut [f64],
}

/// Splits the stacked system into each segment's `2 M_k + 1` rows (`counts` from [`plan_rows`]),
/// in the order of `segments`: disjoint views of the column-major matrix, filled in parallel
/// without a copy.
pub(crate) fn split_rows<'a>(
    matrix: MatMut<'a, f64>,
    rhs: &'a mut [f64],
    segments: &[Segment],
    counts: &[usize],
) -> Vec<RowJob<'a>> {
    let mut jobs = Vec::with_capacity(segments.len());
    let (mut rest_a, mut rest_b) = (matrix, rhs);
    let mut first = 0;
    for (i, (s, &m)) in segments.iter().zip(counts).enumerate() {
        let r = 2 * m + 1;
        let (a, ta) = rest_a.split_at_row_mut(r);
        let (b, tb) = rest_b.split_at_mut(r);
        (rest_a, rest_b) = (ta, tb);
        jobs.push(RowJob {
            index: i,
            segment: *s,
            harmonics: m,
            first_row: first,
            a,
            b,
        });
        first += r;
    }
    jobs
}

/// Checks the segments and counts their equations: `(harmonics per segment, total rows)`.
pub(crate) fn plan_rows(
    signal: &[f64],
    segments: &[Segment],
    params: &IdentifyParams,
) -> Result<(Vec<usize>, usize), SolveError> {
    let clock = params.clock();
    let p = clock.require_whole()?;
    let mut counts = Vec::with_capacity(segments.len());
    let mut rows = 0;
    for (i, s) in segments.iter().enumerate() {
        if !s.fits(clock, signal.len()) {
            return Err(SolveError::Assembly(AssemblyError::BadSegment {
                segment: i,
                start: s.start(),
                period: s.period(),
                len: s.len(),
                record: signal.len(),
                samples_per_period: p,
            }));
        }
        if let Some((j, &value)) = signal[s.start()..=s.start() + s.len()]
            .iter()
            .enumerate()
            .find(|(_, v)| !v.is_finite())
        {
            return Err(SolveError::Assembly(AssemblyError::NonFiniteSample {
                segment: i,
                start: s.start(),
                index: s.start() + j,
                value,
            }));
        }
        let m = params.harmonics().count(s.period(), s.len());
        counts.push(m);
        rows += 2 * m + 1;
    }
    Ok((counts, rows))
}

/// When a term has a measured drive: its samples are given (as many as the record's, which
/// [`Signals::with_drives`] checks) and finite on every segment (which fit the record,
/// [`plan_rows`]).
pub(crate) fn check_drive(
    signals: &Signals<'_>,
    segments: &[Segment],
    params: &IdentifyParams,
) -> Result<(), SolveError> {
    let Some(list) = params.form().terms() else {
        return Ok(());
    };
    for d in list.measured_drives() {
        let drive = signals.drive(d).ok_or_else(|| {
            SolveError::Assembly(AssemblyError::MissingDriveSamples {
                term: list.measured_term().unwrap_or_default(),
            })
        })?;
        if drive.len() != signals.len() {
            return Err(SolveError::Assembly(AssemblyError::DriveLengthMismatch {
                drive: drive.len(),
                record: signals.len(),
            }));
        }
        for (i, s) in segments.iter().enumerate() {
            if let Some((j, &value)) = drive[s.start()..=s.closing()]
                .iter()
                .enumerate()
                .find(|(_, v)| !v.is_finite())
            {
                return Err(SolveError::Assembly(AssemblyError::NonFiniteDriveSample {
                    segment: i,
                    start: s.start(),
                    index: s.start() + j,
                    value,
                }));
            }
        }
    }
    Ok(())
}

/// When a term reads other coordinates: they are given, with their domains, and finite on every
/// segment.
fn check_coordinates(
    signals: &Signals<'_>,
    terms: &[Term],
    segments: &[Segment],
    params: &IdentifyParams,
) -> Result<(), SolveError> {
    let mut read: Vec<usize> = terms.iter().flat_map(|t| t.coupling.coordinates()).collect();
    read.sort_unstable();
    read.dedup();
    let own = signals.own_index();
    for c in read.into_iter().filter(|&c| c != own) {
        let missing = || {
            let i = terms
                .iter()
                .position(|t| t.coupling.coordinates().contains(&c))
                .unwrap_or(0);
            let term = params
                .form()
                .terms()
                .map_or_else(String::new, |list| list.name(i));
            SolveError::Assembly(AssemblyError::MissingCoordinate {
                term,
                coordinate: c,
                given: signals.coordinates(),
            })
        };
        let (Some(x), Some(_)) = (signals.coordinate(c), signals.domain(c)) else {
            return Err(missing());
        };
        for (i, s) in segments.iter().enumerate() {
            if let Some((j, &value)) = x[s.start()..=s.closing()]
                .iter()
                .enumerate()
                .find(|(_, v)| !v.is_finite())
            {
                return Err(SolveError::Assembly(AssemblyError::NonFiniteCoordinateSample {
                    segment: i,
                    start: s.start(),
                    coordinate: c,
                    index: s.start() + j,
                    value,
                }));
            }
        }
    }
    Ok(())
}

/// The `TooFewOrbits` check: more equations than unknowns are needed (so that the residual
/// variance is defined); each missing segment is counted as a period-1 orbit.
pub(crate) fn check_enough(
    segments: usize,
    rows: usize,
    unknowns: usize,
    params: &IdentifyParams,
) -> Result<(), SolveError> {
    if rows > unknowns {
        return Ok(());
    }
    let p = params.clock().require_whole()?;
    let per_orbit = 2 * params.harmonics().count(1, p) + 1;
    let missing = unknowns + 1 - rows;
    Err(SolveError::Lstsq(LstsqError::TooFewOrbits {
        found: segments,
        needed: segments + missing.div_ceil(per_orbit),
    }))
}
