/// Errors of the simulator.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SimError {
    /// A parameter is out of its range.
    #[error("invalid {name}: {value} ({why})")]
    InvalidParameter {
        /// The parameter's name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What it must be.
        why: &'static str,
    },
    /// The step size fell below what floating point can resolve at this time: the solution is
    /// singular or blows up.
    #[error("step size {h:e} too small at t = {t}: the solution blows up or is not smooth")]
    StepSizeTooSmall {
        /// Time reached.
        t: f64,
        /// The step that was too small.
        h: f64,
    },
    /// The step budget ran out.
    #[error("more than {steps} steps before t = {t}")]
    TooManySteps {
        /// Time reached.
        t: f64,
        /// The budget.
        steps: usize,
    },
    /// No state can be estimated at a sample of a record: it is missing, or too few samples
    /// around it are there for the local fit.
    #[error("no state at sample {index}: the local fit needs the sample and {needed} samples around it")]
    NoStateEstimate {
        /// The sample.
        index: usize,
        /// Samples the fit needs.
        needed: usize,
    },
    /// A record too short for what was asked of it.
    #[error("the record has {len} samples; at least {needed} are needed")]
    RecordTooShort {
        /// Its samples.
        len: usize,
        /// The samples needed.
        needed: usize,
    },
    /// The right-hand side or the solution became NaN or infinite.
    #[error("the solution is not finite at t = {t}")]
    NonFinite {
        /// Time reached.
        t: f64,
    },
}
