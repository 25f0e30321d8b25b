//! The statistics stage: one study's ensemble statistics from its realizations' cluster
//! tables: per-load summary and dN/dA_c (`loads.parquet`), area PDF in logarithmic bins
//! (`pdf.parquet`), exact CCDF (`ccdf.parquet`), K, 𝒦 and the wear rate on a grid of A*
//! (`wear.parquet`), and the exponent α by maximum likelihood (`alpha.parquet`). Layouts in
//! docs/CONVENTIONS.md.

use std::path::Path;

use polars::prelude::*;
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

use super::{Inputs, Stage};
use crate::powerlaw::{self, Estimator};
use crate::statistics as stats;
use crate::store::table::{col, load_columns, write};

pub struct Statistics;

/// Thresholds `A*/λ_s²` at which the statistics stage evaluates `K`, `𝒦` and the wear
/// rate: powers of two from 1/4 to 1024 (the paper's Fig. 2 uses `A* = 2 λ_s²`).
pub const A_STAR_OVER_LS2: [f64; 13] = [
    0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0, 128.0, 256.0, 512.0, 1024.0,
];
/// Logarithmic bins of the area PDF (paper Fig. 3).
pub const PDF_BINS: usize = 20;
/// Bootstrap resamples of the exponent's interval.
pub const BOOTSTRAP_RESAMPLES: usize = 200;

/// One study's statistics. Inputs: its realizations' clusters instances, in order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StatisticsJob {
    #[serde(rename = "loads_w_over_w0")]
    pub loads: Vec<f64>,
    /// Grid side.
    pub n: usize,
    /// λ_s in grid spacings (areas per λ_s²).
    pub lambda_s_px: f64,
    /// Seed of the bootstrap resampling.
    pub seed: u64,
    /// Thresholds A*/λ_s² of `wear.parquet`.
    pub a_star_over_ls2: Vec<f64>,
    /// Logarithmic bins of the PDF.
    pub pdf_bins: usize,
    /// Bootstrap resamples of α's interval.
    pub bootstrap_resamples: usize,
    /// Fewest clusters in a fitted tail.
    pub min_tail: usize,
    /// Wear-volume factor ω of the wear rate (volume = ω A^(3/2)).
    pub omega: f64,
    /// A measured study's maps: rows × cols pixels each (`n` is 0). Absent (and not in the
    /// key) for the `n × n` grid.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub map_pixels: Option<u64>,
}

impl StatisticsJob {
    /// The job of a study with the stage's standard grid of thresholds, bins and resamples.
    pub fn standard(loads: Vec<f64>, n: usize, lambda_s_px: f64, seed: u64) -> Self {
        Self {
            loads,
            n,
            lambda_s_px,
            seed,
            a_star_over_ls2: A_STAR_OVER_LS2.to_vec(),
            pdf_bins: PDF_BINS,
            bootstrap_resamples: BOOTSTRAP_RESAMPLES,
            min_tail: powerlaw::MIN_TAIL,
            omega: stats::OMEGA,
            map_pixels: None,
        }
    }
}

impl Stage for Statistics {
    const NAME: &'static str = "statistics";
    const VERSION: u32 = 2;
    type Job = StatisticsJob;

    fn compute(job: &StatisticsJob, inputs: &Inputs, dir: &Path) -> anyhow::Result<Value> {
        anyhow::ensure!(
            job.min_tail == powerlaw::MIN_TAIL,
            "min_tail {} differs from this build's {}: the fits use the built-in value",
            job.min_tail,
            powerlaw::MIN_TAIL
        );
        compute_statistics(job, inputs, dir)
    }
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

fn read_sample(job: &StatisticsJob, inputs: &Inputs) -> anyhow::Result<Sample> {
    let loads = job.loads.len();
    let realizations = inputs.len();
    let mut s = Sample {
        areas: vec![vec![Vec::new(); loads]; realizations],
        contact_px: vec![vec![0; loads]; realizations],
        count: vec![vec![0; loads]; realizations],
        largest: vec![vec![0; loads]; realizations],
        percolating: vec![vec![0; loads]; realizations],
    };
    for r in 0..realizations {
        let path = inputs.file(r, "clusters", "clusters.parquet")?;
        let df = crate::store::table::read(&path)?;
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

/// What the tables of one study are computed from.
struct Study<'a> {
    job: &'a StatisticsJob,
    s: Sample,
    /// `[load]`: the non-percolating cluster areas of every realization together.
    pooled: Vec<Vec<u64>>,
    ls2: f64,
    pixels: f64,
    loads: usize,
    realizations: usize,
}

/// Ensemble statistics of one study.
fn compute_statistics(job: &StatisticsJob, inputs: &Inputs, dir: &Path) -> anyhow::Result<Value> {
    let s = read_sample(job, inputs)?;
    let loads = job.loads.len();
    let pooled: Vec<Vec<u64>> = (0..loads)
        .map(|l| s.areas.iter().flat_map(|r| r[l].iter().copied()).collect())
        .collect();
    let study = Study {
        job,
        s,
        pooled,
        ls2: job.lambda_s_px * job.lambda_s_px,
        pixels: job.map_pixels.unwrap_or((job.n * job.n) as u64) as f64,
        loads,
        realizations: inputs.len(),
    };
    write_loads(&study, dir)?;
    let pdf_rows = write_pdf(&study, dir)?;
    write_ccdf(&study, dir)?;
    write_wear(&study, dir)?;
    // Exponents per load, pooled over realizations.
    let fitted = write_alpha(job, dir, &study.pooled, study.ls2)?;

    Ok(json!({
        "realizations": study.realizations,
        "pdf_rows": pdf_rows,
        "loads_with_exponent": fitted,
        "omega": job.omega,
    }))
}

/// Per-load summary (all clusters, percolating ones included) and dN/dA_c: `loads.parquet`.
fn write_loads(study: &Study, dir: &Path) -> anyhow::Result<()> {
    let Study {
        job,
        s,
        ls2,
        pixels,
        loads,
        realizations,
        ..
    } = study;
    let (ls2, pixels, loads, realizations) = (*ls2, *pixels, *loads, *realizations);
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
    write(
        dir,
        "loads.parquet",
        DataFrame::new(
            loads,
            [
                load_columns(&job.loads).to_vec(),
                vec![
                    col("area_fraction_mean", first(&fraction)),
                    col("area_fraction_ci95", second(&fraction)),
                    col("n_clusters_mean", first(&count)),
                    col("n_clusters_ci95", second(&count)),
                    col("largest_area_over_ls2_mean", first(&largest)),
                    col("largest_area_over_ls2_ci95", second(&largest)),
                    col("dn_dac_per_ls2", dn_dac),
                    col("realizations_percolating", perc),
                ],
            ]
            .concat(),
        )?,
    )?;
    Ok(())
}

/// PDF in logarithmic bins, common edges for the study: `pdf.parquet`; returns its rows.
fn write_pdf(study: &Study, dir: &Path) -> anyhow::Result<usize> {
    let max_area = study.pooled.iter().flatten().copied().max().unwrap_or(0);
    let Study {
        job,
        s,
        pooled,
        ls2,
        loads,
        realizations,
        ..
    } = study;
    let (ls2, loads, realizations) = (*ls2, *loads, *realizations);
    // Edges from 1 px to the largest area (a single bin [1, 2] if all areas are 1 px;
    // no rows if there is no cluster at all).
    let edges = stats::log_edges(1.0, (max_area as f64).max(2.0), job.pdf_bins);
    let (mut li, mut w, mut bin) = (Vec::new(), Vec::new(), Vec::new());
    let (mut lo, mut hi, mut centre, mut width) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
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
    let pdf_rows = li.len();
    write(
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
    Ok(pdf_rows)
}

/// Exact CCDF, pooled (realization null) and per realization; on the pooled rows also the
/// mean over realizations of their own CCDFs at the same areas, with its band (realizations
/// without any cluster at that load have no CCDF and are left out): `ccdf.parquet`.
fn write_ccdf(study: &Study, dir: &Path) -> anyhow::Result<()> {
    let Study {
        job,
        s,
        pooled,
        ls2,
        realizations,
        ..
    } = study;
    let (ls2, realizations) = (*ls2, *realizations);
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
                        .map(|x| (x.len() - x.partition_point(|&a| a <= k)) as f64 / x.len() as f64)
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
    write(
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
    Ok(())
}

/// K, 𝒦 and the wear rate on the A* grid: `wear.parquet`.
fn write_wear(study: &Study, dir: &Path) -> anyhow::Result<()> {
    let Study {
        job,
        s,
        pooled,
        ls2,
        pixels,
        realizations,
        ..
    } = study;
    let (ls2, pixels, realizations) = (*ls2, *pixels, *realizations);
    let mut cols_v: [Vec<f64>; 9] = Default::default();
    let (mut li, mut w) = (Vec::new(), Vec::new());
    for (l, pooled_l) in pooled.iter().enumerate() {
        for &a_star in &job.a_star_over_ls2 {
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
            let rate = band(&|x| job.omega * x.area_above_px / pixels);
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
    write(dir, "wear.parquet", DataFrame::new(rows, columns)?)?;
    Ok(())
}

/// One row of `alpha.parquet`: one estimator at one load (`None`: not fitted, or not an
/// output of that estimator).
#[derive(Default)]
struct AlphaRow {
    alpha: Option<f64>,
    std_error: Option<f64>,
    ci95: Option<(f64, f64, &'static str)>,
    k_min: Option<f64>,
    k_max: Option<f64>,
    k_s: Option<f64>,
    n_fitted: Option<u64>,
    ks_distance: Option<f64>,
    note: String,
}

/// The discrete truncated MLE at load `l`: k_min by the KS criterion, k_max the largest
/// area, a bootstrap interval.
fn truncated_row(job: &StatisticsJob, l: usize, areas: &[u64]) -> AlphaRow {
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
                job.bootstrap_resamples,
                job.seed ^ (l as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15),
            )
            .ok();
            AlphaRow {
                alpha: Some(f.alpha),
                std_error: Some(f.std_error),
                ci95: ci.map(|c| (c.0, c.1, "bootstrap")),
                k_min: Some(f.lower),
                k_max: Some(f.upper),
                n_fitted: Some(f.n as u64),
                ks_distance: Some(f.ks_distance),
                ..AlphaRow::default()
            }
        }
        Err(e) => AlphaRow {
            note: format!("no fit: {e}"),
            ..AlphaRow::default()
        },
    }
}

/// The paper's plateau + power law fitted jointly, with its 95 % profile-likelihood
/// interval.
fn plateau_row(areas: &[u64]) -> AlphaRow {
    match powerlaw::fit_plateau_power_law(areas) {
        Ok(f) => {
            // The 95 % profile-likelihood interval (the fit succeeded, so this does).
            let ci = powerlaw::plateau_alpha_interval(areas, &f).ok();
            AlphaRow {
                alpha: Some(f.alpha),
                ci95: ci.map(|c| (c.low, c.high, "profile_likelihood")),
                k_max: Some(f.k_m as f64),
                k_s: Some(f.k_s),
                n_fitted: Some(f.n as u64),
                note: match ci {
                    Some(c) if c.low_at_edge || c.high_at_edge => format!(
                        "the interval reaches the searched range of α ({} side): the data bound α on one side only",
                        if c.low_at_edge { "low" } else { "high" }
                    ),
                    _ => String::new(),
                },
                ..AlphaRow::default()
            }
        }
        Err(e) => AlphaRow {
            note: format!("no fit: {e}"),
            ..AlphaRow::default()
        },
    }
}

/// One row per load and estimator; a fit that cannot be made leaves nulls and says why.
/// Returns the number of loads the truncated power law was fitted at.
fn write_alpha(
    job: &StatisticsJob,
    dir: &Path,
    pooled: &[Vec<u64>],
    ls2: f64,
) -> anyhow::Result<usize> {
    let mut rows: Vec<(usize, Estimator, AlphaRow)> = Vec::new();
    for (l, areas) in pooled.iter().enumerate() {
        rows.push((
            l,
            Estimator::DiscreteTruncated,
            truncated_row(job, l, areas),
        ));
        rows.push((l, Estimator::DiscretePlateauPowerLaw, plateau_row(areas)));
    }
    let fitted = rows
        .iter()
        .filter(|r| r.1 == Estimator::DiscreteTruncated && r.2.alpha.is_some())
        .count();
    let opt =
        |f: &dyn Fn(&AlphaRow) -> Option<f64>| rows.iter().map(|r| f(&r.2)).collect::<Vec<_>>();
    let n = rows.len();
    write(
        dir,
        "alpha.parquet",
        DataFrame::new(
            n,
            vec![
                col(
                    "load_index",
                    rows.iter().map(|r| r.0 as u32).collect::<Vec<u32>>(),
                ),
                col(
                    "w_over_w0",
                    rows.iter().map(|r| job.loads[r.0]).collect::<Vec<f64>>(),
                ),
                col(
                    "estimator",
                    rows.iter()
                        .map(|r| r.1.name().to_string())
                        .collect::<Vec<String>>(),
                ),
                Column::new("alpha".into(), opt(&|r| r.alpha)),
                Column::new("std_error".into(), opt(&|r| r.std_error)),
                Column::new("ci95_low".into(), opt(&|r| r.ci95.map(|c| c.0))),
                Column::new("ci95_high".into(), opt(&|r| r.ci95.map(|c| c.1))),
                Column::new(
                    "ci95_method".into(),
                    rows.iter()
                        .map(|r| r.2.ci95.map(|c| c.2.to_string()))
                        .collect::<Vec<Option<String>>>(),
                ),
                Column::new("k_min_px".into(), opt(&|r| r.k_min)),
                Column::new("k_max_px".into(), opt(&|r| r.k_max)),
                Column::new("k_s_px".into(), opt(&|r| r.k_s)),
                Column::new("k_s_over_ls2".into(), opt(&|r| r.k_s.map(|k| k / ls2))),
                Column::new(
                    "n_fitted".into(),
                    rows.iter()
                        .map(|r| r.2.n_fitted)
                        .collect::<Vec<Option<u64>>>(),
                ),
                Column::new("ks_distance".into(), opt(&|r| r.ks_distance)),
                col(
                    "note",
                    rows.iter()
                        .map(|r| r.2.note.clone())
                        .collect::<Vec<String>>(),
                ),
            ],
        )?,
    )?;
    Ok(fitted)
}
