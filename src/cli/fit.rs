//! `wearcoef fit`: the exponent of a table of cluster areas, per load, by both estimators
//! (the power law truncated at the largest area above x_min, and the plateau + power law of
//! Appendix A with its A_s and A_m).

use std::path::PathBuf;
use std::process::ExitCode;

use serde_json::json;
use wearcoef::tail::fit_row;

use super::checks::InputError;

#[derive(clap::Args)]
pub struct FitArgs {
    /// Parquet table of cluster areas, e.g. a clusters stage's clusters.parquet, or several
    /// concatenated; with a `load_index` column each load is fitted on its own (realizations
    /// pooled), and with a `percolating` column percolating clusters are left out, as the
    /// statistics stage does.
    #[arg(long)]
    pub areas: PathBuf,
    /// Column of areas in whole grid cells (integers ≥ 1).
    #[arg(long, default_value = "area_px")]
    pub column: String,
    /// Bootstrap resamples of the 95 % interval.
    #[arg(long, default_value_t = 200)]
    pub resamples: usize,
    /// Seed of the bootstrap.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Thresholds A* in grid cells (comma separated): per load, also the counted wear
    /// coefficients K = P(A > A*) (eq. 5) and 𝒦 = A_c*/A_c (eq. 7) of the same clusters
    /// (percolating ones left out, as the statistics stage does). From an area in λ_s²,
    /// multiply by (λ_s/Δl)².
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pub a_star: Vec<f64>,
    /// Column naming the realization of each cluster (tables of several realizations
    /// concatenated): with 5 or more, every interval is over whole realizations, each
    /// resample refitting x_min, A_s and the cut-off. Absent: intervals from the clusters.
    #[arg(long, default_value = "realization")]
    pub realization_column: String,
    #[arg(long)]
    pub json: bool,
}

/// α of a discrete power law truncated at the largest area, by maximum likelihood with
/// x_min chosen by the KS criterion (the statistics stage's `discrete_truncated_mle`).
/// The areas table and its column `column` as whole numbers of cells ≥ 1 (each error names
/// the file, the column and the row).
fn read_areas(
    areas: &std::path::Path,
    column: &str,
) -> anyhow::Result<(polars::prelude::DataFrame, Vec<u64>)> {
    use wearcoef::store::table;
    let df = table::read(areas)
        .map_err(|e| InputError(format!("--areas {}: {e:#}", areas.display())))?;
    let col = df.column(column).map_err(|_| {
        InputError(format!(
            "--areas {}: no column '{column}' (columns: {}); name the areas with --column",
            areas.display(),
            df.get_column_names()
                .iter()
                .map(|c| c.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ))
    })?;
    let values: Vec<Option<f64>> = col
        .cast(&polars::prelude::DataType::Float64)
        .map_err(|_| InputError(format!("--column {column}: not numeric")))?
        .f64()?
        .iter()
        .collect();
    let mut cells = Vec::with_capacity(values.len());
    for (i, v) in values.iter().enumerate() {
        match v {
            Some(x) if x.is_finite() && *x >= 1.0 && x.fract() == 0.0 && *x < 2f64.powi(53) => {
                cells.push(*x as u64)
            }
            _ => {
                return Err(InputError(format!(
                    "--areas {}: row {i} of '{column}' is {}; areas must be whole numbers of grid cells ≥ 1",
                    areas.display(),
                    v.map_or("null".to_string(), |x| x.to_string())
                ))
                .into())
            }
        }
    }
    Ok((df, cells))
}

/// One load's clusters: W/W0, the areas of the clusters that do not percolate, how many
/// percolating ones were left out, and the realization of each area (when the table says).
type LoadGroup = (f64, Vec<u64>, usize, Option<Vec<i64>>);

/// Per load (`load_index`, or one group without it).
type LoadGroups = std::collections::BTreeMap<Option<u32>, LoadGroup>;

fn group_by_load(
    df: &polars::prelude::DataFrame,
    cells: &[u64],
    realization_column: &str,
) -> anyhow::Result<LoadGroups> {
    use wearcoef::store::table;
    // Any integer type (pandas writes int64): cast, refusing what is not a load index.
    let loads: Vec<Option<u32>> = match df.column("load_index") {
        Ok(c) => c
            .strict_cast(&polars::prelude::DataType::UInt32)
            .map_err(|_| {
                InputError(format!(
                    "column 'load_index' ({}) must hold whole numbers from 0 to {}",
                    c.dtype(),
                    u32::MAX
                ))
            })?
            .u32()?
            .iter()
            .collect(),
        Err(_) => vec![None; df.height()],
    };
    let w: Vec<f64> =
        table::f64_column(df, "w_over_w0").unwrap_or_else(|_| vec![f64::NAN; df.height()]);
    let percolating: Vec<bool> =
        table::bool_column(df, "percolating").unwrap_or_else(|_| vec![false; df.height()]);
    let realization: Option<Vec<i64>> = match df.column(realization_column) {
        Ok(c) => Some(
            c.strict_cast(&polars::prelude::DataType::Int64)
                .map_err(|_| {
                    InputError(format!(
                        "column '{realization_column}' ({}) must hold whole numbers naming each cluster's realization",
                        c.dtype()
                    ))
                })?
                .i64()?
                .iter()
                .map(|v| v.unwrap_or(-1))
                .collect(),
        ),
        Err(_) => None,
    };
    let mut groups = LoadGroups::default();
    for i in 0..cells.len() {
        let g = groups.entry(loads[i]).or_insert((
            w[i],
            Vec::new(),
            0,
            realization.as_ref().map(|_| Vec::new()),
        ));
        if percolating[i] {
            g.2 += 1;
        } else {
            g.1.push(cells[i]);
            if let (Some(ids), Some(r)) = (g.3.as_mut(), realization.as_ref()) {
                ids.push(r[i]);
            }
        }
    }
    Ok(groups)
}

/// Intervals over whole realizations, added to `row`: α by both estimators (each
/// resample refitting x_min and the cut-off, or A_s and A_m), and K, 𝒦 at each A* (within
/// [0, 1]); with fewer than 5 realizations, none, and `ci95_method` says why.
fn over_realizations(
    row: &mut serde_json::Value,
    data: &[u64],
    ids: &[i64],
    a_star: &[f64],
    resamples: usize,
    seed: u64,
) {
    use wearcoef::powerlaw;
    use wearcoef::resample::{self, NoInterval};
    let mut by: std::collections::BTreeMap<i64, Vec<u64>> = Default::default();
    for (&a, &r) in data.iter().zip(ids) {
        by.entry(r).or_default().push(a);
    }
    let groups: Vec<Vec<u64>> = by.into_values().collect();
    let pooled =
        |g: &[&Vec<u64>]| -> Vec<u64> { g.iter().flat_map(|v| v.iter().copied()).collect() };
    let truncated = |g: &[&Vec<u64>]| -> Option<f64> {
        powerlaw::fit_tail_at_max(&pooled(g))
            .ok()
            .map(|t| t.fit.alpha)
    };
    let plateau = |g: &[&Vec<u64>]| -> Option<f64> {
        powerlaw::fit_plateau_power_law(&pooled(g))
            .ok()
            .map(|p| p.alpha)
    };
    let put = |row: &mut serde_json::Value, ci: Result<resample::Interval, NoInterval>| match ci {
        Ok(c) => {
            row["realization_ci95_low"] = json!(c.low);
            row["realization_ci95_high"] = json!(c.high);
            row["ci95_method"] = json!(resample::METHOD);
        }
        Err(e) => row["ci95_method"] = json!(e.reason()),
    };
    row["realizations"] = json!(groups.len());
    put(
        row,
        resample::over_realizations(&groups, &truncated, resamples, seed, None),
    );
    put(
        &mut row["plateau"],
        resample::over_realizations(&groups, &plateau, resamples, seed, None),
    );
    for (k, &a) in a_star.iter().enumerate() {
        let wear = |g: &[&Vec<u64>], upscaled: bool| -> Option<f64> {
            let m = wearcoef::statistics::wear_at(&pooled(g), a);
            let v = if upscaled { m.k_upscaled } else { m.k_archard };
            v.is_finite().then_some(v)
        };
        let unit = Some((0.0, 1.0));
        let k_ci = resample::over_realizations(&groups, &|g| wear(g, false), resamples, seed, unit);
        let ku_ci = resample::over_realizations(&groups, &|g| wear(g, true), resamples, seed, unit);
        let smallest = groups
            .iter()
            .map(|g| g.iter().filter(|&&x| x as f64 > a).count())
            .min()
            .unwrap_or(0);
        let m = &mut row["wear"][k];
        m["clusters_above_smallest_realization"] = json!(smallest);
        for (name, ci) in [("k_archard", k_ci), ("k_upscaled", ku_ci)] {
            match ci {
                Ok(c) => {
                    m[format!("{name}_ci95_low")] = json!(c.low);
                    m[format!("{name}_ci95_high")] = json!(c.high);
                }
                Err(e) => m[format!("{name}_ci95_method")] = json!(e.reason()),
            }
        }
    }
}

/// `fit`'s rows as text, one line per load.
fn print_fit_rows(out: &[serde_json::Value]) -> anyhow::Result<()> {
    for r in out {
        let load = r["load_index"]
            .as_u64()
            .map_or("all".to_string(), |l| format!("load {l}"));
        match r["alpha"].as_f64() {
                Some(a) => out!(
                    "{load}: α = {a:.4} ± {:.4} (95 % bootstrap [{:.4}, {:.4}]), x_min = {} px, x_max = {} px, {} of {} clusters fitted, KS {:.4}",
                    r["std_error"].as_f64().unwrap_or(f64::NAN),
                    r["bootstrap_ci95_low"].as_f64().unwrap_or(f64::NAN),
                    r["bootstrap_ci95_high"].as_f64().unwrap_or(f64::NAN),
                    r["x_min_px"],
                    r["x_max_px"],
                    r["n_fitted"],
                    r["clusters"],
                    r["ks_distance"].as_f64().unwrap_or(f64::NAN),
                )?,
                None => out!("{load}: {} ({} clusters)", r["note"].as_str().unwrap_or(""), r["clusters"])?,
            }
        let p = &r["plateau"];
        match p["alpha"].as_f64() {
            Some(a) => out!(
                "{load}: plateau + power law (Appendix A): α = {a:.4} (95 % profile likelihood [{:.4}, {:.4}]), A_s = {:.2} px, A_m = {} px",
                p["profile_ci95_low"].as_f64().unwrap_or(f64::NAN),
                p["profile_ci95_high"].as_f64().unwrap_or(f64::NAN),
                p["a_s_px"].as_f64().unwrap_or(f64::NAN),
                p["a_m_px"],
            )?,
            None => out!("{load}: plateau + power law: {}", p["note"].as_str().unwrap_or(""))?,
        }
        for m in r["wear"].as_array().into_iter().flatten() {
            out!(
                "{load}: A* = {} px: K = {:.6}, 𝒦 = {:.6}",
                m["a_star_px"],
                m["k_archard"].as_f64().unwrap_or(f64::NAN),
                m["k_upscaled"].as_f64().unwrap_or(f64::NAN),
            )?;
        }
    }
    Ok(())
}

pub fn fit(args: FitArgs) -> anyhow::Result<ExitCode> {
    let FitArgs {
        areas,
        column,
        resamples,
        seed,
        a_star,
        realization_column,
        json,
    } = args;
    if let Some(bad) = a_star.iter().find(|a| !(a.is_finite() && **a >= 0.0)) {
        return Err(InputError(format!(
            "--a-star {bad}: thresholds are areas in grid cells, finite and ≥ 0"
        ))
        .into());
    }
    wearcoef::ranges::RESAMPLES
        .check_count("--resamples", resamples as u64)
        .map_err(InputError)?;
    let is_parquet = areas.extension().is_some_and(|e| e == "parquet");
    if !is_parquet {
        return Err(InputError(format!(
            "--areas {}: expected a .parquet table (a clusters stage's clusters.parquet, or a table with an integer column of areas)",
            areas.display()
        ))
        .into());
    }
    let (df, cells) = read_areas(&areas, &column)?;
    let groups = group_by_load(&df, &cells, &realization_column)?;
    let out: Vec<serde_json::Value> = groups
        .into_iter()
        .map(|(load, (w, data, excluded, ids))| {
            let mut row = fit_row(load, w, &data, excluded, resamples, seed);
            row["wear"] = a_star
                .iter()
                .map(|&a| {
                    let m = wearcoef::statistics::wear_at(&data, a);
                    json!({"a_star_px": a, "k_archard": m.k_archard,
                           "k_upscaled": m.k_upscaled, "area_above_px": m.area_above_px,
                           "clusters_above": data.iter().filter(|&&x| x as f64 > a).count()})
                })
                .collect();
            if let Some(ids) = ids {
                over_realizations(&mut row, &data, &ids, &a_star, resamples, seed);
            }
            row
        })
        .collect();
    if json {
        out!("{}", serde_json::to_string(&out)?)?;
    } else {
        print_fit_rows(&out)?;
    }
    Ok(ExitCode::SUCCESS)
}
