//! Windows of a record: their validation, their starts and errors, records that are too short or
//! not finite, and records in pieces.
use proptest::prelude::*;
use upo_search::{Domain, OrbitSource, SampleClock, Segment, UpoError, Windows};

fn clock(p: usize) -> SampleClock {
    SampleClock::nondimensional(p).unwrap()
}

#[test]
fn windows_of_pieces_stay_inside_them() {
    let w = Windows::new(&clock(4)).unwrap();
    let mut x: Vec<f64> = (0..30).map(|n| (n as f64 * 0.3).sin()).collect();
    x[20..23].fill(f64::NAN);
    let pieces = [0..20, 23..30, 30..30];
    assert!(matches!(
        w.windows_pieces(&x, &pieces),
        Err(UpoError::Clock(circle_signal::CircleError::BadPiece {
            index: 2,
            ..
        }))
    ));
    let segs = w.windows_pieces(&x, &pieces[..2]).unwrap();
    // 12-sample windows and their closing sample: starts 0, 4 in the first piece; the second
    // (7 samples) holds none.
    let starts: Vec<usize> = segs.iter().map(Segment::start).collect();
    assert_eq!(starts, [0, 4]);
    assert!(segs.iter().all(|s| s.closing() < 20));
    assert!(matches!(
        w.windows_pieces(&x, &pieces[1..2]),
        Err(UpoError::TooShort {
            len: 7,
            needed: 13,
            ..
        })
    ));
    x[3] = f64::NAN;
    assert!(matches!(
        w.windows_pieces(&x, &[0..2, 3..20]),
        Err(UpoError::NonFinite { index: 3, .. })
    ));
}

#[test]
fn defaults_and_validation() {
    let w = Windows::new(&clock(25)).unwrap();
    assert_eq!((w.periods(), w.step(), w.len()), (3, 25, 75));
    assert_eq!(w.domain(), Domain::Circle);
    assert!(SampleClock::nondimensional(1).is_err());
    assert!(Windows::builder(&clock(25)).periods(0).build().is_err());
    assert!(Windows::builder(&clock(25)).step(0).build().is_err());
    assert!(matches!(
        Windows::builder(&clock(usize::MAX / 2)).periods(3).build(),
        Err(UpoError::InvalidCount {
            name: "window periods",
            ..
        })
    ));
}

#[test]
fn consecutive_and_overlapping_windows() {
    let x: Vec<f64> = (0..101).map(|n| (n as f64 * 0.1).sin()).collect();
    // Consecutive 2-period windows at P = 10: starts 0, 20, .., 80 (80 + 20 = 100 < 101).
    let w = Windows::builder(&clock(10)).periods(2).step(20).build().unwrap();
    let s = w.segments(&x).unwrap();
    assert_eq!(
        s.iter().map(|s| s.start()).collect::<Vec<_>>(),
        [0, 20, 40, 60, 80]
    );
    assert!(s.iter().all(|s| s.period() == 2 && s.len() == 20));
    // One sample fewer: the last window loses its closing sample.
    assert_eq!(w.segments(&x[..100]).unwrap().len(), 4);
    // Default step of one period: starts 0, 10, .., 80.
    let s = Windows::builder(&clock(10))
        .periods(2)
        .build()
        .unwrap()
        .segments(&x)
        .unwrap();
    assert_eq!(s.len(), 9);
    assert_eq!(s[8].start(), 80);
    // The error is how far the window is from closing.
    let e = (x[80 + 20] - x[80]).abs();
    assert!((s[8].error() - e).abs() < 1e-15);
}

#[test]
fn bad_records() {
    let w = Windows::builder(&clock(10)).periods(3).build().unwrap();
    assert_eq!(
        w.segments(&[0.0; 30]),
        Err(UpoError::TooShort {
            len: 30,
            needed: 31,
            period: 3
        })
    );
    assert_eq!(w.segments(&[0.0; 31]).unwrap().len(), 1);
    let mut x = vec![0.0; 40];
    x[33] = f64::NAN;
    assert!(matches!(
        w.segments(&x),
        Err(UpoError::NonFinite { index: 33, .. })
    ));
}

proptest! {
    /// Every window fits the record with its closing sample; starts are the multiples of the
    /// step; the next start would not fit; `count` agrees.
    #[test]
    fn windows_tile_the_record(p in 2usize..30, k in 1usize..5, step in 1usize..80, n in 0usize..600) {
        let w = Windows::builder(&clock(p)).periods(k).step(step).build().unwrap();
        let x = vec![0.5; n];
        match w.segments(&x) {
            Ok(s) => {
                prop_assert_eq!(s.len(), w.count(n));
                for (i, seg) in s.iter().enumerate() {
                    prop_assert_eq!(seg.start(), i * step);
                    prop_assert_eq!(seg.len(), k * p);
                    prop_assert!(seg.start() + seg.len() < n);
                }
                prop_assert!(s.len() * step + k * p >= n);
            }
            Err(UpoError::TooShort { needed, .. }) => {
                prop_assert_eq!(needed, k * p + 1);
                prop_assert!(n <= k * p);
            }
            Err(e) => prop_assert!(false, "{e}"),
        }
    }
}
