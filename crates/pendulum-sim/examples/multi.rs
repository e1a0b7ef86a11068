//! Measures the built-in systems of several coordinates: how the base-excited double pendulum
//! whirls, how far the DFKI arm swings under record 04's drives, and how the coupled Duffing
//! oscillators move between their wells.
//!
//! `cargo run --release -p pendulum-sim --example multi`
#![allow(clippy::print_stdout)]

use std::f64::consts::{PI, TAU};

use pendulum_sim::{
    CoupledDuffing, DoublePendulum, MultiConfig, MultiState, Tolerances, Torque, TorqueDoublePendulum, multi,
};

/// Passages of a continuous angle over the top (`θ ≡ π`), net turns, range and largest speed.
fn describe(name: &str, q: &[f64], v: &[f64]) {
    let over = q
        .windows(2)
        .filter(|w| ((w[0] - PI) / TAU).floor() != ((w[1] - PI) / TAU).floor())
        .count();
    let net = (q[q.len() - 1] - q[0]) / TAU;
    let (lo, hi) = q.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
        (a.min(x), b.max(x))
    });
    let fastest = v.iter().fold(0.0f64, |a, &x| a.max(x.abs()));
    println!(
        "  {name}: {over} passages over the top, net {net:+.2} turns, range {lo:.2} .. {hi:.2} ({:.1} rad), |v| <= {fastest:.3}",
        hi - lo
    );
}

fn main() -> Result<(), pendulum_sim::SimError> {
    let tol = Tolerances::relative(1e-10)?;

    let pendulum = DoublePendulum::whirling();
    let periods = 160;
    let config = MultiConfig::new(MultiState::at_rest(&[2.0, 0.0])?)
        .with_samples_per_period(64)?
        .with_transient_periods(0)
        .with_samples(periods * 64 + 1)?
        .with_tolerances(tol);
    let run = multi::simulate(&pendulum, &config)?;
    println!("DoublePendulum::whirling() from θ = (2, 0) at rest, {periods} periods, 64 samples per period:");
    describe("θ1", &run.q[0], &run.v[0]);
    describe("θ2", &run.q[1], &run.v[1]);
    let step = run
        .q
        .iter()
        .flat_map(|q| q.windows(2).map(|w| (w[1] - w[0]).abs()))
        .fold(0.0f64, f64::max);
    println!("  largest change between samples {step:.3} rad");
    for half in [0, 1] {
        let range = half * periods / 2 * 64..(half + 1) * periods / 2 * 64;
        let over: Vec<usize> = run
            .q
            .iter()
            .map(|q| {
                q[range.clone()]
                    .windows(2)
                    .filter(|w| ((w[0] - PI) / TAU).floor() != ((w[1] - PI) / TAU).floor())
                    .count()
            })
            .collect();
        println!(
            "  periods {:?}: passages over the top {over:?}",
            (range.start / 64, range.end / 64)
        );
    }

    let arm = TorqueDoublePendulum::dfki().with_torques(
        Torque::sinusoid(0.4, 10.0, 0.0)?,
        Torque::sinusoid(-0.6, 5.0, 0.5 * PI)?,
    );
    let times: Vec<f64> = (0..=5000).map(|i| i as f64 * 0.002).collect();
    let run = multi::free_run(&arm, &times, &MultiState::at_rest(&[0.0, 0.0])?, tol)?;
    println!(
        "TorqueDoublePendulum::dfki() from rest, record 04's commanded drives (0.4 sin 10t, -0.6 cos 5t), 10 s: stopped {:?}",
        run.stopped
    );
    describe("q1", &run.q[0], &run.v[0]);
    describe("q2", &run.q[1], &run.v[1]);
    let q12: Vec<f64> = run.q[0].iter().zip(&run.q[1]).map(|(a, b)| a + b).collect();
    let v12: Vec<f64> = run.v[0].iter().zip(&run.v[1]).map(|(a, b)| a + b).collect();
    describe("q1+q2", &q12, &v12);
    let stuck: Vec<usize> = run
        .v
        .iter()
        .map(|v| v.iter().filter(|&&x| x == 0.0).count())
        .collect();
    println!("  samples with a joint at rest (exactly): {stuck:?}");

    let duffing = CoupledDuffing::two_wells();
    let config = MultiConfig::new(MultiState::at_rest(&[1.0, -0.9])?)
        .with_sample_step(0.1)?
        .with_transient_periods(0)
        .with_samples(10_001)?
        .with_tolerances(tol);
    let run = multi::simulate(&duffing, &config)?;
    println!("CoupledDuffing::two_wells() from rest at (1, -0.9), t <= 1000, step 0.1:");
    for c in 0..2 {
        let x = &run.q[c];
        let crossings = x.windows(2).filter(|w| (w[0] < 0.0) != (w[1] < 0.0)).count();
        let (lo, hi) = x.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &y| {
            (a.min(y), b.max(y))
        });
        let fastest = run.v[c].iter().fold(0.0f64, |a, &y| a.max(y.abs()));
        println!(
            "  x{}: {crossings} crossings between the wells, range {lo:.2} .. {hi:.2}, |v| <= {fastest:.3}",
            c + 1
        );
    }
    let drive: Vec<f64> = run.t.iter().map(|&t| duffing.drive().at(t)).collect();
    let rms = (drive.iter().map(|p| p * p).sum::<f64>() / drive.len() as f64).sqrt();
    println!("  base acceleration rms {rms:.3}");
    Ok(())
}
