//! Cost estimates of plan instances: CPU seconds (core-seconds) and peak memory, from a model
//! per stage whose coefficients are fitted to the CPU times that the store's manifests record
//! (their wall times for entries of builds that did not record CPU time; coefficients
//! measured on the 2-core development machine when the store holds no instance of a stage).
//!
//! The model (n: grid side, L: loads of a sweep):
//! - surface: `c · n² log₂ n` seconds; `6 n²` doubles of memory (heights, spectrum, FFT rows).
//! - contact: `c · I · n² log₂ n` seconds, with `I` the iterations of the sweep, predicted as
//!   `L · a · (n/1024)^b` iterations per load (`a`, `b` fitted in log-log to the stored
//!   sweeps); `7.5 n²` doubles of memory (the solver measures at most 7.1 n² doubles in
//!   `make bench-peers`, plus the heights read from file).
//! - clusters: `c · L · n²` seconds; `4 n²` u32 words per map being labelled and the map.
//! - statistics, analytic, audits, figures: the mean seconds of the stored instances of the
//!   stage; memory bounded by 1 GiB (the whole default run peaks below that).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::store::Store;

/// What one instance is expected to cost.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Estimate {
    /// CPU seconds over all threads (core-seconds; on c cores, about seconds/c of wall time
    /// for an instance that parallelises well, as the solver does).
    pub seconds: f64,
    /// Peak resident bytes of the process while it runs this instance alone.
    pub peak_bytes: u64,
}

/// Fitted coefficients.
#[derive(Debug, Clone, Serialize)]
pub struct CostModel {
    /// Seconds per `n² log₂ n` of a surface.
    pub surface_per_n2logn: f64,
    /// Seconds per iteration per `n² log₂ n` of a contact sweep.
    pub contact_per_iteration_n2logn: f64,
    /// Iterations per load at n = 1024, and the exponent of their growth with n.
    pub iterations_per_load_1024: f64,
    pub iterations_exponent: f64,
    /// Seconds per load per n² of a clusters instance.
    pub clusters_per_load_n2: f64,
    /// Mean seconds of the other stages' instances.
    pub per_instance: BTreeMap<String, f64>,
    /// Stored instances the fit used, per stage.
    pub samples: BTreeMap<String, usize>,
}

/// Bytes of analysis stages (statistics, analytic, audits, figures).
const ANALYSIS_BYTES: u64 = 1 << 30;

impl Default for CostModel {
    /// Coefficients measured on the development machine (2 cores, AVX2) from a default-profile
    /// store of 2026-11-24, whose instances ran two at a time on the 2 cores, so their wall
    /// time is about one core's CPU time.
    fn default() -> Self {
        Self {
            surface_per_n2logn: 9.0e-9,
            contact_per_iteration_n2logn: 6.7e-9,
            iterations_per_load_1024: 54.0,
            iterations_exponent: 0.43,
            clusters_per_load_n2: 1.8e-8,
            per_instance: [
                ("statistics", 1.1),
                ("analytic", 0.005),
                ("audits", 0.1),
                ("figures", 0.1),
            ]
            .into_iter()
            .map(|(k, v)| (k.to_string(), v))
            .collect(),
            samples: BTreeMap::new(),
        }
    }
}

fn n2logn(n: f64) -> f64 {
    n * n * n.log2().max(1.0)
}

fn num(v: &Value, key: &str) -> Option<f64> {
    v.get(key).and_then(Value::as_f64)
}

fn loads_of(params: &Value) -> f64 {
    params
        .get("loads_w_over_w0")
        .and_then(Value::as_array)
        .map_or(1.0, |a| a.len() as f64)
}

impl CostModel {
    /// Fit the model to every manifest in the store (defaults where a stage has none).
    pub fn fit(store: &Store) -> anyhow::Result<Self> {
        let mut model = Self::default();
        let mut sums: BTreeMap<String, (f64, f64, usize)> = BTreeMap::new();
        let mut iterations: Vec<(f64, f64)> = Vec::new();
        for (stage, key, _) in store.entries()? {
            let Ok(Some(m)) = store.lookup(&stage, &key) else {
                continue;
            };
            let work = match stage.as_str() {
                "surface" => num(&m.params, "n").map(n2logn),
                "contact" => match (num(&m.results, "n"), num(&m.results, "total_iterations")) {
                    (Some(n), Some(it)) if it > 0.0 => {
                        iterations.push((n, it / loads_of(&m.params)));
                        Some(it * n2logn(n))
                    }
                    _ => None,
                },
                "clusters" => num(&m.params, "n").map(|n| loads_of(&m.params) * n * n),
                _ => Some(1.0),
            };
            if let Some(w) = work.filter(|w| *w > 0.0) {
                let e = sums.entry(stage).or_insert((0.0, 0.0, 0));
                e.0 += m.cpu_seconds.unwrap_or(m.wall_seconds);
                e.1 += w;
                e.2 += 1;
            }
        }
        for (stage, (seconds, work, count)) in sums {
            let c = seconds / work;
            match stage.as_str() {
                "surface" => model.surface_per_n2logn = c,
                "contact" => model.contact_per_iteration_n2logn = c,
                "clusters" => model.clusters_per_load_n2 = c,
                _ => {
                    model.per_instance.insert(stage.clone(), c);
                }
            }
            model.samples.insert(stage, count);
        }
        // ln(iterations per load) = ln a + b ln(n/1024), least squares, when the stored
        // sweeps span more than one grid size.
        let pts: Vec<(f64, f64)> = iterations
            .iter()
            .map(|&(n, it)| ((n / 1024.0).ln(), it.ln()))
            .collect();
        if !pts.is_empty() {
            let k = pts.len() as f64;
            let (mx, my) = (
                pts.iter().map(|p| p.0).sum::<f64>() / k,
                pts.iter().map(|p| p.1).sum::<f64>() / k,
            );
            let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
            let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
            if sxx > 1e-6 {
                model.iterations_exponent = (sxy / sxx).clamp(0.0, 1.0);
            }
            model.iterations_per_load_1024 = (my - model.iterations_exponent * mx).exp();
        }
        Ok(model)
    }

    /// Iterations per load of a sweep on an `n × n` grid.
    pub fn iterations_per_load(&self, n: f64) -> f64 {
        self.iterations_per_load_1024 * (n / 1024.0).powf(self.iterations_exponent)
    }

    /// The estimate of an instance of `stage` with job `params`; `input_n` is the grid side
    /// of its first input's surface (for a contact sweep).
    pub fn estimate(&self, stage: &str, params: &Value, input_n: Option<f64>) -> Estimate {
        let doubles = |k: f64, n: f64| (k * n * n * 8.0) as u64;
        let p = params;
        match stage {
            "surface" => {
                let n = num(p, "n").unwrap_or(0.0);
                Estimate {
                    seconds: self.surface_per_n2logn * n2logn(n),
                    peak_bytes: doubles(6.0, n),
                }
            }
            "contact" => {
                let n = input_n.unwrap_or(0.0);
                let iterations = loads_of(p) * self.iterations_per_load(n);
                Estimate {
                    seconds: self.contact_per_iteration_n2logn * iterations * n2logn(n),
                    peak_bytes: doubles(7.5, n),
                }
            }
            "clusters" => {
                let n = num(p, "n").unwrap_or(0.0);
                Estimate {
                    seconds: self.clusters_per_load_n2 * loads_of(p) * n * n,
                    peak_bytes: (17.0 * n * n) as u64,
                }
            }
            other => Estimate {
                seconds: self.per_instance.get(other).copied().unwrap_or(1.0),
                peak_bytes: ANALYSIS_BYTES,
            },
        }
    }
}

/// Total memory of this machine (`MemTotal` of /proc/meminfo), if known.
pub fn machine_memory_bytes() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}
