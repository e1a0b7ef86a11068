//! Isolated spikes in a record: bit errors that move one sample and leave the next one right.
//!
//! An encoder with a bit error reports one sample off by `±2^k` counts and the next one right
//! again. Left in the record, such a spike is a jump of the angular velocity and acceleration; on
//! the circle a spike near half a turn is worse, since [`unwrap`](crate::unwrap) takes the step
//! into the spike and the step out of it as steps of opposite sign modulo 2π, and the record gains
//! (or loses) a whole false turn. This module finds such spikes by a robust test and replaces them
//! by the local prediction; the test is documented on [`find_spikes`].

use std::f64::consts::{PI, TAU};

use serde::{Deserialize, Serialize};

use crate::{CircleError, Domain, wrap};

/// The standard deviation of a Gaussian over its median absolute value, `1 / Φ⁻¹(3/4)`.
const MAD_TO_SD: f64 = 1.482_602_218_505_602;

/// The relative standard deviation of the median absolute value of `N` Gaussian numbers, times
/// `√N`: `1 / (2 f(m) m)` with `m = Φ⁻¹(3/4)` the median and `f(m) = 2φ(m)` the density of the
/// absolute value there.
const MEDIAN_SPREAD: f64 = 1.166;

/// Parameters of the spike test: the threshold in robust standard deviations, the absolute floor
/// and the block length of the local scale (see [`find_spikes`] for the test).
///
/// Validated when constructed and when deserialised; every field may be left out of the
/// serialised form and takes its default.
///
/// ```
/// use circle_signal::SpikeParams;
///
/// let p = SpikeParams::new().with_threshold(8.0)?.with_quantum(std::f64::consts::TAU / 4096.0)?;
/// assert_eq!(p.threshold(), 8.0);
/// assert!(p.floor().is_some());
/// assert!(SpikeParams::new().with_threshold(-1.0).is_err());
/// # Ok::<(), circle_signal::CircleError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "SpikeParamsRaw", into = "SpikeParamsRaw")]
pub struct SpikeParams {
    threshold: f64,
    floor: Option<f64>,
    block: usize,
}

impl SpikeParams {
    /// Default threshold: 6 robust standard deviations.
    ///
    /// A Gaussian residual passes 6 standard deviations with probability `2 · 10⁻⁹`, so a record
    /// of `10⁷` noisy samples expects fewer than 0.02 false detections; 5 would expect about 6.
    /// The smooth motion alone needs it too: a noise-free whirling angle through a 4096-count
    /// encoder at 25 samples per forcing period (the whirl of the crate's test records) gets 4
    /// false detections in 10⁵ clean samples with a threshold of 5 and none with 6, and the
    /// paper's chaotic record at 25 per period has residuals up to 5 times its robust scale. The
    /// price is the smallest spike found: one of 7 robust standard deviations (64 counts of 4096
    /// at σ = 0.01 rad) is found 69 % of the time at 25 samples per period and 81–82 % at 100 and
    /// 490; 128 counts always
    /// (`cargo run --release -p circle-signal --example spike_rates`).
    pub const DEFAULT_THRESHOLD: f64 = 6.0;

    /// Default block length of the local scale, in samples: the local median is taken over three
    /// blocks, 192 residuals, which estimates a Gaussian scale to about 8 % (one standard
    /// deviation of the sample median).
    pub const DEFAULT_BLOCK: usize = 64;

    /// Shortest block: the local median is then taken over 15 residuals.
    pub const MIN_BLOCK: usize = 5;

    /// The default floor as a fraction of the record's span (one turn on the circle, `max − min`
    /// on the line).
    pub const DEFAULT_FLOOR_FRACTION: f64 = 1e-6;

    /// Shortest record the test takes: a spike among the first five samples (which the
    /// one-sided predictions of samples 0 and 1 both hold) is located by the residuals up to
    /// sample 6.
    pub const MIN_SAMPLES: usize = 7;

    /// The defaults: threshold [`DEFAULT_THRESHOLD`](Self::DEFAULT_THRESHOLD), floor a
    /// [`DEFAULT_FLOOR_FRACTION`](Self::DEFAULT_FLOOR_FRACTION) of the span, block
    /// [`DEFAULT_BLOCK`](Self::DEFAULT_BLOCK).
    pub fn new() -> Self {
        Self {
            threshold: Self::DEFAULT_THRESHOLD,
            floor: None,
            block: Self::DEFAULT_BLOCK,
        }
    }

    /// The threshold `k` in robust standard deviations of the residual: positive and finite.
    pub fn with_threshold(mut self, threshold: f64) -> Result<Self, CircleError> {
        if !(threshold.is_finite() && threshold > 0.0) {
            return Err(CircleError::InvalidParameter {
                name: "spike threshold",
                value: threshold,
                why: "must be positive and finite (robust standard deviations)",
            });
        }
        self.threshold = threshold;
        Ok(self)
    }

    /// The absolute floor of a spike's residual, in the record's unit (radians on the circle):
    /// positive and finite. A residual at or below it is never a spike.
    pub fn with_floor(mut self, floor: f64) -> Result<Self, CircleError> {
        if !(floor.is_finite() && floor > 0.0) {
            return Err(CircleError::InvalidParameter {
                name: "spike floor",
                value: floor,
                why: "must be positive and finite (in the record's unit)",
            });
        }
        self.floor = Some(floor);
        Ok(self)
    }

    /// The floor for a record rounded to multiples of `quantum` (an encoder's count: `2π / counts
    /// per turn` on the circle): `2 · quantum`, above the `4/3 · quantum` that rounding alone can
    /// put into a residual.
    pub fn with_quantum(self, quantum: f64) -> Result<Self, CircleError> {
        if !(quantum.is_finite() && quantum > 0.0) {
            return Err(CircleError::InvalidParameter {
                name: "quantum",
                value: quantum,
                why: "must be positive and finite (in the record's unit)",
            });
        }
        self.with_floor(2.0 * quantum)
    }

    /// The block length of the local scale, in samples: at least
    /// [`MIN_BLOCK`](Self::MIN_BLOCK).
    pub fn with_block(mut self, block: usize) -> Result<Self, CircleError> {
        if block < Self::MIN_BLOCK {
            return Err(CircleError::InvalidParameter {
                name: "spike block",
                value: block as f64,
                why: "must be at least 5 samples",
            });
        }
        self.block = block;
        Ok(self)
    }

    /// The threshold in robust standard deviations.
    pub fn threshold(&self) -> f64 {
        self.threshold
    }

    /// The absolute floor, or `None` for the default (a fraction of the span).
    pub fn floor(&self) -> Option<f64> {
        self.floor
    }

    /// The block length of the local scale.
    pub fn block(&self) -> usize {
        self.block
    }
}

impl Default for SpikeParams {
    fn default() -> Self {
        Self::new()
    }
}

/// The serialised form: every field optional.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct SpikeParamsRaw {
    #[serde(default = "default_threshold")]
    threshold: f64,
    #[serde(default)]
    floor: Option<f64>,
    #[serde(default = "default_block")]
    block: usize,
}

fn default_threshold() -> f64 {
    SpikeParams::DEFAULT_THRESHOLD
}

fn default_block() -> usize {
    SpikeParams::DEFAULT_BLOCK
}

impl From<SpikeParams> for SpikeParamsRaw {
    fn from(p: SpikeParams) -> Self {
        Self {
            threshold: p.threshold,
            floor: p.floor,
            block: p.block,
        }
    }
}

impl TryFrom<SpikeParamsRaw> for SpikeParams {
    type Error = CircleError;

    fn try_from(raw: SpikeParamsRaw) -> Result<Self, CircleError> {
        let p = Self::new().with_threshold(raw.threshold)?.with_block(raw.block)?;
        match raw.floor {
            Some(f) => p.with_floor(f),
            None => Ok(p),
        }
    }
}

/// One spike: where, how far from the local prediction, and the value that replaces it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spike {
    /// Index of the sample.
    pub index: usize,
    /// Its departure from the local prediction, `x_i − p_i` (wrapped into `[−π, π)` on the
    /// circle), the prediction made from the record with every earlier-found spike repaired.
    pub size: f64,
    /// The prediction that replaces it (wrapped into `[−π, π)` on the circle).
    pub replacement: f64,
}

/// The spikes of a record, in increasing order of index, with the scale they were judged by.
#[derive(Debug, Clone, PartialEq)]
pub struct Spikes {
    spikes: Vec<Spike>,
    len: usize,
    domain: Domain,
    scale: f64,
    floor: f64,
}

impl Spikes {
    /// The spikes, in increasing order of index.
    pub fn as_slice(&self) -> &[Spike] {
        &self.spikes
    }

    /// The spikes' indices, increasing.
    pub fn indices(&self) -> impl Iterator<Item = usize> + '_ {
        self.spikes.iter().map(|s| s.index)
    }

    /// The spikes, in increasing order of index.
    pub fn iter(&self) -> std::slice::Iter<'_, Spike> {
        self.spikes.iter()
    }

    /// Number of spikes.
    pub fn len(&self) -> usize {
        self.spikes.len()
    }

    /// Whether no spike was found.
    pub fn is_empty(&self) -> bool {
        self.spikes.is_empty()
    }

    /// Length of the record searched.
    pub fn record_len(&self) -> usize {
        self.len
    }

    /// Domain the record was searched in.
    pub fn domain(&self) -> Domain {
        self.domain
    }

    /// The record's robust standard deviation of the residual, `1.4826 G` (the local scale is
    /// never below it).
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// The absolute floor used (the given one, or the default fraction of the span).
    pub fn floor(&self) -> f64 {
        self.floor
    }
}

impl<'a> IntoIterator for &'a Spikes {
    type Item = &'a Spike;
    type IntoIter = std::slice::Iter<'a, Spike>;

    fn into_iter(self) -> Self::IntoIter {
        self.spikes.iter()
    }
}

/// Finds the isolated spikes of `x`: samples that depart from the cubic through their neighbours
/// by more than the threshold times the local robust scale and more than the floor.
///
/// Errors: [`CircleError::NonFinite`] with the index of the first NaN or infinite sample,
/// [`CircleError::TooShort`] below [`SpikeParams::MIN_SAMPLES`] samples. On the circle the samples
/// need not be wrapped. `O(n)` time; one copy of the record (see [`find_and_repair_spikes`] to
/// repair in place without it).
///
/// # The test
///
/// Each sample is predicted from its neighbours on both sides by the cubic through
/// `x[i−2], x[i−1], x[i+1], x[i+2]`,
///
/// ```text
/// p_i = (−x[i−2] + 4 x[i−1] + 4 x[i+1] − x[i+2]) / 6,      r_i = x_i − p_i = Δ⁴x_i / 6,
/// ```
///
/// the residual `r_i` being a sixth of the fourth difference `Δ⁴x_i = x[i−2] − 4x[i−1] + 6x[i] −
/// 4x[i+1] + x[i+2]`. The prediction is exact for any cubic, so a constant rotation (a linear
/// trend) leaves the residuals unchanged; a smooth signal sampled `h` apart leaves `h⁴ x⁗ / 6`,
/// and white noise of standard deviation `σ` gives residuals of standard deviation
/// `σ √(70) / 6 ≈ 1.39 σ`. A spike `s` at sample `j` gives `r_j = s` and, at its neighbours,
/// `r_{j±1} = −2s/3` and `r_{j±2} = s/6`: the spike's own residual is the largest of the five.
///
/// On the circle the four neighbours are unwrapped relative to `x[i−1]` from wrapped differences
/// (`x[i−2] − x[i−1]`, `x[i+1] − x[i−1]` across the tested sample, then `x[i+2] − x[i+1]`), the
/// prediction is made on that local continuous signal, and `r_i = wrap(x_i − p_i)`. The tested
/// sample never enters its own prediction, so a spike of any size up to half a turn is seen as a
/// residual of that size and never as a turn. This needs the true signal to move less than π over
/// two samples (less than a quarter turn per sample on average), twice as strict as
/// [`unwrap`](crate::unwrap).
///
/// The first and last two samples have neighbours on one side only. Sample 0 is predicted by the
/// cubic through samples 1–4 (`p_0 = 4x₁ − 6x₂ + 4x₃ − x₄`, so `r_0 = Δ⁴x₂`) and sample 1 by the
/// cubic through samples 0, 2, 3 and 4 (`r_1 = −Δ⁴x₂ / 4`); the last two mirror them. Both are the
/// fourth difference of the same five samples as the centred residual of sample 2, so their
/// noise gains `g_i` are 6 and 1.5 times the interior one (`g_i = 1` inside), and a spike there
/// must be that much larger to be found. Residuals are compared between samples as `|r_i| / g_i`.
///
/// # Scale and threshold
///
/// A sample exceeds when `|r_i| / g_i > T_i = max(k · s_i, f)`, with `k` the
/// [threshold](SpikeParams::threshold) in robust standard deviations, `f` the absolute
/// [floor](SpikeParams::floor) and `s_i` the robust scale:
///
/// - the centred residuals are cut into blocks of [`block`](SpikeParams::block) samples; the
///   local median `L_b` of `|r|` is taken over block `b` and its two neighbours (`N = 3 · block`
///   residuals);
/// - the record's median `G` is the median of the `L_b`;
/// - `s_i = 1.4826 · L_b(i)` where `L_b` exceeds `G` by three of its own standard deviations
///   (`L_b > G (1 + 3 · 1.166 / √N)`, 1.166 / √N being the relative spread of the median of `N`
///   Gaussian absolute values), `s_i = 1.4826 · G` elsewhere; 1.4826 is the ratio of the standard
///   deviation of a Gaussian to its median absolute value.
///
/// The local median follows a record that is fast in places and slow elsewhere: at 25 samples
/// per forcing period the smooth motion's own residual `h⁴ x⁗ / 6` reaches 15 counts of a
/// 4096-count encoder in a burst of fast motion and stays below one count between bursts; with the
/// record's scale alone such a record gets thousands of false detections. Using the local median
/// only where it stands out keeps a noisy record's threshold at the record's (the local median
/// scatters by 8 % around it with the default block, which would otherwise raise the threshold
/// where it happens to be high), and the record's median is a lower bound where the residuals
/// happen to be small (or a quantised stretch where most residuals are exactly zero). A spike
/// moves the median of the `N` residuals around it by a few of their ranks only.
///
/// The floor keeps a record whose residuals are mostly zero (a quantised record at rest, a
/// noise-free simulation of a piecewise polynomial) from flagging rounding-level wiggles: by
/// default a millionth of the span (one turn on the circle, `max − min` on the line), far above
/// the rounding of `f64` and of `f32` storage and far below any bit error of an encoder with up to
/// 2²⁰ counts per turn. A record rounded to multiples of a quantum `q` (an encoder's count, `2π /
/// counts` on the circle) has rounding residuals up to `(1 + 10/6) q / 2 = 4q/3`:
/// [`with_quantum`](SpikeParams::with_quantum) sets the floor to `2q`.
///
/// # Isolating the spike
///
/// A spike also enters the residuals of the samples whose prediction holds it (two on each side
/// inside the record, and samples 0, 1 from up to sample 4). The record is swept in order; at the
/// first sample `i` that exceeds, the spike is one of the samples `i`'s prediction spans (`i − 2
/// ..= i + 2` inside, `0 ..= 4` at the start). Each of those that exceeds is replaced in turn by
/// its prediction, and the one whose replacement leaves the smallest sum of `(|r_m| / g_m)²` over
/// the samples within two of that span (and the first or last two samples, whose predictions
/// reach four samples in) is flagged: the spike itself, whose removal clears every
/// neighbour's residual, also where the smooth motion's residual is a sizeable part of the spike
/// (a plain "largest residual" rule picks a neighbour there, whose residual is `2/3` of the
/// spike's plus the motion's). The flagged sample is replaced by its prediction at once, the sweep
/// steps back two samples, and the neighbours are tested again with the repaired value. A sample
/// is flagged only if its repair leaves at most half of that sum: a spike's repair clears the
/// residuals around it (a spike at the threshold of 6 robust standard deviations leaves about a
/// sixth), while the smooth motion's own residual, which in a noise-free record sampled finely can
/// stand out of its local median in a burst of fast motion, is only moved to the neighbours by a
/// repair (the sum grows): such a sample is not a spike, whatever its ratio to the scale.
///
/// A repair moves sample `j` by minus the residual its clean value would have had, which is at
/// most its threshold `g_j T_j`, and that enters sample `i`'s residual with the weight `c_ij` of
/// `x_j` in `p_i` (`2/3` and `1/6` inside the record); so a sample whose prediction holds repaired
/// samples has its threshold raised by `Σ c_ij g_j T_j / g_i`, and the repair of a spike cannot
/// make a false one of its neighbour. A sample is flagged once at most. Two spikes closer than
/// three samples bias each other's predictions and are not resolved reliably: the test is made
/// for isolated spikes. Noise can also make a spike just above the threshold fit worse than its
/// neighbour: of 1552 spikes of 7 robust standard deviations (64 counts at σ = 0.01 rad, 100 and
/// 490 samples per period), 2 had the neighbour flagged instead (the rule "largest residual"
/// errs less there but fails where the motion's own residual is large).
///
/// # Cost
///
/// `O(n)` time: the scale is one pass computing each residual once and a selection (linear time)
/// of the median of each `3 · block` window; the sweep computes each residual once more, and a few
/// dozen more around every sample that exceeds its threshold. Memory: the scale's blocks (`n /
/// block` numbers), one window of `3 · block`, one bit per sample for the flags, and a copy of the
/// record here (none for [`find_and_repair_spikes`]); nothing is allocated per sample. About
/// 0.05 s per 10⁶ samples (`cargo run --release -p circle-signal --example spike_rates`).
///
/// # Example
///
/// ```
/// use circle_signal::{Domain, SpikeParams, find_spikes, repair_spikes, unwrap, wrap};
/// use std::f64::consts::{PI, TAU};
///
/// // A whirling angle, 100 samples per forcing period of 2π, through a 4096-count encoder.
/// let q = TAU / 4096.0;
/// let count = |t: f64| ((t + 0.6 * t.sin()) / q).round();
/// let clean: Vec<f64> = (0..2000).map(|n| wrap(count(n as f64 * TAU / 100.0) * q)).collect();
/// // A bit error of 2048 counts (half a turn) at sample 700.
/// let mut x = clean.clone();
/// x[700] = wrap(x[700] + 2048.0 * q);
/// // Left in, it is unwrapped into a false turn.
/// let turns = |y: &[f64]| ((unwrap(y)[y.len() - 1] - y[0]) / TAU).round();
/// assert_ne!(turns(&x), turns(&clean));
///
/// let params = SpikeParams::new().with_quantum(q)?;
/// let spikes = find_spikes(&x, Domain::Circle, &params)?;
/// assert_eq!(spikes.indices().collect::<Vec<_>>(), vec![700]);
/// assert!((spikes.as_slice()[0].size.abs() - PI).abs() < 0.01);
/// repair_spikes(&mut x, &spikes)?;
/// assert!((x[700] - clean[700]).abs() < 2.0 * q);
/// assert_eq!(turns(&x), turns(&clean));
/// # Ok::<(), circle_signal::CircleError>(())
/// ```
pub fn find_spikes(x: &[f64], domain: Domain, params: &SpikeParams) -> Result<Spikes, CircleError> {
    let mut work = x.to_vec();
    find_and_repair_spikes(&mut work, domain, params)
}

/// Finds the isolated spikes of `x` and replaces each by its local prediction, in place; the
/// same spikes as [`find_spikes`], without a copy of the record.
///
/// On error `x` is unchanged.
pub fn find_and_repair_spikes(
    x: &mut [f64],
    domain: Domain,
    params: &SpikeParams,
) -> Result<Spikes, CircleError> {
    let n = x.len();
    if let Some((index, &value)) = x.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(CircleError::NonFinite { index, value });
    }
    if n < SpikeParams::MIN_SAMPLES {
        return Err(CircleError::TooShort {
            len: n,
            needed: SpikeParams::MIN_SAMPLES,
        });
    }
    match domain {
        Domain::Circle => Search::<OnCircle>::run(x, params, TAU),
        Domain::Line => {
            let (lo, hi) = x.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            });
            Search::<OnLine>::run(x, params, hi - lo)
        }
    }
}

/// Writes the replacements of `spikes` into `x`, the record they were found in (or a copy of it).
///
/// Errors with [`CircleError::LengthMismatch`] when `x` is not as long as the record searched.
pub fn repair_spikes(x: &mut [f64], spikes: &Spikes) -> Result<(), CircleError> {
    if x.len() != spikes.len {
        return Err(CircleError::LengthMismatch {
            expected: spikes.len,
            found: x.len(),
        });
    }
    for s in &spikes.spikes {
        x[s.index] = s.replacement;
    }
    Ok(())
}

/// How differences are taken and values reported in a domain.
trait Geometry {
    const DOMAIN: Domain;
    /// A difference of two samples: into `[−π, π)` on the circle, unchanged on the line.
    fn diff(d: f64) -> f64;
    /// A value as reported: wrapped into `[−π, π)` on the circle, unchanged on the line.
    fn point(v: f64) -> f64;
}

struct OnCircle;
struct OnLine;

impl Geometry for OnCircle {
    const DOMAIN: Domain = Domain::Circle;
    #[inline]
    fn diff(d: f64) -> f64 {
        // Differences of wrapped samples lie within (−2π, 2π): one branch, no division.
        if d >= PI {
            if d < 3.0 * PI { d - TAU } else { wrap(d) }
        } else if d < -PI {
            if d >= -3.0 * PI { d + TAU } else { wrap(d) }
        } else {
            d
        }
    }
    #[inline]
    fn point(v: f64) -> f64 {
        wrap(v)
    }
}

impl Geometry for OnLine {
    const DOMAIN: Domain = Domain::Line;
    #[inline]
    fn diff(d: f64) -> f64 {
        d
    }
    #[inline]
    fn point(v: f64) -> f64 {
        v
    }
}

/// Residual `x_i − p_i` of sample `i` and its prediction `p_i` (on the circle, on the branch of
/// the neighbour it was unwrapped from), by the cubic through four neighbours: centred inside the
/// record, one-sided for the first and last two samples. `x.len() >= 5`.
#[inline]
fn predict<G: Geometry>(x: &[f64], i: usize) -> (f64, f64) {
    let n = x.len();
    let d = G::diff;
    let (base, p) = if i >= 2 && i + 2 < n {
        let base = x[i - 1];
        let a = d(x[i - 2] - base);
        let b = d(x[i + 1] - base);
        let c = b + d(x[i + 2] - x[i + 1]);
        (base, (4.0 * b - a - c) / 6.0)
    } else if i == 0 || i == n - 1 {
        // Cubic extrapolation from the next four: p = 4 x₁ − 6 x₂ + 4 x₃ − x₄.
        let s: isize = if i == 0 { 1 } else { -1 };
        let at = |k: isize| x[(i as isize + s * k) as usize];
        let base = at(1);
        let u2 = d(at(2) - base);
        let u3 = u2 + d(at(3) - at(2));
        let u4 = u3 + d(at(4) - at(3));
        (base, 4.0 * u3 - 6.0 * u2 - u4)
    } else {
        // Sample 1 (or n − 2): the cubic through samples 0, 2, 3, 4 at 1, weights 1/4, 3/2, −1, 1/4.
        let s: isize = if i == 1 { 1 } else { -1 };
        let at = |k: isize| x[(i as isize + s * (k - 1)) as usize];
        let base = at(2);
        let u0 = d(at(0) - base);
        let u3 = d(at(3) - base);
        let u4 = u3 + d(at(4) - at(3));
        (base, 0.25 * (u0 + u4) - u3)
    };
    (d(x[i] - base - p), base + p)
}

/// The noise gain of sample `i`'s prediction relative to the centred one: 6 at the ends, 1.5 next
/// to them, 1 inside.
#[inline]
fn gain(n: usize, i: usize) -> f64 {
    if i == 0 || i == n - 1 {
        6.0
    } else if i == 1 || i == n - 2 {
        1.5
    } else {
        1.0
    }
}

/// The four samples of sample `i`'s prediction and the magnitude of their weights in it.
fn stencil(n: usize, i: usize) -> [(usize, f64); 4] {
    if i >= 2 && i + 2 < n {
        [
            (i - 2, 1.0 / 6.0),
            (i - 1, 2.0 / 3.0),
            (i + 1, 2.0 / 3.0),
            (i + 2, 1.0 / 6.0),
        ]
    } else if i == 0 {
        [(1, 4.0), (2, 6.0), (3, 4.0), (4, 1.0)]
    } else if i == n - 1 {
        [(n - 2, 4.0), (n - 3, 6.0), (n - 4, 4.0), (n - 5, 1.0)]
    } else if i == 1 {
        [(0, 0.25), (2, 1.5), (3, 1.0), (4, 0.25)]
    } else {
        [(n - 1, 0.25), (n - 3, 1.5), (n - 4, 1.0), (n - 5, 0.25)]
    }
}

/// The samples sample `i` and its prediction span, as an inclusive range.
fn reach(n: usize, i: usize) -> (usize, usize) {
    if i <= 1 {
        (0, 4)
    } else if i + 2 >= n {
        (n - 5, n - 1)
    } else {
        (i - 2, i + 2)
    }
}

/// Median of a non-empty slice (the upper one of an even count), reordering it.
fn median(v: &mut [f64]) -> f64 {
    let mid = v.len() / 2;
    *v.select_nth_unstable_by(mid, f64::total_cmp).1
}

struct Search<'a, G> {
    x: &'a mut [f64],
    /// Threshold of a centred residual, per block.
    thresholds: Vec<f64>,
    block: usize,
    /// One bit per sample: flagged already.
    flagged: Vec<u64>,
    spikes: Vec<Spike>,
    _geometry: std::marker::PhantomData<G>,
}

impl<'a, G: Geometry> Search<'a, G> {
    fn run(x: &'a mut [f64], params: &SpikeParams, span: f64) -> Result<Spikes, CircleError> {
        let n = x.len();
        let floor = params.floor.unwrap_or(SpikeParams::DEFAULT_FLOOR_FRACTION * span);
        let block = params.block;
        let (record_median, locals) = scales::<G>(x, block);
        let scale = MAD_TO_SD * record_median;
        if floor.is_nan() || floor <= 0.0 {
            // A constant record on the line: nothing departs from anything.
            return Ok(Spikes {
                spikes: Vec::new(),
                len: n,
                domain: G::DOMAIN,
                scale,
                floor,
            });
        }
        // A local median is used where it stands out of the record's by three of its own
        // standard deviations (relative `MEDIAN_SPREAD / √(3 block)` for Gaussian residuals).
        let significant = record_median * (1.0 + 3.0 * MEDIAN_SPREAD / ((3 * block) as f64).sqrt());
        let thresholds = locals
            .into_iter()
            .map(|l| {
                let s = if l > significant { l } else { record_median };
                (params.threshold * MAD_TO_SD * s).max(floor)
            })
            .collect();
        let mut search = Self {
            x,
            thresholds,
            block,
            flagged: vec![0; n.div_ceil(64)],
            spikes: Vec::new(),
            _geometry: std::marker::PhantomData,
        };
        search.sweep();
        let mut spikes = search.spikes;
        spikes.sort_unstable_by_key(|s| s.index);
        Ok(Spikes {
            spikes,
            len: n,
            domain: G::DOMAIN,
            scale,
            floor,
        })
    }

    /// `|r_i|` over the noise gain of its prediction, comparable between neighbours.
    #[inline]
    fn weighted(&self, i: usize) -> f64 {
        let (r, _) = predict::<G>(self.x, i);
        r.abs() / gain(self.x.len(), i)
    }

    /// The threshold of [`weighted`](Self::weighted) at sample `i`, raised by what the repairs
    /// of flagged samples in its prediction can have put into it: a repair moves sample `j` by
    /// minus the residual its clean value would have had, at most its own threshold `g_j T_j`,
    /// and that enters `r_i` times the weight `c_ij` of `x_j` in `p_i`.
    #[inline]
    fn threshold(&self, i: usize) -> f64 {
        let n = self.x.len();
        let own = self.thresholds[i / self.block];
        let raise: f64 = stencil(n, i)
            .iter()
            .filter(|&&(j, _)| self.is_flagged(j))
            .map(|&(j, c)| c * gain(n, j) * self.thresholds[j / self.block])
            .sum();
        own + raise / gain(n, i)
    }

    #[inline]
    fn is_flagged(&self, i: usize) -> bool {
        self.flagged[i / 64] >> (i % 64) & 1 == 1
    }

    fn flag(&mut self, i: usize) {
        let (size, prediction) = predict::<G>(self.x, i);
        let replacement = G::point(prediction);
        self.x[i] = replacement;
        self.flagged[i / 64] |= 1 << (i % 64);
        self.spikes.push(Spike {
            index: i,
            size,
            replacement,
        });
    }

    /// Whether `weighted(i) = w` exceeds the threshold at `i` (the cheap own threshold first).
    #[inline]
    fn exceeds(&self, i: usize, w: f64) -> bool {
        w > self.thresholds[i / self.block] && w > self.threshold(i)
    }

    fn sweep(&mut self) {
        let n = self.x.len();
        let mut i = 0;
        while i < n {
            if self.is_flagged(i) || !self.exceeds(i, self.weighted(i)) {
                i += 1;
                continue;
            }
            // The spike that makes sample i exceed is in its prediction or is i itself: of the
            // samples there that exceed, the one whose replacement leaves the residuals it can
            // reach smallest (ties: the larger residual, then the earlier sample).
            let (lo, hi) = reach(n, i);
            let window = (
                if lo <= 4 { 0 } else { lo - 2 },
                if hi + 5 >= n { n - 1 } else { hi + 2 },
            );
            let mut best: Option<(usize, f64, f64)> = None;
            for j in lo..=hi {
                if self.is_flagged(j) {
                    continue;
                }
                let w = self.weighted(j);
                if !self.exceeds(j, w) {
                    continue;
                }
                let energy = self.energy_after_repair(j, window);
                let better = match best {
                    None => true,
                    Some((_, be, bw)) => energy < be || (energy == be && w > bw),
                };
                if better {
                    best = Some((j, energy, w));
                }
            }
            // A spike's repair clears its neighbours' residuals; the smooth motion's own residual
            // (a burst of fast motion in a noise-free record) only moves to the neighbours.
            let before: f64 = (window.0..=window.1).map(|m| self.weighted(m).powi(2)).sum();
            match best {
                Some((j, energy, _)) if energy <= CLEARED * before => {
                    self.flag(j);
                    i = j.saturating_sub(2);
                }
                _ => i += 1,
            }
        }
    }

    /// The sum of the squared weighted residuals of the samples in `window` (inclusive) with
    /// sample `j` replaced by its prediction (the record is left as it was).
    fn energy_after_repair(&mut self, j: usize, window: (usize, usize)) -> f64 {
        let original = self.x[j];
        let (_, prediction) = predict::<G>(self.x, j);
        self.x[j] = G::point(prediction);
        let energy = (window.0..=window.1).map(|m| self.weighted(m).powi(2)).sum();
        self.x[j] = original;
        energy
    }
}

/// A repair must leave at most this fraction of the residuals' energy around it for the sample
/// to be a spike (see "Isolating the spike" in [`find_spikes`]).
const CLEARED: f64 = 0.5;

/// The record's median `G` and the local medians `L_b` of `|r|` per block (over
/// the block and its two neighbours), from the centred residuals of samples `2..n−2`.
fn scales<G: Geometry>(x: &[f64], block: usize) -> (f64, Vec<f64>) {
    let n = x.len();
    let blocks = n.div_ceil(block);
    let fill = |b: usize, buf: &mut Vec<f64>| {
        buf.clear();
        let lo = (b * block).max(2);
        let hi = ((b + 1) * block).min(n - 2);
        buf.extend((lo..hi).map(|i| predict::<G>(x, i).0.abs()));
    };
    let (mut prev, mut cur, mut next) = (
        Vec::with_capacity(block),
        Vec::with_capacity(block),
        Vec::with_capacity(block),
    );
    let mut window = Vec::with_capacity(3 * block);
    fill(0, &mut cur);
    fill(1, &mut next);
    let mut locals = Vec::with_capacity(blocks);
    for b in 0..blocks {
        window.clear();
        window.extend_from_slice(&prev);
        window.extend_from_slice(&cur);
        window.extend_from_slice(&next);
        // Never empty: block b or its predecessor holds centred residuals when n >= 7, block >= 5.
        locals.push(median(&mut window));
        std::mem::swap(&mut prev, &mut cur);
        std::mem::swap(&mut cur, &mut next);
        fill(b + 2, &mut next);
    }
    window.clear();
    window.extend_from_slice(&locals);
    (median(&mut window), locals)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn record(n: usize, f: impl Fn(f64) -> f64) -> Vec<f64> {
        (0..n).map(|i| f(i as f64)).collect()
    }

    #[test]
    fn predictions_are_exact_for_cubics() {
        let x = record(12, |t| 0.3 - 0.2 * t + 0.05 * t * t - 0.004 * t * t * t);
        for i in 0..x.len() {
            let (r, p) = predict::<OnLine>(&x, i);
            assert!(r.abs() < 1e-12, "sample {i}: {r}");
            assert!((p - x[i]).abs() < 1e-12);
        }
    }

    #[test]
    fn residuals_are_scaled_fourth_differences() {
        let x = record(9, |t| (0.7 * t).sin() + 0.1 * t.powi(4));
        let d4 = |c: usize| x[c - 2] - 4.0 * x[c - 1] + 6.0 * x[c] - 4.0 * x[c + 1] + x[c + 2];
        let n = x.len();
        let r = |i| predict::<OnLine>(&x, i).0;
        assert!((r(0) - d4(2)).abs() < 1e-12);
        assert!((r(1) + d4(2) / 4.0).abs() < 1e-12);
        assert!((r(4) - d4(4) / 6.0).abs() < 1e-12);
        assert!((r(n - 2) + d4(n - 3) / 4.0).abs() < 1e-12);
        assert!((r(n - 1) - d4(n - 3)).abs() < 1e-12);
    }

    #[test]
    fn circle_prediction_ignores_the_wrap() {
        // A fast rotation crossing ±π many times; the residuals equal those of the line.
        let f = |t: f64| 0.9 * t + 0.3 * (0.4 * t).sin();
        let line = record(40, f);
        let circle: Vec<f64> = line.iter().map(|&v| wrap(v)).collect();
        for i in 0..line.len() {
            let (rl, pl) = predict::<OnLine>(&line, i);
            let (rc, pc) = predict::<OnCircle>(&circle, i);
            assert!((rl - rc).abs() < 1e-12, "sample {i}");
            assert!(crate::circle_distance(pl, pc) < 1e-12);
        }
    }

    #[test]
    fn a_spike_dominates_its_neighbours_even_at_half_a_turn() {
        for v in [-0.6, -0.05, 0.0, 0.05, 0.6] {
            for s in [PI, -PI, PI - 1e-3, 0.3] {
                let mut x: Vec<f64> = record(30, |t| wrap(v * t + 0.2 * (0.3 * t).cos()));
                x[15] = wrap(x[15] + s);
                let r = |i| predict::<OnCircle>(&x, i).0.abs();
                assert!((r(15) - s.abs()).abs() < 0.01, "v {v} s {s}: {}", r(15));
                for j in [13, 14, 16, 17] {
                    assert!(r(j) < 0.7 * s.abs() + 0.01, "v {v} s {s} neighbour {j}: {}", r(j));
                }
            }
        }
    }

    #[test]
    fn each_end_sample_is_told_apart() {
        let clean = record(60, |t| (0.2 * t).sin() + 0.01 * t);
        for j in [0, 1, 2, 3, 56, 57, 58, 59] {
            for s in [0.05, -0.5] {
                let mut x = clean.clone();
                x[j] += s;
                let found = find_spikes(&x, Domain::Line, &SpikeParams::new()).unwrap();
                assert_eq!(found.indices().collect::<Vec<_>>(), vec![j], "spike {s} at {j}");
                // The end samples' extrapolation misses the clean signal by up to |Δ⁴x| ≤ 0.2⁴.
                let spike = found.as_slice()[0];
                assert!((spike.size - s).abs() < 2e-3, "{spike:?}");
                assert!((spike.replacement - clean[j]).abs() < 2e-3, "{spike:?}");
            }
        }
    }

    /// `x = c t⁴` has the same residual `4c` at every sample (`Δ⁴x = 24c`): a smooth motion whose
    /// own residual is a sizeable part of a spike's, with a threshold of one robust standard
    /// deviation (`1.4826 · 4c`).
    fn quartic(c: f64) -> (Vec<f64>, SpikeParams) {
        let x = record(60, |t| c * t.powi(4));
        let params = SpikeParams::new()
            .with_threshold(1.0)
            .and_then(|p| p.with_floor(1e-12))
            .unwrap();
        (x, params)
    }

    #[test]
    fn the_spike_is_told_from_its_neighbours_by_what_its_repair_clears() {
        let c = 1e-3;
        let (clean, params) = quartic(c);
        assert!(find_spikes(&clean, Domain::Line, &params).unwrap().is_empty());
        // A spike of −12c: its residual is −8c, its neighbours' 8c + 4c = 12c, the largest.
        let mut x = clean.clone();
        x[30] -= 12.0 * c;
        assert!(predict::<OnLine>(&x, 31).0.abs() > predict::<OnLine>(&x, 30).0.abs());
        let found = find_spikes(&x, Domain::Line, &params).unwrap();
        assert_eq!(found.indices().collect::<Vec<_>>(), vec![30]);
        let spike = found.as_slice()[0];
        assert!((spike.size + 8.0 * c).abs() < 1e-9, "{spike:?}");
        // The prediction misses the clean sample by the motion's residual.
        assert!(
            (spike.replacement - (clean[30] - 4.0 * c)).abs() < 1e-9,
            "{spike:?}"
        );
    }

    #[test]
    fn a_repair_does_not_make_its_neighbours_spikes() {
        // The repair misses by −4c, which puts 2/3 of that into the neighbours' residuals:
        // 4c + 8c/3 = 6.7c, above the threshold 5.9c of a clean neighbour.
        let c = 1e-3;
        let (mut x, params) = quartic(c);
        x[20] += 50.0 * c;
        x[40] -= 50.0 * c;
        let found = find_spikes(&x, Domain::Line, &params).unwrap();
        assert_eq!(found.indices().collect::<Vec<_>>(), vec![20, 40]);
    }

    #[test]
    fn the_smooth_motion_of_a_noise_free_record_is_not_a_spike() {
        // Bursts of fast motion, 100 samples per period, full precision: the residual of the
        // cubic prediction stands out of its local median in each burst without any spike.
        let h = std::f64::consts::TAU / 100.0;
        let x = record(20_000, |n| {
            let t = n * h;
            let burst = (-(((t % 40.0) - 20.0) / 1.5).powi(2)).exp();
            t.sin() + 0.4 * (3.7 * t).sin() * burst + 0.05 * (11.0 * t).cos() * burst
        });
        let found = find_spikes(&x, Domain::Line, &SpikeParams::default()).unwrap();
        assert!(
            found.is_empty(),
            "{} false spikes, first {:?}",
            found.len(),
            found.as_slice().first()
        );
        // A real spike in it is still found.
        let mut y = x.clone();
        y[10_007] += 0.01;
        let found = find_spikes(&y, Domain::Line, &SpikeParams::default()).unwrap();
        assert_eq!(found.indices().collect::<Vec<_>>(), [10_007]);
    }

    #[test]
    fn errors() {
        let p = SpikeParams::new();
        assert_eq!(
            find_spikes(&[0.0; 6], Domain::Line, &p),
            Err(CircleError::TooShort { len: 6, needed: 7 })
        );
        let mut x = vec![0.0; 20];
        x[11] = f64::NEG_INFINITY;
        assert!(matches!(
            find_spikes(&x, Domain::Circle, &p),
            Err(CircleError::NonFinite { index: 11, .. })
        ));
        let found = find_spikes(&[1.0; 10], Domain::Line, &p).unwrap();
        assert!(found.is_empty());
        assert_eq!(
            repair_spikes(&mut [0.0; 9], &found),
            Err(CircleError::LengthMismatch {
                expected: 10,
                found: 9
            })
        );
    }

    #[test]
    fn params_validate() {
        let p = SpikeParams::new();
        assert!(p.with_threshold(0.0).is_err());
        assert!(p.with_threshold(f64::NAN).is_err());
        assert!(p.with_floor(0.0).is_err());
        assert!(p.with_floor(f64::INFINITY).is_err());
        assert!(p.with_quantum(-1.0).is_err());
        assert!(p.with_block(4).is_err());
        assert_eq!(p.with_quantum(0.5).unwrap().floor(), Some(1.0));
        let q = p
            .with_threshold(4.5)
            .unwrap()
            .with_floor(0.01)
            .unwrap()
            .with_block(32)
            .unwrap();
        let json = serde_json::to_string(&q).unwrap();
        assert_eq!(serde_json::from_str::<SpikeParams>(&json).unwrap(), q);
        assert_eq!(serde_json::from_str::<SpikeParams>("{}").unwrap(), p);
        for bad in [
            r#"{"threshold":-2.0}"#,
            r#"{"floor":0.0}"#,
            r#"{"block":2}"#,
            r#"{"threshold":null}"#,
        ] {
            assert!(serde_json::from_str::<SpikeParams>(bad).is_err(), "{bad}");
        }
    }
}
