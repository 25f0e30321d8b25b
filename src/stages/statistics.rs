//! The statistics stage: one study's ensemble statistics from its realizations' cluster
//! tables: per-load summary and dN/dA_c (`loads.parquet`), area PDF in logarithmic bins
//! (`pdf.parquet`), exact CCDF (`ccdf.parquet`), K, 𝒦 and the wear rate on a grid of A*
//! (`wear.parquet`), and the exponent α by maximum likelihood (`alpha.parquet`). Layouts in
//! docs/CONVENTIONS.md.

use std::path::Path;

use polars::prelude::*;
use serde_json::{json, Value};

use super::stage::Stage;
use crate::store::inputs::Inputs;

pub(crate) mod alpha;
mod job;

use crate::powerlaw;
use crate::resample::{self, NoInterval};
use crate::statistics as stats;
use crate::store::table::{col, load_columns, write};
use alpha::write_alpha;
use job::{Sample, Study};
pub use job::{StatisticsJob, A_STAR_OVER_LS2, BOOTSTRAP_RESAMPLES, PDF_BINS};

pub struct Statistics;

impl Stage for Statistics {
    const NAME: &'static str = "statistics";
    const VERSION: u32 = 3;
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
    let fitted = write_alpha(&study, dir)?;

    Ok(json!({
        "realizations": study.realizations,
        "pdf_rows": pdf_rows,
        "loads_with_exponent": fitted,
        "omega": job.omega,
    }))
}

/// Means over realizations with their 95 % intervals (`resample::mean_over_realizations`),
/// one row at a time, as the columns `<name>_mean`, `<name>_ci95` (the half-width
/// t·s/√R before clipping: a scale, NaN without an interval), `<name>_ci95_low` and
/// `<name>_ci95_high` (clipped to the quantity's bounds: the band to draw).
#[derive(Default)]
struct Band {
    mean: Vec<f64>,
    half: Vec<f64>,
    low: Vec<f64>,
    high: Vec<f64>,
}

impl Band {
    /// One row, `[mean, half-width, low, high]` (NaN without an interval), from one value
    /// per realization, and why it has no interval.
    fn row(values: &[f64], bounds: Option<(f64, f64)>) -> ([f64; 4], Option<NoInterval>) {
        let (m, ci) = resample::mean_over_realizations(values, bounds);
        match ci {
            Ok(c) => {
                let half = resample::student_t_975(c.realizations - 1) * c.std_error;
                ([m, half, c.low, c.high], None)
            }
            Err(e) => ([m, f64::NAN, f64::NAN, f64::NAN], Some(e)),
        }
    }

    /// Adds a row from one value per realization; returns why it has no interval.
    fn push(&mut self, values: &[f64], bounds: Option<(f64, f64)>) -> Option<NoInterval> {
        let (row, why) = Self::row(values, bounds);
        for (c, v) in [
            &mut self.mean,
            &mut self.half,
            &mut self.low,
            &mut self.high,
        ]
        .into_iter()
        .zip(row)
        {
            c.push(v);
        }
        why
    }

    fn columns(self, name: &str) -> [Column; 4] {
        [
            col(&format!("{name}_mean"), self.mean),
            col(&format!("{name}_ci95"), self.half),
            col(&format!("{name}_ci95_low"), self.low),
            col(&format!("{name}_ci95_high"), self.high),
        ]
    }
}

/// A row's `ci95_method`: `method` when every interval of the row was given, else the
/// first reason one was not.
fn method_or_reason(method: &str, reasons: impl IntoIterator<Item = Option<NoInterval>>) -> String {
    reasons
        .into_iter()
        .flatten()
        .next()
        .map_or_else(|| method.to_string(), |e| e.reason())
}

/// Per-load summary (all clusters, percolating ones included) and dN/dA_c: `loads.parquet`.
// `l` indexes every `[realization][load]` table of the sample, not one slice.
#[allow(clippy::needless_range_loop)]
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
    // dN/dA_c of each realization along its own sweep, then averaged like the rest.
    let dn_dac: Vec<Vec<f64>> = (0..realizations)
        .map(|r| {
            let ac: Vec<f64> = (0..loads)
                .map(|l| s.contact_px[r][l] as f64 / ls2)
                .collect();
            let n: Vec<f64> = (0..loads).map(|l| s.count[r][l] as f64).collect();
            stats::derivative(&ac, &n)
        })
        .collect();
    let (mut fraction, mut count, mut largest, mut slope) = Default::default();
    let mut method = Vec::with_capacity(loads);
    for l in 0..loads {
        let of = |f: &dyn Fn(usize) -> f64| (0..realizations).map(f).collect::<Vec<f64>>();
        let reasons = [
            Band::push(
                &mut fraction,
                &of(&|r| s.contact_px[r][l] as f64 / pixels),
                Some((0.0, 1.0)),
            ),
            Band::push(
                &mut count,
                &of(&|r| s.count[r][l] as f64),
                Some((0.0, f64::INFINITY)),
            ),
            Band::push(
                &mut largest,
                &of(&|r| s.largest[r][l] as f64 / ls2),
                Some((0.0, f64::INFINITY)),
            ),
            Band::push(&mut slope, &of(&|r| dn_dac[r][l]), None),
        ];
        method.push(method_or_reason(resample::METHOD_MEAN, reasons));
    }
    let perc: Vec<u32> = (0..loads)
        .map(|l| {
            (0..realizations)
                .filter(|&r| s.percolating[r][l] > 0)
                .count() as u32
        })
        .collect();
    write(
        dir,
        "loads.parquet",
        DataFrame::new(
            loads,
            [
                load_columns(&job.loads).to_vec(),
                fraction.columns("area_fraction").to_vec(),
                count.columns("n_clusters").to_vec(),
                largest.columns("largest_area_over_ls2").to_vec(),
                slope.columns("dn_dac_per_ls2").to_vec(),
                vec![
                    col("realizations", vec![realizations as u32; loads]),
                    col("realizations_percolating", perc),
                    col("ci95_method", method),
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
    let (mut count, mut pooled_pdf, mut band) = (Vec::new(), Vec::new(), Band::default());
    for l in (0..loads).filter(|_| max_area > 0) {
        let bins = stats::log_binned_pdf(&pooled[l], &edges);
        let per_real: Vec<Vec<stats::PdfBin>> = (0..realizations)
            .map(|r| stats::log_binned_pdf(&s.areas[r][l], &edges))
            .collect();
        for (j, b) in bins.iter().enumerate() {
            let v: Vec<f64> = per_real.iter().map(|p| p[j].density_per_px * ls2).collect();
            band.push(&v, Some((0.0, f64::INFINITY)));
            li.push(l as u32);
            w.push(job.loads[l]);
            bin.push(j as u32);
            lo.push(b.lower_px / ls2);
            hi.push(b.upper_px / ls2);
            centre.push(b.centre_px / ls2);
            width.push(b.width_px);
            count.push(b.count);
            pooled_pdf.push(b.density_per_px * ls2);
        }
    }
    let pdf_rows = li.len();
    write(
        dir,
        "pdf.parquet",
        DataFrame::new(
            pdf_rows,
            [
                col("load_index", li),
                col("w_over_w0", w),
                col("bin", bin),
                col("lower_over_ls2", lo),
                col("upper_over_ls2", hi),
                col("centre_over_ls2", centre),
                col("width_px", width),
                col("count_pooled", count),
                col("pdf_pooled", pooled_pdf),
            ]
            .into_iter()
            .chain(band.columns("pdf"))
            .collect(),
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
    // The band columns, null on the rows of one realization.
    let mut band: [Vec<Option<f64>>; 4] = Default::default();
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
                    let (row, _) = Band::row(&v, Some((0.0, 1.0)));
                    for (c, x) in band.iter_mut().zip(row) {
                        c.push(Some(x));
                    }
                } else {
                    for c in band.iter_mut() {
                        c.push(None);
                    }
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
            [
                col("load_index", li),
                col("w_over_w0", w),
                Column::new("realization".into(), real),
                col("area_px", area),
                col("area_over_ls2", area_ls2),
                col("ccdf", ccdf),
            ]
            .into_iter()
            .chain(
                ["ccdf_mean", "ccdf_ci95", "ccdf_ci95_low", "ccdf_ci95_high"]
                    .into_iter()
                    .zip(band)
                    .map(|(name, v)| Column::new(name.into(), v)),
            )
            .collect(),
        )?,
    )?;
    Ok(())
}

/// One realization's clusters against a threshold: how many and how much area lie above
/// it, of how many and how much in all (pixels).
#[derive(Clone, Copy)]
struct Above {
    count: u64,
    clusters: u64,
    area_px: f64,
    total_px: f64,
}

impl Above {
    fn of(areas_px: &[u64], a_star_px: f64) -> Self {
        let mut a = Above {
            count: 0,
            clusters: areas_px.len() as u64,
            area_px: 0.0,
            total_px: 0.0,
        };
        for &x in areas_px {
            a.total_px += x as f64;
            if x as f64 > a_star_px {
                a.count += 1;
                a.area_px += x as f64;
            }
        }
        a
    }

    /// K and 𝒦 of the realizations drawn, pooled (None without any cluster).
    fn pooled(drawn: &[&Above], upscaled: bool) -> Option<f64> {
        let sum = |f: &dyn Fn(&Above) -> f64| drawn.iter().map(|a| f(a)).sum::<f64>();
        if upscaled {
            let total = sum(&|a| a.total_px);
            (total > 0.0).then(|| sum(&|a| a.area_px) / total)
        } else {
            let n = sum(&|a| a.clusters as f64);
            (n > 0.0).then(|| sum(&|a| a.count as f64) / n)
        }
    }
}

/// The means' and the pooled values' methods, for a row where both have intervals.
const WEAR_METHODS: &str = "means: realization_mean_t; pooled: realization_bootstrap_t";

/// K, 𝒦 and the wear rate on the A* grid, pooled over realizations (the pooled value with
/// an interval from resampling whole realizations) and as means of the realizations' own
/// values, with the counts behind them: `wear.parquet`.
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
    let unit = Some((0.0, 1.0));
    let (mut li, mut w, mut a_col) = (Vec::new(), Vec::new(), Vec::new());
    let mut pooled_cols: [Vec<f64>; 6] = Default::default();
    let (mut k, mut kk, mut rate) = (Band::default(), Band::default(), Band::default());
    let (mut above, mut smallest, mut method) = (Vec::new(), Vec::new(), Vec::new());
    for (l, pooled_l) in pooled.iter().enumerate() {
        for (i, &a_star) in job.a_star_over_ls2.iter().enumerate() {
            let a_px = a_star * ls2;
            let per: Vec<Above> = (0..realizations)
                .map(|r| Above::of(&s.areas[r][l], a_px))
                .collect();
            let p = stats::wear_at(pooled_l, a_px);
            let seed = job.seed ^ ((l * 64 + i) as u64 + 1).wrapping_mul(0x2545_F491_4F6C_DD1D);
            let mut reasons = Vec::new();
            for (j, (value, upscaled)) in [(p.k_archard, false), (p.k_upscaled, true)]
                .into_iter()
                .enumerate()
            {
                let ci = resample::over_realizations(
                    &per,
                    &|d: &[&Above]| Above::pooled(d, upscaled),
                    job.bootstrap_resamples,
                    seed ^ j as u64,
                    unit,
                );
                pooled_cols[3 * j].push(value);
                let (lo, hi) = match ci {
                    Ok(c) => (c.low, c.high),
                    Err(e) => {
                        reasons.push(Some(e));
                        (f64::NAN, f64::NAN)
                    }
                };
                pooled_cols[3 * j + 1].push(lo);
                pooled_cols[3 * j + 2].push(hi);
            }
            // A realization without any cluster at this load has no K or 𝒦 of its own.
            let own = |f: &dyn Fn(&Above) -> f64| -> Vec<f64> {
                per.iter()
                    .map(|a| if a.clusters > 0 { f(a) } else { f64::NAN })
                    .collect()
            };
            reasons.push(k.push(&own(&|a| a.count as f64 / a.clusters as f64), unit));
            reasons.push(kk.push(
                &own(&|a| {
                    if a.total_px > 0.0 {
                        a.area_px / a.total_px
                    } else {
                        0.0
                    }
                }),
                unit,
            ));
            let rates: Vec<f64> = per.iter().map(|a| job.omega * a.area_px / pixels).collect();
            reasons.push(rate.push(&rates, Some((0.0, f64::INFINITY))));
            li.push(l as u32);
            w.push(job.loads[l]);
            a_col.push(a_star);
            above.push(per.iter().map(|a| a.count).sum::<u64>());
            smallest.push(per.iter().map(|a| a.count).min().unwrap_or(0));
            method.push(method_or_reason(WEAR_METHODS, reasons));
        }
    }
    let rows = li.len();
    let [kp, kp_lo, kp_hi, kkp, kkp_lo, kkp_hi] = pooled_cols;
    let columns: Vec<Column> = [
        vec![
            col("load_index", li),
            col("w_over_w0", w),
            col("a_star_over_ls2", a_col),
            col("k_archard_pooled", kp),
            col("k_archard_pooled_ci95_low", kp_lo),
            col("k_archard_pooled_ci95_high", kp_hi),
        ],
        k.columns("k_archard").to_vec(),
        vec![
            col("k_upscaled_pooled", kkp),
            col("k_upscaled_pooled_ci95_low", kkp_lo),
            col("k_upscaled_pooled_ci95_high", kkp_hi),
        ],
        kk.columns("k_upscaled").to_vec(),
        rate.columns("wear_rate_over_l2").to_vec(),
        vec![
            col("clusters_above", above),
            col("clusters_above_smallest_realization", smallest),
            col("realizations", vec![realizations as u32; rows]),
            col("ci95_method", method),
        ],
    ]
    .concat();
    write(dir, "wear.parquet", DataFrame::new(rows, columns)?)?;
    Ok(())
}
