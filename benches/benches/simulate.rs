//! Simulation of the paper's data set: 30000 samples at 25 per period after 200 transient
//! periods, rtol 1e-10 (SciPy's DOP853 takes about 19 s for the same job).
use criterion::{Criterion, criterion_group, criterion_main};
use pendulum_sim::{LyapunovConfig, Pendulum, SimulationConfig, largest_lyapunov, simulate};
use std::hint::black_box;

fn bench_simulate(c: &mut Criterion) {
    let pendulum = Pendulum::paper();
    let paper = SimulationConfig::paper();
    let mut group = c.benchmark_group("simulate");
    group.sample_size(20);
    group.bench_function("paper_dataset_30000", |b| {
        b.iter(|| simulate(black_box(&pendulum), &paper).unwrap())
    });
    let lyap = LyapunovConfig::default().with_periods(1000).unwrap();
    group.bench_function("lyapunov_1000_periods", |b| {
        b.iter(|| largest_lyapunov(black_box(&pendulum), &lyap, |_, _| {}).unwrap())
    });
    group.finish();
}

criterion_group!(benches, bench_simulate);
criterion_main!(benches);
