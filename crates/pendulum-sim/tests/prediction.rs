//! Validation without the true equation: the record's spread, the state estimated from the samples,
//! valid prediction times of a true and a wrong model, the envelope of a free decay, and the
//! configuration's checks.
use std::f64::consts::TAU;

use circle_signal::{SampleClock, circle_distance, wrap};
use pendulum_sim::{
    Domain, Pendulum, PredictionConfig, PredictionRecord, SimError, SimulationConfig, decay_envelope,
    estimate_state, predict_window, prediction_starts, simulate, valid_prediction_times,
};

fn paper_record(samples: usize) -> (Vec<f64>, Vec<f64>, SampleClock) {
    let traj = simulate(
        &Pendulum::paper(),
        &SimulationConfig::paper().with_samples(samples).unwrap(),
    )
    .unwrap();
    let clock = SampleClock::nondimensional(25)
        .unwrap()
        .with_start_time(traj.t[0])
        .unwrap();
    (traj.wrapped(), traj.omega, clock)
}

/// The spread of `samples` as a record of them reports it (computed when the record is made).
fn spread(samples: &[f64], domain: Domain) -> f64 {
    let clock = SampleClock::nondimensional(25).unwrap();
    PredictionRecord::new(samples, clock, domain).unwrap().spread()
}

#[test]
fn spread_knows_the_circle() {
    assert_eq!(spread(&[1.0, f64::NAN, -2.0, 0.5], Domain::Line), 3.0);
    // Three points near ±π: the shortest arc through them is 0.3 long, across the wrap.
    let near_pi = [3.0, -3.1, std::f64::consts::PI - 0.05];
    let s = spread(&near_pi, Domain::Circle);
    assert!((s - (TAU - 6.1)).abs() < 1e-12, "{s}");
    let whirl: Vec<f64> = (0..100).map(|n| wrap(0.1 * n as f64)).collect();
    assert!(spread(&whirl, Domain::Circle) > TAU - 0.11);
    assert!(
        PredictionRecord::new(&[0.3; 10], SampleClock::nondimensional(5).unwrap(), Domain::Line).is_err()
    );
}

/// The local fit gives the state of a smooth motion: the velocity of the paper's pendulum to
/// the accuracy of a degree-4 fit of five samples, across the wrap.
#[test]
fn the_state_comes_from_the_samples() {
    let (x, v, clock) = paper_record(2_000);
    let record = PredictionRecord::new(&x, clock, Domain::Circle).unwrap();
    let config = PredictionConfig::default();
    let mut worst: f64 = 0.0;
    let mut worst_x: f64 = 0.0;
    for n in 2..1_998 {
        let [xe, ve] = estimate_state(&record, n, &config).unwrap();
        worst = worst.max((ve - v[n]).abs());
        worst_x = worst_x.max(circle_distance(xe, x[n]));
    }
    // An interpolation reproduces the sample; h⁴ x⁽⁵⁾/30 with h = 2π/25 bounds the velocity's error.
    assert!(worst_x < 1e-12, "{worst_x:e}");
    assert!(worst < 0.05, "largest velocity error {worst:e}");
    // Two samples each side at least.
    assert!(estimate_state(&record, 1, &config).is_err());
    assert!(estimate_state(&record, 2, &config).is_ok());
    let mut gappy = x.clone();
    gappy[100] = f64::NAN;
    gappy[102] = f64::NAN;
    let record = PredictionRecord::new(&gappy, clock, Domain::Circle).unwrap();
    assert!(matches!(
        estimate_state(&record, 101, &config),
        Err(SimError::NoStateEstimate { index: 101, .. })
    ));
    assert!(estimate_state(&record, 100, &config).is_err());
}

/// The true model from the exact state predicts its own record far longer than a model with a
/// wrong damping; windows stop at gaps and at the horizon.
#[test]
fn the_true_model_outlasts_a_wrong_one() {
    let (x, v, clock) = paper_record(6_000);
    let record = PredictionRecord::new(&x, clock, Domain::Circle).unwrap();
    let config = PredictionConfig::default().with_windows(12).unwrap();
    let starts = prediction_starts(&record, &config).unwrap();
    assert_eq!(starts.len(), 12);
    assert!(starts[0] >= 2 && *starts.last().unwrap() <= 6_000 - 1 - 1_000);
    let truth = valid_prediction_times(&Pendulum::paper(), &record, &starts, &config, Some(0.187)).unwrap();
    let wrong = Pendulum::new(1.52, 0.06, 0.8333).unwrap();
    let off = valid_prediction_times(&wrong, &record, &starts, &config, Some(0.187)).unwrap();
    let (a, b) = (truth.in_periods().unwrap(), off.in_periods().unwrap());
    assert!(a.median > 2.0 * b.median, "true {a:?}, wrong {b:?}");
    let lyap = truth.in_lyapunov_times().unwrap();
    assert!((lyap.median - a.median * TAU * 0.187).abs() < 1e-9);
    // From the exact state the true model follows the record to the horizon, or nearly.
    let exact = predict_window(
        &Pendulum::paper(),
        &record,
        starts[3],
        [x[starts[3]], v[starts[3]]],
        &config,
    )
    .unwrap();
    assert!(exact.valid_time > a.median * TAU, "{exact:?}");
    // A gap ends the window, censored.
    let mut gappy = x.clone();
    gappy[starts[0] + 10] = f64::NAN;
    let record = PredictionRecord::new(&gappy, clock, Domain::Circle).unwrap();
    let w = predict_window(
        &Pendulum::paper(),
        &record,
        starts[0],
        [x[starts[0]], v[starts[0]]],
        &config,
    )
    .unwrap();
    assert!(
        w.censored && (w.valid_time - 9.0 * clock.step()).abs() < 1e-9,
        "{w:?}"
    );
    // A short horizon censors every window of the truth.
    let short = config.with_horizon(0.5).unwrap();
    let t = valid_prediction_times(
        &Pendulum::paper(),
        &PredictionRecord::new(&x, clock, Domain::Circle).unwrap(),
        &starts,
        &short,
        None,
    )
    .unwrap();
    let s = t.in_periods().unwrap();
    assert_eq!(s.censored, s.windows);
    assert!(s.median_is_lower_bound() && (s.median - 0.5).abs() < 0.05);
    assert!(t.in_lyapunov_times().is_none());
}

/// A free decay: the true model's envelope matches the record's, a model with twice the
/// damping decays visibly faster.
#[test]
fn decay_envelope_tells_the_damping() {
    let pendulum = Pendulum::new(0.0, 0.05, 0.8333).unwrap();
    let traj = simulate(
        &pendulum,
        &SimulationConfig::paper()
            .with_transient_periods(0)
            .with_initial(2.5, 0.0)
            .unwrap()
            .with_samples(3_000)
            .unwrap(),
    )
    .unwrap();
    let x = traj.wrapped();
    let clock = SampleClock::nondimensional(25).unwrap();
    let record = PredictionRecord::new(&x, clock, Domain::Circle).unwrap();
    let config = PredictionConfig::default();
    let own = decay_envelope(&pendulum, &record, &config).unwrap();
    assert!(own.relative_errors.len() > 20, "{own:?}");
    assert!(own.max_error().unwrap() < 1e-3, "{:?}", own.max_error());
    // The envelope decays: each swing smaller than the one before.
    assert!(own.record.windows(2).all(|w| w[1] < w[0]));
    let heavier = Pendulum::new(0.0, 0.1, 0.8333).unwrap();
    let off = decay_envelope(&heavier, &record, &config).unwrap();
    assert!(off.median_error().unwrap() > 0.1, "{:?}", off.median_error());
    assert!(off.relative_errors.iter().all(|&e| e < 0.0));
}

#[test]
fn config_is_checked() {
    let c = PredictionConfig::default();
    assert!(c.with_tolerance(0.0).is_err() && c.with_tolerance(1.5).is_err());
    assert!(c.with_horizon(f64::NAN).is_err() && c.with_windows(0).is_err());
    assert!(c.with_fit_span(-1.0).is_err());
    let json = serde_json::to_string(&c).unwrap();
    assert_eq!(serde_json::from_str::<PredictionConfig>(&json).unwrap(), c);
    let bad = json.replace("\"windows\":32", "\"windows\":0");
    assert!(serde_json::from_str::<PredictionConfig>(&bad).is_err());
}
