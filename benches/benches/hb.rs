//! Fourier coefficients, assembly and least squares on the paper's data set (e = 3 %, periods 1..16).
use std::hint::black_box;

use circle_signal::SampleClock;
use criterion::{Criterion, criterion_group, criterion_main};
use hb_basis::{FourierPlanner, Harmonic, Hat};
use hb_model::Harmonics;
use hb_solve::{IdentifyParams, LstsqSolver, QrSolver, SvdSolver, assemble, identify};
use upo_search::{CloseReturns, OrbitSource, Segment};

fn paper() -> (f64, Vec<f64>, Vec<Segment>) {
    let (t, x) = hbid_benches::paper_fixture();
    let search = CloseReturns::builder(&upo_search::SampleClock::nondimensional(25).expect("clock"), 5)
        .tolerance(0.03)
        .max_period(16)
        .build()
        .expect("search");
    let segments = search.segments(&x).expect("segments");
    (t[0], x, segments)
}

fn bench(c: &mut Criterion) {
    let (t0, x, segments) = paper();
    let clock = SampleClock::nondimensional(25)
        .expect("clock")
        .with_start_time(t0)
        .expect("t0");
    let params = IdentifyParams::builder(clock).build().expect("params");
    let harmonic = Harmonic::new(1).expect("basis");
    let hat = Hat::new(8).expect("basis");

    c.bench_function("fourier coefficients of every segment (planned)", |b| {
        let mut planner = FourierPlanner::new();
        let mut a = vec![0.0; 13];
        let mut bb = vec![0.0; 13];
        b.iter(|| {
            for s in &segments {
                let plan = planner.plan(s.len()).expect("plan");
                plan.coefficients(&x[s.start()..s.start() + s.len()], &mut a, &mut bb)
                    .expect("coefficients");
                black_box(&a);
            }
        })
    });
    c.bench_function("assemble harmonic K=1", |b| {
        b.iter(|| black_box(assemble(&harmonic, &x, &segments, &params).expect("assemble")))
    });
    c.bench_function("assemble hat N=8", |b| {
        b.iter(|| black_box(assemble(&hat, &x, &segments, &params).expect("assemble")))
    });
    for (name, basis_system) in [
        (
            "K=1",
            assemble(&harmonic, &x, &segments, &params).expect("assemble"),
        ),
        ("hat8", assemble(&hat, &x, &segments, &params).expect("assemble")),
    ] {
        let qr = QrSolver::default();
        let svd = SvdSolver::default();
        c.bench_function(&format!("solve qr {name}"), |b| {
            b.iter(|| {
                black_box(
                    qr.solve(basis_system.matrix(), basis_system.rhs())
                        .expect("solve"),
                )
            })
        });
        c.bench_function(&format!("solve svd {name}"), |b| {
            b.iter(|| {
                black_box(
                    svd.solve(basis_system.matrix(), basis_system.rhs())
                        .expect("solve"),
                )
            })
        });
    }
    // The paper's identification as the NumPy script does it: close returns, rows, least squares.
    c.bench_function("identify paper path K=1 (close returns + assemble + qr)", |b| {
        let search = CloseReturns::builder(&upo_search::SampleClock::nondimensional(25).expect("clock"), 5)
            .tolerance(0.03)
            .max_period(16)
            .build()
            .expect("search");
        b.iter(|| {
            let segments = search.segments(&x).expect("segments");
            black_box(
                identify(
                    harmonic,
                    &x,
                    &segments,
                    &params,
                    &hb_solve::HarmonicBalance,
                    &QrSolver::default(),
                )
                .expect("identify"),
            )
        })
    });
    // The same work as the NumPy script: M = 12 harmonics of every orbit (11225 equations).
    c.bench_function(
        "identify paper path K=1, M=12 (the NumPy script's equations)",
        |b| {
            let search =
                CloseReturns::builder(&upo_search::SampleClock::nondimensional(25).expect("clock"), 5)
                    .tolerance(0.03)
                    .max_period(16)
                    .build()
                    .expect("search");
            let params = IdentifyParams::builder(clock)
                .harmonics(Harmonics::Fixed(12))
                .build()
                .expect("params");
            b.iter(|| {
                let segments = search.segments(&x).expect("segments");
                black_box(
                    identify(
                        harmonic,
                        &x,
                        &segments,
                        &params,
                        &hb_solve::HarmonicBalance,
                        &QrSolver::default(),
                    )
                    .expect("identify"),
                )
            })
        },
    );
    c.bench_function("identify hat N=8 (assemble + qr)", |b| {
        b.iter(|| {
            black_box(
                identify(
                    hat,
                    &x,
                    &segments,
                    &params,
                    &hb_solve::HarmonicBalance,
                    &QrSolver::default(),
                )
                .expect("identify"),
            )
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
