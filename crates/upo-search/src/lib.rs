//! Orbit segments for harmonic-balance identification.
//!
//! The interface between "where do periodic pieces of the record come from" and "how are they
//! balanced": an [`OrbitSource`] yields [`Segment`]s of a sampled signal, each spanning a whole
//! number `k` of forcing periods.
#![deny(missing_docs)]

mod source;

pub use source::{OrbitSource, Segment};
