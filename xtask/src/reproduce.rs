//! `cargo xtask reproduce`: the paper end to end, and its report.

use std::fmt::Write as _;
use std::path::Path;
use std::time::{Duration, Instant};

use anyhow::Context;
use circle_signal::wrap;
use indicatif::{ProgressBar, ProgressStyle};
use pendulum_sim::{
    LyapunovConfig, Pendulum, SimulationConfig, largest_lyapunov, poincare_section, simulate,
};

use crate::plot::{BLUE, Figure, GREY, Series, Style};

/// Sizes of a run.
struct Plan {
    samples: usize,
    section_points: usize,
    lyapunov_periods: usize,
}

impl Plan {
    fn new(quick: bool) -> Self {
        if quick {
            Self {
                samples: 6_000,
                section_points: 400,
                lyapunov_periods: 200,
            }
        } else {
            Self {
                samples: 30_000,
                section_points: 4_000,
                lyapunov_periods: 5_000,
            }
        }
    }
}

/// Wall time of each stage, for the report.
#[derive(Default)]
struct Timings(Vec<(&'static str, Duration)>);

impl Timings {
    /// Runs `work` as a stage with a spinner on stderr and records its wall time.
    fn stage<T>(
        &mut self,
        name: &'static str,
        work: impl FnOnce(&ProgressBar) -> anyhow::Result<T>,
    ) -> anyhow::Result<T> {
        let bar = ProgressBar::new_spinner();
        bar.set_style(ProgressStyle::with_template("{spinner} {msg} ({elapsed})").expect("valid template"));
        bar.set_message(name);
        bar.enable_steady_tick(Duration::from_millis(120));
        let start = Instant::now();
        let out = work(&bar).with_context(|| format!("stage '{name}'"))?;
        let took = start.elapsed();
        bar.finish_and_clear();
        eprintln!("{name:<28} {:>8.3} s", took.as_secs_f64());
        self.0.push((name, took));
        Ok(out)
    }
}

pub fn run(out: &Path, quick: bool) -> anyhow::Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let plan = Plan::new(quick);
    let mut times = Timings::default();
    let mut report = String::new();
    let mut figures = Vec::new();
    let pendulum = Pendulum::paper();

    // 1. The data set, as hbid's defaults make it.
    let config = SimulationConfig::paper().with_samples(plan.samples)?;
    let trajectory = times.stage("simulate data set", |_| Ok(simulate(&pendulum, &config)?))?;
    let x = trajectory.wrapped();

    // 2. The original system's Poincaré section and Lyapunov exponent, the reference for validation.
    let section_cfg = SimulationConfig::paper().with_samples(plan.section_points)?;
    let section = times.stage("Poincaré section (truth)", |_| {
        Ok(poincare_section(&pendulum, &section_cfg)?)
    })?;
    let lyap_cfg = LyapunovConfig::default().with_periods(plan.lyapunov_periods)?;
    let lyapunov = times.stage("Lyapunov exponent (truth)", |bar| {
        bar.set_length(plan.lyapunov_periods as u64);
        Ok(largest_lyapunov(&pendulum, &lyap_cfg, |done, _| {
            bar.set_position(done as u64)
        })?)
    })?;

    // Figures.
    times.stage("figures", |_| {
        let delay = 5;
        let phase_plane: Vec<(f64, f64)> = x.iter().zip(&x[delay..]).map(|(&a, &b)| (a, b)).collect();
        let name = "fig2a_reconstructed_phase_plane.png";
        Figure {
            title: "Reconstructed phase plane, delay 5 (paper Fig. 2a)",
            x_label: "theta(t)",
            y_label: "theta(t + 5 dt)",
            series: vec![Series {
                label: "",
                points: phase_plane,
                style: Style::Dots(1),
                color: BLUE,
            }],
            x_range: Some((-std::f64::consts::PI, std::f64::consts::PI)),
            y_range: Some((-std::f64::consts::PI, std::f64::consts::PI)),
        }
        .save(&out.join(name))?;
        figures.push((
            name,
            "Reconstructed phase plane of the wrapped angle, delay 5 samples (paper Fig. 2a).",
        ));

        let name = "fig2b_poincare_section.png";
        Figure {
            title: "Poincaré section at t = 0 mod 2π (paper Fig. 2b)",
            x_label: "theta (wrapped)",
            y_label: "theta'",
            series: vec![Series {
                label: "",
                points: section.iter().map(|p| (wrap(p[0]), p[1])).collect(),
                style: Style::Dots(1),
                color: BLUE,
            }],
            x_range: Some((-std::f64::consts::PI, std::f64::consts::PI)),
            y_range: None,
        }
        .save(&out.join(name))?;
        figures.push((name, "Poincaré section of the true pendulum (paper Fig. 2b)."));

        let name = "fig_time_series.png";
        let shown = 25 * 40;
        Figure {
            title: "The record as an encoder reports it (first 40 forcing periods)",
            x_label: "t",
            y_label: "theta (wrapped)",
            series: vec![Series {
                label: "",
                points: trajectory
                    .t
                    .iter()
                    .zip(&x)
                    .take(shown)
                    .map(|(&t, &v)| (t, v))
                    .collect(),
                style: Style::Line {
                    break_above: std::f64::consts::PI,
                },
                color: GREY,
            }],
            x_range: None,
            y_range: Some((-std::f64::consts::PI, std::f64::consts::PI)),
        }
        .save(&out.join(name))?;
        figures.push((name, "The wrapped angle record, first 40 forcing periods."));
        Ok(())
    })?;

    // The report.
    writeln!(report, "# Reproduction of Liang & Feeny, base-excited pendulum\n")?;
    writeln!(
        report,
        "Generated by `cargo xtask reproduce{}` (release build). Every number and figure below is computed \
         by this run from nothing.\n",
        if quick { " --quick" } else { "" }
    )?;
    writeln!(report, "## The data set\n")?;
    writeln!(
        report,
        "x'' + c x' + (1/r²) sin x − f sin(t) cos x = 0 with f = 1.52, c = 0.03, r = 0.8333; {} samples at 25 per \
         forcing period after 200 periods of transient from θ(0) = 0.1, θ'(0) = 0; DOP853 at rtol 1e-10; θ wrapped \
         into [−π, π). The paper used 30000 samples at the same rate.\n",
        plan.samples
    )?;
    writeln!(report, "## The true system, for validation\n")?;
    writeln!(report, "| quantity | value |\n| --- | --- |")?;
    writeln!(
        report,
        "| largest Lyapunov exponent (tangent-linear, {} forcing periods after 200 of transient) | {:.4} ± {:.4} per unit t ({:.3} per forcing period) |",
        lyapunov.periods, lyapunov.per_unit_time, lyapunov.standard_error, lyapunov.per_period
    )?;
    writeln!(report, "| Poincaré section points | {} |\n", section.len())?;
    writeln!(report, "## Figures\n")?;
    for (file, caption) in &figures {
        writeln!(report, "![{caption}]({file})\n\n{caption}\n")?;
    }
    writeln!(report, "## Wall time of each stage\n")?;
    writeln!(report, "| stage | seconds |\n| --- | --- |")?;
    for (name, took) in &times.0 {
        writeln!(report, "| {name} | {:.3} |", took.as_secs_f64())?;
    }
    let total: f64 = times.0.iter().map(|(_, d)| d.as_secs_f64()).sum();
    writeln!(report, "| total | {total:.3} |")?;
    let path = out.join("README.md");
    std::fs::write(&path, report).with_context(|| format!("cannot write {}", path.display()))?;
    eprintln!("report written to {}", path.display());
    Ok(())
}
