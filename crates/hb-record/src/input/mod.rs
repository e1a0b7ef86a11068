//! Reading records: text or NumPy `.npy`, from a file or standard input, and the checks a
//! record must pass before identification (time stamps on a uniform grid, with gaps split into
//! pieces).
//!
//! # Text
//!
//! - Lines are rows; blank lines and lines starting with `#` are skipped (line numbers in errors
//!   count them). A UTF-8 byte-order mark and Windows line ends are accepted.
//! - Cells are separated by commas, by semicolons, or by runs of spaces and tabs (leading and
//!   trailing white space is ignored). The separator is that of the first row: semicolons if it
//!   holds one, else commas if it holds one, else white space. Every later row must use the same
//!   one ([`InputError::MixedSeparators`] names the first that does not). Where semicolons
//!   separate the cells, a decimal comma (`0,5`) is read as a decimal point. A cell may be
//!   enclosed in double quotes.
//! - The first row is a header when any of its cells is neither a number nor a missing value's
//!   marker (`NA`, `NaN`, `null`, ...): a first row of numbers and markers is data. An empty cell
//!   is a name left empty (pandas' unnamed index column: `,0,1,2`), so a first row of data with
//!   an empty cell is read as a header. A row right
//!   under the header whose cells are no numbers nor missing values' markers, with a unit in a
//!   column read, is a row of units, passed.
//! - A cell of a column read must hold a finite number. A missing value (an empty cell, a marker
//!   such as `NA`, `null` or `NaN`) is an error naming its line, unless
//!   [`ReadOptions::skip_missing`] leaves its row out (listed in [`Record::missing`]): the row is
//!   then a logger's dropped row, its time a gap's. An `.npy`'s NaN is a missing value too.
//!
//! # Columns
//!
//! Columns are picked by name or by 1-based position ([`Column`]). By default:
//!
//! - with a header, the time is the column `t` and the value (angle or displacement) the first of
//!   `theta`, `x`, `angle` ([`VALUE_NAMES`]), or else the only column besides the time;
//! - without a header, column 1 is the time and column 2 the value, except for exactly two
//!   columns with nothing chosen: then the data decide which is the time, in either order. The
//!   time is the column whose steps are positive and nearly uniform: median step positive,
//!   relative spread of the steps (median of `|step − median|` over the median) at most 0.5 and
//!   less than a tenth of the other column's. If exactly one column passes it is the time; if
//!   both or neither do, column 1 is. (Give the columns to be sure.) `.npy` 2-D arrays follow
//!   the same rule.
//! - With a sampling step `dt` there is no time column: sample n is at `n · dt` and the value
//!   defaults to column 1 (or, with a header, by name as above, or the only column).
//!
//! # `.npy`
//!
//! Recognised by its magic bytes: a 1-D array is the value (it needs `dt`); a 2-D array holds
//! samples in rows and channels in columns, picked by position like text columns. Element types
//! f8, f4, i8, i4 and i2 are read (integers, e.g. raw encoder counts, convert exactly).
//!
//! # Angles
//!
//! [`angle_range`] tells a wrapped angle from an unwrapped one: values within `[−π, π]` are
//! wrapped; within `[0, 2π]`, as encoders count, a wrapped angle too (read by wrapping into
//! `[−π, π)`); anything else is an unwrapped angle. Each bound allows a printing tolerance: the
//! larger of 1e-5 and half a unit in the last decimal the values are written with, so that π
//! printed as `3.141593` or `3.142` is not taken for an unwrapped angle.
//!
//! # Time stamps
//!
//! [`GridRecord::fit`] fits the stamps to a grid `t0 + n · dt`: the step from the median step,
//! refined on runs of single steps, then least squares on the stamps that fit (see the `uniform`
//! module for the steps). The samples are taken on an even grid; the clock that stamps them may
//! round, jitter and slip. The fit follows the clock's local offset from the grid (its level, the
//! median deviation of the neighbouring stamps), so that runs of thousands of stamps a printed
//! unit off the grid (a logger's clock that slips, with single steps a unit short or long) fit.
//! A stamp fits when it is within [`GRID_TOLERANCE`] (a quarter of a step) of its level, or,
//! when the stamps jitter beyond their printing, within [`JITTER_SIGMAS`] robust standard
//! deviations of it (at most half a step), and less than half a step from its grid time, so that
//! its index is never in doubt. The fitted `t0` and `dt` are the record's; the stamps themselves
//! are not used further, but what they showed is reported ([`GridReport`]: the deviations from
//! the grid and from the levels, the slips of the clock).
//!
//! - Gaps: a step of about `k · dt` (`k ≥ 2`) landing back on the grid means missing samples;
//!   the record is split there into [`Piece`]s, each with the grid index of its first sample.
//! - Glitches: a stamp that goes backwards, repeats the previous one or does not fit is an error
//!   ([`InputError::TimeGlitch`], naming its line and the next glitches) unless it is isolated
//!   (the neighbours on both sides fit, one grid step away from it) and repair is asked for
//!   ([`GridOptions::repair`]): then it is replaced by its grid time and listed in
//!   [`GridRecord::repaired`]. A glitch whose neighbours fit with a gap beside it (a logger that
//!   dropped a row and stamped the next late), or a first or last stamp nearest a slot past the
//!   one next to its neighbour, is repaired onto the free slot its stamp is nearest, when within
//!   0.4 steps of it (from its level too, where the clock slips), the gap kept where the row is
//!   missing. Two glitches side by side, or one beside a gap farther from a free slot, stay
//!   errors; at an end of the record, such glitches make an unsettled run.
//! - A logger's unsettled start or end: a run of stamps at an end of the record off the grid of
//!   the rest, increasing at another rate (a loop not yet at its rate), holding glitches that
//!   could not be repaired, is left out when it is at most 1 % of the samples and at most 50
//!   ([`UNSETTLED_FRACTION`], [`UNSETTLED_MAX`]) and listed in [`GridRecord::unsettled`]
//!   ([`GridRecord::kept`] the samples left); longer, it is [`InputError::TimeUnsettled`].
//! - Stamps that do not resolve the samples (more than 5% of them, and at least 3, more than a
//!   quarter step from their level or repeated: printed with too few decimals, or jittering by
//!   more than about a tenth of a step) are [`InputError::TimeUnresolved`]: give the sampling
//!   step instead.
//! - With a sampling step given, the grid is exact and there is one piece.
//!
//! This module holds the record, the options and the entry points; `csv` and `npy` are the two
//! readers, `uniform` the grid fit and `error` what can go wrong ([`InputError`]).

mod chunks;
mod csv;
mod error;
mod npy;
mod uniform;

pub use chunks::{Chunk, Chunks, Opened};
pub use error::{InputError, Location, StampFault};
pub use uniform::{
    GRID_TOLERANCE, GridOptions, GridRecord, GridReport, JITTER_MIN_STAMPS, JITTER_SIGMAS, JITTER_WARNING,
    LEVEL_WINDOW, Piece, RecordEnd, Slip, TimeRepair, UNSETTLED_FRACTION, UNSETTLED_MAX, Unsettled,
};

use std::io::{Read, Seek};
use std::path::{Path, PathBuf};
use std::str::FromStr;

/// A record as read: sample times and the angle (or displacement) at each, with the further
/// coordinates and the measured drives asked for.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Record {
    /// Sample times.
    pub t: Vec<f64>,
    /// The angle (or displacement) at each time: the first coordinate.
    pub theta: Vec<f64>,
    /// The further coordinates at each time, in the order of [`ReadOptions::others`].
    pub others: Vec<Vec<f64>>,
    /// For text input, the line of each sample (1-based, comments included), to name it in errors.
    pub lines: Option<Vec<u64>>,
    /// The measured drives at each time, in the order of [`ReadOptions::drives`].
    pub drives: Vec<Vec<f64>>,
    /// The measured velocities at each time, in the order of [`ReadOptions::velocities`].
    pub velocities: Vec<Vec<f64>>,
    /// The rows left out for a missing value in a column read ([`ReadOptions::skip_missing`]),
    /// in order: a line of text, a sample of an array. An array's samples are named by their
    /// place in it through this list ([`sample_location`]): the preparation adds the rows it
    /// drops (written twice) to it.
    pub missing: Vec<Location>,
}

/// Where sample `i` (from 0) of a record without lines (an array's) is in the array as read: its
/// sample counted from 1 among every row, those left out for a missing value (`missing`, in
/// order, [`Record::missing`]) included.
pub fn sample_location(missing: &[Location], i: usize) -> Location {
    let mut place = i;
    for m in missing {
        match m {
            Location::Sample(s) if *s <= place + 1 => place += 1,
            _ => break,
        }
    }
    Location::Sample(place + 1)
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
    /// The time column (default: `t`, or column 1 without a header; two unnamed columns in
    /// either order, see the module docs).
    pub time: Option<Column>,
    /// The angle (or displacement) column (default: `theta`, `x` or `angle`, or column 2 without
    /// a header; column 1 with `dt`).
    pub angle: Option<Column>,
    /// A fixed sampling step instead of a time column.
    pub dt: Option<f64>,
    /// Further coordinates read beside the angle (a double pendulum's second angle, a chain's
    /// masses), each a column of its own.
    pub others: Vec<Column>,
    /// Columns read beside the coordinates: measured drives `p(t)` (a shaker's base
    /// acceleration, a motor's torque), sampled with them. Never the time or a coordinate's
    /// column.
    pub drives: Vec<Column>,
    /// Columns of the coordinates' measured velocities (a motor driver's, a tachometer's), one
    /// per coordinate in their order, read beside them.
    pub velocities: Vec<Column>,
    /// Leave out every row with a missing value in a column read (an empty cell, a marker such
    /// as `NA`, `null` or `NaN`; an array's NaN), as if the logger had not written it, and list
    /// it in [`Record::missing`]: its time stamp is then a gap's (with a sampling step, the rows
    /// keep their places). Off by default: such a value is an error that names it. An infinity
    /// is an error either way (a value out of range, not a missing one).
    pub skip_missing: bool,
}

impl ReadOptions {
    /// Checks the options on their own: a step positive and finite, not both a step and a time
    /// column, positions counted from 1.
    pub fn validate(&self) -> Result<(), InputError> {
        let chosen = [&self.time, &self.angle]
            .into_iter()
            .flatten()
            .chain(&self.others)
            .chain(&self.drives)
            .chain(&self.velocities);
        for column in chosen {
            if let Column::Position(0) = column {
                return Err(InputError::BadColumn {
                    given: "0".to_owned(),
                });
            }
        }
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
    /// A column chosen in the options is found by name or position. Otherwise:
    ///
    /// - the time is the column named `t` with a header, and without one the first column that
    ///   is not the chosen angle;
    /// - the angle is, with a header, the first of the columns named [`VALUE_NAMES`] (`theta`,
    ///   `x`, `angle`) that is not the time, or else the only column besides the time; without a
    ///   header, the first column that is not the time.
    ///
    /// With a sampling step there is no time column. A single unnamed column with neither a
    /// sampling step nor a time column is an angle whose step is missing. Two unnamed columns
    /// with nothing chosen are read as time then angle, and the data then decide which is which
    /// ([`Columns::order_from_data`]).
    pub(crate) fn columns(&self, names: Option<&[&str]>, width: usize) -> Result<Columns, InputError> {
        if self.dt.is_none() && names.is_none() && width == 1 && self.time.is_none() {
            return Err(InputError::NeedStep);
        }
        let time = match self.dt {
            Some(dt) => Times::Step(dt),
            None => {
                let wanted = match (&self.time, names) {
                    (Some(chosen), _) => chosen.clone(),
                    (None, Some(_)) => Column::Name("t".to_owned()),
                    (None, None) => {
                        let taken = match &self.angle {
                            Some(Column::Position(p)) => Some(p - 1),
                            _ => None,
                        };
                        Column::Position(first_free(taken) + 1)
                    }
                };
                Times::Column(find(Role::Time, wanted, names, width)?)
            }
        };
        let angle = match (&self.angle, names) {
            (Some(chosen), _) => find(Role::Angle, chosen.clone(), names, width)?,
            (None, None) => find(
                Role::Angle,
                Column::Position(first_free(time.column()) + 1),
                names,
                width,
            )?,
            (None, Some(names)) => {
                // The default name, if the header has it, is looked up as a chosen one is (a
                // name given twice is ambiguous).
                if let Some(name) = default_value(names, time.column()).map(|i| names[i])
                    && VALUE_NAMES.contains(&name)
                {
                    find(Role::Angle, Column::Name(name.to_owned()), Some(names), width)?;
                }
                default_value(names, time.column()).ok_or_else(|| InputError::MissingColumn {
                    role: Role::Angle,
                    wanted: Column::Name(VALUE_NAMES[0].to_owned()),
                    found: names.iter().map(|&c| c.to_owned()).collect(),
                    width,
                })?
            }
        };
        // The time and the angle chosen as one column (the defaults never are).
        if time.column() == Some(angle) {
            return Err(InputError::ColumnTwice {
                column: self.angle.clone().unwrap_or(Column::Position(angle + 1)),
                first: Role::Time,
                second: Role::Angle,
            });
        }
        // Every further column: found, and none of them a column already taken.
        let mut taken: Vec<(usize, Role)> = time.column().map(|c| (c, Role::Time)).into_iter().collect();
        taken.push((angle, Role::Angle));
        let mut further = |role: Role, chosen: &[Column]| -> Result<Vec<usize>, InputError> {
            let mut out = Vec::with_capacity(chosen.len());
            for column in chosen {
                let index = find(role, column.clone(), names, width)?;
                if let Some(&(_, first)) = taken.iter().find(|(c, _)| *c == index) {
                    return Err(InputError::ColumnTwice {
                        column: column.clone(),
                        first,
                        second: role,
                    });
                }
                taken.push((index, role));
                out.push(index);
            }
            Ok(out)
        };
        let others = further(Role::Angle, &self.others)?;
        let drives = further(Role::Drive, &self.drives)?;
        let velocities = further(Role::Velocity, &self.velocities)?;
        let order_from_data = names.is_none()
            && width == 2
            && self.time.is_none()
            && self.angle.is_none()
            && self.dt.is_none()
            && self.others.is_empty()
            && self.drives.is_empty()
            && self.velocities.is_empty();
        Ok(Columns {
            time,
            angle,
            others,
            drives,
            velocities,
            order_from_data,
        })
    }
}

/// The names a value (angle or displacement) column goes by when none is chosen, in order of
/// preference.
pub const VALUE_NAMES: [&str; 3] = ["theta", "x", "angle"];

/// The first column that is not `taken` (which may be past the last column: then it is missing).
fn first_free(taken: Option<usize>) -> usize {
    match taken {
        Some(0) => 1,
        _ => 0,
    }
}

/// The default value column among a header's `names`: the first of [`VALUE_NAMES`] that is not
/// the time column, or else the only column that is not the time column.
fn default_value(names: &[&str], time: Option<usize>) -> Option<usize> {
    let not_time = |i: &usize| Some(*i) != time;
    VALUE_NAMES
        .iter()
        .find_map(|v| names.iter().position(|c| c == v).filter(not_time))
        .or_else(|| {
            let mut others = (0..names.len()).filter(not_time);
            match (others.next(), others.next()) {
                (Some(only), None) => Some(only),
                _ => None,
            }
        })
}

/// How the cells of a text row are separated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Separator {
    /// Commas.
    Comma,
    /// Semicolons (commas inside cells are then decimal commas).
    Semicolon,
    /// Tabs (runs of them), in a record whose first row has cells with spaces inside
    /// (`time [s]`, `angle [rad]`): spaces are then part of a cell.
    Tab,
    /// Runs of spaces and tabs.
    Whitespace,
}

impl std::fmt::Display for Separator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Separator::Comma => "commas",
            Separator::Semicolon => "semicolons",
            Separator::Tab => "tabs",
            Separator::Whitespace => "spaces or tabs",
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
    /// The measured drive.
    Drive,
    /// A measured velocity.
    Velocity,
}

impl std::fmt::Display for Role {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Role::Time => "time",
            Role::Angle => "angle",
            Role::Drive => "drive",
            Role::Velocity => "velocity",
        })
    }
}

/// Where a record's times and angles come from; columns count from 0.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Columns {
    /// The times.
    pub(crate) time: Times,
    /// The angle column.
    pub(crate) angle: usize,
    /// The further coordinates' columns.
    pub(crate) others: Vec<usize>,
    /// The measured drives' columns.
    pub(crate) drives: Vec<usize>,
    /// The measured velocities' columns.
    pub(crate) velocities: Vec<usize>,
    /// Two unnamed columns and nothing chosen: `time` and `angle` are columns 1 and 2 as read,
    /// and [`order_from_data`] swaps them when the data say the second is the time.
    pub(crate) order_from_data: bool,
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
        (Column::Name(n), Some(names)) => {
            let positions: Vec<usize> = (0..names.len())
                .filter(|&i| names[i] == n)
                .map(|i| i + 1)
                .collect();
            if positions.len() > 1 {
                return Err(InputError::AmbiguousColumn {
                    role,
                    name: n.clone(),
                    positions,
                });
            }
            positions.first().map(|p| p - 1)
        }
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
        // The usual `.npy` straight into its columns; any other file read whole, from the same
        // handle. (A regular file only is tried: a pipe, such as a named one or a shell's `<(…)`,
        // cannot be read again from its start, nor opened again with its data.)
        let mut file = std::fs::File::open(path).map_err(io)?;
        let meta = file.metadata().map_err(io)?;
        if meta.is_file() {
            if let Some(record) = npy::read_file(&mut file, meta.len(), options, io)? {
                return Ok(record);
            }
            file.seek(std::io::SeekFrom::Start(0)).map_err(io)?;
        }
        let mut buf = Vec::with_capacity(usize::try_from(meta.len()).unwrap_or(0));
        file.read_to_end(&mut buf).map_err(io)?;
        buf
    };
    read_valid(&bytes, options)
}

/// The names of a text file's header, read once from its first mebibyte, and the columns
/// options choose by them (records of one identification chosen by position are told apart by
/// them; a model saved with positional columns must find its own names there).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Header(Vec<String>);

impl Header {
    /// The header of the text file at `path`: `None` without one, for a `.npy` file or standard
    /// input, or where the file cannot be read (reading it says why).
    pub fn of(path: &Path) -> Option<Self> {
        csv::header(&text_start(path)?).map(Self)
    }

    /// Its names, in the order of the columns.
    pub fn names(&self) -> &[String] {
        &self.0
    }

    /// The names of the columns `options` choose, as [`read_path`] finds them: the
    /// coordinates', then the drives', then the velocities'; `None` for options that are not
    /// valid or choose a column the header does not have.
    pub fn chosen(&self, options: &ReadOptions) -> Option<Vec<String>> {
        options.validate().ok()?;
        let cells: Vec<&str> = self.0.iter().map(String::as_str).collect();
        let columns = options.columns(Some(&cells), cells.len()).ok()?;
        let chosen = std::iter::once(columns.angle)
            .chain(columns.others)
            .chain(columns.drives)
            .chain(columns.velocities);
        Some(chosen.map(|i| self.0[i].clone()).collect())
    }
}

/// The first mebibyte of the regular text file at `path` (not standard input, not `.npy`).
fn text_start(path: &Path) -> Option<Vec<u8>> {
    if path == Path::new("-") {
        return None;
    }
    let mut file = std::fs::File::open(path).ok()?;
    if !file.metadata().ok()?.is_file() {
        return None;
    }
    let mut start = vec![0; 1 << 20];
    let got = read_up_to(&mut file, &mut start).ok()?;
    start.truncate(got);
    (!start.starts_with(b"\x93NUMPY")).then_some(start)
}

/// Reads into `buf` until it is full or the reader ends (an interrupted read tried again); how
/// many bytes it read.
pub(super) fn read_up_to(file: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match file.read(&mut buf[got..]) {
            Ok(0) => break,
            Ok(k) => got += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(got)
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

/// The times of `n` samples `dt` apart from 0, for records without a time column; an error when
/// the last one overflows.
fn grid(n: usize, dt: f64) -> Result<Vec<f64>, InputError> {
    grid_of(0..n, n, dt)
}

/// The times of the rows `kept` (their places among `n` rows) `dt` apart from 0: the rows left
/// out ([`ReadOptions::skip_missing`]) keep theirs, as a gap.
fn grid_of(kept: impl IntoIterator<Item = usize>, n: usize, dt: f64) -> Result<Vec<f64>, InputError> {
    if !(n.saturating_sub(1) as f64 * dt).is_finite() {
        return Err(InputError::StepOverflow { dt, samples: n });
    }
    Ok(kept.into_iter().map(|i| i as f64 * dt).collect())
}

/// Largest relative spread of a column's steps (see [`step_spread`]) for it to be read as the
/// time: beyond it the stamps could not fit a grid within [`GRID_TOLERANCE`] anyway.
const TIME_SPREAD_LIMIT: f64 = 2.0 * GRID_TOLERANCE;

/// Spreads below this are rounding in floating point and count as this.
const SPREAD_FLOOR: f64 = 1e-9;

/// How many steps, from the start, decide which of two unnamed columns is the time.
const ORDER_STEPS: usize = 100_000;

/// Decides which of two unnamed columns, read as time then angle, is the time, and swaps them
/// if it is the second.
///
/// A column is the time when its median step `m` is positive, the relative spread of its steps
/// (the median of `|step − m|`, over `m`) is at most [`TIME_SPREAD_LIMIT`], and that spread is
/// less than a tenth of the other column's (spreads below 1e-9 count as 1e-9). If exactly one
/// column is the time by this rule, it is; otherwise (both or neither) the first column is the
/// time, as in any headerless record. Medians ignore gaps and glitches in the time stamps; the
/// first 100 000 steps decide.
fn order_from_data(record: &mut Record) {
    let spread = |x: &[f64]| step_spread(&x[..x.len().min(ORDER_STEPS + 1)]);
    let (first, second) = (spread(&record.t), spread(&record.theta));
    let is_time = |own: Option<f64>, other: Option<f64>| match own {
        Some(s) if s <= TIME_SPREAD_LIMIT => {
            s.max(SPREAD_FLOOR) < other.map_or(f64::INFINITY, |o| o.max(SPREAD_FLOOR)) / 10.0
        }
        _ => false,
    };
    if is_time(second, first) && !is_time(first, second) {
        std::mem::swap(&mut record.t, &mut record.theta);
    }
}

/// The relative spread of the steps of `x`: the median of `|step − m|` over `m`, where `m` is
/// the median step; `None` when `m` is not positive (or there is no step).
fn step_spread(x: &[f64]) -> Option<f64> {
    let mut steps: Vec<f64> = x.windows(2).map(|w| w[1] - w[0]).collect();
    let m = median(&mut steps)?;
    if m.is_nan() || m <= 0.0 {
        return None;
    }
    for s in &mut steps {
        *s = (*s - m).abs();
    }
    Some(median(&mut steps)? / m)
}

/// The median of `values` (the upper middle one for an even count), reordering them; `None` when
/// empty.
fn median(values: &mut [f64]) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    let mid = values.len() / 2;
    let (_, m, _) = values.select_nth_unstable_by(mid, f64::total_cmp);
    Some(*m)
}

/// Where the values of an angle column lie, as an encoder or a program may write them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AngleRange {
    /// Within `[−π, π)`: wrapped already.
    Wrapped,
    /// Within `[0, 2π)`, as most encoders count: a wrapped angle, read by wrapping into
    /// `[−π, π)`.
    FromZero,
    /// Anything else: an unwrapped angle (or a displacement), which wrapping reads on the circle.
    Unwrapped,
}

/// Where the values of an angle column lie: [`AngleRange::Wrapped`] within `[−π, π]`,
/// [`AngleRange::FromZero`] within `[0, 2π]`, else [`AngleRange::Unwrapped`].
///
/// Each bound is widened by a printing tolerance, so that a value that only rounds past it
/// (`3.141593`, π to 6 decimals; `6.283186`) is not taken for an unwrapped angle: the larger of
/// [`ANGLE_PRINT_TOLERANCE`] and half a unit in the last decimal of the values, when they all
/// have at most 9 decimals (half of 0.001 for values printed to 3 decimals).
pub fn angle_range(x: &[f64]) -> AngleRange {
    angle_range_of(&[x])
}

/// [`angle_range`] of the values of `parts` together (a record's pieces, without a copy of
/// them in one column).
pub(crate) fn angle_range_of(parts: &[&[f64]]) -> AngleRange {
    use std::f64::consts::{PI, TAU};
    let values = || parts.iter().flat_map(|p| p.iter());
    let (lo, hi) = values().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
        (lo.min(v), hi.max(v))
    });
    let tolerance = printed_decimals(parts).map_or(ANGLE_PRINT_TOLERANCE, |k| {
        (0.5 * 10f64.powi(-(k as i32))).max(ANGLE_PRINT_TOLERANCE)
    });
    if values().next().is_none() || (lo >= -PI - tolerance && hi <= PI + tolerance) {
        AngleRange::Wrapped
    } else if lo >= -tolerance && hi <= TAU + tolerance {
        AngleRange::FromZero
    } else {
        AngleRange::Unwrapped
    }
}

/// The least printing tolerance of [`angle_range`], in radians: values that far past a bound
/// (and rounding of 4 or more decimals) still count as within it.
pub const ANGLE_PRINT_TOLERANCE: f64 = 1e-5;

/// The fewest decimals (at most 9) that write every value of `x`, if any: the values are then
/// multiples of `10^−k` up to floating-point rounding.
fn printed_decimals(parts: &[&[f64]]) -> Option<u32> {
    (0..=9u32).find(|&k| {
        let scale = 10f64.powi(k as i32);
        parts.iter().all(|p| {
            p.iter().all(|&v| {
                let scaled = v * scale;
                (scaled - round(scaled)).abs() <= 1e-9 + 1e-12 * scaled.abs()
            })
        })
    })
}

/// `x.round()` (half away from zero, the sign of zero kept), bit for bit, without a call: the
/// x86-64 baseline has no instruction for it, and the library's `round` took a tenth of the read
/// stage, which rounds every time stamp to its grid index several times.
#[inline]
pub(crate) fn round(x: f64) -> f64 {
    // Below 2^52 the integer part is exact as an integer, and the fraction as a difference;
    // from 2^52 on every number is whole (and NaN or infinite ones are their own rounding).
    if x.abs() < 4_503_599_627_370_496.0 {
        let whole = x as i64 as f64;
        let fraction = x - whole;
        let r = if fraction >= 0.5 {
            whole + 1.0
        } else if fraction <= -0.5 {
            whole - 1.0
        } else {
            whole
        };
        let r = r.copysign(x);
        debug_assert_eq!(r.to_bits(), x.round().to_bits(), "round({x})");
        r
    } else {
        x
    }
}
