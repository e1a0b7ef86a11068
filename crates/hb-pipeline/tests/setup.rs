//! One identification of the pipeline: a method, a basis and the settings of the fit on the
//! record's clock, identifying as hb-solve does, its steps, term selection and its errors.

use circle_signal::SampleClock;
use hb_basis::{BasisKind, Harmonic, Hat};
use hb_model::{Forcing, Harmonics, ModelForm};
use hb_pipeline::pipeline::{IdentifyStep, Method, ModelSpec};
use hb_solve::{
    BootstrapParams, IdentifyParams, LstsqError, NoiseCorrection, QrSolver, SelectParams, SolveError,
    SvdSolver, WeakForm, identify,
};
use pendulum_sim::{Pendulum, SimulationConfig, simulate};
use upo_search::{CloseReturns, Windows};

fn record() -> (Vec<f64>, SampleClock) {
    let config = SimulationConfig::paper().with_samples(4_000).unwrap();
    let trajectory = simulate(&Pendulum::paper(), &config).unwrap();
    let clock = SampleClock::nondimensional(25)
        .unwrap()
        .with_start_time(trajectory.t[0])
        .unwrap();
    (trajectory.wrapped(), clock)
}

#[test]
fn a_setup_identifies_exactly_as_hb_solve_does() {
    let (x, clock) = record();
    let orbits = CloseReturns::new(&clock, 5).unwrap().search(&x).unwrap();
    let windows = Windows::new(&clock).unwrap().windows(&x).unwrap();
    for (method, segments) in [(Method::Upo, &orbits), (Method::Windowed, &windows)] {
        for basis in [
            BasisKind::from(Harmonic::new(1).unwrap()),
            BasisKind::from(Hat::new(8).unwrap()),
        ] {
            let ours = ModelSpec::new(method, basis)
                .setup(&clock)
                .unwrap()
                .identify(&x, segments)
                .unwrap();
            let assembly = method.assembly(WeakForm::default());
            let params = IdentifyParams::builder(clock)
                .harmonics(assembly.default_harmonics())
                .build()
                .unwrap();
            let theirs = identify(
                basis,
                &x,
                segments,
                &params,
                assembly.as_ref(),
                &QrSolver::default(),
            )
            .unwrap();
            assert_eq!(ours.model, theirs, "{method} {basis}");
            assert!(ours.intervals.is_none());
        }
    }
}

#[test]
fn steps_are_reported_in_order_and_the_bootstrap_only_when_asked() {
    let (x, clock) = record();
    let orbits = CloseReturns::new(&clock, 5).unwrap().search(&x).unwrap();
    let basis = BasisKind::from(Harmonic::new(1).unwrap());
    let mut steps = Vec::new();
    let plain = ModelSpec::new(Method::Upo, basis).setup(&clock).unwrap();
    plain
        .identify_with_progress(&x, &orbits, |s| steps.push(s))
        .unwrap();
    assert_eq!(steps, [IdentifyStep::Assemble, IdentifyStep::Solve]);
    steps.clear();
    let bootstrap = BootstrapParams::builder().resamples(50).build().unwrap();
    let with = ModelSpec::new(Method::Upo, basis)
        .with_solver(Box::new(SvdSolver::default()))
        .with_bootstrap(bootstrap)
        .setup(&clock)
        .unwrap();
    let id = with
        .identify_with_progress(&x, &orbits, |s| steps.push(s))
        .unwrap();
    assert_eq!(
        steps,
        [
            IdentifyStep::Assemble,
            IdentifyStep::Solve,
            IdentifyStep::Bootstrap
        ]
    );
    assert_eq!(id.intervals.unwrap().resamples, 50);
    assert_eq!(id.model.summary().unwrap().solver, "svd");
}

/// Selection from the default model with two drive harmonics (11 candidates) keeps exactly
/// the paper pendulum's three terms by either method, refits them alone (the same model as
/// asking for those terms), reports the selection step and bootstraps the kept terms only.
#[test]
fn selection_keeps_the_true_terms_and_refits_them_alone() {
    let (x, clock) = record();
    let orbits = CloseReturns::new(&clock, 5).unwrap().search(&x).unwrap();
    let windows = Windows::new(&clock).unwrap().windows(&x).unwrap();
    let basis = BasisKind::from(Harmonic::new(1).unwrap());
    let library = ModelForm::parametric().with_drive_harmonics(2);
    for (method, segments) in [(Method::Upo, &orbits), (Method::Windowed, &windows)] {
        let mut steps = Vec::new();
        let id = ModelSpec::new(method, basis)
            .with_form(library.clone())
            .with_selection(SelectParams::default())
            .with_bootstrap(BootstrapParams::builder().resamples(50).build().unwrap())
            .setup(&clock)
            .unwrap()
            .identify_with_progress(&x, segments, |s| steps.push(s))
            .unwrap();
        assert_eq!(
            steps,
            [
                IdentifyStep::Assemble,
                IdentifyStep::Select,
                IdentifyStep::Solve,
                IdentifyStep::Bootstrap
            ]
        );
        let selection = id.selection.as_ref().unwrap();
        assert_eq!(selection.library.len(), 11);
        assert_eq!(selection.library.names(), hb_model::term_names(&basis, &library));
        let kept = ["x'", "sin(t)*cos(x)", "sin(x)"];
        assert_eq!(selection.kept.names(), kept, "{method}: {:?}", selection.outcome);
        assert_eq!(selection.outcome.dropped.len(), 8);
        let names: Vec<&str> = id.model.coefficients().iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, kept);
        assert_eq!(id.intervals.as_ref().unwrap().intervals.len(), 3);
        // The refit is the fit of the kept terms asked for by name.
        let direct = ModelSpec::new(method, basis)
            .with_form(ModelForm::from_terms(selection.kept.clone()))
            .setup(&clock)
            .unwrap()
            .identify(&x, segments)
            .unwrap();
        assert!(direct.selection.is_none());
        for (a, b) in id.model.coefficients().iter().zip(direct.model.coefficients()) {
            assert_eq!(a.name, b.name);
            assert!((a.value - b.value).abs() <= 1e-12 * b.value.abs(), "{a:?} {b:?}");
        }
        assert_eq!(id.quality.explained, direct.quality.explained);
    }
}

/// Selection needs folds of segments: one segment is an error, and a library with a term
/// twice over (a preset's linear stiffness) is refused when the setup is made.
#[test]
fn selection_errors_are_typed() {
    let (x, clock) = record();
    let windows = Windows::new(&clock).unwrap().windows(&x).unwrap();
    let basis = BasisKind::from(Harmonic::new(1).unwrap());
    let setup = ModelSpec::new(Method::Windowed, basis)
        .with_selection(SelectParams::default())
        .setup(&clock)
        .unwrap();
    assert!(setup.selection().is_some());
    assert!(matches!(
        setup.identify(&x, &windows[..1]),
        Err(SolveError::Lstsq(LstsqError::TooFewOrbits { .. }))
    ));
    let line = BasisKind::from(hb_basis::Polynomial::new(3).unwrap());
    let stiff = ModelForm::externally_forced(Forcing::Identified).with_linear_stiffness();
    assert!(matches!(
        ModelSpec::new(Method::Windowed, line)
            .with_form(stiff)
            .with_selection(SelectParams::default())
            .setup(&clock),
        Err(SolveError::Model(hb_model::ModelError::Term(
            hb_model::TermError::InvalidForm { .. }
        )))
    ));
}

#[test]
fn bad_settings_fail_when_set_or_on_the_clock() {
    let basis = BasisKind::from(Harmonic::new(1).unwrap());
    assert!(matches!(
        ModelSpec::new(Method::Upo, basis).with_harmonics(Harmonics::Fixed(0)),
        Err(SolveError::Model(_))
    ));
    let spec =
        ModelSpec::new(Method::Upo, basis).with_noise_correction(NoiseCorrection::Given { sigma: -1.0 });
    assert!(matches!(
        spec.setup(&SampleClock::nondimensional(25).unwrap()),
        Err(SolveError::InvalidParameter {
            name: "noise sigma",
            ..
        })
    ));
    assert_eq!(Method::Upo.to_string(), "upo");
    assert_eq!(Method::Windowed.name(), "windowed");
}
