//! The reference of the Dask throughput measurement (`python/examples/dask_throughput.py`): the
//! same simulations and identifications as the Python sweep, run by Rust alone on a rayon pool.

use pyo3::prelude::*;
use rayon::prelude::*;

use crate::analysis::{IdentifyOptions, Request, identify_core};
use crate::errors::Kind;
use crate::options::Failure;
use crate::record::Source;
use crate::simulate::{Rig, run_rig};

/// One case of the sweep: `simulate(samples=samples, noise=noise, seed=seed)`, then
/// `identify(x, t=t, bootstrap=bootstrap, seed=seed)` with every other argument at its default.
fn case(samples: usize, bootstrap: usize, noise: f64, seed: u64) -> Result<String, Failure> {
    let record = run_rig(&Rig::paper(Some(samples), Some(noise), seed))?;
    let request = Request {
        signal: "circle".to_owned(),
        forcing_period: None,
        forcing_frequency: None,
        options: IdentifyOptions {
            method: "windowed".to_owned(),
            basis: None,
            harmonics: None,
            window_periods: None,
            window_order: None,
            bootstrap,
            level: None,
            seed,
            noise_sigma: None,
            solver: "qr".to_owned(),
            forcing: None,
            parametric: true,
            terms: None,
            select: None,
        },
        tolerance: None,
        max_period: None,
        dim: None,
        delay: None,
    };
    let source = Source::Raw {
        x: &record.x,
        t: Some(&record.t),
        dt: None,
        repair: false,
    };
    Ok(identify_core(source, request)?.json)
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
        .map_err(|e| crate::raise((Kind::Options, format!("threads={threads}: {e}"))))?;
    py.detach(|| {
        pool.install(|| {
            cases
                .par_iter()
                .map(|&(noise, seed)| case(samples, bootstrap, noise, seed))
                .collect::<Result<Vec<_>, _>>()
        })
    })
    .map_err(crate::raise)
}
