//! The requests of the application layer (`hb_pipeline`) from Python: the options arrive as a
//! JSON object of the command line's option names (`_` for `-`), read by the layer's own
//! request types (unknown names refused, every value checked there); the samples arrive as a
//! file's path (several for `identify`, joined into one record), as arrays (one per coordinate
//! and per measured drive), or as a record already on its grid. Each function releases the
//! interpreter while Rust works and returns plain values: the report's JSON text, arrays, a
//! model's bytes, the notices as `(text, is_warning)`.

use std::ops::Range;
use std::path::PathBuf;

use hb_pipeline::{
    CompareRequest, EmbedRequest, IdentifyRequest, Notice, Notices, RecordOptions, Rig, SignalList, Source,
    Spelling, UposRequest, condition_source,
};
use hb_record::prepare::{Channel, GridData, Note};
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList};

use crate::errors::{Kind, option_error, raise, run_error};

/// A record's grid as Python hands it back (from a `Record`): the time of sample 0, the sampling
/// step, the ranges of samples that hold data `(start, stop)`, the signal (`circle`, `line`,
/// or one per coordinate, `circle,line`) and the ranges of samples bridged into gaps.
#[derive(Debug, Clone, FromPyObject)]
pub struct Grid(
    pub f64,
    pub f64,
    pub Vec<(usize, usize)>,
    pub String,
    pub Vec<(usize, usize)>,
);

/// Arrays as Python passes them: one per coordinate, drive or velocity.
type Arrays<'py> = Option<Vec<PyReadonlyArray1<'py, f64>>>;

/// The samples of a request, as Python passes them: paths, arrays, or a record on its grid.
struct Samples {
    paths: Vec<PathBuf>,
    /// One series per coordinate.
    x: Vec<Vec<f64>>,
    t: Option<Vec<f64>>,
    /// One series per measured drive.
    drives: Vec<Vec<f64>>,
    /// One series per coordinate's measured velocity (a record on its grid only).
    velocities: Vec<Vec<f64>>,
    grid: Option<Grid>,
}

impl Samples {
    /// The samples of a function's `path`, `x`, `t`, `drive`, `velocity` and `grid` arguments,
    /// copied while the interpreter's lock is held: the work runs without it, and another thread
    /// may write to the arrays meanwhile.
    fn new(
        paths: Vec<PathBuf>,
        x: &Arrays<'_>,
        t: &Option<PyReadonlyArray1<'_, f64>>,
        drive: &Arrays<'_>,
        velocity: &Arrays<'_>,
        grid: Option<Grid>,
    ) -> PyResult<Self> {
        Ok(Self {
            paths,
            x: copies(x)?,
            t: optional(t)?.map(<[f64]>::to_vec),
            drives: copies(drive)?,
            velocities: copies(velocity)?,
            grid,
        })
    }

    /// The layer's source of the one record; a grid is checked here.
    fn source(&self) -> PyResult<Source<'_>> {
        match &self.paths[..] {
            [] => {}
            [path] if self.x.is_empty() && self.grid.is_none() => return Ok(Source::Path(path)),
            [_] => {
                return Err(raise(
                    Kind::Options,
                    "give a path, or the samples x (with t, dt or a record's grid), not both",
                ));
            }
            _ => {
                return Err(raise(
                    Kind::Options,
                    "one record here: only identify joins several files",
                ));
            }
        }
        if !self.velocities.is_empty() && self.grid.is_none() {
            return Err(raise(
                Kind::Options,
                "velocity_col names columns of a file: read the file with it (hbid.read)",
            ));
        }
        match (&self.x[..], &self.grid) {
            ([], _) => Err(raise(
                Kind::Options,
                "give a path, or the samples x (with t, dt or a record's grid)",
            )),
            (coords, None) => Ok(Source::Arrays {
                coords: coords.iter().map(Vec::as_slice).collect(),
                t: self.t.as_deref(),
                drives: self.drives.iter().map(Vec::as_slice).collect(),
            }),
            ([x, others @ ..], Some(Grid(t0, dt, pieces, signal, bridged))) => {
                let pieces: Vec<Range<usize>> = pieces.iter().map(|&(a, b)| a..b).collect();
                let bridged: Vec<Range<usize>> = bridged.iter().map(|&(a, b)| a..b).collect();
                if bridged
                    .iter()
                    .any(|b| b.start >= b.end || !pieces.iter().any(|p| p.start < b.start && b.end < p.end))
                {
                    return Err(raise(
                        Kind::Options,
                        "a record's bridged samples lie inside its pieces, none at a piece's end",
                    ));
                }
                for series in self.x.iter().chain(&self.drives).chain(&self.velocities) {
                    if series.len() != x.len() {
                        return Err(raise(
                            Kind::Options,
                            format!(
                                "a record's series have {} and {} samples: one per sample of its grid",
                                x.len(),
                                series.len()
                            ),
                        ));
                    }
                }
                for c in &self.x {
                    circle_signal::check_pieces(c, &pieces).map_err(|e| raise(Kind::Input, e))?;
                }
                if !(dt.is_finite() && *dt > 0.0 && t0.is_finite()) {
                    return Err(raise(
                        Kind::Options,
                        format!(
                            "a record's grid needs a finite t0 and a positive step (t0 = {t0}, dt = {dt})"
                        ),
                    ));
                }
                let signals: SignalList = signal.parse().map_err(|e: String| raise(Kind::Options, e))?;
                if signals.len() != 1 && signals.len() != self.x.len() {
                    return Err(raise(
                        Kind::Options,
                        format!(
                            "a record's signal '{signal}' for {} coordinates: one for all or one per coordinate",
                            self.x.len()
                        ),
                    ));
                }
                Ok(Source::Grid(GridData {
                    t0: *t0,
                    dt: *dt,
                    x: x.clone(),
                    pieces,
                    domain: signals.first(),
                    others: others
                        .iter()
                        .enumerate()
                        .map(|(i, o)| Channel {
                            x: o.clone(),
                            domain: signals.of(i + 1),
                        })
                        .collect(),
                    drives: self.drives.clone(),
                    velocities: self.velocities.clone(),
                    bridged,
                    notes: Vec::new(),
                    lead_in: None,
                }))
            }
        }
    }

    /// The layer's sources: each file's, or the one record's.
    fn sources(&self) -> PyResult<Vec<Source<'_>>> {
        match &self.paths[..] {
            [_, _, ..] if self.x.is_empty() && self.grid.is_none() => {
                Ok(self.paths.iter().map(|p| Source::Path(p)).collect())
            }
            _ => Ok(vec![self.source()?]),
        }
    }
}

/// The samples of optional arrays, copied.
fn copies(arrays: &Arrays<'_>) -> PyResult<Vec<Vec<f64>>> {
    arrays
        .iter()
        .flatten()
        .map(|a| crate::slice(a).map(<[f64]>::to_vec))
        .collect::<PyResult<Vec<_>>>()
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
/// does (grid, gaps, wrapping, spikes, integration): what `hbid.read` returns. `coords`,
/// `drives` and `velocities` are every coordinate's, drive's and measured velocity's samples on
/// the grid, `names` and `drive_names` the names terms call them; `spikes` are `(index, size,
/// replaced, coordinate)`.
#[pyfunction]
#[pyo3(signature = (options, *, path=None, x=None, t=None, drive=None))]
pub fn condition<'py>(
    py: Python<'py>,
    options: &str,
    path: Option<PathBuf>,
    x: Arrays<'py>,
    t: Option<PyReadonlyArray1<'py, f64>>,
    drive: Arrays<'py>,
) -> PyResult<Bound<'py, PyDict>> {
    let record: RecordOptions =
        hb_pipeline::options::from_object(self::options(options)?).map_err(option_error)?;
    let names = record.names().map_err(option_error)?;
    let velocity: Arrays<'py> = None;
    let samples = Samples::new(path.into_iter().collect(), &x, &t, &drive, &velocity, None)?;
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
            Note::Spikes {
                found,
                repaired,
                coordinate,
                ..
            } => spikes.extend(found.iter().map(|s| (s.index, s.size, *repaired, *coordinate))),
            _ => {}
        }
    }
    spikes.sort_by_key(|s| (s.3, s.0));
    let domains: Vec<&str> = std::iter::once(grid.domain)
        .chain(grid.others.iter().map(|c| c.domain))
        .map(|d| d.name())
        .collect();
    let signal = if domains.iter().all(|d| *d == domains[0]) {
        domains[0].to_owned()
    } else {
        domains.join(",")
    };
    out.set_item("t0", grid.t0)?;
    out.set_item("dt", grid.dt)?;
    out.set_item(
        "pieces",
        PyList::new(py, grid.pieces.iter().map(|r| (r.start, r.end)))?,
    )?;
    out.set_item(
        "bridged",
        PyList::new(py, grid.bridged.iter().map(|r| (r.start, r.end)))?,
    )?;
    out.set_item("signal", signal)?;
    out.set_item("measured", record.measured.to_string())?;
    out.set_item("repaired", record.repair)?;
    out.set_item("notes", notice_texts(&notices.0))?;
    out.set_item("lead_rows", grid.lead_in.as_ref().map_or(0, |l| l.t.len()))?;
    out.set_item("time_repairs", time_repairs)?;
    out.set_item("spikes", spikes)?;
    out.set_item("names", names.coordinates())?;
    out.set_item(
        "drive_names",
        &names.drives()[..grid.drives.len().min(names.drives().len())],
    )?;
    out.set_item("drive", grid.drives.first().map(|p| PyArray1::from_slice(py, p)))?;
    out.set_item(
        "drives",
        PyList::new(py, grid.drives.iter().map(|p| PyArray1::from_slice(py, p)))?,
    )?;
    out.set_item(
        "velocities",
        PyList::new(py, grid.velocities.iter().map(|v| PyArray1::from_slice(py, v)))?,
    )?;
    out.set_item(
        "coords",
        PyList::new(
            py,
            std::iter::once(grid.x.as_slice())
                .chain(grid.others.iter().map(|c| c.x.as_slice()))
                .map(|c| PyArray1::from_slice(py, c)),
        )?,
    )?;
    out.set_item("x", PyArray1::from_vec(py, grid.x))?;
    Ok(out)
}

/// Identifies the equations of motion as `hbid identify --json` does: the report's JSON, the
/// model's bytes (a system of several coordinates as a system) and the notices. Several `path`s
/// are joined into one record, as the command line joins several files.
#[pyfunction]
#[pyo3(signature = (options, *, path=None, x=None, t=None, drive=None, velocity=None, grid=None))]
#[allow(clippy::too_many_arguments)]
pub fn identify<'py>(
    py: Python<'py>,
    options: &str,
    path: Option<Vec<PathBuf>>,
    x: Arrays<'py>,
    t: Option<PyReadonlyArray1<'py, f64>>,
    drive: Arrays<'py>,
    velocity: Arrays<'py>,
    grid: Option<Grid>,
) -> PyResult<Bound<'py, PyDict>> {
    let request = IdentifyRequest::from_json(self::options(options)?).map_err(option_error)?;
    let samples = Samples::new(path.unwrap_or_default(), &x, &t, &drive, &velocity, grid)?;
    let sources = samples.sources()?;
    let mut notices = Notices::default();
    let (json, model) = py
        .detach(|| {
            let report = hb_pipeline::identify_records(sources, &request, &mut notices)?;
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
#[pyo3(signature = (options, *, path=None, x=None, t=None, drive=None, velocity=None, grid=None))]
#[allow(clippy::too_many_arguments)]
pub fn embed<'py>(
    py: Python<'py>,
    options: &str,
    path: Option<PathBuf>,
    x: Arrays<'py>,
    t: Option<PyReadonlyArray1<'py, f64>>,
    drive: Arrays<'py>,
    velocity: Arrays<'py>,
    grid: Option<Grid>,
) -> PyResult<Bound<'py, PyDict>> {
    let request = EmbedRequest::from_json(self::options(options)?).map_err(option_error)?;
    let samples = Samples::new(path.into_iter().collect(), &x, &t, &drive, &velocity, grid)?;
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
#[pyo3(signature = (options, *, path=None, x=None, t=None, drive=None, velocity=None, grid=None))]
#[allow(clippy::too_many_arguments)]
pub fn upos<'py>(
    py: Python<'py>,
    options: &str,
    path: Option<PathBuf>,
    x: Arrays<'py>,
    t: Option<PyReadonlyArray1<'py, f64>>,
    drive: Arrays<'py>,
    velocity: Arrays<'py>,
    grid: Option<Grid>,
) -> PyResult<Bound<'py, PyDict>> {
    let request = UposRequest::from_json(self::options(options)?).map_err(option_error)?;
    let samples = Samples::new(path.into_iter().collect(), &x, &t, &drive, &velocity, grid)?;
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
            Ok::<_, hb_pipeline::RunError>((simulation.table_columns(), simulation.columns(), json))
        })
        .map_err(run_error)?;
    let column = |i: usize| PyArray1::from_slice(py, &table[i]);
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
/// measured output, as `hbid compare --json` does: the report's JSON, each entry's runs as
/// `(start, init, t, measured, x, v)` pieces (an entry per range, of a system per range and
/// coordinate), and the notices.
#[pyfunction]
#[pyo3(signature = (model, options, *, path=None, x=None, t=None, drive=None, velocity=None, grid=None))]
#[allow(clippy::too_many_arguments)]
pub fn compare<'py>(
    py: Python<'py>,
    model: &[u8],
    options: &str,
    path: Option<PathBuf>,
    x: Arrays<'py>,
    t: Option<PyReadonlyArray1<'py, f64>>,
    drive: Arrays<'py>,
    velocity: Arrays<'py>,
    grid: Option<Grid>,
) -> PyResult<Bound<'py, PyDict>> {
    let model = hb_model::IdentifiedSystem::from_bytes(model).map_err(|e| raise(Kind::Model, e))?;
    let request = CompareRequest::from_json(self::options(options)?).map_err(option_error)?;
    let samples = Samples::new(path.into_iter().collect(), &x, &t, &drive, &velocity, grid)?;
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

/// The columns of a run by name, as arrays: `columns` and `values` (one array per column).
fn run_columns<'py>(py: Python<'py>, run: &hb_pipeline::ModelRun, out: &Bound<'py, PyDict>) -> PyResult<()> {
    let column = |i: usize| PyArray1::from_vec(py, run.rows.iter().map(|row| row[i]).collect());
    out.set_item("columns", &run.columns)?;
    out.set_item("values", PyList::new(py, (0..run.columns.len()).map(column))?)?;
    out.set_item("stopped", run.stopped.clone())?;
    Ok(())
}

/// A saved model or system run from `(x0, v0)` (one position and velocity per coordinate) over
/// the even grid of times `t`, driven by `drive` (one series per measured drive of the model, in
/// the order of its names): the columns (`t`, the coordinates, their velocities) and why the
/// run stopped, if it did.
#[pyfunction]
#[pyo3(signature = (model, t, *, x0, v0, drive=None, rtol=None))]
pub fn model_run_on<'py>(
    py: Python<'py>,
    model: &[u8],
    t: PyReadonlyArray1<'py, f64>,
    x0: Vec<f64>,
    v0: Vec<f64>,
    drive: Arrays<'py>,
    rtol: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let rtol = rtol.unwrap_or(pendulum_sim::Tolerances::DEFAULT_RTOL);
    let system = hb_model::IdentifiedSystem::from_bytes(model).map_err(|e| raise(Kind::Model, e))?;
    // Copied under the interpreter's lock, as every function's samples are.
    let times = crate::slice(&t)?.to_vec();
    let drives = copies(&drive)?;
    let drives: Vec<&[f64]> = drives.iter().map(Vec::as_slice).collect();
    let run = py
        .detach(|| hb_pipeline::run_system_on_times(&system, &times, &drives, &x0, &v0, rtol))
        .map_err(run_error)?;
    let out = PyDict::new(py);
    run_columns(py, &run, &out)?;
    Ok(out)
}

/// A saved model run over a record's grid under its measured drive, as `hbid simulate --model
/// --input` does: its columns at every sample run (`t,x,v`, or of a system `t`, the coordinates
/// and their velocities) and why the run stopped, if it did. `rig` holds the options of
/// `simulate` for a built-in system: any set away from its default is refused, as the command
/// line refuses it.
#[pyfunction]
#[pyo3(signature = (model, options, rig, *, path=None, x=None, t=None, drive=None, velocity=None, grid=None, out=None))]
#[allow(clippy::too_many_arguments)]
pub fn model_run<'py>(
    py: Python<'py>,
    model: &[u8],
    options: &str,
    rig: &str,
    path: Option<PathBuf>,
    x: Arrays<'py>,
    t: Option<PyReadonlyArray1<'py, f64>>,
    drive: Arrays<'py>,
    velocity: Arrays<'py>,
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
    let samples = Samples::new(path.into_iter().collect(), &x, &t, &drive, &velocity, grid)?;
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
    let dict = PyDict::new(py);
    run_columns(py, &run, &dict)?;
    dict.set_item("notes", notice_texts(&notices.0))?;
    Ok(dict)
}
