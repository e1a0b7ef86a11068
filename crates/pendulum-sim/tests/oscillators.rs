//! The pendulum and the Duffing oscillator: parameters are validated, the Jacobians are the
//! derivatives of the accelerations, and the Duffing oscillator round-trips through JSON.
use pendulum_sim::{Duffing, Pendulum, SecondOrderSystem};

#[test]
fn rejects_bad_parameters() {
    assert!(Pendulum::new(1.0, 0.1, 0.0).is_err());
    assert!(Pendulum::new(f64::NAN, 0.1, 1.0).is_err());
    assert!(Pendulum::new(1.0, f64::INFINITY, 1.0).is_err());
    assert_eq!(Pendulum::new(1.52, 0.03, 0.8333).unwrap(), Pendulum::paper());
}

#[test]
fn jacobian_matches_finite_differences() {
    let p = Pendulum::paper();
    let (t, x, v) = (0.7, 2.1, -0.4);
    let e = 1e-6;
    let dx = (p.acceleration(t, x + e, v) - p.acceleration(t, x - e, v)) / (2.0 * e);
    let dv = (p.acceleration(t, x, v + e) - p.acceleration(t, x, v - e)) / (2.0 * e);
    let [jx, jv] = p.jacobian(t, x, v);
    assert!((jx - dx).abs() < 1e-8 && (jv - dv).abs() < 1e-8);
}

#[test]
fn duffing_rejects_bad_parameters_and_has_the_right_jacobian() {
    assert!(Duffing::new(f64::NAN, -1.0, 1.0, 0.3).is_err());
    assert!(Duffing::new(0.25, f64::INFINITY, 1.0, 0.3).is_err());
    assert!(Duffing::new(0.25, -1.0, f64::NEG_INFINITY, 0.3).is_err());
    assert!(Duffing::new(0.25, -1.0, 1.0, f64::NAN).is_err());
    assert_eq!(Duffing::new(0.25, -1.0, 1.0, 0.3).unwrap(), Duffing::two_well());
    let d = Duffing::new(0.15, -1.3, 0.7, 0.4).unwrap();
    let (t, x, v) = (0.7, 1.3, -0.4);
    let e = 1e-6;
    let dx = (d.acceleration(t, x + e, v) - d.acceleration(t, x - e, v)) / (2.0 * e);
    let dv = (d.acceleration(t, x, v + e) - d.acceleration(t, x, v - e)) / (2.0 * e);
    let [jx, jv] = d.jacobian(t, x, v);
    assert!(
        (jx - dx).abs() < 1e-8 && (jv - dv).abs() < 1e-8,
        "{jx} {dx} {jv} {dv}"
    );
    // The drive is +f cos(t) on the right-hand side: at rest at the origin the acceleration is
    // the drive itself.
    assert_eq!(d.acceleration(0.0, 0.0, 0.0), 0.4);
}

#[test]
fn duffing_serde_round_trips() {
    let d = Duffing::two_well();
    let json = serde_json::to_string(&d).unwrap();
    assert_eq!(serde_json::from_str::<Duffing>(&json).unwrap(), d);
}
