//! Reading a measured map, or a text matrix, by its content.

use std::path::Path;

use super::error::IoError;
use super::gsf;
use super::guard;
use super::measured;
use super::netcdf;
use super::npy::{npy_header, read_map_npy};
use super::sdf;
use super::sniff;
use super::text;
use super::x3p;
use super::xyz;

/// Read a plain-text matrix of heights: one row of the map per line, values separated by
/// spaces, tabs, commas or semicolons (a decimal comma where fields are separated by tabs,
/// spaces or semicolons); header lines before the numbers and lines starting with `#` or
/// `%` are skipped; `nan` (any case) is a missing point. Every row must have the same
/// length. A table that is an x-y-z list or a line scan is refused, saying so.
pub fn read_map_text(path: &Path) -> Result<(usize, usize, Vec<f64>), IoError> {
    let err = |message: String| IoError::File {
        path: path.display().to_string(),
        message,
    };
    let table = read_table(path).map_err(err)?;
    match text::classify(&table) {
        text::Shape::Matrix => Ok((table.rows, table.cols, table.values)),
        text::Shape::Xyz => Err(err(
            "is an x-y-z list (three columns on a regular grid), not a matrix".into(),
        )),
        text::Shape::LineScan => Err(err(format!(
            "is {}; a contact needs a 2-D map",
            text::describe_line_scan(&table)
        ))),
    }
}

/// The table of numbers of a text file (a regular file, within the memory budget).
fn read_table(path: &Path) -> Result<text::Table, String> {
    // Every two bytes of text may be a value of eight: the table is bounded by 4× the file.
    let len = guard::regular_file(path)?;
    guard::check_allocation("a table of that much text", u128::from(len) * 5)?;
    let bytes = guard::read_bounded(path)?;
    text::table(&text::decode(&bytes)?)
}

/// Read a measured map by its content: its first bytes say what it is (the suffix must
/// agree); every failure names the file and what is wrong. Devices, pipes and directories
/// are refused before anything is read.
pub fn read_measured(path: &Path) -> Result<measured::MeasuredMap, IoError> {
    use sniff::Content;
    let err = |message: String| IoError::File {
        path: path.display().to_string(),
        message,
    };
    let len = guard::regular_file(path).map_err(err)?;
    let mut head = Vec::with_capacity(len.min(1 << 16) as usize);
    {
        use std::io::Read;
        std::fs::File::open(path)
            .and_then(|f| f.take(1 << 16).read_to_end(&mut head))
            .map_err(|e| err(format!("cannot be read ({e})")))?;
    }
    let content = sniff::sniff(&head);
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    match content {
        Content::Foreign(what) => return Err(err(format!("is {what}"))),
        Content::Binary => {
            return Err(err(if sniff::suffixes(Content::Text).contains(&ext.as_str()) {
                format!("is a binary file, not text (a matrix or an x-y-z list); the formats read are {}", measured::formats_read())
            } else {
                format!(
                    "is a binary file of no format read here; the formats read are {}",
                    measured::formats_read()
                )
            }))
        }
        c if measured::is_format_suffix(&ext) && !sniff::suffixes(c).contains(&ext.as_str()) => {
            return Err(err(format!(
                "is named .{ext} but holds {}: rename it to what it holds, or check that it is the file meant",
                sniff::name(c)
            )))
        }
        _ => {}
    }
    let plain = |(rows, cols, heights): (usize, usize, Vec<f64>), source| measured::MeasuredMap {
        rows,
        cols,
        heights,
        height_unit_m: None,
        pixel_m: None,
        pixel_file_units: None,
        source,
    };
    match content {
        Content::Npy => {
            // A true header of more values than memory allows: refused before reading.
            let (_, shape) = npy_header(path)?;
            let values = shape
                .iter()
                .fold(1u128, |a, &d| a.saturating_mul(d as u128));
            guard::check_allocation("the map's heights", values.saturating_mul(16)).map_err(err)?;
            Ok(plain(read_map_npy(path)?, measured::Source::Npy))
        }
        Content::Zip => x3p::read(path).map_err(err),
        Content::NetCdf3 => netcdf::read(path).map_err(err),
        Content::Gsf => gsf::read(path).map_err(err),
        Content::SdfText | Content::SdfBinary => sdf::read(path).map_err(err),
        _ => {
            let table = read_table(path).map_err(|e| {
                if measured::is_format_suffix(&ext) {
                    err(e)
                } else {
                    err(format!(
                        "a .{ext} file is not read, and as text it {}; the formats read are {}",
                        e.trim_start_matches("is "),
                        measured::formats_read()
                    ))
                }
            })?;
            match text::classify(&table) {
                text::Shape::Xyz => xyz::from_table(&table).map_err(err),
                text::Shape::LineScan => Err(err(format!(
                    "is {}; a contact needs a 2-D map (a matrix, or an x-y-z list on a grid)",
                    text::describe_line_scan(&table)
                ))),
                text::Shape::Matrix if ext == "xyz" && table.cols == 3 => {
                    xyz::from_table(&table).map_err(err)
                }
                text::Shape::Matrix if ext == "xyz" => Err(err(format!(
                    "is named .xyz but holds a table of {} columns, not three (x y z)",
                    table.cols
                ))),
                text::Shape::Matrix => {
                    let mut map = measured::MeasuredMap {
                        rows: table.rows,
                        cols: table.cols,
                        heights: table.values,
                        height_unit_m: None,
                        pixel_m: None,
                        pixel_file_units: None,
                        source: measured::Source::Text,
                    };
                    measured::text_header(&table.header, &mut map).map_err(err)?;
                    Ok(map)
                }
            }
        }
    }
}
