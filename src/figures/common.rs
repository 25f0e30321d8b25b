//! What the figures share: the loads and rows a figure picks, the CCDF tables it reads, the
//! kinds of figure drawn and how they are written, and the tolerance line.

use std::path::Path;

use polars::prelude::*;
use serde_json::{json, Value};

use crate::store::inputs::Inputs;
use crate::store::table::{f64_column, u32_column};

use super::plot::{LinePlot, Panels, RasterPlot, Series};

/// The loads of a sweep nearest to `targets` (deduplicated, increasing).
pub fn pick_loads(loads: &[(u32, f64)], targets: &[f64]) -> Vec<(u32, f64)> {
    let w: Vec<f64> = loads.iter().map(|l| l.1).collect();
    let mut out: Vec<(u32, f64)> = targets
        .iter()
        .filter_map(|&t| crate::statistics::nearest_in_log(&w, t).map(|i| loads[i]))
        .collect();
    out.sort_by(|a, b| a.1.total_cmp(&b.1));
    out.dedup_by_key(|l| l.0);
    out
}

/// The number of realizations a statistics instance (input `i`) pooled.
pub fn realizations_of(inputs: &Inputs, i: usize) -> anyhow::Result<u64> {
    inputs.of(i, "statistics")?.results["realizations"]
        .as_u64()
        .ok_or_else(|| anyhow::anyhow!("statistics results lack 'realizations'"))
}

/// Rows of `df` at load `load_index`.
pub fn rows_at(df: &DataFrame, load_index: u32) -> anyhow::Result<Vec<usize>> {
    Ok(u32_column(df, "load_index")?
        .into_iter()
        .enumerate()
        .filter(|(_, v)| *v == Some(load_index))
        .map(|(i, _)| i)
        .collect())
}

/// The columns of a statistics stage `ccdf.parquet` that figures draw, read once.
pub struct CcdfTable {
    pub(super) load_index: Vec<Option<u32>>,
    pub(super) w_over_w0: Vec<f64>,
    pub(super) realization: Vec<Option<u32>>,
    pub(super) area_over_ls2: Vec<f64>,
    pub(super) ccdf: Vec<f64>,
    pub(super) ccdf_mean: Vec<f64>,
    pub(super) ccdf_ci95_low: Vec<f64>,
    pub(super) ccdf_ci95_high: Vec<f64>,
}

impl CcdfTable {
    /// The table of input `i` (a statistics instance).
    pub fn read(inputs: &Inputs, i: usize) -> anyhow::Result<Self> {
        let df = inputs.table(i, "statistics", "ccdf.parquet")?;
        Ok(CcdfTable {
            load_index: u32_column(&df, "load_index")?,
            w_over_w0: f64_column(&df, "w_over_w0")?,
            realization: u32_column(&df, "realization")?,
            area_over_ls2: f64_column(&df, "area_over_ls2")?,
            ccdf: f64_column(&df, "ccdf")?,
            ccdf_mean: f64_column(&df, "ccdf_mean")?,
            ccdf_ci95_low: f64_column(&df, "ccdf_ci95_low")?,
            ccdf_ci95_high: f64_column(&df, "ccdf_ci95_high")?,
        })
    }

    /// `(A/λ_s², P(A > a))` at load `load_index` of one realization, or of the pooled
    /// ensemble (`None`), or the ensemble mean of the realizations' CCDFs (`mean`).
    pub fn curve(&self, load_index: u32, realization: Option<u32>, mean: bool) -> Vec<(f64, f64)> {
        let v = if mean { &self.ccdf_mean } else { &self.ccdf };
        (0..v.len())
            .filter(|&i| {
                self.load_index[i] == Some(load_index) && self.realization[i] == realization
            })
            .map(|i| (self.area_over_ls2[i], v[i]))
            .collect()
    }

    /// The 95 % band `(A/λ_s², low, high)` of the realizations' mean CCDF at load
    /// `load_index`, where its lower edge is positive.
    pub fn band(&self, load_index: u32) -> Vec<(f64, f64, f64)> {
        (0..self.ccdf_mean.len())
            .filter(|&i| self.load_index[i] == Some(load_index) && self.realization[i].is_none())
            .map(|i| {
                (
                    self.area_over_ls2[i],
                    self.ccdf_ci95_low[i],
                    self.ccdf_ci95_high[i],
                )
            })
            .filter(|b| b.1 > 0.0 && b.2.is_finite())
            .collect()
    }

    /// Distinct loads `(load_index, W/W0)`, in order.
    pub fn loads(&self) -> Vec<(u32, f64)> {
        let mut out: Vec<(u32, f64)> = Vec::new();
        for (l, &w) in self.load_index.iter().zip(&self.w_over_w0) {
            if let Some(l) = *l {
                if !out.iter().any(|e| e.0 == l) {
                    out.push((l, w));
                }
            }
        }
        out
    }

    /// Realizations present, increasing.
    pub fn realizations(&self) -> Vec<u32> {
        let mut r: Vec<u32> = self.realization.iter().flatten().copied().collect();
        r.sort_unstable();
        r.dedup();
        r
    }
}

/// Something a figures instance writes.
pub enum Drawn {
    Line(LinePlot),
    Panels(Panels),
    /// A raster and the plotted array as `.npy` (shape, values).
    Raster(RasterPlot, NpyData),
    /// A table written as `<stem>.parquet`.
    Table(DataFrame),
    /// A value recorded under `<stem>` in the manifest's results.
    Result(Value),
}

pub enum NpyData {
    F64(Vec<usize>, Vec<f64>),
    U8(Vec<usize>, Vec<u8>),
}

/// Write what a figure drew into `dir`; returns the manifest's results.
pub fn write(drawn: Vec<(String, Drawn)>, dir: &Path) -> anyhow::Result<Value> {
    let mut names = Vec::new();
    let mut sizes = serde_json::Map::new();
    let mut notes = serde_json::Map::new();
    for (stem, item) in drawn {
        match item {
            Drawn::Line(plot) => {
                plot.write(dir, &stem)?;
                plot.write_data(&dir.join(format!("{stem}.csv")))?;
                sizes.insert(stem.clone(), json!(super::plot::SIZE_PX));
            }
            Drawn::Panels(panels) => {
                panels.write(dir, &stem)?;
                panels.write_data(&dir.join(format!("{stem}.csv")))?;
                sizes.insert(stem.clone(), json!(panels.size()));
            }
            Drawn::Raster(raster, data) => {
                raster.write(dir, &stem)?;
                let path = dir.join(format!("{stem}.npy"));
                match data {
                    NpyData::F64(shape, v) => crate::io::write_f64(&path, &shape, v)?,
                    NpyData::U8(shape, v) => crate::io::write_u8(&path, &shape, v)?,
                }
                sizes.insert(stem.clone(), json!(super::plot::RASTER_SIZE_PX));
            }
            Drawn::Table(mut df) => {
                let file = std::fs::File::create(dir.join(format!("{stem}.parquet")))?;
                ParquetWriter::new(file).finish(&mut df)?;
                continue;
            }
            Drawn::Result(v) => {
                notes.insert(stem, v);
                continue;
            }
        }
        names.push(stem);
    }
    let mut result = json!({ "figures": names, "png_size_px": sizes });
    for (k, v) in notes {
        result[k] = v;
    }
    Ok(result)
}

/// The black dashed horizontal line of a tolerance, from `x0` to `x1`, labelled with its value.
pub fn tolerance_line(tolerance: f64, x0: f64, x1: f64) -> Series {
    Series {
        rgb: Some((0, 0, 0)),
        dash: super::plot::Dash::Dashed,
        ..Series::line(
            format!("tolerance {}", super::plot::number(tolerance)),
            vec![(x0, tolerance), (x1, tolerance)],
            0,
        )
    }
}
