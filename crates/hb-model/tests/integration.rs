//! The integration tests of hb-model: the vocabulary of terms and its grammar, the layout of the
//! preset forms, the identified equation (evaluated, saved and read back) and the measured drive
//! (the true equation of the simulated systems is tested with them, in pendulum-sim).
//!
//! One test binary for the whole package: each file is a module of this one, so the crates they
//! share (serde, the simulator) are linked once, not once per file.
mod drive;
mod form;
mod model;
mod saved;
mod terms;
