//! Assembly of the harmonic-balance equations (paper eqs. 15-16).

use circle_signal::Segment;
use circle_signal::{RotationSplit, unwrap_into, wrap};
use faer::{Col, ColRef, Mat, MatMut, MatRef};
use hb_basis::{Basis, Complex64, Domain, FourierPlanner, coefficients_from_bin};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::{Forcing, IdentifyParams, LstsqFit, LstsqSolver, ModelForm, SolveError};

/// One unknown of the model, i.e. one column of the system.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Term {
    /// `c_r`, term `x'`.
    Damping,
    /// `n_i`, term `cos(t)*φ_i`.
    CosT(usize),
    /// `p_i`, term `sin(t)*φ_i`.
    SinT(usize),
    /// `q_i`, term `φ_i`.
    Auto(usize),
    /// `F_c`, term `cos(t)`.
    ForcingCos,
    /// `F_s`, term `sin(t)`.
    ForcingSin,
    /// `k`, term `k*x`.
    Stiffness,
}

/// The columns of a model, in order: `x'`; then for each basis function `B` the terms
/// `cos(t)*B`, `sin(t)*B` (if parametric) and `B` (the paper's order n, p, q); then `cos(t)`,
/// `sin(t)` (identified forcing) and `k*x` (linear stiffness).
pub(crate) fn terms(functions: usize, form: &ModelForm) -> Vec<Term> {
    let mut t = vec![Term::Damping];
    for i in 0..functions {
        if form.parametric {
            t.push(Term::CosT(i));
            t.push(Term::SinT(i));
        }
        t.push(Term::Auto(i));
    }
    if form.forcing == Forcing::Identified {
        t.push(Term::ForcingCos);
        t.push(Term::ForcingSin);
    }
    if form.linear_stiffness {
        t.push(Term::Stiffness);
    }
    t
}

pub(crate) fn term_name(term: Term, basis_names: &[String]) -> String {
    match term {
        Term::Damping => "x'".to_owned(),
        Term::CosT(i) => format!("cos(t)*{}", basis_names[i]),
        Term::SinT(i) => format!("sin(t)*{}", basis_names[i]),
        Term::Auto(i) => basis_names[i].clone(),
        Term::ForcingCos => "cos(t)".to_owned(),
        Term::ForcingSin => "sin(t)".to_owned(),
        Term::Stiffness => "k*x".to_owned(),
    }
}

/// The names of the unknowns of a model on `basis` with `form`, in column order (see
/// [`LinearSystem`]): `x'`, then per basis function `B`: `cos(t)*B`, `sin(t)*B`, `B`, then `cos(t)`,
/// `sin(t)`, `k*x` when the form has them.
pub fn term_names<B: Basis + ?Sized>(basis: &B, form: &ModelForm) -> Vec<String> {
    let names = basis.names();
    terms(names.len(), form)
        .into_iter()
        .map(|t| term_name(t, &names))
        .collect()
}

/// Checks that the form's terms exist on the basis' domain.
pub(crate) fn check_form(domain: Domain, form: &ModelForm) -> Result<(), SolveError> {
    if form.linear_stiffness && domain == Domain::Circle {
        return Err(SolveError::TermNotAllowed {
            term: "k*x",
            domain,
            why: "x is an angle known modulo 2π; put sin(x) or hats in the basis instead",
        });
    }
    Ok(())
}

/// Where one segment's equations sit in the stacked system, and what was found on it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Block {
    /// The segment.
    pub segment: Segment,
    /// Its first row (the mean equation); then `cos j`, `sin j` for `j = 1..=harmonics`.
    pub first_row: usize,
    /// Harmonics `M_k` used.
    pub harmonics: usize,
    /// Net turns `m` of the orbit (0 on the line and for oscillating orbits).
    pub winding: i64,
    /// Rotation rate `w_ck = m W / k` (radians per unit time).
    pub rotation_rate: f64,
}

impl Block {
    /// Rows of this block, `2 M_k + 1`.
    pub fn rows(&self) -> usize {
        2 * self.harmonics + 1
    }
}

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

    /// Number of equations.
    pub fn rows(&self) -> usize {
        self.matrix.nrows()
    }

    /// Number of unknowns.
    pub fn unknowns(&self) -> usize {
        self.matrix.ncols()
    }

    /// A system from its parts (the weak form builds the same type).
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

    /// Multiplies column `c` by `factor` (the noise correction).
    pub(crate) fn scale_column(&mut self, c: usize, factor: f64) {
        self.matrix.col_mut(c).iter_mut().for_each(|v| *v *= factor);
    }

    /// Solves by least squares; a rank deficiency names the suspect term.
    pub fn solve<S: LstsqSolver + ?Sized>(&self, solver: &S) -> Result<LstsqFit, SolveError> {
        solver.solve(self.matrix(), self.rhs()).map_err(|e| match e {
            SolveError::RankDeficient {
                rank,
                unknowns,
                rows,
                column,
                suspect,
            } => {
                // The solver knows columns by index; give the term's name.
                let suspect = self.names.get(column).cloned().unwrap_or(suspect);
                SolveError::RankDeficient {
                    rank,
                    unknowns,
                    rows,
                    column,
                    suspect,
                }
            }
            other => other,
        })
    }
}

/// Per-worker buffers, reused over segments.
#[derive(Debug, Clone)]
struct Workspace {
    planner: FourierPlanner,
    unwrapped: Vec<f64>,
    line: Vec<f64>,
    phi: Vec<f64>,
    /// The basis functions over a group's stretch of samples, one row of `span` per function.
    table: Vec<f64>,
    u: Vec<f64>,
    v: Vec<f64>,
}

/// What both assemblies check and count before any work.
pub(crate) struct Layout {
    pub(crate) domain: Domain,
    /// The basis functions' names.
    pub(crate) names: Vec<String>,
    /// The unknowns, in column order.
    pub(crate) terms: Vec<Term>,
    /// Harmonics `M_k` per segment.
    pub(crate) counts: Vec<usize>,
    /// Total equations.
    pub(crate) rows: usize,
}

/// Checks the model form against the basis and the segments against the signal, and counts the
/// equations (enough of them for the unknowns).
pub(crate) fn layout<B: Basis + ?Sized>(
    basis: &B,
    signal: &[f64],
    segments: &[Segment],
    params: &IdentifyParams,
) -> Result<Layout, SolveError> {
    let domain = basis.domain();
    check_form(domain, params.form())?;
    let names = basis.names();
    let terms = terms(names.len(), params.form());
    let (counts, rows) = plan_rows(signal, segments, params)?;
    check_enough(segments.len(), rows, terms.len(), params)?;
    Ok(Layout {
        domain,
        names,
        terms,
        counts,
        rows,
    })
}

/// One segment's share of the stacked system: `(index, segment, harmonics, first row, its rows of
/// A, its entries of b)`.
pub(crate) type RowJob<'a> = (usize, Segment, usize, usize, MatMut<'a, f64>, &'a mut [f64]);

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
        jobs.push((i, *s, m, first, a, b));
        first += r;
    }
    jobs
}

/// Segments whose starts lie within this many samples share one table of the basis.
const GROUP_SPAN: usize = 2048;

/// The basis functions at a segment's samples: rows of a group's table.
#[derive(Clone, Copy)]
struct Rows<'a> {
    table: &'a [f64],
    span: usize,
    offset: usize,
}

impl<'a> Rows<'a> {
    /// Function `i` at the segment's first `len` samples.
    fn row(&self, i: usize, len: usize) -> &'a [f64] {
        let at = i * self.span + self.offset;
        &self.table[at..at + len]
    }
}

/// What every segment shares.
struct Shared<'a, B: ?Sized> {
    basis: &'a B,
    signal: &'a [f64],
    params: &'a IdentifyParams,
    terms: &'a [Term],
    domain: Domain,
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
            return Err(SolveError::BadSegment {
                segment: i,
                start: s.start(),
                period: s.period(),
                len: s.len(),
                record: signal.len(),
                samples_per_period: p,
            });
        }
        if let Some((j, &value)) = signal[s.start()..=s.start() + s.len()]
            .iter()
            .enumerate()
            .find(|(_, v)| !v.is_finite())
        {
            return Err(SolveError::NonFiniteSample {
                segment: i,
                start: s.start(),
                index: s.start() + j,
                value,
            });
        }
        let m = params.harmonics().count(s.period(), s.len());
        counts.push(m);
        rows += 2 * m + 1;
    }
    Ok((counts, rows))
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
    Err(SolveError::TooFewOrbits {
        found: segments,
        needed: segments + missing.div_ceil(per_orbit),
    })
}

/// Assembles the stacked system (paper eq. 16) of `segments` of `signal` for a model on `basis`.
///
/// Segments must satisfy the [`Segment`] invariant for the clock's `P`; each gives `2 M_k + 1`
/// equations (see [`crate::Harmonics`]). On the circle each segment is unwrapped with its closing
/// sample and split into rotation and oscillation ([`RotationSplit`]); on the line it is used as
/// it is. Segments are processed in parallel; FFT plans and buffers are reused.
pub fn assemble<B: Basis + ?Sized>(
    basis: &B,
    signal: &[f64],
    segments: &[Segment],
    params: &IdentifyParams,
) -> Result<LinearSystem, SolveError> {
    let Layout {
        domain,
        names,
        terms,
        counts,
        rows,
    } = layout(basis, signal, segments, params)?;
    let cols = terms.len();

    let mut planner = FourierPlanner::new();
    let mut max_len = 0;
    for s in segments {
        planner.plan(s.len())?;
        max_len = max_len.max(s.len());
    }
    let ws = Workspace {
        planner,
        unwrapped: Vec::with_capacity(max_len + 1),
        line: Vec::with_capacity(max_len),
        phi: vec![0.0; names.len()],
        table: Vec::new(),
        u: Vec::new(),
        v: Vec::new(),
    };
    let shared = Shared {
        basis,
        signal,
        params,
        terms: &terms,
        domain,
    };

    let mut matrix = Mat::<f64>::zeros(rows, cols);
    let mut rhs = vec![0.0; rows];
    let mut jobs = split_rows(matrix.as_mut(), &mut rhs, segments, &counts);
    // Segments overlap (close returns find the same stretch at several periods): group them by
    // start so that each group evaluates the basis once per sample of the stretch it covers.
    jobs.sort_by_key(|job| job.1.start());
    let mut groups: Vec<Vec<_>> = Vec::new();
    let mut group_start = 0;
    for job in jobs {
        match groups.last_mut() {
            Some(g) if job.1.start() - group_start < GROUP_SPAN => g.push(job),
            _ => {
                group_start = job.1.start();
                groups.push(vec![job]);
            }
        }
    }
    let mut blocks: Vec<(usize, Block)> = groups
        .into_par_iter()
        .map_init(
            || ws.clone(),
            |ws, group| {
                let lo = group[0].1.start();
                let hi = group.iter().map(|j| j.1.start() + j.1.len()).max().unwrap_or(lo);
                let span = hi - lo;
                ws.table.clear();
                ws.table.resize(ws.phi.len() * span, 0.0);
                for (n, &x) in signal[lo..hi].iter().enumerate() {
                    let xe = if domain == Domain::Circle { wrap(x) } else { x };
                    basis.eval(xe, &mut ws.phi);
                    for (i, &p) in ws.phi.iter().enumerate() {
                        ws.table[i * span + n] = p;
                    }
                }
                let table = std::mem::take(&mut ws.table);
                let out = group
                    .into_iter()
                    .map(|(i, segment, m, first_row, a, b)| {
                        let rows = Rows {
                            table: &table,
                            span,
                            offset: segment.start() - lo,
                        };
                        let (winding, rotation_rate) = fill_block(ws, &shared, rows, i, &segment, m, a, b)?;
                        Ok((
                            i,
                            Block {
                                segment,
                                first_row,
                                harmonics: m,
                                winding,
                                rotation_rate,
                            },
                        ))
                    })
                    .collect::<Result<Vec<_>, SolveError>>();
                ws.table = table;
                out
            },
        )
        .collect::<Result<Vec<Vec<_>>, SolveError>>()?
        .into_iter()
        .flatten()
        .collect();
    blocks.sort_by_key(|(i, _)| *i);
    let blocks: Vec<Block> = blocks.into_iter().map(|(_, b)| b).collect();

    let rhs = Col::from_fn(rows, |i| rhs[i]);
    let names = terms.iter().map(|&t| term_name(t, &names)).collect();
    let mut system = LinearSystem::from_parts(matrix, rhs, names, blocks);
    crate::noise::correct(basis, signal, params, &mut system)?;
    Ok(system)
}

/// Fills one segment's rows `a` (`2m + 1` rows, all columns) and right-hand side `b`; returns the
/// winding number and rotation rate.
#[allow(clippy::too_many_arguments)]
fn fill_block<B: Basis + ?Sized>(
    ws: &mut Workspace,
    sh: &Shared<'_, B>,
    phi: Rows<'_>,
    index: usize,
    seg: &Segment,
    m: usize,
    mut a: MatMut<'_, f64>,
    b: &mut [f64],
) -> Result<(i64, f64), SolveError> {
    let clock = sh.params.clock();
    let form = sh.params.form();
    let cols = sh.terms.len();
    let (k, l) = (seg.period(), seg.len());
    let big_w = clock.forcing_frequency();
    let omega = big_w / k as f64;
    let raw = &sh.signal[seg.start()..=seg.start() + l];

    // Rotation and oscillation (paper section 2, x_ck = w_ck t + x_var).
    let split;
    let (winding, rate, osc): (i64, f64, &[f64]) = match sh.domain {
        Domain::Circle => {
            unwrap_into(raw, &mut ws.unwrapped);
            split = RotationSplit::new(&ws.unwrapped, clock.step())?;
            (split.winding, split.rate, &split.oscillation)
        }
        Domain::Line => {
            ws.line.clear();
            ws.line.extend_from_slice(&raw[..l]);
            (0, 0.0, &ws.line)
        }
    };
    let plan = ws.planner.plan(l)?;
    let spec = plan.transform(osc)?;
    ws.u.clear();
    ws.v.clear();
    for j in 0..=m {
        let (u, v) = coefficients_from_bin(spec.bins()[j], j, l);
        ws.u.push(u);
        ws.v.push(v);
    }

    // Right-hand side: −x'' balanced harmonic by harmonic (eq. 11).
    b[0] = 0.0;
    for j in 1..=m {
        let jw = j as f64 * omega;
        b[2 * j - 1] = jw * jw * ws.u[j];
        b[2 * j] = jw * jw * ws.v[j];
    }

    // Phase of the forcing at the first sample; cos(W t_n) = cos(θ0 + 2π k n / L).
    let theta0 = big_w * clock.time(seg.start());
    let (s0, c0) = theta0.sin_cos();
    let phasor = Complex64::new(c0, s0);
    // Fourier coefficients of cos(W t) and sin(W t) over the segment: harmonic k only.
    let forcing_rows = (k <= m).then_some((2 * k - 1, 2 * k));

    let n_fn = ws.phi.len();

    for (c, &term) in sh.terms.iter().enumerate() {
        match term {
            Term::Damping => {
                a[(0, c)] = rate;
                for j in 1..=m {
                    let jw = j as f64 * omega;
                    a[(2 * j - 1, c)] = jw * ws.v[j];
                    a[(2 * j, c)] = -jw * ws.u[j];
                }
            }
            Term::ForcingCos => {
                if let Some((rc, rs)) = forcing_rows {
                    a[(rc, c)] = c0;
                    a[(rs, c)] = -s0;
                }
            }
            Term::ForcingSin => {
                if let Some((rc, rs)) = forcing_rows {
                    a[(rc, c)] = s0;
                    a[(rs, c)] = c0;
                }
            }
            Term::Stiffness => {
                let spec = plan.transform(&raw[..l])?;
                a[(0, c)] = spec.bins()[0].re / l as f64;
                for j in 1..=m {
                    let (aj, bj) = coefficients_from_bin(spec.bins()[j], j, l);
                    a[(2 * j - 1, c)] = aj;
                    a[(2 * j, c)] = bj;
                }
            }
            Term::CosT(_) | Term::SinT(_) | Term::Auto(_) => {}
        }
    }
    if let (Forcing::Known { cos, sin }, Some((rc, rs))) = (form.forcing, forcing_rows) {
        b[rc] -= cos * c0 + sin * s0;
        b[rs] -= -cos * s0 + sin * c0;
    }

    // Basis terms: one transform per function, the modulated ones by the shift theorem.
    for i in 0..n_fn {
        let row = phi.row(i, l);
        if row.iter().any(|v| !v.is_finite()) {
            let term = sh.basis.name(i).unwrap_or_default();
            return Err(SolveError::NonFiniteTerm {
                segment: index,
                start: seg.start(),
                term,
            });
        }
        let spec = plan.transform(row)?;
        let col_of = |want: Term| sh.terms.iter().position(|&t| t == want);
        let (auto, cos_t, sin_t) = (
            col_of(Term::Auto(i)),
            col_of(Term::CosT(i)),
            col_of(Term::SinT(i)),
        );
        let mut put = |col: Option<usize>, j: usize, bin: Complex64| {
            if let Some(c) = col {
                let (aj, bj) = coefficients_from_bin(bin, j, l);
                if j == 0 {
                    a[(0, c)] = aj / 2.0;
                } else {
                    a[(2 * j - 1, c)] = aj;
                    a[(2 * j, c)] = bj;
                }
            }
        };
        for j in 0..=m {
            put(auto, j, spec.bins()[j]);
            if cos_t.is_some() || sin_t.is_some() {
                let (cb, sb) = spec.modulated_bins(j as isize, k as isize, phasor);
                put(cos_t, j, cb);
                put(sin_t, j, sb);
            }
        }
    }

    let bad_row = (0..a.nrows()).find(|&r| !b[r].is_finite() || (0..cols).any(|c| !a[(r, c)].is_finite()));
    if let Some(row) = bad_row {
        return Err(SolveError::NonFiniteRow {
            segment: index,
            start: seg.start(),
            row,
        });
    }
    Ok((winding, rate))
}
