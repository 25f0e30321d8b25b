//! Measured topography files, whatever their format, read into one [`MeasuredMap`]: the
//! heights row-major with rows along y (NaN for a missing point), in metres when the file
//! states a unit, and the pixel size when the file states one.

/// The format a map was read from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Source {
    Npy,
    Text,
    X3p,
    NetCdf,
    Gsf,
    Sdf,
    Xyz,
    /// An array given to the Python package, in metres with its pixel size.
    Array,
}

/// A map as read from its file.
#[derive(Debug, Clone)]
pub struct MeasuredMap {
    pub rows: usize,
    pub cols: usize,
    /// Row-major, row `i` along y; NaN marks a missing point. In metres when
    /// `height_unit_m` is known (the file's values times it), else as in the file.
    pub heights: Vec<f64>,
    /// The metres per height unit of the file, when it states one.
    pub height_unit_m: Option<f64>,
    /// The pixel size `(Δx, Δy)` in metres, when the file states it.
    pub pixel_m: Option<(f64, f64)>,
    /// The pixel size in the file's own length unit, when the file gives positions but no
    /// unit (an x-y-z list): the heights' unit, once the user states it.
    pub pixel_file_units: Option<(f64, f64)>,
    pub source: Source,
}

impl MeasuredMap {
    /// The number of missing points.
    pub fn missing(&self) -> usize {
        self.heights.iter().filter(|h| h.is_nan()).count()
    }
}

/// One topography format read: the one list that every help text and message names.
pub struct Format {
    /// What a user calls it (`.x3p`, `text matrix`).
    pub name: &'static str,
    /// What it is, in a few words.
    pub what: &'static str,
    /// The suffixes it goes by (lower case, no dot).
    pub suffixes: &'static [&'static str],
    /// How the file states its units; None where it never does (the user gives them).
    pub units: Option<&'static str>,
}

/// Every topography format read (`io::read_measured`; the content decides, not the suffix).
pub const FORMATS: [Format; 7] = [
    Format {
        name: ".x3p",
        what: "ISO 25178-72",
        suffixes: &["x3p"],
        units: Some("metres by the standard"),
    },
    Format {
        name: ".sdf",
        what: "ISO 25178-71, text or binary",
        suffixes: &["sdf"],
        units: Some("metres by the standard"),
    },
    Format {
        name: ".gsf",
        what: "Gwyddion Simple Field",
        suffixes: &["gsf"],
        units: Some("`XYUnits` and `ZUnits`"),
    },
    Format {
        name: ".nc",
        what: "NetCDF 3 as SurfaceTopography writes it",
        suffixes: &["nc"],
        units: Some("`unit` attributes"),
    },
    Format {
        name: ".npy",
        what: "a 2-D float32 or float64 array, rows along y",
        suffixes: &["npy"],
        units: None,
    },
    Format {
        name: "text matrix",
        what: ".txt, .csv, .asc, .dat, .tsv: one row per line",
        suffixes: &["txt", "csv", "asc", "dat", "tsv"],
        units: Some("SurfaceTopography's `# Value units:` header"),
    },
    Format {
        name: "x-y-z list",
        what: ".xyz: one point per line on a regular grid",
        suffixes: &["xyz"],
        units: Some("Gwyddion's `# Lateral units:` and `# Value units:` header"),
    },
];

/// The formats read, for error messages and `--help`: `.x3p (ISO 25178-72), …`.
pub fn formats_read() -> String {
    FORMATS
        .iter()
        .map(|f| format!("{} ({})", f.name, f.what))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The formats that state their units and how, for the message that asks for one (a .npy
/// never does; text and x-y-z lists only with the header named).
pub fn formats_stating_units() -> String {
    FORMATS
        .iter()
        .filter_map(|f| f.units.map(|u| format!("{} ({u})", f.name)))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Whether `suffix` (lower case, no dot) is one a format read goes by.
pub fn is_format_suffix(suffix: &str) -> bool {
    FORMATS.iter().any(|f| f.suffixes.contains(&suffix))
}

/// Metres per unit for a length unit as files spell it (`m`, `mm`, `um`/`µm`/`μm`,
/// `nm`, `pm`, `A`/`Å`); None if unknown.
pub fn length_unit_m(unit: &str) -> Option<f64> {
    Some(match unit {
        "m" => 1.0,
        "cm" => 1e-2,
        "mm" => 1e-3,
        "um" | "µm" | "μm" | "micrometer" | "micrometre" => 1e-6,
        "nm" => 1e-9,
        "A" | "\u{c5}" | "\u{212b}" => 1e-10,
        "pm" => 1e-12,
        _ => return None,
    })
}

/// The units and sizes a text matrix states in its header lines (with or without a leading
/// `#` or `%`), read by the keys SurfaceTopography's text reader knows (`AscReader`):
/// - counts: `h=305 w=75`, `x-pixels=…`, `y-pixels=…` (rows and columns, checked against
///   the numbers read);
/// - sizes: `Width: 10 µm`, `Height: 10 µm` (`x-length`, `y-length`, `Breite`, `Höhe`);
/// - a pixel size: `pixel size=3.69862e-007 m` (the same along x and y);
/// - units: `Value units: m`, `z-unit`, `x-unit`, `y-unit`; `height conversion factor
///   (-> m)=6.3e-008`, the metres per number (instrument exports in radians of phase).
///
/// A size without its own unit takes the heights' unit, as SurfaceTopography does.
pub(super) fn text_header(header: &[String], map: &mut MeasuredMap) -> Result<(), String> {
    let f = header_keys(header)?;
    apply_header(&f, map)
}

/// What a text header states, as read.
#[derive(Default)]
struct Found {
    nx: Option<usize>,
    ny: Option<usize>,
    size_x: Option<(f64, Option<String>)>,
    size_y: Option<(f64, Option<String>)>,
    pixel: Option<(f64, Option<String>)>,
    xunit: Option<String>,
    yunit: Option<String>,
    zunit: Option<String>,
    zfac: Option<f64>,
}

/// The keys of [`text_header`] read from the header lines.
fn header_keys(header: &[String]) -> Result<Found, String> {
    let mut f = Found::default();
    // A number at the start of `v`, and what follows it (a unit, or nothing).
    let number_and_rest = |v: &str| -> Option<(f64, Option<String>)> {
        let v = v.trim();
        let end = v
            .char_indices()
            .find(|&(i, c)| {
                !(c.is_ascii_digit()
                    || c == '.'
                    || c == '-'
                    || c == '+'
                    || ((c == 'e' || c == 'E')
                        && v[i + c.len_utf8()..]
                            .starts_with(|d: char| d.is_ascii_digit() || d == '-' || d == '+')))
            })
            .map_or(v.len(), |(i, _)| i);
        let x = v[..end].parse::<f64>().ok()?;
        let rest = v[end..].trim();
        Some((x, (!rest.is_empty()).then(|| rest.to_string())))
    };
    let count = |v: &str| v.trim().parse::<usize>().ok();
    for raw in header {
        let line = raw.trim().trim_start_matches(['#', '%']).trim();
        // `key = value`, `key: value` or (counts only) `key value`; several `key=value`
        // pairs may share a line (`h=650 w=650`).
        let lower = line.to_lowercase();
        if let Some(rest) = lower.strip_prefix("height conversion factor (->") {
            let Some((unit, value)) = rest.split_once(')') else {
                continue;
            };
            let value = value.trim().trim_start_matches('=').trim();
            let zfac = value.parse::<f64>().map_err(|_| {
                format!("header '{line}': the height conversion factor is not a number")
            })?;
            f.zunit = Some(unit.trim().to_string());
            f.zfac = Some(zfac);
            continue;
        }
        if lower.starts_with("pixel size") {
            if let Some((_, v)) = line.split_once('=') {
                f.pixel =
                    Some(number_and_rest(v).ok_or_else(|| {
                        format!("header '{line}': the pixel size is not a number")
                    })?);
            }
            continue;
        }
        let pairs: Vec<(String, String)> = if line.contains('=') {
            // `h=650 w=650`, `x-unit = um`: no space around `=`, then split before every
            // `key=`.
            let tight = line.split('=').map(str::trim).collect::<Vec<_>>().join("=");
            let mut out = Vec::new();
            for part in tight.split_whitespace() {
                match part.split_once('=') {
                    Some((k, v)) => out.push((k.to_string(), v.to_string())),
                    None => {
                        if let Some(last) = out.last_mut() {
                            last.1.push(' ');
                            last.1.push_str(part);
                        }
                    }
                }
            }
            out
        } else if let Some((k, v)) = line.split_once(':') {
            vec![(k.to_string(), v.to_string())]
        } else if let Some(v) = line.strip_prefix("X Size") {
            vec![("x size".to_string(), v.to_string())]
        } else if let Some(v) = line.strip_prefix("Y Size") {
            vec![("y size".to_string(), v.to_string())]
        } else {
            continue;
        };
        for (key, value) in pairs {
            let length = || {
                number_and_rest(&value)
                    .filter(|(x, _)| *x > 0.0 && x.is_finite())
                    .ok_or_else(|| format!("header '{line}' is not a length"))
            };
            match key.trim().to_lowercase().as_str() {
                // As SurfaceTopography: `h` and `X Size` count the lines (rows, along y),
                // `w` and `Y Size` the numbers in a line (columns, along x).
                "h" | "x-pixels" | "x size" => f.ny = count(&value),
                "w" | "y-pixels" | "y size" => f.nx = count(&value),
                "width" | "x-length" | "breite" => f.size_x = Some(length()?),
                "height" | "y-length" | "höhe" => f.size_y = Some(length()?),
                "x-unit" => f.xunit = Some(value.trim().to_string()),
                "y-unit" => f.yunit = Some(value.trim().to_string()),
                "z-unit" | "value units" => f.zunit = Some(value.trim().to_string()),
                _ => {}
            }
        }
    }
    Ok(f)
}

/// The counts checked, the heights scaled and the pixel size set from what a header states.
fn apply_header(f: &Found, map: &mut MeasuredMap) -> Result<(), String> {
    for (stated, read, what) in [
        (f.ny, map.rows, "lines (h)"),
        (f.nx, map.cols, "columns (w)"),
    ] {
        if let Some(n) = stated.filter(|&n| n != read) {
            return Err(format!(
                "its header states {n} {what} where the file holds {read}: truncated, or not the matrix the header describes"
            ));
        }
    }
    let unit_m = |u: &str| {
        length_unit_m(u.trim()).ok_or_else(|| format!("header: unknown length unit '{}'", u.trim()))
    };
    let zunit_m = f.zunit.as_deref().map(unit_m).transpose()?;
    if let Some(z) = zunit_m {
        let scale = z * f.zfac.unwrap_or(1.0);
        map.heights.iter_mut().for_each(|h| *h *= scale);
        map.height_unit_m = Some(scale);
    }
    // A size in metres: its own unit, else the axis's, else the heights'.
    let metres =
        |(x, own): &(f64, Option<String>), axis: &Option<String>| -> Result<Option<f64>, String> {
            let unit = own.as_deref().or(axis.as_deref()).or(f.zunit.as_deref());
            Ok(match unit {
                Some(u) => Some(x * unit_m(u)?),
                None => None,
            })
        };
    let (px, py) = match (&f.pixel, &f.size_x, &f.size_y) {
        (Some(p), _, _) => {
            let d = metres(p, &f.xunit)?;
            (d, d)
        }
        (None, Some(w), Some(h)) => (
            metres(w, &f.xunit)?.map(|w| w / map.cols as f64),
            metres(h, &f.yunit)?.map(|h| h / map.rows as f64),
        ),
        _ => (None, None),
    };
    if let (Some(dx), Some(dy)) = (px, py) {
        map.pixel_m = Some((dx, dy));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The one list of formats and the reader's content map agree: every suffix a content
    /// goes by is a format's, and every format's suffix is some content's; every format
    /// appears in the help's and the messages' list, and only the .npy states no unit.
    #[test]
    fn the_format_list_is_the_readers_own() {
        use crate::io::sniff::{suffixes, Content};
        let contents = [
            Content::Npy,
            Content::Zip,
            Content::NetCdf3,
            Content::Gsf,
            Content::SdfText,
            Content::SdfBinary,
            Content::Text,
        ];
        let mut by_content: Vec<&str> = contents
            .iter()
            .flat_map(|&c| suffixes(c).iter().copied())
            .collect();
        let mut by_format: Vec<&str> = FORMATS
            .iter()
            .flat_map(|f| f.suffixes.iter().copied())
            .collect();
        by_content.sort_unstable();
        by_content.dedup();
        by_format.sort_unstable();
        assert_eq!(by_content, by_format);
        let read = formats_read();
        let stating = formats_stating_units();
        for f in &FORMATS {
            assert!(read.contains(&format!("{} ({})", f.name, f.what)), "{read}");
            assert_eq!(stating.contains(f.name), f.units.is_some(), "{stating}");
            for s in f.suffixes {
                assert!(is_format_suffix(s));
            }
        }
        assert!(!is_format_suffix("png") && !is_format_suffix(""));
        assert_eq!(FORMATS.iter().filter(|f| f.units.is_none()).count(), 1);
    }

    fn map(rows: usize, cols: usize) -> MeasuredMap {
        MeasuredMap {
            rows,
            cols,
            heights: vec![2.0; rows * cols],
            height_unit_m: None,
            pixel_m: None,
            pixel_file_units: None,
            source: Source::Text,
        }
    }

    fn header(lines: &[&str]) -> Vec<String> {
        lines.iter().map(|l| l.to_string()).collect()
    }

    /// An instrument's export (SurfaceTopography's matrix-4.txt): counts, one pixel size for
    /// both axes, and the metres per number.
    #[test]
    fn instrument_header_of_counts_pixel_and_conversion() {
        let lines = header(&[
            "h=305 w=75",
            "pixel size=3.69862e-007 m",
            "data unit=rad",
            "height conversion factor (-> m)=2.91818e-008",
        ]);
        let mut m = map(305, 75);
        text_header(&lines, &mut m).unwrap();
        assert_eq!(m.pixel_m, Some((3.69862e-7, 3.69862e-7)));
        assert_eq!(m.heights[0], 2.0 * 2.91818e-8);
        let e = text_header(&lines, &mut map(304, 75)).unwrap_err();
        assert!(
            e.contains("states 305 lines (h) where the file holds 304"),
            "{e}"
        );
    }

    /// Gwyddion's exports in English and German, sizes in their own units, heights in m; a
    /// size without a unit takes the heights'.
    #[test]
    fn gwyddion_headers_and_units() {
        for lines in [
            [
                "# Channel: Main",
                "# Width: 12.34 µm",
                "# Height: 5678.9 nm",
                "# Value units: m",
            ],
            [
                "# Kanal: Main",
                "# Breite: 12.34 µm",
                "# Höhe: 5678.9 nm",
                "# Value units: m",
            ],
        ] {
            let mut m = map(4, 3);
            text_header(&header(&lines), &mut m).unwrap();
            let (dx, dy) = m.pixel_m.unwrap();
            assert!((dx / (12.34e-6 / 3.0) - 1.0).abs() < 1e-12, "{dx}");
            assert!((dy / (5678.9e-9 / 4.0) - 1.0).abs() < 1e-12, "{dy}");
            assert_eq!(m.height_unit_m, Some(1.0));
        }
        let mut m = map(2, 2);
        text_header(
            &header(&["x-length = 4", "y-length = 2", "z-unit = um"]),
            &mut m,
        )
        .unwrap();
        assert_eq!(m.pixel_m, Some((2e-6, 1e-6)));
        assert_eq!(m.heights[0], 2e-6);
    }
}
