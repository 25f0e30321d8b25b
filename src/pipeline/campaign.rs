//! A campaign: the missing instances of a plan cut into job arrays for a batch scheduler.
//!
//! Each plan level is split into at most a few arrays: the many-threaded stages (surfaces,
//! contact sweeps) apart from the one-CPU analysis stages, and by memory class (instances
//! within a factor of two of each other's estimated peak share an array, all below 1 GiB
//! one class, so that a 256² sweep does not ask for an 8192² sweep's memory). An array's instances are written to a plan file of their own and cut
//! into contiguous tasks: small instances are packed into tasks of about
//! `cluster.task_minutes` of estimated wall time, an instance longer than that gets a task to
//! itself. Task `I` of `K` runs `wearcoef exec --plan <array plan> --slice I/K`, which is
//! scheduler-neutral; [`render_script`] wraps it in an `sbatch` script. Arrays longer than
//! the scheduler's maximum are split into chunks, each chunk one `sbatch` call.
//!
//! Resources of an array (every task asks the same):
//! - CPUs: `cluster.solve_cpus` for surfaces and contact sweeps (clamped to the largest
//!   node), one for every other stage.
//! - memory: the class's largest estimated peak (a task runs its instances one after the
//!   other, `exec --at-once 1`, each on all the task's CPUs), times `cluster.memory_safety`,
//!   plus 256 MiB for the process itself.
//! - time: the longest task's estimated core-seconds over its CPUs (the solver parallelises
//!   well), times `cluster.time_safety`, at least `cluster.min_minutes`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::Context;

use serde::{Deserialize, Serialize};

use super::plan::{Instance, Plan};
use crate::config::ClusterConfig;

/// Memory of the process besides its instances: binary, thread stacks, small inputs.
const BASE_MIB: u64 = 256;

/// The largest node a partition offers, as `sinfo` reports it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct NodeLimits {
    pub cpus: u32,
    pub memory_mib: u64,
}

/// What every task of an array asks for.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Resources {
    pub cpus: u32,
    pub memory_mib: u64,
    pub minutes: u64,
}

/// One array: instances of one level, thread use and memory class.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ArraySpec {
    /// `L<level>-<stages>-m<class>`: file names of its plan and scripts.
    pub name: String,
    pub level: usize,
    /// Its stages, joined by `+`.
    pub stage: String,
    pub instances: usize,
    /// Number of tasks `K` (`--slice I/K`).
    pub tasks: usize,
    pub instances_per_task: usize,
    pub resources: Resources,
    /// Estimated wall seconds of the longest task and peak bytes of one task (before the
    /// safety factors): what a measurement is compared with.
    pub estimated_task_seconds: f64,
    pub estimated_task_peak_bytes: u64,
    /// Estimated core-seconds of all its instances.
    pub core_seconds: f64,
}

/// An array and the instances its plan file holds.
#[derive(Debug, Clone)]
pub struct ArrayPlan {
    pub spec: ArraySpec,
    pub plan: Plan,
}

/// Stages whose instances use many threads.
fn is_parallel(stage: &str) -> bool {
    matches!(stage, "surface" | "contact")
}

/// The memory class of an estimate: ⌈log₂ bytes⌉, all below 1 GiB in one class.
fn memory_class(bytes: u64) -> u32 {
    (64 - bytes.max(1).saturating_sub(1).leading_zeros()).max(30)
}

/// Cut the instances of `plan` that are not cached into arrays. `node`, when known, clamps
/// CPUs and refuses an instance that no node can hold.
pub fn arrays(
    plan: &Plan,
    cluster: &ClusterConfig,
    node: Option<NodeLimits>,
) -> Result<Vec<ArrayPlan>, super::error::UsageError> {
    let mut groups: BTreeMap<(usize, bool, u32), Vec<Instance>> = BTreeMap::new();
    for inst in plan.instances.iter().filter(|i| !i.cached) {
        groups
            .entry((
                inst.level,
                is_parallel(&inst.stage),
                memory_class(inst.estimate.peak_bytes),
            ))
            .or_default()
            .push(inst.clone());
    }
    let mut out = Vec::new();
    for ((level, parallel, class), instances) in groups {
        let stage = super::runner::stage_list(instances.iter().map(|i| i.stage.as_str()));
        let mut cpus = if parallel { cluster.solve_cpus } else { 1 };
        if let Some(n) = node {
            cpus = cpus.min(n.cpus.max(1));
        }
        let wall = |i: &Instance| i.estimate.seconds / f64::from(cpus);
        let longest = instances.iter().map(wall).fold(0.0, f64::max);
        let per_task = if longest > 0.0 {
            ((cluster.task_minutes * 60.0 / longest).floor() as usize).clamp(1, instances.len())
        } else {
            instances.len()
        };
        let tasks = instances.len().div_ceil(per_task);
        // Slices as `wearcoef exec --slice I/K` cuts them.
        let slices: Vec<&[Instance]> = (0..tasks)
            .map(|t| &instances[super::plan::slice_range(instances.len(), t, tasks)])
            .collect();
        let per_slice = slices.iter().map(|c| c.len()).max().unwrap_or(0);
        let task_seconds = slices
            .iter()
            .map(|c| c.iter().map(|i| i.estimate.seconds).sum::<f64>() / f64::from(cpus))
            .fold(0.0, f64::max);
        // A task runs its instances one after the other, each on all its CPUs.
        let task_peak = instances
            .iter()
            .map(|i| i.estimate.peak_bytes)
            .max()
            .unwrap_or(0);
        let memory_mib = (task_peak as f64 * cluster.memory_safety / (1u64 << 20) as f64).ceil()
            as u64
            + BASE_MIB;
        let minutes = (task_seconds * cluster.time_safety / 60.0)
            .max(cluster.min_minutes)
            .ceil() as u64;
        if let Some(n) = node {
            if memory_mib > n.memory_mib {
                let big = instances
                    .iter()
                    .max_by_key(|i| i.estimate.peak_bytes)
                    .expect("a group is never empty");
                return Err(super::error::UsageError(format!(
                    "the {stage} instance {} (studies {}) needs about {memory_mib} MiB with the safety factor {}, more than the largest node's {} MiB: submit to a partition with bigger nodes (--partition), lower cluster.memory_safety, or choose smaller sizes",
                    &big.key[..12],
                    big.studies.join(", "),
                    cluster.memory_safety,
                    n.memory_mib
                )));
            }
        }
        let name = format!("L{level}-{stage}-m{class}");
        let core_seconds = instances.iter().map(|i| i.estimate.seconds).sum();
        out.push(ArrayPlan {
            spec: ArraySpec {
                name,
                level,
                stage,
                instances: instances.len(),
                tasks,
                instances_per_task: per_slice,
                resources: Resources {
                    cpus,
                    memory_mib,
                    minutes,
                },
                estimated_task_seconds: task_seconds,
                estimated_task_peak_bytes: task_peak,
                core_seconds,
            },
            plan: Plan {
                profile: plan.profile.clone(),
                instances,
            },
        });
    }
    Ok(out)
}

/// `--time` in Slurm's `D-HH:MM:SS`.
pub fn slurm_time(minutes: u64) -> String {
    let (d, rem) = (minutes / 1440, minutes % 1440);
    format!("{d}-{:02}:{:02}:00", rem / 60, rem % 60)
}

/// Everything a batch script needs besides its array.
#[derive(Debug, Clone)]
pub struct ScriptContext<'a> {
    pub profile: &'a str,
    pub binary: &'a str,
    pub data: &'a str,
    pub campaign_dir: &'a str,
    pub partition: Option<&'a str>,
    pub account: Option<&'a str>,
    pub qos: Option<&'a str>,
    pub throttle: Option<u32>,
}

/// One chunk of an array: tasks `offset .. offset + len` of its `K`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Chunk {
    pub offset: usize,
    pub len: usize,
}

/// Split `tasks` into chunks of at most `max_array_size` tasks (indices 0 … max − 1).
pub fn chunks(tasks: usize, max_array_size: u32) -> Vec<Chunk> {
    let m = max_array_size.max(1) as usize;
    (0..tasks)
        .step_by(m)
        .map(|offset| Chunk {
            offset,
            len: m.min(tasks - offset),
        })
        .collect()
}

/// Quote a string for a POSIX shell.
pub fn shell_quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

/// The `sbatch` script of one chunk of an array.
pub fn render_script(
    ctx: &ScriptContext,
    spec: &ArraySpec,
    chunk: Chunk,
    plan_file: &str,
) -> String {
    let r = spec.resources;
    let throttle = ctx.throttle.map_or(String::new(), |t| format!("%{t}"));
    let mut s = String::new();
    s.push_str("#!/bin/bash\n");
    s.push_str(&format!(
        "# wearcoef campaign, profile {}: level {}, {} {} instance(s) in {} task(s) of up to {}; this array runs tasks {}-{}.\n",
        ctx.profile,
        spec.level,
        spec.instances,
        spec.stage,
        spec.tasks,
        spec.instances_per_task,
        chunk.offset,
        chunk.offset + chunk.len - 1
    ));
    s.push_str(&format!(
        "# Estimated per task: {:.0} s of wall time on {} CPU(s), peak {:.2} GiB (before safety factors).\n",
        spec.estimated_task_seconds,
        r.cpus,
        spec.estimated_task_peak_bytes as f64 / (1u64 << 30) as f64
    ));
    let mut directive = |k: &str, v: &str| s.push_str(&format!("#SBATCH --{k}={v}\n"));
    directive("job-name", &format!("wc-{}-{}", ctx.profile, spec.name));
    directive("array", &format!("0-{}{throttle}", chunk.len - 1));
    directive("cpus-per-task", &r.cpus.to_string());
    directive("mem", &format!("{}M", r.memory_mib));
    directive("time", &slurm_time(r.minutes));
    directive("output", &format!("{}/logs/%x_%A_%a.out", ctx.campaign_dir));
    directive("kill-on-invalid-dep", "yes");
    for (k, v) in [
        ("partition", ctx.partition),
        ("account", ctx.account),
        ("qos", ctx.qos),
    ] {
        if let Some(v) = v {
            directive(k, v);
        }
    }
    s.push_str("set -euo pipefail\n");
    s.push_str(&format!(
        "task=$(( SLURM_ARRAY_TASK_ID + {} ))\n",
        chunk.offset
    ));
    s.push_str(&format!(
        "exec {} exec --plan {} --data {} --slice \"$task/{}\" --jobs \"${{SLURM_CPUS_PER_TASK:-1}}\" --at-once 1 --quiet\n",
        shell_quote(ctx.binary),
        shell_quote(plan_file),
        shell_quote(ctx.data),
        spec.tasks
    ));
    s
}

/// `YYYYMMDDTHHMMSSZ` of a Unix time (UTC), for campaign directory names.
pub fn utc_stamp(unix_seconds: u64) -> String {
    let days = (unix_seconds / 86400) as i64;
    let secs = unix_seconds % 86400;
    // Civil date from days since 1970-01-01 (H. Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}{m:02}{d:02}T{:02}{:02}{:02}Z",
        secs / 3600,
        secs / 60 % 60,
        secs % 60
    )
}

// The record of a submitted campaign (`campaign.json`), written by `wearcoef submit` and
// read by `wearcoef status`.

/// One submitted chunk of an array.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SubmittedChunk {
    pub chunk: Chunk,
    pub script: String,
    pub job_id: Option<String>,
}

/// One array of a campaign.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct CampaignArray {
    pub spec: ArraySpec,
    pub plan: String,
    pub chunks: Vec<SubmittedChunk>,
}

/// `campaign.json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Campaign {
    pub profile: String,
    pub created: String,
    pub submitted: bool,
    pub binary: String,
    pub data: String,
    pub cluster: ClusterConfig,
    pub node: Option<NodeLimits>,
    pub max_array_size: u32,
    pub instances: usize,
    pub core_hours: f64,
    pub arrays: Vec<CampaignArray>,
}

impl Campaign {
    /// Every job id, in submission order.
    pub fn job_ids(&self) -> Vec<String> {
        self.arrays
            .iter()
            .flat_map(|a| a.chunks.iter().filter_map(|c| c.job_id.clone()))
            .collect()
    }
}

/// The submitted campaigns of a profile, oldest first.
pub fn campaigns(data: &Path, profile: &str) -> anyhow::Result<Vec<(PathBuf, Campaign)>> {
    let base = data.join("campaigns").join(profile);
    let mut out = Vec::new();
    let Ok(read) = std::fs::read_dir(&base) else {
        return Ok(out);
    };
    let mut dirs: Vec<PathBuf> = read.filter_map(|e| Some(e.ok()?.path())).collect();
    dirs.sort();
    for dir in dirs {
        let path = dir.join("campaign.json");
        let Ok(text) = std::fs::read_to_string(&path) else {
            continue;
        };
        let c: Campaign = serde_json::from_str(&text)
            .with_context(|| format!("{} is not a campaign record", path.display()))?;
        if c.submitted {
            out.push((dir, c));
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::cost::Estimate;

    fn inst(level: usize, stage: &str, seconds: f64, peak: u64, key: &str) -> Instance {
        Instance {
            stage: stage.into(),
            key: key.into(),
            params: serde_json::Value::Null,
            inputs: vec![],
            level,
            studies: vec!["s".into()],
            realization: None,
            name: None,
            cached: false,
            estimate: Estimate {
                seconds,
                peak_bytes: peak,
            },
            source: None,
        }
    }

    #[test]
    fn small_instances_are_packed_and_a_long_one_runs_alone() {
        let gib = 1u64 << 30;
        let mut instances: Vec<Instance> = (0..100)
            .map(|k| inst(2, "clusters", 6.0, gib / 8, &format!("{k:064}")))
            .collect();
        // One-CPU stages of a level share an array.
        instances.push(inst(2, "statistics", 1.0, gib, &"s".repeat(64)));
        instances.push(inst(1, "contact", 8.0 * 3600.0, 4 * gib, &"c".repeat(64)));
        instances.push(inst(
            1,
            "contact",
            8.0 * 3600.0,
            4 * gib - 1,
            &"d".repeat(64),
        ));
        let mut cached = inst(1, "contact", 1.0, 1, &"e".repeat(64));
        cached.cached = true;
        instances.push(cached);
        let plan = Plan {
            profile: "p".into(),
            instances,
        };
        let cfg = ClusterConfig::default();
        let node = NodeLimits {
            cpus: 4,
            memory_mib: 64 * 1024,
        };
        let a = arrays(&plan, &cfg, Some(node)).unwrap();
        assert_eq!(a.len(), 2, "{a:?}");
        let contact = &a[0].spec;
        assert_eq!((contact.level, contact.instances, contact.tasks), (1, 2, 2));
        // Clamped to the node's 4 CPUs; 8 core-hours over 4 CPUs, twice, at least 10 min.
        assert_eq!(contact.resources.cpus, 4);
        assert_eq!(contact.resources.minutes, 8 * 60 / 4 * 2);
        // One instance per task: 4 GiB × 1.3 + 256 MiB.
        assert_eq!(
            contact.resources.memory_mib,
            (4096.0f64 * 1.3).ceil() as u64 + 256
        );
        let clusters = &a[1].spec;
        assert_eq!(clusters.stage, "clusters+statistics");
        // 101 instances of ≤ 6 s on one CPU: 200 fit in 20 min, so one task runs all.
        assert_eq!((clusters.tasks, clusters.instances_per_task), (1, 101));
        assert_eq!(clusters.resources.cpus, 1);
        // 601 s, twice, in whole minutes.
        assert_eq!(clusters.resources.minutes, 21);
        // A node too small is refused, naming the instance.
        let small = NodeLimits {
            cpus: 4,
            memory_mib: 4096,
        };
        let err = arrays(&plan, &cfg, Some(small)).unwrap_err().0;
        assert!(err.contains("contact instance cccccccccccc"), "{err}");
    }

    #[test]
    fn chunks_cover_every_task_once_within_the_array_limit() {
        for (tasks, max) in [(1, 1001), (1001, 1001), (1002, 1001), (5000, 1000), (7, 2)] {
            let c = chunks(tasks, max);
            assert!(c.iter().all(|c| c.len >= 1 && c.len <= max as usize));
            let covered: Vec<usize> = c.iter().flat_map(|c| c.offset..c.offset + c.len).collect();
            assert_eq!(covered, (0..tasks).collect::<Vec<_>>());
        }
    }

    #[test]
    fn times_and_stamps_are_formatted_as_slurm_and_iso_expect() {
        assert_eq!(slurm_time(10), "0-00:10:00");
        assert_eq!(slurm_time(1441), "1-00:01:00");
        // 2026-11-24T12:34:56Z and the leap day 2024-02-29.
        assert_eq!(utc_stamp(1_795_523_696), "20261124T123456Z");
        assert_eq!(utc_stamp(1_709_164_800), "20240229T000000Z");
        assert_eq!(shell_quote("a'b"), r"'a'\''b'");
    }
}
