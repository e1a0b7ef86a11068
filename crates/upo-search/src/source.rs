use serde::{Deserialize, Serialize};

/// A piece of a sampled record spanning `period` forcing periods.
///
/// Invariant: `len == period * P` for the source's `P` samples per forcing period, and
/// `start + len < signal.len()`, so the closing sample `signal[start + len]` (the first sample of
/// the next repetition) exists.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Segment {
    /// Index of the first sample.
    pub start: usize,
    /// Period `k` in forcing periods.
    pub period: usize,
    /// Number of samples, `k P` (the closing sample excluded).
    pub len: usize,
    /// Recurrence error `|S(start + len) − S(start)|` in the source's metric (radians for an
    /// angle on the circle).
    pub error: f64,
}

/// Anything that yields orbit segments of a sampled signal: close returns (unstable periodic
/// orbits, the paper's method) or plain windows (the weak form).
pub trait OrbitSource {
    /// What can go wrong.
    type Error: std::error::Error + Send + Sync + 'static;

    /// The segments of `signal` (a wrapped angle, or a displacement on the line).
    fn segments(&self, signal: &[f64]) -> Result<Vec<Segment>, Self::Error>;
}
