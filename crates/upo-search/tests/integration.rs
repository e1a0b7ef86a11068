//! The integration tests of upo-search: the close-return search and its catalogue of distinct
//! orbits on synthetic records and the paper's data set, the search's parameters and errors, and
//! the plain windows of a record.
//!
//! One test binary for the whole package: each file is a module of this one, so the generics
//! they share (proptest, rand) are compiled and linked once, not once per file.
mod catalogue;
mod close_returns;
mod search;
mod windows;
