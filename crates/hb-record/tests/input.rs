//! The one column policy of both readers (defaults, chosen columns, a sampling step, two unnamed
//! columns in either order), the options checked before reading, and angle ranges that allow for
//! the printing of the values.
use std::path::Path;

use hb_record::input::{
    AngleRange, Column, GridOptions, GridRecord, InputError, ReadOptions, Record, Role, angle_range,
    read_bytes, read_path,
};

use crate::common::npy_bytes;

fn options(time: Option<&str>, angle: Option<&str>, dt: Option<f64>) -> ReadOptions {
    let column = |c: Option<&str>| c.map(|c| c.parse().expect("a column"));
    ReadOptions {
        time: column(time),
        angle: column(angle),
        dt,
        ..ReadOptions::default()
    }
}

/// Where the times of a record come from; columns count from 0.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Times {
    /// This column.
    Column(usize),
    /// No column: sample n is at `n · dt`.
    Step(f64),
}

/// The columns the reader took a record's times, values and drive from; whether the data
/// decided which of two columns is the time.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Columns {
    time: Times,
    angle: usize,
    drive: Option<usize>,
    order_from_data: bool,
}

/// Rows of the texts [`columns`] reads.
const ROWS: usize = 20;

/// The value in row `r` of column `c` (from 0): `1000 (c + 1) + r`, or `1000 (c + 1) − r` when
/// the column goes `down`. No column holds the values of another, and none starts at 0.
fn cell(c: usize, r: usize, down: bool) -> f64 {
    let (c, r) = (1000.0 * (c + 1) as f64, r as f64);
    if down { c - r } else { c + r }
}

/// Text of `ROWS` rows of `width` columns of [`cell`]s under the header `names` (if any), the
/// column `down` (if any) going down.
fn table(names: Option<&[&str]>, width: usize, down: Option<usize>) -> String {
    let mut text = names.map_or_else(String::new, |names| names.join(",") + "\n");
    for r in 0..ROWS {
        let row: Vec<String> = (0..width)
            .map(|c| cell(c, r, down == Some(c)).to_string())
            .collect();
        text.push_str(&row.join(","));
        text.push('\n');
    }
    text
}

/// The column (from 0) of [`table`] whose values, going up, are `values`.
fn column_of(values: &[f64]) -> usize {
    let c = (values[0] / 1000.0).round() as usize - 1;
    let column: Vec<f64> = (0..ROWS).map(|r| cell(c, r, false)).collect();
    assert_eq!(values, column, "not a column of the table");
    c
}

/// The columns both readers' one policy takes for these options, the header's `names` (`None`
/// without a header) and `width` columns, as the text reader shows them: every column of the
/// text holds its own numbers, so the record's times, values and drive name the columns they
/// were read from (times from 0 on are a step's). Whether the data decide the order of two
/// columns shows in a second text whose time column goes down: the data would take the value
/// column, uniform, for the time and swap the two. (Without a time column there is nothing to
/// swap: a grid of times is never taken for the values.)
fn columns(options: &ReadOptions, names: Option<&[&str]>, width: usize) -> Result<Columns, InputError> {
    let record = read_bytes(table(names, width, None).as_bytes(), options)?;
    let time = if record.t[0] == 0.0 {
        let dt = record.t[1];
        let grid: Vec<f64> = (0..ROWS).map(|i| i as f64 * dt).collect();
        assert_eq!(record.t, grid, "times neither a column nor a grid");
        Times::Step(dt)
    } else {
        Times::Column(column_of(&record.t))
    };
    let angle = column_of(&record.theta);
    let drive = record.drives.first().map(|d| column_of(d));
    let order_from_data = match time {
        Times::Step(_) => false,
        Times::Column(c) => {
            let swapped = read_bytes(table(names, width, Some(c)).as_bytes(), options)?;
            let down: Vec<f64> = (0..ROWS).map(|r| cell(c, r, true)).collect();
            if swapped.t == down {
                assert_eq!(swapped.theta, record.theta);
                false
            } else {
                assert_eq!((&swapped.t, &swapped.theta), (&record.theta, &down));
                true
            }
        }
    };
    Ok(Columns {
        time,
        angle,
        drive,
        order_from_data,
    })
}

#[test]
fn one_column_policy() {
    let header = Some(&["x", "theta", "t"][..]);
    let at = |time, angle| Columns {
        time,
        angle,
        drive: None,
        order_from_data: false,
    };
    let none = options(None, None, None);
    assert_eq!(columns(&none, header, 3).unwrap(), at(Times::Column(2), 1));
    assert_eq!(columns(&none, None, 3).unwrap(), at(Times::Column(0), 1));
    let step = options(None, None, Some(0.5));
    assert_eq!(columns(&step, header, 3).unwrap(), at(Times::Step(0.5), 1));
    assert_eq!(columns(&step, None, 3).unwrap(), at(Times::Step(0.5), 0));
    assert_eq!(columns(&step, None, 1).unwrap(), at(Times::Step(0.5), 0));
    let chosen = options(Some("3"), Some("x"), None);
    assert_eq!(columns(&chosen, header, 3).unwrap(), at(Times::Column(2), 0));
    // Headerless: time and angle are the first columns not taken by the other.
    assert_eq!(
        columns(&options(None, Some("1"), None), None, 3).unwrap(),
        at(Times::Column(1), 0)
    );
    assert_eq!(
        columns(&options(Some("2"), None, None), None, 3).unwrap(),
        at(Times::Column(1), 0)
    );
    // Two unnamed columns, nothing chosen: the data decide.
    assert_eq!(
        columns(&none, None, 2).unwrap(),
        Columns {
            order_from_data: true,
            ..at(Times::Column(0), 1)
        }
    );
    assert!(
        !columns(&options(None, Some("2"), None), None, 2)
            .unwrap()
            .order_from_data
    );
    // A header without the value names: the only other column, else none.
    assert_eq!(
        columns(&none, Some(&["t", "pos"][..]), 2).unwrap(),
        at(Times::Column(0), 1)
    );
    assert_eq!(
        columns(&step, Some(&["pos"][..]), 1).unwrap(),
        at(Times::Step(0.5), 0)
    );
    assert!(matches!(
        columns(&step, Some(&["a", "b"][..]), 2),
        Err(InputError::MissingColumn {
            role: Role::Angle,
            ..
        })
    ));
    // A single unnamed column needs a step; with a header the defaults are names.
    assert!(matches!(columns(&none, None, 1), Err(InputError::NeedStep)));
    assert!(matches!(
        columns(&none, Some(&["theta"][..]), 1),
        Err(InputError::MissingColumn { .. })
    ));
    // Names need a header; positions count from 1 and stay within the columns.
    for (chosen, names, width) in [
        (options(Some("t"), None, None), None, 2),
        (options(None, Some("4"), None), header, 3),
        (options(None, None, None), None, 1),
    ] {
        match columns(&chosen, names, width) {
            Err(InputError::MissingColumn { .. } | InputError::NeedStep) => {}
            other => panic!("{chosen:?}: {other:?}"),
        }
    }
    // Position 0 never reaches the policy: the options are checked first (and no column option
    // parses to it).
    let zero = ReadOptions {
        angle: Some(Column::Position(0)),
        ..step.clone()
    };
    assert!(matches!(
        columns(&zero, None, 2),
        Err(InputError::BadColumn { .. })
    ));
}

#[test]
fn both_readers_follow_the_same_policy() {
    let rows: [[f64; 3]; 3] = [[0.0, 0.1, 0.2], [1.0, 1.1, 1.2], [2.0, 2.1, 2.2]];
    let text: String = rows
        .iter()
        .map(|r| format!("{},{},{}\n", r[0], r[1], r[2]))
        .collect();
    let payload: Vec<u8> = rows.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    let array = npy_bytes("<f8", "(3, 3)", false, &payload);
    let first: Vec<u8> = rows.iter().flat_map(|r| r[0].to_le_bytes()).collect();
    let single = npy_bytes("<f8", "(3,)", false, &first);
    let cases = [
        (options(None, None, None), 3),
        (options(None, None, Some(0.5)), 3),
        (options(Some("2"), Some("3"), None), 3),
        (options(None, Some("4"), None), 3),
        (options(Some("t"), None, None), 3),
        (options(None, Some("theta"), Some(0.5)), 3),
        (options(None, None, None), 1),
        (options(None, None, Some(0.5)), 1),
        (options(Some("1"), None, None), 1),
    ];
    for (options, width) in cases {
        let (text, npy) = if width == 3 {
            (text.clone(), &array)
        } else {
            (rows.iter().map(|r| format!("{}\n", r[0])).collect(), &single)
        };
        match (read_bytes(text.as_bytes(), &options), read_bytes(npy, &options)) {
            (Ok(a), Ok(b)) => assert_eq!((a.t, a.theta), (b.t, b.theta), "{options:?}"),
            (Err(a), Err(b)) => assert_eq!(a.to_string(), b.to_string(), "{options:?}"),
            other => panic!("{options:?}, {width} columns: {other:?}"),
        }
    }
}

#[test]
fn two_unnamed_columns_in_either_order_in_both_readers() {
    let n = 200;
    let dt = 1.0 / 2048.0;
    let time: Vec<f64> = (0..n).map(|i| 100.0 + i as f64 * dt).collect();
    let angle: Vec<f64> = (0..n).map(|i| 3.0 * (i as f64 * 0.05).cos()).collect();
    let npy = |a: &[f64], b: &[f64]| {
        let payload: Vec<u8> = a
            .iter()
            .zip(b)
            .flat_map(|(x, y)| [x.to_le_bytes(), y.to_le_bytes()])
            .flatten()
            .collect();
        npy_bytes("<f8", &format!("({n}, 2)"), false, &payload)
    };
    let text =
        |a: &[f64], b: &[f64]| -> String { a.iter().zip(b).map(|(x, y)| format!("{x} {y}\n")).collect() };
    for bytes in [
        npy(&time, &angle),
        npy(&angle, &time),
        text(&time, &angle).into_bytes(),
        text(&angle, &time).into_bytes(),
    ] {
        let r = read_bytes(&bytes, &ReadOptions::default()).unwrap();
        assert_eq!((&r.t, &r.theta), (&time, &angle));
    }
    // Chosen columns are taken as they are.
    let chosen = options(Some("2"), Some("1"), None);
    let r = read_bytes(&npy(&time, &angle), &chosen).unwrap();
    assert_eq!((&r.t, &r.theta), (&angle, &time));
    // A time column with a gap and a glitch is still the time.
    let mut stamps = time.clone();
    stamps.drain(50..60);
    stamps[100] += 0.4 * dt;
    let r = read_bytes(text(&angle[..190], &stamps).as_bytes(), &ReadOptions::default()).unwrap();
    assert_eq!(r.t, stamps);
}

#[test]
#[expect(clippy::approx_constant, reason = "π and 2π as printed")]
fn angle_ranges_allow_printing() {
    use std::f64::consts::{PI, TAU};
    let wrapped: Vec<f64> = (0..100).map(|i| -PI + i as f64 * TAU / 100.0).collect();
    let from_zero: Vec<f64> = wrapped.iter().map(|v| v + PI).collect();
    assert_eq!(angle_range(&wrapped), AngleRange::Wrapped);
    assert_eq!(angle_range(&from_zero), AngleRange::FromZero);
    assert_eq!(angle_range(&[0.0, 1.0, 6.283186]), AngleRange::FromZero);
    assert_eq!(angle_range(&[-3.141593, 0.0, 3.141593]), AngleRange::Wrapped);
    // Three decimals: half of 0.001 is allowed.
    assert_eq!(angle_range(&[-3.142, 0.5, 3.142]), AngleRange::Wrapped);
    assert_eq!(angle_range(&[0.0, 6.283]), AngleRange::FromZero);
    assert_eq!(angle_range(&[0.0, 6.284]), AngleRange::Unwrapped);
    // Past the tolerance: unwrapped.
    assert_eq!(angle_range(&[0.0, 3.1416926535]), AngleRange::FromZero);
    assert_eq!(angle_range(&[-0.1, 3.2]), AngleRange::Unwrapped);
    assert_eq!(angle_range(&[0.0, 6.2832853071]), AngleRange::Unwrapped);
    assert_eq!(angle_range(&[0.0, 6.29]), AngleRange::Unwrapped);
    assert_eq!(angle_range(&[-3.2, 0.0]), AngleRange::Unwrapped);
    assert_eq!(angle_range(&[]), AngleRange::Wrapped);
    // The fewest decimals that write every value (at most 9), as a record of stamps that repeat
    // (so that the median step is 0) names them.
    let decimals = |values: &[f64]| {
        let t: Vec<f64> = values.iter().flat_map(|&v| [v; 3]).collect();
        let record = Record {
            theta: vec![0.0; t.len()],
            t,
            ..Record::default()
        };
        match GridRecord::fit(record, &GridOptions::default()) {
            Err(InputError::TimeUnresolved { decimals, .. }) => decimals,
            other => panic!("{values:?}: {other:?}"),
        }
    };
    assert_eq!(decimals(&[0.25, 1.5, -3.125]), Some(3));
    assert_eq!(decimals(&[PI]), None);
}

#[test]
fn options_are_checked_before_reading() {
    let bad = options(None, None, Some(-1.0));
    assert!(matches!(
        read_path(Path::new("/no/such/file.csv"), &bad),
        Err(InputError::BadStep { .. })
    ));
    let both = options(Some("1"), None, Some(1.0));
    assert!(matches!(read_bytes(b"1,2\n", &both), Err(InputError::TimeTwice)));
    // A step whose samples' times overflow (found by the fuzz target `text_options`: 25
    // samples of step 2.2e307 were read with infinite times), in both readers.
    let huge = options(None, None, Some(2.2284457792544677e307));
    let text: String = (0..25).map(|i| format!("{i}\n")).collect();
    let npy = npy_bytes("<f8", "(25,)", false, &[0; 200]);
    for bytes in [text.as_bytes(), &npy] {
        match read_bytes(bytes, &huge) {
            Err(e @ InputError::StepOverflow { samples: 25, .. }) => {
                assert!(
                    e.to_string()
                        .starts_with("25 samples of step 2.2284457792544677e307"),
                    "{e}"
                )
            }
            other => panic!("{other:?}"),
        }
        let fits = read_bytes(bytes, &options(None, None, Some(1e300))).unwrap();
        assert_eq!(fits.t[24], 24.0 * 1e300);
    }
    // Position 0 (which no column option parses to) is refused like the text "0", before
    // the column policy counts back from it (found by the fuzz target `text_options`: it
    // underflowed for headerless text).
    for zero in [
        ReadOptions {
            angle: Some(Column::Position(0)),
            ..Default::default()
        },
        ReadOptions {
            time: Some(Column::Position(0)),
            ..Default::default()
        },
        ReadOptions {
            angle: Some(Column::Position(0)),
            dt: Some(0.5),
            ..Default::default()
        },
    ] {
        for bytes in [
            &b"0,1\n1,2\n2,3\n"[..],
            &npy_bytes("<f8", "(1, 2)", false, &[0; 16]),
        ] {
            match read_bytes(bytes, &zero) {
                Err(e @ InputError::BadColumn { .. }) => assert!(e.to_string().starts_with("'0'"), "{e}"),
                other => panic!("{zero:?}: {other:?}"),
            }
        }
    }
}
