//! The one error of a run, and what a front end does with it: its text with the options that fix
//! it (named as [`crate::options::Spelling::render`] reads them), and its kind (the exception a
//! Python user catches).

use hb_record::input::{InputError, Role};
use hb_record::prepare::PrepareError;

use crate::options::{OptionError, chain};
use crate::pipeline::PipelineError;

/// What kind of failure, for front ends that sort them (Python's exceptions).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorKind {
    /// The record: its file, its columns, its values, its time stamps.
    Input,
    /// An option or a combination of options.
    Options,
    /// The identification, the drive's estimate or the analysis could not be done on this
    /// record (too few segments, a rank-deficient system, no oscillation).
    Identification,
    /// A simulation.
    Simulation,
    /// A saved model: reading, writing or using it.
    Model,
    /// Writing a result file.
    Output,
}

/// Everything that can go wrong in a run, from a request's options to its result files.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RunError {
    /// An option, or a combination of options.
    #[error(transparent)]
    Options(#[from] OptionError),
    /// Reading the record, or fitting its time stamps to a grid.
    #[error("{name}: {source}{}", read_fix(source, *coords))]
    Read {
        /// The file (or `the arrays`).
        name: String,
        /// What went wrong (boxed: the largest of the errors).
        #[source]
        source: Box<InputError>,
        /// Whether the coordinates' columns were named as a list («coords»: a system's, or a
        /// saved system's own names): a missing coordinate is chosen there, not with
        /// «angle_col».
        coords: bool,
    },
    /// One of several records given together failed (named: its file, or `the arrays`); a
    /// failure to read one names it already ([`RunError::Read`]).
    #[error("{name}")]
    InRecord {
        /// The record's file (or `the arrays`).
        name: String,
        /// What went wrong with it.
        #[source]
        source: Box<RunError>,
    },
    /// Conditioning the record (spikes, integration).
    #[error(transparent)]
    Prepare(PrepareError),
    /// The drive's period: of the free oscillation, or its clock.
    #[error("{}", drive_text(.0))]
    Drive(#[source] PrepareError),
    /// The drive's period to estimate: the search's range, or no period found.
    #[error(transparent)]
    DriveEstimate(crate::drive::DriveError),
    /// A stage of the analysis (embedding, segments, validation).
    #[error(transparent)]
    Pipeline(#[from] PipelineError),
    /// The identification on the segments found failed.
    #[error("{found}")]
    Identify {
        /// What was found: `12 windows of 3 drive periods`.
        found: String,
        /// Why it failed.
        #[source]
        source: hb_solve::SolveError,
    },
    /// The delay had no first minimum of the mutual information.
    #[error("the delay: choose it with «delay=», or raise «max_lag=»")]
    NoDelay(#[source] embedding::EmbeddingError),
    /// A simulation.
    #[error(transparent)]
    Simulation(#[from] pendulum_sim::SimError),
    /// A model: saved, being saved, or made from a record's drive.
    #[error("the model")]
    Model(#[source] hb_model::ModelError),
    /// An output-error refinement that cannot start.
    #[error("refining the model by its free run: {0}")]
    Refine(String),
    /// A model file that cannot be read or is not a model.
    #[error("{path}: {why}")]
    ModelFile {
        /// The file.
        path: String,
        /// What is wrong with it.
        why: String,
    },
    /// Writing a result file.
    #[error(transparent)]
    Output(#[from] crate::output::OutputError),
}

impl From<hb_model::ModelError> for RunError {
    fn from(e: hb_model::ModelError) -> Self {
        RunError::Model(e)
    }
}

impl From<hb_solve::SolveError> for RunError {
    fn from(e: hb_solve::SolveError) -> Self {
        RunError::Pipeline(PipelineError::Solve(e))
    }
}

impl RunError {
    /// The kind of failure.
    pub fn kind(&self) -> ErrorKind {
        match self {
            RunError::Options(_) => ErrorKind::Options,
            RunError::Read { .. } => ErrorKind::Input,
            RunError::InRecord { source, .. } => source.kind(),
            RunError::Prepare(PrepareError::MeasuredOnCircle(_)) => ErrorKind::Options,
            RunError::Prepare(_) => ErrorKind::Input,
            RunError::Drive(PrepareError::Clock(_) | PrepareError::WindowTooShort { .. }) => {
                ErrorKind::Options
            }
            RunError::DriveEstimate(crate::drive::DriveError::Search(_)) => ErrorKind::Options,
            RunError::DriveEstimate(_) => ErrorKind::Identification,
            RunError::Drive(PrepareError::Input(_)) => ErrorKind::Input,
            RunError::Drive(_) => ErrorKind::Identification,
            // Options are checked before the run: what fails in it is the record's.
            RunError::Pipeline(PipelineError::Solve(_)) => ErrorKind::Options,
            RunError::Pipeline(PipelineError::Simulation(_) | PipelineError::Validation { .. }) => {
                ErrorKind::Simulation
            }
            RunError::Pipeline(_) => ErrorKind::Identification,
            RunError::Identify { .. } | RunError::NoDelay(_) => ErrorKind::Identification,
            RunError::Simulation(_) | RunError::Refine(_) => ErrorKind::Simulation,
            RunError::Model(_) | RunError::ModelFile { .. } => ErrorKind::Model,
            RunError::Output(_) => ErrorKind::Output,
        }
    }

    /// The whole message, every cause behind it, joined by `: ` (options still marked).
    pub fn chain(&self) -> String {
        chain(self)
    }
}

/// The options that fix an input error, appended to its text: `with «dt=»` and the like.
fn input_fix(error: &InputError) -> &'static str {
    match error {
        InputError::NeedStep => " with «dt=»",
        InputError::BadStep { .. } => " («dt=»)",
        InputError::TimeTwice => " («dt», «time_col»)",
        InputError::MissingColumn { role: Role::Time, .. } => "; choose one with «time_col=»",
        InputError::MissingColumn {
            role: Role::Angle, ..
        } => "; choose one with «angle_col=»",
        InputError::MissingColumn {
            role: Role::Drive, ..
        } => " («drive_col»)",
        InputError::BadDrivePeriod { .. } => " («drive_period»)",
        InputError::TimeGlitch { isolated: true, .. } => "; run with «repair=True» to fix isolated glitches",
        InputError::TimeGlitch { isolated: false, .. } | InputError::TimeUnresolved { .. } => " with «dt=»",
        _ => "",
    }
}

/// The options that fix a read error: those of [`input_fix`], but a missing coordinate of a
/// record read by «coords» is chosen with «coords» (the angle's column is its first).
fn read_fix(error: &InputError, coords: bool) -> &'static str {
    match error {
        InputError::MissingColumn {
            role: Role::Angle, ..
        } if coords => "; choose the coordinates' columns with «coords=»",
        error => input_fix(error),
    }
}

/// The text of a failure to find the record's clock, naming what it was about.
fn drive_text(error: &PrepareError) -> String {
    match error {
        PrepareError::FreePeriod(_) => {
            "no drive («drive_period=none»): the period of the free oscillation".to_owned()
        }
        PrepareError::Clock(_) => "the drive's period («drive_period», «drive_frequency»)".to_owned(),
        PrepareError::Resample(_) => {
            "a drive period of no whole number of samples («drive_period», «drive_frequency»)".to_owned()
        }
        PrepareError::Input(e) => format!("{e}{}", input_fix(e)),
        e => e.to_string(),
    }
}
