//! What an encoder reports: seeded noise, counts per turn, the zero offset, the angle's range and
//! bit errors as documented, and where a record's gaps fall.
use std::f64::consts::TAU;

use pendulum_sim::observe::{AngleRange, Encoder, Gaps, NormalDraw};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

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

/// A slowly turning angle over many turns, both signs.
fn whirl(n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| -40.0 + 0.0137 * i as f64 + 0.3 * (0.01 * i as f64).sin())
        .collect()
}

#[test]
fn encoder_settings_are_checked() {
    let e = Encoder::seeded(1);
    assert!(e.with_counts(0).is_err() && e.with_counts(1).is_err());
    assert_eq!(e.with_counts(2).unwrap().counts(), Some(2));
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        assert!(e.with_zero_offset(bad).is_err());
    }
    let counted = e.with_counts(4096).unwrap();
    for bad in [-0.1, 1.5, f64::NAN, f64::INFINITY] {
        assert!(counted.with_bit_errors(bad).is_err(), "{bad}");
    }
    // Bit errors are errors of the count: none without counts, nor with too few.
    assert!(e.with_bit_errors(0.01).is_err());
    assert!(e.with_counts(1000).unwrap().with_bit_errors(0.01).is_err());
    let flipping = counted.with_bit_errors(0.01).unwrap();
    assert!(flipping.with_counts(512).is_err());
    assert_eq!(flipping.with_counts(1024).unwrap().counts(), Some(1024));
    // A zero rate needs nothing.
    assert_eq!(e.with_bit_errors(0.0).unwrap().bit_error_rate(), 0.0);
}

/// The reported angle is on the count grid, at most half a count from the true angle.
#[test]
fn quantisation_error_is_at_most_half_a_count() {
    let theta = whirl(20_000);
    for n in [2u32, 360, 4096, 10_000] {
        let e = Encoder::seeded(0).with_counts(n).unwrap();
        let q = TAU / f64::from(n);
        let continuous = e.observe_continuous(&theta);
        let mut worst: f64 = 0.0;
        for (c, t) in continuous.iter().zip(&theta) {
            worst = worst.max((c - t).abs());
            let k = c / q;
            assert!((k - k.round()).abs() < 1e-6, "{n}: {c} is not on the grid");
        }
        assert!(
            worst <= 0.5 * q * (1.0 + 1e-9),
            "{n}: {worst} > half a count {}",
            0.5 * q
        );
        // Finer than half a count is not what a coarse encoder gives: the error uses the count.
        assert!(worst > 0.4 * q, "{n}: {worst}");
        let wrapped = e.observe(&theta);
        let counts = e.observe_counts(&theta).unwrap();
        for ((w, k), c) in wrapped.iter().zip(&counts).zip(&continuous) {
            assert!(*k < n);
            assert!((-std::f64::consts::PI..std::f64::consts::PI).contains(w));
            assert!(circle_signal::circle_distance(*w, *c) < 1e-9);
            assert!(circle_signal::circle_distance(*w, q * f64::from(*k)) < 1e-12);
        }
    }
    assert_eq!(Encoder::seeded(0).observe_counts(&theta), None);
}

#[test]
fn zero_offset_is_subtracted_before_quantising() {
    let theta = whirl(5_000);
    let o = 0.377;
    let plain = Encoder::seeded(0).with_zero_offset(o).unwrap();
    let want: Vec<f64> = theta.iter().map(|t| circle_signal::wrap(t - o)).collect();
    assert_eq!(plain.observe(&theta), want);
    let n = 4096;
    let counted = plain.with_counts(n).unwrap();
    let per_radian = f64::from(n) / TAU;
    let want: Vec<u32> = theta
        .iter()
        .map(|t| (((t - o) * per_radian).round() as i64).rem_euclid(i64::from(n)) as u32)
        .collect();
    assert_eq!(counted.observe_counts(&theta).unwrap(), want);
    // The encoder reads 0 where the angle equals the offset.
    assert_eq!(counted.observe_counts(&[o, o + TAU]).unwrap(), [0, 0]);
}

#[test]
fn ranges_hold_the_same_angle() {
    let theta = whirl(5_000);
    for e in [
        Encoder::seeded(3).with_noise(0.02).unwrap(),
        Encoder::seeded(3).with_counts(4096).unwrap(),
    ] {
        let signed = e.observe(&theta);
        let positive = e.with_range(AngleRange::Positive).observe(&theta);
        for (s, p) in signed.iter().zip(&positive) {
            assert!((-std::f64::consts::PI..std::f64::consts::PI).contains(s));
            assert!((0.0..TAU).contains(p));
            let d = p - s;
            assert!(d.abs() < 1e-12 || (d - TAU).abs() < 1e-12, "{s} {p}");
        }
    }
    assert_eq!(AngleRange::Positive.wrap(-1e-18), 0.0);
    assert_eq!(AngleRange::Positive.wrap(-TAU), 0.0);
}

/// Samples hit by a bit error, and the spike in counts of each.
fn spikes(clean: &[u32], hit: &[u32], n: u32) -> Vec<(usize, i64)> {
    let n = i64::from(n);
    clean
        .iter()
        .zip(hit)
        .enumerate()
        .filter(|(_, (a, b))| a != b)
        .map(|(i, (&a, &b))| {
            let d = (i64::from(b) - i64::from(a)).rem_euclid(n);
            (i, if 2 * d > n { d - n } else { d })
        })
        .collect()
}

#[test]
fn bit_errors_have_the_rate_and_the_sizes_documented() {
    let theta = whirl(100_000);
    let n = 4096;
    let rate = 0.01;
    let clean = Encoder::seeded(21)
        .with_noise(0.01)
        .unwrap()
        .with_counts(n)
        .unwrap();
    let flipping = clean.with_bit_errors(rate).unwrap();
    let hits = spikes(
        &clean.observe_counts(&theta).unwrap(),
        &flipping.observe_counts(&theta).unwrap(),
        n,
    );
    // Binomial(100000, 0.01): mean 1000, standard deviation 31.5; 5 standard deviations.
    let samples = theta.len() as f64;
    let (mean, sd) = (samples * rate, (samples * rate * (1.0 - rate)).sqrt());
    assert!(
        (hits.len() as f64 - mean).abs() < 5.0 * sd,
        "{} hits, expected {mean} ± {sd}",
        hits.len()
    );
    let sizes: Vec<i64> = Encoder::BIT_ERROR_BITS.iter().map(|b| 1i64 << b).collect();
    for &(i, d) in &hits {
        assert!(sizes.contains(&d.abs()), "sample {i}: spike of {d} counts");
    }
    // Each size and each sign about equally often (a quarter and a half of the hits).
    for size in &sizes {
        let k = hits.iter().filter(|(_, d)| d.abs() == *size).count() as f64;
        let p = 0.25;
        let sd = (hits.len() as f64 * p * (1.0 - p)).sqrt();
        assert!((k - p * hits.len() as f64).abs() < 5.0 * sd, "size {size}: {k}");
    }
    let up = hits.iter().filter(|(_, d)| *d > 0).count() as f64;
    let sd = (hits.len() as f64 * 0.25).sqrt();
    assert!((up - 0.5 * hits.len() as f64).abs() < 5.0 * sd, "{up} up");
    // The same seed gives the same errors; another seed or stream others; a shorter record
    // the first ones.
    assert_eq!(flipping.observe(&theta), flipping.observe(&theta));
    let other = Encoder::seeded(22)
        .with_noise(0.01)
        .unwrap()
        .with_counts(n)
        .unwrap();
    let other_hits = spikes(
        &other.observe_counts(&theta).unwrap(),
        &other
            .with_bit_errors(rate)
            .unwrap()
            .observe_counts(&theta)
            .unwrap(),
        n,
    );
    assert_ne!(hits, other_hits);
    let streamed = clean.with_stream(4);
    let stream_hits = spikes(
        &streamed.observe_counts(&theta).unwrap(),
        &streamed
            .with_bit_errors(rate)
            .unwrap()
            .observe_counts(&theta)
            .unwrap(),
        n,
    );
    assert_ne!(hits, stream_hits);
    let short = spikes(
        &clean.observe_counts(&theta[..30_000]).unwrap(),
        &flipping.observe_counts(&theta[..30_000]).unwrap(),
        n,
    );
    let first: Vec<(usize, i64)> = hits.iter().copied().filter(|(i, _)| *i < 30_000).collect();
    assert_eq!(short, first);
}

/// Counts, offsets and bit errors leave the noise as it was: the existing records stay.
#[test]
fn encoder_effects_keep_the_noise() {
    let theta = whirl(3_000);
    let noisy = Encoder::seeded(9).with_noise(0.03).unwrap();
    let reference = noisy.observe_continuous(&theta);
    let shifted = noisy.with_zero_offset(0.2).unwrap().observe_continuous(&theta);
    for (a, b) in reference.iter().zip(&shifted) {
        assert!((a - 0.2 - b).abs() < 1e-12);
    }
    let n = 1 << 16;
    let fine = noisy.with_counts(n).unwrap().with_bit_errors(0.0).unwrap();
    let q = TAU / f64::from(n);
    for (a, b) in reference.iter().zip(fine.observe_continuous(&theta)) {
        assert!((a - b).abs() <= 0.5 * q * (1.0 + 1e-9));
    }
}

#[test]
fn gaps_are_where_documented() {
    assert!(Gaps::new(0, 5).is_err() && Gaps::new(2, 0).is_err());
    let g = Gaps::new(4, 25).unwrap().seeded(3);
    assert_eq!(g.min_samples(), Some(105));
    assert!(g.kept(104).is_err());
    assert_eq!(Gaps::new(usize::MAX, 2).unwrap().min_samples(), None);
    assert!(Gaps::new(usize::MAX, 2).unwrap().kept(10).is_err());
    for samples in [105, 106, 1_000, 50_000] {
        let kept = g.kept(samples).unwrap();
        assert_eq!(kept.len(), samples);
        assert_eq!(kept.iter().filter(|&&k| !k).count(), 100);
        assert!(kept[0] && kept[samples - 1]);
        // Four separate runs of exactly 25 dropped samples.
        let starts = g.starts(samples).unwrap();
        assert_eq!(starts.len(), 4);
        for w in starts.windows(2) {
            assert!(w[1] > w[0] + 25, "{starts:?}");
        }
        for &s in &starts {
            assert!(kept[s - 1] && kept[s + 25] && kept[s..s + 25].iter().all(|k| !k));
        }
        assert_eq!(g.kept(samples).unwrap(), kept);
    }
    // At the fewest samples there is one placement only.
    let tight = Gaps::new(3, 2).unwrap().seeded(77).kept(10).unwrap();
    let t = true;
    let f = false;
    assert_eq!(tight, [t, f, f, t, f, f, t, f, f, t]);
    assert_ne!(g.starts(50_000).unwrap(), g.seeded(4).starts(50_000).unwrap());
    // One gap: its start is uniform over 1 ..= 989 (mean 495, sd 285.5) across seeds.
    let one = Gaps::new(1, 10).unwrap();
    let seeds = 400;
    let mean = (0..seeds)
        .map(|s| one.seeded(s).starts(1_000).unwrap()[0] as f64)
        .sum::<f64>()
        / seeds as f64;
    let sd = 285.5 / (seeds as f64).sqrt();
    assert!((mean - 495.0).abs() < 5.0 * sd, "mean start {mean}");
}
