//! The surface stage: one surface as `heights.npy`, either a self-affine random surface
//! generated from its parameters and seed (square, periodic, unit rms slope, zero mean, on
//! the unit box) or a measured topography file prepared for contact (rows × cols, not
//! periodic, in metres, with its pixel size, PSD and preparation record).

use std::path::Path;

use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

use super::stage::Stage;
use crate::io::prepare::{prepare_quietly, FillArg, Preparation};
use crate::spectral::Fft2;
use crate::store::inputs::Inputs;
use crate::store::table::{col, write};
use crate::surface::{self, SurfaceParams};

pub struct Surface;

/// What a surface is made from. Untagged: a generated surface's job is its parameters
/// alone, as it always was (and so is its key).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum SurfaceJob {
    Generated(SurfaceParams),
    Measured(MeasuredJob),
}

/// A measured topography file, keyed by its content: the runner copies the file named by
/// the plan into the entry as `file` before the stage runs (see
/// [`crate::pipeline::plan::SourceFile`]), and the stage refuses it unless its SHA-256 is
/// `sha256`. Where the file lies is not part of the key.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeasuredJob {
    /// Name of the copied file in the entry: `topography.<the file's extension>`.
    pub file: String,
    /// SHA-256 of the file's bytes, hex.
    pub sha256: String,
    /// The map's shape as read when the plan was made (checked again here).
    pub rows: usize,
    pub cols: usize,
    pub preparation: Preparation,
    /// The revision of the readers and checks that turn the file into heights
    /// ([`MEASURED_READER`]): part of the key, so that a file read differently is recomputed.
    #[serde(default)]
    pub reader: u32,
}

/// The readers' revision: 2 reads by content (an x-y-z list or decimal commas in a .txt),
/// refuses maps flat once their form is removed and fills of more than half a map; 3 reads
/// X3P members in a folder, SurfaceTopography's text header keys and UTF-16 text, solves
/// rectangular pixels, and records only the PSD's resolved H, λ_l and λ_s.
pub const MEASURED_READER: u32 = 3;

/// The name a measured file is copied under: `topography.<ext>` (the readers go by the
/// extension).
pub fn measured_file_name(path: &Path) -> String {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    format!("topography.{ext}")
}

impl Stage for Surface {
    const NAME: &'static str = "surface";
    const VERSION: u32 = 1;
    type Job = SurfaceJob;

    fn compute(job: &SurfaceJob, _inputs: &Inputs, dir: &Path) -> anyhow::Result<Value> {
        match job {
            SurfaceJob::Generated(params) => generated(params, dir),
            SurfaceJob::Measured(m) => measured(m, dir),
        }
    }
}

fn generated(params: &SurfaceParams, dir: &Path) -> anyhow::Result<Value> {
    let fft = Fft2::new(params.n);
    let mut scratch = fft.make_scratch();
    let s = surface::generate(params, &fft, &mut scratch)?;
    crate::io::write_heights(&dir.join("heights.npy"), s.grid.n(), s.heights)?;
    Ok(json!({
        "mean_height": s.stats.mean_height,
        "rms_height": s.stats.rms_height,
        "rms_slope": s.stats.rms_slope,
        "hurst_fit": s.stats.hurst_fit,
        "box_size": 1.0,
        "grid_spacing": s.grid.spacing(),
    }))
}

/// The measured file checked against its key, prepared, and written as `heights.npy` (metres,
/// rows × cols) with `psd.parquet`; the results are the preparation's record.
fn measured(job: &MeasuredJob, dir: &Path) -> anyhow::Result<Value> {
    let path = dir.join(&job.file);
    let (sha256, _) = crate::store::hash::sha256_file(&path).map_err(|e| {
        anyhow::anyhow!(
            "{}: the measured file was not copied into the entry ({e}): run the plan with `wearcoef run` or `wearcoef exec`, which copy it",
            job.file
        )
    })?;
    anyhow::ensure!(
        sha256 == job.sha256,
        "{}: its SHA-256 is {sha256}, the plan's is {}: the file changed after the plan was made; make the plan anew",
        job.file,
        job.sha256
    );
    anyhow::ensure!(
        job.preparation.fill != FillArg::Keep,
        "fill keep: contact needs every height; choose fill harmonic or none"
    );
    // Quiet: the runner prints the record's warnings naming the file by its path, which
    // the job (keyed by content) does not hold.
    let name = format!("measured file of SHA-256 {}…", &job.sha256[..12]);
    let prepared = prepare_quietly(&path, &name, &job.preparation)?;
    let map = &prepared.map;
    anyhow::ensure!(
        (map.rows, map.cols) == (job.rows, job.cols),
        "{}: read as {} × {}, the plan's is {} × {}",
        job.file,
        map.rows,
        map.cols,
        job.rows,
        job.cols
    );
    crate::io::write_f64(
        &dir.join("heights.npy"),
        &[map.rows, map.cols],
        map.heights.clone(),
    )?;
    let table = psd_table(&prepared.psd)?;
    write(dir, "psd.parquet", table)?;
    let mut results = prepared.report;
    results["input"] = json!(job.file);
    results["sha256"] = json!(sha256);
    results["periodic"] = json!(false);
    Ok(results)
}

/// The radially averaged PSD as a table: `q_low_per_m`, `q_high_per_m`, `q_mean_per_m`
/// (rad/m), `c_m4` (m⁴), `count`.
pub fn psd_table(
    psd: &[crate::psd::PsdBin],
) -> polars::prelude::PolarsResult<polars::prelude::DataFrame> {
    let get = |f: fn(&crate::psd::PsdBin) -> f64| psd.iter().map(f).collect::<Vec<f64>>();
    polars::prelude::DataFrame::new(
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
    )
}
