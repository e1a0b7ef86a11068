//! General terms: lists of terms as written, the true systems with friction, drag, a second drive
//! harmonic and a velocity-dependent stiffness identified by both methods, models with general
//! terms evaluated, saved and read, and models saved before general terms read back.
use hb_solve::AssemblyError;
use std::f64::consts::TAU;

use circle_signal::{Domain, SampleClock, Segment, wrap};
use hb_basis::{BasisKind, Harmonic, Polynomial};
use hb_model::{IdentifiedModel, ModelForm, TermList, TermSpec};
use hb_solve::{
    Assembly, BootstrapParams, FiniteDifferences, HarmonicBalance, IdentifyParams, NoiseCorrection, QrSolver,
    SolveError, WeakForm, bootstrap, build_system, identify,
};
use pendulum_sim::{SecondOrderSystem, SimulationConfig, simulate};
use proptest::prelude::*;
use proptest::test_runner::RngSeed;
use upo_search::{CloseReturns, OrbitSource, Windows};

/// The paper's pendulum with Coulomb friction, quadratic drag and a second drive harmonic of a
/// tenth of the first: `x'' + 0.02 x' + 0.03 sign(x') + 0.01 x'|x'| + (1/r²) sin x
/// − 1.52 sin(t) cos x − 0.152 sin(2t) cos x = 0`.
const PENDULUM: &str = "x', sign(x'), x'*|x'|, {1, cos(t), sin(t), cos(2t), sin(2t)}*{cos(x), sin(x)}";

fn pendulum_values() -> Vec<f64> {
    let q = 1.0 / (0.8333f64 * 0.8333);
    vec![
        0.02, 0.03, 0.01, 0.0, q, 0.0, 0.0, -1.52, 0.0, 0.0, 0.0, -0.152, 0.0,
    ]
}

fn pendulum() -> IdentifiedModel {
    let form = ModelForm::from_terms(TermList::parse(PENDULUM).unwrap());
    IdentifiedModel::new(Harmonic::new(1).unwrap().into(), form, 1.0, &pendulum_values()).unwrap()
}

/// A chaotic Duffing oscillator whose damping grows with the displacement:
/// `x'' + 0.2 x' + 0.05 x² x' − x + x³ = 0.5 cos(1.2 t)`.
const DUFFING: &str = "x', x^2*x', x, x^3, cos(t), sin(t)";
const DUFFING_VALUES: [f64; 6] = [0.2, 0.05, -1.0, 1.0, -0.5, 0.0];

fn duffing() -> IdentifiedModel {
    let form = ModelForm::from_terms(TermList::parse(DUFFING).unwrap());
    IdentifiedModel::new(Polynomial::new(3).unwrap().into(), form, 1.2, &DUFFING_VALUES).unwrap()
}

/// `periods` forcing periods of `system` at `p` samples per period: the clock and the record
/// (wrapped on the circle).
fn record(system: &IdentifiedModel, p: usize, periods: usize) -> (SampleClock, Vec<f64>) {
    let period = TAU / system.drive_angular_frequency();
    let config = SimulationConfig::paper()
        .with_drive_period(period)
        .unwrap()
        .with_samples_per_period(p)
        .unwrap()
        .with_samples(p * periods)
        .unwrap();
    let trajectory = simulate(system, &config).unwrap();
    let clock = SampleClock::new(period, p)
        .unwrap()
        .with_start_time(trajectory.t[0])
        .unwrap();
    let x = match system.domain() {
        Domain::Circle => trajectory.wrapped(),
        Domain::Line => trajectory.theta,
    };
    (clock, x)
}

/// The angle through an encoder of 4096 counts per turn.
fn encoder(x: &[f64]) -> Vec<f64> {
    let q = TAU / 4096.0;
    x.iter().map(|&v| wrap((v / q).round() * q)).collect()
}

/// Identifies `truth`'s own terms from `x` by `method` on `segments`.
fn identified(
    truth: &IdentifiedModel,
    clock: SampleClock,
    x: &[f64],
    segments: &[Segment],
    method: &dyn Assembly,
) -> IdentifiedModel {
    let params = IdentifyParams::builder(clock)
        .form(truth.form().clone())
        .harmonics(method.default_harmonics())
        .build()
        .unwrap();
    identify(*truth.basis(), x, segments, &params, method, &QrSolver::default()).unwrap()
}

/// The largest relative error of the nonzero coefficients, and the largest absolute value of the
/// zero ones.
fn errors(truth: &IdentifiedModel, model: &IdentifiedModel) -> (f64, f64) {
    let (mut rel, mut abs) = (0.0f64, 0.0f64);
    for (t, m) in truth.coefficients().iter().zip(model.coefficients()) {
        assert_eq!(t.name, m.name);
        if t.value == 0.0 {
            abs = abs.max(m.value.abs());
        } else {
            rel = rel.max(((m.value - t.value) / t.value).abs());
        }
    }
    (rel, abs)
}

/// The pendulum's record at 25 samples per period over 1200 periods, simulated once for the tests
/// that share it.
fn pendulum_at_25() -> &'static (SampleClock, Vec<f64>) {
    static RECORD: std::sync::OnceLock<(SampleClock, Vec<f64>)> = std::sync::OnceLock::new();
    RECORD.get_or_init(|| record(&pendulum(), 25, 1200))
}

fn windows(clock: &SampleClock, domain: Domain, x: &[f64]) -> Vec<Segment> {
    Windows::builder(clock)
        .domain(domain)
        .build()
        .unwrap()
        .segments(x)
        .unwrap()
}

fn orbits(clock: &SampleClock, domain: Domain, x: &[f64], tolerance: f64) -> Vec<Segment> {
    let p = clock.require_whole().unwrap();
    CloseReturns::builder(clock, (5 * p).div_ceil(25))
        .domain(domain)
        .tolerance(tolerance)
        .build()
        .unwrap()
        .segments(x)
        .unwrap()
}

// ---------------------------------------------------------------------------------------------
// The true systems identified

/// Friction, drag and a second drive harmonic at 490 samples per period, exact and through a
/// 4096-count encoder, by the weak form: every coefficient (measured: 1.2e-3 and 1.6e-3 relative
/// on `x'`, the worst; the zero ones below 1e-5).
#[test]
fn the_pendulum_with_friction_drag_and_a_second_harmonic_at_490_per_period() {
    let truth = pendulum();
    let (clock, x) = record(&truth, 490, 300);
    for (angle, x) in [("exact", x.clone()), ("4096 counts", encoder(&x))] {
        let model = identified(
            &truth,
            clock,
            &x,
            &windows(&clock, Domain::Circle, &x),
            &WeakForm::default(),
        );
        let (rel, abs) = errors(&truth, &model);
        assert!(rel < 4e-3 && abs < 5e-5, "{angle}: {rel:e}, {abs:e}");
    }
}

/// The same at 25 samples per period over 1200 periods, the paper's sampling: 2.6e-2 relative on
/// `x'` measured, exact or quantised (1.7e-2 on `x'*|x'|`, 7e-3 on `sign(x')`): at 12 harmonics
/// per period the velocity series misses the kinks that the friction puts into `x'`, and the
/// three nearly collinear functions of `x'` pass the error to the smallest coefficient. The other
/// terms are within 3e-4.
#[test]
fn the_pendulum_with_friction_drag_and_a_second_harmonic_at_25_per_period() {
    let truth = pendulum();
    let (clock, x) = pendulum_at_25();
    let clock = *clock;
    for (angle, x) in [("exact", x.clone()), ("4096 counts", encoder(x))] {
        let model = identified(
            &truth,
            clock,
            &x,
            &windows(&clock, Domain::Circle, &x),
            &WeakForm::default(),
        );
        let (rel, abs) = errors(&truth, &model);
        assert!(rel < 3e-2 && abs < 5e-4, "{angle}: {rel:e}, {abs:e}");
        // The terms that do not depend on x' are within 1e-3.
        for (t, m) in truth.coefficients().iter().zip(model.coefficients()).skip(3) {
            assert!(
                (m.value - t.value).abs() < 1e-3,
                "{angle} {}: {} vs {}",
                t.name,
                m.value,
                t.value
            );
        }
    }
}

/// The paper's method on the same pendulum: the closure of the orbits (a close return is not a
/// closed orbit) biases every coefficient by about 3e-3, as on the paper's own data; the three
/// nearly collinear functions of x' turn that into errors of their coefficients larger than
/// themselves, while the coefficients of the other terms stay within 1 %.
#[test]
fn the_pendulum_by_harmonic_balance_on_orbits() {
    let truth = pendulum();
    let (clock, x) = pendulum_at_25();
    let segments = orbits(clock, Domain::Circle, x, 0.03);
    let model = identified(&truth, *clock, x, &segments, &HarmonicBalance);
    for (t, m) in truth.coefficients().iter().zip(model.coefficients()).skip(3) {
        assert!(
            (m.value - t.value).abs() < 1e-2,
            "{}: {} vs {}",
            t.name,
            m.value,
            t.value
        );
    }
}

/// The Duffing oscillator with `x^2*x'`: the weak form integrates `x² x'` by parts exactly
/// (measured 1.6e-7 relative at 25 samples per period); the paper's method on its orbits is
/// within 4e-2 (measured), its usual closure bias.
#[test]
fn the_duffing_oscillator_with_a_displacement_dependent_damping() {
    let truth = duffing();
    let (clock, x) = record(&truth, 25, 1200);
    let weak = identified(
        &truth,
        clock,
        &x,
        &windows(&clock, Domain::Line, &x),
        &WeakForm::default(),
    );
    let (rel, abs) = errors(&truth, &weak);
    assert!(rel < 1e-6 && abs < 1e-7, "windowed: {rel:e}, {abs:e}");
    let segments = orbits(&clock, Domain::Line, &x, 0.02);
    assert!(segments.len() > 50, "{} orbits", segments.len());
    let upo = identified(&truth, clock, &x, &segments, &HarmonicBalance);
    let (rel, abs) = errors(&truth, &upo);
    assert!(rel < 6e-2 && abs < 1e-3, "upo: {rel:e}, {abs:e}");
}

/// The finite differences balance any term pointwise, `x'` from the differences: at 490 samples
/// per period the pendulum's coefficients come back within 2.7e-2 relative (measured, on `x'`;
/// the differences straddle the kinks of `x'` at every reversal), the others within 2e-5.
#[test]
fn finite_differences_balance_general_terms() {
    let truth = pendulum();
    let (clock, x) = record(&truth, 490, 100);
    let model = identified(
        &truth,
        clock,
        &x,
        &windows(&clock, Domain::Circle, &x),
        &FiniteDifferences,
    );
    let (rel, abs) = errors(&truth, &model);
    assert!(rel < 4e-2 && abs < 1e-4, "{rel:e}, {abs:e}");
}

/// The default model with two drive harmonics (`--drive-harmonics 2`) on the pendulum with a
/// second drive harmonic and no friction: the preset's layout, the coefficients by the weak form.
#[test]
fn the_preset_with_two_drive_harmonics() {
    let form = ModelForm::parametric().with_drive_harmonics(2);
    let basis: BasisKind = Harmonic::new(1).unwrap().into();
    let names = hb_model::term_names(&basis, &form);
    let q = 1.0 / (0.8333f64 * 0.8333);
    let values: Vec<f64> = names
        .iter()
        .map(|n| match n.as_str() {
            "x'" => 0.03,
            "sin(t)*cos(x)" => -1.52,
            "sin(2t)*cos(x)" => -0.152,
            "sin(x)" => q,
            _ => 0.0,
        })
        .collect();
    let truth = IdentifiedModel::new(basis, form, 1.0, &values).unwrap();
    let (clock, x) = record(&truth, 25, 600);
    let model = identified(
        &truth,
        clock,
        &x,
        &windows(&clock, Domain::Circle, &x),
        &WeakForm::default(),
    );
    let (rel, abs) = errors(&truth, &model);
    assert!(rel < 1e-5 && abs < 1e-5, "{rel:e}, {abs:e}");
}

// ---------------------------------------------------------------------------------------------
// What refuses or handles general terms

#[test]
fn noise_correction_scales_the_functions_of_the_angle_and_refuses_nonlinear_velocity() {
    let truth = pendulum();
    let (clock, x) = record(&truth, 25, 200);
    let segments = windows(&clock, Domain::Circle, &x);
    let params = |terms: &str, noise| {
        IdentifyParams::builder(clock)
            .form(ModelForm::from_terms(TermList::parse(terms).unwrap()))
            .harmonics(WeakForm::DEFAULT_HARMONICS)
            .noise_correction(noise)
            .build()
            .unwrap()
    };
    let basis = Harmonic::new(2).unwrap();
    let sigma = 0.1;
    let terms = "x', sin(x)*x', cos(2x)*x', sin(x), cos(2t)*sin(2x)";
    let plain = build_system(
        &basis,
        &x,
        &segments,
        &params(terms, NoiseCorrection::None),
        &WeakForm::default(),
    )
    .unwrap();
    let corrected = build_system(
        &basis,
        &x,
        &segments,
        &params(terms, NoiseCorrection::Given { sigma }),
        &WeakForm::default(),
    )
    .unwrap();
    // The factor e^{k²σ²/2} of each column: 1 for x', k = 1 for sin(x)*x' and sin(x), k = 2 for
    // the others.
    for (c, k) in [(0, 0.0), (1, 1.0), (2, 2.0), (3, 1.0), (4, 2.0)] {
        let want = (0.5 * k * k * sigma * sigma).exp();
        for r in 0..plain.rows() {
            let (a, b) = (plain.matrix()[(r, c)], corrected.matrix()[(r, c)]);
            assert!(
                (b - want * a).abs() <= 1e-12 * a.abs().max(1e-300),
                "column {c}, row {r}"
            );
        }
    }
    for terms in ["x', sign(x'), sin(x)", "x', x'*|x'|", "cos(t)*x'^3, sin(x)"] {
        assert!(matches!(
            build_system(
                &basis,
                &x,
                &segments,
                &params(terms, NoiseCorrection::Given { sigma }),
                &WeakForm::default()
            ),
            Err(SolveError::Assembly(
                AssemblyError::NoiseCorrectionUnavailable { .. }
            ))
        ));
    }
}

#[test]
fn the_bootstrap_resamples_general_terms() {
    let truth = pendulum();
    let (clock, x) = record(&truth, 25, 400);
    let segments = windows(&clock, Domain::Circle, &x);
    let params = IdentifyParams::builder(clock)
        .form(truth.form().clone())
        .harmonics(WeakForm::DEFAULT_HARMONICS)
        .build()
        .unwrap();
    let system = build_system(truth.basis(), &x, &segments, &params, &WeakForm::default()).unwrap();
    let b = bootstrap(
        &system,
        &QrSolver::default(),
        &BootstrapParams::builder().resamples(100).build().unwrap(),
    )
    .unwrap();
    assert_eq!(b.intervals.len(), truth.coefficients().len());
    for (i, c) in b.intervals.iter().zip(truth.coefficients()) {
        assert_eq!(i.name, c.name);
        assert!(i.lower <= i.estimate && i.estimate <= i.upper, "{i:?}");
    }
}

#[test]
fn forms_check_their_terms() {
    let circle: BasisKind = Harmonic::new(1).unwrap().into();
    let list = |s: &str| ModelForm::from_terms(TermList::parse(s).unwrap());
    // A function of the other domain, a function the basis lacks.
    assert!(matches!(
        IdentifiedModel::new(circle, list("x', x^3"), 1.0, &[0.0, 0.0]),
        Err(hb_model::ModelError::Term(hb_model::TermError::TermNotAllowed { ref term, .. })) if term == "x^3"
    ));
    assert!(matches!(
        IdentifiedModel::new(circle, list("x', cos(2x)"), 1.0, &[0.0, 0.0]),
        Err(hb_model::ModelError::Term(hb_model::TermError::TermNotInBasis { ref function, .. })) if function == "cos(2x)"
    ));
    // A list with preset switches, or with the known forcing's own terms.
    let known = hb_model::Forcing::Known { cos: 1.0, sin: 0.0 };
    let clock = SampleClock::nondimensional(25).unwrap();
    for form in [
        list("x'").with_linear_stiffness(),
        list("x'").with_drive_harmonics(2),
        list("x'").with_forcing(hb_model::Forcing::Identified),
        list("x', cos(t)").with_forcing(known),
        ModelForm::parametric().with_drive_harmonics(0),
        ModelForm::parametric().with_drive_harmonics(65),
    ] {
        assert!(IdentifyParams::builder(clock).form(form).build().is_err());
    }
    assert!(
        IdentifyParams::builder(clock)
            .form(list("x', sin(t)*cos(x)").with_forcing(known))
            .build()
            .is_ok()
    );
    // The velocity harmonics are validated like the others.
    assert!(
        IdentifyParams::builder(clock)
            .velocity_harmonics(hb_model::Harmonics::DriveCap(0.5))
            .build()
            .is_err()
    );
}

// ---------------------------------------------------------------------------------------------
// Models with general terms

/// The acceleration is `−Σ c D(t) F(x) V(x')` term by term, and the Jacobian its derivative
/// (central differences away from `x' = 0`, where `sign(x')` jumps).
#[test]
fn a_general_model_evaluates_its_terms() {
    let m = pendulum();
    let values = pendulum_values();
    for i in 0..300 {
        let i = f64::from(i);
        let (t, x, v) = (0.37 * i, -20.0 + 0.21 * i, 3.0 * (0.7 * i).sin() + 0.05);
        let (c, s) = (x.cos(), x.sin());
        let sign = if v > 0.0 { 1.0 } else { -1.0 };
        let want = -(values[0] * v
            + values[1] * sign
            + values[2] * v * v.abs()
            + values[4] * s
            + values[7] * t.sin() * c
            + values[11] * (2.0 * t).sin() * c);
        let got = m.acceleration(t, x, v);
        assert!(
            (got - want).abs() < 1e-13 * (1.0 + want.abs()),
            "({t}, {x}, {v}): {got} vs {want}"
        );
        let e = 1e-6;
        let dx = (m.acceleration(t, x + e, v) - m.acceleration(t, x - e, v)) / (2.0 * e);
        let dv = (m.acceleration(t, x, v + e) - m.acceleration(t, x, v - e)) / (2.0 * e);
        let [jx, jv] = m.jacobian(t, x, v);
        if v.abs() > 1e-3 {
            assert!(
                (jx - dx).abs() < 1e-7 && (jv - dv).abs() < 1e-7,
                "({t}, {x}, {v})"
            );
        }
    }
    assert_eq!(m.damping(), 0.02);
    // The autonomous part and the parametric parts of the first drive harmonic.
    let q = values[4];
    assert!((m.autonomous(0.7) - q * 0.7f64.sin()).abs() < 1e-15);
    let (n, p) = m.parametric(0.7);
    assert!(n.abs() < 1e-15 && (p + 1.52 * 0.7f64.cos()).abs() < 1e-15);
}

#[test]
fn a_general_model_is_saved_with_its_terms() {
    let m = pendulum();
    let json = m.to_json().unwrap();
    assert!(json.contains("\"version\": 4"), "{json}");
    assert!(
        json.contains("\"terms\": [") && json.contains("\"sin(2t)*sin(x)\""),
        "{json}"
    );
    assert_eq!(IdentifiedModel::<BasisKind>::from_json(&json).unwrap(), m);
    let bytes = m.to_bytes().unwrap();
    assert_eq!(IdentifiedModel::<BasisKind>::from_bytes(&bytes).unwrap(), m);
    // Terms that do not match the form are refused.
    let renamed = json.replace("\"sign(x')\": {", "\"x'^3\": {");
    assert!(renamed != json);
    assert!(matches!(
        IdentifiedModel::<BasisKind>::from_json(&renamed),
        Err(hb_model::ModelError::Io(
            hb_model::ModelIoError::ModelMismatch { .. }
        ))
    ));
    let bad_list = json.replace("\"x'*|x'|\",", "\"x'*|x'|*x'\",");
    assert!(bad_list != json && IdentifiedModel::<BasisKind>::from_json(&bad_list).is_err());
}

/// Models saved by format version 2 (before general terms), in JSON and binary, read as they
/// were: the same coefficients and the same equation.
#[test]
fn models_saved_before_general_terms_still_load() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures");
    for name in ["model_v2_hat8_upo", "model_v2_duffing_known_forcing"] {
        let json = std::fs::read_to_string(format!("{dir}/{name}.json")).unwrap();
        assert!(json.contains("\"version\": 2"));
        let from_json = IdentifiedModel::<BasisKind>::from_json(&json).unwrap();
        let bytes = std::fs::read(format!("{dir}/{name}.bin")).unwrap();
        assert_eq!(u32::from_le_bytes(bytes[8..12].try_into().unwrap()), 2);
        let from_bytes = IdentifiedModel::<BasisKind>::from_bytes(&bytes).unwrap();
        assert_eq!(from_json, from_bytes, "{name}");
        assert!(from_json.form().terms().is_none());
        assert_eq!(from_json.form().drive_harmonics(), 1);
        // Written again in the present version, read back the same.
        let again = IdentifiedModel::<BasisKind>::from_bytes(&from_json.to_bytes().unwrap()).unwrap();
        assert_eq!(again, from_json);
    }
    let hat = IdentifiedModel::<BasisKind>::from_json(
        &std::fs::read_to_string(format!("{dir}/model_v2_hat8_upo.json")).unwrap(),
    )
    .unwrap();
    assert!(hat.summary().is_some());
    assert!((hat.damping() - 0.03).abs() < 0.01);
    let duffing = IdentifiedModel::<BasisKind>::from_json(
        &std::fs::read_to_string(format!("{dir}/model_v2_duffing_known_forcing.json")).unwrap(),
    )
    .unwrap();
    // x'' = −(0.3 v + 0.1 x² + x³ − x − 0.5 cos(1.2 t) + 0.25 sin(1.2 t)).
    let (t, x, v): (f64, f64, f64) = (0.4, 0.7, -0.2);
    let want = -(0.3 * v + 0.1 * x * x + x * x * x - x - 0.5 * (1.2 * t).cos() + 0.25 * (1.2 * t).sin());
    assert!((duffing.acceleration(t, x, v) - want).abs() < 1e-14);
}

// ---------------------------------------------------------------------------------------------
// Printing and parsing

fn term_strategy() -> impl Strategy<Value = TermSpec> {
    use hb_model::{DriveFactor, VelocityFactor, XFunction};
    let drive = prop_oneof![
        Just(DriveFactor::One),
        (1u32..=64).prop_map(DriveFactor::Cos),
        (1u32..=64).prop_map(DriveFactor::Sin),
    ];
    let function = prop_oneof![
        Just(None),
        (1u32..=20).prop_map(|k| Some(XFunction::Cos(k))),
        (1u32..=20).prop_map(|k| Some(XFunction::Sin(k))),
        (1u32..=20).prop_map(|n| Some(XFunction::Power(n))),
        (0u32..=40).prop_map(|i| Some(XFunction::Hat(i))),
    ];
    let velocity = prop_oneof![
        Just(VelocityFactor::One),
        Just(VelocityFactor::Linear),
        Just(VelocityFactor::Sign),
        Just(VelocityFactor::Quadratic),
        Just(VelocityFactor::Cubic),
    ];
    (drive, function, velocity)
        .prop_map(|(drive, function, velocity)| TermSpec::of_one(drive, function, velocity))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, rng_seed: RngSeed::Fixed(0x7e2a5), ..ProptestConfig::default() })]

    /// Printing a list of terms and parsing it again gives the same list, and so does its JSON.
    #[test]
    fn printing_then_parsing_is_the_identity(terms in proptest::collection::vec(term_strategy(), 1..12)) {
        let mut distinct: Vec<TermSpec> = Vec::new();
        for t in terms {
            if !distinct.contains(&t) {
                distinct.push(t);
            }
        }
        let list = TermList::new(distinct).unwrap();
        let text = list.to_string();
        prop_assert_eq!(&TermList::parse(&text).unwrap(), &list, "{}", text);
        for t in list.terms() {
            prop_assert_eq!(t.to_string().parse::<TermSpec>().unwrap(), *t);
        }
        let json = serde_json::to_string(&list).unwrap();
        prop_assert_eq!(serde_json::from_str::<TermList>(&json).unwrap(), list);
    }
}

/// A model with dry friction and drag runs through the switching integrator as the simulator's
/// own pendulum with those losses does: the same trajectory, its stops at rest included (with
/// `sign(x')` evaluated as a smooth function the model would chatter about `x' = 0` instead).
#[test]
fn a_model_with_friction_sticks_like_the_rig_pendulum() {
    use pendulum_sim::{Losses, Pendulum};
    let (f, c, r, mu, d) = (0.25, 0.03, 0.8333, 0.2, 0.05);
    let pendulum = Pendulum::new(f, c, r)
        .unwrap()
        .with_losses(Losses::none().with_friction(mu).unwrap().with_drag(d).unwrap());
    let model = IdentifiedModel::new(
        BasisKind::from(hb_basis::Harmonic::new(1).unwrap()),
        ModelForm::from_terms(TermList::parse("x', sign(x'), x'*|x'|, sin(x), sin(t)*cos(x)").unwrap()),
        1.0,
        &[c, mu, d, 1.0 / (r * r), -f],
    )
    .unwrap();
    assert!(model.switches_at_rest() && pendulum.switches_at_rest());
    let config = SimulationConfig::paper()
        .with_samples(2_000)
        .unwrap()
        .with_transient_periods(0)
        .with_initial(1.0, 0.0)
        .unwrap();
    let (a, b) = (
        simulate(&pendulum, &config).unwrap(),
        simulate(&model, &config).unwrap(),
    );
    let stuck = a.omega.iter().filter(|&&v| v == 0.0).count();
    assert!(
        stuck > 10,
        "the pendulum should stop at rest: {stuck} samples at rest"
    );
    assert_eq!(stuck, b.omega.iter().filter(|&&v| v == 0.0).count());
    for (p, q) in a.theta.iter().zip(&b.theta) {
        assert!((p - q).abs() < 1e-7, "{p} vs {q}");
    }
}

/// A preset's terms as a list ([`ModelForm::term_list`]) assemble the preset's system, and the
/// system of some of a list's columns ([`hb_solve::LinearSystem::with_columns`]) is the system of
/// those terms assembled alone, by both methods: what model selection refits.
#[test]
fn a_preset_as_a_list_and_the_system_of_some_columns() {
    let (clock, x) = pendulum_at_25();
    let x = &x[..25 * 200 + 1];
    let segments = windows(clock, Domain::Circle, x);
    let basis: BasisKind = Harmonic::new(1).unwrap().into();
    let preset = ModelForm::parametric().with_drive_harmonics(2);
    let list = preset.term_list(&basis).unwrap();
    assert_eq!(list.names(), hb_model::term_names(&basis, &preset));
    let library = ModelForm::from_terms(TermList::parse(PENDULUM).unwrap());
    let keep = [0usize, 2, 4, 7, 11];
    let kept = TermList::new(
        keep.iter()
            .map(|&i| library.terms().unwrap().terms()[i])
            .collect(),
    )
    .unwrap();
    let methods: [&dyn Assembly; 2] = [&WeakForm::default(), &HarmonicBalance];
    for method in methods {
        let params = |form: ModelForm| {
            IdentifyParams::builder(*clock)
                .form(form)
                .harmonics(method.default_harmonics())
                .build()
                .unwrap()
        };
        let system = |form: ModelForm| build_system(&basis, x, &segments, &params(form), method).unwrap();
        let (a, b) = (
            system(preset.clone()),
            system(ModelForm::from_terms(list.clone())),
        );
        assert_eq!(a.names(), b.names());
        assert_eq!(a.matrix(), b.matrix(), "{}", method.name());
        let whole = system(library.clone());
        let some = whole.with_columns(&keep).unwrap();
        let alone = system(ModelForm::from_terms(kept.clone()));
        assert_eq!(some.names(), alone.names());
        assert_eq!(some.names(), kept.names());
        assert_eq!(some.matrix(), alone.matrix(), "{}", method.name());
        assert_eq!(some.rhs(), alone.rhs());
        assert_eq!(some.blocks(), alone.blocks());
    }
    let whole = build_system(
        &basis,
        x,
        &segments,
        &IdentifyParams::builder(*clock).build().unwrap(),
        &HarmonicBalance,
    )
    .unwrap();
    for bad in [&[][..], &[0, 0], &[whole.unknowns()]] {
        assert!(matches!(
            whole.with_columns(bad),
            Err(SolveError::InvalidParameter {
                name: "column index",
                ..
            })
        ));
    }
    // The linear stiffness of a preset has no name in a list.
    let stiff = ModelForm::externally_forced(hb_model::Forcing::Identified).with_linear_stiffness();
    assert!(matches!(
        stiff.term_list(&Polynomial::new(3).unwrap()),
        Err(hb_model::ModelError::Term(
            hb_model::TermError::InvalidForm { .. }
        ))
    ));
}

/// A model of listed terms may name a few functions of its basis: `x', sin(x)` on `cos(x), sin(x)`.
#[test]
fn a_model_of_fewer_terms_than_basis_functions() {
    let form = ModelForm::from_terms(TermList::parse("x', sin(x)").unwrap());
    let model =
        IdentifiedModel::<BasisKind>::new(Harmonic::new(1).unwrap().into(), form, 1.0, &[0.1, 1.0]).unwrap();
    let back = IdentifiedModel::<BasisKind>::from_json(&model.to_json().unwrap()).unwrap();
    assert_eq!(back.coefficients(), model.coefficients());
    // A preset still needs more coefficients than basis functions.
    assert!(
        IdentifiedModel::<BasisKind>::new(
            Harmonic::new(2).unwrap().into(),
            ModelForm::parametric().without_parametric_terms(),
            1.0,
            &[0.1, 1.0, 0.0]
        )
        .is_err()
    );
}
