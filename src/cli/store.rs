//! `run`, `status`, `verify`, `clean`.

use std::path::PathBuf;
use std::process::ExitCode;

use serde_json::json;

use super::{load, InputError, StoreArgs};
use wearcoef::pipeline::runner::{self, RunOptions};
use wearcoef::pipeline::slurm;
use wearcoef::pipeline::store::Store;

#[derive(clap::Args)]
pub struct RunArgs {
    pub targets: Vec<String>,
    #[command(flatten)]
    pub store: StoreArgs,
    /// Profile declared in the pipeline file.
    #[arg(long, default_value = "default")]
    pub profile: String,
    /// Worker threads [default: number of cores].
    #[arg(long)]
    pub jobs: Option<usize>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: RunArgs) -> anyhow::Result<ExitCode> {
    let RunArgs {
        targets,
        store,
        profile,
        jobs,
        quiet,
        json,
    } = args;
    let pipeline = load(&store.config)?;
    let jobs = jobs.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    if jobs == 0 {
        return Err(InputError("--jobs must be ≥ 1".into()).into());
    }
    let opts = RunOptions {
        profile,
        targets,
        jobs,
        quiet,
    };
    let origin = store.config.display().to_string();
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
    #[arg(long)]
    pub json: bool,
}

pub fn status(args: StatusArgs) -> anyhow::Result<ExitCode> {
    let StatusArgs {
        store,
        profile,
        json,
    } = args;
    let pipeline = load(&store.config)?;
    let origin = store.config.display().to_string();
    let runner::Status {
        per_stage,
        per_study: lines,
    } = runner::status(&pipeline, &origin, &Store::new(&store.data), &profile)?;
    let campaigns = super::submit::campaigns(&store.data, &profile)?;
    let ids: Vec<String> = campaigns.iter().flat_map(|(_, c)| c.job_ids()).collect();
    let states = if ids.is_empty() {
        Default::default()
    } else {
        slurm::states(&ids)
    };
    let campaign_json: Vec<_> = campaigns
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
        .collect();
    if json {
        out!(
            "{}",
            serde_json::to_string(&json!({
                "profile": profile,
                "stages": lines,
                "per_stage": per_stage,
                "campaigns": campaign_json,
            }))?
        )?;
        return Ok(ExitCode::SUCCESS);
    }
    out!("{:<10} {:>8} {:>8}", "stage", "present", "missing")?;
    for l in &per_stage {
        out!("{:<10} {:>8} {:>8}", l.stage, l.present, l.missing)?;
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
    for (dir, c) in &campaigns {
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
    Ok(ExitCode::SUCCESS)
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
    if !data.join("cache").is_dir() {
        return Err(InputError(format!(
            "--data {}: no store there (no cache/ directory); give the data directory a run \
             wrote (default: data)",
            data.display()
        ))
        .into());
    }
    let store = Store::new(&data);
    let (checked, problems) = store.verify()?;
    if json {
        out!(
            "{}",
            serde_json::to_string(&json!({"checked": checked, "problems": problems}))?
        )?;
    } else {
        for p in &problems {
            out!("MISMATCH {}: {}", p.path, p.reason)?;
        }
        out!("verified {checked} entries: {} problem(s)", problems.len())?;
    }
    if !problems.is_empty() {
        return Ok(ExitCode::from(1));
    }
    Ok(ExitCode::SUCCESS)
}

#[derive(clap::Args)]
pub struct CleanArgs {
    #[arg(long, default_value = "data")]
    pub data: PathBuf,
    #[arg(long)]
    pub corrupt: bool,
}

pub fn clean(args: CleanArgs) -> anyhow::Result<ExitCode> {
    let CleanArgs { data, corrupt } = args;
    let store = Store::new(&data);
    if corrupt {
        let removed = store.remove_corrupt()?;
        let stale = store.remove_stale_temporaries()?;
        out!(
            "removed {} corrupt entries and {stale} stale temporary directories",
            removed.len()
        )?;
    } else {
        store.remove_all()?;
        out!("removed {}", data.display())?;
    }
    Ok(ExitCode::SUCCESS)
}
