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
