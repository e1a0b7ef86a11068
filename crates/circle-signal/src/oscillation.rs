//! The period of a free oscillation, from the record alone: the time unit of a record with no
//! drive.

use crate::{CircleError, Domain, wrap};

/// The mean period, in samples, of the oscillation of `x`: the mean spacing of the upward zero
/// crossings of its velocity, counted with a hysteresis of a tenth of the velocity's root mean
/// square so that an encoder's dither near a crossing counts once. The velocity is the change of
/// the position (on the circle the unwrapped angle, from steps wrapped into `[−π, π)`) over a lag:
/// one sample first, then an eighth of the period so found (twice), which averages out noise
/// faster than the swing.
///
/// It is what a record without a drive offers as its unit of time: windows "of k oscillation
/// periods" for the weak form of a free decay. The velocity crosses zero upward once per swing,
/// whatever the offset or drift of the position, and not at all while a pendulum whirls, so a
/// decay that starts whirling is measured on its swings. The period of a decaying nonlinear
/// oscillator changes with its amplitude; this is the mean over the swings of the record.
///
/// Errors when a sample is not finite, or when the velocity crosses zero upward fewer than twice
/// (no full swing to measure).
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
    let n = x.len();
    let too_short = |crossings: usize| CircleError::NoOscillation { len: n, crossings };
    if n < 3 {
        return Err(too_short(0));
    }
    // The unwrapped position relative to the first sample: the velocity over `lag` samples is a
    // difference of it.
    let mut position = Vec::with_capacity(n);
    position.push(0.0);
    for w in x.windows(2) {
        let step = match domain {
            Domain::Circle => wrap(w[1] - w[0]),
            Domain::Line => w[1] - w[0],
        };
        position.push(position[position.len() - 1] + step);
    }
    let mut lag = 1;
    let mut period = swing_period(&position, lag).map_err(too_short)?;
    for _ in 0..2 {
        let smoother = ((period / SMOOTHING).round() as usize).clamp(1, (n / 4).max(1));
        if smoother == lag {
            break;
        }
        lag = smoother;
        period = swing_period(&position, lag).map_err(too_short)?;
    }
    Ok(period)
}

/// Velocity over this fraction of the period estimated so far: it averages out noise faster than
/// the swing without flattening the swing itself.
const SMOOTHING: f64 = 8.0;

/// The mean spacing of the upward zero crossings of the velocity over `lag` samples,
/// `position[i + lag] − position[i]`, or the number of crossings when fewer than two.
fn swing_period(position: &[f64], lag: usize) -> Result<f64, usize> {
    let steps: Vec<f64> = position
        .iter()
        .zip(&position[lag.min(position.len())..])
        .map(|(a, b)| b - a)
        .collect();
    // Zero, not the mean step, is the level: a swing reverses the motion, and a long whirl would
    // move the mean.
    let spread = (steps.iter().map(|v| v * v).sum::<f64>() / steps.len() as f64).sqrt();
    let band = 0.1 * spread;
    // Upward crossings of zero, each after the velocity has been below −band.
    let mut armed = false;
    let mut crossings: Vec<f64> = Vec::new();
    for i in 1..steps.len() {
        let (a, b) = (steps[i - 1], steps[i]);
        if b < -band {
            armed = true;
        }
        if armed && a < 0.0 && b >= 0.0 {
            // Linear interpolation of the crossing between steps i − 1 and i.
            crossings.push(i as f64 - b / (b - a));
            armed = false;
        }
    }
    if crossings.len() < 2 {
        return Err(crossings.len());
    }
    Ok((crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

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
    fn a_decay_that_starts_whirling_is_measured_on_its_swings() {
        // Four thousand samples of whirling, slowing down, then swings of period 80 samples.
        let mut theta: Vec<f64> = (0..4000)
            .map(|n| 0.3 * n as f64 - 3e-5 * (n * n) as f64)
            .collect();
        let top = theta[3999];
        theta.extend((1..4000).map(|n| top + 0.8 * (std::f64::consts::TAU * n as f64 / 80.0).sin()));
        let x: Vec<f64> = theta.iter().map(|&t| wrap(t)).collect();
        let p = oscillation_period(&x, Domain::Circle).unwrap();
        assert!((p - 80.0).abs() < 0.01, "{p}");
    }

    #[test]
    fn too_few_crossings_and_bad_samples() {
        let ramp: Vec<f64> = (0..100).map(|n| n as f64).collect();
        assert!(matches!(
            oscillation_period(&ramp, Domain::Line),
            Err(CircleError::NoOscillation { .. })
        ));
        // Under two swings: one upward crossing of the velocity.
        let one: Vec<f64> = (0..100).map(|n| (n as f64 * 0.1).sin()).collect();
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
