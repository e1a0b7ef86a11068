//! The per-sample distances of the hot loops, one type per [`crate::Domain`] case.

use circle_signal::circle_distance;
use std::f64::consts::TAU;

/// A per-sample distance, chosen once per search so that the hot loops are monomorphic.
pub(crate) trait Distance: Copy + Send + Sync {
    /// The distance between two samples.
    fn between(self, a: f64, b: f64) -> f64;
}

/// The circle distance for samples in `[−π, π]`.
///
/// There `|a − b| ≤ 2π`, and the branch-free `min(d, 2π − d)` equals
/// [`circle_distance`] bit for bit (its `rem_euclid` is then the identity, or maps exactly 2π to 0,
/// which `min` also gives).
#[derive(Debug, Clone, Copy)]
pub(crate) struct WrappedCircle;

impl Distance for WrappedCircle {
    #[inline(always)]
    fn between(self, a: f64, b: f64) -> f64 {
        let d = (a - b).abs();
        let e = TAU - d;
        // `d.min(e)` for non-NaN operands, without `min`'s NaN handling (so it vectorizes to
        // one `minpd`).
        if e < d { e } else { d }
    }
}

/// The circle distance for any finite samples.
#[derive(Debug, Clone, Copy)]
pub(crate) struct AnyCircle;

impl Distance for AnyCircle {
    #[inline(always)]
    fn between(self, a: f64, b: f64) -> f64 {
        circle_distance(a, b)
    }
}

/// The distance on the line.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Line;

impl Distance for Line {
    #[inline(always)]
    fn between(self, a: f64, b: f64) -> f64 {
        (a - b).abs()
    }
}
