//! The one error type of the pipeline: the stage crates' errors, and what only the pipeline knows.

use super::Method;

/// Everything that can go wrong between a record and its validated models.
///
/// The stages' own errors pass through unchanged (their text is the stage's); an identification
/// that fails also says which method and how many segments it had.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PipelineError {
    /// The record's clock does not cut it into whole forcing periods, or a segment does not fit.
    #[error(transparent)]
    Clock(#[from] circle_signal::CircleError),
    /// The delay or the embedding dimension (average mutual information, false nearest
    /// neighbours), or their options.
    #[error(transparent)]
    Embedding(#[from] embedding::EmbeddingError),
    /// The close-return search or the windows, or their options.
    #[error(transparent)]
    Orbits(#[from] upo_search::UpoError),
    /// The identification parameters.
    #[error(transparent)]
    Solve(#[from] hb_solve::SolveError),
    /// The model's form or terms.
    #[error(transparent)]
    Model(#[from] hb_model::ModelError),
    /// The simulation of a model, or the validation's options.
    #[error(transparent)]
    Simulation(#[from] pendulum_sim::SimError),
    /// An identification failed (too few segments, a rank-deficient system, ...).
    #[error("{segments} segments ({method})")]
    Identification {
        /// The method.
        method: Method,
        /// The segments it had.
        segments: usize,
        /// Why it failed.
        #[source]
        source: hb_solve::SolveError,
    },
    /// The close-return search cannot search its longest period in the record, or in any of its
    /// pieces between gaps.
    #[error(
        "the record is too short for the close-return search: orbits of up to {period} drive periods need \
         {needed} samples in one stretch ({period} periods of {samples_per_period} samples, and the embedding's span), and {}; give \
         a smaller «max_period», a longer record, or check the drive: at the record's rate one drive period \
         is {samples_per_period} samples («drive_frequency», «drive_period»)",
        longest_stretch(*.longest, *.pieces)
    )]
    NoOrbitFits {
        /// The longest period searched, in drive periods.
        period: usize,
        /// The samples of a drive period.
        samples_per_period: usize,
        /// The samples the search needs in one piece.
        needed: usize,
        /// The samples of the longest piece.
        longest: usize,
        /// The record's pieces.
        pieces: usize,
    },
    /// The delay's search (the average mutual information) reaches beyond the record, or beyond
    /// its longest piece between gaps.
    #[error(
        "the record is too short for the delay's search: the mutual information is taken to a lag of \
         {max_lag} samples, and {}; give {}a longer record, or check the drive: at the record's rate one \
         drive period is {samples_per_period} samples («drive_frequency», «drive_period»)",
        longest_stretch(*.longest, *.pieces),
        .remedy.map(|r| format!("{r}, ")).unwrap_or_default()
    )]
    NoDelayFits {
        /// The largest lag, in samples.
        max_lag: usize,
        /// The samples of a drive period.
        samples_per_period: usize,
        /// The samples of the longest piece.
        longest: usize,
        /// The record's pieces.
        pieces: usize,
        /// What the caller's user can give instead, marked as an option (`a smaller «max_lag»`),
        /// if anything.
        remedy: Option<&'static str>,
    },
    /// A model's free run could not go on in its validation (it blows up, leaves the
    /// floating-point range or its mass matrix turns singular): the model, not the options.
    #[error(
        "the model of the {method} method cannot be run freely, as its validation does{}",
        match .warning {
            Some(w) => format!(" (its identification warned: {w})"),
            None => String::new(),
        }
    )]
    Validation {
        /// The method.
        method: Method,
        /// The identification's warning, if it gave one.
        warning: Option<String>,
        /// Why the run stopped.
        #[source]
        source: pendulum_sim::SimError,
    },
    /// The record has no samples.
    #[error("the record has no samples")]
    EmptyRecord,
    /// No window of the weak form fits in the record, or in any of its pieces between gaps.
    #[error(
        "no window fits {}, and a window of {window} holds {needed} samples{}",
        if *.pieces > 1 {
            format!(
                "between the record's gaps: its longest stretch without one has {} samples \
                 ({} pieces, {} gaps)",
                .longest,
                .pieces,
                .pieces - 1
            )
        } else {
            format!("in the record: it has {} samples", .longest)
        },
        if *.pieces > 1 {
            " (a window never spans a gap); give a shorter «window», or bridge gaps of at most 4 missing \
             samples («bridge_gaps»)"
        } else {
            "; give a shorter «window», or a longer record"
        }
    )]
    NoWindow {
        /// The window, in words (`3 drive periods`).
        window: String,
        /// The samples a window holds (its closing sample included).
        needed: usize,
        /// The samples of the longest piece.
        longest: usize,
        /// How many pieces the record is in.
        pieces: usize,
    },
}

/// What a record has in one stretch: `the record has N`, or of a record in pieces `the longest
/// stretch between the record's gaps has N (P pieces, G gaps)`.
fn longest_stretch(longest: usize, pieces: usize) -> String {
    if pieces > 1 {
        format!(
            "the longest stretch between the record's gaps has {longest} ({pieces} pieces, {} gaps)",
            pieces - 1
        )
    } else {
        format!("the record has {longest}")
    }
}

impl PipelineError {
    /// The windows' error `e`, made [`PipelineError::NoWindow`] when no window fits (a window of
    /// `window`, in words, over a record in `pieces` pieces).
    pub(crate) fn windows(e: upo_search::UpoError, window: impl FnOnce() -> String, pieces: usize) -> Self {
        match e {
            upo_search::UpoError::TooShort { len, needed, .. } => PipelineError::NoWindow {
                window: window(),
                needed,
                longest: len,
                pieces,
            },
            e => PipelineError::from(e),
        }
    }

    /// The mutual information's error `e`, made [`PipelineError::NoDelayFits`] when its largest
    /// lag does not fit (in a record of `samples_per_period` samples per drive period, in `pieces`
    /// pieces; `remedy`, an option to give instead, if any).
    pub(crate) fn delay_search(
        e: embedding::EmbeddingError,
        samples_per_period: usize,
        pieces: usize,
        remedy: Option<&'static str>,
    ) -> Self {
        match e {
            embedding::EmbeddingError::LagTooLarge { max_lag, len } => PipelineError::NoDelayFits {
                max_lag,
                samples_per_period,
                longest: len,
                pieces,
                remedy,
            },
            e => PipelineError::from(e),
        }
    }

    /// The close-return search's error `e`, made [`PipelineError::NoOrbitFits`] when its longest
    /// period does not fit (in a record of `samples_per_period` samples per drive period, in
    /// `pieces` pieces).
    pub(crate) fn orbits(e: upo_search::UpoError, samples_per_period: usize, pieces: usize) -> Self {
        match e {
            upo_search::UpoError::TooShort { len, needed, period } => PipelineError::NoOrbitFits {
                period,
                samples_per_period,
                needed,
                longest: len,
                pieces,
            },
            e => PipelineError::from(e),
        }
    }
}
