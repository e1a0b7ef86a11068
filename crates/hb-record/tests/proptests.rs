//! Properties of the readers as a whole: any input gives a consistent record or an error that
//! names a line that exists; a record written in any supported text layout, or as any supported
//! `.npy` array, reads back to the same samples; a clock printed to a number of decimals fits its
//! grid.

use proptest::prelude::*;
use proptest::test_runner::RngSeed;

use hb_record::input::{
    Column, GridOptions, GridRecord, InputError, Location, ReadOptions, VALUE_NAMES, read_bytes,
};

use crate::common::npy_bytes;

/// The lines of a text as the reader counts them.
fn line_count(text: &[u8]) -> u64 {
    // Lines end in LF, or in CR alone in a text without LF.
    let end = if !text.contains(&b'\n') && text.contains(&b'\r') {
        b'\r'
    } else {
        b'\n'
    };
    let breaks = text.iter().filter(|&&b| b == end).count() as u64;
    breaks + u64::from(!text.ends_with(&[end]) && !text.is_empty())
}

/// The line an error names, if any.
fn error_line(e: &InputError) -> Option<u64> {
    match e {
        InputError::NotANumber { line, .. }
        | InputError::Ragged { line, .. }
        | InputError::MixedSeparators { line, .. }
        | InputError::Malformed { line, .. } => Some(*line),
        InputError::NonFinite {
            at: Location::Line(line),
            ..
        } => Some(*line),
        _ => None,
    }
}

/// Bytes that look like records: digits, signs, separators, line ends, quotes, names.
fn texty() -> impl Strategy<Value = Vec<u8>> {
    proptest::collection::vec(
        proptest::sample::select(b"0123456789.,;-+eE \t\n\r#\"thetaxinf".to_vec()),
        0..400,
    )
}

/// Any column option, 0 and past the last column included.
fn column() -> impl Strategy<Value = Option<Column>> {
    proptest::option::of(prop_oneof![
        (0..5usize).prop_map(Column::Position),
        proptest::sample::select(vec!["t", "theta", "x", "angle", "time", ""])
            .prop_map(|n| Column::Name(n.to_owned())),
    ])
}

/// Any sampling step, bad ones included.
fn step() -> impl Strategy<Value = Option<f64>> {
    proptest::option::of(proptest::sample::select(vec![
        1e-3,
        0.5,
        1e300,
        0.0,
        -1.0,
        f64::NAN,
        f64::INFINITY,
    ]))
}

/// Reads `bytes` and checks the outcome: a record whose samples are finite and numbered by
/// lines that exist, in order, and whose stamps fit a grid or are refused without a panic; or
/// an error that names a line that exists.
fn check_read(bytes: &[u8], options: &ReadOptions) -> Result<(), TestCaseError> {
    let lines = line_count(bytes);
    match read_bytes(bytes, options) {
        Ok(record) => {
            let n = record.theta.len();
            prop_assert!(n > 0);
            prop_assert_eq!(record.t.len(), n);
            prop_assert!(record.t.iter().chain(&record.theta).all(|v| v.is_finite()));
            if bytes.starts_with(b"\x93NUMPY") {
                return Ok(());
            }
            let numbers = record.lines.clone().unwrap_or_default();
            prop_assert_eq!(numbers.len(), n);
            prop_assert!(numbers.windows(2).all(|w| w[0] < w[1]));
            prop_assert!(numbers.iter().all(|l| (1..=lines).contains(l)));
            for repair in [false, true] {
                if let Ok(grid) = GridRecord::fit(record.clone(), &GridOptions { repair }) {
                    prop_assert_eq!(grid.sample_count(), n);
                    prop_assert!(grid.dt > 0.0 && grid.dt.is_finite() && grid.t0.is_finite());
                }
            }
        }
        Err(e) => {
            prop_assert!(!e.to_string().is_empty());
            if let Some(line) = error_line(&e) {
                prop_assert!((1..=lines).contains(&line), "{e} of {lines} lines");
            }
        }
    }
    Ok(())
}

/// How a record is written as text.
#[derive(Debug, Clone, Copy)]
enum Layout {
    /// A header, the columns in this order (0 the time, 1 the value, 2 another), the value
    /// named with this name from [`VALUE_NAMES`].
    Named {
        order: [usize; 3],
        width: usize,
        name: usize,
    },
    /// No header, the time first; `width` 2 or 3 columns.
    TimeFirst { width: usize },
    /// No header, the value first and the time second: the data decide (two columns), or the
    /// columns are chosen (three).
    ValueFirst { width: usize },
    /// No time column: the values alone (one column, no header) and a sampling step.
    Step,
}

/// The separator between cells, and whether numbers are written with a decimal comma.
const SEPARATORS: [(&str, bool); 8] = [
    (",", false),
    (", ", false),
    (";", false),
    (";", true),
    ("; ", true),
    (" ", false),
    ("   ", false),
    ("\t", false),
];

fn layout() -> impl Strategy<Value = Layout> {
    prop_oneof![
        (Just([0, 1, 2]).prop_shuffle(), 2..=3usize, 0..VALUE_NAMES.len()).prop_map(
            |(order, width, name)| {
                let mut order: [usize; 3] = order;
                if width == 2 {
                    // Without the other column: the time and the value, in either order.
                    order = if order.iter().position(|&c| c == 0) < order.iter().position(|&c| c == 1) {
                        [0, 1, 2]
                    } else {
                        [1, 0, 2]
                    };
                }
                Layout::Named { order, width, name }
            }
        ),
        (2..=3usize).prop_map(|width| Layout::TimeFirst { width }),
        (2..=3usize).prop_map(|width| Layout::ValueFirst { width }),
        Just(Layout::Step),
    ]
}

/// What a record's text is written with besides its layout.
#[derive(Debug, Clone)]
struct Dress {
    separator: usize,
    quotes: bool,
    crlf: bool,
    bom: bool,
    /// Comment or blank lines before these rows (the header is row 0 when there is one).
    comments: Vec<usize>,
}

fn dress() -> impl Strategy<Value = Dress> {
    (
        0..SEPARATORS.len(),
        any::<bool>(),
        any::<bool>(),
        any::<bool>(),
        proptest::collection::vec(0..60usize, 0..4),
    )
        .prop_map(|(separator, quotes, crlf, bom, comments)| Dress {
            separator,
            quotes,
            crlf,
            bom,
            comments,
        })
}

/// Writes the samples in a layout; returns the text, the options that read it, and the line of
/// each sample.
fn write(t: &[f64], x: &[f64], layout: Layout, dress: &Dress, dt: f64) -> (String, ReadOptions, Vec<u64>) {
    let (separator, decimal_comma) = SEPARATORS[dress.separator];
    // A decimal comma only where semicolons separate cells: a single column has no separator.
    let decimal_comma = decimal_comma && !matches!(layout, Layout::Step);
    let number = |v: f64| {
        let s = v.to_string();
        let s = if decimal_comma { s.replacen('.', ",", 1) } else { s };
        if dress.quotes { format!("\"{s}\"") } else { s }
    };
    let end = if dress.crlf { "\r\n" } else { "\n" };
    let mut options = ReadOptions::default();
    let (header, cells): (Option<Vec<String>>, Vec<Vec<String>>) = match layout {
        Layout::Named { order, width, name } => {
            let names = ["t", VALUE_NAMES[name], "omega"];
            let header = order[..width].iter().map(|&c| names[c].to_owned()).collect();
            let rows = (0..x.len())
                .map(|i| {
                    let values = [t[i], x[i], 1.0 + i as f64];
                    order[..width].iter().map(|&c| number(values[c])).collect()
                })
                .collect();
            (Some(header), rows)
        }
        Layout::TimeFirst { width } | Layout::ValueFirst { width } => {
            let time_first = matches!(layout, Layout::TimeFirst { .. });
            if !time_first && width == 3 {
                options.time = Some(Column::Position(2));
                options.angle = Some(Column::Position(1));
            }
            let rows = (0..x.len())
                .map(|i| {
                    let mut row = if time_first {
                        vec![number(t[i]), number(x[i])]
                    } else {
                        vec![number(x[i]), number(t[i])]
                    };
                    if width == 3 {
                        row.push(number(-(i as f64)));
                    }
                    row
                })
                .collect();
            (None, rows)
        }
        Layout::Step => {
            options.dt = Some(dt);
            (None, x.iter().map(|&v| vec![number(v)]).collect())
        }
    };
    let mut text = String::new();
    if dress.bom {
        text.push('\u{feff}');
    }
    let mut line = 0u64;
    let mut lines = Vec::new();
    let rows = header.iter().chain(&cells);
    for (r, row) in rows.enumerate() {
        for _ in dress.comments.iter().filter(|&&c| c == r) {
            text.push_str(if r % 2 == 0 {
                "# a comment, with; separators"
            } else {
                "  "
            });
            text.push_str(end);
            line += 1;
        }
        text.push_str(&row.join(separator));
        text.push_str(end);
        line += 1;
        if header.is_none() || r > 0 {
            lines.push(line);
        }
    }
    (text, options, lines)
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 512,
        rng_seed: RngSeed::Fixed(0x7e47_0b1e),
        ..ProptestConfig::default()
    })]

    /// Any bytes, any options: a consistent record or an error naming a line that exists.
    #[test]
    fn any_bytes_read_or_fail_cleanly(
        bytes in prop_oneof![proptest::collection::vec(any::<u8>(), 0..300), texty()],
        time in column(),
        angle in column(),
        dt in step(),
    ) {
        check_read(&bytes, &ReadOptions { time, angle, dt, ..ReadOptions::default() })?;
    }

    /// A record written in any supported layout reads back to the same samples, each numbered by
    /// its line.
    #[test]
    fn every_text_layout_reads_back(
        x in proptest::collection::vec(
            prop_oneof![-1e3..1e3f64, -7.0..7.0f64, (-5000..5000i32).prop_map(f64::from)],
            5..60,
        ),
        t0 in prop_oneof![Just(0.0), -1e4..1e4f64],
        dt in prop_oneof![Just(0.01), 1e-5..10.0f64],
        layout in layout(),
        dress in dress(),
    ) {
        let t: Vec<f64> = match layout {
            Layout::Step => (0..x.len()).map(|i| i as f64 * dt).collect(),
            _ => (0..x.len()).map(|i| t0 + i as f64 * dt).collect(),
        };
        let (text, options, lines) = write(&t, &x, layout, &dress, dt);
        let r = read_bytes(text.as_bytes(), &options)
            .map_err(|e| TestCaseError::fail(format!("{e}\n{text}")))?;
        prop_assert_eq!(&r.t, &t, "{}", text);
        prop_assert_eq!(&r.theta, &x, "{}", text);
        prop_assert_eq!(r.lines, Some(lines), "{}", text);
    }

    /// An array of any supported element type, shape and order reads back to its columns.
    #[test]
    fn every_npy_layout_reads_back(
        rows in 1..40usize,
        cols in 1..4usize,
        fortran in any::<bool>(),
        kind in 0..5usize,
        seed in proptest::collection::vec(-30000..30000i32, 160),
    ) {
        let (descr, size) = [("<f8", 8), ("<f4", 4), ("<i8", 8), ("<i4", 4), ("<i2", 2)][kind];
        // Values every element type holds exactly: integers within i16, quarters in floats.
        let value = |r: usize, c: usize| {
            let v = f64::from(seed[(r * cols + c) % seed.len()]);
            if descr.starts_with("<f") { v / 4.0 } else { v }
        };
        let element = |v: f64| -> Vec<u8> {
            match descr {
                "<f8" => v.to_le_bytes().to_vec(),
                "<f4" => (v as f32).to_le_bytes().to_vec(),
                "<i8" => (v as i64).to_le_bytes().to_vec(),
                "<i4" => (v as i32).to_le_bytes().to_vec(),
                _ => (v as i16).to_le_bytes().to_vec(),
            }
        };
        let mut payload = Vec::with_capacity(rows * cols * size);
        let mut push = |r: usize, c: usize| payload.extend(element(value(r, c)));
        if fortran {
            (0..cols).for_each(|c| (0..rows).for_each(|r| push(r, c)));
        } else {
            (0..rows).for_each(|r| (0..cols).for_each(|c| push(r, c)));
        }
        let shape = if cols == 1 { format!("({rows},)") } else { format!("({rows}, {cols})") };
        let bytes = npy_bytes(descr, &shape, fortran, &payload);
        let column = |c: usize| (0..rows).map(|r| value(r, c)).collect::<Vec<f64>>();
        let (options, t, x) = if cols == 1 {
            let dt = 0.25;
            (ReadOptions { dt: Some(dt), ..Default::default() }, (0..rows).map(|i| i as f64 * dt).collect(), column(0))
        } else {
            let (tc, xc) = (cols - 1, 0);
            let options = ReadOptions {
                time: Some(Column::Position(tc + 1)),
                angle: Some(Column::Position(xc + 1)),
                dt: None,
                ..ReadOptions::default()
            };
            (options, column(tc), column(xc))
        };
        let r = read_bytes(&bytes, &options).map_err(|e| TestCaseError::fail(e.to_string()))?;
        prop_assert_eq!((r.t, r.theta, r.lines), (t, x, None));
    }
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 256,
        rng_seed: RngSeed::Fixed(0x9_7d0c),
        ..ProptestConfig::default()
    })]

    /// A clock at any rate from 1 Hz to 100 kHz, from any start, printed with the fewest decimals
    /// whose resolution is at most `fraction` of a step (so that each stamp is off by at most
    /// half that), read as text and fitted: one piece, no repair, the step within the bound of
    /// least squares on the rounding, and the first sample's time within the rounding of its
    /// true time.
    #[test]
    fn a_printed_clock_fits_its_grid(
        rate in prop_oneof![1.0..1e5f64, proptest::sample::select(vec![100.0, 500.0, 1000.0, 2048.0, 44100.0])],
        t0 in prop_oneof![Just(0.0), 0.0..1e4f64, -100.0..100.0f64],
        n in 50..3000usize,
        fraction in proptest::sample::select(vec![0.1, 0.25, 0.4, 0.5]),
    ) {
        let dt = 1.0 / rate;
        let decimals = (-(fraction * dt).log10()).ceil().max(0.0) as usize;
        let unit = 10f64.powi(-(decimals as i32));
        let text: String = std::iter::once("t,theta\n".to_owned())
            .chain((0..n).map(|i| format!("{:.*},{}\n", decimals, t0 + i as f64 * dt, i % 7)))
            .collect();
        let record = read_bytes(text.as_bytes(), &ReadOptions::default())
            .map_err(|e| TestCaseError::fail(e.to_string()))?;
        let grid = GridRecord::fit(record, &GridOptions::default())
            .map_err(|e| TestCaseError::fail(format!("{e} ({decimals} decimals, {rate} Hz)")))?;
        prop_assert_eq!(grid.pieces.len(), 1);
        prop_assert_eq!(grid.sample_count(), n);
        prop_assert!(grid.repaired.is_empty());
        // The least-squares step from stamps each off by at most e: e Σ|n − n̄| / Σ(n − n̄)²,
        // with the rounding of the numbers themselves.
        let e = 0.5 * unit + 2e-16 * (t0.abs() + n as f64 * dt);
        let mean = (n - 1) as f64 / 2.0;
        let sxx: f64 = (0..n).map(|k| (k as f64 - mean).powi(2)).sum();
        let sabs: f64 = (0..n).map(|k| (k as f64 - mean).abs()).sum();
        let bound = e * sabs / sxx + 1e-12 * dt;
        prop_assert!((grid.dt - dt).abs() <= bound, "step {} vs {dt}, bound {bound:e}", grid.dt);
        prop_assert!((grid.t0 - t0).abs() <= e + mean * bound, "t0 {} vs {t0}", grid.t0);
    }
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 128,
        rng_seed: RngSeed::Fixed(0x0b41_d6e5),
        ..ProptestConfig::default()
    })]

    /// Rows dropped anywhere but at the ends, bridged up to `limit` samples a gap between pieces
    /// searched for spikes: a cubic motion
    /// (a whirling angle on the circle, a displacement, a drive) comes back exactly at every
    /// sample bridged, every sample read is kept as it was, the angle stays in [-π, π), and the
    /// pieces left are those of the gaps too long, or with one sample on a side.
    #[test]
    fn bridged_gaps_give_back_a_cubic_in_every_column(
        n in 60..400usize,
        limit in 1..=hb_record::prepare::MAX_BRIDGE,
        drops in proptest::collection::vec((2..1000usize, 1..8usize), 1..12),
        c in proptest::array::uniform4(-1.0..1.0f64),
    ) {
        use circle_signal::{Domain, wrap};
        use hb_record::input::Record;
        use hb_record::prepare::{PrepareOptions, condition};
        let s = n as f64;
        // Unwrapped angle: up to 1.3 rad a step; displacement and drive: other cubics.
        let angle = |t: f64| c[0] + 1.3 * c[1] * t + 0.3 * c[2] * t * t / s + 0.1 * c[3] * t * t * t / (s * s);
        let line = |t: f64| 2.0 * c[3] - c[2] * t / s + c[1] * (t / s).powi(2) + 3.0 * c[0] * (t / s).powi(3);
        let drive = |t: f64| 0.5 + c[2] * (t / s).powi(3);
        let mut missing = vec![false; n];
        for (at, len) in drops {
            let at = 2 + at % (n - 4);
            for m in missing.iter_mut().take((at + len).min(n - 2)).skip(at) {
                *m = true;
            }
        }
        let rows: Vec<usize> = (0..n).filter(|&i| !missing[i]).collect();
        let of = |f: &dyn Fn(f64) -> f64| rows.iter().map(|&i| f(i as f64)).collect::<Vec<f64>>();
        let record = Record {
            t: of(&|t| t),
            theta: of(&|t| wrap(angle(t))),
            others: vec![of(&line)],
            drives: vec![of(&drive)],
            ..Record::default()
        };
        let options = PrepareOptions::new(Domain::Circle)
            .with_others(vec![Domain::Line])
            .with_bridge(limit);
        let grid = condition(record, &options, &mut |_| {}).map_err(|e| TestCaseError::fail(e.to_string()))?;
        // The gaps of the record as read, and those left.
        let mut expected: Vec<std::ops::Range<usize>> = Vec::new();
        let mut i = 0;
        while i < n {
            let start = i;
            while i < n && !missing[i] {
                i += 1;
            }
            expected.push(start..i);
            while i < n && missing[i] {
                i += 1;
            }
        }
        // A gap is bridged when it misses at most `limit` samples and the pieces read on both
        // sides have 7 samples or more (the spike search's least).
        let mut joined: Vec<std::ops::Range<usize>> = vec![expected[0].clone()];
        for w in expected.windows(2) {
            let bridged = w[1].start - w[0].end <= limit && w[0].len() >= 7 && w[1].len() >= 7;
            match joined.last_mut() {
                Some(last) if bridged => last.end = w[1].end,
                _ => joined.push(w[1].clone()),
            }
        }
        prop_assert_eq!(&grid.pieces, &joined);
        for piece in &grid.pieces {
            for i in piece.clone() {
                let t = i as f64;
                let tol = if missing[i] { 1e-9 } else { 1e-12 };
                prop_assert!(wrap(grid.x[i] - angle(t)).abs() <= tol, "angle at {}: {} vs {}", i, grid.x[i], wrap(angle(t)));
                prop_assert!((-std::f64::consts::PI..std::f64::consts::PI).contains(&grid.x[i]));
                prop_assert!((grid.others[0].x[i] - line(t)).abs() <= tol * 10.0, "line at {}", i);
                prop_assert!((grid.drives[0][i] - drive(t)).abs() <= tol * 10.0, "drive at {}", i);
            }
        }
    }
}
