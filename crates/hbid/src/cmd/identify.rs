//! `hbid identify`: the equation of motion by harmonic balance.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use hb_basis::BasisKind;
use hb_model::{IdentifiedModel, IdentifiedSystem};
use hb_pipeline::pipeline::{Method, TermSelection};
use hb_pipeline::{ForcingTerms, IdentifyOptions, IdentifyReport, IdentifyRequest, SolverKind, TermsOption};
use hb_solve::{BootstrapParams, NoiseCorrection, SelectParams, WeakForm};
use upo_search::Windows;

use super::data::{InputArgs, SearchArgs};
use crate::progress::Console;

/// The command-line values of a [`Method`]: `windowed` or `upo`.
pub fn method_parser() -> impl clap::builder::TypedValueParser<Value = Method> {
    use clap::builder::TypedValueParser;
    clap::builder::PossibleValuesParser::new(Method::ALL.map(Method::name))
        .try_map(|name| name.parse::<Method>())
}

/// Options of `hbid identify`.
#[derive(Debug, Args)]
pub struct IdentifyArgs {
    #[command(flatten)]
    pub input: InputArgs,
    /// Identification method: `windowed`, the weak form on plain windows of the record (any
    /// record: no periodic orbit needed, a measured drive balanced as measured, the noise floor
    /// reached), or `upo`, the paper's harmonic balance on unstable periodic orbits found by close
    /// returns.
    #[arg(long, default_value_t = Method::Windowed, value_parser = method_parser())]
    pub method: Method,
    /// Basis of the unknown functions: harmonic:K (cos kx, sin kx, k = 1..K), hat:N (N periodic hats), poly:D
    /// (x .. x^D). Default: harmonic:1 on the circle, poly:3 on the line.
    #[arg(long, value_name = "harmonic:K|hat:N|poly:D")]
    pub basis: Option<BasisKind>,
    /// Harmonics per segment (default: all j with j/k <= 3 drive harmonics for a period-k orbit with
    /// --method upo, j/k <= 2 for --method windowed).
    #[arg(long)]
    pub harmonics: Option<usize>,
    /// Windowed method: window length in drive periods.
    #[arg(long, default_value_t = Windows::DEFAULT_PERIODS)]
    pub window_periods: usize,
    /// Windowed method, for a record without a periodic drive (--drive-period none, or a measured
    /// drive --drive-col alone): the window length in the record's time unit (seconds for a
    /// record in seconds), instead of periods of the free oscillation or of the default 2π. The
    /// windows' unit is LENGTH/--window-periods, rounded to whole samples; --harmonics counts in
    /// it.
    #[arg(
        long,
        value_name = "LENGTH",
        allow_hyphen_values = true,
        conflicts_with = "window_samples"
    )]
    pub window: Option<f64>,
    /// Windowed method: the window length in samples, instead of --window.
    #[arg(long, value_name = "N")]
    pub window_samples: Option<usize>,
    /// Windowed method: order p of the window w = sin^p (at least 2).
    #[arg(long, default_value_t = WeakForm::DEFAULT_WINDOW_ORDER)]
    pub window_order: u32,
    /// Bootstrap resamples for the confidence intervals (0: none).
    #[arg(long, default_value_t = BootstrapParams::DEFAULT_RESAMPLES)]
    pub bootstrap: usize,
    /// Confidence level of the intervals.
    #[arg(long, default_value_t = BootstrapParams::DEFAULT_LEVEL, allow_hyphen_values = true)]
    pub level: f64,
    /// Seed of the bootstrap (results are the same for a given seed, whatever the number of threads).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Correct the bias of Gaussian noise on the angle in the trigonometric terms: the noise standard deviation
    /// in radians, or `auto` to estimate it from the record's highest frequencies (harmonic basis only).
    #[arg(long, value_name = "SIGMA|auto", allow_hyphen_values = true)]
    pub noise_sigma: Option<NoiseCorrection>,
    /// Least-squares solver: qr (column-pivoted QR) or svd (thin SVD).
    #[arg(long, default_value_t = SolverKind::Qr, value_parser = super::data::choice::<SolverKind>(&["qr", "svd"]))]
    pub solver: SolverKind,
    #[command(flatten)]
    pub search: SearchArgs,
    /// External forcing terms cos(t), sin(t) of the default model (the d_1 p(t) of the paper's eq. 2):
    /// none or identified (default: none on the circle, identified on the line). `none` with no drive
    /// given is a free oscillation (as --drive-period none).
    #[arg(long, value_parser = super::data::choice::<ForcingTerms>(&["none", "identified"]))]
    pub forcing: Option<ForcingTerms>,
    /// Leave out the parametric terms cos(t)*B and sin(t)*B.
    #[arg(long)]
    pub no_parametric: bool,
    /// Drive harmonics H of the default model: the parametric terms cos(kt)*B, sin(kt)*B (and with
    /// --forcing identified the forcing cos(kt), sin(kt)) for k = 1..H.
    #[arg(long, value_name = "H")]
    pub drive_harmonics: Option<u32>,
    /// The model's terms instead of the default: a comma-separated list of products, e.g.
    /// "x', sign(x'), x'*|x'|, {1,cos(t),sin(t),cos(2t),sin(2t)}*{cos(x),sin(x)}".
    ///
    /// The model is x'' + sum_i c_i g_i = 0 and each term g_i a product, factors joined by '*':
    /// at most one drive factor  cos(kt), sin(kt)   (t the drive's phase, k = 1..64: cos(t), sin(2t))
    ///                           or p              (the measured drive of --drive-col)
    /// at most one function of x cos(kx), sin(kx) (harmonic basis), x, x^n (poly), hatN (hat)
    /// at most one function of x'  x', sign(x'), x'*|x'|, x'^3
    /// and 1 (no factor). Braces multiply out: {1,cos(t)}*{cos(x),sin(x)} is cos(x), sin(x),
    /// cos(t)*cos(x), cos(t)*sin(x) (the leftmost set varies slowest). White space is ignored; each
    /// term may appear once. Without --basis the smallest basis that holds every function of x named
    /// is used (cos(2x): harmonic:2; x^3: poly:3; hat7: hat:8); with it, every function named must
    /// be in it. Terms are printed and saved with these names.
    ///
    /// With several coordinates (--coords theta1,theta2) terms name them and the drives by their
    /// columns, and each equation q_i'' + sum_k c_k g_k = 0 may have its own list:
    /// "theta1: theta2''*cos(theta1-theta2), sin(theta1-theta2)*theta2'^2, sin(theta1), theta1';
    ///  theta2: theta1''*cos(theta1-theta2), sin(theta1-theta2)*theta1'^2, sin(theta2), theta2'"
    /// (a list without a name serves the equations not named). Factors in other coordinates:
    /// cos or sin of a whole combination of angles (cos(theta1-theta2), sin(q1+q2)), powers of
    /// positions on the line (x1^2*x2), other velocities (theta2', theta2'^2, q1'*q2', sign(q2')),
    /// and one acceleration times functions of the positions (theta2''*cos(theta1-theta2), or the
    /// own one, q1''*cos(q2): a mass that depends on the state); the own acceleration alone is the
    /// equation's normalisation. Without --terms a system takes the default library of
    /// docs/identification.md ("Several coordinates").
    #[arg(
        long,
        value_name = "LIST",
        verbatim_doc_comment,
        conflicts_with_all = ["no_parametric", "drive_harmonics"]
    )]
    pub terms: Option<TermsOption>,
    /// Model selection: the model's terms (--terms, or the default's with --drive-harmonics) are a
    /// library of candidates; a term is kept only if the model without it predicts held-out
    /// stretches of the record worse (backward elimination, cross-validated over contiguous folds
    /// of segments, one-standard-error rule); the kept terms are then fitted alone.
    #[arg(long)]
    pub select: bool,
    /// Folds of segments of --select (fewer when there are fewer segments; at least 2).
    #[arg(long, value_name = "N", default_value_t = SelectParams::DEFAULT_FOLDS, requires = "select")]
    pub select_folds: usize,
    /// Smallest held-out unexplained fraction a term must remove to be kept by --select, in [0, 1)
    /// (the floor of the allowance within which a smaller model counts as good as the best).
    #[arg(
        long,
        value_name = "X",
        default_value_t = SelectParams::DEFAULT_TOLERANCE,
        requires = "select",
        allow_hyphen_values = true
    )]
    pub select_tolerance: f64,
    /// After the fit, refine the coefficients by the free run's error on the record (output
    /// error: each piece run from the state fitted to its first samples, Levenberg–Marquardt;
    /// docs/identification.md): the model then follows the record as `hbid compare` scores it.
    #[arg(long)]
    pub refine: bool,
    /// Samples at the start of each piece that set the refinement's free-run state and are not
    /// scored (default: one drive period, at most a tenth of the longest piece, at least 8).
    #[arg(long, value_name = "N")]
    pub refine_init: Option<usize>,
    /// Tie physical parameters across the equations of a system (one least squares of both
    /// equations' rows): a JSON file giving, per equation keyed by its coordinate, each term's
    /// coefficient as a fixed number or a linear combination of named parameters, the equation's
    /// own acceleration included, in the sign convention A q1'' + sum a_k g_k = 0 (a measured
    /// torque tau1 on the right-hand side is the term "tau1": -1):
    ///   {"parameters": ["Ia", "I2", "mr2", "b1", "b2"],
    ///    "equations": {"q1": {"q1''": {"Ia": 1, "I2": 1}, "q1''*cos(q2)": {"mr2": 0.6},
    ///                         "q1'": {"b1": 1}, "tau1": -1},
    ///                  "q2": {"q2''": {"I2": 1}, "q2'": {"b2": 1}, "tau2": -1}}}
    /// Each equation needs its own acceleration (not fixed to 0) and a fixed nonzero coefficient
    /// (its scale); every parameter must be used. The keys are terms of the --terms grammar, so
    /// --tie replaces --terms (and is not supported with --select, --method upo or --refine).
    /// Rows are weighted by 1/A of each equation from an unweighted first pass (residuals in
    /// acceleration units); the parameters' standard errors are the stacked regression's, and the
    /// bootstrap (--bootstrap) gives intervals of the parameters, drawing every equation's rows of
    /// a window together. The saved model holds each equation divided by its A.
    #[arg(long, value_name = "PATH", verbatim_doc_comment)]
    pub tie: Option<PathBuf>,
    /// Read the record's file in chunks of 2^21 rows, never holding the whole record (the weak
    /// form; the default for files of 256 MiB or more; a drive estimated with
    /// --drive-frequency auto is estimated on the first chunk: docs/scale.md).
    #[arg(long, conflicts_with = "no_stream")]
    pub stream: bool,
    /// Read the record's file whole, however large.
    #[arg(long)]
    pub no_stream: bool,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Save the identified model: JSON if the name ends in .json, compact binary otherwise (with
    /// --select, the model of the kept terms).
    #[arg(long, value_name = "PATH")]
    pub save_model: Option<PathBuf>,
}

impl IdentifyArgs {
    /// The application layer's options.
    pub fn options(&self) -> IdentifyOptions {
        IdentifyOptions {
            record: self.input.options(),
            method: self.method,
            basis: self.basis,
            harmonics: self.harmonics,
            window_periods: self.window_periods,
            window: self.window,
            window_samples: self.window_samples,
            window_order: self.window_order,
            bootstrap: self.bootstrap,
            level: self.level,
            seed: self.seed,
            noise_sigma: self.noise_sigma,
            solver: self.solver,
            orbits: self.search.options(),
            forcing: self.forcing,
            no_parametric: self.no_parametric,
            drive_harmonics: self.drive_harmonics,
            terms: self.terms.clone(),
            select: self.select,
            select_folds: self.select_folds,
            select_tolerance: self.select_tolerance,
            refine: self.refine,
            refine_init: self.refine_init,
            tie: self
                .tie
                .as_ref()
                .map(|p| serde_json::Value::String(p.to_string_lossy().into_owned())),
            stream: match (self.stream, self.no_stream) {
                (true, _) => Some(true),
                (_, true) => Some(false),
                _ => None,
            },
        }
    }

    /// The request, every option checked.
    pub fn request(&self) -> anyhow::Result<IdentifyRequest> {
        Ok(IdentifyRequest::new(self.options())?)
    }

    /// The request of a report's identification: the measured velocities (`--velocity-col`)
    /// set the report's free runs, not the fit.
    pub fn request_for_report(&self) -> anyhow::Result<IdentifyRequest> {
        let mut options = self.options();
        options.record.velocity_col = None;
        Ok(IdentifyRequest::new(options)?)
    }
}

pub fn run(args: &IdentifyArgs, quiet: bool, timings: bool) -> anyhow::Result<()> {
    let request = args.request()?;
    if let Some(path) = &args.save_model {
        hb_pipeline::output::check_output_path(path).context("«save_model»")?;
    }
    let mut console = Console::new("identify", quiet, timings);
    let report = hb_pipeline::identify_records(args.input.sources(), &request, &mut console)?;
    console.finish();
    if let Some(path) = &args.save_model {
        save_system(&report.system()?, path)?;
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_report(&report);
    }
    Ok(())
}

/// The identification as a table per equation: the equation and selection, the fit, the
/// coefficients (a system's equations one after the other, each headed by its coordinate).
pub fn print_report(report: &IdentifyReport) {
    let several = report.equations.len() > 1;
    if several {
        println!(
            "method {}, {} coordinates ({}), {}",
            report.method,
            report.equations.len(),
            report.names.coordinates().join(", "),
            report.found
        );
    }
    if let Some(parameters) = &report.parameters {
        println!("tied parameters ({}):", parameters.len());
        let width = parameters.iter().map(|p| p.name.len()).max().unwrap_or(0).max(9);
        let intervals = report.parameter_intervals.as_ref();
        match intervals {
            Some(b) => println!(
                "  {:<width$}  {:>14}  {:>12}  {:>27}",
                "parameter",
                "value",
                "std error",
                format!("{:.0} % interval", 100.0 * b.level)
            ),
            None => println!("  {:<width$}  {:>14}  {:>12}", "parameter", "value", "std error"),
        }
        for p in parameters {
            match intervals.and_then(|b| b.interval(&p.name)) {
                Some(i) => println!(
                    "  {:<width$}  {:>14.6e}  {:>12.3e}  [{:>12.5e}, {:>12.5e}]",
                    p.name, p.value, p.std_error, i.lower, i.upper
                ),
                None => println!("  {:<width$}  {:>14.6e}  {:>12.3e}", p.name, p.value, p.std_error),
            }
        }
        println!();
    }
    for (i, e) in report.equations.iter().enumerate() {
        let id = &e.identification;
        if several {
            if i > 0 {
                println!();
            }
            println!("== the equation of {}", e.coordinate);
            println!("{}", equation_of(&e.coordinate, &id.model));
        }
        if let Some(selection) = &id.selection {
            if !several {
                println!("{}", equation(&id.model));
            }
            println!(
                "selected {} of {} candidate terms ({} folds of segments)",
                selection.kept.len(),
                selection.library.len(),
                selection.outcome.folds
            );
        }
        print_table(report, e);
        if let Some(selection) = &id.selection {
            print!("{}", dropped_lines(selection));
        }
    }
}

/// The model's equation on one line, its terms in order with signed coefficients:
/// `x'' + 0.0301 x' + 0.0497 sign(x') - 1.52 sin(t)*cos(x) = 0`.
pub fn equation(model: &IdentifiedModel) -> String {
    equation_of("x", model)
}

/// [`equation`] for the coordinate named `own`: `theta1'' + 0.5 theta2''*cos(theta1-theta2) ...`.
pub fn equation_of(own: &str, model: &IdentifiedModel) -> String {
    let mut line = format!("{own}''");
    for c in model.coefficients() {
        let sign = if c.value < 0.0 { '-' } else { '+' };
        line.push_str(&format!(" {sign} {} {}", significant(c.value.abs(), 4), c.name));
    }
    line.push_str(" = 0");
    line
}

/// `v` to `digits` significant digits, in plain notation between 1e-4 and 1e6, else scientific.
fn significant(v: f64, digits: usize) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let exponent = v.abs().log10().floor() as i32;
    if (-4..6).contains(&exponent) {
        let decimals = (digits as i32 - 1 - exponent).max(0) as usize;
        let text = format!("{v:.decimals$}");
        if text.contains('.') {
            text.trim_end_matches('0').trim_end_matches('.').to_owned()
        } else {
            text
        }
    } else {
        format!("{v:.prec$e}", prec = digits - 1)
    }
}

/// "dropped:" and one line per dropped term, in the order of the elimination: the held-out
/// unexplained fraction without it and with it, and why.
pub fn dropped_lines(selection: &TermSelection) -> String {
    let outcome = &selection.outcome;
    let mut text = String::new();
    if outcome.dropped.is_empty() {
        text.push_str("\ndropped: none (every candidate removes more than the allowance)\n");
        return text;
    }
    let w = outcome
        .dropped
        .iter()
        .map(|d| d.name.chars().count())
        .max()
        .unwrap_or(0)
        .max(18);
    text.push_str(&format!(
        "\ndropped: held-out unexplained fraction without the term vs with it (the model without them is \
         within the allowance {:.2e} of the best)\n",
        outcome.allowance
    ));
    for d in &outcome.dropped {
        let change = d.unexplained_with - d.unexplained_without;
        let why = if change >= 0.0 {
            "no worse without it".to_owned()
        } else {
            format!("removes only {:.2e}", -change)
        };
        text.push_str(&format!(
            "{:<w$} {:>10.3e} vs {:>10.3e}: {why}\n",
            d.name, d.unexplained_without, d.unexplained_with
        ));
    }
    text
}

/// Saves a system (a model of one coordinate as that model, format 4; any other as format 5) as
/// JSON (`.json`) or compact binary (anything else), atomically.
pub fn save_system(system: &IdentifiedSystem, path: &std::path::Path) -> anyhow::Result<()> {
    let json = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("json"));
    let bytes = if json {
        system.to_json()?.into_bytes()
    } else {
        system.to_bytes()?
    };
    hb_pipeline::output::write_atomically(path, |w| w.write_all(&bytes)).map_err(Into::into)
}

fn print_table(report: &IdentifyReport, e: &hb_pipeline::EquationReport) {
    let id = &e.identification;
    let model = &id.model;
    let (method, basis) = (report.method, e.basis.spec());
    let w = model
        .coefficients()
        .iter()
        .map(|c| c.name.chars().count())
        .max()
        .unwrap_or(0)
        .max(18);
    println!("method {method}, basis {basis}");
    if let Some(s) = model.summary() {
        println!(
            "{} segments ({} whirling), {} equations, {} unknowns, solver {}",
            s.segments, s.whirling_segments, s.rows, s.unknowns, s.solver
        );
        println!(
            "condition number {:.3e}, residual RMS {:.3e}",
            s.condition, s.residual_rms
        );
    }
    println!(
        "explained {:.6} of the balanced acceleration (unexplained {:.2e})",
        id.quality.explained, id.quality.unexplained
    );
    if let Some(h) = id.quality.held_out {
        println!(
            "explained {:.6} of stretches it was not fitted on ({} folds of segments)",
            h.explained, h.folds
        );
    }
    if let Some(r) = &report.refinement {
        println!(
            "refined by the free run's error (the fit measures above are the weak form's): RMSE {:.4e} -> {:.4e} \
             over {} samples ({} per piece set the state), {} iterations, {} free runs{}",
            r.rmse_before,
            r.rmse_after,
            r.scored,
            r.init,
            r.iterations,
            r.simulations,
            if r.converged { "" } else { ", not converged" }
        );
    }
    if let Some(why) = &id.no_intervals {
        println!("no intervals: {why}");
    }
    println!();
    if let Some(w) = &id.warning {
        println!("NOT A DESCRIPTION OF THE RECORD: {w}");
    }
    match &id.intervals {
        Some(b) => {
            println!(
                "{:<w$} {:>14} {:>12}   {:.0} % interval (bootstrap, {} resamples)",
                "term",
                "coefficient",
                "std. error",
                100.0 * b.level,
                b.resamples
            );
            for c in model.coefficients() {
                let i = b.interval(&c.name);
                println!(
                    "{:<w$} {:>14.6} {:>12.2e}   [{:.6}, {:.6}]",
                    c.name,
                    c.value,
                    c.std_error,
                    i.map_or(f64::NAN, |i| i.lower),
                    i.map_or(f64::NAN, |i| i.upper)
                );
            }
        }
        None => {
            println!("{:<w$} {:>14} {:>12}", "term", "coefficient", "std. error");
            for c in model.coefficients() {
                println!("{:<w$} {:>14.6} {:>12.2e}", c.name, c.value, c.std_error);
            }
        }
    }
}
