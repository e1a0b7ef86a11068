//! Physical parameters shared by the equations of a system: the tied fit.
//!
//! The untied fit identifies each equation `q_i'' + Σ_k c_ik g_ik = 0` on its own. A rigid-body
//! system has fewer unknowns than that: its mass matrix is symmetric and one inertia or one
//! mass–length product enters several coefficients of both equations. A [`TieSpec`] writes each
//! coefficient of each equation, its own acceleration's included, as a linear combination of
//! named parameters θ, or as a fixed number (the measured torque's `-1` in the torque form
//! `A_i q_i'' + Σ_k a_ik g_ik − τ_i = 0`):
//!
//! ```text
//! a_ik = F_ik + Σ_m P_ikm θ_m        (F_ik = 0 for a combination, P_ikm = 0 for a number)
//! ```
//!
//! [`Tie::fit`] takes the weak-form systems the untied fit assembles for each equation on the
//! shared windows (`S_i c_i = β_i`, with `β_i = −∫ψ'' q_i`, so the own acceleration's column is
//! `−β_i`), makes the column of parameter `m` in the rows of equation `i`
//! `Σ_k P_ikm S_i[:, k] − P_i,own,m β_i`, moves the fixed terms to the right-hand side, and
//! solves the rows of every equation stacked, by the one least squares of the crate
//! ([`LstsqSolver`], which scales the columns: an inertia can be 1e-4 of the other parameters).
//!
//! Weights: a first pass with every row as assembled (torque units), then each equation's rows
//! divided by its own acceleration's coefficient `A_i` from that pass, so that every residual is
//! in the acceleration units of the untied fit (`S_i c_i − β_i`) and the tied fit minimises the
//! untied fit's objective under the constraints. The parameters' standard errors are those of
//! the weighted stacked regression; each equation's normalised coefficients `c_ik = a_ik / A_i`
//! get theirs from the parameters' covariance (first order).

use std::collections::BTreeMap;

use faer::{Col, Mat};
use hb_model::{Names, TermList};
use serde::{Deserialize, Serialize};

use crate::bootstrap::{Bootstrap, BootstrapParams, NoIntervals, bootstrap_or_reason};
use crate::error::{LstsqError, SolveError, TieError};
use crate::lstsq::{LstsqSolver, on_factor_pool, triangular_factor};
use crate::system::{Block, LinearSystem};

/// A coefficient of a tie spec: a fixed number, or a linear combination of parameters by name
/// (`{"Ia": 1, "Ir": 37}`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum TieCoefficient {
    /// A fixed coefficient.
    Fixed(f64),
    /// `Σ weight · parameter`.
    Linear(BTreeMap<String, f64>),
}

/// The serialised form of a [`TieSpec`]: `{"parameters": [...], "equations": {coordinate:
/// {term: coefficient}}}`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct TieSpecRaw {
    parameters: Vec<String>,
    equations: BTreeMap<String, BTreeMap<String, TieCoefficient>>,
}

/// One equation of a [`TieSpec`], as written.
#[derive(Debug, Clone, PartialEq)]
struct EquationSpec {
    coordinate: String,
    own: TieCoefficient,
    /// The other terms by their names as given, in the order of the names.
    terms: Vec<(String, TieCoefficient)>,
}

/// Which coefficients of a system's equations are shared physical parameters: per equation
/// (keyed by its coordinate), each term's coefficient as a fixed number or a linear combination of
/// named parameters, the own acceleration (`q1''` in the equation of `q1`) included. Checked when
/// built and when deserialised: parameters named once and each used, every combination naming
/// known parameters with finite weights, every equation with its own acceleration (not fixed to
/// 0) and at least one fixed nonzero coefficient (otherwise its scale is undetermined). The
/// terms and coordinates are checked against a record's names by [`TieSpec::resolve`].
///
/// A JSON object has no order: the terms of an equation come in the order of their names.
///
/// ```
/// use hb_model::Names;
/// use hb_solve::TieSpec;
///
/// let spec: TieSpec = serde_json::from_str(
///     r#"{"parameters": ["m", "c"],
///         "equations": {"x1": {"x1''": {"m": 1}, "x1'": {"c": 1}, "f": -1},
///                       "x2": {"x2''": {"m": 1}, "x2'": {"c": 2}, "f": -1}}}"#,
/// )?;
/// let names = Names::new(["x1", "x2"], ["f"])?;
/// let tie = spec.resolve(&names)?;
/// assert_eq!(tie.parameters(), ["m", "c"]);
/// // A JSON object has no order: the terms come in the order of their names.
/// assert_eq!(tie.terms(1).names(), ["f", "x2'"]);
/// // A parameter that no coefficient uses is refused.
/// let unused = r#"{"parameters": ["m", "k"], "equations": {"x1": {"x1''": {"m": 1}, "f": -1}}}"#;
/// assert!(serde_json::from_str::<TieSpec>(unused).unwrap_err().to_string().contains("'k'"));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "TieSpecRaw", into = "TieSpecRaw")]
pub struct TieSpec {
    parameters: Vec<String>,
    equations: Vec<EquationSpec>,
}

impl TryFrom<TieSpecRaw> for TieSpec {
    type Error = TieError;

    fn try_from(raw: TieSpecRaw) -> Result<Self, TieError> {
        let equations = raw
            .equations
            .into_iter()
            .map(|(c, terms)| (c, terms.into_iter().collect()))
            .collect();
        Self::new(raw.parameters, equations)
    }
}

impl From<TieSpec> for TieSpecRaw {
    fn from(spec: TieSpec) -> Self {
        let equations = spec
            .equations
            .into_iter()
            .map(|e| {
                let mut terms: BTreeMap<String, TieCoefficient> = e.terms.into_iter().collect();
                terms.insert(format!("{}''", e.coordinate), e.own);
                (e.coordinate, terms)
            })
            .collect();
        Self {
            parameters: spec.parameters,
            equations,
        }
    }
}

/// A key naming the own acceleration of `coordinate` (white space ignored).
fn is_own_acceleration(key: &str, coordinate: &str) -> bool {
    let key: String = key.chars().filter(|c| !c.is_whitespace()).collect();
    key == format!("{coordinate}''")
}

impl TieSpec {
    /// A spec of `parameters` and, per coordinate by name, its terms' coefficients (the own
    /// acceleration's among them, keyed `q''`), checked as [`TieSpec`] says.
    ///
    /// Errors: [`TieError::Parameters`], [`TieError::UnknownParameter`],
    /// [`TieError::UnusedParameter`], [`TieError::BadCoefficient`],
    /// [`TieError::OwnAcceleration`], [`TieError::NoFixedCoefficient`], [`TieError::NoEquations`].
    pub fn new(
        parameters: Vec<String>,
        equations: Vec<(String, Vec<(String, TieCoefficient)>)>,
    ) -> Result<Self, TieError> {
        if parameters.is_empty() {
            return Err(TieError::Parameters(
                "no parameter: list the shared parameters under \"parameters\"".into(),
            ));
        }
        for (i, p) in parameters.iter().enumerate() {
            if p.trim().is_empty() {
                return Err(TieError::Parameters("a parameter with an empty name".into()));
            }
            if parameters[..i].contains(p) {
                return Err(TieError::Parameters(format!(
                    "the parameter '{p}' is listed twice"
                )));
            }
        }
        if equations.is_empty() {
            return Err(TieError::NoEquations);
        }
        let known = parameters.join(", ");
        let mut used = vec![false; parameters.len()];
        let mut out = Vec::with_capacity(equations.len());
        for (coordinate, terms) in equations {
            let mut own = None;
            let mut rest = Vec::with_capacity(terms.len());
            let mut fixed = false;
            for (term, coefficient) in terms {
                let bad = |why| TieError::BadCoefficient {
                    coordinate: coordinate.clone(),
                    term: term.clone(),
                    why,
                };
                match &coefficient {
                    TieCoefficient::Fixed(v) if !v.is_finite() => return Err(bad("not a finite number")),
                    TieCoefficient::Fixed(v) => fixed |= *v != 0.0,
                    TieCoefficient::Linear(map) => {
                        if map.is_empty() {
                            return Err(bad(
                                "an empty combination (give a number for a fixed coefficient)",
                            ));
                        }
                        for (p, w) in map {
                            let Some(m) = parameters.iter().position(|q| q == p) else {
                                return Err(TieError::UnknownParameter {
                                    coordinate: coordinate.clone(),
                                    term: term.clone(),
                                    parameter: p.clone(),
                                    known: known.clone(),
                                });
                            };
                            if !w.is_finite() {
                                return Err(bad("a weight that is not a finite number"));
                            }
                            used[m] |= *w != 0.0;
                        }
                    }
                }
                if is_own_acceleration(&term, &coordinate) {
                    own = Some(coefficient);
                } else {
                    rest.push((term, coefficient));
                }
            }
            let own = match own {
                None => {
                    return Err(TieError::OwnAcceleration {
                        coordinate,
                        why: "has no coefficient of its own acceleration",
                    });
                }
                Some(TieCoefficient::Fixed(0.0)) => {
                    return Err(TieError::OwnAcceleration {
                        coordinate,
                        why: "has its own acceleration fixed to 0",
                    });
                }
                Some(TieCoefficient::Linear(m)) if m.values().all(|w| *w == 0.0) => {
                    return Err(TieError::OwnAcceleration {
                        coordinate,
                        why: "has its own acceleration's combination all 0",
                    });
                }
                Some(c) => c,
            };
            if !fixed {
                return Err(TieError::NoFixedCoefficient(coordinate));
            }
            out.push(EquationSpec {
                coordinate,
                own,
                terms: rest,
            });
        }
        if let Some(m) = used.iter().position(|u| !u) {
            return Err(TieError::UnusedParameter(parameters[m].clone()));
        }
        Ok(Self {
            parameters,
            equations: out,
        })
    }

    /// The parameters, in the order given.
    pub fn parameters(&self) -> &[String] {
        &self.parameters
    }

    /// The coordinates that have an equation, in the order of their names.
    pub fn coordinates(&self) -> impl Iterator<Item = &str> {
        self.equations.iter().map(|e| e.coordinate.as_str())
    }

    /// The spec read in a record's `names`: one equation per coordinate, each key parsed as one
    /// term of the `--terms` grammar for that equation ([`TermList::parse_in`]).
    ///
    /// Errors: [`TieError::UnknownCoordinate`], [`TieError::MissingEquation`] and
    /// [`TieError::Term`] (a key that does not parse, is more than one term, or names a term
    /// twice).
    pub fn resolve(&self, names: &Names) -> Result<Tie, TieError> {
        let coordinates = names.coordinates();
        if let Some(e) = self
            .equations
            .iter()
            .find(|e| names.coordinate(&e.coordinate).is_none())
        {
            return Err(TieError::UnknownCoordinate {
                coordinate: e.coordinate.clone(),
                known: coordinates.join(", "),
            });
        }
        let p = self.parameters.len();
        let affine = |c: &TieCoefficient| match c {
            TieCoefficient::Fixed(v) => Affine {
                constant: *v,
                weights: vec![0.0; p],
            },
            TieCoefficient::Linear(map) => {
                let mut weights = vec![0.0; p];
                for (name, w) in map {
                    let m = self.parameters.iter().position(|q| q == name).expect("checked");
                    weights[m] = *w;
                }
                Affine {
                    constant: 0.0,
                    weights,
                }
            }
        };
        let mut equations = Vec::with_capacity(coordinates.len());
        for (i, coordinate) in coordinates.iter().enumerate() {
            let Some(spec) = self.equations.iter().find(|e| e.coordinate == *coordinate) else {
                return Err(TieError::MissingEquation(coordinate.clone()));
            };
            let term_error = |term: &str, why: String| TieError::Term {
                coordinate: coordinate.clone(),
                term: term.to_owned(),
                why,
            };
            let mut terms = Vec::with_capacity(spec.terms.len());
            for (key, _) in &spec.terms {
                let one = TermList::parse_in(key, names, i).map_err(|e| term_error(key, e.to_string()))?;
                if one.len() != 1 {
                    return Err(term_error(
                        key,
                        format!("names {} terms: a key is one term", one.len()),
                    ));
                }
                let term = one.terms()[0];
                if let Some(before) = terms.iter().position(|t| *t == term) {
                    return Err(term_error(
                        key,
                        format!("the same term as `{}`", spec.terms[before].0),
                    ));
                }
                terms.push(term);
            }
            if terms.is_empty() {
                return Err(term_error(
                    &format!("{coordinate}''"),
                    "the equation has no term besides its own acceleration".into(),
                ));
            }
            let list = TermList::new_in(terms, names.clone(), i)
                .map_err(|e| term_error(&spec.terms[0].0, e.to_string()))?;
            equations.push(TiedEquation {
                coordinate: coordinate.clone(),
                terms: list,
                own: affine(&spec.own),
                coefficients: spec.terms.iter().map(|(_, c)| affine(c)).collect(),
            });
        }
        Ok(Tie {
            parameters: self.parameters.clone(),
            equations,
        })
    }
}

/// `constant + Σ_m weights[m] θ_m`.
#[derive(Debug, Clone, PartialEq)]
struct Affine {
    constant: f64,
    weights: Vec<f64>,
}

impl Affine {
    fn eval(&self, theta: &[f64]) -> f64 {
        self.constant + self.weights.iter().zip(theta).map(|(w, t)| w * t).sum::<f64>()
    }
}

/// One equation of a [`Tie`]: its terms and the coefficients as affine functions of the
/// parameters.
#[derive(Debug, Clone, PartialEq)]
struct TiedEquation {
    coordinate: String,
    terms: TermList,
    own: Affine,
    coefficients: Vec<Affine>,
}

impl TiedEquation {
    /// The coefficient of the equation's own acceleration at `theta`, by which its terms are
    /// normalised: [`TieError::ZeroMass`] where it is zero or not finite.
    fn own_mass(&self, theta: &[f64]) -> Result<f64, TieError> {
        let a = self.own.eval(theta);
        if a.is_finite() && a != 0.0 {
            Ok(a)
        } else {
            Err(TieError::ZeroMass {
                coordinate: self.coordinate.clone(),
                value: a,
            })
        }
    }
}

/// A [`TieSpec`] read in a record's names ([`TieSpec::resolve`]): one equation per coordinate, in
/// the coordinates' order, each with its list of terms (the own acceleration not among them).
#[derive(Debug, Clone, PartialEq)]
pub struct Tie {
    parameters: Vec<String>,
    equations: Vec<TiedEquation>,
}

/// A parameter of a tied fit with its standard error.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TiedParameter {
    /// Its name.
    pub name: String,
    /// The estimate.
    pub value: f64,
    /// Its standard error (of the weighted stacked regression).
    pub std_error: f64,
}

/// One equation of a tied fit, normalised by its own acceleration's coefficient.
#[derive(Debug, Clone, PartialEq)]
pub struct TiedEquationFit {
    /// The coefficient of the own acceleration in the torque form, `A_i`.
    pub own: f64,
    /// The coefficients `c_ik = a_ik / A_i` of the equation's terms, in the order of its list.
    pub coefficients: Vec<f64>,
    /// Their standard errors, from the parameters' covariance to first order.
    pub std_errors: Vec<f64>,
    /// The rows of the equation in the stacked system.
    pub rows: usize,
    /// `sqrt(RSS_i / rows_i)` of its residual, in the untied fit's units (`S_i c_i − β_i`).
    pub residual_rms: f64,
    /// `RSS_i / rows_i` times `rows / (rows − parameters)` of the stacked system.
    pub residual_variance: f64,
}

/// The outcome of [`Tie::fit`].
#[derive(Debug, Clone, PartialEq)]
pub struct TiedFit {
    /// The parameters, in the spec's order.
    pub parameters: Vec<TiedParameter>,
    /// One per equation, in the coordinates' order.
    pub equations: Vec<TiedEquationFit>,
    /// The condition number of the column-scaled weighted stacked system.
    pub condition: f64,
    /// Rows of the stacked system.
    pub rows: usize,
    /// The weight of each equation's rows in the final pass, `1 / |A_i|` of the first.
    pub weights: Vec<f64>,
}

impl Tie {
    /// The parameters, in the spec's order.
    pub fn parameters(&self) -> &[String] {
        &self.parameters
    }

    /// The number of equations (the record's coordinates).
    pub fn equations(&self) -> usize {
        self.equations.len()
    }

    /// The terms of the equation of coordinate `i` (its own acceleration not among them): the
    /// list the equation is assembled and saved with.
    pub fn terms(&self, i: usize) -> &TermList {
        &self.equations[i].terms
    }

    /// Fits the parameters to the assembled `systems`, one per equation in the coordinates' order,
    /// each assembled with [`Tie::terms`] on the same windows (columns found by the terms'
    /// names), by `solver`: the column of parameter `m` in the rows of equation `i` is
    /// `Σ_k P_ikm S_i[:, k] − P_i,own,m β_i` (the own acceleration's column is `−β_i`,
    /// `β_i = −∫ψ'' q_i`), the fixed terms go to the right-hand side, and the rows are weighted
    /// first not at all (torque units), then each equation's by `1 / |A_i|` of that pass, so that
    /// every residual is in the untied fit's acceleration units (`S_i c_i − β_i`). The parameters'
    /// standard errors are the weighted regression's; the coefficients' come from the parameters'
    /// covariance (first order, `s² (XᵀX)⁻¹` from the triangular factor, never from `XᵀX`).
    ///
    /// Errors: [`TieError::SystemMismatch`], [`TieError::NotIdentifiable`] (a rank-deficient
    /// stacked system, naming the parameter that weighs most in the weakest direction),
    /// [`TieError::ZeroMass`], and the solver's.
    pub fn fit<S: LstsqSolver + ?Sized>(
        &self,
        systems: &[LinearSystem],
        solver: &S,
    ) -> Result<TiedFit, SolveError> {
        let columns = self.columns(systems)?;
        let p = self.parameters.len();
        // The equations the systems stand for (a compressed system's rows are fewer).
        let rows: usize = systems.iter().map(LinearSystem::equations).sum();
        // Pass 1: torque units; pass 2: each equation's rows over its own acceleration's coefficient.
        let mut weights = vec![1.0; systems.len()];
        let mut theta = Vec::new();
        let mut last = None;
        for pass in 0..2 {
            let (x, y) = self.stacked(systems, &columns, &weights);
            let fit = solver
                .solve_standing_for(x.as_ref(), y.as_ref(), rows)
                .map_err(|e| self.rank_error(e))?;
            theta = fit.solution.clone();
            if pass == 0 {
                for (w, e) in weights.iter_mut().zip(&self.equations) {
                    *w = 1.0 / e.own_mass(&theta)?.abs();
                }
            }
            last = Some((x, fit));
        }
        let (x, fit) = last.expect("two passes");
        let covariance = covariance(&x, fit.residual_variance);
        let parameters = self
            .parameters
            .iter()
            .zip(theta.iter().zip(&fit.std_errors))
            .map(|(name, (&value, &std_error))| TiedParameter {
                name: name.clone(),
                value,
                std_error,
            })
            .collect();
        let dof = rows as f64 / (rows as f64 - p as f64).max(1.0);
        let mut equations = Vec::with_capacity(systems.len());
        for ((e, s), cols) in self.equations.iter().zip(systems).zip(&columns) {
            let a = e.own_mass(&theta)?;
            let coefficients: Vec<f64> = e.coefficients.iter().map(|c| c.eval(&theta) / a).collect();
            let std_errors = e
                .coefficients
                .iter()
                .zip(&coefficients)
                .map(|(k, &c)| {
                    let g: Vec<f64> = (0..p)
                        .map(|m| (k.weights[m] - c * e.own.weights[m]) / a)
                        .collect();
                    let v: f64 = (0..p)
                        .flat_map(|i| (0..p).map(move |j| (i, j)))
                        .map(|(i, j)| g[i] * covariance[(i, j)] * g[j])
                        .sum();
                    v.max(0.0).sqrt()
                })
                .collect();
            let (m, rhs) = (s.matrix(), s.rhs());
            let rss: f64 = (0..s.rows())
                .map(|r| {
                    let fitted: f64 = cols.iter().zip(&coefficients).map(|(&c, v)| m[(r, c)] * v).sum();
                    (fitted - rhs[r]).powi(2)
                })
                .sum();
            let n = s.equations().max(1) as f64;
            equations.push(TiedEquationFit {
                own: a,
                coefficients,
                std_errors,
                rows: s.equations(),
                residual_rms: (rss / n).sqrt(),
                residual_variance: rss / n * dof,
            });
        }
        Ok(TiedFit {
            parameters,
            equations,
            condition: fit.condition,
            rows,
            weights,
        })
    }

    /// Bootstrap intervals of the parameters of `fit` (made by [`Tie::fit`] from `systems`): the
    /// crate's moving-block bootstrap ([`crate::bootstrap_fit`]) over the shared windows, each
    /// window's rows of every equation drawn together, the weights of the fit held.
    ///
    /// Errors: why there are none ([`NoIntervals`]): the equations' windows differ, or the
    /// bootstrap's own reasons.
    pub fn bootstrap<S: LstsqSolver + ?Sized>(
        &self,
        systems: &[LinearSystem],
        fit: &TiedFit,
        solver: &S,
        params: &BootstrapParams,
    ) -> Result<Bootstrap, NoIntervals> {
        let no = |reason: String| NoIntervals { reason };
        let first = systems.first().ok_or_else(|| no("no equation".into()))?;
        let windows = first.blocks();
        let same = systems.iter().all(|s| {
            s.blocks().len() == windows.len()
                && s.blocks()
                    .iter()
                    .zip(windows)
                    .all(|(a, b)| a.segment == b.segment)
        });
        if !same || fit.weights.len() != systems.len() {
            return Err(no("the equations were not assembled on the same windows".into()));
        }
        let columns = self.columns(systems).map_err(|e| no(e.to_string()))?;
        let (x, y) = self.stacked(systems, &columns, &fit.weights);
        // Each equation's first row in the stacked system.
        let starts: Vec<usize> = systems
            .iter()
            .scan(0, |at, s| {
                let here = *at;
                *at += s.rows();
                Some(here)
            })
            .collect();
        // The rows window by window: every equation's rows of a window in one block.
        let mut order = Vec::with_capacity(x.nrows());
        let mut blocks = Vec::with_capacity(windows.len());
        for (w, window) in windows.iter().enumerate() {
            let first_row = order.len();
            for (s, &start) in systems.iter().zip(&starts) {
                let b = &s.blocks()[w];
                order.extend(start + b.first_row..start + b.first_row + b.rows);
            }
            blocks.push(Block {
                first_row,
                rows: order.len() - first_row,
                harmonics: 0,
                ..*window
            });
        }
        let matrix = Mat::from_fn(order.len(), x.ncols(), |r, c| x[(order[r], c)]);
        let rhs = Col::from_fn(order.len(), |r| y[order[r]]);
        let system = LinearSystem::from_parts(matrix, rhs, self.parameters.clone(), blocks);
        let lstsq = system.solve(solver).map_err(|e| no(e.to_string()))?;
        bootstrap_or_reason(&system, &lstsq, solver, params)
    }

    /// Each term's column in its equation's system, found by the terms' names.
    fn columns(&self, systems: &[LinearSystem]) -> Result<Vec<Vec<usize>>, TieError> {
        let mismatch = |term: &str| TieError::SystemMismatch {
            expected: self.equations.len(),
            found: systems.len(),
            term: term.to_owned(),
        };
        if systems.len() != self.equations.len() {
            return Err(mismatch(""));
        }
        let mut columns = Vec::with_capacity(systems.len());
        for (e, s) in self.equations.iter().zip(systems) {
            let mut cols = Vec::with_capacity(e.terms.len());
            for name in e.terms.names() {
                let c = s
                    .names()
                    .iter()
                    .position(|n| *n == name)
                    .ok_or_else(|| mismatch(&name))?;
                cols.push(c);
            }
            columns.push(cols);
        }
        Ok(columns)
    }

    /// The weighted stacked system: the column of each parameter and the right-hand side of the
    /// fixed terms, equation after equation.
    fn stacked(
        &self,
        systems: &[LinearSystem],
        columns: &[Vec<usize>],
        weights: &[f64],
    ) -> (Mat<f64>, Col<f64>) {
        let p = self.parameters.len();
        let rows: usize = systems.iter().map(LinearSystem::rows).sum();
        let mut x = Mat::<f64>::zeros(rows, p);
        let mut y = Col::<f64>::zeros(rows);
        let mut first = 0;
        for (((e, s), cols), &w) in self.equations.iter().zip(systems).zip(columns).zip(weights) {
            let (a, b) = (s.matrix(), s.rhs());
            for r in 0..s.rows() {
                // Own acceleration: its column is −β.
                let mut fixed = -e.own.constant * b[r];
                for m in 0..p {
                    x[(first + r, m)] = -e.own.weights[m] * b[r];
                }
                for (k, &c) in e.coefficients.iter().zip(cols) {
                    let v = a[(r, c)];
                    fixed += k.constant * v;
                    for m in 0..p {
                        x[(first + r, m)] += k.weights[m] * v;
                    }
                }
                for m in 0..p {
                    x[(first + r, m)] *= w;
                }
                y[first + r] = -w * fixed;
            }
            first += s.rows();
        }
        (x, y)
    }

    /// A rank deficiency of the stacked system named by its parameter.
    fn rank_error(&self, e: SolveError) -> SolveError {
        match e {
            SolveError::Lstsq(LstsqError::RankDeficient {
                rank,
                unknowns,
                column,
                ..
            }) => TieError::NotIdentifiable {
                parameter: self.parameters.get(column).cloned().unwrap_or_default(),
                rank,
                unknowns,
            }
            .into(),
            other => other,
        }
    }
}

/// `s² (XᵀX)⁻¹` from the triangular factor of the column-scaled `x` (never by forming `XᵀX`).
fn covariance(x: &Mat<f64>, variance: f64) -> Mat<f64> {
    let p = x.ncols();
    let norms: Vec<f64> = (0..p)
        .map(|j| {
            x.col(j)
                .iter()
                .map(|v| v * v)
                .sum::<f64>()
                .sqrt()
                .max(f64::MIN_POSITIVE)
        })
        .collect();
    let scaled = Mat::from_fn(x.nrows(), p, |i, j| x[(i, j)] / norms[j]);
    let r = on_factor_pool(|| triangular_factor(scaled));
    // R⁻¹ by back substitution (upper triangular, p × p).
    let mut rinv = Mat::<f64>::zeros(p, p);
    for j in 0..p {
        for i in (0..=j).rev() {
            let mut s = if i == j { 1.0 } else { 0.0 };
            for k in i + 1..=j {
                s -= r[(i, k)] * rinv[(k, j)];
            }
            rinv[(i, j)] = s / r[(i, i)];
        }
    }
    Mat::from_fn(p, p, |i, j| {
        let g: f64 = (0..p).map(|k| rinv[(i, k)] * rinv[(j, k)]).sum();
        variance * g / (norms[i] * norms[j])
    })
}
