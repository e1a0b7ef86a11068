//! NumPy `.npy` arrays: 1-D (the angle) or 2-D (samples × channels).

use std::io::Read;

use super::{Columns, InputError, Location, ReadOptions, Record, Role, Times, grid};

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

pub(super) fn read(bytes: &[u8], options: &ReadOptions) -> Result<Record, InputError> {
    let mut probe = bytes;
    npyz::NpyHeader::from_reader(&mut probe).map_err(npy_error)?;
    let payload = probe.len();
    let npy = npyz::NpyFile::new(bytes).map_err(npy_error)?;
    let shape: Vec<u64> = npy.shape().to_vec();
    let order = npy.order();
    let total: u64 = shape
        .iter()
        .try_fold(1u64, |a, &b| a.checked_mul(b))
        .ok_or_else(|| npy_error("shape overflows"))?;
    let item = npy.dtype().num_bytes().unwrap_or(usize::MAX) as u64;
    // Check the payload's size before allocating anything the header claims.
    if total.checked_mul(item).is_none_or(|n| n > payload as u64) {
        return Err(npy_error(format!(
            "the header announces {total} elements but the file holds {} bytes of data",
            payload
        )));
    }
    let (rows, cols) = match shape[..] {
        [n] => (n as usize, 1usize),
        [n, m] => (n as usize, m as usize),
        _ => {
            return Err(npy_error(format!(
                "shape {shape:?}: expected 1-D (angle) or 2-D (samples × channels)"
            )));
        }
    };
    if rows == 0 || cols == 0 {
        return Err(InputError::NoData);
    }
    // Little-endian f8, the usual case (and 10^7-sample records): read straight from the payload,
    // without a converted copy of every element.
    let payload_bytes = &bytes[bytes.len() - payload..];
    let plain_f8 = npy.dtype().descr() == "'<f8'";
    let values = if plain_f8 { Vec::new() } else { npy_values(npy)? };
    let index = |r: usize, c: usize| match order {
        npyz::Order::C => r * cols + c,
        npyz::Order::Fortran => c * rows + r,
    };
    let at = |r: usize, c: usize| {
        let i = index(r, c);
        if plain_f8 {
            let mut le = [0u8; 8];
            le.copy_from_slice(&payload_bytes[8 * i..8 * i + 8]);
            f64::from_le_bytes(le)
        } else {
            values[i]
        }
    };
    let Columns { time, angle } = options.columns(None, cols)?;
    let theta: Vec<f64> = (0..rows).map(|r| at(r, angle)).collect();
    let t: Vec<f64> = match time {
        Times::Column(it) => (0..rows).map(|r| at(r, it)).collect(),
        Times::Step(dt) => grid(rows, dt),
    };
    for (i, (&ti, &xi)) in t.iter().zip(&theta).enumerate() {
        for (role, value) in [(Role::Time, ti), (Role::Angle, xi)] {
            if !value.is_finite() {
                return Err(InputError::NonFinite {
                    at: Location::Sample(i + 1),
                    role,
                    value,
                });
            }
        }
    }
    Ok(Record {
        t,
        theta,
        lines: None,
    })
}

/// An `.npy` file (format 1.0) with this header and payload.
#[cfg(test)]
pub(super) fn npy_bytes(descr: &str, shape: &str, fortran: bool, payload: &[u8]) -> Vec<u8> {
    let mut header = format!(
        "{{'descr': '{descr}', 'fortran_order': {}, 'shape': {shape}, }}",
        if fortran { "True" } else { "False" }
    );
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    out.extend_from_slice(payload);
    out
}

#[cfg(test)]
mod tests {
    use super::super::*;
    use super::npy_bytes;

    #[test]
    fn reads_npy_1d_2d_and_orders() {
        let f8: Vec<u8> = [0.0f64, 0.5, 1.0, 0.1, 0.2, 0.3]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        // C order, 3 samples × 2 channels: rows (0, 0.5), (1, 0.1), (0.2, 0.3).
        let r = read_bytes(&npy_bytes("<f8", "(3, 2)", false, &f8), &ReadOptions::default()).unwrap();
        assert_eq!(r.t, vec![0.0, 1.0, 0.2]);
        assert_eq!(r.theta, vec![0.5, 0.1, 0.3]);
        // Fortran order: column 1 is (0, 0.5, 1), column 2 is (0.1, 0.2, 0.3).
        let r = read_bytes(&npy_bytes("<f8", "(3, 2)", true, &f8), &ReadOptions::default()).unwrap();
        assert_eq!(r.t, vec![0.0, 0.5, 1.0]);
        assert_eq!(r.theta, vec![0.1, 0.2, 0.3]);
        let dt = ReadOptions {
            dt: Some(0.1),
            ..Default::default()
        };
        let r = read_bytes(&npy_bytes("<f8", "(6,)", false, &f8), &dt).unwrap();
        assert_eq!(r.theta.len(), 6);
        assert!(matches!(
            read_bytes(&npy_bytes("<f8", "(6,)", false, &f8), &ReadOptions::default()),
            Err(InputError::NeedStep)
        ));
        let i4: Vec<u8> = [1i32, -2, 3].iter().flat_map(|v| v.to_le_bytes()).collect();
        let r = read_bytes(&npy_bytes("<i4", "(3,)", false, &i4), &dt).unwrap();
        assert_eq!(r.theta, vec![1.0, -2.0, 3.0]);
        // A header that promises more data than the file holds.
        assert!(matches!(
            read_bytes(&npy_bytes("<f8", "(1000000000000,)", false, &f8), &dt),
            Err(InputError::Npy { .. })
        ));
        let nan: Vec<u8> = [0.0f64, f64::NAN].iter().flat_map(|v| v.to_le_bytes()).collect();
        assert!(matches!(
            read_bytes(&npy_bytes("<f8", "(2,)", false, &nan), &dt),
            Err(InputError::NonFinite { .. })
        ));
    }

    proptest::proptest! {
        #[test]
        fn npy_never_panics_on_corrupted_files(
            cut in 0usize..200,
            flips in proptest::collection::vec((0usize..200, proptest::prelude::any::<u8>()), 0..6),
        ) {
            let f8: Vec<u8> = (0..12).flat_map(|v| (v as f64).to_le_bytes()).collect();
            let mut bytes = npy_bytes("<f8", "(6, 2)", false, &f8);
            for (i, b) in flips {
                if i < bytes.len() { bytes[i] = b; }
            }
            bytes.truncate(cut.max(6));
            let _ = read_bytes(&bytes, &ReadOptions::default());
            let _ = read_bytes(&bytes, &ReadOptions { dt: Some(0.1), ..Default::default() });
        }

    }
}
