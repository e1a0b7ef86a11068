use std::cmp::Ordering;
use std::f64::consts::TAU;
use std::num::NonZeroUsize;

use kiddo::ImmutableKdTree;
use kiddo::dist::Chebyshev;
use rayon::prelude::*;

use crate::metric::Metric;
use crate::{DelayVectors, Domain, EmbeddingError, check_finite};

/// Largest dimension the k-d tree search handles.
pub const MAX_SEARCH_DIM: usize = 8;

/// Neighbours asked of the tree in the first query for one vector.
const FIRST_K: usize = 8;

/// The nearest neighbour of a delay vector.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Neighbour {
    /// Index `m` of the neighbour `S(m)`.
    pub index: usize,
    /// Its distance `|S(n) − S(m)|` (max norm of the per-component metric).
    pub distance: f64,
}

/// The nearest neighbour of every delay vector, by a k-d tree (kiddo), in parallel.
///
/// The neighbour of `S(n)` is the `S(m)` of least the maximum over components of [`Domain::distance`] among those with
/// `|m − n| > theiler` (the Theiler window; 0 excludes only `n` itself) and a distance above zero
/// (an exact copy of `S(n)` says nothing about its neighbourhood). `None` if no vector qualifies.
/// Among neighbours at the same distance any one may be returned.
///
/// The circle metric uses the tree's periodic boundary condition: each coordinate is shifted into
/// `[0, 2π)` and the tree measures `min(|a − b|, 2π − |a − b|)` per axis, which is the circle
/// distance; the Chebyshev (max) norm combines the axes. The returned distance is recomputed from
/// the record with the maximum over components of [`Domain::distance`].
///
/// # Errors
/// Non-finite samples, a dimension above [`MAX_SEARCH_DIM`], a Theiler window that leaves no
/// candidate (`theiler + 1 ≥ len`), or more than `u32::MAX` vectors.
pub fn nearest_neighbours(
    vectors: &DelayVectors<'_>,
    metric: Domain,
    theiler: usize,
) -> Result<Vec<Option<Neighbour>>, EmbeddingError> {
    let used = (vectors.len() - 1) + vectors.delay() * (vectors.dim() - 1) + 1;
    check_finite(&vectors.record()[..used.min(vectors.record().len())])?;
    if theiler.saturating_add(1) >= vectors.len() {
        return Err(EmbeddingError::TheilerTooLarge {
            theiler,
            points: vectors.len(),
        });
    }
    match vectors.dim() {
        1 => search::<1>(vectors, metric, theiler),
        2 => search::<2>(vectors, metric, theiler),
        3 => search::<3>(vectors, metric, theiler),
        4 => search::<4>(vectors, metric, theiler),
        5 => search::<5>(vectors, metric, theiler),
        6 => search::<6>(vectors, metric, theiler),
        7 => search::<7>(vectors, metric, theiler),
        8 => search::<8>(vectors, metric, theiler),
        dim => Err(EmbeddingError::InvalidParameter {
            name: "dim",
            value: dim as f64,
            why: "the neighbour search handles dimensions 1 to 8",
        }),
    }
}

fn search<const D: usize>(
    vectors: &DelayVectors<'_>,
    metric: Domain,
    theiler: usize,
) -> Result<Vec<Option<Neighbour>>, EmbeddingError> {
    let points: Vec<[f64; D]> = vectors
        .iter()
        .map(|s| {
            let mut p = [0.0; D];
            for (c, v) in p.iter_mut().zip(s.iter()) {
                *c = metric.tree_coordinate(v);
            }
            p
        })
        .collect();
    if u32::try_from(points.len()).is_err() {
        return Err(EmbeddingError::TooManyVectors {
            points: points.len(),
            max: u32::MAX as usize,
        });
    }
    // Exact copies are rare in measured data but the rule in a quantised record: group them only
    // when the first components (the samples themselves) repeat, which a sort of their bits shows.
    let copies = has_repeats(&points).then(|| Copies::new(&points));
    let distinct = copies
        .as_ref()
        .map_or(points.as_slice(), |c| c.distinct.as_slice());
    let tree: ImmutableKdTree<f64, D> =
        ImmutableKdTree::new_from_slice(distinct).map_err(|source| EmbeddingError::Tree {
            points: distinct.len(),
            source,
        })?;
    // Each distinct point that has no occurrence outside the window of n has one inside it, so at
    // most 2w + 1 of them (S(n)'s own among them) can come first: 2w + 2 always suffice. For a wide
    // window most are usually not needed: start with at most FIRST_K and double until one
    // qualifies.
    let first_k = (2 * theiler + 2).min(FIRST_K).min(distinct.len());
    let period = [TAU; D];
    Ok(points
        .par_iter()
        .enumerate()
        .map(|(n, p)| {
            let mut k = first_k;
            loop {
                let k_nz = NonZeroUsize::new(k)?;
                let found = match metric {
                    Domain::Line => tree.query(p).nearest_n::<Chebyshev<f64>>(k_nz).execute(),
                    Domain::Circle => tree
                        .query(p)
                        .periodic_boundary_condition(&period)
                        .nearest_n::<Chebyshev<f64>>(k_nz)
                        .execute(),
                };
                // Distance 0 is S(n)'s own group (S(n) and its exact copies).
                let admissible = found
                    .iter()
                    .filter(|r| r.distance > 0.0)
                    .find_map(|r| match &copies {
                        None => Some(r.item as usize).filter(|m| m.abs_diff(n) > theiler),
                        Some(c) => c.outside_window(r.item as usize, n, theiler),
                    });
                if let Some(index) = admissible {
                    let distance = metric.delay_distance(&vectors.at(n), &vectors.at(index));
                    return Some(Neighbour { index, distance });
                }
                if k >= distinct.len() {
                    return None;
                }
                k = (2 * k).min(distinct.len());
            }
        })
        .collect())
}

/// Whether two points share their first coordinate (bit for bit): if not, no two are equal.
fn has_repeats<const D: usize>(points: &[[f64; D]]) -> bool {
    let mut bits: Vec<u64> = points.iter().map(|p| p[0].to_bits()).collect();
    bits.par_sort_unstable();
    bits.windows(2).any(|w| w[0] == w[1])
}

/// The distinct points of a set and where each occurs, so that exact copies (a quantised record
/// repeats values) cost the tree nothing.
struct Copies<const D: usize> {
    /// The distinct points.
    distinct: Vec<[f64; D]>,
    /// Occurrences of `distinct[g]`: `indices[starts[g]..starts[g + 1]]`, ascending.
    starts: Vec<u32>,
    indices: Vec<u32>,
}

impl<const D: usize> Copies<D> {
    /// Groups `points` (fewer than 2³² of them) by exact equality.
    fn new(points: &[[f64; D]]) -> Self {
        let mut indices: Vec<u32> = (0..points.len() as u32).collect();
        let order = |a: &[f64; D], b: &[f64; D]| {
            a.iter()
                .zip(b)
                .map(|(x, y)| x.total_cmp(y))
                .find(|o| o.is_ne())
                .unwrap_or(Ordering::Equal)
        };
        // Stable: the occurrences of one point stay in ascending order.
        indices.par_sort_by(|&i, &j| order(&points[i as usize], &points[j as usize]));
        let mut distinct = Vec::with_capacity(points.len());
        let mut starts = Vec::with_capacity(points.len() + 1);
        for (pos, &i) in indices.iter().enumerate() {
            let p = &points[i as usize];
            if distinct.last().is_none_or(|q| order(q, p).is_ne()) {
                distinct.push(*p);
                starts.push(pos as u32);
            }
        }
        starts.push(indices.len() as u32);
        Self {
            distinct,
            starts,
            indices,
        }
    }

    /// An occurrence `m` of distinct point `group` with `|m − n| > w`, if any.
    #[inline]
    fn outside_window(&self, group: usize, n: usize, w: usize) -> Option<usize> {
        let occ = &self.indices[self.starts[group] as usize..self.starts[group + 1] as usize];
        let (first, last) = (*occ.first()? as usize, *occ.last()? as usize);
        if first + w < n {
            Some(first)
        } else if last > n + w {
            Some(last)
        } else {
            None
        }
    }
}
