//! The true equation of the simulated systems in the model's terms: in their own frame, in a
//! record's frame, with a rig's losses and drive harmonics, and satisfied by records in seconds.

use hb_model::ModelError;
use pendulum_sim::TrueEquation;
use pendulum_sim::{
    DriveHarmonic, DriveHarmonics, Duffing, InFrame, Losses, Pendulum, RecordFrame, SecondOrderSystem,
    SimulationConfig, Tolerances, simulate,
};

/// The equation's terms by name, as the tests below read them.
trait Named {
    fn coefficients(&self, frame: &RecordFrame) -> Result<Vec<(String, f64)>, ModelError>;
}

impl<S: TrueEquation> Named for S {
    fn coefficients(&self, frame: &RecordFrame) -> Result<Vec<(String, f64)>, ModelError> {
        Ok(self.equation(frame)?.named())
    }
}

/// The value of a named term at `(t, x, v)` of the record: `t` in a name is the drive's phase
/// `rate · t`. An independent reading of the names, term by term.
fn term(name: &str, wt: f64, x: f64, v: f64) -> f64 {
    // `cos(kt)` or `sin(kt)` as (is it a cosine, k).
    let drive = |f: &str| -> Option<(bool, f64)> {
        let (cos, rest) = match (f.strip_prefix("cos("), f.strip_prefix("sin(")) {
            (Some(rest), _) => (true, rest),
            (_, Some(rest)) => (false, rest),
            _ => return None,
        };
        let k = rest.strip_suffix("t)")?;
        let k = if k.is_empty() { 1.0 } else { k.parse().ok()? };
        Some((cos, k))
    };
    let factor = |f: &str| match f {
        "x'" => v,
        "|x'|" => v.abs(),
        "x'^3" => v * v * v,
        "sign(x')" => {
            if v > 0.0 {
                1.0
            } else if v < 0.0 {
                -1.0
            } else {
                0.0
            }
        }
        "x" => x,
        "x^2" => x * x,
        "x^3" => x * x * x,
        "sin(x)" => x.sin(),
        "cos(x)" => x.cos(),
        other => match drive(other) {
            Some((true, k)) => (k * wt).cos(),
            Some((false, k)) => (k * wt).sin(),
            None => panic!("unknown factor {other}"),
        },
    };
    name.split('*').map(factor).product()
}

/// `−Σ c_i g_i`: the acceleration the coefficients give.
fn from_terms(terms: &[(String, f64)], rate: f64, t: f64, x: f64, v: f64) -> f64 {
    -terms
        .iter()
        .map(|(n, c)| c * term(n, rate * t, x, v))
        .sum::<f64>()
}

fn frames() -> Vec<RecordFrame> {
    let base = RecordFrame::nondimensional();
    vec![
        base,
        base.with_drive_frequency(1.02).unwrap(),
        base.with_drive_frequency(6.5).unwrap().with_phase(2.3).unwrap(),
        base.with_rate(0.4)
            .unwrap()
            .with_phase(-1.1)
            .unwrap()
            .with_offset(0.7)
            .unwrap(),
    ]
}

/// In its own frame the pendulum's coefficients are `c`, `−f` and `1/r²`, bit for bit.
#[test]
fn own_frame_is_the_equation_as_written() {
    let p = Pendulum::paper();
    let got = p.coefficients(&RecordFrame::nondimensional()).unwrap();
    let want = [
        ("x'", 0.03),
        ("cos(t)*cos(x)", 0.0),
        ("sin(t)*cos(x)", -1.52),
        ("cos(x)", 0.0),
        ("cos(t)*sin(x)", 0.0),
        ("sin(t)*sin(x)", 0.0),
        ("sin(x)", 1.0 / (0.8333 * 0.8333)),
    ];
    let got: Vec<(&str, f64)> = got.iter().map(|(n, v)| (n.as_str(), *v)).collect();
    assert_eq!(got, want);
    assert!(got.iter().all(|(_, v)| v.is_sign_positive() || *v != 0.0));
    let d = Duffing::two_well()
        .coefficients(&RecordFrame::nondimensional())
        .unwrap();
    let d: Vec<(&str, f64)> = d.iter().map(|(n, v)| (n.as_str(), *v)).collect();
    assert_eq!(
        d,
        [
            ("x'", 0.25),
            ("x", -1.0),
            ("x^3", 1.0),
            ("cos(t)", -0.3),
            ("sin(t)", 0.0)
        ]
    );
}

/// A rig's losses and drive harmonics.
fn rig_extras() -> (Losses, DriveHarmonics) {
    let losses = Losses::none()
        .with_friction(0.04)
        .unwrap()
        .with_drag(0.02)
        .unwrap()
        .with_cubic_damping(0.003)
        .unwrap();
    let harmonics = DriveHarmonics::new(&[
        DriveHarmonic::new(2, 0.1, 0.7).unwrap(),
        DriveHarmonic::new(3, 0.05, -2.0).unwrap(),
    ])
    .unwrap();
    (losses, harmonics)
}

/// The coefficients, read term by term, give the acceleration of the system in the frame,
/// with and without a rig's losses and drive harmonics.
#[test]
fn coefficients_are_the_framed_equation() {
    let (losses, harmonics) = rig_extras();
    for (pendulum, duffing) in [
        (
            Pendulum::new(1.3, 0.07, 0.9).unwrap(),
            Duffing::new(0.15, -1.2, 0.8, 0.4).unwrap(),
        ),
        (
            Pendulum::new(1.3, 0.07, 0.9)
                .unwrap()
                .with_losses(losses)
                .with_drive_harmonics(harmonics),
            Duffing::new(0.15, -1.2, 0.8, 0.4)
                .unwrap()
                .with_losses(losses)
                .with_drive_harmonics(harmonics),
        ),
    ] {
        framed_equation(pendulum, duffing);
    }
}

fn framed_equation(pendulum: Pendulum, duffing: Duffing) {
    for frame in frames() {
        let rate = frame.rate();
        let p_terms = pendulum.coefficients(&frame).unwrap();
        let framed = InFrame::new(pendulum, frame);
        let d_terms = (frame.offset() == 0.0).then(|| duffing.coefficients(&frame).unwrap());
        let framed_d = InFrame::new(duffing, frame);
        for i in 0..100 {
            let i = f64::from(i);
            let (t, x, v) = (0.013 * i - 0.4, -3.0 + 0.061 * i, rate * (0.7 * i).sin());
            let want = framed.acceleration(t, x, v);
            let got = from_terms(&p_terms, rate, t, x, v);
            assert!(
                (got - want).abs() <= 1e-12 * (1.0 + want.abs()),
                "{frame:?}: {got} vs {want}"
            );
            if let Some(d_terms) = &d_terms {
                let want = framed_d.acceleration(t, x, v);
                let got = from_terms(d_terms, rate, t, x, v);
                assert!(
                    (got - want).abs() <= 1e-12 * (1.0 + want.abs()),
                    "{frame:?}: {got} vs {want}"
                );
            }
        }
    }
    let shifted = RecordFrame::nondimensional().with_offset(0.1).unwrap();
    assert!(duffing.coefficients(&shifted).is_err());
}

/// The new terms by name, in seconds with no offset: friction scales with `W²`, drag not at
/// all, cubic damping with `1/W`, and the `k`-th harmonic's phase at `t = 0` is `k φ + φ_k`.
#[test]
fn rig_terms_in_seconds() {
    let (losses, harmonics) = rig_extras();
    let frame = RecordFrame::nondimensional()
        .with_drive_frequency(1.02)
        .unwrap()
        .with_phase(0.4)
        .unwrap();
    let w = frame.rate();
    let pendulum = Pendulum::paper()
        .with_losses(losses)
        .with_drive_harmonics(harmonics);
    let got = pendulum.coefficients(&frame).unwrap();
    let value = |name: &str| {
        got.iter()
            .find(|(n, _)| n == name)
            .unwrap_or_else(|| panic!("no {name} in {got:?}"))
            .1
    };
    assert_eq!(got.len(), 7 + 3 + 8);
    assert!((value("sign(x')") - 0.04 * w * w).abs() < 1e-14 * w * w);
    assert_eq!(value("x'*|x'|"), 0.02);
    assert!((value("x'^3") - 0.003 / w).abs() < 1e-18);
    let drive2 = -1.52 * 0.1 * w * w;
    let psi2: f64 = 2.0 * 0.4 + 0.7;
    assert!((value("cos(2t)*cos(x)") - drive2 * psi2.sin()).abs() < 1e-12);
    assert!((value("sin(2t)*cos(x)") - drive2 * psi2.cos()).abs() < 1e-12);
    // No offset: the harmonics have no `sin(x)` parts.
    assert_eq!(value("cos(2t)*sin(x)"), 0.0);
    assert_eq!(value("sin(3t)*sin(x)"), 0.0);
    let duffing = Duffing::two_well()
        .with_losses(losses)
        .with_drive_harmonics(harmonics);
    let got = duffing.coefficients(&frame).unwrap();
    let value = |name: &str| got.iter().find(|(n, _)| n == name).unwrap().1;
    let drive3 = -0.3 * 0.05 * w * w;
    let psi3: f64 = 3.0 * 0.4 - 2.0;
    assert!((value("cos(3t)") - drive3 * psi3.cos()).abs() < 1e-12);
    assert!((value("sin(3t)") + drive3 * psi3.sin()).abs() < 1e-12);
    // Zero losses and harmonics of zero amplitude add no terms.
    let bare = Pendulum::paper()
        .with_losses(Losses::none().with_drag(0.0).unwrap())
        .with_drive_harmonics(DriveHarmonics::new(&[DriveHarmonic::new(2, 0.0, 1.0).unwrap()]).unwrap());
    assert_eq!(
        bare.coefficients(&frame).unwrap(),
        Pendulum::paper().coefficients(&frame).unwrap()
    );
}

/// A record simulated in seconds satisfies the scaled equation: the acceleration from central
/// differences of the written velocity, plus the terms at the sample, is zero to the
/// differences' accuracy; and it is the non-dimensional simulation at `τ = rate · t`.
#[test]
fn a_record_in_seconds_satisfies_the_scaled_equation() {
    let hz = 1.02;
    let frame = RecordFrame::nondimensional().with_drive_frequency(hz).unwrap();
    let rate = frame.rate();
    let tol = Tolerances::relative(1e-12).unwrap();
    let fs = 500.0;
    let config = SimulationConfig::paper()
        .with_drive_period(1.0 / hz)
        .unwrap()
        .with_sample_step(1.0 / fs)
        .unwrap()
        .with_transient_periods(3)
        .with_samples(2000)
        .unwrap()
        .with_tolerances(tol);
    let pendulum = Pendulum::paper();
    let record = simulate(&InFrame::new(pendulum, frame), &config).unwrap();
    let terms = pendulum.coefficients(&frame).unwrap();
    let h = 1.0 / fs;
    let mut worst: f64 = 0.0;
    let mut scale: f64 = 0.0;
    let v = &record.omega;
    for n in 2..record.len() - 2 {
        // The fourth-order central difference of the velocity.
        let acc = (v[n - 2] - 8.0 * v[n - 1] + 8.0 * v[n + 1] - v[n + 2]) / (12.0 * h);
        let residual = acc - from_terms(&terms, rate, record.t[n], record.theta[n], v[n]);
        worst = worst.max(residual.abs());
        scale = scale.max(acc.abs());
    }
    // The difference errs by h^4 x^(6) / 30 (a whirling pendulum sampled at 500 Hz).
    assert!(worst < 1e-6 * scale, "residual {worst:e} of {scale:e}");
    // The same motion as the non-dimensional pendulum sampled at τ = rate · t.
    let nd = SimulationConfig::paper()
        .with_sample_step(rate * h)
        .unwrap()
        .with_transient_periods(3)
        .with_samples(2000)
        .unwrap()
        .with_tolerances(tol);
    let tau = simulate(&pendulum, &nd).unwrap();
    for n in (0..2000).step_by(97) {
        assert!((tau.t[n] - rate * record.t[n]).abs() < 1e-9);
        assert!((tau.theta[n] - record.theta[n]).abs() < 1e-7, "sample {n}");
        assert!((rate * tau.omega[n] - record.omega[n]).abs() < 1e-6, "sample {n}");
    }
}

/// A rig's record in seconds, with every loss and two drive harmonics, satisfies the
/// equation its true coefficients write, at every sample whose neighbours lie on one side of
/// `x' = 0` (the acceleration jumps by `2 μ W²` there, which no difference resolves).
#[test]
fn a_rig_record_in_seconds_satisfies_its_true_equation() {
    let (losses, harmonics) = rig_extras();
    let hz = 1.02;
    let frame = RecordFrame::nondimensional().with_drive_frequency(hz).unwrap();
    let rate = frame.rate();
    let fs = 500.0;
    let config = SimulationConfig::paper()
        .with_drive_period(1.0 / hz)
        .unwrap()
        .with_sample_step(1.0 / fs)
        .unwrap()
        .with_transient_periods(3)
        .with_samples(3000)
        .unwrap()
        .with_tolerances(Tolerances::relative(1e-12).unwrap());
    for (rig, terms) in [
        {
            let p = Pendulum::paper()
                .with_losses(losses)
                .with_drive_harmonics(harmonics);
            (
                simulate(&InFrame::new(p, frame), &config).unwrap(),
                p.coefficients(&frame).unwrap(),
            )
        },
        {
            let d = Duffing::two_well()
                .with_losses(losses)
                .with_drive_harmonics(harmonics);
            (
                simulate(&InFrame::new(d, frame), &config).unwrap(),
                d.coefficients(&frame).unwrap(),
            )
        },
    ] {
        let h = 1.0 / fs;
        let v = &rig.omega;
        let (mut worst, mut scale, mut checked): (f64, f64, usize) = (0.0, 0.0, 0);
        for n in 2..rig.len() - 2 {
            let one_side =
                v[n - 2..=n + 2].iter().all(|&w| w > 0.0) || v[n - 2..=n + 2].iter().all(|&w| w < 0.0);
            if !one_side {
                continue;
            }
            let acc = (v[n - 2] - 8.0 * v[n - 1] + 8.0 * v[n + 1] - v[n + 2]) / (12.0 * h);
            let residual = acc - from_terms(&terms, rate, rig.t[n], rig.theta[n], v[n]);
            worst = worst.max(residual.abs());
            scale = scale.max(acc.abs());
            checked += 1;
        }
        assert!(checked > 2900, "{checked} samples checked");
        assert!(worst < 1e-6 * scale, "residual {worst:e} of {scale:e}");
    }
}

// ---------------------------------------------------------------------------------------------
// Systems of several coordinates.

mod systems {
    use hb_basis::{BasisKind, Domain, Harmonic, Polynomial};
    use hb_model::{IdentifiedModel, IdentifiedSystem, MeasuredDrive, ModelForm, Names};
    use pendulum_sim::truth::{Equation, system_equations};
    use pendulum_sim::{
        ArmParameters, BaseAcceleration, CoupledDuffing, DoublePendulum, InFrame, MultiSystem, RecordFrame,
        Torque, TorqueDoublePendulum,
    };

    /// The truth as a system of the identification's models, the measured drives constant at
    /// `drives`: evaluated by the identification's own code, independently of how it was written.
    fn as_system(
        truth: &[Equation],
        names: &Names,
        domain: Domain,
        w: f64,
        drives: &[f64],
    ) -> IdentifiedSystem {
        let equations = truth
            .iter()
            .map(|e| {
                let basis = e.terms().smallest_basis().unwrap().unwrap_or(match domain {
                    Domain::Circle => BasisKind::from(Harmonic::new(1).unwrap()),
                    Domain::Line => BasisKind::from(Polynomial::new(1).unwrap()),
                });
                IdentifiedModel::new(basis, ModelForm::from_terms(e.terms().clone()), w, e.values()).unwrap()
            })
            .collect();
        let system =
            IdentifiedSystem::new(names.clone(), vec![domain; names.coordinates().len()], equations).unwrap();
        if drives.is_empty() {
            return system;
        }
        let measured = drives
            .iter()
            .map(|&d| MeasuredDrive::new(vec![d; 16], -100.0, 100.0).unwrap())
            .collect();
        system.with_measured_drives(measured).unwrap()
    }

    /// Largest difference of the accelerations of the truth and of the simulator in `frame`, over
    /// states spread over the circle (or the line) and a range of times, relative to their size.
    fn worst(truth: &IdentifiedSystem, system: &dyn MultiSystem, frame: RecordFrame) -> f64 {
        let in_frame = InFrame::new(system, frame);
        let mut worst: f64 = 0.0;
        for i in 0..200 {
            let x = i as f64;
            let t = 0.37 * x;
            let q = [(1.3 * x).sin() * 3.0, (0.7 * x + 1.0).cos() * 3.0];
            let v = [2.0 * (0.9 * x).cos() + 0.1, -1.5 * (1.1 * x).sin() - 0.2];
            let (mut a, mut b) = ([0.0; 2], [0.0; 2]);
            truth.accelerations(t, &q, &v, None, &mut a).unwrap();
            in_frame.accelerations(t, &q, &v, &mut b).unwrap();
            for c in 0..2 {
                worst = worst.max((a[c] - b[c]).abs() / (1.0 + b[c].abs()));
            }
        }
        worst
    }

    #[test]
    fn in_the_simulators_frame_the_terms_are_the_simulators() {
        let pendulum = DoublePendulum::whirling();
        let names = Names::new(["theta1", "theta2"], Vec::<String>::new()).unwrap();
        let truth = system_equations(
            &pendulum.normalised_equations(),
            &names,
            &RecordFrame::nondimensional(),
        )
        .unwrap();
        for (equation, own) in truth.iter().zip(pendulum.normalised_equations()) {
            let renamed: Vec<(String, f64)> = own
                .terms
                .iter()
                .map(|(n, v)| (n.replace("q1", "theta1").replace("q2", "theta2"), *v))
                .collect();
            assert_eq!(equation.named(), renamed);
        }
        // The arm's measured torques keep their place and coefficient.
        let arm = TorqueDoublePendulum::dfki();
        let names = Names::new(["q1", "q2"], ["tau1", "tau2"]).unwrap();
        let truth = system_equations(
            &arm.normalised_equations(),
            &names,
            &RecordFrame::nondimensional(),
        )
        .unwrap();
        for (equation, own) in truth.iter().zip(arm.normalised_equations()) {
            let own: Vec<(String, f64)> = own.terms.iter().map(|(n, v)| (n.to_string(), *v)).collect();
            assert_eq!(equation.named(), own);
        }
    }

    /// `(x1-x2)^3`, which the grammar does not write, is written out by the binomial theorem and
    /// summed with the cubic stiffness of the own coordinate.
    #[test]
    fn a_power_of_a_difference_is_written_out() {
        let d = CoupledDuffing::two_wells().with_mass_ratio(2.0).unwrap();
        let (b, k3, rho) = (d.b(), d.k3(), d.mass_ratio());
        let names = Names::new(["x1", "x2"], ["a"]).unwrap();
        let truth =
            system_equations(&d.normalised_equations(), &names, &RecordFrame::nondimensional()).unwrap();
        let value = |e: usize, name: &str| truth[e].value(name).unwrap_or_else(|| panic!("{name}"));
        assert_eq!(value(0, "x1^3"), b[0] + k3);
        assert_eq!(value(0, "x1^2*x2"), -3.0 * k3);
        assert_eq!(value(0, "x1*x2^2"), 3.0 * k3);
        assert_eq!(value(0, "x2^3"), -k3);
        assert_eq!(value(0, "a"), 1.0);
        assert_eq!(value(1, "x2^3"), b[1] + k3 / rho);
        assert_eq!(value(1, "x1^3"), -k3 / rho);
        assert_eq!(value(1, "x1^2*x2"), 3.0 * k3 / rho);
        assert_eq!(value(1, "x1*x2^2"), -3.0 * k3 / rho);
        assert_eq!(truth[0].terms().len(), 8);
    }

    /// In a record's frame (seconds, a drive phase at `t = 0`, an encoder's zero off the bottom)
    /// the truth accelerates as the simulator does in that frame: the rate, the phase and the
    /// offset are read into every term, combinations of angles and the elbow's relative angle
    /// included.
    #[test]
    fn in_a_records_frame_the_truth_accelerates_as_the_simulator() {
        let frame = RecordFrame::nondimensional()
            .with_drive_frequency(1.3)
            .unwrap()
            .with_phase(0.7)
            .unwrap()
            .with_offset(0.4)
            .unwrap();
        let w = frame.rate();
        let pendulum = DoublePendulum::new(0.3, 0.8, 0.9, 0.7, 0.04, 0.06).unwrap();
        let names = Names::new(["theta1", "theta2"], Vec::<String>::new()).unwrap();
        let truth = system_equations(&pendulum.normalised_equations(), &names, &frame).unwrap();
        // The offset and phase split sin and cos into both parts.
        assert!(truth[0].value("cos(theta1)").is_some() && truth[0].value("cos(t)*sin(theta1)").is_some());
        let e = worst(
            &as_system(&truth, &names, Domain::Circle, w, &[]),
            &pendulum,
            frame,
        );
        assert!(e < 1e-11, "double pendulum: {e:e}");

        // The arm in seconds (rate 1) with both encoders' zero off; constant torques, so that
        // the measured drives are exact at any time.
        let frame = RecordFrame::nondimensional().with_offset(-0.3).unwrap();
        let arm = TorqueDoublePendulum::new(ArmParameters::DFKI_A0)
            .unwrap()
            .with_torques(
                Torque::sinusoid(0.3, 0.0, std::f64::consts::FRAC_PI_2).unwrap(),
                Torque::sinusoid(-0.2, 0.0, std::f64::consts::FRAC_PI_2).unwrap(),
            );
        let names = Names::new(["q1", "q2"], ["tau1", "tau2"]).unwrap();
        let truth = system_equations(&arm.normalised_equations(), &names, &frame).unwrap();
        assert!(truth[0].value("q1''*sin(q2)").is_some(), "{:?}", truth[0].named());
        let e = worst(
            &as_system(&truth, &names, Domain::Circle, 1.0, &[0.3, -0.2]),
            &arm,
            frame,
        );
        assert!(e < 1e-11, "arm: {e:e}");

        // The coupled oscillators in seconds: the base's acceleration as the record writes it,
        // rate² times the system's.
        let frame = RecordFrame::nondimensional().with_drive_frequency(0.6).unwrap();
        let w = frame.rate();
        let coupled = CoupledDuffing::two_wells()
            .with_mass_ratio(1.5)
            .unwrap()
            .with_drive(BaseAcceleration::measured(|_| 0.25));
        let names = Names::new(["x1", "x2"], ["a"]).unwrap();
        let truth = system_equations(&coupled.normalised_equations(), &names, &frame).unwrap();
        let e = worst(
            &as_system(&truth, &names, Domain::Line, w, &[w * w * 0.25]),
            &coupled,
            frame,
        );
        assert!(e < 1e-11, "coupled oscillators: {e:e}");
    }

    #[test]
    fn a_shifted_position_on_the_line_and_mismatched_names_are_refused() {
        let coupled = CoupledDuffing::two_wells();
        let names = Names::new(["x1", "x2"], ["a"]).unwrap();
        let shifted = RecordFrame::nondimensional().with_offset(0.1).unwrap();
        let e = system_equations(&coupled.normalised_equations(), &names, &shifted).unwrap_err();
        assert!(e.to_string().contains("zero offset"), "{e}");
        let no_drive = Names::new(["x1", "x2"], Vec::<String>::new()).unwrap();
        let e = system_equations(
            &coupled.normalised_equations(),
            &no_drive,
            &RecordFrame::nondimensional(),
        )
        .unwrap_err();
        assert!(e.to_string().contains("names each"), "{e}");
    }
}
