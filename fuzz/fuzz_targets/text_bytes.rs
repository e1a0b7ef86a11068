//! Raw bytes to the text reader (and whatever it reads, to the grid fit), with the default
//! columns and with a sampling step instead of a time column.
#![no_main]

use hb_record::input::{ReadOptions, read_bytes};
use hbid_fuzz::{check_error, check_record, line_count};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    // `.npy` has its own target; here the magic would only hide text.
    if data.starts_with(b"\x93NUMPY") {
        return;
    }
    let lines = line_count(data);
    for options in [
        ReadOptions::default(),
        ReadOptions {
            dt: Some(0.01),
            ..Default::default()
        },
    ] {
        match read_bytes(data, &options) {
            Ok(record) => check_record(&record, Some(lines)),
            Err(e) => check_error(&e, lines, 0),
        }
    }
});
