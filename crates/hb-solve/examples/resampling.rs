//! What resampling onto a whole number of samples per forcing period costs in accuracy.
//!
//! The pendulum of the paper is simulated at 490.196 samples per forcing period (a 1.02 Hz drive
//! sampled at 500 Hz) and, for reference, at exactly 490; the first record is resampled onto the
//! 490-sample grid (`circle_signal::resample_to_whole`) and both are identified by the weak form
//! and by the paper's method, from the exact angle and through a 4096-count encoder.
//!
//! ```text
//! cargo run --release -p hb-solve --example resampling
//! ```
//!
//! Prints the Markdown table of `docs/identification.md`.
#![allow(clippy::print_stdout)]

use std::error::Error;
use std::f64::consts::TAU;

use circle_signal::{Domain, SampleClock, resample_to_whole, wrap};
use hb_basis::Harmonic;
use hb_model::IdentifiedModel;
use hb_solve::{Assembly, HarmonicBalance, IdentifyParams, QrSolver, WeakForm, identify_from_source};
use pendulum_sim::{Pendulum, SimulationConfig, simulate};
use upo_search::{CloseReturns, Windows};

/// Forcing periods in each record (the paper's record spans 1200).
const PERIODS: f64 = 1200.0;

/// A record of the paper's pendulum at `ratio` samples per forcing period `2π`: `(t0, wrapped angle)`.
fn record(ratio: f64) -> Result<(f64, Vec<f64>), Box<dyn Error>> {
    // The simulator's grid is `P` samples per its forcing period; giving it the period `P h`
    // samples the (2π-periodic) pendulum every `h = 2π / ratio`.
    let p = ratio.round() as usize;
    let h = TAU / ratio;
    let config = SimulationConfig::paper()
        .with_samples((PERIODS * ratio) as usize)?
        .with_samples_per_period(p)?
        .with_drive_period(p as f64 * h)?;
    let traj = simulate(&Pendulum::paper(), &config)?;
    Ok((traj.t[0], traj.wrapped()))
}

/// The angle through an encoder of `counts` per revolution.
fn encoder(x: &[f64], counts: f64) -> Vec<f64> {
    let q = TAU / counts;
    x.iter().map(|&v| wrap((v / q).round() * q)).collect()
}

/// Largest relative error of the three nonzero coefficients and largest absolute error of the
/// four zero ones.
fn errors(model: &IdentifiedModel<Harmonic>) -> (f64, f64) {
    let truth = [
        ("x'", 0.03),
        ("cos(t)*cos(x)", 0.0),
        ("sin(t)*cos(x)", -1.52),
        ("cos(x)", 0.0),
        ("cos(t)*sin(x)", 0.0),
        ("sin(t)*sin(x)", 0.0),
        ("sin(x)", 1.0 / (0.8333 * 0.8333)),
    ];
    let (mut rel, mut abs) = (0.0f64, 0.0f64);
    for (name, value) in truth {
        let got = model.coefficient(name).map_or(f64::NAN, |c| c.value);
        if value == 0.0 {
            abs = abs.max(got.abs());
        } else {
            rel = rel.max(((got - value) / value).abs());
        }
    }
    (rel, abs)
}

fn identify(method: &dyn Assembly, clock: &SampleClock, x: &[f64]) -> Result<(f64, f64), Box<dyn Error>> {
    let params = IdentifyParams::builder(*clock)
        .harmonics(method.default_harmonics())
        .build()?;
    let basis = Harmonic::new(1)?;
    let model = if method.name() == "upo" {
        // The delay of the paper (5 samples at 25 per period), in forcing periods.
        let p = clock.require_whole()?;
        let delay = (5 * p).div_ceil(25);
        let search = CloseReturns::builder(clock, delay).build()?;
        identify_from_source(basis, x, &search, &params, method, &QrSolver::default())?
    } else {
        let windows = Windows::builder(clock).domain(Domain::Circle).build()?;
        identify_from_source(basis, x, &windows, &params, method, &QrSolver::default())?
    };
    Ok(errors(&model))
}

fn main() -> Result<(), Box<dyn Error>> {
    let odd = 500.0 / 1.02;
    let (t_odd, x_odd) = record(odd)?;
    let (t_whole, x_whole) = record(490.0)?;
    let clock_odd = SampleClock::from_step(TAU, TAU / odd)?.with_start_time(t_odd)?;
    let clock_whole = SampleClock::new(TAU, 490)?.with_start_time(t_whole)?;
    println!(
        "| record | angle | method | largest relative error (x', sin(t)*cos(x), sin(x)) | largest zero coefficient |"
    );
    println!("| --- | --- | --- | --- | --- |");
    let methods: [Box<dyn Assembly>; 2] = [Box::new(WeakForm::default()), Box::new(HarmonicBalance)];
    for (angle, counts) in [("exact", None), ("4096-count encoder", Some(4096.0))] {
        let observe = |x: &[f64]| counts.map_or_else(|| x.to_vec(), |c| encoder(x, c));
        let resampled = resample_to_whole(&observe(&x_odd), &clock_odd, Domain::Circle)?;
        let cases = [
            ("490 per period, sampled so", clock_whole, observe(&x_whole)),
            (
                "490.196 per period, resampled to 490",
                resampled.clock,
                resampled.samples,
            ),
        ];
        for method in &methods {
            for (label, clock, x) in &cases {
                let (rel, abs) = identify(method.as_ref(), clock, x)?;
                println!(
                    "| {label} | {angle} | {} | {rel:.2e} | {abs:.2e} |",
                    method.name()
                );
            }
        }
    }
    Ok(())
}
