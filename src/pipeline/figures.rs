//! The figures stage: each paper figure drawn from stored artifacts as PNG and SVG, with
//! the plotted data as CSV beside it. A run copies the figures of its profile to
//! `figures/<profile>/` next to the data directory.

use std::path::Path;

use polars::prelude::*;
use serde_json::{json, Value};

use super::plot::{
    viridis, ColorBar, Layout, LegendAt, LinePlot, Panels, RasterPlot, Series, YAxis,
};
use super::stages::{FigureJob, StudyRef};
use super::store::Store;
use crate::clusters::{label, Connectivity};

fn read_table(store: &Store, stage: &str, key: &str, file: &str) -> anyhow::Result<DataFrame> {
    let manifest = store
        .lookup(stage, key)?
        .ok_or_else(|| anyhow::anyhow!("input {stage} {key} is missing from the store"))?;
    let path = store.read_output(&manifest, file)?;
    Ok(ParquetReader::new(std::fs::File::open(&path)?).finish()?)
}

fn f64_column(df: &DataFrame, name: &str) -> anyhow::Result<Vec<f64>> {
    Ok(df
        .column(name)?
        .f64()?
        .iter()
        .map(|v| v.unwrap_or(f64::NAN))
        .collect())
}

fn u32_column(df: &DataFrame, name: &str) -> anyhow::Result<Vec<Option<u32>>> {
    Ok(df.column(name)?.u32()?.iter().collect())
}

fn str_column(df: &DataFrame, name: &str) -> anyhow::Result<Vec<String>> {
    Ok(df
        .column(name)?
        .str()?
        .iter()
        .map(|v| v.unwrap_or("").to_string())
        .collect())
}

/// Distinct loads `(load_index, W/W0)` of a statistics table, in order.
fn loads_of(df: &DataFrame) -> anyhow::Result<Vec<(u32, f64)>> {
    let idx = u32_column(df, "load_index")?;
    let w = f64_column(df, "w_over_w0")?;
    let mut out: Vec<(u32, f64)> = Vec::new();
    for (i, w) in idx.into_iter().zip(w) {
        let i = i.unwrap_or(u32::MAX);
        if !out.iter().any(|(j, _)| *j == i) {
            out.push((i, w));
        }
    }
    Ok(out)
}

/// The loads of a sweep nearest to `targets` (deduplicated, increasing).
fn pick_loads(loads: &[(u32, f64)], targets: &[f64]) -> Vec<(u32, f64)> {
    let w: Vec<f64> = loads.iter().map(|l| l.1).collect();
    let mut out: Vec<(u32, f64)> = targets
        .iter()
        .filter_map(|&t| crate::statistics::nearest_in_log(&w, t).map(|i| loads[i]))
        .collect();
    out.sort_by(|a, b| a.1.total_cmp(&b.1));
    out.dedup_by_key(|l| l.0);
    out
}

/// Rows of `df` at load `load_index`.
fn rows_at(df: &DataFrame, load_index: u32) -> anyhow::Result<Vec<usize>> {
    Ok(u32_column(df, "load_index")?
        .into_iter()
        .enumerate()
        .filter(|(_, v)| *v == Some(load_index))
        .map(|(i, _)| i)
        .collect())
}

/// The columns of a statistics stage `ccdf.parquet` that figures draw, read once.
struct CcdfTable {
    load_index: Vec<Option<u32>>,
    w_over_w0: Vec<f64>,
    realization: Vec<Option<u32>>,
    area_over_ls2: Vec<f64>,
    ccdf: Vec<f64>,
    ccdf_mean: Vec<f64>,
}

impl CcdfTable {
    fn read(store: &Store, statistics_key: &str) -> anyhow::Result<Self> {
        let df = read_table(store, "statistics", statistics_key, "ccdf.parquet")?;
        Ok(CcdfTable {
            load_index: u32_column(&df, "load_index")?,
            w_over_w0: f64_column(&df, "w_over_w0")?,
            realization: u32_column(&df, "realization")?,
            area_over_ls2: f64_column(&df, "area_over_ls2")?,
            ccdf: f64_column(&df, "ccdf")?,
            ccdf_mean: f64_column(&df, "ccdf_mean")?,
        })
    }

    /// `(A/λ_s², P(A > a))` at load `load_index` of one realization, or of the pooled
    /// ensemble (`None`), or the ensemble mean of the realizations' CCDFs (`mean`).
    fn curve(&self, load_index: u32, realization: Option<u32>, mean: bool) -> Vec<(f64, f64)> {
        let v = if mean { &self.ccdf_mean } else { &self.ccdf };
        (0..v.len())
            .filter(|&i| {
                self.load_index[i] == Some(load_index) && self.realization[i] == realization
            })
            .map(|i| (self.area_over_ls2[i], v[i]))
            .collect()
    }

    /// Distinct loads `(load_index, W/W0)`, in order.
    fn loads(&self) -> Vec<(u32, f64)> {
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
    fn realizations(&self) -> Vec<u32> {
        let mut r: Vec<u32> = self.realization.iter().flatten().copied().collect();
        r.sort_unstable();
        r.dedup();
        r
    }
}

/// Something a figures instance writes.
enum Drawn {
    Line(LinePlot),
    Panels(Panels),
    /// A raster and the plotted array as `.npy` (shape, values).
    Raster(RasterPlot, NpyData),
    /// A table written as `<stem>.parquet`.
    Table(DataFrame),
    /// A value recorded under `<stem>` in the manifest's results.
    Result(Value),
}

enum NpyData {
    F64(Vec<usize>, Vec<f64>),
    U8(Vec<usize>, Vec<u8>),
}

/// Draw one figure into `dir`.
pub(super) fn compute_figure(job: &FigureJob, dir: &Path, store: &Store) -> anyhow::Result<Value> {
    let stats = |key: &str, file: &str| read_table(store, "statistics", key, file);
    let drawn: Vec<(String, Drawn)> = match job {
        FigureJob::Fig6 { analytic_key } => fig6(&read_table(
            store,
            "analytic",
            analytic_key,
            "fig6.parquet",
        )?)?,
        FigureJob::Fig2ef {
            statistics_key,
            marked_loads,
            ..
        } => {
            let mut out = fig2ef(&stats(statistics_key, "loads.parquet")?, marked_loads)?;
            out.extend(fig2_convergence(store, statistics_key)?);
            out
        }
        FigureJob::Fig2Maps {
            surface_key,
            contact_key,
            maps,
            lambda_s_px,
        } => fig2_maps(store, surface_key, contact_key, maps, *lambda_s_px)?,
        FigureJob::Fig45 {
            statistics_key,
            analytic_key,
        } => fig45(
            &stats(statistics_key, "wear.parquet")?,
            &read_table(store, "analytic", analytic_key, "model.parquet")?,
        )?,
        FigureJob::Fig34a { ratios, hurst } => fig34a(store, ratios, hurst)?,
        FigureJob::Appendix { figure, settings } => appendix(store, figure, settings)?,
        FigureJob::Convergence128 {
            name,
            hurst,
            settings,
        } => fig128_convergence(store, name, *hurst, settings)?,
        FigureJob::LoadResolution {
            fine_statistics_key,
            chosen_statistics_key,
        } => fig45_load_resolution(
            &stats(fine_statistics_key, "wear.parquet")?,
            &stats(chosen_statistics_key, "wear.parquet")?,
        )?,
    };
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

/// Fig. 6: K_PL and 𝒦_PL against A_m/A_s for α = 1.5 and several A*/A_s.
fn fig6(df: &DataFrame) -> anyhow::Result<Vec<(String, Drawn)>> {
    let s = f64_column(df, "a_star_over_a_s")?;
    let m = f64_column(df, "a_m_over_a_s")?;
    let k = f64_column(df, "k_pl")?;
    let kk = f64_column(df, "k_upscaled_pl")?;
    let alpha = f64_column(df, "alpha")?
        .first()
        .copied()
        .unwrap_or(f64::NAN);
    let mut thresholds: Vec<f64> = s.clone();
    thresholds.dedup();
    let mut plot = LinePlot::new(
        format!("Fig. 6: power-law model, α = {alpha}"),
        "A_m / A_s",
        "K_PL (solid), up-scaled K_PL (dashed)",
        true,
        YAxis::Linear,
    );
    for (name, values, dashed) in [("K_PL", &k, false), ("up-scaled K_PL", &kk, true)] {
        for (c, &t) in thresholds.iter().enumerate() {
            let points: Vec<(f64, f64)> = (0..s.len())
                .filter(|&i| s[i] == t && m[i].is_finite() && m[i] >= t)
                .map(|i| (m[i], values[i]))
                .collect();
            plot.series.push(Series {
                dashed,
                ..Series::line(format!("{name}, A*/A_s = {t}"), points, c)
            });
        }
    }
    Ok(vec![("fig6".into(), Drawn::Line(plot))])
}

/// Fig. 2e (A_c and the largest cluster) and 2f (dN/dA_c) against W/W0; the loads of the
/// contact maps (Fig. 2b–d) marked by dashed lines.
fn fig2ef(df: &DataFrame, marked_loads: &[f64]) -> anyhow::Result<Vec<(String, Drawn)>> {
    let w = f64_column(df, "w_over_w0")?;
    let ac = f64_column(df, "area_fraction_mean")?;
    let largest = f64_column(df, "largest_area_over_ls2_mean")?;
    let dn = f64_column(df, "dn_dac_per_ls2")?;
    let mut e = LinePlot::new(
        "Fig. 2e: contact area and largest cluster",
        "W / W0",
        "A_c / L²  and  largest A / λ_s²",
        true,
        YAxis::Log,
    );
    e.legend = LegendAt::LowerRight;
    e.x_marks = marked_loads.to_vec();
    e.series = vec![
        Series::line(
            "A_c / L² (ensemble mean)",
            w.iter().copied().zip(ac).collect(),
            0,
        ),
        Series::line(
            "largest cluster A / λ_s² (ensemble mean)",
            w.iter().copied().zip(largest).collect(),
            1,
        ),
    ];
    let mut f = LinePlot::new(
        "Fig. 2f: growth of the cluster count",
        "W / W0",
        "dN / d(A_c/λ_s²)",
        true,
        YAxis::Linear,
    );
    f.x_marks = marked_loads.to_vec();
    f.series = vec![
        Series::line(
            "dN/dA_c (central differences of ensemble means)",
            w.iter().copied().zip(dn).collect(),
            0,
        ),
        Series {
            rgb: Some((0, 0, 0)),
            width: 1,
            ..Series::line("", vec![(w[0], 0.0), (w[w.len() - 1], 0.0)], 0)
        },
    ];
    Ok(vec![
        ("fig2e".into(), Drawn::Line(e)),
        ("fig2f".into(), Drawn::Line(f)),
    ])
}

/// Per realization and load, the quantities behind Fig. 2e–f: contact area `A_c/λ_s²`,
/// cluster count `N` and largest cluster `A/λ_s²`, all clusters counted (percolating ones
/// included), as in the statistics stage's `loads.parquet`. Returns `[realization][load]`
/// and the loads.
type StudyCurves = (Vec<Vec<[f64; 3]>>, Vec<(u32, f64)>);

fn study_curves(store: &Store, statistics_key: &str) -> anyhow::Result<StudyCurves> {
    let manifest = store
        .lookup("statistics", statistics_key)?
        .ok_or_else(|| anyhow::anyhow!("input statistics {statistics_key} is missing"))?;
    let loads = loads_of(&read_table(
        store,
        "statistics",
        statistics_key,
        "loads.parquet",
    )?)?;
    let mut out = Vec::new();
    for key in &manifest.inputs {
        let df = read_table(store, "clusters", key, "clusters.parquet")?;
        let idx = u32_column(&df, "load_index")?;
        let area = f64_column(&df, "area_over_ls2")?;
        let mut per_load = vec![[0.0f64; 3]; loads.len()];
        for (i, a) in area.iter().enumerate() {
            if let Some(l) = loads.iter().position(|l| Some(l.0) == idx[i]) {
                let v = &mut per_load[l];
                v[0] += a;
                v[1] += 1.0;
                v[2] = v[2].max(*a);
            }
        }
        out.push(per_load);
    }
    Ok((out, loads))
}

/// Largest relative deviation (over loads) of the ensemble-mean curves of Fig. 2e–f over the
/// first `r` realizations from the means over all of them, below which `r` realizations
/// count as enough (the same 5 % as the Appendix B rule's KS tolerance).
pub const FIG2_CURVE_TOLERANCE: f64 = 0.05;
/// Largest shift, in load steps, of the load where the mean cluster count peaks (where
/// dN/dA_c of Fig. 2f changes sign) from the full ensemble's.
pub const FIG2_PEAK_TOLERANCE_STEPS: usize = 1;

/// One row of the Fig. 2 realization-convergence table (first `r` realizations).
struct Fig2ConvergenceRow {
    realizations: u32,
    /// Per quantity (A_c, N, largest): largest relative deviation over loads of the mean of
    /// the first `r` realizations from the mean of all.
    deviation: [f64; 3],
    /// Per quantity: largest relative half-width over loads of the 95 % band of the mean of
    /// the first `r` realizations (Student t).
    band: [f64; 3],
    /// Position in the loads and W/W0 where the mean cluster count of the first `r`
    /// realizations peaks.
    peak_index: usize,
    peak_w: f64,
}

/// Realization convergence of Fig. 2e–f: per `r = 2 … R`, the deviations of the first-`r`
/// mean curves from the full ensemble's, their 95 % bands and the load where the mean cluster
/// count peaks. Drawn as `fig2_convergence` (table `.parquet`, chart) with the rule's result
/// in the manifest.
fn fig2_convergence(store: &Store, statistics_key: &str) -> anyhow::Result<Vec<(String, Drawn)>> {
    let (curves, loads) = study_curves(store, statistics_key)?;
    let total = curves.len();
    if total < 2 || loads.is_empty() {
        return Ok(vec![(
            "convergence".into(),
            Drawn::Result(json!({ "note": "fewer than 2 realizations: no convergence curve" })),
        )]);
    }
    let means = |r: usize| -> Vec<[(f64, f64); 3]> {
        (0..loads.len())
            .map(|l| {
                let band = |q: usize| {
                    let v: Vec<f64> = curves[..r].iter().map(|c| c[l][q]).collect();
                    let (m, _, half) = crate::statistics::mean_band(&v);
                    (m, half)
                };
                [band(0), band(1), band(2)]
            })
            .collect()
    };
    let peak = |m: &[[(f64, f64); 3]]| {
        (0..m.len())
            .max_by(|&a, &b| m[a][1].0.total_cmp(&m[b][1].0).then(b.cmp(&a)))
            .unwrap_or(0)
    };
    let all = means(total);
    let all_peak = peak(&all);
    let mut rows = Vec::new();
    for r in 2..=total {
        let m = means(r);
        let mut deviation = [0.0f64; 3];
        let mut band = [0.0f64; 3];
        for (l, ml) in m.iter().enumerate() {
            for q in 0..3 {
                let reference = all[l][q].0;
                if reference > 0.0 {
                    deviation[q] = deviation[q].max((ml[q].0 - reference).abs() / reference);
                }
                if ml[q].0 > 0.0 && ml[q].1.is_finite() {
                    band[q] = band[q].max(ml[q].1 / ml[q].0);
                }
            }
        }
        let p = peak(&m);
        rows.push(Fig2ConvergenceRow {
            realizations: r as u32,
            deviation,
            band,
            peak_index: p,
            peak_w: loads[p].1,
        });
    }
    let ok = |row: &Fig2ConvergenceRow| {
        row.deviation.iter().all(|&d| d <= FIG2_CURVE_TOLERANCE)
            && row.peak_index.abs_diff(all_peak) <= FIG2_PEAK_TOLERANCE_STEPS
    };
    // The smallest r from which every larger count also meets the rule.
    let chosen = (0..rows.len())
        .find(|&i| rows[i..].iter().all(ok))
        .map(|i| rows[i].realizations);
    let names = ["area", "count", "largest"];
    let f64_col = |name: String, f: &dyn Fn(&Fig2ConvergenceRow) -> f64| {
        Column::new(name.into(), rows.iter().map(f).collect::<Vec<f64>>())
    };
    let mut columns = vec![Column::new(
        "realizations".into(),
        rows.iter().map(|x| x.realizations).collect::<Vec<u32>>(),
    )];
    for (q, name) in names.iter().enumerate() {
        columns.push(f64_col(format!("{name}_max_rel_deviation"), &|x| {
            x.deviation[q]
        }));
    }
    for (q, name) in names.iter().enumerate() {
        columns.push(f64_col(format!("{name}_max_rel_ci95"), &|x| x.band[q]));
    }
    columns.push(Column::new(
        "count_peak_load_index".into(),
        rows.iter()
            .map(|x| loads[x.peak_index].0)
            .collect::<Vec<u32>>(),
    ));
    columns.push(f64_col("count_peak_w_over_w0".into(), &|x| x.peak_w));
    let table = DataFrame::new(rows.len(), columns)?;

    let mut plot = LinePlot::new(
        "Fig. 2e–f: first r realizations vs all",
        "realizations r",
        "max relative deviation of the mean over loads",
        false,
        YAxis::Log,
    );
    plot.legend = LegendAt::UpperRight;
    plot.x_integer = true;
    let labels = [
        "A_c (Fig. 2e)",
        "largest cluster (Fig. 2e)",
        "N (Fig. 2f: dN/dA_c)",
    ];
    for (c, (q, label)) in [0usize, 2, 1].iter().zip(labels).enumerate() {
        plot.series.push(Series::line(
            label,
            rows.iter()
                .filter(|x| x.deviation[*q] > 0.0)
                .map(|x| (x.realizations as f64, x.deviation[*q]))
                .collect(),
            c,
        ));
    }
    plot.series.push(Series {
        width: 1,
        ..tolerance_line(FIG2_CURVE_TOLERANCE, 2.0, total as f64)
    });
    let last = rows.last().expect("at least one row");
    let result = json!({
        "tolerance_rel_deviation": FIG2_CURVE_TOLERANCE,
        "tolerance_peak_load_steps": FIG2_PEAK_TOLERANCE_STEPS,
        "realizations": total,
        "smallest_converged_realizations": chosen,
        "count_peak_w_over_w0": loads[all_peak].1,
        "max_rel_ci95_at_all_realizations": {
            "area": last.band[0],
            "count": last.band[1],
            "largest": last.band[2],
        },
    });
    Ok(vec![
        ("fig2_convergence".into(), Drawn::Table(table)),
        ("fig2_convergence".into(), Drawn::Line(plot)),
        ("convergence".into(), Drawn::Result(result)),
    ])
}

/// Colours of the contact maps of Fig. 2b–d.
const OUT_OF_CONTACT: (u8, u8, u8) = (0, 0, 0);
const SMALL_CLUSTER: (u8, u8, u8) = (255, 215, 0);
const LARGE_CLUSTER: (u8, u8, u8) = (220, 30, 30);
/// The threshold of Fig. 2: `A* = 2 λ_s²`.
pub const FIG2_A_STAR_OVER_LS2: f64 = 2.0;

/// Fig. 2a (the surface of realization 0) and 2b–d (its contact maps at the kept loads,
/// clusters with `A ≤ A*` yellow and `A > A*` red on black).
fn fig2_maps(
    store: &Store,
    surface_key: &str,
    contact_key: &str,
    maps: &[(usize, f64)],
    lambda_s_px: f64,
) -> anyhow::Result<Vec<(String, Drawn)>> {
    let manifest = store
        .lookup("surface", surface_key)?
        .ok_or_else(|| anyhow::anyhow!("input surface {surface_key} is missing from the store"))?;
    let (n, heights) = crate::io::read_square_f64(&store.read_output(&manifest, "heights.npy")?)?;
    let (lo, hi) = heights
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let span = if hi > lo { hi - lo } else { 1.0 };
    let rgb: Vec<u8> = heights
        .iter()
        .flat_map(|&h| {
            let (r, g, b) = viridis((h - lo) / span);
            [r, g, b]
        })
        .collect();
    let mut out = vec![(
        "fig2a".to_string(),
        Drawn::Raster(
            RasterPlot {
                title: "Fig. 2a: rough surface (realization 0)".into(),
                x_label: "x / L".into(),
                y_label: "y / L".into(),
                rows: n,
                cols: n,
                rgb,
                colorbar: Some(ColorBar {
                    lo,
                    hi,
                    label: "height h / L (rms slope 1)".into(),
                }),
                legend: Vec::new(),
            },
            NpyData::F64(vec![n, n], heights),
        ),
    )];
    let manifest = store
        .lookup("contact", contact_key)?
        .ok_or_else(|| anyhow::anyhow!("input contact {contact_key} is missing from the store"))?;
    let a_star_px = FIG2_A_STAR_OVER_LS2 * lambda_s_px * lambda_s_px;
    for (panel, &(index, w)) in ["b", "c", "d"].iter().zip(maps) {
        let path = store.read_output(&manifest, &super::stages::contact_file(index))?;
        let (rows, cols, map, _) = crate::io::read_contact_map(&path)?;
        let lab = label(&map, rows, cols, Connectivity::Eight)?;
        // 0: out of contact, 1: A ≤ A*, 2: A > A*.
        let class: Vec<u8> = lab
            .labels
            .iter()
            .map(|&id| match id {
                0 => 0,
                id if lab.clusters[id as usize - 1].area_px as f64 > a_star_px => 2,
                _ => 1,
            })
            .collect();
        let rgb = class
            .iter()
            .flat_map(|&c| {
                let (r, g, b) = [OUT_OF_CONTACT, SMALL_CLUSTER, LARGE_CLUSTER][c as usize];
                [r, g, b]
            })
            .collect();
        out.push((
            format!("fig2{panel}"),
            Drawn::Raster(
                RasterPlot {
                    title: format!("Fig. 2{panel}: contact clusters at W/W0 = {w:.3}"),
                    x_label: "x / L".into(),
                    y_label: "y / L".into(),
                    rows,
                    cols,
                    rgb,
                    colorbar: None,
                    legend: vec![
                        ("A ≤ A*".into(), Some(SMALL_CLUSTER)),
                        ("A > A*".into(), Some(LARGE_CLUSTER)),
                        ("out of contact".into(), Some(OUT_OF_CONTACT)),
                        ("A* = 2 λ_s²".into(), None),
                    ],
                },
                NpyData::U8(vec![rows, cols], class),
            ),
        ));
    }
    Ok(out)
}

/// Fits of Fig. 3 are drawn only over at least this many decades of area.
pub const MIN_FIT_DECADES: f64 = 1.0;
/// Loads drawn in Figs. 3 and 4a (nearest in each sweep).
const FIG3_LOADS: [f64; 3] = [0.005, 0.02, 0.06];
/// Load drawn in the inset of Fig. 3 (nearest in each sweep).
const FIG3_INSET_LOAD: f64 = 0.06;
/// Tints of the loads of one family, lightest for the smallest load.
const LOAD_TINTS: [f64; 3] = [0.6, 0.3, 0.0];

/// The pooled PDF of one study at one load: `(A/λ_s², p)` per bin with clusters.
fn pdf_points(pdf: &DataFrame, load_index: u32) -> anyhow::Result<(Vec<(f64, f64)>, u64)> {
    let rows = rows_at(pdf, load_index)?;
    let x = f64_column(pdf, "centre_over_ls2")?;
    let p = f64_column(pdf, "pdf_pooled")?;
    let count: Vec<u64> = pdf
        .column("count_pooled")?
        .u64()?
        .iter()
        .map(|v| v.unwrap_or(0))
        .collect();
    let total = rows.iter().map(|&i| count[i]).sum();
    Ok((
        rows.iter()
            .filter(|&&i| count[i] > 0)
            .map(|&i| (x[i], p[i]))
            .collect(),
        total,
    ))
}

/// Points of a fitted curve and its legend text.
type FittedLine = (Vec<(f64, f64)>, String);

/// The fitted discrete truncated power law at one load, drawn over its fitted range in the
/// units of the PDF (per λ_s², weighted by the fraction of clusters in the range), and its
/// legend text. `None` when there is no fit or when the fitted range spans less than
/// [`MIN_FIT_DECADES`] (the KS choice of `k_min` then sits in the cut-off, e.g. λ_l/λ_s = 8,
/// and its exponent is not that of the power-law interval).
fn fitted_power_law(
    alpha_table: &DataFrame,
    load_index: u32,
    clusters: u64,
    lambda_s_px: f64,
) -> anyhow::Result<Option<FittedLine>> {
    let est = str_column(alpha_table, "estimator")?;
    let alpha = f64_column(alpha_table, "alpha")?;
    let lo = f64_column(alpha_table, "bootstrap_ci95_low")?;
    let hi = f64_column(alpha_table, "bootstrap_ci95_high")?;
    let k_min = f64_column(alpha_table, "k_min_px")?;
    let k_max = f64_column(alpha_table, "k_max_px")?;
    let n_fit: Vec<u64> = alpha_table
        .column("n_fitted")?
        .u64()?
        .iter()
        .map(|v| v.unwrap_or(0))
        .collect();
    let Some(i) = rows_at(alpha_table, load_index)?
        .into_iter()
        .find(|&i| est[i] == crate::powerlaw::Estimator::DiscreteTruncated.name())
    else {
        return Ok(None);
    };
    let (a, k0, k1) = (alpha[i], k_min[i], k_max[i]);
    if !(a.is_finite() && k0 >= 1.0 && k1 >= k0 * 10f64.powf(MIN_FIT_DECADES)) || clusters == 0 {
        return Ok(None);
    }
    let (k0, k1) = (k0 as u64, k1 as u64);
    let z = crate::powerlaw::discrete_normalisation(a, k0, k1);
    let weight = n_fit[i] as f64 / clusters as f64;
    let ls2 = lambda_s_px * lambda_s_px;
    let steps = 40;
    let points = (0..=steps)
        .map(|j| {
            let k = k0 as f64 * (k1 as f64 / k0 as f64).powf(j as f64 / steps as f64);
            (k / ls2, weight * k.powf(-a) / z * ls2)
        })
        .collect();
    let text = format!("fitted α = {a:.2}, 95 % CI [{:.2}, {:.2}]", lo[i], hi[i]);
    Ok(Some((points, text)))
}

/// Fig. 3 (PDF of A/λ_s² for several λ_l/λ_s and loads, fitted power law; inset: H) and
/// Fig. 4a (CCDF for the same studies and loads).
fn fig34a(
    store: &Store,
    ratios: &[StudyRef],
    hurst: &[StudyRef],
) -> anyhow::Result<Vec<(String, Drawn)>> {
    let stats = |key: &str, file: &str| read_table(store, "statistics", key, file);
    let mut main = LinePlot::new(
        "Fig. 3: cluster-area PDF, H = 0.8",
        "A / λ_s²",
        "p(A / λ_s²)",
        true,
        YAxis::Log,
    );
    let mut ccdf_plot = LinePlot::new(
        "Fig. 4a: K(A*) = P(A > A*), H = 0.8",
        "A* / λ_s²",
        "P(A > A*)",
        true,
        YAxis::Log,
    );
    ccdf_plot.legend = LegendAt::LowerLeft;
    for (c, study) in ratios.iter().enumerate() {
        let pdf = stats(&study.statistics_key, "pdf.parquet")?;
        let alpha = stats(&study.statistics_key, "alpha.parquet")?;
        let ccdf = CcdfTable::read(store, &study.statistics_key)?;
        let picked = pick_loads(&loads_of(&pdf)?, &FIG3_LOADS);
        let load_list = picked
            .iter()
            .map(|l| format!("{:.3}", l.1))
            .collect::<Vec<_>>()
            .join(", ");
        for (j, &(load_index, _)) in picked.iter().enumerate() {
            let last = j + 1 == picked.len();
            let tint = LOAD_TINTS[LOAD_TINTS.len() - picked.len() + j];
            let (points, clusters) = pdf_points(&pdf, load_index)?;
            let label = if last {
                format!("{} (W/W0 = {load_list}, light → dark)", study.label)
            } else {
                String::new()
            };
            main.series.push(Series {
                tint,
                markers: true,
                width: 1,
                ..Series::line(label.clone(), points, c)
            });
            ccdf_plot.series.push(Series {
                tint,
                ..Series::line(label, ccdf.curve(load_index, None, false), c)
            });
            if last {
                if let Some((fit, text)) =
                    fitted_power_law(&alpha, load_index, clusters, study.lambda_s_px)?
                {
                    main.series.push(Series {
                        dashed: true,
                        rgb: Some((0, 0, 0)),
                        ..Series::line(format!("{} fit: {text}", study.label), fit, c)
                    });
                }
            }
        }
    }
    let mut out = Vec::new();
    if hurst.is_empty() {
        out.push(("fig3".to_string(), Drawn::Line(main)));
    } else {
        let mut inset = LinePlot::new("λ_l/λ_s = 128", "A / λ_s²", "p(A / λ_s²)", true, YAxis::Log);
        for (c, study) in hurst.iter().enumerate() {
            let pdf = stats(&study.statistics_key, "pdf.parquet")?;
            if let Some(&(load_index, w)) = pick_loads(&loads_of(&pdf)?, &[FIG3_INSET_LOAD]).first()
            {
                let (points, _) = pdf_points(&pdf, load_index)?;
                inset.series.push(Series {
                    markers: true,
                    width: 1,
                    ..Series::line(format!("{} (W/W0 = {w:.3})", study.label), points, c + 3)
                });
            }
        }
        out.push((
            "fig3".to_string(),
            Drawn::Panels(Panels {
                plots: vec![main, inset],
                layout: Layout::Inset {
                    rect: (0.12, 0.55, 0.38, 0.33),
                },
            }),
        ));
    }
    out.push(("fig4a".to_string(), Drawn::Line(ccdf_plot)));
    Ok(out)
}

/// Figs. B.1 and B.2: the CCDF of cluster areas per setting. B.1 (one panel per setting):
/// every realization in grey and the ensemble mean in red, per load; B.2 (one panel per
/// load): the ensemble mean of each setting.
fn appendix(
    store: &Store,
    figure: &str,
    settings: &[StudyRef],
) -> anyhow::Result<Vec<(String, Drawn)>> {
    let tables = settings
        .iter()
        .map(|s| CcdfTable::read(store, &s.statistics_key))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let mut plots = Vec::new();
    if figure == "figB1" {
        for (s, table) in settings.iter().zip(&tables) {
            let mut plot = LinePlot::new(
                format!("Fig. B.1: {}", s.label),
                "A / λ_s²",
                "P(A > a)",
                true,
                YAxis::Log,
            );
            plot.legend = LegendAt::LowerLeft;
            let loads = table.loads();
            for (j, &(load_index, _)) in loads.iter().enumerate() {
                for (r_i, &r) in table.realizations().iter().enumerate() {
                    let label = if j == 0 && r_i == 0 {
                        "each realization"
                    } else {
                        ""
                    };
                    plot.series.push(Series {
                        rgb: Some((170, 170, 170)),
                        width: 1,
                        ..Series::line(label, table.curve(load_index, Some(r), false), 0)
                    });
                }
            }
            for (j, &(load_index, w)) in loads.iter().enumerate() {
                plot.series.push(Series {
                    rgb: Some((214, 39, 40)),
                    tint: 0.5 * (loads.len() - 1 - j) as f64 / loads.len().max(2) as f64,
                    ..Series::line(
                        format!("ensemble mean, W/W0 = {w:.3}"),
                        table.curve(load_index, None, true),
                        3,
                    )
                });
            }
            plots.push(plot);
        }
    } else {
        let loads = tables.first().map(CcdfTable::loads).unwrap_or_default();
        for &(load_index, w) in &loads {
            let mut plot = LinePlot::new(
                format!("Fig. B.2: W/W0 = {w:.3}"),
                "A / λ_s²",
                "P(A > a), ensemble mean",
                true,
                YAxis::Log,
            );
            plot.legend = LegendAt::LowerLeft;
            for (c, (s, table)) in settings.iter().zip(&tables).enumerate() {
                plot.series.push(Series::line(
                    s.label.clone(),
                    table.curve(load_index, None, true),
                    c,
                ));
            }
            plots.push(plot);
        }
    }
    anyhow::ensure!(!plots.is_empty(), "{figure}: no setting to draw");
    let columns = plots.len().min(3);
    let mut out = vec![(
        figure.to_string(),
        Drawn::Panels(Panels {
            plots,
            layout: Layout::Grid { columns },
        }),
    )];
    let table = convergence_table(store, settings)?;
    out.push((
        format!("{figure}_convergence"),
        Drawn::Panels(convergence_plots(figure, settings, &table)),
    ));
    out.push((
        format!("{figure}_convergence"),
        Drawn::Table(table.frame()?),
    ));
    out.push(("convergence".into(), Drawn::Result(table.choice())));
    Ok(out)
}

/// Largest KS distance to the reference (over loads) below which a setting, or a number of
/// realizations, counts as converged (Appendix B studies; README "Model no more than a scene
/// needs").
pub const CONVERGENCE_KS_TOLERANCE: f64 = 0.05;
/// Exponent compared between settings: the plateau + power-law fit over the whole
/// distribution (the free-`x_min` tail fit of λ_l/λ_s = 8 surfaces lands in the cut-off).
const CONVERGENCE_ESTIMATOR: crate::powerlaw::Estimator =
    crate::powerlaw::Estimator::DiscretePlateauPowerLaw;

/// Cluster areas (A/λ_s², percolating clusters left out as in the statistics stage) of one
/// study: `[realization][load]`, and the loads `(load_index, W/W0)`.
type StudyAreas = (Vec<Vec<Vec<f64>>>, Vec<(u32, f64)>);

fn study_areas(store: &Store, statistics_key: &str) -> anyhow::Result<StudyAreas> {
    let manifest = store
        .lookup("statistics", statistics_key)?
        .ok_or_else(|| anyhow::anyhow!("input statistics {statistics_key} is missing"))?;
    let loads = loads_of(&read_table(
        store,
        "statistics",
        statistics_key,
        "loads.parquet",
    )?)?;
    let mut out = Vec::new();
    for key in &manifest.inputs {
        let df = read_table(store, "clusters", key, "clusters.parquet")?;
        let idx = u32_column(&df, "load_index")?;
        let area = f64_column(&df, "area_over_ls2")?;
        let perc: Vec<bool> = df
            .column("percolating")?
            .bool()?
            .iter()
            .map(|v| v.unwrap_or(false))
            .collect();
        let mut per_load = vec![Vec::new(); loads.len()];
        for i in 0..area.len() {
            if perc[i] {
                continue;
            }
            if let Some(l) = loads.iter().position(|l| Some(l.0) == idx[i]) {
                per_load[l].push(area[i]);
            }
        }
        out.push(per_load);
    }
    Ok((out, loads))
}

/// One row of the convergence table.
struct ConvergenceRow {
    kind: &'static str,
    study: String,
    setting: f64,
    realizations: u32,
    load_index: u32,
    w_over_w0: f64,
    n_clusters: u64,
    n_reference: u64,
    ks: f64,
    critical: f64,
    alpha: Option<f64>,
    alpha_reference: Option<f64>,
}

struct ConvergenceTable {
    rows: Vec<ConvergenceRow>,
}

impl ConvergenceTable {
    fn frame(&self) -> anyhow::Result<DataFrame> {
        let r = &self.rows;
        let col_f = |name: &str, f: &dyn Fn(&ConvergenceRow) -> f64| {
            Column::new(name.into(), r.iter().map(f).collect::<Vec<f64>>())
        };
        let col_o = |name: &str, f: &dyn Fn(&ConvergenceRow) -> Option<f64>| {
            Column::new(name.into(), r.iter().map(f).collect::<Vec<Option<f64>>>())
        };
        Ok(DataFrame::new(
            r.len(),
            vec![
                Column::new("kind".into(), r.iter().map(|x| x.kind).collect::<Vec<_>>()),
                Column::new(
                    "study".into(),
                    r.iter().map(|x| x.study.as_str()).collect::<Vec<_>>(),
                ),
                col_f("setting", &|x| x.setting),
                Column::new(
                    "realizations".into(),
                    r.iter().map(|x| x.realizations).collect::<Vec<u32>>(),
                ),
                Column::new(
                    "load_index".into(),
                    r.iter().map(|x| x.load_index).collect::<Vec<u32>>(),
                ),
                col_f("w_over_w0", &|x| x.w_over_w0),
                Column::new(
                    "n_clusters".into(),
                    r.iter().map(|x| x.n_clusters).collect::<Vec<u64>>(),
                ),
                Column::new(
                    "n_clusters_reference".into(),
                    r.iter().map(|x| x.n_reference).collect::<Vec<u64>>(),
                ),
                col_f("ks_distance", &|x| x.ks),
                col_f("ks_critical_95", &|x| x.critical),
                col_o("alpha", &|x| x.alpha),
                col_o("alpha_reference", &|x| x.alpha_reference),
                col_o(
                    "alpha_difference",
                    &|x| match (x.alpha, x.alpha_reference) {
                        (Some(a), Some(b)) => Some(a - b),
                        _ => None,
                    },
                ),
                Column::new(
                    "alpha_estimator".into(),
                    vec![CONVERGENCE_ESTIMATOR.name(); r.len()],
                ),
            ],
        )?)
    }

    /// The smallest setting whose KS distance to the finest is within the tolerance at every
    /// load, and per setting the smallest number of realizations whose pooled ensemble is
    /// within the tolerance of the full one at every load.
    /// Largest KS distance over loads of the rows of `kind`, per abscissa `pick(row)` (rows
    /// where it is `None` left out), in increasing abscissa.
    fn max_ks(&self, kind: &str, pick: &dyn Fn(&ConvergenceRow) -> Option<f64>) -> Vec<(f64, f64)> {
        let mut m: Vec<(f64, f64)> = Vec::new();
        for r in self.rows.iter().filter(|r| r.kind == kind) {
            let Some(x) = pick(r) else { continue };
            match m.iter_mut().find(|e| e.0 == x) {
                Some(e) => e.1 = e.1.max(r.ks),
                None => m.push((x, r.ks)),
            }
        }
        m.sort_by(|a, b| a.0.total_cmp(&b.0));
        m
    }

    /// The realization curve of one setting: largest KS over loads against `r`.
    fn max_ks_by_realizations(&self, setting: f64) -> Vec<(f64, f64)> {
        self.max_ks("realizations", &|r| {
            (r.setting == setting).then_some(r.realizations as f64)
        })
    }

    fn choice(&self) -> Value {
        let settings = self.max_ks("setting", &|r| Some(r.setting));
        // The smallest value from which every larger one is within the tolerance.
        let first_converged = |curve: &[(f64, f64)]| {
            (0..curve.len())
                .find(|&i| curve[i..].iter().all(|e| e.1 <= CONVERGENCE_KS_TOLERANCE))
                .map(|i| curve[i].0)
        };
        let chosen_setting = first_converged(&settings);
        let mut per_setting = serde_json::Map::new();
        let mut values: Vec<f64> = settings.iter().map(|e| e.0).collect();
        values.dedup();
        for s in values {
            let chosen = first_converged(&self.max_ks_by_realizations(s)).map(|r| r as u32);
            per_setting.insert(format!("{s}"), json!(chosen));
        }
        json!({
            "tolerance": CONVERGENCE_KS_TOLERANCE,
            "alpha_estimator": CONVERGENCE_ESTIMATOR.name(),
            "max_ks_by_setting": settings,
            "smallest_converged_setting": chosen_setting,
            "smallest_converged_realizations_by_setting": per_setting,
        })
    }
}

/// KS distance and exponent difference of each setting to the finest (last) setting per load,
/// and of the first `r` realizations of each setting to all of them.
fn convergence_table(store: &Store, settings: &[StudyRef]) -> anyhow::Result<ConvergenceTable> {
    let mut data = Vec::new();
    for s in settings {
        let (areas, loads) = study_areas(store, &s.statistics_key)?;
        let alpha = read_table(store, "statistics", &s.statistics_key, "alpha.parquet")?;
        let est = str_column(&alpha, "estimator")?;
        let a = f64_column(&alpha, "alpha")?;
        let idx = u32_column(&alpha, "load_index")?;
        let alpha_at = |l: u32| {
            (0..a.len())
                .find(|&i| idx[i] == Some(l) && est[i] == CONVERGENCE_ESTIMATOR.name())
                .map(|i| a[i])
                .filter(|v| v.is_finite())
        };
        let alphas: Vec<Option<f64>> = loads.iter().map(|l| alpha_at(l.0)).collect();
        data.push((areas, loads, alphas));
    }
    let pooled = |areas: &[Vec<Vec<f64>>], r: usize, l: usize| -> Vec<f64> {
        areas[..r]
            .iter()
            .flat_map(|x| x[l].iter().copied())
            .collect()
    };
    let mut rows = Vec::new();
    let Some((ref_areas, ref_loads, ref_alpha)) = data.last() else {
        return Ok(ConvergenceTable { rows });
    };
    for (s, (areas, loads, alphas)) in settings.iter().zip(&data) {
        let setting = s.value;
        for (l, &(load_index, w)) in loads.iter().enumerate() {
            let all = pooled(areas, areas.len(), l);
            if let Some(rl) = ref_loads.iter().position(|x| (x.1 - w).abs() <= 1e-12 * w) {
                let reference = pooled(ref_areas, ref_areas.len(), rl);
                rows.push(ConvergenceRow {
                    kind: "setting",
                    study: s.label.clone(),
                    setting,
                    realizations: areas.len() as u32,
                    load_index,
                    w_over_w0: w,
                    n_clusters: all.len() as u64,
                    n_reference: reference.len() as u64,
                    ks: crate::statistics::ks_two_sample(&all, &reference),
                    critical: crate::statistics::ks_critical_95(all.len(), reference.len()),
                    alpha: alphas[l],
                    alpha_reference: ref_alpha[rl],
                });
            }
            for r in 1..=areas.len() {
                let part = pooled(areas, r, l);
                rows.push(ConvergenceRow {
                    kind: "realizations",
                    study: s.label.clone(),
                    setting,
                    realizations: r as u32,
                    load_index,
                    w_over_w0: w,
                    n_clusters: part.len() as u64,
                    n_reference: all.len() as u64,
                    ks: crate::statistics::ks_two_sample(&part, &all),
                    critical: crate::statistics::ks_critical_95(part.len(), all.len()),
                    alpha: None,
                    alpha_reference: None,
                });
            }
        }
    }
    Ok(ConvergenceTable { rows })
}

/// The black dashed horizontal line of a tolerance, from `x0` to `x1`, labelled with its value.
fn tolerance_line(tolerance: f64, x0: f64, x1: f64) -> Series {
    Series {
        rgb: Some((0, 0, 0)),
        dashed: true,
        ..Series::line(
            format!("tolerance {tolerance}"),
            vec![(x0, tolerance), (x1, tolerance)],
            0,
        )
    }
}

/// One curve of a convergence figure: KS distance (markers) and its 95 % critical value
/// (dashed, labelled `critical_label`) on `ks`, exponent difference on `da`, against `x(row)`.
fn push_convergence_curves(
    ks: &mut LinePlot,
    da: &mut LinePlot,
    label: &str,
    critical_label: &str,
    rows: &[&ConvergenceRow],
    x: impl Fn(&ConvergenceRow) -> f64,
    color: usize,
) {
    ks.series.push(Series {
        markers: true,
        ..Series::line(label, rows.iter().map(|r| (x(r), r.ks)).collect(), color)
    });
    ks.series.push(Series {
        dashed: true,
        width: 1,
        // A single point of a dashed line would not show.
        markers: rows.len() == 1,
        ..Series::line(
            critical_label,
            rows.iter().map(|r| (x(r), r.critical)).collect(),
            color,
        )
    });
    da.series.push(Series {
        markers: true,
        ..Series::line(
            label,
            rows.iter()
                .filter_map(|r| Some((x(r), r.alpha? - r.alpha_reference?)))
                .collect(),
            color,
        )
    });
}

/// The convergence figure: KS distance and exponent difference to the finest setting against
/// the setting (one curve per load), and KS distance of `r` realizations to all of them.
fn convergence_plots(figure: &str, settings: &[StudyRef], table: &ConvergenceTable) -> Panels {
    let name = if figure == "figB1" {
        "L/λ_l"
    } else {
        "λ_s/Δl"
    };
    let mut ks = LinePlot::new(
        format!("{figure}: KS distance to the finest"),
        name,
        "KS distance",
        false,
        YAxis::Linear,
    );
    let mut da = LinePlot::new(
        format!("{figure}: α − α(finest)"),
        name,
        "α − α(finest), plateau + power-law MLE",
        false,
        YAxis::Linear,
    );
    let mut real = LinePlot::new(
        format!("{figure}: first r realizations vs all"),
        "realizations r",
        "max KS distance over loads",
        false,
        YAxis::Linear,
    );
    real.x_integer = true;
    let mut loads: Vec<(u32, f64)> = table
        .rows
        .iter()
        .filter(|r| r.kind == "setting")
        .map(|r| (r.load_index, r.w_over_w0))
        .collect();
    loads.sort_by(|a, b| a.1.total_cmp(&b.1));
    loads.dedup_by(|a, b| a.1 == b.1);
    for (c, &(_, w)) in loads.iter().enumerate() {
        let rows: Vec<&ConvergenceRow> = table
            .rows
            .iter()
            .filter(|r| r.kind == "setting" && r.w_over_w0 == w)
            .collect();
        let critical = if c == 0 { "95 % critical value" } else { "" };
        let label = format!("W/W0 = {w:.3}");
        push_convergence_curves(&mut ks, &mut da, &label, critical, &rows, |r| r.setting, c);
    }
    if let (Some(lo), Some(hi)) = (settings.first(), settings.last()) {
        ks.series
            .push(tolerance_line(CONVERGENCE_KS_TOLERANCE, lo.value, hi.value));
    }
    for (c, s) in settings.iter().enumerate() {
        let by_r = table.max_ks_by_realizations(s.value);
        real.series.push(Series {
            markers: true,
            ..Series::line(s.label.clone(), by_r, c + 4)
        });
    }
    let most_realizations = table
        .rows
        .iter()
        .map(|r| r.realizations as f64)
        .fold(1.0, f64::max);
    real.series.push(tolerance_line(
        CONVERGENCE_KS_TOLERANCE,
        1.0,
        20.0_f64.min(most_realizations),
    ));
    Panels {
        plots: vec![ks, da, real],
        layout: Layout::Grid { columns: 3 },
    }
}

/// The λ_l/λ_s = 128 convergence figure: KS distance and exponent difference of each
/// setting's pooled cluster areas to the reference's (the last setting, the sizes the
/// Appendix B rule asks for) against W/W0; the ensemble CCDFs at the largest load; the KS
/// distance of the first r realizations of each setting to all of them. Also the table and,
/// per setting, the largest KS distance over loads and whether it is within
/// [`CONVERGENCE_KS_TOLERANCE`].
fn fig128_convergence(
    store: &Store,
    name: &str,
    hurst: f64,
    settings: &[StudyRef],
) -> anyhow::Result<Vec<(String, Drawn)>> {
    anyhow::ensure!(
        settings.len() >= 2,
        "{name}: needs a setting and a reference"
    );
    let table = convergence_table(store, settings)?;
    let reference = settings.last().expect("two settings or more");
    let candidates = &settings[..settings.len() - 1];
    let setting_rows = |label: &str| -> Vec<&ConvergenceRow> {
        let mut rows: Vec<&ConvergenceRow> = table
            .rows
            .iter()
            .filter(|r| r.kind == "setting" && r.study == label)
            .collect();
        rows.sort_by(|a, b| a.w_over_w0.total_cmp(&b.w_over_w0));
        rows
    };
    let title = format!("λ_l/λ_s = 128, H = {hurst}");
    let mut ks = LinePlot::new(
        format!("{title}: KS distance to {}", reference.label),
        "W/W0",
        "KS distance (pooled A/λ_s²)",
        true,
        YAxis::Linear,
    );
    let mut da = LinePlot::new(
        format!("{title}: α − α(reference)"),
        "W/W0",
        "α − α(reference), plateau + power-law MLE",
        true,
        YAxis::Linear,
    );
    let mut summary = Vec::new();
    for (c, s) in candidates.iter().enumerate() {
        let rows = setting_rows(&s.label);
        let critical = if c == 0 { "95 % critical values" } else { "" };
        push_convergence_curves(
            &mut ks,
            &mut da,
            &s.label,
            critical,
            &rows,
            |r| r.w_over_w0,
            c,
        );
        let max_ks = rows.iter().map(|r| r.ks).fold(0.0, f64::max);
        let realizations = rows.first().map(|r| r.realizations).unwrap_or(0);
        summary.push(json!({
            "setting": s.label,
            "n": s.value,
            "realizations": realizations,
            "max_ks_over_loads": max_ks,
            "ks_by_load": rows.iter().map(|r| (r.w_over_w0, r.ks)).collect::<Vec<_>>(),
            "ks_critical_95_by_load": rows.iter().map(|r| (r.w_over_w0, r.critical)).collect::<Vec<_>>(),
            "within_tolerance": !rows.is_empty() && max_ks <= CONVERGENCE_KS_TOLERANCE,
            "loads_within_tolerance": rows
                .iter()
                .filter(|r| r.ks <= CONVERGENCE_KS_TOLERANCE)
                .map(|r| r.w_over_w0)
                .collect::<Vec<_>>(),
            "below_critical_at_every_load": !rows.is_empty()
                && rows.iter().all(|r| r.ks <= r.critical),
        }));
    }
    let loads: Vec<f64> = setting_rows(&candidates[0].label)
        .iter()
        .map(|r| r.w_over_w0)
        .collect();
    if let (Some(&lo), Some(&hi)) = (loads.first(), loads.last()) {
        // One load (profile convergence128_low): a line of zero length would not show.
        let (lo, hi) = if lo < hi {
            (lo, hi)
        } else {
            (lo / 2.0, hi * 2.0)
        };
        ks.series
            .push(tolerance_line(CONVERGENCE_KS_TOLERANCE, lo, hi));
    }
    // Ensemble-mean CCDFs at the largest load, reference in black.
    let tables = settings
        .iter()
        .map(|s| CcdfTable::read(store, &s.statistics_key))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let mut ccdf = LinePlot::new(
        format!("{title}: ensemble CCDF at the largest load"),
        "A / λ_s²",
        "P(A > a), ensemble mean",
        true,
        YAxis::Log,
    );
    ccdf.legend = LegendAt::LowerLeft;
    for (c, (s, t)) in settings.iter().zip(&tables).enumerate() {
        let Some(&(load_index, w)) = t.loads().last() else {
            continue;
        };
        let is_reference = c + 1 == settings.len();
        ccdf.series.push(Series {
            rgb: is_reference.then_some((0, 0, 0)),
            ..Series::line(
                format!("{}, W/W0 = {w:.3}", s.label),
                t.curve(load_index, None, true),
                c,
            )
        });
    }
    let mut real = LinePlot::new(
        format!("{title}: first r realizations vs all"),
        "realizations r",
        "max KS distance over loads",
        false,
        YAxis::Linear,
    );
    for (c, s) in settings.iter().enumerate() {
        let by_r = table.max_ks("realizations", &|r| {
            (r.study == s.label).then_some(r.realizations as f64)
        });
        real.series.push(Series {
            markers: true,
            ..Series::line(s.label.clone(), by_r, c)
        });
    }
    Ok(vec![
        (
            name.into(),
            Drawn::Panels(Panels {
                plots: vec![ks, da, ccdf, real],
                layout: Layout::Grid { columns: 2 },
            }),
        ),
        (name.into(), Drawn::Table(table.frame()?)),
        (
            "convergence".into(),
            Drawn::Result(json!({
                "tolerance": CONVERGENCE_KS_TOLERANCE,
                "alpha_estimator": CONVERGENCE_ESTIMATOR.name(),
                "reference": reference.label,
                "settings": summary,
            })),
        ),
    ])
}

/// Thresholds A*/λ_s² drawn in Figs. 4b and 5.
const FIG45_A_STAR: [f64; 5] = [2.0, 8.0, 32.0, 128.0, 512.0];
/// Fig. 4b: the y axis is linear up to this value and logarithmic above (as in the paper).
const FIG4B_LINEAR_UP_TO: f64 = 1e-5;

/// One series per threshold of `value` against W/W0 from a table with columns
/// `a_star_over_ls2` and `w_over_w0`.
fn per_threshold(
    df: &DataFrame,
    value: &str,
    label: &str,
    dashed: bool,
) -> anyhow::Result<Vec<Series>> {
    let a = f64_column(df, "a_star_over_ls2")?;
    let w = f64_column(df, "w_over_w0")?;
    let v = f64_column(df, value)?;
    let mut out: Vec<Series> = FIG45_A_STAR
        .iter()
        .enumerate()
        .map(|(c, &t)| Series {
            dashed,
            ..Series::line(
                if dashed {
                    String::new()
                } else {
                    format!("{label}, A*/λ_s² = {t}")
                },
                (0..a.len())
                    .filter(|&i| a[i] == t)
                    .map(|i| (w[i], v[i]))
                    .collect(),
                c,
            )
        })
        .collect();
    if dashed {
        // One legend entry for all the dashed curves (same colours as the simulated ones).
        out.push(Series {
            dashed: true,
            rgb: Some((0, 0, 0)),
            ..Series::line(format!("{label} (dashed, colour = A*)"), Vec::new(), 0)
        });
    }
    Ok(out)
}

/// Figs. 4b (K vs load), 5a (𝒦 vs load) and 5b (wear rate vs load), simulated (solid,
/// pooled over realizations) and from the fitted plateau + power-law model (dashed).
fn fig45(wear: &DataFrame, model: &DataFrame) -> anyhow::Result<Vec<(String, Drawn)>> {
    let mut k = per_threshold(wear, "k_archard_pooled", "K_num", false)?;
    k.extend(per_threshold(model, "k_pl", "K_PL fit", true)?);
    let mut kk = per_threshold(wear, "k_upscaled_pooled", "up-scaled K_num", false)?;
    kk.extend(per_threshold(
        model,
        "k_upscaled_pl",
        "up-scaled K_PL fit",
        true,
    )?);
    let rate = per_threshold(wear, "wear_rate_over_l2_mean", "R / L²", false)?;
    let plot = |title: &str, y: &str, y_axis: YAxis, series: Vec<Series>| {
        let mut p = LinePlot::new(title, "W / W0", y, true, y_axis);
        p.series = series;
        match y_axis {
            YAxis::Log => p.legend = LegendAt::LowerRight,
            YAxis::LinLog { .. } => p.legend = LegendAt::MiddleLeft,
            YAxis::Linear => {
                // Fig. 5a: the curves fill the width between 0 and 1, so the legend gets
                // its own band above them.
                p.legend = LegendAt::UpperLeft;
                p.y_headroom = 0.45;
            }
        }
        Drawn::Line(p)
    };
    Ok(vec![
        (
            "fig4b".into(),
            plot(
                "Fig. 4b: Archard's wear coefficient, λ_l/λ_s = 128",
                "K = P(A > A*)  (linear below 1e-5)",
                YAxis::LinLog {
                    threshold: FIG4B_LINEAR_UP_TO,
                },
                k,
            ),
        ),
        (
            "fig5a".into(),
            plot(
                "Fig. 5a: up-scaled wear coefficient, λ_l/λ_s = 128",
                "A_c* / A_c",
                YAxis::Linear,
                kk,
            ),
        ),
        (
            "fig5b".into(),
            plot(
                "Fig. 5b: wear rate (ω = 1/3), λ_l/λ_s = 128",
                "R / L²",
                YAxis::Log,
                rate,
            ),
        ),
    ])
}

/// The curves of Figs. 4b, 5a and 5b: statistics column, the column of its 95 % band, the
/// name in the manifest and the legend.
const FIG45_CURVES: [(&str, &str, &str, &str); 3] = [
    (
        "k_archard_pooled",
        "k_archard_ci95",
        "k_archard",
        "K (Fig. 4b)",
    ),
    (
        "k_upscaled_pooled",
        "k_upscaled_ci95",
        "k_upscaled",
        "up-scaled K (Fig. 5a)",
    ),
    (
        "wear_rate_over_l2_mean",
        "wear_rate_over_l2_ci95",
        "wear_rate_over_l2",
        "R / L² (Fig. 5b)",
    ),
];
/// Load-resolution rule of Figs. 4b and 5: between two loads of the chosen sweep, its curve
/// interpolated linearly in ln W/W0 lies within this many 95 % half-widths (of the
/// realization mean) of the finer sweep's value, except where the interval brackets a curve's
/// departure from zero (located only to within one load step). The finer sweep's own
/// neighbours interpolated at each load are recorded beside it (how far the curve jumps
/// between neighbouring loads), not used by the rule.
pub const LOAD_RESOLUTION_TOLERANCE: f64 = 1.0;

/// One load of the finer sweep, for one curve and threshold.
#[derive(Debug, Clone, PartialEq)]
struct LoadResolutionRow {
    /// Index in `FIG45_CURVES`.
    curve: usize,
    a_star_over_ls2: f64,
    w_over_w0: f64,
    /// The finer sweep's value and its 95 % half-width.
    value: f64,
    ci95: f64,
    /// The chosen sweep's curve at this load.
    interpolated: f64,
    /// The chosen sweep's interval around this load has zero at one end only.
    at_transition: bool,
    /// The finer sweep's own neighbours (the loads before and after) interpolated at this
    /// load; NaN at its first and last load and where they bracket a departure from zero.
    neighbours: f64,
}

/// |estimate − value| in units of the 95 % half-width `ci95` (0 when they agree exactly,
/// infinite for a difference where the band is empty, NaN without a band or estimate).
fn error_over_band(estimate: f64, value: f64, ci95: f64) -> f64 {
    let error = (estimate - value).abs();
    if error == 0.0 {
        0.0
    } else {
        error / ci95
    }
}

impl LoadResolutionRow {
    fn error_over_ci95(&self) -> f64 {
        error_over_band(self.interpolated, self.value, self.ci95)
    }

    fn neighbour_error_over_ci95(&self) -> f64 {
        error_over_band(self.neighbours, self.value, self.ci95)
    }

    /// The rule at this row (rows at a transition are not judged; NaN fails).
    fn within_rule(&self) -> bool {
        self.error_over_ci95() <= LOAD_RESOLUTION_TOLERANCE
    }
}

/// A curve given at increasing loads `u` (values `z`), interpolated linearly in ln W at `w`:
/// `None` outside `[u_0, u_last]`; otherwise the value and whether the bracketing interval
/// has zero at exactly one end. A load equal to a node (to 1e-12) takes the node's value.
fn interpolate_in_log_load(u: &[f64], z: &[f64], w: f64) -> Option<(f64, bool)> {
    let (first, last) = (*u.first()?, *u.last()?);
    if w < first * (1.0 - 1e-12) || w > last * (1.0 + 1e-12) {
        return None;
    }
    if let Some(j) = u.iter().position(|&x| ((x - w) / w).abs() <= 1e-12) {
        return Some((z[j], false));
    }
    let b = u.partition_point(|&x| x < w);
    let a = b - 1;
    let t = (w / u[a]).ln() / (u[b] / u[a]).ln();
    Some((z[a] + t * (z[b] - z[a]), (z[a] == 0.0) != (z[b] == 0.0)))
}

/// One curve of a wear table: `(W/W0, value, 95 % half-width)` at threshold `a_star`, by load.
fn wear_curve(
    df: &DataFrame,
    column: &str,
    band: &str,
    a_star: f64,
) -> anyhow::Result<Vec<(f64, f64, f64)>> {
    let a = f64_column(df, "a_star_over_ls2")?;
    let w = f64_column(df, "w_over_w0")?;
    let v = f64_column(df, column)?;
    let c = f64_column(df, band)?;
    let mut out: Vec<(f64, f64, f64)> = (0..a.len())
        .filter(|&i| a[i] == a_star)
        .map(|i| (w[i], v[i], c[i]))
        .collect();
    out.sort_by(|x, y| x.0.total_cmp(&y.0));
    Ok(out)
}

/// Every curve of Figs. 4b and 5 of the `chosen` sweep at the loads of the `fine` sweep
/// within its range (both wear tables of the statistics stage).
fn load_resolution_rows(
    fine: &DataFrame,
    chosen: &DataFrame,
) -> anyhow::Result<Vec<LoadResolutionRow>> {
    let mut rows = Vec::new();
    for (curve, &(column, band, _, _)) in FIG45_CURVES.iter().enumerate() {
        for &a_star in &FIG45_A_STAR {
            let coarse = wear_curve(chosen, column, band, a_star)?;
            let u: Vec<f64> = coarse.iter().map(|p| p.0).collect();
            let z: Vec<f64> = coarse.iter().map(|p| p.1).collect();
            let own = wear_curve(fine, column, band, a_star)?;
            for (i, &(w, value, ci95)) in own.iter().enumerate() {
                let neighbours = match (i.checked_sub(1), own.get(i + 1)) {
                    (Some(before), Some(after)) => {
                        let (before, after) = (own[before], *after);
                        interpolate_in_log_load(&[before.0, after.0], &[before.1, after.1], w)
                            .filter(|&(_, transition)| !transition)
                            .map_or(f64::NAN, |(v, _)| v)
                    }
                    _ => f64::NAN,
                };
                if let Some((interpolated, at_transition)) = interpolate_in_log_load(&u, &z, w) {
                    rows.push(LoadResolutionRow {
                        curve,
                        a_star_over_ls2: a_star,
                        w_over_w0: w,
                        value,
                        ci95,
                        interpolated,
                        at_transition,
                        neighbours,
                    });
                }
            }
        }
    }
    Ok(rows)
}

/// Distinct loads of a wear table, increasing.
fn distinct_loads(df: &DataFrame) -> anyhow::Result<Vec<f64>> {
    let mut w = f64_column(df, "w_over_w0")?;
    w.sort_by(f64::total_cmp);
    w.dedup();
    Ok(w)
}

/// Load resolution of Figs. 4b and 5 (`fig45_load_resolution`): table, chart of the largest
/// error over thresholds per curve and load, and the rule's result in the manifest.
fn fig45_load_resolution(
    fine: &DataFrame,
    chosen: &DataFrame,
) -> anyhow::Result<Vec<(String, Drawn)>> {
    let rows = load_resolution_rows(fine, chosen)?;
    anyhow::ensure!(
        !rows.is_empty(),
        "fig45_load_resolution: the two sweeps share no load range"
    );
    let fine_loads = distinct_loads(fine)?;
    let chosen_loads = distinct_loads(chosen)?;
    let largest_step = chosen_loads
        .windows(2)
        .map(|p| p[1] / p[0])
        .fold(1.0f64, f64::max);
    let judged = |r: &&LoadResolutionRow| !r.at_transition;
    let mut worst = serde_json::Map::new();
    for (curve, &(_, _, name, _)) in FIG45_CURVES.iter().enumerate() {
        // NaN (no band) and infinity (a difference where the band is empty) both count.
        let e = rows
            .iter()
            .filter(judged)
            .filter(|r| r.curve == curve)
            .map(|r| r.error_over_ci95())
            .fold(0.0f64, |m, x| {
                if x.is_nan() || m.is_nan() {
                    f64::NAN
                } else {
                    m.max(x)
                }
            });
        worst.insert(name.to_string(), json!(e));
    }
    let met = rows.iter().filter(judged).all(|r| r.within_rule());
    let transitions = rows.iter().filter(|r| r.at_transition).count();
    // The judged rows that miss the rule, with the finer sweep's own neighbour error there.
    let beyond_band: Vec<Value> = rows
        .iter()
        .filter(judged)
        .filter(|r| !r.within_rule())
        .map(|r| {
            json!({
                "curve": FIG45_CURVES[r.curve].2,
                "a_star_over_ls2": r.a_star_over_ls2,
                "w_over_w0": r.w_over_w0,
                "error_over_ci95": r.error_over_ci95(),
                "neighbour_error_over_ci95": r.neighbour_error_over_ci95(),
            })
        })
        .collect();
    let table = DataFrame::new(
        rows.len(),
        vec![
            Column::new(
                "curve".into(),
                rows.iter()
                    .map(|r| FIG45_CURVES[r.curve].2)
                    .collect::<Vec<&str>>(),
            ),
            Column::new(
                "a_star_over_ls2".into(),
                rows.iter().map(|r| r.a_star_over_ls2).collect::<Vec<f64>>(),
            ),
            Column::new(
                "w_over_w0".into(),
                rows.iter().map(|r| r.w_over_w0).collect::<Vec<f64>>(),
            ),
            Column::new(
                "value".into(),
                rows.iter().map(|r| r.value).collect::<Vec<f64>>(),
            ),
            Column::new(
                "ci95".into(),
                rows.iter().map(|r| r.ci95).collect::<Vec<f64>>(),
            ),
            Column::new(
                "interpolated".into(),
                rows.iter().map(|r| r.interpolated).collect::<Vec<f64>>(),
            ),
            Column::new(
                "error_over_ci95".into(),
                rows.iter()
                    .map(|r| r.error_over_ci95())
                    .collect::<Vec<f64>>(),
            ),
            Column::new(
                "at_transition".into(),
                rows.iter().map(|r| r.at_transition).collect::<Vec<bool>>(),
            ),
            Column::new(
                "neighbours".into(),
                rows.iter().map(|r| r.neighbours).collect::<Vec<f64>>(),
            ),
            Column::new(
                "neighbour_error_over_ci95".into(),
                rows.iter()
                    .map(|r| r.neighbour_error_over_ci95())
                    .collect::<Vec<f64>>(),
            ),
            Column::new(
                "within_rule".into(),
                rows.iter()
                    .map(|r| !r.at_transition && r.within_rule())
                    .collect::<Vec<bool>>(),
            ),
        ],
    )?;
    let mut plot = LinePlot::new(
        "Figs. 4b, 5: fewer loads interpolated vs the finer sweep",
        "W / W0",
        "|interpolated − value| / 95 % half-width (max over A*)",
        true,
        YAxis::Linear,
    );
    plot.legend = LegendAt::UpperRight;
    for (curve, &(_, _, _, legend)) in FIG45_CURVES.iter().enumerate() {
        let mut points: Vec<(f64, f64)> = Vec::new();
        for w in &fine_loads {
            let e = rows
                .iter()
                .filter(judged)
                .filter(|r| r.curve == curve && r.w_over_w0 == *w)
                .map(|r| r.error_over_ci95())
                .filter(|e| e.is_finite())
                .fold(f64::NEG_INFINITY, f64::max);
            if e.is_finite() {
                points.push((*w, e));
            }
        }
        plot.series.push(Series {
            markers: true,
            ..Series::line(legend, points, curve)
        });
    }
    let (x0, x1) = (
        rows.iter()
            .map(|r| r.w_over_w0)
            .fold(f64::INFINITY, f64::min),
        rows.iter().map(|r| r.w_over_w0).fold(0.0f64, f64::max),
    );
    plot.series.push(Series {
        width: 1,
        ..tolerance_line(LOAD_RESOLUTION_TOLERANCE, x0, x1)
    });
    let result = json!({
        "tolerance_error_over_ci95": LOAD_RESOLUTION_TOLERANCE,
        "fine_loads": fine_loads.len(),
        "chosen_loads": chosen_loads.len(),
        "chosen_largest_load_ratio": largest_step,
        "points": rows.len(),
        "points_at_transition": transitions,
        "points_judged": rows.len() - transitions,
        "points_beyond_band": beyond_band,
        "max_error_over_ci95": worst,
        "rule_met": met,
    });
    Ok(vec![
        ("fig45_load_resolution".into(), Drawn::Table(table)),
        ("fig45_load_resolution".into(), Drawn::Line(plot)),
        ("load_resolution".into(), Drawn::Result(result)),
    ])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The studies drawn only in Figs. 3 and 4a compute exactly the loads those figures draw,
    /// and the inset studies only the inset's load, in the quick, default and paper profiles
    /// (model no more than a scene needs); fig3_ll128 also feeds Figs. 4b and 5, so it sweeps.
    #[test]
    fn figure_3_studies_compute_only_the_loads_figure_3_draws() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("pipeline.yaml");
        let pipeline = crate::config::Pipeline::load(&path).unwrap();
        for profile in ["quick", "default", "paper"] {
            let plans = pipeline.plan(profile, "pipeline.yaml").unwrap();
            let loads = |name: &str| {
                plans
                    .iter()
                    .find(|s| s.name == name)
                    .unwrap_or_else(|| panic!("{profile}: no study {name}"))
                    .loads
                    .clone()
            };
            for name in ["fig3_ll8", "fig3_ll32"] {
                assert_eq!(loads(name), FIG3_LOADS.to_vec(), "{profile}: {name}");
            }
            for name in ["fig3_h06", "fig3_h07"] {
                assert_eq!(loads(name), vec![FIG3_INSET_LOAD], "{profile}: {name}");
            }
            let sweep = loads("fig3_ll128");
            assert!(
                sweep.len() > FIG3_LOADS.len(),
                "{profile}: fig3_ll128 sweeps"
            );
        }
    }

    /// The load-resolution profile's `lr128_chosen` is exactly the default profile's
    /// fig3_ll128 (so its check is about the sweep Figs. 4b and 5 draw), and `lr128_fine` the
    /// same realizations at more loads over the same range.
    #[test]
    fn load_resolution_studies_are_the_default_fig3_ll128_sweep_and_a_finer_one() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("pipeline.yaml");
        let pipeline = crate::config::Pipeline::load(&path).unwrap();
        let default = pipeline.plan("default", "pipeline.yaml").unwrap();
        let check = pipeline
            .plan("load_resolution128", "pipeline.yaml")
            .unwrap();
        let find = |plans: &[crate::config::StudyPlan], name: &str| {
            plans.iter().find(|s| s.name == name).cloned().unwrap()
        };
        let drawn = find(&default, "fig3_ll128");
        let chosen = find(&check, "lr128_chosen");
        let fine = find(&check, "lr128_fine");
        let same = |a: &crate::config::StudyPlan, b: &crate::config::StudyPlan| {
            crate::config::StudyPlan {
                name: String::new(),
                profile: String::new(),
                loads: Vec::new(),
                ..a.clone()
            } == crate::config::StudyPlan {
                name: String::new(),
                profile: String::new(),
                loads: Vec::new(),
                ..b.clone()
            }
        };
        assert!(same(&drawn, &chosen) && drawn.loads == chosen.loads);
        assert!(same(&drawn, &fine));
        assert!(fine.loads.len() > chosen.loads.len());
        // The fine sweep lies inside the chosen one's range, so every fine load is judged.
        assert!(chosen.loads[0] <= fine.loads[0]);
        assert_eq!(chosen.loads.last(), fine.loads.last());
        // The Fig. 3 loads are on the chosen grid or within 1.5 % of it.
        for t in FIG3_LOADS {
            let nearest =
                chosen.loads[crate::statistics::nearest_in_log(&chosen.loads, t).unwrap()];
            assert!((nearest / t - 1.0).abs() < 0.015, "{t}: {nearest}");
        }
    }

    #[test]
    fn interpolation_in_log_load_is_exact_for_a_curve_linear_in_ln_w() {
        let u = [0.001, 0.004, 0.01];
        let z: Vec<f64> = u.iter().map(|w: &f64| 3.0 + 2.0 * w.ln()).collect();
        for w in [0.001, 0.0015, 0.003, 0.004, 0.007, 0.01] {
            let (v, t) = interpolate_in_log_load(&u, &z, w).unwrap();
            assert!((v - (3.0 + 2.0 * f64::ln(w))).abs() < 1e-12, "{w}");
            assert!(!t);
        }
        assert_eq!(interpolate_in_log_load(&u, &z, 0.0009), None);
        assert_eq!(interpolate_in_log_load(&u, &z, 0.011), None);
        // Halfway in ln W between a zero and a one: one half, flagged as a transition; the
        // node itself is not.
        let zero_then_one = [0.0, 0.0, 1.0];
        let mid = (0.004f64 * 0.01).sqrt();
        let (v, t) = interpolate_in_log_load(&u, &zero_then_one, mid).unwrap();
        assert!((v - 0.5).abs() < 1e-12 && t);
        assert_eq!(
            interpolate_in_log_load(&u, &zero_then_one, 0.004),
            Some((0.0, false))
        );
        assert!(
            !interpolate_in_log_load(&u, &zero_then_one, 0.002)
                .unwrap()
                .1
        );
    }

    /// A wear table with every column the load-resolution check reads: `value(w, a*)` and a
    /// constant band `ci95` for each curve.
    fn wear_table(loads: &[f64], value: &dyn Fn(f64, f64) -> f64, ci95: f64) -> DataFrame {
        let mut a = Vec::new();
        let mut w = Vec::new();
        for &l in loads {
            for t in FIG45_A_STAR {
                a.push(t);
                w.push(l);
            }
        }
        let v: Vec<f64> = w.iter().zip(&a).map(|(&w, &a)| value(w, a)).collect();
        let mut columns = vec![
            Column::new("a_star_over_ls2".into(), a.clone()),
            Column::new("w_over_w0".into(), w.clone()),
        ];
        for (column, band, _, _) in FIG45_CURVES {
            columns.push(Column::new(column.into(), v.clone()));
            columns.push(Column::new(band.into(), vec![ci95; v.len()]));
        }
        DataFrame::new(v.len(), columns).unwrap()
    }

    /// The rule on synthetic sweeps: a curve linear in ln W is resolved by any subset of its
    /// loads; a curve with curvature gives the analytic interpolation error, judged against
    /// the band; a departure from zero between two chosen loads is flagged, not judged.
    #[test]
    fn load_resolution_rule_measures_the_interpolation_error_against_the_band() {
        let fine: Vec<f64> = (0..9).map(|i| 0.001 * 2f64.powi(i)).collect();
        let chosen: Vec<f64> = fine.iter().step_by(2).copied().collect();
        let result = |v: &dyn Fn(f64, f64) -> f64, ci95: f64| {
            let drawn =
                fig45_load_resolution(&wear_table(&fine, v, ci95), &wear_table(&chosen, v, ci95))
                    .unwrap();
            match drawn
                .into_iter()
                .find(|d| d.0 == "load_resolution")
                .unwrap()
                .1
            {
                Drawn::Result(r) => r,
                _ => unreachable!(),
            }
        };
        let linear = result(&|w, a| 1.0 + a * w.ln(), 1e-3);
        assert_eq!(linear["rule_met"], json!(true));
        assert_eq!(linear["points"], json!(3 * 5 * 9));
        assert_eq!(linear["points_at_transition"], json!(0));
        assert_eq!(linear["chosen_largest_load_ratio"], json!(4.0));
        // (ln W)²: the midpoint (in ln W) of an interval of width 2h = ln 4 is off by h².
        let h = 2f64.ln();
        let curved = |ci95: f64| result(&|w, _| w.ln().powi(2), ci95);
        let worst = curved(1.0)["max_error_over_ci95"]["k_archard"]
            .as_f64()
            .unwrap();
        assert!((worst - h * h).abs() < 1e-9, "{worst}");
        assert_eq!(curved(h * h * 1.01)["rule_met"], json!(true));
        let failed = curved(h * h * 0.99);
        assert_eq!(failed["rule_met"], json!(false));
        // The four fine loads between chosen ones, for 3 curves and 5 thresholds, each
        // beside a finer-sweep neighbour error of the same h² (the fine neighbours span the
        // same 2h here).
        let beyond = failed["points_beyond_band"].as_array().unwrap();
        assert_eq!(beyond.len(), 4 * 3 * 5);
        for b in beyond {
            let e = b["error_over_ci95"].as_f64().unwrap();
            let n = b["neighbour_error_over_ci95"].as_f64().unwrap();
            assert!((e - 1.0 / 0.99).abs() < 1e-9 && (n - e).abs() < 1e-9, "{b}");
        }
        // Zero up to 0.004, one from 0.008 (a fine load between two chosen ones: 0.016 is
        // chosen, 0.008 is not): flagged, and the rule holds although the band is empty.
        let step = result(&|w, _| if w > 0.005 { 1.0 } else { 0.0 }, 0.0);
        assert_eq!(step["points_at_transition"], json!(3 * 5));
        assert_eq!(step["rule_met"], json!(true));
    }
}
