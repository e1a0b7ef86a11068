//! The time stamps fitted to a grid: exact and printed clocks, gaps, glitches named or repaired,
//! a logger's clock that slips by its printed unit, jittering stamps reported or refused, a
//! logger's unsettled start or end left out or refused, and properties of the fit over any
//! stamps.
use hb_record::input::{
    GridOptions, GridRecord, GridReport, InputError, JITTER_WARNING, LEVEL_WINDOW, Location, ReadOptions,
    Record, RecordEnd, StampFault, read_bytes,
};
use proptest::prelude::*;

/// A fraction as a percentage with two significant digits (at least one decimal below 10 %), as
/// the report writes it.
struct Percent(f64);

impl std::fmt::Display for Percent {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let p = 100.0 * self.0;
        if p >= 10.0 {
            write!(f, "{p:.0} %")
        } else if p >= 0.1 {
            write!(f, "{p:.1} %")
        } else {
            write!(f, "{:.1e} %", p)
        }
    }
}

/// A record with these stamps (line numbers from 2, after a header) and values 0, 1, 2, ….
fn record(t: Vec<f64>) -> Record {
    Record {
        theta: (0..t.len()).map(|i| i as f64).collect(),
        lines: Some((0..t.len() as u64).map(|i| i + 2).collect()),
        t,
        ..Record::default()
    }
}

fn fit(t: Vec<f64>) -> Result<GridRecord, InputError> {
    GridRecord::fit(record(t), &GridOptions::default())
}

fn repair(t: Vec<f64>) -> Result<GridRecord, InputError> {
    GridRecord::fit(record(t), &GridOptions { repair: true })
}

/// `n` stamps `t0 + i · dt` printed with `decimals` decimals.
fn printed(n: usize, t0: f64, dt: f64, decimals: usize) -> Vec<f64> {
    (0..n)
        .map(|i| format!("{:.*}", decimals, t0 + i as f64 * dt).parse().unwrap())
        .collect()
}

#[test]
fn exact_grid_is_one_piece() {
    let u = fit((0..100).map(|n| 10.0 + n as f64 * 0.04).collect()).unwrap();
    assert!((u.dt - 0.04).abs() < 1e-15 && (u.t0 - 10.0).abs() < 1e-13);
    assert_eq!(u.pieces.len(), 1);
    assert_eq!(u.pieces[0].first, 0);
    assert_eq!(
        u.pieces[0].samples,
        (0..100).map(|i| i as f64).collect::<Vec<_>>()
    );
    assert!(u.repaired.is_empty());
    assert_eq!(u.sample_count(), 100);
    assert!(matches!(fit(vec![0.0]), Err(InputError::TooFewSamples { .. })));
    assert_eq!(fit(vec![3.0, 3.5]).unwrap().dt, 0.5);
}

/// The bound on the error of a least-squares step from stamps at grid indices `indices`,
/// each off by at most `e`: `e · Σ|n − n̄| / Σ(n − n̄)²`.
fn step_bound(indices: &[usize], e: f64) -> f64 {
    let count = indices.len() as f64;
    let mean = indices.iter().sum::<usize>() as f64 / count;
    let sxx: f64 = indices.iter().map(|&k| (k as f64 - mean).powi(2)).sum();
    let sabs: f64 = indices.iter().map(|&k| (k as f64 - mean).abs()).sum();
    e * sabs / sxx
}

#[test]
fn stamps_printed_to_4_decimals_at_2048_hz_fit() {
    // One minute at 2048 Hz: each stamp is off by up to 0.1 step.
    let dt = 1.0 / 2048.0;
    let n = 2048 * 60;
    let u = fit(printed(n, 0.0, dt, 4)).unwrap();
    let error = (u.dt - dt).abs() / dt;
    assert!(error < 1e-9, "relative error of the step {error:e}");
    assert!(u.t0.abs() < 0.1 * dt, "{}", u.t0);
    assert_eq!((u.pieces.len(), u.sample_count()), (1, n));
    // From any start, the step is within the bound of least squares.
    let indices: Vec<usize> = (0..n).collect();
    for t0 in [12.3456, 3.7, -1.23456789] {
        let u = fit(printed(n, t0, dt, 4)).unwrap();
        let bound = step_bound(&indices, 0.5e-4);
        assert!(
            (u.dt - dt).abs() <= bound,
            "{t0}: {} vs {dt}, bound {bound:e}",
            u.dt
        );
        assert!((u.t0 - t0).abs() < 0.1 * dt, "{}", u.t0);
    }
}

#[test]
fn stamps_printed_too_coarsely_ask_for_the_step() {
    for (rate, decimals) in [(2048.0, 3), (1500.0, 3), (300.0, 2)] {
        let t = printed(4096, 1.0, 1.0 / rate, decimals);
        match fit(t) {
            Err(e @ InputError::TimeUnresolved { .. }) => {
                let text = e.to_string();
                assert!(
                    text.contains(&format!("written with {decimals} decimals")),
                    "{text}"
                );
                assert!(text.contains("give its step"), "{text}");
            }
            other => panic!("{rate} Hz, {decimals} decimals: {other:?}"),
        }
    }
    // Stamps that the decimals write exactly fit, however few the decimals.
    assert!(fit(printed(4096, 1.0, 1e-3, 3)).is_ok());
}

#[test]
fn a_backwards_stamp_names_its_line() {
    let mut t: Vec<f64> = (0..50).map(|i| i as f64 * 0.1).collect();
    t[20] = 1.85; // between samples 18 and 19
    match fit(t.clone()) {
        Err(
            e @ InputError::TimeGlitch {
                at: Location::Line(22),
                fault: StampFault::Backwards { previous },
                isolated: true,
                ..
            },
        ) => {
            assert!((previous - 1.9).abs() < 1e-12);
            let text = e.to_string();
            assert!(text.starts_with("line 22: time 1.85 does not increase"), "{text}");
            assert!(
                text.contains("this sample is at 2:") && text.contains("can be repaired"),
                "{text}"
            );
        }
        other => panic!("{other:?}"),
    }
    let u = repair(t).unwrap();
    assert_eq!(u.pieces.len(), 1);
    assert_eq!(u.repaired.len(), 1);
    let r = u.repaired[0];
    assert_eq!((r.at, r.was), (Location::Line(22), 1.85));
    assert!((r.now - 2.0).abs() < 1e-12, "{r:?}");
}

#[test]
fn repair_fixes_isolated_glitches_of_every_kind() {
    let grid = |n: usize| -> Vec<f64> { (0..n).map(|i| 5.0 + i as f64 * 0.01).collect() };
    let cases: [(usize, f64, StampFault); 5] = [
        (30, 5.3045, StampFault::OffGrid), // off the grid by 0.45 step
        (30, 5.35, StampFault::OffGrid),   // on the grid, five steps ahead
        (30, 5.29, StampFault::Repeated),  // the previous stamp again
        (0, 4.996, StampFault::OffGrid),   // the first stamp, 0.4 step early
        (99, 5.0, StampFault::Backwards { previous: 5.98 }), // the last
    ];
    for (i, glitch, fault) in cases {
        let mut t = grid(100);
        let truth = t[i];
        t[i] = glitch;
        match fit(t.clone()) {
            Err(InputError::TimeGlitch {
                at,
                fault: f,
                isolated: true,
                expected,
                ..
            }) => {
                assert_eq!(at, Location::Line(i as u64 + 2), "{glitch}");
                assert!((expected - truth).abs() < 1e-9, "{glitch}: {expected}");
                match (fault, f) {
                    (StampFault::Backwards { previous: a }, StampFault::Backwards { previous: b }) => {
                        assert!((a - b).abs() < 1e-12)
                    }
                    _ => assert_eq!(f, fault, "{glitch}"),
                }
            }
            other => panic!("{glitch}: {other:?}"),
        }
        let u = repair(t).unwrap();
        assert_eq!(u.pieces.len(), 1, "{glitch}");
        assert_eq!(u.pieces[0].samples.len(), 100);
        assert_eq!(u.repaired.len(), 1);
        assert!(
            (u.repaired[0].now - truth).abs() < 1e-9,
            "{glitch}: {:?}",
            u.repaired
        );
        assert!((u.t0 - 5.0).abs() < 1e-9 && (u.dt - 0.01).abs() < 1e-12);
    }
}

/// A logger that drops a row and stamps the next one late: the count from its neighbours leaves
/// it two slots, and with repair it takes the free one its stamp is nearest (within 0.4 steps),
/// the gap staying where the row was dropped; without repair the error says it can be repaired
/// and where. Early or late, before or after the gap, a gap of one or of several samples, the
/// first or last sample with rows dropped beside it. (A few stamps from an end, a glitch beside
/// a gap makes an unsettled run there instead: a logger settling to its rate looks the same.)
#[test]
fn a_glitch_beside_a_gap_takes_its_nearest_free_slot_on_repair() {
    let grid = || -> Vec<f64> { (0..200).map(|i| i as f64 * 0.5).collect() };
    // (samples dropped, the glitch's sample, its shift in steps, where it lands, the pieces)
    type Case<'a> = (&'a [usize], usize, f64, usize, [std::ops::Range<usize>; 2]);
    let cases: [Case<'_>; 7] = [
        (&[70], 71, 0.38, 71, [0..70, 71..200]),
        (&[70], 69, -0.3, 69, [0..70, 71..200]),
        (&[70, 71, 72], 73, -0.35, 73, [0..70, 73..200]),
        (&[100], 101, -0.35, 101, [0..100, 101..200]),
        // The first or the last sample, with rows dropped beside it.
        (&[1], 0, -0.3, 0, [0..1, 2..200]),
        (&[198], 199, 0.3, 199, [0..198, 199..200]),
        (&[194, 195, 196, 197, 198], 199, 0.3, 199, [0..194, 199..200]),
    ];
    for (dropped, glitch, shift, lands, pieces) in cases {
        let mut t = grid();
        t[glitch] += shift * 0.5;
        let kept: Vec<f64> = t
            .iter()
            .enumerate()
            .filter(|(i, _)| !dropped.contains(i))
            .map(|(_, &v)| v)
            .collect();
        let line = kept.iter().position(|&v| v == t[glitch]).unwrap() as u64 + 2;
        match fit(kept.clone()) {
            Err(e @ InputError::TimeGlitch { isolated: true, .. }) => {
                let text = e.to_string();
                assert!(text.starts_with(&format!("line {line}:")), "{text}");
                assert!(
                    text.contains(&format!("this sample is at {}", lands as f64 * 0.5)),
                    "{text}"
                );
                assert!(text.contains("can be repaired"), "{text}");
            }
            other => panic!("{dropped:?}: {other:?}"),
        }
        let u = repair(kept).unwrap();
        assert_eq!(u.repaired.len(), 1, "{dropped:?}");
        assert_eq!(u.repaired[0].at, Location::Line(line));
        assert!(
            (u.repaired[0].now - lands as f64 * 0.5).abs() < 1e-9,
            "{:?}",
            u.repaired
        );
        let got: Vec<std::ops::Range<usize>> = u
            .pieces
            .iter()
            .map(|p| p.first..p.first + p.samples.len())
            .collect();
        assert_eq!(got, pieces, "{dropped:?}");
    }
}

#[test]
fn non_isolated_glitches_fail_even_with_repair() {
    let grid = || -> Vec<f64> { (0..100).map(|i| i as f64 * 0.5).collect() };
    let mut two = grid();
    (two[40], two[41]) = (20.2, 20.7); // two neighbours off the grid
    let mut swapped = grid();
    swapped.swap(60, 61);
    // The sample after a gap off the grid by more than NEAREST_SLOT (0.4) steps of its nearest
    // free slot, or nearest the slot of the sample after it: its slot is in doubt.
    let mut beside_a_gap = grid();
    beside_a_gap.remove(70);
    beside_a_gap[70] += 0.225;
    let mut nearest_taken = grid();
    nearest_taken.remove(70);
    nearest_taken[70] += 0.35;
    for (t, line) in [(two, 42), (swapped, 62), (beside_a_gap, 72), (nearest_taken, 72)] {
        for options in [GridOptions::default(), GridOptions { repair: true }] {
            match GridRecord::fit(record(t.clone()), &options) {
                Err(e @ InputError::TimeGlitch { isolated: false, .. }) => {
                    assert!(e.to_string().starts_with(&format!("line {line}:")), "{e}");
                    assert!(e.to_string().contains("cannot be repaired"), "{e}");
                }
                other => panic!("line {line}: {other:?}"),
            }
        }
    }
    // A clock that starts again: everything after is backwards.
    let mut reset = grid();
    for v in &mut reset[50..] {
        *v -= 20.0;
    }
    assert!(matches!(
        repair(reset),
        Err(InputError::TimeGlitch {
            at: Location::Line(52),
            fault: StampFault::Backwards { .. },
            isolated: false,
            ..
        })
    ));
    // Time going down all along.
    assert!(matches!(
        fit((0..10).map(|i| -(i as f64)).collect()),
        Err(InputError::TimeNotIncreasing {
            at: Location::Line(3),
            ..
        })
    ));
}

#[test]
fn a_duplicate_stamp_is_a_glitch() {
    let mut t: Vec<f64> = (0..64).map(|i| i as f64 / 64.0).collect();
    t[10] = t[9];
    match fit(t.clone()) {
        Err(InputError::TimeGlitch {
            at: Location::Line(12),
            fault: StampFault::Repeated,
            ..
        }) => {}
        other => panic!("{other:?}"),
    }
    let u = repair(t).unwrap();
    assert_eq!((u.pieces.len(), u.repaired[0].at), (1, Location::Line(12)));
    assert!((u.repaired[0].now - 10.0 / 64.0).abs() < 1e-12);
}

/// Stamps near the largest floating-point numbers: a grid was fitted, but the repaired time
/// of the middle stamp overflowed (found by the fuzz target `grid_fit`).
#[test]
fn stamps_whose_grid_overflows_are_refused() {
    let t = vec![
        -1.2089666594180364e308,
        4.104138993080699e-207,
        -1.1843625389819756e308,
    ];
    for options in [GridOptions::default(), GridOptions { repair: true }] {
        match GridRecord::fit(record(t.clone()), &options) {
            Err(e @ InputError::TimeOverflow { .. }) => {
                assert!(
                    e.to_string()
                        .starts_with("line 4: time -1.1843625389819756e308 is too far"),
                    "{e}"
                )
            }
            other => panic!("{options:?}: {other:?}"),
        }
    }
    // Large stamps whose grid stays finite fit.
    let large: Vec<f64> = (0..10).map(|i| 1e307 + f64::from(i) * 1e305).collect();
    let u = fit(large).unwrap();
    assert!((u.dt / 1e305 - 1.0).abs() < 1e-12 && (u.t0 / 1e307 - 1.0).abs() < 1e-12);
}

/// A stamp far off the others (a logger's first stamp before its clock was set, an end glitched
/// far away, a pause of a day) would make a grid of billions of samples: refused with its line,
/// before any of it is held. A gap that leaves the grid within bounds is a gap.
#[test]
fn a_gap_that_would_make_the_grid_huge_is_refused() {
    let clock: Vec<f64> = (0..2000).map(|i| 1.7e9 + f64::from(i) * 0.002).collect();
    let mut t = vec![0.0];
    t.extend(&clock[1..]);
    for options in [GridOptions::default(), GridOptions { repair: true }] {
        match GridRecord::fit(record(t.clone()), &options) {
            Err(e @ InputError::GapTooLong { .. }) => {
                let text = e.to_string();
                assert!(
                    text.starts_with("line 3: time 1700000000.002 follows 0 after a gap of"),
                    "{text}"
                );
                assert!(
                    text.contains("split the record there, or remove the stamp"),
                    "{text}"
                );
            }
            other => panic!("{options:?}: {other:?}"),
        }
    }
    let mut t = clock.clone();
    *t.last_mut().unwrap() = 1e10;
    assert!(matches!(fit(t), Err(InputError::GapTooLong { .. })));
    // A pause of a day in 4 s at 500 Hz: refused; of a minute: a gap.
    for (pause, refused) in [(86_400.0, true), (60.0, false)] {
        let t: Vec<f64> = (0..2000)
            .map(|i| f64::from(i) * 0.002 + if i >= 1000 { pause } else { 0.0 })
            .collect();
        let fitted = fit(t);
        assert_eq!(
            matches!(fitted, Err(InputError::GapTooLong { .. })),
            refused,
            "{pause}: {fitted:?}"
        );
        if !refused {
            assert_eq!(fitted.unwrap().pieces.len(), 2);
        }
    }
}

#[test]
fn gaps_split_the_record() {
    // Samples 0..100, then 103..200, then 250..300, stamped at 0.001 s printed to 5 decimals.
    let kept: Vec<usize> = (0..100).chain(103..200).chain(250..300).collect();
    let t: Vec<f64> = kept
        .iter()
        .map(|&k| format!("{:.5}", 7.0 + k as f64 * 0.001).parse().unwrap())
        .collect();
    let u = fit(t).unwrap();
    let firsts: Vec<usize> = u.pieces.iter().map(|p| p.first).collect();
    assert_eq!(firsts, vec![0, 103, 250]);
    let lengths: Vec<usize> = u.pieces.iter().map(|p| p.samples.len()).collect();
    assert_eq!(lengths, vec![100, 97, 50]);
    assert_eq!(u.pieces[1].samples[0], 100.0);
    assert!((u.dt - 0.001).abs() < 1e-12 && (u.t0 - 7.0).abs() < 1e-9);
    // A gap of two steps at the start too.
    let u = fit(vec![0.0, 2.0, 3.0, 4.0, 5.0]).unwrap();
    assert_eq!(u.pieces.iter().map(|p| p.first).collect::<Vec<_>>(), vec![0, 2]);
}

#[test]
fn a_step_given_is_one_piece() {
    let opts = ReadOptions {
        dt: Some(0.125),
        ..Default::default()
    };
    let r = read_bytes(b"1\n2\n3\n4\n", &opts).unwrap();
    let u = GridRecord::fit(r, &GridOptions::default()).unwrap();
    assert_eq!((u.t0, u.dt, u.pieces.len()), (0.0, 0.125, 1));
}

/// A logger's stamps at 500 Hz printed to 1 ms (3 decimals): the samples on an even grid from
/// `t0`, the logger's clock 1 ms behind the grid over the ranges `late` (it slips by -1 ms at
/// the start of each, by +1 ms at the end: single steps of 1 and 3 ms), and the stamps of
/// `glitches` 7 ms early (a step of -5 ms to each, then one of +9 ms).
fn logger_clock(n: usize, t0: f64, late: &[std::ops::Range<usize>], glitches: &[usize]) -> Vec<f64> {
    (0..n)
        .map(|i| {
            let behind = if late.iter().any(|r| r.contains(&i)) {
                1e-3
            } else {
                0.0
            };
            let early = if glitches.contains(&i) { 7e-3 } else { 0.0 };
            let stamp = t0 + i as f64 * 2e-3 - behind - early;
            format!("{stamp:.3}").parse().unwrap()
        })
        .collect()
}

/// Seeded uniform numbers in [0, 1) (splitmix64), and normal ones by Box–Muller.
struct Draws(u64);

impl Draws {
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    fn normal(&mut self) -> f64 {
        let (u, v) = (1.0 - self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}

/// How stamps jitter about their grid times.
#[derive(Debug, Clone, Copy)]
enum Jitter {
    /// Normal, with this standard deviation (a fraction of the step).
    Gaussian(f64),
    /// Uniform, with this standard deviation (a fraction of the step; half-width √3 times it).
    Uniform(f64),
}

/// `n` stamps at 500 Hz from `t0`, each moved by `jitter`, printed to 7 decimals (0.005 % of
/// the step), seeded.
fn jittered(n: usize, t0: f64, jitter: Jitter, seed: u64) -> Vec<f64> {
    let dt = 2e-3;
    let mut draws = Draws(seed);
    (0..n)
        .map(|i| {
            let off = match jitter {
                Jitter::Gaussian(s) => s * draws.normal(),
                Jitter::Uniform(s) => s * 3f64.sqrt() * (2.0 * draws.uniform() - 1.0),
            };
            let stamp = t0 + (i as f64 + off) * dt;
            format!("{stamp:.7}").parse().unwrap()
        })
        .collect()
}

/// The record: 250 s at 500 Hz printed to 1 ms, 25 147 stamps 1 ms behind the grid in
/// two runs, and two stamps 7 ms early three places apart.
const LATE: [std::ops::Range<usize>; 2] = [20_000..32_000, 70_000..83_147];
const EARLY: [usize; 2] = [76_000, 76_003];
const T0: f64 = 41.2374;

#[test]
fn a_slipping_logger_clock_fits_and_its_isolated_glitches_are_repaired() {
    let n = 125_000;
    let t = logger_clock(n, T0, &LATE, &EARLY);
    // Without repair: the first glitch, and the other one named.
    let e = fit(t.clone()).unwrap_err();
    let text = e.to_string();
    match e {
        InputError::TimeGlitch {
            at: Location::Line(76_002),
            fault: StampFault::Backwards { previous },
            isolated: true,
            others,
            other_count: 1,
            expected,
            ..
        } => {
            assert_eq!(others, [Location::Line(76_005)]);
            assert_eq!(previous, t[75_999]);
            // The grid lies within the 1.4 ms the stamps are off the true times.
            assert!((expected - (T0 + 152.0)).abs() < 1.4e-3, "{expected}");
        }
        other => panic!("{other:?}"),
    }
    let head = format!(
        "line 76002: time {} does not increase (previous sample at {})",
        t[76_000], t[75_999]
    );
    assert!(text.starts_with(&head), "{text}");
    assert!(
        text.ends_with("; 1 more glitch: line 76005: an isolated glitch, which can be repaired"),
        "{text}"
    );

    let u = repair(t.clone()).unwrap();
    assert_eq!((u.pieces.len(), u.sample_count()), (1, n));
    let at: Vec<Location> = u.repaired.iter().map(|r| r.at).collect();
    assert_eq!(at, [Location::Line(76_002), Location::Line(76_005)]);
    for r in &u.repaired {
        let Location::Line(line) = r.at else {
            unreachable!()
        };
        let i = line as usize - 2;
        assert_eq!(r.was, t[i]);
        assert!((r.now - (T0 + i as f64 * 2e-3)).abs() < 1.4e-3, "{r:?}");
    }
    // Every stamp within half a millisecond of the middle of its band (1 ms: the rounding of
    // the true times and the slip), so the step within the bound of least squares on that.
    let indices: Vec<usize> = (0..n).collect();
    let bound = step_bound(&indices, 0.5e-3);
    assert!((u.dt - 2e-3).abs() <= bound, "{} (bound {bound:e})", u.dt);
    assert!((u.t0 - T0).abs() < 1.4e-3, "{}", u.t0);

    let r = &u.report;
    assert_eq!(r.step, u.dt);
    assert!(r.resolution.is_some_and(|u| (u - 1e-3).abs() < 1e-15));
    let slips: Vec<Location> = r.slips.iter().map(|s| s.at).collect();
    assert_eq!(
        slips,
        [20_002, 32_002, 70_002, 83_149].map(Location::Line),
        "{:?}",
        r.slips
    );
    for (s, by) in r.slips.iter().zip([-1e-3, 1e-3, -1e-3, 1e-3]) {
        // The levels drift against the fitted grid (its slope is that of the stamps, slips and all).
        assert!((s.by - by).abs() < 1e-6, "{s:?}");
    }
    // The grid among the two levels, every stamp within a printed unit of it and on its level.
    assert!(r.max_deviation.abs() < 1e-3 && r.rms_deviation < r.max_deviation.abs());
    assert!(r.max_jitter.abs() < 1e-6 && r.rms_jitter < 1e-6, "{r:?}");
    assert!(r.within_printing() && r.is_notable() && !r.is_warning(), "{r:?}");
    let text = r.to_string();
    assert!(
        text.contains(
            "slips 4 time(s), at line 20002 (-0.001), line 32002 (+0.001), line 70002 (-0.001), line 83149 (+0.001)"
        ),
        "{text}"
    );
    assert!(
        text.contains("within their printed resolution of 0.001"),
        "{text}"
    );
    assert!(
        text.starts_with("the time stamps deviate from the even grid of step 0.002"),
        "{text}"
    );
    let by = format!(
        "by up to {} of the step (RMS {})",
        Percent(r.max_fraction()),
        Percent(r.rms_fraction())
    );
    assert!(text.contains(&by), "{text}");
}

#[test]
fn glitches_side_by_side_on_a_slipping_clock_stay_errors() {
    // Steps of -5, 2 and 9 ms: two stamps 7 ms early side by side.
    let t = logger_clock(
        20_000,
        T0,
        std::slice::from_ref(&(5_000..9_000)),
        &[12_000, 12_001],
    );
    for options in [GridOptions::default(), GridOptions { repair: true }] {
        match GridRecord::fit(record(t.clone()), &options) {
            Err(
                e @ InputError::TimeGlitch {
                    at: Location::Line(12_002),
                    isolated: false,
                    ..
                },
            ) => assert!(e.to_string().contains("1 more glitch: line 12003"), "{e}"),
            other => panic!("{options:?}: {other:?}"),
        }
    }
    // A run of stamps several units off is a run of glitches.
    let run: Vec<usize> = (5_000..5_010).collect();
    assert!(matches!(
        repair(logger_clock(20_000, T0, &[], &run)),
        Err(InputError::TimeGlitch {
            at: Location::Line(5_002),
            isolated: false,
            other_count: 9,
            ..
        })
    ));
    // A run one unit off is within the printing: a slip when it holds for more than half the
    // window, else nothing to report.
    let short = fit(logger_clock(
        20_000,
        T0,
        std::slice::from_ref(&(5_000..5_010)),
        &[],
    ))
    .unwrap();
    assert!(
        short.report.slips.is_empty() && short.report.within_printing(),
        "{:?}",
        short.report
    );
    let long = logger_clock(20_000, T0, std::slice::from_ref(&(5_000..5_100)), &[]);
    let u = fit(long).unwrap();
    let slips: Vec<Location> = u.report.slips.iter().map(|s| s.at).collect();
    assert_eq!(slips, [Location::Line(5_002), Location::Line(5_102)]);
}

#[test]
fn gaps_in_a_slipping_clock_split_the_record() {
    // 100 samples missing inside a run 1 ms behind the grid, 40 inside one on it.
    let t = logger_clock(30_000, T0, std::slice::from_ref(&(10_000..20_000)), &[]);
    let kept: Vec<usize> = (0..30_000)
        .filter(|i| !(15_000..15_100).contains(i) && !(25_000..25_040).contains(i))
        .collect();
    let u = fit(kept.iter().map(|&i| t[i]).collect()).unwrap();
    let firsts: Vec<usize> = u.pieces.iter().map(|p| p.first).collect();
    assert_eq!(firsts, [0, 15_100, 25_040]);
    assert_eq!(u.sample_count(), kept.len());
    let slips: Vec<Location> = u.report.slips.iter().map(|s| s.at).collect();
    assert_eq!(
        slips,
        [Location::Line(10_002), Location::Line(19_902)],
        "{:?}",
        u.report
    );
    assert!(u.report.within_printing(), "{:?}", u.report);
}

#[test]
fn a_clock_slipping_by_its_printed_unit_fits_at_any_rate() {
    // Runs one printed unit behind the grid, at resolutions from 0.044 to half a step.
    for (rate, decimals) in [(500.0, 3), (300.0, 3), (2048.0, 4), (1000.0, 4), (44_100.0, 6)] {
        let (dt, unit) = (1.0 / rate, 10f64.powi(-decimals));
        let late = [3_000..7_000, 12_000..12_500];
        let n = 20_000;
        let t: Vec<f64> = (0..n)
            .map(|i| {
                let behind = if late.iter().any(|r| r.contains(&i)) {
                    unit
                } else {
                    0.0
                };
                format!("{:.*}", decimals as usize, 3.21 + i as f64 * dt - behind)
                    .parse()
                    .unwrap()
            })
            .collect();
        let u = fit(t).unwrap_or_else(|e| panic!("{rate} Hz, {decimals} decimals: {e}"));
        assert_eq!((u.pieces.len(), u.sample_count()), (1, n));
        let indices: Vec<usize> = (0..n).collect();
        let bound = step_bound(&indices, unit) + 1e-12 * dt;
        assert!(
            (u.dt - dt).abs() <= bound,
            "{rate} Hz: {} (bound {bound:e})",
            u.dt
        );
        let r = &u.report;
        assert_eq!(r.slips.len(), 4, "{rate} Hz: {:?}", r.slips);
        for (s, (place, by)) in
            r.slips
                .iter()
                .zip([(3_000, -1.0), (7_000, 1.0), (12_000, -1.0), (12_500, 1.0)])
        {
            let Location::Line(line) = s.at else {
                unreachable!()
            };
            let off = (line as i64 - 2 - place).abs();
            assert!(off <= LEVEL_WINDOW as i64 / 2, "{rate} Hz: {s:?} for {place}");
            assert!((s.by / unit - by).abs() < 0.5, "{rate} Hz: {s:?}");
        }
        assert!(r.is_notable() && !r.is_warning(), "{rate} Hz: {r:?}");
        assert!(r.max_jitter.abs() <= unit, "{rate} Hz: {r:?}");
    }
}

#[test]
fn jittering_stamps_are_reported_or_refused() {
    let n = 50_000;
    for level in [0.001, 0.01, 0.04, 0.1] {
        for (seed, jitter) in [(1, Jitter::Gaussian(level)), (2, Jitter::Uniform(level))] {
            let u = fit(jittered(n, 7.0, jitter, seed)).unwrap_or_else(|e| panic!("{jitter:?}: {e}"));
            assert_eq!((u.pieces.len(), u.sample_count(), u.repaired.len()), (1, n, 0));
            let r = &u.report;
            assert!(r.slips.is_empty(), "{jitter:?}: {:?}", r.slips);
            assert!(r.is_notable() && !r.within_printing(), "{jitter:?}: {r:?}");
            assert_eq!(r.is_warning(), level > JITTER_WARNING, "{jitter:?}: {r:?}");
            // The deviations are the jitter's (the rounding to 7 decimals adds 1.4e-5 step RMS).
            let rms = r.rms_fraction();
            assert!((rms / level - 1.0).abs() < 0.03, "{jitter:?}: RMS {rms}");
            assert!(
                (r.jitter_fraction() / level - 1.0).abs() < 0.15,
                "{jitter:?}: {r:?}"
            );
            let max = r.max_fraction() / level;
            match jitter {
                Jitter::Uniform(_) => assert!(max <= 3f64.sqrt() * 1.001 + 0.03, "{jitter:?}: {max}"),
                Jitter::Gaussian(_) => assert!((3.5..5.5).contains(&max), "{jitter:?}: {max}"),
            }
            let text = r.to_string();
            assert!(
                text.contains(&format!("(RMS {})", Percent(r.rms_fraction())))
                    && text.contains("more than their printed resolution of 0.0000001 explains"),
                "{text}"
            );
            assert_eq!(
                text.contains("which moves them by as much"),
                r.is_warning(),
                "{text}"
            );
        }
    }
    // Beyond about a tenth of a step the stamps no longer tell the samples apart.
    for (seed, jitter) in [(3, Jitter::Gaussian(0.3)), (4, Jitter::Uniform(0.3))] {
        match fit(jittered(n, 7.0, jitter, seed)) {
            Err(e @ InputError::TimeUnresolved { scatter: Some(s), .. }) => {
                assert!((0.2..0.45).contains(&s), "{jitter:?}: {s}");
                assert!(e.to_string().contains("scattering about the grid by"), "{e}");
            }
            other => panic!("{jitter:?}: {other:?}"),
        }
    }
    // A glitch stands out of a small jitter: a stamp 0.45 step off among stamps that jitter
    // by 1 % of the step.
    let mut t = jittered(n, 7.0, Jitter::Gaussian(0.01), 5);
    t[1_000] += 0.45 * 2e-3;
    assert!(matches!(
        fit(t.clone()),
        Err(InputError::TimeGlitch {
            at: Location::Line(1_002),
            fault: StampFault::OffGrid,
            isolated: true,
            ..
        })
    ));
    let u = repair(t).unwrap();
    assert_eq!(u.repaired.len(), 1);
    assert!((u.repaired[0].now - (7.0 + 2.0)).abs() < 1e-5, "{:?}", u.repaired);
}

#[test]
fn clean_stamps_report_nothing_notable() {
    let u = fit(printed(4096, 12.3456, 1.0 / 2048.0, 4)).unwrap();
    assert!(
        u.report.slips.is_empty() && u.report.within_printing(),
        "{:?}",
        u.report
    );
    assert!(!u.report.is_notable());
    let u = fit((0..1000).map(|i| i as f64 * 0.01).collect()).unwrap();
    assert!(!u.report.is_notable(), "{:?}", u.report);
}

/// Fits stamps `t0 + n · dt` printed with the fewest decimals whose half unit is within 0.2
/// step, plus `extra`, at the indices of `runs` (lengths and the gaps after them), and checks
/// that the fit finds every sample's index and a step within the bound of least squares on
/// errors of at most half a unit ([`step_bound`]).
fn check_fit(t0: f64, dt: f64, extra: usize, runs: &[(usize, usize)]) -> Result<(), TestCaseError> {
    let decimals = ((2.5 / dt).log10().ceil().max(0.0) as usize + extra).min(12);
    let unit = 10f64.powi(-(decimals as i32));
    let mut indices = Vec::new();
    let mut firsts = Vec::new();
    let mut k = 0;
    for (len, gap) in runs {
        firsts.push(k);
        indices.extend(k..k + len);
        k += len + gap;
    }
    let t: Vec<f64> = indices
        .iter()
        .map(|&k| format!("{:.*}", decimals, t0 + k as f64 * dt).parse().unwrap())
        .collect();
    let theta: Vec<f64> = (0..t.len()).map(|i| (i as f64).sin()).collect();
    let rec = Record {
        t,
        theta: theta.clone(),
        lines: None,
        ..Record::default()
    };
    let u = GridRecord::fit(rec, &GridOptions::default()).map_err(|e| TestCaseError::fail(e.to_string()))?;
    prop_assert_eq!(u.pieces.iter().map(|p| p.first).collect::<Vec<_>>(), firsts);
    let joined: Vec<f64> = u.pieces.iter().flat_map(|p| p.samples.iter().copied()).collect();
    prop_assert_eq!(joined, theta);
    prop_assert!(u.repaired.is_empty());
    // Half a unit, and the rounding of the numbers themselves; the arithmetic of the fit.
    let e = 0.5 * unit + 1e-15 * (t0.abs() + k as f64 * dt);
    let bound = step_bound(&indices, e) + 1e-12 * dt;
    let off = (u.dt - dt).abs();
    prop_assert!(
        off <= bound,
        "step {} vs {dt}: off by {off:e}, bound {bound:e}",
        u.dt
    );
    Ok(())
}

proptest! {
    /// Rounding of up to 0.2 step, gaps up to 60 samples between runs of at least 20.
    #[test]
    fn fit_recovers_the_grid(
        t0 in -1e3..1e3f64,
        dt in 1e-5..10.0f64,
        extra in 0..2usize,
        runs in proptest::collection::vec((20..400usize, 2..60usize), 1..6),
    ) {
        check_fit(t0, dt, extra, &runs)?;
    }

    /// Any stamps at all: an error or a consistent grid, never a panic.
    #[test]
    fn fit_never_panics(
        t in proptest::collection::vec(
            prop_oneof![-1e3..1e3f64, Just(0.0), Just(1.0), -1e300..1e300f64, (0..40u32).prop_map(|k| k as f64 * 0.25)],
            0..40,
        ),
        repair in proptest::bool::ANY,
    ) {
        let n = t.len();
        if let Ok(u) = GridRecord::fit(record(t), &GridOptions { repair }) {
            prop_assert!(u.dt > 0.0 && u.dt.is_finite() && u.t0.is_finite());
            prop_assert_eq!(u.sample_count(), n);
            prop_assert_eq!(u.pieces[0].first, 0);
            prop_assert!(u.pieces.iter().all(|p| p.first as f64 <= 2f64.powi(53)));
            for w in u.pieces.windows(2) {
                prop_assert!(w[1].first > w[0].first + w[0].samples.len());
            }
            prop_assert!(repair || u.repaired.is_empty());
            let r = &u.report;
            prop_assert!(r.max_deviation.abs() < 0.5 * u.dt, "{:?}", r);
            prop_assert!(r.rms_deviation <= r.max_deviation.abs() * (1.0 + 1e-12), "{:?}", r);
            prop_assert!(r.max_jitter.is_finite() && r.slips.iter().all(|s| s.by.is_finite()), "{:?}", r);
            prop_assert!(!r.to_string().is_empty());
        }
    }

    /// Rounding of up to 0.002 step, gaps up to 5000 samples between runs of at least 20.
    #[test]
    fn fit_recovers_long_gaps(
        t0 in -1e3..1e3f64,
        dt in 1e-5..10.0f64,
        extra in 2..4usize,
        runs in proptest::collection::vec((20..400usize, 2..5000usize), 1..8),
    ) {
        check_fit(t0, dt, extra, &runs)?;
    }
}

/// A logger at 500 Hz from `T0`: `n` samples on the grid, each stamp jittering by 0.5 % of the
/// step (normal, seeded, printed to 9 decimals), after samples stamped `head` steps apart (the
/// last of them the step onto the grid) and followed by samples stamped `tail` steps apart (the
/// first of them the step off the grid): a loop not yet (or no longer) at its rate. With it, the
/// stamps of the grid alone.
fn settling(n: usize, head: &[f64], tail: &[f64], seed: u64) -> (Vec<f64>, Vec<f64>) {
    let dt = 2e-3;
    let mut draws = Draws(seed);
    let print = |t: f64| -> f64 { format!("{t:.9}").parse().unwrap() };
    let grid: Vec<f64> = (0..n)
        .map(|i| print(T0 + (i as f64 + 0.005 * draws.normal()) * dt))
        .collect();
    let mut t: Vec<f64> = (0..head.len())
        .map(|j| print(grid[0] - head[j..].iter().sum::<f64>() * dt))
        .collect();
    t.extend(&grid);
    t.extend((1..=tail.len()).map(|j| print(grid[n - 1] + tail[..j].iter().sum::<f64>() * dt)));
    (t, grid)
}

/// The report of stamps fitted alone, as the record they are in names them: its sample `first`
/// is their first, and it has line numbers or not.
fn within(alone: &GridReport, first: usize, lines: bool) -> GridReport {
    let Location::Line(line) = alone.max_at else {
        unreachable!()
    };
    let i = line as usize - 2 + first;
    GridReport {
        max_at: if lines {
            Location::Line(i as u64 + 2)
        } else {
            Location::Sample(i + 1)
        },
        ..alone.clone()
    }
}

/// The DFKI double pendulum's start: five steps of 1.5 to 1.9 steps before the grid.
const SETTLING: [f64; 5] = [1.5, 1.6, 1.7, 1.8, 1.9];

#[test]
fn a_logger_settling_to_its_rate_is_left_out_with_its_stamps_named() {
    let n = 3_000;
    let (t, grid) = settling(n, &SETTLING, &[], 11);
    // Nothing else in the record: the rest is fitted as the grid's stamps alone are.
    let alone = fit(grid.clone()).unwrap();
    for options in [GridOptions::default(), GridOptions { repair: true }] {
        let u = GridRecord::fit(record(t.clone()), &options).unwrap();
        assert_eq!(u.unsettled.len(), 1, "{:?}", u.unsettled);
        let run = &u.unsettled[0];
        assert_eq!((run.end, run.samples.clone()), (RecordEnd::Start, 0..5));
        assert_eq!((run.first, run.last), (Location::Line(2), Location::Line(6)));
        assert_eq!((run.from, run.to), (t[0], t[4]));
        assert_eq!(run.step, u.dt);
        // The steps of the run, the one onto the grid included (its jitter of 0.5 % of a step).
        assert!((run.shortest / u.dt - 1.5).abs() < 0.05, "{run:?}");
        assert!((run.longest / u.dt - 1.9).abs() < 0.05, "{run:?}");
        assert_eq!(u.kept(), 5..n + 5);
        assert_eq!((u.pieces.len(), u.sample_count()), (1, n));
        let values: Vec<f64> = (5..n + 5).map(|i| i as f64).collect();
        assert_eq!(u.pieces[0].samples, values);
        assert!(u.repaired.is_empty());
        assert_eq!((u.t0, u.dt), (alone.t0, alone.dt));
        assert_eq!(u.report, within(&alone.report, 5, true));
        // The grid is the true one, within what the jitter allows.
        assert!((u.dt - 2e-3).abs() < 1e-9, "{}", u.dt);
        assert!((u.t0 - T0).abs() < 1e-6, "{}", u.t0);
        let text = run.to_string();
        assert_eq!(
            text,
            format!(
                "the first 5 samples (line 2 to line 6, t = {} to {}) are left out: their time stamps are 1.5 \
                 to 1.9 steps of 0.002 apart, off the grid of the rest (a logger settling to its rate)",
                t[0], t[4]
            )
        );
    }
}

#[test]
fn a_logger_leaving_its_rate_at_the_end_is_left_out_too() {
    let n = 3_000;
    let tail: Vec<f64> = SETTLING.iter().rev().copied().collect();
    let (t, grid) = settling(n, &[], &tail, 12);
    let alone = fit(grid).unwrap();
    let u = fit(t.clone()).unwrap();
    assert_eq!(u.unsettled.len(), 1, "{:?}", u.unsettled);
    let run = &u.unsettled[0];
    assert_eq!((run.end, run.samples.clone()), (RecordEnd::End, n..n + 5));
    assert_eq!(
        (run.first, run.last),
        (Location::Line(n as u64 + 2), Location::Line(n as u64 + 6))
    );
    assert_eq!((run.from, run.to), (t[n], t[n + 4]));
    assert_eq!(u.kept(), 0..n);
    assert_eq!((u.t0, u.dt, &u.report), (alone.t0, alone.dt, &alone.report));
    assert!(
        (u.t0 - T0).abs() < 1e-6 && (u.dt - 2e-3).abs() < 1e-9,
        "{} {}",
        u.t0,
        u.dt
    );
    assert!(
        run.to_string()
            .starts_with(&format!("the last 5 samples (line {} to line {}", n + 2, n + 6))
            && run
                .to_string()
                .ends_with("(a logger leaving its rate as it stops)"),
        "{run}"
    );

    // Both ends, in a record without line numbers: its samples named by their place in it.
    let (t, grid) = settling(n, &SETTLING, &tail, 13);
    let alone = fit(grid).unwrap();
    let rec = Record {
        lines: None,
        ..record(t)
    };
    let u = GridRecord::fit(rec, &GridOptions::default()).unwrap();
    let ends: Vec<_> = u
        .unsettled
        .iter()
        .map(|r| (r.end, r.samples.clone(), r.first, r.last))
        .collect();
    assert_eq!(
        ends,
        [
            (RecordEnd::Start, 0..5, Location::Sample(1), Location::Sample(5)),
            (
                RecordEnd::End,
                n + 5..n + 10,
                Location::Sample(n + 6),
                Location::Sample(n + 10)
            ),
        ]
    );
    assert_eq!(u.kept(), 5..n + 5);
    assert_eq!(u.pieces[0].samples[0], 5.0);
    assert_eq!((u.t0, u.dt), (alone.t0, alone.dt));
    assert_eq!(u.report, within(&alone.report, 5, false));
}

#[test]
fn a_longer_irregular_start_is_refused_naming_it() {
    // 80 samples at 1.5 to 1.9 steps before 5 000 on the grid: more than the 50 left out.
    let head: Vec<f64> = (0..80).map(|i| SETTLING[i % 5]).collect();
    let (t, _) = settling(5_000, &head, &[], 14);
    for options in [GridOptions::default(), GridOptions { repair: true }] {
        match GridRecord::fit(record(t.clone()), &options) {
            Err(
                e @ InputError::TimeUnsettled {
                    end: RecordEnd::Start,
                    first: Location::Line(2),
                    last: Location::Line(81),
                    count: 80,
                    bound: 50,
                    ..
                },
            ) => {
                let text = e.to_string();
                assert!(
                    text.starts_with(
                        "line 2 to line 81: the first 80 time stamps are 1.5 to 1.9 steps of 0.002 apart, off \
                         the grid of the rest: more than the 50 samples at an end of a record (1 % of it, and \
                         at most 50)"
                    ),
                    "{text}"
                );
                assert!(
                    text.ends_with("remove their rows; if they are, correct their time stamps"),
                    "{text}"
                );
            }
            other => panic!("{options:?}: {other:?}"),
        }
    }
    // In a short record 1 % is fewer: 5 samples of 300 are too many.
    let (t, _) = settling(300, &SETTLING, &[], 15);
    assert!(matches!(
        fit(t),
        Err(InputError::TimeUnsettled {
            count: 5,
            bound: 3,
            ..
        })
    ));
}

#[test]
fn glitches_beside_a_settling_start_are_handled_as_before() {
    let n = 3_000;
    let (mut t, grid) = settling(n, &SETTLING, &[], 16);
    // A stamp 0.45 step late in the middle: once the start is left out, an isolated glitch,
    // named alone, and repaired on request.
    t[1_005] += 0.45 * 2e-3;
    match fit(t.clone()) {
        Err(InputError::TimeGlitch {
            at: Location::Line(1_007),
            fault: StampFault::OffGrid,
            isolated: true,
            other_count: 0,
            ..
        }) => {}
        other => panic!("{other:?}"),
    }
    let u = repair(t.clone()).unwrap();
    let runs: Vec<_> = u.unsettled.iter().map(|r| (r.end, r.samples.clone())).collect();
    assert_eq!(runs, [(RecordEnd::Start, 0..5)]);
    assert_eq!(u.repaired.len(), 1);
    assert_eq!(
        (u.repaired[0].at, u.repaired[0].was),
        (Location::Line(1_007), t[1_005])
    );
    assert!((u.repaired[0].now - grid[1_000]).abs() < 1e-4, "{:?}", u.repaired);
    // Two side by side stay an error, with or without repair.
    t[1_006] += 0.45 * 2e-3;
    for options in [GridOptions::default(), GridOptions { repair: true }] {
        assert!(matches!(
            GridRecord::fit(record(t.clone()), &options),
            Err(InputError::TimeGlitch {
                at: Location::Line(1_007),
                isolated: false,
                ..
            })
        ));
    }
    // A single slow first step is one stamp off the grid: a glitch that can be repaired, as
    // anywhere, not a run left out. Its stamp, 1.7 steps before the next, lies past the slot
    // next to it, nearest the one before (0.3 step off): a row may have been dropped between,
    // as at a gap, so it takes that slot and a gap of one sample follows it. 1.3 steps before
    // the next, it takes the slot next to it.
    for (first, slots) in [(1.7, 2.0), (1.3, 1.0)] {
        let (t, grid) = settling(n, &[first], &[], 17);
        assert!(matches!(
            fit(t.clone()),
            Err(InputError::TimeGlitch {
                at: Location::Line(2),
                isolated: true,
                ..
            })
        ));
        let u = repair(t).unwrap();
        assert!(u.unsettled.is_empty() && u.repaired.len() == 1, "{u:?}");
        assert!(
            (u.repaired[0].now - (grid[0] - slots * 2e-3)).abs() < 1e-4,
            "{first}: {:?}",
            u.repaired
        );
        assert_eq!(u.pieces.len(), slots as usize, "{first}");
    }
    // A logger settling in four steps (1.7, 1.5, 1.9, 1.9), some of its stamps near a slot by
    // chance and the others then beside gaps: left out as a run, with or without repair, not
    // spread over the grid as a logger's dropped rows.
    for seed in [11, 12] {
        let (t, _) = settling(n, &[1.7, 1.5, 1.9, 1.9], &[], seed);
        for u in [fit(t.clone()), repair(t)] {
            let u = u.unwrap();
            let runs: Vec<_> = u.unsettled.iter().map(|r| (r.end, r.samples.clone())).collect();
            assert_eq!(runs, [(RecordEnd::Start, 0..4)], "seed {seed}");
        }
    }
    // One last stamp 1.55 steps after the one before, in a short record: a glitch, repaired
    // onto the slot next to its neighbour (no slot past it within 0.4 steps), not a run.
    let (t, grid) = settling(50, &[], &[1.55], 5);
    assert!(matches!(
        fit(t.clone()),
        Err(InputError::TimeGlitch { isolated: true, .. })
    ));
    let u = repair(t).unwrap();
    assert!(u.unsettled.is_empty() && u.repaired.len() == 1, "{u:?}");
    assert!(
        (u.repaired[0].now - (grid[49] + 2e-3)).abs() < 1e-4,
        "{:?}",
        u.repaired
    );
    // A clock going backwards at the start is a glitch of the clock, not a rate.
    let mut t = settling(n, &SETTLING, &[], 18).0;
    t.swap(1, 2);
    assert!(matches!(
        repair(t),
        Err(InputError::TimeGlitch { isolated: false, .. })
    ));
}

/// Stamps so large that the fit's arithmetic overflows (steps of 1e305, 1e300 at 1e8 steps in)
/// are refused as an error, never a panic of the debug build's checks.
#[test]
fn stamps_near_the_largest_number_are_an_error_not_a_panic() {
    for (step, start) in [(1e305, 0.0), (1e300, 1e308), (1.0, 1.7e308)] {
        let t: Vec<f64> = (0..200).map(|k| start + k as f64 * step).collect();
        let finite = t.iter().all(|v| v.is_finite());
        match fit(t) {
            Ok(grid) => assert!(finite && grid.dt.is_finite(), "{step}, {start}: {grid:?}"),
            Err(e) => assert!(!e.to_string().is_empty()),
        }
    }
}
