//! The record of a request: where its samples come from ([`Source`]), the options that say how
//! to read and condition it ([`RecordOptions`], shared by `identify`, `embed`, `upos` and
//! `report`), and the one way it becomes a [`Data`] ([`load`]).

use std::fmt;
use std::path::Path;
use std::str::FromStr;

use circle_signal::{Domain, Measured};
use hb_record::input::{Column, InputError, ReadOptions, Record as InputRecord, Role, read_path};
use hb_record::prepare::{
    BadDrive, Data, DriveFound, DriveSpec, DriveUnit, GridData, PrepareError, PrepareOptions, condition,
};
use serde::{Deserialize, Serialize};

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

/// The options of a record, as `hbid identify`, `embed`, `upos` and `report` take them and the
/// Python functions of the same names. Defaults: an angle on the circle, measured as the
/// displacement itself, nothing repaired, the drive's period 2π (the paper's time) unless given.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct RecordOptions {
    /// The time column of a file, by header name or 1-based position.
    #[serde(with = "optional_text")]
    pub time_col: Option<String>,
    /// The angle (or displacement) column of a file, by header name or 1-based position.
    #[serde(with = "optional_text")]
    pub angle_col: Option<String>,
    /// The sampling step, for records without time stamps (the first sample at t = 0).
    pub dt: Option<f64>,
    /// The column of a file that holds the measured drive `p(t)`, sampled with the angle.
    #[serde(with = "optional_text")]
    pub drive_col: Option<String>,
    /// Replace isolated time-stamp glitches and encoder spikes (each named in a note).
    pub repair: bool,
    /// An angle on the circle or a displacement on the line.
    #[serde(with = "text")]
    pub signal: Domain,
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
}

impl RecordOptions {
    /// Checks the options that do not depend on the record.
    pub fn check(&self) -> Result<(), OptionError> {
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
        for (name, col) in [
            ("time_col", &self.time_col),
            ("angle_col", &self.angle_col),
            ("drive_col", &self.drive_col),
        ] {
            if let Some(text) = col {
                text.parse::<Column>()
                    .map_err(|e| OptionError::value(name, text, e))?;
            }
        }
        if self.measured != Measured::Displacement && self.signal == Domain::Circle {
            return Err(OptionError::value(
                "measured",
                self.measured,
                "a velocity or acceleration record is integrated to a displacement on the line: needs «signal=line»",
            ));
        }
        Ok(())
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

    fn read_options(&self) -> Result<ReadOptions, OptionError> {
        let column = |name: &str, text: &Option<String>| {
            text.as_deref()
                .map(|t| t.parse::<Column>().map_err(|e| OptionError::value(name, t, e)))
                .transpose()
        };
        Ok(ReadOptions {
            time: column("time_col", &self.time_col)?,
            angle: column("angle_col", &self.angle_col)?,
            dt: self.dt,
            drive: column("drive_col", &self.drive_col)?,
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
    /// and the measured drive `p(t)` sampled with them, if any.
    Arrays {
        /// The angle (or displacement) samples.
        x: &'a [f64],
        /// Their time stamps.
        t: Option<&'a [f64]>,
        /// The measured drive, one sample per sample of `x`.
        drive: Option<&'a [f64]>,
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
    x: &[f64],
    t: Option<&[f64]>,
    drive: Option<&[f64]>,
    options: &RecordOptions,
) -> Result<InputRecord, RunError> {
    if options.time_col.is_some() || options.angle_col.is_some() || options.drive_col.is_some() {
        let name = if options.time_col.is_some() {
            "time_col"
        } else if options.angle_col.is_some() {
            "angle_col"
        } else {
            "drive_col"
        };
        return Err(
            OptionError::sentence(name, "names a column of a file: give arrays, or a file to read").into(),
        );
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
    if let Some(p) = drive
        && p.len() != x.len()
    {
        return Err(OptionError::new(
            "drive",
            format!(
                "{} drive samples for {} samples: give one per sample",
                p.len(),
                x.len()
            ),
        )
        .into());
    }
    for (i, (&ti, &xi)) in t.iter().zip(x).enumerate() {
        for (role, value) in [(Role::Time, ti), (Role::Angle, xi)] {
            if !value.is_finite() {
                return Err(RunError::Read {
                    name: "the arrays".to_owned(),
                    source: InputError::NonFinite {
                        at: hb_record::input::Location::Sample(i + 1),
                        role,
                        value,
                    },
                });
            }
        }
    }
    Ok(InputRecord {
        t,
        theta: x.to_vec(),
        lines: None,
        drive: drive.map(<[f64]>::to_vec),
    })
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
            read_path(path, &options.read_options()?).map_err(|source| RunError::Read {
                name: name.clone(),
                source,
            })?
        }
        Source::Arrays { x, t, drive } => arrays_record(x, t, drive, options)?,
    };
    let prepare = PrepareOptions::new(options.signal)
        .with_repair(options.repair)
        .with_measured(options.measured);
    condition(record, &prepare, &mut |note| {
        observer.notice(&Notice::Record(note.clone()))
    })
    .map_err(|e| match e {
        PrepareError::Input(source) => RunError::Read { name, source },
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
    if matches!(drive, DriveSpec::Auto(_)) {
        observer.stage(Stage::Drive);
    }
    let data = grid
        .with_drive(drive, &mut |done, total| observer.progress(done, total))
        .map_err(RunError::Drive)?;
    match &data.drive {
        DriveFound::Given => {}
        DriveFound::Estimated(e) => observer.notice(&Notice::DriveEstimated(e.as_ref().clone())),
        DriveFound::Free { samples } => observer.notice(&Notice::FreePeriod {
            samples: *samples,
            used: data.p,
        }),
        DriveFound::Windows { samples } => observer.notice(&Notice::WindowUnit {
            samples: *samples,
            length: *samples as f64 * data.clock.step(),
        }),
    }
    if let Some(from) = data.resampled_from {
        observer.notice(&Notice::Resampled { from, to: data.p });
    }
    Ok(data)
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
            DriveFound::Estimated(e) => ("estimated", Some(e.period_uncertainty)),
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
