//! A saved model against a record: ranges of samples read, printed and placed on the record,
//! options checked, and the default samples of the initial state.

use std::f64::consts::TAU;

use hb_basis::{BasisKind, Polynomial};
use hb_model::{IdentifiedModel, IdentifiedSystem, ModelForm};
use hb_pipeline::compare::RangeScore;
use hb_pipeline::{CompareOptions, CompareRequest, RunError, SampleRange, Source, compare};

/// `x'' = −0.1 x'` on the line, with the drive angular frequency `omega`: no term has the drive,
/// so the frequency only sets what one drive period is in samples.
fn at_rest(omega: f64) -> IdentifiedModel {
    let basis = BasisKind::from(Polynomial::new(1).unwrap());
    IdentifiedModel::new(
        basis,
        ModelForm::from_terms("x'".parse().unwrap()),
        omega,
        &[-0.1],
    )
    .unwrap()
}

/// The scores of [`at_rest`]`(omega)` on a record of `len` samples at rest, `dt` apart, over
/// `ranges` (none: the whole record), run from the state given (at rest: nothing is fitted).
fn scores(omega: f64, dt: f64, len: usize, ranges: &[SampleRange]) -> Result<Vec<RangeScore>, RunError> {
    let x = vec![0.0; len];
    let request = CompareRequest::new(CompareOptions {
        dt: Some(dt),
        x0: Some(0.0.into()),
        v0: Some(0.0.into()),
        range: ranges.to_vec(),
        ..CompareOptions::default()
    })
    .unwrap();
    let source = Source::Arrays {
        coords: vec![&x],
        t: None,
        drives: Vec::new(),
    };
    Ok(compare(&IdentifiedSystem::one(at_rest(omega)), source, &request, &mut ())?.ranges)
}

#[test]
fn ranges_read_and_print() {
    let r: SampleRange = "100..40575".parse().unwrap();
    assert_eq!(
        r,
        SampleRange {
            start: 100,
            end: Some(40575)
        }
    );
    assert_eq!(r.to_string(), "100..40575");
    assert_eq!("5..".parse::<SampleRange>().unwrap().end, None);
    assert!("7..7".parse::<SampleRange>().is_err());
    assert!("a..b".parse::<SampleRange>().is_err());
    assert!("12".parse::<SampleRange>().is_err());
    // The range on a record of 40000 samples ends past it; on one of 50000 it is [100, 40575).
    match scores(1.0, 0.1, 40000, &[r]) {
        Err(RunError::Options(e)) => assert_eq!(e.option(), "range", "{e}"),
        other => panic!("{other:?}"),
    }
    assert_eq!(scores(1.0, 0.1, 50000, &[r]).unwrap()[0].range, [100, 40575]);
}

#[test]
fn options_are_checked() {
    let bad = |o: CompareOptions| CompareRequest::new(o).unwrap_err().option().to_owned();
    let d = CompareOptions::default;
    assert_eq!(bad(CompareOptions { init: Some(1), ..d() }), "init");
    assert_eq!(
        bad(CompareOptions {
            x0: Some(1.0.into()),
            ..d()
        }),
        "x0"
    );
    assert_eq!(
        bad(CompareOptions {
            v0: Some(1.0.into()),
            ..d()
        }),
        "v0"
    );
    assert_eq!(bad(CompareOptions { rtol: 0.0, ..d() }), "rtol");
    assert_eq!(
        bad(CompareOptions {
            dt: Some(-1.0),
            ..d()
        }),
        "dt"
    );
    let json = serde_json::json!({"range": ["100..200", "300.."], "init": 50, "dt": 0.01});
    let request = CompareRequest::from_json(json).unwrap();
    assert_eq!(request.options().range.len(), 2);
    assert!(CompareRequest::from_json(serde_json::json!({"ranges": ["1..2"]})).is_err());
}

/// The samples of the initial state when none are given (a range's `init`): one drive period in
/// samples, at most a tenth of the range and at least 8. The period is the drive's `2π/ω` over
/// the step: the record's step is chosen for each period in samples (an infinite one from the
/// smallest positive `ω`).
#[test]
fn the_default_init_scales_with_the_drive_and_the_range() {
    let default_init = |period_samples: f64, range: usize| {
        let (omega, dt) = if period_samples.is_finite() {
            (1.0, TAU / period_samples)
        } else {
            (f64::MIN_POSITIVE, 1.0)
        };
        assert_eq!(TAU / omega / dt == f64::INFINITY, period_samples.is_infinite());
        let scores = scores(omega, dt, range, &[]).unwrap();
        assert_eq!(scores[0].range, [0, range]);
        scores[0].init
    };
    assert_eq!(default_init(25.0, 30_000), 25);
    assert_eq!(default_init(490.2, 150_000), 490);
    assert_eq!(default_init(6283.0, 20_000), 2000);
    assert_eq!(default_init(3.0, 1000), 8);
    assert_eq!(default_init(f64::INFINITY, 1000), 8);
}
