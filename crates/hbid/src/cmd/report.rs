//! `hbid report`: embed → orbits → identify → validate on the user's own record, as a Markdown
//! report with figures.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Args;
use embedding::{FnnParams, false_nearest_neighbours};
use hbid::plot::{BLUE, Figure, GREY, ORANGE, RED, Series, Style, add_figure};
use pendulum_sim::{CheckConfig, SimulationConfig, StateSpace, check_model, energy_distance, simulate};
use upo_search::{CloseReturns, Metric};

use super::data::{Data, Signal};
use super::identify::{IdentifyArgs, json};
use crate::progress::Progress;

/// Options of `hbid report`.
#[derive(Debug, Args)]
pub struct ReportArgs {
    #[command(flatten)]
    pub identify: IdentifyArgs,
    /// Folder of the report (created if missing; README.md, figures and the model go there).
    #[arg(long)]
    pub out: PathBuf,
    /// Forcing periods simulated for each model's Poincaré section and Lyapunov exponent.
    #[arg(long, default_value_t = 2000)]
    pub validation_periods: usize,
}

/// Delay-coordinate section of a wrapped or linear record: `(x_n, x_{n+delay})` at the samples
/// `n ≡ offset (mod P)`, embedded for the energy distance (`(cos, sin)` of each angle, or the raw
/// pair on the line).
fn delay_section(
    x: &[f64],
    p: usize,
    offset: usize,
    delay: usize,
    signal: Signal,
) -> (Vec<(f64, f64)>, Vec<[f64; 4]>) {
    let pairs: Vec<(f64, f64)> = (offset..x.len().saturating_sub(delay))
        .step_by(p.max(1))
        .map(|n| (x[n], x[n + delay]))
        .collect();
    let embedded = pairs
        .iter()
        .map(|&(a, b)| match signal {
            Signal::Circle => [a.cos(), a.sin(), b.cos(), b.sin()],
            Signal::Line => [a, b, 0.0, 0.0],
        })
        .collect();
    (pairs, embedded)
}

pub fn run(args: &ReportArgs, quiet: bool) -> anyhow::Result<()> {
    std::fs::create_dir_all(&args.out).with_context(|| format!("cannot create {}", args.out.display()))?;
    if args.validation_periods < 10 {
        anyhow::bail!(
            "--validation-periods {} must be at least 10",
            args.validation_periods
        );
    }
    let id = &args.identify;
    let stage = |name: &str| Progress::spinner(name, quiet);

    let bar = stage("read");
    let data = id.input.load()?;
    bar.finish();
    let setup = id.setup(&data)?;

    let bar = stage("embed");
    let metric = super::embed::metric_for(data.signal, None);
    let (ami, ami_delay) = super::embed::ami(&data.x, metric, 16, 40)?;
    let delay = id.delay.unwrap_or(ami_delay);
    let fnn = false_nearest_neighbours(&data.x, &FnnParams::new(metric, delay)?.with_max_dim(8)?)?;
    bar.finish();

    let bar = stage("orbits");
    let search = CloseReturns::builder(data.p, delay)
        .tolerance(id.tolerance)
        .max_period(id.max_period)
        .dimension(id.dim)
        .metric(match data.signal {
            Signal::Circle => Metric::Circle,
            Signal::Line => Metric::Linear,
        })
        .build()?;
    let catalogue = search.catalogue(&data.x)?;
    bar.finish();

    let bar = stage("identify");
    let model = hb_solve::identify(
        setup.basis,
        &data.x,
        catalogue.segments(),
        &setup.params,
        setup.solver.as_ref(),
    )
    .map_err(|e| anyhow::anyhow!("{e}"))
    .with_context(|| format!("{} orbit segments found", catalogue.segments().len()))?;
    bar.finish();

    let bar = stage("validate");
    let space = match data.signal {
        Signal::Circle => StateSpace::Circle,
        Signal::Line => StateSpace::Line,
    };
    let t_period = id.input.forcing_period;
    let x0 = data.x[0];
    let check = check_model(
        &model,
        &CheckConfig::new(t_period, space, args.validation_periods, args.validation_periods)?
            .with_initial(x0, 0.0)?,
    )?;
    // The model sampled like the data, for a section in the same delay coordinates.
    let sim_cfg = SimulationConfig::paper()
        .with_forcing_period(t_period)?
        .with_samples_per_period(data.p)?
        .with_samples((args.validation_periods * data.p).min(data.x.len().max(50 * data.p)))?
        .with_initial(x0, 0.0)?;
    let sim = simulate(&model, &sim_cfg)?;
    let sim_x: Vec<f64> = match data.signal {
        Signal::Circle => sim.wrapped(),
        Signal::Line => sim.theta.clone(),
    };
    bar.finish();

    // The data's samples at the forcing's phase 0: t0 + offset·dt ≡ 0 (mod T).
    let offset = ((-data.t0).rem_euclid(t_period) / data.dt).round() as usize % data.p;
    let (data_pairs, data_embedded) = delay_section(&data.x, data.p, offset, delay, data.signal);
    let (model_pairs, model_embedded) = delay_section(&sim_x, data.p, 0, delay, data.signal);
    let half = data_embedded.len() / 2;
    let distance = energy_distance(&data_embedded, &model_embedded);
    let floor = energy_distance(&data_embedded[..half], &data_embedded[half..]);

    write_report(
        args,
        &data,
        &ami.values,
        delay,
        &fnn,
        &catalogue,
        &model,
        &setup.basis_name,
        &check,
        distance,
        floor,
        &data_pairs,
        &model_pairs,
    )
}

#[allow(clippy::too_many_arguments)]
fn write_report(
    args: &ReportArgs,
    data: &Data,
    ami: &[f64],
    delay: usize,
    fnn: &embedding::FnnResult,
    catalogue: &upo_search::Catalogue,
    model: &hb_solve::IdentifiedModel,
    basis: &str,
    check: &pendulum_sim::ModelCheck,
    distance: Option<f64>,
    floor: Option<f64>,
    data_pairs: &[(f64, f64)],
    model_pairs: &[(f64, f64)],
) -> anyhow::Result<()> {
    let out = &args.out;
    let mut r = String::new();
    let mut figures: Vec<(String, String)> = Vec::new();
    writeln!(
        r,
        "# Identification report: {}\n",
        args.identify.input.file.display()
    )?;
    writeln!(
        r,
        "{}; forcing period {}.\n",
        data.summary(),
        args.identify.input.forcing_period
    )?;

    writeln!(r, "## Delay and embedding\n")?;
    writeln!(
        r,
        "Delay (first minimum of the average mutual information, 16 boxes): **{delay}** samples."
    )?;
    match fnn.minimum_dimension() {
        Some(d) => writeln!(
            r,
            "Embedding dimension (false nearest neighbours below {}): **{d}**.\n",
            fnn.fraction_threshold
        )?,
        None => writeln!(
            r,
            "No embedding dimension up to {} brings false neighbours below {}.\n",
            fnn.levels.len(),
            fnn.fraction_threshold
        )?,
    }
    writeln!(r, "| d | false neighbours |\n| --- | --- |")?;
    for l in &fnn.levels {
        writeln!(r, "| {} | {:.4} |", l.dim, l.fraction())?;
    }
    writeln!(r)?;
    let ami_pts: Vec<(f64, f64)> = ami
        .iter()
        .enumerate()
        .skip(1)
        .map(|(l, &v)| (l as f64, v))
        .collect();
    Figure {
        title: "Average mutual information",
        x_label: "lag (samples)",
        y_label: "I (nats)",
        series: vec![
            Series {
                label: "AMI",
                points: ami_pts,
                style: Style::Line {
                    break_above: f64::INFINITY,
                },
                color: BLUE,
            },
            Series {
                label: "delay",
                points: vec![(delay as f64, ami.get(delay).copied().unwrap_or(0.0))],
                style: Style::Dots(6),
                color: RED,
            },
        ],
        x_range: None,
        y_range: None,
    }
    .save(&out.join("ami.png"))?;
    add_figure(
        &mut figures,
        "ami.png",
        "Average mutual information against lag (from lag 1), the delay marked.",
    );
    Figure {
        title: "False nearest neighbours",
        x_label: "embedding dimension",
        y_label: "fraction",
        series: vec![Series {
            label: "",
            points: fnn.levels.iter().map(|l| (l.dim as f64, l.fraction())).collect(),
            style: Style::Line {
                break_above: f64::INFINITY,
            },
            color: BLUE,
        }],
        x_range: None,
        y_range: Some((0.0, 1.05)),
    }
    .save(&out.join("fnn.png"))?;
    add_figure(
        &mut figures,
        "fnn.png",
        "Fraction of false nearest neighbours against the embedding dimension.",
    );

    writeln!(r, "## Periodic orbits (close returns)\n")?;
    writeln!(
        r,
        "Tolerance {} of the span (ε = {:.4}), delay vectors of dimension {}.\n",
        args.identify.tolerance,
        catalogue.tolerance(),
        args.identify.dim
    )?;
    writeln!(r, "| period | segments | distinct orbits |\n| --- | --- | --- |")?;
    for c in catalogue.counts() {
        writeln!(r, "| {} | {} | {} |", c.period, c.segments, c.orbits)?;
    }
    writeln!(r)?;

    writeln!(
        r,
        "## Identified model (harmonic balance on the orbits, basis {basis})\n"
    )?;
    let j = json(model, "upo", basis);
    writeln!(
        r,
        "{} orbit segments, {} equations, condition number {:.3e}, residual RMS {:.3e}. The standard errors treat the \
         equations as independent: read them as lower bounds.\n",
        j["orbits_used"],
        j["rows"],
        j["condition_number"].as_f64().unwrap_or(f64::NAN),
        j["residual_rms"].as_f64().unwrap_or(f64::NAN)
    )?;
    writeln!(r, "| term | coefficient | std. error |\n| --- | --- | --- |")?;
    for c in model.coefficients() {
        writeln!(r, "| `{}` | {:.6} | {:.2e} |", c.name, c.value, c.std_error)?;
    }
    writeln!(r)?;
    let model_file = "model.json";
    std::fs::write(out.join(model_file), model.to_json()?).context("saving the model")?;
    writeln!(
        r,
        "The model is saved as `{model_file}` (load it with `hb_solve::IdentifiedModel::from_json`).\n"
    )?;

    writeln!(r, "## Does the model behave like the record?\n")?;
    writeln!(r, "| quantity | value |\n| --- | --- |")?;
    let fmt = |v: Option<f64>| v.map_or("n/a".to_owned(), |v| format!("{v:.2e}"));
    writeln!(
        r,
        "| energy distance, record vs model, sections in delay coordinates at the forcing's phase 0 | {} |",
        fmt(distance)
    )?;
    writeln!(
        r,
        "| the same between the two halves of the record (the floor: what one attractor gives) | {} |",
        fmt(floor)
    )?;
    writeln!(
        r,
        "| largest Lyapunov exponent of the model (per unit time) | {:.4} ± {:.4} |",
        check.lyapunov.per_unit_time, check.lyapunov.standard_error
    )?;
    writeln!(
        r,
        "| fraction of forcing periods the model whirls | {:.3} |",
        check.whirling
    )?;
    let orbits: Vec<String> = check
        .orbits
        .iter()
        .map(|o| format!("{:.4} ({})", o.x, o.winding))
        .collect();
    writeln!(
        r,
        "| the model's period-1 orbits at phase 0: x (winding) | {} |\n",
        if orbits.is_empty() {
            "none found".to_owned()
        } else {
            orbits.join(", ")
        }
    )?;
    writeln!(
        r,
        "A distance of the order of the floor means the model's attractor cannot be told from the record's with this many points.\n"
    )?;

    let (range, label) = match data.signal {
        Signal::Circle => (Some((-std::f64::consts::PI, std::f64::consts::PI)), "x (wrapped)"),
        Signal::Line => (None, "x"),
    };
    let y_label = format!("x(t + {delay} dt)");
    for (file, title, pts, color) in [
        (
            "section_record.png",
            "Record: section in delay coordinates",
            data_pairs,
            GREY,
        ),
        (
            "section_model.png",
            "Model: section in delay coordinates",
            model_pairs,
            ORANGE,
        ),
    ] {
        Figure {
            title,
            x_label: label,
            y_label: &y_label,
            series: vec![Series {
                label: "",
                points: pts.to_vec(),
                style: Style::Dots(2),
                color,
            }],
            x_range: range,
            y_range: range,
        }
        .save(&out.join(file))?;
        add_figure(
            &mut figures,
            file,
            format!("{title}, once per forcing period at phase 0."),
        );
    }
    writeln!(r, "## Figures\n")?;
    for (file, caption) in &figures {
        writeln!(r, "![{caption}]({file})\n\n{caption}\n")?;
    }
    let path = out.join("README.md");
    crate::output::write_atomically(&path, |w| w.write_all(r.as_bytes()))?;
    eprintln!("report written to {}", path.display());
    Ok(())
}

/// The report's figures need a folder; checked before any work.
pub fn check_out(path: &Path) -> anyhow::Result<()> {
    if path.exists() && !path.is_dir() {
        anyhow::bail!("--out {} exists and is not a folder", path.display());
    }
    Ok(())
}
