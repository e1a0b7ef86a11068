//! Distinct orbits among close-return segments.

use crate::metric::Distance;
use circle_signal::Segment;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Where a segment sits in the [`Catalogue`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Assignment {
    /// Index of the segment's orbit in [`Catalogue::orbits`].
    pub orbit: usize,
    /// Cyclic shift `r` (samples, `0 ≤ r < kP`) that aligns the segment with its orbit's
    /// representative: `x[rep.start() + i]` agrees with `x[start + (i + r) mod kP]` for every `i`.
    /// `r ≡ rep.start() − start (mod P)`, so aligned samples share the phase of the forcing.
    pub shift: usize,
    /// `max_i |x[rep.start() + i] − x[start + (i + r) mod kP]|` in the search's metric (`< ε`; zero
    /// for the representative itself).
    pub distance: f64,
}

/// One distinct unstable periodic orbit: the segments that are passages near it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Orbit {
    /// Period `k` in forcing periods.
    pub period: usize,
    /// Index in [`Catalogue::segments`] of the member of least recurrence error.
    pub representative: usize,
    /// Indices in [`Catalogue::segments`] of all members (the representative included), ascending.
    pub members: Vec<usize>,
}

/// Segments and distinct orbits of one period.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct PeriodCount {
    /// Period `k` in forcing periods.
    pub period: usize,
    /// Close-return segments of that period.
    pub segments: usize,
    /// Distinct orbits of that period.
    pub orbits: usize,
}

/// The close-return segments of a record grouped into distinct orbits.
///
/// Two segments `A` (start `a`) and `B` (start `b`) of one period `k`, `L = kP` samples each,
/// **agree** when for some cyclic shift `r = r₀ + sP`, `s = 0, …, k − 1`,
/// `r₀ = (a − b) mod P`,
///
/// ```text
/// max_{0 ≤ i < L} | x[a + i] − x[b + (i + r) mod L] | < ε
/// ```
///
/// in the search's metric, `ε` the absolute tolerance. Every sample of the period is compared (not
/// only the `k` stroboscopic ones: a position alone at `k` instants does not pin down an orbit,
/// and for `k = 1` it is a single number), and aligned samples always share the phase of the
/// forcing (`a + i ≡ b + i + r (mod P)`): in a forced system a periodic orbit is a closed curve in
/// `(x, ẋ, t mod T)`, and a shift by a fraction of the forcing period is another solution. When
/// `a ≡ b (mod P)` the shifts are the whole forcing periods `sP`. A shifted segment wraps around
/// its own end, as a periodic orbit would; its close return keeps the seam continuous (within `ε`
/// at the samples of the delay vector).
///
/// Grouping is by representative, so it is deterministic and never chains: the segments of each
/// period are taken by increasing error (then start); each joins the first orbit (in order of
/// creation) whose representative it agrees with, or else founds a new orbit and is its
/// representative. So the representative is the member of least error and every member agrees
/// with it. Orbits are numbered by period, then by the start of the representative.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Catalogue {
    tolerance: f64,
    max_period: usize,
    segments: Vec<Segment>,
    assignments: Vec<Assignment>,
    orbits: Vec<Orbit>,
}

impl Catalogue {
    /// The absolute tolerance `ε` used for both the search and the grouping.
    pub fn tolerance(&self) -> f64 {
        self.tolerance
    }

    /// The segments, ordered by period, then start (as the search returned them).
    pub fn segments(&self) -> &[Segment] {
        &self.segments
    }

    /// The distinct orbits, ordered by period, then start of the representative.
    pub fn orbits(&self) -> &[Orbit] {
        &self.orbits
    }

    /// One assignment per segment (same indices as [`segments`](Self::segments)).
    pub fn assignments(&self) -> &[Assignment] {
        &self.assignments
    }

    /// The orbit id (index in [`orbits`](Self::orbits)) of segment `segment`.
    ///
    /// # Panics
    /// If `segment` is not an index of [`segments`](Self::segments).
    pub fn orbit_of(&self, segment: usize) -> usize {
        self.assignments[segment].orbit
    }

    /// The representative segment of each distinct orbit, in orbit order.
    pub fn representatives(&self) -> impl ExactSizeIterator<Item = &Segment> + '_ {
        self.orbits.iter().map(|o| &self.segments[o.representative])
    }

    /// Segments and distinct orbits for every period `1..=k_max`, zeros included.
    pub fn counts(&self) -> Vec<PeriodCount> {
        let mut counts: Vec<PeriodCount> = (1..=self.max_period)
            .map(|period| PeriodCount {
                period,
                segments: 0,
                orbits: 0,
            })
            .collect();
        for s in &self.segments {
            counts[s.period() - 1].segments += 1;
        }
        for o in &self.orbits {
            counts[o.period - 1].orbits += 1;
        }
        counts
    }
}

/// Groups `segments` (sorted by period, then start; all in bounds, `len = period · p`), the periods
/// in parallel.
pub(crate) fn group<D: Distance>(
    x: &[f64],
    segments: Vec<Segment>,
    p: usize,
    max_period: usize,
    tolerance: f64,
    dist: D,
) -> Catalogue {
    let mut ranges = Vec::new();
    let mut first = 0;
    while first < segments.len() {
        let k = segments[first].period();
        let end = first + segments[first..].iter().take_while(|s| s.period() == k).count();
        ranges.push(first..end);
        first = end;
    }
    let per_period: Vec<(Vec<Assignment>, Vec<usize>)> = ranges
        .par_iter()
        .map(|r| group_period(x, &segments[r.clone()], p, tolerance, dist))
        .collect();
    let mut assignments = Vec::with_capacity(segments.len());
    let mut orbits: Vec<Orbit> = Vec::new();
    for (r, (local, reps)) in ranges.iter().zip(per_period) {
        let offset = orbits.len();
        orbits.extend(reps.iter().map(|&rep| Orbit {
            period: segments[r.start].period(),
            representative: r.start + rep,
            members: Vec::new(),
        }));
        for (i, mut a) in local.into_iter().enumerate() {
            a.orbit += offset;
            orbits[a.orbit].members.push(r.start + i);
            assignments.push(a);
        }
    }
    Catalogue {
        tolerance,
        max_period,
        segments,
        assignments,
        orbits,
    }
}

/// The segments of one period (sorted by start): assignments with local orbit ids, numbered by
/// representative start, and the local index of each orbit's representative.
fn group_period<D: Distance>(
    x: &[f64],
    segments: &[Segment],
    p: usize,
    tolerance: f64,
    dist: D,
) -> (Vec<Assignment>, Vec<usize>) {
    let mut order: Vec<usize> = (0..segments.len()).collect();
    order.sort_by(|&i, &j| {
        segments[i]
            .error()
            .total_cmp(&segments[j].error())
            .then(i.cmp(&j))
    });
    let unset = Assignment {
        orbit: usize::MAX,
        shift: 0,
        distance: 0.0,
    };
    let mut assignments = vec![unset; segments.len()];
    // Representatives in order of creation.
    let mut reps: Vec<usize> = Vec::new();
    for &i in &order {
        let found = reps.iter().enumerate().find_map(|(o, &rep)| {
            best_shift(x, &segments[rep], &segments[i], p, tolerance, dist).map(|(shift, distance)| {
                Assignment {
                    orbit: o,
                    shift,
                    distance,
                }
            })
        });
        assignments[i] = found.unwrap_or_else(|| {
            reps.push(i);
            Assignment {
                orbit: reps.len() - 1,
                shift: 0,
                distance: 0.0,
            }
        });
    }
    // Renumber by representative start (segments are sorted by start, so by representative index).
    let mut by_start: Vec<usize> = (0..reps.len()).collect();
    by_start.sort_by_key(|&o| reps[o]);
    let mut new_id = vec![0; reps.len()];
    for (rank, &o) in by_start.iter().enumerate() {
        new_id[o] = rank;
    }
    for a in &mut assignments {
        a.orbit = new_id[a.orbit];
    }
    (assignments, by_start.iter().map(|&o| reps[o]).collect())
}

/// The phase-aligned cyclic shift of `seg` that best matches `rep`, if its distance is `< tol`.
fn best_shift<D: Distance>(
    x: &[f64],
    rep: &Segment,
    seg: &Segment,
    p: usize,
    tol: f64,
    dist: D,
) -> Option<(usize, f64)> {
    let len = rep.len();
    let a = &x[rep.start()..rep.start() + len];
    let b = &x[seg.start()..seg.start() + len];
    let r0 = (rep.start() % p + p - seg.start() % p) % p;
    let mut best: Option<(usize, f64)> = None;
    for r in (r0..len).step_by(p) {
        let bound = best.map_or(tol, |(_, d)| d);
        // Most shifts fail at once: reject on the first sample before the full comparison.
        if dist.between(a[0], b[r]) >= bound {
            continue;
        }
        // a[i] against b[(i + r) mod len]: b[r..] then b[..r].
        let (head, tail) = a.split_at(len - r);
        let mut worst = 0.0_f64;
        for (&u, &v) in head.iter().zip(&b[r..]).chain(tail.iter().zip(&b[..r])) {
            worst = worst.max(dist.between(u, v));
            if worst >= bound {
                break;
            }
        }
        if worst < bound {
            best = Some((r, worst));
        }
    }
    best
}
