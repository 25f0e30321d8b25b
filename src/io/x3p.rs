//! ISO 25178-72 (ISO 5436-2) X3P: a zip archive of an XML index (`main.xml`) and the
//! heights in binary (`bindata/data.bin`, x fastest, then y), with an optional bit mask of
//! the valid points (`bindata/valid.bin`, least significant bit first). Lengths are in
//! metres by the standard; heights are `raw · increment + offset` on the z axis.

use std::io::Read;
use std::path::Path;

use md5::{Digest, Md5};

use super::measured::{MeasuredMap, Source};

/// Read an X3P file: only areal maps on a regular grid (`FeatureType` SUR, x and y axes
/// incremental, one layer) are surfaces; anything else is refused with what it holds.
pub fn read(path: &Path) -> Result<MeasuredMap, String> {
    super::guard::regular_file(path)?;
    let file = std::fs::File::open(path).map_err(|e| format!("cannot be opened ({e})"))?;
    let mut zip = zip::ZipArchive::new(file)
        .map_err(|e| format!("is not a readable zip archive, so not an X3P file ({e})"))?;
    // main.xml at the root, as ISO 5436-2 lays the archive out, or in the one folder that
    // holds everything (as x3ptools and other writers zip a directory); the links of
    // main.xml are relative to it.
    let folder = main_folder(&zip)?;
    let at = |link: &str| format!("{folder}{}", link.trim());
    // main.xml is text of a few KiB; 64 MiB is far beyond any index a writer makes.
    let xml = member(&mut zip, &at("main.xml"), 64 << 20)?;
    let xml = String::from_utf8(xml).map_err(|_| "main.xml is not UTF-8 text".to_string())?;
    let doc = roxmltree::Document::parse(&xml)
        .map_err(|e| format!("main.xml is not well-formed XML ({e})"))?;
    let root = doc.root_element();
    let feature = text(root, &["Record1", "FeatureType"])?;
    if feature.trim() != "SUR" {
        return Err(format!(
            "holds a feature of type '{}', not an areal surface (SUR)",
            feature.trim()
        ));
    }
    let axis = |name: &str| -> Result<Axis, String> {
        let base = ["Record1", "Axes", name];
        // An empty element (`<Offset/>`, as x3ptools writes it) states nothing.
        let get = |field: &str| {
            optional(root, &[base[0], base[1], base[2], field]).filter(|s| !s.trim().is_empty())
        };
        Ok(Axis {
            kind: text(root, &[base[0], base[1], base[2], "AxisType"])?,
            data_type: get("DataType").unwrap_or_default(),
            increment: get("Increment")
                .map(|s| number(&s, &format!("{name} Increment")))
                .transpose()?,
            offset: get("Offset")
                .map(|s| number(&s, &format!("{name} Offset")))
                .transpose()?,
        })
    };
    let (cx, cy, cz) = (axis("CX")?, axis("CY")?, axis("CZ")?);
    for (name, a) in [("CX", &cx), ("CY", &cy)] {
        if a.kind.trim() != "I" {
            return Err(format!(
                "axis {name} is of type '{}': only incremental (I) lateral axes, a regular grid, are read",
                a.kind.trim()
            ));
        }
    }
    let dx = positive(cx.increment, "CX Increment")?;
    let dy = positive(cy.increment, "CY Increment")?;
    let dims = ["Record3", "MatrixDimension"];
    let size = |field: &str| -> Result<usize, String> {
        let s = text(root, &[dims[0], dims[1], field])?;
        s.trim()
            .parse::<usize>()
            .map_err(|_| format!("MatrixDimension {field} '{}' is not a count", s.trim()))
    };
    let (cols, rows, layers) = (size("SizeX")?, size("SizeY")?, size("SizeZ")?);
    if layers != 1 || cols == 0 || rows == 0 {
        return Err(format!(
            "has {cols} × {rows} × {layers} points: a surface has one layer and at least one point"
        ));
    }
    if optional(root, &["Record3", "DataList"]).is_some()
        || optional(root, &["Record3", "DataLink", "PointDataLink"]).is_none()
    {
        return Err(
            "keeps its points inline in main.xml (DataList): only binary point data (DataLink) is read"
                .into(),
        );
    }
    let link = text(root, &["Record3", "DataLink", "PointDataLink"])?;
    let width = match cz.data_type.trim() {
        "I" => 2,
        "L" | "F" => 4,
        _ => 8,
    };
    // The member is read to at most the size MatrixDimension and DataType promise, checked
    // against memory first: a member that inflates beyond it (a zip bomb) is refused.
    super::guard::check_allocation(
        &format!("{cols} × {rows} points of DataType {}", cz.data_type.trim()),
        (rows as u128 * cols as u128).saturating_mul(8 + width),
    )?;
    let data = member(
        &mut zip,
        &at(&link),
        rows as u64 * cols as u64 * width as u64,
    )?;
    check_md5(
        &data,
        optional(root, &["Record3", "DataLink", "MD5ChecksumPointData"]),
        link.trim(),
    )?;
    let count = rows * cols;
    let raw = decode(&data, cz.data_type.trim(), count, link.trim())?;
    let (scale, shift) = (cz.increment.unwrap_or(1.0), cz.offset.unwrap_or(0.0));
    let mut heights: Vec<f64> = raw.into_iter().map(|v| v * scale + shift).collect();
    if let Some(valid_link) = optional(root, &["Record3", "DataLink", "ValidPointsLink"]) {
        let stated = optional(root, &["Record3", "DataLink", "MD5ChecksumValidPoints"]);
        mark_invalid(&mut zip, &at(&valid_link), stated, &mut heights)?;
    }
    Ok(MeasuredMap {
        rows,
        cols,
        heights,
        height_unit_m: Some(1.0),
        pixel_m: Some((dx, dy)),
        pixel_file_units: None,
        source: Source::X3p,
    })
}

/// The folder of the archive's `main.xml` (`""` at the root, else `name/`): the root's, or
/// that of the only `main.xml` outside macOS's `__MACOSX/` resource forks.
fn main_folder(zip: &zip::ZipArchive<std::fs::File>) -> Result<String, String> {
    let indices: Vec<String> = zip
        .file_names()
        .filter_map(|n| n.ok().map(|n| n.into_owned()))
        .filter(|n| !n.starts_with("__MACOSX/"))
        .filter(|n| n == "main.xml" || n.ends_with("/main.xml"))
        .collect();
    if indices.iter().any(|n| n == "main.xml") {
        return Ok(String::new());
    }
    match indices.as_slice() {
        [one] => Ok(one.trim_end_matches("main.xml").to_string()),
        [] => Err(
            "has no member 'main.xml' (an X3P archive holds main.xml and the data it links)".into(),
        ),
        many => Err(format!(
            "holds {} main.xml ({}): several surfaces in one archive; extract the one to read",
            many.len(),
            many.join(", ")
        )),
    }
}

/// NaN at every point the validity bits `link` (least significant bit first) mark invalid.
fn mark_invalid(
    zip: &mut zip::ZipArchive<std::fs::File>,
    link: &str,
    stated_md5: Option<String>,
    heights: &mut [f64],
) -> Result<(), String> {
    let count = heights.len();
    let bits = member(zip, link, count.div_ceil(8) as u64 + 64)?;
    check_md5(&bits, stated_md5, link)?;
    if bits.len() < count.div_ceil(8) {
        return Err(format!(
            "{link} holds {} bytes: too few for the validity bits of {count} points",
            bits.len()
        ));
    }
    for (i, h) in heights.iter_mut().enumerate() {
        if bits[i / 8] >> (i % 8) & 1 == 0 {
            *h = f64::NAN;
        }
    }
    Ok(())
}

struct Axis {
    kind: String,
    data_type: String,
    increment: Option<f64>,
    offset: Option<f64>,
}

/// The member `name`, read to at most `most` bytes: one that holds (or inflates to) more is
/// refused before it is read further.
fn member(
    zip: &mut zip::ZipArchive<std::fs::File>,
    name: &str,
    most: u64,
) -> Result<Vec<u8>, String> {
    let entry = zip.by_name(name).map_err(|_| {
        format!("has no member '{name}' (an X3P archive holds main.xml and the data it links)")
    })?;
    let mut bytes = Vec::with_capacity(entry.size().min(most) as usize);
    entry.take(most + 1).read_to_end(&mut bytes).map_err(|e| {
        format!("member '{name}' cannot be read ({e}): the archive is corrupt or truncated")
    })?;
    if bytes.len() as u64 > most {
        return Err(format!(
            "member '{name}' holds more than the {} that main.xml's MatrixDimension and DataType account for: corrupt, or a zip bomb",
            super::guard::human_bytes(u128::from(most))
        ));
    }
    Ok(bytes)
}

fn check_md5(bytes: &[u8], stated: Option<String>, name: &str) -> Result<(), String> {
    let Some(stated) = stated else { return Ok(()) };
    let stated = stated.trim().to_ascii_lowercase();
    let actual: String = Md5::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    if stated.is_empty() || stated == actual {
        Ok(())
    } else {
        Err(format!(
            "'{name}' does not match its MD5 sum in main.xml ({actual} against {stated}): the data is corrupt"
        ))
    }
}

fn decode(bytes: &[u8], data_type: &str, count: usize, name: &str) -> Result<Vec<f64>, String> {
    let width = match data_type {
        "I" => 2,
        "L" => 4,
        "F" => 4,
        "D" => 8,
        other => {
            return Err(format!(
                "CZ DataType '{other}' is not one of I (int16), L (int32), F (float32), D (float64)"
            ))
        }
    };
    if bytes.len() != count * width {
        return Err(format!(
            "'{name}' holds {} bytes where MatrixDimension and DataType {data_type} need {}: truncated or mismatched",
            bytes.len(),
            count * width
        ));
    }
    let chunks = bytes.chunks_exact(width);
    Ok(match data_type {
        "I" => chunks
            .map(|c| i16::from_le_bytes([c[0], c[1]]) as f64)
            .collect(),
        "L" => chunks
            .map(|c| i32::from_le_bytes(c.try_into().expect("4 bytes")) as f64)
            .collect(),
        "F" => chunks
            .map(|c| f32::from_le_bytes(c.try_into().expect("4 bytes")) as f64)
            .collect(),
        _ => chunks
            .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
            .collect(),
    })
}

/// The element at `path` below `node`, matched by local name (the namespace prefix of the
/// root varies between writers).
fn find<'a>(node: roxmltree::Node<'a, 'a>, path: &[&str]) -> Option<roxmltree::Node<'a, 'a>> {
    path.iter().try_fold(node, |n, name| {
        n.children()
            .find(|c| c.is_element() && c.tag_name().name() == *name)
    })
}

fn optional(node: roxmltree::Node, path: &[&str]) -> Option<String> {
    find(node, path).map(|n| n.text().unwrap_or("").to_string())
}

fn text(node: roxmltree::Node, path: &[&str]) -> Result<String, String> {
    optional(node, path).ok_or_else(|| format!("main.xml has no {}", path.join("/")))
}

fn number(s: &str, what: &str) -> Result<f64, String> {
    s.trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| format!("{what} '{}' in main.xml is not a number", s.trim()))
}

fn positive(v: Option<f64>, what: &str) -> Result<f64, String> {
    match v {
        Some(v) if v > 0.0 => Ok(v),
        Some(v) => Err(format!("{what} is {v}: a pixel size must be > 0")),
        None => Err(format!(
            "main.xml states no {what}: the pixel size is unknown"
        )),
    }
}
