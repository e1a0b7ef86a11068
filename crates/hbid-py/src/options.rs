//! The Python arguments as the library's types, each checked with a message that names the
//! Python argument.

use std::f64::consts::TAU;

use circle_signal::Domain;
use hb_basis::{BasisKind, Harmonic, Hat, Polynomial};
use hb_pipeline::pipeline::Method;
use hb_record::prepare::DriveSpec;
use hb_solve::{NoiseCorrection, PeriodRange};
use pyo3::prelude::*;

use crate::errors::Kind;

/// A failure inside the work done without the interpreter: the exception to raise and its text.
pub type Failure = (Kind, String);

/// A failure of `kind` from a Rust error, with its chain of messages.
pub fn fail<E: std::error::Error + 'static>(kind: Kind) -> impl FnOnce(E) -> Failure {
    move |e| (kind, crate::errors::chain(&e))
}

/// A bad argument.
pub fn bad(message: impl Into<String>) -> Failure {
    (Kind::Options, message.into())
}

/// A number or a text, as `forcing_period=2.0` or `forcing_period="auto:5..7"`.
#[derive(Debug, Clone, FromPyObject)]
pub enum NumberOrText {
    /// A number.
    Number(f64),
    /// A text.
    Text(String),
}

/// `signal=`: `circle` or `line` (and `linear` for a metric).
pub fn domain(name: &str, argument: &str, also_linear: bool) -> Result<Domain, Failure> {
    match name {
        "circle" => Ok(Domain::Circle),
        "line" => Ok(Domain::Line),
        "linear" if also_linear => Ok(Domain::Line),
        other => Err(bad(format!(
            "{argument}='{other}': expected 'circle' or 'line'{}",
            if also_linear { " (or 'linear')" } else { "" }
        ))),
    }
}

/// `method=`: `windowed` or `upo`.
pub fn method(name: &str) -> Result<Method, Failure> {
    match name {
        "windowed" => Ok(Method::Windowed),
        "upo" => Ok(Method::Upo),
        other => Err(bad(format!("method='{other}': expected 'windowed' or 'upo'"))),
    }
}

/// `basis=`: `harmonic:K`, `hat:N` or `poly:D`.
pub fn basis(text: &str) -> Result<BasisKind, Failure> {
    let (kind, n) = text
        .split_once(':')
        .ok_or_else(|| bad(format!("basis='{text}': expected harmonic:K, hat:N or poly:D")))?;
    let n: usize = n
        .trim()
        .parse()
        .map_err(|_| bad(format!("basis='{text}': '{n}' is not a whole number")))?;
    let options = |e: hb_basis::BasisError| (Kind::Options, format!("basis='{text}': {e}"));
    Ok(match kind.trim() {
        "harmonic" => BasisKind::from(Harmonic::new(n).map_err(options)?),
        "hat" => BasisKind::from(Hat::new(n).map_err(options)?),
        "poly" => BasisKind::from(Polynomial::new(n).map_err(options)?),
        other => {
            return Err(bad(format!(
                "basis='{text}': unknown basis '{other}' (harmonic, hat or poly)"
            )));
        }
    })
}

/// The basis named as the command line does when none is chosen.
pub fn default_basis_name(domain: Domain) -> &'static str {
    match domain {
        Domain::Circle => "harmonic:1",
        Domain::Line => "poly:3",
    }
}

/// `noise_sigma=`: radians, or `auto`.
pub fn noise(value: Option<NumberOrText>) -> Result<NoiseCorrection, Failure> {
    Ok(match value {
        None => NoiseCorrection::None,
        Some(NumberOrText::Text(t)) if t == "auto" => NoiseCorrection::Estimated,
        Some(NumberOrText::Number(sigma)) => NoiseCorrection::Given { sigma },
        Some(NumberOrText::Text(t)) => match t.trim().parse() {
            Ok(sigma) => NoiseCorrection::Given { sigma },
            Err(_) => return Err(bad(format!("noise_sigma='{t}': a number of radians or 'auto'"))),
        },
    })
}

/// The drive from `forcing_period=` or `forcing_frequency=` (a number, `auto` or `auto:A..B`);
/// without either, none when `free`, else the period 2π of the paper's time.
pub fn drive(
    period: Option<NumberOrText>,
    frequency: Option<NumberOrText>,
    free: bool,
) -> Result<DriveSpec, Failure> {
    match (period, frequency) {
        (Some(_), Some(_)) => Err(bad("give forcing_period or forcing_frequency, not both")),
        (Some(p), None) => one_drive(p, false),
        (None, Some(f)) => one_drive(f, true),
        (None, None) if free => Ok(DriveSpec::Free),
        (None, None) => Ok(DriveSpec::Period(TAU)),
    }
}

fn one_drive(value: NumberOrText, frequency: bool) -> Result<DriveSpec, Failure> {
    let argument = if frequency {
        "forcing_frequency"
    } else {
        "forcing_period"
    };
    let positive = |v: f64, shown: &str| {
        if v.is_finite() && v > 0.0 {
            Ok(v)
        } else {
            Err(bad(format!(
                "{argument}={shown}: {v} must be positive and finite"
            )))
        }
    };
    let text = match value {
        NumberOrText::Number(v) => {
            let v = positive(v, &v.to_string())?;
            return Ok(DriveSpec::Period(if frequency { 1.0 / v } else { v }));
        }
        NumberOrText::Text(t) => t,
    };
    let shown = format!("'{text}'");
    let number = |s: &str| -> Result<f64, Failure> {
        let v: f64 = s
            .trim()
            .parse()
            .map_err(|_| bad(format!("{argument}={shown}: '{}' is not a number", s.trim())))?;
        positive(v, &shown)
    };
    let trimmed = text.trim();
    if let Some(rest) = trimmed.strip_prefix("auto") {
        if rest.is_empty() {
            return Ok(DriveSpec::Auto(None));
        }
        let (a, b) = rest
            .strip_prefix(':')
            .and_then(|r| r.split_once(".."))
            .ok_or_else(|| {
                bad(format!(
                    "{argument}={shown}: expected a number, 'auto' or 'auto:A..B'"
                ))
            })?;
        let (a, b) = (number(a)?, number(b)?);
        let range = if frequency {
            PeriodRange::frequencies(a, b)
        } else {
            PeriodRange::periods(a, b)
        }
        .map_err(|e| bad(format!("{argument}={shown}: {}", crate::errors::chain(&e))))?;
        return Ok(DriveSpec::Auto(Some(range)));
    }
    let v = number(trimmed)?;
    Ok(DriveSpec::Period(if frequency { 1.0 / v } else { v }))
}
