//! The checks a record must pass before identification: uniform time steps, a whole number of
//! samples per forcing period.

use super::{InputError, Location, Record};

/// A record on a uniform time grid: `t_n = t0 + n · dt`.
#[derive(Debug, Clone, PartialEq)]
pub struct UniformRecord {
    /// Time of the first sample.
    pub t0: f64,
    /// Sampling step.
    pub dt: f64,
    /// The samples.
    pub x: Vec<f64>,
}

/// Largest relative deviation of a time step from the mean step that counts as uniform.
pub const UNIFORM_TOLERANCE: f64 = 1e-6;

impl UniformRecord {
    /// Checks that time increases in uniform steps (within [`UNIFORM_TOLERANCE`] relative).
    pub fn new(record: Record) -> Result<Self, InputError> {
        let n = record.t.len();
        if n < 2 {
            return Err(InputError::TooFewSamples { found: n, needed: 2 });
        }
        let at = |i: usize| match record.lines.as_ref().and_then(|lines| lines.get(i)) {
            Some(&line) => Location::Line(line),
            None => Location::Sample(i + 1),
        };
        for i in 1..n {
            if record.t[i] <= record.t[i - 1] {
                return Err(InputError::TimeNotIncreasing {
                    at: at(i),
                    t: record.t[i],
                    previous: record.t[i - 1],
                });
            }
        }
        let mean = (record.t[n - 1] - record.t[0]) / (n - 1) as f64;
        for i in 1..n {
            let step = record.t[i] - record.t[i - 1];
            if (step - mean).abs() > UNIFORM_TOLERANCE * mean {
                return Err(InputError::NonUniform {
                    at: at(i),
                    step,
                    mean,
                });
            }
        }
        Ok(Self {
            t0: record.t[0],
            dt: mean,
            x: record.theta,
        })
    }

    /// The number of samples per forcing period `T / dt`, which must be a whole number within
    /// 1e-6 relative.
    pub fn samples_per_period(&self, forcing_period: f64) -> Result<usize, InputError> {
        if !(forcing_period.is_finite() && forcing_period > 0.0) {
            return Err(InputError::BadForcingPeriod {
                period: forcing_period,
            });
        }
        let ratio = forcing_period / self.dt;
        let nearest = ratio.round();
        if nearest < 1.0 || (ratio - nearest).abs() > UNIFORM_TOLERANCE * ratio {
            return Err(InputError::NotWholeSamples {
                period: forcing_period,
                dt: self.dt,
                ratio,
                nearest: nearest.max(0.0) as u64,
            });
        }
        Ok(nearest as usize)
    }

    /// Whether any sample lies outside `[−π, π)`: then the record is an unwrapped angle (or a
    /// displacement) and must be wrapped to be read as an angle on the circle.
    pub fn outside_circle(&self) -> bool {
        use std::f64::consts::PI;
        self.x.iter().any(|x| !(-PI..PI).contains(x))
    }
}

#[cfg(test)]
mod tests {
    use super::super::*;

    #[test]
    fn uniform_checks() {
        let rec = |t: Vec<f64>| Record {
            theta: vec![0.0; t.len()],
            t,
            lines: None,
        };
        assert!(matches!(
            UniformRecord::new(rec(vec![0.0])),
            Err(InputError::TooFewSamples { .. })
        ));
        assert!(matches!(
            UniformRecord::new(rec(vec![0.0, 1.0, 0.5])),
            Err(InputError::TimeNotIncreasing { .. })
        ));
        assert!(matches!(
            UniformRecord::new(rec(vec![0.0, 1.0, 2.1, 3.0])),
            Err(InputError::NonUniform { .. })
        ));
        let u = UniformRecord::new(rec((0..100).map(|n| 10.0 + n as f64 * 0.04).collect())).unwrap();
        assert!((u.dt - 0.04).abs() < 1e-15 && u.t0 == 10.0);
        assert_eq!(u.samples_per_period(1.0).unwrap(), 25);
        match u.samples_per_period(1.01) {
            Err(InputError::NotWholeSamples { nearest: 25, .. }) => {}
            other => panic!("{other:?}"),
        }
        assert!(u.samples_per_period(-1.0).is_err());
        assert!(u.samples_per_period(0.01).is_err());
    }
}
