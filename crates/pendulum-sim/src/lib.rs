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
//!   driven at `f_drive` Hz) (module [`frame`]);
//! - [`poincare_section`]: the stroboscopic map, one state per forcing period;
//! - [`largest_lyapunov`]: the largest Lyapunov exponent from the tangent-linear equation
//!   `(δx, δv)' = (δv, ∂F/∂x δx + ∂F/∂v δv)`, renormalised every forcing period;
//! - validation of identified models: [`periodic_orbits`] of the stroboscopic map by Newton
//!   shooting (with Floquet multipliers), [`section_energy_distance`] between Poincaré sections,
//!   and the [`whirling_fraction`];
//! - validation that needs no true equation ([`prediction`]): the [`valid_prediction_times`] of a
//!   model started from a record's own state (of a system of several coordinates too,
//!   [`prediction::system_valid_prediction_times`]), and the [`decay_envelope`] of a free decay;
//! - [`observe`]: what an encoder reports of the simulated angle (zero offset, seeded noise,
//!   counts per turn, bit errors, the wrap) and where a record has gaps;
//! - a real machine's imperfections ([`Losses`]: dry friction `μ sign(x')`, quadratic drag
//!   `d x'|x'|`, cubic damping `c₃ x'^3`; [`DriveHarmonics`]: harmonics `k = 2, 3, …` of the
//!   drive), options of [`Pendulum`] and [`Duffing`] that leave them exactly as they were when
//!   absent;
//! - systems of several coordinates ([`multi`]): a [`MultiSystem`] gives its accelerations solved
//!   from its mass matrix and is integrated by the same [`Dop853`] at the state's size `2n`,
//!   sampled by the same code, and sticks at `q_c' = 0` by the rule below, one coordinate at a
//!   time; the base-excited [`DoublePendulum`], the torque-driven [`TorqueDoublePendulum`] (the
//!   DFKI arm) and the [`CoupledDuffing`] oscillators under a measured base acceleration, each
//!   with its equations in the identification's form ([`equations`]).
//!
//! # Dry friction: integrating across `x' = 0`
//!
//! `sign(x')` jumps at `x' = 0`, and `|x'|` has a kink there. An adaptive Runge–Kutta method
//! integrating through the jump loses its order in the step that contains it, and where the
//! forcing cannot overcome the friction the exact solution stays at rest while the sign
//! chatters, which no step size control resolves. So a system that declares the switch
//! ([`SecondOrderSystem::switches_at_rest`]) is integrated by event location, with Filippov's
//! convention at rest:
//!
//! - each side of `x' = 0` on its own smooth branch ([`SecondOrderSystem::acceleration_on`]:
//!   `sign(x') = ±1`, `|x'| = ±x'`), so DOP853 keeps its order in every step;
//! - every `x' = 0` located on the step's dense output (the velocity looked at at eight points
//!   of each step, the zero then bisected to the last bit of the time), the step cut there;
//! - at `x' = 0` a branch starts only if it accelerates away from rest on its own side
//!   (`s F_s(t, x, 0) > 0`); if neither does, the body sticks (`x' = 0`, `x` constant,
//!   exactly) until one does, tested at points no further apart than the step the controller
//!   proposed when it stopped, the release then bisected on `F` itself;
//! - the tangent vectors of the Lyapunov exponent and of Newton shooting jump by the saltation
//!   matrix at each reversal (`diag(1, F_new/F_old)`) and lose their velocity part at a stick.
//!
//! A reversal of the velocity that starts and ends within one eighth of a step is not seen.
//! A smooth system runs through exactly the same steps as before (the paper's numbers are
//! unchanged bit for bit).
//!
//! Accuracy, measured by `cargo run --release -p pendulum-sim --example friction`:
//!
//! - the free decay of `x'' + ω² x + μ sign(x') = 0` (ω = 1.3, μ = 0.05, from rest at 1: 17
//!   swings, each `2μ/ω²` smaller, then at rest) against its closed form: the largest error of
//!   `x` over 60 time units is 1.6e-6, 3.2e-8, 5.3e-10, 2.8e-12 at rtol 1e-6, 1e-8, 1e-10,
//!   1e-12 (about 5 rtol), the velocity's 30 % more, and the amplitude lost in 7 cycles is
//!   `28 μ/ω²` to 4.8e-10 at rtol 1e-10; the final rest position to 5e-10;
//! - a driven oscillator that sticks for half of the time (`x'' + 0.1 x' + x + 0.45 sign(x')
//!   = 0.5 cos t`) against the same equation with `tanh(x'/ε)` for `sign(x')`, integrated as a
//!   smooth stiff system: the difference is 3.6e-5, 4.2e-6, 4.7e-7 for ε = 1e-5, 1e-6, 1e-7,
//!   converging like `5 ε` to the located solution;
//! - the chaotic pendulum with `μ = 0.02`, `d = 0.01`, `c₃ = 0.002`, rtol 1e-10 against 1e-13:
//!   3.4e-10 after 3 forcing periods (the paper's pendulum: 3.3e-9), 3.2e-9 after 10.
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

mod arm;
mod coupled_duffing;
mod dop853;
mod double_pendulum;
pub mod equations;
mod error;
pub mod frame;
mod free_run;
mod machine;
pub mod multi;
pub mod observe;
mod oscillators;
pub mod prediction;
mod signal;
mod simulate;
mod switching;
mod system;
mod tableau;
pub mod truth;
mod validate;

pub use arm::{ARM_PARAMETERS, ArmCoefficient, ArmParameters, ArmTie, Torque, TorqueDoublePendulum};
pub use circle_signal::Domain;
pub use coupled_duffing::{BaseAcceleration, CoupledDuffing};
pub use dop853::{Dop853, OdeSystem, Stats, Tolerances};
pub use double_pendulum::DoublePendulum;
pub use equations::NormalisedEquation;
pub use error::{SimError, reserve_series};
pub use frame::{InFrame, RecordFrame};
pub use free_run::{FreeRun, InitialState, fit_initial_state, free_run, free_run_reporting};
pub use machine::{DriveHarmonic, DriveHarmonics, Losses};
pub use multi::{
    MAX_COORDINATES, MultiConfig, MultiFreeRun, MultiInitialState, MultiState, MultiSystem, MultiTrajectory,
    OneCoordinate, SingularMass,
};
pub use oscillators::{Duffing, Pendulum};
pub use prediction::{
    DecayEnvelope, PredictionConfig, PredictionRecord, PredictionTimes, TimeSummary, WindowPrediction,
    decay_envelope, estimate_state, predict_window, prediction_starts, valid_prediction_times,
};
pub use signal::{MeasuredSignal, Sinusoid, SyntheticDrive};
pub use simulate::{
    FirstOrder, LyapunovConfig, LyapunovEstimate, SimulationConfig, Tangent, Trajectory, largest_lyapunov,
    poincare_section, simulate, simulate_each, simulate_while, simulate_with_progress,
};
pub use system::{Branch, SecondOrderSystem};
pub use truth::{Equation, TrueEquation, pendulum_model};
pub use validate::{
    CheckConfig, ModelCheck, PeriodicOrbit, Seeds, ShootingConfig, Variational, check_model, energy_distance,
    flow_with_jacobian, periodic_orbits, section_energy_distance, whirling_fraction,
};
