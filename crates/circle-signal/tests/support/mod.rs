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
