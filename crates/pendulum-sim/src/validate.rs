//! Checks of an identified model against the system it should describe: periodic orbits of the
//! stroboscopic map by Newton shooting, the distance between Poincaré sections, and the fraction
//! of time spent whirling.

use circle_signal::Domain;
use std::f64::consts::{PI, TAU};

use nalgebra::{Matrix2, Vector2};

use crate::dop853::{OdeSystem, Tolerances};
use crate::error::SimError;
use crate::simulate::checked_period;
use crate::simulate::{
    LyapunovConfig, LyapunovEstimate, SimulationConfig, largest_lyapunov, poincare_section,
};
use crate::switching::{Flow, OnMode, Switched};
use crate::system::SecondOrderSystem;

/// A second-order system with its variational equation for two tangent vectors: the state is
/// `(x, v, Φ11, Φ21, Φ12, Φ22)`, the columns of the fundamental matrix `Φ` stacked.
#[derive(Debug, Clone, Copy)]
pub struct Variational<S>(pub S);

impl<S: SecondOrderSystem> OdeSystem<6> for Variational<S> {
    #[inline]
    fn rhs(&self, t: f64, y: &[f64; 6], dy: &mut [f64; 6]) {
        let [jx, jv] = self.0.jacobian(t, y[0], y[1]);
        *dy = [
            y[1],
            self.0.acceleration(t, y[0], y[1]),
            y[3],
            jx * y[2] + jv * y[3],
            y[5],
            jx * y[4] + jv * y[5],
        ];
    }
}

impl<S: SecondOrderSystem> Switched<6> for Variational<OnMode<S>> {
    type System = S;
    fn on_mode(&self) -> &OnMode<S> {
        &self.0
    }
    fn on_mode_mut(&mut self) -> &mut OnMode<S> {
        &mut self.0
    }
}

/// The flow over `duration` from `(x, v)` at `t0`, and its derivative (the monodromy matrix when
/// `duration` is the period).
pub fn flow_with_jacobian<S: SecondOrderSystem>(
    system: &S,
    t0: f64,
    state: [f64; 2],
    duration: f64,
    tolerances: Tolerances,
) -> Result<([f64; 2], Matrix2<f64>), SimError> {
    let mut ode = Flow::new(
        Variational(OnMode::new(system)),
        t0,
        [state[0], state[1], 1.0, 0.0, 0.0, 1.0],
        tolerances,
    )?
    .with_max_steps(1_000_000);
    ode.advance_to(t0 + duration)?;
    let y = *ode.y();
    Ok(([y[0], y[1]], Matrix2::new(y[2], y[4], y[3], y[5])))
}

/// Where Newton's method starts.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Seeds {
    /// An `nx × nv` grid of cell centres over `x_range × v_range`.
    Grid {
        /// Cells along `x`.
        nx: usize,
        /// Cells along `v`.
        nv: usize,
        /// Range of `x`.
        x_range: (f64, f64),
        /// Range of `v`.
        v_range: (f64, f64),
    },
    /// Given points, e.g. near-returns of a Poincaré section (the best seeds for unstable orbits,
    /// whose Newton basins are small).
    Points(Vec<[f64; 2]>),
}

/// Settings of the search for periodic orbits of the stroboscopic map by Newton shooting from a
/// grid of seeds.
///
/// Deserialising validates every field as the `with_*` setters do; the phase must lie in
/// `[0, 1)`, the Newton tolerance be positive and finite, and the iterations at least 1.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(try_from = "ShootingConfigRaw", into = "ShootingConfigRaw")]
pub struct ShootingConfig {
    forcing_period: f64,
    phase: f64,
    periods: usize,
    seeds: Seeds,
    space: Domain,
    tolerances: Tolerances,
    newton_tolerance: f64,
    max_iterations: usize,
}

/// The serialised form of [`ShootingConfig`].
#[derive(serde::Serialize, serde::Deserialize)]
struct ShootingConfigRaw {
    forcing_period: f64,
    phase: f64,
    periods: usize,
    seeds: Seeds,
    space: Domain,
    tolerances: Tolerances,
    newton_tolerance: f64,
    max_iterations: usize,
}

impl TryFrom<ShootingConfigRaw> for ShootingConfig {
    type Error = SimError;
    fn try_from(raw: ShootingConfigRaw) -> Result<Self, SimError> {
        if !(0.0..1.0).contains(&raw.phase) {
            return Err(invalid("phase", raw.phase, "must lie in [0, 1)"));
        }
        if !(raw.newton_tolerance.is_finite() && raw.newton_tolerance > 0.0) {
            return Err(invalid(
                "newton tolerance",
                raw.newton_tolerance,
                "must be positive and finite",
            ));
        }
        if raw.max_iterations == 0 {
            return Err(invalid("max iterations", 0.0, "must be at least 1"));
        }
        let config = Self::default()
            .with_drive_period(raw.forcing_period)?
            .with_periods(raw.periods)?
            .with_space(raw.space)
            .with_tolerances(raw.tolerances);
        let config = match raw.seeds {
            Seeds::Grid {
                nx,
                nv,
                x_range,
                v_range,
            } => config.with_seeds(nx, nv, x_range, v_range)?,
            Seeds::Points(points) => config.with_seed_points(points)?,
        };
        Ok(Self {
            phase: raw.phase,
            newton_tolerance: raw.newton_tolerance,
            max_iterations: raw.max_iterations,
            ..config
        })
    }
}

impl From<ShootingConfig> for ShootingConfigRaw {
    fn from(c: ShootingConfig) -> Self {
        Self {
            forcing_period: c.forcing_period,
            phase: c.phase,
            periods: c.periods,
            seeds: c.seeds,
            space: c.space,
            tolerances: c.tolerances,
            newton_tolerance: c.newton_tolerance,
            max_iterations: c.max_iterations,
        }
    }
}

impl Default for ShootingConfig {
    /// Period-1 orbits of the paper's pendulum at forcing phase 0: a 24 × 24 grid of seeds over
    /// `x ∈ [−π, π)`, `v ∈ [−3, 3]`, on the circle, rtol 1e-11, Newton until the residual is below
    /// 1e-9 (at most 40 iterations).
    fn default() -> Self {
        Self {
            forcing_period: TAU,
            phase: 0.0,
            periods: 1,
            seeds: Seeds::Grid {
                nx: 24,
                nv: 24,
                x_range: (-PI, PI),
                v_range: (-3.0, 3.0),
            },
            space: Domain::Circle,
            tolerances: Tolerances::new(1e-11, 1e-12).expect("valid tolerances"),
            newton_tolerance: 1e-9,
            max_iterations: 40,
        }
    }
}

fn invalid(name: &'static str, value: f64, why: &'static str) -> SimError {
    SimError::InvalidParameter { name, value, why }
}

impl ShootingConfig {
    /// The forcing period `T` (positive).
    pub fn with_drive_period(mut self, period: f64) -> Result<Self, SimError> {
        self.forcing_period = checked_period(period)?;
        Ok(self)
    }
    /// Orbits of period `k` forcing periods (`>= 1`).
    pub fn with_periods(mut self, k: usize) -> Result<Self, SimError> {
        if k == 0 {
            return Err(invalid("periods", 0.0, "must be at least 1"));
        }
        self.periods = k;
        Ok(self)
    }
    /// Seeds: an `nx × nv` grid over the given ranges (each count `>= 1`, ranges finite, `lo < hi`).
    pub fn with_seeds(
        mut self,
        nx: usize,
        nv: usize,
        x_range: (f64, f64),
        v_range: (f64, f64),
    ) -> Result<Self, SimError> {
        if nx == 0 || nv == 0 {
            return Err(invalid("seeds", 0.0, "need at least one seed in each direction"));
        }
        for (lo, hi) in [x_range, v_range] {
            if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                return Err(invalid("seed range", lo, "must be finite with lo < hi"));
            }
        }
        self.seeds = Seeds::Grid {
            nx,
            nv,
            x_range,
            v_range,
        };
        Ok(self)
    }
    /// Seeds at given points (finite; at least one).
    pub fn with_seed_points(mut self, points: Vec<[f64; 2]>) -> Result<Self, SimError> {
        if points.is_empty() {
            return Err(invalid("seeds", 0.0, "need at least one seed point"));
        }
        if let Some(bad) = points.iter().flatten().find(|v| !v.is_finite()) {
            return Err(invalid("seed point", *bad, "must be finite"));
        }
        self.seeds = Seeds::Points(points);
        Ok(self)
    }
    /// Whether `x` is an angle (default) or a displacement.
    pub fn with_space(mut self, space: Domain) -> Self {
        self.space = space;
        self
    }
    /// Integration tolerances.
    pub fn with_tolerances(mut self, tolerances: Tolerances) -> Self {
        self.tolerances = tolerances;
        self
    }
}

/// A periodic orbit of the stroboscopic map.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PeriodicOrbit {
    /// Its point at the section (wrapped into `[−π, π)` on the circle).
    pub x: f64,
    /// Its velocity at the section.
    pub v: f64,
    /// Net turns over one period (0 on the line).
    pub winding: i64,
    /// Floquet multipliers (eigenvalues of the monodromy matrix) as `(re, im)`.
    pub multipliers: [(f64, f64); 2],
    /// `|Φ(z) − z|` at the solution.
    pub residual: f64,
}

impl PeriodicOrbit {
    /// Whether every multiplier lies inside the unit circle.
    pub fn is_stable(&self) -> bool {
        self.multipliers.iter().all(|(re, im)| re.hypot(*im) < 1.0)
    }
}

/// Periodic orbits of the stroboscopic map `z ↦ Φ_{kT}(z)` at the configured phase, found by
/// Newton's method (`(M − I) δ = −(Φ(z) − z)`, `M` the monodromy matrix from the variational
/// equation) from every seed of the grid, deduplicated (1e-6), sorted by `x`.
///
/// Seeds whose Newton iteration diverges or fails to integrate are skipped. Seeds run in
/// parallel; the result does not depend on the number of threads.
pub fn periodic_orbits<S: SecondOrderSystem + Sync>(
    system: &S,
    config: &ShootingConfig,
) -> Vec<PeriodicOrbit> {
    use rayon::prelude::*;
    let seeds: Vec<[f64; 2]> = match &config.seeds {
        Seeds::Grid {
            nx,
            nv,
            x_range,
            v_range,
        } => (0..nx * nv)
            .map(|c| {
                let (i, j) = (c / nv, c % nv);
                [
                    x_range.0 + (i as f64 + 0.5) * (x_range.1 - x_range.0) / *nx as f64,
                    v_range.0 + (j as f64 + 0.5) * (v_range.1 - v_range.0) / *nv as f64,
                ]
            })
            .collect(),
        Seeds::Points(p) => p.clone(),
    };
    let solutions: Vec<Option<PeriodicOrbit>> =
        seeds.par_iter().map(|&z| newton(system, config, z)).collect();
    let mut found: Vec<PeriodicOrbit> = Vec::new();
    for orbit in solutions.into_iter().flatten() {
        let same = |o: &PeriodicOrbit| {
            let dx = match config.space {
                Domain::Circle => circle_signal::circle_distance(o.x, orbit.x),
                Domain::Line => (o.x - orbit.x).abs(),
            };
            dx < 1e-6 && (o.v - orbit.v).abs() < 1e-6
        };
        if !found.iter().any(same) {
            found.push(orbit);
        }
    }
    found.sort_by(|a, b| a.x.total_cmp(&b.x));
    found
}

fn newton<S: SecondOrderSystem>(
    system: &S,
    config: &ShootingConfig,
    seed: [f64; 2],
) -> Option<PeriodicOrbit> {
    let t0 = config.phase * config.forcing_period;
    let duration = config.periods as f64 * config.forcing_period;
    let mut z = seed;
    // Iterate at a loose tolerance while far away; polish at the configured one.
    let loose = Tolerances::new(
        config.tolerances.rtol().max(1e-8),
        config.tolerances.atol().max(1e-9),
    )
    .ok()?;
    let mut polishing = false;
    for _ in 0..config.max_iterations {
        let tol = if polishing { config.tolerances } else { loose };
        let (end, m) = flow_with_jacobian(system, t0, z, duration, tol).ok()?;
        let turns = match config.space {
            Domain::Circle => ((end[0] - z[0]) / TAU).round(),
            Domain::Line => 0.0,
        };
        let f = Vector2::new(end[0] - z[0] - TAU * turns, end[1] - z[1]);
        let residual = f.norm();
        if !residual.is_finite() {
            return None;
        }
        if !polishing && residual < 1e-5 {
            polishing = true;
        }
        if polishing && residual < config.newton_tolerance {
            let eig = m.complex_eigenvalues();
            let x = match config.space {
                Domain::Circle => circle_signal::wrap(z[0]),
                Domain::Line => z[0],
            };
            return Some(PeriodicOrbit {
                x,
                v: z[1],
                winding: turns as i64,
                multipliers: [(eig[0].re, eig[0].im), (eig[1].re, eig[1].im)],
                residual,
            });
        }
        let step = (m - Matrix2::identity()).try_inverse()? * (-f);
        // Damp long steps: Newton's basin on a chaotic map is small.
        let scale = (0.5 / step.norm()).min(1.0);
        z = [z[0] + scale * step[0], z[1] + scale * step[1]];
        if config.space == Domain::Circle {
            z[0] = circle_signal::wrap(z[0]);
        }
        // Far from its seed: diverged (and integrating wild states only costs time).
        let far = |a: f64, b: f64| (a - b).abs() > 3.0 * (1.0 + b.abs());
        if far(z[1], seed[1]) || (config.space == Domain::Line && far(z[0], seed[0])) {
            return None;
        }
    }
    None
}

/// The fraction of forcing periods in which the angle turns by more than half a revolution
/// (`|θ(t + T) − θ(t)| > π`), over consecutive periods of a continuous (unwrapped) record with
/// `samples_per_period` samples per period. `None` for a record shorter than one period.
pub fn whirling_fraction(theta: &[f64], samples_per_period: usize) -> Option<f64> {
    if samples_per_period == 0 || theta.len() <= samples_per_period {
        return None;
    }
    let periods = (theta.len() - 1) / samples_per_period;
    let whirling = (0..periods)
        .filter(|&k| (theta[(k + 1) * samples_per_period] - theta[k * samples_per_period]).abs() > PI)
        .count();
    Some(whirling as f64 / periods as f64)
}

/// The energy distance between two Poincaré sections (points `(x, v)`, `x` an angle) on the
/// cylinder, embedded in R³ as `(cos x, sin x, v)` with Euclidean distances (Székely & Rizzo):
///
/// `E = 2 E|X − Y| − E|X − X'| − E|Y − Y'|`
///
/// estimated without bias (within-sample means over distinct pairs). `E ≥ 0` with equality exactly
/// when the two distributions agree; the estimate is zero in expectation for two samples of one
/// distribution and may then come out slightly negative, so compare it with the value for two
/// samples of the same system (a floor), not with zero. `None` when either section has fewer than
/// two points.
pub fn section_energy_distance(a: &[[f64; 2]], b: &[[f64; 2]]) -> Option<f64> {
    let embed = |p: &[[f64; 2]]| -> Vec<[f64; 3]> { p.iter().map(|&[x, v]| [x.cos(), x.sin(), v]).collect() };
    energy_distance(&embed(a), &embed(b))
}

/// The energy distance `2 E|X − Y| − E|X − X'| − E|Y − Y'|` between two samples of points in
/// R^D with Euclidean distances, estimated without bias (see [`section_energy_distance`]). `None`
/// when either sample has fewer than two points. The points are fixed arrays (`[f64; D]`) or
/// slices of one length, such as the sections of a system whose number of coordinates is known
/// only at run time.
pub fn energy_distance<P: AsRef<[f64]>>(a: &[P], b: &[P]) -> Option<f64> {
    if a.len() < 2 || b.len() < 2 {
        return None;
    }
    let dist = |p: &P, q: &P| {
        p.as_ref()
            .iter()
            .zip(q.as_ref())
            .map(|(x, y)| (x - y).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    let cross: f64 = a
        .iter()
        .map(|p| b.iter().map(|q| dist(p, q)).sum::<f64>())
        .sum::<f64>()
        / (a.len() * b.len()) as f64;
    let within = |e: &[P]| -> f64 {
        let mut s = 0.0;
        for i in 0..e.len() {
            for j in i + 1..e.len() {
                s += dist(&e[i], &e[j]);
            }
        }
        2.0 * s / (e.len() * (e.len() - 1)) as f64
    };
    Some(2.0 * cross - within(a) - within(b))
}

/// Settings of [`check_model`]: what is measured of a system to compare it with another.
///
/// Deserialising validates each part, that the parts share one forcing period and that the
/// section and the Lyapunov run start from one state, as [`CheckConfig::new`] and the `with_*`
/// setters ensure.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(try_from = "CheckConfigRaw", into = "CheckConfigRaw")]
pub struct CheckConfig {
    section: SimulationConfig,
    lyapunov: LyapunovConfig,
    shooting: ShootingConfig,
    max_seeds: usize,
}

/// The serialised form of [`CheckConfig`]; each part validates itself when deserialised.
#[derive(serde::Serialize, serde::Deserialize)]
struct CheckConfigRaw {
    section: SimulationConfig,
    lyapunov: LyapunovConfig,
    shooting: ShootingConfig,
    max_seeds: usize,
}

impl TryFrom<CheckConfigRaw> for CheckConfig {
    type Error = SimError;
    fn try_from(raw: CheckConfigRaw) -> Result<Self, SimError> {
        let period = raw.section.drive_period();
        for other in [raw.lyapunov.drive_period(), raw.shooting.forcing_period] {
            if other != period {
                return Err(invalid(
                    "forcing period",
                    other,
                    "must be the same for the section, the Lyapunov exponent and the orbit search",
                ));
            }
        }
        let [x0, v0] = raw.section.initial();
        if raw.lyapunov.initial() != [x0, v0] {
            return Err(invalid(
                "initial state",
                raw.lyapunov.initial()[0],
                "must be the same for the section and the Lyapunov exponent",
            ));
        }
        let max_seeds = raw.max_seeds;
        Self {
            section: raw.section,
            lyapunov: raw.lyapunov,
            shooting: raw.shooting,
            max_seeds,
        }
        .with_max_seeds(max_seeds)
    }
}

impl From<CheckConfig> for CheckConfigRaw {
    fn from(c: CheckConfig) -> Self {
        Self {
            section: c.section,
            lyapunov: c.lyapunov,
            shooting: c.shooting,
            max_seeds: c.max_seeds,
        }
    }
}

impl CheckConfig {
    /// Sections of `points` forcing periods after 200 of transient from `(0.1, 0)`, the Lyapunov
    /// exponent over `lyapunov_periods`, and period-1 orbits from up to 64 near-returns of the
    /// section, for a forcing period `T` and a state space.
    pub fn new(
        forcing_period: f64,
        space: Domain,
        points: usize,
        lyapunov_periods: usize,
    ) -> Result<Self, SimError> {
        Ok(Self {
            section: SimulationConfig::paper()
                .with_drive_period(forcing_period)?
                .with_samples(points)?,
            lyapunov: LyapunovConfig::default()
                .with_drive_period(forcing_period)?
                .with_periods(lyapunov_periods)?,
            shooting: ShootingConfig::default()
                .with_drive_period(forcing_period)?
                .with_space(space),
            max_seeds: 64,
        })
    }

    /// The initial state of the section and Lyapunov runs (finite).
    pub fn with_initial(mut self, x0: f64, v0: f64) -> Result<Self, SimError> {
        self.section = self.section.with_initial(x0, v0)?;
        self.lyapunov = self.lyapunov.with_initial(x0, v0)?;
        Ok(self)
    }

    /// At most this many seeds for the orbit search (`>= 1`).
    pub fn with_max_seeds(mut self, seeds: usize) -> Result<Self, SimError> {
        if seeds == 0 {
            return Err(invalid("seeds", 0.0, "must be at least 1"));
        }
        self.max_seeds = seeds;
        Ok(self)
    }
}

/// What [`check_model`] measured of one system.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ModelCheck {
    /// The Poincaré section `(x, v)` at the forcing's phase 0, `x` continuous.
    pub section: Vec<[f64; 2]>,
    /// The largest Lyapunov exponent.
    pub lyapunov: LyapunovEstimate,
    /// Period-1 orbits of the stroboscopic map found from near-returns of the section.
    pub orbits: Vec<PeriodicOrbit>,
    /// Fraction of forcing periods with more than half a turn (see [`whirling_fraction`]).
    pub whirling: f64,
}

/// Measures a system the way an identified model is judged: its Poincaré section, its largest
/// Lyapunov exponent, its period-1 orbits (Newton shooting from the section points that return
/// closest to themselves after one period) and its fraction of whirling periods.
pub fn check_model<S: SecondOrderSystem + Sync>(
    system: &S,
    config: &CheckConfig,
) -> Result<ModelCheck, SimError> {
    let section = poincare_section(system, &config.section)?;
    let xs: Vec<f64> = section.iter().map(|p| p[0]).collect();
    let whirling = whirling_fraction(&xs, 1).unwrap_or(0.0);
    let lyapunov = largest_lyapunov(system, &config.lyapunov, |_, _| {})?;
    let circle = config.shooting.space == Domain::Circle;
    let mut returns: Vec<(f64, [f64; 2])> = section
        .windows(2)
        .map(|w| {
            let dx = if circle {
                circle_signal::circle_distance(w[0][0], w[1][0])
            } else {
                (w[0][0] - w[1][0]).abs()
            };
            (dx.hypot(w[0][1] - w[1][1]), w[0])
        })
        .collect();
    returns.sort_by(|a, b| a.0.total_cmp(&b.0));
    let seeds: Vec<[f64; 2]> = returns.iter().take(config.max_seeds).map(|&(_, z)| z).collect();
    let orbits = if seeds.is_empty() {
        Vec::new()
    } else {
        periodic_orbits(system, &config.shooting.clone().with_seed_points(seeds)?)
    };
    Ok(ModelCheck {
        section,
        lyapunov,
        orbits,
        whirling,
    })
}
