//! `wearcoef topography`: a measured map read, its units stated, its form removed and its
//! missing points counted or filled; the prepared heights written in metres with what was
//! done. [`prepare`] is shared with `wearcoef wear`.

use std::path::PathBuf;
use std::process::ExitCode;

use serde_json::json;
use wearcoef::io::measured::READ_EXTENSIONS;
use wearcoef::io::read_measured;
use wearcoef::psd::{fit_self_affine, log_edges, radial_psd, PsdBin};
use wearcoef::topography::{Form, Topography};

use super::{check_output_named, write_atomically, InputError};

/// A length unit of a measured map.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum Unit {
    M,
    Mm,
    Um,
    Nm,
}

impl Unit {
    fn metres(self) -> f64 {
        match self {
            Unit::M => 1.0,
            Unit::Mm => 1e-3,
            Unit::Um => 1e-6,
            Unit::Nm => 1e-9,
        }
    }
}

/// The form removed, as `pipeline.yaml` and the output spell it.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum FormArg {
    /// Nothing removed (the heights as read, scaled to metres).
    None,
    Mean,
    Plane,
    Curvature,
}

/// What is done with missing points.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum FillArg {
    /// Refuse a map with missing points, naming how many and the first.
    None,
    /// Harmonic (Laplace) interpolation from the present points, after the form removal.
    Harmonic,
    /// Keep them missing (NaN) in the prepared map: `topography` only, for inspection;
    /// contact needs every height.
    Keep,
}

/// Reading and preparing a measured map (shared by `topography` and `wear`).
#[derive(clap::Args, Debug, Clone)]
pub struct PrepareArgs {
    /// The map: .x3p (ISO 25178-72), .sdf (ISO 25178-71, text or binary), .gsf (Gwyddion),
    /// .nc (NetCDF 3 as SurfaceTopography writes it), which state their units; a 2-D .npy
    /// (float32 or float64, any shape, rows along y) or a text matrix (.txt, .csv, .asc,
    /// .dat: one row per line). NaN or the format's invalid flag marks a missing point.
    #[arg(long)]
    pub input: PathBuf,
    /// The unit of the heights: required when the file states none (.npy, text); given
    /// for a file that states one, it overrides the file.
    #[arg(long, value_enum)]
    pub height_unit: Option<Unit>,
    /// The pixel size along x (columns), in --pixel-unit: required when the file states
    /// none; overrides the file's.
    #[arg(long)]
    pub pixel_size: Option<f64>,
    /// The pixel size along y (rows), if not that of x.
    #[arg(long)]
    pub pixel_size_y: Option<f64>,
    /// The unit of the pixel sizes (default: that of the heights).
    #[arg(long, value_enum)]
    pub pixel_unit: Option<Unit>,
    /// The form removed by least squares (over the present points) before contact.
    #[arg(long, value_enum, default_value = "plane")]
    pub form: FormArg,
    /// What to do with missing points.
    #[arg(long, value_enum, default_value = "none")]
    pub fill: FillArg,
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

/// The PSD of a complete map, its self-affine fit and the warnings it calls for.
fn spectrum(map: &Topography) -> (Vec<PsdBin>, serde_json::Value, Vec<String>) {
    let psd = radial_psd(map, &log_edges(map, 10));
    let fit = fit_self_affine(&psd);
    let mut warnings = Vec::new();
    match fit {
        Some(f) if f.lambda_s_m / map.dx.max(map.dy) < MIN_LAMBDA_S_PX => warnings.push(format!(
            "the fitted λ_s = {:.3e} m is {:.1} pixels: below {MIN_LAMBDA_S_PX} the discretised contact area is biased (docs/SIZES.md); measure at a finer pixel",
            f.lambda_s_m,
            f.lambda_s_m / map.dx.max(map.dy)
        )),
        None => warnings.push(
            "the PSD has no self-affine range of 5 bins (within a factor 2 of a power law): H, λ_l and λ_s are not fitted".into(),
        ),
        _ => {}
    }
    let fit = fit.map_or(serde_json::Value::Null, |f| {
        json!({"hurst": f.hurst, "lambda_l_m": f.lambda_l_m, "lambda_s_m": f.lambda_s_m,
               "lambda_s_px": f.lambda_s_m / map.dx.max(map.dy),
               "max_log10_residual": f.max_log10_residual, "bins": f.bins})
    });
    (psd, fit, warnings)
}

/// Read, scale to metres, remove the form and fill (or refuse) missing points.
pub fn prepare(args: &PrepareArgs) -> anyhow::Result<Prepared> {
    let input = &args.input;
    let bad = |why: String| InputError(format!("--input {}: {why}", input.display()));
    let read = read_measured(input)?;
    let (height_scale, height_unit_from) = match (args.height_unit, read.height_unit_m) {
        (Some(u), Some(file)) => (u.metres() / file, "--height-unit (overriding the file)"),
        (Some(u), None) => (u.metres(), "--height-unit"),
        (None, Some(_)) => (1.0, "the file"),
        (None, None) => {
            return Err(bad(format!(
                "the file states no height unit; give --height-unit (m, mm, um, nm). Files that state theirs: {READ_EXTENSIONS}"
            ))
            .into())
        }
    };
    let p_unit = args.pixel_unit.or(args.height_unit).map(Unit::metres);
    let ((dx, dy), pixel_from) = match (args.pixel_size, read.pixel_m) {
        (Some(px), file) => {
            let Some(u) = p_unit else {
                return Err(bad(
                    "--pixel-size needs --pixel-unit (or --height-unit) to state its unit".into(),
                )
                .into());
            };
            let py = args.pixel_size_y.unwrap_or(px);
            let from = if file.is_some() {
                "--pixel-size (overriding the file)"
            } else {
                "--pixel-size"
            };
            ((px * u, py * u), from)
        }
        (None, Some(d)) => (d, "the file"),
        (None, None) => {
            return Err(bad(
                "the file states no pixel size; give --pixel-size (and --pixel-unit)".into(),
            )
            .into())
        }
    };
    let (rows, cols) = (read.rows, read.cols);
    let heights = read.heights.into_iter().map(|h| h * height_scale).collect();
    let mut map = Topography::new(rows, cols, dx, dy, heights).map_err(|e| bad(e.to_string()))?;
    let missing = map.missing();
    if args.fill == FillArg::None {
        map.refuse_missing()
            .map_err(|e| bad(format!("{e} (--fill harmonic)")))?;
    }
    let form = match args.form {
        FormArg::None => None,
        FormArg::Mean => Some(Form::Mean),
        FormArg::Plane => Some(Form::Plane),
        FormArg::Curvature => Some(Form::Curvature),
    };
    let coefficients = match form {
        Some(form) => map.remove_form(form).map_err(|e| bad(e.to_string()))?,
        None => Vec::new(),
    };
    let filled = match args.fill {
        FillArg::Keep => 0,
        _ => map.fill_harmonic().map_err(|e| bad(e.to_string()))?,
    };
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
    let (psd, fit, warnings) = if args.fill == FillArg::Keep && missing > 0 {
        (Vec::new(), serde_json::Value::Null, Vec::new())
    } else {
        spectrum(&map)
    };
    for w in &warnings {
        wearcoef::note!("warning: {}: {w}", input.display());
    }
    let report = json!({
        "input": input.display().to_string(), "format": read.source,
        "rows": rows, "cols": cols,
        "pixel_size_x_m": dx, "pixel_size_y_m": dy, "pixel_size_from": pixel_from,
        "height_unit_from": height_unit_from,
        "missing_points": missing, "filled_points": filled,
        "fill": match (args.fill, filled) {
            (FillArg::Keep, _) => "keep",
            (_, 0) => "none",
            _ => "harmonic",
        },
        "form_removed": form.map_or("none".to_string(), |f| format!("{f:?}").to_lowercase()),
        "form_coefficients_m": coefficients,
        "rms_height_m": rms_height, "rms_slope": rms_slope,
        "psd_fit": fit, "warnings": warnings,
    });
    Ok(Prepared { map, report, psd })
}

#[derive(clap::Args)]
pub struct TopographyArgs {
    #[command(flatten)]
    pub prepare: PrepareArgs,
    /// Write the prepared heights here (float64 .npy, metres, rows along y).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Write the radially averaged PSD here (Parquet: q_low_per_m, q_high_per_m,
    /// q_mean_per_m in rad/m, c_m4 in m⁴, count).
    #[arg(long)]
    pub psd: Option<PathBuf>,
    /// Print the preparation as JSON.
    #[arg(long)]
    pub json: bool,
}

/// The PSD bins as a table.
pub fn psd_frame(psd: &[PsdBin]) -> anyhow::Result<polars::prelude::DataFrame> {
    use wearcoef::store::table::col;
    let get = |f: fn(&PsdBin) -> f64| psd.iter().map(f).collect::<Vec<f64>>();
    Ok(polars::prelude::DataFrame::new(
        psd.len(),
        vec![
            col("q_low_per_m", get(|b| b.q_low)),
            col("q_high_per_m", get(|b| b.q_high)),
            col("q_mean_per_m", get(|b| b.q_mean)),
            col("c_m4", get(|b| b.c)),
            col(
                "count",
                psd.iter().map(|b| b.count as u64).collect::<Vec<_>>(),
            ),
        ],
    )?)
}

pub fn topography(args: TopographyArgs) -> anyhow::Result<ExitCode> {
    let input = [("--input", args.prepare.input.as_path())];
    if let Some(out) = &args.output {
        check_output_named(
            "--output",
            out,
            "npy",
            "the prepared map is a .npy file",
            &input,
        )?;
    }
    if let Some(out) = &args.psd {
        check_output_named(
            "--psd",
            out,
            "parquet",
            "the PSD is a Parquet table",
            &input,
        )?;
    }
    let Prepared { map, report, psd } = prepare(&args.prepare)?;
    if let Some(out) = &args.psd {
        let mut df = psd_frame(&psd)?;
        write_atomically(out, |tmp| {
            polars::prelude::ParquetWriter::new(std::fs::File::create(tmp)?).finish(&mut df)?;
            Ok(())
        })?;
    }
    if let Some(out) = &args.output {
        let values = map.heights.clone();
        write_atomically(out, |tmp| {
            wearcoef::io::write_f64(tmp, &[map.rows, map.cols], values)?;
            Ok(())
        })?;
    }
    if args.json {
        out!("{}", serde_json::to_string(&report)?)?;
    } else {
        out!(
            "{} × {} map, pixel {:.4e} × {:.4e} m, {} missing ({} filled); {} removed; rms height {:.4e} m, rms slope {:.4}",
            map.rows,
            map.cols,
            map.dx,
            map.dy,
            report["missing_points"],
            report["filled_points"],
            report["form_removed"].as_str().unwrap_or(""),
            report["rms_height_m"].as_f64().unwrap_or(f64::NAN),
            report["rms_slope"].as_f64().unwrap_or(f64::NAN),
        )?;
    }
    Ok(ExitCode::SUCCESS)
}
