//! Deserialising a validated type runs its validation: an invalid value is rejected, a valid one
//! round-trips.
use pendulum_sim::{
    CheckConfig, CoupledDuffing, Domain, DoublePendulum, DriveHarmonic, DriveHarmonics, Duffing, Losses,
    LyapunovConfig, MultiConfig, MultiState, Pendulum, ShootingConfig, SimulationConfig, Sinusoid,
    Tolerances, Torque, TorqueDoublePendulum,
};
use serde::Serialize;
use serde::de::DeserializeOwned;
use serde_json::{Value, json};

/// `value` survives a JSON round trip unchanged.
fn round_trips<T: Serialize + DeserializeOwned + PartialEq + std::fmt::Debug>(value: &T) {
    let text = serde_json::to_string(value).unwrap();
    let back: T = serde_json::from_str(&text).unwrap();
    assert_eq!(&back, value, "{text}");
}

/// The JSON of `value` with the field at `path` (object keys, outermost first) replaced by `new`
/// is rejected, and the message says why.
fn rejects<T: Serialize + DeserializeOwned + std::fmt::Debug>(
    value: &T,
    path: &[&str],
    new: Value,
    why: &str,
) {
    let mut json = serde_json::to_value(value).unwrap();
    let mut field = &mut json;
    for key in path {
        field = field
            .get_mut(*key)
            .unwrap_or_else(|| panic!("no field {key} in {path:?}"));
    }
    *field = new;
    let err = serde_json::from_value::<T>(json.clone()).expect_err(&format!("accepted {json}"));
    assert!(err.to_string().contains(why), "{err}");
}

#[test]
fn pendulum() {
    let p = Pendulum::new(1.2, -0.1, 0.9).unwrap();
    round_trips(&p);
    round_trips(&Pendulum::paper());
    // The cached 1/r² is not part of the serialised form, so it cannot contradict r.
    assert_eq!(
        serde_json::to_value(p).unwrap(),
        json!({"f": 1.2, "c": -0.1, "r": 0.9})
    );
    let stale: Pendulum =
        serde_json::from_value(json!({"f": 1.2, "c": -0.1, "r": 0.9, "inv_r2": 5.0})).unwrap();
    assert_eq!(stale, p);
    rejects(&p, &["r"], json!(0.0), "invalid r");
}

#[test]
fn tolerances() {
    let t = Tolerances::new(1e-9, 0.0).unwrap();
    round_trips(&t);
    rejects(&t, &["rtol"], json!(0.0), "invalid rtol");
    rejects(&t, &["rtol"], json!(1.0), "invalid rtol");
    rejects(&t, &["atol"], json!(-1e-12), "invalid atol");
}

#[test]
fn simulation_config() {
    let c = SimulationConfig::paper()
        .with_samples(100)
        .unwrap()
        .with_phase(0.25)
        .unwrap()
        .with_initial(0.3, -0.2)
        .unwrap();
    round_trips(&c);
    rejects(&c, &["samples"], json!(0), "invalid samples");
    rejects(
        &c,
        &["samples_per_period"],
        json!(0),
        "invalid samples per period",
    );
    rejects(&c, &["forcing_period"], json!(-1.0), "invalid forcing period");
    rejects(&c, &["phase"], json!(1.0), "invalid phase");
    rejects(&c, &["tolerances", "rtol"], json!(2.0), "invalid rtol");
    // A non-whole sample step round-trips and is checked; a config without the field (written
    // before steps existed) reads as the whole grid.
    let stepped = c.clone().with_sample_step(0.002).unwrap();
    round_trips(&stepped);
    rejects(&stepped, &["sample_step"], json!(-0.002), "invalid sample step");
    rejects(&stepped, &["sample_step"], json!(0.0), "invalid sample step");
    let mut old = serde_json::to_value(&c).unwrap();
    old.as_object_mut().unwrap().remove("sample_step");
    assert_eq!(serde_json::from_value::<SimulationConfig>(old).unwrap(), c);
}

#[test]
fn duffing() {
    let d = Duffing::new(0.15, -1.0, 1.0, 0.3).unwrap();
    round_trips(&d);
    assert_eq!(
        serde_json::to_value(d).unwrap(),
        json!({"c": 0.15, "a": -1.0, "b": 1.0, "f": 0.3})
    );
}

/// A rig's losses and drive harmonics.
fn rig() -> (Losses, DriveHarmonics) {
    let losses = Losses::none()
        .with_friction(0.05)
        .unwrap()
        .with_drag(0.01)
        .unwrap()
        .with_cubic_damping(0.002)
        .unwrap();
    let harmonics = DriveHarmonics::new(&[
        DriveHarmonic::new(3, 0.05, -1.0).unwrap(),
        DriveHarmonic::new(2, 0.1, 0.5).unwrap(),
    ])
    .unwrap();
    (losses, harmonics)
}

#[test]
fn rig_options() {
    let (losses, harmonics) = rig();
    round_trips(&losses);
    round_trips(&harmonics);
    assert_eq!(
        serde_json::to_value(losses).unwrap(),
        json!({"friction": 0.05, "drag": 0.01, "cubic_damping": 0.002})
    );
    // Listed by increasing harmonic, the phase optional.
    assert_eq!(
        serde_json::to_value(harmonics).unwrap(),
        json!([{"k": 2, "ratio": 0.1, "phase": 0.5}, {"k": 3, "ratio": 0.05, "phase": -1.0}])
    );
    let no_phase: DriveHarmonics = serde_json::from_value(json!([{"k": 4, "ratio": 0.2}])).unwrap();
    assert_eq!(no_phase.iter().next().unwrap().phase(), 0.0);
    rejects(&losses, &["friction"], json!(-0.1), "invalid friction");
    rejects(&losses, &["drag"], json!(-1.0), "invalid drag");
    rejects(&losses, &["cubic_damping"], json!(-1e-3), "invalid cubic damping");
    for (bad, why) in [
        (json!([{"k": 1, "ratio": 0.1}]), "invalid drive harmonic"),
        (json!([{"k": 17, "ratio": 0.1}]), "invalid drive harmonic"),
        (json!([{"k": 2, "ratio": -0.1}]), "invalid drive harmonic ratio"),
        (
            json!([{"k": 2, "ratio": 0.1}, {"k": 2, "ratio": 0.2}]),
            "more than once",
        ),
    ] {
        let err = serde_json::from_value::<DriveHarmonics>(bad.clone()).expect_err(&bad.to_string());
        assert!(err.to_string().contains(why), "{err}");
    }
    // A system with options round-trips and checks them; without, its form is unchanged.
    let p = Pendulum::paper()
        .with_losses(losses)
        .with_drive_harmonics(harmonics);
    round_trips(&p);
    rejects(&p, &["losses", "friction"], json!(-1.0), "invalid friction");
    let d = Duffing::two_well()
        .with_losses(losses)
        .with_drive_harmonics(harmonics);
    round_trips(&d);
    rejects(&d, &["losses", "drag"], json!(-0.5), "invalid drag");
    assert_eq!(
        serde_json::to_value(Pendulum::paper().with_losses(Losses::none())).unwrap(),
        json!({"f": 1.52, "c": 0.03, "r": 0.8333})
    );
}

#[test]
fn lyapunov_config() {
    let c = LyapunovConfig::default().with_periods(50).unwrap();
    round_trips(&c);
    rejects(&c, &["periods"], json!(0), "invalid periods");
    rejects(&c, &["forcing_period"], json!(0.0), "invalid forcing period");
}

#[test]
fn shooting_config() {
    let grid = ShootingConfig::default()
        .with_periods(2)
        .unwrap()
        .with_seeds(3, 4, (-1.0, 1.0), (-2.0, 2.0))
        .unwrap()
        .with_space(Domain::Line);
    round_trips(&grid);
    let points = ShootingConfig::default()
        .with_seed_points(vec![[0.1, 0.2], [-0.3, 0.4]])
        .unwrap();
    round_trips(&points);
    rejects(&grid, &["periods"], json!(0), "invalid periods");
    rejects(&grid, &["forcing_period"], json!(0.0), "invalid forcing period");
    rejects(&grid, &["phase"], json!(-0.5), "invalid phase");
    rejects(
        &grid,
        &["newton_tolerance"],
        json!(0.0),
        "invalid newton tolerance",
    );
    rejects(&grid, &["max_iterations"], json!(0), "invalid max iterations");
    rejects(&grid, &["seeds", "Grid", "nx"], json!(0), "invalid seeds");
    rejects(
        &grid,
        &["seeds", "Grid", "x_range"],
        json!([1.0, -1.0]),
        "invalid seed range",
    );
    rejects(&points, &["seeds", "Points"], json!([]), "invalid seeds");
}

#[test]
fn check_config() {
    let c = CheckConfig::new(2.0, Domain::Circle, 40, 30)
        .unwrap()
        .with_initial(0.5, 0.1)
        .unwrap()
        .with_max_seeds(8)
        .unwrap();
    round_trips(&c);
    rejects(&c, &["max_seeds"], json!(0), "invalid seeds");
    rejects(&c, &["section", "samples"], json!(0), "invalid samples");
    rejects(&c, &["lyapunov", "periods"], json!(0), "invalid periods");
    rejects(&c, &["shooting", "periods"], json!(0), "invalid periods");
    // Each part valid, but not the same system: the constructor never builds that.
    rejects(
        &c,
        &["shooting", "forcing_period"],
        json!(3.0),
        "must be the same",
    );
    rejects(
        &c,
        &["lyapunov", "initial"],
        json!([0.0, 0.0]),
        "must be the same",
    );
}

#[test]
fn systems_of_several_coordinates() {
    let p = DoublePendulum::new(0.3, 0.7, 0.8, 0.9, 0.04, -0.01).unwrap();
    round_trips(&p);
    assert_eq!(
        serde_json::to_value(p).unwrap(),
        json!({"mu": 0.3, "lambda": 0.7, "omega2": 0.8, "f": 0.9, "c1": 0.04, "c2": -0.01})
    );
    rejects(&p, &["mu"], json!(1.5), "invalid mu");
    rejects(&p, &["lambda"], json!(0.0), "invalid lambda");

    let arm = TorqueDoublePendulum::dfki().with_torques(
        Torque::Sinusoids(vec![
            Sinusoid::new(0.4, 10.0, 0.0).unwrap(),
            Sinusoid::new(0.1, 3.0, 1.0).unwrap(),
        ]),
        Torque::None,
    );
    round_trips(&arm);
    // The published file's names, the torques beside them.
    let value = serde_json::to_value(&arm).unwrap();
    assert_eq!(value["I1"], json!(0.053470810264216295));
    assert_eq!(value["torque2"], json!("none"));
    assert_eq!(value["torque1"]["sinusoids"][1]["phase"], json!(1.0));
    // Without torques they default to none.
    let mut bare = value.clone();
    bare.as_object_mut().unwrap().remove("torque1");
    bare.as_object_mut().unwrap().remove("torque2");
    assert_eq!(
        serde_json::from_value::<TorqueDoublePendulum>(bare).unwrap(),
        TorqueDoublePendulum::dfki()
    );
    rejects(&arm, &["I2"], json!(0.001), "invalid I2");
    rejects(&arm, &["gr"], json!(-6.0), "invalid gr");
    rejects(&arm, &["cf1"], json!(-0.1), "invalid cf1");
    // A measured torque is the caller's: written as such, read back missing (NaN), never zero.
    let measured = arm
        .clone()
        .with_torques(Torque::None, Torque::measured(|t| t.cos()));
    let back: TorqueDoublePendulum =
        serde_json::from_str(&serde_json::to_string(&measured).unwrap()).unwrap();
    assert!(matches!(&back.torques()[1], Torque::Measured(m) if m.is_missing()));
    assert!(back.torques()[1].at(0.0).is_nan());

    let duffing = CoupledDuffing::two_wells().with_mass_ratio(1.5).unwrap();
    round_trips(&duffing);
    rejects(&duffing, &["mass_ratio"], json!(0.0), "invalid mass ratio");
    rejects(
        &duffing,
        &["drive", "synthetic", "band"],
        json!([3.0, 1.0]),
        "invalid noise band",
    );
    rejects(
        &duffing,
        &["drive", "synthetic", "noise_rms"],
        json!(-1.0),
        "invalid noise rms",
    );
}

#[test]
fn multi_config() {
    let state = MultiState::new(&[2.0, 0.0], &[0.0, -0.5]).unwrap();
    round_trips(&state);
    assert_eq!(
        serde_json::to_value(&state).unwrap(),
        json!({"q": [2.0, 0.0], "v": [0.0, -0.5]})
    );
    rejects(&state, &["v"], json!([0.0]), "invalid velocities");
    rejects(&state, &["q"], json!([]), "invalid coordinates");
    let c = MultiConfig::new(state)
        .with_samples(100)
        .unwrap()
        .with_samples_per_period(64)
        .unwrap()
        .with_phase(0.25)
        .unwrap();
    round_trips(&c);
    let stepped = c.clone().with_sample_step(0.002).unwrap();
    round_trips(&stepped);
    rejects(&c, &["samples"], json!(0), "invalid samples");
    rejects(&c, &["phase"], json!(1.0), "invalid phase");
    rejects(&stepped, &["sample_step"], json!(0.0), "invalid sample step");
    rejects(&c, &["initial", "q"], json!([1.0]), "invalid velocities");
}
