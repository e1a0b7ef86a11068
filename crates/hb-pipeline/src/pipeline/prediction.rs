//! Validation that needs no true equation: each model's valid prediction time on windows of the
//! record (`pendulum_sim::prediction`), in drive periods and in Lyapunov times.
//!
//! The windows are the record's own, spread evenly over it ([`prediction_starts`]); the model
//! starts each from the record's state there (a local polynomial fit of the samples) and is
//! followed until it leaves the tolerance. The identification used the whole record, so these
//! windows are not held out from it: with a few coefficients fitted to thousands of samples the
//! difference is small, but a held-out record (a continuation, another run of the rig) is the
//! stricter test, and [`PredictionOptions::measure`] takes any record.

use pendulum_sim::{
    PredictionConfig, PredictionRecord, PredictionTimes, SecondOrderSystem, prediction_starts,
    valid_prediction_times,
};

use super::{PipelineError, Record};

/// Whether, and with what settings, each model's valid prediction time is measured.
///
/// Default: measured with [`PredictionConfig::default`] (32 windows, a tolerance of 10 % of the
/// record's spread, a horizon of 40 drive periods).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PredictionOptions {
    config: Option<PredictionConfig>,
}

impl Default for PredictionOptions {
    fn default() -> Self {
        Self {
            config: Some(PredictionConfig::default()),
        }
    }
}

impl PredictionOptions {
    /// No prediction test.
    pub fn none() -> Self {
        Self { config: None }
    }

    /// The test with `config` (checked when it was built).
    pub fn with_config(config: PredictionConfig) -> Self {
        Self { config: Some(config) }
    }

    /// The settings, `None` when the test is off.
    pub fn config(&self) -> Option<&PredictionConfig> {
        self.config.as_ref()
    }

    /// The record as the prediction test reads it and its windows: checks that the record allows
    /// the test (it moves, and is long enough for a state estimate). `None` when the test is off.
    fn windows<'a>(
        &self,
        record: &Record<'a>,
    ) -> Result<Option<(PredictionConfig, PredictionRecord<'a>, Vec<usize>)>, PipelineError> {
        let Some(config) = self.config else {
            return Ok(None);
        };
        let observed = PredictionRecord::new(record.samples(), *record.clock(), record.domain())?;
        let starts = prediction_starts(&observed, &config)?;
        Ok(Some((config, observed, starts)))
    }

    /// Checks the test against `record` before any work.
    pub(super) fn check(&self, record: &Record<'_>) -> Result<(), PipelineError> {
        self.windows(record).map(|_| ())
    }

    /// The valid prediction times of `system` on the windows of `record` (as every model of the
    /// pipeline is measured, so that a reference system, such as the true one, is measured
    /// alike); `lyapunov`, the exponent per unit time, adds them in Lyapunov times. `None` when
    /// the test is off.
    pub fn measure<S: SecondOrderSystem + Sync>(
        &self,
        system: &S,
        record: &Record<'_>,
        lyapunov: Option<f64>,
    ) -> Result<Option<PredictionTimes>, PipelineError> {
        let Some((config, observed, starts)) = self.windows(record)? else {
            return Ok(None);
        };
        Ok(Some(valid_prediction_times(
            system, &observed, &starts, &config, lyapunov,
        )?))
    }
}
