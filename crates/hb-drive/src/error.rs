//! The errors of the drive-period search.

use hb_model::ModelError;
use hb_solve::SolveError;

/// Everything that can go wrong in the search for the drive's period.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DriveSearchError {
    /// The model form has no term with the drive, so its residual does not depend on the forcing
    /// period.
    #[error(
        "the model form has no drive term (no parametric terms, no external forcing): the forcing period \
         cannot be estimated from its residual"
    )]
    NoDriveTerm,
    /// A range of forcing periods the record cannot resolve.
    #[error(
        "forcing period range {shortest}..{longest} does not fit the record: candidate periods must lie in \
         {min_period}..{max_period} (at least 4 samples per period, and the record must span the window \
         length plus 3 periods of the longest)"
    )]
    DriveRangeUnfit {
        /// Shortest period asked for.
        shortest: f64,
        /// Longest period asked for.
        longest: f64,
        /// Shortest period the record resolves.
        min_period: f64,
        /// Longest period the record holds.
        max_period: f64,
    },
    /// The best forcing period lies on an end of the range searched: the drive is probably outside.
    #[error(
        "the weak form's residual is smallest at the {edge}-period end of the range searched (period {period} \
         in {shortest}..{longest}, normalised residual {residual:.3e}): the forcing period is probably outside \
         the range; widen it"
    )]
    DrivePeriodAtRangeEdge {
        /// The period at the end.
        period: f64,
        /// Shortest period of the range.
        shortest: f64,
        /// Longest period of the range.
        longest: f64,
        /// `short` or `long`.
        edge: &'static str,
        /// Its normalised residual.
        residual: f64,
    },
    /// No period of the range explains the record much better than a typical candidate: the best
    /// one's residual is not far enough below the scan's median.
    #[error(
        "no forcing period in the range explains the record: the best, {period}, leaves a normalised \
         residual of {residual:.3e} against a typical {typical:.3e} over the range; the drive is probably \
         outside the range (or the model form has no term for it)"
    )]
    DrivePeriodNotFound {
        /// The best period found.
        period: f64,
        /// Its normalised residual on the whole record.
        residual: f64,
        /// The median normalised residual of the scan.
        typical: f64,
    },
    /// The identification behind the search.
    #[error(transparent)]
    Solve(#[from] SolveError),
    /// The model's form.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// A parameter is out of range.
    #[error("invalid {name}: {} ({why})", circle_signal::Shown(*.value))]
    InvalidParameter {
        /// The parameter's name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What it must be.
        why: &'static str,
    },
}

impl From<hb_model::TermError> for DriveSearchError {
    fn from(e: hb_model::TermError) -> Self {
        DriveSearchError::Model(ModelError::Term(e))
    }
}

impl From<hb_basis::BasisError> for DriveSearchError {
    fn from(e: hb_basis::BasisError) -> Self {
        DriveSearchError::Model(ModelError::from(e))
    }
}

impl From<circle_signal::CircleError> for DriveSearchError {
    fn from(e: circle_signal::CircleError) -> Self {
        DriveSearchError::Solve(SolveError::from(e))
    }
}
