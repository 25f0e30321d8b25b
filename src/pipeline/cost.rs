//! Cost estimates of plan instances: CPU seconds (core-seconds) and peak memory, from a model
//! per stage whose coefficients are fitted to the CPU times that the store's manifests record
//! (their wall times for entries of builds that did not record CPU time; coefficients
//! measured on the 2-core development machine when the store holds no instance of a stage).
//!
//! The model (n: grid side, L: loads of a sweep):
//! - surface: `c · n² log₂ n` seconds; `4 n²` doubles of memory (heights and the complex
//!   spectrum) and the process's own [`PROCESS_BYTES`] (measured 4.01 n² doubles at 16384²).
//! - contact: `c · I · n² log₂ n` seconds, with `I` the iterations of the sweep; `7.5 n²`
//!   doubles of memory (the solver measures at most 7.1 n² doubles in `make bench-peers`,
//!   plus the heights read from file). The iterations depend on the spectrum and on the loads
//!   (how far each load is from the one before), so they are predicted from the stored sweeps
//!   of the same *family* when there are any: the same spectrum in grid spacings (H, λ_l, λ_s,
//!   generator, roll-off), loads and tolerance, on any box size and seed. Within a family,
//!   `ln I = ln A + b ln n` is fitted to the sweeps of its two largest grid sizes (the
//!   iterations grow faster with n on bigger grids; b is the global one when the family has
//!   one size). Without it, a *scaled family* (the spectrum widened with n: the same λ_s,
//!   L/λ_l, loads and tolerance) of two sizes or more extrapolates its two largest. Else:
//!   `L · a · (n/1024)^b` iterations
//!   (`a`, `b` fitted in log-log to all stored sweeps' iterations per load). To calibrate a
//!   big campaign, run its studies first at small box sizes (profile `paper_size_calibration`
//!   does this for `paper_size`; docs/CLUSTER.md).
//! - a measured map of `rows × cols`: its surface as `n² = rows·cols`; its sweep on the
//!   zero-padded square, `n = 2·max(rows, cols)` (the cost BENCHMARKS measures for it); its
//!   clusters as `n² = rows·cols`.
//! - clusters: `c · L · n²` seconds; one u32 label per node and the packed map (4.125 n²
//!   bytes) and the stage's own [`CLUSTERS_BASE_BYTES`] (measured 1.04–1.11 GiB at 16384²,
//!   0.46 at 8192², 0.21 from 128² to 2048²).
//! - statistics, analytic, audits, figures: the mean seconds of the stored instances of the
//!   stage; memory bounded by 1 GiB (the whole default run peaks below that).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::store::Store;

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
    /// Per sweep family: the fit `I = A · n^b` of its stored sweeps' iterations.
    pub families: BTreeMap<String, FamilyFit>,
    /// Seconds per load per n² of a clusters instance.
    pub clusters_per_load_n2: f64,
    /// Mean seconds of the other stages' instances.
    pub per_instance: BTreeMap<String, f64>,
    /// Stored instances the fit used, per stage.
    pub samples: BTreeMap<String, usize>,
}

/// The iterations of the stored sweeps of one family against their grid side (the sweeps of
/// its two largest sides).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct FamilyFit {
    /// `ln A` and `b` of `I = A · n^b`.
    pub ln_a: f64,
    pub exponent: f64,
    /// Whether `b` was fitted to this family (two or more grid sizes) or is the global one.
    pub own_exponent: bool,
    /// Stored sweeps and their grid sides.
    pub sweeps: usize,
    pub sides: Vec<f64>,
}

/// The family of a sweep: its surface's spectrum in grid spacings, generator and roll-off,
/// and its loads and tolerance; everything that sets the iterations but the box size (n) and
/// the seed. `None` when the surface's parameters are unknown.
pub fn sweep_family(contact: &Value, surface: Option<&Value>) -> Option<String> {
    let s = surface?;
    let pick = |v: &Value, keys: &[&str]| -> Vec<Value> {
        keys.iter()
            .map(|k| v.get(*k).cloned().unwrap_or(Value::Null))
            .collect()
    };
    let family = serde_json::json!([
        pick(
            s,
            &[
                "hurst",
                "lambda_l_px",
                "lambda_s_px",
                "method",
                "rolloff_lambda_px"
            ]
        ),
        pick(contact, &["loads_w_over_w0", "tolerance"]),
    ]);
    Some(family.to_string())
}

/// The scaled family of a sweep: its surface's shape relative to the grid (H, λ_s in grid
/// spacings, L/λ_l, generator, roll-off relative to λ_l) and its loads and tolerance, the
/// spectrum's width λ_l/λ_s growing with n: a series like profile `spectrum`, whose narrower
/// members calibrate the wider one (prefixed `scaled:` among the families). `None` when the
/// surface's parameters are unknown.
pub fn scaled_family(contact: &Value, surface: Option<&Value>) -> Option<String> {
    let s = surface?;
    let (n, lambda_l) = (num(s, "n")?, num(s, "lambda_l_px")?);
    let rolloff = num(s, "rolloff_lambda_px").map(|r| r / lambda_l);
    let family = serde_json::json!([
        s.get("hurst"),
        s.get("lambda_s_px"),
        s.get("method"),
        n / lambda_l,
        rolloff,
        contact.get("loads_w_over_w0"),
        contact.get("tolerance"),
    ]);
    Some(format!("scaled:{family}"))
}

/// Least-squares line through `(x, y)`: `(intercept, slope)`, slope `None` when the x do not
/// spread.
fn line(points: &[(f64, f64)]) -> (f64, Option<f64>) {
    let k = points.len() as f64;
    let mx = points.iter().map(|p| p.0).sum::<f64>() / k;
    let my = points.iter().map(|p| p.1).sum::<f64>() / k;
    let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    if sxx > 1e-6 {
        let b = sxy / sxx;
        (my - b * mx, Some(b))
    } else {
        (my, None)
    }
}

/// Bytes of analysis stages (statistics, analytic, audits, figures).
const ANALYSIS_BYTES: u64 = 1 << 30;
/// Resident bytes of the process before any array (binary, libraries, thread pools): 24 MiB
/// measured for a 128² surface.
pub const PROCESS_BYTES: u64 = 24 << 20;
/// Resident bytes of a clusters instance before its maps (Parquet writer, thread pools): 215
/// MiB measured from 128² to 2048².
pub const CLUSTERS_BASE_BYTES: u64 = 215 << 20;

impl Default for CostModel {
    /// Coefficients measured on the development machine (2 cores, AVX2) on 2026-11-25: the
    /// seconds per unit of work from a default-profile store (instances two at a time on the
    /// 2 cores, so wall time is about one core's CPU time; the contact stage's then scaled by
    /// 3.64/3.67, the iteration's cost in FFT pairs of the solver of 2026-11-26 04:58 against
    /// the one measured in that store, `make bench-iteration` at 1024², 1 thread, and by 0.92,
    /// contact stage version 9's iteration time against that solver's, interleaved `wearcoef
    /// solve` of the paper spectrum's 1024² sweep on 1 thread, 0.91–0.95 over three rounds;
    /// version 10's iteration takes the same time, 0.99–1.03 of version 9's at 1024² and
    /// 2048² on 1 thread, and version 11's the same convolutions per iteration, 2.57 against
    /// 2.56 at 1024², and the far term of versions 12 and 13 adds no convolution; then by
    /// 1.054, version 14's time per iteration against version 13's on four loads at 4096² with
    /// the deflation in every settled phase, 1 thread, interleaved, two rounds: an upper bound
    /// for a sweep, where only the settled phases of its denser loads are deflated); the
    /// iterations per load and their growth with n from the paper's own spectrum
    /// (`SEEDS="3128 1 2 3 4 5 6 7 8" REALIZATIONS="9 4 2 2" make bench-iteration-growth
    /// BOXES="1 2 4 8"`, 2026-11-26/27, contact stage version 15: means of 15.1, 17.3, 17.4
    /// and 19.5 iterations per load at 1024², 2048², 4096² and 8192² over 9, 4, 2 and 2
    /// realizations, fitted as 15.4 (n/1024)^0.112), which dominates the paper campaign.
    /// Version 15's entry margin adds no pass to an iteration.
    fn default() -> Self {
        Self {
            surface_per_n2logn: 5.8e-9,
            contact_per_iteration_n2logn: 2.74e-9,
            iterations_per_load_1024: 15.4,
            iterations_exponent: 0.112,
            clusters_per_load_n2: 3.8e-9,
            families: BTreeMap::new(),
            per_instance: [
                ("statistics", 0.39),
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
        let mut by_family: BTreeMap<String, Vec<(f64, f64)>> = BTreeMap::new();
        // Manifests only: timings are read, no output is (so nothing is hashed here).
        for (stage, key, _) in store.entries()? {
            let Some(m) = store.manifest(&stage, &key) else {
                continue;
            };
            let work = match stage.as_str() {
                "surface" => num(&m.params, "n").map(n2logn),
                "contact" => match (num(&m.results, "n"), num(&m.results, "total_iterations")) {
                    (Some(n), Some(it)) if it > 0.0 => {
                        iterations.push((n, it / loads_of(&m.params)));
                        let surface = m.inputs.first().and_then(|k| store.manifest("surface", k));
                        let surface = surface.as_ref().map(|s| &s.params);
                        for f in [
                            sweep_family(&m.params, surface),
                            scaled_family(&m.params, surface),
                        ]
                        .into_iter()
                        .flatten()
                        {
                            by_family.entry(f).or_default().push((n.ln(), it.ln()));
                        }
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
            if let (_, Some(b)) = line(&pts) {
                model.iterations_exponent = b.clamp(0.0, 1.0);
            }
            model.iterations_per_load_1024 = (my - model.iterations_exponent * mx).exp();
        }
        for (family, all) in by_family {
            // The two largest grid sizes only: the iterations grow faster with n on bigger
            // grids (λ_l/λ_s = 128, three loads: n^0.43 from 1024 to 2048, n^0.63 to 4096,
            // n^0.80 to 8192), and the fit serves to extrapolate upwards.
            let mut sizes: Vec<f64> = all.iter().map(|p| p.0).collect();
            sizes.sort_by(|a, b| b.total_cmp(a));
            sizes.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
            let keep = &sizes[..sizes.len().min(2)];
            let pts: Vec<(f64, f64)> = all
                .iter()
                .copied()
                .filter(|p| keep.iter().any(|k| (p.0 - k).abs() < 1e-9))
                .collect();
            let (_, own) = line(&pts);
            // A family's own slope, within what CG on this operator can do (iterations grow
            // with n, at most linearly); else the global one through the family's mean.
            let exponent = own.map_or(model.iterations_exponent, |b| b.clamp(0.0, 1.5));
            let k = pts.len() as f64;
            let (mx, my) = (
                pts.iter().map(|p| p.0).sum::<f64>() / k,
                pts.iter().map(|p| p.1).sum::<f64>() / k,
            );
            let mut sides: Vec<f64> = pts.iter().map(|p| p.0.exp().round()).collect();
            sides.sort_by(f64::total_cmp);
            sides.dedup();
            model.families.insert(
                family,
                FamilyFit {
                    ln_a: my - exponent * mx,
                    exponent,
                    own_exponent: own.is_some(),
                    sweeps: pts.len(),
                    sides,
                },
            );
        }
        Ok(model)
    }

    /// Iterations of a sweep of `n × n` whose job is `params` on a surface with parameters
    /// `surface`: from its family's fit when the store holds that family, else from the
    /// global iterations per load. Without its own family, a scaled family of two sizes or
    /// more extrapolates its two largest (iterations grow faster with λ_l/λ_s than with n
    /// alone: 13.3, 14.8, 20.8, 31.7 per load at λ_l/λ_s = 128 … 1024, profile `spectrum`).
    pub fn sweep_iterations(&self, params: &Value, surface: Option<&Value>, n: f64) -> f64 {
        let own = sweep_family(params, surface).and_then(|f| self.families.get(&f));
        let scaled = || {
            scaled_family(params, surface)
                .and_then(|f| self.families.get(&f))
                .filter(|fit| fit.own_exponent)
        };
        own.or_else(scaled).map_or_else(
            || loads_of(params) * self.iterations_per_load(n),
            |fit| (fit.ln_a + fit.exponent * n.ln()).exp(),
        )
    }

    /// Iterations per load of a sweep on an `n × n` grid.
    pub fn iterations_per_load(&self, n: f64) -> f64 {
        self.iterations_per_load_1024 * (n / 1024.0).powf(self.iterations_exponent)
    }

    /// The estimate of an instance of `stage` with job `params`; `surface` holds the
    /// parameters of its first input when that is a surface (for a contact sweep).
    pub fn estimate(&self, stage: &str, params: &Value, surface: Option<&Value>) -> Estimate {
        let doubles = |k: f64, n: f64| (k * n * n * 8.0) as u64;
        let p = params;
        match stage {
            "surface" => {
                let n = num(p, "n").unwrap_or_else(|| measured_side(p).sqrt());
                Estimate {
                    seconds: self.surface_per_n2logn * n2logn(n),
                    peak_bytes: doubles(4.0, n) + PROCESS_BYTES,
                }
            }
            "contact" => {
                // A measured map is solved on the zero-padded square of twice its longer
                // side (contact::window).
                let n = surface.map_or(0.0, |s| num(s, "n").unwrap_or_else(|| padded_side(s)));
                let iterations = self.sweep_iterations(p, surface, n);
                Estimate {
                    seconds: self.contact_per_iteration_n2logn * iterations * n2logn(n),
                    peak_bytes: doubles(7.5, n),
                }
            }
            "clusters" => {
                let n = match p.get("window").and_then(|w| w.as_array()) {
                    Some(w) => w.iter().filter_map(Value::as_f64).product::<f64>().sqrt(),
                    None => num(p, "n").unwrap_or(0.0),
                };
                Estimate {
                    seconds: self.clusters_per_load_n2 * loads_of(p) * n * n,
                    peak_bytes: (4.125 * n * n) as u64 + CLUSTERS_BASE_BYTES,
                }
            }
            other => Estimate {
                seconds: self.per_instance.get(other).copied().unwrap_or(1.0),
                peak_bytes: ANALYSIS_BYTES,
            },
        }
    }
}

/// `rows·cols` of a measured surface job (0 for any other).
fn measured_side(p: &Value) -> f64 {
    num(p, "rows").unwrap_or(0.0) * num(p, "cols").unwrap_or(0.0)
}

/// The FFT side of a measured surface's padded solve: twice its longer side, made even.
fn padded_side(p: &Value) -> f64 {
    let longer = num(p, "rows")
        .unwrap_or(0.0)
        .max(num(p, "cols").unwrap_or(0.0));
    2.0 * (longer / 2.0).ceil() * 2.0
}

pub use crate::machine::memory_bytes as machine_memory_bytes;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::store::{Manifest, Program};
    use serde_json::json;

    fn put(store: &Store, stage: &str, key: &str, params: Value, inputs: &[&str], results: Value) {
        let entry = store.begin(stage, key).unwrap();
        entry
            .commit(Manifest {
                stage: stage.into(),
                version: 1,
                key: key.into(),
                params,
                inputs: inputs.iter().map(|s| s.to_string()).collect(),
                input_digests: Default::default(),
                outputs: Default::default(),
                program: Program::current(),
                wall_seconds: 1.0,
                cpu_seconds: Some(1.0),
                peak_rss_bytes: None,
                results,
                results_sha256: None,
            })
            .unwrap();
    }

    fn surface(n: u32, lambda_s_px: f64) -> Value {
        json!({"hurst": 0.8, "lambda_l_px": 1024.0, "lambda_s_px": lambda_s_px,
               "method": "filter", "n": n, "rolloff_lambda_px": null, "seed": n})
    }

    fn sweep(loads: &[f64]) -> Value {
        json!({"e_star": 1.0, "keep_pressure": [], "loads_w_over_w0": loads,
               "max_iterations": 5000, "tolerance": 1e-10})
    }

    /// Sweeps of one family at two sizes give that family's own power law in n; a sweep of
    /// a family the store lacks falls back to the global iterations per load.
    #[test]
    fn iterations_follow_the_sweeps_own_family() {
        let dir = tempfile::tempdir().unwrap();
        let store = Store::new(dir.path());
        let three = [0.005, 0.02, 0.06];
        // 512 is not among the two largest sizes: left out of the fit.
        let sizes = [(512u32, 40.0), (1024, 185.0), (2048, 275.0)];
        for (k, (n, it)) in sizes.into_iter().enumerate() {
            let s = format!("s{k}");
            put(&store, "surface", &s, surface(n, 8.0), &[], json!({}));
            put(
                &store,
                "contact",
                &format!("c{k}"),
                sweep(&three),
                &[&s],
                json!({"n": n, "total_iterations": it}),
            );
        }
        // Another family (λ_s = 16 px): one size, 16 loads.
        put(&store, "surface", "s9", surface(512, 16.0), &[], json!({}));
        put(
            &store,
            "contact",
            "c9",
            sweep(&[0.01; 16]),
            &["s9"],
            json!({"n": 512, "total_iterations": 640.0}),
        );
        let model = CostModel::fit(&store).unwrap();
        let b = (275.0f64 / 185.0).ln() / 2f64.ln();
        let predicted = model.sweep_iterations(&sweep(&three), Some(&surface(8192, 8.0)), 8192.0);
        let expected = 275.0 * 4f64.powf(b);
        assert!(
            (predicted - expected).abs() < 1e-6 * expected,
            "{predicted} vs {expected}"
        );
        // The same loads on another spectrum: no family, the global law.
        let other = model.sweep_iterations(&sweep(&three), Some(&surface(8192, 4.0)), 8192.0);
        let global = 3.0 * model.iterations_per_load(8192.0);
        assert_eq!(other, global);
        assert!(other != predicted);
        // The one-size family uses the global exponent through its own point.
        let fit = model
            .families
            .values()
            .find(|f| f.sides == [512.0])
            .unwrap();
        assert!(!fit.own_exponent);
        assert_eq!(fit.exponent, model.iterations_exponent);
        let at_512 = (fit.ln_a + fit.exponent * 512f64.ln()).exp();
        assert!((at_512 - 640.0).abs() < 1e-9 * 640.0);
    }

    /// A spectrum widened with the grid (λ_l ∝ n, the same λ_s, L/λ_l, loads, tolerance) is
    /// predicted from its narrower members' two largest sizes when the store lacks its own
    /// family; its own family, once stored, takes over.
    #[test]
    fn a_widening_spectrum_follows_its_scaled_family() {
        let dir = tempfile::tempdir().unwrap();
        let store = Store::new(dir.path());
        let three = [0.005, 0.02, 0.06];
        let widened = |n: u32| {
            let mut s = surface(n, 8.0);
            s["lambda_l_px"] = json!(f64::from(n) / 2.0);
            s
        };
        for (k, (n, it)) in [(512u32, 30.0), (1024, 40.0), (2048, 56.0)]
            .into_iter()
            .enumerate()
        {
            put(
                &store,
                "surface",
                &format!("s{k}"),
                widened(n),
                &[],
                json!({}),
            );
            put(
                &store,
                "contact",
                &format!("c{k}"),
                sweep(&three),
                &[&format!("s{k}")],
                json!({"n": n, "total_iterations": it}),
            );
        }
        let model = CostModel::fit(&store).unwrap();
        let predicted = model.sweep_iterations(&sweep(&three), Some(&widened(4096)), 4096.0);
        let expected = 56.0 * 56.0 / 40.0;
        assert!(
            (predicted - expected).abs() < 1e-6 * expected,
            "{predicted}"
        );
        // Another box (L/λ_l ≈ 5.9) is another scaled family: the global law.
        let mut boxed = widened(4096);
        boxed["lambda_l_px"] = json!(700.0);
        let global = 3.0 * model.iterations_per_load(4096.0);
        assert_eq!(
            model.sweep_iterations(&sweep(&three), Some(&boxed), 4096.0),
            global
        );
        // Its own family stored at one size: that sweep's iterations, not the extrapolation.
        put(&store, "surface", "s9", widened(4096), &[], json!({}));
        put(
            &store,
            "contact",
            "c9",
            sweep(&three),
            &["s9"],
            json!({"n": 4096, "total_iterations": 100.0}),
        );
        let model = CostModel::fit(&store).unwrap();
        let own = model.sweep_iterations(&sweep(&three), Some(&widened(4096)), 4096.0);
        assert!((own - 100.0).abs() < 1e-9 * 100.0, "{own}");
    }
}
