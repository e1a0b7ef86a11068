//! The outlier search on a vibrometer's velocity record on the line: the velocity of the chaotic
//! two-well Duffing oscillator sampled 100 to 1024 times per forcing period (a drive of 20 to
//! 2 Hz at 2048 Hz), with measurement noise whose level is constant or changes along the record,
//! and injected dropouts. The bounds come from the tables of `docs/spikes.md`
//! (`cargo run --release -p circle-signal --example spike_outliers`).

use std::collections::BTreeSet;

use crate::support::{VibrometerNoise, duffing, vibrometer};
use circle_signal::{Domain, SpikeParams, find_spikes};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const SAMPLES: usize = 100_000;

/// The standard deviation of a centred residual of white noise of unit standard deviation.
const RESIDUAL: f64 = 1.394_433_963_956_97;

fn alarms(x: &[f64]) -> Vec<usize> {
    find_spikes(x, Domain::Line, &SpikeParams::new())
        .expect("search")
        .indices()
        .collect()
}

/// Ordinary noise raises no alarm: white noise from 10⁻³ to 10⁻¹ of the velocity, coloured
/// noise, and noise whose level rises to five times in bursts of 100 samples. With the block
/// scale alone (the test before the local scale) the bursts gave 324 to 464 alarms in 4 · 10⁵
/// samples at each rate; with the local scale none in 1.6 · 10⁶.
#[test]
fn ordinary_noise_of_any_level_raises_no_alarm() {
    for (p, per_period) in [100.0, 256.0, 1024.0].into_iter().enumerate() {
        let cases = [
            (VibrometerNoise::White, 1e-3),
            (VibrometerNoise::White, 1e-1),
            (VibrometerNoise::Coloured, 1e-2),
            (
                VibrometerNoise::Bursts {
                    len: 100,
                    factor: 5.0,
                },
                1e-2,
            ),
        ];
        for (c, (noise, relative)) in cases.into_iter().enumerate() {
            let seed = 100 + 10 * p as u64 + c as u64;
            let x = vibrometer(per_period, SAMPLES, relative, noise, seed);
            let found = alarms(&x);
            assert!(
                found.is_empty(),
                "{noise:?} {relative} at {per_period} per period: {} alarms, first {:?}",
                found.len(),
                &found[..found.len().min(5)]
            );
        }
    }
}

/// Speckle noise whose level changes by up to 4.5 times within about a hundred samples (cells of
/// one unit of displacement at 1024 samples per period): 1.0 · 10⁻⁵ alarms per sample were
/// measured (4 in 4 · 10⁵), against 4.6 · 10⁻⁴ with the block scale alone. The bound, 5 · 10⁻⁵, is
/// where a Poisson count of mean 2 lies with probability below 10⁻⁴.
#[test]
fn speckle_noise_changing_over_a_hundred_samples_raises_few_alarms() {
    let mut total = 0;
    for seed in 0..2 {
        let x = vibrometer(1024.0, SAMPLES, 1e-2, VibrometerNoise::Speckle(1.0), 200 + seed);
        total += alarms(&x).len();
    }
    assert!(total <= 10, "{total} alarms in {} samples", 2 * SAMPLES);
}

/// Injects runs of `len` samples about 600 apart, every sample of a run moved by `size` or, with
/// `size` NaN, dropped to a tenth; returns the record and each run's first sample and largest
/// move.
fn dropouts(x: &[f64], len: usize, size: f64, seed: u64) -> (Vec<f64>, Vec<(usize, f64)>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut y = x.to_vec();
    let mut at = Vec::new();
    let mut i = 300 + rng.random_range(0..300);
    while i + len + 300 < y.len() {
        let sign = if rng.random::<bool>() { 1.0 } else { -1.0 };
        let mut moved: f64 = 0.0;
        for k in 0..len {
            let before = y[i + k];
            y[i + k] = if size.is_nan() {
                0.1 * before
            } else {
                before + sign * size
            };
            moved = moved.max((y[i + k] - before).abs());
        }
        at.push((i, moved));
        i += 400 + rng.random_range(0..400);
    }
    (y, at)
}

/// Runs of one to three samples moved by 16 residual standard deviations are found whole: 100,
/// 99.9 and 100 % of 667 each were measured (the block scale alone found no run of two or three
/// whole). Runs dropped to a tenth by 24 standard deviations or more: all of 1593 found. Nothing
/// else is flagged (at most one sample besides the runs was measured per case).
#[test]
fn vibrometer_dropouts_of_one_to_three_samples_are_found() {
    let relative = 1e-2;
    let (_, v) = duffing(256.0, SAMPLES);
    let rms = (v.iter().map(|a| a * a).sum::<f64>() / v.len() as f64).sqrt();
    let sigma_r = RESIDUAL * relative * rms;
    for len in 1..=3usize {
        let x = vibrometer(256.0, SAMPLES, relative, VibrometerNoise::White, 300 + len as u64);
        for (size, what) in [(16.0 * sigma_r, "16 σ_r"), (f64::NAN, "drop to a tenth")] {
            let (y, at) = dropouts(&x, len, size, 310 + len as u64);
            let found: BTreeSet<usize> = alarms(&y).into_iter().collect();
            let runs: Vec<_> = at.iter().filter(|&&(_, moved)| moved >= 16.0 * sigma_r).collect();
            let whole = runs
                .iter()
                .filter(|&&&(i, _)| (i..i + len).all(|j| found.contains(&j)))
                .count();
            let inside: usize = at
                .iter()
                .map(|&(i, _)| (i..i + len).filter(|j| found.contains(j)).count())
                .sum();
            if size.is_nan() {
                // Drops of 24 σ_r and more: every one.
                let big: Vec<_> = at.iter().filter(|&&(_, moved)| moved >= 24.0 * sigma_r).collect();
                let big_whole = big
                    .iter()
                    .filter(|&&&(i, _)| (i..i + len).all(|j| found.contains(&j)))
                    .count();
                assert!(big.len() > 100, "{} drops", big.len());
                assert_eq!(big_whole, big.len(), "runs of {len}, {what}");
            } else {
                assert!(runs.len() > 150, "{} runs", runs.len());
                assert!(
                    whole as f64 >= 0.99 * runs.len() as f64,
                    "runs of {len}, {what}: {whole} of {} found whole",
                    runs.len()
                );
            }
            assert!(
                found.len() - inside <= 2,
                "runs of {len}, {what}: {} flagged besides",
                found.len() - inside
            );
        }
    }
}

/// Isolated spikes only (`max_run` 1), the test an encoder's bit errors need: a run of two is
/// never replaced as a run, and a single spike still is.
#[test]
fn isolated_spikes_only_when_asked() {
    let x = vibrometer(256.0, 20_000, 1e-2, VibrometerNoise::White, 400);
    let (_, v) = duffing(256.0, 20_000);
    let rms = (v.iter().map(|a| a * a).sum::<f64>() / v.len() as f64).sqrt();
    let s = 50.0 * RESIDUAL * 1e-2 * rms;
    let mut y = x.clone();
    y[5000] += s;
    y[5001] += s;
    y[9000] -= s;
    let isolated = SpikeParams::new().with_max_run(1).expect("valid");
    let found: Vec<usize> = find_spikes(&y, Domain::Line, &isolated)
        .expect("search")
        .indices()
        .collect();
    assert!(found.contains(&9000), "{found:?}");
    assert!(!(found.contains(&5000) && found.contains(&5001)), "{found:?}");
    let runs: Vec<usize> = alarms(&y);
    assert_eq!(runs, [5000, 5001, 9000]);
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig {
        cases: 256,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x0071_1e55),
        ..proptest::prelude::ProptestConfig::default()
    })]

    /// Any finite record of any length the test takes, with any longest run: no panic, each
    /// sample flagged at most once, every replacement finite, and the in-place search agrees.
    #[test]
    fn any_record_is_searched(
        values in proptest::collection::vec(-1e3..1e3f64, 7..400),
        outliers in proptest::collection::vec((0usize..400, -1e6..1e6f64), 0..20),
        max_run in 1usize..=SpikeParams::MAX_RUN,
        circle in proptest::bool::ANY,
    ) {
        let mut x = values;
        let n = x.len();
        for (i, v) in outliers {
            x[i % n] = v;
        }
        let domain = if circle { Domain::Circle } else { Domain::Line };
        let params = SpikeParams::new().with_max_run(max_run).unwrap();
        let found = find_spikes(&x, domain, &params).unwrap();
        let at: Vec<usize> = found.indices().collect();
        proptest::prop_assert!(at.windows(2).all(|w| w[0] < w[1]), "{:?}", at);
        proptest::prop_assert!(at.iter().all(|&i| i < n));
        proptest::prop_assert!(found.iter().all(|s| s.replacement.is_finite() && s.size.is_finite()));
        let mut y = x.clone();
        let in_place = circle_signal::find_and_repair_spikes(&mut y, domain, &params).unwrap();
        proptest::prop_assert_eq!(in_place, found);
    }
}
