//! The figures stage: each paper figure drawn from stored artifacts as PNG and SVG, with
//! the plotted data as CSV beside it. A run copies the figures of its profile to
//! `figures/<profile>/` next to the data directory.

use std::path::Path;

use polars::prelude::*;
use serde_json::{json, Value};

use super::plot::{LinePlot, Series};
use super::stages::FigureJob;
use super::store::Store;

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

/// Draw one figure into `dir`.
pub(super) fn compute_figure(job: &FigureJob, dir: &Path, store: &Store) -> anyhow::Result<Value> {
    let plots: Vec<(&str, LinePlot)> = match job {
        FigureJob::Fig6 { analytic_key } => fig6(&read_table(
            store,
            "analytic",
            analytic_key,
            "fig6.parquet",
        )?)?,
        FigureJob::Fig2ef { statistics_key, .. } => fig2ef(&read_table(
            store,
            "statistics",
            statistics_key,
            "loads.parquet",
        )?)?,
        FigureJob::Fig45 {
            statistics_key,
            analytic_key,
        } => fig45(
            &read_table(store, "statistics", statistics_key, "wear.parquet")?,
            &read_table(store, "analytic", analytic_key, "model.parquet")?,
        )?,
    };
    let mut names = Vec::new();
    for (stem, plot) in &plots {
        plot.write(dir, stem)?;
        plot.write_data(&dir.join(format!("{stem}.csv")))?;
        names.push(*stem);
    }
    Ok(json!({ "figures": names, "png_size_px": super::plot::SIZE_PX }))
}

/// Fig. 6: K_PL and 𝒦_PL against A_m/A_s for α = 1.5 and several A*/A_s.
fn fig6(df: &DataFrame) -> anyhow::Result<Vec<(&'static str, LinePlot)>> {
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
    let mut series = Vec::new();
    for (name, values, dashed) in [("K_PL", &k, false), ("up-scaled K_PL", &kk, true)] {
        for (c, &t) in thresholds.iter().enumerate() {
            let points: Vec<(f64, f64)> = (0..s.len())
                .filter(|&i| s[i] == t && m[i].is_finite() && m[i] >= t)
                .map(|i| (m[i], values[i]))
                .collect();
            series.push(Series {
                label: format!("{name}, A*/A_s = {t}"),
                points,
                color: c,
                dashed,
            });
        }
    }
    Ok(vec![(
        "fig6",
        LinePlot {
            title: format!("Fig. 6: power-law model, α = {alpha}"),
            x_label: "A_m / A_s".into(),
            y_label: "K_PL (solid), up-scaled K_PL (dashed)".into(),
            x_log: true,
            y_log: false,
            series,
        },
    )])
}

/// Fig. 2e (A_c and the largest cluster) and 2f (dN/dA_c) against W/W0.
fn fig2ef(df: &DataFrame) -> anyhow::Result<Vec<(&'static str, LinePlot)>> {
    let w = f64_column(df, "w_over_w0")?;
    let ac = f64_column(df, "area_fraction_mean")?;
    let largest = f64_column(df, "largest_area_over_ls2_mean")?;
    let dn = f64_column(df, "dn_dac_per_ls2")?;
    let e = LinePlot {
        title: "Fig. 2e: contact area and largest cluster".into(),
        x_label: "W / W0".into(),
        y_label: "A_c / L²  and  largest A / λ_s²".into(),
        x_log: true,
        y_log: true,
        series: vec![
            Series {
                label: "A_c / L² (ensemble mean)".into(),
                points: w.iter().copied().zip(ac).collect(),
                color: 0,
                dashed: false,
            },
            Series {
                label: "largest cluster A / λ_s² (ensemble mean)".into(),
                points: w.iter().copied().zip(largest).collect(),
                color: 1,
                dashed: false,
            },
        ],
    };
    let f = LinePlot {
        title: "Fig. 2f: growth of the cluster count".into(),
        x_label: "W / W0".into(),
        y_label: "dN / d(A_c/λ_s²)".into(),
        x_log: true,
        y_log: false,
        series: vec![Series {
            label: "dN/dA_c (central differences of ensemble means)".into(),
            points: w.iter().copied().zip(dn).collect(),
            color: 0,
            dashed: false,
        }],
    };
    Ok(vec![("fig2e", e), ("fig2f", f)])
}

/// Thresholds A*/λ_s² drawn in Figs. 4b and 5.
const FIG45_A_STAR: [f64; 4] = [0.5, 2.0, 8.0, 32.0];

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
    Ok(FIG45_A_STAR
        .iter()
        .enumerate()
        .map(|(c, &t)| Series {
            label: format!("{label}, A*/λ_s² = {t}"),
            points: (0..a.len())
                .filter(|&i| a[i] == t)
                .map(|i| (w[i], v[i]))
                .collect(),
            color: c,
            dashed,
        })
        .collect())
}

/// Figs. 4b (K vs load), 5a (𝒦 vs load) and 5b (wear rate vs load), simulated (solid,
/// pooled over realizations) and from the fitted plateau + power-law model (dashed).
fn fig45(wear: &DataFrame, model: &DataFrame) -> anyhow::Result<Vec<(&'static str, LinePlot)>> {
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
    let plot = |title: &str, y: &str, y_log: bool, series| LinePlot {
        title: title.into(),
        x_label: "W / W0".into(),
        y_label: y.into(),
        x_log: true,
        y_log,
        series,
    };
    Ok(vec![
        (
            "fig4b",
            plot(
                "Fig. 4b: Archard's wear coefficient, λ_l/λ_s = 128",
                "K = P(A > A*)",
                false,
                k,
            ),
        ),
        (
            "fig5a",
            plot(
                "Fig. 5a: up-scaled wear coefficient, λ_l/λ_s = 128",
                "A_c* / A_c",
                false,
                kk,
            ),
        ),
        (
            "fig5b",
            plot(
                "Fig. 5b: wear rate (ω = 1/3), λ_l/λ_s = 128",
                "R / L²",
                true,
                rate,
            ),
        ),
    ])
}
