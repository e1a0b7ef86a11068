//! Real FFT plans of `f64` samples, for every crate of the workspace that takes a spectrum
//! (`circle-signal`'s oscillation period, `hb-basis`'s Fourier coefficients).
//!
//! A thin, non-generic front of [`realfft`]: its planner is generic over the float type, and an
//! optimised build compiles a generic planner anew in every crate that names it (thousands of
//! functions: every butterfly of `rustfft` for every instruction set). [`Planner`] names it once,
//! here; the plans it gives are trait objects, so the crates that use them compile none of it.
//! Nothing else is added: plans, buffers and the transforms are `realfft`'s.
//!
//! # Example
//!
//! ```
//! use hb_fft::Planner;
//!
//! // The spectrum of cos(2π·3n/16): one line, at bin 3, of height 16/2.
//! let mut planner = Planner::new();
//! let fft = planner.forward(16);
//! let mut input: Vec<f64> = (0..16).map(|n| (std::f64::consts::TAU * 3.0 * n as f64 / 16.0).cos()).collect();
//! let mut bins = fft.make_output_vec();
//! fft.process(&mut input, &mut bins).unwrap();
//! assert!((bins[3].re - 8.0).abs() < 1e-12 && bins[2].norm() < 1e-12);
//! ```
#![deny(missing_docs)]

use std::fmt;
use std::sync::Arc;

pub use realfft::num_complex::Complex;
pub use realfft::{ComplexToReal, FftError, RealToComplex};

/// A real-to-complex forward transform of one length.
pub type Forward = Arc<dyn RealToComplex<f64>>;

/// A complex-to-real inverse transform of one length.
pub type Inverse = Arc<dyn ComplexToReal<f64>>;

/// Plans real FFTs of `f64` samples, reusing what it has planned (one plan per length and
/// direction, shared).
pub struct Planner(realfft::RealFftPlanner<f64>);

impl Planner {
    /// A planner with nothing planned.
    #[inline(never)]
    pub fn new() -> Self {
        Self(realfft::RealFftPlanner::new())
    }

    /// The forward transform of `len` real samples into `len / 2 + 1` bins.
    #[inline(never)]
    pub fn forward(&mut self, len: usize) -> Forward {
        self.0.plan_fft_forward(len)
    }

    /// The inverse transform of `len / 2 + 1` bins into `len` real samples (unnormalised: the
    /// forward transform followed by this one multiplies by `len`).
    #[inline(never)]
    pub fn inverse(&mut self, len: usize) -> Inverse {
        self.0.plan_fft_inverse(len)
    }
}

impl Default for Planner {
    fn default() -> Self {
        Self::new()
    }
}

impl fmt::Debug for Planner {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("Planner")
    }
}
