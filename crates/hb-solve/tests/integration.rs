//! The integration tests of hb-solve: identification, a measured drive, fit quality and selection,
//! general terms, the weak form.
//!
//! One test binary for the whole package: each file is a module of this one, so the generics
//! they share (faer, proptest, serde) are compiled once, not once per file.
mod common;

mod compressed;
mod coupled;
mod double_pendulum;

mod identification;
mod measured_drive;
mod quality;
mod terms;
mod weak;
