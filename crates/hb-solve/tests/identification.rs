//! Identification checks: manufactured systems with exact answers, the least-squares solvers as
//! identities, errors, and the paper's data set.
use std::f64::consts::{PI, TAU};

use circle_signal::wrap;
use faer::{Col, Mat};
use hb_basis::{Basis, BasisKind, Harmonic, Hat, Polynomial};
use hb_solve::{
    Forcing, Harmonics, IdentifiedModel, IdentifyParams, LstsqSolver, ModelForm, QrSolver, SampleClock,
    SolveError, SvdSolver, assemble, identify, identify_from_source,
};
use pendulum_sim::{Pendulum, SecondOrderSystem};
use proptest::prelude::*;
use upo_search::{CloseReturns, Metric, Segment};

// ---------------------------------------------------------------------------------------------
// Helpers

/// One classical Runge-Kutta step of x'' = f(t, x, v).
mod common;
use common::{TRUTH, read_paper_dataset};

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
    let search = CloseReturns::builder(25, 5)
        .tolerance(0.03)
        .max_period(16)
        .dimension(2)
        .metric(Metric::Circle)
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
    let w = clock.forcing_frequency();
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
        Segment {
            start: 13,
            period: 1,
            len: 40,
            error: 0.0,
        },
        Segment {
            start: 3,
            period: 2,
            len: 80,
            error: 0.0,
        },
    ];
    let form = ModelForm::externally_forced(Forcing::Known { cos: -amp, sin: 0.0 });
    let params = IdentifyParams::builder(clock).form(form).build().unwrap();
    for solver in [&QrSolver::default() as &dyn LstsqSolver, &SvdSolver::default()] {
        let m = identify(Polynomial::new(1).unwrap(), &x, &segments, &params, solver).unwrap();
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
        let w = clock.forcing_frequency();
        let want = -c * v - k * xx + amp * (w * t).cos();
        assert!((m.acceleration(t, xx, v) - want).abs() <= 1e-8 * k);
    }
}

#[test]
fn linear_oscillator_with_unknown_forcing_is_rank_deficient() {
    // One sinusoidal orbit balances only harmonic 1: two equations for c, k, F_c, F_s.
    let (clock, x, _) = linear_oscillator();
    let segments = [Segment {
        start: 13,
        period: 1,
        len: 40,
        error: 0.0,
    }];
    let params = IdentifyParams::builder(clock)
        .form(ModelForm::externally_forced(Forcing::Identified))
        .build()
        .unwrap();
    for solver in [&QrSolver::default() as &dyn LstsqSolver, &SvdSolver::default()] {
        match identify(Polynomial::new(1).unwrap(), &x, &segments, &params, solver) {
            Err(SolveError::RankDeficient { rank, unknowns, .. }) => {
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
        &QrSolver::default(),
    ) {
        Err(SolveError::RankDeficient {
            rank: 2,
            unknowns: 3,
            suspect,
            ..
        }) => {
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
        Segment {
            start: 21,
            period: 1,
            len: p,
            error: 0.0,
        },
        Segment {
            start: 5,
            period: 2,
            len: 2 * p,
            error: 0.0,
        },
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
        Segment {
            start: 17,
            period: 2,
            len: 2 * p,
            error: 0.0,
        },
        Segment {
            start: b_start + 29,
            period: 3,
            len: 3 * p,
            error: 0.0,
        },
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
            .harmonics(Harmonics::ForcingCap(8.0))
            .build()
            .unwrap();
        for solver in [&QrSolver::default() as &dyn LstsqSolver, &SvdSolver::default()] {
            let system = assemble(&Harmonic::new(1).unwrap(), &record, &segments, &params).unwrap();
            let windings: Vec<i64> = system.blocks().iter().map(|b| b.winding).collect();
            assert_eq!(windings, [-2, 3]);
            let m = identify(Harmonic::new(1).unwrap(), &record, &segments, &params, solver).unwrap();
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
    let clock = common::paper_clock(t0);
    let params = IdentifyParams::builder(clock)
        .harmonics(Harmonics::Fixed(3))
        .build()
        .unwrap();
    let one = [Segment {
        start: 0,
        period: 1,
        len: 25,
        error: 0.0,
    }];
    // Harmonic K = 3: 1 + 3·6 = 19 unknowns; a period-1 orbit gives 7 equations; 20 are needed.
    let err = identify(Harmonic::new(3).unwrap(), &x, &one, &params, &QrSolver::default()).unwrap_err();
    assert!(
        matches!(err, SolveError::TooFewOrbits { found: 1, needed: 3 }),
        "{err:?}"
    );
    let msg = err.to_string();
    assert!(
        msg.contains("1 segment") && msg.contains("at least 3") && msg.contains("tolerance"),
        "{msg}"
    );
    let err = identify(Harmonic::new(1).unwrap(), &x, &[], &params, &QrSolver::default()).unwrap_err();
    assert!(
        matches!(err, SolveError::TooFewOrbits { found: 0, needed: 2 }),
        "{err:?}"
    );
}

#[test]
fn bad_input_never_reaches_the_solver() {
    let (t0, mut x) = read_paper_dataset();
    let clock = common::paper_clock(t0);
    let params = IdentifyParams::builder(clock).build().unwrap();
    let segs: Vec<Segment> = (0..4)
        .map(|i| Segment {
            start: 100 * i,
            period: 1,
            len: 25,
            error: 0.0,
        })
        .collect();
    x[310] = f64::NAN;
    let err = identify(
        Harmonic::new(1).unwrap(),
        &x,
        &segs,
        &params,
        &QrSolver::default(),
    )
    .unwrap_err();
    assert!(
        matches!(
            err,
            SolveError::NonFiniteSample {
                segment: 3,
                index: 310,
                ..
            }
        ),
        "{err:?}"
    );
    x[310] = 0.0;
    let bad = [Segment {
        start: 0,
        period: 2,
        len: 25,
        error: 0.0,
    }];
    assert!(matches!(
        identify(Harmonic::new(1).unwrap(), &x, &bad, &params, &QrSolver::default()),
        Err(SolveError::BadSegment { segment: 0, .. })
    ));
    let past_end = [Segment {
        start: x.len() - 25,
        period: 1,
        len: 25,
        error: 0.0,
    }];
    assert!(matches!(
        identify(
            Harmonic::new(1).unwrap(),
            &x,
            &past_end,
            &params,
            &QrSolver::default()
        ),
        Err(SolveError::BadSegment { .. })
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
            &QrSolver::default()
        ),
        Err(SolveError::TermNotAllowed { term: "k*x", .. })
    ));
    // A monomial that overflows is caught with its segment.
    let huge: Vec<f64> = (0..200).map(|n| 1e120 * (n as f64 * 0.3).sin()).collect();
    let params = IdentifyParams::builder(clock)
        .form(ModelForm::externally_forced(Forcing::None))
        .build()
        .unwrap();
    let segs = [
        Segment {
            start: 0,
            period: 1,
            len: 25,
            error: 0.0,
        },
        Segment {
            start: 50,
            period: 1,
            len: 25,
            error: 0.0,
        },
    ];
    assert!(matches!(
        identify(Polynomial::new(3).unwrap(), &huge, &segs, &params, &QrSolver::default()),
        Err(SolveError::NonFiniteTerm { segment: 0, ref term, .. }) if term == "x^3"
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
    let clock = common::paper_clock(t0);
    let params = IdentifyParams::builder(clock).build().unwrap();
    let basis: BasisKind = Harmonic::new(1).unwrap().into();
    let m = identify(basis, &x, &segs, &params, &QrSolver::default()).unwrap();
    for (name, want) in TRUTH {
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
    let search = CloseReturns::builder(25, 5)
        .tolerance(0.03)
        .max_period(16)
        .dimension(2)
        .build()
        .unwrap();
    let m2 = identify_from_source(basis, &x, &search, &params, &SvdSolver::default()).unwrap();
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
    let clock = common::paper_clock(t0);
    let params = IdentifyParams::builder(clock).build().unwrap();
    let hat = Hat::new(8).unwrap();
    let m = identify(hat, &x, &segs, &params, &QrSolver::default()).unwrap();
    assert!((m.damping() - 0.03).abs() < 0.003, "c_r = {}", m.damping());
    let q_ref = hat
        .project(PROJECTION_POINTS, |x| 1.0 / (0.8333f64 * 0.8333) * x.sin())
        .unwrap();
    let p_ref = hat.project(PROJECTION_POINTS, |x| -1.52 * x.cos()).unwrap();
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
    let clock = common::paper_clock(t0);
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
        assert_eq!(ba.rows(), bb.rows());
        for r in 0..ba.rows() {
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
