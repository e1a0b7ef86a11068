//! `hbid report` of a system of several coordinates (`--coords`), or of a saved model
//! (`--model`): the equations' coefficients, the residuals of their fit, each model's free run
//! against the record (`hbid compare`'s) coordinate by coordinate, the phase portraits and
//! Poincaré sections of the record beside each model's ([`attractor`]), and its valid prediction
//! time, as a Markdown report with figures.
//!
//! Every number is computed before the first file is written: a run that fails (a bad option, a
//! record that does not fit the model) leaves no report behind, and README.md is written last.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Context;
use circle_signal::{Domain, SampleClock, wrap};
use hb_model::IdentifiedSystem;
use hb_pipeline::pipeline::Method;
use hb_pipeline::{
    ColumnList, CompareOptions, CompareReport, CompareRequest, IdentifyReport, IdentifyRequest, OptionError,
    RecordOptions, Source, Spelling,
};
use hb_plot::{BLUE, Figure, GREEN, INK, ORANGE, PURPLE, RED, Series, Style, add_figure};
use hb_record::prepare::{DriveFound, GridData};
use pendulum_sim::PredictionConfig;
use pendulum_sim::prediction::{
    SystemPredictionRecord, SystemPredictionTimes, system_prediction_starts, system_valid_prediction_times,
};

use super::report_args::{Kept, ReportArgs};
use crate::progress::Console;

mod attractor;

/// Drive periods of each free-run figure, from the end of the state's fit.
const SHOWN_PERIODS: f64 = 20.0;

/// One model of the report: identified here by a method, or read from a file.
struct Entry {
    /// Its name in tables and files: the method's (`upo`, `windowed`), or `model`.
    name: String,
    /// What it is, for the headings.
    how: String,
    system: IdentifiedSystem,
    /// The identification, when the report made it.
    identified: Option<IdentifyReport>,
}

/// What was measured of one model.
struct Measured {
    compare: CompareReport,
    /// The valid prediction times, or why there are none.
    prediction: Result<SystemPredictionTimes, String>,
    /// Whether the free runs start from the measured states (`--velocity-col`), every sample
    /// scored, rather than from states fitted to first samples.
    from_measured: bool,
}

/// The report of `args`: a system identified by both methods on the record, or the saved model of
/// `--model`, checked against the record.
pub fn run(args: &ReportArgs, quiet: bool) -> anyhow::Result<()> {
    // One record, a file.
    args.identify.input.source()?;
    let file = args.identify.input.file();
    let mut kept = Kept {
        console: Console::new("report", quiet, false),
        notices: Vec::new(),
    };
    let mut missing = Vec::new();
    let (entries, summary, grid) = match &args.model {
        Some(path) => {
            let system = hb_pipeline::read_model(path)?;
            // A velocity or acceleration record read as measured, and integrated with the
            // constants the model's equation holds best with, as `hbid compare` does.
            let mut options = record_options(args, &system)?;
            let measured = std::mem::take(&mut options.measured);
            // Checked before the record is read.
            let integrated = match (measured, system.equations()) {
                (circle_signal::Measured::Displacement, _) => None,
                (_, [model]) => {
                    hb_pipeline::integrated::check_model(model, measured)?;
                    Some(model)
                }
                _ => {
                    return Err(OptionError::new(
                        "measured",
                        "is for a record of one coordinate, not a system of several («coords»)",
                    )
                    .into());
                }
            };
            let mut grid = hb_pipeline::condition_source(Source::Path(file), &options, &mut kept)?;
            if let Some(model) = integrated {
                let found = hb_pipeline::integrated::integrate(model, &mut grid, measured)?;
                for notice in hb_pipeline::integrated::notices(measured, &found) {
                    hb_pipeline::Observer::notice(&mut kept, &notice);
                }
            }
            let summary = format!(
                "The saved model `{}` ({} coordinate(s): {}) against the record: {} samples in steps of {}.",
                path.display(),
                system.coordinates(),
                system.names().coordinates().join(", "),
                grid.pieces.iter().map(|p| p.len()).sum::<usize>(),
                grid.dt
            );
            let entry = Entry {
                name: "model".to_owned(),
                how: format!("the saved model `{}`", path.display()),
                system,
                identified: None,
            };
            (vec![entry], summary, grid)
        }
        None => {
            let request = args.identify.request_for_report()?;
            // Read with the measured velocities, which the free runs start from.
            let record = &args.identify.input.options();
            // Read and conditioned once: every model is identified on it and run against it.
            let grid = hb_pipeline::condition_source(Source::Path(file), record, &mut kept)?;
            let data = hb_pipeline::load(Source::Grid(grid.clone()), record, request.drive(), &mut kept)?;
            let mut entries = Vec::new();
            for method in args.methods() {
                let how = match method {
                    Method::Upo => {
                        "harmonic balance on vector orbits, the close returns of the whole state: the paper's method"
                    }
                    Method::Windowed => "the weak form on plain windows of the record",
                };
                let identified = IdentifyRequest::new(hb_pipeline::IdentifyOptions {
                    method,
                    ..request.options().clone()
                })
                .map_err(anyhow::Error::from)
                .and_then(|r| Ok(hb_pipeline::identify_data(&data, &r, &mut kept)?));
                match identified {
                    Ok(report) => entries.push(Entry {
                        name: method.name().to_owned(),
                        how: how.to_owned(),
                        system: report.system()?,
                        identified: Some(report),
                    }),
                    // The weak form is the one that needs no orbit: its failure is the report's.
                    // So is the failure of the one method asked for.
                    Err(e) if method == Method::Windowed || args.method_given => return Err(e),
                    Err(e) => missing.push((method, how, e)),
                }
            }
            let period = match data.drive {
                DriveFound::Given | DriveFound::Estimated { .. } => {
                    format!("; forcing period {}", data.clock.drive_period())
                }
                _ => String::new(),
            };
            let summary = format!(
                "A system of {} coordinates ({}): {}{period}.",
                request.equations(),
                request.names().coordinates().join(", "),
                data.summary(),
            );
            (entries, summary, grid)
        }
    };
    let measured = entries
        .iter()
        .map(|e| measure(args, e, &grid, &mut kept))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let attractors = attractor::measure(&entries, &measured, &grid)?;
    let Kept { console, notices } = kept;
    console.finish();
    // The summary, then the notes, each a paragraph.
    let intro: Vec<String> = std::iter::once(summary)
        .chain(
            notices
                .iter()
                .filter(|n| super::report::in_report(n))
                .map(|n| Spelling::CommandLine.render(&n.to_string())),
        )
        .collect();
    // Written beside the folder, then moved into it together.
    let staged = super::report::Staged::new(&args.out)?;
    write(
        staged.path(),
        file,
        &intro,
        &entries,
        &missing,
        &measured,
        &attractors,
    )?;
    staged.commit()
}

/// The record's options that read the coordinates of `system` (and its measured drives) as
/// `hbid compare` reads them: the columns of --coords, or the system's own.
fn record_options(args: &ReportArgs, system: &IdentifiedSystem) -> anyhow::Result<RecordOptions> {
    let input = &args.identify.input;
    let columns = system.columns();
    let as_columns = |names: &[String], columns: &[String]| -> anyhow::Result<ColumnList> {
        names
            .iter()
            .zip(columns)
            .map(|(name, column)| format!("{name}={column}"))
            .collect::<Vec<_>>()
            .join(",")
            .parse::<ColumnList>()
            .map_err(anyhow::Error::msg)
    };
    if let Some(c) = &input.coords
        && c.len() != system.coordinates()
    {
        return Err(OptionError::value(
            "coords",
            c,
            format!(
                "the model has {} coordinate(s) ({}): name one column per coordinate",
                system.coordinates(),
                system.names().coordinates().join(", ")
            ),
        )
        .into());
    }
    // A system's own columns; one coordinate's angle from the record's default column unless
    // saved with one, its drives by their names unless it is one model (the drive `p`).
    let coords = match &input.coords {
        Some(c) => Some(c.clone()),
        None if system.coordinates() > 1 || columns.coordinates != system.names().coordinates() => {
            Some(as_columns(system.names().coordinates(), &columns.coordinates)?)
        }
        None => None,
    };
    let drive_col = match &input.drive_col {
        Some(d) if system.has_measured_drive() => Some(d.clone()),
        None if system.has_measured_drive() && !system.is_one_model() => {
            Some(as_columns(system.names().drives(), &columns.drives)?)
        }
        _ => None,
    };
    Ok(RecordOptions {
        time_col: input.time_col.clone(),
        angle_col: input.angle_col.clone(),
        coords,
        dt: input.dt,
        drive_col,
        repair: input.repair,
        no_repair: input.no_repair,
        bridge_gaps: input.bridge_gaps,
        skip_missing: input.skip_missing,
        velocity_col: input.velocity_col.clone(),
        signal: system
            .domains()
            .iter()
            .map(ToString::to_string)
            .collect::<Vec<_>>()
            .join(",")
            .parse()
            .map_err(anyhow::Error::msg)?,
        measured: input.measured,
        angle_unit: input.angle_unit,
        ..RecordOptions::default()
    })
}

/// The free run of `entry` against the record on `grid` (`hbid compare`'s defaults), and its
/// valid prediction time from the record's own states.
fn measure(
    args: &ReportArgs,
    entry: &Entry,
    grid: &GridData,
    observer: &mut Kept,
) -> anyhow::Result<Measured> {
    let system = &entry.system;
    let input = &args.identify.input;
    let request = CompareRequest::new(CompareOptions {
        time_col: input.time_col.clone(),
        angle_col: input.angle_col.clone(),
        dt: input.dt,
        coords: input.coords.clone(),
        drive_col: input.drive_col.clone().filter(|_| system.has_measured_drive()),
        repair: input.repair,
        no_repair: input.no_repair,
        bridge_gaps: input.bridge_gaps,
        skip_missing: input.skip_missing,
        velocity_col: input.velocity_col.clone(),
        // A velocity or acceleration record is integrated once, when read.
        measured: circle_signal::Measured::Displacement,
        // On the record's grid, as the report draws it beside the models' runs.
        skip_unsettled: true,
        ..CompareOptions::default()
    })?;
    let compare = hb_pipeline::compare(system, Source::Grid(grid.clone()), &request, observer)
        .with_context(|| format!("the free run of {} against the record", entry.name))?;
    let prediction = if system.has_measured_drive() {
        Err("it reads a measured drive, which the prediction test does not give it".to_owned())
    } else {
        prediction(system, grid)?
    };
    Ok(Measured {
        compare,
        prediction,
        from_measured: input.velocity_col.is_some(),
    })
}

/// The valid prediction time of `system` on the record's grid (not resampled), or why there is
/// none.
fn prediction(
    system: &IdentifiedSystem,
    grid: &GridData,
) -> anyhow::Result<Result<SystemPredictionTimes, String>> {
    let period = std::f64::consts::TAU / system.drive_angular_frequency();
    let clock = SampleClock::from_step(period, grid.dt)?.with_start_time(grid.t0)?;
    let samples: Vec<&[f64]> = std::iter::once(grid.x.as_slice())
        .chain(grid.others.iter().map(|c| c.x.as_slice()))
        .collect();
    let config = PredictionConfig::default();
    Ok(SystemPredictionRecord::new(&samples, clock, system.domains())
        .and_then(|record| {
            let starts = system_prediction_starts(&record, &config)?;
            system_valid_prediction_times(system, &record, &starts, &config)
        })
        .map_err(|e| e.to_string()))
}

/// Writes the figures, `compare.json`, `sections.json`, `prediction.json`, the models and
/// README.md (last).
fn write(
    out: &Path,
    file: &Path,
    intro: &[String],
    entries: &[Entry],
    missing: &[(Method, &str, anyhow::Error)],
    measured: &[Measured],
    attractors: &attractor::Attractors,
) -> anyhow::Result<()> {
    let mut r = String::new();
    let mut figures: Vec<(String, String)> = Vec::new();
    writeln!(r, "# Identification report: {}\n", file.display())?;
    for paragraph in intro {
        writeln!(r, "{paragraph}\n")?;
    }
    for (method, how, error) in missing {
        writeln!(r, "## Identified system: {} ({how})\n", method.name())?;
        writeln!(
            r,
            "Not identified: {}.\n",
            Spelling::CommandLine.render(&crate::message(error))
        )?;
    }
    for entry in entries {
        equations_section(&mut r, out, entry)?;
    }
    residuals_section(&mut r, entries)?;
    compare_section(&mut r, &mut figures, out, entries, measured)?;
    attractor::section(&mut r, &mut figures, out, entries, attractors)?;
    prediction_section(&mut r, &mut figures, out, entries, measured)?;
    writeln!(r, "## Figures\n")?;
    for (file, caption) in &figures {
        writeln!(r, "![{caption}]({file})\n\n{caption}\n")?;
    }
    let path = out.join("README.md");
    hb_pipeline::output::write_atomically(&path, |w| w.write_all(r.as_bytes()))?;
    Ok(())
}

/// Each equation of `entry`: its line, its fit and its coefficients; the model saved (for one
/// identified here).
fn equations_section(r: &mut String, out: &Path, entry: &Entry) -> anyhow::Result<()> {
    let system = &entry.system;
    match &entry.identified {
        Some(report) => {
            writeln!(
                r,
                "## Identified system: {} ({}), basis {}\n",
                entry.name,
                entry.how,
                report.basis.spec()
            )?;
            writeln!(r, "{}.\n", report.found)?;
            if let Some(parameters) = &report.parameters {
                tied_parameters(r, parameters, report.parameter_intervals.as_ref())?;
            }
        }
        None => writeln!(r, "## The model: {}\n", entry.how)?,
    }
    for (i, model) in system.equations().iter().enumerate() {
        let own = &system.names().coordinates()[i];
        let identification = entry.identified.as_ref().map(|r| &r.equations[i].identification);
        writeln!(r, "### The equation of {own}\n")?;
        writeln!(r, "    {}\n", super::identify::equation_of(own, model))?;
        if let Some(s) = model.summary() {
            write!(
                r,
                "{} segments, {} equations, condition number {:.3e}, residual RMS {:.3e}",
                s.segments, s.rows, s.condition, s.residual_rms
            )?;
            match identification {
                Some(id) => writeln!(
                    r,
                    "; explained {:.6} of the balanced acceleration.\n",
                    id.quality.explained
                )?,
                None => writeln!(r, ".\n")?,
            }
        }
        if let Some(warning) = identification.and_then(|id| id.warning.as_ref()) {
            writeln!(r, "**Not a description of the record**: {warning}\n")?;
        }
        writeln!(
            r,
            "| term | coefficient | std. error | interval |\n| --- | --- | --- | --- |"
        )?;
        for c in model.coefficients() {
            let interval = identification
                .and_then(|id| id.intervals.as_ref())
                .and_then(|b| b.interval(&c.name))
                .map_or("—".to_owned(), |i| format!("[{:.6}, {:.6}]", i.lower, i.upper));
            writeln!(
                r,
                "| `{}` | {:.6} | {:.2e} | {interval} |",
                c.name, c.value, c.std_error
            )?;
        }
        writeln!(r)?;
    }
    if entry.identified.is_some() {
        let model_file = format!("model_{}.json", entry.name);
        let json = system.to_json()?;
        hb_pipeline::output::write_atomically(&out.join(&model_file), |w| w.write_all(json.as_bytes()))?;
        writeln!(
            r,
            "Saved as `{model_file}` (`hbid compare` and `hbid report --model` read it; \
             `hb_model::IdentifiedSystem::from_json` loads it).\n"
        )?;
    }
    Ok(())
}

/// A tied fit's physical parameters (`--tie`), which every equation's coefficients below are
/// made of.
fn tied_parameters(
    r: &mut String,
    parameters: &[hb_solve::TiedParameter],
    intervals: Option<&hb_solve::Bootstrap>,
) -> anyhow::Result<()> {
    writeln!(
        r,
        "### The tied parameters

Shared by the equations (`--tie`): each equation's coefficients below are \
         the spec's combinations of them, divided by its own acceleration's. Standard errors of the weighted \
         stacked regression.\n"
    )?;
    writeln!(
        r,
        "| parameter | value | std. error | interval |\n| --- | --- | --- | --- |"
    )?;
    for p in parameters {
        let interval = intervals
            .and_then(|b| b.interval(&p.name))
            .map_or("—".to_owned(), |i| {
                format!("[{:.6e}, {:.6e}]", i.lower, i.upper)
            });
        writeln!(
            r,
            "| `{}` | {:.6e} | {:.2e} | {interval} |",
            p.name, p.value, p.std_error
        )?;
    }
    writeln!(r)?;
    Ok(())
}

/// The residuals of each equation's fit: how much of the balanced acceleration it leaves, and
/// where (for a model identified here), or the saved fit's residual.
fn residuals_section(r: &mut String, entries: &[Entry]) -> anyhow::Result<()> {
    writeln!(r, "## Residuals of the fit\n")?;
    writeln!(
        r,
        "The residual of each equation's least squares: its RMS, the fraction of the balanced acceleration \
         (the right-hand side of the harmonic balance, or of the weak form on windows) it leaves unexplained, \
         and the drive harmonic where it is largest against the right-hand side's line there (a missing drive \
         term would stand out). A saved model keeps only its RMS.\n"
    )?;
    writeln!(
        r,
        "| model | equation | residual RMS | unexplained | largest residual line (harmonic: residual / rhs) |\n\
         | --- | --- | --- | --- | --- |"
    )?;
    for entry in entries {
        for (i, model) in entry.system.equations().iter().enumerate() {
            let own = &entry.system.names().coordinates()[i];
            let quality = entry
                .identified
                .as_ref()
                .map(|r| &r.equations[i].identification.quality);
            let rms = model
                .summary()
                .map_or("n/a".to_owned(), |s| format!("{:.3e}", s.residual_rms));
            let unexplained = quality.map_or("n/a".to_owned(), |q| format!("{:.2e}", q.unexplained));
            let line = quality
                .and_then(|q| {
                    q.spectrum
                        .iter()
                        .filter(|l| l.rhs_rms > 0.0)
                        .max_by(|a, b| a.residual_rms.total_cmp(&b.residual_rms))
                })
                .map_or("n/a".to_owned(), |l| {
                    let harmonic = if l.harmonic.fract() == 0.0 {
                        format!("{}", l.harmonic)
                    } else {
                        format!("{:.3}", l.harmonic)
                    };
                    format!("{harmonic}: {:.2e} / {:.2e}", l.residual_rms, l.rhs_rms)
                });
            writeln!(r, "| {} | {own} | {rms} | {unexplained} | {line} |", entry.name)?;
        }
    }
    writeln!(r)?;
    Ok(())
}

/// A score, or `–`.
fn cell(value: Option<f64>, f: impl Fn(f64) -> String) -> String {
    value.map_or_else(|| "–".to_owned(), f)
}

/// Each model's free run against the record (`hbid compare`), a table, `compare.json` and a figure
/// per model and coordinate.
fn compare_section(
    r: &mut String,
    figures: &mut Vec<(String, String)>,
    out: &Path,
    entries: &[Entry],
    measured: &[Measured],
) -> anyhow::Result<()> {
    // Every run starts alike: from the measured states when the record's velocities are read.
    let from_measured = measured.iter().any(|m| m.from_measured);
    let start = match from_measured {
        true => {
            "from each piece's first measured state (the angles and `--velocity-col`), every sample scored"
        }
        false => "from the state whose free run best matches the first samples of each piece (not scored)",
    };
    writeln!(r, "## Free run against the record\n")?;
    writeln!(
        r,
        "Each model run freely over the whole record as `hbid compare` runs it: {start}, driven as `hbid compare` drives it (its own \
         periodic drive on the record's clock, or the record's measured drives), every coordinate at once; RMSE in the record's unit (shortest arcs on the circle), NRMSE (over the measured \
         coordinate's standard deviation) and fit % = 100 (1 − ‖y − ŷ‖ / ‖y − ȳ‖). A chaotic record is followed \
         for a few drive periods at best, so the scores over the whole record say little; the figures show the \
         first {SHOWN_PERIODS} drive periods.\n"
    )?;
    writeln!(
        r,
        "| model | coordinate | range | init | scored | RMSE | NRMSE | fit % | max error |\n\
         | --- | --- | --- | --- | --- | --- | --- | --- | --- |"
    )?;
    let mut json = Vec::new();
    for (entry, m) in entries.iter().zip(measured) {
        let report = &m.compare;
        for (k, s) in report.ranges.iter().enumerate() {
            let coordinate = s.coordinate.clone().unwrap_or_else(|| coordinate_name(entry, k));
            writeln!(
                r,
                "| {} | {coordinate} | {}..{} | {} | {} | {} | {} | {} | {} |",
                entry.name,
                s.range[0],
                s.range[1],
                s.init,
                s.scored,
                cell(s.rmse, |v| format!("{v:.4e}")),
                cell(s.nrmse, |v| format!("{v:.4}")),
                cell(s.fit_percent, |v| format!("{v:.2}")),
                cell(s.max_error, |v| format!("{v:.3e}"))
            )?;
        }
        json.push(serde_json::json!({ "model": entry.name, "compare": report }));
    }
    writeln!(r)?;
    for (entry, m) in entries.iter().zip(measured) {
        let stride = m.compare.coordinates.len().max(1);
        for s in m.compare.ranges.iter().step_by(stride) {
            if let Some(why) = &s.stopped {
                writeln!(
                    r,
                    "{}: the free run of the range {}..{} stopped: {why}\n",
                    entry.name, s.range[0], s.range[1]
                )?;
            }
        }
    }
    let text = serde_json::to_string_pretty(&serde_json::json!({ "models": json }))?;
    hb_pipeline::output::write_atomically(&out.join("compare.json"), |w| writeln!(w, "{text}"))?;
    writeln!(
        r,
        "Every range's scores and initial states are in `compare.json`.\n"
    )?;
    for (entry, m) in entries.iter().zip(measured) {
        for (k, pieces) in m.compare.runs.iter().enumerate() {
            // The first range only: one figure per coordinate.
            if k >= entry.system.coordinates() {
                break;
            }
            let coordinate = coordinate_name(entry, k);
            let Some(piece) = pieces.first() else {
                continue;
            };
            let domain = entry.system.domains()[k];
            let break_above = match domain {
                Domain::Circle => std::f64::consts::PI,
                Domain::Line => f64::INFINITY,
            };
            let span = SHOWN_PERIODS * std::f64::consts::TAU / entry.system.drive_angular_frequency();
            let t0 = piece
                .t
                .get(piece.init.min(piece.t.len().saturating_sub(1)))
                .copied()
                .unwrap_or(0.0);
            // Every piece's samples within the span (a record with gaps runs piece by piece).
            let shown: Vec<(&hb_pipeline::compare::RunPiece, usize)> = pieces
                .iter()
                .flat_map(|p| (0..p.t.len()).map(move |i| (p, i)))
                .filter(|&(p, i)| p.t[i] <= t0 + span)
                .collect();
            let show = |value: &dyn Fn(&hb_pipeline::compare::RunPiece, usize) -> f64| -> Vec<(f64, f64)> {
                shown
                    .iter()
                    .map(|&(p, i)| (p.t[i], value(p, i)))
                    .filter(|p| p.1.is_finite())
                    .collect()
            };
            let as_measured = |x: f64| match domain {
                Domain::Circle => wrap(x),
                Domain::Line => x,
            };
            let difference = |p: &hb_pipeline::compare::RunPiece, i: usize| match domain {
                Domain::Circle => wrap(p.x[i] - p.measured[i]),
                Domain::Line => p.x[i] - p.measured[i],
            };
            let name = format!("compare_{}_{coordinate}.png", entry.name);
            let title = format!("{coordinate}: the record and the free run of {}", entry.name);
            Figure {
                title: &title,
                x_label: "t",
                y_label: &coordinate,
                series: vec![
                    Series {
                        label: "model, free run",
                        points: show(&|p, i| as_measured(p.x[i])),
                        style: Style::Line { break_above },
                        color: ORANGE,
                    },
                    // The record last, as dots: where the model follows it, they lie on its line.
                    Series {
                        label: "measured",
                        points: show(&|p, i| p.measured[i]),
                        style: Style::Dots(1),
                        color: INK,
                    },
                ],
                x_range: None,
                y_range: None,
            }
            .save(&out.join(&name))?;
            add_figure(
                figures,
                name,
                match from_measured {
                    true => format!(
                        "{coordinate}: the record (dots) and the free run of {} from its first measured state (after \
                         a gap, from each piece's own), over the first {SHOWN_PERIODS} drive periods.",
                        entry.name
                    ),
                    false => format!(
                        "{coordinate}: the record (dots) and the free run of {} from the state fitted to its first {} \
                         samples (after a gap, from each piece's own), over the first {SHOWN_PERIODS} drive periods.",
                        entry.name, piece.init
                    ),
                },
            );
            let name = format!("residual_{}_{coordinate}.png", entry.name);
            let title = format!("{coordinate}: free run of {} less the record", entry.name);
            let y_label = format!("{coordinate} (model − measured)");
            Figure {
                title: &title,
                x_label: "t",
                y_label: &y_label,
                series: vec![Series {
                    label: "",
                    points: show(&difference),
                    style: Style::Line { break_above },
                    color: RED,
                }],
                x_range: None,
                y_range: None,
            }
            .save(&out.join(&name))?;
            add_figure(
                figures,
                name,
                format!(
                    "{coordinate}: the free run of {} less the record ({}), over the same drive periods.",
                    entry.name,
                    match domain {
                        Domain::Circle => "the shortest arc",
                        Domain::Line => "in the record's unit",
                    }
                ),
            );
        }
    }
    Ok(())
}

/// The name of coordinate `k` of `entry`'s system.
fn coordinate_name(entry: &Entry, k: usize) -> String {
    let names = entry.system.names().coordinates();
    names.get(k % names.len().max(1)).cloned().unwrap_or_default()
}

/// The valid prediction time of each model: a table, `prediction.json` and a figure of every
/// window.
fn prediction_section(
    r: &mut String,
    figures: &mut Vec<(String, String)>,
    out: &Path,
    entries: &[Entry],
    measured: &[Measured],
) -> anyhow::Result<()> {
    let Some(first) = measured.iter().find_map(|m| m.prediction.as_ref().ok()) else {
        writeln!(r, "## How long do the models predict the record?\n")?;
        for (entry, m) in entries.iter().zip(measured) {
            if let Err(why) = &m.prediction {
                writeln!(r, "{}: no valid prediction time: {why}.\n", entry.name)?;
            }
        }
        return Ok(());
    };
    let names = entries[0].system.names().coordinates();
    writeln!(r, "## How long do the models predict the record?\n")?;
    writeln!(
        r,
        "From the record's own state at {} samples spread over it (each coordinate and its velocity from a \
         least-squares polynomial of degree 4 through the samples within a twelfth of a forcing period), each \
         model is integrated until **any** coordinate leaves the record by more than a tenth of that coordinate's \
         spread ({}): its valid prediction time. A window that reaches its horizon (40 forcing periods), the \
         record's end or a gap first counts at that length (a lower bound). {}\n",
        first.windows.len(),
        names
            .iter()
            .zip(&first.tolerances)
            .map(|(n, t)| format!("{n} {t:.4}"))
            .collect::<Vec<_>>()
            .join(", "),
        if entries.iter().all(|e| e.identified.is_some()) {
            "The identification used the whole record, so these windows are not held out from it."
        } else {
            "They are held out from a saved model only if it was identified on another record."
        }
    )?;
    write!(
        r,
        "| model | median (forcing periods) | quartiles | windows reaching the end |"
    )?;
    for name in names {
        write!(r, " {name} left first |")?;
    }
    writeln!(r)?;
    writeln!(r, "|{}", " --- |".repeat(4 + names.len()))?;
    let mut json = Vec::new();
    let mut series = Vec::new();
    let colors = [ORANGE, BLUE, GREEN, PURPLE, INK];
    for ((entry, m), color) in entries.iter().zip(measured).zip(colors.iter().cycle()) {
        let times = match &m.prediction {
            Ok(times) => times,
            Err(why) => {
                writeln!(
                    r,
                    "| {} | n/a: {why} | | |{}",
                    entry.name,
                    " |".repeat(names.len())
                )?;
                continue;
            }
        };
        let Some(periods) = times.in_periods() else {
            continue;
        };
        let bound = if periods.median_is_lower_bound() {
            "≥ "
        } else {
            ""
        };
        write!(
            r,
            "| {} | {bound}{:.2} | {:.2} – {:.2} | {} of {} |",
            entry.name,
            periods.median,
            periods.lower_quartile,
            periods.upper_quartile,
            periods.censored,
            periods.windows
        )?;
        for c in 0..names.len() {
            write!(r, " {} |", times.left_by(c))?;
        }
        writeln!(r)?;
        json.push(serde_json::json!({
            "model": entry.name,
            "periods": periods,
            "windows": times.windows,
        }));
        let period = times.drive_period;
        series.push(Series {
            label: &entry.name,
            points: times
                .windows
                .iter()
                .map(|w| (w.start_time / period, w.valid_time / period))
                .collect(),
            style: Style::Dots(3),
            color: *color,
        });
    }
    writeln!(r)?;
    let text = serde_json::to_string_pretty(&serde_json::json!({
        "coordinates": names,
        "tolerances": first.tolerances,
        "forcing_period": first.drive_period,
        "models": json,
    }))?;
    hb_pipeline::output::write_atomically(&out.join("prediction.json"), |w| writeln!(w, "{text}"))?;
    writeln!(r, "Each window's valid time is in `prediction.json`.\n")?;
    Figure {
        title: "Valid prediction time of each window",
        x_label: "window start (forcing periods)",
        y_label: "valid time (forcing periods)",
        series,
        x_range: None,
        y_range: None,
    }
    .save(&out.join("prediction.png"))?;
    add_figure(
        figures,
        "prediction.png",
        "Valid prediction time against the window's start, each model started from the record's own state.",
    );
    Ok(())
}
