//! Goodness of fit and model selection on identifications of simulated and published records.

mod common;

use hb_basis::{BasisKind, Harmonic};
use hb_solve::{
    EXPLAINED_WARNING_WINDOWS, IdentifyParams, ModelForm, QrSolver, SelectParams, WeakForm, build_system,
    fit_quality, select_terms,
};
use upo_search::Windows;

use common::{paper_clock, read_paper_dataset};

/// The paper's data set by the weak form: the right model explains all but rounding of the
/// windowed acceleration and leaves no line at a drive harmonic; the model without the
/// parametric drive terms explains less and leaves its residual at the drive's first harmonic.
#[test]
fn the_paper_model_fits_and_a_model_without_the_drive_says_so() {
    let (t0, x) = read_paper_dataset();
    let clock = paper_clock(t0);
    let segments = Windows::new(&clock).unwrap().windows(&x).unwrap();
    let basis: BasisKind = Harmonic::new(1).unwrap().into();
    let weak = WeakForm::default();
    let quality = |form: ModelForm| {
        let params = IdentifyParams::builder(clock)
            .harmonics(WeakForm::DEFAULT_HARMONICS)
            .form(form)
            .build()
            .unwrap();
        let system = build_system(&basis, &x, &segments, &params, &weak).unwrap();
        let fit = system.solve(&QrSolver::default()).unwrap();
        fit_quality(&system, &fit.solution).unwrap()
    };
    let good = quality(ModelForm::parametric());
    assert!(good.explained > 1.0 - 1e-9, "{}", good.explained);
    assert!(good.warning(EXPLAINED_WARNING_WINDOWS).is_none());

    let bad = quality(ModelForm::parametric().without_parametric_terms());
    assert!(bad.explained < 0.9, "{}", bad.explained);
    assert!(
        bad.warning(EXPLAINED_WARNING_WINDOWS)
            .is_some_and(|w| w.contains("likely missing terms"))
    );
}

/// From the paper's model plus candidates the pendulum does not have, selection keeps exactly
/// the paper's nonzero terms.
#[test]
fn selection_on_the_paper_dataset() {
    let (t0, x) = read_paper_dataset();
    let clock = paper_clock(t0);
    let segments = Windows::new(&clock).unwrap().windows(&x).unwrap();
    let basis: BasisKind = Harmonic::new(2).unwrap().into();
    let params = IdentifyParams::builder(clock)
        .harmonics(WeakForm::DEFAULT_HARMONICS)
        .build()
        .unwrap();
    let system = build_system(&basis, &x, &segments, &params, &WeakForm::default()).unwrap();
    let s = select_terms(&system, &SelectParams::default()).unwrap();
    assert_eq!(s.kept_names, ["x'", "sin(t)*cos(x)", "sin(x)"], "{s:#?}");
}
