//! Rust errors as the Python exceptions of `hbid.errors`, with the command line's messages.

use std::error::Error;
use std::fmt::Display;

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
}

impl Kind {
    fn class(self) -> &'static str {
        match self {
            Kind::Input => "InputError",
            Kind::Options => "OptionsError",
            Kind::Identification => "IdentificationError",
            Kind::Simulation => "SimulationError",
            Kind::Model => "ModelError",
        }
    }
}

/// The message of `error` and of every error below it, joined by `": "` (as the command line
/// prints them).
pub fn chain(error: &(dyn Error + 'static)) -> String {
    let mut text = error.to_string();
    let mut source = error.source();
    while let Some(e) = source {
        text.push_str(": ");
        text.push_str(&e.to_string());
        source = e.source();
    }
    text
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

/// The exception `kind` carrying `error`'s messages.
pub fn from_error(kind: Kind, error: &(dyn Error + 'static)) -> PyErr {
    raise(kind, chain(error))
}

/// Converts a Rust error into the exception `kind`.
pub trait OrRaise<T> {
    /// `Ok` as it is, `Err` as the exception `kind`.
    fn or_raise(self, kind: Kind) -> PyResult<T>;
}

impl<T, E: Error + 'static> OrRaise<T> for Result<T, E> {
    fn or_raise(self, kind: Kind) -> PyResult<T> {
        self.map_err(|e| from_error(kind, &e))
    }
}
