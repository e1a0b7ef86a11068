//! What an encoder reports of a simulated angle: the observation model between a [`Trajectory`]
//! and a record.
//!
//! An [`Encoder`] turns the true angle `θ_n` of each sample into what a rig's encoder reports, in
//! this order:
//!
//! 1. **zero offset** `o` ([`Encoder::with_zero_offset`]): the encoder's zero is `o` radians from
//!    the pendulum's bottom, so it sees `θ_n − o`;
//! 2. **noise** `σ` ([`Encoder::with_noise`]): seeded Gaussian noise, `θ_n − o + ε_n` with
//!    `ε_n ~ N(0, σ²)` independent;
//! 3. **counts per turn** `N` ([`Encoder::with_counts`]): the angle is quantised to the nearest
//!    whole count, `k_n = round((θ_n − o + ε_n) · N / 2π)`, an error of at most half a count
//!    (`π / N` radians);
//! 4. **bit errors** at rate `p` ([`Encoder::with_bit_errors`], counts needed): each sample
//!    independently, with probability `p`, gets a spike `k_n ± 2^b` counts, the sign `+` or `−`
//!    equally likely and `b` drawn uniformly from [`Encoder::BIT_ERROR_BITS`] = {6, 7, 8, 9}
//!    (a flipped bit of a binary count: 64 to 512 counts);
//! 5. **the report**: the count modulo `N`, in `[0, N)` ([`Encoder::observe_counts`]), or the angle
//!    `k · 2π / N` in the encoder's [`AngleRange`], `[−π, π)` by default or `[0, 2π)`
//!    ([`Encoder::observe`]); [`Encoder::observe_continuous`] keeps every turn (a multi-turn
//!    encoder, or a displacement on the line).
//!
//! Without counts steps 3 and 4 are skipped and the angle `θ_n − o + ε_n` is reported wrapped
//! into the range: `x_n = wrap(θ_n + ε_n)` for an encoder with only noise, and an ideal encoder
//! (`σ = 0`, the default) only wraps. Every seeded noisy record of the workspace (the command
//! line's `simulate`, the accuracy studies, the tests) is made here, so one seed and stream give
//! one record everywhere.
//!
//! The noise is drawn from ChaCha8 (`rand_chacha`) seeded by [`SeedableRng::seed_from_u64`], one
//! normal number per sample in sample order, so a shorter record gets the first samples' noise of a
//! longer one with the same seed and stream. The bit errors are drawn from the same seed and
//! stream starting at word `2^66` (far beyond any record's noise), in sample order: a uniform
//! number for whether the sample is hit, then, if it is, the bit and the sign. So adding bit errors
//! does not change the noise, and a shorter record gets the first samples' errors of a longer one.
//!
//! [`Gaps`] says which samples a data acquisition drops: `K` gaps of `L` samples each at seeded
//! random places. [`Jitter`] moves the time stamps a data acquisition writes off the instants the
//! samples were taken at: seeded Gaussian errors of the clock.
//!
//! A record of several coordinates has one encoder per angle: the same settings, each drawing
//! from its own stream of the seed ([`Encoder::with_stream`], stream `c` for coordinate `c`), so
//! that the first coordinate's record is the one-coordinate record of that seed and the others'
//! noise and bit errors are independent of it.
//!
//! [`Trajectory`]: crate::Trajectory

use std::collections::BTreeSet;
use std::f64::consts::TAU;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use crate::error::SimError;

/// Where the bit errors' draws start in the encoder's ChaCha8 stream, in 32-bit words.
const BIT_ERROR_WORD: u128 = 1 << 66;
/// Where the gaps' draws start in ChaCha8 stream 0 of their seed, in 32-bit words.
const GAPS_WORD: u128 = 1 << 67;
/// Where the time stamps' jitter is drawn from in ChaCha8 stream 0 of its seed, in 32-bit words.
const JITTER_WORD: u128 = 1 << 68;

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

/// The interval an encoder reports a wrapped angle in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum AngleRange {
    /// `[−π, π)`: zero at the encoder's zero, negative on one side.
    #[default]
    Signed,
    /// `[0, 2π)`: the count times `2π / N`, as an incremental encoder's counter reads.
    Positive,
}

impl AngleRange {
    /// `x` (radians, finite) moved by whole turns into the range.
    pub fn wrap(self, x: f64) -> f64 {
        match self {
            Self::Signed => circle_signal::wrap(x),
            Self::Positive => {
                let r = x.rem_euclid(TAU);
                // A tiny negative x rounds up to 2π itself.
                if r >= TAU { 0.0 } else { r }
            }
        }
    }
}

/// A model of an angle encoder: zero offset, seeded Gaussian noise, counts per turn, seeded bit
/// errors, the angle reported in a range.
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
/// // A 4096-count encoder whose zero is 0.1 rad from the bottom, with rare bit errors.
/// let rig = Encoder::seeded(7).with_counts(4096)?.with_zero_offset(0.1)?.with_bit_errors(1e-3)?;
/// let counts = rig.observe_counts(&theta).expect("counts are set");
/// assert!(counts.iter().all(|&k| k < 4096));
/// # Ok::<(), pendulum_sim::SimError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Encoder {
    sigma: f64,
    seed: u64,
    stream: u64,
    draw: NormalDraw,
    counts: Option<u32>,
    offset: f64,
    bit_error_rate: f64,
    range: AngleRange,
}

impl Encoder {
    /// The bits a bit error flips: a spike of `±2^b` counts, `b` drawn uniformly from these.
    pub const BIT_ERROR_BITS: [u32; 4] = [6, 7, 8, 9];

    /// The fewest counts per turn bit errors are modelled with: `2 · 2^9`, so that the largest
    /// spike is at most half a turn and is seen at its size.
    pub const BIT_ERROR_MIN_COUNTS: u32 = 1024;

    /// An ideal encoder (no noise, no offset, no quantisation, no bit errors, angles in
    /// `[−π, π)`) whose random effects, once set, are drawn from ChaCha8 seeded with `seed`,
    /// stream 0, the noise by [`NormalDraw::Ziggurat`].
    pub fn seeded(seed: u64) -> Self {
        Self {
            sigma: 0.0,
            seed,
            stream: 0,
            draw: NormalDraw::Ziggurat,
            counts: None,
            offset: 0.0,
            bit_error_rate: 0.0,
            range: AngleRange::Signed,
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

    /// The ChaCha8 stream of the seed the noise and bit errors are drawn from (`0` by default):
    /// independent records from one seed.
    pub fn with_stream(mut self, stream: u64) -> Self {
        self.stream = stream;
        self
    }

    /// How the normal numbers are drawn ([`NormalDraw::Ziggurat`] by default).
    pub fn with_draw(mut self, draw: NormalDraw) -> Self {
        self.draw = draw;
        self
    }

    /// `counts` counts per turn (at least 2; at least [`Self::BIT_ERROR_MIN_COUNTS`] when bit
    /// errors are set): the angle is reported to the nearest count.
    pub fn with_counts(mut self, counts: u32) -> Result<Self, SimError> {
        if counts < 2 {
            return Err(SimError::InvalidParameter {
                name: "counts per turn",
                value: f64::from(counts),
                why: "must be at least 2",
            });
        }
        if self.bit_error_rate > 0.0 && counts < Self::BIT_ERROR_MIN_COUNTS {
            return Err(SimError::InvalidParameter {
                name: "counts per turn",
                value: f64::from(counts),
                why: "must be at least 1024 with bit errors (spikes of up to 512 counts)",
            });
        }
        self.counts = Some(counts);
        Ok(self)
    }

    /// The encoder's zero is `offset` radians (finite) from the angle's zero: it reports
    /// `θ − offset`.
    pub fn with_zero_offset(mut self, offset: f64) -> Result<Self, SimError> {
        if !offset.is_finite() {
            return Err(SimError::InvalidParameter {
                name: "zero offset",
                value: offset,
                why: "must be finite",
            });
        }
        self.offset = offset;
        Ok(self)
    }

    /// Bit errors: each sample, with probability `rate` (in `[0, 1]`), gets a spike of `±2^b`
    /// counts, `b` from [`Self::BIT_ERROR_BITS`]. A positive rate needs the counts per turn set
    /// first ([`with_counts`](Self::with_counts), at least [`Self::BIT_ERROR_MIN_COUNTS`]).
    pub fn with_bit_errors(mut self, rate: f64) -> Result<Self, SimError> {
        if !(0.0..=1.0).contains(&rate) {
            return Err(SimError::InvalidParameter {
                name: "bit error rate",
                value: rate,
                why: "must lie in [0, 1]",
            });
        }
        if rate > 0.0 {
            match self.counts {
                None => {
                    return Err(SimError::InvalidParameter {
                        name: "bit error rate",
                        value: rate,
                        why: "needs the encoder's counts per turn: bit errors are errors of the count",
                    });
                }
                Some(n) if n < Self::BIT_ERROR_MIN_COUNTS => {
                    return Err(SimError::InvalidParameter {
                        name: "counts per turn",
                        value: f64::from(n),
                        why: "must be at least 1024 with bit errors (spikes of up to 512 counts)",
                    });
                }
                Some(_) => {}
            }
        }
        self.bit_error_rate = rate;
        Ok(self)
    }

    /// The interval the wrapped angle is reported in ([`AngleRange::Signed`] by default).
    pub fn with_range(mut self, range: AngleRange) -> Self {
        self.range = range;
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
    /// Counts per turn, if the angle is quantised.
    pub fn counts(&self) -> Option<u32> {
        self.counts
    }
    /// The zero offset in radians.
    pub fn zero_offset(&self) -> f64 {
        self.offset
    }
    /// The probability of a bit error per sample.
    pub fn bit_error_rate(&self) -> f64 {
        self.bit_error_rate
    }
    /// The interval of the reported angle.
    pub fn range(&self) -> AngleRange {
        self.range
    }

    /// What the encoder reports of the angle `theta`: the count's angle `k · 2π / N` (with
    /// counts) or the angle itself, wrapped into the encoder's range (`[−π, π)` by default).
    pub fn observe(&self, theta: &[f64]) -> Vec<f64> {
        let mut reader = self.reader();
        theta.iter().map(|&v| reader.observe(v)).collect()
    }

    /// The angle as the encoder sees it, not wrapped: `θ_n − o + ε_n`, or with counts the whole
    /// count over every turn times `2π / N` (a multi-turn encoder). A record of the continuous
    /// angle (or, without counts and offset, of a displacement on the line with noise). Its wrap
    /// into the range is [`Encoder::observe`].
    pub fn observe_continuous(&self, theta: &[f64]) -> Vec<f64> {
        let mut reader = self.reader();
        theta.iter().map(|&v| reader.observe_continuous(v)).collect()
    }

    /// The counts the encoder reports, in `[0, N)`; `None` when the encoder has no counts per
    /// turn.
    pub fn observe_counts(&self, theta: &[f64]) -> Option<Vec<u32>> {
        self.counts?;
        let mut reader = self.reader();
        theta.iter().map(|&v| reader.observe_count(v)).collect()
    }

    /// The encoder's reports one sample at a time, in sample order: the numbers
    /// [`observe`](Self::observe), [`observe_continuous`](Self::observe_continuous) and
    /// [`observe_counts`](Self::observe_counts) give for a whole record, without holding it (a
    /// record written as it is simulated). One reader serves one record: its noise and bit errors
    /// go on from sample to sample.
    ///
    /// ```
    /// use pendulum_sim::observe::Encoder;
    ///
    /// let encoder = Encoder::seeded(7).with_noise(0.01)?.with_counts(4096)?.with_bit_errors(0.1)?;
    /// let theta: Vec<f64> = (0..100).map(|n| 0.1 * n as f64).collect();
    /// let mut reader = encoder.reader();
    /// let one_by_one: Vec<f64> = theta.iter().map(|&v| reader.observe(v)).collect();
    /// assert_eq!(one_by_one, encoder.observe(&theta));
    /// # Ok::<(), pendulum_sim::SimError>(())
    /// ```
    pub fn reader(&self) -> EncoderReader {
        let mut noise = ChaCha8Rng::seed_from_u64(self.seed);
        noise.set_stream(self.stream);
        let mut errors = ChaCha8Rng::seed_from_u64(self.seed);
        errors.set_stream(self.stream);
        errors.set_word_pos(BIT_ERROR_WORD);
        EncoderReader {
            encoder: *self,
            normal: Normal::new(0.0, self.sigma).expect("sigma checked finite and >= 0"),
            noise,
            errors,
        }
    }
}

/// An [`Encoder`]'s reports of a record one sample at a time ([`Encoder::reader`]).
#[derive(Debug, Clone)]
pub struct EncoderReader {
    encoder: Encoder,
    normal: Normal<f64>,
    /// The noise's draws, one normal number per sample.
    noise: ChaCha8Rng,
    /// The bit errors' draws, from word `2^66` of the same seed and stream.
    errors: ChaCha8Rng,
}

impl EncoderReader {
    /// What the encoder reports of the next sample's angle `theta` ([`Encoder::observe`]).
    pub fn observe(&mut self, theta: f64) -> f64 {
        let e = self.encoder;
        match e.counts {
            None => {
                let v = self.reading(theta);
                e.range.wrap(v)
            }
            Some(n) => {
                let k = self.turn_count(theta, n);
                let n = i64::from(n);
                let k = k.rem_euclid(n);
                let k = match e.range {
                    AngleRange::Positive => k,
                    AngleRange::Signed if 2 * k >= n => k - n,
                    AngleRange::Signed => k,
                };
                TAU * k as f64 / n as f64
            }
        }
    }

    /// The next sample's angle as the encoder sees it, not wrapped
    /// ([`Encoder::observe_continuous`]).
    pub fn observe_continuous(&mut self, theta: f64) -> f64 {
        match self.encoder.counts {
            None => self.reading(theta),
            Some(n) => TAU * self.turn_count(theta, n) as f64 / f64::from(n),
        }
    }

    /// The count the encoder reports of the next sample, in `[0, N)`; `None` when the encoder has
    /// no counts per turn (and then no sample is read).
    pub fn observe_count(&mut self, theta: f64) -> Option<u32> {
        let n = self.encoder.counts?;
        let k = self.turn_count(theta, n);
        Some(u32::try_from(k.rem_euclid(i64::from(n))).expect("a count modulo a u32 fits a u32"))
    }

    /// The whole count over every turn of `counts` per turn, its bit error included.
    fn turn_count(&mut self, theta: f64, counts: u32) -> i64 {
        let per_radian = f64::from(counts) / TAU;
        let mut k = (self.reading(theta) * per_radian).round() as i64;
        let rate = self.encoder.bit_error_rate;
        if rate > 0.0 && self.errors.random::<f64>() < rate {
            let bits = Encoder::BIT_ERROR_BITS;
            let bit = bits[self.errors.random_range(0..bits.len())];
            let spike = 1i64 << bit;
            k += if self.errors.random::<bool>() {
                spike
            } else {
                -spike
            };
        }
        k
    }

    /// `θ_n − o + ε_n`: the offset, then the noise.
    fn reading(&mut self, theta: f64) -> f64 {
        let e = self.encoder;
        match e.draw {
            NormalDraw::Ziggurat => (theta - e.offset) + self.normal.sample(&mut self.noise),
            NormalDraw::BoxMuller => {
                let rng = &mut self.noise;
                let (u1, u2): (f64, f64) = (rng.random_range(f64::EPSILON..1.0), rng.random());
                (theta - e.offset) + e.sigma * (-2.0 * u1.ln()).sqrt() * (TAU * u2).cos()
            }
        }
    }
}

/// Samples a data acquisition drops: `count` gaps of `length` consecutive samples each, at
/// seeded random places.
///
/// The gaps are placed uniformly at random among all placements that keep at least one sample
/// before the first gap, between any two gaps and after the last (so the record keeps its first
/// and last samples and no two gaps merge): with `M = samples − count · length` kept samples, the
/// gaps fall after `count` distinct kept samples drawn uniformly from the first `M − 1` (Floyd's
/// algorithm on ChaCha8 seeded with the seed, stream 0, from word `2^67`, so that the gaps are
/// independent of an encoder's noise and bit errors from the same seed).
///
/// ```
/// use pendulum_sim::observe::Gaps;
///
/// let gaps = Gaps::new(3, 10)?.seeded(5);
/// let kept = gaps.kept(1000)?;
/// assert_eq!(kept.iter().filter(|&&k| !k).count(), 30);
/// assert!(kept[0] && kept[999]);
/// # Ok::<(), pendulum_sim::SimError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Gaps {
    count: usize,
    length: usize,
    seed: u64,
}

impl Gaps {
    /// `count >= 1` gaps of `length >= 1` samples, seed 0.
    pub fn new(count: usize, length: usize) -> Result<Self, SimError> {
        if count == 0 {
            return Err(SimError::InvalidParameter {
                name: "number of gaps",
                value: 0.0,
                why: "must be at least 1",
            });
        }
        if length == 0 {
            return Err(SimError::InvalidParameter {
                name: "gap length",
                value: 0.0,
                why: "must be at least 1 sample",
            });
        }
        Ok(Self {
            count,
            length,
            seed: 0,
        })
    }

    /// The seed of the places.
    pub fn seeded(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// Number of gaps.
    pub fn count(&self) -> usize {
        self.count
    }
    /// Samples per gap.
    pub fn length(&self) -> usize {
        self.length
    }
    /// The seed.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// The fewest samples a record needs for these gaps: `count · (length + 1) + 1`, or `None`
    /// if that overflows.
    pub fn min_samples(&self) -> Option<usize> {
        self.count
            .checked_mul(self.length.checked_add(1)?)?
            .checked_add(1)
    }

    /// The first dropped sample of each gap, in increasing order, for a record of `samples`.
    ///
    /// Errors: fewer samples than [`min_samples`](Self::min_samples).
    pub fn starts(&self, samples: usize) -> Result<Vec<usize>, SimError> {
        match self.min_samples() {
            Some(min) if samples >= min => {}
            _ => {
                return Err(SimError::InvalidParameter {
                    name: "samples",
                    value: samples as f64,
                    why: "too few for the gaps: need count × (length + 1) + 1",
                });
            }
        }
        let kept = samples - self.count * self.length;
        // Floyd: `count` distinct values of 0 .. kept − 1, each the index of the kept sample a gap
        // follows, minus one.
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        rng.set_word_pos(GAPS_WORD);
        let range = kept - 1;
        let mut chosen = BTreeSet::new();
        for j in range - self.count..range {
            let t = rng.random_range(0..=j);
            if !chosen.insert(t) {
                chosen.insert(j);
            }
        }
        Ok(chosen
            .into_iter()
            .enumerate()
            .map(|(i, after)| after + 1 + i * self.length)
            .collect())
    }

    /// Which of `samples` samples are kept (`false` inside a gap).
    ///
    /// Errors: fewer samples than [`min_samples`](Self::min_samples).
    pub fn kept(&self, samples: usize) -> Result<Vec<bool>, SimError> {
        let mut kept = vec![true; samples];
        for start in self.starts(samples)? {
            kept[start..start + self.length].fill(false);
        }
        Ok(kept)
    }
}

/// The jitter of a data acquisition's time stamps: each written stamp is the instant its sample
/// was taken plus an independent Gaussian error of standard deviation `sigma` (in the record's
/// time unit), as a logger whose clock is read a little early or late writes them; the samples
/// themselves are those of the true instants.
///
/// The errors are drawn from ChaCha8 seeded with the seed, stream 0, from word `2^68`, one normal
/// number per sample in sample order (so that they are independent of an encoder's noise and bit
/// errors and of the gaps from the same seed, and a shorter record gets the first samples' errors
/// of a longer one).
///
/// ```
/// use pendulum_sim::observe::Jitter;
///
/// let t: Vec<f64> = (0..1000).map(|n| n as f64 * 0.002).collect();
/// let stamps = Jitter::new(1e-5)?.seeded(3).apply(&t);
/// assert!(stamps.iter().zip(&t).all(|(s, t)| (s - t).abs() < 1e-4));
/// assert_eq!(stamps, Jitter::new(1e-5)?.seeded(3).apply(&t));
/// # Ok::<(), pendulum_sim::SimError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Jitter {
    sigma: f64,
    seed: u64,
}

impl Jitter {
    /// Jitter of standard deviation `sigma` (finite, `>= 0`), seed 0.
    pub fn new(sigma: f64) -> Result<Self, SimError> {
        if !(sigma.is_finite() && sigma >= 0.0) {
            return Err(SimError::InvalidParameter {
                name: "jitter standard deviation",
                value: sigma,
                why: "must be finite and >= 0",
            });
        }
        Ok(Self { sigma, seed: 0 })
    }

    /// The seed of the errors.
    pub fn seeded(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// The standard deviation.
    pub fn sigma(&self) -> f64 {
        self.sigma
    }
    /// The seed.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// The stamps written for samples taken at `t`.
    pub fn apply(&self, t: &[f64]) -> Vec<f64> {
        let mut stamps = self.stamps();
        t.iter().map(|&t| stamps.stamp(t)).collect()
    }

    /// The stamps one sample at a time, in sample order: the numbers [`apply`](Self::apply) gives
    /// for a whole record, without holding it.
    pub fn stamps(&self) -> JitterStamps {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        rng.set_word_pos(JITTER_WORD);
        JitterStamps {
            normal: Normal::new(0.0, self.sigma).expect("sigma checked finite and >= 0"),
            rng,
        }
    }
}

/// A [`Jitter`]'s stamps of a record one sample at a time ([`Jitter::stamps`]).
#[derive(Debug, Clone)]
pub struct JitterStamps {
    normal: Normal<f64>,
    rng: ChaCha8Rng,
}

impl JitterStamps {
    /// The stamp written for the next sample, taken at `t`.
    pub fn stamp(&mut self, t: f64) -> f64 {
        t + self.normal.sample(&mut self.rng)
    }
}
