//! Plain-file input and output of fields as `.npy` (float64, C order), readable by
//! `numpy.load`.

use std::path::Path;

use ndarray::Array2;
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
