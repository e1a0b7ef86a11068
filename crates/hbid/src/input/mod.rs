//! Reading records: CSV text or NumPy `.npy`, from a file or standard input, and the checks a
//! record must pass before identification (uniform time steps, a whole number of samples per
//! forcing period).
//!
//! CSV: `#` starts a comment line; the first non-comment row is a header when any of its cells is
//! not a number. Columns are picked by name or by 1-based position ([`Column`]); the defaults are
//! the columns named `t` and `theta`, or, without a header, column 1 (time) and column 2 (angle).
//! With `dt` given there is no time column: sample n is at `n · dt` and the angle defaults to
//! column 1.
//!
//! `.npy` (recognised by its magic bytes): a 1-D array is the angle (it needs `dt`); a 2-D array
//! holds samples in rows and channels in columns, picked by position like CSV columns. Element
//! types f8, f4, i8, i4 and i2 are read (integers, e.g. raw encoder counts, convert exactly).
//!
//! This module holds the record, the options and the entry points; `csv` and `npy` are the two
//! readers, `uniform` the checks before identification and `error` what can go wrong
//! ([`InputError`]).

mod csv;
mod error;
mod npy;
mod uniform;

pub use error::InputError;
pub use uniform::{UNIFORM_TOLERANCE, UniformRecord};

use std::io::Read;
use std::path::{Path, PathBuf};
use std::str::FromStr;

/// A record as read: sample times and the angle (or displacement) at each.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Record {
    /// Sample times.
    pub t: Vec<f64>,
    /// The angle (or displacement) at each time.
    pub theta: Vec<f64>,
    /// For text input, the line of each sample (1-based, comments included), to name it in errors.
    pub lines: Option<Vec<u64>>,
}

/// A column chosen by header name or by 1-based position.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Column {
    /// The column whose header is this name.
    Name(String),
    /// The column at this 1-based position.
    Position(usize),
}

impl FromStr for Column {
    type Err = InputError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let s = s.trim();
        if s.is_empty() {
            return Err(InputError::BadColumn { given: s.to_owned() });
        }
        if s.bytes().all(|b| b.is_ascii_digit()) {
            return match s.parse::<usize>() {
                Ok(p) if p >= 1 => Ok(Column::Position(p)),
                _ => Err(InputError::BadColumn { given: s.to_owned() }),
            };
        }
        Ok(Column::Name(s.to_owned()))
    }
}

impl std::fmt::Display for Column {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Column::Name(n) => write!(f, "'{n}'"),
            Column::Position(p) => write!(f, "{p}"),
        }
    }
}

/// How to read a record.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ReadOptions {
    /// The time column (default: `t`, or column 1 without a header).
    pub time: Option<Column>,
    /// The angle column (default: `theta`, or column 2 without a header; column 1 with `dt`).
    pub angle: Option<Column>,
    /// A fixed sampling step instead of a time column.
    pub dt: Option<f64>,
}

impl ReadOptions {
    /// Checks the options on their own.
    pub fn validate(&self) -> Result<(), InputError> {
        if let Some(dt) = self.dt {
            if !(dt.is_finite() && dt > 0.0) {
                return Err(InputError::BadStep { dt });
            }
            if self.time.is_some() {
                return Err(InputError::TimeTwice);
            }
        }
        Ok(())
    }
}

/// Reads a record from a path (`-` is standard input), CSV or `.npy` by content.
pub fn read_path(path: &Path, options: &ReadOptions) -> Result<Record, InputError> {
    options.validate()?;
    let io = |source| InputError::Io {
        path: path.to_owned(),
        source,
    };
    let bytes = if path == Path::new("-") {
        let mut buf = Vec::new();
        std::io::stdin().lock().read_to_end(&mut buf).map_err(io)?;
        buf
    } else {
        if path.is_dir() {
            return Err(InputError::IsFolder {
                path: path.to_owned(),
            });
        }
        std::fs::read(path).map_err(io)?
    };
    read_bytes(&bytes, options)
}

/// Reads a record from bytes in memory, CSV or `.npy` by content.
pub fn read_bytes(bytes: &[u8], options: &ReadOptions) -> Result<Record, InputError> {
    options.validate()?;
    if bytes.starts_with(b"\x93NUMPY") {
        npy::read(bytes, options)
    } else {
        csv::read(bytes, options)
    }
}

/// Reads CSV text with the default columns `t` and `theta`.
pub fn read_csv(input: impl Read) -> Result<Record, InputError> {
    let mut bytes = Vec::new();
    let mut input = input;
    input.read_to_end(&mut bytes).map_err(|source| InputError::Io {
        path: PathBuf::from("<input>"),
        source,
    })?;
    csv::read(&bytes, &ReadOptions::default())
}
