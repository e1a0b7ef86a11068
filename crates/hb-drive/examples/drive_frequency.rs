//! How accurately, how honestly and how fast the forcing period is estimated from a record.
//!
//! ```text
//! cargo run --release -p hb-solve --example drive_frequency            # accuracy and time
//! cargo run --release -p hb-solve --example drive_frequency -- honesty [rig] # spread against uncertainty
//! cargo run --release -p hb-solve --example drive_frequency -- contrast # noise, ranges without the truth
//! cargo run --release -p hb-solve --example drive_frequency -- costs    # settings, 10^6 samples, resampling
//! ```
//!
//! The paper's pendulum is simulated (DOP853, `rtol = 1e-10`): the paper's record (30000 samples at
//! 25 per forcing period `2π`), and a record of 300 periods of a 1.02 Hz drive sampled at 500 Hz
//! (490.196 samples per period, time in seconds: the non-dimensional time relabelled by
//! `T / 2π`), each exact and through a 4096-count encoder. The search range is 0.5 to 2 times the
//! truth, and the default range (from the spectrum) is tried too. `honesty` estimates the period
//! of 40 seeded records with σ = 0.01 rad of noise on the angle (the paper's record, or with `rig`
//! 90 periods at 490.196 samples per period) and compares the spread of the estimates with the
//! reported uncertainties. `contrast` shows the winner's contrast with noise and with ranges that
//! miss the truth; `costs` the evaluations and time of other settings of the search, on records up
//! to a million samples, beside the time of one resampling of the record.
#![allow(clippy::print_stdout)]

use std::error::Error;
use std::f64::consts::TAU;
use std::time::Instant;

use circle_signal::{Domain, SampleClock, resample_to_whole, wrap};
use hb_basis::Harmonic;
use hb_drive::{DriveEstimate, DriveSearch, PeriodRange, RangeSource, estimate_drive_period};
use hb_model::ModelForm;
use pendulum_sim::observe::Encoder;
use pendulum_sim::{Dop853, FirstOrder, Pendulum, Tolerances};

/// A record of the paper's pendulum: `samples` samples every `dt` (non-dimensional time) after 200
/// forcing periods of transient from `(0.1, 0)`, relabelled so that the forcing period is
/// `period`: `(t0, step, continuous angle)`.
fn record(period: f64, dt: f64, samples: usize) -> Result<(f64, f64, Vec<f64>), Box<dyn Error>> {
    let scale = period / TAU;
    let mut ode = Dop853::new(
        FirstOrder(Pendulum::paper()),
        0.0,
        [0.1, 0.0],
        Tolerances::default(),
    )?;
    let t_first = 200.0 * TAU;
    let mut theta = Vec::with_capacity(samples);
    ode.sample_grid(t_first, dt, samples, |_, _, y| theta.push(y[0]))?;
    Ok((t_first * scale, dt * scale, theta))
}

/// The angle through an encoder of `counts` per revolution.
fn encoder(x: &[f64], counts: f64) -> Vec<f64> {
    let q = TAU / counts;
    x.iter().map(|&v| wrap((v / q).round() * q)).collect()
}

fn estimate(
    x: &[f64],
    step: f64,
    t0: f64,
    range: Option<PeriodRange>,
) -> Result<(DriveEstimate, f64), Box<dyn Error>> {
    let mut builder = DriveSearch::builder();
    if let Some(range) = range {
        builder = builder.range(range);
    }
    estimate_with(x, step, t0, &builder.build()?)
}

fn estimate_with(
    x: &[f64],
    step: f64,
    t0: f64,
    search: &DriveSearch,
) -> Result<(DriveEstimate, f64), Box<dyn Error>> {
    let basis = Harmonic::new(1)?;
    let start = Instant::now();
    let found = estimate_drive_period(
        x,
        step,
        t0,
        Domain::Circle,
        search,
        &basis,
        &ModelForm::parametric(),
        |_, _| {},
    )?;
    Ok((found, start.elapsed().as_secs_f64()))
}

fn accuracy() -> Result<(), Box<dyn Error>> {
    let paper_period = TAU;
    let rig_period = 1.0 / 1.02;
    let rig_ratio = 500.0 / 1.02;
    let records = [
        ("paper, 30000 at 25/period", paper_period, TAU / 25.0, 30_000),
        (
            "1.02 Hz at 500 Hz, 300 periods",
            rig_period,
            TAU / rig_ratio,
            (300.0 * rig_ratio) as usize,
        ),
    ];
    println!(
        "| record | angle | range | estimate / truth − 1 | reported σ_T/T (robust, iid) | contrast | evaluations | time (s) |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- |");
    for (label, period, dt, samples) in records {
        let (t0, step, theta) = record(period, dt, samples)?;
        for (angle, counts) in [("exact", None), ("4096 counts", Some(4096.0))] {
            let x = match counts {
                None => theta.iter().map(|&v| wrap(v)).collect::<Vec<_>>(),
                Some(c) => encoder(&theta, c),
            };
            for (name, range) in [
                (
                    "0.5..2 T",
                    Some(PeriodRange::periods(0.5 * period, 2.0 * period)?),
                ),
                ("default", None),
            ] {
                match estimate(&x, step, t0, range) {
                    Ok((found, seconds)) => println!(
                        "| {label} | {angle} | {name}{} | {:+.2e} | {:.2e}, {:.2e} | {:.1e} | {} | {seconds:.3} |",
                        match found.range_source {
                            RangeSource::Spectrum { dominant_period } => format!(
                                " ({:.3}..{:.3} T, T_p = {:.3} T)",
                                found.range.shortest() / period,
                                found.range.longest() / period,
                                dominant_period / period
                            ),
                            _ => String::new(),
                        },
                        found.period / period - 1.0,
                        found.relative_uncertainty(),
                        found.period_uncertainty_iid / found.period,
                        found.contrast,
                        found.evaluations,
                    ),
                    Err(e) => println!("| {label} | {angle} | {name} | error: {e} | | | | |"),
                }
            }
        }
    }
    Ok(())
}

fn honesty(rig: bool) -> Result<(), Box<dyn Error>> {
    let (label, period, (t0, step, theta)) = if rig {
        let ratio = 500.0 / 1.02;
        let period = 1.0 / 1.02;
        (
            "44118 samples (490.196 per period, 90 periods)",
            period,
            record(period, TAU / ratio, (90.0 * ratio) as usize)?,
        )
    } else {
        (
            "30000 samples (25 per period)",
            TAU,
            record(TAU, TAU / 25.0, 30_000)?,
        )
    };
    let range = PeriodRange::periods(0.5 * period, 2.0 * period)?;
    let records = 40;
    let mut errors = Vec::new();
    let (mut robust, mut iid) = (Vec::new(), Vec::new());
    for stream in 0..records {
        let x = Encoder::seeded(2024)
            .with_noise(0.01)?
            .with_stream(stream)
            .observe(&theta);
        let (found, _) = estimate(&x, step, t0, Some(range))?;
        errors.push(found.period / period - 1.0);
        robust.push(found.relative_uncertainty());
        iid.push(found.period_uncertainty_iid / found.period);
    }
    let n = errors.len() as f64;
    let mean = errors.iter().sum::<f64>() / n;
    let spread = (errors.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    let rms = (errors.iter().map(|e| e * e).sum::<f64>() / n).sqrt();
    let mean_of = |v: &[f64]| (v.iter().map(|s| s * s).sum::<f64>() / v.len() as f64).sqrt();
    let within = |v: &[f64], k: f64| errors.iter().zip(v).filter(|(e, s)| e.abs() <= k * **s).count();
    println!("{records} records of {label}, σ = 0.01 rad, range 0.5..2 T");
    println!("mean relative error {mean:+.2e}, spread (sd) {spread:.2e}, rms {rms:.2e}");
    for (name, v) in [("robust", &robust), ("iid", &iid)] {
        let s = mean_of(v);
        println!(
            "{name}: rms reported σ_T/T {s:.2e}; spread / reported {:.2}; within 1σ {}, 2σ {} of {records}",
            spread / s,
            within(v, 1.0),
            within(v, 2.0),
        );
    }
    Ok(())
}

/// The contrast of the winner with noise on the angle, and with ranges that miss the truth.
fn contrast() -> Result<(), Box<dyn Error>> {
    let (t0, step, theta) = record(TAU, TAU / 25.0, 30_000)?;
    println!("| σ (rad) | range (× T) | outcome | contrast | residual |");
    println!("| --- | --- | --- | --- | --- |");
    for sigma in [0.0, 0.01, 0.05, 0.1, 0.2] {
        let x = Encoder::seeded(5).with_noise(sigma)?.observe(&theta);
        for (lo, hi) in [
            (0.5, 2.0),
            (1.005, 1.6),
            (1.05, 1.6),
            (1.2, 1.6),
            (0.7, 0.95),
            (0.3, 0.45),
        ] {
            let range = PeriodRange::periods(lo * TAU, hi * TAU)?;
            match estimate(&x, step, t0, Some(range)) {
                Ok((found, _)) => println!(
                    "| {sigma} | {lo}..{hi} | {:+.2e} ± {:.1e} | {:.2e} | {:.2e} |",
                    found.period / TAU - 1.0,
                    found.relative_uncertainty(),
                    found.contrast,
                    found.residual
                ),
                Err(e) => println!("| {sigma} | {lo}..{hi} | {e} | | |"),
            }
        }
    }
    Ok(())
}

/// Evaluations and time of the search's settings, and of a record of a million samples.
fn costs() -> Result<(), Box<dyn Error>> {
    let rig_ratio = 500.0 / 1.02;
    let rig = 1.0 / 1.02;
    println!("| record | setting | estimate / truth − 1 | evaluations | time (s) |");
    println!("| --- | --- | --- | --- | --- |");
    for (label, period, dt, samples) in [
        ("paper, 30000 at 25/period", TAU, TAU / 25.0, 30_000),
        (
            "490.196/period, 300 periods",
            rig,
            TAU / rig_ratio,
            (300.0 * rig_ratio) as usize,
        ),
        (
            "490.196/period, 2040 periods (10^6 samples)",
            rig,
            TAU / rig_ratio,
            1_000_000,
        ),
    ] {
        let (t0, step, theta) = record(period, dt, samples)?;
        let x: Vec<f64> = theta.iter().map(|&v| wrap(v)).collect();
        let range = PeriodRange::periods(0.5 * period, 2.0 * period)?;
        let base = || DriveSearch::builder().range(range);
        let settings = [
            (
                "defaults (growth 4, 3 survivors, 4 points per basin)",
                base().build()?,
            ),
            ("growth 2", base().growth(2).build()?),
            ("1 survivor", base().survivors(1).build()?),
            ("2 points per basin", base().points_per_basin(2).build()?),
            ("scan over 8 periods", base().scan_periods(8).build()?),
        ];
        for (name, search) in settings {
            match estimate_with(&x, step, t0, &search) {
                Ok((found, seconds)) => println!(
                    "| {label} | {name} | {:+.2e} | {} | {seconds:.3} |",
                    found.period / period - 1.0,
                    found.evaluations
                ),
                Err(e) => println!("| {label} | {name} | error: {e} | | |"),
            }
        }
        let noisy = Encoder::seeded(11).with_noise(0.01)?.observe(&theta);
        for (name, search) in [
            ("σ = 0.01 rad, defaults", base().build()?),
            ("σ = 0.01 rad, growth 2", base().growth(2).build()?),
            ("σ = 0.01 rad, 1 survivor", base().survivors(1).build()?),
        ] {
            let (found, seconds) = estimate_with(&noisy, step, t0, &search)?;
            println!(
                "| {label} | {name} | {:+.2e} ± {:.1e} | {} | {seconds:.3} |",
                found.period / period - 1.0,
                found.relative_uncertainty(),
                found.evaluations
            );
        }
        let clock = SampleClock::from_step(period * 1.0123, step)?;
        let start = Instant::now();
        let resampled = resample_to_whole(&x, &clock, Domain::Circle)?;
        println!(
            "| {label} | one resampling onto a whole grid ({} samples) | | | {:.3} |",
            resampled.samples.len(),
            start.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

fn main() -> Result<(), Box<dyn Error>> {
    match std::env::args().nth(1).as_deref() {
        Some("costs") => costs(),
        Some("contrast") => contrast(),
        Some("honesty") => honesty(std::env::args().nth(2).as_deref() == Some("rig")),
        _ => accuracy(),
    }
}
