//! The layout of the unknowns of the paper's preset forms.

use hb_basis::Basis;
use hb_model::form::column_families;
use hb_model::{Column, Forcing, ModelForm, columns, term_names};

#[test]
fn paper_layout() {
    let basis = hb_basis::Harmonic::new(1).unwrap();
    let names = basis.names();
    let layout = columns(&basis, &ModelForm::parametric()).unwrap();
    let got: Vec<String> = layout.iter().map(|t| t.name(&names)).collect();
    assert_eq!(
        got,
        [
            "x'",
            "cos(t)*cos(x)",
            "sin(t)*cos(x)",
            "cos(x)",
            "cos(t)*sin(x)",
            "sin(t)*sin(x)",
            "sin(x)"
        ]
    );
    assert!(column_families(&layout).iter().all(Column::is_paper));
    // Two drive harmonics: cos(2t)*B, sin(2t)*B after cos(t)*B, sin(t)*B, and the forcing.
    let form = ModelForm::parametric()
        .with_forcing(Forcing::Identified)
        .with_drive_harmonics(2);
    assert_eq!(
        term_names(&basis, &form),
        [
            "x'",
            "cos(t)*cos(x)",
            "sin(t)*cos(x)",
            "cos(2t)*cos(x)",
            "sin(2t)*cos(x)",
            "cos(x)",
            "cos(t)*sin(x)",
            "sin(t)*sin(x)",
            "cos(2t)*sin(x)",
            "sin(2t)*sin(x)",
            "sin(x)",
            "cos(t)",
            "sin(t)",
            "cos(2t)",
            "sin(2t)"
        ]
    );
}
