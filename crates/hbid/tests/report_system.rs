//! `hbid report` of a system of several coordinates: a double pendulum's record made by `hbid
//! simulate`, identified with `--coords` by both methods or read from a model saved by `hbid
//! identify --save-model`, reported with each equation's coefficients, the residuals, each
//! coordinate's free run against the record, the phase portraits and Poincaré sections of the
//! record beside the models' and the valid prediction time; a system driven by a measured drive
//! has no section and says so; bad input fails with one line and leaves no report.
use crate::support::hbid_quiet as hbid;
use std::path::{Path, PathBuf};
use std::process::Output;

fn ok(args: &[&str]) -> Output {
    let out = hbid(args);
    assert!(
        out.status.success(),
        "hbid {}: {}",
        args.join(" "),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// A fresh scratch folder (emptied first) of this module.
fn scratch(name: &str) -> PathBuf {
    let dir = crate::support::scratch("report-system", name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// The whirling double pendulum as `hbid simulate` writes it (t,theta1,theta2,omega1,omega2:
/// 30000 samples at 64 per drive period), and the `--terms` of its truth.
fn double_pendulum(dir: &Path) -> (PathBuf, String, serde_json::Value) {
    let record = dir.join("dp.csv");
    let truth = dir.join("dp.json");
    ok(&[
        "simulate",
        "--system",
        "double-pendulum",
        "--truth",
        s(&truth),
        "--out",
        s(&record),
    ]);
    let truth = json(&truth);
    let terms = truth["identify"]["terms"].as_str().unwrap().to_owned();
    (record, terms, truth)
}

/// Every figure README.md shows exists and is a PNG of some size, and every PNG of the folder
/// is shown; the report ends with its figures, the last the valid prediction time's.
fn assert_complete(dir: &Path) -> String {
    let text = assert_figures(dir);
    let last = text.trim_end().lines().last().unwrap();
    assert!(last.ends_with(" the record's own state."), "ends with: {last}");
    text
}

/// Every figure README.md shows exists and is a PNG of some size, and every PNG of the folder
/// is shown.
fn assert_figures(dir: &Path) -> String {
    let text = std::fs::read_to_string(dir.join("README.md")).unwrap();
    let shown: Vec<&str> = text
        .lines()
        .filter_map(|l| l.strip_prefix("!["))
        .map(|l| {
            let (_, rest) = l.split_once("](").unwrap();
            rest.trim_end_matches(')')
        })
        .collect();
    assert!(!shown.is_empty());
    for file in &shown {
        let bytes = std::fs::read(dir.join(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert!(bytes.len() > 1000 && bytes.starts_with(b"\x89PNG"), "{file}");
    }
    for entry in std::fs::read_dir(dir).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        assert!(!name.starts_with(".hbid-partial"), "{name} left behind");
        if name.ends_with(".png") {
            assert!(shown.contains(&name.as_str()), "{name} not in the report");
        }
    }
    text
}

/// The phase portrait and the Poincaré sections of every coordinate, and in the angles' torus,
/// as figures; each model's section as far from the record's as the record's halves are from
/// each other, give or take the estimate's scatter at these sizes.
fn assert_sections(dir: &Path, text: &str, models: &[&str]) {
    assert!(text.contains("## Phase portraits and Poincaré sections"));
    for figure in [
        "portrait_theta1.png",
        "portrait_theta2.png",
        "section_theta1.png",
        "section_theta2.png",
        "section_theta1_theta2.png",
    ] {
        assert!(text.contains(&format!("]({figure})")), "{figure} not shown");
    }
    assert!(text.contains("| model | section points | energy distance to the record's section |"));
    let sections = json(&dir.join("sections.json"));
    let floor = sections["floor"].as_f64().unwrap();
    assert!(sections["record_points"].as_u64().unwrap() > 400, "{sections}");
    let rows = sections["models"].as_array().unwrap();
    assert_eq!(rows.len(), models.len());
    for (row, model) in rows.iter().zip(models) {
        assert_eq!(row["model"], *model);
        assert_eq!(row["points"], 300);
        let distance = row["distance"].as_f64().unwrap();
        assert!(distance.abs() < 0.05 && floor.abs() < 0.05, "{sections}");
        assert!(
            text.contains(&format!("| {model} | 300 | {distance:.2e} |")),
            "{model}'s distance not in the report"
        );
    }
}

/// The coefficient of `term` in the table of the equation of `coordinate` under `heading`.
fn coefficient(text: &str, heading: &str, coordinate: &str, term: &str) -> f64 {
    let section = &text[text.find(heading).unwrap_or_else(|| panic!("{heading} missing"))..];
    let equation = &section[section
        .find(&format!("### The equation of {coordinate}"))
        .unwrap()..];
    let row = equation
        .lines()
        .find(|l| l.starts_with(&format!("| `{term}` |")))
        .unwrap_or_else(|| panic!("{term} missing"));
    row.split('|').nth(2).unwrap().trim().parse().unwrap()
}

#[test]
fn report_identifies_a_double_pendulum_by_both_methods() {
    let dir = scratch("both");
    let (record, terms, truth) = double_pendulum(&dir);
    let out = dir.join("report");
    ok(&[
        "report",
        s(&record),
        "--coords",
        "theta1,theta2",
        "--terms",
        &terms,
        "--bootstrap",
        "0",
        "--out",
        s(&out),
    ]);
    let text = assert_complete(&out);
    assert_sections(&out, &text, &["upo", "windowed"]);
    for needle in [
        "A system of 2 coordinates (theta1, theta2)",
        "## Identified system: upo",
        "## Identified system: windowed",
        "## Residuals of the fit",
        "## Free run against the record",
        "## How long do the models predict the record?",
        "| windowed | theta2 |",
    ] {
        assert!(text.contains(needle), "{needle} missing");
    }
    // Every true coefficient in the weak form's tables, to the accuracy of its fit.
    for coordinate in ["theta1", "theta2"] {
        let equation = truth["equations"][coordinate]["coefficients"]
            .as_object()
            .unwrap();
        for (term, want) in equation {
            let got = coefficient(&text, "## Identified system: windowed", coordinate, term);
            assert!(
                (got - want.as_f64().unwrap()).abs() < 1e-4,
                "{coordinate}: {term} {got}"
            );
        }
    }
    // Per model and coordinate, the free run and its residual.
    for model in ["upo", "windowed"] {
        for coordinate in ["theta1", "theta2"] {
            for kind in ["compare", "residual"] {
                assert!(out.join(format!("{kind}_{model}_{coordinate}.png")).exists());
            }
        }
        // The saved system reads back with both equations.
        let saved = json(&out.join(format!("model_{model}.json")));
        assert_eq!(saved["coordinates"], serde_json::json!(["theta1", "theta2"]));
        assert_eq!(saved["equations"].as_array().unwrap().len(), 2);
    }
    let compare = json(&out.join("compare.json"));
    let models = compare["models"].as_array().unwrap();
    assert_eq!(models.len(), 2);
    for m in models {
        assert_eq!(
            m["compare"]["coordinates"],
            serde_json::json!(["theta1", "theta2"])
        );
        assert_eq!(m["compare"]["ranges"].as_array().unwrap().len(), 2);
    }
    let prediction = json(&out.join("prediction.json"));
    assert_eq!(prediction["coordinates"], serde_json::json!(["theta1", "theta2"]));
    for m in prediction["models"].as_array().unwrap() {
        let windows = m["windows"].as_array().unwrap();
        assert_eq!(windows.len(), 32);
        // Each window that ended names the coordinate that left first.
        assert!(
            windows
                .iter()
                .all(|w| w["censored"].as_bool().unwrap() || w["left"].is_u64())
        );
        assert!(m["periods"]["median"].as_f64().unwrap() > 0.5, "{m}");
    }
}

#[test]
fn report_of_a_saved_system() {
    let dir = scratch("saved");
    let (record, terms, truth) = double_pendulum(&dir);
    let model = dir.join("dp-model.json");
    ok(&[
        "identify",
        s(&record),
        "--coords",
        "theta1,theta2",
        "--terms",
        &terms,
        "--bootstrap",
        "0",
        "--save-model",
        s(&model),
    ]);
    let out = dir.join("report");
    ok(&["report", s(&record), "--model", s(&model), "--out", s(&out)]);
    let text = assert_complete(&out);
    assert_sections(&out, &text, &["model"]);
    assert!(text.contains("(2 coordinate(s): theta1, theta2)"), "{text}");
    assert!(text.contains("## The model: the saved model"));
    let want = truth["equations"]["theta2"]["coefficients"]["sin(theta2)"]
        .as_f64()
        .unwrap();
    let got = coefficient(&text, "## The model", "theta2", "sin(theta2)");
    assert!((got - want).abs() < 1e-4, "{got}");
    for coordinate in ["theta1", "theta2"] {
        assert!(out.join(format!("compare_model_{coordinate}.png")).exists());
        assert!(out.join(format!("residual_model_{coordinate}.png")).exists());
    }
    // A saved model is reported, not saved again.
    assert!(!out.join("model_model.json").exists());
    // The same system's columns under other names: --coords maps them.
    let renamed = dir.join("renamed.csv");
    let csv = std::fs::read_to_string(&record).unwrap();
    std::fs::write(&renamed, csv.replacen("theta1,theta2", "a1,a2", 1)).unwrap();
    let out = dir.join("renamed-report");
    ok(&[
        "report",
        s(&renamed),
        "--model",
        s(&model),
        "--coords",
        "theta1=a1,theta2=a2",
        "--out",
        s(&out),
    ]);
    assert_complete(&out);
}

/// Two coupled Duffing oscillators on a shaken base, driven by its measured acceleration `a`
/// alone: each coordinate's phase portrait beside each model's free run under the measured drive,
/// and no stroboscopic section (the drive has no period), said in the report, not failed on.
#[test]
fn a_system_driven_by_a_measured_drive_has_no_stroboscopic_section() {
    let dir = scratch("measured");
    let record = dir.join("cd.csv");
    let truth = dir.join("cd.json");
    ok(&[
        "simulate",
        "--system",
        "coupled-duffing",
        "--samples",
        "4000",
        "--truth",
        s(&truth),
        "--out",
        s(&record),
    ]);
    let identify = json(&truth)["identify"].clone();
    let out = dir.join("report");
    ok(&[
        "report",
        s(&record),
        "--coords",
        "x1,x2",
        "--signal",
        "line",
        "--drive-col",
        "a",
        "--window",
        &identify["window"].as_f64().unwrap().to_string(),
        "--terms",
        identify["terms"].as_str().unwrap(),
        "--bootstrap",
        "0",
        "--out",
        s(&out),
    ]);
    let text = assert_figures(&out);
    assert!(
        text.contains(
            "There is no stroboscopic section: the system is driven by the record's measured drive (a), which has \
             no period"
        ),
        "{text}"
    );
    assert!(text.contains("driven by the record's measured drives"), "{text}");
    for coordinate in ["x1", "x2"] {
        assert!(
            text.contains(&format!("](portrait_{coordinate}.png)")),
            "{coordinate}"
        );
        assert!(!out.join(format!("section_{coordinate}.png")).exists());
    }
    assert!(!out.join("section_x1_x2.png").exists());
    let sections = json(&out.join("sections.json"));
    assert!(
        sections["no_section"]
            .as_str()
            .unwrap()
            .contains("measured drive")
    );
    assert!(sections.get("models").is_none());
}

/// One line on stderr naming the problem, a failing status, and no report: not README.md, not a
/// figure, not the folder.
fn assert_refused(args: &[&str], out: &Path, mentions: &str) {
    let result = hbid(args);
    assert!(!result.status.success(), "hbid {} succeeded", args.join(" "));
    let err = String::from_utf8_lossy(&result.stderr);
    assert!(!err.contains("panicked"), "panic: {err}");
    let errors: Vec<&str> = err.lines().filter(|l| !l.starts_with("warning:")).collect();
    assert_eq!(errors.len(), 1, "one line expected: {err}");
    assert!(errors[0].contains(mentions), "'{mentions}' not in: {err}");
    assert!(!out.exists(), "{} left behind for: {err}", out.display());
}

#[test]
fn bad_input_leaves_no_report() {
    let dir = scratch("bad");
    let (record, terms, _) = double_pendulum(&dir);
    let model = dir.join("dp-model.json");
    ok(&[
        "identify",
        s(&record),
        "--coords",
        "theta1,theta2",
        "--terms",
        &terms,
        "--bootstrap",
        "0",
        "--save-model",
        s(&model),
    ]);
    let out = dir.join("report");
    let o = s(&out);
    let r = s(&record);
    // A model that is not there, or not a model.
    let missing = dir.join("missing.json");
    assert_refused(
        &["report", r, "--model", s(&missing), "--out", o],
        &out,
        "missing.json",
    );
    let garbage = dir.join("garbage.json");
    std::fs::write(&garbage, "{\"format\": \"hbid-model\", \"version\": 5}").unwrap();
    assert_refused(
        &["report", r, "--model", s(&garbage), "--out", o],
        &out,
        "garbage.json",
    );
    // A record without the system's columns.
    let paper = dir.join("one.csv");
    std::fs::write(&paper, "t,theta\n0,0.1\n0.1,0.2\n0.2,0.25\n0.3,0.2\n").unwrap();
    assert_refused(
        &["report", s(&paper), "--model", s(&model), "--out", o],
        &out,
        "theta1",
    );
    // One of them missing: the columns are chosen with --coords (a system's), not --angle-col.
    let half = dir.join("half.csv");
    std::fs::write(&half, "t,theta1\n0,0.1\n0.1,0.2\n0.2,0.25\n0.3,0.2\n").unwrap();
    assert_refused(
        &["report", s(&half), "--model", s(&model), "--out", o],
        &out,
        "no angle column 'theta2' in the input (columns: t,theta1); choose the coordinates' columns with --coords",
    );
    // Columns that are not in the record.
    assert_refused(
        &["report", r, "--coords", "theta1,nosuch", "--out", o],
        &out,
        "nosuch",
    );
    // Terms that do not parse, and identification options beside a saved model.
    assert_refused(
        &[
            "report",
            r,
            "--coords",
            "theta1,theta2",
            "--terms",
            "theta1: sin(theta3)",
            "--out",
            o,
        ],
        &out,
        "terms",
    );
    assert_refused(
        &["report", r, "--model", s(&model), "--terms", &terms, "--out", o],
        &out,
        "--terms",
    );
    // A model of another number of coordinates than the columns named.
    assert_refused(
        &[
            "report",
            r,
            "--model",
            s(&model),
            "--coords",
            "theta1",
            "--out",
            o,
        ],
        &out,
        "coords",
    );
    // Not a folder.
    let file = dir.join("plain");
    std::fs::write(&file, "x").unwrap();
    let result = hbid(&["report", r, "--model", s(&model), "--out", s(&file)]);
    assert!(!result.status.success());
    assert!(String::from_utf8_lossy(&result.stderr).contains("not a folder"));
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "x");
}

/// A report is written beside its folder and moved into it whole: one that cannot write a file
/// (a folder in the way) leaves none of its files, and a report written into an earlier one's
/// folder leaves none of that report's files it does not write again.
#[test]
fn a_report_is_written_whole_or_not_at_all() {
    let dir = scratch("whole");
    let (record, _, _) = double_pendulum(&dir);
    let out = dir.join("report");
    std::fs::create_dir_all(out.join("prediction.png")).unwrap();
    let r = s(&record);
    let windowed = [
        "report",
        r,
        "--coords",
        "theta1,theta2",
        "--method",
        "windowed",
        "--out",
        s(&out),
    ];
    let result = hbid(&windowed);
    let err = String::from_utf8_lossy(&result.stderr);
    assert!(!result.status.success() && !err.contains("panicked"), "{err}");
    assert!(err.contains("prediction.png is a folder"), "{err}");
    let left: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left, ["prediction.png"], "{err}");
    std::fs::remove_dir_all(&out).unwrap();
    // Both methods, then the windowed method alone into the same folder: the orbits' files go.
    ok(&["report", r, "--coords", "theta1,theta2", "--out", s(&out)]);
    assert!(out.join("model_upo.json").exists());
    ok(&windowed);
    assert!(!out.join("model_upo.json").exists() && out.join("model_windowed.json").exists());
    let mut names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert!(names.iter().all(|n| !n.contains("upo")), "{names:?}");
    assert_complete(&out);
    // Nothing is left beside the folder.
    let beside: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".hbid"))
        .collect();
    assert!(beside.is_empty(), "{beside:?}");
}
