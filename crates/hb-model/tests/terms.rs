//! The vocabulary of terms: names, the grammar of lists (braces, spellings, errors and where they
//! are), the smallest basis and the domains, serialisation, and the velocity factors.

use hb_basis::{Domain, Hat, Polynomial};
use hb_model::{
    Coupling, DriveFactor, PositionFactor, Term, TermError, TermList, TermSpec, VelocityFactor, XFunction,
};

#[test]
fn names_follow_the_vocabulary() {
    let names = vec!["cos(x)".to_owned(), "sin(x)".to_owned()];
    let show = |drive, position, velocity| {
        Term {
            drive,
            position,
            velocity,
            coupling: Coupling::NONE,
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
            velocity: VelocityFactor::Linear,
            coupling: Coupling::NONE
        }
    );
    assert_eq!(
        one("x^2*x'"),
        TermSpec {
            drive: DriveFactor::One,
            function: Some(XFunction::Power(2)),
            velocity: VelocityFactor::Linear,
            coupling: Coupling::NONE
        }
    );
    assert_eq!(
        one("sin(2t)*cos(x)"),
        TermSpec {
            drive: DriveFactor::Sin(2),
            function: Some(XFunction::Cos(1)),
            velocity: VelocityFactor::One,
            coupling: Coupling::NONE
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
    // x'^3*x' is not in the vocabulary: the error is at the product's first factor in x'.
    assert!(matches!(
        TermList::parse("{x'^3}*{1, x'}"),
        Err(TermError::TermProduct { at: 2, .. })
    ));
    // x'*x' is x'^2, the square of the velocity (a centrifugal force's).
    assert_eq!(TermList::parse("{x'}*{1, x'}").unwrap().names(), ["x'", "x'^2"]);
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
    assert_eq!(error_at("x'^4"), 4);
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

/// Terms over several coordinates: names of the record's columns, factors in other coordinates
/// and accelerations, printed in one order whatever the equation, and read back.
#[test]
fn terms_of_a_system_read_and_print_in_its_names() {
    use hb_model::{Factor, Names};
    let names = Names::new(["theta1", "theta2"], ["tau1", "tau2"]).unwrap();
    let list = |spec: &str, own: usize| TermList::parse_in(spec, &names, own).unwrap();
    // The same product is written the same way in both equations.
    for own in [0, 1] {
        let l = list(
            "cos(theta1-theta2)*theta2'', theta2'^2 * sin(theta1-theta2), theta2'*sin(theta2)*theta1', \
             sin(theta1), cos(theta2), tau1, tau2*cos(theta1), sign(theta1'), theta1'*|theta1'|",
            own,
        );
        assert_eq!(
            l.names(),
            [
                "theta2''*cos(theta1-theta2)",
                "sin(theta1-theta2)*theta2'^2",
                "sin(theta2)*theta1'*theta2'",
                "sin(theta1)",
                "cos(theta2)",
                "tau1",
                "tau2*cos(theta1)",
                "sign(theta1')",
                "theta1'*|theta1'|",
            ],
            "own {own}"
        );
        assert_eq!(TermList::parse_in(&l.to_string(), &names, own).unwrap(), l);
        assert_eq!(TermList::from_names_in(&l.names(), &names, own).unwrap(), l);
    }
    // What is the own coordinate's and what another's.
    let first = list("sin(theta1), sin(theta2), theta1', theta2'", 0);
    let t = first.terms();
    assert_eq!(t[0].function, Some(XFunction::Sin(1)));
    assert!(t[0].coupling.is_empty() && !t[1].coupling.is_empty());
    assert_eq!(t[2].velocity, VelocityFactor::Linear);
    assert!(matches!(
        t[3].coupling.factors().next(),
        Some(Factor::Velocity {
            coordinate: 1,
            function: VelocityFactor::Linear
        })
    ));
    // A drive by its column's name; harmonics and combinations.
    let second = list(
        "tau2, cos(2t)*sin(theta2), sin(theta1+2theta2), cos(theta2-theta1), theta1''",
        1,
    );
    assert_eq!(second.measured_drives(), [1]);
    assert_eq!(
        second.names()[2..],
        ["sin(theta1+2theta2)", "cos(theta1-theta2)", "theta1''"]
    );
    assert_eq!(second.terms()[4].coupling.acceleration(), Some(0));
    // A mass matrix that depends on the state: the own acceleration times a function of it.
    let own_mass = list("theta1''*cos(theta2), theta1''*cos(theta1)", 0);
    assert_eq!(own_mass.terms()[0].coupling.acceleration(), Some(0));
}

#[test]
fn terms_of_a_system_that_are_no_terms_are_refused_with_a_reason() {
    use hb_model::Names;
    let names = Names::new(["q1", "q2"], ["u"]).unwrap();
    let refused = |spec: &str| TermList::parse_in(spec, &names, 0).unwrap_err().to_string();
    // The own acceleration alone is the normalisation.
    assert!(refused("q1''").contains("normalisation"), "{}", refused("q1''"));
    // Accelerations multiply functions of the positions only, one at a time.
    assert!(refused("q2''*q2'").contains("positions only"));
    assert!(refused("q2''*cos(t)").contains("positions only"));
    assert!(refused("q2''*q1''").contains("at most one acceleration"));
    // −sin of the turned combination is not written with a leading minus.
    assert!(refused("sin(q2-q1)").contains("turned"));
    // The order is the coordinates' as listed, which the message says (the text has no minus
    // in front).
    assert!(
        refused("sin(q2-q1)").contains("the coordinates taken in the order they are listed"),
        "{}",
        refused("sin(q2-q1)")
    );
    // cos of it is: the same as the turned one.
    assert_eq!(
        TermList::parse_in("cos(q2-q1)", &names, 0).unwrap().names(),
        ["cos(q1-q2)"]
    );
    // Names the record does not have; two functions of one coordinate.
    assert!(matches!(
        TermList::parse_in("q3'", &names, 0),
        Err(TermError::TermSyntax { at: 1, .. })
    ));
    assert!(refused("sin(q2)*cos(q2)").contains("one function"));
    // A name inside sin(..) that is no coordinate: the message lists the record's coordinates.
    let unknown = refused("sin(q3)");
    assert!(unknown.contains("a coordinate (q1, q2)"), "{unknown}");
    assert!(refused("sin(q1+q3)").contains("a coordinate's name (q1, q2)"));
    // An equation without terms says so rather than asking for a factor.
    assert!(refused("").contains("an equation without terms"));
    assert!(refused("  ").contains("an equation without terms"));
    assert!(matches!(
        TermList::parse_in("p", &names, 0),
        Err(TermError::TermSyntax { .. })
    ));
    // Names that cannot be written in terms.
    for bad in [
        vec!["t"],
        vec!["cos"],
        vec!["hat3"],
        vec!["q", "q"],
        vec!["1q"],
        vec![],
    ] {
        assert!(
            matches!(
                Names::new(bad.clone(), Vec::<String>::new()),
                Err(TermError::BadName { .. })
            ),
            "{bad:?}"
        );
    }
    assert!(matches!(Names::new(["q"], ["q"]), Err(TermError::BadName { .. })));
    assert!(TermList::parse_in("q1'", &names, 2).is_err());
}

#[test]
fn one_coordinate_terms_keep_their_names() {
    // The one-coordinate spelling is the case of one coordinate named x.
    let list = TermList::parse("x', x'^2, x''*cos(x), sin(x)*x'").unwrap();
    assert_eq!(list.names(), ["x'", "x'^2", "x''*cos(x)", "sin(x)*x'"]);
    assert!(list.is_coupled());
    assert!(!TermList::parse("x', sin(x)").unwrap().is_coupled());
}
