//! Prints the simulator's accuracy against the SciPy reference and its Lyapunov exponent.
//!
//! `cargo run --release -p pendulum-sim --example accuracy`
#![allow(clippy::print_stdout)]

use pendulum_sim::{LyapunovConfig, Pendulum, SimulationConfig, Tolerances, largest_lyapunov, simulate};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/fixtures/reference_trajectory.csv"
    );
    let reference: Vec<[f64; 3]> = std::fs::read_to_string(path)?
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with('t'))
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|c| c.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    println!("| rtol | max abs theta error over 201 samples (8 periods) | accepted steps |");
    println!("| --- | --- | --- |");
    for rtol in [1e-8, 1e-10, 1e-12, 1e-13] {
        let cfg = SimulationConfig::paper()
            .with_samples(reference.len())?
            .with_transient_periods(0)
            .with_tolerances(Tolerances::relative(rtol)?);
        let traj = simulate(&Pendulum::paper(), &cfg)?;
        let worst = traj
            .theta
            .iter()
            .zip(&reference)
            .map(|(a, r)| (a - r[1]).abs())
            .fold(0.0, f64::max);
        let mut ode = pendulum_sim::Dop853::new(
            pendulum_sim::FirstOrder(Pendulum::paper()),
            0.0,
            [0.1, 0.0],
            Tolerances::relative(rtol)?,
        )?;
        ode.advance_to(16.0 * std::f64::consts::PI)?;
        println!("| {rtol:e} | {worst:.2e} | {} |", ode.stats().accepted);
    }
    println!();
    println!("| measured periods | lambda per unit t | std. error | per forcing period |");
    println!("| --- | --- | --- | --- |");
    for periods in [1000, 5000, 20000] {
        let cfg = LyapunovConfig::default().with_periods(periods)?;
        let est = largest_lyapunov(&Pendulum::paper(), &cfg, |_, _| {})?;
        println!(
            "| {periods} | {:.4} | {:.4} | {:.3} |",
            est.per_unit_time, est.standard_error, est.per_period
        );
    }
    Ok(())
}
