//! The spike search on a whirling angle through a 4096-count encoder, 100 samples per forcing
//! period, with a bit error every 997 samples: 10^6 and 10^7 samples, searched into a copy
//! (`find_spikes`) and in place (`find_and_repair_spikes`).
use std::f64::consts::TAU;
use std::hint::black_box;
use std::time::Duration;

use circle_signal::{Domain, SpikeParams, find_and_repair_spikes, find_spikes, wrap};
use criterion::{BatchSize, Criterion, criterion_group, criterion_main};

const COUNT: f64 = TAU / 4096.0;

fn record(n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| {
            let t = i as f64 * TAU / 100.0;
            let theta = t + 0.8 * (t + 0.3).sin() + 0.1 * (3.0 * t).sin();
            let spike = if i % 997 == 500 {
                f64::from(64 << (i % 4))
            } else {
                0.0
            };
            wrap(((theta / COUNT).round() + spike) * COUNT)
        })
        .collect()
}

fn bench_spikes(c: &mut Criterion) {
    let params = SpikeParams::new().with_quantum(COUNT).expect("valid quantum");
    let mut group = c.benchmark_group("spikes");
    group.sample_size(10).measurement_time(Duration::from_secs(10));
    for n in [1_000_000, 10_000_000] {
        let x = record(n);
        group.bench_function(format!("find_{n}"), |b| {
            b.iter(|| find_spikes(black_box(&x), Domain::Circle, &params).expect("search"))
        });
        group.bench_function(format!("find_and_repair_{n}"), |b| {
            b.iter_batched_ref(
                || x.clone(),
                |y| find_and_repair_spikes(y, Domain::Circle, &params).expect("search"),
                BatchSize::LargeInput,
            )
        });
    }
    group.finish();
}

criterion_group!(benches, bench_spikes);
criterion_main!(benches);
