//! The displacement of a velocity or acceleration sensor's record, for a method that needs the
//! displacement.
//!
//! Laser vibrometers measure velocity, accelerometers acceleration. Integrating them gives the
//! displacement up to unknown constants: a velocity record gives `x − x₀`, an acceleration record
//! `x − x₀ − v₀ t`. [`displacement`] integrates the record once or twice and removes, piece by
//! piece, the least-squares polynomial of those unknowns from the result: the mean for a velocity
//! record, the linear trend for an acceleration record.
//!
//! What is left is `x` less its mean (velocity), which a model on the line absorbs with a constant
//! term and its polynomial terms (`(x + C)³` is a cubic in `x`), or `x` less its least-squares
//! linear trend (acceleration): the trend of the true displacement over the record is removed with
//! `v₀`, an error that is small for an oscillation about one equilibrium and large for one that
//! hops between wells (measured in `docs/real-records.md`). The integrated sensor noise drifts (a
//! random walk for a velocity record, an integrated one for acceleration), and a sensor's bias `b`
//! integrates into a ramp `b t` (velocity) or a parabola `b t² / 2` (acceleration): remove a known
//! bias before.
//!
//! Integration is the cumulative sixth-order rule on the samples ([`cumulative_integral`]): the
//! error of a sinusoid's integral is below `1e-6` of its amplitude from 25 samples per period,
//! and falls as `h⁶`.

use std::ops::Range;

use crate::CircleError;

/// What a record's sensor measured.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Measured {
    /// The displacement (or angle) itself (the default).
    #[default]
    Displacement,
    /// Its first derivative (a laser vibrometer, a tachometer).
    Velocity,
    /// Its second derivative (an accelerometer).
    Acceleration,
}

impl std::fmt::Display for Measured {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Measured::Displacement => "displacement",
            Measured::Velocity => "velocity",
            Measured::Acceleration => "acceleration",
        })
    }
}

/// A name that is not a [`Measured`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown measured quantity '{0}': displacement, velocity or acceleration")]
pub struct UnknownMeasured(pub String);

/// `displacement`, `velocity` or `acceleration`, as [`Measured`]'s `Display` writes them.
impl std::str::FromStr for Measured {
    type Err = UnknownMeasured;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        [Measured::Displacement, Measured::Velocity, Measured::Acceleration]
            .into_iter()
            .find(|m| m.to_string() == s.trim().to_ascii_lowercase())
            .ok_or_else(|| UnknownMeasured(s.to_owned()))
    }
}

/// The cumulative integral `I_n = ∫_{t_0}^{t_n} y` of samples `y` at step `h`, `I_0 = 0`, by
/// the sixth-order rule on the interior steps (the quintic through six neighbouring samples
/// integrated over the middle step, `h/1440 (11 y_{n−2} − 93 y_{n−1} + 802 y_n + 802 y_{n+1}
/// − 93 y_{n+2} + 11 y_{n+3})`) and cubics (fourth order) over the two first and two last steps,
/// whose errors only shift the samples after them by a constant. Needs at least 4 finite samples
/// and `h > 0`.
pub fn cumulative_integral(y: &[f64], h: f64) -> Result<Vec<f64>, CircleError> {
    if y.len() < 4 {
        return Err(CircleError::TooShort {
            len: y.len(),
            needed: 4,
        });
    }
    if !(h.is_finite() && h > 0.0) {
        return Err(CircleError::NonFinite { index: 0, value: h });
    }
    if let Some(index) = y.iter().position(|v| !v.is_finite()) {
        return Err(CircleError::NonFinite {
            index,
            value: y[index],
        });
    }
    let n = y.len();
    let (w4, w6) = (h / 24.0, h / 1440.0);
    let mut out = Vec::with_capacity(n);
    out.push(0.0);
    let mut acc = 0.0;
    for i in 0..n - 1 {
        let step = if i == 0 {
            w4 * (9.0 * y[0] + 19.0 * y[1] - 5.0 * y[2] + y[3])
        } else if i == n - 2 {
            w4 * (y[i - 2] - 5.0 * y[i - 1] + 19.0 * y[i] + 9.0 * y[i + 1])
        } else if i == 1 || i == n - 3 {
            w4 * (-y[i - 1] + 13.0 * y[i] + 13.0 * y[i + 1] - y[i + 2])
        } else {
            w6 * (11.0 * (y[i - 2] + y[i + 3]) - 93.0 * (y[i - 1] + y[i + 2]) + 802.0 * (y[i] + y[i + 1]))
        };
        acc += step;
        out.push(acc);
    }
    Ok(out)
}

/// Removes the least-squares polynomial of degree `degree <= 2` in the sample index from `v`
/// (Legendre-like orthogonal polynomials on the samples, so that the fit is well conditioned at
/// any length).
fn remove_trend(v: &mut [f64], degree: usize) {
    let n = v.len();
    let c = (n as f64 - 1.0) / 2.0;
    let p1 = |i: usize| i as f64 - c;
    // p2 = p1² − mean(p1²), orthogonal to 1 and p1 on symmetric samples.
    let m2 = (0..n).map(|i| p1(i) * p1(i)).sum::<f64>() / n as f64;
    let p2 = |i: usize| p1(i) * p1(i) - m2;
    let mean = v.iter().sum::<f64>() / n as f64;
    v.iter_mut().for_each(|x| *x -= mean);
    let mut fit = |p: &dyn Fn(usize) -> f64| {
        let (num, den) = (0..n).fold((0.0, 0.0), |(a, b), i| (a + v[i] * p(i), b + p(i) * p(i)));
        if den > 0.0 {
            let k = num / den;
            v.iter_mut().enumerate().for_each(|(i, x)| *x -= k * p(i));
        }
    };
    if degree >= 1 {
        fit(&p1);
    }
    if degree >= 2 {
        fit(&p2);
    }
}

/// The displacement less its mean (velocity) or its least-squares linear trend (acceleration)
/// from a record of what `measured` says, at step `h`, piece by
/// piece (each range of `pieces` is integrated on its own; samples outside them, e.g. the NaN
/// of gaps, are copied as they are). See the module docs for what is removed and why.
pub fn displacement(
    y: &[f64],
    h: f64,
    measured: Measured,
    pieces: &[Range<usize>],
) -> Result<Vec<f64>, CircleError> {
    crate::check_pieces(y, pieces)?;
    let mut out = y.to_vec();
    let integrations = match measured {
        Measured::Displacement => 0,
        Measured::Velocity => 1,
        Measured::Acceleration => 2,
    };
    for piece in pieces {
        let mut v = y[piece.clone()].to_vec();
        for _ in 0..integrations {
            v = cumulative_integral(&v, h).map_err(|e| match e {
                CircleError::TooShort { needed, .. } => CircleError::TooShort {
                    len: piece.len(),
                    needed,
                },
                CircleError::NonFinite { index, value } => CircleError::NonFinite {
                    index: index + piece.start,
                    value,
                },
                other => other,
            })?;
        }
        if integrations > 0 {
            remove_trend(&mut v, integrations - 1);
        }
        out[piece.clone()].copy_from_slice(&v);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn max_error(n: usize) -> f64 {
        let h = std::f64::consts::TAU / n as f64;
        let y: Vec<f64> = (0..=3 * n).map(|i| (i as f64 * h).cos()).collect();
        let got = cumulative_integral(&y, h).unwrap();
        // Up to the constant the end steps add (the interior error).
        let err: Vec<f64> = got
            .iter()
            .enumerate()
            .map(|(i, g)| g - (i as f64 * h).sin())
            .collect();
        let shift = err[3 * n / 2];
        err[2..3 * n - 2]
            .iter()
            .map(|e| (e - shift).abs())
            .fold(0.0, f64::max)
    }

    #[test]
    fn the_rule_converges_fast() {
        // The interior rule's order; the end steps only shift the samples after them.
        let (coarse, fine) = (max_error(25), max_error(50));
        let order = (coarse / fine).log2();
        assert!(order > 5.5, "order {order}: {coarse:e} -> {fine:e}");
        assert!(coarse < 1e-6, "{coarse:e}");
    }

    /// Cubics are integrated exactly, first and last steps included.
    #[test]
    fn cubics_are_exact() {
        let h = 0.1;
        let y: Vec<f64> = (0..9)
            .map(|i| (i as f64 * h).powi(3) - 2.0 * i as f64 * h)
            .collect();
        let got = cumulative_integral(&y, h).unwrap();
        for (i, g) in got.iter().enumerate() {
            let t = i as f64 * h;
            assert!((g - (t.powi(4) / 4.0 - t * t)).abs() < 1e-14, "{i}");
        }
    }

    /// x = 0.7 + sin(t) + 0.3 cos(2.3 t): from its velocity, the displacement less its mean; from
    /// its acceleration, less its least-squares linear trend.
    #[test]
    fn displacement_from_velocity_and_acceleration() {
        let h = std::f64::consts::TAU / 200.0;
        let n = 200 * 40;
        let t = |i: usize| i as f64 * h;
        let x: Vec<f64> = (0..n)
            .map(|i| 0.7 + t(i).sin() + 0.3 * (2.3 * t(i)).cos())
            .collect();
        let v: Vec<f64> = (0..n).map(|i| t(i).cos() - 0.69 * (2.3 * t(i)).sin()).collect();
        let a: Vec<f64> = (0..n).map(|i| -t(i).sin() - 1.587 * (2.3 * t(i)).cos()).collect();
        let all: Vec<Range<usize>> = std::iter::once(0..n).collect();
        for (y, what, degree) in [(&v, Measured::Velocity, 0), (&a, Measured::Acceleration, 1)] {
            let got = displacement(y, h, what, &all).unwrap();
            let mut want = x.clone();
            remove_trend(&mut want, degree);
            let err = got
                .iter()
                .zip(&want)
                .map(|(g, w)| (g - w).abs())
                .fold(0.0, f64::max);
            let tol = 1e-8;
            assert!(err < tol, "{what:?}: {err:e}");
        }
        let same = displacement(&x, h, Measured::Displacement, &all).unwrap();
        assert_eq!(same, x);
    }

    #[test]
    fn bad_input_is_an_error() {
        assert!(cumulative_integral(&[1.0, 2.0, 3.0], 0.1).is_err());
        assert!(cumulative_integral(&[1.0, 2.0, f64::NAN, 3.0], 0.1).is_err());
        assert!(cumulative_integral(&[1.0; 5], 0.0).is_err());
        let bad_piece: Vec<Range<usize>> = std::iter::once(Range { start: 3, end: 2 }).collect();
        assert!(displacement(&[0.0; 8], 0.1, Measured::Velocity, &bad_piece).is_err());
        let short = [0..3, 4..8];
        assert!(matches!(
            displacement(&[0.0; 8], 0.1, Measured::Velocity, &short),
            Err(CircleError::TooShort { len: 3, .. })
        ));
    }
}

#[cfg(test)]
mod trend_tests {
    use super::*;

    #[test]
    fn trends_are_removed_exactly() {
        let mut v: Vec<f64> = (0..101)
            .map(|i| 3.0 - 0.2 * i as f64 + 0.01 * (i * i) as f64)
            .collect();
        remove_trend(&mut v, 2);
        assert!(v.iter().all(|x| x.abs() < 1e-10), "{v:?}");
        let mut w: Vec<f64> = (0..50).map(|i| 1.0 + 0.5 * i as f64).collect();
        remove_trend(&mut w, 1);
        assert!(w.iter().all(|x| x.abs() < 1e-12));
    }
}
