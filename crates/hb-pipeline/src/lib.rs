//! The application layer of `hbid`: what every front end (the command line `hbid`, the Python
//! package, `cargo xtask`) runs on a record, written once.
//!
//! Each request is a struct of every option of its subcommand, by the command line's names (`_`
//! for `-`), with the one default of every front end: [`IdentifyOptions`] (checked into an
//! [`IdentifyRequest`]), [`EmbedRequest`], [`UposRequest`] and [`SimulateOptions`] (checked into
//! a [`Rig`]). A request is built by the command line from its arguments and by Python from a
//! JSON object of its keyword arguments ([`options::from_object`]: unknown names refused, a bad
//! value named); its grammars (`harmonic:1`, `auto:5..7`, term lists) are the types' own.
//!
//! The runs ([`identify()`], [`embed()`], [`upos`], [`simulate()`]) take a [`Source`] (a file,
//! arrays, or a record on its grid), make it ready the one way ([`load`]: read, grid, wrap,
//! spikes, integrate, drive, resample) and return reports whose serialisation is the JSON of the
//! command line's `--json` ([`IdentifyReport`], [`EmbedReport`], [`UposReport`], [`Truth`]).
//! Errors are one [`RunError`] with a [`ErrorKind`]; messages name options between `«` and `»`,
//! and [`Spelling::render`] writes them as the front end spells them (`--drive-col`,
//! `drive_col=`).
//!
//! - [`pipeline`]: the whole analysis of one record behind `hbid report` and `cargo xtask
//!   reproduce` (embedding, orbits, identification by each method, validation by simulation);
//! - [`observe`]: progress and notices of a run ([`Observer`]);
//! - [`output`]: result files written atomically (all or nothing, even on an interrupt).
//!
//! Nothing here prints; files are touched only where a caller names one.
//!
//! # Example
//!
//! The paper's pendulum, simulated as `hbid simulate` does and identified as `hbid identify`
//! does; the same request from Python's keyword arguments is the same request.
//!
//! ```
//! use hb_pipeline::{IdentifyOptions, IdentifyRequest, Rig, SimulateOptions, Source};
//!
//! let rig = Rig::new(SimulateOptions { samples: Some(2_000), ..SimulateOptions::default() })?;
//! let table = hb_pipeline::simulate(&rig, &mut ())?.table();
//! let (t, x): (Vec<f64>, Vec<f64>) = table.iter().map(|row| (row[0], row[1])).unzip();
//! let request = IdentifyRequest::new(IdentifyOptions { bootstrap: 0, ..IdentifyOptions::default() })?;
//! let source = Source::Arrays { coords: vec![&x], t: Some(&t), drives: Vec::new() };
//! let report = hb_pipeline::identify(source, &request, &mut ())?;
//! let drive = report.identification().model.coefficient("sin(t)*cos(x)").unwrap().value;
//! assert!((drive + 1.52).abs() < 1e-5);
//! assert_eq!(IdentifyRequest::from_json(serde_json::json!({"bootstrap": 0}))?, request);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![deny(missing_docs)]

pub mod compare;
pub mod drive;
pub mod embed;
pub mod error;
pub mod identify;
pub mod integrated;
pub mod observe;
pub mod options;
pub mod output;
pub mod pipeline;
pub mod record;
pub mod refine;
pub mod simulate;
pub mod stream;

pub use compare::{
    CompareOptions, CompareReport, CompareRequest, ModelRun, SampleRange, compare, model_run, read_model,
    run_on_times, run_system_on_times,
};
pub use drive::{DriveSpec, DriveUnit};
pub use embed::{EmbedReport, EmbedRequest, OrbitOptions, UposReport, UposRequest, embed, upos};
pub use error::{ErrorKind, RunError};
pub use identify::{
    EquationReport, ForcingTerms, IdentifyOptions, IdentifyReport, IdentifyRequest, SolverKind, TermsOption,
    identify, identify_data, identify_records, system_library,
};
pub use observe::{Notice, Notices, Observer, Stage};
pub use options::{OptionError, Spelling};
pub use record::{
    AngleUnit, ColumnList, DriveFrequency, DrivePeriod, RecordOptions, RecordSummary, SignalList, Source,
    condition_source, load,
};
pub use refine::{Refinement, refine};
pub use simulate::{Rig, SimulateOptions, Simulation, Truth, simulate};
