//! The store's types and the helpers its parts share: the store, an entry's manifest and
//! outputs, the errors, and reading an entry's directory.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::hash;

/// Name of the manifest file in every entry.
pub const MANIFEST: &str = "manifest.json";

/// Errors of the store.
#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    #[error("{path}: {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
    #[error("{0}")]
    Write(String),
    #[error("corrupt cache entry {path}: {reason}. Fix: run `wearcoef verify` to list damaged entries and `wearcoef clean --corrupt` to remove them; the next run rebuilds them")]
    Corrupt { path: String, reason: String },
}

pub(super) fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> StoreError + '_ {
    move |source| StoreError::Io {
        path: path.display().to_string(),
        source,
    }
}

/// One output file of an entry.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct OutputFile {
    pub sha256: String,
    pub bytes: u64,
}

/// Who wrote an entry.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct Program {
    pub name: String,
    pub version: String,
    pub git_commit: Option<String>,
}

impl Program {
    /// This build of wearcoef.
    pub fn current() -> Self {
        Self {
            name: env!("CARGO_PKG_NAME").to_string(),
            version: env!("CARGO_PKG_VERSION").to_string(),
            git_commit: option_env!("WEARCOEF_GIT_COMMIT")
                .filter(|s| !s.is_empty())
                .map(str::to_string),
        }
    }
}

/// `manifest.json`: everything needed to explain and check an entry.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    pub stage: String,
    pub version: u32,
    pub key: String,
    pub params: Value,
    pub inputs: Vec<String>,
    /// The [`Manifest::content_digest`] of each input (by key) when this entry was computed
    /// from it (absent in entries of older builds).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub input_digests: BTreeMap<String, String>,
    pub outputs: BTreeMap<String, OutputFile>,
    pub program: Program,
    pub wall_seconds: f64,
    /// CPU seconds the instance used on all its threads (absent in entries of older
    /// builds): what the cost model fits, since instances that run side by side share the
    /// cores and each one's wall time counts the others'.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cpu_seconds: Option<f64>,
    /// Peak resident memory of the process while this instance ran alone in it (absent
    /// when instances ran side by side, or in entries of older builds): what the cost
    /// model's memory estimate is checked against.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub peak_rss_bytes: Option<u64>,
    /// Stage-specific results (realised statistics, solver reports, ...).
    pub results: Value,
    /// SHA-256 of the canonical JSON of `results` and `wall_seconds`, so that `verify`
    /// notices an edited result (absent in entries of older builds).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub results_sha256: Option<String>,
}

impl Manifest {
    /// The hash `results_sha256` records.
    pub fn results_hash(&self) -> String {
        let v = serde_json::json!({"results": self.results, "wall_seconds": self.wall_seconds});
        hash::sha256_hex(hash::canonical_json(&v).as_bytes())
    }
}

/// The store rooted at a data directory.
#[derive(Debug, Clone)]
pub struct Store {
    pub(super) root: PathBuf,
}

/// A temporary entry being written; dropped without [`TempEntry::commit`] it is removed.
pub struct TempEntry {
    pub(super) dir: PathBuf,
    pub(super) final_dir: PathBuf,
    pub(super) committed: bool,
}

/// How a commit ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CommitOutcome {
    /// Our copy is now the entry.
    Stored,
    /// Another process stored the same key first; our identical copy was discarded.
    AlreadyPresent,
}

/// Result of checking one entry.
#[derive(Debug, Clone, Serialize)]
pub struct EntryProblem {
    pub path: String,
    pub reason: String,
}

pub(super) fn list_dirs(dir: &Path) -> Result<Vec<PathBuf>, StoreError> {
    if !dir.exists() {
        return Ok(Vec::new());
    }
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(io_err(dir))? {
        let entry = entry.map_err(io_err(dir))?;
        if entry.file_type().map_err(io_err(dir))?.is_dir() {
            out.push(entry.path());
        }
    }
    out.sort();
    Ok(out)
}

pub(super) fn read_manifest(dir: &Path) -> Result<Manifest, StoreError> {
    let path = dir.join(MANIFEST);
    let text = std::fs::read_to_string(&path).map_err(|e| StoreError::Corrupt {
        path: path.display().to_string(),
        reason: format!("manifest unreadable ({e})"),
    })?;
    serde_json::from_str(&text).map_err(|e| StoreError::Corrupt {
        path: path.display().to_string(),
        reason: format!("manifest is not valid ({e})"),
    })
}
