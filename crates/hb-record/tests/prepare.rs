//! The notes of preparing a record: what they say of spikes on the circle and of outliers on the
//! line, found or replaced.
use circle_signal::{Domain, Spike};
use hb_record::prepare::Note;

#[test]
fn the_spikes_note_speaks_of_bit_errors_on_the_circle_and_of_outliers_on_the_line() {
    let found = vec![Spike {
        index: 41,
        size: 0.5,
        replacement: 0.1,
    }];
    let note = |domain, repaired| {
        Note::Spikes {
            coordinate: 0,
            found: found.clone(),
            repaired,
            domain,
        }
        .to_string()
    };
    assert_eq!(
        note(Domain::Circle, false),
        "1 isolated spike(s) (bit errors?) in the record: sample 42 (+0.5000)"
    );
    assert_eq!(
        note(Domain::Line, false),
        "1 outlier(s) in the record: sample 42 (+0.5000)"
    );
    assert_eq!(
        note(Domain::Line, true),
        "1 outlier(s) replaced by the local prediction: sample 42 (+0.5000)"
    );
    assert!(!note(Domain::Line, false).contains("bit error"));
}
