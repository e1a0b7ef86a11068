//! The notes of preparing a record: what they say of spikes on the circle and of outliers on the
//! line, found or replaced, and of a logger's unsettled start or end left out of every column.
use std::path::Path;

use circle_signal::{Domain, Spike};
use hb_record::input::{Column, Location, ReadOptions, Record, RecordEnd, Unsettled, read_path};
use hb_record::prepare::{Note, PrepareOptions, condition};

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

#[test]
fn the_unsettled_note_says_what_was_left_out_and_why() {
    let run = Unsettled {
        end: RecordEnd::Start,
        samples: 0..6,
        first: Location::Line(2),
        last: Location::Line(7),
        from: 0.0,
        to: 0.015,
        shortest: 0.003,
        longest: 0.0038,
        step: 0.002,
    };
    let note = Note::Unsettled(run.clone());
    assert!(!note.is_warning());
    assert_eq!(
        note.to_string(),
        "the first 6 samples (line 2 to line 7, t = 0 to 0.015) are left out: their time stamps are 1.5 to 1.9 \
         steps of 0.002 apart, off the grid of the rest (a logger settling to its rate)"
    );
    let end = Note::Unsettled(Unsettled {
        end: RecordEnd::End,
        samples: 994..1000,
        first: Location::Sample(995),
        last: Location::Sample(1000),
        ..run
    });
    assert!(
        end.to_string()
            .starts_with("the last 6 samples (sample 995 to sample 1000, t = 0 to 0.015) are left out")
            && end
                .to_string()
                .ends_with("(a logger leaving its rate as it stops)"),
        "{end}"
    );
}

#[test]
fn an_unsettled_start_and_end_are_left_out_of_every_column() {
    // 2 000 samples at 500 Hz from t = 10, after 5 samples and before 4 at 1.5 to 1.9 steps; the
    // angle, a further coordinate and a drive numbered by their place in the record as read.
    let dt = 2e-3;
    let (head, tail) = ([1.5, 1.6, 1.7, 1.8, 1.9], [1.9, 1.7, 1.6, 1.5]);
    let mut t: Vec<f64> = (0..head.len())
        .map(|j| 10.0 - head[j..].iter().sum::<f64>() * dt)
        .collect();
    t.extend((0..2_000).map(|i| 10.0 + i as f64 * dt));
    let last = t[t.len() - 1];
    t.extend((1..=tail.len()).map(|j| last + tail[..j].iter().sum::<f64>() * dt));
    let n = t.len();
    let place = |scale: f64| -> Vec<f64> { (0..n).map(|i| scale * i as f64).collect() };
    let record = Record {
        t,
        theta: place(1.0),
        others: vec![place(10.0)],
        drives: vec![place(-1.0)],
        lines: Some((2..n as u64 + 2).collect()),
    };
    let options = PrepareOptions::new(Domain::Line).with_others(vec![Domain::Line]);
    let mut heard = Vec::new();
    let grid = condition(record, &options, &mut |note| heard.push(note.clone())).unwrap();
    assert_eq!(heard, grid.notes);
    let runs: Vec<(RecordEnd, std::ops::Range<usize>)> = grid
        .notes
        .iter()
        .filter_map(|note| match note {
            Note::Unsettled(run) => Some((run.end, run.samples.clone())),
            _ => None,
        })
        .collect();
    assert_eq!(runs, [(RecordEnd::Start, 0..5), (RecordEnd::End, 2_005..2_009)]);
    assert!(
        grid.notes[0]
            .to_string()
            .starts_with("the first 5 samples (line 2 to line 6, t = "),
        "{}",
        grid.notes[0]
    );
    assert!(
        grid.notes.iter().all(|note| !note.is_warning()),
        "{:?}",
        grid.notes
    );
    assert_eq!(grid.pieces, std::slice::from_ref(&(0..2_000)));
    assert!(
        (grid.t0 - 10.0).abs() < 1e-12 && (grid.dt - dt).abs() < 1e-15,
        "{} {}",
        grid.t0,
        grid.dt
    );
    // Every column from the same sample on: the first on the grid.
    let kept: Vec<f64> = (5..2_005).map(|i| i as f64).collect();
    assert_eq!(grid.x, kept);
    assert_eq!(
        grid.others[0].x,
        kept.iter().map(|v| 10.0 * v).collect::<Vec<_>>()
    );
    assert_eq!(grid.drives[0], kept.iter().map(|v| -v).collect::<Vec<_>>());
}

/// The DFKI double pendulum's records (`trajectory_*.csv` in the shared benchmarks): each starts
/// with 4 to 6 samples 1.4 to 1.9 steps apart before its loop runs at 500 Hz.
#[test]
#[expect(clippy::print_stderr, reason = "a test that cannot run says why")]
fn the_dfki_records_condition_with_their_first_samples_left_out() {
    let folder =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/benchmarks/dfki_double_pendulum");
    let Ok(entries) = std::fs::read_dir(&folder) else {
        eprintln!(
            "skipped: no DFKI double pendulum records at {} (the shared benchmarks are not here)",
            folder.display()
        );
        return;
    };
    let mut paths: Vec<_> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("trajectory_") && n.ends_with(".csv"))
        })
        .collect();
    paths.sort();
    assert!(!paths.is_empty(), "no trajectory_*.csv in {}", folder.display());
    let column = |name: &str| Column::Name(name.to_owned());
    let read = ReadOptions {
        time: Some(column("time")),
        angle: Some(column("pos_meas1")),
        others: vec![column("pos_meas2")],
        drives: vec![column("tau_meas1"), column("tau_meas2")],
        ..ReadOptions::default()
    };
    let options = PrepareOptions::new(Domain::Circle).with_others(vec![Domain::Circle]);
    for path in paths {
        let name = path.display();
        let record = read_path(&path, &read).unwrap_or_else(|e| panic!("{name}: {e}"));
        let n = record.t.len();
        let (t, first_drive) = (record.t.clone(), record.drives[0].clone());
        let grid = condition(record, &options, &mut |_| {}).unwrap_or_else(|e| panic!("{name}: {e}"));
        let Some(Note::Unsettled(run)) = grid.notes.first() else {
            panic!("{name}: {:?}", grid.notes)
        };
        let left_out = run.samples.len();
        assert_eq!(
            (run.end, run.samples.start, run.first),
            (RecordEnd::Start, 0, Location::Line(2)),
            "{name}"
        );
        assert!((4..=6).contains(&left_out), "{name}: {run:?}");
        assert!(
            run.shortest / run.step > 1.4 && run.longest / run.step < 2.0,
            "{name}: {run:?}"
        );
        assert_eq!(grid.pieces, std::slice::from_ref(&(0..n - left_out)), "{name}");
        assert!((grid.dt - 2e-3).abs() < 1e-6, "{name}: {}", grid.dt);
        assert!(
            (grid.t0 - t[left_out]).abs() < 0.25 * grid.dt,
            "{name}: {}",
            grid.t0
        );
        assert_eq!(grid.drives[0][0], first_drive[left_out], "{name}");
    }
}
