//! Systems that switch at `x' = 0` (dry friction, drag): closed-form Coulomb decay, stick-slip
//! against a regularised friction, convergence with the tolerance, frames, the flow's derivative
//! across reversals and sticks, rest, energy, and the branches.
use std::f64::consts::PI;

use pendulum_sim::{
    Branch, DriveHarmonic, DriveHarmonics, Duffing, InFrame, Losses, Pendulum, RecordFrame,
    SecondOrderSystem, SimulationConfig, Tolerances, flow_with_jacobian, simulate,
};
use proptest::prelude::*;

fn friction(mu: f64) -> Losses {
    Losses::none().with_friction(mu).unwrap()
}

/// `x'' + ω² x + μ sign(x') = 0` from rest at `x0`: each half-cycle is a cosine of period
/// `2π/ω` about `−μ s/ω²` (`s` the sign of the velocity), so the turning points fall at
/// `t_n = nπ/ω` and lose `2μ/ω²` each, until the spring cannot overcome the friction
/// (`ω² |x| <= μ`) and the body stays where it is.
fn coulomb_closed_form(omega: f64, mu: f64, x0: f64, t: f64) -> [f64; 2] {
    let w2 = omega * omega;
    let mut start = x0;
    let mut t_n = 0.0;
    loop {
        if w2 * start.abs() <= mu {
            return [start, 0.0];
        }
        let s = -start.signum();
        let centre = -mu * s / w2;
        let half = PI / omega;
        if t <= t_n + half {
            let phase = omega * (t - t_n);
            return [
                centre + (start - centre) * phase.cos(),
                -(start - centre) * omega * phase.sin(),
            ];
        }
        start = 2.0 * centre - start;
        t_n += half;
    }
}

#[test]
fn coulomb_oscillator_has_its_closed_form_decay() {
    let (omega, mu, x0) = (1.3, 0.05, 1.0);
    let system = Duffing::new(0.0, omega * omega, 0.0, 0.0)
        .unwrap()
        .with_losses(friction(mu));
    // Twenty half-cycles and some rest after: 17 swings, then stuck at 0.0118.
    let h = 0.01;
    let config = SimulationConfig::paper()
        .with_sample_step(h)
        .unwrap()
        .with_transient_periods(0)
        .with_initial(x0, 0.0)
        .unwrap()
        .with_samples(6_000)
        .unwrap()
        .with_tolerances(Tolerances::relative(1e-10).unwrap());
    let traj = simulate(&system, &config).unwrap();
    let mut worst: f64 = 0.0;
    for n in 0..traj.len() {
        let [x, v] = coulomb_closed_form(omega, mu, x0, traj.t[n]);
        worst = worst
            .max((traj.theta[n] - x).abs())
            .max((traj.omega[n] - v).abs());
    }
    // About 5 rtol (the example `friction` gives it at rtol 1e-6 to 1e-12).
    assert!(worst < 2e-9, "largest difference from the closed form {worst:e}");
    // Amplitude lost per full cycle: exactly 4μ/ω² (turning points at t = 2nπ/ω).
    let period = 2.0 * PI / omega;
    let at = |t: f64| {
        simulate(
            &system,
            &config
                .clone()
                .with_sample_step(t)
                .unwrap()
                .with_samples(2)
                .unwrap(),
        )
        .unwrap()
        .theta[1]
    };
    for cycles in [1.0, 3.0, 7.0] {
        let lost = x0 - at(cycles * period);
        let want = cycles * 4.0 * mu / (omega * omega);
        assert!(
            (lost - want).abs() < 2e-9,
            "{cycles} cycles: lost {lost}, want {want}"
        );
    }
    // At rest for good: the velocity is exactly zero, the position constant.
    let rest = &traj.theta[5_000..];
    assert!(traj.omega[5_000..].iter().all(|&v| v == 0.0));
    assert!(rest.iter().all(|&x| x == rest[0]));
    let final_x = x0 - 17.0 * 2.0 * mu / (omega * omega);
    assert!((rest[0].abs() - final_x.abs()).abs() < 2e-9, "{}", rest[0]);
}

/// A driven oscillator whose friction holds it for part of each cycle, against the same
/// oscillator with the friction regularised to `μ tanh(v/ε)` and integrated as a smooth
/// (stiff) system: the two agree to `O(ε)`.
#[test]
fn stick_slip_matches_a_regularised_friction() {
    struct Regularised {
        system: Duffing,
        mu: f64,
        eps: f64,
    }
    impl SecondOrderSystem for Regularised {
        fn acceleration(&self, t: f64, x: f64, v: f64) -> f64 {
            self.system.acceleration(t, x, v) - self.mu * (v / self.eps).tanh()
        }
        fn jacobian(&self, t: f64, x: f64, v: f64) -> [f64; 2] {
            let [jx, jv] = self.system.jacobian(t, x, v);
            [jx, jv - self.mu / self.eps / (v / self.eps).cosh().powi(2)]
        }
    }
    let mu = 0.45;
    let smooth = Duffing::new(0.1, 1.0, 0.0, 0.5).unwrap();
    let rig = smooth.with_losses(friction(mu));
    let config = SimulationConfig::paper()
        .with_sample_step(0.05)
        .unwrap()
        .with_transient_periods(0)
        .with_initial(0.2, 0.0)
        .unwrap()
        .with_samples(800)
        .unwrap()
        .with_tolerances(Tolerances::relative(1e-11).unwrap());
    let traj = simulate(&rig, &config).unwrap();
    let stuck = traj.omega.iter().filter(|&&v| v == 0.0).count();
    assert!(stuck > 100, "{stuck} samples at rest: no test of sticking");
    // While stuck, friction holds the body: |F without friction| <= μ.
    for n in 0..traj.len() {
        if traj.omega[n] == 0.0 {
            let free = smooth.acceleration(traj.t[n], traj.theta[n], 0.0);
            assert!(free.abs() <= mu + 1e-9, "sample {n}: {free}");
        }
    }
    // The regularised solutions converge to the located one like 5 ε (example `friction`, down
    // to ε = 1e-7): checked at two ε a decade apart, with first-order convergence between them.
    // (The regularised system is stiff, its explicit integration costing like 1/ε.)
    let worst = |eps: f64| {
        let reference = simulate(
            &Regularised {
                system: smooth,
                mu,
                eps,
            },
            // Stiff: explicit steps like 1/ε, past the default budget.
            &config.clone().with_max_steps(usize::MAX).unwrap(),
        )
        .unwrap();
        traj.theta
            .iter()
            .zip(&reference.theta)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
    };
    let (coarse, fine) = (worst(1e-5), worst(1e-6));
    assert!(
        coarse < 10.0 * 1e-5 && fine < 10.0 * 1e-6,
        "largest differences from the regularised friction {coarse:e} (ε = 1e-5), {fine:e} (ε = 1e-6)"
    );
    assert!(
        coarse / fine > 5.0,
        "not converging like ε: {coarse:e} at ε = 1e-5, {fine:e} at 1e-6"
    );
}

/// The chaotic pendulum with every rig option, at two tolerances a thousand times apart, over
/// three forcing periods (the paper's pendulum differs by 3e-9 there).
#[test]
fn a_rig_pendulum_converges_with_the_tolerance() {
    let losses = friction(0.02)
        .with_drag(0.01)
        .unwrap()
        .with_cubic_damping(0.002)
        .unwrap();
    let harmonics = DriveHarmonics::new(&[DriveHarmonic::new(2, 0.1, 0.3).unwrap()]).unwrap();
    let rig = Pendulum::paper()
        .with_losses(losses)
        .with_drive_harmonics(harmonics);
    let run = |rtol: f64| {
        simulate(
            &rig,
            &SimulationConfig::paper()
                .with_transient_periods(0)
                .with_samples(75)
                .unwrap()
                .with_tolerances(Tolerances::relative(rtol).unwrap()),
        )
        .unwrap()
    };
    let (loose, tight) = (run(1e-10), run(1e-13));
    let worst = loose
        .theta
        .iter()
        .zip(&tight.theta)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-8, "rtol 1e-10 against 1e-13 over 3 periods: {worst:e}");
}

/// The same rig in seconds and in its own time: the events do not depend on the frame (a
/// pendulum on a periodic attractor, so that rounding is not amplified).
#[test]
fn a_rig_in_seconds_is_the_rig_in_its_own_time() {
    let rig = Pendulum::new(0.8, 0.1, 0.8333)
        .unwrap()
        .with_losses(friction(0.05).with_drag(0.02).unwrap());
    let frame = RecordFrame::nondimensional().with_drive_frequency(1.5).unwrap();
    let rate = frame.rate();
    let tol = Tolerances::relative(1e-12).unwrap();
    let seconds = simulate(
        &InFrame::new(rig, frame),
        &SimulationConfig::paper()
            .with_drive_period(frame.drive_period())
            .unwrap()
            .with_sample_step(0.01)
            .unwrap()
            .with_transient_periods(0)
            .with_samples(1_500)
            .unwrap()
            .with_tolerances(tol),
    )
    .unwrap();
    let own = simulate(
        &rig,
        &SimulationConfig::paper()
            .with_sample_step(0.01 * rate)
            .unwrap()
            .with_transient_periods(0)
            .with_samples(1_500)
            .unwrap()
            .with_tolerances(tol),
    )
    .unwrap();
    for n in (0..1_500).step_by(7) {
        assert!((own.theta[n] - seconds.theta[n]).abs() < 1e-9, "sample {n}");
        assert!(
            (rate * own.omega[n] - seconds.omega[n]).abs() < 1e-8,
            "sample {n}"
        );
    }
}

/// The variational equation with the saltation at every reversal and stick is the
/// derivative of the flow, as finite differences of the flow give it.
#[test]
fn the_flow_derivative_crosses_reversals_and_sticks() {
    let tol = Tolerances::new(1e-13, 1e-14).unwrap();
    for (system, duration) in [
        // Reversals only.
        (
            Duffing::new(0.1, 1.0, 0.0, 1.5)
                .unwrap()
                .with_losses(friction(0.2)),
            9.0,
        ),
        // A stick on the way.
        (
            Duffing::new(0.1, 1.0, 0.0, 0.5)
                .unwrap()
                .with_losses(friction(0.3)),
            9.0,
        ),
        // Drag and friction on the chaotic pendulum.
        (
            Duffing::two_well().with_losses(friction(0.02).with_drag(0.05).unwrap()),
            12.0,
        ),
    ] {
        let z = [0.3, 0.4];
        let (_, m) = flow_with_jacobian(&system, 0.0, z, duration, tol).unwrap();
        let e = 1e-6;
        for (j, dz) in [[e, 0.0], [0.0, e]].iter().enumerate() {
            let plus = flow_with_jacobian(&system, 0.0, [z[0] + dz[0], z[1] + dz[1]], duration, tol)
                .unwrap()
                .0;
            let minus = flow_with_jacobian(&system, 0.0, [z[0] - dz[0], z[1] - dz[1]], duration, tol)
                .unwrap()
                .0;
            for i in 0..2 {
                let fd = (plus[i] - minus[i]) / (2.0 * e);
                assert!(
                    (m[(i, j)] - fd).abs() < 1e-4 * (1.0 + fd.abs()),
                    "{system:?}: M[{i},{j}] = {} vs {fd}",
                    m[(i, j)]
                );
            }
        }
    }
}

/// A body that starts at rest where friction holds it never moves.
#[test]
fn held_at_rest_it_stays() {
    let system = Duffing::new(0.0, 1.0, 0.0, 0.0)
        .unwrap()
        .with_losses(friction(0.5));
    let traj = simulate(
        &system,
        &SimulationConfig::paper()
            .with_transient_periods(0)
            .with_initial(0.3, 0.0)
            .unwrap()
            .with_samples(100)
            .unwrap(),
    )
    .unwrap();
    assert!(traj.theta.iter().all(|&x| x == 0.3) && traj.omega.iter().all(|&v| v == 0.0));
}

fn pendulum_rig() -> impl Strategy<Value = (Pendulum, f64, f64)> {
    (
        0.0..0.1f64,
        0.5..1.5f64,
        0.0..0.2f64,
        0.0..0.2f64,
        0.0..0.1f64,
        -3.0..3.0f64,
        -3.0..3.0f64,
    )
        .prop_map(|(c, r, mu, d, c3, x0, v0)| {
            let losses = Losses::none()
                .with_friction(mu)
                .unwrap()
                .with_drag(d)
                .unwrap()
                .with_cubic_damping(c3)
                .unwrap();
            (Pendulum::new(0.0, c, r).unwrap().with_losses(losses), x0, v0)
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Without a drive, every loss takes energy out: `E` never grows along a trajectory.
    #[test]
    fn free_energy_never_grows((pendulum, x0, v0) in pendulum_rig()) {
        let traj = simulate(
            &pendulum,
            &SimulationConfig::paper()
                .with_sample_step(0.05)
                .unwrap()
                .with_transient_periods(0)
                .with_initial(x0, v0)
                .unwrap()
                .with_samples(600)
                .unwrap(),
        )
        .unwrap();
        let energy: Vec<f64> = traj
            .theta
            .iter()
            .zip(&traj.omega)
            .map(|(&x, &v)| pendulum.energy(x, v))
            .collect();
        for w in energy.windows(2) {
            prop_assert!(w[1] <= w[0] + 1e-9 * (1.0 + w[0]), "{} -> {}", w[0], w[1]);
        }
    }

    /// Away from `x' = 0` the Jacobian is the derivative of `F` (central differences), and
    /// each branch is `F` on its own side.
    #[test]
    fn jacobian_and_branches_away_from_rest(
        (pendulum, x, v) in pendulum_rig(),
        f in -2.0..2.0f64,
        ratio in 0.0..0.5f64,
        phase in -3.0..3.0f64,
        t in -10.0..10.0f64,
    ) {
        prop_assume!(v.abs() > 1e-3);
        let harmonics = DriveHarmonics::new(&[DriveHarmonic::new(3, ratio, phase).unwrap()]).unwrap();
        let p = Pendulum::new(f, pendulum.c(), pendulum.r())
            .unwrap()
            .with_losses(*pendulum.losses())
            .with_drive_harmonics(harmonics);
        let duffing = Duffing::new(pendulum.c(), -1.0, 1.0, f)
            .unwrap()
            .with_losses(*pendulum.losses())
            .with_drive_harmonics(harmonics);
        let branch = Branch::of(v).unwrap();
        for s in [&p as &dyn SecondOrderSystem, &duffing] {
            let e = 1e-6 * (1.0 + v.abs());
            let dx = (s.acceleration(t, x + e, v) - s.acceleration(t, x - e, v)) / (2.0 * e);
            let dv = (s.acceleration(t, x, v + e) - s.acceleration(t, x, v - e)) / (2.0 * e);
            let [jx, jv] = s.jacobian(t, x, v);
            prop_assert!((jx - dx).abs() < 1e-6 * (1.0 + dx.abs()), "{jx} vs {dx}");
            prop_assert!((jv - dv).abs() < 1e-6 * (1.0 + dv.abs()), "{jv} vs {dv}");
            let a = s.acceleration(t, x, v);
            prop_assert!((s.acceleration_on(branch, t, x, v) - a).abs() <= 1e-12 * (1.0 + a.abs()));
            prop_assert_eq!(s.jacobian_on(branch, t, x, v), s.jacobian(t, x, v));
        }
    }
}
