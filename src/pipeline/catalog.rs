//! The per-profile catalog under `D/<profile>/`, so that nobody needs a hash to find data:
//!
//! - `index.parquet` (and `index.csv`): one row per file of every stored instance of the
//!   profile, with columns that apply to every row: `profile`, `stage`, `studies` (the
//!   profile's studies that use the instance, space-separated; empty for shared model
//!   curves), `realization` (null for instances of a whole study), `name` (the figure or
//!   audit; null otherwise), `state` (`stored`, or `failed`: a computation that failed, whose
//!   only file is its record under `failed/`), `file`, `path` (relative to the store root
//!   `D`), `key`, `bytes`.
//! - `index_<stage>.parquet`: one row per instance of that stage: the same identifying
//!   columns (`path` is the entry's directory), the study's spectrum in the ratios the paper
//!   uses (`l_over_lambda_l`, `lambda_l_over_lambda_s`, `lambda_s_over_dl`, `hurst`) where
//!   the instance belongs to studies of one spectrum, then every scalar parameter and result
//!   of its manifest, typed; columns null in every row are left out.
//!
//! Every table records the profile and the store root's absolute path in its metadata
//! (`wearcoef.profile`, `wearcoef.store_root`) besides the units of its columns.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use polars::prelude::*;
use serde_json::Value;

use super::plan::Instance;
use crate::config::StudyPlan;
use crate::store::table;
use crate::store::Store;

/// The columns every catalog table starts with, for one instance.
#[derive(Debug, Clone)]
pub struct Ident {
    /// `stored`, or `failed` for an instance whose computation failed (its record under
    /// `failed/` is its only file).
    pub state: &'static str,
    pub stage: String,
    pub studies: Vec<String>,
    pub realization: Option<u32>,
    pub name: Option<String>,
    pub key: String,
}

/// One file of a stored instance.
#[derive(Debug, Clone)]
pub struct FileRow {
    pub ident: Ident,
    pub file: String,
    /// Relative to the store root.
    pub path: String,
    pub bytes: u64,
}

/// One stored instance, with its parameters and scalar results.
#[derive(Debug, Clone)]
pub struct InstanceRow {
    pub ident: Ident,
    /// The entry's directory, relative to the store root.
    pub path: String,
    pub extra: BTreeMap<String, Value>,
}

/// The catalog of one profile.
#[derive(Debug, Clone)]
pub struct Catalog {
    pub profile: String,
    /// Absolute path of the store root (the data directory).
    pub root: PathBuf,
    pub files: Vec<FileRow>,
    pub instances: Vec<InstanceRow>,
}

/// The spectrum of a study in the ratios the paper uses.
fn ratios(plan: &StudyPlan) -> [(&'static str, Value); 4] {
    let s = &plan.surface;
    [
        ("l_over_lambda_l", Value::from(s.n as f64 / s.lambda_l_px)),
        (
            "lambda_l_over_lambda_s",
            Value::from(s.lambda_l_px / s.lambda_s_px),
        ),
        ("lambda_s_over_dl", Value::from(s.lambda_s_px)),
        ("hurst", Value::from(s.hurst)),
    ]
}

impl Catalog {
    /// The catalog of the stored instances among `instances` (those of `profile`), with the
    /// spectrum of each study from `studies`.
    pub fn collect(
        store: &Store,
        profile: &str,
        instances: &[Instance],
        studies: &[StudyPlan],
    ) -> anyhow::Result<Self> {
        let root = std::path::absolute(store.root())?;
        let by_name: BTreeMap<&str, &StudyPlan> =
            studies.iter().map(|s| (s.name.as_str(), s)).collect();
        let mut files = Vec::new();
        let mut rows = Vec::new();
        for inst in instances {
            let Some(manifest) = store.lookup(&inst.stage, &inst.key)? else {
                if let Some(f) = store.failure(&inst.stage, &inst.key) {
                    let path = store.failure_path(&inst.stage, &inst.key);
                    let relative = Path::new("failed")
                        .join(&inst.stage)
                        .join(format!("{}.json", inst.key));
                    let ident = Ident {
                        state: "failed",
                        stage: inst.stage.clone(),
                        studies: inst.studies.clone(),
                        realization: inst.realization,
                        name: inst.name.clone(),
                        key: inst.key.clone(),
                    };
                    files.push(FileRow {
                        ident: ident.clone(),
                        file: format!("{}.json", inst.key),
                        path: relative.display().to_string(),
                        bytes: std::fs::metadata(&path).map_or(0, |m| m.len()),
                    });
                    let mut extra = BTreeMap::new();
                    extra.insert("failure".to_string(), Value::from(f.error));
                    if let Value::Object(report) = f.report {
                        extra.extend(report);
                    }
                    extra.insert("wall_seconds".into(), Value::from(f.wall_seconds));
                    rows.push(InstanceRow {
                        ident,
                        path: relative.display().to_string(),
                        extra,
                    });
                }
                continue;
            };
            let ident = Ident {
                state: "stored",
                stage: inst.stage.clone(),
                studies: inst.studies.clone(),
                realization: inst.realization,
                name: inst.name.clone(),
                key: inst.key.clone(),
            };
            let dir = Path::new("cache").join(&inst.stage).join(&inst.key);
            for (file, out) in &manifest.outputs {
                files.push(FileRow {
                    ident: ident.clone(),
                    file: file.clone(),
                    path: dir.join(file).display().to_string(),
                    bytes: out.bytes,
                });
            }
            let mut extra = BTreeMap::new();
            // The spectrum, where every study of the instance has the same one.
            let spectra: Vec<[(&str, Value); 4]> = inst
                .studies
                .iter()
                .filter_map(|s| by_name.get(s.as_str()))
                .filter(|p| p.measured.is_none())
                .map(|p| ratios(p))
                .collect();
            let numerical = !matches!(inst.stage.as_str(), "figures" | "audits");
            if numerical && !spectra.is_empty() && spectra.iter().all(|s| s == &spectra[0]) {
                for (k, v) in spectra[0].clone() {
                    extra.insert(k.to_string(), v);
                }
            }
            for source in [&manifest.params, &manifest.results] {
                if let Value::Object(map) = source {
                    for (k, v) in map {
                        let fixed = [
                            "profile",
                            "stage",
                            "studies",
                            "realization",
                            "name",
                            "path",
                            "key",
                        ];
                        if !v.is_object() && !v.is_array() && !fixed.contains(&k.as_str()) {
                            extra.insert(k.clone(), v.clone());
                        }
                    }
                }
            }
            extra.insert("wall_seconds".into(), Value::from(manifest.wall_seconds));
            rows.push(InstanceRow {
                ident,
                path: dir.display().to_string(),
                extra,
            });
        }
        Ok(Self {
            profile: profile.to_string(),
            root,
            files,
            instances: rows,
        })
    }

    fn ident_columns<'a>(&self, idents: impl Iterator<Item = &'a Ident> + Clone) -> Vec<Column> {
        let len = idents.clone().count();
        vec![
            table::col("profile", vec![self.profile.clone(); len]),
            table::col(
                "stage",
                idents.clone().map(|i| i.stage.clone()).collect::<Vec<_>>(),
            ),
            table::col(
                "studies",
                idents
                    .clone()
                    .map(|i| i.studies.join(" "))
                    .collect::<Vec<_>>(),
            ),
            table::col(
                "realization",
                idents.clone().map(|i| i.realization).collect::<Vec<_>>(),
            ),
            table::col(
                "name",
                idents.clone().map(|i| i.name.clone()).collect::<Vec<_>>(),
            ),
            table::col("state", idents.clone().map(|i| i.state).collect::<Vec<_>>()),
        ]
    }

    /// `index.parquet`: one row per file.
    pub fn files_frame(&self) -> PolarsResult<DataFrame> {
        let mut columns = self.ident_columns(self.files.iter().map(|r| &r.ident));
        columns.extend([
            table::col(
                "file",
                self.files
                    .iter()
                    .map(|r| r.file.clone())
                    .collect::<Vec<_>>(),
            ),
            table::col(
                "path",
                self.files
                    .iter()
                    .map(|r| r.path.clone())
                    .collect::<Vec<_>>(),
            ),
            table::col(
                "key",
                self.files
                    .iter()
                    .map(|r| r.ident.key.clone())
                    .collect::<Vec<_>>(),
            ),
            table::col(
                "bytes",
                self.files.iter().map(|r| r.bytes).collect::<Vec<_>>(),
            ),
        ]);
        DataFrame::new(self.files.len(), columns)
    }

    /// The stages with stored instances, in pipeline order.
    pub fn stages(&self) -> Vec<String> {
        let present: BTreeSet<&str> = self
            .instances
            .iter()
            .map(|r| r.ident.stage.as_str())
            .collect();
        crate::pipeline::registry::names()
            .into_iter()
            .filter(|s| present.contains(s))
            .map(str::to_string)
            .collect()
    }

    /// `index_<stage>.parquet`: one row per instance of `stage`.
    pub fn stage_frame(&self, stage: &str) -> PolarsResult<DataFrame> {
        let rows: Vec<&InstanceRow> = self
            .instances
            .iter()
            .filter(|r| r.ident.stage == stage)
            .collect();
        let mut columns = self.ident_columns(rows.iter().map(|r| &r.ident));
        columns.extend([
            table::col(
                "path",
                rows.iter().map(|r| r.path.clone()).collect::<Vec<_>>(),
            ),
            table::col(
                "key",
                rows.iter().map(|r| r.ident.key.clone()).collect::<Vec<_>>(),
            ),
        ]);
        let names: BTreeSet<&String> = rows.iter().flat_map(|r| r.extra.keys()).collect();
        for name in names {
            let values: Vec<Option<&Value>> = rows
                .iter()
                .map(|r| r.extra.get(name).filter(|v| !v.is_null()))
                .collect();
            if let Some(c) = typed_column(name, &values) {
                columns.push(c);
            }
        }
        // Columns that apply to no instance of the stage (`realization` of a study's
        // statistics, `name` of anything but figures and audits) are left out.
        columns.retain(|c| c.null_count() < rows.len() || rows.is_empty());
        DataFrame::new(rows.len(), columns)
    }

    /// The metadata every catalog table carries.
    fn metadata(&self) -> Vec<(String, String)> {
        vec![
            ("wearcoef.profile".into(), self.profile.clone()),
            (
                "wearcoef.store_root".into(),
                self.root.display().to_string(),
            ),
        ]
    }

    /// Write `dir/index.parquet`, `dir/index.csv` and `dir/index_<stage>.parquet` for every
    /// stage with stored instances, each atomically; per-stage tables of stages with none
    /// left are removed.
    pub fn write(&self, dir: &Path) -> anyhow::Result<()> {
        std::fs::create_dir_all(dir)?;
        let files = self.files_frame()?;
        table::write_with_metadata(&dir.join("index.parquet"), files.clone(), self.metadata())?;
        write_csv(&dir.join("index.csv"), &files)?;
        let stages = self.stages();
        for stage in crate::pipeline::registry::names() {
            let path = dir.join(format!("index_{stage}.parquet"));
            if stages.iter().any(|s| s == stage) {
                let mut kv = self.metadata();
                kv.push(("wearcoef.stage".into(), stage.to_string()));
                table::write_with_metadata(&path, self.stage_frame(stage)?, kv)?;
            } else if path.exists() {
                std::fs::remove_file(&path)?;
            }
        }
        Ok(())
    }
}

/// A typed column of JSON scalars: Boolean, UInt64, Int64, Float64 or String; `None` when
/// every value is null.
fn typed_column(name: &str, values: &[Option<&Value>]) -> Option<Column> {
    let present: Vec<&Value> = values.iter().flatten().copied().collect();
    if present.is_empty() {
        return None;
    }
    let name: PlSmallStr = name.into();
    // One column of `get` applied to every value (null stays null).
    fn of<T>(values: &[Option<&Value>], get: impl Fn(&Value) -> Option<T>) -> Vec<Option<T>> {
        values.iter().map(|v| v.and_then(&get)).collect()
    }
    let col = if present.iter().all(|v| v.is_boolean()) {
        Column::new(name, of(values, Value::as_bool))
    } else if present.iter().all(|v| v.is_u64()) {
        Column::new(name, of(values, Value::as_u64))
    } else if present.iter().all(|v| v.as_i64().is_some()) {
        Column::new(name, of(values, Value::as_i64))
    } else if present.iter().all(|v| v.is_number()) {
        Column::new(name, of(values, Value::as_f64))
    } else {
        Column::new(
            name,
            of(values, |v| {
                Some(match v {
                    Value::String(s) => s.clone(),
                    other => other.to_string(),
                })
            }),
        )
    };
    Some(col)
}

/// Write `df` as CSV (empty fields for nulls, floats in shortest round-trip form) through a
/// temporary sibling and a rename.
pub fn write_csv(path: &Path, df: &DataFrame) -> anyhow::Result<()> {
    crate::io::atomic::write_atomically(path, |tmp| {
        let mut w = csv::Writer::from_path(tmp)?;
        write_csv_to(&mut w, df)?;
        w.flush()?;
        Ok(())
    })
}

/// Write `df` as CSV records to `w`.
pub fn write_csv_to<W: std::io::Write>(
    w: &mut csv::Writer<W>,
    df: &DataFrame,
) -> anyhow::Result<()> {
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
    Ok(())
}

/// Check every catalog under the store root (`D/<profile>/index.parquet`) against the store:
/// each row's file exists at its path, belongs to the entry its key names and has the size
/// that entry's manifest records. Returns the number of rows checked and the problems.
pub fn verify(store: &Store) -> anyhow::Result<(usize, Vec<crate::store::EntryProblem>)> {
    use crate::store::EntryProblem;
    let mut checked = 0;
    let mut problems = Vec::new();
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(store.root())?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.join("index.parquet").is_file())
        .collect();
    dirs.sort();
    for dir in dirs {
        let index = dir.join("index.parquet");
        let problem = |reason: String| EntryProblem {
            path: index.display().to_string(),
            reason,
        };
        let df = match table::read(&index) {
            Ok(df) => df,
            Err(e) => {
                problems.push(problem(format!("unreadable catalog ({e:#})")));
                continue;
            }
        };
        let columns = ["stage", "key", "file", "path"].map(|c| table::str_column(&df, c));
        let [Ok(stages), Ok(keys), Ok(files), Ok(paths)] = columns else {
            problems.push(problem(
                "not a catalog of this version (no stage, key, file or path column): run `wearcoef run` to write it anew".into(),
            ));
            continue;
        };
        let bytes = table::u64_column(&df, "bytes").unwrap_or_default();
        let states = table::str_column(&df, "state").unwrap_or_default();
        for i in 0..df.height() {
            checked += 1;
            if states.get(i).is_some_and(|s| s == "failed") {
                if store.failure(&stages[i], &keys[i]).is_none() {
                    problems.push(problem(format!(
                        "row {i} ({}/{}): a failure the store no longer records",
                        stages[i], keys[i]
                    )));
                }
                continue;
            }
            let row = format!("row {i} ({}/{} {})", stages[i], &keys[i], files[i]);
            let expected = Path::new("cache")
                .join(&stages[i])
                .join(&keys[i])
                .join(&files[i]);
            if Path::new(&paths[i]) != expected {
                problems.push(problem(format!(
                    "{row}: path {} is not {} (relative to the store root)",
                    paths[i],
                    expected.display()
                )));
                continue;
            }
            let manifest = match store.lookup(&stages[i], &keys[i]) {
                Ok(Some(m)) => m,
                Ok(None) => {
                    problems.push(problem(format!("{row}: no such entry in the store")));
                    continue;
                }
                // A damaged entry is reported by the store's own check, once.
                Err(_) => continue,
            };
            match manifest.outputs.get(&files[i]) {
                None => problems.push(problem(format!("{row}: not an output of its entry"))),
                Some(out) if bytes.get(i).is_some_and(|b| *b != out.bytes) => {
                    problems.push(problem(format!(
                        "{row}: {} bytes in the catalog, {} in the manifest",
                        bytes[i], out.bytes
                    )))
                }
                Some(_) => {}
            }
        }
    }
    Ok((checked, problems))
}
