//! The clusters stage (labelling of every contact map of a sweep) and the statistics
//! stage (per study: PDFs, CCDFs, wear coefficients, exponents), writing Parquet tables.
//! File layouts are in docs/CONVENTIONS.md.

use std::path::Path;

use polars::prelude::*;
use serde_json::{json, Value};

use super::stages::{
    contact_file, AnalyticJob, ClustersJob, StatisticsJob, A_STAR_OVER_LS2, BOOTSTRAP_RESAMPLES,
    FIG6_ALPHA, FIG6_A_STAR_OVER_A_S, FIG6_POINTS, PDF_BINS,
};
use super::store::Store;
use crate::analytic::PlateauPowerLaw;
use crate::clusters;
use crate::powerlaw::{self, Estimator};
use crate::statistics::{self as stats, OMEGA};

fn write_parquet(dir: &Path, name: &str, mut df: DataFrame) -> anyhow::Result<()> {
    let file = std::fs::File::create(dir.join(name))?;
    ParquetWriter::new(file).finish(&mut df)?;
    Ok(())
}

fn col<T>(name: &str, values: Vec<T>) -> Column
where
    Series: NamedFrom<Vec<T>, [T]>,
{
    Column::new(name.into(), values)
}

/// Label the contact map of every load of one realization.
pub(super) fn compute_clusters(
    job: &ClustersJob,
    dir: &Path,
    store: &Store,
) -> anyhow::Result<Value> {
    let manifest = store.lookup("contact", &job.contact_key)?.ok_or_else(|| {
        anyhow::anyhow!(
            "input contact {} is missing from the store",
            job.contact_key
        )
    })?;
    let ls2 = job.lambda_s_px * job.lambda_s_px;
    let pixels = (job.n * job.n) as f64;
    // Per cluster.
    let (mut load_index, mut w, mut id) = (Vec::new(), Vec::new(), Vec::new());
    let (mut area, mut area_ls2, mut perimeter) = (Vec::new(), Vec::new(), Vec::new());
    let (mut extent_x, mut extent_y, mut percolating) = (Vec::new(), Vec::new(), Vec::new());
    // Per load.
    let (mut n_clusters, mut fraction, mut largest, mut n_perc) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for (i, &load) in job.loads.iter().enumerate() {
        let path = store.read_output(&manifest, &contact_file(i))?;
        let (rows, cols, map, _) = crate::io::read_contact_map(&path)?;
        if (rows, cols) != (job.n, job.n) {
            anyhow::bail!(
                "{}: contact map is {rows} × {cols}, the study's grid is {n} × {n}",
                path.display(),
                n = job.n
            );
        }
        let l = clusters::label(&map, rows, cols, job.connectivity)?;
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
    write_parquet(
        dir,
        "clusters.parquet",
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
            ],
        )?,
    )?;
    let loads = job.loads.len();
    let total: u64 = n_clusters.iter().map(|&v| v as u64).sum();
    let percolating_loads = n_perc.iter().filter(|&&v| v > 0).count();
    write_parquet(
        dir,
        "loads.parquet",
        DataFrame::new(
            loads,
            vec![
                col("load_index", (0..loads as u32).collect::<Vec<_>>()),
                col("w_over_w0", job.loads.clone()),
                col("n_clusters", n_clusters),
                col("area_fraction", fraction),
                col("largest_area_over_ls2", largest),
                col("n_percolating", n_perc),
            ],
        )?,
    )?;
    Ok(json!({
        "total_clusters": total,
        "loads_with_percolating_cluster": percolating_loads,
    }))
}

/// Areas (pixels) of the non-percolating clusters and summary per realization and load.
struct Sample {
    /// `[realization][load]` areas of the clusters that do not wrap around the box.
    areas: Vec<Vec<Vec<u64>>>,
    /// `[realization][load]`: pixels in contact (all clusters), cluster count (all),
    /// largest area (all), percolating clusters.
    contact_px: Vec<Vec<u64>>,
    count: Vec<Vec<u64>>,
    largest: Vec<Vec<u64>>,
    percolating: Vec<Vec<u64>>,
}

fn read_sample(job: &StatisticsJob, store: &Store) -> anyhow::Result<Sample> {
    let loads = job.loads.len();
    let realizations = job.clusters_keys.len();
    let mut s = Sample {
        areas: vec![vec![Vec::new(); loads]; realizations],
        contact_px: vec![vec![0; loads]; realizations],
        count: vec![vec![0; loads]; realizations],
        largest: vec![vec![0; loads]; realizations],
        percolating: vec![vec![0; loads]; realizations],
    };
    for (r, key) in job.clusters_keys.iter().enumerate() {
        let manifest = store
            .lookup("clusters", key)?
            .ok_or_else(|| anyhow::anyhow!("input clusters {key} is missing from the store"))?;
        let path = store.read_output(&manifest, "clusters.parquet")?;
        let df = ParquetReader::new(std::fs::File::open(&path)?).finish()?;
        let li = df.column("load_index")?.u32()?.clone();
        let area = df.column("area_px")?.u64()?.clone();
        let perc = df.column("percolating")?.bool()?.clone();
        for ((l, a), p) in li.iter().zip(area.iter()).zip(perc.iter()) {
            let (Some(l), Some(a), Some(p)) = (l, a, p) else {
                anyhow::bail!("{}: null in a cluster row", path.display());
            };
            let l = l as usize;
            if l >= loads {
                anyhow::bail!("{}: load index {l} out of range", path.display());
            }
            s.contact_px[r][l] += a;
            s.count[r][l] += 1;
            s.largest[r][l] = s.largest[r][l].max(a);
            if p {
                s.percolating[r][l] += 1;
            } else {
                s.areas[r][l].push(a);
            }
        }
    }
    Ok(s)
}

/// Ensemble statistics of one study.
pub(super) fn compute_statistics(
    job: &StatisticsJob,
    dir: &Path,
    store: &Store,
) -> anyhow::Result<Value> {
    let s = read_sample(job, store)?;
    let ls2 = job.lambda_s_px * job.lambda_s_px;
    let pixels = (job.n * job.n) as f64;
    let loads = job.loads.len();
    let realizations = job.clusters_keys.len();
    let pooled: Vec<Vec<u64>> = (0..loads)
        .map(|l| s.areas.iter().flat_map(|r| r[l].iter().copied()).collect())
        .collect();

    // Per-load summary (all clusters, percolating ones included) and dN/dA_c.
    {
        let per_load = |f: &dyn Fn(usize, usize) -> f64| -> Vec<(f64, f64)> {
            (0..loads)
                .map(|l| {
                    let v: Vec<f64> = (0..realizations).map(|r| f(r, l)).collect();
                    let (m, _, half) = stats::mean_band(&v);
                    (m, half)
                })
                .collect()
        };
        let fraction = per_load(&|r, l| s.contact_px[r][l] as f64 / pixels);
        let count = per_load(&|r, l| s.count[r][l] as f64);
        let largest = per_load(&|r, l| s.largest[r][l] as f64 / ls2);
        let ac_ls2: Vec<f64> = fraction.iter().map(|f| f.0 * pixels / ls2).collect();
        let n_mean: Vec<f64> = count.iter().map(|c| c.0).collect();
        let dn_dac = stats::derivative(&ac_ls2, &n_mean);
        let perc: Vec<u32> = (0..loads)
            .map(|l| {
                (0..realizations)
                    .filter(|&r| s.percolating[r][l] > 0)
                    .count() as u32
            })
            .collect();
        let first = |v: &[(f64, f64)]| v.iter().map(|x| x.0).collect::<Vec<_>>();
        let second = |v: &[(f64, f64)]| v.iter().map(|x| x.1).collect::<Vec<_>>();
        write_parquet(
            dir,
            "loads.parquet",
            DataFrame::new(
                loads,
                vec![
                    col("load_index", (0..loads as u32).collect::<Vec<_>>()),
                    col("w_over_w0", job.loads.clone()),
                    col("area_fraction_mean", first(&fraction)),
                    col("area_fraction_ci95", second(&fraction)),
                    col("n_clusters_mean", first(&count)),
                    col("n_clusters_ci95", second(&count)),
                    col("largest_area_over_ls2_mean", first(&largest)),
                    col("largest_area_over_ls2_ci95", second(&largest)),
                    col("dn_dac_per_ls2", dn_dac),
                    col("realizations_percolating", perc),
                ],
            )?,
        )?;
    }

    // PDF in logarithmic bins, common edges for the study.
    let max_area = pooled.iter().flatten().copied().max().unwrap_or(0);
    let pdf_rows;
    {
        // Edges from 1 px to the largest area (a single bin [1, 2] if all areas are 1 px;
        // no rows if there is no cluster at all).
        let edges = stats::log_edges(1.0, (max_area as f64).max(2.0), PDF_BINS);
        let (mut li, mut w, mut bin) = (Vec::new(), Vec::new(), Vec::new());
        let (mut lo, mut hi, mut centre, mut width) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let (mut count, mut pooled_pdf, mut mean, mut half) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for l in (0..loads).filter(|_| max_area > 0) {
            let bins = stats::log_binned_pdf(&pooled[l], &edges);
            let per_real: Vec<Vec<stats::PdfBin>> = (0..realizations)
                .map(|r| stats::log_binned_pdf(&s.areas[r][l], &edges))
                .collect();
            for (j, b) in bins.iter().enumerate() {
                let v: Vec<f64> = per_real.iter().map(|p| p[j].density_per_px * ls2).collect();
                let (m, _, h) = stats::mean_band(&v);
                li.push(l as u32);
                w.push(job.loads[l]);
                bin.push(j as u32);
                lo.push(b.lower_px / ls2);
                hi.push(b.upper_px / ls2);
                centre.push(b.centre_px / ls2);
                width.push(b.width_px);
                count.push(b.count);
                pooled_pdf.push(b.density_per_px * ls2);
                mean.push(m);
                half.push(h);
            }
        }
        pdf_rows = li.len();
        write_parquet(
            dir,
            "pdf.parquet",
            DataFrame::new(
                pdf_rows,
                vec![
                    col("load_index", li),
                    col("w_over_w0", w),
                    col("bin", bin),
                    col("lower_over_ls2", lo),
                    col("upper_over_ls2", hi),
                    col("centre_over_ls2", centre),
                    col("width_px", width),
                    col("count_pooled", count),
                    col("pdf_pooled", pooled_pdf),
                    col("pdf_mean", mean),
                    col("pdf_ci95", half),
                ],
            )?,
        )?;
    }

    // Exact CCDF, pooled (realization null) and per realization; on the pooled rows also
    // the mean over realizations of their own CCDFs at the same areas, with its band
    // (realizations without any cluster at that load have no CCDF and are left out).
    {
        let (mut li, mut w, mut real, mut area, mut area_ls2, mut ccdf) = (
            Vec::new(),
            Vec::new(),
            Vec::<Option<u32>>::new(),
            Vec::new(),
            Vec::new(),
            Vec::new(),
        );
        let (mut mean, mut half) = (Vec::<Option<f64>>::new(), Vec::<Option<f64>>::new());
        for (l, pooled_l) in pooled.iter().enumerate() {
            let sorted: Vec<Vec<u64>> = (0..realizations)
                .filter(|&r| !s.areas[r][l].is_empty())
                .map(|r| {
                    let mut v = s.areas[r][l].clone();
                    v.sort_unstable();
                    v
                })
                .collect();
            let sets = std::iter::once((None, pooled_l))
                .chain((0..realizations).map(|r| (Some(r as u32), &s.areas[r][l])));
            for (r, a) in sets {
                for (k, p) in stats::ccdf_steps(a) {
                    li.push(l as u32);
                    w.push(job.loads[l]);
                    real.push(r);
                    area.push(k);
                    area_ls2.push(k as f64 / ls2);
                    ccdf.push(p);
                    if r.is_none() {
                        let v: Vec<f64> = sorted
                            .iter()
                            .map(|x| {
                                (x.len() - x.partition_point(|&a| a <= k)) as f64 / x.len() as f64
                            })
                            .collect();
                        let (m, _, h) = stats::mean_band(&v);
                        mean.push(Some(m));
                        half.push(Some(h));
                    } else {
                        mean.push(None);
                        half.push(None);
                    }
                }
            }
        }
        let rows = li.len();
        write_parquet(
            dir,
            "ccdf.parquet",
            DataFrame::new(
                rows,
                vec![
                    col("load_index", li),
                    col("w_over_w0", w),
                    Column::new("realization".into(), real),
                    col("area_px", area),
                    col("area_over_ls2", area_ls2),
                    col("ccdf", ccdf),
                    Column::new("ccdf_mean".into(), mean),
                    Column::new("ccdf_ci95".into(), half),
                ],
            )?,
        )?;
    }

    // K, 𝒦 and the wear rate on the A* grid.
    {
        let mut cols_v: [Vec<f64>; 9] = Default::default();
        let (mut li, mut w) = (Vec::new(), Vec::new());
        for (l, pooled_l) in pooled.iter().enumerate() {
            for &a_star in &A_STAR_OVER_LS2 {
                let a_px = a_star * ls2;
                let per: Vec<stats::WearAt> = (0..realizations)
                    .map(|r| stats::wear_at(&s.areas[r][l], a_px))
                    .collect();
                let p = stats::wear_at(pooled_l, a_px);
                let band = |f: &dyn Fn(&stats::WearAt) -> f64| {
                    let v: Vec<f64> = per.iter().map(f).collect();
                    let (m, _, h) = stats::mean_band(&v);
                    (m, h)
                };
                let k = band(&|x| x.k_archard);
                let kk = band(&|x| x.k_upscaled);
                let rate = band(&|x| OMEGA * x.area_above_px / pixels);
                li.push(l as u32);
                w.push(job.loads[l]);
                for (c, v) in cols_v.iter_mut().zip([
                    a_star,
                    p.k_archard,
                    k.0,
                    k.1,
                    p.k_upscaled,
                    kk.0,
                    kk.1,
                    rate.0,
                    rate.1,
                ]) {
                    c.push(v);
                }
            }
        }
        let names = [
            "a_star_over_ls2",
            "k_archard_pooled",
            "k_archard_mean",
            "k_archard_ci95",
            "k_upscaled_pooled",
            "k_upscaled_mean",
            "k_upscaled_ci95",
            "wear_rate_over_l2_mean",
            "wear_rate_over_l2_ci95",
        ];
        let rows = li.len();
        let mut columns = vec![col("load_index", li), col("w_over_w0", w)];
        for (name, v) in names.iter().zip(cols_v) {
            columns.push(col(name, v));
        }
        write_parquet(dir, "wear.parquet", DataFrame::new(rows, columns)?)?;
    }

    // Exponents per load, pooled over realizations.
    let fitted = write_alpha(job, dir, &pooled, ls2)?;

    Ok(json!({
        "realizations": realizations,
        "pdf_rows": pdf_rows,
        "loads_with_exponent": fitted,
        "omega": OMEGA,
    }))
}

/// One row per load and estimator; a fit that cannot be made leaves nulls and says why.
fn write_alpha(
    job: &StatisticsJob,
    dir: &Path,
    pooled: &[Vec<u64>],
    ls2: f64,
) -> anyhow::Result<usize> {
    let mut li = Vec::new();
    let mut w = Vec::new();
    let mut est = Vec::new();
    let mut alpha: Vec<Option<f64>> = Vec::new();
    let mut se: Vec<Option<f64>> = Vec::new();
    let mut ci_lo: Vec<Option<f64>> = Vec::new();
    let mut ci_hi: Vec<Option<f64>> = Vec::new();
    let mut k_min: Vec<Option<f64>> = Vec::new();
    let mut k_max: Vec<Option<f64>> = Vec::new();
    let mut k_s: Vec<Option<f64>> = Vec::new();
    let mut k_s_ls2: Vec<Option<f64>> = Vec::new();
    let mut n_fit: Vec<Option<u64>> = Vec::new();
    let mut ks: Vec<Option<f64>> = Vec::new();
    let mut note = Vec::new();
    let mut fitted = 0;
    for (l, areas) in pooled.iter().enumerate() {
        // Discrete truncated MLE, KS-chosen k_min, k_max = largest area.
        li.push(l as u32);
        w.push(job.loads[l]);
        est.push(Estimator::DiscreteTruncated.name().to_string());
        let k_hi = areas.iter().copied().max();
        match k_hi
            .ok_or(powerlaw::FitError::Empty)
            .and_then(|m| powerlaw::fit_discrete_tail(areas, Some(m)).map(|t| (t, m)))
        {
            Ok((t, m)) => {
                let f = t.fit;
                let ci = powerlaw::bootstrap_discrete(
                    areas,
                    f.lower as u64,
                    Some(m),
                    BOOTSTRAP_RESAMPLES,
                    job.seed ^ (l as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15),
                )
                .ok();
                alpha.push(Some(f.alpha));
                se.push(Some(f.std_error));
                ci_lo.push(ci.map(|c| c.0));
                ci_hi.push(ci.map(|c| c.1));
                k_min.push(Some(f.lower));
                k_max.push(Some(f.upper));
                n_fit.push(Some(f.n as u64));
                ks.push(Some(f.ks_distance));
                note.push(String::new());
                fitted += 1;
            }
            Err(e) => {
                for v in [
                    &mut alpha, &mut se, &mut ci_lo, &mut ci_hi, &mut k_min, &mut k_max, &mut ks,
                ] {
                    v.push(None);
                }
                n_fit.push(None);
                note.push(format!("no fit: {e}"));
            }
        }
        k_s.push(None);
        k_s_ls2.push(None);

        // Joint plateau + power law.
        li.push(l as u32);
        w.push(job.loads[l]);
        est.push(Estimator::DiscretePlateauPowerLaw.name().to_string());
        for v in [&mut se, &mut ci_lo, &mut ci_hi, &mut k_min, &mut ks] {
            v.push(None);
        }
        match powerlaw::fit_plateau_power_law(areas) {
            Ok(f) => {
                alpha.push(Some(f.alpha));
                k_max.push(Some(f.k_m as f64));
                k_s.push(Some(f.k_s));
                k_s_ls2.push(Some(f.k_s / ls2));
                n_fit.push(Some(f.n as u64));
                note.push(String::new());
            }
            Err(e) => {
                alpha.push(None);
                k_max.push(None);
                k_s.push(None);
                k_s_ls2.push(None);
                n_fit.push(None);
                note.push(format!("no fit: {e}"));
            }
        }
    }
    let rows = li.len();
    write_parquet(
        dir,
        "alpha.parquet",
        DataFrame::new(
            rows,
            vec![
                col("load_index", li),
                col("w_over_w0", w),
                col("estimator", est),
                Column::new("alpha".into(), alpha),
                Column::new("std_error".into(), se),
                Column::new("bootstrap_ci95_low".into(), ci_lo),
                Column::new("bootstrap_ci95_high".into(), ci_hi),
                Column::new("k_min_px".into(), k_min),
                Column::new("k_max_px".into(), k_max),
                Column::new("k_s_px".into(), k_s),
                Column::new("k_s_over_ls2".into(), k_s_ls2),
                Column::new("n_fitted".into(), n_fit),
                Column::new("ks_distance".into(), ks),
                col("note", note),
            ],
        )?,
    )?;
    Ok(fitted)
}

/// The analytic stage: the fitted plateau + power-law model of each load of a study on the
/// statistics' A* grid (`model.parquet`), or the model curves of Fig. 6 (`fig6.parquet`).
pub(super) fn compute_analytic(
    job: &AnalyticJob,
    dir: &Path,
    store: &Store,
) -> anyhow::Result<Value> {
    let Some(key) = &job.statistics_key else {
        return fig6_curves(dir);
    };
    let manifest = store
        .lookup("statistics", key)?
        .ok_or_else(|| anyhow::anyhow!("input statistics {key} is missing from the store"))?;
    let path = store.read_output(&manifest, "alpha.parquet")?;
    let df = ParquetReader::new(std::fs::File::open(&path)?).finish()?;
    let ls2 = job.lambda_s_px * job.lambda_s_px;
    let est = df.column("estimator")?.str()?.clone();
    let li = df.column("load_index")?.u32()?.clone();
    let w = df.column("w_over_w0")?.f64()?.clone();
    let alpha = df.column("alpha")?.f64()?.clone();
    let k_s = df.column("k_s_px")?.f64()?.clone();
    let k_m = df.column("k_max_px")?.f64()?.clone();
    let mut rows: (Vec<u32>, Vec<f64>, Vec<f64>) = Default::default();
    let mut fit: [Vec<Option<f64>>; 5] = Default::default();
    let mut fitted_loads = 0;
    for i in 0..df.height() {
        if est.get(i) != Some(Estimator::DiscretePlateauPowerLaw.name()) {
            continue;
        }
        let (Some(l), Some(wi)) = (li.get(i), w.get(i)) else {
            anyhow::bail!("{}: null load in row {i}", path.display());
        };
        let model = match (alpha.get(i), k_s.get(i), k_m.get(i)) {
            (Some(a), Some(s), Some(m)) => Some(PlateauPowerLaw::new(a, s, m)?),
            _ => None,
        };
        fitted_loads += usize::from(model.is_some());
        for &a_star in &A_STAR_OVER_LS2 {
            rows.0.push(l);
            rows.1.push(wi);
            rows.2.push(a_star);
            let values = match &model {
                Some(m) => [
                    Some(m.alpha),
                    Some(m.a_s / ls2),
                    Some(m.a_m / ls2),
                    Some(m.k_archard(a_star * ls2)?),
                    Some(m.k_upscaled(a_star * ls2)?),
                ],
                None => [None; 5],
            };
            for (c, v) in fit.iter_mut().zip(values) {
                c.push(v);
            }
        }
    }
    let n = rows.0.len();
    let [a, s, m, k, kk] = fit;
    write_parquet(
        dir,
        "model.parquet",
        DataFrame::new(
            n,
            vec![
                col("load_index", rows.0),
                col("w_over_w0", rows.1),
                col("a_star_over_ls2", rows.2),
                Column::new("alpha".into(), a),
                Column::new("a_s_over_ls2".into(), s),
                Column::new("a_m_over_ls2".into(), m),
                Column::new("k_pl".into(), k),
                Column::new("k_upscaled_pl".into(), kk),
            ],
        )?,
    )?;
    Ok(
        json!({ "fitted_loads": fitted_loads, "source_estimator": Estimator::DiscretePlateauPowerLaw.name() }),
    )
}

/// K_PL and 𝒦_PL against `A_m/A_s` for α = 1.5 and several `A*/A_s` (paper Fig. 6), plus
/// the `A_m → ∞` limits as rows with `a_m_over_a_s = inf`.
fn fig6_curves(dir: &Path) -> anyhow::Result<Value> {
    let (mut a_star, mut a_m, mut k, mut kk) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for &s in &FIG6_A_STAR_OVER_A_S {
        let grid = (0..FIG6_POINTS)
            .map(|i| 10f64.powf(12.0 * i as f64 / (FIG6_POINTS - 1) as f64))
            .chain(std::iter::once(f64::INFINITY));
        for m in grid {
            let model = PlateauPowerLaw::new(FIG6_ALPHA, 1.0, m)?;
            a_star.push(s);
            a_m.push(m);
            k.push(model.k_archard(s)?);
            kk.push(model.k_upscaled(s)?);
        }
    }
    let n = a_star.len();
    write_parquet(
        dir,
        "fig6.parquet",
        DataFrame::new(
            n,
            vec![
                col("alpha", vec![FIG6_ALPHA; n]),
                col("a_star_over_a_s", a_star),
                col("a_m_over_a_s", a_m),
                col("k_pl", k),
                col("k_upscaled_pl", kk),
            ],
        )?,
    )?;
    Ok(json!({ "rows": n }))
}
