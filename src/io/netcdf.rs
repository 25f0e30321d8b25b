//! NetCDF 3 maps as SurfaceTopography writes them (and the Contact Mechanics Challenge
//! files): a variable `heights` over the dimensions `(x, y)`, x slowest; the coordinate
//! variables `x` and `y` carry the box lengths (`length`) and the unit (`unit`), and an
//! optional byte variable `mask` marks the missing points with 1.

use std::path::Path;

use netcdf3::{DataVector, FileReader};

use super::measured::{length_unit_m, MeasuredMap, Source};

pub fn read(path: &Path) -> Result<MeasuredMap, String> {
    let mut file = FileReader::open(path).map_err(|e| {
        format!("is not a readable NetCDF 3 file ({e:?}); NetCDF 4 (HDF5) is not read")
    })?;
    let set = file.data_set();
    let var = set
        .get_var("heights")
        .ok_or("holds no variable named 'heights' (SurfaceTopography's layout)")?;
    let dims = var.dim_names();
    let (nx, ny) = match dims.iter().map(String::as_str).collect::<Vec<_>>()[..] {
        ["x", "y"] => (
            set.dim_size("x").unwrap_or(0),
            set.dim_size("y").unwrap_or(0),
        ),
        _ => {
            return Err(format!(
                "'heights' is defined over ({}), not the map's dimensions (x, y)",
                dims.join(", ")
            ))
        }
    };
    if nx == 0 || ny == 0 {
        return Err(format!("'heights' has {nx} × {ny} points"));
    }
    let unit_of = |name: &str| -> Result<Option<f64>, String> {
        match set.get_var(name).and_then(|v| v.get_attr_as_string("unit")) {
            None => Ok(None),
            Some(u) => length_unit_m(u.trim()).map(Some).ok_or_else(|| {
                format!(
                    "variable '{name}' has the unknown length unit '{}'",
                    u.trim()
                )
            }),
        }
    };
    let (x_unit, h_unit) = (unit_of("x")?, unit_of("heights")?);
    let length = |name: &str| -> Option<f64> {
        let v = set.get_var(name)?;
        v.get_attr_f64("length")
            .map(|a| a.first().copied())
            .or_else(|| {
                v.get_attr_f32("length")
                    .map(|a| a.first().map(|&x| x as f64))
            })
            .flatten()
    };
    let lateral_unit = x_unit.or(h_unit);
    let pixel = match (length("x"), length("y"), lateral_unit) {
        (Some(sx), Some(sy), Some(u)) if sx > 0.0 && sy > 0.0 => {
            Some((sx * u / nx as f64, sy * u / ny as f64))
        }
        _ => None,
    };
    let heights_unit = h_unit.or(x_unit);
    let values = to_f64(
        file.read_var("heights")
            .map_err(|e| format!("'heights' cannot be read ({e:?}): truncated or corrupt"))?,
    );
    if values.len() != nx * ny {
        return Err(format!(
            "'heights' holds {} values for {nx} × {ny} points",
            values.len()
        ));
    }
    let mask = match file.data_set().has_var("mask") {
        true => Some(to_f64(file.read_var("mask").map_err(|e| {
            format!("'mask' cannot be read ({e:?}): truncated or corrupt")
        })?)),
        false => None,
    };
    // x slowest in the file; rows along y here.
    let mut heights = vec![0.0; nx * ny];
    for ix in 0..nx {
        for iy in 0..ny {
            let k = ix * ny + iy;
            let masked = mask.as_ref().is_some_and(|m| m[k] != 0.0);
            heights[iy * nx + ix] = if masked { f64::NAN } else { values[k] };
        }
    }
    Ok(MeasuredMap {
        rows: ny,
        cols: nx,
        heights: match heights_unit {
            Some(u) => heights.into_iter().map(|h| h * u).collect(),
            None => heights,
        },
        height_unit_m: heights_unit,
        pixel_m: pixel,
        pixel_file_units: None,
        source: Source::NetCdf,
    })
}

fn to_f64(v: DataVector) -> Vec<f64> {
    match v {
        DataVector::I8(v) => v.into_iter().map(f64::from).collect(),
        DataVector::U8(v) => v.into_iter().map(f64::from).collect(),
        DataVector::I16(v) => v.into_iter().map(f64::from).collect(),
        DataVector::I32(v) => v.into_iter().map(f64::from).collect(),
        DataVector::F32(v) => v.into_iter().map(f64::from).collect(),
        DataVector::F64(v) => v,
    }
}
