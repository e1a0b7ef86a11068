//! Measures the outlier search on the line and on the circle: false alarms on clean and noisy
//! records (a vibrometer's velocity of a chaotic Duffing oscillator with white, coloured and
//! speckle noise; encoder angles at 4096 counts), detection of bit errors of `±2^k` counts and of
//! vibrometer dropouts (one to three samples) by size, the time on long records, and the
//! calibration of the local scale's factor:
//!
//! ```text
//! cargo run --release -p circle-signal --example spike_outliers
//! ```
//!
//! (`-- --quick` for a shorter run: one rate, one motion; `-- --long` for the long records and
//! their times alone). The tables are in `docs/spikes.md`.
//! Everything is seeded.
#![allow(clippy::print_stdout)]

#[path = "../tests/support/mod.rs"]
mod support;

use std::collections::BTreeSet;
use std::time::Instant;

use circle_signal::{Domain, SpikeParams, find_spikes};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use support::{
    COUNT, Motion, Record, VibrometerNoise, bit_errors, duffing, inject, positions, run, vibrometer,
};

/// Samples per record.
const SAMPLES: usize = 100_000;

/// Records per case of the false-alarm table.
const RECORDS: u64 = 4;

/// The standard deviation of a centred residual of white noise of unit standard deviation.
const RESIDUAL: f64 = 1.394_433_963_956_97;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let quick = std::env::args().any(|a| a == "--quick");
    if std::env::args().any(|a| a == "--long") {
        return long_records();
    }
    calibration(if quick { 200_000 } else { 2_000_000 });
    false_alarms_line(quick)?;
    false_alarms_circle(quick)?;
    bit_error_detection()?;
    dropout_detection()?;
    long_records()?;
    Ok(())
}

/// The tail `P(|Z| > z)` of a standard Gaussian (Numerical Recipes' `erfcc`, relative error
/// below 1.2e-7).
fn tail(z: f64) -> f64 {
    let x = z / std::f64::consts::SQRT_2;
    let t = 1.0 / (1.0 + 0.5 * x.abs());
    let poly = -x * x - 1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_98
                                + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    let r = t * poly.exp();
    if x >= 0.0 { r } else { 2.0 - r }
}

/// The local scale's statistic on white noise: the (count / 16)-th largest of the `count` nearest
/// partner-limited `|r|` outside ±2 of the position (each `|r_j|` limited to the largest of its
/// 16 partners 9 to 16 positions away), in standard deviations of the residual, for windows of
/// 96 down to 48 positions; and the factor κ that makes `P(|r| > κ q)` 10⁻⁶ for a Gaussian
/// residual independent of `q`, with a direct count at 10⁻⁴ and 10⁻⁵ (where the residuals next
/// to the window are not quite independent of it).
fn calibration(n: usize) {
    let (gap, partners) = (9usize, 8usize);
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let normal = Normal::new(0.0, 1.0).expect("unit normal");
    let x: Vec<f64> = (0..n).map(|_| normal.sample(&mut rng)).collect();
    let r: Vec<f64> = (2..n - 2)
        .map(|i| {
            ((x[i - 2] - 4.0 * x[i - 1] + 6.0 * x[i] - 4.0 * x[i + 1] + x[i + 2]) / 6.0 / RESIDUAL).abs()
        })
        .collect();
    let edge = gap + partners;
    let level: Vec<f64> = (0..r.len())
        .map(|j| {
            if j < edge || j + edge >= r.len() {
                return r[j];
            }
            let p = (gap..edge).fold(0.0f64, |m, d| m.max(r[j - d]).max(r[j + d]));
            r[j].min(p)
        })
        .collect();
    // The window of `count` positions, half on each side of c outside c ± 2, and its
    // (count / 16)-th largest level.
    let q_at = |c: usize, count: usize, buf: &mut Vec<f64>| {
        let half = count / 2;
        buf.clear();
        buf.extend_from_slice(&level[c - 2 - half..c - 2]);
        buf.extend_from_slice(&level[c + 3..c + 3 + count - half]);
        let k = buf.len() - count / 16;
        *buf.select_nth_unstable_by(k, f64::total_cmp).1
    };
    let mut buf = Vec::new();
    let margin = 48 + edge + 4;
    println!("## Calibration of the local scale\n");
    println!(
        "White noise, {} residuals; q at every 7th position; κ such that the mean of P(|r| > κ q) over q is the \
         rate (the residual taken as independent of its window), and a direct count of |r| > κ q at every position.\n",
        r.len()
    );
    println!("| window | q: the level ranked | false alarms per sample | κ | direct count |");
    println!("|---|---|---|---|---|");
    for count in [96usize, 80, 64, 48] {
        let qs: Vec<(usize, f64)> = (margin..r.len() - margin)
            .step_by(7)
            .map(|c| (c, q_at(c, count, &mut buf)))
            .collect();
        let rate = |kappa: f64| qs.iter().map(|&(_, q)| tail(kappa * q)).sum::<f64>() / qs.len() as f64;
        let solve = |target: f64| {
            let (mut lo, mut hi) = (0.5, 50.0);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if rate(mid) > target { lo = mid } else { hi = mid }
            }
            hi
        };
        let targets: &[f64] = if count == 96 {
            &[1e-4, 1e-5, 1e-6, 1e-7]
        } else {
            &[1e-6]
        };
        for &target in targets {
            let kappa = solve(target);
            let direct = if target >= 1e-5 {
                let (mut hits, mut total) = (0usize, 0usize);
                for (c, &rc) in r.iter().enumerate().take(r.len() - margin).skip(margin) {
                    if rc > kappa * q_at(c, count, &mut buf) {
                        hits += 1;
                    }
                    total += 1;
                }
                format!("{:.1e} ({hits} of {total})", hits as f64 / total as f64)
            } else {
                "–".to_owned()
            };
            let rank = ["3rd", "4th", "5th", "6th"][count / 16 - 3];
            println!("| {count} | {rank} largest | {target:.0e} | {kappa:.3} | {direct} |");
        }
        if count == 96 {
            let mut sorted: Vec<f64> = qs.iter().map(|&(_, q)| q).collect();
            sorted.sort_by(f64::total_cmp);
            let at = |p: f64| sorted[((sorted.len() - 1) as f64 * p) as usize];
            let kappa = solve(1e-6);
            println!(
                "\nWindow of 96: q in residual standard deviations 10 % {:.3}, median {:.3}, 90 % {:.3}; with κ = {kappa:.3} \
                 the local threshold κ q exceeds 6 in {:.0} % of positions; a spike of 7 (8) standard deviations passes \
                 max(6, κ q) with probability {:.3} ({:.3}), against {:.3} ({:.3}) for the threshold 6 alone.\n",
                at(0.1),
                at(0.5),
                at(0.9),
                100.0 * qs.iter().filter(|&&(_, q)| kappa * q > 6.0).count() as f64 / qs.len() as f64,
                detection(&qs, kappa, 7.0),
                detection(&qs, kappa, 8.0),
                tail_one(-1.0),
                tail_one(-2.0),
            );
            println!("| window | q: the level ranked | false alarms per sample | κ | direct count |");
            println!("|---|---|---|---|---|");
        }
    }
    println!();
}

/// `P(Z > z)` for a standard Gaussian.
fn tail_one(z: f64) -> f64 {
    if z >= 0.0 {
        0.5 * tail(z)
    } else {
        1.0 - 0.5 * tail(-z)
    }
}

/// The mean probability that a residual `size + Z` passes `max(6, κ q)`.
fn detection(qs: &[(usize, f64)], kappa: f64, size: f64) -> f64 {
    qs.iter()
        .map(|&(_, q)| tail_one((6.0f64).max(kappa * q) - size))
        .sum::<f64>()
        / qs.len() as f64
}

/// A case of the false-alarm table: its name, the noise's relative level and the record by seed.
type Case = (String, f64, Box<dyn Fn(u64) -> Vec<f64>>);

fn false_alarms_line(quick: bool) -> Result<(), Box<dyn std::error::Error>> {
    println!("## False alarms on the line\n");
    println!(
        "The velocity of the chaotic two-well Duffing oscillator `x'' + 0.25 x' − x + x³ = 0.3 cos t` as a vibrometer \
         measures it, {RECORDS} records of {SAMPLES} samples per case (seeds 0..{RECORDS}), default parameters; noise \
         relative to the velocity's root-mean-square. At 2048 Hz, 100, 256 and 1024 samples per period are drives of \
         20.5, 8 and 2 Hz.\n"
    );
    println!("| samples/period | noise | relative level | alarms | per sample | records with any |");
    println!("|---|---|---|---|---|---|");
    let params = SpikeParams::new();
    let rates: &[f64] = if quick {
        &[256.0]
    } else {
        &[25.0, 100.0, 256.0, 1024.0]
    };
    let mut total_samples = 0usize;
    for &per_period in rates {
        let mut cases: Vec<Case> = vec![(
            "none (clean)".to_owned(),
            0.0,
            Box::new(move |s| vibrometer(per_period, SAMPLES, 0.0, VibrometerNoise::White, s)),
        )];
        for relative in [1e-3, 1e-2, 1e-1] {
            cases.push((
                "white".to_owned(),
                relative,
                Box::new(move |s| vibrometer(per_period, SAMPLES, relative, VibrometerNoise::White, s)),
            ));
        }
        cases.push((
            "coloured (AR(1) 0.7)".to_owned(),
            1e-2,
            Box::new(move |s| vibrometer(per_period, SAMPLES, 1e-2, VibrometerNoise::Coloured, s)),
        ));
        for cell in [2.0, 1.0, 0.5, 0.2] {
            cases.push((
                format!("speckle, cell {cell}"),
                1e-2,
                Box::new(move |s| vibrometer(per_period, SAMPLES, 1e-2, VibrometerNoise::Speckle(cell), s)),
            ));
        }
        for (len, factor) in [(100usize, 5.0), (30, 5.0), (15, 3.0)] {
            cases.push((
                format!("bursts of {len} samples at {factor}×"),
                1e-2,
                Box::new(move |s| {
                    vibrometer(
                        per_period,
                        SAMPLES,
                        1e-2,
                        VibrometerNoise::Bursts { len, factor },
                        s,
                    )
                }),
            ));
        }
        cases.push((
            "Student t, 5 degrees of freedom".to_owned(),
            1e-2,
            Box::new(move |s| vibrometer(per_period, SAMPLES, 1e-2, VibrometerNoise::Student(5.0), s)),
        ));
        for (name, relative, make) in &cases {
            let (mut alarms, mut any, mut samples) = (0usize, 0u64, 0usize);
            for seed in 0..RECORDS {
                let x = make(seed);
                let found = find_spikes(&x, Domain::Line, &params)?.len();
                alarms += found;
                any += u64::from(found > 0);
                samples += x.len();
            }
            total_samples += samples;
            println!(
                "| {per_period} | {name} | {relative:.0e} | {alarms} | {:.1e} | {any} of {RECORDS} |",
                alarms as f64 / samples as f64
            );
        }
    }
    println!("\n{total_samples} samples on the line.\n");
    Ok(())
}

fn false_alarms_circle(quick: bool) -> Result<(), Box<dyn std::error::Error>> {
    println!("## False alarms on the circle\n");
    println!(
        "Encoder angles at 4096 counts (rounded), Gaussian noise σ before rounding, {RECORDS} records of {SAMPLES} \
         samples per case; `with_quantum` sets the floor to 2 counts, `default` searches with the defaults.\n"
    );
    println!(
        "| motion | samples/period | σ (rad) | alarms (with_quantum) | alarms (default) | records with any |"
    );
    println!("|---|---|---|---|---|---|");
    let quantum = SpikeParams::new().with_quantum(COUNT)?;
    let default = SpikeParams::new();
    let motions: &[(&str, Motion)] = if quick {
        &[("whirl", Motion::Whirl)]
    } else {
        &[
            ("whirl", Motion::Whirl),
            ("swing", Motion::Swing),
            ("burst", Motion::Burst),
        ]
    };
    let mut total = 0usize;
    for &(name, motion) in motions {
        for per_period in [25.0, 100.0, 500.0 / 1.02] {
            for sigma in [0.0, 0.003, 0.01] {
                let (mut with_q, mut with_d, mut any) = (0usize, 0usize, 0u64);
                for seed in 0..RECORDS {
                    let x = Record::new(motion, per_period, SAMPLES, sigma, true, 500 + seed).wrapped();
                    let q = find_spikes(&x, Domain::Circle, &quantum)?.len();
                    let d = find_spikes(&x, Domain::Circle, &default)?.len();
                    with_q += q;
                    with_d += d;
                    any += u64::from(q > 0);
                    total += x.len();
                }
                println!("| {name} | {per_period:.3} | {sigma} | {with_q} | {with_d} | {any} of {RECORDS} |");
            }
        }
    }
    println!("\n{total} samples on the circle.\n");
    Ok(())
}

fn bit_error_detection() -> Result<(), Box<dyn std::error::Error>> {
    println!("## Bit errors\n");
    println!(
        "Bit errors of ±2^k counts of 4096 at isolated positions (rate 1e-3, at least 5 apart) in the records of the \
         table above (whirl, swing and burst together, 2 records each), `with_quantum`; σ_r is the residual's noise, \
         1.39 σ: a spike of 64 counts is 7 σ_r at σ = 0.01 rad.\n"
    );
    println!("| samples/period | σ (rad) | k=6 | k=7 | k=8 | k=9 | flagged besides |");
    println!("|---|---|---|---|---|---|---|");
    let quantum = SpikeParams::new().with_quantum(COUNT)?;
    for per_period in [25.0, 100.0, 500.0 / 1.02] {
        for sigma in [0.0, 0.003, 0.01] {
            let mut per_k = [(0usize, 0usize); 4];
            let mut besides = 0;
            for (m, motion) in [Motion::Whirl, Motion::Swing, Motion::Burst]
                .into_iter()
                .enumerate()
            {
                for seed in 0..2u64 {
                    let seed = 7000 + 100 * m as u64 + 10 * seed;
                    let clean = Record::new(motion, per_period, SAMPLES, sigma, true, seed).wrapped();
                    let spikes = bit_errors(&positions(SAMPLES, 1e-3, 5, seed + 1), &[6, 7, 8, 9], seed + 2);
                    let out = run(&clean, &spikes, &quantum);
                    for &(k, injected, found) in &out.per_power {
                        let slot = &mut per_k[(k - 6) as usize];
                        slot.0 += injected;
                        slot.1 += found;
                    }
                    besides += out.false_alarms;
                }
            }
            let cell = |(i, f): (usize, usize)| format!("{:.1} % ({f}/{i})", 100.0 * f as f64 / i as f64);
            println!(
                "| {per_period:.3} | {sigma} | {} | {} | {} | {} | {besides} |",
                cell(per_k[0]),
                cell(per_k[1]),
                cell(per_k[2]),
                cell(per_k[3])
            );
        }
    }
    println!();
    Ok(())
}

/// Injects dropouts of `len` samples at positions about 600 apart: each sample of a run moved by
/// `size` (the same sign for the run), or, with `size` NaN, dropped to a tenth of its value.
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

fn dropout_detection() -> Result<(), Box<dyn std::error::Error>> {
    println!("## Vibrometer dropouts\n");
    println!(
        "Runs of 1 to 3 samples at positions 400 to 800 apart in the vibrometer record (256 samples per period, white \
         noise σ of 1e-2 of the velocity's root-mean-square, 4 records), each sample moved by S (the same sign within \
         a run; S in standard deviations σ_r = 1.39 σ of the residual), or dropped to a tenth of its value (binned by \
         the largest drop of the run). A run counts as found when every one of its samples is flagged; `partly` when \
         some are; `besides` counts flagged samples outside any run.\n"
    );
    println!("| run | size | runs | found | partly | besides |");
    println!("|---|---|---|---|---|---|");
    let params = SpikeParams::new();
    let relative = 1e-2;
    for len in 1..=3usize {
        for size in [6.0, 8.0, 10.0, 12.0, 16.0, 24.0, 48.0] {
            let (mut runs, mut found, mut partly, mut besides) = (0, 0, 0, 0);
            for seed in 0..4u64 {
                let x = vibrometer(256.0, SAMPLES, relative, VibrometerNoise::White, seed);
                let sigma = noise_of(&x, relative);
                let (y, at) = dropouts(&x, len, size * RESIDUAL * sigma, 900 + seed);
                let (r, f, p, b) = score(&y, &at, len, &params)?;
                runs += r;
                found += f;
                partly += p;
                besides += b;
            }
            println!(
                "| {len} | {size} σ_r | {runs} | {:.1} % | {partly} | {besides} |",
                100.0 * found as f64 / runs as f64
            );
        }
        // Drops to a tenth, binned by size.
        let mut bins = [(0usize, 0usize, 0usize); 4];
        let mut besides = 0;
        for seed in 0..4u64 {
            let x = vibrometer(256.0, SAMPLES, relative, VibrometerNoise::White, seed);
            let sigma = noise_of(&x, relative);
            let (y, at) = dropouts(&x, len, f64::NAN, 950 + seed);
            let found: BTreeSet<usize> = find_spikes(&y, Domain::Line, &params)?.indices().collect();
            let mut inside = 0;
            for &(i, moved) in &at {
                let s = moved / (RESIDUAL * sigma);
                let bin = if s < 6.0 {
                    0
                } else if s < 12.0 {
                    1
                } else if s < 24.0 {
                    2
                } else {
                    3
                };
                let hits = (i..i + len).filter(|j| found.contains(j)).count();
                inside += hits;
                bins[bin].0 += 1;
                bins[bin].1 += usize::from(hits == len);
                bins[bin].2 += usize::from(hits > 0 && hits < len);
            }
            besides += found.len() - inside;
        }
        for (bin, name) in ["< 6 σ_r", "6–12 σ_r", "12–24 σ_r", "≥ 24 σ_r"]
            .iter()
            .enumerate()
        {
            let (runs, found, partly) = bins[bin];
            let rate = if runs == 0 {
                "–".to_owned()
            } else {
                format!("{:.1} %", 100.0 * found as f64 / runs as f64)
            };
            let b = if bin == 3 {
                besides.to_string()
            } else {
                String::new()
            };
            println!("| {len} | drop to 1/10, {name} | {runs} | {rate} | {partly} | {b} |");
        }
    }
    println!();
    Ok(())
}

/// The noise's standard deviation of a [`vibrometer`] record made with `relative`.
fn noise_of(x: &[f64], relative: f64) -> f64 {
    let (_, v) = duffing(256.0, x.len());
    relative * (v.iter().map(|a| a * a).sum::<f64>() / v.len() as f64).sqrt()
}

/// Runs, runs found whole, runs found in part, samples flagged outside the runs.
fn score(
    y: &[f64],
    at: &[(usize, f64)],
    len: usize,
    params: &SpikeParams,
) -> Result<(usize, usize, usize, usize), circle_signal::CircleError> {
    let found: BTreeSet<usize> = find_spikes(y, Domain::Line, params)?.indices().collect();
    let (mut whole, mut part, mut inside) = (0, 0, 0);
    for &(i, _) in at {
        let hits = (i..i + len).filter(|j| found.contains(j)).count();
        inside += hits;
        whole += usize::from(hits == len);
        part += usize::from(hits > 0 && hits < len);
    }
    Ok((at.len(), whole, part, found.len() - inside))
}

/// The paper's pendulum `x'' + 0.03 x' + (1/0.8333²) sin x − 1.52 sin(t) cos x = 0`, chaotic,
/// noise-free and wrapped: `n` samples at 25 per forcing period after 200 periods from `x = 0.1`,
/// classical Runge–Kutta with 8 steps per sample.
fn paper_long(n: usize) -> Vec<f64> {
    let per_period = 25.0;
    let h = std::f64::consts::TAU / per_period / 8.0;
    let k = 1.0 / (0.8333 * 0.8333);
    let f = |t: f64, x: f64, v: f64| (v, -0.03 * v - k * x.sin() + 1.52 * t.sin() * x.cos());
    let (mut x, mut v, mut t) = (0.1, 0.0, 0.0);
    let skip = 200 * 25;
    let mut xs = Vec::with_capacity(n);
    for i in 0..skip + n {
        if i >= skip {
            xs.push(circle_signal::wrap(x));
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
    xs
}

/// The alarms of one search of `x` and the shortest time of three (the machine is shared: the
/// shortest is the one least slowed by others).
fn timed(
    x: &[f64],
    domain: Domain,
    params: &SpikeParams,
) -> Result<(usize, f64), Box<dyn std::error::Error>> {
    let mut best = f64::INFINITY;
    let mut found = 0;
    for _ in 0..3 {
        let t = Instant::now();
        found = find_spikes(x, domain, params)?.len();
        best = best.min(t.elapsed().as_secs_f64());
    }
    Ok((found, best))
}

fn long_records() -> Result<(), Box<dyn std::error::Error>> {
    println!("## Long records and time\n");
    println!("| record | samples | alarms | time (s, shortest of 3) |");
    println!("|---|---|---|---|");
    let params = SpikeParams::new();
    for (name, noise) in [
        ("vibrometer, white 1e-2", VibrometerNoise::White),
        ("vibrometer, speckle cell 1", VibrometerNoise::Speckle(1.0)),
    ] {
        let x = vibrometer(256.0, 2_000_000, 1e-2, noise, 5);
        let (found, time) = timed(&x, Domain::Line, &params)?;
        println!("| {name} | {} | {found} | {time:.3} |", x.len());
    }
    let quantum = SpikeParams::new().with_quantum(COUNT)?;
    let clean = Record::new(Motion::Whirl, 100.0, 2_000_000, 0.003, true, 6).wrapped();
    let (found, time) = timed(&clean, Domain::Circle, &quantum)?;
    println!(
        "| encoder, whirl, σ = 0.003 | {} | {found} | {time:.3} |",
        clean.len()
    );
    let spikes = bit_errors(&positions(clean.len(), 1e-3, 5, 7), &[6, 7, 8, 9], 8);
    let x = inject(&clean, &spikes);
    let (found, time) = timed(&x, Domain::Circle, &quantum)?;
    println!(
        "| the same with {} bit errors | {} | {found} | {time:.3} |",
        spikes.len(),
        x.len()
    );
    // The paper's chaotic record, noise-free at 25 samples per period: where its smooth motion's
    // residual stands out of its block (a fifth of the samples) the local scales are needed.
    let paper = paper_long(1_000_000);
    let (found, time) = timed(&paper, Domain::Circle, &params)?;
    println!(
        "| the paper's pendulum, noise-free, 25 per period | {} | {found} | {time:.3} |",
        paper.len()
    );
    println!();
    Ok(())
}
