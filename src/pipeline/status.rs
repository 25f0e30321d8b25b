//! What a profile's store holds ([`status`]: present, missing, failed, per stage and study)
//! and what a run would compute and why ([`dry_run`]).

use std::collections::BTreeSet;

use serde::Serialize;
use serde_json::Value;

use super::cost::CostModel;
use super::plan::{Instance, Plan};
use super::runner::{forced_keys, RunOptions};
use crate::config::Pipeline;
use crate::store::Store;

/// Presence of every instance of a profile, per stage and study.
#[derive(Debug, Clone, Serialize)]
pub struct StatusLine {
    pub stage: String,
    pub study: String,
    pub present: usize,
    /// Not stored (failed ones included).
    pub missing: usize,
    /// Not stored because the computation failed (recorded under `failed/`).
    pub failed: usize,
}

/// What is present or missing for a profile: per stage (each instance once), and per stage
/// and study (an instance shared by studies counts in each).
#[derive(Debug, Clone, Serialize)]
pub struct Status {
    pub per_stage: Vec<StatusLine>,
    pub per_study: Vec<StatusLine>,
    /// Every instance of the profile once.
    pub totals: StatusLine,
    pub instances: Vec<InstanceState>,
}

/// What names one instance of a profile: its stage and key, and the studies, realization and
/// figure it belongs to (as the plan lists them).
#[derive(Debug, Clone, Serialize)]
pub struct InstanceId {
    pub stage: String,
    pub key: String,
    pub studies: Vec<String>,
    pub realization: Option<u32>,
    pub name: Option<String>,
}

impl InstanceId {
    fn of(inst: &crate::pipeline::plan::Instance) -> Self {
        Self {
            stage: inst.stage.clone(),
            key: inst.key.clone(),
            studies: inst.studies.clone(),
            realization: inst.realization,
            name: inst.name.clone(),
        }
    }

    /// Stage, figure or studies, realization and the first `key_chars` of the key, in
    /// aligned columns (`wearcoef status --keys`, `run --dry-run`).
    pub fn columns(&self, key_chars: usize) -> String {
        format!(
            "{:<10} {:<24} {:>3} {}",
            self.stage,
            self.name.clone().unwrap_or_else(|| self.studies.join(",")),
            self.realization
                .map_or("-".to_string(), |r| format!("r{r}")),
            &self.key[..key_chars.min(self.key.len())]
        )
    }
}

/// One instance of a profile and whether the store holds it.
#[derive(Debug, Clone, Serialize)]
pub struct InstanceState {
    #[serde(flatten)]
    pub id: InstanceId,
    /// `present`, `missing` or `failed` (missing, with a failure recorded).
    pub state: String,
    /// The recorded failure of a failed instance.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

/// Count the instances of `stage` (of `study`, when given) that the store holds.
fn status_line(
    store: &Store,
    plan: &Plan,
    stage: &str,
    study: Option<&str>,
) -> anyhow::Result<StatusLine> {
    let mut line = StatusLine {
        stage: stage.to_string(),
        study: study.unwrap_or_default().to_string(),
        present: 0,
        missing: 0,
        failed: 0,
    };
    for inst in plan
        .instances
        .iter()
        .filter(|i| i.stage == stage && study.is_none_or(|s| i.studies.iter().any(|x| x == s)))
    {
        if store.reusable(&inst.stage, &inst.key)?.is_some() {
            line.present += 1;
        } else {
            line.missing += 1;
            if store.failure(&inst.stage, &inst.key).is_some() {
                line.failed += 1;
            }
        }
    }
    Ok(line)
}

/// What is present or missing for a profile.
pub fn status(
    pipeline: &Pipeline,
    origin: &str,
    store: &Store,
    profile: &str,
) -> anyhow::Result<Status> {
    let studies = pipeline.plan(profile, origin)?;
    let plan = Plan::build(pipeline, origin, profile, &[])?;
    let mut status = Status {
        per_stage: Vec::new(),
        per_study: Vec::new(),
        totals: StatusLine {
            stage: "total".into(),
            study: String::new(),
            present: 0,
            missing: 0,
            failed: 0,
        },
        instances: Vec::new(),
    };
    for inst in &plan.instances {
        let present = store.reusable(&inst.stage, &inst.key)?.is_some();
        let failure = (!present)
            .then(|| store.failure(&inst.stage, &inst.key))
            .flatten();
        if present {
            status.totals.present += 1;
        } else {
            status.totals.missing += 1;
        }
        let state = match (present, &failure) {
            (true, _) => "present",
            (false, Some(_)) => "failed",
            (false, None) => "missing",
        };
        if failure.is_some() {
            status.totals.failed += 1;
        }
        status.instances.push(InstanceState {
            id: InstanceId::of(inst),
            state: state.to_string(),
            error: failure.map(|f| f.error),
        });
    }
    for stage in crate::pipeline::registry::names() {
        status
            .per_stage
            .push(status_line(store, &plan, stage, None)?);
        for study in &studies {
            status
                .per_study
                .push(status_line(store, &plan, stage, Some(&study.name))?);
        }
    }
    Ok(status)
}

/// An instance a run would compute, and why.
#[derive(Debug, Clone, Serialize)]
pub struct Pending {
    #[serde(flatten)]
    pub id: InstanceId,
    /// `missing`, `forced`, `changed parameter: …`, `stage version a → b`, `input changed`.
    pub reason: String,
}

/// What `run` would compute, and why, without computing anything: each instance the store
/// lacks (or that `--force` names) with the reason, found by comparing it with the instance
/// the profile's catalog lists for the same stage, studies, realization and figure.
pub fn dry_run(
    pipeline: &Pipeline,
    origin: &str,
    store: &Store,
    opts: &RunOptions,
) -> anyhow::Result<Vec<Pending>> {
    let mut plan = Plan::build(pipeline, origin, &opts.profile, &opts.targets)?;
    plan.mark(store, &CostModel::fit(store)?)?;
    let forced = forced_keys(&plan, &opts.force)?;
    let previous = previous_instances(store, &opts.profile);
    let mut out = Vec::new();
    for inst in &plan.instances {
        let reason = if forced.contains(&inst.key) {
            if opts.force.contains(&inst.stage) {
                format!("forced (--force {})", inst.stage)
            } else {
                "forced: downstream of a forced stage".to_string()
            }
        } else if inst.cached {
            continue;
        } else if let Some(f) = store.failure(&inst.stage, &inst.key) {
            if opts.retry_failed {
                format!("failed before, retried (--retry-failed): {}", f.error)
            } else {
                format!(
                    "failed before, not retried without --retry-failed: {}",
                    f.error
                )
            }
        } else if let Some(input) = store
            .lookup(&inst.stage, &inst.key)?
            .map(|m| store.changed_input(&m))
            .transpose()?
            .flatten()
        {
            format!("outdated: computed from {input}, whose content has changed since")
        } else {
            why_missing(store, inst, &previous)
        };
        out.push(Pending {
            id: InstanceId::of(inst),
            reason,
        });
    }
    Ok(out)
}

/// (stage, studies, realization, name) → key of each instance the profile's catalog lists.
type Slot = (String, Vec<String>, Option<u32>, Option<String>);

fn previous_instances(store: &Store, profile: &str) -> Vec<(Slot, String)> {
    let mut out = Vec::new();
    for stage in crate::pipeline::registry::names() {
        let path = store
            .root()
            .join(profile)
            .join(format!("index_{stage}.parquet"));
        let Ok(df) = crate::store::table::read(&path) else {
            continue;
        };
        let (Ok(keys), Ok(studies)) = (
            crate::store::table::str_column(&df, "key"),
            crate::store::table::str_column(&df, "studies"),
        ) else {
            continue;
        };
        let realizations = crate::store::table::u32_column(&df, "realization").ok();
        let names = df.column("name").ok().and_then(|c| c.str().ok().cloned());
        for i in 0..df.height() {
            let slot = (
                stage.to_string(),
                studies[i].split_whitespace().map(String::from).collect(),
                realizations.as_ref().and_then(|r| r[i]),
                names.as_ref().and_then(|n| n.get(i)).map(String::from),
            );
            out.push((slot, keys[i].clone()));
        }
    }
    out
}

fn why_missing(store: &Store, inst: &Instance, previous: &[(Slot, String)]) -> String {
    let before = previous.iter().find(|((stage, studies, r, name), _)| {
        stage == &inst.stage
            && r == &inst.realization
            && name == &inst.name
            && studies.iter().any(|s| inst.studies.contains(s))
    });
    let Some(Ok(Some(old))) = before.map(|(_, key)| store.lookup(&inst.stage, key)) else {
        return "missing".to_string();
    };
    let version = crate::pipeline::registry::find(&inst.stage).map_or(0, |s| s.version());
    if old.version != version {
        return format!("stage version {} → {version}", old.version);
    }
    let mut changed = Vec::new();
    if let (Value::Object(a), Value::Object(b)) = (&old.params, &inst.params) {
        let names: BTreeSet<&String> = a.keys().chain(b.keys()).collect();
        for n in names {
            let (x, y) = (a.get(n), b.get(n));
            if x != y {
                let show = |v: Option<&Value>| {
                    let t = v.map_or("(none)".to_string(), Value::to_string);
                    if t.chars().count() > 40 {
                        format!("{}…", t.chars().take(40).collect::<String>())
                    } else {
                        t
                    }
                };
                changed.push(format!("{n} {} → {}", show(x), show(y)));
            }
        }
    }
    if !changed.is_empty() {
        return format!("changed parameter: {}", changed.join("; "));
    }
    "input changed".to_string()
}
