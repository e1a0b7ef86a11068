//! Measures the valid prediction time of the paper's pendulum on its own record: what the
//! estimate of the starting state costs (against the simulation's exact states), how the result
//! depends on the tolerance, the fit span, noise and the sampling rate; and the decay envelope of a
//! free decay against a model with a wrong damping.
//!
//! `cargo run --release -p pendulum-sim --example prediction`
#![allow(clippy::print_stdout)]

use circle_signal::{SampleClock, wrap};
use pendulum_sim::{
    Domain, Pendulum, PredictionConfig, PredictionRecord, PredictionTimes, SimulationConfig, Trajectory,
    decay_envelope, predict_window, prediction_starts, simulate, valid_prediction_times,
};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

type Result<T> = std::result::Result<T, Box<dyn std::error::Error>>;

/// The paper's data set at `p` samples per forcing period, 1200 periods long.
fn data_set(p: usize) -> Result<(Trajectory, SampleClock)> {
    let traj = simulate(
        &Pendulum::paper(),
        &SimulationConfig::paper()
            .with_samples_per_period(p)?
            .with_samples(1200 * p)?,
    )?;
    let clock = SampleClock::nondimensional(p)?.with_start_time(traj.t[0])?;
    Ok((traj, clock))
}

/// Median (quartiles) in forcing periods.
fn cell(t: &PredictionTimes) -> String {
    let s = t.in_periods().expect("windows");
    format!(
        "{:.2} ({:.2}–{:.2})",
        s.median, s.lower_quartile, s.upper_quartile
    )
}

/// The truth's times from the estimated states and from the exact ones.
fn estimated_and_exact(
    traj: &Trajectory,
    record: &PredictionRecord<'_>,
    config: &PredictionConfig,
) -> Result<(PredictionTimes, PredictionTimes)> {
    let starts = prediction_starts(record, config)?;
    let estimated = valid_prediction_times(&Pendulum::paper(), record, &starts, config, None)?;
    let windows = starts
        .iter()
        .map(|&n| {
            predict_window(
                &Pendulum::paper(),
                record,
                n,
                [traj.theta[n], traj.omega[n]],
                config,
            )
        })
        .collect::<std::result::Result<Vec<_>, _>>()?;
    let exact = PredictionTimes {
        windows,
        ..estimated.clone()
    };
    Ok((estimated, exact))
}

fn main() -> Result<()> {
    let (traj, clock) = data_set(25)?;
    let x = traj.wrapped();
    let record = PredictionRecord::new(&x, clock, Domain::Circle)?;

    println!("The true pendulum on its own record (1200 periods, 25 per period, 32 windows):");
    println!("median valid time in forcing periods (quartiles)\n");
    println!("| tolerance (of the spread) | from estimated states | from exact states |");
    println!("| --- | --- | --- |");
    for tol in [0.05, 0.1, 0.2] {
        let config = PredictionConfig::default().with_tolerance(tol)?;
        let (estimated, exact) = estimated_and_exact(&traj, &record, &config)?;
        println!("| {tol} | {} | {} |", cell(&estimated), cell(&exact));
    }

    println!(
        "\n| samples per period | fit span | samples in the fit | from estimated states | from exact states |"
    );
    println!("| --- | --- | --- | --- | --- |");
    for p in [25, 50, 100] {
        let (traj, clock) = data_set(p)?;
        let x = traj.wrapped();
        let record = PredictionRecord::new(&x, clock, Domain::Circle)?;
        for span in [1.0 / 12.0, 1.0 / 6.0] {
            let config = PredictionConfig::default().with_fit_span(span)?;
            let m = ((span * p as f64).round() as usize).max(2);
            let (estimated, exact) = estimated_and_exact(&traj, &record, &config)?;
            println!(
                "| {p} | T/{:.0} | {} | {} | {} |",
                1.0 / span,
                2 * m + 1,
                cell(&estimated),
                cell(&exact)
            );
        }
    }

    println!("\nGaussian noise on the angle (25 per period; seed 1):\n");
    println!("| noise σ (rad) | fit span T/12 | fit span T/8 | fit span T/6 |");
    println!("| --- | --- | --- | --- |");
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    for sigma in [1e-3, 1e-2] {
        let noise = Normal::new(0.0, sigma)?;
        let noisy: Vec<f64> = traj
            .theta
            .iter()
            .map(|&t| wrap(t + noise.sample(&mut rng)))
            .collect();
        let record = PredictionRecord::new(&noisy, clock, Domain::Circle)?;
        let cells = [12.0, 8.0, 6.0]
            .iter()
            .map(|&d| {
                let config = PredictionConfig::default().with_fit_span(1.0 / d)?;
                let starts = prediction_starts(&record, &config)?;
                Ok(cell(&valid_prediction_times(
                    &Pendulum::paper(),
                    &record,
                    &starts,
                    &config,
                    None,
                )?))
            })
            .collect::<Result<Vec<_>>>()?;
        println!("| {sigma} | {} |", cells.join(" | "));
    }

    println!("\nA model with a wrong damping c (the truth 0.03), on the noise-free record:\n");
    println!("| c | median valid time (periods) |");
    println!("| --- | --- |");
    let config = PredictionConfig::default();
    let starts = prediction_starts(&record, &config)?;
    for c in [0.03, 0.0303, 0.033, 0.036] {
        let model = Pendulum::new(1.52, c, 0.8333)?;
        let t = valid_prediction_times(&model, &record, &starts, &config, None)?;
        println!("| {c} | {} |", cell(&t));
    }

    println!("\nFree decay of the pendulum (f = 0, c = 0.05) from 2.5 rad at rest, 120 periods of 2π:\n");
    println!("| model | swings compared | median |error| | largest |error| |");
    println!("| --- | --- | --- | --- |");
    let free = Pendulum::new(0.0, 0.05, 0.8333)?;
    let decay = simulate(
        &free,
        &SimulationConfig::paper()
            .with_transient_periods(0)
            .with_initial(2.5, 0.0)?
            .with_samples(3_000)?,
    )?;
    let x = decay.wrapped();
    let record = PredictionRecord::new(&x, SampleClock::nondimensional(25)?, Domain::Circle)?;
    for c in [0.05, 0.055, 0.1] {
        let e = decay_envelope(&Pendulum::new(0.0, c, 0.8333)?, &record, &config)?;
        println!(
            "| c = {c} | {} | {:.1e} | {:.1e} |",
            e.relative_errors.len(),
            e.median_error().unwrap_or(f64::NAN),
            e.max_error().unwrap_or(f64::NAN)
        );
    }
    Ok(())
}
