//! The plan's instances and how they are collected: one stage instance, deduplicated by key,
//! its level one above its deepest input's; the keys of a study that figures and audits read.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::config::StudyPlan;
use crate::pipeline::cost::Estimate;
use crate::pipeline::sources::SourceFile;
use crate::stages::{keyed, InputRef, Stage};

/// One stage instance of a plan.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Instance {
    pub stage: String,
    pub key: String,
    /// The job, as the stage reads it and the key hashes it.
    pub params: Value,
    /// Inputs in the order the stage reads them.
    pub inputs: Vec<InputRef>,
    /// Longest path from a source (surfaces and model curves are level 0): every input of
    /// an instance is on a lower level, so a level runs once the previous ones are done.
    pub level: usize,
    /// Studies of the profile that use this instance (several may share one).
    pub studies: Vec<String>,
    pub realization: Option<u32>,
    /// The figure or audit this instance draws or checks (figures and audits stages).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Whether the store holds it (set by [`Plan::mark`]).
    #[serde(default)]
    pub cached: bool,
    #[serde(default)]
    pub estimate: Estimate,
    /// A file the runner copies into the entry before computing it (a measured study's
    /// topography); its content, not its place, is in the key.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<SourceFile>,
}

impl Instance {
    /// The reference other instances use to name this one as an input.
    pub fn as_input(&self) -> InputRef {
        InputRef {
            stage: self.stage.clone(),
            key: self.key.clone(),
        }
    }
}

/// The keys of one study's instances that figures and audits read.
pub(super) struct StudyKeys<'a> {
    pub(super) plan: &'a StudyPlan,
    pub(super) surfaces: Vec<InputRef>,
    pub(super) contacts: Vec<InputRef>,
    pub(super) clusters: Vec<InputRef>,
    pub(super) statistics: InputRef,
    pub(super) analytic: InputRef,
}

/// Instances being collected, deduplicated by key.
#[derive(Default)]
pub(super) struct Builder {
    pub(super) out: Vec<Instance>,
    pub(super) index: BTreeMap<String, usize>,
}

impl Builder {
    /// Add an instance of `S` (or record more studies on the one with the same key).
    pub(super) fn add<S: Stage>(
        &mut self,
        job: &S::Job,
        inputs: Vec<InputRef>,
        studies: &[String],
        realization: Option<u32>,
        name: Option<&str>,
    ) -> InputRef {
        let (params, key) = keyed::<S>(job, &inputs);
        if let Some(&i) = self.index.get(&key) {
            let existing = &mut self.out[i];
            for s in studies {
                if !existing.studies.contains(s) {
                    existing.studies.push(s.clone());
                }
            }
        } else {
            let level = inputs
                .iter()
                .map(|r| self.out[self.index[&r.key]].level + 1)
                .max()
                .unwrap_or(0);
            self.index.insert(key.clone(), self.out.len());
            self.out.push(Instance {
                stage: S::NAME.to_string(),
                key: key.clone(),
                params,
                inputs,
                level,
                studies: studies.to_vec(),
                realization,
                name: name.map(str::to_string),
                cached: false,
                estimate: Estimate::default(),
                source: None,
            });
        }
        InputRef {
            stage: S::NAME.to_string(),
            key,
        }
    }
}
