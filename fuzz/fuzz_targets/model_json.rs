//! Text to the JSON model loader; a model that loads must evaluate and save and load back to
//! itself in both formats.
#![no_main]

use hb_basis::BasisKind;
use hb_model::IdentifiedModel;
use hbid_fuzz::check_model;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|text: &str| {
    if let Ok(model) = IdentifiedModel::<BasisKind>::from_json(text) {
        check_model(&model);
    }
});
