//! The close-return search's parameters and errors, records in pieces, the circle distance of its
//! scan, and the recurrence error of one delay vector.
use circle_signal::circle_distance;
use std::f64::consts::PI;
use upo_search::{CloseReturns, Domain, SampleClock, Segment, UpoError};

fn clock(p: usize) -> SampleClock {
    SampleClock::nondimensional(p).unwrap()
}

#[test]
fn builder_validates() {
    assert!(CloseReturns::new(&clock(25), 5).is_ok());
    for bad in [0.0, -0.1, 0.5, 0.7, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            CloseReturns::builder(&clock(25), 5).tolerance(bad).build(),
            Err(UpoError::InvalidTolerance { .. })
        ));
    }
    assert!(SampleClock::nondimensional(0).is_err());
    let odd = SampleClock::from_step(1.0, 0.3).unwrap();
    assert!(matches!(
        CloseReturns::new(&odd, 5),
        Err(UpoError::Clock(circle_signal::CircleError::NotWholePeriod { .. }))
    ));
    assert!(matches!(
        CloseReturns::new(&clock(25), 0),
        Err(UpoError::InvalidCount { name: "delay", .. })
    ));
    assert!(matches!(
        CloseReturns::builder(&clock(25), 5).max_period(0).build(),
        Err(UpoError::InvalidCount {
            name: "max_period",
            ..
        })
    ));
    assert!(matches!(
        CloseReturns::builder(&clock(25), 5).dimension(0).build(),
        Err(UpoError::InvalidCount {
            name: "dimension",
            ..
        })
    ));
    assert!(matches!(
        CloseReturns::builder(&clock(usize::MAX / 2), 5)
            .max_period(3)
            .build(),
        Err(UpoError::InvalidCount {
            name: "max_period",
            ..
        })
    ));
    let s = CloseReturns::new(&clock(25), 5).unwrap();
    assert_eq!(
        (s.tolerance(), s.max_period(), s.dimension(), s.domain()),
        (0.03, 16, 2, Domain::Circle)
    );
}

#[test]
fn short_and_non_finite_records_are_errors() {
    let s = CloseReturns::builder(&clock(10), 3)
        .max_period(2)
        .dimension(3)
        .build()
        .unwrap();
    assert_eq!(s.needed_len(2), Some(27));
    let x = vec![0.0; 26];
    assert_eq!(
        s.search(&x),
        Err(UpoError::TooShort {
            len: 26,
            needed: 27,
            period: 2
        })
    );
    let mut x = vec![0.5; 27];
    assert!(s.search(&x).is_ok());
    x[13] = f64::NAN;
    assert!(matches!(s.search(&x), Err(UpoError::NonFinite { index: 13, .. })));
    x[13] = f64::NEG_INFINITY;
    assert!(matches!(
        s.catalogue(&x),
        Err(UpoError::NonFinite { index: 13, .. })
    ));
    assert!(matches!(
        s.return_error(&x, 0, 1),
        Err(UpoError::NonFinite { index: 13, .. })
    ));
    let lin = CloseReturns::builder(&clock(10), 3)
        .max_period(2)
        .domain(Domain::Line)
        .build()
        .unwrap();
    assert_eq!(
        lin.search(&[2.0; 40]),
        Err(UpoError::ConstantSignal { value: 2.0 })
    );
}

#[test]
fn pieces_are_searched_apart_and_catalogued_together() {
    // A quasi-random angle with a whirling period-2 orbit laid twice: once in each piece of a
    // record whose gap is NaN.
    let p = 10;
    let orbit: Vec<f64> = (0..2 * p)
        .map(|i| circle_signal::wrap(PI * i as f64 / p as f64 + 0.3 * (0.7 * i as f64).sin()))
        .collect();
    let noise = |n: usize| circle_signal::wrap(1.7 * (n as f64 * 2.399).sin() + n as f64 * 0.61);
    let mut piece: Vec<f64> = (0..30).map(noise).collect();
    piece.extend(orbit.iter().chain(&orbit[..5]));
    piece.extend((100..130).map(noise));
    // A gap that keeps the phase of the forcing: the orbit is the same orbit in both pieces.
    let gap = 15;
    let mut x = piece.clone();
    x.extend(std::iter::repeat_n(f64::NAN, gap));
    x.extend(&piece);
    let second = piece.len() + gap;
    let pieces = [0..piece.len(), second..x.len()];
    let s = CloseReturns::builder(&clock(p), 1).max_period(2).build().unwrap();
    let alone = s.search(&piece).unwrap();
    assert!(!alone.is_empty());
    let both = s.search_pieces(&x, &pieces).unwrap();
    // The same segments, moved into the second piece, sorted by period then start.
    let mut expected: Vec<(usize, usize)> = alone
        .iter()
        .flat_map(|seg| [(seg.period(), seg.start()), (seg.period(), seg.start() + second)])
        .collect();
    expected.sort();
    let found: Vec<(usize, usize)> = both.iter().map(|seg| (seg.period(), seg.start())).collect();
    assert_eq!(found, expected);
    // No segment reads the gap; one orbit per distinct orbit of a piece.
    assert!(both.iter().all(|seg| {
        pieces
            .iter()
            .any(|r| r.contains(&seg.start()) && r.contains(&seg.closing()))
    }));
    let one = s.catalogue(&piece).unwrap();
    let catalogue = s.catalogue_pieces(&x, &pieces).unwrap();
    assert_eq!(catalogue.orbits().len(), one.orbits().len());
    assert_eq!(catalogue.segments().len(), 2 * one.segments().len());
    // Without the pieces, the gap is an error; bad pieces are errors.
    assert!(matches!(s.search(&x), Err(UpoError::NonFinite { .. })));
    let (empty, beyond) = (4..4, 0..x.len() + 1);
    for bad in [&[0..5, 3..9][..], &[0..5, empty], &[beyond]] {
        assert!(matches!(
            s.search_pieces(&x, bad),
            Err(UpoError::Clock(circle_signal::CircleError::BadPiece { .. }))
        ));
    }
    assert!(matches!(
        s.search_pieces(&x, &[0..10, 20..30]),
        Err(UpoError::TooShort { len: 10, .. })
    ));
}

#[test]
fn constant_angle_is_one_period_one_orbit() {
    // Every n returns with error 0 at every period: one run, one segment at n = 0, and the
    // longer periods are repetitions of it.
    let s = CloseReturns::builder(&clock(4), 1).max_period(3).build().unwrap();
    let segs = s.search(&[1.0; 30]).unwrap();
    assert_eq!(segs, vec![Segment::new(0, 1, &clock(4), 0.0, 30).unwrap()]);
}

#[test]
fn fast_circle_distance_matches_circle_signal() {
    // Every sample within [−π, π]: the scan takes its branch-free circle distance. At P = 2, with
    // d = 1 and k_max = 1, a record of three samples has one delay vector, at n = 0, and its return
    // error is that distance between the last sample and the first, reported as the error of a
    // segment when below ε. The largest tolerance below 1/2 makes ε the largest number below π, so
    // every distance but π itself is read exactly; π is never below ε, so there it must give no
    // segment.
    let s = CloseReturns::builder(&clock(2), 1)
        .tolerance(0.5_f64.next_down())
        .max_period(1)
        .dimension(1)
        .build()
        .unwrap();
    let eps = s.absolute_tolerance(&[0.0; 3]).unwrap();
    assert_eq!(eps, PI.next_down());
    let vals = [-PI, -3.0, -1.0, -1e-300, 0.0, 1e-17, 0.5, 3.0, PI - 1e-15, PI];
    for &a in &vals {
        for &b in &vals {
            let want = circle_distance(a, b);
            let segs = s.search(&[b, 0.0, a]).unwrap();
            if want < eps {
                assert_eq!(segs.len(), 1, "{a} {b}");
                assert_eq!(segs[0].error(), want, "{a} {b}");
            } else {
                assert_eq!(want, PI, "{a} {b}");
                assert!(segs.is_empty(), "{a} {b}: {segs:?}");
            }
        }
    }
}

#[test]
fn return_error_bounds() {
    let s = CloseReturns::builder(&clock(5), 2).max_period(1).build().unwrap();
    let x: Vec<f64> = (0..20).map(|i| (i as f64 * 0.3).sin()).collect();
    assert!(s.return_error(&x, 12, 1).is_ok());
    assert_eq!(
        s.return_error(&x, 13, 1),
        Err(UpoError::TooShort {
            len: 20,
            needed: 21,
            period: 1
        })
    );
    assert!(matches!(
        s.return_error(&x, 0, 0),
        Err(UpoError::InvalidCount { .. })
    ));
    let want = circle_distance(x[5], x[0]).max(circle_distance(x[7], x[2]));
    assert_eq!(s.return_error(&x, 0, 1).unwrap(), want);
}
