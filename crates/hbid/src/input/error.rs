//! What can be wrong with an input.

use std::path::PathBuf;

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
