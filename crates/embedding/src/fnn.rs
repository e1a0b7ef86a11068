use crate::{Domain, Embedding, EmbeddingError, MAX_SEARCH_DIM, check_finite, nearest_neighbours};

/// Parameters of the false-nearest-neighbour test, validated at construction.
///
/// Defaults: dimensions `1..=8`, ratio threshold 10, attractor-size threshold 2, Theiler window 0,
/// fraction threshold 0.05, no neighbour cutoff.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FnnParams {
    metric: Domain,
    delay: usize,
    max_dim: usize,
    ratio_threshold: f64,
    attractor_threshold: Option<f64>,
    theiler: usize,
    fraction_threshold: f64,
    neighbour_cutoff: Option<f64>,
}

impl FnnParams {
    /// Default largest dimension tested.
    pub const DEFAULT_MAX_DIM: usize = 8;
    /// Default threshold `R_tol` of the distance-ratio test.
    pub const DEFAULT_RATIO_THRESHOLD: f64 = 10.0;
    /// Default threshold `A_tol` of the attractor-size test (Kennel et al. 1992).
    pub const DEFAULT_ATTRACTOR_THRESHOLD: f64 = 2.0;
    /// Default fraction of false neighbours below which a dimension is enough.
    pub const DEFAULT_FRACTION_THRESHOLD: f64 = 0.05;

    /// Defaults for a record compared with `metric`, embedded with delay `delay ≥ 1` samples.
    pub fn new(metric: Domain, delay: usize) -> Result<Self, EmbeddingError> {
        if delay == 0 {
            return Err(EmbeddingError::InvalidParameter {
                name: "delay",
                value: 0.0,
                why: "must be at least 1",
            });
        }
        Ok(Self {
            metric,
            delay,
            max_dim: Self::DEFAULT_MAX_DIM,
            ratio_threshold: Self::DEFAULT_RATIO_THRESHOLD,
            attractor_threshold: Some(Self::DEFAULT_ATTRACTOR_THRESHOLD),
            theiler: 0,
            fraction_threshold: Self::DEFAULT_FRACTION_THRESHOLD,
            neighbour_cutoff: None,
        })
    }

    /// Tests dimensions `1..=max_dim`, `1 ≤ max_dim ≤ 8`.
    pub fn with_max_dim(mut self, max_dim: usize) -> Result<Self, EmbeddingError> {
        if !(1..=MAX_SEARCH_DIM).contains(&max_dim) {
            return Err(EmbeddingError::InvalidParameter {
                name: "max_dim",
                value: max_dim as f64,
                why: "must be between 1 and 8",
            });
        }
        self.max_dim = max_dim;
        Ok(self)
    }

    /// Sets `R_tol`, finite and positive.
    pub fn with_ratio_threshold(mut self, threshold: f64) -> Result<Self, EmbeddingError> {
        self.ratio_threshold = positive("ratio_threshold", threshold)?;
        Ok(self)
    }

    /// Sets `A_tol`, finite and positive; `None` switches the attractor-size test off.
    pub fn with_attractor_threshold(mut self, threshold: Option<f64>) -> Result<Self, EmbeddingError> {
        self.attractor_threshold = threshold
            .map(|t| positive("attractor_threshold", t))
            .transpose()?;
        Ok(self)
    }

    /// Sets the Theiler window `w`: neighbours `m` of `n` need `|m − n| > w`.
    pub fn with_theiler_window(mut self, theiler: usize) -> Self {
        self.theiler = theiler;
        self
    }

    /// Sets the fraction below which a dimension is taken as enough, in `(0, 1)`.
    pub fn with_fraction_threshold(mut self, threshold: f64) -> Result<Self, EmbeddingError> {
        if !(threshold > 0.0 && threshold < 1.0) {
            return Err(EmbeddingError::InvalidParameter {
                name: "fraction_threshold",
                value: threshold,
                why: "must lie strictly between 0 and 1",
            });
        }
        self.fraction_threshold = threshold;
        Ok(self)
    }

    /// Leaves out (does not count) every vector whose neighbour lies farther than
    /// `cutoff · R_A`; `None` (the default) keeps them all.
    ///
    /// TISEAN's `false_nearest` works this way, with `cutoff = 1 / R_tol` and without the
    /// attractor-size test: `with_attractor_threshold(None)?.with_neighbour_cutoff(Some(1.0 / r_tol))`
    /// reproduces its fractions.
    pub fn with_neighbour_cutoff(mut self, cutoff: Option<f64>) -> Result<Self, EmbeddingError> {
        self.neighbour_cutoff = cutoff.map(|c| positive("neighbour_cutoff", c)).transpose()?;
        Ok(self)
    }

    /// The metric.
    pub fn metric(&self) -> Domain {
        self.metric
    }

    /// The delay in samples.
    pub fn delay(&self) -> usize {
        self.delay
    }

    /// The largest dimension tested.
    pub fn max_dim(&self) -> usize {
        self.max_dim
    }

    /// `R_tol`.
    pub fn ratio_threshold(&self) -> f64 {
        self.ratio_threshold
    }

    /// `A_tol`, if the attractor-size test is on.
    pub fn attractor_threshold(&self) -> Option<f64> {
        self.attractor_threshold
    }

    /// The Theiler window.
    pub fn theiler_window(&self) -> usize {
        self.theiler
    }

    /// The fraction threshold.
    pub fn fraction_threshold(&self) -> f64 {
        self.fraction_threshold
    }

    /// The neighbour cutoff in units of `R_A`, if any.
    pub fn neighbour_cutoff(&self) -> Option<f64> {
        self.neighbour_cutoff
    }
}

fn positive(name: &'static str, value: f64) -> Result<f64, EmbeddingError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(EmbeddingError::InvalidParameter {
            name,
            value,
            why: "must be positive and finite",
        })
    }
}

/// The false-nearest-neighbour counts of one dimension `d`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FnnLevel {
    /// The dimension `d` of the vectors whose neighbours were tested.
    pub dim: usize,
    /// Vectors that have a neighbour (the denominator of the fractions).
    pub points: usize,
    /// Vectors without any admissible neighbour (left out).
    pub unmatched: usize,
    /// Vectors whose neighbour lies beyond the neighbour cutoff (left out).
    pub distant: usize,
    /// Neighbours failing the distance-ratio test.
    pub ratio_false: usize,
    /// Neighbours failing the attractor-size test (0 when it is off).
    pub size_false: usize,
    /// Neighbours failing either test: the false nearest neighbours.
    pub false_neighbours: usize,
    /// Mean distance `R_d` to the nearest neighbour.
    pub mean_distance: f64,
}

impl FnnLevel {
    /// Fraction of false nearest neighbours (either test).
    pub fn fraction(&self) -> f64 {
        self.false_neighbours as f64 / self.points as f64
    }

    /// Fraction failing the distance-ratio test.
    pub fn ratio_fraction(&self) -> f64 {
        self.ratio_false as f64 / self.points as f64
    }

    /// Fraction failing the attractor-size test.
    pub fn size_fraction(&self) -> f64 {
        self.size_false as f64 / self.points as f64
    }
}

/// False nearest neighbours for dimensions `1..=max_dim`.
#[derive(Debug, Clone, PartialEq)]
pub struct FnnResult {
    /// One entry per dimension, `levels[d − 1]` for dimension `d`.
    pub levels: Vec<FnnLevel>,
    /// `R_A`, the size of the attractor ([`spread`](crate::spread) of the record).
    pub attractor_size: f64,
    /// The fraction threshold used for [`FnnResult::minimum_dimension`].
    pub fraction_threshold: f64,
}

impl FnnResult {
    /// The minimum embedding dimension: the first `d` whose [`FnnLevel::fraction`] is below the
    /// threshold, or `None` if no tested dimension reaches it.
    pub fn minimum_dimension(&self) -> Option<usize> {
        self.levels
            .iter()
            .find(|l| l.fraction() < self.fraction_threshold)
            .map(|l| l.dim)
    }
}

/// The false-nearest-neighbour test of Kennel, Brown & Abarbanel (1992) for `d = 1..=d_max`.
///
/// The vectors tested are `S(n)`, `n = 0..M` with `M = N − d_max T_d` (the same `n` for every
/// `d`, so each has the extra coordinate `x_{n+d T_d}` even at `d_max`). For each, its nearest
/// neighbour `S(m)` in dimension `d` is found by [`nearest_neighbours`] (max norm, Theiler window
/// `w`, exact copies skipped), at distance `R_d`. With `Δ = |x_{n+d T_d} − x_{m+d T_d}|` in the
/// metric and `R_{d+1} = max(R_d, Δ)`, the neighbour is false if
///
/// - distance-ratio test: `Δ / R_d > R_tol`, or
/// - attractor-size test: `R_{d+1} / R_A > A_tol`, `R_A` the [`spread`](crate::spread) of the record.
///
/// The fraction for `d` is the false count over the vectors that have a neighbour (and, with
/// [`FnnParams::with_neighbour_cutoff`], a neighbour closer than the cutoff).
///
/// # Errors
/// Non-finite samples, a record shorter than `d_max T_d + w + 2` samples, or a dimension in
/// which no vector has a neighbour.
pub fn false_nearest_neighbours(x: &[f64], params: &FnnParams) -> Result<FnnResult, EmbeddingError> {
    check_finite(x)?;
    let (metric, delay, max_dim) = (params.metric, params.delay, params.max_dim);
    let needed = max_dim * delay + params.theiler + 2;
    if x.len() < needed {
        return Err(EmbeddingError::TooShort { len: x.len(), needed });
    }
    let points = x.len() - max_dim * delay;
    let attractor_size = crate::metric::spread(metric, x);
    let size_limit = params.attractor_threshold.map(|a| a * attractor_size);
    let distance_limit = params.neighbour_cutoff.map(|c| c * attractor_size);
    let mut levels = Vec::with_capacity(max_dim);
    for dim in 1..=max_dim {
        let vectors = Embedding::new(dim, delay)?.vectors(x)?.take(points);
        let neighbours = nearest_neighbours(&vectors, metric, params.theiler)?;
        let ahead = dim * delay;
        let mut level = FnnLevel {
            dim,
            points: 0,
            unmatched: 0,
            distant: 0,
            ratio_false: 0,
            size_false: 0,
            false_neighbours: 0,
            mean_distance: 0.0,
        };
        for (n, nb) in neighbours.iter().enumerate() {
            let Some(nb) = nb else {
                level.unmatched += 1;
                continue;
            };
            let r_d = nb.distance;
            if distance_limit.is_some_and(|limit| r_d > limit) {
                level.distant += 1;
                continue;
            }
            let extra = metric.distance(x[n + ahead], x[nb.index + ahead]);
            let ratio_false = extra > params.ratio_threshold * r_d;
            let size_false = size_limit.is_some_and(|limit| r_d.max(extra) > limit);
            level.points += 1;
            level.ratio_false += usize::from(ratio_false);
            level.size_false += usize::from(size_false);
            level.false_neighbours += usize::from(ratio_false || size_false);
            level.mean_distance += r_d;
        }
        if level.points == 0 {
            return Err(EmbeddingError::NoNeighbours { dim });
        }
        level.mean_distance /= level.points as f64;
        levels.push(level);
    }
    Ok(FnnResult {
        levels,
        attractor_size,
        fraction_threshold: params.fraction_threshold,
    })
}
