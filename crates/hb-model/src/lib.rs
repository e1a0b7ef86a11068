//! The model of a forced oscillator, `x'' + Σ_i c_i g_i(t, x, x') = 0`: its vocabulary, its form,
//! the identified equation, its saved formats, the measured drive it may hold, and the true
//! equation of the simulated systems in the same terms.
//!
//! - [`terms`]: each term `g_i` is a product of a drive factor (`1`, `cos(kt)`, `sin(kt)`, or
//!   `p`, a measured drive), a function of `x` (`1`, a basis function of `hb-basis`, or `x`) and
//!   a function of `x'` (`1`, `x'`, `sign(x')`, `x'*|x'|`, `x'^3`), named by its factors joined by
//!   `*`; [`TermList`] reads and prints lists of them (`x', {1,cos(t)}*{cos(x),sin(x)}`);
//! - [`form`]: [`ModelForm`], the paper's presets (eq. 2 specialised as eq. 6) or a list of
//!   terms, and [`columns`], the one layout of the unknowns every assembly fills and every reader
//!   of a system assumes; [`Harmonics`], the band each segment was balanced over;
//! - [`model`]: [`IdentifiedModel`], the coefficients with their standard errors, evaluated as a
//!   [`circle_signal::system::SecondOrderSystem`] (so that `pendulum_sim` simulates, sections and measures it with the
//!   code that made the data), saved and loaded by [`io`] (JSON and compact binary, format 4,
//!   reading 2 and 3);
//! - [`MeasuredDrive`]: the samples of a measured drive `p(t)` on a record's grid, what a term in
//!   `p` is balanced from and what a model in `p` is simulated with.
//!
//! The true equations of the simulated systems, in these terms and a record's frame, are the
//! simulator's (`pendulum_sim::truth`): this crate never reaches the simulator.
//!
//! Errors: [`TermError`] for lists and forms, [`ModelIoError`] for saved models, folded into
//! [`ModelError`].
//!
//! # Example
//!
//! ```
//! use hb_basis::{BasisKind, Harmonic};
//! use hb_model::{IdentifiedModel, ModelForm, TermList};
//! use circle_signal::system::SecondOrderSystem;
//!
//! // x'' + 0.03 x' + 1.44 sin(x) - 1.52 sin(t)*cos(x) = 0, as a list of terms.
//! let form = ModelForm::from_terms(TermList::parse("x', sin(x), sin(t)*cos(x)")?);
//! let basis = BasisKind::from(Harmonic::new(1)?);
//! let model = IdentifiedModel::new(basis, form, 1.0, &[0.03, 1.44, -1.52])?;
//! let a = model.acceleration(0.5, 0.2, -0.1);
//! assert!((a + 0.03 * -0.1 + 1.44 * 0.2f64.sin() - 1.52 * 0.5f64.sin() * 0.2f64.cos()).abs() < 1e-15);
//! let back: IdentifiedModel = IdentifiedModel::from_bytes(&model.to_bytes()?)?;
//! assert_eq!(back, model);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![deny(missing_docs)]

pub mod drive;
pub mod error;
pub mod form;
pub mod io;
pub mod model;
pub mod system;
pub mod terms;

pub use drive::MeasuredDrive;
pub use error::{ModelError, ModelIoError, TermError};
pub use form::{Column, Forcing, Harmonics, ModelForm, columns, term_names};
pub use io::{MODEL_FORMAT, MODEL_MAGIC, MODEL_OLDEST_VERSION, MODEL_VERSION, SYSTEM_VERSION};
pub use model::{Coefficient, FitSummary, IdentifiedModel};
pub use system::{
    Columns, IdentifiedSystem, NEAR_SINGULAR_PIVOT, SINGULAR_PIVOT, SingularMass, SingularState,
};
pub use terms::{
    Combination, Coupling, DriveFactor, Factor, MAX_COORDINATES, MAX_COUPLING, MAX_DRIVE_HARMONIC,
    MAX_DRIVES, MAX_TERMS, Names, PositionFactor, Term, TermList, TermSpec, VelocityFactor, XFunction,
};
