//! `cargo xtask reproduce`: the paper end to end, and its report.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Context;
use circle_signal::wrap;
use hb_basis::{BasisKind, Harmonic, Hat};
use hb_pipeline::pipeline::{
    Embedded, InitialState, Method, ModelSpec, Pipeline, PipelineOptions, PredictionOptions, Record,
    RecordComparison, Stage, ValidationOptions,
};
use pendulum_sim::{
    Domain, Pendulum, PredictionConfig, PredictionRecord, PredictionTimes, SimulationConfig, Trajectory,
    predict_window, prediction_starts, simulate,
};

use circle_signal::{RotationSplit, SampleClock, unwrap};
use upo_search::{Catalogue, Segment};

use crate::identification::{Identified, Validation, hat_curves, table_one, validation_section};
use crate::timings::Timings;
use hb_plot::{BLUE, Figure, GREY, ORANGE, RED, Series, Style};

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

/// The identified models of the report: label, file, method and basis, in the pipeline's order
/// (the harmonic basis K = 1 and 8 hats, on the close-return orbits and on plain windows).
fn models() -> anyhow::Result<[(&'static str, &'static str, Method, BasisKind); 4]> {
    let (harmonic, hat) = (BasisKind::from(Harmonic::new(1)?), BasisKind::from(Hat::new(8)?));
    Ok([
        (
            "harmonic K = 1, UPOs",
            "model_harmonic_upo.json",
            Method::Upo,
            harmonic,
        ),
        ("8 hats, UPOs", "model_hat8_upo.json", Method::Upo, hat),
        (
            "harmonic K = 1, windowed",
            "model_harmonic_windowed.json",
            Method::Windowed,
            harmonic,
        ),
        (
            "8 hats, windowed",
            "model_hat8_windowed.json",
            Method::Windowed,
            hat,
        ),
    ])
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
    let trajectory = times.stage("simulate data set", || Ok(simulate(&pendulum, &config)?))?;
    let x = trajectory.wrapped();

    // 2. The pipeline with the paper's settings: the delay from the AMI (16 boxes), the dimension
    // by false nearest neighbours in both metrics, close returns at e = 3 %, periods 1..16,
    // d = 2; every model measured from θ = 0.1, θ' = 0 like the true pendulum below.
    let clock = SampleClock::nondimensional(25)?.with_start_time(trajectory.t[0])?;
    let validation = ValidationOptions::default()
        .with_section_points(plan.section_points)?
        .with_lyapunov_periods(plan.lyapunov_periods)?
        .with_initial(InitialState::Given { x: 0.1, v: 0.0 })?
        .with_record_comparison(RecordComparison::None)?;
    let specs = models()?;
    let options = PipelineOptions {
        embed: hb_pipeline::pipeline::EmbedOptions::default().with_compared_metric(Domain::Line),
        models: specs
            .iter()
            .map(|&(_, _, method, basis)| ModelSpec::new(method, basis))
            .collect(),
        validation,
        ..PipelineOptions::default()
    };
    let pipeline = Pipeline::new(Record::new(&x, clock, Domain::Circle)?, options)?;

    // 3. Delay and embedding dimension (paper section 3.1), both metrics.
    let embed = times.stage("AMI and false nearest neighbours", || Ok(pipeline.embed()?))?;
    let delay = embed.delay;

    // 4. Unstable periodic orbits by close returns (paper section 3.2), and the plain windows.
    let segments = times.stage("UPO search (close returns)", || Ok(pipeline.segments(&embed)?))?;
    let catalogue = &segments.catalogue;

    // 5. Identification by harmonic balance on the UPOs (paper section 4.2), and by the weak
    // form on plain windows beside it.
    let identified = pipeline.identify(&segments, |stage| {
        if let Stage::Identify { method, .. } = stage {
            times.start(match method {
                Method::Upo => "identification (UPOs)",
                Method::Windowed => "identification (windowed)",
            });
        }
    });
    let identified = times.finish(identified)?;

    // 6. Validation: every model measured as the truth is (paper section 5, and numbers).
    let truth = times.stage("validation: truth", || {
        Ok(Validation {
            label: "true pendulum".to_owned(),
            check: validation.check(&pendulum, pipeline.record())?,
        })
    })?;
    let floor = times.stage("validation: floor", || {
        Ok(Validation {
            label: "true pendulum, another initial state".to_owned(),
            check: validation
                .with_initial(InitialState::Given { x: 1.0, v: 0.5 })?
                .check(&pendulum, pipeline.record())?,
        })
    })?;
    let measured = times.stage("validation: models", || {
        // The paper's models are all run freely: one that cannot be is the run's error.
        Ok(pipeline.validate(&embed, &identified, |_| {})?.all()?)
    })?;
    let models: Vec<Identified> = specs
        .iter()
        .zip(identified)
        .map(|(&(label, file, ..), id)| Identified {
            label,
            file,
            model: id.model,
            quality: id.quality,
            warning: id.warning,
        })
        .collect();
    let in_sample: Vec<Option<PredictionTimes>> = measured.iter().map(|v| v.prediction.clone()).collect();
    let checks: Vec<Validation> = models
        .iter()
        .zip(measured)
        .map(|(m, v)| Validation {
            label: m.label.to_owned(),
            check: v.check,
        })
        .collect();
    for m in &models {
        let path = out.join(m.file);
        std::fs::write(&path, m.model.to_json()?)
            .with_context(|| format!("cannot write {}", path.display()))?;
    }

    // 7. Valid prediction time, on the record's windows and on its continuation (held out).
    let prediction = times.stage("prediction time", || {
        prediction_times(
            &plan,
            &pendulum,
            &trajectory,
            pipeline.record(),
            &truth,
            &checks,
            &models,
            in_sample,
        )
    })?;

    // Figures.
    times.stage("figures", || {
        orbit_figures(out, &x, catalogue, delay, &mut figures)?;
        embed_figures(out, &embed, &mut figures)?;
        let phase_plane: Vec<(f64, f64)> = x.iter().zip(&x[delay..]).map(|(&a, &b)| (a, b)).collect();
        let name = "fig2a_reconstructed_phase_plane.png";
        let y_label = format!("theta(t + {delay} dt)");
        Figure {
            title: "Reconstructed phase plane, delay from the AMI (paper Fig. 2a)",
            x_label: "theta(t)",
            y_label: &y_label,
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
        hb_plot::add_figure(
            &mut figures,
            name,
            "Reconstructed phase plane of the wrapped angle with the AMI delay (paper Fig. 2a).".to_owned(),
        );

        let name = "fig2b_poincare_section.png";
        Figure {
            title: "Poincaré section at t = 0 mod 2π (paper Fig. 2b)",
            x_label: "theta (wrapped)",
            y_label: "theta'",
            series: vec![Series {
                label: "",
                points: truth.check.section.iter().map(|p| (wrap(p[0]), p[1])).collect(),
                style: Style::Dots(1),
                color: BLUE,
            }],
            x_range: Some((-std::f64::consts::PI, std::f64::consts::PI)),
            y_range: None,
        }
        .save(&out.join(name))?;
        hb_plot::add_figure(
            &mut figures,
            name,
            "Poincaré section of the true pendulum (paper Fig. 2b).",
        );

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
        hb_plot::add_figure(
            &mut figures,
            name,
            "The wrapped angle record, first 40 forcing periods.",
        );
        Ok(())
    })?;

    // The paper's next step, one link up: its section follows the pendulum's figures.
    let mut double_pendulum = String::new();
    crate::double_pendulum::section(out, quick, &mut times, &mut double_pendulum)?;

    // The report.
    writeln!(report, "# Reproduction of Liang & Feeny, base-excited pendulum\n")?;
    writeln!(
        report,
        "Generated by `cargo xtask reproduce{}` ({}). Every number and figure below is computed \
         by this run from nothing.\n",
        if quick { " --quick" } else { "" },
        crate::build_profile()
    )?;
    writeln!(report, "## The data set\n")?;
    writeln!(
        report,
        "x'' + c x' + (1/r²) sin x − f sin(t) cos x = 0 with f = 1.52, c = 0.03, r = 0.8333; {} samples at 25 per \
         forcing period after 200 periods of transient from θ(0) = 0.1, θ'(0) = 0; DOP853 at rtol 1e-10; θ wrapped \
         into [−π, π). The paper used 30000 samples at the same rate.\n",
        plan.samples
    )?;
    embed_section(&mut report, &embed)?;
    upo_section(&mut report, catalogue, catalogue.tolerance())?;
    table_one(
        &mut report,
        &models
            .iter()
            .filter(|m| m.label.starts_with("harmonic"))
            .collect::<Vec<_>>(),
    )?;
    crate::identification::goodness_of_fit(&mut report, &models)?;
    if let Some(hat) = models.iter().find(|m| m.label.starts_with("8 hats")) {
        hat_curves(out, &mut report, &hat.model, &mut figures)?;
    }
    if let Some(hat) = models.iter().find(|m| m.label == "8 hats, windowed") {
        writeln!(
            report,
            "With the weak form on plain windows the 8-hat model has c_r = {:.6}.\n",
            hat.model.damping()
        )?;
    }
    validation_section(out, &mut report, &truth, &floor, &checks, &mut figures)?;
    prediction_section(&mut report, &prediction)?;
    writeln!(
        report,
        "The identified models are saved beside this report: {}.\n",
        models
            .iter()
            .map(|m| format!("`{}`", m.file))
            .collect::<Vec<_>>()
            .join(", ")
    )?;
    writeln!(report, "## Figures\n")?;
    for (file, caption) in &figures {
        writeln!(report, "![{caption}]({file})\n\n{caption}\n")?;
    }
    report.push_str(&double_pendulum);
    writeln!(report, "## Wall time of each stage\n")?;
    writeln!(report, "| stage | seconds |\n| --- | --- |")?;
    for (name, took) in times.done() {
        writeln!(report, "| {name} | {:.3} |", took.as_secs_f64())?;
    }
    let total: f64 = times.done().iter().map(|(_, d)| d.as_secs_f64()).sum();
    writeln!(report, "| total | {total:.3} |")?;
    let path = out.join("README.md");
    std::fs::write(&path, report).with_context(|| format!("cannot write {}", path.display()))?;
    eprintln!("report written to {}", path.display());
    Ok(())
}

/// Valid prediction times of one system.
struct Prediction {
    label: String,
    /// On the windows of the data set (which the identification used).
    in_sample: Option<PredictionTimes>,
    /// On the windows of the data set's continuation (never seen by the identification).
    held_out: Option<PredictionTimes>,
}

/// What the prediction section reports.
struct Predictions {
    systems: Vec<Prediction>,
    /// The true pendulum on the data set's windows from the simulation's exact states.
    exact_truth: PredictionTimes,
    /// Samples of the held-out continuation.
    held_out_samples: usize,
}

/// The valid prediction time of the truth and of every model, with the pipeline's options, on the
/// data set's windows and on a continuation of the data set after its last sample; and the truth
/// from the exact states, the measure of what the state estimate costs.
#[allow(clippy::too_many_arguments)]
fn prediction_times(
    plan: &Plan,
    pendulum: &Pendulum,
    trajectory: &Trajectory,
    record: &Record<'_>,
    truth: &Validation,
    checks: &[Validation],
    models: &[Identified],
    in_sample: Vec<Option<PredictionTimes>>,
) -> anyhow::Result<Predictions> {
    let options = PredictionOptions::default();
    // The continuation: the same trajectory's next `samples` samples.
    let periods = plan.samples / 25;
    let later = simulate(
        pendulum,
        &SimulationConfig::paper()
            .with_transient_periods(200 + periods)
            .with_samples(plan.samples)?,
    )?;
    let later_x = later.wrapped();
    let later_clock = SampleClock::nondimensional(25)?.with_start_time(later.t[0])?;
    let held_out = Record::new(&later_x, later_clock, Domain::Circle)?;
    let truth_lyapunov = Some(truth.check.lyapunov.per_unit_time);
    let mut systems = vec![Prediction {
        label: truth.label.clone(),
        in_sample: options.measure(pendulum, record, truth_lyapunov)?,
        held_out: options.measure(pendulum, &held_out, truth_lyapunov)?,
    }];
    for ((model, check), in_sample) in models.iter().zip(checks).zip(in_sample) {
        systems.push(Prediction {
            label: model.label.to_owned(),
            in_sample,
            held_out: options.measure(&model.model, &held_out, Some(check.check.lyapunov.per_unit_time))?,
        });
    }
    let config = PredictionConfig::default();
    let observed = PredictionRecord::new(record.samples(), *record.clock(), Domain::Circle)?;
    let windows = prediction_starts(&observed, &config)?
        .into_iter()
        .map(|n| {
            predict_window(
                pendulum,
                &observed,
                n,
                [trajectory.theta[n], trajectory.omega[n]],
                &config,
            )
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Predictions {
        systems,
        exact_truth: PredictionTimes {
            windows,
            tolerance: config.tolerance() * observed.spread(),
            drive_period: record.clock().drive_period(),
            lyapunov: truth_lyapunov,
        },
        held_out_samples: plan.samples,
    })
}

/// The prediction-time table of the report.
fn prediction_section(report: &mut String, p: &Predictions) -> anyhow::Result<()> {
    writeln!(report, "## Valid prediction time\n")?;
    writeln!(
        report,
        "The validation that needs no true equation (`pendulum_sim::prediction`, as `hbid report` runs it): from \
         the record's own state at 32 samples spread over it (θ and θ' from a least-squares polynomial of degree \
         4 through the samples within a twelfth of a forcing period, here five samples), each system is \
         integrated until its angle is more than {:.4} (10 % of the record's spread) from the record; the median \
         over the windows, in forcing periods (quartiles in brackets), and in Lyapunov times of the system's own \
         exponent. *Data set*: the windows of the record every model was identified on; *held out*: the {} \
         samples that follow it on the same trajectory, which no identification saw; *ratio*: the held-out \
         median against the true pendulum's.\n",
        p.exact_truth.tolerance, p.held_out_samples
    )?;
    writeln!(
        report,
        "| system | data set: median (periods) | held out: median (periods) | held out: median (Lyapunov times) | ratio |\n\
         | --- | --- | --- | --- | --- |"
    )?;
    let cell = |t: Option<&PredictionTimes>| {
        t.and_then(PredictionTimes::in_periods)
            .map_or("n/a".to_owned(), |s| {
                format!(
                    "{}{:.2} ({:.2}–{:.2})",
                    if s.median_is_lower_bound() { "≥ " } else { "" },
                    s.median,
                    s.lower_quartile,
                    s.upper_quartile
                )
            })
    };
    let median = |t: Option<&PredictionTimes>| t.and_then(PredictionTimes::in_periods).map(|s| s.median);
    let reference = median(p.systems[0].held_out.as_ref());
    for s in &p.systems {
        let lyapunov = s
            .held_out
            .as_ref()
            .and_then(PredictionTimes::in_lyapunov_times)
            .map_or("n/a".to_owned(), |l| format!("{:.2}", l.median));
        let ratio = match (median(s.held_out.as_ref()), reference) {
            (Some(m), Some(r)) if r > 0.0 => format!("{:.3}", m / r),
            _ => "n/a".to_owned(),
        };
        writeln!(
            report,
            "| {} | {} | {} | {lyapunov} | {ratio} |",
            s.label,
            cell(s.in_sample.as_ref()),
            cell(s.held_out.as_ref())
        )?;
    }
    writeln!(
        report,
        "\nThe state estimate is what limits these times: the true pendulum started from the simulation's exact \
         states at the same windows of the data set stays within the tolerance for {} forcing periods (median), \
         against {} from the estimated states.\n",
        cell(Some(&p.exact_truth)),
        cell(p.systems[0].in_sample.as_ref())
    )?;
    Ok(())
}

/// The UPO table of the report.
fn upo_section(report: &mut String, catalogue: &Catalogue, epsilon: f64) -> anyhow::Result<()> {
    writeln!(report, "## Unstable periodic orbits (close returns)\n")?;
    writeln!(
        report,
        "e = 3 % of 2π (ε = {epsilon:.4} rad), delay vectors of dimension 2 and delay 5, circle metric (max over \
         components), periods 1 to 16. A *segment* is one passage near an orbit (one per run of consecutive close \
         returns); passages of one period whose samples agree within ε, up to a shift that keeps the forcing's \
         phase, are one *distinct orbit*. The paper reports \"around 25 UPOs from period 1 to 16\" at e = 3 %.\n"
    )?;
    writeln!(
        report,
        "| period | segments | distinct orbits |\n| --- | --- | --- |"
    )?;
    let counts = catalogue.counts();
    for c in &counts {
        writeln!(report, "| {} | {} | {} |", c.period, c.segments, c.orbits)?;
    }
    let (s, o): (usize, usize) = counts
        .iter()
        .fold((0, 0), |(s, o), c| (s + c.segments, o + c.orbits));
    writeln!(report, "| all | {s} | {o} |\n")?;
    Ok(())
}

/// The representative segment of the first distinct orbit of `period` with the given whirling
/// property, if any.
fn pick_orbit<'a>(x: &[f64], catalogue: &'a Catalogue, period: usize, whirling: bool) -> Option<&'a Segment> {
    catalogue
        .representatives()
        .filter(|s| s.period() == period)
        .find(|s| {
            let xc = unwrap(&x[s.start()..=s.start() + s.len()]);
            let turns = ((xc[s.len()] - xc[0]) / std::f64::consts::TAU).round();
            (turns != 0.0) == whirling
        })
}

/// Figures 1 (a period-4 orbit: wrapped, unwrapped, rotation plus oscillation) and 4 (period-1
/// and period-2 orbits in the delay plane).
fn orbit_figures(
    out: &Path,
    x: &[f64],
    catalogue: &Catalogue,
    delay: usize,
    figures: &mut Vec<(String, String)>,
) -> anyhow::Result<()> {
    use std::f64::consts::PI;
    let h = std::f64::consts::TAU / 25.0;
    let four = pick_orbit(x, catalogue, 4, true).or_else(|| pick_orbit(x, catalogue, 4, false));
    if let Some(seg) = four {
        let tau: Vec<f64> = (0..=seg.len()).map(|n| n as f64 * h).collect();
        let wrapped = &x[seg.start()..=seg.start() + seg.len()];
        let xc = unwrap(wrapped);
        let split = RotationSplit::new(&xc, h)?;
        let name = "fig1a_period4_sampled.png";
        Figure {
            title: "A period-4 orbit as sampled (paper Fig. 1a)",
            x_label: "time since the start of the orbit",
            y_label: "x (wrapped)",
            series: vec![Series {
                label: "",
                points: tau.iter().copied().zip(wrapped.iter().copied()).collect(),
                style: Style::Line { break_above: PI },
                color: BLUE,
            }],
            x_range: None,
            y_range: Some((-PI, PI)),
        }
        .save(&out.join(name))?;
        hb_plot::add_figure(
            figures,
            name,
            "A period-4 orbit from the close-return search, as the encoder reports it (Fig. 1a).",
        );
        let name = "fig1b_period4_unwrapped.png";
        Figure {
            title: "The same orbit unwrapped, x_c (paper Fig. 1b)",
            x_label: "time since the start of the orbit",
            y_label: "x_c",
            series: vec![Series {
                label: "",
                points: tau.iter().copied().zip(xc.iter().copied()).collect(),
                style: Style::Line {
                    break_above: f64::INFINITY,
                },
                color: BLUE,
            }],
            x_range: None,
            y_range: None,
        }
        .save(&out.join(name))?;
        hb_plot::add_figure(
            figures,
            name,
            "The period-4 orbit unwrapped into a continuous signal (Fig. 1b).",
        );
        let name = "fig1c_period4_rotation_oscillation.png";
        Figure {
            title: "Rotation w_ck t and oscillation x_var (paper Fig. 1c)",
            x_label: "time since the start of the orbit",
            y_label: "angle",
            series: vec![
                Series {
                    label: "rotation w_ck t",
                    points: tau.iter().map(|&t| (t, split.rate * t)).collect(),
                    style: Style::Line {
                        break_above: f64::INFINITY,
                    },
                    color: GREY,
                },
                Series {
                    label: "oscillation x_var",
                    points: tau
                        .iter()
                        .copied()
                        .zip(split.oscillation.iter().copied())
                        .collect(),
                    style: Style::Line {
                        break_above: f64::INFINITY,
                    },
                    color: ORANGE,
                },
            ],
            x_range: None,
            y_range: None,
        }
        .save(&out.join(name))?;
        hb_plot::add_figure(
            figures,
            name,
            "Its split into a constant rotation and a periodic oscillation (Fig. 1c).",
        );
    }
    let delay_plane = |seg: &Segment| -> Vec<(f64, f64)> {
        (seg.start()..=seg.start() + seg.len())
            .filter(|&n| n + delay < x.len())
            .map(|n| (x[n], x[n + delay]))
            .collect()
    };
    let mut series = Vec::new();
    let picks = [
        (1, "period 1", BLUE),
        (2, "period 2 (whirling)", ORANGE),
        (2, "period 2 (oscillating)", RED),
    ];
    for (i, (period, label, color)) in picks.into_iter().enumerate() {
        let seg = if i == 2 {
            pick_orbit(x, catalogue, period, false)
        } else {
            pick_orbit(x, catalogue, period, i == 1)
        }
        .or_else(|| catalogue.representatives().find(|s| s.period() == period));
        if let Some(seg) = seg {
            series.push(Series {
                label,
                points: delay_plane(seg),
                style: Style::Line { break_above: PI },
                color,
            });
        }
    }
    let name = "fig4_orbits_delay_plane.png";
    let y_label = format!("x(t + {delay} dt)");
    Figure {
        title: "Period-1 and period-2 orbits in the delay plane (paper Fig. 4)",
        x_label: "x(t)",
        y_label: &y_label,
        series,
        x_range: Some((-PI, PI)),
        y_range: Some((-PI, PI)),
    }
    .save(&out.join(name))?;
    hb_plot::add_figure(
        figures,
        name,
        "Period-1 and period-2 orbits found by close returns, in the delay plane (Fig. 4).",
    );
    Ok(())
}

fn embed_section(report: &mut String, e: &Embedded) -> anyhow::Result<()> {
    let linear = linear_fnn(e)?;
    writeln!(report, "## Delay and embedding dimension\n")?;
    let dims = |r: &embedding::FnnResult| r.minimum_dimension().map_or("none".to_owned(), |d| d.to_string());
    writeln!(report, "| quantity | paper | this run |\n| --- | --- | --- |")?;
    writeln!(
        report,
        "| delay (first minimum of the AMI, 16 boxes) | 5 | {} |",
        e.delay
    )?;
    writeln!(
        report,
        "| embedding dimension (false neighbours < {}) | 4 | {} (circle metric), {} (linear metric) |\n",
        e.fnn.fraction_threshold,
        dims(&e.fnn),
        dims(linear)
    )?;
    writeln!(
        report,
        "| d | false fraction, circle metric | false fraction, linear metric |\n| --- | --- | --- |"
    )?;
    for (c, l) in e.fnn.levels.iter().zip(&linear.levels) {
        writeln!(
            report,
            "| {} | {:.4} | {:.4} |",
            c.dim,
            c.fraction(),
            l.fraction()
        )?;
    }
    writeln!(report)?;
    Ok(())
}

/// False nearest neighbours with the linear metric, asked of the pipeline beside the circle's.
fn linear_fnn(e: &Embedded) -> anyhow::Result<&embedding::FnnResult> {
    e.fnn_compared
        .as_ref()
        .context("the pipeline was asked for the linear metric's false nearest neighbours")
}

fn embed_figures(out: &Path, e: &Embedded, figures: &mut Vec<(String, String)>) -> anyhow::Result<()> {
    let linear = linear_fnn(e)?;
    let name = "fig3_mutual_information.png";
    // Lags 0 and 1 are the entropy and near it, far above the rest: the frame starts at lag 2.
    let curve: Vec<(f64, f64)> = e
        .ami
        .values
        .iter()
        .enumerate()
        .skip(2)
        .map(|(l, &v)| (l as f64, v))
        .collect();
    Figure {
        title: "Average mutual information (paper Fig. 3)",
        x_label: "lag (samples)",
        y_label: "I (nats)",
        series: vec![
            Series {
                label: "AMI, 16 boxes",
                points: curve.clone(),
                style: Style::Line {
                    break_above: f64::INFINITY,
                },
                color: BLUE,
            },
            Series {
                label: "first minimum",
                points: vec![(e.delay as f64, e.ami.values[e.delay])],
                style: Style::Dots(6),
                color: RED,
            },
        ],
        x_range: None,
        y_range: Some((0.0, 1.05 * e.ami.values.get(2).copied().unwrap_or(1.0))),
    }
    .save(&out.join(name))?;
    hb_plot::add_figure(
        figures,
        name,
        "Average mutual information against lag, first minimum marked (Fig. 3), from lag 2 (I(0) and I(1) are far above).",
    );
    let name = "fig3b_false_nearest_neighbours.png";
    let pts = |r: &embedding::FnnResult| -> Vec<(f64, f64)> {
        r.levels.iter().map(|l| (l.dim as f64, l.fraction())).collect()
    };
    Figure {
        title: "False nearest neighbours, delay from the AMI",
        x_label: "embedding dimension d",
        y_label: "fraction of false neighbours",
        series: vec![
            Series {
                label: "circle metric",
                points: pts(&e.fnn),
                style: Style::Line {
                    break_above: f64::INFINITY,
                },
                color: BLUE,
            },
            Series {
                label: "linear metric",
                points: pts(linear),
                style: Style::Line {
                    break_above: f64::INFINITY,
                },
                color: ORANGE,
            },
        ],
        x_range: None,
        y_range: Some((0.0, 1.05)),
    }
    .save(&out.join(name))?;
    hb_plot::add_figure(
        figures,
        name,
        "Fraction of false nearest neighbours against dimension, circle and linear metrics.",
    );
    Ok(())
}
