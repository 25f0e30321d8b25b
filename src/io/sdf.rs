//! ISO 25178-71 Surface Data Files, text (`aISO-1.0`) and binary (`bISO-1.0`). The header
//! gives `NumPoints` (along x) and `NumProfiles` (along y), the pixel sizes `Xscale`,
//! `Yscale` and the height scale `Zscale` in metres, and the `DataType` of the values
//! (0 u8, 1 u16, 2 u32, 3 f32, 4 i8, 5 i16, 6 i32, 7 f64; binary little-endian); a height is
//! `value · Zscale`. Missing points: `BAD` in text, NaN, or for 16- and 32-bit integers the
//! reserved value (the minimum of a signed type, the maximum of an unsigned one), as
//! Gwyddion and SurfaceTopography read them. Compressed files are refused.

use std::path::Path;

use super::measured::{MeasuredMap, Source};

pub fn read(path: &Path) -> Result<MeasuredMap, String> {
    let bytes = super::guard::read_bounded(path)?;
    match bytes.get(..8) {
        Some(b"aISO-1.0") => text(&bytes),
        Some(b"bISO-1.0") => binary(&bytes),
        _ => Err("does not start with 'aISO-1.0' or 'bISO-1.0': not an SDF file".into()),
    }
}

struct Header {
    points: usize,
    profiles: usize,
    x_scale: f64,
    y_scale: f64,
    z_scale: f64,
    compression: u8,
    data_type: u8,
}

impl Header {
    fn check(&self) -> Result<(), String> {
        if self.points == 0 || self.profiles == 0 {
            return Err(format!(
                "NumPoints = {}, NumProfiles = {}: a map has at least one point",
                self.points, self.profiles
            ));
        }
        for (name, v) in [
            ("Xscale", self.x_scale),
            ("Yscale", self.y_scale),
            ("Zscale", self.z_scale),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("{name} = {v}: a scale must be finite and > 0"));
            }
        }
        if self.compression != 0 {
            return Err(format!(
                "Compression = {}: compressed SDF data is not read",
                self.compression
            ));
        }
        if self.data_type > 7 {
            return Err(format!(
                "DataType = {} is not one of 0 to 7",
                self.data_type
            ));
        }
        Ok(())
    }

    /// The reserved value marking a missing point, if the type has one.
    fn invalid(&self) -> Option<f64> {
        match self.data_type {
            1 => Some(u16::MAX as f64),
            2 => Some(u32::MAX as f64),
            5 => Some(i16::MIN as f64),
            6 => Some(i32::MIN as f64),
            _ => None,
        }
    }

    fn map(&self, raw: Vec<f64>) -> MeasuredMap {
        let invalid = self.invalid();
        MeasuredMap {
            rows: self.profiles,
            cols: self.points,
            heights: raw
                .into_iter()
                .map(|v| {
                    if Some(v) == invalid {
                        f64::NAN
                    } else {
                        v * self.z_scale
                    }
                })
                .collect(),
            height_unit_m: Some(1.0),
            pixel_m: Some((self.x_scale, self.y_scale)),
            pixel_file_units: None,
            source: Source::Sdf,
        }
    }
}

fn text(bytes: &[u8]) -> Result<MeasuredMap, String> {
    let text = std::str::from_utf8(bytes).map_err(|_| "is not UTF-8 text".to_string())?;
    let mut lines = text.lines().skip(1);
    let mut fields = std::collections::HashMap::new();
    for line in lines.by_ref() {
        let line = line.trim();
        if line == "*" {
            break;
        }
        if let Some((k, v)) = line.split_once('=') {
            fields.insert(k.trim().to_string(), v.trim().to_string());
        }
    }
    let get = |k: &str| -> Result<f64, String> {
        let v = fields
            .get(k)
            .ok_or_else(|| format!("its header has no {k}"))?;
        v.parse::<f64>()
            .map_err(|_| format!("{k} = {v} is not a number"))
    };
    let size = |k: &str| -> Result<usize, String> {
        let v = get(k)?;
        if !(v.fract() == 0.0 && (1.0..=u32::MAX as f64).contains(&v)) {
            return Err(format!(
                "{k} = {}: a count of points from 1 to {}",
                fields[k],
                u32::MAX
            ));
        }
        Ok(v as usize)
    };
    let header = Header {
        points: size("NumPoints")?,
        profiles: size("NumProfiles")?,
        x_scale: get("Xscale")?,
        y_scale: get("Yscale")?,
        z_scale: get("Zscale")?,
        compression: fields
            .get("Compression")
            .map_or(Ok(0.0), |_| get("Compression"))? as u8,
        data_type: get("DataType")? as u8,
    };
    header.check()?;
    // Each value takes at least two characters (a digit and a separator).
    let count = super::guard::check_promised(
        "NumPoints × NumProfiles",
        header.points as u128 * header.profiles as u128,
        2,
        bytes.len() as u64,
    )?;
    let mut raw = Vec::with_capacity(count);
    for token in lines
        .take_while(|l| l.trim() != "*")
        .flat_map(str::split_whitespace)
    {
        if raw.len() == count {
            return Err(format!(
                "holds more than NumPoints × NumProfiles = {count} values"
            ));
        }
        raw.push(match token {
            "BAD" => f64::NAN,
            t => t
                .parse::<f64>()
                .map_err(|_| format!("'{t}' is not a number"))?,
        });
    }
    if raw.len() != count {
        return Err(format!(
            "holds {} values where NumPoints × NumProfiles = {count}: truncated or mismatched",
            raw.len()
        ));
    }
    Ok(header.map(raw))
}

/// The fixed binary header: magic (8), ManufacID (10), CreateDate (12), ModDate (12),
/// NumPoints u16, NumProfiles u16, Xscale, Yscale, Zscale, Zresolution f64, Compression,
/// DataType, CheckType u8, little-endian and packed: 81 bytes.
const BINARY_HEADER: usize = 81;

fn binary(bytes: &[u8]) -> Result<MeasuredMap, String> {
    if bytes.len() < BINARY_HEADER {
        return Err(format!(
            "holds {} bytes, fewer than the 81 of its header: truncated",
            bytes.len()
        ));
    }
    let u16_at = |o: usize| u16::from_le_bytes([bytes[o], bytes[o + 1]]) as usize;
    let f64_at = |o: usize| f64::from_le_bytes(bytes[o..o + 8].try_into().expect("8 bytes"));
    let header = Header {
        points: u16_at(42),
        profiles: u16_at(44),
        x_scale: f64_at(46),
        y_scale: f64_at(54),
        z_scale: f64_at(62),
        compression: bytes[78],
        data_type: bytes[79],
    };
    header.check()?;
    let width = [1, 2, 4, 4, 1, 2, 4, 8][header.data_type as usize];
    let count = header.points * header.profiles;
    let data = &bytes[BINARY_HEADER..];
    if data.len() < count * width {
        return Err(format!(
            "holds {} bytes of data where NumPoints × NumProfiles = {count} values of DataType {} need {}: truncated",
            data.len(),
            header.data_type,
            count * width
        ));
    }
    let raw = data[..count * width]
        .chunks_exact(width)
        .map(|c| match header.data_type {
            0 => c[0] as f64,
            1 => u16::from_le_bytes([c[0], c[1]]) as f64,
            2 => u32::from_le_bytes(c.try_into().expect("4 bytes")) as f64,
            3 => f32::from_le_bytes(c.try_into().expect("4 bytes")) as f64,
            4 => c[0] as i8 as f64,
            5 => i16::from_le_bytes([c[0], c[1]]) as f64,
            6 => i32::from_le_bytes(c.try_into().expect("4 bytes")) as f64,
            _ => f64::from_le_bytes(c.try_into().expect("8 bytes")),
        })
        .collect();
    Ok(header.map(raw))
}
