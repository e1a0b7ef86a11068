//! Terms over several coordinates in the weak form: manufactured motions of two angles whose
//! equation holds exactly for a measured drive made from them, so that every coefficient is
//! known in closed form, and the refusals of what a record does not give.
use circle_signal::{SampleClock, Segment, wrap};
use hb_basis::{BasisKind, Domain, Harmonic, Polynomial};
use hb_model::{IdentifiedModel, ModelForm, Names, TermList};
use hb_solve::{AssemblyError, IdentifyParams, QrSolver, Signals, SolveError, WeakForm, identify};
use upo_search::{OrbitSource, Windows};

/// Two angles that whirl and swing: `q_i = w_i t + a_i sin(b_i t + c_i)`, with their first two
/// derivatives.
fn angles(t: f64) -> ([f64; 2], [f64; 2], [f64; 2]) {
    let parts = [(0.35, 0.8, 1.3, 0.2), (-0.6, 1.1, 0.7 * 2.0_f64.sqrt(), 1.0)];
    let mut q = [0.0; 2];
    let mut v = [0.0; 2];
    let mut a = [0.0; 2];
    for (i, &(w, amp, b, c)) in parts.iter().enumerate() {
        q[i] = w * t + amp * (b * t + c).sin();
        v[i] = w + amp * b * (b * t + c).cos();
        a[i] = -amp * b * b * (b * t + c).sin();
    }
    (q, v, a)
}

/// Windows of the default length over the record.
fn windows(clock: &SampleClock, x: &[f64]) -> Vec<Segment> {
    Windows::builder(clock)
        .domain(Domain::Circle)
        .build()
        .unwrap()
        .segments(x)
        .unwrap()
}

/// The first equation of a two-angle system fitted by the weak form from the wrapped angles and
/// the drive `p = q1'' + Σ c g` the motion needs: every coefficient, the drive's −1 among them.
fn fit_first(terms: &str, truth: &[f64]) -> IdentifiedModel {
    let clock = SampleClock::new(std::f64::consts::TAU, 64).unwrap();
    let n = 64 * 60;
    let names = Names::new(["theta1", "theta2"], ["tau1"]).unwrap();
    let list = TermList::parse_in(&format!("{terms}, tau1"), &names, 0).unwrap();
    let (mut q1, mut q2, mut p) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..n {
        let t = clock.time(i);
        let (q, v, a) = angles(t);
        q1.push(wrap(q[0]));
        q2.push(wrap(q[1]));
        let d = q[0] - q[1];
        // Every term the tests name, at this instant.
        let value = |name: &str| match name {
            "theta2''*cos(theta1-theta2)" => a[1] * d.cos(),
            "theta2''" => a[1],
            "theta1''*cos(theta2)" => a[0] * q[1].cos(),
            "sin(theta1-theta2)*theta2'^2" => d.sin() * v[1] * v[1],
            "sin(theta1)" => q[0].sin(),
            "cos(theta2)" => q[1].cos(),
            "theta1'" => v[0],
            "theta2'" => v[1],
            "sin(theta2)*theta1'*theta2'" => q[1].sin() * v[0] * v[1],
            other => panic!("no value for {other}"),
        };
        let rest: f64 = list.names()[..truth.len()]
            .iter()
            .zip(truth)
            .map(|(name, c)| c * value(name))
            .sum();
        // q1'' + Σ c g − p = 0.
        p.push(a[0] + rest);
    }
    let segments = windows(&clock, &q1);
    let params = IdentifyParams::builder(clock)
        .form(ModelForm::from_terms(list))
        .harmonics(WeakForm::DEFAULT_HARMONICS)
        .build()
        .unwrap();
    let signals = Signals::system(vec![(&q1[..], Domain::Circle), (&q2[..], Domain::Circle)], 0)
        .unwrap()
        .with_drives(vec![&p[..]])
        .unwrap();
    identify(
        BasisKind::from(Harmonic::new(1).unwrap()),
        signals,
        &segments,
        &params,
        &WeakForm::default(),
        &QrSolver::default(),
    )
    .unwrap()
}

/// The inertial coupling of a double pendulum's first equation: the other acceleration times the
/// cosine of the difference (by parts with the velocities), the other velocity squared times
/// the sine, gravity and damping.
#[test]
fn the_inertial_coupling_of_two_angles_comes_back() {
    let truth = [0.45, 0.45, 1.3, 0.07];
    let model = fit_first(
        "theta2''*cos(theta1-theta2), sin(theta1-theta2)*theta2'^2, sin(theta1), theta1'",
        &truth,
    );
    let names = [
        "theta2''*cos(theta1-theta2)",
        "sin(theta1-theta2)*theta2'^2",
        "sin(theta1)",
        "theta1'",
        "tau1",
    ];
    for (name, want) in names.iter().zip(truth.iter().chain(&[-1.0])) {
        let got = model.coefficient(name).unwrap().value;
        assert!((got - want).abs() < 1e-8, "{name}: {got} vs {want}");
    }
}

/// Another acceleration alone (twice by parts, no velocity), and the own acceleration times a
/// function of the other angle (a mass that depends on the state), with a Coriolis product.
#[test]
fn accelerations_alone_and_a_state_dependent_mass_come_back() {
    let truth = [0.3, -0.25, 0.6, 0.9, 0.05];
    let model = fit_first(
        "theta2'', theta1''*cos(theta2), sin(theta2)*theta1'*theta2', sin(theta1), theta2'",
        &truth,
    );
    for (name, want) in [
        ("theta2''", 0.3),
        ("theta1''*cos(theta2)", -0.25),
        ("sin(theta2)*theta1'*theta2'", 0.6),
        ("sin(theta1)", 0.9),
        ("theta2'", 0.05),
        ("tau1", -1.0),
    ] {
        let got = model.coefficient(name).unwrap().value;
        assert!((got - want).abs() < 1e-8, "{name}: {got} vs {want}");
    }
}

#[test]
fn a_term_in_a_coordinate_the_record_lacks_is_refused() {
    let clock = SampleClock::new(2.0, 32).unwrap();
    let x: Vec<f64> = (0..32 * 40).map(|i| (0.9 * clock.time(i)).sin()).collect();
    let names = Names::new(["x1", "x2"], Vec::<String>::new()).unwrap();
    let list = TermList::parse_in("x1', x1, x2", &names, 0).unwrap();
    let params = IdentifyParams::builder(clock)
        .form(ModelForm::from_terms(list))
        .build()
        .unwrap();
    let segments = Windows::builder(&clock)
        .domain(Domain::Line)
        .build()
        .unwrap()
        .segments(&x)
        .unwrap();
    let run = |signals: Signals<'_>| {
        identify(
            BasisKind::from(Polynomial::new(1).unwrap()),
            signals,
            &segments,
            &params,
            &WeakForm::default(),
            &QrSolver::default(),
        )
    };
    assert!(matches!(
        run(Signals::one(&x)),
        Err(SolveError::Assembly(AssemblyError::MissingCoordinate {
            coordinate: 1,
            ..
        }))
    ));
    let mut broken = x.clone();
    broken[200] = f64::NAN;
    let signals = Signals::system(vec![(&x[..], Domain::Line), (&broken[..], Domain::Line)], 0).unwrap();
    assert!(matches!(
        run(signals),
        Err(SolveError::Assembly(AssemblyError::NonFiniteCoordinateSample {
            coordinate: 1,
            index: 200,
            ..
        }))
    ));
    let short = &x[..100];
    assert!(matches!(
        Signals::system(vec![(&x[..], Domain::Line), (short, Domain::Line)], 0),
        Err(SolveError::Assembly(AssemblyError::CoordinateLengthMismatch {
            coordinate: 1,
            ..
        }))
    ));
    // The record's domain and the basis' must agree.
    let signals = Signals::system(vec![(&x[..], Domain::Circle), (&x[..], Domain::Line)], 0).unwrap();
    assert!(matches!(
        run(signals),
        Err(SolveError::Assembly(AssemblyError::DomainMismatch { .. }))
    ));
}

/// The paper's rows of terms in other coordinates on an exactly periodic orbit of two angles
/// (one of them whirling) are the Fourier coefficients of the terms, the acceleration's taken by
/// parts: each column against the coefficients of the term's closed form, summed on a grid 64
/// times finer.
#[test]
fn harmonic_balance_columns_of_coupled_terms_are_their_fourier_coefficients() {
    use hb_model::Harmonics;
    let p = 64;
    let clock = SampleClock::nondimensional(p).unwrap();
    // One drive period: q1 swings, q2 whirls once.
    let motion = |t: f64| {
        let q = [
            0.3 * t.sin() + 0.2 * (2.0 * t + 0.4).cos(),
            t + 0.4 * (t + 0.3).sin(),
        ];
        let v = [
            0.3 * t.cos() - 0.4 * (2.0 * t + 0.4).sin(),
            1.0 + 0.4 * (t + 0.3).cos(),
        ];
        let a = [
            -0.3 * t.sin() - 0.8 * (2.0 * t + 0.4).cos(),
            -0.4 * (t + 0.3).sin(),
        ];
        (q, v, a)
    };
    let terms = [
        "q2''*cos(q1-q2)",
        "sin(q1-q2)*q2'^2",
        "sin(q2)*q1'*q2'",
        "q1''*cos(q2)",
    ];
    let value = |name: &str, t: f64| {
        let (q, v, a) = motion(t);
        match name {
            "q2''*cos(q1-q2)" => a[1] * (q[0] - q[1]).cos(),
            "sin(q1-q2)*q2'^2" => (q[0] - q[1]).sin() * v[1] * v[1],
            "sin(q2)*q1'*q2'" => q[1].sin() * v[0] * v[1],
            "q1''*cos(q2)" => a[0] * q[1].cos(),
            other => panic!("{other}"),
        }
    };
    let names = Names::new(["q1", "q2"], Vec::<String>::new()).unwrap();
    let (q1, q2): (Vec<f64>, Vec<f64>) = (0..=p)
        .map(|n| {
            let (q, _, _) = motion(clock.time(n));
            (wrap(q[0]), wrap(q[1]))
        })
        .unzip();
    let segment = Segment::new(0, 1, &clock, 0.0, q1.len()).unwrap();
    let m = 6;
    let params = IdentifyParams::builder(clock)
        .form(ModelForm::from_terms(
            TermList::parse_in(&terms.join(", "), &names, 0).unwrap(),
        ))
        .harmonics(Harmonics::Fixed(m))
        .velocity_harmonics(IdentifyParams::SYSTEM_VELOCITY_HARMONICS)
        .build()
        .unwrap();
    let signals = Signals::system(vec![(&q1[..], Domain::Circle), (&q2[..], Domain::Circle)], 0).unwrap();
    let system = hb_solve::assemble(&Harmonic::new(1).unwrap(), signals, &[segment], &params).unwrap();
    let fine = 64 * p;
    for (c, name) in terms.iter().enumerate() {
        for j in 0..=m {
            let (mut a, mut b) = (0.0, 0.0);
            for n in 0..fine {
                let t = std::f64::consts::TAU * n as f64 / fine as f64;
                let g = value(name, t);
                a += 2.0 * g * (j as f64 * t).cos() / fine as f64;
                b += 2.0 * g * (j as f64 * t).sin() / fine as f64;
            }
            let rows = if j == 0 {
                vec![(0, a / 2.0)]
            } else {
                vec![(2 * j - 1, a), (2 * j, b)]
            };
            for (row, want) in rows {
                let got = system.matrix()[(row, c)];
                assert!(
                    (got - want).abs() < 1e-9,
                    "{name}, harmonic {j}, row {row}: {got} vs {want}"
                );
            }
        }
    }
}
