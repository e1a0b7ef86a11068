use std::f64::consts::{PI, TAU};

use circle_signal::circle_distance;

use crate::delay::DelayVector;

/// How two samples (and two delay vectors) of a record are compared.
///
/// The distance between two delay vectors is always the **maximum** over components of the
/// per-component distance (the Chebyshev norm), as in `circle_signal::max_circle_distance`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Metric {
    /// Plain differences `|a − b|`: a signal on the line, or what classic tools do with any record.
    Linear,
    /// The circle distance of paper eq. 19, `|a − b|_c = |wrap(a − b)|` in `[0, π]`: the right
    /// metric for an angle, wrapped or not. Samples a little apart across ±π are close.
    Circle,
}

impl Metric {
    /// Distance between two samples.
    #[inline]
    pub fn distance(self, a: f64, b: f64) -> f64 {
        match self {
            Self::Linear => (a - b).abs(),
            Self::Circle => circle_distance(a, b),
        }
    }

    /// Distance between two delay vectors: the maximum over components of [`Metric::distance`].
    ///
    /// # Panics
    /// If the two vectors have different dimensions.
    #[inline]
    pub fn vector_distance(self, a: &DelayVector<'_>, b: &DelayVector<'_>) -> f64 {
        assert_eq!(a.dim(), b.dim(), "delay vectors of different dimension");
        a.iter()
            .zip(b.iter())
            .map(|(p, q)| self.distance(p, q))
            .fold(0.0, f64::max)
    }

    /// The size of the attractor `R_A` used by the attractor-size test of false nearest
    /// neighbours: the root-mean-square distance of the samples from their mean.
    ///
    /// - Linear: the population standard deviation, `sqrt(mean((x − x̄)²))` (Kennel et al. 1992).
    /// - Circle: the same with the circle distance and the circular mean
    ///   `μ = atan2(Σ sin x, Σ cos x)`. For data spread evenly over the circle it tends to
    ///   `π / √3 ≈ 1.81`.
    ///
    /// Returns 0 for an empty slice. The caller checks that the samples are finite.
    pub fn spread(self, x: &[f64]) -> f64 {
        if x.is_empty() {
            return 0.0;
        }
        let n = x.len() as f64;
        let centre = match self {
            Self::Linear => x.iter().sum::<f64>() / n,
            Self::Circle => {
                let (s, c) = x.iter().fold((0.0, 0.0), |(s, c), &v| (s + v.sin(), c + v.cos()));
                s.atan2(c)
            }
        };
        (x.iter().map(|&v| self.distance(v, centre).powi(2)).sum::<f64>() / n).sqrt()
    }

    /// The coordinate a sample takes in the k-d tree: the sample itself (linear), or the angle
    /// shifted into `[0, 2π)` for the tree's periodic boundary condition (circle).
    #[inline]
    pub(crate) fn tree_coordinate(self, v: f64) -> f64 {
        match self {
            Self::Linear => v,
            Self::Circle => {
                let r = (v + PI).rem_euclid(TAU);
                // `rem_euclid` may round up to exactly 2π for tiny negative arguments.
                if r >= TAU { 0.0 } else { r }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distances() {
        assert_eq!(Metric::Linear.distance(3.0, -3.0), 6.0);
        assert!((Metric::Circle.distance(3.0, -3.0) - (TAU - 6.0)).abs() < 1e-15);
        assert_eq!(Metric::Circle.distance(0.5, 0.5 + 2.0 * TAU), 0.0);
    }

    #[test]
    fn tree_coordinates_are_in_the_box() {
        for v in [-PI, -1e-300, -1e-17, 0.0, PI, 3.0 * PI, -7.0, 1e6] {
            let c = Metric::Circle.tree_coordinate(v);
            assert!((0.0..TAU).contains(&c), "{v} -> {c}");
            // The shift by π keeps circle distances.
            assert!((Metric::Circle.distance(c, PI) - Metric::Circle.distance(v, 0.0)).abs() < 1e-9);
        }
    }

    #[test]
    fn spread_values() {
        let x = [1.0, 3.0];
        assert_eq!(Metric::Linear.spread(&x), 1.0);
        // Two angles either side of π: the circular mean is π and the spread is 0.1.
        let y = [PI - 0.1, -PI + 0.1];
        assert!((Metric::Circle.spread(&y) - 0.1).abs() < 1e-12);
        let even: Vec<f64> = (0..10_000)
            .map(|k| -PI + TAU * (k as f64 + 0.5) / 10_000.0)
            .collect();
        assert!((Metric::Circle.spread(&even) - PI / 3f64.sqrt()).abs() < 1e-3);
        assert_eq!(Metric::Circle.spread(&[]), 0.0);
    }
}
