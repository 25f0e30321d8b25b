//! Fields as `.npy` (float64, C order), readable by `numpy.load`, and contact maps.

use std::path::Path;

use ndarray::{Array2, Array3, Axis};
use ndarray_npy::{read_npy, write_npy};

use super::error::IoError;

/// Write an `n × n` row-major field as float64 `.npy`.
pub fn write_heights(path: &Path, n: usize, values: Vec<f64>) -> Result<(), IoError> {
    write_f64(path, &[n, n], values)
}

/// The `descr` and `shape` of a `.npy` file's header, checked against the file's length
/// before anything is allocated: a header that promises more data than the file holds (a
/// truncated or forged file) is an error, never an attempt to allocate what it claims.
pub fn npy_header(path: &Path) -> Result<(String, Vec<usize>), IoError> {
    use std::io::Read;
    let err = |message: String| IoError::File {
        path: path.display().to_string(),
        message,
    };
    let mut file = std::fs::File::open(path).map_err(|e| err(format!("cannot open ({e})")))?;
    let meta = file
        .metadata()
        .map_err(|e| err(format!("cannot read ({e})")))?;
    if !meta.is_file() {
        return Err(err(
            "is not a regular file (a pipe, device or directory): a .npy file is checked against its size before it is read; save the data to a file and name that"
                .into(),
        ));
    }
    let file_len = meta.len();
    let not_npy = || err("not a .npy file (no NUMPY header)".into());
    let mut magic = [0u8; 8];
    file.read_exact(&mut magic).map_err(|_| not_npy())?;
    if &magic[..6] != b"\x93NUMPY" {
        return Err(not_npy());
    }
    let (len_bytes, prefix) = match magic[6] {
        1 => (2, 10u64),
        2 | 3 => (4, 12u64),
        v => return Err(err(format!(".npy format version {v} is not supported"))),
    };
    let mut len = [0u8; 4];
    file.read_exact(&mut len[..len_bytes])
        .map_err(|_| not_npy())?;
    let header_len = u32::from_le_bytes(len) as u64;
    if prefix + header_len > file_len {
        return Err(err(format!(
            "header of {header_len} bytes is longer than the file ({file_len} bytes)"
        )));
    }
    let mut header = vec![0u8; header_len as usize];
    file.read_exact(&mut header).map_err(|_| not_npy())?;
    let header = String::from_utf8_lossy(&header);
    let field = |name: &str| -> Option<&str> {
        let start = header.find(&format!("'{name}'"))? + name.len() + 2;
        let rest = header[start..].trim_start().strip_prefix(':')?.trim_start();
        Some(rest)
    };
    let descr = field("descr")
        .and_then(|r| r.strip_prefix('\''))
        .and_then(|r| r.split('\'').next())
        .ok_or_else(|| err("header has no 'descr'".into()))?
        .to_string();
    let shape_text = field("shape")
        .and_then(|r| r.strip_prefix('('))
        .and_then(|r| r.split(')').next())
        .ok_or_else(|| err("header has no 'shape'".into()))?;
    let shape = shape_text
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| s.trim_end_matches('L').parse::<usize>())
        .collect::<Result<Vec<_>, _>>()
        .map_err(|_| {
            err(format!(
                "header's shape ({shape_text}) is not a tuple of sizes"
            ))
        })?;
    let item_bytes: u64 = descr
        .trim_start_matches(['<', '>', '|', '='])
        .get(1..)
        .and_then(|s| s.parse().ok())
        .ok_or_else(|| {
            err(format!(
                "header's dtype '{descr}' is not a plain number type"
            ))
        })?;
    let payload = shape
        .iter()
        .try_fold(item_bytes, |acc, &d| acc.checked_mul(d as u64));
    let available = file_len - prefix - header_len;
    if payload != Some(available) {
        return Err(err(format!(
            "the header promises shape ({shape_text}) of '{descr}', {} bytes, but the file holds {available} bytes after it: truncated or not written by numpy",
            payload.map_or("more than 2^64".to_string(), |b| b.to_string()),
        )));
    }
    Ok((descr, shape))
}

/// Read a square float64 `.npy` field; returns `(n, values row-major)`. The header is
/// checked first, so a file of another type or shape is refused with what it holds.
pub fn read_square_f64(path: &Path) -> Result<(usize, Vec<f64>), IoError> {
    let err = |message: String| IoError::File {
        path: path.display().to_string(),
        message,
    };
    let (descr, shape) = npy_header(path)?;
    if !matches!(descr.as_str(), "<f8" | ">f8" | "=f8") {
        return Err(err(format!(
            "holds values of type '{descr}', not float64 ('<f8'): save the heights as float64 (numpy: h.astype('float64'))"
        )));
    }
    if shape.len() != 2 || shape[0] != shape[1] || shape[0] == 0 {
        return Err(err(format!(
            "holds an array of shape ({}), not a non-empty square 2-D array of heights (one period of a periodic surface; a measured map of any shape goes through `wearcoef wear`, which solves it without wrap-around)",
            shape
                .iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        )));
    }
    let (rows, _, values) = read_map_npy(path)?;
    Ok((rows, values))
}

/// Read a 2-D `.npy` map of heights of any shape, float32 or float64 (either byte order, C
/// or Fortran order), as `(rows, cols, values row-major in f64)`; NaN stays NaN (a missing
/// point). The header is checked first: another type or rank is refused with what it holds.
pub fn read_map_npy(path: &Path) -> Result<(usize, usize, Vec<f64>), IoError> {
    let err = |message: String| IoError::File {
        path: path.display().to_string(),
        message,
    };
    let (descr, shape) = npy_header(path)?;
    if shape.len() != 2 || shape[0] == 0 || shape[1] == 0 {
        return Err(err(format!(
            "holds an array of shape ({}), not a non-empty 2-D map of heights",
            shape
                .iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        )));
    }
    let row_major = |a: Array2<f64>| -> Vec<f64> {
        if a.is_standard_layout() {
            a.into_raw_vec_and_offset().0
        } else {
            a.iter().copied().collect()
        }
    };
    let values = match &descr[1..] {
        "f8" => {
            row_major(read_npy(path).map_err(|e| err(format!("cannot be read as float64 ({e})")))?)
        }
        "f4" => {
            let a: Array2<f32> =
                read_npy(path).map_err(|e| err(format!("cannot be read as float32 ({e})")))?;
            row_major(a.mapv(f64::from))
        }
        _ => {
            return Err(err(format!(
                "holds values of type '{descr}', not float32 or float64 heights"
            )))
        }
    };
    Ok((shape[0], shape[1], values))
}

/// Write any float64 array of the given shape (C order) as `.npy`.
pub fn write_f64(path: &Path, shape: &[usize], values: Vec<f64>) -> Result<(), IoError> {
    write_array(path, shape, values)
}

/// Write any uint8 array of the given shape (C order) as `.npy`.
pub fn write_u8(path: &Path, shape: &[usize], values: Vec<u8>) -> Result<(), IoError> {
    write_array(path, shape, values)
}

fn write_array<T: ndarray_npy::WritableElement>(
    path: &Path,
    shape: &[usize],
    values: Vec<T>,
) -> Result<(), IoError> {
    let err = |message: String| IoError::File {
        path: path.display().to_string(),
        message,
    };
    let array = ndarray::ArrayD::from_shape_vec(ndarray::IxDyn(shape), values)
        .map_err(|e| err(e.to_string()))?;
    write_npy(path, &array).map_err(|e| err(e.to_string()))
}

/// How a contact map file was stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum ContactMapFormat {
    /// `bool` array `(rows, cols)`.
    Bool,
    /// `uint8` array of 0/1 `(rows, cols)`.
    ZeroOne,
    /// One map of a `uint8` stack of 0/1 maps `(loads, rows, cols)`, as `wearcoef solve
    /// --contact-out` writes for several loads.
    Stacked,
    /// The project's bit-packed rows (numpy `packbits(axis=1)` convention): `uint8`
    /// `(n, ceil(n/8))` for an `n × n` map, most significant bit first.
    Packed,
}

/// Read a 2-D contact map: `bool`, `uint8` 0/1, or the project's bit-packed `uint8`
/// `(n, ceil(n/8))` (recognised by that shape with `n ≥ 2`; the map is then `n × n`).
/// Returns `(rows, cols, map row-major, format)`.
pub fn read_contact_map(
    path: &Path,
) -> Result<(usize, usize, Vec<bool>, ContactMapFormat), IoError> {
    let err = |message: String| IoError::File {
        path: path.display().to_string(),
        message,
    };
    let flat = |a: ndarray::ArrayView2<'_, u8>| a.iter().copied().collect::<Vec<u8>>();
    match read_npy::<_, Array2<u8>>(path) {
        Ok(a) => {
            let (rows, cols) = a.dim();
            if rows == 0 || cols == 0 {
                return Err(err(format!("contact map is empty ({rows} × {cols})")));
            }
            let bytes = flat(a.view());
            if rows >= 2 && cols == rows.div_ceil(8) && cols != rows {
                let n = rows;
                // The last byte of a row holds 8·cols − n padding bits, zero in a packed map.
                let pad: u8 = if n % 8 == 0 { 0 } else { 0xff >> (n % 8) };
                if let Some(r) = (0..n).find(|r| bytes[r * cols + cols - 1] & pad != 0) {
                    return Err(err(format!(
                        "bit-packed map of {n} × {n}: row {r} has bits set past column {n} (the padding of its last byte); a packed map keeps them zero, so this file is damaged or not a packed map"
                    )));
                }
                let map = (0..n * n)
                    .map(|i| bytes[(i / n) * cols + (i % n) / 8] & (0x80 >> (i % n % 8)) != 0)
                    .collect();
                return Ok((n, n, map, ContactMapFormat::Packed));
            }
            if let Some((i, v)) = bytes.iter().enumerate().find(|(_, &v)| v > 1) {
                return Err(err(format!(
                    "uint8 contact map must hold 0 or 1, found {v} at row {}, column {} \
                     (bit-packed maps have shape (n, ceil(n/8)))",
                    i / cols,
                    i % cols
                )));
            }
            Ok((
                rows,
                cols,
                bytes.iter().map(|&v| v == 1).collect(),
                ContactMapFormat::ZeroOne,
            ))
        }
        Err(_) => match read_npy::<_, Array2<bool>>(path) {
            Ok(a) => {
                let (rows, cols) = a.dim();
                if rows == 0 || cols == 0 {
                    return Err(err(format!("contact map is empty ({rows} × {cols})")));
                }
                Ok((
                    rows,
                    cols,
                    a.iter().copied().collect(),
                    ContactMapFormat::Bool,
                ))
            }
            Err(_) => Err(err(match npy_header(path) {
                Ok((descr, shape)) if shape.len() == 2 => format!(
                    "holds values of type '{descr}'; a contact map is bool or uint8 0/1 ('|b1', '|u1'), or a contact stage's bit-packed uint8 map"
                ),
                Ok((_, shape)) => format!(
                    "holds an array of shape ({}); a contact map is 2-D (or a 3-D uint8 stack of maps)",
                    shape.iter().map(|d| d.to_string()).collect::<Vec<_>>().join(", ")
                ),
                Err(e) => e.to_string(),
            })),
        },
    }
}

/// One contact map: rows, columns, the map row-major, and the format it was read from.
pub type ContactMap = (usize, usize, Vec<bool>, ContactMapFormat);

/// Every contact map of a file: the one map of a 2-D file ([`read_contact_map`]), or each
/// map of a 3-D `uint8` stack of 0/1 maps `(loads, rows, cols)` in order.
pub fn read_contact_maps(path: &Path) -> Result<Vec<ContactMap>, IoError> {
    npy_header(path)?;
    let Ok(stack) = read_npy::<_, Array3<u8>>(path) else {
        return read_contact_map(path).map(|m| vec![m]);
    };
    let err = |message: String| IoError::File {
        path: path.display().to_string(),
        message,
    };
    let (maps, rows, cols) = stack.dim();
    if maps == 0 || rows == 0 || cols == 0 {
        return Err(err(format!(
            "contact maps are empty ({maps} × {rows} × {cols})"
        )));
    }
    if let Some(((k, i, j), v)) = stack.indexed_iter().find(|(_, &v)| v > 1) {
        return Err(err(format!(
            "a stack of uint8 contact maps must hold 0 or 1, found {v} in map {k}, row {i}, \
             column {j}"
        )));
    }
    Ok(stack
        .axis_iter(Axis(0))
        .map(|m| {
            let map = m.iter().map(|&v| v == 1).collect();
            (rows, cols, map, ContactMapFormat::Stacked)
        })
        .collect())
}
