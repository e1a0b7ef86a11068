//! How the identification error on the paper's data set moves with the harmonics per orbit `M` and
//! the close-return tolerance `e`.
//!
//! ```text
//! cargo run --release -p hb-solve --example sweep [-- path/to/paper_dataset.csv]
//! ```
//!
//! Prints Markdown tables (the ones in `docs/identification.md`).
#![allow(clippy::print_stdout)]

use std::error::Error;
use std::f64::consts::{PI, TAU};

use circle_signal::SampleClock;
use hb_basis::{Basis, Harmonic, Hat};
use hb_model::{Harmonics, IdentifiedModel};
use hb_solve::{IdentifyParams, QrSolver, identify};
use pendulum_sim::observe::{Encoder, NormalDraw};
use upo_search::{CloseReturns, Domain, OrbitSource, Segment};

#[path = "../tests/common/mod.rs"]
mod common;
use common::{read_dataset, truth};

/// Quadrature points of the L2 projections of the true curves onto the hats.
const PROJECTION_POINTS: usize = 4096;

/// RMS over the circle of the difference between the model's curve and the projected curve.
fn curve_rms(hat: &Hat, model: &IdentifiedModel<Hat>, which: usize, reference: &[f64]) -> f64 {
    let grid = 2048;
    let mut phi = vec![0.0; hat.len()];
    let mut sum = 0.0;
    for s in 0..grid {
        let x = -PI + TAU * (s as f64 + 0.5) / grid as f64;
        hat.eval(x, &mut phi);
        let want: f64 = phi.iter().zip(reference).map(|(p, r)| p * r).sum();
        let got = match which {
            0 => model.autonomous(x),
            _ => model.parametric(x).1,
        };
        sum += (got - want).powi(2);
    }
    (sum / grid as f64).sqrt()
}

fn segments(x: &[f64], e: f64) -> Result<Vec<Segment>, Box<dyn Error>> {
    let search = CloseReturns::builder(&upo_search::SampleClock::nondimensional(25)?, 5)
        .tolerance(e)
        .max_period(16)
        .dimension(2)
        .domain(Domain::Circle)
        .build()?;
    Ok(search.segments(x)?)
}

/// Largest absolute coefficient error of the K = 1 model, and the term.
fn worst(m: &IdentifiedModel<Harmonic>, truth: &IdentifiedModel<Harmonic>) -> (String, f64) {
    truth
        .coefficients()
        .iter()
        .map(|t| {
            (
                &t.name,
                (m.coefficient(&t.name).map_or(f64::NAN, |c| c.value) - t.value).abs(),
            )
        })
        .fold(
            (String::new(), 0.0),
            |acc, (n, e)| if e > acc.1 { (n.clone(), e) } else { acc },
        )
}

fn label(h: Harmonics) -> String {
    match h {
        Harmonics::Fixed(m) => format!("M = {m}"),
        Harmonics::DriveCap(c) => format!("j/k <= {c}"),
        _ => format!("{h:?}"),
    }
}

fn main() -> Result<(), Box<dyn Error>> {
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| common::PAPER_DATASET.to_owned());
    let (t0, x) = read_dataset(&path)?;
    let clock = SampleClock::nondimensional(25)?.with_start_time(t0)?;
    let solver = QrSolver::default();
    let hat = Hat::new(8)?;
    let k1 = Harmonic::new(1)?;
    let truth = truth();
    let q_ref = hat.project(PROJECTION_POINTS, |x| truth.autonomous(x))?;
    let p_ref = hat.project(PROJECTION_POINTS, |x| truth.parametric(x).1)?;
    let params = |h: Harmonics| IdentifyParams::builder(clock).harmonics(h).build();

    let policies: Vec<Harmonics> = [1usize, 2, 3, 6, 12, 24]
        .iter()
        .map(|&m| Harmonics::Fixed(m))
        .chain([1.0, 2.0, 3.0, 6.0].iter().map(|&c| Harmonics::DriveCap(c)))
        .collect();

    let segs = segments(&x, 0.03)?;
    println!("\n### Harmonics per orbit, e = 3 % ({} segments)\n", segs.len());
    println!(
        "| harmonics | rows | c_r (K=1) | max coef. error (K=1) | worst term | cond. | c_r (hat 8) | q curve RMS | p curve RMS |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for &h in &policies {
        let m = identify(k1, &x, &segs, &params(h)?, &hb_solve::HarmonicBalance, &solver)?;
        let (term, err) = worst(&m, &truth);
        let s = m.summary().ok_or("no summary")?;
        let mh = identify(hat, &x, &segs, &params(h)?, &hb_solve::HarmonicBalance, &solver)?;
        println!(
            "| {} | {} | {:.4} | {:.4} | `{term}` | {:.1} | {:.4} | {:.3} | {:.3} |",
            label(h),
            s.rows,
            m.damping(),
            err,
            s.condition,
            mh.damping(),
            curve_rms(&hat, &mh, 0, &q_ref),
            curve_rms(&hat, &mh, 1, &p_ref)
        );
    }

    println!("\n### Close-return tolerance e\n");
    println!(
        "| e | segments | c_r, default | max error, default | c_r, M = 12 | max error, M = 12 | c_r (hat 8), default | q, p curve RMS (hat 8) |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- |");
    for &e in &[0.01, 0.02, 0.03, 0.04, 0.05] {
        let segs = segments(&x, e)?;
        let d = identify(
            k1,
            &x,
            &segs,
            &params(Harmonics::DEFAULT)?,
            &hb_solve::HarmonicBalance,
            &solver,
        )?;
        let f = identify(
            k1,
            &x,
            &segs,
            &params(Harmonics::Fixed(12))?,
            &hb_solve::HarmonicBalance,
            &solver,
        )?;
        let h = identify(
            hat,
            &x,
            &segs,
            &params(Harmonics::DEFAULT)?,
            &hb_solve::HarmonicBalance,
            &solver,
        )?;
        println!(
            "| {:.0} % | {} | {:.4} | {:.4} | {:.4} | {:.4} | {:.4} | {:.3}, {:.3} |",
            e * 100.0,
            segs.len(),
            d.damping(),
            worst(&d, &truth).1,
            f.damping(),
            worst(&f, &truth).1,
            h.damping(),
            curve_rms(&hat, &h, 0, &q_ref),
            curve_rms(&hat, &h, 1, &p_ref)
        );
    }

    println!("\n### Gaussian noise on the angle, e = 3 % (max coefficient error, K = 1)\n");
    let sigmas = [0.005, 0.01, 0.02];
    let noisy_sets: Vec<(Vec<f64>, Vec<Segment>)> = sigmas
        .iter()
        .map(|&s| {
            // Box-Muller, the draw the table in docs/identification.md was made with.
            let xn = Encoder::seeded(7)
                .with_noise(s)?
                .with_draw(NormalDraw::BoxMuller)
                .observe(&x);
            let sg = segments(&xn, 0.03)?;
            Ok((xn, sg))
        })
        .collect::<Result<_, Box<dyn Error>>>()?;
    print!("| harmonics |");
    for ((_, sg), s) in noisy_sets.iter().zip(sigmas) {
        print!(" sigma = {s} rad ({} segments) |", sg.len());
    }
    println!("\n| --- |{}", " --- |".repeat(sigmas.len()));
    for &h in &policies {
        print!("| {} |", label(h));
        for (xn, sg) in &noisy_sets {
            match identify(k1, xn, sg, &params(h)?, &hb_solve::HarmonicBalance, &solver) {
                Ok(m) => print!(" {:.4} (c_r {:.4}) |", worst(&m, &truth).1, m.damping()),
                Err(e) => print!(" {e} |"),
            }
        }
        println!();
    }
    Ok(())
}
