//! The read stage of `hbid identify` (what `--timings` calls `read`) on 10^6 samples, `.npy` and
//! CSV: the file read, its time stamps fitted to a grid, the angles wrapped and searched for
//! spikes, the drive's period given (`hb_pipeline::load` with the command's defaults). Records:
//! the paper's pendulum as `hbid simulate --samples 1000000` writes it (25 samples per period),
//! the same at 64 per period (`--samples-per-period 64`), and the whirling double pendulum
//! (`--system double-pendulum`, two coordinates read with `--time-col 1 --coords
//! theta1=2,theta2=3`). The records are simulated and written once, outside the timed closures;
//! `RAYON_NUM_THREADS=1` for one thread (the two coordinates are conditioned in parallel).
use std::path::Path;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use hb_pipeline::simulate::SystemKind;
use hb_pipeline::{RecordOptions, Rig, SimulateOptions, Source, load, simulate};

/// `samples` samples of `options`' system, written to `path` as `hbid simulate` writes them.
fn write_record(options: SimulateOptions, samples: usize, path: &Path) {
    let rig = Rig::new(SimulateOptions {
        samples: Some(samples),
        ..options
    })
    .expect("valid settings");
    simulate(&rig, &mut ())
        .expect("simulation")
        .write(path)
        .expect("record written");
}

fn bench_read(c: &mut Criterion) {
    let dir = tempfile::tempdir().expect("temporary folder");
    let mut group = c.benchmark_group("read");
    group.sample_size(10).measurement_time(Duration::from_secs(10));
    let one = RecordOptions::default();
    let two = RecordOptions {
        time_col: Some("1".to_owned()),
        coords: Some("theta1=2,theta2=3".parse().expect("columns")),
        ..RecordOptions::default()
    };
    let records = [
        ("npy_1e6", "npy", SimulateOptions::default(), &one),
        ("csv_1e6", "csv", SimulateOptions::default(), &one),
        (
            "npy_1e6_64_per_period",
            "npy",
            SimulateOptions {
                samples_per_period: Some(64),
                ..SimulateOptions::default()
            },
            &one,
        ),
        (
            "npy_1e6_double_pendulum",
            "npy",
            SimulateOptions {
                system: SystemKind::DoublePendulum,
                ..SimulateOptions::default()
            },
            &two,
        ),
    ];
    for (name, ext, simulation, options) in records {
        let path = dir.path().join(format!("{name}.{ext}"));
        write_record(simulation, 1_000_000, &path);
        let drive = options.drive(false);
        group.bench_function(name, |b| {
            b.iter(|| load(Source::Path(&path), options, drive, &mut ()).expect("read"))
        });
    }
    group.finish();
}

criterion_group!(benches, bench_read);
criterion_main!(benches);
