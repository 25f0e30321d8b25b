//! `run`, `status`, `verify`, `clean`.

use std::path::PathBuf;
use std::process::ExitCode;

use serde_json::json;

use super::{load, InputError, StoreArgs};
use wearcoef::pipeline::runner::{self, RunOptions};
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
        println!("{}", serde_json::to_string(&summary)?);
    } else {
        println!("{summary}");
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
    let lines = runner::status(&pipeline, &origin, &Store::new(&store.data), &profile)?;
    if json {
        println!(
            "{}",
            serde_json::to_string(&json!({"profile": profile, "stages": lines}))?
        );
    } else {
        println!(
            "{:<10} {:<24} {:>8} {:>8}",
            "stage", "study", "present", "missing"
        );
        for l in &lines {
            println!(
                "{:<10} {:<24} {:>8} {:>8}",
                l.stage, l.study, l.present, l.missing
            );
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
    let store = Store::new(&data);
    let (checked, problems) = store.verify()?;
    if json {
        println!(
            "{}",
            serde_json::to_string(&json!({"checked": checked, "problems": problems}))?
        );
    } else {
        for p in &problems {
            println!("MISMATCH {}: {}", p.path, p.reason);
        }
        println!("verified {checked} entries: {} problem(s)", problems.len());
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
        println!(
            "removed {} corrupt entries and {stale} stale temporary directories",
            removed.len()
        );
    } else {
        store.remove_all()?;
        println!("removed {}", data.display());
    }
    Ok(ExitCode::SUCCESS)
}
