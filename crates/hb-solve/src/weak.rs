//! The weak form of harmonic balance over windows of the record (method notes section 7).

use std::collections::HashMap;
use std::f64::consts::{PI, TAU};

use circle_signal::Segment;
use circle_signal::{RotationSplit, unwrap_into, wrap};
use faer::{Col, Mat, MatMut};
use hb_basis::{Basis, Domain, FourierPlanner};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{AssemblyError, SolveError};
use crate::method::EquationInput;
use crate::params::IdentifyParams;
use crate::signals::Signals;
use crate::system::{Block, LinearSystem};
use crate::system::{Layout, RowJob, layout, split_rows};
use crate::velocity::{Series, TrendTables, VelocityTrend, cell_sign, velocity_into};
use hb_model::terms::Combination;
use hb_model::{Column, DriveFactor, Factor, MAX_COORDINATES, PositionFactor, Term, VelocityFactor};
use hb_model::{Forcing, Harmonics};

/// Parameters of the weak form: the order `p` of the window `w(τ) = sin^p(π τ / T_s)`.
///
/// On a segment of `k` forcing periods (`L = k P` samples and the closing one, duration
/// `T_s = k T`, local time `τ = t − t_start`), the equation
/// `x'' + c_r x' + Σ_i λ_i g_i(x, t) = 0` (the `g_i` being `φ_i(x)`, `φ_i(x) cos(W t)`,
/// `φ_i(x) sin(W t)`, and `cos(W t)`, `sin(W t)`, `x` when the [`ModelForm`](hb_model::ModelForm) has them) is
/// multiplied by test functions `ψ` that vanish with their first derivative at both ends, and
/// every derivative is moved onto `ψ` by parts:
///
/// ```text
/// ∫ ψ x' = −∫ ψ' x,     ∫ ψ x'' = ∫ ψ'' x     ⇒     c_r (−∫ ψ' x) + Σ_i λ_i ∫ ψ g_i = −∫ ψ'' x.
/// ```
///
/// The test functions are `ψ = w(τ) cos(jΩτ)` for `j = 0..M` and `w(τ) sin(jΩτ)` for
/// `j = 1..M`, `Ω = W / k` (the balance of harmonic `j`, as in paper eq. 15, but of the windowed
/// equation), so a segment gives `2M + 1` rows in the same layout as [`crate::assemble`]. `M` comes
/// from the params' [`Harmonics`] (see [`WeakForm::DEFAULT_HARMONICS`]). On the circle `x` is the
/// unwrapped angle of the window; no derivative of the data is taken and the window need not be
/// periodic, so plain windows (`upo_search::Windows`) serve as well as orbits. Integrals are
/// taken by the trapezoid rule on the samples; since `w` vanishes at the ends with its first
/// `p − 1` derivatives, the rule converges fast: its error falls as `h^(2⌊p/2⌋)` (the
/// Euler–Maclaurin terms of `ψ'' x` start there), so even orders are the economical ones.
///
/// Any other term of a [`ModelForm`](hb_model::ModelForm) (a product `D(t) f(x) v(x')`, see [`Term`](hb_model::Term)):
///
/// - linear in `x'` with a drive factor of the drive's phase (or none), `D(t) f(x) x'` is the
///   time derivative of `D(t) F(x)` less `D'(t) F(x)`, with `F` an antiderivative of `f`
///   ([`hb_basis::Basis::eval_antiderivative`], taken along the unwrapped angle; `x` itself for
///   `f = 1`), so it is integrated by parts exactly: `∫ ψ D f(x) x' = −∫ (ψ' D + ψ D') F(x)`;
/// - with `sign(x')`, `x'*|x'|` or `x'^3`, or `x'` times the measured drive `p` (whose derivative
///   the record does not give): `∫ ψ g` at the velocity of the window's Fourier series
///   ([`crate::velocity_series`] with [`crate::VelocityTrend::Quintic`], up to the params'
///   velocity harmonics), `sign(x')` averaged over each sample's cell so that its jumps fall where
///   the interpolated velocity crosses zero (`docs/identification.md` measures what this costs);
/// - otherwise `∫ ψ g` of its samples, the drive factor at the samples' absolute time, or for
///   the measured drive `p` its sample (`IdentifyParams::measured_drive`) at each of the
///   window's samples: `∫ ψ p f(x)` by the same trapezoid rule as every other sampled term, so
///   that a drive of any waveform (harmonics, noise, no period at all) enters the rows as it was
///   measured.
///
/// `p >= 2` is needed (`ψ'` must vanish at the ends); larger `p` integrates more accurately but
/// concentrates the window on its middle, so that fewer samples carry weight. The default `p = 4`
/// is measured in `docs/identification.md`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(try_from = "WeakFormRaw")]
pub struct WeakForm {
    window_order: u32,
}

/// The serialised form of [`WeakForm`], validated on reading.
#[derive(Debug, Clone, Copy, Deserialize)]
struct WeakFormRaw {
    window_order: u32,
}

impl TryFrom<WeakFormRaw> for WeakForm {
    type Error = SolveError;

    fn try_from(raw: WeakFormRaw) -> Result<Self, SolveError> {
        Self::new(raw.window_order)
    }
}

impl Default for WeakForm {
    fn default() -> Self {
        Self {
            window_order: Self::DEFAULT_WINDOW_ORDER,
        }
    }
}

impl WeakForm {
    /// Default window order `p`.
    pub const DEFAULT_WINDOW_ORDER: u32 = 4;
    /// Largest window order accepted.
    pub const MAX_WINDOW_ORDER: u32 = 64;
    /// Default harmonics per window for the weak form: every `j` with `j / k <= 2`, i.e. test
    /// functions up to twice the forcing frequency (`j = 0..6` on the default 3-period windows).
    /// Without noise more harmonics change little (every coefficient of the paper's data set is
    /// within 1e-6 of the truth from a cap of 1 up); with noise on the angle the right-hand side
    /// `−∫ψ'' x` amplifies it by `(jΩ)²`, and caps above 2 lose accuracy quickly. See
    /// `docs/identification.md` for the measurements behind the choice.
    pub const DEFAULT_HARMONICS: Harmonics = Harmonics::DriveCap(2.0);

    /// The weak form with window order `2 <= p <=` [`MAX_WINDOW_ORDER`](Self::MAX_WINDOW_ORDER).
    pub fn new(window_order: u32) -> Result<Self, SolveError> {
        if !(2..=Self::MAX_WINDOW_ORDER).contains(&window_order) {
            return Err(SolveError::InvalidParameter {
                name: "window order p",
                value: f64::from(window_order),
                why: "must be at least 2 (the window's derivative must vanish at the ends) and at most 64",
            });
        }
        Ok(Self { window_order })
    }

    /// The window order `p`.
    pub fn window_order(&self) -> u32 {
        self.window_order
    }

    /// The test functions of a segment of `len` samples (and the closing one) with `harmonics`
    /// harmonics and sample step `h`: `2M + 1` rows of `len + 1` values of `ψ`, `ψ'` and `ψ''`,
    /// each multiplied by its trapezoid weight, and the drive's phase advance from the first
    /// sample at `drive_angular_frequency` (`W`, radians per unit time).
    pub fn tables(&self, len: usize, harmonics: usize, h: f64, drive_angular_frequency: f64) -> Tables {
        let p = self.window_order as i32;
        let pf = f64::from(self.window_order);
        let samples = len + 1;
        let rows = 2 * harmonics + 1;
        let span = len as f64 * h;
        let a = PI / span;
        let omega = TAU / span;
        let mut t = Tables {
            samples,
            psi: vec![0.0; rows * samples],
            dpsi: vec![0.0; rows * samples],
            ddpsi: vec![0.0; rows * samples],
            turn: (0..samples)
                .map(|n| {
                    let (s, c) = (drive_angular_frequency * n as f64 * h).sin_cos();
                    (c, s)
                })
                .collect(),
        };
        for n in 0..samples {
            let q = if n == 0 || n == len { 0.5 * h } else { h };
            let (s, c) = (PI * n as f64 / len as f64).sin_cos();
            let w = s.powi(p);
            let dw = pf * a * s.powi(p - 1) * c;
            let ddw = pf * a * a * ((pf - 1.0) * s.powi(p - 2) * c * c - w);
            let mut put = |r: usize, v: (f64, f64, f64)| {
                t.psi[r * samples + n] = q * v.0;
                t.dpsi[r * samples + n] = q * v.1;
                t.ddpsi[r * samples + n] = q * v.2;
            };
            put(0, (w, dw, ddw));
            for j in 1..=harmonics {
                let om = j as f64 * omega;
                // The phase from the integer product, exact for every n.
                let (sj, cj) = (TAU * ((j * n) % len) as f64 / len as f64).sin_cos();
                put(
                    2 * j - 1,
                    (
                        w * cj,
                        dw * cj - om * w * sj,
                        ddw * cj - 2.0 * om * dw * sj - om * om * w * cj,
                    ),
                );
                put(
                    2 * j,
                    (
                        w * sj,
                        dw * sj + om * w * cj,
                        ddw * sj + 2.0 * om * dw * cj - om * om * w * sj,
                    ),
                );
            }
        }
        t
    }
}

/// The weighted test functions of one segment shape, row-major (`rows × samples`): the test
/// functions `ψ_r = w cos(jΩτ)`, `w sin(jΩτ)` of a window and their first two derivatives at
/// every sample, what every row of the weak form integrates against ([`WeakForm::tables`]).
#[derive(Debug)]
pub struct Tables {
    /// Samples of the window (its closing one included).
    pub samples: usize,
    /// `ψ_r(τ_n)`, row `r` after row `r − 1`.
    pub psi: Vec<f64>,
    /// `ψ_r'(τ_n)`.
    pub dpsi: Vec<f64>,
    /// `ψ_r''(τ_n)`.
    pub ddpsi: Vec<f64>,
    /// `(cos, sin)(W n h)`: the forcing's phase advance from the window's first sample.
    turn: Vec<(f64, f64)>,
}

impl Tables {
    /// Row `r` of `table` (one of [`Tables::psi`], [`Tables::dpsi`], [`Tables::ddpsi`]).
    pub fn row<'a>(&self, table: &'a [f64], r: usize) -> &'a [f64] {
        &table[r * self.samples..(r + 1) * self.samples]
    }
}

/// Per-worker buffers of one equation.
#[derive(Debug, Clone)]
struct Workspace {
    /// The own coordinate's window less its mean: the data of the right-hand side and of the
    /// damping column.
    xc: Vec<f64>,
    /// Column-major: one column of `samples` values per unknown (`x` less its mean for the
    /// damping), then the second factor of each column integrated by parts.
    g: Vec<f64>,
    /// `(cos W t_n, sin W t_n)` at every sample.
    forcing: Vec<(f64, f64)>,
    /// The antiderivatives of the basis functions at every sample, `anti_stride` per sample.
    anti: Vec<f64>,
    anti_stride: usize,
    /// `(cos kW t_n, sin kW t_n)` for `k = 0..=` the highest drive harmonic, at every sample.
    harmonics: Vec<(f64, f64)>,
    /// Where each combination of [`Shared::trig`] is held in [`Windows`]' sines and cosines.
    trig_slots: Vec<usize>,
    /// The basis functions (and their derivatives) at the samples of the segment, kept for the
    /// next one.
    table: BasisTable,
}

/// The basis functions at every sample of a segment, and their derivatives after them when an
/// acceleration multiplies one, by the sample's place in the record; the last segment's are kept,
/// so that a sample it shares with the next (the windows overlap: with the default hop of one
/// drive period, a sample lies in three) is evaluated once. The functions of a sample depend on
/// that sample alone, so the values are the same numbers either way.
#[derive(Debug, Clone, Default)]
struct BasisTable {
    /// The record the values are of (its first sample's address), and the first sample and the
    /// count of `values`' samples.
    at: (usize, usize, usize),
    /// The basis functions per sample, and the values per sample (twice as many with the
    /// derivatives).
    len: usize,
    stride: usize,
    values: Vec<f64>,
    /// The same of the segment before.
    previous_at: (usize, usize, usize),
    previous: Vec<f64>,
}

impl BasisTable {
    /// The values at the samples of `segment` (the `index`-th) of the equation's own coordinate,
    /// per sample the basis functions, then their derivatives when an acceleration multiplies
    /// one. A function that is not finite is an error naming it.
    fn make<B: Basis + ?Sized>(
        &mut self,
        sh: &Shared<'_, B>,
        segment: &Segment,
        index: usize,
    ) -> Result<(), SolveError> {
        let (basis, signal, deriv) = (sh.basis, sh.signals.own(), sh.needs_dphi);
        let circle = sh.domain == Domain::Circle;
        let (start, samples) = (segment.start(), segment.len() + 1);
        let len = basis.len();
        let stride = if deriv { 2 * len } else { len };
        let source = signal.as_ptr() as usize;
        std::mem::swap(&mut self.values, &mut self.previous);
        self.previous_at = self.at;
        self.at = (source, start, samples);
        (self.len, self.stride) = (len, stride);
        // Every value is written below (copied from the segment before, or evaluated), so the
        // buffer's old values are not cleared first.
        self.values.resize(stride * samples, 0.0);
        // The samples the segment before holds, copied at once.
        let (lo, hi) = if self.previous_at.0 == source {
            copy_shared(
                &mut self.values,
                start,
                &self.previous,
                self.previous_at.1,
                stride,
            )
        } else {
            (0, 0)
        };
        for (n, row) in self.values.chunks_exact_mut(stride).enumerate() {
            let at = start + n;
            if at >= lo && at < hi {
                continue;
            }
            let xr = signal[at];
            let xe = if circle { wrap(xr) } else { xr };
            let (phi, dphi) = row.split_at_mut(len);
            basis.eval(xe, phi);
            if let Some(i) = phi.iter().position(|v| !v.is_finite()) {
                return Err(SolveError::Assembly(AssemblyError::NonFiniteTerm {
                    segment: index,
                    start,
                    term: basis.name(i).unwrap_or_default(),
                }));
            }
            if deriv {
                basis.eval_deriv(xe, dphi);
            }
        }
        Ok(())
    }

    /// The functions at sample `n` of the segment, and their derivatives (empty without them).
    #[inline]
    fn at(&self, n: usize) -> (&[f64], &[f64]) {
        self.values[n * self.stride..(n + 1) * self.stride].split_at(self.len)
    }
}

/// The record's coordinates over one segment, each made continuous (unwrapped on the circle) and
/// its velocity estimated at most once, whatever equations read them: a system's equations are
/// assembled window by window together ([`weak_rows_many`]), and each reads its own coordinate
/// and the others its terms name.
#[derive(Debug, Clone, Default)]
struct Windows {
    /// The segment (start, samples) the entries are of.
    at: Option<(usize, usize)>,
    /// Per coordinate: whether its window is made, unwrapped or not, and the window.
    x: Vec<(Option<bool>, Vec<f64>)>,
    /// Per coordinate: the velocity harmonics its velocity was estimated with, and the velocity.
    v: Vec<(Option<usize>, Vec<f64>)>,
    /// The first `trig_made` entries: a combination of the coordinates and its `(sin, cos)` at
    /// every sample of the segment (the equations of a double pendulum both read
    /// `theta1 − theta2`), of the samples as recorded (wrapped on the circle): the values of a
    /// sample depend on that sample alone, whatever window holds it.
    trig: Vec<(Combination, Vec<(f64, f64)>)>,
    trig_made: usize,
    /// The same of the segment before (start, samples), whose samples the next one shares (the
    /// windows overlap: with the default hop of one drive period, a sample lies in three).
    previous_trig: Vec<(Combination, Vec<(f64, f64)>)>,
    previous_made: usize,
    previous_at: Option<(usize, usize)>,
    /// The window less its trend (scratch of the velocity).
    detrended: Vec<f64>,
    /// The trend's functions of the last window length.
    trend: TrendTables,
    planner: FourierPlanner,
}

impl Windows {
    /// Forgets the entries when `segment` is not the one they are of.
    fn on(&mut self, segment: &Segment, coordinates: usize) {
        let at = Some((segment.start(), segment.len() + 1));
        if self.at != at {
            std::mem::swap(&mut self.trig, &mut self.previous_trig);
            (self.previous_made, self.previous_at) = (self.trig_made, self.at);
            self.at = at;
            self.x
                .resize_with(coordinates.max(self.x.len()), Default::default);
            self.v
                .resize_with(coordinates.max(self.v.len()), Default::default);
            self.x.iter_mut().for_each(|e| e.0 = None);
            self.v.iter_mut().for_each(|e| e.0 = None);
            self.trig_made = 0;
        }
    }

    /// Makes coordinate `c`'s window of the segment, unwrapped when `circle`.
    fn make_window(&mut self, raw: &[f64], c: usize, circle: bool) {
        let (made, x) = &mut self.x[c];
        if *made == Some(circle) {
            return;
        }
        if circle {
            unwrap_into(raw, x);
        } else {
            x.clear();
            x.extend_from_slice(raw);
        }
        *made = Some(circle);
        // A velocity estimated from the other treatment, or a combination of the other
        // window, no longer holds.
        self.v[c].0 = None;
        self.trig_made = 0;
    }

    /// Makes the sines and cosines of `combinations` over the segment from `raw`, each
    /// coordinate's samples of the segment as recorded and whether it is on the circle (wrapped
    /// there), and writes where each is held into `slots`. The samples the segment before made
    /// are copied.
    fn make_trig<'r>(
        &mut self,
        combinations: &[Combination],
        raw: impl Fn(usize) -> (&'r [f64], bool),
        slots: &mut Vec<usize>,
    ) {
        slots.clear();
        let Some((start, samples)) = self.at else {
            return;
        };
        for &combination in combinations {
            if let Some(at) = self.trig[..self.trig_made]
                .iter()
                .position(|(c, _)| *c == combination)
            {
                slots.push(at);
                continue;
            }
            if self.trig.len() == self.trig_made {
                self.trig.push((combination, Vec::new()));
            }
            let (held, values) = &mut self.trig[self.trig_made];
            *held = combination;
            values.clear();
            values.resize(samples, (0.0, 0.0));
            // The samples the segment before holds, copied at once.
            let before = self.previous_at.and_then(|(from, _)| {
                self.previous_trig[..self.previous_made]
                    .iter()
                    .find(|(c, _)| *c == combination)
                    .map(|(_, v)| (from, v))
            });
            let (lo, hi) = match before {
                Some((from, previous)) => copy_shared(values, start, previous, from, 1),
                None => (0, 0),
            };
            // Each coordinate's samples, looked up once per combination.
            let columns: [Option<(&[f64], bool)>; MAX_COORDINATES] =
                std::array::from_fn(|c| (combination.coefficient(c) != 0).then(|| raw(c)));
            let mut q = [0.0; MAX_COORDINATES];
            for (n, value) in values.iter_mut().enumerate() {
                if (lo..hi).contains(&(start + n)) {
                    continue;
                }
                for (c, column) in columns.iter().enumerate() {
                    if let Some((x, circle)) = *column {
                        q[c] = if circle { wrap(x[n]) } else { x[n] };
                    }
                }
                let a = combination.eval(&q);
                *value = (a.sin(), a.cos());
            }
            slots.push(self.trig_made);
            self.trig_made += 1;
        }
    }

    /// `(sin, cos)` of the combination held in `slot` at every sample of the segment.
    #[inline]
    fn trig_values(&self, slot: usize) -> &[(f64, f64)] {
        &self.trig[slot].1
    }

    /// Estimates coordinate `c`'s velocity over the segment (its window made), `series`'
    /// harmonics kept.
    fn make_velocity(&mut self, c: usize, len: usize, series: Series) -> Result<(), SolveError> {
        if self.v[c].0 == Some(series.harmonics) {
            return Ok(());
        }
        let plan = self.planner.plan(len)?;
        velocity_into(
            plan,
            &mut self.trend,
            &self.x[c].1,
            series,
            &mut self.detrended,
            &mut self.v[c].1,
        )?;
        self.v[c].0 = Some(series.harmonics);
        Ok(())
    }

    fn window(&self, c: usize) -> &[f64] {
        &self.x[c].1
    }

    /// Every coordinate's window and velocity, by coordinate (those not made as they were left,
    /// empty when never made).
    fn all(&self) -> ([&[f64]; MAX_COORDINATES], [&[f64]; MAX_COORDINATES]) {
        (
            std::array::from_fn(|c| self.x.get(c).map_or(&[][..], |e| &e.1[..])),
            std::array::from_fn(|c| self.v.get(c).map_or(&[][..], |e| &e.1[..])),
        )
    }

    fn velocity(&self, c: usize) -> &[f64] {
        &self.v[c].1
    }
}

/// Copies into `values`, the entries of the samples from `start` (`stride` per sample), those of
/// `previous`, the entries of the samples from `from`, that both hold (overlapping windows share
/// samples); returns the samples copied, `lo .. hi` in the record (empty when none).
fn copy_shared<T: Copy>(
    values: &mut [T],
    start: usize,
    previous: &[T],
    from: usize,
    stride: usize,
) -> (usize, usize) {
    let (lo, hi) = (
        start.max(from),
        (start + values.len() / stride).min(from + previous.len() / stride),
    );
    if lo < hi {
        values[(lo - start) * stride..(hi - start) * stride]
            .copy_from_slice(&previous[(lo - from) * stride..(hi - from) * stride]);
    }
    (lo, hi)
}

/// How a column's samples become its entries `A[r, c]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Mode {
    /// `Σ ψ_r g_c`.
    Psi,
    /// `−Σ ψ'_r g_c`: `g_c` is an antiderivative of the term (the damping: `x`).
    MinusDpsi,
    /// `−Σ ψ'_r g_c − Σ ψ_r g_s`: by parts with a drive factor, `g_c = D F` and `g_s = D' F` in
    /// column `s` of the second block; or an acceleration times a function of the positions,
    /// `g_c = f q_j'` and `g_s = (df/dt) q_j'`.
    ByParts(usize),
    /// `Σ ψ''_r g_c`: another coordinate's acceleration alone, twice by parts, `g_c = q_j`.
    DdPsi,
}

/// `Σ a_i b_i` (slices of equal length) in the vectors of `simd`, two partial sums: the inner
/// product of every row of the weak form.
#[inline(always)]
pub fn dot<S: pulp::Simd>(simd: S, a: &[f64], b: &[f64]) -> f64 {
    let (a_head, a_tail) = S::as_simd_f64s(a);
    let (b_head, b_tail) = S::as_simd_f64s(b);
    let (mut acc0, mut acc1) = (simd.splat_f64s(0.0), simd.splat_f64s(0.0));
    let mut pairs_a = a_head.chunks_exact(2);
    let mut pairs_b = b_head.chunks_exact(2);
    for (x, y) in (&mut pairs_a).zip(&mut pairs_b) {
        acc0 = simd.mul_add_f64s(x[0], y[0], acc0);
        acc1 = simd.mul_add_f64s(x[1], y[1], acc1);
    }
    for (x, y) in pairs_a.remainder().iter().zip(pairs_b.remainder()) {
        acc0 = simd.mul_add_f64s(*x, *y, acc0);
    }
    let tail: f64 = a_tail.iter().zip(b_tail).map(|(x, y)| x * y).sum();
    simd.reduce_sum_f64s(simd.add_f64s(acc0, acc1)) + tail
}

/// The rows of one window, `A[r, c] = Σ ψ_r g_c` (or `−Σ ψ'_r g_c`, and both parts of a term
/// integrated by parts with a drive factor, see [`Mode`]) and `b[r] = −Σ ψ''_r x`, in the widest
/// SIMD the machine has (chosen at run time: the build itself targets the x86-64 baseline).
struct WindowRows<'a> {
    t: &'a Tables,
    /// One column of `samples` values per unknown, then the second parts.
    g: &'a [f64],
    /// `x` less its mean, the data of the right-hand side.
    x: &'a [f64],
    modes: &'a [Mode],
    samples: usize,
    cols: usize,
    a: MatMut<'a, f64>,
    b: &'a mut [f64],
}

impl pulp::WithSimd for WindowRows<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, simd: S) {
        let WindowRows {
            t,
            g,
            x,
            modes,
            samples,
            cols,
            mut a,
            b,
        } = self;
        let column = |c: usize| &g[c * samples..(c + 1) * samples];
        for (r, br) in b.iter_mut().enumerate() {
            let (psi, dpsi, ddpsi) = (t.row(&t.psi, r), t.row(&t.dpsi, r), t.row(&t.ddpsi, r));
            for (c, mode) in modes.iter().enumerate().take(cols) {
                a[(r, c)] = match *mode {
                    Mode::Psi => dot(simd, psi, column(c)),
                    Mode::MinusDpsi => -dot(simd, dpsi, column(c)),
                    Mode::ByParts(second) => {
                        -dot(simd, dpsi, column(c)) - dot(simd, psi, column(cols + second))
                    }
                    Mode::DdPsi => dot(simd, ddpsi, column(c)),
                };
            }
            *br = -dot(simd, ddpsi, x);
        }
    }
}

/// Assembles the weak-form system of `segments` of `signal` for a model on `basis`: the same
/// [`LinearSystem`] as [`crate::assemble`] (unknowns, names, one [`Block`] of `2M + 1` rows per
/// segment), so that solvers, [`crate::IdentifiedModel`], the bootstrap and the noise correction
/// serve both.
///
/// Segments must satisfy the [`Segment`] invariant for the clock's `P` (including the closing
/// sample, the window's last point) but need not be periodic: `upo_search::Windows` gives plain
/// windows. `M` per segment is `params.harmonics().count(k, L)`. Segments are processed in
/// parallel; the test functions are tabulated once per segment length.
pub(crate) fn weak_rows<B: Basis + ?Sized>(
    basis: &B,
    signals: &Signals<'_>,
    segments: &[Segment],
    params: &IdentifyParams,
    weak: &WeakForm,
) -> Result<LinearSystem, SolveError> {
    let mut systems = weak_rows_many(&[(basis, signals, params)], segments, weak)?;
    Ok(systems.pop().expect("one system per equation"))
}

/// [`weak_rows`] of each of a system's `equations` over the same `segments`, window by window:
/// each coordinate's window is unwrapped and its velocity estimated once per segment for every
/// equation that reads it ([`Windows`]), and each equation's rows are those [`weak_rows`] gives it
/// alone, to the bit. The equations read the same record (their [`Signals`] hold the same
/// coordinates) on the same clock.
pub(crate) fn weak_rows_many<B: Basis + ?Sized>(
    equations: &[EquationInput<'_, B>],
    segments: &[Segment],
    weak: &WeakForm,
) -> Result<Vec<LinearSystem>, SolveError> {
    if !same_record(equations) {
        return equations
            .iter()
            .map(|&(basis, signals, params)| weak_rows(basis, signals, segments, params, weak))
            .collect();
    }
    let layouts = equations
        .iter()
        .map(|&(basis, signals, params)| layout(basis, signals, segments, params))
        .collect::<Result<Vec<Layout>, SolveError>>()?;
    let mut prepared = Vec::with_capacity(equations.len());
    for (&(basis, signals, params), layout) in equations.iter().zip(&layouts) {
        prepared.push(prepare(basis, signals, params, layout, segments, weak));
    }
    let mut outputs: Vec<(Mat<f64>, Vec<f64>)> = layouts
        .iter()
        .map(|l| (Mat::<f64>::zeros(l.rows, l.columns.len()), vec![0.0; l.rows]))
        .collect();
    // Each segment's rows of every equation, filled together.
    let mut jobs: Vec<Vec<RowJob<'_>>> = (0..segments.len())
        .map(|_| Vec::with_capacity(equations.len()))
        .collect();
    for ((matrix, rhs), layout) in outputs.iter_mut().zip(&layouts) {
        for (segment_jobs, job) in
            jobs.iter_mut()
                .zip(split_rows(matrix.as_mut(), rhs, segments, &layout.counts))
        {
            segment_jobs.push(job);
        }
    }
    let coordinates = equations
        .iter()
        .map(|(_, signals, _)| signals.coordinates())
        .max()
        .unwrap_or(1);
    let workspaces: Vec<Workspace> = prepared.iter().map(|p| p.workspace.clone()).collect();
    let per_segment: Vec<Vec<Block>> = jobs
        .into_par_iter()
        .with_min_len(8)
        .map_init(
            || (workspaces.clone(), Windows::default()),
            |(workspaces, windows), segment_jobs: Vec<RowJob<'_>>| {
                segment_jobs
                    .into_iter()
                    .zip(workspaces.iter_mut())
                    .zip(&prepared)
                    .map(|((job, ws), p)| {
                        windows.on(&job.segment, coordinates);
                        let t = &p.tables[&(job.segment.len(), job.harmonics)];
                        fill_block(ws, windows, &p.shared, t, job)
                    })
                    .collect::<Result<Vec<Block>, SolveError>>()
            },
        )
        .collect::<Result<_, SolveError>>()?;

    let mut blocks: Vec<Vec<Block>> = (0..equations.len())
        .map(|_| Vec::with_capacity(segments.len()))
        .collect();
    for segment_blocks in per_segment {
        for (equation_blocks, block) in blocks.iter_mut().zip(segment_blocks) {
            equation_blocks.push(block);
        }
    }
    Ok(outputs
        .into_iter()
        .zip(blocks)
        .zip(&layouts)
        .map(|(((matrix, rhs), blocks), layout)| {
            let rhs = Col::from_fn(layout.rows, |i| rhs[i]);
            LinearSystem::from_parts(matrix, rhs, layout.term_names(), blocks)
        })
        .collect())
}

/// Whether `equations` read the same record on the same clock: the same coordinates (the same
/// samples, not equal ones) with the same domains, so that a coordinate's window and velocity
/// serve each of them.
fn same_record<B: ?Sized>(equations: &[EquationInput<'_, B>]) -> bool {
    let Some(&(_, first, params)) = equations.first() else {
        return true;
    };
    equations.iter().all(|&(_, signals, p)| {
        p.clock() == params.clock()
            && signals.coordinates() == first.coordinates()
            && (0..first.coordinates()).all(|c| {
                signals.domain(c) == first.domain(c)
                    && match (signals.coordinate(c), first.coordinate(c)) {
                        (Some(a), Some(b)) => std::ptr::eq(a, b),
                        _ => false,
                    }
            })
    })
}

/// What one equation's segments share: its columns' modes and needs, its test functions'
/// tables per segment shape, and a workspace to clone per worker.
struct Prepared<'a, B: ?Sized> {
    shared: Shared<'a, B>,
    tables: HashMap<(usize, usize), Tables>,
    workspace: Workspace,
}

/// [`Prepared`] of the equation of `basis`, `signals` and `params` laid out as `layout`.
fn prepare<'a, B: Basis + ?Sized>(
    basis: &'a B,
    signals: &'a Signals<'a>,
    params: &'a IdentifyParams,
    layout: &'a Layout,
    segments: &[Segment],
    weak: &WeakForm,
) -> Prepared<'a, B> {
    let Layout {
        domain,
        ref names,
        ref columns,
        ref counts,
        ..
    } = *layout;
    let cols = columns.len();

    let h = params.clock().step();
    let mut tables: HashMap<(usize, usize), Tables> = HashMap::new();
    let mut max_samples = 0;
    for (s, &m) in segments.iter().zip(counts) {
        tables
            .entry((s.len(), m))
            .or_insert_with(|| weak.tables(s.len(), m, h, params.clock().drive_angular_frequency()));
        max_samples = max_samples.max(s.len() + 1);
    }
    let workspace = Workspace {
        xc: Vec::with_capacity(max_samples),
        g: Vec::with_capacity(cols * max_samples),
        forcing: Vec::with_capacity(max_samples),
        anti: Vec::new(),
        anti_stride: names.len(),
        harmonics: Vec::new(),
        trig_slots: Vec::new(),
        table: BasisTable::default(),
    };

    let mut modes = Vec::with_capacity(cols);
    let mut second = 0;
    for column in columns {
        modes.push(match column {
            Column::Damping => Mode::MinusDpsi,
            Column::Product(t) if !t.coupling.is_empty() => match t.coupling.acceleration() {
                Some(_) if has_positions(t) => {
                    second += 1;
                    Mode::ByParts(second - 1)
                }
                Some(_) => Mode::DdPsi,
                None => Mode::Psi,
            },
            Column::Product(t) if t.velocity == VelocityFactor::Linear && !t.drive.is_measured() => {
                if t.drive == DriveFactor::One {
                    Mode::MinusDpsi
                } else {
                    second += 1;
                    Mode::ByParts(second - 1)
                }
            }
            _ => Mode::Psi,
        });
    }
    // The other coordinates the terms read, whose windows and velocities each segment takes.
    let own = signals.own_index();
    let mut others: Vec<usize> = columns
        .iter()
        .filter_map(|c| match c {
            Column::Product(t) => Some(t.coupling.coordinates()),
            _ => None,
        })
        .flatten()
        .filter(|&c| c != own)
        .collect();
    others.sort_unstable();
    others.dedup();
    let coupled = columns
        .iter()
        .any(|c| matches!(c, Column::Product(t) if !t.coupling.is_empty()));
    let products =
        |f: &dyn Fn(&Term) -> bool| columns.iter().any(|c| matches!(c, Column::Product(t) if f(t)));
    let shared = Shared {
        basis,
        signals,
        params,
        columns,
        domain,
        arch: pulp::Arch::new(),
        modes,
        accelerations: columns
            .iter()
            .map(|c| match c {
                Column::Product(t) => t.coupling.acceleration(),
                _ => None,
            })
            .collect(),
        second,
        drive_harmonics: columns
            .iter()
            .map(|c| match c {
                Column::Product(t) => t.drive.harmonic() as usize,
                _ => 1,
            })
            .max()
            .unwrap_or(1),
        needs_anti: products(&|t| {
            t.velocity == VelocityFactor::Linear && matches!(t.position, PositionFactor::Basis(_))
        }),
        needs_velocity: coupled
            || products(&|t| match t.velocity {
                VelocityFactor::One => false,
                VelocityFactor::Linear => t.drive.is_measured(),
                _ => true,
            }),
        needs_dphi: products(&|t| {
            t.coupling.acceleration().is_some() && matches!(t.position, PositionFactor::Basis(_))
        }),
        drives: (0..signals.drives()).map(|d| signals.drive(d)).collect(),
        others,
        coupled,
        resolved: Vec::new(),
        trig: trig_arguments(columns),
    };
    let resolved = columns
        .iter()
        .map(|c| match c {
            Column::Product(t) => t
                .coupling
                .factors()
                .map(|f| Resolved::new(f, &shared.trig, &shared.others))
                .collect(),
            _ => Vec::new(),
        })
        .collect();
    let shared = Shared { resolved, ..shared };
    Prepared {
        shared,
        tables,
        workspace,
    }
}

/// Whether a term has a function of a position (its own, or another coordinate's).
fn has_positions(t: &Term) -> bool {
    t.position != PositionFactor::One
        || t.coupling
            .factors()
            .any(|f| matches!(f, Factor::Trig { .. } | Factor::Power { .. }))
}

/// What every segment shares.
struct Shared<'a, B: ?Sized> {
    basis: &'a B,
    signals: &'a Signals<'a>,
    params: &'a IdentifyParams,
    columns: &'a [Column],
    domain: Domain,
    /// The machine's SIMD, detected once per assembly.
    arch: pulp::Arch,
    /// How each column is integrated.
    modes: Vec<Mode>,
    /// The coordinate whose acceleration each column's term holds, if it holds one (found once,
    /// not at every sample).
    accelerations: Vec<Option<usize>>,
    /// Columns of the second block (terms integrated by parts with a drive factor).
    second: usize,
    /// The highest drive harmonic of a column.
    drive_harmonics: usize,
    /// Whether a column needs the antiderivatives of the basis.
    needs_anti: bool,
    /// Whether a column needs the velocity at the samples.
    needs_velocity: bool,
    /// Whether a column needs the derivatives of the basis (an acceleration times one).
    needs_dphi: bool,
    /// The measured drives' samples, aligned with the signal's (checked by the layout when a
    /// term has one).
    drives: Vec<Option<&'a [f64]>>,
    /// The other coordinates a term reads, in increasing order.
    others: Vec<usize>,
    /// Whether a term reads another coordinate or an acceleration.
    coupled: bool,
    /// The factors of each column's term in other coordinates, resolved once.
    resolved: Vec<Vec<Resolved>>,
    /// The arguments of the terms' sines and cosines of positions, each once: a term and its
    /// rate, and the terms of an equation, share them (`cos(theta1-theta2)` by parts needs its
    /// sine too, and `sin(theta1-theta2)` is another term's).
    trig: Vec<Combination>,
}

/// Fills one segment's rows; returns its block.
fn fill_block<B: Basis + ?Sized>(
    ws: &mut Workspace,
    windows: &mut Windows,
    sh: &Shared<'_, B>,
    t: &Tables,
    job: RowJob<'_>,
) -> Result<Block, SolveError> {
    let RowJob {
        index,
        segment,
        harmonics,
        first_row,
        mut a,
        b,
    } = job;
    let seg = &segment;
    let clock = sh.params.clock();
    let samples = seg.len() + 1;
    let raw = &sh.signals.own()[seg.start()..seg.start() + samples];
    let cols = sh.columns.len();
    let series = Series {
        periods: seg.period(),
        harmonics: sh.params.velocity_harmonics().count(seg.period(), seg.len()),
        step: clock.step(),
        trend: VelocityTrend::Quintic,
    };

    // The continuous displacement of each coordinate's window and its velocity, made once per
    // segment for every equation that reads the coordinate ([`Windows`]).
    let own = sh.signals.own_index();
    windows.make_window(raw, own, sh.domain == Domain::Circle);
    if sh.needs_velocity {
        windows.make_velocity(own, seg.len(), series)?;
    }
    for &c in &sh.others {
        let x = sh.signals.coordinate(c).expect("checked by the layout");
        let raw = &x[seg.start()..seg.start() + samples];
        windows.make_window(raw, c, sh.signals.domain(c) == Some(Domain::Circle));
        windows.make_velocity(c, seg.len(), series)?;
    }
    if sh.coupled {
        // As the windows were made: the own coordinate in the equation's domain.
        let raw = |c: usize| {
            let x = sh.signals.coordinate(c).expect("checked by the layout");
            let domain = if c == own {
                Some(sh.domain)
            } else {
                sh.signals.domain(c)
            };
            (
                &x[seg.start()..seg.start() + samples],
                domain == Some(Domain::Circle),
            )
        };
        windows.make_trig(&sh.trig, raw, &mut ws.trig_slots);
    }
    let windows = &*windows;
    let x = windows.window(own);
    let xdot: &[f64] = if sh.needs_velocity {
        windows.velocity(own)
    } else {
        &[]
    };
    // The own window less its mean (∫ψ' and ∫ψ'' of a constant vanish, so the mean only adds
    // rounding).
    let (winding, rate) = match sh.domain {
        Domain::Circle => RotationSplit::winding_and_rate(x, clock.step())?,
        Domain::Line => (0, 0.0),
    };
    let mean = x.iter().sum::<f64>() / samples as f64;
    ws.xc.clear();
    ws.xc.extend(x.iter().map(|v| v - mean));

    // g: one column of samples per unknown; the forcing at every sample.
    let width = cols + sh.second;
    // Every entry is written below (each column at every sample, each second part with its
    // column), so the last window's values are not cleared first; a debug build fills them with
    // NaN, which an entry left unwritten would carry into every test's coefficients.
    ws.g.resize(width * samples, 0.0);
    if cfg!(debug_assertions) {
        ws.g.fill(f64::NAN);
    }
    let big_w = clock.drive_angular_frequency();
    let (s0, c0) = (big_w * clock.time(seg.start())).sin_cos();
    ws.table.make(sh, seg, index)?;
    // What the columns read at every sample, made once: the drive's phase (cos, sin of
    // W t_n = W t_start + W n h by the angle-addition formulas), its harmonics (cos, sin of k W t_n
    // by the same formulas, k = 0..=H) and the basis' antiderivatives where a column reads them.
    ws.forcing.clear();
    ws.forcing.extend(
        t.turn[..samples]
            .iter()
            .map(|&(cr, sr)| (c0 * cr - s0 * sr, s0 * cr + c0 * sr)),
    );
    let per_sample = sh.drive_harmonics + 1;
    ws.harmonics.clear();
    if sh.drive_harmonics > 1 {
        for &(c, s) in &ws.forcing {
            let base = ws.harmonics.len();
            ws.harmonics.push((1.0, 0.0));
            for q in 1..=sh.drive_harmonics {
                let (cq, sq) = ws.harmonics[base + q - 1];
                ws.harmonics.push((cq * c - sq * s, sq * c + cq * s));
            }
        }
    }
    let anti_stride = ws.anti_stride;
    if sh.needs_anti {
        ws.anti.resize(anti_stride * samples, 0.0);
        for (row, &xn) in ws.anti.chunks_exact_mut(anti_stride).zip(x) {
            sh.basis.eval_antiderivative(xn, row);
        }
    }

    // Column by column, each term's structure read once per window rather than at every sample;
    // every entry is the same arithmetic, in the same order, as a sample-by-sample fill.
    let Workspace {
        xc,
        g,
        forcing,
        anti,
        harmonics: drive_harmonics,
        trig_slots,
        table,
        ..
    } = ws;
    let (xc, forcing, anti, drive_harmonics, table) = (&*xc, &*forcing, &*anti, &*drive_harmonics, &*table);
    let (g, seconds) = g.split_at_mut(cols * samples);
    let start = seg.start();
    // The drive factor of a term at sample `n`, and its time derivative (never needed for the
    // measured drive: a term in it is never integrated by parts).
    let drive = |term: &Term, n: usize| -> (f64, f64) {
        match term.drive {
            DriveFactor::One => (1.0, 0.0),
            DriveFactor::Measured(i) => (
                sh.drives
                    .get(usize::from(i))
                    .copied()
                    .flatten()
                    .map_or(f64::NAN, |p| p[start + n]),
                0.0,
            ),
            DriveFactor::Cos(k) | DriveFactor::Sin(k) => {
                let (ck, sk) = if k == 1 {
                    forcing[n]
                } else {
                    drive_harmonics[n * per_sample + k as usize]
                };
                let kw = f64::from(k) * big_w;
                match term.drive {
                    DriveFactor::Cos(_) => (ck, -kw * sk),
                    _ => (sk, kw * ck),
                }
            }
        }
    };
    for (col, column) in sh.columns.iter().enumerate() {
        let out = &mut g[col * samples..(col + 1) * samples];
        let mut second = match sh.modes[col] {
            Mode::ByParts(s) => Some(&mut seconds[s * samples..(s + 1) * samples]),
            _ => None,
        };
        match *column {
            Column::Damping => out.copy_from_slice(xc),
            Column::Auto(i) => fill(out, &|n| table.at(n).0[i]),
            Column::CosT(i) => fill(out, &|n| table.at(n).0[i] * forcing[n].0),
            Column::SinT(i) => fill(out, &|n| table.at(n).0[i] * forcing[n].1),
            Column::ForcingCos => fill(out, &|n| forcing[n].0),
            Column::ForcingSin => fill(out, &|n| forcing[n].1),
            Column::Stiffness => out.copy_from_slice(raw),
            Column::Product(ref term) if !term.coupling.is_empty() => {
                // Factor by factor over the window (each a loop of one kind), every entry the
                // same arithmetic in the same order as a sample-by-sample product.
                let factors = &sh.resolved[col];
                let (q, v) = windows.all();
                let held_of = |arg: usize| windows.trig_values(trig_slots[arg]);
                match (sh.accelerations[col], &mut second) {
                    (Some(j), _) if sh.modes[col] == Mode::DdPsi => out.copy_from_slice(&q[j][..samples]),
                    (Some(j), Some(second)) => {
                        // ∫ψ f q_j'' = −∫ψ' f q_j' − ∫ψ (df/dt) q_j': `out` holds f times the
                        // factors so far and `second` its rate, by the product rule.
                        let mut start = |f: &dyn Fn(usize) -> (f64, f64)| {
                            for (n, (g, rate)) in out.iter_mut().zip(second.iter_mut()).enumerate() {
                                let (f, df) = f(n);
                                *g = f;
                                *rate = df * xdot[n];
                            }
                        };
                        match term.position {
                            PositionFactor::One => start(&|_| (1.0, 0.0)),
                            PositionFactor::Basis(i) => start(&|n| {
                                let (phi, dphi) = table.at(n);
                                (phi[i], dphi[i])
                            }),
                            PositionFactor::Linear => start(&|n| (raw[n], 1.0)),
                        }
                        for factor in factors.iter().filter(|r| r.positional()) {
                            factor.fold_with_rate(&q, &v, &held_of, out, second);
                        }
                        for ((g, rate), vj) in out.iter_mut().zip(second.iter_mut()).zip(v[j]) {
                            *rate *= vj;
                            *g *= vj;
                        }
                    }
                    _ => {
                        // `d · f · v` of the drive, the own position and velocity factors, each
                        // in a loop of its own (a factor 1 leaves the product as it is).
                        match term.drive {
                            DriveFactor::One => out.fill(1.0),
                            _ => fill(out, &|n| drive(term, n).0),
                        }
                        match term.position {
                            PositionFactor::One => {}
                            PositionFactor::Basis(i) => scale(out, &|n| table.at(n).0[i]),
                            PositionFactor::Linear => scale(out, &|n| raw[n]),
                        }
                        scale_by(out, xdot, term.velocity);
                        for factor in factors {
                            factor.fold(&q, &v, &held_of, out);
                        }
                    }
                }
            }
            Column::Product(ref term) => {
                for n in 0..samples {
                    let (d, dd) = drive(term, n);
                    let xr = raw[n];
                    out[n] = match term.velocity {
                        VelocityFactor::Linear if !term.drive.is_measured() => {
                            // By parts: an antiderivative F of the function of x along the window.
                            let f = match term.position {
                                PositionFactor::One => xc[n],
                                PositionFactor::Basis(i) => anti[n * anti_stride + i],
                                PositionFactor::Linear => 0.5 * xr * xr,
                            };
                            if let Some(second) = &mut second {
                                second[n] = dd * f;
                            }
                            d * f
                        }
                        velocity => {
                            let f = match term.position {
                                PositionFactor::One => 1.0,
                                PositionFactor::Basis(i) => table.at(n).0[i],
                                PositionFactor::Linear => xr,
                            };
                            let v = match velocity {
                                VelocityFactor::One => 1.0,
                                VelocityFactor::Sign => cell_sign(xdot, n, false),
                                _ => velocity.eval(xdot[n]),
                            };
                            d * f * v
                        }
                    };
                }
            }
        }
    }

    // An acceleration alone is balanced as `Σ ψ'' q_j`: less its mean, like the left-hand side.
    for (col, mode) in sh.modes.iter().enumerate() {
        if *mode == Mode::DdPsi {
            let g = &mut ws.g[col * samples..(col + 1) * samples];
            let mean = g.iter().sum::<f64>() / samples as f64;
            g.iter_mut().for_each(|x| *x -= mean);
        }
    }

    let known = match sh.params.form().forcing() {
        Forcing::Known { cos, sin } => Some((cos, sin)),
        _ => None,
    };
    let rows = b.len();
    sh.arch.dispatch(WindowRows {
        t,
        g: &ws.g,
        x: &ws.xc,
        modes: &sh.modes,
        samples,
        cols,
        a: a.as_mut(),
        b: &mut *b,
    });
    if let Some((fc, fs)) = known {
        for (r, br) in b.iter_mut().enumerate() {
            let (ic, is) = t
                .row(&t.psi, r)
                .iter()
                .zip(&ws.forcing)
                .fold((0.0, 0.0), |(ic, is), (&w, &(c, s))| (ic + w * c, is + w * s));
            *br -= fc * ic + fs * is;
        }
    }

    let bad_row = (0..rows).find(|&r| !b[r].is_finite() || (0..cols).any(|c| !a[(r, c)].is_finite()));
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
        rows: 2 * harmonics + 1,
        harmonics,
        winding,
        rotation_rate: rate,
        group: None,
    })
}

/// Writes `f(n)` into every entry `n` of `out` (a column of a window), in one loop. `f` is
/// called through a pointer: a generic `f` inlined into `fill_block` made the pendulum's whole run
/// 8 % more instructions (callgrind, 2 · 10^5 samples, 0.68 → 0.74 · 10^9).
fn fill(out: &mut [f64], f: &dyn Fn(usize) -> f64) {
    for (n, o) in out.iter_mut().enumerate() {
        *o = f(n);
    }
}

/// Multiplies every entry `n` of `out` by `f(n)`, in one loop (`f` through a pointer, as in
/// [`fill`]).
fn scale(out: &mut [f64], f: &dyn Fn(usize) -> f64) {
    for (n, o) in out.iter_mut().enumerate() {
        *o *= f(n);
    }
}

/// Multiplies every entry `n` of `out` by `function` of the velocity `v` at sample `n` (the
/// sign averaged over the sample's cell, [`cell_sign`]), one loop per function (chosen once,
/// not at every sample).
fn scale_by(out: &mut [f64], v: &[f64], function: VelocityFactor) {
    #[inline(always)]
    fn each(out: &mut [f64], v: &[f64], f: impl Fn(f64) -> f64) {
        for (o, &v) in out.iter_mut().zip(v) {
            *o *= f(v);
        }
    }
    match function {
        VelocityFactor::One => {}
        VelocityFactor::Linear => each(out, v, |v| v),
        VelocityFactor::Square => each(out, v, |v| VelocityFactor::Square.eval(v)),
        VelocityFactor::Cubic => each(out, v, |v| VelocityFactor::Cubic.eval(v)),
        VelocityFactor::Quadratic => each(out, v, |v| VelocityFactor::Quadratic.eval(v)),
        VelocityFactor::Sign => scale(out, &|n| cell_sign(v, n, false)),
    }
}

/// A window's samples of each coordinate (its positions, or its velocities), by coordinate.
type Series8<'a> = [&'a [f64]; MAX_COORDINATES];

/// A factor of a term in other coordinates (or in several), resolved once per assembly: what a
/// sample's value and rate of it read, without looking the factor up at every sample.
#[derive(Debug, Clone, Copy)]
enum Resolved {
    /// `sin` (`sine`) or `cos` of the argument `arg` of [`Shared::trig`], whose sine and cosine
    /// are held per sample; the argument's first `count` coordinates and coefficients, in order
    /// (its rate).
    Trig {
        arg: usize,
        sine: bool,
        terms: [(usize, f64); MAX_COORDINATES],
        count: usize,
    },
    /// `q_c^power`.
    Power { coordinate: usize, power: u8 },
    /// A function of coordinate `c`'s velocity (its sign averaged over the sample's cell).
    Velocity {
        coordinate: usize,
        function: VelocityFactor,
    },
    /// An acceleration: 1 (the column is built around it).
    Acceleration,
}

impl Resolved {
    /// `factor` of a term whose equation holds the sines and cosines of `args`, reading the
    /// other coordinates `others`.
    fn new(factor: &Factor, args: &[Combination], others: &[usize]) -> Self {
        match *factor {
            Factor::Trig { sine, combination } => {
                let mut terms = [(0, 0.0); MAX_COORDINATES];
                let mut count = 0;
                for (c, a) in combination.terms() {
                    terms[count] = (c, f64::from(a));
                    count += 1;
                }
                Resolved::Trig {
                    arg: args
                        .iter()
                        .position(|&a| a == combination)
                        .expect("every argument of the terms is held"),
                    sine,
                    terms,
                    count,
                }
            }
            Factor::Power { coordinate, power } => Resolved::Power {
                coordinate: usize::from(coordinate),
                power,
            },
            Factor::Velocity { coordinate, function } => {
                let c = usize::from(coordinate);
                debug_assert!(others.binary_search(&c).is_ok(), "a coordinate the terms read");
                Resolved::Velocity {
                    coordinate: c,
                    function,
                }
            }
            Factor::Acceleration { .. } => Resolved::Acceleration,
        }
    }

    /// Multiplies every entry of `g` (a column over the window) by the factor's value at its
    /// sample ([`value`](Self::value)), one kind of factor per loop; an acceleration's 1 leaves
    /// them as they are.
    fn fold<'h>(&self, q: &Series8, v: &Series8, held: &impl Fn(usize) -> &'h [(f64, f64)], g: &mut [f64]) {
        match *self {
            Resolved::Acceleration => {}
            Resolved::Trig { arg, sine, .. } => {
                let values = &held(arg)[..g.len()];
                if sine {
                    for (g, &(sin, _)) in g.iter_mut().zip(values) {
                        *g *= sin;
                    }
                } else {
                    for (g, &(_, cos)) in g.iter_mut().zip(values) {
                        *g *= cos;
                    }
                }
            }
            Resolved::Velocity { coordinate, function } => scale_by(g, v[coordinate], function),
            _ => {
                let held = |arg: usize, n: usize| held(arg)[n];
                for (n, g) in g.iter_mut().enumerate() {
                    *g *= self.value(q, v, n, &held);
                }
            }
        }
    }

    /// The product rule over a window: for every sample, `rate ← rate · f + g · f'` and
    /// `g ← g · f`, `f` the factor's value and `f'` its [`rate`](Self::rate).
    fn fold_with_rate<'h>(
        &self,
        q: &Series8,
        v: &Series8,
        held: &impl Fn(usize) -> &'h [(f64, f64)],
        g: &mut [f64],
        rate: &mut [f64],
    ) {
        if let Resolved::Trig {
            arg,
            sine,
            terms,
            count,
        } = *self
        {
            // `value` and `rate` of a sine or cosine, the kind chosen once.
            let values = &held(arg)[..g.len()];
            for (n, ((g, rate), &(sin, cos))) in g.iter_mut().zip(rate.iter_mut()).zip(values).enumerate() {
                let value = if sine { sin } else { cos };
                let d: f64 = terms[..count]
                    .iter()
                    .map(|&(c, a)| {
                        let dq = if sine { a * cos } else { -a * sin };
                        dq * v[c][n]
                    })
                    .sum();
                *rate = *rate * value + *g * d;
                *g *= value;
            }
            return;
        }
        let held = |arg: usize, n: usize| held(arg)[n];
        for (n, (g, rate)) in g.iter_mut().zip(rate.iter_mut()).enumerate() {
            let value = self.value(q, v, n, &held);
            *rate = *rate * value + *g * self.rate(q, v, n, &held);
            *g *= value;
        }
    }

    /// Whether the factor is a function of positions (a sine or cosine, or a power).
    #[inline]
    fn positional(&self) -> bool {
        matches!(self, Resolved::Trig { .. } | Resolved::Power { .. })
    }

    /// [`Factor::eval`] at sample `n` of the positions `q` and velocities `v` (by coordinate),
    /// a sine or cosine from its argument's `(sin, cos)` held at the sample (`held(arg, n)`), a
    /// sign averaged over the sample's cell: the same numbers, each computed once per sample.
    #[inline(always)]
    fn value(&self, q: &Series8, v: &Series8, n: usize, held: &impl Fn(usize, usize) -> (f64, f64)) -> f64 {
        match *self {
            Resolved::Trig { arg, sine, .. } => {
                let (sin, cos) = held(arg, n);
                if sine { sin } else { cos }
            }
            Resolved::Power { coordinate, power } => q[coordinate][n].powi(i32::from(power)),
            Resolved::Velocity {
                coordinate,
                function: VelocityFactor::Sign,
            } => cell_sign(v[coordinate], n, false),
            Resolved::Velocity { coordinate, function } => function.eval(v[coordinate][n]),
            Resolved::Acceleration => 1.0,
        }
    }

    /// The time derivative of a factor of the positions at sample `n`, `Σ_c ∂f/∂q_c q_c'`, a
    /// sine or cosine from its argument's `(sin, cos)` held (0 for a factor of velocities or an
    /// acceleration).
    #[inline(always)]
    fn rate(&self, q: &Series8, v: &Series8, n: usize, held: &impl Fn(usize, usize) -> (f64, f64)) -> f64 {
        match *self {
            Resolved::Trig {
                arg,
                sine,
                terms,
                count,
            } => {
                let (sin, cos) = held(arg, n);
                terms[..count]
                    .iter()
                    .map(|&(c, a)| {
                        let dq = if sine { a * cos } else { -a * sin };
                        dq * v[c][n]
                    })
                    .sum()
            }
            // `Factor::eval_dq` in its own coordinate.
            Resolved::Power { coordinate: c, power } => {
                f64::from(power) * q[c][n].powi(i32::from(power) - 1) * v[c][n]
            }
            Resolved::Velocity { .. } | Resolved::Acceleration => 0.0,
        }
    }
}

/// The arguments of the sines and cosines of positions in the columns' terms, each once.
fn trig_arguments(columns: &[Column]) -> Vec<Combination> {
    let mut args: Vec<Combination> = columns
        .iter()
        .filter_map(|c| match c {
            Column::Product(t) => Some(t.coupling.factors().filter_map(|f| match *f {
                Factor::Trig { combination, .. } => Some(combination),
                _ => None,
            })),
            _ => None,
        })
        .flatten()
        .collect();
    args.sort_unstable();
    args.dedup();
    args
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sines and cosines held per sample, and the factors resolved once, give every factor
    /// and its rate to the bit, as `Factor::eval` and `Factor::eval_dq` compute them afresh.
    #[test]
    fn held_trig_is_bit_identical() {
        let combination = |a: &[i32]| Combination::new(a).expect("a combination");
        let factors = [
            Factor::Trig {
                sine: false,
                combination: combination(&[1, -1]),
            },
            Factor::Trig {
                sine: true,
                combination: combination(&[1, -1]),
            },
            Factor::Trig {
                sine: true,
                combination: combination(&[2, 1]),
            },
            Factor::Trig {
                sine: false,
                combination: combination(&[0, 3]),
            },
            Factor::Power {
                coordinate: 1,
                power: 3,
            },
            Factor::Power {
                coordinate: 0,
                power: 1,
            },
            Factor::Velocity {
                coordinate: 1,
                function: VelocityFactor::Square,
            },
        ];
        let args = {
            let mut a: Vec<Combination> = factors
                .iter()
                .filter_map(|f| match *f {
                    Factor::Trig { combination, .. } => Some(combination),
                    _ => None,
                })
                .collect();
            a.sort_unstable();
            a.dedup();
            a
        };
        let mut q = [0.0; MAX_COORDINATES];
        let mut v = [0.0; MAX_COORDINATES];
        for k in 0..2000 {
            let k = k as f64;
            (q[0], q[1]) = (
                37.0 * (0.37 * k).sin() + 0.01 * k,
                -12.0 * (0.11 * k).cos() - 0.3 * k,
            );
            (v[0], v[1]) = ((0.7 * k).cos() * 9.0, (1.3 * k).sin() * 4.0);
            let trig: Vec<(f64, f64)> = args
                .iter()
                .map(|c| {
                    let a = c.eval(&q);
                    (a.sin(), a.cos())
                })
                .collect();
            for f in &factors {
                let resolved = Resolved::new(f, &args, &[0, 1]);
                let held = |arg: usize, _| trig[arg];
                let (qs, vs): (Series8, Series8) = (
                    std::array::from_fn(|c| &q[c..=c]),
                    std::array::from_fn(|c| &v[c..=c]),
                );
                let value = resolved.value(&qs, &vs, 0, &held);
                assert_eq!(value.to_bits(), f.eval(&q, &v).to_bits());
                let fresh: f64 = match *f {
                    Factor::Trig { combination, .. } => {
                        combination.terms().map(|(c, _)| f.eval_dq(&q, c) * v[c]).sum()
                    }
                    Factor::Power { coordinate, .. } => {
                        let c = usize::from(coordinate);
                        [f.eval_dq(&q, c) * v[c]].into_iter().sum()
                    }
                    _ => 0.0,
                };
                let rate = resolved.rate(&qs, &vs, 0, &held);
                assert_eq!(rate.to_bits(), fresh.to_bits());
            }
        }
    }

    /// A column built factor by factor over the window ([`Resolved::fold`],
    /// [`Resolved::fold_with_rate`]) is, entry by entry, the product taken sample by sample.
    #[test]
    fn folds_over_a_window_are_the_products_sample_by_sample() {
        let combination = Combination::new(&[1, -1]).expect("a combination");
        let factors = [
            Factor::Trig {
                sine: true,
                combination,
            },
            Factor::Power {
                coordinate: 1,
                power: 2,
            },
            Factor::Velocity {
                coordinate: 1,
                function: VelocityFactor::Square,
            },
            Factor::Velocity {
                coordinate: 0,
                function: VelocityFactor::Sign,
            },
            Factor::Trig {
                sine: false,
                combination,
            },
        ];
        let args = [combination];
        let len = 300;
        let series = |f: &dyn Fn(f64) -> f64| (0..len).map(|k| f(k as f64)).collect::<Vec<f64>>();
        let q = [
            series(&|k| 3.0 * (0.05 * k).sin() + 0.02 * k),
            series(&|k| -(0.03 * k).cos()),
        ];
        let v = [series(&|k| (0.07 * k).cos()), series(&|k| 2.0 * (0.13 * k).sin())];
        let trig: Vec<(f64, f64)> = (0..len).map(|n| (q[0][n] - q[1][n]).sin_cos()).collect();
        let (qs, vs): (Series8, Series8) = (
            std::array::from_fn(|c| q.get(c).map_or(&[][..], |s| &s[..])),
            std::array::from_fn(|c| v.get(c).map_or(&[][..], |s| &s[..])),
        );
        let resolved: Vec<Resolved> = factors.iter().map(|f| Resolved::new(f, &args, &[0, 1])).collect();
        let start = series(&|k| 1.0 + 0.5 * (0.2 * k).sin());
        let start_rate = series(&|k| 0.1 * k - 4.0);
        let (mut g, mut rate) = (start.clone(), start_rate.clone());
        let mut plain = start.clone();
        for r in &resolved {
            r.fold(&qs, &vs, &|_| &trig[..], &mut plain);
            if r.positional() {
                r.fold_with_rate(&qs, &vs, &|_| &trig[..], &mut g, &mut rate);
            }
        }
        let held = |_: usize, n: usize| trig[n];
        for n in 0..len {
            let mut one = start[n];
            let (mut gn, mut rn) = (start[n], start_rate[n]);
            for r in &resolved {
                one *= r.value(&qs, &vs, n, &held);
                if r.positional() {
                    let value = r.value(&qs, &vs, n, &held);
                    rn = rn * value + gn * r.rate(&qs, &vs, n, &held);
                    gn *= value;
                }
            }
            assert_eq!(plain[n].to_bits(), one.to_bits(), "sample {n}");
            assert_eq!(g[n].to_bits(), gn.to_bits(), "sample {n}");
            assert_eq!(rate[n].to_bits(), rn.to_bits(), "sample {n}");
        }
    }

    #[test]
    fn window_order_is_validated() {
        assert!(WeakForm::new(1).is_err());
        assert!(WeakForm::new(65).is_err());
        assert_eq!(WeakForm::new(6).unwrap().window_order(), 6);
        assert_eq!(WeakForm::default().window_order(), 4);
    }

    /// Largest error of the discrete integration by parts, `|∫ψ' f + ∫ψ f'|` and
    /// `|∫ψ'' f − ∫ψ f''|` over all rows, for `f = sin(1.3 τ + 0.4)` on a window of duration 10.
    fn by_parts_error(p: u32, len: usize) -> f64 {
        let (m, h) = (6, 10.0 / len as f64);
        let t = WeakForm::new(p).unwrap().tables(len, m, h, 1.0);
        let at = |g: fn(f64) -> f64| (0..=len).map(|n| g(1.3 * n as f64 * h + 0.4)).collect::<Vec<_>>();
        let (f, df, ddf) = (at(f64::sin), at(f64::cos), at(f64::sin));
        let df: Vec<f64> = df.iter().map(|v| 1.3 * v).collect();
        let ddf: Vec<f64> = ddf.iter().map(|v| -1.69 * v).collect();
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        (0..2 * m + 1)
            .map(|r| {
                let e1 = (dot(t.row(&t.dpsi, r), &f) + dot(t.row(&t.psi, r), &df)).abs();
                let e2 = (dot(t.row(&t.ddpsi, r), &f) - dot(t.row(&t.psi, r), &ddf)).abs();
                e1.max(e2)
            })
            .fold(0.0, f64::max)
    }

    /// The tabulated derivatives are those of the tabulated functions, and the trapezoid rule
    /// converges as `h^(2⌊p/2⌋)`.
    #[test]
    fn test_functions_integrate_by_parts() {
        for p in [2, 3, 4, 5, 6, 7, 8] {
            let (coarse, fine) = (by_parts_error(p, 100), by_parts_error(p, 200));
            let order = (coarse / fine).log2();
            let want = f64::from(2 * (p / 2));
            assert!(
                order > want - 0.3 || fine < 1e-13,
                "p {p}: {coarse:e} -> {fine:e}, order {order}"
            );
        }
        assert!(by_parts_error(4, 200) < 1e-7);
        assert!(by_parts_error(8, 200) < 1e-12);
    }
}
