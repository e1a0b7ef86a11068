use std::f64::consts::{LN_2, TAU};

use rayon::prelude::*;

use crate::metric::Metric;
use crate::{Domain, EmbeddingError, check_finite};

/// The unit of the mutual information.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum InfoUnit {
    /// Natural logarithm (the default, as TISEAN's `mutual`).
    #[default]
    Nats,
    /// Base-2 logarithm (as written in paper eq. 18): nats divided by ln 2.
    Bits,
}

/// Parameters of the average mutual information, validated at construction.
///
/// Defaults: 16 boxes, lags `0..=40`, nats.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AmiParams {
    metric: Domain,
    bins: usize,
    max_lag: usize,
    unit: InfoUnit,
}

impl AmiParams {
    /// Default number of boxes.
    pub const DEFAULT_BINS: usize = 16;
    /// Default largest lag.
    pub const DEFAULT_MAX_LAG: usize = 40;
    /// Largest number of boxes accepted (the joint histogram holds `bins²` counters).
    pub const MAX_BINS: usize = 1024;

    /// Defaults for a record compared with `metric`.
    pub fn new(metric: Domain) -> Self {
        Self {
            metric,
            bins: Self::DEFAULT_BINS,
            max_lag: Self::DEFAULT_MAX_LAG,
            unit: InfoUnit::Nats,
        }
    }

    /// Sets the number of equal boxes, `2 ≤ bins ≤ 1024`.
    pub fn with_bins(mut self, bins: usize) -> Result<Self, EmbeddingError> {
        if !(2..=Self::MAX_BINS).contains(&bins) {
            return Err(EmbeddingError::InvalidParameter {
                name: "bins",
                value: bins as f64,
                why: "must be between 2 and 1024",
            });
        }
        self.bins = bins;
        Ok(self)
    }

    /// Sets the largest lag `L ≥ 1` (it must also be shorter than the record).
    pub fn with_max_lag(mut self, max_lag: usize) -> Result<Self, EmbeddingError> {
        if max_lag == 0 {
            return Err(EmbeddingError::InvalidParameter {
                name: "max_lag",
                value: 0.0,
                why: "must be at least 1",
            });
        }
        self.max_lag = max_lag;
        Ok(self)
    }

    /// Sets the unit of the result.
    pub fn with_unit(mut self, unit: InfoUnit) -> Self {
        self.unit = unit;
        self
    }

    /// The metric.
    pub fn metric(&self) -> Domain {
        self.metric
    }

    /// The number of boxes.
    pub fn bins(&self) -> usize {
        self.bins
    }

    /// The largest lag.
    pub fn max_lag(&self) -> usize {
        self.max_lag
    }

    /// The unit.
    pub fn unit(&self) -> InfoUnit {
        self.unit
    }
}

/// The average mutual information `I(τ)` for lags `τ = 0..=L`.
#[derive(Debug, Clone, PartialEq)]
pub struct AmiCurve {
    /// `I(τ)` at index `τ`.
    pub values: Vec<f64>,
    /// Unit of the values.
    pub unit: InfoUnit,
}

impl AmiCurve {
    /// The first minimum: the smallest lag `τ ≥ 1` with `I(τ) < I(τ − 1)` such that the first
    /// value after `τ` that differs from `I(τ)` is larger (`I(τ + 1) > I(τ)` in the usual case;
    /// on a flat bottom the left end is taken). `None` if no lag up to `L − 1` qualifies (the curve
    /// still falls at `L`, or never falls).
    pub fn first_minimum(&self) -> Option<usize> {
        let v = &self.values;
        (1..v.len())
            .find(|&t| v[t] < v[t - 1] && v[t + 1..].iter().find(|&&w| w != v[t]).is_some_and(|&w| w > v[t]))
    }

    /// The delay `T_d` (paper section 3.1): the [`AmiCurve::first_minimum`].
    ///
    /// # Errors
    /// [`EmbeddingError::NoFirstMinimum`] when there is none.
    pub fn delay(&self) -> Result<usize, EmbeddingError> {
        self.first_minimum().ok_or(EmbeddingError::NoFirstMinimum {
            max_lag: self.values.len() - 1,
        })
    }
}

/// The average mutual information of `x` with itself `τ` samples later, paper eq. 18, for
/// `τ = 0..=L`.
///
/// The values are put in `B` equal boxes: over `[min x, max x]` with the linear metric (box
/// `⌊B (x − min)/(max − min)⌋`, the maximum going into the last box), over the whole circle
/// `[−π, π)` with the circle metric (box `⌊B (wrap(x) + π)/2π⌋`). For lag `τ` the pairs
/// `(x_i, x_{i+τ})`, `i = 0..N−τ`, give the joint frequencies `p_ij`, and the marginals are
/// those of the same pairs, so that
///
/// `I(τ) = Σ_ij p_ij ln(p_ij / (p_i p_j))`
///
/// with `0 ln 0 = 0`. `I(0)` is the entropy of the boxed record.
///
/// # Errors
/// Non-finite samples, `L ≥ N`, or (linear metric) a constant record.
pub fn average_mutual_information(x: &[f64], params: &AmiParams) -> Result<AmiCurve, EmbeddingError> {
    check_finite(x)?;
    let (bins, max_lag) = (params.bins, params.max_lag);
    if max_lag >= x.len() {
        return Err(EmbeddingError::LagTooLarge {
            max_lag,
            len: x.len(),
        });
    }
    let boxes = box_indices(x, params.metric, bins)?;
    let scale = match params.unit {
        InfoUnit::Nats => 1.0,
        InfoUnit::Bits => 1.0 / LN_2,
    };
    let values = (0..=max_lag)
        .into_par_iter()
        .map_init(
            || (vec![0u32; bins * bins], vec![0u32; bins], vec![0u32; bins]),
            |(joint, rows, cols), lag| scale * mutual_information(&boxes, lag, bins, joint, rows, cols),
        )
        .collect();
    Ok(AmiCurve {
        values,
        unit: params.unit,
    })
}

/// Box index of every sample.
fn box_indices(x: &[f64], metric: Domain, bins: usize) -> Result<Vec<u16>, EmbeddingError> {
    let top = bins - 1;
    let b = bins as f64;
    let boxes = match metric {
        Domain::Line => {
            let (lo, hi) = x.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            });
            let range = hi - lo;
            if range <= 0.0 {
                return Err(EmbeddingError::ConstantSignal { value: lo });
            }
            x.iter()
                .map(|&v| (((v - lo) / range * b) as usize).min(top) as u16)
                .collect()
        }
        Domain::Circle => x
            .iter()
            .map(|&v| ((metric.tree_coordinate(v) / TAU * b) as usize).min(top) as u16)
            .collect(),
    };
    Ok(boxes)
}

/// `I(lag)` in nats from the box indices, with caller-owned counters.
fn mutual_information(
    boxes: &[u16],
    lag: usize,
    bins: usize,
    joint: &mut [u32],
    rows: &mut [u32],
    cols: &mut [u32],
) -> f64 {
    joint.fill(0);
    let pairs = boxes.len() - lag;
    for (&a, &b) in boxes[..pairs].iter().zip(&boxes[lag..]) {
        joint[a as usize * bins + b as usize] += 1;
    }
    rows.fill(0);
    cols.fill(0);
    for (i, row) in joint.chunks_exact(bins).enumerate() {
        for (j, &c) in row.iter().enumerate() {
            rows[i] += c;
            cols[j] += c;
        }
    }
    // Σ p_ij ln(p_ij / (p_i p_j)) with p = count / n: Σ (c_ij / n) ln(c_ij n / (r_i c_j)).
    let n = pairs as f64;
    let mut sum = 0.0;
    for (i, row) in joint.chunks_exact(bins).enumerate() {
        for (j, &c) in row.iter().enumerate() {
            if c > 0 {
                let c = f64::from(c);
                sum += c * (c * n / (f64::from(rows[i]) * f64::from(cols[j]))).ln();
            }
        }
    }
    sum / n
}
