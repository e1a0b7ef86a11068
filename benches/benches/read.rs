//! The read stage of `hbid identify` (what `--timings` calls `read`) on 10^6 samples of the paper's
//! pendulum as `hbid simulate --samples 1000000` writes them, `.npy` and CSV: the file read, its
//! time stamps fitted to a grid, the angle wrapped and searched for spikes, the drive's period
//! given (`hb_pipeline::load` with the command's defaults). The records are simulated and written
//! once, outside the timed closures; `RAYON_NUM_THREADS=1` for one thread.
use std::path::Path;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use hb_pipeline::{RecordOptions, Rig, SimulateOptions, Source, load, simulate};

/// The paper's pendulum, `samples` samples, written to `path` as `hbid simulate` writes it.
fn write_record(samples: usize, path: &Path) {
    let rig = Rig::new(SimulateOptions {
        samples: Some(samples),
        ..SimulateOptions::default()
    })
    .expect("the paper's settings");
    simulate(&rig, &mut ())
        .expect("simulation")
        .write(path)
        .expect("record written");
}

fn bench_read(c: &mut Criterion) {
    let dir = tempfile::tempdir().expect("temporary folder");
    let options = RecordOptions::default();
    let drive = options.drive(false);
    let mut group = c.benchmark_group("read");
    group.sample_size(10).measurement_time(Duration::from_secs(10));
    for ext in ["npy", "csv"] {
        let path = dir.path().join(format!("pendulum_1e6.{ext}"));
        write_record(1_000_000, &path);
        group.bench_function(format!("{ext}_1e6"), |b| {
            b.iter(|| load(Source::Path(&path), &options, drive, &mut ()).expect("read"))
        });
    }
    group.finish();
}

criterion_group!(benches, bench_read);
criterion_main!(benches);
