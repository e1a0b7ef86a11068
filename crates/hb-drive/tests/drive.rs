//! The forcing period estimated from a record: the paper's pendulum and a forced Duffing
//! oscillator, simulated on whole and non-whole sampling grids, exact, quantised and noisy.
use std::f64::consts::TAU;

use circle_signal::wrap;
use hb_basis::{Harmonic, Polynomial};
use hb_drive::DriveSearchError;
use hb_drive::{
    DriveEstimate, DriveSearch, PeriodRange, RangeSource, dominant_period, estimate_drive_period,
};
use hb_model::{Forcing, Harmonics, ModelForm};
use hb_solve::{AssemblyError, SolveError};
use pendulum_sim::observe::Encoder;
use pendulum_sim::{Domain, Dop853, FirstOrder, Pendulum, SecondOrderSystem, Tolerances};

/// `samples` samples of a second-order system every `dt` of its own time from `t_first` (after a
/// transient from `(0.1, 0)` at `t = 0`), with time relabelled by `scale`: `(t0, step, x)`.
fn sample<S: SecondOrderSystem>(
    system: S,
    t_first: f64,
    dt: f64,
    samples: usize,
    scale: f64,
) -> (f64, f64, Vec<f64>) {
    let mut ode = Dop853::new(FirstOrder(system), 0.0, [0.1, 0.0], Tolerances::default()).unwrap();
    let mut x = Vec::with_capacity(samples);
    ode.sample_grid(t_first, dt, samples, |_, _, y| x.push(y[0]))
        .unwrap();
    (t_first * scale, dt * scale, x)
}

/// The paper's pendulum after 200 forcing periods, `ratio` samples per forcing period, time
/// relabelled so that the forcing period is `period`: `(t0, step, continuous angle)`.
fn pendulum(period: f64, ratio: f64, periods: f64) -> (f64, f64, Vec<f64>) {
    let samples = (periods * ratio) as usize;
    sample(Pendulum::paper(), 200.0 * TAU, TAU / ratio, samples, period / TAU)
}

/// The angle through an encoder of `counts` per revolution.
fn encoder(x: &[f64], counts: f64) -> Vec<f64> {
    let q = TAU / counts;
    x.iter().map(|&v| wrap((v / q).round() * q)).collect()
}

fn search(period: f64, below: f64, above: f64) -> DriveSearch {
    DriveSearch::builder()
        .range(PeriodRange::periods(below * period, above * period).unwrap())
        .build()
        .unwrap()
}

fn on_circle(x: &[f64], step: f64, t0: f64, search: &DriveSearch) -> Result<DriveEstimate, DriveSearchError> {
    let basis = Harmonic::new(1).unwrap();
    estimate_drive_period(
        x,
        step,
        t0,
        Domain::Circle,
        search,
        &basis,
        &ModelForm::parametric(),
        |_, _| {},
    )
}

fn relative_error(found: &DriveEstimate, period: f64) -> f64 {
    found.period / period - 1.0
}

/// The paper's record (30000 samples at 25 per period, non-dimensional time) and a 1.02 Hz drive
/// sampled at 500 Hz (490.196 samples per period, seconds): exact, and through a 4096-count
/// encoder, with a range of 0.5 to 2 times the truth.
#[test]
fn exact_and_quantised_records_give_the_period() {
    let rig = 1.0 / 1.02;
    for (period, ratio, periods) in [(TAU, 25.0, 1200.0), (rig, 500.0 / 1.02, 60.0)] {
        let (t0, step, theta) = pendulum(period, ratio, periods);
        let s = search(period, 0.5, 2.0);
        let exact: Vec<f64> = theta.iter().map(|&v| wrap(v)).collect();
        let found = on_circle(&exact, step, t0, &s).unwrap();
        let e = relative_error(&found, period);
        assert!(e.abs() < 1e-8, "exact, {ratio} per period: {e:e}");
        assert!(found.range_source == RangeSource::Given);
        assert!(found.residual < 1e-10, "{}", found.residual);
        assert!(found.scan.len() > 50 && found.evaluations > found.scan.len());
        // The scan spans the range, in increasing period.
        assert_eq!(found.scan.first().unwrap().period, 0.5 * period);
        assert_eq!(found.scan.last().unwrap().period, 2.0 * period);
        assert!(found.scan.windows(2).all(|w| w[0].period < w[1].period));

        // The quantisation error is a function of the angle, not independent noise: the reported
        // uncertainty need not cover it (on the 60-period record at 490.196 per period the error
        // is about 6 of them), but the estimate is far within the 1e-5 asked for.
        let found = on_circle(&encoder(&theta, 4096.0), step, t0, &s).unwrap();
        let e = relative_error(&found, period);
        assert!(e.abs() < 1e-6, "quantised, {ratio} per period: {e:e}");
        assert!(found.contrast < 1e-3, "{}", found.contrast);
    }
}

/// Noise of σ = 0.01 rad on the angle, 20 seeded records: every estimate within 4 reported
/// standard uncertainties of the truth, and the spread of the estimates within a factor 1.6 of
/// the reported uncertainty (the sample standard deviation of 20 values is itself uncertain by
/// about 16 %).
#[test]
fn noisy_records_are_within_the_reported_uncertainty() {
    let (t0, step, theta) = pendulum(TAU, 25.0, 1200.0);
    let s = search(TAU, 0.5, 2.0);
    let mut errors = Vec::new();
    let mut reported = Vec::new();
    for stream in 0..20 {
        let x = Encoder::seeded(99)
            .with_noise(0.01)
            .unwrap()
            .with_stream(stream)
            .observe(&theta);
        let found = on_circle(&x, step, t0, &s).unwrap();
        let e = relative_error(&found, TAU);
        let sigma = found.relative_uncertainty();
        assert!(e.abs() < 4.0 * sigma, "stream {stream}: {e:e} against {sigma:e}");
        assert!(sigma < 1e-5, "{sigma:e}");
        errors.push(e);
        reported.push(sigma);
    }
    let n = errors.len() as f64;
    let mean = errors.iter().sum::<f64>() / n;
    let spread = (errors.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    let sigma = (reported.iter().map(|s| s * s).sum::<f64>() / n).sqrt();
    let ratio = spread / sigma;
    assert!(
        (1.0 / 1.6..1.6).contains(&ratio),
        "spread {spread:e}, reported {sigma:e}"
    );
}

/// A range that excludes the truth gives an error, not a number: just outside, one naming the end
/// of the range where the scan's residual is smallest; far outside, one saying that no period of
/// the range explains the record. With the truth in the range the same record gives it.
#[test]
fn a_range_without_the_truth_is_an_error() {
    let (t0, step, theta) = pendulum(TAU, 25.0, 400.0);
    let exact: Vec<f64> = theta.iter().map(|&v| wrap(v)).collect();
    let noisy = Encoder::seeded(3).with_noise(0.01).unwrap().observe(&theta);
    for x in [&exact, &noisy] {
        for (below, above, end) in [(1.005, 1.6, "short"), (0.7, 0.995, "long")] {
            match on_circle(x, step, t0, &search(TAU, below, above)) {
                Err(hb_drive::DriveSearchError::DrivePeriodAtRangeEdge { period, edge, .. }) => {
                    assert_eq!(edge, end);
                    let bound = if end == "short" { below } else { above } * TAU;
                    assert!((period / bound - 1.0).abs() < 1e-9, "{period} against {bound}");
                }
                other => panic!("{below}..{above}: {other:?}"),
            }
        }
        for (below, above) in [(1.2, 1.6), (0.3, 0.45)] {
            match on_circle(x, step, t0, &search(TAU, below, above)) {
                Err(hb_drive::DriveSearchError::DrivePeriodNotFound {
                    residual, typical, ..
                }) => {
                    assert!(residual > 0.9 * typical, "{residual} against {typical}");
                }
                other => panic!("{below}..{above}: {other:?}"),
            }
        }
        let found = on_circle(x, step, t0, &search(TAU, 0.995, 1.6)).unwrap();
        assert!(relative_error(&found, TAU).abs() < 1e-6);
    }
}

/// The forced Duffing oscillator `x'' + 0.3 x' − x + x³ = 0.5 cos(1.2 t)`, chaotic.
struct Duffing;

const DUFFING_W: f64 = 1.2;

impl SecondOrderSystem for Duffing {
    fn acceleration(&self, t: f64, x: f64, v: f64) -> f64 {
        -0.3 * v + x - x * x * x + 0.5 * (DUFFING_W * t).cos()
    }

    fn jacobian(&self, _t: f64, x: f64, _v: f64) -> [f64; 2] {
        [1.0 - 3.0 * x * x, -0.3]
    }
}

/// On the line with a cubic polynomial basis and an identified forcing, 37.7 samples per period:
/// with a given range and with the default one from the spectrum.
#[test]
fn duffing_on_the_line() {
    let period = TAU / DUFFING_W;
    let ratio = 37.7;
    let (t0, step, x) = sample(
        Duffing,
        50.0 * period,
        period / ratio,
        (300.0 * ratio) as usize,
        1.0,
    );
    let basis = Polynomial::new(3).unwrap();
    let form = ModelForm::externally_forced(Forcing::Identified);
    for s in [search(period, 0.5, 2.0), DriveSearch::default()] {
        let found = estimate_drive_period(&x, step, t0, Domain::Line, &s, &basis, &form, |_, _| {}).unwrap();
        let e = relative_error(&found, period);
        assert!(e.abs() < 1e-8, "{:?}: {e:e}", found.range_source);
        if s.range().is_none() {
            assert!(matches!(found.range_source, RangeSource::Spectrum { .. }));
            assert!(found.range.contains(period));
        }
    }
}

/// Without a range, the default one around the dominant spectral period holds the truth on the
/// paper's record; progress is reported in order and ends with every evaluation done.
#[test]
fn default_range_and_progress() {
    let (t0, step, theta) = pendulum(TAU, 25.0, 1200.0);
    let x: Vec<f64> = theta.iter().map(|&v| wrap(v)).collect();
    let mut calls: Vec<(usize, usize)> = Vec::new();
    let found = estimate_drive_period(
        &x,
        step,
        t0,
        Domain::Circle,
        &DriveSearch::default(),
        &Harmonic::new(1).unwrap(),
        &ModelForm::parametric(),
        |done, total| calls.push((done, total)),
    )
    .unwrap();
    assert!(relative_error(&found, TAU).abs() < 1e-8);
    let RangeSource::Spectrum { dominant_period } = found.range_source else {
        panic!("{:?}", found.range_source)
    };
    assert!(
        found.range.contains(TAU),
        "{:?} from {dominant_period}",
        found.range
    );
    assert!(calls.windows(2).all(|w| w[0].0 <= w[1].0));
    assert!(calls.iter().all(|&(done, total)| done <= total));
    assert_eq!(calls.last(), Some(&(found.evaluations, found.evaluations)));
}

#[test]
fn bad_input_is_refused() {
    let (t0, step, theta) = pendulum(TAU, 25.0, 100.0);
    let x: Vec<f64> = theta.iter().map(|&v| wrap(v)).collect();
    let s = search(TAU, 0.5, 2.0);
    let basis = Harmonic::new(1).unwrap();
    let run = |x: &[f64], step: f64, domain: Domain, s: &DriveSearch, form: &ModelForm| {
        estimate_drive_period(x, step, t0, domain, s, &basis, form, |_, _| {})
    };
    let parametric = ModelForm::parametric();
    let no_drive = ModelForm::parametric().without_parametric_terms();
    assert!(matches!(
        run(&x, step, Domain::Circle, &s, &no_drive),
        Err(hb_drive::DriveSearchError::NoDriveTerm)
    ));
    assert!(matches!(
        run(&x, step, Domain::Line, &s, &parametric),
        Err(DriveSearchError::Solve(SolveError::Assembly(
            AssemblyError::DomainMismatch { .. }
        )))
    ));
    assert!(matches!(
        run(&x, 0.0, Domain::Circle, &s, &parametric),
        Err(DriveSearchError::InvalidParameter { .. })
    ));
    // Fewer than 4 samples per period, and a period too long for 6 of it in the record.
    for (lo, hi) in [(2.0 * step, TAU), (TAU, 20.0 * TAU)] {
        let s = DriveSearch::builder()
            .range(PeriodRange::periods(lo, hi).unwrap())
            .build()
            .unwrap();
        assert!(matches!(
            run(&x, step, Domain::Circle, &s, &parametric),
            Err(hb_drive::DriveSearchError::DriveRangeUnfit { .. })
        ));
    }
    let mut bad = x.clone();
    bad[77] = f64::NAN;
    assert!(matches!(
        run(&bad, step, Domain::Circle, &s, &parametric),
        Err(DriveSearchError::Solve(SolveError::Assembly(
            AssemblyError::NonFiniteRecordSample { index: 77, .. }
        )))
    ));
}

/// A known forcing (moved to the right-hand side, no drive column): the linear oscillator
/// `x'' + 0.1 x' + 2 x = cos(W t)` with a decaying free oscillation, on a basis chosen at run time.
#[test]
fn known_forcing_and_a_basis_chosen_at_run_time() {
    let period = 1.37;
    let (w, h) = (TAU / period, period / 61.3);
    let d = (2.0 - w * w).powi(2) + (0.1 * w).powi(2);
    let (a, b) = ((2.0 - w * w) / d, 0.1 * w / d);
    let s = (2.0f64 - 0.0025).sqrt();
    let t0 = 12.5;
    let x: Vec<f64> = (0..8000)
        .map(|n| {
            let t = t0 + n as f64 * h;
            a * (w * t).cos() + b * (w * t).sin() + (-0.05 * t).exp() * (s * t).cos()
        })
        .collect();
    let basis: Box<dyn hb_basis::Basis> =
        Box::new(hb_basis::BasisKind::Polynomial(Polynomial::new(1).unwrap()));
    let form = ModelForm::externally_forced(Forcing::Known { cos: -1.0, sin: 0.0 });
    let found = estimate_drive_period(
        &x,
        h,
        t0,
        Domain::Line,
        &search(period, 0.6, 1.8),
        basis.as_ref(),
        &form,
        |_, _| {},
    )
    .unwrap();
    let e = relative_error(&found, period);
    assert!(e.abs() < 1e-8, "{e:e}");
}

/// The search balances the paper's families only: a form with a term nonlinear in the velocity
/// is refused by name before any work.
#[test]
fn the_drive_estimate_refuses_general_terms() {
    let form =
        ModelForm::from_terms(hb_model::TermList::parse("x', sign(x'), sin(x), sin(t)*cos(x)").unwrap());
    let x: Vec<f64> = (0..4000).map(|n| wrap(0.3 * (0.25 * n as f64).sin())).collect();
    let result = estimate_drive_period(
        &x,
        TAU / 25.0,
        0.0,
        Domain::Circle,
        &DriveSearch::builder().build().unwrap(),
        &Harmonic::new(1).unwrap(),
        &form,
        &mut |_, _| {},
    );
    assert!(
        matches!(
            result,
            Err(DriveSearchError::Solve(SolveError::Assembly(AssemblyError::TermNotSupported { ref term, .. })))
                if term == "sign(x')"
        ),
        "{result:?}"
    );
}

// Parameters and the spectral first guess.

#[test]
fn ranges_are_validated() {
    let r = PeriodRange::frequencies(0.5, 2.0).unwrap();
    assert_eq!((r.shortest(), r.longest()), (0.5, 2.0));
    let r = PeriodRange::around(2.0, 4.0).unwrap();
    assert_eq!((r.shortest(), r.longest()), (0.5, 8.0));
    assert!(r.contains(0.5) && r.contains(8.0) && !r.contains(8.5));
    for (a, b) in [
        (0.0, 1.0),
        (1.0, 1.0),
        (2.0, 1.0),
        (f64::NAN, 1.0),
        (1.0, f64::INFINITY),
    ] {
        assert!(PeriodRange::periods(a, b).is_err(), "{a}..{b}");
        assert!(PeriodRange::frequencies(a, b).is_err(), "{a}..{b}");
    }
    assert!(PeriodRange::around(1.0, 1.0).is_err());
    let json = serde_json::to_string(&PeriodRange::periods(1.0, 3.0).unwrap()).unwrap();
    assert_eq!(
        serde_json::from_str::<PeriodRange>(&json).unwrap(),
        PeriodRange::periods(1.0, 3.0).unwrap()
    );
    assert!(serde_json::from_str::<PeriodRange>(r#"{"shortest":3.0,"longest":1.0}"#).is_err());
}

#[test]
fn search_params_are_validated() {
    let ok = DriveSearch::builder()
        .range(PeriodRange::periods(1.0, 2.0).unwrap())
        .survivors(5)
        .build()
        .unwrap();
    assert_eq!(ok.survivors(), 5);
    assert_eq!(DriveSearch::builder().build().unwrap(), DriveSearch::default());
    let b = DriveSearch::builder;
    for bad in [
        b().window_periods(0).build(),
        b().scan_periods(3).build(),
        b().points_per_basin(1).build(),
        b().growth(1).build(),
        b().survivors(0).build(),
        b().prune_ratio(0.5).build(),
        b().prune_ratio(f64::NAN).build(),
        b().tolerance(0.0).build(),
        b().tolerance(0.1).build(),
        b().max_iterations(0).build(),
        b().harmonics(Harmonics::Fixed(0)).build(),
    ] {
        assert!(
            matches!(bad, Err(DriveSearchError::InvalidParameter { .. })),
            "{bad:?}"
        );
    }
    assert!(b().prune_ratio(f64::INFINITY).build().is_ok());
    let json = serde_json::to_string(&ok).unwrap();
    assert_eq!(serde_json::from_str::<DriveSearch>(&json).unwrap(), ok);
    let bad = json.replace(r#""growth":4"#, r#""growth":1"#);
    assert!(bad != json && serde_json::from_str::<DriveSearch>(&bad).is_err());
}

/// The dominant period of a sinusoid (on the line) and of an oscillating angle (on the
/// circle), neither a whole number of bins.
#[test]
fn dominant_period_of_a_sinusoid() {
    let (period, h) = (1.37, 0.01);
    let line: Vec<f64> = (0..5000)
        .map(|n| 0.3 * n as f64 * h + (TAU * n as f64 * h / period).sin())
        .collect();
    let found = dominant_period(&line, h, Domain::Line, 5).unwrap();
    assert!((found / period - 1.0).abs() < 2e-3, "{found}");
    let angle: Vec<f64> = (0..5000)
        .map(|n| wrap(1.5 * (TAU * n as f64 * h / period).cos()))
        .collect();
    let found = dominant_period(&angle, h, Domain::Circle, 5).unwrap();
    assert!((found / period - 1.0).abs() < 2e-3, "{found}");
    assert!(dominant_period(&line[..10], h, Domain::Line, 5).is_err());
    assert!(dominant_period(&line, -1.0, Domain::Line, 5).is_err());
}
