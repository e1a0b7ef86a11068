//! A system of equations, one per coordinate: `q_i'' + Σ_k c_ik g_ik(t, q, q', q'') = 0`, each
//! an [`IdentifiedModel`] whose terms are written in the system's [`Names`], solved for the
//! accelerations through its mass matrix, and saved (format 5; a system of one coordinate in the
//! names of one, `x` and at most the drive `p`, is saved as the model it is, in format 4).

use circle_signal::system::MultiSystem;
pub use circle_signal::system::SingularMass;
use hb_basis::{Basis, BasisKind, Domain};
use serde::{Deserialize, Serialize};

use crate::drive::MeasuredDrive;
use crate::error::{ModelError, ModelIoError, TermError};
use crate::form::ModelForm;
use crate::io::{CoefficientMap, MODEL_FORMAT, MODEL_MAGIC, MODEL_VERSION, SYSTEM_VERSION};
use crate::model::{FitSummary, IdentifiedModel};
use crate::terms::{MAX_COORDINATES, Names, TermList};

/// A system of `n` coordinates with one equation each, in the [`Names`] of its record: equation
/// `i` is a model ([`IdentifiedModel`]) of the own coordinate `i`, its terms possibly reading the
/// other coordinates, their velocities and accelerations, and the measured drives.
///
/// The accelerations solve `M(t, q) q'' = −r(t, q, q')`, row `i` of `M` being `1` at `i` plus the
/// coefficients of the terms of equation `i` in an acceleration ([`IdentifiedModel::equation_at`]).
/// A record of one coordinate is the system of one equation ([`IdentifiedSystem::one`]).
///
/// ```
/// use hb_basis::{BasisKind, Domain, Harmonic};
/// use hb_model::{IdentifiedModel, IdentifiedSystem, ModelForm, Names, TermList};
///
/// // A double pendulum: θ1'' + 0.5 θ2''cos(θ1−θ2) + 0.5 θ2'² sin(θ1−θ2) + 2 sin θ1 = 0 and
/// // θ2'' + θ1''cos(θ1−θ2) − θ1'² sin(θ1−θ2) + 2 sin θ2 = 0.
/// let names = Names::new(["theta1", "theta2"], Vec::<String>::new())?;
/// let basis = BasisKind::from(Harmonic::new(1)?);
/// let equation = |own: usize, terms: &str, values: &[f64]| {
///     let list = TermList::parse_in(terms, &names, own)?;
///     IdentifiedModel::new(basis, ModelForm::from_terms(list), 1.0, values)
/// };
/// let system = IdentifiedSystem::new(
///     names.clone(),
///     vec![Domain::Circle; 2],
///     vec![
///         equation(0, "theta2''*cos(theta1-theta2), sin(theta1-theta2)*theta2'^2, sin(theta1)", &[0.5, 0.5, 2.0])?,
///         equation(1, "theta1''*cos(theta1-theta2), sin(theta1-theta2)*theta1'^2, sin(theta2)", &[1.0, -1.0, 2.0])?,
///     ],
/// )?;
/// let mut acc = [0.0; 2];
/// system.accelerations(0.0, &[0.3, 0.0], &[0.0, 0.0], None, &mut acc)?;
/// // M = [[1, 0.5 c], [c, 1]] with c = cos 0.3; r = [2 sin 0.3, 0].
/// let c = 0.3f64.cos();
/// let det = 1.0 - 0.5 * c * c;
/// assert!((acc[0] + 2.0 * 0.3f64.sin() / det).abs() < 1e-14);
/// let back = IdentifiedSystem::from_json(&system.to_json()?)?;
/// assert_eq!(back, system);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct IdentifiedSystem<B = BasisKind> {
    names: Names,
    domains: Vec<Domain>,
    equations: Vec<IdentifiedModel<B>>,
    /// The record's columns of the coordinates and of the drives, when they are not named as
    /// the system names them.
    columns: Option<Columns>,
}

/// The record's columns a system's coordinates and drives were read from.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Columns {
    /// The coordinates' columns, in order.
    pub coordinates: Vec<String>,
    /// The drives' columns, in order.
    pub drives: Vec<String>,
}

impl<B: Basis> IdentifiedSystem<B> {
    /// The system of `equations` (equation `i` of coordinate `i`) over coordinates of `names`
    /// on `domains`.
    ///
    /// Errors: as many equations and domains as coordinates, each equation's own coordinate
    /// its place and its terms in these names (a one-coordinate model's terms are in the
    /// one-coordinate names), its basis on its coordinate's domain, one drive frequency for
    /// all.
    pub fn new(
        names: Names,
        domains: Vec<Domain>,
        equations: Vec<IdentifiedModel<B>>,
    ) -> Result<Self, ModelError> {
        let n = names.coordinates().len();
        let invalid = |why: &'static str| ModelError::Term(TermError::InvalidForm { why });
        if equations.len() != n || domains.len() != n || n > MAX_COORDINATES {
            return Err(invalid("a system has one equation and one domain per coordinate"));
        }
        for (i, (model, &domain)) in equations.iter().zip(&domains).enumerate() {
            if model.domain() != domain {
                return Err(invalid("an equation's basis lives on its coordinate's domain"));
            }
            match model.form().terms() {
                Some(list) if list.own() == i && list.names_in() == &names => {}
                Some(list) if n == 1 && list.own() == 0 && list.names_in().is_default() => {}
                None if n == 1 => {}
                _ => {
                    return Err(invalid(
                        "equation i of a system is written in the system's names for its coordinate i",
                    ));
                }
            }
            if model.drive_angular_frequency() != equations[0].drive_angular_frequency() {
                return Err(invalid("the equations of a system share one drive frequency"));
            }
        }
        Ok(Self {
            names,
            domains,
            equations,
            columns: None,
        })
    }

    /// The same system with the record's `columns` its coordinates and drives were read from
    /// (kept with the system, so that it is compared with records of the same columns).
    ///
    /// Errors: as many columns as coordinates and as drives.
    pub fn with_columns(mut self, columns: Columns) -> Result<Self, ModelError> {
        if columns.coordinates.len() != self.names.coordinates().len()
            || columns.drives.len() != self.names.drives().len()
        {
            return Err(ModelError::Term(TermError::InvalidForm {
                why: "a system's columns are one per coordinate and one per drive",
            }));
        }
        self.columns = Some(columns);
        Ok(self)
    }

    /// The record's columns of the coordinates and drives: those given with
    /// [`with_columns`](Self::with_columns), or their names.
    pub fn columns(&self) -> Columns {
        self.columns.clone().unwrap_or_else(|| Columns {
            coordinates: self.names.coordinates().to_vec(),
            drives: self.names.drives().to_vec(),
        })
    }

    /// The system of one model: a record of one coordinate `x`.
    pub fn one(model: IdentifiedModel<B>) -> Self {
        let names = model
            .form()
            .terms()
            .map_or_else(Names::default, |l| l.names_in().clone());
        Self {
            names,
            domains: vec![model.domain()],
            equations: vec![model],
            columns: None,
        }
    }

    /// The names of the coordinates and drives.
    pub fn names(&self) -> &Names {
        &self.names
    }

    /// The domain of each coordinate.
    pub fn domains(&self) -> &[Domain] {
        &self.domains
    }

    /// The number of coordinates.
    pub fn coordinates(&self) -> usize {
        self.equations.len()
    }

    /// The equations, one per coordinate.
    pub fn equations(&self) -> &[IdentifiedModel<B>] {
        &self.equations
    }

    /// The equations, to consume.
    pub fn into_equations(self) -> Vec<IdentifiedModel<B>> {
        self.equations
    }

    /// Drive angular frequency `W` of its terms in `cos(kt)`, `sin(kt)`.
    pub fn drive_angular_frequency(&self) -> f64 {
        self.equations[0].drive_angular_frequency()
    }

    /// Whether a term reads a measured drive and the drives were not given.
    pub fn needs_measured_drive(&self) -> bool {
        self.equations.iter().any(IdentifiedModel::needs_measured_drive)
    }

    /// Whether an equation reads a measured drive.
    pub fn has_measured_drive(&self) -> bool {
        self.equations.iter().any(|m| m.form().has_measured_drive())
    }

    /// The system with the recorded drives of its record, in the order of its names' drives.
    ///
    /// Errors: as [`IdentifiedModel::with_measured_drives`], for an equation that reads one.
    pub fn with_measured_drives(mut self, drives: Vec<MeasuredDrive>) -> Result<Self, ModelError> {
        self.equations = self
            .equations
            .into_iter()
            .map(|m| {
                if m.form().has_measured_drive() {
                    m.with_measured_drives(drives.clone())
                } else {
                    Ok(m)
                }
            })
            .collect::<Result<_, _>>()?;
        Ok(self)
    }

    /// Whether a factor switches at rest in the velocity of coordinate `c` in any equation.
    pub fn switches_in(&self, c: usize) -> bool {
        self.equations.iter().any(|m| m.switches_in(c))
    }

    /// The accelerations at `(t, q, v)` into `acc`: `M q'' = −r` solved by nalgebra's LU with
    /// partial pivoting, of the `n × n` mass matrix (the same arithmetic as on a fixed 8 × 8
    /// matrix whose unused rows are the identity's, and the same decision of singularity).
    /// `sides[c]` is the value of `sign(q_c')` (a branch's ±1, a held value while `q_c` sticks;
    /// `None`: the sign of `v[c]`).
    ///
    /// Errors: [`SingularMass`] where a pivot of the factorisation falls below
    /// [`SINGULAR_PIVOT`] times the matrix's largest entry, or is not finite.
    pub fn accelerations(
        &self,
        t: f64,
        q: &[f64],
        v: &[f64],
        sides: Option<&[f64]>,
        acc: &mut [f64],
    ) -> Result<(), SingularMass> {
        let mut r = [0.0; MAX_COORDINATES];
        let mass = self.mass(|i, model, row| {
            r[i] = -model.equation_at(t, q, v, sides, row);
        });
        solve_mass(self.equations.len(), &mass, Some(&r), t, acc)
    }

    /// The mass matrix's rows, each equation's written by `row(i, equation, row)`.
    fn mass(&self, mut row: impl FnMut(usize, &IdentifiedModel<B>, &mut [f64])) -> MassRows {
        let n = self.equations.len();
        let mut m = [[0.0; MAX_COORDINATES]; MAX_COORDINATES];
        for (i, model) in self.equations.iter().enumerate() {
            row(i, model, &mut m[i][..n]);
        }
        m
    }
}

// `solve_mass` writes out the sizes 1 to 8.
const _: () = assert!(MAX_COORDINATES == 8);

/// The rows of a mass matrix of up to [`MAX_COORDINATES`] coordinates (the first `n` of each of
/// the first `n` rows used).
type MassRows = [[f64; MAX_COORDINATES]; MAX_COORDINATES];

/// Factorises the `n × n` mass matrix `m` by nalgebra's LU with partial pivoting and, with a
/// right-hand side `r`, solves it into `out`; [`SingularMass`] where the smallest pivot,
/// relative to the largest entry, is below [`SINGULAR_PIVOT`] or not finite. Both measures
/// count the unit pivots and entries of the identity that pads the matrix to 8 × 8 (the
/// factorisation this replaces, whose arithmetic on the `n × n` block is this one's).
fn solve_mass(
    n: usize,
    m: &MassRows,
    r: Option<&[f64; MAX_COORDINATES]>,
    t: f64,
    out: &mut [f64],
) -> Result<(), SingularMass> {
    let factored = factor_mass(n, m, r, out);
    let pivot = factored.pivot;
    // Every pivot then non-zero: the factorisation solves.
    let solves = pivot.is_finite() && pivot > SINGULAR_PIVOT && factored.invertible && factored.solved;
    if !solves {
        return Err(SingularMass { t, pivot });
    }
    Ok(())
}

/// What [`factor_mass`] found of a mass matrix.
struct Factored {
    /// The smallest pivot relative to the largest entry (both counting the identity that pads
    /// the matrix to 8 × 8).
    pivot: f64,
    /// The determinant, computed only without a right-hand side (the identification's check:
    /// a free run's solve at every step has no use for it).
    det: Option<f64>,
    /// Whether every pivot is non-zero.
    invertible: bool,
    /// Whether the right-hand side given was solved into `out` (true without one).
    solved: bool,
}

/// Factorises the `n × n` mass matrix `m` by nalgebra's LU with partial pivoting and, with a
/// right-hand side `r` and a pivot above [`SINGULAR_PIVOT`], solves it into `out`.
fn factor_mass(n: usize, m: &MassRows, r: Option<&[f64; MAX_COORDINATES]>, out: &mut [f64]) -> Factored {
    // One body per size (nalgebra's LU of a fixed size wants its size written out).
    macro_rules! sized {
        ($n:literal) => {{
            let matrix = nalgebra::SMatrix::<f64, $n, $n>::from_fn(|i, j| m[i][j]);
            let padded = $n < MAX_COORDINATES;
            let scale = if padded {
                matrix.amax().max(1.0)
            } else {
                matrix.amax()
            };
            let lu = matrix.lu();
            let smallest = lu
                .u()
                .diagonal()
                .iter()
                .map(|d| d.abs())
                .fold(f64::INFINITY, f64::min);
            let pivot = if padded { smallest.min(1.0) } else { smallest } / scale;
            let invertible = lu.is_invertible();
            let mut solved = true;
            if let Some(r) = r
                && pivot.is_finite()
                && pivot > SINGULAR_PIVOT
                && invertible
            {
                match lu.solve(&nalgebra::SVector::<f64, $n>::from_fn(|i, _| r[i])) {
                    Some(x) => out[..$n].copy_from_slice(x.as_slice()),
                    None => solved = false,
                }
            }
            Factored {
                pivot,
                det: r.is_none().then(|| lu.determinant()),
                invertible,
                solved,
            }
        }};
    }
    match n {
        1 => sized!(1),
        2 => sized!(2),
        3 => sized!(3),
        4 => sized!(4),
        5 => sized!(5),
        6 => sized!(6),
        7 => sized!(7),
        _ => sized!(8),
    }
}

impl<B: Basis + Sync> IdentifiedSystem<B> {
    /// The first state of `paths` (each a list of indices into `coordinates`, one record per
    /// coordinate, along a stretch of the record without gaps; tried in parallel, the first in
    /// their order told) at which the mass matrix is singular or nearly so, with the velocities
    /// taken as zero (a mass matrix is a function of the positions); `time(k)` is the time of
    /// sample `k`. It is so at a state where its smallest pivot, relative to its largest entry
    /// (as [`accelerations`](Self::accelerations) factorises it), is at most
    /// [`NEAR_SINGULAR_PIVOT`], and between two states of one path where its determinant has
    /// opposite signs: it is continuous along the path, so it vanishes between them, where every
    /// free run along the record would stop (the state of the two with the smaller pivot is
    /// told, [`SingularState::changes_sign`] set). `None` where neither is found: terms that
    /// leave the accelerations undetermined on a record (a coordinate's column the copy of
    /// another's, whose equations then explain each other's acceleration) are found before any
    /// run stops.
    pub fn first_singular(
        &self,
        coordinates: &[&[f64]],
        paths: &[Vec<usize>],
        time: impl Fn(usize) -> f64 + Sync,
    ) -> Option<SingularState> {
        use rayon::prelude::*;
        let n = coordinates.len();
        let state = |q: &mut Vec<f64>, k: usize| {
            for (qi, x) in q.iter_mut().zip(coordinates) {
                *qi = x[k];
            }
        };
        // The mass rows alone, as `accelerations` factorises them (the rest of each equation
        // does not decide whether it can solve): each state's pivot and determinant.
        let measured: Vec<Vec<(f64, f64)>> = paths
            .iter()
            .map(|path| {
                path.par_iter()
                    .map_init(
                        || (vec![0.0; n], vec![0.0; n]),
                        |(q, v), &k| {
                            state(q, k);
                            let t = time(k);
                            mass_pivot(
                                n,
                                &self.mass(|_, model, row| model.mass_row_at(t, q, v, None, row)),
                            )
                        },
                    )
                    .collect()
            })
            .collect();
        let told = |k: usize, pivot: f64, changes_sign: bool| {
            let mut q = vec![0.0; n];
            state(&mut q, k);
            SingularState {
                sample: k,
                q,
                mass: SingularMass { t: time(k), pivot },
                changes_sign,
            }
        };
        for (path, states) in paths.iter().zip(&measured) {
            for (i, (&k, &(pivot, det))) in path.iter().zip(states).enumerate() {
                if pivot.is_nan() || pivot <= NEAR_SINGULAR_PIVOT {
                    return Some(told(k, pivot, false));
                }
                if let Some(&(next_pivot, next_det)) = states.get(i + 1)
                    && det.signum() != next_det.signum()
                    && next_pivot > NEAR_SINGULAR_PIVOT
                {
                    let (k, pivot) = if next_pivot < pivot {
                        (path[i + 1], next_pivot)
                    } else {
                        (k, pivot)
                    };
                    return Some(told(k, pivot, true));
                }
            }
        }
        None
    }
}

/// The smallest pivot of the `n × n` mass matrix `m` relative to its largest entry, as
/// [`solve_mass`] measures it, and its determinant (whose sign tells the two sides of a
/// singular state apart).
fn mass_pivot(n: usize, m: &MassRows) -> (f64, f64) {
    let factored = factor_mass(n, m, None, &mut []);
    (factored.pivot, factored.det.unwrap_or(f64::NAN))
}

/// The smallest relative pivot of a mass matrix at a record's state below which an identified
/// system is refused ([`IdentifiedSystem::first_singular`]): far above the
/// [`SINGULAR_PIVOT`] a free run divides by, and far below a physical system's (a double
/// pendulum's is `1 − μ cos²(θ1 − θ2) ≥ 1 − μ`, `μ` the lower link's share of the inertia): a
/// system whose inertia nearly vanishes on the record is a column the copy of another's, or
/// terms that explain one acceleration by another.
pub const NEAR_SINGULAR_PIVOT: f64 = 1e-6;

/// Where [`IdentifiedSystem::first_singular`] found the mass matrix singular.
#[derive(Debug, Clone, PartialEq)]
pub struct SingularState {
    /// The sample.
    pub sample: usize,
    /// The positions there, one per coordinate.
    pub q: Vec<f64>,
    /// The time and the smallest pivot.
    pub mass: SingularMass,
    /// Whether the determinant changes sign between this state and the next one checked of its
    /// path (the matrix is singular between them) rather than the pivot being small here.
    pub changes_sign: bool,
}

/// The smallest pivot of a mass matrix's factorisation, relative to its largest entry, that
/// [`IdentifiedSystem::accelerations`] divides by.
pub const SINGULAR_PIVOT: f64 = 1e-12;

/// Every system is simulated by `pendulum_sim`'s integrators of several coordinates, sticking
/// at rest where its friction says so.
impl<B: Basis> MultiSystem for IdentifiedSystem<B> {
    fn coordinates(&self) -> usize {
        self.equations.len()
    }

    fn accelerations(&self, t: f64, q: &[f64], v: &[f64], acc: &mut [f64]) -> Result<(), SingularMass> {
        IdentifiedSystem::accelerations(self, t, q, v, None, acc)
    }

    fn switches_at_rest(&self, c: usize) -> bool {
        self.switches_in(c)
    }

    fn accelerations_with_signs(
        &self,
        t: f64,
        q: &[f64],
        v: &[f64],
        signs: &[f64],
        acc: &mut [f64],
    ) -> Result<(), SingularMass> {
        IdentifiedSystem::accelerations(self, t, q, v, Some(signs), acc)
    }
}

/// One equation of a saved system: its terms by name in the system's names.
#[derive(Serialize, Deserialize)]
struct EquationRecord<B> {
    coordinate: String,
    basis: B,
    terms: Vec<String>,
    forcing_frequency: f64,
    coefficients: CoefficientMap,
    fit: Option<FitSummary>,
}

/// A saved system (format 5).
#[derive(Serialize, Deserialize)]
struct SystemRecord<B> {
    format: String,
    version: u32,
    coordinates: Vec<String>,
    domains: Vec<Domain>,
    drives: Vec<String>,
    #[serde(default)]
    columns: Option<Columns>,
    equations: Vec<EquationRecord<B>>,
}

/// The version a saved text or file says it is, without reading the rest.
#[derive(Deserialize)]
struct Version {
    version: u32,
}

impl<B: Basis + Clone + Serialize> IdentifiedSystem<B> {
    fn record(&self) -> Result<SystemRecord<B>, ModelError> {
        let equations = self
            .equations
            .iter()
            .enumerate()
            .map(|(i, m)| {
                let list = m.form().terms().ok_or(ModelError::Term(TermError::InvalidForm {
                    why: "an equation of a system is a list of terms",
                }))?;
                Ok(EquationRecord {
                    coordinate: self.names.coordinates()[i].clone(),
                    basis: m.basis().clone(),
                    terms: list.names(),
                    forcing_frequency: m.drive_angular_frequency(),
                    coefficients: CoefficientMap(m.coefficients().to_vec()),
                    fit: m.summary().cloned(),
                })
            })
            .collect::<Result<_, ModelError>>()?;
        Ok(SystemRecord {
            format: MODEL_FORMAT.to_owned(),
            version: SYSTEM_VERSION,
            coordinates: self.names.coordinates().to_vec(),
            domains: self.domains.clone(),
            drives: self.names.drives().to_vec(),
            columns: self.columns.clone(),
            equations,
        })
    }

    /// Whether the system is its one model (saved in format 4, compared and run as one model):
    /// one coordinate in the names of
    /// one (`x`, and at most the drive `p`), which that format keeps no names for. One
    /// coordinate with drives of other names (two measured drives, `u` and `w`) is saved as a
    /// system.
    pub fn is_one_model(&self) -> bool {
        self.equations.len() == 1 && self.names == Names::default()
    }

    /// Pretty JSON: a system of one coordinate in the names of one as its model
    /// ([`IdentifiedModel::to_json`], format 4), any other system as `{"format": "hbid-model", "version": 5,
    /// "coordinates": [..], "domains": [..], "drives": [..], "equations": [{"coordinate": ..,
    /// "basis": .., "terms": [..], "forcing_frequency": .., "coefficients": {..}, "fit": ..}]}`.
    pub fn to_json(&self) -> Result<String, ModelError> {
        if self.is_one_model() {
            return self.equations[0].to_json();
        }
        Ok(serde_json::to_string_pretty(&self.record()?)?)
    }

    /// Compact binary: [`MODEL_MAGIC`], the version as a little-endian `u32`, then postcard (a
    /// system of one coordinate in the names of one as its model).
    pub fn to_bytes(&self) -> Result<Vec<u8>, ModelError> {
        if self.is_one_model() {
            return self.equations[0].to_bytes();
        }
        let mut out = MODEL_MAGIC.to_vec();
        out.extend_from_slice(&SYSTEM_VERSION.to_le_bytes());
        Ok(postcard::to_extend(&self.record()?, out)?)
    }
}

impl<B: Basis + Clone + serde::de::DeserializeOwned> IdentifiedSystem<B> {
    fn from_record(r: SystemRecord<B>) -> Result<Self, ModelError> {
        if r.format != MODEL_FORMAT {
            return Err(ModelError::Io(ModelIoError::BadMagic));
        }
        let names = Names::new(r.coordinates.clone(), r.drives)?;
        if r.equations.len() != names.coordinates().len() {
            return Err(ModelError::Term(TermError::InvalidForm {
                why: "a saved system has one equation per coordinate",
            }));
        }
        let equations = r
            .equations
            .into_iter()
            .enumerate()
            .map(|(i, e)| {
                if e.coordinate != r.coordinates[i] {
                    return Err(ModelError::Term(TermError::InvalidForm {
                        why: "the equations of a saved system are in the order of its coordinates",
                    }));
                }
                let list = TermList::from_names_in(&e.terms, &names, i)?;
                IdentifiedModel::from_coefficients(
                    e.basis,
                    ModelForm::from_terms(list),
                    e.forcing_frequency,
                    e.coefficients.0,
                    e.fit,
                )
            })
            .collect::<Result<Vec<_>, _>>()?;
        let system = Self::new(names, r.domains, equations)?;
        match r.columns {
            Some(columns) => system.with_columns(columns),
            None => Ok(system),
        }
    }

    /// Reads a system written by [`to_json`](Self::to_json), or any saved model (format 2 to 4)
    /// as a system of one coordinate.
    pub fn from_json(text: &str) -> Result<Self, ModelError> {
        let version: Version = serde_json::from_str(text)?;
        if version.version <= MODEL_VERSION {
            return IdentifiedModel::from_json(text).map(Self::one);
        }
        if version.version != SYSTEM_VERSION {
            return Err(ModelError::Io(ModelIoError::UnsupportedVersion {
                found: version.version,
                supported: SYSTEM_VERSION,
            }));
        }
        Self::from_record(serde_json::from_str(text)?)
    }

    /// Reads a system written by [`to_bytes`](Self::to_bytes), or any saved model (format 2
    /// to 4) as a system of one coordinate.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, ModelError> {
        if bytes.len() < 12 || bytes[..8] != MODEL_MAGIC {
            return Err(ModelError::Io(ModelIoError::BadMagic));
        }
        let version = u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]);
        if version <= MODEL_VERSION {
            return IdentifiedModel::from_bytes(bytes).map(Self::one);
        }
        if version != SYSTEM_VERSION {
            return Err(ModelError::Io(ModelIoError::UnsupportedVersion {
                found: version,
                supported: SYSTEM_VERSION,
            }));
        }
        let record: SystemRecord<B> = postcard::from_bytes(&bytes[12..])?;
        if record.version != version {
            return Err(ModelError::Io(ModelIoError::UnsupportedVersion {
                found: record.version,
                supported: SYSTEM_VERSION,
            }));
        }
        Self::from_record(record)
    }
}
