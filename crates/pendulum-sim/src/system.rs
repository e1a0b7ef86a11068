//! Second-order systems `x'' = F(t, x, x')`.

use serde::{Deserialize, Serialize};

use crate::SimError;

/// A forced second-order oscillator `x'' = F(t, x, x')`.
///
/// Both the true pendulum and every identified model implement this, so they run through the
/// same integrator, stroboscopic sampler and Lyapunov estimator.
pub trait SecondOrderSystem {
    /// The acceleration `F(t, x, v)`.
    fn acceleration(&self, t: f64, x: f64, v: f64) -> f64;

    /// The partial derivatives `[∂F/∂x, ∂F/∂v]` at `(t, x, v)`, for tangent-linear integration.
    fn jacobian(&self, t: f64, x: f64, v: f64) -> [f64; 2];
}

impl<S: SecondOrderSystem + ?Sized> SecondOrderSystem for &S {
    fn acceleration(&self, t: f64, x: f64, v: f64) -> f64 {
        (**self).acceleration(t, x, v)
    }
    fn jacobian(&self, t: f64, x: f64, v: f64) -> [f64; 2] {
        (**self).jacobian(t, x, v)
    }
}

/// The horizontally base-excited pendulum, paper eq. 1 in non-dimensional time:
///
/// `x'' + c x' + (1/r²) sin x − f sin(t) cos x = 0`.
///
/// Construct with [`Pendulum::new`] (validated) or [`Pendulum::paper`]. Serialised as `f`, `c`
/// and `r` only; deserialising validates them as [`Pendulum::new`] does.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "PendulumRaw", into = "PendulumRaw")]
pub struct Pendulum {
    f: f64,
    c: f64,
    r: f64,
    /// `1/r²`, cached for the right-hand side; derived from `r`, so never serialised.
    inv_r2: f64,
}

/// The serialised form of [`Pendulum`].
#[derive(Serialize, Deserialize)]
struct PendulumRaw {
    f: f64,
    c: f64,
    r: f64,
}

impl TryFrom<PendulumRaw> for Pendulum {
    type Error = SimError;
    fn try_from(raw: PendulumRaw) -> Result<Self, SimError> {
        Self::new(raw.f, raw.c, raw.r)
    }
}

impl From<Pendulum> for PendulumRaw {
    fn from(p: Pendulum) -> Self {
        Self {
            f: p.f,
            c: p.c,
            r: p.r,
        }
    }
}

impl Pendulum {
    /// The paper's parameters: `f = 1.52`, `c = 0.03`, `r = 0.8333`.
    pub const PAPER: (f64, f64, f64) = (1.52, 0.03, 0.8333);

    /// A pendulum with forcing amplitude `f`, damping `c = 2ξ/r` and frequency ratio `r`.
    ///
    /// `f` and `c` must be finite (either sign is accepted), `r` finite and non-zero.
    pub fn new(f: f64, c: f64, r: f64) -> Result<Self, SimError> {
        for (name, value) in [("f", f), ("c", c), ("r", r)] {
            if !value.is_finite() {
                return Err(SimError::InvalidParameter {
                    name,
                    value,
                    why: "must be finite",
                });
            }
        }
        if r == 0.0 {
            return Err(SimError::InvalidParameter {
                name: "r",
                value: r,
                why: "must be non-zero",
            });
        }
        Ok(Self {
            f,
            c,
            r,
            inv_r2: 1.0 / (r * r),
        })
    }

    /// The paper's pendulum (`f = 1.52`, `c = 0.03`, `r = 0.8333`).
    pub fn paper() -> Self {
        let (f, c, r) = Self::PAPER;
        Self {
            f,
            c,
            r,
            inv_r2: 1.0 / (r * r),
        }
    }

    /// Forcing amplitude `f`.
    pub fn f(&self) -> f64 {
        self.f
    }
    /// Damping `c`.
    pub fn c(&self) -> f64 {
        self.c
    }
    /// Frequency ratio `r`.
    pub fn r(&self) -> f64 {
        self.r
    }
}

impl SecondOrderSystem for Pendulum {
    #[inline]
    fn acceleration(&self, t: f64, x: f64, v: f64) -> f64 {
        let (s, c) = x.sin_cos();
        -self.c * v - self.inv_r2 * s + self.f * t.sin() * c
    }

    #[inline]
    fn jacobian(&self, t: f64, x: f64, _v: f64) -> [f64; 2] {
        let (s, c) = x.sin_cos();
        [-self.inv_r2 * c - self.f * t.sin() * s, -self.c]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_bad_parameters() {
        assert!(Pendulum::new(1.0, 0.1, 0.0).is_err());
        assert!(Pendulum::new(f64::NAN, 0.1, 1.0).is_err());
        assert!(Pendulum::new(1.0, f64::INFINITY, 1.0).is_err());
        assert_eq!(Pendulum::new(1.52, 0.03, 0.8333).unwrap(), Pendulum::paper());
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let p = Pendulum::paper();
        let (t, x, v) = (0.7, 2.1, -0.4);
        let e = 1e-6;
        let dx = (p.acceleration(t, x + e, v) - p.acceleration(t, x - e, v)) / (2.0 * e);
        let dv = (p.acceleration(t, x, v + e) - p.acceleration(t, x, v - e)) / (2.0 * e);
        let [jx, jv] = p.jacobian(t, x, v);
        assert!((jx - dx).abs() < 1e-8 && (jv - dv).abs() < 1e-8);
    }
}
