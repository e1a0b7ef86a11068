//! The integration of systems of several coordinates: one coordinate runs as the one-coordinate
//! simulation does, a smooth system as DOP853 alone, every size against a closed form, the
//! sampling conventions, a singular mass matrix stopping a free run, and refused input.
// Samples of several series (times, coordinates, velocities) are indexed together.
#![allow(clippy::needless_range_loop)]

use std::f64::consts::TAU;

use pendulum_sim::{
    Dop853, DoublePendulum, Duffing, Losses, MultiConfig, MultiState, MultiSystem, OdeSystem, OneCoordinate,
    Pendulum, SimError, SimulationConfig, SingularMass, Tolerances, free_run, multi, poincare_section,
    simulate,
};

fn one_coordinate_config(x0: f64, v0: f64) -> SimulationConfig {
    SimulationConfig::paper()
        .with_samples(2_000)
        .unwrap()
        .with_samples_per_period(40)
        .unwrap()
        .with_transient_periods(3)
        .with_phase(0.25)
        .unwrap()
        .with_initial(x0, v0)
        .unwrap()
        .with_tolerances(Tolerances::relative(1e-10).unwrap())
}

/// With `n = 1` the multi integrator is the one-coordinate integrator: the same steps, events
/// and numbers, bit for bit, for a smooth system and for one that sticks for long stretches.
#[test]
fn one_coordinate_runs_as_the_one_coordinate_simulation() {
    let sticking = Duffing::new(0.1, 1.0, 0.0, 0.5)
        .unwrap()
        .with_losses(Losses::none().with_friction(0.45).unwrap());
    for (x0, v0) in [(0.2, 0.0), (0.1, -0.3)] {
        let config = one_coordinate_config(x0, v0);
        let state = MultiState::new(&[x0], &[v0]).unwrap();
        let several = MultiConfig::from_sampling(config.clone(), state);
        let one = simulate(&Pendulum::paper(), &config).unwrap();
        let many = multi::simulate(&OneCoordinate(Pendulum::paper()), &several).unwrap();
        assert_eq!(many.coordinates(), 1);
        assert_eq!(many.coordinate(0), one, "the paper's pendulum from ({x0}, {v0})");
        let one = simulate(&sticking, &config).unwrap();
        let many = multi::simulate(&OneCoordinate(sticking), &several).unwrap();
        assert_eq!(
            many.coordinate(0),
            one,
            "a stick-slip oscillator from ({x0}, {v0})"
        );
    }
    let rests = simulate(&sticking, &one_coordinate_config(0.2, 0.0))
        .unwrap()
        .omega
        .iter()
        .filter(|&&v| v == 0.0)
        .count();
    assert!(rests > 200, "{rests} samples at rest: sticking is not tested");

    // Free runs and sections likewise.
    let rig = Pendulum::paper().with_losses(
        Losses::none()
            .with_friction(0.02)
            .unwrap()
            .with_drag(0.01)
            .unwrap(),
    );
    let tol = Tolerances::relative(1e-10).unwrap();
    let one = free_run(&rig, 1.0, 0.1, 500, [0.3, 0.1], tol).unwrap();
    let times: Vec<f64> = (0..500).map(|n| 1.0 + n as f64 * 0.1).collect();
    let many = multi::free_run(
        &OneCoordinate(rig),
        &times,
        &MultiState::new(&[0.3], &[0.1]).unwrap(),
        tol,
    )
    .unwrap();
    assert_eq!((&many.q[0], &many.v[0]), (&one.x, &one.v));
    assert!(many.stopped.is_none() && one.stopped.is_none());
    let config = one_coordinate_config(0.3, 0.0).with_samples(50).unwrap();
    let one = poincare_section(&rig, &config).unwrap();
    let many = multi::poincare_section(
        &OneCoordinate(rig),
        &MultiConfig::from_sampling(config, MultiState::new(&[0.3], &[0.0]).unwrap()),
    )
    .unwrap();
    let pairs: Vec<[f64; 2]> = many.q[0].iter().zip(&many.v[0]).map(|(&x, &v)| [x, v]).collect();
    assert_eq!(pairs, one);
}

/// Two oscillators coupled by a spring, driven by a measured cosine, as a hand-written first-order
/// system.
#[derive(Clone, Copy)]
struct Oscillators {
    drive: fn(f64) -> f64,
}

impl OdeSystem<4> for Oscillators {
    fn rhs(&self, t: f64, y: &[f64; 4], dy: &mut [f64; 4]) {
        let mut acc = [0.0; 2];
        self.accelerations(t, &y[..2], &y[2..], &mut acc).unwrap();
        *dy = [y[2], y[3], acc[0], acc[1]];
    }
}

impl MultiSystem for Oscillators {
    fn coordinates(&self) -> usize {
        2
    }
    fn accelerations(&self, t: f64, q: &[f64], v: &[f64], acc: &mut [f64]) -> Result<(), SingularMass> {
        let p = (self.drive)(t);
        acc[0] = -0.1 * v[0] - 1.3 * q[0] - q[0].powi(3) - 0.4 * (q[0] - q[1]) - p;
        acc[1] = -0.2 * v[1] - 0.7 * q[1] + 0.4 * (q[0] - q[1]) - p;
        Ok(())
    }
}

/// A smooth system of several coordinates takes exactly the steps of DOP853 alone: its samples
/// are those of the integrator on the same first-order system, bit for bit.
#[test]
fn a_smooth_system_takes_the_steps_of_dop853_alone() {
    let system = Oscillators {
        drive: |t| 0.8 * (0.9 * t).cos(),
    };
    let tol = Tolerances::relative(1e-9).unwrap();
    let config = MultiConfig::new(MultiState::new(&[0.5, -0.2], &[0.0, 0.3]).unwrap())
        .with_sample_step(0.05)
        .unwrap()
        .with_transient_periods(0)
        .with_samples(2_000)
        .unwrap()
        .with_tolerances(tol);
    let traj = multi::simulate(&system, &config).unwrap();
    let mut alone = Dop853::new(system, 0.0, [0.5, -0.2, 0.0, 0.3], tol).unwrap();
    let mut expected = Vec::new();
    alone
        .sample_grid(0.0, 0.05, 2_000, |_, _, y| expected.push(*y))
        .unwrap();
    for (n, y) in expected.iter().enumerate() {
        let got = [traj.q[0][n], traj.q[1][n], traj.v[0][n], traj.v[1][n]];
        assert_eq!(&got, y, "sample {n}");
    }
}

/// `n` uncoupled oscillators `x_i'' + ω_i² x_i = 0`, `ω_i = 1 + i/10`: every size of state the
/// integrator is compiled for, against `x_i = cos(ω_i t)`.
struct Uncoupled(usize);

impl MultiSystem for Uncoupled {
    fn coordinates(&self) -> usize {
        self.0
    }
    fn accelerations(&self, _t: f64, q: &[f64], _v: &[f64], acc: &mut [f64]) -> Result<(), SingularMass> {
        for i in 0..self.0 {
            let w = 1.0 + 0.1 * i as f64;
            acc[i] = -w * w * q[i];
        }
        Ok(())
    }
}

#[test]
fn every_size_integrates_its_closed_form() {
    for n in 1..=pendulum_sim::MAX_COORDINATES {
        let config = MultiConfig::new(MultiState::at_rest(&vec![1.0; n]).unwrap())
            .with_sample_step(0.1)
            .unwrap()
            .with_transient_periods(1)
            .with_samples(300)
            .unwrap()
            .with_tolerances(Tolerances::relative(1e-11).unwrap());
        let traj = multi::simulate(&Uncoupled(n), &config).unwrap();
        assert_eq!(traj.coordinates(), n);
        for (k, &t) in traj.t.iter().enumerate() {
            for i in 0..n {
                let w = 1.0 + 0.1 * i as f64;
                let (x, v) = ((w * t).cos(), -w * (w * t).sin());
                // Global error of a few hundred steps at 1e-11: far below 1e-8.
                assert!(
                    (traj.q[i][k] - x).abs() < 1e-8 && (traj.v[i][k] - v).abs() < 1e-8,
                    "n = {n}, coordinate {i}, t = {t}"
                );
            }
        }
    }
    for n in [0, pendulum_sim::MAX_COORDINATES + 1] {
        let err = multi::free_run(
            &Uncoupled(n),
            &[0.0, 1.0],
            &MultiState::at_rest(&[1.0]).unwrap(),
            Tolerances::default(),
        )
        .unwrap_err();
        assert!(
            matches!(
                err,
                SimError::InvalidParameter {
                    name: "coordinates",
                    ..
                }
            ),
            "{err}"
        );
    }
}

/// Samples at exactly the config's times (by multiplication); the section is the stroboscopic
/// subsample of a full run that ends at the same time; progress ends at the total.
#[test]
fn sampling_follows_the_one_coordinate_conventions() {
    let pendulum = DoublePendulum::whirling();
    let per = 32;
    let periods = 12;
    let config = MultiConfig::new(MultiState::at_rest(&[2.0, 0.0]).unwrap())
        .with_samples_per_period(per)
        .unwrap()
        .with_transient_periods(2)
        .with_phase(0.5)
        .unwrap()
        .with_samples((periods - 1) * per + 1)
        .unwrap();
    let mut calls = Vec::new();
    let full =
        multi::simulate_with_progress(&pendulum, &config, |done, total| calls.push((done, total))).unwrap();
    assert_eq!(calls.first(), Some(&(0, full.len())));
    assert_eq!(calls.last(), Some(&(full.len(), full.len())));
    assert!(calls.len() >= 100, "{} progress calls", calls.len());
    for (n, &t) in full.t.iter().enumerate() {
        assert_eq!(t, config.sample_time(n));
        assert_eq!(t, 0.5 * TAU + (2 * per + n) as f64 * TAU / per as f64);
    }
    let section = multi::poincare_section(&pendulum, &config.clone().with_samples(periods).unwrap()).unwrap();
    assert_eq!(section.len(), periods);
    for k in 0..periods {
        for c in 0..2 {
            assert_eq!(section.q[c][k], full.q[c][k * per], "period {k}, coordinate {c}");
            assert_eq!(section.v[c][k], full.v[c][k * per], "period {k}, coordinate {c}");
        }
    }
}

/// Two coordinates whose mass matrix `[[1, t/2], [t/2, 1]]` becomes singular at `t = 2` (and
/// indefinite after), no forces: uniform motion until then.
struct Degenerating;

impl MultiSystem for Degenerating {
    fn coordinates(&self) -> usize {
        2
    }
    fn accelerations(&self, t: f64, _q: &[f64], _v: &[f64], acc: &mut [f64]) -> Result<(), SingularMass> {
        let det = 1.0 - 0.25 * t * t;
        if det <= 0.0 {
            return Err(SingularMass { t, pivot: det });
        }
        // M a = 0.
        acc[0] = 0.0;
        acc[1] = 0.0;
        Ok(())
    }
}

#[test]
fn a_singular_mass_matrix_stops_a_free_run_with_its_reason() {
    let times: Vec<f64> = (0..40).map(|n| n as f64 * 0.1).collect();
    let state = MultiState::new(&[1.0, -1.0], &[0.5, 0.25]).unwrap();
    let run = multi::free_run(&Degenerating, &times, &state, Tolerances::default()).unwrap();
    // t = 0, 0.1, ..., 1.9 (rounded below 2) before the singularity; 2.0 and after not.
    assert_eq!(run.finite_len(), 20);
    for n in 0..20 {
        let t = times[n];
        assert!((run.q[0][n] - (1.0 + 0.5 * t)).abs() < 1e-12);
        assert!((run.q[1][n] - (-1.0 + 0.25 * t)).abs() < 1e-12);
    }
    assert!(
        run.q
            .iter()
            .chain(&run.v)
            .all(|x| x[20..].iter().all(|v| v.is_nan()))
    );
    match run.stopped {
        Some(SimError::SingularMass { t, pivot }) => {
            assert!((t - 2.0).abs() < 1e-9 && pivot <= 0.0, "t = {t}, pivot {pivot}")
        }
        other => panic!("stopped by {other:?}"),
    }

    // A base-excited double pendulum with a massless first bob (μ = 1) started with its links in
    // line: singular from the first instant. A free run says so; a simulation fails with it.
    let aligned = DoublePendulum::new(1.0, 0.5, 0.5, 0.6, 0.05, 0.05).unwrap();
    let state = MultiState::at_rest(&[1.0, 1.0]).unwrap();
    let run = multi::free_run(&aligned, &[0.5, 1.0], &state, Tolerances::default()).unwrap();
    assert_eq!(run.finite_len(), 0);
    assert!(
        matches!(run.stopped, Some(SimError::SingularMass { t, .. }) if t == 0.5),
        "{:?}",
        run.stopped
    );
    let err = multi::simulate(&aligned, &MultiConfig::new(state).with_samples(10).unwrap()).unwrap_err();
    assert!(
        matches!(err, SimError::SingularMass { t, .. } if t == 0.0),
        "{err}"
    );
}

#[test]
fn refuses_what_it_cannot_run() {
    let tol = Tolerances::default();
    let pendulum = DoublePendulum::whirling();
    let three = MultiState::at_rest(&[0.1, 0.2, 0.3]).unwrap();
    assert!(matches!(
        multi::free_run(&pendulum, &[0.0, 1.0], &three, tol),
        Err(SimError::InvalidParameter {
            name: "initial state",
            ..
        })
    ));
    assert!(multi::simulate(&pendulum, &MultiConfig::new(three)).is_err());
    let two = MultiState::at_rest(&[0.1, 0.2]).unwrap();
    for bad in [vec![0.0, 1.0, 0.5], vec![0.0, f64::NAN]] {
        assert!(
            matches!(
                multi::free_run(&pendulum, &bad, &two, tol),
                Err(SimError::InvalidParameter {
                    name: "sample time",
                    ..
                })
            ),
            "{bad:?}"
        );
    }
    // Equal times are samples of the same instant.
    let run = multi::free_run(&pendulum, &[1.0, 1.0, 2.0, 2.0], &two, tol).unwrap();
    assert_eq!(run.q[0][0], 0.1);
    assert_eq!(run.q[0][1], 0.1);
    assert_eq!(run.q[1][2], run.q[1][3]);
    assert!(multi::free_run(&pendulum, &[], &two, tol).unwrap().q[0].is_empty());
    // States: as many velocities as coordinates, 1 to 8 of them, all finite.
    assert!(MultiState::new(&[], &[]).is_err());
    assert!(MultiState::new(&[0.0; 9], &[0.0; 9]).is_err());
    assert!(MultiState::new(&[0.0, 1.0], &[0.0]).is_err());
    assert!(MultiState::new(&[0.0, f64::INFINITY], &[0.0, 0.0]).is_err());
    assert!(MultiState::new(&[0.0, 1.0], &[f64::NAN, 0.0]).is_err());
}

/// The systems can be shared between threads, a measured drive included.
#[test]
fn systems_are_send_and_sync() {
    fn shared<T: Send + Sync>() {}
    shared::<pendulum_sim::DoublePendulum>();
    shared::<pendulum_sim::TorqueDoublePendulum>();
    shared::<pendulum_sim::CoupledDuffing>();
    shared::<pendulum_sim::MultiConfig>();
}

/// A sample that breaks ends the simulation there, of one coordinate and of several: the samples
/// given until then are the whole simulation's, none comes after, and the progress never says
/// the record is done (a writer whose disk filled up stops the integration at once).
#[test]
fn a_simulation_stops_at_the_sample_that_breaks() {
    use std::ops::ControlFlow;
    let stop_at = |n: usize| {
        if n == 99 {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    };
    let config = MultiConfig::new(MultiState::new(&[0.4, -0.2], &[0.0, 0.1]).unwrap())
        .with_samples(1_000)
        .unwrap()
        .with_transient_periods(1);
    let system = DoublePendulum::whirling();
    let whole = multi::simulate(&system, &config).unwrap();
    let (mut seen, mut done) = (Vec::new(), 0);
    multi::simulate_while(
        &system,
        &config,
        |d, _| done = d,
        |n, _, q, _| {
            seen.push((n, q[1]));
            stop_at(n)
        },
    )
    .unwrap();
    assert_eq!(seen.len(), 100);
    assert!(seen.iter().all(|&(n, q1)| q1 == whole.q[1][n]));
    assert!(done < 1_000, "progress said {done} of 1000");
    let one = one_coordinate_config(0.1, 0.0);
    let whole = simulate(&Pendulum::paper(), &one).unwrap();
    let mut last = None;
    pendulum_sim::simulate_while(
        &Pendulum::paper(),
        &one,
        |_, _| {},
        |n, _, x, _| {
            last = Some((n, x));
            stop_at(n)
        },
    )
    .unwrap();
    assert_eq!(last, Some((99, whole.theta[99])));
}
