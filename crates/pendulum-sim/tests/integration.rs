//! The integration tests of pendulum-sim: the simulator against an independent integrator's data,
//! deserialisation that validates, and the tests of each module through the public interface (the
//! integrator and its tableau, frames, free runs, the encoder, the oscillators, prediction
//! (of one coordinate and of systems), sampling, switching at rest, validation).
//!
//! One test binary for the whole package: each file is a module of this one, so the generics
//! they share (serde, the integrator) are compiled and linked once, not once per file.
mod coupled_duffing;
mod deserialising;
mod dop853;
mod double_pendulum;
mod frame;
mod free_run;
mod multi;
mod observe;
mod oscillators;
mod prediction;
mod reference;
mod simulate;
mod switching;
mod system_prediction;
mod tableau;
mod truth;
mod validate;
