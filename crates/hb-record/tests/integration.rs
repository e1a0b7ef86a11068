//! The integration tests of hb-record: the text and `.npy` readers and their one column policy,
//! the errors' texts, the time stamps fitted to a grid (gaps, glitches, a slipping or jittering
//! clock), the notes of preparing a record, and properties of the readers over any input.
//!
//! One test binary for the whole package: each file is a module of this one, so the generics
//! they share (proptest) are compiled and linked once, not once per file.
mod common;

mod chunks;
mod csv;
mod error;
mod input;
mod npy;
mod prepare;
mod proptests;
mod uniform;
