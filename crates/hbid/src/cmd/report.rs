//! `hbid report`: embed → orbits → identify (both methods) → validate on the user's own record,
//! as a Markdown report with figures; a system of several coordinates and a saved model have
//! their own report ([`super::report_system`]).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Context;
use circle_signal::Measured;
use embedding::EmbeddingError;
use hb_pipeline::DriveSpec;
use hb_pipeline::pipeline::{
    EmbedOptions, Identification, InitialState, Method, Outcome, Pipeline, PipelineError, PipelineOptions,
    PredictionOptions, Record, RecordComparison, Stage, TermSelection, Validation, ValidationOptions,
    fit_drift,
};
use hb_pipeline::{IdentifyRequest, Notice, Observer, Spelling};
use hb_plot::{BLUE, Figure, GREY, ORANGE, RED, Series, Style, add_figure};
use hb_record::prepare::{Data, Note};
use pendulum_sim::Domain;

use super::report_args::Kept;
pub use super::report_args::ReportArgs;
use crate::progress::{Console, Progress};

/// One method's identification and its checks.
struct MethodResult<'a> {
    method: Method,
    ident: &'a Identification,
    /// What the validation measured, or why the model cannot be run freely
    /// ([`hb_pipeline::pipeline::PipelineError::Validation`]).
    validation: Result<&'a Validation, &'a hb_pipeline::pipeline::PipelineError>,
}

/// Whether a report's README keeps the notice: the record's notes are on the console, but
/// those that change what its samples are (gaps bridged: samples the file does not have; rows left
/// out for a missing value) are in the report too, as is every notice of the fit.
pub fn in_report(notice: &Notice) -> bool {
    match notice.inner() {
        Notice::Record(Note::Bridged { .. } | Note::MissingRows { .. }) => true,
        Notice::Resampled { .. } | Notice::Record(_) | Notice::Column { .. } => false,
        _ => true,
    }
}

/// The report's figures need a folder; checked before any work.
pub fn check_out(path: &Path) -> anyhow::Result<()> {
    if path.exists() && !path.is_dir() {
        anyhow::bail!("--out {} exists and is not a folder", path.display());
    }
    Ok(())
}

/// The pipeline's options from the request (the models' first, as `hbid identify` checks them).
fn options(args: &ReportArgs, request: &IdentifyRequest, data: &Data) -> anyhow::Result<PipelineOptions> {
    let models = args
        .methods()
        .into_iter()
        .map(|method| request.model_spec(data, method))
        .collect::<Result<_, _>>()?;
    let mut embed = EmbedOptions::default();
    if let Some(delay) = request.options().orbits.delay {
        embed = embed.with_delay(delay)?;
    }
    let periods = args.validation_periods;
    Ok(PipelineOptions {
        embed,
        search: request.search(),
        windows: request.windows(),
        models,
        validation: ValidationOptions::default()
            .with_section_points(periods)?
            .with_lyapunov_periods(periods)?
            .with_initial(InitialState::FirstSample)?
            .with_record_comparison(RecordComparison::DelaySection { periods })?,
        prediction: PredictionOptions::default(),
    })
}

/// The spinner's name of a stage.
fn stage_name(stage: Stage) -> String {
    match stage {
        Stage::Embed => "embed".to_owned(),
        Stage::Segments => "orbits".to_owned(),
        Stage::Identify { method, .. } => format!("identify ({method})"),
        Stage::Validate { method, .. } => format!("validate ({method})"),
        _ => "report".to_owned(),
    }
}

/// A pipeline error, with the options that fix it where the library cannot know them.
fn naming_options(error: PipelineError) -> anyhow::Error {
    match error {
        PipelineError::Embedding(EmbeddingError::NoFirstMinimum { .. }) => {
            anyhow::Error::new(error).context("choose the delay with «delay=», or raise «max_lag=»")
        }
        error => error.into(),
    }
}

pub fn run(args: &ReportArgs, quiet: bool) -> anyhow::Result<()> {
    if args.validation_periods < 10 {
        anyhow::bail!(
            "--validation-periods {} must be at least 10",
            args.validation_periods
        );
    }
    // A report runs its models over the record and draws it whole: read in chunks, it would be
    // held whole anyway (the option is `identify`'s, which this command shares).
    if args.identify.stream {
        anyhow::bail!(
            "«stream»: hbid report reads its record whole (it simulates its models along the record and draws \
             it); identify a long record in chunks with hbid identify --stream"
        );
    }
    // The report writes its models and tables into its folder: identify's outputs would be
    // accepted and not written.
    if let Some(path) = &args.identify.save_model {
        anyhow::bail!(
            "«save_model={}»: hbid report saves its models into its folder (model_METHOD.json in «out»); \
             save one with hbid identify --save-model",
            path.display()
        );
    }
    if args.identify.json {
        anyhow::bail!(
            "«json»: hbid report writes Markdown and figures into its folder; print JSON with hbid identify \
             --json"
        );
    }
    // A system of several coordinates, or a saved model: its own report.
    if args.model.is_some() || args.identify.input.coords.as_ref().is_some_and(|c| c.len() > 1) {
        return super::report_system::run(args, quiet);
    }
    let request = args.identify.request_for_report()?;
    if let Some(col) = &args.identify.input.velocity_col {
        anyhow::bail!(
            "«velocity_col={col}»: the report of one coordinate runs its models from the record's own states \
             (fitted to its samples), which measured velocities do not set; start a saved model's run from them with \
             hbid compare --velocity-col {col}"
        );
    }
    if let Some(spec) = &args.identify.tie {
        anyhow::bail!(
            "«tie={}»: the report of one coordinate identifies by both methods and a tied fit is the weak \
             form's alone; identify it with hbid identify --tie {}",
            spec.display(),
            spec.display()
        );
    }
    if let Some(col) = &args.identify.input.drive_col {
        anyhow::bail!(
            "«drive_col={col}»: hbid report simulates each model for --validation-periods periods from the record's \
             start and compares it by orbits, which a model driven by a measured drive cannot do beyond the record's \
             samples; identify it with hbid identify --method windowed --drive-col {col}"
        );
    }
    if matches!(request.drive(), DriveSpec::Free | DriveSpec::Windows(_)) {
        anyhow::bail!(
            "a record without a periodic drive has no orbits or Poincaré section to report; identify it with \
             hbid identify --method windowed (--drive-period none, --window)"
        );
    }
    // Made before the work, so that a folder that cannot be made is told first; removed again
    // (when this made it and it is still empty) if the report is not written.
    let mut made = MadeFolder {
        path: (!args.out.exists()).then(|| args.out.clone()),
    };
    std::fs::create_dir_all(&args.out).with_context(|| format!("cannot create {}", args.out.display()))?;

    let mut kept = Kept {
        console: Console::new("report", quiet, false),
        notices: Vec::new(),
    };
    let record = args.identify.input.options();
    let mut data = hb_pipeline::load(args.identify.input.source()?, &record, request.drive(), &mut kept)?;
    // A velocity or acceleration record's drift, found once by the weak form on windows, serves
    // every model of the report.
    if record.measured != Measured::Displacement {
        let setup = request.model_spec(&data, Method::Windowed)?.setup(&data.clock)?;
        let (windows, found) = request.segments(&data, 1, Method::Windowed)?;
        let drives: Vec<&[f64]> = data.drives.iter().map(Vec::as_slice).collect();
        let (x, fit) = fit_drift(
            &setup,
            &data.x,
            &drives,
            &data.pieces,
            &windows,
            record.measured,
            |_, _| {},
        )
        .with_context(|| format!("{found}: fitting the integrated record's drift"))?;
        kept.notice(&Notice::Drift {
            measured: record.measured,
            fit,
            samples_per_period: data.p,
        });
        data.x = x;
    }
    // Every option is checked before the work.
    let pipeline = Pipeline::new(Record::from_data(&data)?, options(args, &request, &data)?)?;
    let Kept { console, notices } = kept;
    console.finish();

    let mut bar: Option<Progress> = None;
    let outcome = pipeline.run(|stage| {
        drop(bar.take());
        bar = Some(Progress::spinner(&stage_name(stage), quiet));
    });
    drop(bar);
    let notes: Vec<String> = notices
        .iter()
        .filter(|n| in_report(n))
        .map(|n| Spelling::CommandLine.render(&n.to_string()))
        .collect();
    write_report(args, &request, &data, &notes, &outcome.map_err(naming_options)?)?;
    // Written: kept.
    made.path = None;
    Ok(())
}

/// The name of the list of a report's files that each report leaves in its folder: the next
/// report into that folder removes those it does not write again.
const MANIFEST: &str = ".hbid-report";

/// A report's files, written into a folder beside `--out` and moved into it together once every
/// one is written: a report that fails part-way (a figure that cannot be drawn, a full disk)
/// leaves none of its files, and one written into the folder of an earlier report leaves none
/// of that report's files it does not write again (a model of a method not run this time).
pub(crate) struct Staged {
    dir: tempfile::TempDir,
    out: PathBuf,
}

impl Staged {
    /// A new folder for the files of the report into `out`, beside it (on its file system).
    pub(crate) fn new(out: &Path) -> anyhow::Result<Self> {
        let parent = match out.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        let dir = tempfile::Builder::new()
            .prefix(".hbid-report-")
            .tempdir_in(parent)
            .with_context(|| format!("cannot write beside {}", out.display()))?;
        hb_pipeline::output::track(dir.path());
        Ok(Self {
            dir,
            out: out.to_owned(),
        })
    }

    /// Where the report's files are written.
    pub(crate) fn path(&self) -> &Path {
        self.dir.path()
    }

    /// Moves every file written into `out`, after removing the files an earlier report listed
    /// there that this one does not write; refused, moving nothing, where a file's name in `out`
    /// is a folder.
    pub(crate) fn commit(self) -> anyhow::Result<()> {
        let mut names: Vec<std::ffi::OsString> = std::fs::read_dir(self.dir.path())?
            .map(|e| e.map(|e| e.file_name()))
            .collect::<Result<_, _>>()?;
        names.sort();
        std::fs::create_dir_all(&self.out)
            .with_context(|| format!("cannot create {}", self.out.display()))?;
        if let Some(name) = names.iter().find(|n| self.out.join(n).is_dir()) {
            anyhow::bail!(
                "«out»: {} is a folder: the report's file of that name cannot be written (nothing was written)",
                self.out.join(name).display()
            );
        }
        let manifest = self.out.join(MANIFEST);
        if let Ok(earlier) = std::fs::read_to_string(&manifest) {
            for name in earlier.lines().filter(|l| !l.is_empty() && !l.contains('/')) {
                if !names.iter().any(|n| n == name) {
                    let _ = std::fs::remove_file(self.out.join(name));
                }
            }
        }
        for name in &names {
            let to = self.out.join(name);
            std::fs::rename(self.dir.path().join(name), &to)
                .with_context(|| format!("cannot write {}", to.display()))?;
        }
        let listed: String = names
            .iter()
            .map(|n| format!("{}\n", n.to_string_lossy()))
            .collect();
        std::fs::write(&manifest, listed).with_context(|| format!("cannot write {}", manifest.display()))?;
        hb_pipeline::output::untrack(self.dir.path());
        eprintln!("report written to {}", self.out.join("README.md").display());
        Ok(())
    }
}

/// The folder a report made, if it made one: removed when dropped if it is still empty (the
/// report was not written).
struct MadeFolder {
    path: Option<std::path::PathBuf>,
}

impl Drop for MadeFolder {
    fn drop(&mut self) {
        if let Some(path) = &self.path {
            // Fails, leaving it, when anything is in it.
            let _ = std::fs::remove_dir(path);
        }
    }
}

fn write_report(
    args: &ReportArgs,
    request: &IdentifyRequest,
    data: &Data,
    notes: &[String],
    outcome: &Outcome,
) -> anyhow::Result<()> {
    let staged = Staged::new(&args.out)?;
    write_files(args, request, data, notes, outcome, staged.path())?;
    staged.commit()
}

/// The report's files, written into `out`.
fn write_files(
    args: &ReportArgs,
    request: &IdentifyRequest,
    data: &Data,
    notes: &[String],
    outcome: &Outcome,
    out: &Path,
) -> anyhow::Result<()> {
    let embedded = &outcome.embedded;
    let (delay, fnn, ami) = (embedded.delay, &embedded.fnn, &embedded.ami.values);
    let catalogue = &outcome.segments.catalogue;
    let basis = request.basis().spec();
    let results: Vec<MethodResult<'_>> = args
        .methods()
        .into_iter()
        .zip(&outcome.models)
        .zip(&outcome.validation.models)
        .map(|((method, ident), validation)| MethodResult {
            method,
            ident,
            validation: validation.as_ref(),
        })
        .collect();
    // A model that cannot be run freely is reported as such, beside the others.
    for res in &results {
        if let Err(e) = res.validation {
            let message = Spelling::CommandLine.render(&crate::message_of(e));
            eprintln!("warning: {message}; the report says so");
        }
    }
    let (section, floor) = outcome
        .validation
        .record
        .as_ref()
        .map_or((&[][..], None), |s| (&s.points[..], s.distance));
    let mut r = String::new();
    let mut figures: Vec<(String, String)> = Vec::new();
    writeln!(
        r,
        "# Identification report: {}\n",
        args.identify.input.file().display()
    )?;
    writeln!(
        r,
        "{}; forcing period {}.\n",
        data.summary(),
        data.clock.drive_period()
    )?;
    // The summary above already says whether the record was resampled.
    for note in notes {
        writeln!(r, "{note}\n")?;
    }

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
        args.identify.search.tolerance,
        catalogue.tolerance(),
        args.identify.search.dim
    )?;
    writeln!(r, "| period | segments | distinct orbits |\n| --- | --- | --- |")?;
    for c in catalogue.counts() {
        writeln!(r, "| {} | {} | {} |", c.period, c.segments, c.orbits)?;
    }
    writeln!(r)?;

    for res in &results {
        let summary = res.ident.model.summary();
        let how = match res.method {
            Method::Upo => "harmonic balance on the orbits above, the paper's method",
            Method::Windowed => "the weak form on plain windows of the record",
        };
        writeln!(
            r,
            "## Identified model: {} ({how}), basis {}\n",
            res.method.name(),
            basis
        )?;
        writeln!(
            r,
            "{} segments, {} equations, condition number {:.3e}, residual RMS {:.3e}. Standard errors treat the \
             equations as independent (read them as lower bounds); the intervals come from a bootstrap over \
             segments.\n",
            summary.map_or(0, |s| s.segments),
            summary.map_or(0, |s| s.rows),
            summary.map_or(f64::NAN, |s| s.condition),
            summary.map_or(f64::NAN, |s| s.residual_rms)
        )?;
        if let Some(selection) = &res.ident.selection {
            selection_section(&mut r, &res.ident.model, selection)?;
        }
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
            "Saved as `{model_file}` (load it with `hb_model::IdentifiedModel::from_json`).\n"
        )?;
    }

    writeln!(r, "## Do the models behave like the record?\n")?;
    let fmt = |v: Option<f64>| v.map_or("n/a".to_owned(), |v| format!("{v:.2e}"));
    writeln!(
        r,
        "Energy distance between the record's section and the model's, in delay coordinates at the forcing's phase \
         0; the floor is the distance between the two halves of the record ({}): a distance of that order means the \
         model's attractor cannot be told from the record's with this many points.\n",
        fmt(floor)
    )?;
    writeln!(
        r,
        "| model | energy distance to the record | largest Lyapunov exponent (per unit time) | whirling fraction | \
         period-1 orbits at phase 0: x (winding) |\n| --- | --- | --- | --- | --- |"
    )?;
    let mut failures = Vec::new();
    for res in &results {
        let validation = match res.validation {
            Ok(v) => v,
            Err(e) => {
                writeln!(
                    r,
                    "| {} | cannot be run freely (below) | — | — | — |",
                    res.method.name()
                )?;
                failures.push(Spelling::CommandLine.render(&crate::message_of(e)));
                continue;
            }
        };
        let check = &validation.check;
        let distance = validation.section.as_ref().and_then(|s| s.distance);
        let orbits: Vec<String> = check
            .orbits
            .iter()
            .map(|o| format!("{:.4} ({})", o.x, o.winding))
            .collect();
        writeln!(
            r,
            "| {} | {} | {:.4} ± {:.4} | {:.3} | {} |",
            res.method.name(),
            fmt(distance),
            check.lyapunov.per_unit_time,
            check.lyapunov.standard_error,
            check.whirling,
            if orbits.is_empty() {
                "none found".to_owned()
            } else {
                orbits.join(", ")
            }
        )?;
    }
    writeln!(r)?;
    for failure in &failures {
        writeln!(r, "**Not validated:** {failure}.\n")?;
    }
    prediction_section(&mut r, &mut figures, out, &results)?;

    let (range, label) = match data.domain {
        Domain::Circle => (Some((-std::f64::consts::PI, std::f64::consts::PI)), "x (wrapped)"),
        Domain::Line => (None, "x"),
    };
    let y_label = format!("x(t + {delay} dt)");
    let mut panels = vec![(
        "section_record.png".to_owned(),
        "Record".to_owned(),
        section,
        GREY,
    )];
    for (res, color) in results.iter().zip([ORANGE, BLUE]) {
        let Ok(validation) = res.validation else {
            continue;
        };
        panels.push((
            format!("section_model_{}.png", res.method.name()),
            format!("Model ({})", res.method.name()),
            validation.section.as_ref().map_or(&[][..], |s| &s.points[..]),
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
    hb_pipeline::output::write_atomically(&path, |w| w.write_all(r.as_bytes()))?;
    Ok(())
}

/// The selection of terms: the chosen equation, and a table of the dropped terms with the
/// held-out unexplained fraction without and with each.
fn selection_section(
    r: &mut String,
    model: &hb_model::IdentifiedModel,
    selection: &TermSelection,
) -> anyhow::Result<()> {
    let outcome = &selection.outcome;
    writeln!(
        r,
        "Model selection kept {} of {} candidate terms (backward elimination, cross-validated over {} contiguous \
         folds of segments; a term is dropped when the model without it leaves no more than the allowance {:.2e} \
         of the held-out right-hand side unexplained beyond the best model on the path):\n",
        selection.kept.len(),
        selection.library.len(),
        outcome.folds,
        outcome.allowance
    )?;
    writeln!(r, "    {}\n", super::identify::equation(model))?;
    if !outcome.dropped.is_empty() {
        writeln!(
            r,
            "| dropped term | held-out unexplained without it | with it |\n| --- | --- | --- |"
        )?;
        for d in &outcome.dropped {
            writeln!(
                r,
                "| `{}` | {:.3e} | {:.3e} |",
                d.name, d.unexplained_without, d.unexplained_with
            )?;
        }
        writeln!(r)?;
    }
    Ok(())
}

/// The valid prediction time of each model: a table, `prediction.json` and a figure of every
/// window.
fn prediction_section(
    r: &mut String,
    figures: &mut Vec<(String, String)>,
    out: &Path,
    results: &[MethodResult<'_>],
) -> anyhow::Result<()> {
    let measured: Vec<(&MethodResult<'_>, &pendulum_sim::PredictionTimes)> = results
        .iter()
        .filter_map(|res| res.validation.ok()?.prediction.as_ref().map(|p| (res, p)))
        .collect();
    let Some((_, first)) = measured.first() else {
        return Ok(());
    };
    writeln!(r, "## How long do the models predict the record?\n")?;
    writeln!(
        r,
        "From the record's own state at {} samples spread over it (x and x' from a least-squares polynomial of \
         degree 4 through the samples within a twelfth of a forcing period), each model is integrated until it \
         leaves the record by more than {:.4} (10 % of the record's spread): its valid prediction time. A window \
         that reaches its horizon (40 forcing periods), the record's end or a gap first counts at that length \
         (a lower bound). The identification used the whole record, so these windows are not held out from it. \
         Lyapunov times use each model's own exponent.\n",
        first.windows.len(),
        first.tolerance
    )?;
    writeln!(
        r,
        "| model | median (forcing periods) | quartiles | median (Lyapunov times) | windows reaching the end |\n\
         | --- | --- | --- | --- | --- |"
    )?;
    let mut json = Vec::new();
    let mut series = Vec::new();
    for ((res, times), color) in measured.iter().zip([ORANGE, BLUE]) {
        let Some(periods) = times.in_periods() else {
            continue;
        };
        let lyapunov = times.in_lyapunov_times();
        let bound = if periods.median_is_lower_bound() {
            "≥ "
        } else {
            ""
        };
        writeln!(
            r,
            "| {} | {bound}{:.2} | {:.2} – {:.2} | {} | {} of {} |",
            res.method.name(),
            periods.median,
            periods.lower_quartile,
            periods.upper_quartile,
            lyapunov.map_or("n/a".to_owned(), |l| format!("{bound}{:.2}", l.median)),
            periods.censored,
            periods.windows
        )?;
        json.push(serde_json::json!({
            "method": res.method.name(),
            "periods": periods,
            "lyapunov_times": lyapunov,
            "lyapunov_per_unit_time": times.lyapunov,
            "windows": times.windows,
        }));
        let period = times.drive_period;
        series.push(Series {
            label: res.method.name(),
            points: times
                .windows
                .iter()
                .map(|w| (w.start_time / period, w.valid_time / period))
                .collect(),
            style: Style::Dots(3),
            color,
        });
    }
    writeln!(r)?;
    let text = serde_json::to_string_pretty(&serde_json::json!({
        "tolerance": first.tolerance,
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
