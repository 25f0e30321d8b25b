//! Talking to Slurm through its commands (`sbatch`, `scancel`, `squeue`, `sacct`, `sinfo`,
//! `scontrol`), which find the cluster as they always do (`SLURM_CONF` or the site's
//! configuration). Nothing here polls: each function runs one command and returns; queries
//! give up after 10 s (an unreachable controller makes Slurm's clients retry for a minute).

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

use anyhow::Context;
use serde::Serialize;

use super::campaign::NodeLimits;

/// How long a query may take: Slurm's clients retry for about a minute when the controller
/// or the configuration cannot be reached, and a query only informs (`None` is a valid
/// answer).
const QUERY_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(10);

/// Stdout of a successful query, `None` on failure or after [`QUERY_TIMEOUT`].
fn output(cmd: &mut Command) -> Option<String> {
    use std::io::Read;
    let mut child = cmd
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::null())
        .spawn()
        .ok()?;
    let mut stdout = child.stdout.take()?;
    // Read on a thread so that a large answer cannot block the child on a full pipe.
    let reader = std::thread::spawn(move || {
        let mut text = String::new();
        stdout.read_to_string(&mut text).map(|_| text)
    });
    let deadline = std::time::Instant::now() + QUERY_TIMEOUT;
    let status = loop {
        match child.try_wait().ok()? {
            Some(status) => break status,
            None if std::time::Instant::now() >= deadline => {
                let _ = child.kill();
                let _ = child.wait();
                return None;
            }
            None => std::thread::sleep(std::time::Duration::from_millis(20)),
        }
    };
    let text = reader.join().ok()?.ok()?;
    status.success().then_some(text)
}

/// Whether `sbatch` can be run at all.
pub fn available() -> bool {
    Command::new("sbatch")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success())
}

/// The largest CPU count and memory of the nodes of `partition` (or of every partition).
pub fn node_limits(partition: Option<&str>) -> Option<NodeLimits> {
    let mut cmd = Command::new("sinfo");
    cmd.args(["-h", "-N", "-o", "%c %m"]);
    if let Some(p) = partition {
        cmd.args(["-p", p]);
    }
    let text = output(&mut cmd)?;
    let num = |s: &str| s.trim_end_matches('+').parse::<u64>().ok();
    let mut best: Option<NodeLimits> = None;
    for line in text.lines() {
        let mut f = line.split_whitespace();
        let (Some(c), Some(m)) = (f.next().and_then(num), f.next().and_then(num)) else {
            continue;
        };
        let b = best.get_or_insert(NodeLimits {
            cpus: 0,
            memory_mib: 0,
        });
        b.cpus = b.cpus.max(c as u32);
        b.memory_mib = b.memory_mib.max(m);
    }
    best
}

/// A value of `scontrol show config` (`Name = value`).
pub fn config_value(name: &str) -> Option<String> {
    let text = output(Command::new("scontrol").args(["show", "config"]))?;
    text.lines().find_map(|l| {
        let (k, v) = l.split_once('=')?;
        (k.trim() == name).then(|| v.trim().to_string())
    })
}

/// Submit a script; `after` are job ids it waits for (`afterok`). Returns the job id.
pub fn sbatch(script: &Path, after: &[String]) -> anyhow::Result<String> {
    let mut cmd = Command::new("sbatch");
    cmd.arg("--parsable");
    if !after.is_empty() {
        cmd.arg(format!("--dependency=afterok:{}", after.join(":")));
    }
    cmd.arg(script);
    let out = cmd
        .output()
        .context("cannot run sbatch: is Slurm's client installed and on PATH?")?;
    if !out.status.success() {
        anyhow::bail!(
            "sbatch {} failed: {}",
            script.display(),
            String::from_utf8_lossy(&out.stderr).trim()
        );
    }
    let text = String::from_utf8_lossy(&out.stdout);
    let id = text
        .trim()
        .split(';')
        .next()
        .unwrap_or_default()
        .to_string();
    anyhow::ensure!(
        !id.is_empty() && id.chars().all(|c| c.is_ascii_digit()),
        "sbatch printed '{}', not a job id",
        text.trim()
    );
    Ok(id)
}

/// Cancel jobs (whole arrays); errors are ignored (a job may have ended).
pub fn scancel(ids: &[String]) {
    if !ids.is_empty() {
        let _ = Command::new("scancel").args(ids).output();
    }
}

/// State of the tasks of one array job: task id (or a range while pending) → state.
#[derive(Debug, Clone, Default, Serialize)]
pub struct JobStates {
    /// `PENDING`, `RUNNING`, `COMPLETED`, `FAILED`, `CANCELLED`, … per task.
    pub tasks: BTreeMap<String, String>,
    /// Where finished states came from: `sacct`, `jobcomp` (the job completion file) or
    /// none (the tasks have left the queue and the cluster keeps no record).
    pub finished_from: Option<String>,
}

impl JobStates {
    /// Count of tasks per state.
    pub fn counts(&self) -> BTreeMap<String, usize> {
        let mut c = BTreeMap::new();
        for s in self.tasks.values() {
            *c.entry(s.clone()).or_insert(0) += 1;
        }
        c
    }
}

/// States of the tasks of the given array jobs: queued and running ones from `squeue`,
/// finished ones from `sacct` when accounting is on, else from the job completion file
/// (`JobCompType=jobcomp/filetxt`), else unknown.
pub fn states(ids: &[String]) -> BTreeMap<String, JobStates> {
    let mut out: BTreeMap<String, JobStates> = ids
        .iter()
        .map(|i| (i.clone(), JobStates::default()))
        .collect();
    // Finished first, so that the queue's view wins for anything still in it.
    let finished = sacct(ids)
        .map(|s| ("sacct", s))
        .or_else(|| jobcomp(ids).map(|s| ("jobcomp", s)));
    if let Some((source, records)) = finished {
        for (job, task, state) in records {
            if let Some(j) = out.get_mut(&job) {
                j.tasks.insert(task, state);
                j.finished_from = Some(source.to_string());
            }
        }
    }
    if let Some(text) = output(Command::new("squeue").args(["-h", "-r", "-o", "%F|%K|%T"])) {
        for line in text.lines() {
            let f: Vec<&str> = line.split('|').collect();
            if let [job, task, state] = f[..] {
                if let Some(j) = out.get_mut(job) {
                    j.tasks.insert(task.to_string(), state.to_string());
                }
            }
        }
    }
    out
}

/// `(array job, task, state)` from `sacct`, or `None` when accounting is off.
fn sacct(ids: &[String]) -> Option<Vec<(String, String, String)>> {
    let text = output(Command::new("sacct").args([
        "-n",
        "-P",
        "-X",
        "-o",
        "JobID,State",
        "-j",
        &ids.join(","),
    ]))?;
    Some(
        text.lines()
            .filter_map(|l| {
                let (id, state) = l.split_once('|')?;
                let (job, task) = id.split_once('_')?;
                // "CANCELLED by 0" → "CANCELLED".
                let state = state.split_whitespace().next()?.to_string();
                Some((job.to_string(), task.to_string(), state))
            })
            .collect(),
    )
}

/// `(array job, task, state)` from the job completion file, when the cluster writes one.
fn jobcomp(ids: &[String]) -> Option<Vec<(String, String, String)>> {
    if config_value("JobCompType")? != "jobcomp/filetxt" {
        return None;
    }
    let text = std::fs::read_to_string(config_value("JobCompLoc")?).ok()?;
    Some(
        text.lines()
            .filter_map(|l| {
                let field = |k: &str| {
                    l.split_whitespace()
                        .find_map(|f| f.strip_prefix(k)?.strip_prefix('='))
                };
                let job = field("ArrayJobId")?;
                ids.iter().any(|i| i == job).then(|| {
                    Some((
                        job.to_string(),
                        field("ArrayTaskId")?.to_string(),
                        field("JobState")?.to_string(),
                    ))
                })?
            })
            .collect(),
    )
}
