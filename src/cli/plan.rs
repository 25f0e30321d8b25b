//! `wearcoef plan` (the DAG of a profile, its cost and what the store holds) and
//! `wearcoef exec` (run given instances of a plan file: the scheduler-neutral core that a
//! cluster's job arrays, or a plain shell loop, call).

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::process::ExitCode;

use serde::Serialize;
use serde_json::json;

use wearcoef::config::Pipeline;
use wearcoef::pipeline::cost::{machine_memory_bytes, CostModel};
use wearcoef::pipeline::plan::{Instance, Plan};
use wearcoef::pipeline::runner;
use wearcoef::pipeline::UsageError;
use wearcoef::store::hash::instance_key;
use wearcoef::store::Store;

use super::checks::{load, StoreArgs};

/// Totals of a plan, per stage and overall.
#[derive(Debug, Serialize)]
pub struct Totals {
    pub instances: usize,
    pub cached: usize,
    pub levels: usize,
    /// Estimated core-hours of the missing instances.
    pub missing_core_hours: f64,
    /// The same in wall hours on this machine's `cores` cores (perfect use assumed).
    pub missing_hours: f64,
    /// Core-hours of every instance, cached or not (the campaign from nothing).
    pub total_core_hours: f64,
    pub cores: usize,
    /// The largest instance's estimated peak memory and its stage and key.
    pub largest_peak_bytes: u64,
    pub largest: Option<String>,
    pub machine_memory_bytes: Option<u64>,
    pub per_stage: BTreeMap<String, StageTotals>,
}

#[derive(Debug, Default, Serialize)]
pub struct StageTotals {
    pub instances: usize,
    pub cached: usize,
    pub core_hours: f64,
    pub largest_peak_bytes: u64,
}

pub fn totals(plan: &Plan, cores: usize) -> Totals {
    let core_hours = |i: &Instance| i.estimate.seconds / 3600.0;
    let mut per_stage: BTreeMap<String, StageTotals> = BTreeMap::new();
    for i in &plan.instances {
        let t = per_stage.entry(i.stage.clone()).or_default();
        t.instances += 1;
        t.cached += usize::from(i.cached);
        t.core_hours += core_hours(i);
        t.largest_peak_bytes = t.largest_peak_bytes.max(i.estimate.peak_bytes);
    }
    let missing: Vec<&Instance> = plan.instances.iter().filter(|i| !i.cached).collect();
    // (0.0 + …: an empty float sum is −0.0.)
    let missing_core_hours = 0.0 + missing.iter().map(|i| core_hours(i)).sum::<f64>();
    let largest = plan.largest();
    Totals {
        instances: plan.instances.len(),
        cached: plan.instances.len() - missing.len(),
        levels: plan.levels(),
        missing_core_hours,
        missing_hours: missing_core_hours / cores as f64,
        total_core_hours: 0.0 + plan.instances.iter().map(core_hours).sum::<f64>(),
        cores,
        largest_peak_bytes: largest.map_or(0, |i| i.estimate.peak_bytes),
        largest: largest.map(|i| format!("{} {}", i.stage, i.key)),
        machine_memory_bytes: machine_memory_bytes(),
        per_stage,
    }
}

/// Plan a profile against a store, with estimates from the cost model fitted to it.
pub fn make_plan(
    pipeline: &Pipeline,
    origin: &str,
    data: &std::path::Path,
    profile: &str,
    targets: &[String],
) -> anyhow::Result<(Plan, CostModel)> {
    let store = Store::new(data);
    let mut plan = Plan::build(pipeline, origin, profile, targets)?;
    let model = CostModel::fit(&store)?;
    plan.mark(&store, &model)?;
    Ok((plan, model))
}

/// Print a plan: the whole DAG as one JSON object (with the cost model's coefficients and the
/// stored instances each was fitted to), or a table of totals per stage.
pub fn print_plan(
    plan: &Plan,
    model: &CostModel,
    json_out: bool,
    out: Option<&PathBuf>,
) -> anyhow::Result<()> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let totals = totals(plan, cores);
    let doc = json!({
        "profile": plan.profile,
        "totals": totals,
        "cost_model": model,
        "instances": plan.instances,
    });
    if let Some(path) = out {
        super::checks::write_atomically(path, |tmp| {
            std::fs::write(tmp, serde_json::to_vec_pretty(&doc)?)?;
            Ok(())
        })?;
    }
    if json_out {
        out!("{}", serde_json::to_string(&doc)?)?;
        return Ok(());
    }
    let gib = |b: u64| b as f64 / (1u64 << 30) as f64;
    out!(
        "{:<11} {:>9} {:>7} {:>11} {:>12}",
        "stage",
        "instances",
        "cached",
        "core-hours",
        "largest GiB"
    )?;
    for (stage, t) in &totals.per_stage {
        out!(
            "{:<11} {:>9} {:>7} {:>11.3} {:>12.2}",
            stage,
            t.instances,
            t.cached,
            t.core_hours,
            gib(t.largest_peak_bytes)
        )?;
    }
    out!(
        "profile {}: {} instances in {} levels, {} cached; {:.2} core-hours from nothing, {:.2} core-hours ({:.2} h on {} cores) for what is missing; largest instance {:.2} GiB ({})",
        plan.profile,
        totals.instances,
        totals.levels,
        totals.cached,
        totals.total_core_hours,
        totals.missing_core_hours,
        totals.missing_hours,
        cores,
        gib(totals.largest_peak_bytes),
        totals.largest.as_deref().unwrap_or("-"),
    )?;
    Ok(())
}

/// `plan --against`: a saved plan's estimates beside what the store's manifests measured.
fn print_against(
    saved: &std::path::Path,
    data: &std::path::Path,
    json_out: bool,
) -> anyhow::Result<ExitCode> {
    let text = std::fs::read_to_string(saved)
        .map_err(|e| UsageError(format!("--against {}: {e}", saved.display())))?;
    let plan: Plan = serde_json::from_str(&text).map_err(|e| {
        UsageError(format!(
            "--against {}: not a plan made by `wearcoef plan --out`: {e}",
            saved.display()
        ))
    })?;
    let store = Store::existing(data)?;
    let rows = wearcoef::pipeline::measured::compare(&plan.instances, &store);
    if json_out {
        out!("{}", serde_json::to_string(&rows)?)?;
        return Ok(ExitCode::SUCCESS);
    }
    let gib = |b: u64| b as f64 / (1u64 << 30) as f64;
    let ratio = |r: Option<f64>| r.map_or("-".to_string(), |r| format!("{r:.2}"));
    out!(
        "{:<11} {:>8} {:>8} {:>12} {:>12} {:>6} {:>10} {:>10} {:>6}",
        "stage",
        "planned",
        "measured",
        "est. core-h",
        "meas. core-h",
        "ratio",
        "est. GiB",
        "meas. GiB",
        "ratio"
    )?;
    for r in &rows {
        out!(
            "{:<11} {:>8} {:>8} {:>12.3} {:>12.3} {:>6} {:>10.2} {:>10.2} {:>6}",
            r.stage,
            r.planned,
            r.measured,
            r.estimated_cpu_seconds / 3600.0,
            r.measured_cpu_seconds / 3600.0,
            ratio(r.cpu_ratio()),
            gib(r.estimated_peak_bytes),
            gib(r.measured_peak_bytes),
            ratio(r.peak_ratio())
        )?;
    }
    out!(
        "plan {} against the store {}: CPU over the instances measured; peak memory over those computed one at a time (run --at-once 1)",
        saved.display(),
        data.display()
    )?;
    Ok(ExitCode::SUCCESS)
}

/// `I/K`: the I-th (0-based) of K contiguous slices.
pub fn parse_slice(s: &str) -> Result<(usize, usize), String> {
    let (i, k) = s
        .split_once('/')
        .ok_or_else(|| format!("--slice {s}: write I/K, e.g. 0/4"))?;
    let (i, k): (usize, usize) = (
        i.parse()
            .map_err(|_| format!("--slice {s}: I is not a whole number"))?,
        k.parse()
            .map_err(|_| format!("--slice {s}: K is not a whole number"))?,
    );
    if k == 0 || i >= k {
        return Err(format!("--slice {s}: need 0 ≤ I < K"));
    }
    Ok((i, k))
}

/// Run the instances of a plan file (optionally one level, optionally one slice of it).
pub fn exec_plan(
    plan_path: &std::path::Path,
    data: &std::path::Path,
    level: Option<usize>,
    slice: Option<(usize, usize)>,
    jobs: usize,
    at_once: usize,
    quiet: bool,
) -> anyhow::Result<serde_json::Value> {
    let text = std::fs::read_to_string(plan_path)
        .map_err(|e| UsageError(format!("--plan {}: {e}", plan_path.display())))?;
    let plan: Plan = serde_json::from_str(&text).map_err(|e| {
        UsageError(format!(
            "--plan {}: not a plan made by `wearcoef plan --out`: {e}",
            plan_path.display()
        ))
    })?;
    let levels = plan
        .instances
        .iter()
        .map(|i| i.level + 1)
        .max()
        .unwrap_or(0);
    if let Some(l) = level.filter(|&l| l >= levels) {
        return Err(UsageError(format!(
            "--level {l}: the plan {} has levels 0 to {} (`wearcoef plan` lists them)",
            plan_path.display(),
            levels.saturating_sub(1)
        ))
        .into());
    }
    let mut chosen: Vec<Instance> = plan
        .instances
        .into_iter()
        .filter(|i| level.is_none_or(|l| i.level == l))
        .collect();
    if let Some((i, k)) = slice {
        let range = wearcoef::pipeline::plan::slice_range(chosen.len(), i, k);
        chosen = chosen.drain(range).collect();
    }
    for inst in &chosen {
        let stage = wearcoef::pipeline::registry::find(&inst.stage).ok_or_else(|| {
            UsageError(format!(
                "the plan names stage '{}', which this build does not have",
                inst.stage
            ))
        })?;
        stage.check(&inst.params)?;
        let keys: Vec<String> = inst.inputs.iter().map(|r| r.key.clone()).collect();
        let key = instance_key(stage.name(), stage.version(), &inst.params, &keys);
        if key != inst.key {
            return Err(UsageError(format!(
                "--plan {}: the {} instance {} does not match its parameters (they give {key}): the plan was edited or made by another version of wearcoef; make it anew with `wearcoef plan --out`",
                plan_path.display(),
                inst.stage,
                inst.key
            ))
            .into());
        }
    }
    let store = Store::new(data);
    let start = std::time::Instant::now();
    let computed = runner::execute(&store, &chosen, jobs, at_once, quiet)?;
    Ok(json!({
        "instances": chosen.len(),
        "computed": computed,
        "wall_seconds": start.elapsed().as_secs_f64(),
        "peak_rss_bytes": peak_rss_bytes(),
    }))
}

/// The process's peak resident memory (`getrusage`), what a cluster's memory limit counts.
fn peak_rss_bytes() -> Option<u64> {
    // SAFETY: `usage` is a valid, writable rusage; the call only writes to it.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let rc = unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut usage) };
    // Linux reports kibibytes.
    (rc == 0).then(|| usage.ru_maxrss as u64 * 1024)
}

#[derive(clap::Args)]
pub struct PlanArgs {
    pub targets: Vec<String>,
    #[command(flatten)]
    pub store: StoreArgs,
    #[arg(long, default_value = "default")]
    pub profile: String,
    /// Print the whole plan as one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Also write the plan (JSON) to this file, for `wearcoef exec`.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Instead of planning: for the instances of this saved plan (`--out`, made before a
    /// campaign) that the store holds, their estimated against their measured CPU time and
    /// peak memory, per stage.
    #[arg(long, value_name = "PLAN")]
    pub against: Option<PathBuf>,
}

pub fn plan(args: PlanArgs) -> anyhow::Result<ExitCode> {
    let PlanArgs {
        targets,
        store,
        profile,
        json,
        out,
        against,
    } = args;
    if let Some(saved) = against {
        return print_against(&saved, &store.data, json);
    }
    let pipeline = load(&store.config)?;
    if let Some(path) = &out {
        super::checks::check_outputs_of_pipeline(&[("--out", path)], &store.config, &pipeline)?;
    }
    let origin = store.config.display().to_string();
    let (plan, model) = make_plan(&pipeline, &origin, &store.data, &profile, &targets)?;
    print_plan(&plan, &model, json, out.as_ref())?;
    Ok(ExitCode::SUCCESS)
}

#[derive(clap::Args)]
pub struct ExecArgs {
    /// Plan written by `wearcoef plan --out`.
    #[arg(long)]
    pub plan: PathBuf,
    #[arg(long, default_value = "data")]
    pub data: PathBuf,
    #[arg(long)]
    pub level: Option<usize>,
    #[arg(long, value_parser = parse_slice)]
    pub slice: Option<(usize, usize)>,
    /// Threads of each instance [default: number of cores].
    #[arg(long)]
    pub jobs: Option<usize>,
    /// Instances run side by side [default: --jobs]; 1 runs them one after the other, each
    /// on all threads (what cluster tasks do: their memory is then one instance's).
    #[arg(long)]
    pub at_once: Option<usize>,
    #[arg(long)]
    pub quiet: bool,
}

pub fn exec(args: ExecArgs) -> anyhow::Result<ExitCode> {
    let ExecArgs {
        plan,
        data,
        level,
        slice,
        jobs,
        at_once,
        quiet,
    } = args;
    let jobs = jobs.unwrap_or_else(wearcoef::machine::cores);
    let at_once = at_once.unwrap_or(jobs);
    super::checks::check_threads(&format!("--jobs {jobs} --at-once {at_once}"), at_once, jobs)?;
    let done = exec_plan(&plan, &data, level, slice, jobs, at_once, quiet)?;
    out!("{done}")?;
    Ok(ExitCode::SUCCESS)
}
