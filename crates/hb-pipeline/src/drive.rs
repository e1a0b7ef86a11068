//! The drive of a record as a request gives it ([`DriveSpec`]: a period, `auto`, `none`, or
//! windows of a length) and the estimate of its period where it is not given ([`estimate`]).
//!
//! Estimating the period is a weak-form fit over candidate periods (`hb_drive`): it is done here,
//! above the record path, so that reading and conditioning a record (`hb_record`) builds no
//! solver. What it finds goes down to the record as a [`PeriodSource`].

use circle_signal::Domain;
use hb_basis::BasisKind;
use hb_drive::{DriveEstimate, DriveSearch, DriveSearchError, PeriodRange, estimate_drive_period};
use hb_model::{Forcing, ModelForm};
use hb_record::prepare::{GridData, PeriodSource, WindowUnit};

/// What drives the record.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DriveSpec {
    /// A known drive period, in the record's time unit.
    Period(f64),
    /// A drive period to estimate from the record, within this range if given.
    Auto(Option<PeriodRange>),
    /// No drive: a free oscillation, whose mean period is the unit of the windows.
    Free,
    /// No periodic drive (none, or a measured one with no period): the unit of the windows given
    /// by its length.
    Windows(WindowUnit),
}

/// How a drive is given in text: by its period or by its frequency.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DriveUnit {
    /// A period in the record's time unit (`T`, and `auto:A..B` between periods A and B).
    Period,
    /// A frequency in cycles per time unit of the record, hertz for seconds (`F`, and
    /// `auto:A..B` between frequencies A and B).
    Frequency,
}

/// A drive given in text that is none of `T`, `auto`, `auto:A..B` or `none`.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{reason}")]
pub struct BadDrive {
    /// The text.
    pub text: String,
    /// What is wrong with it.
    pub reason: String,
}

impl DriveSpec {
    /// Reads a drive as the command line and Python give it, by its period or its frequency
    /// (`unit`): a positive number, `auto` (estimated from the record), `auto:A..B` (estimated
    /// between A and B) or `none` (a free oscillation).
    ///
    /// ```
    /// use hb_pipeline::drive::{DriveSpec, DriveUnit};
    ///
    /// assert_eq!(DriveSpec::parse("4", DriveUnit::Frequency)?, DriveSpec::Period(0.25));
    /// assert_eq!(DriveSpec::parse("none", DriveUnit::Period)?, DriveSpec::Free);
    /// assert!(matches!(DriveSpec::parse("auto:0.5..2", DriveUnit::Frequency)?, DriveSpec::Auto(Some(_))));
    /// assert!(DriveSpec::parse("-1", DriveUnit::Period).is_err());
    /// # Ok::<(), hb_pipeline::drive::BadDrive>(())
    /// ```
    pub fn parse(text: &str, unit: DriveUnit) -> Result<Self, BadDrive> {
        let bad = |reason: String| BadDrive {
            text: text.to_owned(),
            reason,
        };
        let number = |s: &str| -> Result<f64, BadDrive> {
            let v: f64 = s
                .trim()
                .parse()
                .map_err(|_| bad(format!("'{}' is not a number", s.trim())))?;
            if !(v.is_finite() && v > 0.0) {
                return Err(bad(format!("{v} must be positive and finite")));
            }
            Ok(v)
        };
        let trimmed = text.trim();
        if trimmed.eq_ignore_ascii_case("none") {
            return Ok(Self::Free);
        }
        if let Some(rest) = trimmed.strip_prefix("auto") {
            if rest.is_empty() {
                return Ok(Self::Auto(None));
            }
            let (a, b) = rest
                .strip_prefix(':')
                .and_then(|r| r.split_once(".."))
                .ok_or_else(|| bad("expected a number, auto, auto:A..B or none".to_owned()))?;
            let (a, b) = (number(a)?, number(b)?);
            let range = match unit {
                DriveUnit::Period => PeriodRange::periods(a, b),
                DriveUnit::Frequency => PeriodRange::frequencies(a, b),
            }
            .map_err(|e| bad(e.to_string()))?;
            return Ok(Self::Auto(Some(range)));
        }
        let v = number(trimmed)?;
        Ok(Self::Period(match unit {
            DriveUnit::Period => v,
            DriveUnit::Frequency => 1.0 / v,
        }))
    }
}

impl DriveSpec {
    /// What the record's conditioning takes for this drive, the period estimated from `grid`
    /// when it is to be ([`estimate`]; `progress` follows its scan), and the estimate itself.
    pub fn resolve(
        self,
        grid: &GridData,
        progress: &mut dyn FnMut(usize, usize),
    ) -> Result<(PeriodSource, Option<DriveEstimate>), DriveError> {
        Ok(match self {
            Self::Period(t) => (PeriodSource::Given(t), None),
            Self::Free => (PeriodSource::Free, None),
            Self::Windows(unit) => (PeriodSource::Windows(unit), None),
            Self::Auto(range) => {
                let estimate = estimate(grid, range, progress).map_err(|e| match e {
                    DriveError::Estimate(source) if !grid.others.is_empty() => {
                        DriveError::EstimateOfSystem(source)
                    }
                    other => other,
                })?;
                let source = PeriodSource::Estimated {
                    period: estimate.period,
                    uncertainty: estimate.period_uncertainty,
                };
                (source, Some(estimate))
            }
        })
    }
}

/// A drive's period that could not be estimated.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DriveError {
    /// The search's options (its range).
    #[error("the drive's search range («drive_period», «drive_frequency»)")]
    Search(#[source] DriveSearchError),
    /// The search ran and found no period.
    #[error("estimating the drive's period")]
    Estimate(#[source] DriveSearchError),
    /// The search ran on a record of several coordinates and found no period.
    #[error(
        "estimating the drive's period (searched on the first coordinate alone, with the default model \
         of one coordinate, which the coordinates of a coupled system need not follow: give the drive, \
         «drive_frequency» or «drive_period», if the search cannot find it)"
    )]
    EstimateOfSystem(#[source] DriveSearchError),
}

/// The drive period of the record on `grid`, estimated on its longest piece within `range` (the
/// search's default range without one) by the weak form of the default model of its domain: the
/// pendulum's on the circle, Duffing's with an identified forcing on the line.
pub fn estimate(
    grid: &GridData,
    range: Option<PeriodRange>,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<DriveEstimate, DriveError> {
    let mut search = DriveSearch::builder();
    if let Some(range) = range {
        search = search.range(range);
    }
    let search = search.build().map_err(DriveError::Search)?;
    let basis = BasisKind::default_for(grid.domain);
    let form = match grid.domain {
        Domain::Circle => ModelForm::parametric(),
        Domain::Line => ModelForm::parametric().with_forcing(Forcing::Identified),
    };
    let longest = circle_signal::longest_piece(&grid.pieces);
    let piece_t0 = grid.t0 + longest.start as f64 * grid.dt;
    estimate_drive_period(
        &grid.x[longest],
        grid.dt,
        piece_t0,
        grid.domain,
        &search,
        &basis,
        &form,
        progress,
    )
    .map_err(DriveError::Estimate)
}
