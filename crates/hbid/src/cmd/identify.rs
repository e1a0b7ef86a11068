//! `hbid identify`: the equation of motion by harmonic balance.

use std::path::PathBuf;

use anyhow::{Context, bail};
use circle_signal::{Domain, Segment};
use clap::{Args, ValueEnum};
use hb_basis::{BasisKind, Harmonic, Hat, Polynomial};
use hb_solve::{
    BootstrapParams, DriveSamples, Forcing, Harmonics, IdentifiedModel, LstsqSolver, MAX_DRIVE_HARMONIC,
    ModelForm, NoiseCorrection, QrSolver, SelectParams, SvdSolver, TermList, WeakForm,
};
use hbid::pipeline::{Identification, ModelSpec, Setup, TermSelection, WindowOptions};
use upo_search::Windows;

pub use hbid::pipeline::Method;

use super::data::{Data, DriveFound, DriveSpec, InputArgs, SearchArgs};

/// A line on how the record's clock was found, when it was not simply given: the drive's
/// estimate with its uncertainty, or the free oscillation's period; and the resampling.
pub fn drive_note(data: &Data) -> Option<String> {
    let mut notes = Vec::new();
    match &data.drive {
        DriveFound::Given => {}
        DriveFound::Estimated(e) => notes.push(format!(
            "note: forcing period estimated from the record: {:.9} ± {:.2e} (frequency {:.9} ± {:.2e})",
            e.period,
            e.period_uncertainty,
            e.frequency(),
            e.frequency_uncertainty()
        )),
        DriveFound::Free { samples } => notes.push(format!(
            "note: no drive: windows in periods of the free oscillation, {samples:.2} samples on average ({} used)",
            data.p
        )),
    }
    if let Some(from) = data.resampled_from {
        notes.push(format!(
            "note: {from:.6} samples per forcing period: resampled (band-limited) to {}",
            data.p
        ));
    }
    (!notes.is_empty()).then(|| notes.join("\n"))
}

/// Least-squares solver.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SolverArg {
    /// Column-pivoted QR.
    Qr,
    /// Thin SVD.
    Svd,
}

/// External forcing terms cos(t), sin(t) (the d_1 p(t) of the paper's eq. 2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ForcingArg {
    /// No external forcing term.
    None,
    /// Identify the coefficients of cos(t) and sin(t).
    Identified,
}

/// Options of `hbid identify`.
#[derive(Debug, Args)]
pub struct IdentifyArgs {
    #[command(flatten)]
    pub input: InputArgs,
    /// Identification method.
    #[arg(long, value_enum, default_value_t = Method::Upo)]
    pub method: Method,
    /// Basis of the unknown functions: harmonic:K (cos kx, sin kx, k = 1..K), hat:N (N periodic hats), poly:D
    /// (x .. x^D). Default: harmonic:1 on the circle, poly:3 on the line.
    #[arg(long)]
    pub basis: Option<String>,
    /// Harmonics per segment (default: all j with j/k <= 3 forcing harmonics for a period-k orbit with
    /// --method upo, j/k <= 2 for --method windowed).
    #[arg(long)]
    pub harmonics: Option<usize>,
    /// Windowed method: window length in forcing periods.
    #[arg(long, default_value_t = Windows::DEFAULT_PERIODS)]
    pub window_periods: usize,
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
    #[arg(long, value_name = "SIGMA|auto")]
    pub noise_sigma: Option<String>,
    /// Least-squares solver.
    #[arg(long, value_enum, default_value_t = SolverArg::Qr)]
    pub solver: SolverArg,
    #[command(flatten)]
    pub search: SearchArgs,
    /// External forcing terms (default: none on the circle, identified on the line).
    #[arg(long, value_enum)]
    pub forcing: Option<ForcingArg>,
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
    ///                           or p              (the measured drive of --forcing-col)
    /// at most one function of x cos(kx), sin(kx) (harmonic basis), x, x^n (poly), hatN (hat)
    /// at most one function of x'  x', sign(x'), x'*|x'|, x'^3
    /// and 1 (no factor). Braces multiply out: {1,cos(t)}*{cos(x),sin(x)} is cos(x), sin(x),
    /// cos(t)*cos(x), cos(t)*sin(x) (the leftmost set varies slowest). White space is ignored; each
    /// term may appear once. Without --basis the smallest basis that holds every function of x named
    /// is used (cos(2x): harmonic:2; x^3: poly:3; hat7: hat:8); with it, every function named must
    /// be in it. Terms are printed and saved with these names.
    #[arg(
        long,
        value_name = "LIST",
        verbatim_doc_comment,
        conflicts_with_all = ["no_parametric", "drive_harmonics"]
    )]
    pub terms: Option<String>,
    /// The measured drive p(t): a column of the record (by header name or 1-based position), such
    /// as a shaker's base acceleration or a motor's torque, sampled with the angle. Terms name it
    /// `p` (`p`, `p*cos(x)`, `p*x'`); without --terms the default model has it in place of cos(t)
    /// and sin(t): x', {1,p}*B and (with --forcing identified, the default on the line) p, B the
    /// basis. The weak form (--method windowed) balances it at every sample as measured, of any
    /// waveform; windows are still counted in forcing periods (--forcing-period, or --forcing none
    /// for periods of the oscillation).
    #[arg(long, value_name = "NAME|N")]
    pub forcing_col: Option<String>,
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
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Save the identified model: JSON if the name ends in .json, compact binary otherwise (with
    /// --select, the model of the kept terms).
    #[arg(long, value_name = "PATH")]
    pub save_model: Option<PathBuf>,
}

/// The command line's name of a basis: `harmonic:K`, `hat:N` or `poly:D`.
pub fn basis_spec(basis: &BasisKind) -> String {
    match basis {
        BasisKind::Harmonic(b) => format!("harmonic:{}", b.order()),
        BasisKind::Hat(b) => format!("hat:{}", b.nodes()),
        BasisKind::Polynomial(b) => format!("poly:{}", b.degree()),
    }
}

/// Parses `harmonic:K`, `hat:N` or `poly:D`.
pub fn parse_basis(text: &str) -> anyhow::Result<BasisKind> {
    let (kind, n) = text
        .split_once(':')
        .ok_or_else(|| anyhow::anyhow!("--basis '{text}': expected harmonic:K, hat:N or poly:D"))?;
    let n: usize = n
        .trim()
        .parse()
        .map_err(|_| anyhow::anyhow!("--basis '{text}': '{n}' is not a whole number"))?;
    let basis = match kind.trim() {
        "harmonic" => BasisKind::from(Harmonic::new(n)?),
        "hat" => BasisKind::from(Hat::new(n)?),
        "poly" => BasisKind::from(Polynomial::new(n)?),
        other => bail!("--basis '{text}': unknown basis '{other}' (harmonic, hat or poly)"),
    };
    Ok(basis)
}

impl IdentifyArgs {
    /// The setup of the chosen method on `data`, every option checked.
    pub fn setup(&self, data: &Data) -> anyhow::Result<Setup> {
        Ok(self.spec(data, self.method)?.setup(&data.clock)?)
    }

    /// Whether `--forcing none` was asked for: with no forcing period or frequency given either,
    /// the record is a free oscillation.
    pub fn free(&self) -> bool {
        self.forcing == Some(ForcingArg::None)
    }

    /// Reads the record with these options' drive, showing the estimate of the drive (if any) on
    /// `progress`.
    pub fn load(&self, progress: &mut dyn FnMut(usize, usize)) -> anyhow::Result<Data> {
        let drive = self.input.drive(self.free())?;
        if drive == DriveSpec::Free && self.method == Method::Upo {
            bail!(
                "--forcing none without a forcing period is a free oscillation, which has no periodic orbits: use --method windowed"
            );
        }
        self.input
            .load_with_drive_column(drive, self.forcing_col.as_deref(), progress)
    }

    /// The terms of `--terms`, parsed.
    pub fn term_list(&self) -> anyhow::Result<Option<TermList>> {
        self.terms
            .as_deref()
            .map(|text| TermList::parse(text).context("--terms"))
            .transpose()
    }

    /// The basis as named on the command line (default: the smallest that holds the functions of x
    /// of --terms, otherwise harmonic:1 on the circle, poly:3 on the line), for the outputs.
    pub fn basis_name(&self, domain: Domain) -> String {
        if let Some(name) = &self.basis {
            return name.clone();
        }
        let inferred = self
            .term_list()
            .ok()
            .flatten()
            .and_then(|list| list.smallest_basis().ok().flatten());
        match inferred {
            Some(basis) => basis_spec(&basis),
            None => match domain {
                Domain::Circle => "harmonic:1".to_owned(),
                Domain::Line => "poly:3".to_owned(),
            },
        }
    }

    /// The form of the model: `--terms` (checked against the basis and the record), or the
    /// default with `--forcing`, `--no-parametric` and `--drive-harmonics`.
    fn form(&self, data: &Data, basis: &BasisKind) -> anyhow::Result<ModelForm> {
        let domain = data.domain;
        let free = matches!(data.drive, DriveFound::Free { .. });
        if let Some(list) = self.term_list()? {
            if self.forcing == Some(ForcingArg::Identified) {
                bail!("--forcing identified with --terms: name the forcing terms cos(t), sin(t) in the list");
            }
            list.check_domain(domain).context("--terms")?;
            list.resolve(basis)
                .with_context(|| format!("--terms with the basis {}", self.basis_name(domain)))?;
            if free && let Some(t) = list.phase_term() {
                bail!(
                    "--terms: the term `{t}` has a drive factor, but the record is a free oscillation without a drive"
                );
            }
            match (list.measured_term(), &self.forcing_col) {
                (Some(t), None) => bail!(
                    "--terms: the term `{t}` has the measured drive p: name the record's column that holds it with --forcing-col"
                ),
                (None, Some(col)) => {
                    bail!("--forcing-col {col}: no term of --terms has the measured drive p")
                }
                _ => {}
            }
            return Ok(self.with_drive_column(ModelForm::from_terms(list)));
        }
        if let Some(col) = &self.forcing_col {
            return self.measured_default(col, domain, basis);
        }
        let forcing = match self.forcing.unwrap_or(match domain {
            Domain::Circle => ForcingArg::None,
            Domain::Line => ForcingArg::Identified,
        }) {
            ForcingArg::None => Forcing::None,
            ForcingArg::Identified => Forcing::Identified,
        };
        let mut form = ModelForm::parametric().with_forcing(forcing);
        if self.no_parametric || free {
            form = form.without_parametric_terms();
        }
        match self.drive_harmonics {
            Some(h) if !(1..=MAX_DRIVE_HARMONIC).contains(&h) => {
                bail!("--drive-harmonics {h}: must be between 1 and {MAX_DRIVE_HARMONIC}")
            }
            Some(h) => form = form.with_drive_harmonics(h),
            None => {}
        }
        Ok(form)
    }

    /// The default model with the measured drive `p` of `--forcing-col` in place of cos(t) and
    /// sin(t): `x'`, `{1,p}*B` (`B` without `--no-parametric`) and `p` with the forcing
    /// identified (the default on the line).
    fn measured_default(&self, col: &str, domain: Domain, basis: &BasisKind) -> anyhow::Result<ModelForm> {
        if let Some(h) = self.drive_harmonics {
            bail!(
                "--drive-harmonics {h} with --forcing-col {col}: the measured drive p has no harmonics to name; \
                 list terms such as cos(2t)*sin(x) with --terms"
            );
        }
        let functions = hb_basis::Basis::names(basis).join(",");
        let mut spec = if self.no_parametric {
            format!("x', {{{functions}}}")
        } else {
            format!("x', {{1,p}}*{{{functions}}}")
        };
        let forcing = self.forcing.unwrap_or(match domain {
            Domain::Circle => ForcingArg::None,
            Domain::Line => ForcingArg::Identified,
        });
        if forcing == ForcingArg::Identified {
            spec.push_str(", p");
        }
        let list = TermList::parse(&spec)
            .with_context(|| format!("the default terms with --forcing-col: {spec}"))?;
        if !list.has_measured_drive() {
            bail!(
                "--forcing-col {col} with --no-parametric and --forcing none: no term has the measured drive p"
            );
        }
        Ok(self.with_drive_column(ModelForm::from_terms(list)))
    }

    /// The form with the name of `--forcing-col`, when given.
    fn with_drive_column(&self, form: ModelForm) -> ModelForm {
        match &self.forcing_col {
            Some(col) => form.with_drive_column(col.trim()),
            None => form,
        }
    }

    /// What these options ask to identify by `method` (which may differ from the one chosen on the
    /// command line) on `data`: a free oscillation has no drive terms at all.
    pub fn spec(&self, data: &Data, method: Method) -> anyhow::Result<ModelSpec> {
        let domain = data.domain;
        // A malformed list is named before a basis inferred from it.
        self.term_list()?;
        let basis = parse_basis(&self.basis_name(domain))?;
        let form = self.form(data, &basis)?;
        if form.has_measured_drive() && method == Method::Upo {
            bail!(
                "--forcing-col: the measured drive p is balanced by the weak form only (--method windowed): a periodic \
                 orbit of the state does not make the series of a measured drive close"
            );
        }
        let mut spec = ModelSpec::new(method, basis)
            .with_form(form)
            .with_weak_form(WeakForm::new(self.window_order)?);
        if let Some(p) = &data.measured_drive {
            spec = spec.with_drive_samples(DriveSamples::new(p.clone())?);
        }
        match self.harmonics {
            Some(0) => bail!("--harmonics must be at least 1"),
            Some(m) => spec = spec.with_harmonics(Harmonics::Fixed(m))?,
            None => {}
        }
        let noise = match self.noise_sigma.as_deref() {
            None => NoiseCorrection::None,
            Some("auto") => NoiseCorrection::Estimated,
            Some(text) => NoiseCorrection::Given {
                sigma: text
                    .parse()
                    .map_err(|_| anyhow::anyhow!("--noise-sigma '{text}': a number of radians or auto"))?,
            },
        };
        let solver: Box<dyn LstsqSolver> = match self.solver {
            SolverArg::Qr => Box::new(QrSolver::default()),
            SolverArg::Svd => Box::new(SvdSolver::default()),
        };
        spec = spec.with_noise_correction(noise).with_solver(solver);
        if let Some(params) = self.selection()? {
            spec = spec.with_selection(params);
        }
        self.windows()?;
        if self.bootstrap > 0 {
            spec = spec.with_bootstrap(
                BootstrapParams::builder()
                    .resamples(self.bootstrap)
                    .level(self.level)
                    .seed(self.seed)
                    .build()?,
            );
        }
        Ok(spec)
    }

    /// The parameters of `--select`, checked (`None` without it).
    pub fn selection(&self) -> anyhow::Result<Option<SelectParams>> {
        if !self.select {
            return Ok(None);
        }
        if self.select_folds < 2 {
            bail!("--select-folds {}: must be at least 2", self.select_folds);
        }
        if !(0.0..1.0).contains(&self.select_tolerance) {
            bail!(
                "--select-tolerance {}: must be a fraction of the held-out power in [0, 1)",
                self.select_tolerance
            );
        }
        Ok(Some(SelectParams::new(self.select_folds, self.select_tolerance)?))
    }

    /// The options of the windowed method's windows.
    pub fn windows(&self) -> anyhow::Result<WindowOptions> {
        if self.window_periods == 0 {
            bail!("--window-periods must be at least 1");
        }
        Ok(WindowOptions::default().with_periods(self.window_periods)?)
    }

    /// The segments of the chosen method: close returns (with the delay) or plain windows.
    pub fn segments(&self, data: &Data, delay: usize, method: Method) -> anyhow::Result<Vec<Segment>> {
        Ok(match method {
            Method::Upo => self
                .search
                .close_returns(data, delay)?
                .search_pieces(&data.x, &data.pieces)?,
            Method::Windowed => self
                .windows()?
                .windows(&data.record()?)?
                .windows_pieces(&data.x, &data.pieces)?,
        })
    }
}

/// For a velocity or acceleration record: the integrated record with the drift that the model of
/// `setup` explains best over `segments` ([`hbid::pipeline::fit_drift`]), and a note of it on
/// standard error; `None` for a displacement record.
pub fn fitted_drift(
    args: &IdentifyArgs,
    data: &Data,
    setup: &Setup,
    segments: &[Segment],
    found: &str,
) -> anyhow::Result<Option<Vec<f64>>> {
    let measured = circle_signal::Measured::from(args.input.measured);
    if measured == circle_signal::Measured::Displacement {
        return Ok(None);
    }
    let (x, fit) = hbid::pipeline::fit_drift(setup, &data.x, &data.pieces, segments, measured, |_, _| {})
        .with_context(|| format!("{found}: fitting the integrated record's drift"))?;
    if fit.evaluations > 0 {
        let period = data.p as f64;
        let pieces: Vec<String> = fit
            .pieces
            .iter()
            .map(|d| {
                format!(
                    "slope {:.3e} per period, offset {:.3e}",
                    d.slope * period,
                    d.offset
                )
            })
            .collect();
        eprintln!(
            "note: the drift of the integrated record that the model explains best ({}): unexplained {:.2e} before, {:.2e} after",
            pieces.join("; "),
            fit.unexplained_before,
            fit.unexplained_after
        );
    }
    Ok(Some(x))
}

pub fn run(args: &IdentifyArgs, quiet: bool, timings: bool) -> anyhow::Result<()> {
    let mut stages = crate::progress::Stages::new("identify", quiet, timings);
    if let Some(path) = &args.save_model {
        crate::output::check_output_path(path).context("--save-model")?;
    }
    stages.start("read");
    let data = args.load(&mut |_, _| {})?;
    if let Some(note) = drive_note(&data) {
        eprintln!("{note}");
    }
    let setup = args.setup(&data)?;
    let delay = match args.method {
        Method::Upo => {
            stages.start("delay");
            args.search.delay(&data)?
        }
        Method::Windowed => 1,
    };
    stages.start("segments");
    let segments = args.segments(&data, delay, args.method)?;
    let found = match args.method {
        Method::Upo => format!(
            "{} orbit segments found at tolerance {}",
            segments.len(),
            args.search.tolerance
        ),
        Method::Windowed => format!(
            "{} windows of {} {} periods",
            segments.len(),
            args.window_periods,
            if matches!(data.drive, DriveFound::Free { .. }) {
                "oscillation"
            } else {
                "forcing"
            }
        ),
    };
    let drifted = fitted_drift(args, &data, &setup, &segments, &found)?;
    let x = drifted.as_deref().unwrap_or(&data.x);
    let id = setup
        .identify_with_progress(x, &segments, |step| stages.start(step.name()))
        .with_context(|| found)?;
    stages.finish();
    if let Some(path) = &args.save_model {
        save_model(&id.model, path)?;
    }
    let basis_name = args.basis_name(data.domain);
    if let Some(w) = &id.warning {
        eprintln!("warning: {w}");
    }
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&hbid::json::identification(&id, args.method.name(), &basis_name))?
        );
    } else {
        if let Some(selection) = &id.selection {
            println!("{}", equation(&id.model));
            println!(
                "selected {} of {} candidate terms ({} folds of segments)",
                selection.kept.len(),
                selection.library.len(),
                selection.outcome.folds
            );
        }
        print_table(&id, args.method.name(), &basis_name);
        if let Some(selection) = &id.selection {
            print!("{}", dropped_lines(selection));
        }
    }
    Ok(())
}

/// The model's equation on one line, its terms in order with signed coefficients:
/// `x'' + 0.0301 x' + 0.0497 sign(x') - 1.52 sin(t)*cos(x) = 0`.
pub fn equation(model: &IdentifiedModel) -> String {
    let mut line = "x''".to_owned();
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

/// Saves a model as JSON (`.json`) or compact binary (anything else), atomically.
pub fn save_model(model: &IdentifiedModel, path: &std::path::Path) -> anyhow::Result<()> {
    let json = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("json"));
    let bytes = if json {
        model.to_json()?.into_bytes()
    } else {
        model.to_bytes()?
    };
    crate::output::write_atomically(path, |w| w.write_all(&bytes)).map_err(Into::into)
}

fn print_table(id: &Identification, method: &str, basis: &str) {
    let model = &id.model;
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
