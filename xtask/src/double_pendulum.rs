//! The reproduction's next step, one link up: the base-excited double pendulum, whirling,
//! identified as `hbid identify --coords` does by the paper's harmonic balance on vector orbits
//! (close returns of the whole state) and by the weak form, and checked by free runs of the
//! identified systems against the truth.

use std::f64::consts::{PI, TAU};
use std::fmt::Write as _;
use std::path::Path;

use anyhow::Context;
use circle_signal::{Domain, SampleClock, Segment, wrap};
use hb_model::IdentifiedSystem;
use hb_pipeline::pipeline::Method;
use hb_pipeline::{IdentifyOptions, IdentifyReport, IdentifyRequest, OrbitOptions, RecordOptions, Source};
use hb_plot::{BLUE, Figure, GREY, INK, ORANGE, RED, Series, Style};
use pendulum_sim::multi::{self, MultiConfig, MultiState, MultiSystem, MultiTrajectory};
use pendulum_sim::prediction::{
    SystemPredictionRecord, SystemPredictionTimes, predict_system_window, system_prediction_starts,
    system_valid_prediction_times,
};
use pendulum_sim::{DoublePendulum, PredictionConfig, SimulationConfig, Tolerances, energy_distance};

use crate::timings::Timings;

/// Samples per drive period: no angle of the whirling pendulum moves more than 0.45 rad between
/// two of them.
const P: usize = 64;
/// Drive periods of transient before the record, and before each section.
const TRANSIENT: usize = 100;
/// The record's initial state: at rest with link 1 at 2 rad.
const START: [f64; 2] = [2.0, 0.0];
/// The floor's initial state: another start on the same attractor.
const FLOOR_START: [f64; 2] = [0.5, -1.0];
/// The close-return search: a quarter period of delay, delay vectors of dimension 2 of each
/// angle, a tolerance of 1.5 % of 2π, periods up to 8.
const DELAY: usize = P / 4;
const DIMENSION: usize = 2;
const TOLERANCE: f64 = 0.015;
const MAX_PERIOD: usize = 8;
/// Drive periods of the time-series figure.
const SHOWN_PERIODS: usize = 20;
/// The coordinates' names, as the simulator's equations write them.
const NAMES: [&str; 2] = ["q1", "q2"];

/// Sizes of the section's run.
struct Plan {
    /// Drive periods of the record the systems are identified from.
    periods: usize,
    /// Drive periods after it, held out for the valid prediction time.
    held_out: usize,
    /// Points of each Poincaré section.
    section_points: usize,
    /// Windows of the valid prediction time.
    windows: usize,
}

impl Plan {
    fn new(quick: bool) -> Self {
        if quick {
            Self {
                periods: 6_000,
                held_out: 200,
                section_points: 300,
                windows: 16,
            }
        } else {
            Self {
                periods: 10_000,
                held_out: 800,
                section_points: 2_000,
                windows: 32,
            }
        }
    }
}

/// One identification of the section: its label, file and report.
struct Identified {
    label: &'static str,
    file: &'static str,
    report: IdentifyReport,
    system: IdentifiedSystem,
}

/// A Poincaré section of one system, or why it has none.
struct Section {
    label: String,
    points: Result<MultiTrajectory, String>,
}

/// The section in R⁶ as the energy distance reads it: each angle as the point `(cos, sin)` on
/// its circle, and both velocities.
fn embedded(section: &MultiTrajectory) -> Vec<[f64; 6]> {
    (0..section.len())
        .map(|i| {
            let (a, b) = (section.q[0][i], section.q[1][i]);
            [
                a.cos(),
                a.sin(),
                b.cos(),
                b.sin(),
                section.v[0][i],
                section.v[1][i],
            ]
        })
        .collect()
}

/// Passages over the top of a continuous angle: changes of the turn it is on.
fn passages(q: &[f64]) -> usize {
    let turn = |x: f64| ((x + PI) / TAU).floor();
    q.windows(2).filter(|w| turn(w[0]) != turn(w[1])).count()
}

/// The simulation's tolerances (those of the identification tests of the double pendulum).
fn tolerances() -> anyhow::Result<Tolerances> {
    Ok(Tolerances::new(1e-12, 1e-13)?)
}

/// `samples` of `system` at `P` per period after the transient from rest at `start`.
fn sampling(samples: usize, start: [f64; 2]) -> anyhow::Result<MultiConfig> {
    let sampling = SimulationConfig::paper()
        .with_samples_per_period(P)?
        .with_samples(samples)?
        .with_transient_periods(TRANSIENT)
        .with_tolerances(tolerances()?);
    Ok(MultiConfig::from_sampling(sampling, MultiState::at_rest(&start)?))
}

/// The terms of each true equation, as `hbid identify --terms` takes them.
fn true_terms(truth: &DoublePendulum) -> String {
    truth
        .normalised_equations()
        .iter()
        .zip(NAMES)
        .map(|(e, name)| {
            let terms: Vec<&str> = e.terms.iter().map(|(term, _)| term.as_ref()).collect();
            format!("{name}: {}", terms.join(", "))
        })
        .collect::<Vec<_>>()
        .join("; ")
}

/// The request of `hbid identify --coords q1,q2 --terms TERMS --method METHOD --bootstrap 0`
/// with the section's close-return search.
fn request(method: Method, terms: &str) -> anyhow::Result<IdentifyRequest> {
    Ok(IdentifyRequest::new(IdentifyOptions {
        record: RecordOptions {
            coords: Some(NAMES.join(",").parse().map_err(anyhow::Error::msg)?),
            ..RecordOptions::default()
        },
        method,
        bootstrap: 0,
        orbits: OrbitOptions {
            tolerance: TOLERANCE,
            max_period: MAX_PERIOD,
            dim: DIMENSION,
            delay: Some(DELAY),
        },
        terms: Some(terms.parse().map_err(anyhow::Error::msg)?),
        ..IdentifyOptions::default()
    })?)
}

/// The double pendulum's section of the report: simulation, vector orbits, both identifications,
/// the coefficient table, sections, valid prediction times and figures. Appends its text to
/// `report`, its figures and models to `out`.
pub fn section(out: &Path, quick: bool, times: &mut Timings, report: &mut String) -> anyhow::Result<()> {
    let plan = Plan::new(quick);
    let truth = DoublePendulum::whirling();
    let n = P * plan.periods;

    // The record and its held-out continuation, one run.
    let run = times.stage("double pendulum: simulate", || {
        Ok(multi::simulate(
            &truth,
            &sampling(P * (plan.periods + plan.held_out), START)?,
        )?)
    })?;
    let wrapped: Vec<Vec<f64>> = run
        .q
        .iter()
        .map(|q| q.iter().map(|&x| wrap(x)).collect())
        .collect();

    // Vector orbits and both identifications, through the application layer.
    let terms = true_terms(&truth);
    let upo = request(Method::Upo, &terms)?;
    let windowed = request(Method::Windowed, &terms)?;
    let data = times.stage("double pendulum: vector orbits", || {
        let source = Source::Arrays {
            coords: vec![&wrapped[0][..n], &wrapped[1][..n]],
            t: Some(&run.t[..n]),
            drives: Vec::new(),
        };
        let data = hb_pipeline::load(source, &upo.options().record, upo.drive(), &mut ())?;
        let (segments, _) = upo.segments(&data, DELAY, Method::Upo)?;
        Ok((data, segments))
    })?;
    let (data, segments) = data;
    let mut models = Vec::new();
    for (label, file, method, req, stage) in [
        (
            "harmonic balance on vector orbits",
            "dp_model_upo.json",
            Method::Upo,
            &upo,
            "double pendulum: identification (UPOs)",
        ),
        (
            "weak form on windows",
            "dp_model_windowed.json",
            Method::Windowed,
            &windowed,
            "double pendulum: identification (windowed)",
        ),
    ] {
        let report = times.stage(stage, || Ok(hb_pipeline::identify_data(&data, req, &mut ())?))?;
        anyhow::ensure!(
            report.method == method,
            "{label}: identified by {}",
            report.method
        );
        let system = report.system()?;
        let path = out.join(file);
        std::fs::write(&path, system.to_json()?)
            .with_context(|| format!("cannot write {}", path.display()))?;
        models.push(Identified {
            label,
            file,
            report,
            system,
        });
    }

    // Validation: sections, valid prediction times, free runs for the figures.
    let validation = times.stage("double pendulum: validation", || {
        validate(&plan, &truth, &run, &wrapped, &models)
    })?;

    // The text.
    writeln!(report, "## The next step: the base-excited double pendulum\n")?;
    let (mu, lambda, omega2, f, c1, c2) = (
        truth.mu(),
        truth.lambda(),
        truth.omega2(),
        truth.f(),
        truth.c1(),
        truth.c2(),
    );
    writeln!(
        report,
        "Two links on the same shaken pivot, absolute angles θ1 = q1 and θ2 = q2 from the downward vertical \
         (`pendulum_sim::DoublePendulum::whirling`), each equation normalised so that its own acceleration has \
         the coefficient 1:\n\n\
         ```text\n\
         θ1'' + μλ θ2'' cos(θ1−θ2) + μλ θ2'² sin(θ1−θ2) + ω² sin θ1 − f sin(t) cos θ1 + c1 θ1' = 0\n\
         θ2'' + (1/λ) θ1'' cos(θ1−θ2) − (1/λ) θ1'² sin(θ1−θ2) + (ω²/λ) sin θ2 − (f/λ) sin(t) cos θ2 + c2 θ2' = 0\n\
         ```\n\n\
         with μ = {mu}, λ = {lambda}, ω² = {omega2}, f = {f}, c1 = {c1}, c2 = {c2}. {} drive periods at {P} \
         samples per period after {TRANSIENT} periods of transient from rest at θ = ({}, {}), DOP853 at rtol \
         1e-12; both angles wrapped into [−π, π) as two encoders report them. Both links whirl: over the record \
         link 1 passes over the top {} times and link 2 {} times. The {} periods that follow on the same \
         trajectory are held out for the valid prediction time.\n",
        plan.periods,
        START[0],
        START[1],
        passages(&run.q[0][..n]),
        passages(&run.q[1][..n]),
        plan.held_out
    )?;
    orbit_table(report, &segments)?;
    coefficient_table(report, &truth, &models)?;
    validation_text(report, &plan, &validation, &models)?;
    let figures = times.stage("double pendulum: figures", || {
        figures(out, &run, &wrapped, n, &segments, &validation, &models)
    })?;
    for (file, caption) in &figures {
        writeln!(report, "![{caption}]({file})\n\n{caption}\n")?;
    }
    writeln!(
        report,
        "The identified systems are saved beside this report: {} (`hbid compare`, `hbid report --model` and \
         `hb_model::IdentifiedSystem::from_json` read them; their coordinates are named q1, q2).\n",
        models
            .iter()
            .map(|m| format!("`{}`", m.file))
            .collect::<Vec<_>>()
            .join(", ")
    )?;
    Ok(())
}

/// The vector orbits by period.
fn orbit_table(report: &mut String, segments: &[Segment]) -> anyhow::Result<()> {
    writeln!(report, "### Vector orbits (close returns of the whole state)\n")?;
    writeln!(
        report,
        "A return is close when the delay vectors (dimension {DIMENSION}, delay {DELAY} samples, a quarter \
         period) of both angles return together within {} % of 2π (ε = {:.4} rad, circle distance, the largest \
         over the angles and delays): the state of the whole system returns, not one link's projection of it. \
         One segment per run of consecutive close returns, periods 1 to {MAX_PERIOD}.\n",
        100.0 * TOLERANCE,
        TOLERANCE * TAU
    )?;
    writeln!(
        report,
        "| period | segments | largest closing error (rad) |\n| --- | --- | --- |"
    )?;
    for period in 1..=MAX_PERIOD {
        let of: Vec<&Segment> = segments.iter().filter(|s| s.period() == period).collect();
        if of.is_empty() {
            continue;
        }
        let worst = of.iter().map(|s| s.error()).fold(0.0, f64::max);
        writeln!(report, "| {period} | {} | {worst:.4} |", of.len())?;
    }
    writeln!(report, "| all | {} | |\n", segments.len())?;
    Ok(())
}

/// True against identified coefficients of both equations, and how each fit went.
fn coefficient_table(
    report: &mut String,
    truth: &DoublePendulum,
    models: &[Identified],
) -> anyhow::Result<()> {
    writeln!(report, "### Identified coefficients\n")?;
    writeln!(
        report,
        "Each equation with the true terms (the `--terms` that `hbid simulate --system double-pendulum --truth` \
         writes), identified as `hbid identify --coords q1,q2 --terms … --bootstrap 0` does: by harmonic \
         balance on the vector orbits above (`--method upo`, the paper's method, the velocities of each orbit's \
         series up to 32 drive harmonics) and by the weak form on plain windows of 3 drive periods \
         (`--method windowed`).\n"
    )?;
    write!(report, "| equation | term | truth |")?;
    for m in models {
        write!(report, " {} | error |", m.label)?;
    }
    writeln!(report)?;
    writeln!(report, "|{}", " --- |".repeat(3 + 2 * models.len()))?;
    let mut worst = vec![0.0f64; models.len()];
    for (i, equation) in truth.normalised_equations().iter().enumerate() {
        for (term, value) in &equation.terms {
            write!(report, "| {} | `{term}` | {value:.6} |", NAMES[i])?;
            for (k, m) in models.iter().enumerate() {
                let got = m.report.equations[i]
                    .identification
                    .model
                    .coefficient(term)
                    .map_or(f64::NAN, |c| c.value);
                let error = (got - value).abs();
                worst[k] = worst[k].max(if error.is_nan() { f64::INFINITY } else { error });
                write!(report, " {got:.6} | {error:.1e} |")?;
            }
            writeln!(report)?;
        }
    }
    write!(report, "| largest error | | |")?;
    for w in &worst {
        write!(report, " | {w:.1e} |")?;
    }
    writeln!(report, "\n")?;
    writeln!(
        report,
        "| method | segments | equation | explained | condition number | residual RMS |\n| --- | --- | --- | --- | --- | --- |"
    )?;
    for m in models {
        for e in &m.report.equations {
            let id = &e.identification;
            let summary = id.model.summary();
            writeln!(
                report,
                "| {} | {} | {} | {:.8} | {:.3e} | {:.3e} |",
                m.label,
                m.report.segments,
                e.coordinate,
                id.quality.explained,
                summary.map_or(f64::NAN, |s| s.condition),
                summary.map_or(f64::NAN, |s| s.residual_rms)
            )?;
        }
    }
    writeln!(report)?;
    Ok(())
}

/// What the validation measured.
struct Validation {
    /// The truth's section, the floor's (the truth from another start) and each model's.
    sections: Vec<Section>,
    /// The valid prediction times on the held-out continuation: the truth from the estimated
    /// states, then each model; and the truth from the simulation's exact states.
    prediction: Vec<(String, SystemPredictionTimes)>,
    exact: SystemPredictionTimes,
    /// Each model's free run from the held-out continuation's first state (for the figures).
    runs: Vec<multi::MultiFreeRun>,
}

/// The prediction test's settings: the defaults, but the state from two samples each side (an
/// interpolation): the default span of a twelfth of a period holds 11 samples at 64 per period and
/// smooths the links' sharpest turns.
fn prediction_config(windows: usize) -> anyhow::Result<PredictionConfig> {
    Ok(PredictionConfig::default()
        .with_windows(windows)?
        .with_fit_span(2.0 / P as f64)?)
}

fn validate(
    plan: &Plan,
    truth: &DoublePendulum,
    run: &MultiTrajectory,
    wrapped: &[Vec<f64>],
    models: &[Identified],
) -> anyhow::Result<Validation> {
    let n = P * plan.periods;
    let section_of =
        |system: &dyn MultiSystem, start: [f64; 2]| -> anyhow::Result<Result<MultiTrajectory, String>> {
            let config = sampling(plan.section_points, start)?;
            Ok(multi::poincare_section(system, &config).map_err(|e| e.to_string()))
        };
    let mut sections = vec![
        Section {
            label: "true double pendulum".to_owned(),
            points: section_of(truth, START)?,
        },
        Section {
            label: format!(
                "true double pendulum from ({}, {})",
                FLOOR_START[0], FLOOR_START[1]
            ),
            points: section_of(truth, FLOOR_START)?,
        },
    ];
    for m in models {
        sections.push(Section {
            label: m.label.to_owned(),
            points: section_of(&m.system, START)?,
        });
    }
    // Each model from the floor's start too: another draw of its section (after the models', which
    // the figures take in order).
    for m in models {
        sections.push(Section {
            label: format!("{} from ({}, {})", m.label, FLOOR_START[0], FLOOR_START[1]),
            points: section_of(&m.system, FLOOR_START)?,
        });
    }
    // The held-out continuation.
    let clock = SampleClock::nondimensional(P)?.with_start_time(run.t[n])?;
    let record =
        SystemPredictionRecord::new(&[&wrapped[0][n..], &wrapped[1][n..]], clock, &[Domain::Circle; 2])?;
    let config = prediction_config(plan.windows)?;
    let starts = system_prediction_starts(&record, &config)?;
    let mut prediction = vec![(
        "true double pendulum".to_owned(),
        system_valid_prediction_times(truth, &record, &starts, &config)?,
    )];
    for m in models {
        prediction.push((
            m.label.to_owned(),
            system_valid_prediction_times(&m.system, &record, &starts, &config)?,
        ));
    }
    let state = |k: usize| MultiState::new(&[run.q[0][k], run.q[1][k]], &[run.v[0][k], run.v[1][k]]);
    let windows = starts
        .iter()
        .map(|&s| Ok(predict_system_window(truth, &record, s, &state(n + s)?, &config)?))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let exact = SystemPredictionTimes {
        windows,
        ..prediction[0].1.clone()
    };
    let times = &run.t[n..n + P * SHOWN_PERIODS];
    let runs = models
        .iter()
        .map(|m| Ok(multi::free_run(&m.system, times, &state(n)?, tolerances()?)?))
        .collect::<anyhow::Result<Vec<_>>>()?;
    Ok(Validation {
        sections,
        prediction,
        exact,
        runs,
    })
}

fn validation_text(
    report: &mut String,
    plan: &Plan,
    v: &Validation,
    models: &[Identified],
) -> anyhow::Result<()> {
    writeln!(report, "### Validation: free runs of the identified systems\n")?;
    writeln!(
        report,
        "*Sections*: each system from rest at θ = ({}, {}) after {TRANSIENT} periods of transient, {} points \
         once per drive period (phase 0). *Section distance*: the energy distance to the truth's section with \
         the torus and the velocities embedded in R⁶ as (cos θ1, sin θ1, cos θ2, sin θ2, θ1', θ2'), estimated \
         without bias; the *floor* is the truth against itself from another start (θ = ({}, {})): distances of \
         its size mean that the sections cannot be told apart with this many points. *Whirling*: passages of \
         each link over the top per drive period along the section.\n",
        START[0], START[1], plan.section_points, FLOOR_START[0], FLOOR_START[1]
    )?;
    writeln!(
        report,
        "| system | section distance to the truth | link 1 passages per period | link 2 passages per period |\n\
         | --- | --- | --- | --- |"
    )?;
    let reference = v.sections[0].points.as_ref().ok().map(embedded);
    for (i, s) in v.sections.iter().enumerate() {
        match &s.points {
            Ok(points) => {
                let distance = if i == 0 {
                    "0 (reference)".to_owned()
                } else {
                    reference
                        .as_ref()
                        .and_then(|r| energy_distance(r, &embedded(points)))
                        .map_or("n/a".to_owned(), |d| format!("{d:.2e}"))
                };
                let rate =
                    |c: usize| passages(&points.q[c]) as f64 / points.len().saturating_sub(1).max(1) as f64;
                writeln!(
                    report,
                    "| {} | {distance} | {:.3} | {:.3} |",
                    s.label,
                    rate(0),
                    rate(1)
                )?;
            }
            Err(why) => writeln!(report, "| {} | its simulation stopped: {why} | | |", s.label)?,
        }
    }
    writeln!(
        report,
        "\nThe free runs are chaotic: a system run from another start, or with its coefficients changed in \
         their last digits, follows another trajectory on its attractor, and its section is another draw of {} \
         points. The rows \"from ({}, {})\" are such draws, the truth's and each system's: how far a system's \
         two distances lie apart is how far these figures can move without any change of the system. They tell \
         a system whose sections differ (distances many times those) from one whose sections cannot be told \
         apart; the coefficients' errors above are the finer measure.\n",
        plan.section_points, FLOOR_START[0], FLOOR_START[1]
    )?;
    let first = &v.prediction[0].1;
    writeln!(
        report,
        "*Valid prediction time* (`pendulum_sim::prediction::system_valid_prediction_times`): from the held-out \
         record's own state at {} samples spread over it (both angles and velocities, each from a polynomial of \
         degree 4 through the two samples each side of it: at {P} samples per period the default fit over a \
         twelfth of a period smooths the links' sharpest turns), each system is integrated until **either** \
         angle is further from the record than a tenth of that angle's spread ({:.4} and {:.4} rad); the median \
         over the windows in drive periods (quartiles in brackets), the windows that reached the horizon of {} \
         periods, and which link left first.\n",
        first.windows.len(),
        first.tolerances[0],
        first.tolerances[1],
        PredictionConfig::DEFAULT_HORIZON
    )?;
    writeln!(
        report,
        "| system | median (periods) | windows reaching the horizon | link 1 left first | link 2 left first |\n\
         | --- | --- | --- | --- | --- |"
    )?;
    let row = |report: &mut String, label: &str, t: &SystemPredictionTimes| -> anyhow::Result<()> {
        let cell = t.in_periods().map_or("n/a".to_owned(), |s| {
            format!(
                "{}{:.2} ({:.2}–{:.2})",
                if s.median_is_lower_bound() { "≥ " } else { "" },
                s.median,
                s.lower_quartile,
                s.upper_quartile
            )
        });
        let censored = t.windows.iter().filter(|w| w.censored).count();
        writeln!(
            report,
            "| {label} | {cell} | {censored} of {} | {} | {} |",
            t.windows.len(),
            t.left_by(0),
            t.left_by(1)
        )?;
        Ok(())
    };
    for (label, t) in &v.prediction {
        row(report, label, t)?;
    }
    row(report, "true double pendulum, exact states", &v.exact)?;
    writeln!(report)?;
    for (m, r) in models.iter().zip(&v.runs) {
        if let Some(why) = &r.stopped {
            writeln!(
                report,
                "The free run of the {} system for the figures stopped: {why}.\n",
                m.label
            )?;
        }
    }
    Ok(())
}

/// The section's figures: both angles' time series, the Poincaré sections, a phase portrait and
/// a vector orbit; their files and captions.
fn figures(
    out: &Path,
    run: &MultiTrajectory,
    wrapped: &[Vec<f64>],
    n: usize,
    segments: &[Segment],
    v: &Validation,
    models: &[Identified],
) -> anyhow::Result<Vec<(String, String)>> {
    let mut figures = Vec::new();
    let angle = Style::Line { break_above: PI };
    let range = Some((-PI, PI));
    let colors = [ORANGE, BLUE];
    // Both angles from the held-out continuation's first state: the record and each model.
    let shown = P * SHOWN_PERIODS;
    let period = |k: usize| (run.t[n + k] - run.t[n]) / TAU;
    for (c, record) in wrapped.iter().enumerate() {
        let mut series = Vec::new();
        for ((m, r), color) in models.iter().zip(&v.runs).zip(colors) {
            series.push(Series {
                label: m.label,
                points: (0..shown)
                    .filter(|&k| r.q[c][k].is_finite())
                    .map(|k| (period(k), wrap(r.q[c][k])))
                    .collect(),
                style: angle,
                color,
            });
        }
        // The record last, as dots: where a model follows it, the dots lie on its line.
        series.push(Series {
            label: "truth (the record)",
            points: (0..shown).map(|k| (period(k), record[n + k])).collect(),
            style: Style::Dots(1),
            color: INK,
        });
        let name = format!("fig_dp_theta{}_time_series.png", c + 1);
        let title = format!(
            "Double pendulum: θ{} of the truth and the identified systems",
            c + 1
        );
        let y_label = format!("theta{} (wrapped)", c + 1);
        Figure {
            title: &title,
            x_label: "drive periods since the held-out record's start",
            y_label: &y_label,
            series,
            x_range: None,
            y_range: range,
        }
        .save(&out.join(&name))?;
        hb_plot::add_figure(
            &mut figures,
            name,
            format!(
                "θ{} over {SHOWN_PERIODS} drive periods: the held-out record (dots), and each identified system \
                 run freely from the record's exact state at its start.",
                c + 1
            ),
        );
    }
    // Poincaré sections in the torus of the angles: the truth against each model.
    if let Ok(truth) = &v.sections[0].points {
        let torus = |s: &MultiTrajectory| -> Vec<(f64, f64)> {
            (0..s.len()).map(|i| (wrap(s.q[0][i]), wrap(s.q[1][i]))).collect()
        };
        for ((m, s), color) in models.iter().zip(&v.sections[2..]).zip(colors) {
            let Ok(points) = &s.points else {
                continue;
            };
            let method = m.report.method.name();
            let name = format!("fig_dp_poincare_{method}.png");
            let title = format!("Double pendulum: Poincaré section, truth and {}", m.label);
            Figure {
                title: &title,
                x_label: "theta1 (wrapped)",
                y_label: "theta2 (wrapped)",
                series: vec![
                    Series {
                        label: "truth",
                        points: torus(truth),
                        style: Style::Dots(2),
                        color: GREY,
                    },
                    Series {
                        label: m.label,
                        points: torus(points),
                        style: Style::Dots(2),
                        color,
                    },
                ],
                x_range: range,
                y_range: range,
            }
            .save(&out.join(&name))?;
            hb_plot::add_figure(
                &mut figures,
                name,
                format!(
                    "Poincaré section (phase 0) in the angles' torus: the true double pendulum and the system \
                     identified by {}, both from the same start.",
                    m.label
                ),
            );
        }
    }
    // The record's phase portrait, each link.
    let portrait = |c: usize| -> Vec<(f64, f64)> {
        (0..n.min(P * 200))
            .map(|k| (wrapped[c][k], run.v[c][k]))
            .collect()
    };
    let name = "fig_dp_phase_portrait.png";
    Figure {
        title: "Double pendulum: phase portrait of each link (first 200 drive periods)",
        x_label: "angle (wrapped)",
        y_label: "angular velocity",
        series: vec![
            Series {
                label: "link 1",
                points: portrait(0),
                style: Style::Dots(1),
                color: BLUE,
            },
            Series {
                label: "link 2",
                points: portrait(1),
                style: Style::Dots(1),
                color: ORANGE,
            },
        ],
        x_range: range,
        y_range: None,
    }
    .save(&out.join(name))?;
    hb_plot::add_figure(
        &mut figures,
        name,
        "Phase portrait of the record: each link's wrapped angle against its velocity.",
    );
    // The shortest vector orbit found (the first of its period), in the angles' torus.
    if let Some(orbit) = segments.iter().min_by_key(|s| s.period()) {
        let points = |c: usize| -> Vec<f64> { wrapped[c][orbit.start()..=orbit.closing()].to_vec() };
        let (a, b) = (points(0), points(1));
        let name = "fig_dp_vector_orbit.png";
        let title = format!("Double pendulum: a period-{} vector orbit", orbit.period());
        Figure {
            title: &title,
            x_label: "theta1 (wrapped)",
            y_label: "theta2 (wrapped)",
            series: vec![
                Series {
                    label: "",
                    points: a.iter().copied().zip(b.iter().copied()).collect(),
                    style: angle,
                    color: RED,
                },
                Series {
                    label: "start and closing sample",
                    points: vec![(a[0], b[0]), (a[a.len() - 1], b[b.len() - 1])],
                    style: Style::Dots(5),
                    color: GREY,
                },
            ],
            x_range: range,
            y_range: range,
        }
        .save(&out.join(name))?;
        hb_plot::add_figure(
            &mut figures,
            name,
            format!(
                "A period-{} vector orbit from the close-return search in the angles' torus: both links return \
                 together (closing error {:.4} rad).",
                orbit.period(),
                orbit.error()
            ),
        );
    }
    Ok(figures)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn passages_count_each_crossing_of_the_top() {
        // Up over the top twice, back once: three crossings of ±π.
        let q = [0.0, 3.0, 3.3, 6.0, 9.6, 9.0, 8.0, 6.0];
        assert_eq!(passages(&q), 3);
        assert_eq!(passages(&[0.1, -0.2, 3.1]), 0);
    }

    #[test]
    fn the_true_terms_make_a_request_of_both_methods() {
        let terms = true_terms(&DoublePendulum::whirling());
        assert!(terms.starts_with("q1: q2''*cos(q1-q2)"), "{terms}");
        assert!(terms.contains("; q2: q1''*cos(q1-q2)"), "{terms}");
        for method in [Method::Upo, Method::Windowed] {
            let request = request(method, &terms).unwrap();
            assert_eq!(request.equations(), 2);
        }
    }
}
