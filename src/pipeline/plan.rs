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

use super::cost::Estimate;
use super::sources::measured_surfaces;
pub use super::sources::SourceFile;
use crate::config::{FigureDecl, FigureKind, Pipeline, StudyPlan};
use crate::stages::analytic::{Analytic, AnalyticJob};
use crate::stages::audits::{AuditJob, Audits, Setting};
use crate::stages::clusters::{Clusters, ClustersJob};
use crate::stages::contact::{Contact, ContactJob};
use crate::stages::figures::StudyRef;
use crate::stages::figures::{FigureJob, Figures};
use crate::stages::statistics::{Statistics, StatisticsJob, A_STAR_OVER_LS2};
use crate::stages::surface::{Surface, SurfaceJob};
use crate::stages::{keyed, InputRef, Stage};
use crate::store::Store;

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

/// The keys of one study's instances that figures and audits read.
struct StudyKeys<'a> {
    plan: &'a StudyPlan,
    surfaces: Vec<InputRef>,
    contacts: Vec<InputRef>,
    clusters: Vec<InputRef>,
    statistics: InputRef,
    analytic: InputRef,
}

/// Instances being collected, deduplicated by key.
#[derive(Default)]
struct Builder {
    out: Vec<Instance>,
    index: BTreeMap<String, usize>,
}

impl Builder {
    /// Add an instance of `S` (or record more studies on the one with the same key).
    fn add<S: Stage>(
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
                return Err(crate::pipeline::UsageError(format!(
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
            keys.push(study_instances(&mut b, plan)?);
        }
        for (name, decl) in &figures {
            figure_instances(&mut b, name, decl, profile, &keys)?;
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
            return Err(crate::pipeline::UsageError(format!(
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

fn study_instances<'a>(b: &mut Builder, plan: &'a StudyPlan) -> anyhow::Result<StudyKeys<'a>> {
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
    let (mut contacts, mut clusters) = (Vec::new(), Vec::new());
    for (r, surface) in surfaces.iter().enumerate() {
        let r = r as u32;
        let job = ContactJob {
            loads: plan.loads.clone(),
            keep_pressure: plan.keep_pressure.clone(),
            e_star: plan.e_star,
            tolerance: plan.tolerance,
            max_iterations: plan.max_iterations,
            hardness: plan.hardness,
        };
        let contact = b.add::<Contact>(&job, vec![surface.clone()], studies, Some(r), None);
        let job = ClustersJob {
            loads: plan.loads.clone(),
            n: plan.surface.n,
            lambda_s_px: plan.surface.lambda_s_px,
            realization: r,
            connectivity: Default::default(),
            saturated: plan.hardness.is_some(),
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

/// A study's reference in a figure: legend text `name = value`.
fn study_ref(k: &StudyKeys, label: String, value: f64) -> StudyRef {
    StudyRef {
        study: k.plan.name.clone(),
        label,
        value,
        lambda_s_px: k.plan.surface.lambda_s_px,
    }
}

/// One declared figure in one profile, with the studies' keys it draws from.
struct FigureContext<'a> {
    name: &'a str,
    decl: &'a FigureDecl,
    profile: &'a str,
    keys: &'a [StudyKeys<'a>],
}

impl<'a> FigureContext<'a> {
    fn find(&self, s: &str) -> anyhow::Result<&'a StudyKeys<'a>> {
        self.keys.iter().find(|k| k.plan.name == s).ok_or_else(|| {
            anyhow::anyhow!(
                "figure {}: study {s} is not in profile {}",
                self.name,
                self.profile
            )
        })
    }

    /// The studies of `list` the figure draws in this profile.
    fn used(&self, list: &[String]) -> anyhow::Result<Vec<&'a StudyKeys<'a>>> {
        self.decl
            .used(list, self.profile)
            .into_iter()
            .map(|s| self.find(s))
            .collect()
    }
}

fn names(ks: &[&StudyKeys]) -> Vec<String> {
    ks.iter().map(|k| k.plan.name.clone()).collect()
}

/// The audit and figure instances of one declared figure.
fn figure_instances(
    b: &mut Builder,
    name: &str,
    decl: &FigureDecl,
    profile: &str,
    keys: &[StudyKeys],
) -> anyhow::Result<()> {
    let c = FigureContext {
        name,
        decl,
        profile,
        keys,
    };
    match decl.kind {
        FigureKind::Fig6 => fig6_instances(b, &c),
        FigureKind::Fig2 => fig2_instances(b, &c),
        FigureKind::Fig3Fig4a => fig3_instances(b, &c),
        FigureKind::Fig45 => fig45_instances(b, &c),
        FigureKind::AppendixB1 | FigureKind::AppendixB2 => appendix_instances(b, &c),
        FigureKind::Convergence => convergence_instances(b, &c),
        FigureKind::LoadResolution => load_resolution_instances(b, &c),
        FigureKind::Plastic => plastic_instances(b, &c),
    }
}

fn fig6_instances(b: &mut Builder, c: &FigureContext) -> anyhow::Result<()> {
    let fig = Some(c.name);

    let model = b.add::<Analytic>(&AnalyticJob::fig6(), vec![], &[], None, None);
    b.add::<Figures>(&FigureJob::Fig6, vec![model], &[], None, fig);
    Ok(())
}

fn fig2_instances(b: &mut Builder, c: &FigureContext) -> anyhow::Result<()> {
    let (decl, fig) = (c.decl, Some(c.name));

    let k = c.find(decl.study.as_deref().unwrap_or_default())?;
    let studies = [k.plan.name.clone()];
    let maps: Vec<(usize, f64)> = k
        .plan
        .keep_pressure
        .iter()
        .map(|&i| (i, k.plan.loads[i]))
        .collect();
    let job = FigureJob::Fig2Maps {
        maps: maps.clone(),
        lambda_s_px: k.plan.surface.lambda_s_px,
        a_star_over_ls2: crate::stages::figures::FIG2_A_STAR_OVER_LS2,
        measured: k.plan.measured.is_some(),
    };
    let inputs = vec![k.surfaces[0].clone(), k.contacts[0].clone()];
    b.add::<Figures>(&job, inputs, &studies, None, fig);
    let audit = b.add::<Audits>(
        &AuditJob::realizations(),
        k.clusters.clone(),
        &studies,
        None,
        fig,
    );
    let job = FigureJob::Fig2ef {
        marked_loads: maps.iter().map(|m| m.1).collect(),
    };
    let inputs = vec![k.statistics.clone(), audit, k.analytic.clone()];
    b.add::<Figures>(&job, inputs, &studies, None, fig);
    Ok(())
}

fn fig3_instances(b: &mut Builder, c: &FigureContext) -> anyhow::Result<()> {
    let (decl, fig) = (c.decl, Some(c.name));

    let ratio = |k: &StudyKeys| k.plan.surface.lambda_l_px / k.plan.surface.lambda_s_px;
    let ratios = c.used(&decl.ratios)?;
    let hurst = c.used(&decl.hurst)?;
    let job = FigureJob::Fig3Fig4a {
        ratios: ratios
            .iter()
            .map(|k| study_ref(k, format!("λ_l/λ_s = {}", ratio(k)), ratio(k)))
            .collect(),
        hurst: hurst
            .iter()
            .map(|k| {
                let h = k.plan.surface.hurst;
                study_ref(k, format!("H = {h}"), h)
            })
            .collect(),
        loads: decl.loads.clone(),
        inset_load: decl.inset_load.unwrap_or_default(),
    };
    let inputs = ratios
        .iter()
        .chain(&hurst)
        .map(|k| k.statistics.clone())
        .collect();
    let mut studies = names(&ratios);
    for s in names(&hurst) {
        if !studies.contains(&s) {
            studies.push(s);
        }
    }
    b.add::<Figures>(&job, inputs, &studies, None, fig);
    Ok(())
}

fn fig45_instances(b: &mut Builder, c: &FigureContext) -> anyhow::Result<()> {
    let (decl, fig) = (c.decl, Some(c.name));

    let k = c.find(decl.study.as_deref().unwrap_or_default())?;
    let inputs = vec![k.statistics.clone(), k.analytic.clone()];
    let studies = std::slice::from_ref(&k.plan.name);
    let job = match &k.plan.measured {
        Some(m) => FigureJob::Fig45 {
            lambda_l_over_lambda_s: 0.0,
            measured: Some(format!(
                "measured ({} file{}, λ_s = {} px)",
                m.files.len(),
                if m.files.len() == 1 { "" } else { "s" },
                k.plan.surface.lambda_s_px
            )),
        },
        None => FigureJob::Fig45 {
            lambda_l_over_lambda_s: k.plan.surface.lambda_l_px / k.plan.surface.lambda_s_px,
            measured: None,
        },
    };
    b.add::<Figures>(&job, inputs, studies, None, fig);
    Ok(())
}

fn appendix_instances(b: &mut Builder, c: &FigureContext) -> anyhow::Result<()> {
    let (decl, fig) = (c.decl, Some(c.name));

    let b1 = decl.kind == FigureKind::AppendixB1;
    let setting = |k: &StudyKeys| {
        let s = &k.plan.surface;
        if b1 {
            s.n as f64 / s.lambda_l_px
        } else {
            s.lambda_s_px
        }
    };
    let quantity = if b1 { "L/λ_l" } else { "λ_s/Δl" };
    let mut studies = c.used(&decl.studies)?;
    studies.sort_by(|a, b| setting(a).total_cmp(&setting(b)));
    let refs: Vec<StudyRef> = studies
        .iter()
        .map(|k| study_ref(k, format!("{quantity} = {}", setting(k)), setting(k)))
        .collect();
    let audit = settings_audit(b, c.name, &studies, &refs);
    let mut inputs: Vec<InputRef> = studies.iter().map(|k| k.statistics.clone()).collect();
    inputs.push(audit);
    let job = FigureJob::Appendix {
        figure: c.name.to_string(),
        quantity: quantity.to_string(),
        b1,
        settings: refs,
    };
    b.add::<Figures>(&job, inputs, &names(&studies), None, fig);
    Ok(())
}

fn convergence_instances(b: &mut Builder, c: &FigureContext) -> anyhow::Result<()> {
    let (decl, fig) = (c.decl, Some(c.name));

    let mut studies = c.used(&decl.studies)?;
    // Reference last: the largest grid, and of equal grids the finer discretisation
    // (the declared order breaks remaining ties).
    studies.sort_by(|a, b| {
        let (sa, sb) = (&a.plan.surface, &b.plan.surface);
        (sa.n, sa.lambda_s_px)
            .partial_cmp(&(sb.n, sb.lambda_s_px))
            .expect("finite sizes")
    });
    let mut refs: Vec<StudyRef> = studies
        .iter()
        .map(|k| {
            let s = &k.plan.surface;
            let label = format!(
                "L/λ_l = {}, λ_s/Δl = {} (n = {})",
                s.n as f64 / s.lambda_l_px,
                s.lambda_s_px,
                s.n
            );
            study_ref(k, label, s.n as f64)
        })
        .collect();
    // Two studies with the same sizes would share a label: tell them apart by name.
    for i in 0..refs.len() {
        if refs.iter().filter(|r| r.label == refs[i].label).count() > 1 {
            refs[i].label = refs[i].named();
        }
    }
    let hurst = studies[0].plan.surface.hurst;
    let audit = settings_audit(b, c.name, &studies, &refs);
    let mut inputs: Vec<InputRef> = studies.iter().map(|k| k.statistics.clone()).collect();
    inputs.push(audit);
    let job = FigureJob::Convergence {
        figure: c.name.to_string(),
        hurst,
        settings: refs,
    };
    b.add::<Figures>(&job, inputs, &names(&studies), None, fig);
    Ok(())
}

fn load_resolution_instances(b: &mut Builder, c: &FigureContext) -> anyhow::Result<()> {
    let (decl, fig) = (c.decl, Some(c.name));

    let chosen = c.find(decl.chosen.as_deref().unwrap_or_default())?;
    let fine = c.find(decl.fine.as_deref().unwrap_or_default())?;
    let studies = names(&[fine, chosen]);
    let inputs = vec![fine.statistics.clone(), chosen.statistics.clone()];
    let audit = b.add::<Audits>(&AuditJob::load_resolution(), inputs, &studies, None, fig);
    let job = FigureJob::LoadResolution {
        figure: c.name.to_string(),
    };
    b.add::<Figures>(&job, vec![audit], &studies, None, fig);
    Ok(())
}

/// The plastic family: the settings ordered by 1/𝓗 (elastic first, at 0); inputs are
/// each setting's statistics, then each setting's contact sweeps (the saturated nodes).
fn plastic_instances(b: &mut Builder, c: &FigureContext) -> anyhow::Result<()> {
    let (decl, fig) = (c.decl, Some(c.name));

    let inverse = |k: &StudyKeys| k.plan.hardness.map_or(0.0, |h| 1.0 / h);
    let mut studies = c.used(&decl.studies)?;
    studies.sort_by(|a, b| inverse(a).total_cmp(&inverse(b)));
    let settings: Vec<StudyRef> = studies
        .iter()
        .map(|k| {
            let label = match k.plan.hardness {
                Some(h) => format!("𝓗 = {h}"),
                None => "elastic".to_string(),
            };
            study_ref(k, label, inverse(k))
        })
        .collect();
    let mut inputs: Vec<InputRef> = studies.iter().map(|k| k.statistics.clone()).collect();
    let realizations = studies.iter().map(|k| k.contacts.len()).collect();
    for k in &studies {
        inputs.extend(k.contacts.iter().cloned());
    }
    let job = FigureJob::Plastic {
        settings,
        realizations,
        loads: decl.loads.clone(),
    };
    b.add::<Figures>(&job, inputs, &names(&studies), None, fig);
    Ok(())
}

/// The convergence audit of settings (the last one the reference): inputs are each
/// setting's statistics followed by its clusters instances.
fn settings_audit(
    b: &mut Builder,
    name: &str,
    studies: &[&StudyKeys],
    refs: &[StudyRef],
) -> InputRef {
    let mut inputs = Vec::new();
    let mut settings = Vec::new();
    for (k, r) in studies.iter().zip(refs) {
        inputs.push(k.statistics.clone());
        inputs.extend(k.clusters.iter().cloned());
        settings.push(Setting {
            label: r.label.clone(),
            value: r.value,
            realizations: k.clusters.len(),
        });
    }
    let names: Vec<String> = studies.iter().map(|k| k.plan.name.clone()).collect();
    b.add::<Audits>(
        &AuditJob::settings(settings),
        inputs,
        &names,
        None,
        Some(name),
    )
}
