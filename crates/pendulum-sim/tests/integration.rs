//! The integration tests of pendulum-sim: the simulator against an independent integrator's data,
//! and deserialisation that validates.
//!
//! One test binary for the whole package: each file is a module of this one, so the generics
//! they share (serde, the integrator) are compiled and linked once, not once per file.
mod deserialising;
mod reference;
