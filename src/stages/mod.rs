//! The stage contract and the registry of stages.
//!
//! A stage is a pure function from a serialisable job and the stored outputs of its inputs
//! to files in a fresh directory. Its key is the SHA-256 of canonical JSON of
//! `{salt, stage, version, params, inputs}` ([`crate::pipeline::hash::instance_key`]), where
//! `params` is the job serialised: a parameter cannot change an output without being in the
//! key, and nothing but the job's own fields is. Input keys are not part of the job; the
//! plan lists them beside it (in the order the stage reads them), and they enter the key
//! through `inputs`.
//!
//! The runner knows no stage by name: it looks the instance's stage up in [`REGISTRY`],
//! which deserialises the job and calls [`Stage::compute`]. Adding a stage is one file
//! with a `Stage` impl, and one line in [`REGISTRY`].

use std::marker::PhantomData;
use std::path::{Path, PathBuf};

use polars::prelude::DataFrame;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::pipeline::hash::instance_key;
use crate::pipeline::store::{Manifest, Store};

pub mod analytic;
pub mod audits;
pub mod clusters;
pub mod contact;
pub mod figures;
pub mod statistics;
pub mod surface;

/// One stage of the pipeline.
pub trait Stage: 'static {
    /// Directory name under `cache/` and the `stage` of manifests and catalogs.
    const NAME: &'static str;
    /// Bump when the stage's algorithm or outputs change: every key of the stage changes.
    const VERSION: u32;
    /// Exactly what the stage reads besides its inputs: its serialisation is the key's
    /// `params` and the manifest's `params`.
    type Job: Serialize + DeserializeOwned;
    /// Compute the instance into `out` (an empty temporary directory); returns the results
    /// recorded in the manifest.
    fn compute(job: &Self::Job, inputs: &Inputs, out: &Path) -> anyhow::Result<Value>;
}

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
        crate::pipeline::table::read(&self.file(i, stage, file)?)
    }

    /// Indices of the inputs from `stage`, in plan order.
    pub fn indices_of(&self, stage: &str) -> Vec<usize> {
        (0..self.len())
            .filter(|&i| self.entries[i].0.stage == stage)
            .collect()
    }

    /// The store the inputs live in (for stages that read an input's own inputs).
    pub fn store(&self) -> &Store {
        self.store
    }
}

/// A stage behind its JSON job, as the runner sees it.
pub trait DynStage: Sync {
    fn name(&self) -> &'static str;
    fn version(&self) -> u32;
    /// Check that `params` deserialise into the stage's job (a plan edited by hand, or one
    /// from another version of the program, is refused before any work).
    fn check(&self, params: &Value) -> anyhow::Result<()>;
    fn compute(&self, params: &Value, inputs: &Inputs, out: &Path) -> anyhow::Result<Value>;
}

struct Registered<S>(PhantomData<fn() -> S>);

fn job_of<S: Stage>(params: &Value) -> anyhow::Result<S::Job> {
    serde_json::from_value(params.clone())
        .map_err(|e| anyhow::anyhow!("parameters of a {} instance: {e}", S::NAME))
}

impl<S: Stage> DynStage for Registered<S> {
    fn name(&self) -> &'static str {
        S::NAME
    }
    fn version(&self) -> u32 {
        S::VERSION
    }
    fn check(&self, params: &Value) -> anyhow::Result<()> {
        job_of::<S>(params).map(|_| ())
    }
    fn compute(&self, params: &Value, inputs: &Inputs, out: &Path) -> anyhow::Result<Value> {
        S::compute(&job_of::<S>(params)?, inputs, out)
    }
}

/// Every stage, in the order a run's levels usually list them.
pub static REGISTRY: &[&dyn DynStage] = &[
    &Registered::<surface::Surface>(PhantomData),
    &Registered::<contact::Contact>(PhantomData),
    &Registered::<clusters::Clusters>(PhantomData),
    &Registered::<statistics::Statistics>(PhantomData),
    &Registered::<analytic::Analytic>(PhantomData),
    &Registered::<audits::Audits>(PhantomData),
    &Registered::<figures::Figures>(PhantomData),
];

/// The registered stage called `name`.
pub fn find(name: &str) -> Option<&'static dyn DynStage> {
    REGISTRY.iter().copied().find(|s| s.name() == name)
}

/// Names of every registered stage, in registry order.
pub fn names() -> Vec<&'static str> {
    REGISTRY.iter().map(|s| s.name()).collect()
}

/// `params` and key of a job of stage `S` with the given inputs.
pub fn keyed<S: Stage>(job: &S::Job, inputs: &[InputRef]) -> (Value, String) {
    let params = serde_json::to_value(job).expect("a stage job serialises to JSON");
    let keys: Vec<String> = inputs.iter().map(|r| r.key.clone()).collect();
    let key = instance_key(S::NAME, S::VERSION, &params, &keys);
    (params, key)
}
