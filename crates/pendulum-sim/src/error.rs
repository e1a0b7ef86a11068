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
    /// The right-hand side or the solution became NaN or infinite.
    #[error("the solution is not finite at t = {t}")]
    NonFinite {
        /// Time reached.
        t: f64,
    },
}
