//! Invariants of wrap, unwrap and the circle distance.
use circle_signal::{RotationSplit, circle_distance, max_circle_distance, unwrap, wrap};
use proptest::prelude::*;
use std::f64::consts::{PI, TAU};

fn wrapped() -> impl Strategy<Value = f64> {
    (-PI..PI).prop_map(|x| x)
}

/// `wrap` as its documentation defines it, the remainder always taken.
fn wrap_by_remainder(theta: f64) -> f64 {
    let mut r = (theta + PI).rem_euclid(TAU);
    if r >= TAU {
        r -= TAU;
    }
    r - PI
}

#[test]
fn wrap_skips_the_remainder_without_changing_a_bit() {
    // Around the ends of the turn (where the sum with π rounds), zero of either sign, far away,
    // and the values that are no numbers.
    let mut values = vec![0.0, -0.0, PI, -PI, TAU, -TAU, 3.0 * PI, -3.0 * PI, 1e300, -1e300];
    for edge in [PI, -PI, TAU, -TAU, 0.0] {
        let mut up = edge;
        let mut down = edge;
        for _ in 0..64 {
            up = up.next_up();
            down = down.next_down();
            values.extend([up, down]);
        }
    }
    for v in values {
        assert_eq!(wrap(v).to_bits(), wrap_by_remainder(v).to_bits(), "{v:e}");
    }
    for v in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        assert!(wrap(v).is_nan());
    }
}

/// `unwrap` as its documentation defines it: every step's turns rounded.
fn unwrap_by_rounding(x: &[f64]) -> Vec<f64> {
    let mut turns = 0.0_f64;
    let mut out = Vec::with_capacity(x.len());
    for (i, &xn) in x.iter().enumerate() {
        if i > 0 {
            turns -= ((xn - x[i - 1]) / TAU).round();
        }
        out.push(xn + TAU * turns);
    }
    out
}

#[test]
fn unwrap_skips_the_rounding_without_changing_a_bit() {
    // Steps at half a turn and next to it, of many turns, and values that are no numbers.
    let mut x = vec![
        0.0,
        PI,
        0.0,
        -PI,
        0.0,
        PI.next_up(),
        0.0,
        PI.next_down(),
        0.0,
        40.0,
        -40.0,
        1e300,
    ];
    x.extend([0.5, f64::NAN, 0.5, 1.0, f64::INFINITY, 2.0]);
    let got: Vec<u64> = unwrap(&x).iter().map(|v| v.to_bits()).collect();
    let want: Vec<u64> = unwrap_by_rounding(&x).iter().map(|v| v.to_bits()).collect();
    assert_eq!(got, want);
}

proptest! {
    #[test]
    fn unwrap_is_the_rounding_to_the_bit(x in prop::collection::vec(-20.0..20.0f64, 1..300)) {
        let got: Vec<u64> = unwrap(&x).iter().map(|v| v.to_bits()).collect();
        let want: Vec<u64> = unwrap_by_rounding(&x).iter().map(|v| v.to_bits()).collect();
        prop_assert_eq!(got, want);
    }

    #[test]
    fn wrap_is_the_remainder_to_the_bit(x in -1e3..1e3f64, wrapped in -PI..PI) {
        prop_assert_eq!(wrap(x).to_bits(), wrap_by_remainder(x).to_bits());
        prop_assert_eq!(wrap(wrapped).to_bits(), wrap_by_remainder(wrapped).to_bits());
    }

    #[test]
    fn wrap_is_in_range_and_idempotent(x in -1e6..1e6f64) {
        let w = wrap(x);
        prop_assert!((-PI..PI).contains(&w));
        // Wrapping again moves a wrapped value by at most rounding.
        prop_assert!(circle_distance(wrap(w), w) <= 1e-15);
        // And x and wrap(x) are the same point of the circle.
        prop_assert!(circle_distance(x, w) <= 1e-9 * (1.0 + x.abs() * 1e-6));
    }

    #[test]
    fn wrap_of_unwrap_is_identity(x in prop::collection::vec(wrapped(), 1..200)) {
        let u = unwrap(&x);
        prop_assert_eq!(u.len(), x.len());
        for (i, (&ui, &xi)) in u.iter().zip(&x).enumerate() {
            let turns = ((ui - xi) / TAU).round();
            // u = x + 2π m exactly up to the rounding of one multiply-add.
            prop_assert!((ui - xi - TAU * turns).abs() <= 1e-12 * (1.0 + turns.abs()), "sample {}", i);
            prop_assert!(circle_distance(wrap(ui), xi) <= 1e-12 * (1.0 + turns.abs()));
        }
        prop_assert_eq!(u[0], x[0]);
    }

    #[test]
    fn unwrap_of_wrap_recovers_signal_up_to_one_constant(
        start in -50.0..50.0f64,
        steps in prop::collection::vec(-3.1..3.1f64, 1..300),
    ) {
        let mut theta = vec![start];
        for s in steps {
            let last = *theta.last().unwrap();
            theta.push(last + s);
        }
        let u = unwrap(&theta.iter().map(|&t| wrap(t)).collect::<Vec<_>>());
        let m = ((theta[0] - u[0]) / TAU).round();
        for (&t, &v) in theta.iter().zip(&u) {
            prop_assert!((t - v - TAU * m).abs() < 1e-9, "theta {} unwrapped {} m {}", t, v, m);
        }
    }

    #[test]
    fn distance_is_a_metric_on_the_circle(a in -20.0..20.0f64, b in -20.0..20.0f64, c in -20.0..20.0f64, m in -5i32..5) {
        let dab = circle_distance(a, b);
        prop_assert_eq!(dab, circle_distance(b, a));
        prop_assert!((0.0..=PI).contains(&dab));
        prop_assert_eq!(circle_distance(a, a), 0.0);
        prop_assert!(dab <= circle_distance(a, c) + circle_distance(c, b) + 1e-12);
        let shift = TAU * f64::from(m);
        prop_assert!((circle_distance(a + shift, b) - dab).abs() < 1e-12);
        prop_assert!((circle_distance(a, b - shift) - dab).abs() < 1e-12);
        prop_assert!(circle_distance(a, a + shift) < 1e-12);
    }

    #[test]
    fn distance_zero_only_when_equal_mod_two_pi(a in -PI..PI, d in 1e-9..(TAU - 1e-9)) {
        prop_assert!(circle_distance(a, a + d) > 0.0);
    }

    #[test]
    fn vector_distance_is_max_of_components(a in prop::collection::vec(-10.0..10.0f64, 1..8), shift in -1.0..1.0f64) {
        let b: Vec<f64> = a.iter().enumerate().map(|(i, &x)| x + shift * i as f64).collect();
        let expected = a.iter().zip(&b).map(|(&x, &y)| circle_distance(x, y)).fold(0.0, f64::max);
        prop_assert_eq!(max_circle_distance(&a, &b), expected);
        prop_assert_eq!(max_circle_distance(&a, &b), max_circle_distance(&b, &a));
    }

    #[test]
    fn rotation_split_recovers_winding(m in -4i64..5, k in 1usize..5, amp in 0.0..0.8f64, phase in -PI..PI) {
        let p = 25usize;
        let l = k * p;
        let h = TAU / p as f64;
        let rate = m as f64 / k as f64;
        let x_c: Vec<f64> = (0..=l)
            .map(|n| {
                let t = n as f64 * h;
                rate * t + amp * (t / k as f64 + phase).sin()
            })
            .collect();
        let wrapped: Vec<f64> = x_c.iter().map(|&x| wrap(x)).collect();
        let continuous = unwrap(&wrapped);
        let s = RotationSplit::new(&continuous, h).unwrap();
        prop_assert_eq!(s.winding, m);
        prop_assert!((s.rate - rate).abs() < 1e-12);
        // The oscillation is periodic: its first sample matches the closing one, the closing sample
        // of the segment less the rotation over the segment.
        let closing = continuous[l] - s.rate * l as f64 * h;
        prop_assert!(
            (s.oscillation[0] - closing).abs() < 1e-9,
            "first {} closing {}",
            s.oscillation[0],
            closing
        );
    }
}
