//! Subcommands.
pub mod simulate;
