//! The `.npy` reader: 1-D and 2-D arrays in C and Fortran order, converted element types, and
//! corrupted or hostile headers refused before anything is allocated.
use hb_record::input::{Column, InputError, Location, ReadOptions, Role, read_bytes};

use crate::common::{is_about_the_content, npy_bytes};

#[test]
fn reads_npy_1d_2d_and_orders() {
    let f8: Vec<u8> = [0.0f64, 0.5, 1.0, 0.1, 0.2, 0.3]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    // C order, 3 samples × 2 channels: rows (0, 0.5), (1, 0.1), (0.2, 0.3).
    let r = read_bytes(&npy_bytes("<f8", "(3, 2)", false, &f8), &ReadOptions::default()).unwrap();
    assert_eq!(r.t, vec![0.0, 1.0, 0.2]);
    assert_eq!(r.theta, vec![0.5, 0.1, 0.3]);
    // Fortran order: column 1 is (0, 0.5, 1), column 2 is (0.1, 0.2, 0.3).
    let r = read_bytes(&npy_bytes("<f8", "(3, 2)", true, &f8), &ReadOptions::default()).unwrap();
    assert_eq!(r.t, vec![0.0, 0.5, 1.0]);
    assert_eq!(r.theta, vec![0.1, 0.2, 0.3]);
    let dt = ReadOptions {
        dt: Some(0.1),
        ..Default::default()
    };
    let r = read_bytes(&npy_bytes("<f8", "(6,)", false, &f8), &dt).unwrap();
    assert_eq!(r.theta.len(), 6);
    assert!(matches!(
        read_bytes(&npy_bytes("<f8", "(6,)", false, &f8), &ReadOptions::default()),
        Err(InputError::NeedStep)
    ));
    let i4: Vec<u8> = [1i32, -2, 3].iter().flat_map(|v| v.to_le_bytes()).collect();
    let r = read_bytes(&npy_bytes("<i4", "(3,)", false, &i4), &dt).unwrap();
    assert_eq!(r.theta, vec![1.0, -2.0, 3.0]);
    // A header that promises more data than the file holds.
    assert!(matches!(
        read_bytes(&npy_bytes("<f8", "(1000000000000,)", false, &f8), &dt),
        Err(InputError::Npy { .. })
    ));
    let nan: Vec<u8> = [0.0f64, f64::NAN].iter().flat_map(|v| v.to_le_bytes()).collect();
    assert!(matches!(
        read_bytes(&npy_bytes("<f8", "(2,)", false, &nan), &dt),
        Err(InputError::NonFinite { .. })
    ));
}

#[test]
fn converted_elements_follow_the_order_and_name_samples() {
    let f4: Vec<u8> = [0.0f32, 0.5, 1.0, 0.25, -0.5, 2.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let r = read_bytes(&npy_bytes("<f4", "(3, 2)", true, &f4), &ReadOptions::default()).unwrap();
    assert_eq!((r.t, r.theta), (vec![0.0, 0.5, 1.0], vec![0.25, -0.5, 2.0]));
    let r = read_bytes(&npy_bytes("<f4", "(3, 2)", false, &f4), &ReadOptions::default()).unwrap();
    assert_eq!((r.t, r.theta), (vec![0.0, 1.0, -0.5], vec![0.5, 0.25, 2.0]));
    for shape in ["()", "(1, 2, 3)"] {
        assert!(matches!(
            read_bytes(&npy_bytes("<f4", shape, false, &f4), &ReadOptions::default()),
            Err(InputError::Npy { .. })
        ));
    }
    let f8: Vec<u8> = [0.0f64, 1.0, 1.0, f64::INFINITY]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    match read_bytes(&npy_bytes("<f8", "(2, 2)", false, &f8), &ReadOptions::default()) {
        Err(e @ InputError::NonFinite { at, role, .. }) => {
            assert_eq!((at, role), (Location::Sample(2), Role::Angle));
            assert_eq!(at.to_string(), "sample 2");
            assert!(e.to_string().contains("inf in column 2"), "{e}");
        }
        other => panic!("{other:?}"),
    }
}

/// A header length beyond the file (a reader would allocate it: 4 GiB for format 2) is an
/// error before anything is allocated; so are versions and files cut short.
#[test]
fn header_lengths_beyond_the_file_are_refused() {
    // The input the fuzz target `npy` found: format 2.0, header length 0xfffffffe.
    let mut found = b"\x93NUMPY\x02\x00\xfe\xff\xff\xff{'descr': '".to_vec();
    found.extend_from_slice(&[b' '; 40]);
    for (bytes, says) in [
        (found, "announces 4294967294 bytes"),
        (b"\x93NUMPY\x01\x00\x40\x00{}".to_vec(), "announces 64 bytes"),
        (b"\x93NUMPY\x04\x00\x00\x00".to_vec(), "version 4.0"),
        (b"\x93NUMPY\x01".to_vec(), "inside the format version"),
        (b"\x93NUMPY\x03\x00\x01\x00".to_vec(), "inside the header length"),
    ] {
        match read_bytes(&bytes, &ReadOptions::default()) {
            Err(e @ InputError::Npy { .. }) => assert!(e.to_string().contains(says), "{e}"),
            other => panic!("{bytes:?}: {other:?}"),
        }
    }
    // Brackets nested 22 deep in the shape (found by the fuzz target `npy`: the header's
    // parser took more than 10 s); within the limit, brackets in a string are only a bad element
    // type.
    let mut deep =
        b"\x93NUMPY\x01\x00\x76\x00{'descr': '<i4', 'fortran_order': False, 'shape': (2, ".to_vec();
    deep.extend_from_slice(&[b'['; 22]);
    deep.resize(10 + 0x76 - 1, b' ');
    deep.push(b'\n');
    deep.extend_from_slice(&[0; 16]);
    let start = std::time::Instant::now();
    match read_bytes(&deep, &ReadOptions::default()) {
        Err(e @ InputError::Npy { .. }) => assert!(e.to_string().contains("24 deep"), "{e}"),
        other => panic!("{other:?}"),
    }
    assert!(start.elapsed().as_secs_f64() < 1.0, "{:?}", start.elapsed());
    let strange = npy_bytes("<f8[[", "(2,)", false, &[0; 16]);
    match read_bytes(&strange, &ReadOptions::default()) {
        Err(e @ InputError::Npy { .. }) => assert!(!e.to_string().contains("deep"), "{e}"),
        other => panic!("{other:?}"),
    }
    // Format 2 with a header that fits reads as format 1 does.
    let f8: Vec<u8> = [0.0f64, 1.0, 0.5, 2.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let mut v2 = npy_bytes("<f8", "(2, 2)", false, &f8);
    let length = u16::from_le_bytes([v2[8], v2[9]]);
    v2[6] = 2;
    v2.splice(8..10, u32::from(length).to_le_bytes());
    let r = read_bytes(&v2, &ReadOptions::default()).unwrap();
    assert_eq!((r.t, r.theta), (vec![0.0, 0.5], vec![1.0, 2.0]));
}

proptest::proptest! {
    #[test]
    fn npy_never_panics_on_corrupted_files(
        cut in 0usize..200,
        flips in proptest::collection::vec((0usize..200, proptest::prelude::any::<u8>()), 0..6),
    ) {
        let f8: Vec<u8> = (0..12).flat_map(|v| (v as f64).to_le_bytes()).collect();
        let mut bytes = npy_bytes("<f8", "(6, 2)", false, &f8);
        for (i, b) in flips {
            if i < bytes.len() { bytes[i] = b; }
        }
        bytes.truncate(cut.max(6));
        for options in [ReadOptions::default(), ReadOptions { dt: Some(0.1), ..Default::default() }] {
            if let Err(e) = read_bytes(&bytes, &options) {
                proptest::prop_assert!(is_about_the_content(&e), "{e:?}");
            }
        }
    }
}

/// A file is read by path straight into its columns, a block of rows at a time (little-endian
/// f8 in C order), and otherwise whole; either way the record (or the error) is that of its bytes
/// read whole: rows cut by the blocks' ends, a column taken twice, bytes past the last row, 1-D
/// arrays, Fortran order, other element types, and a file shorter than its header says.
#[test]
fn a_file_read_by_path_is_its_bytes_read_whole() {
    use hb_record::input::{Column, read_path};
    let dir = std::env::temp_dir().join(format!("hb-record-npy-file-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // 3 columns of 8 bytes: a row crosses each 1 MiB block's end; 150 001 rows, 3.6 MB.
    let rows = 150_001;
    let values: Vec<f64> = (0..rows)
        .flat_map(|i| [1e-3 * i as f64, (1e-2 * i as f64).sin(), (i % 7) as f64])
        .collect();
    let f8: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    let f4: Vec<u8> = values.iter().flat_map(|&v| (v as f32).to_le_bytes()).collect();
    let mut longer = f8.clone();
    longer.extend_from_slice(&[7u8; 13]);
    let twice = ReadOptions {
        others: vec![Column::Position(3)],
        drives: vec![Column::Position(3), Column::Position(2)],
        ..ReadOptions::default()
    };
    let one_d = ReadOptions {
        dt: Some(0.5),
        ..ReadOptions::default()
    };
    let cases: Vec<(&str, Vec<u8>, ReadOptions)> = vec![
        (
            "c",
            npy_bytes("<f8", &format!("({rows}, 3)"), false, &f8),
            ReadOptions::default(),
        ),
        (
            "twice",
            npy_bytes("<f8", &format!("({rows}, 3)"), false, &f8),
            twice,
        ),
        (
            "longer",
            npy_bytes("<f8", &format!("({rows}, 3)"), false, &longer),
            ReadOptions::default(),
        ),
        (
            "one-d",
            npy_bytes("<f8", &format!("({},)", 3 * rows), false, &f8),
            one_d,
        ),
        (
            "fortran",
            npy_bytes("<f8", &format!("({rows}, 3)"), true, &f8),
            ReadOptions::default(),
        ),
        (
            "f4",
            npy_bytes("<f4", &format!("({rows}, 3)"), false, &f4),
            ReadOptions::default(),
        ),
        (
            "short",
            npy_bytes("<f8", &format!("({}, 3)", rows + 1), false, &f8),
            ReadOptions::default(),
        ),
    ];
    for (name, bytes, options) in cases {
        let path = dir.join(format!("{name}.npy"));
        std::fs::write(&path, &bytes).unwrap();
        let by_path = read_path(&path, &options);
        let whole = read_bytes(&bytes, &options);
        match (by_path, whole) {
            (Ok(a), Ok(b)) => {
                assert_eq!(
                    (&a.t, &a.theta, &a.others, &a.drives, &a.velocities),
                    (&b.t, &b.theta, &b.others, &b.drives, &b.velocities),
                    "{name}"
                );
                assert!(a.theta.len() >= rows, "{name}");
            }
            (Err(a), Err(b)) => assert_eq!(a.to_string(), b.to_string(), "{name}"),
            (a, b) => panic!("{name}: by path {:?}, whole {:?}", a.map(|_| ()), b.map(|_| ())),
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A `.npy` record given by the path of a pipe (a shell's `<(cat record.npy)`) is read whole,
/// as from a file: a pipe cannot be read again from its start, so its first block is not tried
/// as a plain array's header first.
#[cfg(unix)]
#[test]
fn an_npy_record_through_a_pipe_is_read_as_from_a_file() {
    use hb_record::input::read_path;
    let dir = std::env::temp_dir().join(format!("hb-record-npy-pipe-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let rows = 2000;
    let f8: Vec<u8> = (0..rows)
        .flat_map(|i| [1e-2 * i as f64, (1e-1 * i as f64).sin()])
        .flat_map(f64::to_le_bytes)
        .collect();
    let bytes = npy_bytes("<f8", &format!("({rows}, 2)"), false, &f8);
    let pipe = dir.join("record.npy");
    std::fs::remove_file(&pipe).ok();
    let made = std::process::Command::new("mkfifo").arg(&pipe).status();
    assert!(made.is_ok_and(|s| s.success()), "mkfifo made the pipe");
    let writer = {
        let (pipe, bytes) = (pipe.clone(), bytes.clone());
        std::thread::spawn(move || std::fs::write(pipe, bytes).unwrap())
    };
    // A reader that opened the pipe again would wait for a writer for ever: the test fails
    // after a while instead.
    let (sent, received) = std::sync::mpsc::channel();
    {
        let pipe = pipe.clone();
        std::thread::spawn(move || {
            let read = read_path(&pipe, &ReadOptions::default()).map_err(|e| e.to_string());
            sent.send(read).ok();
        });
    }
    let through_pipe = received
        .recv_timeout(std::time::Duration::from_secs(60))
        .expect("the pipe read within a minute")
        .unwrap();
    writer.join().unwrap();
    let whole = read_bytes(&bytes, &ReadOptions::default()).unwrap();
    assert_eq!((through_pipe.t, through_pipe.theta), (whole.t, whole.theta));
    std::fs::remove_dir_all(&dir).ok();
}

/// Unsigned integers (an encoder's 16-bit counter, bytes) and one-byte signed ones read as their
/// values; a type that is not read is named as NumPy writes it, not as a parser's structure.
#[test]
fn unsigned_counts_read_and_other_types_are_named_plainly() {
    let rows: [(f64, f64); 3] = [(0.0, 4095.0), (1.0, 65535.0), (2.0, 7.0)];
    let cases: [(&str, Vec<u8>); 5] = [
        (
            "<u2",
            rows.iter()
                .flat_map(|&(t, x)| [t as u16, x as u16])
                .flat_map(u16::to_le_bytes)
                .collect(),
        ),
        (
            "<u4",
            rows.iter()
                .flat_map(|&(t, x)| [t as u32, x as u32])
                .flat_map(u32::to_le_bytes)
                .collect(),
        ),
        (
            "<u8",
            rows.iter()
                .flat_map(|&(t, x)| [t as u64, x as u64])
                .flat_map(u64::to_le_bytes)
                .collect(),
        ),
        (
            "|u1",
            rows.iter()
                .flat_map(|&(t, x)| [t as u8, (x as u64 % 256) as u8])
                .collect(),
        ),
        (
            "|i1",
            rows.iter()
                .flat_map(|&(t, x)| [t as i8, (x as u64 % 100) as i8])
                .map(|v| v as u8)
                .collect(),
        ),
    ];
    for (descr, payload) in cases {
        let r = read_bytes(
            &npy_bytes(descr, "(3, 2)", false, &payload),
            &ReadOptions::default(),
        )
        .unwrap();
        assert_eq!(r.t, vec![0.0, 1.0, 2.0], "{descr}");
        let expected: Vec<f64> = match descr {
            "|u1" => rows.iter().map(|&(_, x)| (x as u64 % 256) as f64).collect(),
            "|i1" => rows.iter().map(|&(_, x)| (x as u64 % 100) as f64).collect(),
            _ => rows.iter().map(|&(_, x)| x).collect(),
        };
        assert_eq!(r.theta, expected, "{descr}");
    }
    let too_large: Vec<u8> = [0u64, (1 << 53) + 2]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let e = read_bytes(
        &npy_bytes("<u8", "(1, 2)", false, &too_large),
        &ReadOptions::default(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("too large to convert exactly"), "{e}");
    let half: Vec<u8> = [0u16; 6].iter().flat_map(|v| v.to_le_bytes()).collect();
    let e = read_bytes(&npy_bytes("<f2", "(3, 2)", false, &half), &ReadOptions::default()).unwrap_err();
    let text = e.to_string();
    assert!(text.contains("'<f2' is not supported"), "{text}");
    assert!(!text.contains("TypeStr") && !text.contains("Plain("), "{text}");
}

/// A header NumPy would not write (Python 2's `30000L`) is refused in one line that says where
/// and what was expected, not with the parser's drawing of the header.
#[test]
fn a_header_that_does_not_parse_is_refused_in_one_line() {
    let payload = vec![0u8; 4 * 3 * 8];
    let bytes = npy_bytes("<f8", "(4L, 3L)", false, &payload);
    let e = read_bytes(&bytes, &ReadOptions::default()).unwrap_err();
    let text = e.to_string();
    assert!(
        !text.contains('\n') && !text.contains("^---") && !text.contains("-->"),
        "{text}"
    );
    assert!(text.contains("at column") && text.contains("expected"), "{text}");
}

/// An array's NaN in a column read is an error naming its sample and how to read the record
/// without its row; with `skip_missing` the row is left out and listed, the others keeping their
/// times (a sampling step's places too), and an error after it still names the file's sample.
#[test]
fn rows_with_a_nan_are_left_out_on_request() {
    let rows: [[f64; 3]; 5] = [
        [0.0, 0.1, 1.0],
        [0.5, f64::NAN, 2.0],
        [1.0, 0.3, 3.0],
        [1.5, 0.4, f64::NAN],
        [2.0, 0.5, 5.0],
    ];
    let payload: Vec<u8> = rows.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    let bytes = npy_bytes("<f8", "(5, 3)", false, &payload);
    let options = |skip: bool| ReadOptions {
        time: Some(Column::Position(1)),
        angle: Some(Column::Position(2)),
        drives: vec![Column::Position(3)],
        skip_missing: skip,
        ..ReadOptions::default()
    };
    let err = read_bytes(&bytes, &options(false)).unwrap_err();
    assert!(
        matches!(
            err,
            InputError::NonFinite {
                at: Location::Sample(2),
                ..
            }
        ),
        "{err:?}"
    );
    assert!(err.to_string().contains("«skip_missing=True»"), "{err}");
    let r = read_bytes(&bytes, &options(true)).unwrap();
    assert_eq!((r.t, r.theta), (vec![0.0, 1.0, 2.0], vec![0.1, 0.3, 0.5]));
    assert_eq!(r.drives, vec![vec![1.0, 3.0, 5.0]]);
    assert_eq!(r.missing, vec![Location::Sample(2), Location::Sample(4)]);
    let stepped = ReadOptions {
        time: None,
        dt: Some(0.25),
        ..options(true)
    };
    let r = read_bytes(&bytes, &stepped).unwrap();
    assert_eq!(r.t, vec![0.0, 0.5, 1.0]);
    // An infinity after a row left out is named by its place in the file.
    let mut with_inf = rows;
    with_inf[4][1] = f64::INFINITY;
    let payload: Vec<u8> = with_inf.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    let err = read_bytes(&npy_bytes("<f8", "(5, 3)", false, &payload), &options(true)).unwrap_err();
    assert!(
        matches!(
            err,
            InputError::NonFinite {
                at: Location::Sample(5),
                ..
            }
        ),
        "{err:?}"
    );
}

/// After rows are left out for a NaN, what the grid fit and the duplicate rows' note name is
/// the array's own sample, not its place among the rows kept.
#[test]
fn samples_after_rows_left_out_are_named_by_their_place_in_the_array() {
    use hb_record::input::{GridOptions, GridRecord};
    use hb_record::prepare::{Note, PrepareOptions, condition};
    let array = |edit: &dyn Fn(&mut Vec<[f64; 2]>)| {
        let mut rows: Vec<[f64; 2]> = (0..400)
            .map(|i| [0.1 * i as f64, (0.1 * i as f64).sin()])
            .collect();
        rows[1][1] = f64::NAN; // sample 2
        edit(&mut rows);
        let payload: Vec<u8> = rows.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
        let bytes = npy_bytes("<f8", "(400, 2)", false, &payload);
        let options = ReadOptions {
            skip_missing: true,
            ..ReadOptions::default()
        };
        read_bytes(&bytes, &options).unwrap()
    };
    // Sample 10's time goes back.
    let back = array(&|rows| rows[9][0] = 0.75);
    match GridRecord::fit(back, &GridOptions::default()) {
        Err(e) => assert!(e.to_string().starts_with("sample 10: "), "{e}"),
        Ok(_) => panic!("a time going back fits"),
    }
    // Sample 21 repeats sample 20.
    let twice = array(&|rows| rows[20] = rows[19]);
    let grid = condition(
        twice,
        &PrepareOptions::new(circle_signal::Domain::Line),
        &mut |_| {},
    )
    .unwrap();
    assert!(
        grid.notes.iter().any(|n| matches!(
            n,
            Note::DuplicateRows {
                first: Location::Sample(21),
                ..
            }
        )),
        "{:?}",
        grid.notes
    );
    // After a row written twice, too: sample 41's time going back is named as the array's.
    let both = array(&|rows| {
        rows[20] = rows[19];
        rows[40][0] = 3.75;
    });
    match condition(
        both,
        &PrepareOptions::new(circle_signal::Domain::Line),
        &mut |_| {},
    ) {
        Err(e) => assert!(e.to_string().contains("sample 41: "), "{e}"),
        Ok(_) => panic!("a time going back fits"),
    }
}
