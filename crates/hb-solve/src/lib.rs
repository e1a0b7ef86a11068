//! Harmonic-balance identification of a forced oscillator from periodic pieces of one record.
//!
//! The model (paper eq. 2, specialised as eq. 6 for the pendulum) is linear in its unknowns:
//!
//! ```text
//! c_r x' + k x + Σ_i q_i φ_i(x) + Σ_i [n_i cos(W t) + p_i sin(W t)] φ_i(x) + F_c cos(W t) + F_s sin(W t) = −x''
//! ```
//!
//! with a basis `{φ_i}` from `hb-basis` and the terms chosen by a [`ModelForm`] (`k x` and the
//! external forcing `F` are optional). Over a period-`k` orbit segment of `L = kP` samples, every
//! signal is expanded in a Fourier series of the orbit's fundamental `Ω = W / k` (eqs. 7-14); for an
//! angle on the circle the segment is first unwrapped and split into a constant rotation `w_ck t`
//! and an oscillation `x_var` (section 2, Figure 1), so `x' = w_ck + Σ ...` (eq. 10) and
//! `x'' = −Σ (jΩ)² (...)` (eq. 11). Balancing the mean and harmonics `j = 1..M` gives `2M + 1`
//! linear equations per orbit (eq. 15, see [`LinearSystem`]); those of all orbits are stacked
//! (eq. 16) and solved in the least-squares sense (eq. 17) by a column-pivoted QR or a thin SVD
//! ([`LstsqSolver`]), never through the normal equations.
//!
//! Time is the data's own: `P` samples per forcing period `T`, `h = T / P`, `W = 2π / T`, and the
//! forcing terms use the absolute time `t_n = t_0 + n h` of each sample ([`SampleClock`]); with the
//! paper's non-dimensional time (`T = 2π`) the rows are exactly those of the method notes.
//!
//! The result is an [`IdentifiedModel`]: coefficients with standard errors (`s² (AᵀA)⁻¹` from the
//! factorisation), the condition number and residual of the fit, simulation through
//! [`pendulum_sim::SecondOrderSystem`], and JSON or compact binary save/load.
//!
//! # Example
//!
//! A linear oscillator `x'' + 0.1 x' + 2 x = cos t` has the exactly periodic solution
//! `x = A cos t + B sin t` with `A = 1/1.01`, `B = 0.1/1.01`. With the forcing known, damping and
//! stiffness come back exactly from one orbit:
//!
//! ```
//! use hb_basis::Polynomial;
//! use hb_solve::{Forcing, IdentifyParams, ModelForm, QrSolver, SampleClock, identify};
//! use upo_search::Segment;
//!
//! let p = 25;
//! let clock = SampleClock::nondimensional(p)?.with_start_time(3.7)?;
//! let x: Vec<f64> = (0..=p)
//!     .map(|n| {
//!         let t = clock.time(n);
//!         (t.cos() + 0.1 * t.sin()) / 1.01
//!     })
//!     .collect();
//! let segment = Segment { start: 0, period: 1, len: p, error: 0.0 };
//! // The term cos(t) sits on the left with x'': its known coefficient is −1.
//! let form = ModelForm::externally_forced(Forcing::Known { cos: -1.0, sin: 0.0 });
//! let params = IdentifyParams::builder(clock).form(form).build()?;
//! let model = identify(Polynomial::new(1)?, &x, &[segment], &params, &QrSolver::default())?;
//! assert!((model.damping() - 0.1).abs() < 1e-12);
//! assert!((model.coefficient("x").unwrap().value - 2.0).abs() < 1e-12);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![deny(missing_docs)]

mod assemble;
mod error;
mod lstsq;
mod model;
mod params;

pub use assemble::{Block, LinearSystem, assemble, term_names};
pub use error::SolveError;
pub use lstsq::{LstsqFit, LstsqSolver, QrSolver, RankTolerance, SvdSolver};
pub use model::{Coefficient, FitSummary, IdentifiedModel, MODEL_FORMAT, MODEL_MAGIC, MODEL_VERSION};
pub use params::{Forcing, Harmonics, IdentifyParams, IdentifyParamsBuilder, ModelForm, SampleClock};

use hb_basis::Basis;
use upo_search::{OrbitSource, Segment};

/// Identifies a model on `basis` from `segments` of `signal` (assembly, then least squares).
///
/// Errors: [`SolveError::TooFewOrbits`] when the segments give no more equations than unknowns,
/// [`SolveError::RankDeficient`] when they do not determine every unknown, and typed errors for
/// bad segments and non-finite samples.
pub fn identify<B: Basis, S: LstsqSolver + ?Sized>(
    basis: B,
    signal: &[f64],
    segments: &[Segment],
    params: &IdentifyParams,
    solver: &S,
) -> Result<IdentifiedModel<B>, SolveError> {
    let system = assemble(&basis, signal, segments, params)?;
    let fit = system.solve(solver)?;
    IdentifiedModel::from_fit(basis, params, &system, &fit, solver.name())
}

/// [`identify`] with the segments of an [`OrbitSource`] (e.g. `upo_search::CloseReturns`).
pub fn identify_from_source<B: Basis, O: OrbitSource, S: LstsqSolver + ?Sized>(
    basis: B,
    signal: &[f64],
    source: &O,
    params: &IdentifyParams,
    solver: &S,
) -> Result<IdentifiedModel<B>, SolveError> {
    let segments = source
        .segments(signal)
        .map_err(|e| SolveError::Source(Box::new(e)))?;
    identify(basis, signal, &segments, params, solver)
}
