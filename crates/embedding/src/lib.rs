//! Delay embedding of a scalar record: the delay and the embedding dimension (paper section 3.1).
//!
//! Only one signal is measured, the angle θ; the close-return search needs a phase space, which is
//! rebuilt from delay vectors (paper section 3, the unnumbered equation before section 3.1):
//!
//! `S(n) = (x_n, x_{n+T_d}, …, x_{n+(d−1)T_d})`
//!
//! This crate chooses `T_d` and checks `d`:
//!
//! - [`Embedding`], [`DelayVectors`], [`DelayVector`]: the vectors as strided views on the record
//!   (nothing is copied; [`DelayVector::copy_to`] fills a caller's buffer).
//! - [`average_mutual_information`]: paper eq. 18, `I(τ) = Σ p_ij ln(p_ij / (p_i p_j))` over `B`
//!   equal boxes (default 16) for lags `τ = 0..=L`, in nats unless [`InfoUnit::Bits`] is asked for
//!   (the paper writes log₂; the minimum does not depend on the base). The delay is the first
//!   minimum ([`AmiCurve::first_minimum`]).
//! - [`false_nearest_neighbours`]: Kennel, Brown & Abarbanel (1992), the distance-ratio test
//!   (`R_tol`, default 10) and the attractor-size test (`A_tol`, default 2), with a Theiler window,
//!   for `d = 1..=d_max` (default 8). The minimum embedding dimension is the first `d` whose
//!   fraction of false neighbours is below a threshold (default 0.05).
//! - [`nearest_neighbours`]: the all-points nearest-neighbour search behind it (a kiddo k-d tree,
//!   in parallel with rayon), with a Theiler window.
//!
//! # Domain and metric
//!
//! Every distance goes through the record's [`Domain`]. [`Domain::Circle`] is the circle distance of paper
//! eq. 19, `|a − b|_c = |wrap(a − b)|`: the right one for a wrapped angle, where −3.1 and 3.1 are
//! 0.08 apart. [`Domain::Line`] takes plain differences, as classic tools do; on a wrapped angle
//! it sees a jump of 2π where the pendulum hardly moved and calls many neighbours false.
//! Delay vectors are compared with the **maximum** over components (the Chebyshev norm), the same
//! norm as `circle_signal::max_circle_distance`; in the false-nearest-neighbour test the extra
//! coordinate `|x_{n+dT_d} − x_{m+dT_d}|` is measured with the same metric. For the mutual
//! information the metric decides the boxes: `[min, max]` of the data on the line, the whole
//! circle `[−π, π)` for an angle.
//!
//! # Example
//!
//! ```
//! use embedding::{average_mutual_information, false_nearest_neighbours, AmiParams, FnnParams, Domain};
//!
//! // A quasi-periodic angle winding round the circle, seen wrapped.
//! let x: Vec<f64> = (0..3000)
//!     .map(|n| {
//!         let t = 0.25 * n as f64;
//!         circle_signal::wrap(0.3 * t + 2.0 * (t / 1.618).sin())
//!     })
//!     .collect();
//!
//! let ami = average_mutual_information(&x, &AmiParams::new(Domain::Circle).with_max_lag(30)?)?;
//! assert!(ami.values[0] > ami.values[1]); // I(0) is the entropy of the boxed record
//! let delay = ami.delay()?;
//!
//! let params = FnnParams::new(Domain::Circle, delay)?.with_max_dim(4)?;
//! let fnn = false_nearest_neighbours(&x, &params)?;
//! assert_eq!(fnn.levels.len(), 4);
//! // The orbit lies on a torus: two delay coordinates unfold most of it.
//! assert!(fnn.levels[2].fraction() < fnn.levels[0].fraction());
//! # Ok::<(), embedding::EmbeddingError>(())
//! ```
#![deny(missing_docs)]

mod ami;
mod delay;
mod error;
mod fnn;
mod metric;
mod neighbours;

pub use ami::{AmiCurve, AmiParams, InfoUnit, average_mutual_information};
pub use circle_signal::Domain;
pub use delay::{DelayVector, DelayVectors, Embedding};
pub use error::EmbeddingError;
pub use fnn::{FnnLevel, FnnParams, FnnResult, false_nearest_neighbours};
pub use metric::{delay_distance, spread};
pub use neighbours::{MAX_SEARCH_DIM, Neighbour, nearest_neighbours};

/// The first non-finite sample, as an error.
pub(crate) fn check_finite(x: &[f64]) -> Result<(), EmbeddingError> {
    match x.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(EmbeddingError::NonFinite {
            index,
            value: x[index],
        }),
        None => Ok(()),
    }
}
