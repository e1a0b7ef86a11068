//! Identified models and systems: their coefficients, saved and loaded as `hbid identify
//! --save-model` does, and simulated by `pendulum_sim`. A model crosses into Python as its
//! compact bytes ([`IdentifiedSystem::to_bytes`]: a model of one coordinate in format 4, any other
//! system, one coordinate under drives of their own names among them, in format 5), so that it
//! pickles as it is.

use std::io::Write;
use std::path::PathBuf;

use circle_signal::Domain;
use hb_model::{IdentifiedModel, IdentifiedSystem};
use numpy::PyArray1;
use pendulum_sim::{SimulationConfig, Tolerances, simulate};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList};

use crate::errors::{Kind, OrRaise};

/// Three arrays: time, position, velocity.
type Arrays3<'py> = (
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
);

fn decode(bytes: &[u8]) -> PyResult<IdentifiedModel> {
    match IdentifiedSystem::from_bytes(bytes)
        .or_raise(Kind::Model)?
        .into_equations()
    {
        equations if equations.len() == 1 => Ok(equations.into_iter().next().expect("one")),
        equations => Err(crate::errors::raise(
            Kind::Options,
            format!(
                "a system of {} coordinates runs over given times: Model.simulate(t=..., x0=[...], v0=[...])",
                equations.len()
            ),
        )),
    }
}

fn decode_system(bytes: &[u8]) -> PyResult<IdentifiedSystem> {
    IdentifiedSystem::from_bytes(bytes).or_raise(Kind::Model)
}

/// The summary of a model's fit, or None.
fn summary<'py>(py: Python<'py>, model: &IdentifiedModel) -> PyResult<Option<Bound<'py, PyDict>>> {
    let Some(s) = model.summary() else {
        return Ok(None);
    };
    let summary = PyDict::new(py);
    summary.set_item("solver", &s.solver)?;
    summary.set_item("rows", s.rows)?;
    summary.set_item("unknowns", s.unknowns)?;
    summary.set_item("segments", s.segments)?;
    summary.set_item("whirling_segments", s.whirling_segments)?;
    summary.set_item("condition_number", s.condition)?;
    summary.set_item("residual_rms", s.residual_rms)?;
    summary.set_item("forcing_period", s.clock.drive_period())?;
    summary.set_item("sample_step", s.clock.step())?;
    Ok(Some(summary))
}

/// The coefficients `(name, value, standard error)` of a model, in its order.
fn coefficients(model: &IdentifiedModel) -> Vec<(String, f64, f64)> {
    model
        .coefficients()
        .iter()
        .map(|c| (c.name.clone(), c.value, c.std_error))
        .collect()
}

/// A model or system: its coordinates, measured drives and their domains, each equation's
/// coefficients, basis and fit summary, and (the first equation's) coefficients, basis,
/// signal, forcing frequency and fit summary as a model of one coordinate has them.
#[pyfunction]
pub fn model_info<'py>(py: Python<'py>, model: &[u8]) -> PyResult<Bound<'py, PyDict>> {
    let system = decode_system(model)?;
    let names = system.names();
    let first = &system.equations()[0];
    let out = PyDict::new(py);
    out.set_item("coordinates", names.coordinates())?;
    let drives: &[String] = if system.has_measured_drive() {
        names.drives()
    } else {
        &[]
    };
    out.set_item("drives", drives)?;
    out.set_item(
        "signals",
        system.domains().iter().map(|d| d.name()).collect::<Vec<_>>(),
    )?;
    let equations = PyList::empty(py);
    for (name, model) in names.coordinates().iter().zip(system.equations()) {
        let e = PyDict::new(py);
        e.set_item("coordinate", name)?;
        e.set_item("coefficients", coefficients(model))?;
        e.set_item("basis", model.basis().spec())?;
        e.set_item("signal", model.domain().name())?;
        e.set_item("summary", summary(py, model)?)?;
        equations.append(e)?;
    }
    out.set_item("equations", equations)?;
    out.set_item("coefficients", coefficients(first))?;
    out.set_item("basis", first.basis().to_string())?;
    out.set_item("signal", first.domain().name())?;
    out.set_item("forcing_frequency", system.drive_angular_frequency())?;
    out.set_item("summary", summary(py, first)?)?;
    Ok(out)
}

/// The model as JSON (the file `--save-model model.json` writes; a system's format 5).
#[pyfunction]
pub fn model_json(model: &[u8]) -> PyResult<String> {
    decode_system(model)?.to_json().or_raise(Kind::Model)
}

/// A model read from JSON text (`model.json`, a model or a system).
#[pyfunction]
pub fn model_from_json<'py>(py: Python<'py>, text: &str) -> PyResult<Bound<'py, PyBytes>> {
    let model: IdentifiedSystem = IdentifiedSystem::from_json(text).or_raise(Kind::Model)?;
    Ok(PyBytes::new(py, &model.to_bytes().or_raise(Kind::Model)?))
}

/// Saves a model: JSON if the name ends in `.json`, compact binary otherwise, atomically.
#[pyfunction]
pub fn model_save(py: Python<'_>, model: &[u8], path: PathBuf) -> PyResult<()> {
    let model = decode_system(model)?;
    let json = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("json"));
    let bytes = if json {
        model.to_json().or_raise(Kind::Model)?.into_bytes()
    } else {
        model.to_bytes().or_raise(Kind::Model)?
    };
    py.detach(|| hb_pipeline::output::write_atomically(&path, |w: &mut dyn Write| w.write_all(&bytes)))
        .map_err(|e| {
            crate::errors::raise(
                Kind::Output,
                format!("{}: {}", path.display(), crate::errors::chain(&e)),
            )
        })
}

/// That a result can be written at `path` (its folder exists, it is not a folder), checked
/// before any work: `OutputError` otherwise.
#[pyfunction]
pub fn check_output(path: PathBuf) -> PyResult<()> {
    hb_pipeline::output::check_output_path(&path).map_err(|e| {
        crate::errors::raise(
            Kind::Output,
            format!("{}: {}", path.display(), crate::errors::chain(&e)),
        )
    })
}

/// Loads a model saved by `model_save` or `hbid identify --save-model` (JSON or binary; a model
/// of one coordinate or a system).
#[pyfunction]
pub fn model_load<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyBytes>> {
    let model = py
        .detach(|| hb_pipeline::read_model(&path))
        .map_err(crate::errors::run_error)?;
    Ok(PyBytes::new(py, &model.to_bytes().or_raise(Kind::Model)?))
}

/// Simulates a model from `(x0, v0)` at the record's time: `samples` samples, `samples_per_period`
/// per forcing period (default: the record's, from the fit; required for a model without one),
/// after `transient_periods`.
#[pyfunction]
#[pyo3(signature = (model, *, samples, x0=0.1, v0=0.0, samples_per_period=None, transient_periods=0, rtol=None, wrapped=true))]
#[allow(clippy::too_many_arguments)]
pub fn model_simulate<'py>(
    py: Python<'py>,
    model: &[u8],
    samples: usize,
    x0: f64,
    v0: f64,
    samples_per_period: Option<usize>,
    transient_periods: usize,
    rtol: Option<f64>,
    wrapped: bool,
) -> PyResult<Arrays3<'py>> {
    let model = decode(model)?;
    let w = model.drive_angular_frequency();
    let period = std::f64::consts::TAU / w;
    let p = samples_per_period
        .or_else(|| model.summary().and_then(|s| s.clock.whole_samples_per_period()))
        .ok_or_else(|| {
            crate::errors::raise(
                Kind::Options,
                "samples_per_period: the model has no record to take it from; give it",
            )
        })?;
    let config = SimulationConfig::paper()
        .with_drive_period(period)
        .and_then(|c| c.with_samples_per_period(p))
        .and_then(|c| c.with_samples(samples))
        .and_then(|c| c.with_initial(x0, v0))
        .and_then(|c| Ok(c.with_tolerances(Tolerances::relative(rtol.unwrap_or(Tolerances::DEFAULT_RTOL))?)))
        .map(|c| c.with_transient_periods(transient_periods))
        .or_raise(Kind::Options)?;
    let trajectory = py
        .detach(|| simulate(&model, &config))
        .or_raise(Kind::Simulation)?;
    let x = if wrapped && model.domain() == Domain::Circle {
        trajectory.wrapped()
    } else {
        trajectory.theta
    };
    Ok((
        PyArray1::from_vec(py, trajectory.t),
        PyArray1::from_vec(py, x),
        PyArray1::from_vec(py, trajectory.omega),
    ))
}
