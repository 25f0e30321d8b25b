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
