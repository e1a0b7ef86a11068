//! CSV text: comments, an optional header, columns by name or position.

use std::path::PathBuf;

use csv::StringRecord;

use super::{Column, Columns, InputError, Location, ReadOptions, Record, Role, Times, grid};

/// Reads CSV text; the options are assumed valid.
pub(super) fn read(bytes: &[u8], options: &ReadOptions) -> Result<Record, InputError> {
    let mut reader = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .has_headers(false)
        .flexible(false)
        .trim(csv::Trim::All)
        .from_reader(bytes);
    let mut row = StringRecord::new();
    if !next_row(&mut reader, &mut row)? {
        return Err(InputError::Empty);
    }
    let first = row.clone();
    let header = first.iter().any(|c| c.parse::<f64>().is_err()).then_some(&first);
    let names: Option<Vec<&str>> = header.map(|h| h.iter().collect());
    let Columns { time, angle } = options.columns(names.as_deref(), first.len())?;
    let field = |role, index| Field { index, role, header };
    let (time_field, angle_field) = (
        time.column().map(|i| field(Role::Time, i)),
        field(Role::Angle, angle),
    );

    let mut record = Record::default();
    let mut lines = Vec::new();
    let mut counter = LineCounter {
        bytes,
        pos: 0,
        line: 1,
    };
    let mut push = |row: &StringRecord| -> Result<(), InputError> {
        let line = row.position().map_or(0, |p| counter.line_at(p.byte()));
        if let Some(time) = &time_field {
            record.t.push(time.value(row, line)?);
        }
        record.theta.push(angle_field.value(row, line)?);
        lines.push(line);
        Ok(())
    };
    if header.is_none() {
        push(&first)?;
    }
    while next_row(&mut reader, &mut row)? {
        push(&row)?;
    }
    if record.theta.is_empty() {
        return Err(InputError::NoData);
    }
    if let Times::Step(dt) = time {
        record.t = grid(record.theta.len(), dt);
    }
    record.lines = Some(lines);
    Ok(record)
}

/// The next row that is not blank, into `row`; false at the end of the input.
fn next_row(reader: &mut csv::Reader<&[u8]>, row: &mut StringRecord) -> Result<bool, InputError> {
    loop {
        match reader.read_record(row) {
            Ok(true) if row.len() == 1 && row[0].is_empty() => continue,
            Ok(more) => return Ok(more),
            Err(e) => return Err(csv_error(e)),
        }
    }
}

/// Physical line numbers (comment lines included, which the CSV parser does not count) from
/// byte offsets that only move forward.
struct LineCounter<'a> {
    bytes: &'a [u8],
    pos: usize,
    line: u64,
}

impl LineCounter<'_> {
    fn line_at(&mut self, byte: u64) -> u64 {
        let target = (byte as usize).min(self.bytes.len());
        if target > self.pos {
            self.line += self.bytes[self.pos..target]
                .iter()
                .filter(|&&b| b == b'\n')
                .count() as u64;
            self.pos = target;
        }
        // The parser's record position may point at comment or blank lines skipped before it.
        while self.pos < self.bytes.len() && matches!(self.bytes[self.pos], b'#' | b'\n' | b'\r') {
            match self.bytes[self.pos..].iter().position(|&b| b == b'\n') {
                Some(nl) => {
                    self.pos += nl + 1;
                    self.line += 1;
                }
                None => break,
            }
        }
        self.line
    }
}

/// A column read from every row: where it is, what it holds, and the header to name it in errors.
struct Field<'a> {
    index: usize,
    role: Role,
    header: Option<&'a StringRecord>,
}

impl Field<'_> {
    /// The finite number in this column of `row`, which is on `line`.
    fn value(&self, row: &StringRecord, line: u64) -> Result<f64, InputError> {
        let text = &row[self.index];
        let value: f64 = text.parse().map_err(|_| InputError::NotANumber {
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

fn csv_error(e: csv::Error) -> InputError {
    let line = e.position().map_or(0, |p| p.line());
    match *e.kind() {
        csv::ErrorKind::UnequalLengths {
            expected_len, len, ..
        } => InputError::Ragged {
            line,
            expected: expected_len as usize,
            found: len as usize,
        },
        // Not from text in memory, but the parser reads any source.
        csv::ErrorKind::Io(_) => match e.into_kind() {
            csv::ErrorKind::Io(source) => InputError::Io {
                path: PathBuf::from("<input>"),
                source,
            },
            _ => unreachable!("the kind was Io"),
        },
        _ => InputError::Malformed { line, source: e },
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

    #[test]
    fn reads_with_comments_and_extra_columns() {
        let r = read("# a comment\nt,theta,omega\n0,0.1,0\n# mid\n0.5,-3.0,1e-3\n").unwrap();
        assert_eq!(r.t, vec![0.0, 0.5]);
        assert_eq!(r.theta, vec![0.1, -3.0]);
        assert_eq!(r.lines, Some(vec![3, 5]));
        let r = read("theta, t\n1,2\n").unwrap();
        assert_eq!((r.t[0], r.theta[0]), (2.0, 1.0));
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
            dt: None,
        };
        let r = with("time,x,angle\n0,9,1\n1,9,2\n", opts).unwrap();
        assert_eq!(r.theta, vec![1.0, 2.0]);
        assert!("0".parse::<Column>().is_err());
        assert!("".parse::<Column>().is_err());
        let both = ReadOptions {
            time: Some(Column::Position(1)),
            dt: Some(1.0),
            angle: None,
        };
        assert!(matches!(with("1,2\n", both), Err(InputError::TimeTwice)));
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
        assert!(read_bytes(&[0xff, 0xfe, 0x00, 0x01], &ReadOptions::default()).is_err());
    }

    #[test]
    fn a_time_column_is_reported_as_a_time_whatever_its_name() {
        let named = ReadOptions {
            time: Some(Column::Name("time".into())),
            angle: Some(Column::Name("angle".into())),
            dt: None,
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
            ("0,1\n-inf,2\n", &unnamed, Role::Time, 2, "the time is -inf"),
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
    fn binary_data_keeps_the_parser_complaint() {
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
        fn csv_round_trips_numbers(values in proptest::collection::vec(-1e6..1e6f64, 1..50)) {
            let mut text = String::from("t,theta\n");
            for (i, v) in values.iter().enumerate() {
                text.push_str(&format!("{i},{v}\n"));
            }
            let r = read_bytes(text.as_bytes(), &ReadOptions::default()).unwrap();
            proptest::prop_assert_eq!(r.theta, values);
        }
    }
}
