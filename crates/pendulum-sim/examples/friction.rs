//! Measures the integration of dry friction: the free decay of a linear oscillator with Coulomb
//! friction against its closed form, a stick-slip oscillator against regularised friction, and
//! the chaotic pendulum with a rig's losses at two tolerances.
//!
//! `cargo run --release -p pendulum-sim --example friction`
#![allow(clippy::print_stdout)]

use std::f64::consts::PI;

use pendulum_sim::{Duffing, Losses, Pendulum, SecondOrderSystem, SimulationConfig, Tolerances, simulate};

/// `x'' + ω² x + μ sign(x') = 0` from rest at `x0`, in closed form.
fn coulomb(omega: f64, mu: f64, x0: f64, t: f64) -> [f64; 2] {
    let w2 = omega * omega;
    let (mut start, mut t_n) = (x0, 0.0);
    loop {
        if w2 * start.abs() <= mu {
            return [start, 0.0];
        }
        let s = -start.signum();
        let centre = -mu * s / w2;
        if t <= t_n + PI / omega {
            let phase = omega * (t - t_n);
            return [
                centre + (start - centre) * phase.cos(),
                -(start - centre) * omega * phase.sin(),
            ];
        }
        start = 2.0 * centre - start;
        t_n += PI / omega;
    }
}

/// Friction regularised to `μ tanh(v/ε)`: a smooth, stiff system.
struct Regularised {
    system: Duffing,
    mu: f64,
    eps: f64,
}

impl SecondOrderSystem for Regularised {
    fn acceleration(&self, t: f64, x: f64, v: f64) -> f64 {
        self.system.acceleration(t, x, v) - self.mu * (v / self.eps).tanh()
    }
    fn jacobian(&self, t: f64, x: f64, v: f64) -> [f64; 2] {
        let [jx, jv] = self.system.jacobian(t, x, v);
        [jx, jv - self.mu / self.eps / (v / self.eps).cosh().powi(2)]
    }
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let (omega, mu, x0) = (1.3, 0.05, 1.0);
    let system = Duffing::new(0.0, omega * omega, 0.0, 0.0)?.with_losses(Losses::none().with_friction(mu)?);
    println!("Coulomb oscillator, omega = {omega}, mu = {mu}, x0 = {x0}: 17 swings, then at rest");
    println!("| rtol | max |x - exact| | max |x' - exact| | amplitude lost in 7 cycles - 28 mu/omega^2 |");
    println!("| --- | --- | --- | --- |");
    for rtol in [1e-6, 1e-8, 1e-10, 1e-12] {
        let config = SimulationConfig::paper()
            .with_sample_step(0.01)?
            .with_transient_periods(0)
            .with_initial(x0, 0.0)?
            .with_samples(6_000)?
            .with_tolerances(Tolerances::relative(rtol)?);
        let traj = simulate(&system, &config)?;
        let exact: Vec<[f64; 2]> = traj.t.iter().map(|&t| coulomb(omega, mu, x0, t)).collect();
        let ex: f64 = traj
            .theta
            .iter()
            .zip(&exact)
            .map(|(a, e)| (a - e[0]).abs())
            .fold(0.0, f64::max);
        let ev: f64 = traj
            .omega
            .iter()
            .zip(&exact)
            .map(|(a, e)| (a - e[1]).abs())
            .fold(0.0, f64::max);
        let seven = simulate(
            &system,
            &config
                .clone()
                .with_sample_step(7.0 * 2.0 * PI / omega)?
                .with_samples(2)?,
        )?;
        let lost = x0 - seven.theta[1] - 7.0 * 4.0 * mu / (omega * omega);
        println!("| {rtol:e} | {ex:.1e} | {ev:.1e} | {lost:.1e} |");
    }

    println!();
    println!("Stick-slip: x'' + 0.1 x' + x + mu sign(x') = 0.5 cos t, from (0.2, 0), 40 time units");
    println!("| mu | samples at rest | eps of tanh(v/eps) | max |x - x_eps| |");
    println!("| --- | --- | --- | --- |");
    for mu in [0.3, 0.45] {
        let smooth = Duffing::new(0.1, 1.0, 0.0, 0.5)?;
        let rig = smooth.with_losses(Losses::none().with_friction(mu)?);
        let config = SimulationConfig::paper()
            .with_sample_step(0.05)?
            .with_transient_periods(0)
            .with_initial(0.2, 0.0)?
            .with_samples(800)?
            .with_tolerances(Tolerances::relative(1e-11)?);
        let traj = simulate(&rig, &config)?;
        let rest = traj.omega.iter().filter(|&&v| v == 0.0).count();
        for eps in [1e-5, 1e-6, 1e-7] {
            let reference = simulate(
                &Regularised {
                    system: smooth,
                    mu,
                    eps,
                },
                &config,
            )?;
            println!(
                "| {mu} | {rest} | {eps:e} | {:.1e} |",
                max_diff(&traj.theta, &reference.theta)
            );
        }
    }

    println!();
    println!("Chaotic pendulum, 3 and 10 forcing periods from (0.1, 0): max |x(rtol) - x(1e-13)|");
    println!("| system | periods | rtol 1e-8 | rtol 1e-10 | rtol 1e-12 |");
    println!("| --- | --- | --- | --- | --- |");
    let rig = Pendulum::paper().with_losses(
        Losses::none()
            .with_friction(0.02)?
            .with_drag(0.01)?
            .with_cubic_damping(0.002)?,
    );
    for (name, p) in [
        ("paper", Pendulum::paper()),
        ("paper + mu 0.02, d 0.01, c3 0.002", rig),
    ] {
        for periods in [3, 10] {
            let run = |rtol: f64| -> Result<Vec<f64>, Box<dyn std::error::Error>> {
                Ok(simulate(
                    &p,
                    &SimulationConfig::paper()
                        .with_transient_periods(0)
                        .with_samples(25 * periods)?
                        .with_tolerances(Tolerances::relative(rtol)?),
                )?
                .theta)
            };
            let reference = run(1e-13)?;
            let cells: Vec<String> = [1e-8, 1e-10, 1e-12]
                .iter()
                .map(|&rtol| Ok(format!("{:.1e}", max_diff(&run(rtol)?, &reference))))
                .collect::<Result<_, Box<dyn std::error::Error>>>()?;
            println!("| {name} | {periods} | {} |", cells.join(" | "));
        }
    }
    Ok(())
}
