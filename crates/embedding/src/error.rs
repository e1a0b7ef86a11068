/// Errors of the embedding stage.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum EmbeddingError {
    /// A parameter is out of its range.
    #[error("invalid {name}: {} ({why})", circle_signal::Shown(*.value))]
    InvalidParameter {
        /// The parameter's name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What it must be.
        why: &'static str,
    },
    /// A sample is NaN or infinite.
    #[error("sample {index} is not finite ({value})")]
    NonFinite {
        /// Index of the sample.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// The record is too short for the requested operation.
    #[error("record of {len} samples is too short: at least {needed} are needed")]
    TooShort {
        /// Samples given.
        len: usize,
        /// Samples needed.
        needed: usize,
    },
    /// Every sample has the same value, so the range of the data is empty (linear metric).
    #[error("every sample equals {}: the range of the data is empty", circle_signal::Shown(*.value))]
    ConstantSignal {
        /// The common value.
        value: f64,
    },
    /// The requested lag is not shorter than the record.
    #[error("maximum lag {max_lag} must be shorter than the record ({len} samples)")]
    LagTooLarge {
        /// The maximum lag asked for.
        max_lag: usize,
        /// Samples in the record.
        len: usize,
    },
    /// The mutual information has no first minimum among the lags computed.
    #[error("the mutual information has no first minimum for lags 1..{max_lag}")]
    NoFirstMinimum {
        /// The largest lag computed.
        max_lag: usize,
    },
    /// The Theiler window excludes every candidate neighbour.
    #[error("Theiler window {theiler} leaves no candidate neighbour among {points} delay vectors")]
    TheilerTooLarge {
        /// The Theiler window.
        theiler: usize,
        /// Delay vectors available.
        points: usize,
    },
    /// No delay vector has a neighbour to test (every candidate coincides with it, lies in its
    /// Theiler window, or lies beyond the neighbour cutoff).
    #[error("no delay vector of dimension {dim} has a neighbour to test")]
    NoNeighbours {
        /// Embedding dimension.
        dim: usize,
    },
    /// More delay vectors than the k-d tree can index.
    #[error("{points} delay vectors exceed the {max} a k-d tree can index")]
    TooManyVectors {
        /// Delay vectors given.
        points: usize,
        /// The largest number accepted.
        max: usize,
    },
    /// The k-d tree could not be built.
    #[error("k-d tree of {points} points could not be built: {source}")]
    Tree {
        /// Number of points.
        points: usize,
        /// What the tree library reported.
        source: kiddo::kd_tree::ConstructionError,
    },
}
