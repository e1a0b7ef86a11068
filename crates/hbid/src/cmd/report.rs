//! `hbid report`: embed → orbits → identify (both methods) → validate on the user's own record,
//! as a Markdown report with figures.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Args;
use embedding::{AmiParams, FnnParams, FnnResult, false_nearest_neighbours};
use hbid::plot::{BLUE, Figure, GREY, ORANGE, RED, Series, Style, add_figure};
use pendulum_sim::{
    CheckConfig, Domain, ModelCheck, SimulationConfig, check_model, energy_distance, simulate,
};
use upo_search::Catalogue;

use super::data::{Data, ami};
use super::identify::{Identification, IdentifyArgs, Method, json};
use crate::progress::Progress;

/// Options of `hbid report`.
#[derive(Debug, Args)]
pub struct ReportArgs {
    #[command(flatten)]
    pub identify: IdentifyArgs,
    /// Folder of the report (created if missing; README.md, figures and the models go there).
    #[arg(long)]
    pub out: PathBuf,
    /// Forcing periods simulated for each model's Poincaré section and Lyapunov exponent.
    #[arg(long, default_value_t = 2000)]
    pub validation_periods: usize,
}

/// One method's identification and its checks.
struct MethodResult {
    method: Method,
    basis: String,
    ident: Identification,
    check: ModelCheck,
    /// The model's delay-coordinate section and its energy distance to the record's.
    section: Vec<(f64, f64)>,
    distance: Option<f64>,
}

/// What the report shows of the record itself.
struct RecordFacts<'a> {
    data: &'a Data,
    ami: Vec<f64>,
    delay: usize,
    fnn: FnnResult,
    catalogue: Catalogue,
    section: Vec<(f64, f64)>,
    floor: Option<f64>,
}

/// Delay-coordinate section of a wrapped or linear record: `(x_n, x_{n+delay})` at the samples
/// `n ≡ offset (mod P)`, and its embedding for the energy distance (`(cos, sin)` of each angle, or
/// the raw pair on the line).
fn delay_section(
    x: &[f64],
    p: usize,
    offset: usize,
    delay: usize,
    domain: Domain,
) -> (Vec<(f64, f64)>, Vec<[f64; 4]>) {
    let pairs: Vec<(f64, f64)> = (offset..x.len().saturating_sub(delay))
        .step_by(p.max(1))
        .map(|n| (x[n], x[n + delay]))
        .collect();
    let embedded = pairs
        .iter()
        .map(|&(a, b)| match domain {
            Domain::Circle => [a.cos(), a.sin(), b.cos(), b.sin()],
            Domain::Line => [a, b, 0.0, 0.0],
        })
        .collect();
    (pairs, embedded)
}

/// The report's figures need a folder; checked before any work.
pub fn check_out(path: &Path) -> anyhow::Result<()> {
    if path.exists() && !path.is_dir() {
        anyhow::bail!("--out {} exists and is not a folder", path.display());
    }
    Ok(())
}

pub fn run(args: &ReportArgs, quiet: bool) -> anyhow::Result<()> {
    if args.validation_periods < 10 {
        anyhow::bail!(
            "--validation-periods {} must be at least 10",
            args.validation_periods
        );
    }
    std::fs::create_dir_all(&args.out).with_context(|| format!("cannot create {}", args.out.display()))?;
    let id = &args.identify;
    let stage = |name: &str| Progress::spinner(name, quiet);

    let bar = stage("read");
    let data = id.input.load()?;
    // Check every option before the work.
    id.setup_for(&data, Method::Upo)?;
    bar.finish();

    let bar = stage("embed");
    let metric = data.domain;
    let (ami, ami_delay) = ami(&data.x, &AmiParams::new(metric))?;
    let delay = id.search.delay.unwrap_or(ami_delay);
    let fnn = false_nearest_neighbours(&data.x, &FnnParams::new(metric, delay)?.with_max_dim(8)?)?;
    bar.finish();

    let bar = stage("orbits");
    let catalogue = id.search.close_returns(&data, delay)?.catalogue(&data.x)?;
    bar.finish();

    // The record's own section at the forcing's phase 0 (t0 + offset·dt ≡ 0 mod T), and the
    // distance between its two halves: what one attractor gives.
    let t_period = id.input.forcing_period;
    let offset =
        ((-data.clock.start_time()).rem_euclid(t_period) / data.clock.step()).round() as usize % data.p;
    let (section, embedded) = delay_section(&data.x, data.p, offset, delay, data.domain);
    let half = embedded.len() / 2;
    let floor = energy_distance(&embedded[..half], &embedded[half..]);

    let space = data.domain;
    let x0 = data.x[0];
    let mut results = Vec::new();
    for method in [Method::Upo, Method::Windowed] {
        let bar = stage(&format!("identify ({})", method.name()));
        let setup = id.setup_for(&data, method)?;
        let segments = id.segments(&data, delay, method)?;
        let ident = setup
            .identify(&data.x, &segments)
            .with_context(|| format!("{} segments ({})", segments.len(), method.name()))?;
        bar.finish();

        let bar = stage(&format!("validate ({})", method.name()));
        let cfg = CheckConfig::new(t_period, space, args.validation_periods, args.validation_periods)?
            .with_initial(x0, 0.0)?;
        let check = check_model(&ident.model, &cfg)?;
        // The model sampled like the record, for a section in the same delay coordinates.
        let sim_cfg = SimulationConfig::paper()
            .with_forcing_period(t_period)?
            .with_samples_per_period(data.p)?
            .with_samples((args.validation_periods * data.p).min(data.x.len().max(50 * data.p)))?
            .with_initial(x0, 0.0)?;
        let sim = simulate(&ident.model, &sim_cfg)?;
        let sim_x = match data.domain {
            Domain::Circle => sim.wrapped(),
            Domain::Line => sim.theta,
        };
        let (model_section, model_embedded) = delay_section(&sim_x, data.p, 0, delay, data.domain);
        let distance = energy_distance(&embedded, &model_embedded);
        bar.finish();
        results.push(MethodResult {
            method,
            basis: setup.basis_name,
            ident,
            check,
            section: model_section,
            distance,
        });
    }
    let facts = RecordFacts {
        data: &data,
        ami: ami.values,
        delay,
        fnn,
        catalogue,
        section,
        floor,
    };
    write_report(args, &facts, &results)
}

fn write_report(args: &ReportArgs, f: &RecordFacts<'_>, results: &[MethodResult]) -> anyhow::Result<()> {
    let out = &args.out;
    let (data, delay) = (f.data, f.delay);
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
    match f.fnn.minimum_dimension() {
        Some(d) => writeln!(
            r,
            "Embedding dimension (false nearest neighbours below {}): **{d}**.\n",
            f.fnn.fraction_threshold
        )?,
        None => writeln!(
            r,
            "No embedding dimension up to {} brings false neighbours below {}.\n",
            f.fnn.levels.len(),
            f.fnn.fraction_threshold
        )?,
    }
    writeln!(r, "| d | false neighbours |\n| --- | --- |")?;
    for l in &f.fnn.levels {
        writeln!(r, "| {} | {:.4} |", l.dim, l.fraction())?;
    }
    writeln!(r)?;
    let ami_pts: Vec<(f64, f64)> = f
        .ami
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
                points: vec![(delay as f64, f.ami.get(delay).copied().unwrap_or(0.0))],
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
            points: f
                .fnn
                .levels
                .iter()
                .map(|l| (l.dim as f64, l.fraction()))
                .collect(),
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
        args.identify.search.tolerance,
        f.catalogue.tolerance(),
        args.identify.search.dim
    )?;
    writeln!(r, "| period | segments | distinct orbits |\n| --- | --- | --- |")?;
    for c in f.catalogue.counts() {
        writeln!(r, "| {} | {} | {} |", c.period, c.segments, c.orbits)?;
    }
    writeln!(r)?;

    for res in results {
        let j = json(&res.ident, res.method.name(), &res.basis);
        let how = match res.method {
            Method::Upo => "harmonic balance on the orbits above, the paper's method",
            Method::Windowed => "the weak form on plain windows of the record",
        };
        writeln!(
            r,
            "## Identified model: {} ({how}), basis {}\n",
            res.method.name(),
            res.basis
        )?;
        writeln!(
            r,
            "{} segments, {} equations, condition number {:.3e}, residual RMS {:.3e}. Standard errors treat the \
             equations as independent (read them as lower bounds); the intervals come from a bootstrap over \
             segments.\n",
            j["orbits_used"],
            j["rows"],
            j["condition_number"].as_f64().unwrap_or(f64::NAN),
            j["residual_rms"].as_f64().unwrap_or(f64::NAN)
        )?;
        writeln!(
            r,
            "| term | coefficient | std. error | interval |\n| --- | --- | --- | --- |"
        )?;
        for c in res.ident.model.coefficients() {
            let interval = res
                .ident
                .intervals
                .as_ref()
                .and_then(|b| b.interval(&c.name))
                .map_or("—".to_owned(), |i| format!("[{:.6}, {:.6}]", i.lower, i.upper));
            writeln!(
                r,
                "| `{}` | {:.6} | {:.2e} | {interval} |",
                c.name, c.value, c.std_error
            )?;
        }
        writeln!(r)?;
        let model_file = format!("model_{}.json", res.method.name());
        std::fs::write(out.join(&model_file), res.ident.model.to_json()?).context("saving a model")?;
        writeln!(
            r,
            "Saved as `{model_file}` (load it with `hb_solve::IdentifiedModel::from_json`).\n"
        )?;
    }

    writeln!(r, "## Do the models behave like the record?\n")?;
    let fmt = |v: Option<f64>| v.map_or("n/a".to_owned(), |v| format!("{v:.2e}"));
    writeln!(
        r,
        "Energy distance between the record's section and the model's, in delay coordinates at the forcing's phase \
         0; the floor is the distance between the two halves of the record ({}): a distance of that order means the \
         model's attractor cannot be told from the record's with this many points.\n",
        fmt(f.floor)
    )?;
    writeln!(
        r,
        "| model | energy distance to the record | largest Lyapunov exponent (per unit time) | whirling fraction | \
         period-1 orbits at phase 0: x (winding) |\n| --- | --- | --- | --- | --- |"
    )?;
    for res in results {
        let orbits: Vec<String> = res
            .check
            .orbits
            .iter()
            .map(|o| format!("{:.4} ({})", o.x, o.winding))
            .collect();
        writeln!(
            r,
            "| {} | {} | {:.4} ± {:.4} | {:.3} | {} |",
            res.method.name(),
            fmt(res.distance),
            res.check.lyapunov.per_unit_time,
            res.check.lyapunov.standard_error,
            res.check.whirling,
            if orbits.is_empty() {
                "none found".to_owned()
            } else {
                orbits.join(", ")
            }
        )?;
    }
    writeln!(r)?;

    let (range, label) = match data.domain {
        Domain::Circle => (Some((-std::f64::consts::PI, std::f64::consts::PI)), "x (wrapped)"),
        Domain::Line => (None, "x"),
    };
    let y_label = format!("x(t + {delay} dt)");
    let mut panels = vec![(
        "section_record.png".to_owned(),
        "Record".to_owned(),
        &f.section[..],
        GREY,
    )];
    for (res, color) in results.iter().zip([ORANGE, BLUE]) {
        panels.push((
            format!("section_model_{}.png", res.method.name()),
            format!("Model ({})", res.method.name()),
            &res.section[..],
            color,
        ));
    }
    for (file, who, pts, color) in panels {
        let title = format!("{who}: section in delay coordinates");
        Figure {
            title: &title,
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
        .save(&out.join(&file))?;
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
