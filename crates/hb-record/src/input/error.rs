//! What can be wrong with an input, and where.
//!
//! The texts name the input's own terms (a sampling step, a time column), never the options of a
//! program that reads it: the command line adds its option names itself.

use std::fmt;
use std::path::PathBuf;

use super::{Column, RecordEnd, Role, Separator, UNSETTLED_FRACTION, UNSETTLED_MAX};

/// What an error about a missing value adds: how to read the record without its row.
const MISSING_HINT: &str =
    " (a missing value: «skip_missing=True» leaves out every row with one, as a logger's dropped row)";

/// Where in the input a value is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Location {
    /// A line of text, counted from 1, comment lines included.
    Line(u64),
    /// A sample of an array, counted from 1.
    Sample(usize),
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::Line(n) => write!(f, "line {n}"),
            Location::Sample(n) => write!(f, "sample {n}"),
        }
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
    /// Every row has a missing value in a column read
    /// ([`ReadOptions::skip_missing`](super::ReadOptions::skip_missing)).
    #[error("every row ({rows}) has a missing value in a column read: no row is left")]
    AllMissing {
        /// The rows left out.
        rows: usize,
    },
    /// A column the reader needs is not in the input.
    #[error("no {role} column {wanted} in the input ({})", columns_found(.found, *.width, .wanted))]
    MissingColumn {
        /// What the column would hold.
        role: Role,
        /// The column wanted, chosen or by default.
        wanted: Column,
        /// The header's names; empty without a header.
        found: Vec<String>,
        /// The number of columns.
        width: usize,
    },
    /// A column chosen by a name that the header gives to several columns.
    #[error("the {role} column '{name}' is ambiguous: the header names columns {} so (choose one by its position)",
        positions.iter().map(|p| p.to_string()).collect::<Vec<_>>().join(" and "))]
    AmbiguousColumn {
        /// What the column would hold.
        role: Role,
        /// The name.
        name: String,
        /// The 1-based positions of the columns of that name.
        positions: Vec<usize>,
    },
    /// A column option that is neither a name nor a positive position.
    #[error("'{given}' is not a column: give a header name or a position counted from 1")]
    BadColumn {
        /// What was given.
        given: String,
    },
    /// One column chosen for two roles.
    #[error(
        "column {column} {}",
        match first == second {
            true => format!("is chosen twice, as two {second} columns"),
            false => format!("cannot be both the {first} and the {second}"),
        }
    )]
    ColumnTwice {
        /// The column as chosen.
        column: Column,
        /// What it already is.
        first: Role,
        /// What it was also chosen for.
        second: Role,
    },
    /// A sampling step that is not positive and finite.
    #[error("the sampling step {} must be positive and finite", circle_signal::Shown(*.dt))]
    BadStep {
        /// The step given.
        dt: f64,
    },
    /// Both a time column and a sampling step.
    #[error("give either a sampling step or a time column, not both")]
    TimeTwice,
    /// A single unnamed column, and neither a sampling step nor a time column chosen.
    #[error("the input has a single column: give its sampling step")]
    NeedStep,
    /// A cell is not a number.
    #[error(
        "line {line}: '{value}' in column {column} is not a number{}",
        if *.missing { MISSING_HINT } else { "" }
    )]
    NotANumber {
        /// Line number.
        line: u64,
        /// The column, by name with a header, by position without.
        column: Column,
        /// The cell.
        value: String,
        /// Whether the cell is empty or a missing value's marker (`NA`, `null`, ...).
        missing: bool,
    },
    /// A value is NaN or infinite.
    #[error(
        "{at}: {} is {value} in column {column}: only finite numbers are accepted{}",
        .role.value_noun(),
        if .value.is_nan() { MISSING_HINT } else { "" }
    )]
    NonFinite {
        /// Where.
        at: Location,
        /// What the value is.
        role: Role,
        /// The column, by name with a header, by position without (a `.npy`'s by position).
        column: Column,
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
    /// A row whose cells are separated otherwise than the first row's.
    #[error("line {line}: cells separated by {found} where the first row uses {expected}")]
    MixedSeparators {
        /// Line number.
        line: u64,
        /// The separator of the first row.
        expected: Separator,
        /// The separator of this row.
        found: Separator,
    },
    /// The bytes are not text.
    #[error("line {line}: not text (not UTF-8: binary data?)")]
    Malformed {
        /// Line number.
        line: u64,
        /// Why the bytes are not UTF-8.
        #[source]
        source: std::str::Utf8Error,
    },
    /// An `.npy` file that cannot be read.
    #[error("not a readable .npy array: {why}")]
    Npy {
        /// Why.
        why: String,
    },
    /// A sampling step so large that the times of the samples overflow.
    #[error("{samples} samples of step {dt:e} reach past the largest number")]
    StepOverflow {
        /// The step.
        dt: f64,
        /// The samples.
        samples: usize,
    },
    /// Too few samples.
    #[error("{found} samples: at least {needed} are needed")]
    TooFewSamples {
        /// Samples in the record.
        found: usize,
        /// Samples needed.
        needed: usize,
    },
    /// Time decreases in most steps.
    #[error("{at}: time {} does not increase (previous sample at {})", circle_signal::Shown(*.t), circle_signal::Shown(*.previous))]
    TimeNotIncreasing {
        /// Where.
        at: Location,
        /// The time.
        t: f64,
        /// The previous time.
        previous: f64,
    },
    /// A time stamp that goes backwards, repeats the previous one or does not fit the grid of the
    /// others, and is not repaired: either repair was not asked for, or the glitch is not
    /// isolated.
    #[error(
        "{at}: time {t} {fault}; on the grid of step {} this sample is at {}{}: {}",
        Rounded(*.dt),
        Rounded(*.expected),
        other_glitches(.others, *.other_count),
        glitch_advice(*.isolated)
    )]
    TimeGlitch {
        /// Where.
        at: Location,
        /// The time stamp.
        t: f64,
        /// What is wrong with it.
        fault: StampFault,
        /// The time of the sample on the grid, counted from its nearest good neighbour.
        expected: f64,
        /// The grid's step.
        dt: f64,
        /// Whether the neighbours on both sides fit the grid, one step away or with a gap beside
        /// it and the stamp within 0.4 steps of a free slot, so that repair would replace this
        /// stamp by its grid time.
        isolated: bool,
        /// The next glitches after this one that are errors too (at most five), in order.
        others: Vec<Location>,
        /// How many glitches after this one are errors too (all of them, named or not).
        other_count: usize,
    },
    /// A run of time stamps at an end of the record that do not fit the grid of the rest, as a
    /// logger's before it settles to its rate (or after it leaves it), too long to leave out
    /// ([`super::Unsettled`]): more than [`super::UNSETTLED_FRACTION`] of the record's samples or
    /// [`super::UNSETTLED_MAX`].
    #[error(
        "{first} to {last}: the {} {count} time stamps are {} to {} steps of {} apart, off the grid of the rest: more than the {bound} samples at an end of a record ({}) that are left out as a logger settling to its rate; if these samples are not wanted, remove their rows; if they are, correct their time stamps",
        .end.which(),
        Rounded(*.shortest / *.dt).digits(2),
        Rounded(*.longest / *.dt).digits(2),
        Rounded(*.dt).digits(6),
        unsettled_bound()
    )]
    TimeUnsettled {
        /// Which end of the record.
        end: RecordEnd,
        /// Where the run's first sample is.
        first: Location,
        /// Where its last sample is.
        last: Location,
        /// The samples in the run.
        count: usize,
        /// The shortest step between its stamps, the step to the rest included.
        shortest: f64,
        /// The longest such step.
        longest: f64,
        /// The step of the grid of the rest.
        dt: f64,
        /// The most samples left out at an end of this record.
        bound: usize,
    },
    /// So many time stamps are off the grid or repeated that they cannot be glitches: the stamps
    /// do not resolve the samples (printed with too few decimals, or jittering).
    #[error(
        "{off} of {total} time stamps are off the grid of the others or repeat the previous one{}{}: they do not resolve the samples; if the sampling is uniform, give its step",
        printed_hint(*.decimals),
        scatter_hint(*.scatter)
    )]
    TimeUnresolved {
        /// Stamps off the grid or repeating the previous one.
        off: usize,
        /// Stamps in the record.
        total: usize,
        /// The decimals the stamps are written with, when they are all written with at most 9.
        decimals: Option<u32>,
        /// How far the stamps scatter about the grid, as a fraction of its step (robust standard
        /// deviation about the clock's level), when a grid was fitted.
        scatter: Option<f64>,
    },
    /// Time stamps so far apart that the times of their grid overflow (stamps near the largest
    /// floating-point numbers).
    #[error("{at}: time {t:e} is too far from the first stamps: the times of the grid overflow")]
    TimeOverflow {
        /// Where: the last sample.
        at: Location,
        /// Its time stamp.
        t: f64,
    },
    /// A gap in the time stamps that would make the record's grid far longer than its samples
    /// (a stamp far off the others: a logger's first stamp before its clock was set, a glitch
    /// at an end, a pause of hours).
    #[error(
        "{at}: time {t} follows {previous} after a gap of {missing} steps of {dt}, and the grid of the \
         record's {samples} samples would hold {grid} (a stamp far off the others? a logger's clock set \
         or reset there, or a pause): split the record there, or remove the stamp"
    )]
    GapTooLong {
        /// The first sample after the gap.
        at: Location,
        /// Its time stamp.
        t: f64,
        /// The stamp before the gap.
        previous: f64,
        /// Grid steps missing in the gap.
        missing: usize,
        /// The grid's step.
        dt: f64,
        /// Samples read.
        samples: usize,
        /// Grid points the record would span.
        grid: usize,
    },
    /// A drive period that is not positive and finite.
    #[error("the drive period {} must be positive and finite", circle_signal::Shown(*.period))]
    BadDrivePeriod {
        /// The period given.
        period: f64,
    },
}

impl InputError {
    /// The error with every place it names mapped by `at` (a chunk's places as the file's,
    /// [`super::Chunk::relocate`]); a line number is mapped as a [`Location::Line`].
    pub fn relocated(self, at: &dyn Fn(Location) -> Location) -> Self {
        let line = |n: u64| match at(Location::Line(n)) {
            Location::Line(m) => m,
            Location::Sample(_) => n,
        };
        match self {
            Self::NotANumber {
                line: n,
                column,
                value,
                missing,
            } => Self::NotANumber {
                line: line(n),
                column,
                value,
                missing,
            },
            Self::NonFinite {
                at: a,
                role,
                column,
                value,
            } => Self::NonFinite {
                at: at(a),
                role,
                column,
                value,
            },
            Self::Ragged {
                line: n,
                expected,
                found,
            } => Self::Ragged {
                line: line(n),
                expected,
                found,
            },
            Self::MixedSeparators {
                line: n,
                expected,
                found,
            } => Self::MixedSeparators {
                line: line(n),
                expected,
                found,
            },
            Self::Malformed { line: n, source } => Self::Malformed {
                line: line(n),
                source,
            },
            Self::TimeNotIncreasing { at: a, t, previous } => Self::TimeNotIncreasing {
                at: at(a),
                t,
                previous,
            },
            Self::TimeGlitch {
                at: a,
                t,
                fault,
                expected,
                dt,
                isolated,
                others,
                other_count,
            } => Self::TimeGlitch {
                at: at(a),
                t,
                fault,
                expected,
                dt,
                isolated,
                others: others.into_iter().map(at).collect(),
                other_count,
            },
            Self::TimeUnsettled {
                end,
                first,
                last,
                count,
                shortest,
                longest,
                dt,
                bound,
            } => Self::TimeUnsettled {
                end,
                first: at(first),
                last: at(last),
                count,
                shortest,
                longest,
                dt,
                bound,
            },
            Self::TimeOverflow { at: a, t } => Self::TimeOverflow { at: at(a), t },
            Self::GapTooLong {
                at: a,
                t,
                previous,
                missing,
                dt,
                samples,
                grid,
            } => Self::GapTooLong {
                at: at(a),
                t,
                previous,
                missing,
                dt,
                samples,
                grid,
            },
            other => other,
        }
    }
}

impl Role {
    /// The value in a column of this role, as the errors name it.
    fn value_noun(self) -> &'static str {
        match self {
            Role::Time => "the time",
            Role::Angle => "a value",
            Role::Drive => "a drive sample",
            Role::Velocity => "a velocity",
        }
    }
}

/// The columns an input has, for [`InputError::MissingColumn`].
fn columns_found(found: &[String], width: usize, wanted: &Column) -> String {
    match (found, wanted) {
        ([], Column::Name(_)) => format!("{width} unnamed columns: give a position"),
        ([], Column::Position(_)) => format!("{width} unnamed columns"),
        (names, _) => format!("columns: {}", names.join(",")),
    }
}

/// What is wrong with a time stamp.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StampFault {
    /// It is earlier than the previous stamp.
    Backwards {
        /// The previous stamp.
        previous: f64,
    },
    /// It is the previous stamp again.
    Repeated,
    /// It is off the grid of the others, or on it but out of place.
    OffGrid,
}

impl fmt::Display for StampFault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StampFault::Backwards { previous } => {
                write!(f, "does not increase (previous sample at {previous})")
            }
            StampFault::Repeated => f.write_str("repeats the previous stamp"),
            StampFault::OffGrid => f.write_str("does not fit the grid of the others"),
        }
    }
}

/// A computed number, written to 9 significant digits (the shortest text that reads back as
/// the rounded value).
pub(super) struct Rounded(pub(super) f64);

impl Rounded {
    /// The number to `digits` significant digits (at least 1).
    pub(super) fn digits(&self, digits: usize) -> String {
        let rounded: f64 = format!("{:.*e}", digits.max(1) - 1, self.0)
            .parse()
            .unwrap_or(self.0);
        rounded.to_string()
    }
}

impl fmt::Display for Rounded {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let rounded: f64 = format!("{:.8e}", self.0).parse().unwrap_or(self.0);
        write!(f, "{rounded}")
    }
}

/// What to do about a glitch, for [`InputError::TimeGlitch`].
fn glitch_advice(isolated: bool) -> &'static str {
    if isolated {
        "an isolated glitch, which can be repaired"
    } else {
        "not an isolated glitch (a neighbour is off the grid too, or samples are missing beside it), so it cannot be repaired; correct the time stamps, or, if the sampling is uniform, give its step"
    }
}

/// The other glitches that are errors, for [`InputError::TimeGlitch`].
fn other_glitches(others: &[Location], count: usize) -> String {
    if count == 0 {
        return String::new();
    }
    let named: Vec<String> = others.iter().map(Location::to_string).collect();
    let more = count.saturating_sub(others.len());
    let more = if more > 0 {
        format!(" and {more} more")
    } else {
        String::new()
    };
    let noun = if count == 1 { "glitch" } else { "glitches" };
    format!("; {count} more {noun}: {}{more}", named.join(", "))
}

/// The scatter of the stamps, for [`InputError::TimeUnresolved`].
fn scatter_hint(scatter: Option<f64>) -> String {
    scatter.map_or_else(String::new, |s| {
        format!(
            ", scattering about the grid by {} % of its step (robust RMS)",
            Rounded(100.0 * s).digits(2)
        )
    })
}

/// The decimals of the stamps, for [`InputError::TimeUnresolved`].
fn printed_hint(decimals: Option<u32>) -> String {
    decimals.map_or_else(String::new, |k| format!(" (they are written with {k} decimals)"))
}

/// The bound on a run left out at an end of a record, for [`InputError::TimeUnsettled`].
fn unsettled_bound() -> String {
    format!(
        "{} % of it, and at most {UNSETTLED_MAX}",
        Rounded(100.0 * UNSETTLED_FRACTION).digits(2)
    )
}
