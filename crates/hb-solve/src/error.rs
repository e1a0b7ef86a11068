use hb_basis::{BasisError, Domain};

/// Errors of identification.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SolveError {
    /// The segments give no more equations than there are unknowns.
    #[error(
        "too few orbits: {found} segment(s) found but at least {needed} are needed for the unknowns of this \
         model; use a larger close-return tolerance, a longer record, more harmonics per orbit, or a smaller basis"
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
    /// A term has the measured drive `p` but the params hold no samples of it.
    #[error(
        "the term `{term}` has the measured drive p, but no samples of it were given (IdentifyParamsBuilder::drive_samples)"
    )]
    MissingDriveSamples {
        /// The first term in `p`.
        term: String,
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
    /// A value given to the solver is NaN or infinite.
    #[error("non-finite entry in the least-squares {what} at row {row}")]
    NonFiniteInput {
        /// `matrix` or `right-hand side`.
        what: &'static str,
        /// The row.
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
    #[error("invalid {name}: {value} ({why})")]
    InvalidParameter {
        /// The parameter's name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What it must be.
        why: &'static str,
    },
    /// A model term that does not belong on the basis' domain.
    #[error("the term `{term}` cannot be used with a basis on the {domain:?} domain: {why}")]
    TermNotAllowed {
        /// The term's name.
        term: String,
        /// The basis' domain.
        domain: Domain,
        /// Why.
        why: &'static str,
    },
    /// A term that a computation does not handle.
    #[error("the term `{term}` is not supported by {by}")]
    TermNotSupported {
        /// The term's name.
        term: String,
        /// What does not support it.
        by: &'static str,
    },
    /// A list of terms that does not parse.
    #[error("term list \"{spec}\": at character {at}, expected {expected}; found {found}")]
    TermSyntax {
        /// The list as given.
        spec: String,
        /// 1-based position of the character where the error is (one past the end at the end).
        at: usize,
        /// What was found there.
        found: String,
        /// What was expected.
        expected: &'static str,
    },
    /// Factors that do not make a term together.
    #[error("term list \"{spec}\": the product at character {at} is not a term: {why}")]
    TermProduct {
        /// The list as given.
        spec: String,
        /// 1-based position of the offending factor.
        at: usize,
        /// Why.
        why: &'static str,
    },
    /// A term named twice in a list.
    #[error("the term `{term}` is named twice (again at character {at} of the list)")]
    DuplicateTerm {
        /// The term.
        term: String,
        /// Where it appears again (1-based character of its item; for a list built from terms,
        /// the 1-based index of the term).
        at: usize,
    },
    /// A list of terms with too many of them.
    #[error("{count} terms are too many (at most {max})")]
    TooManyTerms {
        /// Terms asked for.
        count: usize,
        /// The most allowed.
        max: usize,
    },
    /// A term whose function of `x` the basis does not have.
    #[error(
        "the term `{term}` needs the function {function}, which the basis ({}) does not have; choose a basis \
         that holds it (e.g. harmonic:2 for cos(2x), poly:3 for x^3, hat:8 for hat7)", basis.join(", ")
    )]
    TermNotInBasis {
        /// The term.
        term: String,
        /// Its function of `x`.
        function: String,
        /// The basis' functions.
        basis: Vec<String>,
    },
    /// Functions of `x` of two kinds of basis in one list.
    #[error(
        "the functions {first} and {second} come from different bases (harmonic, polynomial, hat): one basis holds the functions of a model"
    )]
    MixedBases {
        /// A function of one kind.
        first: String,
        /// One of another.
        second: String,
    },
    /// A model form whose parts contradict each other.
    #[error("invalid model form: {why}")]
    InvalidForm {
        /// Why.
        why: &'static str,
    },
    /// The noise correction cannot be applied to a term of this model.
    #[error("no noise correction for the term `{term}`: {why}")]
    NoiseCorrectionUnavailable {
        /// The term (basis function) concerned.
        term: String,
        /// Why.
        why: &'static str,
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
    /// Model selection: with a fold of segments held out, the candidate library is not determined.
    #[error(
        "model selection: the candidate library is not determined by the data with one of {folds} folds of \
         segments held out; some candidates are (nearly) combinations of others: remove them, or use a longer record"
    )]
    SelectionUndetermined {
        /// Folds used.
        folds: usize,
    },
    /// The model form has no term with the drive, so its residual does not depend on the forcing
    /// period.
    #[error(
        "the model form has no drive term (no parametric terms, no external forcing): the forcing period \
         cannot be estimated from its residual"
    )]
    NoDriveTerm,
    /// The record's domain is not the basis' domain.
    #[error("the record is on the {record} but the basis on the {basis}")]
    DomainMismatch {
        /// The record's domain.
        record: Domain,
        /// The basis' domain.
        basis: Domain,
    },
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
    /// The SVD did not converge.
    #[error("the singular value decomposition did not converge")]
    SvdNoConvergence,
    /// A basis or Fourier error.
    #[error(transparent)]
    Basis(#[from] BasisError),
    /// A segment split error.
    #[error(transparent)]
    Circle(#[from] circle_signal::CircleError),
    /// The orbit source failed.
    #[error("the orbit source failed: {0}")]
    Source(#[source] Box<dyn std::error::Error + Send + Sync + 'static>),
    /// A saved model does not start with the magic bytes.
    #[error("not a saved model: the first bytes are not the model magic number")]
    BadMagic,
    /// A saved model of another format version.
    #[error(
        "saved model format version {found} is not supported (this build reads versions 2 to {supported})"
    )]
    UnsupportedVersion {
        /// Version in the file.
        found: u32,
        /// The newest version this build reads, the one it writes.
        supported: u32,
    },
    /// A saved model whose coefficients do not match its basis and form.
    #[error("saved model is inconsistent: expected the terms {expected:?}, found {found:?}")]
    ModelMismatch {
        /// Terms implied by the basis and form.
        expected: Vec<String>,
        /// Terms in the file.
        found: Vec<String>,
    },
    /// A saved model with a non-finite number.
    #[error("saved model has a non-finite value for `{name}`")]
    NonFiniteModelValue {
        /// Which value.
        name: String,
    },
    /// JSON (de)serialisation failed.
    #[error("JSON: {0}")]
    Json(#[from] serde_json::Error),
    /// Binary (de)serialisation failed.
    #[error("binary model: {0}")]
    Postcard(#[from] postcard::Error),
}
