//! What an equation's rows are balanced from: the samples of a system's coordinates on one grid
//! (the equation's own among them) and of its measured drives.

use hb_basis::Domain;

use crate::error::{AssemblyError, SolveError};

/// The samples an equation is identified from, all on one grid (NaN in the gaps of a record in
/// pieces): the coordinates of the system, one of them the equation's own (what its basis
/// functions, its velocity and the left-hand side `x''` read), and the measured drives its
/// terms may name (by index, as [`hb_model::DriveFactor::Measured`] does).
///
/// A record of one coordinate is [`Signals::one`] (or `x.into()`), with its drive, if any, by
/// [`Signals::with_drives`]; a system's is [`Signals::system`].
///
/// ```
/// use hb_basis::Domain;
/// use hb_solve::Signals;
///
/// let (q1, q2) = (vec![0.1; 100], vec![0.2; 100]);
/// let tau = vec![0.0; 100];
/// let signals = Signals::system(vec![(&q1[..], Domain::Circle), (&q2[..], Domain::Circle)], 1)?
///     .with_drives(vec![&tau[..]])?;
/// assert_eq!(signals.own(), &q2[..]);
/// assert_eq!(signals.coordinates(), 2);
/// assert_eq!(signals.drive(0), Some(&tau[..]));
/// # Ok::<(), hb_solve::SolveError>(())
/// ```
#[derive(Debug, Clone)]
pub struct Signals<'a> {
    own: usize,
    coordinates: Vec<&'a [f64]>,
    /// The domain of each coordinate; `None` for a one-coordinate record's, which is its
    /// basis'.
    domains: Vec<Option<Domain>>,
    drives: Vec<&'a [f64]>,
}

impl<'a> Signals<'a> {
    /// A record of one coordinate `x` (its domain is the basis').
    pub fn one(x: &'a [f64]) -> Self {
        Self {
            own: 0,
            coordinates: vec![x],
            domains: vec![None],
            drives: Vec::new(),
        }
    }

    /// The coordinates of a system with their domains, all of one length, for the equation of
    /// coordinate `own`.
    ///
    /// Errors: no coordinate, `own` out of range, or coordinates of different lengths.
    pub fn system(coordinates: Vec<(&'a [f64], Domain)>, own: usize) -> Result<Self, SolveError> {
        let len = coordinates.first().map(|(x, _)| x.len());
        if own >= coordinates.len() {
            return Err(SolveError::InvalidParameter {
                name: "own coordinate",
                value: own as f64,
                why: "must be one of the system's coordinates",
            });
        }
        if let Some((c, (x, _))) = coordinates
            .iter()
            .enumerate()
            .find(|(_, (x, _))| Some(x.len()) != len)
        {
            return Err(SolveError::Assembly(AssemblyError::CoordinateLengthMismatch {
                coordinate: c,
                len: x.len(),
                record: len.unwrap_or(0),
            }));
        }
        let (coordinates, domains) = coordinates.into_iter().map(|(x, d)| (x, Some(d))).unzip();
        Ok(Self {
            own,
            coordinates,
            domains,
            drives: Vec::new(),
        })
    }

    /// The same with the measured drives, in order, each as long as the coordinates.
    ///
    /// Errors: a drive of another length.
    pub fn with_drives(mut self, drives: Vec<&'a [f64]>) -> Result<Self, SolveError> {
        if let Some(d) = drives.iter().find(|d| d.len() != self.len()) {
            return Err(SolveError::Assembly(AssemblyError::DriveLengthMismatch {
                drive: d.len(),
                record: self.len(),
            }));
        }
        self.drives = drives;
        Ok(self)
    }

    /// The equation's own coordinate's samples.
    pub fn own(&self) -> &'a [f64] {
        self.coordinates[self.own]
    }

    /// The index of the own coordinate.
    pub fn own_index(&self) -> usize {
        self.own
    }

    /// The number of coordinates.
    pub fn coordinates(&self) -> usize {
        self.coordinates.len()
    }

    /// The samples of coordinate `c`.
    pub fn coordinate(&self, c: usize) -> Option<&'a [f64]> {
        self.coordinates.get(c).copied()
    }

    /// The domain of coordinate `c`, when given (a one-coordinate record's is its basis').
    pub fn domain(&self, c: usize) -> Option<Domain> {
        self.domains.get(c).copied().flatten()
    }

    /// The samples of measured drive `d`, when given.
    pub fn drive(&self, d: usize) -> Option<&'a [f64]> {
        self.drives.get(d).copied()
    }

    /// The number of measured drives given.
    pub fn drives(&self) -> usize {
        self.drives.len()
    }

    /// The number of samples of each coordinate.
    pub fn len(&self) -> usize {
        self.own().len()
    }

    /// Whether the record has no sample.
    pub fn is_empty(&self) -> bool {
        self.own().is_empty()
    }
}

impl<'a> From<&'a [f64]> for Signals<'a> {
    fn from(x: &'a [f64]) -> Self {
        Self::one(x)
    }
}

impl<'a> From<&'a Vec<f64>> for Signals<'a> {
    fn from(x: &'a Vec<f64>) -> Self {
        Self::one(x)
    }
}

impl<'a, const N: usize> From<&'a [f64; N]> for Signals<'a> {
    fn from(x: &'a [f64; N]) -> Self {
        Self::one(x)
    }
}

impl<'a> From<&Signals<'a>> for Signals<'a> {
    fn from(s: &Signals<'a>) -> Self {
        s.clone()
    }
}
