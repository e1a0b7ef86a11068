//! The whole analysis of one record: records with and without gaps, options checked when set and
//! models before any work, and an identification that fails naming its method and segments.

use circle_signal::{Domain, SampleClock};
use hb_basis::{BasisKind, Harmonic};
use hb_pipeline::pipeline::{
    EmbedOptions, InitialState, Method, ModelSpec, Pipeline, PipelineError, PipelineOptions, Record,
    RecordComparison, SearchOptions, Segments, Stage, ValidationOptions, WindowOptions,
};
use hb_solve::NoiseCorrection;
use pendulum_sim::{SimulationConfig, simulate};

fn clock() -> SampleClock {
    SampleClock::nondimensional(25).unwrap()
}

/// A validation short enough for a test: 20 section points and Lyapunov periods, the record's
/// section over 40 periods.
fn short_validation() -> ValidationOptions {
    ValidationOptions::default()
        .with_section_points(20)
        .unwrap()
        .with_lyapunov_periods(20)
        .unwrap()
        .with_record_comparison(RecordComparison::DelaySection { periods: 40 })
        .unwrap()
}

#[test]
fn a_record_needs_samples_and_whole_periods() {
    assert!(matches!(
        Record::new(&[], clock(), Domain::Circle),
        Err(PipelineError::EmptyRecord)
    ));
    let uneven = SampleClock::from_step(1.0, 0.3).unwrap();
    assert!(matches!(
        Record::new(&[0.0; 10], uneven, Domain::Line),
        Err(PipelineError::Clock(_))
    ));
    let record = Record::new(&[0.0; 10], clock(), Domain::Line).unwrap();
    assert_eq!(record.samples_per_period(), 25);
}

#[test]
fn a_record_with_gaps_is_identified_from_its_pieces() {
    let config = SimulationConfig::paper().with_samples(4_000).unwrap();
    let trajectory = simulate(&pendulum_sim::Pendulum::paper(), &config).unwrap();
    let clock = clock().with_start_time(trajectory.t[0]).unwrap();
    let mut x = trajectory.wrapped();
    // A gap that is not a whole number of forcing periods: the drive's phase must come from the
    // one clock.
    x[1_510..1_617].fill(f64::NAN);
    let pieces = vec![0..1_510, 1_617..4_000];
    assert!(matches!(
        Record::with_pieces(&x, std::iter::once(0..1_511).collect(), clock, Domain::Circle),
        Err(PipelineError::Clock(circle_signal::CircleError::NonFinite {
            index: 1_510,
            ..
        }))
    ));
    assert!(matches!(
        Record::with_pieces(&x, vec![0..10, 5..20], clock, Domain::Circle),
        Err(PipelineError::Clock(circle_signal::CircleError::BadPiece {
            index: 1,
            ..
        }))
    ));
    let record = Record::with_pieces(&x, pieces.clone(), clock, Domain::Circle).unwrap();
    assert_eq!(record.longest_piece().len(), 2_383);
    let basis = BasisKind::from(hb_basis::Harmonic::new(1).unwrap());
    let options = PipelineOptions {
        models: vec![
            ModelSpec::new(Method::Windowed, basis),
            ModelSpec::new(Method::Upo, basis),
        ],
        validation: short_validation(),
        ..PipelineOptions::default()
    };
    let outcome = Pipeline::new(record, options).unwrap().run(|_| {}).unwrap();
    for method in [Method::Windowed, Method::Upo] {
        let segments = outcome.segments.of(method);
        assert!(!segments.is_empty());
        for s in segments {
            assert!(
                pieces
                    .iter()
                    .any(|r| r.contains(&s.start()) && r.contains(&s.closing())),
                "{method}: {}..={}",
                s.start(),
                s.closing()
            );
        }
    }
    let weak = &outcome.models[0].model;
    let truth = [
        ("x'", 0.03),
        ("sin(x)", 1.0 / (0.8333f64 * 0.8333)),
        ("sin(t)*cos(x)", -1.52),
    ];
    for (name, value) in truth {
        let found = weak.coefficient(name).unwrap().value;
        assert!(
            (found - value).abs() < 1e-5 * value.abs(),
            "{name}: {found} vs {value}"
        );
    }
    let section = outcome.validation.record.unwrap();
    assert!(section.points.iter().all(|(a, b)| a.is_finite() && b.is_finite()));
}

#[test]
fn options_are_checked_when_set() {
    let embed = EmbedOptions::default();
    assert!(embed.with_delay(0).is_err() && embed.with_bins(1).is_err());
    assert!(embed.with_max_lag(0).is_err() && embed.with_max_dim(9).is_err());
    assert_eq!(embed.with_delay(5).unwrap().delay(), Some(5));
    let search = SearchOptions::default();
    assert!(matches!(
        search.with_tolerance(0.5),
        Err(PipelineError::Orbits(_))
    ));
    assert!(search.with_max_period(0).is_err() && search.with_dimension(0).is_err());
    assert_eq!(search.with_tolerance(0.1).unwrap().tolerance(), 0.1);
    assert!(WindowOptions::default().with_periods(0).is_err());
    let validation = ValidationOptions::default();
    assert!(matches!(
        validation.with_section_points(0),
        Err(PipelineError::Simulation(_))
    ));
    assert!(validation.with_lyapunov_periods(0).is_err());
    assert!(
        validation
            .with_initial(InitialState::Given { x: f64::NAN, v: 0.0 })
            .is_err()
    );
    assert!(
        validation
            .with_record_comparison(RecordComparison::DelaySection { periods: 0 })
            .is_err()
    );
}

#[test]
fn the_pipeline_checks_its_models_before_any_work() {
    let x = vec![0.0; 100];
    let basis = BasisKind::from(Harmonic::new(1).unwrap());
    let options = PipelineOptions {
        models: vec![
            ModelSpec::new(Method::Upo, basis),
            ModelSpec::new(Method::Windowed, basis)
                .with_noise_correction(NoiseCorrection::Given { sigma: f64::NAN }),
        ],
        ..PipelineOptions::default()
    };
    let record = Record::new(&x, clock(), Domain::Circle).unwrap();
    assert!(matches!(
        Pipeline::new(record, options),
        Err(PipelineError::Solve(_))
    ));
}

#[test]
fn an_identification_that_fails_names_its_method_and_segments() {
    // A chirp never returns within so small a tolerance: no orbit at all.
    let x: Vec<f64> = (0..2_000)
        .map(|n| circle_signal::wrap(1e-3 * (n * n) as f64))
        .collect();
    let basis = BasisKind::from(Harmonic::new(1).unwrap());
    let record = Record::new(&x, clock(), Domain::Circle).unwrap();
    let search = SearchOptions::default().with_tolerance(1e-9).unwrap();
    let pipeline = Pipeline::new(
        record.clone(),
        PipelineOptions {
            search,
            models: vec![ModelSpec::new(Method::Upo, basis)],
            ..PipelineOptions::default()
        },
    )
    .unwrap();
    let segments = Segments {
        catalogue: search.close_returns(&record, 1).unwrap().catalogue(&x).unwrap(),
        windows: None,
    };
    let mut stages = Vec::new();
    let error = pipeline.identify(&segments, |s| stages.push(s)).unwrap_err();
    assert_eq!(
        stages,
        [Stage::Identify {
            model: 0,
            method: Method::Upo
        }]
    );
    let PipelineError::Identification {
        method, segments: n, ..
    } = &error
    else {
        panic!("{error}");
    };
    assert_eq!((*method, *n), (Method::Upo, 0));
    assert!(error.to_string().ends_with("segments (upo)"), "{error}");
    assert!(segments.of(Method::Windowed).is_empty());
}

#[test]
fn a_model_whose_free_run_cannot_go_on_is_named_by_its_validation() {
    let config = SimulationConfig::paper().with_samples(4_000).unwrap();
    let trajectory = simulate(&pendulum_sim::Pendulum::paper(), &config).unwrap();
    let clock = clock().with_start_time(trajectory.t[0]).unwrap();
    let x = trajectory.wrapped();
    let record = Record::new(&x, clock, Domain::Circle).unwrap();
    let basis = BasisKind::from(Harmonic::new(1).unwrap());
    let options = PipelineOptions {
        models: vec![ModelSpec::new(Method::Windowed, basis)],
        validation: short_validation(),
        ..PipelineOptions::default()
    };
    let pipeline = Pipeline::new(record, options).unwrap();
    let embedded = pipeline.embed().unwrap();
    let segments = pipeline.segments(&embedded).unwrap();
    let mut models = pipeline.identify(&segments, |_| {}).unwrap();
    assert!(
        pipeline
            .validate(&embedded, &models, |_| {})
            .unwrap()
            .all()
            .is_ok()
    );
    // x'' − 50 x' + ... = 0: the velocity grows as e^(50 t) until no step can follow it.
    let model = &models[0].model;
    let coefficients = model
        .coefficients()
        .iter()
        .map(|c| hb_model::Coefficient {
            value: if c.name == "x'" { -50.0 } else { c.value },
            ..c.clone()
        })
        .collect();
    models[0].model = hb_model::IdentifiedModel::from_coefficients(
        *model.basis(),
        model.form().clone(),
        model.drive_angular_frequency(),
        coefficients,
        None,
    )
    .unwrap();
    models[0].warning = Some("the library does not describe the record".into());
    // The model's own failure, in its place: the validation itself goes through.
    let mut validations = pipeline.validate(&embedded, &models, |_| {}).unwrap();
    assert_eq!(validations.models.len(), 1);
    let error = validations.models.remove(0).unwrap_err();
    let PipelineError::Validation { method, warning, .. } = &error else {
        panic!("{error}");
    };
    assert_eq!(*method, Method::Windowed);
    assert_eq!(
        warning.as_deref(),
        Some("the library does not describe the record")
    );
    assert_eq!(
        error.to_string(),
        "the model of the windowed method cannot be run freely, as its validation does (its identification \
         warned: the library does not describe the record)"
    );
    // The run's own error is its source, not repeated in the message.
    let source = std::error::Error::source(&error).expect("the run's error");
    assert!(
        source.downcast_ref::<pendulum_sim::SimError>().is_some(),
        "{source}"
    );
}
