//! Text records: comments, an optional header (and a row of units under it), cells separated by
//! commas, semicolons or white space, columns by name or position.

use super::{
    Column, Columns, InputError, Location, ReadOptions, Record, Role, Separator, Times, grid, grid_of,
};

/// Reads text; the options are assumed valid.
pub(super) fn read<'a>(bytes: &'a [u8], options: &ReadOptions) -> Result<Record, InputError> {
    let (mut lines, first_line, first, separator) = first_row(bytes)?;
    let mut first_cells = Vec::new();
    separator.split(first, &mut first_cells);
    let width = first_cells.len();
    let is_header = is_header(&first_cells, separator);
    let header = is_header.then_some(&first_cells[..]);
    let columns = options.columns(header, width)?;
    let Columns { time, angle, .. } = columns.clone();
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
    let other_fields: Vec<Field<'_>> = columns.others.iter().map(|&i| field(Role::Angle, i)).collect();
    // The columns read, where a row of units names at least one unit.
    let read_columns: Vec<usize> = time
        .column()
        .into_iter()
        .chain([angle])
        .chain(columns.others.iter().copied())
        .chain(columns.drives.iter().copied())
        .chain(columns.velocities.iter().copied())
        .collect();
    let drive_fields: Vec<Field<'_>> = columns.drives.iter().map(|&i| field(Role::Drive, i)).collect();
    let velocity_fields: Vec<Field<'_>> = columns
        .velocities
        .iter()
        .map(|&i| field(Role::Velocity, i))
        .collect();

    let mut record = Record {
        others: vec![Vec::new(); other_fields.len()],
        drives: vec![Vec::new(); drive_fields.len()],
        velocities: vec![Vec::new(); velocity_fields.len()],
        ..Record::default()
    };
    let mut numbers = Vec::new();
    let mut cells: Vec<&'a str> = Vec::with_capacity(width);
    let mut values: Vec<f64> = Vec::with_capacity(width);
    // Every row of data's place, and the places of those kept when rows are left out.
    let (mut rows, mut places) = (0usize, Vec::new());
    let mut push = |line: u64, text: &'a str, cells: &mut Vec<&'a str>| -> Result<(), InputError> {
        rows += 1;
        // A row of numbers only, each cell parsed as it is found: the common row, without
        // splitting it first; any other row takes the general path below.
        if numbers_only(text, separator, &mut values) && values.len() == width {
            // Every debug build (the tests' too) reads the row the general way as well: the same
            // separator, the same cells, and each cell's number the same bits.
            #[cfg(debug_assertions)]
            {
                assert_eq!(
                    separator.of_row(text).filter(|&s| s != separator && width > 1),
                    None,
                    "{text}"
                );
                separator.split(text, cells);
                let general: Vec<u64> = cells
                    .iter()
                    .map(|c| number(c, separator).map_or(u64::MAX, f64::to_bits))
                    .collect();
                let quick: Vec<u64> = values.iter().map(|v| v.to_bits()).collect();
                assert_eq!(quick, general, "the cells of {text:?}");
            }
            let cell = |field: &Field<'_>| values[field.index];
            if let Some(time) = &time_field {
                record.t.push(cell(time));
            }
            record.theta.push(cell(&angle_field));
            for (field, column) in other_fields.iter().zip(&mut record.others) {
                column.push(cell(field));
            }
            for (field, column) in drive_fields.iter().zip(&mut record.drives) {
                column.push(cell(field));
            }
            for (field, column) in velocity_fields.iter().zip(&mut record.velocities) {
                column.push(cell(field));
            }
            numbers.push(line);
            if options.skip_missing {
                places.push(rows - 1);
            }
            return Ok(());
        }
        if let Some(found) = separator.of_row(text).filter(|&s| s != separator && width > 1) {
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
        if options.skip_missing
            && time_field
                .iter()
                .chain([&angle_field])
                .chain(&other_fields)
                .chain(&drive_fields)
                .chain(&velocity_fields)
                .any(|field| missing_value(cells[field.index], separator))
        {
            record.missing.push(Location::Line(line));
            return Ok(());
        }
        if let Some(time) = &time_field {
            record.t.push(time.value(cells, line)?);
        }
        record.theta.push(angle_field.value(cells, line)?);
        for (field, values) in other_fields.iter().zip(&mut record.others) {
            values.push(field.value(cells, line)?);
        }
        for (field, values) in drive_fields.iter().zip(&mut record.drives) {
            values.push(field.value(cells, line)?);
        }
        for (field, values) in velocity_fields.iter().zip(&mut record.velocities) {
            values.push(field.value(cells, line)?);
        }
        numbers.push(line);
        if options.skip_missing {
            places.push(rows - 1);
        }
        Ok(())
    };
    if header.is_none() {
        push(first_line, first, &mut cells)?;
    }
    let mut under_header = header.is_some();
    while let Some((line, text)) = lines.next_row()? {
        // A row of the columns' units under the header (`s, rad, N m`): as many cells, none of
        // them a number, so no data; passed as the header is.
        if std::mem::take(&mut under_header) && units_row(text, separator, width, &read_columns) {
            continue;
        }
        push(line, text, &mut cells)?;
    }
    if record.theta.is_empty() {
        return Err(match record.missing.len() {
            0 => InputError::NoData,
            rows => InputError::AllMissing { rows },
        });
    }
    if let Times::Step(dt) = time {
        record.t = if record.missing.is_empty() {
            grid(record.theta.len(), dt)?
        } else {
            grid_of(places.iter().copied(), rows, dt)?
        };
    }
    record.lines = Some(numbers);
    if columns.order_from_data {
        super::order_from_data(&mut record);
    }
    Ok(record)
}

/// The rows of `bytes` (a byte-order mark left out) after its first, that first row with its
/// line number, and the separator of its cells.
fn first_row(bytes: &[u8]) -> Result<(Lines<'_>, u64, &str, Separator), InputError> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    // A text that is UTF-8 throughout has every line so (no byte of a longer character is a
    // line end), checked once; otherwise line by line, so that the first bad row is named.
    let mut lines = Lines {
        rest: match std::str::from_utf8(bytes) {
            Ok(text) => Rest::Text(text),
            Err(_) => Rest::Bytes(bytes),
        },
        line: 0,
        // Lines end in LF (CR LF included: the CR is trimmed), or in CR alone where no LF is
        // (an old Mac's or some loggers' files).
        end: if memchr::memchr(b'\n', bytes).is_none() && memchr::memchr(b'\r', bytes).is_some() {
            b'\r'
        } else {
            b'\n'
        },
    };
    let Some((first_line, first)) = lines.next_row()? else {
        return Err(InputError::Empty);
    };
    let separator = match Separator::of(first) {
        // Tabs alone separate where the first row's cells hold spaces (a header's `time [s]`):
        // there are fewer of them between tabs than between spaces and tabs.
        Some(Separator::Tab) => {
            let mut by_tabs = Vec::new();
            let mut by_white = Vec::new();
            Separator::Tab.split(first, &mut by_tabs);
            Separator::Whitespace.split(first, &mut by_white);
            if by_tabs.len() < by_white.len() {
                Separator::Tab
            } else {
                Separator::Whitespace
            }
        }
        Some(s) => s,
        // A single cell: any separator splits it into itself.
        None => Separator::Whitespace,
    };
    Ok((lines, first_line, first, separator))
}

/// Whether `text` is a row of units under a header of `width` cells: as many cells, none of them
/// a number or a missing value's marker (`NA`, `null`, ...), at least one of the columns `read`
/// not empty (a row whose columns read are empty is data with missing values). In a text
/// separated by tabs a unit may hold a space (`rad s-1`) or be left empty (two tabs in a row),
/// so such a row is also split at each tab.
fn units_row(text: &str, separator: Separator, width: usize, read: &[usize]) -> bool {
    let units = |cells: &[&str]| {
        cells.len() == width
            && read.iter().any(|&c| cells.get(c).is_some_and(|c| !c.is_empty()))
            && cells
                .iter()
                .all(|c| c.is_empty() || (number(c, separator).is_none() && !missing_marker(c)))
    };
    let mut cells = Vec::new();
    separator.split(text, &mut cells);
    if cells.iter().any(|c| number(c, separator).is_some()) {
        return false;
    }
    if units(&cells) {
        return true;
    }
    if matches!(separator, Separator::Tab | Separator::Whitespace) && text.contains('\t') {
        let unquoted = |c: &'_ str| -> String { c.trim().trim_matches('"').trim().to_owned() };
        let tabbed: Vec<String> = text.split('\t').map(unquoted).collect();
        let tabbed: Vec<&str> = tabbed.iter().map(String::as_str).collect();
        return units(&tabbed);
    }
    false
}

/// Whether a cell holds no value: empty, a missing value's marker, or a number that is NaN
/// ([`ReadOptions::skip_missing`]).
fn missing_value(cell: &str, separator: Separator) -> bool {
    cell.is_empty() || missing_marker(cell) || number(cell, separator).is_some_and(f64::is_nan)
}

/// Whether a cell is how a program writes a missing value, not a unit.
fn missing_marker(cell: &str) -> bool {
    ["na", "n/a", "nan", "null", "none", "nil", "missing", "#n/a"]
        .iter()
        .any(|m| cell.eq_ignore_ascii_case(m))
}

/// The names of a text's header, from the first row of `bytes` (the start of a text is enough);
/// `None` when that row is not a header.
pub(super) fn header(bytes: &[u8]) -> Option<Vec<String>> {
    let (_, _, first, separator) = first_row(bytes).ok()?;
    let mut cells = Vec::new();
    separator.split(first, &mut cells);
    if !is_header(&cells, separator) {
        return None;
    }
    Some(cells.iter().map(|c| (*c).to_owned()).collect())
}

/// Whether a first row is a header: a cell in it is neither a number nor a missing value's
/// marker (`NA`, `NaN`, `null`, ...). A row of numbers and such markers (`0,NA`) is data; an
/// empty cell is a name left empty (pandas' unnamed index column, `,0,1,2`), so a first row of
/// data with an empty cell cannot be told from a header and is one.
fn is_header(cells: &[&str], separator: Separator) -> bool {
    cells
        .iter()
        .any(|c| number(c, separator).is_none() && !missing_marker(c))
}

/// The rows of a text: lines that are neither blank nor comments, with their line numbers.
struct Lines<'a> {
    /// What is left to read.
    rest: Rest<'a>,
    /// The number of the last line read, counted from 1.
    line: u64,
    /// The byte that ends a line.
    end: u8,
}

/// What is left of a text to read: checked to be UTF-8 throughout, or bytes to check line by
/// line.
enum Rest<'a> {
    Text(&'a str),
    Bytes(&'a [u8]),
}

impl Rest<'_> {
    fn is_empty(&self) -> bool {
        match self {
            Rest::Text(t) => t.is_empty(),
            Rest::Bytes(b) => b.is_empty(),
        }
    }
}

impl<'a> Lines<'a> {
    /// The next row, trimmed, with its line number; `None` at the end.
    fn next_row(&mut self) -> Result<Option<(u64, &'a str)>, InputError> {
        while !self.rest.is_empty() {
            self.line += 1;
            let text = match &mut self.rest {
                // No byte of a longer character is a line end: a text that is UTF-8 throughout
                // splits into lines that are.
                Rest::Text(text) => {
                    let (line, rest) = match memchr::memchr(self.end, text.as_bytes()) {
                        Some(e) => (&text[..e], &text[e + 1..]),
                        None => (*text, ""),
                    };
                    *text = rest;
                    line
                }
                Rest::Bytes(bytes) => {
                    let (raw, rest) = match memchr::memchr(self.end, bytes) {
                        Some(e) => (&bytes[..e], &bytes[e + 1..]),
                        None => (*bytes, &bytes[bytes.len()..]),
                    };
                    *bytes = rest;
                    std::str::from_utf8(raw).map_err(|source| InputError::Malformed {
                        line: self.line,
                        source,
                    })?
                }
            };
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
    /// commas), else commas when it holds one, else tabs when it holds one, else spaces when it
    /// holds any; `None` for a single cell. (A first row of tabs is read as one of tabs alone
    /// only where its cells hold spaces, see `read`.)
    fn of(text: &str) -> Option<Self> {
        let bytes = text.as_bytes();
        let (semicolon, comma, tab, space) = if memchr::memchr(b'"', bytes).is_some() {
            // What is between double quotes is a cell's own: one pass, nothing copied.
            let (mut quoted, mut found) = (false, [false; 4]);
            for &b in bytes {
                match b {
                    b'"' => quoted = !quoted,
                    _ if quoted => {}
                    b';' => found[0] = true,
                    b',' => found[1] = true,
                    b'\t' => found[2] = true,
                    b' ' => found[3] = true,
                    _ => {}
                }
            }
            (found[0], found[1], found[2], found[3])
        } else {
            (
                memchr::memchr(b';', bytes).is_some(),
                memchr::memchr(b',', bytes).is_some(),
                memchr::memchr(b'\t', bytes).is_some(),
                memchr::memchr(b' ', bytes).is_some(),
            )
        };
        if semicolon {
            Some(Separator::Semicolon)
        } else if comma {
            Some(Separator::Comma)
        } else if tab {
            Some(Separator::Tab)
        } else if space {
            Some(Separator::Whitespace)
        } else {
            None
        }
    }

    /// The separator a row after the first uses, in a record whose first row uses `self`: a
    /// row of tabs and spaces (no comma or semicolon) is one of tabs in a record of tabs (its
    /// spaces inside cells) and one of spaces in a record of spaces.
    fn of_row(self, text: &str) -> Option<Self> {
        match (self, Self::of(text)) {
            (Separator::Whitespace, Some(Separator::Tab)) => Some(Separator::Whitespace),
            (Separator::Tab, Some(Separator::Whitespace)) => Some(Separator::Tab),
            (_, found) => found,
        }
    }

    /// The cells of a trimmed row into `cells`, each trimmed and without enclosing double quotes.
    fn split<'a>(self, text: &'a str, cells: &mut Vec<&'a str>) {
        fn clean(c: &str) -> &str {
            // Most cells begin and end with a visible ASCII character other than a quote:
            // nothing to take off (the bytes of a longer character are not ASCII).
            let plain = |b: u8| b.is_ascii_graphic() && b != b'"';
            if let (Some(&first), Some(&last)) = (c.as_bytes().first(), c.as_bytes().last())
                && plain(first)
                && plain(last)
            {
                return c;
            }
            let c = c.trim();
            c.strip_prefix('"')
                .and_then(|c| c.strip_suffix('"'))
                .map_or(c, str::trim)
        }
        // The cells between the separator's bytes (ASCII, so every piece is whole characters);
        // a separator between double quotes is the cell's own (`"Time, s"`).
        fn split_at<'a>(text: &'a str, separator: u8, cells: &mut Vec<&'a str>) {
            let mut start = 0;
            if memchr::memchr(b'"', text.as_bytes()).is_some() {
                let mut quoted = false;
                for (end, &b) in text.as_bytes().iter().enumerate() {
                    if b == b'"' {
                        quoted = !quoted;
                    } else if b == separator && !quoted {
                        cells.push(clean(&text[start..end]));
                        start = end + 1;
                    }
                }
            } else {
                for end in memchr::memchr_iter(separator, text.as_bytes()) {
                    cells.push(clean(&text[start..end]));
                    start = end + 1;
                }
            }
            cells.push(clean(&text[start..]));
        }
        cells.clear();
        match self {
            Separator::Comma => split_at(text, b',', cells),
            Separator::Semicolon => split_at(text, b';', cells),
            Separator::Tab => cells.extend(text.split('\t').map(clean).filter(|c| !c.is_empty())),
            Separator::Whitespace => {
                cells.extend(text.split([' ', '\t']).filter(|c| !c.is_empty()).map(clean))
            }
        }
    }
}

/// Whether the row `text` holds finite numbers only, each followed by `separator` or the row's
/// end, and if so its numbers in `values`: what the general path reads of such a row (its cells
/// split at the separator are those numbers' texts, with nothing to trim or unquote, and a
/// finite number's value is the one `str::parse` gives: both round the decimal correctly).
/// `false` at anything else (a space, a quote, a decimal comma, a cell that is no number, or
/// none, an infinity or NaN), which the general path then reads or names. White space separates
/// by a run of spaces and tabs, as [`Separator::split`] does (the row is trimmed: none at its
/// ends).
fn numbers_only(text: &str, separator: Separator, values: &mut Vec<f64>) -> bool {
    values.clear();
    let byte = match separator {
        Separator::Comma => b',',
        Separator::Semicolon => b';',
        Separator::Tab => b'\t',
        Separator::Whitespace => b' ',
    };
    let white = matches!(separator, Separator::Whitespace | Separator::Tab);
    let mut rest = text.as_bytes();
    loop {
        let Ok((value, used)) = fast_float2::parse_partial::<f64, _>(rest) else {
            return false;
        };
        if !value.is_finite() {
            return false;
        }
        values.push(value);
        match rest.get(used) {
            None => return true,
            Some(&b) if b == byte && !white => rest = &rest[used + 1..],
            Some(b' ' | b'\t') if white => {
                let gap = rest[used..]
                    .iter()
                    .take_while(|&&b| b == b' ' || b == b'\t')
                    .count();
                // Between tabs' cells a gap holds a tab (spaces alone are inside a cell).
                if separator == Separator::Tab && memchr::memchr(b'\t', &rest[used..used + gap]).is_none() {
                    return false;
                }
                rest = &rest[used + gap..];
            }
            Some(_) => return false,
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
            missing: text.is_empty() || missing_marker(text),
        })?;
        if !value.is_finite() {
            return Err(InputError::NonFinite {
                at: Location::Line(line),
                role: self.role,
                column: self.column(),
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
