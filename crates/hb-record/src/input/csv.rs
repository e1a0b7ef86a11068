//! Text records: comments, an optional header, cells separated by commas, semicolons or white
//! space, columns by name or position.

use super::{Column, Columns, InputError, Location, ReadOptions, Record, Role, Separator, Times, grid};

/// Reads text; the options are assumed valid.
pub(super) fn read<'a>(bytes: &'a [u8], options: &ReadOptions) -> Result<Record, InputError> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let mut lines = Lines { bytes, line: 0 };
    let Some((first_line, first)) = lines.next_row()? else {
        return Err(InputError::Empty);
    };
    let separator = match Separator::of(first) {
        Some(s) => s,
        // A single cell: any separator splits it into itself.
        None => Separator::Whitespace,
    };
    let mut first_cells = Vec::new();
    separator.split(first, &mut first_cells);
    let width = first_cells.len();
    let is_header = first_cells.iter().any(|c| number(c, separator).is_none());
    let header = is_header.then_some(&first_cells[..]);
    let columns = options.columns(header, width)?;
    let Columns { time, angle, .. } = columns;
    let field = |role, index| Field {
        index,
        // Until the data decide which column is the time, neither is called one.
        role: if columns.order_from_data {
            Role::Angle
        } else {
            role
        },
        header,
        separator,
    };
    let (time_field, angle_field) = (
        time.column().map(|i| field(Role::Time, i)),
        field(Role::Angle, angle),
    );
    let drive_field = columns.drive.map(|i| field(Role::Drive, i));

    let mut record = Record {
        drive: drive_field.as_ref().map(|_| Vec::new()),
        ..Record::default()
    };
    let mut numbers = Vec::new();
    let mut cells: Vec<&'a str> = Vec::with_capacity(width);
    let mut push = |line: u64, text: &'a str, cells: &mut Vec<&'a str>| -> Result<(), InputError> {
        if let Some(found) = Separator::of(text).filter(|&s| s != separator && width > 1) {
            return Err(InputError::MixedSeparators {
                line,
                expected: separator,
                found,
            });
        }
        separator.split(text, cells);
        if cells.len() != width {
            return Err(InputError::Ragged {
                line,
                expected: width,
                found: cells.len(),
            });
        }
        if let Some(time) = &time_field {
            record.t.push(time.value(cells, line)?);
        }
        record.theta.push(angle_field.value(cells, line)?);
        if let (Some(field), Some(drive)) = (&drive_field, &mut record.drive) {
            drive.push(field.value(cells, line)?);
        }
        numbers.push(line);
        Ok(())
    };
    if header.is_none() {
        push(first_line, first, &mut cells)?;
    }
    while let Some((line, text)) = lines.next_row()? {
        push(line, text, &mut cells)?;
    }
    if record.theta.is_empty() {
        return Err(InputError::NoData);
    }
    if let Times::Step(dt) = time {
        record.t = grid(record.theta.len(), dt)?;
    }
    record.lines = Some(numbers);
    if columns.order_from_data {
        super::order_from_data(&mut record);
    }
    Ok(record)
}

/// The rows of a text: lines that are neither blank nor comments, with their line numbers.
struct Lines<'a> {
    /// What is left to read.
    bytes: &'a [u8],
    /// The number of the last line read, counted from 1.
    line: u64,
}

impl<'a> Lines<'a> {
    /// The next row, trimmed, with its line number; `None` at the end.
    fn next_row(&mut self) -> Result<Option<(u64, &'a str)>, InputError> {
        while !self.bytes.is_empty() {
            let end = self.bytes.iter().position(|&b| b == b'\n');
            let (raw, rest) = match end {
                Some(e) => (&self.bytes[..e], &self.bytes[e + 1..]),
                None => (self.bytes, &self.bytes[self.bytes.len()..]),
            };
            self.bytes = rest;
            self.line += 1;
            let text = std::str::from_utf8(raw).map_err(|source| InputError::Malformed {
                line: self.line,
                source,
            })?;
            let text = text.trim();
            if !(text.is_empty() || text.starts_with('#')) {
                return Ok(Some((self.line, text)));
            }
        }
        Ok(None)
    }
}

impl Separator {
    /// The separator of a trimmed row: semicolons when it holds one (commas are then decimal
    /// commas), else commas when it holds one, else white space when it holds any; `None` for a
    /// single cell.
    fn of(text: &str) -> Option<Self> {
        if text.contains(';') {
            Some(Separator::Semicolon)
        } else if text.contains(',') {
            Some(Separator::Comma)
        } else if text.contains([' ', '\t']) {
            Some(Separator::Whitespace)
        } else {
            None
        }
    }

    /// The cells of a trimmed row into `cells`, each trimmed and without enclosing double quotes.
    fn split<'a>(self, text: &'a str, cells: &mut Vec<&'a str>) {
        fn clean(c: &str) -> &str {
            let c = c.trim();
            c.strip_prefix('"')
                .and_then(|c| c.strip_suffix('"'))
                .map_or(c, str::trim)
        }
        cells.clear();
        match self {
            Separator::Comma => cells.extend(text.split(',').map(clean)),
            Separator::Semicolon => cells.extend(text.split(';').map(clean)),
            Separator::Whitespace => {
                cells.extend(text.split([' ', '\t']).filter(|c| !c.is_empty()).map(clean))
            }
        }
    }
}

/// The number in a cell, if it is one: a decimal comma is accepted where semicolons separate
/// the cells.
fn number(cell: &str, separator: Separator) -> Option<f64> {
    match cell.parse() {
        Ok(v) => Some(v),
        Err(_) if separator == Separator::Semicolon && cell.contains(',') => {
            cell.replacen(',', ".", 1).parse().ok()
        }
        Err(_) => None,
    }
}

/// A column read from every row: where it is, what it holds, and the header to name it in errors.
struct Field<'a> {
    index: usize,
    role: Role,
    header: Option<&'a [&'a str]>,
    separator: Separator,
}

impl Field<'_> {
    /// The finite number in this column of the row's `cells`, which is on `line`.
    fn value(&self, cells: &[&str], line: u64) -> Result<f64, InputError> {
        let text = cells[self.index];
        let value = number(text, self.separator).ok_or_else(|| InputError::NotANumber {
            line,
            column: self.column(),
            value: text.chars().take(40).collect(),
        })?;
        if !value.is_finite() {
            return Err(InputError::NonFinite {
                at: Location::Line(line),
                role: self.role,
                value,
            });
        }
        Ok(value)
    }

    /// The column by its header name, or by position without a header.
    fn column(&self) -> Column {
        match self.header {
            Some(h) => Column::Name(h[self.index].to_owned()),
            None => Column::Position(self.index + 1),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::*;

    fn read(text: &str) -> Result<Record, InputError> {
        read_bytes(text.as_bytes(), &ReadOptions::default())
    }

    fn with(text: &str, options: ReadOptions) -> Result<Record, InputError> {
        read_bytes(text.as_bytes(), &options)
    }

    /// A drive column is read beside the angle, by name or position, in text and `.npy`; it may
    /// not be the time or the angle, and a bad cell in it names its line.
    #[test]
    fn reads_a_drive_column_beside_the_angle() {
        let drive = |c: &str| ReadOptions {
            drive: Some(c.parse().unwrap()),
            ..Default::default()
        };
        let text = "t,theta,omega,acc\n0,0.1,0,5\n# c\n0.5,0.2,1,-6\n";
        for chosen in ["acc", "4"] {
            let r = with(text, drive(chosen)).unwrap();
            assert_eq!((r.theta, r.drive), (vec![0.1, 0.2], Some(vec![5.0, -6.0])));
        }
        assert_eq!(read(text).unwrap().drive, None);
        for taken in ["t", "theta", "1"] {
            assert!(matches!(
                with(text, drive(taken)),
                Err(InputError::ColumnTwice {
                    second: Role::Drive,
                    ..
                })
            ));
        }
        assert!(matches!(
            with(text, drive("p")),
            Err(InputError::MissingColumn {
                role: Role::Drive,
                ..
            })
        ));
        match with("t,theta,p\n0,1,2\n1,2,x\n", drive("p")) {
            Err(e @ InputError::NotANumber { line: 3, .. }) => assert!(e.to_string().contains("'p'"), "{e}"),
            other => panic!("{other:?}"),
        }
        // Two unnamed columns and a drive: no guessing of the order, the time is column 1.
        let r = with("0.1,0,7\n0.2,1,8\n", drive("3")).unwrap();
        assert_eq!((r.t, r.drive), (vec![0.1, 0.2], Some(vec![7.0, 8.0])));
        // .npy: rows (t, x, p).
        let f8: Vec<u8> = [0.0f64, 0.5, 9.0, 1.0, 0.6, f64::NAN]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let npy = super::super::npy::npy_bytes("<f8", "(2, 3)", false, &f8);
        assert!(matches!(
            read_bytes(&npy, &drive("3")),
            Err(InputError::NonFinite {
                role: Role::Drive,
                ..
            })
        ));
        let f8: Vec<u8> = [0.0f64, 0.5, 9.0, 1.0, 0.6, 8.0]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let npy = super::super::npy::npy_bytes("<f8", "(2, 3)", false, &f8);
        assert_eq!(read_bytes(&npy, &drive("3")).unwrap().drive, Some(vec![9.0, 8.0]));
    }

    #[test]
    fn reads_with_comments_and_extra_columns() {
        let r = read("# a comment\nt,theta,omega\n0,0.1,0\n# mid\n0.5,-3.0,1e-3\n").unwrap();
        assert_eq!(r.t, vec![0.0, 0.5]);
        assert_eq!(r.theta, vec![0.1, -3.0]);
        assert_eq!(r.lines, Some(vec![3, 5]));
        let r = read("theta, t\n1,2\n").unwrap();
        assert_eq!((r.t[0], r.theta[0]), (2.0, 1.0));
        // Windows line ends, a byte-order mark, quoted names, blank lines.
        let r = read("\u{feff}\"t\",\"theta\"\r\n\r\n0,1\r\n0.5,2\r\n").unwrap();
        assert_eq!(
            (r.t, r.theta, r.lines),
            (vec![0.0, 0.5], vec![1.0, 2.0], Some(vec![3, 4]))
        );
    }

    #[test]
    fn whitespace_semicolons_and_tabs_separate_cells() {
        let expected = (vec![0.0, 0.5, 1.0], vec![0.1, -0.2, 0.3]);
        for text in [
            "t theta\n0 0.1\n0.5 -0.2\n1 0.3\n",
            "   t    theta  \n  0   0.1\n0.5     -0.2   \n 1 0.3 \n",
            "t\ttheta\n0\t0.1\n0.5\t-0.2\n1\t0.3\n",
            "t \t theta\n0\t\t0.1\n0.5 \t-0.2\n1 0.3\n",
            "t;theta\n0;0.1\n0.5;-0.2\n1;0.3\n",
            "t ; theta\n0; 0,1\n0,5 ;-0,2\n1;0.3\n",
            "0 0.1\n0.5 -0.2\n1 0.3\n",
            "0;0.1\n0.5;-0.2\n1;0.3\n",
        ] {
            let r = read(text).unwrap_or_else(|e| panic!("{text:?}: {e}"));
            assert_eq!((r.t, r.theta), expected, "{text:?}");
        }
        // A single column with the step: white space around it is no separator.
        let step = ReadOptions {
            dt: Some(0.5),
            ..Default::default()
        };
        assert_eq!(with("  1.5\n2.5  \n", step).unwrap().theta, vec![1.5, 2.5]);
    }

    #[test]
    fn mixed_separators_name_the_line() {
        for (text, line, expected, found) in [
            ("0,1\n1,2\n2 3\n", 3, Separator::Comma, Separator::Whitespace),
            (
                "t theta\n0 1\n1;2\n",
                3,
                Separator::Whitespace,
                Separator::Semicolon,
            ),
            (
                "t;theta\n0;1\n# c\n1,2\n",
                4,
                Separator::Semicolon,
                Separator::Comma,
            ),
            ("0\t1\n1\t2\n2,3\n", 3, Separator::Whitespace, Separator::Comma),
        ] {
            match read(text) {
                Err(e @ InputError::MixedSeparators { .. }) => {
                    assert_eq!(
                        e.to_string(),
                        format!(
                            "line {line}: cells separated by {found} where the first row uses {expected}"
                        ),
                    );
                }
                other => panic!("{text:?}: {other:?}"),
            }
        }
    }

    #[test]
    fn headerless_and_column_choices() {
        let r = read("0,1.5\n1,2.5\n").unwrap();
        assert_eq!((r.t.clone(), r.theta.clone()), (vec![0.0, 1.0], vec![1.5, 2.5]));
        let opts = ReadOptions {
            dt: Some(0.5),
            ..Default::default()
        };
        let r = with("1.5\n2.5\n3.5\n", opts.clone()).unwrap();
        assert_eq!(r.t, vec![0.0, 0.5, 1.0]);
        assert!(matches!(read("1.5\n2.5\n"), Err(InputError::NeedStep)));
        let opts = ReadOptions {
            time: Some("time".parse().unwrap()),
            angle: Some("3".parse().unwrap()),
            ..Default::default()
        };
        let r = with("time,x,angle\n0,9,1\n1,9,2\n", opts).unwrap();
        assert_eq!(r.theta, vec![1.0, 2.0]);
        assert!("0".parse::<Column>().is_err());
        assert!("".parse::<Column>().is_err());
        let both = ReadOptions {
            time: Some(Column::Position(1)),
            dt: Some(1.0),
            ..Default::default()
        };
        assert!(matches!(with("1,2\n", both), Err(InputError::TimeTwice)));
    }

    #[test]
    fn default_value_columns() {
        // theta first, then x, then angle; else the only column besides the time.
        for (header, expected) in [
            ("t,x,theta", 3.0),
            ("angle,t,x", 3.0),
            ("angle,t,y", 1.0),
            ("t,position", 2.0),
            ("volts,t", 1.0),
        ] {
            // Row 1 holds each column's position.
            let width = header.split(',').count();
            let row: Vec<String> = (1..=width).map(|c| c.to_string()).collect();
            let text = format!("{header}\n{}\n", row.join(","));
            let r = read(&text).unwrap_or_else(|e| panic!("{header}: {e}"));
            assert_eq!(r.theta[0], expected, "{header}");
        }
        // Three columns and none of the names: nothing to guess.
        assert!(matches!(
            read("t,a,b\n0,1,2\n"),
            Err(InputError::MissingColumn {
                role: Role::Angle,
                ..
            })
        ));
        // An explicit choice still wins.
        let chosen = ReadOptions {
            angle: Some(Column::Name("a".into())),
            ..Default::default()
        };
        assert_eq!(with("t,a,x\n0,1,2\n", chosen).unwrap().theta, vec![1.0]);
    }

    #[test]
    fn headerless_columns_in_either_order() {
        let n = 50;
        let dt = 1.0 / 2048.0;
        let angle = |i: usize| 2.5 * (i as f64 * 0.3).sin();
        let time_first: String = (0..n)
            .map(|i| format!("{:.4} {:.6}\n", 3.0 + i as f64 * dt, angle(i)))
            .collect();
        let angle_first: String = (0..n)
            .map(|i| format!("{:.6}\t{:.4}\n", angle(i), 3.0 + i as f64 * dt))
            .collect();
        let a = read(&time_first).unwrap();
        let b = read(&angle_first).unwrap();
        assert_eq!((&a.t, &a.theta), (&b.t, &b.theta));
        assert!((a.t[1] - a.t[0] - dt).abs() < 1e-4 && (a.theta[1] - angle(1)).abs() < 1e-6);
        // A value column as uniform as the time leaves the default: column 1 is the time.
        let ramps: String = (0..n).map(|i| format!("{} {}\n", 2 * i, i)).collect();
        assert_eq!(read(&ramps).unwrap().t[1], 2.0);
    }

    #[test]
    fn bad_inputs_are_named() {
        assert!(matches!(read(""), Err(InputError::Empty)));
        assert!(matches!(read("# only a comment\n"), Err(InputError::Empty)));
        assert!(matches!(read("t,theta\n"), Err(InputError::NoData)));
        assert!(matches!(
            read("time,angle\n1,2\n"),
            Err(InputError::MissingColumn { .. })
        ));
        match read("t,theta\n0,1\n1,abc\n") {
            Err(InputError::NotANumber { line: 3, .. }) => {}
            other => panic!("{other:?}"),
        }
        match read("t,theta\n0,1\n1,NaN\n") {
            Err(InputError::NonFinite { at, .. })
                if at == Location::Line(3) && at.to_string() == "line 3" => {}
            other => panic!("{other:?}"),
        }
        match read("t,theta\n0,1\n1,inf\n") {
            Err(InputError::NonFinite { .. }) => {}
            other => panic!("{other:?}"),
        }
        match read("t,theta\n0,1\n1\n") {
            Err(InputError::Ragged {
                line: 3,
                expected: 2,
                found: 1,
            }) => {}
            other => panic!("{other:?}"),
        }
        // A decimal comma only where semicolons separate the cells.
        assert!(matches!(
            read("t theta\n0 1,5\n"),
            Err(InputError::MixedSeparators { .. })
        ));
        assert!(read_bytes(&[0xff, 0xfe, 0x00, 0x01], &ReadOptions::default()).is_err());
    }

    #[test]
    fn a_time_column_is_reported_as_a_time_whatever_its_name() {
        let named = ReadOptions {
            time: Some(Column::Name("time".into())),
            angle: Some(Column::Name("angle".into())),
            ..Default::default()
        };
        let unnamed = ReadOptions::default();
        for (text, options, role, line, says) in [
            (
                "time,angle\n0,1\nnan,2\n",
                &named,
                Role::Time,
                3,
                "the time is NaN",
            ),
            (
                "time,angle\n0,1\n1,inf\n",
                &named,
                Role::Angle,
                3,
                "a value is inf",
            ),
            ("0,1,2\n-inf,2,3\n", &unnamed, Role::Time, 2, "the time is -inf"),
            // Two unnamed columns: which is the time is not known yet.
            ("0,1\n-inf,2\n", &unnamed, Role::Angle, 2, "a value is -inf"),
        ] {
            match read_bytes(text.as_bytes(), options) {
                Err(e @ InputError::NonFinite { role: r, at, .. })
                    if r == role && at == Location::Line(line) =>
                {
                    assert!(e.to_string().contains(says), "{e}");
                }
                other => panic!("{text:?}: {other:?}"),
            }
        }
    }

    #[test]
    fn bad_cells_name_their_column() {
        match read("time,theta,t\n0,1,2\n1,x,3\n") {
            Err(InputError::NotANumber {
                line: 3,
                column,
                value,
            }) => {
                assert_eq!((column, value.as_str()), (Column::Name("theta".into()), "x"));
            }
            other => panic!("{other:?}"),
        }
        match read("0,1\nx,2\n") {
            Err(InputError::NotANumber { column, .. }) => assert_eq!(column, Column::Position(1)),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn binary_data_is_named() {
        match read_bytes(&[b'1', b',', 0xff, 0xfe, b'\n'], &ReadOptions::default()) {
            Err(e @ InputError::Malformed { line: 1, .. }) => {
                assert!(e.to_string().contains("binary data"), "{e}");
                assert!(std::error::Error::source(&e).is_some());
            }
            other => panic!("{other:?}"),
        }
    }

    proptest::proptest! {
        #[test]
        fn csv_never_panics_on_arbitrary_bytes(bytes in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..300)) {
            for options in [ReadOptions::default(), ReadOptions { dt: Some(0.1), ..Default::default() }] {
                if let Err(e) = read_bytes(&bytes, &options) {
                    proptest::prop_assert!(e.is_about_the_content(), "{e:?}");
                }
            }
        }

        #[test]
        fn csv_round_trips_numbers(
            values in proptest::collection::vec(-1e6..1e6f64, 1..50),
            separator in proptest::sample::select(vec![",", ";", " ", "\t", "  \t "]),
        ) {
            let mut text = format!("t{separator}theta\n");
            for (i, v) in values.iter().enumerate() {
                text.push_str(&format!("{i}{separator}{v}\n"));
            }
            let r = read_bytes(text.as_bytes(), &ReadOptions::default()).unwrap();
            proptest::prop_assert_eq!(r.theta, values);
        }
    }
}
