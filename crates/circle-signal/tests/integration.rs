//! The integration tests of circle-signal: outliers, properties of the circle's operations, spikes.
//!
//! One test binary for the whole package: each file is a module of this one, so the generics
//! they share (faer, proptest, serde) are compiled once, not once per file.
mod support;

mod outliers;
mod properties;
mod spikes;
