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

/// The file extensions read, for error messages and `--help`.
pub const READ_EXTENSIONS: &str = ".x3p (ISO 25178-72), .sdf (ISO 25178-71), .gsf (Gwyddion), .nc (NetCDF 3), .npy, text matrix (.txt, .csv, .asc, .dat), x-y-z list (.xyz)";

/// The formats that state their units (a .npy never does; text and x-y-z lists only with
/// the header named), for the message that asks for one.
pub const STATE_UNITS: &str = ".x3p, .sdf, .gsf, .nc with `unit` attributes, a text matrix with SurfaceTopography's `# Value units:` header, an x-y-z list with Gwyddion's `# Lateral units:` and `# Value units:`";

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

/// The units a text matrix states in its comment header, as SurfaceTopography writes it
/// (`# Width: 30.0 µm`, `# Height: 18.0 µm`, `# Value units: µm`): applied to `map`.
pub(super) fn text_header(header: &[String], map: &mut MeasuredMap) -> Result<(), String> {
    let (mut width, mut height, mut unit) = (None, None, None);
    for line in header
        .iter()
        .map(|l| l.trim())
        .filter(|l| l.starts_with('#'))
    {
        let Some((key, value)) = line.trim_start_matches('#').split_once(':') else {
            continue;
        };
        let length = |v: &str| -> Result<(f64, f64), String> {
            let mut parts = v.split_whitespace();
            let number = parts.next().and_then(|x| x.parse::<f64>().ok());
            let scale = parts.next().map(|u| {
                length_unit_m(u)
                    .ok_or_else(|| format!("header '{}': unknown length unit '{u}'", line))
            });
            match (number, scale) {
                (Some(x), Some(s)) if x > 0.0 && x.is_finite() => Ok((x, s?)),
                _ => Err(format!("header '{line}' is not a length with its unit")),
            }
        };
        match key.trim().to_ascii_lowercase().as_str() {
            "width" => width = Some(length(value)?),
            "height" => height = Some(length(value)?),
            "value units" => {
                let u = value.trim();
                unit = Some(
                    length_unit_m(u)
                        .ok_or_else(|| format!("header '{line}': unknown length unit '{u}'"))?,
                );
            }
            _ => {}
        }
    }
    if let Some(u) = unit {
        map.heights.iter_mut().for_each(|h| *h *= u);
        map.height_unit_m = Some(u);
    }
    if let (Some((w, wu)), Some((h, hu))) = (width, height) {
        map.pixel_m = Some((w * wu / map.cols as f64, h * hu / map.rows as f64));
    }
    Ok(())
}
