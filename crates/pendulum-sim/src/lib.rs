//! Simulation of forced second-order oscillators `x'' = F(t, x, x')`.
//!
//! The true system of the paper is the horizontally base-excited pendulum (Liang & Feeny, eq. 1):
//!
//! ```text
//! x'' + c x' + (1/r²) sin x − f sin(t) cos x = 0,     f = 1.52, c = 0.03, r = 0.8333,
//! ```
//!
//! in non-dimensional time (forcing period 2π). The second true system is the two-well
//! [`Duffing`] oscillator `x'' + c x' + a x + b x³ = f cos(t)`. Every system, these and the models
//! that later stages identify, implements [`SecondOrderSystem`] and runs through the same code:
//!
//! - [`Dop853`]: the explicit Runge–Kutta pair of Dormand and Prince of order 8 with error
//!   estimators of orders 5 and 3 and a 7th-order dense output (Hairer, Nørsett & Wanner,
//!   *Solving ODEs I*, II.10), with Hairer's step-size control and initial step;
//! - [`simulate`]: samples at exactly `t_n = t_0 + n T/P`, or `t_0 + n h` for any step `h`
//!   (computed by multiplication, so no sample is lost or shifted by accumulated rounding), from
//!   dense output;
//! - [`InFrame`]: a system in a record's time unit and coordinate (`τ = 2π f_drive t` for a rig
//!   driven at `f_drive` Hz), and [`TrueCoefficients`]: its equation in the identification's form
//!   (module [`frame`]);
//! - [`poincare_section`]: the stroboscopic map, one state per forcing period;
//! - [`largest_lyapunov`]: the largest Lyapunov exponent from the tangent-linear equation
//!   `(δx, δv)' = (δv, ∂F/∂x δx + ∂F/∂v δv)`, renormalised every forcing period;
//! - validation of identified models: [`periodic_orbits`] of the stroboscopic map by Newton
//!   shooting (with Floquet multipliers), [`section_energy_distance`] between Poincaré sections,
//!   and the [`whirling_fraction`];
//! - [`observe`]: what an encoder reports of the simulated angle (zero offset, seeded noise,
//!   counts per turn, bit errors, the wrap) and where a record has gaps.
//!
//! # Example
//!
//! ```
//! use pendulum_sim::{simulate, Pendulum, SimulationConfig, Tolerances};
//!
//! let pendulum = Pendulum::new(1.52, 0.03, 0.8333)?;
//! let config = SimulationConfig::paper()
//!     .with_samples(250)?
//!     .with_transient_periods(10)
//!     .with_tolerances(Tolerances::relative(1e-10)?);
//! let trajectory = simulate(&pendulum, &config)?;
//! let encoder = trajectory.wrapped(); // what an encoder would report, in [-π, π)
//! assert_eq!(encoder.len(), 250);
//! assert!(encoder.iter().all(|x| (-std::f64::consts::PI..std::f64::consts::PI).contains(x)));
//! # Ok::<(), pendulum_sim::SimError>(())
//! ```
#![deny(missing_docs)]

mod dop853;
mod error;
pub mod frame;
pub mod observe;
mod simulate;
mod system;
mod tableau;
mod validate;

pub use circle_signal::Domain;
pub use dop853::{Dop853, OdeSystem, Stats, Tolerances};
pub use error::SimError;
pub use frame::{InFrame, RecordFrame, TrueCoefficients};
pub use simulate::{
    FirstOrder, LyapunovConfig, LyapunovEstimate, SimulationConfig, Tangent, Trajectory, largest_lyapunov,
    poincare_section, simulate, simulate_with_progress,
};
pub use system::{Duffing, Pendulum, SecondOrderSystem};
pub use validate::{
    CheckConfig, ModelCheck, PeriodicOrbit, Seeds, ShootingConfig, Variational, check_model, energy_distance,
    flow_with_jacobian, periodic_orbits, section_energy_distance, whirling_fraction,
};
