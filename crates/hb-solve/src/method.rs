//! The identification methods behind one trait: how segments of a record become the stacked
//! system of a model.

use std::fmt;

use circle_signal::Segment;
use hb_basis::Basis;

use crate::error::SolveError;

use crate::params::IdentifyParams;
use crate::signals::Signals;

use crate::system::LinearSystem;

use crate::weak::WeakForm;

use hb_model::{Harmonics, ModelForm};

/// A way of turning segments of a record into the stacked system `A λ = β` of a model
/// ([`LinearSystem`]): the paper's harmonic-balance rows ([`HarmonicBalance`]), the weak form
/// ([`WeakForm`]), or pointwise finite differences ([`crate::FiniteDifferences`], the classic peer).
///
/// Every method produces the same column layout (the [`columns`](hb_model::columns) of the params' form), so
/// that solvers, models and the bootstrap serve them all; a front end chooses a method in one
/// place (`Box<dyn Assembly>`) and calls [`crate::identify`].
pub trait Assembly: fmt::Debug + Send + Sync {
    /// A short name: `upo` (the paper's rows on periodic orbits), `windowed` (the weak form) or
    /// `differences`.
    fn name(&self) -> &'static str;

    /// The harmonics per segment to balance when the user gives none, for a form without drive
    /// harmonics above the first.
    fn default_harmonics(&self) -> Harmonics;

    /// The harmonics per segment to balance for a model of `form` (or, with a selection, of the
    /// library `form`) when the user gives none: [`Assembly::default_harmonics`] widened to reach
    /// the form's highest drive harmonic ([`Harmonics::reaching`],
    /// [`ModelForm::highest_drive_harmonic`]). No margin beyond it is needed: on a two-well
    /// Duffing record driven with 12 % and 14 % second and third harmonics, the weak form's
    /// selection keeps `cos(3t)` from a cap of 8/3 up, and a cap of 3 gives its coefficient within
    /// 4e-4 at noise 0.01 where a cap of 4 gives 7e-4 (`docs/identification.md`).
    fn default_harmonics_for(&self, form: &ModelForm) -> Harmonics {
        self.default_harmonics().reaching(form.highest_drive_harmonic())
    }

    /// Assembles the stacked system of `segments` of the record `signals` (its own coordinate,
    /// the others and the measured drives its terms read) for a model on `basis` with `params`. Segments must satisfy the [`Segment`] invariant for the params' clock. The
    /// params' noise correction is not applied here but by [`crate::build_system`], the same way
    /// for every method.
    fn assemble(
        &self,
        basis: &dyn Basis,
        signals: &Signals<'_>,
        segments: &[Segment],
        params: &IdentifyParams,
    ) -> Result<LinearSystem, SolveError>;

    /// [`Assembly::assemble`] of each of a system's equations, `(basis, signals, params)`, over
    /// the same `segments`: the same systems, in order. By default each equation is assembled
    /// alone; the weak form assembles them window by window together, each coordinate's window
    /// and velocity made once for every equation that reads it, the rows the same to the bit.
    fn assemble_many(
        &self,
        equations: &[EquationInput<'_>],
        segments: &[Segment],
    ) -> Result<Vec<LinearSystem>, SolveError> {
        equations
            .iter()
            .map(|&(basis, signals, params)| self.assemble(basis, signals, segments, params))
            .collect()
    }
}

/// One equation of a system to assemble ([`Assembly::assemble_many`]): its basis (any basis
/// behind `dyn`, or one type `B` for the assemblies' generic code), its view of the record (its
/// own coordinate among the others) and its parameters.
pub type EquationInput<'e, B = dyn Basis> = (&'e B, &'e Signals<'e>, &'e IdentifyParams);

/// The paper's method: eq. 15 on every segment, which must be (nearly) periodic, stacked as
/// eq. 16 (see [`LinearSystem`] for the rows).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct HarmonicBalance;

impl HarmonicBalance {
    /// Default harmonics: [`Harmonics::DEFAULT`], every orbit balanced up to three times the
    /// forcing frequency.
    pub const DEFAULT_HARMONICS: Harmonics = Harmonics::DEFAULT;
}

impl Assembly for HarmonicBalance {
    fn name(&self) -> &'static str {
        "upo"
    }

    fn default_harmonics(&self) -> Harmonics {
        Self::DEFAULT_HARMONICS
    }

    fn assemble(
        &self,
        basis: &dyn Basis,
        signals: &Signals<'_>,
        segments: &[Segment],
        params: &IdentifyParams,
    ) -> Result<LinearSystem, SolveError> {
        crate::assemble::harmonic_rows(basis, signals, segments, params)
    }
}

impl Assembly for WeakForm {
    fn name(&self) -> &'static str {
        "windowed"
    }

    fn default_harmonics(&self) -> Harmonics {
        Self::DEFAULT_HARMONICS
    }

    fn assemble(
        &self,
        basis: &dyn Basis,
        signals: &Signals<'_>,
        segments: &[Segment],
        params: &IdentifyParams,
    ) -> Result<LinearSystem, SolveError> {
        crate::weak::weak_rows(basis, signals, segments, params, self)
    }

    fn assemble_many(
        &self,
        equations: &[EquationInput<'_>],
        segments: &[Segment],
    ) -> Result<Vec<LinearSystem>, SolveError> {
        crate::weak::weak_rows_many(equations, segments, self)
    }
}
