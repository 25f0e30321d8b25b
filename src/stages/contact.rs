//! The contact stage: one surface's load sweep, its contact maps (bit-packed, every load),
//! pressure fields (the loads a figure shows) and per-load solver summary (`loads.parquet`).

use std::path::Path;

use polars::prelude::*;
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

use super::stage::Stage;
use crate::contact::elastic::ElasticOperator;
use crate::contact::interface::Interface;
use crate::contact::solver::SolverConfig;
use crate::contact::sweep::{pack_contact, sweep_heights_under, LoadResult};
use crate::contact::window::sweep_window;
use crate::grid::Grid;
use crate::store::inputs::Inputs;
use crate::store::table::{col, load_columns, write};
use crate::topography::Topography;

pub struct Contact;

/// One realization's sweep. Input 0: its surface.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactJob {
    /// W/W0 of each load, solved in this order (warm starts).
    #[serde(rename = "loads_w_over_w0")]
    pub loads: Vec<f64>,
    /// Indices into `loads` whose pressure field is stored.
    pub keep_pressure: Vec<usize>,
    /// Effective modulus E* (pressures are in its unit).
    pub e_star: f64,
    /// Solver tolerance on the complementarity error, and iteration cap.
    pub tolerance: f64,
    pub max_iterations: u32,
    /// The interface: written as the hardness (units of W/W0) of a perfectly plastic one,
    /// absent (and then not in the key) for elastic contact.
    #[serde(
        default,
        rename = "hardness",
        skip_serializing_if = "Interface::is_elastic"
    )]
    pub interface: Interface,
}

/// File name of the packed contact map of load `index`.
pub fn contact_file(index: usize) -> String {
    format!("contact_{index:03}.npy")
}

/// File name of the packed saturated map (p = 𝓗) of load `index`, under a hardness.
pub fn saturated_file(index: usize) -> String {
    format!("saturated_{index:03}.npy")
}

/// File name of the plastic displacement field of kept load `index`, under a hardness.
pub fn plastic_file(index: usize) -> String {
    format!("plastic_displacement_{index:03}.npy")
}

/// File name of the pressure field of load `index`.
pub fn pressure_file(index: usize) -> String {
    format!("pressure_{index:03}.npy")
}

impl Stage for Contact {
    const NAME: &'static str = "contact";
    const VERSION: u32 = 15;
    type Job = ContactJob;

    fn compute(job: &ContactJob, inputs: &Inputs, dir: &Path) -> anyhow::Result<Value> {
        let surface = inputs.of(0, "surface")?;
        if surface.results["periodic"] == Value::Bool(false) {
            return compute_window(job, inputs, dir);
        }
        let path = inputs.file(0, "surface", "heights.npy")?;
        let (n, heights) = crate::io::read_square_f64(&path)?;
        let cfg = SolverConfig {
            tolerance: job.tolerance,
            max_iterations: job.max_iterations as usize,
            ..SolverConfig::default()
        };
        let row_bytes = n.div_ceil(8);
        let (slope, results) = sweep_heights_under(
            &heights,
            n,
            job.e_star,
            &job.loads,
            &cfg,
            job.interface,
            |index, pressure, result| {
                let packed = pack_contact(pressure, n);
                crate::io::write_u8(&dir.join(contact_file(index)), &[n, row_bytes], packed)
                    .map_err(|e| e.to_string())?;
                if let Some(ceiling) = result.ceiling {
                    let saturated: Vec<f64> = pressure
                        .iter()
                        .map(|&p| if p >= ceiling { 1.0 } else { 0.0 })
                        .collect();
                    crate::io::write_u8(
                        &dir.join(saturated_file(index)),
                        &[n, row_bytes],
                        pack_contact(&saturated, n),
                    )
                    .map_err(|e| e.to_string())?;
                    if job.keep_pressure.contains(&index) {
                        let plastic =
                            plastic_displacement(&heights, n, job.e_star, pressure, ceiling)
                                .map_err(|e| e.to_string())?;
                        crate::io::write_f64(&dir.join(plastic_file(index)), &[n, n], plastic)
                            .map_err(|e| e.to_string())?;
                    }
                }
                if job.keep_pressure.contains(&index) {
                    crate::io::write_f64(
                        &dir.join(pressure_file(index)),
                        &[n, n],
                        pressure.to_vec(),
                    )
                    .map_err(|e| e.to_string())?;
                }
                Ok(())
            },
        )?;
        write(dir, "loads.parquet", loads_table(&results)?)?;
        Ok(json!({
            "n": n,
            "rms_slope": slope,
            "total_iterations": results.iter().map(|r| r.report.iterations).sum::<usize>(),
            "solve_seconds": results.iter().map(|r| r.seconds).collect::<Vec<_>>(),
        }))
    }
}

/// The sweep of a measured map (not periodic, rows × cols, heights in metres): the free
/// boundary half-space of [`sweep_window`]. Contact maps are written unpacked (`u8` 0/1,
/// rows × cols), saturated maps likewise; no plastic displacement field is written.
fn compute_window(job: &ContactJob, inputs: &Inputs, dir: &Path) -> anyhow::Result<Value> {
    let results = &inputs.of(0, "surface")?.results;
    let pixel = |k: &str| {
        results[k]
            .as_f64()
            .ok_or_else(|| anyhow::anyhow!("the measured surface records no {k}"))
    };
    let path = inputs.file(0, "surface", "heights.npy")?;
    let read = crate::io::read_measured(&path)?;
    let map = Topography::new(
        read.rows,
        read.cols,
        pixel("pixel_size_x_m")?,
        pixel("pixel_size_y_m")?,
        read.heights,
    )?;
    let cfg = SolverConfig {
        tolerance: job.tolerance,
        max_iterations: job.max_iterations as usize,
        ..SolverConfig::default()
    };
    let (rows, cols) = (map.rows, map.cols);
    // As the window computes it, (𝓗·h'_rms)·E*, so that a saturated node's pressure equals
    // it to the bit.
    let ceiling = job
        .interface
        .hardness()
        .map(|h| (h * map.rms_slope()) * job.e_star);
    let bits = |on: &dyn Fn(f64) -> bool, p: &[f64]| -> Vec<u8> {
        p.iter().map(|&v| u8::from(on(v))).collect()
    };
    let (layout, loads) = sweep_window(
        &map,
        job.e_star,
        &job.loads,
        &cfg,
        job.interface,
        |index, pressure, _| {
            let write = |name: String, values: Vec<u8>| {
                crate::io::write_u8(&dir.join(name), &[rows, cols], values)
                    .map_err(|e| e.to_string())
            };
            write(contact_file(index), bits(&|p| p > 0.0, pressure))?;
            if let Some(c) = ceiling {
                write(saturated_file(index), bits(&|p| p >= c, pressure))?;
            }
            if job.keep_pressure.contains(&index) {
                crate::io::write_f64(
                    &dir.join(pressure_file(index)),
                    &[rows, cols],
                    pressure.to_vec(),
                )
                .map_err(|e| e.to_string())?;
            }
            Ok(())
        },
    )?;
    let results: Vec<LoadResult> = loads
        .into_iter()
        .map(|l| LoadResult {
            w_over_w0: l.w_over_w0,
            mean_pressure: l.mean_pressure,
            area_fraction: l.area_fraction,
            n_contact_px: l.n_contact_px,
            n_saturated_px: l.n_saturated_px,
            ceiling,
            report: l.report,
            seconds: l.seconds,
        })
        .collect();
    write(dir, "loads.parquet", loads_table(&results)?)?;
    Ok(json!({
        "rows": rows,
        "cols": cols,
        "rms_slope": layout.rms_slope,
        "half_space": "free boundary (zero-padded), the map's outside never in contact",
        "layout": layout,
        "total_iterations": results.iter().map(|r| r.report.iterations).sum::<usize>(),
        "solve_seconds": results.iter().map(|r| r.seconds).collect::<Vec<_>>(),
    }))
}

/// The plastic displacement of a solved field under the ceiling `ceiling` (docs/CONVENTIONS.md):
/// on the saturated nodes `ℓ − w ≥ 0`, with `w = K p − h` recomputed here by the operator and
/// `ℓ` its least value over the unsaturated nodes; 0 elsewhere. In the unit of the heights.
fn plastic_displacement(
    heights: &[f64],
    n: usize,
    e_star: f64,
    pressure: &[f64],
    ceiling: f64,
) -> anyhow::Result<Vec<f64>> {
    let op = ElasticOperator::new(Grid::unit(n)?, e_star);
    let mut w = vec![0.0; n * n];
    op.apply(pressure, &mut w, &mut op.make_workspace());
    for (w, h) in w.iter_mut().zip(heights) {
        *w -= h;
    }
    let level = pressure
        .iter()
        .zip(&w)
        .filter(|(&p, _)| p < ceiling)
        .fold(f64::INFINITY, |m, (_, &w)| m.min(w));
    let level = if level.is_finite() {
        level
    } else {
        w.iter().fold(f64::NEG_INFINITY, |m, &v| m.max(v))
    };
    Ok(pressure
        .iter()
        .zip(&w)
        .map(|(&p, &w)| {
            if p >= ceiling {
                (level - w).max(0.0)
            } else {
                0.0
            }
        })
        .collect())
}

fn loads_table(results: &[LoadResult]) -> PolarsResult<DataFrame> {
    let per = |f: &dyn Fn(&LoadResult) -> f64| results.iter().map(f).collect::<Vec<f64>>();
    let count = |f: &dyn Fn(&LoadResult) -> usize| {
        results.iter().map(|r| f(r) as u32).collect::<Vec<u32>>()
    };
    DataFrame::new(
        results.len(),
        [
            load_columns(&per(&|r| r.w_over_w0)).to_vec(),
            vec![
                col("mean_pressure", per(&|r| r.mean_pressure)),
                col("area_fraction", per(&|r| r.area_fraction)),
                col(
                    "n_contact_px",
                    results
                        .iter()
                        .map(|r| r.n_contact_px as u64)
                        .collect::<Vec<_>>(),
                ),
                col("iterations", count(&|r| r.report.iterations)),
                col("convolutions", count(&|r| r.report.convolutions)),
                col("error", per(&|r| r.report.error)),
                col(
                    "converged",
                    results
                        .iter()
                        .map(|r| r.report.converged())
                        .collect::<Vec<_>>(),
                ),
            ],
            // Under a hardness only (elastic tables keep their columns and bits): the
            // ceiling in the unit of E* and the saturated nodes.
            if results.iter().all(|r| r.ceiling.is_some()) && !results.is_empty() {
                vec![
                    col("hardness_pressure", per(&|r| r.ceiling.unwrap_or(f64::NAN))),
                    col(
                        "n_saturated_px",
                        results
                            .iter()
                            .map(|r| r.n_saturated_px.unwrap_or(0) as u64)
                            .collect::<Vec<_>>(),
                    ),
                ]
            } else {
                vec![]
            },
        ]
        .concat(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::solver::{Ceiling, Solver};

    /// The stored plastic displacement, recomputed from the pressure by the operator, equals
    /// the solver's own (from its separation) on a surface where a third of the contact
    /// saturates, to the solver's tolerance in units of the heights.
    #[test]
    fn plastic_displacement_matches_the_solver() {
        let n = 64;
        let heights: Vec<f64> = (0..n * n)
            .map(|i| {
                let (x, y) = ((i % n) as f64 / n as f64, (i / n) as f64 / n as f64);
                let tau = std::f64::consts::TAU;
                0.01 * ((tau * x).cos()
                    + 0.5 * (tau * 3.0 * y).sin()
                    + 0.3 * (tau * (5.0 * x + 2.0 * y)).cos())
            })
            .collect();
        let op = ElasticOperator::new(Grid::unit(n).unwrap(), 1.0);
        let ceiling = 0.02;
        let mut solver =
            Solver::with_constraint(&op, &heights, Ceiling::new(ceiling).unwrap()).unwrap();
        let cfg = SolverConfig {
            tolerance: 1e-12,
            ..SolverConfig::default()
        };
        assert!(solver.solve(0.004, &cfg).unwrap().converged());
        let saturated = solver.saturated_count();
        assert!(
            saturated > 0 && saturated < solver.contact_count(),
            "{saturated}"
        );
        let stored = plastic_displacement(&heights, n, 1.0, solver.pressure(), ceiling).unwrap();
        let own: Vec<f64> = solver.plastic_displacement().collect();
        let largest = own.iter().fold(0.0f64, |m, &d| m.max(d));
        assert!(largest > 0.0);
        for (i, (a, b)) in stored.iter().zip(&own).enumerate() {
            assert!((a - b).abs() <= 1e-9 * largest, "node {i}: {a} vs {b}");
        }
    }
}
