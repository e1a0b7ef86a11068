//! The valid prediction time of a system of several coordinates: one coordinate is the
//! one-coordinate test, the true double pendulum outlasts a wrong one, the coordinate that leaves
//! first is named, gaps in any coordinate end a window, a failing integration ends it where it
//! stopped, and the inputs are checked.
use circle_signal::{SampleClock, circle_distance, wrap};
use pendulum_sim::multi::{self, MultiConfig, MultiState, MultiSystem, OneCoordinate, SingularMass};
use pendulum_sim::prediction::{
    SystemPredictionRecord, SystemPredictionTimes, estimate_system_state, predict_system_window,
    system_prediction_starts, system_valid_prediction_times,
};
use pendulum_sim::{
    Domain, DoublePendulum, MultiTrajectory, Pendulum, PredictionConfig, PredictionRecord, SimError,
    SimulationConfig, prediction_starts, simulate, valid_prediction_times,
};

/// The whirling double pendulum at 64 samples per drive period, `periods` periods after 50 of
/// transient from rest at `(2, 0)`: the run and its clock.
fn whirling(periods: usize) -> (MultiTrajectory, SampleClock) {
    let config = MultiConfig::new(MultiState::at_rest(&[2.0, 0.0]).unwrap())
        .with_samples_per_period(64)
        .unwrap()
        .with_transient_periods(50)
        .with_samples(64 * periods)
        .unwrap();
    let run = multi::simulate(&DoublePendulum::whirling(), &config).unwrap();
    let clock = SampleClock::nondimensional(64)
        .unwrap()
        .with_start_time(run.t[0])
        .unwrap();
    (run, clock)
}

fn wrapped(q: &[f64]) -> Vec<f64> {
    q.iter().map(|&x| wrap(x)).collect()
}

/// The paper's pendulum as a system of one coordinate gives the valid times of the one-coordinate
/// test on the same windows.
#[test]
fn one_coordinate_is_the_one_coordinate_test() {
    let traj = simulate(
        &Pendulum::paper(),
        &SimulationConfig::paper().with_samples(4_000).unwrap(),
    )
    .unwrap();
    let x = traj.wrapped();
    let clock = SampleClock::nondimensional(25)
        .unwrap()
        .with_start_time(traj.t[0])
        .unwrap();
    let config = PredictionConfig::default().with_windows(8).unwrap();
    let one = PredictionRecord::new(&x, clock, Domain::Circle).unwrap();
    let system = SystemPredictionRecord::new(&[&x], clock, &[Domain::Circle]).unwrap();
    let starts = prediction_starts(&one, &config).unwrap();
    assert_eq!(system_prediction_starts(&system, &config).unwrap(), starts);
    let a = valid_prediction_times(&Pendulum::paper(), &one, &starts, &config, None).unwrap();
    let b =
        system_valid_prediction_times(&OneCoordinate(Pendulum::paper()), &system, &starts, &config).unwrap();
    assert_eq!(b.tolerances, vec![a.tolerance]);
    assert_eq!(b.drive_period, a.drive_period);
    for (wa, wb) in a.windows.iter().zip(&b.windows) {
        assert_eq!((wa.start, wa.censored), (wb.start, wb.censored));
        assert_eq!(wa.state, [wb.state.q()[0], wb.state.v()[0]]);
        // The same equation by the same integrator; only where the steps stop differs.
        assert!(
            (wa.valid_time - wb.valid_time).abs() < 1e-6,
            "{wa:?} against {wb:?}"
        );
        assert_eq!(wb.left.is_some(), !wb.censored);
    }
}

/// Both links' states come from the samples as the one-coordinate fit gives them. The whirling
/// links turn sharply: the default fit over a sixth of a period (11 samples at 64 per period)
/// smooths them (velocities to a few thousandths in the median, a few tenths at the sharpest
/// turns); two samples each side interpolate (positions exact, velocities to 0.06 everywhere).
#[test]
fn the_state_of_every_coordinate_comes_from_its_samples() {
    let (run, clock) = whirling(40);
    let (q1, q2) = (wrapped(&run.q[0]), wrapped(&run.q[1]));
    let record = SystemPredictionRecord::new(&[&q1, &q2], clock, &[Domain::Circle; 2]).unwrap();
    assert_eq!((record.len(), record.coordinates().len()), (q1.len(), 2));
    // Largest position and velocity errors, and the median velocity error.
    let errors = |config: &PredictionConfig| {
        let (mut worst_q, mut worst_v, mut v): (f64, f64, Vec<f64>) = (0.0, 0.0, Vec::new());
        for n in (10..q1.len() - 10).step_by(7) {
            let state = estimate_system_state(&record, n, config).unwrap();
            for c in 0..2 {
                worst_q = worst_q.max(circle_distance(state.q()[c], wrap(run.q[c][n])));
                let e = (state.v()[c] - run.v[c][n]).abs();
                worst_v = worst_v.max(e);
                v.push(e);
            }
        }
        v.sort_by(f64::total_cmp);
        (worst_q, worst_v, v[v.len() / 2])
    };
    let (_, _, median) = errors(&PredictionConfig::default());
    assert!(median < 1e-2, "median velocity error {median:e}");
    let interpolating = PredictionConfig::default().with_fit_span(2.0 / 64.0).unwrap();
    let (worst_q, worst_v, median) = errors(&interpolating);
    assert!(worst_q < 1e-12, "largest position error {worst_q:e}");
    assert!(
        worst_v < 0.06 && median < 1e-3,
        "velocity errors {worst_v:e}, {median:e}"
    );
    let config = PredictionConfig::default();
    // A gap in either coordinate leaves no state there.
    let mut gappy = q2.clone();
    gappy[300] = f64::NAN;
    let record = SystemPredictionRecord::new(&[&q1, &gappy], clock, &[Domain::Circle; 2]).unwrap();
    assert!(matches!(
        estimate_system_state(&record, 300, &config),
        Err(SimError::NoStateEstimate { index: 300, .. })
    ));
}

/// The true double pendulum stays with its record far longer than one whose second link is damped
/// three times as much; from the simulation's exact state longer still.
#[test]
fn the_true_double_pendulum_outlasts_a_wrong_one() {
    let (run, clock) = whirling(200);
    let (q1, q2) = (wrapped(&run.q[0]), wrapped(&run.q[1]));
    let record = SystemPredictionRecord::new(&[&q1, &q2], clock, &[Domain::Circle; 2]).unwrap();
    let config = PredictionConfig::default().with_windows(16).unwrap();
    let starts = system_prediction_starts(&record, &config).unwrap();
    assert_eq!(starts.len(), 16);
    let truth = DoublePendulum::whirling();
    let wrong = DoublePendulum::new(
        truth.mu(),
        truth.lambda(),
        truth.omega2(),
        truth.f(),
        truth.c1(),
        3.0 * truth.c2(),
    )
    .unwrap();
    let good = system_valid_prediction_times(&truth, &record, &starts, &config).unwrap();
    let bad = system_valid_prediction_times(&wrong, &record, &starts, &config).unwrap();
    let (a, b) = (good.in_periods().unwrap(), bad.in_periods().unwrap());
    assert!(a.median > 2.0 * b.median, "true {a:?}, wrong {b:?}");
    assert!((a.median * good.drive_period - good.summary().unwrap().median).abs() < 1e-9);
    // Every window that ended by leaving names the coordinate that left.
    for times in [&good, &bad] {
        let left: usize = (0..2).map(|c| times.left_by(c)).sum();
        let ended = times.windows.iter().filter(|w| !w.censored).count();
        assert_eq!(left, ended);
    }
    // The tolerance of each coordinate is a tenth of its spread: whirling links span the circle.
    for &t in &good.tolerances {
        assert!((t - 0.1 * std::f64::consts::TAU).abs() < 0.01, "{t}");
    }
    let n = starts[4];
    let exact = MultiState::new(&[run.q[0][n], run.q[1][n]], &[run.v[0][n], run.v[1][n]]).unwrap();
    let w = predict_system_window(&truth, &record, n, &exact, &config).unwrap();
    assert!(w.valid_time > a.median * good.drive_period, "{w:?}");
    // The windows serialise and come back (to the last digit JSON keeps).
    let json = serde_json::to_string(&good).unwrap();
    let back: SystemPredictionTimes = serde_json::from_str(&json).unwrap();
    assert_eq!(back.windows.len(), good.windows.len());
    for (a, b) in back.windows.iter().zip(&good.windows) {
        assert_eq!((a.start, a.left, a.censored), (b.start, b.left, b.censored));
        assert!((a.valid_time - b.valid_time).abs() < 1e-12);
    }
}

/// A record whose second coordinate turns away from the system's motion: the window ends there
/// and names that coordinate; a gap in one coordinate ends the window as censored.
#[test]
fn the_coordinate_that_leaves_first_is_named_and_gaps_end_windows() {
    let (run, clock) = whirling(30);
    let truth = DoublePendulum::whirling();
    let q1 = wrapped(&run.q[0]);
    let start = 200;
    let turn = start + 150;
    // Link 2 is a radian off from sample `turn` on.
    let q2: Vec<f64> = (0..q1.len())
        .map(|n| wrap(run.q[1][n] + if n >= turn { 1.0 } else { 0.0 }))
        .collect();
    let record = SystemPredictionRecord::new(&[&q1, &q2], clock, &[Domain::Circle; 2]).unwrap();
    let config = PredictionConfig::default();
    let exact = MultiState::new(
        &[run.q[0][start], run.q[1][start]],
        &[run.v[0][start], run.v[1][start]],
    )
    .unwrap();
    let w = predict_system_window(&truth, &record, start, &exact, &config).unwrap();
    assert_eq!(w.left, Some(1), "{w:?}");
    assert!(!w.censored);
    let (before, at) = (
        clock.time(turn - 1) - clock.time(start),
        clock.time(turn) - clock.time(start),
    );
    assert!(w.valid_time > before && w.valid_time <= at, "{w:?}");
    // Link 1 a radian off instead: link 1 is named.
    let q1_off: Vec<f64> = (0..q1.len())
        .map(|n| wrap(run.q[0][n] + if n >= turn { 1.0 } else { 0.0 }))
        .collect();
    let q2_true = wrapped(&run.q[1]);
    let record = SystemPredictionRecord::new(&[&q1_off, &q2_true], clock, &[Domain::Circle; 2]).unwrap();
    let w = predict_system_window(&truth, &record, start, &exact, &config).unwrap();
    assert_eq!(w.left, Some(0), "{w:?}");
    // A gap in link 2 ends the window before it, censored.
    let mut gappy = q2_true.clone();
    gappy[start + 40] = f64::NAN;
    let record = SystemPredictionRecord::new(&[&q1, &gappy], clock, &[Domain::Circle; 2]).unwrap();
    let w = predict_system_window(&truth, &record, start, &exact, &config).unwrap();
    assert!(w.censored && w.left.is_none(), "{w:?}");
    assert!((w.valid_time - 39.0 * clock.step()).abs() < 1e-9, "{w:?}");
    // A start at the gap has no state; the default starts skip it.
    assert!(matches!(
        predict_system_window(&truth, &record, start + 40, &exact, &config),
        Err(SimError::NoStateEstimate { .. })
    ));
    let spread_out = config.with_windows(q1.len()).unwrap();
    let starts = system_prediction_starts(&record, &spread_out).unwrap();
    assert!(!starts.contains(&(start + 40)));
    // A state already out of the tolerance has no valid time.
    let far = MultiState::new(&[run.q[0][start] + 2.0, run.q[1][start]], exact.v()).unwrap();
    let w = predict_system_window(&truth, &record, start, &far, &config).unwrap();
    assert_eq!((w.valid_time, w.left, w.censored), (0.0, Some(0), false));
}

/// A system whose mass matrix cannot be solved after a time: its integration fails, and its
/// valid time ends at the last sample it reached, neither censored nor naming a coordinate.
struct SingularAfter {
    t: f64,
}

impl MultiSystem for SingularAfter {
    fn coordinates(&self) -> usize {
        2
    }
    fn accelerations(&self, t: f64, q: &[f64], _v: &[f64], acc: &mut [f64]) -> Result<(), SingularMass> {
        if t > self.t {
            return Err(SingularMass { t, pivot: 0.0 });
        }
        // Two independent harmonic oscillators.
        acc[0] = -q[0];
        acc[1] = -q[1];
        Ok(())
    }
}

#[test]
fn a_failing_integration_ends_the_window_where_it_stopped() {
    let clock = SampleClock::nondimensional(32).unwrap();
    let h = clock.step();
    // Two oscillators' swings, one twice as wide.
    let q1: Vec<f64> = (0..2_000).map(|n| 0.3 * (n as f64 * h).cos()).collect();
    let q2: Vec<f64> = q1.iter().map(|x| 2.0 * x).collect();
    let v1 = -0.3 * (10.0 * h).sin();
    let record = SystemPredictionRecord::new(&[&q1, &q2], clock, &[Domain::Circle; 2]).unwrap();
    let config = PredictionConfig::default();
    let stop = clock.time(100) + 0.3 * h;
    let state = MultiState::new(&[q1[10], q2[10]], &[v1, 2.0 * v1]).unwrap();
    let w = predict_system_window(&SingularAfter { t: stop }, &record, 10, &state, &config).unwrap();
    assert!(!w.censored && w.left.is_none(), "{w:?}");
    assert!(
        (w.valid_time - (clock.time(100) - clock.time(10))).abs() < 1e-9,
        "{w:?}"
    );
}

#[test]
fn inputs_are_checked() {
    let clock = SampleClock::nondimensional(32).unwrap();
    let a: Vec<f64> = (0..200).map(|n| (0.1 * n as f64).sin()).collect();
    let b = a[..150].to_vec();
    let flat = vec![0.5; 200];
    let circle = [Domain::Circle; 2];
    assert!(SystemPredictionRecord::new(&[], clock, &[]).is_err());
    let nine: Vec<&[f64]> = vec![&a; 9];
    assert!(SystemPredictionRecord::new(&nine, clock, &[Domain::Line; 9]).is_err());
    assert!(SystemPredictionRecord::new(&[&a, &a], clock, &[Domain::Circle]).is_err());
    assert!(SystemPredictionRecord::new(&[&a, &b], clock, &circle).is_err());
    assert!(SystemPredictionRecord::new(&[&a, &flat], clock, &circle).is_err());
    let mut infinite = a.clone();
    infinite[3] = f64::INFINITY;
    assert!(SystemPredictionRecord::new(&[&a, &infinite], clock, &circle).is_err());
    // Each coordinate keeps its own domain and spread.
    let record = SystemPredictionRecord::new(&[&a, &a], clock, &[Domain::Circle, Domain::Line]).unwrap();
    assert_eq!(record.coordinates()[1].domain(), Domain::Line);
    assert!(!record.is_empty());
    let config = PredictionConfig::default();
    let pendulum = OneCoordinate(Pendulum::paper());
    // A system, or a state, of another number of coordinates; no start.
    assert!(system_valid_prediction_times(&pendulum, &record, &[20], &config).is_err());
    assert!(system_valid_prediction_times(&DoublePendulum::whirling(), &record, &[], &config).is_err());
    let one = MultiState::at_rest(&[0.0]).unwrap();
    assert!(predict_system_window(&DoublePendulum::whirling(), &record, 20, &one, &config).is_err());
    let two = MultiState::at_rest(&[0.0, 0.0]).unwrap();
    assert!(predict_system_window(&DoublePendulum::whirling(), &record, 200, &two, &config).is_err());
    // Too short for a state anywhere.
    let short = SystemPredictionRecord::new(&[&a[..3], &a[..3]], clock, &circle).unwrap();
    assert!(matches!(
        system_prediction_starts(&short, &config),
        Err(SimError::RecordTooShort { len: 3, .. })
    ));
}
