//! The integration tests of the `hbid` command: every subcommand run as a user runs it.
//!
//! One test binary for the whole package: each file is a module of this one, so the generics
//! they share (faer, proptest, serde) are compiled once, not once per file.

mod support;

mod cli;
mod compare;
mod free_decay;
mod logger_clock;
mod report_system;
mod tie;
