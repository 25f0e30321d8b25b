//! The clusters stage: every contact map of one realization's sweep labelled on the periodic
//! torus (8-neighbour by default); one row per cluster (`clusters.parquet`) and one per load
//! (`loads.parquet`). File layouts are in docs/CONVENTIONS.md.

use std::path::Path;

use polars::prelude::*;
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

use super::contact::{contact_file, saturated_file};
use super::stage::Stage;
use crate::clusters::{self, Boundary, Connectivity};
use crate::store::inputs::Inputs;
use crate::store::table::{col, load_columns, write};

pub struct Clusters;

/// One realization's labelling. Input 0: its contact sweep.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClustersJob {
    /// W/W0 of the sweep's loads, in its order.
    #[serde(rename = "loads_w_over_w0")]
    pub loads: Vec<f64>,
    /// Grid side.
    pub n: usize,
    /// λ_s in grid spacings: areas are also given in units of λ_s².
    pub lambda_s_px: f64,
    /// Realization index, written to every row.
    pub realization: u32,
    /// Neighbours that link pixels (8, the paper's).
    pub connectivity: Connectivity,
    /// The sweep was under a hardness: its saturated maps are labelled too, into
    /// `saturated_clusters.parquet` (the same columns). Absent (and not in the key) when
    /// elastic.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub saturated: bool,
    /// A measured map: its `[rows, cols]`, labelled without wrap-around (`n` is 0), with a
    /// `touches_edge` column for the clusters its border cuts. Absent (and not in the key)
    /// for the periodic `n × n` grid.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub window: Option<[usize; 2]>,
}

impl ClustersJob {
    /// Rows, columns and boundary of the maps.
    fn shape(&self) -> (usize, usize, Boundary) {
        match self.window {
            Some([rows, cols]) => (rows, cols, Boundary::Open),
            None => (self.n, self.n, Boundary::Periodic),
        }
    }
}

impl Stage for Clusters {
    const NAME: &'static str = "clusters";
    const VERSION: u32 = 1;
    type Job = ClustersJob;

    fn compute(job: &ClustersJob, inputs: &Inputs, dir: &Path) -> anyhow::Result<Value> {
        compute_clusters(job, inputs, dir)
    }
}

/// Label the contact map of every load of one realization (and, under a hardness, its
/// saturated map).
fn compute_clusters(job: &ClustersJob, inputs: &Inputs, dir: &Path) -> anyhow::Result<Value> {
    let summary = label_maps(job, inputs, dir, contact_file, "clusters.parquet", true)?;
    if job.saturated {
        label_maps(
            job,
            inputs,
            dir,
            saturated_file,
            "saturated_clusters.parquet",
            false,
        )?;
    }
    Ok(summary)
}

/// Label the maps `file(i)` of the sweep's loads into one row per cluster in `table`, and,
/// if `per_load`, one row per load in `loads.parquet`; the summary of the labelling.
fn label_maps(
    job: &ClustersJob,
    inputs: &Inputs,
    dir: &Path,
    file: fn(usize) -> String,
    table: &str,
    per_load: bool,
) -> anyhow::Result<Value> {
    let ls2 = job.lambda_s_px * job.lambda_s_px;
    let (want_rows, want_cols, boundary) = job.shape();
    let pixels = (want_rows * want_cols) as f64;
    let mut touches_edge = Vec::new();
    // Per cluster.
    let (mut load_index, mut w, mut id) = (Vec::new(), Vec::new(), Vec::new());
    let (mut area, mut area_ls2, mut perimeter) = (Vec::new(), Vec::new(), Vec::new());
    let (mut extent_x, mut extent_y, mut percolating) = (Vec::new(), Vec::new(), Vec::new());
    // Per load.
    let (mut n_clusters, mut fraction, mut largest, mut n_perc) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for (i, &load) in job.loads.iter().enumerate() {
        let path = inputs.file(0, "contact", &file(i))?;
        let (rows, cols, map, _) = crate::io::read_contact_map(&path)?;
        if (rows, cols) != (want_rows, want_cols) {
            anyhow::bail!(
                "{}: contact map is {rows} × {cols}, the study's grid is {want_rows} × {want_cols}",
                path.display(),
            );
        }
        let l = clusters::label_with(&map, rows, cols, job.connectivity, boundary)?;
        if job.window.is_some() {
            touches_edge.extend(l.touching_border());
        }
        let mut in_contact = 0u64;
        let mut max_area = 0u64;
        for (k, c) in l.clusters.iter().enumerate() {
            load_index.push(i as u32);
            w.push(load);
            id.push(k as u32 + 1);
            area.push(c.area_px);
            area_ls2.push(c.area_px as f64 / ls2);
            perimeter.push(c.perimeter_px);
            extent_x.push(c.extent_x_px);
            extent_y.push(c.extent_y_px);
            percolating.push(c.percolating());
            in_contact += c.area_px;
            max_area = max_area.max(c.area_px);
        }
        n_clusters.push(l.clusters.len() as u32);
        fraction.push(in_contact as f64 / pixels);
        largest.push(max_area as f64 / ls2);
        n_perc.push(l.clusters.iter().filter(|c| c.percolating()).count() as u32);
    }
    let rows = area.len();
    let realization = vec![job.realization; rows];
    write(
        dir,
        table,
        DataFrame::new(
            rows,
            vec![
                col("realization", realization),
                col("load_index", load_index),
                col("w_over_w0", w),
                col("cluster_id", id),
                col("area_px", area),
                col("area_over_ls2", area_ls2),
                col("perimeter_px", perimeter),
                col("extent_x_px", extent_x),
                col("extent_y_px", extent_y),
                col("percolating", percolating),
            ]
            .into_iter()
            .chain(job.window.map(|_| col("touches_edge", touches_edge)))
            .collect(),
        )?,
    )?;
    let loads = job.loads.len();
    if !per_load {
        return Ok(Value::Null);
    }
    let total: u64 = n_clusters.iter().map(|&v| v as u64).sum();
    let percolating_loads = n_perc.iter().filter(|&&v| v > 0).count();
    write(
        dir,
        "loads.parquet",
        DataFrame::new(
            loads,
            [
                load_columns(&job.loads).to_vec(),
                vec![
                    col("n_clusters", n_clusters),
                    col("area_fraction", fraction),
                    col("largest_area_over_ls2", largest),
                    col("n_percolating", n_perc),
                ],
            ]
            .concat(),
        )?,
    )?;
    Ok(json!({
        "total_clusters": total,
        "loads_with_percolating_cluster": percolating_loads,
    }))
}
