//! The vocabulary of terms: names, the grammar of lists (braces, spellings, errors and where they
//! are), the smallest basis and the domains, serialisation, and the velocity factors.

use hb_basis::{Domain, Hat, Polynomial};
use hb_model::{DriveFactor, PositionFactor, Term, TermError, TermList, TermSpec, VelocityFactor, XFunction};

#[test]
fn names_follow_the_vocabulary() {
    let names = vec!["cos(x)".to_owned(), "sin(x)".to_owned()];
    let show = |drive, position, velocity| {
        Term {
            drive,
            position,
            velocity,
        }
        .name(&names)
    };
    use DriveFactor as D;
    use PositionFactor as X;
    use VelocityFactor as V;
    assert_eq!(show(D::One, X::One, V::Linear), "x'");
    assert_eq!(show(D::One, X::One, V::Sign), "sign(x')");
    assert_eq!(show(D::One, X::One, V::Quadratic), "x'*|x'|");
    assert_eq!(show(D::One, X::One, V::Cubic), "x'^3");
    assert_eq!(show(D::Cos(1), X::Basis(1), V::One), "cos(t)*sin(x)");
    assert_eq!(show(D::Sin(2), X::Basis(0), V::One), "sin(2t)*cos(x)");
    assert_eq!(show(D::Cos(3), X::One, V::One), "cos(3t)");
    assert_eq!(show(D::One, X::Basis(1), V::Linear), "sin(x)*x'");
    assert_eq!(show(D::One, X::One, V::One), "1");
}

#[test]
fn parses_every_example() {
    let one = |spec: &str| -> TermSpec { spec.parse().unwrap() };
    for name in [
        "x'",
        "sign(x')",
        "x'*|x'|",
        "x'^3",
        "sin(x)",
        "cos(2x)",
        "x^3",
        "x^2*x'",
        "cos(t)*sin(x)",
        "sin(2t)*cos(x)",
        "cos(3t)",
        "hat3",
        "1",
        "cos(2t)*x*sign(x')",
    ] {
        assert_eq!(one(name).to_string(), name);
    }
    assert_eq!(
        one("x'"),
        TermSpec {
            drive: DriveFactor::One,
            function: None,
            velocity: VelocityFactor::Linear
        }
    );
    assert_eq!(
        one("x^2*x'"),
        TermSpec {
            drive: DriveFactor::One,
            function: Some(XFunction::Power(2)),
            velocity: VelocityFactor::Linear
        }
    );
    assert_eq!(
        one("sin(2t)*cos(x)"),
        TermSpec {
            drive: DriveFactor::Sin(2),
            function: Some(XFunction::Cos(1)),
            velocity: VelocityFactor::One
        }
    );
    // Other spellings of the same terms: factors in any order, white space, explicit 1s.
    assert_eq!(one("|x'| * x'"), one("x'*|x'|"));
    assert_eq!(one("sin(x) * cos( 1t )"), one("cos(t)*sin(x)"));
    assert_eq!(one("x'^1"), one("x'"));
    assert_eq!(one("x^1"), one("x"));
    assert_eq!(one("1*cos(3t)*1"), one("cos(3t)"));
    assert_eq!(one("x'*x'*x'"), one("x'^3"));
}

#[test]
fn braces_multiply_out_in_order() {
    let list =
        TermList::parse("x', sign(x'), x'*|x'|, {1,cos(t),sin(t),cos(2t),sin(2t)}*{cos(x),sin(x)}").unwrap();
    assert_eq!(
        list.names(),
        [
            "x'",
            "sign(x')",
            "x'*|x'|",
            "cos(x)",
            "sin(x)",
            "cos(t)*cos(x)",
            "cos(t)*sin(x)",
            "sin(t)*cos(x)",
            "sin(t)*sin(x)",
            "cos(2t)*cos(x)",
            "cos(2t)*sin(x)",
            "sin(2t)*cos(x)",
            "sin(2t)*sin(x)"
        ]
    );
    assert_eq!(list.drive_harmonics(), 2);
    let nested = TermList::parse("{x', {sign(x'), 1}*x^2}*{1, cos(3t)}").unwrap();
    assert_eq!(
        nested.to_string(),
        "x', cos(3t)*x', x^2*sign(x'), cos(3t)*x^2*sign(x'), x^2, cos(3t)*x^2"
    );
    // x'*x' is not in the vocabulary: the error is at the product's first factor in x'.
    assert!(matches!(
        TermList::parse("{x'}*{1, x'}"),
        Err(TermError::TermProduct { at: 2, .. })
    ));
}

/// The position of an error: a 1-based character index into the spec.
fn error_at(spec: &str) -> usize {
    match TermList::parse(spec) {
        Err(TermError::TermSyntax { at, .. } | TermError::TermProduct { at, .. }) => at,
        Err(TermError::DuplicateTerm { at, .. }) => at,
        other => panic!("{spec}: {other:?}"),
    }
}

#[test]
fn errors_say_where() {
    assert_eq!(error_at("x', cos(t)*foo"), 12);
    assert_eq!(error_at("x', cos(t)*"), 12);
    assert_eq!(error_at(""), 1);
    assert_eq!(error_at("x',,sin(x)"), 4);
    assert_eq!(error_at("cos(2y)"), 6);
    assert_eq!(error_at("cos(0t)"), 5);
    assert_eq!(error_at("x^0"), 3);
    assert_eq!(error_at("x'^2"), 4);
    assert_eq!(error_at("{x', sin(x)"), 12);
    assert_eq!(error_at("sin(x) cos(x)"), 8);
    assert_eq!(error_at("2*sin(x)"), 1);
    assert_eq!(error_at("sign(x)"), 6);
    // Products that are not terms: the second factor of a kind.
    assert_eq!(error_at("cos(t)*sin(2t)"), 8);
    assert_eq!(error_at("x', sin(x)*cos(x)"), 12);
    assert_eq!(error_at("sign(x')*x'"), 1);
    assert_eq!(error_at("|x'|"), 1);
    // Duplicates: the item where the term comes again.
    assert_eq!(error_at("x', sin(x), x'"), 13);
    assert_eq!(error_at("sin(x), {1, cos(t)}*sin(x)"), 9);
    match TermList::parse("sin(x), sin(x) * 1") {
        Err(TermError::DuplicateTerm { term, .. }) => assert_eq!(term, "sin(x)"),
        other => panic!("{other:?}"),
    }
    let message = TermList::parse("x', cos(t)*foo").unwrap_err().to_string();
    assert!(
        message.contains("character 12") && message.contains("'foo'"),
        "{message}"
    );
    assert!(matches!(
        TermList::parse("cos(65t)"),
        Err(TermError::DriveHarmonicOutOfRange { .. })
    ));
    assert!(matches!(
        TermList::parse("cos(99999999999t)"),
        Err(TermError::TermSyntax { at: 5, .. })
    ));
    let big = "{1,cos(t),sin(t),cos(2t),sin(2t),cos(3t),sin(3t),cos(4t)}";
    assert!(matches!(
        TermList::parse(&format!("{big}*{big}*{big}*{big}*{{1,x}}")),
        Err(TermError::TooManyTerms { .. })
    ));
}

#[test]
fn smallest_basis_and_domains() {
    let basis = |spec: &str| TermList::parse(spec).unwrap().smallest_basis().unwrap();
    assert_eq!(
        basis("x', cos(2x)"),
        Some(hb_basis::Harmonic::new(2).unwrap().into())
    );
    assert_eq!(
        basis("sin(x), cos(t)*sin(3x)"),
        Some(hb_basis::Harmonic::new(3).unwrap().into())
    );
    assert_eq!(basis("x, x^2*x', x^3"), Some(Polynomial::new(3).unwrap().into()));
    assert_eq!(basis("hat7, hat2"), Some(Hat::new(8).unwrap().into()));
    assert_eq!(basis("hat0"), Some(Hat::new(3).unwrap().into()));
    assert_eq!(basis("x', sign(x'), cos(t)"), None);
    assert!(matches!(
        TermList::parse("sin(x), x^3").unwrap().smallest_basis(),
        Err(TermError::MixedBases { .. })
    ));
    let on_line = TermList::parse("x', x^3").unwrap();
    assert!(on_line.check_domain(Domain::Line).is_ok());
    assert!(matches!(
        on_line.check_domain(Domain::Circle),
        Err(TermError::TermNotAllowed { ref term, .. }) if term == "x^3"
    ));
    // Resolution finds each function by name, and names what the basis lacks.
    let list = TermList::parse("x', sin(2x)*x', cos(t)*cos(x)").unwrap();
    let terms = list.resolve(&hb_basis::Harmonic::new(2).unwrap()).unwrap();
    assert_eq!(terms[1].position, PositionFactor::Basis(3));
    assert_eq!(terms[2].position, PositionFactor::Basis(0));
    match list.resolve(&hb_basis::Harmonic::new(1).unwrap()) {
        Err(TermError::TermNotInBasis { term, function, .. }) => {
            assert_eq!((term.as_str(), function.as_str()), ("sin(2x)*x'", "sin(2x)"));
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn lists_serialise_as_names() {
    let list = TermList::parse("x', {1, cos(2t)}*sin(x)").unwrap();
    let json = serde_json::to_string(&list).unwrap();
    assert_eq!(json, r#"["x'","sin(x)","cos(2t)*sin(x)"]"#);
    assert_eq!(serde_json::from_str::<TermList>(&json).unwrap(), list);
    for bad in [r#"["x'","x'"]"#, r#"["x', sin(x)"]"#, r#"["foo"]"#, "[]"] {
        assert!(serde_json::from_str::<TermList>(bad).is_err(), "{bad}");
    }
}

#[test]
fn velocity_factors_and_their_derivatives() {
    for v in [-2.5, -0.3, 0.4, 1.7] {
        for f in [
            VelocityFactor::One,
            VelocityFactor::Linear,
            VelocityFactor::Sign,
            VelocityFactor::Quadratic,
            VelocityFactor::Cubic,
        ] {
            let e = 1e-6;
            let numeric = (f.eval(v + e) - f.eval(v - e)) / (2.0 * e);
            assert!((numeric - f.eval_deriv(v)).abs() < 1e-6, "{f:?} at {v}");
        }
    }
    assert_eq!(VelocityFactor::Sign.eval(0.0), 0.0);
    assert_eq!(VelocityFactor::Sign.eval(-3.0), -1.0);
    assert!(VelocityFactor::Sign.eval(f64::NAN).is_nan());
    assert_eq!(VelocityFactor::Quadratic.eval(-2.0), -4.0);
}
