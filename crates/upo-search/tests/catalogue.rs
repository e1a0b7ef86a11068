//! The catalogue on records built so that the close returns are known passages: the shift that
//! aligns a segment with its representative keeps the phase of the forcing, and segments are
//! grouped by the representative of least error, orbits numbered by its start, and counted per
//! period.
use upo_search::{CloseReturns, Domain, Orbit, PeriodCount, SampleClock};

fn clock(p: usize) -> SampleClock {
    SampleClock::nondimensional(p).unwrap()
}

/// Fill between the passages: `lo + width · frac(n α)`, α the golden ratio's fractional part, so
/// that two fill samples `k` apart differ by `width · min(frac(k α), 1 − frac(k α))` (up to
/// rounding), the same for every `n`.
fn fill(n: usize, lo: f64, width: f64) -> f64 {
    lo + width * (n as f64 * 0.618_033_988_749_895).fract()
}

/// The tolerance (a fraction of the span of `x`) that makes the absolute tolerance `eps` on the
/// line.
fn fraction_for(x: &[f64], eps: f64) -> f64 {
    let (lo, hi) = x.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
        (l.min(v), h.max(v))
    });
    eps / (hi - lo)
}

/// The close-return search of both tests on the line record `x`: `p` samples per period,
/// periods 1 and 2, d = 1, absolute tolerance `eps`.
fn line_search(x: &[f64], p: usize, eps: f64) -> CloseReturns {
    CloseReturns::builder(&clock(p), 1)
        .tolerance(fraction_for(x, eps))
        .max_period(2)
        .dimension(1)
        .domain(Domain::Line)
        .build()
        .unwrap()
}

#[test]
fn shift_aligns_forcing_phase() {
    // An orbit of period 2, P = 3, as a function of absolute time: x[n] = pattern[n mod 6], held
    // for one period and its closing sample (error 0) at starts whose offsets from the first are
    // ≡ 3, 1, 1 (mod 6), as 3, 7, 13 are, and 2, 4, 5: started one forcing period later, and part
    // way through a forcing period. Between the passages, fill in [5.5, 9.5): at least 0.5 from the
    // orbit, and 0.58 (3 samples apart) or 1.17 (6 apart) from itself, so no other close return.
    let pattern = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0];
    let offsets = [0, 3, 7, 13, 2, 4, 5];
    let starts: Vec<usize> = offsets.iter().enumerate().map(|(i, &o)| 6 + 30 * i + o).collect();
    let mut x: Vec<f64> = (0..starts[starts.len() - 1] + 20)
        .map(|n| fill(n, 5.5, 4.0))
        .collect();
    for &s in &starts {
        for n in s..=s + 6 {
            x[n] = pattern[n % 6];
        }
    }
    let search = line_search(&x, 3, 0.1);
    let cat = search.catalogue(&x).unwrap();
    assert!((cat.tolerance() - 0.1).abs() < 1e-15, "{}", cat.tolerance());
    let found: Vec<(usize, usize, f64)> = cat
        .segments()
        .iter()
        .map(|s| (s.start(), s.period(), s.error()))
        .collect();
    let expected: Vec<(usize, usize, f64)> = starts.iter().map(|&s| (s, 2, 0.0)).collect();
    assert_eq!(found, expected);
    // All errors are 0: the representative is the first passage, at start 6 ≡ 0 (mod 6).
    assert_eq!(
        cat.orbits(),
        [Orbit {
            period: 2,
            representative: 0,
            members: (0..starts.len()).collect()
        }]
    );
    for (i, &start) in starts.iter().enumerate().skip(1) {
        let a = cat.assignments()[i];
        let r = a.shift;
        assert_eq!(a.distance, 0.0);
        assert_eq!((start + r) % 6, 0, "start {start} shift {r}");
        assert_eq!(r % 3, (6 - start % 3) % 3);
    }
}

#[test]
fn groups_by_representative_and_counts() {
    // P = 4, period-1 passages (four samples and the closing sample) at starts 8, 24, 40, 56:
    // the orbit `pattern` closing 0.02 off, again closing 0.01 off, a different orbit of the same
    // period (10 + pattern, closing exactly), then a perturbed copy of the first (pattern + 0.01,
    // closing 0.03 off). Between them, fill in [4.5, 9.5): at least 0.5 from every passage, and
    // 2.4 (4 samples apart) or 0.28 (8 apart) from itself, so no other close return.
    let pattern = [0.0, 1.0, 2.0, 3.0];
    let mut x: Vec<f64> = (0..72).map(|n| fill(n, 4.5, 5.0)).collect();
    let passages = [(8, 0.0, 0.02), (24, 0.0, 0.01), (40, 10.0, 0.0), (56, 0.01, 0.03)];
    for &(start, offset, error) in &passages {
        for (i, &v) in pattern.iter().enumerate() {
            x[start + i] = offset + v;
        }
        x[start + 4] = offset + pattern[0] + error;
    }
    let search = line_search(&x, 4, 0.05);
    let cat = search.catalogue(&x).unwrap();
    assert!((cat.tolerance() - 0.05).abs() < 1e-15, "{}", cat.tolerance());
    assert_eq!(cat.segments().len(), 4);
    for (s, &(start, _, error)) in cat.segments().iter().zip(&passages) {
        assert_eq!((s.start(), s.period()), (start, 1));
        assert!((s.error() - error).abs() < 1e-12, "{s:?}");
    }
    assert_eq!(cat.orbits().len(), 2);
    // Least error of the first orbit is segment 1; orbits numbered by representative start.
    assert_eq!(
        cat.orbits()[0],
        Orbit {
            period: 1,
            representative: 1,
            members: vec![0, 1, 3]
        }
    );
    assert_eq!(
        cat.orbits()[1],
        Orbit {
            period: 1,
            representative: 2,
            members: vec![2]
        }
    );
    assert_eq!(cat.orbit_of(3), 0);
    assert!((cat.assignments()[3].distance - 0.01).abs() < 1e-12);
    assert_eq!(
        cat.counts(),
        vec![
            PeriodCount {
                period: 1,
                segments: 4,
                orbits: 2
            },
            PeriodCount {
                period: 2,
                segments: 0,
                orbits: 0
            }
        ]
    );
    assert_eq!(
        cat.representatives().map(|s| s.start()).collect::<Vec<_>>(),
        vec![24, 40]
    );
}
