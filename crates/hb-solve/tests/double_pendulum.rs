//! The base-excited double pendulum of `pendulum-sim`, whirling, sampled at 64 per drive period
//! and wrapped as encoders give it: each equation's physical terms by the weak form, against the
//! truth the simulator writes ([`DoublePendulum::normalised_equations`]).
use circle_signal::{Domain, SampleClock, wrap};
use hb_basis::{BasisKind, Harmonic};
use hb_model::{ModelForm, Names, TermList};
use hb_solve::{IdentifyParams, QrSolver, Signals, WeakForm, identify};
use pendulum_sim::multi::{self, MultiConfig, MultiState};
use pendulum_sim::{DoublePendulum, SimulationConfig, Tolerances};
use upo_search::{OrbitSource, Windows};

/// The whirling double pendulum: `periods` drive periods at `p` samples each after 100 periods
/// of transient, from rest at `θ = (2, 0)`; the wrapped angles.
fn record(p: usize, periods: usize) -> (SampleClock, Vec<f64>, Vec<f64>) {
    let system = DoublePendulum::whirling();
    let sampling = SimulationConfig::paper()
        .with_samples_per_period(p)
        .unwrap()
        .with_samples(p * periods)
        .unwrap()
        .with_transient_periods(100)
        .with_tolerances(Tolerances::new(1e-12, 1e-13).unwrap());
    let config = MultiConfig::from_sampling(sampling, MultiState::at_rest(&[2.0, 0.0]).unwrap());
    let run = multi::simulate(&system, &config).unwrap();
    let clock = SampleClock::nondimensional(p)
        .unwrap()
        .with_start_time(run.t[0])
        .unwrap();
    let wrapped = |q: &[f64]| q.iter().map(|&x| wrap(x)).collect::<Vec<f64>>();
    (clock, wrapped(&run.q[0]), wrapped(&run.q[1]))
}

#[test]
fn every_coefficient_of_the_whirling_double_pendulum_comes_back_by_the_weak_form() {
    let (clock, q1, q2) = record(64, 400);
    let names = Names::new(["q1", "q2"], Vec::<String>::new()).unwrap();
    let segments = Windows::builder(&clock)
        .domain(Domain::Circle)
        .build()
        .unwrap()
        .segments(&q1)
        .unwrap();
    let mut worst: f64 = 0.0;
    for (own, truth) in DoublePendulum::whirling()
        .normalised_equations()
        .iter()
        .enumerate()
    {
        let spec: Vec<&str> = truth.terms.iter().map(|(name, _)| name.as_ref()).collect();
        let list = TermList::parse_in(&spec.join(", "), &names, own).unwrap();
        let params = IdentifyParams::builder(clock)
            .form(ModelForm::from_terms(list))
            .harmonics(WeakForm::DEFAULT_HARMONICS)
            .velocity_harmonics(IdentifyParams::SYSTEM_VELOCITY_HARMONICS)
            .build()
            .unwrap();
        let signals =
            Signals::system(vec![(&q1[..], Domain::Circle), (&q2[..], Domain::Circle)], own).unwrap();
        let model = identify(
            BasisKind::from(Harmonic::new(1).unwrap()),
            signals,
            &segments,
            &params,
            &WeakForm::default(),
            &QrSolver::default(),
        )
        .unwrap();
        for (name, want) in &truth.terms {
            let got = model.coefficient(name).unwrap().value;
            worst = worst.max((got - want).abs());
        }
    }
    assert!(worst < 1e-4, "largest error {worst:e}");
}

/// The paper's method one link up: close returns of the whole state (both angles' delay vectors
/// return together) as vector orbits, harmonic balance on them.
#[test]
fn the_papers_method_on_vector_orbits_of_the_double_pendulum() {
    // Close returns of a four-dimensional state are rare: 10000 drive periods give 23 vector
    // orbits of periods 1 to 8 within 1.5 % of 2π (7 within 1 %, 45 within 2 %). A looser
    // tolerance admits orbits that close worse and biases the second equation (largest error
    // 1.1e-2 at 1.5 %, 1.8e-2 at 1 %, 5.5e-2 at 2 %).
    let (clock, q1, q2) = record(64, 10_000);
    let names = Names::new(["q1", "q2"], Vec::<String>::new()).unwrap();
    let search = upo_search::CloseReturns::builder(&clock, 16)
        .tolerance(0.015)
        .max_period(8)
        .dimension(2)
        .domain(Domain::Circle)
        .build()
        .unwrap();
    let whole = std::iter::once(0..q1.len()).collect::<Vec<_>>();
    let segments = search.search_system_pieces(&[&q1, &q2], &whole).unwrap();
    assert!(segments.len() >= 20, "{} vector orbits", segments.len());
    let mut worst: f64 = 0.0;
    for (own, truth) in DoublePendulum::whirling()
        .normalised_equations()
        .iter()
        .enumerate()
    {
        let spec: Vec<&str> = truth.terms.iter().map(|(name, _)| name.as_ref()).collect();
        let list = TermList::parse_in(&spec.join(", "), &names, own).unwrap();
        let params = IdentifyParams::builder(clock)
            .form(ModelForm::from_terms(list))
            .velocity_harmonics(IdentifyParams::SYSTEM_VELOCITY_HARMONICS)
            .build()
            .unwrap();
        let signals =
            Signals::system(vec![(&q1[..], Domain::Circle), (&q2[..], Domain::Circle)], own).unwrap();
        let model = identify(
            BasisKind::from(Harmonic::new(1).unwrap()),
            signals,
            &segments,
            &params,
            &hb_solve::HarmonicBalance,
            &QrSolver::default(),
        )
        .unwrap();
        for (name, want) in &truth.terms {
            let got = model.coefficient(name).unwrap().value;
            worst = worst.max((got - want).abs());
        }
    }
    assert!(worst < 5e-2, "largest error {worst:e}");
    // Each coefficient within 5e-2 of the truth, as the paper's method reaches on the single
    // pendulum's orbits; the weak form on windows of the same kind of record within 1e-5.
}
