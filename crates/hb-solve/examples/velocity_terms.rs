//! How well general terms come back, in both methods: a pendulum with Coulomb friction, quadratic
//! drag and a second drive harmonic, and a Duffing oscillator with the damping `x^2*x'`.
//!
//! Each true system is an `IdentifiedModel` with the general terms, simulated by DOP853
//! (`rtol = 1e-10`) at 25 and at 490 samples per forcing period for 1200 periods, observed exactly
//! and through a 4096-count encoder (the angle, or the displacement in steps of `2π / 4096`), and
//! identified with its own terms by the weak form on windows and by harmonic balance on the
//! close-return orbits, for several cuts of the velocity series.
//!
//! ```text
//! cargo run --release -p hb-solve --example velocity_terms [-- quick]
//! ```
//!
//! Prints the Markdown tables of `docs/identification.md`: the largest relative error of the
//! nonzero coefficients (and which), the largest absolute value of the zero ones, and the RMS error
//! of the velocity the nonlinear terms are evaluated at (over the windows, weighted by the window
//! `sin⁴`, relative to the RMS velocity).
#![allow(clippy::print_stdout)]

use std::error::Error;
use std::f64::consts::{PI, TAU};

use circle_signal::{Domain, SampleClock, Segment, unwrap, wrap};
use hb_basis::{BasisKind, Harmonic, Polynomial};
use hb_model::{Harmonics, IdentifiedModel, ModelForm, TermList};
use hb_solve::{
    Assembly, HarmonicBalance, IdentifyParams, QrSolver, VelocityTrend, WeakForm, identify, velocity_series,
};
use pendulum_sim::{SimulationConfig, Trajectory, simulate};
use upo_search::{CloseReturns, OrbitSource, Windows};

/// A true system: its terms, values, basis, domain and forcing period.
struct Truth {
    label: &'static str,
    terms: &'static str,
    values: Vec<f64>,
    basis: BasisKind,
    domain: Domain,
    period: f64,
}

fn systems() -> Result<Vec<Truth>, Box<dyn Error>> {
    let q = 1.0 / (0.8333f64 * 0.8333);
    Ok(vec![
        Truth {
            label: "pendulum, friction, drag, 2nd harmonic",
            terms: "x', sign(x'), x'*|x'|, {1, cos(t), sin(t), cos(2t), sin(2t)}*{cos(x), sin(x)}",
            // x', sign, drag; cos(x), sin(x); cos(t)*.., sin(t)*.., cos(2t)*.., sin(2t)*..
            values: vec![
                0.02, 0.03, 0.01, 0.0, q, 0.0, 0.0, -1.52, 0.0, 0.0, 0.0, -0.152, 0.0,
            ],
            basis: Harmonic::new(1)?.into(),
            domain: Domain::Circle,
            period: TAU,
        },
        Truth {
            label: "pendulum, drag only",
            terms: "x', x'*|x'|, {1, sin(t)}*{cos(x), sin(x)}",
            values: vec![0.02, 0.01, 0.0, q, -1.52, 0.0],
            basis: Harmonic::new(1)?.into(),
            domain: Domain::Circle,
            period: TAU,
        },
        Truth {
            label: "pendulum, friction only",
            terms: "x', sign(x'), {1, sin(t)}*{cos(x), sin(x)}",
            values: vec![0.02, 0.03, 0.0, q, -1.52, 0.0],
            basis: Harmonic::new(1)?.into(),
            domain: Domain::Circle,
            period: TAU,
        },
        Truth {
            label: "Duffing with x^2*x'",
            terms: "x', x^2*x', x, x^3, cos(t), sin(t)",
            values: vec![0.2, 0.05, -1.0, 1.0, -0.5, 0.0],
            basis: Polynomial::new(3)?.into(),
            domain: Domain::Line,
            period: TAU / 1.2,
        },
    ])
}

impl Truth {
    fn model(&self) -> Result<IdentifiedModel, Box<dyn Error>> {
        let form = ModelForm::from_terms(TermList::parse(self.terms)?);
        Ok(IdentifiedModel::new(
            self.basis,
            form,
            TAU / self.period,
            &self.values,
        )?)
    }
}

/// The trajectory at `p` samples per period.
fn record(truth: &Truth, p: usize, periods: usize) -> Result<Trajectory, Box<dyn Error>> {
    let config = SimulationConfig::paper()
        .with_drive_period(truth.period)?
        .with_samples_per_period(p)?
        .with_samples(p * periods)?;
    Ok(simulate(&truth.model()?, &config)?)
}

/// The record as observed: wrapped on the circle, quantised in steps of `2π / counts`.
fn observe(x: &[f64], domain: Domain, counts: Option<f64>) -> Vec<f64> {
    x.iter()
        .map(|&v| {
            let v = counts.map_or(v, |c| {
                let q = TAU / c;
                (v / q).round() * q
            });
            if domain == Domain::Circle { wrap(v) } else { v }
        })
        .collect()
}

/// Largest relative error of the nonzero coefficients (and its term), largest |zero coefficient|.
fn errors(truth: &Truth, model: &IdentifiedModel) -> (f64, String, f64) {
    let (mut rel, mut worst, mut abs) = (0.0f64, String::new(), 0.0f64);
    for (c, &want) in model.coefficients().iter().zip(&truth.values) {
        if want == 0.0 {
            abs = abs.max(c.value.abs());
        } else {
            let e = ((c.value - want) / want).abs();
            if e > rel {
                (rel, worst) = (e, c.name.clone());
            }
        }
    }
    (rel, worst, abs)
}

/// RMS of the velocity estimate's error over the windows, weighted by `sin⁴`, relative to the RMS
/// velocity.
fn velocity_error(
    x: &[f64],
    v: &[f64],
    segments: &[Segment],
    h: f64,
    cap: Harmonics,
    trend: VelocityTrend,
) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for s in segments {
        let window = &x[s.start()..=s.start() + s.len()];
        let Ok(est) = velocity_series(window, h, s.period(), cap.count(s.period(), s.len()), trend) else {
            return f64::NAN;
        };
        for (n, e) in est.iter().enumerate() {
            let w = (PI * n as f64 / s.len() as f64).sin().powi(4);
            let truth = v[s.start() + n];
            num += w * (e - truth) * (e - truth);
            den += w * truth * truth;
        }
    }
    (num / den).sqrt()
}

fn main() -> Result<(), Box<dyn Error>> {
    let quick = std::env::args().any(|a| a == "quick");
    let periods = if quick { 300 } else { 1200 };
    let caps: &[f64] = if quick {
        &[4.0, 8.0, 16.0, 64.0]
    } else {
        &[2.0, 4.0, 8.0, 16.0, 64.0]
    };
    println!(
        "| system | samples per period | angle | method | velocity harmonics | largest relative error (term) | largest zero coefficient | velocity RMS error |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- |");
    for truth in systems()? {
        for p in [25, 490] {
            let traj = record(&truth, p, periods)?;
            let (t0, x, v) = (traj.t[0], &traj.theta, &traj.omega);
            let clock = SampleClock::new(truth.period, p)?.with_start_time(t0)?;
            let h = clock.step();
            for (angle, counts) in [("exact", None), ("4096 counts", Some(4096.0))] {
                let observed = observe(x, truth.domain, counts);
                let continuous = match truth.domain {
                    Domain::Circle => unwrap(&observed),
                    Domain::Line => observed.clone(),
                };
                let windows = Windows::builder(&clock)
                    .domain(truth.domain)
                    .build()?
                    .segments(&observed)?;
                // The paper's delay (5 samples at 25 per period) in forcing periods.
                let delay = (5 * p).div_ceil(25);
                let tolerance = if truth.domain == Domain::Circle {
                    0.03
                } else {
                    0.02
                };
                let orbits = CloseReturns::builder(&clock, delay)
                    .domain(truth.domain)
                    .tolerance(tolerance)
                    .build()?
                    .segments(&observed)?;
                let methods: [(Box<dyn Assembly>, &[Segment]); 2] = [
                    (Box::new(WeakForm::default()), &windows),
                    (Box::new(HarmonicBalance), &orbits),
                ];
                for (method, segments) in &methods {
                    for &cap in caps {
                        let cap = Harmonics::DriveCap(cap);
                        let params = IdentifyParams::builder(clock)
                            .form(truth.model()?.form().clone())
                            .harmonics(method.default_harmonics())
                            .velocity_harmonics(cap)
                            .build()?;
                        let result = identify(
                            truth.basis,
                            &observed,
                            segments,
                            &params,
                            method.as_ref(),
                            &QrSolver::default(),
                        );
                        let trend = if method.name() == "upo" {
                            VelocityTrend::Line
                        } else {
                            VelocityTrend::Quintic
                        };
                        let verr = velocity_error(&continuous, v, segments, h, cap, trend);
                        let cap_name = match cap {
                            Harmonics::DriveCap(c) => format!("{c} W"),
                            other => format!("{other:?}"),
                        };
                        match result {
                            Ok(model) => {
                                let (rel, worst, abs) = errors(&truth, &model);
                                println!(
                                    "| {} | {p} | {angle} | {} ({} segments) | {cap_name} | {rel:.2e} (`{worst}`) | {abs:.2e} | {verr:.2e} |",
                                    truth.label,
                                    method.name(),
                                    segments.len()
                                );
                            }
                            Err(e) => println!(
                                "| {} | {p} | {angle} | {} | {cap_name} | {e} | | |",
                                truth.label,
                                method.name()
                            ),
                        }
                    }
                }
            }
        }
    }
    Ok(())
}
