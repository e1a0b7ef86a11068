//! The identify request: every option of `hbid identify` (and of Python's `hbid.identify`), typed
//! and checked once ([`IdentifyOptions`] → [`IdentifyRequest`]), its run on a record
//! ([`identify`]), and its report ([`IdentifyReport`], whose serialisation is the JSON of
//! `hbid identify --json`).

use std::fmt;
use std::str::FromStr;

use circle_signal::{Domain, Measured, Segment};
use hb_basis::{Basis, BasisKind};
use hb_model::{
    Forcing, Harmonics, IdentifiedModel, IdentifiedSystem, MAX_DRIVE_HARMONIC, ModelForm, Names, TermError,
    TermList,
};
use hb_record::prepare::{Data, DriveFound, GridData, WindowUnit};
use hb_solve::identifier::Identifier;
use hb_solve::{
    BootstrapParams, LstsqSolver, NoiseCorrection, QrSolver, SelectParams, Signals, SvdSolver, Tie, TieSpec,
    TiedParameter, WeakForm,
};
use serde::{Deserialize, Serialize, Serializer};
use upo_search::Windows;

use crate::drive::DriveSpec;
use crate::embed::{OrbitOptions, first_minimum};
use crate::error::RunError;
use crate::observe::{Notice, Observer, Stage};
use crate::options::{OptionError, from_object, optional_text, text};
use crate::pipeline::{
    DriftFit, Identification, IdentifyStep, Method, ModelSpec, Record, SearchOptions, TermSelection,
    WindowOptions, fit_drift,
};
use crate::record::{RecordOptions, RecordSummary, Source, load, load_all};

/// The least-squares solver, by name: `qr` (column-pivoted QR) or `svd` (thin SVD).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SolverKind {
    /// Column-pivoted QR.
    #[default]
    Qr,
    /// Thin SVD.
    Svd,
}

impl SolverKind {
    /// The solver.
    pub fn solver(self) -> Box<dyn LstsqSolver> {
        match self {
            SolverKind::Qr => Box::new(QrSolver::default()),
            SolverKind::Svd => Box::new(SvdSolver::default()),
        }
    }
}

impl FromStr for SolverKind {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        match s.trim() {
            "qr" => Ok(SolverKind::Qr),
            "svd" => Ok(SolverKind::Svd),
            other => Err(format!("unknown solver '{other}': qr or svd")),
        }
    }
}

impl fmt::Display for SolverKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            SolverKind::Qr => "qr",
            SolverKind::Svd => "svd",
        })
    }
}

/// The external forcing terms of the default model: none, or `cos(t)`, `sin(t)` identified (the
/// `d_1 p(t)` of the paper's eq. 2).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ForcingTerms {
    /// No external forcing term.
    None,
    /// The coefficients of `cos(t)` and `sin(t)` (of `p` with a measured drive) identified.
    Identified,
}

impl FromStr for ForcingTerms {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        match s.trim() {
            "none" => Ok(ForcingTerms::None),
            "identified" => Ok(ForcingTerms::Identified),
            other => Err(format!("unknown forcing '{other}': none or identified")),
        }
    }
}

impl fmt::Display for ForcingTerms {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ForcingTerms::None => "none",
            ForcingTerms::Identified => "identified",
        })
    }
}

/// The model's terms as given: one list for every equation (`x', sin(x)`), or a list per
/// coordinate by its name (`theta1: theta2''*cos(theta1-theta2), sin(theta1); theta2: ...`; from
/// Python a dict of lists), each read in the record's names for its equation
/// ([`TermList::parse_in`]). A coordinate without a list of its own takes the one for all, or
/// the default library.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct TermsOption {
    all: Option<String>,
    per: Vec<(String, String)>,
}

impl TermsOption {
    /// The list for the coordinate named `name`: its own, or the one for all.
    pub fn for_coordinate(&self, name: &str) -> Option<&str> {
        self.per
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, l)| l.as_str())
            .or(self.all.as_deref())
    }

    /// The coordinates named with a list of their own.
    pub fn named(&self) -> impl Iterator<Item = &str> {
        self.per.iter().map(|(n, _)| n.as_str())
    }
}

impl FromStr for TermsOption {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let mut out = Self::default();
        for part in s.split(';').map(str::trim).filter(|p| !p.is_empty()) {
            match part.split_once(':') {
                Some((name, list)) => {
                    let name = name.trim().to_owned();
                    if out.per.iter().any(|(n, _)| *n == name) {
                        return Err(format!("the terms of '{name}' are given twice"));
                    }
                    out.per.push((name, list.trim().to_owned()));
                }
                None if out.all.is_none() => out.all = Some(part.to_owned()),
                None => {
                    return Err(
                        "give one list for all equations, or one per coordinate as «name: list»".into(),
                    );
                }
            }
        }
        if out.all.is_none() && out.per.is_empty() {
            return Err("no terms given".into());
        }
        Ok(out)
    }
}

impl fmt::Display for TermsOption {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut parts: Vec<String> = self.all.iter().cloned().collect();
        parts.extend(self.per.iter().map(|(n, l)| format!("{n}: {l}")));
        f.write_str(&parts.join("; "))
    }
}

/// Every option of `hbid identify` as given, by the names of the command line (`_` for `-`) and of
/// Python's keyword arguments, with their defaults. Checked by [`IdentifyRequest::new`].
///
/// Defaults, one for every front end: the weak form (`method = windowed`: it needs no periodic
/// orbit, balances a measured drive as measured and reaches the noise floor; the paper's method is
/// `upo`), the basis `harmonic:1` on the circle and `poly:3` on the line, the external forcing
/// terms none on the circle and identified on the line, windows of 3 drive periods with the
/// window `sin^4`, 1000 bootstrap resamples at 95 % from seed 0, no noise correction, QR.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct IdentifyOptions {
    /// The record.
    #[serde(flatten)]
    pub record: RecordOptions,
    /// `windowed` (the weak form on plain windows) or `upo` (the paper's: harmonic balance on
    /// unstable periodic orbits found by close returns).
    #[serde(with = "text")]
    pub method: Method,
    /// The basis of the unknown functions of `x`: `harmonic:K`, `hat:N` or `poly:D`.
    #[serde(with = "optional_text")]
    pub basis: Option<BasisKind>,
    /// Harmonics balanced per segment (default: the method's band).
    pub harmonics: Option<usize>,
    /// Window length in drive periods (the weak form).
    pub window_periods: usize,
    /// Window length in the record's time unit, for a record without a periodic drive (no drive,
    /// or a measured drive alone): the windows' unit is this over `window_periods`, rounded to
    /// whole samples (at least 2).
    pub window: Option<f64>,
    /// Window length in samples, instead of `window`.
    pub window_samples: Option<usize>,
    /// Order `p` of the window `sin^p` (the weak form), at least 2.
    pub window_order: u32,
    /// Bootstrap resamples for the intervals (0: none).
    pub bootstrap: usize,
    /// Confidence level of the intervals.
    pub level: f64,
    /// Seed of the bootstrap.
    pub seed: u64,
    /// The correction of Gaussian noise on the angle: `σ` in radians, or `auto`.
    #[serde(with = "optional_text")]
    pub noise_sigma: Option<NoiseCorrection>,
    /// `qr` or `svd`.
    #[serde(with = "text")]
    pub solver: SolverKind,
    /// The close-return search (`upo`).
    #[serde(flatten)]
    pub orbits: OrbitOptions,
    /// The default model's external forcing terms (default: none on the circle, identified on
    /// the line). `none` with no drive given is a free oscillation.
    #[serde(with = "optional_text")]
    pub forcing: Option<ForcingTerms>,
    /// Leave out the default model's parametric terms `cos(t)*B`, `sin(t)*B`.
    pub no_parametric: bool,
    /// Drive harmonics `1..=H` of the default model's drive terms.
    pub drive_harmonics: Option<u32>,
    /// The model's terms instead of the default: a list ([`TermList`]) for every equation, or
    /// one per coordinate ([`TermsOption`]).
    #[serde(with = "optional_text")]
    pub terms: Option<TermsOption>,
    /// Model selection: the terms are a library of candidates, the kept ones refitted alone.
    pub select: bool,
    /// Folds of segments of the selection (at least 2).
    pub select_folds: usize,
    /// The smallest held-out unexplained fraction a term must remove to be kept, in `[0, 1)`.
    pub select_tolerance: f64,
    /// Refine the coefficients by the free run's error on the record after the fit
    /// ([`refine`](fn@crate::refine)): the model then follows the record as `compare` scores it.
    pub refine: bool,
    /// Samples at the start of each piece that set the free run's state in the refinement and
    /// are not scored (default as `compare`'s: one drive period, at most a tenth of the longest
    /// piece and at least 8).
    pub refine_init: Option<usize>,
    /// Physical parameters shared by the equations (a tied fit, [`hb_solve::TieSpec`]): the path
    /// of a JSON file of the spec, or the spec itself as a JSON object. Its keys are the
    /// equations' terms, so it replaces `terms`.
    pub tie: Option<serde_json::Value>,
    /// Read the record's file in chunks ([`crate::stream`]): memory that does not grow with the
    /// record. Default (`None`): for a file of at least [`crate::stream::STREAM_BYTES`] whose
    /// identification can be streamed (the weak form, a displacement, no refinement).
    pub stream: Option<bool>,
}

impl Default for IdentifyOptions {
    fn default() -> Self {
        Self {
            record: RecordOptions::default(),
            method: Method::Windowed,
            basis: None,
            harmonics: None,
            window_periods: Windows::DEFAULT_PERIODS,
            window: None,
            window_samples: None,
            window_order: WeakForm::DEFAULT_WINDOW_ORDER,
            bootstrap: BootstrapParams::DEFAULT_RESAMPLES,
            level: BootstrapParams::DEFAULT_LEVEL,
            seed: 0,
            noise_sigma: None,
            solver: SolverKind::Qr,
            orbits: OrbitOptions::default(),
            forcing: None,
            no_parametric: false,
            drive_harmonics: None,
            terms: None,
            select: false,
            select_folds: SelectParams::DEFAULT_FOLDS,
            select_tolerance: SelectParams::DEFAULT_TOLERANCE,
            refine: false,
            refine_init: None,
            tie: None,
            stream: None,
        }
    }
}

/// The windows' unit given by `window` or `window_samples` (a window is `window_periods` units),
/// checked.
fn window_unit(o: &IdentifyOptions) -> Result<Option<WindowUnit>, OptionError> {
    let k = o.window_periods.max(1);
    match (o.window, o.window_samples) {
        (Some(_), Some(_)) => Err(OptionError::new(
            "window",
            "give the windows' length by «window» or by «window_samples», not both",
        )),
        (Some(length), None) => {
            if !(length.is_finite() && length > 0.0) {
                return Err(OptionError::value(
                    "window",
                    length,
                    "must be positive and finite",
                ));
            }
            Ok(Some(WindowUnit::Time(length / k as f64)))
        }
        (None, Some(n)) => {
            if n < 2 * k {
                return Err(OptionError::value(
                    "window_samples",
                    n,
                    format!(
                        "must be at least {} (2 samples per unit, «window_periods={k}»)",
                        2 * k
                    ),
                ));
            }
            Ok(Some(WindowUnit::Samples((n + k / 2) / k)))
        }
        (None, None) => Ok(None),
    }
}

/// An identify request, every option checked: only a checked request runs ([`identify`]).
/// Read from options ([`IdentifyRequest::new`]) or from a JSON object of option names
/// ([`IdentifyRequest::from_json`], unknown names refused).
#[derive(Debug, Clone, PartialEq)]
pub struct IdentifyRequest {
    options: IdentifyOptions,
    drive: DriveSpec,
    basis: BasisKind,
    /// The basis of each equation.
    bases: Vec<BasisKind>,
    /// The terms given for each equation, read in the record's names.
    lists: Vec<Option<TermList>>,
    /// The names terms are written in.
    names: Names,
    weak: WeakForm,
    windows: WindowOptions,
    search: SearchOptions,
    bootstrap: Option<BootstrapParams>,
    selection: Option<SelectParams>,
    /// The tie spec read in the record's names.
    tie: Option<Tie>,
}

/// The options a tied fit (`tie`) does not go with, refused before any other check of them.
fn check_tie_with(o: &IdentifyOptions) -> Result<(), OptionError> {
    if o.tie.is_none() {
        return Ok(());
    }
    if o.terms.is_some() {
        return Err(OptionError::new(
            "tie",
            "replaces «terms»: the spec's keys are the equations' terms (leave out «terms»)",
        ));
    }
    if o.select {
        return Err(OptionError::new(
            "tie",
            "is not supported with «select»: a tied fit's terms are the spec's",
        ));
    }
    if o.method == Method::Upo {
        return Err(OptionError::new(
            "tie",
            "is not supported with «method=upo»: a tied fit is made by the weak form («method=windowed»)",
        ));
    }
    if o.refine {
        return Err(OptionError::new(
            "tie",
            "is not supported with «refine»: the refinement moves each coefficient on its own",
        ));
    }
    Ok(())
}

/// The tie spec of `value` (a path to a JSON file, or the spec as an object), read in `names`.
fn read_tie(value: &serde_json::Value, names: &Names) -> Result<Tie, OptionError> {
    let bad = |why: String| OptionError::new("tie", why);
    let spec: TieSpec = match value {
        serde_json::Value::String(path) => {
            let text =
                std::fs::read_to_string(path).map_err(|e| bad(format!("cannot read '{path}': {e}")))?;
            serde_json::from_str(&text).map_err(|e| bad(format!("{path}: {e}")))?
        }
        serde_json::Value::Object(_) => {
            serde_json::from_value(value.clone()).map_err(|e| bad(e.to_string()))?
        }
        other => {
            return Err(bad(format!(
                "expected the path of a JSON file or the spec as an object, not {other}"
            )));
        }
    };
    spec.resolve(names).map_err(|e| bad(e.to_string()))
}

impl IdentifyRequest {
    /// Checks `options`, alone and together.
    pub fn new(options: IdentifyOptions) -> Result<Self, OptionError> {
        let o = &options;
        o.record.check()?;
        if o.record.velocity_col.is_some() {
            return Err(OptionError::new(
                "velocity_col",
                "sets the state of a free run (compare, simulate with a model, a report's runs): the \
                 identification reads no velocities, leave it out",
            ));
        }
        check_tie_with(o)?;
        let search = o.orbits.search()?;
        o.orbits.check_delay()?;
        let weak = WeakForm::new(o.window_order)
            .map_err(|e| OptionError::checked("window_order", o.window_order, &e))?;
        if o.window_periods == 0 {
            return Err(OptionError::value("window_periods", 0, "must be at least 1"));
        }
        let windows = WindowOptions::default()
            .with_periods(o.window_periods)
            .map_err(|e| OptionError::checked("window_periods", o.window_periods, &e))?;
        if o.harmonics == Some(0) {
            return Err(OptionError::value("harmonics", 0, "must be at least 1"));
        }
        if let Some(noise) = o.noise_sigma {
            noise
                .validate()
                .map_err(|e| OptionError::checked("noise_sigma", noise, &e))?;
        }
        let bootstrap = if o.bootstrap > 0 {
            Some(
                BootstrapParams::builder()
                    .resamples(o.bootstrap)
                    .level(o.level)
                    .seed(o.seed)
                    .build()
                    .map_err(|e| match &e {
                        hb_solve::SolveError::InvalidParameter {
                            name: "bootstrap resamples",
                            ..
                        } if o.bootstrap > BootstrapParams::MAX_RESAMPLES => {
                            OptionError::checked("bootstrap", o.bootstrap, &e)
                        }
                        // Too few resamples for the level: the count is what to change.
                        hb_solve::SolveError::InvalidParameter {
                            name: "bootstrap resamples",
                            ..
                        } => OptionError::value(
                            "bootstrap",
                            o.bootstrap,
                            format!(
                                "too few resamples for «level» {}: at least {} (max(20, 2 / (1 - level)))",
                                o.level,
                                (2.0 / (1.0 - o.level)).ceil().max(20.0)
                            ),
                        ),
                        _ => OptionError::checked("level", o.level, &e),
                    })?,
            )
        } else {
            None
        };
        if let Some(init) = o.refine_init {
            if !o.refine {
                return Err(OptionError::new(
                    "refine_init",
                    "is for a refinement: give «refine» too",
                ));
            }
            if init < crate::compare::CompareRequest::MIN_INIT {
                return Err(OptionError::value(
                    "refine_init",
                    init,
                    "must be at least 2: a state has two components",
                ));
            }
        }
        let selection = if o.select {
            if o.select_folds < 2 {
                return Err(OptionError::value(
                    "select_folds",
                    o.select_folds,
                    "must be at least 2",
                ));
            }
            if !(0.0..1.0).contains(&o.select_tolerance) {
                return Err(OptionError::value(
                    "select_tolerance",
                    o.select_tolerance,
                    "must be a fraction of the held-out power in [0, 1)",
                ));
            }
            Some(
                SelectParams::new(o.select_folds, o.select_tolerance)
                    .map_err(|e| OptionError::new("select", crate::options::chain(&e)))?,
            )
        } else {
            None
        };
        if let Some(h) = o.drive_harmonics
            && !(1..=MAX_DRIVE_HARMONIC).contains(&h)
        {
            return Err(OptionError::value(
                "drive_harmonics",
                h,
                format!("must be between 1 and {MAX_DRIVE_HARMONIC}"),
            ));
        }
        let free = o.forcing == Some(ForcingTerms::None) && o.record.given_drive().is_none()
            || o.record.given_drive() == Some(DriveSpec::Free);
        let mut drive = o.record.drive(free);
        if let Some(unit) = window_unit(o)? {
            let name = if o.window.is_some() {
                "window"
            } else {
                "window_samples"
            };
            if matches!(
                o.record.given_drive(),
                Some(DriveSpec::Period(_) | DriveSpec::Auto(_))
            ) {
                return Err(OptionError::new(
                    name,
                    "is for a record without a periodic drive (none, or a measured drive «drive_col» alone): with a \
                     periodic drive the windows are «window_periods» of its periods",
                ));
            }
            if o.method == Method::Upo {
                return Err(OptionError::value(
                    "method",
                    "upo",
                    format!("«{name}» sets the weak form's windows: use «method=windowed»"),
                ));
            }
            if o.forcing == Some(ForcingTerms::Identified) && o.record.drive_col.is_none() {
                return Err(OptionError::value(
                    "forcing",
                    "identified",
                    "a record without a periodic drive has no cos(t), sin(t) to identify (a measured drive is \
                     named with «drive_col»)",
                ));
            }
            drive = DriveSpec::Windows(unit);
        }
        if drive == DriveSpec::Free && o.method == Method::Upo {
            return Err(OptionError::value(
                "method",
                "upo",
                "a free oscillation (no drive) has no periodic orbits: use «method=windowed»",
            ));
        }
        let names = o.record.names()?;
        let domains = o.record.domains();
        let n = domains.len();
        if n > 1 {
            let preset = [
                ("forcing", o.forcing.is_some()),
                ("no_parametric", o.no_parametric),
                ("drive_harmonics", o.drive_harmonics.is_some()),
            ];
            if let Some((name, _)) = preset.iter().find(|(_, given)| *given) {
                return Err(OptionError::new(
                    *name,
                    "shapes the default model of one coordinate; a system's default library names its own terms \
                     (or list them with «terms»)",
                ));
            }
            let one_only = [
                ("measured", o.record.measured != Measured::Displacement),
                ("noise_sigma", o.noise_sigma.is_some()),
                ("refine", o.refine),
            ];
            if let Some((name, _)) = one_only.iter().find(|(_, given)| *given) {
                return Err(OptionError::new(
                    *name,
                    "is for a record of one coordinate, not a system of several («coords»)",
                ));
            }
        }
        // The list of each equation, read in the record's names for it.
        let mut lists: Vec<Option<TermList>> = vec![None; n];
        let tie = match &o.tie {
            None => None,
            Some(value) => {
                let tie = read_tie(value, &names)?;
                for (i, slot) in lists.iter_mut().enumerate() {
                    *slot = Some(tie.terms(i).clone());
                }
                Some(tie)
            }
        };
        if let Some(terms) = &o.terms {
            if let Some(unknown) = terms.named().find(|name| names.coordinate(name).is_none()) {
                return Err(OptionError::new(
                    "terms",
                    format!(
                        "names the coordinate '{unknown}', which has no equation (the coordinates are {})",
                        names.coordinates().join(", ")
                    ),
                ));
            }
            for (i, slot) in lists.iter_mut().enumerate() {
                if let Some(text) = terms.for_coordinate(&names.coordinates()[i]) {
                    let list = TermList::parse_in(text, &names, i).map_err(|e| {
                        let at = if n > 1 {
                            format!("the equation of {}: ", names.coordinates()[i])
                        } else {
                            String::new()
                        };
                        OptionError::new("terms", format!("{at}{e}"))
                    })?;
                    *slot = Some(list);
                }
            }
        }
        // A system's measured drive that no equation's terms name is a mistake (a column in
        // the wrong option, or a term left out), not a column to read for nothing.
        if n > 1 && lists.iter().all(Option::is_some) {
            let used: std::collections::BTreeSet<usize> =
                lists.iter().flatten().flat_map(|l| l.measured_drives()).collect();
            if let Some(unused) = (0..names.drives().len()).find(|d| !used.contains(d)) {
                return Err(OptionError::new(
                    "drive_col",
                    format!(
                        "the drive '{}' is in no equation's terms: name it in «terms», or leave it out",
                        names.drives()[unused]
                    ),
                ));
            }
        }
        // A term that does not fit its coordinate's domain (`x^3` of an angle) is the list's
        // error, before the basis it would imply is found on the wrong domain.
        for list in lists.iter().flatten() {
            list.check_domains(&domains)
                .map_err(|e| OptionError::new("terms", e))?;
        }
        let mut bases = Vec::with_capacity(n);
        for (i, list) in lists.iter().enumerate() {
            let domain = domains[i];
            let basis = match (&o.basis, list) {
                (Some(b), _) => *b,
                (None, Some(list)) => list
                    .smallest_basis()
                    .map_err(|e| OptionError::new("terms", e))?
                    .unwrap_or_else(|| BasisKind::default_for(domain)),
                (None, None) => BasisKind::default_for(domain),
            };
            if basis.domain() != domain {
                return Err(OptionError::value(
                    "basis",
                    basis.spec(),
                    format!(
                        "is a basis on the {}, but coordinate {} is on the {domain}",
                        basis.domain(),
                        i + 1
                    ),
                ));
            }
            bases.push(basis);
        }
        let basis = bases[0];
        for (list, basis) in lists.iter().zip(&bases) {
            let Some(list) = list else {
                continue;
            };
            if o.forcing == Some(ForcingTerms::Identified) {
                return Err(OptionError::value(
                    "forcing",
                    "identified",
                    "not with «terms»: name the forcing terms cos(t), sin(t) in the list",
                ));
            }
            if o.no_parametric {
                return Err(OptionError::new(
                    "no_parametric",
                    "not with «terms»: the list says its terms (leave out cos(t)*B, sin(t)*B)",
                ));
            }
            if let Some(h) = o.drive_harmonics {
                return Err(OptionError::value(
                    "drive_harmonics",
                    h,
                    "not with «terms»: name the harmonics' terms in the list (cos(2t)*sin(x))",
                ));
            }
            list.resolve(basis)
                .map_err(|e| OptionError::new("terms", format!("with the basis {}: {e}", basis.spec())))?;
            if matches!(drive, DriveSpec::Free | DriveSpec::Windows(_))
                && let Some(t) = list.phase_term()
            {
                let why = match drive {
                    DriveSpec::Windows(_) => {
                        "windows of a given length («window», «window_samples») are for a record without a periodic \
                         drive: leave them out for windows of drive periods («window_periods»)"
                    }
                    _ => "the record has no periodic drive («drive_period=none»)",
                };
                return Err(OptionError::new(
                    "terms",
                    format!("the term `{t}` has a drive factor, but {why}"),
                ));
            }
            if let Some(t) = list.measured_term()
                && o.record.drive_col.is_none()
            {
                return Err(OptionError::new(
                    "terms",
                    format!(
                        "the term `{t}` has a measured drive: name the record's column that holds it with \
                         «drive_col=»"
                    ),
                ));
            }
        }
        if let (Some(col), Some(h)) = (&o.record.drive_col, o.drive_harmonics) {
            return Err(OptionError::value(
                "drive_harmonics",
                h,
                format!(
                    "with «drive_col={col}»: the measured drive p has no harmonics to name; list terms such as \
                     cos(2t)*sin(x) with «terms»"
                ),
            ));
        }
        if o.record.drive_col.is_some() && o.method == Method::Upo {
            return Err(OptionError::value(
                "method",
                "upo",
                "the measured drive p is balanced by the weak form only («method=windowed»): a periodic orbit of \
                 the state does not make the series of a measured drive close",
            ));
        }
        Ok(Self {
            drive,
            basis,
            bases,
            lists,
            names,
            weak,
            windows,
            search,
            bootstrap,
            selection,
            tie,
            options,
        })
    }

    /// A request from a JSON object of option names (Python's keyword arguments), unknown names
    /// refused.
    pub fn from_json(value: serde_json::Value) -> Result<Self, OptionError> {
        Self::new(from_object(value)?)
    }

    /// The tie spec read in the record's names, when the parameters are tied (`tie`).
    pub fn tie(&self) -> Option<&Tie> {
        self.tie.as_ref()
    }

    /// The options as given.
    pub fn options(&self) -> &IdentifyOptions {
        &self.options
    }

    /// The drive of the record.
    pub fn drive(&self) -> DriveSpec {
        self.drive
    }

    /// The basis of the unknown functions of the first (or only) coordinate: the one given, or
    /// the smallest that holds the functions of `x` of the terms, or the domain's default.
    pub fn basis(&self) -> BasisKind {
        self.basis
    }

    /// The basis of the own coordinate's functions in the equation of coordinate `i`.
    pub fn basis_of(&self, i: usize) -> BasisKind {
        self.bases[i]
    }

    /// The number of equations: one per coordinate.
    pub fn equations(&self) -> usize {
        self.bases.len()
    }

    /// The names of the coordinates and drives, as terms are written in them.
    pub fn names(&self) -> &Names {
        &self.names
    }

    /// The windows of the weak form.
    pub fn windows(&self) -> WindowOptions {
        self.windows
    }

    /// The close-return search.
    pub fn search(&self) -> SearchOptions {
        self.search
    }

    /// The model's form on `data`: the terms given (the measured drive's column named), or the
    /// default with the forcing, parametric and drive-harmonic options; a free oscillation has no
    /// drive terms.
    pub fn form(&self, data: &Data) -> Result<ModelForm, OptionError> {
        self.form_of(data, 0)
    }

    /// The form of the equation of coordinate `i` on `data`: the terms given for it, or the
    /// default (for a record of one coordinate the paper's preset with the forcing, parametric
    /// and drive-harmonic options, for a system the library of [`system_library`]).
    pub fn form_of(&self, data: &Data, i: usize) -> Result<ModelForm, OptionError> {
        let o = &self.options;
        let measured = !data.drives.is_empty();
        // Windows given in time or samples: no periodic drive, so no cos(t), sin(t) terms.
        let free = matches!(data.drive, DriveFound::Free { .. })
            || matches!(data.drive, DriveFound::Windows { .. }) && !measured;
        let named = |form: ModelForm| match o.record.drive_cols() {
            [col] if self.equations() == 1 && form.has_measured_drive() => form.with_drive_column(col.trim()),
            _ => form,
        };
        if let Some(list) = &self.lists[i] {
            if measured && self.equations() == 1 && !list.has_measured_drive() {
                return Err(OptionError::new(
                    "drive_col",
                    "no term of «terms» has the measured drive p",
                ));
            }
            return Ok(named(ModelForm::from_terms(list.clone())));
        }
        if self.equations() > 1 {
            let domains = o.record.domains();
            let list = system_library(&self.names, &domains, i, !free && !measured)
                .map_err(|e| OptionError::new("terms", e))?;
            return Ok(ModelForm::from_terms(list));
        }
        let forcing = match (o.forcing, data.domain) {
            (Some(f), _) => f,
            (None, _) if free && matches!(data.drive, DriveFound::Windows { .. }) => ForcingTerms::None,
            (None, Domain::Circle) => ForcingTerms::None,
            (None, Domain::Line) => ForcingTerms::Identified,
        };
        if measured {
            // The measured drives in place of cos(t) and sin(t): x', {1,p}*B and p.
            let functions = self.basis.names().join(",");
            let drives = self.names.drives().join(",");
            let mut spec = if o.no_parametric {
                format!("x', {{{functions}}}")
            } else {
                format!("x', {{1,{drives}}}*{{{functions}}}")
            };
            if forcing == ForcingTerms::Identified {
                spec.push_str(&format!(", {{{drives}}}"));
            }
            let list =
                TermList::parse_in(&spec, &self.names, 0).map_err(|e| OptionError::new("drive_col", e))?;
            if !list.has_measured_drive() {
                return Err(OptionError::new(
                    "drive_col",
                    "with «no_parametric» and «forcing=none» no term has the measured drive p",
                ));
            }
            return Ok(named(ModelForm::from_terms(list)));
        }
        let mut form = ModelForm::parametric().with_forcing(match forcing {
            ForcingTerms::None => Forcing::None,
            ForcingTerms::Identified => Forcing::Identified,
        });
        if o.no_parametric || free {
            form = form.without_parametric_terms();
        }
        if let Some(h) = o.drive_harmonics {
            form = form.with_drive_harmonics(h);
        }
        Ok(form)
    }

    /// What to identify by `method` (the request's own, or another for a report) on `data`: the
    /// equation of its first (or only) coordinate.
    pub fn model_spec(&self, data: &Data, method: Method) -> Result<ModelSpec, RunError> {
        self.equation_spec(data, method, 0)
    }

    /// What to identify by `method` on `data` for the equation of coordinate `i`.
    pub fn equation_spec(&self, data: &Data, method: Method, i: usize) -> Result<ModelSpec, RunError> {
        let o = &self.options;
        let form = self.form_of(data, i)?;
        let mut spec = ModelSpec::new(method, self.bases[i])
            .with_form(form)
            .with_weak_form(self.weak)
            .with_noise_correction(o.noise_sigma.unwrap_or_default())
            .with_solver(o.solver.solver());
        if let Some(m) = o.harmonics {
            spec = spec.with_harmonics(Harmonics::Fixed(m))?;
        }
        if let Some(params) = self.selection {
            spec = spec.with_selection(params);
        }
        if let Some(b) = &self.bootstrap {
            spec = spec.with_bootstrap(*b);
        }
        Ok(spec)
    }

    /// The delay: the one given, or the first minimum of the average mutual information of the
    /// longest piece.
    pub fn delay(&self, data: &Data, observer: &mut dyn Observer) -> Result<usize, RunError> {
        // The search's options are checked against the record first, so that a bad option fails
        // before any work.
        let record = Record::from_data(data)?;
        self.search
            .close_returns(&record, self.options.orbits.delay.unwrap_or(1))?;
        match self.options.orbits.delay {
            Some(d) => Ok(d),
            None => {
                observer.stage(Stage::Delay);
                first_minimum(data, data.domain, None, None, crate::embed::DELAY_REMEDY).map(|(_, d)| d)
            }
        }
    }

    /// The segments of `method` on `data`: close returns with `delay`, or plain windows; and a
    /// line saying what was found.
    pub fn segments(
        &self,
        data: &Data,
        delay: usize,
        method: Method,
    ) -> Result<(Vec<Segment>, String), RunError> {
        let record = Record::from_data(data)?;
        Ok(match method {
            Method::Upo => {
                if data.others.iter().any(|c| c.domain != data.domain) {
                    return Err(OptionError::value(
                        "method",
                        "upo",
                        "the close returns of a system are searched in one metric: its coordinates must all be \
                         angles or all displacements (use «method=windowed»)",
                    )
                    .into());
                }
                let coordinates: Vec<&[f64]> = data.coordinates().into_iter().map(|(x, _)| x).collect();
                let segments = self
                    .search
                    .close_returns(&record, delay)?
                    .search_system_pieces(&coordinates, &data.pieces)
                    .map_err(|e| crate::pipeline::PipelineError::orbits(e, data.p, data.pieces.len()))?;
                let found = format!(
                    "{} orbit segments found at tolerance {}",
                    segments.len(),
                    self.options.orbits.tolerance
                );
                (segments, found)
            }
            Method::Windowed => {
                let k = self.options.window_periods;
                let unit = match data.drive {
                    DriveFound::Free { .. } => "oscillation periods".to_owned(),
                    DriveFound::Windows { samples } => {
                        // The window in the record's time, to four significant digits.
                        let span = k as f64 * samples as f64 * data.clock.step();
                        let decimals = (3 - span.log10().floor() as i32).max(0) as usize;
                        format!("units of {samples} samples ({span:.decimals$} in the record's time unit)")
                    }
                    _ => "drive periods".to_owned(),
                };
                let segments = self
                    .windows
                    .windows(&record)?
                    .windows_pieces(&data.x, &data.pieces)
                    .map_err(|e| {
                        crate::pipeline::PipelineError::windows(
                            e,
                            || format!("{k} {unit}"),
                            data.pieces.len(),
                        )
                    })?;
                let found = windows_found(data, k, segments.len());
                (segments, found)
            }
        })
    }
}

/// What `count` windows of `k` units of `data` are, in a line.
pub(crate) fn windows_found(data: &Data, k: usize, count: usize) -> String {
    match data.drive {
        DriveFound::Free { .. } => format!("{count} windows of {k} oscillation periods"),
        DriveFound::Windows { samples } => format!("{count} windows of {} samples", k * samples),
        _ => format!("{count} windows of {k} drive periods"),
    }
}

/// The default library of the equation of coordinate `own` of a system with `names` on
/// `domains`, with a periodic drive (`cos(t)`, `sin(t)`) or not, documented in
/// `docs/identification.md`:
///
/// - on the circle, what pendulum chains need: each angle's `sin` and `cos`, each other angle's
///   acceleration times the `cos` of the difference, the other velocity squared times its `sin`,
///   each velocity, and the drive (`cos(t)`, `sin(t)`, or each measured drive) alone and times
///   each angle's `sin` and `cos`;
/// - on the line, every monomial of degree 1 to 3 of the positions, each velocity, and each
///   drive (`cos(t)`, `sin(t)` or the measured ones);
/// - a system of both, the circle's terms of its angles and the line's of its positions.
pub fn system_library(
    names: &Names,
    domains: &[Domain],
    own: usize,
    periodic: bool,
) -> Result<TermList, TermError> {
    let q = names.coordinates();
    let angles: Vec<usize> = (0..q.len()).filter(|&c| domains[c] == Domain::Circle).collect();
    let lines: Vec<usize> = (0..q.len()).filter(|&c| domains[c] == Domain::Line).collect();
    let mut drives: Vec<String> = names.drives().to_vec();
    if periodic {
        drives.splice(0..0, ["cos(t)".to_owned(), "sin(t)".to_owned()]);
    }
    let mut terms: Vec<String> = Vec::new();
    for &c in &angles {
        terms.push(format!("sin({})", q[c]));
        terms.push(format!("cos({})", q[c]));
    }
    if domains[own] == Domain::Circle {
        for &c in angles.iter().filter(|&&c| c != own) {
            let (a, b) = if own < c { (own, c) } else { (c, own) };
            terms.push(format!("{}''*cos({}-{})", q[c], q[a], q[b]));
            terms.push(format!("sin({}-{})*{}'^2", q[a], q[b], q[c]));
        }
    }
    // Monomials of degree 1 to 3 of the positions on the line.
    for (i, &a) in lines.iter().enumerate() {
        terms.push(q[a].clone());
        for (j, &b) in lines.iter().enumerate().skip(i) {
            terms.push(format!("{}*{}", q[a], q[b]));
            for &c in lines.iter().skip(j) {
                terms.push(format!("{}*{}*{}", q[a], q[b], q[c]));
            }
        }
    }
    for name in q {
        terms.push(format!("{name}'"));
    }
    for d in &drives {
        terms.push(d.clone());
        for &c in &angles {
            terms.push(format!("{d}*sin({})", q[c]));
            terms.push(format!("{d}*cos({})", q[c]));
        }
    }
    TermList::parse_in(&terms.join(", "), names, own)
}

impl Default for IdentifyRequest {
    fn default() -> Self {
        Self::new(IdentifyOptions::default()).expect("the default options are valid")
    }
}

/// Read through [`IdentifyRequest::from_json`]: unknown names refused, every option checked.
impl<'de> Deserialize<'de> for IdentifyRequest {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let value = serde_json::Value::deserialize(d)?;
        Self::from_json(value).map_err(serde::de::Error::custom)
    }
}

impl Serialize for IdentifyRequest {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.options.serialize(s)
    }
}

/// What an identification found, with the record and the run that led to it. Its serialisation
/// is the JSON of `hbid identify --json` and of Python's `Identification.to_json()`.
#[derive(Debug, Clone, PartialEq)]
pub struct IdentifyReport {
    /// The method.
    pub method: Method,
    /// The basis of the first (or only) coordinate's functions.
    pub basis: BasisKind,
    /// One equation per coordinate, in order: the model, its intervals, fit quality, warning
    /// and selection.
    pub equations: Vec<EquationReport>,
    /// The names of the coordinates and drives, as the terms are written in them.
    pub names: Names,
    /// The record's columns of the coordinates and drives (for a system).
    pub columns: Option<hb_model::Columns>,
    /// The record as analysed.
    pub record: RecordSummary,
    /// The delay of the close-return search (`upo`).
    pub delay: Option<usize>,
    /// The segments identified on.
    pub segments: usize,
    /// What was found: `12 windows of 3 drive periods`.
    pub found: String,
    /// The drift found for an integrated velocity or acceleration record.
    pub drift: Option<DriftFit>,
    /// What the output-error refinement did (`refine`); the model's coefficients are then the
    /// refined ones, and its fit measures, intervals and selection those of the weak form.
    pub refinement: Option<crate::refine::Refinement>,
    /// A tied fit's parameters (`tie`), in the spec's order; the equations' coefficients are
    /// made from them.
    pub parameters: Option<Vec<TiedParameter>>,
    /// The bootstrap intervals of a tied fit's parameters, when asked for and they can be had.
    pub parameter_intervals: Option<hb_solve::Bootstrap>,
}

/// The identification of one coordinate's equation.
#[derive(Debug, Clone, PartialEq)]
pub struct EquationReport {
    /// The coordinate's name.
    pub coordinate: String,
    /// The basis of its functions.
    pub basis: BasisKind,
    /// The model, its intervals, fit quality, warning and selection.
    pub identification: Identification,
}

impl IdentifyReport {
    /// The identification of the first (or only) coordinate's equation.
    pub fn identification(&self) -> &Identification {
        &self.equations[0].identification
    }

    /// The identified system, one equation per coordinate (a record of one coordinate is the
    /// system of its model).
    pub fn system(&self) -> Result<IdentifiedSystem, RunError> {
        let system = system_of(&self.names, &self.equations)?;
        if system.is_one_model() {
            return Ok(system);
        }
        Ok(match &self.columns {
            Some(columns) => system.with_columns(columns.clone())?,
            None => system,
        })
    }
}

/// The identified system of `equations` in `names`, one equation per coordinate (a record of one
/// coordinate is the system of its model).
fn system_of(names: &Names, equations: &[EquationReport]) -> Result<IdentifiedSystem, RunError> {
    let models: Vec<IdentifiedModel> = equations.iter().map(|e| e.identification.model.clone()).collect();
    if models.len() == 1 {
        return Ok(IdentifiedSystem::one(models.into_iter().next().expect("one")));
    }
    let domains = models.iter().map(IdentifiedModel::domain).collect();
    Ok(IdentifiedSystem::new(names.clone(), domains, models)?)
}

/// The most samples of a record at which [`check_mass_matrix`] solves the identified mass matrix
/// (every sample of a shorter record; evenly spread over a longer one).
const MASS_CHECKS: usize = 20_000;

/// That the identified system's mass matrix can be solved at the record's states, as its free
/// run solves it at every step ([`IdentifiedSystem::accelerations`], whose pivot criterion it
/// uses): terms that leave the accelerations undetermined on the record (a coordinate's column
/// the copy of another's, whose equations then explain each other's acceleration) are an error
/// naming the terms and the columns, never a model whose every run stops.
fn check_mass_matrix(
    system: &IdentifiedSystem,
    request: &IdentifyRequest,
    data: &Data,
    coordinates: &[(&[f64], Domain)],
) -> Result<(), RunError> {
    let n = coordinates.len();
    let samples: usize = data.pieces.iter().map(|p| p.len()).sum();
    let stride = samples.div_ceil(MASS_CHECKS).max(1);
    let paths: Vec<Vec<usize>> = data
        .pieces
        .iter()
        .map(|piece| piece.clone().step_by(stride).collect())
        .collect();
    let records: Vec<&[f64]> = coordinates.iter().map(|&(x, _)| x).collect();
    let Some(found) = system.first_singular(&records, &paths, |k| data.clock.time(k)) else {
        return Ok(());
    };
    let (t, q, singular) = (found.mass.t, found.q, found.mass);
    let how = if found.changes_sign {
        "singular next to"
    } else if singular.pivot > hb_model::SINGULAR_PIVOT {
        "nearly singular at"
    } else {
        "singular at"
    };
    let names = request.names.coordinates();
    let state: Vec<String> = names
        .iter()
        .zip(&q)
        .map(|(c, x)| format!("{c} = {x:.4}"))
        .collect();
    Err(OptionError::new(
        "terms",
        format!(
            "the identified mass matrix is {how} t = {t} ({}; smallest pivot {:.1e} of its largest \
             entry{}): the acceleration terms leave the accelerations of {} undetermined on the record, and \
             every free run of the model would stop there{}",
            state.join(", "),
            singular.pivot,
            if found.changes_sign {
                ", its determinant changing sign before the next state checked"
            } else {
                ""
            },
            names.join(", "),
            if n > 1 {
                "; is one coordinate's column («coords») a copy of another's?"
            } else {
                ""
            }
        ),
    )
    .into())
}

/// The integrator's relative tolerance in the refinement (as `compare`'s default: the
/// differences of free runs a millionth of a coefficient apart must stand above its error).
pub const REFINE_RTOL: f64 = pendulum_sim::Tolerances::DEFAULT_RTOL;
/// The most Levenberg–Marquardt iterations of the refinement.
pub const REFINE_ITERATIONS: usize = 30;

/// Identifies the equation of motion of the record of `source` as `request` asks: the record
/// read, conditioned and its drive found ([`load`]); the delay (`upo`); the segments; the drift
/// of an integrated record; assembly, selection, least squares and the bootstrap. `observer`
/// hears every stage and notice.
pub fn identify(
    source: Source<'_>,
    request: &IdentifyRequest,
    observer: &mut dyn Observer,
) -> Result<IdentifyReport, RunError> {
    match source {
        Source::Path(path) if crate::stream::streams(path, request)? => {
            return crate::stream::identify_streamed(path, request, observer);
        }
        _ if request.options.stream == Some(true) => {
            return Err(OptionError::new(
                "stream",
                "reads a file in chunks: give the record as a file, one file",
            )
            .into());
        }
        _ => {}
    }
    let data = load(source, &request.options.record, request.drive, observer)?;
    identify_data(&data, request, observer)
}

/// [`identify`] on several records of the same columns, one fit: each read and conditioned on
/// its own and joined by [`load_all`] (a gap between each two, so no window or orbit spans two).
pub fn identify_records(
    sources: Vec<Source<'_>>,
    request: &IdentifyRequest,
    observer: &mut dyn Observer,
) -> Result<IdentifyReport, RunError> {
    if sources.len() == 1 {
        return identify(sources.into_iter().next().expect("one"), request, observer);
    }
    if request.options.stream == Some(true) {
        return Err(OptionError::new("stream", "reads one file in chunks: give one record").into());
    }
    let data = load_all(sources, &request.options.record, request.drive, observer)?;
    identify_data(&data, request, observer)
}

/// [`identify`] on a record already loaded.
pub fn identify_data(
    data: &Data,
    request: &IdentifyRequest,
    observer: &mut dyn Observer,
) -> Result<IdentifyReport, RunError> {
    let method = request.options.method;
    let n = request.equations();
    if data.others.len() + 1 != n {
        return Err(OptionError::new(
            "coords",
            format!(
                "the record has {} coordinate(s), the request {n}",
                data.others.len() + 1
            ),
        )
        .into());
    }
    let setups = (0..n)
        .map(|i| {
            request
                .equation_spec(data, method, i)?
                .setup(&data.clock)
                .map_err(RunError::from)
        })
        .collect::<Result<Vec<_>, RunError>>()?;
    let delay = match method {
        Method::Upo => Some(request.delay(data, observer)?),
        Method::Windowed => None,
    };
    observer.stage(Stage::Segments);
    let (segments, found) = request.segments(data, delay.unwrap_or(1), method)?;
    let measured = request.options.record.measured;
    let drives: Vec<&[f64]> = data.drives.iter().map(Vec::as_slice).collect();
    let mut drifted = None;
    let mut drift = None;
    if measured != Measured::Displacement {
        observer.stage(Stage::Drift);
        let (x, fit) = fit_drift(
            &setups[0],
            &data.x,
            &drives,
            &data.pieces,
            &segments,
            measured,
            |done, total| observer.progress(done, total),
        )
        .map_err(|source| RunError::Identify {
            found: format!("{found}: fitting the integrated record's drift"),
            source,
        })?;
        if fit.evaluations > 0 {
            observer.notice(&Notice::Drift {
                measured,
                fit: fit.clone(),
                samples_per_period: data.p,
            });
        }
        drifted = Some(x);
        drift = Some(fit);
    }
    let x = drifted.as_deref().unwrap_or(&data.x);
    let mut coordinates = data.coordinates();
    coordinates[0].0 = x;
    let identify_error = |i: Option<usize>, source| RunError::Identify {
        found: match i {
            Some(i) if n > 1 => format!("{found}, the equation of {}", request.names.coordinates()[i]),
            _ => found.clone(),
        },
        source,
    };
    let signals = (0..n)
        .map(|i| {
            Signals::system(coordinates.clone(), i)
                .and_then(|s| s.with_drives(drives.clone()))
                .map_err(|e| identify_error(Some(i), e))
        })
        .collect::<Result<Vec<_>, RunError>>()?;
    // Every equation's rows at once, window by window: each coordinate's window and velocity
    // are made once for all the equations that read them.
    observer.stage(Stage::Assemble);
    let systems = match Identifier::systems(&setups, &signals, &segments) {
        Ok(systems) => systems,
        // Which equation's rows failed: each assembled alone names it.
        Err(e) => {
            for i in 0..n {
                Identifier::systems(&setups[i..=i], &signals[i..=i], &segments)
                    .map_err(|e| identify_error(Some(i), e))?;
            }
            return Err(identify_error(None, e));
        }
    };
    finish(
        request,
        Assembled {
            setups,
            systems,
            found,
            segments: segments.len(),
            delay,
            drift,
            record: RecordSummary::of(data),
            resampled: data.resampled_from.is_some(),
            states: Some(States { data, coordinates, x }),
        },
        observer,
    )
}

/// What the identification of a record assembled, for [`finish`].
pub(crate) struct Assembled<'a> {
    /// Each equation's setup.
    pub(crate) setups: Vec<Identifier>,
    /// Each equation's system.
    pub(crate) systems: Vec<hb_solve::LinearSystem>,
    /// What was found (windows, orbits), in a line.
    pub(crate) found: String,
    /// How many segments.
    pub(crate) segments: usize,
    /// The delay (`upo`).
    pub(crate) delay: Option<usize>,
    /// The drift of an integrated record.
    pub(crate) drift: Option<DriftFit>,
    /// The record's summary.
    pub(crate) record: RecordSummary,
    /// Whether the record was resampled.
    pub(crate) resampled: bool,
    /// The record's states, where it is held: for the mass matrix's check and the refinement.
    pub(crate) states: Option<States<'a>>,
}

/// A record held in memory, and its coordinates (the first one as fitted: integrated records'
/// drift removed).
pub(crate) struct States<'a> {
    pub(crate) data: &'a Data,
    pub(crate) coordinates: Vec<(&'a [f64], Domain)>,
    pub(crate) x: &'a [f64],
}

/// The identification from the assembled systems: selection, least squares, bootstrap,
/// warnings, the mass matrix's check and the refinement, and the report.
pub(crate) fn finish(
    request: &IdentifyRequest,
    assembled: Assembled<'_>,
    observer: &mut dyn Observer,
) -> Result<IdentifyReport, RunError> {
    let Assembled {
        setups,
        systems,
        found,
        segments,
        delay,
        drift,
        record,
        resampled,
        states,
    } = assembled;
    let method = request.options.method;
    let n = request.equations();
    let identify_error = |i: Option<usize>, source| RunError::Identify {
        found: match i {
            Some(i) if n > 1 => format!("{found}, the equation of {}", request.names.coordinates()[i]),
            _ => found.clone(),
        },
        source,
    };
    let mut equations = Vec::with_capacity(n);
    let mut parameters = None;
    let mut parameter_intervals = None;
    let stage = |step| match step {
        IdentifyStep::Assemble => Stage::Assemble,
        IdentifyStep::Select => Stage::Select,
        IdentifyStep::Solve => Stage::Solve,
        IdentifyStep::Bootstrap => Stage::Bootstrap,
    };
    let identifications = match request.tie() {
        Some(tie) => {
            let tied = hb_solve::identify_tied(tie, &setups, systems, |step| observer.stage(stage(step)))
                .map_err(|source| match source {
                    hb_solve::SolveError::Tie(e) => OptionError::new("tie", e.to_string()).into(),
                    source => identify_error(None, source),
                })?;
            if let Some(why) = &tied.no_intervals {
                observer.notice(&Notice::NoIntervals(format!("the tied parameters: {why}")));
            }
            parameters = Some(tied.fit.parameters);
            parameter_intervals = tied.intervals;
            tied.equations
        }
        None => {
            let mut identifications = Vec::with_capacity(n);
            for (i, (setup, system)) in setups.iter().zip(systems).enumerate() {
                identifications.push(
                    setup
                        .identify_system(system, |step| observer.stage(stage(step)))
                        .map_err(|e| identify_error(Some(i), e))?,
                );
            }
            identifications
        }
    };
    // A model that does not describe a record whose drive was not given may have been fitted at
    // the paper's period, 2π of the record's time unit, on a record in seconds: say so where 2π
    // is no whole number of its steps (a record in the paper's time has a whole number of
    // samples per period; one in seconds at a whole rate never has: 2π is irrational).
    let drive_hint = if request.options.record.given_drive().is_none()
        && request.options.record.drive_col.is_none()
        && matches!(request.drive, DriveSpec::Period(_))
        && resampled
    {
        "; no drive was given, so its period is 2π in the record's time unit (the paper's \
         non-dimensional time): for a record in seconds give «drive_frequency» in hertz, or \
         «drive_frequency=auto» to estimate it"
    } else {
        ""
    };
    for (i, identification) in identifications.into_iter().enumerate() {
        let of = if n > 1 {
            format!("the equation of {}: ", request.names.coordinates()[i])
        } else {
            String::new()
        };
        if let Some(why) = &identification.no_intervals {
            observer.notice(&Notice::NoIntervals(format!("{of}{why}")));
        }
        if let Some(w) = &identification.warning {
            observer.notice(&Notice::Warning(format!("{of}{w}{drive_hint}")));
        }
        equations.push(EquationReport {
            coordinate: request.names.coordinates()[i].clone(),
            basis: request.bases[i],
            identification,
        });
    }
    // A mass matrix other than the identity (an acceleration times a function of the state, in
    // a system or in the one equation of a record) is solved on the record as a free run will.
    if let Some(states) = &states
        && equations.iter().any(|e| e.identification.model.is_coupled())
    {
        check_mass_matrix(
            &system_of(&request.names, &equations)?,
            request,
            states.data,
            &states.coordinates,
        )?;
    }
    if method == Method::Windowed && segments < hb_solve::HELD_OUT_FOLDS {
        let unknowns = equations
            .iter()
            .map(|e| e.identification.model.coefficients().len())
            .max()
            .unwrap_or(0);
        // Windows of the paper's drive period, 2π of the record's time unit, when no drive was
        // given: in seconds, long ones.
        let defaulted = request.options.record.given_drive().is_none()
            && matches!(request.drive, DriveSpec::Period(_))
            && request.options.window.is_none()
            && request.options.window_samples.is_none();
        let drive = if defaulted {
            "; no drive was given, so the windows' unit is the paper's period of 2π in the record's time unit: \
             give the drive («drive_frequency»), or for a record without a periodic drive «drive_period=none» \
             or «window»"
        } else {
            ""
        };
        observer.notice(&Notice::Warning(format!(
            "only {} window(s) ({found}) for {unknowns} unknowns: too few to check the fit on stretches it was \
             not fitted on, so its share explained says little; shorten the windows with «window», \
             «window_samples» or «window_periods»{drive}",
            segments
        )));
    }
    let mut refinement = None;
    if request.options.refine {
        let Some(States { data, x, .. }) = states else {
            return Err(OptionError::sentence(
                "refine",
                "refines on the record in memory: a record read in chunks («stream») is not held",
            )
            .into());
        };
        observer.stage(Stage::Refine);
        let identification = &mut equations[0].identification;
        let grid = GridData {
            t0: data.clock.start_time(),
            dt: data.clock.step(),
            x: x.to_vec(),
            pieces: data.pieces.clone(),
            domain: data.domain,
            others: Vec::new(),
            drives: data.drives.clone(),
            velocities: Vec::new(),
            bridged: data.bridged.clone(),
            notes: Vec::new(),
            lead_in: None,
        };
        let model = &identification.model;
        let longest = data.pieces.iter().map(|p| p.len()).max().unwrap_or(0);
        let period = std::f64::consts::TAU / model.drive_angular_frequency() / grid.dt;
        let init = request
            .options
            .refine_init
            .unwrap_or_else(|| crate::compare::default_init(period, longest));
        let tolerances = pendulum_sim::Tolerances::new(REFINE_RTOL, REFINE_RTOL / 10.0)
            .map_err(|e| RunError::Refine(e.to_string()))?;
        let (refined, done) =
            crate::refine::refine(model, &grid, init, tolerances, REFINE_ITERATIONS, &mut |d, t| {
                observer.progress(d, t)
            })?;
        identification.model = refined;
        if identification.intervals.take().is_some() || identification.no_intervals.is_some() {
            identification.no_intervals = Some(
                "the coefficients were refined by the free run's error: their standard errors are the \
                 refinement's, and the weak form's bootstrap intervals do not apply to them"
                    .into(),
            );
        }
        if !done.converged {
            observer.notice(&Notice::Warning(format!(
                "the refinement stopped after {} iterations without converging: the free run's RMSE went from \
                 {:.4e} to {:.4e}",
                done.iterations, done.rmse_before, done.rmse_after
            )));
        }
        refinement = Some(done);
    }
    Ok(IdentifyReport {
        method,
        basis: request.basis,
        equations,
        names: request.names.clone(),
        // A system's columns; one coordinate's too when its drives have names of their own (the
        // one-model format keeps its own): its angle's column, or its name for the record's
        // default column.
        columns: (n > 1 || request.names != Names::default()).then(|| hb_model::Columns {
            coordinates: match (&request.options.record.coords, &request.options.record.angle_col) {
                (Some(c), _) => c.columns().to_vec(),
                (None, Some(angle)) if n == 1 => vec![angle.clone()],
                _ => request.names.coordinates().to_vec(),
            },
            drives: request.options.record.drive_cols().to_vec(),
        }),
        refinement,
        parameters,
        parameter_intervals,
        record,
        delay,
        segments,
        found,
        drift,
    })
}

/// Coefficients keyed by term name, in the model's order.
struct Ordered<'a, T: Serialize>(Vec<(&'a str, T)>);

impl<T: Serialize> Serialize for Ordered<'_, T> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for (name, value) in &self.0 {
            map.serialize_entry(name, value)?;
        }
        map.end()
    }
}

/// One line of the residual by harmonic.
#[derive(Serialize)]
struct SpectrumLine {
    harmonic: f64,
    residual_rms: f64,
    rhs_rms: f64,
    rows: usize,
}

/// The JSON of a selection.
#[derive(Serialize)]
struct SelectionJson<'a> {
    library: Vec<String>,
    kept: Vec<String>,
    dropped: Vec<DroppedJson<'a>>,
    folds: usize,
    allowance: f64,
    path: Vec<StepJson<'a>>,
}

#[derive(Serialize)]
struct DroppedJson<'a> {
    term: &'a str,
    unexplained_without: f64,
    unexplained_with: f64,
}

#[derive(Serialize)]
struct StepJson<'a> {
    removed: Option<&'a str>,
    terms: usize,
    unexplained: f64,
    std_error: f64,
}

impl<'a> SelectionJson<'a> {
    fn of(selection: &'a TermSelection) -> Self {
        let outcome = &selection.outcome;
        Self {
            library: selection.library.names(),
            kept: selection.kept.names(),
            dropped: outcome
                .dropped
                .iter()
                .map(|d| DroppedJson {
                    term: &d.name,
                    unexplained_without: d.unexplained_without,
                    unexplained_with: d.unexplained_with,
                })
                .collect(),
            folds: outcome.folds,
            allowance: outcome.allowance,
            path: outcome
                .path
                .iter()
                .map(|p| StepJson {
                    removed: p.removed.as_deref(),
                    terms: p.size,
                    unexplained: p.unexplained,
                    std_error: p.std_error,
                })
                .collect(),
        }
    }
}

/// The JSON of an identification: the model's terms in order, coefficients, standard errors,
/// intervals, the fit's measures and warning, the selection, and the record and run.
#[derive(Serialize)]
struct ReportJson<'a> {
    method: &'static str,
    /// A tied fit's parameters.
    #[serde(skip_serializing_if = "Option::is_none")]
    parameters: Option<Ordered<'a, ParameterJson>>,
    basis: String,
    terms: Vec<&'a str>,
    drive_column: Option<&'a str>,
    coefficients: Ordered<'a, f64>,
    std_errors: Ordered<'a, f64>,
    /// Segments (orbits or windows) the model was fitted on; kept under its first name.
    orbits_used: Option<usize>,
    segments: usize,
    rows: Option<usize>,
    condition_number: Option<f64>,
    residual_rms: Option<f64>,
    intervals: Option<Ordered<'a, [f64; 2]>>,
    interval_level: Option<f64>,
    resamples: Option<usize>,
    no_intervals: Option<&'a str>,
    explained: f64,
    unexplained: f64,
    held_out_explained: Option<f64>,
    residual_spectrum: Vec<SpectrumLine>,
    warning: Option<&'a str>,
    selection: Option<SelectionJson<'a>>,
    delay: Option<usize>,
    found: &'a str,
    record: &'a RecordSummary,
    refinement: Option<RefinementJson<'a>>,
}

/// The JSON of a refinement: the coefficients it started from keyed by name.
#[derive(Serialize)]
struct RefinementJson<'a> {
    rmse_before: f64,
    rmse_after: f64,
    scored: usize,
    init: usize,
    iterations: usize,
    simulations: usize,
    converged: bool,
    start: Ordered<'a, f64>,
}

/// The JSON of one equation of a system: its terms, coefficients, standard errors, intervals,
/// fit measures, warning and selection, term names as the grammar writes them.
#[derive(Serialize)]
struct EquationJson<'a> {
    basis: String,
    terms: Vec<&'a str>,
    coefficients: Ordered<'a, f64>,
    std_errors: Ordered<'a, f64>,
    rows: Option<usize>,
    condition_number: Option<f64>,
    residual_rms: Option<f64>,
    intervals: Option<Ordered<'a, [f64; 2]>>,
    interval_level: Option<f64>,
    resamples: Option<usize>,
    no_intervals: Option<&'a str>,
    explained: f64,
    unexplained: f64,
    held_out_explained: Option<f64>,
    warning: Option<&'a str>,
    selection: Option<SelectionJson<'a>>,
}

impl<'a> EquationJson<'a> {
    fn of(e: &'a EquationReport) -> Self {
        let id = &e.identification;
        let coefficients = id.model.coefficients();
        let summary = id.model.summary();
        Self {
            basis: e.basis.spec(),
            terms: coefficients.iter().map(|c| c.name.as_str()).collect(),
            coefficients: Ordered(coefficients.iter().map(|c| (c.name.as_str(), c.value)).collect()),
            std_errors: Ordered(
                coefficients
                    .iter()
                    .map(|c| (c.name.as_str(), c.std_error))
                    .collect(),
            ),
            rows: summary.map(|s| s.rows),
            condition_number: summary.map(|s| s.condition),
            residual_rms: summary.map(|s| s.residual_rms),
            intervals: id.intervals.as_ref().map(|b| {
                Ordered(
                    b.intervals
                        .iter()
                        .map(|i| (i.name.as_str(), [i.lower, i.upper]))
                        .collect(),
                )
            }),
            interval_level: id.intervals.as_ref().map(|b| b.level),
            resamples: id.intervals.as_ref().map(|b| b.resamples),
            no_intervals: id.no_intervals.as_deref(),
            explained: id.quality.explained,
            unexplained: id.quality.unexplained,
            held_out_explained: id.quality.held_out.map(|h| h.explained),
            warning: id.warning.as_deref(),
            selection: id.selection.as_ref().map(SelectionJson::of),
        }
    }
}

/// The JSON of a system's identification: one entry per coordinate under `equations`, keyed
/// by its name, and the record and run.
#[derive(Serialize)]
struct SystemJson<'a> {
    method: &'static str,
    coordinates: &'a [String],
    drives: &'a [String],
    equations: Ordered<'a, EquationJson<'a>>,
    /// A tied fit's parameters.
    #[serde(skip_serializing_if = "Option::is_none")]
    parameters: Option<Ordered<'a, ParameterJson>>,
    segments: usize,
    delay: Option<usize>,
    found: &'a str,
    record: &'a RecordSummary,
}

/// A tied fit's parameter in the JSON.
#[derive(Serialize)]
struct ParameterJson {
    value: f64,
    std_error: f64,
    /// The bootstrap interval, at `interval_level`.
    #[serde(skip_serializing_if = "Option::is_none")]
    interval: Option<[f64; 2]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    interval_level: Option<f64>,
}

/// The parameters of a tied fit keyed by name, in the spec's order.
fn parameters_json<'a>(
    parameters: &'a Option<Vec<TiedParameter>>,
    intervals: &Option<hb_solve::Bootstrap>,
) -> Option<Ordered<'a, ParameterJson>> {
    parameters.as_ref().map(|ps| {
        Ordered(
            ps.iter()
                .map(|p| {
                    (
                        p.name.as_str(),
                        ParameterJson {
                            value: p.value,
                            std_error: p.std_error,
                            interval: intervals
                                .as_ref()
                                .and_then(|b| b.interval(&p.name))
                                .map(|i| [i.lower, i.upper]),
                            interval_level: intervals.as_ref().map(|b| b.level),
                        },
                    )
                })
                .collect(),
        )
    })
}

impl Serialize for IdentifyReport {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        if self.equations.len() > 1 {
            return SystemJson {
                method: self.method.name(),
                coordinates: self.names.coordinates(),
                drives: self.names.drives(),
                equations: Ordered(
                    self.equations
                        .iter()
                        .map(|e| (e.coordinate.as_str(), EquationJson::of(e)))
                        .collect(),
                ),
                parameters: parameters_json(&self.parameters, &self.parameter_intervals),
                segments: self.segments,
                delay: self.delay,
                found: &self.found,
                record: &self.record,
            }
            .serialize(s);
        }
        let id = self.identification();
        let model = &id.model;
        let coefficients = model.coefficients();
        let summary = model.summary();
        ReportJson {
            method: self.method.name(),
            parameters: parameters_json(&self.parameters, &self.parameter_intervals),
            basis: self.basis.spec(),
            terms: coefficients.iter().map(|c| c.name.as_str()).collect(),
            drive_column: model.form().drive_column(),
            coefficients: Ordered(coefficients.iter().map(|c| (c.name.as_str(), c.value)).collect()),
            std_errors: Ordered(
                coefficients
                    .iter()
                    .map(|c| (c.name.as_str(), c.std_error))
                    .collect(),
            ),
            orbits_used: summary.map(|s| s.segments),
            segments: self.segments,
            rows: summary.map(|s| s.rows),
            condition_number: summary.map(|s| s.condition),
            residual_rms: summary.map(|s| s.residual_rms),
            intervals: id.intervals.as_ref().map(|b| {
                Ordered(
                    b.intervals
                        .iter()
                        .map(|i| (i.name.as_str(), [i.lower, i.upper]))
                        .collect(),
                )
            }),
            interval_level: id.intervals.as_ref().map(|b| b.level),
            resamples: id.intervals.as_ref().map(|b| b.resamples),
            no_intervals: id.no_intervals.as_deref(),
            explained: id.quality.explained,
            unexplained: id.quality.unexplained,
            held_out_explained: id.quality.held_out.map(|h| h.explained),
            residual_spectrum: id
                .quality
                .spectrum
                .iter()
                .map(|l| SpectrumLine {
                    harmonic: l.harmonic,
                    residual_rms: l.residual_rms,
                    rhs_rms: l.rhs_rms,
                    rows: l.rows,
                })
                .collect(),
            warning: id.warning.as_deref(),
            selection: id.selection.as_ref().map(SelectionJson::of),
            delay: self.delay,
            found: &self.found,
            record: &self.record,
            refinement: self.refinement.as_ref().map(|r| RefinementJson {
                rmse_before: r.rmse_before,
                rmse_after: r.rmse_after,
                scored: r.scored,
                init: r.init,
                iterations: r.iterations,
                simulations: r.simulations,
                converged: r.converged,
                start: Ordered(r.start.iter().map(|(n, v)| (n.as_str(), *v)).collect()),
            }),
        }
        .serialize(s)
    }
}
