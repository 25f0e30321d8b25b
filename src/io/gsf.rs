//! Gwyddion Simple Field (.gsf): the line `Gwyddion Simple Field 1.0`, then `Key = Value`
//! lines (`XRes`, `YRes` required; `XReal`, `YReal`, `XYUnits`, `ZUnits` optional), 1 to
//! 4 NUL bytes padding the header to a multiple of 4, then `XRes·YRes` little-endian
//! float32 row by row (rows along y); NaN is a missing point.

use std::path::Path;

use super::measured::{length_unit_m, MeasuredMap, Source};

const MAGIC: &[u8] = b"Gwyddion Simple Field 1.0\n";

pub fn read(path: &Path) -> Result<MeasuredMap, String> {
    let bytes = super::guard::read_bounded(path)?;
    if !bytes.starts_with(MAGIC) {
        return Err("does not start with 'Gwyddion Simple Field 1.0': not a GSF file".into());
    }
    let end = bytes
        .iter()
        .position(|&b| b == 0)
        .ok_or("has no NUL byte ending its header: truncated")?;
    let header = std::str::from_utf8(&bytes[MAGIC.len()..end])
        .map_err(|_| "its header is not UTF-8 text".to_string())?;
    let data_start = (end / 4 + 1) * 4;
    let mut fields = std::collections::HashMap::new();
    for line in header.lines().filter(|l| !l.trim().is_empty()) {
        let (k, v) = line
            .split_once('=')
            .ok_or_else(|| format!("header line '{line}' is not 'Key = Value'"))?;
        fields.insert(k.trim().to_string(), v.trim().to_string());
    }
    let count = |key: &str| -> Result<usize, String> {
        let v = fields
            .get(key)
            .ok_or_else(|| format!("its header has no {key}"))?;
        v.parse::<usize>()
            .ok()
            .filter(|&n| n > 0)
            .ok_or_else(|| format!("{key} = {v} is not a positive count"))
    };
    let (cols, rows) = (count("XRes")?, count("YRes")?);
    let length = |key: &str| -> Result<Option<f64>, String> {
        fields
            .get(key)
            .map(|v| {
                v.parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite() && *x > 0.0)
                    .ok_or_else(|| format!("{key} = {v} is not a positive length"))
            })
            .transpose()
    };
    let unit = |key: &str| -> Result<Option<f64>, String> {
        fields
            .get(key)
            .map(|u| length_unit_m(u).ok_or_else(|| format!("{key} = {u}: an unknown length unit")))
            .transpose()
    };
    let (xy_unit, z_unit) = (unit("XYUnits")?, unit("ZUnits")?);
    let pixel = match (length("XReal")?, length("YReal")?, xy_unit) {
        (Some(sx), Some(sy), Some(u)) => Some((sx * u / cols as f64, sy * u / rows as f64)),
        _ => None,
    };
    let data = bytes.get(data_start..).unwrap_or(&[]);
    let count = super::guard::check_promised(
        "XRes × YRes",
        rows as u128 * cols as u128,
        4,
        data.len() as u64,
    )?;
    let need = count * 4;
    if data.len() != need {
        return Err(format!(
            "holds {} bytes of data where XRes × YRes = {cols} × {rows} float32 need {need}: truncated or mismatched",
            data.len()
        ));
    }
    let scale = z_unit.unwrap_or(1.0);
    let heights = data
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes(c.try_into().expect("4 bytes")) as f64 * scale)
        .collect();
    Ok(MeasuredMap {
        rows,
        cols,
        heights,
        height_unit_m: z_unit,
        pixel_m: pixel,
        pixel_file_units: None,
        source: Source::Gsf,
    })
}
