//! Close-return search and catalogue on the paper's data set (30000 samples, the SciPy fixture)
//! and on 10^6 simulated samples (P = 25, Td = 5, d = 2, e = 3 %, periods 1..=16).
use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use upo_search::CloseReturns;

fn bench(c: &mut Criterion) {
    let search = CloseReturns::new(&upo_search::SampleClock::nondimensional(25).expect("clock"), 5)
        .expect("parameters");
    let (_, paper) = hbid_benches::paper_fixture();
    let million = hbid_benches::record(1_000_000).expect("simulation");

    let mut group = c.benchmark_group("upo_search");
    group.bench_function("search/paper_30k", |b| {
        b.iter(|| search.search(black_box(&paper)).expect("search"))
    });
    group.bench_function("catalogue/paper_30k", |b| {
        b.iter(|| search.catalogue(black_box(&paper)).expect("catalogue"))
    });
    group.sample_size(10);
    group.bench_function("search/sim_1e6", |b| {
        b.iter(|| search.search(black_box(&million)).expect("search"))
    });
    group.bench_function("catalogue/sim_1e6", |b| {
        b.iter(|| search.catalogue(black_box(&million)).expect("catalogue"))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
