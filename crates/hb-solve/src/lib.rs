//! Harmonic-balance identification of a forced oscillator from periodic pieces of one record.
//!
//! The model (paper eq. 2, specialised as eq. 6 for the pendulum) is linear in its unknowns:
//!
//! ```text
//! c_r x' + k x + Σ_i q_i φ_i(x) + Σ_i [n_i cos(W t) + p_i sin(W t)] φ_i(x) + F_c cos(W t) + F_s sin(W t) = −x''
//! ```
//!
//! with a basis `{φ_i}` from `hb-basis` and the terms chosen by a [`ModelForm`](hb_model::ModelForm) (`k x` and the
//! external forcing `F` are optional; the parametric terms and the forcing may have the drive's
//! harmonics `2..H` too). More generally the model is `x'' + Σ_i c_i g_i = 0` with any terms
//! `g_i`, each the product of a drive factor (`1`, `cos(kt)`, `sin(kt)`), a function of `x` (`1`
//! or a basis function) and a function of `x'` (`1`, `x'`, `sign(x')`, `x'*|x'|`, `x'^3`), listed
//! by a [`TermList`](hb_model::TermList) (parsed from text such as `x', sign(x'), {1,cos(t),sin(t)}*{cos(x),sin(x)}`)
//! and given by [`ModelForm::from_terms`](hb_model::ModelForm::from_terms). Over a period-`k` orbit segment of `L = kP` samples, every
//! signal is expanded in a Fourier series of the orbit's fundamental `Ω = W / k` (eqs. 7-14); for an
//! angle on the circle the segment is first unwrapped and split into a constant rotation `w_ck t`
//! and an oscillation `x_var` (section 2, Figure 1), so `x' = w_ck + Σ ...` (eq. 10) and
//! `x'' = −Σ (jΩ)² (...)` (eq. 11). Balancing the mean and harmonics `j = 1..M` gives `2M + 1`
//! linear equations per orbit (eq. 15, see [`LinearSystem`]); those of all orbits are stacked
//! (eq. 16) and solved in the least-squares sense (eq. 17) by a column-pivoted QR or a thin SVD
//! ([`LstsqSolver`]), never through the normal equations.
//!
//! Time is the data's own: `P` samples per forcing period `T`, `h = T / P`, `W = 2π / T`, and the
//! forcing terms use the absolute time `t_n = t_0 + n h` of each sample ([`SampleClock`](circle_signal::SampleClock)); with the
//! paper's non-dimensional time (`T = 2π`) the rows are exactly those of the method notes.
//!
//! The result is an [`IdentifiedModel`]: coefficients with standard errors (`s² (AᵀA)⁻¹` from the
//! factorisation), the condition number and residual of the fit, simulation through
//! `pendulum_sim::SecondOrderSystem`, and JSON or compact binary save/load.
//!
//! Beyond the paper:
//!
//! - the weak form ([`WeakForm`], [`assemble_weak`]): the equation is multiplied
//!   by test functions `w(τ) cos(jΩτ)`, `w(τ) sin(jΩτ)` with a window `w = sin^p(π τ / T_s)` that
//!   vanishes with its first derivative at both ends of a segment, and integrated by parts, so no
//!   derivative of the data is taken and no segment needs to be periodic: plain windows of the
//!   record (`upo_search::Windows`) replace the orbits, and the equations come out in the same
//!   [`LinearSystem`];
//! - confidence intervals for every coefficient by a seeded moving-block bootstrap over segments
//!   ([`bootstrap`]), for either method;
//! - a correction of the bias `E[cos(k(x + n))] = e^{−k²σ²/2} cos(kx)` that Gaussian noise on a
//!   measured angle puts into the trigonometric terms ([`NoiseCorrection`]), with `σ` given or
//!   estimated from the record ([`estimate_noise_sigma`]).
//!
//! The whole recipe of one equation (assemble, select terms, solve, measure the fit, bootstrap)
//! is [`identifier`]'s: a [`ModelSpec`] checked on the record's clock into an [`Identifier`]; a
//! system of several coordinates runs one per equation on the same segments.
//!
//! # Example
//!
//! A linear oscillator `x'' + 0.1 x' + 2 x = cos t` has the exactly periodic solution
//! `x = A cos t + B sin t` with `A = 1/1.01`, `B = 0.1/1.01`. With the forcing known, damping and
//! stiffness come back exactly from one orbit:
//!
//! ```
//! use hb_basis::Polynomial;
//! use circle_signal::{SampleClock, Segment};
//! use hb_model::{Forcing, ModelForm};
//! use hb_solve::{HarmonicBalance, IdentifyParams, QrSolver, identify};
//!
//! let p = 25;
//! let clock = SampleClock::nondimensional(p)?.with_start_time(3.7)?;
//! let x: Vec<f64> = (0..=p)
//!     .map(|n| {
//!         let t = clock.time(n);
//!         (t.cos() + 0.1 * t.sin()) / 1.01
//!     })
//!     .collect();
//! let segment = Segment::new(0, 1, &clock, 0.0, x.len())?;
//! // The term cos(t) sits on the left with x'': its known coefficient is −1.
//! let form = ModelForm::externally_forced(Forcing::Known { cos: -1.0, sin: 0.0 });
//! let params = IdentifyParams::builder(clock).form(form.clone()).build()?;
//! let model = identify(Polynomial::new(1)?, &x, &[segment], &params, &HarmonicBalance, &QrSolver::default())?;
//! assert!((model.damping() - 0.1).abs() < 1e-12);
//! assert!((model.coefficient("x").unwrap().value - 2.0).abs() < 1e-12);
//!
//! // The weak form on plain windows of 2 forcing periods, which need not close: any stretch of
//! // the record works. Here a transient `e^{−0.05 t} cos(1.4 t)` is added, a solution of the
//! // homogeneous equation, so that no window is periodic.
//! let s = (2.0f64 - 0.0025).sqrt();
//! let x: Vec<f64> = (0..=10 * p)
//!     .map(|n| {
//!         let t = clock.time(n);
//!         (t.cos() + 0.1 * t.sin()) / 1.01 + (-0.05 * t).exp() * (s * t).cos()
//!     })
//!     .collect();
//! let windows = upo_search::Windows::builder(&clock).domain(circle_signal::Domain::Line).build()?;
//! let params = IdentifyParams::builder(clock)
//!     .form(form)
//!     .harmonics(hb_solve::WeakForm::DEFAULT_HARMONICS)
//!     .build()?;
//! let model = hb_solve::identify_from_source(
//!     Polynomial::new(1)?, &x, &windows, &params, &hb_solve::WeakForm::default(), &QrSolver::default(),
//! )?;
//! assert!((model.damping() - 0.1).abs() < 1e-6);
//! assert!((model.coefficient("x").unwrap().value - 2.0).abs() < 1e-6);
//!
//! // Every method sits behind the one trait `Assembly`: a program chooses it at run time.
//! let methods: [Box<dyn hb_solve::Assembly>; 2] =
//!     [Box::new(hb_solve::WeakForm::default()), Box::new(hb_solve::FiniteDifferences)];
//! let segments = upo_search::OrbitSource::segments(&windows, &x)?;
//! for method in &methods {
//!     let model = identify(Polynomial::new(1)?, &x, &segments, &params, method.as_ref(), &QrSolver::default())?;
//!     assert!((model.damping() - 0.1).abs() < 1e-3, "{}", method.name());
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![deny(missing_docs)]

mod assemble;
mod bootstrap;
mod differences;
pub mod drift;
mod error;
mod fit;
pub mod identifier;
mod lstsq;
mod method;
mod noise;
mod params;
mod quality;
mod select;
mod signals;
mod system;
mod tie;
mod velocity;
mod weak;

/// The building blocks of the weak form and of the least squares, for identifications built
/// beside this crate's (the drive-period search of `hb-drive` assembles the weak form on a
/// record's own grid for many candidate periods): the test functions of a window
/// ([`WeakForm::tables`]), the inner product of a row, the triangular factor of a block of rows,
/// and the factorisations' own thread pool.
pub mod kernel {
    pub use crate::lstsq::{on_factor_pool, triangular_factor};
    pub use crate::weak::{Tables, dot};
}

pub use bootstrap::{
    Bootstrap, BootstrapParams, BootstrapParamsBuilder, Interval, NORMAL_EQUATIONS_CONDITION, NoIntervals,
    ResampleBlock, bootstrap, bootstrap_fit, bootstrap_or_reason,
};
pub use differences::FiniteDifferences;
pub use error::{AssemblyError, BootstrapError, LstsqError, SelectError, SolveError, TieError};
pub use fit::FitModel;
pub use identifier::{
    Identification, Identifier, IdentifyStep, Method, ModelSpec, TIED_NO_INTERVALS, TermSelection,
    TiedIdentification, UnknownMethod, identify_tied,
};
pub use lstsq::{LstsqFit, LstsqSolver, QrSolver, RankTolerance, SvdSolver};
pub use method::{Assembly, EquationInput, HarmonicBalance};
pub use noise::{NOISE_BAND_START, NOISE_ESTIMATE_MIN_LEN, correct_noise, estimate_noise_sigma};
pub use params::{IdentifyParams, IdentifyParamsBuilder, NoiseCorrection};
pub use quality::{
    EXPLAINED_WARNING_ORBITS, EXPLAINED_WARNING_WINDOWS, FitQuality, HELD_OUT_FOLDS, HELD_OUT_LOSS_RATIO,
    HeldOut, ResidualLine, fit_quality, held_out,
};
pub use select::{DroppedTerm, SelectParams, Selection, SelectionStep, select_terms};
pub use signals::Signals;
pub use system::{Block, COMPRESS_CHUNK, Group, LinearSystem, MAX_BLOCKS};
pub use tie::{Tie, TieCoefficient, TieSpec, TiedEquationFit, TiedFit, TiedParameter};
pub use velocity::{VelocityTrend, velocity_series};
pub use weak::WeakForm;

use circle_signal::{OrbitSource, Segment};
use hb_basis::Basis;
use hb_model::IdentifiedModel;

/// The stacked system of `segments` of the record `signals` (a one-coordinate record's samples
/// `&x` convert; a system's and the measured drives by [`Signals`]) for a model on `basis` by
/// `method`, with the params' noise correction applied to its columns: what every
/// identification solves.
pub fn build_system<'a, B: Basis, A: Assembly + ?Sized>(
    basis: &B,
    signals: impl Into<Signals<'a>>,
    segments: &[Segment],
    params: &IdentifyParams,
    method: &A,
) -> Result<LinearSystem, SolveError> {
    let signals = signals.into();
    let mut system = method.assemble(basis, &signals, segments, params)?;
    correct_noise(basis, signals.own(), params, &mut system)?;
    Ok(system)
}

/// [`build_system`] of each of a system's `equations` over the same `segments`
/// ([`Assembly::assemble_many`]), each with its noise correction: the same systems as each
/// equation's [`build_system`], to the bit.
pub fn build_systems<A: Assembly + ?Sized>(
    equations: &[EquationInput<'_>],
    segments: &[Segment],
    method: &A,
) -> Result<Vec<LinearSystem>, SolveError> {
    let mut systems = method.assemble_many(equations, segments)?;
    for (system, &(basis, signals, params)) in systems.iter_mut().zip(equations) {
        correct_noise(basis, signals.own(), params, system)?;
    }
    Ok(systems)
}

/// The paper's stacked system (eq. 16) of `segments` of `signals` for a model on `basis`, noise
/// correction applied: [`build_system`] with [`HarmonicBalance`], for any basis.
///
/// Segments must satisfy the [`Segment`] invariant for the clock's `P`; each gives `2 M_k + 1`
/// equations (see [`Harmonics`](hb_model::Harmonics)). On the circle each segment is unwrapped with its closing
/// sample and split into rotation and oscillation ([`circle_signal::RotationSplit`]); on the line
/// it is used as it is. Segments are processed in parallel; FFT plans and buffers are reused.
pub fn assemble<'a, B: Basis + ?Sized>(
    basis: &B,
    signals: impl Into<Signals<'a>>,
    segments: &[Segment],
    params: &IdentifyParams,
) -> Result<LinearSystem, SolveError> {
    let signals = signals.into();
    let mut system = assemble::harmonic_rows(basis, &signals, segments, params)?;
    correct_noise(basis, signals.own(), params, &mut system)?;
    Ok(system)
}

/// The weak form's stacked system of `segments` of `signals` for a model on `basis`, noise
/// correction applied: [`build_system`] with `weak`, for any basis.
///
/// Segments must satisfy the [`Segment`] invariant for the clock's `P` (including the closing
/// sample, the window's last point) but need not be periodic: `upo_search::Windows` gives plain
/// windows. `M` per segment is `params.harmonics().count(k, L)`. Segments are processed in
/// parallel; the test functions are tabulated once per segment length.
pub fn assemble_weak<'a, B: Basis + ?Sized>(
    basis: &B,
    signals: impl Into<Signals<'a>>,
    segments: &[Segment],
    params: &IdentifyParams,
    weak: &WeakForm,
) -> Result<LinearSystem, SolveError> {
    let signals = signals.into();
    let mut system = weak::weak_rows(basis, &signals, segments, params, weak)?;
    correct_noise(basis, signals.own(), params, &mut system)?;
    Ok(system)
}

/// Identifies a model on `basis` from `segments` of `signals` by `method` ([`HarmonicBalance`],
/// [`WeakForm`] or [`FiniteDifferences`]): [`build_system`], then least squares by `solver`.
///
/// Errors: `SolveError::Lstsq(LstsqError::TooFewOrbits)` when the segments give no more equations than unknowns,
/// `SolveError::Lstsq(LstsqError::RankDeficient)` when they do not determine every unknown, and typed errors for
/// bad segments and non-finite samples.
pub fn identify<'a, B: Basis, A: Assembly + ?Sized, S: LstsqSolver + ?Sized>(
    basis: B,
    signals: impl Into<Signals<'a>>,
    segments: &[Segment],
    params: &IdentifyParams,
    method: &A,
    solver: &S,
) -> Result<IdentifiedModel<B>, SolveError> {
    let system = build_system(&basis, signals, segments, params, method)?;
    IdentifiedModel::fit(basis, params, &system, solver)
}

/// [`identify`] with the segments of an [`OrbitSource`] (e.g. `upo_search::CloseReturns` for the
/// paper's method, `upo_search::Windows` for the weak form) on the own coordinate.
pub fn identify_from_source<'a, B: Basis, O: OrbitSource, A: Assembly + ?Sized, S: LstsqSolver + ?Sized>(
    basis: B,
    signals: impl Into<Signals<'a>>,
    source: &O,
    params: &IdentifyParams,
    method: &A,
    solver: &S,
) -> Result<IdentifiedModel<B>, SolveError> {
    let signals = signals.into();
    let segments = source
        .segments(signals.own())
        .map_err(|e| SolveError::Assembly(AssemblyError::Source(Box::new(e))))?;
    identify(basis, signals, &segments, params, method, solver)
}
