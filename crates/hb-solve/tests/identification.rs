//! Identification checks: manufactured systems with exact answers, the least-squares solvers as
//! identities, errors, and the paper's data set.
use hb_solve::{AssemblyError, LstsqError};
use std::f64::consts::{PI, TAU};

use circle_signal::SampleClock;
use circle_signal::wrap;
use faer::{Col, Mat};
use hb_basis::{Basis, BasisKind, Harmonic, Hat, Polynomial};
use hb_model::{Forcing, Harmonics, IdentifiedModel, ModelForm};
use hb_solve::{
    IdentifyParams, LstsqSolver, QrSolver, SolveError, SvdSolver, assemble, identify, identify_from_source,
};
use pendulum_sim::{Pendulum, SecondOrderSystem};
use proptest::prelude::*;
use proptest::test_runner::RngSeed;
use upo_search::{CloseReturns, Domain, Segment};

// ---------------------------------------------------------------------------------------------
// Helpers

/// One classical Runge-Kutta step of x'' = f(t, x, v).
use crate::common::{read_paper_dataset, truth};

fn rk4(f: &impl Fn(f64, f64, f64) -> f64, t: f64, (x, v): (f64, f64), h: f64) -> (f64, f64) {
    let k1 = (v, f(t, x, v));
    let k2 = (
        v + 0.5 * h * k1.1,
        f(t + 0.5 * h, x + 0.5 * h * k1.0, v + 0.5 * h * k1.1),
    );
    let k3 = (
        v + 0.5 * h * k2.1,
        f(t + 0.5 * h, x + 0.5 * h * k2.0, v + 0.5 * h * k2.1),
    );
    let k4 = (v + h * k3.1, f(t + h, x + h * k3.0, v + h * k3.1));
    (
        x + h / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0),
        v + h / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1),
    )
}

/// Integrates a forced oscillator (forcing period 2π) from (x0, v0) at t = 0 onto its attracting
/// period-`k` orbit with RK4 at `p * 128` steps per forcing period: a transient, then period after
/// period until the state repeats after k periods (modulo 2π in x) to 1e-13. Returns the time of the
/// first sample and `samples` samples at `p` per forcing period.
fn attractor_samples(
    f: impl Fn(f64, f64, f64) -> f64,
    (x0, v0): (f64, f64),
    k: usize,
    p: usize,
    samples: usize,
) -> (f64, Vec<f64>) {
    let sub = 128;
    let h = TAU / (p * sub) as f64;
    let mut y = (x0, v0);
    let mut step = 0usize;
    let mut advance = |y: &mut (f64, f64), steps: usize| {
        for _ in 0..steps {
            *y = rk4(&f, step as f64 * h, *y, h);
            step += 1;
        }
    };
    advance(&mut y, 100 * p * sub);
    let mut history = vec![y];
    for period in 0.. {
        assert!(period < 2000, "no period-{k} attractor reached");
        advance(&mut y, p * sub);
        history.push(y);
        if history.len() > k {
            let old = history[history.len() - 1 - k];
            if wrap(y.0 - old.0).abs() < 1e-13 && (y.1 - old.1).abs() < 1e-13 {
                break;
            }
        }
    }
    let start = (history.len() - 1 + 100) as f64 * TAU;
    let mut out = Vec::with_capacity(samples);
    for _ in 0..samples {
        out.push(y.0);
        advance(&mut y, sub);
    }
    (start, out)
}

fn paper_segments(x: &[f64]) -> Vec<Segment> {
    use upo_search::OrbitSource;
    let search = CloseReturns::builder(&SampleClock::nondimensional(25).unwrap(), 5)
        .tolerance(0.03)
        .max_period(16)
        .dimension(2)
        .domain(Domain::Circle)
        .build()
        .unwrap();
    search.segments(x).unwrap()
}

// ---------------------------------------------------------------------------------------------
// Manufactured checks with exact answers

/// x'' + c x' + k x = A cos(W t), the exactly periodic solution sampled on a clock with forcing
/// period 0.5 (data in seconds, W = 4π) starting at t0 = 0.37 s.
fn linear_oscillator() -> (SampleClock, Vec<f64>, (f64, f64, f64)) {
    let (c, k, amp) = (0.1 * 4.0 * PI, 2.0 * (4.0 * PI) * (4.0 * PI), 3.0);
    let clock = SampleClock::new(0.5, 40).unwrap().with_start_time(0.37).unwrap();
    let w = clock.drive_angular_frequency();
    // X = amp / (k − w² + i c w): x = Re(X e^{iwt}).
    let (re, im) = (k - w * w, c * w);
    let den = re * re + im * im;
    let (xr, xi) = (amp * re / den, -amp * im / den);
    let x = (0..=3 * 40).map(|n| {
        let t = clock.time(n);
        xr * (w * t).cos() - xi * (w * t).sin()
    });
    (clock, x.collect(), (c, k, amp))
}

#[test]
fn linear_oscillator_with_known_forcing_is_recovered_exactly() {
    let (clock, x, (c, k, amp)) = linear_oscillator();
    // One period-1 segment starting off the forcing's phase, and one period-2 segment.
    let segments = [
        crate::common::segment(13, 1, 40, 0.0),
        crate::common::segment(3, 2, 80, 0.0),
    ];
    let form = ModelForm::externally_forced(Forcing::Known { cos: -amp, sin: 0.0 });
    let params = IdentifyParams::builder(clock).form(form).build().unwrap();
    for solver in [&QrSolver::default() as &dyn LstsqSolver, &SvdSolver::default()] {
        let m = identify(
            Polynomial::new(1).unwrap(),
            &x,
            &segments,
            &params,
            &hb_solve::HarmonicBalance,
            solver,
        )
        .unwrap();
        assert_eq!(m.coefficients().len(), 2);
        assert!(
            (m.damping() - c).abs() <= 1e-9 * c,
            "{}: c = {} vs {c}",
            solver.name(),
            m.damping()
        );
        let kk = m.coefficient("x").unwrap().value;
        assert!((kk - k).abs() <= 1e-9 * k, "{}: k = {kk} vs {k}", solver.name());
        // The model reproduces the acceleration of the true system.
        let (t, xx, v) = (0.81, 0.02, -0.3);
        let w = clock.drive_angular_frequency();
        let want = -c * v - k * xx + amp * (w * t).cos();
        assert!((m.acceleration(t, xx, v) - want).abs() <= 1e-8 * k);
    }
}

#[test]
fn linear_oscillator_with_unknown_forcing_is_rank_deficient() {
    // One sinusoidal orbit balances only harmonic 1: two equations for c, k, F_c, F_s.
    let (clock, x, _) = linear_oscillator();
    let segments = [crate::common::segment(13, 1, 40, 0.0)];
    let params = IdentifyParams::builder(clock)
        .form(ModelForm::externally_forced(Forcing::Identified))
        .build()
        .unwrap();
    for solver in [&QrSolver::default() as &dyn LstsqSolver, &SvdSolver::default()] {
        match identify(
            Polynomial::new(1).unwrap(),
            &x,
            &segments,
            &params,
            &hb_solve::HarmonicBalance,
            solver,
        ) {
            Err(SolveError::Lstsq(LstsqError::RankDeficient { rank, unknowns, .. })) => {
                assert_eq!((rank, unknowns), (2, 4), "{}", solver.name())
            }
            other => panic!("{}: expected a rank deficiency, got {other:?}", solver.name()),
        }
    }
    // A separate k*x beside the monomial x is a duplicate column, and is named.
    let params = IdentifyParams::builder(clock)
        .form(ModelForm::externally_forced(Forcing::Known { cos: -3.0, sin: 0.0 }).with_linear_stiffness())
        .build()
        .unwrap();
    match identify(
        Polynomial::new(1).unwrap(),
        &x,
        &segments,
        &params,
        &hb_solve::HarmonicBalance,
        &QrSolver::default(),
    ) {
        Err(SolveError::Lstsq(LstsqError::RankDeficient {
            rank: 2,
            unknowns: 3,
            suspect,
            ..
        })) => {
            assert!(suspect == "x" || suspect == "k*x", "{suspect}")
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn duffing_orbit_identifies_stiffness_nonlinearity_and_forcing() {
    // x'' + 0.3 x' + x + 0.5 x³ = 1.2 cos t: one attracting period-1 orbit determines all six
    // coefficients of the polynomial model with an identified external forcing (the odd harmonics
    // of a nonlinear orbit give the equations a sinusoid cannot).
    let p = 64;
    let f = |t: f64, x: f64, v: f64| -0.3 * v - x - 0.5 * x * x * x + 1.2 * t.cos();
    let (t0, x) = attractor_samples(f, (0.0, 0.0), 1, p, 3 * p + 1);
    let clock = SampleClock::nondimensional(p)
        .unwrap()
        .with_start_time(t0)
        .unwrap();
    let segments = [
        crate::common::segment(21, 1, p, 0.0),
        crate::common::segment(5, 2, 2 * p, 0.0),
    ];
    let params = IdentifyParams::builder(clock)
        .harmonics(Harmonics::Fixed(20))
        .form(ModelForm::externally_forced(Forcing::Identified))
        .build()
        .unwrap();
    let m = identify(
        Polynomial::new(3).unwrap(),
        &x,
        &segments,
        &params,
        &hb_solve::HarmonicBalance,
        &QrSolver::default(),
    )
    .unwrap();
    let truth = [
        ("x'", 0.3),
        ("x", 1.0),
        ("x^2", 0.0),
        ("x^3", 0.5),
        ("cos(t)", -1.2),
        ("sin(t)", 0.0),
    ];
    for (name, want) in truth {
        let got = m.coefficient(name).unwrap().value;
        assert!((got - want).abs() < 1e-9, "{name}: {got} vs {want}");
    }
}

#[test]
fn whirling_pendulum_orbits_identify_the_pendulum_exactly() {
    // x'' + 0.2 x' + 0.5 sin x − 2.5 sin t cos x = 0 has two coexisting attracting whirling orbits:
    // period 2 with winding −2 (from (0, 1)) and period 3 with winding +3 (from (0, −1)).
    let p = 64;
    let truth = Pendulum::new(2.5, 0.2, 2f64.sqrt()).unwrap();
    let f = |t, x, v| truth.acceleration(t, x, v);
    let (ta, xa) = attractor_samples(f, (0.0, 1.0), 2, p, 2 * p + 40);
    let (tb, xb) = attractor_samples(f, (0.0, -1.0), 3, p, 3 * p + 40);
    // Both start at a whole number of forcing periods, so each keeps its forcing phase in the record.
    let _ = tb;
    // Exactly periodic up to the integration error, with the expected windings.
    assert!(
        (xa[2 * p] - xa[0] + 2.0 * TAU).abs() < 1e-10,
        "period-2 orbit closes: {}",
        xa[2 * p] - xa[0]
    );
    assert!(
        (xb[3 * p] - xb[0] - 3.0 * TAU).abs() < 1e-10,
        "period-3 orbit closes: {}",
        xb[3 * p] - xb[0]
    );

    // One encoder record: orbit A, then orbit B, both wrapped; the time runs on across the record,
    // so orbit B's samples are shifted by a whole number of forcing periods (its phase is kept).
    let shift = 2 * p + 40;
    assert_eq!(shift % p, 40);
    let gap = p - 40; // pad so that orbit B starts a whole number of forcing periods later
    let mut record: Vec<f64> = xa.iter().map(|&v| wrap(v)).collect();
    record.extend(std::iter::repeat_n(0.0, gap));
    let b_start = record.len();
    assert_eq!(b_start % p, 0);
    record.extend(xb.iter().map(|&v| wrap(v)));
    let segments = [
        crate::common::segment(17, 2, 2 * p, 0.0),
        crate::common::segment(b_start + 29, 3, 3 * p, 0.0),
    ];
    let want = [
        ("x'", 0.2),
        ("cos(t)*cos(x)", 0.0),
        ("sin(t)*cos(x)", -2.5),
        ("cos(x)", 0.0),
        ("cos(t)*sin(x)", 0.0),
        ("sin(t)*sin(x)", 0.0),
        ("sin(x)", 0.5),
    ];
    for (clock_period, scale_c, scale_q) in [(TAU, 1.0, 1.0), (0.5, 4.0 * PI, 16.0 * PI * PI)] {
        // The same samples on a clock in seconds (forcing period 0.5 s): c scales by W, the rest by W².
        let t0 = ta * clock_period / TAU;
        let clock = SampleClock::new(clock_period, p)
            .unwrap()
            .with_start_time(t0)
            .unwrap();
        let params = IdentifyParams::builder(clock)
            .harmonics(Harmonics::DriveCap(8.0))
            .build()
            .unwrap();
        for solver in [&QrSolver::default() as &dyn LstsqSolver, &SvdSolver::default()] {
            let system = assemble(&Harmonic::new(1).unwrap(), &record, &segments, &params).unwrap();
            let windings: Vec<i64> = system.blocks().iter().map(|b| b.winding).collect();
            assert_eq!(windings, [-2, 3]);
            let m = identify(
                Harmonic::new(1).unwrap(),
                &record,
                &segments,
                &params,
                &hb_solve::HarmonicBalance,
                solver,
            )
            .unwrap();
            for (name, v) in want {
                let scale = if name == "x'" { scale_c } else { scale_q };
                let got = m.coefficient(name).unwrap().value / scale;
                assert!(
                    (got - v).abs() < 1e-9,
                    "{} T = {clock_period}: {name} = {got} vs {v}",
                    solver.name()
                );
            }
            assert_eq!(m.summary().unwrap().whirling_segments, 2);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Errors

#[test]
fn too_few_orbits_says_how_many() {
    let (t0, x) = read_paper_dataset();
    let clock = crate::common::paper_clock(t0);
    let params = IdentifyParams::builder(clock)
        .harmonics(Harmonics::Fixed(3))
        .build()
        .unwrap();
    let one = [crate::common::segment(0, 1, 25, 0.0)];
    // Harmonic K = 3: 1 + 3·6 = 19 unknowns; a period-1 orbit gives 7 equations; 20 are needed.
    let err = identify(
        Harmonic::new(3).unwrap(),
        &x,
        &one,
        &params,
        &hb_solve::HarmonicBalance,
        &QrSolver::default(),
    )
    .unwrap_err();
    assert!(
        matches!(
            err,
            SolveError::Lstsq(LstsqError::TooFewOrbits { found: 1, needed: 3 })
        ),
        "{err:?}"
    );
    let msg = err.to_string();
    assert!(
        msg.contains("1 found") && msg.contains("at least 3") && msg.contains("tolerance"),
        "{msg}"
    );
    let err = identify(
        Harmonic::new(1).unwrap(),
        &x,
        &[],
        &params,
        &hb_solve::HarmonicBalance,
        &QrSolver::default(),
    )
    .unwrap_err();
    assert!(
        matches!(
            err,
            SolveError::Lstsq(LstsqError::TooFewOrbits { found: 0, needed: 2 })
        ),
        "{err:?}"
    );
}

#[test]
fn bad_input_never_reaches_the_solver() {
    let (t0, mut x) = read_paper_dataset();
    let clock = crate::common::paper_clock(t0);
    let params = IdentifyParams::builder(clock).build().unwrap();
    let segs: Vec<Segment> = (0..4)
        .map(|i| crate::common::segment(100 * i, 1, 25, 0.0))
        .collect();
    x[310] = f64::NAN;
    let err = identify(
        Harmonic::new(1).unwrap(),
        &x,
        &segs,
        &params,
        &hb_solve::HarmonicBalance,
        &QrSolver::default(),
    )
    .unwrap_err();
    assert!(
        matches!(
            err,
            SolveError::Assembly(AssemblyError::NonFiniteSample {
                segment: 3,
                index: 310,
                ..
            })
        ),
        "{err:?}"
    );
    x[310] = 0.0;
    let bad = [crate::common::segment(0, 2, 25, 0.0)];
    assert!(matches!(
        identify(
            Harmonic::new(1).unwrap(),
            &x,
            &bad,
            &params,
            &hb_solve::HarmonicBalance,
            &QrSolver::default()
        ),
        Err(SolveError::Assembly(AssemblyError::BadSegment { segment: 0, .. }))
    ));
    let past_end = [crate::common::segment(x.len() - 25, 1, 25, 0.0)];
    assert!(matches!(
        identify(
            Harmonic::new(1).unwrap(),
            &x,
            &past_end,
            &params,
            &hb_solve::HarmonicBalance,
            &QrSolver::default()
        ),
        Err(SolveError::Assembly(AssemblyError::BadSegment { .. }))
    ));
    // k*x makes no sense for an angle.
    let params = IdentifyParams::builder(clock)
        .form(ModelForm::parametric().with_linear_stiffness())
        .build()
        .unwrap();
    assert!(matches!(
        identify(
            Harmonic::new(1).unwrap(),
            &x,
            &segs,
            &params,
            &hb_solve::HarmonicBalance,
            &QrSolver::default()
        ),
        Err(SolveError::Model(hb_model::ModelError::Term(hb_model::TermError::TermNotAllowed { ref term, .. }))) if term == "k*x"
    ));
    // A monomial that overflows is caught with its segment.
    let huge: Vec<f64> = (0..200).map(|n| 1e120 * (n as f64 * 0.3).sin()).collect();
    let params = IdentifyParams::builder(clock)
        .form(ModelForm::externally_forced(Forcing::None))
        .build()
        .unwrap();
    let segs = [
        crate::common::segment(0, 1, 25, 0.0),
        crate::common::segment(50, 1, 25, 0.0),
    ];
    assert!(matches!(
        identify(Polynomial::new(3).unwrap(), &huge, &segs, &params, &hb_solve::HarmonicBalance, &QrSolver::default()),
        Err(SolveError::Assembly(AssemblyError::NonFiniteTerm { segment: 0, ref term, .. })) if term == "x^3"
    ));
    // So it is by the weak form, whose basis values at a sample serve every window holding it:
    // overlapping windows, the overflow in the samples the second shares with the first only.
    let mut late = vec![0.0; 200];
    late[60] = 1e120;
    let segs = [
        crate::common::segment(40, 1, 25, 0.0),
        crate::common::segment(50, 1, 25, 0.0),
    ];
    assert!(matches!(
        identify(Polynomial::new(3).unwrap(), &late, &segs, &params, &hb_solve::WeakForm::default(), &QrSolver::default()),
        Err(SolveError::Assembly(AssemblyError::NonFiniteTerm { ref term, start: 40 | 50, .. })) if term == "x^3"
    ));
}

// ---------------------------------------------------------------------------------------------
// Least squares as identities

fn system(seed: u64, m: usize, n: usize) -> (Mat<f64>, Col<f64>) {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    // Well conditioned: a random tall matrix with columns of different scales.
    let scales: Vec<f64> = (0..n).map(|_| 10f64.powf(rng.random_range(-2.0..2.0))).collect();
    let a = Mat::from_fn(m, n, |_, j| rng.random_range(-1.0..1.0) * scales[j]);
    let b = Col::from_fn(m, |_| rng.random_range(-1.0..1.0));
    (a, b)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn solvers_satisfy_the_normal_equations_and_agree(seed in any::<u64>(), n in 1usize..9, extra in 1usize..40) {
        let m = n + extra;
        let (a, b) = system(seed, m, n);
        let qr = QrSolver::default().solve(a.as_ref(), b.as_ref()).unwrap();
        let svd = SvdSolver::default().solve(a.as_ref(), b.as_ref()).unwrap();
        for fit in [&qr, &svd] {
            // Aᵀ(Ax − b) = 0, relative to |A_j| |b| column by column.
            for j in 0..n {
                let col = a.col(j);
                let mut g = 0.0;
                for i in 0..m {
                    let r: f64 = (0..n).map(|c| a[(i, c)] * fit.solution[c]).sum::<f64>() - b[i];
                    g += col[i] * r;
                }
                let scale = col.iter().map(|v| v * v).sum::<f64>().sqrt() * b.iter().map(|v| v * v).sum::<f64>().sqrt();
                prop_assert!(g.abs() <= 1e-12 * scale, "column {}: {} vs {}", j, g, scale);
            }
        }
        for j in 0..n {
            let x = qr.solution[j].abs().max(svd.solution[j].abs()).max(1e-300);
            prop_assert!((qr.solution[j] - svd.solution[j]).abs() <= 1e-10 * x.max(1.0 / a.col(j).iter().map(|v| v.abs()).fold(0.0, f64::max)),
                "x_{}: {} vs {}", j, qr.solution[j], svd.solution[j]);
            // The covariance from R and from V Σ⁻² Vᵀ agree.
            prop_assert!((qr.std_errors[j] - svd.std_errors[j]).abs() <= 1e-8 * qr.std_errors[j].max(1e-300),
                "se_{}: {} vs {}", j, qr.std_errors[j], svd.std_errors[j]);
        }
        prop_assert!((qr.condition - svd.condition).abs() <= 1e-8 * svd.condition);
        prop_assert!((qr.rss - svd.rss).abs() <= 1e-10 * (1.0 + svd.rss));
    }
}

#[test]
fn standard_errors_match_the_textbook_formula() {
    // s² (AᵀA)⁻¹ computed here by Gauss-Jordan on a small well-conditioned system.
    let (a, b) = system(3, 30, 3);
    let fit = QrSolver::default().solve(a.as_ref(), b.as_ref()).unwrap();
    let mut g = [[0.0; 6]; 3];
    for i in 0..3 {
        for j in 0..3 {
            g[i][j] = (0..30).map(|r| a[(r, i)] * a[(r, j)]).sum();
        }
        g[i][3 + i] = 1.0;
    }
    for c in 0..3 {
        let piv = g[c][c];
        for v in g[c].iter_mut() {
            *v /= piv;
        }
        for r in 0..3 {
            if r != c {
                let f = g[r][c];
                let row = g[c];
                for (v, w) in g[r].iter_mut().zip(row) {
                    *v -= f * w;
                }
            }
        }
    }
    for j in 0..3 {
        let se = (fit.residual_variance * g[j][3 + j]).sqrt();
        assert!(
            (se - fit.std_errors[j]).abs() < 1e-10 * se,
            "{se} vs {}",
            fit.std_errors[j]
        );
    }
}

// ---------------------------------------------------------------------------------------------
// The paper's data set (e = 3 %, periods 1..16, d = 2, delay 5, P = 25)

#[test]
fn paper_dataset_harmonic_basis() {
    let (t0, x) = read_paper_dataset();
    let segs = paper_segments(&x);
    let clock = crate::common::paper_clock(t0);
    let params = IdentifyParams::builder(clock).build().unwrap();
    let basis: BasisKind = Harmonic::new(1).unwrap().into();
    let m = identify(
        basis,
        &x,
        &segs,
        &params,
        &hb_solve::HarmonicBalance,
        &QrSolver::default(),
    )
    .unwrap();
    for t in truth().coefficients() {
        let (name, want) = (&t.name, t.value);
        let c = m.coefficient(name).unwrap();
        assert!((c.value - want).abs() < 0.005, "{name}: {} vs {want}", c.value);
        assert!(
            c.std_error > 0.0 && c.std_error < 0.01,
            "{name}: standard error {}",
            c.std_error
        );
    }
    let s = m.summary().unwrap();
    assert_eq!(s.segments, segs.len());
    assert!(s.whirling_segments > 0 && s.whirling_segments < s.segments);
    assert!(s.condition > 1.0 && s.condition < 100.0);

    // The same through the OrbitSource and the SVD, and after a save/load round trip.
    let search = CloseReturns::builder(&SampleClock::nondimensional(25).unwrap(), 5)
        .tolerance(0.03)
        .max_period(16)
        .dimension(2)
        .build()
        .unwrap();
    let m2 = identify_from_source(
        basis,
        &x,
        &search,
        &params,
        &hb_solve::HarmonicBalance,
        &SvdSolver::default(),
    )
    .unwrap();
    for (a, b) in m.coefficients().iter().zip(m2.coefficients()) {
        assert!((a.value - b.value).abs() < 1e-10, "{}", a.name);
    }
    assert_eq!(
        IdentifiedModel::<BasisKind>::from_json(&m.to_json().unwrap()).unwrap(),
        m
    );
    assert_eq!(
        IdentifiedModel::<BasisKind>::from_bytes(&m.to_bytes().unwrap()).unwrap(),
        m
    );

    // The identified model drives like the pendulum.
    let truth = Pendulum::paper();
    for i in 0..50 {
        let (t, xx, v) = (
            0.37 * i as f64,
            -PI + 0.13 * i as f64,
            2.0 * (i as f64 * 0.7).sin(),
        );
        let d = (m.acceleration(t, xx, v) - truth.acceleration(t, xx, v)).abs();
        assert!(d < 0.02, "t = {t}, x = {xx}, v = {v}: {d}");
    }
}

/// Quadrature points of the L2 projections of the true curves onto the hats.
const PROJECTION_POINTS: usize = 4096;

#[test]
fn paper_dataset_hat_basis() {
    let (t0, x) = read_paper_dataset();
    let segs = paper_segments(&x);
    let clock = crate::common::paper_clock(t0);
    let params = IdentifyParams::builder(clock).build().unwrap();
    let hat = Hat::new(8).unwrap();
    let m = identify(
        hat,
        &x,
        &segs,
        &params,
        &hb_solve::HarmonicBalance,
        &QrSolver::default(),
    )
    .unwrap();
    let truth = truth();
    assert!(
        (m.damping() - truth.damping()).abs() < 0.003,
        "c_r = {}",
        m.damping()
    );
    // The true curves: q(x) = (1/r²) sin x, p(x) = −f cos x (and n(x) = 0).
    let q_ref = hat.project(PROJECTION_POINTS, |x| truth.autonomous(x)).unwrap();
    let p_ref = hat.project(PROJECTION_POINTS, |x| truth.parametric(x).1).unwrap();
    let (mut dq, mut dp, mut dn) = (0.0, 0.0, 0.0);
    let grid = 1000;
    let mut phi = vec![0.0; 8];
    for s in 0..grid {
        let xx = -PI + TAU * (s as f64 + 0.5) / grid as f64;
        hat.eval(xx, &mut phi);
        let q: f64 = phi.iter().zip(&q_ref).map(|(a, b)| a * b).sum();
        let p: f64 = phi.iter().zip(&p_ref).map(|(a, b)| a * b).sum();
        let (n_got, p_got) = m.parametric(xx);
        dq += (m.autonomous(xx) - q).powi(2);
        dp += (p_got - p).powi(2);
        dn += n_got.powi(2);
    }
    let (dq, dp, dn) = (
        (dq / grid as f64).sqrt(),
        (dp / grid as f64).sqrt(),
        (dn / grid as f64).sqrt(),
    );
    assert!(dq < 0.1 && dp < 0.1, "q curve RMS {dq}, p curve RMS {dp}");
    assert!(dn < 0.1, "n curve RMS {dn} (true curve 0)");
}

/// A segment's rows do not depend on the other segments or their order (segments are grouped by
/// start to share one evaluation of the basis): the rows of the paper's segments assembled in
/// reverse order, and of a few segments alone, are those of the full system, bit for bit.
#[test]
fn rows_do_not_depend_on_the_other_segments() {
    let (t0, x) = read_paper_dataset();
    let segs = paper_segments(&x);
    let clock = crate::common::paper_clock(t0);
    let params = IdentifyParams::builder(clock).build().unwrap();
    let basis = Hat::new(8).unwrap();
    let all = assemble(&basis, &x, &segs, &params).unwrap();
    let reversed: Vec<Segment> = segs.iter().rev().copied().collect();
    let rev = assemble(&basis, &x, &reversed, &params).unwrap();
    // Far-apart segments (different groups), enough rows for 25 unknowns.
    let few: Vec<Segment> = segs.iter().step_by(37).copied().collect();
    let some = assemble(&basis, &x, &few, &params).unwrap();
    let same_rows = |a: &hb_solve::LinearSystem, ia: usize, b: &hb_solve::LinearSystem, ib: usize| {
        let (ba, bb) = (&a.blocks()[ia], &b.blocks()[ib]);
        assert_eq!(ba.segment, bb.segment);
        assert_eq!(ba.rows, bb.rows);
        for r in 0..ba.rows {
            assert_eq!(a.rhs()[ba.first_row + r], b.rhs()[bb.first_row + r]);
            for c in 0..a.unknowns() {
                assert_eq!(
                    a.matrix()[(ba.first_row + r, c)],
                    b.matrix()[(bb.first_row + r, c)]
                );
            }
        }
    };
    let n = segs.len();
    assert_eq!(rev.blocks().len(), n);
    for i in 0..n {
        same_rows(&all, i, &rev, n - 1 - i);
    }
    for (k, i) in (0..n).step_by(37).enumerate() {
        same_rows(&all, i, &some, k);
    }
}

// ---------------------------------------------------------------------------------------------
// The assembly identity: every row of `A λ − β` is a balance of the residual of the equation
//
// A record is sampled from a signal known in closed form, `x(t) = x_0 + w t + Σ a cos(ω t + φ)`
// (a rotation only on the circle, where the record is wrapped), on any of the three bases with
// any model form, and the coefficients `λ` of every column are drawn at random. The
// residual of the model, `r(t) = x'' + Σ_c λ_c g_c(x, x', t)` (plus a known forcing), is computed
// here independently of the assemblies: `x'` and `x''` from their closed forms, `g_c` from the
// factors of the column's term (drive × function of x × function of x'), the basis evaluated at
// the sample. Each method's rows must then be a linear functional of `r`: its Fourier coefficients
// over an orbit (harmonic balance), its trapezoid integral against the test functions (the weak
// form), or its value at each sample (finite differences). A wrong column, sign, phase or scale
// breaks the equality by the size of that column's terms.
//
// Besides the rounding of the arithmetic (`1e-12` of the size of the terms), each sample carries
// the rounding `δ` of its computation and wrapping; the bounds add `δ` times the norm of each
// method's map from the samples to a row.

/// A signal in closed form, `x(t) = x_0 + w (t − t_mid) + Σ a cos(ω t + φ)`.
#[derive(Debug, Clone)]
struct Signal {
    offset: f64,
    rate: f64,
    /// `t_mid`, the middle of the record, so that the rotation adds as little as possible to `|x|`.
    origin: f64,
    /// `(a, ω, φ)`.
    waves: Vec<(f64, f64, f64)>,
}

impl Signal {
    fn x(&self, t: f64) -> f64 {
        self.offset
            + self.rate * (t - self.origin)
            + self
                .waves
                .iter()
                .map(|&(a, w, p)| a * (w * t + p).cos())
                .sum::<f64>()
    }

    fn dx(&self, t: f64) -> f64 {
        self.rate
            - self
                .waves
                .iter()
                .map(|&(a, w, p)| a * w * (w * t + p).sin())
                .sum::<f64>()
    }

    fn ddx(&self, t: f64) -> f64 {
        -self
            .waves
            .iter()
            .map(|&(a, w, p)| a * w * w * (w * t + p).cos())
            .sum::<f64>()
    }

    /// `Σ |a| ω^n`, a bound of `|x^(n)|` for `n >= 2`.
    fn derivative_bound(&self, n: i32) -> f64 {
        self.waves.iter().map(|&(a, w, _)| a.abs() * w.powi(n)).sum()
    }

    /// A bound of every intermediate of `x(t)` for `|t| <= t_max`, and of the wrapped angle's.
    fn magnitude(&self, t_max: f64) -> f64 {
        self.offset.abs()
            + self.rate.abs() * (t_max + self.origin.abs())
            + self
                .waves
                .iter()
                .map(|&(a, w, p)| a.abs() * (1.0 + w * t_max + p.abs()))
                .sum::<f64>()
            + PI
    }
}

/// What proptest draws for one case of the identity.
#[derive(Debug, Clone)]
struct Draw {
    basis: BasisKind,
    parametric: bool,
    /// 0: no forcing, 1: identified, 2: known.
    forcing: u8,
    known: (f64, f64),
    stiffness: bool,
    /// Forcing period `T` of the clock.
    forcing_period: f64,
    samples_per_period: usize,
    start_time: f64,
    /// The orbit's period `k` in forcing periods.
    period: usize,
    /// Turns per `k` periods on the circle (periodic records).
    winding: i64,
    /// Rotation rate in units of `W` on the circle (records that need not be periodic).
    rate: f64,
    offset: f64,
    /// `(ω / W, a, φ)`; for a periodic record `ω` is rounded to a harmonic of `W / k`.
    waves: Vec<(f64, f64, f64)>,
    /// `(where in the record, twice the orbit's period)`.
    segments: Vec<(f64, bool)>,
    harmonics: usize,
    lambda: Vec<f64>,
    /// A list of terms instead of the preset: `(drive, function, velocity)` codes, see
    /// [`general_terms`].
    general: Option<Vec<(u8, usize, u8)>>,
}

/// The list of terms of `codes` on `basis`: drive `0` none, `1..=6` `cos(t)`, `sin(t)`, `cos(2t)`,
/// .., `sin(3t)`; function `0` none, `i` basis function `i − 1` (modulo); velocity `0..5` none,
/// `x'`, `sign(x')`, `x'*|x'|`, `x'^3`. Repeated terms are dropped.
fn general_terms(codes: &[(u8, usize, u8)], basis: &BasisKind) -> hb_model::TermList {
    let names = basis.names();
    let mut terms: Vec<hb_model::TermSpec> = Vec::new();
    for &(drive, function, velocity) in codes {
        let mut factors: Vec<String> = Vec::new();
        if drive > 0 {
            let q = u32::from(drive).div_ceil(2);
            let trig = if drive % 2 == 1 { "cos" } else { "sin" };
            factors.push(format!("{trig}({q}t)"));
        }
        let f = function % (names.len() + 1);
        if f > 0 {
            factors.push(names[f - 1].clone());
        }
        match velocity {
            1 => factors.push("x'".into()),
            2 => factors.push("sign(x')".into()),
            3 => factors.push("x'*|x'|".into()),
            4 => factors.push("x'^3".into()),
            _ => {}
        }
        let name = if factors.is_empty() {
            "1".to_owned()
        } else {
            factors.join("*")
        };
        let term: hb_model::TermSpec = name.parse().unwrap();
        if !terms.contains(&term) {
            terms.push(term);
        }
    }
    hb_model::TermList::new(terms).unwrap()
}

/// `codes` with every velocity factor mapped by `f`.
fn map_velocity(d: &Draw, f: impl Fn(u8) -> u8) -> Draw {
    Draw {
        general: d
            .general
            .as_ref()
            .map(|g| g.iter().map(|&(a, b, v)| (a, b, f(v))).collect()),
        ..d.clone()
    }
}

/// For the weak form on hats: no hat times `x'`. The weak form integrates `hat(x) x'` by parts,
/// `−∫ ψ' H(x)` with `H` the hat's antiderivative, and the trapezoid sums of the two sides of the
/// integration by parts agree only to `O(h²)` when the integrand has kinks (where `x` crosses a
/// node); for the smooth bases they agree to the rule's (spectral) accuracy.
fn smooth_by_parts(d: &Draw) -> Draw {
    let hats = matches!(d.basis, BasisKind::Hat(_));
    Draw {
        general: d.general.as_ref().map(|g| {
            g.iter()
                .map(|&(a, b, v)| (a, if hats && v == 1 { 0 } else { b }, v))
                .collect()
        }),
        ..d.clone()
    }
}

fn basis_strategy() -> impl Strategy<Value = BasisKind> {
    prop_oneof![
        (1usize..=3).prop_map(|k| BasisKind::from(Harmonic::new(k).unwrap())),
        (3usize..=8).prop_map(|n| BasisKind::from(Hat::new(n).unwrap())),
        (1usize..=3).prop_map(|d| BasisKind::from(Polynomial::new(d).unwrap())),
    ]
}

prop_compose! {
    fn draw()(
        basis in basis_strategy(),
        (parametric, forcing, known, stiffness) in (any::<bool>(), 0u8..3, (-2.0..2.0, -2.0..2.0), any::<bool>()),
        forcing_period in prop_oneof![Just(TAU), Just(0.5)],
        samples_per_period in prop_oneof![Just(24usize), Just(32), Just(40)],
        start_time in -20.0..20.0,
        (period, winding, rate, offset) in (1usize..=3, -2i64..=2, -2.0..2.0, -1.0..1.0),
        waves in proptest::collection::vec((0.2..2.0, 0.05..0.8, 0.0..TAU), 1..=3),
        segments in proptest::collection::vec((0.0..1.0, any::<bool>()), 1..=4),
        harmonics in 1usize..=8,
        lambda in proptest::collection::vec(-2.0..2.0, 40),
        general in proptest::option::of(proptest::collection::vec((0u8..7, 0usize..16, 0u8..5), 1..=8)),
    ) -> Draw {
        Draw {
            basis, parametric, forcing, known, stiffness, forcing_period, samples_per_period,
            start_time, period, winding, rate, offset, waves, segments, harmonics, lambda, general,
        }
    }
}

/// One case: a model (basis, params, coefficients), the signal and its record, and segments.
#[derive(Debug)]
struct Case {
    basis: BasisKind,
    params: IdentifyParams,
    signal: Signal,
    record: Vec<f64>,
    segments: Vec<Segment>,
    lambda: Vec<f64>,
}

impl Case {
    /// The case of `draw`; with `periodic`, the signal repeats after `k` forcing periods (the
    /// rotation included) and every segment spans `k` or `2k` periods.
    fn new(d: &Draw, periodic: bool) -> Self {
        let clock = SampleClock::new(d.forcing_period, d.samples_per_period)
            .unwrap()
            .with_start_time(d.start_time)
            .unwrap();
        let big_w = clock.drive_angular_frequency();
        let k = d.period;
        let omega = big_w / k as f64;
        let circle = d.basis.domain() == Domain::Circle;
        let p = d.samples_per_period;
        let len = 6 * k * p + 1;
        let waves = d
            .waves
            .iter()
            .map(|&(f, a, phase)| {
                let w = if periodic {
                    (f * k as f64).round().max(1.0) * omega
                } else {
                    f * big_w
                };
                (a, w, phase)
            })
            .collect();
        let signal = Signal {
            offset: if circle { d.offset * PI } else { 0.5 * d.offset },
            rate: match (circle, periodic) {
                (false, _) => 0.0,
                (true, true) => d.winding as f64 * omega,
                (true, false) => d.rate * big_w,
            },
            origin: clock.time(len / 2),
            waves,
        };
        let forcing = match d.forcing {
            0 => Forcing::None,
            1 => Forcing::Identified,
            _ => Forcing::Known {
                cos: d.known.0,
                sin: d.known.1,
            },
        };
        let mut form = ModelForm::parametric().with_forcing(forcing);
        if !d.parametric {
            form = form.without_parametric_terms();
        }
        if d.stiffness && !circle {
            form = form.with_linear_stiffness();
        }
        if let Some(codes) = &d.general {
            form = ModelForm::from_terms(general_terms(codes, &d.basis));
        }
        let unknowns = hb_model::columns(&d.basis, &form).unwrap().len();
        let params = IdentifyParams::builder(clock)
            .harmonics(Harmonics::Fixed(d.harmonics))
            .form(form)
            .build()
            .unwrap();
        let segments: Vec<(f64, usize)> = d
            .segments
            .iter()
            .map(|&(at, double)| (at, if double { 2 * k } else { k }))
            .collect();
        Self::from_parts(
            d.basis,
            params,
            signal,
            len,
            &segments,
            d.lambda[..unknowns].to_vec(),
        )
    }

    /// The record of `len` samples of `signal` (wrapped on the circle) and segments of it: at
    /// `(where, period)`, each leaving two samples on either side (the stencils of the
    /// differences), repeated at other places until there are more equations than unknowns
    /// (2M + 1 per segment; the differences give more).
    fn from_parts(
        basis: BasisKind,
        params: IdentifyParams,
        signal: Signal,
        len: usize,
        segments: &[(f64, usize)],
        lambda: Vec<f64>,
    ) -> Self {
        let clock = *params.clock();
        let circle = basis.domain() == Domain::Circle;
        let record: Vec<f64> = (0..len)
            .map(|n| {
                let x = signal.x(clock.time(n));
                if circle { wrap(x) } else { x }
            })
            .collect();
        let p = clock.whole_samples_per_period().unwrap();
        let mut placed = Vec::new();
        let mut rows = 0;
        for (i, &(at, period)) in segments.iter().cycle().enumerate() {
            if i >= segments.len() && rows > lambda.len() {
                break;
            }
            let room = len - 5 - period * p;
            let at = (at + 0.377 * (i / segments.len()) as f64).fract();
            let start = 2 + (at * room as f64) as usize;
            placed.push(Segment::new(start, period, &clock, 0.0, len).unwrap());
            rows += 2 * params.harmonics().count(period, period * p) + 1;
        }
        Self {
            basis,
            params,
            signal,
            record,
            segments: placed,
            lambda,
        }
    }

    fn clock(&self) -> &SampleClock {
        self.params.clock()
    }

    /// The residual `x'' + Σ λ g + F_c cos(W t) + F_s sin(W t)` at sample `n`, from the closed
    /// form of the signal and the terms' factors.
    fn residual(&self, n: usize) -> f64 {
        self.residual_terms(n, None).0
    }

    /// The residual at sample `n` with the nonlinear functions of `x'` evaluated at `v` (a
    /// method's estimate of the velocity there).
    fn residual_at_velocity(&self, n: usize, v: f64) -> f64 {
        self.residual_terms(n, Some(v)).0
    }

    /// The residual at sample `n`; the sum of the absolute values of its terms; and the sum of
    /// the absolute values of the derivatives of its terms in `x` (`|∂r/∂x|` bounded, the
    /// sensitivity of the basis terms to an error in the sample).
    fn residual_terms(&self, n: usize, estimate: Option<f64>) -> (f64, f64, f64) {
        use hb_model::{DriveFactor, PositionFactor, VelocityFactor};
        let t = self.clock().time(n);
        let big_w = self.clock().drive_angular_frequency();
        let sample = self.record[n];
        let (mut phi, mut dphi) = (vec![0.0; self.basis.len()], vec![0.0; self.basis.len()]);
        let at = if self.basis.domain() == Domain::Circle {
            wrap(sample)
        } else {
            sample
        };
        self.basis.eval(at, &mut phi);
        self.basis.eval_deriv(at, &mut dphi);
        let v = self.signal.dx(t);
        let form = self.params.form();
        let mut r = self.signal.ddx(t);
        let (mut size, mut slope) = (r.abs(), 0.0);
        for (term, lambda) in hb_model::columns(&self.basis, form)
            .unwrap()
            .iter()
            .zip(&self.lambda)
        {
            let drive = match term.drive {
                DriveFactor::One => 1.0,
                DriveFactor::Cos(j) => (f64::from(j) * big_w * t).cos(),
                DriveFactor::Sin(j) => (f64::from(j) * big_w * t).sin(),
                // The generated systems have no measured drive.
                DriveFactor::Measured(_) => f64::NAN,
            };
            let (position, dposition) = match term.position {
                PositionFactor::One => (1.0, 0.0),
                PositionFactor::Basis(i) => (phi[i], dphi[i]),
                PositionFactor::Linear => (sample, 1.0),
            };
            let nonlinear = estimate.unwrap_or(v);
            let velocity = match term.velocity {
                VelocityFactor::One => 1.0,
                VelocityFactor::Linear => v,
                VelocityFactor::Sign => nonlinear.signum(),
                VelocityFactor::Quadratic => nonlinear * nonlinear.abs(),
                VelocityFactor::Cubic => nonlinear * nonlinear * nonlinear,
                VelocityFactor::Square => nonlinear * nonlinear,
            };
            let g = lambda * drive * position * velocity;
            r += g;
            size += g.abs();
            slope += (lambda * drive * dposition * velocity).abs();
        }
        if let Forcing::Known { cos, sin } = form.forcing() {
            let f = [cos * (big_w * t).cos(), sin * (big_w * t).sin()];
            r += f[0] + f[1];
            size += f[0].abs() + f[1].abs();
        }
        (r, size, slope)
    }

    /// The assembled system (noise correction included, here none), `A λ − β` row by row, and
    /// the size of the terms of both sides: the largest of `Σ_c |A_rc λ_c| + |β_r|` over the rows
    /// and of the sum of the absolute values of the residual's terms over the record.
    fn rows(&self, method: &dyn hb_solve::Assembly) -> (hb_solve::LinearSystem, Vec<f64>, f64) {
        let system =
            hb_solve::build_system(&self.basis, &self.record, &self.segments, &self.params, method).unwrap();
        let (a, b) = (system.matrix(), system.rhs());
        assert_eq!(a.ncols(), self.lambda.len());
        let mut scale = 0.0f64;
        let rows = (0..a.nrows())
            .map(|r| {
                let terms = (0..a.ncols()).map(|c| a[(r, c)] * self.lambda[c]);
                scale = scale.max(terms.clone().map(f64::abs).sum::<f64>() + b[r].abs());
                terms.sum::<f64>() - b[r]
            })
            .collect();
        let residual_size = (0..self.record.len())
            .map(|n| self.residual_terms(n, None).1)
            .fold(0.0, f64::max);
        (system, rows, scale.max(residual_size))
    }

    /// `δ`, a bound of the rounding error of a sample as the assemblies see it: the closed form
    /// evaluated, wrapped and unwrapped, eight roundings of its largest intermediate.
    fn sample_error(&self) -> f64 {
        let t_max = (0..self.record.len())
            .map(|n| self.clock().time(n).abs())
            .fold(0.0, f64::max);
        8.0 * f64::EPSILON * self.signal.magnitude(t_max)
    }

    /// The largest `Σ |∂g/∂x'|` of the residual's terms over the record (`|c|` for the presets).
    fn velocity_slope(&self) -> f64 {
        use hb_model::{DriveFactor, PositionFactor};
        let big_w = self.clock().drive_angular_frequency();
        let terms = hb_model::columns(&self.basis, self.params.form()).unwrap();
        let mut phi = vec![0.0; self.basis.len()];
        (0..self.record.len())
            .map(|n| {
                let t = self.clock().time(n);
                let v = self.signal.dx(t);
                let sample = self.record[n];
                self.basis.eval(sample, &mut phi);
                terms
                    .iter()
                    .zip(&self.lambda)
                    .map(|(term, lambda)| {
                        let drive = match term.drive {
                            DriveFactor::One => 1.0,
                            DriveFactor::Cos(j) => (f64::from(j) * big_w * t).cos(),
                            DriveFactor::Sin(j) => (f64::from(j) * big_w * t).sin(),
                            DriveFactor::Measured(_) => f64::NAN,
                        };
                        let position = match term.position {
                            PositionFactor::One => 1.0,
                            PositionFactor::Basis(i) => phi[i],
                            PositionFactor::Linear => sample,
                        };
                        (lambda * drive * position * term.velocity.eval_deriv(v)).abs()
                    })
                    .sum::<f64>()
            })
            .fold(0.0, f64::max)
    }

    /// Whether a term beyond the presets holds a function of `x'`, estimated from the series
    /// (harmonic balance) or integrated by parts with an antiderivative (the weak form).
    fn general_velocity(&self) -> bool {
        self.params.form().terms().is_some_and(|list| {
            list.terms()
                .iter()
                .any(|t| t.velocity != hb_model::VelocityFactor::One)
        })
    }

    /// The largest `Σ |∂g/∂x|` of the residual's basis terms over the record.
    fn slope(&self) -> f64 {
        (0..self.record.len())
            .map(|n| self.residual_terms(n, None).2)
            .fold(0.0, f64::max)
    }
}

/// The Fourier coefficients of the residual over each block's segment by a naive DFT: the mean,
/// then `(2/L) Σ r_n cos(2π j n / L)`, `(2/L) Σ r_n sin(2π j n / L)` for `j = 1..M`, with `n`
/// counted from the segment's first sample (local time, as in eq. 15).
fn residual_fourier(case: &Case, system: &hb_solve::LinearSystem) -> Vec<f64> {
    let mut want = Vec::with_capacity(system.rows());
    for block in system.blocks() {
        let (s, l) = (block.segment.start(), block.segment.len());
        let r: Vec<f64> = (0..l).map(|n| case.residual(s + n)).collect();
        want.push(r.iter().sum::<f64>() / l as f64);
        for j in 1..=block.harmonics {
            let (mut c, mut d) = (0.0, 0.0);
            for (n, &rn) in r.iter().enumerate() {
                let (sin, cos) = (TAU * ((j * n) % l) as f64 / l as f64).sin_cos();
                c += rn * cos;
                d += rn * sin;
            }
            want.push(2.0 * c / l as f64);
            want.push(2.0 * d / l as f64);
        }
    }
    want
}

/// The trapezoid integrals `∫ ψ r` over each block's window for the weak form's test functions
/// `ψ = w(τ)`, `w(τ) cos(jΩτ)`, `w(τ) sin(jΩτ)` (`j = 1..M`), `w = sin^p(π τ / T_s)`,
/// `Ω = 2π / T_s`, `τ` the time from the window's first sample, `T_s = L h`.
fn residual_weak(case: &Case, system: &hb_solve::LinearSystem, p: i32) -> Vec<f64> {
    residual_weak_with(case, system, p, false)
}

/// [`residual_weak`], with the nonlinear functions of `x'` at the weak form's estimate of the
/// velocity (`estimated`: [`hb_solve::velocity_series`] of the window's closed form, with the
/// params' velocity harmonics and [`hb_solve::VelocityTrend::Quintic`]).
fn residual_weak_with(case: &Case, system: &hb_solve::LinearSystem, p: i32, estimated: bool) -> Vec<f64> {
    let h = case.clock().step();
    let mut want = Vec::with_capacity(system.rows());
    for block in system.blocks() {
        let (s, l, k) = (block.segment.start(), block.segment.len(), block.segment.period());
        let velocity = estimated.then(|| {
            let x: Vec<f64> = (0..=l).map(|n| case.signal.x(case.clock().time(s + n))).collect();
            let harmonics = case.params.velocity_harmonics().count(k, l);
            hb_solve::velocity_series(&x, h, k, harmonics, hb_solve::VelocityTrend::Quintic).unwrap()
        });
        let terms: Vec<(f64, f64)> = (0..=l)
            .map(|n| {
                let weight = if n == 0 || n == l { 0.5 * h } else { h };
                let window = (PI * n as f64 / l as f64).sin().powi(p);
                let r = match &velocity {
                    Some(v) => case.residual_at_velocity(s + n, v[n]),
                    None => case.residual(s + n),
                };
                (weight * window, r)
            })
            .collect();
        want.push(terms.iter().map(|(w, r)| w * r).sum());
        for j in 1..=block.harmonics {
            let (mut c, mut d) = (0.0, 0.0);
            for (n, &(w, r)) in terms.iter().enumerate() {
                let (sin, cos) = (TAU * ((j * n) % l) as f64 / l as f64).sin_cos();
                c += w * cos * r;
                d += w * sin * r;
            }
            want.push(c);
            want.push(d);
        }
    }
    want
}

/// `δ` times the norm of the map from the samples to a row of harmonic balance over `block`:
/// `(jΩ)² u_j`, `c (jΩ) v_j` and the coefficients of the basis terms move by at most twice the
/// change of the samples times `(MΩ)²`, `|c| MΩ` and `Σ|∂g/∂x|`.
///
/// A list of terms with functions of `x'` evaluates them at the velocity of the orbit's series up
/// to `J` harmonics, which moves by at most `2δ (Ω J (J + 1) + 1 / (L h))`.
fn harmonic_allowance(case: &Case, block: &hb_solve::Block, delta: f64, slope: f64) -> f64 {
    let omega = block.segment.fundamental(case.clock());
    let m_omega = block.harmonics as f64 * omega;
    let velocity = if case.general_velocity() {
        let j = case
            .params
            .velocity_harmonics()
            .count(block.segment.period(), block.segment.len()) as f64;
        2.0 * (omega * j * (j + 1.0) + 1.0 / block.segment.duration(case.clock()))
    } else {
        m_omega
    };
    2.0 * delta * (m_omega * m_omega + case.velocity_slope() * velocity + slope)
}

/// `δ` times the norm of the map from the samples to a row of the weak form of order `p` over
/// `block`: `∫|ψ''|`, `|c| ∫|ψ'|` and `Σ|∂g/∂x| ∫|ψ|`, with `|ψ| <= 1`, `|ψ'| <= p a + MΩ`,
/// `|ψ''| <= (p a + MΩ)²` (`a = π / T_s`, `Ω = 2π / T_s`).
///
/// A list of terms integrates `D(t) f(x) x'` by parts, `−∫ (ψ D)' F(x)`, and evaluates the other
/// functions of `x'` at the velocity of the window's series (see [`harmonic_allowance`]).
fn weak_allowance(case: &Case, block: &hb_solve::Block, p: u32, delta: f64, slope: f64) -> f64 {
    let span = block.segment.duration(case.clock());
    let rate = f64::from(p) * PI / span + block.harmonics as f64 * TAU / span;
    let velocity = if case.general_velocity() {
        let omega = block.segment.fundamental(case.clock());
        let j = case
            .params
            .velocity_harmonics()
            .count(block.segment.period(), block.segment.len()) as f64;
        rate + 3.0 * case.clock().drive_angular_frequency() + 2.0 * (omega * j * (j + 1.0) + 1.0 / span)
    } else {
        rate
    };
    delta * span * (rate * rate + case.velocity_slope() * velocity + slope)
}

/// `δ` times the norm of the map from the samples to a row of the differences: the stencils'
/// `64/12h²` (`x''`) and `18/12h` (`x'`, times `|c|`), and `Σ|∂g/∂x|`.
fn difference_allowance(case: &Case, delta: f64, slope: f64) -> f64 {
    let h = case.clock().step();
    delta * (64.0 / (12.0 * h * h) + case.velocity_slope() * 18.0 / (12.0 * h) + slope)
}

/// The truncation error of the fourth-order differences on the signal: for a sinusoid with
/// `ω h <= 1` at most `h⁴ ω⁵ / 30` in `x'` and `h⁴ ω⁶ / 90` in `x''` (alternating series).
fn truncation(case: &Case) -> f64 {
    let h = case.clock().step();
    case.velocity_slope() * h.powi(4) / 30.0 * case.signal.derivative_bound(5)
        + h.powi(4) / 90.0 * case.signal.derivative_bound(6)
}

/// Window order of the weak-form identity, on records of twice the drawn samples per period (48
/// to 80): the two sides are trapezoid sums of the same integral, the method's after moving the
/// derivatives onto `ψ` by parts, and the rule's errors on their integrands (which vanish with
/// their first `p − 1` derivatives at both ends) are then far below the rounding allowed.
const IDENTITY_WINDOW: u32 = 16;

proptest! {
    #![proptest_config(ProptestConfig { cases: 32, rng_seed: RngSeed::Fixed(0x1de7_1717), ..ProptestConfig::default() })]

    /// Harmonic balance on orbits of an exactly periodic, band-limited record (harmonics of
    /// `W / k` below the Nyquist frequency, any winding): row for row, `A λ − β` equals the
    /// Fourier coefficients of the residual by a naive DFT.
    #[test]
    fn harmonic_rows_are_the_fourier_coefficients_of_the_residual(d in draw()) {
        // sign(x') is averaged over each sample's cell (tested on its own below).
        let d = map_velocity(&d, |v| if v == 2 { 3 } else { v });
        let case = Case::new(&d, true);
        let (system, got, scale) = case.rows(&hb_solve::HarmonicBalance);
        let want = residual_fourier(&case, &system);
        let (delta, slope) = (case.sample_error(), case.slope());
        prop_assert_eq!(got.len(), want.len());
        for block in system.blocks() {
            let tolerance = 1e-12 * scale + harmonic_allowance(&case, block, delta, slope);
            for r in block.first_row..block.first_row + block.rows {
                prop_assert!((got[r] - want[r]).abs() <= tolerance,
                    "row {}: {} vs {} (tolerance {})", r, got[r], want[r], tolerance);
            }
        }
    }

    /// The weak form on windows of a record that need not repeat (any frequencies, any rotation
    /// rate): row for row, `A λ − β` equals the trapezoid integral of the residual against the
    /// row's test function.
    #[test]
    fn weak_rows_are_the_test_integrals_of_the_residual(d in draw()) {
        // Functions of x' other than x' itself come from a window's series, exact only on a
        // periodic record (below); x' times anything is integrated by parts exactly.
        let d = smooth_by_parts(&map_velocity(&d, |v| v.min(1)));
        let d = Draw { samples_per_period: 2 * d.samples_per_period, ..d };
        let case = Case::new(&d, false);
        let weak = hb_solve::WeakForm::new(IDENTITY_WINDOW).unwrap();
        let (system, got, scale) = case.rows(&weak);
        let want = residual_weak(&case, &system, IDENTITY_WINDOW as i32);
        let (delta, slope) = (case.sample_error(), case.slope());
        prop_assert_eq!(got.len(), want.len());
        for block in system.blocks() {
            let tolerance = 1e-12 * scale + weak_allowance(&case, block, IDENTITY_WINDOW, delta, slope);
            for r in block.first_row..block.first_row + block.rows {
                prop_assert!((got[r] - want[r]).abs() <= tolerance,
                    "row {}: {} vs {} (tolerance {})", r, got[r], want[r], tolerance);
            }
        }
    }

    /// The weak form on windows of a record that need not repeat, with any terms: row for row,
    /// `A λ − β` equals the trapezoid integral of the residual against the row's test function
    /// with the nonlinear functions of `x'` at the velocity of the window's series
    /// ([`hb_solve::velocity_series`]).
    #[test]
    fn weak_rows_with_the_window_velocity(d in draw()) {
        // sign(x') is averaged over each sample's cell (tested on its own below).
        let d = smooth_by_parts(&map_velocity(&d, |v| if v == 2 { 3 } else { v }));
        let d = Draw { samples_per_period: 2 * d.samples_per_period, ..d };
        let case = Case::new(&d, false);
        let weak = hb_solve::WeakForm::new(IDENTITY_WINDOW).unwrap();
        let (system, got, scale) = case.rows(&weak);
        let want = residual_weak_with(&case, &system, IDENTITY_WINDOW as i32, true);
        let (delta, slope) = (case.sample_error(), case.slope());
        for block in system.blocks() {
            let tolerance = 1e-12 * scale + weak_allowance(&case, block, IDENTITY_WINDOW, delta, slope);
            for r in block.first_row..block.first_row + block.rows {
                prop_assert!((got[r] - want[r]).abs() <= tolerance,
                    "row {}: {} vs {} (tolerance {})", r, got[r], want[r], tolerance);
            }
        }
    }

    /// Finite differences on a record that need not repeat: the row of sample `n` is the residual
    /// at `t_n` up to the truncation error of the fourth-order differences ([`truncation`], of
    /// order `h⁴`).
    #[test]
    fn difference_rows_are_the_residual_up_to_h4(d in draw()) {
        // sign(x') jumps where x' crosses zero, and the differences' x' is off by O(h⁴): the other
        // functions of x' are smooth.
        let d = map_velocity(&d, |v| if v == 2 { 3 } else { v });
        let case = Case::new(&d, false);
        let (system, got, scale) = case.rows(&hb_solve::FiniteDifferences);
        let h = case.clock().step();
        let w_max = case.signal.waves.iter().map(|w| w.1).fold(0.0, f64::max);
        prop_assert!(w_max * h <= 1.0);
        let tolerance = truncation(&case)
            + 1e-12 * scale
            + difference_allowance(&case, case.sample_error(), case.slope());
        for block in system.blocks() {
            prop_assert_eq!(block.rows, block.segment.len());
            for r in 0..block.rows {
                let n = block.segment.start() + r;
                let (g, w) = (got[block.first_row + r], case.residual(n));
                prop_assert!((g - w).abs() <= tolerance,
                    "sample {}: {} vs {} (tolerance {})", n, g, w, tolerance);
            }
        }
    }
}

/// The record of an exact solution and the true coefficients of its equation, with the
/// identity's windows, harmonics and segments: on the line (`whirl` false)
/// `x = a cos(W t + φ)`, which solves `x'' + c x' + k x + F_c cos(W t) + F_s sin(W t) = 0` for
/// `F_c = (W² − k) A − c W B`, `F_s = (W² − k) B + c W A` (`A = a cos φ`, `B = −a sin φ`), on the
/// polynomial basis (higher powers 0) with the forcing identified or known; on the circle
/// (`whirl` true) the uniform whirl `x = W t + φ`, which solves the harmonic-basis (K = 1) model
/// with identified forcing when `sin(t)*sin(x)` = `n_cc`, `cos(t)*sin(x)` = `−p_sc`,
/// `c = (p_sc sin φ − n_cc cos φ) / W`, `F_c = −(q_c cos φ + q_s sin φ)` and
/// `F_s = q_c sin φ − q_s cos φ` for any `n_cc` (`cos(t)*cos(x)`), `p_sc` (`sin(t)*cos(x)`),
/// `q_c`, `q_s`: the products of the drive and the whirl balance in the mean and the second
/// harmonic, the autonomous terms against the forcing in the first.
fn exact_case(d: &Draw, whirl: bool, known: bool) -> Case {
    // The whirl on twice the samples, as the weak-form identity (its `∫ψ' x` is a trapezoid sum
    // of a non-periodic integrand).
    let samples_per_period = if whirl { 2 } else { 1 } * d.samples_per_period;
    let clock = SampleClock::new(d.forcing_period, samples_per_period)
        .unwrap()
        .with_start_time(d.start_time)
        .unwrap();
    let big_w = clock.drive_angular_frequency();
    let len = 6 * 3 * samples_per_period + 1;
    let origin = clock.time(len / 2);
    let l = &d.lambda;
    let segments: Vec<(f64, usize)> = d
        .segments
        .iter()
        .enumerate()
        .map(|(i, &(at, _))| (at, 1 + i % 3))
        .collect();
    let params = |form| {
        IdentifyParams::builder(clock)
            .harmonics(Harmonics::Fixed(d.harmonics))
            .form(form)
            .build()
            .unwrap()
    };
    if whirl {
        let basis = BasisKind::from(Harmonic::new(1).unwrap());
        let offset = d.offset * PI;
        // x = W (t − t_mid) + offset = W t + φ.
        let phi = offset - big_w * origin;
        let (s, c) = phi.sin_cos();
        let (n_cc, p_sc, q_c, q_s) = (l[0], l[1], l[2], l[3]);
        let lambda = vec![
            (p_sc * s - n_cc * c) / big_w,
            n_cc,
            p_sc,
            q_c,
            -p_sc,
            n_cc,
            q_s,
            -(q_c * c + q_s * s),
            q_c * s - q_s * c,
        ];
        let form = ModelForm::parametric().with_forcing(Forcing::Identified);
        assert_eq!(
            hb_model::term_names(&basis, &form),
            [
                "x'",
                "cos(t)*cos(x)",
                "sin(t)*cos(x)",
                "cos(x)",
                "cos(t)*sin(x)",
                "sin(t)*sin(x)",
                "sin(x)",
                "cos(t)",
                "sin(t)"
            ]
        );
        let signal = Signal {
            offset,
            rate: big_w,
            origin,
            waves: Vec::new(),
        };
        Case::from_parts(basis, params(form), signal, len, &segments, lambda)
    } else {
        let basis = match d.basis {
            BasisKind::Polynomial(p) => BasisKind::from(p),
            _ => BasisKind::from(Polynomial::new(1 + d.period % 3).unwrap()),
        };
        let (_, a, phase) = d.waves[0];
        let (big_a, big_b) = (a * phase.cos(), -a * phase.sin());
        let (c, k) = (l[0] * big_w, l[1] * big_w * big_w);
        let f_c = (big_w * big_w - k) * big_a - c * big_w * big_b;
        let f_s = (big_w * big_w - k) * big_b + c * big_w * big_a;
        let forcing = if known {
            Forcing::Known { cos: f_c, sin: f_s }
        } else {
            Forcing::Identified
        };
        let form = ModelForm::externally_forced(forcing);
        let lambda = hb_model::term_names(&basis, &form)
            .iter()
            .map(|name| match name.as_str() {
                "x'" => c,
                "x" => k,
                "cos(t)" => f_c,
                "sin(t)" => f_s,
                _ => 0.0,
            })
            .collect();
        let signal = Signal {
            offset: 0.0,
            rate: 0.0,
            origin,
            waves: vec![(a, big_w, phase)],
        };
        Case::from_parts(basis, params(form), signal, len, &segments, lambda)
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 32, rng_seed: RngSeed::Fixed(0x0e8a_c7ed), ..ProptestConfig::default() })]

    /// A record of an exact solution ([`exact_case`]) satisfies every method's system with the
    /// true coefficients: `|(A λ − β)_r|` is at most `1e-12` of the size of the terms plus the
    /// samples' rounding through the method (harmonic balance; the weak form with an even window
    /// order `p = 2..8` on windows of whole forcing periods, where every integrand on the line is a
    /// trigonometric polynomial of degree below `L` and the trapezoid rule is exact, and `p = 16`
    /// for the whirl, whose `∫ψ' x` is not periodic, on 48 to 80 samples per period), and the
    /// differences' `h⁴` truncation (zero
    /// for the whirl, which they differentiate exactly).
    #[test]
    fn an_exact_solution_satisfies_every_system(d in draw(), whirl in any::<bool>(), known in any::<bool>(), order in 1u32..=4) {
        let case = exact_case(&d, whirl, known);
        let (delta, slope) = (case.sample_error(), case.slope());
        let (_, _, scale) = case.rows(&hb_solve::HarmonicBalance);
        // The residual is zero up to rounding.
        for n in 0..case.record.len() {
            prop_assert!(case.residual(n).abs() <= 1e-12 * scale, "residual {} at {}", case.residual(n), n);
        }
        let p = if whirl { IDENTITY_WINDOW } else { 2 * order };
        let weak = hb_solve::WeakForm::new(p).unwrap();
        let methods: [&dyn hb_solve::Assembly; 3] = [&hb_solve::HarmonicBalance, &weak, &hb_solve::FiniteDifferences];
        for method in methods {
            let (system, got, scale) = case.rows(method);
            for block in system.blocks() {
                let tolerance = 1e-12 * scale + match method.name() {
                    "upo" => harmonic_allowance(&case, block, delta, slope),
                    "windowed" => weak_allowance(&case, block, p, delta, slope),
                    _ => truncation(&case) + difference_allowance(&case, delta, slope),
                };
                let rows = &got[block.first_row..block.first_row + block.rows];
                for (i, g) in rows.iter().enumerate() {
                    prop_assert!(g.abs() <= tolerance,
                        "{} p {}: row {} of A λ − β is {} (tolerance {})", method.name(), p, block.first_row + i, g, tolerance);
                }
            }
        }
    }
}
