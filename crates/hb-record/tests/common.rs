//! What the tests share: `.npy` files made in memory, and which errors bytes alone can cause.
use hb_record::input::InputError;

/// An `.npy` file (format 1.0) with this header and payload.
pub fn npy_bytes(descr: &str, shape: &str, fortran: bool, payload: &[u8]) -> Vec<u8> {
    let mut header = format!(
        "{{'descr': '{descr}', 'fortran_order': {}, 'shape': {shape}, }}",
        if fortran { "True" } else { "False" }
    );
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    out.extend_from_slice(payload);
    out
}

/// Whether the error is about what the input holds, the only kind bytes alone can cause (not
/// reading a file, the options on their own, or the checks after reading).
pub fn is_about_the_content(e: &InputError) -> bool {
    match e {
        InputError::Empty
        | InputError::NoData
        | InputError::MissingColumn { .. }
        | InputError::AmbiguousColumn { .. }
        | InputError::NeedStep
        | InputError::NotANumber { .. }
        | InputError::NonFinite { .. }
        | InputError::Ragged { .. }
        | InputError::MixedSeparators { .. }
        | InputError::Malformed { .. }
        | InputError::StepOverflow { .. }
        | InputError::Npy { .. } => true,
        InputError::Io { .. }
        | InputError::IsFolder { .. }
        | InputError::BadColumn { .. }
        | InputError::BadStep { .. }
        | InputError::TimeTwice
        | InputError::ColumnTwice { .. }
        | InputError::TooFewSamples { .. }
        | InputError::TimeNotIncreasing { .. }
        | InputError::TimeGlitch { .. }
        | InputError::TimeUnresolved { .. }
        | InputError::TimeUnsettled { .. }
        | InputError::TimeOverflow { .. }
        | InputError::GapTooLong { .. }
        | InputError::BadDrivePeriod { .. } => false,
        // `InputError` is non-exhaustive: a variant added later is not about the content until
        // it is listed above (so that a test seeing it fails rather than passes by default).
        _ => false,
    }
}
