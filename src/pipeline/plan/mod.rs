//! The plan: every stage instance a profile needs, as a DAG built before anything runs.
//!
//! [`Plan::build`] turns the resolved studies and the profile's declared figures into
//! instances (stage, key, job parameters, inputs, level, the studies that use it), shared
//! instances once. [`Plan::mark`] then records which are already in a store and estimates
//! each one's cost ([`super::cost`]). Executors take a plan: the local runner
//! ([`super::runner`]) and `wearcoef exec`, which runs given instances of a plan JSON file.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::sources::measured_surfaces;

mod builder;
mod figures;

pub use super::sources::SourceFile;
use crate::config::{ExponentLoads, Pipeline, StudyPlan};
use crate::contact::interface::Interface;
use crate::stages::analytic::{Analytic, AnalyticJob};
use crate::stages::clusters::{Clusters, ClustersJob};
use crate::stages::contact::{Contact, ContactJob};
use crate::stages::statistics::{Statistics, StatisticsJob, A_STAR_OVER_LS2};
use crate::stages::surface::{Surface, SurfaceJob};
use crate::stages::{InputRef, Stage};
use crate::store::Store;
pub use builder::Instance;
use builder::{Builder, StudyKeys};

/// The instances of the `i`-th of `k` contiguous slices of `len` (`wearcoef exec --slice
/// I/K`): slices of `⌈len/k⌉`, the last ones shorter or empty.
pub fn slice_range(len: usize, i: usize, k: usize) -> std::ops::Range<usize> {
    let per = len.div_ceil(k.max(1));
    (i * per).min(len)..((i + 1) * per).min(len)
}

/// The instances of one profile.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Plan {
    pub profile: String,
    pub instances: Vec<Instance>,
}

impl Plan {
    /// Every instance of `profile` (or of the studies and figures named in `targets`; empty
    /// means all), in level order.
    pub fn build(
        pipeline: &Pipeline,
        origin: &str,
        profile: &str,
        targets: &[String],
    ) -> anyhow::Result<Self> {
        Self::build_whole(pipeline, origin, profile)?.targeted(pipeline, origin, targets)
    }

    /// The part of this (whole) plan that `targets` ask for (stage, study or figure names,
    /// each checked against the profile) with what they need; all of it for no target.
    pub fn targeted(
        &self,
        pipeline: &Pipeline,
        origin: &str,
        targets: &[String],
    ) -> anyhow::Result<Self> {
        let profile = self.profile.as_str();
        let plans = pipeline.plan(profile, origin)?;
        let figures = pipeline.figures_of(profile);
        for t in targets {
            let known = plans.iter().any(|p| &p.name == t)
                || figures.iter().any(|(n, _)| n == t)
                || crate::pipeline::registry::find(t).is_some();
            if !known {
                return Err(crate::pipeline::error::UsageError(format!(
                    "unknown target '{t}' for profile '{profile}': use a stage ({}), a study ({}) or a figure ({}) of this profile",
                    crate::pipeline::registry::names().join(", "),
                    plans.iter().map(|p| p.name.as_str()).collect::<Vec<_>>().join(", "),
                    figures.iter().map(|f| f.0).collect::<Vec<_>>().join(", "),
                ))
                .into());
            }
        }
        let mut instances = self.instances.clone();
        if !targets.is_empty() {
            instances = select(instances, targets);
        }
        instances.sort_by_key(|i| i.level);
        Ok(Self {
            profile: profile.to_string(),
            instances,
        })
    }

    /// Every instance of the profile: its studies' and its declared figures'.
    fn build_whole(pipeline: &Pipeline, origin: &str, profile: &str) -> anyhow::Result<Self> {
        let plans = pipeline.plan(profile, origin)?;
        let figures = pipeline.figures_of(profile);
        let mut b = Builder::default();
        let mut keys: Vec<StudyKeys> = Vec::new();
        for plan in &plans {
            let shown = exponent_interval_loads(plan, &plans, &figures, profile);
            keys.push(study_instances(&mut b, plan, shown)?);
        }
        for (name, decl) in &figures {
            figures::figure_instances(&mut b, name, decl, profile, &keys)?;
        }
        let mut instances = b.out;
        instances.sort_by_key(|i| i.level);
        Ok(Self {
            profile: profile.to_string(),
            instances,
        })
    }

    /// Record which instances the store holds, and estimate each one's cost from `model`.
    pub fn mark(&mut self, store: &Store, model: &super::cost::CostModel) -> anyhow::Result<()> {
        let surfaces: BTreeMap<String, Value> = self
            .instances
            .iter()
            .filter(|i| i.stage == Surface::NAME)
            .map(|i| (i.key.clone(), i.params.clone()))
            .collect();
        for inst in &mut self.instances {
            inst.cached = store.reusable(&inst.stage, &inst.key)?.is_some();
            let surface = inst.inputs.first().and_then(|r| surfaces.get(&r.key));
            inst.estimate = model.estimate(&inst.stage, &inst.params, surface);
        }
        Ok(())
    }

    /// The instance with the largest memory estimate.
    pub fn largest(&self) -> Option<&Instance> {
        self.instances.iter().max_by_key(|i| i.estimate.peak_bytes)
    }

    /// Refuse a plan whose largest instance needs more memory than `available` bytes.
    pub fn check_memory(&self, available: u64) -> anyhow::Result<()> {
        if let Some(i) = self.largest().filter(|i| i.estimate.peak_bytes > available) {
            return Err(crate::pipeline::error::UsageError(format!(
                "the {} instance {} (studies {}) needs about {:.1} GiB, more than this machine's {:.1} GiB: run it where there is more memory (wearcoef submit) or choose smaller sizes for profile {}",
                i.stage,
                &i.key[..12],
                i.studies.join(", "),
                i.estimate.peak_bytes as f64 / (1u64 << 30) as f64,
                available as f64 / (1u64 << 30) as f64,
                self.profile
            ))
            .into());
        }
        Ok(())
    }

    /// Number of levels.
    pub fn levels(&self) -> usize {
        self.instances
            .iter()
            .map(|i| i.level + 1)
            .max()
            .unwrap_or(0)
    }
}

/// The instances that build `targets` (stages, studies or figures by name) and everything
/// upstream of them.
fn select(all: Vec<Instance>, targets: &[String]) -> Vec<Instance> {
    let hit = |i: &Instance| {
        targets.iter().any(|t| {
            &i.stage == t || i.studies.contains(t) || i.name.as_deref() == Some(t.as_str())
        })
    };
    let by_key: BTreeMap<&str, &Instance> = all.iter().map(|i| (i.key.as_str(), i)).collect();
    let mut wanted: std::collections::BTreeSet<String> = Default::default();
    let mut stack: Vec<&Instance> = all.iter().filter(|i| hit(i)).collect();
    while let Some(i) = stack.pop() {
        if wanted.insert(i.key.clone()) {
            stack.extend(i.inputs.iter().filter_map(|r| by_key.get(r.key.as_str())));
        }
    }
    all.into_iter()
        .filter(|i| wanted.contains(&i.key))
        .collect()
}

/// A study's surface instances: generated from its seed, or its measured files read (each
/// hashed, and its shape taken, here) and attached as the instances' sources.
fn surface_instances(b: &mut Builder, plan: &StudyPlan) -> anyhow::Result<Vec<InputRef>> {
    let studies = std::slice::from_ref(&plan.name);
    let Some(m) = &plan.measured else {
        return Ok((0..plan.realizations)
            .map(|r| {
                let job = SurfaceJob::Generated(plan.surface_for(r));
                b.add::<Surface>(&job, vec![], studies, Some(r), None)
            })
            .collect());
    };
    let mut out = Vec::new();
    for (r, (job, source)) in measured_surfaces(m)?.into_iter().enumerate() {
        let surface = b.add::<Surface>(&job, vec![], studies, Some(r as u32), None);
        b.out[b.index[&surface.key]].source = Some(source);
        out.push(surface);
    }
    Ok(out)
}

/// The load indices of `plan`'s sweep at which the profile's figures show α̂ with its
/// interval: the union over the figures that use the study.
fn exponent_interval_loads(
    plan: &StudyPlan,
    plans: &[StudyPlan],
    figures: &[(&str, &crate::config::FigureDecl)],
    profile: &str,
) -> Vec<u32> {
    let mut out: Vec<u32> = Vec::new();
    let mut nearest =
        |loads: &[f64]| {
            out.extend(loads.iter().filter_map(|&w| {
                crate::statistics::nearest_in_log(&plan.loads, w).map(|i| i as u32)
            }))
        };
    for (_, decl) in figures.iter().filter(|f| f.1.uses(&plan.name, profile)) {
        match decl.exponent_loads(&plan.name) {
            ExponentLoads::Nowhere => {}
            ExponentLoads::Nearest(loads) => nearest(&loads),
            ExponentLoads::OfSparsestStudy => {
                let sparsest = plans
                    .iter()
                    .filter(|p| decl.uses(&p.name, profile))
                    .min_by_key(|p| p.loads.len());
                nearest(sparsest.map_or(&plan.loads, |p| &p.loads));
            }
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}

fn study_instances<'a>(
    b: &mut Builder,
    plan: &'a StudyPlan,
    exponent_interval_loads: Vec<u32>,
) -> anyhow::Result<StudyKeys<'a>> {
    let studies = std::slice::from_ref(&plan.name);
    let surfaces = surface_instances(b, plan)?;
    let window = match (&plan.measured, surfaces.first()) {
        (Some(_), Some(first)) => {
            let job = &b.out[b.index[&first.key]].params;
            let dim = |k: &str| job[k].as_u64().unwrap_or(0) as usize;
            Some([dim("rows"), dim("cols")])
        }
        _ => None,
    };
    // The configuration checked the hardness; from here on the interface carries it.
    let interface = Interface::from_hardness(plan.hardness)?;
    let (mut contacts, mut clusters) = (Vec::new(), Vec::new());
    for (r, surface) in surfaces.iter().enumerate() {
        let r = r as u32;
        let job = ContactJob {
            loads: plan.loads.clone(),
            keep_pressure: plan.keep_pressure.clone(),
            e_star: plan.e_star,
            tolerance: plan.tolerance,
            max_iterations: plan.max_iterations,
            interface,
        };
        let contact = b.add::<Contact>(&job, vec![surface.clone()], studies, Some(r), None);
        let job = ClustersJob {
            loads: plan.loads.clone(),
            n: plan.surface.n,
            lambda_s_px: plan.surface.lambda_s_px,
            realization: r,
            connectivity: Default::default(),
            saturated: !interface.is_elastic(),
            window,
        };
        clusters.push(b.add::<Clusters>(&job, vec![contact.clone()], studies, Some(r), None));
        contacts.push(contact);
    }
    let mut job = StatisticsJob::standard(
        plan.loads.clone(),
        plan.surface.n,
        plan.surface.lambda_s_px,
        plan.seed,
    );
    job.map_pixels = window.map(|[rows, cols]| (rows * cols) as u64);
    job.exponent_interval_loads = Some(exponent_interval_loads);
    let statistics = b.add::<Statistics>(&job, clusters.clone(), studies, None, None);
    let job = AnalyticJob::Fitted {
        lambda_s_px: plan.surface.lambda_s_px,
        a_star_over_ls2: A_STAR_OVER_LS2.to_vec(),
    };
    let analytic = b.add::<Analytic>(&job, vec![statistics.clone()], studies, None, None);
    Ok(StudyKeys {
        plan,
        surfaces,
        contacts,
        clusters,
        statistics,
        analytic,
    })
}
