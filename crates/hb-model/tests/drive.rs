//! The measured drive between its samples: cubics reproduced to the ends, a band-limited drive
//! keeping its amplitude, and gaps splitting the spline into runs.

use hb_model::MeasuredDrive;

fn drive(p: Vec<f64>) -> MeasuredDrive {
    MeasuredDrive::new(p, 0.0, 1.0).unwrap()
}

/// The largest error between samples `lo .. hi` (at 7 points each) against `f`.
fn worst(d: &MeasuredDrive, f: impl Fn(f64) -> f64, lo: usize, hi: usize) -> f64 {
    (lo..hi)
        .flat_map(|i| (1..8).map(move |k| i as f64 + k as f64 / 8.0))
        .map(|t| (d.at(t) - f(t)).abs())
        .fold(0.0, f64::max)
}

#[test]
fn cubics_are_reproduced_to_the_ends() {
    let f = |t: f64| 0.3 - 1.2 * t + 0.05 * t * t - 0.004 * t * t * t;
    for n in [4, 5, 9, 40] {
        let d = drive((0..n).map(|i| f(i as f64)).collect());
        let err = worst(&d, f, 0, n - 1);
        assert!(err < 1e-12, "{n} samples: {err}");
    }
    // Three samples: the parabola through them; two: the line.
    let g = |t: f64| 1.0 + 2.0 * t - 0.5 * t * t;
    assert!(worst(&drive(vec![g(0.0), g(1.0), g(2.0)]), g, 0, 2) < 1e-14);
    let d = drive(vec![1.0, 3.0]);
    assert!((d.at(0.25) - 1.5).abs() < 1e-15);
}

/// A sinusoid at a quarter of the sampling rate keeps its amplitude between samples (within
/// 2.5 %) where the Catmull–Rom spline loses a tenth of it.
#[test]
fn a_band_limited_drive_keeps_its_amplitude() {
    let f = |t: f64| (0.5 * std::f64::consts::PI * t + 0.3).sin();
    let p: Vec<f64> = (0..400).map(|i| f(i as f64)).collect();
    let d = drive(p.clone());
    // Away from the ends, where the spline is the cardinal one.
    let spline = worst(&d, f, 50, 350);
    let catmull_rom = (50..350)
        .map(|i| {
            let (m0, m1) = (0.5 * (p[i + 1] - p[i - 1]), 0.5 * (p[i + 2] - p[i]));
            let mid = 0.5 * (p[i] + p[i + 1]) + (m0 - m1) / 8.0;
            (mid - f(i as f64 + 0.5)).abs()
        })
        .fold(0.0, f64::max);
    assert!(spline < 0.025, "spline {spline}");
    assert!(catmull_rom > 0.09, "Catmull–Rom {catmull_rom}");
}

#[test]
fn gaps_split_the_spline_into_runs() {
    let f = |t: f64| (0.3 * t).cos();
    let mut p: Vec<f64> = (0..30).map(|i| f(i as f64)).collect();
    p[10] = f64::NAN;
    p[12] = f64::INFINITY;
    let d = drive(p);
    // Each run is its own spline: finite inside, NaN on the intervals that touch a gap.
    assert!(worst(&d, f, 13, 29) < 2e-3);
    assert!(worst(&d, f, 0, 9) < 2e-3);
    for t in [9.5, 10.0, 10.5, 11.5, 12.0, 12.5] {
        assert!(d.at(t).is_nan(), "{t}");
    }
    // The samples around the gaps themselves are kept, and the lone sample 11 too.
    for i in [9, 11, 13] {
        assert_eq!(d.at(i as f64), f(i as f64));
    }
    // A piece of the record keeps its spline from another origin.
    let moved = d.starting_at(100.0).unwrap();
    assert_eq!(moved.at(103.25), d.at(3.25));
    assert!(d.starting_at(f64::NAN).is_err());
}

/// At uneven stamps (a logger's first rows, before it settled): cubics reproduced to the ends,
/// a smooth drive followed closely, the grid's spline where the stamps are even, and bad stamps
/// refused.
#[test]
fn uneven_stamps_have_their_own_spline() {
    let f = |t: f64| 0.3 - 1.2 * t + 0.05 * t * t - 0.004 * t * t * t;
    let t = [0.0, 1.7, 3.4, 4.9, 6.5, 7.5, 8.5, 9.5, 10.5];
    for n in [4, 5, 9] {
        let d = MeasuredDrive::at_stamps(t[..n].iter().map(|&s| f(s)).collect::<Vec<_>>(), &t[..n]).unwrap();
        for w in t[..n].windows(2) {
            for k in 0..=8 {
                let s = w[0] + (w[1] - w[0]) * f64::from(k) / 8.0;
                assert!((d.at(s) - f(s)).abs() < 1e-12, "{n} samples at {s}");
            }
        }
        assert_eq!(d.end_time(), t[n - 1]);
        assert!(d.at(t[n - 1] + 0.1).is_nan() && d.at(-0.1).is_nan());
    }
    let g = |t: f64| 1.0 + 2.0 * t - 0.5 * t * t;
    let three = MeasuredDrive::at_stamps(vec![g(0.0), g(0.4), g(1.5)], &[0.0, 0.4, 1.5]).unwrap();
    assert!((three.at(1.0) - g(1.0)).abs() < 1e-14);
    // A sinusoid at 3 to 1.5 ms steps, as the DFKI logger's first rows: within 1e-7 of it.
    let h = |t: f64| (10.0 * t).sin();
    let mut stamps = vec![0.0, 0.0035, 0.0068, 0.0099, 0.0129, 0.0159];
    stamps.extend((1..200).map(|i| 0.0159 + 0.002 * f64::from(i)));
    let d = MeasuredDrive::at_stamps(stamps.iter().map(|&s| h(s)).collect::<Vec<_>>(), &stamps).unwrap();
    let err = (0..4000)
        .map(|i| f64::from(i) * 1e-4)
        .map(|s| (d.at(s) - h(s)).abs())
        .fold(0.0, f64::max);
    assert!(err < 1e-7, "{err}");
    // Even stamps give the grid's spline.
    let even: Vec<f64> = (0..40).map(|i| 2.0 + 0.5 * f64::from(i)).collect();
    let p: Vec<f64> = even.iter().map(|&s| (0.7 * s).cos()).collect();
    let (a, b) = (
        MeasuredDrive::at_stamps(p.clone(), &even).unwrap(),
        MeasuredDrive::new(p, 2.0, 0.5).unwrap(),
    );
    for k in 0..300 {
        let s = 2.0 + 0.0651 * f64::from(k);
        assert!((a.at(s) - b.at(s)).abs() < 1e-12, "{s}");
    }
    // Moved to another origin, the same spline.
    let moved = d.starting_at(5.0).unwrap();
    assert!((moved.at(5.0123) - d.at(0.0123)).abs() < 1e-12);
    assert!(MeasuredDrive::at_stamps(vec![1.0, 2.0], &[0.0]).is_err());
    assert!(MeasuredDrive::at_stamps(vec![1.0, 2.0, 3.0], &[0.0, 1.0, 1.0]).is_err());
    assert!(MeasuredDrive::at_stamps(vec![1.0, 2.0], &[0.0, f64::NAN]).is_err());
    assert!(MeasuredDrive::at_stamps(vec![1.0], &[0.0]).is_err());
}
