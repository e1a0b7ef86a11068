//! Measures the spike search on encoder-like records: detection of bit errors of `±2^k` counts
//! (k = 6..9, and half a turn) per sampling rate and noise level, false detections on the clean
//! records, the repair error and the winding, and the time on 10^7 samples:
//!
//! ```text
//! cargo run --release -p circle-signal --example spike_rates
//! ```
#![allow(clippy::print_stdout)]

#[path = "../tests/support/mod.rs"]
mod support;

use std::time::Instant;

use circle_signal::{Domain, SpikeParams, find_and_repair_spikes, find_spikes};
use support::{COUNT, Motion, Record, bit_errors, paper_quantised, positions, run};

const SAMPLES: usize = 100_000;
const SIGMAS: [f64; 3] = [0.0, 0.003, 0.01];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let block: usize = std::env::args()
        .nth(1)
        .map_or(Ok(SpikeParams::DEFAULT_BLOCK), |a| a.parse())?;
    let quantum = SpikeParams::new().with_quantum(COUNT)?.with_block(block)?;
    let default = SpikeParams::new();
    println!("Bit errors of ±2^k counts of 4096 at isolated positions (rate 1e-3), quantised records,");
    println!(
        "floor 2 counts (`with_quantum`); `clean (default floor)` searches the clean record with the defaults.\n"
    );
    println!(
        "| record | samples/period | σ (rad) | scale (counts) | k=6 | k=7 | k=8 | k=9 | false | clean | clean (default floor) | repair rms (counts) | winding ok |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    let mut cases: Vec<(String, f64, f64, Vec<f64>)> = Vec::new();
    for (name, motion) in [
        ("whirl", Motion::Whirl),
        ("swing", Motion::Swing),
        ("burst", Motion::Burst),
    ] {
        for per_period in [25.0, 100.0, 500.0 / 1.02] {
            for (s, &sigma) in SIGMAS.iter().enumerate() {
                let rec = Record::new(motion, per_period, SAMPLES, sigma, true, 11 + s as u64);
                cases.push((name.to_owned(), per_period, sigma, rec.wrapped()));
            }
        }
    }
    for (s, &sigma) in SIGMAS.iter().enumerate() {
        cases.push((
            "paper".to_owned(),
            25.0,
            sigma,
            paper_quantised(sigma, 21 + s as u64),
        ));
    }
    for (c, (name, per_period, sigma, clean)) in cases.iter().enumerate() {
        let at = positions(clean.len(), 1e-3, 5, 100 + c as u64);
        let spikes = bit_errors(&at, &[6, 7, 8, 9], 200 + c as u64);
        let out = run(clean, &spikes, &quantum);
        let scale = find_spikes(clean, Domain::Circle, &quantum)?.scale() / COUNT;
        let default_flags = find_spikes(clean, Domain::Circle, &default)?.len();
        let cell = |k: u32| {
            out.per_power
                .iter()
                .find(|p| p.0 == k)
                .map_or("-".to_owned(), |p| format!("{}/{}", p.2, p.1))
        };
        println!(
            "| {name} | {per_period:.3} | {sigma} | {scale:.2} | {} | {} | {} | {} | {} | {}/{} | {default_flags} | {:.2} | {} |",
            cell(6),
            cell(7),
            cell(8),
            cell(9),
            out.false_alarms,
            out.clean_flags,
            out.samples,
            out.repair_rms / COUNT,
            out.winding.0 == out.winding.2 && out.unwrap_gap < 1.0,
        );
    }

    println!("\nHalf a turn: ±2048 and ±2047 counts, same positions.\n");
    println!(
        "| record | samples/period | σ (rad) | found | false | repair max (counts) | winding clean / spiked / repaired | unwrap gap spiked / repaired (rad) |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for (c, (name, per_period, sigma, clean)) in cases.iter().enumerate() {
        let at = positions(clean.len(), 1e-3, 5, 100 + c as u64);
        let spikes: Vec<support::Injected> = at
            .iter()
            .enumerate()
            .map(|(j, &index)| support::Injected {
                index,
                counts: [2048.0, -2048.0, 2047.0, -2047.0][j % 4],
            })
            .collect();
        let out = run(clean, &spikes, &quantum);
        let (inj, found) = out.totals();
        println!(
            "| {name} | {per_period:.3} | {sigma} | {found}/{inj} | {} | {:.2} | {} / {} / {} | {:.2} / {:.3} |",
            out.false_alarms,
            out.repair_max / COUNT,
            out.winding.0,
            out.winding.1,
            out.winding.2,
            out.unwrap_gap_spiked,
            out.unwrap_gap,
        );
    }

    println!("\nSpikes of 64 counts at σ = 0.01 rad, 5 records of each motion per rate (k = 7 alongside):\n");
    println!("| samples/period | 64 counts found | rate | 128 counts found | false |");
    println!("|---|---|---|---|---|");
    for per_period in [25.0, 100.0, 500.0 / 1.02] {
        let (mut small, mut small_found, mut next, mut next_found, mut false_alarms) = (0, 0, 0, 0, 0);
        for (m, motion) in [Motion::Whirl, Motion::Swing, Motion::Burst]
            .into_iter()
            .enumerate()
        {
            for seed in 0..5u64 {
                let seed = 9000 + 100 * m as u64 + 10 * seed;
                let clean = Record::new(motion, per_period, SAMPLES, 0.01, true, seed).wrapped();
                let at = positions(clean.len(), 1e-3, 5, seed + 1);
                let out = run(&clean, &bit_errors(&at, &[6, 7], seed + 2), &quantum);
                for &(k, injected, found) in &out.per_power {
                    if k == 6 {
                        small += injected;
                        small_found += found;
                    } else {
                        next += injected;
                        next_found += found;
                    }
                }
                false_alarms += out.false_alarms + out.clean_flags;
            }
        }
        println!(
            "| {per_period:.3} | {small_found}/{small} | {:.0} % | {next_found}/{next} | {false_alarms} |",
            100.0 * small_found as f64 / small as f64
        );
    }

    for n in [1_000_000, 10_000_000] {
        let rec = Record::new(Motion::Whirl, 100.0, n, 0.003, true, 5);
        let mut x = rec.wrapped();
        let at = positions(n, 1e-3, 5, 6);
        let spikes = bit_errors(&at, &[6, 7, 8, 9], 7);
        x = support::inject(&x, &spikes);
        let t = Instant::now();
        let found = find_spikes(&x, Domain::Circle, &quantum)?;
        let copy = t.elapsed();
        let t = Instant::now();
        let in_place = find_and_repair_spikes(&mut x, Domain::Circle, &quantum)?;
        let place = t.elapsed();
        println!(
            "\n{n} samples: find_spikes {:.3} s, find_and_repair_spikes {:.3} s; {} of {} found",
            copy.as_secs_f64(),
            place.as_secs_f64(),
            found.len().min(in_place.len()),
            spikes.len()
        );
    }
    Ok(())
}
