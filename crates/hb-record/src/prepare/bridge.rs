//! Short gaps bridged: the samples a gap misses interpolated, in every column of the record, so
//! that the pieces on either side are analysed as one.
//!
//! A logger that drops rows now and then (a missed packet of a networked driver, a busy loop)
//! splits a record into many pieces, and no window of the weak form spans a gap: at one row in a
//! hundred missing, a 500 Hz record has no stretch of 1.5 s left. A gap of a few samples within
//! motion the record resolves well is bridged instead, on request
//! ([`PrepareOptions::bridge`](super::PrepareOptions::bridge)): each missing sample is the cubic
//! through the two samples on each side (Lagrange interpolation at their grid times), of the
//! angles unwrapped across the gap, of the displacements, drives and measured velocities as they
//! are. Its error is that of a cubic over `m + 3` steps: about `(ω h)^4 (m + 3)^4 / 100` of the
//! amplitude of a motion of angular frequency `ω` sampled every `h` (a few 1e-6 rad for a gap of
//! one sample at 50 samples per period of the fastest motion), and a bridged sample carries
//! no noise of its own beyond its neighbours'.

use std::ops::Range;

use circle_signal::{Domain, wrap};

/// The most samples a bridged gap may miss: beyond, a cubic through two samples on each side is
/// no measurement of what happened in between.
pub const MAX_BRIDGE: usize = 64;

/// The gaps between consecutive `pieces` (ranges of one grid, in order) that miss at most
/// `limit` samples and have at least two samples on each side: gap `i` lies between `pieces[i]`
/// and `pieces[i + 1]`.
pub(crate) fn bridgeable(pieces: &[Range<usize>], limit: usize) -> Vec<usize> {
    if limit == 0 {
        return Vec::new();
    }
    pieces
        .windows(2)
        .enumerate()
        .filter(|(_, w)| w[1].start - w[0].end <= limit && w[0].len() >= 2 && w[1].len() >= 2)
        .map(|(i, _)| i)
        .collect()
}

/// Fills the samples `end..start` of `x` (a gap: `x[end - 2..end]` and `x[start..start + 2]`
/// hold samples) with the cubic through the two samples on each side, on `domain`: on the
/// circle the four samples unwrapped across the gap (the far side's branch the one nearest the
/// line through the near side's two samples, so that a fast whirl keeps its turns) and the
/// result wrapped into `[-π, π)`.
pub(crate) fn fill(x: &mut [f64], end: usize, start: usize, domain: Domain) {
    let m = start - end;
    let (y0, y1, y2, y3) = (x[end - 2], x[end - 1], x[start], x[start + 1]);
    let (u0, u1, u2, u3) = match domain {
        Domain::Line => (y0, y1, y2, y3),
        Domain::Circle => {
            let u0 = y1 + wrap(y0 - y1);
            let guess = y1 + (m + 1) as f64 * (y1 - u0);
            let u2 = guess + wrap(y2 - guess);
            (u0, y1, u2, u2 + wrap(y3 - y2))
        }
    };
    // Nodes at grid steps -1, 0, m + 1, m + 2 from the gap's last sample before it.
    let nodes = [-1.0, 0.0, (m + 1) as f64, (m + 2) as f64];
    let values = [u0, u1, u2, u3];
    for (k, slot) in x[end..start].iter_mut().enumerate() {
        let s = (k + 1) as f64;
        let mut sum = 0.0;
        for (i, (&ni, &vi)) in nodes.iter().zip(&values).enumerate() {
            let weight: f64 = nodes
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, &nj)| (s - nj) / (ni - nj))
                .product();
            sum += weight * vi;
        }
        *slot = match domain {
            Domain::Line => sum,
            Domain::Circle => wrap(sum),
        };
    }
}

/// `pieces` with the gaps `bridged` (indices as [`bridgeable`] gives them, in order) closed.
pub(crate) fn joined(pieces: &[Range<usize>], bridged: &[usize]) -> Vec<Range<usize>> {
    let mut out: Vec<Range<usize>> = Vec::with_capacity(pieces.len() - bridged.len());
    let mut next = bridged.iter().peekable();
    for (i, piece) in pieces.iter().enumerate() {
        let joins_before = i > 0 && next.peek().is_some_and(|&&g| g == i - 1);
        match out.last_mut() {
            Some(last) if joins_before => {
                next.next();
                last.end = piece.end;
            }
            _ => out.push(piece.clone()),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn a_cubic_is_bridged_exactly_on_the_line() {
        let f = |n: f64| 0.3 - 1.2 * n + 0.05 * n * n - 0.002 * n * n * n;
        let mut x: Vec<f64> = (0..12).map(|n| f(n as f64)).collect();
        for v in &mut x[4..7] {
            *v = f64::NAN;
        }
        fill(&mut x, 4, 7, Domain::Line);
        for (n, v) in x.iter().enumerate() {
            assert!(
                (v - f(n as f64)).abs() < 1e-12,
                "sample {n}: {v} against {}",
                f(n as f64)
            );
        }
    }

    #[test]
    fn a_whirl_is_bridged_across_the_wrap_and_keeps_its_turns() {
        // 2.5 rad per step: the gap of two samples spans more than a turn.
        let f = |n: f64| 0.4 + 2.5 * n + 0.01 * n * n;
        let mut x: Vec<f64> = (0..10).map(|n| wrap(f(n as f64))).collect();
        let truth = x.clone();
        x[4] = f64::NAN;
        x[5] = f64::NAN;
        fill(&mut x, 4, 6, Domain::Circle);
        for n in 0..10 {
            assert!(
                wrap(x[n] - truth[n]).abs() < 1e-12,
                "sample {n}: {} against {}",
                x[n],
                truth[n]
            );
            assert!((-PI..PI).contains(&x[n]));
        }
    }

    #[test]
    fn a_smooth_motion_is_bridged_within_the_error_of_a_cubic() {
        // 50 samples per period, one sample missing: the error bound of the module docs.
        let h = 2.0 * PI / 50.0;
        let mut x: Vec<f64> = (0..20).map(|n| (n as f64 * h).sin()).collect();
        x[10] = f64::NAN;
        fill(&mut x, 10, 11, Domain::Line);
        let error = (x[10] - (10.0 * h).sin()).abs();
        assert!(error < h.powi(4) * 4f64.powi(4) / 100.0, "error {error}");
        assert!(error > 0.0);
    }

    #[test]
    fn only_short_gaps_with_two_samples_on_each_side_are_bridged() {
        let pieces = vec![0..5, 6..8, 11..14, 15..16, 17..20, 30..40];
        assert_eq!(bridgeable(&pieces, 0), Vec::<usize>::new());
        // 5..6 misses 1; 8..11 misses 3; 14..15 and 16..17 have one sample on a side; 20..30
        // misses 10.
        assert_eq!(bridgeable(&pieces, 1), vec![0]);
        assert_eq!(bridgeable(&pieces, 3), vec![0, 1]);
        assert_eq!(bridgeable(&pieces, 10), vec![0, 1, 4]);
        assert_eq!(joined(&pieces, &[0, 1, 4]), vec![0..14, 15..16, 17..40]);
        assert_eq!(joined(&pieces, &[]), pieces);
        assert_eq!(joined(&pieces, &[0, 1, 2, 3, 4]), vec![0..40]);
    }
}
