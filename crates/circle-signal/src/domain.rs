//! Where the measured coordinate lives: the circle or the line.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::circle_distance;

/// Where the measured coordinate `x` lives, and so how two samples are compared.
///
/// The one vocabulary every stage uses: the delay and embedding ([`Domain::distance`] and the
/// maximum over components, [`Domain::vector_distance`]), the close-return search, the basis (a
/// basis on the circle is 2π-periodic) and the identification (on the circle each segment is
/// unwrapped and split into rotation and oscillation before it is balanced).
///
/// Parsed from and printed as `circle` or `line` (`linear` is accepted for the line, the name
/// classic embedding tools give plain differences).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Domain {
    /// An angle on the circle S¹, as an encoder reports it (wrapped into `[−π, π)`): samples are
    /// compared by the circle distance of paper eq. 19, and whirling orbits are unwrapped.
    #[default]
    #[serde(alias = "Circle")]
    Circle,
    /// A displacement (or any signal) on the real line R¹: plain differences, never unwrapped.
    #[serde(alias = "Line", alias = "linear", alias = "Linear")]
    Line,
}

impl Domain {
    /// The distance between two samples: [`circle_distance`] on the circle, `|a − b|` on the line.
    #[inline]
    pub fn distance(self, a: f64, b: f64) -> f64 {
        match self {
            Self::Circle => circle_distance(a, b),
            Self::Line => (a - b).abs(),
        }
    }

    /// The distance between two delay vectors: the maximum over components of
    /// [`distance`](Self::distance) (the Chebyshev norm, on the torus for an angle).
    ///
    /// # Panics
    /// If the two slices have different lengths.
    #[inline]
    pub fn vector_distance(self, a: &[f64], b: &[f64]) -> f64 {
        assert_eq!(a.len(), b.len(), "delay vectors of different dimension");
        a.iter()
            .zip(b)
            .map(|(&x, &y)| self.distance(x, y))
            .fold(0.0, f64::max)
    }

    /// The name, `circle` or `line`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Circle => "circle",
            Self::Line => "line",
        }
    }
}

impl fmt::Display for Domain {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A name that is not a [`Domain`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown domain '{0}': circle or line")]
pub struct UnknownDomain(pub String);

impl FromStr for Domain {
    type Err = UnknownDomain;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "circle" => Ok(Self::Circle),
            "line" | "linear" => Ok(Self::Line),
            _ => Err(UnknownDomain(s.to_owned())),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::TAU;

    #[test]
    fn distances() {
        assert_eq!(Domain::Line.distance(3.0, -3.0), 6.0);
        assert!((Domain::Circle.distance(3.0, -3.0) - (TAU - 6.0)).abs() < 1e-15);
        assert_eq!(Domain::Circle.distance(0.5, 0.5 + 2.0 * TAU), 0.0);
        assert_eq!(Domain::Circle.vector_distance(&[0.0, 1.0], &[0.5, 1.25]), 0.5);
        assert_eq!(Domain::Line.vector_distance(&[0.0, 1.0], &[0.5, 3.0]), 2.0);
    }

    #[test]
    fn names_round_trip() {
        for d in [Domain::Circle, Domain::Line] {
            assert_eq!(d.to_string().parse::<Domain>(), Ok(d));
        }
        assert_eq!("Linear".parse::<Domain>(), Ok(Domain::Line));
        assert!("torus".parse::<Domain>().is_err());
    }
}

/// A number as messages show it: Rust's shortest decimal between `1e-4` and `1e12` in size
/// (and zero), scientific notation outside, where the decimal runs to hundreds of digits
/// (`1e300`, `1e-300`).
///
/// ```
/// use circle_signal::Shown;
///
/// assert_eq!(Shown(0.25).to_string(), "0.25");
/// assert_eq!(Shown(1e300).to_string(), "1e300");
/// assert_eq!(Shown(-1.7e-300).to_string(), "-1.7e-300");
/// assert_eq!(Shown(f64::NAN).to_string(), "NaN");
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shown(pub f64);

impl fmt::Display for Shown {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = self.0;
        if v.is_finite() && v != 0.0 && !(1e-4..1e12).contains(&v.abs()) {
            write!(f, "{v:e}")
        } else {
            write!(f, "{v}")
        }
    }
}
