//! Bytes after the `.npy` magic to the reader (header, element types, shapes, orders, payload),
//! with the column options chosen by the first byte; whatever is read goes to the grid fit.
#![no_main]

use hb_record::input::{Column, ReadOptions, read_bytes};
use hbid_fuzz::{check_error, check_record};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&choice, rest)) = data.split_first() else {
        return;
    };
    let options = match choice % 6 {
        0 => ReadOptions::default(),
        1 => ReadOptions {
            dt: Some(0.5),
            ..Default::default()
        },
        2 => ReadOptions {
            time: Some(Column::Position(2)),
            angle: Some(Column::Position(1)),
            dt: None,
            drive: None,
        },
        3 => ReadOptions {
            angle: Some(Column::Position(usize::from(choice / 6))),
            dt: Some(1e-3),
            ..Default::default()
        },
        4 => ReadOptions {
            time: Some(Column::Position(usize::from(choice / 6))),
            ..Default::default()
        },
        _ => ReadOptions {
            angle: Some(Column::Name("theta".to_owned())),
            ..Default::default()
        },
    };
    let mut bytes = b"\x93NUMPY".to_vec();
    bytes.extend_from_slice(rest);
    match read_bytes(&bytes, &options) {
        Ok(record) => check_record(&record, None),
        // Every element takes at least a byte of the payload.
        Err(e) => check_error(&e, 0, rest.len()),
    }
});
