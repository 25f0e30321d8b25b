//! A measured map prepared for contact: read, its units stated, its form removed and its
//! missing points counted or filled, with the record of what was done. Shared by `wearcoef
//! topography`, `wearcoef wear` and the surface stage of a `measured` study, which spell
//! the same settings as options (`--height-unit`) and as `pipeline.yaml` fields
//! (`height_unit`).

use std::path::Path;

use serde::{Deserialize, Serialize};
use serde_json::json;

use super::error::IoError;
use super::measured::{formats_stating_units, MeasuredMap};
use super::read::read_measured;
use crate::psd::{log_edges, radial_psd, resolve, PsdBin};
use crate::topography::{Form, Topography};

/// A length unit of a measured map.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Unit {
    M,
    Mm,
    Um,
    Nm,
}

impl Unit {
    pub fn metres(self) -> f64 {
        match self {
            Unit::M => 1.0,
            Unit::Mm => 1e-3,
            Unit::Um => 1e-6,
            Unit::Nm => 1e-9,
        }
    }
}

/// The form removed by least squares over the present points.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FormArg {
    /// Nothing removed (the heights as read, scaled to metres).
    None,
    Mean,
    Plane,
    Curvature,
}

/// What is done with missing points.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FillArg {
    /// Refuse a map with missing points, naming how many and the first.
    None,
    /// Harmonic (Laplace) interpolation from the present points, after the form removal.
    Harmonic,
    /// Keep them missing (NaN) in the prepared map: `topography` only, for inspection;
    /// contact needs every height.
    Keep,
}

/// How a measured map is prepared: its units where the file states none (or overriding
/// the file's), the form removed and the rule for missing points.
#[derive(clap::Args, Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Preparation {
    /// The unit of the heights: required when the file states none (.npy, text); given
    /// for a file that states one, it overrides the file.
    #[arg(long, value_enum)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub height_unit: Option<Unit>,
    /// The pixel size along x (columns), in --pixel-unit: required when the file states
    /// none; overrides the file's.
    #[arg(long)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pixel_size: Option<f64>,
    /// The pixel size along y (rows), if not that of x.
    #[arg(long)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pixel_size_y: Option<f64>,
    /// The unit of the pixel sizes (default: that of the heights).
    #[arg(long, value_enum)]
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pixel_unit: Option<Unit>,
    /// The form removed by least squares (over the present points) before contact.
    #[arg(long, value_enum, default_value = "plane")]
    #[serde(default = "plane")]
    pub form: FormArg,
    /// What to do with missing points.
    #[arg(long, value_enum, default_value = "none")]
    #[serde(default = "no_fill")]
    pub fill: FillArg,
    /// Resample a map of rectangular pixels onto square ones of its finer pixel size, by
    /// linear interpolation along the coarser axis (after the form and the fill). Never
    /// needed: rectangular pixels are solved as measured. `wear` and `topography` only.
    #[arg(long)]
    #[serde(skip)]
    pub resample: bool,
}

fn plane() -> FormArg {
    FormArg::Plane
}

fn no_fill() -> FillArg {
    FillArg::None
}

/// A prepared map and the record of its preparation (JSON, stored with every output).
pub struct Prepared {
    pub map: Topography,
    pub report: serde_json::Value,
    /// The radially averaged PSD (none when missing points were kept).
    pub psd: Vec<PsdBin>,
}

/// The smallest λ_s/Δl at which the project's own discretisation study finds the contact
/// area unbiased (docs/SIZES.md); below it a warning is given and recorded.
const MIN_LAMBDA_S_PX: f64 = 8.0;

/// The PSD of a complete map, what it resolves ([`resolve`]: H, λ_l and λ_s only where the
/// spectrum shows them) and the warnings it calls for: a resolved λ_s under
/// [`MIN_LAMBDA_S_PX`] pixels, or a self-affine power law that runs to the pixel (the
/// roughness continues below it). A spectrum that shows no self-affine range warns of
/// nothing: what it does not resolve is recorded with the reason, and printed as a note.
fn spectrum(map: &Topography) -> (Vec<PsdBin>, serde_json::Value, Vec<String>) {
    let psd = radial_psd(map, &log_edges(map, 10));
    let r = resolve(&psd);
    let pixel = map.dx.max(map.dy);
    let mut warnings = Vec::new();
    match (r.hurst, r.lambda_s_m) {
        (Some(_), Some(ls)) if ls / pixel < MIN_LAMBDA_S_PX => warnings.push(format!(
            "the spectrum rolls off at λ_s = {ls:.3e} m, {:.1} pixels: below {MIN_LAMBDA_S_PX} the discretised contact area is biased (docs/SIZES.md); measure at a finer pixel",
            ls / pixel
        )),
        (Some(h), None) => warnings.push(format!(
            "the spectrum is self-affine (H = {h:.2}) down to the pixel: the roughness continues below it, and contact areas depend on the pixel size (docs/SIZES.md); the trust band's coarsened map shows by how much"
        )),
        _ => {}
    }
    let mut fit = serde_json::to_value(&r).expect("plain numbers and strings");
    fit["lambda_s_px"] = json!(r.lambda_s_m.map(|ls| ls / pixel));
    (psd, fit, warnings)
}

/// The heights' scale to metres and where the unit came from.
fn height_scale(
    p: &Preparation,
    file: Option<f64>,
    bad: &dyn Fn(String) -> IoError,
) -> Result<(f64, &'static str), IoError> {
    match (p.height_unit, file) {
        (Some(u), Some(file)) => Ok((u.metres() / file, "height_unit (overriding the file)")),
        (Some(u), None) => Ok((u.metres(), "height_unit")),
        (None, Some(_)) => Ok((1.0, "the file")),
        (None, None) => Err(bad(format!(
            "the file states no height unit; give one (--height-unit, or height_unit in pipeline.yaml: m, mm, um, nm). Files that state theirs: {}",
            formats_stating_units()
        ))),
    }
}

/// The pixel size `(Δx, Δy)` in metres and where it came from.
fn pixel_size(
    p: &Preparation,
    read: &super::measured::MeasuredMap,
    bad: &dyn Fn(String) -> IoError,
) -> Result<((f64, f64), &'static str), IoError> {
    let unit = p.pixel_unit.or(p.height_unit).map(Unit::metres);
    if let (None, None, Some((dx, dy))) = (p.pixel_size, read.pixel_m, read.pixel_file_units) {
        // Positions without a unit share the heights' (an x-y-z list).
        return match unit {
            Some(u) => Ok(((dx * u, dy * u), "the file's positions, in height_unit")),
            None => Err(bad(
                "the file states no unit; give one (--height-unit, or height_unit in pipeline.yaml: m, mm, um, nm), which its positions share".into(),
            )),
        };
    }
    let file = read.pixel_m;
    match (p.pixel_size, file) {
        (Some(px), file) => {
            let Some(u) = unit else {
                return Err(bad(
                    "a pixel size needs its unit: give pixel_unit (or height_unit)".into(),
                ));
            };
            let py = p.pixel_size_y.unwrap_or(px);
            let unit_name = p
                .pixel_unit
                .or(p.height_unit)
                .map_or("", |u| match u {
                    Unit::M => "m",
                    Unit::Mm => "mm",
                    Unit::Um => "um",
                    Unit::Nm => "nm",
                });
            for (option, v) in [("pixel_size", px), ("pixel_size_y", py)] {
                let r = crate::ranges::PIXEL_M;
                if r.check(option, v * u).is_err() {
                    return Err(bad(format!(
                        "--{} {} {unit_name} ({option}: {} in pipeline.yaml): the {} must be in {} ({})",
                        option.replace('_', "-"),
                        crate::ranges::show(v),
                        crate::ranges::show(v),
                        r.what,
                        r.span(),
                        r.why
                    )));
                }
            }
            let from = if file.is_some() {
                "pixel_size (overriding the file)"
            } else {
                "pixel_size"
            };
            Ok(((px * u, py * u), from))
        }
        (None, Some(d)) => {
            let show = crate::ranges::show;
            if !(d.0.is_finite() && d.0 > 0.0 && d.1.is_finite() && d.1 > 0.0) {
                return Err(bad(format!(
                    "the file states a pixel size of {} × {} m: a pixel size is finite and > 0 (give --pixel-size, or pixel_size in pipeline.yaml)",
                    show(d.0),
                    show(d.1)
                )));
            }
            Ok((d, "the file"))
        }
        (None, None) => Err(bad(
            "the file states no pixel size; give one (--pixel-size and --pixel-unit, or pixel_size and pixel_unit in pipeline.yaml)".into(),
        )),
    }
}

/// The largest share of a map that a harmonic fill may invent: beyond it the contact would
/// be that of the interpolation, not of the measurement.
pub const MAX_FILLED_FRACTION: f64 = 0.5;

/// A share of filled points above which the record and the terminal say so.
pub const WARN_FILLED_FRACTION: f64 = 0.05;

/// A map whose heights, once the form is removed, vary by less than this fraction of what
/// they varied before is flat: what is left is the fit's rounding, not roughness.
pub const FLAT_RESIDUE: f64 = 1e-9;

/// Pixels longer than wide by more than this are refused: the pressure would be resolved
/// along one side by a fraction of the other, and such a ratio is more often a wrong pixel
/// size than an instrument's.
pub const MAX_PIXEL_ASPECT: f64 = 64.0;

/// Pixels longer than wide by more than this are solved with a warning: the contact is
/// resolved along the long side as a map of that coarser pixel.
pub const WARN_PIXEL_ASPECT: f64 = 4.0;

/// Whether a map of pixels `dx × dy` can be solved (rectangular pixels are solved as
/// measured, without resampling), and the warning it calls for.
pub fn check_pixel_aspect(dx: f64, dy: f64) -> Result<Option<String>, String> {
    let aspect = dx.max(dy) / dx.min(dy);
    if aspect > MAX_PIXEL_ASPECT {
        return Err(format!(
            "its pixels are {} × {} m, {aspect:.0} times longer than wide (at most {MAX_PIXEL_ASPECT:.0} is solved): check the pixel size the file or pipeline.yaml states",
            crate::ranges::show(dx),
            crate::ranges::show(dy)
        ));
    }
    Ok((aspect > WARN_PIXEL_ASPECT).then(|| {
        format!(
            "its pixels are {aspect:.1} times longer than wide: the contact is resolved along the long side as on a map of {} m pixels",
            crate::ranges::show(dx.max(dy))
        )
    }))
}

/// Refuse a fill that would invent more than [`MAX_FILLED_FRACTION`] of a map; a warning
/// when it fills more than [`WARN_FILLED_FRACTION`].
pub fn check_filled_share(missing: usize, total: usize) -> Result<Option<String>, String> {
    let share = missing as f64 / total.max(1) as f64;
    if share > MAX_FILLED_FRACTION {
        return Err(format!(
            "{missing} of {total} points ({:.1} %) are missing: a harmonic fill would invent more than {:.0} % of the map, and its contact would be that of the interpolation; crop the map to its measured part",
            100.0 * share,
            100.0 * MAX_FILLED_FRACTION
        ));
    }
    Ok((share > WARN_FILLED_FRACTION).then(|| {
        format!(
            "{missing} of {total} points ({:.1} %) are missing and filled by harmonic interpolation: where they cluster, the contact is that of the interpolation",
            100.0 * share
        )
    }))
}

/// The range of the present heights (0 when fewer than two).
fn height_range(heights: &[f64]) -> f64 {
    let (lo, hi) = heights
        .iter()
        .filter(|h| !h.is_nan())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &h| {
            (a.min(h), b.max(h))
        });
    if hi > lo {
        hi - lo
    } else {
        0.0
    }
}

/// Refuse a map that is flat once its form is removed: its heights vary by no more than
/// [`FLAT_RESIDUE`] of their range before (the rounding of the fit).
pub fn check_not_flat(before: &[f64], after: &[f64], form: &str) -> Result<(), String> {
    let (was, is) = (height_range(before), height_range(after));
    if is == 0.0 && was == 0.0 {
        return Err(
            "the map is flat: every height is the same; there is nothing to press (check the file)"
                .into(),
        );
    }
    if is <= FLAT_RESIDUE * was || is == 0.0 {
        return Err(format!(
            "the map is flat once its {form} is removed (its heights then vary by {} m, {} of the {} m before: the fit's rounding, not roughness); there is nothing to press: check the file, or remove less form (--form none)",
            crate::ranges::show(is),
            crate::ranges::show(if was > 0.0 { is / was } else { 0.0 }),
            crate::ranges::show(was)
        ));
    }
    Ok(())
}

/// What [`prepare`] would refuse in a map already read, checked without filling it or
/// computing its spectrum (so that a plan refuses it before any work): the units, a pixel
/// size in range and of a sane aspect, the share a fill would invent, and a map flat once its form
/// is removed.
pub fn check_for_contact(
    read: &super::measured::MeasuredMap,
    p: &Preparation,
) -> Result<(), String> {
    let bad = |why: String| IoError::File {
        path: String::new(),
        message: why,
    };
    let plain = |e: IoError| match e {
        IoError::File { message, .. } => message,
    };
    let (scale, _) = height_scale(p, read.height_unit_m, &bad).map_err(plain)?;
    let ((dx, dy), _) = pixel_size(p, read, &bad).map_err(plain)?;
    check_pixel_aspect(dx, dy)?;
    let missing = read.missing();
    if p.fill == FillArg::Harmonic {
        check_filled_share(missing, read.rows * read.cols)?;
    }
    let heights: Vec<f64> = read.heights.iter().map(|h| h * scale).collect();
    let mut map = Topography::new(read.rows, read.cols, dx, dy, heights.clone())
        .map_err(|e| e.to_string())?;
    let form = match p.form {
        FormArg::None => None,
        FormArg::Mean => Some(Form::Mean),
        FormArg::Plane => Some(Form::Plane),
        FormArg::Curvature => Some(Form::Curvature),
    };
    if let Some(form) = form {
        map.remove_form(form).map_err(|e| e.to_string())?;
    }
    let form_name = form.map_or("none".to_string(), |f| format!("{f:?}").to_lowercase());
    check_not_flat(&heights, &map.heights, &form_name)
}

/// Read `input`, scale it to metres, remove the form and fill (or refuse) missing points;
/// its warnings and what the spectrum does not resolve are printed, naming `input`.
pub fn prepare(input: &Path, p: &Preparation) -> anyhow::Result<Prepared> {
    let prepared = prepare_quietly(input, &input.display().to_string(), p)?;
    announce(&input.display().to_string(), &prepared.report);
    Ok(prepared)
}

/// Print the warnings of a preparation's record and what its spectrum does not resolve,
/// naming the map `name` (the pipeline names a measured file by its path in
/// pipeline.yaml, which its stage does not see).
pub fn announce(name: &str, report: &serde_json::Value) {
    for w in report["warnings"].as_array().into_iter().flatten() {
        if let Some(w) = w.as_str() {
            crate::note!("warning: {name}: {w}");
        }
    }
    for why in report["psd_fit"]["not_resolved"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|w| w.as_str())
    {
        crate::note!("note: {name}: not resolved: {why}");
    }
}

/// [`prepare`] without printing, naming the map `name` in its record (a copy read from a
/// temporary place is named by what it is; see [`announce`]).
pub fn prepare_quietly(input: &Path, name: &str, p: &Preparation) -> anyhow::Result<Prepared> {
    let read = read_measured(input)?;
    prepare_map(read, &input.display().to_string(), name, p)
}

/// [`prepare_quietly`] of a map already read (or given as an array by the Python package):
/// `input` names it in errors, `name` in its record.
pub fn prepare_map(
    read: MeasuredMap,
    input: &str,
    name: &str,
    p: &Preparation,
) -> anyhow::Result<Prepared> {
    let bad = |why: String| IoError::File {
        path: input.to_string(),
        message: why,
    };
    let (scale, height_unit_from) = height_scale(p, read.height_unit_m, &bad)?;
    let ((dx, dy), pixel_from) = pixel_size(p, &read, &bad)?;
    let (rows, cols) = (read.rows, read.cols);
    let heights = read.heights.into_iter().map(|h| h * scale).collect();
    let mut map = Topography::new(rows, cols, dx, dy, heights).map_err(|e| bad(e.to_string()))?;
    let missing = map.missing();
    if p.fill == FillArg::None {
        map.refuse_missing().map_err(|e| {
            bad(format!(
                "{e} (--fill harmonic, or fill: harmonic in pipeline.yaml)"
            ))
        })?;
    }
    let form = match p.form {
        FormArg::None => None,
        FormArg::Mean => Some(Form::Mean),
        FormArg::Plane => Some(Form::Plane),
        FormArg::Curvature => Some(Form::Curvature),
    };
    let aspect_warning = check_pixel_aspect(dx, dy)
        .map_err(bad)?
        .filter(|_| !p.resample);
    let mut fill_warning = None;
    if p.fill == FillArg::Harmonic {
        fill_warning = check_filled_share(missing, rows * cols).map_err(bad)?;
    }
    let before = map.heights.clone();
    let coefficients = match form {
        Some(form) => map.remove_form(form).map_err(|e| bad(e.to_string()))?,
        None => Vec::new(),
    };
    let form_name = form.map_or("none".to_string(), |f| format!("{f:?}").to_lowercase());
    check_not_flat(&before, &map.heights, &form_name).map_err(bad)?;
    drop(before);
    let filled = match p.fill {
        FillArg::Keep => 0,
        _ => map.fill_harmonic().map_err(|e| bad(e.to_string()))?,
    };
    let measured_shape = (rows, cols, dx, dy);
    if p.resample {
        map = map.resampled_square();
    }
    let (rows, cols, dx, dy) = (map.rows, map.cols, map.dx, map.dy);
    let resampled = p.resample.then(|| {
        json!({
            "rows": measured_shape.0, "cols": measured_shape.1,
            "pixel_size_x_m": measured_shape.2, "pixel_size_y_m": measured_shape.3,
            "method": "linear along the coarser axis",
        })
    });
    let present: Vec<f64> = map
        .heights
        .iter()
        .copied()
        .filter(|h| !h.is_nan())
        .collect();
    let mean = present.iter().sum::<f64>() / present.len().max(1) as f64;
    let rms_height = (present.iter().map(|h| (h - mean) * (h - mean)).sum::<f64>()
        / present.len().max(1) as f64)
        .sqrt();
    let rms_slope = map.rms_slope();
    let (psd, fit, mut warnings) = if p.fill == FillArg::Keep && missing > 0 {
        (Vec::new(), serde_json::Value::Null, Vec::new())
    } else {
        spectrum(&map)
    };
    warnings.extend(aspect_warning);
    warnings.extend(fill_warning);
    let mut report = json!({
        "input": name, "format": read.source,
        "rows": rows, "cols": cols,
        "pixel_size_x_m": dx, "pixel_size_y_m": dy, "pixel_size_from": pixel_from,
        "height_unit_from": height_unit_from,
        "missing_points": missing, "filled_points": filled,
        "fill": match (p.fill, filled) {
            (FillArg::Keep, _) => "keep",
            (_, 0) => "none",
            _ => "harmonic",
        },
        "form_removed": form_name,
        "form_coefficients_m": coefficients,
        "rms_height_m": rms_height, "rms_slope": rms_slope,
        "psd_fit": fit, "warnings": warnings,
    });
    if let Some(from) = resampled {
        report["resampled_from"] = from;
    }
    Ok(Prepared { map, report, psd })
}
