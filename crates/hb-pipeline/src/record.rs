//! The record of a request: where its samples come from ([`Source`]), the options that say how
//! to read and condition it ([`RecordOptions`], shared by `identify`, `embed`, `upos` and
//! `report`), and the one way it becomes a [`Data`] ([`load`]).

use std::fmt;
use std::path::Path;
use std::str::FromStr;

use circle_signal::{Domain, Measured};
use hb_record::input::{Column, InputError, ReadOptions, Record as InputRecord, Role, read_path};
use hb_record::prepare::{
    Data, DriveFound, GridData, Note, PeriodSource, PrepareError, PrepareOptions, SpikePolicy, condition,
};
use serde::{Deserialize, Serialize};

use crate::drive::{BadDrive, DriveSpec, DriveUnit};
use crate::error::RunError;
use crate::observe::{Notice, Observer, Stage};
use crate::options::{OptionError, optional_text, text};

/// A drive given in text by its period: `T`, `auto`, `auto:A..B` or `none`
/// ([`DriveSpec::parse`] with [`DriveUnit::Period`]).
#[derive(Debug, Clone, PartialEq)]
pub struct DrivePeriod {
    spec: DriveSpec,
    text: String,
}

/// A drive given in text by its frequency in cycles per time unit (hertz for seconds): `F`,
/// `auto`, `auto:A..B` or `none` ([`DriveSpec::parse`] with [`DriveUnit::Frequency`]).
#[derive(Debug, Clone, PartialEq)]
pub struct DriveFrequency {
    spec: DriveSpec,
    text: String,
}

macro_rules! drive_text {
    ($t:ty, $unit:expr) => {
        impl FromStr for $t {
            type Err = BadDrive;

            fn from_str(s: &str) -> Result<Self, BadDrive> {
                Ok(Self {
                    spec: DriveSpec::parse(s, $unit)?,
                    text: s.trim().to_owned(),
                })
            }
        }

        impl fmt::Display for $t {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(&self.text)
            }
        }

        impl $t {
            /// The drive it gives.
            pub fn spec(&self) -> DriveSpec {
                self.spec
            }
        }
    };
}

drive_text!(DrivePeriod, DriveUnit::Period);
drive_text!(DriveFrequency, DriveUnit::Frequency);

/// Columns of a file by header name or 1-based position, written `A,B,C` (from Python a list of
/// texts), each with the name terms call it: its own, or one given before it, `NAME=COLUMN`
/// (`q1=pos_meas1,q2=pos_meas2`).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct ColumnList {
    names: Vec<String>,
    columns: Vec<String>,
}

impl ColumnList {
    /// The names terms call the columns, in order.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// The columns of the file, in order.
    pub fn columns(&self) -> &[String] {
        &self.columns
    }

    /// The number of columns.
    pub fn len(&self) -> usize {
        self.columns.len()
    }

    /// Never true: a list names at least one column.
    pub fn is_empty(&self) -> bool {
        self.columns.is_empty()
    }
}

impl FromStr for ColumnList {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let mut out = Self::default();
        for item in s.split(',') {
            let (name, column) = match item.split_once('=') {
                Some((name, column)) => (name.trim(), column.trim()),
                None => (item.trim(), item.trim()),
            };
            if name.is_empty() || column.is_empty() {
                return Err(
                    "expected columns separated by commas (NAME=COLUMN to name one), none empty".to_owned(),
                );
            }
            column.parse::<Column>().map_err(|e| e.to_string())?;
            if out.columns.iter().any(|c| c == column) {
                return Err(format!("the column '{column}' is named twice"));
            }
            if out.names.iter().any(|n| n == name) {
                return Err(format!("the name '{name}' is given twice"));
            }
            out.names.push(name.to_owned());
            out.columns.push(column.to_owned());
        }
        Ok(out)
    }
}

impl fmt::Display for ColumnList {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let items: Vec<String> = self
            .names
            .iter()
            .zip(&self.columns)
            .map(|(n, c)| if n == c { c.clone() } else { format!("{n}={c}") })
            .collect();
        f.write_str(&items.join(","))
    }
}

/// Where each coordinate lives, written `circle` or `line` for all, or one per coordinate
/// (`circle,circle,line`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SignalList(Vec<Domain>);

impl SignalList {
    /// One domain for every coordinate.
    pub fn all(domain: Domain) -> Self {
        Self(vec![domain])
    }

    /// The domain of coordinate `i` (the one domain given for all, or the `i`-th).
    pub fn of(&self, i: usize) -> Domain {
        if self.0.len() == 1 { self.0[0] } else { self.0[i] }
    }

    /// The domain of the first coordinate.
    pub fn first(&self) -> Domain {
        self.0[0]
    }

    /// The number of domains given (1 for one for all).
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// Never true.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

impl Default for SignalList {
    fn default() -> Self {
        Self::all(Domain::Circle)
    }
}

impl From<Domain> for SignalList {
    fn from(domain: Domain) -> Self {
        Self::all(domain)
    }
}

impl FromStr for SignalList {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        s.split(',')
            .map(|d| d.trim().parse::<Domain>().map_err(|e| e.to_string()))
            .collect::<Result<Vec<_>, _>>()
            .map(Self)
    }
}

impl fmt::Display for SignalList {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let texts: Vec<String> = self.0.iter().map(ToString::to_string).collect();
        f.write_str(&texts.join(","))
    }
}

/// The unit of a record's angles: radians (the default), degrees or an encoder's counts per
/// turn. Angles on the circle, and their measured velocities, are converted to radians as they
/// are read.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum AngleUnit {
    /// Radians.
    #[default]
    Radians,
    /// Degrees.
    Degrees,
    /// An encoder's counts, this many per turn.
    Counts(u64),
}

impl AngleUnit {
    /// Radians per unit.
    pub fn radians(self) -> f64 {
        match self {
            AngleUnit::Radians => 1.0,
            AngleUnit::Degrees => std::f64::consts::PI / 180.0,
            AngleUnit::Counts(n) => std::f64::consts::TAU / n as f64,
        }
    }
}

/// `rad`, `deg`, `counts:N`.
impl fmt::Display for AngleUnit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            AngleUnit::Radians => f.write_str("rad"),
            AngleUnit::Degrees => f.write_str("deg"),
            AngleUnit::Counts(n) => write!(f, "counts:{n}"),
        }
    }
}

impl FromStr for AngleUnit {
    type Err = String;

    /// `rad`, `deg` or `counts:N` (N counts per turn, at least 2).
    fn from_str(s: &str) -> Result<Self, String> {
        let text = s.trim().to_ascii_lowercase();
        match text.as_str() {
            "rad" | "radians" => Ok(AngleUnit::Radians),
            "deg" | "degrees" => Ok(AngleUnit::Degrees),
            _ => match text.strip_prefix("counts:").map(|n| n.trim().parse::<u64>()) {
                Some(Ok(n)) if n >= 2 => Ok(AngleUnit::Counts(n)),
                _ => Err(format!(
                    "'{s}' is not an angle unit: rad, deg or counts:N (an encoder's N counts per turn, N at least 2)"
                )),
            },
        }
    }
}

/// The options of a record, as `hbid identify`, `embed`, `upos` and `report` take them and the
/// Python functions of the same names. Defaults: an angle on the circle, measured as the
/// displacement itself, nothing repaired, the drive's period 2π (the paper's time) unless given.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct RecordOptions {
    /// The time column of a file, by header name or 1-based position.
    #[serde(with = "optional_text")]
    pub time_col: Option<String>,
    /// The angle (or displacement) column of a file, by header name or 1-based position: a
    /// record of one coordinate.
    #[serde(with = "optional_text")]
    pub angle_col: Option<String>,
    /// The columns of a file that each get an equation (`theta1,theta2`): a system of several
    /// coordinates, named in terms by these names. One column is `angle_col`'s record.
    #[serde(with = "optional_text")]
    pub coords: Option<ColumnList>,
    /// The sampling step, for records without time stamps (the first sample at t = 0).
    pub dt: Option<f64>,
    /// The columns of a file that hold measured drives (`p(t)` for a record of one coordinate and
    /// one drive, otherwise named in terms by their columns), sampled with the coordinates; they
    /// get no equation.
    #[serde(with = "optional_text")]
    pub drive_col: Option<ColumnList>,
    /// The columns of the coordinates' measured velocities (a motor driver's, a tachometer's),
    /// one per coordinate in their order: read with the record and conditioned on its grid;
    /// `compare` starts a free run from the first sample's measured state.
    #[serde(with = "optional_text")]
    pub velocity_col: Option<ColumnList>,
    /// Replace isolated time-stamp glitches and every encoder spike (each named in a note).
    pub repair: bool,
    /// Keep every spike in the record (a warning) instead of replacing them when they are few
    /// (at most one per 1000 samples; the default, said in a note).
    pub no_repair: bool,
    /// Bridge every gap of at most this many missing samples, between pieces of at least 7 (each
    /// searched for spikes), by the cubic through the two samples on each side, in every column,
    /// so that its pieces are analysed as one (a logger's dropped rows; each bridge counted in a
    /// note). 0, the default, bridges none; at most [`hb_record::prepare::MAX_BRIDGE`] (4: a
    /// bridged sample then carries at most 1.61 times one sample's noise); a displacement record
    /// only.
    pub bridge_gaps: usize,
    /// Leave out every row of a file with a missing value in a column read (an empty cell, `NA`,
    /// `null`, `NaN`, ...), as if the logger had not written it: its time is then a gap's (with
    /// `dt`, the rows keep their places), which `bridge_gaps` may bridge; a note counts them and
    /// names the first. Off by default: such a value is an error naming its line.
    pub skip_missing: bool,
    /// An angle on the circle or a displacement on the line: one for every coordinate, or one
    /// per coordinate.
    #[serde(with = "text")]
    pub signal: SignalList,
    /// What the sensor measured (on the line): the displacement, or its velocity or
    /// acceleration, integrated to the displacement.
    #[serde(with = "text")]
    pub measured: Measured,
    /// The drive's period in the record's time unit, or `auto[:A..B]`, or `none`.
    #[serde(with = "optional_text")]
    pub drive_period: Option<DrivePeriod>,
    /// The drive's frequency in cycles per time unit (Hz for seconds), or `auto[:A..B]`, or
    /// `none`.
    #[serde(with = "optional_text")]
    pub drive_frequency: Option<DriveFrequency>,
    /// The unit of the angles on the circle (and of their measured velocities, per time unit):
    /// `rad` (the default), `deg` or `counts:N`; converted to radians as they are read.
    #[serde(with = "text")]
    pub angle_unit: AngleUnit,
}

impl RecordOptions {
    /// Checks the options that do not depend on the record, the names terms will call its
    /// columns by among them ([`names`](Self::names)).
    pub fn check(&self) -> Result<(), OptionError> {
        self.check_columns()?;
        self.names()?;
        Ok(())
    }

    /// [`check`](Self::check) but for the names: for a record whose columns take the names of a
    /// model's (`hbid compare`), which a column given by its position then has.
    pub fn check_columns(&self) -> Result<(), OptionError> {
        if let Some(dt) = self.dt
            && !(dt.is_finite() && dt > 0.0)
        {
            return Err(OptionError::value("dt", dt, "must be positive and finite"));
        }
        if self.drive_period.is_some() && self.drive_frequency.is_some() {
            return Err(OptionError::new(
                "drive_period",
                "give the drive by «drive_period» or by «drive_frequency», not both",
            ));
        }
        for (name, col) in [("time_col", &self.time_col), ("angle_col", &self.angle_col)] {
            if let Some(text) = col {
                text.parse::<Column>()
                    .map_err(|e| OptionError::value(name, text, e))?;
            }
        }
        if self.angle_unit != AngleUnit::Radians && !self.domains().contains(&Domain::Circle) {
            return Err(OptionError::value(
                "angle_unit",
                self.angle_unit,
                "is the unit of angles on the circle, and every coordinate is on the line («signal»)",
            ));
        }
        if self.repair && self.no_repair {
            return Err(OptionError::new(
                "no_repair",
                "give «repair» or «no_repair», not both",
            ));
        }
        if self.bridge_gaps > hb_record::prepare::MAX_BRIDGE {
            return Err(OptionError::value(
                "bridge_gaps",
                self.bridge_gaps,
                format!(
                    "at most {}: the cubic through two samples on each side would carry more than 1.61 times one \
                     sample's noise into a longer gap's samples",
                    hb_record::prepare::MAX_BRIDGE
                ),
            ));
        }
        if self.bridge_gaps > 0 && self.measured != Measured::Displacement {
            return Err(OptionError::value(
                "bridge_gaps",
                self.bridge_gaps,
                "a velocity or acceleration record («measured») is integrated piece by piece: its gaps cannot be \
                 bridged",
            ));
        }
        if self.angle_col.is_some() && self.coords.is_some() {
            return Err(OptionError::new(
                "coords",
                "name the coordinates by «coords» or the one angle by «angle_col», not both",
            ));
        }
        let n = self.coordinates();
        if n > hb_model::MAX_COORDINATES {
            return Err(OptionError::value(
                "coords",
                self.coords.as_ref().map(ToString::to_string).unwrap_or_default(),
                format!("at most {} coordinates", hb_model::MAX_COORDINATES),
            ));
        }
        if self.signal.len() != 1 && self.signal.len() != n {
            return Err(OptionError::value(
                "signal",
                &self.signal,
                format!("give one domain for all coordinates or one per coordinate ({n})"),
            ));
        }
        if let (Some(coords), Some(drives)) = (&self.coords, &self.drive_col)
            && let Some(both) = drives.columns().iter().find(|d| coords.columns().contains(d))
        {
            return Err(OptionError::value(
                "drive_col",
                both,
                "is a coordinate («coords») too: a drive gets no equation",
            ));
        }
        if let Some(drives) = &self.drive_col
            && drives.len() > hb_model::MAX_DRIVES
        {
            return Err(OptionError::value(
                "drive_col",
                drives,
                format!("at most {} measured drives", hb_model::MAX_DRIVES),
            ));
        }
        if self.measured != Measured::Displacement && (0..n).any(|i| self.signal.of(i) == Domain::Circle) {
            return Err(OptionError::value(
                "measured",
                self.measured,
                "a velocity or acceleration record is integrated to a displacement on the line: needs «signal=line»",
            ));
        }
        if let Some(v) = &self.velocity_col
            && v.len() != n
        {
            return Err(OptionError::value(
                "velocity_col",
                v,
                format!("give one velocity column per coordinate ({n})"),
            ));
        }
        Ok(())
    }

    /// The number of coordinates: those of `coords`, or one.
    pub fn coordinates(&self) -> usize {
        self.coords.as_ref().map_or(1, ColumnList::len)
    }

    /// The domain of every coordinate, in order.
    pub fn domains(&self) -> Vec<Domain> {
        (0..self.coordinates()).map(|i| self.signal.of(i)).collect()
    }

    /// The measured drives' columns, in order (none without `drive_col`).
    pub fn drive_cols(&self) -> &[String] {
        self.drive_col.as_ref().map_or(&[], |d| d.columns())
    }

    /// The names terms call the measured drives, in order (their columns unless named).
    pub fn drive_names(&self) -> &[String] {
        self.drive_col.as_ref().map_or(&[], |d| d.names())
    }

    /// The names terms are written in: a record of one coordinate is `x` with the drive `p`
    /// (one drive) or the drives' columns; a system's coordinates and drives are their columns
    /// (which must then be names that terms can spell).
    pub fn names(&self) -> Result<hb_model::Names, OptionError> {
        let drives = self.drive_names();
        let single = self.coordinates() == 1;
        let coordinates: Vec<String> = match &self.coords {
            Some(c) if !single => c.names().to_vec(),
            _ => vec!["x".to_owned()],
        };
        // One coordinate with at most one drive: the names of every list before several
        // coordinates (`p` is a term's factor even before a drive is named, so that the error
        // says to name it).
        let drives: Vec<String> = if single && drives.len() <= 1 {
            vec!["p".to_owned()]
        } else {
            drives.to_vec()
        };
        hb_model::Names::new(coordinates.clone(), drives.clone()).map_err(|e| {
            // The option whose list holds the name that cannot be used.
            let bad = match &e {
                hb_model::TermError::BadName { name, .. } => Some(name.as_str()),
                _ => None,
            };
            // A name in both lists is the drive's to change: the coordinates are named first.
            let in_drives = bad.is_some_and(|b| drives.iter().any(|d| d == b));
            let option = if single || in_drives {
                "drive_col"
            } else {
                "coords"
            };
            let position = bad.filter(|b| !b.is_empty() && b.bytes().all(|c| c.is_ascii_digit()));
            let example = if option == "drive_col" { "tau1" } else { "theta1" };
            let hint = match position {
                Some(p) => format!(
                    "a column given by its position needs a name for the terms to call it by: NAME=COLUMN \
                     ({example}={p})"
                ),
                None => format!(
                    "the columns of a system are named in its terms (by the file's header names, or NAME=COLUMN: \
                     {example}=2)"
                ),
            };
            OptionError::new(option, format!("{e}: {hint}"))
        })
    }

    /// The drive given by `drive_period` or `drive_frequency`, if any.
    pub fn given_drive(&self) -> Option<DriveSpec> {
        match (&self.drive_period, &self.drive_frequency) {
            (Some(p), _) => Some(p.spec()),
            (None, Some(f)) => Some(f.spec()),
            (None, None) => None,
        }
    }

    /// The drive: the one given, else none when `free` (no drive named, a model with no forcing
    /// asked for), else the period 2π of the paper's non-dimensional time.
    pub fn drive(&self, free: bool) -> DriveSpec {
        match self.given_drive() {
            Some(spec) => spec,
            None if free => DriveSpec::Free,
            None => DriveSpec::Period(std::f64::consts::TAU),
        }
    }

    pub(crate) fn read_options(&self) -> Result<ReadOptions, OptionError> {
        let column = |name: &str, text: &Option<String>| {
            text.as_deref()
                .map(|t| t.parse::<Column>().map_err(|e| OptionError::value(name, t, e)))
                .transpose()
        };
        let list = |name: &str, columns: &[String]| -> Result<Vec<Column>, OptionError> {
            columns
                .iter()
                .map(|t| t.parse::<Column>().map_err(|e| OptionError::value(name, t, e)))
                .collect()
        };
        let coords = self
            .coords
            .as_ref()
            .map(|c| c.columns().to_vec())
            .unwrap_or_default();
        let angle = match coords.first() {
            Some(first) => Some(
                first
                    .parse::<Column>()
                    .map_err(|e| OptionError::value("coords", first, e))?,
            ),
            None => column("angle_col", &self.angle_col)?,
        };
        Ok(ReadOptions {
            time: column("time_col", &self.time_col)?,
            angle,
            dt: self.dt,
            others: list("coords", coords.get(1..).unwrap_or_default())?,
            drives: list("drive_col", self.drive_cols())?,
            velocities: list(
                "velocity_col",
                self.velocity_col.as_ref().map_or(&[], |v| v.columns()),
            )?,
            skip_missing: self.skip_missing,
        })
    }
}

/// Where the samples of a request come from.
#[derive(Debug)]
pub enum Source<'a> {
    /// A file: text or `.npy` (`-` reads standard input); its columns and step as the
    /// [`RecordOptions`] say.
    Path(&'a Path),
    /// Samples with their time stamps `t`, or (without `t`) the step of [`RecordOptions::dt`],
    /// and the measured drives sampled with them, if any.
    Arrays {
        /// The samples of each coordinate (one for a record of one angle or displacement).
        coords: Vec<&'a [f64]>,
        /// Their time stamps.
        t: Option<&'a [f64]>,
        /// The measured drives, one sample per sample of each coordinate.
        drives: Vec<&'a [f64]>,
    },
    /// A record on its grid already (read and conditioned before): only its drive is found.
    Grid(GridData),
}

/// The name of a source in messages: the file's path, or `the arrays`.
fn source_name(source: &Source<'_>) -> String {
    match source {
        Source::Path(p) => p.display().to_string(),
        Source::Arrays { .. } => "the arrays".to_owned(),
        Source::Grid(_) => "the record".to_owned(),
    }
}

/// The samples of `source` as a read record.
fn arrays_record(
    coords: &[&[f64]],
    t: Option<&[f64]>,
    drives: &[&[f64]],
    options: &RecordOptions,
) -> Result<InputRecord, RunError> {
    if options.time_col.is_some() || options.angle_col.is_some() {
        let name = if options.time_col.is_some() {
            "time_col"
        } else {
            "angle_col"
        };
        return Err(
            OptionError::sentence(name, "names a column of a file: give arrays, or a file to read").into(),
        );
    }
    if options.velocity_col.is_some() {
        return Err(OptionError::sentence(
            "velocity_col",
            "names columns of a file: give arrays without it, or a file to read",
        )
        .into());
    }
    let Some((&x, others)) = coords.split_first() else {
        return Err(OptionError::new("x", "no coordinate given").into());
    };
    if coords.len() != options.coordinates() {
        return Err(OptionError::new(
            "coords",
            format!(
                "{} names for {} coordinates of the arrays: name each column",
                options.coordinates(),
                coords.len()
            ),
        )
        .into());
    }
    if drives.len() != options.drive_cols().len() {
        return Err(OptionError::new(
            "drive_col",
            format!(
                "{} names for {} drives of the arrays: name each drive",
                options.drive_cols().len(),
                drives.len()
            ),
        )
        .into());
    }
    let t = match (t, options.dt) {
        (Some(_), Some(_)) => {
            return Err(
                OptionError::new("dt", "give the time stamps t= or the sampling step dt=, not both").into(),
            );
        }
        (None, None) => {
            return Err(OptionError::new("dt", "give the time stamps t= or the sampling step dt=").into());
        }
        (Some(t), None) => {
            if t.len() != x.len() {
                return Err(OptionError::new(
                    "t",
                    format!(
                        "{} time stamps for {} samples: give one time per sample",
                        t.len(),
                        x.len()
                    ),
                )
                .into());
            }
            t.to_vec()
        }
        (None, Some(dt)) => (0..x.len()).map(|i| i as f64 * dt).collect(),
    };
    for (what, series) in others
        .iter()
        .map(|o| ("coordinate", o))
        .chain(drives.iter().map(|d| ("drive", d)))
    {
        if series.len() != x.len() {
            return Err(OptionError::new(
                if what == "drive" { "drive" } else { "x" },
                format!(
                    "{} {what} samples for {} samples: give one per sample",
                    series.len(),
                    x.len()
                ),
            )
            .into());
        }
    }
    let roles = std::iter::once(Role::Time)
        .chain(coords.iter().map(|_| Role::Angle))
        .chain(drives.iter().map(|_| Role::Drive));
    // With «skip_missing», the samples with a NaN in any array left out, as a file's rows are.
    let mut missing = Vec::new();
    let mut kept: Vec<Vec<f64>> = Vec::new();
    // Each sample kept's place in the arrays (when some are left out).
    let mut places: Vec<usize> = Vec::new();
    if options.skip_missing {
        let all: Vec<&[f64]> = std::iter::once(t.as_slice())
            .chain(coords.iter().copied())
            .chain(drives.iter().copied())
            .collect();
        let keep: Vec<bool> = (0..x.len()).map(|i| all.iter().all(|v| !v[i].is_nan())).collect();
        missing = (0..x.len())
            .filter(|&i| !keep[i])
            .map(|i| hb_record::input::Location::Sample(i + 1))
            .collect();
        if missing.len() == x.len() {
            return Err(RunError::Read {
                name: "the arrays".to_owned(),
                coords: options.coords.is_some(),
                source: Box::new(InputError::AllMissing { rows: x.len() }),
            });
        }
        if !missing.is_empty() {
            places = (0..x.len()).filter(|&i| keep[i]).collect();
            kept = all
                .iter()
                .map(|v| {
                    v.iter()
                        .zip(&keep)
                        .filter(|(_, k)| **k)
                        .map(|(a, _)| *a)
                        .collect()
                })
                .collect();
        }
    }
    let columns: Vec<&[f64]> = if kept.is_empty() {
        std::iter::once(t.as_slice())
            .chain(coords.iter().copied())
            .chain(drives.iter().copied())
            .collect()
    } else {
        kept.iter().map(Vec::as_slice).collect()
    };
    // Each array by the name it was given (x and p for one coordinate and one drive).
    let coordinate_names: Vec<String> = match &options.coords {
        Some(c) => c.names().to_vec(),
        None => vec!["x".to_owned()],
    };
    let drive_names: Vec<String> = match options.drive_cols() {
        [] => vec!["p".to_owned()],
        _ => options.drive_names().to_vec(),
    };
    let names = std::iter::once("t".to_owned())
        .chain(coordinate_names)
        .chain(drive_names);
    for ((role, column), name) in roles.zip(columns.iter().copied()).zip(names) {
        if let Some((i, &value)) = column.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(RunError::Read {
                name: "the arrays".to_owned(),
                coords: options.coords.is_some(),
                source: Box::new(InputError::NonFinite {
                    at: hb_record::input::Location::Sample(places.get(i).map_or(i, |&p| p) + 1),
                    role,
                    column: hb_record::input::Column::Name(name),
                    value,
                }),
            });
        }
    }
    let n = 1 + coords.len();
    Ok(InputRecord {
        t: columns[0].to_vec(),
        theta: columns[1].to_vec(),
        others: columns[2..n].iter().map(|o| o.to_vec()).collect(),
        lines: None,
        drives: columns[n..].iter().map(|d| d.to_vec()).collect(),
        velocities: Vec::new(),
        missing,
    })
}

/// The angles on the circle of `record` (and their measured velocities) in radians, read in
/// `unit`. In radians, an angle that wraps by what a turn is in degrees or in an encoder's
/// counts (its span, where it wraps, within 5 % of 360 or of a power of two) is warned of, a
/// system's by its column's name (`columns`, empty for a record of one coordinate).
fn in_radians(
    mut record: InputRecord,
    domains: &[Domain],
    columns: &[String],
    unit: AngleUnit,
    observer: &mut dyn Observer,
) -> InputRecord {
    let on_circle = |i: usize| domains.get(i).or(domains.first()) == Some(&Domain::Circle);
    let scale = unit.radians();
    if unit != AngleUnit::Radians {
        for (i, column) in std::iter::once(&mut record.theta)
            .chain(record.others.iter_mut())
            .enumerate()
        {
            if on_circle(i) {
                column.iter_mut().for_each(|v| *v *= scale);
            }
        }
        for (i, column) in record.velocities.iter_mut().enumerate() {
            if on_circle(i) {
                column.iter_mut().for_each(|v| *v *= scale);
            }
        }
        return record;
    }
    for (i, column) in std::iter::once(&record.theta).chain(&record.others).enumerate() {
        if !on_circle(i) {
            continue;
        }
        if let Some(turn) = wrap_size(column) {
            let unit = if (turn / 360.0 - 1.0).abs() < 0.05 {
                Some("«angle_unit=deg» if they are degrees".to_owned())
            } else {
                let counts = turn.log2().round();
                ((8.0..=32.0).contains(&counts) && (turn / counts.exp2() - 1.0).abs() < 0.05).then(|| {
                    format!(
                        "«angle_unit=counts:{}» if they are an encoder's counts",
                        counts.exp2()
                    )
                })
            };
            if let Some(unit) = unit {
                // A system's angle by its column's name, as its spikes are.
                let which = match columns.get(i) {
                    Some(name) if columns.len() > 1 => name.clone(),
                    _ => "the angle".to_owned(),
                };
                observer.notice(&Notice::Warning(format!(
                    "{which} jumps by about {turn:.0} where it wraps, not 2π: read as radians; give {unit}"
                )));
            }
        }
    }
    record
}

/// What a turn is in the unit of `x` when it wraps in another unit than radians: its span
/// (largest less smallest value), when the span is beyond a turn and a half in radians and at
/// least two steps jump by more than half of it (where it wraps).
fn wrap_size(x: &[f64]) -> Option<f64> {
    let (lo, hi) = x
        .iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    let span = hi - lo;
    // A NaN span (no finite value) is no span either.
    if span.is_nan() || span <= 3.0 * std::f64::consts::PI {
        return None;
    }
    let wraps = x.windows(2).filter(|w| (w[1] - w[0]).abs() > 0.5 * span).count();
    (wraps >= 2).then_some(span)
}

/// Reads `source` (for a file) and conditions it: time stamps fitted to a grid, wrapped on the
/// circle, spikes found and repaired on request, integrated when a velocity or acceleration was
/// measured. Each note is told to `observer` as it is found.
pub fn condition_source(
    source: Source<'_>,
    options: &RecordOptions,
    observer: &mut dyn Observer,
) -> Result<GridData, RunError> {
    options.check()?;
    let name = source_name(&source);
    let record = match source {
        Source::Grid(grid) => return Ok(grid),
        Source::Path(path) => {
            observer.stage(Stage::Read);
            // A step given for a record that has its own stamps replaces them: said, since a
            // wrong step would otherwise pass unseen.
            if options.dt.is_some()
                && options.time_col.is_none()
                && hb_record::input::Header::of(path).is_some_and(|h| h.names().iter().any(|n| n == "t"))
            {
                observer.notice(&Notice::Warning(
                    "the record has a time column 't', whose stamps «dt» replaces (not read): give «time_col=t» \
                     instead of «dt» to read them"
                        .to_owned(),
                ));
            }
            read_path(path, &options.read_options()?).map_err(|source| RunError::Read {
                name: name.clone(),
                source: Box::new(source),
                coords: options.coords.is_some(),
            })?
        }
        Source::Arrays { coords, t, drives } => arrays_record(&coords, t, &drives, options)?,
    };
    condition_read(record, options, name, observer, &|at| at)
}

/// A read record conditioned as [`condition_source`] conditions it; the places its notes and
/// errors name mapped by `relocate` (a chunk's as the file's).
pub(crate) fn condition_read(
    record: InputRecord,
    options: &RecordOptions,
    name: String,
    observer: &mut dyn Observer,
    relocate: &dyn Fn(hb_record::input::Location) -> hb_record::input::Location,
) -> Result<GridData, RunError> {
    let domains = options.domains();
    // A system's notes are named by their column.
    let columns: Vec<String> = match &options.coords {
        Some(c) if c.len() > 1 => c.names().to_vec(),
        _ => Vec::new(),
    };
    let record = in_radians(record, &domains, &columns, options.angle_unit, observer);
    let prepare = PrepareOptions::new(domains[0])
        .with_others(domains[1..].to_vec())
        .with_repair(options.repair)
        .with_spikes(if options.no_repair {
            SpikePolicy::Keep
        } else {
            SpikePolicy::RepairFew
        })
        .with_measured(options.measured)
        .with_bridge(options.bridge_gaps);
    condition(record, &prepare, &mut |note| {
        let note = note.relocated(relocate);
        let notice = match note {
            Note::Spikes { coordinate, .. } if coordinate < columns.len() => Notice::Column {
                column: columns[coordinate].clone(),
                note,
            },
            note => Notice::Record(note),
        };
        observer.notice(&notice)
    })
    .map_err(|e| match e {
        PrepareError::Input(source) => RunError::Read {
            name,
            source: Box::new(source.relocated(relocate)),
            coords: options.coords.is_some(),
        },
        e => RunError::Prepare(e),
    })
}

/// The record of `source` ready for analysis ([`condition_source`]), its clock found by `drive`
/// (given, estimated or the free oscillation's), resampled onto whole periods when needed; the
/// drive found is told to `observer`.
pub fn load(
    source: Source<'_>,
    options: &RecordOptions,
    drive: DriveSpec,
    observer: &mut dyn Observer,
) -> Result<Data, RunError> {
    let grid = condition_source(source, options, observer)?;
    Ok(on_clock(grid, drive, observer)?.0)
}

/// A conditioned record on its clock ([`load`]'s second half), and the period's source it was
/// found by.
pub(crate) fn on_clock(
    grid: GridData,
    drive: DriveSpec,
    observer: &mut dyn Observer,
) -> Result<(Data, PeriodSource), RunError> {
    if matches!(drive, DriveSpec::Auto(_)) {
        observer.stage(Stage::Drive);
    }
    let (period, estimate) = drive
        .resolve(&grid, &mut |done, total| observer.progress(done, total))
        .map_err(RunError::DriveEstimate)?;
    if let Some(estimate) = estimate {
        observer.notice(&Notice::DriveEstimated(estimate));
    }
    let data = grid.with_period(period).map_err(RunError::Drive)?;
    match &data.drive {
        DriveFound::Given | DriveFound::Estimated { .. } => {}
        DriveFound::Free { samples } => observer.notice(&Notice::FreePeriod {
            samples: *samples,
            used: data.p,
        }),
        DriveFound::Windows { samples } => observer.notice(&Notice::WindowUnit {
            samples: *samples,
            length: *samples as f64 * data.clock.step(),
            measured_drive: !data.drives.is_empty(),
        }),
    }
    if let Some(from) = data.resampled_from {
        observer.notice(&Notice::Resampled { from, to: data.p });
    }
    Ok((data, period))
}

/// The records of `sources`, each read, conditioned and its clock found as [`load`] does, joined
/// into one on the first one's grid: each record is a piece of its own (or several, with its own
/// gaps), after a gap of at least one drive period, so that no window or orbit spans two records
/// and every stage sees one record. With a periodic drive each record keeps its own drive phase:
/// it is placed a whole number of drive periods after its own time origin, which needs the
/// records' time stamps to lie on one grid (the same step, and origins a whole number of steps
/// apart); without one (a measured drive, no drive, windows in time) the records' time origins
/// do not matter. One record is [`load`]'s.
///
/// Errors: records with other samples per period or steps more than 0.1 % apart, another
/// number of coordinates or drives, and, with a periodic drive, origins off the first's grid.
pub fn load_all(
    sources: Vec<Source<'_>>,
    options: &RecordOptions,
    drive: DriveSpec,
    observer: &mut dyn Observer,
) -> Result<Data, RunError> {
    let several = sources.len() > 1;
    let names: Vec<String> = sources.iter().map(source_name).collect();
    let read = options.read_options()?;
    // The first file's header names of the columns chosen, which every other file's must be.
    let mut first_names: Option<(String, Vec<String>)> = None;
    let mut records = Vec::with_capacity(sources.len());
    for (source, name) in sources.into_iter().zip(&names) {
        if let (true, Source::Path(path)) = (several, &source)
            && let Some(names) = hb_record::input::Header::of(path).and_then(|h| h.chosen(&read))
        {
            match &first_names {
                None => first_names = Some((path.display().to_string(), names)),
                Some((first, expected)) => same_columns(options, first, expected, path, &names)?,
            }
        }
        // Of several records, the one that fails is named (a read error names it already).
        // Of several records, each one's notes are named by it.
        let mut named = crate::observe::OfRecord {
            record: name,
            inner: &mut *observer,
        };
        let observer: &mut dyn Observer = if several { &mut named } else { &mut *observer };
        records.push(load(source, options, drive, observer).map_err(|e| match e {
            e @ (RunError::Read { .. } | RunError::Options(_)) => e,
            e if several => RunError::InRecord {
                name: name.clone(),
                source: Box::new(e),
            },
            e => e,
        })?);
    }
    let mut records = records.into_iter();
    let Some(mut joined) = records.next() else {
        return Err(OptionError::new("file", "no record given").into());
    };
    let periodic = matches!(joined.drive, DriveFound::Given | DriveFound::Estimated { .. });
    let h = joined.clock.step();
    for (i, data) in records.enumerate() {
        let (which, first) = (&names[i + 1], &names[0]);
        let differs = |what: String| -> RunError {
            OptionError::new(
                "file",
                format!("{which} {what}: records of one identification share one kind of grid ({first} is the first)"),
            )
            .into()
        };
        if data.p != joined.p {
            return Err(differs(format!(
                "has {} samples per period, the first {}",
                data.p, joined.p
            )));
        }
        if ((data.clock.step() - h) / h).abs() > 1e-3 {
            return Err(differs(format!(
                "has the step {}, the first {h}",
                data.clock.step()
            )));
        }
        if data.others.len() != joined.others.len() || data.drives.len() != joined.drives.len() {
            return Err(differs("has other columns".to_owned()));
        }
        // A gap of at least one period; with a periodic drive as many samples more as put the
        // record's first sample at its own time plus whole periods.
        let end = joined.x.len();
        let mut gap = joined.p;
        if periodic {
            let period = joined.clock.drive_period();
            let at = joined.clock.time(end + gap);
            let offset = (data.clock.start_time() - at).rem_euclid(period) / h;
            let whole = offset.round();
            if (offset - whole).abs() > 1e-3 {
                return Err(differs(format!(
                    "starts {} steps off the first's grid (modulo the drive period): with a periodic drive the \
                     records' time stamps must lie on one grid (the same step and origins whole steps apart)",
                    offset - offset.floor()
                )));
            }
            gap += whole as usize % joined.p;
        }
        let shift = end + gap;
        let pad = |v: &mut Vec<f64>, more: &[f64]| {
            v.resize(shift, f64::NAN);
            v.extend_from_slice(more);
        };
        pad(&mut joined.x, &data.x);
        for (mine, theirs) in joined.others.iter_mut().zip(&data.others) {
            pad(&mut mine.x, &theirs.x);
        }
        for (mine, theirs) in joined.drives.iter_mut().zip(&data.drives) {
            pad(mine, theirs);
        }
        for (mine, theirs) in joined.velocities.iter_mut().zip(&data.velocities) {
            pad(mine, theirs);
        }
        joined
            .pieces
            .extend(data.pieces.iter().map(|r| r.start + shift..r.end + shift));
        joined
            .bridged
            .extend(data.bridged.iter().map(|r| r.start + shift..r.end + shift));
    }
    Ok(joined)
}

/// That the columns `options` choose are named in the header of the file at `path` as in the
/// first file's (`expected`): records chosen by position whose headers name other columns there
/// would be joined silently, one's angle taken for another's.
fn same_columns(
    options: &RecordOptions,
    first: &str,
    expected: &[String],
    path: &Path,
    names: &[String],
) -> Result<(), RunError> {
    let Some(k) = (0..names.len().min(expected.len())).find(|&k| names[k] != expected[k]) else {
        return Ok(());
    };
    let coordinates = options.coordinates();
    let drives = options.drive_cols().len();
    let (option, list) = if k < coordinates {
        match &options.coords {
            Some(c) => ("coords", c.columns().to_vec()),
            None => (
                "angle_col",
                options.angle_col.iter().map(|c| c.to_string()).collect(),
            ),
        }
    } else if k < coordinates + drives {
        ("drive_col", options.drive_cols().to_vec())
    } else {
        (
            "velocity_col",
            options
                .velocity_col
                .as_ref()
                .map(|v| v.columns().to_vec())
                .unwrap_or_default(),
        )
    };
    let slot = if k < coordinates {
        k
    } else if k < coordinates + drives {
        k - coordinates
    } else {
        k - coordinates - drives
    };
    let column = list.get(slot).cloned().unwrap_or_default();
    Err(OptionError::new(
        option,
        format!(
            "column {column} is '{}' in {} and '{}' in {first}: the records of one identification hold the \
             same columns (choose them by their header names)",
            names[k],
            path.display(),
            expected[k]
        ),
    )
    .into())
}

/// What the record turned out to be, for the reports.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RecordSummary {
    /// Samples that hold data (the gaps not counted).
    pub samples: usize,
    /// The time of sample 0 of the grid.
    pub start: f64,
    /// The sampling step after any resampling.
    pub step: f64,
    /// Samples per drive period (or per oscillation period of a free record) after any
    /// resampling.
    pub samples_per_period: usize,
    /// The period that is the windows' unit: the drive's, or the free oscillation's.
    pub period: f64,
    /// `given`, `estimated`, `free`, or `windows` (no periodic drive: the windows' length
    /// given).
    pub drive: &'static str,
    /// The estimate's standard uncertainty, for an estimated drive.
    pub period_uncertainty: Option<f64>,
    /// Samples per period as read, when the record was resampled.
    pub resampled_from: Option<f64>,
    /// The pieces that hold data, `[start, end)` sample ranges of the grid.
    pub pieces: Vec<[usize; 2]>,
    /// An angle (`circle`) or a displacement (`line`).
    #[serde(serialize_with = "text::serialize")]
    pub signal: Domain,
    /// The record in one line.
    pub summary: String,
}

impl RecordSummary {
    /// The summary of `data`.
    pub fn of(data: &Data) -> Self {
        let (drive, uncertainty) = match &data.drive {
            DriveFound::Given => ("given", None),
            DriveFound::Estimated { uncertainty } => ("estimated", Some(*uncertainty)),
            DriveFound::Free { .. } => ("free", None),
            DriveFound::Windows { .. } => ("windows", None),
        };
        Self {
            samples: data.pieces.iter().map(|r| r.len()).sum(),
            start: data.clock.start_time(),
            step: data.clock.step(),
            samples_per_period: data.p,
            period: data.clock.drive_period(),
            drive,
            period_uncertainty: uncertainty,
            resampled_from: data.resampled_from,
            pieces: data.pieces.iter().map(|r| [r.start, r.end]).collect(),
            signal: data.domain,
            summary: data.summary(),
        }
    }
}
