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

/// What can be wrong with an input. Line numbers count from 1 and include comment lines.
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
    /// Nothing but comments and white space.
    #[error("the input is empty")]
    Empty,
    /// A header but no data rows.
    #[error("the input has a header but no data rows")]
    NoData,
    /// A column the reader needs is not in the header.
    #[error("no column {wanted} in the input (columns: {found}); choose one with {option}")]
    MissingColumn {
        /// The column wanted.
        wanted: String,
        /// The header, or the number of columns.
        found: String,
        /// The option that picks it.
        option: &'static str,
    },
    /// A column option that is neither a name nor a positive position.
    #[error("'{given}' is not a column: give a header name or a position counted from 1")]
    BadColumn {
        /// What was given.
        given: String,
    },
    /// A non-positive or non-finite `--dt`.
    #[error("--dt {dt} must be positive and finite")]
    BadStep {
        /// The step given.
        dt: f64,
    },
    /// Both a time column and `--dt`.
    #[error("give either --dt or --time-col, not both")]
    TimeTwice,
    /// Neither a time column nor `--dt` for a single-channel record.
    #[error("the input has a single column: give its sampling step with --dt")]
    NeedStep,
    /// A cell is not a number.
    #[error("line {line}: '{value}' in column {column} is not a number")]
    NotANumber {
        /// Line number.
        line: u64,
        /// Column.
        column: String,
        /// The cell.
        value: String,
    },
    /// A value is NaN or infinite.
    #[error("{at}: {what} is {value}: only finite numbers are accepted")]
    NonFinite {
        /// Where ("line 12" or "sample 12").
        at: String,
        /// Which value.
        what: &'static str,
        /// The value.
        value: f64,
    },
    /// A row has a different number of cells from the first row.
    #[error("line {line}: {found} cells where the first row has {expected}")]
    Ragged {
        /// Line number.
        line: u64,
        /// Cells in the first row.
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
    /// An `.npy` file that cannot be read.
    #[error("not a readable .npy array: {why}")]
    Npy {
        /// Why.
        why: String,
    },
    /// Too few samples.
    #[error("{found} samples: at least {needed} are needed")]
    TooFewSamples {
        /// Samples in the record.
        found: usize,
        /// Samples needed.
        needed: usize,
    },
    /// Time does not increase.
    #[error("{at}: time {t} does not increase (previous sample at {previous})")]
    TimeNotIncreasing {
        /// Where.
        at: String,
        /// The time.
        t: f64,
        /// The previous time.
        previous: f64,
    },
    /// A time step differs from the mean step by more than 1e-6 relative.
    #[error(
        "{at}: time step {step} differs from the record's mean step {mean} (more than 1e-6 relative): resample to a uniform grid first"
    )]
    NonUniform {
        /// Where.
        at: String,
        /// The step.
        step: f64,
        /// The mean step.
        mean: f64,
    },
    /// A forcing period that is not positive.
    #[error("--forcing-period {period} must be positive and finite")]
    BadForcingPeriod {
        /// The period given.
        period: f64,
    },
    /// The forcing period is not a whole number of samples.
    #[error(
        "the forcing period {period} is {ratio} sampling steps of {dt}, not a whole number (nearest: {nearest}); the method needs a whole number of samples per forcing period"
    )]
    NotWholeSamples {
        /// Forcing period.
        period: f64,
        /// Sampling step.
        dt: f64,
        /// Their ratio.
        ratio: f64,
        /// The nearest whole number.
        nearest: u64,
    },
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
        read_npy(bytes, options)
    } else {
        read_csv_with(bytes, options)
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
    read_csv_with(&bytes, &ReadOptions::default())
}

fn column_index(
    wanted: Option<&Column>,
    header: Option<&csv::StringRecord>,
    default_name: &str,
    default_position: usize,
    width: usize,
    option: &'static str,
) -> Result<usize, InputError> {
    let missing = |wanted: String| InputError::MissingColumn {
        wanted,
        found: match header {
            Some(h) => h.iter().collect::<Vec<_>>().join(","),
            None => format!("{width} unnamed"),
        },
        option,
    };
    match (wanted, header) {
        (Some(Column::Position(p)), _) => {
            if *p <= width {
                Ok(p - 1)
            } else {
                Err(missing(p.to_string()))
            }
        }
        (Some(Column::Name(n)), Some(h)) => h
            .iter()
            .position(|c| c == n)
            .ok_or_else(|| missing(format!("'{n}'"))),
        (Some(Column::Name(n)), None) => Err(missing(format!("'{n}'"))),
        (None, Some(h)) => h
            .iter()
            .position(|c| c == default_name)
            .ok_or_else(|| missing(format!("'{default_name}'"))),
        (None, None) => {
            if default_position <= width {
                Ok(default_position - 1)
            } else {
                Err(missing(default_position.to_string()))
            }
        }
    }
}

fn read_csv_with(bytes: &[u8], options: &ReadOptions) -> Result<Record, InputError> {
    let mut reader = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .has_headers(false)
        .flexible(false)
        .trim(csv::Trim::All)
        .from_reader(bytes);
    let mut row = csv::StringRecord::new();
    let first = loop {
        match reader.read_record(&mut row) {
            Ok(false) => return Err(InputError::Empty),
            Ok(true) if row.len() == 1 && row[0].is_empty() => continue,
            Ok(true) => break row.clone(),
            Err(e) => return Err(csv_error(e)),
        }
    };
    let is_header = first.iter().any(|c| c.parse::<f64>().is_err());
    let header = is_header.then_some(&first);
    let width = first.len();
    let time = match options.dt {
        Some(_) => None,
        None => {
            if header.is_none() && width == 1 && options.time.is_none() {
                return Err(InputError::NeedStep);
            }
            Some(column_index(
                options.time.as_ref(),
                header,
                "t",
                1,
                width,
                "--time-col",
            )?)
        }
    };
    let angle_default = if options.dt.is_some() { 1 } else { 2 };
    let angle = column_index(
        options.angle.as_ref(),
        header,
        "theta",
        angle_default,
        width,
        "--angle-col",
    )?;
    let name = |i: usize| match header {
        Some(h) => format!("'{}'", &h[i]),
        None => (i + 1).to_string(),
    };
    let (time_name, angle_name) = (time.map(name).unwrap_or_default(), name(angle));

    let mut record = Record {
        lines: Some(Vec::new()),
        ..Record::default()
    };
    let lines = record.lines.as_mut().expect("text input has lines");
    let mut counter = LineCounter {
        bytes,
        pos: 0,
        line: 1,
    };
    let mut push = |row: &csv::StringRecord| -> Result<(), InputError> {
        let line = row.position().map_or(0, |p| counter.line_at(p.byte()));
        if let Some(it) = time {
            record.t.push(cell(row, it, &time_name, line)?);
        }
        record.theta.push(cell(row, angle, &angle_name, line)?);
        lines.push(line);
        Ok(())
    };
    if !is_header {
        push(&first)?;
    }
    loop {
        match reader.read_record(&mut row) {
            Ok(false) => break,
            Ok(true) if row.len() == 1 && row[0].is_empty() => continue,
            Ok(true) => push(&row)?,
            Err(e) => return Err(csv_error(e)),
        }
    }
    if record.theta.is_empty() {
        return Err(InputError::NoData);
    }
    if let Some(dt) = options.dt {
        record.t = (0..record.theta.len()).map(|n| n as f64 * dt).collect();
    }
    Ok(record)
}

/// Physical line numbers (comment lines included, which the CSV parser does not count) from
/// byte offsets that only move forward.
struct LineCounter<'a> {
    bytes: &'a [u8],
    pos: usize,
    line: u64,
}

impl LineCounter<'_> {
    fn line_at(&mut self, byte: u64) -> u64 {
        let target = (byte as usize).min(self.bytes.len());
        if target > self.pos {
            self.line += self.bytes[self.pos..target]
                .iter()
                .filter(|&&b| b == b'\n')
                .count() as u64;
            self.pos = target;
        }
        // The parser's record position may point at comment or blank lines skipped before it.
        while self.pos < self.bytes.len() && matches!(self.bytes[self.pos], b'#' | b'\n' | b'\r') {
            match self.bytes[self.pos..].iter().position(|&b| b == b'\n') {
                Some(nl) => {
                    self.pos += nl + 1;
                    self.line += 1;
                }
                None => break,
            }
        }
        self.line
    }
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
            at: format!("line {line}"),
            what: if column == "'t'" { "the time" } else { "a value" },
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
        csv::ErrorKind::Utf8 { pos, .. } => InputError::Malformed {
            line: pos.map_or(line, |p| p.line()),
            why: "not UTF-8 text (binary data?)".to_owned(),
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

fn npy_error(why: impl std::fmt::Display) -> InputError {
    InputError::Npy { why: why.to_string() }
}

/// Reads all elements of an `.npy` payload as f64, whatever the supported element type.
fn npy_values(npy: npyz::NpyFile<&[u8]>) -> Result<Vec<f64>, InputError> {
    fn collect<T: npyz::Deserialize + Into<f64>, R: Read>(
        r: npyz::NpyReader<T, R>,
    ) -> Result<Vec<f64>, InputError> {
        r.map(|v| v.map(Into::into))
            .collect::<Result<_, _>>()
            .map_err(npy_error)
    }
    let npy = match npy.try_data::<f64>() {
        Ok(r) => return collect(r),
        Err(npy) => npy,
    };
    let npy = match npy.try_data::<f32>() {
        Ok(r) => return collect(r),
        Err(npy) => npy,
    };
    let npy = match npy.try_data::<i32>() {
        Ok(r) => return collect(r),
        Err(npy) => npy,
    };
    let npy = match npy.try_data::<i16>() {
        Ok(r) => return collect(r),
        Err(npy) => npy,
    };
    match npy.try_data::<i64>() {
        // Encoder counts fit in 53 bits; larger ones would not convert exactly and are refused.
        Ok(r) => r
            .map(|v| {
                let v = v.map_err(npy_error)?;
                if v.unsigned_abs() > (1u64 << 53) {
                    Err(npy_error(format!("integer {v} is too large to convert exactly")))
                } else {
                    Ok(v as f64)
                }
            })
            .collect(),
        Err(npy) => Err(npy_error(format!(
            "element type {:?} is not supported (use f8, f4, i8, i4 or i2)",
            npy.dtype()
        ))),
    }
}

fn read_npy(bytes: &[u8], options: &ReadOptions) -> Result<Record, InputError> {
    let mut probe = bytes;
    npyz::NpyHeader::from_reader(&mut probe).map_err(npy_error)?;
    let payload = probe.len();
    let npy = npyz::NpyFile::new(bytes).map_err(npy_error)?;
    let shape: Vec<u64> = npy.shape().to_vec();
    let order = npy.order();
    let total: u64 = shape
        .iter()
        .try_fold(1u64, |a, &b| a.checked_mul(b))
        .ok_or_else(|| npy_error("shape overflows"))?;
    let item = npy.dtype().num_bytes().unwrap_or(usize::MAX) as u64;
    // Check the payload's size before allocating anything the header claims.
    if total.checked_mul(item).is_none_or(|n| n > payload as u64) {
        return Err(npy_error(format!(
            "the header announces {total} elements but the file holds {} bytes of data",
            payload
        )));
    }
    let (rows, cols) = match shape[..] {
        [n] => (n as usize, 1usize),
        [n, m] => (n as usize, m as usize),
        _ => {
            return Err(npy_error(format!(
                "shape {shape:?}: expected 1-D (angle) or 2-D (samples × channels)"
            )));
        }
    };
    if rows == 0 || cols == 0 {
        return Err(InputError::NoData);
    }
    // Little-endian f8, the usual case (and 10^7-sample records): read straight from the payload,
    // without a converted copy of every element.
    let payload_bytes = &bytes[bytes.len() - payload..];
    let plain_f8 = npy.dtype().descr() == "'<f8'";
    let values = if plain_f8 { Vec::new() } else { npy_values(npy)? };
    let index = |r: usize, c: usize| match order {
        npyz::Order::C => r * cols + c,
        npyz::Order::Fortran => c * rows + r,
    };
    let at = |r: usize, c: usize| {
        let i = index(r, c);
        if plain_f8 {
            let mut le = [0u8; 8];
            le.copy_from_slice(&payload_bytes[8 * i..8 * i + 8]);
            f64::from_le_bytes(le)
        } else {
            values[i]
        }
    };
    let pick = |wanted: Option<&Column>, default: usize, option: &'static str| -> Result<usize, InputError> {
        let p = match wanted {
            Some(Column::Position(p)) => *p,
            Some(Column::Name(n)) => {
                return Err(InputError::MissingColumn {
                    wanted: format!("'{n}'"),
                    found: format!("{cols} unnamed (.npy has no names: give positions)"),
                    option,
                });
            }
            None => default,
        };
        if p > cols {
            return Err(InputError::MissingColumn {
                wanted: p.to_string(),
                found: format!("{cols} unnamed"),
                option,
            });
        }
        Ok(p - 1)
    };
    let angle = pick(
        options.angle.as_ref(),
        if options.dt.is_some() || cols == 1 { 1 } else { 2 },
        "--angle-col",
    )?;
    let theta: Vec<f64> = (0..rows).map(|r| at(r, angle)).collect();
    let t: Vec<f64> = match options.dt {
        Some(dt) => (0..rows).map(|n| n as f64 * dt).collect(),
        None => {
            if cols == 1 && options.time.is_none() {
                return Err(InputError::NeedStep);
            }
            let it = pick(options.time.as_ref(), 1, "--time-col")?;
            (0..rows).map(|r| at(r, it)).collect()
        }
    };
    for (i, (&ti, &xi)) in t.iter().zip(&theta).enumerate() {
        for (what, v) in [("the time", ti), ("a value", xi)] {
            if !v.is_finite() {
                return Err(InputError::NonFinite {
                    at: format!("sample {}", i + 1),
                    what,
                    value: v,
                });
            }
        }
    }
    Ok(Record {
        t,
        theta,
        lines: None,
    })
}

/// A record on a uniform time grid: `t_n = t0 + n · dt`.
#[derive(Debug, Clone, PartialEq)]
pub struct UniformRecord {
    /// Time of the first sample.
    pub t0: f64,
    /// Sampling step.
    pub dt: f64,
    /// The samples.
    pub x: Vec<f64>,
}

/// Largest relative deviation of a time step from the mean step that counts as uniform.
pub const UNIFORM_TOLERANCE: f64 = 1e-6;

impl UniformRecord {
    /// Checks that time increases in uniform steps (within [`UNIFORM_TOLERANCE`] relative).
    pub fn new(record: Record) -> Result<Self, InputError> {
        let n = record.t.len();
        if n < 2 {
            return Err(InputError::TooFewSamples { found: n, needed: 2 });
        }
        let at = |i: usize| match &record.lines {
            Some(lines) => format!("line {}", lines[i]),
            None => format!("sample {}", i + 1),
        };
        for i in 1..n {
            if record.t[i] <= record.t[i - 1] {
                return Err(InputError::TimeNotIncreasing {
                    at: at(i),
                    t: record.t[i],
                    previous: record.t[i - 1],
                });
            }
        }
        let mean = (record.t[n - 1] - record.t[0]) / (n - 1) as f64;
        for i in 1..n {
            let step = record.t[i] - record.t[i - 1];
            if (step - mean).abs() > UNIFORM_TOLERANCE * mean {
                return Err(InputError::NonUniform {
                    at: at(i),
                    step,
                    mean,
                });
            }
        }
        Ok(Self {
            t0: record.t[0],
            dt: mean,
            x: record.theta,
        })
    }

    /// The number of samples per forcing period `T / dt`, which must be a whole number within
    /// 1e-6 relative.
    pub fn samples_per_period(&self, forcing_period: f64) -> Result<usize, InputError> {
        if !(forcing_period.is_finite() && forcing_period > 0.0) {
            return Err(InputError::BadForcingPeriod {
                period: forcing_period,
            });
        }
        let ratio = forcing_period / self.dt;
        let nearest = ratio.round();
        if nearest < 1.0 || (ratio - nearest).abs() > UNIFORM_TOLERANCE * ratio {
            return Err(InputError::NotWholeSamples {
                period: forcing_period,
                dt: self.dt,
                ratio,
                nearest: nearest.max(0.0) as u64,
            });
        }
        Ok(nearest as usize)
    }

    /// Whether any sample lies outside `[−π, π)`: then the record is an unwrapped angle (or a
    /// displacement) and must be wrapped to be read as an angle on the circle.
    pub fn outside_circle(&self) -> bool {
        use std::f64::consts::PI;
        self.x.iter().any(|x| !(-PI..PI).contains(x))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str) -> Result<Record, InputError> {
        read_bytes(text.as_bytes(), &ReadOptions::default())
    }

    fn with(text: &str, options: ReadOptions) -> Result<Record, InputError> {
        read_bytes(text.as_bytes(), &options)
    }

    #[test]
    fn reads_with_comments_and_extra_columns() {
        let r = read("# a comment\nt,theta,omega\n0,0.1,0\n# mid\n0.5,-3.0,1e-3\n").unwrap();
        assert_eq!(r.t, vec![0.0, 0.5]);
        assert_eq!(r.theta, vec![0.1, -3.0]);
        assert_eq!(r.lines, Some(vec![3, 5]));
        let r = read("theta, t\n1,2\n").unwrap();
        assert_eq!((r.t[0], r.theta[0]), (2.0, 1.0));
    }

    #[test]
    fn headerless_and_column_choices() {
        let r = read("0,1.5\n1,2.5\n").unwrap();
        assert_eq!((r.t.clone(), r.theta.clone()), (vec![0.0, 1.0], vec![1.5, 2.5]));
        let opts = ReadOptions {
            dt: Some(0.5),
            ..Default::default()
        };
        let r = with("1.5\n2.5\n3.5\n", opts.clone()).unwrap();
        assert_eq!(r.t, vec![0.0, 0.5, 1.0]);
        assert!(matches!(read("1.5\n2.5\n"), Err(InputError::NeedStep)));
        let opts = ReadOptions {
            time: Some("time".parse().unwrap()),
            angle: Some("3".parse().unwrap()),
            dt: None,
        };
        let r = with("time,x,angle\n0,9,1\n1,9,2\n", opts).unwrap();
        assert_eq!(r.theta, vec![1.0, 2.0]);
        assert!("0".parse::<Column>().is_err());
        assert!("".parse::<Column>().is_err());
        let both = ReadOptions {
            time: Some(Column::Position(1)),
            dt: Some(1.0),
            angle: None,
        };
        assert!(matches!(with("1,2\n", both), Err(InputError::TimeTwice)));
    }

    #[test]
    fn bad_inputs_are_named() {
        assert!(matches!(read(""), Err(InputError::Empty)));
        assert!(matches!(read("# only a comment\n"), Err(InputError::Empty)));
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
            Err(InputError::NonFinite { at, .. }) if at == "line 3" => {}
            other => panic!("{other:?}"),
        }
        match read("t,theta\n0,1\n1,inf\n") {
            Err(InputError::NonFinite { .. }) => {}
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
        assert!(read_bytes(&[0xff, 0xfe, 0x00, 0x01], &ReadOptions::default()).is_err());
    }

    #[test]
    fn uniform_checks() {
        let rec = |t: Vec<f64>| Record {
            theta: vec![0.0; t.len()],
            t,
            lines: None,
        };
        assert!(matches!(
            UniformRecord::new(rec(vec![0.0])),
            Err(InputError::TooFewSamples { .. })
        ));
        assert!(matches!(
            UniformRecord::new(rec(vec![0.0, 1.0, 0.5])),
            Err(InputError::TimeNotIncreasing { .. })
        ));
        assert!(matches!(
            UniformRecord::new(rec(vec![0.0, 1.0, 2.1, 3.0])),
            Err(InputError::NonUniform { .. })
        ));
        let u = UniformRecord::new(rec((0..100).map(|n| 10.0 + n as f64 * 0.04).collect())).unwrap();
        assert!((u.dt - 0.04).abs() < 1e-15 && u.t0 == 10.0);
        assert_eq!(u.samples_per_period(1.0).unwrap(), 25);
        match u.samples_per_period(1.01) {
            Err(InputError::NotWholeSamples { nearest: 25, .. }) => {}
            other => panic!("{other:?}"),
        }
        assert!(u.samples_per_period(-1.0).is_err());
        assert!(u.samples_per_period(0.01).is_err());
    }

    fn npy_bytes(descr: &str, shape: &str, fortran: bool, payload: &[u8]) -> Vec<u8> {
        let mut header = format!(
            "{{'descr': '{descr}', 'fortran_order': {}, 'shape': {shape}, }}",
            if fortran { "True" } else { "False" }
        );
        while (10 + header.len() + 1) % 64 != 0 {
            header.push(' ');
        }
        header.push('\n');
        let mut out = b"\x93NUMPY\x01\x00".to_vec();
        out.extend_from_slice(&(header.len() as u16).to_le_bytes());
        out.extend_from_slice(header.as_bytes());
        out.extend_from_slice(payload);
        out
    }

    #[test]
    fn reads_npy_1d_2d_and_orders() {
        let f8: Vec<u8> = [0.0f64, 0.5, 1.0, 0.1, 0.2, 0.3]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        // C order, 3 samples × 2 channels: rows (0, 0.5), (1, 0.1), (0.2, 0.3).
        let r = read_bytes(&npy_bytes("<f8", "(3, 2)", false, &f8), &ReadOptions::default()).unwrap();
        assert_eq!(r.t, vec![0.0, 1.0, 0.2]);
        assert_eq!(r.theta, vec![0.5, 0.1, 0.3]);
        // Fortran order: column 1 is (0, 0.5, 1), column 2 is (0.1, 0.2, 0.3).
        let r = read_bytes(&npy_bytes("<f8", "(3, 2)", true, &f8), &ReadOptions::default()).unwrap();
        assert_eq!(r.t, vec![0.0, 0.5, 1.0]);
        assert_eq!(r.theta, vec![0.1, 0.2, 0.3]);
        let dt = ReadOptions {
            dt: Some(0.1),
            ..Default::default()
        };
        let r = read_bytes(&npy_bytes("<f8", "(6,)", false, &f8), &dt).unwrap();
        assert_eq!(r.theta.len(), 6);
        assert!(matches!(
            read_bytes(&npy_bytes("<f8", "(6,)", false, &f8), &ReadOptions::default()),
            Err(InputError::NeedStep)
        ));
        let i4: Vec<u8> = [1i32, -2, 3].iter().flat_map(|v| v.to_le_bytes()).collect();
        let r = read_bytes(&npy_bytes("<i4", "(3,)", false, &i4), &dt).unwrap();
        assert_eq!(r.theta, vec![1.0, -2.0, 3.0]);
        // A header that promises more data than the file holds.
        assert!(matches!(
            read_bytes(&npy_bytes("<f8", "(1000000000000,)", false, &f8), &dt),
            Err(InputError::Npy { .. })
        ));
        let nan: Vec<u8> = [0.0f64, f64::NAN].iter().flat_map(|v| v.to_le_bytes()).collect();
        assert!(matches!(
            read_bytes(&npy_bytes("<f8", "(2,)", false, &nan), &dt),
            Err(InputError::NonFinite { .. })
        ));
    }

    proptest::proptest! {
        #[test]
        fn csv_never_panics_on_arbitrary_bytes(bytes in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..300)) {
            let _ = read_bytes(&bytes, &ReadOptions::default());
            let _ = read_bytes(&bytes, &ReadOptions { dt: Some(0.1), ..Default::default() });
        }

        #[test]
        fn npy_never_panics_on_corrupted_files(
            cut in 0usize..200,
            flips in proptest::collection::vec((0usize..200, proptest::prelude::any::<u8>()), 0..6),
        ) {
            let f8: Vec<u8> = (0..12).flat_map(|v| (v as f64).to_le_bytes()).collect();
            let mut bytes = npy_bytes("<f8", "(6, 2)", false, &f8);
            for (i, b) in flips {
                if i < bytes.len() { bytes[i] = b; }
            }
            bytes.truncate(cut.max(6));
            let _ = read_bytes(&bytes, &ReadOptions::default());
            let _ = read_bytes(&bytes, &ReadOptions { dt: Some(0.1), ..Default::default() });
        }

        #[test]
        fn csv_round_trips_numbers(values in proptest::collection::vec(-1e6..1e6f64, 1..50)) {
            let mut text = String::from("t,theta\n");
            for (i, v) in values.iter().enumerate() {
                text.push_str(&format!("{i},{v}\n"));
            }
            let r = read_bytes(text.as_bytes(), &ReadOptions::default()).unwrap();
            proptest::prop_assert_eq!(r.theta, values);
        }
    }
}
