//! CSV text: comments, an optional header, columns by name or position.

use std::path::PathBuf;

use super::{Column, InputError, ReadOptions, Record};

fn column_index(
    wanted: Option<&Column>,
    header: Option<&csv::StringRecord>,
    default_name: &str,
    default_position: usize,
    width: usize,
    option: &'static str,
) -> Result<usize, InputError> {
    let missing = |wanted: String| InputError::MissingColumn {
        wanted,
        found: match header {
            Some(h) => h.iter().collect::<Vec<_>>().join(","),
            None => format!("{width} unnamed"),
        },
        option,
    };
    match (wanted, header) {
        (Some(Column::Position(p)), _) => {
            if *p <= width {
                Ok(p - 1)
            } else {
                Err(missing(p.to_string()))
            }
        }
        (Some(Column::Name(n)), Some(h)) => h
            .iter()
            .position(|c| c == n)
            .ok_or_else(|| missing(format!("'{n}'"))),
        (Some(Column::Name(n)), None) => Err(missing(format!("'{n}'"))),
        (None, Some(h)) => h
            .iter()
            .position(|c| c == default_name)
            .ok_or_else(|| missing(format!("'{default_name}'"))),
        (None, None) => {
            if default_position <= width {
                Ok(default_position - 1)
            } else {
                Err(missing(default_position.to_string()))
            }
        }
    }
}

pub(super) fn read(bytes: &[u8], options: &ReadOptions) -> Result<Record, InputError> {
    let mut reader = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .has_headers(false)
        .flexible(false)
        .trim(csv::Trim::All)
        .from_reader(bytes);
    let mut row = csv::StringRecord::new();
    let first = loop {
        match reader.read_record(&mut row) {
            Ok(false) => return Err(InputError::Empty),
            Ok(true) if row.len() == 1 && row[0].is_empty() => continue,
            Ok(true) => break row.clone(),
            Err(e) => return Err(csv_error(e)),
        }
    };
    let is_header = first.iter().any(|c| c.parse::<f64>().is_err());
    let header = is_header.then_some(&first);
    let width = first.len();
    let time = match options.dt {
        Some(_) => None,
        None => {
            if header.is_none() && width == 1 && options.time.is_none() {
                return Err(InputError::NeedStep);
            }
            Some(column_index(
                options.time.as_ref(),
                header,
                "t",
                1,
                width,
                "--time-col",
            )?)
        }
    };
    let angle_default = if options.dt.is_some() { 1 } else { 2 };
    let angle = column_index(
        options.angle.as_ref(),
        header,
        "theta",
        angle_default,
        width,
        "--angle-col",
    )?;
    let name = |i: usize| match header {
        Some(h) => format!("'{}'", &h[i]),
        None => (i + 1).to_string(),
    };
    let (time_name, angle_name) = (time.map(name).unwrap_or_default(), name(angle));

    let mut record = Record {
        lines: Some(Vec::new()),
        ..Record::default()
    };
    let lines = record.lines.as_mut().expect("text input has lines");
    let mut counter = LineCounter {
        bytes,
        pos: 0,
        line: 1,
    };
    let mut push = |row: &csv::StringRecord| -> Result<(), InputError> {
        let line = row.position().map_or(0, |p| counter.line_at(p.byte()));
        if let Some(it) = time {
            record.t.push(cell(row, it, &time_name, line)?);
        }
        record.theta.push(cell(row, angle, &angle_name, line)?);
        lines.push(line);
        Ok(())
    };
    if !is_header {
        push(&first)?;
    }
    loop {
        match reader.read_record(&mut row) {
            Ok(false) => break,
            Ok(true) if row.len() == 1 && row[0].is_empty() => continue,
            Ok(true) => push(&row)?,
            Err(e) => return Err(csv_error(e)),
        }
    }
    if record.theta.is_empty() {
        return Err(InputError::NoData);
    }
    if let Some(dt) = options.dt {
        record.t = (0..record.theta.len()).map(|n| n as f64 * dt).collect();
    }
    Ok(record)
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

fn cell(row: &csv::StringRecord, index: usize, column: &str, line: u64) -> Result<f64, InputError> {
    let text = &row[index];
    let value: f64 = text.parse().map_err(|_| InputError::NotANumber {
        line,
        column: column.to_owned(),
        value: text.chars().take(40).collect(),
    })?;
    if !value.is_finite() {
        return Err(InputError::NonFinite {
            at: format!("line {line}"),
            what: if column == "'t'" { "the time" } else { "a value" },
            value,
        });
    }
    Ok(value)
}

fn csv_error(e: csv::Error) -> InputError {
    let line = e.position().map_or(0, |p| p.line());
    match e.into_kind() {
        csv::ErrorKind::UnequalLengths {
            expected_len,
            len,
            pos,
        } => InputError::Ragged {
            line: pos.map_or(line, |p| p.line()),
            expected: expected_len as usize,
            found: len as usize,
        },
        csv::ErrorKind::Utf8 { pos, .. } => InputError::Malformed {
            line: pos.map_or(line, |p| p.line()),
            why: "not UTF-8 text (binary data?)".to_owned(),
        },
        csv::ErrorKind::Io(source) => InputError::Io {
            path: PathBuf::from("<input>"),
            source,
        },
        other => InputError::Malformed {
            line,
            why: format!("{other:?}"),
        },
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
            Err(InputError::NonFinite { at, .. }) if at == "line 3" => {}
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

    proptest::proptest! {
        #[test]
        fn csv_never_panics_on_arbitrary_bytes(bytes in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..300)) {
            let _ = read_bytes(&bytes, &ReadOptions::default());
            let _ = read_bytes(&bytes, &ReadOptions { dt: Some(0.1), ..Default::default() });
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
