//! Running a profile: plan the instances, build the missing ones in parallel, write the
//! catalog, report.

use std::collections::BTreeSet;
use std::io::IsTerminal;
use std::time::Instant;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde::Serialize;
use serde_json::Value;

use super::catalog::Catalog;
use super::cost::{machine_memory_bytes, CostModel};
use super::gallery;
use super::plan::{Instance, Plan};
use crate::config::Pipeline;
use crate::stages::Inputs;
use crate::store::{CommitOutcome, Failure, Manifest, Program, Store};

/// What to run.
#[derive(Debug, Clone)]
pub struct RunOptions {
    pub profile: String,
    /// Stage or study names; empty means everything in the profile.
    pub targets: Vec<String>,
    /// Instances computed side by side, each on min(jobs, cores) threads.
    pub jobs: usize,
    /// Instances side by side instead of `jobs` (1: one at a time on all its threads, so
    /// each manifest records the instance's own peak memory).
    pub at_once: Option<usize>,
    /// Hide the progress bar even on a terminal.
    pub quiet: bool,
    /// Root of the galleries: figures go to `<figures>/<profile>/`.
    pub figures: std::path::PathBuf,
    /// Stages to recompute even where stored (with everything downstream of them).
    pub force: Vec<String>,
    /// Compute again the instances whose computation failed in an earlier run.
    pub retry_failed: bool,
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
    // The whole plan, built once: the targets' part runs, the whole is catalogued.
    let whole = Plan::build(pipeline, origin, &opts.profile, &[])?;
    let mut plan = whole.targeted(pipeline, origin, &opts.targets)?;
    if plan.instances.is_empty() {
        return Err(crate::pipeline::error::UsageError(format!(
            "profile {p} builds nothing: no study has an entry for it (studies.<name>.profiles.{p}) and no figure lists it; add one, or run another profile",
            p = opts.profile
        ))
        .into());
    }
    plan.mark(store, &CostModel::fit(store)?)?;
    let forced = forced_keys(&plan, &opts.force)?;
    for inst in &mut plan.instances {
        if forced.contains(&inst.key) {
            inst.cached = false;
        }
    }
    let mut at_once = opts.at_once.unwrap_or(opts.jobs);
    if let Some(memory) = machine_memory_bytes() {
        let missing = Plan {
            profile: plan.profile.clone(),
            instances: plan
                .instances
                .iter()
                .filter(|i| !i.cached)
                .cloned()
                .collect(),
        };
        missing.check_memory(memory)?;
        // As many instances side by side as the largest fits in memory that many times.
        if let Some(largest) = missing.largest().map(|i| i.estimate.peak_bytes.max(1)) {
            let fit = (memory / largest).max(1) as usize;
            if at_once > fit {
                if !opts.quiet {
                    crate::note!(
                        "at most {fit} instance(s) at once instead of {at_once}: the largest needs about {:.1} GiB of this machine's {:.1} GiB",
                        largest as f64 / (1u64 << 30) as f64,
                        memory as f64 / (1u64 << 30) as f64
                    );
                }
                at_once = fit;
            }
        }
    }
    store.remove_stale_temporaries()?;
    let reused = plan.instances.iter().filter(|i| i.cached).count();
    // Up to `at_once` instances at once, each on a pool of at most one thread per core.
    let outcome = execute_forcing(
        store,
        &plan.instances,
        &forced,
        opts.retry_failed,
        opts.jobs.min(crate::machine::cores()),
        at_once,
        opts.quiet,
    )?;
    let computed = outcome.computed;

    let catalog_dir = store.root().join(&opts.profile);
    // A partial plan (targets) exports its figures but leaves the gallery's record and
    // report alone.
    let record = opts.targets.is_empty();
    let complete = outcome.failed.is_empty() && outcome.failed_before.is_empty();
    // An incomplete run (failures) leaves the gallery as it was.
    let provenance = if complete {
        gallery::export(store, &opts.figures, &plan.instances, &opts.profile, record)?
    } else {
        None
    };
    if let Some(provenance) = provenance {
        let context = super::report::Context::of(pipeline, origin, &opts.profile)?;
        let dir = gallery::dir(&opts.figures, &opts.profile);
        super::report::write(store, &dir, &provenance, &context)?;
    }
    // The catalog describes every stored instance of the whole profile: a targeted run adds
    // rows, never drops the other studies'.
    let listed = if opts.targets.is_empty() {
        &plan.instances
    } else {
        &whole.instances
    };
    let studies = pipeline.plan(&opts.profile, origin)?;
    Catalog::collect(store, &opts.profile, listed, &studies)?.write(&catalog_dir)?;
    // Failures end the run with exit 1, after the catalog lists them.
    outcome.into_result()?;
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
    execute_forcing(
        store,
        instances,
        &BTreeSet::new(),
        false,
        jobs,
        at_once,
        quiet,
    )?
    .into_result()
}

/// How an execution ended: what was computed, what failed now, what had failed before and
/// was not retried, and what could not run because an input failed.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Outcome {
    pub computed: usize,
    pub failed: Vec<String>,
    pub failed_before: Vec<String>,
    pub skipped: usize,
}

impl Outcome {
    /// The number computed, or an error (exit 1) that says what failed.
    pub fn into_result(self) -> anyhow::Result<usize> {
        if self.failed.is_empty() && self.failed_before.is_empty() {
            return Ok(self.computed);
        }
        let mut text = String::new();
        if !self.failed.is_empty() {
            text.push_str(&format!(
                "{} instance(s) failed (a failure of the computation itself, such as a solve that did not converge, is recorded under failed/ in the store and listed by `wearcoef status`):\n  {}",
                self.failed.len(),
                self.failed.join("\n  ")
            ));
        }
        if !self.failed_before.is_empty() {
            if !text.is_empty() {
                text.push('\n');
            }
            text.push_str(&format!(
                "{} instance(s) failed in an earlier run and were not retried (retry with --retry-failed, or change their parameters):\n  {}",
                self.failed_before.len(),
                self.failed_before.join("\n  ")
            ));
        }
        if self.skipped > 0 {
            text.push_str(&format!(
                "\n{} instance(s) not run because an input failed; {} computed",
                self.skipped, self.computed
            ));
        }
        Err(anyhow::Error::new(ComputeFailed(text)))
    }
}

/// The keys `--force STAGE…` recomputes: every instance of those stages and everything
/// downstream of them in the plan. An unknown stage is a usage error.
pub fn forced_keys(plan: &Plan, stages: &[String]) -> anyhow::Result<BTreeSet<String>> {
    for s in stages {
        if crate::pipeline::registry::find(s).is_none() {
            return Err(crate::pipeline::error::UsageError(format!(
                "--force {s}: no such stage; use one of {}",
                crate::pipeline::registry::names().join(", ")
            ))
            .into());
        }
    }
    let mut forced = BTreeSet::new();
    // Instances are in level order: inputs come first.
    for inst in &plan.instances {
        if stages.contains(&inst.stage) || inst.inputs.iter().any(|r| forced.contains(&r.key)) {
            forced.insert(inst.key.clone());
        }
    }
    Ok(forced)
}

/// [`execute`], recomputing the instances whose keys are in `forced` even where stored (the
/// new entry replaces the old one only once it is complete).
pub fn execute_forcing(
    store: &Store,
    instances: &[Instance],
    forced: &BTreeSet<String>,
    retry_failed: bool,
    jobs: usize,
    at_once: usize,
    quiet: bool,
) -> anyhow::Result<Outcome> {
    let jobs = jobs.max(1);
    let at_once = at_once.max(1);
    let levels = instances.iter().map(|i| i.level + 1).max().unwrap_or(0);
    let mut outcome = Outcome::default();
    // Keys whose new entry replaces a stored one: the forced, and the outdated.
    let mut replace = forced.clone();
    // Keys that failed, now or before, and everything downstream of them.
    let mut blocked: BTreeSet<String> = BTreeSet::new();
    for level in 0..levels {
        let mut missing = Vec::new();
        for inst in instances.iter().filter(|i| i.level == level) {
            let wanted = if forced.contains(&inst.key) {
                true
            } else if let Some(m) = store.lookup(&inst.stage, &inst.key)? {
                // Computed from an input whose content has changed since (an input that
                // was damaged, then rebuilt): recomputed, and replaced once complete.
                let outdated = store.changed_input(&m)?.is_some();
                if outdated {
                    replace.insert(inst.key.clone());
                }
                outdated
            } else {
                true
            };
            if !wanted {
                continue;
            }
            if inst.inputs.iter().any(|r| blocked.contains(&r.key)) {
                blocked.insert(inst.key.clone());
                outcome.skipped += 1;
            } else if let Some(f) = (!retry_failed && !forced.contains(&inst.key))
                .then(|| store.failure(&inst.stage, &inst.key))
                .flatten()
            {
                blocked.insert(inst.key.clone());
                outcome.failed_before.push(f.error);
            } else {
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
        let results = build_all(store, &missing, &replace, jobs, at_once, &bar, lines)?;
        bar.finish_and_clear();
        for (inst, r) in missing.iter().zip(results) {
            match r {
                Ok(()) => outcome.computed += 1,
                Err(e) if e.downcast_ref::<ComputeFailed>().is_some() => {
                    blocked.insert(inst.key.clone());
                    outcome.failed.push(e.to_string());
                }
                Err(e) => return Err(e),
            }
        }
    }
    Ok(outcome)
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
    forced: &BTreeSet<String>,
    jobs: usize,
    at_once: usize,
    bar: &ProgressBar,
    lines: bool,
) -> anyhow::Result<Vec<anyhow::Result<()>>> {
    use std::sync::atomic::{AtomicUsize, Ordering};
    let workers = at_once.min(missing.len()).max(1);
    // One instance at a time: the process's peak memory is that instance's.
    let alone = workers == 1;
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
                        let replace = forced.contains(&inst.key);
                        let built =
                            pool.install(|| build(store, inst, &pool, before, replace, alone));
                        let verdict = if built.is_ok() { "done" } else { "FAILED" };
                        out.push((i, built));
                        bar.inc(1);
                        if lines {
                            crate::note!(
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

/// The error of an instance whose computation failed with `e` (its message `cause`, in the
/// user's paths). A failure of the computation itself (a solve that does not converge, a
/// degenerate input) is data: recorded for status, the catalog and an audit, never as an
/// entry that looks valid (the temporary entry is dropped). A failure of the machine (a full
/// disk, a permission) is not the instance's: it is only reported, and the next run tries
/// again.
fn failed(
    store: &Store,
    inst: &Instance,
    e: &anyhow::Error,
    cause: String,
    keys: Vec<String>,
    start: Instant,
) -> anyhow::Error {
    let message = format!(
        "stage {} ({}, realization {}, key {}) failed: {cause}",
        inst.stage,
        inst.name.as_ref().map_or_else(
            || format!("studies {}", inst.studies.join(", ")),
            |n| n.clone()
        ),
        inst.realization.map_or("-".to_string(), |r| r.to_string()),
        &inst.key[..12.min(inst.key.len())]
    );
    if !is_computational(e) {
        let note = if message.contains("bytes free") {
            String::new()
        } else {
            crate::io::disk_note(store.root())
        };
        return anyhow::Error::new(ComputeFailed(format!(
            "{message}{note} (not recorded as a failure: the next run tries again)"
        )));
    }
    if let Err(record) = store.record_failure(&Failure {
        stage: inst.stage.clone(),
        key: inst.key.clone(),
        params: inst.params.clone(),
        inputs: keys,
        studies: inst.studies.clone(),
        realization: inst.realization,
        error: message.clone(),
        report: failure_report(e),
        program: Program::current(),
        wall_seconds: start.elapsed().as_secs_f64(),
    }) {
        return record.into();
    }
    anyhow::Error::new(ComputeFailed(message))
}

/// Compute one instance on `pool` (whose threads had used `cpu_before` CPU seconds).
fn build(
    store: &Store,
    inst: &Instance,
    pool: &rayon::ThreadPool,
    cpu_before: f64,
    replace: bool,
    alone: bool,
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
    let key = crate::store::hash::instance_key(stage.name(), stage.version(), &inst.params, &keys);
    anyhow::ensure!(
        key == inst.key,
        "the plan's {} instance {} does not match its parameters (their key is {key}): the plan was edited or made by another version; make it anew with `wearcoef plan`",
        inst.stage,
        inst.key
    );
    let inputs = Inputs::load(store, &inst.inputs)?;
    let entry = store.begin(&inst.stage, &inst.key)?;
    // Messages in the user's terms: the entry's place in the store, not its temporary's.
    let (temporary, place) = (
        entry.path().display().to_string(),
        store
            .entry_dir(&inst.stage, &inst.key)
            .display()
            .to_string(),
    );
    let plain = |e: &dyn std::fmt::Display| format!("{e:#}").replace(&temporary, &place);
    if let Some(src) = &inst.source {
        // A measured file: copied in, so the entry holds what it was computed from (the
        // stage checks its hash against the key's).
        std::fs::copy(&src.path, entry.path().join(&src.file)).map_err(|e| {
            crate::pipeline::error::UsageError(format!(
                "{}: cannot be read ({e}); a measured study's files must stay where the plan found them",
                src.path.display()
            ))
        })?;
    }
    let measured = alone && crate::machine::reset_peak_rss();
    let results = match stage.compute(&inst.params, &inputs, entry.path()) {
        Ok(results) => results,
        Err(e) => {
            let cause = plain(&e);
            drop(entry);
            return Err(failed(store, inst, &e, cause, keys, start));
        }
    };
    if let Some(src) = &inst.source {
        crate::io::prepare::announce(&src.path.display().to_string(), &results);
    }
    crate::store::table::stamp(
        entry.path(),
        &crate::store::table::TableOrigin {
            stage: &inst.stage,
            key: &inst.key,
            params: &inst.params,
            realization: inst.realization,
        },
    )
    .map_err(|e| anyhow::anyhow!(plain(&e)))?;
    let wall_seconds = start.elapsed().as_secs_f64();
    let cpu_after: f64 = pool.broadcast(|_| thread_cpu_seconds()).iter().sum();
    let manifest = Manifest {
        stage: inst.stage.clone(),
        version: stage.version(),
        key: inst.key.clone(),
        params: inst.params.clone(),
        inputs: keys,
        input_digests: inputs.digests(),
        outputs: Default::default(),
        program: Program::current(),
        wall_seconds,
        cpu_seconds: Some((cpu_after - cpu_before).max(0.0)),
        peak_rss_bytes: measured.then(crate::machine::peak_rss_bytes).flatten(),
        results,
        results_sha256: None,
    };
    let outcome = if replace {
        entry.commit_replacing(manifest)
    } else {
        entry.commit(manifest)
    }
    .map_err(|e| anyhow::anyhow!(plain(&e)))?;
    match outcome {
        CommitOutcome::Stored | CommitOutcome::AlreadyPresent => {
            store.clear_failure(&inst.stage, &inst.key)?;
            Ok(())
        }
    }
}

/// A stage's computation failed (recorded in the store's `failed/`); the run goes on with
/// whatever does not depend on it.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct ComputeFailed(pub String);

/// Whether a stage's error is a property of its inputs and parameters (a sweep that does not
/// converge, a degenerate surface), which the same computation would meet again.
fn is_computational(e: &anyhow::Error) -> bool {
    use crate::contact::sweep::SweepError;
    e.chain().any(|c| {
        c.downcast_ref::<SweepError>()
            .is_some_and(|s| !matches!(s, SweepError::Callback(_)))
    })
}

/// What a failed computation reported, as JSON: the contact sweep's non-convergence
/// (load, W/W0, solver status, iterations, last error, tolerance), else `null`.
fn failure_report(e: &anyhow::Error) -> Value {
    use crate::contact::sweep::SweepError;
    for c in e.chain() {
        if let Some(SweepError::NotConverged {
            index,
            w_over_w0,
            status,
            iterations,
            error,
            tolerance,
        }) = c.downcast_ref::<SweepError>()
        {
            return serde_json::json!({
                "load_index": index,
                "w_over_w0": w_over_w0,
                "solver_status": format!("{status:?}"),
                "iterations": iterations,
                "last_error": error,
                "tolerance": tolerance,
            });
        }
    }
    Value::Null
}
