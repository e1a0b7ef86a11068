//! Output-error refinement: the coefficients that make a model's free run follow a record.
//!
//! The weak form fits the equation to the record (an equation error); a free run under the
//! record's input is what [`compare`](crate::compare()) scores, and what a user of the model
//! does with it. The two optima differ wherever the equation error is not the whole story: the
//! noise in the measured output, terms that are almost but not quite right, a drive measured
//! through a filter. The refinement starts from a fitted model and minimises the free run's
//! error over the record by Levenberg–Marquardt:
//!
//! - each piece of the record (between gaps) longer than `init` samples is run from the state
//!   fitted to its first `init` samples, as [`compare`](crate::compare()) sets it, and scored on
//!   the rest, so that the state is not a free parameter that hides the model's errors (on an
//!   integrating plant a free initial position would absorb a biased force's drift);
//! - the Jacobian is by forward differences (one free run per coefficient, in parallel), which a
//!   non-smooth term such as `sign(x')` tolerates;
//! - a step is taken only if the error falls; the search stops when a step lowers it by less
//!   than [`REFINE_TOLERANCE`] (relative), after `max_iterations`, or when no step helps;
//! - the standard errors are those of the output-error least squares at the end,
//!   `σ² (JᵀJ)⁻¹` with `σ²` the mean square of the residual (white measurement noise assumed:
//!   they are optimistic for a residual that is correlated from sample to sample).

use hb_model::{Coefficient, IdentifiedModel};
use hb_record::prepare::GridData;
use nalgebra::{DMatrix, DVector};
use pendulum_sim::{Tolerances, fit_initial_state, free_run};
use rayon::prelude::*;
use serde::Serialize;

use crate::compare::{difference, driven_on};
use crate::error::RunError;

/// The relative decrease of the squared error below which the search has converged.
pub const REFINE_TOLERANCE: f64 = 1e-5;

/// The forward-difference step, relative to each coefficient. Not smaller: a free run with
/// dry friction sticks and slips at event times located to a tolerance, and an adaptive
/// integrator picks its steps anew for every coefficient, so that the free run's error is a
/// smooth function of the coefficients only to about 1e-4 of itself (measured on a ball screw
/// with dry friction); a step of a millionth of a coefficient would difference that noise.
const FD_STEP: f64 = 1e-3;

/// What a refinement did.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Refinement {
    /// The RMSE of the free run over the scored samples, with the coefficients given.
    pub rmse_before: f64,
    /// The same with the refined coefficients.
    pub rmse_after: f64,
    /// Samples scored (those after each piece's first `init`, but the samples bridged into gaps,
    /// which were not measured).
    pub scored: usize,
    /// Samples of each piece that set its state and are not scored.
    pub init: usize,
    /// Levenberg–Marquardt iterations (Jacobians evaluated).
    pub iterations: usize,
    /// Free runs of the whole record.
    pub simulations: usize,
    /// Whether the search converged (rather than stopping at the iteration limit).
    pub converged: bool,
    /// The coefficients given (the weak form's), keyed by term name in the model's order.
    pub start: Vec<(String, f64)>,
}

/// The residuals of `model`'s free runs on the pieces of `grid` longer than `init`, the samples
/// flagged in `bridged` left out: `None` when a run cannot start or stops (the model blows up,
/// or no state runs through the first samples).
fn residuals(
    model: &IdentifiedModel,
    grid: &GridData,
    bridged: &[bool],
    init: usize,
    tolerances: Tolerances,
) -> Result<Option<Vec<f64>>, RunError> {
    let mut r = Vec::new();
    for piece in grid.pieces.iter().filter(|p| p.len() > init) {
        let y = &grid.x[piece.clone()];
        let t0 = grid.t0 + piece.start as f64 * grid.dt;
        let model = driven_on(model, grid, piece.start, piece.end)?;
        let Ok(state) = fit_initial_state(&model, &y[..init], t0, grid.dt, grid.domain, tolerances) else {
            return Ok(None);
        };
        let run = free_run(&model, t0, grid.dt, y.len(), state.state, tolerances)?;
        if run.stopped.is_some() {
            return Ok(None);
        }
        r.extend(
            (init..y.len())
                .filter(|&j| !bridged[piece.start + j])
                .map(|j| difference(grid.domain, run.x[j], y[j])),
        );
    }
    Ok(Some(r))
}

/// `model` with coefficient `values` (in its order) and `std_errors`.
fn with_values(
    model: &IdentifiedModel,
    values: &[f64],
    std_errors: Option<&[f64]>,
) -> Result<IdentifiedModel, RunError> {
    let coefficients = model
        .coefficients()
        .iter()
        .enumerate()
        .map(|(j, c)| Coefficient {
            name: c.name.clone(),
            value: values[j],
            std_error: std_errors.map_or(c.std_error, |s| s[j]),
        })
        .collect();
    let refined = IdentifiedModel::from_coefficients(
        *model.basis(),
        model.form().clone(),
        model.drive_angular_frequency(),
        coefficients,
        model.summary().cloned(),
    )?;
    Ok(match model.measured_drive() {
        Some(d) => refined.with_measured_drive(d.clone())?,
        None => refined,
    })
}

fn squared(r: &[f64]) -> f64 {
    r.iter().map(|e| e * e).sum()
}

/// Refines `model`'s coefficients on `grid` (see the [module documentation](self)): each piece
/// longer than `init` samples is scored after its first `init`, at most `max_iterations`
/// Levenberg–Marquardt steps. `progress` hears the iterations done of at most `max_iterations`.
///
/// Errors: no piece longer than `init`, or no free run of the given model through the record
/// ([`RunError::Refine`]); a model that cannot be rebuilt with new values.
pub fn refine(
    model: &IdentifiedModel,
    grid: &GridData,
    init: usize,
    tolerances: Tolerances,
    max_iterations: usize,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<(IdentifiedModel, Refinement), RunError> {
    if !grid.pieces.iter().any(|p| p.len() > init) {
        return Err(RunError::Refine(format!(
            "no piece of the record is longer than the {init} samples that set its state"
        )));
    }
    let start: Vec<f64> = model.coefficients().iter().map(|c| c.value).collect();
    let n = start.len();
    // A sample bridged into a gap was not measured: every run goes on through it, unscored.
    let mut bridged = vec![false; grid.x.len()];
    for b in &grid.bridged {
        bridged[b.start.min(grid.x.len())..b.end.min(grid.x.len())].fill(true);
    }
    let evaluate = |values: &[f64]| -> Result<Option<Vec<f64>>, RunError> {
        residuals(
            &with_values(model, values, None)?,
            grid,
            &bridged,
            init,
            tolerances,
        )
    };
    let Some(mut r) = evaluate(&start)? else {
        return Err(RunError::Refine(
            "the model's free run does not go through the record from the fitted states".into(),
        ));
    };
    let scored = r.len();
    let rmse_before = (squared(&r) / scored as f64).sqrt();
    let mut theta = start.clone();
    let mut cost = squared(&r);
    let mut simulations = 1;
    let mut iterations = 0;
    let mut converged = false;
    let mut lambda = 1e-3;
    // Forward-difference steps: FD_STEP of each coefficient (a millionth of the largest for a
    // zero one).
    let scale = theta.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-12);
    let jacobian = |theta: &[f64], r: &[f64]| -> Result<Option<Vec<Vec<f64>>>, RunError> {
        let columns: Vec<Result<Option<Vec<f64>>, RunError>> = (0..n)
            .into_par_iter()
            .map(|j| {
                let h = if theta[j] != 0.0 {
                    FD_STEP * theta[j].abs()
                } else {
                    1e-6 * scale
                };
                let mut shifted = theta.to_vec();
                shifted[j] += h;
                Ok(evaluate(&shifted)?.map(|rj| rj.iter().zip(r).map(|(a, b)| (a - b) / h).collect()))
            })
            .collect();
        columns.into_iter().collect::<Result<Option<Vec<_>>, _>>()
    };
    let mut last_jacobian = None;
    while iterations < max_iterations {
        let Some(jac) = jacobian(&theta, &r)? else {
            break;
        };
        simulations += n;
        iterations += 1;
        progress(iterations, max_iterations);
        let jac = DMatrix::from_fn(r.len(), n, |i, j| jac[j][i]);
        let jtj = jac.tr_mul(&jac);
        let jtr = jac.tr_mul(&DVector::from_column_slice(&r));
        last_jacobian = Some(jtj.clone());
        let mut stepped = false;
        while lambda < 1e6 {
            let mut a = jtj.clone();
            for j in 0..n {
                a[(j, j)] += lambda * jtj[(j, j)].max(1e-300);
            }
            let Some(delta) = a.cholesky().map(|c| c.solve(&-&jtr)) else {
                lambda *= 4.0;
                continue;
            };
            let trial: Vec<f64> = theta.iter().zip(&delta).map(|(t, d)| t + d).collect();
            simulations += 1;
            match evaluate(&trial)? {
                Some(rt) if squared(&rt) < cost => {
                    let new_cost = squared(&rt);
                    converged = cost - new_cost < REFINE_TOLERANCE * cost;
                    theta = trial;
                    r = rt;
                    cost = new_cost;
                    lambda = (lambda / 3.0).max(1e-9);
                    stepped = true;
                    break;
                }
                _ => lambda *= 4.0,
            }
        }
        if !stepped {
            converged = true;
            break;
        }
        if converged {
            break;
        }
    }
    // Standard errors from the last Jacobian (at the last point it was evaluated: the final
    // one, or the one before a step too small to matter).
    let std_errors = last_jacobian.and_then(|jtj| {
        let sigma2 = cost / (scored.saturating_sub(n).max(1)) as f64;
        let inverse = jtj.cholesky()?.inverse();
        Some(
            (0..n)
                .map(|j| (sigma2 * inverse[(j, j)]).sqrt())
                .collect::<Vec<f64>>(),
        )
    });
    let refined = with_values(model, &theta, std_errors.as_deref())?;
    Ok((
        refined,
        Refinement {
            rmse_before,
            rmse_after: (cost / scored as f64).sqrt(),
            scored,
            init,
            iterations,
            simulations,
            converged,
            start: model
                .coefficients()
                .iter()
                .map(|c| (c.name.clone(), c.value))
                .collect(),
        },
    ))
}
