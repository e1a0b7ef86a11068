//! `identify`, `embed` and `upos` as the command line runs them, on a record from arrays or from
//! `read`.

use circle_signal::{Domain, Segment};
use embedding::{AmiParams, FnnParams, average_mutual_information, false_nearest_neighbours};
use hb_basis::BasisKind;
use hb_pipeline::pipeline::{EmbedOptions, Method, ModelSpec, SearchOptions, WindowOptions};
use hb_record::prepare::{Data, DriveFound};
use hb_solve::{
    BootstrapParams, Forcing, Harmonics, LstsqSolver, ModelForm, QrSolver, SelectParams, SvdSolver, TermList,
    WeakForm,
};
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use upo_search::Windows;

use crate::errors::Kind;
use crate::options::{self, Failure, NumberOrText, bad, fail};
use crate::record::{Grid, Source, data, domain_name};

/// Where the record comes from, as Python passes it.
fn source<'a>(
    x: &'a [f64],
    t: Option<&'a [f64]>,
    dt: Option<f64>,
    grid: Option<Grid>,
    repair: bool,
) -> Result<Source<'a>, Failure> {
    match grid {
        Some(grid) => {
            if t.is_some() || dt.is_some() {
                return Err(bad("a Record carries its own time: give no t or dt with it"));
            }
            Ok(Source::Grid { x, grid })
        }
        None => Ok(Source::Raw { x, t, dt, repair }),
    }
}

/// The search's options from the Python arguments (defaults: the command line's).
fn search_options(
    tolerance: Option<f64>,
    max_period: Option<usize>,
    dim: Option<usize>,
) -> Result<SearchOptions, Failure> {
    let mut search = SearchOptions::default();
    if let Some(t) = tolerance {
        search = search.with_tolerance(t).map_err(fail(Kind::Options))?;
    }
    if let Some(m) = max_period {
        search = search.with_max_period(m).map_err(fail(Kind::Options))?;
    }
    if let Some(d) = dim {
        search = search.with_dimension(d).map_err(fail(Kind::Options))?;
    }
    Ok(search)
}

/// The delay: the one given, or the first minimum of the mutual information. The search's
/// options are checked against the record first, so that a bad option fails before any work.
fn delay(search: &SearchOptions, data: &Data, given: Option<usize>) -> Result<usize, Failure> {
    let record = hb_pipeline::pipeline::Record::from_data(data).map_err(fail(Kind::Input))?;
    search
        .close_returns(&record, given.unwrap_or(1))
        .map_err(fail(Kind::Options))?;
    match given {
        Some(d) => Ok(d),
        None => {
            let max_lag = EmbedOptions::default().max_lag(data.p);
            let params = AmiParams::new(data.domain)
                .with_max_lag(max_lag)
                .map_err(fail(Kind::Options))?;
            first_minimum(data.longest(), &params).map(|(_, d)| d)
        }
    }
}

/// The mutual-information curve and its first minimum.
fn first_minimum(x: &[f64], params: &AmiParams) -> Result<(embedding::AmiCurve, usize), Failure> {
    let curve = average_mutual_information(x, params).map_err(fail(Kind::Identification))?;
    let delay = curve.delay().map_err(|e| {
        let (kind, text) = fail(Kind::Identification)(e);
        (
            kind,
            format!("{text}: choose the delay with delay=, or raise max_lag="),
        )
    })?;
    Ok((curve, delay))
}

/// Everything `identify` is asked, as the command line's options.
#[derive(Debug)]
pub struct IdentifyOptions {
    pub method: String,
    pub basis: Option<String>,
    pub harmonics: Option<usize>,
    pub window_periods: Option<usize>,
    pub window_order: Option<u32>,
    pub bootstrap: usize,
    pub level: Option<f64>,
    pub seed: u64,
    pub noise_sigma: Option<NumberOrText>,
    pub solver: String,
    pub forcing: Option<String>,
    pub parametric: bool,
    /// `terms=`: the model's terms, a list as `--terms` reads it.
    pub terms: Option<String>,
    /// `select=`: the selection's folds and tolerance, when asked.
    pub select: Option<(usize, f64)>,
}

impl IdentifyOptions {
    /// The windows of the windowed method.
    fn windows(&self) -> Result<WindowOptions, Failure> {
        let periods = self.window_periods.unwrap_or(Windows::DEFAULT_PERIODS);
        if periods == 0 {
            return Err(bad("window_periods must be at least 1"));
        }
        WindowOptions::default()
            .with_periods(periods)
            .map_err(fail(Kind::Options))
    }

    /// The terms of `terms=`, parsed.
    fn term_list(&self) -> Result<Option<TermList>, Failure> {
        self.terms
            .as_deref()
            .map(|text| TermList::parse(text).map_err(terms_error))
            .transpose()
    }

    /// The basis as named on the command line: the one given, or the smallest that holds the
    /// functions of x of `terms=`, or the domain's default.
    pub fn basis_name(&self, domain: Domain) -> Result<String, Failure> {
        if let Some(name) = &self.basis {
            return Ok(name.clone());
        }
        let inferred = match self.term_list()? {
            Some(list) => list.smallest_basis().map_err(terms_error)?,
            None => None,
        };
        Ok(match inferred {
            Some(BasisKind::Harmonic(b)) => format!("harmonic:{}", b.order()),
            Some(BasisKind::Hat(b)) => format!("hat:{}", b.nodes()),
            Some(BasisKind::Polynomial(b)) => format!("poly:{}", b.degree()),
            None => options::default_basis_name(domain).to_owned(),
        })
    }

    /// The model's form: `terms=` (checked against the basis and the record), or the default
    /// with `forcing=` and `parametric=`; a free oscillation has no drive terms at all.
    fn form(&self, data: &Data, basis: &BasisKind, forcing: Forcing) -> Result<ModelForm, Failure> {
        let free = matches!(data.drive, DriveFound::Free { .. });
        if let Some(list) = self.term_list()? {
            if self.forcing.as_deref() == Some("identified") {
                return Err(bad(
                    "forcing='identified' with terms=: name the forcing terms cos(t), sin(t) in the list",
                ));
            }
            if !self.parametric {
                return Err(bad(
                    "parametric=False with terms=: the list says its terms (leave out cos(t)*B, sin(t)*B)",
                ));
            }
            list.check_domain(data.domain).map_err(terms_error)?;
            list.resolve(basis).map_err(terms_error)?;
            if free && let Some(t) = list.terms().iter().find(|t| t.drive.harmonic() > 0) {
                return Err(bad(format!(
                    "terms: the term `{t}` has a drive factor, but the record is a free oscillation without a drive"
                )));
            }
            return Ok(ModelForm::from_terms(list));
        }
        let mut form = ModelForm::parametric().with_forcing(forcing);
        if !self.parametric || free {
            form = form.without_parametric_terms();
        }
        Ok(form)
    }

    /// What to identify on `data`, as `hbid identify` builds it.
    fn spec(&self, method: Method, data: &Data, forcing: Forcing) -> Result<ModelSpec, Failure> {
        // A malformed list is named before a basis inferred from it.
        self.term_list()?;
        let basis = options::basis(&self.basis_name(data.domain)?)?;
        let form = self.form(data, &basis, forcing)?;
        let weak =
            WeakForm::new(self.window_order.unwrap_or(WeakForm::DEFAULT_WINDOW_ORDER)).map_err(|e| {
                let (kind, text) = fail(Kind::Options)(e);
                (kind, format!("window_order: {text}"))
            })?;
        let mut spec = ModelSpec::new(method, basis).with_form(form).with_weak_form(weak);
        match self.harmonics {
            Some(0) => return Err(bad("harmonics must be at least 1")),
            Some(m) => {
                spec = spec
                    .with_harmonics(Harmonics::Fixed(m))
                    .map_err(fail(Kind::Options))?;
            }
            None => {}
        }
        let solver: Box<dyn LstsqSolver> = match self.solver.as_str() {
            "qr" => Box::new(QrSolver::default()),
            "svd" => Box::new(SvdSolver::default()),
            other => return Err(bad(format!("solver='{other}': expected 'qr' or 'svd'"))),
        };
        spec = spec
            .with_noise_correction(options::noise(self.noise_sigma.clone())?)
            .with_solver(solver);
        if let Some((folds, tolerance)) = self.select {
            let params = SelectParams::new(folds, tolerance).map_err(|e| {
                let (kind, message) = fail(Kind::Options)(e);
                (kind, format!("select: {message}"))
            })?;
            spec = spec.with_selection(params);
        }
        self.windows()?;
        if self.bootstrap > 0 {
            let params = BootstrapParams::builder()
                .resamples(self.bootstrap)
                .level(self.level.unwrap_or(BootstrapParams::DEFAULT_LEVEL))
                .seed(self.seed)
                .build()
                .map_err(fail(Kind::Options))?;
            spec = spec.with_bootstrap(params);
        }
        Ok(spec)
    }

    /// The external forcing terms: the ones asked for, or none on the circle and identified on
    /// the line.
    fn forcing(&self, domain: Domain) -> Result<Forcing, Failure> {
        match self.forcing.as_deref() {
            None => Ok(match domain {
                Domain::Circle => Forcing::None,
                Domain::Line => Forcing::Identified,
            }),
            Some("none") => Ok(Forcing::None),
            Some("identified") => Ok(Forcing::Identified),
            Some(other) => Err(bad(format!("forcing='{other}': expected 'none' or 'identified'"))),
        }
    }
}

/// A bad `terms=`, named.
fn terms_error(e: hb_solve::SolveError) -> Failure {
    let (kind, message) = fail(Kind::Options)(e);
    (kind, format!("terms: {message}"))
}

/// The bootstrap intervals: level, resamples and `(name, lower, upper)` of each coefficient.
type Intervals = (f64, usize, Vec<(String, f64, f64)>);

/// What an identification gives back, before it becomes Python objects.
#[derive(Debug)]
pub struct Identified {
    /// The JSON of `hbid identify --json`.
    pub json: String,
    coefficients: Vec<(String, f64, f64)>,
    intervals: Option<Intervals>,
    model: Vec<u8>,
    basis: String,
    segments: usize,
    delay: Option<usize>,
    data: Data,
    summary: String,
}

/// What `identify` is asked, besides the record.
#[derive(Debug)]
pub struct Request {
    /// `circle` or `line`.
    pub signal: String,
    /// The forcing period given, if any.
    pub forcing_period: Option<NumberOrText>,
    /// The forcing frequency given, if any.
    pub forcing_frequency: Option<NumberOrText>,
    /// The model and the fit.
    pub options: IdentifyOptions,
    /// Close-return tolerance.
    pub tolerance: Option<f64>,
    /// Longest orbit period.
    pub max_period: Option<usize>,
    /// Dimension of the delay vectors.
    pub dim: Option<usize>,
    /// Delay of the close-return search.
    pub delay: Option<usize>,
}

/// One identification of `source`, as `hbid identify --json` runs it; no Python involved.
pub fn identify_core(source: Source<'_>, request: Request) -> Result<Identified, Failure> {
    let Request {
        signal,
        forcing_period,
        forcing_frequency,
        options: opts,
        tolerance,
        max_period,
        dim,
        delay,
    } = request;
    let domain = options::domain(&signal, "signal", false)?;
    let method = options::method(&opts.method)?;
    let free = opts.forcing.as_deref() == Some("none");
    let drive = options::drive(forcing_period, forcing_frequency, free)?;
    let forcing = opts.forcing(domain)?;
    let search = search_options(tolerance, max_period, dim)?;
    if drive == hb_record::prepare::DriveSpec::Free && method == Method::Upo {
        return Err(bad(
            "forcing='none' without a forcing period is a free oscillation, which has no periodic orbits: use method='windowed'",
        ));
    }
    let data = data(source, domain, drive)?;
    let setup = opts
        .spec(method, &data, forcing)?
        .setup(&data.clock)
        .map_err(fail(Kind::Options))?;
    let (segments, delay, found) = match method {
        Method::Upo => {
            let d = self::delay(&search, &data, delay)?;
            let record = hb_pipeline::pipeline::Record::from_data(&data).map_err(fail(Kind::Input))?;
            let segments = search
                .close_returns(&record, d)
                .and_then(|s| Ok(s.search_pieces(&data.x, &data.pieces)?))
                .map_err(fail(Kind::Identification))?;
            let found = format!(
                "{} orbit segments found at tolerance {}",
                segments.len(),
                search.tolerance()
            );
            (segments, Some(d), found)
        }
        Method::Windowed => {
            let windows = opts.windows()?;
            let record = hb_pipeline::pipeline::Record::from_data(&data).map_err(fail(Kind::Input))?;
            let segments: Vec<Segment> = windows
                .windows(&record)
                .and_then(|w| Ok(w.windows_pieces(&data.x, &data.pieces)?))
                .map_err(fail(Kind::Identification))?;
            let unit = if matches!(data.drive, DriveFound::Free { .. }) {
                "oscillation"
            } else {
                "forcing"
            };
            let found = format!(
                "{} windows of {} {unit} periods",
                segments.len(),
                windows.periods()
            );
            (segments, None, found)
        }
    };
    let id = setup.identify(&data.x, &segments).map_err(|e| {
        let (kind, text) = fail(Kind::Identification)(e);
        (kind, format!("{found}: {text}"))
    })?;
    let basis_name = opts.basis_name(domain)?;
    let json = serde_json::to_string_pretty(&hb_pipeline::json::identification(
        &id,
        method.name(),
        &basis_name,
    ))
    .map_err(fail(Kind::Identification))?;
    let model = id.model.to_bytes().map_err(fail(Kind::Model))?;
    let coefficients = id
        .model
        .coefficients()
        .iter()
        .map(|c| (c.name.clone(), c.value, c.std_error))
        .collect();
    let intervals = id.intervals.as_ref().map(|b| {
        (
            b.level,
            b.resamples,
            b.intervals
                .iter()
                .map(|i| (i.name.clone(), i.lower, i.upper))
                .collect(),
        )
    });
    Ok(Identified {
        json,
        coefficients,
        intervals,
        model,
        basis: basis_name,
        segments: segments.len(),
        delay,
        summary: data.summary(),
        data,
    })
}

/// Identifies the equation of motion of a record, as `hbid identify --json` does.
#[pyfunction]
#[pyo3(signature = (
    x, *, t=None, dt=None, grid=None, repair=false, signal="circle", forcing_period=None,
    forcing_frequency=None, forcing=None, parametric=true, method="windowed", basis=None,
    harmonics=None, window_periods=None, window_order=None, bootstrap=BootstrapParams::DEFAULT_RESAMPLES,
    level=None, seed=0, noise_sigma=None, solver="qr", tolerance=None, max_period=None, dim=None,
    delay=None, terms=None, select=false, select_folds=SelectParams::DEFAULT_FOLDS,
    select_tolerance=SelectParams::DEFAULT_TOLERANCE
))]
#[allow(clippy::too_many_arguments)]
pub fn identify<'py>(
    py: Python<'py>,
    x: PyReadonlyArray1<'py, f64>,
    t: Option<PyReadonlyArray1<'py, f64>>,
    dt: Option<f64>,
    grid: Option<Grid>,
    repair: bool,
    signal: &str,
    forcing_period: Option<NumberOrText>,
    forcing_frequency: Option<NumberOrText>,
    forcing: Option<String>,
    parametric: bool,
    method: &str,
    basis: Option<String>,
    harmonics: Option<usize>,
    window_periods: Option<usize>,
    window_order: Option<u32>,
    bootstrap: usize,
    level: Option<f64>,
    seed: u64,
    noise_sigma: Option<NumberOrText>,
    solver: &str,
    tolerance: Option<f64>,
    max_period: Option<usize>,
    dim: Option<usize>,
    delay: Option<usize>,
    terms: Option<String>,
    select: bool,
    select_folds: usize,
    select_tolerance: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let x = crate::slice(&x)?;
    let t = t.as_ref().map(crate::slice).transpose()?;
    let request = Request {
        signal: signal.to_owned(),
        forcing_period,
        forcing_frequency,
        options: IdentifyOptions {
            method: method.to_owned(),
            basis,
            harmonics,
            window_periods,
            window_order,
            bootstrap,
            level,
            seed,
            noise_sigma,
            solver: solver.to_owned(),
            forcing,
            parametric,
            terms,
            select: select.then_some((select_folds, select_tolerance)),
        },
        tolerance,
        max_period,
        dim,
        delay,
    };
    let done = py
        .detach(|| identify_core(source(x, t, dt, grid, repair)?, request))
        .map_err(crate::raise)?;
    let out = PyDict::new(py);
    out.set_item("json", done.json)?;
    out.set_item("coefficients", done.coefficients)?;
    match done.intervals {
        Some((level, resamples, intervals)) => {
            out.set_item("interval_level", level)?;
            out.set_item("resamples", resamples)?;
            out.set_item("intervals", intervals)?;
        }
        None => {
            out.set_item("interval_level", py.None())?;
            out.set_item("resamples", 0)?;
            out.set_item("intervals", py.None())?;
        }
    }
    out.set_item("model", PyBytes::new(py, &done.model))?;
    out.set_item("method", method)?;
    out.set_item("basis", done.basis)?;
    out.set_item("segments", done.segments)?;
    out.set_item("delay", done.delay)?;
    out.set_item("summary", done.summary)?;
    drive_items(&out, &done.data)?;
    Ok(out)
}

/// The record's clock and where its forcing period came from.
fn drive_items(out: &Bound<'_, PyDict>, data: &Data) -> PyResult<()> {
    out.set_item("forcing_period", data.clock.forcing_period())?;
    out.set_item("samples_per_period", data.p)?;
    out.set_item("resampled_from", data.resampled_from)?;
    out.set_item("signal", domain_name(data.domain))?;
    let (drive, uncertainty) = match &data.drive {
        DriveFound::Given => ("given", None),
        DriveFound::Estimated(e) => ("estimated", Some(e.period_uncertainty)),
        DriveFound::Free { .. } => ("free", None),
    };
    out.set_item("drive", drive)?;
    out.set_item("forcing_period_uncertainty", uncertainty)?;
    Ok(())
}

/// The delay by the first minimum of the average mutual information and the embedding
/// dimension by false nearest neighbours, as `hbid embed --json` gives them.
#[pyfunction]
#[pyo3(signature = (
    x, *, t=None, dt=None, grid=None, repair=false, signal="circle", forcing_period=None,
    forcing_frequency=None, max_lag=None, bins=AmiParams::DEFAULT_BINS, max_dim=FnnParams::DEFAULT_MAX_DIM,
    metric=None, theiler=0
))]
#[allow(clippy::too_many_arguments)]
pub fn embed<'py>(
    py: Python<'py>,
    x: PyReadonlyArray1<'py, f64>,
    t: Option<PyReadonlyArray1<'py, f64>>,
    dt: Option<f64>,
    grid: Option<Grid>,
    repair: bool,
    signal: &str,
    forcing_period: Option<NumberOrText>,
    forcing_frequency: Option<NumberOrText>,
    max_lag: Option<usize>,
    bins: usize,
    max_dim: usize,
    metric: Option<String>,
    theiler: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let x = crate::slice(&x)?;
    let t = t.as_ref().map(crate::slice).transpose()?;
    let (data, curve, delay, fnn, metric) = py
        .detach(|| {
            if bins < 2 {
                return Err(bad(format!("bins={bins} must be at least 2")));
            }
            if max_dim == 0 {
                return Err(bad("max_dim must be at least 1"));
            }
            let domain = options::domain(signal, "signal", false)?;
            let metric = metric
                .as_deref()
                .map(|m| options::domain(m, "metric", true))
                .transpose()?;
            let drive = options::drive(forcing_period, forcing_frequency, false)?;
            let data = data(source(x, t, dt, grid, repair)?, domain, drive)?;
            let metric = metric.unwrap_or(data.domain);
            let max_lag = max_lag.unwrap_or_else(|| EmbedOptions::default().max_lag(data.p));
            let params = AmiParams::new(metric)
                .with_bins(bins)
                .and_then(|p| p.with_max_lag(max_lag))
                .map_err(fail(Kind::Options))?;
            let (curve, delay) = first_minimum(data.longest(), &params)?;
            let params = FnnParams::new(metric, delay)
                .and_then(|p| p.with_max_dim(max_dim))
                .map_err(fail(Kind::Options))?
                .with_theiler_window(theiler);
            let fnn =
                false_nearest_neighbours(data.longest(), &params).map_err(fail(Kind::Identification))?;
            Ok((data, curve, delay, fnn, metric))
        })
        .map_err(crate::raise)?;
    let out = PyDict::new(py);
    let json = serde_json::to_string(&hb_pipeline::json::embedding(&curve, delay, &fnn))
        .map_err(|e| crate::errors::raise(Kind::Identification, e))?;
    out.set_item("json", json)?;
    out.set_item("delay", delay)?;
    out.set_item("embedding_dimension", fnn.minimum_dimension())?;
    out.set_item(
        "fnn",
        PyArray1::from_vec(py, fnn.levels.iter().map(|l| l.fraction()).collect()),
    )?;
    out.set_item("fraction_threshold", fnn.fraction_threshold)?;
    out.set_item("ami", PyArray1::from_vec(py, curve.values))?;
    out.set_item("metric", domain_name(metric))?;
    out.set_item("summary", data.summary())?;
    drive_items(&out, &data)?;
    Ok(out)
}

/// Unstable periodic orbits by close returns, as `hbid upos --json` gives them.
#[pyfunction]
#[pyo3(signature = (
    x, *, t=None, dt=None, grid=None, repair=false, signal="circle", forcing_period=None,
    forcing_frequency=None, tolerance=None, max_period=None, dim=None, delay=None
))]
#[allow(clippy::too_many_arguments)]
pub fn upos<'py>(
    py: Python<'py>,
    x: PyReadonlyArray1<'py, f64>,
    t: Option<PyReadonlyArray1<'py, f64>>,
    dt: Option<f64>,
    grid: Option<Grid>,
    repair: bool,
    signal: &str,
    forcing_period: Option<NumberOrText>,
    forcing_frequency: Option<NumberOrText>,
    tolerance: Option<f64>,
    max_period: Option<usize>,
    dim: Option<usize>,
    delay: Option<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    let x = crate::slice(&x)?;
    let t = t.as_ref().map(crate::slice).transpose()?;
    let (data, catalogue, delay) = py
        .detach(|| {
            let domain = options::domain(signal, "signal", false)?;
            let search = search_options(tolerance, max_period, dim)?;
            let drive = options::drive(forcing_period, forcing_frequency, false)?;
            let data = data(source(x, t, dt, grid, repair)?, domain, drive)?;
            let d = self::delay(&search, &data, delay)?;
            let record = hb_pipeline::pipeline::Record::from_data(&data).map_err(fail(Kind::Input))?;
            let catalogue = search
                .close_returns(&record, d)
                .and_then(|s| Ok(s.catalogue_pieces(&data.x, &data.pieces)?))
                .map_err(fail(Kind::Identification))?;
            Ok((data, catalogue, d))
        })
        .map_err(crate::raise)?;
    let out = PyDict::new(py);
    let json = serde_json::to_string(&hb_pipeline::json::orbits(&catalogue))
        .map_err(|e| crate::errors::raise(Kind::Identification, e))?;
    out.set_item("json", json)?;
    out.set_item("delay", delay)?;
    out.set_item("tolerance", catalogue.tolerance())?;
    out.set_item(
        "segments",
        catalogue
            .segments()
            .iter()
            .map(|s| (s.period(), s.start(), s.error()))
            .collect::<Vec<_>>(),
    )?;
    out.set_item(
        "orbit_of_segment",
        (0..catalogue.segments().len())
            .map(|i| catalogue.orbit_of(i))
            .collect::<Vec<_>>(),
    )?;
    out.set_item("distinct_orbits", catalogue.orbits().len())?;
    out.set_item("summary", data.summary())?;
    drive_items(&out, &data)?;
    Ok(out)
}
