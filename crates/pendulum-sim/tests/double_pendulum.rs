//! The double pendulums: energy conserved without damping and drive, small oscillations at the
//! normal modes' frequencies, link 1 of the base-excited pendulum as the paper's pendulum when
//! `μ → 0`, the equations in the identification's form against the accelerations, the DFKI model
//! written out as its source writes it, the published parameters, and dry friction at the joints:
//! sticking within the friction, breaking away beyond it, one joint held while the other swings.
// Samples of several series (times, coordinates, velocities) are indexed together.
#![allow(clippy::needless_range_loop)]

use std::f64::consts::{PI, TAU};

use pendulum_sim::equations::{
    Q1_D, Q1_DD, Q1_DD_COS_Q1_MINUS_Q2, Q1_DD_COS_Q2, Q2_D, Q2_DD, Q2_DD_COS_Q1_MINUS_Q2, Q2_DD_COS_Q2,
    SIGN_Q1_D, SIGN_Q2_D, SIN_Q1, SIN_Q1_MINUS_Q2_Q1_D_SQ, SIN_Q1_MINUS_Q2_Q2_D_SQ, SIN_Q1_PLUS_Q2, SIN_Q2,
    SIN_Q2_Q1_D_Q2_D, SIN_Q2_Q1_D_SQ, SIN_Q2_Q2_D_SQ, SIN_T_COS_Q1, SIN_T_COS_Q2, TAU1, TAU2,
};
use pendulum_sim::{
    ArmParameters, DoublePendulum, DriveHarmonic, DriveHarmonics, MultiConfig, MultiState, MultiSystem,
    NormalisedEquation, Pendulum, SecondOrderSystem, SimulationConfig, Tolerances, Torque,
    TorqueDoublePendulum, free_run, multi, simulate,
};
use proptest::prelude::*;

/// The value of a term of the identification's grammar at `(t, q, q', q'')` with torques `tau`.
fn term(name: &str, t: f64, q: &[f64], v: &[f64], a: &[f64], tau: [f64; 2]) -> f64 {
    let sign = |x: f64| {
        if x > 0.0 {
            1.0
        } else if x < 0.0 {
            -1.0
        } else {
            0.0
        }
    };
    let d = q[0] - q[1];
    match name {
        n if n == Q1_DD => a[0],
        n if n == Q2_DD => a[1],
        n if n == Q1_D => v[0],
        n if n == Q2_D => v[1],
        n if n == Q1_DD_COS_Q2 => a[0] * q[1].cos(),
        n if n == Q2_DD_COS_Q2 => a[1] * q[1].cos(),
        n if n == SIN_Q2_Q1_D_Q2_D => q[1].sin() * v[0] * v[1],
        n if n == SIN_Q2_Q2_D_SQ => q[1].sin() * v[1] * v[1],
        n if n == SIN_Q2_Q1_D_SQ => q[1].sin() * v[0] * v[0],
        n if n == SIN_Q1 => q[0].sin(),
        n if n == SIN_Q2 => q[1].sin(),
        n if n == SIN_Q1_PLUS_Q2 => (q[0] + q[1]).sin(),
        n if n == SIGN_Q1_D => sign(v[0]),
        n if n == SIGN_Q2_D => sign(v[1]),
        n if n == TAU1 => tau[0],
        n if n == TAU2 => tau[1],
        n if n == Q1_DD_COS_Q1_MINUS_Q2 => a[0] * d.cos(),
        n if n == Q2_DD_COS_Q1_MINUS_Q2 => a[1] * d.cos(),
        n if n == SIN_Q1_MINUS_Q2_Q1_D_SQ => d.sin() * v[0] * v[0],
        n if n == SIN_Q1_MINUS_Q2_Q2_D_SQ => d.sin() * v[1] * v[1],
        n if n == SIN_T_COS_Q1 => t.sin() * q[0].cos(),
        n if n == SIN_T_COS_Q2 => t.sin() * q[1].cos(),
        // A drive harmonic, `sin(kt)*cos(qi)` or `cos(kt)*cos(qi)`.
        other => {
            let (drive, angle) = other
                .split_once("t)*cos(q")
                .unwrap_or_else(|| panic!("no term {other}"));
            let i: usize = angle.trim_end_matches(')').parse().unwrap();
            let (f, k) = drive.split_at(4);
            let k: f64 = k.parse().unwrap();
            let d = if f == "sin(" { (k * t).sin() } else { (k * t).cos() };
            d * q[i - 1].cos()
        }
    }
}

/// `q_i'' + Σ c_k g_k` of each equation, relative to the largest of its terms.
fn residuals(
    equations: &[NormalisedEquation],
    t: f64,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    tau: [f64; 2],
) -> Vec<f64> {
    equations
        .iter()
        .map(|eq| {
            let own = term(eq.acceleration, t, q, v, a, tau);
            let parts: Vec<f64> = eq
                .terms
                .iter()
                .map(|(name, c)| c * term(name, t, q, v, a, tau))
                .collect();
            let scale = parts.iter().fold(own.abs(), |m, p| m.max(p.abs()));
            (own + parts.iter().sum::<f64>()) / scale
        })
        .collect()
}

const STATES: [([f64; 2], [f64; 2]); 5] = [
    ([0.3, -1.2], [0.7, -2.0]),
    ([2.5, 1.0], [-1.5, 0.4]),
    ([-1.0, 3.0], [2.2, 1.3]),
    ([0.0, 0.5], [-0.3, -0.8]),
    ([7.0, -4.0], [0.1, 5.0]),
];

#[test]
fn the_normalised_equations_hold_at_the_accelerations() {
    let pendulum = DoublePendulum::new(0.3, 0.7, 0.8, 0.9, 0.04, 0.06).unwrap();
    // A shaker's drive: a second and a third harmonic, out of phase.
    let shaken = pendulum.with_drive_harmonics(
        DriveHarmonics::new(&[
            DriveHarmonic::new(2, 0.3, 0.5).unwrap(),
            DriveHarmonic::new(3, 0.1, -1.0).unwrap(),
        ])
        .unwrap(),
    );
    assert_eq!(shaken.normalised_equations()[0].terms.len(), 5 + 4);
    let arm = TorqueDoublePendulum::dfki().with_torques(
        Torque::sinusoid(0.4, 10.0, 0.3).unwrap(),
        Torque::measured(|t| -0.6 * (5.0 * t).cos()),
    );
    for (k, (q, v)) in STATES.iter().enumerate() {
        let t = 0.37 + k as f64;
        let mut a = [0.0; 2];
        pendulum.accelerations(t, q, v, &mut a).unwrap();
        for r in residuals(&pendulum.normalised_equations(), t, q, v, &a, [0.0; 2]) {
            assert!(r.abs() < 1e-14, "base-excited, state {k}: residual {r:e}");
        }
        shaken.accelerations(t, q, v, &mut a).unwrap();
        for r in residuals(&shaken.normalised_equations(), t, q, v, &a, [0.0; 2]) {
            assert!(
                r.abs() < 1e-14,
                "base-excited with harmonics, state {k}: residual {r:e}"
            );
        }
        arm.accelerations(t, q, v, &mut a).unwrap();
        let tau = [arm.torques()[0].at(t), arm.torques()[1].at(t)];
        for r in residuals(&arm.normalised_equations(), t, q, v, &a, tau) {
            assert!(r.abs() < 1e-14, "torque-driven, state {k}: residual {r:e}");
        }
    }
    // The terms each equation has, in the grammar's names, as the identification will fit them.
    let names = |eqs: &[NormalisedEquation]| -> Vec<Vec<String>> {
        eqs.iter()
            .map(|e| e.terms.iter().map(|(n, _)| n.to_string()).collect())
            .collect()
    };
    assert_eq!(
        names(&arm.normalised_equations()),
        [
            vec![
                "q1''*cos(q2)",
                "q2''",
                "q2''*cos(q2)",
                "sin(q2)*q1'*q2'",
                "sin(q2)*q2'^2",
                "sin(q1)",
                "sin(q1+q2)",
                "q1'",
                "sign(q1')",
                "tau1"
            ],
            vec![
                "q1''",
                "q1''*cos(q2)",
                "sin(q2)*q1'^2",
                "sin(q1+q2)",
                "q2'",
                "sign(q2')",
                "tau2"
            ],
        ]
    );
    // A torque on the right of the physical equation stands on the left with a negative
    // coefficient: minus one over the equation's own constant inertia.
    let eqs = arm.normalised_equations();
    let p = ArmParameters::DFKI_A0;
    let k2 = p.i2 + p.gr * p.gr * p.ir;
    assert_eq!(eqs[1].coefficient("tau2"), Some(-1.0 / k2));
    assert_eq!(eqs[0].acceleration, "q1''");
    assert_eq!(
        pendulum.normalised_equations()[0].coefficient("sin(t)*cos(q1)"),
        Some(-0.9)
    );
}

/// The DFKI model as its source writes it (README of the benchmark): the torque that the
/// accelerations need, from the identifiable combinations, and the sum of the magnitudes of its
/// terms (the scale of its rounding).
fn dfki_inverse_dynamics(p: &ArmParameters, q: &[f64], v: &[f64], a: &[f64]) -> ([f64; 2], [f64; 2]) {
    let ia = p.i1 + p.m2 * p.l1 * p.l1;
    let mr1 = p.m1 * p.r1 + p.m2 * p.l1;
    let mr2 = p.m2 * p.r2;
    let (s2, c2) = q[1].sin_cos();
    let sign = |x: f64| if x == 0.0 { 0.0 } else { x.signum() };
    let terms1 = [
        (ia + p.i2 + 2.0 * p.l1 * mr2 * c2 + (p.gr * p.gr + 1.0) * p.ir) * a[0],
        (p.i2 + p.l1 * mr2 * c2 - p.gr * p.ir) * a[1],
        -p.l1 * mr2 * s2 * (2.0 * v[0] * v[1] + v[1] * v[1]),
        p.g * mr1 * q[0].sin(),
        p.g * mr2 * (q[0] + q[1]).sin(),
        p.b1 * v[0],
        p.cf1 * sign(v[0]),
    ];
    let terms2 = [
        (p.i2 + p.l1 * mr2 * c2 - p.gr * p.ir) * a[0],
        (p.i2 + p.gr * p.gr * p.ir) * a[1],
        p.l1 * mr2 * s2 * v[0] * v[0],
        p.g * mr2 * (q[0] + q[1]).sin(),
        p.b2 * v[1],
        p.cf2 * sign(v[1]),
    ];
    (
        [terms1.iter().sum(), terms2.iter().sum()],
        [
            terms1.iter().map(|x| x.abs()).sum(),
            terms2.iter().map(|x| x.abs()).sum(),
        ],
    )
}

#[test]
fn the_arm_is_the_published_model_with_the_published_parameters() {
    let p = ArmParameters::DFKI_A0;
    // The identifiable combinations as the benchmark's README rounds them: to half a unit of the
    // last digit given.
    assert!((p.i1 + p.m2 * p.l1 * p.l1 - 0.107862).abs() <= 5e-7);
    assert!((p.m1 * p.r1 + p.m2 * p.l1 - 0.349118).abs() <= 5e-7);
    assert!((p.m2 * p.r2 - 0.111065).abs() <= 5e-7);
    assert!((p.ir - 7.6593e-5).abs() <= 5e-10 && p.i2 == 0.02392374528789766);
    assert_eq!(
        (p.gr, p.g, p.b1, p.b2, p.cf1, p.cf2),
        (6.0, 9.81, 0.001, 0.001, 0.093, 0.078)
    );
    assert_eq!(TorqueDoublePendulum::dfki().parameters(), &p);

    let arm = TorqueDoublePendulum::dfki().with_torques(
        Torque::Sinusoids(vec![
            pendulum_sim::Sinusoid::new(0.6, 10.0, 0.0).unwrap(),
            pendulum_sim::Sinusoid::new(0.1, 3.0, 1.0).unwrap(),
        ]),
        Torque::sinusoid(-0.6, 5.0, 0.5).unwrap(),
    );
    for (k, (q, v)) in STATES.iter().enumerate() {
        let t = 0.11 * k as f64;
        let mut a = [0.0; 2];
        arm.accelerations(t, q, v, &mut a).unwrap();
        let (tau, _) = dfki_inverse_dynamics(&p, q, v, &a);
        let want = [arm.torques()[0].at(t), arm.torques()[1].at(t)];
        for c in 0..2 {
            // The torques are sums of terms up to about 10 N m: agreement to rounding.
            assert!(
                (tau[c] - want[c]).abs() < 1e-12,
                "state {k}, joint {c}: {} against {}",
                tau[c],
                want[c]
            );
        }
    }
}

/// The arm's tie (`ArmTie`), evaluated at the arm's parameters, is its normalised equations times
/// each equation's own-acceleration coefficient: the same terms, the same numbers to rounding.
#[test]
fn the_arms_tie_is_its_equations_in_the_physical_parameters() {
    use pendulum_sim::{ARM_PARAMETERS, ArmCoefficient, ArmTie};
    let p = ArmParameters::DFKI_A0;
    let values = [
        p.i1 + p.m2 * p.l1 * p.l1,
        p.i2,
        p.ir,
        p.m1 * p.r1 + p.m2 * p.l1,
        p.m2 * p.r2,
        p.b1,
        p.cf1,
        p.b2,
        p.cf2,
    ];
    let tie = ArmTie::new(p.l1, p.g, p.gr, 1.0);
    assert_eq!(tie.parameters, ARM_PARAMETERS);
    let value = |c: &ArmCoefficient| match c {
        ArmCoefficient::Fixed(v) => *v,
        ArmCoefficient::Linear(parts) => parts
            .iter()
            .map(|(name, factor)| factor * values[ARM_PARAMETERS.iter().position(|n| n == name).unwrap()])
            .sum(),
    };
    let equations = TorqueDoublePendulum::new(p).unwrap().normalised_equations();
    for (equation, q) in equations.iter().zip(["q1", "q2"]) {
        let tied = &tie.equations[q];
        let own = value(&tied[equation.acceleration]);
        assert_eq!(tied.len(), equation.terms.len() + 1, "{q}");
        for (name, coefficient) in &equation.terms {
            let got = value(&tied[name.as_ref()]) / own;
            assert!(
                (got - coefficient).abs() <= 1e-12 * coefficient.abs().max(1.0),
                "{q}: {name}: {got} against {coefficient}"
            );
        }
    }
}

/// The relative drift of the energy along a run: `max |E − E0| / E0`.
fn energy_drift(energy: impl Fn(&[f64], &[f64]) -> f64, run: &pendulum_sim::MultiTrajectory) -> f64 {
    let at = |i: usize| energy(&[run.q[0][i], run.q[1][i]], &[run.v[0][i], run.v[1][i]]);
    let e0 = at(0);
    (0..run.len()).map(|i| (at(i) - e0).abs()).fold(0.0, f64::max) / e0
}

/// Without damping and drive both pendulums conserve their energy, on a chaotic run where both
/// links go over the top, to a thousand times the tolerance (DOP853 is not symplectic: its error
/// in the energy is the local errors summed over the steps, a few hundred of them here).
#[test]
fn energy_is_conserved_without_damping_and_drive() {
    let rtol = 1e-10;
    let tol = Tolerances::relative(rtol).unwrap();
    let pendulum = DoublePendulum::new(0.3, 0.8, 1.0, 0.0, 0.0, 0.0).unwrap();
    let config = MultiConfig::new(MultiState::new(&[2.0, -1.0], &[0.5, 2.0]).unwrap())
        .with_sample_step(0.05)
        .unwrap()
        .with_transient_periods(0)
        .with_samples(2_000)
        .unwrap()
        .with_tolerances(tol);
    let run = multi::simulate(&pendulum, &config).unwrap();
    let turns = |c: usize| {
        let (lo, hi) = run.q[c]
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        hi - lo
    };
    assert!(turns(1) > TAU, "link 2 never went over the top: a weak test");
    let drift = energy_drift(|q, v| pendulum.energy(q, v), &run);
    assert!(
        drift < 1e3 * rtol,
        "base-excited: relative energy drift {drift:e}"
    );

    let p = ArmParameters {
        b1: 0.0,
        b2: 0.0,
        cf1: 0.0,
        cf2: 0.0,
        ..ArmParameters::DFKI_A0
    };
    let arm = TorqueDoublePendulum::new(p).unwrap();
    let config = MultiConfig::new(MultiState::new(&[1.5, -2.0], &[3.0, -4.0]).unwrap())
        .with_sample_step(0.002)
        .unwrap()
        .with_transient_periods(0)
        .with_samples(2_500)
        .unwrap()
        .with_tolerances(tol);
    let run = multi::simulate(&arm, &config).unwrap();
    let drift = energy_drift(|q, v| arm.energy(q, v), &run);
    assert!(
        drift < 1e3 * rtol,
        "torque-driven: relative energy drift {drift:e}"
    );
}

/// The frequencies `Ω²` of `M Ω² φ = K φ` for symmetric 2×2 `M`, `K` (the roots of
/// `det(K − Ω² M) = 0`), each with its mode shape.
fn normal_modes(m: [[f64; 2]; 2], k: [[f64; 2]; 2]) -> [(f64, [f64; 2]); 2] {
    let a = m[0][0] * m[1][1] - m[0][1] * m[0][1];
    let b = -(k[0][0] * m[1][1] + k[1][1] * m[0][0] - 2.0 * k[0][1] * m[0][1]);
    let c = k[0][0] * k[1][1] - k[0][1] * k[0][1];
    let root = (b * b - 4.0 * a * c).sqrt();
    [(-b - root) / (2.0 * a), (-b + root) / (2.0 * a)].map(|w2| {
        // The null vector of the first row of K − Ω² M.
        let shape = [k[0][1] - w2 * m[0][1], -(k[0][0] - w2 * m[0][0])];
        let size = shape[0].abs().max(shape[1].abs());
        (w2, [shape[0] / size, shape[1] / size])
    })
}

/// A small oscillation started in a normal mode's shape stays in it at the mode's frequency:
/// `q(t) = ε φ cos(Ω t)` to the nonlinearity's relative `O(ε²)` and the integration's error.
fn check_modes(system: &dyn MultiSystem, m: [[f64; 2]; 2], k: [[f64; 2]; 2], name: &str) {
    let eps = 1e-5;
    for (w2, shape) in normal_modes(m, k) {
        let omega = w2.sqrt();
        let period = TAU / omega;
        let config = MultiConfig::new(MultiState::at_rest(&[eps * shape[0], eps * shape[1]]).unwrap())
            .with_sample_step(period / 20.0)
            .unwrap()
            .with_transient_periods(0)
            .with_samples(201)
            .unwrap()
            .with_tolerances(Tolerances::new(1e-12, 1e-20).unwrap());
        let run = multi::simulate(&system, &config).unwrap();
        for (i, &t) in run.t.iter().enumerate() {
            for c in 0..2 {
                let want = eps * shape[c] * (omega * t).cos();
                assert!(
                    (run.q[c][i] - want).abs() < 1e-6 * eps,
                    "{name}, Ω² = {w2}: coordinate {c} at t = {t}: {} against {want}",
                    run.q[c][i]
                );
            }
        }
    }
}

#[test]
fn small_oscillations_are_the_normal_modes() {
    // Base-excited, undamped and undriven: in the symmetric form (equation 2 times μλ²)
    // M = [[1, μλ], [μλ, μλ²]], K = ω² diag(1, μλ).
    let (mu, lambda, omega2) = (0.2, 0.5, 0.5);
    let pendulum = DoublePendulum::new(mu, lambda, omega2, 0.0, 0.0, 0.0).unwrap();
    let ml = mu * lambda;
    let m = [[1.0, ml], [ml, ml * lambda]];
    let k = [[omega2, 0.0], [0.0, omega2 * ml]];
    // The classic closed form: Ω² = ω² [(1+λ) ∓ √((1+λ)² − 4(1−μ)λ)] / (2(1−μ)λ).
    let disc = ((1.0 + lambda).powi(2) - 4.0 * (1.0 - mu) * lambda).sqrt();
    let slow = omega2 * ((1.0 + lambda) - disc) / (2.0 * (1.0 - mu) * lambda);
    assert!((normal_modes(m, k)[0].0 - slow).abs() < 1e-14);
    check_modes(&pendulum, m, k, "base-excited");

    // The arm without friction, about hanging: M(0) and K = g [[mr1 + mr2, mr2], [mr2, mr2]].
    let p = ArmParameters {
        b1: 0.0,
        b2: 0.0,
        cf1: 0.0,
        cf2: 0.0,
        ..ArmParameters::DFKI_A0
    };
    let arm = TorqueDoublePendulum::new(p).unwrap();
    let mr1 = p.m1 * p.r1 + p.m2 * p.l1;
    let mr2 = p.m2 * p.r2;
    let k = [[p.g * (mr1 + mr2), p.g * mr2], [p.g * mr2, p.g * mr2]];
    check_modes(&arm, arm.mass_matrix(0.0), k, "torque-driven");
}

/// With `μ = 0` link 1 is the paper's pendulum `x'' + c x' + (1/r²) sin x − f sin(t) cos x = 0`
/// with `c = c1`, `1/r² = ω²`; with small `μ` it departs from it in proportion to `μ`.
#[test]
fn link_one_is_the_papers_pendulum_when_link_two_is_massless() {
    let (f, c, r) = Pendulum::PAPER;
    let omega2 = 1.0 / (r * r);
    let tol = Tolerances::relative(1e-12).unwrap();
    let single = SimulationConfig::paper()
        .with_samples(3 * 50 + 1)
        .unwrap()
        .with_samples_per_period(50)
        .unwrap()
        .with_transient_periods(0)
        .with_initial(0.1, 0.0)
        .unwrap()
        .with_tolerances(tol);
    let reference = simulate(&Pendulum::paper(), &single).unwrap();
    let departure = |mu: f64| {
        let pendulum = DoublePendulum::new(mu, 0.7, omega2, f, c, 0.02).unwrap();
        let config = MultiConfig::from_sampling(
            single.clone(),
            MultiState::new(&[0.1, -0.4], &[0.0, 0.3]).unwrap(),
        );
        let run = multi::simulate(&pendulum, &config).unwrap();
        assert_eq!(run.t, reference.t);
        run.q[0]
            .iter()
            .zip(&reference.theta)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
    };
    // The same equation integrated with a different error norm (four components): the paper's
    // pendulum moves 3.3e-9 over three periods between rtol 1e-10 and 1e-13 (crate documentation),
    // so at 1e-12 the two agree far within 1e-8.
    let exact = departure(0.0);
    assert!(exact < 1e-8, "μ = 0: link 1 departs by {exact:e}");
    // Link 2 swings wildly and the pendulum is chaotic: small enough μ that link 1's departure
    // stays far below its swing, where it is linear in μ.
    let (small, smaller) = (departure(1e-6), departure(1e-7));
    assert!(
        small < 1e-2,
        "μ = 1e-6 moves link 1 by {small:e}: not a small departure"
    );
    assert!(smaller > 1e2 * exact, "μ = 1e-7 moves link 1 by only {smaller:e}");
    let ratio = small / smaller;
    assert!(
        (7.0..14.0).contains(&ratio),
        "departure not proportional to μ: {small:e} / {smaller:e}"
    );
}

/// The arm with large dry friction at both joints (more than the torques of the small torques
/// and of gravity near hanging), a small torque at each, and from `t = 3 s` a torque at the
/// shoulder growing by 1.5 N m per second.
fn stiction_arm() -> (TorqueDoublePendulum, ArmParameters, fn(f64) -> [f64; 2]) {
    let p = ArmParameters {
        cf1: 2.5,
        cf2: 1.0,
        ..ArmParameters::DFKI_A0
    };
    let tau: fn(f64) -> [f64; 2] = |t| {
        [
            0.3 * (4.0 * t).sin() + 1.5 * (t - 3.0).max(0.0),
            0.2 * (3.0 * t).cos(),
        ]
    };
    let arm = TorqueDoublePendulum::new(p).unwrap().with_torques(
        Torque::measured(move |t| tau(t)[0]),
        Torque::measured(move |t| tau(t)[1]),
    );
    (arm, p, tau)
}

/// The friction torque that holds the arm at rest at `q` under the torques `tau`: with
/// `q' = q'' = 0` the equations leave `F = τ + G(q)`.
fn holding(p: &ArmParameters, q: [f64; 2], tau: [f64; 2]) -> [f64; 2] {
    let gravity2 = p.g * p.m2 * p.r2 * (q[0] + q[1]).sin();
    let gravity1 = p.g * (p.m1 * p.r1 + p.m2 * p.l1) * q[0].sin() + gravity2;
    [tau[0] - gravity1, tau[1] - gravity2]
}

#[test]
fn joints_stick_within_their_friction_and_break_away_beyond_it() {
    let (arm, p, tau) = stiction_arm();
    let dt = 0.01;
    let times: Vec<f64> = (0..=800).map(|i| i as f64 * dt).collect();
    let state = MultiState::new(&[0.1, -0.1], &[1.5, -2.0]).unwrap();
    let run = multi::free_run(&arm, &times, &state, Tolerances::relative(1e-10).unwrap()).unwrap();
    assert!(run.stopped.is_none(), "{:?}", run.stopped);
    let at_rest = |i: usize| run.v[0][i] == 0.0 && run.v[1][i] == 0.0;
    let rest = (0..times.len())
        .find(|&i| at_rest(i))
        .expect("never came to rest");
    assert!(times[rest] < 2.0, "came to rest only at {}", times[rest]);
    let q = [run.q[0][rest], run.q[1][rest]];
    // When friction can no longer hold it, by the equations written out here: the first time
    // after coming to rest at which the torque needed exceeds a joint's friction.
    let exceeds = |t: f64| {
        let f = holding(&p, q, tau(t));
        f[0].abs() > p.cf1 || f[1].abs() > p.cf2
    };
    let mut before = times[rest];
    while !exceeds(before + 1e-3) {
        before += 1e-3;
        assert!(
            before < 6.0,
            "the torque never overcomes the friction: no break-away to test"
        );
    }
    let mut after = before + 1e-3;
    while after - before > 1e-12 {
        let mid = 0.5 * (before + after);
        if exceeds(mid) {
            after = mid;
        } else {
            before = mid;
        }
    }
    let breakaway = after;
    assert!(
        breakaway > 3.0,
        "the small torques alone broke it away at {breakaway}"
    );
    // Stuck until then: velocities exactly zero, positions exactly constant, and the force that
    // holds each joint within its friction.
    for i in rest..times.len() {
        if times[i] >= breakaway {
            break;
        }
        assert!(
            at_rest(i),
            "moving at {} before the break-away at {breakaway}",
            times[i]
        );
        assert_eq!([run.q[0][i], run.q[1][i]], q, "drifting at {}", times[i]);
        let f = holding(&p, q, tau(times[i]));
        assert!(
            f[0].abs() <= p.cf1 && f[1].abs() <= p.cf2,
            "held by {f:?} at {}",
            times[i]
        );
    }
    // And moving from the first sample after it.
    let first = times.iter().position(|&t| t > breakaway).unwrap();
    assert!(
        !at_rest(first),
        "still at rest at {} after the break-away at {breakaway}",
        times[first]
    );
    assert!(
        run.v[0][first] > 0.0,
        "the shoulder moves with the growing torque"
    );
}

/// The shoulder held by its friction while the elbow, without dry friction, swings under its
/// torque: the shoulder's velocity stays exactly zero while the force that holds it (from the
/// equations with `q1' = q1'' = 0`, the elbow moving) is within its friction, and the shoulder
/// moves, in the direction of that force, from the first sample after it is not.
#[test]
fn one_joint_stays_stuck_while_the_other_swings_until_its_friction_gives() {
    let p = ArmParameters {
        cf1: 2.0,
        cf2: 0.0,
        ..ArmParameters::DFKI_A0
    };
    let tau2 = |t: f64| 0.5 * (5.0 * t).sin();
    let arm = TorqueDoublePendulum::new(p)
        .unwrap()
        .with_torques(Torque::None, Torque::measured(tau2));
    assert!(arm.switches_at_rest(0) && !arm.switches_at_rest(1));
    let times: Vec<f64> = (0..=400).map(|i| i as f64 * 0.01).collect();
    let state = MultiState::new(&[0.2, 0.8], &[0.0, 0.0]).unwrap();
    let run = multi::free_run(&arm, &times, &state, Tolerances::relative(1e-10).unwrap()).unwrap();
    assert!(run.stopped.is_none(), "{:?}", run.stopped);
    let a = p.m2 * p.l1 * p.r2;
    let k2 = p.i2 + p.gr * p.gr * p.ir;
    // The shoulder's holding force at sample i, were the shoulder at rest there.
    let holding = |i: usize| {
        let (q1, q2, v2) = (run.q[0][i], run.q[1][i], run.v[1][i]);
        let s12 = (q1 + q2).sin();
        // Elbow: M22 q2'' = τ2 − g mr2 sin(q1+q2) − b2 q2'.
        let a2 = (tau2(times[i]) - p.g * p.m2 * p.r2 * s12 - p.b2 * v2) / k2;
        // Shoulder: F1 = τ1 − M12 q2'' + a sin q2 q2'² − g mr1 sin q1 − g mr2 sin(q1+q2).
        let m12 = p.i2 + a * q2.cos() - p.gr * p.ir;
        -m12 * a2 + a * q2.sin() * v2 * v2
            - p.g * (p.m1 * p.r1 + p.m2 * p.l1) * q1.sin()
            - p.g * p.m2 * p.r2 * s12
    };
    let release = (0..times.len())
        .find(|&i| run.v[0][i] != 0.0)
        .expect("the shoulder never moved: no release to test");
    for i in 0..release {
        assert_eq!(run.q[0][i], 0.2);
        let f1 = holding(i);
        assert!(f1.abs() <= p.cf1, "held by {f1} at {}", times[i]);
    }
    let f1 = holding(release);
    assert!(
        f1.abs() > p.cf1 && f1.signum() == run.v[0][release].signum(),
        "released at {} where the holding force is {f1} and the velocity {}",
        times[release],
        run.v[0][release]
    );
    // While the shoulder is held, the elbow is a pendulum hanging from a fixed link 1: its own
    // equation with q1 = 0.2, q1' = q1'' = 0, integrated on its own.
    struct Elbow {
        p: ArmParameters,
        k2: f64,
    }
    impl SecondOrderSystem for Elbow {
        fn acceleration(&self, t: f64, x: f64, v: f64) -> f64 {
            let p = &self.p;
            (0.5 * (5.0 * t).sin() - p.g * p.m2 * p.r2 * (0.2 + x).sin() - p.b2 * v) / self.k2
        }
        fn jacobian(&self, _t: f64, _x: f64, _v: f64) -> [f64; 2] {
            unreachable!()
        }
    }
    let elbow = free_run(
        &Elbow { p, k2 },
        0.0,
        0.01,
        release,
        [0.8, 0.0],
        Tolerances::relative(1e-10).unwrap(),
    )
    .unwrap();
    // Two integrations of one equation at rtol 1e-10 over four seconds: far within 1e-7.
    for i in 0..release {
        assert!(
            (elbow.x[i] - run.q[1][i]).abs() < 1e-7,
            "the elbow at {}: {} against {} on its own",
            times[i],
            run.q[1][i],
            elbow.x[i]
        );
    }
    let swing = run.q[1][..release]
        .iter()
        .fold(0.0f64, |m, &x| m.max((x - 0.8).abs()));
    assert!(
        swing > 0.5 && release > 100,
        "the elbow swung by {swing} in {release} samples: a weak test"
    );
}

/// Physical parameters of an arm: inertias at least those of the masses at their centres.
fn physical() -> impl Strategy<Value = ArmParameters> {
    (
        (0.01..5.0f64, 0.01..5.0f64, 0.05..2.0f64, 0.0..2.0f64, 0.0..2.0f64),
        (1e-6..1.0f64, 1e-6..1.0f64, 0.0..1e-3f64, 1.0..50.0f64),
    )
        .prop_map(|((m1, m2, l1, r1, r2), (e1, e2, ir, gr))| ArmParameters {
            m1,
            m2,
            l1,
            r1,
            r2,
            i1: m1 * r1 * r1 + e1,
            i2: m2 * r2 * r2 + e2,
            ir,
            gr,
            ..ArmParameters::DFKI_A0
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// For physical parameters the mass matrix is symmetric positive definite at every elbow
    /// angle, and the accelerations solve the model's equations.
    #[test]
    fn the_mass_matrix_is_symmetric_positive_definite(
        p in physical(),
        q in prop::array::uniform2(-10.0..10.0f64),
        v in prop::array::uniform2(-20.0..20.0f64),
    ) {
        let arm = TorqueDoublePendulum::new(p).unwrap();
        let m = arm.mass_matrix(q[1]);
        prop_assert_eq!(m[0][1], m[1][0]);
        prop_assert!(m[0][0] > 0.0 && m[1][1] > 0.0);
        let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
        prop_assert!(det > 0.0, "det {} of {:?}", det, m);
        let mut a = [0.0; 2];
        arm.accelerations(0.0, &q, &v, &mut a).unwrap();
        // No torque: the model's torque at the accelerations is zero to the rounding of its terms
        // (a backward-stable solve leaves a residual of a few ulp of them).
        let (tau, scale) = dfki_inverse_dynamics(&p, &q, &v, &a);
        prop_assert!(tau[0].abs() <= 1e-13 * scale[0] && tau[1].abs() <= 1e-13 * scale[1], "{:?} of {:?}", tau, scale);
    }
}

#[test]
fn parameters_are_validated() {
    let p = ArmParameters::DFKI_A0;
    let bad = [
        ArmParameters { m1: -0.1, ..p },
        ArmParameters { l1: 0.0, ..p },
        ArmParameters { r2: f64::NAN, ..p },
        // Less inertia about the joint than the mass has at its centre.
        ArmParameters {
            i2: 0.9 * p.m2 * p.r2 * p.r2,
            ..p
        },
        ArmParameters {
            i1: 0.9 * p.m1 * p.r1 * p.r1,
            ..p
        },
        ArmParameters { ir: -1e-6, ..p },
        ArmParameters { gr: 0.0, ..p },
        ArmParameters { cf2: -0.01, ..p },
        ArmParameters {
            b1: f64::INFINITY,
            ..p
        },
    ];
    for params in bad {
        assert!(TorqueDoublePendulum::new(params).is_err(), "{params:?}");
    }
    assert!(DoublePendulum::new(1.1, 0.5, 0.5, 0.6, 0.0, 0.0).is_err());
    assert!(DoublePendulum::new(-0.1, 0.5, 0.5, 0.6, 0.0, 0.0).is_err());
    assert!(DoublePendulum::new(0.2, 0.0, 0.5, 0.6, 0.0, 0.0).is_err());
    assert!(DoublePendulum::new(0.2, 0.5, -0.5, 0.6, 0.0, 0.0).is_err());
    assert!(DoublePendulum::new(0.2, 0.5, 0.5, f64::NAN, 0.0, 0.0).is_err());
    let (mu, lambda, omega2, f, c1, c2) = DoublePendulum::WHIRLING;
    assert_eq!(
        DoublePendulum::new(mu, lambda, omega2, f, c1, c2).unwrap(),
        DoublePendulum::whirling()
    );
}

/// The built-in set whirls: both links go over the top again and again in each half of 160 drive
/// periods, and no angle moves more than a twelfth of a turn between 64 samples per period.
#[test]
fn the_whirling_set_whirls_and_is_resolved_at_64_samples_per_period() {
    let config = MultiConfig::new(MultiState::at_rest(&[2.0, 0.0]).unwrap())
        .with_samples_per_period(64)
        .unwrap()
        .with_transient_periods(0)
        .with_samples(160 * 64 + 1)
        .unwrap();
    let run = multi::simulate(&DoublePendulum::whirling(), &config).unwrap();
    for c in 0..2 {
        for half in [0, 80 * 64] {
            let over = run.q[c][half..=half + 80 * 64]
                .windows(2)
                .filter(|w| ((w[0] - PI) / TAU).floor() != ((w[1] - PI) / TAU).floor())
                .count();
            assert!(
                over >= 10,
                "link {} over the top {over} times from sample {half}",
                c + 1
            );
        }
        let step = run.q[c]
            .windows(2)
            .map(|w| (w[1] - w[0]).abs())
            .fold(0.0, f64::max);
        assert!(
            step < TAU / 12.0,
            "link {} moves {step} rad between samples",
            c + 1
        );
    }
}
