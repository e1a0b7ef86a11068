//! The one error type of this crate.

/// Everything that can go wrong in a close-return search.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum UpoError {
    /// The tolerance, a fraction of the span of the data, is outside `(0, 0.5)`.
    #[error("invalid tolerance {}: it is a fraction of the span of the data and must lie in (0, 0.5)", circle_signal::Shown(*.value))]
    InvalidTolerance {
        /// The fraction given.
        value: f64,
    },
    /// A count parameter (period, dimension, delay, samples per period) is out of range.
    #[error("invalid {name}: {value} ({why})")]
    InvalidCount {
        /// The parameter's name.
        name: &'static str,
        /// The value given.
        value: usize,
        /// What it must be.
        why: &'static str,
    },
    /// The record is too short for the longest period searched.
    #[error(
        "record of {len} samples is too short for period {period}: at least {needed} samples are needed \
         (k P + (d - 1) Td + 1)"
    )]
    TooShort {
        /// Samples given.
        len: usize,
        /// Samples needed.
        needed: usize,
        /// The period (in forcing periods) that does not fit.
        period: usize,
    },
    /// A sample is NaN or infinite.
    #[error("sample {index} is not finite ({value})")]
    NonFinite {
        /// Index of the sample.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// The clock cannot cut the record into whole forcing periods, or a segment does not fit.
    #[error(transparent)]
    Clock(#[from] circle_signal::CircleError),
    /// With the linear metric, a constant record has zero span and so no tolerance.
    #[error("the record is constant ({}): its span is zero, so a tolerance relative to it is zero", circle_signal::Shown(*.value))]
    ConstantSignal {
        /// The constant value.
        value: f64,
    },
}
