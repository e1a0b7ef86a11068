//! Records: read from a file or taken from arrays, and made ready for analysis exactly as the
//! command line makes them (`hbid::prepare`).

use std::ops::Range;
use std::path::PathBuf;

use circle_signal::Domain;
use hbid::input::{Column, InputError, Location, ReadOptions, Record as InputRecord, Role, read_path};
use hbid::prepare::{Data, DriveSpec, GridData, Note, PrepareError, PrepareOptions, condition};
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::errors::Kind;
use crate::options::{Failure, bad, fail};

/// A record's grid as Python hands it back (from a `Record` of `read`): the time of sample 0,
/// the sampling step and the ranges of samples that hold data, `(start, stop)`.
#[derive(Debug, Clone, FromPyObject)]
pub struct Grid(pub f64, pub f64, pub Vec<(usize, usize)>);

/// Where a record comes from: samples with their time stamps or step, or samples already on
/// their grid.
#[derive(Debug)]
pub enum Source<'a> {
    /// Samples with time stamps (`t`) or a step (`dt`), to be fitted to a grid.
    Raw {
        /// The samples.
        x: &'a [f64],
        /// Their time stamps.
        t: Option<&'a [f64]>,
        /// Or their step.
        dt: Option<f64>,
        /// Repair glitches and spikes.
        repair: bool,
    },
    /// Samples on a grid already (NaN outside the pieces).
    Grid {
        /// The samples.
        x: &'a [f64],
        /// Their grid.
        grid: Grid,
    },
}

/// Texts of the notes as `(text, is_warning)`, warnings with the Python argument that fixes
/// them.
fn note_texts(notes: &[Note]) -> Vec<(String, bool)> {
    notes
        .iter()
        .map(|n| {
            if n.is_warning() {
                (format!("{n}; read with repair=True to replace them"), true)
            } else {
                (n.to_string(), false)
            }
        })
        .collect()
}

/// An input error with the Python arguments that fix it, as the command line names its options.
fn input_failure(error: InputError) -> Failure {
    let hint = match &error {
        InputError::NeedStep => " with dt=",
        InputError::BadStep { .. } => " (dt=)",
        InputError::TimeTwice => " (dt=, time_col=)",
        InputError::MissingColumn { role: Role::Time, .. } => "; choose one with time_col=",
        InputError::MissingColumn {
            role: Role::Angle, ..
        } => "; choose one with angle_col=",
        InputError::BadForcingPeriod { .. } => " (forcing_period=)",
        InputError::TimeGlitch { isolated: true, .. } => "; pass repair=True to fix isolated glitches",
        InputError::TimeGlitch { isolated: false, .. } | InputError::TimeUnresolved { .. } => " with dt=",
        _ => "",
    };
    (Kind::Input, format!("{}{hint}", crate::errors::chain(&error)))
}

fn prepare_failure(error: PrepareError) -> Failure {
    match error {
        PrepareError::Input(e) => input_failure(e),
        PrepareError::DriveSearch(e) => fail(Kind::Options)(e),
        PrepareError::DriveEstimate(_) | PrepareError::FreePeriod(_) => fail(Kind::Identification)(error),
        e => fail(Kind::Input)(e),
    }
}

/// Checks that every time and value is finite, naming the first sample that is not (as the
/// `.npy` reader does).
fn check_finite(t: &[f64], theta: &[f64]) -> Result<(), Failure> {
    for (i, (&ti, &xi)) in t.iter().zip(theta).enumerate() {
        for (role, value) in [(Role::Time, ti), (Role::Angle, xi)] {
            if !value.is_finite() {
                return Err(input_failure(InputError::NonFinite {
                    at: Location::Sample(i + 1),
                    role,
                    value,
                }));
            }
        }
    }
    Ok(())
}

/// The samples `x` with their time stamps `t` or their step `dt`, as a read record.
fn input_record(x: &[f64], t: Option<&[f64]>, dt: Option<f64>) -> Result<InputRecord, Failure> {
    let t = match (t, dt) {
        (Some(_), Some(_)) => return Err(bad("give t or dt, not both")),
        (None, None) => return Err(bad("give the time stamps t or the sampling step dt")),
        (Some(t), None) => {
            if t.len() != x.len() {
                return Err(bad(format!(
                    "t has {} values and x {}: give one time per sample",
                    t.len(),
                    x.len()
                )));
            }
            t.to_vec()
        }
        (None, Some(dt)) => {
            if !(dt.is_finite() && dt > 0.0) {
                return Err(input_failure(InputError::BadStep { dt }));
            }
            (0..x.len()).map(|i| i as f64 * dt).collect()
        }
    };
    let theta = x.to_vec();
    check_finite(&t, &theta)?;
    Ok(InputRecord {
        t,
        theta,
        lines: None,
        drive: None,
    })
}

/// The record of `source` on its grid.
pub fn grid_data(source: Source<'_>, signal: Domain) -> Result<GridData, Failure> {
    match source {
        Source::Raw { x, t, dt, repair } => {
            let record = input_record(x, t, dt)?;
            let options = PrepareOptions::new(signal).with_repair(repair);
            condition(record, &options, &mut |_| {}).map_err(prepare_failure)
        }
        Source::Grid { x, grid } => {
            let Grid(t0, dt, pieces) = grid;
            let pieces: Vec<Range<usize>> = pieces.iter().map(|&(a, b)| a..b).collect();
            circle_signal::check_pieces(x, &pieces).map_err(fail(Kind::Input))?;
            if !(dt.is_finite() && dt > 0.0 && t0.is_finite()) {
                return Err(bad(format!(
                    "a record's grid needs a finite t0 and a positive step (t0 = {t0}, dt = {dt})"
                )));
            }
            Ok(GridData {
                t0,
                dt,
                x: x.to_vec(),
                pieces,
                domain: signal,
                drive: None,
                notes: Vec::new(),
            })
        }
    }
}

/// The record of `source` ready for analysis: on its grid, its clock found by `drive`.
pub fn data(source: Source<'_>, signal: Domain, drive: DriveSpec) -> Result<Data, Failure> {
    grid_data(source, signal)?
        .with_drive(drive, &mut |_, _| {})
        .map_err(prepare_failure)
}

/// Reads a record from a file (text or `.npy`) and fits it to its grid, as `hbid` does.
#[pyfunction]
#[pyo3(signature = (path, *, time_col=None, angle_col=None, dt=None, repair=false, signal="circle"))]
pub fn read<'py>(
    py: Python<'py>,
    path: PathBuf,
    time_col: Option<String>,
    angle_col: Option<String>,
    dt: Option<f64>,
    repair: bool,
    signal: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let grid = py
        .detach(|| -> Result<GridData, Failure> {
            let signal = crate::options::domain(signal, "signal", false)?;
            let column = |s: &Option<String>, argument: &str| {
                s.as_deref()
                    .map(str::parse::<Column>)
                    .transpose()
                    .map_err(|e| bad(format!("{argument}: {e}")))
            };
            let options = ReadOptions {
                time: column(&time_col, "time_col")?,
                angle: column(&angle_col, "angle_col")?,
                dt,
                drive: None,
            };
            let name = path.display().to_string();
            let record = read_path(&path, &options).map_err(|e| {
                let (kind, text) = input_failure(e);
                (kind, format!("{name}: {text}"))
            })?;
            let options = PrepareOptions::new(signal).with_repair(repair);
            condition(record, &options, &mut |_| {}).map_err(|e| {
                let (kind, text) = prepare_failure(e);
                (kind, format!("{name}: {text}"))
            })
        })
        .map_err(crate::raise)?;
    grid_dict(py, grid, repair)
}

/// Fits samples with time stamps (or a step) to their grid, as `hbid` does with a file.
#[pyfunction]
#[pyo3(signature = (x, *, t=None, dt=None, repair=false, signal="circle"))]
pub fn condition_arrays<'py>(
    py: Python<'py>,
    x: PyReadonlyArray1<'py, f64>,
    t: Option<PyReadonlyArray1<'py, f64>>,
    dt: Option<f64>,
    repair: bool,
    signal: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let x = crate::slice(&x)?;
    let t = t.as_ref().map(crate::slice).transpose()?;
    let grid = py
        .detach(|| {
            let signal = crate::options::domain(signal, "signal", false)?;
            grid_data(Source::Raw { x, t, dt, repair }, signal)
        })
        .map_err(crate::raise)?;
    grid_dict(py, grid, repair)
}

/// A record on its grid as a dict: `t0`, `dt`, `x`, `pieces`, `signal`, `repaired`, `notes`
/// (`(text, is_warning)`), `time_repairs` (`(where, was, now)`) and `spikes` (`(index, size,
/// replaced)`).
fn grid_dict(py: Python<'_>, grid: GridData, repaired: bool) -> PyResult<Bound<'_, PyDict>> {
    let out = PyDict::new(py);
    let notes = note_texts(&grid.notes);
    let mut time_repairs = Vec::new();
    let mut spikes = Vec::new();
    for note in &grid.notes {
        match note {
            Note::TimeRepaired(r) => time_repairs.push((r.at.to_string(), r.was, r.now)),
            Note::Spikes { found, repaired, .. } => {
                spikes.extend(found.iter().map(|s| (s.index, s.size, *repaired)));
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
    out.set_item("signal", domain_name(grid.domain))?;
    out.set_item("repaired", repaired)?;
    out.set_item("notes", notes)?;
    out.set_item("time_repairs", time_repairs)?;
    out.set_item("spikes", spikes)?;
    out.set_item("x", PyArray1::from_vec(py, grid.x))?;
    Ok(out)
}

/// `circle` or `line`.
pub fn domain_name(domain: Domain) -> &'static str {
    match domain {
        Domain::Circle => "circle",
        Domain::Line => "line",
    }
}
