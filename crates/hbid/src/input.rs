//! Reading records: CSV with a header naming a time column `t` and an angle column `theta`.

use std::io::Read;
use std::path::{Path, PathBuf};

/// A uniformly or non-uniformly sampled record as read (checks of uniformity come later).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Record {
    /// Sample times.
    pub t: Vec<f64>,
    /// The angle (or displacement) at each time.
    pub theta: Vec<f64>,
}

/// What can be wrong with an input file. Line numbers count from 1 and include comment lines.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum InputError {
    /// The file cannot be opened or read.
    #[error("cannot read {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The path is a folder.
    #[error("{path} is a folder, not a file")]
    IsFolder {
        /// The path.
        path: PathBuf,
    },
    /// No header line at all.
    #[error("the input is empty (no header line)")]
    Empty,
    /// A header but no data rows.
    #[error("the input has a header but no data rows")]
    NoData,
    /// A column the reader needs is not in the header.
    #[error("no column named '{name}' in the header (columns: {found})")]
    MissingColumn {
        /// The column wanted.
        name: String,
        /// The header as found.
        found: String,
    },
    /// A cell is not a number.
    #[error("line {line}: '{value}' in column '{column}' is not a number")]
    NotANumber {
        /// Line number.
        line: u64,
        /// Column name.
        column: String,
        /// The cell.
        value: String,
    },
    /// A cell is NaN or infinite.
    #[error("line {line}: column '{column}' is {value}: only finite numbers are accepted")]
    NonFinite {
        /// Line number.
        line: u64,
        /// Column name.
        column: String,
        /// The value.
        value: f64,
    },
    /// A row has a different number of cells from the header.
    #[error("line {line}: {found} cells where the header has {expected}")]
    Ragged {
        /// Line number.
        line: u64,
        /// Cells in the header.
        expected: usize,
        /// Cells in this row.
        found: usize,
    },
    /// The bytes are not CSV text.
    #[error("line {line}: not CSV text ({why})")]
    Malformed {
        /// Line number.
        line: u64,
        /// The parser's complaint.
        why: String,
    },
}

/// Reads CSV text with a header line; `#` starts a comment line. The columns `t` and `theta`
/// must be present (others are allowed and ignored); every cell of those columns must be a
/// finite number.
pub fn read_csv(input: impl Read) -> Result<Record, InputError> {
    let mut reader = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .has_headers(true)
        .flexible(false)
        .trim(csv::Trim::All)
        .from_reader(input);
    let headers = reader.headers().map_err(csv_error)?.clone();
    if headers.is_empty() || (headers.len() == 1 && headers[0].is_empty()) {
        return Err(InputError::Empty);
    }
    let find = |name: &str| {
        headers
            .iter()
            .position(|h| h == name)
            .ok_or_else(|| InputError::MissingColumn {
                name: name.to_owned(),
                found: headers.iter().collect::<Vec<_>>().join(","),
            })
    };
    let (it, ix) = (find("t")?, find("theta")?);
    let mut record = Record::default();
    let mut row = csv::StringRecord::new();
    loop {
        match reader.read_record(&mut row) {
            Ok(false) => break,
            Ok(true) => {}
            Err(e) => return Err(csv_error(e)),
        }
        let line = row.position().map_or(0, |p| p.line());
        record.t.push(cell(&row, it, "t", line)?);
        record.theta.push(cell(&row, ix, "theta", line)?);
    }
    if record.t.is_empty() {
        return Err(InputError::NoData);
    }
    Ok(record)
}

/// [`read_csv`] from a file.
pub fn read_csv_file(path: &Path) -> Result<Record, InputError> {
    if path.is_dir() {
        return Err(InputError::IsFolder {
            path: path.to_owned(),
        });
    }
    let file = std::fs::File::open(path).map_err(|source| InputError::Io {
        path: path.to_owned(),
        source,
    })?;
    read_csv(std::io::BufReader::new(file))
}

fn cell(row: &csv::StringRecord, index: usize, column: &str, line: u64) -> Result<f64, InputError> {
    let text = &row[index];
    let value: f64 = text.parse().map_err(|_| InputError::NotANumber {
        line,
        column: column.to_owned(),
        value: text.chars().take(40).collect(),
    })?;
    if !value.is_finite() {
        return Err(InputError::NonFinite {
            line,
            column: column.to_owned(),
            value,
        });
    }
    Ok(value)
}

fn csv_error(e: csv::Error) -> InputError {
    let line = e.position().map_or(0, |p| p.line());
    match e.into_kind() {
        csv::ErrorKind::UnequalLengths {
            expected_len,
            len,
            pos,
        } => InputError::Ragged {
            line: pos.map_or(line, |p| p.line()),
            expected: expected_len as usize,
            found: len as usize,
        },
        csv::ErrorKind::Utf8 { pos, err } => InputError::Malformed {
            line: pos.map_or(line, |p| p.line()),
            why: format!("invalid UTF-8: {err}"),
        },
        csv::ErrorKind::Io(source) => InputError::Io {
            path: PathBuf::from("<input>"),
            source,
        },
        other => InputError::Malformed {
            line,
            why: format!("{other:?}"),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str) -> Result<Record, InputError> {
        read_csv(text.as_bytes())
    }

    #[test]
    fn reads_with_comments_and_extra_columns() {
        let r = read("# a comment\nt,theta,omega\n0,0.1,0\n# mid\n0.5,-3.0,1e-3\n").unwrap();
        assert_eq!(r.t, vec![0.0, 0.5]);
        assert_eq!(r.theta, vec![0.1, -3.0]);
        let r = read("theta, t\n1,2\n").unwrap();
        assert_eq!((r.t[0], r.theta[0]), (2.0, 1.0));
    }

    #[test]
    fn bad_inputs_are_named() {
        assert!(matches!(read(""), Err(InputError::Empty)));
        assert!(matches!(read("t,theta\n"), Err(InputError::NoData)));
        assert!(matches!(
            read("time,angle\n1,2\n"),
            Err(InputError::MissingColumn { .. })
        ));
        match read("t,theta\n0,1\n1,abc\n") {
            Err(InputError::NotANumber { line: 3, .. }) => {}
            other => panic!("{other:?}"),
        }
        match read("t,theta\n0,1\n1,NaN\n") {
            Err(InputError::NonFinite { line: 3, .. }) => {}
            other => panic!("{other:?}"),
        }
        match read("t,theta\n0,1\n1\n") {
            Err(InputError::Ragged {
                line: 3,
                expected: 2,
                found: 1,
            }) => {}
            other => panic!("{other:?}"),
        }
        assert!(read_csv(&[0xff, 0xfe, 0x00, 0x01][..]).is_err());
    }

    proptest::proptest! {
        #[test]
        fn never_panics_on_arbitrary_bytes(bytes in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..300)) {
            let _ = read_csv(&bytes[..]);
        }
    }
}
