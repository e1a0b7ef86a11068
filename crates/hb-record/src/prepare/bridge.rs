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
//! are.
//!
//! - **Its error** is the cubic's remainder: on a sine of amplitude `A` and angular frequency
//!   `ω` sampled every `h`, at most `A (ω h)^4` times 1/6, 1/2, 3/2 and 3 for gaps of 1, 2, 3
//!   and 4 samples (4e-5 `A` for one sample at 50 samples per period of the fastest motion).
//! - **Its noise**: the cubic's weights carry the four samples' noise into a bridged sample, at
//!   most 0.97, 1.17, 1.39 and 1.61 times one sample's for gaps of 1, 2, 3 and 4 samples, and
//!   growing about as `m / 4` beyond (2.6 at 8, 16.5 at 64). So no longer gap is bridged
//!   ([`MAX_BRIDGE`]).
//! - **Only searched samples are its nodes**: a gap is bridged only between pieces of at least
//!   [`SpikeParams::MIN_SAMPLES`] samples, each searched for spikes (and repaired as asked)
//!   before the fill; a shorter piece is not searched, and stays apart.
//! - **On the circle** the far side's branch is the one nearest the line that leaves the near
//!   side with the mean of the two sides' steps, so that a fast whirl keeps its turns and a
//!   motion that turns back within the gap gains none. Where the far side lies more than a
//!   quarter turn off that line (a coarsely sampled angle that reverses twice within the gap),
//!   its turn cannot be told: the gap is left as it is, and the note counts it.

use std::ops::Range;

use circle_signal::{Domain, SpikeParams, wrap};

/// The most samples a bridged gap may miss: beyond, the cubic through two samples on each side
/// carries more than 1.61 times one sample's noise into the samples it stands for (see the
/// [module documentation](self)).
pub const MAX_BRIDGE: usize = 4;

/// The gaps between consecutive `pieces` (ranges of one grid, in order) that miss at most
/// `limit` samples, between pieces of at least [`SpikeParams::MIN_SAMPLES`] samples (searched
/// for spikes): gap `i` lies between `pieces[i]` and `pieces[i + 1]`.
pub(crate) fn bridgeable(pieces: &[Range<usize>], limit: usize) -> Vec<usize> {
    if limit == 0 {
        return Vec::new();
    }
    let searched = |p: &Range<usize>| p.len() >= SpikeParams::MIN_SAMPLES.max(2);
    pieces
        .windows(2)
        .enumerate()
        .filter(|(_, w)| w[1].start - w[0].end <= limit && searched(&w[0]) && searched(&w[1]))
        .map(|(i, _)| i)
        .collect()
}

/// The far side of a gap on the circle, `end..start` of `x`: the near and far sides' steps, and
/// the far side's first sample on the branch nearest the line that leaves the near side with
/// their mean, with its distance from that line.
fn far_branch(x: &[f64], end: usize, start: usize) -> (f64, f64, f64, f64) {
    let m = start - end;
    let (y0, y1, y2, y3) = (x[end - 2], x[end - 1], x[start], x[start + 1]);
    let (near, far) = (wrap(y1 - y0), wrap(y3 - y2));
    let guess = y1 + (m + 1) as f64 * 0.5 * (near + far);
    let off = wrap(y2 - guess);
    (near, far, guess + off, off)
}

/// Whether the angle `x` (on the circle) tells its turn across the gap `end..start`: its far
/// side within a quarter turn of the line that leaves the near side with the mean of both sides'
/// steps.
pub(crate) fn turn_clear(x: &[f64], end: usize, start: usize) -> bool {
    far_branch(x, end, start).3.abs() <= std::f64::consts::FRAC_PI_2
}

/// Fills the samples `end..start` of `x` (a gap: `x[end - 2..end]` and `x[start..start + 2]`
/// hold samples) with the cubic through the two samples on each side, on `domain`: on the
/// circle the four samples unwrapped across the gap (the far side's branch the one nearest the
/// line that leaves the near side with the mean of both sides' steps) and the result wrapped
/// into `[-π, π)`.
pub(crate) fn fill(x: &mut [f64], end: usize, start: usize, domain: Domain) {
    let m = start - end;
    let (y0, y1, y2, y3) = (x[end - 2], x[end - 1], x[start], x[start + 1]);
    let (u0, u1, u2, u3) = match domain {
        Domain::Line => (y0, y1, y2, y3),
        Domain::Circle => {
            let (near, far, u2, _) = far_branch(x, end, start);
            (y1 - near, y1, u2, u2 + far)
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

    /// Every sample of `x` on `truth`'s point of the circle, and wrapped into [-π, π).
    fn assert_on_the_circle(x: &[f64], truth: &[f64]) {
        for (n, (&x, &truth)) in x.iter().zip(truth).enumerate() {
            assert!(wrap(x - truth).abs() < 1e-12, "sample {n}: {x} against {truth}");
            assert!((-PI..PI).contains(&x), "sample {n}: {x}");
        }
    }

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
        assert_on_the_circle(&x, &truth);
    }

    #[test]
    fn a_sine_is_bridged_within_the_cubics_remainder() {
        // 50 samples per period, the gap centred on the sine's crest, where its fourth
        // derivative is largest: the error is the documented bound to within the crest's
        // curvature over the gap.
        let h = 2.0 * PI / 50.0;
        for (m, factor) in [(1usize, 1.0 / 6.0), (2, 0.5), (3, 1.5), (4, 3.0)] {
            let centre = 10.0 + (m as f64 - 1.0) / 2.0;
            let f = |n: f64| ((n - centre) * h + PI / 2.0).sin();
            let mut x: Vec<f64> = (0..30).map(|n| f(n as f64)).collect();
            for v in &mut x[10..10 + m] {
                *v = f64::NAN;
            }
            fill(&mut x, 10, 10 + m, Domain::Line);
            let worst = (10..10 + m)
                .map(|n| (x[n] - f(n as f64)).abs())
                .fold(0.0, f64::max);
            let bound = factor * h.powi(4);
            assert!(
                worst <= bound && worst > 0.9 * bound,
                "gap of {m}: {worst:e} against {bound:e}"
            );
        }
    }

    #[test]
    fn an_angle_that_turns_back_twice_within_a_gap_is_left_unbridged() {
        // 16 samples a period of a swing of 3 rad: across a gap of 4 it reverses twice, and
        // the far side lies more than a quarter turn off the line from the near side.
        let f = |n: f64| 3.0 * (n * 2.0 * PI / 16.0).sin() + 0.4 * (n * 2.0 * PI / 5.0).sin();
        let x: Vec<f64> = (0..20).map(|n| wrap(f(n as f64))).collect();
        let unclear = (2..14).filter(|&end| !turn_clear(&x, end, end + 4)).count();
        assert!(unclear > 0);
        // A whirl and the crest of a sine sampled finely are clear.
        let whirl: Vec<f64> = (0..20)
            .map(|n| wrap(2.5 * n as f64 + 0.01 * (n * n) as f64))
            .collect();
        let sine: Vec<f64> = (0..20).map(|n| (n as f64 * 2.0 * PI / 50.0).sin()).collect();
        for end in 2..14 {
            assert!(turn_clear(&whirl, end, end + 4) && turn_clear(&sine, end, end + 4));
        }
    }

    #[test]
    fn only_short_gaps_between_searched_pieces_are_bridged() {
        let pieces = vec![0..10, 11..20, 23..30, 31..36, 37..50, 60..80];
        assert_eq!(bridgeable(&pieces, 0), Vec::<usize>::new());
        // 10..11 misses 1; 20..23 misses 3; 30..31 and 36..37 border a piece of 5 samples, too
        // short for the spike search; 50..60 misses 10.
        assert_eq!(bridgeable(&pieces, 1), vec![0]);
        assert_eq!(bridgeable(&pieces, 3), vec![0, 1]);
        assert_eq!(bridgeable(&pieces, 10), vec![0, 1, 4]);
        assert_eq!(joined(&pieces, &[0, 1, 4]), vec![0..30, 31..36, 37..80]);
        assert_eq!(joined(&pieces, &[]), pieces);
        assert_eq!(joined(&pieces, &[0, 1, 2, 3, 4]), vec![0..80]);
    }

    #[test]
    fn a_motion_that_turns_back_within_a_gap_gains_no_turn() {
        // 0.72 rad a step into the gap and out of it the other way: the line through the near
        // side alone would land 3.6 rad off, on the wrong branch.
        let f = |n: f64| 3.0 - 0.12 * (n - 3.5) * (n - 3.5);
        let mut x: Vec<f64> = (0..8).map(|n| wrap(f(n as f64))).collect();
        let truth = x.clone();
        for v in &mut x[2..6] {
            *v = f64::NAN;
        }
        fill(&mut x, 2, 6, Domain::Circle);
        assert_on_the_circle(&x, &truth);
    }

    #[test]
    fn the_noise_a_bridge_carries_is_at_most_its_documented_gain() {
        // The root sum of squares of the cubic's weights at each bridged sample.
        let gain = |m: usize| {
            let mut worst: f64 = 0.0;
            for k in 0..m {
                let mut x = vec![0.0; m + 4];
                let mut sum = 0.0;
                for node in [0, 1, m + 2, m + 3] {
                    x.iter_mut().for_each(|v| *v = 0.0);
                    x[node] = 1.0;
                    fill(&mut x, 2, m + 2, Domain::Line);
                    sum += x[2 + k] * x[2 + k];
                }
                worst = worst.max(sum.sqrt());
            }
            worst
        };
        for (m, documented) in [(1, 0.97), (2, 1.17), (3, 1.39), (4, 1.61)] {
            assert!((gain(m) - documented).abs() < 0.005, "{m}: {}", gain(m));
        }
        assert!((gain(64) - 16.5).abs() < 0.05, "{}", gain(64));
    }
}
