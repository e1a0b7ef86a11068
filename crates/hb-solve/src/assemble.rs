//! Assembly of the harmonic-balance equations (paper eqs. 15-16).

use std::f64::consts::TAU;

use circle_signal::{RotationSplit, Segment, unwrap_into, wrap};
use faer::{Col, Mat, MatMut};
use hb_basis::{Basis, Complex64, Domain, FourierPlan, FourierPlanner, coefficients_from_bin};
use rayon::prelude::*;

use crate::error::{AssemblyError, SolveError};
use crate::params::IdentifyParams;
use crate::signals::Signals;
use crate::system::{Block, LinearSystem};
use crate::system::{Layout, RowJob, layout, split_rows};
use crate::velocity::{Series, TrendTables, VelocityTrend, acceleration_into, cell_sign, velocity_into};
use hb_model::Forcing;
use hb_model::{Column, DriveFactor, Factor, MAX_COORDINATES, PositionFactor, Term, VelocityFactor};

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
    /// Buffers of the general terms.
    general: GeneralBuffers,
}

/// Buffers of the terms outside the paper's families.
#[derive(Debug, Clone, Default)]
struct GeneralBuffers {
    /// The samples of one term.
    g: Vec<f64>,
    /// The velocity at every sample, when a term is nonlinear in it.
    xdot: Vec<f64>,
    /// The segment less its trend.
    detrended: Vec<f64>,
    /// The samples of a second part of one term (by parts).
    g2: Vec<f64>,
    /// The basis functions' derivatives at one sample.
    dphi: Vec<f64>,
    /// The own acceleration at every sample, when a term reads it.
    xddot: Vec<f64>,
    /// The other coordinates a term reads ([`Shared::coordinates`]): each one's samples over the
    /// segment (continuous), velocity and acceleration.
    other_x: Vec<Vec<f64>>,
    other_v: Vec<Vec<f64>>,
    other_a: Vec<Vec<f64>>,
    /// A scratch series.
    scratch: Vec<f64>,
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
    signals: &'a Signals<'a>,
    params: &'a IdentifyParams,
    columns: &'a [Column],
    domain: Domain,
    /// The basis functions' names.
    names: &'a [String],
    /// Per basis function: whether a column takes its spectrum.
    used: Vec<bool>,
    /// Per basis function: the columns of it times a drive harmonic `k >= 2` (shift theorem).
    shifted: Vec<Vec<(usize, DriveFactor)>>,
    /// The other general columns.
    others: Vec<(usize, Term)>,
    /// The other coordinates the terms read, in increasing order.
    coordinates: Vec<usize>,
}

impl<'a, B: Basis + ?Sized> Shared<'a, B> {
    fn new(
        basis: &'a B,
        signals: &'a Signals<'a>,
        params: &'a IdentifyParams,
        columns: &'a [Column],
        domain: Domain,
        names: &'a [String],
    ) -> Self {
        let n = names.len();
        let mut used = vec![false; n];
        let mut shifted = vec![Vec::new(); n];
        let mut others = Vec::new();
        for (c, &column) in columns.iter().enumerate() {
            match column {
                Column::Auto(i) | Column::CosT(i) | Column::SinT(i) => used[i] = true,
                Column::Product(t) => match (t.position, t.velocity) {
                    (PositionFactor::Basis(i), VelocityFactor::One) if t.coupling.is_empty() => {
                        used[i] = true;
                        shifted[i].push((c, t.drive));
                    }
                    _ => others.push((c, t)),
                },
                _ => {}
            }
        }
        let own = signals.own_index();
        let mut coordinates: Vec<usize> = others
            .iter()
            .flat_map(|(_, t)| t.coupling.coordinates())
            .filter(|&c| c != own)
            .collect();
        coordinates.sort_unstable();
        coordinates.dedup();
        Self {
            basis,
            signals,
            params,
            columns,
            domain,
            names,
            used,
            shifted,
            others,
            coordinates,
        }
    }
}

/// Assembles the stacked system (paper eq. 16) of `segments` of `signal` for a model on `basis`.
///
/// Segments must satisfy the [`Segment`] invariant for the clock's `P`; each gives `2 M_k + 1`
/// equations (see [`crate::Harmonics`]). On the circle each segment is unwrapped with its closing
/// sample and split into rotation and oscillation ([`RotationSplit`]); on the line it is used as
/// it is. Segments are processed in parallel; FFT plans and buffers are reused.
pub(crate) fn harmonic_rows<B: Basis + ?Sized>(
    basis: &B,
    signals: &Signals<'_>,
    segments: &[Segment],
    params: &IdentifyParams,
) -> Result<LinearSystem, SolveError> {
    refuse_measured_drive(params)?;
    let layout = layout(basis, signals, segments, params)?;
    let signal = signals.own();
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
        general: GeneralBuffers::default(),
    };
    let shared = Shared::new(basis, signals, params, columns, domain, names);

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

/// The paper's rows balance every term's Fourier series over a segment that is (nearly) a
/// periodic orbit of the state, found by its close return. A measured drive is not periodic with
/// such a segment: the clock of a record driven by a measured signal is only its dominant period,
/// and a drive of any waveform (or none periodic at all) does not return with the state, so its
/// series over the segment would not close and its harmonics would not balance. Terms in `p` are
/// refused here; the weak form, which needs no periodic segment, balances them.
fn refuse_measured_drive(params: &IdentifyParams) -> Result<(), SolveError> {
    match params.form().terms().and_then(|list| list.measured_term()) {
        Some(term) => Err(measured_drive_refused(term.to_string())),
        None => Ok(()),
    }
}

/// The refusal of a term in the measured drive `p` by the paper's method.
fn measured_drive_refused(term: String) -> SolveError {
    SolveError::Assembly(AssemblyError::MeasuredDriveUnsupported {
        term,
        method: "the harmonic balance of periodic orbits (upo)",
        why: "an orbit is periodic in the state, not in a measured drive, whose Fourier series over the \
              orbit does not close; use the weak form on windows (windowed)",
    })
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
    let big_w = clock.drive_angular_frequency();
    let omega = seg.fundamental(clock);
    let raw = &sh.signals.own()[seg.start()..=seg.start() + l];

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
            Column::CosT(_) | Column::SinT(_) | Column::Auto(_) | Column::Product(_) => {}
        }
    }
    if let (Forcing::Known { cos, sin }, Some((rc, rs))) = (form.forcing(), forcing_rows) {
        b[rc] -= cos * c0 + sin * s0;
        b[rs] -= -cos * s0 + sin * c0;
    }

    // Basis terms: one transform per function, the modulated ones by the shift theorem.
    for i in (0..n_fn).filter(|&i| sh.used[i]) {
        let row = phi.row(i, l);
        if row.iter().any(|v| !v.is_finite()) {
            let term = sh.basis.name(i).unwrap_or_default();
            return Err(SolveError::Assembly(AssemblyError::NonFiniteTerm {
                segment: index,
                start: seg.start(),
                term,
            }));
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
        // Higher drive harmonics q: a shift by q k bins and the phase q W t_start.
        for &(c, drive) in &sh.shifted[i] {
            let q = drive.harmonic() as usize;
            let phasor = Complex64::from_polar(1.0, q as f64 * theta0);
            for j in 0..=m {
                let (cb, sb) = spec.modulated_bins(j as isize, (q * k) as isize, phasor);
                let bin = match drive {
                    DriveFactor::Sin(_) => sb,
                    DriveFactor::Cos(_) => cb,
                    // `shifted` holds harmonics k >= 2 only (and p is refused before assembly).
                    DriveFactor::One | DriveFactor::Measured(_) => spec.bins()[j],
                };
                put(Some(c), j, bin);
            }
        }
    }

    if !sh.others.is_empty() {
        let view = SegmentView {
            index,
            start: seg.start(),
            raw,
            cont: match sh.domain {
                Domain::Circle => &ws.unwrapped,
                Domain::Line => raw,
            },
            osc,
            theta0,
            k,
            m,
            h: clock.step(),
        };
        general_columns(plan, &mut ws.general, sh, phi, &view, a.as_mut())?;
    }

    let bad_row = (0..a.nrows()).find(|&r| !b[r].is_finite() || (0..cols).any(|c| !a[(r, c)].is_finite()));
    if let Some(row) = bad_row {
        return Err(SolveError::Assembly(AssemblyError::NonFiniteRow {
            segment: index,
            start: seg.start(),
            row,
        }));
    }
    Ok(Block {
        segment,
        first_row,
        rows: 2 * m + 1,
        harmonics: m,
        winding,
        rotation_rate: rate,
        group: None,
    })
}

/// One segment as the general terms see it.
struct SegmentView<'a> {
    index: usize,
    start: usize,
    /// The samples and the closing one, as recorded.
    raw: &'a [f64],
    /// The continuous displacement (unwrapped on the circle), `L + 1` samples.
    cont: &'a [f64],
    /// The oscillation (the continuous displacement less the rotation), `L` samples.
    osc: &'a [f64],
    /// The drive's phase `W t` at the first sample.
    theta0: f64,
    /// Period in forcing periods.
    k: usize,
    /// Harmonics balanced.
    m: usize,
    /// Sample step.
    h: f64,
}

impl SegmentView<'_> {
    /// A drive factor at sample `n`: the phase `q (θ0 + 2π k n / L)`, reduced exactly.
    fn drive(&self, d: DriveFactor, n: usize) -> f64 {
        let l = self.osc.len();
        let phase = |q: u32| {
            let q = q as usize;
            q as f64 * self.theta0 + TAU * ((q * self.k % l) * n % l) as f64 / l as f64
        };
        match d {
            DriveFactor::One => 1.0,
            DriveFactor::Cos(q) => phase(q).cos(),
            DriveFactor::Sin(q) => phase(q).sin(),
            // Refused before assembly (`refuse_measured_drive`): never a number here.
            DriveFactor::Measured(_) => f64::NAN,
        }
    }
}

/// Writes the balance of harmonics `0..=m` of the DFT bins `bin(j)` of one column into column `c`.
fn put_bins(a: &mut MatMut<'_, f64>, c: usize, m: usize, len: usize, bin: impl Fn(usize) -> Complex64) {
    for j in 0..=m {
        let (aj, bj) = coefficients_from_bin(bin(j), j, len);
        if j == 0 {
            a[(0, c)] = aj / 2.0;
        } else {
            a[(2 * j - 1, c)] = aj;
            a[(2 * j, c)] = bj;
        }
    }
}

/// The columns of the terms outside the paper's families (but the basis functions times a drive
/// harmonic, which come from the basis' spectra by the shift theorem):
///
/// - a drive factor alone: its Fourier coefficients in closed form (harmonic `q k` only);
/// - any other: the DFT of its samples `D(t_n) f(x_n) v(x'_n)`, with `x'_n` from the orbit's
///   Fourier series up to the params' velocity harmonics ([`crate::velocity_series`] with
///   [`VelocityTrend::Line`]: the rotation plus the derivative of the oscillation's series, as the
///   damping column's `jΩ` times the oscillation's coefficients), and `sign(x')` averaged over
///   each sample's cell with `x'` linear between samples (so that its jumps fall where the
///   velocity crosses zero, not on the nearest sample).
fn general_columns<B: Basis + ?Sized>(
    plan: &mut FourierPlan,
    buf: &mut GeneralBuffers,
    sh: &Shared<'_, B>,
    phi: Rows<'_>,
    seg: &SegmentView<'_>,
    mut a: MatMut<'_, f64>,
) -> Result<(), SolveError> {
    let l = seg.osc.len();
    let (m, k) = (seg.m, seg.k);
    let coupled = sh.others.iter().any(|(_, t)| !t.coupling.is_empty());
    let series = Series {
        periods: k,
        harmonics: sh.params.velocity_harmonics().count(k, l),
        step: seg.h,
        trend: VelocityTrend::Line,
    };
    if coupled || sh.others.iter().any(|(_, t)| t.velocity != VelocityFactor::One) {
        velocity_into(
            plan,
            &mut TrendTables::default(),
            seg.cont,
            series,
            &mut buf.detrended,
            &mut buf.xdot,
        )?;
    }
    let own = sh.signals.own_index();
    if coupled {
        // The orbit's other coordinates over the same samples: continuous, with the velocity and
        // acceleration of their series (the rotation's line and the oscillation's derivatives).
        acceleration_into(plan, &buf.xdot, seg.h, &mut buf.scratch, &mut buf.xddot)?;
        buf.other_x.resize_with(sh.coordinates.len(), Vec::new);
        buf.other_v.resize_with(sh.coordinates.len(), Vec::new);
        buf.other_a.resize_with(sh.coordinates.len(), Vec::new);
        for (i, &c) in sh.coordinates.iter().enumerate() {
            let x = sh.signals.coordinate(c).expect("checked by the layout");
            let raw = &x[seg.start..=seg.start + l];
            match sh.signals.domain(c) {
                Some(Domain::Circle) => unwrap_into(raw, &mut buf.other_x[i]),
                _ => {
                    buf.other_x[i].clear();
                    buf.other_x[i].extend_from_slice(raw);
                }
            }
            velocity_into(
                plan,
                &mut TrendTables::default(),
                &buf.other_x[i],
                series,
                &mut buf.detrended,
                &mut buf.other_v[i],
            )?;
            acceleration_into(
                plan,
                &buf.other_v[i],
                seg.h,
                &mut buf.scratch,
                &mut buf.other_a[i],
            )?;
        }
    }
    let not_finite = |term: &Term| {
        SolveError::Assembly(AssemblyError::NonFiniteTerm {
            segment: seg.index,
            start: seg.start,
            term: term.name(sh.names),
        })
    };
    for &(c, term) in &sh.others {
        match (term.position, term.velocity) {
            (PositionFactor::One, VelocityFactor::One) if term.coupling.is_empty() => match term.drive {
                DriveFactor::One => a[(0, c)] = 1.0,
                // Refused before assembly (`refuse_measured_drive`).
                DriveFactor::Measured(_) => return Err(measured_drive_refused(term.name(sh.names))),
                DriveFactor::Cos(q) | DriveFactor::Sin(q) => {
                    let j = q as usize * k;
                    if j <= m {
                        let (sq, cq) = (f64::from(q) * seg.theta0).sin_cos();
                        let (ca, cb) = match term.drive {
                            DriveFactor::Cos(_) => (cq, -sq),
                            _ => (sq, cq),
                        };
                        a[(2 * j - 1, c)] = ca;
                        a[(2 * j, c)] = cb;
                    }
                }
            },
            (position, _) if term.coupling.acceleration().is_some() => {
                // An acceleration times a function f of the positions, by parts over the orbit
                // (whose series is periodic): the coefficients of (f q_j')' less those of
                // f' q_j', so that only velocities are taken from the series — the second
                // derivative of a series that does not quite close rings at its seam.
                let j_acc = term.coupling.acceleration().expect("matched");
                buf.g.clear();
                buf.g2.clear();
                let (mut q, mut v) = ([0.0; MAX_COORDINATES], [0.0; MAX_COORDINATES]);
                buf.dphi.resize(sh.names.len(), 0.0);
                for n in 0..l {
                    q[own] = seg.cont[n];
                    v[own] = buf.xdot[n];
                    for (i, &c) in sh.coordinates.iter().enumerate() {
                        q[c] = buf.other_x[i][n];
                        v[c] = buf.other_v[i][n];
                    }
                    let (mut f, mut rate) = match position {
                        PositionFactor::One => (1.0, 0.0),
                        PositionFactor::Basis(i) => {
                            let xe = if sh.domain == Domain::Circle {
                                wrap(seg.cont[n])
                            } else {
                                seg.cont[n]
                            };
                            sh.basis.eval_deriv(xe, &mut buf.dphi);
                            (phi.row(i, l)[n], buf.dphi[i] * v[own])
                        }
                        PositionFactor::Linear => (seg.cont[n], v[own]),
                    };
                    for factor in term.coupling.factors() {
                        if matches!(factor, Factor::Trig { .. } | Factor::Power { .. }) {
                            let value = factor.eval(&q, &v);
                            let d: f64 = (0..MAX_COORDINATES).map(|c| factor.eval_dq(&q, c) * v[c]).sum();
                            rate = rate * value + f * d;
                            f *= value;
                        }
                    }
                    buf.g.push(f * v[j_acc]);
                    buf.g2.push(rate * v[j_acc]);
                }
                if buf.g.iter().chain(&buf.g2).any(|v| !v.is_finite()) {
                    return Err(not_finite(&term));
                }
                let first: Vec<Complex64> = plan.transform(&buf.g)?.bins().to_vec();
                let second = plan.transform(&buf.g2)?;
                let omega = TAU / (l as f64 * seg.h);
                put_bins(&mut a, c, m, l, |j| {
                    let w = j as f64 * omega;
                    let s = first[j];
                    Complex64::new(-w * s.im, w * s.re) - second.bins()[j]
                });
            }
            (position, velocity) => {
                buf.g.clear();
                let (mut q, mut v) = ([0.0; MAX_COORDINATES], [0.0; MAX_COORDINATES]);
                for n in 0..l {
                    let f = match position {
                        PositionFactor::One => 1.0,
                        PositionFactor::Basis(i) => phi.row(i, l)[n],
                        PositionFactor::Linear => seg.raw[n],
                    };
                    let own_v = match velocity {
                        VelocityFactor::One => 1.0,
                        VelocityFactor::Sign => cell_sign(&buf.xdot, n, true),
                        _ => velocity.eval(buf.xdot[n]),
                    };
                    let mut g = seg.drive(term.drive, n) * f * own_v;
                    if !term.coupling.is_empty() {
                        q[own] = seg.cont[n];
                        v[own] = buf.xdot[n];
                        for (i, &c) in sh.coordinates.iter().enumerate() {
                            q[c] = buf.other_x[i][n];
                            v[c] = buf.other_v[i][n];
                        }
                        for factor in term.coupling.factors() {
                            g *= match *factor {
                                Factor::Acceleration { coordinate } => {
                                    let c = usize::from(coordinate);
                                    if c == own {
                                        buf.xddot[n]
                                    } else {
                                        let i = sh.coordinates.binary_search(&c).expect("read");
                                        buf.other_a[i][n]
                                    }
                                }
                                Factor::Velocity {
                                    coordinate,
                                    function: VelocityFactor::Sign,
                                } => {
                                    let i = sh
                                        .coordinates
                                        .binary_search(&usize::from(coordinate))
                                        .expect("read");
                                    cell_sign(&buf.other_v[i], n, true)
                                }
                                other => other.eval(&q, &v),
                            };
                        }
                    }
                    buf.g.push(g);
                }
                if buf.g.iter().any(|v| !v.is_finite()) {
                    return Err(not_finite(&term));
                }
                let spec = plan.transform(&buf.g)?;
                put_bins(&mut a, c, m, l, |j| spec.bins()[j]);
            }
        }
    }
    Ok(())
}
