//! The reference of the Dask throughput measurement (`python/examples/dask_throughput.py`): the
//! same simulations and identifications as the Python sweep, run by Rust alone on a rayon pool.

use hb_pipeline::{IdentifyOptions, IdentifyRequest, Rig, RunError, SimulateOptions, Source};
use pyo3::prelude::*;
use rayon::prelude::*;

use crate::errors::{Kind, raise, run_error};

/// One case of the sweep: `simulate(samples=samples, noise=noise, seed=seed)`, then
/// `identify(x, t=t, bootstrap=bootstrap, seed=seed)` with every other argument at its default.
fn case(samples: usize, bootstrap: usize, noise: f64, seed: u64) -> Result<String, RunError> {
    let rig = Rig::new(SimulateOptions {
        samples: Some(samples),
        noise: Some(noise),
        seed,
        ..SimulateOptions::default()
    })?;
    let simulation = hb_pipeline::simulate(&rig, &mut ())?;
    let mut columns = simulation.table_columns().into_iter();
    let (t, x) = (
        columns.next().unwrap_or_default(),
        columns.next().unwrap_or_default(),
    );
    let request = IdentifyRequest::new(IdentifyOptions {
        bootstrap,
        seed,
        ..IdentifyOptions::default()
    })?;
    let source = Source::Arrays {
        coords: vec![&x],
        t: Some(&t),
        drives: Vec::new(),
    };
    let report = hb_pipeline::identify(source, &request, &mut ())?;
    serde_json::to_string_pretty(&report).map_err(|e| hb_pipeline::OptionError::new("options", e).into())
}

/// The sweep's cases `(noise, seed)` on a rayon pool of `threads`, without the interpreter: the
/// JSON of each identification, in the order of `cases`.
#[pyfunction]
#[pyo3(signature = (cases, *, samples, bootstrap, threads))]
pub fn rayon_sweep(
    py: Python<'_>,
    cases: Vec<(f64, u64)>,
    samples: usize,
    bootstrap: usize,
    threads: usize,
) -> PyResult<Vec<String>> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| raise(Kind::Options, format!("threads={threads}: {e}")))?;
    py.detach(|| {
        pool.install(|| {
            cases
                .par_iter()
                .map(|&(noise, seed)| case(samples, bootstrap, noise, seed))
                .collect::<Result<Vec<_>, _>>()
        })
    })
    .map_err(run_error)
}
