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

/// The shared fixture `paper_dataset.csv` (made by SciPy): `(t, theta)` columns.
///
/// # Panics
/// If `../shared/fixtures/paper_dataset.csv` is missing or malformed: benches need it.
pub fn paper_fixture() -> (Vec<f64>, Vec<f64>) {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../shared/fixtures/paper_dataset.csv"
    );
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .skip(1)
        .map(|l| {
            let mut cells = l.split(',').map(|c| c.trim().parse::<f64>().expect("a number"));
            (cells.next().expect("t"), cells.next().expect("theta"))
        })
        .unzip()
}
