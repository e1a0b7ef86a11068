//! What every fuzz target checks after calling a reader or a loader: the result, if any, is
//! consistent, and an error names a place that exists. A violated check panics, which libFuzzer
//! reports as a crash, like a panic inside the code under test.

use hb_basis::BasisKind;
use hb_model::IdentifiedModel;
use hb_record::input::{
    GridOptions, GridRecord, InputError, Location, Record, RecordEnd, UNSETTLED_FRACTION, UNSETTLED_MAX,
    angle_range,
};
use pendulum_sim::SecondOrderSystem;

/// The number of lines of a text as the reader counts them (a last line without a line end
/// counts).
pub fn line_count(text: &[u8]) -> u64 {
    let breaks = text.iter().filter(|&&b| b == b'\n').count() as u64;
    breaks + u64::from(!text.ends_with(b"\n") && !text.is_empty())
}

/// Checks an error of a reader: its text can be written, and the line or sample it names exists
/// (`lines` lines of text, or `samples` samples of an array).
pub fn check_error(error: &InputError, lines: u64, samples: usize) {
    let text = error.to_string();
    assert!(!text.is_empty());
    let line = match error {
        InputError::NotANumber { line, .. }
        | InputError::Ragged { line, .. }
        | InputError::MixedSeparators { line, .. }
        | InputError::Malformed { line, .. } => Some(*line),
        InputError::NonFinite { at, .. }
        | InputError::TimeNotIncreasing { at, .. }
        | InputError::TimeGlitch { at, .. } => match at {
            Location::Line(line) => Some(*line),
            Location::Sample(s) => {
                assert!(
                    (1..=samples).contains(s),
                    "{error:?} names sample {s} of {samples}"
                );
                None
            }
        },
        _ => None,
    };
    if let Some(line) = line {
        assert!(
            (1..=lines).contains(&line),
            "{error:?} names line {line} of {lines}"
        );
        assert!(text.contains(&format!("line {line}")), "{text}");
    }
}

/// Checks a record as read: as many times as values, all finite, and for text one line number per
/// sample, increasing, within the text's `lines`. Then reads its angle range and fits its time
/// stamps, with and without repair.
pub fn check_record(record: &Record, lines: Option<u64>) {
    let n = record.theta.len();
    assert!(n > 0, "an empty record was read");
    assert_eq!(record.t.len(), n);
    assert!(
        record.t.iter().chain(&record.theta).all(|v| v.is_finite()),
        "{record:?}"
    );
    match (&record.lines, lines) {
        (Some(numbers), Some(lines)) => {
            assert_eq!(numbers.len(), n);
            assert!(numbers.windows(2).all(|w| w[0] < w[1]), "{numbers:?}");
            assert!(
                numbers.iter().all(|l| (1..=lines).contains(l)),
                "{numbers:?} of {lines}"
            );
        }
        (None, None) => {}
        (numbers, lines) => panic!("line numbers {numbers:?} for text of {lines:?} lines"),
    }
    angle_range(&record.theta);
    for repair in [false, true] {
        fit_and_check(record.clone(), repair);
    }
}

/// Fits a record's stamps to a grid and checks the result: every sample in exactly one piece, in
/// order, but those of unsettled runs at the ends (each at most 1 % of the record and 50), the
/// pieces apart by gaps, a finite positive step; repairs only when asked for, each at a sample of
/// the record. An error must name a place in the record.
pub fn fit_and_check(record: Record, repair: bool) {
    let n = record.t.len();
    let theta = record.theta.clone();
    let numbers = record.lines.clone();
    match GridRecord::fit(record, &GridOptions { repair }) {
        Ok(grid) => {
            assert!(grid.dt.is_finite() && grid.dt > 0.0, "{}", grid.dt);
            assert!(grid.t0.is_finite(), "{}", grid.t0);
            let kept = grid.kept();
            assert!(
                kept.end <= n && grid.sample_count() == kept.len(),
                "{kept:?} of {n}"
            );
            let ends: Vec<_> = grid
                .unsettled
                .iter()
                .map(|r| (r.end, r.samples.clone()))
                .collect();
            let expected: Vec<_> = [(RecordEnd::Start, 0..kept.start), (RecordEnd::End, kept.end..n)]
                .into_iter()
                .filter(|(_, r)| !r.is_empty())
                .collect();
            assert_eq!(ends, expected, "the runs left out and the samples kept");
            for run in &grid.unsettled {
                let len = run.samples.len();
                assert!(
                    len >= 2 && len as f64 <= UNSETTLED_FRACTION * n as f64 && len <= UNSETTLED_MAX,
                    "{run:?} of {n}"
                );
                assert!(!run.to_string().is_empty());
            }
            assert_eq!(grid.pieces.first().map(|p| p.first), Some(0));
            for w in grid.pieces.windows(2) {
                assert!(
                    w[1].first >= w[0].first + w[0].samples.len() + 1,
                    "pieces overlap"
                );
            }
            let joined: Vec<f64> = grid
                .pieces
                .iter()
                .flat_map(|p| p.samples.iter().copied())
                .collect();
            assert!(
                joined
                    .iter()
                    .zip(&theta[kept])
                    .all(|(a, b)| a.to_bits() == b.to_bits()),
                "the samples moved"
            );
            assert!(repair || grid.repaired.is_empty());
            let report = &grid.report;
            assert_eq!(report.step, grid.dt);
            assert!(
                report.max_deviation.abs() < 0.5 * grid.dt
                    && report.rms_deviation <= report.max_deviation.abs() * (1.0 + 1e-12),
                "{report:?}"
            );
            assert!(report.rms_jitter.is_finite() && report.max_jitter.is_finite(), "{report:?}");
            assert!(report.slips.iter().all(|s| s.by.is_finite() && s.by != 0.0), "{report:?}");
            assert!(!report.to_string().is_empty());
            for r in &grid.repaired {
                assert!(r.now.is_finite());
                match (r.at, &numbers) {
                    (Location::Line(l), Some(numbers)) => assert!(numbers.contains(&l)),
                    (Location::Sample(s), None) => assert!((1..=n).contains(&s)),
                    (at, _) => panic!("repair at {at:?}"),
                }
            }
        }
        Err(e) => {
            assert!(!e.to_string().is_empty());
            let named = match &e {
                InputError::TimeGlitch { at, .. } | InputError::TimeNotIncreasing { at, .. } => vec![*at],
                InputError::TimeUnsettled { first, last, .. } => vec![*first, *last],
                _ => Vec::new(),
            };
            for at in &named {
                match (at, &numbers) {
                    (Location::Line(l), Some(numbers)) => assert!(numbers.contains(l), "{e:?}"),
                    (Location::Sample(s), None) => assert!((1..=n).contains(s), "{e:?}"),
                    _ => panic!("{e:?} for a record with lines {numbers:?}"),
                }
            }
        }
    }
}

/// Checks a loaded model: it evaluates to finite or infinite numbers without panicking at a few
/// points, and it saves and loads back to itself in both formats.
pub fn check_model(model: &IdentifiedModel<BasisKind>) {
    for &(t, x, v) in &[(0.0, 0.0, 0.0), (1.3, -2.1, 0.7), (-40.0, 1e3, -1e3)] {
        model.acceleration(t, x, v);
        model.jacobian(t, x, v);
        model.autonomous(x);
        model.parametric(x);
    }
    let json = model.to_json().expect("a loaded model saves as JSON");
    let back = IdentifiedModel::<BasisKind>::from_json(&json).expect("and loads back");
    assert_eq!(&back, model);
    let bytes = model.to_bytes().expect("a loaded model saves as bytes");
    let back = IdentifiedModel::<BasisKind>::from_bytes(&bytes).expect("and loads back");
    assert_eq!(&back, model);
}
