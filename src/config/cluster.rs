//! The `cluster:` block of pipeline.yaml: how `wearcoef submit` sizes the Slurm arrays.
//! Every field has a default; the command line overrides any of them.

use serde::{Deserialize, Serialize};

use super::error::ConfigError;

/// Settings of `wearcoef submit`.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ClusterConfig {
    /// `sbatch --partition` (none: the site's default partition).
    #[serde(default)]
    pub partition: Option<String>,
    /// `sbatch --account`.
    #[serde(default)]
    pub account: Option<String>,
    /// `sbatch --qos`.
    #[serde(default)]
    pub qos: Option<String>,
    /// CPUs of one contact sweep or surface (`--cpus-per-task`); clamped to the largest node
    /// of the partition when `sinfo` answers. Analysis instances take one CPU each.
    #[serde(default = "default_solve_cpus")]
    pub solve_cpus: u32,
    /// Small instances are packed into array tasks of about this many estimated minutes of
    /// wall time, so that thousands of tiny instances do not flood the controller; an
    /// instance longer than that gets a task of its own.
    #[serde(default = "default_task_minutes")]
    pub task_minutes: f64,
    /// `--mem` is the task's estimated peak memory times this.
    #[serde(default = "default_memory_safety")]
    pub memory_safety: f64,
    /// `--time` is the task's estimated wall time times this.
    #[serde(default = "default_time_safety")]
    pub time_safety: f64,
    /// No task asks for less than this many minutes (start-up, file system, scheduler).
    #[serde(default = "default_min_minutes")]
    pub min_minutes: f64,
    /// Largest array size when `scontrol show config` does not say (Slurm's default 1001).
    #[serde(default = "default_max_array_size")]
    pub max_array_size: u32,
    /// At most this many tasks of one array at once (`--array=…%N`); none: no limit.
    #[serde(default)]
    pub throttle: Option<u32>,
}

fn default_solve_cpus() -> u32 {
    8
}
fn default_task_minutes() -> f64 {
    20.0
}
fn default_memory_safety() -> f64 {
    1.3
}
fn default_time_safety() -> f64 {
    2.0
}
fn default_min_minutes() -> f64 {
    10.0
}
fn default_max_array_size() -> u32 {
    1001
}

impl Default for ClusterConfig {
    fn default() -> Self {
        Self {
            partition: None,
            account: None,
            qos: None,
            solve_cpus: default_solve_cpus(),
            task_minutes: default_task_minutes(),
            memory_safety: default_memory_safety(),
            time_safety: default_time_safety(),
            min_minutes: default_min_minutes(),
            max_array_size: default_max_array_size(),
            throttle: None,
        }
    }
}

/// A Slurm partition, account or QOS name: letters, digits, `_`, `-` and `.`, as Slurm
/// names them (at most 64); anything else (a quote, `$(…)`, a space) would be read by the
/// batch script's `#SBATCH` line, not passed as a name.
pub fn check_slurm_name(v: &str) -> Result<(), String> {
    let ok = !v.is_empty()
        && v.len() <= 64
        && v.chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'));
    if ok {
        Ok(())
    } else {
        Err("a Slurm name of 1 to 64 letters, digits, '_', '-' or '.' (as `sacctmgr show qos` and `sinfo` list them)".into())
    }
}

impl ClusterConfig {
    /// Check every value; `origin` names the file in messages.
    pub fn validate(&self, origin: &str) -> Result<(), ConfigError> {
        let invalid = |field: &str, value: String, allowed: &str| ConfigError::Invalid {
            path: origin.to_string(),
            field: format!("cluster.{field}"),
            value,
            allowed: allowed.to_string(),
        };
        if self.solve_cpus == 0 {
            return Err(invalid("solve_cpus", "0".into(), "must be ≥ 1"));
        }
        use crate::ranges::{MEMORY_SAFETY, MINUTES, TASK_MINUTES, TIME_SAFETY};
        for (field, v, range) in [
            ("task_minutes", self.task_minutes, TASK_MINUTES),
            ("min_minutes", self.min_minutes, MINUTES),
            ("memory_safety", self.memory_safety, MEMORY_SAFETY),
            ("time_safety", self.time_safety, TIME_SAFETY),
        ] {
            if let Err(why) = range.check(&format!("cluster.{field}"), v) {
                let allowed = why.split_once(": ").map_or(why.as_str(), |(_, w)| w);
                return Err(invalid(field, crate::ranges::show(v), allowed));
            }
        }
        // Names written into #SBATCH lines: a plain word, nothing a shell or Slurm reads.
        for (field, v) in [
            ("partition", &self.partition),
            ("account", &self.account),
            ("qos", &self.qos),
        ] {
            if let Some(v) = v {
                check_slurm_name(v).map_err(|why| invalid(field, format!("{v:?}"), &why))?;
            }
        }
        if self.max_array_size < 2 {
            return Err(invalid(
                "max_array_size",
                self.max_array_size.to_string(),
                "must be ≥ 2 (Slurm's MaxArraySize; arrays use indices 0 … MaxArraySize − 1)",
            ));
        }
        if self.throttle == Some(0) {
            return Err(invalid("throttle", "0".into(), "must be ≥ 1, or left out"));
        }
        for (field, v) in [
            ("partition", &self.partition),
            ("account", &self.account),
            ("qos", &self.qos),
        ] {
            if let Some(s) = v {
                if s.is_empty() || s.chars().any(|c| c.is_whitespace() || c == '\'') {
                    return Err(invalid(
                        field,
                        format!("{s:?}"),
                        "a Slurm name: not empty, no spaces or quotes",
                    ));
                }
            }
        }
        Ok(())
    }
}
