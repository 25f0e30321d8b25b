//! The stored inputs of a stage instance, as the stage reads them.

use std::path::PathBuf;

use polars::prelude::DataFrame;
use serde::{Deserialize, Serialize};

use super::base::{Manifest, Store};

/// A reference to a stage instance: its stage and key.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct InputRef {
    pub stage: String,
    pub key: String,
}

/// The stored inputs of an instance, in the order the plan lists them.
pub struct Inputs<'a> {
    store: &'a Store,
    entries: Vec<(InputRef, Manifest)>,
}

impl<'a> Inputs<'a> {
    /// Look every input up in the store; an input that is absent is an error naming it.
    pub fn load(store: &'a Store, refs: &[InputRef]) -> anyhow::Result<Self> {
        let mut entries = Vec::with_capacity(refs.len());
        for r in refs {
            let manifest = store.lookup(&r.stage, &r.key)?.ok_or_else(|| {
                anyhow::anyhow!(
                    "input {} {} is missing from the store {}: run its stage first (wearcoef run)",
                    r.stage,
                    r.key,
                    store.root().display()
                )
            })?;
            entries.push((r.clone(), manifest));
        }
        Ok(Self { store, entries })
    }

    /// The content digest of every input, by key, as the manifest of an entry computed
    /// from them records it.
    pub fn digests(&self) -> std::collections::BTreeMap<String, String> {
        self.entries
            .iter()
            .map(|(r, m)| (r.key.clone(), m.content_digest()))
            .collect()
    }

    pub fn len(&self) -> usize {
        self.entries.len()
    }

    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// The manifest of input `i`.
    pub fn manifest(&self, i: usize) -> anyhow::Result<&Manifest> {
        self.entries.get(i).map(|e| &e.1).ok_or_else(|| {
            anyhow::anyhow!("input {i} is not in the plan (it lists {})", self.len())
        })
    }

    /// The manifest of input `i`, checked to come from `stage`.
    pub fn of(&self, i: usize, stage: &str) -> anyhow::Result<&Manifest> {
        let m = self.manifest(i)?;
        anyhow::ensure!(
            m.stage == stage,
            "input {i} is a {} instance where a {stage} instance was expected",
            m.stage
        );
        Ok(m)
    }

    /// Path of output `file` of input `i`, which must come from `stage` (hash not checked
    /// here; `wearcoef verify` does that).
    pub fn file(&self, i: usize, stage: &str, file: &str) -> anyhow::Result<PathBuf> {
        let m = self.of(i, stage)?;
        Ok(self.store.read_output(m, file)?)
    }

    /// Parquet table `file` of input `i` (from `stage`).
    pub fn table(&self, i: usize, stage: &str, file: &str) -> anyhow::Result<DataFrame> {
        super::table::read(&self.file(i, stage, file)?)
    }
}
