//! Close returns on synthetic records with known orbits, on the paper's data set, and the
//! invariants of the search and the catalogue.
use circle_signal::{max_circle_distance, wrap};
use proptest::prelude::*;
use proptest::test_runner::RngSeed;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::{PI, TAU};
use upo_search::{Catalogue, CloseReturns, Domain, OrbitSource, SampleClock, Segment, UpoError};

fn clock(p: usize) -> SampleClock {
    SampleClock::nondimensional(p).unwrap()
}

/// Uniform noise on the circle, seeded.
fn noise(rng: &mut ChaCha8Rng, n: usize) -> Vec<f64> {
    (0..n).map(|_| rng.random_range(-PI..PI)).collect()
}

/// `reps` exact copies of `pattern`.
fn repeat(pattern: &[f64], reps: usize) -> Vec<f64> {
    pattern
        .iter()
        .copied()
        .cycle()
        .take(pattern.len() * reps)
        .collect()
}

/// The record of the paper's data set (`t,theta`, `#` comments, one header line).
fn paper_theta() -> Vec<f64> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/fixtures/paper_dataset.csv"
    );
    let text = std::fs::read_to_string(path).expect("paper_dataset.csv");
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .skip(1)
        .map(|l| {
            l.split(',')
                .nth(1)
                .expect("two columns")
                .trim()
                .parse::<f64>()
                .expect("a number")
        })
        .collect()
}

/// The delay vector `S(n)` of dimension `d`, delay `td`.
fn delay_vector(x: &[f64], n: usize, d: usize, td: usize) -> Vec<f64> {
    (0..d).map(|c| x[n + c * td]).collect()
}

/// Checks every segment against the definition, recomputed from the samples.
fn verify(search: &CloseReturns, x: &[f64], segments: &[Segment]) {
    let (p, d, td) = (search.samples_per_period(), search.dimension(), search.delay());
    let eps = search.absolute_tolerance(x).unwrap();
    for s in segments {
        assert_eq!(s.len(), s.period() * p);
        assert!(
            s.start() + s.len() + (d - 1) * td < x.len(),
            "{s:?} out of bounds"
        );
        let a = delay_vector(x, s.start(), d, td);
        let b = delay_vector(x, s.start() + s.len(), d, td);
        let recomputed = match search.domain() {
            Domain::Circle => max_circle_distance(&b, &a),
            Domain::Line => a.iter().zip(&b).map(|(u, v)| (u - v).abs()).fold(0.0, f64::max),
        };
        assert_eq!(s.error(), recomputed, "{s:?}");
        assert!(s.error() < eps, "{s:?} eps {eps}");
    }
}

/// P = 20; noise, a period-1 oscillation held 6 forcing periods, noise, a period-3 whirling orbit
/// (one backward turn per 3 forcing periods, crossing ±π) held 3 times, noise.
fn spliced_record() -> (Vec<f64>, usize, usize) {
    let p = 20;
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let one: Vec<f64> = (0..p)
        .map(|i| 2.9 * (TAU * i as f64 / p as f64 + 0.3).sin())
        .collect();
    let three: Vec<f64> = (0..3 * p)
        .map(|i| wrap(1.0 - TAU * i as f64 / (3 * p) as f64 + 0.5 * (TAU * i as f64 / p as f64).sin()))
        .collect();
    let mut x = noise(&mut rng, 200);
    let start_one = x.len();
    x.extend(repeat(&one, 6));
    x.extend(noise(&mut rng, 237));
    let start_three = x.len();
    x.extend(repeat(&three, 3));
    x.extend(noise(&mut rng, 200));
    (x, start_one, start_three)
}

#[test]
fn spliced_orbits_are_found_at_their_starts() {
    let (x, start_one, start_three) = spliced_record();
    // The whirling piece does cross ±π.
    assert!(
        x[start_three..start_three + 60]
            .windows(2)
            .any(|w| (w[1] - w[0]).abs() > PI)
    );
    let search = CloseReturns::builder(&clock(20), 3)
        .tolerance(0.01)
        .max_period(6)
        .dimension(3)
        .build()
        .unwrap();
    let segments = search.segments(&x).unwrap();
    verify(&search, &x, &segments);
    let found: Vec<(usize, usize)> = segments.iter().map(|s| (s.start(), s.period())).collect();
    assert_eq!(found, vec![(start_one, 1), (start_three, 3)]);
    assert!(segments.iter().all(|s| s.error() == 0.0));
    // The repetitions exist (error 0 at 2, 3, 4, 5 forcing periods, and at 6 for the period-3
    // orbit) and were dropped by the divisor rule.
    for k in 2..=5 {
        assert_eq!(search.return_error(&x, start_one, k).unwrap(), 0.0);
    }
    assert_eq!(search.return_error(&x, start_three, 6).unwrap(), 0.0);
    // The period-3 orbit does not close after 1 or 2 forcing periods.
    assert!(search.return_error(&x, start_three, 1).unwrap() > 2.0);
    assert!(search.return_error(&x, start_three, 2).unwrap() > 2.0);
}

#[test]
fn divisor_rule_drops_the_period_2_copy_of_a_period_1_orbit() {
    let (x, start_one, _) = spliced_record();
    let search = CloseReturns::builder(&clock(20), 3)
        .tolerance(0.01)
        .max_period(2)
        .dimension(3)
        .build()
        .unwrap();
    let eps = search.absolute_tolerance(&x).unwrap();
    assert!(search.return_error(&x, start_one, 2).unwrap() < eps);
    let segments = search.search(&x).unwrap();
    assert!(segments.iter().any(|s| s.period() == 1 && s.start() == start_one));
    assert!(!segments.iter().any(|s| s.period() == 2), "{segments:?}");
}

#[test]
fn linear_metric_uses_the_span_of_the_record() {
    // A displacement: the period-1 piece scaled onto the line, noise of span 20.
    let (x, start_one, _) = spliced_record();
    let y: Vec<f64> = x.iter().map(|v| 10.0 * v / PI).collect();
    let search = CloseReturns::builder(&clock(20), 3)
        .tolerance(0.01)
        .max_period(2)
        .dimension(3)
        .domain(Domain::Line)
        .build()
        .unwrap();
    let (lo, hi) = y.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
        (l.min(v), h.max(v))
    });
    assert_eq!(search.absolute_tolerance(&y).unwrap(), 0.01 * (hi - lo));
    let segments = search.search(&y).unwrap();
    verify(&search, &y, &segments);
    assert!(segments.iter().any(|s| s.period() == 1 && s.start() == start_one));
}

/// An orbit of period 2 (P = 10) as a function of absolute time: `x_n = orbit(n mod 20)`, so that
/// copies are exact.
fn orbit_a(n: usize) -> f64 {
    let t = TAU * (n % 20) as f64 / 20.0;
    2.0 * t.sin() + 0.8 * (2.0 * t + 0.4).cos()
}

#[test]
fn catalogue_merges_passages_of_one_orbit() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let mut x = noise(&mut rng, 100);
    // Passage 1 at its first forcing period (start 100 ≡ 0 mod 20).
    x.extend((100..160).map(orbit_a));
    x.extend(noise(&mut rng, 150));
    // Passage 2 of the same orbit entered at its second forcing period (start 310 ≡ 10 mod 20).
    x.extend((310..370).map(orbit_a));
    x.extend(noise(&mut rng, 130));
    // A different orbit: the same curve half a forcing period late against the forcing.
    x.extend((500..560).map(|n| orbit_a(n + 5)));
    x.extend(noise(&mut rng, 143));
    // Passage 3 of the first orbit, entered mid forcing period (start 703 ≡ 3 mod 10).
    x.extend((703..763).map(orbit_a));
    x.extend(noise(&mut rng, 100));
    // A small tolerance: at the edges of a passage a delay vector mixes noise and orbit samples, and
    // may return by chance when the noise lands near the orbit (a genuine, if short, close return).
    let search = CloseReturns::builder(&clock(10), 2)
        .tolerance(0.002)
        .max_period(4)
        .dimension(3)
        .build()
        .unwrap();
    let cat: Catalogue = search.catalogue(&x).unwrap();
    verify(&search, &x, cat.segments());
    let starts: Vec<(usize, usize)> = cat.segments().iter().map(|s| (s.start(), s.period())).collect();
    assert_eq!(starts, vec![(100, 2), (310, 2), (500, 2), (703, 2)]);
    assert_eq!(cat.orbits().len(), 2);
    let ids: Vec<usize> = (0..4).map(|i| cat.orbit_of(i)).collect();
    assert_eq!(ids, vec![0, 0, 1, 0]);
    let counts = cat.counts();
    assert_eq!((counts[1].segments, counts[1].orbits), (4, 2));
    // Shifts align samples of equal orbit phase: start + shift ≡ representative start (mod 20).
    let rep = cat.segments()[cat.orbits()[0].representative].start();
    for i in [0, 1, 3] {
        let a = cat.assignments()[i];
        assert_eq!((cat.segments()[i].start() + a.shift) % 20, rep % 20);
        assert_eq!(a.distance, 0.0);
    }
}

#[test]
fn errors_are_typed() {
    let search = CloseReturns::new(&clock(25), 5).unwrap();
    // 16 periods of 25 samples, plus the delay, plus the closing sample.
    assert_eq!(
        search.search(&vec![0.1; 405]),
        Err(UpoError::TooShort {
            len: 405,
            needed: 406,
            period: 16
        })
    );
    let mut x = vec![0.1; 500];
    x[42] = f64::INFINITY;
    assert_eq!(
        search.search(&x),
        Err(UpoError::NonFinite {
            index: 42,
            value: f64::INFINITY
        })
    );
    let msg = search.search(&[0.0; 10]).unwrap_err().to_string();
    assert!(msg.contains("10 samples") && msg.contains("406"), "{msg}");
}

#[test]
fn paper_dataset_close_returns() {
    let x = paper_theta();
    assert_eq!(x.len(), 30000);
    let search = CloseReturns::builder(&clock(25), 5)
        .tolerance(0.03)
        .max_period(16)
        .dimension(2)
        .build()
        .unwrap();
    let cat = search.catalogue(&x).unwrap();
    assert_eq!(cat.tolerance(), 0.03 * TAU);
    verify(&search, &x, cat.segments());
    let counts = cat.counts();
    assert_eq!(counts.len(), 16);
    for c in &counts {
        assert!(c.orbits <= c.segments, "{c:?}");
    }
    // The low periods are visited often on this attractor.
    for c in &counts[..3] {
        assert!(c.segments > 0 && c.orbits > 0, "{c:?}");
    }
    // Members agree with their representative within ε, and representatives have least error.
    for o in cat.orbits() {
        let rep = cat.segments()[o.representative];
        for &m in &o.members {
            let s = cat.segments()[m];
            assert_eq!(s.period(), o.period);
            assert!(rep.error() <= s.error());
            let a = cat.assignments()[m];
            assert!(a.distance < cat.tolerance());
            let recomputed = (0..s.len())
                .map(|i| {
                    circle_signal::circle_distance(x[rep.start() + i], x[s.start() + (i + a.shift) % s.len()])
                })
                .fold(0.0, f64::max);
            assert_eq!(a.distance, recomputed);
        }
    }
}

/// A record of noise and noisy periodic pieces, from a seed.
fn random_record(seed: u64, p: usize, linear: bool, lengths: std::ops::Range<usize>) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let target = rng.random_range(lengths);
    let mut x = Vec::with_capacity(target + 200);
    while x.len() < target {
        if rng.random_bool(0.4) {
            let n = rng.random_range(1..3 * p);
            x.extend(noise(&mut rng, n));
        } else {
            let q = rng.random_range(1..=3);
            let pattern = noise(&mut rng, q * p);
            let reps = rng.random_range(2..=4);
            let jitter = rng.random_range(0.0..0.3);
            let piece: Vec<f64> = repeat(&pattern, reps)
                .into_iter()
                .map(|v| wrap(v + jitter * rng.random_range(-1.0..1.0)))
                .collect();
            x.extend(piece);
        }
    }
    if linear {
        x.iter_mut().for_each(|v| *v *= 3.0);
    }
    x
}

/// The definition, written out naively with `return_error`.
fn naive(search: &CloseReturns, x: &[f64]) -> Vec<Segment> {
    let eps = search.absolute_tolerance(x).unwrap();
    let (p, reach) = (
        search.samples_per_period(),
        (search.dimension() - 1) * search.delay(),
    );
    let mut out = Vec::new();
    for k in 1..=search.max_period() {
        let errors: Vec<f64> = (0..x.len() - k * p - reach)
            .map(|n| search.return_error(x, n, k).unwrap())
            .collect();
        let mut n = 0;
        while n < errors.len() {
            if errors[n] >= eps {
                n += 1;
                continue;
            }
            let mut best = n;
            while n < errors.len() && errors[n] < eps {
                if errors[n] < errors[best] {
                    best = n;
                }
                n += 1;
            }
            let repeated = (1..k).any(|j| k % j == 0 && search.return_error(x, best, j).unwrap() < eps);
            if !repeated {
                out.push(Segment::new(best, k, search.clock(), errors[best], x.len()).unwrap());
            }
        }
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, rng_seed: RngSeed::Fixed(0x5eed_0f0b), ..ProptestConfig::default() })]

    #[test]
    fn search_equals_definition_and_catalogue_is_consistent(
        seed in any::<u64>(),
        p in 2usize..8,
        td in 1usize..4,
        d in 1usize..4,
        k_max in 1usize..5,
        e in 0.02..0.3f64,
        linear in any::<bool>(),
    ) {
        let x = random_record(seed, p, linear, 120..500);
        let metric = if linear { Domain::Line } else { Domain::Circle };
        let search = CloseReturns::builder(&clock(p), td).tolerance(e).max_period(k_max).dimension(d).domain(metric).build().unwrap();
        let Ok(cat) = search.catalogue(&x) else {
            // Only a record too short for k_max may fail here.
            prop_assert!(x.len() < search.needed_len(k_max).unwrap());
            return Ok(());
        };
        let segments = cat.segments();
        let eps = cat.tolerance();
        verify(&search, &x, segments);
        // The search is its definition.
        let expected = naive(&search, &x);
        prop_assert_eq!(segments, expected.as_slice());
        // Ordered by period, then start; no two segments of one period from one run.
        for w in segments.windows(2) {
            prop_assert!((w[0].period(), w[0].start()) < (w[1].period(), w[1].start()));
            if w[0].period() == w[1].period() {
                let k = w[0].period();
                prop_assert!((w[0].start() + 1..w[1].start()).any(|n| search.return_error(&x, n, k).unwrap() >= eps));
            }
        }
        // No segment closes at a proper divisor of its period.
        for s in segments {
            for j in (1..s.period()).filter(|j| s.period() % j == 0) {
                prop_assert!(search.return_error(&x, s.start(), j).unwrap() >= eps);
            }
        }
        // The orbits partition the segments; representatives have least error; members agree.
        let mut seen = vec![0usize; segments.len()];
        for (id, o) in cat.orbits().iter().enumerate() {
            prop_assert!(o.members.contains(&o.representative));
            for &m in &o.members {
                seen[m] += 1;
                prop_assert_eq!(cat.orbit_of(m), id);
                prop_assert_eq!(segments[m].period(), o.period);
                prop_assert!(segments[o.representative].error() <= segments[m].error());
                let a = cat.assignments()[m];
                prop_assert_eq!(a.shift % p, (segments[o.representative].start() + p - segments[m].start() % p) % p);
                prop_assert!(a.distance < eps);
            }
        }
        prop_assert!(seen.iter().all(|&c| c == 1));
        let counts = cat.counts();
        prop_assert_eq!(counts.iter().map(|c| c.segments).sum::<usize>(), segments.len());
        prop_assert_eq!(counts.iter().map(|c| c.orbits).sum::<usize>(), cat.orbits().len());
        prop_assert!(counts.iter().all(|c| c.orbits <= c.segments));
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, rng_seed: RngSeed::Fixed(0x0b10_c45e), ..ProptestConfig::default() })]

    /// Records longer than the scan's blocks (2048 samples), so that runs cross block boundaries.
    #[test]
    fn long_records_equal_definition(seed in any::<u64>(), p in 2usize..6, d in 1usize..4, e in 0.05..0.3f64) {
        let x = random_record(seed, p, false, 4000..9000);
        let search = CloseReturns::builder(&clock(p), 2).tolerance(e).max_period(4).dimension(d).build().unwrap();
        let segments = search.search(&x).unwrap();
        verify(&search, &x, &segments);
        let expected = naive(&search, &x);
        prop_assert_eq!(segments, expected);
    }
}

#[test]
fn paper_dataset_search_equals_definition() {
    let x = paper_theta();
    let search = CloseReturns::new(&clock(25), 5).unwrap();
    assert_eq!(search.search(&x).unwrap(), naive(&search, &x));
}
