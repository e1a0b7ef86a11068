/// Errors of the simulator.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SimError {
    /// A parameter is out of its range.
    #[error("invalid {name}: {} ({why})", circle_signal::Shown(*.value))]
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
    #[error("step size {h:e} too small at t = {}: the solution blows up or is not smooth", circle_signal::Shown(*.t))]
    StepSizeTooSmall {
        /// Time reached.
        t: f64,
        /// The step that was too small.
        h: f64,
    },
    /// The step budget ran out: the steps shrank as the solution grew (or turned stiff).
    #[error(
        "more than {steps} steps before t = {}: the solution blows up or is too stiff for the tolerances", circle_signal::Shown(*.t)
    )]
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
    /// The mass matrix of a system of several coordinates cannot be solved at the state reached:
    /// it is singular, or not positive definite ([`crate::SingularMass`]).
    #[error("the mass matrix is singular at t = {} (relative pivot {pivot:e})", circle_signal::Shown(*.t))]
    SingularMass {
        /// Time reached.
        t: f64,
        /// The pivot that failed, relative to the matrix's scale.
        pivot: f64,
    },
    /// The right-hand side or the solution became NaN or infinite.
    #[error("the solution is not finite at t = {}", circle_signal::Shown(*.t))]
    NonFinite {
        /// Time reached.
        t: f64,
    },
    /// A trajectory kept in memory that the memory cannot hold.
    #[error(
        "{samples} samples of {series} series ({:.3e} GiB) cannot be held in memory: simulate fewer",
        *.samples as f64 * *.series as f64 * 8.0 / (1u64 << 30) as f64
    )]
    TooLarge {
        /// Samples asked for.
        samples: usize,
        /// Series of them kept (times, positions, velocities).
        series: usize,
    },
}

/// `series` empty series with room for `samples` values each, or [`SimError::TooLarge`] when the
/// memory cannot be had: an allocation that fails aborts the process, a reservation that fails
/// is an error.
pub fn reserve_series(series: usize, samples: usize) -> Result<Vec<Vec<f64>>, SimError> {
    let too_large = || SimError::TooLarge { samples, series };
    // All of them at once first: each alone could be had where all cannot.
    let total = samples.checked_mul(series).ok_or_else(too_large)?;
    Vec::<f64>::new()
        .try_reserve_exact(total)
        .map_err(|_| too_large())?;
    (0..series)
        .map(|_| {
            let mut v = Vec::new();
            v.try_reserve_exact(samples).map_err(|_| too_large())?;
            Ok(v)
        })
        .collect()
}

/// An [`SimError::InvalidParameter`].
pub(crate) fn invalid(name: &'static str, value: f64, why: &'static str) -> SimError {
    SimError::InvalidParameter { name, value, why }
}

/// `value` if finite.
pub(crate) fn finite(name: &'static str, value: f64) -> Result<f64, SimError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(invalid(name, value, "must be finite"))
    }
}

/// `value` if finite and `>= 0` (`-0.0` as `0.0`).
pub(crate) fn non_negative(name: &'static str, value: f64) -> Result<f64, SimError> {
    if value.is_finite() && value >= 0.0 {
        Ok(value + 0.0)
    } else {
        Err(invalid(name, value, "must be finite and non-negative"))
    }
}

/// `value` if finite and `> 0`.
pub(crate) fn positive(name: &'static str, value: f64) -> Result<f64, SimError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(invalid(name, value, "must be positive and finite"))
    }
}
