//! The embed and orbit requests: the delay (first minimum of the average mutual information),
//! the embedding dimension (false nearest neighbours) and the unstable periodic orbits by close
//! returns, as `hbid embed` and `hbid upos` (and Python's `hbid.embed`, `hbid.upos`) run them.

use std::collections::BTreeMap;

use circle_signal::Domain;
use embedding::{
    AmiCurve, AmiParams, EmbeddingError, FnnParams, FnnResult, average_mutual_information,
    false_nearest_neighbours,
};
use hb_record::prepare::Data;
use serde::{Deserialize, Serialize, Serializer};
use upo_search::{Catalogue, CloseReturns};

use crate::error::RunError;
use crate::observe::{Observer, Stage};
use crate::options::{OptionError, from_object, optional_text};
use crate::pipeline::{EmbedOptions as Lags, Record, SearchOptions};
use crate::record::{RecordOptions, RecordSummary, Source, load};

/// The largest lag of the mutual information: the one given, or two drive periods (at least
/// [`AmiParams::DEFAULT_MAX_LAG`]), so that the search reaches as far in time at any sampling
/// rate.
fn max_lag(data: &Data, given: Option<usize>) -> usize {
    given.unwrap_or_else(|| Lags::default().max_lag(data.p))
}

/// What a user of the orbit search gives where the record is too short for the delay's search.
pub(crate) const DELAY_REMEDY: Option<&str> = Some("the delay itself («delay»)");

/// The mutual-information curve of the longest piece of `data` in `metric` and its first
/// minimum; `remedy` is the option the caller's user can give where the record is too short for
/// the largest lag (`a smaller «max_lag»`, `the delay itself («delay»)`), if any.
pub(crate) fn first_minimum(
    data: &Data,
    metric: Domain,
    given_max_lag: Option<usize>,
    bins: Option<usize>,
    remedy: Option<&'static str>,
) -> Result<(AmiCurve, usize), RunError> {
    let lag = max_lag(data, given_max_lag);
    let params = AmiParams::new(metric)
        .with_max_lag(lag)
        .map_err(|e| OptionError::checked("max_lag", lag, &e))?;
    let params = match bins {
        Some(b) => params
            .with_bins(b)
            .map_err(|e| OptionError::checked("bins", b, &e))?,
        None => params,
    };
    let curve = average_mutual_information(data.longest(), &params)
        .map_err(|e| crate::pipeline::PipelineError::delay_search(e, data.p, data.pieces.len(), remedy))?;
    let delay = curve.delay().map_err(RunError::NoDelay)?;
    Ok((curve, delay))
}

/// The options of the close-return search and the delay, shared by `identify`, `upos` and
/// `report`. Defaults: the paper's (a tolerance of 3 % of the data's span, periods 1 to 16, delay
/// vectors of dimension 2), the delay the first minimum of the average mutual information.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct OrbitOptions {
    /// Close-return tolerance as a fraction of the span of the data (2π for an angle), in
    /// `(0, 0.5)`.
    pub tolerance: f64,
    /// Longest orbit period searched, in drive periods.
    pub max_period: usize,
    /// Dimension of the delay vectors compared.
    pub dim: usize,
    /// The delay in samples (default: the first minimum of the average mutual information).
    pub delay: Option<usize>,
}

impl Default for OrbitOptions {
    fn default() -> Self {
        Self {
            tolerance: CloseReturns::DEFAULT_TOLERANCE,
            max_period: CloseReturns::DEFAULT_MAX_PERIOD,
            dim: CloseReturns::DEFAULT_DIMENSION,
            delay: None,
        }
    }
}

impl OrbitOptions {
    /// The search's options, checked.
    pub fn search(&self) -> Result<SearchOptions, OptionError> {
        let tolerance = SearchOptions::default()
            .with_tolerance(self.tolerance)
            .map_err(|e| OptionError::checked("tolerance", self.tolerance, &e))?;
        let max_period = tolerance
            .with_max_period(self.max_period)
            .map_err(|e| OptionError::checked("max_period", self.max_period, &e))?;
        max_period
            .with_dimension(self.dim)
            .map_err(|e| OptionError::checked("dim", self.dim, &e))
    }

    /// Checks the delay (at least one sample).
    pub fn check_delay(&self) -> Result<(), OptionError> {
        match self.delay {
            Some(0) => Err(OptionError::value("delay", 0, "must be at least 1 sample")),
            _ => Ok(()),
        }
    }
}

/// Every option of `hbid embed`, by the names of the command line and Python. Defaults: lags up to
/// two drive periods, 16 boxes, dimensions up to 8, the signal's own metric, no Theiler window.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct EmbedRequest {
    /// The record.
    #[serde(flatten)]
    pub record: RecordOptions,
    /// Largest lag of the average mutual information (default: two drive periods, at least 40).
    pub max_lag: Option<usize>,
    /// Equal boxes of the mutual-information histogram.
    pub bins: usize,
    /// Largest embedding dimension tested by false nearest neighbours.
    pub max_dim: usize,
    /// The distance between samples: `circle` or `linear` (plain differences, as classic tools
    /// do); default: the signal's.
    #[serde(with = "optional_text")]
    pub metric: Option<Domain>,
    /// Neighbours closer in time than this many samples are not counted.
    pub theiler: usize,
}

impl Default for EmbedRequest {
    fn default() -> Self {
        Self {
            record: RecordOptions::default(),
            max_lag: None,
            bins: AmiParams::DEFAULT_BINS,
            max_dim: FnnParams::DEFAULT_MAX_DIM,
            metric: None,
            theiler: 0,
        }
    }
}

impl EmbedRequest {
    /// Checks the options that do not depend on the record.
    pub fn check(&self) -> Result<(), OptionError> {
        self.record.check()?;
        AmiParams::new(Domain::Circle)
            .with_bins(self.bins)
            .map_err(|e| OptionError::checked("bins", self.bins, &e))?;
        if let Some(lag) = self.max_lag {
            AmiParams::new(Domain::Circle)
                .with_max_lag(lag)
                .map_err(|e| OptionError::checked("max_lag", lag, &e))?;
        }
        FnnParams::new(Domain::Circle, 1)
            .and_then(|p| p.with_max_dim(self.max_dim))
            .map_err(|e| OptionError::checked("max_dim", self.max_dim, &e))?;
        Ok(())
    }

    /// A request from a JSON object of option names, unknown names refused, checked.
    pub fn from_json(value: serde_json::Value) -> Result<Self, OptionError> {
        let request: Self = from_object(value)?;
        request.check()?;
        Ok(request)
    }
}

/// The delay and the embedding dimension of a record.
#[derive(Debug, Clone, PartialEq)]
pub struct EmbedReport {
    /// The metric used.
    pub metric: Domain,
    /// The mutual information against lag, from lag 0.
    pub ami: AmiCurve,
    /// Its first minimum.
    pub delay: usize,
    /// False nearest neighbours with that delay.
    pub fnn: FnnResult,
    /// The record as analysed.
    pub record: RecordSummary,
}

/// The delay and the embedding dimension of the record of `source`.
pub fn embed(
    source: Source<'_>,
    request: &EmbedRequest,
    observer: &mut dyn Observer,
) -> Result<EmbedReport, RunError> {
    request.check()?;
    let data = load(source, &request.record, request.record.drive(false), observer)?;
    let metric = request.metric.unwrap_or(data.domain);
    observer.stage(Stage::Delay);
    let (ami, delay) = first_minimum(
        &data,
        metric,
        request.max_lag,
        Some(request.bins),
        Some("a smaller «max_lag»"),
    )?;
    observer.stage(Stage::Embed);
    let params = FnnParams::new(metric, delay)
        .and_then(|p| p.with_max_dim(request.max_dim))
        .map_err(|e| OptionError::checked("max_dim", request.max_dim, &e))?
        .with_theiler_window(request.theiler);
    let fnn = false_nearest_neighbours(data.longest(), &params)
        .map_err(|e: EmbeddingError| RunError::Pipeline(crate::pipeline::PipelineError::Embedding(e)))?;
    Ok(EmbedReport {
        metric,
        ami,
        delay,
        fnn,
        record: RecordSummary::of(&data),
    })
}

/// The JSON of `hbid embed --json`.
#[derive(Serialize)]
struct EmbedJson<'a> {
    delay: usize,
    ami: &'a [f64],
    fnn: Vec<f64>,
    embedding_dimension: Option<usize>,
    fraction_threshold: f64,
    metric: &'static str,
    record: &'a RecordSummary,
}

impl Serialize for EmbedReport {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        EmbedJson {
            delay: self.delay,
            ami: &self.ami.values,
            fnn: self.fnn.levels.iter().map(|l| l.fraction()).collect(),
            embedding_dimension: self.fnn.minimum_dimension(),
            fraction_threshold: self.fnn.fraction_threshold,
            metric: self.metric.name(),
            record: &self.record,
        }
        .serialize(s)
    }
}

/// Every option of `hbid upos`, by the names of the command line and Python.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct UposRequest {
    /// The record.
    #[serde(flatten)]
    pub record: RecordOptions,
    /// The close-return search.
    #[serde(flatten)]
    pub orbits: OrbitOptions,
}

impl UposRequest {
    /// Checks the options that do not depend on the record.
    pub fn check(&self) -> Result<SearchOptions, OptionError> {
        self.record.check()?;
        self.orbits.check_delay()?;
        self.orbits.search()
    }

    /// A request from a JSON object of option names, unknown names refused, checked.
    pub fn from_json(value: serde_json::Value) -> Result<Self, OptionError> {
        let request: Self = from_object(value)?;
        request.check()?;
        Ok(request)
    }
}

/// The unstable periodic orbits of a record.
#[derive(Debug, Clone, PartialEq)]
pub struct UposReport {
    /// The delay of the delay vectors compared.
    pub delay: usize,
    /// The segments found, grouped into distinct orbits.
    pub catalogue: Catalogue,
    /// The record as analysed.
    pub record: RecordSummary,
}

/// The unstable periodic orbits of the record of `source`, by close returns.
pub fn upos(
    source: Source<'_>,
    request: &UposRequest,
    observer: &mut dyn Observer,
) -> Result<UposReport, RunError> {
    let search = request.check()?;
    let data = load(source, &request.record, request.record.drive(false), observer)?;
    let record = Record::from_data(&data)?;
    search.close_returns(&record, request.orbits.delay.unwrap_or(1))?;
    let delay = match request.orbits.delay {
        Some(d) => d,
        None => {
            observer.stage(Stage::Delay);
            first_minimum(&data, data.domain, None, None, DELAY_REMEDY)?.1
        }
    };
    observer.stage(Stage::Segments);
    let catalogue = search
        .close_returns(&record, delay)?
        .catalogue_pieces(&data.x, &data.pieces)
        .map_err(|e| crate::pipeline::PipelineError::orbits(e, data.p, data.pieces.len()))?;
    Ok(UposReport {
        delay,
        catalogue,
        record: RecordSummary::of(&data),
    })
}

#[derive(Serialize)]
struct OrbitJson {
    period: usize,
    start: usize,
    error: f64,
}

/// The JSON of `hbid upos --json`.
#[derive(Serialize)]
struct UposJson<'a> {
    segments: usize,
    by_period: BTreeMap<String, usize>,
    distinct_orbits: usize,
    distinct_by_period: BTreeMap<String, usize>,
    orbits: Vec<OrbitJson>,
    orbit_of_segment: Vec<usize>,
    delay: usize,
    tolerance: f64,
    record: &'a RecordSummary,
}

impl Serialize for UposReport {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let c = &self.catalogue;
        let counts = c.counts();
        UposJson {
            segments: c.segments().len(),
            by_period: counts
                .iter()
                .map(|n| (n.period.to_string(), n.segments))
                .collect(),
            distinct_orbits: c.orbits().len(),
            distinct_by_period: counts.iter().map(|n| (n.period.to_string(), n.orbits)).collect(),
            orbits: c
                .segments()
                .iter()
                .map(|s| OrbitJson {
                    period: s.period(),
                    start: s.start(),
                    error: s.error(),
                })
                .collect(),
            orbit_of_segment: (0..c.segments().len()).map(|i| c.orbit_of(i)).collect(),
            delay: self.delay,
            tolerance: c.tolerance(),
            record: &self.record,
        }
        .serialize(s)
    }
}
