//! `hbid simulate`: the paper's pendulum, sampled as an encoder would see it.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use npyz::WriterBuilder;
use pendulum_sim::observe::Encoder;
use pendulum_sim::{Pendulum, SimulationConfig, Tolerances, simulate_with_progress};

use crate::progress::Progress;

/// Simulate the base-excited pendulum x'' + c x' + (1/r²) sin x − f sin(t) cos x = 0 and write
/// `t,theta,omega`: CSV, or a samples × 3 `.npy` array of f8 when the file name ends in `.npy`.
/// The defaults are the paper's data set.
#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// Forcing amplitude f.
    #[arg(long, default_value_t = 1.52, allow_hyphen_values = true)]
    f: f64,
    /// Damping c.
    #[arg(long, default_value_t = 0.03, allow_hyphen_values = true)]
    c: f64,
    /// Frequency ratio r (the stiffness is 1/r²).
    #[arg(long, default_value_t = 0.8333, allow_hyphen_values = true)]
    r: f64,
    /// Samples written.
    #[arg(long, default_value_t = 30_000)]
    samples: usize,
    /// Samples per forcing period (2π).
    #[arg(long, default_value_t = 25)]
    samples_per_period: usize,
    /// Forcing periods integrated and dropped before the first sample.
    #[arg(long, default_value_t = 200)]
    transient_periods: usize,
    /// Initial angle at t = 0.
    #[arg(long, default_value_t = 0.1, allow_hyphen_values = true)]
    theta0: f64,
    /// Initial angular velocity at t = 0.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    omega0: f64,
    /// Standard deviation (radians) of Gaussian noise added to theta before wrapping; omega stays clean.
    #[arg(long, value_name = "SIGMA", allow_hyphen_values = true)]
    noise: Option<f64>,
    /// Seed of the noise generator (ChaCha8).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Write the continuous angle instead of wrapping it into [-π, π).
    #[arg(long)]
    unwrapped: bool,
    /// Relative tolerance of the integrator (the absolute one is rtol/10).
    #[arg(long, default_value_t = 1e-10, allow_hyphen_values = true)]
    rtol: f64,
    /// Output file: `.npy` (samples × 3, f8, columns t, theta, omega) or CSV (anything else).
    #[arg(long)]
    out: PathBuf,
}

pub fn run(args: &SimulateArgs, quiet: bool) -> anyhow::Result<()> {
    let pendulum = Pendulum::new(args.f, args.c, args.r)?;
    let config = SimulationConfig::paper()
        .with_samples(args.samples)?
        .with_samples_per_period(args.samples_per_period)?
        .with_transient_periods(args.transient_periods)
        .with_initial(args.theta0, args.omega0)?
        .with_tolerances(Tolerances::relative(args.rtol)?);
    let encoder = match args.noise {
        None => None,
        Some(s) => Some(Encoder::seeded(args.seed).with_noise(s).context("--noise")?),
    };
    crate::output::check_output_path(&args.out)?;

    let bar = Progress::new("simulate", args.samples as u64, quiet);
    let mut traj = simulate_with_progress(&pendulum, &config, |done, _| bar.set(done as u64))?;
    bar.finish();
    if let Some(encoder) = encoder {
        traj.theta = encoder.observe_continuous(&traj.theta);
    }
    let wrap = !args.unwrapped;
    let npy = args
        .out
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("npy"));
    if npy {
        return crate::output::write_atomically(&args.out, |w: &mut dyn Write| {
            let mut writer = npyz::WriteOptions::<f64>::new()
                .default_dtype()
                .shape(&[traj.t.len() as u64, 3])
                .writer(w)
                .begin_nd()?;
            for ((t, x), v) in traj.t.iter().zip(&traj.theta).zip(&traj.omega) {
                let x = if wrap { circle_signal::wrap(*x) } else { *x };
                writer.extend([*t, x, *v])?;
            }
            writer.finish()
        })
        .map_err(Into::into);
    }
    crate::output::write_atomically(&args.out, |w: &mut dyn Write| {
        writeln!(w, "t,theta,omega")?;
        for ((t, x), v) in traj.t.iter().zip(&traj.theta).zip(&traj.omega) {
            let x = if wrap { circle_signal::wrap(*x) } else { *x };
            writeln!(w, "{t},{x},{v}")?;
        }
        Ok(())
    })
    .map_err(Into::into)
}
