//! The requests of the application layer (`hb_pipeline`) from Python: the options arrive as a
//! JSON object of the command line's option names (`_` for `-`), read by the layer's own
//! request types (unknown names refused, every value checked there); the samples arrive as a
//! file's path, as arrays, or as a record already on its grid. Each function releases the
//! interpreter while Rust works and returns plain values: the report's JSON text, arrays, a
//! model's bytes, the notices as `(text, is_warning)`.

use std::ops::Range;
use std::path::PathBuf;

use circle_signal::Domain;
use hb_pipeline::{
    CompareRequest, EmbedRequest, IdentifyRequest, Notice, Notices, RecordOptions, Rig, Source, Spelling,
    UposRequest, condition_source,
};
use hb_record::prepare::{GridData, Note};
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList};

use crate::errors::{Kind, option_error, raise, run_error};

/// A record's grid as Python hands it back (from a `Record`): the time of sample 0, the sampling
/// step, the ranges of samples that hold data `(start, stop)` and the signal (`circle`, `line`).
#[derive(Debug, Clone, FromPyObject)]
pub struct Grid(pub f64, pub f64, pub Vec<(usize, usize)>, pub String);

/// The samples of a request, as Python passes them: a path, arrays, or a record on its grid.
struct Samples<'a> {
    path: Option<PathBuf>,
    x: Option<&'a [f64]>,
    t: Option<&'a [f64]>,
    drive: Option<&'a [f64]>,
    grid: Option<Grid>,
}

impl<'a> Samples<'a> {
    /// The samples of a function's `path`, `x`, `t`, `drive` and `grid` arguments.
    fn new(
        path: Option<PathBuf>,
        x: &'a Option<PyReadonlyArray1<'_, f64>>,
        t: &'a Option<PyReadonlyArray1<'_, f64>>,
        drive: &'a Option<PyReadonlyArray1<'_, f64>>,
        grid: Option<Grid>,
    ) -> PyResult<Self> {
        Ok(Self {
            path,
            x: optional(x)?,
            t: optional(t)?,
            drive: optional(drive)?,
            grid,
        })
    }

    /// The layer's source; a grid is checked here.
    fn source(&self) -> PyResult<Source<'_>> {
        match (&self.path, self.x, &self.grid) {
            (Some(path), None, None) => Ok(Source::Path(path)),
            (None, Some(x), None) => Ok(Source::Arrays {
                coords: vec![x],
                t: self.t,
                drives: self.drive.into_iter().collect(),
            }),
            (None, Some(x), Some(Grid(t0, dt, pieces, signal))) => {
                let pieces: Vec<Range<usize>> = pieces.iter().map(|&(a, b)| a..b).collect();
                circle_signal::check_pieces(x, &pieces).map_err(|e| raise(Kind::Input, e))?;
                if !(dt.is_finite() && *dt > 0.0 && t0.is_finite()) {
                    return Err(raise(
                        Kind::Options,
                        format!(
                            "a record's grid needs a finite t0 and a positive step (t0 = {t0}, dt = {dt})"
                        ),
                    ));
                }
                let domain: Domain = signal.parse().map_err(|e| raise(Kind::Options, e))?;
                Ok(Source::Grid(GridData {
                    t0: *t0,
                    dt: *dt,
                    x: x.to_vec(),
                    pieces,
                    domain,
                    others: Vec::new(),
                    drives: self.drive.map(<[f64]>::to_vec).into_iter().collect(),
                    velocities: Vec::new(),
                    notes: Vec::new(),
                }))
            }
            _ => Err(raise(
                Kind::Options,
                "give a path, or the samples x (with t, dt or a record's grid)",
            )),
        }
    }
}

/// The options object of a request.
fn options(text: &str) -> PyResult<serde_json::Value> {
    serde_json::from_str(text).map_err(|e| raise(Kind::Options, format!("the options: {e}")))
}

/// The notices as `(text, is_warning)`, options spelled as Python arguments.
fn notice_texts(notices: &[Notice]) -> Vec<(String, bool)> {
    notices
        .iter()
        .map(|n| (Spelling::Python.render(&n.to_string()), n.is_warning()))
        .collect()
}

/// The borrowed samples of an optional array.
fn optional<'a>(array: &'a Option<PyReadonlyArray1<'_, f64>>) -> PyResult<Option<&'a [f64]>> {
    array.as_ref().map(crate::slice).transpose()
}

/// Reads a record from a file, or takes it from arrays, and makes it ready as the command line
/// does (grid, gaps, wrapping, spikes, integration): what `hbid.read` returns.
#[pyfunction]
#[pyo3(signature = (options, *, path=None, x=None, t=None, drive=None))]
pub fn condition<'py>(
    py: Python<'py>,
    options: &str,
    path: Option<PathBuf>,
    x: Option<PyReadonlyArray1<'py, f64>>,
    t: Option<PyReadonlyArray1<'py, f64>>,
    drive: Option<PyReadonlyArray1<'py, f64>>,
) -> PyResult<Bound<'py, PyDict>> {
    let record: RecordOptions =
        hb_pipeline::options::from_object(self::options(options)?).map_err(option_error)?;
    let samples = Samples::new(path, &x, &t, &drive, None)?;
    let source = samples.source()?;
    let mut notices = Notices::default();
    let grid = py
        .detach(|| condition_source(source, &record, &mut notices))
        .map_err(run_error)?;
    let out = PyDict::new(py);
    let mut time_repairs = Vec::new();
    let mut spikes = Vec::new();
    for note in &grid.notes {
        match note {
            Note::TimeRepaired(r) => time_repairs.push((r.at.to_string(), r.was, r.now)),
            Note::Spikes { found, repaired, .. } => {
                spikes.extend(found.iter().map(|s| (s.index, s.size, *repaired)))
            }
            _ => {}
        }
    }
    out.set_item("t0", grid.t0)?;
    out.set_item("dt", grid.dt)?;
    out.set_item(
        "pieces",
        PyList::new(py, grid.pieces.iter().map(|r| (r.start, r.end)))?,
    )?;
    out.set_item("signal", grid.domain.name())?;
    out.set_item("measured", record.measured.to_string())?;
    out.set_item("repaired", record.repair)?;
    out.set_item("notes", notice_texts(&notices.0))?;
    out.set_item("time_repairs", time_repairs)?;
    out.set_item("spikes", spikes)?;
    out.set_item(
        "drive",
        grid.drives.into_iter().next().map(|p| PyArray1::from_vec(py, p)),
    )?;
    out.set_item("x", PyArray1::from_vec(py, grid.x))?;
    Ok(out)
}

/// Identifies the equation of motion as `hbid identify --json` does: the report's JSON, the
/// model's bytes and the notices.
#[pyfunction]
#[pyo3(signature = (options, *, path=None, x=None, t=None, drive=None, grid=None))]
pub fn identify<'py>(
    py: Python<'py>,
    options: &str,
    path: Option<PathBuf>,
    x: Option<PyReadonlyArray1<'py, f64>>,
    t: Option<PyReadonlyArray1<'py, f64>>,
    drive: Option<PyReadonlyArray1<'py, f64>>,
    grid: Option<Grid>,
) -> PyResult<Bound<'py, PyDict>> {
    let request = IdentifyRequest::from_json(self::options(options)?).map_err(option_error)?;
    let samples = Samples::new(path, &x, &t, &drive, grid)?;
    let source = samples.source()?;
    let mut notices = Notices::default();
    let (json, model) = py
        .detach(|| {
            let report = hb_pipeline::identify(source, &request, &mut notices)?;
            let json = serde_json::to_string_pretty(&report)
                .map_err(|e| hb_pipeline::OptionError::new("options", e))?;
            let model = report
                .system()?
                .to_bytes()
                .map_err(hb_pipeline::RunError::Model)?;
            Ok::<_, hb_pipeline::RunError>((json, model))
        })
        .map_err(run_error)?;
    let out = PyDict::new(py);
    out.set_item("json", json)?;
    out.set_item("model", PyBytes::new(py, &model))?;
    out.set_item("notes", notice_texts(&notices.0))?;
    Ok(out)
}

/// The delay and the embedding dimension, as `hbid embed --json` gives them.
#[pyfunction]
#[pyo3(signature = (options, *, path=None, x=None, t=None, drive=None, grid=None))]
pub fn embed<'py>(
    py: Python<'py>,
    options: &str,
    path: Option<PathBuf>,
    x: Option<PyReadonlyArray1<'py, f64>>,
    t: Option<PyReadonlyArray1<'py, f64>>,
    drive: Option<PyReadonlyArray1<'py, f64>>,
    grid: Option<Grid>,
) -> PyResult<Bound<'py, PyDict>> {
    let request = EmbedRequest::from_json(self::options(options)?).map_err(option_error)?;
    let samples = Samples::new(path, &x, &t, &drive, grid)?;
    let source = samples.source()?;
    let mut notices = Notices::default();
    let report = py
        .detach(|| hb_pipeline::embed(source, &request, &mut notices))
        .map_err(run_error)?;
    let out = PyDict::new(py);
    out.set_item(
        "json",
        serde_json::to_string(&report).map_err(|e| raise(Kind::Options, e))?,
    )?;
    out.set_item("ami", PyArray1::from_vec(py, report.ami.values.clone()))?;
    out.set_item(
        "fnn",
        PyArray1::from_vec(py, report.fnn.levels.iter().map(|l| l.fraction()).collect()),
    )?;
    out.set_item("notes", notice_texts(&notices.0))?;
    Ok(out)
}

/// Unstable periodic orbits by close returns, as `hbid upos --json` gives them.
#[pyfunction]
#[pyo3(signature = (options, *, path=None, x=None, t=None, drive=None, grid=None))]
pub fn upos<'py>(
    py: Python<'py>,
    options: &str,
    path: Option<PathBuf>,
    x: Option<PyReadonlyArray1<'py, f64>>,
    t: Option<PyReadonlyArray1<'py, f64>>,
    drive: Option<PyReadonlyArray1<'py, f64>>,
    grid: Option<Grid>,
) -> PyResult<Bound<'py, PyDict>> {
    let request = UposRequest::from_json(self::options(options)?).map_err(option_error)?;
    let samples = Samples::new(path, &x, &t, &drive, grid)?;
    let source = samples.source()?;
    let mut notices = Notices::default();
    let report = py
        .detach(|| hb_pipeline::upos(source, &request, &mut notices))
        .map_err(run_error)?;
    let out = PyDict::new(py);
    out.set_item(
        "json",
        serde_json::to_string(&report).map_err(|e| raise(Kind::Options, e))?,
    )?;
    out.set_item("notes", notice_texts(&notices.0))?;
    Ok(out)
}

/// Simulates a rig's record as `hbid simulate` does, writing it to `out` and its truth to
/// `truth` when given: the record's columns as written (the gaps left out), their names and the
/// truth's JSON.
#[pyfunction]
#[pyo3(signature = (options, *, out=None, truth=None))]
pub fn simulate<'py>(
    py: Python<'py>,
    options: &str,
    out: Option<PathBuf>,
    truth: Option<PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    let rig = Rig::from_json(self::options(options)?).map_err(option_error)?;
    let (table, columns, truth_json) = py
        .detach(|| {
            hb_pipeline::simulate::check_outputs(out.as_deref(), truth.as_deref())?;
            let simulation = hb_pipeline::simulate(&rig, &mut ())?;
            let record_truth = simulation.truth()?;
            if let Some(path) = &out {
                simulation.write(path)?;
            }
            if let Some(path) = &truth {
                hb_pipeline::simulate::write_truth(&record_truth, path)?;
            }
            let json = serde_json::to_string(&record_truth)
                .map_err(|e| hb_pipeline::OptionError::new("truth", e))?;
            Ok::<_, hb_pipeline::RunError>((simulation.table(), simulation.columns(), json))
        })
        .map_err(run_error)?;
    let column = |i: usize| PyArray1::from_vec(py, table.iter().map(|row| row[i]).collect());
    // A record is `t`, its coordinates, their velocities, then its drives: `x` and `v` are the
    // first coordinate and its velocity, `drive` the first drive written; `named` has every
    // column by its name (a system's `theta2`, `tau2`, ...).
    let n = rig.options().system.coordinates();
    let dict = PyDict::new(py);
    dict.set_item("t", column(0))?;
    dict.set_item("x", column(1))?;
    dict.set_item("v", column(1 + n))?;
    dict.set_item("drive", (columns.len() > 1 + 2 * n).then(|| column(1 + 2 * n)))?;
    let named = PyDict::new(py);
    for (i, name) in columns.iter().enumerate() {
        named.set_item(*name, column(i))?;
    }
    dict.set_item("named", named)?;
    dict.set_item("columns", columns)?;
    dict.set_item("truth", truth_json)?;
    Ok(dict)
}

/// A saved model (its bytes) run freely under a record's measured input and scored against its
/// measured output, as `hbid compare --json` does: the report's JSON, each range's runs as
/// `(start, init, t, measured, x, v)` pieces, and the notices.
#[pyfunction]
#[pyo3(signature = (model, options, *, path=None, x=None, t=None, drive=None, grid=None))]
#[allow(clippy::too_many_arguments)]
pub fn compare<'py>(
    py: Python<'py>,
    model: &[u8],
    options: &str,
    path: Option<PathBuf>,
    x: Option<PyReadonlyArray1<'py, f64>>,
    t: Option<PyReadonlyArray1<'py, f64>>,
    drive: Option<PyReadonlyArray1<'py, f64>>,
    grid: Option<Grid>,
) -> PyResult<Bound<'py, PyDict>> {
    let model = hb_model::IdentifiedSystem::from_bytes(model).map_err(|e| raise(Kind::Model, e))?;
    let request = CompareRequest::from_json(self::options(options)?).map_err(option_error)?;
    let samples = Samples::new(path, &x, &t, &drive, grid)?;
    let source = samples.source()?;
    let mut notices = Notices::default();
    let report = py
        .detach(|| hb_pipeline::compare(&model, source, &request, &mut notices))
        .map_err(run_error)?;
    let out = PyDict::new(py);
    out.set_item(
        "json",
        serde_json::to_string(&report).map_err(|e| raise(Kind::Options, e))?,
    )?;
    let runs = PyList::empty(py);
    for range in report.runs {
        let pieces = PyList::empty(py);
        for p in range {
            pieces.append((
                p.start,
                p.init,
                PyArray1::from_vec(py, p.t),
                PyArray1::from_vec(py, p.measured),
                PyArray1::from_vec(py, p.x),
                PyArray1::from_vec(py, p.v),
            ))?;
        }
        runs.append(pieces)?;
    }
    out.set_item("runs", runs)?;
    out.set_item("notes", notice_texts(&notices.0))?;
    Ok(out)
}

/// A saved model run from `(x0, v0)` over the even grid of times `t`, driven by `drive` (for a
/// model with terms in p): `(t, x, v)` and why the run stopped, if it did.
#[pyfunction]
#[pyo3(signature = (model, t, *, x0, v0, drive=None, rtol=1e-10))]
pub fn model_run_on<'py>(
    py: Python<'py>,
    model: &[u8],
    t: PyReadonlyArray1<'py, f64>,
    x0: f64,
    v0: f64,
    drive: Option<PyReadonlyArray1<'py, f64>>,
    rtol: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let model = hb_model::IdentifiedModel::from_bytes(model).map_err(|e| raise(Kind::Model, e))?;
    let times = crate::slice(&t)?;
    let drive = optional(&drive)?;
    let run = py
        .detach(|| hb_pipeline::run_on_times(&model, times, drive, [x0, v0], rtol))
        .map_err(run_error)?;
    let column = |i: usize| PyArray1::from_vec(py, run.rows.iter().map(|row| row[i]).collect());
    let out = PyDict::new(py);
    out.set_item("t", column(0))?;
    out.set_item("x", column(1))?;
    out.set_item("v", column(2))?;
    out.set_item("stopped", run.stopped.clone())?;
    Ok(out)
}

/// A saved model run over a record's grid under its measured drive, as `hbid simulate --model
/// --input` does: `(t, x, v)` at every sample run and why the run stopped, if it did.
/// `rig` holds the options of `simulate` for a built-in system: any set away from its default is
/// refused, as the command line refuses it.
#[pyfunction]
#[pyo3(signature = (model, options, rig, *, path=None, x=None, t=None, drive=None, grid=None, out=None))]
#[allow(clippy::too_many_arguments)]
pub fn model_run<'py>(
    py: Python<'py>,
    model: &[u8],
    options: &str,
    rig: &str,
    path: Option<PathBuf>,
    x: Option<PyReadonlyArray1<'py, f64>>,
    t: Option<PyReadonlyArray1<'py, f64>>,
    drive: Option<PyReadonlyArray1<'py, f64>>,
    grid: Option<Grid>,
    out: Option<PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    let rig: hb_pipeline::SimulateOptions =
        hb_pipeline::options::from_object(self::options(rig)?).map_err(option_error)?;
    if let Some(name) = rig.rig_settings().first() {
        return Err(option_error(hb_pipeline::OptionError::sentence(
            name.as_str(),
            hb_pipeline::simulate::MODEL_TAKES_NO_RIG,
        )));
    }
    let model = hb_model::IdentifiedSystem::from_bytes(model).map_err(|e| raise(Kind::Model, e))?;
    let request = CompareRequest::from_json(self::options(options)?).map_err(option_error)?;
    hb_pipeline::simulate::check_model_state(&rig, request.options().x0.is_some()).map_err(option_error)?;
    let samples = Samples::new(path, &x, &t, &drive, grid)?;
    let source = samples.source()?;
    let mut notices = Notices::default();
    let run = py
        .detach(|| {
            if let Some(path) = &out {
                hb_pipeline::output::check_output_path(path)?;
            }
            let run = hb_pipeline::model_run(&model, source, &request, &mut notices)?;
            if let Some(path) = &out {
                run.write(path)?;
            }
            Ok::<_, hb_pipeline::RunError>(run)
        })
        .map_err(run_error)?;
    let column = |i: usize| PyArray1::from_vec(py, run.rows.iter().map(|row| row[i]).collect());
    let dict = PyDict::new(py);
    dict.set_item("t", column(0))?;
    dict.set_item("x", column(1))?;
    dict.set_item("v", column(2))?;
    dict.set_item("stopped", run.stopped.clone())?;
    dict.set_item("notes", notice_texts(&notices.0))?;
    Ok(dict)
}
