//! A record made ready for analysis, the one way every front end does it: time stamps fitted to a
//! grid (pieces on one grid, NaN in the gaps, a logger's unsettled start or end left out of every
//! column), wrapped on the circle, encoder spikes found (and repaired on request), the drive
//! given (or estimated by the caller, from [`GridData`]), or absent (a free oscillation, whose
//! period [`circle_signal::oscillation_period`] measures), and the record resampled once onto a
//! whole number of samples per drive period when needed.
//!
//! Two steps, so that a front end can show a record before it knows the drive: [`condition`]
//! (read record to [`GridData`]) and [`GridData::with_period`] (to [`Data`], the record as every
//! stage takes it). Estimating a drive's period is a weak-form fit, the solver's business: it is
//! done above this crate (`hb_drive`), which reads no model and builds no solver. Nothing here prints: what was done to the record is reported as [`Note`]s,
//! through a callback as each happens and kept in the result.
//!
//! # Example
//!
//! ```
//! use circle_signal::Domain;
//! use hb_record::input::Record;
//! use hb_record::prepare::{PeriodSource, PrepareOptions, condition};
//!
//! // 8 samples per forcing period of 2 time units, with a gap of 3 samples.
//! let t: Vec<f64> = (0..80).chain(83..160).map(|n| n as f64 * 0.25).collect();
//! let theta = t.iter().map(|t| (std::f64::consts::PI * t).sin()).collect();
//! let record = Record { t, theta, ..Record::default() };
//! let grid = condition(record, &PrepareOptions::new(Domain::Circle), &mut |_| {})?;
//! assert_eq!(grid.pieces, [0..80, 83..160]);
//! let data = grid.with_period(PeriodSource::Given(2.0))?;
//! assert_eq!(data.p, 8);
//! # Ok::<(), hb_record::prepare::PrepareError>(())
//! ```

use std::f64::consts::PI;
use std::fmt;
use std::ops::Range;

use crate::input::{
    AngleRange, GridOptions, GridRecord, GridReport, InputError, Location, Record as InputRecord, RecordEnd,
    TimeRepair, UNSETTLED_MAX, Unsettled, angle_range_of,
};
use circle_signal::{
    CircleError, Domain, Measured, SampleClock, Spike, SpikeParams, find_and_repair_spikes,
    find_spikes_in_place, resample_columns,
};

use rayon::prelude::*;

pub mod bridge;
pub use bridge::MAX_BRIDGE;

/// Where the windows' unit, a drive period, comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PeriodSource {
    /// A known drive period, in the record's time unit.
    Given(f64),
    /// A drive period estimated from the record (by the caller), with its standard uncertainty.
    Estimated {
        /// The period, in the record's time unit.
        period: f64,
        /// Its standard uncertainty.
        uncertainty: f64,
    },
    /// No drive: a free oscillation, whose mean period is the unit of the windows.
    Free,
    /// No periodic drive (none, or a measured one with no period): the unit of the windows given
    /// by its length.
    Windows(WindowUnit),
}

/// The length of the windows' unit (a window is a whole number of units), for a record without a
/// periodic drive to count them in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum WindowUnit {
    /// A length in the record's time unit, rounded to whole samples.
    Time(f64),
    /// A whole number of samples (at least 2).
    Samples(usize),
}

/// Where a record's time unit for the analysis came from.
#[derive(Debug, Clone, PartialEq)]
pub enum DriveFound {
    /// The forcing period given.
    Given,
    /// Estimated from the record.
    Estimated {
        /// The estimate's standard uncertainty.
        uncertainty: f64,
    },
    /// No drive: the mean period of the free oscillation, in samples.
    Free {
        /// The measured mean period, in samples (the clock's period is its nearest whole number).
        samples: f64,
    },
    /// No periodic drive: the windows' unit as given, in whole samples.
    Windows {
        /// Samples per unit.
        samples: usize,
    },
}

/// How to condition a record.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PrepareOptions {
    /// An angle on the circle (wrapped into `[-π, π)`) or a displacement on the line.
    pub signal: Domain,
    /// The domains of the further coordinates ([`crate::input::Record::others`]), in order.
    pub others: Vec<Domain>,
    /// Replace isolated time-stamp glitches by their grid time and every isolated encoder spike by
    /// the local prediction, whatever [`spikes`](Self::spikes) says (without it, a glitch is an
    /// error).
    pub repair: bool,
    /// What to do with the spikes without [`repair`](Self::repair): by default replace them when
    /// they are few ([`SpikePolicy::RepairFew`]).
    pub spikes: SpikePolicy,
    /// What the sensor measured: the displacement itself, or its velocity or acceleration (on the
    /// line only), integrated to the displacement by [`circle_signal::displacement`].
    pub measured: Measured,
    /// Bridge every gap of at most this many missing samples, between pieces long enough to be
    /// searched for spikes, by the cubic through the two samples on each side, in every column
    /// (see [`bridge`]); 0, the default, bridges none. At most [`MAX_BRIDGE`], and only for a
    /// record of the displacement itself (a velocity or acceleration is integrated piece by
    /// piece).
    pub bridge: usize,
}

impl PrepareOptions {
    /// A record of `signal`: no time stamp repaired, spikes replaced when they are few.
    pub fn new(signal: Domain) -> Self {
        Self {
            signal,
            others: Vec::new(),
            repair: false,
            spikes: SpikePolicy::RepairFew,
            measured: Measured::Displacement,
            bridge: 0,
        }
    }

    /// With further coordinates on these domains (see [`PrepareOptions::others`]).
    pub fn with_others(mut self, others: Vec<Domain>) -> Self {
        self.others = others;
        self
    }

    /// The domain of every coordinate, the first one first.
    pub fn domains(&self) -> Vec<Domain> {
        std::iter::once(self.signal)
            .chain(self.others.iter().copied())
            .collect()
    }

    /// With this policy for the spikes (see [`PrepareOptions::spikes`]).
    pub fn with_spikes(mut self, spikes: SpikePolicy) -> Self {
        self.spikes = spikes;
        self
    }

    /// A record of the velocity or acceleration of the displacement (see
    /// [`PrepareOptions::measured`]).
    pub fn with_measured(mut self, measured: Measured) -> Self {
        self.measured = measured;
        self
    }

    /// Bridging gaps of at most `bridge` missing samples (see [`PrepareOptions::bridge`]).
    pub fn with_bridge(mut self, bridge: usize) -> Self {
        self.bridge = bridge;
        self
    }

    /// With repairs (see [`PrepareOptions::repair`]).
    pub fn with_repair(mut self, repair: bool) -> Self {
        self.repair = repair;
        self
    }
}

/// Something done to a record, or found in it, on the way to the analysis.
#[derive(Debug, Clone, PartialEq)]
pub enum Note {
    /// How the time stamps sit on the grid, when worth a note ([`GridReport::is_notable`]): the
    /// clock that stamped them slips, or they deviate from the grid beyond their printing.
    Grid(GridReport),
    /// Samples left out at an end of the record: stamped at another rate than the rest, before
    /// the logger settled to its rate or after it left it.
    Unsettled(Unsettled),
    /// A time stamp replaced by its grid time.
    TimeRepaired(TimeRepair),
    /// Gaps in the time stamps: the record is analysed in pieces.
    Gaps {
        /// The gaps.
        gaps: usize,
        /// Samples missing in them.
        missing: usize,
    },
    /// Gaps of at most `limit` missing samples bridged ([`PrepareOptions::bridge`]): the samples
    /// they miss interpolated in every column, their pieces analysed as one.
    Bridged {
        /// The gaps bridged.
        gaps: usize,
        /// The samples interpolated in them.
        missing: usize,
        /// The most samples a bridged gap may miss.
        limit: usize,
        /// Gaps short enough but left as they are: an angle moved too far across them to tell
        /// its turn (see [`bridge`]).
        unclear: usize,
    },
    /// Rows written twice (a stamp and every value the same as the row before), the second of
    /// each left out.
    DuplicateRows {
        /// Where the first repeated row is.
        first: Location,
        /// How many were left out.
        count: usize,
        /// Their time stamps (where a record read in chunks counts each once).
        times: Vec<f64>,
    },
    /// Rows with a missing value in a column read, left out as a logger's dropped rows
    /// ([`crate::input::ReadOptions::skip_missing`]).
    MissingRows {
        /// How many.
        count: usize,
        /// Where the first few are (at most [`MISSING_NAMED`]).
        first: Vec<Location>,
    },
    /// Values outside `[-π, π)` read as an unwrapped angle, and wrapped.
    Wrapped,
    /// A velocity or acceleration record integrated to the displacement.
    Integrated(Measured),
    /// Isolated spikes (bit errors on the circle) or outliers (on the line: a sample or a short
    /// run far off its neighbours) found in the record, replaced when `repaired`.
    Spikes {
        /// The coordinate they were found in (0, the first, for a record of one).
        coordinate: usize,
        /// The spikes, indices in the record's grid.
        found: Vec<Spike>,
        /// Whether they were replaced by the local prediction.
        repaired: bool,
        /// Where the record lives: on the circle an encoder's bit errors, on the line outliers.
        domain: Domain,
        /// The policy they were met with: [`SpikePolicy::Repair`] when repairs were asked for.
        policy: SpikePolicy,
        /// The grid's first time and step, when known: each spike is then named by its time
        /// too (a sample's index counts on the grid, which a logger's first rows or a gap do
        /// not keep in step with the file's rows).
        grid: Option<(f64, f64)>,
    },
}

impl Note {
    /// The note of coordinate `coordinate`: a spikes note's coordinate replaced, any other
    /// note as it is.
    pub fn of_coordinate(&self, coordinate: usize) -> Note {
        match self {
            Note::Spikes {
                found,
                repaired,
                domain,
                policy,
                grid,
                ..
            } => Note::Spikes {
                coordinate,
                found: found.clone(),
                repaired: *repaired,
                domain: *domain,
                policy: *policy,
                grid: *grid,
            },
            other => other.clone(),
        }
    }

    /// The note with every place of the file it names mapped by `at` (a chunk's places as the
    /// file's, [`crate::input::Chunk::relocate`]); a spike's index, a place in the grid, is not
    /// one of them.
    pub fn relocated(&self, at: &dyn Fn(Location) -> Location) -> Note {
        match self {
            Note::Grid(report) => Note::Grid(GridReport {
                max_at: at(report.max_at),
                slips: report
                    .slips
                    .iter()
                    .map(|s| crate::input::Slip {
                        at: at(s.at),
                        by: s.by,
                    })
                    .collect(),
                ..report.clone()
            }),
            Note::Unsettled(run) => Note::Unsettled(crate::input::Unsettled {
                first: at(run.first),
                last: at(run.last),
                ..run.clone()
            }),
            Note::TimeRepaired(r) => Note::TimeRepaired(crate::input::TimeRepair { at: at(r.at), ..*r }),
            Note::DuplicateRows { first, count, times } => Note::DuplicateRows {
                first: at(*first),
                count: *count,
                times: times.clone(),
            },
            Note::MissingRows { count, first } => Note::MissingRows {
                count: *count,
                first: first.iter().map(|&l| at(l)).collect(),
            },
            other => other.clone(),
        }
    }

    /// Whether the note is a warning (spikes left in the record, or time stamps that jitter by
    /// more than [`crate::input::JITTER_WARNING`] of the step), not a plain note.
    pub fn is_warning(&self) -> bool {
        match self {
            Note::Spikes { repaired, .. } => !repaired,
            Note::Grid(report) => report.is_warning(),
            _ => false,
        }
    }
}

/// The text of the note, without its `note:` or `warning:` and without the options of a front
/// end (a front end adds how to repair the spikes it warns about).
impl fmt::Display for Note {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Note::Grid(report) => write!(f, "{report}"),
            Note::Unsettled(run) => write!(f, "{run}"),
            Note::TimeRepaired(r) => {
                write!(f, "{}: time {} replaced by its grid time {}", r.at, r.was, r.now)
            }
            Note::Gaps { gaps, missing } => write!(
                f,
                "{gaps} gap(s) in the time stamps ({missing} samples missing): the record is analysed in {} pieces",
                gaps + 1
            ),
            Note::Bridged {
                gaps,
                missing,
                limit,
                unclear,
            } => {
                write!(
                    f,
                    "{gaps} gap(s) of at most {limit} missing sample(s) bridged: {missing} sample(s) interpolated in \
                     every column by the cubic through the two samples on each side"
                )?;
                if *unclear > 0 {
                    write!(
                        f,
                        "; {unclear} more left as gaps: an angle moves too far across them to tell its turn"
                    )?;
                }
                Ok(())
            }
            Note::Wrapped => f.write_str("values outside [-π, π): read as an unwrapped angle and wrapped"),
            Note::MissingRows { count, first } => {
                let named: Vec<String> = first.iter().map(ToString::to_string).collect();
                write!(
                    f,
                    "{count} row(s) with a missing value in a column read left out, as a logger's dropped rows: {}{}",
                    named.join(", "),
                    if *count > first.len() { ", ..." } else { "" }
                )
            }
            Note::DuplicateRows { first, count, .. } => write!(
                f,
                "{count} row(s) written twice (the stamp and every value of the row before) left out, the \
                 first at {first}"
            ),
            Note::Integrated(measured) => {
                let (what, removed) = match measured {
                    Measured::Acceleration => ("an acceleration", "least-squares linear trend"),
                    _ => ("a velocity", "mean"),
                };
                write!(
                    f,
                    "{what} record integrated to the displacement less its {removed}; the drift left is fitted \
                     with the model"
                )
            }
            Note::Spikes {
                coordinate,
                found,
                repaired,
                domain,
                policy,
                grid,
            } => {
                if *coordinate > 0 {
                    write!(f, "coordinate {}: ", coordinate + 1)?;
                }
                let list: Vec<String> = found
                    .iter()
                    .take(5)
                    .map(|s| match grid {
                        // To a tenth of the step: the time a file's stamp shows.
                        Some((t0, dt)) => format!(
                            "sample {} at t = {:.*} ({})",
                            s.index + 1,
                            (1.0 - dt.log10()).ceil().clamp(0.0, 12.0) as usize,
                            t0 + s.index as f64 * dt,
                            signed_size(s.size)
                        ),
                        None => format!("sample {} ({})", s.index + 1, signed_size(s.size)),
                    })
                    .collect();
                let more = if found.len() > 5 { ", ..." } else { "" };
                // On the circle the samples are an encoder's: isolated spikes are its bit errors;
                // consecutive ones (runs) are said as such, not called isolated.
                let (isolated, runs, longest) = groups(found);
                let what = match domain {
                    Domain::Circle if runs == 0 => "isolated spike(s)".to_owned(),
                    Domain::Circle => {
                        let lengths = match longest {
                            2 => "2".to_owned(),
                            _ => format!("2 to {longest}"),
                        };
                        format!("outlying sample(s), {isolated} alone and {runs} run(s) of {lengths}")
                    }
                    Domain::Line => "outlier(s)".to_owned(),
                };
                let few = match policy {
                    SpikePolicy::RepairFew if *repaired => format!(
                        " (by default: larger than the record's steps, at most one in {} samples)",
                        SpikePolicy::FEW_ONE_IN
                    ),
                    SpikePolicy::RepairFew => format!(
                        " (not replaced by default: within the record's own steps, or more than one in {} \
                         samples)",
                        SpikePolicy::FEW_ONE_IN
                    ),
                    _ => String::new(),
                };
                if *repaired {
                    write!(
                        f,
                        "{} {what} replaced by the local prediction{few}: {}{more}",
                        found.len(),
                        list.join(", ")
                    )
                } else {
                    let why = match domain {
                        Domain::Circle if runs == 0 => " (bit errors?)",
                        Domain::Circle => " (bit errors, glitches, or motion too fast for the sampling?)",
                        Domain::Line => "",
                    };
                    write!(
                        f,
                        "{} {what}{why} in the record{few}: {}{more}",
                        found.len(),
                        list.join(", ")
                    )
                }
            }
        }
    }
}

/// What can go wrong on the way from a read record to [`Data`]. The texts name no option of a
/// front end; a front end adds them.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PrepareError {
    /// The time stamps (grid fit, glitches) or the forcing period.
    #[error(transparent)]
    Input(#[from] InputError),
    /// The spike test of a piece.
    #[error(transparent)]
    Spikes(CircleError),
    /// A velocity or acceleration record of an angle on the circle.
    #[error("a {0} record is integrated to a displacement on the line; an angle's {0} is not supported")]
    MeasuredOnCircle(Measured),
    /// The integration of a velocity or acceleration record.
    #[error("integrating the record to the displacement")]
    Integrate(#[source] CircleError),
    /// The period of a free oscillation could not be measured.
    #[error("the period of the free oscillation")]
    FreePeriod(#[source] CircleError),
    /// No clock with this forcing period and step.
    #[error("the forcing period")]
    Clock(#[source] CircleError),
    /// The resampling onto whole periods failed.
    #[error("resampling onto a whole number of samples per forcing period")]
    Resample(#[source] CircleError),
    /// The clock is not whole after resampling.
    #[error(transparent)]
    Whole(CircleError),
    /// Windows given in the record's time whose unit is shorter than two samples.
    #[error(
        "the windows' unit of {length:.3e} in the record's time is {:.2} of its steps of {dt}: it needs at \
         least 2 (a longer «window», or fewer «window_periods»)",
        length / dt
    )]
    WindowTooShort {
        /// The unit's length in the record's time (the window over its periods).
        length: f64,
        /// The record's step.
        dt: f64,
    },
    /// Gaps to bridge in a record integrated piece by piece, or too long to bridge.
    #[error("{0}")]
    Bridge(String),
    /// Further coordinates read and their domains do not match.
    #[error("{read} coordinate(s) were read but {domains} domain(s) given")]
    Coordinates {
        /// Coordinates read.
        read: usize,
        /// Domains given.
        domains: usize,
    },
}

/// A coordinate of a record beyond its first, on the record's grid (NaN in the gaps).
#[derive(Debug, Clone, PartialEq)]
pub struct Channel {
    /// The samples.
    pub x: Vec<f64>,
    /// What they are.
    pub domain: Domain,
}

/// How many of the rows left out for a missing value [`Note::MissingRows`] names.
pub const MISSING_NAMED: usize = 5;

/// A record on its grid `t0 + n · dt`: read, fitted, wrapped (on the circle), spikes found.
#[derive(Debug, Clone, PartialEq)]
pub struct GridData {
    /// The time of sample 0.
    pub t0: f64,
    /// The sampling step.
    pub dt: f64,
    /// The samples of the first coordinate on the grid (NaN in the gaps).
    pub x: Vec<f64>,
    /// The ranges of `x` that hold data: one without gaps.
    pub pieces: Vec<Range<usize>>,
    /// What the samples are.
    pub domain: Domain,
    /// The further coordinates on the same grid.
    pub others: Vec<Channel>,
    /// The measured drives on the same grid (NaN in the gaps), in the order read.
    pub drives: Vec<Vec<f64>>,
    /// The coordinates' measured velocities on the same grid (NaN in the gaps), when read.
    pub velocities: Vec<Vec<f64>>,
    /// The samples filled by bridging gaps ([`PrepareOptions::bridge`]), in order: inside
    /// `pieces`, but interpolated in every column, not measured (empty when none were).
    pub bridged: Vec<Range<usize>>,
    /// What was done to the record or found in it, in order.
    pub notes: Vec<Note>,
    /// The record's first rows, left out of the grid because a logger stamped them before it
    /// settled to its rate ([`Unsettled`]), kept aside at their own stamps (none when the record
    /// has no such rows, or they cannot be run through: see [`LeadIn`]).
    pub lead_in: Option<Box<LeadIn>>,
}

/// The rows a logger stamped before it settled to its rate ([`Unsettled`] at the record's
/// start): not on the grid, so left out of every analysis on it, but kept with their own time
/// stamps for what needs no grid, such as a free run compared with the record from its first
/// row. Every series holds one value per row; the angles are wrapped as the grid's are. Kept
/// only when every value is finite, the stamps increase, and the last comes before the grid's
/// first sample; not for a velocity or acceleration record (integrated on the grid alone).
#[derive(Debug, Clone, PartialEq)]
pub struct LeadIn {
    /// What was left out, as the note says it.
    pub run: Unsettled,
    /// The rows' time stamps, as read.
    pub t: Vec<f64>,
    /// The first coordinate.
    pub x: Vec<f64>,
    /// The further coordinates, in order.
    pub others: Vec<Vec<f64>>,
    /// The measured drives, in the order read.
    pub drives: Vec<Vec<f64>>,
    /// The coordinates' measured velocities, when read.
    pub velocities: Vec<Vec<f64>>,
}

impl LeadIn {
    /// The number of rows.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// Never true: a logger's unsettled run holds at least two rows.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }
}

/// A record ready for analysis.
#[derive(Debug)]
pub struct Data {
    /// The record's clock: forcing period, step `T / P`, time of the first sample.
    pub clock: SampleClock,
    /// Samples per forcing period `P`.
    pub p: usize,
    /// The samples (wrapped into [-π, π) for a signal on the circle; NaN in the gaps).
    pub x: Vec<f64>,
    /// The ranges of `x` that hold data: one without gaps.
    pub pieces: Vec<Range<usize>>,
    /// What the samples are.
    pub domain: Domain,
    /// Where the forcing period came from.
    pub drive: DriveFound,
    /// The samples per forcing period of the record as read, when it was resampled to `p`.
    pub resampled_from: Option<f64>,
    /// The further coordinates on the same clock (resampled with the record).
    pub others: Vec<Channel>,
    /// The measured drives on the same clock (resampled with the record; NaN in the gaps), in
    /// the order read.
    pub drives: Vec<Vec<f64>>,
    /// The coordinates' measured velocities on the same clock (resampled with the record), when
    /// read.
    pub velocities: Vec<Vec<f64>>,
    /// The samples filled by bridging gaps ([`GridData::bridged`]), on this clock: a resampled
    /// record's every sample within a bridged stretch's time.
    pub bridged: Vec<Range<usize>>,
}

impl Data {
    /// One line describing the record, for the readable outputs.
    pub fn summary(&self) -> String {
        let samples: usize = self.pieces.iter().map(Range::len).sum();
        let mut line = format!(
            "{samples} samples from t = {} in steps of {} ({} per {})",
            self.clock.start_time(),
            self.clock.step(),
            self.p,
            match self.drive {
                DriveFound::Free { .. } => "oscillation period",
                DriveFound::Windows { .. } => "window unit",
                _ => "forcing period",
            }
        );
        if let Some(from) = self.resampled_from {
            line.push_str(&format!(", resampled from {from:.6} per period"));
        }
        if self.pieces.len() > 1 {
            line.push_str(&format!(", in {} pieces (gaps)", self.pieces.len()));
        }
        line
    }

    /// The longest piece (the whole record without gaps).
    pub fn longest(&self) -> &[f64] {
        &self.x[circle_signal::longest_piece(&self.pieces)]
    }

    /// The first measured drive, when the record holds one.
    pub fn measured_drive(&self) -> Option<&[f64]> {
        self.drives.first().map(Vec::as_slice)
    }

    /// Every coordinate's samples and domain, the first one first.
    pub fn coordinates(&self) -> Vec<(&[f64], Domain)> {
        std::iter::once((self.x.as_slice(), self.domain))
            .chain(self.others.iter().map(|c| (c.x.as_slice(), c.domain)))
            .collect()
    }
}

/// Leaves out every row of `record` that repeats the row before it, its stamp and every value
/// (a logger that wrote a row twice), and says so; `None` when there is none. A stamp repeated
/// with other values is the grid fit's to judge (a glitch).
fn drop_duplicate_rows(record: &mut InputRecord) -> Option<Note> {
    let n = record.t.len();
    let same = |v: &[f64], i: usize| v.get(i).map(|x| x.to_bits()) == v.get(i - 1).map(|x| x.to_bits());
    let repeated = |r: &InputRecord, i: usize| {
        r.t[i] == r.t[i - 1]
            && std::iter::once(&r.theta)
                .chain(&r.others)
                .chain(&r.drives)
                .chain(&r.velocities)
                .all(|v| same(v, i))
    };
    let drop: Vec<usize> = (1..n).filter(|&i| repeated(record, i)).collect();
    let &first = drop.first()?;
    let first = match record.lines.as_ref().and_then(|l| l.get(first)) {
        Some(&line) => Location::Line(line),
        None => crate::input::sample_location(&record.missing, first),
    };
    let times: Vec<f64> = drop.iter().map(|&i| record.t[i]).collect();
    /// `v` without the rows `drop` (increasing).
    fn without<T>(v: &mut Vec<T>, drop: &[usize]) {
        let mut next = drop.iter().peekable();
        let mut i = 0;
        v.retain(|_| {
            let gone = next.next_if_eq(&&i).is_some();
            i += 1;
            !gone
        });
    }
    without(&mut record.t, &drop);
    without(&mut record.theta, &drop);
    for column in record
        .others
        .iter_mut()
        .chain(&mut record.drives)
        .chain(&mut record.velocities)
    {
        without(column, &drop);
    }
    match &mut record.lines {
        Some(lines) => without(lines, &drop),
        // An array's samples are named by their place in it: the rows dropped here join those
        // left out before (`Record::missing`, a place list from here on) so that later places
        // stay the array's.
        None => {
            let mut left: Vec<Location> = drop
                .iter()
                .map(|&i| crate::input::sample_location(&record.missing, i))
                .chain(record.missing.iter().copied())
                .collect();
            left.sort_by_key(|l| match *l {
                Location::Sample(s) => s as u64,
                Location::Line(l) => l,
            });
            record.missing = left;
        }
    }
    Some(Note::DuplicateRows {
        first,
        count: drop.len(),
        times,
    })
}

/// Fits the record's time stamps to a grid (pieces on one grid, NaN in the gaps), wraps it (on the
/// circle) and finds its spikes, repairing glitches and spikes when asked; `notes` hears of each
/// thing done or found as it happens.
pub fn condition(
    record: InputRecord,
    options: &PrepareOptions,
    notes: &mut dyn FnMut(&Note),
) -> Result<GridData, PrepareError> {
    let mut kept = Vec::new();
    let mut note = |n: Note| {
        notes(&n);
        kept.push(n);
    };
    if options.bridge > MAX_BRIDGE {
        return Err(PrepareError::Bridge(format!(
            "a bridged gap may miss at most {MAX_BRIDGE} samples, not {}: the cubic through two samples on each \
             side would carry more than 1.61 times one sample's noise into a longer one's",
            options.bridge
        )));
    }
    if options.bridge > 0 && options.measured != Measured::Displacement {
        return Err(PrepareError::Bridge(
            "a velocity or acceleration record is integrated piece by piece: its gaps cannot be bridged"
                .into(),
        ));
    }
    let mut record = record;
    if !record.missing.is_empty() {
        note(Note::MissingRows {
            count: record.missing.len(),
            first: record.missing.iter().take(MISSING_NAMED).copied().collect(),
        });
    }
    if let Some(duplicates) = drop_duplicate_rows(&mut record) {
        note(duplicates);
    }
    // A logger's unsettled start is at most UNSETTLED_MAX rows: their values, kept aside.
    let head = |v: &[f64]| v[..v.len().min(UNSETTLED_MAX)].to_vec();
    let (head_t, head_x) = (head(&record.t), head(&record.theta));
    let drives_read = std::mem::take(&mut record.drives);
    let velocities_read = std::mem::take(&mut record.velocities);
    let others_read = std::mem::take(&mut record.others);
    if others_read.len() != options.others.len() {
        return Err(PrepareError::Coordinates {
            read: others_read.len() + 1,
            domains: options.others.len() + 1,
        });
    }
    let grid = GridRecord::fit(
        record,
        &GridOptions {
            repair: options.repair,
        },
    )?;
    for run in &grid.unsettled {
        note(Note::Unsettled(run.clone()));
    }
    if grid.report.is_notable() {
        note(Note::Grid(grid.report.clone()));
    }
    for r in &grid.repaired {
        note(Note::TimeRepaired(*r));
    }
    let (t0, dt, read_kept) = (grid.t0, grid.dt, grid.kept());
    let lead_in = grid
        .unsettled
        .iter()
        .find(|run| run.end == RecordEnd::Start)
        .filter(|_| options.measured == Measured::Displacement)
        .and_then(|run| {
            let rows = run.samples.clone();
            let domains = options.domains();
            let angles = |v: &[f64], domain: Domain| -> Vec<f64> {
                v.iter()
                    .map(|&a| match domain {
                        Domain::Circle if !(-PI..PI).contains(&a) => circle_signal::wrap(a),
                        _ => a,
                    })
                    .collect()
            };
            let lead = LeadIn {
                run: run.clone(),
                t: head_t.get(rows.clone())?.to_vec(),
                x: angles(head_x.get(rows.clone())?, domains[0]),
                others: others_read
                    .iter()
                    .zip(&domains[1..])
                    .map(|(v, &d)| Some(angles(v.get(rows.clone())?, d)))
                    .collect::<Option<_>>()?,
                drives: drives_read
                    .iter()
                    .map(|v| v.get(rows.clone()).map(<[f64]>::to_vec))
                    .collect::<Option<_>>()?,
                velocities: velocities_read
                    .iter()
                    .map(|v| v.get(rows.clone()).map(<[f64]>::to_vec))
                    .collect::<Option<_>>()?,
            };
            let finite = std::iter::once(&lead.t)
                .chain(std::iter::once(&lead.x))
                .chain(&lead.others)
                .chain(&lead.drives)
                .chain(&lead.velocities)
                .all(|v| v.iter().all(|a| a.is_finite()));
            let increasing = lead.t.windows(2).all(|w| w[1] > w[0]) && lead.t.last().is_some_and(|&l| l < t0);
            (finite && increasing && !lead.t.is_empty()).then(|| Box::new(lead))
        });
    // One grid for every piece, NaN in the gaps.
    let mut x: Vec<f64> = Vec::new();
    let mut pieces = Vec::with_capacity(grid.pieces.len());
    for piece in grid.pieces {
        pieces.push(piece.first..piece.first + piece.samples.len());
        if x.is_empty() && piece.first == 0 {
            // The first piece from the grid's start (a record without gaps: the only one) is
            // taken as it is, not copied.
            x = piece.samples;
        } else {
            x.resize(piece.first, f64::NAN);
            x.extend(piece.samples);
        }
    }
    // The drives' and further coordinates' samples follow the record's in order: every sample
    // read and kept (not in an unsettled run at an end) is in a piece, the pieces in the order
    // of the samples.
    let whole = pieces.len() == 1 && pieces[0] == (0..x.len());
    let on_grid = |read: Vec<f64>| {
        // A record without gaps, every row read kept: the column is its grid as it is (no
        // copy, as for the first coordinate's).
        if whole && read_kept == (0..read.len()) && read.len() == x.len() {
            return read;
        }
        let mut out = vec![f64::NAN; x.len()];
        let mut next = read.into_iter().skip(read_kept.start).take(read_kept.len());
        for r in &pieces {
            for (slot, value) in out[r.clone()].iter_mut().zip(next.by_ref()) {
                *slot = value;
            }
        }
        out
    };
    let mut drives: Vec<Vec<f64>> = drives_read.into_iter().map(on_grid).collect();
    let mut velocities: Vec<Vec<f64>> = velocities_read.into_iter().map(on_grid).collect();
    let mut others: Vec<Channel> = others_read
        .into_iter()
        .zip(&options.others)
        .map(|(read, &domain)| Channel {
            x: on_grid(read),
            domain,
        })
        .collect();
    // The gaps bridged are filled once every coordinate is conditioned on its pieces (its spikes
    // found and replaced as asked, so that none is a node of the cubic); the note of the gaps
    // counts those left.
    let (bridged, unclear): (Vec<usize>, Vec<usize>) = bridge::bridgeable(&pieces, options.bridge)
        .into_iter()
        .partition(|&g| {
            let (end, start) = (pieces[g].end, pieces[g + 1].start);
            std::iter::once((&x, options.signal))
                .chain(others.iter().map(|c| (&c.x, c.domain)))
                .all(|(x, domain)| domain == Domain::Line || bridge::turn_clear(x, end, start))
        });
    let after = bridge::joined(&pieces, &bridged);
    if after.len() > 1 {
        let missing = x.len() - after.iter().map(Range::len).sum::<usize>();
        note(Note::Gaps {
            gaps: after.len() - 1,
            missing,
        });
    }
    // Each coordinate on its own, in parallel (a double pendulum's two angles take the same
    // time); what each found is told in the coordinates' order, as if one after the other.
    let channels: Vec<(&mut Vec<f64>, Domain)> = std::iter::once((&mut x, options.signal))
        .chain(others.iter_mut().map(|c| (&mut c.x, c.domain)))
        .collect();
    let conditioned: Vec<Conditioned> = channels
        .into_par_iter()
        .enumerate()
        .map(|(coordinate, (x, domain))| condition_channel(x, domain, coordinate, &pieces, (t0, dt), options))
        .collect();
    let mut wrapped = false;
    for channel in conditioned {
        if channel.unwrapped && !wrapped {
            note(Note::Wrapped);
            wrapped = true;
        }
        for spikes in channel.notes {
            note(spikes);
        }
        channel.result?;
    }
    if options.measured != Measured::Displacement {
        note(Note::Integrated(options.measured));
    }
    let mut filled = Vec::with_capacity(bridged.len());
    if !bridged.is_empty() || !unclear.is_empty() {
        let mut missing = 0;
        for &g in &bridged {
            let (end, start) = (pieces[g].end, pieces[g + 1].start);
            missing += start - end;
            filled.push(end..start);
            bridge::fill(&mut x, end, start, options.signal);
            for c in &mut others {
                bridge::fill(&mut c.x, end, start, c.domain);
            }
            for v in drives.iter_mut().chain(velocities.iter_mut()) {
                bridge::fill(v, end, start, Domain::Line);
            }
        }
        note(Note::Bridged {
            gaps: bridged.len(),
            missing,
            limit: options.bridge,
            unclear: unclear.len(),
        });
    }
    Ok(GridData {
        t0,
        dt,
        x,
        pieces: after,
        domain: options.signal,
        others,
        drives,
        velocities,
        bridged: filled,
        notes: kept,
        lead_in,
    })
}

/// What [`condition`] did to one coordinate: whether it was read as an unwrapped angle, the
/// notes of its spikes, and how it ended.
struct Conditioned {
    unwrapped: bool,
    notes: Vec<Note>,
    result: Result<(), PrepareError>,
}

/// One coordinate of [`condition`]: wrapped on the circle, its spikes found (and replaced as
/// the options say), integrated when it is a velocity or acceleration.
fn condition_channel(
    x: &mut Vec<f64>,
    domain: Domain,
    coordinate: usize,
    pieces: &[Range<usize>],
    grid: (f64, f64),
    options: &PrepareOptions,
) -> Conditioned {
    let dt = grid.1;
    let mut unwrapped = false;
    if domain == Domain::Circle {
        let parts: Vec<&[f64]> = pieces.iter().map(|r| &x[r.clone()]).collect();
        if parts
            .iter()
            .flat_map(|p| p.iter())
            .any(|v| !(-PI..PI).contains(v))
        {
            // The pieces read where they are (a copy of the column in one would be a column's
            // memory more, in each coordinate's thread).
            unwrapped = angle_range_of(&parts) == AngleRange::Unwrapped;
            for r in pieces {
                for v in &mut x[r.clone()] {
                    *v = circle_signal::wrap(*v);
                }
            }
        }
    }
    let mut channel_options = options.clone();
    channel_options.signal = domain;
    let found = match spikes(x, pieces, Some(grid), &channel_options) {
        Ok(found) => found,
        Err(e) => {
            return Conditioned {
                unwrapped,
                notes: Vec::new(),
                result: Err(e),
            };
        }
    };
    let notes = found.iter().map(|note| note.of_coordinate(coordinate)).collect();
    let result = if options.measured == Measured::Displacement {
        Ok(())
    } else if domain == Domain::Circle {
        Err(PrepareError::MeasuredOnCircle(options.measured))
    } else {
        circle_signal::displacement(x, dt, options.measured, pieces)
            .map(|integrated| *x = integrated)
            .map_err(PrepareError::Integrate)
    };
    Conditioned {
        unwrapped,
        notes,
        result,
    }
}

/// What to do with the spikes (or outliers) a record is found to have.
///
/// A spike left in a record decides more than its one sample: on the circle one near half a turn
/// is unwrapped into a false turn (and every sample after it is a turn off), and a few of them
/// turn a free decay's windows into whirling ones; on the line an outlier is a jump of the
/// velocity and acceleration the fit balances. A few isolated spikes are what an encoder's bit
/// errors or a vibrometer's dropouts give, and their replacement by the local prediction is what
/// the spike test is measured to do right (`docs/spikes.md`): so by default they are replaced
/// when few, and a note lists them. Many spikes are something else (noise whose level changes
/// within tens of samples, heavy tails, a record too coarse for its motion), which a warning
/// leaves to the user.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SpikePolicy {
    /// Replace them when they are few, at most one in [`FEW_ONE_IN`](Self::FEW_ONE_IN) samples
    /// of the record (rounded up: one in a shorter record); otherwise report them only (a
    /// warning).
    #[default]
    RepairFew,
    /// Replace every one.
    Repair,
    /// Report them only (a warning), replacing none.
    Keep,
}

impl SpikePolicy {
    /// Spikes are few when there are at most one in this many samples: an encoder's bit errors
    /// at the rates rigs show (10⁻⁴ in this project's rig records, 10⁻³ in the spike test's
    /// measurements) are few; the test's false alarms where the noise level changes within tens
    /// of samples (up to `7.5 · 10⁻⁴` per sample on a vibrometer's speckle, `docs/spikes.md`)
    /// are replaced too, which puts the local prediction in place of an ordinary noisy sample.
    pub const FEW_ONE_IN: usize = 1000;

    /// Whether `spikes` in a record of `samples` are few: at most `⌈samples / FEW_ONE_IN⌉`.
    pub fn few(spikes: usize, samples: usize) -> bool {
        spikes <= samples.div_ceil(Self::FEW_ONE_IN)
    }

    /// The smallest size of a spike that [`SpikePolicy::RepairFew`] replaces: one that a lone
    /// sample decides by, larger than the record's own motion from one sample to the next (the
    /// 99th percentile of its steps, wrapped on the circle), and on the circle any of a quarter
    /// turn or more (a jump the unwrapping may take for a turn). A bit error of the count's upper
    /// bits, a vibrometer's dropout, is far larger than the motion between two samples; on a
    /// clean record of fast motion (a whirling double pendulum at 64 samples per period) the
    /// spike test flags runs of samples a few hundredths of a radian off the cubic where the
    /// motion turns sharply, well inside its steps of tenths of a radian, and a repair there
    /// would move true samples: those are kept and warned of.
    pub fn decisive(x: &[f64], pieces: &[Range<usize>], domain: Domain) -> f64 {
        let mut steps: Vec<f64> = pieces
            .iter()
            .flat_map(|r| {
                x[r.clone()].windows(2).map(move |w| match domain {
                    Domain::Circle => circle_signal::wrap(w[1] - w[0]).abs(),
                    Domain::Line => (w[1] - w[0]).abs(),
                })
            })
            .filter(|v| v.is_finite())
            .collect();
        let fastest = if steps.is_empty() {
            0.0
        } else {
            let k = ((steps.len() - 1) as f64 * 0.99).round() as usize;
            *steps.select_nth_unstable_by(k, f64::total_cmp).1
        };
        match domain {
            Domain::Circle => fastest.min(std::f64::consts::FRAC_PI_2),
            Domain::Line => fastest,
        }
    }
}

/// Finds the isolated spikes (bit errors) of every piece and replaces them as the policy says
/// ([`SpikePolicy`]; every one with [`PrepareOptions::repair`]), counting them over the whole
/// record. Pieces too short for the test are left as they are. A record rounded to a quantum (an
/// encoder's counts) is tested with the floor of that quantum ([`SpikeParams::with_quantum`]):
/// near rest such a record toggles between two counts, and without the floor each toggle is a
/// spike (and a repair next to a half-turn bit error can take the wrong sample).
fn spikes(
    x: &mut [f64],
    pieces: &[Range<usize>],
    grid: Option<(f64, f64)>,
    options: &PrepareOptions,
) -> Result<Vec<Note>, PrepareError> {
    let params = match quantum(x, pieces, options.signal) {
        Some(q) => SpikeParams::default()
            .with_quantum(q)
            .map_err(PrepareError::Spikes)?,
        None => SpikeParams::default(),
    };
    let policy = if options.repair {
        SpikePolicy::Repair
    } else {
        options.spikes
    };
    let mut found: Vec<Spike> = Vec::new();
    let mut searched = 0;
    for r in pieces.iter().filter(|r| r.len() >= SpikeParams::MIN_SAMPLES) {
        let piece = &mut x[r.clone()];
        searched += piece.len();
        let spikes = if policy == SpikePolicy::Repair {
            find_and_repair_spikes(piece, options.signal, &params)
        } else {
            find_spikes_in_place(piece, options.signal, &params)
        }
        .map_err(PrepareError::Spikes)?;
        found.extend(spikes.iter().map(|s| Spike {
            index: s.index + r.start,
            ..*s
        }));
    }
    let note = |found: Vec<Spike>, repaired: bool| Note::Spikes {
        coordinate: 0,
        found,
        repaired,
        domain: options.signal,
        policy,
        grid,
    };
    Ok(match policy {
        SpikePolicy::Repair | SpikePolicy::Keep => {
            let repaired = policy == SpikePolicy::Repair;
            (!found.is_empty())
                .then(|| note(found, repaired))
                .into_iter()
                .collect()
        }
        SpikePolicy::RepairFew => {
            // Only the spikes a lone sample would decide by (a jump the unwrapping or the fit
            // takes for motion), and only when they are few.
            // (Nothing to split when nothing was found: the percentile of every step is spared.)
            let decisive = if found.is_empty() {
                0.0
            } else {
                SpikePolicy::decisive(x, pieces, options.signal)
            };
            let (mut replaced, mut kept): (Vec<Spike>, Vec<Spike>) =
                found.into_iter().partition(|s| s.size.abs() >= decisive);
            if !SpikePolicy::few(replaced.len(), searched) {
                kept.append(&mut replaced);
                kept.sort_by_key(|s| s.index);
            }
            for s in &replaced {
                x[s.index] = s.replacement;
            }
            [(replaced, true), (kept, false)]
                .into_iter()
                .filter(|(f, _)| !f.is_empty())
                .map(|(f, repaired)| note(f, repaired))
                .collect()
        }
    })
}

/// The quantum a record is rounded to (an encoder's count, a converter's least step): the
/// smallest step between successive samples (on the circle wrapped into `[-π, π)`), when every
/// step is a whole multiple of it to within a hundredth of it (a record printed to fewer
/// decimals than its quantum has still rounded it); `None` when the record moves by less
/// (unquantised) or not at all.
fn quantum(x: &[f64], pieces: &[Range<usize>], domain: Domain) -> Option<f64> {
    let steps = || {
        pieces.iter().flat_map(move |r| {
            x[r.clone()].windows(2).map(move |w| match domain {
                Domain::Circle => circle_signal::wrap(w[1] - w[0]).abs(),
                Domain::Line => (w[1] - w[0]).abs(),
            })
        })
    };
    let scale = pieces
        .iter()
        .flat_map(|r| x[r.clone()].iter())
        .fold(0.0_f64, |a, v| a.max(v.abs()));
    // Steps below this are rounding of the printed values, not a quantum.
    let noise = 1e-9 * scale.max(f64::MIN_POSITIVE);
    let q = steps().filter(|&s| s > noise).fold(f64::INFINITY, f64::min);
    (q.is_finite() && steps().all(|s| s <= noise || ((s / q) - (s / q).round()).abs() <= 0.01)).then_some(q)
}

impl GridData {
    /// The record's clock with the period of `source` as the windows' unit, the record resampled
    /// onto a whole number of samples per period when needed.
    pub fn with_period(self, source: PeriodSource) -> Result<Data, PrepareError> {
        let GridData {
            t0,
            dt,
            x,
            pieces,
            domain,
            others,
            drives,
            velocities,
            bridged,
            ..
        } = self;
        let (period, found) = match source {
            PeriodSource::Given(t) => (t, DriveFound::Given),
            PeriodSource::Estimated { period, uncertainty } => {
                (period, DriveFound::Estimated { uncertainty })
            }
            PeriodSource::Free => {
                let longest = circle_signal::longest_piece(&pieces);
                let samples = circle_signal::oscillation_period(&x[longest], domain)
                    .map_err(PrepareError::FreePeriod)?;
                let whole = samples.round().max(2.0);
                (whole * dt, DriveFound::Free { samples })
            }
            PeriodSource::Windows(unit) => {
                let samples = match unit {
                    WindowUnit::Time(length) if (length / dt).round() < 2.0 => {
                        return Err(PrepareError::WindowTooShort { length, dt });
                    }
                    WindowUnit::Time(length) => (length / dt).round().min(1e12) as usize,
                    WindowUnit::Samples(n) => n.max(2),
                };
                (samples as f64 * dt, DriveFound::Windows { samples })
            }
        };
        if !(period.is_finite() && period > 0.0) {
            return Err(InputError::BadDrivePeriod { period }.into());
        }
        let clock = SampleClock::from_step(period, dt)
            .and_then(|c| c.with_start_time(t0))
            .map_err(PrepareError::Clock)?;
        // The coordinates, measured drives and velocities on one grid: resampled together (a
        // drive or velocity as a signal on the line), the kernel's weights once for them all,
        // onto the same pieces.
        let (out_clock, x, out_pieces, resampled_from, others, drives, velocities) =
            match clock.whole_samples_per_period() {
                Some(_) => (clock, x, pieces, None, others, drives, velocities),
                None => {
                    let (n_others, n_drives) = (others.len(), drives.len());
                    let other_domains: Vec<Domain> = others.iter().map(|c| c.domain).collect();
                    let columns: Vec<(Vec<f64>, Domain)> = std::iter::once((x, domain))
                        .chain(others.into_iter().map(|c| (c.x, c.domain)))
                        .chain(drives.into_iter().map(|p| (p, Domain::Line)))
                        .chain(velocities.into_iter().map(|v| (v, Domain::Line)))
                        .collect();
                    let r = resample_columns(columns, &pieces, &clock).map_err(PrepareError::Resample)?;
                    let mut columns = r.columns.into_iter();
                    let x = columns.next().unwrap_or_default();
                    let others = other_domains
                        .into_iter()
                        .zip(columns.by_ref().take(n_others))
                        .map(|(domain, x)| Channel { x, domain })
                        .collect();
                    let drives = columns.by_ref().take(n_drives).collect();
                    let velocities = columns.collect();
                    (
                        r.clock,
                        x,
                        r.pieces,
                        Some(clock.samples_per_period()),
                        others,
                        drives,
                        velocities,
                    )
                }
            };
        let (clock, pieces) = (out_clock, out_pieces);
        let p = clock.require_whole().map_err(PrepareError::Whole)?;
        // A bridged stretch's samples on the new clock: every one from the sample before its
        // first to the one after its last (the resampling's kernel reads the stretch there).
        let bridged = match resampled_from {
            None => bridged,
            Some(_) => {
                let (step, start, len) = (clock.step(), clock.start_time(), x.len());
                bridged
                    .iter()
                    .map(|b| {
                        let (a, z) = (t0 + b.start as f64 * dt, t0 + (b.end - 1) as f64 * dt);
                        let first = ((a - start) / step).floor().max(0.0) as usize;
                        let last = ((z - start) / step).ceil().max(0.0) as usize;
                        first.min(len)..(last + 1).min(len)
                    })
                    .filter(|r| !r.is_empty())
                    .collect()
            }
        };
        Ok(Data {
            clock,
            p,
            x,
            pieces,
            domain,
            drive: found,
            resampled_from,
            others,
            drives,
            velocities,
            bridged,
        })
    }
}

/// A spike's size with four decimals, or in scientific notation where those would show it as
/// zero (`+0.0123`, `-3.2e-5`).
/// The flagged samples (increasing) in groups of consecutive ones: how many stand alone, how
/// many groups are runs of two or more, and the longest run.
fn groups(found: &[Spike]) -> (usize, usize, usize) {
    let (mut isolated, mut runs, mut longest) = (0, 0, 0);
    let mut k = 0;
    while k < found.len() {
        let mut end = k + 1;
        while end < found.len() && found[end].index == found[end - 1].index + 1 {
            end += 1;
        }
        match end - k {
            1 => isolated += 1,
            len => {
                runs += 1;
                longest = longest.max(len);
            }
        }
        k = end;
    }
    (isolated, runs, longest)
}

fn signed_size(size: f64) -> String {
    if size != 0.0 && size.abs() < 5e-5 {
        format!("{size:+.1e}")
    } else {
        format!("{size:+.4}")
    }
}
