//! The identified equation: evaluated, built from a true equation, checked when built, saved and
//! read back, and inconsistent files refused.

use circle_signal::SampleClock;
use hb_basis::{Basis, BasisKind, Harmonic, Hat, Polynomial};
use hb_model::{
    FitSummary, Forcing, Harmonics, IdentifiedModel, MODEL_VERSION, ModelError, ModelForm, ModelIoError,
    TermError,
};
use pendulum_sim::{Pendulum, RecordFrame, SecondOrderSystem, TrueEquation};

/// The true model of `p` on the harmonic basis of order 1 in the paper's layout.
fn true_model<B: Basis + From<Harmonic>>(p: &Pendulum) -> Result<IdentifiedModel<B>, ModelError> {
    p.equation(&RecordFrame::nondimensional())?.model(
        B::from(Harmonic::new(1)?),
        &ModelForm::parametric(),
        1.0,
    )
}

/// The paper's pendulum, x'' + 0.03 x' + (1/0.8333²) sin x − 1.52 sin t cos x = 0.
fn pendulum() -> IdentifiedModel<BasisKind> {
    true_model(&Pendulum::paper()).unwrap()
}

#[test]
fn evaluates_the_pendulum() {
    let m = pendulum();
    let q = 1.0 / (0.8333 * 0.8333);
    let (t, x, v): (f64, f64, f64) = (0.7, 2.1 + 6.0 * std::f64::consts::PI, -0.4);
    let want = -0.03 * v - q * x.sin() + 1.52 * t.sin() * x.cos();
    assert!((m.acceleration(t, x, v) - want).abs() < 1e-12);
    let jx = -q * x.cos() - 1.52 * t.sin() * x.sin();
    let [a, b] = m.jacobian(t, x, v);
    assert!((a - jx).abs() < 1e-12 && (b + 0.03).abs() < 1e-15);
    assert!((m.autonomous(x) - q * x.sin()).abs() < 1e-12);
    let (pc, ps) = m.parametric(x);
    assert!(pc.abs() < 1e-15 && (ps + 1.52 * x.cos()).abs() < 1e-12);
    assert_eq!(m.coefficient("sin(t)*cos(x)").unwrap().value, -1.52);
    assert_eq!(m.damping(), 0.03);
}

/// The true model of a pendulum: the coefficients, bit for bit, by name, and the same
/// equation as the pendulum's own (acceleration and Jacobian at points all over the phase
/// space and the forcing cycle).
#[test]
fn from_pendulum_is_the_pendulum() {
    let pendulums = [
        Pendulum::paper(),
        Pendulum::new(2.5, 0.2, 2f64.sqrt()).unwrap(),
        Pendulum::new(-0.7, -0.05, -3.0).unwrap(),
        Pendulum::new(0.0, 0.0, 1.0).unwrap(),
    ];
    for p in pendulums {
        let m = true_model::<Harmonic>(&p).unwrap();
        assert_eq!(m.basis(), &Harmonic::new(1).unwrap());
        assert_eq!(m.form(), &ModelForm::parametric());
        assert_eq!(m.drive_angular_frequency(), 1.0);
        assert!(m.summary().is_none());
        let want = [
            ("x'", p.c()),
            ("cos(t)*cos(x)", 0.0),
            ("sin(t)*cos(x)", -p.f()),
            ("cos(x)", 0.0),
            ("cos(t)*sin(x)", 0.0),
            ("sin(t)*sin(x)", 0.0),
            ("sin(x)", 1.0 / (p.r() * p.r())),
        ];
        let got: Vec<(&str, f64, f64)> = m
            .coefficients()
            .iter()
            .map(|c| (c.name.as_str(), c.value, c.std_error))
            .collect();
        let want: Vec<(&str, f64, f64)> = want.iter().map(|&(n, v)| (n, v, 0.0)).collect();
        assert_eq!(got, want, "{p:?}");
        for i in 0..200 {
            let i = f64::from(i);
            let (t, x, v) = (0.37 * i, -20.0 + 0.21 * i, 3.0 * (0.7 * i).sin());
            let scale = 1.0 + p.c().abs() * v.abs() + p.f().abs() + 1.0 / (p.r() * p.r());
            let d = m.acceleration(t, x, v) - p.acceleration(t, x, v);
            assert!(d.abs() <= 1e-14 * scale, "{p:?} at ({t}, {x}, {v}): {d:e}");
            let [mx, mv] = m.jacobian(t, x, v);
            let [px, pv] = p.jacobian(t, x, v);
            assert!(
                (mx - px).abs() <= 1e-14 * scale && mv == pv,
                "{p:?} at ({t}, {x}, {v})"
            );
        }
        let kind = true_model::<BasisKind>(&p).unwrap();
        assert_eq!(kind.coefficients(), m.coefficients());
        assert_eq!(kind.basis(), &BasisKind::from(Harmonic::new(1).unwrap()));
    }
    // The paper's, as the tests and the reproduction have always written it.
    let paper = true_model::<Harmonic>(&Pendulum::paper()).unwrap();
    let values: Vec<f64> = paper.coefficients().iter().map(|c| c.value).collect();
    assert_eq!(values, [0.03, 0.0, -1.52, 0.0, 0.0, 0.0, 1.0 / (0.8333 * 0.8333)]);
    // 1/r² overflows.
    assert!(matches!(
        true_model::<Harmonic>(&Pendulum::new(1.0, 0.1, 1e-160).unwrap()),
        Err(ModelError::Io(ModelIoError::NonFiniteModelValue { ref name })) if name == "sin(x)"
    ));
}

#[test]
fn json_and_bytes_round_trip() {
    let m = pendulum();
    let json = m.to_json().unwrap();
    assert!(json.contains("\"cos(t)*cos(x)\""), "{json}");
    assert_eq!(IdentifiedModel::<BasisKind>::from_json(&json).unwrap(), m);
    let bytes = m.to_bytes().unwrap();
    assert_eq!(&bytes[..8], b"HBIDMODL");
    assert_eq!(IdentifiedModel::<BasisKind>::from_bytes(&bytes).unwrap(), m);
}

#[test]
fn rejects_inconsistent_files() {
    let m = pendulum();
    let mut bytes = m.to_bytes().unwrap();
    // Format 5 is a system's: read as one model, it says so.
    bytes[8..12].copy_from_slice(&hb_model::SYSTEM_VERSION.to_le_bytes());
    assert!(matches!(
        IdentifiedModel::<BasisKind>::from_bytes(&bytes),
        Err(ModelError::Io(ModelIoError::SavedSystem))
    ));
    let foreign = hb_model::SYSTEM_VERSION + 1;
    bytes[8..12].copy_from_slice(&foreign.to_le_bytes());
    assert!(matches!(
        IdentifiedModel::<BasisKind>::from_bytes(&bytes),
        Err(ModelError::Io(ModelIoError::UnsupportedVersion {
            found,
            supported: MODEL_VERSION
        })) if found == foreign
    ));
    assert!(matches!(
        IdentifiedModel::<BasisKind>::from_bytes(b"nonsense"),
        Err(ModelError::Io(ModelIoError::BadMagic))
    ));
    // A basis of another size than the coefficients.
    let json = m.to_json().unwrap().replace("\"order\": 1", "\"order\": 2");
    assert!(matches!(
        IdentifiedModel::<BasisKind>::from_json(&json),
        Err(ModelError::Io(ModelIoError::ModelMismatch { .. }))
    ));
    let json = m.to_json().unwrap().replace("\"value\": 0.03", "\"value\": NaN");
    assert!(IdentifiedModel::<BasisKind>::from_json(&json).is_err());
}

/// The paper's pendulum with a fit summary whose residual variance is `variance`.
fn fitted(variance: f64) -> IdentifiedModel<BasisKind> {
    let m = pendulum();
    let summary = FitSummary {
        solver: "qr".to_owned(),
        harmonics: Harmonics::DEFAULT,
        clock: SampleClock::new(std::f64::consts::TAU, 25).unwrap(),
        rows: 100,
        unknowns: 7,
        segments: 3,
        whirling_segments: 0,
        condition: 10.0,
        residual_rms: 1e-3,
        residual_variance: variance,
    };
    IdentifiedModel::from_coefficients(
        *m.basis(),
        m.form().clone(),
        m.drive_angular_frequency(),
        m.coefficients().to_vec(),
        Some(summary),
    )
    .unwrap()
}

/// A binary model whose fit has a non-finite residual variance (found by the fuzz target
/// `model_bytes`): JSON cannot hold it, so it loaded but could not be saved as JSON and read
/// back. Now it does not load.
#[test]
fn a_non_finite_residual_variance_does_not_load() {
    let good = fitted(1e-6);
    assert_eq!(
        IdentifiedModel::<BasisKind>::from_bytes(&good.to_bytes().unwrap()).unwrap(),
        good
    );
    for variance in [f64::NAN, f64::INFINITY] {
        let bytes = fitted(variance).to_bytes().unwrap();
        assert!(matches!(
            IdentifiedModel::<BasisKind>::from_bytes(&bytes),
            Err(ModelError::Io(ModelIoError::NonFiniteModelValue { ref name })) if name == "fit residual_variance"
        ));
    }
}

/// A file may claim a basis of any size: it is refused from the number of coefficients,
/// before a name is made for each of its functions.
#[test]
fn a_basis_larger_than_the_coefficients_is_refused_before_naming_it() {
    let json = pendulum().to_json().unwrap();
    let huge = "\"order\": 1000000000000000";
    for json in [
        json.replace("\"order\": 1", huge),
        json.replace("\"order\": 1", "\"order\": 4"),
        json.replace("{\n      \"order\": 1\n    }", "{\"nodes\": 1000000000000000}")
            .replace("\"harmonic\"", "\"hat\""),
    ] {
        assert!(
            json.contains("000000000000000") || json.contains("\"order\": 4"),
            "{json}"
        );
        match IdentifiedModel::<BasisKind>::from_json(&json) {
            Err(
                e @ ModelError::InvalidParameter {
                    name: "basis size", ..
                },
            ) => {
                assert!(e.to_string().contains("coefficients"), "{e}");
            }
            // A size beyond any basis is refused by the basis as it is read.
            Err(e) if json.contains("000000000000000") => {
                assert!(e.to_string().contains("more than 4096 functions"), "{e}");
            }
            other => panic!("{other:?}"),
        }
    }
}

#[test]
fn construction_checks() {
    let hat: BasisKind = Hat::new(4).unwrap().into();
    assert!(matches!(
        IdentifiedModel::new(hat, ModelForm::parametric(), 1.0, &[0.0; 3]),
        Err(ModelError::Io(ModelIoError::ModelMismatch { .. }))
    ));
    assert!(matches!(
        IdentifiedModel::new(
            hat,
            ModelForm::parametric().with_linear_stiffness(),
            1.0,
            &[0.0; 14]
        ),
        Err(ModelError::Term(TermError::TermNotAllowed { .. }))
    ));
    let line: BasisKind = Polynomial::new(1).unwrap().into();
    let form = ModelForm::externally_forced(Forcing::Known { cos: -1.0, sin: 0.0 });
    let m = IdentifiedModel::new(line, form.clone(), 1.0, &[0.1, 2.0]).unwrap();
    // x'' = −(0.1 v + 2 x − cos t)
    assert!((m.acceleration(0.3, 0.5, 0.2) - (-(0.02 + 1.0 - 0.3f64.cos()))).abs() < 1e-14);
    assert!(IdentifiedModel::new(line, form, 0.0, &[0.1, 2.0]).is_err());
}

/// A system's mass matrix, `[[1, cos(θ1−θ2)], [cos(θ1−θ2), 1]]`, is singular where the angles
/// are equal: found at the first such sample of those asked, in their order, whatever the
/// parallel order of the search; none among samples where it is not.
#[test]
fn the_first_state_where_the_mass_matrix_is_singular_is_found() {
    use hb_basis::Domain;
    use hb_model::{IdentifiedSystem, Names, TermList};
    let names = Names::new(["theta1", "theta2"], Vec::<String>::new()).unwrap();
    let basis = BasisKind::from(Harmonic::new(1).unwrap());
    let equation = |own: usize, terms: &str| {
        let list = TermList::parse_in(terms, &names, own).unwrap();
        IdentifiedModel::new(basis, ModelForm::from_terms(list), 1.0, &[1.0, 2.0]).unwrap()
    };
    let system = IdentifiedSystem::new(
        names.clone(),
        vec![Domain::Circle; 2],
        vec![
            equation(0, "theta2''*cos(theta1-theta2), sin(theta1)"),
            equation(1, "theta1''*cos(theta1-theta2), sin(theta2)"),
        ],
    )
    .unwrap();
    let theta1: Vec<f64> = (0..400).map(|k| 0.01 * k as f64).collect();
    let mut theta2: Vec<f64> = theta1.iter().map(|x| x + 0.5).collect();
    for k in [250, 251, 390] {
        theta2[k] = theta1[k];
    }
    let all: Vec<usize> = (0..400).collect();
    let found = system
        .first_singular(&[&theta1, &theta2], &[all], |k| 10.0 + 0.5 * k as f64)
        .expect("singular where the angles are equal");
    assert_eq!(found.sample, 250);
    assert_eq!(found.q, vec![2.5, 2.5]);
    assert_eq!(found.mass.t, 135.0);
    assert!(found.mass.pivot < 1e-12, "pivot {}", found.mass.pivot);
    assert!(!found.changes_sign);
    let apart: Vec<usize> = (0..250).collect();
    assert_eq!(
        system.first_singular(&[&theta1, &theta2], &[apart], |k| k as f64),
        None
    );
}

/// A mass matrix `[[1 − 1.5 cos θ2]]` (one coordinate, its own acceleration times a function of
/// another's position) vanishes where `cos θ2 = 2/3`: between two states of one path on either
/// side of it, never at one of them, it is found by its determinant's change of sign; between
/// states of two paths (a gap between them) it is not; a matrix whose pivot is a millionth of its
/// scale is refused as nearly singular, one ten times larger is not.
#[test]
fn a_mass_matrix_that_changes_sign_between_states_or_nearly_vanishes_is_found() {
    use hb_basis::Domain;
    use hb_model::{IdentifiedSystem, NEAR_SINGULAR_PIVOT, Names, TermList};
    let names = Names::new(["theta1", "theta2"], Vec::<String>::new()).unwrap();
    let basis = BasisKind::from(Harmonic::new(1).unwrap());
    let system = |c: f64| {
        let equation = |own: usize, terms: &str, coefficients: &[f64]| {
            let list = TermList::parse_in(terms, &names, own).unwrap();
            IdentifiedModel::new(basis, ModelForm::from_terms(list), 1.0, coefficients).unwrap()
        };
        IdentifiedSystem::new(
            names.clone(),
            vec![Domain::Circle; 2],
            vec![
                equation(0, "theta1''*cos(theta2), sin(theta1)", &[c, 1.0]),
                equation(1, "sin(theta2)", &[1.0]),
            ],
        )
        .unwrap()
    };
    let crossing = (2.0f64 / 3.0).acos();
    let theta1 = vec![0.3; 4];
    // Two states on either side of the crossing, then two more beyond it.
    let theta2 = vec![crossing - 0.05, crossing + 0.05, 1.2, 1.4];
    let singular = system(-1.5);
    let found = singular
        .first_singular(&[&theta1, &theta2], &[vec![0, 1, 2, 3]], |k| k as f64)
        .expect("singular between samples 0 and 1");
    assert!(found.changes_sign && found.sample <= 1, "{found:?}");
    assert!(found.mass.pivot > 1e-3, "{found:?}");
    assert_eq!(
        singular.first_singular(&[&theta1, &theta2], &[vec![0], vec![1, 2, 3]], |k| k as f64),
        None
    );
    // 1 + c cos θ2 at θ2 = 0.1 with c = −1/cos(0.1) (1 + ε): a relative pivot of ε.
    let near = |epsilon: f64| {
        system(-(1.0 + epsilon) / 0.1f64.cos())
            .first_singular(&[&[0.3][..], &[0.1][..]], &[vec![0]], |k| k as f64)
    };
    assert!(near(-0.5 * NEAR_SINGULAR_PIVOT).is_some());
    assert!(near(-10.0 * NEAR_SINGULAR_PIVOT).is_none());
}

/// The cap of the harmonics in units of the drive frequency is saved under the name files have
/// always had, and read back from it; a cap below 1 is refused on reading.
#[test]
fn a_harmonic_cap_keeps_its_saved_name() {
    let json = serde_json::to_string(&Harmonics::DriveCap(2.5)).unwrap();
    assert_eq!(json, r#"{"forcing_cap":2.5}"#);
    let back: Harmonics = serde_json::from_str(&json).unwrap();
    assert_eq!(back, Harmonics::DriveCap(2.5));
    assert!(serde_json::from_str::<Harmonics>(r#"{"forcing_cap":0.5}"#).is_err());
    assert_eq!(
        serde_json::from_str::<Harmonics>(r#"{"fixed":4}"#).unwrap(),
        Harmonics::Fixed(4)
    );
}

/// The mass row alone is the row the whole equation writes, bit for bit, whatever functions of
/// the positions the accelerations carry (of the own angle, of both) and whatever the state.
#[test]
fn the_mass_row_alone_is_the_equations_row() {
    use hb_model::{Names, TermList};
    let names = Names::new(["theta1", "theta2"], Vec::<String>::new()).unwrap();
    let basis = BasisKind::from(Harmonic::new(2).unwrap());
    let terms = "theta2''*cos(theta1-theta2), theta2'', theta1''*sin(theta1), \
                 theta2''*sin(theta1+theta2), sin(theta1), sin(theta1-theta2)*theta2'^2, theta1', sin(2t)";
    let list = TermList::parse_in(terms, &names, 0).unwrap();
    let values = [0.7, -0.2, 0.3, 0.05, 9.0, 0.4, 0.1, 1.5];
    let model = IdentifiedModel::new(basis, ModelForm::from_terms(list), 1.3, &values).unwrap();
    for k in 0..500 {
        let k = k as f64;
        let q = [3.0 * (0.37 * k).sin() + 0.2 * k, -2.0 * (0.11 * k).cos()];
        let v = [(0.7 * k).cos() * 4.0, (1.3 * k).sin() * 3.0];
        let sides = [1.0, -1.0];
        for (v, sides) in [([0.0, 0.0], None), (v, None), (v, Some(&sides[..]))] {
            let (mut whole, mut alone) = ([0.0; 2], [7.0; 2]);
            model.equation_at(0.1 * k, &q, &v, sides, &mut whole);
            model.mass_row_at(0.1 * k, &q, &v, sides, &mut alone);
            assert_eq!(whole.map(f64::to_bits), alone.map(f64::to_bits), "state {k}");
            assert_ne!(whole[1], 0.0);
        }
    }
}
