//! Plain-file input and output of fields as `.npy` (float64, C order), readable by
//! `numpy.load`.

use std::path::Path;

use ndarray::{Array2, Array3, Axis};
use ndarray_npy::{read_npy, write_npy};

/// Errors reading or writing field files.
#[derive(Debug, thiserror::Error)]
pub enum IoError {
    #[error("{path}: {message}")]
    File { path: String, message: String },
}

/// Write an `n × n` row-major field as float64 `.npy`.
pub fn write_heights(path: &Path, n: usize, values: Vec<f64>) -> Result<(), IoError> {
    write_f64(path, &[n, n], values)
}

/// Read a square float64 `.npy` field; returns `(n, values row-major)`.
pub fn read_square_f64(path: &Path) -> Result<(usize, Vec<f64>), IoError> {
    let err = |message: String| IoError::File {
        path: path.display().to_string(),
        message,
    };
    let array: Array2<f64> =
        read_npy(path).map_err(|e| err(format!("not a 2-D float64 .npy file ({e})")))?;
    let (rows, cols) = array.dim();
    if rows != cols || rows == 0 {
        return Err(err(format!(
            "expected a non-empty square array, got {rows} × {cols}"
        )));
    }
    let values = if array.is_standard_layout() {
        array.into_raw_vec_and_offset().0
    } else {
        array.iter().copied().collect()
    };
    Ok((rows, values))
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
        Err(first) => match read_npy::<_, Array2<bool>>(path) {
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
            Err(_) => Err(err(format!(
                "not a 2-D bool or uint8 .npy contact map ({first})"
            ))),
        },
    }
}

/// One contact map: rows, columns, the map row-major, and the format it was read from.
pub type ContactMap = (usize, usize, Vec<bool>, ContactMapFormat);

/// Every contact map of a file: the one map of a 2-D file ([`read_contact_map`]), or each
/// map of a 3-D `uint8` stack of 0/1 maps `(loads, rows, cols)` in order.
pub fn read_contact_maps(path: &Path) -> Result<Vec<ContactMap>, IoError> {
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
