//! The per-profile catalog: `D/<profile>/index.parquet` and `index.csv`, one row per
//! artifact file, so that nobody needs a hash to find data.
//!
//! Columns: `stage`, `study`, `realization`, `file`, `path` (relative to the working
//! directory the run was started in), `key`, then every stage parameter and every scalar
//! result recorded in the manifest, typed (UInt64 / Int64 / Float64 / Boolean / String;
//! null where a column does not apply to a stage).

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use polars::prelude::*;
use serde_json::Value;

/// One catalog row: fixed fields plus typed extra columns.
#[derive(Debug, Clone)]
pub struct Row {
    pub stage: String,
    pub study: String,
    pub realization: Option<u32>,
    pub file: String,
    pub path: String,
    pub key: String,
    pub extra: BTreeMap<String, Value>,
}

enum Kind {
    Bool,
    UInt,
    Int,
    Float,
    Text,
}

fn kind_of(values: &[Option<&Value>]) -> Kind {
    let present: Vec<&Value> = values.iter().flatten().copied().collect();
    if present.is_empty() {
        return Kind::Text;
    }
    if present.iter().all(|v| v.is_boolean()) {
        Kind::Bool
    } else if present.iter().all(|v| v.is_u64()) {
        Kind::UInt
    } else if present.iter().all(|v| v.is_i64() || v.is_u64())
        && present.iter().all(|v| v.as_i64().is_some())
    {
        Kind::Int
    } else if present.iter().all(|v| v.is_number()) {
        Kind::Float
    } else {
        Kind::Text
    }
}

fn text(v: &Value) -> String {
    match v {
        Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// Build the catalog frame.
pub fn frame(rows: &[Row]) -> PolarsResult<DataFrame> {
    let mut columns = vec![
        Column::new(
            "stage".into(),
            rows.iter().map(|r| r.stage.clone()).collect::<Vec<_>>(),
        ),
        Column::new(
            "study".into(),
            rows.iter().map(|r| r.study.clone()).collect::<Vec<_>>(),
        ),
        Column::new(
            "realization".into(),
            rows.iter().map(|r| r.realization).collect::<Vec<_>>(),
        ),
        Column::new(
            "file".into(),
            rows.iter().map(|r| r.file.clone()).collect::<Vec<_>>(),
        ),
        Column::new(
            "path".into(),
            rows.iter().map(|r| r.path.clone()).collect::<Vec<_>>(),
        ),
        Column::new(
            "key".into(),
            rows.iter().map(|r| r.key.clone()).collect::<Vec<_>>(),
        ),
    ];
    let names: BTreeSet<&String> = rows.iter().flat_map(|r| r.extra.keys()).collect();
    for name in names {
        let values: Vec<Option<&Value>> = rows
            .iter()
            .map(|r| r.extra.get(name).filter(|v| !v.is_null()))
            .collect();
        let col = match kind_of(&values) {
            Kind::Bool => Column::new(
                name.into(),
                values
                    .iter()
                    .map(|v| v.and_then(Value::as_bool))
                    .collect::<Vec<_>>(),
            ),
            Kind::UInt => Column::new(
                name.into(),
                values
                    .iter()
                    .map(|v| v.and_then(Value::as_u64))
                    .collect::<Vec<_>>(),
            ),
            Kind::Int => Column::new(
                name.into(),
                values
                    .iter()
                    .map(|v| v.and_then(Value::as_i64))
                    .collect::<Vec<_>>(),
            ),
            Kind::Float => Column::new(
                name.into(),
                values
                    .iter()
                    .map(|v| v.and_then(Value::as_f64))
                    .collect::<Vec<_>>(),
            ),
            Kind::Text => Column::new(
                name.into(),
                values.iter().map(|v| v.map(text)).collect::<Vec<_>>(),
            ),
        };
        columns.push(col);
    }
    DataFrame::new(rows.len(), columns)
}

/// Write `dir/index.parquet` and `dir/index.csv` atomically (temporary file + rename).
pub fn write(dir: &Path, rows: &[Row]) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir)?;
    let mut df = frame(rows)?;
    let tag = format!("{}-{}", std::process::id(), unique());

    let parquet = dir.join("index.parquet");
    let tmp = dir.join(format!(".index.parquet.{tag}"));
    {
        let file = std::fs::File::create(&tmp)?;
        ParquetWriter::new(file).finish(&mut df)?;
    }
    std::fs::rename(&tmp, &parquet)?;

    let csv_path = dir.join("index.csv");
    let tmp = dir.join(format!(".index.csv.{tag}"));
    {
        let mut w = csv::Writer::from_path(&tmp)?;
        let names: Vec<String> = df
            .get_column_names()
            .iter()
            .map(|s| s.to_string())
            .collect();
        w.write_record(&names)?;
        for i in 0..df.height() {
            let record: Vec<String> = df
                .columns()
                .iter()
                .map(|c| match c.get(i) {
                    Ok(AnyValue::Null) | Err(_) => String::new(),
                    Ok(AnyValue::String(s)) => s.to_string(),
                    Ok(AnyValue::Float64(f)) => format!("{f:?}"),
                    Ok(v) => v.to_string(),
                })
                .collect();
            w.write_record(&record)?;
        }
        w.flush()?;
    }
    std::fs::rename(&tmp, &csv_path)?;
    Ok(())
}

fn unique() -> u128 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos())
        .unwrap_or(0)
}
