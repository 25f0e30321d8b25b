//! Parquet tables: reading, writing and the column helpers every stage uses.

use std::path::Path;

use polars::prelude::*;

/// Read a Parquet file.
pub fn read(path: &Path) -> anyhow::Result<DataFrame> {
    let file = std::fs::File::open(path).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    Ok(ParquetReader::new(file).finish()?)
}

/// Write `df` as `dir/name`.
pub fn write(dir: &Path, name: &str, mut df: DataFrame) -> anyhow::Result<()> {
    let file = std::fs::File::create(dir.join(name))?;
    ParquetWriter::new(file).finish(&mut df)?;
    Ok(())
}

/// A named column from a vector (any type polars stores, options for nulls).
pub fn col<T>(name: &str, values: Vec<T>) -> Column
where
    Series: NamedFrom<Vec<T>, [T]>,
{
    Column::new(name.into(), values)
}

/// The two columns every per-load table starts with: `load_index` (0, 1, …) and
/// `w_over_w0`.
pub fn load_columns(loads: &[f64]) -> [Column; 2] {
    [
        col("load_index", (0..loads.len() as u32).collect::<Vec<_>>()),
        col("w_over_w0", loads.to_vec()),
    ]
}

/// A float column, nulls as NaN.
pub fn f64_column(df: &DataFrame, name: &str) -> anyhow::Result<Vec<f64>> {
    Ok(df
        .column(name)?
        .f64()?
        .iter()
        .map(|v| v.unwrap_or(f64::NAN))
        .collect())
}

/// A `u32` column with its nulls.
pub fn u32_column(df: &DataFrame, name: &str) -> anyhow::Result<Vec<Option<u32>>> {
    Ok(df.column(name)?.u32()?.iter().collect())
}

/// A `u64` column, nulls as 0.
pub fn u64_column(df: &DataFrame, name: &str) -> anyhow::Result<Vec<u64>> {
    Ok(df
        .column(name)?
        .u64()?
        .iter()
        .map(|v| v.unwrap_or(0))
        .collect())
}

/// A boolean column, nulls as false.
pub fn bool_column(df: &DataFrame, name: &str) -> anyhow::Result<Vec<bool>> {
    Ok(df
        .column(name)?
        .bool()?
        .iter()
        .map(|v| v.unwrap_or(false))
        .collect())
}

/// A string column, nulls as "".
pub fn str_column(df: &DataFrame, name: &str) -> anyhow::Result<Vec<String>> {
    Ok(df
        .column(name)?
        .str()?
        .iter()
        .map(|v| v.unwrap_or("").to_string())
        .collect())
}

/// Distinct loads `(load_index, W/W0)` of a table with those columns, in order of first
/// appearance.
pub fn loads_of(df: &DataFrame) -> anyhow::Result<Vec<(u32, f64)>> {
    let idx = u32_column(df, "load_index")?;
    let w = f64_column(df, "w_over_w0")?;
    let mut out: Vec<(u32, f64)> = Vec::new();
    for (i, w) in idx.into_iter().zip(w) {
        let Some(i) = i else { continue };
        if !out.iter().any(|(j, _)| *j == i) {
            out.push((i, w));
        }
    }
    Ok(out)
}

/// The unit of a column of any table the pipeline writes, by name (docs/CONVENTIONS.md):
/// written into every Parquet file's metadata (`wearcoef.units`). `None` for a name this
/// list does not know; the client test fails on any column without a unit.
pub fn unit_of(column: &str) -> Option<&'static str> {
    // A band's ends, and an interval's half-width, have the unit of the quantity.
    for suffix in ["_ci95_low", "_ci95_high", "_ci95"] {
        if let Some(base) = column.strip_suffix(suffix) {
            if !base.is_empty() && base != "pdf" && base != "ccdf" {
                if let Some(u) = unit_of(&format!("{base}_mean")).or_else(|| unit_of(base)) {
                    return Some(u);
                }
            }
        }
    }
    named_unit(column)
}

/// The unit of a column named in full (not by a band's suffix).
fn named_unit(column: &str) -> Option<&'static str> {
    let unit = match column {
        // Where a row comes from.
        "realization" | "load_index" | "bin" | "cluster_id" | "count_peak_load_index" => "index",
        "stage" | "study" | "studies" | "profile" | "file" | "path" | "key" | "estimator"
        | "ci95_method" | "note" | "tail_verdict" | "kind" | "curve" | "alpha_estimator"
        | "panel" | "series" | "x_quantity" | "y_quantity" | "status" | "error_message"
        | "state" | "failure" | "solver_status" => "text",
        "last_error" => "1 (relative complementarity error)",
        "converged" | "hollow" | "percolating" | "at_transition" | "within_rule" | "cached"
        | "saturated" => "boolean",
        // Loads and pressures.
        "w_over_w0" | "count_peak_w_over_w0" => "W₀ = E*·h′rms·L²",
        "mean_pressure" | "hardness_pressure" => "E*",
        // The hardness 𝓗 of a study, in the units of W/W0 (p̄/𝓗 = (W/W0)/hardness).
        "hardness" => "E*·h′rms",
        "inverse_hardness" => "1 (E*·h′rms/𝓗; 0: elastic)",
        "w_over_w0_solved" | "w_over_w0_lowest" | "w_over_w0_highest" => "W₀ = E*·h′rms·L²",
        // The load where dN/dA_c changes sign: 0 below the sweep, inf above it.
        "w_over_w0_sign_change" => {
            "W₀ = E*·h′rms·L² (0: before the lowest load, inf: after the highest, NaN: undefined)"
        }
        // Areas, lengths and counts on the grid.
        "area_px" | "width_px" | "k_min_px" | "k_max_px" | "k_s_px" | "n_contact_px" => {
            "Δl² (grid cells)"
        }
        "perimeter_px" | "extent_x_px" | "extent_y_px" => "Δl (grid spacings)",
        "n_clusters"
        | "n_clusters_reference"
        | "n_percolating"
        | "n_fitted"
        | "count_pooled"
        | "iterations"
        | "convolutions"
        | "realizations"
        | "realizations_percolating"
        | "n_clusters_mean"
        | "n_clusters_ci95" => "count",
        "dn_dac_per_ls2" | "dn_dac_per_ls2_mean" => "clusters per λₛ² of contact area",
        "pdf_pooled" | "pdf_mean" | "pdf_ci95" | "pdf_ci95_low" | "pdf_ci95_high" => {
            "1/λₛ² (density of A/λₛ²)"
        }
        "clusters" | "clusters_above" | "clusters_above_smallest_realization" => "count",
        "wear_rate_over_l2_mean" | "wear_rate_over_l2_ci95" => {
            "L² (worn volume per sliding distance, ω = 1/3)"
        }
        // Dimensionless ratios and fractions.
        "alpha" | "alpha_reference" | "alpha_difference" | "alpha_above_k_min" | "std_error"
        | "ci95_low" | "ci95_high" | "ks_distance" | "gof_p" | "ks_critical_95" | "ccdf"
        | "ccdf_mean" | "ccdf_ci95" | "ccdf_ci95_low" | "ccdf_ci95_high" | "error"
        | "area_fraction" | "area_fraction_mean" | "area_fraction_ci95" | "k_pl"
        | "k_upscaled_pl" | "k_pl_plateau" | "k_pl_at_load" | "a_star_over_a_s"
        | "a_m_over_a_s" => "1",
        "area_max_rel_deviation"
        | "area_max_rel_ci95"
        | "count_max_rel_deviation"
        | "count_max_rel_ci95"
        | "largest_max_rel_deviation"
        | "largest_max_rel_ci95" => "1 (relative to the reference)",
        "error_over_ci95" | "neighbour_error_over_ci95" => "1 (in units of the 95 % CI)",
        "value" | "ci95" | "interpolated" | "neighbours" => "1 (the quantity named by curve)",
        "setting" => "1 (the study's varied parameter: λₛ/Δl, L/λₗ or n)",
        "x" => "the unit of x_quantity",
        "y" => "the unit of y_quantity",
        "lambda_l_over_lambda_s" | "lambda_s_over_dl" | "l_over_lambda_l" | "hurst" => "1",
        "n" => "grid cells per side",
        // Parameters and scalar results of manifests (the catalog's per-stage tables).
        "name" | "curves" | "source_estimator" | "audit" | "reference" | "connectivity"
        | "draw" | "figure" | "quantity" | "method" | "b1" => "text",
        "rule_met" => "boolean",
        "bytes" => "bytes",
        "seed" => "seed",
        "e_star" => "E*",
        "box_size" | "grid_spacing" | "mean_height" | "rms_height" => "L (box side)",
        "plateau_w_over_w0" | "inset_load" => "W₀ = E*·h′rms·L²",
        "fitted_loads"
        | "points"
        | "rows"
        | "chosen_loads"
        | "fine_loads"
        | "points_judged"
        | "points_at_transition"
        | "smallest_converged_realizations"
        | "tolerance_peak_load_steps"
        | "peak_tolerance_steps"
        | "loads_with_percolating_cluster"
        | "total_clusters"
        | "max_iterations"
        | "total_iterations"
        | "bootstrap_resamples"
        | "loads_with_exponent"
        | "min_tail"
        | "pdf_bins"
        | "pdf_rows" => "count",
        "chosen_largest_load_ratio"
        | "curve_tolerance"
        | "ks_tolerance"
        | "tolerance"
        | "tolerance_error_over_ci95"
        | "tolerance_rel_deviation"
        | "rms_slope"
        | "hurst_fit"
        | "omega"
        | "smallest_converged_setting" => "1",
        _ if column.ends_with("_seconds") => "s",
        _ if column.ends_with("_px") => "Δl (grid spacings)",
        _ if column.starts_with("k_archard") || column.starts_with("k_upscaled") => "1",
        // Likelihood-ratio tests: R/(σ√n) and its p-value.
        _ if column.starts_with("lr_") => "1",
        _ if column.ends_with("_over_ls2")
            || column.ends_with("_over_ls2_mean")
            || column.ends_with("_over_ls2_ci95") =>
        {
            "λₛ²"
        }
        _ => return None,
    };
    Some(unit)
}

/// Where the tables of a stage instance come from.
pub struct TableOrigin<'a> {
    pub stage: &'a str,
    pub key: &'a str,
    pub params: &'a serde_json::Value,
    /// The realization of a per-realization instance (surface, contact, clusters).
    pub realization: Option<u32>,
}

/// Rewrite every Parquet file of an instance's directory with the file-level key-value
/// metadata a reader needs to know what it holds (`wearcoef.stage`, `wearcoef.key`,
/// `wearcoef.params` as JSON, `wearcoef.units` as JSON column → unit, `wearcoef.program`),
/// and, for a per-realization instance, a leading `realization` column where the table has
/// none, so that concatenated tables keep where their rows came from.
pub fn stamp(dir: &Path, origin: &TableOrigin) -> anyhow::Result<()> {
    let mut names: Vec<std::path::PathBuf> = std::fs::read_dir(dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "parquet"))
        .collect();
    names.sort();
    for path in names {
        let mut df = read(&path)?;
        if let Some(r) = origin.realization {
            if df.column("realization").is_err() {
                let height = df.height();
                df.insert_column(0, col("realization", vec![r; height]))?;
            }
        }
        let mut kv = vec![
            ("wearcoef.stage".to_string(), origin.stage.to_string()),
            ("wearcoef.key".to_string(), origin.key.to_string()),
            ("wearcoef.params".to_string(), origin.params.to_string()),
        ];
        if let Some(r) = origin.realization {
            kv.push(("wearcoef.realization".to_string(), r.to_string()));
        }
        write_with_metadata(&path, df, kv)?;
    }
    Ok(())
}

/// This program's name and version, as tables record it (the git commit is in manifests
/// only, so that tables stay byte-identical across commits of one version).
pub fn program() -> String {
    format!("{} {}", env!("CARGO_PKG_NAME"), env!("CARGO_PKG_VERSION"))
}

/// Write `df` to `path` (through a temporary sibling and a rename) with `kv` plus the units of
/// its columns (`wearcoef.units`) and the program (`wearcoef.program`) as file metadata.
pub fn write_with_metadata(
    path: &Path,
    mut df: DataFrame,
    mut kv: Vec<(String, String)>,
) -> anyhow::Result<()> {
    let units: serde_json::Map<String, serde_json::Value> = df
        .get_column_names()
        .iter()
        .map(|c| {
            let unit = unit_of(c.as_str()).unwrap_or("");
            (c.to_string(), serde_json::Value::from(unit))
        })
        .collect();
    kv.push((
        "wearcoef.units".to_string(),
        serde_json::Value::Object(units).to_string(),
    ));
    kv.push(("wearcoef.program".to_string(), program()));
    kv.push(("ARROW:schema".to_string(), arrow_schema_with(&df, &kv)));
    crate::io::atomic::write_atomically(path, |tmp| {
        let file = std::fs::File::create(tmp)?;
        ParquetWriter::new(file)
            .with_key_value_metadata(Some(KeyValueMetadata::from_static(kv)))
            .finish(&mut df)?;
        Ok(())
    })
}

/// The `ARROW:schema` entry of a Parquet file of `df` (what polars writes itself: the Arrow IPC
/// schema message, length-prefixed, base64) with `kv` as the schema's metadata: Arrow readers
/// (pyarrow, pandas) take a file's schema metadata from there, not from the footer's
/// key-value pairs.
fn arrow_schema_with(df: &DataFrame, kv: &[(String, String)]) -> String {
    use base64::Engine as _;
    use polars_arrow::io::ipc::write::{default_ipc_fields, schema_to_bytes};
    let schema = df.schema().to_arrow(CompatLevel::newest());
    let metadata: polars_arrow::datatypes::Metadata = kv
        .iter()
        .map(|(k, v)| (k.as_str().into(), v.as_str().into()))
        .collect();
    let message = schema_to_bytes(
        &schema,
        &default_ipc_fields(schema.iter_values()),
        Some(&metadata),
    );
    let mut prefixed = Vec::with_capacity(message.len() + 8);
    prefixed.extend_from_slice(&[255u8, 255, 255, 255]);
    prefixed.extend_from_slice(&(message.len() as u32).to_le_bytes());
    prefixed.extend_from_slice(&message);
    base64::engine::general_purpose::STANDARD.encode(&prefixed)
}
