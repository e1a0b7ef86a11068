//! The coupled Duffing oscillators: the linear case against its closed form under a measured
//! drive, energy without damping and drive, the equations in the identification's form, the
//! built-in drive, a drive deserialised without its samples, and the built-in set's motion.

// Samples of several series (times, coordinates, velocities) are indexed together.
#![allow(clippy::needless_range_loop)]

use pendulum_sim::equations::{P, X1, X1_CUBED, X1_D, X1_DD, X1_MINUS_X2_CUBED, X2, X2_CUBED, X2_D, X2_DD};
use pendulum_sim::{
    BaseAcceleration, CoupledDuffing, MultiConfig, MultiState, MultiSystem, SimError, SyntheticDrive,
    Tolerances, multi,
};

/// `y'' + 2ζω y' + ω² y = 0` from `(y0, v0)`, underdamped: `(y, y')`.
fn damped(t: f64, zeta: f64, omega: f64, y0: f64, v0: f64) -> [f64; 2] {
    let wd = omega * (1.0 - zeta * zeta).sqrt();
    let s = zeta * omega;
    let b = (v0 + s * y0) / wd;
    let (sin, cos) = (wd * t).sin_cos();
    let e = (-s * t).exp();
    [
        e * (y0 * cos + b * sin),
        e * ((-s * y0 + b * wd) * cos + (-s * b - y0 * wd) * sin),
    ]
}

/// Linear oscillators alike (`a1 = a2 = a`, `c1 = c2 = c`, equal masses, `b = k3 = 0`) decouple
/// into the mean `s = (x1 + x2)/2`, `s'' + c s' + a s = −p(t)`, and the difference
/// `d = x1 − x2`, `d'' + c d' + (a + 2k) d = 0`; with `p = P cos(w t)` measured, both in closed
/// form.
#[test]
fn linear_oscillators_have_their_closed_form() {
    let (a, c, k) = (1.3, 0.1, 0.4);
    let (amp, w) = (0.2, 0.7);
    let system = CoupledDuffing::new(
        [c, c],
        [a, a],
        [0.0, 0.0],
        k,
        0.0,
        BaseAcceleration::measured(move |t| amp * (w * t).cos()),
    )
    .unwrap();
    let (x0, v0) = ([0.5, -0.3], [0.2, 0.4]);
    let config = MultiConfig::new(MultiState::new(&x0, &v0).unwrap())
        .with_sample_step(0.1)
        .unwrap()
        .with_transient_periods(0)
        .with_samples(600)
        .unwrap()
        .with_tolerances(Tolerances::relative(1e-11).unwrap());
    let run = multi::simulate(&system, &config).unwrap();
    // The mean's steady state −P Re(e^{iwt} / (a − w² + i c w)) and its free part.
    let den = (a - w * w).powi(2) + (c * w).powi(2);
    let steady = |t: f64| {
        let (sin, cos) = (w * t).sin_cos();
        [
            -amp * ((a - w * w) * cos + c * w * sin) / den,
            -amp * w * (-(a - w * w) * sin + c * w * cos) / den,
        ]
    };
    let [p0, pv0] = steady(0.0);
    let (s0, sv0) = (0.5 * (x0[0] + x0[1]), 0.5 * (v0[0] + v0[1]));
    let omega_s = a.sqrt();
    let omega_d = (a + 2.0 * k).sqrt();
    for (i, &t) in run.t.iter().enumerate() {
        let [sf, svf] = damped(t, c / (2.0 * omega_s), omega_s, s0 - p0, sv0 - pv0);
        let [sp, svp] = steady(t);
        let [d, dv] = damped(t, c / (2.0 * omega_d), omega_d, x0[0] - x0[1], v0[0] - v0[1]);
        let want = [sf + sp + 0.5 * d, sf + sp - 0.5 * d];
        let want_v = [svf + svp + 0.5 * dv, svf + svp - 0.5 * dv];
        for j in 0..2 {
            // Sixty time units at rtol 1e-11: the global error is far below 1e-8.
            assert!(
                (run.q[j][i] - want[j]).abs() < 1e-8 && (run.v[j][i] - want_v[j]).abs() < 1e-8,
                "x{} at t = {t}: ({}, {}) against ({}, {})",
                j + 1,
                run.q[j][i],
                run.v[j][i],
                want[j],
                want_v[j]
            );
        }
    }
}

#[test]
fn energy_is_conserved_without_damping_and_drive() {
    let rtol = 1e-10;
    let system = CoupledDuffing::new(
        [0.0, 0.0],
        [-1.0, 0.7],
        [1.0, 0.4],
        0.5,
        0.3,
        BaseAcceleration::measured(|_| 0.0),
    )
    .unwrap()
    .with_mass_ratio(1.7)
    .unwrap();
    let config = MultiConfig::new(MultiState::new(&[1.2, -0.5], &[0.3, 1.0]).unwrap())
        .with_sample_step(0.1)
        .unwrap()
        .with_transient_periods(0)
        .with_samples(2_000)
        .unwrap()
        .with_tolerances(Tolerances::relative(rtol).unwrap());
    let run = multi::simulate(&system, &config).unwrap();
    let energy = |i: usize| system.energy(&[run.q[0][i], run.q[1][i]], &[run.v[0][i], run.v[1][i]]);
    let e0 = energy(0);
    let drift = (0..run.len()).map(|i| (energy(i) - e0).abs()).fold(0.0, f64::max) / e0.abs();
    // As for the pendulums: the local errors summed over the steps, within a thousand times rtol.
    assert!(drift < 1e3 * rtol, "relative energy drift {drift:e}");
}

#[test]
fn the_normalised_equations_hold_at_the_accelerations() {
    let system = CoupledDuffing::two_wells().with_mass_ratio(0.6).unwrap();
    let value = |name: &str, t: f64, x: &[f64], v: &[f64], a: &[f64]| match name {
        n if n == X1_DD => a[0],
        n if n == X2_DD => a[1],
        n if n == X1_D => v[0],
        n if n == X2_D => v[1],
        n if n == X1 => x[0],
        n if n == X2 => x[1],
        n if n == X1_CUBED => x[0].powi(3),
        n if n == X2_CUBED => x[1].powi(3),
        n if n == X1_MINUS_X2_CUBED => (x[0] - x[1]).powi(3),
        n if n == P => system.drive().at(t),
        other => panic!("no term {other}"),
    };
    for (k, (x, v)) in [
        ([1.2, -0.4], [0.3, 0.9]),
        ([-0.7, 1.5], [-1.1, 0.2]),
        ([0.1, 0.0], [0.0, -2.0]),
    ]
    .iter()
    .enumerate()
    {
        let t = 3.7 * k as f64;
        let mut a = [0.0; 2];
        system.accelerations(t, x, v, &mut a).unwrap();
        for eq in system.normalised_equations() {
            let own = value(eq.acceleration, t, x, v, &a);
            let parts: Vec<f64> = eq.terms.iter().map(|(n, c)| c * value(n, t, x, v, &a)).collect();
            let scale = parts.iter().fold(own.abs(), |m, p| m.max(p.abs()));
            let r = (own + parts.iter().sum::<f64>()) / scale;
            assert!(r.abs() < 1e-14, "{}, state {k}: residual {r:e}", eq.acceleration);
        }
    }
    let eqs = system.normalised_equations();
    // The coupling spreads over the linear terms; the drive is +p on the left of both.
    assert_eq!(eqs[0].coefficient("x1"), Some(-1.0 + 0.3));
    assert_eq!(eqs[1].coefficient("x1"), Some(-0.3 / 0.6));
    assert_eq!(eqs[1].coefficient("(x1-x2)^3"), Some(-0.05 / 0.6));
    assert_eq!(eqs[0].coefficient("p"), Some(1.0));
    assert_eq!(eqs[1].coefficient("p"), Some(1.0));
}

#[test]
fn the_built_in_drive_is_seeded_band_limited_noise_on_sinusoids() {
    let drive = SyntheticDrive::incommensurate(7);
    let again = SyntheticDrive::incommensurate(7);
    let other = SyntheticDrive::incommensurate(8);
    let times: Vec<f64> = (0..200_000).map(|i| i as f64 * 0.05).collect();
    assert!(times.iter().all(|&t| drive.at(t) == again.at(t)));
    assert!(times[..100].iter().any(|&t| drive.at(t) != other.at(t)));
    // The noise: equal amplitudes whose mean squares add up to σ², every frequency in the band.
    let sigma = drive.noise_rms();
    let [low, high] = drive.band();
    let noise = drive.noise_components();
    assert_eq!(noise.len(), SyntheticDrive::NOISE_COMPONENTS);
    let power: f64 = noise.iter().map(|s| 0.5 * s.amplitude() * s.amplitude()).sum();
    assert!(
        (power - sigma * sigma).abs() < 1e-15,
        "{power} against {}",
        sigma * sigma
    );
    assert!(noise.iter().all(|s| (low..high).contains(&s.angular_frequency())));
    // Over ten thousand time units its mean square is σ² to the beating of close frequencies.
    let tones = |t: f64| -> f64 { drive.tones().iter().map(|s| s.at(t)).sum() };
    let mean_square = times
        .iter()
        .map(|&t| (drive.at(t) - tones(t)).powi(2))
        .sum::<f64>()
        / times.len() as f64;
    assert!(
        (mean_square.sqrt() / sigma - 1.0).abs() < 0.1,
        "noise rms {} against {sigma}",
        mean_square.sqrt()
    );
    assert!(SyntheticDrive::new(vec![], 0.1, [2.0, 1.0], 1).is_err());
    assert!(SyntheticDrive::new(vec![], -0.1, [0.0, 1.0], 1).is_err());
    assert!(SyntheticDrive::new(vec![], 0.1, [-1.0, 1.0], 1).is_err());
}

/// A system in `p` deserialised without its measured drive does not run as if `p` were 0: its
/// accelerations are NaN and a run stops at once.
#[test]
fn a_missing_measured_drive_stops_a_run() {
    let measured = CoupledDuffing::two_wells().with_drive(BaseAcceleration::measured(|t| t.sin()));
    let json = serde_json::to_string(&measured).unwrap();
    assert!(json.contains("\"measured\""), "{json}");
    let back: CoupledDuffing = serde_json::from_str(&json).unwrap();
    let mut a = [0.0; 2];
    back.accelerations(0.0, &[0.1, 0.2], &[0.0, 0.0], &mut a).unwrap();
    assert!(a.iter().all(|x| x.is_nan()));
    let run = multi::free_run(
        &back,
        &[0.0, 0.1],
        &MultiState::at_rest(&[0.1, 0.2]).unwrap(),
        Tolerances::default(),
    )
    .unwrap();
    assert_eq!(run.finite_len(), 0);
    assert!(
        matches!(run.stopped, Some(SimError::NonFinite { .. })),
        "{:?}",
        run.stopped
    );
}

/// The built-in set moves between the wells of both oscillators, again and again.
#[test]
fn the_two_well_set_hops_between_its_wells() {
    let config = MultiConfig::new(MultiState::at_rest(&[1.0, -0.9]).unwrap())
        .with_sample_step(0.1)
        .unwrap()
        .with_transient_periods(0)
        .with_samples(3_001)
        .unwrap();
    let run = multi::simulate(&CoupledDuffing::two_wells(), &config).unwrap();
    for c in 0..2 {
        let crossings = run.q[c]
            .windows(2)
            .filter(|w| (w[0] < 0.0) != (w[1] < 0.0))
            .count();
        assert!(
            crossings >= 10,
            "x{} crossed between its wells {crossings} times in 300",
            c + 1
        );
    }
}
