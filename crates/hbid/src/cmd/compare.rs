//! `hbid compare`: a saved model run freely under a record's measured input and scored against its
//! measured output (the application layer's [`hb_pipeline::compare`]); this module holds the
//! arguments, prints the scores and draws the figure.

use std::path::{Path, PathBuf};

use anyhow::Context;
use circle_signal::{Domain, Measured};
use clap::Args;
use hb_pipeline::compare::Values;
use hb_pipeline::{
    AngleUnit, ColumnList, CompareOptions, CompareReport, CompareRequest, SampleRange, Source,
};
use hb_plot::{BLUE, Figure, ORANGE, RED, Series, Style};

use super::data::choice;
use crate::progress::Console;

/// Options of `hbid compare`.
#[derive(Debug, Args)]
pub struct CompareArgs {
    /// The model, as saved by `hbid identify --save-model` (JSON or binary).
    pub model: PathBuf,
    /// The record: its measured output (the angle or displacement column) and, for a model with
    /// terms in p, its measured drive (--drive-col); text or .npy, as for `hbid identify`.
    pub file: PathBuf,
    /// Time column, by header name or 1-based position.
    #[arg(long, value_name = "NAME|N")]
    pub time_col: Option<String>,
    /// The measured output's column (angle or displacement), by header name or 1-based position.
    #[arg(long, value_name = "NAME|N")]
    pub angle_col: Option<String>,
    /// Sampling step, for records without a time column (the first sample is at t = 0).
    #[arg(long, allow_hyphen_values = true)]
    pub dt: Option<f64>,
    /// A system's coordinates: the record's columns, by the model's names in any order
    /// (NAME=COLUMN, q2=3,q1=2), or alone (header names or positions) in the order of the
    /// model's coordinates [default: the model's names].
    #[arg(long, value_name = "A,B[,..]", conflicts_with = "angle_col")]
    pub coords: Option<ColumnList>,
    /// The measured drives, for a model with terms in them: columns of the record, by header name
    /// or 1-based position, in the order of the model's drives, or for a system by its names in
    /// any order (tau2=7,tau1=6; a system's default: the model's names). Between samples the model reads each from the interpolating cubic spline of the
    /// samples (not-a-knot), which keeps a band-limited drive's amplitude and has no kink.
    #[arg(long, value_name = "NAME|N[,..]")]
    pub drive_col: Option<ColumnList>,
    /// Fix isolated time-stamp glitches and encoder spikes (each listed on stderr).
    #[arg(long)]
    pub repair: bool,
    /// The coordinates' measured velocities (a motor driver's, a tachometer's): columns of the
    /// record, one per coordinate in their order, or by the coordinates' names (q2=v2,q1=v1). `compare` starts each
    /// free run from the first sample's measured state, every sample scored (unless --init says otherwise).
    #[arg(long, value_name = "NAME|N[,..]")]
    pub velocity_col: Option<ColumnList>,
    /// Keep every isolated spike in the record (warned of) instead of replacing them by the local
    /// prediction when they are few (at most one per 1000 samples; the default, said in a note).
    #[arg(long, conflicts_with = "repair")]
    pub no_repair: bool,
    /// Bridge every gap of at most N missing samples (N at most 4), between pieces of at least 7
    /// samples, by the cubic through the two samples on each side, in every column (angles across
    /// their wraps): a free run then goes on through it (driven by the bridged drives), and the
    /// bridged samples, not measured, are counted apart and not scored (a logger's dropped rows; a
    /// note counts them). A bridged sample of a sine of amplitude A and
    /// angular frequency ω is off by at most A (ω dt)^4 times 1/6, 1/2, 3/2 or 3 for N = 1, 2, 3 or
    /// 4, and carries at most 1.61 times one sample's noise; an angle that moves too far across a
    /// gap to tell its turn leaves it a gap; 0 bridges none (a displacement record only).
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub bridge_gaps: usize,
    /// Leave out every row with a missing value in a column read (an empty cell, NA, null, NaN,
    /// ...), as if the logger had not written it: its time is a gap's (with --dt the rows keep
    /// their places), which --bridge-gaps may bridge; a note counts them and names the first.
    /// Without it such a value is an error naming its line.
    #[arg(long)]
    pub skip_missing: bool,
    /// circle or line [default: the model's].
    #[arg(long, value_parser = choice::<Domain>(&["circle", "line"]))]
    pub signal: Option<Domain>,
    /// What the sensor measured, on the line: displacement, velocity or acceleration. A velocity
    /// or acceleration record is integrated to the displacement piece by piece, with the
    /// constants (offset; and velocity, for an acceleration) the model's equation holds best with
    /// (a note gives them), and its free run is scored against that displacement. A logger's
    /// first rows stamped before it settled are left out.
    #[arg(long, default_value_t = Measured::Displacement, value_parser = choice::<Measured>(&["displacement", "velocity", "acceleration"]))]
    pub measured: Measured,
    /// The unit of the angles on the circle, and of their measured velocities (per time unit):
    /// rad, deg, or counts:N for an encoder's N counts per turn (4096 counts from 0 to 4095, say);
    /// converted to radians as they are read.
    #[arg(long, value_name = "rad|deg|counts:N", default_value_t = AngleUnit::Radians)]
    pub angle_unit: AngleUnit,
    /// Samples compared, A..B (0-based, B excluded) or A.. to the end: the record's rows for a
    /// record without gaps, its first rows included when a logger stamped them before it settled
    /// to its rate (see --skip-unsettled), samples bridged into gaps (--bridge-gaps) counted among
    /// them; repeatable, each range scored on its own [default: the whole record].
    #[arg(long, value_name = "A..B")]
    pub range: Vec<SampleRange>,
    /// Samples at the start of each range (and after each gap) that set the model's initial state
    /// and are not scored [default: one period of the model's drive, at most a tenth of the range,
    /// at least 8].
    #[arg(long, value_name = "N")]
    pub init: Option<usize>,
    /// The initial position instead of fitting it (with --v0): one per coordinate of a system
    /// (a,b); every sample of a range is then scored unless --init says otherwise.
    #[arg(long, allow_hyphen_values = true, value_name = "X[,..]")]
    pub x0: Option<Values>,
    /// The initial velocity in the record's time unit (with --x0): one per coordinate.
    #[arg(long, allow_hyphen_values = true, value_name = "V[,..]")]
    pub v0: Option<Values>,
    /// Relative tolerance of the integrator (the absolute one is rtol/10).
    #[arg(long, default_value_t = CompareRequest::DEFAULT_RTOL, allow_hyphen_values = true)]
    pub rtol: f64,
    /// Leave out the record's first rows when a logger stamped them before it settled to its
    /// rate (steps of 1.5 to 2 of the later ones), as `identify` does, and start at the first row
    /// on the grid; the ranges then count from there. By default the free run starts at the
    /// record's first row and passes those rows at their own stamps (a note says so).
    #[arg(long)]
    pub skip_unsettled: bool,
    /// Print the scores as JSON.
    #[arg(long)]
    pub json: bool,
    /// Draw the measured and the simulated output and their difference (PNG, or SVG by extension).
    #[arg(long, value_name = "FILE.png")]
    pub plot: Option<PathBuf>,
}

impl CompareArgs {
    /// The application layer's options.
    pub fn options(&self) -> CompareOptions {
        CompareOptions {
            time_col: self.time_col.clone(),
            angle_col: self.angle_col.clone(),
            coords: self.coords.clone(),
            dt: self.dt,
            drive_col: self.drive_col.clone(),
            repair: self.repair,
            no_repair: self.no_repair,
            bridge_gaps: self.bridge_gaps,
            skip_missing: self.skip_missing,
            velocity_col: self.velocity_col.clone(),
            signal: self.signal,
            measured: self.measured,
            angle_unit: self.angle_unit,
            range: self.range.clone(),
            init: self.init,
            x0: self.x0.clone(),
            v0: self.v0.clone(),
            rtol: self.rtol,
            skip_unsettled: self.skip_unsettled,
        }
    }
}

pub fn run(args: &CompareArgs, quiet: bool) -> anyhow::Result<()> {
    let request = CompareRequest::new(args.options())?;
    if let Some(path) = &args.plot {
        if hb_plot::Format::of(path).is_none() {
            anyhow::bail!(
                "«plot={}»: a figure is written as PNG or SVG: name its file .png or .svg",
                path.display()
            );
        }
        hb_pipeline::output::check_output_path(path).context("«plot»")?;
    }
    let model = hb_pipeline::read_model(&args.model)?;
    let mut console = Console::new("compare", quiet, false);
    let report = hb_pipeline::compare(&model, Source::Path(&args.file), &request, &mut console)?;
    console.finish();
    if let Some(path) = &args.plot {
        plot(&report, path)?;
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print!("{}", table(&report));
    }
    Ok(())
}

/// A score, or `-` when there is none.
fn cell(value: Option<f64>, f: impl Fn(f64) -> String) -> String {
    value.map_or_else(|| "-".to_owned(), f)
}

/// The scores as a table, one line per range, and why a run stopped.
pub fn table(report: &CompareReport) -> String {
    // A system's coordinates have their own domains.
    let circle = |d: &Domain| *d == Domain::Circle;
    let unit = if report.domains.is_empty() {
        match report.signal {
            Domain::Circle => "radians (shortest arcs)",
            Domain::Line => "the record's unit",
        }
    } else if report.domains.iter().all(circle) {
        "radians (shortest arcs)"
    } else if report.domains.iter().any(circle) {
        "each coordinate's unit (radians, shortest arcs, for the angles)"
    } else {
        "the record's units"
    };
    let drive = if report.measured_drive {
        "driven by the record's measured drive"
    } else {
        "on its own drive, on the record's clock"
    };
    let uneven = match report.unsettled_rows {
        0 => String::new(),
        n => format!(" (the first {n} at their own stamps)"),
    };
    let mut out = format!(
        "free run of the model {drive}, {} samples{uneven}, step {}; errors in {unit}\n\n",
        report.samples, report.step
    );
    let w = report
        .coordinates
        .iter()
        .map(|c| c.chars().count() + 1)
        .max()
        .unwrap_or(0);
    out.push_str(&format!(
        "{:<w$}{:<18} {:>6} {:>9} {:>12} {:>10} {:>9} {:>12}\n",
        if w > 0 { "coordinate" } else { "" },
        "range",
        "init",
        "scored",
        "RMSE",
        "NRMSE",
        "fit %",
        "max error",
        w = w.max(if w > 0 { 11 } else { 0 })
    ));
    for r in &report.ranges {
        out.push_str(&format!(
            "{:<w$}{:<18} {:>6} {:>9} {:>12} {:>10} {:>9} {:>12}\n",
            r.coordinate.as_deref().unwrap_or(""),
            format!("{}..{}", r.range[0], r.range[1]),
            r.init,
            r.scored,
            cell(r.rmse, |v| format!("{v:.4e}")),
            cell(r.nrmse, |v| format!("{v:.4}")),
            cell(r.fit_percent, |v| format!("{v:.2}")),
            cell(r.max_error, |v| format!("{v:.3e}")),
            w = w.max(if w > 0 { 11 } else { 0 })
        ));
    }
    for r in report.ranges.iter().step_by(report.coordinates.len().max(1)) {
        if let Some(why) = &r.stopped {
            out.push_str(&format!("\nrange {}..{}: {why}\n", r.range[0], r.range[1]));
        }
        if r.skipped_pieces > 0 {
            out.push_str(&format!(
                "range {}..{}: {} piece(s) between gaps no longer than --init {} were not run\n",
                r.range[0], r.range[1], r.skipped_pieces, r.init
            ));
        }
        if r.bridged > 0 {
            out.push_str(&format!(
                "range {}..{}: {} sample(s) bridged into gaps (--bridge-gaps) were run through, not scored\n",
                r.range[0], r.range[1], r.bridged
            ));
        }
    }
    out
}

/// Draws the measured and simulated output and their difference into `path`, atomically: one
/// panel, or for a system one panel per coordinate, side by side.
fn plot(report: &CompareReport, path: &Path) -> anyhow::Result<()> {
    let break_above = match report.signal {
        Domain::Circle => std::f64::consts::PI,
        Domain::Line => f64::INFINITY,
    };
    // The entries of each coordinate (all of them for a record of one).
    let panels: Vec<(Option<&str>, Vec<usize>)> = if report.coordinates.len() > 1 {
        report
            .coordinates
            .iter()
            .map(|q| {
                let entries = (0..report.ranges.len())
                    .filter(|&e| report.ranges[e].coordinate.as_deref() == Some(q.as_str()))
                    .collect();
                (Some(q.as_str()), entries)
            })
            .collect()
    } else {
        vec![(None, (0..report.runs.len()).collect())]
    };
    let titles: Vec<String> = panels
        .iter()
        .map(|(q, _)| match q {
            Some(q) => format!("{q}: the model's free run against the record"),
            None => "The model's free run against the record".to_owned(),
        })
        .collect();
    let figures: Vec<Figure<'_>> = panels
        .iter()
        .zip(&titles)
        .map(|((q, entries), title)| {
            let mut series = Vec::new();
            let pieces = entries.iter().flat_map(|&e| &report.runs[e]);
            for (i, piece) in pieces.enumerate() {
                let first = i == 0;
                // On the circle every curve is drawn wrapped, as the measured angle is.
                let points = |v: &dyn Fn(usize) -> f64| -> Vec<(f64, f64)> {
                    (0..piece.t.len())
                        .map(|k| match report.signal {
                            Domain::Circle => (piece.t[k], circle_signal::wrap(v(k))),
                            Domain::Line => (piece.t[k], v(k)),
                        })
                        .filter(|p| p.1.is_finite())
                        .collect()
                };
                series.push(Series {
                    label: if first { "measured" } else { "" },
                    points: points(&|k| piece.measured[k]),
                    style: Style::Line { break_above },
                    color: BLUE,
                });
                series.push(Series {
                    label: if first { "model, free run" } else { "" },
                    points: points(&|k| piece.x[k]),
                    style: Style::Line { break_above },
                    color: ORANGE,
                });
                let difference = |k: usize| match report.signal {
                    Domain::Circle => circle_signal::wrap(piece.x[k] - piece.measured[k]),
                    Domain::Line => piece.x[k] - piece.measured[k],
                };
                series.push(Series {
                    label: if first { "model − measured" } else { "" },
                    points: points(&difference),
                    style: Style::Line { break_above },
                    color: RED,
                });
            }
            Figure {
                title,
                x_label: "t",
                y_label: q.unwrap_or("output"),
                series,
                x_range: None,
                y_range: None,
            }
        })
        .collect();
    let draw = |to: &Path| -> anyhow::Result<()> {
        match figures.as_slice() {
            [figure] => figure.save(to)?,
            panels => hb_plot::save_row(panels, to)?,
        }
        Ok(())
    };
    // Through a symbolic link to its file; a device or named pipe in place.
    let (target, in_place) = hb_pipeline::output::output_target(path);
    if in_place {
        return draw(&target).with_context(|| format!("cannot write {}", target.display()));
    }
    let path = target.as_path();
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let suffix = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_else(|| ".png".to_owned());
    let mut builder = tempfile::Builder::new();
    builder.prefix(".hbid-partial-").suffix(&suffix);
    // An ordinary file's permissions (0o666 less the umask), not the temporary file's owner-only.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let tmp = builder
        .tempfile_in(parent)
        .with_context(|| format!("cannot create a file in {}", parent.display()))?;
    draw(tmp.path())?;
    tmp.persist(path)
        .with_context(|| format!("cannot write {}", path.display()))?;
    Ok(())
}
