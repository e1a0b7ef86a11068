//! Bytes after the magic number and version to the binary (postcard) model loader; a model that
//! loads must evaluate and save and load back to itself in both formats.
#![no_main]

use hb_basis::BasisKind;
use hb_model::{IdentifiedModel, MODEL_MAGIC, MODEL_VERSION};
use hbid_fuzz::check_model;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut bytes = MODEL_MAGIC.to_vec();
    bytes.extend_from_slice(&MODEL_VERSION.to_le_bytes());
    bytes.extend_from_slice(data);
    if let Ok(model) = IdentifiedModel::<BasisKind>::from_bytes(&bytes) {
        check_model(&model);
    }
});
