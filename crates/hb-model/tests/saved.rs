//! Models saved by every format version of `hbid identify --save-model` (the repository's
//! `fixtures/`), in JSON and in the compact binary: each still loads, the two forms read the same,
//! and they give the equations they were saved with.

use hb_model::{IdentifiedModel, IdentifiedSystem, MODEL_VERSION, SYSTEM_VERSION};

/// The repository's `fixtures/` folder.
const FIXTURES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures");

/// A fixture's JSON and binary forms, read as a system, with the version each says it is.
fn read(name: &str) -> (IdentifiedSystem, IdentifiedSystem, String, u32) {
    let json = std::fs::read_to_string(format!("{FIXTURES}/{name}.json")).unwrap();
    let bytes = std::fs::read(format!("{FIXTURES}/{name}.bin")).unwrap();
    let version = u32::from_le_bytes(bytes[8..12].try_into().unwrap());
    let from_json = IdentifiedSystem::from_json(&json).unwrap();
    let from_bytes = IdentifiedSystem::from_bytes(&bytes).unwrap();
    (from_json, from_bytes, json, version)
}

/// Every one-coordinate model of versions 2 to today's loads as a system of one equation, the
/// same from JSON and from the binary.
#[test]
fn every_saved_model_of_one_coordinate_loads_as_a_system_of_one() {
    for (name, want) in [
        ("model_v2_hat8_upo", 2),
        ("model_v2_duffing_known_forcing", 2),
        ("model_v3_rig_terms", 3),
        ("model_v4_pendulum_terms", 4),
    ] {
        let (from_json, from_bytes, json, version) = read(name);
        assert_eq!(version, want, "{name}");
        assert!(json.contains(&format!("\"version\": {want}")), "{name}");
        assert_eq!(from_json, from_bytes, "{name}");
        assert_eq!(from_json.coordinates(), 1, "{name}");
    }
    assert_eq!(
        MODEL_VERSION, 4,
        "a new version of the one-coordinate format wants its fixture here"
    );
}

/// Version 4: the paper's pendulum identified with four named terms (`x'`, `sin(x)`,
/// `sin(t)*cos(x)`, `cos(t)*cos(x)`) from the paper's data set.
#[test]
fn a_model_of_named_terms_saved_by_version_4_reads_its_coefficients() {
    let (system, _, _, _) = read("model_v4_pendulum_terms");
    let json = std::fs::read_to_string(format!("{FIXTURES}/model_v4_pendulum_terms.json")).unwrap();
    let model = IdentifiedModel::<hb_basis::BasisKind>::from_json(&json).unwrap();
    assert_eq!(&system.equations()[0], &model);
    let stiffness = 1.0 / (0.8333_f64 * 0.8333);
    for (term, want) in [
        ("x'", 0.03),
        ("sin(x)", stiffness),
        ("sin(t)*cos(x)", -1.52),
        ("cos(t)*cos(x)", 0.0),
    ] {
        let got = model.coefficient(term).unwrap().value;
        assert!((got - want).abs() < 1e-5, "{term}: {got} against {want}");
    }
}

/// Version 5, a system: the base-excited double pendulum (`hbid simulate --system
/// double-pendulum --samples 20000`, its physical terms), both equations with their coordinates'
/// names and coefficients within 1e-4 of the simulated truth.
#[test]
fn a_double_pendulum_saved_by_version_5_reads_both_equations() {
    let (system, from_bytes, _, version) = read("system_v5_double_pendulum");
    assert_eq!(version, SYSTEM_VERSION);
    assert_eq!(
        SYSTEM_VERSION, 5,
        "a new version of the system format wants its fixture here"
    );
    assert_eq!(system, from_bytes);
    assert_eq!(system.names().coordinates(), ["theta1", "theta2"]);
    let truth: [&[(&str, f64)]; 2] = [
        &[
            ("theta2''*cos(theta1-theta2)", 0.5),
            ("sin(theta1-theta2)*theta2'^2", 0.5),
            ("sin(theta1)", 0.8),
            ("sin(t)*cos(theta1)", -0.6),
            ("theta1'", 0.05),
        ],
        &[
            ("theta1''*cos(theta1-theta2)", 1.0),
            ("sin(theta1-theta2)*theta1'^2", -1.0),
            ("sin(theta2)", 0.8),
            ("sin(t)*cos(theta2)", -0.6),
            ("theta2'", 0.05),
        ],
    ];
    for (equation, truth) in system.equations().iter().zip(truth) {
        assert_eq!(equation.coefficients().len(), truth.len());
        for &(term, want) in truth {
            let got = equation.coefficient(term).unwrap().value;
            assert!((got - want).abs() < 1e-4, "{term}: {got} against {want}");
        }
    }
}
