//! The simulator against data made by an independent integrator (SciPy's DOP853 at rtol 1e-13).
use pendulum_sim::{Pendulum, SimulationConfig, Tolerances, largest_lyapunov, poincare_section, simulate};

fn fixture(name: &str) -> String {
    let path = format!("{}/../../../shared/fixtures/{name}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("cannot read {path}: {e}"))
}

fn reference() -> Vec<[f64; 3]> {
    fixture("reference_trajectory.csv")
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with('t'))
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|c| c.trim().parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect()
}

#[test]
fn matches_scipy_reference_to_1e_8() {
    let rows = reference();
    assert_eq!(rows.len(), 201);
    let cfg = SimulationConfig::paper()
        .with_samples(201)
        .unwrap()
        .with_transient_periods(0)
        .with_tolerances(Tolerances::relative(1e-12).unwrap());
    let traj = simulate(&Pendulum::paper(), &cfg).unwrap();
    let mut worst_theta: f64 = 0.0;
    let mut worst_omega: f64 = 0.0;
    for (i, row) in rows.iter().enumerate() {
        assert!((traj.t[i] - row[0]).abs() <= 1e-12 * row[0].max(1.0), "t at {i}");
        worst_theta = worst_theta.max((traj.theta[i] - row[1]).abs());
        worst_omega = worst_omega.max((traj.omega[i] - row[2]).abs());
    }
    assert!(worst_theta <= 1e-8, "largest |theta error| {worst_theta:e}");
    assert!(worst_omega <= 1e-8, "largest |omega error| {worst_omega:e}");
}

#[test]
fn grid_has_exact_count_and_end() {
    let cfg = SimulationConfig::paper()
        .with_samples(1000)
        .unwrap()
        .with_transient_periods(3);
    let traj = simulate(&Pendulum::paper(), &cfg).unwrap();
    assert_eq!(traj.len(), 1000);
    let h = std::f64::consts::TAU / 25.0;
    assert!((traj.t[999] - (75 + 999) as f64 * h).abs() < 1e-9);
    assert!(traj.t.windows(2).all(|w| ((w[1] - w[0]) - h).abs() < 1e-9));
}

#[test]
fn poincare_section_is_the_stroboscopic_subsample() {
    let cfg = SimulationConfig::paper()
        .with_samples(20)
        .unwrap()
        .with_transient_periods(5);
    let section = poincare_section(&Pendulum::paper(), &cfg).unwrap();
    let full = simulate(&Pendulum::paper(), &cfg.clone().with_samples(20 * 25).unwrap()).unwrap();
    for (i, p) in section.iter().enumerate() {
        // Same steps, different output grids: only the dense output differs.
        assert!((p[0] - full.theta[25 * i]).abs() < 1e-9, "period {i}");
        assert!((p[1] - full.omega[25 * i]).abs() < 1e-9, "period {i}");
    }
}

#[test]
fn lyapunov_exponent_of_the_pendulum() {
    // The method notes give about 0.187 per unit time (1.17 per forcing period).
    let cfg = pendulum_sim::LyapunovConfig::default()
        .with_periods(1000)
        .unwrap();
    let est = largest_lyapunov(&Pendulum::paper(), &cfg, |_, _| {}).unwrap();
    assert!(
        (est.per_unit_time - 0.187).abs() < 0.03,
        "lambda = {} ± {} per unit time",
        est.per_unit_time,
        est.standard_error
    );
    assert!((est.per_period - est.per_unit_time * std::f64::consts::TAU).abs() < 1e-12);
}

#[test]
fn linear_oscillator_settles_on_its_closed_form_periodic_solution() {
    struct Linear;
    impl pendulum_sim::SecondOrderSystem for Linear {
        fn acceleration(&self, t: f64, x: f64, v: f64) -> f64 {
            t.cos() - 0.1 * v - 2.0 * x
        }
        fn jacobian(&self, _t: f64, _x: f64, _v: f64) -> [f64; 2] {
            [-2.0, -0.1]
        }
    }
    // x'' + 0.1 x' + 2 x = cos t: x_p = A cos t + B sin t with A = 1/1.01, B = 0.1/1.01.
    let (a, b) = (1.0 / 1.01, 0.1 / 1.01);
    let cfg = SimulationConfig::paper()
        .with_samples(100)
        .unwrap()
        .with_transient_periods(150)
        .with_initial(a, b)
        .unwrap()
        .with_tolerances(Tolerances::relative(1e-12).unwrap());
    let traj = simulate(&Linear, &cfg).unwrap();
    for (t, x) in traj.t.iter().zip(&traj.theta) {
        assert!((x - (a * t.cos() + b * t.sin())).abs() < 1e-9, "t = {t}");
    }
}
