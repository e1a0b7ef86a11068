//! The notes of preparing a record: what they say of spikes on the circle and of outliers on the
//! line, found or replaced, and of a logger's unsettled start or end left out of every column;
//! and the spike policy: a free decay through a 4096-count encoder with a few bit errors, two of
//! them half a turn, keeps its turns by default.
use std::f64::consts::TAU;
use std::path::Path;

use circle_signal::{Domain, Spike, unwrap, wrap};
use hb_record::input::{Column, Location, ReadOptions, Record, RecordEnd, Unsettled, read_path};
use hb_record::prepare::{DriveFound, GridData, Note, PeriodSource, PrepareOptions, SpikePolicy, condition};

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
            policy: if repaired {
                SpikePolicy::Repair
            } else {
                SpikePolicy::Keep
            },
            grid: None,
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
    // With the grid's clock, each is named by its time too.
    let timed = Note::Spikes {
        coordinate: 0,
        found: found.clone(),
        repaired: false,
        domain: Domain::Line,
        policy: SpikePolicy::Keep,
        grid: Some((10.0, 0.5)),
    };
    assert_eq!(
        timed.to_string(),
        "1 outlier(s) in the record: sample 42 at t = 30.50 (+0.5000)"
    );
}

/// Consecutive samples flagged on the circle are not called isolated spikes: the note counts the
/// samples alone and the runs (a fast motion's bumps are runs of two to four).
#[test]
fn the_spikes_note_counts_runs_apart_from_isolated_spikes() {
    let at = |index| Spike {
        index,
        size: 0.03,
        replacement: 0.1,
    };
    let found: Vec<Spike> = [5, 9, 10, 11, 20, 30, 31].into_iter().map(at).collect();
    let note = Note::Spikes {
        coordinate: 1,
        found,
        repaired: false,
        domain: Domain::Circle,
        policy: SpikePolicy::Keep,
        grid: None,
    }
    .to_string();
    assert!(
        note.starts_with(
            "coordinate 2: 7 outlying sample(s), 2 alone and 2 run(s) of 2 to 3 (bit errors, glitches, or \
             motion too fast for the sampling?) in the record: sample 6 (+0.0300), sample 10 (+0.0300)"
        ),
        "{note}"
    );
    assert!(!note.contains("isolated"), "{note}");
}

/// A row written twice (its stamp and every value the row before's) is left out of every
/// column, with a note naming its line; the record is then the one without it. A stamp repeated
/// with other values is not a duplicate (the grid fit judges it).
#[test]
fn a_row_written_twice_is_left_out() {
    let n = 400;
    let t: Vec<f64> = (0..n).map(|i| 5.0 + i as f64 * 0.01).collect();
    let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.05).sin()).collect();
    let drive: Vec<f64> = (0..n).map(|i| (i as f64 * 0.03).cos()).collect();
    let clean = Record {
        t: t.clone(),
        theta: x.clone(),
        drives: vec![drive.clone()],
        lines: Some((2..n as u64 + 2).collect()),
        ..Record::default()
    };
    let twice = |v: &[f64]| -> Vec<f64> { v[..201].iter().chain(&v[200..]).copied().collect() };
    let doubled = Record {
        t: twice(&t),
        theta: twice(&x),
        drives: vec![twice(&drive)],
        lines: Some((2..n as u64 + 3).collect()),
        ..Record::default()
    };
    let options = PrepareOptions::new(Domain::Line);
    let expected = condition(clean, &options, &mut |_| {}).unwrap();
    let grid = condition(doubled, &options, &mut |_| {}).unwrap();
    assert_eq!(grid.x, expected.x);
    assert_eq!(grid.drives, expected.drives);
    assert_eq!(
        grid.notes[0].to_string(),
        "1 row(s) written twice (the stamp and every value of the row before) left out, the first at line 203"
    );
    // The same stamp with another value: not a duplicate row.
    let mut glitch = twice(&x);
    glitch[201] += 0.5;
    let record = Record {
        t: twice(&t),
        theta: glitch,
        ..Record::default()
    };
    assert!(condition(record, &options, &mut |_| {}).is_err());
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
        velocities: vec![place(5.0), place(6.0)],
        lines: Some((2..n as u64 + 2).collect()),
        missing: Vec::new(),
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
    assert_eq!(
        grid.velocities,
        [5.0, 6.0].map(|k| kept.iter().map(|v| k * v).collect::<Vec<_>>())
    );
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

#[test]
fn the_spikes_note_says_when_they_were_replaced_by_default_and_when_they_were_too_many() {
    let found = vec![Spike {
        index: 41,
        size: -3.1408,
        replacement: 0.7,
    }];
    let note = |repaired| Note::Spikes {
        coordinate: 0,
        found: found.clone(),
        repaired,
        domain: Domain::Circle,
        policy: SpikePolicy::RepairFew,
        grid: None,
    };
    assert_eq!(
        note(true).to_string(),
        "1 isolated spike(s) replaced by the local prediction (by default: larger than the record's steps, at \
         most one in 1000 samples): sample 42 (-3.1408)"
    );
    assert!(!note(true).is_warning());
    assert_eq!(
        note(false).to_string(),
        "1 isolated spike(s) (bit errors?) in the record (not replaced by default: within the record's own \
         steps, or more than one in 1000 samples): sample 42 (-3.1408)"
    );
    assert!(note(false).is_warning());
    // A size four decimals would print as zero is written so that it shows.
    let tiny = Note::Spikes {
        coordinate: 1,
        found: vec![Spike {
            index: 7,
            size: 3.2e-5,
            replacement: 0.1,
        }],
        repaired: false,
        domain: Domain::Circle,
        policy: SpikePolicy::RepairFew,
        grid: None,
    };
    assert!(
        tiny.to_string().starts_with("coordinate 2: 1 isolated spike(s)"),
        "{tiny}"
    );
    assert!(tiny.to_string().ends_with("sample 8 (+3.2e-5)"), "{tiny}");
}

#[test]
fn spikes_are_few_up_to_one_in_a_thousand_samples_rounded_up() {
    assert!(SpikePolicy::few(0, 0));
    assert!(SpikePolicy::few(1, 7));
    assert!(!SpikePolicy::few(2, 7));
    assert!(SpikePolicy::few(1, 1000));
    assert!(!SpikePolicy::few(2, 1000));
    assert!(SpikePolicy::few(2, 1001));
    assert!(SpikePolicy::few(45, 45_000));
    assert!(!SpikePolicy::few(46, 45_000));
    assert_eq!(PrepareOptions::new(Domain::Circle).spikes, SpikePolicy::RepairFew);
}

/// The count of a 4096-count encoder.
const COUNT: f64 = TAU / 4096.0;

/// Samples per second of the decay, and its frequency (Hz).
const RATE: f64 = 1000.0;
const FREQUENCY: f64 = 1.3;

/// A free decay as a rig logs it: 45 s at 1 kHz of a swing at 1.3 Hz decaying from 80 counts to 3
/// of a 4096-count encoder whose zero is 0.7 rad off (near rest the angle toggles between
/// counts), wrapped into [-π, π).
fn decay() -> Vec<f64> {
    let tau = 45.0 / (80.0_f64 / 3.0).ln();
    (0..45_000)
        .map(|n| {
            let t = n as f64 / RATE;
            let theta = 0.7 + 80.0 * COUNT * (-t / tau).exp() * (TAU * FREQUENCY * t).cos();
            wrap((theta / COUNT).round() * COUNT)
        })
        .collect()
}

/// Bit errors at `(index, counts)`.
fn with_bit_errors(clean: &[f64], errors: &[(usize, f64)]) -> Vec<f64> {
    let mut x = clean.to_vec();
    for &(i, counts) in errors {
        x[i] = wrap(x[i] + counts * COUNT);
    }
    x
}

/// Where a half-turn bit error of `counts` (±2048) is unwrapped into a whole false turn, from
/// sample `from` on: the steps into and out of it, each half a turn give or take the motion and
/// the rounding, are taken as steps of the same sign.
fn false_turn(clean: &[f64], from: usize, counts: f64) -> usize {
    (from..clean.len() - 1)
        .find(|&i| {
            let spiked = wrap(clean[i] + counts * COUNT);
            let u = unwrap(&[clean[i - 1], spiked, clean[i + 1]]);
            ((u[2] - u[0]) / TAU).round() != 0.0
        })
        .expect("a sample where a half turn is a false one")
}

fn record(x: Vec<f64>) -> Record {
    let t = (0..x.len()).map(|n| n as f64 / RATE).collect();
    Record {
        t,
        theta: x,
        ..Record::default()
    }
}

fn conditioned(x: Vec<f64>, options: &PrepareOptions) -> GridData {
    condition(record(x), options, &mut |_| {}).expect("the record is conditioned")
}

/// The windows of one period of the free oscillation whose unwrapped angle ends a whole turn
/// from where it starts: whirling, where the decay only swings.
fn whirling_windows(grid: GridData) -> (usize, usize) {
    let data = grid
        .with_period(PeriodSource::Free)
        .expect("the period of the oscillation");
    let DriveFound::Free { samples } = data.drive else {
        panic!("a free oscillation: {:?}", data.drive);
    };
    // The period is the swing's.
    assert!(
        (samples / (RATE / FREQUENCY) - 1.0).abs() < 0.01,
        "{samples} samples per period"
    );
    let windows: Vec<_> = data.x.chunks_exact(data.p).collect();
    let whirling = windows
        .windows(2)
        .filter(|pair| {
            let mut w = pair[0].to_vec();
            w.push(pair[1][0]);
            let u = unwrap(&w);
            ((u[u.len() - 1] - u[0]) / TAU).round() != 0.0
        })
        .count();
    (whirling, windows.len() - 1)
}

#[test]
fn a_free_decay_with_half_turn_spikes_keeps_its_turns_by_default() {
    let clean = decay();
    let (a, b) = (
        false_turn(&clean, 3_000, 2048.0),
        false_turn(&clean, 20_000, -2048.0),
    );
    let mut errors = vec![
        (a, 2048.0),
        (b, -2048.0),
        (1_234, 64.0),
        (9_876, -128.0),
        (33_333, 256.0),
    ];
    let x = with_bit_errors(&clean, &errors);
    errors.sort_by_key(|e| e.0);

    // By default: found, replaced (a note, not a warning), every unwrapped sample where it was:
    // each bit error is far larger than the decay's steps.
    let grid = conditioned(x.clone(), &PrepareOptions::new(Domain::Circle));
    let [
        Note::Spikes {
            found,
            repaired,
            policy,
            ..
        },
    ] = grid.notes.as_slice()
    else {
        panic!("one note of spikes: {:?}", grid.notes);
    };
    assert!(*repaired);
    assert_eq!(*policy, SpikePolicy::RepairFew);
    assert_eq!(
        found.iter().map(|s| s.index).collect::<Vec<_>>(),
        errors.iter().map(|e| e.0).collect::<Vec<_>>()
    );
    for s in found {
        assert!((s.replacement - clean[s.index]).abs() <= 2.0 * COUNT, "{s:?}");
    }
    let (u, c) = (unwrap(&grid.x), unwrap(&clean));
    let off = u.iter().zip(&c).map(|(u, c)| (u - c).abs()).fold(0.0, f64::max);
    assert!(off <= 2.0 * COUNT, "the unwrapped record departs by {off} rad");
    assert_eq!(whirling_windows(grid), (0, 57));

    // Kept, the half-turn spikes are false turns: windows of the swing come out whirling.
    let kept = conditioned(
        x,
        &PrepareOptions::new(Domain::Circle).with_spikes(SpikePolicy::Keep),
    );
    assert!(
        kept.notes
            .iter()
            .all(|n| !matches!(n, Note::Spikes { repaired: true, .. }))
    );
    assert!(kept.notes.iter().any(Note::is_warning));
    let u = unwrap(&kept.x);
    let turned = u.iter().zip(&c).filter(|(u, c)| (*u - *c).abs() > 6.0).count();
    assert!(turned > 10_000, "{turned} unwrapped samples a turn off");
    let (whirling, _) = whirling_windows(kept);
    assert!(whirling >= 2, "{whirling} windows whirling");
}

#[test]
fn more_spikes_than_one_in_a_thousand_samples_are_reported_not_replaced_by_default() {
    let clean = decay();
    // 50 bit errors of 512 counts in 45 000 samples, 450 apart.
    let errors: Vec<(usize, f64)> = (0..50).map(|k| (500 + 900 * k, 512.0)).collect();
    let x = with_bit_errors(&clean, &errors);
    let grid = conditioned(x.clone(), &PrepareOptions::new(Domain::Circle));
    let [note @ Note::Spikes { found, repaired, .. }] = grid.notes.as_slice() else {
        panic!("one note of spikes: {:?}", grid.notes);
    };
    assert_eq!(found.len(), 50);
    assert!(!repaired && note.is_warning());
    assert_eq!(grid.x, x, "the record is left as read");
    // With repairs asked for, every one is replaced.
    let repaired = conditioned(x, &PrepareOptions::new(Domain::Circle).with_repair(true));
    let [
        Note::Spikes {
            found,
            repaired,
            policy,
            ..
        },
    ] = repaired.notes.as_slice()
    else {
        panic!("one note of spikes: {:?}", repaired.notes);
    };
    assert_eq!((found.len(), *repaired, *policy), (50, true, SpikePolicy::Repair));
}

#[test]
fn a_half_turn_spike_in_a_short_record_is_replaced_by_default() {
    // 700 samples: one spike is at most one in a thousand, rounded up.
    let clean: Vec<f64> = decay()[..700].to_vec();
    let a = false_turn(&clean, 300, 2048.0);
    let grid = conditioned(
        with_bit_errors(&clean, &[(a, 2048.0)]),
        &PrepareOptions::new(Domain::Circle),
    );
    let [Note::Spikes { found, repaired, .. }] = grid.notes.as_slice() else {
        panic!("one note of spikes: {:?}", grid.notes);
    };
    assert_eq!((found.len(), found[0].index, *repaired), (1, a, true));
    assert!((grid.x[a] - clean[a]).abs() <= 2.0 * COUNT);
}

/// Rows dropped here and there (a networked logger's lost packets: one to three in a row) split a
/// record into pieces; bridged, the pieces are one again and every column's missing samples are
/// the cubic through their neighbours: a whirling angle across its wraps, a further coordinate
/// on the line, a drive and a measured velocity. A gap longer than the limit stays a gap, and
/// the notes count both.
#[test]
fn short_gaps_are_bridged_in_every_column_and_longer_ones_kept() {
    let dt = 2e-3;
    // 3 turns a second and a sway: the angle wraps about every 170 samples.
    let angle = |t: f64| 6.0 * std::f64::consts::PI * t + 0.3 * (7.0 * t).sin();
    let line = |t: f64| 0.2 * (5.0 * t).cos();
    let drive = |t: f64| 0.5 * (10.0 * t).sin();
    let velocity = |t: f64| 6.0 * std::f64::consts::PI + 2.1 * (7.0 * t).cos();
    // Rows 100, 400..403, 900..902 and 1500..1520 missing (1, 3, 2 and 20 samples).
    let rows: Vec<usize> = (0..2_000)
        .filter(|i| ![100, 400, 401, 402, 900, 901].contains(i) && !(1_500..1_520).contains(i))
        .collect();
    let of = |f: &dyn Fn(f64) -> f64| rows.iter().map(|&i| f(i as f64 * dt)).collect::<Vec<f64>>();
    let record = Record {
        t: of(&|t| t),
        theta: of(&|t| wrap(angle(t))),
        others: vec![of(&line)],
        drives: vec![of(&drive)],
        velocities: vec![of(&velocity), of(&|t| -5.0 * (5.0 * t).sin())],
        lines: None,
        missing: Vec::new(),
    };
    let options = PrepareOptions::new(Domain::Circle).with_others(vec![Domain::Line]);
    let kept = condition(record.clone(), &options, &mut |_| {}).unwrap();
    assert_eq!(
        kept.pieces,
        [0..100, 101..400, 403..900, 902..1_500, 1_520..2_000]
    );
    assert!(
        kept.notes.contains(&Note::Gaps { gaps: 4, missing: 26 }),
        "{:?}",
        kept.notes
    );

    let grid = condition(record, &options.with_bridge(3), &mut |_| {}).unwrap();
    assert_eq!(grid.pieces, [0..1_500, 1_520..2_000]);
    assert!(
        grid.notes.contains(&Note::Gaps { gaps: 1, missing: 20 }),
        "{:?}",
        grid.notes
    );
    let bridged = Note::Bridged {
        gaps: 3,
        missing: 6,
        limit: 3,
        unclear: 0,
    };
    assert!(grid.notes.contains(&bridged), "{:?}", grid.notes);
    assert_eq!(
        bridged.to_string(),
        "3 gap(s) of at most 3 missing sample(s) bridged: 6 sample(s) interpolated in every column by the \
         cubic through the two samples on each side"
    );
    // Every column at every sample within a cubic's error of the truth (below 1e-6 here, where
    // a straight line between the neighbours would miss the drive by 4e-4), the samples read
    // exactly as they were.
    for i in 0..1_500 {
        let t = i as f64 * dt;
        let tol = if rows.contains(&i) { 1e-12 } else { 1e-6 };
        let close = |got: f64, want: f64, what: &str| {
            assert!((got - want).abs() <= tol, "{what} at {i}: {got} against {want}");
        };
        close(wrap(grid.x[i] - angle(t)), 0.0, "angle");
        assert!((-std::f64::consts::PI..std::f64::consts::PI).contains(&grid.x[i]));
        close(grid.others[0].x[i], line(t), "further coordinate");
        close(grid.drives[0][i], drive(t), "drive");
        close(grid.velocities[0][i], velocity(t), "velocity");
    }
    assert!(grid.x[1_500..1_520].iter().all(|v| v.is_nan()));
}

/// Bridging is refused where it cannot be right: a velocity record integrated piece by piece,
/// and gaps longer than a cubic through four samples can stand for.
#[test]
fn bridging_is_refused_for_an_integrated_record_and_beyond_its_limit() {
    let x: Vec<f64> = (0..200).map(|n| (n as f64 * 0.1).sin()).collect();
    let line = PrepareOptions::new(Domain::Line);
    let err = condition(
        record(x.clone()),
        &line
            .clone()
            .with_measured(circle_signal::Measured::Velocity)
            .with_bridge(2),
        &mut |_| {},
    )
    .unwrap_err();
    assert!(err.to_string().contains("integrated piece by piece"), "{err}");
    let err = condition(
        record(x),
        &line.with_bridge(hb_record::prepare::MAX_BRIDGE + 1),
        &mut |_| {},
    )
    .unwrap_err();
    assert!(err.to_string().contains("at most 4 samples, not 5"), "{err}");
}

/// A coarsely sampled angle (16 samples a period of a 3 rad swing) that can reverse twice within
/// a gap of four: where its turn across a gap cannot be told, the gap stays and the note counts
/// it; every gap bridged is filled on the right turn (within a quarter turn: the cubic itself
/// misses by up to a radian at this sampling).
#[test]
fn a_gap_across_which_an_angle_cannot_tell_its_turn_is_left() {
    let f = |n: f64| {
        3.0 * (n * std::f64::consts::TAU / 16.0).sin() + 0.4 * (n * std::f64::consts::TAU / 5.0).sin()
    };
    // Four rows missing every 23 from row 20.
    let missing = |i: usize| i >= 20 && (i - 20) % 23 < 4;
    let rows: Vec<usize> = (0..700).filter(|&i| !missing(i)).collect();
    let record = Record {
        t: rows.iter().map(|&i| i as f64).collect(),
        theta: rows.iter().map(|&i| wrap(f(i as f64))).collect(),
        ..Record::default()
    };
    let grid = condition(
        record,
        &PrepareOptions::new(Domain::Circle)
            .with_spikes(SpikePolicy::Keep)
            .with_bridge(4),
        &mut |_| {},
    )
    .unwrap();
    let (gaps, unclear) = grid
        .notes
        .iter()
        .find_map(|n| match n {
            Note::Bridged { gaps, unclear, .. } => Some((*gaps, *unclear)),
            _ => None,
        })
        .expect("a note of the gaps bridged");
    assert!(gaps > 0 && unclear > 0, "{:?}", grid.notes);
    assert_eq!(grid.pieces.len(), unclear + 1, "{:?}", grid.pieces);
    assert!(grid.notes.last().unwrap().to_string().ends_with(&format!(
        "; {unclear} more left as gaps: an angle moves too far across them to tell its turn"
    )));
    for piece in &grid.pieces {
        for i in piece.clone().filter(|&i| missing(i)) {
            let error = wrap(grid.x[i] - f(i as f64)).abs();
            assert!(error < std::f64::consts::FRAC_PI_2, "sample {i}: {error}");
        }
    }
}

/// Rows left out for a missing value are a logger's dropped rows: a note counts them and names
/// the first five, the record is split at them as at any gap, and bridging closes the gaps.
#[test]
fn rows_left_out_for_a_missing_value_are_gaps_and_can_be_bridged() {
    let n = 400;
    let dt = 0.01;
    let missing = [50usize, 120, 121, 200, 260, 333];
    let mut text = String::from("t,theta\n");
    for i in 0..n {
        let t = i as f64 * dt;
        let x = if missing.contains(&i) {
            "NA".to_owned()
        } else {
            format!("{}", (2.0 * t).sin())
        };
        text.push_str(&format!("{t},{x}\n"));
    }
    let options = ReadOptions {
        skip_missing: true,
        ..ReadOptions::default()
    };
    let record = hb_record::input::read_bytes(text.as_bytes(), &options).unwrap();
    let lines: Vec<Location> = missing.iter().map(|&i| Location::Line(i as u64 + 2)).collect();
    assert_eq!(record.missing, lines);
    let grid = condition(record.clone(), &PrepareOptions::new(Domain::Line), &mut |_| {}).unwrap();
    assert_eq!(
        grid.notes[..2],
        [
            Note::MissingRows {
                count: 6,
                first: lines[..5].to_vec(),
            },
            Note::Gaps { gaps: 5, missing: 6 },
        ]
    );
    assert_eq!(
        grid.notes[0].to_string(),
        "6 row(s) with a missing value in a column read left out, as a logger's dropped rows: line 52, line 122, \
         line 123, line 202, line 262, ..."
    );
    assert_eq!(grid.pieces.len(), 6);
    assert!(missing.iter().all(|&i| grid.x[i].is_nan()));
    let bridged = condition(
        record,
        &PrepareOptions::new(Domain::Line).with_bridge(2),
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(bridged.pieces, vec![0..n]);
    assert_eq!(
        bridged.bridged,
        vec![50..51, 120..122, 200..201, 260..261, 333..334]
    );
    for &i in &missing {
        let truth = (2.0 * i as f64 * dt).sin();
        assert!(
            (bridged.x[i] - truth).abs() < 1e-7,
            "sample {i}: {} against {truth}",
            bridged.x[i]
        );
    }
}
