//! NetCDF 3 maps as SurfaceTopography writes them (and the Contact Mechanics Challenge
//! files): a variable `heights` over the dimensions `(x, y)`, x slowest; the coordinate
//! variables `x` and `y` carry the box lengths (`length`, any numeric type) and the unit
//! (`unit`), and an optional byte variable `mask` marks the missing points with 1.
//!
//! The classic formats (CDF-1, CDF-2 with 64-bit offsets, CDF-5 with 64-bit data) are read
//! here rather than by a crate: every count and size the header states is checked against
//! the bytes left in the file before anything is allocated, so a header that lies is an
//! error naming what it claims, never an allocation of what it claims.

use std::path::Path;

use super::guard;
use super::measured::{length_unit_m, MeasuredMap, Source};

/// A value of an attribute: numbers (any numeric type) or text.
#[derive(Debug, Clone)]
enum Value {
    Text(String),
    Numbers(Vec<f64>),
}

#[derive(Debug)]
struct Variable {
    name: String,
    dims: Vec<usize>,
    attrs: Vec<(String, Value)>,
    nc_type: u32,
    begin: u64,
}

impl Variable {
    fn attr(&self, name: &str) -> Option<&Value> {
        self.attrs.iter().find(|(n, _)| n == name).map(|(_, v)| v)
    }
}

/// A cursor over the file's bytes whose every read is bounds-checked.
struct Cursor<'a> {
    bytes: &'a [u8],
    at: usize,
    /// CDF-5: counts, dimension lengths and sizes are 8 bytes.
    wide: bool,
}

impl<'a> Cursor<'a> {
    fn take(&mut self, n: u64, what: &str) -> Result<&'a [u8], String> {
        let left = (self.bytes.len() - self.at) as u64;
        if n > left {
            return Err(format!(
                "its header is cut short in {what} ({n} bytes stated, {left} left in the file): truncated or not NetCDF"
            ));
        }
        let s = &self.bytes[self.at..self.at + n as usize];
        self.at += n as usize;
        Ok(s)
    }
    fn u32(&mut self, what: &str) -> Result<u32, String> {
        Ok(u32::from_be_bytes(
            self.take(4, what)?.try_into().expect("4 bytes"),
        ))
    }
    fn u64(&mut self, what: &str) -> Result<u64, String> {
        Ok(u64::from_be_bytes(
            self.take(8, what)?.try_into().expect("8 bytes"),
        ))
    }
    /// A count or length: 4 bytes (8 in CDF-5), non-negative.
    fn count(&mut self, what: &str) -> Result<u64, String> {
        let v = if self.wide {
            self.u64(what)? as i64
        } else {
            self.u32(what)? as i32 as i64
        };
        u64::try_from(v).map_err(|_| format!("its header states {what} = {v}: negative"))
    }
    /// A count of items each at least `min_bytes` long, checked against the bytes left.
    fn items(&mut self, what: &str, min_bytes: u64) -> Result<usize, String> {
        let n = self.count(what)?;
        let left = (self.bytes.len() - self.at) as u64;
        if n.saturating_mul(min_bytes) > left {
            return Err(format!(
                "its header states {n} {what}, which need at least {} bytes, but {} are left in the file: the header is wrong or the file truncated",
                guard::human_bytes(u128::from(n) * u128::from(min_bytes)),
                guard::human_bytes(u128::from(left))
            ));
        }
        Ok(n as usize)
    }
    fn pad(&mut self, n: u64) -> Result<(), String> {
        self.take((4 - n % 4) % 4, "padding").map(|_| ())
    }
    fn name(&mut self, what: &str) -> Result<String, String> {
        let n = self.items(&format!("characters of a {what} name"), 1)?;
        let s = String::from_utf8_lossy(self.take(n as u64, what)?).into_owned();
        self.pad(n as u64)?;
        Ok(s)
    }
    /// A list's tag and length: (0, 0) is absent, else `tag` then the count.
    fn list(&mut self, tag: u32, what: &str, min_bytes: u64) -> Result<usize, String> {
        let t = self.u32(what)?;
        if t == 0 {
            self.count(what)?;
            return Ok(0);
        }
        if t != tag {
            return Err(format!(
                "its header has tag {t:#x} where the {what} list ({tag:#x}) belongs: corrupt or not NetCDF 3"
            ));
        }
        self.items(what, min_bytes)
    }
    fn attrs(&mut self) -> Result<Vec<(String, Value)>, String> {
        let n = self.list(0x0C, "attributes", 12)?;
        let mut out = Vec::with_capacity(n);
        for _ in 0..n {
            let name = self.name("attribute")?;
            let t = self.u32("an attribute's type")?;
            let width = type_width(t).ok_or_else(|| {
                format!("attribute '{name}' has the type {t}, not a NetCDF 3 type")
            })?;
            let count = self.items(&format!("values of attribute '{name}'"), width)?;
            let raw = self.take(count as u64 * width, "an attribute's values")?;
            self.pad(count as u64 * width)?;
            let value = if t == 2 {
                Value::Text(
                    String::from_utf8_lossy(raw)
                        .trim_end_matches('\0')
                        .to_string(),
                )
            } else {
                Value::Numbers(decode(raw, t))
            };
            out.push((name, value));
        }
        Ok(out)
    }
}

/// Bytes of one value of NetCDF type `t`.
fn type_width(t: u32) -> Option<u64> {
    Some(match t {
        1 | 2 | 7 => 1,
        3 | 8 => 2,
        4 | 5 | 9 => 4,
        6 | 10 | 11 => 8,
        _ => return None,
    })
}

fn type_name(t: u32) -> &'static str {
    match t {
        1 => "byte",
        2 => "char",
        3 => "short",
        4 => "int",
        5 => "float",
        6 => "double",
        7 => "ubyte",
        8 => "ushort",
        9 => "uint",
        10 => "int64",
        _ => "uint64",
    }
}

/// Big-endian values of type `t` as f64.
fn decode(raw: &[u8], t: u32) -> Vec<f64> {
    let w = type_width(t).unwrap_or(1) as usize;
    raw.chunks_exact(w)
        .map(|c| match t {
            1 => c[0] as i8 as f64,
            2 | 7 => c[0] as f64,
            3 => i16::from_be_bytes([c[0], c[1]]) as f64,
            8 => u16::from_be_bytes([c[0], c[1]]) as f64,
            4 => i32::from_be_bytes(c.try_into().expect("4")) as f64,
            9 => u32::from_be_bytes(c.try_into().expect("4")) as f64,
            5 => f32::from_be_bytes(c.try_into().expect("4")) as f64,
            6 => f64::from_be_bytes(c.try_into().expect("8")),
            10 => i64::from_be_bytes(c.try_into().expect("8")) as f64,
            _ => u64::from_be_bytes(c.try_into().expect("8")) as f64,
        })
        .collect()
}

/// The dimensions and variables of a classic NetCDF file.
/// Dimensions (name, length; 0 for the record dimension) and variables.
type Header = (Vec<(String, u64)>, Vec<Variable>);

fn header(bytes: &[u8]) -> Result<Header, String> {
    let version = match bytes.get(..4) {
        Some([b'C', b'D', b'F', v @ (1 | 2 | 5)]) => *v,
        _ => return Err("does not start with 'CDF' and a version 1, 2 or 5: not NetCDF 3 (NetCDF 4 is HDF5, not read)".into()),
    };
    let mut c = Cursor {
        bytes,
        at: 4,
        wide: version == 5,
    };
    c.count("the number of records")?;
    let ndims = c.list(0x0A, "dimensions", 8)?;
    let mut dims = Vec::with_capacity(ndims);
    for _ in 0..ndims {
        let name = c.name("dimension")?;
        let len = c.count(&format!("the length of dimension '{name}'"))?;
        dims.push((name, len));
    }
    c.attrs()?;
    let nvars = c.list(0x0B, "variables", 16)?;
    let mut vars = Vec::with_capacity(nvars);
    for _ in 0..nvars {
        let name = c.name("variable")?;
        let rank = c.items(&format!("dimensions of variable '{name}'"), 4)?;
        let mut ids = Vec::with_capacity(rank);
        for _ in 0..rank {
            let id = c.count("a dimension id")? as usize;
            if id >= dims.len() {
                return Err(format!(
                    "variable '{name}' names dimension {id} of {}: corrupt",
                    dims.len()
                ));
            }
            ids.push(id);
        }
        let attrs = c.attrs()?;
        let nc_type = c.u32("a variable's type")?;
        if type_width(nc_type).is_none() {
            return Err(format!(
                "variable '{name}' has the type {nc_type}, not a NetCDF 3 type"
            ));
        }
        c.count("a variable's size")?;
        let begin = if version == 1 {
            u64::from(c.u32("a variable's offset")?)
        } else {
            c.u64("a variable's offset")?
        };
        vars.push(Variable {
            name,
            dims: ids,
            attrs,
            nc_type,
            begin,
        });
    }
    Ok((dims, vars))
}

/// The values of a fixed-size variable as f64, checked against the file's length and
/// memory first.
fn values(bytes: &[u8], dims: &[(String, u64)], v: &Variable) -> Result<Vec<f64>, String> {
    if v.dims.iter().any(|&d| dims[d].1 == 0) {
        return Err(format!(
            "'{}' runs along the record (unlimited) dimension: only fixed-size maps are read",
            v.name
        ));
    }
    let count = v
        .dims
        .iter()
        .fold(1u128, |acc, &d| acc.saturating_mul(u128::from(dims[d].1)));
    let width = type_width(v.nc_type).expect("checked in the header");
    let available = (bytes.len() as u64).saturating_sub(v.begin);
    let n = guard::check_promised(
        &format!("variable '{}'", v.name),
        count,
        u128::from(width),
        available,
    )?;
    let start = v.begin as usize;
    Ok(decode(&bytes[start..start + n * width as usize], v.nc_type))
}

pub fn read(path: &Path) -> Result<MeasuredMap, String> {
    let bytes = guard::read_bounded(path)?;
    let (dims, vars) = header(&bytes)?;
    let var = |name: &str| vars.iter().find(|v| v.name == name);
    let heights =
        var("heights").ok_or("holds no variable named 'heights' (SurfaceTopography's layout)")?;
    let dim_names: Vec<&str> = heights.dims.iter().map(|&d| dims[d].0.as_str()).collect();
    if dim_names != ["x", "y"] {
        return Err(format!(
            "'heights' is defined over ({}), not the map's dimensions (x, y)",
            dim_names.join(", ")
        ));
    }
    let (nx, ny) = (
        dims[heights.dims[0]].1 as usize,
        dims[heights.dims[1]].1 as usize,
    );
    let unit_of = |name: &str| -> Result<Option<f64>, String> {
        match var(name).and_then(|v| v.attr("unit")) {
            None => Ok(None),
            Some(Value::Text(u)) => length_unit_m(u.trim()).map(Some).ok_or_else(|| {
                format!(
                    "variable '{name}' has the unknown length unit '{}' (m, mm, um, nm, A, pm)",
                    u.trim()
                )
            }),
            Some(Value::Numbers(_)) => Err(format!(
                "variable '{name}' has a numeric 'unit' attribute: a unit is text (m, mm, um, nm)"
            )),
        }
    };
    let (x_unit, h_unit) = (unit_of("x")?, unit_of("heights")?);
    let length = |name: &str| -> Result<Option<f64>, String> {
        match var(name).and_then(|v| v.attr("length")) {
            None => Ok(None),
            Some(Value::Numbers(v)) => match v.first() {
                Some(&l) if l.is_finite() && l > 0.0 => Ok(Some(l)),
                Some(&l) => Err(format!(
                    "variable '{name}' has length = {l}: the map's side must be finite and > 0"
                )),
                None => Err(format!("variable '{name}' has an empty 'length' attribute")),
            },
            Some(Value::Text(t)) => t
                .trim()
                .parse::<f64>()
                .ok()
                .filter(|l| l.is_finite() && *l > 0.0)
                .map(Some)
                .ok_or_else(|| format!("variable '{name}' has length = '{t}': not a length > 0")),
        }
    };
    let lateral_unit = x_unit.or(h_unit);
    let pixel = match (length("x")?, length("y")?, lateral_unit) {
        (Some(sx), Some(sy), Some(u)) => Some((sx * u / nx as f64, sy * u / ny as f64)),
        _ => None,
    };
    let heights_unit = h_unit.or(x_unit);
    if heights.nc_type == 2 {
        return Err("'heights' holds characters, not numbers".into());
    }
    let data = values(&bytes, &dims, heights)?;
    let mask = match var("mask") {
        Some(m) if m.dims == heights.dims => Some(values(&bytes, &dims, m)?),
        Some(m) => {
            return Err(format!(
                "'mask' is of type {} over other dimensions than 'heights'",
                type_name(m.nc_type)
            ))
        }
        None => None,
    };
    // x slowest in the file; rows along y here.
    let mut out = vec![0.0; nx * ny];
    for ix in 0..nx {
        for iy in 0..ny {
            let k = ix * ny + iy;
            let masked = mask.as_ref().is_some_and(|m| m[k] != 0.0);
            out[iy * nx + ix] = if masked { f64::NAN } else { data[k] };
        }
    }
    Ok(MeasuredMap {
        rows: ny,
        cols: nx,
        heights: match heights_unit {
            Some(u) => out.into_iter().map(|h| h * u).collect(),
            None => out,
        },
        height_unit_m: heights_unit,
        pixel_m: pixel,
        pixel_file_units: None,
        source: Source::NetCdf,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A CDF-1 file: dims x, y; variables x (length, unit), y (length), heights.
    fn classic(nx: u32, ny: u32, length: Option<(u32, Vec<u8>)>, data: &[f64]) -> Vec<u8> {
        let mut b = Vec::new();
        let name = |b: &mut Vec<u8>, s: &str| {
            b.extend((s.len() as u32).to_be_bytes());
            b.extend(s.as_bytes());
            b.resize(b.len().next_multiple_of(4), 0);
        };
        b.extend(b"CDF\x01");
        b.extend(0u32.to_be_bytes());
        b.extend(0x0Au32.to_be_bytes());
        b.extend(2u32.to_be_bytes());
        name(&mut b, "x");
        b.extend(nx.to_be_bytes());
        name(&mut b, "y");
        b.extend(ny.to_be_bytes());
        b.extend([0u8; 8]);
        b.extend(0x0Bu32.to_be_bytes());
        b.extend(2u32.to_be_bytes());
        // x: a scalar variable carrying the attributes.
        name(&mut b, "x");
        b.extend(0u32.to_be_bytes());
        let mut attrs = 1u32;
        if length.is_some() {
            attrs += 1;
        }
        b.extend(0x0Cu32.to_be_bytes());
        b.extend(attrs.to_be_bytes());
        name(&mut b, "unit");
        b.extend(2u32.to_be_bytes());
        b.extend(2u32.to_be_bytes());
        b.extend(b"um\0\0");
        if let Some((t, raw)) = &length {
            name(&mut b, "length");
            b.extend(t.to_be_bytes());
            b.extend(1u32.to_be_bytes());
            b.extend(raw);
            b.resize(b.len().next_multiple_of(4), 0);
        }
        b.extend(6u32.to_be_bytes());
        b.extend(8u32.to_be_bytes());
        let x_begin = b.len();
        b.extend(0u32.to_be_bytes());
        name(&mut b, "heights");
        b.extend(2u32.to_be_bytes());
        b.extend(0u32.to_be_bytes());
        b.extend(1u32.to_be_bytes());
        b.extend([0u8; 8]);
        b.extend(6u32.to_be_bytes());
        b.extend((nx * ny * 8).to_be_bytes());
        let h_begin = b.len();
        b.extend(0u32.to_be_bytes());
        let x_at = b.len() as u32;
        b[x_begin..x_begin + 4].copy_from_slice(&x_at.to_be_bytes());
        b.extend(0f64.to_be_bytes());
        let h_at = b.len() as u32;
        b[h_begin..h_begin + 4].copy_from_slice(&h_at.to_be_bytes());
        for v in data {
            b.extend(v.to_be_bytes());
        }
        b
    }

    #[test]
    fn integer_lengths_are_read_and_bad_ones_named() {
        let data: Vec<f64> = (0..6).map(f64::from).collect();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.nc");
        // `length` as a 32-bit integer: 30 µm over 3 points.
        std::fs::write(
            &path,
            classic(3, 2, Some((4, 30i32.to_be_bytes().to_vec())), &data),
        )
        .unwrap();
        let m = read(&path).unwrap();
        assert_eq!((m.rows, m.cols), (2, 3));
        // Only x carries a length here: no pixel size, and no error.
        assert_eq!(m.pixel_m, None);
        assert_eq!(m.heights[1], 2.0 * 1e-6);
        std::fs::write(
            &path,
            classic(3, 2, Some((4, (-3i32).to_be_bytes().to_vec())), &data),
        )
        .unwrap();
        assert!(read(&path).unwrap_err().contains("length = -3"));
    }

    #[test]
    fn a_lying_header_is_refused_before_allocating() {
        let data: Vec<f64> = (0..6).map(f64::from).collect();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.nc");
        let mut b = classic(3, 2, None, &data);
        // The dimension count: 2 → 2^31 − 1.
        b[12..16].copy_from_slice(&0x7fff_ffffu32.to_be_bytes());
        std::fs::write(&path, &b).unwrap();
        let e = read(&path).unwrap_err();
        assert!(e.contains("2147483647 dimensions"), "{e}");
        // x's length: 3 → 10^9 points (8 GB of doubles over a few bytes).
        let mut b = classic(3, 2, None, &data);
        b[24..28].copy_from_slice(&1_000_000_000u32.to_be_bytes());
        std::fs::write(&path, &b).unwrap();
        let e = read(&path).unwrap_err();
        assert!(e.contains("the header promises 2000000000 values"), "{e}");
    }
}
