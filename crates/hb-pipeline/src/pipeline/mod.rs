//! The whole analysis of one record, from the samples to validated models: the delay and the
//! embedding dimension, the segments (orbits by close returns, plain windows), the identification
//! by each method asked for, and the validation of every model by simulation.
//!
//! This is what `hbid report` runs on a user's record and `cargo xtask reproduce` on the paper's:
//! the front ends hold only their presentation (tables, figures, progress bars). Nothing here
//! prints or touches a file; progress comes through a callback ([`Stage`]); every option is
//! checked when it is set or, where it depends on the record, when the [`Pipeline`] is built,
//! before any work.
//!
//! The stages, in order ([`Pipeline::run`] calls them all; a front end that interleaves work of
//! its own calls them one by one):
//!
//! 1. [`Pipeline::embed`]: the average mutual information and its first minimum (the delay,
//!    unless given), and false nearest neighbours with that delay ([`EmbedOptions`]);
//! 2. [`Pipeline::segments`]: the close-return search and its catalogue of distinct orbits
//!    ([`SearchOptions`]), and plain windows when a model asks for them ([`WindowOptions`]);
//! 3. [`Pipeline::identify`]: each [`ModelSpec`] in turn, by [`hb_solve::build_system`] with its
//!    method's [`hb_solve::Assembly`], least squares and the bootstrap ([`Setup`]);
//! 4. [`Pipeline::validate`]: each model simulated and measured by
//!    [`pendulum_sim::check_model`], and compared with the record in delay coordinates
//!    ([`ValidationOptions`]) and by its valid prediction time from the record's own states
//!    ([`PredictionOptions`]).
//!
//! # Example
//!
//! The paper's pendulum, simulated and wrapped as an encoder reports it, identified by the weak
//! form on plain windows:
//!
//! ```
//! use circle_signal::SampleClock;
//! use hb_basis::{BasisKind, Harmonic};
//! use hb_pipeline::pipeline::{Method, ModelSpec, Pipeline, PipelineOptions, Record, Stage, ValidationOptions};
//! use pendulum_sim::{Domain, Pendulum, SimulationConfig, simulate};
//!
//! let config = SimulationConfig::paper().with_samples(4_000)?;
//! let trajectory = simulate(&Pendulum::paper(), &config)?;
//! let x = trajectory.wrapped();
//! let clock = SampleClock::nondimensional(25)?.with_start_time(trajectory.t[0])?;
//! let record = Record::new(&x, clock, Domain::Circle)?;
//! let options = PipelineOptions {
//!     models: vec![ModelSpec::new(Method::Windowed, BasisKind::from(Harmonic::new(1)?))],
//!     validation: ValidationOptions::default()
//!         .with_section_points(20)?
//!         .with_lyapunov_periods(20)?,
//!     ..PipelineOptions::default()
//! };
//! let mut stages = Vec::new();
//! let outcome = Pipeline::new(record, options)?.run(|stage| stages.push(stage))?;
//! assert_eq!(outcome.embedded.ami.first_minimum(), Some(outcome.embedded.delay));
//! let model = &outcome.models[0].model;
//! assert!((model.coefficient("sin(t)*cos(x)").unwrap().value + 1.52).abs() < 1e-6);
//! assert_eq!(outcome.validation.models.len(), 1);
//! let windowed = Method::Windowed;
//! assert_eq!(
//!     stages,
//!     [
//!         Stage::Embed,
//!         Stage::Segments,
//!         Stage::Identify { model: 0, method: windowed },
//!         Stage::Validate { model: 0, method: windowed },
//!     ]
//! );
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod error;
mod prediction;

pub use error::PipelineError;
pub use hb_solve::drift::{DriftFit, GOLDEN_STEPS, PieceDrift, SCAN_POINTS, fit_drift};
/// The per-equation identifier, [`hb_solve::identifier`]'s, by the names this module has always
/// given it (`Setup` is [`hb_solve::Identifier`]).
pub use hb_solve::identifier::{
    Identification, Identifier as Setup, IdentifyStep, Method, ModelSpec, TermSelection, UnknownMethod,
};
pub use prediction::PredictionOptions;

use std::ops::Range;

use rayon::prelude::*;

use circle_signal::{Domain, SampleClock, Segment};
use embedding::{
    AmiCurve, AmiParams, FnnParams, FnnResult, average_mutual_information, false_nearest_neighbours,
};
use pendulum_sim::{
    CheckConfig, LyapunovConfig, ModelCheck, PredictionTimes, SecondOrderSystem, SimError, SimulationConfig,
    check_model, energy_distance, simulate,
};
use upo_search::{Catalogue, CloseReturns, Windows};

/// A record ready for the pipeline: its samples, its clock and what the samples are, and, for a
/// record with gaps, the pieces that hold data.
///
/// A record with gaps keeps one clock: its samples lie on one grid, the missing ones NaN, and its
/// pieces are the ranges that hold data. Every stage respects them: the delay and the embedding
/// dimension come from the longest piece, orbits and windows are searched in each piece (none spans
/// a gap), and the record's own section in the validation takes its points from every piece.
#[derive(Debug, Clone, PartialEq)]
pub struct Record<'a> {
    samples: &'a [f64],
    pieces: Vec<Range<usize>>,
    clock: SampleClock,
    domain: Domain,
    samples_per_period: usize,
}

impl<'a> Record<'a> {
    /// `samples` (not empty; on the circle, wrapped into `[−π, π)`) taken on `clock`, whose forcing
    /// period must be a whole number `P` of samples, in `domain`.
    pub fn new(samples: &'a [f64], clock: SampleClock, domain: Domain) -> Result<Self, PipelineError> {
        Self::with_pieces(
            samples,
            std::iter::once(0..samples.len()).collect(),
            clock,
            domain,
        )
    }

    /// A record with gaps: `samples` on `clock`'s grid hold data in `pieces` (non-empty ranges, in
    /// order and disjoint, every sample in them finite); what lies between the pieces is never read.
    pub fn with_pieces(
        samples: &'a [f64],
        pieces: Vec<Range<usize>>,
        clock: SampleClock,
        domain: Domain,
    ) -> Result<Self, PipelineError> {
        let samples_per_period = clock.require_whole()?;
        if samples.is_empty() || pieces.is_empty() {
            return Err(PipelineError::EmptyRecord);
        }
        circle_signal::check_pieces(samples, &pieces)?;
        Ok(Self {
            samples,
            pieces,
            clock,
            domain,
            samples_per_period,
        })
    }

    /// The prepared record `data` ([`hb_record::prepare::Data`]) as the pipeline takes it.
    pub fn from_data(data: &'a hb_record::prepare::Data) -> Result<Self, PipelineError> {
        Self::with_pieces(&data.x, data.pieces.clone(), data.clock, data.domain)
    }

    /// The samples (NaN in the gaps between pieces).
    pub fn samples(&self) -> &'a [f64] {
        self.samples
    }

    /// The ranges of the samples that hold data: one for a record without gaps.
    pub fn pieces(&self) -> &[Range<usize>] {
        &self.pieces
    }

    /// The longest piece (the first of the longest), on which the delay and the embedding
    /// dimension are found.
    pub fn longest_piece(&self) -> &'a [f64] {
        &self.samples[circle_signal::longest_piece(&self.pieces)]
    }

    /// The first sample that holds data.
    pub fn first_sample(&self) -> f64 {
        self.samples[self.pieces[0].start]
    }

    /// The clock: forcing period, sample step, time of the first sample.
    pub fn clock(&self) -> &SampleClock {
        &self.clock
    }

    /// An angle on the circle or a displacement on the line.
    pub fn domain(&self) -> Domain {
        self.domain
    }

    /// Samples per forcing period, `P`.
    pub fn samples_per_period(&self) -> usize {
        self.samples_per_period
    }
}

/// Options of the delay and embedding stage, checked when set.
///
/// Defaults: the delay is the first minimum of the average mutual information over 16 equal
/// boxes and lags up to two forcing periods (at least [`AmiParams::DEFAULT_MAX_LAG`]), so that the
/// search reaches as far in time at any sampling rate; false nearest neighbours up to dimension 8 in the record's own metric,
/// and in no other.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EmbedOptions {
    delay: Option<usize>,
    bins: usize,
    max_lag: Option<usize>,
    max_dim: usize,
    compared_metric: Option<Domain>,
}

impl Default for EmbedOptions {
    fn default() -> Self {
        Self {
            delay: None,
            bins: AmiParams::DEFAULT_BINS,
            max_lag: None,
            max_dim: FnnParams::DEFAULT_MAX_DIM,
            compared_metric: None,
        }
    }
}

impl EmbedOptions {
    /// A given delay `>= 1` in samples for every later stage. The mutual information is still
    /// computed (for its figure), but need not have a first minimum.
    pub fn with_delay(mut self, delay: usize) -> Result<Self, PipelineError> {
        FnnParams::new(Domain::Circle, delay)?;
        self.delay = Some(delay);
        Ok(self)
    }

    /// Equal boxes of the mutual-information histogram, `2..=1024`.
    pub fn with_bins(mut self, bins: usize) -> Result<Self, PipelineError> {
        AmiParams::new(Domain::Circle).with_bins(bins)?;
        self.bins = bins;
        Ok(self)
    }

    /// Largest lag `>= 1` of the mutual information (shorter than the record) instead of the
    /// default two forcing periods.
    pub fn with_max_lag(mut self, max_lag: usize) -> Result<Self, PipelineError> {
        AmiParams::new(Domain::Circle).with_max_lag(max_lag)?;
        self.max_lag = Some(max_lag);
        Ok(self)
    }

    /// Largest embedding dimension tested by false nearest neighbours, `1..=8`.
    pub fn with_max_dim(mut self, max_dim: usize) -> Result<Self, PipelineError> {
        FnnParams::new(Domain::Circle, 1)?.with_max_dim(max_dim)?;
        self.max_dim = max_dim;
        Ok(self)
    }

    /// False nearest neighbours also with `metric`, to show what the metric changes (the
    /// reproduction sets the linear metric beside the circle's).
    pub fn with_compared_metric(mut self, metric: Domain) -> Self {
        self.compared_metric = Some(metric);
        self
    }

    /// The given delay, if any.
    pub fn delay(&self) -> Option<usize> {
        self.delay
    }

    /// The largest lag of the mutual information on a record of `samples_per_period`: the one
    /// given, or two forcing periods (at least [`AmiParams::DEFAULT_MAX_LAG`]).
    pub fn max_lag(&self, samples_per_period: usize) -> usize {
        self.max_lag
            .unwrap_or_else(|| (2 * samples_per_period).max(AmiParams::DEFAULT_MAX_LAG))
    }

    fn ami_params(&self, metric: Domain, samples_per_period: usize) -> Result<AmiParams, PipelineError> {
        Ok(AmiParams::new(metric)
            .with_bins(self.bins)?
            .with_max_lag(self.max_lag(samples_per_period))?)
    }

    fn fnn_params(&self, metric: Domain, delay: usize) -> Result<FnnParams, PipelineError> {
        Ok(FnnParams::new(metric, delay)?.with_max_dim(self.max_dim)?)
    }
}

/// A clock with whole periods on which the options that do not depend on the record are checked.
fn probe_clock() -> SampleClock {
    SampleClock::nondimensional(2).expect("two samples per period make a valid clock")
}

/// Options of the close-return search (paper section 3.2), checked when set (and against the
/// record when the pipeline is built).
///
/// Defaults: the paper's, a tolerance of 3 % of the span of the data, periods 1 to 16, delay
/// vectors of dimension 2 ([`CloseReturns::DEFAULT_TOLERANCE`] and the like).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SearchOptions {
    tolerance: f64,
    max_period: usize,
    dimension: usize,
}

impl Default for SearchOptions {
    fn default() -> Self {
        Self {
            tolerance: CloseReturns::DEFAULT_TOLERANCE,
            max_period: CloseReturns::DEFAULT_MAX_PERIOD,
            dimension: CloseReturns::DEFAULT_DIMENSION,
        }
    }
}

impl SearchOptions {
    /// Tolerance as a fraction of the span of the data (2π for an angle), in `(0, 0.5)`.
    pub fn with_tolerance(mut self, fraction: f64) -> Result<Self, PipelineError> {
        CloseReturns::builder(&probe_clock(), 1)
            .tolerance(fraction)
            .build()?;
        self.tolerance = fraction;
        Ok(self)
    }

    /// Longest orbit period searched `>= 1`, in forcing periods.
    pub fn with_max_period(mut self, max_period: usize) -> Result<Self, PipelineError> {
        CloseReturns::builder(&probe_clock(), 1)
            .max_period(max_period)
            .build()?;
        self.max_period = max_period;
        Ok(self)
    }

    /// Dimension `>= 1` of the delay vectors compared.
    pub fn with_dimension(mut self, dimension: usize) -> Result<Self, PipelineError> {
        CloseReturns::builder(&probe_clock(), 1)
            .dimension(dimension)
            .build()?;
        self.dimension = dimension;
        Ok(self)
    }

    /// The tolerance, a fraction of the span of the data.
    pub fn tolerance(&self) -> f64 {
        self.tolerance
    }

    /// The search on `record` with `delay` (checked against the record's clock).
    pub fn close_returns(&self, record: &Record<'_>, delay: usize) -> Result<CloseReturns, PipelineError> {
        Ok(CloseReturns::builder(record.clock(), delay)
            .tolerance(self.tolerance)
            .max_period(self.max_period)
            .dimension(self.dimension)
            .domain(record.domain())
            .build()?)
    }
}

/// Options of the plain windows of the weak form, checked when set (and against the record when
/// the pipeline is built).
///
/// Default: windows of [`Windows::DEFAULT_PERIODS`] forcing periods, one period apart.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowOptions {
    periods: usize,
}

impl Default for WindowOptions {
    fn default() -> Self {
        Self {
            periods: Windows::DEFAULT_PERIODS,
        }
    }
}

impl WindowOptions {
    /// Window length `>= 1` in forcing periods.
    pub fn with_periods(mut self, periods: usize) -> Result<Self, PipelineError> {
        Windows::builder(&probe_clock()).periods(periods).build()?;
        self.periods = periods;
        Ok(self)
    }

    /// The window length in forcing periods.
    pub fn periods(&self) -> usize {
        self.periods
    }

    /// The windows of `record` (checked against its clock).
    pub fn windows(&self, record: &Record<'_>) -> Result<Windows, PipelineError> {
        Ok(Windows::builder(record.clock())
            .periods(self.periods)
            .domain(record.domain())
            .build()?)
    }
}

/// Where the simulations of the validation start (before their transient).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum InitialState {
    /// The record's first sample, at rest.
    FirstSample,
    /// A given state `(x, x')`.
    Given {
        /// Position.
        x: f64,
        /// Velocity.
        v: f64,
    },
}

/// Whether each model is also compared with the record itself.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RecordComparison {
    /// No comparison with the record (e.g. when the true system is known and serves instead).
    None,
    /// The model is simulated from the validation's initial state and sampled like the record, for
    /// `periods` forcing periods but no more than the record's length (or 50 periods if the record
    /// is shorter); its section in delay coordinates at the forcing's phase 0 is compared with the
    /// record's by the energy distance.
    DelaySection {
        /// Forcing periods simulated.
        periods: usize,
    },
}

/// Options of the validation, checked when set (and against the record when the pipeline is
/// built).
///
/// Defaults: Poincaré sections of 2000 forcing periods and the Lyapunov exponent over 2000, both
/// from the record's first sample at rest, and the comparison with the record in delay
/// coordinates over 2000 periods (`hbid report`'s defaults).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ValidationOptions {
    section_points: usize,
    lyapunov_periods: usize,
    initial: InitialState,
    comparison: RecordComparison,
}

impl Default for ValidationOptions {
    fn default() -> Self {
        Self {
            section_points: Self::DEFAULT_PERIODS,
            lyapunov_periods: Self::DEFAULT_PERIODS,
            initial: InitialState::FirstSample,
            comparison: RecordComparison::DelaySection {
                periods: Self::DEFAULT_PERIODS,
            },
        }
    }
}

impl ValidationOptions {
    /// Default forcing periods of each measurement.
    pub const DEFAULT_PERIODS: usize = 2000;

    /// Points `>= 1` of each Poincaré section (one per forcing period).
    pub fn with_section_points(mut self, points: usize) -> Result<Self, PipelineError> {
        SimulationConfig::paper().with_samples(points)?;
        self.section_points = points;
        Ok(self)
    }

    /// Forcing periods `>= 1` of the Lyapunov exponent.
    pub fn with_lyapunov_periods(mut self, periods: usize) -> Result<Self, PipelineError> {
        LyapunovConfig::default().with_periods(periods)?;
        self.lyapunov_periods = periods;
        Ok(self)
    }

    /// Where the simulations start (a given state must be finite).
    pub fn with_initial(mut self, initial: InitialState) -> Result<Self, PipelineError> {
        if let InitialState::Given { x, v } = initial {
            SimulationConfig::paper().with_initial(x, v)?;
        }
        self.initial = initial;
        Ok(self)
    }

    /// Whether and how long each model is compared with the record (at least one period).
    pub fn with_record_comparison(mut self, comparison: RecordComparison) -> Result<Self, PipelineError> {
        if let RecordComparison::DelaySection { periods } = comparison {
            SimulationConfig::paper().with_samples(periods)?;
        }
        self.comparison = comparison;
        Ok(self)
    }

    /// Measures `system` as every model of `record` is measured ([`check_model`] with this
    /// section, Lyapunov exponent and initial state, on the record's forcing period and domain): a
    /// reference system, such as the true one, is then measured alike.
    pub fn check<S: SecondOrderSystem + Sync>(
        &self,
        system: &S,
        record: &Record<'_>,
    ) -> Result<ModelCheck, PipelineError> {
        Ok(check_model(system, &self.check_config(record)?)?)
    }

    fn initial_state(&self, record: &Record<'_>) -> (f64, f64) {
        match self.initial {
            InitialState::FirstSample => (record.first_sample(), 0.0),
            InitialState::Given { x, v } => (x, v),
        }
    }

    fn check_config(&self, record: &Record<'_>) -> Result<CheckConfig, PipelineError> {
        let (x0, v0) = self.initial_state(record);
        Ok(CheckConfig::new(
            record.clock.drive_period(),
            record.domain,
            self.section_points,
            self.lyapunov_periods,
        )?
        .with_initial(x0, v0)?)
    }

    /// The simulation of a model sampled like the record, for the comparison in delay coordinates.
    fn comparison_config(&self, record: &Record<'_>) -> Result<Option<SimulationConfig>, PipelineError> {
        let RecordComparison::DelaySection { periods } = self.comparison else {
            return Ok(None);
        };
        let p = record.samples_per_period;
        let (x0, v0) = self.initial_state(record);
        let samples = periods.saturating_mul(p).min(record.samples.len().max(50 * p));
        Ok(Some(
            SimulationConfig::paper()
                .with_drive_period(record.clock.drive_period())?
                .with_samples_per_period(p)?
                .with_samples(samples)?
                .with_initial(x0, v0)?,
        ))
    }
}

/// Everything the pipeline does, and on what. Its public fields are options already checked
/// when set; [`Pipeline::new`] checks them against the record.
#[derive(Debug, Default)]
pub struct PipelineOptions {
    /// The delay and the embedding dimension.
    pub embed: EmbedOptions,
    /// The close-return search.
    pub search: SearchOptions,
    /// The plain windows of the weak form.
    pub windows: WindowOptions,
    /// The models to identify, in this order (default: none).
    pub models: Vec<ModelSpec>,
    /// The validation of every model.
    pub validation: ValidationOptions,
    /// The valid prediction time of every model on windows of the record (default: measured).
    pub prediction: PredictionOptions,
}

/// The stage that starts, as reported to the pipeline's progress callback.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Stage {
    /// Delay and embedding dimension.
    Embed,
    /// Close returns (and windows).
    Segments,
    /// The identification of model `model` (its index in [`PipelineOptions::models`]).
    Identify {
        /// Index of the model.
        model: usize,
        /// Its method.
        method: Method,
    },
    /// The validation of model `model` (the record's own section is taken before the first).
    Validate {
        /// Index of the model.
        model: usize,
        /// Its method.
        method: Method,
    },
}

/// What the delay and embedding stage found.
#[derive(Debug, Clone, PartialEq)]
pub struct Embedded {
    /// The average mutual information against lag, from lag 0.
    pub ami: AmiCurve,
    /// The delay of every later stage: the one given, or the first minimum of the AMI.
    pub delay: usize,
    /// False nearest neighbours with that delay, in the record's metric.
    pub fnn: FnnResult,
    /// The same in the compared metric, if one was asked for.
    pub fnn_compared: Option<FnnResult>,
}

/// The segments of each method.
#[derive(Debug, Clone, PartialEq)]
pub struct Segments {
    /// The close-return segments, grouped into distinct orbits: the segments of [`Method::Upo`].
    pub catalogue: Catalogue,
    /// The plain windows of [`Method::Windowed`], when a model asks for them.
    pub windows: Option<Vec<Segment>>,
}

impl Segments {
    /// The segments that `method` identifies on (none for windows not computed).
    pub fn of(&self, method: Method) -> &[Segment] {
        match method {
            Method::Upo => self.catalogue.segments(),
            Method::Windowed => self.windows.as_deref().unwrap_or(&[]),
        }
    }
}

/// A section in delay coordinates `(x_n, x_{n+delay})`, once per forcing period at its phase 0,
/// and an energy distance.
#[derive(Debug, Clone, PartialEq)]
pub struct DelaySection {
    /// The points of the section.
    pub points: Vec<(f64, f64)>,
    /// For the record, the energy distance between the sections of its two halves (the floor: what
    /// one attractor gives with this many points); for a model, the energy distance of its section
    /// to the record's. `None` for sections of fewer than two points.
    pub distance: Option<f64>,
}

/// What the validation measured of one model.
#[derive(Debug, Clone, PartialEq)]
pub struct Validation {
    /// Poincaré section, Lyapunov exponent, period-1 orbits and whirling fraction.
    pub check: ModelCheck,
    /// The comparison with the record, if asked for.
    pub section: Option<DelaySection>,
    /// The valid prediction time on windows of the record, in Lyapunov times of the model's own
    /// exponent too, if asked for.
    pub prediction: Option<PredictionTimes>,
}

/// What the validation measured: the record's own section and each model.
#[derive(Debug)]
pub struct Validations {
    /// The record's section in delay coordinates and its floor, if a comparison was asked for.
    pub record: Option<DelaySection>,
    /// Each model's validation, in the order of the models: what it measured, or why the model
    /// cannot be run freely ([`PipelineError::Validation`], the model's own failure: it blows up,
    /// leaves the floating-point range or its mass matrix turns singular). One model's failure
    /// leaves the others' validations standing.
    pub models: Vec<Result<Validation, PipelineError>>,
}

impl Validations {
    /// Every model's validation, or the first model's failure (in the models' order).
    pub fn all(self) -> Result<Vec<Validation>, PipelineError> {
        self.models.into_iter().collect()
    }
}

/// Everything [`Pipeline::run`] found.
#[derive(Debug)]
pub struct Outcome {
    /// Delay and embedding dimension.
    pub embedded: Embedded,
    /// The segments of each method.
    pub segments: Segments,
    /// The identified models, in the order of [`PipelineOptions::models`].
    pub models: Vec<Identification>,
    /// Their validation.
    pub validation: Validations,
}

/// The analysis of one record, its options checked against it.
#[derive(Debug)]
pub struct Pipeline<'a> {
    record: Record<'a>,
    embed: EmbedOptions,
    search: SearchOptions,
    windows: Windows,
    setups: Vec<Setup>,
    validation: ValidationOptions,
    prediction: PredictionOptions,
}

impl<'a> Pipeline<'a> {
    /// The pipeline on `record`: every option is checked against it here, before any work (the
    /// search with the given delay or 1, every model's parameters on the record's clock, the
    /// validation's simulations).
    pub fn new(record: Record<'a>, options: PipelineOptions) -> Result<Self, PipelineError> {
        let setups = options
            .models
            .into_iter()
            .map(|spec| spec.setup(record.clock()))
            .collect::<Result<Vec<_>, _>>()?;
        options
            .search
            .close_returns(&record, options.embed.delay.unwrap_or(1))?;
        let windows = options.windows.windows(&record)?;
        options.validation.check_config(&record)?;
        options.validation.comparison_config(&record)?;
        options.prediction.check(&record)?;
        Ok(Self {
            record,
            embed: options.embed,
            search: options.search,
            windows,
            setups,
            validation: options.validation,
            prediction: options.prediction,
        })
    }

    /// The record.
    pub fn record(&self) -> &Record<'a> {
        &self.record
    }

    /// The setups of the models, in order.
    pub fn setups(&self) -> &[Setup] {
        &self.setups
    }

    /// Every stage in order, calling `progress` as each starts.
    pub fn run(&self, mut progress: impl FnMut(Stage)) -> Result<Outcome, PipelineError> {
        progress(Stage::Embed);
        let embedded = self.embed()?;
        progress(Stage::Segments);
        let segments = self.segments(&embedded)?;
        let models = self.identify(&segments, &mut progress)?;
        let validation = self.validate(&embedded, &models, &mut progress)?;
        Ok(Outcome {
            embedded,
            segments,
            models,
            validation,
        })
    }

    /// The average mutual information and the delay, and false nearest neighbours with it.
    pub fn embed(&self) -> Result<Embedded, PipelineError> {
        let (x, metric) = (self.record.longest_piece(), self.record.domain);
        let params = self.embed.ami_params(metric, self.record.samples_per_period)?;
        let ami = average_mutual_information(x, &params).map_err(|e| {
            PipelineError::delay_search(
                e,
                self.record.samples_per_period,
                self.record.pieces().len(),
                // The curve is drawn whether or not the delay is given.
                None,
            )
        })?;
        let delay = match self.embed.delay {
            Some(delay) => delay,
            None => ami.delay()?,
        };
        let fnn = false_nearest_neighbours(x, &self.embed.fnn_params(metric, delay)?)?;
        let fnn_compared = match self.embed.compared_metric {
            Some(other) => Some(false_nearest_neighbours(
                x,
                &self.embed.fnn_params(other, delay)?,
            )?),
            None => None,
        };
        Ok(Embedded {
            ami,
            delay,
            fnn,
            fnn_compared,
        })
    }

    /// The close-return catalogue with the delay found, and the windows if a model needs them.
    pub fn segments(&self, embedded: &Embedded) -> Result<Segments, PipelineError> {
        let (x, pieces) = (self.record.samples, self.record.pieces());
        let catalogue = self
            .search
            .close_returns(&self.record, embedded.delay)?
            .catalogue_pieces(x, pieces)
            .map_err(|e| PipelineError::orbits(e, self.record.samples_per_period, pieces.len()))?;
        let windows = if self.setups.iter().any(|s| s.method() == Method::Windowed) {
            Some(self.windows.windows_pieces(x, pieces).map_err(|e| {
                PipelineError::windows(
                    e,
                    || format!("{} drive periods", self.windows.periods()),
                    pieces.len(),
                )
            })?)
        } else {
            None
        };
        Ok(Segments { catalogue, windows })
    }

    /// Identifies every model on the segments of its method, calling `progress` as each starts.
    pub fn identify(
        &self,
        segments: &Segments,
        mut progress: impl FnMut(Stage),
    ) -> Result<Vec<Identification>, PipelineError> {
        self.setups
            .iter()
            .enumerate()
            .map(|(model, setup)| {
                let method = setup.method();
                progress(Stage::Identify { model, method });
                let segments = segments.of(method);
                setup.identify(self.record.samples, segments).map_err(|source| {
                    PipelineError::Identification {
                        method,
                        segments: segments.len(),
                        source,
                    }
                })
            })
            .collect()
    }

    /// Validates every model (`models` in the order of the setups, as [`Pipeline::identify`]
    /// returns them), the models side by side on rayon's threads. `progress` is called on this
    /// thread, in the setups' order: model `i`'s stage when every model before it is done (the
    /// first at once). A model whose free run cannot go on has its [`PipelineError::Validation`]
    /// in its place of [`Validations::models`], beside the others' validations; any other error
    /// (the first in the models' order, as a serial loop would meet it) is returned.
    pub fn validate(
        &self,
        embedded: &Embedded,
        models: &[Identification],
        mut progress: impl FnMut(Stage),
    ) -> Result<Validations, PipelineError> {
        let record = &self.record;
        let (p, domain, delay) = (record.samples_per_period, record.domain, embedded.delay);
        let comparison = self.validation.comparison_config(record)?;
        // The record's own section at the forcing's phase 0 (t0 + offset·h ≡ 0 mod T), and the
        // distance between its two halves: what one attractor gives.
        let record_section = comparison.as_ref().map(|_| {
            let clock = record.clock;
            let offset =
                ((-clock.start_time()).rem_euclid(clock.drive_period()) / clock.step()).round() as usize % p;
            let (points, embedded) = delay_section(record.samples, p, offset, delay, domain);
            let half = embedded.len() / 2;
            let floor = energy_distance(&embedded[..half], &embedded[half..]);
            (
                DelaySection {
                    points,
                    distance: floor,
                },
                embedded,
            )
        });
        let check = self.validation.check_config(record)?;
        let one = |ident: &Identification| -> Result<Validation, PipelineError> {
            let measured = check_model(&ident.model, &check)?;
            let section = match (&comparison, &record_section) {
                (Some(config), Some((_, record_embedded))) => {
                    let sim = simulate(&ident.model, config)?;
                    let sim_x = match domain {
                        Domain::Circle => sim.wrapped(),
                        Domain::Line => sim.theta,
                    };
                    let (points, model_embedded) = delay_section(&sim_x, p, 0, delay, domain);
                    Some(DelaySection {
                        points,
                        distance: energy_distance(record_embedded, &model_embedded),
                    })
                }
                _ => None,
            };
            let prediction =
                self.prediction
                    .measure(&ident.model, record, Some(measured.lyapunov.per_unit_time))?;
            Ok(Validation {
                check: measured,
                section,
                prediction,
            })
        };
        // The models side by side (each validation is a long serial run, and they are
        // independent: the numbers do not depend on the order). `progress` hears the stages on
        // this thread, in the setups' order: a model's when every model before it is done.
        let stage = |model: usize| Stage::Validate {
            model,
            method: self.setups[model].method(),
        };
        let count = models.len().min(self.setups.len());
        let mut results = Vec::with_capacity(count);
        std::thread::scope(|scope| {
            let (send, receive) = std::sync::mpsc::channel();
            let one = &one;
            scope.spawn(move || {
                models[..count]
                    .par_iter()
                    .enumerate()
                    .for_each_with(send, |send, (model, ident)| {
                        let result = one(ident).map_err(|e| match e {
                            // A free run that cannot go on is the model's, whatever the stage.
                            PipelineError::Simulation(
                                source @ (SimError::StepSizeTooSmall { .. }
                                | SimError::TooManySteps { .. }
                                | SimError::NonFinite { .. }
                                | SimError::SingularMass { .. }),
                            ) => PipelineError::Validation {
                                method: self.setups[model].method(),
                                warning: ident.warning.clone(),
                                source,
                            },
                            other => other,
                        });
                        // The receiver lives until every model is in: a send cannot fail.
                        let _ = send.send((model, result));
                    });
            });
            let mut finished = vec![false; count];
            let mut next = 0;
            if count > 0 {
                progress(stage(0));
            }
            for (model, result) in receive {
                finished[model] = true;
                results.push((model, result));
                while next < count && finished[next] {
                    next += 1;
                    if next < count {
                        progress(stage(next));
                    }
                }
            }
        });
        results.sort_by_key(|&(model, _)| model);
        let mut validations = Vec::with_capacity(results.len());
        for (_, result) in results {
            match result {
                Err(e) if !matches!(e, PipelineError::Validation { .. }) => return Err(e),
                kept => validations.push(kept),
            }
        }
        Ok(Validations {
            record: record_section.map(|(section, _)| section),
            models: validations,
        })
    }
}

/// Delay-coordinate section of a wrapped or linear record: `(x_n, x_{n+delay})` at the samples
/// `n ≡ offset (mod P)` where both are finite, and its embedding for the energy distance (`(cos, sin)` of each angle, or
/// the raw pair on the line).
fn delay_section(
    x: &[f64],
    p: usize,
    offset: usize,
    delay: usize,
    domain: Domain,
) -> (Vec<(f64, f64)>, Vec<[f64; 4]>) {
    let pairs: Vec<(f64, f64)> = (offset..x.len().saturating_sub(delay))
        .step_by(p.max(1))
        .map(|n| (x[n], x[n + delay]))
        // The gaps of a record in pieces are NaN: a pair that reaches into one is no point.
        .filter(|(a, b)| a.is_finite() && b.is_finite())
        .collect();
    let embedded = pairs
        .iter()
        .map(|&(a, b)| match domain {
            Domain::Circle => [a.cos(), a.sin(), b.cos(), b.sin()],
            Domain::Line => [a, b, 0.0, 0.0],
        })
        .collect();
    (pairs, embedded)
}
