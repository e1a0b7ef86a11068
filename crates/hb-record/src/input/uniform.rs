//! The checks a record must pass before identification: time stamps on a uniform grid
//! `t0 + n · dt`, split into pieces at gaps, isolated glitches repaired on request, and a report
//! of how far the stamps are from the grid ([`GridReport`]). (The forcing period need not be a
//! whole number of steps: the command line resamples the record once,
//! `circle_signal::resample_pieces`.)
//!
//! The samples of a record are taken on an even grid; the clock that stamps them need not be
//! even. A logger's clock rounds to the decimals it prints, may jitter, and may slip: runs of
//! thousands of stamps one printed unit off the grid, with single steps one unit short or long
//! where the clock slips (at 500 Hz printed to 1 ms, steps of 1 and 3 ms among the 2 ms ones).
//! The fit finds the grid behind such a clock: it follows the clock's local offset from the grid
//! (its "level", the median deviation of the neighbouring stamps), accepts every stamp near its
//! level, and reports what it found: the step, the deviations from the grid, the jitter about
//! the level, and the slips of the level.
//!
//! The grid is fitted in five steps, each robust to what the previous one could not see:
//!
//! 1. a first step, the median of the steps (at most 100 001 of them, evenly spread);
//! 2. the step refined as the mean of the "single" steps (within half a step of the estimate,
//!    a slip of half a step included), until it settles; runs of single steps telescope, so the
//!    rounding of the stamps inside a run cancels;
//! 3. the runs of single steps linked into one index sequence (the gap between two runs rounded
//!    to whole steps), and a least-squares line fitted to their stamps;
//! 4. every stamp indexed by the line (`n = round((t − t0) / dt)`) and the line fitted again to
//!    the stamps less than half a step from their grid time, until it no longer changes: the
//!    line stays among the levels of a slipping clock rather than on the most common one;
//! 5. the clock's level at each stamp: the median deviation from the line of the
//!    [`LEVEL_WINDOW`] stamps that end at it or of those that start at it, whichever is nearer
//!    its own deviation (so that a stamp beside a slip takes the level of its own side); the
//!    scatter of the stamps about their levels (robust standard deviation); and the line fitted
//!    again to the stamps that fit, until it no longer changes. (When every stamp is within
//!    0.6 of a printed unit of the line, or a millionth of a step without a printed resolution,
//!    or no run of [`LEVEL_WINDOW`] stamps has its median deviation half the smallest slip off
//!    the line, no slip can hide among them: the levels are 0 and are not computed.)
//!
//! Then each stamp is judged against the final line: it fits when it is within the tolerance of
//! its level (see below) and less than half a step from its grid time; it is in place when its
//! "index level" `n − i` (grid index less position) does not go down from the previous good
//! stamp's, and does not stand above the index level of the stamps that follow. An index level
//! going up is a gap; any other stamp is a glitch.
//!
//! # A logger's unsettled start or end
//!
//! A data-acquisition loop often takes its first few samples (or its last) at another rate than
//! the rest, before it settles: the DFKI double pendulum's records start with 4 to 6 steps of 1.4
//! to 1.9 steps, then run at 500 Hz for 10 s. Those samples were not taken on the grid, so no
//! grid time is theirs: repaired, they would move by up to half a step; kept as a piece of their
//! own, they would be on the grid all the same. They are left out, and said to be
//! ([`Unsettled`], in [`GridRecord::unsettled`]). The rest of the record begins at the first four
//! stamps that fit one step apart and ends at the last four (a loop not at its rate puts a stamp
//! on the grid by chance, not four one step apart); what lies before (or after) it is an
//! unsettled run when its stamps increase, into the rest too (a stamp repeated or going
//! backwards is a clock's glitch, not a rate), and it holds a glitch that is not isolated. A
//! single stamp off the grid at an end is an isolated glitch, as anywhere, and a record that fits
//! with or without repair is fitted as it always was: only a record refused until now has a run
//! left out. A run of at most [`UNSETTLED_FRACTION`] of the samples and at most
//! [`UNSETTLED_MAX`] is left out and the rest fitted on its own, as a record without those
//! samples would be (its glitches named or repaired, its gaps split); a longer one is refused,
//! [`InputError::TimeUnsettled`], naming it.
//!
//! # Tolerances, and what is refused
//!
//! - A stamp fits when it is within [`GRID_TOLERANCE`] (a quarter of a step) or a printed unit
//!   (at most half a step) of its level, or within a quarter step of its grid time. When the stamps scatter about their levels by more than their printing
//!   explains (robust standard deviation σ above 0.74 printed unit, the most that rounding gives),
//!   the tolerance about the level is [`JITTER_SIGMAS`] σ, at least a quarter and at most half a
//!   step, so that the tails of a jitter are not taken for glitches (in records of at least
//!   [`JITTER_MIN_STAMPS`] stamps).
//! - No stamp is ever half a step or more from its grid time: its index would be in doubt.
//!   A clock whose levels span more than that (slips both ways from the grid at a resolution of
//!   half a step, or a long slip of half a step or more) is refused, as is a slip that coincides
//!   with a gap when it could as well be a missing sample (at a resolution of half a step).
//! - More than 5 % of the stamps (and at least 3) more than a quarter step (or a printed unit)
//!   from their level or repeated: the stamps do not resolve the samples ([`InputError::TimeUnresolved`], with the
//!   scatter). A jitter of 10 % of the step (RMS, normal) puts 1.2 % of the stamps beyond a
//!   quarter step and is accepted; one of 30 % puts 40 % there and is refused.
//! - A run of stamps at an end of the record off the grid of the rest, as a logger's before it
//!   settles, longer than [`UNSETTLED_FRACTION`] of the samples or [`UNSETTLED_MAX`]
//!   ([`InputError::TimeUnsettled`]); a run so long that its stamps off the grid are more than
//!   5 % of the record's is [`InputError::TimeUnresolved`], as above.
//! - A level that holds for fewer than half of [`LEVEL_WINDOW`] stamps is not a slip: those
//!   stamps are glitches, repaired only when isolated.
//! - A slip is reported where a stamp's level moves from the mean level since the last slip by
//!   half a printed unit or more (by 3 σ or more when the stamps jitter beyond their printing),
//!   and by at least a hundredth of a step.
//!
//! # What is reported
//!
//! [`GridReport`], in [`GridRecord::report`]: the step, the resolution of the stamps, their
//! largest and RMS deviation from their grid times, their largest and RMS deviation from their
//! levels (rounding and jitter), and the slips of the level (where, by how much). A front end
//! shows it when [`GridReport::is_notable`] (slips, or deviations beyond the printing), as a
//! warning when [`GridReport::is_warning`]: the stamps jitter by more than [`JITTER_WARNING`] of
//! the step (RMS). The samples are placed on the grid either way; if they were taken at their
//! stamps instead, that moves them by the reported deviations, which act on the record as noise
//! of the deviation times the signal's rate of change: at 5 % of the step (RMS) and 25 samples
//! per period of a harmonic, about 1.3 % of its amplitude.

use super::error::Rounded;
use super::{InputError, Location, Record, StampFault, median, printed_decimals, round};

/// Largest distance of a time stamp from its level (the clock's local offset from the grid), in
/// steps, for it to fit when the stamps do not jitter beyond their printing.
///
/// A quarter of a step: it covers stamps printed with a resolution up to half a step (a DAQ at
/// 2048 Hz printing 4 decimals is off by up to a tenth of a step) plus the jitter of a clock.
pub const GRID_TOLERANCE: f64 = 0.25;

/// The tolerance of a jittering clock about its level, in robust standard deviations of the
/// stamps about their levels (when that is above what rounding gives): at most 2e-9 of
/// the stamps of a normal jitter lie further.
pub const JITTER_SIGMAS: f64 = 6.0;

/// The fewest stamps whose scatter about their levels sets a jitter's tolerance: the robust
/// standard deviation of fewer is uncertain by more than 15 %, and one glitch among them moves the
/// line they are measured from.
pub const JITTER_MIN_STAMPS: usize = 100;

/// The RMS deviation of the stamps from their levels, as a fraction of the step, above which
/// [`GridReport::is_warning`]: 5 %, noise of about 1.3 % of the amplitude of a harmonic sampled
/// 25 times a period if the samples were taken at their stamps.
pub const JITTER_WARNING: f64 = 0.05;

/// A stamp's level is the median deviation from the grid of this many stamps, those that end at
/// it or those that start at it: a level that holds for more than half as many stamps is a slip
/// of the clock, one that holds for fewer is a run of glitches.
pub const LEVEL_WINDOW: usize = 33;

/// The most samples left out at each end of a record as a logger's unsettled run (see
/// [`Unsettled`]), as a fraction of the record's samples: whatever is left out, the record left
/// is the record, 99 % of it.
pub const UNSETTLED_FRACTION: f64 = 0.01;

/// The most samples left out at each end of a record as a logger's unsettled run, however long
/// the record (see [`UNSETTLED_FRACTION`]): a loop settles to its rate within a few dozen
/// cycles (the DFKI double pendulum's within 6, at 500 Hz); a longer stretch at another rate is
/// a part of the record to look at, not a start to drop.
pub const UNSETTLED_MAX: usize = 50;

/// The fewest stamps, one step apart and each fitting the grid, that begin (or end) the settled
/// rest of a record. A logger not yet at its rate puts a stamp near the grid by chance, and the
/// next one too at times, but its steps are not one step: two stamps that fit one step apart
/// are rare, four in a row a logger at its rate.
const SETTLED_STAMPS: usize = 4;

/// More stamps than this fraction of the record (and at least [`UNRESOLVED_MIN`]) off their
/// level or repeated are not glitches: the stamps do not resolve the samples.
const UNRESOLVED_FRACTION: f64 = 0.05;

/// See [`UNRESOLVED_FRACTION`].
const UNRESOLVED_MIN: usize = 3;

/// Steps, evenly spread, whose median is the first estimate of the step; also the stamps whose
/// deviations give the scatter about the levels.
const MEDIAN_STEPS: usize = 100_001;

/// The largest grid index a stamp may have (from the first stamp of the first run).
const MAX_INDEX: f64 = (1u64 << 52) as f64;

/// Refits of the line before it is taken as it stands.
const MAX_REFITS: usize = 50;

/// A step is single within half a step of the grid's and this fraction of a step more: the
/// rounding of the numbers themselves, so that a slip of half a step (a step of 1 or 3 ms at
/// 500 Hz) stays single whichever way the subtraction rounds.
const SINGLE_SLACK: f64 = 1e-6;

/// The smallest change of level reported as a slip, as a fraction of the step (also at least
/// half a printed unit, or [`SLIP_SIGMAS`] times the scatter of a jitter, above the noise of a
/// median of [`LEVEL_WINDOW`] stamps).
const SLIP_FLOOR: f64 = 0.01;

/// See [`SLIP_FLOOR`]: a median of 33 normal deviates scatters by 0.22 σ.
const SLIP_SIGMAS: f64 = 3.0;

/// Every stamp within this many printed units of the line (or [`NO_LEVELS_UNROUNDED`] of a step
/// when the stamps have no printed resolution): the levels are 0, not computed.
const NO_LEVELS_UNITS: f64 = 0.6;

/// See [`NO_LEVELS_UNITS`].
const NO_LEVELS_UNROUNDED: f64 = 1e-6;

/// A stamp within a printed unit of its level (and this little more, for the arithmetic) fits:
/// the rounding of the stamp and of its level, where the rounding error of a clock whose step is
/// not a whole number of units moves by a unit at once.
const PRINTED_UNITS: f64 = 1.001;

/// The robust standard deviation of a normal sample: the median absolute deviation times this.
const MAD_TO_SIGMA: f64 = 1.482_602_218_505_602;

/// The most other glitches an error names.
const GLITCHES_NAMED: usize = 5;

/// A glitch beside a gap is repaired onto the free grid slot its stamp is nearest when within
/// this many steps of it (from the slot's time, and from its level where the clock slips): the
/// next nearest slot is then at least 0.6 steps away, so that the slot is not in doubt.
const NEAREST_SLOT: f64 = 0.4;

/// A record whose gaps make its grid more than this many times its samples, and more than
/// [`GAP_MISSING_ALLOWED`] steps longer, is refused ([`InputError::GapTooLong`]): every stage
/// holds the grid, NaN in the gaps, so a stamp far off the others would take all memory.
pub const GAP_GRID_FACTOR: usize = 4;

/// Grid steps a record's gaps may hold in all whatever its length (see [`GAP_GRID_FACTOR`]).
pub const GAP_MISSING_ALLOWED: usize = 1 << 24;

/// How to fit a record's time stamps to a grid.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct GridOptions {
    /// Replace each isolated glitch (a stamp off its level, repeated or going backwards, whose
    /// neighbours on both sides fit the grid one step away) by its grid time, and report it in
    /// [`GridRecord::repaired`]. Without it, such a stamp is an error.
    pub repair: bool,
}

/// A time stamp replaced by its grid time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimeRepair {
    /// Where the stamp is.
    pub at: Location,
    /// The stamp as read.
    pub was: f64,
    /// Its grid time.
    pub now: f64,
}

/// Which end of a record.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RecordEnd {
    /// Its first samples.
    Start,
    /// Its last samples.
    End,
}

impl RecordEnd {
    /// `first` or `last`, as the texts name the samples at this end.
    pub fn which(self) -> &'static str {
        match self {
            RecordEnd::Start => "first",
            RecordEnd::End => "last",
        }
    }
}

/// A run of samples at an end of a record whose time stamps do not fit the grid of the rest: a
/// data-acquisition loop not yet at its rate when it started (or no longer at it as it
/// stopped), its steps longer or shorter than the grid's. Its samples were not taken on the
/// grid, so no grid time is theirs: they are left out of the record (not repaired, which would
/// move them by up to half a step, nor kept as a piece, which would put them on the grid all the
/// same), and a front end says so.
///
/// A run is left out when it is at most [`UNSETTLED_FRACTION`] of the record's samples and at
/// most [`UNSETTLED_MAX`], its stamps increase, and it holds a glitch that could not be repaired
/// (one stamp off the grid at an end, its neighbour fitting, is an isolated glitch, as
/// anywhere): so it holds at least two samples, and a record that fits without it (with or
/// without repair) is fitted as it always was. Longer, it is [`InputError::TimeUnsettled`].
#[derive(Debug, Clone, PartialEq)]
pub struct Unsettled {
    /// Which end of the record.
    pub end: RecordEnd,
    /// The samples left out, counted from 0 in the record as read.
    pub samples: std::ops::Range<usize>,
    /// Where its first sample is.
    pub first: Location,
    /// Where its last sample is.
    pub last: Location,
    /// The time stamp of its first sample.
    pub from: f64,
    /// The time stamp of its last sample.
    pub to: f64,
    /// The shortest step between its stamps, the step to the rest's nearest stamp included.
    pub shortest: f64,
    /// The longest such step.
    pub longest: f64,
    /// The step of the grid of the rest.
    pub step: f64,
}

/// What was left out and why, without the options of a front end.
impl std::fmt::Display for Unsettled {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let why = match self.end {
            RecordEnd::Start => "a logger settling to its rate",
            RecordEnd::End => "a logger leaving its rate as it stops",
        };
        write!(
            f,
            "the {} {} samples ({} to {}, t = {} to {}) are left out: their time stamps are {} to {} steps of {} \
             apart, off the grid of the rest ({why})",
            self.end.which(),
            self.samples.len(),
            self.first,
            self.last,
            self.from,
            self.to,
            Rounded(self.shortest / self.step).digits(2),
            Rounded(self.longest / self.step).digits(2),
            Rounded(self.step).digits(6),
        )
    }
}

/// A run of samples without gaps.
#[derive(Debug, Clone, PartialEq)]
pub struct Piece {
    /// The grid index of its first sample: that sample is at `t0 + first · dt`.
    pub first: usize,
    /// The samples, one step apart.
    pub samples: Vec<f64>,
}

/// A change of the level of the clock that stamps a record: from this stamp on, the stamps sit
/// `by` further from their grid times (negative: earlier) than before it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slip {
    /// The first stamp at the new level.
    pub at: Location,
    /// The change of level, in the record's time unit.
    pub by: f64,
}

/// How the time stamps of a record sit on its grid: what [`GridRecord::fit`] found (see the
/// module docs). Deviations are stamp less grid time, over the stamps kept (repaired ones
/// aside), in the record's time unit.
#[derive(Debug, Clone, PartialEq)]
pub struct GridReport {
    /// The grid's step.
    pub step: f64,
    /// The resolution the stamps are written with (`10^−k` for `k` decimals), when they are all
    /// written with at most 9 decimals.
    pub resolution: Option<f64>,
    /// The largest deviation of a stamp from its grid time (signed).
    pub max_deviation: f64,
    /// Where that stamp is.
    pub max_at: Location,
    /// The root mean square of the deviations from the grid times.
    pub rms_deviation: f64,
    /// The largest deviation of a stamp from its level, the clock's local offset (signed):
    /// rounding and jitter, the slips aside.
    pub max_jitter: f64,
    /// The root mean square of the deviations from the levels.
    pub rms_jitter: f64,
    /// The slips of the clock's level, in order.
    pub slips: Vec<Slip>,
}

impl GridReport {
    /// The largest deviation from the grid, as a fraction of the step.
    pub fn max_fraction(&self) -> f64 {
        self.max_deviation.abs() / self.step
    }

    /// The RMS deviation from the grid, as a fraction of the step.
    pub fn rms_fraction(&self) -> f64 {
        self.rms_deviation / self.step
    }

    /// The RMS deviation from the levels (the jitter), as a fraction of the step.
    pub fn jitter_fraction(&self) -> f64 {
        self.rms_jitter / self.step
    }

    /// Whether every stamp is within one printed unit of its level (and of its grid time when
    /// the clock does not slip): the deviations are the printing's.
    pub fn within_printing(&self) -> bool {
        // A thousandth of a unit for the arithmetic of the fit, and a millionth of a step where
        // no resolution is known (stamps computed in floating point).
        let unit = self.resolution.map_or(1e-6 * self.step, |u| u * 1.001);
        self.max_jitter.abs() <= unit && (!self.slips.is_empty() || self.max_deviation.abs() <= unit)
    }

    /// Whether the report is worth showing: the clock slips, or the stamps deviate by more than
    /// their printing explains.
    pub fn is_notable(&self) -> bool {
        !self.slips.is_empty() || !self.within_printing()
    }

    /// Whether the report is a warning: the stamps jitter about their levels by more than
    /// [`JITTER_WARNING`] of the step (RMS), beyond their printing.
    pub fn is_warning(&self) -> bool {
        !self.within_printing() && self.jitter_fraction() > JITTER_WARNING
    }
}

/// A fraction as a percentage with two significant digits (at least one decimal below 10 %).
struct Percent(f64);

impl std::fmt::Display for Percent {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let p = 100.0 * self.0;
        if p >= 10.0 {
            write!(f, "{p:.0} %")
        } else if p >= 0.1 {
            write!(f, "{p:.1} %")
        } else {
            write!(f, "{:.1e} %", p)
        }
    }
}

/// What the fit found, in a sentence without the options of a front end: the deviations from the
/// grid, the slips of the clock (the first five), and whether the printing explains them.
impl std::fmt::Display for GridReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the time stamps deviate from the even grid of step {} by up to {} of the step (RMS {})",
            Rounded(self.step).digits(6),
            Percent(self.max_fraction()),
            Percent(self.rms_fraction())
        )?;
        if !self.slips.is_empty() {
            let list: Vec<String> = self
                .slips
                .iter()
                .take(5)
                .map(|s| {
                    format!(
                        "{} ({}{})",
                        s.at,
                        if s.by > 0.0 { "+" } else { "" },
                        Rounded(s.by).digits(3)
                    )
                })
                .collect();
            let more = if self.slips.len() > 5 { ", ..." } else { "" };
            write!(
                f,
                "; the clock that stamps them slips {} time(s), at {}{more}",
                self.slips.len(),
                list.join(", ")
            )?;
        }
        let printing = match self.resolution {
            Some(u) => format!("their printed resolution of {}", Rounded(u)),
            None => "the rounding of the numbers".to_owned(),
        };
        if self.within_printing() {
            write!(f, "; about their clock they are within {printing}")
        } else {
            write!(
                f,
                "; about their clock they scatter by up to {} of the step (RMS {}), more than {printing} explains",
                Percent(self.max_jitter.abs() / self.step),
                Percent(self.jitter_fraction())
            )
        }?;
        f.write_str("; the samples are placed on the grid")?;
        if self.is_warning() {
            f.write_str(", which moves them by as much if they were taken at their stamps")?;
        }
        Ok(())
    }
}

/// A record on a uniform time grid `t0 + n · dt`, in pieces separated by gaps (missing samples).
#[derive(Debug, Clone, PartialEq)]
pub struct GridRecord {
    /// Time of the first sample (its grid time, the stamp as fitted).
    pub t0: f64,
    /// Sampling step.
    pub dt: f64,
    /// The pieces, in order; the first starts at index 0, and each next one at least two steps
    /// after the end of the previous one. A single piece when there is no gap.
    pub pieces: Vec<Piece>,
    /// The stamps replaced by their grid time, in order (empty unless repair was asked for).
    pub repaired: Vec<TimeRepair>,
    /// How the stamps sit on the grid: deviations, jitter, slips of the clock.
    pub report: GridReport,
    /// The runs of samples left out at the ends of the record, stamped before the logger settled
    /// to its rate or after it left it, in order (empty when there is none).
    pub unsettled: Vec<Unsettled>,
}

impl GridRecord {
    /// Fits the record's time stamps to a uniform grid (see the module docs), splits it at gaps,
    /// leaves out a logger's unsettled run at either end ([`Unsettled`]), repairs isolated
    /// glitches if asked, and reports how the stamps sit on the grid.
    ///
    /// Errors: fewer than 2 samples; time decreasing in most steps; stamps that do not resolve
    /// the samples ([`InputError::TimeUnresolved`]); an unsettled run too long to leave out
    /// ([`InputError::TimeUnsettled`]); a glitch not repaired ([`InputError::TimeGlitch`]), the
    /// first in the record, naming the others.
    pub fn fit(record: Record, options: &GridOptions) -> Result<Self, InputError> {
        // Every debug build (the tests' too) checks that the pass over a record on its own
        // indices gives what the general passes give, bit for bit.
        #[cfg(debug_assertions)]
        let general = Self::fit_from(record.clone(), options, 0, true, false);
        let fitted = Self::fit_from(record, options, 0, true, true);
        #[cfg(debug_assertions)]
        assert_eq!(
            format!("{fitted:?}"),
            format!("{general:?}"),
            "the grid fit of a record on its own indices"
        );
        fitted
    }

    /// [`GridRecord::fit`] of the samples of a record as read from its sample `before` on (for
    /// the samples without a line, named by their place in the record as read), leaving out
    /// unsettled runs at the ends when `settle`; `quick` lets a record whose stamps all lie on
    /// their own indices take one pass instead of several ([`OwnIndices`], the same result).
    fn fit_from(
        record: Record,
        options: &GridOptions,
        before: usize,
        settle: bool,
        quick: bool,
    ) -> Result<Self, InputError> {
        let Record {
            t,
            theta,
            lines,
            missing,
            ..
        } = record;
        let n = t.len();
        if n < 2 {
            return Err(InputError::TooFewSamples { found: n, needed: 2 });
        }
        let at = |i: usize| match lines.as_ref().and_then(|lines| lines.get(i)) {
            Some(&line) => Location::Line(line),
            None => super::sample_location(&missing, before + i),
        };
        let decimals = printed_decimals(&[&t]);
        let unresolved = |off: usize, scatter: Option<f64>| InputError::TimeUnresolved {
            off,
            total: n,
            decimals,
            scatter,
        };

        let dt0 = first_step(&t);
        if dt0.is_nan() || dt0 <= 0.0 {
            if dt0 == 0.0 {
                return Err(unresolved(t.windows(2).filter(|w| w[1] == w[0]).count(), None));
            }
            let i = (1..n).find(|&i| t[i] <= t[i - 1]).unwrap_or(1);
            return Err(InputError::TimeNotIncreasing {
                at: at(i),
                t: t[i],
                previous: t[i - 1],
            });
        }
        let (dt, runs) = refine_step(&t, dt0);
        let Some(&(start, _)) = runs.first() else {
            return Err(unresolved(n, None));
        };
        let origin = t[start];
        let tau = |i: usize| t[i] - origin;
        let starts = link(&t, &runs, dt);
        // Whether `line` is the least-squares line through `(i, τ_i)` of every sample, in order
        // (the record one run of single steps, its first sample at index 0). A refit whose
        // indices are `0, 1, …, n − 1` again makes the same sums in the same order, so gives
        // `line` back: it is not made.
        let mut through_all = runs == [(0, n - 1)] && starts == [0.0];
        let mut line = least_squares(|| {
            runs.iter()
                .zip(&starts)
                .flat_map(|(&(s, e), &k)| (s..=e).map(move |i| (k + (i - s) as f64, tau(i))))
        })
        .ok_or_else(|| unresolved(n, None))?;
        // A record whose every stamp lies less than half a step from the grid time of its own
        // index (the common case): the refits give the line back, and what the passes below
        // measure of each stamp is its deviation from that line, found here in one pass.
        let own = (quick && through_all)
            .then(|| OwnIndices::of(n, &tau, line))
            .flatten();
        // Every stamp less than half a step from its grid time: the line among the levels.
        // (Each refit's indices are found once, for both of its passes.)
        let mut indices = Vec::new();
        for _ in 0..MAX_REFITS {
            if own.is_some() {
                // The refit's indices are `0, 1, …, n − 1`, as the line's: the same line.
                break;
            }
            let next = least_squares_indexed(n, &tau, &mut indices, line, &mut through_all, |i| {
                let k = line.index(tau(i));
                line.indexable(k, tau(i)).then_some(k)
            });
            let Some(next) = next else {
                break;
            };
            match next {
                Refit::Line(next) if next != line => line = next,
                _ => break,
            }
        }
        if !(line.b.is_finite() && line.b > 0.0) {
            return Err(unresolved(n, None));
        }

        // The clock's level at each stamp, against this line; the scatter about the levels and
        // the tolerance it sets. A stamp's deviation from its level does not depend on the line
        // it is indexed by, so the levels are found once.
        let base = line;
        let deviation = |i: usize| {
            let k = base.index(tau(i));
            tau(i) - base.at(k)
        };
        let resolution = decimals.map(|k| 10f64.powi(-(k as i32)));
        let unit = resolution.unwrap_or(0.0);
        let stride = n.div_ceil(MEDIAN_STEPS).max(1);
        // The robust standard deviation of the stamps about `level` (over at most 100 001 of
        // them, evenly spread), and whether rounding alone cannot give it: rounding puts half the
        // stamps within half a unit of their level at most.
        let scatter_about = |level: &dyn Fn(usize) -> f64| {
            let mut spread: Vec<f64> = (0..n)
                .step_by(stride)
                .filter_map(|i| {
                    let k = base.index(tau(i));
                    base.indexable(k, tau(i)).then(|| (deviation(i) - level(i)).abs())
                })
                .collect();
            MAD_TO_SIGMA * median(&mut spread).unwrap_or(0.0)
        };
        let jitter = |scatter: f64| scatter > MAD_TO_SIGMA * 0.5 * unit;
        let slip_threshold = |scatter: f64| {
            if jitter(scatter) {
                SLIP_SIGMAS * scatter
            } else {
                0.5 * unit
            }
            .max(SLIP_FLOOR * base.b)
        };
        // Levels only where a slip can be: some stamp beyond the rounding of the line, and some
        // window of stamps whose median is half a slip off it.
        let flat_scatter = scatter_about(&|_| 0.0);
        let plain = resolution.map_or(NO_LEVELS_UNROUNDED * base.b, |u| NO_LEVELS_UNITS * u);
        let beyond_plain = match &own {
            Some(own) => own.largest.abs() > plain,
            None => (0..n).any(|i| {
                let d = deviation(i).abs();
                d.is_nan() || d > plain
            }),
        };
        let levels = (beyond_plain && windows_depart(n, &deviation, 0.5 * slip_threshold(flat_scatter)))
            .then(|| levels(n, &deviation));
        let level = |i: usize| levels.as_ref().map_or(0.0, |l| l.own[i]);
        // A stamp's deviation from its level, indexed `k` on `line`: against the line the levels
        // were found on, where there are levels; against `line` itself, where they are all 0.
        let off_level = |line: Line, k: f64, i: usize| match &levels {
            Some(levels) => tau(i) - base.at(k) - levels.own[i],
            None => tau(i) - line.at(k),
        };
        let scatter = match levels {
            Some(_) => scatter_about(&level),
            None => flat_scatter,
        };
        // The scatter of a few stamps is too uncertain to widen the tolerance by.
        let jitters = jitter(scatter) && n >= JITTER_MIN_STAMPS;
        // A printed unit about the level is the printing's (the rounding of the stamp and of the
        // level), never more than half a step.
        let near_level =
            (GRID_TOLERANCE * base.b).max((PRINTED_UNITS * resolution.unwrap_or(0.0)).min(0.5 * base.b));
        let tolerance = if jitters {
            (JITTER_SIGMAS * scatter).clamp(near_level, 0.5 * base.b)
        } else {
            near_level
        };
        // Near its level, or near its grid time as a stamp with no level would be.
        let fits = |line: Line, k: f64, i: usize| {
            line.indexable(k, tau(i))
                && (off_level(line, k, i).abs() <= tolerance
                    || (tau(i) - line.at(k)).abs() <= GRID_TOLERANCE * line.b)
        };
        // Whether every stamp fits `line` at index i (found by the last refit, which then gave
        // `line` back). On its own indices without levels a stamp fits when its deviation from
        // the line does: so all of them, when the largest does.
        let own =
            own.filter(|own| levels.is_none() && own.largest.abs() <= tolerance.max(GRID_TOLERANCE * line.b));
        let mut on_grid = own.is_some();
        for _ in 0..MAX_REFITS {
            if on_grid {
                break;
            }
            let next = least_squares_indexed(n, &tau, &mut indices, line, &mut through_all, |i| {
                let k = line.index(tau(i));
                fits(line, k, i).then_some(k)
            });
            match next {
                Some(Refit::Same) => {
                    on_grid = true;
                    break;
                }
                Some(Refit::Line(next)) if next != line && next.b.is_finite() && next.b > 0.0 => line = next,
                _ => break,
            }
        }
        drop(indices);
        // Grid times increase with the index: those of every stamp's index (and of the indices
        // next to them, where glitches are repaired) are finite when the extreme ones are.
        let (lowest, highest) = if on_grid {
            (0.0, (n - 1) as f64)
        } else {
            (0..n).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), i| {
                let k = line.index(tau(i));
                (lo.min(k), hi.max(k))
            })
        };
        if !(origin + line.at(lowest - 1.0)).is_finite() || !(origin + line.at(highest + 1.0)).is_finite() {
            return Err(InputError::TimeOverflow {
                at: at(n - 1),
                t: t[n - 1],
            });
        }

        let index = |i: usize| line.index(tau(i));
        // Every stamp fitting at its own index is good (every level 0, every stamp anchored).
        let bad = if on_grid {
            Vec::new()
        } else {
            judge(n, |i| {
                let k = index(i);
                (k, fits(line, k, i))
            })
        };
        // Stamps off their level by more than a quarter step (those within a jitter's tolerance
        // beyond it included), and repeated ones.
        let near = |i: usize| {
            let k = index(i);
            line.indexable(k, tau(i))
                && (off_level(line, k, i).abs() <= near_level
                    || (tau(i) - line.at(k)).abs() <= GRID_TOLERANCE * line.b)
        };
        let off = match &own {
            Some(own) if own.largest.abs() <= near_level.max(GRID_TOLERANCE * line.b) => 0,
            _ => (0..n).filter(|&i| !near(i)).count(),
        } + bad
            .iter()
            .filter(|&&i| near(i) && i > 0 && t[i] == t[i - 1])
            .count();
        let scatter_of_step = Some(scatter / base.b).filter(|s| s.is_finite());
        if bad.len() == n || (off >= UNRESOLVED_MIN && off as f64 > UNRESOLVED_FRACTION * n as f64) {
            return Err(unresolved(off, scatter_of_step));
        }

        // Every glitch repaired, or the first one that cannot be is an error.
        // The grid index a glitch is repaired onto, when it can be. Isolated (its neighbours fit
        // one grid step apart on either side): the slot between them. Beside a gap (a logger
        // that dropped a row and stamped the next late): the count from its neighbours leaves it
        // more than one slot, so it takes the free slot its stamp is nearest, when within
        // NEAREST_SLOT steps of it (the next nearest then at least 1 − NEAREST_SLOT away). At an
        // end: the slot next to its neighbour, unless its stamp is within NEAREST_SLOT of a slot
        // past that one (rows may have been dropped there), which it then takes.
        let slot = |p: usize| -> Option<f64> {
            let i = bad[p];
            let prev_good = i > 0 && (p == 0 || bad[p - 1] != i - 1);
            let next_good = i + 1 < n && bad.get(p + 1) != Some(&(i + 1));
            let k = index(i);
            let near = || {
                off_level(line, k, i).abs() <= NEAREST_SLOT * line.b
                    && (tau(i) - line.at(k)).abs() <= NEAREST_SLOT * line.b
            };
            if i + 1 == n {
                // The last (a record has two samples at least).
                let next = index(i - 1) + 1.0;
                return prev_good.then(|| if k > next && near() { k } else { next });
            }
            if i == 0 {
                let previous = index(1) - 1.0;
                return next_good.then(|| if k < previous && near() { k } else { previous });
            }
            if !(prev_good && next_good) {
                return None;
            }
            let (before, after) = (index(i - 1), index(i + 1));
            if after - before == 2.0 {
                return Some(before + 1.0);
            }
            (after - before >= 3.0 && k > before && k < after && near()).then_some(k)
        };
        // A logger's unsettled start or end, when there are glitches at all: the rest is fitted
        // on its own, as a record without those samples would be. A run is one where a glitch
        // is not isolated (its neighbours fit, one grid step apart, or it is at an end beside
        // one that fits): a logger settling to its rate stamps some rows near a slot by chance,
        // the others then beside gaps, which are not taken for a logger's dropped rows there.
        let isolated = |p: usize| {
            let i = bad[p];
            let prev_good = i > 0 && (p == 0 || bad[p - 1] != i - 1);
            let next_good = i + 1 < n && bad.get(p + 1) != Some(&(i + 1));
            (i == 0 || prev_good)
                && (i + 1 == n || next_good)
                && (i == 0 || i + 1 == n || index(i + 1) - index(i - 1) == 2.0)
        };
        if settle && !bad.is_empty() {
            let runs = unsettled(&t, &bad, index, isolated, &at);
            let bound = ((UNSETTLED_FRACTION * n as f64) as usize).min(UNSETTLED_MAX);
            if let Some(long) = runs.iter().find(|r| r.samples.len() > bound) {
                return Err(InputError::TimeUnsettled {
                    end: long.end,
                    first: long.first,
                    last: long.last,
                    count: long.samples.len(),
                    shortest: long.shortest,
                    longest: long.longest,
                    dt: line.b,
                    bound,
                });
            }
            if !runs.is_empty() {
                let start = runs
                    .iter()
                    .find(|r| r.end == RecordEnd::Start)
                    .map_or(0, |r| r.samples.end);
                let stop = runs
                    .iter()
                    .find(|r| r.end == RecordEnd::End)
                    .map_or(n, |r| r.samples.start);
                let rest = Record {
                    t: t[start..stop].to_vec(),
                    theta: theta[start..stop].to_vec(),
                    lines: lines
                        .as_ref()
                        .and_then(|lines| lines.get(start..stop))
                        .map(<[u64]>::to_vec),
                    missing: missing.clone(),
                    ..Record::default()
                };
                let mut grid = Self::fit_from(rest, options, before + start, false, quick)?;
                grid.unsettled = runs
                    .into_iter()
                    .map(|r| Unsettled {
                        samples: before + r.samples.start..before + r.samples.end,
                        step: grid.dt,
                        ..r
                    })
                    .collect();
                return Ok(grid);
            }
        }
        let repairable = |p: usize| slot(p).is_some();
        let error = |p: usize| !(repairable(p) && options.repair);
        if let Some(p) = (0..bad.len()).find(|&p| error(p)) {
            let i = bad[p];
            let fault = match i.checked_sub(1).map(|j| t[j]) {
                Some(previous) if t[i] == previous => StampFault::Repeated,
                Some(previous) if t[i] < previous => StampFault::Backwards { previous },
                _ => StampFault::OffGrid,
            };
            let others: Vec<usize> = (p + 1..bad.len()).filter(|&q| error(q)).collect();
            return Err(InputError::TimeGlitch {
                at: at(i),
                t: t[i],
                fault,
                expected: origin + line.at(slot(p).unwrap_or_else(|| expected_index(&bad, p, n, index))),
                dt: line.b,
                isolated: repairable(p),
                others: others.iter().take(GLITCHES_NAMED).map(|&q| at(bad[q])).collect(),
                other_count: others.len(),
            });
        }
        // Every glitch is repairable here (the first that is not was an error).
        let fixed: Vec<f64> = (0..bad.len()).map(|p| slot(p).unwrap_or(f64::NAN)).collect();
        let final_index = |i: usize| match bad.binary_search(&i) {
            Ok(p) => fixed[p],
            Err(_) => index(i),
        };
        let k0 = final_index(0);
        let t0 = origin + line.at(k0);
        let repaired = bad
            .iter()
            .zip(&fixed)
            .map(|(&i, &k)| TimeRepair {
                at: at(i),
                was: t[i],
                now: t0 + (k - k0) * line.b,
            })
            .collect();

        // What the stamps kept say about the clock: deviations from the grid and from the
        // levels, and the changes of level beyond the noise of a median.
        let threshold = slip_threshold(scatter);
        let mut report = GridReport {
            step: line.b,
            resolution,
            max_deviation: 0.0,
            max_at: at(0),
            rms_deviation: 0.0,
            max_jitter: 0.0,
            rms_jitter: 0.0,
            slips: Vec::new(),
        };
        let (mut squares, mut jitter_squares, mut kept) = (Sum::default(), Sum::default(), 0usize);
        if let Some(own) = &own {
            // On its own indices every stamp is kept and its deviation from its level is its
            // deviation from the line: measured already.
            (squares, jitter_squares, kept) = (own.squares, own.squares, n);
            (report.max_deviation, report.max_at, report.max_jitter) = (own.largest, at(own.at), own.largest);
        } else {
            let mut next_bad = bad.iter().peekable();
            for i in 0..n {
                if next_bad.next_if_eq(&&i).is_some() {
                    continue;
                }
                let k = index(i);
                let deviation = tau(i) - line.at(k);
                let jitter = off_level(line, k, i);
                kept += 1;
                // In steps, so that no square overflows.
                squares.add((deviation / line.b).powi(2));
                jitter_squares.add((jitter / line.b).powi(2));
                if deviation.abs() > report.max_deviation.abs() {
                    (report.max_deviation, report.max_at) = (deviation, at(i));
                }
                if jitter.abs() > report.max_jitter.abs() {
                    report.max_jitter = jitter;
                }
            }
        }
        if let Some(levels) = &levels {
            let good = |i: usize| bad.binary_search(&i).is_err();
            report.slips = slips(levels, good, threshold)
                .into_iter()
                .map(|(i, by)| Slip { at: at(i), by })
                .collect();
        }
        if kept > 0 {
            report.rms_deviation = line.b * (squares.value() / kept as f64).sqrt();
            report.rms_jitter = line.b * (jitter_squares.value() / kept as f64).sqrt();
        }

        // Pieces, split from the end so that each sample moves once.
        let mut starts = vec![(0, 0)];
        let mut previous = k0;
        // On the grid every stamp is at its own index: one piece.
        if !on_grid {
            for i in 1..n {
                let k = final_index(i);
                if k - previous >= 2.0 {
                    starts.push((i, (k - k0) as usize));
                }
                previous = k;
            }
        }
        // A grid far longer than the samples: refused before anything holds it.
        let span = match starts.last() {
            // Saturating: a stamp far off (1e299) puts its index past any grid.
            Some(&(i, first)) => first.saturating_add(n - i),
            None => n,
        };
        if span > GAP_GRID_FACTOR.saturating_mul(n) && span - n > GAP_MISSING_ALLOWED {
            let (at_gap, missing) = starts
                .windows(2)
                .map(|w| (w[1].0, (w[1].1 - w[0].1).saturating_sub(w[1].0 - w[0].0)))
                .max_by_key(|&(_, missing)| missing)
                .unwrap_or((n - 1, span - n));
            return Err(InputError::GapTooLong {
                at: at(at_gap),
                t: t[at_gap],
                previous: t[at_gap.saturating_sub(1)],
                missing,
                dt: line.b,
                samples: n,
                grid: span,
            });
        }
        let mut theta = theta;
        let mut pieces: Vec<Piece> = starts
            .iter()
            .rev()
            .map(|&(i, first)| Piece {
                first,
                // The first piece takes the samples left as they are (split_off(0) copies them).
                samples: if i == 0 {
                    std::mem::take(&mut theta)
                } else {
                    theta.split_off(i)
                },
            })
            .collect();
        pieces.reverse();
        Ok(Self {
            t0,
            dt: line.b,
            pieces,
            repaired,
            report,
            unsettled: Vec::new(),
        })
    }

    /// The number of samples in all pieces.
    pub fn sample_count(&self) -> usize {
        self.pieces.iter().map(|p| p.samples.len()).sum()
    }

    /// The samples of the record as read that the pieces hold, counted from 0: all of them but
    /// the [`GridRecord::unsettled`] runs at its ends.
    pub fn kept(&self) -> std::ops::Range<usize> {
        let start = self
            .unsettled
            .iter()
            .find(|r| r.end == RecordEnd::Start)
            .map_or(0, |r| r.samples.end);
        start..start + self.sample_count()
    }
}

/// The unsettled runs at the ends of a record (see [`Unsettled`]), whatever their length, from
/// its stamps `t`, the samples `bad` whose stamps are glitches (in order), each sample's grid
/// index, whether the glitch `bad[p]` is isolated, and where each sample is; `samples` counted
/// in `t`, `step` not set.
///
/// The rest begins at the first [`SETTLED_STAMPS`] stamps that fit one step apart and ends at
/// the last ones; a run is what lies before (or after) it, when it holds a glitch that is not
/// isolated and its stamps increase, into the rest too (a stamp repeated or going backwards is a
/// clock's glitch, not a rate).
fn unsettled(
    t: &[f64],
    bad: &[usize],
    index: impl Fn(usize) -> f64,
    isolated: impl Fn(usize) -> bool,
    at: &impl Fn(usize) -> Location,
) -> Vec<Unsettled> {
    let n = t.len();
    let good = |i: usize| bad.binary_search(&i).is_err();
    let settled = |i: usize| {
        i + SETTLED_STAMPS <= n
            && (i..i + SETTLED_STAMPS).all(|j| good(j) && index(j) - index(i) == (j - i) as f64)
    };
    let Some(start) = (0..n).find(|&i| settled(i)) else {
        return Vec::new();
    };
    let stop = (start..=n - SETTLED_STAMPS)
        .rev()
        .find(|&i| settled(i))
        .map_or(n, |i| i + SETTLED_STAMPS);
    // Each run with the steps from each of its stamps to the next, the one into the rest included.
    [
        (RecordEnd::Start, 0..start, 0..start),
        (RecordEnd::End, stop..n, stop - 1..n - 1),
    ]
    .into_iter()
    .filter(|(_, run, _)| !run.is_empty())
    .filter(|(_, run, _)| (0..bad.len()).any(|p| run.contains(&bad[p]) && !isolated(p)))
    .filter_map(|(end, run, steps)| {
        let (shortest, longest) = steps
            .map(|i| t[i + 1] - t[i])
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), s| {
                (lo.min(s), hi.max(s))
            });
        (shortest > 0.0).then(|| Unsettled {
            end,
            first: at(run.start),
            last: at(run.end - 1),
            from: t[run.start],
            to: t[run.end - 1],
            samples: run,
            shortest,
            longest,
            step: f64::NAN,
        })
    })
    .collect()
}

/// The line `τ = a + n · b` through the stamps, `τ` counted from the first stamp of the first
/// run of single steps.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Line {
    a: f64,
    b: f64,
}

impl Line {
    /// The grid index nearest to `tau`.
    fn index(self, tau: f64) -> f64 {
        round((tau - self.a) / self.b)
    }

    /// Whether `tau` is less than half a step from the grid time of index `k` (never for an
    /// index beyond 2^52, where whole numbers are no longer exact): its index is not in doubt.
    fn indexable(self, k: f64, tau: f64) -> bool {
        (tau - self.at(k)).abs() < 0.5 * self.b && k.abs() <= MAX_INDEX
    }

    /// The grid time of index `k`.
    fn at(self, k: f64) -> f64 {
        self.a + k * self.b
    }
}

/// Whether the median deviation of some run of [`LEVEL_WINDOW`] stamps (in consecutive runs from
/// the first) is `limit` or more from the line.
fn windows_depart(n: usize, deviation: &impl Fn(usize) -> f64, limit: f64) -> bool {
    let mut window = [0.0; LEVEL_WINDOW];
    (0..n).step_by(LEVEL_WINDOW).any(|start| {
        let len = LEVEL_WINDOW.min(n - start);
        for (j, slot) in window[..len].iter_mut().enumerate() {
            *slot = deviation(start + j);
        }
        median(&mut window[..len]).is_some_and(|m| m.is_nan() || m.abs() >= limit)
    })
}

/// The clock's levels, against the line they were found on.
struct Levels {
    /// Each stamp's own level: the median deviation of the [`LEVEL_WINDOW`] stamps that end at it
    /// or of those that start at it (the first or last ones of the record at its ends),
    /// whichever is nearer its own deviation.
    own: Vec<f64>,
    /// The median deviation of the [`LEVEL_WINDOW`] stamps that start at each (the last ones of
    /// the record at its end).
    after: Vec<f64>,
}

impl Levels {
    /// The median deviation of the [`LEVEL_WINDOW`] stamps centred on stamp `i` (shifted to stay
    /// whole at the ends): it moves from one level to the next at a slip, without picking sides.
    fn centred(&self, i: usize) -> f64 {
        self.after[i.saturating_sub(LEVEL_WINDOW / 2)]
    }
}

/// The levels of the stamps from their deviations `deviation(i)` from the line.
fn levels(n: usize, deviation: &impl Fn(usize) -> f64) -> Levels {
    let h = LEVEL_WINDOW - 1;
    let mut own = running_median(n, h, 0, deviation);
    let after = running_median(n, 0, h, deviation);
    for (i, (b, &a)) in own.iter_mut().zip(&after).enumerate() {
        let d = deviation(i);
        if (d - *b).abs() > (d - a).abs() {
            *b = a;
        }
    }
    Levels { own, after }
}

/// The slips of the clock, `(first stamp at the new level, change of level)`, from the centred
/// levels of the good stamps: a slip where a level moves `threshold` or more from the mean of the
/// levels from one and a half windows to one window before it (whose windows do not reach it,
/// however gradually a centred median moves from one level to the next), none of them before the
/// previous slip. Its size is the mean level of the stamps from half a window to a window after
/// it less that of the stamps from a window to half a window before it, or, where those are cut
/// off by another slip or the record's ends, the nearest levels there are.
fn slips(levels: &Levels, good: impl Fn(usize) -> bool, threshold: f64) -> Vec<(usize, f64)> {
    let (n, w, half) = (levels.after.len(), LEVEL_WINDOW, LEVEL_WINDOW / 2);
    let mean = |range: std::ops::Range<usize>| {
        let (sum, count) = range
            .filter(|&i| good(i))
            .fold((0.0, 0usize), |(s, c), i| (s + levels.centred(i), c + 1));
        (count > 0).then(|| sum / count as f64)
    };
    let mut found: Vec<(usize, f64)> = Vec::new();
    // The first stamp whose centred window is past the previous slip.
    let mut since = 0;
    // The reference window `[from, to)` and the sum and count of its good levels, slid one
    // stamp at a time and summed afresh after a slip.
    let (mut from, mut to, mut sum, mut count) = (0, 0, 0.0, 0usize);
    for i in (w..n).filter(|&i| good(i)) {
        let (start, end) = (since.max(i - w - half.min(i - w)), (i - w).max(since));
        if start < from || start > to || end < to {
            (from, to, sum, count) = (start, start, 0.0, 0);
        }
        for j in from..start.min(to) {
            if good(j) {
                sum -= levels.centred(j);
                count -= 1;
            }
        }
        from = start;
        for j in to.max(start)..end {
            if good(j) {
                sum += levels.centred(j);
                count += 1;
            }
        }
        to = end;
        if count == 0 {
            continue;
        }
        let reference = sum / count as f64;
        if (levels.centred(i) - reference).abs() >= threshold {
            let before = mean(since.max(i - w)..(i - half).max(since)).unwrap_or(reference);
            let after = mean((i + half).min(n)..(i + w).min(n)).unwrap_or(levels.centred(i));
            if (after - before).abs() >= threshold {
                found.push((i, after - before));
                since = i + half;
            }
        }
    }
    found
}

/// The median of the values from `before` places before each one to `after` places after it,
/// the window shifted to stay whole at the ends of the record (the upper middle of an even
/// count), in `O(n w)` for a window of `w` at worst and `O(n)` where the values repeat.
fn running_median(n: usize, before: usize, after: usize, value: impl Fn(usize) -> f64) -> Vec<f64> {
    let len = (before + after + 1).min(n);
    let low = |i: usize| i.saturating_sub(before).min(n - len);
    let place = |window: &[f64], v: f64| window.partition_point(|x| x.total_cmp(&v).is_lt());
    let mut window: Vec<f64> = Vec::with_capacity(len + 1);
    for j in 0..len {
        let v = value(j);
        window.insert(place(&window, v), v);
    }
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        out.push(window[len / 2]);
        if i + 1 == n || low(i + 1) == low(i) {
            continue;
        }
        let (drop, add) = (value(low(i)), value(low(i) + len));
        if drop.to_bits() != add.to_bits() {
            window.remove(place(&window, drop));
            window.insert(place(&window, add), add);
        }
    }
    out
}

/// The median of at most [`MEDIAN_STEPS`] steps, evenly spread.
fn first_step(t: &[f64]) -> f64 {
    let stride = (t.len() - 1).div_ceil(MEDIAN_STEPS).max(1);
    let mut steps: Vec<f64> = (0..t.len() - 1)
        .step_by(stride)
        .map(|i| t[i + 1] - t[i])
        .collect();
    median(&mut steps).unwrap_or(f64::NAN)
}

/// Whether the step from `a` to `b` is a single step of about `dt`.
fn single(a: f64, b: f64, dt: f64) -> bool {
    ((b - a) / dt - 1.0).abs() <= 0.5 + SINGLE_SLACK
}

/// The maximal runs `(first, last)` of at least two samples with single steps between them.
fn single_runs(t: &[f64], dt: f64) -> Vec<(usize, usize)> {
    let mut runs = Vec::new();
    let mut start = None;
    for i in 0..t.len() - 1 {
        if single(t[i], t[i + 1], dt) {
            start.get_or_insert(i);
        } else if let Some(s) = start.take() {
            runs.push((s, i));
        }
    }
    if let Some(s) = start {
        runs.push((s, t.len() - 1));
    }
    runs
}

/// The mean single step (runs telescoped), from `dt` until it settles, and the
/// [`single_runs`] of that step.
fn refine_step(t: &[f64], mut dt: f64) -> (f64, Vec<(usize, usize)>) {
    for _ in 0..8 {
        let runs = single_runs(t, dt);
        let (span, steps) = runs.iter().fold((0.0, 0usize), |(span, steps), &(s, e)| {
            (span + (t[e] - t[s]), steps + (e - s))
        });
        if steps == 0 {
            return (dt, runs);
        }
        let next = span / steps as f64;
        if next == dt {
            return (dt, runs);
        }
        dt = next;
    }
    (dt, single_runs(t, dt))
}

/// The grid index of the first sample of each run, consistent across the runs (any one may be
/// shifted by the same whole number).
///
/// From the longest run outwards, each time to the neighbour run nearer in time: its index is
/// that of the line fitted to the runs linked so far, so that each gap is measured against the
/// longest baseline there is.
fn link(t: &[f64], runs: &[(usize, usize)], dt: f64) -> Vec<f64> {
    if runs.len() <= 1 {
        // Nothing to link: the one run starts at index 0.
        return vec![0.0; runs.len()];
    }
    let longest = (0..runs.len())
        .max_by_key(|&r| (runs[r].1 - runs[r].0, std::cmp::Reverse(r)))
        .unwrap_or(0);
    let origin = t[runs[longest].0];
    let mut moments = Moments::default();
    let add = |moments: &mut Moments, (s, e): (usize, usize), k: f64| {
        for (j, &ti) in t[s..=e].iter().enumerate() {
            moments.add(k + j as f64, ti - origin);
        }
    };
    let mut starts = vec![0.0; runs.len()];
    add(&mut moments, runs[longest], 0.0);
    let (mut lo, mut hi) = (longest, longest);
    while lo > 0 || hi + 1 < runs.len() {
        let line = moments.line().unwrap_or(Line { a: 0.0, b: dt });
        let index = |i: usize| round((t[i] - origin - line.a) / line.b);
        let left = (lo > 0).then(|| t[runs[lo].0] - t[runs[lo - 1].1]);
        let right = (hi + 1 < runs.len()).then(|| t[runs[hi + 1].0] - t[runs[hi].1]);
        let go_left = match (left, right) {
            (Some(l), Some(r)) => l <= r,
            (l, _) => l.is_some(),
        };
        let r = if go_left { lo - 1 } else { hi + 1 };
        let (s, e) = runs[r];
        starts[r] = if go_left {
            index(e) - (e - s) as f64
        } else {
            index(s)
        };
        add(&mut moments, runs[r], starts[r]);
        if go_left {
            lo = r;
        } else {
            hi = r;
        }
    }
    starts
}

/// Sums of the points `(n, τ)` of a least-squares line, added one at a time.
#[derive(Debug, Default)]
struct Moments {
    count: usize,
    n: Sum,
    tau: Sum,
    nn: Sum,
    ntau: Sum,
}

impl Moments {
    fn add(&mut self, k: f64, tau: f64) {
        self.count += 1;
        self.n.add(k);
        self.tau.add(tau);
        self.nn.add(k * k);
        self.ntau.add(k * tau);
    }

    /// The line through the points so far; `None` for fewer than two distinct indices.
    fn line(&self) -> Option<Line> {
        let count = self.count as f64;
        let (n, tau) = (self.n.value(), self.tau.value());
        let sxx = self.nn.value() - n * n / count;
        let sxy = self.ntau.value() - n * tau / count;
        if sxx.is_nan() || sxx <= 0.0 {
            return None;
        }
        let b = sxy / sxx;
        Some(Line {
            a: (tau - b * n) / count,
            b,
        })
    }
}

/// The least-squares line through the points `(n, τ)` that `points` gives (it is called twice,
/// and must give the same points); `None` for fewer than two distinct indices.
fn least_squares<I: Iterator<Item = (f64, f64)>>(points: impl Fn() -> I) -> Option<Line> {
    let (mut count, mut sum_n, mut sum_t) = (0usize, Sum::default(), Sum::default());
    points().for_each(|(k, tau)| {
        count += 1;
        sum_n.add(k);
        sum_t.add(tau);
    });
    if count < 2 {
        return None;
    }
    let (mean_n, mean_t) = (sum_n.value() / count as f64, sum_t.value() / count as f64);
    let (mut sxx, mut sxy) = (Sum::default(), Sum::default());
    points().for_each(|(k, tau)| {
        let dk = k - mean_n;
        sxx.add(dk * dk);
        sxy.add(dk * (tau - mean_t));
    });
    let (sxx, sxy) = (sxx.value(), sxy.value());
    if sxx.is_nan() || sxx <= 0.0 {
        return None;
    }
    let b = sxy / sxx;
    Some(Line {
        a: mean_t - b * mean_n,
        b,
    })
}

/// A refit of a line.
enum Refit {
    /// The line through the points.
    Line(Line),
    /// The points are those the line was fitted to: it is the same line.
    Same,
}

/// [`least_squares`] through the points `(index(i), tau(i))` of the samples `i < n` that have an
/// index, each index found once for both passes (kept in `indices`, NaN for none): the same
/// sums in the same order, so the same line. `through_all` says whether `line`, the line
/// refitted, was fitted to `(i, tau(i))` of every sample `i < n` in order; when the indices are
/// `0, 1, …, n − 1` again, [`Refit::Same`] is returned without the sums (checked against them in
/// every debug build). It is set for the line returned.
fn least_squares_indexed(
    n: usize,
    tau: &impl Fn(usize) -> f64,
    indices: &mut Vec<f64>,
    line: Line,
    through_all: &mut bool,
    index: impl Fn(usize) -> Option<f64>,
) -> Option<Refit> {
    indices.clear();
    let mut consecutive = true;
    indices.extend((0..n).map(|i| {
        let k = index(i).unwrap_or(f64::NAN);
        consecutive &= k == i as f64;
        k
    }));
    if consecutive && *through_all {
        debug_assert!(
            least_squares(|| (0..n).map(|i| (i as f64, tau(i)))).is_some_and(|again| again.a.to_bits()
                == line.a.to_bits()
                && again.b.to_bits() == line.b.to_bits()),
            "a refit on the points of {line:?}"
        );
        return Some(Refit::Same);
    }
    *through_all = consecutive;
    let indices = &*indices;
    least_squares(|| {
        indices
            .iter()
            .enumerate()
            // An index is a whole number (never NaN) where there is one.
            .filter(|(_, k)| !k.is_nan())
            .map(|(i, &k)| (k, tau(i)))
    })
    .map(Refit::Line)
}

/// What the passes of [`GridRecord::fit`] measure of a record whose every stamp `i` is less than
/// half a step from the grid time of index `i` on the line through all of them (and whose
/// refits therefore give that line back): each stamp's deviation from the line, found in one
/// pass. The deviation of stamp `i` is `τ_i − line.at(i)`, the same arithmetic as the passes'.
struct OwnIndices {
    /// The largest deviation (signed; the first of equal sizes).
    largest: f64,
    /// Where it is.
    at: usize,
    /// The squares of the deviations in steps, summed in order.
    squares: Sum,
}

impl OwnIndices {
    /// The deviations of the `n` stamps `tau` from `line`, or `None` when some stamp is not at
    /// its own index (or not less than half a step from it).
    fn of(n: usize, tau: &impl Fn(usize) -> f64, line: Line) -> Option<Self> {
        let mut own = Self {
            largest: 0.0,
            at: 0,
            squares: Sum::default(),
        };
        // Where `(τ − a) / b` is within a quarter of `i`, its rounding is `i`: a product by
        // `1 / b` settles that without the division (the two differ by a few units in the last
        // place, far less than a quarter), which the others take.
        let per_step = 1.0 / line.b;
        for i in 0..n {
            let tau = tau(i);
            let at = i as f64;
            let k = if ((tau - line.a) * per_step - at).abs() < 0.25 {
                at
            } else {
                line.index(tau)
            };
            // Equal as numbers (a stamp just before the origin rounds to −0, whose grid time
            // `a + (−0) b` is `a` as well), or both not numbers (stamps so large that the
            // line's arithmetic overflows, which `indexable` then refuses).
            debug_assert!(
                k == line.index(tau) || (k.is_nan() && line.index(tau).is_nan()),
                "stamp {i}: {k} against {}",
                line.index(tau)
            );
            if k != at || !line.indexable(k, tau) {
                return None;
            }
            let deviation = tau - line.at(k);
            own.squares.add((deviation / line.b).powi(2));
            if deviation.abs() > own.largest.abs() {
                (own.largest, own.at) = (deviation, i);
            }
        }
        Some(own)
    }
}

/// A compensated (Neumaier) sum: exact to a few roundings whatever the number of terms.
#[derive(Debug, Default, Clone, Copy)]
struct Sum {
    sum: f64,
    compensation: f64,
}

impl Sum {
    #[inline]
    fn add(&mut self, x: f64) {
        let t = self.sum + x;
        // Both corrections, then a choice: a select rather than a branch, which the mixed signs
        // of the deviations make unpredictable.
        let (big, small) = ((self.sum - t) + x, (x - t) + self.sum);
        self.compensation += if self.sum.abs() >= x.abs() { big } else { small };
        self.sum = t;
    }

    fn value(self) -> f64 {
        self.sum + self.compensation
    }
}

/// Stamps whose levels [`judge`] holds at once.
const JUDGE_HELD: usize = 16;

/// Judges every stamp by its grid index `locate(i)` and whether it fits (see the module docs);
/// returns the samples whose stamps are glitches, in order.
///
/// With `g_i = n_i − i` its index level, a stamp that fits is anchored when a neighbour that fits
/// has the same index level. A stamp is good when it fits, its index level is not below the last
/// good stamp's, and, unless it is anchored, not above the next anchored stamp's either.
fn judge(n: usize, locate: impl Fn(usize) -> (f64, bool)) -> Vec<usize> {
    // The levels asked for lie within a sample of the current stamp and of the next anchored
    // one: held in a few slots, each stamp is located about once instead of five times.
    let held = std::cell::RefCell::new([(usize::MAX, (0.0, false)); JUDGE_HELD]);
    let level = |i: usize| {
        let slot = &mut held.borrow_mut()[i % JUDGE_HELD];
        if slot.0 != i {
            let (k, fits) = locate(i);
            *slot = (i, (k - i as f64, fits));
        }
        slot.1
    };
    let anchored = |i: usize| {
        let (g, fits) = level(i);
        fits && ((i > 0 && level(i - 1) == (g, true)) || (i + 1 < n && level(i + 1) == (g, true)))
    };
    let mut bad = Vec::new();
    let mut last: Option<f64> = None;
    // The next anchored stamp after the current one (n when there is none).
    let mut ahead = 0;
    for i in 0..n {
        let (g, fits) = level(i);
        let good = fits
            && last.is_none_or(|l| g >= l)
            && (anchored(i) || {
                if ahead <= i {
                    ahead = i + 1;
                    while ahead < n && !anchored(ahead) {
                        ahead += 1;
                    }
                }
                ahead == n || g <= level(ahead).0
            });
        if good {
            last = Some(g);
        } else {
            bad.push(i);
        }
    }
    bad
}

/// The grid index sample `bad[p]` would have, counted from its nearest good neighbour (the one
/// before it if any).
fn expected_index(bad: &[usize], p: usize, n: usize, index: impl Fn(usize) -> f64) -> f64 {
    let i = bad[p];
    let mut first = p;
    while first > 0 && bad[first - 1] == bad[first] - 1 {
        first -= 1;
    }
    if bad[first] > 0 {
        let j = bad[first] - 1;
        return index(j) + (i - j) as f64;
    }
    let mut last = p;
    while last + 1 < bad.len() && bad[last + 1] == bad[last] + 1 {
        last += 1;
    }
    let j = (bad[last] + 1).min(n - 1);
    index(j) - (j as f64 - i as f64)
}
