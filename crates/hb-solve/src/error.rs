//! The errors of identification, one enum per concern, folded into [`SolveError`].

use hb_basis::{BasisError, Domain};
use hb_model::{ModelError, ModelIoError, TermError};

/// Assembling the equations of a record's segments.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum AssemblyError {
    /// A sample of a segment is NaN or infinite.
    #[error("segment {segment} (start {start}): sample {index} of the record is not finite ({value})")]
    NonFiniteSample {
        /// Index of the segment in the list given.
        segment: usize,
        /// Its first sample.
        start: usize,
        /// Index of the bad sample in the record.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// A sample of the measured drive on a segment is NaN or infinite.
    #[error(
        "segment {segment} (start {start}): sample {index} of the measured drive p is not finite ({value})"
    )]
    NonFiniteDriveSample {
        /// Index of the segment in the list given.
        segment: usize,
        /// Its first sample.
        start: usize,
        /// Index of the bad sample in the record.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// A term has a measured drive but no samples of it were given.
    #[error("the term `{term}` has a measured drive, but no samples of it were given (Signals::with_drives)")]
    MissingDriveSamples {
        /// The first term in a measured drive.
        term: String,
    },
    /// A term reads a coordinate the record does not give.
    #[error("the term `{term}` reads coordinate {coordinate}, but the record gives {given} coordinate(s)")]
    MissingCoordinate {
        /// The term.
        term: String,
        /// The coordinate's index.
        coordinate: usize,
        /// The coordinates given.
        given: usize,
    },
    /// A coordinate of a system with another number of samples than the first.
    #[error(
        "coordinate {coordinate} has {len} samples but the first {record}: a system's coordinates share one grid"
    )]
    CoordinateLengthMismatch {
        /// The coordinate's index.
        coordinate: usize,
        /// Its samples.
        len: usize,
        /// The first coordinate's samples.
        record: usize,
    },
    /// A sample of another coordinate of the system on a segment is NaN or infinite.
    #[error(
        "segment {segment} (start {start}): sample {index} of coordinate {coordinate} is not finite ({value})"
    )]
    NonFiniteCoordinateSample {
        /// Index of the segment in the list given.
        segment: usize,
        /// Its first sample.
        start: usize,
        /// The coordinate.
        coordinate: usize,
        /// Index of the bad sample in the record.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// A system's equations given with a different number of views of the record
    /// (`Identifier::systems`).
    #[error("{setups} equation setups but {signals} views of the record: one each")]
    EquationCount {
        /// The setups.
        setups: usize,
        /// The views of the record.
        signals: usize,
    },
    /// The measured drive and the record have different numbers of samples.
    #[error(
        "the measured drive has {drive} samples but the record {record}: they must be sampled together, sample for sample"
    )]
    DriveLengthMismatch {
        /// Samples of the drive.
        drive: usize,
        /// Samples of the record.
        record: usize,
    },
    /// A term in the measured drive `p` with a method that cannot balance it.
    #[error("the term `{term}` has the measured drive p, which {method} cannot balance: {why}")]
    MeasuredDriveUnsupported {
        /// The first term in `p`.
        term: String,
        /// The method.
        method: &'static str,
        /// Why.
        why: &'static str,
    },
    /// A sample of the record is NaN or infinite.
    #[error("sample {index} of the record is not finite ({value})")]
    NonFiniteRecordSample {
        /// Index of the bad sample.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// A term of the model is not finite on a segment (e.g. a monomial overflowed).
    #[error("segment {segment} (start {start}): the term `{term}` is not finite on it")]
    NonFiniteTerm {
        /// Index of the segment.
        segment: usize,
        /// Its first sample.
        start: usize,
        /// The basis function or term.
        term: String,
    },
    /// An equation built from a segment is not finite (e.g. a monomial overflowed).
    #[error("segment {segment} (start {start}) gives a non-finite equation (row {row} of its block)")]
    NonFiniteRow {
        /// Index of the segment.
        segment: usize,
        /// Its first sample.
        start: usize,
        /// Row within the segment's block.
        row: usize,
    },
    /// A segment does not fit the record or the sampling.
    #[error(
        "segment {segment}: start {start}, period {period}, {len} samples does not fit a record of {record} \
         samples at {samples_per_period} per forcing period (need len = period * P >= 2 and a closing sample)"
    )]
    BadSegment {
        /// Index of the segment.
        segment: usize,
        /// Its first sample.
        start: usize,
        /// Its period in forcing periods.
        period: usize,
        /// Its number of samples.
        len: usize,
        /// Length of the record.
        record: usize,
        /// Samples per forcing period.
        samples_per_period: usize,
    },
    /// A term that a computation does not handle.
    #[error("the term `{term}` is not supported by {by}")]
    TermNotSupported {
        /// The term's name.
        term: String,
        /// What does not support it.
        by: &'static str,
    },
    /// The noise correction cannot be applied to a term of this model.
    #[error("no noise correction for the term `{term}`: {why}")]
    NoiseCorrectionUnavailable {
        /// The term (basis function) concerned.
        term: String,
        /// Why.
        why: &'static str,
    },
    /// A drive harmonic the sampling cannot resolve: at or above half the samples per drive
    /// period a sampled `cos(kt)`, `sin(kt)` is the alias of a lower harmonic (or zero), and its
    /// coefficient would be taken from another term's or from nothing.
    #[error(
        "{what} has the drive's harmonic {harmonic}, which {samples_per_period} samples per drive period \
         cannot resolve: a sampled harmonic is a lower one's alias from half the samples per period on \
         (harmonics up to {} here)",
        samples_per_period.saturating_sub(1) / 2
    )]
    DriveHarmonicAliased {
        /// The term (`the term `sin(16t)*cos(x)``) or the default library.
        what: String,
        /// Its harmonic of the drive.
        harmonic: u32,
        /// Samples per drive period of the record.
        samples_per_period: usize,
    },
    /// A record too short for what was asked of it.
    #[error("{what} needs at least {needed} samples; the record has {len}")]
    RecordTooShort {
        /// What needed the samples.
        what: &'static str,
        /// Samples given.
        len: usize,
        /// Samples needed.
        needed: usize,
    },
    /// The record's domain is not the basis' domain.
    #[error("the record is on the {record} but the basis on the {basis}")]
    DomainMismatch {
        /// The record's domain.
        record: Domain,
        /// The basis' domain.
        basis: Domain,
    },
    /// A segment split error.
    #[error(transparent)]
    Circle(circle_signal::CircleError),
    /// The orbit source failed.
    #[error("the orbit source failed: {0}")]
    Source(#[source] Box<dyn std::error::Error + Send + Sync + 'static>),
}

/// Least squares: the system does not determine the unknowns, or holds a non-finite entry.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LstsqError {
    /// The segments give no more equations than there are unknowns.
    #[error(
        "too few segments (orbits or windows): {found} found but at least {needed} are needed for the unknowns \
         of this model; use a longer record, shorter windows (orbits: a larger close-return tolerance), more \
         harmonics per segment, or a smaller basis"
    )]
    TooFewOrbits {
        /// Segments given.
        found: usize,
        /// Segments needed (each extra one counted as a period-1 orbit).
        needed: usize,
    },
    /// The stacked system does not determine every unknown.
    #[error(
        "rank-deficient system: rank {rank} for {unknowns} unknowns ({rows} equations); the term `{suspect}` \
         is (nearly) a combination of the others: drop it, use a smaller basis, or add orbits"
    )]
    RankDeficient {
        /// Numerical rank found.
        rank: usize,
        /// Number of unknowns (columns).
        unknowns: usize,
        /// Number of equations (rows).
        rows: usize,
        /// Index of the column that weighs most in the weakest singular direction of the system.
        column: usize,
        /// Its name (the term's name once assembled; `column N` from a bare solver).
        suspect: String,
    },
    /// A least-squares problem with no more rows than columns.
    #[error("least squares needs more equations than unknowns: {rows} x {cols}")]
    Underdetermined {
        /// Rows.
        rows: usize,
        /// Columns.
        cols: usize,
    },
    /// A value given to the solver is NaN or infinite.
    #[error("non-finite entry in the least-squares {what} at row {row}")]
    NonFiniteInput {
        /// `matrix` or `right-hand side`.
        what: &'static str,
        /// The row.
        row: usize,
    },
    /// The SVD did not converge.
    #[error("the singular value decomposition did not converge")]
    SvdNoConvergence,
}

/// The bootstrap over segments.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BootstrapError {
    /// Too many bootstrap resamples gave a rank-deficient or underdetermined system.
    #[error(
        "bootstrap: {failed} of {resamples} resamples did not determine every unknown (more than the \
         {allowed} allowed); use more segments or a longer record"
    )]
    BootstrapFailed {
        /// Resamples that failed.
        failed: usize,
        /// Resamples drawn.
        resamples: usize,
        /// Failures tolerated.
        allowed: usize,
    },
    /// The bootstrap needs at least two runs of consecutive segments that do not overlap:
    /// otherwise every resample is (nearly) the estimate itself and the interval would be a point.
    #[error(
        "bootstrap: {segments} segment(s) in runs of {block} cannot be resampled (at least {needed} are \
         needed); use a longer record, or no intervals"
    )]
    TooFewSegmentsToResample {
        /// Segments of the system.
        segments: usize,
        /// Consecutive segments drawn together.
        block: usize,
        /// Segments needed.
        needed: usize,
    },
}

/// Model selection.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SelectError {
    /// Model selection: with a fold of segments held out, the candidate library is not determined.
    #[error(
        "model selection: the candidate library is not determined by the data with one of {folds} folds of \
         segments held out; some candidates are (nearly) combinations of others: remove them, or use a longer record"
    )]
    SelectionUndetermined {
        /// Folds used.
        folds: usize,
    },
}

/// A tie spec ([`crate::TieSpec`]) that does not make a tied fit, or a tied fit the record does not
/// determine. Each message names the coordinate, term or parameter at fault.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TieError {
    /// No parameter, or one named twice or by an empty name.
    #[error("{0}")]
    Parameters(String),
    /// A combination names a parameter that is not in the list of parameters.
    #[error(
        "the coefficient of `{term}` in the equation of {coordinate} names the parameter '{parameter}', which is not among the parameters ({known})"
    )]
    UnknownParameter {
        /// The equation's coordinate.
        coordinate: String,
        /// The term.
        term: String,
        /// The name given.
        parameter: String,
        /// The parameters, joined.
        known: String,
    },
    /// A parameter that no coefficient uses.
    #[error("the parameter '{0}' is used by no coefficient: it cannot be identified (drop it, or use it)")]
    UnusedParameter(String),
    /// A number that is not finite, or a combination without a parameter.
    #[error("the coefficient of `{term}` in the equation of {coordinate}: {why}")]
    BadCoefficient {
        /// The equation's coordinate.
        coordinate: String,
        /// The term.
        term: String,
        /// What is wrong.
        why: &'static str,
    },
    /// An equation without its own acceleration, or with it fixed to 0.
    #[error(
        "the equation of {coordinate} {why}: give its own acceleration `{coordinate}''` a coefficient (its mass, a combination of parameters)"
    )]
    OwnAcceleration {
        /// The equation's coordinate.
        coordinate: String,
        /// What is wrong: missing or zero.
        why: &'static str,
    },
    /// An equation with no fixed coefficient: its scale is undetermined.
    #[error(
        "the equation of {0} has no fixed coefficient (a number, such as the measured torque's -1): its scale, and with it every parameter, is undetermined"
    )]
    NoFixedCoefficient(String),
    /// No equation at all.
    #[error("no equation: give one per coordinate under \"equations\"")]
    NoEquations,
    /// An equation of a coordinate the record does not have.
    #[error("the equation of '{coordinate}' is not one of the record's coordinates ({known})")]
    UnknownCoordinate {
        /// The name given.
        coordinate: String,
        /// The coordinates, joined.
        known: String,
    },
    /// A coordinate of the record without an equation in the spec.
    #[error(
        "the record's coordinate {0} has no equation in the spec: a tied fit gives every equation its terms"
    )]
    MissingEquation(String),
    /// A key that is not one term of the grammar.
    #[error("the equation of {coordinate}: `{term}`: {why}")]
    Term {
        /// The equation's coordinate.
        coordinate: String,
        /// The key as given.
        term: String,
        /// The parser's message.
        why: String,
    },
    /// The stacked system does not determine the parameters.
    #[error(
        "the parameters are not identifiable from the record: the stacked system has rank {rank} for {unknowns} parameters, and '{parameter}' weighs most in the undetermined direction (a combination of parameters that no term separates)"
    )]
    NotIdentifiable {
        /// The parameter that weighs most in the weakest direction.
        parameter: String,
        /// The numerical rank.
        rank: usize,
        /// The number of parameters.
        unknowns: usize,
    },
    /// The identified own-acceleration coefficient of an equation is zero or not finite.
    #[error(
        "the identified coefficient of {coordinate}'' is {value}: the equation cannot be normalised by its own acceleration"
    )]
    ZeroMass {
        /// The equation's coordinate.
        coordinate: String,
        /// The coefficient.
        value: f64,
    },
    /// The assembled systems do not match the spec's equations.
    #[error(
        "the tied fit was given {found} assembled system(s) for {expected} equation(s), or a system without the column of `{term}`"
    )]
    SystemMismatch {
        /// Equations of the spec.
        expected: usize,
        /// Systems given.
        found: usize,
        /// The first term not found, if any.
        term: String,
    },
}

/// Everything that can go wrong in an identification, by concern.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SolveError {
    /// The model: its terms and form, a saved model.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// Assembling the equations.
    #[error(transparent)]
    Assembly(#[from] AssemblyError),
    /// Least squares.
    #[error(transparent)]
    Lstsq(#[from] LstsqError),
    /// The bootstrap.
    #[error(transparent)]
    Bootstrap(#[from] BootstrapError),
    /// Model selection.
    #[error(transparent)]
    Select(#[from] SelectError),
    /// The tied fit of physical parameters shared by several equations.
    #[error(transparent)]
    Tie(#[from] TieError),
    /// A setting given in text that does not read as one.
    #[error("{name} '{text}': expected {expected}")]
    InvalidText {
        /// The setting.
        name: &'static str,
        /// The text given.
        text: String,
        /// What it should be.
        expected: &'static str,
    },
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

impl From<TermError> for SolveError {
    fn from(e: TermError) -> Self {
        SolveError::Model(ModelError::Term(e))
    }
}

impl From<ModelIoError> for SolveError {
    fn from(e: ModelIoError) -> Self {
        SolveError::Model(ModelError::Io(e))
    }
}

impl From<BasisError> for SolveError {
    fn from(e: BasisError) -> Self {
        SolveError::Model(ModelError::Term(TermError::Basis(e)))
    }
}

impl From<circle_signal::CircleError> for SolveError {
    fn from(e: circle_signal::CircleError) -> Self {
        SolveError::Assembly(AssemblyError::Circle(e))
    }
}
