//! The whole `hbid identify` as a user runs it (process start, reading, delay, segments, assembly,
//! least squares, 1000 bootstrap resamples): on the paper's data set and on 10^6 samples, read
//! whole and in chunks (`--stream`).
//!
//! The release `hbid` is built first by the same `cargo` (`cargo build --release -p hbid`): it
//! lives here and not in the `hbid` package so that `cargo test` builds no criterion.
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use criterion::{Criterion, criterion_group, criterion_main};

/// The release `hbid`, `<target>/release/hbid`, built once per bench run.
fn hbid_exe() -> &'static Path {
    static EXE: OnceLock<PathBuf> = OnceLock::new();
    EXE.get_or_init(|| {
        let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
        let status = Command::new(cargo)
            .args(["build", "--release", "--quiet", "-p", "hbid"])
            .status()
            .expect("cargo runs");
        assert!(status.success(), "cargo build --release -p hbid failed");
        // This bench is <target>/release/deps/identify-HASH.
        let exe = std::env::current_exe().expect("the bench's path");
        let target = exe
            .ancestors()
            .nth(3)
            .expect("the bench is in a cargo target folder");
        let hbid = target
            .join("release")
            .join(format!("hbid{}", std::env::consts::EXE_SUFFIX));
        assert!(hbid.exists(), "no release hbid at {}", hbid.display());
        hbid
    })
}

fn hbid(args: &[&str], file: &Path) {
    let out = Command::new(hbid_exe())
        .args(args)
        .arg(file)
        .output()
        .expect("hbid runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
}

/// 10^6 samples of the paper's pendulum as `.npy`, simulated once per bench run.
fn million(dir: &Path) -> PathBuf {
    let path = dir.join("pendulum_1e6.npy");
    let status = Command::new(hbid_exe())
        .args(["simulate", "--quiet", "--samples", "1000000", "--out"])
        .arg(&path)
        .status()
        .expect("hbid simulate runs");
    assert!(status.success());
    path
}

fn bench(c: &mut Criterion) {
    let paper = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/fixtures/paper_dataset.csv");
    let mut group = c.benchmark_group("hbid_identify");
    group.sample_size(10);
    if paper.exists() {
        for method in ["upo", "windowed"] {
            group.bench_function(format!("paper_30000_csv/{method}"), |b| {
                b.iter(|| hbid(&["identify", "--quiet", "--method", method], &paper))
            });
        }
    }
    let dir = tempfile::tempdir().expect("temporary folder");
    let record = million(dir.path());
    for method in ["upo", "windowed"] {
        group.bench_function(format!("simulated_1e6_npy/{method}"), |b| {
            b.iter(|| hbid(&["identify", "--quiet", "--method", method], &record))
        });
    }
    // The same record read in chunks (one chunk of it: the reading, conditioning and compressed
    // assembly of `hb_pipeline::stream` against the record read whole above).
    group.bench_function("simulated_1e6_npy/windowed_stream", |b| {
        b.iter(|| hbid(&["identify", "--quiet", "--stream"], &record))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
