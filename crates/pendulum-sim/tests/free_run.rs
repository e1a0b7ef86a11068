//! Free runs and the initial state fitted to a record: closed-form solutions, noise, the circle, dry
//! friction, a diverging model, refused input.
use circle_signal::wrap;
use pendulum_sim::{
    Domain, Duffing, Losses, Pendulum, SecondOrderSystem, SimError, Tolerances, fit_initial_state, free_run,
};

/// `x'' + 2ζω x' + ω² x = 0` from `(x0, v0)`: the closed-form underdamped solution.
fn damped(t: f64, zeta: f64, omega: f64, x0: f64, v0: f64) -> f64 {
    let wd = omega * (1.0 - zeta * zeta).sqrt();
    let a = x0;
    let b = (v0 + zeta * omega * x0) / wd;
    (-zeta * omega * t).exp() * (a * (wd * t).cos() + b * (wd * t).sin())
}

#[derive(Debug)]
struct Linear {
    zeta: f64,
    omega: f64,
}

impl SecondOrderSystem for Linear {
    fn acceleration(&self, _t: f64, x: f64, v: f64) -> f64 {
        -2.0 * self.zeta * self.omega * v - self.omega * self.omega * x
    }
    fn jacobian(&self, _t: f64, _x: f64, _v: f64) -> [f64; 2] {
        [-self.omega * self.omega, -2.0 * self.zeta * self.omega]
    }
}

#[test]
fn a_free_run_is_the_closed_form_solution() {
    let sys = Linear {
        zeta: 0.05,
        omega: 3.0,
    };
    let run = free_run(&sys, 2.0, 0.01, 1000, [0.7, -0.4], Tolerances::default()).unwrap();
    assert!(run.stopped.is_none());
    for (n, x) in run.x.iter().enumerate() {
        let exact = damped(n as f64 * 0.01, 0.05, 3.0, 0.7, -0.4);
        assert!((x - exact).abs() < 1e-8, "sample {n}: {x} against {exact}");
    }
}

#[test]
fn the_fitted_state_is_the_true_one_and_noise_is_smoothed() {
    let sys = Linear {
        zeta: 0.02,
        omega: 2.0,
    };
    let (x0, v0, dt) = (-0.3, 1.1, 0.05);
    let exact: Vec<f64> = (0..50)
        .map(|n| damped(n as f64 * dt, 0.02, 2.0, x0, v0))
        .collect();
    let fit = fit_initial_state(&sys, &exact, 0.0, dt, Domain::Line, Tolerances::default()).unwrap();
    assert!(
        (fit.state[0] - x0).abs() < 1e-7 && (fit.state[1] - v0).abs() < 1e-6,
        "{fit:?}"
    );
    // Alternating noise of 1 % of the amplitude: the fit smooths it far below its size.
    let noisy: Vec<f64> = exact
        .iter()
        .enumerate()
        .map(|(n, x)| x + if n % 2 == 0 { 0.01 } else { -0.01 })
        .collect();
    let fit = fit_initial_state(&sys, &noisy, 0.0, dt, Domain::Line, Tolerances::default()).unwrap();
    assert!((fit.state[0] - x0).abs() < 3e-3, "{fit:?}");
    assert!((fit.state[1] - v0).abs() < 1e-2, "{fit:?}");
    assert!((fit.rms - 0.01).abs() < 2e-3, "{fit:?}");
}

#[test]
fn a_whirling_pendulum_is_fitted_on_the_circle() {
    let p = Pendulum::paper();
    let (dt, t0) = (std::f64::consts::TAU / 25.0, 0.3);
    let run = free_run(&p, t0, dt, 40, [3.0, 2.5], Tolerances::default()).unwrap();
    let wrapped: Vec<f64> = run.x.iter().map(|&x| wrap(x)).collect();
    let fit = fit_initial_state(&p, &wrapped, t0, dt, Domain::Circle, Tolerances::default()).unwrap();
    assert!((wrap(fit.state[0] - 3.0)).abs() < 1e-6, "{fit:?}");
    assert!((fit.state[1] - 2.5).abs() < 1e-6, "{fit:?}");
    // On the turn of the first sample as read.
    assert!((fit.state[0] - wrapped[0]).abs() < 0.5);
}

#[test]
fn dry_friction_sticks_in_a_free_run() {
    // A Duffing oscillator with dry friction and no drive comes to rest and stays there.
    let losses = Losses::none().with_friction(0.3).unwrap();
    let sys = Duffing::new(0.05, 1.0, 0.0, 0.0).unwrap().with_losses(losses);
    let run = free_run(&sys, 0.0, 0.05, 4000, [2.0, 0.0], Tolerances::default()).unwrap();
    assert!(run.stopped.is_none());
    let end = &run.x[3000..];
    assert!(end.iter().all(|&x| (x - end[0]).abs() < 1e-12), "not at rest");
    assert!(
        end[0].abs() <= 0.3 + 1e-9,
        "rests outside the friction band: {}",
        end[0]
    );
}

#[test]
fn a_diverging_model_stops_and_says_where() {
    #[derive(Debug)]
    struct Blowup;
    impl SecondOrderSystem for Blowup {
        fn acceleration(&self, _t: f64, x: f64, _v: f64) -> f64 {
            x * x * x * x
        }
        fn jacobian(&self, _t: f64, x: f64, _v: f64) -> [f64; 2] {
            [4.0 * x * x * x, 0.0]
        }
    }
    let run = free_run(&Blowup, 0.0, 0.1, 100, [1.0, 1.0], Tolerances::default()).unwrap();
    let stopped = run.stopped.clone().expect("a finite-time blow-up stops the run");
    assert!(run.finite_len() < 100 && run.finite_len() > 0, "{stopped}");
    assert!(run.x[run.finite_len()..].iter().all(|x| x.is_nan()));
}

#[test]
fn bad_input_is_refused() {
    let sys = Linear {
        zeta: 0.1,
        omega: 1.0,
    };
    let tol = Tolerances::default();
    assert!(free_run(&sys, 0.0, 0.0, 10, [0.0, 0.0], tol).is_err());
    assert!(free_run(&sys, f64::NAN, 0.1, 10, [0.0, 0.0], tol).is_err());
    assert!(free_run(&sys, 0.0, 0.1, 10, [f64::INFINITY, 0.0], tol).is_err());
    assert!(free_run(&sys, 0.0, 0.1, 0, [0.0, 0.0], tol).unwrap().x.is_empty());
    assert!(matches!(
        fit_initial_state(&sys, &[1.0], 0.0, 0.1, Domain::Line, tol),
        Err(SimError::RecordTooShort { .. })
    ));
    assert!(fit_initial_state(&sys, &[1.0, f64::NAN], 0.0, 0.1, Domain::Line, tol).is_err());
}
