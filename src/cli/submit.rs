//! `wearcoef submit`: the missing instances of a profile as Slurm job arrays, one `sbatch`
//! per array chunk, all submitted at once and chained level by level with
//! `--dependency=afterok`. No process stays behind on the login node.
//!
//! A campaign directory `D/campaigns/<profile>/<UTC time>/` keeps what was submitted: the
//! plan of each array (`<array>.json`, read by `wearcoef exec`), its batch scripts
//! (`<array>[-c<chunk>].sh`), the tasks' logs (`logs/`) and `campaign.json` (arrays,
//! resources, estimates, job ids), which `wearcoef status` reads.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context;

use wearcoef::config::ClusterConfig;
use wearcoef::pipeline::campaign::{self, Campaign, CampaignArray, ScriptContext, SubmittedChunk};
use wearcoef::pipeline::slurm;
use wearcoef::pipeline::UsageError;

use super::checks::{load, StoreArgs};

#[derive(clap::Args)]
pub struct SubmitArgs {
    /// Stage, study or figure names (default: the whole profile).
    pub targets: Vec<String>,
    #[command(flatten)]
    pub store: StoreArgs,
    #[arg(long, default_value = "default")]
    pub profile: String,
    /// Overrides of the pipeline file's `cluster:` block.
    #[arg(long)]
    pub partition: Option<String>,
    #[arg(long)]
    pub account: Option<String>,
    #[arg(long)]
    pub qos: Option<String>,
    /// At most this many tasks of one array at once (`--array=…%N`).
    #[arg(long)]
    pub throttle: Option<u32>,
    /// CPUs of each contact sweep or surface task.
    #[arg(long)]
    pub solve_cpus: Option<u32>,
    /// Pack small instances into tasks of about this many estimated minutes.
    #[arg(long)]
    pub task_minutes: Option<f64>,
    #[arg(long)]
    pub memory_safety: Option<f64>,
    #[arg(long)]
    pub time_safety: Option<f64>,
    #[arg(long)]
    pub min_minutes: Option<f64>,
    #[arg(long)]
    pub max_array_size: Option<u32>,
    /// The wearcoef binary the tasks run [default: this one].
    #[arg(long)]
    pub binary: Option<PathBuf>,
    /// Write the batch scripts and print them; submit nothing.
    #[arg(long)]
    pub dry_run: bool,
}

fn cluster_config(base: &ClusterConfig, a: &SubmitArgs) -> ClusterConfig {
    let mut c = base.clone();
    if a.partition.is_some() {
        c.partition = a.partition.clone();
    }
    if a.account.is_some() {
        c.account = a.account.clone();
    }
    if a.qos.is_some() {
        c.qos = a.qos.clone();
    }
    c.throttle = a.throttle.or(c.throttle);
    c.solve_cpus = a.solve_cpus.unwrap_or(c.solve_cpus);
    c.task_minutes = a.task_minutes.unwrap_or(c.task_minutes);
    c.memory_safety = a.memory_safety.unwrap_or(c.memory_safety);
    c.time_safety = a.time_safety.unwrap_or(c.time_safety);
    c.min_minutes = a.min_minutes.unwrap_or(c.min_minutes);
    c.max_array_size = a.max_array_size.unwrap_or(c.max_array_size);
    c
}

/// A path for a batch script: absolute, and without characters that need care in
/// `#SBATCH` lines.
fn script_path(p: &Path, what: &str) -> anyhow::Result<String> {
    let s = p
        .to_str()
        .with_context(|| format!("{what} {} is not valid UTF-8", p.display()))?;
    if s.chars()
        .any(|c| c.is_whitespace() || c == '%' || c == '\'')
    {
        return Err(UsageError(format!(
            "{what} {s}: Slurm's #SBATCH lines cannot hold spaces, '%' or quotes; use a path without them"
        ))
        .into());
    }
    Ok(s.to_string())
}

/// A fresh campaign directory under `D/campaigns/<profile>/`.
fn campaign_dir(data: &Path, profile: &str, dry_run: bool) -> anyhow::Result<(PathBuf, String)> {
    let now = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let stamp = campaign::utc_stamp(now);
    let base = data.join("campaigns").join(profile);
    std::fs::create_dir_all(&base).with_context(|| format!("cannot create {}", base.display()))?;
    for k in 0.. {
        let mut name = stamp.clone();
        if k > 0 {
            name.push_str(&format!("-{k}"));
        }
        if dry_run {
            name.push_str("-dry-run");
        }
        let dir = base.join(&name);
        if std::fs::create_dir(&dir).is_ok() {
            std::fs::create_dir(dir.join("logs"))?;
            return Ok((dir, stamp));
        }
    }
    unreachable!("some suffix is free")
}

/// The pipeline's `cluster:` block with the command line's overrides, checked. The file's
/// block was checked when it was loaded: what fails here came from an option, and the
/// message names the option and the field it overrides.
fn checked_cluster(
    pipeline: &wearcoef::config::Pipeline,
    args: &SubmitArgs,
    origin: &str,
) -> anyhow::Result<ClusterConfig> {
    let cluster = cluster_config(&pipeline.cluster, args);
    cluster.validate(origin).map_err(|e| match e {
        wearcoef::config::ConfigError::Invalid {
            field,
            value,
            allowed,
            ..
        } => {
            let name = field.trim_start_matches("cluster.");
            anyhow::Error::from(super::checks::InputError(format!(
                "--{} {value} (cluster.{name} of {origin}): {allowed}",
                name.replace('_', "-")
            )))
        }
        other => other.into(),
    })?;
    Ok(cluster)
}

pub fn submit(args: SubmitArgs) -> anyhow::Result<ExitCode> {
    let pipeline = load(&args.store.config)?;
    let origin = args.store.config.display().to_string();
    let cluster = checked_cluster(&pipeline, &args, &origin)?;
    std::fs::create_dir_all(&args.store.data)
        .with_context(|| format!("cannot create {}", args.store.data.display()))?;
    let data = args.store.data.canonicalize()?;
    let (plan, _model) =
        super::plan::make_plan(&pipeline, &origin, &data, &args.profile, &args.targets)?;
    let missing = plan.instances.iter().filter(|i| !i.cached).count();
    if missing == 0 {
        out!(
            "nothing to submit: the store holds all {} instances of profile {}; `wearcoef run --profile {}` (or `make figures PROFILE={}`) exports the figures and writes the catalog",
            plan.instances.len(),
            args.profile,
            args.profile,
            args.profile
        )?;
        return Ok(ExitCode::SUCCESS);
    }
    if !args.dry_run && !slurm::available() {
        return Err(UsageError(
            "sbatch is not available here: run `wearcoef submit` on a Slurm login node, or use --dry-run to see the scripts (docs/CLUSTER.md shows how to run a plan without Slurm)".into(),
        )
        .into());
    }
    let node = slurm::node_limits(cluster.partition.as_deref());
    let max_array_size = slurm::config_value("MaxArraySize")
        .and_then(|v| v.parse::<u32>().ok())
        .map_or(cluster.max_array_size, |m| m.min(cluster.max_array_size));
    let arrays = campaign::arrays(&plan, &cluster, node)?;
    let binary = match &args.binary {
        Some(b) => b.clone(),
        None => std::env::current_exe()?.canonicalize()?,
    };
    let binary = script_path(&binary, "the binary")?;
    let data_s = script_path(&data, "the data directory")?;
    let (dir, created) = campaign_dir(&data, &args.profile, args.dry_run)?;
    let dir_s = script_path(&dir, "the campaign directory")?;
    let ctx = ScriptContext {
        profile: &args.profile,
        binary: &binary,
        data: &data_s,
        campaign_dir: &dir_s,
        partition: cluster.partition.as_deref(),
        account: cluster.account.as_deref(),
        qos: cluster.qos.as_deref(),
        throttle: cluster.throttle,
    };
    let mut record = Campaign {
        profile: args.profile.clone(),
        created,
        submitted: !args.dry_run,
        binary: binary.clone(),
        data: data_s.clone(),
        cluster: cluster.clone(),
        node,
        max_array_size,
        instances: missing,
        core_hours: arrays.iter().map(|a| a.spec.core_seconds).sum::<f64>() / 3600.0,
        arrays: Vec::new(),
    };
    for a in &arrays {
        let plan_file = dir.join(format!("{}.json", a.spec.name));
        std::fs::write(&plan_file, serde_json::to_vec_pretty(&a.plan)?)?;
        let plan_s = script_path(&plan_file, "the plan file")?;
        let parts = campaign::chunks(a.spec.tasks, max_array_size);
        let mut chunks = Vec::new();
        for (k, chunk) in parts.iter().enumerate() {
            let suffix = if parts.len() > 1 {
                format!("-c{k}")
            } else {
                String::new()
            };
            let script = dir.join(format!("{}{suffix}.sh", a.spec.name));
            std::fs::write(
                &script,
                campaign::render_script(&ctx, &a.spec, *chunk, &plan_s),
            )?;
            chunks.push(SubmittedChunk {
                chunk: *chunk,
                script: script.display().to_string(),
                job_id: None,
            });
        }
        record.arrays.push(CampaignArray {
            spec: a.spec.clone(),
            plan: plan_s,
            chunks,
        });
    }
    if args.dry_run {
        for a in &record.arrays {
            for c in &a.chunks {
                out!("# ---- {}", c.script)?;
                {
                    use std::io::Write as _;
                    write!(
                        std::io::stdout().lock(),
                        "{}",
                        std::fs::read_to_string(&c.script)?
                    )
                }?;
            }
        }
    } else {
        submit_all(&mut record)?;
    }
    let json = dir.join("campaign.json");
    std::fs::write(&json, serde_json::to_vec_pretty(&record)?)?;
    print_summary(&record, &dir)?;
    Ok(ExitCode::SUCCESS)
}

/// Submit every chunk, each level after the previous one (`afterok`). If any `sbatch`
/// fails, cancel what was submitted: a campaign runs whole or not at all.
fn submit_all(record: &mut Campaign) -> anyhow::Result<()> {
    let mut after: Vec<String> = Vec::new();
    let mut this_level: Vec<String> = Vec::new();
    let mut level = None;
    let mut submitted: Vec<String> = Vec::new();
    for a in &mut record.arrays {
        if level != Some(a.spec.level) {
            if !this_level.is_empty() {
                after = std::mem::take(&mut this_level);
            }
            level = Some(a.spec.level);
        }
        for c in &mut a.chunks {
            match slurm::sbatch(Path::new(&c.script), &after) {
                Ok(id) => {
                    c.job_id = Some(id.clone());
                    this_level.push(id.clone());
                    submitted.push(id);
                }
                Err(e) => {
                    slurm::scancel(&submitted);
                    return Err(e.context(format!(
                        "submission stopped; the {} array(s) already submitted were cancelled",
                        submitted.len()
                    )));
                }
            }
        }
    }
    Ok(())
}

fn print_summary(record: &Campaign, dir: &Path) -> std::io::Result<()> {
    out!(
        "{:<32} {:>6} {:>9} {:>5} {:>9} {:>11}  job ids",
        "array",
        "tasks",
        "instances",
        "cpus",
        "mem MiB",
        "time"
    )?;
    for a in &record.arrays {
        let r = a.spec.resources;
        let ids: Vec<String> = a.chunks.iter().filter_map(|c| c.job_id.clone()).collect();
        out!(
            "{:<32} {:>6} {:>9} {:>5} {:>9} {:>11}  {}",
            a.spec.name,
            a.spec.tasks,
            a.spec.instances,
            r.cpus,
            r.memory_mib,
            campaign::slurm_time(r.minutes),
            if ids.is_empty() {
                "-".to_string()
            } else {
                ids.join(",")
            }
        )?;
    }
    let verb = if record.submitted {
        "submitted"
    } else {
        "written (dry run, nothing submitted)"
    };
    out!(
        "profile {}: {} missing instances in {} arrays {verb}; {:.2} core-hours estimated; campaign {}",
        record.profile,
        record.instances,
        record.arrays.len(),
        record.core_hours,
        dir.display()
    )?;
    if record.submitted {
        out!(
            "watch with `wearcoef status --profile {p}`; when the arrays are done, `wearcoef run --profile {p}` exports the figures and writes the catalog (it computes nothing that the arrays stored)",
            p = record.profile
        )?;
    }
    Ok(())
}
