//! What an encoder reports of a simulated angle: the observation model between a [`Trajectory`]
//! and a record.
//!
//! An [`Encoder`] adds seeded Gaussian noise of standard deviation `σ` to the angle and reports it
//! modulo 2π, `x_n = wrap(θ_n + ε_n)` with `ε_n ~ N(0, σ²)` independent; a `σ` of zero is an
//! ideal encoder. Every seeded noisy record of the workspace (the command line's `simulate`, the
//! accuracy studies, the tests) is made here, so one seed and stream give one record everywhere.
//! The rest of a real encoder's behaviour belongs here too when it is modelled: its resolution in
//! counts per turn, its zero offset, and bit errors.
//!
//! The noise is drawn from ChaCha8 (`rand_chacha`) seeded by [`SeedableRng::seed_from_u64`], one
//! normal number per sample in sample order, so a shorter record gets the first samples' noise of a
//! longer one with the same seed and stream.
//!
//! [`Trajectory`]: crate::Trajectory

use std::f64::consts::TAU;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use crate::SimError;

/// How a standard normal number is drawn from the uniform stream.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[non_exhaustive]
pub enum NormalDraw {
    /// `rand_distr`'s [`Normal`] (the ziggurat method): one or more uniform draws per number.
    #[default]
    Ziggurat,
    /// The Box–Muller transform, cosine branch only: `√(−2 ln u₁) cos(2π u₂)` with
    /// `u₁ ∈ [ε, 1)` and `u₂ ∈ [0, 1)` drawn in that order, two uniform draws per number. Kept so
    /// that records made with it (the noise table of `docs/identification.md`) can be made again.
    BoxMuller,
}

/// A model of an angle encoder: seeded Gaussian noise on the angle, reported modulo 2π.
///
/// Built by [`Encoder::seeded`] (an ideal encoder) and the validating setters; see the
/// [module documentation](self) for the model.
///
/// # Example
///
/// ```
/// use pendulum_sim::observe::Encoder;
///
/// let theta: Vec<f64> = (0..100).map(|n| 0.1 * n as f64).collect();
/// let encoder = Encoder::seeded(7).with_noise(0.05)?;
/// let x = encoder.observe(&theta);
/// // Reported in [−π, π), and the same seed gives the same record.
/// assert!(x.iter().all(|v| (-std::f64::consts::PI..std::f64::consts::PI).contains(v)));
/// assert_eq!(x, encoder.observe(&theta));
/// // Another stream of the same seed is independent noise.
/// assert_ne!(x, encoder.with_stream(1).observe(&theta));
/// // Without noise the encoder only wraps.
/// let ideal = Encoder::seeded(7).observe(&[4.0]);
/// assert!((ideal[0] - (4.0 - std::f64::consts::TAU)).abs() < 1e-15);
/// # Ok::<(), pendulum_sim::SimError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Encoder {
    sigma: f64,
    seed: u64,
    stream: u64,
    draw: NormalDraw,
}

impl Encoder {
    /// An ideal encoder (no noise) whose noise, once set, is drawn from ChaCha8 seeded with
    /// `seed`, stream 0, by [`NormalDraw::Ziggurat`].
    pub fn seeded(seed: u64) -> Self {
        Self {
            sigma: 0.0,
            seed,
            stream: 0,
            draw: NormalDraw::Ziggurat,
        }
    }

    /// Gaussian noise of standard deviation `sigma` radians on the angle (finite, `>= 0`).
    pub fn with_noise(mut self, sigma: f64) -> Result<Self, SimError> {
        if !(sigma.is_finite() && sigma >= 0.0) {
            return Err(SimError::InvalidParameter {
                name: "noise standard deviation",
                value: sigma,
                why: "must be finite and >= 0",
            });
        }
        self.sigma = sigma;
        Ok(self)
    }

    /// The ChaCha8 stream of the seed the noise is drawn from (`0` by default): independent
    /// noise for several records made from one seed.
    pub fn with_stream(mut self, stream: u64) -> Self {
        self.stream = stream;
        self
    }

    /// How the normal numbers are drawn ([`NormalDraw::Ziggurat`] by default).
    pub fn with_draw(mut self, draw: NormalDraw) -> Self {
        self.draw = draw;
        self
    }

    /// The noise's standard deviation `σ` in radians.
    pub fn sigma(&self) -> f64 {
        self.sigma
    }
    /// The seed.
    pub fn seed(&self) -> u64 {
        self.seed
    }
    /// The stream of the seed.
    pub fn stream(&self) -> u64 {
        self.stream
    }

    /// What the encoder reports of the angle `theta`: `wrap(θ_n + ε_n)`, in `[−π, π)`.
    pub fn observe(&self, theta: &[f64]) -> Vec<f64> {
        let mut x = self.observe_continuous(theta);
        for v in &mut x {
            *v = circle_signal::wrap(*v);
        }
        x
    }

    /// The angle `theta` with the encoder's noise, `θ_n + ε_n`, not wrapped: a record of the
    /// continuous angle (or of a displacement on the line). Its wrap is [`Encoder::observe`].
    pub fn observe_continuous(&self, theta: &[f64]) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        rng.set_stream(self.stream);
        match self.draw {
            NormalDraw::Ziggurat => {
                let normal = Normal::new(0.0, self.sigma).expect("sigma checked finite and >= 0");
                theta.iter().map(|&v| v + normal.sample(&mut rng)).collect()
            }
            NormalDraw::BoxMuller => theta
                .iter()
                .map(|&v| {
                    let (u1, u2): (f64, f64) = (rng.random_range(f64::EPSILON..1.0), rng.random());
                    v + self.sigma * (-2.0 * u1.ln()).sqrt() * (TAU * u2).cos()
                })
                .collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sigma_is_checked() {
        for bad in [-0.1, f64::NAN, f64::INFINITY] {
            assert!(Encoder::seeded(1).with_noise(bad).is_err(), "{bad}");
        }
        assert_eq!(Encoder::seeded(1).with_noise(0.2).unwrap().sigma(), 0.2);
    }

    /// Stream 0 is the plain seeded generator, so records made before streams existed are the same.
    #[test]
    fn stream_zero_is_the_seeded_generator() {
        let theta: Vec<f64> = (0..50).map(|n| 0.3 * n as f64).collect();
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let normal = Normal::new(0.0, 0.1).unwrap();
        let want: Vec<f64> = theta
            .iter()
            .map(|&v| circle_signal::wrap(v + normal.sample(&mut rng)))
            .collect();
        assert_eq!(Encoder::seeded(11).with_noise(0.1).unwrap().observe(&theta), want);
    }

    #[test]
    fn noise_has_the_requested_size_and_no_mean() {
        for draw in [NormalDraw::Ziggurat, NormalDraw::BoxMuller] {
            let zeros = vec![0.0; 20_000];
            let e = Encoder::seeded(3).with_noise(0.05).unwrap().with_draw(draw);
            let n = e.observe_continuous(&zeros);
            let mean = n.iter().sum::<f64>() / n.len() as f64;
            let sd = (n.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n.len() as f64).sqrt();
            assert!(
                mean.abs() < 3.0 * 0.05 / (n.len() as f64).sqrt() * 1.5,
                "{draw:?}: mean {mean}"
            );
            assert!((sd - 0.05).abs() < 0.002, "{draw:?}: sd {sd}");
            assert_ne!(n, e.with_stream(1).observe_continuous(&zeros));
        }
    }
}
