//! `hbid._hbid`: the extension module of the Python package `hbid` (built by maturin from
//! `python/`).
//!
//! A thin binding of the application layer the command line runs (`hb_pipeline`): each function
//! takes the options as a JSON object of the command line's option names (read and checked by
//! the layer's request types, so defaults, grammars and messages are the command line's) and the
//! samples as a path or NumPy arrays (borrowed when contiguous `float64`), releases the
//! interpreter while Rust works, and returns plain Python values (the report's JSON text, arrays,
//! `bytes` for a model), which the pure-Python package `hbid` wraps in documented, picklable
//! classes. Errors become the exceptions of `hbid.errors` by their kind (`errors::Kind`), the
//! options named as Python arguments.
//!
//! # Example (Python)
//!
//! ```text
//! import hbid
//! sim = hbid.simulate(samples=6000)
//! result = hbid.identify(sim.x, t=sim.t, bootstrap=0)
//! print(result.equation)
//! ```
#![deny(missing_docs)]

mod bench;
mod errors;
mod model;
mod run;

use numpy::PyReadonlyArray1;
use pyo3::prelude::*;

use errors::{Kind, raise};

/// The samples of a one-dimensional array, borrowed: the Python side passes contiguous `float64`
/// arrays (`numpy.ascontiguousarray`). Callers copy them before the interpreter's lock is
/// released, so that no other thread writes to what the work reads.
fn slice<'a>(array: &'a PyReadonlyArray1<'_, f64>) -> PyResult<&'a [f64]> {
    array.as_slice().map_err(|_| {
        raise(
            Kind::Options,
            "the array is not contiguous: pass numpy.ascontiguousarray(x)",
        )
    })
}

/// The extension module.
#[pymodule]
fn _hbid(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    // The integrator's default relative tolerance, written once (the Python signatures read it).
    m.add("DEFAULT_RTOL", pendulum_sim::Tolerances::DEFAULT_RTOL)?;
    m.add_function(wrap_pyfunction!(run::condition, m)?)?;
    m.add_function(wrap_pyfunction!(run::identify, m)?)?;
    m.add_function(wrap_pyfunction!(run::embed, m)?)?;
    m.add_function(wrap_pyfunction!(run::upos, m)?)?;
    m.add_function(wrap_pyfunction!(run::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(run::compare, m)?)?;
    m.add_function(wrap_pyfunction!(run::model_run, m)?)?;
    m.add_function(wrap_pyfunction!(run::model_run_on, m)?)?;
    m.add_function(wrap_pyfunction!(model::model_info, m)?)?;
    m.add_function(wrap_pyfunction!(model::model_json, m)?)?;
    m.add_function(wrap_pyfunction!(model::model_from_json, m)?)?;
    m.add_function(wrap_pyfunction!(model::model_save, m)?)?;
    m.add_function(wrap_pyfunction!(model::check_output, m)?)?;
    m.add_function(wrap_pyfunction!(model::model_load, m)?)?;
    m.add_function(wrap_pyfunction!(model::model_simulate, m)?)?;
    m.add_function(wrap_pyfunction!(bench::rayon_sweep, m)?)?;
    Ok(())
}
