//! Assembly of the harmonic-balance equations (paper eqs. 15-16).

use circle_signal::{RotationSplit, Segment, unwrap_into, wrap};
use faer::{Col, Mat};
use hb_basis::{Basis, Complex64, Domain, FourierPlanner, coefficients_from_bin};
use rayon::prelude::*;

use crate::system::{Layout, RowJob, layout, split_rows};
use crate::terms::Column;
use crate::{Block, Forcing, IdentifyParams, LinearSystem, SolveError};

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
    columns: &'a [Column],
    domain: Domain,
}

/// Assembles the stacked system (paper eq. 16) of `segments` of `signal` for a model on `basis`.
///
/// Segments must satisfy the [`Segment`] invariant for the clock's `P`; each gives `2 M_k + 1`
/// equations (see [`crate::Harmonics`]). On the circle each segment is unwrapped with its closing
/// sample and split into rotation and oscillation ([`RotationSplit`]); on the line it is used as
/// it is. Segments are processed in parallel; FFT plans and buffers are reused.
pub(crate) fn harmonic_rows<B: Basis + ?Sized>(
    basis: &B,
    signal: &[f64],
    segments: &[Segment],
    params: &IdentifyParams,
) -> Result<LinearSystem, SolveError> {
    let layout = layout(basis, signal, segments, params)?;
    let Layout {
        domain,
        ref names,
        ref columns,
        ref counts,
        rows,
        ..
    } = layout;
    let cols = columns.len();

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
        columns,
        domain,
    };

    let mut matrix = Mat::<f64>::zeros(rows, cols);
    let mut rhs = vec![0.0; rows];
    let mut jobs = split_rows(matrix.as_mut(), &mut rhs, segments, counts);
    // Segments overlap (close returns find the same stretch at several periods): group them by
    // start so that each group evaluates the basis once per sample of the stretch it covers.
    jobs.sort_by_key(|job| job.segment.start());
    let mut groups: Vec<Vec<_>> = Vec::new();
    let mut group_start = 0;
    for job in jobs {
        match groups.last_mut() {
            Some(g) if job.segment.start() - group_start < GROUP_SPAN => g.push(job),
            _ => {
                group_start = job.segment.start();
                groups.push(vec![job]);
            }
        }
    }
    let mut blocks: Vec<(usize, Block)> = groups
        .into_par_iter()
        .map_init(
            || ws.clone(),
            |ws, group| {
                let lo = group[0].segment.start();
                let hi = group.iter().map(|j| j.segment.closing()).max().unwrap_or(lo);
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
                    .map(|job| {
                        let rows = Rows {
                            table: &table,
                            span,
                            offset: job.segment.start() - lo,
                        };
                        Ok((job.index, fill_block(ws, &shared, rows, job)?))
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
    Ok(LinearSystem::from_parts(matrix, rhs, layout.term_names(), blocks))
}

/// Fills one segment's rows (`2m + 1` rows of `A`, all columns) and right-hand side; returns its
/// block.
fn fill_block<B: Basis + ?Sized>(
    ws: &mut Workspace,
    sh: &Shared<'_, B>,
    phi: Rows<'_>,
    job: RowJob<'_>,
) -> Result<Block, SolveError> {
    let RowJob {
        index,
        segment,
        harmonics: m,
        first_row,
        mut a,
        b,
    } = job;
    let seg = &segment;
    let clock = sh.params.clock();
    let form = sh.params.form();
    let cols = sh.columns.len();
    let (k, l) = (seg.period(), seg.len());
    let big_w = clock.forcing_frequency();
    let omega = seg.fundamental(clock);
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

    for (c, &column) in sh.columns.iter().enumerate() {
        match column {
            Column::Damping => {
                a[(0, c)] = rate;
                for j in 1..=m {
                    let jw = j as f64 * omega;
                    a[(2 * j - 1, c)] = jw * ws.v[j];
                    a[(2 * j, c)] = -jw * ws.u[j];
                }
            }
            Column::ForcingCos => {
                if let Some((rc, rs)) = forcing_rows {
                    a[(rc, c)] = c0;
                    a[(rs, c)] = -s0;
                }
            }
            Column::ForcingSin => {
                if let Some((rc, rs)) = forcing_rows {
                    a[(rc, c)] = s0;
                    a[(rs, c)] = c0;
                }
            }
            Column::Stiffness => {
                let spec = plan.transform(&raw[..l])?;
                a[(0, c)] = spec.bins()[0].re / l as f64;
                for j in 1..=m {
                    let (aj, bj) = coefficients_from_bin(spec.bins()[j], j, l);
                    a[(2 * j - 1, c)] = aj;
                    a[(2 * j, c)] = bj;
                }
            }
            Column::CosT(_) | Column::SinT(_) | Column::Auto(_) => {}
        }
    }
    if let (Forcing::Known { cos, sin }, Some((rc, rs))) = (form.forcing(), forcing_rows) {
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
        let col_of = |want: Column| sh.columns.iter().position(|&t| t == want);
        let (auto, cos_t, sin_t) = (
            col_of(Column::Auto(i)),
            col_of(Column::CosT(i)),
            col_of(Column::SinT(i)),
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
    Ok(Block {
        segment,
        first_row,
        rows: 2 * m + 1,
        harmonics: m,
        winding,
        rotation_rate: rate,
    })
}
