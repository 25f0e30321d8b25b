//! Integration tests (one binary to save link time).

mod analytic;
mod bad_input;
mod cli;
mod clusters;
mod config;
mod contact;
mod docs;
mod galleries;
mod layout;
mod measured_study;
mod plan;
mod plastic;
mod powerlaw;
mod spectrum;
mod stability;
mod stages;
mod store;
mod store_cli;
mod store_integrity;
mod submit;
mod surface;
mod topography;
mod window;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The repository root, read when the test runs (cargo sets `CARGO_MANIFEST_DIR` for test
/// processes): a target directory shared between clones (.ci/run's) may hold this binary
/// built from identical sources at another path, whose compile-time path is gone.
pub fn repo_root() -> PathBuf {
    std::env::var_os("CARGO_MANIFEST_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")))
}

/// The wearcoef binary built for these tests.
pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_wearcoef"))
}

/// Run wearcoef in `dir` with `args`; returns the output.
pub fn run_in(dir: &Path, args: &[&str]) -> Output {
    bin()
        .current_dir(dir)
        .args(args)
        .output()
        .expect("wearcoef runs")
}

/// Parse stdout as one JSON value.
pub fn stdout_json(out: &Output) -> serde_json::Value {
    let text = String::from_utf8_lossy(&out.stdout);
    serde_json::from_str(text.trim()).unwrap_or_else(|e| {
        panic!(
            "stdout is not JSON ({e}): {text}\nstderr: {}",
            String::from_utf8_lossy(&out.stderr)
        )
    })
}

/// A small pipeline file with two studies, for store tests.
pub fn small_pipeline(hurst_b: f64, description_a: &str) -> String {
    format!(
        r#"schema_version: 1
material: {{e_star: 1.0}}
solver: {{tolerance: 1.0e-10, max_iterations: 1000}}
profiles: {{t: "test"}}
studies:
  a:
    description: "{description_a}"
    hurst: 0.8
    lambda_l_over_lambda_s: 4
    seed: 7
    loads: {{values: [0.01, 0.02]}}
    profiles:
      t: {{l_over_lambda_l: 2, lambda_s_over_dl: 8, realizations: 3}}
  b:
    hurst: {hurst_b}
    lambda_l_over_lambda_s: 4
    seed: 8
    loads: {{values: [0.01]}}
    profiles:
      t: {{l_over_lambda_l: 2, lambda_s_over_dl: 8, realizations: 2}}
figures:
  fig6: {{kind: fig6, profiles: [t]}}
"#
    )
}

/// A fresh temporary directory holding `pipeline.yaml` with `text`.
pub fn workdir(text: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(dir.path().join("pipeline.yaml"), text).expect("write pipeline");
    let path = dir.path().to_path_buf();
    (dir, path)
}

/// Every file under `dir`'s subdirectories `tops` (path relative to `dir` → bytes),
/// manifests excluded (they hold wall times).
pub fn files_under(dir: &Path, tops: &[&str]) -> std::collections::BTreeMap<String, Vec<u8>> {
    let mut out = std::collections::BTreeMap::new();
    for top in tops {
        let mut stack = vec![dir.join(top)];
        while let Some(d) = stack.pop() {
            for e in std::fs::read_dir(&d).unwrap() {
                let p = e.unwrap().path();
                if p.is_dir() {
                    stack.push(p);
                } else if p.file_name().unwrap() != "manifest.json" {
                    let rel = p.strip_prefix(dir).unwrap().display().to_string();
                    out.insert(rel, std::fs::read(&p).unwrap());
                }
            }
        }
    }
    out
}

/// A Parquet file as a data frame.
pub fn table(path: &Path) -> polars::prelude::DataFrame {
    use polars::prelude::SerReader;
    polars::prelude::ParquetReader::new(std::fs::File::open(path).unwrap())
        .finish()
        .unwrap()
}

/// A numeric column as f64, nulls as NaN.
pub fn f64s(df: &polars::prelude::DataFrame, name: &str) -> Vec<f64> {
    let c = df
        .column(name)
        .unwrap()
        .cast(&polars::prelude::DataType::Float64)
        .unwrap();
    c.f64()
        .unwrap()
        .iter()
        .map(|v| v.unwrap_or(f64::NAN))
        .collect()
}
