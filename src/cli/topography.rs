//! `wearcoef topography`: a measured map read, its units stated, its form removed and its
//! missing points counted or filled; the prepared heights written in metres with what was
//! done. [`prepare`] is shared with `wearcoef wear`.

use std::path::PathBuf;
use std::process::ExitCode;

pub use wearcoef::io::prepare::{FillArg, Preparation, Prepared};

use super::checks::{check_output_named, write_atomically};
use wearcoef::io::measured::{formats_read, formats_stating_units};

/// Reading and preparing a measured map (shared by `topography` and `wear`).
#[derive(clap::Args, Debug, Clone)]
pub struct PrepareArgs {
    // The map; its help lists the formats read (`io::measured::FORMATS`).
    #[arg(long, help = input_help())]
    pub input: PathBuf,
    #[command(flatten)]
    pub preparation: Preparation,
}

/// `--input`'s help: every format read, and which state their units.
fn input_help() -> String {
    format!(
        "The map: {}. The content decides, not the suffix. Files that state their units: {}; \
         the others need --height-unit and --pixel-size. NaN or the format's invalid flag marks \
         a missing point",
        formats_read(),
        formats_stating_units()
    )
}

/// Read, scale to metres, remove the form and fill (or refuse) missing points.
pub fn prepare(args: &PrepareArgs) -> anyhow::Result<Prepared> {
    wearcoef::io::prepare::prepare(&args.input, &args.preparation)
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
        let mut df = wearcoef::stages::surface::psd_table(&psd)?;
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
