//! The errors of the model's vocabulary and of its saved formats, folded into [`ModelError`].

use hb_basis::{BasisError, Domain};

/// A list of terms that does not read, or a form whose terms do not exist on its basis or domain.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TermError {
    /// A drive factor `cos(kt)`, `sin(kt)` of a harmonic out of `1..=64`.
    #[error("drive harmonic {harmonic} of a term must be between 1 and 64")]
    DriveHarmonicOutOfRange {
        /// The harmonic.
        harmonic: u32,
    },
    /// A list of terms that does not parse.
    #[error("term list \"{spec}\": at character {at}, expected {expected}; found {found}")]
    TermSyntax {
        /// The list as given.
        spec: String,
        /// 1-based position of the character where the error is (one past the end at the end).
        at: usize,
        /// What was found there.
        found: String,
        /// What was expected.
        expected: std::borrow::Cow<'static, str>,
    },
    /// Factors that do not make a term together.
    #[error("term list \"{spec}\": the product at character {at} is not a term: {why}")]
    TermProduct {
        /// The list as given.
        spec: String,
        /// 1-based position of the offending factor.
        at: usize,
        /// Why.
        why: &'static str,
    },
    /// A term named twice in a list.
    #[error("the term `{term}` is named twice (again at character {at} of the list)")]
    DuplicateTerm {
        /// The term.
        term: String,
        /// Where it appears again (1-based character of its item; for a list built from terms,
        /// the 1-based index of the term).
        at: usize,
    },
    /// A list of terms with too many of them.
    #[error("{count} terms are too many (at most {max})")]
    TooManyTerms {
        /// Terms asked for.
        count: usize,
        /// The most allowed.
        max: usize,
    },
    /// A term whose function of `x` the basis does not have.
    #[error(
        "the term `{term}` needs the function {function}, which the basis ({}) does not have; choose a basis \
         that holds it (e.g. harmonic:2 for cos(2x), poly:3 for x^3, hat:8 for hat7)", basis.join(", ")
    )]
    TermNotInBasis {
        /// The term.
        term: String,
        /// Its function of `x`.
        function: String,
        /// The basis' functions.
        basis: Vec<String>,
    },
    /// Functions of `x` of two kinds of basis in one list.
    #[error(
        "the functions {first} and {second} come from different bases (harmonic, polynomial, hat): one basis holds the functions of a model"
    )]
    MixedBases {
        /// A function of one kind.
        first: String,
        /// One of another.
        second: String,
    },
    /// A model term that does not belong on the basis' domain.
    #[error(
        "the term `{term}` cannot be used with a basis on the {domain} (the signal of its coordinate): {why}"
    )]
    TermNotAllowed {
        /// The term's name.
        term: String,
        /// The basis' domain.
        domain: Domain,
        /// Why.
        why: &'static str,
    },
    /// A model form whose parts contradict each other.
    #[error("invalid model form: {why}")]
    InvalidForm {
        /// Why.
        why: &'static str,
    },
    /// A name of a coordinate or a drive that cannot be written in terms.
    #[error("the name `{name}` cannot be used: {why}")]
    BadName {
        /// The name (or names).
        name: String,
        /// Why.
        why: &'static str,
    },
    /// A term that names a coordinate or a drive the record does not have.
    #[error("the term `{term}` names a {what} the record does not have")]
    UnknownName {
        /// The term.
        term: String,
        /// What it names: `coordinate` or `measured drive`.
        what: &'static str,
    },
    /// A term whose factors do not make a term of its equation.
    #[error("the term `{term}` is not a term of its equation: {why}")]
    InvalidTerm {
        /// The term.
        term: String,
        /// Why.
        why: &'static str,
    },
    /// A basis or Fourier error.
    #[error(transparent)]
    Basis(#[from] BasisError),
}

/// A saved model that cannot be read (or written).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ModelIoError {
    /// A saved model does not start with the magic bytes.
    #[error("not a saved model: the first bytes are not the model magic number")]
    BadMagic,
    /// A saved model of another format version.
    #[error(
        "saved model format version {found} is not supported (this build reads versions 2 to {supported})"
    )]
    UnsupportedVersion {
        /// Version in the file.
        found: u32,
        /// The newest version this build reads, the one it writes.
        supported: u32,
    },
    /// A saved model whose coefficients do not match its basis and form.
    #[error("saved model is inconsistent: expected the terms {expected:?}, found {found:?}")]
    ModelMismatch {
        /// Terms implied by the basis and form.
        expected: Vec<String>,
        /// Terms in the file.
        found: Vec<String>,
    },
    /// A saved model with a non-finite number.
    #[error("saved model has a non-finite value for `{name}`")]
    NonFiniteModelValue {
        /// Which value.
        name: String,
    },
    /// A saved system (several coordinates, or one under drives of its own names) read as one
    /// model.
    #[error("a saved system (format 5): read it as a system, not as one model")]
    SavedSystem,
    /// JSON (de)serialisation failed.
    #[error("JSON: {0}")]
    Json(#[from] serde_json::Error),
    /// Binary (de)serialisation failed.
    #[error("binary model: {0}")]
    Postcard(#[from] postcard::Error),
}

/// Everything that can go wrong with a model: its terms, its saved form, a setting out of range.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ModelError {
    /// The terms or the form.
    #[error(transparent)]
    Term(#[from] TermError),
    /// A saved model.
    #[error(transparent)]
    Io(#[from] ModelIoError),
    /// A parameter is out of range.
    #[error("invalid {name}: {} ({why})", circle_signal::Shown(*.value))]
    InvalidParameter {
        /// The parameter's name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What it must be.
        why: &'static str,
    },
    /// A measured drive of fewer than two samples (nothing to interpolate).
    #[error("a measured drive needs at least 2 samples; it has {len}")]
    DriveTooShort {
        /// The samples given.
        len: usize,
    },
}

impl From<BasisError> for ModelError {
    fn from(e: BasisError) -> Self {
        ModelError::Term(TermError::Basis(e))
    }
}

impl From<serde_json::Error> for ModelError {
    fn from(e: serde_json::Error) -> Self {
        ModelError::Io(ModelIoError::Json(e))
    }
}

impl From<postcard::Error> for ModelError {
    fn from(e: postcard::Error) -> Self {
        ModelError::Io(ModelIoError::Postcard(e))
    }
}
