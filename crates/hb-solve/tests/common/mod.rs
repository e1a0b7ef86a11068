//! What the tests and the `sweep` example of hb-solve share: the shared fixture's paper data set
//! and the true model of the pendulum.
// Each user takes the part it needs.
#![allow(dead_code)]

use std::error::Error;

/// The paper's pendulum, x'' + 0.03 x' + (1/0.8333²) sin x − 1.52 sin t cos x = 0, as a model on
/// the harmonic basis K = 1 (method notes section 1): the truth identified models are compared with.
pub fn truth() -> hb_model::IdentifiedModel<hb_basis::Harmonic> {
    pendulum_sim::truth::pendulum_model(&pendulum_sim::Pendulum::paper()).unwrap()
}

/// The shared fixture `paper_dataset.csv`, beside the repository.
pub const PAPER_DATASET: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../../shared/fixtures/paper_dataset.csv"
);

/// `(t0, theta)` of a `t,theta` CSV (`#` comments and the header skipped).
pub fn read_dataset(path: &str) -> Result<(f64, Vec<f64>), Box<dyn Error>> {
    let text = std::fs::read_to_string(path)?;
    let mut t0 = None;
    let mut x = Vec::new();
    for line in text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("t,"))
    {
        let mut parts = line.split(',');
        let t: f64 = parts.next().ok_or("missing t")?.trim().parse()?;
        let theta: f64 = parts.next().ok_or("missing theta")?.trim().parse()?;
        t0.get_or_insert(t);
        x.push(theta);
    }
    Ok((t0.ok_or("empty data set")?, x))
}

/// The paper's data set from the shared fixtures.
pub fn read_paper_dataset() -> (f64, Vec<f64>) {
    read_dataset(PAPER_DATASET).expect("the shared fixtures are next to the repository")
}

/// The clock of the paper's data set: non-dimensional time, 25 samples per forcing period, first
/// sample at `t0`.
pub fn paper_clock(t0: f64) -> circle_signal::SampleClock {
    circle_signal::SampleClock::nondimensional(25)
        .unwrap()
        .with_start_time(t0)
        .unwrap()
}

/// A segment of `period` forcing periods and `len` samples from `start`, on the non-dimensional
/// clock with `len / period` samples per period (the record's length is checked by the assembly).
pub fn segment(start: usize, period: usize, len: usize, error: f64) -> circle_signal::Segment {
    let clock = circle_signal::SampleClock::nondimensional(len / period).unwrap();
    circle_signal::Segment::new(start, period, &clock, error, usize::MAX).unwrap()
}
