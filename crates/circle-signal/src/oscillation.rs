//! The period of a free oscillation, from the record alone: the time unit of a record with no
//! drive.

use crate::{CircleError, Domain, unwrap};

/// The mean period, in samples, of the oscillation of `x` about its trend: the mean spacing of the
/// upward crossings of the line fitted to the record (least squares; on the circle, to the
/// unwrapped angle, so that a steady rotation is the trend and not an oscillation), counted with a
/// hysteresis of a tenth of the residual's standard deviation so that noise near a crossing
/// counts once.
///
/// It is what a record without a drive offers as its unit of time: windows "of k oscillation
/// periods" for the weak form of a free decay. The period of a decaying nonlinear oscillator
/// changes with its amplitude; this is the mean over the record.
///
/// Errors when a sample is not finite, or when the record crosses its trend upward fewer than
/// twice (no full oscillation to measure).
///
/// ```
/// use circle_signal::{Domain, oscillation_period};
///
/// // A decaying oscillation of period 37.5 samples about a drifting offset.
/// let x: Vec<f64> = (0..2000)
///     .map(|n| {
///         let t = n as f64;
///         0.3 + 1e-4 * t + (-t / 900.0).exp() * (std::f64::consts::TAU * t / 37.5).sin()
///     })
///     .collect();
/// let p = oscillation_period(&x, Domain::Line)?;
/// assert!((p - 37.5).abs() < 0.05);
/// # Ok::<(), circle_signal::CircleError>(())
/// ```
pub fn oscillation_period(x: &[f64], domain: Domain) -> Result<f64, CircleError> {
    if let Some((index, &value)) = x.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(CircleError::NonFinite { index, value });
    }
    let y = match domain {
        Domain::Circle => unwrap(x),
        Domain::Line => x.to_vec(),
    };
    let n = y.len();
    let too_short = |crossings: usize| CircleError::NoOscillation { len: n, crossings };
    if n < 3 {
        return Err(too_short(0));
    }
    let mid = (n - 1) as f64 / 2.0;
    let mean = y.iter().sum::<f64>() / n as f64;
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (i, v) in y.iter().enumerate() {
        let d = i as f64 - mid;
        sxy += d * (v - mean);
        sxx += d * d;
    }
    let slope = sxy / sxx;
    let residual = |i: usize| y[i] - mean - slope * (i as f64 - mid);
    let spread = ((0..n).map(|i| residual(i).powi(2)).sum::<f64>() / n as f64).sqrt();
    let band = 0.1 * spread;
    // Upward crossings of zero, each after the residual has been below −band.
    let mut armed = false;
    let mut crossings: Vec<f64> = Vec::new();
    for i in 1..n {
        let (a, b) = (residual(i - 1), residual(i));
        if b < -band {
            armed = true;
        }
        if armed && a < 0.0 && b >= 0.0 {
            // Linear interpolation of the crossing between samples i − 1 and i.
            crossings.push(i as f64 - b / (b - a));
            armed = false;
        }
    }
    if crossings.len() < 2 {
        return Err(too_short(crossings.len()));
    }
    Ok((crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wrap;

    #[test]
    fn periods_on_the_line_and_on_the_circle() {
        // A pendulum-like free decay seen by an encoder (wrapped), about a zero offset of 3 rad so
        // that it crosses ±π, with a little noise from a fixed sequence.
        let period = 123.4;
        let x: Vec<f64> = (0..5000)
            .map(|n| {
                let t = n as f64;
                let wobble = 0.01 * (t * 12.9898).sin();
                wrap(3.0 + 1.5 * (-t / 3000.0).exp() * (std::f64::consts::TAU * t / period).cos() + wobble)
            })
            .collect();
        let p = oscillation_period(&x, Domain::Circle).unwrap();
        assert!((p - period).abs() < 0.05, "{p}");
        // On the line the same samples are read as they are: the wrap makes jumps of 2π, and the
        // estimate is of another signal, but still an estimate (no error, no NaN).
        assert!(oscillation_period(&x, Domain::Line).unwrap().is_finite());
    }

    #[test]
    fn too_few_crossings_and_bad_samples() {
        let ramp: Vec<f64> = (0..100).map(|n| n as f64).collect();
        assert!(matches!(
            oscillation_period(&ramp, Domain::Line),
            Err(CircleError::NoOscillation { .. })
        ));
        let one: Vec<f64> = (0..100).map(|n| (n as f64 * 0.05).sin()).collect();
        assert!(matches!(
            oscillation_period(&one, Domain::Line),
            Err(CircleError::NoOscillation { crossings: 1, .. })
        ));
        assert!(matches!(
            oscillation_period(&[0.0, f64::NAN, 1.0], Domain::Line),
            Err(CircleError::NonFinite { index: 1, .. })
        ));
        assert!(matches!(
            oscillation_period(&[0.0, 1.0], Domain::Line),
            Err(CircleError::NoOscillation { .. })
        ));
    }
}
