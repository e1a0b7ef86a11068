//! The spike search on encoder-like records: 4096 counts per turn, Gaussian noise of 0, 0.003 and
//! 0.01 rad, 25, 100 and 490.196 samples per forcing period, bit errors of `±2^k` counts at
//! isolated positions. The full table of rates is printed by
//! `cargo run --release -p circle-signal --example spike_rates`.

use std::f64::consts::{PI, TAU};

use crate::support::{
    COUNT, Injected, Motion, Outcome, Record, bit_errors, inject, motion_residual_max, paper_quantised,
    paper_record, positions, run, smooth_residual_max,
};
use circle_signal::{
    CircleError, Domain, SpikeParams, circle_distance, find_and_repair_spikes, find_spikes, repair_spikes,
    unwrap, wrap,
};
use proptest::prelude::*;
use proptest::test_runner::RngSeed;

const SAMPLES: usize = 100_000;
const RATE: f64 = 1e-3;
/// Spikes at least this far apart: isolated.
const GAP: usize = 5;

fn quantum() -> SpikeParams {
    SpikeParams::new().with_quantum(COUNT).expect("valid quantum")
}

/// The root-mean-square of the noise in a residual: the sample's and its prediction's
/// (`√(34)/6 σ`), each with its rounding to counts.
fn residual_noise(sigma: f64) -> f64 {
    ((1.0 + 34.0 / 36.0) * (sigma * sigma + COUNT * COUNT / 12.0)).sqrt()
}

/// One record with bit errors of 64 to 512 counts; the seed picks record, positions and sizes.
fn bit_error_case(motion: Motion, per_period: f64, sigma: f64, seed: u64) -> Outcome {
    let clean = Record::new(motion, per_period, SAMPLES, sigma, true, seed).wrapped();
    let spikes = bit_errors(&positions(SAMPLES, RATE, GAP, seed + 1), &[6, 7, 8, 9], seed + 2);
    run(&clean, &spikes, &quantum())
}

/// Asserts the common outcome: nothing flagged in the clean record or besides the spikes, the
/// repair at the noise level, the winding and every unwrapped sample kept.
///
/// An isolated spike's replacement is the prediction from clean neighbours, so it misses the
/// clean sample by exactly the clean record's residual there: noise (`residual_noise`) plus the
/// smooth motion's own residual, at most `smooth`.
fn assert_clean_repair(out: &Outcome, sigma: f64, smooth: f64, what: &str) {
    assert_eq!(out.clean_flags, 0, "{what}: false detections in the clean record");
    assert_eq!(out.false_alarms, 0, "{what}: samples flagged besides the spikes");
    let noise = residual_noise(sigma);
    assert!(
        out.repair_rms <= 1.3 * noise + smooth,
        "{what}: repair rms {} (noise {noise}, smooth motion {smooth})",
        out.repair_rms
    );
    assert!(
        out.repair_max <= 5.0 * noise + smooth,
        "{what}: repair max {} (noise {noise}, smooth motion {smooth})",
        out.repair_max
    );
    assert_eq!(out.winding.0, out.winding.2, "{what}: winding");
    assert!(
        out.unwrap_gap < 0.2,
        "{what}: unwrapped repaired record departs by {}",
        out.unwrap_gap
    );
}

#[test]
fn every_bit_error_is_found_at_100_and_490_samples_per_period() {
    for (m, motion) in [Motion::Whirl, Motion::Swing, Motion::Burst]
        .into_iter()
        .enumerate()
    {
        for (p, per_period) in [100.0, 500.0 / 1.02].into_iter().enumerate() {
            for (s, sigma) in [0.0, 0.003].into_iter().enumerate() {
                let seed = 1000 + 100 * m as u64 + 10 * p as u64 + 3 * s as u64;
                let out = bit_error_case(motion, per_period, sigma, seed);
                let what = format!("{motion:?} at {per_period} per period, sigma {sigma}");
                let (injected, found) = out.totals();
                assert!(injected > 50, "{what}: {injected} spikes");
                assert_eq!(found, injected, "{what}: {:?}", out.per_power);
                let smooth = motion_residual_max(motion, per_period, SAMPLES);
                assert_clean_repair(&out, sigma, smooth, &what);
            }
        }
    }
}

#[test]
fn at_25_samples_per_period_every_bit_error_is_found_up_to_003_rad() {
    for sigma in [0.0, 0.003] {
        for (m, motion) in [Motion::Whirl, Motion::Burst].into_iter().enumerate() {
            let out = bit_error_case(motion, 25.0, sigma, 2000 + 10 * m as u64);
            let what = format!("{motion:?} at 25 per period, sigma {sigma}");
            let (injected, found) = out.totals();
            assert_eq!(found, injected, "{what}: {:?}", out.per_power);
            assert_clean_repair(&out, sigma, motion_residual_max(motion, 25.0, SAMPLES), &what);
        }
        // The paper's chaotic record, quantised.
        let clean = paper_quantised(sigma, 2100);
        let spikes = bit_errors(&positions(clean.len(), RATE, GAP, 2101), &[6, 7, 8, 9], 2102);
        let out = run(&clean, &spikes, &quantum());
        let (injected, found) = out.totals();
        assert!(injected > 15);
        assert_eq!(found, injected, "paper, sigma {sigma}: {:?}", out.per_power);
        let smooth = smooth_residual_max(&unwrap(&paper_record()));
        assert_clean_repair(&out, sigma, smooth, "paper");
    }
}

/// At σ = 0.01 rad (9.1 counts of residual noise, a threshold of about 55 counts) a spike of 64
/// counts is 7 standard deviations: found about three times in four (the example prints the
/// rates). Spikes of 128 counts and more are all found, at every rate, with no false detection.
#[test]
fn at_001_rad_spikes_of_128_counts_and_more_are_all_found() {
    let (mut small, mut small_found) = (0, 0);
    for (m, motion) in [Motion::Whirl, Motion::Swing, Motion::Burst]
        .into_iter()
        .enumerate()
    {
        for (p, per_period) in [25.0, 100.0, 500.0 / 1.02].into_iter().enumerate() {
            let out = bit_error_case(motion, per_period, 0.01, 3000 + 100 * m as u64 + 10 * p as u64);
            let what = format!("{motion:?} at {per_period} per period");
            for &(k, injected, found) in &out.per_power {
                if k == 6 {
                    small += injected;
                    small_found += found;
                } else {
                    assert_eq!(found, injected, "{what}: 2^{k} counts");
                }
            }
            assert_clean_repair(
                &out,
                0.01,
                motion_residual_max(motion, per_period, SAMPLES),
                &what,
            );
        }
    }
    let rate = small_found as f64 / small as f64;
    assert!(small > 100, "{small} spikes of 64 counts");
    // 7.0 robust standard deviations over a threshold of 6: 84 % if the scale were exact; its
    // spread and the spikes' own contribution to it lower that. Far from both 0 and 1.
    assert!(
        (0.55..0.95).contains(&rate),
        "64-count spikes found: {small_found} of {small}"
    );
}

#[test]
fn half_a_turn_never_becomes_a_false_turn() {
    for (m, motion) in [Motion::Whirl, Motion::Swing].into_iter().enumerate() {
        for (p, per_period) in [25.0, 100.0, 500.0 / 1.02].into_iter().enumerate() {
            for (s, sigma) in [0.0, 0.003, 0.01].into_iter().enumerate() {
                let seed = 4000 + 100 * m as u64 + 10 * p as u64 + s as u64;
                let clean = Record::new(motion, per_period, SAMPLES, sigma, true, seed).wrapped();
                let spikes: Vec<Injected> = positions(SAMPLES, RATE, GAP, seed + 1)
                    .into_iter()
                    .enumerate()
                    .map(|(j, index)| Injected {
                        index,
                        counts: [2048.0, -2048.0, 2047.0, -2047.0][j % 4],
                    })
                    .collect();
                let out = run(&clean, &spikes, &quantum());
                let what = format!("{motion:?} at {per_period} per period, sigma {sigma}");
                let (injected, found) = out.totals();
                assert_eq!(found, injected, "{what}");
                assert_clean_repair(
                    &out,
                    sigma,
                    motion_residual_max(motion, per_period, SAMPLES),
                    &what,
                );
                // Left in, the spikes are unwrapped into false turns.
                assert!(out.unwrap_gap_spiked > PI, "{what}: {}", out.unwrap_gap_spiked);
            }
        }
    }
}

#[test]
fn spikes_at_the_ends_are_found_and_told_apart() {
    let n = 2000;
    let clean = Record::new(Motion::Whirl, 100.0, n, 0.003, true, 5000).wrapped();
    for index in [0, 1, 2, 3, 4, n - 5, n - 4, n - 3, n - 2, n - 1] {
        // The end samples' threshold is 6 times the interior one (about 100 counts here).
        for counts in [512.0, -512.0, 2048.0, 2047.0] {
            let x = inject(&clean, &[Injected { index, counts }]);
            let found = find_spikes(&x, Domain::Circle, &quantum()).expect("search");
            assert_eq!(
                found.indices().collect::<Vec<_>>(),
                vec![index],
                "{counts} counts at {index}"
            );
            let spike = found.as_slice()[0];
            assert!(circle_distance(spike.size, counts * COUNT) < 0.1, "{spike:?}");
            // The end sample's extrapolation has 8.4 times the noise of the clean sample.
            assert!(
                circle_distance(spike.replacement, clean[index]) < 0.15,
                "{spike:?}"
            );
        }
    }
}

#[test]
fn displacement_on_the_line() {
    // A displacement in metres from a linear encoder of 10 µm, 100 samples per period.
    let quantum = 1e-5;
    let clean: Vec<f64> = (0..20_000)
        .map(|i| {
            let t = i as f64 * TAU / 100.0;
            (0.02 * Motion::Swing.angle(t) / quantum).round() * quantum
        })
        .collect();
    let at = positions(clean.len(), RATE, GAP, 6000);
    let mut x = clean.clone();
    for (j, &i) in at.iter().enumerate() {
        x[i] += f64::from(1u32 << (6 + j % 4)) * quantum * if j % 2 == 0 { 1.0 } else { -1.0 };
    }
    let params = SpikeParams::new().with_quantum(quantum).expect("valid");
    assert!(
        find_spikes(&clean, Domain::Line, &params)
            .expect("search")
            .is_empty()
    );
    let found = find_spikes(&x, Domain::Line, &params).expect("search");
    assert_eq!(found.indices().collect::<Vec<_>>(), at);
    repair_spikes(&mut x, &found).expect("same record");
    for &i in &at {
        assert!((x[i] - clean[i]).abs() < 2.0 * quantum, "sample {i}");
    }
}

#[test]
fn in_place_search_equals_search_then_repair() {
    let clean = Record::new(Motion::Whirl, 100.0, 20_000, 0.003, true, 7000).wrapped();
    let spikes = bit_errors(&positions(clean.len(), RATE, GAP, 7001), &[6, 9, 11], 7002);
    let mut x = inject(&clean, &spikes);
    let found = find_spikes(&x, Domain::Circle, &quantum()).expect("search");
    let mut repaired = x.clone();
    repair_spikes(&mut repaired, &found).expect("same record");
    let in_place = find_and_repair_spikes(&mut x, Domain::Circle, &quantum()).expect("search");
    assert_eq!(in_place, found);
    assert_eq!(x, repaired);
    assert_eq!(found.len(), spikes.len());
    assert!(repaired.iter().all(|v| (-PI..PI).contains(v)));
}

#[test]
fn non_finite_samples_are_reported() {
    let mut x = Record::new(Motion::Swing, 100.0, 500, 0.0, false, 1).wrapped();
    x[321] = f64::NAN;
    let err = find_and_repair_spikes(&mut x, Domain::Circle, &SpikeParams::new()).unwrap_err();
    assert!(matches!(err, CircleError::NonFinite { index: 321, .. }), "{err}");
    assert!(x[322].is_finite());
}

/// A smooth angle: a constant rotation plus four harmonics of the drive, at least 25 samples per
/// forcing period and less than π over two samples.
fn smooth_angle() -> impl Strategy<Value = (f64, Vec<(f64, f64)>)> {
    (-1.5..1.5f64, prop::collection::vec((0.0..1.0f64, -PI..PI), 4)).prop_map(|(rate, harmonics)| {
        // Harmonic k at most 1.2 / k² rad: speed at most |rate| + 1.2 (1 + 1/2 + 1/3 + 1/4).
        let h = harmonics
            .into_iter()
            .enumerate()
            .map(|(k, (a, phase))| (1.2 * a / ((k + 1) * (k + 1)) as f64, phase))
            .collect();
        (rate, h)
    })
}

fn angle_at(rate: f64, harmonics: &[(f64, f64)], t: f64) -> f64 {
    rate * t
        + harmonics
            .iter()
            .enumerate()
            .map(|(k, &(a, phase))| a * ((k + 1) as f64 * t + phase).sin())
            .sum::<f64>()
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 64,
        rng_seed: RngSeed::Fixed(0x5b1c_e5ed),
        ..ProptestConfig::default()
    })]

    /// A spike-free smooth record is never flagged: continuous with the default floor, or
    /// rounded to 4096 counts with the floor of that quantum.
    #[test]
    fn smooth_records_are_never_flagged(
        (rate, harmonics) in smooth_angle(),
        per_period in 25.0..500.0f64,
        n in 200usize..4000,
        quantised in any::<bool>(),
    ) {
        let x: Vec<f64> = (0..n)
            .map(|i| {
                let theta = angle_at(rate, &harmonics, i as f64 * TAU / per_period);
                wrap(if quantised { (theta / COUNT).round() * COUNT } else { theta })
            })
            .collect();
        let params = if quantised { quantum() } else { SpikeParams::new() };
        let found = find_spikes(&x, Domain::Circle, &params).unwrap();
        prop_assert!(found.is_empty(), "{:?}", found.as_slice().iter().take(5).collect::<Vec<_>>());
    }

    /// Adding whole turns to the unwrapped input, or a constant rotation at any rate (which the
    /// cubic prediction follows exactly), changes neither the spikes found nor their sizes, and
    /// the replacements are the same points of the circle.
    #[test]
    fn search_is_invariant_under_whole_turns_and_constant_rotation(
        (rate, harmonics) in smooth_angle(),
        per_period in 50.0..200.0f64,
        turns in -50i32..50,
        spin in -0.5..0.5f64,
        seed in 0u64..1000,
    ) {
        let n = 3000;
        let rng_spikes = bit_errors(&positions(n, 3e-3, GAP, seed), &[6, 8, 10, 11], seed + 1);
        let theta: Vec<f64> = (0..n)
            .map(|i| angle_at(rate, &harmonics, i as f64 * TAU / per_period))
            .collect();
        let mut spiked = theta.clone();
        for s in &rng_spikes {
            spiked[s.index] += s.counts * COUNT;
        }
        let params = SpikeParams::new();
        let base = find_spikes(&spiked.iter().map(|&v| wrap(v)).collect::<Vec<_>>(), Domain::Circle, &params).unwrap();
        let shifted: Vec<f64> = spiked.iter().map(|&v| v + TAU * f64::from(turns)).collect();
        let spun: Vec<f64> = spiked.iter().enumerate().map(|(i, &v)| wrap(v + spin * i as f64)).collect();
        for (other, label) in [(&shifted, "whole turns"), (&spun, "rotation")] {
            let found = find_spikes(other, Domain::Circle, &params).unwrap();
            prop_assert_eq!(found.indices().collect::<Vec<_>>(), base.indices().collect::<Vec<_>>(), "{}", label);
            for (a, b) in found.iter().zip(&base) {
                prop_assert!(circle_distance(a.size, b.size) < 1e-9, "{}: {:?} {:?}", label, a, b);
                let moved = if label == "rotation" { spin * a.index as f64 } else { 0.0 };
                prop_assert!(circle_distance(a.replacement - moved, b.replacement) < 1e-9, "{}: {:?} {:?}", label, a, b);
            }
        }
        // And the spikes are exactly those injected.
        prop_assert_eq!(base.indices().collect::<Vec<_>>(), rng_spikes.iter().map(|s| s.index).collect::<Vec<_>>());
    }
}

/// Searched in the record itself, the spikes are those found in a copy, and the record is left as
/// it was to the bit: bit errors on an encoder's angle (noisy and noise-free, among the paper's
/// fast events, where the search weighs and rejects many candidates), and outliers and runs on a
/// line.
#[test]
fn a_record_searched_in_place_is_left_as_it_was() {
    use circle_signal::find_spikes_in_place;
    let noisy = Record::new(Motion::Whirl, 100.0, 20_000, 0.003, true, 7).wrapped();
    let spikes = bit_errors(&positions(20_000, RATE, GAP, 8), &[6, 7, 8, 9], 9);
    let mut line: Vec<f64> = (0..20_000)
        .map(|i| (i as f64 * 0.05).sin() + 0.3 * (i as f64 * 0.011).cos())
        .collect();
    for (k, at) in [(0.5, 1000), (-0.4, 5000), (0.6, 5001), (0.6, 5002), (1.0, 12_345)] {
        line[at] += k;
    }
    let cases: Vec<(&str, Vec<f64>, Domain, SpikeParams)> = vec![
        ("encoder", inject(&noisy, &spikes), Domain::Circle, quantum()),
        (
            "paper's chaotic record",
            inject(&paper_record(), &spikes[..5]),
            Domain::Circle,
            SpikeParams::new(),
        ),
        ("line", line, Domain::Line, SpikeParams::new()),
    ];
    for (what, x, domain, params) in cases {
        let copy = find_spikes(&x, domain, &params).expect("search");
        assert!(!copy.is_empty(), "{what}: something to find");
        let mut y = x.clone();
        let here = find_spikes_in_place(&mut y, domain, &params).expect("search");
        assert_eq!(here, copy, "{what}");
        assert!(
            y.iter().zip(&x).all(|(a, b)| a.to_bits() == b.to_bits()),
            "{what}: the record changed"
        );
    }
}
