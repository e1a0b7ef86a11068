//! The `hbid` command line: identify the equation of motion of a forced oscillator from a
//! measured record, and the input and output plumbing the subcommands share.
//!
//! This library half holds what the binary `hbid` (the user-facing part) and `cargo xtask` share
//! and what must be tested on its own: the readers ([`input`], tested and fuzzed on their own),
//! the whole analysis of a record from its samples to validated models ([`pipeline`]: no printing,
//! no files), the preparation of a read record for it ([`prepare`]: grid, wrap, spikes, drive,
//! resampling), the JSON of the results ([`json`]), atomic output files ([`output`]) and the figures ([`plot`]).
//!
//! # Example
//!
//! ```
//! let csv = "# an encoder record\nt,theta\n0,0.1\n0.25,0.2\n";
//! let record = hbid::input::read_csv(csv.as_bytes())?;
//! assert_eq!(record.theta, vec![0.1, 0.2]);
//! # Ok::<(), hbid::input::InputError>(())
//! ```
#![deny(missing_docs)]

pub mod input;
pub mod json;
pub mod output;
pub mod pipeline;
pub mod plot;
pub mod prepare;
