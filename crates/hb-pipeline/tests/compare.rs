//! A saved model against a record: ranges of samples read, printed and placed on the record,
//! options checked, and the default samples of the initial state.

use std::f64::consts::TAU;

use hb_basis::{BasisKind, Polynomial};
use hb_model::{IdentifiedModel, IdentifiedSystem, ModelForm};
use hb_pipeline::compare::RangeScore;
use hb_pipeline::{CompareOptions, CompareRequest, RunError, SampleRange, Source, compare};

/// `x'' = −0.1 x'` on the line, with the drive angular frequency `omega`: no term has the drive,
/// so the frequency only sets what one drive period is in samples.
fn at_rest(omega: f64) -> IdentifiedModel {
    let basis = BasisKind::from(Polynomial::new(1).unwrap());
    IdentifiedModel::new(
        basis,
        ModelForm::from_terms("x'".parse().unwrap()),
        omega,
        &[-0.1],
    )
    .unwrap()
}

/// The scores of [`at_rest`]`(omega)` on a record of `len` samples at rest, `dt` apart, over
/// `ranges` (none: the whole record), run from the state given (at rest: nothing is fitted).
fn scores(omega: f64, dt: f64, len: usize, ranges: &[SampleRange]) -> Result<Vec<RangeScore>, RunError> {
    scores_from(omega, dt, len, ranges, true)
}

/// [`scores`], from the state given or (`given` false) from the state fitted to each range's
/// first samples.
fn scores_from(
    omega: f64,
    dt: f64,
    len: usize,
    ranges: &[SampleRange],
    given: bool,
) -> Result<Vec<RangeScore>, RunError> {
    let x = vec![0.0; len];
    let request = CompareRequest::new(CompareOptions {
        dt: Some(dt),
        x0: given.then(|| 0.0.into()),
        v0: given.then(|| 0.0.into()),
        range: ranges.to_vec(),
        ..CompareOptions::default()
    })
    .unwrap();
    let source = Source::Arrays {
        coords: vec![&x],
        t: None,
        drives: Vec::new(),
    };
    Ok(compare(&IdentifiedSystem::one(at_rest(omega)), source, &request, &mut ())?.ranges)
}

#[test]
fn ranges_read_and_print() {
    let r: SampleRange = "100..40575".parse().unwrap();
    assert_eq!(
        r,
        SampleRange {
            start: 100,
            end: Some(40575)
        }
    );
    assert_eq!(r.to_string(), "100..40575");
    assert_eq!("5..".parse::<SampleRange>().unwrap().end, None);
    assert!("7..7".parse::<SampleRange>().is_err());
    assert!("a..b".parse::<SampleRange>().is_err());
    assert!("12".parse::<SampleRange>().is_err());
    // The range on a record of 40000 samples ends past it; on one of 50000 it is [100, 40575).
    match scores(1.0, 0.1, 40000, &[r]) {
        Err(RunError::Options(e)) => assert_eq!(e.option(), "range", "{e}"),
        other => panic!("{other:?}"),
    }
    assert_eq!(scores(1.0, 0.1, 50000, &[r]).unwrap()[0].range, [100, 40575]);
}

#[test]
fn options_are_checked() {
    let bad = |o: CompareOptions| CompareRequest::new(o).unwrap_err().option().to_owned();
    let d = CompareOptions::default;
    assert_eq!(bad(CompareOptions { init: Some(1), ..d() }), "init");
    assert_eq!(
        bad(CompareOptions {
            x0: Some(1.0.into()),
            ..d()
        }),
        "x0"
    );
    assert_eq!(
        bad(CompareOptions {
            v0: Some(1.0.into()),
            ..d()
        }),
        "v0"
    );
    assert_eq!(bad(CompareOptions { rtol: 0.0, ..d() }), "rtol");
    assert_eq!(
        bad(CompareOptions {
            dt: Some(-1.0),
            ..d()
        }),
        "dt"
    );
    let json = serde_json::json!({"range": ["100..200", "300.."], "init": 50, "dt": 0.01});
    let request = CompareRequest::from_json(json).unwrap();
    assert_eq!(request.options().range.len(), 2);
    assert!(CompareRequest::from_json(serde_json::json!({"ranges": ["1..2"]})).is_err());
}

/// The samples of the initial state when none are given (a range's `init`): one drive period in
/// samples, at most a tenth of the range and at least 8. The period is the drive's `2π/ω` over
/// the step: the record's step is chosen for each period in samples (an infinite one from the
/// smallest positive `ω`).
#[test]
fn the_default_init_scales_with_the_drive_and_the_range() {
    let default_init = |period_samples: f64, range: usize| {
        let (omega, dt) = if period_samples.is_finite() {
            (1.0, TAU / period_samples)
        } else {
            (f64::MIN_POSITIVE, 1.0)
        };
        assert_eq!(TAU / omega / dt == f64::INFINITY, period_samples.is_infinite());
        let scores = scores_from(omega, dt, range, &[], false).unwrap();
        assert_eq!(scores[0].range, [0, range]);
        assert_eq!(scores[0].scored, range - scores[0].init);
        scores[0].init
    };
    assert_eq!(default_init(25.0, 30_000), 25);
    assert_eq!(default_init(490.2, 150_000), 490);
    assert_eq!(default_init(6283.0, 20_000), 2000);
    assert_eq!(default_init(3.0, 1000), 8);
    assert_eq!(default_init(f64::INFINITY, 1000), 8);
    // A piece that starts from the state given fits none: every sample is scored.
    let given = &scores(1.0, TAU / 25.0, 1000, &[]).unwrap()[0];
    assert_eq!((given.init, given.scored), (0, 1000));
}

/// The double pendulum of `hbid simulate --system double-pendulum` (its truth's equations,
/// nondimensional time): the system a Python user runs with `Model.simulate(t=..., x0=[..],
/// v0=[..])`.
fn double_pendulum() -> IdentifiedSystem {
    circle_system(
        (["theta1", "theta2"], &[]),
        [
            (
                "theta2''*cos(theta1-theta2), sin(theta1-theta2)*theta2'^2, sin(theta1), sin(t)*cos(theta1), theta1'",
                &[0.5, 0.5, 0.8, -0.6, 0.05],
            ),
            (
                "theta1''*cos(theta1-theta2), sin(theta1-theta2)*theta1'^2, sin(theta2), sin(t)*cos(theta2), theta2'",
                &[1.0, -1.0, 0.8, -0.6, 0.05],
            ),
        ],
    )
}

/// A system of two angles named `names.0` with the drives `names.1`, each equation its terms
/// (in the grammar) and their coefficients, on the basis `harmonic:1` and the drive `W = 1`.
fn circle_system(names: ([&str; 2], &[&str]), equations: [(&str, &[f64]); 2]) -> IdentifiedSystem {
    use hb_basis::{Domain, Harmonic};
    use hb_model::{Names, TermList};
    let names = Names::new(names.0, names.1.iter().copied()).unwrap();
    let basis = BasisKind::from(Harmonic::new(1).unwrap());
    let models = equations
        .iter()
        .enumerate()
        .map(|(own, (terms, values))| {
            let list = TermList::parse_in(terms, &names, own).unwrap();
            IdentifiedModel::new(basis, ModelForm::from_terms(list), 1.0, values).unwrap()
        })
        .collect();
    IdentifiedSystem::new(names.clone(), vec![Domain::Circle; 2], models).unwrap()
}

/// A system run over given times from a given state is the free run `compare` (and `hbid
/// simulate --model --input --init 0`) makes from that state on a record of those times: the
/// same integrator, the same columns, and the record it was simulated as.
#[test]
fn a_system_runs_on_given_times_as_compare_runs_it() {
    use hb_pipeline::{Rig, model_run, run_system_on_times};
    let system = double_pendulum();
    let rig = Rig::from_json(serde_json::json!({"system": "double-pendulum", "samples": 640})).unwrap();
    let table = hb_pipeline::simulate(&rig, &mut ()).unwrap().table();
    let column = |c: usize| -> Vec<f64> { table.iter().map(|row| row[c]).collect() };
    let (t, q1, q2) = (column(0), column(1), column(2));
    let (x0, v0) = ([q1[0], q2[0]], [table[0][3], table[0][4]]);
    let run = run_system_on_times(&system, &t, &[], &x0, &v0, 1e-10).unwrap();
    assert_eq!(run.columns, ["t", "theta1", "theta2", "theta1'", "theta2'"]);
    assert_eq!(run.rows.len(), t.len());
    assert!(run.stopped.is_none());

    let values = |v: [f64; 2]| format!("{},{}", v[0], v[1]).parse().unwrap();
    let request = CompareRequest::new(CompareOptions {
        x0: Some(values(x0)),
        v0: Some(values(v0)),
        ..CompareOptions::default()
    })
    .unwrap();
    let source = Source::Arrays {
        coords: vec![&q1, &q2],
        t: Some(&t),
        drives: Vec::new(),
    };
    let compared = model_run(&system, source, &request, &mut ()).unwrap();
    assert_eq!(compared.columns, run.columns);
    let wrap = |a: f64| (a + std::f64::consts::PI).rem_euclid(TAU) - std::f64::consts::PI;
    for (mine, theirs) in run.rows.iter().zip(&compared.rows) {
        assert!((mine[0] - theirs[0]).abs() < 1e-9);
        // compare puts the angles on the measured turn; velocities as run.
        for c in 1..3 {
            assert!(wrap(mine[c] - theirs[c]).abs() < 1e-9, "{mine:?} {theirs:?}");
        }
        for c in 3..5 {
            assert!((mine[c] - theirs[c]).abs() < 1e-9, "{mine:?} {theirs:?}");
        }
    }
    // The record is this system's: one drive period of its run is the record's.
    for (row, sample) in run.rows.iter().zip(&table).take(64) {
        assert!(wrap(row[1] - sample[1]).abs() < 1e-6 && wrap(row[2] - sample[2]).abs() < 1e-6);
    }
}

/// A state or drives that are not one per coordinate or drive of the system, and times off an
/// even grid, are the options' errors, by name.
#[test]
fn a_systems_run_refuses_a_state_or_drives_that_do_not_fit() {
    use hb_pipeline::{ErrorKind, run_system_on_times};
    let system = double_pendulum();
    let t: Vec<f64> = (0..100).map(|i| f64::from(i) * 0.1).collect();
    let refused = |result: Result<hb_pipeline::ModelRun, RunError>, option: &str| {
        let e = result.unwrap_err();
        assert_eq!(e.kind(), ErrorKind::Options, "{e}");
        assert!(e.to_string().contains(option), "{e}");
    };
    refused(
        run_system_on_times(&system, &t, &[], &[0.1], &[0.0, 0.0], 1e-10),
        "x0",
    );
    refused(
        run_system_on_times(&system, &t, &[], &[0.1, 0.2], &[0.0], 1e-10),
        "v0",
    );
    refused(
        run_system_on_times(&system, &t, &[], &[0.1, f64::NAN], &[0.0, 0.0], 1e-10),
        "x0",
    );
    refused(
        run_system_on_times(&system, &t, &[&t], &[0.1, 0.2], &[0.0, 0.0], 1e-10),
        "drive",
    );
    let uneven: Vec<f64> = t.iter().map(|v| v * v).collect();
    refused(
        run_system_on_times(&system, &uneven, &[], &[0.1, 0.2], &[0.0, 0.0], 1e-10),
        "even grid",
    );
    // A measured drive with a sample that is not a number: named, not run into a reason that
    // misleads (a singular mass matrix, a step too small).
    let driven = circle_system(
        (["q1", "q2"], &["tau1", "tau2"]),
        [
            ("sin(q1), q1', tau1", &[9.0, 0.1, -1.0]),
            ("sin(q2), q2', tau2", &[9.0, 0.1, -1.0]),
        ],
    );
    let mut tau1 = vec![0.1; t.len()];
    let tau2 = vec![0.0; t.len()];
    assert!(run_system_on_times(&driven, &t, &[&tau1, &tau2], &[0.1, 0.2], &[0.0, 0.0], 1e-10).is_ok());
    tau1[10] = f64::NAN;
    let e = run_system_on_times(&driven, &t, &[&tau1, &tau2], &[0.1, 0.2], &[0.0, 0.0], 1e-10).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Options, "{e}");
    assert!(
        e.to_string().contains("sample 10 of the drive tau1 is NaN"),
        "{e}"
    );
}

/// Measured velocities are columns of a file: samples given as arrays with `velocity_col` are
/// refused by name, not read without them.
#[test]
fn arrays_refuse_velocity_columns() {
    let x: Vec<f64> = (0..200).map(|i| (f64::from(i) * 0.1).sin()).collect();
    let options = hb_pipeline::RecordOptions {
        dt: Some(0.1),
        velocity_col: Some("v".parse().unwrap()),
        ..Default::default()
    };
    let source = Source::Arrays {
        coords: vec![&x],
        t: None,
        drives: Vec::new(),
    };
    let e = hb_pipeline::condition_source(source, &options, &mut ()).unwrap_err();
    assert_eq!(e.kind(), hb_pipeline::ErrorKind::Options);
    assert!(e.to_string().contains("velocity_col"), "{e}");
}

/// A record without one of the columns named by `coords` is fixed with `coords`, which names
/// every coordinate's column (a saved system's own names, when it is read without them), not
/// with `angle_col`, which names only a single coordinate's; a missing single angle still is.
#[test]
fn a_missing_coordinate_names_the_option_that_chooses_it() {
    let dir = std::env::temp_dir().join(format!("hb-pipeline-missing-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("one.csv");
    std::fs::write(&path, "t,theta1\n0,0.1\n0.1,0.2\n0.2,0.25\n0.3,0.2\n").unwrap();
    let read = |options: hb_pipeline::RecordOptions| {
        let e = hb_pipeline::condition_source(Source::Path(&path), &options, &mut ()).unwrap_err();
        assert_eq!(e.kind(), hb_pipeline::ErrorKind::Input, "{e}");
        hb_pipeline::Spelling::CommandLine.render(&e.to_string())
    };
    let system = read(hb_pipeline::RecordOptions {
        coords: Some("theta1,theta2".parse().unwrap()),
        ..Default::default()
    });
    assert!(system.contains("'theta2'"), "{system}");
    assert!(system.contains("with --coords"), "{system}");
    assert!(!system.contains("angle-col"), "{system}");
    let one = read(hb_pipeline::RecordOptions {
        angle_col: Some("theta2".to_owned()),
        ..Default::default()
    });
    assert!(
        one.contains("'theta2'") && one.contains("with --angle-col"),
        "{one}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The time stamps of a logger that takes its first steps at 3.0 to 3.5 ms before it settles to
/// 2 ms (as the DFKI double pendulum's): `len` rows, the first 5 of them unsettled.
fn unsettled_stamps(len: usize) -> Vec<f64> {
    let mut t = vec![0.0, 0.0035, 0.0068, 0.0099, 0.0129];
    let settled = 0.0159;
    t.extend((0..len - t.len()).map(|i| settled + 0.002 * i as f64));
    t
}

/// A torque-driven double pendulum in relative angles (q2 of link 2 against link 1), the shape
/// of the DFKI rig's model: its equations read the torques tau1, tau2.
fn torque_pendulum() -> IdentifiedSystem {
    circle_system(
        (["q1", "q2"], &["tau1", "tau2"]),
        [
            (
                "q2''*cos(q2), sin(q1), sin(q1+q2), q1', tau1",
                &[0.3, 20.0, 6.0, 0.2, -8.0],
            ),
            ("q1''*cos(q2), sin(q1+q2), q2', tau2", &[0.9, 40.0, 0.1, -30.0]),
        ],
    )
}

/// The torques of the record: smooth, so that a spline through their samples is them.
fn torques(t: f64) -> [f64; 2] {
    [0.4 * (10.0 * t).sin(), -0.3 * (5.0 * t).cos()]
}

/// A drive sampled every 0.1 ms over `[0, end]`: its spline is the function to 1e-12.
fn fine(f: impl Fn(f64) -> f64, end: f64) -> hb_model::MeasuredDrive {
    let n = (end / 1e-4).ceil() as usize + 2;
    hb_model::MeasuredDrive::new((0..n).map(|i| f(i as f64 * 1e-4)).collect::<Vec<_>>(), 0.0, 1e-4).unwrap()
}

/// A record whose first rows a logger stamped 3.0 to 3.5 ms apart before it settled to 2 ms is
/// compared from its first row, as the protocol of such a record runs it: the true system,
/// started from row 0's measured state, follows its own record at every row, the unsettled ones
/// at their own stamps, and the ranges count those rows as the record's first. With
/// `skip_unsettled` the comparison starts at the first row on the grid instead, as before.
#[test]
fn a_record_with_an_unsettled_start_is_compared_from_its_first_row() {
    use hb_pipeline::{Notice, Notices};
    use pendulum_sim::multi::{self, MultiState};
    let system = torque_pendulum();
    let t = unsettled_stamps(2000);
    let end = t[t.len() - 1];
    let driven = system
        .clone()
        .with_measured_drives(vec![fine(|s| torques(s)[0], end), fine(|s| torques(s)[1], end)])
        .unwrap();
    let (x0, v0) = ([0.1, -0.2], [0.0, 0.5]);
    let tolerances = pendulum_sim::Tolerances::new(1e-12, 1e-13).unwrap();
    let run = multi::free_run(&driven, &t, &MultiState::new(&x0, &v0).unwrap(), tolerances).unwrap();
    assert!(run.stopped.is_none());
    // It moves: half a radian of swing, so that a row placed a step off would show.
    let swing = run.q[1].iter().fold(0.0f64, |m, q| m.max(q.abs()));
    assert!(swing > 0.3, "{swing}");
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("unsettled.csv");
    let mut text = "time,pos1,pos2,vel1,vel2,tau1,tau2\n".to_owned();
    for (i, &s) in t.iter().enumerate() {
        let [u1, u2] = torques(s);
        text.push_str(&format!(
            "{s},{},{},{},{},{u1},{u2}\n",
            run.q[0][i], run.q[1][i], run.v[0][i], run.v[1][i]
        ));
    }
    std::fs::write(&path, text).unwrap();

    let compared = |skip_unsettled: bool| {
        let request = CompareRequest::new(CompareOptions {
            time_col: Some("time".into()),
            coords: Some("q1=pos1,q2=pos2".parse().unwrap()),
            drive_col: Some("tau1=tau1,tau2=tau2".parse().unwrap()),
            velocity_col: Some("vel1,vel2".parse().unwrap()),
            range: vec!["0..".parse().unwrap(), "0..500".parse().unwrap()],
            skip_unsettled,
            ..CompareOptions::default()
        })
        .unwrap();
        let mut notices = Notices::default();
        let report = compare(&system, Source::Path(&path), &request, &mut notices).unwrap();
        (report, notices.0)
    };

    let (report, notices) = compared(false);
    assert_eq!(report.unsettled_rows, 5);
    assert_eq!(report.samples, 2000);
    let uneven: Vec<_> = notices
        .iter()
        .filter_map(|n| match n {
            Notice::UnevenStart(run) => Some(run.samples.clone()),
            _ => None,
        })
        .collect();
    assert_eq!(uneven.len(), 1, "{notices:?}");
    assert_eq!(uneven[0], 0..5, "{notices:?}");
    assert_eq!(report.ranges.len(), 4);
    for (i, r) in report.ranges.iter().enumerate() {
        let end = if i < 2 { 2000 } else { 500 };
        assert_eq!((r.range, r.init, r.scored), ([0, end], 0, end), "{r:?}");
        assert!(r.rmse.unwrap() < 1e-6, "{r:?}");
        assert!(r.max_error.unwrap() < 1e-5, "{r:?}");
    }
    // From row 0's measured state, at the rows' own stamps.
    let first = &report.runs[0][0];
    assert_eq!(first.start, 0);
    assert_eq!(&first.t[..6], &t[..6]);
    assert!((first.t[1999] - t[1999]).abs() < 1e-9);
    assert_eq!(report.ranges[0].initial_states, [[x0[0], v0[0], 0.0]]);
    assert_eq!(report.ranges[1].initial_states, [[x0[1], v0[1], 0.0]]);

    // Left out: the grid's first sample is row 5, the ranges count from there.
    let (skipped, notices) = compared(true);
    assert_eq!((skipped.unsettled_rows, skipped.samples), (0, 1995));
    assert!(!notices.iter().any(|n| matches!(n, Notice::UnevenStart(_))));
    assert_eq!(skipped.ranges[0].range, [0, 1995]);
    assert!((skipped.runs[0][0].t[0] - t[5]).abs() < 1e-9);
    assert_eq!(skipped.ranges[0].initial_states[0][0], run.q[0][5]);
    assert!(skipped.ranges[0].rmse.unwrap() < 1e-6);
}

/// A model of one coordinate on such a record, its state fitted to the first samples (no
/// velocities: samples given as arrays with their stamps): the fit and the run go through the
/// unsettled rows at their stamps, and the true model is its own record's.
#[test]
fn one_coordinate_is_fitted_and_run_through_an_unsettled_start() {
    use pendulum_sim::multi::{self, MultiState, OneCoordinate};
    let basis = BasisKind::from(Polynomial::new(3).unwrap());
    let form = ModelForm::from_terms("x', x, x^3, p".parse().unwrap());
    let model = IdentifiedModel::new(basis, form, 1.0, &[0.2, 30.0, 5.0, -40.0]).unwrap();
    let t = unsettled_stamps(3000);
    let end = t[t.len() - 1];
    let p = |s: f64| (7.0 * s).sin() + 0.3 * (13.0 * s).cos();
    let driven = model.clone().with_measured_drive(fine(p, end)).unwrap();
    let tolerances = pendulum_sim::Tolerances::new(1e-12, 1e-13).unwrap();
    let state = MultiState::new(&[0.05], &[-0.4]).unwrap();
    let run = multi::free_run(&OneCoordinate(&driven), &t, &state, tolerances).unwrap();
    assert!(run.stopped.is_none());
    let drive: Vec<f64> = t.iter().map(|&s| p(s)).collect();
    let request = CompareRequest::new(CompareOptions {
        init: Some(40),
        drive_col: Some("p".parse().unwrap()),
        ..CompareOptions::default()
    })
    .unwrap();
    let source = Source::Arrays {
        coords: vec![&run.q[0]],
        t: Some(&t),
        drives: vec![&drive],
    };
    let report = compare(&IdentifiedSystem::one(model), source, &request, &mut ()).unwrap();
    assert_eq!(report.unsettled_rows, 5);
    let r = &report.ranges[0];
    assert_eq!((r.range, r.init, r.scored), ([0, 3000], 40, 2960), "{r:?}");
    let [x, v, rms] = r.initial_states[0];
    assert!(
        (x - 0.05).abs() < 1e-7 && (v + 0.4).abs() < 1e-5 && rms < 1e-8,
        "{x} {v} {rms}"
    );
    assert!(r.rmse.unwrap() < 1e-6, "{r:?}");
    assert_eq!(&report.runs[0][0].t[..6], &t[..6]);
}

/// What a comparison tells of its progress: `(done, total)` in order.
#[derive(Default)]
struct Told(Vec<(usize, usize)>);

impl hb_pipeline::Observer for Told {
    fn progress(&mut self, done: usize, total: usize) {
        self.0.push((done, total));
    }
}

impl Told {
    /// Told as the runs go (at least ten times before the end), never going back, ending with
    /// all `samples` done.
    fn as_it_goes(&self, samples: usize) {
        let within = self.0.iter().filter(|(done, total)| done < total).count();
        assert!(within >= 10, "{:?}", self.0);
        assert!(self.0.windows(2).all(|w| w[0].0 <= w[1].0), "{:?}", self.0);
        assert_eq!(self.0.last(), Some(&(samples, samples)));
    }
}

/// A comparison of one coordinate tells its progress within a range too, on a grid and off one.
#[test]
fn a_models_comparison_tells_its_progress_within_a_range() {
    let x = vec![0.0; 3000];
    let t: Vec<f64> = (0..3000)
        .map(|i| 0.05 * i as f64 + if i % 7 == 3 { 1e-4 } else { 0.0 })
        .collect();
    for times in [None, Some(&t[..])] {
        let request = CompareRequest::new(CompareOptions {
            dt: times.is_none().then_some(0.05),
            x0: Some(0.0.into()),
            v0: Some(0.0.into()),
            ..CompareOptions::default()
        })
        .unwrap();
        let source = Source::Arrays {
            coords: vec![&x],
            t: times,
            drives: Vec::new(),
        };
        let mut told = Told::default();
        compare(&IdentifiedSystem::one(at_rest(1.0)), source, &request, &mut told).unwrap();
        told.as_it_goes(3000);
    }
}

/// A system's comparison tells how far its free run is as it goes, not only when a range is
/// done: a stiff identified system can run for minutes over one range.
#[test]
fn a_systems_comparison_tells_its_progress_within_a_range() {
    use hb_pipeline::Rig;
    let system = double_pendulum();
    let rig = Rig::from_json(serde_json::json!({"system": "double-pendulum", "samples": 2000})).unwrap();
    let table = hb_pipeline::simulate(&rig, &mut ()).unwrap().table();
    let column = |c: usize| -> Vec<f64> { table.iter().map(|row| row[c]).collect() };
    let (t, q1, q2) = (column(0), column(1), column(2));
    let source = Source::Arrays {
        coords: vec![&q1, &q2],
        t: Some(&t),
        drives: Vec::new(),
    };
    let request = CompareRequest::new(CompareOptions::default()).unwrap();
    let mut told = Told::default();
    compare(&system, source, &request, &mut told).unwrap();
    told.as_it_goes(2000);
}

/// A state given sets the first piece of a range, measured velocities every later one: both
/// score every sample; a piece after a gap without measured velocities fits its state from its
/// first `init` samples, which are not scored. A range that starts in a gap takes the state
/// given at the first sample after it.
#[test]
fn pieces_from_a_state_given_or_measured_score_every_sample() {
    use circle_signal::Domain;
    use hb_record::prepare::GridData;
    let n = 300;
    let mut x = vec![0.0; n];
    x[100..110].fill(f64::NAN);
    let grid = |velocities: bool| GridData {
        t0: 0.0,
        dt: TAU / 25.0,
        x: x.clone(),
        pieces: vec![0..100, 110..n],
        domain: Domain::Line,
        others: Vec::new(),
        drives: Vec::new(),
        velocities: if velocities {
            vec![vec![0.0; n]]
        } else {
            Vec::new()
        },
        bridged: Vec::new(),
        notes: Vec::new(),
        lead_in: None,
    };
    let scored = |velocities: bool, range: &str| {
        let request = CompareRequest::new(CompareOptions {
            x0: Some(0.0.into()),
            v0: Some(0.0.into()),
            range: vec![range.parse().unwrap()],
            ..CompareOptions::default()
        })
        .unwrap();
        let report = compare(
            &IdentifiedSystem::one(at_rest(1.0)),
            Source::Grid(grid(velocities)),
            &request,
            &mut (),
        )
        .unwrap();
        (report.ranges[0].scored, report.ranges[0].initial_states.len())
    };
    // The default init is one drive period, 25 samples.
    assert_eq!(scored(true, "0.."), (290, 2));
    assert_eq!(scored(false, "0.."), (290 - 25, 2));
    // From inside the gap: the state given is the first sample's after it.
    assert_eq!(scored(false, "105.."), (190, 1));
}
