//! Orbit segments for harmonic-balance identification.
//!
//! The interface between "where do periodic pieces of the record come from" and "how are they
//! balanced": an [`OrbitSource`] yields [`Segment`]s of a sampled signal, each spanning a whole
//! number `k` of forcing periods.
//!
//! # Close returns (paper section 3.2)
//!
//! [`CloseReturns`] finds approximate unstable periodic orbits (UPOs) in a chaotic record
//! `x_0, …, x_{N−1}` sampled `P` times per forcing period. With the delay vectors
//!
//! ```text
//! S(n) = (x_n, x_{n+Td}, …, x_{n+(d−1)Td})
//! ```
//!
//! there is a period-`k` close return at `n` when
//!
//! ```text
//! |S(n + kP) − S(n)| = max_{c < d} |x_{n+cTd+kP} − x_{n+cTd}| < ε,    n + kP + (d − 1) Td < N,
//! ```
//!
//! where the per-component distance is the circle distance `|a − b|_c` of paper eq. 19 for a
//! wrapped angle ([`Domain::Circle`]) or `|a − b|` on the line ([`Domain::Line`]), and the
//! absolute tolerance is `ε = e · span`, `e` a fraction (the paper: 1–5 %, default 3 %) of the span
//! of the data (2π on the circle, `max − min` on the line). The paper writes the test backwards in
//! time, `|S(n − kT) − S(n)|_c < e`; it is the same set of pairs.
//!
//! A chaotic trajectory that passes near a UPO returns for several consecutive `n`; such a run is
//! one passage and gives one [`Segment`] (`start = n` of least error, `len = kP`). A period-`k`
//! segment that also closes at a proper divisor `j` of `k` at its `n` is a repeated period-`j` orbit
//! and is dropped. Periods are searched in parallel; results are ordered by period, then start.
//!
//! Repeated passages near one orbit give several segments; [`Catalogue`] groups segments of one
//! period whose samples agree within `ε` after a cyclic shift that keeps the phase of the forcing
//! (see its docs for the exact rule), so the number of distinct orbits can be compared with the
//! paper's "about 25 UPOs from period 1 to 16".
//!
//! A record with gaps (missing samples) is searched in pieces
//! ([`CloseReturns::search_pieces`], [`Windows::windows_pieces`]): every segment lies inside one
//! piece, and an orbit met in several pieces is one orbit of the catalogue.
//!
//! # Example
//!
//! ```
//! use upo_search::{CloseReturns, OrbitSource};
//! use std::f64::consts::PI;
//!
//! // P = 20 samples per forcing period; a whirling period-1 orbit (one turn per forcing period,
//! // crossing ±π), recorded for 6 forcing periods.
//! let p = 20;
//! let orbit: Vec<f64> =
//!     (0..p).map(|i| circle_signal::wrap(2.0 * PI * i as f64 / p as f64 + 0.4 * (4.0 * PI * i as f64 / p as f64).sin())).collect();
//! let x: Vec<f64> = orbit.iter().copied().cycle().take(6 * p).collect();
//!
//! let clock = upo_search::SampleClock::nondimensional(p)?;
//! let search = CloseReturns::builder(&clock, 3).max_period(3).build()?;
//! let segments = search.segments(&x)?;
//! // One passage, found at its first sample; the returns after 2 and 3 forcing periods are
//! // repetitions of the period-1 orbit.
//! assert_eq!(segments.len(), 1);
//! assert_eq!((segments[0].start(), segments[0].period(), segments[0].len()), (0, 1, 20));
//! assert_eq!(segments[0].error(), 0.0);
//!
//! let catalogue = search.catalogue(&x)?;
//! assert_eq!(catalogue.orbits().len(), 1);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![deny(missing_docs)]

mod catalogue;
mod close_returns;
mod error;
mod metric;
mod windows;

pub use catalogue::{Assignment, Catalogue, Orbit, PeriodCount};
pub use circle_signal::{Domain, OrbitSource, SampleClock, Segment};
pub use close_returns::{CloseReturns, CloseReturnsBuilder};
pub use error::UpoError;
pub use windows::{Windows, WindowsBuilder};

/// Checks the pieces of a record with gaps ([`circle_signal::check_pieces`]); a non-finite sample
/// is this crate's [`UpoError::NonFinite`], as for a record without gaps.
fn check_pieces(signal: &[f64], pieces: &[std::ops::Range<usize>]) -> Result<(), UpoError> {
    circle_signal::check_pieces(signal, pieces).map_err(|e| match e {
        circle_signal::CircleError::NonFinite { index, value } => UpoError::NonFinite { index, value },
        e => UpoError::Clock(e),
    })
}
