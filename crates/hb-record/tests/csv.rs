//! The text reader: comments, headers, separators, default and chosen columns, a drive column,
//! and the errors that name the line and column of what is wrong.
use hb_record::input::{Column, InputError, Location, ReadOptions, Record, Role, Separator, read_bytes};

use crate::common::{is_about_the_content, npy_bytes};

fn read(text: &str) -> Result<Record, InputError> {
    read_bytes(text.as_bytes(), &ReadOptions::default())
}

fn with(text: &str, options: ReadOptions) -> Result<Record, InputError> {
    read_bytes(text.as_bytes(), &options)
}

/// A drive column is read beside the angle, by name or position, in text and `.npy`; it may
/// not be the time or the angle, and a bad cell in it names its line.
#[test]
fn reads_a_drive_column_beside_the_angle() {
    let drive = |c: &str| ReadOptions {
        drives: vec![c.parse().unwrap()],
        ..Default::default()
    };
    let text = "t,theta,omega,acc\n0,0.1,0,5\n# c\n0.5,0.2,1,-6\n";
    for chosen in ["acc", "4"] {
        let r = with(text, drive(chosen)).unwrap();
        assert_eq!((r.theta, r.drives), (vec![0.1, 0.2], vec![vec![5.0, -6.0]]));
    }
    assert!(read(text).unwrap().drives.is_empty());
    for taken in ["t", "theta", "1"] {
        assert!(matches!(
            with(text, drive(taken)),
            Err(InputError::ColumnTwice {
                second: Role::Drive,
                ..
            })
        ));
    }
    assert!(matches!(
        with(text, drive("p")),
        Err(InputError::MissingColumn {
            role: Role::Drive,
            ..
        })
    ));
    // Nor may the angle be the time (it was read as both, and failed later as a fit that
    // cannot tell its terms apart).
    for (time, angle) in [("1", "1"), ("t", "t"), ("t", "1")] {
        let options = ReadOptions {
            time: Some(time.parse().unwrap()),
            angle: Some(angle.parse().unwrap()),
            ..Default::default()
        };
        match with(text, options) {
            Err(
                e @ InputError::ColumnTwice {
                    first: Role::Time,
                    second: Role::Angle,
                    ..
                },
            ) => assert!(e.to_string().contains("both the time and the angle"), "{e}"),
            other => panic!("{time}, {angle}: {other:?}"),
        }
    }
    match with("t,theta,p\n0,1,2\n1,2,x\n", drive("p")) {
        Err(e @ InputError::NotANumber { line: 3, .. }) => assert!(e.to_string().contains("'p'"), "{e}"),
        other => panic!("{other:?}"),
    }
    // Two unnamed columns and a drive: no guessing of the order, the time is column 1.
    let r = with("0.1,0,7\n0.2,1,8\n", drive("3")).unwrap();
    assert_eq!((r.t, r.drives), (vec![0.1, 0.2], vec![vec![7.0, 8.0]]));
    // .npy: rows (t, x, p).
    let f8: Vec<u8> = [0.0f64, 0.5, 9.0, 1.0, 0.6, f64::NAN]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let npy = npy_bytes("<f8", "(2, 3)", false, &f8);
    assert!(matches!(
        read_bytes(&npy, &drive("3")),
        Err(InputError::NonFinite {
            role: Role::Drive,
            ..
        })
    ));
    let f8: Vec<u8> = [0.0f64, 0.5, 9.0, 1.0, 0.6, 8.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let npy = npy_bytes("<f8", "(2, 3)", false, &f8);
    assert_eq!(
        read_bytes(&npy, &drive("3")).unwrap().drives,
        vec![vec![9.0, 8.0]]
    );
}

/// A column chosen by a name the header gives twice is refused, naming both positions; by its
/// position, or when the name chosen is another, the record reads.
#[test]
fn a_name_the_header_gives_twice_is_ambiguous() {
    let text = "t,theta,omega,theta\n0,0.1,0,5\n0.5,0.2,1,-6\n";
    let e = read(text).unwrap_err();
    assert!(
        matches!(&e, InputError::AmbiguousColumn { role: Role::Angle, name, positions } if name == "theta" && positions == &[2, 4]),
        "{e:?}"
    );
    assert_eq!(
        e.to_string(),
        "the angle column 'theta' is ambiguous: the header names columns 2 and 4 so (choose one by its position)"
    );
    let by_position = ReadOptions {
        angle: Some("4".parse().unwrap()),
        ..Default::default()
    };
    assert_eq!(with(text, by_position).unwrap().theta, vec![5.0, -6.0]);
    let e = read("t,theta,t\n0,1,2\n1,2,3\n").unwrap_err();
    assert!(
        matches!(e, InputError::AmbiguousColumn { role: Role::Time, .. }),
        "{e:?}"
    );
    // Names the reader does not look up may repeat.
    assert_eq!(
        read("t,theta,v,v\n0,1,2,3\n1,2,3,4\n").unwrap().theta,
        vec![1.0, 2.0]
    );
}

#[test]
fn reads_with_comments_and_extra_columns() {
    let r = read("# a comment\nt,theta,omega\n0,0.1,0\n# mid\n0.5,-3.0,1e-3\n").unwrap();
    assert_eq!(r.t, vec![0.0, 0.5]);
    assert_eq!(r.theta, vec![0.1, -3.0]);
    assert_eq!(r.lines, Some(vec![3, 5]));
    let r = read("theta, t\n1,2\n").unwrap();
    assert_eq!((r.t[0], r.theta[0]), (2.0, 1.0));
    // Windows line ends, a byte-order mark, quoted names, blank lines.
    let r = read("\u{feff}\"t\",\"theta\"\r\n\r\n0,1\r\n0.5,2\r\n").unwrap();
    assert_eq!(
        (r.t, r.theta, r.lines),
        (vec![0.0, 0.5], vec![1.0, 2.0], Some(vec![3, 4]))
    );
}

/// A row of the columns' units under the header (as a data-acquisition export writes it) is
/// passed like the header, its lines counted; a row under the header with a number in it is
/// data, and its other cells name their line; without a header no row is units.
#[test]
fn a_row_of_units_under_the_header_is_passed() {
    let r = read("# export\nt,theta,tau\ns,rad,N m\n0,0.1,2\n0.5,0.2,3\n").unwrap();
    assert_eq!(
        (r.t, r.theta, r.lines),
        (vec![0.0, 0.5], vec![0.1, 0.2], Some(vec![4, 5]))
    );
    let r = read("t;theta\n[s];[rad]\n0;0,1\n0,5;0,2\n").unwrap();
    assert_eq!((r.t, r.theta), (vec![0.0, 0.5], vec![0.1, 0.2]));
    assert!(matches!(
        read("t,theta\n0,rad\n0.5,0.2\n"),
        Err(InputError::NotANumber { line: 2, .. })
    ));
    // Only the row right under the header.
    assert!(matches!(
        read("t,theta\ns,rad\n0,0.1\ns,rad\n"),
        Err(InputError::NotANumber { line: 4, .. })
    ));
    assert!(matches!(
        read("0,0.1\ns,rad\n"),
        Err(InputError::NotANumber { line: 2, .. })
    ));
    // Missing values are no units: the row stays data, and is refused as such.
    for missing in ["NA,NA", ",", "null,", "N/A,rad"] {
        let text = format!("t,theta\n{missing}\n0,0.1\n0.5,0.2\n");
        assert!(read(&text).is_err(), "{missing}");
    }
    // Units with a space, or one left out, in a text of tabs whose names have no spaces.
    for units in ["s\trad\trad s-1", "s\t\trad/s", "[s]\t[rad]\t[rad/s]"] {
        let text = format!("t\ttheta\tomega\n{units}\n0\t0.1\t1\n0.5\t0.2\t2\n");
        let r = read(&text).unwrap_or_else(|e| panic!("{units:?}: {e}"));
        assert_eq!((r.t, r.theta), (vec![0.0, 0.5], vec![0.1, 0.2]), "{units:?}");
    }
    let r = read("t,theta,omega\ns,,rad/s\n0,0.1,1\n").unwrap();
    assert_eq!(r.theta, vec![0.1]);
    // Quoted numbers under a header of tabs are data.
    let r = read("t\ttheta\n\"0\"\t\"0.1\"\n\"0.5\"\t\"0.2\"\n").unwrap();
    assert_eq!((r.t, r.theta), (vec![0.0, 0.5], vec![0.1, 0.2]));
}

#[test]
fn whitespace_semicolons_and_tabs_separate_cells() {
    let expected = (vec![0.0, 0.5, 1.0], vec![0.1, -0.2, 0.3]);
    for text in [
        "t theta\n0 0.1\n0.5 -0.2\n1 0.3\n",
        "   t    theta  \n  0   0.1\n0.5     -0.2   \n 1 0.3 \n",
        "t\ttheta\n0\t0.1\n0.5\t-0.2\n1\t0.3\n",
        "t \t theta\n0\t\t0.1\n0.5 \t-0.2\n1 0.3\n",
        "t;theta\n0;0.1\n0.5;-0.2\n1;0.3\n",
        "t ; theta\n0; 0,1\n0,5 ;-0,2\n1;0.3\n",
        "0 0.1\n0.5 -0.2\n1 0.3\n",
        "0;0.1\n0.5;-0.2\n1;0.3\n",
        // Line ends: CR LF, and CR alone.
        "t,theta\r\n0,0.1\r\n0.5,-0.2\r\n1,0.3\r\n",
        "t,theta\r0,0.1\r0.5,-0.2\r1,0.3\r",
    ] {
        let r = read(text).unwrap_or_else(|e| panic!("{text:?}: {e}"));
        assert_eq!((r.t, r.theta), expected, "{text:?}");
    }
    // A header whose names hold spaces between tabs (units): tabs alone separate, spaces and
    // runs of tabs about a cell are not cells of their own.
    let named = ReadOptions {
        time: Some("time [s]".parse().unwrap()),
        angle: Some("angle [rad]".parse().unwrap()),
        ..Default::default()
    };
    for text in [
        "time [s]\tangle [rad]\n0\t0.1\n0.5\t\t-0.2\n1 \t 0.3\n",
        "\"time [s]\"\t\"angle [rad]\"\tstatus flag\n0\t0.1\tok\n0.5\t-0.2\tSYNC LOST\n1\t0.3\tok\n",
    ] {
        let r = with(text, named.clone()).unwrap_or_else(|e| panic!("{text:?}: {e}"));
        assert_eq!((r.t, r.theta), expected, "{text:?}");
    }
    // Separators between double quotes are a cell's own (a header's units after a comma).
    let quoted = ReadOptions {
        time: Some("Time, s".parse().unwrap()),
        angle: Some("Angle, rad".parse().unwrap()),
        ..Default::default()
    };
    for text in [
        "\"Time, s\",\"Angle, rad\"\n0,0.1\n0.5,-0.2\n1,0.3\n",
        "\"Time, s\"\t\"Angle, rad\"\n0\t0.1\n0.5\t-0.2\n1\t0.3\n",
        "\"Time, s\";\"Angle, rad\"\n0;0,1\n0,5;-0,2\n1;0,3\n",
    ] {
        let r = with(text, quoted.clone()).unwrap_or_else(|e| panic!("{text:?}: {e}"));
        assert_eq!((r.t, r.theta), expected, "{text:?}");
    }
    // A single column with the step: white space around it is no separator.
    let step = ReadOptions {
        dt: Some(0.5),
        ..Default::default()
    };
    assert_eq!(with("  1.5\n2.5  \n", step).unwrap().theta, vec![1.5, 2.5]);
}

#[test]
fn mixed_separators_name_the_line() {
    for (text, line, expected, found) in [
        ("0,1\n1,2\n2 3\n", 3, Separator::Comma, Separator::Whitespace),
        (
            "t theta\n0 1\n1;2\n",
            3,
            Separator::Whitespace,
            Separator::Semicolon,
        ),
        (
            "t;theta\n0;1\n# c\n1,2\n",
            4,
            Separator::Semicolon,
            Separator::Comma,
        ),
        ("0\t1\n1\t2\n2,3\n", 3, Separator::Whitespace, Separator::Comma),
    ] {
        match read(text) {
            Err(e @ InputError::MixedSeparators { .. }) => {
                assert_eq!(
                    e.to_string(),
                    format!("line {line}: cells separated by {found} where the first row uses {expected}"),
                );
            }
            other => panic!("{text:?}: {other:?}"),
        }
    }
}

#[test]
fn headerless_and_column_choices() {
    let r = read("0,1.5\n1,2.5\n").unwrap();
    assert_eq!((r.t.clone(), r.theta.clone()), (vec![0.0, 1.0], vec![1.5, 2.5]));
    let opts = ReadOptions {
        dt: Some(0.5),
        ..Default::default()
    };
    let r = with("1.5\n2.5\n3.5\n", opts.clone()).unwrap();
    assert_eq!(r.t, vec![0.0, 0.5, 1.0]);
    assert!(matches!(read("1.5\n2.5\n"), Err(InputError::NeedStep)));
    let opts = ReadOptions {
        time: Some("time".parse().unwrap()),
        angle: Some("3".parse().unwrap()),
        ..Default::default()
    };
    let r = with("time,x,angle\n0,9,1\n1,9,2\n", opts).unwrap();
    assert_eq!(r.theta, vec![1.0, 2.0]);
    assert!("0".parse::<Column>().is_err());
    assert!("".parse::<Column>().is_err());
    let both = ReadOptions {
        time: Some(Column::Position(1)),
        dt: Some(1.0),
        ..Default::default()
    };
    assert!(matches!(with("1,2\n", both), Err(InputError::TimeTwice)));
}

#[test]
fn default_value_columns() {
    // theta first, then x, then angle; else the only column besides the time.
    for (header, expected) in [
        ("t,x,theta", 3.0),
        ("angle,t,x", 3.0),
        ("angle,t,y", 1.0),
        ("t,position", 2.0),
        ("volts,t", 1.0),
    ] {
        // Row 1 holds each column's position.
        let width = header.split(',').count();
        let row: Vec<String> = (1..=width).map(|c| c.to_string()).collect();
        let text = format!("{header}\n{}\n", row.join(","));
        let r = read(&text).unwrap_or_else(|e| panic!("{header}: {e}"));
        assert_eq!(r.theta[0], expected, "{header}");
    }
    // Three columns and none of the names: nothing to guess.
    assert!(matches!(
        read("t,a,b\n0,1,2\n"),
        Err(InputError::MissingColumn {
            role: Role::Angle,
            ..
        })
    ));
    // An explicit choice still wins.
    let chosen = ReadOptions {
        angle: Some(Column::Name("a".into())),
        ..Default::default()
    };
    assert_eq!(with("t,a,x\n0,1,2\n", chosen).unwrap().theta, vec![1.0]);
}

#[test]
fn headerless_columns_in_either_order() {
    let n = 50;
    let dt = 1.0 / 2048.0;
    let angle = |i: usize| 2.5 * (i as f64 * 0.3).sin();
    let time_first: String = (0..n)
        .map(|i| format!("{:.4} {:.6}\n", 3.0 + i as f64 * dt, angle(i)))
        .collect();
    let angle_first: String = (0..n)
        .map(|i| format!("{:.6}\t{:.4}\n", angle(i), 3.0 + i as f64 * dt))
        .collect();
    let a = read(&time_first).unwrap();
    let b = read(&angle_first).unwrap();
    assert_eq!((&a.t, &a.theta), (&b.t, &b.theta));
    assert!((a.t[1] - a.t[0] - dt).abs() < 1e-4 && (a.theta[1] - angle(1)).abs() < 1e-6);
    // A value column as uniform as the time leaves the default: column 1 is the time.
    let ramps: String = (0..n).map(|i| format!("{} {}\n", 2 * i, i)).collect();
    assert_eq!(read(&ramps).unwrap().t[1], 2.0);
}

#[test]
fn bad_inputs_are_named() {
    assert!(matches!(read(""), Err(InputError::Empty)));
    assert!(matches!(read("# only a comment\n"), Err(InputError::Empty)));
    assert!(matches!(read("t,theta\n"), Err(InputError::NoData)));
    assert!(matches!(
        read("time,angle\n1,2\n"),
        Err(InputError::MissingColumn { .. })
    ));
    match read("t,theta\n0,1\n1,abc\n") {
        Err(InputError::NotANumber { line: 3, .. }) => {}
        other => panic!("{other:?}"),
    }
    match read("t,theta\n0,1\n1,NaN\n") {
        Err(InputError::NonFinite { at, .. }) if at == Location::Line(3) && at.to_string() == "line 3" => {}
        other => panic!("{other:?}"),
    }
    match read("t,theta\n0,1\n1,inf\n") {
        Err(InputError::NonFinite { .. }) => {}
        other => panic!("{other:?}"),
    }
    match read("t,theta\n0,1\n1\n") {
        Err(InputError::Ragged {
            line: 3,
            expected: 2,
            found: 1,
        }) => {}
        other => panic!("{other:?}"),
    }
    // A decimal comma only where semicolons separate the cells.
    assert!(matches!(
        read("t theta\n0 1,5\n"),
        Err(InputError::MixedSeparators { .. })
    ));
    assert!(read_bytes(&[0xff, 0xfe, 0x00, 0x01], &ReadOptions::default()).is_err());
}

#[test]
fn a_time_column_is_reported_as_a_time_whatever_its_name() {
    let named = ReadOptions {
        time: Some(Column::Name("time".into())),
        angle: Some(Column::Name("angle".into())),
        ..Default::default()
    };
    let unnamed = ReadOptions::default();
    for (text, options, role, line, says) in [
        (
            "time,angle\n0,1\nnan,2\n",
            &named,
            Role::Time,
            3,
            "the time is NaN in column 'time'",
        ),
        (
            "time,angle\n0,1\n1,inf\n",
            &named,
            Role::Angle,
            3,
            "a value is inf in column 'angle'",
        ),
        (
            "0,1,2\n-inf,2,3\n",
            &unnamed,
            Role::Time,
            2,
            "the time is -inf in column 1",
        ),
        // Two unnamed columns: which is the time is not known yet.
        ("0,1\n-inf,2\n", &unnamed, Role::Angle, 2, "a value is -inf"),
    ] {
        match read_bytes(text.as_bytes(), options) {
            Err(e @ InputError::NonFinite { role: r, at, .. }) if r == role && at == Location::Line(line) => {
                assert!(e.to_string().contains(says), "{e}");
            }
            other => panic!("{text:?}: {other:?}"),
        }
    }
}

#[test]
fn bad_cells_name_their_column() {
    match read("time,theta,t\n0,1,2\n1,x,3\n") {
        Err(InputError::NotANumber {
            line: 3,
            column,
            value,
            missing: false,
        }) => {
            assert_eq!((column, value.as_str()), (Column::Name("theta".into()), "x"));
        }
        other => panic!("{other:?}"),
    }
    match read("0,1\nx,2\n") {
        Err(InputError::NotANumber { column, .. }) => assert_eq!(column, Column::Position(1)),
        other => panic!("{other:?}"),
    }
}

#[test]
fn binary_data_is_named() {
    match read_bytes(&[b'1', b',', 0xff, 0xfe, b'\n'], &ReadOptions::default()) {
        Err(e @ InputError::Malformed { line: 1, .. }) => {
            assert!(e.to_string().contains("binary data"), "{e}");
            assert!(std::error::Error::source(&e).is_some());
        }
        other => panic!("{other:?}"),
    }
}

proptest::proptest! {
    #[test]
    fn csv_never_panics_on_arbitrary_bytes(bytes in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..300)) {
        for options in [ReadOptions::default(), ReadOptions { dt: Some(0.1), ..Default::default() }] {
            if let Err(e) = read_bytes(&bytes, &options) {
                proptest::prop_assert!(is_about_the_content(&e), "{e:?}");
            }
        }
    }

    #[test]
    fn csv_round_trips_numbers(
        values in proptest::collection::vec(-1e6..1e6f64, 1..50),
        separator in proptest::sample::select(vec![",", ";", " ", "\t", "  \t "]),
    ) {
        let mut text = format!("t{separator}theta\n");
        for (i, v) in values.iter().enumerate() {
            text.push_str(&format!("{i}{separator}{v}\n"));
        }
        let r = read_bytes(text.as_bytes(), &ReadOptions::default()).unwrap();
        proptest::prop_assert_eq!(r.theta, values);
    }
}

/// A cell's number is the one `str::parse` reads (the rows of numbers only are parsed as they
/// are split), and a cell it does not read is an error naming its line, in rows of numbers only
/// and beside quoted, spaced or decimal-comma cells alike.
#[test]
fn every_cell_reads_as_str_parse_reads_it() {
    let cells = [
        "1",
        "-0",
        "+1.5",
        ".5",
        "5.",
        "1e5",
        "1E-5",
        "1.5e+3",
        "-2.5e-310",
        "1e308",
        "1e309",
        "4.9e-324",
        "2.2250738585072011e-308",
        "0.1000000000000000055511151231257827",
        "123456789012345678901234567890",
        "1e",
        "e5",
        ".",
        "+",
        "-",
        "1.5e+",
        "0x10",
        "1_0",
        "inf",
        "-infinity",
        "NaN",
        "1.2.3",
        "--1",
        "1e5x",
    ];
    for cell in cells {
        let text = format!("t,theta,omega\n0,{cell},2\n1,{cell},3\n");
        let got = read(&text);
        match cell.parse::<f64>() {
            Ok(v) if v.is_finite() => {
                let theta = got.unwrap_or_else(|e| panic!("{cell}: {e}")).theta;
                assert_eq!(
                    theta.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                    [v.to_bits(); 2],
                    "{cell}"
                );
            }
            Ok(_) => assert!(
                matches!(got, Err(InputError::NonFinite { .. })),
                "{cell}: {got:?}"
            ),
            Err(_) => assert!(
                matches!(got, Err(InputError::NotANumber { line: 2, .. })),
                "{cell}: {got:?}"
            ),
        }
    }
    // A row of numbers only next to rows the general path reads: the same values.
    let text = "t;theta\n0;1,25\n1;1.25\n2;\"1.25\"\n3; 1.25\n";
    assert_eq!(read(text).unwrap().theta, [1.25; 4]);
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig {
        cases: 256,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x0c5f_0a57),
        ..proptest::prelude::ProptestConfig::default()
    })]

    /// Rows of any cells (numbers in several spellings, near-numbers, text, spaces, quotes,
    /// decimal commas, empty cells) with commas, semicolons or white space: every row read in
    /// one pass is read the general way too in this (debug) build and must give the same
    /// numbers, and no row panics.
    #[test]
    fn any_row_reads_as_the_general_path_reads_it(
        rows in proptest::collection::vec(proptest::collection::vec(0usize..18, 2..4), 1..12),
        numbers in proptest::collection::vec(-1e6..1e6f64, 40),
        separator in 0usize..5,
    ) {
        let separator = [",", ";", " ", "\t", " \t  "][separator];
        let spell = |kind: usize, v: f64| match kind {
            0..=5 => format!("{v}"),
            6 => format!("{v:e}"),
            7 => format!("{v:.3}"),
            8 => "1e".to_owned(),
            9 => "+.5".to_owned(),
            10 => "0x1F".to_owned(),
            11 => "inf".to_owned(),
            12 => format!(" {v}"),
            13 => format!("\"{v}\""),
            14 => String::new(),
            15 => "1,5".to_owned(),
            16 => "abc".to_owned(),
            _ => format!("{v}e-3"),
        };
        let mut text = String::from("t,theta\n").replace(',', separator);
        for (r, row) in rows.iter().enumerate() {
            let cells: Vec<String> = row
                .iter()
                .enumerate()
                .map(|(c, &k)| spell(k, numbers[(r * 3 + c) % 40]))
                .collect();
            text.push_str(&cells.join(separator));
            text.push('\n');
        }
        let _ = read(&text);
    }

    /// Any finite numbers, written as a logger writes them (shortest, fixed, scientific), are
    /// read to the bit as `str::parse` reads their text.
    #[test]
    fn numbers_read_to_the_bit(
        values in proptest::collection::vec(
            proptest::num::f64::NORMAL | proptest::num::f64::SUBNORMAL | proptest::num::f64::ZERO,
            1..40,
        ),
        style in 0usize..4,
    ) {
        let write = |v: f64| match style {
            0 => format!("{v}"),
            1 => format!("{v:e}"),
            2 => format!("{v:.6}"),
            _ => format!("{v:.17E}"),
        };
        let mut text = String::from("t,theta\n");
        for (i, &v) in values.iter().enumerate() {
            text.push_str(&format!("{i},{}\n", write(v)));
        }
        let theta = read(&text).unwrap().theta;
        for (&got, &v) in theta.iter().zip(&values) {
            proptest::prop_assert_eq!(got.to_bits(), write(v).parse::<f64>().unwrap().to_bits());
        }
    }
}

/// A missing value in a column read (an empty cell, a marker, a NaN) is an error naming its line
/// and how to read the record without its row; with `skip_missing` the row is left out and
/// listed, its time a gap's (with a sampling step the other rows keep their places), a missing
/// value in a column not read changes nothing, and an infinity stays an error.
#[test]
fn rows_with_a_missing_value_are_left_out_on_request() {
    let text = "t,theta,p,unused\n0,0.1,1,\n0.5,,2,x\n1,0.3,NA,0\n1.5,0.4,4,\n2,nan,5,1\n2.5,0.6,6,NaN\n";
    let drive = |skip: bool| ReadOptions {
        drives: vec!["p".parse().unwrap()],
        skip_missing: skip,
        ..ReadOptions::default()
    };
    let hint =
        "(a missing value: «skip_missing=True» leaves out every row with one, as a logger's dropped row)";
    {
        let (err, line, column) = (with(text, drive(false)).unwrap_err(), 3, "'theta'");
        assert!(
            matches!(&err, InputError::NotANumber { line: l, missing: true, .. } if *l == line),
            "{err:?}"
        );
        let said = err.to_string();
        assert!(said.contains(column) && said.ends_with(hint), "{said}");
    }
    // NaN parses: it is named as a value that is not finite, with the same hint.
    let nan = with("t,theta\n0,0.1\n0.5,NaN\n", ReadOptions::default()).unwrap_err();
    assert!(nan.to_string().ends_with(hint), "{nan}");
    // A word that is no marker of a missing value is not one.
    let word = with("t,theta\n0,0.1\n0.5,oops\n", ReadOptions::default()).unwrap_err();
    assert!(!word.to_string().contains("skip_missing"), "{word}");

    let r = with(text, drive(true)).unwrap();
    assert_eq!(r.t, vec![0.0, 1.5, 2.5]);
    assert_eq!(r.theta, vec![0.1, 0.4, 0.6]);
    assert_eq!(r.drives, vec![vec![1.0, 4.0, 6.0]]);
    assert_eq!(r.lines, Some(vec![2, 5, 7]));
    assert_eq!(
        r.missing,
        vec![Location::Line(3), Location::Line(4), Location::Line(6)]
    );
    // With a sampling step and no time column, the rows kept keep their places.
    let stepped = ReadOptions {
        dt: Some(0.5),
        angle: Some("theta".parse().unwrap()),
        skip_missing: true,
        ..ReadOptions::default()
    };
    // (A blank line is no row: a single column's empty cell cannot be told from one.)
    let r = with("theta\n0.1\n\n0.2\nNA\n0.4\n", stepped).unwrap();
    assert_eq!((r.t, r.theta), (vec![0.0, 0.5, 1.5], vec![0.1, 0.2, 0.4]));
    // Every row missing a value: no row is left, said so.
    assert!(matches!(
        with(
            "t,theta\n0,\n1,NA\n",
            ReadOptions {
                skip_missing: true,
                ..ReadOptions::default()
            }
        ),
        Err(InputError::AllMissing { rows: 2 })
    ));
    // An infinity is a value out of range, not a missing one.
    let inf = with(
        "t,theta\n0,0.1\n0.5,inf\n",
        ReadOptions {
            skip_missing: true,
            ..ReadOptions::default()
        },
    );
    assert!(matches!(inf, Err(InputError::NonFinite { .. })), "{inf:?}");
}

/// A missing value in the first row of data is data, not a header or a row of units: a
/// headerless first row of numbers and missing values, a lone `NA` first, and a row under the
/// header whose columns read are empty (whatever a column not read holds).
#[test]
fn a_missing_value_in_the_first_row_of_data_is_no_header() {
    let skip = |options: ReadOptions| ReadOptions {
        skip_missing: true,
        ..options
    };
    let err = read("0,NA\n0.1,0.2\n0.2,0.3\n").unwrap_err();
    assert!(
        matches!(
            err,
            InputError::NotANumber {
                line: 1,
                missing: true,
                ..
            }
        ),
        "{err:?}"
    );
    let r = with("0,NA\n0.1,0.2\n0.2,0.3\n", skip(ReadOptions::default())).unwrap();
    assert_eq!((r.t, r.missing), (vec![0.1, 0.2], vec![Location::Line(1)]));
    let stepped = ReadOptions {
        dt: Some(0.5),
        ..ReadOptions::default()
    };
    let r = with("NA\n0.2\n0.3\n0.4\n", skip(stepped.clone())).unwrap();
    assert_eq!((r.t, r.theta), (vec![0.5, 1.0, 1.5], vec![0.2, 0.3, 0.4]));
    assert_eq!(r.missing, vec![Location::Line(1)]);
    let labelled = ReadOptions {
        dt: Some(1.0),
        angle: Some("x".parse().unwrap()),
        ..ReadOptions::default()
    };
    let text = "x,label\n,start\n0.1,a\n0.2,b\n,c\n0.4,d\n";
    assert!(matches!(
        with(text, labelled.clone()),
        Err(InputError::NotANumber {
            line: 2,
            missing: true,
            ..
        })
    ));
    let r = with(text, skip(labelled)).unwrap();
    assert_eq!((r.t, r.theta), (vec![1.0, 2.0, 4.0], vec![0.1, 0.2, 0.4]));
    assert_eq!(r.missing, vec![Location::Line(2), Location::Line(5)]);
    // A row of units is still one when a column read names its unit.
    let r = with(
        "t,theta,label\ns,rad,\n0,0.1,a\n1,0.2,b\n",
        ReadOptions::default(),
    )
    .unwrap();
    assert_eq!(r.t, vec![0.0, 1.0]);
}

/// pandas' header of an unnamed index column and numbered columns (`,0,1,2`) is a header, and
/// both readers of a header agree on it.
#[test]
fn an_empty_name_beside_numbered_columns_is_a_header() {
    let text = ",0,1,2\n0,0.0,0.1,5\n1,0.5,0.2,6\n2,1.0,0.3,7\n";
    let options = ReadOptions {
        time: Some(Column::Position(2)),
        angle: Some(Column::Position(3)),
        ..ReadOptions::default()
    };
    let r = with(text, options).unwrap();
    assert_eq!((r.t, r.theta), (vec![0.0, 0.5, 1.0], vec![0.1, 0.2, 0.3]));
    assert_eq!(r.lines, Some(vec![2, 3, 4]));
    let path = std::env::temp_dir().join(format!("hb-record-pandas-{}.csv", std::process::id()));
    std::fs::write(&path, text).unwrap();
    let named = hb_record::input::Header::of(&path).map(|h| h.names().to_vec());
    std::fs::remove_file(&path).unwrap();
    assert_eq!(
        named,
        Some(vec![String::new(), "0".into(), "1".into(), "2".into()])
    );
    // A first row of numbers and markers of missing values is data to both.
    let data = std::env::temp_dir().join(format!("hb-record-na-{}.csv", std::process::id()));
    std::fs::write(&data, "0,NA\n0.1,0.2\n").unwrap();
    let none = hb_record::input::Header::of(&data).map(|h| h.names().to_vec());
    std::fs::remove_file(&data).unwrap();
    assert_eq!(none, None);
}
