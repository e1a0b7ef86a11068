//! The drift of a displacement integrated from a velocity or an acceleration record, found by
//! the model.
//!
//! Integrating a velocity leaves the displacement's offset unknown; integrating an acceleration
//! twice leaves an offset and a slope unknown (the initial displacement and velocity).
//! [`circle_signal::displacement`] removes each piece's mean (velocity) or least-squares line
//! (acceleration), which is right only if the true displacement has no mean and no trend over
//! the piece. A bounded oscillation has a trend of the order of its range over the piece's
//! length: on a 300-period record of a chaotic two-well oscillator the least-squares line of the
//! true displacement rises by 0.21 over the record (wells at ±1), and the coefficients come out
//! 15 % wrong.
//!
//! The weak form sees a linear drift `a + b t` only through the functions of `x` (the test
//! functions annihilate it in `x''`, and it adds a constant to `x'`): so the drift that makes the
//! model explain the most of the record is the record's. [`fit_drift`] finds, piece by piece,
//! the slope (acceleration records) and the offset (when the model has no constant term `1`
//! that absorbs it) that minimise the unexplained fraction of the identification, by a scan of
//! [`SCAN_POINTS`] values over the range a bounded signal allows, then golden-section search.

use std::ops::Range;

use circle_signal::{Measured, Segment};

use crate::{Identifier, Signals, SolveError};

/// Values of each unknown scanned before the golden-section search.
pub const SCAN_POINTS: usize = 24;
/// Golden-section steps after the scan (the bracket shrinks by 0.618 each step).
pub const GOLDEN_STEPS: usize = 40;

/// The drift found for one piece of the record.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PieceDrift {
    /// The slope added to the piece, per sample, about its middle sample.
    pub slope: f64,
    /// The offset added to the piece.
    pub offset: f64,
}

/// What [`fit_drift`] found and did.
#[derive(Debug, Clone, PartialEq)]
pub struct DriftFit {
    /// One per piece of the record.
    pub pieces: Vec<PieceDrift>,
    /// The unexplained fraction before and after.
    pub unexplained_before: f64,
    /// The unexplained fraction with the drift removed.
    pub unexplained_after: f64,
    /// Identifications run.
    pub evaluations: usize,
}

/// Finds the drift of `x` (integrated from a record of `measured`) that the model of `setup`
/// explains best over `segments`, piece by piece, and returns `x` with it added. Nothing to
/// find for a displacement record, or when the model has a constant term and the record was a
/// velocity. The setup's bootstrap is not run. `progress(done, total)` is called after each
/// identification. `drives` are the record's measured drives, which the model's terms may read.
pub fn fit_drift(
    setup: &Identifier,
    x: &[f64],
    drives: &[&[f64]],
    pieces: &[Range<usize>],
    segments: &[Segment],
    measured: Measured,
    mut progress: impl FnMut(usize, usize),
) -> Result<(Vec<f64>, DriftFit), SolveError> {
    let mut x = x.to_vec();
    let unexplained = |x: &[f64]| setup.unexplained(Signals::one(x).with_drives(drives.to_vec())?, segments);
    let (before, has_constant) = unexplained(&x)?;
    let fit_slope = measured == Measured::Acceleration;
    let fit_offset = measured != Measured::Displacement && !has_constant;
    let unknowns = usize::from(fit_slope) + usize::from(fit_offset);
    let total = pieces.len() * unknowns * (SCAN_POINTS + GOLDEN_STEPS + 1);
    let mut evaluations = 0;
    let mut objective = |x: &[f64]| -> Result<f64, SolveError> {
        evaluations += 1;
        progress(evaluations, total);
        Ok(unexplained(x)?.0)
    };
    let mut drifts = vec![
        PieceDrift {
            slope: 0.0,
            offset: 0.0
        };
        pieces.len()
    ];
    for (piece, drift) in pieces.iter().zip(&mut drifts) {
        // Only pieces that hold a segment count.
        if !segments
            .iter()
            .any(|s| s.start() >= piece.start && s.start() < piece.end)
        {
            continue;
        }
        let values = &x[piece.clone()];
        let (lo, hi) = values
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            });
        let range = hi - lo;
        if !range.is_finite() || range <= 0.0 {
            continue;
        }
        let middle = (piece.start + piece.end - 1) as f64 / 2.0;
        let len = piece.len() as f64;
        if fit_slope {
            // The least-squares slope of a signal within a range R over L samples is at most
            // 1.5 R / L (a step from one end of the range to the other at the middle).
            let bound = 1.5 * range / len;
            let base = x.clone();
            let slope = minimise(-bound, bound, |b| {
                let mut trial = base.clone();
                for (i, v) in trial[piece.clone()].iter_mut().enumerate() {
                    *v += b * ((piece.start + i) as f64 - middle);
                }
                objective(&trial)
            })?;
            for (i, v) in x[piece.clone()].iter_mut().enumerate() {
                *v += slope * ((piece.start + i) as f64 - middle);
            }
            drift.slope = slope;
        }
        if fit_offset {
            // The integrated piece has zero mean; the true one's mean is within its range.
            let base = x.clone();
            let offset = minimise(-range, range, |a| {
                let mut trial = base.clone();
                for v in &mut trial[piece.clone()] {
                    *v += a;
                }
                objective(&trial)
            })?;
            for v in &mut x[piece.clone()] {
                *v += offset;
            }
            drift.offset = offset;
        }
    }
    let after = unexplained(&x)?.0;
    Ok((
        x,
        DriftFit {
            pieces: drifts,
            unexplained_before: before,
            unexplained_after: after,
            evaluations,
        },
    ))
}

/// The minimiser of `f` on `[lo, hi]`: the best of [`SCAN_POINTS`] equally spaced values, then
/// golden-section search between its neighbours. A value that fails to evaluate is an error.
pub fn minimise<E>(lo: f64, hi: f64, mut f: impl FnMut(f64) -> Result<f64, E>) -> Result<f64, E> {
    let n = SCAN_POINTS;
    let at = |k: usize| lo + (hi - lo) * k as f64 / (n - 1) as f64;
    let mut best = (0, f64::INFINITY);
    for k in 0..n {
        let v = f(at(k))?;
        if v < best.1 {
            best = (k, v);
        }
    }
    let (mut a, mut b) = (at(best.0.saturating_sub(1)), at((best.0 + 1).min(n - 1)));
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let mut c = b - g * (b - a);
    let mut d = a + g * (b - a);
    let (mut fc, mut fd) = (f(c)?, f(d)?);
    for _ in 2..GOLDEN_STEPS {
        if fc < fd {
            b = d;
            d = c;
            fd = fc;
            c = b - g * (b - a);
            fc = f(c)?;
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + g * (b - a);
            fd = f(d)?;
        }
    }
    let middle = 0.5 * (a + b);
    // The scan's best stands if the refined value is no better (a flat or noisy objective).
    let refined = f(middle)?;
    Ok(if refined <= best.1 { middle } else { at(best.0) })
}
