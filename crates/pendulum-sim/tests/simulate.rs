//! Sampled trajectories, Poincaré sections and the Lyapunov exponent: grids that are not a whole
//! number of samples per period, an independent RK4 integration, the Duffing oscillator's energy
//! balance and its chaos.
use std::f64::consts::TAU;

use pendulum_sim::{
    Duffing, LyapunovConfig, Pendulum, SecondOrderSystem, SimulationConfig, Tolerances, largest_lyapunov,
    poincare_section, simulate,
};

/// The classic fourth-order Runge–Kutta method with a fixed step, from `(0, y0)` to each of
/// `times` (increasing), landing exactly on each: an integrator independent of DOP853.
fn rk4<S: SecondOrderSystem>(system: &S, y0: [f64; 2], times: &[f64], max_step: f64) -> Vec<[f64; 2]> {
    let f = |t: f64, y: [f64; 2]| [y[1], system.acceleration(t, y[0], y[1])];
    let mut t = 0.0;
    let mut y = y0;
    let mut out = Vec::with_capacity(times.len());
    for &target in times {
        let steps = ((target - t) / max_step).ceil().max(1.0) as usize;
        let dt = (target - t) / steps as f64;
        for i in 0..steps {
            let ti = t + i as f64 * dt;
            let k1 = f(ti, y);
            let k2 = f(ti + 0.5 * dt, [y[0] + 0.5 * dt * k1[0], y[1] + 0.5 * dt * k1[1]]);
            let k3 = f(ti + 0.5 * dt, [y[0] + 0.5 * dt * k2[0], y[1] + 0.5 * dt * k2[1]]);
            let k4 = f(ti + dt, [y[0] + dt * k3[0], y[1] + dt * k3[1]]);
            for j in 0..2 {
                y[j] += dt / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]);
            }
        }
        t = target;
        out.push(y);
    }
    out
}

#[test]
fn sample_step_is_checked_and_replaced_by_a_whole_grid() {
    let c = SimulationConfig::paper();
    for bad in [0.0, -0.1, f64::NAN, f64::INFINITY] {
        assert!(c.clone().with_sample_step(bad).is_err(), "{bad}");
    }
    let stepped = c.clone().with_sample_step(0.3).unwrap();
    assert_eq!(stepped.sample_step(), 0.3);
    assert_eq!(stepped.whole_samples_per_period(), None);
    let whole = stepped.with_samples_per_period(25).unwrap();
    assert_eq!(whole.whole_samples_per_period(), Some(25));
    assert_eq!(whole, SimulationConfig::paper());
}

/// A step of 2T/25 (12.5 samples per period, not whole) samples every other point of the
/// 25-per-period grid: the same values there.
#[test]
fn a_non_whole_grid_agrees_with_the_whole_grid_where_they_meet() {
    let tol = Tolerances::relative(1e-12).unwrap();
    let base = SimulationConfig::paper()
        .with_transient_periods(20)
        .with_phase(0.3)
        .unwrap()
        .with_tolerances(tol);
    let n = 1500;
    let whole = simulate(&Pendulum::paper(), &base.clone().with_samples(2 * n - 1).unwrap()).unwrap();
    let stepped_config = base
        .with_sample_step(2.0 * TAU / 25.0)
        .unwrap()
        .with_samples(n)
        .unwrap();
    let stepped = simulate(&Pendulum::paper(), &stepped_config).unwrap();
    assert_eq!(stepped.len(), n);
    let mut worst: f64 = 0.0;
    for i in 0..n {
        let t = stepped.t[i];
        assert!((t - whole.t[2 * i]).abs() <= 1e-13 * t, "time of sample {i}");
        assert_eq!(t, stepped_config.sample_time(i));
        assert_eq!(t, (0.3 + 20.0) * TAU + i as f64 * (2.0 * TAU / 25.0));
        worst = worst
            .max((stepped.theta[i] - whole.theta[2 * i]).abs())
            .max((stepped.omega[i] - whole.omega[2 * i]).abs());
    }
    // One integration, interpolated at times that differ by rounding only.
    assert!(worst < 1e-11, "largest difference {worst:e}");
}

/// Samples on a non-whole grid (2π / 0.3 = 20.94 per period) are the solution at their times,
/// as an independent fixed-step RK4 integration gives it.
#[test]
fn a_non_whole_grid_is_the_solution_at_its_times() {
    let h = 0.3;
    let config = SimulationConfig::paper()
        .with_sample_step(h)
        .unwrap()
        .with_transient_periods(1)
        .with_phase(0.1)
        .unwrap()
        .with_samples(80)
        .unwrap()
        .with_initial(0.4, -0.2)
        .unwrap()
        .with_tolerances(Tolerances::relative(1e-12).unwrap());
    for system in [&Pendulum::paper() as &dyn SecondOrderSystem, &Duffing::two_well()] {
        let traj = simulate(&system, &config).unwrap();
        let fine = rk4(&system, [0.4, -0.2], &traj.t, 2e-4);
        let coarse = rk4(&system, [0.4, -0.2], &traj.t, 4e-4);
        let mut worst: f64 = 0.0;
        let mut rk4_error: f64 = 0.0;
        for (i, (a, b)) in fine.iter().zip(&coarse).enumerate() {
            worst = worst
                .max((traj.theta[i] - a[0]).abs())
                .max((traj.omega[i] - a[1]).abs());
            rk4_error = rk4_error.max((a[0] - b[0]).abs()).max((a[1] - b[1]).abs());
        }
        // RK4's own error at the finer step is about 1/15 of the two steps' difference.
        assert!(rk4_error < 1e-9, "RK4 is not a reference here: {rk4_error:e}");
        assert!(worst < 1e-8, "largest difference from RK4 {worst:e}");
    }
}

/// The poincaré section ignores the sample step.
#[test]
fn poincare_section_ignores_the_sample_step() {
    let c = SimulationConfig::paper()
        .with_samples(10)
        .unwrap()
        .with_transient_periods(3);
    let a = poincare_section(&Pendulum::paper(), &c).unwrap();
    let b = poincare_section(&Pendulum::paper(), &c.with_sample_step(0.123).unwrap()).unwrap();
    assert_eq!(a, b);
}

/// Along a solution of the Duffing oscillator the energy changes by the work of damping and
/// drive: `E(t) − E(t_0) = ∫ (−c v² + f cos(s) v) ds` (Simpson's rule on the samples).
#[test]
fn duffing_energy_balance() {
    let d = Duffing::two_well();
    let h = 0.01;
    let config = SimulationConfig::paper()
        .with_sample_step(h)
        .unwrap()
        .with_transient_periods(0)
        .with_samples(20_001)
        .unwrap()
        .with_tolerances(Tolerances::relative(1e-12).unwrap());
    let traj = simulate(&d, &config).unwrap();
    let power: Vec<f64> = traj
        .t
        .iter()
        .zip(&traj.omega)
        .map(|(&t, &v)| -d.c() * v * v + d.f() * t.cos() * v)
        .collect();
    let mut worst: f64 = 0.0;
    let mut work = 0.0;
    let e0 = d.energy(traj.theta[0], traj.omega[0]);
    for k in (2..traj.len()).step_by(2) {
        work += h / 3.0 * (power[k - 2] + 4.0 * power[k - 1] + power[k]);
        let de = d.energy(traj.theta[k], traj.omega[k]) - e0;
        worst = worst.max((de - work).abs());
    }
    assert!(worst < 1e-7, "energy balance off by {worst:e}");
    // A wrong sign of the drive breaks the balance by far more.
    let wrong: f64 = (2..traj.len())
        .step_by(2)
        .map(|k| {
            h / 3.0
                * [k - 2, k - 1, k]
                    .iter()
                    .zip([1.0, 4.0, 1.0])
                    .map(|(&i, w)| w * 2.0 * d.f() * traj.t[i].cos() * traj.omega[i])
                    .sum::<f64>()
        })
        .map(f64::abs)
        .sum();
    assert!(wrong > 1e3 * worst);
}

/// The two-well set is chaotic and crosses between the wells: a positive largest Lyapunov
/// exponent, and many irregular crossings of `x = 0` that visit both wells.
#[test]
fn two_well_duffing_is_chaotic_and_crosses_wells() {
    let d = Duffing::two_well();
    let lyap = largest_lyapunov(
        &d,
        &LyapunovConfig::default().with_periods(1000).unwrap(),
        |_, _| {},
    )
    .unwrap();
    assert!(
        lyap.per_unit_time > 5.0 * lyap.standard_error && lyap.per_unit_time > 0.05,
        "{lyap:?}"
    );
    let section = poincare_section(
        &d,
        &SimulationConfig::paper()
            .with_samples(1000)
            .unwrap()
            .with_transient_periods(100),
    )
    .unwrap();
    let left = section.iter().filter(|p| p[0] < 0.0).count();
    assert!(
        (200..800).contains(&left),
        "{left} of 1000 section points in the left well"
    );
    let switches = section
        .windows(2)
        .filter(|w| (w[0][0] < 0.0) != (w[1][0] < 0.0))
        .count();
    assert!(switches > 100, "{switches} well changes in 1000 periods");
}

/// A runaway oscillator (negative damping against a hardening spring: its amplitude, and with it
/// its frequency, grows without end, so the steps shrink) stops on its step budget, of one
/// coordinate and of several, instead of grinding on; the same budget leaves a long ordinary
/// simulation alone.
#[test]
fn a_runaway_simulation_stops_on_its_step_budget() {
    use pendulum_sim::multi::{self, MultiConfig, MultiState};
    use pendulum_sim::{BaseAcceleration, CoupledDuffing, SimError};
    let config = SimulationConfig::paper()
        .with_samples(100)
        .unwrap()
        .with_transient_periods(0);
    let runaway = Duffing::new(-5.0, -1.0, 1.0, 0.3).unwrap();
    match simulate(&runaway, &config) {
        Err(SimError::TooManySteps { t, steps }) => {
            assert_eq!(steps, 100_000 + 1_000 * 100);
            assert!(t > 0.0 && t < config.sample_time(99), "stopped at t = {t}");
        }
        other => panic!("expected the step budget to run out, got {other:?}"),
    }
    let pair = CoupledDuffing::new(
        [-5.0, -5.0],
        [-1.0, -1.0],
        [1.0, 1.0],
        0.3,
        0.0,
        BaseAcceleration::measured(|t: f64| 0.3 * t.cos()),
    )
    .unwrap();
    let state = MultiState::new(&[0.1, 0.0], &[0.0, 0.0]).unwrap();
    let config = MultiConfig::new(state)
        .with_samples(100)
        .unwrap()
        .with_transient_periods(0);
    assert!(
        matches!(
            multi::simulate(&pair, &config),
            Err(SimError::TooManySteps { .. })
        ),
        "the coupled runaway pair runs out of steps"
    );
    // The paper's chaotic pendulum, 200 transient periods and 2000 samples at 25 per period: far
    // inside the default budget, and stopped by a budget set below what it takes.
    let long = SimulationConfig::paper().with_samples(2_000).unwrap();
    assert_eq!(long.step_budget(), 100_000 + 1_000 * (200 * 25 + 2_000));
    assert_eq!(simulate(&Pendulum::paper(), &long).unwrap().len(), 2_000);
    assert!(matches!(
        simulate(&Pendulum::paper(), &long.clone().with_max_steps(1_000).unwrap()),
        Err(SimError::TooManySteps { steps: 1_000, .. })
    ));
    // The budget given is kept by the serialised form; the default is not written.
    let json = serde_json::to_string(&long.clone().with_max_steps(5_000).unwrap()).unwrap();
    let back: SimulationConfig = serde_json::from_str(&json).unwrap();
    assert_eq!(back.step_budget(), 5_000);
    assert!(!serde_json::to_string(&long).unwrap().contains("max_steps"));
    // No step at all is refused, when made and when read.
    assert!(matches!(
        long.clone().with_max_steps(0),
        Err(SimError::InvalidParameter {
            name: "max_steps",
            ..
        })
    ));
    assert!(serde_json::from_str::<SimulationConfig>(&json.replace("5000", "0")).is_err());
    assert!(matches!(
        config.clone().with_max_steps(0),
        Err(SimError::InvalidParameter {
            name: "max_steps",
            ..
        })
    ));
}
