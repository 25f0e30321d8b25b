//! `run`, `status`, `verify`, `clean`.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use serde_json::json;

use super::checks::{load, InputError, StoreArgs};
use wearcoef::pipeline::runner::{self, RunOptions};
use wearcoef::pipeline::slurm;
use wearcoef::store::Store;

#[derive(clap::Args)]
pub struct RunArgs {
    pub targets: Vec<String>,
    #[command(flatten)]
    pub store: StoreArgs,
    /// Profile declared in the pipeline file.
    #[arg(long, default_value = "default")]
    pub profile: String,
    /// Instances computed side by side, each on min(JOBS, cores) threads [default: number
    /// of cores].
    #[arg(long)]
    pub jobs: Option<usize>,
    /// Instances side by side instead of JOBS; 1 computes one at a time on all its threads
    /// and records each instance's peak memory in its manifest.
    #[arg(long)]
    pub at_once: Option<usize>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
    /// Where the galleries go: the figures of a profile, its provenance.json and index.html
    /// land in FIGURES/<profile>/ (everything else stays under --data).
    #[arg(long, default_value = "figures")]
    pub figures: PathBuf,
    /// Print what would be computed and why (missing, changed parameter, stage version,
    /// input changed, forced), compute nothing.
    #[arg(long)]
    pub dry_run: bool,
    /// Recompute this stage's instances even where stored, and everything downstream of them
    /// (repeatable).
    #[arg(long, value_name = "STAGE")]
    pub force: Vec<String>,
    /// Compute again the instances whose computation failed in an earlier run (by default
    /// a recorded failure is reported, not retried).
    #[arg(long)]
    pub retry_failed: bool,
}

pub fn run(args: RunArgs) -> anyhow::Result<ExitCode> {
    let RunArgs {
        targets,
        store,
        profile,
        jobs,
        at_once,
        quiet,
        json,
        figures,
        dry_run,
        force,
        retry_failed,
    } = args;
    let pipeline = load(&store.config)?;
    super::checks::check_dir("--data", &store.data)?;
    super::checks::check_dir("--figures", &figures)?;
    if super::checks::same_dir(&store.data, &figures) {
        return Err(InputError(format!(
            "--figures {} is the data directory: the gallery and the catalog of a profile would share one directory; give the figures their own (default: figures)",
            figures.display()
        ))
        .into());
    }
    let jobs = jobs.unwrap_or_else(wearcoef::machine::cores);
    // Up to `jobs` instances at once, each on a pool of at most one thread per core.
    super::checks::check_threads(
        &format!("--jobs {jobs}"),
        at_once.unwrap_or(jobs),
        jobs.min(wearcoef::machine::cores()),
    )?;
    let opts = RunOptions {
        profile,
        targets,
        jobs,
        at_once,
        quiet,
        figures,
        force,
        retry_failed,
    };
    let origin = store.config.display().to_string();
    if dry_run {
        let pending = wearcoef::pipeline::status::dry_run(
            &pipeline,
            &origin,
            &Store::new(&store.data),
            &opts,
        )?;
        if json {
            out!("{}", serde_json::to_string(&pending)?)?;
        } else {
            for p in &pending {
                out!("{} {}", p.id.columns(12), p.reason)?;
            }
            out!(
                "wearcoef run --profile {} would compute {} instance(s)",
                opts.profile,
                pending.len()
            )?;
        }
        return Ok(ExitCode::SUCCESS);
    }
    let summary = runner::run(&pipeline, &origin, &Store::new(&store.data), &opts)?;
    if json {
        out!("{}", serde_json::to_string(&summary)?)?;
    } else {
        out!("{summary}")?;
    }
    Ok(ExitCode::SUCCESS)
}

#[derive(clap::Args)]
pub struct StatusArgs {
    #[command(flatten)]
    pub store: StoreArgs,
    #[arg(long, default_value = "default")]
    pub profile: String,
    /// Everything as JSON: totals, per stage and study, every instance with its key.
    #[arg(long)]
    pub json: bool,
    /// Also list every instance: stage, studies or figure, realization, key, present/missing.
    #[arg(long)]
    pub keys: bool,
}

pub fn status(args: StatusArgs) -> anyhow::Result<ExitCode> {
    let StatusArgs {
        store,
        profile,
        json,
        keys,
    } = args;
    let pipeline = load(&store.config)?;
    let origin = store.config.display().to_string();
    let wearcoef::pipeline::status::Status {
        per_stage,
        per_study: lines,
        totals,
        instances,
    } = wearcoef::pipeline::status::status(&pipeline, &origin, &Store::new(&store.data), &profile)?;
    let campaigns = wearcoef::pipeline::campaign::campaigns(&store.data, &profile)?;
    let ids: Vec<String> = campaigns.iter().flat_map(|(_, c)| c.job_ids()).collect();
    let states = if ids.is_empty() {
        Default::default()
    } else {
        slurm::states(&ids)
    };
    let campaign_json = campaigns_json(&campaigns, &states);
    if json {
        out!(
            "{}",
            serde_json::to_string(&json!({
                "profile": profile,
                "totals": totals,
                "instances": instances,
                "stages": lines,
                "per_stage": per_stage,
                "campaigns": campaign_json,
            }))?
        )?;
        return Ok(ExitCode::SUCCESS);
    }
    out!(
        "{:<10} {:>8} {:>8} {:>8}",
        "stage",
        "present",
        "missing",
        "(failed)"
    )?;
    for l in per_stage.iter().chain([&totals]) {
        out!(
            "{:<10} {:>8} {:>8} {:>8}",
            l.stage,
            l.present,
            l.missing,
            l.failed
        )?;
    }
    for i in instances.iter().filter(|i| i.state == "failed") {
        out!("FAILED {}", i.error.as_deref().unwrap_or(""))?;
    }
    if keys {
        out!()?;
        for i in &instances {
            out!("{} {}", i.id.columns(usize::MAX), i.state)?;
        }
    }
    out!()?;
    out!(
        "{:<10} {:<24} {:>8} {:>8}",
        "stage",
        "study",
        "present",
        "missing"
    )?;
    for l in &lines {
        out!(
            "{:<10} {:<24} {:>8} {:>8}",
            l.stage,
            l.study,
            l.present,
            l.missing
        )?;
    }
    print_campaigns(&campaigns, &states)?;
    Ok(ExitCode::SUCCESS)
}

type Campaigns = [(PathBuf, wearcoef::pipeline::campaign::Campaign)];
type States = std::collections::BTreeMap<String, slurm::JobStates>;

/// The submitted campaigns of `status --json`: per array chunk its job and task states.
fn campaigns_json(campaigns: &Campaigns, states: &States) -> Vec<serde_json::Value> {
    campaigns
        .iter()
        .map(|(dir, c)| {
            let arrays: Vec<_> = c
                .arrays
                .iter()
                .flat_map(|a| {
                    a.chunks.iter().map(|ch| {
                        let id = ch.job_id.clone().unwrap_or_default();
                        let st = states.get(&id).cloned().unwrap_or_default();
                        json!({
                            "array": a.spec.name,
                            "level": a.spec.level,
                            "job_id": id,
                            "tasks": ch.chunk.len,
                            "states": st.counts(),
                            "finished_from": st.finished_from,
                        })
                    })
                })
                .collect();
            json!({"dir": dir.display().to_string(), "created": c.created, "arrays": arrays})
        })
        .collect()
}

/// The submitted campaigns in `status`'s text: per array chunk its job and task states.
fn print_campaigns(campaigns: &Campaigns, states: &States) -> anyhow::Result<()> {
    for (dir, c) in campaigns {
        out!(
            "\ncampaign {} ({} instances submitted)",
            dir.display(),
            c.instances
        )?;
        for a in &c.arrays {
            for ch in &a.chunks {
                let id = ch.job_id.clone().unwrap_or_default();
                let st = states.get(&id).cloned().unwrap_or_default();
                let mut counts: Vec<String> = st
                    .counts()
                    .into_iter()
                    .map(|(s, n)| format!("{n} {s}"))
                    .collect();
                let unknown = ch.chunk.len.saturating_sub(st.tasks.len());
                if unknown > 0 {
                    counts.push(format!(
                        "{unknown} left the queue (no record: see the store above)"
                    ));
                }
                out!(
                    "  job {:<8} {:<24} {:>5} tasks: {}",
                    id,
                    a.spec.name,
                    ch.chunk.len,
                    counts.join(", ")
                )?;
            }
        }
    }
    Ok(())
}

#[derive(clap::Args)]
pub struct VerifyArgs {
    #[arg(long, default_value = "data")]
    pub data: PathBuf,
    #[arg(long)]
    pub json: bool,
}

pub fn verify(args: VerifyArgs) -> anyhow::Result<ExitCode> {
    let VerifyArgs { data, json } = args;
    let store = Store::existing(&data)?;
    let (checked, mut problems) = store.verify()?;
    let (rows, catalog_problems) = wearcoef::pipeline::catalog::verify(&store)?;
    problems.extend(catalog_problems);
    if json {
        out!(
            "{}",
            serde_json::to_string(
                &json!({"checked": checked, "catalog_rows": rows, "problems": problems})
            )?
        )?;
    } else {
        for p in &problems {
            out!("MISMATCH {}: {}", p.path, p.reason)?;
        }
        out!(
            "verified {checked} entries and {rows} catalog rows: {} problem(s)",
            problems.len()
        )?;
    }
    if !problems.is_empty() {
        return Ok(ExitCode::from(1));
    }
    Ok(ExitCode::SUCCESS)
}

#[derive(clap::Args)]
pub struct CleanArgs {
    /// The store to remove. Only a directory whose every file is one a store holds
    /// (cache/, failed/, campaigns/, catalogs) is removed; anything else is refused.
    #[arg(long, default_value = "data")]
    pub data: PathBuf,
    /// Remove only the entries that fail `wearcoef verify`, those computed from an input
    /// that has changed since, and the temporaries of dead processes.
    #[arg(long)]
    pub corrupt: bool,
    /// Say what would be removed, remove nothing.
    #[arg(long)]
    pub dry_run: bool,
}

pub fn clean(args: CleanArgs) -> anyhow::Result<ExitCode> {
    let CleanArgs {
        data,
        corrupt,
        dry_run,
    } = args;
    let store = Store::existing(&data)?;
    let verb = if dry_run { "would remove" } else { "removed" };
    if corrupt {
        let removed = if dry_run {
            store.verify()?.1.into_iter().map(|p| p.path).collect()
        } else {
            store.remove_corrupt()?
        };
        for path in &removed {
            out!("{verb} {path}")?;
        }
        let stale = if dry_run {
            0
        } else {
            store.remove_stale_temporaries()?
        };
        out!(
            "{verb} {} damaged or outdated entries and {stale} stale temporary directories",
            removed.len()
        )?;
        return Ok(ExitCode::SUCCESS);
    }
    let contents = store.contents(&wearcoef::pipeline::registry::names()).map_err(|why| {
        InputError(format!(
            "--data {}: {why}; clean removes only a store, so nothing was removed (remove other files yourself)",
            data.display()
        ))
    })?;
    let here = std::env::current_dir()?;
    let root = data.canonicalize()?;
    if here.starts_with(&root) && root != here {
        return Err(InputError(format!(
            "--data {}: holds the working directory {}; run clean from outside it",
            data.display(),
            here.display()
        ))
        .into());
    }
    if !dry_run {
        store
            .remove_contents(&contents)
            .with_context(|| format!("removing the store {}", data.display()))?;
    }
    out!("{verb} the store {}: {contents}", data.display())?;
    Ok(ExitCode::SUCCESS)
}

#[derive(Clone, Copy, clap::ValueEnum)]
pub enum CatalogFormat {
    Csv,
    Parquet,
}

#[derive(clap::Args)]
pub struct CatalogArgs {
    #[command(flatten)]
    pub store: StoreArgs,
    #[arg(long, default_value = "default")]
    pub profile: String,
    /// csv (to standard output, or --output) or parquet (needs --output).
    #[arg(long, value_enum, default_value = "csv")]
    pub format: CatalogFormat,
    /// One row per instance of this stage with its parameters and results, instead of one
    /// row per file.
    #[arg(long)]
    pub stage: Option<String>,
    /// Write here instead of standard output.
    #[arg(long, short)]
    pub output: Option<PathBuf>,
}

/// The catalog of a profile, built from the store as it is now (nothing runs).
pub fn catalog(args: CatalogArgs) -> anyhow::Result<ExitCode> {
    use wearcoef::pipeline::catalog::{write_csv, write_csv_to, Catalog};
    use wearcoef::pipeline::plan::Plan;
    let CatalogArgs {
        store,
        profile,
        format,
        stage,
        output,
    } = args;
    if let Some(s) = &stage {
        if wearcoef::pipeline::registry::find(s).is_none() {
            return Err(InputError(format!(
                "--stage {s}: no such stage; use one of {}",
                wearcoef::pipeline::registry::names().join(", ")
            ))
            .into());
        }
    }
    if matches!(format, CatalogFormat::Parquet) && output.is_none() {
        return Err(InputError(
            "--format parquet needs --output FILE (Parquet is not written to a terminal)".into(),
        )
        .into());
    }
    let pipeline = load(&store.config)?;
    if let Some(path) = &output {
        super::checks::check_outputs_of_pipeline(&[("--output", path)], &store.config, &pipeline)?;
    }
    let data = Store::existing(&store.data)?;
    let origin = store.config.display().to_string();
    let plan = Plan::build(&pipeline, &origin, &profile, &[])?;
    let studies = pipeline.plan(&profile, &origin)?;
    let cat = Catalog::collect(&data, &profile, &plan.instances, &studies)?;
    let df = match &stage {
        Some(s) => cat.stage_frame(s)?,
        None => cat.files_frame()?,
    };
    match (format, output) {
        (CatalogFormat::Csv, None) => {
            let mut w = csv::Writer::from_writer(std::io::stdout().lock());
            write_csv_to(&mut w, &df)?;
            w.flush()?;
        }
        (CatalogFormat::Csv, Some(path)) => write_csv(&path, &df)?,
        (CatalogFormat::Parquet, Some(path)) => {
            let kv = vec![
                ("wearcoef.profile".to_string(), profile.clone()),
                (
                    "wearcoef.store_root".to_string(),
                    std::path::absolute(data.root())?.display().to_string(),
                ),
            ];
            wearcoef::store::table::write_with_metadata(&path, df, kv)?;
        }
        (CatalogFormat::Parquet, None) => unreachable!("checked above"),
    }
    Ok(ExitCode::SUCCESS)
}

#[derive(clap::Args)]
pub struct GcArgs {
    #[command(flatten)]
    pub store: StoreArgs,
    /// List what would be removed, remove nothing.
    #[arg(long)]
    pub dry_run: bool,
    #[arg(long)]
    pub json: bool,
}

/// Remove the store entries that no profile of the pipeline file references (and the
/// temporaries of dead processes of this host).
pub fn gc(args: GcArgs) -> anyhow::Result<ExitCode> {
    use std::collections::BTreeSet;
    use wearcoef::pipeline::plan::Plan;
    let GcArgs {
        store,
        dry_run,
        json,
    } = args;
    let data = Store::existing(&store.data)?;
    let pipeline = load(&store.config)?;
    let origin = store.config.display().to_string();
    // Every profile must plan, or nothing is removed: an entry only an unplannable profile
    // references must not go.
    let mut referenced: BTreeSet<(String, String)> = BTreeSet::new();
    for profile in pipeline.profile_names() {
        let plan = Plan::build(&pipeline, &origin, &profile, &[])?;
        referenced.extend(plan.instances.into_iter().map(|i| (i.stage, i.key)));
    }
    let mut removed = Vec::new();
    let mut bytes = 0u64;
    for (stage, key, dir) in data.entries()? {
        if referenced.contains(&(stage.clone(), key.clone())) {
            continue;
        }
        let size: u64 = std::fs::read_dir(&dir)?
            .filter_map(|e| e.ok()?.metadata().ok())
            .map(|m| m.len())
            .sum();
        if !dry_run {
            data.remove_entry(&dir)?;
        }
        bytes += size;
        removed.push(json!({"stage": stage, "key": key, "bytes": size}));
    }
    for (stage, key, path) in data.failures()? {
        if referenced.contains(&(stage.clone(), key.clone())) {
            continue;
        }
        if !dry_run {
            std::fs::remove_file(&path)?;
        }
        removed.push(json!({"stage": stage, "key": key, "failed": true, "bytes": 0}));
    }
    let temporaries = if dry_run {
        0
    } else {
        data.remove_stale_temporaries()?
    };
    let verb = if dry_run { "would remove" } else { "removed" };
    if json {
        out!(
            "{}",
            serde_json::to_string(&json!({
                "dry_run": dry_run,
                "entries": removed,
                "bytes": bytes,
                "kept": referenced.len(),
                "temporaries": temporaries,
            }))?
        )?;
    } else {
        for r in &removed {
            out!(
                "{verb} {}/{}",
                r["stage"].as_str().unwrap_or(""),
                r["key"].as_str().unwrap_or("")
            )?;
        }
        out!(
            "{verb} {} unreferenced entries ({:.1} MiB) and {temporaries} stale temporary directories; the profiles of {} reference {} instances",
            removed.len(),
            bytes as f64 / (1u64 << 20) as f64,
            store.config.display(),
            referenced.len()
        )?;
    }
    Ok(ExitCode::SUCCESS)
}
