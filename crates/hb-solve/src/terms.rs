//! The vocabulary of the model's terms, and the column layout of every system defined once.
//!
//! The model is `x'' + Σ_i c_i g_i = 0`, each term `g_i` a product of three factors: a drive
//! factor (`1`, `cos(kt)`, `sin(kt)` for harmonic `k` of the drive, `t` standing for the drive's
//! phase `W t`), a function of `x` (`1`, a basis function, or `x` itself) and a function of `x'`
//! (`1`, `x'`, `sign(x')`, `x'*|x'|`, `x'^3`). A term is named by its factors joined by `*`, drive
//! factor first: `x'`, `cos(t)*sin(x)`, `sin(2t)*cos(x)`, `cos(3t)`, `x'*|x'|`.
//!
//! [`columns`] gives the unknowns of a [`ModelForm`] on a basis, in the order every assembly,
//! solver, bootstrap and saved model uses.

use std::fmt;

use hb_basis::{Basis, Domain};

use crate::{Forcing, ModelForm, SolveError};

/// The drive factor of a term: `1`, `cos(k t)` or `sin(k t)` for harmonic `k >= 1` of the drive.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DriveFactor {
    /// No drive factor.
    One,
    /// `cos(k t)`.
    Cos(u32),
    /// `sin(k t)`.
    Sin(u32),
}

/// The factor in the displacement `x` of a term.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PositionFactor {
    /// No function of `x`.
    One,
    /// Function `i` of the basis.
    Basis(usize),
    /// `x` itself, a linear stiffness beside the basis (on the line only); named `k*x`.
    Linear,
}

/// The factor in the velocity `x'` of a term.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum VelocityFactor {
    /// No function of `x'`.
    One,
    /// `x'` (viscous damping).
    Linear,
    /// `sign(x')` (dry, Coulomb friction).
    Sign,
    /// `x'*|x'|` (quadratic drag).
    Quadratic,
    /// `x'^3`.
    Cubic,
}

/// One term of the model: the product of a drive factor, a function of `x` and a function of `x'`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Term {
    /// The drive factor.
    pub drive: DriveFactor,
    /// The function of `x`.
    pub position: PositionFactor,
    /// The function of `x'`.
    pub velocity: VelocityFactor,
}

impl Term {
    /// `x'`, the linear damping.
    pub const DAMPING: Self = Self {
        drive: DriveFactor::One,
        position: PositionFactor::One,
        velocity: VelocityFactor::Linear,
    };

    /// The drive factor alone (`cos(kt)` or `sin(kt)`, an external forcing).
    pub const fn drive(drive: DriveFactor) -> Self {
        Self {
            drive,
            position: PositionFactor::One,
            velocity: VelocityFactor::One,
        }
    }

    /// Basis function `i` times a drive factor (`One` for the autonomous term).
    pub const fn basis(drive: DriveFactor, i: usize) -> Self {
        Self {
            drive,
            position: PositionFactor::Basis(i),
            velocity: VelocityFactor::One,
        }
    }

    /// The term's name with the basis functions' `names`, e.g. `cos(t)*sin(x)`.
    pub fn name(&self, names: &[String]) -> String {
        self.display(names).to_string()
    }

    /// The term shown with the basis functions' `names`.
    pub fn display<'a>(&'a self, names: &'a [String]) -> impl fmt::Display + 'a {
        TermName { term: self, names }
    }

    /// The column family of the two assemblies, or `None` for a term they do not balance yet.
    pub(crate) fn column(&self) -> Option<Column> {
        use DriveFactor as D;
        use PositionFactor as X;
        use VelocityFactor as V;
        Some(match (self.drive, self.position, self.velocity) {
            (D::One, X::One, V::Linear) => Column::Damping,
            (D::Cos(1), X::Basis(i), V::One) => Column::CosT(i),
            (D::Sin(1), X::Basis(i), V::One) => Column::SinT(i),
            (D::One, X::Basis(i), V::One) => Column::Auto(i),
            (D::Cos(1), X::One, V::One) => Column::ForcingCos,
            (D::Sin(1), X::One, V::One) => Column::ForcingSin,
            (D::One, X::Linear, V::One) => Column::Stiffness,
            _ => return None,
        })
    }
}

struct TermName<'a> {
    term: &'a Term,
    names: &'a [String],
}

impl fmt::Display for TermName<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut parts: Vec<String> = Vec::with_capacity(3);
        let harmonic = |k: u32| if k == 1 { "t".to_owned() } else { format!("{k}t") };
        match self.term.drive {
            DriveFactor::One => {}
            DriveFactor::Cos(k) => parts.push(format!("cos({})", harmonic(k))),
            DriveFactor::Sin(k) => parts.push(format!("sin({})", harmonic(k))),
        }
        match self.term.position {
            PositionFactor::One => {}
            PositionFactor::Basis(i) => {
                parts.push(self.names.get(i).cloned().unwrap_or_else(|| format!("phi{i}(x)")))
            }
            PositionFactor::Linear => parts.push("k*x".to_owned()),
        }
        match self.term.velocity {
            VelocityFactor::One => {}
            VelocityFactor::Linear => parts.push("x'".to_owned()),
            VelocityFactor::Sign => parts.push("sign(x')".to_owned()),
            VelocityFactor::Quadratic => parts.push("x'*|x'|".to_owned()),
            VelocityFactor::Cubic => parts.push("x'^3".to_owned()),
        }
        if parts.is_empty() {
            f.write_str("1")
        } else {
            f.write_str(&parts.join("*"))
        }
    }
}

/// The column families the assemblies balance today (paper eq. 6 and an external forcing).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Column {
    /// `c_r`, term `x'`.
    Damping,
    /// `n_i`, term `cos(t)*φ_i`.
    CosT(usize),
    /// `p_i`, term `sin(t)*φ_i`.
    SinT(usize),
    /// `q_i`, term `φ_i`.
    Auto(usize),
    /// `F_c`, term `cos(t)`.
    ForcingCos,
    /// `F_s`, term `sin(t)`.
    ForcingSin,
    /// `k`, term `k*x`.
    Stiffness,
}

/// The unknowns of a model with `functions` basis functions and `form`, in column order: `x'`;
/// then for each basis function `B` the terms `cos(t)*B`, `sin(t)*B` (if parametric) and `B` (the
/// paper's order n, p, q); then `cos(t)`, `sin(t)` (identified forcing) and `k*x` (linear
/// stiffness).
pub fn columns(functions: usize, form: &ModelForm) -> Vec<Term> {
    let mut t = vec![Term::DAMPING];
    for i in 0..functions {
        if form.is_parametric() {
            t.push(Term::basis(DriveFactor::Cos(1), i));
            t.push(Term::basis(DriveFactor::Sin(1), i));
        }
        t.push(Term::basis(DriveFactor::One, i));
    }
    if form.forcing() == Forcing::Identified {
        t.push(Term::drive(DriveFactor::Cos(1)));
        t.push(Term::drive(DriveFactor::Sin(1)));
    }
    if form.has_linear_stiffness() {
        t.push(Term {
            drive: DriveFactor::One,
            position: PositionFactor::Linear,
            velocity: VelocityFactor::One,
        });
    }
    t
}

/// The column families of `terms`, or [`SolveError::TermNotSupported`] for the first term the
/// assemblies do not balance.
pub(crate) fn column_families(terms: &[Term], names: &[String]) -> Result<Vec<Column>, SolveError> {
    terms
        .iter()
        .map(|t| {
            t.column()
                .ok_or_else(|| SolveError::TermNotSupported { term: t.name(names) })
        })
        .collect()
}

/// The names of the unknowns of a model on `basis` with `form`, in column order (see
/// [`columns`]).
pub fn term_names<B: Basis + ?Sized>(basis: &B, form: &ModelForm) -> Vec<String> {
    let names = basis.names();
    columns(names.len(), form)
        .iter()
        .map(|t| t.name(&names))
        .collect()
}

/// Checks that the form's terms exist on the basis' domain.
pub(crate) fn check_form(domain: Domain, form: &ModelForm) -> Result<(), SolveError> {
    if form.has_linear_stiffness() && domain == Domain::Circle {
        return Err(SolveError::TermNotAllowed {
            term: "k*x",
            domain,
            why: "x is an angle known modulo 2π; put sin(x) or hats in the basis instead",
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

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
    }

    #[test]
    fn paper_layout() {
        let names = vec!["cos(x)".to_owned(), "sin(x)".to_owned()];
        let got: Vec<String> = columns(2, &ModelForm::parametric())
            .iter()
            .map(|t| t.name(&names))
            .collect();
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
        assert!(column_families(&columns(2, &ModelForm::parametric()), &names).is_ok());
        let drag = [Term {
            drive: DriveFactor::One,
            position: PositionFactor::One,
            velocity: VelocityFactor::Quadratic,
        }];
        assert!(matches!(
            column_families(&drag, &names),
            Err(SolveError::TermNotSupported { .. })
        ));
    }
}
