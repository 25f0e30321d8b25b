//! Measured costs against a plan's estimates: for the instances of a saved plan (`wearcoef
//! plan --out`, made before a campaign) that the store now holds, the CPU time and peak
//! memory their manifests record beside what the plan estimated, per stage.

use std::collections::BTreeMap;

use serde::Serialize;

use super::plan::Instance;
use crate::store::Store;

/// One stage's estimate and measurement, over the instances measured.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct StageCosts {
    pub stage: String,
    /// Instances of the stage in the plan.
    pub planned: usize,
    /// Of those, the stored ones whose manifest records CPU time.
    pub measured: usize,
    /// The plan's estimate and the manifests' record of CPU seconds, over `measured`.
    pub estimated_cpu_seconds: f64,
    pub measured_cpu_seconds: f64,
    /// Stored instances whose manifest records a peak memory (computed one at a time).
    pub peak_measured: usize,
    /// The largest estimate and the largest record of peak memory, over `peak_measured`.
    pub estimated_peak_bytes: u64,
    pub measured_peak_bytes: u64,
}

impl StageCosts {
    /// Measured over estimated CPU time (None before anything is measured).
    pub fn cpu_ratio(&self) -> Option<f64> {
        (self.estimated_cpu_seconds > 0.0 && self.measured > 0)
            .then(|| self.measured_cpu_seconds / self.estimated_cpu_seconds)
    }

    /// Measured over estimated peak memory (None before any peak is measured).
    pub fn peak_ratio(&self) -> Option<f64> {
        (self.estimated_peak_bytes > 0 && self.peak_measured > 0)
            .then(|| self.measured_peak_bytes as f64 / self.estimated_peak_bytes as f64)
    }
}

/// Per stage (in name order), the estimates of `instances` against the store's records.
pub fn compare(instances: &[Instance], store: &Store) -> Vec<StageCosts> {
    let mut by_stage: BTreeMap<&str, StageCosts> = BTreeMap::new();
    for inst in instances {
        let c = by_stage
            .entry(inst.stage.as_str())
            .or_insert_with(|| StageCosts {
                stage: inst.stage.clone(),
                ..Default::default()
            });
        c.planned += 1;
        let Some(m) = store.manifest(&inst.stage, &inst.key) else {
            continue;
        };
        if let Some(cpu) = m.cpu_seconds {
            c.measured += 1;
            c.estimated_cpu_seconds += inst.estimate.seconds;
            c.measured_cpu_seconds += cpu;
        }
        if let Some(peak) = m.peak_rss_bytes {
            c.peak_measured += 1;
            c.estimated_peak_bytes = c.estimated_peak_bytes.max(inst.estimate.peak_bytes);
            c.measured_peak_bytes = c.measured_peak_bytes.max(peak);
        }
    }
    by_stage.into_values().collect()
}
