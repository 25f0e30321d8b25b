//! The stage contract ([`Stage`]), a stage behind its JSON job as the runner sees it
//! ([`DynStage`]), and the key of a job.

use std::marker::PhantomData;
use std::path::Path;

use serde::de::DeserializeOwned;
use serde::Serialize;
use serde_json::Value;

use crate::store::hash::instance_key;
use crate::store::inputs::{InputRef, Inputs};

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

/// A stage behind its JSON job, as the runner sees it.
pub trait DynStage: Sync {
    fn name(&self) -> &'static str;
    fn version(&self) -> u32;
    /// Check that `params` deserialise into the stage's job (a plan edited by hand, or one
    /// from another version of the program, is refused before any work).
    fn check(&self, params: &Value) -> anyhow::Result<()>;
    fn compute(&self, params: &Value, inputs: &Inputs, out: &Path) -> anyhow::Result<Value>;
}

/// A stage registered under its name (see [`crate::pipeline::registry`]).
pub struct Registered<S>(PhantomData<fn() -> S>);

impl<S> Registered<S> {
    pub const fn new() -> Self {
        Self(PhantomData)
    }
}

impl<S> Default for Registered<S> {
    fn default() -> Self {
        Self::new()
    }
}

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

/// `params` and key of a job of stage `S` with the given inputs.
pub fn keyed<S: Stage>(job: &S::Job, inputs: &[InputRef]) -> (Value, String) {
    let params = serde_json::to_value(job).expect("a stage job serialises to JSON");
    let keys: Vec<String> = inputs.iter().map(|r| r.key.clone()).collect();
    let key = instance_key(S::NAME, S::VERSION, &params, &keys);
    (params, key)
}
