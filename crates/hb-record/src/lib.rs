//! A measured record made ready for identification.
//!
//! Two steps, each its own module:
//!
//! - [`input`] reads a record as a data-acquisition program writes it (text with any separator,
//!   with or without a header, or `.npy`) and fits its time stamps to one grid `t_0 + n h`: gaps
//!   split it into pieces, isolated glitches are named (and replaced on request), a logger's
//!   few samples at another rate before it settles (or as it stops) are left out;
//! - [`prepare`] makes the read record what every stage of the identification takes: pieces on
//!   one grid with NaN in the gaps (gaps of a few samples bridged on request), an angle wrapped
//!   into `[−π, π)`, encoder spikes found (and replaced on request), a velocity or acceleration
//!   integrated to the displacement, the drive's period given (or estimated above this crate) or
//!   absent (a free oscillation), and the record resampled once onto a whole number of samples
//!   per period when needed.
//!
//! The crate sits on the vocabulary crate (`circle-signal`) alone: reading a record builds no
//! solver, model or integrator.
//!
//! Nothing here prints: what was done to a record is reported as [`prepare::Note`]s through a
//! callback and kept in the result. Files are read only when a caller names one
//! ([`input::read_path`]).
//!
//! # Example
//!
//! ```
//! use circle_signal::Domain;
//! use hb_record::input::read_csv;
//! use hb_record::prepare::{PeriodSource, PrepareOptions, condition};
//!
//! // 8 samples per drive period of 2 s, an angle.
//! let mut csv = String::from("t,theta\n");
//! for n in 0..160 {
//!     let t = n as f64 * 0.25;
//!     csv.push_str(&format!("{t},{}\n", (std::f64::consts::PI * t).sin()));
//! }
//! let record = read_csv(csv.as_bytes())?;
//! let grid = condition(record, &PrepareOptions::new(Domain::Circle), &mut |_| {})?;
//! let data = grid.with_period(PeriodSource::Given(2.0))?;
//! assert_eq!(data.p, 8);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![deny(missing_docs)]

pub mod input;
pub mod prepare;
