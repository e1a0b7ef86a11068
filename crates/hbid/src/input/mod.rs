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

pub use error::{InputError, Location};
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

    /// The one column policy of both readers: which columns hold the time and the angle, given
    /// the header's names (`None` without a header, as always for `.npy`) and the number of
    /// columns. The options are assumed valid ([`ReadOptions::validate`]).
    ///
    /// A column chosen in the options is found by name or position. The defaults are the columns
    /// named `t` and `theta` with a header, positions 1 and 2 without. With a sampling step there
    /// is no time column and the angle defaults to position 1 (still `theta` with a header). A
    /// single unnamed column with neither a sampling step nor a time column is an angle whose
    /// step is missing.
    pub(crate) fn columns(&self, names: Option<&[&str]>, width: usize) -> Result<Columns, InputError> {
        let default = |role: Role| match (names, role, self.dt) {
            (Some(_), Role::Time, _) => Column::Name("t".to_owned()),
            (Some(_), Role::Angle, _) => Column::Name("theta".to_owned()),
            (None, Role::Time, _) | (None, Role::Angle, Some(_)) => Column::Position(1),
            (None, Role::Angle, None) => Column::Position(2),
        };
        let chosen = |role: Role| {
            let wanted = match role {
                Role::Time => &self.time,
                Role::Angle => &self.angle,
            };
            let wanted = wanted.clone().unwrap_or_else(|| default(role));
            find(role, wanted, names, width)
        };
        let time = match self.dt {
            Some(dt) => Times::Step(dt),
            None if names.is_none() && width == 1 && self.time.is_none() => {
                return Err(InputError::NeedStep);
            }
            None => Times::Column(chosen(Role::Time)?),
        };
        Ok(Columns {
            time,
            angle: chosen(Role::Angle)?,
        })
    }
}

/// What a column holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// The sample times.
    Time,
    /// The angle (or displacement).
    Angle,
}

impl std::fmt::Display for Role {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Role::Time => "time",
            Role::Angle => "angle",
        })
    }
}

/// Where a record's times and angles come from; columns count from 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Columns {
    /// The times.
    pub(crate) time: Times,
    /// The angle column.
    pub(crate) angle: usize,
}

/// Where the sample times come from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Times {
    /// This column.
    Column(usize),
    /// No column: sample n is at `n · dt`.
    Step(f64),
}

impl Times {
    /// The time column, if any.
    pub(crate) fn column(self) -> Option<usize> {
        match self {
            Times::Column(i) => Some(i),
            Times::Step(_) => None,
        }
    }
}

/// The index of the column `wanted` among `width` columns with these names (if any).
fn find(role: Role, wanted: Column, names: Option<&[&str]>, width: usize) -> Result<usize, InputError> {
    let index = match (&wanted, names) {
        (Column::Position(p), _) => (1..=width).contains(p).then(|| p - 1),
        (Column::Name(n), Some(names)) => names.iter().position(|c| c == n),
        (Column::Name(_), None) => None,
    };
    index.ok_or_else(|| InputError::MissingColumn {
        role,
        wanted,
        found: names.map_or_else(Vec::new, |n| n.iter().map(|&c| c.to_owned()).collect()),
        width,
    })
}

/// Reads a record from a path (`-` is standard input), CSV or `.npy` by content.
pub fn read_path(path: &Path, options: &ReadOptions) -> Result<Record, InputError> {
    // Before reading, so that bad options do not wait for standard input.
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
    read_valid(&bytes, options)
}

/// Reads a record from bytes in memory, CSV or `.npy` by content.
pub fn read_bytes(bytes: &[u8], options: &ReadOptions) -> Result<Record, InputError> {
    options.validate()?;
    read_valid(bytes, options)
}

/// Reads a record with options already validated.
fn read_valid(bytes: &[u8], options: &ReadOptions) -> Result<Record, InputError> {
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

/// The times of `n` samples `dt` apart from 0, for records without a time column.
fn grid(n: usize, dt: f64) -> Vec<f64> {
    (0..n).map(|i| i as f64 * dt).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn options(time: Option<&str>, angle: Option<&str>, dt: Option<f64>) -> ReadOptions {
        let column = |c: Option<&str>| c.map(|c| c.parse().expect("a column"));
        ReadOptions {
            time: column(time),
            angle: column(angle),
            dt,
        }
    }

    #[test]
    fn one_column_policy() {
        let header = Some(&["x", "theta", "t"][..]);
        let at = |time, angle| Columns { time, angle };
        let none = options(None, None, None);
        assert_eq!(none.columns(header, 3).unwrap(), at(Times::Column(2), 1));
        assert_eq!(none.columns(None, 3).unwrap(), at(Times::Column(0), 1));
        let step = options(None, None, Some(0.5));
        assert_eq!(step.columns(header, 3).unwrap(), at(Times::Step(0.5), 1));
        assert_eq!(step.columns(None, 3).unwrap(), at(Times::Step(0.5), 0));
        assert_eq!(step.columns(None, 1).unwrap(), at(Times::Step(0.5), 0));
        let chosen = options(Some("3"), Some("x"), None);
        assert_eq!(chosen.columns(header, 3).unwrap(), at(Times::Column(2), 0));
        // A single unnamed column needs a step; with a header the defaults are names.
        assert!(matches!(none.columns(None, 1), Err(InputError::NeedStep)));
        assert!(matches!(
            none.columns(Some(&["theta"][..]), 1),
            Err(InputError::MissingColumn { .. })
        ));
        // Names need a header; positions count from 1 and stay within the columns.
        for (chosen, names, width) in [
            (options(Some("t"), None, None), None, 2),
            (options(None, Some("4"), None), header, 3),
            (options(None, None, None), None, 1),
            (
                ReadOptions {
                    angle: Some(Column::Position(0)),
                    ..step.clone()
                },
                None,
                2,
            ),
        ] {
            match chosen.columns(names, width) {
                Err(InputError::MissingColumn { .. } | InputError::NeedStep) => {}
                other => panic!("{chosen:?}: {other:?}"),
            }
        }
    }

    #[test]
    fn both_readers_follow_the_same_policy() {
        let rows: [[f64; 3]; 3] = [[0.0, 0.1, 0.2], [1.0, 1.1, 1.2], [2.0, 2.1, 2.2]];
        let text: String = rows
            .iter()
            .map(|r| format!("{},{},{}\n", r[0], r[1], r[2]))
            .collect();
        let payload: Vec<u8> = rows.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
        let array = npy::npy_bytes("<f8", "(3, 3)", false, &payload);
        let first: Vec<u8> = rows.iter().flat_map(|r| r[0].to_le_bytes()).collect();
        let single = npy::npy_bytes("<f8", "(3,)", false, &first);
        let cases = [
            (options(None, None, None), 3),
            (options(None, None, Some(0.5)), 3),
            (options(Some("2"), Some("3"), None), 3),
            (options(None, Some("4"), None), 3),
            (options(Some("t"), None, None), 3),
            (options(None, Some("theta"), Some(0.5)), 3),
            (options(None, None, None), 1),
            (options(None, None, Some(0.5)), 1),
            (options(Some("1"), None, None), 1),
        ];
        for (options, width) in cases {
            let (text, npy) = if width == 3 {
                (text.clone(), &array)
            } else {
                (rows.iter().map(|r| format!("{}\n", r[0])).collect(), &single)
            };
            match (read_bytes(text.as_bytes(), &options), read_bytes(npy, &options)) {
                (Ok(a), Ok(b)) => assert_eq!((a.t, a.theta), (b.t, b.theta), "{options:?}"),
                (Err(a), Err(b)) => assert_eq!(a.to_string(), b.to_string(), "{options:?}"),
                other => panic!("{options:?}, {width} columns: {other:?}"),
            }
        }
    }

    #[test]
    fn options_are_checked_before_reading() {
        let bad = options(None, None, Some(-1.0));
        assert!(matches!(
            read_path(Path::new("/no/such/file.csv"), &bad),
            Err(InputError::BadStep { .. })
        ));
        let both = options(Some("1"), None, Some(1.0));
        assert!(matches!(read_bytes(b"1,2\n", &both), Err(InputError::TimeTwice)));
    }
}
