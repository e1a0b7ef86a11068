//! Basis functions and segment Fourier coefficients for harmonic-balance identification.
//!
//! The identified equation of motion (paper eq. 6) is
//!
//! ```text
//! c_r x' + Σ_i q_i φ_i(x) + Σ_i n_i φ_i(x) cos t + Σ_i p_i φ_i(x) sin t = −x''
//! ```
//!
//! with the unknown autonomous and parametric functions expanded in a basis `{φ_i}` (eqs. 4-5).
//! This crate holds the [`Basis`] trait and three bases:
//!
//! - [`Harmonic`] of order `K`: `cos(kx), sin(kx)`, `k = 1..K` (paper eq. 20), on the circle;
//! - [`Hat`] with `N` nodes: periodic linear interpolation on the circle (paper section 4.2.2),
//!   node `i` at `−π + 2π i / N`, summing to one everywhere;
//! - [`Polynomial`] of degree `D`: `x, x², .., x^D`, on the line (for eq. 2 with `x ∈ R¹`).
//!
//! It also computes the Fourier coefficients that harmonic balance needs (eqs. 7, 12-14) with
//! planned real FFTs ([`FourierPlan`], [`FourierPlanner`]): for a segment of `L` samples,
//! `a_j = 2 Re(S_j)/L`, `b_j = −2 Im(S_j)/L`, harmonic `j` of a period-`k` segment having
//! frequency `j/k` in units of the forcing frequency. [`Spectrum::modulated_bins`] turns the
//! spectrum of `φ_i(x_n)` into those of `φ_i(x_n) cos(W t_n)` and `φ_i(x_n) sin(W t_n)` by the
//! shift theorem, so eqs. 13-14 cost no further transform.
//!
//! # Example
//!
//! ```
//! use hb_basis::{Basis, FourierPlan, Hat, Harmonic};
//! use std::f64::consts::TAU;
//!
//! // Hats sum to one; harmonic functions are named as in the identified equation.
//! let hat = Hat::new(8).unwrap();
//! let mut phi = vec![0.0; hat.len()];
//! hat.eval(2.5, &mut phi);
//! assert!((phi.iter().sum::<f64>() - 1.0).abs() < 1e-12);
//! assert_eq!(Harmonic::new(2).unwrap().names(), ["cos(x)", "sin(x)", "cos(2x)", "sin(2x)"]);
//!
//! // Fourier coefficients of a 50-sample segment spanning k = 2 forcing periods:
//! // cos(t) is harmonic j = 2 of the segment.
//! let s: Vec<f64> = (0..50).map(|n| 0.3 + (TAU * n as f64 / 25.0).cos()).collect();
//! let mut plan = FourierPlan::new(50).unwrap();
//! let (mut a, mut b) = (vec![0.0; 4], vec![0.0; 4]);
//! plan.coefficients(&s, &mut a, &mut b).unwrap();
//! assert!((a[0] / 2.0 - 0.3).abs() < 1e-12 && (a[2] - 1.0).abs() < 1e-12 && a[1].abs() < 1e-12);
//! ```
#![deny(missing_docs)]

mod basis;
mod error;
mod fourier;

pub use basis::{Basis, BasisKind, Domain, Harmonic, Hat, Polynomial};

/// The most functions a basis may have (`2K` harmonics, `N` hats, `D` monomials): each is an
/// unknown of the least squares, and a record determines a few dozen, not thousands. A size
/// beyond it is refused when the basis is made (and read), not met as memory the fit cannot have.
pub const MAX_FUNCTIONS: usize = 4096;
pub use error::BasisError;
pub use fourier::{
    Complex64, FourierPlan, FourierPlanner, Spectrum, coefficients_from_bin, fourier_coefficients,
};
