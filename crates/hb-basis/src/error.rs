/// Errors of this crate.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum BasisError {
    /// A size parameter (order, number of nodes, degree, transform length) is too small.
    #[error("invalid {name}: {value} (must be at least {min})")]
    TooSmall {
        /// The parameter's name.
        name: &'static str,
        /// The value given.
        value: usize,
        /// The smallest accepted value.
        min: usize,
    },
    /// A size parameter is beyond what a least-squares fit of a record can determine
    /// ([`crate::MAX_FUNCTIONS`] functions).
    #[error(
        "invalid {name}: {value} (at most {max}: a basis of more than {} functions is more unknowns than a fit determines)",
        crate::MAX_FUNCTIONS
    )]
    TooLarge {
        /// The parameter's name.
        name: &'static str,
        /// The value given.
        value: usize,
        /// The largest accepted value.
        max: usize,
    },
    /// A slice does not have the length the operation needs.
    #[error("{what} has {found} elements but {expected} are needed")]
    LengthMismatch {
        /// Which slice.
        what: &'static str,
        /// Elements needed.
        expected: usize,
        /// Elements given.
        found: usize,
    },
    /// More harmonics were asked for than a segment of this length resolves.
    #[error("harmonic {requested} asked of a {len}-sample segment, which resolves harmonics 0..={max}")]
    HarmonicOutOfRange {
        /// The highest harmonic asked for.
        requested: usize,
        /// Segment length.
        len: usize,
        /// The highest harmonic the segment resolves (`len / 2`).
        max: usize,
    },
    /// A sample is NaN or infinite.
    #[error("sample {index} is not finite ({value})")]
    NonFinite {
        /// Index of the sample.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// A basis named in text that is not `harmonic:K`, `hat:N` or `poly:D`.
    #[error("{reason}")]
    BadSpec {
        /// The text.
        text: String,
        /// What is wrong with it.
        reason: String,
    },
}
