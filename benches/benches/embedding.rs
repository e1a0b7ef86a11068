//! Delay and dimension on the paper's data set (30000 samples) and on 10^6 simulated samples:
//! average mutual information for lags 0..=40, false nearest neighbours for d = 1..=6.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use embedding::{AmiParams, Domain, FnnParams, average_mutual_information, false_nearest_neighbours};

fn run(c: &mut Criterion, name: &str, x: &[f64]) {
    let ami = AmiParams::new(Domain::Circle)
        .with_max_lag(40)
        .expect("valid lag");
    let fnn_linear = FnnParams::new(Domain::Line, 5)
        .and_then(|p| p.with_max_dim(6))
        .expect("valid params");
    let fnn_circle = FnnParams::new(Domain::Circle, 5)
        .and_then(|p| p.with_max_dim(6))
        .expect("valid params");
    let mut group = c.benchmark_group(name);
    group.sample_size(10).measurement_time(Duration::from_secs(10));
    group.bench_function("ami_lags_0_to_40", |b| {
        b.iter(|| average_mutual_information(black_box(x), black_box(&ami)).expect("ami"))
    });
    group.bench_function("fnn_linear_d1_to_6", |b| {
        b.iter(|| false_nearest_neighbours(black_box(x), black_box(&fnn_linear)).expect("fnn"))
    });
    group.bench_function("fnn_circle_d1_to_6", |b| {
        b.iter(|| false_nearest_neighbours(black_box(x), black_box(&fnn_circle)).expect("fnn"))
    });
    group.finish();
}

fn paper(c: &mut Criterion) {
    run(c, "embedding/paper_30000", &hbid_benches::paper_fixture().1);
}

fn million(c: &mut Criterion) {
    run(
        c,
        "embedding/simulated_1e6",
        &hbid_benches::record(1_000_000).expect("simulation"),
    );
}

criterion_group!(benches, paper, million);
criterion_main!(benches);
