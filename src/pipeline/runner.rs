//! Running a profile: plan the instances, build the missing ones in parallel, write the
//! catalog, report.

use std::io::IsTerminal;
use std::time::Instant;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde::Serialize;
use serde_json::Value;

use super::catalog::{self, Row};
use super::cost::{machine_memory_bytes, CostModel};
use super::gallery;
use super::plan::{Instance, Plan};
use super::store::{CommitOutcome, Manifest, Program, Store};
use crate::config::Pipeline;
use crate::stages::Inputs;

/// What to run.
#[derive(Debug, Clone)]
pub struct RunOptions {
    pub profile: String,
    /// Stage or study names; empty means everything in the profile.
    pub targets: Vec<String>,
    /// Worker threads (instances and FFTs share one pool).
    pub jobs: usize,
    /// Hide the progress bar even on a terminal.
    pub quiet: bool,
}

/// The one-line outcome of a run.
#[derive(Debug, Clone, Serialize)]
pub struct RunSummary {
    pub profile: String,
    pub instances: usize,
    pub computed: usize,
    pub reused: usize,
    pub wall_seconds: f64,
    pub catalog: String,
}

impl std::fmt::Display for RunSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "wearcoef run --profile {}: {} instances, {} computed, {} reused, {:.2} s; catalog {}",
            self.profile,
            self.instances,
            self.computed,
            self.reused,
            self.wall_seconds,
            self.catalog
        )
    }
}

/// Build what is missing for a profile: plan, refuse a plan that cannot fit in memory, run
/// the missing instances level by level, export the figures, write the catalog.
pub fn run(
    pipeline: &Pipeline,
    origin: &str,
    store: &Store,
    opts: &RunOptions,
) -> anyhow::Result<RunSummary> {
    let start = Instant::now();
    let mut plan = Plan::build(pipeline, origin, &opts.profile, &opts.targets)?;
    plan.mark(store, &CostModel::fit(store)?)?;
    if let Some(memory) = machine_memory_bytes() {
        Plan {
            profile: plan.profile.clone(),
            instances: plan
                .instances
                .iter()
                .filter(|i| !i.cached)
                .cloned()
                .collect(),
        }
        .check_memory(memory)?;
    }
    store.remove_stale_temporaries()?;
    let reused = plan.instances.iter().filter(|i| i.cached).count();
    let computed = execute(store, &plan.instances, opts.jobs, opts.jobs, opts.quiet)?;

    let catalog_dir = store.root().join(&opts.profile);
    // A partial plan (targets) exports its figures but leaves the gallery's record and
    // report alone.
    let record = opts.targets.is_empty();
    if let Some(provenance) = gallery::export(store, &plan.instances, &opts.profile, record)? {
        let descriptions: std::collections::BTreeMap<String, String> = pipeline
            .figures_of(&opts.profile)
            .into_iter()
            .map(|(name, decl)| (name.to_string(), decl.description.clone()))
            .collect();
        let dir = gallery::dir(store, &opts.profile);
        super::report::write(store, &dir, &provenance, &descriptions)?;
    }
    // The catalog describes every stored instance of the whole profile: a targeted run adds
    // rows, never drops the other studies'.
    let whole = if opts.targets.is_empty() {
        None
    } else {
        Some(Plan::build(pipeline, origin, &opts.profile, &[])?)
    };
    let listed = whole.as_ref().map_or(&plan.instances, |p| &p.instances);
    let rows = catalog_rows(store, listed)?;
    catalog::write(&catalog_dir, &rows)?;
    Ok(RunSummary {
        profile: opts.profile.clone(),
        instances: plan.instances.len(),
        computed,
        reused,
        wall_seconds: start.elapsed().as_secs_f64(),
        catalog: catalog_dir.join("index.parquet").display().to_string(),
    })
}

/// Compute the instances of `instances` that the store lacks, level by level (every input
/// of a level is on a lower one), each level's instances in parallel. An instance whose
/// inputs are neither in the store nor among `instances` fails with an error naming the
/// missing input. At most `at_once` instances run side by side, each on a pool of `jobs`
/// threads. Returns how many were computed.
pub fn execute(
    store: &Store,
    instances: &[Instance],
    jobs: usize,
    at_once: usize,
    quiet: bool,
) -> anyhow::Result<usize> {
    let jobs = jobs.max(1);
    let at_once = at_once.max(1);
    let levels = instances.iter().map(|i| i.level + 1).max().unwrap_or(0);
    let mut computed = 0;
    for level in 0..levels {
        let mut missing = Vec::new();
        for inst in instances.iter().filter(|i| i.level == level) {
            if store.lookup(&inst.stage, &inst.key)?.is_none() {
                missing.push(inst);
            }
        }
        if missing.is_empty() {
            continue;
        }
        let label = stage_list(missing.iter().map(|i| i.stage.as_str()));
        let bar = progress(missing.len(), &label, quiet);
        // Off a terminal (a log file, CI) the bar is hidden: one plain line per instance.
        let lines = !quiet && bar.is_hidden();
        let results = build_all(store, &missing, jobs, at_once, &bar, lines)?;
        bar.finish_and_clear();
        for r in results {
            r?;
            computed += 1;
        }
    }
    Ok(computed)
}

/// An instance for a progress line: stage, figure or studies, realization, short key.
fn describe(inst: &Instance) -> String {
    let mut s = inst.stage.clone();
    match (&inst.name, inst.studies.as_slice()) {
        (Some(name), _) => s.push_str(&format!(" {name}")),
        (None, []) => {}
        (None, studies) => s.push_str(&format!(" {}", studies.join(","))),
    }
    if let Some(r) = inst.realization {
        s.push_str(&format!(" r{r}"));
    }
    s.push_str(&format!(" {}", &inst.key[..12.min(inst.key.len())]));
    s
}

/// The stages of a batch, in order of first appearance (`contact+clusters`).
pub fn stage_list<'a>(stages: impl IntoIterator<Item = &'a str>) -> String {
    let mut names: Vec<&str> = Vec::new();
    for s in stages {
        if !names.contains(&s) {
            names.push(s);
        }
    }
    names.join("+")
}

fn progress(len: usize, stage: &str, quiet: bool) -> ProgressBar {
    let bar = ProgressBar::new(len as u64);
    if quiet || !std::io::stdout().is_terminal() {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    } else {
        bar.set_draw_target(ProgressDrawTarget::stderr());
    }
    bar.set_style(
        ProgressStyle::with_template(
            "{prefix:>10} [{bar:30}] {pos}/{len} {elapsed_precise} eta {eta} {wide_msg}",
        )
        .expect("static template")
        .progress_chars("=> "),
    );
    bar.set_prefix(stage.to_string());
    bar
}

/// Compute `missing` with `min(at_once, instances)` workers, each with its own rayon pool of
/// `jobs` threads for the instance's inner parallelism (so a lone last instance still uses
/// every core; while several run, the OS shares the cores between them). Separate pools keep
/// one instance's parallel loops from running another instance while they wait, so each
/// manifest's `wall_seconds` is that instance's own elapsed time. Results in input order.
fn build_all(
    store: &Store,
    missing: &[&Instance],
    jobs: usize,
    at_once: usize,
    bar: &ProgressBar,
    lines: bool,
) -> anyhow::Result<Vec<anyhow::Result<()>>> {
    use std::sync::atomic::{AtomicUsize, Ordering};
    let workers = at_once.min(missing.len()).max(1);
    let threads_each = jobs;
    let next = AtomicUsize::new(0);
    let mut results: Vec<Option<anyhow::Result<()>>> = (0..missing.len()).map(|_| None).collect();
    std::thread::scope(|scope| -> anyhow::Result<()> {
        let handles: Vec<_> = (0..workers)
            .map(|_| {
                scope.spawn(|| -> anyhow::Result<Vec<(usize, anyhow::Result<()>)>> {
                    let pool = rayon::ThreadPoolBuilder::new()
                        .num_threads(threads_each)
                        .build()?;
                    let mut out = Vec::new();
                    loop {
                        let i = next.fetch_add(1, Ordering::Relaxed);
                        let Some(inst) = missing.get(i) else { break };
                        let what = describe(inst);
                        bar.set_message(what.clone());
                        let started = std::time::Instant::now();
                        let before: f64 = pool.broadcast(|_| thread_cpu_seconds()).iter().sum();
                        let built = pool.install(|| build(store, inst, &pool, before));
                        let verdict = if built.is_ok() { "done" } else { "FAILED" };
                        out.push((i, built));
                        bar.inc(1);
                        if lines {
                            eprintln!(
                                "{verdict} {what} in {:.1} s ({}/{} of this level)",
                                started.elapsed().as_secs_f64(),
                                bar.position(),
                                bar.length().unwrap_or(0)
                            );
                        }
                    }
                    Ok(out)
                })
            })
            .collect();
        for h in handles {
            let done = h
                .join()
                .map_err(|_| anyhow::anyhow!("a worker thread panicked"))??;
            for (i, r) in done {
                results[i] = Some(r);
            }
        }
        Ok(())
    })?;
    Ok(results
        .into_iter()
        .map(|r| r.unwrap_or_else(|| Err(anyhow::anyhow!("instance not computed"))))
        .collect())
}

/// CPU time of the calling thread (Linux `CLOCK_THREAD_CPUTIME_ID`), 0 if unavailable.
fn thread_cpu_seconds() -> f64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid, writable timespec; the call only writes to it.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) };
    if rc == 0 {
        t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9
    } else {
        0.0
    }
}

/// Compute one instance on `pool` (whose threads had used `cpu_before` CPU seconds).
fn build(
    store: &Store,
    inst: &Instance,
    pool: &rayon::ThreadPool,
    cpu_before: f64,
) -> anyhow::Result<()> {
    let start = Instant::now();
    let stage = crate::pipeline::registry::find(&inst.stage).ok_or_else(|| {
        anyhow::anyhow!(
            "the plan names stage '{}', which this build does not have ({})",
            inst.stage,
            crate::pipeline::registry::names().join(", ")
        )
    })?;
    let keys: Vec<String> = inst.inputs.iter().map(|r| r.key.clone()).collect();
    let key = super::hash::instance_key(stage.name(), stage.version(), &inst.params, &keys);
    anyhow::ensure!(
        key == inst.key,
        "the plan's {} instance {} does not match its parameters (their key is {key}): the plan was edited or made by another version; make it anew with `wearcoef plan`",
        inst.stage,
        inst.key
    );
    let inputs = Inputs::load(store, &inst.inputs)?;
    let entry = store.begin(&inst.stage, &inst.key)?;
    let results = stage
        .compute(&inst.params, &inputs, entry.path())
        .map_err(|e| {
            anyhow::anyhow!(
                "stage {} (studies {}, realization {}) failed: {e:#}",
                inst.stage,
                inst.studies.join(", "),
                inst.realization.map_or("-".to_string(), |r| r.to_string())
            )
        })?;
    let wall_seconds = start.elapsed().as_secs_f64();
    let cpu_after: f64 = pool.broadcast(|_| thread_cpu_seconds()).iter().sum();
    let manifest = Manifest {
        stage: inst.stage.clone(),
        version: stage.version(),
        key: inst.key.clone(),
        params: inst.params.clone(),
        inputs: keys,
        outputs: Default::default(),
        program: Program::current(),
        wall_seconds,
        cpu_seconds: Some((cpu_after - cpu_before).max(0.0)),
        results,
    };
    match entry.commit(manifest)? {
        CommitOutcome::Stored | CommitOutcome::AlreadyPresent => Ok(()),
    }
}

fn catalog_rows(store: &Store, all: &[Instance]) -> anyhow::Result<Vec<Row>> {
    let mut rows = Vec::new();
    for inst in all {
        let Some(manifest) = store.lookup(&inst.stage, &inst.key)? else {
            continue;
        };
        let mut extra = std::collections::BTreeMap::new();
        for source in [&manifest.params, &manifest.results] {
            if let Value::Object(map) = source {
                for (k, v) in map {
                    // Scalars only; a parameter named like a fixed column (the clusters
                    // stage's `realization`) is already there.
                    let fixed = ["stage", "study", "realization", "file", "path", "key"];
                    if !v.is_object() && !v.is_array() && !fixed.contains(&k.as_str()) {
                        extra.insert(k.clone(), v.clone());
                    }
                }
            }
        }
        let dir = store.entry_dir(&inst.stage, &inst.key);
        let loads: Option<Vec<f64>> = (inst.stage == "contact")
            .then(|| inst.params.get("loads_w_over_w0")?.as_array().cloned())
            .flatten()
            .map(|a| a.iter().filter_map(Value::as_f64).collect());
        // Shared instances (the model curves of Fig. 6) are listed once, with no study.
        let studies = if inst.studies.is_empty() {
            vec![String::new()]
        } else {
            inst.studies.clone()
        };
        for study in &studies {
            for file in manifest.outputs.keys() {
                let mut extra = extra.clone();
                // Per-load files carry their load index in the name (`contact_007.npy`).
                let index = file
                    .rsplit_once('_')
                    .and_then(|(_, rest)| rest.strip_suffix(".npy"))
                    .and_then(|d| d.parse::<usize>().ok());
                if let (Some(i), Some(loads)) = (index, &loads) {
                    extra.insert("load_index".into(), Value::from(i as u64));
                    extra.insert("w_over_w0".into(), Value::from(loads[i]));
                }
                rows.push(Row {
                    stage: inst.stage.clone(),
                    study: study.clone(),
                    realization: inst.realization,
                    file: file.clone(),
                    path: dir.join(file).display().to_string(),
                    key: inst.key.clone(),
                    extra,
                });
            }
        }
    }
    Ok(rows)
}

/// Presence of every instance of a profile, per stage and study.
#[derive(Debug, Clone, Serialize)]
pub struct StatusLine {
    pub stage: String,
    pub study: String,
    pub present: usize,
    pub missing: usize,
}

/// What is present or missing for a profile: per stage (each instance once), and per stage
/// and study (an instance shared by studies counts in each).
#[derive(Debug, Clone, Serialize)]
pub struct Status {
    pub per_stage: Vec<StatusLine>,
    pub per_study: Vec<StatusLine>,
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
    };
    for inst in plan
        .instances
        .iter()
        .filter(|i| i.stage == stage && study.is_none_or(|s| i.studies.iter().any(|x| x == s)))
    {
        if store.lookup(&inst.stage, &inst.key)?.is_some() {
            line.present += 1;
        } else {
            line.missing += 1;
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
    };
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
