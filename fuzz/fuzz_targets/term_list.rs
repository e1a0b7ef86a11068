//! Text to the term-list parser (`hbid identify --terms`, the `terms` of a saved model): a list
//! that parses prints back to text that parses to the same list, and its smallest basis, when it
//! has one, holds every term.
#![no_main]

use hb_model::TermList;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|text: &str| {
    let Ok(list) = TermList::parse(text) else {
        return;
    };
    let printed = list.to_string();
    let again = TermList::parse(&printed).unwrap_or_else(|e| panic!("{printed:?} does not parse back: {e}"));
    assert_eq!(again, list, "{text:?} printed as {printed:?}");
    if let Ok(Some(basis)) = list.smallest_basis() {
        list.resolve(&basis)
            .unwrap_or_else(|e| panic!("{printed:?}: its smallest basis does not hold it: {e}"));
    }
});
