//! The attractors of `hbid report` of a system: each coordinate's phase portrait of the record
//! beside each model's long run, and the stroboscopic (Poincaré) sections of both, in each
//! coordinate's plane and in the plane of the first two coordinates (the angles' torus), with
//! the energy distance between the sections.
//!
//! A model driven by its own periodic drive is run from the record's state at its first whole
//! drive period for [`TRANSIENT_PERIODS`] periods, then [`RUN_PERIODS`] more are kept (the
//! reproduction's sections of the double pendulum are drawn the same way). A model driven by
//! measured drives can run only where they were measured: its phase portrait is its free run
//! over the record (`hbid compare`'s), and there is no stroboscopic section.

use std::f64::consts::{PI, TAU};
use std::fmt::Write as _;
use std::path::Path;

use circle_signal::{Domain, SampleClock, wrap};
use hb_model::IdentifiedSystem;
use hb_plot::{BLUE, Figure, GREEN, GREY, ORANGE, PURPLE, RGBColor, Series, Style, add_figure, save_row};
use hb_record::prepare::GridData;
use pendulum_sim::multi::{self, MultiState};
use pendulum_sim::prediction::{SystemPredictionRecord, estimate_system_state};
use pendulum_sim::{PredictionConfig, Tolerances, energy_distance};

use super::{Entry, Measured};

/// Drive periods of each model's long run that are kept: its phase portrait, and the points of
/// its section. The record's phase portrait shows as many of its first periods.
pub(super) const RUN_PERIODS: usize = 300;
/// Drive periods each long run is integrated for before the kept ones, to forget its start.
pub(super) const TRANSIENT_PERIODS: usize = 100;
/// Samples per drive period of a long run.
const RUN_SAMPLES_PER_PERIOD: usize = 64;
/// The long run's relative tolerance (the absolute one a tenth of it): a chaotic run leaves any
/// one trajectory within a few periods whatever the tolerance, and its attractor is drawn as
/// well at 1e-8 as at the free run's 1e-10, in half the steps.
const RUN_RTOL: f64 = 1e-8;

/// A state: every coordinate (continuous), then every velocity.
type State = Vec<f64>;

/// Where the record's velocities come from.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Velocities {
    /// The record's measured velocity columns (`--velocity-col`).
    Measured,
    /// The local polynomial fit of the prediction test.
    Estimated,
}

/// The record's side: its phase portrait and section.
pub(super) struct RecordAttractor {
    /// Each coordinate's points `(q, q')` (an angle wrapped into [−π, π)), or why there are none.
    portrait: Result<Vec<Vec<(f64, f64)>>, String>,
    velocities: Velocities,
    /// Drive periods of the record the portrait shows.
    portrait_periods: f64,
    /// The drive period `T` (of the first model).
    period: f64,
    /// The section once per drive period at phase 0 (`t` a whole multiple of `T`): its times and
    /// states, or why there is none.
    section: Result<Vec<(f64, State)>, String>,
    /// Where each model's long run starts: the first point of the section, or without one the
    /// record's first state.
    start: Option<(f64, State)>,
}

/// One model's side: its phase portrait and section.
pub(super) struct ModelAttractor {
    /// Each coordinate's points `(q, q')`.
    portrait: Vec<Vec<(f64, f64)>>,
    /// The section of its long run (none for a model driven by measured drives).
    section: Option<Vec<State>>,
    /// Why the run stopped early, if it did.
    stopped: Option<String>,
}

/// Both sides: the record's and each model's (in the order of the entries).
pub(super) struct Attractors {
    record: RecordAttractor,
    models: Vec<ModelAttractor>,
    /// Why there is no stroboscopic section, when there is none.
    no_section: Option<String>,
}

/// Why `system` has no stroboscopic section, if it has none: it is driven by measured drives
/// (which have no period and end with the record), or by no drive at all.
fn no_section(system: &IdentifiedSystem) -> Option<String> {
    if system.has_measured_drive() {
        let drives = system.names().drives();
        Some(format!(
            "the system is driven by the record's measured drive{} ({}), which {} no period and cannot be run \
             beyond the record",
            if drives.len() == 1 { "" } else { "s" },
            drives.join(", "),
            if drives.len() == 1 { "has" } else { "have" }
        ))
    } else if system
        .equations()
        .iter()
        .all(|m| m.form().highest_drive_harmonic() == 0)
    {
        Some("the system has no term in the drive's phase (no periodic drive)".to_owned())
    } else {
        None
    }
}

/// `x` as shown: an angle wrapped into [−π, π).
fn shown(x: f64, domain: Domain) -> f64 {
    match domain {
        Domain::Circle => wrap(x),
        Domain::Line => x,
    }
}

/// The record's states at its samples: the samples with their measured velocities, or each
/// coordinate and its velocity from the local polynomial fit of the prediction test.
struct RecordStates<'a> {
    samples: Vec<&'a [f64]>,
    measured: Option<&'a [Vec<f64>]>,
    record: Result<SystemPredictionRecord<'a>, String>,
    config: PredictionConfig,
}

impl<'a> RecordStates<'a> {
    fn new(grid: &'a GridData, period: f64, domains: &[Domain]) -> Self {
        let samples: Vec<&[f64]> = std::iter::once(grid.x.as_slice())
            .chain(grid.others.iter().map(|c| c.x.as_slice()))
            .collect();
        let measured = (grid.velocities.len() == samples.len()).then_some(grid.velocities.as_slice());
        let record = SampleClock::from_step(period, grid.dt)
            .and_then(|clock| clock.with_start_time(grid.t0))
            .map_err(|e| e.to_string())
            .and_then(|clock| {
                SystemPredictionRecord::new(&samples, clock, domains).map_err(|e| e.to_string())
            });
        Self {
            samples,
            measured,
            record,
            config: PredictionConfig::default(),
        }
    }

    fn velocities(&self) -> Velocities {
        if self.measured.is_some() {
            Velocities::Measured
        } else {
            Velocities::Estimated
        }
    }

    /// The state at sample `i`, if the record has one there.
    fn at(&self, i: usize) -> Option<State> {
        match self.measured {
            Some(v) => {
                let state: State = self
                    .samples
                    .iter()
                    .map(|s| s[i])
                    .chain(v.iter().map(|v| v[i]))
                    .collect();
                state.iter().all(|x| x.is_finite()).then_some(state)
            }
            None => {
                let record = self.record.as_ref().ok()?;
                let state = estimate_system_state(record, i, &self.config).ok()?;
                Some(state.q().iter().chain(state.v()).copied().collect())
            }
        }
    }
}

/// The record's phase portrait and section, on the drive period of `system`.
fn record_attractor(system: &IdentifiedSystem, grid: &GridData) -> RecordAttractor {
    let domains = system.domains();
    let n = domains.len();
    let period = TAU / system.drive_angular_frequency();
    let states = RecordStates::new(grid, period, domains);
    let len = grid.x.len();
    let shown_samples = ((RUN_PERIODS as f64 * period / grid.dt).ceil() as usize).min(len);
    let why = states.record.as_ref().err().filter(|_| states.measured.is_none());
    let portrait = match why {
        Some(why) => Err(format!("no velocities of the record: {why}")),
        None => {
            let mut points = vec![Vec::with_capacity(shown_samples); n];
            for i in 0..shown_samples {
                if let Some(s) = states.at(i) {
                    for (c, p) in points.iter_mut().enumerate() {
                        p.push((shown(s[c], domains[c]), s[n + c]));
                    }
                }
            }
            Ok(points)
        }
    };
    let section = match (no_section(system), why) {
        (Some(why), _) => Err(why),
        (None, Some(why)) => Err(format!("no velocities of the record: {why}")),
        (None, None) => Ok(record_section(&states, grid, period, domains)),
    };
    let start = match &section {
        Ok(points) => points.first().cloned(),
        Err(_) => (0..len).find_map(|i| Some((grid.t0 + i as f64 * grid.dt, states.at(i)?))),
    };
    RecordAttractor {
        portrait,
        velocities: states.velocities(),
        portrait_periods: shown_samples as f64 * grid.dt / period,
        period,
        section,
        start,
    }
}

/// The record's states at every whole multiple of `period` within it, each interpolated
/// linearly between the samples either side (an angle along its shorter arc).
fn record_section(
    states: &RecordStates<'_>,
    grid: &GridData,
    period: f64,
    domains: &[Domain],
) -> Vec<(f64, State)> {
    let n = domains.len();
    let len = grid.x.len();
    if len < 2 {
        return Vec::new();
    }
    let first = (grid.t0 / period).ceil() as i64;
    let last = ((grid.t0 + (len - 1) as f64 * grid.dt) / period).floor() as i64;
    let mut points = Vec::new();
    for k in first..=last {
        let t = k as f64 * period;
        let u = ((t - grid.t0) / grid.dt).max(0.0);
        let i = (u.floor() as usize).min(len - 2);
        let f = (u - i as f64).clamp(0.0, 1.0);
        let (Some(a), Some(b)) = (states.at(i), states.at(i + 1)) else {
            continue;
        };
        let state: State = (0..2 * n)
            .map(|j| {
                let step = match (j < n, domains[j % n]) {
                    (true, Domain::Circle) => wrap(b[j] - a[j]),
                    _ => b[j] - a[j],
                };
                a[j] + f * step
            })
            .collect();
        points.push((t, state));
    }
    points
}

/// The long run of `system` from the record's first section point (or its first state), sampled
/// [`RUN_SAMPLES_PER_PERIOD`] times per drive period on the grid of whole fractions of the
/// period, so that every [`RUN_SAMPLES_PER_PERIOD`]-th sample is at the drive's phase 0.
fn long_run(system: &IdentifiedSystem, start: (f64, &[f64]), period: f64) -> anyhow::Result<ModelAttractor> {
    let n = system.coordinates();
    let domains = system.domains();
    let p = RUN_SAMPLES_PER_PERIOD;
    let h = period / p as f64;
    let (t_start, state) = start;
    // The grid's index of the first time after the start, and the run's times.
    let first = (t_start / h).floor() as i64 + 1;
    let count = (TRANSIENT_PERIODS + RUN_PERIODS) * p;
    let times: Vec<f64> = std::iter::once(t_start)
        .chain((0..count as i64).map(|j| (first + j) as f64 * h))
        .collect();
    let run = multi::free_run(
        system,
        &times,
        &MultiState::new(&state[..n], &state[n..])?,
        Tolerances::new(RUN_RTOL, RUN_RTOL / 10.0)?,
    )?;
    let kept = 1 + TRANSIENT_PERIODS * p;
    let mut portrait = vec![Vec::with_capacity(RUN_PERIODS * p); n];
    let mut section = Vec::with_capacity(RUN_PERIODS);
    for k in kept..times.len() {
        if !(0..n).all(|c| run.q[c][k].is_finite() && run.v[c][k].is_finite()) {
            break;
        }
        for (c, points) in portrait.iter_mut().enumerate() {
            points.push((shown(run.q[c][k], domains[c]), run.v[c][k]));
        }
        if (first + k as i64 - 1).rem_euclid(p as i64) == 0 {
            section.push(
                (0..n)
                    .map(|c| run.q[c][k])
                    .chain((0..n).map(|c| run.v[c][k]))
                    .collect(),
            );
        }
    }
    Ok(ModelAttractor {
        portrait,
        section: Some(section),
        stopped: run.stopped.map(|e| e.to_string()),
    })
}

/// The free run of `entry` over the record (`hbid compare`'s, its first range), as a phase
/// portrait of the record's first periods.
fn run_over_record(entry: &Entry, m: &Measured, record: &RecordAttractor, dt: f64) -> ModelAttractor {
    let domains = entry.system.domains();
    let shown_samples = (record.portrait_periods * record.period / dt).round() as usize;
    let portrait = (0..entry.system.coordinates())
        .map(|c| {
            m.compare.runs.get(c).map_or_else(Vec::new, |pieces| {
                pieces
                    .iter()
                    .flat_map(|piece| {
                        (0..piece.t.len())
                            .filter(move |&i| piece.start + i < shown_samples)
                            .map(move |i| (piece.x[i], piece.v[i]))
                    })
                    .filter(|(x, v)| x.is_finite() && v.is_finite())
                    .map(|(x, v)| (shown(x, domains[c]), v))
                    .collect()
            })
        })
        .collect();
    let stride = m.compare.coordinates.len().max(1);
    let stopped = m
        .compare
        .ranges
        .iter()
        .step_by(stride)
        .find_map(|s| s.stopped.clone());
    ModelAttractor {
        portrait,
        section: None,
        stopped,
    }
}

/// The record's attractor and each model's.
pub(super) fn measure(
    entries: &[Entry],
    measured: &[Measured],
    grid: &GridData,
) -> anyhow::Result<Attractors> {
    let record = record_attractor(&entries[0].system, grid);
    let no_section = no_section(&entries[0].system);
    let models = entries
        .iter()
        .zip(measured)
        .map(|(entry, m)| {
            if entry.system.has_measured_drive() {
                return Ok(run_over_record(entry, m, &record, grid.dt));
            }
            match &record.start {
                Some((t, state)) => {
                    let mut run = long_run(&entry.system, (*t, state), record.period)?;
                    if no_section.is_some() {
                        run.section = None;
                    }
                    Ok(run)
                }
                None => Ok(ModelAttractor {
                    portrait: vec![Vec::new(); entry.system.coordinates()],
                    section: None,
                    stopped: Some("the record has no state to start from".to_owned()),
                }),
            }
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    Ok(Attractors {
        record,
        models,
        no_section,
    })
}

/// A state as the energy distance reads it: an angle as the point `(cos, sin)` on its circle, a
/// displacement as it is, then the velocities.
fn embedded(state: &[f64], domains: &[Domain]) -> Vec<f64> {
    let n = domains.len();
    let mut out = Vec::with_capacity(3 * n);
    for (c, &domain) in domains.iter().enumerate() {
        match domain {
            Domain::Circle => out.extend([state[c].cos(), state[c].sin()]),
            Domain::Line => out.push(state[c]),
        }
    }
    out.extend_from_slice(&state[n..]);
    out
}

/// The colours of the models' panels, in the order of the entries.
const COLORS: [RGBColor; 4] = [ORANGE, BLUE, GREEN, PURPLE];

/// The panels of one figure: the record's, then each model's, each a scatter of `points`.
fn panels<'a>(
    titles: &'a [String],
    x_label: &'a str,
    y_label: &'a str,
    points: Vec<Vec<(f64, f64)>>,
    dots: u32,
    x_range: Option<(f64, f64)>,
    y_range: Option<(f64, f64)>,
) -> Vec<Figure<'a>> {
    titles
        .iter()
        .zip(points)
        .enumerate()
        .map(|(k, (title, points))| Figure {
            title,
            x_label,
            y_label,
            series: vec![Series {
                label: "",
                points,
                style: Style::Dots(dots),
                color: if k == 0 {
                    GREY
                } else {
                    COLORS[(k - 1) % COLORS.len()]
                },
            }],
            x_range,
            y_range,
        })
        .collect()
}

/// The label of a coordinate's axis: an angle is shown wrapped.
fn axis_label(name: &str, domain: Domain) -> String {
    match domain {
        Domain::Circle => format!("{name} (wrapped)"),
        Domain::Line => name.to_owned(),
    }
}

/// The points of a section's panels: the record's section, then each model's, each state
/// projected onto the panel's axes by `project`.
fn section_points(
    record: &[(f64, State)],
    models: &[ModelAttractor],
    project: impl Fn(&State) -> (f64, f64),
) -> Vec<Vec<(f64, f64)>> {
    std::iter::once(record.iter().map(|(_, s)| project(s)).collect())
        .chain(
            models
                .iter()
                .map(|m| m.section.iter().flatten().map(&project).collect()),
        )
        .collect()
}

/// Draws a row of panels into `file` under `out` and lists it in `figures` with `caption`.
fn draw_row(
    out: &Path,
    figures: &mut Vec<(String, String)>,
    file: String,
    row: &[Figure<'_>],
    caption: String,
) -> anyhow::Result<()> {
    save_row(row, &out.join(&file))?;
    add_figure(figures, file, caption);
    Ok(())
}

/// The range of an axis of `domain`: [−π, π] for an angle, the data's otherwise.
fn range(domain: Domain) -> Option<(f64, f64)> {
    match domain {
        Domain::Circle => Some((-PI, PI)),
        Domain::Line => None,
    }
}

/// The section's text, `sections.json` and figures: each coordinate's phase portrait and
/// section, and the section in the plane of the first two coordinates.
pub(super) fn section(
    r: &mut String,
    figures: &mut Vec<(String, String)>,
    out: &Path,
    entries: &[Entry],
    a: &Attractors,
) -> anyhow::Result<()> {
    let system = &entries[0].system;
    let names = system.names().coordinates();
    let domains = system.domains();
    let n = names.len();
    let record = &a.record;
    writeln!(r, "## Phase portraits and Poincaré sections\n")?;
    let velocities = match record.velocities {
        Velocities::Measured => "its measured velocity columns".to_owned(),
        Velocities::Estimated => format!(
            "the local polynomial of degree 4 through the samples within a twelfth of {}, as the prediction test \
             below estimates them",
            if a.no_section.is_some() {
                "T"
            } else {
                "a drive period"
            }
        ),
    };
    let run = match &a.no_section {
        Some(_) if system.has_measured_drive() => {
            "each model's free run over the same span of the record, driven by the record's measured drives (the \
             free run above)"
                .to_owned()
        }
        Some(_) => format!(
            "each model's long run from the record's first state: {TRANSIENT_PERIODS} periods T left out as \
             transient, then {RUN_PERIODS} periods at {RUN_SAMPLES_PER_PERIOD} samples per period"
        ),
        None => format!(
            "each model's long run on its own drive: from the record's state at its first whole drive period, \
             {TRANSIENT_PERIODS} periods of transient left out, then {RUN_PERIODS} periods at \
             {RUN_SAMPLES_PER_PERIOD} samples per period"
        ),
    };
    let span = if a.no_section.is_some() {
        format!(
            "{:.2} units of time ({:.0} periods T = {:.4} of the record's clock, which has no drive period)",
            record.portrait_periods * record.period,
            record.portrait_periods,
            record.period
        )
    } else {
        format!("{:.0} drive periods", record.portrait_periods)
    };
    writeln!(
        r,
        "Each coordinate against its velocity{}: the record's first {span}, its velocities from {velocities}, \
         beside {run}.\n",
        if domains.contains(&Domain::Circle) {
            " (an angle wrapped into [−π, π))"
        } else {
            ""
        },
    )?;
    if let Err(why) = &record.portrait {
        writeln!(r, "The record has no phase portrait: {why}.\n")?;
    }
    for (entry, m) in entries.iter().zip(&a.models) {
        if let Some(why) = &m.stopped {
            writeln!(r, "{}: the run stopped: {why}.\n", entry.name)?;
        }
    }
    let mut json = serde_json::json!({ "drive_period": record.period });
    let strobe = match (&a.no_section, &record.section) {
        (Some(why), _) => {
            writeln!(
                r,
                "There is no stroboscopic section: {why}. Each model's attractor is shown by its phase portrait \
                 alone.\n"
            )?;
            json["no_section"] = serde_json::json!(why);
            None
        }
        (None, Err(why)) => {
            writeln!(r, "There is no stroboscopic section of the record: {why}.\n")?;
            json["no_section"] = serde_json::json!(why);
            None
        }
        (None, Ok(points)) => Some(points),
    };
    if let Some(points) = strobe {
        let record_points: Vec<Vec<f64>> = points.iter().map(|(_, s)| embedded(s, domains)).collect();
        let half = record_points.len() / 2;
        let floor = energy_distance(&record_points[..half], &record_points[half..]);
        let fmt = |v: Option<f64>| v.map_or("n/a".to_owned(), |v| format!("{v:.2e}"));
        writeln!(
            r,
            "The Poincaré section: the state once per drive period at the drive's phase 0 (t a whole multiple of \
             the period {:.6}): the record's {} points (each interpolated between the samples either side) and each \
             model's points of its long run. The energy distance between the record's section and a model's reads \
             every coordinate and velocity at once ({}), estimated without bias; the floor is the distance between \
             the two halves of the record's section ({}): a distance of that order means the model's attractor \
             cannot be told from the record's with this many points.\n",
            record.period,
            points.len(),
            if domains.contains(&Domain::Circle) {
                "an angle as the point (cos, sin) on its circle"
            } else {
                "in the record's units"
            },
            fmt(floor)
        )?;
        writeln!(
            r,
            "| model | section points | energy distance to the record's section |\n| --- | --- | --- |"
        )?;
        let mut models = Vec::new();
        for (entry, m) in entries.iter().zip(&a.models) {
            let model_points: Vec<Vec<f64>> =
                m.section.iter().flatten().map(|s| embedded(s, domains)).collect();
            let distance = energy_distance(&record_points, &model_points);
            writeln!(
                r,
                "| {} | {} | {} |",
                entry.name,
                model_points.len(),
                fmt(distance)
            )?;
            models.push(serde_json::json!({
                "model": entry.name,
                "points": model_points.len(),
                "distance": distance,
                "stopped": m.stopped,
            }));
        }
        writeln!(r)?;
        json["record_points"] = serde_json::json!(points.len());
        json["floor"] = serde_json::json!(floor);
        json["models"] = serde_json::json!(models);
        writeln!(r, "The distances are in `sections.json`.\n")?;
    }
    let text = serde_json::to_string_pretty(&json)?;
    hb_pipeline::output::write_atomically(&out.join("sections.json"), |w| writeln!(w, "{text}"))?;

    // Each coordinate's phase portrait and section: the record, then each model.
    let who: Vec<&str> = std::iter::once("the record")
        .chain(entries.iter().map(|e| e.name.as_str()))
        .collect();
    for (c, name) in names.iter().enumerate() {
        let x_label = axis_label(name, domains[c]);
        let y_label = format!("{name}'");
        if let Ok(portrait) = &record.portrait {
            let titles: Vec<String> = who.iter().map(|w| format!("{name}: {w}")).collect();
            let points = std::iter::once(portrait[c].clone())
                .chain(a.models.iter().map(|m| m.portrait[c].clone()))
                .collect();
            let caption = format!(
                "Phase portrait of {name}: the record (grey) beside {} on the same axes.",
                match &a.no_section {
                    Some(_) if system.has_measured_drive() => "each model's free run over the record",
                    _ => "each model's long run",
                }
            );
            let row = panels(&titles, &x_label, &y_label, points, 1, range(domains[c]), None);
            draw_row(out, figures, format!("portrait_{name}.png"), &row, caption)?;
        }
        if let Some(points) = strobe {
            let titles: Vec<String> = who.iter().map(|w| format!("{name} at phase 0: {w}")).collect();
            let points = section_points(points, &a.models, |s| (shown(s[c], domains[c]), s[n + c]));
            let caption = format!(
                "Poincaré section of {name} against its velocity, once per drive period at phase 0: the record \
                 (grey) beside each model's long run."
            );
            let row = panels(&titles, &x_label, &y_label, points, 2, range(domains[c]), None);
            draw_row(out, figures, format!("section_{name}.png"), &row, caption)?;
        }
    }
    if let (Some(points), [first, second, ..]) = (strobe, names) {
        let (x_label, y_label) = (axis_label(first, domains[0]), axis_label(second, domains[1]));
        let torus = domains[..2].iter().all(|&d| d == Domain::Circle);
        let titles: Vec<String> = who
            .iter()
            .map(|w| format!("{first}, {second} at phase 0: {w}"))
            .collect();
        let points = section_points(points, &a.models, |s| {
            (shown(s[0], domains[0]), shown(s[1], domains[1]))
        });
        let caption = format!(
            "Poincaré section in the {} of {first} and {second}, once per drive period at phase 0: the record \
             (grey) beside each model's long run.",
            if torus { "angles' torus" } else { "plane" }
        );
        let row = panels(
            &titles,
            &x_label,
            &y_label,
            points,
            2,
            range(domains[0]),
            range(domains[1]),
        );
        draw_row(
            out,
            figures,
            format!("section_{first}_{second}.png"),
            &row,
            caption,
        )?;
    }
    Ok(())
}
