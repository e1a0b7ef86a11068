//! Simulation of forced second-order oscillators.
#![deny(missing_docs)]

mod error;
mod system;

pub use error::SimError;
pub use system::{Pendulum, SecondOrderSystem};
