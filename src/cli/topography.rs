//! `wearcoef topography`: a measured map read, its units stated, its form removed and its
//! missing points counted; the prepared heights written in metres with what was done.

use std::path::PathBuf;
use std::process::ExitCode;

use serde_json::json;
use wearcoef::topography::{Form, Topography};

use super::{check_outputs, write_atomically, InputError};

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
    Mean,
    Plane,
    Curvature,
}

#[derive(clap::Args)]
pub struct TopographyArgs {
    /// The map: a 2-D .npy (float32 or float64, any shape) or a text matrix (.txt, .csv,
    /// .asc, .dat: one row per line), NaN for a missing point.
    #[arg(long)]
    pub input: PathBuf,
    /// The unit of the heights in the file.
    #[arg(long, value_enum)]
    pub height_unit: Unit,
    /// The pixel size along x (columns), in --pixel-unit.
    #[arg(long)]
    pub pixel_size: f64,
    /// The pixel size along y (rows), if not that of x.
    #[arg(long)]
    pub pixel_size_y: Option<f64>,
    /// The unit of the pixel sizes (default: that of the heights).
    #[arg(long, value_enum)]
    pub pixel_unit: Option<Unit>,
    /// The form removed by least squares before contact.
    #[arg(long, value_enum, default_value = "plane")]
    pub form: FormArg,
    /// Write the prepared heights here (float64 .npy, metres).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Print the preparation as JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn topography(args: TopographyArgs) -> anyhow::Result<ExitCode> {
    let input = &args.input;
    let bad = |why: String| InputError(format!("--input {}: {why}", input.display()));
    if let Some(out) = &args.output {
        if out.extension().is_none_or(|e| e != "npy") {
            return Err(InputError(format!(
                "--output {}: the prepared map is a .npy file; name it FILE.npy",
                out.display()
            ))
            .into());
        }
        check_outputs(&[("--output", out)], &[("--input", input)])?;
    }
    let ext = input
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let (rows, cols, raw) = match ext.as_str() {
        "npy" => wearcoef::io::read_map_npy(input)?,
        "txt" | "csv" | "asc" | "dat" => wearcoef::io::read_map_text(input)?,
        other => {
            return Err(bad(format!(
                "a .{other} file is not read yet; give a 2-D .npy or a text matrix (.txt, .csv, .asc, .dat)"
            ))
            .into())
        }
    };
    let h_unit = args.height_unit.metres();
    let p_unit = args.pixel_unit.unwrap_or(args.height_unit).metres();
    let (dx, dy) = (
        args.pixel_size * p_unit,
        args.pixel_size_y.unwrap_or(args.pixel_size) * p_unit,
    );
    let heights = raw.into_iter().map(|h| h * h_unit).collect();
    let mut map = Topography::new(rows, cols, dx, dy, heights).map_err(|e| bad(e.to_string()))?;
    map.refuse_missing().map_err(|e| bad(e.to_string()))?;
    let form = match args.form {
        FormArg::Mean => Form::Mean,
        FormArg::Plane => Form::Plane,
        FormArg::Curvature => Form::Curvature,
    };
    let coefficients = map.remove_form(form).map_err(|e| bad(e.to_string()))?;
    let rms_height =
        (map.heights.iter().map(|h| h * h).sum::<f64>() / map.heights.len() as f64).sqrt();
    let rms_slope = map.rms_slope();
    if let Some(out) = &args.output {
        let values = map.heights.clone();
        write_atomically(out, |tmp| {
            wearcoef::io::write_f64(tmp, &[rows, cols], values)?;
            Ok(())
        })?;
    }
    let report = json!({
        "input": input.display().to_string(), "rows": rows, "cols": cols,
        "pixel_size_x_m": dx, "pixel_size_y_m": dy,
        "missing_points": 0, "form_removed": format!("{form:?}").to_lowercase(),
        "form_coefficients_m": coefficients,
        "rms_height_m": rms_height, "rms_slope": rms_slope,
    });
    if args.json {
        out!("{}", serde_json::to_string(&report)?)?;
    } else {
        out!(
            "{rows} × {cols} map, pixel {dx:.4e} × {dy:.4e} m, no missing point; {} removed; rms height {rms_height:.4e} m, rms slope {rms_slope:.4}",
            report["form_removed"].as_str().unwrap_or("")
        )?;
    }
    Ok(ExitCode::SUCCESS)
}
