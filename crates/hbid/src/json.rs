//! The JSON of the results, as the command line prints it with `--json` (and the Python package's
//! `to_json`): one definition for every front end.

use std::collections::BTreeMap;

use embedding::{AmiCurve, FnnResult};
use upo_search::Catalogue;

use crate::pipeline::{Identification, TermSelection};

/// The JSON of an identification, as `hbid identify --json` prints it: `method` and `basis` as
/// named on the command line, `drive_column` the record's column of the measured drive `p` (null
/// without one), `no_intervals` why there are no intervals when they were asked for (null
/// otherwise), `held_out_explained` the share explained on stretches of the record the model was
/// not fitted on (null when it cannot be had), `warning` that the model does not describe the
/// record.
pub fn identification(id: &Identification, method: &str, basis: &str) -> serde_json::Value {
    let model = &id.model;
    let intervals: Option<serde_json::Map<String, serde_json::Value>> = id.intervals.as_ref().map(|b| {
        b.intervals
            .iter()
            .map(|i| (i.name.clone(), serde_json::json!([i.lower, i.upper])))
            .collect()
    });
    let values: serde_json::Map<String, serde_json::Value> = model
        .coefficients()
        .iter()
        .map(|c| (c.name.clone(), c.value.into()))
        .collect();
    let errors: serde_json::Map<String, serde_json::Value> = model
        .coefficients()
        .iter()
        .map(|c| (c.name.clone(), c.std_error.into()))
        .collect();
    let summary = model.summary();
    let terms: Vec<&str> = model.coefficients().iter().map(|c| c.name.as_str()).collect();
    serde_json::json!({
        "method": method,
        "basis": basis,
        "terms": terms,
        "drive_column": model.form().drive_column(),
        "coefficients": values,
        "std_errors": errors,
        "orbits_used": summary.map(|s| s.segments),
        "rows": summary.map(|s| s.rows),
        "condition_number": summary.map(|s| s.condition),
        "residual_rms": summary.map(|s| s.residual_rms),
        "intervals": intervals,
        "interval_level": id.intervals.as_ref().map(|b| b.level),
        "no_intervals": id.no_intervals,
        "explained": id.quality.explained,
        "unexplained": id.quality.unexplained,
        "held_out_explained": id.quality.held_out.map(|h| h.explained),
        "residual_spectrum": id.quality.spectrum.iter().map(|l| serde_json::json!({
            "harmonic": l.harmonic, "residual_rms": l.residual_rms, "rhs_rms": l.rhs_rms, "rows": l.rows,
        })).collect::<Vec<_>>(),
        "warning": id.warning,
        "selection": id.selection.as_ref().map(selection),
    })
}

/// The JSON of a selection of terms: the library, the kept terms, the dropped ones with the
/// held-out unexplained fraction without and with each, the folds, the allowance and the
/// elimination path.
pub fn selection(selection: &TermSelection) -> serde_json::Value {
    let outcome = &selection.outcome;
    serde_json::json!({
        "library": selection.library.names(),
        "kept": selection.kept.names(),
        "dropped": outcome.dropped.iter().map(|d| serde_json::json!({
            "term": d.name,
            "unexplained_without": d.unexplained_without,
            "unexplained_with": d.unexplained_with,
        })).collect::<Vec<_>>(),
        "folds": outcome.folds,
        "allowance": outcome.allowance,
        "path": outcome.path.iter().map(|p| serde_json::json!({
            "removed": p.removed,
            "terms": p.size,
            "unexplained": p.unexplained,
            "std_error": p.std_error,
        })).collect::<Vec<_>>(),
    })
}

/// The JSON of the delay and the embedding dimension, as `hbid embed --json` prints it.
pub fn embedding(curve: &AmiCurve, delay: usize, fnn: &FnnResult) -> serde_json::Value {
    serde_json::json!({
        "delay": delay,
        "ami": curve.values,
        "fnn": fnn.levels.iter().map(|l| l.fraction()).collect::<Vec<_>>(),
        "embedding_dimension": fnn.minimum_dimension(),
    })
}

/// The JSON of the orbits found by close returns, as `hbid upos --json` prints it.
pub fn orbits(catalogue: &Catalogue) -> serde_json::Value {
    let counts = catalogue.counts();
    let by_period: BTreeMap<String, usize> = counts
        .iter()
        .map(|c| (c.period.to_string(), c.segments))
        .collect();
    let distinct: BTreeMap<String, usize> = counts.iter().map(|c| (c.period.to_string(), c.orbits)).collect();
    serde_json::json!({
        "segments": catalogue.segments().len(),
        "by_period": by_period,
        "distinct_orbits": catalogue.orbits().len(),
        "distinct_by_period": distinct,
        "orbits": catalogue.segments().iter().map(|s| serde_json::json!({
            "period": s.period(), "start": s.start(), "error": s.error(),
        })).collect::<Vec<_>>(),
    })
}
