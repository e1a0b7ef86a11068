//! An identified model from a solved system: the coefficients and standard errors of the fit, and
//! its summary (solver, rows, segments, condition number, residual), on the model's crate's
//! [`IdentifiedModel`].

use hb_basis::Basis;
use hb_model::{Coefficient, FitSummary, IdentifiedModel};

use crate::error::SolveError;
use crate::lstsq::{LstsqFit, LstsqSolver};
use crate::params::IdentifyParams;
use crate::system::LinearSystem;

/// A model made by fitting an assembled system (implemented by [`IdentifiedModel`]).
pub trait FitModel<B>: Sized {
    /// Solves an assembled `system` (from [`crate::build_system`] with the same `basis` and
    /// `params`) with `solver` and builds the model, e.g. to keep the system for
    /// [`crate::bootstrap`].
    ///
    /// Errors: a mismatch of the system's unknowns with those of `basis` and `params`, and the
    /// solver's errors.
    fn fit<S: LstsqSolver + ?Sized>(
        basis: B,
        params: &IdentifyParams,
        system: &LinearSystem,
        solver: &S,
    ) -> Result<Self, SolveError>;

    /// [`FitModel::fit`] from a fit already computed, `fit = system.solve(solver)` with a solver
    /// named `solver`: the fit can then also serve [`crate::bootstrap_fit`].
    fn from_fit(
        basis: B,
        params: &IdentifyParams,
        system: &LinearSystem,
        fit: &LstsqFit,
        solver: &str,
    ) -> Result<Self, SolveError>;
}

impl<B: Basis> FitModel<B> for IdentifiedModel<B> {
    fn fit<S: LstsqSolver + ?Sized>(
        basis: B,
        params: &IdentifyParams,
        system: &LinearSystem,
        solver: &S,
    ) -> Result<Self, SolveError> {
        let fit = system.solve(solver)?;
        Self::from_fit(basis, params, system, &fit, solver.name())
    }

    fn from_fit(
        basis: B,
        params: &IdentifyParams,
        system: &LinearSystem,
        fit: &LstsqFit,
        solver: &str,
    ) -> Result<Self, SolveError> {
        let coefficients = system
            .names()
            .iter()
            .zip(fit.solution.iter().zip(&fit.std_errors))
            .map(|(name, (&value, &std_error))| Coefficient {
                name: name.clone(),
                value,
                std_error,
            })
            .collect();
        let summary = FitSummary {
            solver: solver.to_owned(),
            harmonics: params.harmonics(),
            clock: *params.clock(),
            rows: fit.rows,
            unknowns: fit.cols,
            segments: system.segments(),
            whirling_segments: system.whirling_segments(),
            condition: fit.condition,
            residual_rms: fit.residual_rms,
            residual_variance: fit.residual_variance,
        };
        Ok(IdentifiedModel::from_coefficients(
            basis,
            params.form().clone(),
            params.clock().drive_angular_frequency(),
            coefficients,
            Some(summary),
        )?)
    }
}
