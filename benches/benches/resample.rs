//! Band-limited resampling onto a whole number of samples per forcing period: a whirling angle
//! (wrapped, on the circle) and a displacement (on the line) at 100.3 samples per period,
//! 10^5 and 10^6 samples, resampled to 100; and both as the two columns of one record, resampled
//! together (`resample_columns`, the kernel's weights once per output) against one after the other.
use std::f64::consts::TAU;
use std::hint::black_box;
use std::time::Duration;

use circle_signal::{Domain, SampleClock, resample_columns, resample_pieces, resample_to_whole, wrap};
use criterion::{Criterion, criterion_group, criterion_main};

fn bench_resample(c: &mut Criterion) {
    let clock = SampleClock::from_step(TAU, TAU / 100.3).expect("valid clock");
    let mut group = c.benchmark_group("resample");
    group.sample_size(10).measurement_time(Duration::from_secs(10));
    for n in [100_000, 1_000_000] {
        let angle: Vec<f64> = (0..n)
            .map(|i| {
                let t = clock.time(i);
                wrap(t + 0.8 * (t + 0.3).sin() + 0.1 * (3.0 * t).sin())
            })
            .collect();
        let line: Vec<f64> = (0..n).map(|i| (clock.time(i) + 0.3).sin()).collect();
        group.bench_function(format!("circle_{n}"), |b| {
            b.iter(|| resample_to_whole(black_box(&angle), &clock, Domain::Circle).expect("resample"))
        });
        group.bench_function(format!("line_{n}"), |b| {
            b.iter(|| resample_to_whole(black_box(&line), &clock, Domain::Line).expect("resample"))
        });
        // One piece, the whole record.
        let whole = 0..n;
        let pieces = std::slice::from_ref(&whole);
        group.bench_function(format!("two_columns_one_by_one_{n}"), |b| {
            b.iter(|| {
                (
                    resample_pieces(black_box(&angle), pieces, &clock, Domain::Circle).expect("resample"),
                    resample_pieces(black_box(&line), pieces, &clock, Domain::Line).expect("resample"),
                )
            })
        });
        group.bench_function(format!("two_columns_together_{n}"), |b| {
            b.iter(|| {
                let columns = vec![(angle.clone(), Domain::Circle), (line.clone(), Domain::Line)];
                resample_columns(black_box(columns), pieces, &clock).expect("resample")
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_resample);
criterion_main!(benches);
