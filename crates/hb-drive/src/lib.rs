//! The drive's period of a forced oscillator, estimated from its record alone: the period whose
//! drive terms make the weak form's equations fit best ([`estimate_drive_period`]), searched by
//! a multi-resolution scan and variable-projection Gauss–Newton over a range
//! ([`PeriodRange`], [`DriveSearch`]), with a cluster-robust uncertainty ([`DriveEstimate`]); and
//! the dominant period of a signal ([`dominant_period`]), the range's default. The module
//! [`search`] says how and why.
//!
//! The identification it runs is `hb-solve`'s weak form on the record's own grid (its test
//! functions and factorisations, [`hb_solve::kernel`]); the model whose residual it minimises is
//! never the one reported.
//!
//! # Example
//!
//! ```
//! use circle_signal::Domain;
//! use hb_basis::Harmonic;
//! use hb_drive::{DriveSearch, PeriodRange, estimate_drive_period};
//! use hb_model::ModelForm;
//! use pendulum_sim::{Pendulum, SimulationConfig, simulate};
//!
//! // The paper's pendulum sampled 25 times per drive period 2π, the period searched in 5..8.
//! let config = SimulationConfig::paper().with_samples(6_000)?;
//! let trajectory = simulate(&Pendulum::paper(), &config)?;
//! let x = trajectory.wrapped();
//! let search = DriveSearch::builder().range(PeriodRange::periods(5.0, 8.0)?).build()?;
//! let step = std::f64::consts::TAU / 25.0;
//! let estimate = estimate_drive_period(
//!     &x, step, trajectory.t[0], Domain::Circle, &search, &Harmonic::new(1)?,
//!     &ModelForm::parametric(), &mut |_, _| {},
//! )?;
//! assert!((estimate.period - std::f64::consts::TAU).abs() < 1e-6);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![deny(missing_docs)]

pub mod error;
pub mod search;

pub use error::DriveSearchError;
pub use search::{
    DriveEstimate, DriveSearch, DriveSearchBuilder, MIN_SAMPLES_PER_PERIOD, PeriodRange, RangeSource,
    RefinedCandidate, ScanPoint, dominant_period, estimate_drive_period,
};
