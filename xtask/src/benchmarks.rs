//! `cargo xtask benchmarks`: the field's public benchmarks of `../shared/benchmarks` by their
//! protocols. Each is identified by one `hbid identify` command on its training part and scored
//! by `hbid compare` on its test parts (a free run under the test input, the first samples
//! setting the state, or the measured state where the record has velocities); a term selection
//! from a wider library, on the training part alone, is scored beside the physical model. The
//! DFKI double pendulum is in `dfki.rs`. Writes `docs/benchmarks.md` and, with `--out DIR`,
//! `DIR/benchmarks.json`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anyhow::{Context, bail};
use serde_json::{Value, json};

use crate::{hbid, shown};

/// The `hbid` of this xtask's own build (the test profile: `cargo xtask` shares the build of
/// `cargo test --workspace`), brought up to date by `cargo test --workspace --no-run`: with the
/// workspace's features, so that after `cargo test` it builds nothing (`cargo build -p hbid`
/// alone would resolve other features and build every dependency again).
fn hbid_exe() -> anyhow::Result<PathBuf> {
    let status = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
        .args(["test", "--workspace", "--no-run", "--quiet"])
        .status()
        .context("cargo test --no-run")?;
    if !status.success() {
        bail!("cargo test --workspace --no-run failed");
    }
    let exe = std::env::current_exe()?;
    let dir = exe.parent().context("xtask is not in a cargo target folder")?;
    let hbid = dir.join(format!("hbid{}", std::env::consts::EXE_SUFFIX));
    if !hbid.exists() {
        bail!("expected hbid at {}", hbid.display());
    }
    Ok(hbid)
}

fn strings(args: &[&str]) -> Vec<String> {
    args.iter().map(|s| s.to_string()).collect()
}

/// One model of a benchmark: how it was identified, and its scores.
struct Scored {
    label: &'static str,
    identify: Vec<String>,
    compare: Vec<String>,
    found: Value,
    scores: Value,
    seconds: f64,
}

impl Scored {
    fn coefficient(&self, name: &str) -> f64 {
        self.found["coefficients"][name].as_f64().unwrap_or(0.0)
    }

    fn terms(&self) -> usize {
        self.found["terms"].as_array().map_or(0, Vec::len)
    }

    /// The RMSE of each range, times `scale`.
    fn rmse(&self, scale: f64) -> Vec<Option<f64>> {
        self.scores["ranges"]
            .as_array()
            .map(|r| r.iter().map(|r| r["rmse"].as_f64().map(|v| v * scale)).collect())
            .unwrap_or_default()
    }
}

/// Identifies with `identify` (the training record first) and scores with `compare` (the model
/// and test record first). Both are kept as shown in the report, with the records' bare names;
/// `located` gives the path a bare name stands for when hbid runs.
fn scored(
    exe: &Path,
    label: &'static str,
    identify: Vec<String>,
    model: &Path,
    compare: Vec<String>,
    located: &dyn Fn(&str) -> Option<PathBuf>,
) -> anyhow::Result<Scored> {
    let locate = |words: &[String]| -> Vec<String> {
        words
            .iter()
            .map(|w| located(w).map_or_else(|| w.clone(), |p| p.display().to_string()))
            .collect()
    };
    let mut args = locate(&identify);
    args.extend([
        "--bootstrap".into(),
        "0".into(),
        "--json".into(),
        "--save-model".into(),
    ]);
    args.push(model.display().to_string());
    let started = Instant::now();
    let found = hbid(exe, &args)?;
    let seconds = started.elapsed().as_secs_f64();
    let mut args = vec!["compare".to_owned(), model.display().to_string()];
    args.extend(locate(&compare));
    args.push("--json".into());
    let scores = hbid(exe, &args)?;
    Ok(Scored {
        label,
        identify,
        compare,
        found,
        scores,
        seconds,
    })
}

fn command(words: &[String], model: &str) -> String {
    let quoted: Vec<String> = words
        .iter()
        .map(|w| {
            if w.contains(' ') {
                format!("\"{w}\"")
            } else {
                w.clone()
            }
        })
        .collect();
    format!("hbid {} --save-model {model}", quoted.join(" "))
}

/// The peer (`xtask/peers/sysidentpy_benchmarks.py`: sysidentpy's polynomial NARX by FROLS) run
/// with `python` on the same files, its JSON.
fn peer(python: &str, shared: &Path, work: &Path) -> anyhow::Result<Value> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("peers/sysidentpy_benchmarks.py");
    let out = work.join("sysidentpy.json");
    let status = Command::new(python)
        .arg(&script)
        .arg("--silverbox")
        .arg(shared.join("silverbox/SNLS80mV.csv"))
        .arg("--emps-train")
        .arg(shared.join("emps/emps_train_txp.csv"))
        .arg("--emps-test")
        .arg(shared.join("emps/emps_test_txp.csv"))
        .arg("--out")
        .arg(&out)
        .status()
        .with_context(|| format!("running {python} {}", script.display()))?;
    if !status.success() {
        bail!(
            "{python} {} failed (is sysidentpy installed? `{python} -m pip install -r xtask/peers/requirements.txt`)",
            script.display()
        );
    }
    let text = std::fs::read_to_string(&out).with_context(|| out.display().to_string())?;
    serde_json::from_str(&text).with_context(|| format!("{}: its JSON", out.display()))
}

/// What the refined rows are.
const REFINED: &str = "Refined: the same `hbid identify` with `--refine`, on the training part alone: after the weak \
form, Levenberg–Marquardt on the free run's error over the training part, each run's state set by its first \
samples as the protocol sets it on the test sets (`--refine-init`); its time includes the refinement.";

/// The numbers of a JSON array (null where a value is not a number).
fn numbers(v: &Value) -> Vec<Option<f64>> {
    v.as_array()
        .map(|a| a.iter().map(Value::as_f64).collect())
        .unwrap_or_default()
}

pub fn run(doc: &Path, out: Option<&Path>, work: &Path, python: Option<&str>) -> anyhow::Result<()> {
    let shared = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/benchmarks");
    if !shared.is_dir() {
        bail!("the benchmarks are not at {}", shared.display());
    }
    std::fs::create_dir_all(work).with_context(|| work.display().to_string())?;
    let exe = hbid_exe()?;

    // Silverbox: the official file has no time column and a trailing comma on every line; the
    // protocol's sample ranges are its rows.
    let text = std::fs::read_to_string(shared.join("silverbox/SNLS80mV.csv"))?;
    let rows: Vec<&str> = text
        .lines()
        .skip(1)
        .map(|l| l.trim().trim_end_matches(','))
        .filter(|l| !l.is_empty())
        .collect();
    if rows.len() != 131_072 {
        bail!("SNLS80mV.csv has {} rows, not 131072", rows.len());
    }
    let whole = work.join("silverbox.csv");
    let train = work.join("silverbox-train.csv");
    std::fs::write(&whole, format!("u,y\n{}\n", rows.join("\n")))?;
    std::fs::write(&train, format!("u,y\n{}\n", rows[40_650..105_712].join("\n")))?;
    let sb_read = [
        "--signal",
        "line",
        "--angle-col",
        "y",
        "--drive-col",
        "u",
        "--dt",
        "0.0016384",
    ];
    let sb_identify = |terms: &str, extra: &[&str]| {
        let mut a = vec!["identify".to_owned(), "silverbox-train.csv".into()];
        a.extend(strings(&sb_read));
        a.extend(strings(&["--drive-period", "none", "--terms", terms]));
        a.extend(strings(extra));
        a
    };
    let mut sb_compare = vec!["silverbox.csv".to_owned()];
    sb_compare.extend(strings(&sb_read[2..]));
    sb_compare.extend(strings(&[
        "--init",
        "50",
        "--range",
        "105712..127400",
        "--range",
        "100..40575",
        "--range",
        "100..32100",
    ]));
    let in_work =
        |name: &str| matches!(name, "silverbox.csv" | "silverbox-train.csv").then(|| work.join(name));
    let silverbox = |label, terms: &str, extra: &[&str], name: &str| {
        let identify = sb_identify(terms, extra);
        scored(
            &exe,
            label,
            identify,
            &work.join(name),
            sb_compare.clone(),
            &in_work,
        )
    };
    eprintln!("silverbox");
    let sb_terms = "1, x', x, x^2, x^3, p";
    let sb = silverbox("physical", sb_terms, &[], "silverbox.json")?;
    // The refinement's state set by as many samples as the protocol's: 50.
    let sb_refined = silverbox(
        "physical, refined by its free run",
        sb_terms,
        &["--refine", "--refine-init", "50"],
        "silverbox-refined.json",
    )?;
    let sb_library = "1, x', x'^3, x'*|x'|, x, x^2, x^3, x^4, x^5, p, x*x', x^2*x'";
    let sb_select = silverbox("selected", sb_library, &["--select"], "silverbox-selected.json")?;

    // EMPS: the force has no period, so the weak form's windows are given in seconds.
    eprintln!("emps");
    let emps_train = shared.join("emps/emps_train_txp.csv");
    let emps_test = shared.join("emps/emps_test_txp.csv");
    let emps_identify = |terms: &str, extra: &[&str]| {
        let mut a = strings(&[
            "identify",
            "emps_train_txp.csv",
            "--signal",
            "line",
            "--drive-col",
            "p",
        ]);
        a.extend(strings(&["--window", "0.75", "--terms", terms]));
        a.extend(strings(extra));
        a
    };
    let emps_compare = strings(&["emps_test_txp.csv", "--drive-col", "p", "--init", "20"]);
    let emps_paths = |name: &str| match name {
        "emps_train_txp.csv" => Some(emps_train.clone()),
        "emps_test_txp.csv" => Some(emps_test.clone()),
        _ => None,
    };
    let emps = |label, terms: &str, extra: &[&str], name: &str| {
        let identify = emps_identify(terms, extra);
        scored(
            &exe,
            label,
            identify,
            &work.join(name),
            emps_compare.clone(),
            &emps_paths,
        )
    };
    let em_terms = "1, x', sign(x'), p";
    let em = emps("physical", em_terms, &[], "emps.json")?;
    let em_refined = emps(
        "physical, refined by its free run",
        em_terms,
        &["--refine", "--refine-init", "20"],
        "emps-refined.json",
    )?;
    let em_library = "1, x', sign(x'), x'*|x'|, x'^3, x, p";
    let em_select = emps("selected", em_library, &["--select"], "emps-selected.json")?;
    let peer = match python {
        Some(python) => {
            eprintln!("sysidentpy");
            Some(peer(python, &shared, work)?)
        }
        None => None,
    };
    let started = Instant::now();
    let (dfki_section, dfki) = crate::dfki::run(&exe, &shared, work, python)?;
    eprintln!("dfki: {:.1} s", started.elapsed().as_secs_f64());

    // Physical parameters: the equation x'' + Σ c_i g_i = 0 times the mass -1/c_p.
    let physical = |s: &Scored, names: &[(&str, &str)]| -> Vec<(String, f64)> {
        let mass = -1.0 / s.coefficient("p");
        let mut v = vec![("mass".to_owned(), mass)];
        v.extend(
            names
                .iter()
                .map(|(label, term)| (label.to_string(), mass * s.coefficient(term))),
        );
        v
    };
    let sb_names = [
        ("damping d", "x'"),
        ("stiffness k1", "x"),
        ("k2 (of y^2)", "x^2"),
        ("k3 (of y^3)", "x^3"),
        ("offset", "1"),
    ];
    let sb_params = physical(&sb, &sb_names);
    let sb_params_refined = physical(&sb_refined, &sb_names);
    let em_names = [
        ("viscous friction Fv", "x'"),
        ("dry friction Fc", "sign(x')"),
        ("offset", "1"),
    ];
    let em_params = physical(&em, &em_names);
    let em_params_refined = physical(&em_refined, &em_names);

    let mut r = String::new();
    writeln!(
        r,
        "# The public benchmarks\n\n\
         Made by `cargo xtask benchmarks` ({}) from `../shared/benchmarks`, each by its protocol (the folder's \
         README): identified by one `hbid identify` command on the training part, scored by `hbid compare` on the \
         test parts, a free run of the model under the test record's measured input alone, the first samples of \
         each test set setting its initial state and not scored (on the DFKI double pendulum, whose records have \
         the joints' velocities, its first sample's measured state, every sample scored). Beside the physical \
         model, the terms selected \
         (`--select`, held-out cross-validation on the training part only) from a wider library; no modelling \
         choice looked at a test set. Wall times are of `hbid identify` with reading, this build.\n",
        crate::build_profile()
    )?;
    writeln!(r, "## Silverbox (RMSE of the free run, mV)\n")?;
    writeln!(
        r,
        "The training samples `[40650, 105712)` of `SNLS80mV.csv` are cut into `silverbox-train.csv`; both files \
         get the header `u,y` and lose the trailing comma. fs = 10^7/2^14 Hz: `--dt 0.0016384`. The model is \
         `y'' + Σ c_i g_i(y, y') = 0` in volts and seconds, with the input `u` as `p`.\n"
    )?;
    writeln!(
        r,
        "| model | terms | multisine | arrow, full | arrow, no extrapolation | identification |"
    )?;
    writeln!(r, "| --- | ---: | ---: | ---: | ---: | ---: |")?;
    for s in [&sb, &sb_refined, &sb_select] {
        let v = s.rmse(1e3);
        writeln!(
            r,
            "| {} | {} | {} | {} | {} | {:.2} s |",
            s.label,
            s.terms(),
            shown(v.first().copied().flatten(), 3),
            shown(v.get(1).copied().flatten(), 3),
            shown(v.get(2).copied().flatten(), 3),
            s.seconds
        )?;
    }
    if let Some(peer) = &peer {
        let s = &peer["silverbox"];
        let v = numbers(&s["rmse_mv"]);
        let joined = |v: &Value, decimals: usize| -> String {
            numbers(v)
                .into_iter()
                .map(|x| shown(x, decimals))
                .collect::<Vec<_>>()
                .join(" / ")
        };
        writeln!(
            r,
            "| polynomial NARX by FROLS, sysidentpy {} run here (its published configuration) | {} | {} | {} | {} | {} s |",
            peer["version"].as_str().unwrap_or("?"),
            joined(&s["terms"], 0),
            shown(v.first().copied().flatten(), 3),
            shown(v.get(1).copied().flatten(), 3),
            shown(v.get(2).copied().flatten(), 3),
            joined(&s["fit_seconds"], 2),
        )?;
    }
    writeln!(
        r,
        "| goal of this project | | 0.33 | 0.45 | 0.34 | under 1 s |\n\
         | SUBNET (Beintema et al. 2021) | | 0.36 | 1.4 | 0.32 | |\n\
         | GRU, mean of 3 seeds (2025, not peer reviewed) | | 0.33 | 1.43 | 0.31 | |\n\
         | polynomial NARX by FROLS (sysidentpy's documentation) | | 7.7 | 4.1 | 2.2 | |\n\n\
         The output noise floor is about 0.29 mV.\n"
    )?;
    if let Some(peer) = &peer {
        let fits = numbers(&peer["silverbox"]["fit_seconds"]);
        let ratio = |x: Option<f64>| x.map_or_else(|| "—".to_owned(), |x| format!("{:.0}", x / sb.seconds));
        writeln!(
            r,
            "The peer ran in this command on this machine (`--peer PYTHON`, `xtask/peers/sysidentpy_benchmarks.py`): \
             sysidentpy's own Silverbox configuration (its tutorial), which fits one model per test set (terms and fit \
             times are listed per set; the two arrow sets share one model), a choice the protocol leaves to the \
             training part. Its fits took {} and {} times as long as ours (fit alone against identification with \
             reading). Its single arrow model scored on all three sets: [{}] mV.\n",
            ratio(fits.first().copied().flatten()),
            ratio(fits.get(1).copied().flatten()),
            numbers(&peer["silverbox"]["rmse_mv_by_model"]["arrow_full"])
                .into_iter()
                .map(|x| shown(x, 3))
                .collect::<Vec<_>>()
                .join("; "),
        )?;
    }
    writeln!(r, "```\n{}", command(&sb.identify, "silverbox.json"))?;
    writeln!(r, "hbid compare silverbox.json {}\n```\n", sb.compare.join(" "))?;
    writeln!(
        r,
        "{REFINED}\n\n```\n{}\n```\n",
        command(&sb_refined.identify, "silverbox-refined.json")
    )?;
    writeln!(
        r,
        "Selected ({}): `{}` from `{sb_library}`.\n",
        sb_select.terms(),
        term_list(&sb_select)
    )?;
    writeln!(
        r,
        "Physical parameters of `m y'' + d y' + k1 y + k2 y^2 + k3 y^3 + offset = u` (V, s):\n"
    )?;
    writeln!(r, "| parameter | weak form | refined |\n| --- | ---: | ---: |")?;
    for ((name, value), (_, refined)) in sb_params.iter().zip(&sb_params_refined) {
        writeln!(r, "| {name} | {value:.6e} | {refined:.6e} |")?;
    }
    writeln!(r, "\n## EMPS (RMSE of the free run, mm)\n")?;
    writeln!(
        r,
        "Estimated on `DATA_EMPS`, tested on `DATA_EMPS_PULSES` (`emps_train_txp.csv`, `emps_test_txp.csv`: x = qm \
         in m, p = gtau·vir in N, t in s). The force has no period: the weak form's windows are given in seconds \
         (`--window 0.75`). The plant is an integrator, so any bias of the force model grows in the free run.\n"
    )?;
    writeln!(
        r,
        "| model | terms | RMSE | identification |\n| --- | ---: | ---: | ---: |"
    )?;
    for s in [&em, &em_refined, &em_select] {
        writeln!(
            r,
            "| {} | {} | {} | {:.2} s |",
            s.label,
            s.terms(),
            shown(s.rmse(1e3).first().copied().flatten(), 2),
            s.seconds
        )?;
    }
    if let Some(peer) = &peer {
        let e = &peer["emps"];
        writeln!(
            r,
            "| polynomial NARX by FROLS, sysidentpy {} run here (degree 2, lags 2, AIC) | {} | {} | {} s |",
            peer["version"].as_str().unwrap_or("?"),
            e["terms"]
                .as_u64()
                .map_or_else(|| "—".to_owned(), |n| n.to_string()),
            shown(e["rmse_mm"].as_f64(), 2),
            shown(e["fit_seconds"].as_f64(), 2),
        )?;
    }
    writeln!(
        r,
        "| goal of this project | | 8.0 | under 1 s |\n\
         | the benchmark's reference model, open loop | 4 | about 8.4 | |\n"
    )?;
    if let Some(peer) = &peer {
        writeln!(
            r,
            "sysidentpy publishes no EMPS configuration: the peer takes its README's quick start (FROLS, polynomial \
             degree 2, lags 2, the size by AIC), fixed before any run. Its fit took {} times as long as ours.\n",
            peer["emps"]["fit_seconds"]
                .as_f64()
                .map_or_else(|| "—".to_owned(), |x| format!("{:.0}", x / em.seconds))
        )?;
    }
    writeln!(r, "```\n{}", command(&em.identify, "emps.json"))?;
    writeln!(r, "hbid compare emps.json {}\n```\n", em.compare.join(" "))?;
    writeln!(
        r,
        "{REFINED}\n\n```\n{}\n```\n",
        command(&em_refined.identify, "emps-refined.json")
    )?;
    writeln!(
        r,
        "Selected ({}): `{}` from `{em_library}`.\n",
        em_select.terms(),
        term_list(&em_select)
    )?;
    writeln!(
        r,
        "Physical parameters of `M x'' + Fv x' + Fc sign(x') + offset = p` (kg, N s/m, N, N) beside the benchmark's \
         reference (inverse-dynamics least squares, its document):\n"
    )?;
    writeln!(
        r,
        "| parameter | weak form | refined | reference |\n| --- | ---: | ---: | ---: |"
    )?;
    for (((name, value), (_, refined)), reference) in em_params
        .iter()
        .zip(&em_params_refined)
        .zip([95.1089, 203.5034, 20.3935, -3.1648])
    {
        writeln!(r, "| {name} | {value:.4} | {refined:.4} | {reference} |")?;
    }
    r.push_str(&dfki_section);
    std::fs::write(doc, &r).with_context(|| doc.display().to_string())?;
    eprintln!("wrote {}", doc.display());

    if let Some(dir) = out {
        std::fs::create_dir_all(dir)?;
        let summary = json!({
            "silverbox": {
                "coefficients": sb.found["coefficients"],
                "rmse_mv": sb.rmse(1e3),
                "selected": {"coefficients": sb_select.found["coefficients"], "rmse_mv": sb_select.rmse(1e3)},
                "identify_seconds": sb.seconds,
                "refined": {
                    "coefficients": sb_refined.found["coefficients"],
                    "rmse_mv": sb_refined.rmse(1e3),
                    "identify_seconds": sb_refined.seconds,
                    "refinement": sb_refined.found["refinement"],
                },
            },
            "emps": {
                "coefficients": em.found["coefficients"],
                "rmse_mm": em.rmse(1e3).first().copied().flatten(),
                "selected": {"coefficients": em_select.found["coefficients"], "rmse_mm": em_select.rmse(1e3).first().copied().flatten()},
                "identify_seconds": em.seconds,
                "refined": {
                    "coefficients": em_refined.found["coefficients"],
                    "rmse_mm": em_refined.rmse(1e3).first().copied().flatten(),
                    "identify_seconds": em_refined.seconds,
                    "refinement": em_refined.found["refinement"],
                },
            },
            "peer": peer,
            "dfki": dfki,
        });
        let path = dir.join("benchmarks.json");
        std::fs::write(&path, serde_json::to_string_pretty(&summary)? + "\n")?;
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}

/// The terms of a model, joined.
fn term_list(s: &Scored) -> String {
    s.found["terms"]
        .as_array()
        .map(|t| t.iter().filter_map(Value::as_str).collect::<Vec<_>>().join(", "))
        .unwrap_or_default()
}
