use std::f64::consts::{PI, TAU};

use circle_signal::Domain;

use crate::delay::DelayVector;

/// The distances of this crate for a [`Domain`]: between delay vectors, the size of the
/// attractor, and the coordinate a sample takes in the k-d tree.
pub(crate) trait Metric: Copy {
    /// Distance between two delay vectors: the maximum over components of [`Domain::distance`].
    ///
    /// # Panics
    /// If the two vectors have different dimensions.
    fn delay_distance(self, a: &DelayVector<'_>, b: &DelayVector<'_>) -> f64;

    /// The coordinate a sample takes in the k-d tree: the sample itself (line), or the angle
    /// shifted into `[0, 2π)` for the tree's periodic boundary condition (circle).
    fn tree_coordinate(self, v: f64) -> f64;
}

impl Metric for Domain {
    #[inline]
    fn delay_distance(self, a: &DelayVector<'_>, b: &DelayVector<'_>) -> f64 {
        assert_eq!(a.dim(), b.dim(), "delay vectors of different dimension");
        a.iter()
            .zip(b.iter())
            .map(|(p, q)| self.distance(p, q))
            .fold(0.0, f64::max)
    }

    #[inline]
    fn tree_coordinate(self, v: f64) -> f64 {
        match self {
            Domain::Line => v,
            Domain::Circle => {
                let r = (v + PI).rem_euclid(TAU);
                // `rem_euclid` may round up to exactly 2π for tiny negative arguments.
                if r >= TAU { 0.0 } else { r }
            }
        }
    }
}

/// Distance between two delay vectors in `domain`: the maximum over components of
/// [`Domain::distance`].
///
/// # Panics
/// If the two vectors have different dimensions.
pub fn delay_distance(domain: Domain, a: &DelayVector<'_>, b: &DelayVector<'_>) -> f64 {
    domain.delay_distance(a, b)
}

/// The size of the attractor `R_A` used by the attractor-size test of false nearest neighbours:
/// the root-mean-square distance of the samples from their mean.
///
/// - Line: the population standard deviation, `sqrt(mean((x − x̄)²))` (Kennel et al. 1992).
/// - Circle: the same with the circle distance and the circular mean
///   `μ = atan2(Σ sin x, Σ cos x)`. For data spread evenly over the circle it tends to
///   `π / √3 ≈ 1.81`.
///
/// Returns 0 for an empty slice. The caller checks that the samples are finite.
pub fn spread(domain: Domain, x: &[f64]) -> f64 {
    if x.is_empty() {
        return 0.0;
    }
    let n = x.len() as f64;
    let centre = match domain {
        Domain::Line => x.iter().sum::<f64>() / n,
        Domain::Circle => {
            let (s, c) = x.iter().fold((0.0, 0.0), |(s, c), &v| (s + v.sin(), c + v.cos()));
            s.atan2(c)
        }
    };
    (x.iter().map(|&v| domain.distance(v, centre).powi(2)).sum::<f64>() / n).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tree_coordinates_are_in_the_box() {
        for v in [-PI, -1e-300, -1e-17, 0.0, PI, 3.0 * PI, -7.0, 1e6] {
            let c = Domain::Circle.tree_coordinate(v);
            assert!((0.0..TAU).contains(&c), "{v} -> {c}");
            // The shift by π keeps circle distances.
            assert!((Domain::Circle.distance(c, PI) - Domain::Circle.distance(v, 0.0)).abs() < 1e-9);
        }
    }

    #[test]
    fn spread_values() {
        let x = [1.0, 3.0];
        assert_eq!(spread(Domain::Line, &x), 1.0);
        // Two angles either side of π: the circular mean is π and the spread is 0.1.
        let y = [PI - 0.1, -PI + 0.1];
        assert!((spread(Domain::Circle, &y) - 0.1).abs() < 1e-12);
        let even: Vec<f64> = (0..10_000)
            .map(|k| -PI + TAU * (k as f64 + 0.5) / 10_000.0)
            .collect();
        assert!((spread(Domain::Circle, &even) - PI / 3f64.sqrt()).abs() < 1e-3);
        assert_eq!(spread(Domain::Circle, &[]), 0.0);
    }
}
