//! Shared inputs of the benchmarks: data sets made once, outside the timed closures.
#![deny(missing_docs)]

use pendulum_sim::{Pendulum, SimError, SimulationConfig, simulate};

/// The paper's data set as an encoder reports it: 30000 wrapped samples, 25 per forcing period,
/// after 200 periods of transient, at rtol 1e-10.
pub fn paper_record() -> Result<Vec<f64>, SimError> {
    record(30_000)
}

/// A longer record of the same system, `samples` wrapped samples.
pub fn record(samples: usize) -> Result<Vec<f64>, SimError> {
    let cfg = SimulationConfig::paper().with_samples(samples)?;
    Ok(simulate(&Pendulum::paper(), &cfg)?.wrapped())
}
