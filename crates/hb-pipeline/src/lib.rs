//! The application layer of `hbid`: what every front end (the command line `hbid`, the Python
//! package, `cargo xtask`) runs on a record, written once.
//!
//! - [`pipeline`]: the whole analysis of one record, from its samples to validated models (the
//!   delay, the segments, the identification by each method, the validation by simulation);
//! - [`json`]: the JSON of the results;
//! - [`output`]: result files written atomically (all or nothing, even on an interrupt).
//!
//! Nothing here prints; progress comes through callbacks. Files are touched only where a caller
//! names one ([`output`]).
//!
//! # Example
//!
//! ```
//! use circle_signal::SampleClock;
//! use hb_basis::{BasisKind, Harmonic};
//! use hb_pipeline::pipeline::{Method, ModelSpec};
//! use pendulum_sim::{Pendulum, SimulationConfig, simulate};
//! use upo_search::Windows;
//!
//! let trajectory = simulate(&Pendulum::paper(), &SimulationConfig::paper().with_samples(2_000)?)?;
//! let x = trajectory.wrapped();
//! let clock = SampleClock::nondimensional(25)?.with_start_time(trajectory.t[0])?;
//! let windows = Windows::new(&clock)?.windows(&x)?;
//! let id = ModelSpec::new(Method::Windowed, BasisKind::from(Harmonic::new(1)?))
//!     .setup(&clock)?
//!     .identify(&x, &windows)?;
//! assert!((id.model.coefficient("sin(t)*cos(x)").unwrap().value + 1.52).abs() < 1e-6);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![deny(missing_docs)]

pub mod json;
pub mod output;
pub mod pipeline;
