//! `hbid._hbid`: the extension module of the Python package `hbid` (built by maturin from
//! `python/`).
//!
//! A thin layer over the library the command line uses: records are read by `hb_record::input` and
//! made ready by `hb_record::prepare`, identified through `hb_pipeline::pipeline` and `hb_solve`, and the JSON
//! is `hb_pipeline::json`'s, so messages and results are the command line's. Each function takes NumPy
//! arrays (borrowed, not copied, when they are contiguous `float64`), releases the interpreter
//! while Rust works, and returns plain Python values (dicts, lists, arrays, `bytes` for a model),
//! which the pure-Python package `hbid` wraps in documented, picklable classes. Errors become the
//! exceptions of `hbid.errors` ([`errors::Kind`]) with the command line's messages, the options
//! named as Python arguments.
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

mod analysis;
mod bench;
mod errors;
mod model;
mod options;
mod record;
mod simulate;

use numpy::PyReadonlyArray1;
use pyo3::prelude::*;

use errors::{Kind, raise as raise_kind};
use options::Failure;

/// A failure as its exception.
fn raise((kind, message): Failure) -> PyErr {
    raise_kind(kind, message)
}

/// The samples of a one-dimensional array, borrowed: the Python side passes contiguous `float64`
/// arrays (`numpy.ascontiguousarray`), so nothing is copied.
fn slice<'a>(array: &'a PyReadonlyArray1<'_, f64>) -> PyResult<&'a [f64]> {
    array.as_slice().map_err(|_| {
        raise_kind(
            Kind::Options,
            "the array is not contiguous: pass numpy.ascontiguousarray(x)",
        )
    })
}

/// The extension module.
#[pymodule]
fn _hbid(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(record::read, m)?)?;
    m.add_function(wrap_pyfunction!(record::condition_arrays, m)?)?;
    m.add_function(wrap_pyfunction!(analysis::identify, m)?)?;
    m.add_function(wrap_pyfunction!(analysis::embed, m)?)?;
    m.add_function(wrap_pyfunction!(analysis::upos, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(model::model_info, m)?)?;
    m.add_function(wrap_pyfunction!(model::model_json, m)?)?;
    m.add_function(wrap_pyfunction!(model::model_from_json, m)?)?;
    m.add_function(wrap_pyfunction!(model::model_save, m)?)?;
    m.add_function(wrap_pyfunction!(model::model_load, m)?)?;
    m.add_function(wrap_pyfunction!(model::model_simulate, m)?)?;
    m.add_function(wrap_pyfunction!(bench::rayon_sweep, m)?)?;
    Ok(())
}
