//! A measured drive `p`: exact manufactured cases of the weak form, the refusals of the paper's
//! method and of missing or mismatched samples, a model driven by its recorded drive, and models
//! saved before the measured drive (format 3) still read.
use circle_signal::SampleClock;
use hb_basis::{BasisKind, Domain, Polynomial};
use hb_model::{IdentifiedModel, MeasuredDrive, ModelForm, TermList};
use hb_solve::AssemblyError;
use hb_solve::{HarmonicBalance, IdentifyParams, QrSolver, Signals, SolveError, WeakForm, identify};
use pendulum_sim::{
    PredictionConfig, PredictionRecord, SecondOrderSystem, SimulationConfig, Tolerances, prediction_starts,
    simulate, valid_prediction_times,
};
use upo_search::{OrbitSource, Windows};

/// A smooth motion of two incommensurate frequencies, with its first and second derivatives.
fn motion(t: f64) -> (f64, f64, f64) {
    let (a, b) = (1.3, 2.0_f64.sqrt() * 1.7);
    let x = 0.9 * (a * t).sin() + 0.4 * (b * t + 0.3).cos();
    let v = 0.9 * a * (a * t).cos() - 0.4 * b * (b * t + 0.3).sin();
    let acc = -0.9 * a * a * (a * t).sin() - 0.4 * b * b * (b * t + 0.3).cos();
    (x, v, acc)
}

/// Windows of the default length over a displacement `x` on the line.
fn line_windows(clock: &SampleClock, x: &[f64]) -> Vec<circle_signal::Segment> {
    Windows::builder(clock)
        .domain(Domain::Line)
        .build()
        .unwrap()
        .segments(x)
        .unwrap()
}

/// The parameters of `form` on `clock`, and the samples of the measured drive `p` that go with
/// the record.
struct Driven {
    params: IdentifyParams,
    p: Option<Vec<f64>>,
}

/// The parameters of `form` on `clock` with the measured drive `p`.
fn with_drive(clock: SampleClock, form: ModelForm, p: Vec<f64>) -> Driven {
    Driven {
        params: IdentifyParams::builder(clock).form(form).build().unwrap(),
        p: Some(p),
    }
}

/// Parameters without a measured drive.
fn undriven(params: IdentifyParams) -> Driven {
    Driven { params, p: None }
}

/// The weak form's fit (QR) of `driven` over windows of `x` on the line, on the polynomial
/// basis of `degree`.
fn weak_fit(degree: usize, x: &[f64], driven: &Driven) -> Result<IdentifiedModel, SolveError> {
    let basis = BasisKind::from(Polynomial::new(degree).unwrap());
    let segments = line_windows(driven.params.clock(), x);
    let signals = Signals::one(x).with_drives(driven.p.iter().map(Vec::as_slice).collect())?;
    identify(
        basis,
        signals,
        &segments,
        &driven.params,
        &WeakForm::default(),
        &QrSolver::default(),
    )
}

/// Any motion satisfies `x'' + c x' + k x + b x³ − p = 0` exactly for the drive
/// `p = x'' + c x' + k x + b x³` it takes: a drive with no period at all. The weak form finds
/// `c`, `k`, `b` and the coefficient −1 of `p` to the accuracy of its quadrature, whatever `p`'s
/// waveform, where no function of the drive's phase could describe it.
#[test]
fn a_drive_of_no_period_is_balanced_exactly_by_the_weak_form() {
    let clock = SampleClock::new(2.0, 64).unwrap().with_start_time(0.25).unwrap();
    let (c, k, b) = (0.17, -0.8, 1.1);
    let n = 64 * 120;
    let (mut x, mut p) = (Vec::with_capacity(n), Vec::with_capacity(n));
    for i in 0..n {
        let (xi, vi, ai) = motion(clock.time(i));
        x.push(xi);
        p.push(ai + c * vi + k * xi + b * xi * xi * xi);
    }
    let list: TermList = "x', x, x^3, p".parse().unwrap();
    let params = with_drive(
        clock,
        ModelForm::from_terms(list).with_drive_column("p"),
        p.clone(),
    );
    let model = weak_fit(3, &x, &params).unwrap();
    for (name, want) in [("x'", c), ("x", k), ("x^3", b), ("p", -1.0)] {
        let got = model.coefficient(name).unwrap().value;
        assert!((got - want).abs() < 1e-6 * want.abs(), "{name}: {got} vs {want}");
    }
    assert_eq!(model.form().drive_column(), Some("p"));

    // The same record through a drive of the drive's phase cannot be described: cos(t), sin(t)
    // and their harmonics explain only part of it.
    let phase: TermList = "x', x, x^3, {cos(t),sin(t),cos(2t),sin(2t),cos(3t),sin(3t)}"
        .parse()
        .unwrap();
    let params = IdentifyParams::builder(clock)
        .form(ModelForm::from_terms(phase))
        .build()
        .unwrap();
    let wrong = weak_fit(3, &x, &undriven(params)).unwrap();
    assert!((wrong.coefficient("x").unwrap().value - k).abs() > 1e-3);
}

/// `p` times a function of `x'` has no exact integration by parts (the record does not give
/// `p'`): it is balanced at the velocity of each window's series, close but not exact.
#[test]
fn a_drive_times_the_velocity_is_balanced_at_the_series_velocity() {
    let clock = SampleClock::new(2.0, 64).unwrap();
    let (c, k, e) = (0.2, 1.0, 0.3);
    let n = 64 * 120;
    // The record from the motion, with p solving the equation for a known coefficient of p*x'.
    let x: Vec<f64> = (0..n).map(|i| motion(clock.time(i)).0).collect();
    let p: Vec<f64> = (0..n)
        .map(|i| {
            let t = clock.time(i);
            let (xi, vi, ai) = motion(t);
            // x'' + c x' + k x + e p x' − p = 0  ⇒  p = (x'' + c x' + k x) / (1 − e x').
            (ai + c * vi + k * xi) / (1.0 - e * vi)
        })
        .collect();
    let list: TermList = "x', x, p*x', p".parse().unwrap();
    let params = with_drive(clock, ModelForm::from_terms(list), p);
    let model = weak_fit(1, &x, &params).unwrap();
    for (name, want) in [("x'", c), ("x", k), ("p*x'", e), ("p", -1.0)] {
        let got = model.coefficient(name).unwrap().value;
        assert!((got - want).abs() < 1e-4 * want.abs(), "{name}: {got} vs {want}");
    }
}

#[test]
fn missing_mismatched_or_broken_drive_samples_and_the_papers_method_are_refused() {
    let clock = SampleClock::new(2.0, 32).unwrap();
    let x: Vec<f64> = (0..32 * 40).map(|i| motion(clock.time(i)).0).collect();
    let segments = line_windows(&clock, &x);
    let basis = BasisKind::from(Polynomial::new(1).unwrap());
    let form = || ModelForm::from_terms("x', x, p".parse().unwrap());
    let run = |driven: &Driven, weak: bool| {
        if weak {
            weak_fit(1, &x, driven)
        } else {
            let signals = Signals::one(&x).with_drives(driven.p.iter().map(Vec::as_slice).collect())?;
            identify(
                basis,
                signals,
                &segments,
                &driven.params,
                &HarmonicBalance,
                &QrSolver::default(),
            )
        }
    };
    let without = undriven(IdentifyParams::builder(clock).form(form()).build().unwrap());
    assert!(
        matches!(run(&without, true), Err(SolveError::Assembly(AssemblyError::MissingDriveSamples { term })) if term == "p")
    );
    let short = with_drive(clock, form(), vec![1.0; x.len() - 1]);
    assert!(matches!(
        run(&short, true),
        Err(SolveError::Assembly(AssemblyError::DriveLengthMismatch { drive, record })) if drive + 1 == record
    ));
    let mut broken = vec![1.0; x.len()];
    broken[100] = f64::NAN;
    let broken = with_drive(clock, form(), broken);
    assert!(matches!(
        run(&broken, true),
        Err(SolveError::Assembly(AssemblyError::NonFiniteDriveSample {
            index: 100,
            ..
        }))
    ));
    let fine = with_drive(clock, form(), vec![1.0; x.len()]);
    let refused = run(&fine, false).unwrap_err();
    assert!(
        matches!(
            refused,
            SolveError::Assembly(AssemblyError::MeasuredDriveUnsupported { .. })
        ),
        "{refused}"
    );
    assert!(refused.to_string().contains("weak form"), "{refused}");
    assert!(MeasuredDrive::new(Vec::<f64>::new(), 0.0, 1.0).is_err());
    assert!(MeasuredDrive::new(vec![1.0, 2.0], 0.0, 0.0).is_err());
    // A column is named only for a form with a term in p.
    let no_p = ModelForm::from_terms("x', x".parse().unwrap()).with_drive_column("p");
    assert!(matches!(
        IdentifyParams::builder(clock).form(no_p).build(),
        Err(SolveError::Model(hb_model::ModelError::Term(
            hb_model::TermError::InvalidForm { .. }
        )))
    ));
}

/// A Duffing oscillator driven by a waveform with harmonics, identified with `p`, integrated
/// again with its recorded drive ([`MeasuredDrive`]) from the record's state, follows the record;
/// without the signal the model says it needs one, and outside the recorded span it is NaN.
#[test]
fn a_model_in_the_measured_drive_is_simulated_with_its_recorded_drive() {
    let duffing = pendulum_sim::Duffing::new(0.25, -1.0, 1.0, 0.3)
        .unwrap()
        .with_drive_harmonics(
            pendulum_sim::DriveHarmonics::new(&[
                pendulum_sim::DriveHarmonic::new(2, 0.12, 0.5).unwrap(),
                pendulum_sim::DriveHarmonic::new(3, 0.15, -1.0).unwrap(),
            ])
            .unwrap(),
        );
    let p_per = 64;
    let config = SimulationConfig::paper()
        .with_samples_per_period(p_per)
        .unwrap()
        .with_samples(p_per * 200)
        .unwrap()
        .with_tolerances(Tolerances::new(1e-11, 1e-12).unwrap());
    let traj = simulate(&duffing, &config).unwrap();
    let clock = SampleClock::nondimensional(p_per)
        .unwrap()
        .with_start_time(traj.t[0])
        .unwrap();
    let p: Vec<f64> = traj.t.iter().map(|&t| duffing.drive(t)).collect();
    let params = with_drive(
        clock,
        ModelForm::from_terms("x', x, x^3, p".parse().unwrap()),
        p.clone(),
    );
    let model = weak_fit(3, &traj.theta, &params).unwrap();
    for (name, want) in [("x'", 0.25), ("x", -1.0), ("x^3", 1.0), ("p", -1.0)] {
        let got = model.coefficient(name).unwrap().value;
        assert!((got - want).abs() < 1e-6, "{name}: {got} vs {want}");
    }
    assert!(model.needs_measured_drive());
    let (t, x, v) = (traj.t[500], traj.theta[500], traj.omega[500]);
    assert!(model.acceleration(t, x, v).is_nan());

    let signal = MeasuredDrive::new(p.clone(), clock.start_time(), clock.step()).unwrap();
    // The spline passes through every sample and is NaN outside the span.
    assert!((signal.at(clock.time(37)) - p[37]).abs() < 1e-12);
    assert!(signal.at(clock.time(p.len() - 1) + 0.5 * clock.step()).is_nan());
    assert!(signal.at(clock.start_time() - 1e-9).is_nan());
    let model = model.with_measured_drive(signal).unwrap();
    assert!(!model.needs_measured_drive());
    // Its acceleration is the oscillator's within the spline's error (step 2π/64).
    let want = duffing.acceleration(t + 0.3 * clock.step(), x, v);
    let got = model.acceleration(t + 0.3 * clock.step(), x, v);
    assert!((got - want).abs() < 1e-4, "{got} vs {want}");
    // Validation that needs no truth: started from the record's own states, the model driven by
    // the recorded drive stays with the record as long as the true oscillator does.
    let record = PredictionRecord::new(&traj.theta, clock, Domain::Line).unwrap();
    let config = PredictionConfig::default().with_windows(12).unwrap();
    let starts = prediction_starts(&record, &config).unwrap();
    let ours = valid_prediction_times(&model, &record, &starts, &config, None).unwrap();
    let true_times = valid_prediction_times(&duffing, &record, &starts, &config, None).unwrap();
    let (a, b) = (
        ours.in_periods().unwrap().median,
        true_times.in_periods().unwrap().median,
    );
    assert!(
        b > 2.0 && (a - b).abs() <= 0.1 * b,
        "identified {a} vs true {b} drive periods"
    );
    // A model without a term in p takes no signal.
    let plain = weak_fit(
        3,
        &traj.theta,
        &undriven(
            IdentifyParams::builder(clock)
                .form(ModelForm::from_terms("x', x, x^3, cos(t)".parse().unwrap()))
                .build()
                .unwrap(),
        ),
    )
    .unwrap();
    let signal = MeasuredDrive::new(vec![0.0, 1.0], 0.0, 1.0).unwrap();
    assert!(matches!(
        plain.with_measured_drive(signal),
        Err(hb_model::ModelError::Term(
            hb_model::TermError::InvalidForm { .. }
        ))
    ));
}

/// The column of the measured drive is saved with the model (format 4), in JSON and binary; a
/// model saved by format 3 (general terms, no measured drive) reads as it was.
#[test]
fn the_drive_column_is_saved_and_format_3_models_still_load() {
    let clock = SampleClock::new(2.0, 32).unwrap();
    let x: Vec<f64> = (0..32 * 40).map(|i| motion(clock.time(i)).0).collect();
    let p: Vec<f64> = (0..x.len()).map(|i| (0.7 * clock.time(i)).sin()).collect();
    let params = with_drive(
        clock,
        ModelForm::from_terms("x', x, p".parse().unwrap()).with_drive_column("base acc"),
        p,
    );
    let model = weak_fit(1, &x, &params).unwrap();
    let json = model.to_json().unwrap();
    assert!(
        json.contains("\"version\": 4") && json.contains("\"drive_column\": \"base acc\""),
        "{json}"
    );
    let back = IdentifiedModel::<BasisKind>::from_json(&json).unwrap();
    assert_eq!(back, model);
    let bytes = IdentifiedModel::<BasisKind>::from_bytes(&model.to_bytes().unwrap()).unwrap();
    assert_eq!(bytes.form().drive_column(), Some("base acc"));
    // A column without a term in p, or an empty one, is refused on reading.
    let orphan = json
        .replace("\"p\"\n", "\"x^1\"\n")
        .replace("\"p\": {", "\"x^1\": {");
    assert!(IdentifiedModel::<BasisKind>::from_json(&orphan).is_err());
    assert!(IdentifiedModel::<BasisKind>::from_json(&json.replace("\"base acc\"", "\"\"")).is_err());

    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures");
    let json = std::fs::read_to_string(format!("{dir}/model_v3_rig_terms.json")).unwrap();
    assert!(json.contains("\"version\": 3"));
    let from_json = IdentifiedModel::<BasisKind>::from_json(&json).unwrap();
    let bytes = std::fs::read(format!("{dir}/model_v3_rig_terms.bin")).unwrap();
    assert_eq!(u32::from_le_bytes(bytes[8..12].try_into().unwrap()), 3);
    let from_bytes = IdentifiedModel::<BasisKind>::from_bytes(&bytes).unwrap();
    assert_eq!(from_json, from_bytes);
    assert_eq!(from_json.form().drive_column(), None);
    assert_eq!(from_json.coefficients().len(), 9);
    assert!((from_json.coefficient("sin(2t)*cos(x)").unwrap().value + 0.152).abs() < 1e-3);
}
