//! Encoder-like test records for the spike search: smooth angles, quantised to a number of counts
//! per turn, with Gaussian noise and injected bit errors of `±2^k` counts.
#![allow(dead_code)]

use std::f64::consts::TAU;

use circle_signal::wrap;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// Counts per turn of the simulated encoder.
pub const COUNTS: f64 = 4096.0;

/// One count, in radians.
pub const COUNT: f64 = TAU / COUNTS;

/// The continuous angle of a pendulum-like motion at non-dimensional time `t` (forcing period 2π).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Motion {
    /// Whirling at a rate that swings between rest and one turn per forcing period (over about
    /// 70 periods), plus a swing at the drive and harmonics 2, 3 and 5 whose amplitude comes and
    /// goes (over about 80 periods): fast in places, slow elsewhere.
    Whirl,
    /// Oscillation about the hanging position, 1.2 rad at the drive plus harmonics 3 and 5.
    Swing,
    /// A slow swing of 0.3 rad, with bursts of fast motion (harmonics 2, 3 and 5 up to 2 rad per
    /// unit time) lasting about 10 forcing periods every 48: the smooth motion's residual at 25
    /// samples per period is a count or less between bursts and about 15 counts in them.
    Burst,
}

impl Motion {
    /// The angle at time `t`.
    pub fn angle(self, t: f64) -> f64 {
        match self {
            Self::Whirl => {
                let m = 0.5 * (1.0 + (t / 13.0).sin());
                0.5 * t
                    + 5.5 * (t / 11.0).sin()
                    + 0.8 * (t + 0.3).sin()
                    + m * (0.3 * (2.0 * t + 1.1).sin()
                        + 0.1 * (3.0 * t + 2.0).sin()
                        + 0.02 * (5.0 * t + 0.5).sin())
            }
            Self::Swing => 1.2 * (t + 0.4).sin() + 0.15 * (3.0 * t + 1.0).sin() + 0.02 * (5.0 * t).sin(),
            Self::Burst => {
                let b = (0.5 * (1.0 + (t * TAU / 300.0).cos())).powi(8);
                0.3 * (t + 0.2).sin()
                    + b * (0.6 * (2.0 * t + 1.0).sin()
                        + 0.2 * (3.0 * t + 2.0).sin()
                        + 0.04 * (5.0 * t + 0.5).sin())
            }
        }
    }
}

/// A record: the encoder's counts (before wrapping) and whether they are rounded.
#[derive(Debug, Clone)]
pub struct Record {
    /// The reported angle of every sample before wrapping (counts times one count when quantised).
    pub continuous: Vec<f64>,
    /// Rounded to whole counts.
    pub quantised: bool,
}

impl Record {
    /// `n` samples of `motion` at `per_period` samples per forcing period, with Gaussian noise of
    /// standard deviation `sigma` (seeded), rounded to whole counts when `quantised`.
    pub fn new(motion: Motion, per_period: f64, n: usize, sigma: f64, quantised: bool, seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let normal = Normal::new(0.0, 1.0).expect("unit normal");
        let continuous = (0..n)
            .map(|i| {
                let theta = motion.angle(i as f64 * TAU / per_period) + sigma * normal.sample(&mut rng);
                if quantised {
                    (theta / COUNT).round() * COUNT
                } else {
                    theta
                }
            })
            .collect();
        Self {
            continuous,
            quantised,
        }
    }

    /// The record as the encoder reports it, wrapped into `[−π, π)`.
    pub fn wrapped(&self) -> Vec<f64> {
        self.continuous.iter().map(|&v| wrap(v)).collect()
    }
}

/// An injected spike: sample and size in counts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Injected {
    /// Sample index.
    pub index: usize,
    /// Size in counts (a whole number).
    pub counts: f64,
}

/// Isolated positions in `[2, n − 2)`, each sample with probability `rate`, at least `gap` apart.
pub fn positions(n: usize, rate: f64, gap: usize, seed: u64) -> Vec<usize> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out: Vec<usize> = Vec::new();
    for i in 2..n - 2 {
        if rng.random::<f64>() < rate && out.last().is_none_or(|&l| i >= l + gap) {
            out.push(i);
        }
    }
    out
}

/// Spikes of `±2^k` counts, `k` drawn from `powers`, at the given positions.
pub fn bit_errors(at: &[usize], powers: &[u32], seed: u64) -> Vec<Injected> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    at.iter()
        .map(|&index| {
            let k = powers[rng.random_range(0..powers.len())];
            let sign = if rng.random::<bool>() { 1.0 } else { -1.0 };
            Injected {
                index,
                counts: sign * f64::from(1u32 << k),
            }
        })
        .collect()
}

/// The wrapped record with the spikes added (by whole counts, so a quantised record stays on
/// its counts).
pub fn inject(clean: &[f64], spikes: &[Injected]) -> Vec<f64> {
    let mut x = clean.to_vec();
    for s in spikes {
        x[s.index] = wrap(x[s.index] + s.counts * COUNT);
    }
    x
}

/// The paper's data set (`shared/fixtures/paper_dataset.csv`): 30000 wrapped samples of the
/// chaotic pendulum at 25 per forcing period.
pub fn paper_record() -> Vec<f64> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/fixtures/paper_dataset.csv"
    );
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .skip(1)
        .map(|l| {
            l.split(',')
                .nth(1)
                .and_then(|c| c.trim().parse().ok())
                .unwrap_or_else(|| panic!("bad line {l}"))
        })
        .collect()
}

/// The paper's record rounded to whole counts, with Gaussian noise of `sigma` added first.
pub fn paper_quantised(sigma: f64, seed: u64) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let normal = Normal::new(0.0, 1.0).expect("unit normal");
    paper_record()
        .into_iter()
        .map(|v| wrap(((v + sigma * normal.sample(&mut rng)) / COUNT).round() * COUNT))
        .collect()
}

/// What the search made of one record.
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    /// Samples in the record.
    pub samples: usize,
    /// Per power `k`: spikes injected and found (at their own index).
    pub per_power: Vec<(u32, usize, usize)>,
    /// Samples flagged that were not injected.
    pub false_alarms: usize,
    /// Samples flagged in the clean record.
    pub clean_flags: usize,
    /// Largest and root-mean-square circle distance between the repaired and the clean record at
    /// the repaired samples.
    pub repair_max: f64,
    /// See [`Outcome::repair_max`].
    pub repair_rms: f64,
    /// Winding of the whole record (turns from unwrapping, as `RotationSplit` counts them): clean,
    /// with the spikes, repaired.
    pub winding: (i64, i64, i64),
    /// Largest distance between the unwrapped repaired and unwrapped clean records (a false turn
    /// anywhere makes it at least about 2π).
    pub unwrap_gap: f64,
    /// The same with the spikes left in.
    pub unwrap_gap_spiked: f64,
}

impl Outcome {
    /// Spikes injected and found, over every power.
    pub fn totals(&self) -> (usize, usize) {
        self.per_power
            .iter()
            .fold((0, 0), |(i, f), &(_, a, b)| (i + a, f + b))
    }
}

/// Searches `clean` and `clean` with `spikes` injected on the circle, repairs, and compares.
pub fn run(clean: &[f64], spikes: &[Injected], params: &circle_signal::SpikeParams) -> Outcome {
    use circle_signal::{Domain, RotationSplit, circle_distance, find_spikes, repair_spikes, unwrap};
    let clean_flags = find_spikes(clean, Domain::Circle, params).expect("search").len();
    let mut x = inject(clean, spikes);
    let spiked = x.clone();
    let found = find_spikes(&x, Domain::Circle, params).expect("search");
    repair_spikes(&mut x, &found).expect("same record");
    let flagged: std::collections::BTreeSet<usize> = found.indices().collect();
    let mut per_power: Vec<(u32, usize, usize)> = Vec::new();
    for s in spikes {
        let k = s.counts.abs().log2().round() as u32;
        let hit = usize::from(flagged.contains(&s.index));
        match per_power.iter_mut().find(|p| p.0 == k) {
            Some(p) => {
                p.1 += 1;
                p.2 += hit;
            }
            None => per_power.push((k, 1, hit)),
        }
    }
    per_power.sort_by_key(|p| p.0);
    let injected: std::collections::BTreeSet<usize> = spikes.iter().map(|s| s.index).collect();
    let false_alarms = flagged.difference(&injected).count();
    let errors: Vec<f64> = found.indices().map(|i| circle_distance(x[i], clean[i])).collect();
    let repair_max = errors.iter().copied().fold(0.0, f64::max);
    let repair_rms = if errors.is_empty() {
        0.0
    } else {
        (errors.iter().map(|e| e * e).sum::<f64>() / errors.len() as f64).sqrt()
    };
    // Any positive step: the winding does not depend on it.
    let winding = |y: &[f64]| {
        RotationSplit::winding_and_rate(&unwrap(y), 1.0)
            .expect("winding")
            .0
    };
    let gap = |y: &[f64]| {
        unwrap(y)
            .iter()
            .zip(unwrap(clean))
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
    };
    Outcome {
        samples: clean.len(),
        per_power,
        false_alarms,
        clean_flags,
        repair_max,
        repair_rms,
        winding: (winding(clean), winding(&spiked), winding(&x)),
        unwrap_gap: gap(&x),
        unwrap_gap_spiked: gap(&spiked),
    }
}

/// The largest residual `|Δ⁴x / 6|` of the centred cubic prediction over a continuous
/// (unwrapped) record: what the smooth motion alone puts into the search's residuals.
pub fn smooth_residual_max(continuous: &[f64]) -> f64 {
    continuous
        .windows(5)
        .map(|w| ((w[0] - 4.0 * w[1] + 6.0 * w[2] - 4.0 * w[3] + w[4]) / 6.0).abs())
        .fold(0.0, f64::max)
}

/// [`smooth_residual_max`] of `motion` without noise or rounding.
pub fn motion_residual_max(motion: Motion, per_period: f64, n: usize) -> f64 {
    smooth_residual_max(&Record::new(motion, per_period, n, 0.0, false, 0).continuous)
}

/// The velocity of the two-well Duffing oscillator `x'' + 0.25 x' − x + x³ = 0.3 cos t` (chaotic,
/// forcing period 2π) at `per_period` samples per forcing period, `n` samples after 50 periods
/// of transient from `x = 0.1`, `x' = 0`; classical Runge–Kutta with 8 steps per sample. Also
/// returns the displacement.
pub fn duffing(per_period: f64, n: usize) -> (Vec<f64>, Vec<f64>) {
    let h = TAU / per_period / 8.0;
    let f = |t: f64, x: f64, v: f64| (v, -0.25 * v + x - x * x * x + 0.3 * t.cos());
    let (mut x, mut v, mut t) = (0.1, 0.0, 0.0);
    let skip = (50.0 * per_period).round() as usize;
    let (mut xs, mut vs) = (Vec::with_capacity(n), Vec::with_capacity(n));
    for i in 0..skip + n {
        if i >= skip {
            xs.push(x);
            vs.push(v);
        }
        for _ in 0..8 {
            let (k1x, k1v) = f(t, x, v);
            let (k2x, k2v) = f(t + h / 2.0, x + h / 2.0 * k1x, v + h / 2.0 * k1v);
            let (k3x, k3v) = f(t + h / 2.0, x + h / 2.0 * k2x, v + h / 2.0 * k2v);
            let (k4x, k4v) = f(t + h, x + h * k3x, v + h * k3v);
            x += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
            v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
            t += h;
        }
    }
    (xs, vs)
}

/// How a simulated vibrometer's noise behaves.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum VibrometerNoise {
    /// White Gaussian noise of constant level.
    White,
    /// Gaussian noise low-pass filtered (first order, correlation 0.7 from sample to sample),
    /// of the same standard deviation.
    Coloured,
    /// Speckle: the noise's standard deviation is `σ / √(0.05 + I)` over its mean, with the
    /// returned light's intensity `I = (1 + cos(2π x / c + φ)) / 2` changing with the
    /// displacement `x` over speckle cells of `c` (the wells are at ±1, the motion spans about
    /// 3): the level changes by up to 4.5 times, several times per forcing period.
    Speckle(f64),
    /// White noise, with bursts of `len` samples at `factor` times the level starting with
    /// probability 10⁻³ per sample.
    Bursts {
        /// Samples per burst.
        len: usize,
        /// Level in a burst over the level elsewhere.
        factor: f64,
    },
    /// Student's t with the given degrees of freedom (more than 2), scaled to the standard
    /// deviation: heavy tails.
    Student(f64),
}

/// A vibrometer's velocity record of [`duffing`]: noise of `relative` times the velocity's
/// root-mean-square, of the given kind, seeded.
pub fn vibrometer(per_period: f64, n: usize, relative: f64, noise: VibrometerNoise, seed: u64) -> Vec<f64> {
    let (x, v) = duffing(per_period, n);
    let rms = (v.iter().map(|a| a * a).sum::<f64>() / n as f64).sqrt();
    let sigma = relative * rms;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let normal = Normal::new(0.0, 1.0).expect("unit normal");
    let phase = rng.random_range(0.0..TAU);
    let cell = match noise {
        VibrometerNoise::Speckle(c) => c,
        _ => 1.0,
    };
    let level = |x: f64| (0.05 + 0.5 * (1.0 + (TAU * x / cell + phase).cos())).powf(-0.5);
    let mean_level = match noise {
        VibrometerNoise::Speckle(_) => x.iter().map(|&x| level(x)).sum::<f64>() / n as f64,
        _ => 1.0,
    };
    let mut coloured = 0.0;
    let mut burst = 0usize;
    x.iter()
        .zip(&v)
        .map(|(&x, &v)| {
            let e = match noise {
                VibrometerNoise::White => normal.sample(&mut rng),
                VibrometerNoise::Coloured => {
                    coloured = 0.7 * coloured + (1.0f64 - 0.49).sqrt() * normal.sample(&mut rng);
                    coloured
                }
                VibrometerNoise::Speckle(_) => level(x) / mean_level * normal.sample(&mut rng),
                VibrometerNoise::Bursts { len, factor } => {
                    if burst == 0 && rng.random::<f64>() < 1e-3 {
                        burst = len;
                    }
                    let f = if burst > 0 {
                        burst -= 1;
                        factor
                    } else {
                        1.0
                    };
                    f * normal.sample(&mut rng)
                }
                VibrometerNoise::Student(dof) => {
                    let t = rand_distr::StudentT::new(dof).expect("degrees of freedom");
                    t.sample(&mut rng) / (dof / (dof - 2.0)).sqrt()
                }
            };
            v + sigma * e
        })
        .collect()
}
