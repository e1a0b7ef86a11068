//! The weak form, the bootstrap and the noise correction: exact manufactured cases, the paper's
//! data set, determinism, and the effect of the correction on a noisy simulated record.
use circle_signal::SampleClock;
use hb_basis::{BasisKind, Domain, Harmonic, Hat, Polynomial};
use hb_model::{Forcing, Harmonics, IdentifiedModel, ModelForm};
use hb_solve::{AssemblyError, FitModel, LstsqError};
use hb_solve::{
    BootstrapParams, IdentifyParams, NoiseCorrection, QrSolver, ResampleBlock, SolveError, SvdSolver,
    WeakForm, assemble, assemble_weak, bootstrap, estimate_noise_sigma, identify, identify_from_source,
};
use pendulum_sim::observe::Encoder;
use pendulum_sim::{Pendulum, SimulationConfig, Tolerances, simulate};
use upo_search::{CloseReturns, OrbitSource, Windows};

use crate::common::{read_paper_dataset, truth};

fn max_error<B: hb_basis::Basis>(m: &IdentifiedModel<B>) -> f64 {
    truth()
        .coefficients()
        .iter()
        .map(|t| (m.coefficient(&t.name).unwrap().value - t.value).abs())
        .fold(0.0, f64::max)
}

/// What an encoder with Gaussian noise of `sigma` rad and seed `seed` reports of `x`.
fn with_noise(x: &[f64], sigma: f64, seed: u64) -> Vec<f64> {
    Encoder::seeded(seed).with_noise(sigma).unwrap().observe(x)
}

// ---------------------------------------------------------------------------------------------
// Exact manufactured cases

/// `x'' + c x' + k x + F_c cos(W t) + F_s sin(W t) = 0` on a clock with forcing period 0.5 s:
/// the periodic response plus a decaying free oscillation, so that no window closes.
fn linear_transient() -> (SampleClock, Vec<f64>, [f64; 4]) {
    let clock = SampleClock::new(0.5, 40).unwrap().with_start_time(0.37).unwrap();
    let w = clock.drive_angular_frequency();
    let (c, k, fc, fs) = (0.1 * w, 2.3 * w * w, -3.0 * w * w, 1.2 * w * w);
    // Particular solution X cos + Y sin of x'' + c x' + k x = −F_c cos − F_s sin.
    let (d, e) = (k - w * w, c * w);
    let det = d * d + e * e;
    let (x_amp, y_amp) = ((-fc * d + fs * e) / det, (-fs * d - fc * e) / det);
    let wd = (k - c * c / 4.0).sqrt();
    let x = (0..=12 * 40)
        .map(|n| {
            let t = clock.time(n);
            let free = (-0.5 * c * (t - 0.37)).exp() * (0.8 * (wd * t).cos() - 0.5 * (wd * t).sin());
            x_amp * (w * t).cos() + y_amp * (w * t).sin() + free
        })
        .collect();
    (clock, x, [c, k, fc, fs])
}

#[test]
fn non_periodic_windows_of_a_linear_oscillator_are_exact() {
    let (clock, x, want) = linear_transient();
    let windows = Windows::builder(&SampleClock::nondimensional(40).unwrap())
        .domain(Domain::Line)
        .build()
        .unwrap();
    let segments = windows.segments(&x).unwrap();
    // Not one window closes: the free oscillation is still there.
    assert!(segments.iter().all(|s| s.error() > 1e-3), "{segments:?}");
    let form = ModelForm::externally_forced(Forcing::Identified);
    for (p, harmonics, tol) in [
        (4, WeakForm::DEFAULT_HARMONICS, 1e-6),
        (8, Harmonics::Fixed(10), 1e-9),
    ] {
        let params = IdentifyParams::builder(clock)
            .form(form.clone())
            .harmonics(harmonics)
            .build()
            .unwrap();
        let m = identify(
            Polynomial::new(1).unwrap(),
            &x,
            &segments,
            &params,
            &WeakForm::new(p).unwrap(),
            &QrSolver::default(),
        )
        .unwrap();
        let got = [
            m.damping(),
            m.coefficient("x").unwrap().value,
            m.coefficient("cos(t)").unwrap().value,
            m.coefficient("sin(t)").unwrap().value,
        ];
        for (name, (g, w)) in ["c", "k", "F_c", "F_s"].iter().zip(got.iter().zip(want)) {
            assert!((g - w).abs() < tol * w.abs(), "p = {p}: {name} = {g}, want {w}");
        }
        // The equations hold to quadrature accuracy: a tiny residual against |rhs|.
        let s = m.summary().unwrap();
        assert_eq!(s.segments, segments.len());
        assert!(s.residual_rms < 1e-5 * want[1], "{}", s.residual_rms);
    }

    // Known forcing: moved to the right-hand side, same c and k.
    let known = ModelForm::externally_forced(Forcing::Known {
        cos: want[2],
        sin: want[3],
    });
    let params = IdentifyParams::builder(clock).form(known).build().unwrap();
    let m = identify(
        Polynomial::new(1).unwrap(),
        &x,
        &segments,
        &params,
        &WeakForm::new(8).unwrap(),
        &QrSolver::default(),
    )
    .unwrap();
    assert!((m.damping() - want[0]).abs() < 1e-8 * want[0]);
    assert!((m.coefficient("x").unwrap().value - want[1]).abs() < 1e-8 * want[1]);
}

/// The weak form of an oscillation without forcing, on the circle: `x'' + c x' + q sin x = 0`
/// integrated at tight tolerance from a large swing, windows laid over the decaying motion.
#[test]
fn unforced_pendulum_on_the_circle() {
    // A pendulum with f = 0: the forcing terms of the model must come out zero.
    let pendulum = Pendulum::new(0.0, 0.05, 0.9).unwrap();
    let cfg = SimulationConfig::paper()
        .with_samples(40 * 30)
        .unwrap()
        .with_samples_per_period(40)
        .unwrap()
        .with_transient_periods(0)
        .with_initial(0.5, 3.0)
        .unwrap()
        .with_tolerances(Tolerances::new(1e-13, 1e-14).unwrap());
    let x = simulate(&pendulum, &cfg).unwrap().wrapped();
    let clock = SampleClock::nondimensional(40).unwrap();
    let params = IdentifyParams::builder(clock)
        .harmonics(Harmonics::Fixed(6))
        .build()
        .unwrap();
    let windows = Windows::builder(&SampleClock::nondimensional(40).unwrap())
        .periods(3)
        .step(20)
        .build()
        .unwrap();
    let m = identify_from_source(
        Harmonic::new(1).unwrap(),
        &x,
        &windows,
        &params,
        &WeakForm::new(8).unwrap(),
        &SvdSolver::default(),
    )
    .unwrap();
    let want = pendulum_sim::truth::pendulum_model::<Harmonic>(&pendulum).unwrap();
    for (c, w) in m.coefficients().iter().zip(want.coefficients()) {
        assert_eq!(c.name, w.name);
        let w = w.value;
        assert!((c.value - w).abs() < 1e-7, "{}: {} vs {w}", c.name, c.value);
    }
    // It starts whirling (3 rad/s from 0.5 rad) and ends swinging.
    assert!(m.summary().unwrap().whirling_segments > 0);
}

// ---------------------------------------------------------------------------------------------
// The paper's data set

#[test]
fn paper_dataset_with_the_defaults() {
    let (t0, x) = read_paper_dataset();
    let clock = crate::common::paper_clock(t0);
    let windows = Windows::new(&SampleClock::nondimensional(25).unwrap()).unwrap();
    let segments = windows.segments(&x).unwrap();
    assert_eq!(segments.len(), 1197);
    let params = IdentifyParams::builder(clock)
        .harmonics(WeakForm::DEFAULT_HARMONICS)
        .build()
        .unwrap();
    let basis: BasisKind = Harmonic::new(1).unwrap().into();
    let m = identify(
        basis,
        &x,
        &segments,
        &params,
        &WeakForm::default(),
        &QrSolver::default(),
    )
    .unwrap();
    assert!(max_error(&m) < 1e-5, "{:?}", m.coefficients());
    let s = m.summary().unwrap();
    assert_eq!((s.segments, s.rows, s.unknowns), (1197, 1197 * 13, 7));
    assert!(s.whirling_segments > 0 && s.whirling_segments < s.segments);

    // By hand: 2-period windows and 16 harmonics.
    let segments = Windows::builder(&SampleClock::nondimensional(25).unwrap())
        .periods(2)
        .build()
        .unwrap()
        .segments(&x)
        .unwrap();
    assert_eq!(segments.len(), 1198);
    let params = IdentifyParams::builder(clock)
        .harmonics(Harmonics::Fixed(16))
        .build()
        .unwrap();
    let m = identify(
        basis,
        &x,
        &segments,
        &params,
        &WeakForm::default(),
        &QrSolver::default(),
    )
    .unwrap();
    assert!(max_error(&m) < 1e-7, "{:?}", m.coefficients());
}

// ---------------------------------------------------------------------------------------------
// Bootstrap

#[test]
fn bootstrap_is_deterministic_and_brackets_the_estimate() {
    let (t0, x) = read_paper_dataset();
    let x = with_noise(&x[..250 * 25 + 1], 0.05, 3);
    let clock = crate::common::paper_clock(t0);
    let params = IdentifyParams::builder(clock)
        .harmonics(WeakForm::DEFAULT_HARMONICS)
        .build()
        .unwrap();
    let basis = Harmonic::new(1).unwrap();
    let segments = Windows::new(&SampleClock::nondimensional(25).unwrap())
        .unwrap()
        .segments(&x)
        .unwrap();
    let system = assemble_weak(&basis, &x, &segments, &params, &WeakForm::default()).unwrap();
    let bp = BootstrapParams::builder()
        .resamples(200)
        .seed(42)
        .build()
        .unwrap();
    let solver = QrSolver::default();
    let a = bootstrap(&system, &solver, &bp).unwrap();
    let b = bootstrap(&system, &solver, &bp).unwrap();
    assert_eq!(a, b);
    // The same on one thread: streams are per resample, not per worker.
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    assert_eq!(one.install(|| bootstrap(&system, &solver, &bp).unwrap()), a);
    let other = bootstrap(
        &system,
        &solver,
        &BootstrapParams::builder()
            .resamples(200)
            .seed(43)
            .build()
            .unwrap(),
    )
    .unwrap();
    assert_ne!(a, other);

    // Runs of Politis and White's length for windows that share each sample 3-fold: 248 windows
    // of 3 periods give 7 (more than the 3 that cover one window).
    assert_eq!(segments.len(), 248);
    assert_eq!((a.resamples, a.failed, a.block, a.level), (200, 0, 7, 0.95));
    let model = IdentifiedModel::fit(basis, &params, &system, &solver).unwrap();
    for (iv, c) in a.intervals.iter().zip(model.coefficients()) {
        assert_eq!(iv.name, c.name);
        assert_eq!(iv.estimate, c.value);
        assert!(iv.contains(iv.estimate), "{iv:?}");
        assert!(iv.upper - iv.lower > 0.0 && iv.std_error > 0.0, "{iv:?}");
        // The interval is a few bootstrap standard errors wide (about 3.9 for a normal law).
        let width = (iv.upper - iv.lower) / iv.std_error;
        assert!((3.0..5.0).contains(&width), "{iv:?}: {width}");
    }
    // Drawing windows one by one ignores their overlap: narrower intervals.
    let single = bootstrap(
        &system,
        &solver,
        &BootstrapParams::builder()
            .resamples(200)
            .seed(42)
            .block(ResampleBlock::Segments(1))
            .build()
            .unwrap(),
    )
    .unwrap();
    assert_eq!(single.block, 1);
}

#[test]
fn bootstrap_of_orbit_segments() {
    let (t0, x) = read_paper_dataset();
    let x = &x[..600 * 25];
    let clock = crate::common::paper_clock(t0);
    let params = IdentifyParams::builder(clock).build().unwrap();
    let basis = Harmonic::new(1).unwrap();
    let segments = CloseReturns::builder(&SampleClock::nondimensional(25).unwrap(), 5)
        .build()
        .unwrap()
        .segments(x)
        .unwrap();
    let system = assemble(&basis, x, &segments, &params).unwrap();
    let bp = BootstrapParams::builder().resamples(100).build().unwrap();
    let boot = bootstrap(&system, &QrSolver::default(), &bp).unwrap();
    for (iv, t) in boot.intervals.iter().zip(truth().coefficients()) {
        let (name, truth) = (&t.name, t.value);
        assert_eq!(&iv.name, name);
        assert!(iv.contains(iv.estimate), "{iv:?}");
        // Every interval is within 0.05 of the truth (the method's bias is a few 1e-3).
        assert!(iv.lower > truth - 0.05 && iv.upper < truth + 0.05, "{iv:?}");
    }
}

// ---------------------------------------------------------------------------------------------
// Noise correction

#[test]
fn noise_correction_removes_the_bias_of_the_trigonometric_terms() {
    let cfg = SimulationConfig::paper()
        .with_samples(25 * 800 + 1)
        .unwrap()
        .with_transient_periods(100)
        .with_initial(0.4, 0.2)
        .unwrap();
    let clean = simulate(&Pendulum::paper(), &cfg).unwrap();
    let t0 = clean.t[0];
    let sigma = 0.2;
    let x = with_noise(&clean.wrapped(), sigma, 17);
    let est = estimate_noise_sigma(&x, Domain::Circle).unwrap();
    assert!((est / sigma - 1.0).abs() < 0.03, "estimated sigma {est}");

    let clock = crate::common::paper_clock(t0);
    let segments = Windows::new(&SampleClock::nondimensional(25).unwrap())
        .unwrap()
        .segments(&x)
        .unwrap();
    let fit = |noise: NoiseCorrection| {
        let params = IdentifyParams::builder(clock)
            .harmonics(WeakForm::DEFAULT_HARMONICS)
            .noise_correction(noise)
            .build()
            .unwrap();
        identify(
            Harmonic::new(1).unwrap(),
            &x,
            &segments,
            &params,
            &WeakForm::default(),
            &QrSolver::default(),
        )
        .unwrap()
    };
    let plain = fit(NoiseCorrection::None);
    let given = fit(NoiseCorrection::Given { sigma });
    let estimated = fit(NoiseCorrection::Estimated);
    // The damping is not rescaled; the trigonometric coefficients are, by e^{−σ²/2}.
    assert!((plain.damping() - given.damping()).abs() < 1e-12 * plain.damping());
    let shrink = (-0.5 * sigma * sigma).exp();
    for name in ["sin(t)*cos(x)", "sin(x)"] {
        let (p, g) = (
            plain.coefficient(name).unwrap().value,
            given.coefficient(name).unwrap().value,
        );
        assert!((g - p * shrink).abs() < 1e-12 * p.abs(), "{name}");
    }
    // The bias of the two large coefficients: about 2 % of them uncorrected.
    let bias = |m: &IdentifiedModel<Harmonic>| {
        ["sin(t)*cos(x)", "sin(x)"]
            .map(|name| (m.coefficient(name).unwrap().value - truth().coefficient(name).unwrap().value).abs())
    };
    let (b_plain, b_given, b_est) = (bias(&plain), bias(&given), bias(&estimated));
    for i in 0..2 {
        assert!(b_plain[i] > 0.02, "{b_plain:?}");
        assert!(b_given[i] < 0.3 * b_plain[i], "{b_given:?} vs {b_plain:?}");
        assert!(b_est[i] < 0.3 * b_plain[i], "{b_est:?} vs {b_plain:?}");
    }
}

#[test]
fn noise_correction_needs_single_harmonics_on_the_circle() {
    let (t0, x) = read_paper_dataset();
    let x = &x[..100 * 25 + 1];
    let clock = crate::common::paper_clock(t0);
    let params = IdentifyParams::builder(clock)
        .harmonics(WeakForm::DEFAULT_HARMONICS)
        .noise_correction(NoiseCorrection::Given { sigma: 0.1 })
        .build()
        .unwrap();
    let segments = Windows::new(&SampleClock::nondimensional(25).unwrap())
        .unwrap()
        .segments(x)
        .unwrap();
    let hat = Hat::new(8).unwrap();
    assert!(matches!(
        assemble_weak(&hat, x, &segments, &params, &WeakForm::default()),
        Err(SolveError::Assembly(
            AssemblyError::NoiseCorrectionUnavailable { .. }
        ))
    ));
    // Both assemblies apply it.
    let basis = Harmonic::new(2).unwrap();
    let plain_params = IdentifyParams::builder(clock)
        .harmonics(WeakForm::DEFAULT_HARMONICS)
        .build()
        .unwrap();
    let a = assemble_weak(&basis, x, &segments, &params, &WeakForm::default()).unwrap();
    let b = assemble_weak(&basis, x, &segments, &plain_params, &WeakForm::default()).unwrap();
    // Column 12 is sin(2x): factor e^{4 σ²/2}.
    let f = (2.0f64 * 0.01).exp();
    assert!((a.matrix()[(3, 12)] - f * b.matrix()[(3, 12)]).abs() < 1e-14);
    assert_eq!(a.matrix()[(3, 0)], b.matrix()[(3, 0)]);
    assert_eq!(a.rhs()[3], b.rhs()[3]);
}

// ---------------------------------------------------------------------------------------------
// Errors

#[test]
fn bad_input_is_refused() {
    let (clock, x, _) = linear_transient();
    let params = IdentifyParams::builder(clock)
        .form(ModelForm::externally_forced(Forcing::Identified))
        .build()
        .unwrap();
    let weak = WeakForm::default();
    let basis = Polynomial::new(1).unwrap();
    let mut segments = Windows::builder(&SampleClock::nondimensional(40).unwrap())
        .domain(Domain::Line)
        .build()
        .unwrap()
        .segments(&x)
        .unwrap();
    let mut bad = x.clone();
    bad[45] = f64::NAN;
    assert!(matches!(
        assemble_weak(&basis, &bad, &segments, &params, &weak),
        Err(SolveError::Assembly(AssemblyError::NonFiniteSample {
            index: 45,
            ..
        }))
    ));
    // Too few windows for four unknowns.
    assert!(matches!(
        assemble_weak(&basis, &x, &segments[..0], &params, &weak),
        Err(SolveError::Lstsq(LstsqError::TooFewOrbits { .. }))
    ));
    // A window that runs past the record.
    segments[0] = crate::common::segment(x.len() - 10, 3, 120, 0.0);
    assert!(matches!(
        assemble_weak(&basis, &x, &segments, &params, &weak),
        Err(SolveError::Assembly(AssemblyError::BadSegment { segment: 0, .. }))
    ));
    // A model of another basis than the system.
    let system = assemble_weak(&basis, &x, &segments[1..], &params, &weak).unwrap();
    assert!(matches!(
        IdentifiedModel::fit(
            Polynomial::new(2).unwrap(),
            &params,
            &system,
            &QrSolver::default()
        ),
        Err(SolveError::Model(hb_model::ModelError::Io(
            hb_model::ModelIoError::ModelMismatch { .. }
        )))
    ));
}
