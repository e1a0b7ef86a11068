//! Rust errors as the Python exceptions of `hbid.errors`, with the command line's messages and
//! the options named as the Python arguments that set them.

use std::error::Error;
use std::fmt::Display;

use hb_pipeline::{ErrorKind, OptionError, RunError, Spelling};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyString;

/// Which exception of `hbid.errors` an error becomes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// `InputError`: the record (file, columns, time stamps, values).
    Input,
    /// `OptionsError`: an argument's value, or a combination of arguments.
    Options,
    /// `IdentificationError`: the analysis of a valid record failed (too few segments, a
    /// rank-deficient system, no first minimum of the mutual information).
    Identification,
    /// `SimulationError`: a simulation failed.
    Simulation,
    /// `ModelError`: a saved model that cannot be read or written.
    Model,
    /// `OutputError`: a result file that cannot be written.
    Output,
}

impl Kind {
    fn class(self) -> &'static str {
        match self {
            Kind::Input => "InputError",
            Kind::Options => "OptionsError",
            Kind::Identification => "IdentificationError",
            Kind::Simulation => "SimulationError",
            Kind::Model => "ModelError",
            Kind::Output => "OutputError",
        }
    }
}

impl From<ErrorKind> for Kind {
    fn from(kind: ErrorKind) -> Self {
        match kind {
            ErrorKind::Input => Kind::Input,
            ErrorKind::Options => Kind::Options,
            ErrorKind::Identification => Kind::Identification,
            ErrorKind::Simulation => Kind::Simulation,
            ErrorKind::Model => Kind::Model,
            ErrorKind::Output => Kind::Output,
        }
    }
}

/// The message of `error` and of every error below it, joined by `": "` (as the command line
/// prints them), with the options spelled as Python arguments.
pub fn chain(error: &(dyn Error + 'static)) -> String {
    let mut text = error.to_string();
    let mut source = error.source();
    while let Some(e) = source {
        let more = e.to_string();
        if !text.contains(&more) {
            text.push_str(": ");
            text.push_str(&more);
        }
        source = e.source();
    }
    Spelling::Python.render(&text)
}

/// The exception `kind` with `message`.
pub fn raise(kind: Kind, message: impl Display) -> PyErr {
    let message = message.to_string();
    Python::attach(|py| {
        let made = py
            .import("hbid.errors")
            .and_then(|m| m.getattr(kind.class()))
            .and_then(|class| class.call1((PyString::new(py, &message),)));
        match made {
            Ok(instance) => PyErr::from_value(instance),
            Err(_) => PyRuntimeError::new_err(message),
        }
    })
}

/// A run's error as its exception: the kind by the error's variant.
pub fn run_error(error: RunError) -> PyErr {
    raise(error.kind().into(), chain(&error))
}

/// A bad option as `OptionsError`.
pub fn option_error(error: OptionError) -> PyErr {
    raise(Kind::Options, error.spelled(Spelling::Python))
}

/// Converts a Rust error into the exception `kind`.
pub trait OrRaise<T> {
    /// `Ok` as it is, `Err` as the exception `kind`.
    fn or_raise(self, kind: Kind) -> PyResult<T>;
}

impl<T, E: Error + 'static> OrRaise<T> for Result<T, E> {
    fn or_raise(self, kind: Kind) -> PyResult<T> {
        self.map_err(|e| raise(kind, chain(&e)))
    }
}
