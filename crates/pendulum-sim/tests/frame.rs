//! A system in a record's frame: the frame's setters validate, and the framed system's Jacobian is
//! the derivative of its acceleration.
use pendulum_sim::{InFrame, Pendulum, RecordFrame, SecondOrderSystem};

#[test]
fn frame_setters_validate() {
    let f = RecordFrame::nondimensional();
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(f.with_rate(bad).is_err(), "{bad}");
        assert!(f.with_drive_frequency(bad).is_err(), "{bad}");
    }
    assert!(f.with_phase(f64::NAN).is_err());
    assert!(f.with_offset(f64::INFINITY).is_err());
    let g = f.with_drive_frequency(2.0).unwrap();
    assert_eq!(g.rate(), 4.0 * std::f64::consts::PI);
    assert!((g.drive_period() - 0.5).abs() < 1e-15);
}

#[test]
fn framed_jacobian_matches_finite_differences() {
    let frame = RecordFrame::nondimensional()
        .with_drive_frequency(1.02)
        .unwrap()
        .with_phase(0.4)
        .unwrap()
        .with_offset(-0.3)
        .unwrap();
    let s = InFrame::new(Pendulum::paper(), frame);
    let (t, x, v) = (0.31, 2.1, -4.0);
    let e = 1e-6;
    let dx = (s.acceleration(t, x + e, v) - s.acceleration(t, x - e, v)) / (2.0 * e);
    let dv = (s.acceleration(t, x, v + e) - s.acceleration(t, x, v - e)) / (2.0 * e);
    let [jx, jv] = s.jacobian(t, x, v);
    assert!((jx - dx).abs() < 1e-6 * dx.abs().max(1.0), "{jx} vs {dx}");
    assert!((jv - dv).abs() < 1e-6 * dv.abs().max(1.0), "{jv} vs {dv}");
}
