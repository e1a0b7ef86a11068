//! One equation's identification, the recipe every front end runs: a method, a basis and the
//! settings of the fit ([`ModelSpec`]), checked against the record's clock into an
//! [`Identifier`], which assembles the segments, selects terms, solves, measures the fit and
//! bootstraps ([`Identifier::identify`]), giving an [`Identification`]. A system of several
//! coordinates runs one identifier per equation on the same segments.

use std::fmt;

use crate::{
    Assembly, AssemblyError, Bootstrap, BootstrapParams, EXPLAINED_WARNING_ORBITS, EXPLAINED_WARNING_WINDOWS,
    FitModel, FitQuality, HELD_OUT_FOLDS, HarmonicBalance, IdentifyParams, LinearSystem, LstsqSolver,
    NoiseCorrection, QrSolver, SelectParams, Selection, Signals, SolveError, WeakForm, bootstrap_or_reason,
    build_system, fit_quality, select_terms,
};
use circle_signal::{SampleClock, Segment};
use hb_basis::{Basis, BasisKind};
use hb_model::{Forcing, Harmonics, IdentifiedModel, ModelForm, TermList};

/// Identification method: where the segments come from and how they become equations.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Method {
    /// The paper's: harmonic balance over unstable periodic orbits found by close returns.
    Upo,
    /// The weak form: harmonic balance of the windowed equation over plain windows of the record.
    Windowed,
}

impl Method {
    /// The assembly of the method: the one place a method turns into rows
    /// ([`HarmonicBalance`] on orbits, `weak` on windows).
    pub fn assembly(self, weak: WeakForm) -> Box<dyn Assembly> {
        match self {
            Method::Upo => Box::new(HarmonicBalance),
            Method::Windowed => Box::new(weak),
        }
    }

    /// The name used in reports and JSON (the assembly's): `upo` or `windowed`.
    pub fn name(self) -> &'static str {
        self.assembly(WeakForm::default()).name()
    }
}

impl Method {
    /// Every method, in the order of the reports.
    pub const ALL: [Method; 2] = [Method::Upo, Method::Windowed];
}

/// `upo` or `windowed`, the names [`Method::name`] gives.
impl std::str::FromStr for Method {
    type Err = UnknownMethod;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Method::ALL
            .into_iter()
            .find(|m| m.name() == s.trim())
            .ok_or_else(|| UnknownMethod(s.to_owned()))
    }
}

/// A name that is no [`Method`]'s.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown method '{0}': expected 'windowed' or 'upo'")]
pub struct UnknownMethod(pub String);

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// One step of an identification, reported as it starts (see [`Identifier::identify_with_progress`]).
/// Exhaustive: a front end maps every step to its own display, and a new step must reach them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IdentifyStep {
    /// Assembling the stacked system of every segment (noise correction included).
    Assemble,
    /// Selecting the terms of the library, when asked for ([`ModelSpec::with_selection`]).
    Select,
    /// Solving it by least squares.
    Solve,
    /// The bootstrap over segments, when asked for.
    Bootstrap,
}

impl IdentifyStep {
    /// A short name for progress displays and timings: `assemble`, `select`, `solve`,
    /// `bootstrap`.
    pub fn name(self) -> &'static str {
        match self {
            IdentifyStep::Assemble => "assemble",
            IdentifyStep::Select => "select",
            IdentifyStep::Solve => "solve",
            IdentifyStep::Bootstrap => "bootstrap",
        }
    }
}

/// What to identify: a method and a basis, and the settings of the fit. It becomes an [`Identifier`]
/// against the record's clock ([`ModelSpec::setup`]), where the combination is checked.
///
/// Defaults: the paper's form ([`ModelForm::parametric`]: damping, autonomous and parametric
/// terms, no external forcing), the method's own harmonics per segment, reaching the form's
/// highest drive harmonic ([`Assembly::default_harmonics_for`]), no noise correction, column-pivoted QR, no bootstrap, and
/// the default weak form ([`WeakForm::default`], used by [`Method::Windowed`] only), and no
/// selection of terms.
#[derive(Debug)]
pub struct ModelSpec {
    method: Method,
    basis: BasisKind,
    form: ModelForm,
    harmonics: Option<Harmonics>,
    noise: NoiseCorrection,
    solver: Box<dyn LstsqSolver>,
    bootstrap: Option<BootstrapParams>,
    weak: WeakForm,
    selection: Option<SelectParams>,
}

impl ModelSpec {
    /// A model on `basis` identified by `method`, with the defaults above.
    pub fn new(method: Method, basis: BasisKind) -> Self {
        Self {
            method,
            basis,
            form: ModelForm::parametric(),
            harmonics: None,
            noise: NoiseCorrection::None,
            solver: Box::new(QrSolver::default()),
            bootstrap: None,
            weak: WeakForm::default(),
            selection: None,
        }
    }

    /// The terms of the model.
    pub fn with_form(mut self, form: ModelForm) -> Self {
        self.form = form;
        self
    }

    /// Harmonics per segment instead of the method's default (checked: `M >= 1`, or a cap `>= 1`).
    pub fn with_harmonics(mut self, harmonics: Harmonics) -> Result<Self, SolveError> {
        self.harmonics = Some(harmonics.validate()?);
        Ok(self)
    }

    /// The correction of the bias of Gaussian noise on the angle (checked with the rest of the
    /// parameters by [`ModelSpec::setup`]).
    pub fn with_noise_correction(mut self, noise: NoiseCorrection) -> Self {
        self.noise = noise;
        self
    }

    /// The least-squares solver.
    pub fn with_solver(mut self, solver: Box<dyn LstsqSolver>) -> Self {
        self.solver = solver;
        self
    }

    /// Bootstrap intervals for every coefficient.
    pub fn with_bootstrap(mut self, bootstrap: BootstrapParams) -> Self {
        self.bootstrap = Some(bootstrap);
        self
    }

    /// The weak form's window (for [`Method::Windowed`]).
    pub fn with_weak_form(mut self, weak: WeakForm) -> Self {
        self.weak = weak;
        self
    }

    /// Model selection: the form's terms are a library of candidates, the terms the data
    /// support are chosen by [`crate::select_terms`] with `params`, and only those are fitted
    /// ([`Identification::selection`] says which and why). The library is the form's terms on the
    /// basis ([`ModelForm::term_list`]): a list of terms, or the default form's own.
    pub fn with_selection(mut self, params: SelectParams) -> Self {
        self.selection = Some(params);
        self
    }

    /// The method.
    pub fn method(&self) -> Method {
        self.method
    }

    /// The setup on the record's `clock`: the identification parameters are built and checked
    /// (with a selection, the library's terms too).
    pub fn setup(self, clock: &SampleClock) -> Result<Identifier, SolveError> {
        let assembly = self.method.assembly(self.weak);
        let harmonics = self
            .harmonics
            .unwrap_or_else(|| assembly.default_harmonics_for(&self.form));
        let selection = match self.selection {
            Some(p) => Some((self.form.term_list(&self.basis)?, p)),
            None => None,
        };
        let params = IdentifyParams::builder(*clock)
            .velocity_harmonics(IdentifyParams::default_velocity_harmonics_for(&self.form))
            .form(self.form)
            .harmonics(harmonics)
            .noise_correction(self.noise)
            .build()?;
        Ok(Identifier {
            method: self.method,
            weak: self.weak,
            basis: self.basis,
            params,
            solver: self.solver,
            bootstrap: self.bootstrap,
            assembly,
            selection,
        })
    }
}

/// Everything but the data: basis, parameters, assembly and solver, checked before any work.
#[derive(Debug)]
pub struct Identifier {
    method: Method,
    /// The weak form's settings (of its assembly, when the method is the weak form's).
    weak: WeakForm,
    basis: BasisKind,
    params: IdentifyParams,
    solver: Box<dyn LstsqSolver>,
    bootstrap: Option<BootstrapParams>,
    assembly: Box<dyn Assembly>,
    /// The library's terms and the selection's parameters, when terms are selected.
    selection: Option<(TermList, SelectParams)>,
}

/// The terms a selection kept from its library of candidates, and why it dropped the others.
#[derive(Debug, Clone, PartialEq)]
pub struct TermSelection {
    /// Every candidate, in the library's order (the names of the model's terms).
    pub library: TermList,
    /// The kept terms, in the library's order: the terms of the fitted model.
    pub kept: TermList,
    /// What [`crate::select_terms`] found: the kept terms (indices into `library`), the
    /// dropped ones with their held-out scores, the elimination path, the folds and the
    /// allowance.
    pub outcome: Selection,
}

/// An identified model with its bootstrap intervals.
#[derive(Debug, Clone, PartialEq)]
pub struct Identification {
    /// The model, with its fit summary.
    pub model: IdentifiedModel,
    /// The bootstrap intervals of its coefficients, when asked for and they can be had.
    pub intervals: Option<Bootstrap>,
    /// Why there are no intervals when they were asked for ([`crate::bootstrap_or_reason`]):
    /// the model and its standard errors are given all the same.
    pub no_intervals: Option<String>,
    /// How well it fits: the fraction of the balanced acceleration it explains, in sample and on
    /// held-out stretches of the record, and the residual by frequency
    /// ([`crate::fit_quality`], [`crate::held_out`]).
    pub quality: FitQuality,
    /// A warning that the model does not describe the record: it explains too little for its
    /// method, in sample or held out, or far less held out than in sample
    /// ([`FitQuality::warning`], [`crate::EXPLAINED_WARNING_WINDOWS`],
    /// [`crate::EXPLAINED_WARNING_ORBITS`]).
    pub warning: Option<String>,
    /// With [`ModelSpec::with_selection`]: the library, and which of its terms were kept (the
    /// model, its intervals, quality and warning are those of the kept terms alone).
    pub selection: Option<TermSelection>,
}

impl Identifier {
    /// The method.
    pub fn method(&self) -> Method {
        self.method
    }

    /// The basis of the unknown functions.
    pub fn basis(&self) -> BasisKind {
        self.basis
    }

    /// The identification parameters (clock, form, harmonics, noise correction).
    pub fn params(&self) -> &IdentifyParams {
        &self.params
    }

    /// The bootstrap's parameters, if intervals are asked for.
    pub fn bootstrap(&self) -> Option<&BootstrapParams> {
        self.bootstrap.as_ref()
    }

    /// The least-squares solver.
    pub(crate) fn solver(&self) -> &dyn LstsqSolver {
        self.solver.as_ref()
    }

    /// The library of candidate terms and the selection's parameters, when terms are selected.
    pub fn selection(&self) -> Option<(&TermList, &SelectParams)> {
        self.selection.as_ref().map(|(l, p)| (l, p))
    }

    /// Assembles the rows of the method over `segments` of `signals` ([`build_system`]: the own
    /// coordinate's samples `&x`, or a system's coordinates and drives), selects the terms when
    /// asked (then only the kept columns are solved), solves, and bootstraps.
    ///
    /// Errors: the assembly's, the solver's and the bootstrap's; with a selection also
    /// `SolveError::Lstsq(LstsqError::TooFewOrbits)` for fewer than two segments and
    /// `SolveError::Select(SelectError::SelectionUndetermined)` when a fold held out leaves the library
    /// undetermined.
    pub fn identify<'a>(
        &self,
        signals: impl Into<Signals<'a>>,
        segments: &[Segment],
    ) -> Result<Identification, SolveError> {
        self.identify_with_progress(signals, segments, |_| {})
    }

    /// The unexplained fraction of the fit over `segments` of `signal` (no bootstrap), and
    /// whether the model has a constant term `1`: what a drift's fit minimises ([`fit_drift`](crate::drift::fit_drift)).
    pub fn unexplained<'a>(
        &self,
        signals: impl Into<Signals<'a>>,
        segments: &[Segment],
    ) -> Result<(f64, bool), SolveError> {
        let system = self.system(&signals.into(), segments)?;
        let fit = system.solve(self.solver.as_ref())?;
        let constant = system.names().iter().any(|n| n == "1");
        Ok((fit_quality(&system, &fit.solution)?.unexplained, constant))
    }

    /// The stacked rows of the method over `segments` of `signals` ([`build_system`]).
    pub(crate) fn system(
        &self,
        signals: &Signals<'_>,
        segments: &[Segment],
    ) -> Result<LinearSystem, SolveError> {
        build_system(
            &self.basis,
            signals,
            segments,
            &self.params,
            self.assembly.as_ref(),
        )
    }

    /// [`Identifier::identify`], calling `progress` with each step as it starts.
    pub fn identify_with_progress<'a>(
        &self,
        signals: impl Into<Signals<'a>>,
        segments: &[Segment],
        mut progress: impl FnMut(IdentifyStep),
    ) -> Result<Identification, SolveError> {
        progress(IdentifyStep::Assemble);
        let system = self.system(&signals.into(), segments)?;
        self.identify_system(system, progress)
    }

    /// The stacked rows of each of a system's equations, `setups[i]` on `signals[i]`, over the
    /// shared `segments` ([`build_system`] of each): assembled together when the setups share
    /// their method and its settings ([`crate::build_systems`]: each coordinate's window made
    /// once per segment for every equation), one after the other otherwise; the same systems
    /// either way. What [`Identifier::identify_system`] takes.
    ///
    /// More segments than [`crate::MAX_BLOCKS`]: the segments are assembled in chunks of
    /// [`crate::COMPRESS_CHUNK`] groups of `g = ⌈segments / MAX_BLOCKS⌉` consecutive segments, and each
    /// chunk's systems [compressed](LinearSystem::compressed) by those groups before the next is
    /// assembled, so that a long record's rows are never all held: the same least-squares
    /// problems, at most `MAX_BLOCKS` blocks of `unknowns + 1` rows each.
    ///
    /// Errors: the assemblies'; [`SolveError::Assembly`] when `signals` and `setups` differ in
    /// number.
    pub fn systems(
        setups: &[Identifier],
        signals: &[Signals<'_>],
        segments: &[Segment],
    ) -> Result<Vec<LinearSystem>, SolveError> {
        if setups.len() != signals.len() {
            return Err(SolveError::Assembly(AssemblyError::EquationCount {
                setups: setups.len(),
                signals: signals.len(),
            }));
        }
        let group = segments.len().div_ceil(crate::MAX_BLOCKS);
        if group <= 1 {
            return Self::systems_at_once(setups, signals, segments);
        }
        Self::systems_grouped(setups, signals, segments, group)
    }

    /// [`Identifier::systems`] compressed by groups of `group` consecutive segments (at least
    /// 1; [`LinearSystem::compressed`]), assembled [`crate::COMPRESS_CHUNK`] groups at a time:
    /// what a record read in chunks assembles each chunk's segments by, its group found from the
    /// whole record's length.
    ///
    /// Errors: [`Identifier::systems`]'.
    pub fn systems_grouped(
        setups: &[Identifier],
        signals: &[Signals<'_>],
        segments: &[Segment],
        group: usize,
    ) -> Result<Vec<LinearSystem>, SolveError> {
        if setups.len() != signals.len() {
            return Err(SolveError::Assembly(AssemblyError::EquationCount {
                setups: setups.len(),
                signals: signals.len(),
            }));
        }
        Self::grouped_in(setups, signals, segments, group.max(1), crate::COMPRESS_CHUNK)
    }

    /// [`Identifier::systems_grouped`] assembled `chunk` groups at a time.
    fn grouped_in(
        setups: &[Identifier],
        signals: &[Signals<'_>],
        segments: &[Segment],
        group: usize,
        chunk: usize,
    ) -> Result<Vec<LinearSystem>, SolveError> {
        // Chunks of about `chunk` groups, as even as the segments allow (a short last chunk
        // could hold fewer rows than unknowns).
        let chunks = segments.len().div_ceil(group * chunk.max(1)).max(1);
        let mut parts: Vec<Vec<LinearSystem>> = (0..setups.len()).map(|_| Vec::new()).collect();
        for c in 0..chunks {
            let piece = &segments[c * segments.len() / chunks..(c + 1) * segments.len() / chunks];
            for (part, system) in parts
                .iter_mut()
                .zip(Self::systems_at_once(setups, signals, piece)?)
            {
                part.push(system.compressed(group)?);
            }
        }
        parts.into_iter().map(LinearSystem::joined).collect()
    }

    /// [`Identifier::systems`] with every segment's rows held.
    fn systems_at_once(
        setups: &[Identifier],
        signals: &[Signals<'_>],
        segments: &[Segment],
    ) -> Result<Vec<LinearSystem>, SolveError> {
        let together = setups
            .windows(2)
            .all(|w| w[0].method == w[1].method && w[0].weak == w[1].weak);
        match setups.first() {
            Some(first) if together && setups.len() > 1 => {
                let equations: Vec<crate::EquationInput<'_>> = setups
                    .iter()
                    .zip(signals)
                    .map(|(s, signals)| (&s.basis as &dyn Basis, signals, &s.params))
                    .collect();
                crate::build_systems(&equations, segments, first.assembly.as_ref())
            }
            _ => setups
                .iter()
                .zip(signals)
                .map(|(s, signals)| s.system(signals, segments))
                .collect(),
        }
    }

    /// [`Identifier::identify_with_progress`] from the assembled `system` of this setup
    /// ([`Identifier::systems`]): selection, least squares, quality and bootstrap, calling
    /// `progress` with each step as it starts.
    pub fn identify_system(
        &self,
        system: LinearSystem,
        mut progress: impl FnMut(IdentifyStep),
    ) -> Result<Identification, SolveError> {
        let (system, params, selection) = match &self.selection {
            Some((library, select)) => {
                progress(IdentifyStep::Select);
                let (system, params, selection) = self.select(system, library, select)?;
                (system, params, Some(selection))
            }
            None => (system, self.params.clone(), None),
        };
        progress(IdentifyStep::Solve);
        let solver = self.solver.as_ref();
        let fit = system.solve(solver)?;
        let model = IdentifiedModel::from_fit(self.basis, &params, &system, &fit, solver.name())?;
        let folds = self.selection.as_ref().map_or(HELD_OUT_FOLDS, |(_, p)| p.folds());
        let quality = fit_quality(&system, &fit.solution)?.with_held_out(&system, folds);
        let warning = quality
            .warning(match self.method {
                Method::Upo => EXPLAINED_WARNING_ORBITS,
                Method::Windowed => EXPLAINED_WARNING_WINDOWS,
            })
            .or_else(|| undetermined_warning(&quality, &system, folds, fit.condition));
        let (intervals, no_intervals) = match &self.bootstrap {
            Some(b) => {
                progress(IdentifyStep::Bootstrap);
                match bootstrap_or_reason(&system, &fit, solver, b) {
                    Ok(intervals) => (Some(intervals), None),
                    Err(why) => (None, Some(why.reason)),
                }
            }
            None => (None, None),
        };
        Ok(Identification {
            model,
            intervals,
            no_intervals,
            quality,
            warning,
            selection,
        })
    }

    /// Selects the terms of `library` on its `system`: the system of the kept columns, the
    /// parameters of the kept terms' model (a list of them, a known forcing kept), and the
    /// selection.
    fn select(
        &self,
        system: LinearSystem,
        library: &TermList,
        select: &SelectParams,
    ) -> Result<(LinearSystem, IdentifyParams, TermSelection), SolveError> {
        let outcome = select_terms(&system, select)?;
        let terms = library.terms();
        let selection = TermSelection {
            library: library.clone(),
            kept: TermList::new_in(
                outcome.kept.iter().map(|&i| terms[i]).collect(),
                library.names_in().clone(),
                library.own(),
            )?,
            outcome,
        };
        let kept = system.with_columns(&selection.outcome.kept)?;
        let mut form = ModelForm::from_terms(selection.kept.clone());
        if let known @ Forcing::Known { .. } = self.params.form().forcing() {
            form = form.with_forcing(known);
        }
        if let Some(column) = self.params.form().drive_column()
            && form.has_measured_drive()
        {
            form = form.with_drive_column(column);
        }
        let params = IdentifyParams::builder(*self.params.clock())
            .form(form)
            .harmonics(self.params.harmonics())
            .noise_correction(self.params.noise_correction())
            .velocity_harmonics(self.params.velocity_harmonics())
            .build()?;
        Ok((kept, params, selection))
    }
}

/// A tied identification ([`identify_tied`]): each equation's identification (its model in the
/// ordinary form, normalised by its own acceleration) and the shared parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct TiedIdentification {
    /// One per equation, in the coordinates' order. No bootstrap intervals: `no_intervals`
    /// says so when they were asked for. The share explained is in sample only.
    pub equations: Vec<Identification>,
    /// The parameters and the per-equation fits.
    pub fit: crate::TiedFit,
    /// The bootstrap intervals of the parameters, when asked for and they can be had.
    pub intervals: Option<Bootstrap>,
    /// Why there are no intervals of the parameters when they were asked for.
    pub no_intervals: Option<String>,
}

/// Why the equations of a tied fit have no bootstrap intervals of their own.
pub const TIED_NO_INTERVALS: &str =
    "a tied fit's bootstrap intervals are its parameters' (the coefficients follow from them)";

/// The tied fit of a system ([`crate::Tie`]) from each equation's rows, `systems[i]` assembled by
/// its `setups[i]` (made with the form of [`crate::Tie::terms`]) over the shared segments
/// ([`Identifier::systems`]): the parameters fitted to the stacked rows by the first setup's
/// solver ([`crate::Tie::fit`]), and each equation's model made from its normalised
/// coefficients. `progress` hears each step.
///
/// Errors: [`crate::TieError`] and the solver's.
pub fn identify_tied(
    tie: &crate::Tie,
    setups: &[Identifier],
    systems: Vec<LinearSystem>,
    mut progress: impl FnMut(IdentifyStep),
) -> Result<TiedIdentification, SolveError> {
    progress(IdentifyStep::Solve);
    let solver = setups
        .first()
        .ok_or(crate::TieError::SystemMismatch {
            expected: tie.equations(),
            found: 0,
            term: String::new(),
        })?
        .solver();
    let fit = tie.fit(&systems, solver)?;
    let (intervals, no_intervals) = match setups[0].bootstrap() {
        Some(params) => {
            progress(IdentifyStep::Bootstrap);
            match tie.bootstrap(&systems, &fit, solver, params) {
                Ok(b) => (Some(b), None),
                Err(why) => (None, Some(why.reason)),
            }
        }
        None => (None, None),
    };
    let mut equations = Vec::with_capacity(systems.len());
    for (i, ((setup, system), eq)) in setups.iter().zip(&systems).zip(&fit.equations).enumerate() {
        let terms = tie.terms(i).names();
        let coefficients = system
            .names()
            .iter()
            .map(|name| {
                let k = terms.iter().position(|n| n == name);
                let k = k.ok_or_else(|| crate::TieError::SystemMismatch {
                    expected: tie.equations(),
                    found: systems.len(),
                    term: name.clone(),
                })?;
                Ok(hb_model::Coefficient {
                    name: name.clone(),
                    value: eq.coefficients[k],
                    std_error: eq.std_errors[k],
                })
            })
            .collect::<Result<Vec<_>, SolveError>>()?;
        let summary = hb_model::FitSummary {
            solver: solver.name().to_owned(),
            harmonics: setup.params.harmonics(),
            clock: *setup.params.clock(),
            rows: eq.rows,
            unknowns: tie.parameters().len(),
            segments: system.segments(),
            whirling_segments: system.whirling_segments(),
            condition: fit.condition,
            residual_rms: eq.residual_rms,
            residual_variance: eq.residual_variance,
        };
        let values: Vec<f64> = coefficients.iter().map(|c| c.value).collect();
        let model = IdentifiedModel::from_coefficients(
            setup.basis,
            setup.params.form().clone(),
            setup.params.clock().drive_angular_frequency(),
            coefficients,
            Some(summary),
        )?;
        let quality = fit_quality(system, &values)?;
        let warning = quality.warning(match setup.method {
            Method::Upo => EXPLAINED_WARNING_ORBITS,
            Method::Windowed => EXPLAINED_WARNING_WINDOWS,
        });
        equations.push(Identification {
            model,
            intervals: None,
            no_intervals: setup.bootstrap.is_some().then(|| TIED_NO_INTERVALS.to_owned()),
            quality,
            warning,
            selection: None,
        });
    }
    Ok(TiedIdentification {
        equations,
        fit,
        intervals,
        no_intervals,
    })
}

/// The warning of a fit whose share on held-out stretches could not be had because the record
/// less one of its folds does not determine the coefficients (its normal equations singular to
/// working precision): the terms are nearly dependent on this record, and the coefficients,
/// however well they fit it, are not those of its equation (a periodic response, on which a
/// parametric library's terms are functions of one another, is the common case).
fn undetermined_warning(
    quality: &FitQuality,
    system: &LinearSystem,
    folds: usize,
    condition: f64,
) -> Option<String> {
    (quality.held_out.is_none() && folds >= 2 && system.blocks().len() >= 2).then(|| {
        format!(
            "the record does not tell the terms apart: without one of {folds} folds of its stretches they are \
             dependent to working precision (condition number {condition:.1e}), so the coefficients, however \
             well they fit, are not determined (a periodic response excites too few states for a library this \
             large: fewer terms, «select», or a record of richer motion)"
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{QrSolver, fit_quality};
    use hb_basis::Harmonic;

    /// A long record's systems, assembled in chunks and compressed by groups, give the
    /// coefficients, standard errors and share explained of the systems held whole.
    #[test]
    fn systems_in_chunks_solve_as_the_whole() {
        let p = 25;
        let clock = SampleClock::nondimensional(p).unwrap();
        let h = clock.step();
        // A damped, driven oscillator's response with a little deterministic ripple.
        let x: Vec<f64> = (0..30_000)
            .map(|n| {
                let t = n as f64 * h;
                0.8 * (t + 0.3).sin() + 0.2 * (2.0 * t).cos() + 1e-3 * (0.37 * n as f64).sin()
            })
            .collect();
        let segments = upo_search::Windows::new(&clock).unwrap().windows(&x).unwrap();
        assert!(segments.len() > 1000);
        let setup = ModelSpec::new(Method::Windowed, Harmonic::new(1).unwrap().into())
            .setup(&clock)
            .unwrap();
        let signals = [Signals::from(&x[..])];
        let whole = Identifier::systems(std::slice::from_ref(&setup), &signals, &segments).unwrap();
        let max = 97;
        // Chunks of 8 groups: several of them, joined.
        let chunked = Identifier::grouped_in(
            std::slice::from_ref(&setup),
            &signals,
            &segments,
            segments.len().div_ceil(max),
            8,
        )
        .unwrap();
        let (whole, chunked) = (&whole[0], &chunked[0]);
        assert!(!whole.is_compressed() && chunked.is_compressed());
        assert!(chunked.blocks().len() <= max, "{} blocks", chunked.blocks().len());
        assert_eq!(chunked.segments(), segments.len());
        assert_eq!(chunked.whirling_segments(), whole.whirling_segments());
        assert_eq!(chunked.equations(), whole.rows());
        assert!(chunked.rows() <= max * (whole.unknowns() + 1));
        let solver = QrSolver::default();
        let (a, b) = (whole.solve(&solver).unwrap(), chunked.solve(&solver).unwrap());
        assert_eq!(a.rows, b.rows);
        for (u, v) in a.solution.iter().zip(&b.solution) {
            assert!((u - v).abs() <= 1e-10 * u.abs().max(1e-3), "{u} vs {v}");
        }
        for (u, v) in a.std_errors.iter().zip(&b.std_errors) {
            assert!((u - v).abs() <= 1e-6 * u.abs(), "{u} vs {v}");
        }
        let (qa, qb) = (
            fit_quality(whole, &a.solution).unwrap(),
            fit_quality(chunked, &b.solution).unwrap(),
        );
        assert!((qa.unexplained - qb.unexplained).abs() <= 1e-6 * qa.unexplained.max(1e-12));
        assert_eq!(qa.spectrum.len(), qb.spectrum.len());
        for (la, lb) in qa.spectrum.iter().zip(&qb.spectrum) {
            assert_eq!((la.harmonic, la.rows), (lb.harmonic, lb.rows));
            assert!((la.rhs_rms - lb.rhs_rms).abs() <= 1e-9 * la.rhs_rms.max(1e-12));
            assert!((la.residual_rms - lb.residual_rms).abs() <= 1e-5 * la.residual_rms.max(1e-9));
        }
    }
}
