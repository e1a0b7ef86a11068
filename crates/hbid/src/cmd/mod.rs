//! Subcommands.
pub mod data;
pub mod embed;
pub mod simulate;
pub mod upos;
