//! Subcommands.
pub mod compare;
pub mod data;
pub mod embed;
pub mod identify;
pub mod report;
pub mod report_args;
pub mod report_system;
pub mod simulate;
pub mod upos;
