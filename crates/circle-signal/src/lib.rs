//! Angles on the circle S¹, as an encoder reports them.
//!
//! An encoder gives a whirling angle θ only modulo 2π. This crate holds the few operations every
//! later stage needs on such a signal, with one convention fixed for the whole workspace:
//!
//! - [`wrap`]: `x = ((θ + π) mod 2π) − π`, always in `[−π, π)`.
//! - [`unwrap`]: the continuous signal `x_c` whose wrap is the input; a step of the wrapped signal
//!   larger than π in magnitude is taken as a jump of 2π (so the true signal must move by less
//!   than π between two samples).
//! - [`circle_distance`]: the distance on the circle, paper eq. 19, `|a − b|_c = min(d, 2π − d)`
//!   with `d = |a − b| mod 2π`; it lies in `[0, π]`.
//! - [`max_circle_distance`]: the distance between two delay vectors, the **maximum** over components
//!   of the per-component circle distance (the Chebyshev norm on the torus). Every stage that
//!   compares delay vectors of a wrapped angle uses this one norm.
//! - [`RotationSplit`]: the split of a period-k segment into a constant rotation `w_ck τ` and an
//!   oscillation `x_var` (paper section 2, `x_ck = w_ck t + x_var,k`), needed before a whirling
//!   orbit can be expanded in a Fourier series.
//! - [`find_spikes`] / [`repair_spikes`]: outliers, isolated spikes (an encoder's bit errors) and
//!   short runs (a vibrometer's dropouts), each sample tested against the cubic through its four
//!   neighbours on the circle or the line with a robust scale that follows the local noise, and
//!   replaced by that prediction, so that no spike is unwrapped into a false turn.
//!
//! It also holds the vocabulary every later stage shares, so that each is defined once:
//!
//! - [`Domain`]: whether the measured coordinate is an angle on the circle or a displacement on
//!   the line, and the distance between samples and delay vectors that goes with it;
//! - [`SampleClock`]: the forcing period, the sample step and the time of the first sample, made
//!   once from the record;
//! - [`Segment`] and [`OrbitSource`]: pieces of the record spanning whole forcing periods, and the
//!   interface of whatever finds them (close returns, plain windows);
//! - [`system`]: the state traits of a system, one coordinate ([`SecondOrderSystem`]) or several
//!   ([`MultiSystem`]), that simulated systems and identified models both implement.
//!
//! # Example
//!
//! ```
//! use circle_signal::{circle_distance, unwrap, wrap, RotationSplit};
//! use std::f64::consts::PI;
//!
//! // A pendulum whirling once per 8 samples, with a small wobble, seen through an encoder.
//! let theta: Vec<f64> = (0..=16).map(|n| 2.0 * PI * n as f64 / 8.0 + 0.1 * (n as f64).sin()).collect();
//! let encoder: Vec<f64> = theta.iter().map(|&t| wrap(t)).collect();
//! let continuous = unwrap(&encoder);
//! for (c, t) in continuous.iter().zip(&theta) {
//!     assert!((c - t).abs() < 1e-12);
//! }
//! assert!((circle_distance(3.1, -3.1) - (2.0 * PI - 6.2)).abs() < 1e-12);
//!
//! // 16 samples spanning two forcing periods of length 2π each: h = 4π / 16.
//! let split = RotationSplit::new(&continuous, 4.0 * PI / 16.0).unwrap();
//! assert_eq!(split.winding, 2);
//! assert!((split.rate - 1.0).abs() < 1e-12); // m / k rotations per unit time, times 2π / T
//! ```
#![deny(missing_docs)]

mod clock;
mod domain;
mod integrate;
mod oscillation;
mod resample;
mod segment;
mod spikes;
pub mod system;

pub use clock::SampleClock;
pub use domain::{Domain, Shown, UnknownDomain};
pub use integrate::{Measured, UnknownMeasured, cumulative_integral, displacement};
pub use oscillation::{NoOscillationReason, OscillationPeriod, oscillation_period};
pub use resample::{
    RESAMPLE_HALF_WIDTH, Resampled, ResampledColumns, ResampledPieces, resample_columns, resample_pieces,
    resample_to_whole,
};
pub use segment::{OrbitSource, Segment};
pub use spikes::{
    Spike, SpikeParams, Spikes, find_and_repair_spikes, find_spikes, find_spikes_in_place, repair_spikes,
};
pub use system::{Branch, MultiSystem, SecondOrderSystem, SingularMass};

use std::f64::consts::{PI, TAU};

/// The longest of the pieces of a record with gaps (the first of the longest; `0..0` for none):
/// the piece that whole-record measurements (the delay, the embedding, a free oscillation's period,
/// the drive's estimate) are taken on.
///
/// ```
/// assert_eq!(circle_signal::longest_piece(&[0..5, 8..13, 20..22]), 0..5);
/// assert_eq!(circle_signal::longest_piece(&[]), 0..0);
/// ```
pub fn longest_piece(pieces: &[std::ops::Range<usize>]) -> std::ops::Range<usize> {
    pieces
        .iter()
        .rev()
        .max_by_key(|r| r.len())
        .cloned()
        .unwrap_or(0..0)
}

/// Checks the pieces of a record with gaps: non-empty ranges of `x`, in order and disjoint, every
/// sample in them finite (what lies between them, such as the NaN of a gap, is not read).
///
/// ```
/// use circle_signal::{CircleError, check_pieces};
///
/// let x = [0.1, 0.2, f64::NAN, 0.4, 0.5];
/// assert!(check_pieces(&x, &[0..2, 3..5]).is_ok());
/// assert!(matches!(check_pieces(&x, &[0..3]), Err(CircleError::NonFinite { index: 2, .. })));
/// assert!(matches!(check_pieces(&x, &[3..5, 0..2]), Err(CircleError::BadPiece { index: 1, .. })));
/// ```
pub fn check_pieces(x: &[f64], pieces: &[std::ops::Range<usize>]) -> Result<(), CircleError> {
    let mut end = 0;
    for (index, piece) in pieces.iter().enumerate() {
        if piece.start < end || piece.start >= piece.end || piece.end > x.len() {
            return Err(CircleError::BadPiece {
                index,
                start: piece.start,
                end: piece.end,
                len: x.len(),
            });
        }
        end = piece.end;
        if let Some((i, &value)) = x[piece.clone()].iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(CircleError::NonFinite {
                index: piece.start + i,
                value,
            });
        }
    }
    Ok(())
}

/// Errors of this crate.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum CircleError {
    /// A segment is too short for the operation.
    #[error("segment of {len} samples is too short: at least {needed} are needed")]
    TooShort {
        /// Samples given.
        len: usize,
        /// Samples needed.
        needed: usize,
    },
    /// A record without a drive must oscillate for its period to be measured.
    #[error("the record of {len} samples shows no oscillation to measure the period of: {reason}")]
    NoOscillation {
        /// Samples of the record.
        len: usize,
        /// What the record shows instead.
        reason: NoOscillationReason,
    },
    /// The pieces of a record with gaps must be non-empty ranges of it, in order and disjoint.
    #[error("piece {index} ({start}..{end}) is empty, out of order or beyond the record of {len} samples")]
    BadPiece {
        /// Index of the piece.
        index: usize,
        /// Its first sample.
        start: usize,
        /// One past its last sample.
        end: usize,
        /// Samples of the record.
        len: usize,
    },
    /// A sample is NaN or infinite.
    #[error("sample {index} is not finite ({value})")]
    NonFinite {
        /// Index of the sample.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// The forcing period is not a whole number of sampling steps, and the operation needs one.
    #[error(
        "the forcing period is {} sampling steps, not a whole number: this stage \
         cuts the record into whole forcing periods", crate::Shown(*.samples_per_period)
    )]
    NotWholePeriod {
        /// Samples per forcing period, `T / h`.
        samples_per_period: f64,
    },
    /// A segment's closing sample lies outside the record.
    #[error(
        "segment of {len} samples from sample {start} does not close inside the record of {record} samples"
    )]
    SegmentOutside {
        /// First sample.
        start: usize,
        /// Samples `k P`.
        len: usize,
        /// Samples in the record.
        record: usize,
    },
    /// A record is not as long as the one an operation was prepared for.
    #[error("record of {found} samples where {expected} were expected")]
    LengthMismatch {
        /// Samples expected.
        expected: usize,
        /// Samples given.
        found: usize,
    },
    /// A parameter is out of range.
    #[error("invalid {name}: {} ({why})", crate::Shown(*.value))]
    InvalidParameter {
        /// The parameter's name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What it must be.
        why: &'static str,
    },
}

/// Wraps an angle into `[−π, π)`: `((θ + π) mod 2π) − π`.
///
/// NaN and infinities give NaN.
#[inline]
pub fn wrap(theta: f64) -> f64 {
    let shifted = theta + PI;
    // Inside one turn the remainder is the number itself (exactly: a remainder is exact): the
    // same result without the division (`rem_euclid` is a call of `fmod`), for the many angles
    // that are wrapped already.
    if (0.0..TAU).contains(&shifted) {
        return shifted - PI;
    }
    let mut r = shifted.rem_euclid(TAU);
    // `rem_euclid` may round up to exactly 2π for tiny negative arguments.
    if r >= TAU {
        r -= TAU;
    }
    r - PI
}

/// Distance on the circle (paper eq. 19): `min(d, 2π − d)` with `d = |a − b| mod 2π`.
///
/// The result lies in `[0, π]`, is exactly symmetric in its arguments, and is zero for `a == b`.
#[inline]
pub fn circle_distance(a: f64, b: f64) -> f64 {
    let d = (a - b).abs().rem_euclid(TAU);
    d.min(TAU - d)
}

/// Distance between two delay vectors of a wrapped angle: the maximum over components of the
/// per-component [`circle_distance`].
///
/// # Panics
/// If the two slices have different lengths.
#[inline]
pub fn max_circle_distance(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len(), "delay vectors of different dimension");
    a.iter()
        .zip(b)
        .map(|(&x, &y)| circle_distance(x, y))
        .fold(0.0, f64::max)
}

/// Unwraps a sampled angle into a continuous signal that starts at `x[0]`.
///
/// Each step is taken modulo 2π into `(−π, π]`: the output is `x[n] + 2π m_n` with integer `m_n`,
/// so no rounding accumulates along a long record. Samples need not be wrapped on input.
pub fn unwrap(x: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(x.len());
    unwrap_into(x, &mut out);
    out
}

/// [`unwrap`] into a caller's buffer (cleared first), to reuse one allocation over many segments.
pub fn unwrap_into(x: &[f64], out: &mut Vec<f64>) {
    out.clear();
    out.extend_from_slice(x);
    unwrap_in_place(out);
}

/// [`unwrap`] in place: the same numbers, each sample's step read before it is overwritten.
pub(crate) fn unwrap_in_place(x: &mut [f64]) {
    let Some(&first) = x.first() else {
        return;
    };
    let (mut turns, mut prev) = (0.0_f64, first);
    for v in &mut x[1..] {
        let xn = *v;
        // Within half a turn the step rounds to ±0, which leaves `turns` as it is (never −0):
        // the same numbers without a call of `round` (the x86-64 baseline has no instruction for
        // it) at nearly every sample. (A NaN step is rounded, and makes every later sample NaN,
        // as always.)
        let step = (xn - prev) / TAU;
        if step.abs() >= 0.5 || step.is_nan() {
            turns -= step.round();
        }
        *v = xn + TAU * turns;
        prev = xn;
    }
}

/// A period-k segment of an unwrapped angle, split into rotation and oscillation.
///
/// With `L` samples one step `h` apart (spanning `k` forcing periods, `L h = k T`), and the
/// closing sample `x_c[L]` (the first sample of the next repetition), the winding number is
/// `m = round((x_c[L] − x_c[0]) / 2π)`, the rotation rate `w = 2π m / (L h)` (for the paper's
/// non-dimensional time, `L h = 2π k` and `w = m / k`), and the oscillation
/// `x_var[n] = x_c[n] − w n h` for `n = 0..L` is nearly periodic.
#[derive(Debug, Clone, PartialEq)]
pub struct RotationSplit {
    /// Net turns over the segment (`m`); zero for an oscillating orbit.
    pub winding: i64,
    /// Rotation rate `w_ck` in radians per unit time.
    pub rate: f64,
    /// The oscillating part `x_var`, `L` samples (the closing sample excluded).
    pub oscillation: Vec<f64>,
}

impl RotationSplit {
    /// Splits `x_c`, an unwrapped segment of `L + 1` samples (closing sample last) with sample
    /// step `h`.
    pub fn new(x_c: &[f64], step: f64) -> Result<Self, CircleError> {
        let (winding, rate) = Self::winding_and_rate(x_c, step)?;
        let l = x_c.len() - 1;
        let oscillation = x_c[..l]
            .iter()
            .enumerate()
            .map(|(n, &x)| x - rate * n as f64 * step)
            .collect();
        Ok(Self {
            winding,
            rate,
            oscillation,
        })
    }

    /// The winding number `m` and rotation rate `w` of [`RotationSplit::new`], without the
    /// oscillation (for a caller that subtracts the rotation as it goes).
    pub fn winding_and_rate(x_c: &[f64], step: f64) -> Result<(i64, f64), CircleError> {
        if !(step.is_finite() && step > 0.0) {
            return Err(CircleError::InvalidParameter {
                name: "h",
                value: step,
                why: "must be positive and finite",
            });
        }
        if x_c.len() < 3 {
            return Err(CircleError::TooShort {
                len: x_c.len(),
                needed: 3,
            });
        }
        if let Some((index, &value)) = x_c.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(CircleError::NonFinite { index, value });
        }
        let l = x_c.len() - 1;
        let turns = ((x_c[l] - x_c[0]) / TAU).round();
        Ok((turns as i64, TAU * turns / (l as f64 * step)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_edges() {
        assert_eq!(wrap(PI), -PI);
        assert_eq!(wrap(-PI), -PI);
        assert_eq!(wrap(0.0), 0.0);
        // -1e-300 + π rounds to π: the nearest representable answer is 0.
        assert_eq!(wrap(-1e-300), 0.0);
        assert!(wrap(f64::NAN).is_nan());
        assert!(wrap(f64::INFINITY).is_nan());
        let w = wrap(-PI - 1e-17);
        assert!((-PI..PI).contains(&w), "{w}");
    }

    #[test]
    fn distance_values() {
        assert_eq!(circle_distance(0.0, PI), PI);
        assert!((circle_distance(-3.0, 3.0) - (TAU - 6.0)).abs() < 1e-15);
        assert_eq!(max_circle_distance(&[0.0, 1.0], &[0.5, 1.25]), 0.5);
    }

    #[test]
    fn unwrap_linear_ramp() {
        let theta: Vec<f64> = (0..100).map(|n| -0.9 * n as f64).collect();
        let w: Vec<f64> = theta.iter().map(|&t| wrap(t)).collect();
        let u = unwrap(&w);
        for (a, b) in u.iter().zip(&theta) {
            assert!((a - b).abs() < 1e-12);
        }
        assert!(unwrap(&[]).is_empty());
    }

    #[test]
    fn split_errors() {
        assert!(matches!(
            RotationSplit::new(&[0.0, 1.0], 0.1),
            Err(CircleError::TooShort { .. })
        ));
        assert!(RotationSplit::new(&[0.0, 1.0, 2.0], 0.0).is_err());
        assert!(RotationSplit::new(&[0.0, f64::NAN, 2.0], 0.1).is_err());
    }

    #[test]
    fn split_oscillating_orbit_has_zero_winding() {
        let h = TAU / 25.0;
        let x: Vec<f64> = (0..=25).map(|n| 1.2 * (n as f64 * h).sin()).collect();
        let s = RotationSplit::new(&x, h).unwrap();
        assert_eq!(s.winding, 0);
        assert_eq!(s.rate, 0.0);
        assert_eq!(s.oscillation.len(), 25);
    }
}
