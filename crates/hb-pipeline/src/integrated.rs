//! A velocity or acceleration record made a displacement for a saved model's free run
//! (`compare` and `report --model` with `measured`, a model of one coordinate on the line).
//!
//! Integrating a velocity leaves each piece's offset unknown; integrating an acceleration twice
//! leaves its offset and its velocity's offset unknown. `hb_solve::drift` finds them in an
//! identification by the fit itself; a saved model is a fit already, so here they are the
//! constants with which the model's own equation holds best on the piece, its coefficients fixed:
//!
//! - a velocity `v`: the displacement `x = ∫v + c`, and `c` minimises `Σ_k R_k²` with
//!   `R_k = v(e_k) − v(b_k) − ∫_{b_k}^{e_k} F(t, x, v) dt` over consecutive windows of
//!   [`WINDOW`] samples: the equation integrated, so that no measured sample is differentiated;
//! - an acceleration `a`: `v = ∫a + s` and `x = ∫∫a + s (t − t_m) + c`, and `(s, c)` minimise
//!   `Σ_i (a_i − F(t_i, x_i, v_i))²`, the equation at each sample.
//!
//! Every integral is the identification's sixth-order rule ([`circle_signal::cumulative_integral`]).
//! Each unknown is scanned ([`hb_solve::drift::minimise`]) over the integral's range about 0, the
//! bracket doubled about the best value while that value lies at its edge (a record whose mean is
//! far from the integral's, an oscillation about 5); an acceleration's two, which move together,
//! are then refined together by Gauss–Newton with the model's Jacobian. A constant that the
//! model's equation does not see (the offset of a model with no stiffness) stays 0, the integral's
//! mean: the free run from a state fitted to the samples does not see it either. A piece too
//! short for the constants ([`MIN_SAMPLES`]) is left out as a gap, and said so.

use std::ops::Range;

use circle_signal::{Measured, SecondOrderSystem};
use hb_model::IdentifiedModel;
use hb_record::prepare::GridData;
use rayon::prelude::*;

use crate::compare::driven_on;
use crate::error::RunError;
use crate::options::OptionError;

/// Samples of each window of a velocity piece's integrated equation.
pub const WINDOW: usize = 8;

/// The fewest samples of a piece whose constants are found (two windows and one): a shorter one
/// is left out, as a gap.
pub const MIN_SAMPLES: usize = 2 * WINDOW + 1;

/// The fraction of the measured side left unexplained above which the constants, and the scores,
/// are warned of.
pub const UNEXPLAINED_WARNING: f64 = 1e-2;

/// The integration's constants found for one piece.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PieceConstants {
    /// The piece's samples.
    pub start: usize,
    /// Its end (exclusive).
    pub end: usize,
    /// The offset added to the velocity (an acceleration record's; 0 for a velocity).
    pub velocity: f64,
    /// The offset added to the displacement, after the integral's mean (or, with a velocity
    /// found, its least-squares line) was taken out.
    pub offset: f64,
    /// The fraction of the measured side the model's equation leaves unexplained with the
    /// constants found (`Σ R² / Σ (measured side)²`).
    pub unexplained: f64,
}

/// What [`integrate`] found and did.
#[derive(Debug, Clone, PartialEq)]
pub struct Integration {
    /// The constants of each piece integrated.
    pub pieces: Vec<PieceConstants>,
    /// Pieces shorter than [`MIN_SAMPLES`], left out as gaps: `(start, end)`.
    pub left_out: Vec<(usize, usize)>,
}

/// That `model` can be run against a record integrated from `measured`: a displacement needs
/// nothing; a velocity or an acceleration is integrated on the line, so a model on the circle is
/// refused (before the record is read, by each front end that integrates).
pub fn check_model(model: &IdentifiedModel, measured: Measured) -> Result<(), OptionError> {
    if measured != Measured::Displacement && model.domain() == circle_signal::Domain::Circle {
        return Err(OptionError::value(
            "measured",
            measured,
            "a model on the circle is not compared with a velocity or acceleration record (integrated on the line)",
        ));
    }
    Ok(())
}

/// `grid.x`, read as `measured` (a velocity or an acceleration), replaced by the displacement
/// with each piece's constants that `model` explains best; what was found (a displacement is
/// left as it is). Pieces of fewer than [`MIN_SAMPLES`] samples are left out of the grid's
/// pieces (their samples NaN, as a gap's).
///
/// Errors: a model on the circle ([`check_model`]), every piece too short, a measured drive the
/// model cannot be driven by.
pub fn integrate(
    model: &IdentifiedModel,
    grid: &mut GridData,
    measured: Measured,
) -> Result<Integration, RunError> {
    check_model(model, measured)?;
    let mut found = Vec::new();
    let mut left_out = Vec::new();
    if measured == Measured::Displacement {
        return Ok(Integration {
            pieces: found,
            left_out,
        });
    }
    let pieces: Vec<Range<usize>> = grid.pieces.clone();
    let mut x = grid.x.clone();
    let mut kept = Vec::with_capacity(pieces.len());
    for r in pieces {
        if r.len() < MIN_SAMPLES {
            x[r.clone()].fill(f64::NAN);
            left_out.push((r.start, r.end));
            continue;
        }
        let driven = driven_on(model, grid, r.start, r.end)?;
        let t: Vec<f64> = (r.start..r.end).map(|i| grid.t0 + i as f64 * grid.dt).collect();
        let raw = &grid.x[r.clone()];
        let constants = match measured {
            Measured::Displacement => continue,
            Measured::Velocity => velocity_piece(&driven, &t, raw, grid.dt, &mut x[r.clone()]),
            Measured::Acceleration => acceleration_piece(&driven, &t, raw, grid.dt, &mut x[r.clone()]),
        };
        found.push(PieceConstants {
            start: r.start,
            end: r.end,
            ..constants
        });
        kept.push(r);
    }
    if kept.is_empty() {
        return Err(OptionError::value(
            "measured",
            measured,
            format!(
                "every piece of the record is shorter than {MIN_SAMPLES} samples: too short to find its \
                 integration's constants"
            ),
        )
        .into());
    }
    grid.x = x;
    grid.pieces = kept;
    Ok(Integration {
        pieces: found,
        left_out,
    })
}

/// What an integration tells a run: the note of the constants and, when a piece's equation
/// leaves more than [`UNEXPLAINED_WARNING`] of its measured side unexplained, a warning that the
/// scores include the integration's error.
pub fn notices(measured: Measured, integration: &Integration) -> Vec<crate::observe::Notice> {
    use crate::observe::Notice;
    let mut out = vec![Notice::Integrated {
        measured,
        integration: integration.clone(),
    }];
    if let Some(worst) = integration
        .pieces
        .iter()
        .filter(|p| p.unexplained > UNEXPLAINED_WARNING || p.unexplained.is_nan())
        .max_by(|a, b| a.unexplained.total_cmp(&b.unexplained))
    {
        out.push(Notice::Warning(format!(
            "the model's equation leaves {:.2e} of the measured {measured} unexplained on samples {}..{} with the \
             best constants found: the integrated displacement, and the scores against it, carry that error (a \
             model that does not describe the record, noise the integral accumulates, or too few samples per \
             period for the integral)",
            worst.unexplained, worst.start, worst.end
        )));
    }
    out
}

/// `∫ y dt` from 0 at the first sample, by the sixth-order rule of the identification's
/// integration ([`circle_signal::cumulative_integral`]; trapezoids below its 4 samples, or for
/// a value that is not finite).
fn cumulative(y: &[f64], dt: f64) -> Vec<f64> {
    circle_signal::cumulative_integral(y, dt).unwrap_or_else(|_| {
        let mut out = Vec::with_capacity(y.len());
        let mut sum = 0.0;
        for (i, &v) in y.iter().enumerate() {
            if i > 0 {
                sum += 0.5 * dt * (y[i - 1] + v);
            }
            out.push(sum);
        }
        out
    })
}

/// `y` less its mean.
fn centred(mut y: Vec<f64>) -> Vec<f64> {
    let mean = y.iter().sum::<f64>() / y.len().max(1) as f64;
    y.iter_mut().for_each(|v| *v -= mean);
    y
}

/// The range `max − min` of `y`.
fn range(y: &[f64]) -> f64 {
    let (lo, hi) = y.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
        (lo.min(v), hi.max(v))
    });
    hi - lo
}

/// A velocity piece `v`: `out` gets `∫v` (mean taken out) plus the offset found.
fn velocity_piece<S: SecondOrderSystem + Sync>(
    model: &S,
    t: &[f64],
    v: &[f64],
    dt: f64,
    out: &mut [f64],
) -> PieceConstants {
    let x = centred(cumulative(v, dt));
    let n = v.len();
    let windows: Vec<(usize, usize)> = (0..n.saturating_sub(1) / WINDOW)
        .map(|k| (k * WINDOW, (k + 1) * WINDOW))
        .collect();
    let measured: f64 = windows.iter().map(|&(b, e)| (v[e] - v[b]).powi(2)).sum();
    let residual = |c: f64| -> f64 {
        // Each sample's acceleration on the pool (collected in order: the sums below stay the
        // same from run to run).
        let a: Vec<f64> = (0..n)
            .into_par_iter()
            .map(|i| model.acceleration(t[i], x[i] + c, v[i]))
            .collect();
        let integral = cumulative(&a, dt);
        windows
            .iter()
            .map(|&(b, e)| (v[e] - v[b] - (integral[e] - integral[b])).powi(2))
            .sum()
    };
    let span = range(&x);
    let offset = if windows.len() >= 2 && span.is_finite() && span > 0.0 {
        widening(span, good(windows.len(), measured), residual)
    } else {
        0.0
    };
    for (o, xi) in out.iter_mut().zip(&x) {
        *o = xi + offset;
    }
    PieceConstants {
        start: 0,
        end: 0,
        velocity: 0.0,
        offset,
        unexplained: relative(residual(offset), measured),
    }
}

/// An acceleration piece `a`: `out` gets `∫∫a` (its least-squares line taken out) plus the
/// velocity and the offset found.
fn acceleration_piece<S: SecondOrderSystem + Sync>(
    model: &S,
    t: &[f64],
    a: &[f64],
    dt: f64,
    out: &mut [f64],
) -> PieceConstants {
    let n = a.len();
    let v0 = centred(cumulative(a, dt));
    let x0 = cumulative(&v0, dt);
    // The line of x0 taken out, and its slope from the velocity, so that x stays ∫v.
    let middle = 0.5 * (t[0] + t[n - 1]);
    let (slope, mean) = line(t, &x0, middle);
    let x: Vec<f64> = x0
        .iter()
        .zip(t)
        .map(|(x, &ti)| x - mean - slope * (ti - middle))
        .collect();
    let v: Vec<f64> = v0.iter().map(|v| v - slope).collect();
    let measured: f64 = a.iter().map(|a| a * a).sum();
    let residual = |s: f64, c: f64| -> f64 {
        let squares: Vec<f64> = (0..n)
            .into_par_iter()
            .map(|i| (a[i] - model.acceleration(t[i], x[i] + s * (t[i] - middle) + c, v[i] + s)).powi(2))
            .collect();
        squares.iter().sum()
    };
    let (span_x, span_v) = (range(&x), range(&v));
    let (mut s, mut c) = (0.0, 0.0);
    if n >= 2 * WINDOW && span_x.is_finite() && span_x > 0.0 && span_v.is_finite() {
        // The least-squares slope of a signal within a range R over a time L is at most
        // 1.5 R / L: a true velocity's offset within its range of that (to begin with).
        let bound = span_v.max(1.5 * span_x / (t[n - 1] - t[0]));
        let good = good(n / WINDOW, measured);
        // The two move together: scanned one after the other for the basin (the offset first, as
        // a bounded oscillation's velocity has about the integral's mean while its offset can be
        // a well away; on a short piece the velocity first too, the lower kept), then refined
        // together by Gauss–Newton.
        let search = |offset_first: bool| {
            let (mut s, mut c) = (0.0, 0.0);
            for _ in 0..2 {
                if offset_first {
                    c = widening(span_x, good, |c| residual(s, c));
                    s = widening(bound, good, |s| residual(s, c));
                } else {
                    s = widening(bound, good, |s| residual(s, c));
                    c = widening(span_x, good, |c| residual(s, c));
                }
            }
            gauss_newton(model, t, a, &x, &v, middle, (s, c), &residual)
        };
        let first = search(true);
        (s, c) = first;
        // A short piece (every bracket searched) is searched the other way too; a long one,
        // whose equation holds in one basin, once (noise that keeps it above `good` would
        // otherwise double the work for nothing).
        if good == 0.0 {
            let second = search(false);
            if residual(second.0, second.1) < residual(first.0, first.1) {
                (s, c) = second;
            }
        }
    }
    for (i, o) in out.iter_mut().enumerate() {
        *o = x[i] + s * (t[i] - middle) + c;
    }
    PieceConstants {
        start: 0,
        end: 0,
        velocity: s,
        offset: c,
        unexplained: relative(residual(s, c), measured),
    }
}

/// The least-squares line `y ≈ mean + slope (t − middle)`: `(slope, mean)`.
fn line(t: &[f64], y: &[f64], middle: f64) -> (f64, f64) {
    let n = y.len() as f64;
    let mean = y.iter().sum::<f64>() / n;
    let (mut sxy, mut sxx) = (0.0, 0.0);
    let tm = t.iter().sum::<f64>() / n;
    for (&ti, &yi) in t.iter().zip(y) {
        sxy += (ti - tm) * (yi - mean);
        sxx += (ti - tm) * (ti - tm);
    }
    let slope = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    // The line's value at `middle`.
    (slope, mean + slope * (middle - tm))
}

/// `(s, c)` refined from `start` by Gauss–Newton on the residuals `a_i − F(t_i, x_i + s (t_i −
/// middle) + c, v_i + s)` with the model's Jacobian, each step halved until it lowers
/// `residual`; at most 50 steps.
#[allow(clippy::too_many_arguments)]
fn gauss_newton<S: SecondOrderSystem>(
    model: &S,
    t: &[f64],
    a: &[f64],
    x: &[f64],
    v: &[f64],
    middle: f64,
    start: (f64, f64),
    residual: &dyn Fn(f64, f64) -> f64,
) -> (f64, f64) {
    let (mut s, mut c) = start;
    let mut current = residual(s, c);
    for _ in 0..50 {
        // Normal equations of the 2 × 2 problem.
        let (mut jss, mut jsc, mut jcc, mut gs, mut gc) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for i in 0..t.len() {
            let dt = t[i] - middle;
            let (xi, vi) = (x[i] + s * dt + c, v[i] + s);
            let r = a[i] - model.acceleration(t[i], xi, vi);
            let [fx, fv] = model.jacobian(t[i], xi, vi);
            // ∂r/∂s and ∂r/∂c.
            let (js, jc) = (-(fx * dt + fv), -fx);
            jss += js * js;
            jsc += js * jc;
            jcc += jc * jc;
            gs += js * r;
            gc += jc * r;
        }
        let det = jss * jcc - jsc * jsc;
        if !(det.is_finite() && det > 0.0) {
            break;
        }
        let (ds, dc) = (-(jcc * gs - jsc * gc) / det, -(jss * gc - jsc * gs) / det);
        let mut step = 1.0;
        let mut moved = false;
        while step > 1e-6 {
            let trial = residual(s + step * ds, c + step * dc);
            if trial < current {
                (s, c, current) = (s + step * ds, c + step * dc, trial);
                moved = true;
                break;
            }
            step *= 0.5;
        }
        if !moved
            || (step * ds).abs() <= 1e-14 * (1.0 + s.abs()) && (step * dc).abs() <= 1e-14 * (1.0 + c.abs())
        {
            break;
        }
    }
    (s, c)
}

/// The minimiser of `f`: scanned over `[−width, width]`, then over brackets doubled (at most
/// [`WIDENINGS`] times, to 10³ times the first) while the best value so far lies at the
/// bracket's edge or is above `good` (a basin of its own within the first bracket, as the wrong
/// well of a two-well oscillator), centred on that value when it lies at the edge. A wider
/// bracket's best replaces the one so far only when it is lower by more than [`BETTER`] of it,
/// and the result is 0 unless it is that much lower than at 0: a constant the equation hardly
/// sees (a stiffness of 1e-12) stays the integral's mean rather than running off.
fn widening(width: f64, good: f64, mut f: impl FnMut(f64) -> f64) -> f64 {
    let at_zero = f(0.0);
    let (mut centre, mut width) = (0.0, width);
    let (mut found, mut value) = (0.0, at_zero);
    let mut idle = 0;
    for _ in 0..WIDENINGS {
        let next = best(centre - width, centre + width, &mut f);
        let next_value = f(next);
        let edge = 2.0 * width / (hb_solve::drift::SCAN_POINTS - 1) as f64;
        let at_edge = (next - (centre - width)).abs() <= edge || (centre + width - next).abs() <= edge;
        let better = next_value.is_finite() && next_value < value * (1.0 - BETTER);
        if better {
            (found, value, idle) = (next, next_value, 0);
        } else {
            idle += 1;
        }
        // Good, and inside its bracket: found. Doubling after doubling without a better value
        // (a flat objective, or one only noise keeps above `good`): nothing further to find.
        // (A value that is NaN is not good.)
        let good_enough = value <= good;
        if (good_enough && !(better && at_edge)) || idle >= IDLE {
            break;
        }
        if better && at_edge {
            centre = found;
        }
        width *= 2.0;
    }
    if value.is_finite() && value < at_zero * (1.0 - BETTER) {
        found
    } else {
        0.0
    }
}

/// The value of the objective below which [`widening`] takes a basin for the one: a piece of
/// [`FEW_WINDOWS`] windows or more, whose equation holds in one basin alone, stops at the first
/// that leaves at most [`UNEXPLAINED_WARNING`] of the `measured` side unexplained; a shorter one,
/// which the wrong well of a two-well oscillator can explain to a few thousandths, searches
/// every bracket for the lowest (0).
fn good(windows: usize, measured: f64) -> f64 {
    if windows >= FEW_WINDOWS {
        UNEXPLAINED_WARNING * measured
    } else {
        0.0
    }
}

/// Windows (of [`WINDOW`] samples) below which a piece's constants are searched over every
/// bracket, not stopped at the first basin that explains all but [`UNEXPLAINED_WARNING`].
pub const FEW_WINDOWS: usize = 32;

/// The most times [`widening`] doubles its bracket (2¹⁰ ≈ 10³): a constant found further off
/// than that is one the equation hardly sees.
const WIDENINGS: usize = 10;

/// Doublings in a row without a better value after which [`widening`] stops (a basin 2⁴ times
/// the first bracket away is still reached).
const IDLE: usize = 4;

/// How much lower a value must be to be taken for a better constant: a thousandth.
const BETTER: f64 = 1e-3;

/// The minimiser of `f` on `[lo, hi]`; a non-finite value counts as the worst.
fn best(lo: f64, hi: f64, mut f: impl FnMut(f64) -> f64) -> f64 {
    let found: Result<f64, std::convert::Infallible> = hb_solve::drift::minimise(lo, hi, |c| {
        let v = f(c);
        Ok(if v.is_finite() { v } else { f64::INFINITY })
    });
    found.unwrap_or_else(|never| match never {})
}

/// `part / whole`, 0 for nothing to explain.
fn relative(part: f64, whole: f64) -> f64 {
    if whole > 0.0 { part / whole } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A linear oscillator `x'' = −4 (x − 5) − 0.1 x'` about 5, far beyond its own swing: the
    /// offset's bracket must widen to reach it.
    struct Spring;

    impl SecondOrderSystem for Spring {
        fn acceleration(&self, _t: f64, x: f64, v: f64) -> f64 {
            -4.0 * (x - 5.0) - 0.1 * v
        }
        fn jacobian(&self, _t: f64, _x: f64, _v: f64) -> [f64; 2] {
            [-4.0, -0.1]
        }
    }

    /// Its motion from `x(0) = 5.8`, `v(0) = 0.3`, sampled every `dt` (closed form).
    fn motion(n: usize, dt: f64) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
        let (zeta_w, wd) = (0.05, (4.0f64 - 0.0025).sqrt());
        let (x0, v0) = (0.8, 0.3);
        let (a, b) = (x0, (v0 + zeta_w * x0) / wd);
        let mut out = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for i in 0..n {
            let t = i as f64 * dt;
            let e = (-zeta_w * t).exp();
            let (c, s) = ((wd * t).cos(), (wd * t).sin());
            let x = e * (a * c + b * s);
            let v = e * ((-zeta_w * a + b * wd) * c + (-zeta_w * b - a * wd) * s);
            out.0.push(t);
            out.1.push(x + 5.0);
            out.2.push(v);
            out.3.push(-4.0 * x - 0.1 * v);
        }
        out
    }

    #[test]
    fn a_velocity_records_offset_is_the_one_the_equation_holds_with() {
        let (t, x, v, _) = motion(2000, 0.01);
        let mut out = vec![0.0; t.len()];
        let found = velocity_piece(&Spring, &t, &v, 0.01, &mut out);
        let worst = out.iter().zip(&x).map(|(o, x)| (o - x).abs()).fold(0.0, f64::max);
        // The sixth-order rule at 0.01 s on a 0.3 Hz motion: the integral is exact to ~1e-12.
        assert!(worst < 1e-8, "{worst} ({found:?})");
        assert!(found.unexplained < 1e-6, "{found:?}");
    }

    #[test]
    fn an_acceleration_records_velocity_and_offset_are_found_together() {
        let (t, x, v, a) = motion(2000, 0.01);
        let mut out = vec![0.0; t.len()];
        let found = acceleration_piece(&Spring, &t, &a, 0.01, &mut out);
        let worst = out.iter().zip(&x).map(|(o, x)| (o - x).abs()).fold(0.0, f64::max);
        assert!(worst < 1e-3, "{worst} ({found:?})");
        assert!(found.unexplained < 1e-6, "{found:?}");
        let _ = v;
    }

    /// A free mass under a periodic force, `x'' = −0.1 x' + cos t`: no term sees the offset, which
    /// stays the integral's mean (0) rather than a scan's arbitrary end.
    struct Free;

    impl SecondOrderSystem for Free {
        fn acceleration(&self, t: f64, _x: f64, v: f64) -> f64 {
            -0.1 * v + t.cos()
        }
        fn jacobian(&self, _t: f64, _x: f64, _v: f64) -> [f64; 2] {
            [0.0, -0.1]
        }
    }

    #[test]
    fn constants_the_equation_leaves_much_unexplained_are_warned_of() {
        let piece = |unexplained| PieceConstants {
            start: 0,
            end: 100,
            velocity: 0.0,
            offset: 0.1,
            unexplained,
        };
        let told = |unexplained: f64| {
            notices(
                Measured::Velocity,
                &Integration {
                    pieces: vec![piece(1e-6), piece(unexplained)],
                    left_out: Vec::new(),
                },
            )
        };
        assert_eq!(told(1e-3).len(), 1);
        for bad in [0.5, f64::NAN] {
            let notices = told(bad);
            assert_eq!(notices.len(), 2, "{notices:?}");
            assert!(notices[1].is_warning() && notices[1].to_string().contains("unexplained"));
        }
    }

    #[test]
    fn an_offset_the_equation_does_not_see_stays_the_integrals_mean() {
        let dt = 0.01;
        let t: Vec<f64> = (0..2000).map(|i| i as f64 * dt).collect();
        // The steady response's velocity, (0.1 cos t + sin t) / 1.01.
        let v: Vec<f64> = t.iter().map(|t| (0.1 * t.cos() + t.sin()) / 1.01).collect();
        let mut out = vec![0.0; t.len()];
        let found = velocity_piece(&Free, &t, &v, dt, &mut out);
        assert_eq!(found.offset, 0.0, "{found:?}");
        let mean = out.iter().sum::<f64>() / out.len() as f64;
        assert!(mean.abs() < 1e-12, "{mean}");
    }
}
