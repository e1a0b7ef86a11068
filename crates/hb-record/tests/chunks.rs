//! A file read in chunks: the chunks' new rows are the whole file's rows, what they name is
//! placed in the file, and times without a time column count from its first row.

use std::path::PathBuf;

use hb_record::input::{Chunk, Chunks, Column, InputError, Location, Opened, ReadOptions, Record, read_path};

use crate::common::npy_bytes;

fn file(name: &str, bytes: &[u8]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("hb-record-chunks-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

fn chunks(path: &std::path::Path, options: &ReadOptions) -> Chunks {
    match Chunks::open(path, options).unwrap() {
        Opened::Chunks(c) => *c,
        Opened::Whole(why) => panic!("read whole: {why}"),
    }
}

/// The rows of every chunk after those it repeats, joined; and the chunks.
fn read_all(mut c: Chunks, rows: usize, keep: usize) -> (Record, Vec<Chunk>) {
    let mut joined = Record::default();
    let mut all = Vec::new();
    while let Some(chunk) = c.next_chunk(rows, keep).unwrap() {
        let r = &chunk.record;
        assert!(chunk.repeated <= keep);
        assert_eq!(
            chunk.first_row + chunk.repeated,
            joined.t.len(),
            "chunks follow each other"
        );
        joined.t.extend_from_slice(&r.t[chunk.repeated..]);
        joined.theta.extend_from_slice(&r.theta[chunk.repeated..]);
        joined.others.resize(r.others.len(), Vec::new());
        for (j, o) in joined.others.iter_mut().zip(&r.others) {
            j.extend_from_slice(&o[chunk.repeated..]);
        }
        if let Some(lines) = &r.lines {
            joined
                .lines
                .get_or_insert_with(Vec::new)
                .extend_from_slice(&lines[chunk.repeated..]);
        }
        all.push(chunk);
    }
    assert!(all.last().is_some_and(|c| c.last));
    (joined, all)
}

#[test]
fn npy_chunks_are_the_file() {
    let rows = 103;
    let payload: Vec<u8> = (0..rows)
        .flat_map(|i| [0.01 * i as f64, (0.1 * i as f64).sin(), i as f64])
        .flat_map(f64::to_le_bytes)
        .collect();
    let path = file(
        "a.npy",
        &npy_bytes("<f8", &format!("({rows}, 3)"), false, &payload),
    );
    let options = ReadOptions {
        others: vec![Column::Position(3)],
        ..ReadOptions::default()
    };
    let whole = read_path(&path, &options).unwrap();
    let c = chunks(&path, &options);
    assert_eq!(c.total_rows(), Some(rows));
    let (joined, all) = read_all(c, 20, 7);
    assert_eq!(all.len(), 6);
    assert_eq!(
        (joined.t, joined.theta, joined.others),
        (whole.t, whole.theta, whole.others)
    );
    assert_eq!(all[1].repeated, 7);
    assert_eq!(all[2].relocate(Location::Sample(1)), Location::Sample(34));
}

#[test]
fn npy_chunks_name_the_file_s_rows_and_count_times_from_its_first() {
    let rows = 50;
    let mut values: Vec<f64> = (0..rows).map(|i| (0.1 * i as f64).cos()).collect();
    let path = file(
        "step.npy",
        &npy_bytes(
            "<f8",
            &format!("({rows},)"),
            false,
            &values.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<_>>(),
        ),
    );
    let options = ReadOptions {
        dt: Some(0.1),
        ..ReadOptions::default()
    };
    let whole = read_path(&path, &options).unwrap();
    let (joined, _) = read_all(chunks(&path, &options), 16, 4);
    assert_eq!(joined.t, whole.t);
    assert_eq!(joined.theta, whole.theta);
    // A value not finite in the third chunk is named by its row in the file.
    values[37] = f64::NAN;
    let path = file(
        "nan.npy",
        &npy_bytes(
            "<f8",
            &format!("({rows},)"),
            false,
            &values.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<_>>(),
        ),
    );
    let mut c = chunks(&path, &options);
    let e = loop {
        match c.next_chunk(16, 4) {
            Ok(Some(_)) => {}
            Ok(None) => panic!("no error"),
            Err(e) => break e,
        }
    };
    assert!(
        matches!(
            e,
            InputError::NonFinite {
                at: Location::Sample(38),
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn text_chunks_without_a_time_column_count_times_from_the_file_s_first_row() {
    let mut text = String::from("# one column\ntheta\n");
    for i in 0..70 {
        text.push_str(&format!("{}\n", (0.3 * i as f64).sin()));
    }
    let path = file("step.txt", text.as_bytes());
    let options = ReadOptions {
        dt: Some(0.002),
        ..ReadOptions::default()
    };
    let whole = read_path(&path, &options).unwrap();
    let (joined, all) = read_all(chunks(&path, &options), 20, 6);
    assert!(all.len() >= 3);
    assert_eq!((joined.t, joined.theta), (whole.t, whole.theta));
}

#[test]
fn text_chunks_are_the_file_and_name_its_lines() {
    let mut text = String::from("# logger 7\n# rate 100 Hz\ntime [s],angle [rad]\n");
    for i in 0..90 {
        if i == 40 {
            text.push_str("# a comment between rows\n\n");
        }
        text.push_str(&format!("{},{}\n", 0.01 * i as f64, (0.2 * i as f64).sin()));
    }
    let path = file("a.csv", text.as_bytes());
    let options = ReadOptions {
        time: Some(Column::Name("time [s]".into())),
        angle: Some(Column::Name("angle [rad]".into())),
        ..ReadOptions::default()
    };
    let whole = read_path(&path, &options).unwrap();
    let c = chunks(&path, &options);
    assert_eq!(c.total_rows(), None);
    let (joined, all) = read_all(c, 25, 6);
    assert!(all.len() >= 4);
    assert_eq!(
        (joined.t, joined.theta, joined.lines),
        (whole.t, whole.theta, whole.lines)
    );
    // A bad cell in a later chunk is named by the file's line.
    let bad = text.replacen("0.7000000000000001,", "0.7000000000000001x,", 1);
    assert_ne!(bad, text);
    let path = file("bad.csv", bad.as_bytes());
    let mut c = chunks(&path, &options);
    let e = loop {
        match c.next_chunk(25, 6) {
            Ok(Some(_)) => {}
            Ok(None) => panic!("no error"),
            Err(e) => break e,
        }
    };
    let line = bad
        .lines()
        .position(|l| l.starts_with("0.7000000000000001x"))
        .unwrap() as u64
        + 1;
    assert!(e.to_string().starts_with(&format!("line {line}:")), "{e}");
}

#[test]
fn fortran_arrays_standard_input_and_cr_alone_are_read_whole() {
    let path = file("f.npy", &npy_bytes("<f8", "(2, 2)", true, &[0u8; 32]));
    assert!(matches!(
        Chunks::open(&path, &ReadOptions::default()).unwrap(),
        Opened::Whole(_)
    ));
    assert!(matches!(
        Chunks::open(std::path::Path::new("-"), &ReadOptions::default()).unwrap(),
        Opened::Whole(_)
    ));
    let cr = file("cr.csv", b"t,theta\r0,0.1\r0.1,0.2\r0.2,0.3\r");
    assert!(matches!(
        Chunks::open(&cr, &ReadOptions::default()).unwrap(),
        Opened::Whole(_)
    ));
    // CR LF is read in chunks, as the whole file is.
    let crlf: String = (0..40).map(|i| format!("{},{}\r\n", 0.1 * i as f64, i)).collect();
    let path = file("crlf.csv", format!("t,theta\r\n{crlf}").as_bytes());
    let whole = read_path(&path, &ReadOptions::default()).unwrap();
    let (joined, _) = read_all(chunks(&path, &ReadOptions::default()), 15, 4);
    assert_eq!((joined.t, joined.theta), (whole.t, whole.theta));
}

/// A pipe is not read in chunks (they are read where they lie in the file): it is told to be read
/// whole, before it is opened (which would wait for its writer).
#[cfg(unix)]
#[test]
fn a_pipe_is_read_whole() {
    let dir = std::env::temp_dir().join(format!("hb-record-chunks-pipe-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let pipe = dir.join("record.npy");
    std::fs::remove_file(&pipe).ok();
    let made = std::process::Command::new("mkfifo").arg(&pipe).status();
    assert!(made.is_ok_and(|s| s.success()), "mkfifo made the pipe");
    match Chunks::open(&pipe, &ReadOptions::default()).unwrap() {
        Opened::Whole(why) => assert!(why.contains("pipe"), "{why}"),
        Opened::Chunks(_) => panic!("a pipe read in chunks"),
    }
    std::fs::remove_dir_all(&dir).ok();
}
