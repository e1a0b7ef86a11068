//! `hbid identify --tie`: physical parameters shared by a system's equations, on the simulated
//! torque-driven double pendulum (the DFKI arm) whose truth `hbid simulate` writes.
use crate::support::hbid;
use std::path::{Path, PathBuf};

use serde_json::{Value, json};

fn scratch(name: &str) -> PathBuf {
    crate::support::scratch("tie", name)
}

/// The simulated arm record and its truth.
fn arm(dir: &Path) -> (PathBuf, Value) {
    let record = dir.join("arm.csv");
    let truth = dir.join("arm.json");
    let out = hbid(&[
        "simulate",
        "--system",
        "arm",
        "--truth",
        truth.to_str().unwrap(),
        "--out",
        record.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let truth: Value = serde_json::from_str(&std::fs::read_to_string(&truth).unwrap()).unwrap();
    (record, truth)
}

/// The rigid-body parameters of the DFKI model as the spec names them, from the truth's
/// parameters: `Ia = I1 + m2 l1²`, `mr1 = m1 r1 + m2 l1`, `mr2 = m2 r2`.
fn physical(truth: &Value) -> Vec<(&'static str, f64)> {
    let p = |k: &str| truth["parameters"][k].as_f64().unwrap();
    vec![
        ("Ia", p("I1") + p("m2") * p("l1") * p("l1")),
        ("I2", p("I2")),
        ("Ir", p("Ir")),
        ("mr1", p("m1") * p("r1") + p("m2") * p("l1")),
        ("mr2", p("m2") * p("r2")),
        ("b1", p("b1")),
        ("cf1", p("cf1")),
        ("b2", p("b2")),
        ("cf2", p("cf2")),
    ]
}

/// The tie spec of the arm's equations (`pendulum_sim::ArmTie`), with the known `g`, `l1` and
/// gear ratio of the truth, and its Coulomb friction `cf · sign(q')`.
fn arm_spec(truth: &Value) -> Value {
    let p = |k: &str| truth["parameters"][k].as_f64().unwrap();
    serde_json::to_value(pendulum_sim::ArmTie::new(p("l1"), p("g"), p("gr"), 1.0)).unwrap()
}

/// The truth's `identify` options less `--terms` (the record's coordinates, drives, window).
fn base_args(truth: &Value, record: &Path) -> Vec<String> {
    let mut args = vec!["identify".to_owned(), record.to_str().unwrap().to_owned()];
    let given: Vec<String> = truth["identify"]["args"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a.as_str().unwrap().to_owned())
        .collect();
    let mut i = 0;
    while i < given.len() {
        if given[i] == "--terms" {
            i += 2;
            continue;
        }
        args.push(given[i].clone());
        i += 1;
    }
    args
}

fn run_json(args: &[String]) -> Value {
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    let out = hbid(&refs);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    serde_json::from_slice(&out.stdout).unwrap()
}

fn write(dir: &Path, name: &str, spec: &Value) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_string_pretty(spec).unwrap()).unwrap();
    path
}

/// Noise-free, the tied weak form lands every physical parameter within 1e-3 of the truth
/// (measured: the worst, b1, 5.5e-4; the rigid-body ones within 2e-4), and the saved model is
/// the ordinary system that `compare` reads.
#[test]
fn tied_fit_recovers_the_arms_physical_parameters() {
    let dir = scratch("truth");
    let (record, truth) = arm(&dir);
    let spec = write(&dir, "tie.json", &arm_spec(&truth));
    let model = dir.join("model.json");
    let mut args = base_args(&truth, &record);
    args.extend([
        "--tie".to_owned(),
        spec.to_str().unwrap().to_owned(),
        "--save-model".to_owned(),
        model.to_str().unwrap().to_owned(),
        "--json".to_owned(),
    ]);
    let v = run_json(&args);
    let mut worst = 0.0_f64;
    for (name, value) in physical(&truth) {
        let got = v["parameters"][name]["value"].as_f64().unwrap();
        let se = v["parameters"][name]["std_error"].as_f64().unwrap();
        assert!(se.is_finite() && se > 0.0, "{name}: std error {se}");
        // The bootstrap's interval of the parameter, every equation's rows of a window together.
        let interval = &v["parameters"][name]["interval"];
        let (lo, hi) = (interval[0].as_f64().unwrap(), interval[1].as_f64().unwrap());
        assert!(
            lo < got && got < hi,
            "{name}: {got} outside its interval [{lo}, {hi}]"
        );
        let rel = (got - value).abs() / value.abs();
        worst = worst.max(rel);
        assert!(rel < 1e-3, "{name}: {got} against the truth {value} ({rel:.2e})");
    }
    // Measured: 5.5e-4 (b1); the bound above is a little more.
    assert!(worst > 0.0, "an exact fit would hide a broken comparison");
    // The equations' normalised coefficients are the truth's.
    for q in ["q1", "q2"] {
        let coefficients = truth["equations"][q]["coefficients"].as_object().unwrap();
        for (term, value) in coefficients {
            let got = v["equations"][q]["coefficients"][term].as_f64().unwrap();
            let value = value.as_f64().unwrap();
            assert!(
                (got - value).abs() <= 2e-3 * value.abs(),
                "{q}: {term} {got} against {value}"
            );
        }
    }
    let saved: Value = serde_json::from_str(&std::fs::read_to_string(&model).unwrap()).unwrap();
    assert_eq!(saved["equations"].as_array().unwrap().len(), 2);
    let out = hbid(&[
        "compare",
        model.to_str().unwrap(),
        record.to_str().unwrap(),
        "--coords",
        "q1,q2",
        "--drive-col",
        "tau1,tau2",
        "--velocity-col",
        "v1,v2",
        "--json",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
}

/// A report of a tied fit lists its physical parameters as `identify` gives them; with the
/// measured velocities its free runs start from the measured states, and it says so.
#[test]
fn a_report_of_a_tied_fit_lists_its_parameters() {
    let dir = scratch("tied-report");
    let (record, truth) = arm(&dir);
    let spec = write(&dir, "tie.json", &arm_spec(&truth));
    let mut args = base_args(&truth, &record);
    args.extend([
        "--tie".to_owned(),
        spec.to_str().unwrap().to_owned(),
        "--bootstrap".into(),
        "0".into(),
    ]);
    let mut identify = args.clone();
    identify.push("--json".into());
    let v = run_json(&identify);
    let out = dir.join("report");
    args[0] = "report".into();
    args.extend([
        "--velocity-col".into(),
        "v1,v2".into(),
        "--method".into(),
        "windowed".into(),
        "--out".into(),
        out.to_str().unwrap().into(),
    ]);
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    let run = hbid(&refs);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let text = std::fs::read_to_string(out.join("README.md")).unwrap();
    assert!(text.contains("### The tied parameters"), "{text}");
    for (name, _) in physical(&truth) {
        let value = v["parameters"][name]["value"].as_f64().unwrap();
        assert!(
            text.contains(&format!("| `{name}` | {value:.6e} |")),
            "{name} {value:.6e} not in the report: {text}"
        );
    }
    assert!(
        text.contains(
            "from each piece's first measured state (the angles and `--velocity-col`), every sample scored"
        ),
        "{text}"
    );
    assert!(!text.contains("fitted to its first"), "{text}");
}

/// A spec whose every coefficient is a parameter of its own, the own acceleration fixed to 1, ties
/// nothing: the stacked least squares is the two equations' own, and gives the untied fit's
/// coefficients.
#[test]
fn a_spec_that_ties_nothing_is_the_untied_fit() {
    let dir = scratch("untied");
    let (record, truth) = arm(&dir);
    let terms = truth["identify"]["terms"].as_str().unwrap();
    let mut parameters = Vec::new();
    let mut equations = serde_json::Map::new();
    for part in terms.split(';') {
        let (q, list) = part.split_once(':').unwrap();
        let q = q.trim();
        let mut eq = serde_json::Map::new();
        eq.insert(format!("{q}''"), json!(1.0));
        for (k, term) in list.split(", ").enumerate() {
            let name = format!("{q}_{k}");
            eq.insert(term.trim().to_owned(), json!({ name.clone(): 1.0 }));
            parameters.push(name);
        }
        equations.insert(q.to_owned(), Value::Object(eq));
    }
    let spec = write(
        &dir,
        "none.json",
        &json!({"parameters": parameters, "equations": equations}),
    );
    let mut tied = base_args(&truth, &record);
    tied.extend(["--tie".into(), spec.to_str().unwrap().into(), "--json".into()]);
    let mut untied = base_args(&truth, &record);
    untied.extend([
        "--terms".into(),
        terms.into(),
        "--json".into(),
        "--bootstrap".into(),
        "0".into(),
    ]);
    let (t, u) = (run_json(&tied), run_json(&untied));
    for q in ["q1", "q2"] {
        let uc = u["equations"][q]["coefficients"].as_object().unwrap();
        let ts = t["equations"][q]["std_errors"].as_object().unwrap();
        for (term, value) in uc {
            let (a, b) = (
                t["equations"][q]["coefficients"][term].as_f64().unwrap(),
                value.as_f64().unwrap(),
            );
            assert!(
                (a - b).abs() <= 1e-9 * b.abs().max(1e-3),
                "{q}: {term} tied {a}, untied {b}"
            );
            let (sa, sb) = (
                ts[term].as_f64().unwrap(),
                u["equations"][q]["std_errors"][term].as_f64().unwrap(),
            );
            assert!(
                sa.is_finite() && sa > 0.0 && sb > 0.0,
                "{q}: {term} std errors {sa} {sb}"
            );
        }
    }
}

/// Every bad spec or combination is one line naming `--tie` and what is wrong, and writes no
/// model.
#[test]
fn bad_tie_specs_fail_in_one_line_without_output() {
    let dir = scratch("bad");
    let (record, truth) = arm(&dir);
    let good = arm_spec(&truth);
    let edit = |f: &dyn Fn(&mut Value)| {
        let mut v = good.clone();
        f(&mut v);
        v
    };
    let model = dir.join("never.json");
    let cases: Vec<(Value, Vec<&str>, &str)> = vec![
        (
            edit(&|v| v["equations"]["q1"]["q1'"] = json!({"b9": 1.0})),
            vec![],
            "'b9'",
        ),
        (
            edit(&|v| v["parameters"].as_array_mut().unwrap().push(json!("extra"))),
            vec![],
            "'extra' is used by no coefficient",
        ),
        (
            edit(&|v| v["equations"]["q2"]["tau2"] = json!({"cf2": 1.0})),
            vec![],
            "equation of q2 has no fixed coefficient",
        ),
        (
            edit(&|v| {
                v["equations"]["q2"].as_object_mut().unwrap().remove("q2''");
            }),
            vec![],
            "no coefficient of its own acceleration",
        ),
        (
            edit(&|v| v["equations"]["q1"]["q1''"] = json!(0.0)),
            vec![],
            "own acceleration fixed to 0",
        ),
        (
            edit(&|v| v["equations"]["q3"] = json!({"q3''": {"I2": 1.0}, "tau2": -1.0})),
            vec![],
            "'q3' is not one of the record's coordinates",
        ),
        (
            edit(&|v| v["equations"]["q1"]["sin(q9)"] = json!(1.0)),
            vec![],
            "sin(q9)",
        ),
        (
            // b1 and a second parameter only ever together: not identifiable.
            edit(&|v| {
                v["parameters"].as_array_mut().unwrap().push(json!("b1x"));
                v["equations"]["q1"]["q1'"] = json!({"b1": 1.0, "b1x": 2.0});
            }),
            vec![],
            "not identifiable",
        ),
        (good.clone(), vec!["--terms", "q1'"], "replaces --terms"),
        (good.clone(), vec!["--select"], "not supported with --select"),
        (
            good.clone(),
            vec!["--method", "upo"],
            "not supported with --method upo",
        ),
    ];
    for (i, (spec, extra, mentions)) in cases.iter().enumerate() {
        let path = write(&dir, &format!("bad{i}.json"), spec);
        let mut args = base_args(&truth, &record);
        args.extend(["--tie".into(), path.to_str().unwrap().into()]);
        args.extend(extra.iter().map(|s| s.to_string()));
        args.extend(["--save-model".into(), model.to_str().unwrap().into()]);
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = hbid(&refs);
        // The notes of the record read before a failure of the fit are not the error.
        let err: String = String::from_utf8_lossy(&out.stderr)
            .lines()
            .filter(|l| !l.starts_with("note:"))
            .collect::<Vec<_>>()
            .join("\n");
        assert!(!out.status.success(), "case {i}: expected failure");
        assert!(!err.contains("panicked"), "case {i}: {err}");
        assert_eq!(
            err.trim().lines().count(),
            1,
            "case {i}: one line expected: {err}"
        );
        assert!(err.contains("--tie"), "case {i}: --tie not named: {err}");
        assert!(err.contains(mentions), "case {i}: '{mentions}' not in: {err}");
        assert!(!model.exists(), "case {i}: a model was written");
    }
    // A file that is not there, or not JSON.
    let not_json = dir.join("not.json");
    std::fs::write(&not_json, "{").unwrap();
    for (path, mentions) in [(dir.join("missing.json"), "cannot read"), (not_json, "not.json")] {
        let mut args = base_args(&truth, &record);
        args.extend(["--tie".into(), path.to_str().unwrap().into()]);
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = hbid(&refs);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.trim().lines().count() == 1, "{err}");
        assert!(err.contains("--tie") && err.contains(mentions), "{err}");
    }
}

/// The report of one coordinate identifies by both methods, and a tied fit is the weak form's
/// alone: `--tie` there is refused in one line, and no report is written (it was ignored).
#[test]
fn the_report_of_one_coordinate_refuses_a_tie() {
    let dir = scratch("report");
    let record = dir.join("pendulum.csv");
    let out = hbid(&["simulate", "--samples", "4000", "--out", record.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let spec = write(
        &dir,
        "pendulum_tie.json",
        &json!({
            "parameters": ["a", "c", "k"],
            "equations": {"x": {"x''": {"a": 1}, "x'": {"c": 1}, "sin(x)": {"k": 1}, "sin(t)*cos(x)": -1.52}}
        }),
    );
    let report = dir.join("report");
    let out = hbid(&[
        "report",
        record.to_str().unwrap(),
        "--time-col",
        "1",
        "--angle-col",
        "2",
        "--tie",
        spec.to_str().unwrap(),
        "--out",
        report.to_str().unwrap(),
        "--quiet",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("--tie") && stderr.contains("hbid identify --tie"),
        "{stderr}"
    );
    assert!(!report.exists(), "a report was written");
    std::fs::remove_dir_all(&dir).ok();
}
