//! The options of the requests: errors that name the option as each front end spells it, unknown
//! names refused with the names they may have meant, and a library's check given its reason once.

use hb_pipeline::IdentifyOptions;
use hb_pipeline::options::{OptionError, Spelling, from_object, known_names};
use serde::{Deserialize, Serialize};

#[derive(Debug, Default, Serialize, Deserialize, PartialEq)]
#[serde(default)]
struct Sample {
    folds: usize,
    basis: Option<String>,
}

/// The options of a real request read through the library's text grammar (the basis, by
/// [`IdentifyOptions`]), and the names of a request of two options.
#[test]
fn options_are_named_in_errors_and_unknown_ones_refused() {
    let ok: IdentifyOptions = from_object(serde_json::json!({"select_folds": 3, "basis": "hat:8"})).unwrap();
    assert_eq!(ok.select_folds, 3);
    assert_eq!(ok.basis.unwrap().spec(), "hat:8");
    let ok: Sample = from_object(serde_json::json!({"folds": 3, "basis": "hat:8"})).unwrap();
    assert_eq!(ok.folds, 3);
    let e = from_object::<Sample>(serde_json::json!({"fold": 3})).unwrap_err();
    assert_eq!(e.option(), "fold");
    assert!(e.reason().contains("did you mean folds?"), "{e}");
    let e = from_object::<IdentifyOptions>(serde_json::json!({"basis": "cheb:3"})).unwrap_err();
    assert_eq!(e.option(), "basis");
    assert!(e.spelled(Spelling::Python).starts_with("basis='cheb:3': "), "{e}");
    assert!(e.reason().contains("unknown basis 'cheb'"), "{e}");
    let e = from_object::<Sample>(serde_json::json!({"folds": -1})).unwrap_err();
    assert_eq!(e.option(), "folds");
    assert_eq!(known_names::<Sample>(), ["basis", "folds"]);
    // An optional text option that is not given is still an option (serialised as null).
    assert!(
        known_names::<IdentifyOptions>()
            .iter()
            .any(|name| name == "basis")
    );
}

#[test]
fn a_library_check_gives_its_reason_once() {
    let e = embedding::AmiParams::new(circle_signal::Domain::Circle)
        .with_bins(1)
        .unwrap_err();
    let e = OptionError::checked("bins", 1, &e);
    assert_eq!(
        e.spelled(Spelling::CommandLine),
        "--bins 1: must be between 2 and 1024"
    );
    let e = upo_search::CloseReturns::builder(&circle_signal::SampleClock::nondimensional(4).unwrap(), 1)
        .tolerance(0.7)
        .build()
        .unwrap_err();
    let e = OptionError::checked("tolerance", 0.7, &e);
    assert!(
        e.spelled(Spelling::Python)
            .starts_with("tolerance=0.7: it is a fraction"),
        "{e}"
    );
}

/// Two options, `kitten` away from one by two edits (`sittin`: a substitution, a substitution) and
/// from the other by three (`sitting`: one more insertion): only names within two edits are
/// suggested.
#[derive(Debug, Default, Serialize, Deserialize)]
#[serde(default)]
struct Near {
    sittin: usize,
    sitting: usize,
}

#[test]
fn spellings() {
    let e = OptionError::value("select_folds", 1, "must be at least 2");
    assert_eq!(
        e.spelled(Spelling::CommandLine),
        "--select-folds 1: must be at least 2"
    );
    assert_eq!(e.spelled(Spelling::Python), "select_folds=1: must be at least 2");
    let e = OptionError::new("terms", "not with «no_parametric»; give the step with «dt=»");
    assert_eq!(
        e.spelled(Spelling::CommandLine),
        "--terms: not with --no-parametric; give the step with --dt"
    );
    assert_eq!(
        e.spelled(Spelling::Python),
        "terms: not with no_parametric; give the step with dt="
    );
    let e = OptionError::sentence("bit_errors", "needs «counts»");
    assert_eq!(e.spelled(Spelling::CommandLine), "--bit-errors needs --counts");
    // The records given are the command line's FILE arguments, Python's first argument x.
    let e = OptionError::new("file", "record 2 has other columns");
    assert_eq!(
        e.spelled(Spelling::CommandLine),
        "FILE: record 2 has other columns"
    );
    assert_eq!(e.spelled(Spelling::Python), "x: record 2 has other columns");
    // The edit distance of kitten and sitting is 3, of kitten and sittin 2.
    let e = from_object::<Near>(serde_json::json!({"kitten": 1})).unwrap_err();
    assert_eq!(e.reason(), "unknown option; did you mean sittin?");
    let e = from_object::<Near>(serde_json::json!({"kittin": 1})).unwrap_err();
    assert_eq!(e.reason(), "unknown option; did you mean sittin or sitting?");
}
