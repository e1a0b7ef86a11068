use std::iter::{StepBy, Take};
use std::slice::Iter;

use crate::error::EmbeddingError;

/// An embedding dimension `d ≥ 1` and a delay `T_d ≥ 1` (in samples), validated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Embedding {
    dim: usize,
    delay: usize,
}

impl Embedding {
    /// Checks `dim ≥ 1` and `delay ≥ 1`.
    pub fn new(dim: usize, delay: usize) -> Result<Self, EmbeddingError> {
        if dim == 0 {
            return Err(EmbeddingError::InvalidParameter {
                name: "dim",
                value: 0.0,
                why: "must be at least 1",
            });
        }
        if delay == 0 {
            return Err(EmbeddingError::InvalidParameter {
                name: "delay",
                value: 0.0,
                why: "must be at least 1",
            });
        }
        Ok(Self { dim, delay })
    }

    /// The embedding dimension `d`.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// The delay `T_d` in samples.
    pub fn delay(&self) -> usize {
        self.delay
    }

    /// Samples spanned by one delay vector, `(d − 1) T_d + 1`.
    pub fn window(&self) -> usize {
        (self.dim - 1) * self.delay + 1
    }

    /// Number of delay vectors in a record of `len` samples, `len − (d − 1) T_d` (0 if shorter).
    pub fn count(&self, len: usize) -> usize {
        (len + 1).saturating_sub(self.window())
    }

    /// The delay vectors of `x`, a view that copies nothing.
    ///
    /// # Errors
    /// [`EmbeddingError::TooShort`] if `x` holds fewer samples than one vector spans.
    pub fn vectors<'a>(&self, x: &'a [f64]) -> Result<DelayVectors<'a>, EmbeddingError> {
        let len = self.count(x.len());
        if len == 0 {
            return Err(EmbeddingError::TooShort {
                len: x.len(),
                needed: self.window(),
            });
        }
        Ok(DelayVectors {
            x,
            dim: self.dim,
            delay: self.delay,
            len,
        })
    }
}

/// All delay vectors `S(n) = (x_n, x_{n+T_d}, …, x_{n+(d−1)T_d})` of a record, `n = 0..len()`.
///
/// A view on the record: nothing is copied, and [`DelayVectors::get`] costs nothing.
#[derive(Debug, Clone, Copy)]
pub struct DelayVectors<'a> {
    x: &'a [f64],
    dim: usize,
    delay: usize,
    len: usize,
}

impl<'a> DelayVectors<'a> {
    /// Number of vectors.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether there is no vector (never, for a view built by [`Embedding::vectors`] or kept
    /// non-empty by [`DelayVectors::take`]).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The embedding dimension `d`.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// The delay `T_d` in samples.
    pub fn delay(&self) -> usize {
        self.delay
    }

    /// The record the vectors are taken from.
    pub fn record(&self) -> &'a [f64] {
        self.x
    }

    /// The first `count` vectors only (all of them if there are fewer).
    pub fn take(self, count: usize) -> Self {
        Self {
            len: self.len.min(count),
            ..self
        }
    }

    /// Vector `S(n)`, or `None` if `n ≥ len()`.
    #[inline]
    pub fn get(&self, n: usize) -> Option<DelayVector<'a>> {
        (n < self.len).then(|| DelayVector {
            x: &self.x[n..],
            dim: self.dim,
            delay: self.delay,
        })
    }

    /// Vector `S(n)` for `n < len()` (checked by the caller).
    #[inline]
    pub(crate) fn at(&self, n: usize) -> DelayVector<'a> {
        debug_assert!(n < self.len);
        DelayVector {
            x: &self.x[n..],
            dim: self.dim,
            delay: self.delay,
        }
    }

    /// All vectors in order.
    pub fn iter(&self) -> impl ExactSizeIterator<Item = DelayVector<'a>> + 'a {
        let (x, dim, delay) = (self.x, self.dim, self.delay);
        (0..self.len).map(move |n| DelayVector {
            x: &x[n..],
            dim,
            delay,
        })
    }
}

/// One delay vector `S(n)`: a strided view on the record.
#[derive(Debug, Clone, Copy)]
pub struct DelayVector<'a> {
    /// The record from sample `n` on.
    x: &'a [f64],
    dim: usize,
    delay: usize,
}

impl<'a> DelayVector<'a> {
    /// The dimension `d`.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Component `k` (`x_{n+k T_d}`), or `None` if `k ≥ d`.
    #[inline]
    pub fn component(&self, k: usize) -> Option<f64> {
        (k < self.dim).then(|| self.x[k * self.delay])
    }

    /// The `d` components in order.
    #[inline]
    pub fn iter(&self) -> std::iter::Copied<Take<StepBy<Iter<'a, f64>>>> {
        self.x.iter().step_by(self.delay).take(self.dim).copied()
    }

    /// Copies the components into `out`, to fill a caller's buffer in a hot loop.
    ///
    /// # Panics
    /// If `out.len() != d`.
    #[inline]
    pub fn copy_to(&self, out: &mut [f64]) {
        assert_eq!(
            out.len(),
            self.dim,
            "buffer length differs from the embedding dimension"
        );
        for (o, v) in out.iter_mut().zip(self.iter()) {
            *o = v;
        }
    }
}
