//! The weak form on the paper's data set: windows, assembly, identification, bootstrap, noise estimate.
use std::hint::black_box;

use circle_signal::SampleClock;
use criterion::{Criterion, criterion_group, criterion_main};
use hb_basis::{Domain, Harmonic, Hat};
use hb_model::Harmonics;
use hb_solve::{
    BootstrapParams, IdentifyParams, QrSolver, WeakForm, assemble_weak, bootstrap, estimate_noise_sigma,
    identify,
};
use upo_search::{OrbitSource, Windows};

fn bench(c: &mut Criterion) {
    let (t, x) = hbid_benches::paper_fixture();
    let clock = SampleClock::nondimensional(25)
        .expect("clock")
        .with_start_time(t[0])
        .expect("t0");
    let windows =
        Windows::new(&upo_search::SampleClock::nondimensional(25).expect("clock")).expect("windows");
    let segments = windows.segments(&x).expect("segments");
    let params = IdentifyParams::builder(clock)
        .harmonics(WeakForm::DEFAULT_HARMONICS)
        .build()
        .expect("params");
    let params16 = IdentifyParams::builder(clock)
        .harmonics(Harmonics::Fixed(16))
        .build()
        .expect("params");
    let weak = WeakForm::default();
    let harmonic = Harmonic::new(1).expect("basis");
    let hat = Hat::new(8).expect("basis");
    let qr = QrSolver::default();

    c.bench_function("windows (defaults: 3 periods, step 1)", |b| {
        b.iter(|| black_box(windows.segments(&x).expect("segments")))
    });
    c.bench_function("assemble weak K=1 (j <= 2k)", |b| {
        b.iter(|| black_box(assemble_weak(&harmonic, &x, &segments, &params, &weak).expect("assemble")))
    });
    let windows2 = Windows::builder(&upo_search::SampleClock::nondimensional(25).expect("clock"))
        .periods(2)
        .build()
        .expect("windows");
    c.bench_function(
        "identify weak K=1, 2 periods, j <= 16 (windows + assemble + qr, the Python reference's setting)",
        |b| {
            b.iter(|| {
                let segments = windows2.segments(&x).expect("segments");
                black_box(identify(harmonic, &x, &segments, &params16, &weak, &qr).expect("identify"))
            })
        },
    );
    c.bench_function("assemble weak hat N=8 (j <= 2k)", |b| {
        b.iter(|| black_box(assemble_weak(&hat, &x, &segments, &params, &weak).expect("assemble")))
    });
    c.bench_function("identify weak K=1 (windows + assemble + qr)", |b| {
        b.iter(|| {
            let segments = windows.segments(&x).expect("segments");
            black_box(identify(harmonic, &x, &segments, &params, &weak, &qr).expect("identify"))
        })
    });
    let system = assemble_weak(&harmonic, &x, &segments, &params, &weak).expect("assemble");
    let mut group = c.benchmark_group("bootstrap");
    group.sample_size(10);
    group.bench_function("weak K=1, 1000 resamples", |b| {
        b.iter(|| black_box(bootstrap(&system, &qr, &BootstrapParams::default()).expect("bootstrap")))
    });
    group.finish();
    c.bench_function("noise sigma estimate (30000 samples)", |b| {
        b.iter(|| black_box(estimate_noise_sigma(&x, Domain::Circle).expect("sigma")))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
