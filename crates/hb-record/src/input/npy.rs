//! NumPy `.npy` arrays: 1-D (the angle) or 2-D (samples × channels).

use std::io::Read;

use super::{InputError, Location, ReadOptions, Record, Role, Times, grid};

fn npy_error(why: impl std::fmt::Display) -> InputError {
    InputError::Npy { why: why.to_string() }
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
    let npy = match npy.try_data::<f64>() {
        Ok(r) => return collect(r),
        Err(npy) => npy,
    };
    let npy = match npy.try_data::<f32>() {
        Ok(r) => return collect(r),
        Err(npy) => npy,
    };
    let npy = match npy.try_data::<i32>() {
        Ok(r) => return collect(r),
        Err(npy) => npy,
    };
    let npy = match npy.try_data::<i16>() {
        Ok(r) => return collect(r),
        Err(npy) => npy,
    };
    match npy.try_data::<i64>() {
        // Encoder counts fit in 53 bits; larger ones would not convert exactly and are refused.
        Ok(r) => r
            .map(|v| {
                let v = v.map_err(npy_error)?;
                if v.unsigned_abs() > (1u64 << 53) {
                    Err(npy_error(format!("integer {v} is too large to convert exactly")))
                } else {
                    Ok(v as f64)
                }
            })
            .collect(),
        Err(npy) => Err(npy_error(format!(
            "element type {:?} is not supported (use f8, f4, i8, i4 or i2)",
            npy.dtype()
        ))),
    }
}

/// Reads an `.npy` array; the options are assumed valid.
pub(super) fn read(bytes: &[u8], options: &ReadOptions) -> Result<Record, InputError> {
    let array = Array::open(bytes)?;
    let columns = options.columns(None, array.cols)?;
    let theta = array.column(columns.angle);
    let t = match columns.time {
        Times::Column(c) => array.column(c),
        Times::Step(dt) => grid(array.rows, dt)?,
    };
    // Until the data decide which column is the time, neither is called one.
    let time_role = if columns.order_from_data {
        Role::Angle
    } else {
        Role::Time
    };
    check_finite(&t, time_role, &theta)?;
    let read = |role: Role, cs: &[usize]| -> Result<Vec<Vec<f64>>, InputError> {
        cs.iter()
            .map(|&c| {
                let values = array.column(c);
                match values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
                    Some((i, &value)) => Err(InputError::NonFinite {
                        at: Location::Sample(i + 1),
                        role,
                        value,
                    }),
                    None => Ok(values),
                }
            })
            .collect()
    };
    let others = read(Role::Angle, &columns.others)?;
    let drives = read(Role::Drive, &columns.drives)?;
    let velocities = read(Role::Velocity, &columns.velocities)?;
    let mut record = Record {
        t,
        theta,
        others,
        lines: None,
        drives,
        velocities,
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
fn check_finite(t: &[f64], time_role: Role, theta: &[f64]) -> Result<(), InputError> {
    for (i, (&ti, &xi)) in t.iter().zip(theta).enumerate() {
        for (role, value) in [(time_role, ti), (Role::Angle, xi)] {
            if !value.is_finite() {
                return Err(InputError::NonFinite {
                    at: Location::Sample(i + 1),
                    role,
                    value,
                });
            }
        }
    }
    Ok(())
}
