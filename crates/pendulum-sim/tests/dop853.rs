//! The DOP853 integrator through its public interface: order 8 at a fixed step, closed-form
//! solutions, the dense output inside long steps, refused input, and a blow-up that ends in an
//! error.
use pendulum_sim::{Dop853, OdeSystem, Tolerances};

/// y'' = -y as a first-order system.
struct Harmonic;
impl OdeSystem<2> for Harmonic {
    fn rhs(&self, _t: f64, y: &[f64; 2], dy: &mut [f64; 2]) {
        *dy = [y[1], -y[0]];
    }
}

/// y' = cos(t) y: a time-dependent equation with y = exp(sin t).
struct TimeDependent;
impl OdeSystem<1> for TimeDependent {
    fn rhs(&self, t: f64, y: &[f64; 1], dy: &mut [f64; 1]) {
        dy[0] = t.cos() * y[0];
    }
}

/// Error at t = 2 with a fixed step h: step `i` is limited to end at `i h`, and the tolerances are
/// so loose that the controller always proposes a longer step and rejects none, so every step ends
/// exactly there (checked).
fn fixed_step_error(h: f64) -> f64 {
    let tol = Tolerances::new(0.5, 1e3).unwrap();
    let mut ode = Dop853::new(TimeDependent, 0.0, [1.0], tol).unwrap();
    let n = (2.0 / h).round() as usize;
    for i in 1..=n {
        ode.step(i as f64 * h).unwrap();
        assert_eq!(ode.t(), i as f64 * h, "step {i} of h = {h} is not a fixed step");
    }
    let stats = ode.stats();
    assert_eq!((stats.accepted, stats.rejected), (n, 0), "h = {h}: {stats:?}");
    (ode.y()[0] - 2f64.sin().exp()).abs()
}

#[test]
fn order_of_convergence_is_eight() {
    let e1 = fixed_step_error(0.2);
    let e2 = fixed_step_error(0.1);
    let order = (e1 / e2).log2();
    assert!(
        (7.5..9.0).contains(&order),
        "observed order {order} ({e1:e} -> {e2:e})"
    );
}

#[test]
fn closed_form_harmonic_oscillator() {
    let tol = Tolerances::new(1e-12, 1e-14).unwrap();
    let mut ode = Dop853::new(Harmonic, 0.0, [1.0, 0.0], tol).unwrap();
    let mut worst: f64 = 0.0;
    ode.sample_grid(0.0, 0.1, 1001, |_, t, y| {
        worst = worst.max((y[0] - t.cos()).abs()).max((y[1] + t.sin()).abs());
    })
    .unwrap();
    assert!(worst < 1e-10, "worst {worst:e}");
    assert_eq!(ode.t(), 100.0);
}

#[test]
fn dense_output_is_accurate_inside_steps() {
    // Few, long steps, each sampled at many interior points: the interpolant, not the step, is tested.
    let tol = Tolerances::new(1e-10, 1e-12).unwrap();
    let mut ode = Dop853::new(Harmonic, 0.0, [1.0, 0.0], tol).unwrap();
    let mut worst: f64 = 0.0;
    let mut steps_with_samples = 0;
    while ode.t() < 20.0 {
        let t0 = ode.t();
        let t1 = ode.step(20.0).unwrap();
        steps_with_samples += 1;
        for i in 1..10 {
            let t = t0 + (t1 - t0) * i as f64 / 10.0;
            let y = ode.interpolate(t);
            // The step's own global error is part of this; it is far below 1e-9 here.
            worst = worst.max((y[0] - t.cos()).abs());
        }
    }
    assert!(
        steps_with_samples < 100,
        "{steps_with_samples} steps: not a test of long steps"
    );
    assert!(worst < 1e-9, "dense error {worst:e}");
}

#[test]
fn time_dependent_equation_is_solved() {
    let tol = Tolerances::new(1e-12, 1e-14).unwrap();
    let mut ode = Dop853::new(TimeDependent, 0.0, [1.0], tol).unwrap();
    ode.advance_to(30.0).unwrap();
    assert!((ode.y()[0] - 30f64.sin().exp()).abs() < 1e-10);
}

#[test]
fn rejects_bad_tolerances_and_states() {
    assert!(Tolerances::new(-1e-6, 0.0).is_err());
    assert!(Tolerances::new(1e-20, 0.0).is_err());
    assert!(Tolerances::new(1e-6, f64::NAN).is_err());
    assert!(Dop853::new(Harmonic, 0.0, [f64::NAN, 0.0], Tolerances::default()).is_err());
}

#[test]
fn blow_up_is_an_error_not_a_hang() {
    /// y' = y^2 blows up at t = 1 from y = 1.
    struct BlowUp;
    impl OdeSystem<1> for BlowUp {
        fn rhs(&self, _t: f64, y: &[f64; 1], dy: &mut [f64; 1]) {
            dy[0] = y[0] * y[0];
        }
    }
    let mut ode = Dop853::new(BlowUp, 0.0, [1.0], Tolerances::default())
        .unwrap()
        .with_max_steps(100_000);
    assert!(ode.advance_to(2.0).is_err());
}
