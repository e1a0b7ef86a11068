//! NumPy `.npy` arrays: 1-D (the angle) or 2-D (samples × channels).

use std::io::Read;

use super::{Column, InputError, Location, ReadOptions, Record, Role, Times, grid, read_up_to};

/// An `.npy` error in one line: the header parser's errors draw the header over several lines
/// with a caret under the fault; that becomes the column it names and what it expected.
fn npy_error(why: impl std::fmt::Display) -> InputError {
    let text = why.to_string();
    if !text.contains('\n') {
        return InputError::Npy { why: text };
    }
    // Its lines less the drawing (the header's text after "1 |", the bars and the caret).
    let kept: Vec<&str> = text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('|') && !l.starts_with(|c: char| c.is_ascii_digit()))
        .map(|l| l.trim_start_matches('=').trim())
        .collect();
    let mut why = kept.join(" ");
    // "--> 1:57": the line and column of the header's text.
    if let Some(at) = why.find("-->") {
        let rest = &why[at + 3..];
        let place = rest.split_whitespace().next().unwrap_or("");
        let column = place.rsplit(':').next().unwrap_or(place);
        let tail = rest.trim_start()[place.len()..].trim_start().to_owned();
        why = format!(
            "{} at column {column} of the header: {tail}",
            why[..at].trim_end()
        );
    }
    InputError::Npy { why }
}

/// Reads all elements of an `.npy` payload as f64, whatever the supported element type.
fn npy_values(npy: npyz::NpyFile<&[u8]>) -> Result<Vec<f64>, InputError> {
    fn collect<T: npyz::Deserialize + Into<f64>, R: Read>(
        r: npyz::NpyReader<T, R>,
    ) -> Result<Vec<f64>, InputError> {
        r.map(|v| v.map(Into::into))
            .collect::<Result<_, _>>()
            .map_err(npy_error)
    }
    // Each type that converts exactly, tried in turn: floats, signed integers, and unsigned
    // counts (an encoder's 16-bit counter) and bytes.
    macro_rules! exactly {
        ($npy:ident: $($t:ty),*) => {
            $(
                let $npy = match $npy.try_data::<$t>() {
                    Ok(r) => return collect(r),
                    Err(npy) => npy,
                };
            )*
        };
    }
    exactly!(npy: f64, f32, i32, i16, u16, u32, u8, i8);
    // Encoder counts fit in 53 bits; larger ones would not convert exactly and are refused.
    let too_large =
        |v: &dyn std::fmt::Display| npy_error(format!("integer {v} is too large to convert exactly"));
    let npy = match npy.try_data::<i64>() {
        Ok(r) => {
            return r
                .map(|v| {
                    let v = v.map_err(npy_error)?;
                    if v.unsigned_abs() > (1u64 << 53) {
                        Err(too_large(&v))
                    } else {
                        Ok(v as f64)
                    }
                })
                .collect();
        }
        Err(npy) => npy,
    };
    match npy.try_data::<u64>() {
        Ok(r) => r
            .map(|v| {
                let v = v.map_err(npy_error)?;
                if v > (1u64 << 53) {
                    Err(too_large(&v))
                } else {
                    Ok(v as f64)
                }
            })
            .collect(),
        Err(npy) => Err(npy_error(format!(
            "element type {} is not supported (use one of f8, f4, i8, i4, i2, i1, u8, u4, u2, u1: \
             NumPy's float64, float32, int64 to int8 and uint64 to uint8)",
            npy.dtype().descr()
        ))),
    }
}

/// Reads an `.npy` array; the options are assumed valid.
pub(super) fn read(bytes: &[u8], options: &ReadOptions) -> Result<Record, InputError> {
    let array = Array::open(bytes)?;
    let columns = options.columns(None, array.cols)?;
    assemble(array.rows, &columns, options.skip_missing, |c| array.column(c))
}

/// Bytes of a file read at once by [`read_file`]: its header, then its rows a block at a time.
const FILE_BLOCK: usize = 1 << 20;

/// Reads an `.npy` file of little-endian f8 in C order (what NumPy writes by default, and
/// `hbid simulate`) from `file` of `len` bytes, its columns straight from the file a block at a
/// time, without the whole file in memory first: a record of 10^6 samples then touches a third
/// less fresh memory, and a process reading it cold spends that much less in page faults.
/// `None` (nothing of the record read, `file` anywhere) for every other file, which
/// [`read`] reads whole: another magic, element type or order, a header past the first block,
/// or one that [`read`] refuses (it says why). The options are assumed valid.
pub(super) fn read_file(
    file: &mut impl Read,
    len: u64,
    options: &ReadOptions,
    io: impl Fn(std::io::Error) -> InputError,
) -> Result<Option<Record>, InputError> {
    let mut first = Vec::with_capacity(FILE_BLOCK.min(len as usize));
    file.by_ref()
        .take(FILE_BLOCK as u64)
        .read_to_end(&mut first)
        .map_err(&io)?;
    let Some(header) = plain_header(&first, len) else {
        return Ok(None);
    };
    let columns = options.columns(None, header.cols)?;
    let row = 8 * header.cols;
    // The columns the record takes, each filled as the rows arrive, and how many times each is
    // taken.
    let mut wanted: Vec<Option<Vec<f64>>> = vec![None; header.cols];
    let mut uses = vec![0usize; header.cols];
    let time = match columns.time {
        Times::Column(c) => Some(c),
        Times::Step(_) => None,
    };
    for c in std::iter::once(columns.angle)
        .chain(time)
        .chain(columns.others.iter().copied())
        .chain(columns.drives.iter().copied())
        .chain(columns.velocities.iter().copied())
    {
        uses[c] += 1;
        wanted[c].get_or_insert_with(|| Vec::with_capacity(header.rows));
    }
    let mut rows_left = header.rows;
    let mut take = |block: &[u8], rows_left: &mut usize| -> usize {
        let rows = (block.len() / row).min(*rows_left);
        for (c, column) in wanted.iter_mut().enumerate() {
            if let Some(column) = column {
                column.extend(
                    block[..rows * row]
                        .chunks_exact(row)
                        .map(|r| f64::from_le_bytes(r[8 * c..8 * c + 8].try_into().expect("eight bytes"))),
                );
            }
        }
        *rows_left -= rows;
        rows * row
    };
    // The payload's rows in the first block, then block after block; a row cut by a block's end
    // is carried to the next.
    let mut buf = first;
    let used = take(&buf[header.payload..], &mut rows_left);
    buf.drain(..header.payload + used);
    while rows_left > 0 {
        let have = buf.len();
        let want = (FILE_BLOCK / row).max(1).min(rows_left) * row;
        buf.resize(want.max(have), 0);
        let got = read_up_to(file, &mut buf[have..]).map_err(&io)?;
        buf.truncate(have + got);
        if got == 0 {
            // The file is shorter than when its length was taken.
            return Err(npy_error(format!(
                "the header announces {} rows but the file ends after {}",
                header.rows,
                header.rows - rows_left
            )));
        }
        let used = take(&buf, &mut rows_left);
        buf.drain(..used);
    }
    // A column taken more than once (the angle also a drive) is copied for all but its last use.
    assemble(header.rows, &columns, options.skip_missing, |c| {
        uses[c] -= 1;
        match (&mut wanted[c], uses[c]) {
            (slot, 0) => slot.take(),
            (slot, _) => slot.clone(),
        }
        .expect("every column taken was read")
    })
    .map(Some)
}

/// The shape of a plain array and where its payload starts in its file.
struct PlainHeader {
    rows: usize,
    cols: usize,
    /// The payload's first byte in the file.
    payload: usize,
}

/// The header at the start of `first` (the first bytes of a file of `len` bytes) when [`read`]
/// would read the file as little-endian f8 in C order, 1-D or 2-D, with at least one row and
/// column, and the payload holding them; `None` otherwise.
fn plain_header(first: &[u8], len: u64) -> Option<PlainHeader> {
    if !first.starts_with(b"\x93NUMPY") {
        return None;
    }
    check_header(first).ok()?;
    let mut probe = first;
    npyz::NpyHeader::from_reader(&mut probe).ok()?;
    let payload = first.len() - probe.len();
    let npy = npyz::NpyFile::new(first).ok()?;
    if npy.dtype().descr() != "'<f8'" || npy.order() != npyz::Order::C {
        return None;
    }
    check_size(
        npy.shape(),
        &npy.dtype(),
        usize::try_from(len).ok()?.checked_sub(payload)?,
    )
    .ok()?;
    let (rows, cols) = matrix_shape(npy.shape()).ok()?;
    (rows > 0 && cols > 0).then_some(PlainHeader { rows, cols, payload })
}

/// The record of an array of `rows` rows read by `columns`, each column's values given by
/// `column` (asked once for each use); with `skip_missing`, the rows with a NaN in a column read
/// left out ([`ReadOptions::skip_missing`]).
fn assemble(
    rows: usize,
    columns: &super::Columns,
    skip_missing: bool,
    mut column: impl FnMut(usize) -> Vec<f64>,
) -> Result<Record, InputError> {
    let mut theta = column(columns.angle);
    let mut t = match columns.time {
        Times::Column(c) => column(c),
        Times::Step(dt) => grid(rows, dt)?,
    };
    let mut others: Vec<Vec<f64>> = columns.others.iter().map(|&c| column(c)).collect();
    let mut drives: Vec<Vec<f64>> = columns.drives.iter().map(|&c| column(c)).collect();
    let mut velocities: Vec<Vec<f64>> = columns.velocities.iter().map(|&c| column(c)).collect();
    let mut missing = Vec::new();
    if skip_missing {
        let nan_at = |i: usize| {
            std::iter::once(&t)
                .chain([&theta])
                .chain(&others)
                .chain(&drives)
                .chain(&velocities)
                .any(|v| v[i].is_nan())
        };
        let keep: Vec<bool> = (0..rows).map(|i| !nan_at(i)).collect();
        missing = (0..rows)
            .filter(|&i| !keep[i])
            .map(|i| Location::Sample(i + 1))
            .collect();
        if !missing.is_empty() {
            if missing.len() == rows {
                return Err(InputError::AllMissing { rows });
            }
            for v in std::iter::once(&mut t)
                .chain([&mut theta])
                .chain(&mut others)
                .chain(&mut drives)
                .chain(&mut velocities)
            {
                let mut k = keep.iter();
                v.retain(|_| *k.next().expect("one flag a row"));
            }
        }
    }
    // Each row kept names its own sample in errors.
    let sample = |i: usize| match super::sample_location(&missing, i) {
        Location::Sample(s) => s,
        Location::Line(_) => i + 1,
    };
    // Until the data decide which column is the time, neither is called one.
    let time_role = if columns.order_from_data {
        Role::Angle
    } else {
        Role::Time
    };
    check_finite(
        &t,
        time_role,
        columns.time.column(),
        &theta,
        columns.angle,
        &sample,
    )?;
    let finite = |role: Role, cs: &[usize], values: &[Vec<f64>]| -> Result<(), InputError> {
        for (&c, values) in cs.iter().zip(values) {
            if let Some((i, &value)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
                return Err(InputError::NonFinite {
                    at: Location::Sample(sample(i)),
                    role,
                    column: Column::Position(c + 1),
                    value,
                });
            }
        }
        Ok(())
    };
    finite(Role::Angle, &columns.others, &others)?;
    finite(Role::Drive, &columns.drives, &drives)?;
    finite(Role::Velocity, &columns.velocities, &velocities)?;
    let mut record = Record {
        t,
        theta,
        others,
        lines: None,
        drives,
        velocities,
        missing,
    };
    if columns.order_from_data {
        super::order_from_data(&mut record);
    }
    Ok(record)
}

/// An array as a matrix: samples in rows, channels in columns (a 1-D array is one column).
struct Array<'a> {
    rows: usize,
    cols: usize,
    order: npyz::Order,
    elements: Elements<'a>,
}

/// The elements of an array, in its order.
enum Elements<'a> {
    /// Little-endian f8, the usual case (and 10^7-sample records): read straight from the
    /// payload, without a converted copy of every element.
    F8(&'a [u8]),
    /// Any other supported type, converted.
    Converted(Vec<f64>),
}

impl<'a> Array<'a> {
    /// Reads the header, checks it against the payload, and converts the elements unless they are
    /// little-endian f8.
    fn open(bytes: &'a [u8]) -> Result<Self, InputError> {
        check_header(bytes)?;
        let mut probe = bytes;
        npyz::NpyHeader::from_reader(&mut probe).map_err(npy_error)?;
        let payload = &bytes[bytes.len() - probe.len()..];
        let npy = npyz::NpyFile::new(bytes).map_err(npy_error)?;
        check_size(npy.shape(), &npy.dtype(), payload.len())?;
        let (rows, cols) = matrix_shape(npy.shape())?;
        if rows == 0 || cols == 0 {
            return Err(InputError::NoData);
        }
        let order = npy.order();
        let elements = if npy.dtype().descr() == "'<f8'" {
            Elements::F8(payload)
        } else {
            Elements::Converted(npy_values(npy)?)
        };
        Ok(Self {
            rows,
            cols,
            order,
            elements,
        })
    }

    /// Column `c` (from 0), every row.
    fn column(&self, c: usize) -> Vec<f64> {
        let f8 = |bytes: &[u8]| f64::from_le_bytes(bytes.try_into().expect("eight bytes"));
        match (&self.elements, self.order) {
            // The payload's rows in order, without an index computed per element.
            (Elements::F8(payload), npyz::Order::C) => payload
                .chunks_exact(8 * self.cols)
                .take(self.rows)
                .map(|row| f8(&row[8 * c..8 * c + 8]))
                .collect(),
            (Elements::F8(payload), npyz::Order::Fortran) => payload[8 * c * self.rows..]
                .chunks_exact(8)
                .take(self.rows)
                .map(f8)
                .collect(),
            _ => (0..self.rows).map(|r| self.get(r, c)).collect(),
        }
    }

    fn get(&self, r: usize, c: usize) -> f64 {
        let i = match self.order {
            npyz::Order::C => r * self.cols + c,
            npyz::Order::Fortran => c * self.rows + r,
        };
        match &self.elements {
            Elements::F8(payload) => {
                let mut le = [0u8; 8];
                le.copy_from_slice(&payload[8 * i..8 * i + 8]);
                f64::from_le_bytes(le)
            }
            Elements::Converted(values) => values[i],
        }
    }
}

/// Deepest nesting of brackets in a header that [`check_header`] lets through: a plain array's
/// header is a dictionary holding a tuple (2 deep); structured element types nest deeper but are
/// not read here anyway.
const MAX_HEADER_DEPTH: usize = 4;

/// Checks a header before it is parsed: the file must hold as many bytes as its first bytes
/// announce (a 16-bit length for format 1, 32-bit for formats 2 and 3; a reader allocates what it
/// says), and brackets may not nest deeper than [`MAX_HEADER_DEPTH`] (the parser of the header's
/// Python literal takes time exponential in the depth: 20 brackets take seconds).
pub(super) fn check_header(bytes: &[u8]) -> Result<(), InputError> {
    // The magic (6 bytes) and the version (2) come first.
    let (size, length) = match bytes.get(6..8) {
        Some([1, 0]) => (
            2,
            bytes
                .get(8..10)
                .map(|b| u64::from(u16::from_le_bytes([b[0], b[1]]))),
        ),
        Some([2 | 3, 0]) => (
            4,
            bytes
                .get(8..12)
                .map(|b| u64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))),
        ),
        Some(&[major, minor]) => {
            return Err(npy_error(format!(
                "format version {major}.{minor} is not supported"
            )));
        }
        _ => return Err(npy_error("the file ends inside the format version")),
    };
    let length = length.ok_or_else(|| npy_error("the file ends inside the header length"))?;
    let header = &bytes[8 + size..];
    if length > header.len() as u64 {
        return Err(npy_error(format!(
            "the header announces {length} bytes but the file holds {} after the header length",
            header.len()
        )));
    }
    let (mut depth, mut deepest) = (0usize, 0usize);
    for &b in &header[..length as usize] {
        match b {
            b'(' | b'[' | b'{' => {
                depth += 1;
                deepest = deepest.max(depth);
            }
            b')' | b']' | b'}' => depth = depth.saturating_sub(1),
            _ => {}
        }
    }
    if deepest > MAX_HEADER_DEPTH {
        return Err(npy_error(format!(
            "the header nests brackets {deepest} deep; a plain array's header needs at most {MAX_HEADER_DEPTH}"
        )));
    }
    Ok(())
}

/// Checks that the payload holds the elements the header announces, before anything the header
/// claims is allocated.
fn check_size(shape: &[u64], dtype: &npyz::DType, payload: usize) -> Result<(), InputError> {
    let total: u64 = shape
        .iter()
        .try_fold(1u64, |a, &b| a.checked_mul(b))
        .ok_or_else(|| npy_error("shape overflows"))?;
    let item = dtype.num_bytes().unwrap_or(usize::MAX) as u64;
    if total.checked_mul(item).is_none_or(|n| n > payload as u64) {
        return Err(npy_error(format!(
            "the header announces {total} elements but the file holds {payload} bytes of data"
        )));
    }
    Ok(())
}

/// Rows (samples) and columns (channels) of a 1-D or 2-D shape.
fn matrix_shape(shape: &[u64]) -> Result<(usize, usize), InputError> {
    match *shape {
        [n] => Ok((n as usize, 1)),
        [n, m] => Ok((n as usize, m as usize)),
        _ => Err(npy_error(format!(
            "shape {shape:?}: expected 1-D (angle) or 2-D (samples × channels)"
        ))),
    }
}

/// Checks that every time (read as `time_role`) and value is finite, naming the first sample
/// that is not.
fn check_finite(
    t: &[f64],
    time_role: Role,
    time_column: Option<usize>,
    theta: &[f64],
    angle_column: usize,
    sample: &dyn Fn(usize) -> usize,
) -> Result<(), InputError> {
    for (i, (&ti, &xi)) in t.iter().zip(theta).enumerate() {
        // A grid made from a step is finite: its column is never named.
        for (role, column, value) in [
            (time_role, time_column.unwrap_or(0), ti),
            (Role::Angle, angle_column, xi),
        ] {
            if !value.is_finite() {
                return Err(InputError::NonFinite {
                    at: Location::Sample(sample(i)),
                    role,
                    column: Column::Position(column + 1),
                    value,
                });
            }
        }
    }
    Ok(())
}
