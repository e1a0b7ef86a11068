//! The `hbid` command line: identify the equation of motion of a forced oscillator from a
//! measured record, and the input and output plumbing the subcommands share.
//!
//! This library half exists so that the readers can be tested and fuzzed on their own; the
//! binary `hbid` is the user-facing part.
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
pub mod output;
pub mod plot;
