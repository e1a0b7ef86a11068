//! Outliers in a record: isolated spikes (an encoder's bit errors) and short runs of samples (a
//! vibrometer's dropouts) that depart from their neighbours by many times the local noise.
//!
//! An encoder with a bit error reports one sample off by `±2^k` counts and the next one right
//! again. Left in the record, such a spike is a jump of the angular velocity and acceleration; on
//! the circle a spike near half a turn is worse, since [`unwrap`](crate::unwrap) takes the step
//! into the spike and the step out of it as steps of opposite sign modulo 2π, and the record gains
//! (or loses) a whole false turn. A laser vibrometer that loses its light for a moment reports a
//! sample or a few near zero, or far off. This module finds such outliers by a robust test whose
//! threshold follows the local noise, and replaces them by the local prediction; the test is
//! documented on [`find_spikes`], its measured rates in `docs/spikes.md`.

use std::collections::BTreeMap;
use std::f64::consts::{PI, TAU};
use std::sync::LazyLock;

use serde::{Deserialize, Serialize};

use crate::{CircleError, Domain, wrap};

mod clearing;
mod stretch;

use clearing::Clearing;
use stretch::{LEVEL_BLOCK, Stretch};

/// The standard deviation of a Gaussian over its median absolute value, `1 / Φ⁻¹(3/4)`.
const MAD_TO_SD: f64 = 1.482_602_218_505_602;

/// The relative standard deviation of the median absolute value of `N` Gaussian numbers, times
/// `√N`: `1 / (2 f(m) m)` with `m = Φ⁻¹(3/4)` the median and `f(m) = 2φ(m)` the density of the
/// absolute value there.
const MEDIAN_SPREAD: f64 = 1.166;

/// Parameters of the spike test: the threshold in robust standard deviations, the absolute floor,
/// the block length of the block scale and the longest run of samples replaced together (see
/// [`find_spikes`] for the test).
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
    max_run: usize,
}

/// Longest run of samples that can be replaced together.
const MAX_RUN: usize = 4;

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
    /// at σ = 0.01 rad) is found 51 % of the time at 25 samples per period and 66–68 % at 100
    /// and 490 (69 % and 81–82 % with the block scale alone, before the local scale was added);
    /// 128 counts always (`cargo run --release -p circle-signal --example spike_rates`).
    pub const DEFAULT_THRESHOLD: f64 = 6.0;

    /// Default block length of the block scale, in samples: the block's median is taken over
    /// three blocks, 192 residuals, which estimates a Gaussian scale to about 8 % (one standard
    /// deviation of the sample median).
    pub const DEFAULT_BLOCK: usize = 64;

    /// Default longest run of samples replaced together: 3, a vibrometer's dropout of up to
    /// 1.5 ms at 2048 Hz.
    pub const DEFAULT_MAX_RUN: usize = 3;

    /// Longest run of samples that can be replaced together.
    pub const MAX_RUN: usize = MAX_RUN;

    /// Shortest block: the block's median is then taken over 15 residuals.
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
    /// [`DEFAULT_BLOCK`](Self::DEFAULT_BLOCK), runs up to
    /// [`DEFAULT_MAX_RUN`](Self::DEFAULT_MAX_RUN).
    pub fn new() -> Self {
        Self {
            threshold: Self::DEFAULT_THRESHOLD,
            floor: None,
            block: Self::DEFAULT_BLOCK,
            max_run: Self::DEFAULT_MAX_RUN,
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

    /// The block length of the block scale, in samples: at least
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

    /// The longest run of samples replaced together: from 1 (isolated spikes only, the test of
    /// an encoder's bit errors) to [`MAX_RUN`](Self::MAX_RUN).
    pub fn with_max_run(mut self, max_run: usize) -> Result<Self, CircleError> {
        if !(1..=MAX_RUN).contains(&max_run) {
            return Err(CircleError::InvalidParameter {
                name: "spike run",
                value: max_run as f64,
                why: "must be 1 to 4 samples",
            });
        }
        self.max_run = max_run;
        Ok(self)
    }

    /// The longest run of samples replaced together.
    pub fn max_run(&self) -> usize {
        self.max_run
    }

    /// The threshold in robust standard deviations.
    pub fn threshold(&self) -> f64 {
        self.threshold
    }

    /// The absolute floor, or `None` for the default (a fraction of the span).
    pub fn floor(&self) -> Option<f64> {
        self.floor
    }

    /// The block length of the block scale.
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
    #[serde(default = "default_max_run")]
    max_run: usize,
}

fn default_max_run() -> usize {
    SpikeParams::DEFAULT_MAX_RUN
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
            max_run: p.max_run,
        }
    }
}

impl TryFrom<SpikeParamsRaw> for SpikeParams {
    type Error = CircleError;

    fn try_from(raw: SpikeParamsRaw) -> Result<Self, CircleError> {
        let p = Self::new()
            .with_threshold(raw.threshold)?
            .with_block(raw.block)?
            .with_max_run(raw.max_run)?;
        match raw.floor {
            Some(f) => p.with_floor(f),
            None => Ok(p),
        }
    }
}

/// One outlying sample (a spike, or one sample of a run): where, how far from the local
/// prediction, and the value that replaces it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spike {
    /// Index of the sample.
    pub index: usize,
    /// Its departure from the local prediction, `x_i − p_i` (wrapped into `[−π, π)` on the
    /// circle), the prediction made from the record with every earlier-found spike repaired (for
    /// a sample of a run, the prediction of the run from the two samples on each side of it).
    pub size: f64,
    /// The prediction that replaces it (wrapped into `[−π, π)` on the circle).
    pub replacement: f64,
}

/// The outlying samples of a record (a run of `m` samples gives `m` consecutive ones), in
/// increasing order of index, with the record's scale.
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

    /// The record's robust standard deviation of the residual, `1.4826 G` (no threshold is below
    /// `k` times it).
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

/// Finds the outliers of `x`: isolated spikes, samples that depart from the cubic through their
/// neighbours, and runs of up to [`max_run`](SpikeParams::max_run) consecutive samples that depart
/// from the cubic through the two samples on each side of them, by more than the threshold times
/// the larger of the block's and the local robust scale, and more than the floor.
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
/// # Runs
///
/// A run of `m` samples moved by `S` gives the residuals `S/6, −S/2, S/3, S/3, −S/2, S/6`
/// (`m = 2`) or `S/6, −S/2, S/2, 0, S/2, −S/2, S/6` (`m = 3`): none stands out as a spike's own
/// residual does, and the single prediction of one of its samples is made from the others. The
/// sum of the run's `m` residuals does: `2S/3` and `S`, over noise gains `√0.4` and `√0.6` of
/// one residual's for white noise (the residuals' autocovariance is `70, −56, 28, −8, 1` in units
/// of `σ²/36`), about as large as a single spike's own residual in its noise. So the statistics of
/// a sample `i` are `|r_i| / g_i` and, inside the record, `|r_i + … + r_{i+m−1}|` over its gain for
/// `m` up to [`max_run`](SpikeParams::max_run).
///
/// A run `a ..= b` is predicted by the cubic through `x[a−2], x[a−1], x[b+1], x[b+2]` (Lagrange's
/// weights at the run's samples; on the circle unwrapped relative to `x[a−1]`, so the true signal
/// must move less than π over `m + 1` samples), inside the record only (samples 2 to `n − 3`). It
/// is replaced rather than a single sample only where every one of its samples departs from that
/// prediction by more than its threshold (relative to the prediction's noise gain, after what a
/// smooth motion makes the wider gap miss: 3, 6 and 9 times the motion's residual, taken as the
/// mean residual over the run's reach and two more samples on each side, from which the run's
/// own residuals cancel), where its repair leaves at most half of what the best single repair
/// leaves over the residuals either reaches (whether or not that sample exceeds its threshold: a
/// run whose prediction is made from a spike departs from it), and less by 10.83 squared
/// standard deviations of the residual per sample beyond the first (what the repair of an
/// ordinary sample takes out once in a thousand).
///
/// # Scale and threshold
///
/// A statistic of width `m` exceeds when it is above `T_i = max(k · s_i, k · q_i / c, f)`, with
/// `k` the [threshold](SpikeParams::threshold) in robust standard deviations, `f` the absolute
/// [floor](SpikeParams::floor), `s_i` the block scale and `q_i / c` the local scale:
///
/// - the block scale: the centred residuals are cut into blocks of
///   [`block`](SpikeParams::block) samples; the median `L_b` of `|r|` is taken over block `b` and
///   its two neighbours (`N = 3 · block` residuals); the record's median `G` is the median of the
///   `L_b`; `s_i = 1.4826 · L_b(i)` where `L_b` exceeds `G` by three of its own standard deviations
///   (`L_b > G (1 + 3 · 1.166 / √N)`, 1.166 / √N being the relative spread of the median of `N`
///   Gaussian absolute values), `s_i = 1.4826 · G` elsewhere; 1.4826 is the ratio of the standard
///   deviation of a Gaussian to its median absolute value;
/// - the local scale: over the 96 positions nearest to the outlier whose statistics hold none of
///   its residuals (48 on each side; near the ends of the record as many as there are within 48,
///   a multiple of 16 and at least 48, or no local scale), the statistic of width `m` at each
///   position, counted at most as large as the largest of its 16 partners 2 `max_run` + 3 to
///   2 `max_run` + 10 positions away on either side; `q_i` is the 6th largest of these 96 levels
///   (the (count / 16)-th of a shorter window), and `c = 6 / κ` with `κ` = 3.649 for 96
///   positions (3.793, 3.963 and 4.200 for 80, 64 and 48).
///
/// The block scale follows a record that is fast in places and slow elsewhere: at 25 samples
/// per forcing period the smooth motion's own residual `h⁴ x⁗ / 6` reaches 15 counts of a
/// 4096-count encoder in a burst of fast motion and stays below one count between bursts; with the
/// record's scale alone such a record gets thousands of false detections. Using a block's median
/// only where it stands out keeps a noisy record's threshold at the record's (the block's median
/// scatters by 8 % around it with the default block, which would otherwise raise the threshold
/// where it happens to be high), and the record's median is a lower bound where the residuals
/// happen to be small (or a quantised stretch where most residuals are exactly zero).
///
/// The local scale follows the noise where its level changes faster than the block scale can see: a
/// vibrometer's noise rises where the returned light is weak, in bursts of tens to hundreds of
/// samples, and the block's median over 192 residuals, or a record's median, puts ordinary samples
/// of such a burst at many times the scale (bursts of 100 samples at five times the noise level
/// gave 324 to 468 false alarms in `4 · 10⁵` samples with the block scale alone, none with the
/// local scale). The factor `c` makes the local test alone pass white Gaussian noise `10⁻⁶` times
/// per sample at `k = 6` (3.649 is the `κ` with `E[P(|r| > κ q)] = 10⁻⁶` over the distribution of
/// `q` in white noise, the residual taken as independent of its window; a direct count at `10⁻⁴`
/// and `10⁻⁵` finds 0.74 and 0.8 of that rate). Where the noise is stationary the block scale holds
/// the rate at `2 · 10⁻⁹`, and the local one only raises the threshold. A residual without a
/// partner as large nearby is an outlier's (a spike or a run reaches at most 2 `max_run` + 3
/// consecutive positions of a statistic), so a spike or run near another does not raise the other's
/// threshold, while noise whose level has risen has partners as large; where outliers are so close
/// that they are one another's partners, the search is repeated after their repair (see below). The
/// price is the smallest spike found: the local threshold `k q / c` is above `k` robust standard
/// deviations at about half of the positions of stationary noise, so a spike of 7 standard
/// deviations is found about 0.72 of the time where the threshold 6 alone would find 0.84
/// (`docs/spikes.md` has the rates). The window is the trade: shorter windows follow faster changes
/// of the level and miss more small spikes (48 positions on each side keep a spike of 7 standard
/// deviations at σ = 0.01 rad found in more than half of the cases at every rate).
///
/// The floor keeps a record whose residuals are mostly zero (a quantised record at rest, a
/// noise-free simulation of a piecewise polynomial) from flagging rounding-level wiggles: by
/// default a millionth of the span (one turn on the circle, `max − min` on the line), far above
/// the rounding of `f64` and of `f32` storage and far below any bit error of an encoder with up to
/// 2²⁰ counts per turn. A record rounded to multiples of a quantum `q` (an encoder's count, `2π /
/// counts` on the circle) has rounding residuals up to `(1 + 10/6) q / 2 = 4q/3`:
/// [`with_quantum`](SpikeParams::with_quantum) sets the floor to `2q`.
///
/// # Isolating the outlier
///
/// An outlier also enters the residuals of the samples whose prediction holds it (two on each
/// side inside the record, and samples 0, 1 from up to sample 4). The record is swept in order;
/// at the first sample `i` one of whose statistics exceeds its block threshold, the outlier is
/// placed where the statistics stand out most from their thresholds (block and local, the latter
/// from the residuals around `i`'s) among `i ..= i + 6` (a spike's or run's residuals start two
/// samples before it, and the sums of up to `max_run` residuals reach them from further back), at
/// `c` with width `m`, and that statistic must exceed its threshold with the local scale taken
/// around `c`. The candidates are then the runs whose residuals reach the residuals of that
/// statistic (`c − 2 ..= c + m + 1`) and whose samples all exceed their threshold, and the samples
/// whose change reaches theirs (their predictions are made from those) that exceed their
/// threshold: `c − 2 − e ..= c + m + 1 + e` with `e = 2 (max_run − 1)` (`c − 2 ..= c + 2` for
/// isolated spikes inside the record, `0 ..= 4` at the start). Each is replaced in turn by its
/// prediction, and the single sample whose replacement leaves the smallest sum of
/// `(|r_m| / g_m)²` over the samples within two of the candidates (and the first or last two
/// samples, whose predictions reach four samples in) is chosen (ties: the larger residual, then
/// the earlier sample), or the best run as above: the spike itself, whose removal clears every
/// neighbour's residual, also where the smooth motion's residual is a sizeable part of the spike
/// (a plain "largest residual" rule picks a neighbour there, whose residual is `2/3` of the
/// spike's plus the motion's). The choice is made again among the candidates around the one
/// chosen until it holds, at most four times. The chosen sample or run is replaced by its
/// prediction at once, and the sweep steps back to two samples before it (or to `i` if that is
/// earlier), so the neighbours are tested again with the repaired values. It is flagged only if
/// its repair leaves at most half of the sum over the residuals within two samples of its reach
/// (`j − 4 ..= j + 4` for a sample `j`): a spike's repair clears the residuals around it (a spike
/// at the threshold of 6 robust standard deviations leaves about a sixth), while the smooth
/// motion's own residual, which in a noise-free record sampled finely can stand out of its scale
/// in a burst of fast motion, is only moved to the neighbours by a repair (the sum grows): such a
/// sample is not a spike, whatever its ratio to the scale. A peak that is rejected (its statistic
/// below its threshold with the local scale taken around it, no candidate chosen, or a repair that
/// does not clear) is passed: the sweep goes on from the sample after the peak, since the samples
/// before it found it the largest of their reach and would find it again (a burst of fast motion
/// exceeds at several consecutive samples, and each would weigh the same candidates). A repair
/// that does not clear passes the samples whose own residual it reaches too (the sweep goes on
/// from three samples after the choice, if that is later): their peaks weigh mostly the same
/// candidates around the same burst and choose, as a rule, the same sample, whose repair, with the
/// record unchanged, clears no better. On a whirling double pendulum sampled at 64 per drive
/// period, noise-free, a rejected choice was weighed 2.2 times on average before, 1.1 times now,
/// and every flag of the tables in `docs/spikes.md` is as it was.
///
/// Most such peaks are not weighed at all: before its peak is looked for, a sample is passed
/// (the sweep goes on from the next one) when no repair the search from it could choose would
/// clear, those starting up to four recentrings (24 samples with the default runs) from the
/// samples its peak can be at. That is decided for every repair at once, in closed form, on the
/// record unwrapped locally: a repair moves its samples to their prediction and the residuals
/// within two samples by those moves times their weights in the predictions (`1`, `−2/3`,
/// `1/6`), and before that its gain is bounded by the squared distance of the residuals it
/// reaches to a cubic, from their fourth differences (no move of its samples takes more from
/// their energy: a move's residuals are orthogonal to the cubics there). On that record one
/// repair in a thousand could clear, and the search takes 0.07 s per 10⁶ samples of an angle
/// instead of 0.19 s. Where a step reaches π/4 (π/5 with runs of 4) or a residual a radian,
/// where the residuals' squares could overflow, near the ends of the record, and within rounding
/// (a millionth of the energy and a thousand times the rounding of the values), a repair counts
/// as one that could clear. Where noise surrounds the samples, nearly half of the repairs could,
/// and the test is work in vain: after eight samples that needed new tests and found a repair
/// that could clear, none passed between them, the next 64 are searched without it. A sample so
/// passed can flag nothing, and every flag of `docs/spikes.md` and of the tests is as it was
/// without the test.
///
/// A repair moves sample `j` by minus the residual its clean value would have had, which is at
/// most its threshold `g_j T_j`, and that enters sample `i`'s residual with the weight `c_ij` of
/// `x_j` in `p_i` (`2/3` and `1/6` inside the record); so a sample whose prediction holds repaired
/// samples has its threshold raised by `Σ c_ij g_j T_j / g_i` (with the thresholds the repaired
/// samples were flagged with, and for a run's samples their prediction's noise gain), and the
/// repair of a spike cannot make a false one of its neighbour. A sample is flagged once at most.
/// When a sweep has flagged anything, the search sweeps again over the samples within reach of
/// the local scales of what it flagged (±158 samples with the defaults), until a sweep flags
/// nothing new (at most eight sweeps): an outlier hidden by another's contribution to its local
/// scale is found once the other is repaired. Two spikes closer than three samples bias each
/// other's predictions and are taken for a run or resolved unreliably. Noise can also make a
/// spike just above the threshold fit worse than its neighbour: of 1552 spikes of 7 robust
/// standard deviations (64 counts at σ = 0.01 rad, 100 and 490 samples per period), 2 had the
/// neighbour flagged instead with the block scale alone (the rule "largest residual" errs less
/// there but fails where the motion's own residual is large).
///
/// # Cost
///
/// `O(n)` time with a small constant: the block scale is one pass computing each residual once
/// and a selection (linear time) of the median of each `3 · block` window; the sweep reads each
/// sample's statistics from a stretch of a few thousand samples where each residual is computed
/// once more. Around a sample whose statistic exceeds its block threshold, the local scales come
/// from the stretch's levels, each computed once (the partners' largest by a sliding maximum) and
/// patched where a repair changes the record; a lower bound of the local threshold, the largest
/// levels of blocks of 8 inside the window, settles most such samples (where the smooth motion's
/// own residual stands out of its block: a fifth of the samples of the paper's noise-free
/// chaotic record at 25 per period), and a selection among the 96 levels is made only where it
/// does not; a few dozen residuals per candidate. Memory: the scale's blocks (`n / block`
/// numbers), the stretch (about 4300 positions: statistics and levels of each width, 300 kB),
/// one bit per sample for the flags and a map of the flagged samples' bounds, and a copy of the
/// record here (none for [`find_and_repair_spikes`]). Computing the local scales afresh from the
/// residuals at each such sample, as the search did before, took some ten thousand operations
/// each: `3.2 · 10¹⁰` instructions per 10⁶ samples of that record, `7.8 · 10⁸` now. On the
/// project's 2-core machine under load, per 10⁶ samples: 0.11 s for that record (3.2 s before),
/// 0.06 s for a noisy vibrometer record or an encoder's, 0.11 s with a bit error per thousand
/// samples and 0.1 s where the noise level changes within tens of samples (`docs/spikes.md`).
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

/// Finds the outliers of `x` as [`find_spikes`] does, searching `x` itself and leaving it as it
/// was (the search repairs what it finds as it goes; here those samples are put back at the
/// end): the same outliers without a copy of the record.
///
/// ```
/// use circle_signal::{Domain, SpikeParams, find_spikes, find_spikes_in_place};
///
/// let mut x: Vec<f64> = (0..2000).map(|i| (i as f64 * 0.05).sin()).collect();
/// x[900] += 0.5;
/// let before = x.clone();
/// let params = SpikeParams::new();
/// let found = find_spikes_in_place(&mut x, Domain::Line, &params)?;
/// assert_eq!(x, before);
/// assert_eq!(found, find_spikes(&x, Domain::Line, &params)?);
/// assert_eq!(found.indices().collect::<Vec<_>>(), vec![900]);
/// # Ok::<(), circle_signal::CircleError>(())
/// ```
pub fn find_spikes_in_place(
    x: &mut [f64],
    domain: Domain,
    params: &SpikeParams,
) -> Result<Spikes, CircleError> {
    check_searchable(x)?;
    let (spikes, originals) = search(x, domain, params, true);
    for (i, v) in originals {
        x[i] = v;
    }
    Ok(spikes)
}

/// Finds the outliers of `x` and replaces each by its local prediction, in place; the same
/// outliers as [`find_spikes`], without a copy of the record.
///
/// On error `x` is unchanged.
pub fn find_and_repair_spikes(
    x: &mut [f64],
    domain: Domain,
    params: &SpikeParams,
) -> Result<Spikes, CircleError> {
    check_searchable(x)?;
    Ok(search(x, domain, params, true).0)
}

/// Whether `x` can be searched: finite, and at least [`SpikeParams::MIN_SAMPLES`] long.
fn check_searchable(x: &[f64]) -> Result<(), CircleError> {
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
    Ok(())
}

/// The search of [`find_and_repair_spikes`] on a record it takes, with or without the
/// `shortcuts` that spare it work: the outliers, and the values of the samples it replaced. The
/// held residuals and ranked windows change nothing; the pass of samples from which no repair
/// could clear (see "Isolating the outlier" on [`find_spikes`]) flags nothing at those samples
/// but goes on from the next sample where the full search of a rejected peak goes on past it,
/// so it could in principle change what a later sample finds. The tests compare the outliers
/// with and without them: the same, to the bit, on every record they hold.
fn search(
    x: &mut [f64],
    domain: Domain,
    params: &SpikeParams,
    shortcuts: bool,
) -> (Spikes, Vec<(usize, f64)>) {
    match domain {
        Domain::Circle => Search::<OnCircle>::run(x, params, TAU, shortcuts),
        Domain::Line => {
            let (lo, hi) = x.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            });
            Search::<OnLine>::run(x, params, hi - lo, shortcuts)
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
        let (r, p) = centred::<G>(&x[i - 2..i + 3]);
        return (r, x[i - 1] + p);
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

/// The centred residual of the middle one of five samples `w` and its prediction relative to
/// `w[1]` (see [`predict`]).
#[inline]
fn centred<G: Geometry>(w: &[f64]) -> (f64, f64) {
    let d = G::diff;
    let &[x0, x1, x2, x3, x4] = w else {
        unreachable!("five samples");
    };
    let a = d(x0 - x1);
    let b = d(x3 - x1);
    let c = b + d(x4 - x3);
    let p = (4.0 * b - a - c) / 6.0;
    (d(x2 - x1 - p), p)
}

/// The centred residuals of samples `from .. to` (all inside the record: `2 ≤ from`,
/// `to ≤ n − 2`), appended to `out`.
fn centred_residuals<G: Geometry>(x: &[f64], from: usize, to: usize, out: &mut Vec<f64>) {
    if from < to {
        out.extend(x[from - 2..to + 2].windows(5).map(|w| centred::<G>(w).0));
    }
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

/// The `rank` largest levels of width `m` (index `m − 1`) of `parts` in decreasing order (by
/// [`f64::total_cmp`]), `rank` from 1 to [`KEPT`], `−∞` past the levels there are: one pass
/// holding the largest `rank` in order, cheaper than a selection for the few a local scale ranks.
///
/// Levels are numbers from `+0` up (never NaN, never `−0`: see `Stretch::compute_levels`),
/// whose bits, as unsigned integers, order as [`f64::total_cmp`] orders them; they are compared
/// so.
fn largest_levels(parts: [&[[f64; MAX_RUN]]; 2], m: usize, rank: usize) -> [f64; KEPT] {
    let mut top = [0u64; KEPT];
    let mut held = 0;
    for part in parts {
        for level in part {
            let v = level[m - 1].to_bits();
            debug_assert!(v >> 63 == 0 && !level[m - 1].is_nan(), "a level {}", level[m - 1]);
            if held == rank {
                if v <= top[rank - 1] {
                    continue;
                }
            } else {
                held += 1;
            }
            let mut at = held - 1;
            while at > 0 && v > top[at - 1] {
                top[at] = top[at - 1];
                at -= 1;
            }
            top[at] = v;
        }
    }
    std::array::from_fn(|k| {
        if k < held {
            f64::from_bits(top[k])
        } else {
            f64::NEG_INFINITY
        }
    })
}

/// Puts `value` among the largest `top` (decreasing by [`f64::total_cmp`]) if it is larger than
/// the last, which then leaves.
#[inline]
fn push_largest(top: &mut [f64], value: f64) {
    let rank = top.len();
    if value.total_cmp(&top[rank - 1]).is_le() {
        return;
    }
    let mut at = rank - 1;
    while at > 0 && value.total_cmp(&top[at - 1]).is_gt() {
        top[at] = top[at - 1];
        at -= 1;
    }
    top[at] = value;
}

/// The largest rank a local scale takes: the 6th largest of 96 levels.
const MAX_LOCAL_RANK: usize = 2 * LOCAL_HALF_WINDOW / LOCAL_STEP;

/// Median of a non-empty slice (the upper one of an even count), reordering it.
fn median(v: &mut [f64]) -> f64 {
    let mid = v.len() / 2;
    *v.select_nth_unstable_by(mid, f64::total_cmp).1
}

struct Search<'a, G> {
    x: &'a mut [f64],
    /// Threshold of a centred residual, per block: the record's or block's scale, and the floor.
    thresholds: Vec<f64>,
    block: usize,
    /// The threshold `k` in robust standard deviations.
    k: f64,
    /// Longest run of samples replaced together.
    max_run: usize,
    /// One bit per sample: flagged already.
    flagged: Vec<u64>,
    /// Per flagged sample: the largest error its repair can have left in it, in the record's
    /// unit (its prediction's noise gain times its threshold when it was flagged).
    bounds: BTreeMap<usize, f64>,
    spikes: Vec<Spike>,
    /// The samples flagged and their values before, in the order flagged (each once).
    originals: Vec<(usize, f64)>,
    /// The statistics and the local scale's levels of the stretch being swept.
    stretch: Stretch,
    /// Per sample: whether a repair starting there could clear the residuals around it.
    clearing: Clearing,
    /// Samples that needed new tests in vain since the last passed, and samples left to search
    /// without the test.
    in_vain: usize,
    untested: usize,
    /// Per use ([`SEARCHING`] or [`PEAK`]) and width of a statistic: the window last ranked for
    /// its local scale and its largest levels, which the next window, mostly the same positions,
    /// is ranked from (none after a repair).
    ranked: [[Option<Ranked>; MAX_RUN]; 2],
    /// Per sample `i` (at `i % HELD`, with `i`): its residual in the record as it stands and
    /// its term of an energy (none after a repair). The choices of outliers read each residual
    /// around them many times, with a candidate's samples replaced and without.
    held: Vec<(usize, Held)>,
    /// Per candidate inside the record (at `start % HELD` and its length, with `start`): the
    /// terms of an energy of samples `start − 2 ..= end + 2` with its samples replaced by their
    /// predictions (none after a repair): the choices of outliers around nearby peaks consider
    /// the same candidates.
    repaired: Vec<(usize, [f64; MAX_RUN + 4])>,
    /// The terms of an energy over `window` in the record as it stands (when `window` is
    /// `Some`; none after a repair): every candidate of a choice is weighed over one window.
    terms: Vec<f64>,
    window: Option<(usize, usize)>,
    /// Whether the search spares itself work by the held residuals and the
    /// ranked windows (always but in the tests, which compare the outliers found without them).
    shortcuts: bool,
    _geometry: std::marker::PhantomData<G>,
}

/// The positions of a local scale's window: `left` and `right` of the outlier's (half-open), and
/// the `steps` of [`LOCAL_STEP`] positions they hold.
#[derive(Debug, Clone, Copy)]
struct LocalWindow {
    left: (usize, usize),
    right: (usize, usize),
    steps: usize,
}

/// A residual held for the choice of an outlier, and its term of an energy (its square over the
/// squared noise gain).
#[derive(Debug, Clone, Copy, Default)]
struct Held {
    residual: f64,
    term: f64,
}

/// Samples whose residuals, and whose repairs' terms, the search holds at once: more than a
/// choice of an outlier reads.
const HELD: usize = 128;

/// The largest levels of a local scale's window: the first `kept` of `top`, decreasing by
/// [`f64::total_cmp`], at least `window.steps` of them; every other level of the window is at
/// most as large as the last of them.
#[derive(Debug, Clone, Copy)]
struct Ranked {
    window: LocalWindow,
    top: [f64; KEPT],
    kept: usize,
}

/// The levels a window ranked afresh keeps: twice the largest rank, so that as the window moves
/// on, some of its largest can leave it before it must be ranked afresh.
const KEPT: usize = 2 * MAX_LOCAL_RANK;

/// The local windows of the sweep's search for a peak, which move on with the sample searched
/// from.
const SEARCHING: usize = 0;

/// The local windows of a peak: near the search's (the peak is among the next few samples), and
/// near the last peak's when that was near.
const PEAK: usize = 1;

/// The most levels that leave and enter a window ranked from the last one: beyond them, ranking
/// the window afresh costs about as much.
const SLIDE: usize = 48;

/// A repair considered: one sample, or a run of `len` samples from `start` replaced together by
/// the cubic through the two samples on each side.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Candidate {
    start: usize,
    len: usize,
}

impl Candidate {
    fn end(&self) -> usize {
        self.start + self.len - 1
    }
}

impl<'a, G: Geometry> Search<'a, G> {
    fn run(
        x: &'a mut [f64],
        params: &SpikeParams,
        span: f64,
        shortcuts: bool,
    ) -> (Spikes, Vec<(usize, f64)>) {
        let n = x.len();
        let floor = params.floor.unwrap_or(SpikeParams::DEFAULT_FLOOR_FRACTION * span);
        let block = params.block;
        let (record_median, locals) = scales::<G>(x, block);
        let scale = MAD_TO_SD * record_median;
        if floor.is_nan() || floor <= 0.0 {
            // A constant record on the line: nothing departs from anything.
            return (
                Spikes {
                    spikes: Vec::new(),
                    len: n,
                    domain: G::DOMAIN,
                    scale,
                    floor,
                },
                Vec::new(),
            );
        }
        // A block's median is used where it stands out of the record's by three of its own
        // standard deviations (relative `MEDIAN_SPREAD / √(3 block)` for Gaussian residuals).
        let significant = record_median * (1.0 + 3.0 * MEDIAN_SPREAD / ((3 * block) as f64).sqrt());
        let thresholds = locals
            .into_iter()
            .map(|l| {
                let s = if l > significant { l } else { record_median };
                (params.threshold * MAD_TO_SD * s).max(floor)
            })
            .collect();
        let mut search = Self::new(x, thresholds, block, params.threshold, params.max_run, shortcuts);
        search.search();
        let mut spikes = search.spikes;
        spikes.sort_unstable_by_key(|s| s.index);
        (
            Spikes {
                spikes,
                len: n,
                domain: G::DOMAIN,
                scale,
                floor,
            },
            search.originals,
        )
    }

    /// A search of `x` against `thresholds` (one per sample), nothing found yet: `block` and `k`
    /// of the local scales, runs of at most `max_run` samples.
    fn new(
        x: &'a mut [f64],
        thresholds: Vec<f64>,
        block: usize,
        k: f64,
        max_run: usize,
        shortcuts: bool,
    ) -> Self {
        let n = x.len();
        Self {
            x,
            thresholds,
            block,
            k,
            max_run,
            flagged: vec![0; n.div_ceil(64)],
            bounds: BTreeMap::new(),
            spikes: Vec::new(),
            originals: Vec::new(),
            stretch: Stretch::new(n, max_run),
            clearing: Clearing::new(n, max_run),
            in_vain: 0,
            untested: 0,
            ranked: [[None; MAX_RUN]; 2],
            held: vec![(usize::MAX, Held::default()); HELD],
            repaired: vec![(usize::MAX, [0.0; MAX_RUN + 4]); HELD * MAX_RUN],
            terms: Vec::new(),
            window: None,
            shortcuts,
            _geometry: std::marker::PhantomData,
        }
    }

    /// `|r_i|` over the noise gain of its prediction, comparable between neighbours.
    #[inline]
    fn weighted(&self, i: usize) -> f64 {
        self.residual(i).abs() / gain(self.x.len(), i)
    }

    /// The residual of sample `i` (as [`predict`] gives it), from those held when it is.
    #[inline]
    fn residual(&self, i: usize) -> f64 {
        match self.held[i % HELD] {
            (at, held) if at == i => held.residual,
            _ => predict::<G>(self.x, i).0,
        }
    }

    /// The squared weighted residual of sample `i`, its term of an [`energy`](Self::energy),
    /// from those held when it is.
    #[inline]
    fn term(&self, i: usize) -> f64 {
        match self.held[i % HELD] {
            (at, held) if at == i => held.term,
            _ => self.weighted(i).powi(2),
        }
    }

    /// Holds the residuals of samples `from ..= to` (clamped to the record) of the record as it
    /// stands (those not held already), until the next repair.
    fn hold_residuals(&mut self, from: usize, to: usize) {
        if !self.shortcuts {
            return;
        }
        let x = &*self.x;
        let n = x.len();
        for j in from..=to.min(n - 1) {
            let slot = &mut self.held[j % HELD];
            if slot.0 != j {
                let residual = predict::<G>(x, j).0;
                let term = (residual.abs() / gain(n, j)).powi(2);
                *slot = (j, Held { residual, term });
            }
        }
    }

    /// The terms of an energy of samples `c.start − 2 ..= c.end + 2` with the candidate's samples
    /// (inside the record, 5 to `n − 6`) replaced by their predictions, held until the next
    /// repair.
    fn repaired_terms(&mut self, c: Candidate) -> [f64; MAX_RUN + 4] {
        let slot = (c.start % HELD) * MAX_RUN + c.len - 1;
        if let (at, terms) = self.repaired[slot]
            && at == c.start
        {
            return terms;
        }
        let old = self.apply(c);
        let n = self.x.len();
        let mut terms = [0.0; MAX_RUN + 4];
        for (term, m) in terms.iter_mut().zip(c.start - 2..=c.end() + 2) {
            *term = (predict::<G>(self.x, m).0.abs() / gain(n, m)).powi(2);
        }
        self.restore(c, old);
        self.repaired[slot] = (c.start, terms);
        terms
    }

    /// The statistics of sample `i` by width `m` (index `m − 1`): its weighted residual
    /// (`m = 1`), and inside the record the sums of the centred residuals of `i ..= i + m − 1`
    /// over their noise gains for white noise (`m` up to the longest run; 0 where the record
    /// ends), which a run of `m` samples from `i` makes about as large as a single spike of its
    /// size makes its own residual.
    #[inline]
    fn statistics(&mut self, i: usize) -> [f64; MAX_RUN] {
        self.stretch.stats::<G>(self.x, i)
    }

    /// The block's threshold of sample `i` (the record's or the block's scale, and the floor).
    #[inline]
    fn block_threshold(&self, i: usize) -> f64 {
        self.thresholds[i / self.block]
    }

    /// What the repairs of flagged samples among `samples` (with the magnitudes of their
    /// weights in a prediction) can have put into that prediction, over its noise gain `g`.
    fn raise(&self, samples: &[(usize, f64)], g: f64) -> f64 {
        let raise: f64 = samples
            .iter()
            .filter(|&&(j, _)| self.is_flagged(j))
            .map(|&(j, c)| c * self.bounds.get(&j).copied().unwrap_or(0.0))
            .sum();
        raise / g
    }

    /// The window of the local scale of the statistic of width `m` around an outlier whose
    /// residuals lie in `c − 2 ..= c + width + 1`: the positions nearest to it whose statistics
    /// hold none of those residuals, up to [`LOCAL_HALF_WINDOW`] on each side, a multiple of
    /// [`LOCAL_STEP`] (96 inside the record, down to 48 near its ends); `None` where the record is
    /// too short for one.
    fn local_window(&self, c: usize, width: usize, m: usize) -> Option<LocalWindow> {
        let n = self.x.len();
        let w = LOCAL_HALF_WINDOW;
        // The centred residuals the window, its sums and the partners reach.
        let gap = 2 * self.max_run + 3;
        let reach = w + width + 2 + gap + LOCAL_PARTNERS + 2 * self.max_run;
        let first = c.saturating_sub(reach).max(2);
        let last = (c + reach).min(n - 3);
        if last < first + 2 * LOCAL_STEP {
            return None;
        }
        // The last position of a statistic of width m (its residuals up to `last`).
        let top = last + 1 - m;
        let (lo_out, hi_out) = ((c + 1).saturating_sub(2 + m), c + width + 1);
        let left = lo_out.saturating_sub(first).min(w);
        let right = top.saturating_sub(hi_out).min(w);
        let count = ((left + right) / LOCAL_STEP * LOCAL_STEP).min(2 * w);
        if count < 3 * LOCAL_STEP {
            return None;
        }
        // Dropping the farthest positions, from the longer side.
        let (mut left, mut right) = (left, right);
        while left + right > count {
            if left > right {
                left -= 1;
            } else {
                right -= 1;
            }
        }
        Some(LocalWindow {
            left: (lo_out - left, lo_out),
            right: (hi_out + 1, hi_out + 1 + right),
            steps: count / LOCAL_STEP,
        })
    }

    /// The windows of the statistics of width 1 to the longest run, with their levels made
    /// available.
    fn local_windows(&mut self, c: usize, width: usize) -> [Option<LocalWindow>; MAX_RUN] {
        let mut windows = [None; MAX_RUN];
        let (mut a, mut b) = (usize::MAX, 0);
        for m in 1..=self.max_run {
            windows[m - 1] = self.local_window(c, width, m);
            if let Some(w) = windows[m - 1] {
                for (from, to) in [w.left, w.right].into_iter().filter(|(from, to)| from < to) {
                    a = a.min(from);
                    b = b.max(to - 1);
                }
            }
        }
        if a <= b {
            self.stretch.ensure_levels::<G>(self.x, a, b);
        }
        windows
    }

    /// The threshold of a local scale `q` in a window of `steps` steps: `k q / c`.
    #[inline]
    fn local_threshold(&self, q: f64, steps: usize) -> f64 {
        self.k * q * LOCAL_KAPPA[steps - 3] / 6.0
    }

    /// The local threshold of the statistic of width `m` over its window `w`: `k` times its
    /// local scale, the `steps`-th largest level (the (count / 16)-th largest).
    fn local_threshold_in(&mut self, w: LocalWindow, m: usize, using: usize) -> f64 {
        let q = match self.slide(w, m, using) {
            Some(q) => q,
            None => self.rank(w, m, using),
        };
        self.local_threshold(q, w.steps)
    }

    /// The `steps`-th largest level of width `m` in window `w`, ranked afresh (and kept for the
    /// next window).
    fn rank(&mut self, w: LocalWindow, m: usize, using: usize) -> f64 {
        let stretch = &self.stretch;
        let (left, right) = (stretch.levels(w.left), stretch.levels(w.right));
        let kept = KEPT.min(left.len() + right.len());
        let top = largest_levels([left, right], m, kept);
        self.ranked[using][m - 1] = Some(Ranked { window: w, top, kept });
        top[w.steps - 1]
    }

    /// The `steps`-th largest level of width `m` in window `w`, from the largest levels kept of
    /// the window last ranked for width `m`, when at most [`SLIDE`] levels leave and enter and
    /// enough of those kept stay; `None` otherwise. A level that leaves and is at least the last
    /// kept is one of those kept (every other is at most as large) and leaves them; one that
    /// enters joins them if it is at least the last of them (when they are fewer than [`KEPT`])
    /// or larger than it (the last then leaving them); every level left out is then still at
    /// most the last kept.
    fn slide(&mut self, w: LocalWindow, m: usize, using: usize) -> Option<f64> {
        if !self.shortcuts {
            return None;
        }
        let near = |slot: &Option<Ranked>| {
            let (leaving, entering) = moved(slot.as_ref()?.window, w);
            (leaving.count() + entering.count() <= SLIDE).then_some((leaving, entering))
        };
        // A peak's window from the last peak's, or else from the search's.
        let (leaving, entering) = match near(&self.ranked[using][m - 1]) {
            Some(moved) => moved,
            None if using == PEAK => {
                let moved = near(&self.ranked[SEARCHING][m - 1])?;
                self.ranked[PEAK][m - 1] = self.ranked[SEARCHING][m - 1];
                moved
            }
            None => return None,
        };
        let (leaving, entering) = (leaving.as_slice(), entering.as_slice());
        // The levels that leave are held by the stretch (those that enter are, in `w`).
        if let (Some(first), Some(last)) = (leaving.first(), leaving.last())
            && !self.stretch.holds_levels(first.0, last.1 - 1)
        {
            return None;
        }
        let stretch = &self.stretch;
        let slot = self.ranked[using][m - 1].as_mut()?;
        let (top, kept) = (&mut slot.top, &mut slot.kept);
        let rank = w.steps;
        for &range in leaving {
            for level in stretch.levels(range) {
                let v = level[m - 1];
                if v.total_cmp(&top[*kept - 1]).is_lt() {
                    continue;
                }
                // Among those kept (every level left out is at most the last of them).
                let Some(at) = top[..*kept].iter().position(|t| t.total_cmp(&v).is_eq()) else {
                    self.ranked[using][m - 1] = None;
                    return None;
                };
                top.copy_within(at + 1..*kept, at);
                *kept -= 1;
                if *kept < rank {
                    self.ranked[using][m - 1] = None;
                    return None;
                }
            }
        }
        for &range in entering {
            for level in stretch.levels(range) {
                let v = level[m - 1];
                if *kept == KEPT {
                    push_largest(top, v);
                } else if v.total_cmp(&top[*kept - 1]).is_ge() {
                    let mut at = *kept;
                    while at > 0 && v.total_cmp(&top[at - 1]).is_gt() {
                        top[at] = top[at - 1];
                        at -= 1;
                    }
                    top[at] = v;
                    *kept += 1;
                }
            }
        }
        if *kept < rank {
            self.ranked[using][m - 1] = None;
            return None;
        }
        slot.window = w;
        Some(slot.top[rank - 1])
    }

    /// The local thresholds of the statistics of width 1 to the longest run (see
    /// [`statistics`](Self::statistics)) around an outlier whose residuals lie in `c − 2 ..=
    /// c + width + 1`: `k` times the local scale of each statistic over its
    /// [window](Self::local_window) (0 where there is none).
    fn local_thresholds(&mut self, c: usize, width: usize) -> [f64; MAX_RUN] {
        let mut out = [0.0; MAX_RUN];
        let windows = self.local_windows(c, width);
        for m in 1..=self.max_run {
            if let Some(w) = windows[m - 1] {
                out[m - 1] = self.local_threshold_in(w, m, PEAK);
            }
        }
        out
    }

    /// The local thresholds around `c` (as [`local_thresholds`](Self::local_thresholds)) of the
    /// widths whose largest statistic among the samples tested, `above` (0 for none), can exceed
    /// them; `∞` for the others, whose statistics cannot stand out of their local thresholds, and
    /// `None` when none can.
    ///
    /// A width's statistics cannot when `above` is at most its threshold, where that is found
    /// cheaply from the last window's ([`slide`](Self::slide)), or at most a lower bound of it,
    /// taken without a selection: the `steps`-th largest of the maxima of the blocks of
    /// [`LEVEL_BLOCK`] levels that lie in the window (those blocks hold that many distinct levels
    /// at least as large). This settles most of the samples of a smooth motion whose residual
    /// stands out of its block.
    fn local_thresholds_above(
        &mut self,
        c: usize,
        width: usize,
        above: [f64; MAX_RUN],
    ) -> Option<[f64; MAX_RUN]> {
        let windows = self.local_windows(c, width);
        let mut out = [f64::INFINITY; MAX_RUN];
        let mut any = false;
        for m in 1..=self.max_run {
            if above[m - 1] <= 0.0 {
                continue;
            }
            let Some(w) = windows[m - 1] else {
                // No window, no local threshold: the block's alone.
                out[m - 1] = 0.0;
                any = true;
                continue;
            };
            if let Some(q) = self.slide(w, m, SEARCHING) {
                let threshold = self.local_threshold(q, w.steps);
                if above[m - 1] > threshold {
                    out[m - 1] = threshold;
                    any = true;
                }
                continue;
            }
            let blocks = |(from, to): (usize, usize)| (from.div_ceil(LEVEL_BLOCK), to / LEVEL_BLOCK);
            let settled = self
                .stretch
                .blocks_hold(blocks(w.left), blocks(w.right), m, w.steps, |most| {
                    above[m - 1] <= self.local_threshold(most, w.steps)
                });
            if settled {
                continue;
            }
            let q = self.rank(w, m, SEARCHING);
            out[m - 1] = self.local_threshold(q, w.steps);
            any = true;
        }
        any.then_some(out)
    }

    #[inline]
    fn is_flagged(&self, i: usize) -> bool {
        self.flagged[i / 64] >> (i % 64) & 1 == 1
    }

    /// Flags sample `i` with the given replacement, its bound and its size.
    fn flag(&mut self, i: usize, size: f64, replacement: f64, bound: f64) {
        self.originals.push((i, self.x[i]));
        self.x[i] = replacement;
        self.stretch.patch::<G>(self.x, i, i);
        self.clearing.changed(i);
        self.flagged[i / 64] |= 1 << (i % 64);
        self.held.fill((usize::MAX, Held::default()));
        self.repaired.fill((usize::MAX, [0.0; MAX_RUN + 4]));
        self.window = None;
        self.ranked = [[None; MAX_RUN]; 2];
        self.bounds.insert(i, bound);
        self.spikes.push(Spike {
            index: i,
            size,
            replacement,
        });
    }

    /// The run's departures from its prediction and the predictions (wrapped on the circle),
    /// per sample of the run.
    fn run_residuals(&self, c: Candidate) -> [(f64, f64); MAX_RUN] {
        let mut out = [(0.0, 0.0); MAX_RUN];
        let d = G::diff;
        let x = &*self.x;
        let (a, b) = (c.start, c.end());
        let base = x[a - 1];
        let u_before = d(x[a - 2] - base);
        let u_after = d(x[b + 1] - base);
        let u_after2 = u_after + d(x[b + 2] - x[b + 1]);
        for (p, slot) in out.iter_mut().enumerate().take(c.len) {
            let w = run_cubic(c.len, p).weights;
            let pred = w[0] * u_before + w[2] * u_after + w[3] * u_after2;
            *slot = (d(x[a + p] - base - pred), G::point(base + pred));
        }
        out
    }

    /// The smallest weighted departure of a run's samples from their prediction if every one
    /// exceeds its threshold (`own` the threshold of a centred residual there), `None` if not.
    fn run_exceeds(&self, c: Candidate, own: f64) -> Option<f64> {
        let n = self.x.len();
        let (a, b) = (c.start, c.end());
        let nodes = [a - 2, a - 1, b + 1, b + 2];
        let res = self.run_residuals(c);
        // A departure less the smooth motion's part is at most the departure: a sample that does
        // not exceed without it does not exceed with it (most runs a choice weighs end here,
        // before the smooth motion's residual is taken).
        if res[..c.len]
            .iter()
            .enumerate()
            .any(|(p, &(r, _))| r.abs() / run_cubic(c.len, p).gain <= own)
        {
            return None;
        }
        // The smooth motion's residual there: the mean of the centred residuals over the run's
        // reach and two more on each side, from which any departure of the run's samples
        // cancels (the fourth differences of a local bump sum to zero).
        let (lo, hi) = (a.saturating_sub(4).max(2), (b + 4).min(n - 3));
        let smooth = ((lo..=hi).map(|j| self.residual(j)).sum::<f64>() / (hi + 1 - lo) as f64).abs();
        let mut least = f64::INFINITY;
        for (p, &(r, _)) in res.iter().enumerate().take(c.len) {
            let cubic = run_cubic(c.len, p);
            let (w, g) = (cubic.weights, cubic.gain);
            let stencil = [
                (nodes[0], w[0].abs()),
                (nodes[1], w[1].abs()),
                (nodes[2], w[2].abs()),
                (nodes[3], w[3].abs()),
            ];
            // The run's prediction misses a smooth motion by `run_smooth_gain` times its residual.
            let v = (r.abs() - cubic.smooth_gain * smooth).max(0.0) / g;
            if !(v > own && v > own + self.raise(&stencil, g)) {
                return None;
            }
            least = least.min(v);
        }
        Some(least)
    }

    /// Replaces the candidate's samples by their predictions, returning the old values.
    fn apply(&mut self, c: Candidate) -> [f64; MAX_RUN] {
        let mut old = [0.0; MAX_RUN];
        if c.len == 1 {
            let (_, prediction) = predict::<G>(self.x, c.start);
            old[0] = self.x[c.start];
            self.x[c.start] = G::point(prediction);
        } else {
            let res = self.run_residuals(c);
            for p in 0..c.len {
                old[p] = self.x[c.start + p];
                self.x[c.start + p] = res[p].1;
            }
        }
        old
    }

    fn restore(&mut self, c: Candidate, old: [f64; MAX_RUN]) {
        self.x[c.start..=c.end()].copy_from_slice(&old[..c.len]);
    }

    /// The sum of the squared weighted residuals over `window` (inclusive).
    fn energy(&self, window: (usize, usize)) -> f64 {
        (window.0..=window.1).map(|m| self.term(m)).sum()
    }

    /// The same with the candidate's samples replaced by their predictions (the record is left
    /// as it was). The residuals the candidate's samples do not enter are the record's (those
    /// held, when they are).
    fn energy_after_repair(&mut self, c: Candidate, window: (usize, usize)) -> f64 {
        let n = self.x.len();
        if self.shortcuts && c.start >= 5 && c.end() + 6 <= n {
            // The residuals it reaches are those of c.start − 2 ..= c.end + 2, all inside the
            // record: the window's terms with those replaced, in order.
            if self.window != Some(window) {
                self.terms.clear();
                for m in window.0..=window.1 {
                    let term = self.term(m);
                    self.terms.push(term);
                }
                self.window = Some(window);
            }
            let repaired = self.repaired_terms(c);
            return sum_replaced(&self.terms, window.0, c.start - 2, &repaired[..c.len + 4]);
        }
        let old = self.apply(c);
        let energy = (window.0..=window.1)
            .map(|m| {
                if reaches(n, m, c) {
                    (predict::<G>(self.x, m).0.abs() / gain(n, m)).powi(2)
                } else {
                    self.term(m)
                }
            })
            .sum();
        self.restore(c, old);
        energy
    }

    /// The candidates around an outlier placed at `at` (a sample, or a run of samples): the runs
    /// whose residuals reach `at`'s residuals (`at.start − 2 ..= at.end + 2`), and the samples
    /// whose change reaches theirs or `at`'s, which the runs' predictions are made from
    /// (inclusive ranges; the samples only when `max_run` is 1).
    fn around(&self, at: Candidate) -> ((usize, usize), (usize, usize)) {
        let n = self.x.len();
        let extra = 2 * (self.max_run - 1);
        let (a, b) = (at.start, at.end());
        let mut span = (a.saturating_sub(2 + extra), (b + 2 + extra).min(n - 1));
        if a <= 1 {
            span = (0, span.1.max(4));
        }
        if b + 2 >= n {
            span = (span.0.min(n - 5), n - 1);
        }
        let runs = (a.saturating_sub(extra).max(2), (b + extra).min(n - 3));
        (span, runs)
    }

    /// The best repair among the candidates: the samples of `span` that exceed their
    /// threshold (`own`) and the runs of two to `max_run` samples inside `runs` whose samples
    /// all do; of those, the single sample whose replacement leaves the residuals they reach
    /// smallest (ties: the larger departure, then the earlier sample), unless the best run
    /// leaves at most half of what the best single repair leaves and less by a noise-level
    /// margin for each sample beyond the first.
    fn choose(
        &mut self,
        span: (usize, usize),
        runs: (usize, usize),
        own: &dyn Fn(&Self, usize, usize) -> f64,
    ) -> Option<Candidate> {
        let n = self.x.len();
        let window = footprint(n, span);
        // The residuals every candidate's energy and test read: the window's, those a run's
        // smooth motion is taken from, and the wider window of a run against a single sample.
        self.hold_residuals(
            window.0.min(runs.0).saturating_sub(2 + 2 * MAX_RUN),
            window.1.max(runs.1) + 2 + 2 * MAX_RUN,
        );
        // The single samples, and whether each exceeds its threshold.
        let mut single: Option<(Candidate, f64, f64)> = None;
        let mut any_single: Option<(Candidate, f64)> = None;
        for j in span.0..=span.1 {
            if self.is_flagged(j) {
                continue;
            }
            let cand = Candidate { start: j, len: 1 };
            let energy = self.energy_after_repair(cand, window);
            if any_single.is_none_or(|(_, e)| energy < e) {
                any_single = Some((cand, energy));
            }
            let w = self.weighted(j);
            let t = own(self, j, 1);
            if !(w > t && w > t + self.raise(&stencil(n, j), gain(n, j))) {
                continue;
            }
            let better = match single {
                None => true,
                Some((_, be, bw)) => energy < be || (energy == be && w > bw),
            };
            if better {
                single = Some((cand, energy, w));
            }
        }
        // The runs whose samples all exceed.
        let (first, last) = runs;
        let mut run: Option<(Candidate, f64, f64)> = None;
        for len in 2..=self.max_run {
            if first + len > last + 1 {
                break;
            }
            for start in first..=last + 1 - len {
                let cand = Candidate { start, len };
                if (start..=cand.end()).any(|j| self.is_flagged(j)) {
                    continue;
                }
                let own_run = (start..=cand.end())
                    .map(|j| own(self, j, len))
                    .fold(0.0, f64::max);
                let Some(w) = self.run_exceeds(cand, own_run) else {
                    continue;
                };
                let energy = self.energy_after_repair(cand, window);
                let better = match run {
                    None => true,
                    Some((_, be, bw)) => energy < be || (energy == be && w > bw),
                };
                if better {
                    run = Some((cand, energy, w));
                }
            }
        }
        // A run must leave at most half of what the best single repair leaves (whether or not
        // that sample exceeds: a run whose prediction is made from a spike departs from it),
        // over the residuals either reaches, and less by what an ordinary sample's noise gives
        // once in a thousand (11 squared robust standard deviations of the residual) for each
        // sample beyond the first.
        if let Some((r, _, _)) = run {
            let Some((s, _)) = any_single else {
                return Some(r);
            };
            let near = footprint(
                n,
                (
                    r.start.min(s.start).saturating_sub(2),
                    (r.end().max(s.end()) + 2).min(n - 1),
                ),
            );
            let er = self.energy_after_repair(r, near);
            let es = self.energy_after_repair(s, near);
            let penalty = RUN_PENALTY * (own(self, r.start, 1) / self.k).powi(2);
            if er <= RUN_CLEARED * es && es - er >= (r.len - 1) as f64 * penalty {
                return Some(r);
            }
        }
        single.map(|(s, _, _)| s)
    }

    /// Sweeps the record, then again around what each sweep found until a sweep finds
    /// nothing new: a spike or run within reach of another's local scale can raise it above
    /// the other one, which the next sweep, with the first repaired, finds.
    fn search(&mut self) {
        let n = self.x.len();
        let reach = 2 * (LOCAL_HALF_WINDOW + 2 * self.max_run + 3 + LOCAL_PARTNERS + PEAK_SEARCH + 8);
        let mut ranges = vec![(0, n)];
        for _ in 0..MAX_SWEEPS {
            let found = self.spikes.len();
            for &(from, to) in &ranges {
                self.sweep(from, to);
            }
            if self.spikes.len() == found {
                break;
            }
            let mut at: Vec<usize> = self.spikes[found..].iter().map(|s| s.index).collect();
            at.sort_unstable();
            ranges.clear();
            for j in at {
                let (from, to) = (j.saturating_sub(reach), (j + reach + 1).min(n));
                match ranges.last_mut() {
                    Some(last) if from <= last.1 => last.1 = last.1.max(to),
                    _ => ranges.push((from, to)),
                }
            }
        }
    }

    /// The first sample of `i .. to` that is not flagged and one of whose statistics exceeds its
    /// block threshold, or `to`.
    fn next_exceeding(&mut self, mut i: usize, to: usize) -> usize {
        while i < to {
            // The stretch that holds sample i.
            self.statistics(i);
            let (lo, stats) = self.stretch.held();
            let end = to.min(lo + stats.len());
            while i < end {
                let b = i / self.block;
                let threshold = self.thresholds[b];
                let stop = end.min((b + 1) * self.block);
                for (p, s) in (i..stop).zip(&stats[i - lo..stop - lo]) {
                    if !s.iter().all(|&v| v <= threshold) && !self.is_flagged(p) {
                        return p;
                    }
                }
                i = stop;
            }
        }
        to
    }

    /// Whether no repair that the search from sample `i` can choose could clear the residuals
    /// around it (see [`could_clear_near`](Self::could_clear_near)), where that is worth
    /// testing: after [`TESTS_IN_VAIN`] samples that needed new tests and found a repair that
    /// could, none passed between them, the next [`UNTESTED`] samples are searched without the
    /// test (where noise surrounds the samples, nearly half of the repairs could clear, and the
    /// test is work in vain).
    fn hopeless(&mut self, i: usize) -> bool {
        if self.untested > 0 {
            self.untested -= 1;
            return false;
        }
        let (could, tested) = self.could_clear_near(i);
        if could {
            // Work in vain where the test had to be made.
            if tested {
                self.in_vain += 1;
                if self.in_vain == TESTS_IN_VAIN {
                    (self.in_vain, self.untested) = (0, UNTESTED);
                }
            }
            return false;
        }
        self.in_vain = 0;
        true
    }

    /// Whether a repair that the search from sample `i` can choose could clear the residuals
    /// around it: those starting up to [`RECENTRE`] recentrings away from the samples its peak
    /// can be at.
    fn could_clear_near(&mut self, i: usize) -> (bool, bool) {
        let drift = RECENTRE * (2 + 2 * (self.max_run - 1));
        let (from, to) = (
            i.saturating_sub(drift),
            i + PEAK_SEARCH + self.max_run - 1 + drift,
        );
        self.clearing.could_clear::<G>(self.x, from, to)
    }

    /// One sweep of samples `from .. to`.
    fn sweep(&mut self, from: usize, to: usize) {
        let n = self.x.len();
        // What the sweep asks of the stretch ends short of its window's reach past `to`.
        self.stretch
            .set_horizon(to + PEAK_SEARCH + 2 * LOCAL_HALF_WINDOW + 8 * MAX_RUN);
        let mut i = from;
        while i < to {
            i = self.next_exceeding(i, to);
            if i == to {
                break;
            }
            if self.shortcuts && self.hopeless(i) {
                i += 1;
                continue;
            }
            let stats = self.statistics(i);
            // The outlier that makes a statistic of sample i exceed is where the statistics
            // stand out most from their thresholds, among the samples whose residuals reach
            // i's: the block's and the local ones, the latter from the residuals around those.
            let last = (i + PEAK_SEARCH).min(n - 1);
            let mut near = [[0.0; MAX_RUN]; PEAK_SEARCH + 1];
            // The largest statistic of each width above its block threshold.
            let mut above = [0.0_f64; MAX_RUN];
            let (mut b, mut into) = (i / self.block, i % self.block);
            for j in i..=last {
                let threshold = self.thresholds[b];
                (b, into) = if into + 1 == self.block {
                    (b + 1, 0)
                } else {
                    (b, into + 1)
                };
                if self.is_flagged(j) {
                    continue;
                }
                near[j - i] = if j == i { stats } else { self.statistics(j) };
                for (a, &v) in above.iter_mut().zip(&near[j - i]) {
                    *a = a.max(if v > threshold { v } else { 0.0 });
                }
            }
            // The local thresholds of the widths that can stand out of them (most of the samples
            // of a smooth motion whose residual stands out of its block cannot).
            let Some(around) = self.local_thresholds_above(i, PEAK_SEARCH + self.max_run, above) else {
                i += 1;
                continue;
            };
            let (mut c, mut t, mut peak) = (i, 1, 0.0);
            for j in i..=last {
                if self.is_flagged(j) {
                    continue;
                }
                let stats = near[j - i];
                for m in 1..=self.max_run {
                    let ratio = stats[m - 1] / self.block_threshold(j).max(around[m - 1]);
                    if ratio > peak {
                        (c, t, peak) = (j, m, ratio);
                    }
                }
            }
            if peak <= 1.0 {
                i += 1;
                continue;
            }
            // The thresholds there: the local ones from the residuals nearest to the peak's.
            let local = self.local_thresholds(c, t);
            let own = |s: &Self, j: usize, m: usize| s.block_threshold(j).max(local[m - 1]);
            // A rejected peak (here, or without a choice, or by its repair below) is passed: the
            // sweep goes on after it. The samples between `i` and the peak found it the largest
            // of their reach, and would find it again.
            if self.statistics(c)[t - 1] <= own(self, c, t) {
                i = c + 1;
                continue;
            }
            // The outlier is chosen among the candidates around the peak, then again around
            // the one chosen, until the choice holds (the samples that reach its own residuals
            // are candidates too).
            let (mut span, mut runs) = self.around(Candidate { start: c, len: t });
            let mut chosen = None;
            for _ in 0..RECENTRE {
                let Some(pick) = self.choose(span, runs, &own) else {
                    break;
                };
                let again = self.around(pick);
                if again == (span, runs) {
                    chosen = Some(pick);
                    break;
                }
                (span, runs) = again;
            }
            let Some(chosen) = chosen else {
                i = c + 1;
                continue;
            };
            let window = footprint(n, (chosen.start.saturating_sub(2), (chosen.end() + 2).min(n - 1)));
            // A spike's repair clears its neighbours' residuals; the smooth motion's own residual
            // (a burst of fast motion in a noise-free record) only moves to the neighbours.
            let before = self.energy(window);
            if self.energy_after_repair(chosen, window) > CLEARED * before {
                // The peaks of the samples up to two after it would choose it again.
                i = (c + 1).max(chosen.end() + 3);
                continue;
            }
            if chosen.len == 1 {
                let (size, prediction) = predict::<G>(self.x, chosen.start);
                let bound = gain(n, chosen.start) * own(self, chosen.start, 1);
                self.flag(chosen.start, size, G::point(prediction), bound);
            } else {
                let res = self.run_residuals(chosen);
                for (p, &(size, replacement)) in res.iter().enumerate().take(chosen.len) {
                    let j = chosen.start + p;
                    let bound = run_cubic(chosen.len, p).gain * own(self, j, chosen.len);
                    self.flag(j, size, replacement, bound);
                }
            }
            // Back to before the trigger: an outlier passed over for a larger one after it.
            i = i.min(chosen.start.saturating_sub(2));
        }
    }
}

/// What replacing an ordinary sample by its prediction takes out of the residuals' energy once
/// in a thousand, in squared standard deviations of the residual: the 0.999 quantile of χ² with
/// one degree of freedom.
const RUN_PENALTY: f64 = 10.83;

/// Samples that needed new tests and found a repair that could clear, none passed between them,
/// after which the test is left out for a while.
const TESTS_IN_VAIN: usize = 8;

/// Samples searched without the test after [`TESTS_IN_VAIN`] in a row where it was in vain.
const UNTESTED: usize = 64;

/// Half the local scale's window, in positions.
const LOCAL_HALF_WINDOW: usize = 48;

/// The local scale's window holds a multiple of `LOCAL_STEP` positions (96 inside the record, down
/// to 48 near its ends), and `q` is the (positions / `LOCAL_STEP`)-th largest level: the 6th of 96.
const LOCAL_STEP: usize = 16;

/// Partners of a window position on each side.
const LOCAL_PARTNERS: usize = 8;

/// `κ = 6 / c` of the local scale `q / c` for windows of 48, 64, 80 and 96 positions: the local
/// threshold `k q / c` passes white Gaussian noise `10⁻⁶` times per sample at `k = 6` (the
/// calibration of the example `spike_outliers`).
const LOCAL_KAPPA: [f64; 4] = [4.200, 3.963, 3.793, 3.649];

/// Most sweeps of a record.
const MAX_SWEEPS: usize = 8;

/// Most choices of the outlier around a peak before the search moves on.
const RECENTRE: usize = 4;

/// How far past a sample whose statistic exceeds the search looks for the outlier: a spike's
/// or run's residuals start two samples before it, and the sums of up to four residuals reach
/// those from three more before.
const PEAK_SEARCH: usize = 6;

/// The noise gains of the sums of 1 to 4 consecutive centred residuals relative to one, for
/// white noise: `√(var / 70)` with the sums' variances 70, 28, 42 and 40 (in units of
/// `σ² / 36`, from the residual's autocovariance 70, −56, 28, −8, 1).
const SUM_GAINS: [f64; MAX_RUN] = [
    1.0,
    0.632_455_532_033_675_9,
    0.774_596_669_241_483_4,
    0.755_928_946_018_454_5,
];

/// The residuals a change of samples `span.0 ..= span.1` reaches, within two samples of the
/// span, and the first or last two samples when their predictions reach into it (inclusive).
fn footprint(n: usize, span: (usize, usize)) -> (usize, usize) {
    (
        if span.0 <= 4 { 0 } else { span.0 - 2 },
        if span.1 + 5 >= n { n - 1 } else { span.1 + 2 },
    )
}

/// Ordered, disjoint, non-empty half-open ranges of positions: the first `len` of `ranges`.
#[derive(Debug, Clone, Copy, Default)]
struct Ranges {
    ranges: [(usize, usize); 6],
    len: usize,
}

impl Ranges {
    fn push(&mut self, range: (usize, usize)) {
        self.ranges[self.len] = range;
        self.len += 1;
    }

    fn as_slice(&self) -> &[(usize, usize)] {
        &self.ranges[..self.len]
    }

    /// The positions they hold.
    fn count(&self) -> usize {
        self.as_slice().iter().map(|(a, b)| b - a).sum()
    }
}

/// The positions that leave window `o` and those that enter it as it becomes `w` (see
/// [`minus`]): where both sides move on by the same few positions, the first few of each side
/// and the next few past each.
fn moved(o: LocalWindow, w: LocalWindow) -> (Ranges, Ranges) {
    let len = |(from, to): (usize, usize)| to - from;
    if let Some(d) = w.left.0.checked_sub(o.left.0)
        && w.right.0.checked_sub(o.right.0) == Some(d)
        && len(o.left) == len(w.left)
        && len(o.right) == len(w.right)
        && d <= len(o.left).min(len(o.right))
        && o.left.1 + d <= o.right.0
    {
        let (mut leaving, mut entering) = (Ranges::default(), Ranges::default());
        if d > 0 {
            for (from, to) in [(o.left.0, w.left.0), (o.right.0, w.right.0)] {
                leaving.push((from, to));
            }
            for (from, to) in [(o.left.1, w.left.1), (o.right.1, w.right.1)] {
                entering.push((from, to));
            }
        }
        return (leaving, entering);
    }
    let (old, new) = ([o.left, o.right], [w.left, w.right]);
    (minus(old, new), minus(new, old))
}

/// The positions of `x` that are not in `y` (each two ordered, disjoint, half-open ranges of
/// positions; each range of `x` leaves at most three).
fn minus(x: [(usize, usize); 2], y: [(usize, usize); 2]) -> Ranges {
    let mut out = Ranges::default();
    for (mut from, to) in x {
        for (a, b) in y {
            if from >= to {
                break;
            }
            if b <= from || a >= to || a >= b {
                continue;
            }
            if a > from {
                out.push((from, a));
            }
            from = b;
        }
        if from < to {
            out.push((from, to));
        }
    }
    out
}

/// The sum, in order, of `terms` (those of samples `from ..`) with the terms of samples `at ..`
/// replaced by `replaced` where they overlap.
fn sum_replaced(terms: &[f64], from: usize, at: usize, replaced: &[f64]) -> f64 {
    let a = at.clamp(from, from + terms.len()) - from;
    let replaced = &replaced[(from.saturating_sub(at)).min(replaced.len())..];
    let b = (a + replaced.len()).min(terms.len());
    terms[..a]
        .iter()
        .chain(&replaced[..b - a])
        .chain(&terms[b..])
        .sum()
}

/// Whether the residual of sample `m` (as [`predict`] gives it) reads a sample of candidate `c`:
/// sample `m` and its four neighbours inside the record, samples 0 to 4 for samples 0 and 1 and
/// the last five for the last two.
#[inline]
fn reaches(n: usize, m: usize, c: Candidate) -> bool {
    let (lo, hi) = if m >= 2 && m + 2 < n {
        (m - 2, m + 2)
    } else if m < 2 {
        (0, 4)
    } else {
        (n - 5, n - 1)
    };
    lo <= c.end() && c.start <= hi
}

/// A run's prediction at one of its samples: its weights ([`run_weights`]), noise gain
/// ([`run_gain`]) and what it misses of a smooth motion ([`run_smooth_gain`]).
#[derive(Debug, Clone, Copy, Default)]
struct RunCubic {
    weights: [f64; 4],
    gain: f64,
    smooth_gain: f64,
}

/// The runs' predictions, computed once: `[len − 1][p]` for sample `p` of a run of `len`.
static RUN_CUBICS: LazyLock<[[RunCubic; MAX_RUN]; MAX_RUN]> = LazyLock::new(|| {
    std::array::from_fn(|l| {
        std::array::from_fn(|p| {
            let len = l + 1;
            if p < len {
                RunCubic {
                    weights: run_weights(len, p),
                    gain: run_gain(len, p),
                    smooth_gain: run_smooth_gain(len, p),
                }
            } else {
                RunCubic::default()
            }
        })
    })
});

/// The prediction of a run of `len` at its sample `p` ([`RUN_CUBICS`]).
#[inline]
fn run_cubic(len: usize, p: usize) -> RunCubic {
    RUN_CUBICS[len - 1][p]
}

/// Weights of the cubic through the samples at `−2, −1, len, len + 1` (relative to a run's
/// first sample) at the run's sample `p`: Lagrange's.
fn run_weights(len: usize, p: usize) -> [f64; 4] {
    let t = [-2.0, -1.0, len as f64, len as f64 + 1.0];
    let at = p as f64;
    let mut w = [0.0; 4];
    for (k, wk) in w.iter_mut().enumerate() {
        *wk = (0..4)
            .filter(|&l| l != k)
            .map(|l| (at - t[l]) / (t[k] - t[l]))
            .product();
    }
    w
}

/// What a run's prediction at its sample `p` misses of a smooth motion, relative to the
/// motion's centred residual: `|Π (p − t_k)| / 4` over the nodes `t_k` (the cubic's error
/// `Π (p − t_k) h⁴ x⁗ / 24` over the centred residual's `h⁴ x⁗ / 6`): 3 at either sample of a
/// pair, 6 and 9 for a run of three.
fn run_smooth_gain(len: usize, p: usize) -> f64 {
    let t = [-2.0, -1.0, len as f64, len as f64 + 1.0];
    let at = p as f64;
    t.iter().map(|tk| at - tk).product::<f64>().abs() / 4.0
}

/// The noise gain of a run's prediction at its sample `p`, relative to the centred one:
/// `√(1 + Σ w²) / √(70 / 36)`.
fn run_gain(len: usize, p: usize) -> f64 {
    let s: f64 = run_weights(len, p).iter().map(|w| w * w).sum();
    ((1.0 + s) / (70.0 / 36.0)).sqrt()
}

/// A repair must leave at most this fraction of the residuals' energy around it for the sample
/// to be a spike (see "Isolating the outlier" in [`find_spikes`]).
const CLEARED: f64 = 0.5;

/// A run is replaced rather than a single sample only where its repair leaves at most this
/// fraction of what the best single repair leaves.
const RUN_CLEARED: f64 = 0.5;

/// The record's median `G` and the block medians `L_b` of `|r|` per block (over
/// the block and its two neighbours), from the centred residuals of samples `2..n−2`.
fn scales<G: Geometry>(x: &[f64], block: usize) -> (f64, Vec<f64>) {
    let n = x.len();
    let blocks = n.div_ceil(block);
    // The magnitudes as their bits: for numbers without a sign those order as the numbers do (as
    // `f64::total_cmp` orders them), and integers are selected faster.
    let fill = |b: usize, buf: &mut Vec<u64>| {
        buf.clear();
        let lo = (b * block).max(2);
        let hi = ((b + 1) * block).min(n - 2);
        if lo < hi {
            buf.extend(
                x[lo - 2..hi + 2]
                    .windows(5)
                    .map(|w| centred::<G>(w).0.abs().to_bits()),
            );
        }
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
        let mid = window.len() / 2;
        locals.push(f64::from_bits(*window.select_nth_unstable(mid).1));
        std::mem::swap(&mut prev, &mut cur);
        std::mem::swap(&mut cur, &mut next);
        fill(b + 2, &mut next);
    }
    let mut all = locals.clone();
    (median(&mut all), locals)
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
    fn run_predictions_are_exact_for_cubics_and_gains_match_the_noise() {
        let cubic = |t: f64| 0.3 - 0.2 * t + 0.05 * t * t - 0.004 * t * t * t;
        for len in 1..=MAX_RUN {
            let nodes = [-2.0, -1.0, len as f64, len as f64 + 1.0];
            for p in 0..len {
                let w = run_weights(len, p);
                let predicted: f64 = w.iter().zip(nodes).map(|(w, t)| w * cubic(t)).sum();
                assert!(
                    (predicted - cubic(p as f64)).abs() < 1e-12,
                    "run {len} sample {p}"
                );
            }
        }
        // A single sample: the centred prediction, gain 1, its smooth error the residual's.
        assert_eq!(
            run_weights(1, 0).map(|w| (w * 6.0).round()),
            [-1.0, 4.0, 4.0, -1.0]
        );
        assert!((run_gain(1, 0) - 1.0).abs() < 1e-12);
        assert!((run_smooth_gain(1, 0) - 1.0).abs() < 1e-12);
        assert_eq!(
            [
                run_smooth_gain(2, 0),
                run_smooth_gain(3, 0),
                run_smooth_gain(3, 1)
            ],
            [3.0, 6.0, 9.0]
        );
        // The sums' gains from the residual's autocovariance 70, −56, 28, −8, 1.
        let cov = [70.0, -56.0, 28.0, -8.0, 1.0];
        for m in 1..=MAX_RUN {
            let var: f64 = (0..m)
                .flat_map(|a| (0..m).map(move |b| cov.get(a.abs_diff(b)).copied().unwrap_or(0.0)))
                .sum();
            assert!((SUM_GAINS[m - 1] - (var / 70.0).sqrt()).abs() < 1e-12, "{m}");
        }
    }

    #[test]
    fn runs_are_found_and_replaced_by_the_cubic_around_them() {
        let clean = record(400, |t| (0.05 * t).sin() + 0.3 * (0.013 * t).cos());
        for max_run in 1..=MAX_RUN {
            let params = SpikeParams::new().with_max_run(max_run).unwrap();
            for len in 1..=max_run {
                let mut x = clean.clone();
                x[200..200 + len].fill(0.0);
                x[300] += 0.5;
                let found = find_spikes(&x, Domain::Line, &params).unwrap();
                let mut want: Vec<usize> = (200..200 + len).collect();
                want.push(300);
                assert_eq!(found.indices().collect::<Vec<_>>(), want, "run of {len}");
                for s in &found {
                    // The cubic across a gap misses the clean record by `|Π (p − t_k)| / 24`
                    // (at most 72 / 24 for a run of four) times
                    // `h⁴ max |x⁗| ≤ 0.05⁴ + 0.3 · 0.013⁴`.
                    assert!(
                        (s.replacement - clean[s.index]).abs() < 3.0 * 6.3e-6,
                        "run of {len}, max {max_run}: {s:?} clean {}",
                        clean[s.index]
                    );
                }
            }
        }
    }

    /// The local thresholds as first written: the residuals, statistics (running sums) and levels
    /// of the window computed afresh around the outlier, and a selection.
    fn reference_local_thresholds<G: Geometry>(
        x: &[f64],
        max_run: usize,
        k: f64,
        c: usize,
        width: usize,
    ) -> [f64; MAX_RUN] {
        let mut out = [0.0; MAX_RUN];
        let n = x.len();
        let w = LOCAL_HALF_WINDOW;
        let gap = 2 * max_run + 3;
        let reach = w + width + 2 + gap + LOCAL_PARTNERS + 2 * max_run;
        let first = c.saturating_sub(reach).max(2);
        let last = (c + reach).min(n - 3);
        if last < first + 2 * LOCAL_STEP {
            return out;
        }
        let around: Vec<f64> = (first..=last).map(|j| predict::<G>(x, j).0).collect();
        for m in 1..=max_run {
            let count = last + 2 - m - first;
            let mut stat = Vec::new();
            let mut sum: f64 = around[..m - 1].iter().sum();
            for k in 0..count {
                sum += around[k + m - 1];
                stat.push(sum.abs() / SUM_GAINS[m - 1]);
                sum -= around[k];
            }
            let at = |j: usize| stat[j - first];
            let top = first + count - 1;
            let level = |j: usize| {
                let mut partner: f64 = 0.0;
                for d in gap..gap + LOCAL_PARTNERS {
                    if j >= first + d {
                        partner = partner.max(at(j - d));
                    }
                    if j + d <= top {
                        partner = partner.max(at(j + d));
                    }
                }
                at(j).min(partner)
            };
            let (lo_out, hi_out) = ((c + 1).saturating_sub(2 + m), c + width + 1);
            let left = lo_out.saturating_sub(first).min(w);
            let right = top.saturating_sub(hi_out).min(w);
            let count = ((left + right) / LOCAL_STEP * LOCAL_STEP).min(2 * w);
            if count < 3 * LOCAL_STEP {
                continue;
            }
            let (mut left, mut right) = (left, right);
            while left + right > count {
                if left > right {
                    left -= 1;
                } else {
                    right -= 1;
                }
            }
            let mut window: Vec<f64> = (lo_out - left..lo_out).map(level).collect();
            window.extend((hi_out + 1..=hi_out + right).map(level));
            let steps = count / LOCAL_STEP;
            let rank = window.len() - steps;
            let q = *window.select_nth_unstable_by(rank, f64::total_cmp).1;
            out[m - 1] = k * q * LOCAL_KAPPA[steps - 3] / 6.0;
        }
        out
    }

    /// A search of `x` with no threshold of its own (the local scales do not read it).
    fn bare_search<G: Geometry>(x: &mut [f64], max_run: usize) -> Search<'_, G> {
        let n = x.len();
        Search::new(
            x,
            vec![f64::INFINITY; n],
            1,
            SpikeParams::DEFAULT_THRESHOLD,
            max_run,
            true,
        )
    }

    /// Checks the local thresholds of every position and a few widths against the reference, and
    /// that the lower bounds settle only what the thresholds settle.
    fn check_local_thresholds<G: Geometry>(search: &mut Search<'_, G>, what: &str) {
        let n = search.x.len();
        let max_run = search.max_run;
        for width in [1, 2, max_run, PEAK_SEARCH + max_run] {
            for c in 0..n {
                let want = reference_local_thresholds::<G>(search.x, max_run, search.k, c, width);
                let got = search.local_thresholds(c, width);
                // Ranked from the last window where that is cheap, afresh otherwise: the same.
                search.shortcuts = false;
                let afresh = search.local_thresholds(c, width);
                search.shortcuts = true;
                assert_eq!(
                    got.map(f64::to_bits),
                    afresh.map(f64::to_bits),
                    "{what}: c {c} width {width}"
                );
                for m in 0..MAX_RUN {
                    assert!(
                        (got[m] - want[m]).abs() <= 1e-12 * want[m].abs(),
                        "{what}: c {c} width {width} m {}: {} against {}",
                        m + 1,
                        got[m],
                        want[m]
                    );
                }
                // The statistics just below, at and above the thresholds (or anywhere when 0).
                for factor in [0.5, 0.999, 1.0, 1.001, 3.0] {
                    let above = want.map(|t| if t > 0.0 { factor * t } else { factor });
                    let settled = search.local_thresholds_above(c, width, above);
                    for m in 0..max_run {
                        let exceeds = above[m] > got[m];
                        match settled {
                            None => assert!(!exceeds, "{what}: c {c} m {} settled", m + 1),
                            Some(t) if t[m].is_infinite() => {
                                assert!(!exceeds, "{what}: c {c} m {} passed over", m + 1)
                            }
                            Some(t) => assert_eq!(t[m], got[m], "{what}: c {c} m {}", m + 1),
                        }
                    }
                }
            }
        }
    }

    /// The search without its shortcuts, and with them: the same outliers, sizes, replacements,
    /// scale and repaired record, to the bit.
    fn assert_shortcuts_change_nothing(x: &[f64], domain: Domain, params: &SpikeParams, what: &str) {
        let (mut with, mut without) = (x.to_vec(), x.to_vec());
        let fast = search(&mut with, domain, params, true).0;
        let plain = search(&mut without, domain, params, false).0;
        let bits = |s: &Spikes| -> Vec<(usize, u64, u64)> {
            s.iter()
                .map(|s| (s.index, s.size.to_bits(), s.replacement.to_bits()))
                .collect()
        };
        assert_eq!(bits(&fast), bits(&plain), "{what}: the outliers");
        assert_eq!(
            fast.scale().to_bits(),
            plain.scale().to_bits(),
            "{what}: the scale"
        );
        assert!(
            with.iter().zip(&without).all(|(a, b)| a.to_bits() == b.to_bits()),
            "{what}: the repaired record"
        );
    }

    #[test]
    fn the_positions_that_leave_and_enter_a_moving_window() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let window = |rng: &mut rand_chacha::ChaCha8Rng| {
            let a = rng.random_range(0..40);
            let b = a + rng.random_range(0..20);
            let c = b + rng.random_range(0..20);
            let d = c + rng.random_range(0..20);
            LocalWindow {
                left: (a, b),
                right: (c, d),
                steps: 3,
            }
        };
        let positions =
            |w: LocalWindow| -> Vec<usize> { (w.left.0..w.left.1).chain(w.right.0..w.right.1).collect() };
        let listed = |r: Ranges| -> Vec<usize> { r.as_slice().iter().flat_map(|&(a, b)| a..b).collect() };
        for case in 0..2000 {
            let o = window(&mut rng);
            // Moved on by a few positions, or anywhere.
            let w = if case % 2 == 0 {
                let d = rng.random_range(0..12);
                LocalWindow {
                    left: (o.left.0 + d, o.left.1 + d),
                    right: (o.right.0 + d, o.right.1 + d),
                    steps: 3,
                }
            } else {
                window(&mut rng)
            };
            let (leaving, entering) = moved(o, w);
            let (old, new) = (positions(o), positions(w));
            let want_leaving: Vec<usize> = old.iter().copied().filter(|p| !new.contains(p)).collect();
            let want_entering: Vec<usize> = new.iter().copied().filter(|p| !old.contains(p)).collect();
            assert_eq!(listed(leaving), want_leaving, "{o:?} to {w:?}");
            assert_eq!(listed(entering), want_entering, "{o:?} to {w:?}");
            assert!(
                leaving
                    .as_slice()
                    .iter()
                    .chain(entering.as_slice())
                    .all(|(a, b)| a < b)
            );
        }
    }

    #[test]
    fn a_sum_with_terms_replaced_is_the_sum_in_order() {
        let terms: Vec<f64> = (0..9).map(|k| 0.1 * f64::from(k) + 1e-17).collect();
        let replaced = [3.3, 1e-9, 7.0, 0.25, 1e5];
        for at in 0..20 {
            for len in 0..=replaced.len() {
                let naive: f64 = (5..14)
                    .map(|m| {
                        if (at..at + len).contains(&m) {
                            replaced[m - at]
                        } else {
                            terms[m - 5]
                        }
                    })
                    .sum();
                let fast = sum_replaced(&terms, 5, at, &replaced[..len]);
                assert_eq!(fast.to_bits(), naive.to_bits(), "at {at}, {len} replaced");
            }
        }
    }

    /// Every repair whose clearing the search measures (its energy after the repair over its
    /// footprint, by [`Search::energy_after_repair`] on the record changed and put back) is one
    /// the closed form says could clear; returns the repairs tested, those that clear, and the
    /// starts the closed form marks without a repair that clears.
    fn check_clearing<G: Geometry>(x: &mut [f64], max_run: usize, what: &str) -> (usize, usize, usize) {
        let n = x.len();
        let mut search = bare_search::<G>(x, max_run);
        search.shortcuts = false;
        let (mut tested, mut clear, mut marked_in_vain) = (0, 0, 0);
        for a in 2..n - 2 {
            let mut any = false;
            for len in 1..=max_run {
                let c = Candidate { start: a, len };
                if len > 1 && c.end() + 3 > n {
                    continue;
                }
                let window = footprint(n, (a.saturating_sub(2), (c.end() + 2).min(n - 1)));
                let before = search.energy(window);
                let after = search.energy_after_repair(c, window);
                tested += 1;
                if after <= CLEARED * before {
                    clear += 1;
                    any = true;
                }
            }
            let marked = search.clearing.could_clear::<G>(search.x, a, a).0;
            assert!(marked || !any, "{what}: sample {a} clears but is not marked");
            if marked && !any && (10..n - 10 - max_run).contains(&a) {
                marked_in_vain += 1;
            }
        }
        (tested, clear, marked_in_vain)
    }

    #[test]
    fn the_repairs_that_could_clear_are_found_in_closed_form() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(23);
        let n = 6000;
        let h = TAU / 64.0;
        // Sharp turns (some repairs of runs clear), with spikes and a dropout; noise on the
        // line (nearly half clear); an encoder's counts.
        let mut turns: Vec<f64> = (0..n)
            .map(|i| {
                let t = i as f64 * h;
                wrap(t + 2.0 * (3.0 * t.sin()).tanh())
            })
            .collect();
        let smooth = turns.clone();
        for j in (100..n).step_by(397) {
            turns[j] = wrap(turns[j] + 0.05 * (j % 7) as f64 - 0.15);
        }
        turns[3000..3003].fill(0.0);
        let noise: Vec<f64> = (0..n)
            .map(|i| 0.4 * (i as f64 * 0.05).sin() + 1e-3 * (rng.random::<f64>() - 0.5))
            .collect();
        let q = TAU / 4096.0;
        let counts: Vec<f64> = (0..n)
            .map(|i| {
                let t = i as f64 * TAU / 100.0;
                wrap(((t + 0.6 * t.sin()) / q).round() * q)
            })
            .collect();
        for max_run in [1, 3, MAX_RUN] {
            // Where no step nears π/4, the closed form marks exactly the samples whose repairs
            // clear (with runs of four its steps of up to 0.69 rad exceed π/5: every sample is
            // marked).
            let (_, clear, in_vain) =
                check_clearing::<OnCircle>(&mut smooth.clone(), max_run, "smooth turns");
            assert!(
                clear > 0 && (in_vain == 0 || max_run == 4),
                "smooth turns: {clear} clear, {in_vain} in vain"
            );
            let (tested, clear, in_vain) = check_clearing::<OnLine>(&mut noise.clone(), max_run, "noise");
            assert!(
                clear > tested / 10 && in_vain == 0,
                "noise: {clear} of {tested}, {in_vain}"
            );
            // With spikes beside steps of 0.7 rad, and a dropout, some blocks hold steps of more
            // than π/4: all their samples are marked (all blocks with runs of four).
            let (tested, clear, in_vain) = check_clearing::<OnCircle>(&mut turns.clone(), max_run, "turns");
            assert!(
                clear > 0 && clear < tested / 20,
                "turns: {clear} of {tested} clear"
            );
            assert!(
                in_vain <= 64 * 17 || max_run == 4,
                "turns: {in_vain} marked in vain"
            );
            check_clearing::<OnCircle>(&mut counts.clone(), max_run, "counts");
        }
    }

    /// Records where the closed form once missed a repair that clears: a run of four whose
    /// prediction unwraps five steps of about 0.6 rad (more than half a turn); small noise in
    /// the block of a much larger spike (energies as differences of sums from the block's start
    /// lost their digits); residuals whose squares overflow (found through `find_spikes` too).
    #[test]
    fn the_closed_form_misses_no_repair_where_it_once_did() {
        use rand::{Rng, SeedableRng};
        let mut wide: Vec<f64> = [
            0.0, -0.52992, -1.00316, -1.44196, -1.93616, -2.49681, -3.09139, 2.64372, 2.15547, 1.62225,
            1.08179, 0.54054, -0.05941, -0.63568, -1.19849, -1.74464, -2.25376, -2.83040, 2.91713, 2.35560,
            1.63796, 0.92032, 0.20268, -0.51497, -0.47103, -1.05734, -1.56520, -2.09681, -2.63513, -3.12386,
            2.71019, 2.32571, 1.99910, 1.75467, 1.58050, 1.32444, 1.06410, 0.85109, 0.59911, 0.29555,
            -0.05735, -0.49296, -0.85242, -1.24095, -1.55815, -1.91645, -2.27895, -2.66507,
        ]
        .to_vec();
        check_clearing::<OnCircle>(&mut wide, 4, "steps of 0.6 rad, runs of four");
        for seed in 0..40 {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
            let mut line: Vec<f64> = (0..200).map(|_| 3e-6 * (rng.random::<f64>() - 0.5)).collect();
            let mut circle: Vec<f64> = (0..200).map(|_| 1e-8 * (rng.random::<f64>() - 0.5)).collect();
            let j = 64 + rng.random_range(0..8);
            line[j] += 100.0;
            circle[j] += 0.5;
            check_clearing::<OnLine>(&mut line, 3, &format!("noise beside a spike of 100, seed {seed}"));
            check_clearing::<OnCircle>(
                &mut circle,
                3,
                &format!("noise beside a spike of 0.5, seed {seed}"),
            );
        }
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        let base: Vec<f64> = (0..2000)
            .map(|i| 0.4 * (i as f64 * 0.05).sin() + 1e-3 * (rng.random::<f64>() - 0.5))
            .collect();
        for scale in [1.0, 1e150, 1e160, 1e200, 1e300] {
            let mut x: Vec<f64> = base.iter().map(|v| v * scale).collect();
            for j in (100..x.len()).step_by(300) {
                x[j] += 0.05 * scale;
            }
            let found = find_spikes(&x, Domain::Line, &SpikeParams::new()).unwrap();
            assert_eq!(found.len(), 7, "scale {scale:e}");
            assert_shortcuts_change_nothing(
                &x,
                Domain::Line,
                &SpikeParams::new(),
                &format!("scale {scale:e}"),
            );
        }
    }

    /// The bound of a repair's gain by the residuals' distance to a cubic: the inverse Gram
    /// matrices are inverses, and no move of a run's samples takes more from the energy of the
    /// residuals they reach.
    #[test]
    fn no_repair_takes_more_than_the_distance_to_a_cubic() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        for m in 1..=MAX_RUN {
            let g = clearing::inverse_gram(m);
            // The bound of the residuals `r` of m + 4 samples: `e G e` of their fourth
            // differences at samples 2 ..= m + 1.
            let bound = |r: &[f64]| -> f64 {
                let fourth: Vec<f64> = (2..m + 2)
                    .map(|k| r[k - 2] + r[k + 2] - 4.0 * (r[k - 1] + r[k + 1]) + 6.0 * r[k])
                    .collect();
                (0..m)
                    .map(|i| fourth[i] * (0..m).map(|j| g[i][j] * fourth[j]).sum::<f64>())
                    .sum()
            };
            // The residuals of m + 4 samples moved by `moves` at samples 2 ..= m + 1 of them.
            for _ in 0..2000 {
                let r: Vec<f64> = (0..m + 4).map(|_| rng.random::<f64>() - 0.5).collect();
                let moves: Vec<f64> = (0..m).map(|_| 2.0 * rng.random::<f64>() - 1.0).collect();
                let most = bound(&r);
                let gain: f64 = (0..m + 4)
                    .map(|k| {
                        let moved = r[k]
                            + (0..m)
                                .map(|p| weight_of(k.abs_diff(p + 2)) * moves[p])
                                .sum::<f64>();
                        r[k] * r[k] - moved * moved
                    })
                    .sum();
                assert!(gain <= most * (1.0 + 1e-12) + 1e-15, "m {m}: {gain} > {most}");
            }
            // The best move attains it: the residuals of a spike (or run) alone are cleared.
            let mut r = vec![0.0; m + 4];
            for p in 0..m {
                for (k, v) in r.iter_mut().enumerate() {
                    *v -= weight_of(k.abs_diff(p + 2)) * (p as f64 + 1.0);
                }
            }
            let most = bound(&r);
            let energy: f64 = r.iter().map(|v| v * v).sum();
            assert!(
                (most - energy).abs() <= 1e-9 * energy,
                "m {m}: {most} against {energy}"
            );
        }
    }

    /// The weight of a move of a sample `d` away in a residual.
    fn weight_of(d: usize) -> f64 {
        [1.0, -2.0 / 3.0, 1.0 / 6.0].get(d).copied().unwrap_or(0.0)
    }

    #[test]
    fn the_shortcuts_find_what_the_search_finds_without_them() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(17);
        let n = 30_000;
        let h = TAU / 64.0;
        let q = TAU / 4096.0;
        // Whirling angles at 64 samples per period whose motion turns sharply, as a whirling
        // double pendulum's does: the search rejects the same peaks from many samples (the
        // first), or flags thousands of its turns (the second).
        let turns: Vec<f64> = (0..n)
            .map(|i| {
                let t = i as f64 * h;
                t + 2.0 * (3.0 * t.sin()).tanh()
            })
            .collect();
        let steep: Vec<f64> = (0..n)
            .map(|i| {
                let t = i as f64 * h;
                wrap(0.3 * t + 1.5 * (8.0 * t.sin()).tanh() + 0.2 * (2.3 * t).sin())
            })
            .collect();
        // With bit errors of 64 to 2048 counts and dropouts of one to three samples, wrapped, and
        // through a 4096-count encoder.
        let mut broken = turns.clone();
        for j in (300..n).step_by(1531) {
            broken[j] += f64::from(64 << (j % 6)) * q;
        }
        for (j, len) in [(1000, 2), (7000, 3), (15_000, 1), (21_000, 2)] {
            broken[j..j + len].fill(0.0);
        }
        let counts: Vec<f64> = broken.iter().map(|v| wrap((v / q).round() * q)).collect();
        let turns: Vec<f64> = turns.iter().map(|&v| wrap(v)).collect();
        let broken: Vec<f64> = broken.iter().map(|&v| wrap(v)).collect();
        // Noise whose level changes within tens of samples, with outliers and runs, on the line.
        let mut noisy: Vec<f64> = (0..n)
            .map(|i| {
                let level = 1e-3 * (1.0 + 4.0 * ((i as f64 / 70.0).sin()).powi(2));
                0.4 * (i as f64 * 0.05).sin() + level * (rng.random::<f64>() - 0.5)
            })
            .collect();
        for j in (17..n).step_by(613) {
            noisy[j] += 0.05;
        }
        for j in (400..n).step_by(2777) {
            noisy[j..j + 2].fill(-0.3);
        }
        for params in [
            SpikeParams::new(),
            SpikeParams::new().with_max_run(1).unwrap(),
            SpikeParams::new()
                .with_max_run(MAX_RUN)
                .and_then(|p| p.with_threshold(4.0))
                .unwrap(),
        ] {
            let what = format!("{params:?}");
            for (x, domain, name) in [
                (&turns, Domain::Circle, "sharp turns"),
                (
                    &broken,
                    Domain::Circle,
                    "sharp turns with bit errors and dropouts",
                ),
                (&steep, Domain::Circle, "steep turns"),
                (&noisy, Domain::Line, "noise"),
            ] {
                assert_shortcuts_change_nothing(x, domain, &params, &format!("{name}, {what}"));
            }
        }
        let quantum = SpikeParams::new().with_quantum(q).unwrap();
        assert_shortcuts_change_nothing(&counts, Domain::Circle, &quantum, "encoder");
    }

    #[test]
    fn the_stretch_gives_the_local_thresholds_as_computed_afresh() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        // Noise whose level changes along the record, with outliers and runs, on the line and
        // on the circle (crossing ±π), and records short enough for the ends to cut the windows.
        for (n, max_run) in [(900, 3), (900, 1), (300, MAX_RUN), (60, 3), (40, 2), (7, 3)] {
            let base: Vec<f64> = (0..n)
                .map(|i| {
                    let level = 1e-3 * (1.0 + 4.0 * ((i as f64 / 70.0).sin()).powi(2));
                    0.4 * (i as f64 * 0.05).sin() + level * (rng.random::<f64>() - 0.5)
                })
                .collect();
            let mut line = base.clone();
            for j in (17..n).step_by(113) {
                line[j] += 0.05;
            }
            let mut circle: Vec<f64> = base
                .iter()
                .enumerate()
                .map(|(i, v)| wrap(v + 0.3 * i as f64))
                .collect();
            for j in (29..n).step_by(97) {
                circle[j] = wrap(circle[j] + PI);
            }
            let mut search = bare_search::<OnLine>(&mut line, max_run);
            check_local_thresholds(&mut search, &format!("line, {n} samples"));
            // Stretches as long as the record, and no longer than asked for (refilled at every
            // position).
            for short in [false, true] {
                let what = format!("circle, {n} samples, short stretches {short}");
                let mut copy = circle.clone();
                let mut search = bare_search::<OnCircle>(&mut copy, max_run);
                if short {
                    search.stretch.set_horizon(0);
                }
                check_local_thresholds(&mut search, &what);
                // Repairs change the record under the stretch: its statistics and levels follow.
                for j in (5..n).step_by(61) {
                    let (size, prediction) = predict::<OnCircle>(search.x, j);
                    search.flag(j, size, OnCircle::point(prediction), 0.0);
                    let (a, b) = (
                        j.saturating_sub(2 * LOCAL_HALF_WINDOW),
                        (j + 2 * LOCAL_HALF_WINDOW).min(n - 1),
                    );
                    let mut now = search.x.to_vec();
                    let mut fresh = bare_search::<OnCircle>(&mut now, max_run);
                    for c in a..=b {
                        assert_eq!(
                            search.statistics(c),
                            fresh.statistics(c),
                            "{what}: statistic at {c}"
                        );
                    }
                }
                check_local_thresholds(&mut search, &format!("{what}, repaired"));
            }
        }
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
        assert!(p.with_max_run(0).is_err());
        assert!(p.with_max_run(SpikeParams::MAX_RUN + 1).is_err());
        assert_eq!(p.max_run(), SpikeParams::DEFAULT_MAX_RUN);
        assert_eq!(p.with_quantum(0.5).unwrap().floor(), Some(1.0));
        let q = p
            .with_threshold(4.5)
            .unwrap()
            .with_floor(0.01)
            .unwrap()
            .with_block(32)
            .unwrap()
            .with_max_run(1)
            .unwrap();
        let json = serde_json::to_string(&q).unwrap();
        assert_eq!(serde_json::from_str::<SpikeParams>(&json).unwrap(), q);
        assert_eq!(serde_json::from_str::<SpikeParams>("{}").unwrap(), p);
        for bad in [
            r#"{"threshold":-2.0}"#,
            r#"{"floor":0.0}"#,
            r#"{"block":2}"#,
            r#"{"max_run":5}"#,
            r#"{"threshold":null}"#,
        ] {
            assert!(serde_json::from_str::<SpikeParams>(bad).is_err(), "{bad}");
        }
    }
}
