//! Sweeps and the quantities the figures show, with their errors in units of the scatter
//! between realizations.

use std::path::Path;
use std::process::Command;
use std::time::Instant;

use wearcoef::clusters::{label, Connectivity};
use wearcoef::contact::elastic::ElasticOperator;
use wearcoef::contact::solver::{NonNegative, SolverConfig};
use wearcoef::contact::sweep::sweep;
use wearcoef::grid::Grid;
use wearcoef::powerlaw::fit_plateau_power_law;
use wearcoef::spectral::Fft2;
use wearcoef::statistics::{ks_two_sample, nearest_in_log, wear_at};
use wearcoef::surface::{self, Method, SurfaceParams};

/// Thresholds A*/λₛ² of Figs. 4b and 5.
pub const A_STAR_OVER_LS2: [f64; 5] = [2.0, 8.0, 32.0, 128.0, 512.0];

/// A surface spectrum and box: λ_l/λ_s, L/λ_l, λ_s/Δl.
#[derive(Clone, Copy, Debug)]
pub struct Setup {
    pub hurst: f64,
    pub lambda_l_over_lambda_s: f64,
    pub l_over_lambda_l: f64,
    pub lambda_s_over_dl: f64,
}

impl Setup {
    pub fn n(&self) -> usize {
        (self.l_over_lambda_l * self.lambda_l_over_lambda_s * self.lambda_s_over_dl).round()
            as usize
    }

    pub fn heights(&self, seed: u64) -> Vec<f64> {
        let n = self.n();
        let fft = Fft2::new(n);
        let mut scratch = fft.make_scratch();
        let lambda_s_px = self.lambda_s_over_dl;
        let p = SurfaceParams {
            n,
            hurst: self.hurst,
            lambda_l_px: lambda_s_px * self.lambda_l_over_lambda_s,
            lambda_s_px,
            rolloff_lambda_px: None,
            method: Method::Filter,
            seed,
        };
        surface::generate(&p, &fft, &mut scratch).unwrap().heights
    }
}

/// One sweep's contact maps reduced to what the figures use.
#[derive(Clone)]
pub struct Sweep {
    /// Seconds of the solves and the labelling.
    pub seconds: f64,
    /// Applications of the elastic operator (FFT pairs) over the sweep: the solver's work,
    /// counted exactly (None for a peer, which does not report it).
    pub convolutions: Option<usize>,
    /// Contact fraction A_c/A per load.
    pub area: Vec<f64>,
    /// Areas (pixels) of the clusters that do not wrap around the box, per load.
    pub clusters: Vec<Vec<u64>>,
}

fn clusters_of(map: &[bool], n: usize) -> Vec<u64> {
    let l = label(map, n, n, Connectivity::Eight).expect("labelling");
    l.clusters
        .iter()
        .filter(|c| !c.percolating())
        .map(|c| c.area_px)
        .collect()
}

/// Our warm-started sweep over `loads` at `tolerance`.
pub fn ours(h: &[f64], n: usize, loads: &[f64], tolerance: f64) -> Sweep {
    let grid = Grid::unit(n).unwrap();
    let slope = surface::rms_slope(&grid, h);
    let op = ElasticOperator::new(grid, 1.0);
    let cfg = SolverConfig {
        tolerance,
        max_iterations: 20000,
        ..SolverConfig::default()
    };
    let mut clusters = Vec::new();
    let start = Instant::now();
    let results = sweep(&op, h, slope, loads, &cfg, NonNegative, |_, solver, _| {
        let map: Vec<bool> = solver.pressure().iter().map(|&p| p > 0.0).collect();
        clusters.push(clusters_of(&map, n));
        Ok(())
    })
    .unwrap_or_else(|e| panic!("sweep at tolerance {tolerance:e} failed: {e}"));
    Sweep {
        seconds: start.elapsed().as_secs_f64(),
        convolutions: Some(results.iter().map(|r| r.report.convolutions).sum()),
        area: results.iter().map(|r| r.area_fraction).collect(),
        clusters,
    }
}

/// Tamaas's sweep on the same surface (benches/peers/contact_peers.py --tamaas-maps), in the
/// Python environment `python`; its seconds are the solves' alone, as Tamaas reports them
/// (our labelling of its maps is not counted).
pub fn tamaas(
    python: &Path,
    work: &Path,
    h: &[f64],
    n: usize,
    loads: &[f64],
    tolerance: f64,
) -> Result<Sweep, String> {
    let surface = work.join(format!("surface_{n}.npy"));
    wearcoef::io::write_heights(&surface, n, h.to_vec()).map_err(|e| e.to_string())?;
    let maps = work.join(format!("maps_{n}.u8"));
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/peers/contact_peers.py");
    let list: Vec<String> = loads.iter().map(|w| format!("{w:?}")).collect();
    let out = Command::new(python)
        .arg(&script)
        .arg("--tamaas-maps")
        .arg(&surface)
        .arg(format!("{tolerance:e}"))
        .arg(list.join(","))
        .arg(&maps)
        .output()
        .map_err(|e| format!("{}: {e}", python.display()))?;
    if !out.status.success() {
        return Err(String::from_utf8_lossy(&out.stderr).into_owned());
    }
    let report: serde_json::Value =
        serde_json::from_slice(&out.stdout).map_err(|e| e.to_string())?;
    let seconds = report["seconds"].as_f64().ok_or("no seconds")?;
    let bytes = std::fs::read(&maps).map_err(|e| e.to_string())?;
    if bytes.len() != loads.len() * n * n {
        return Err(format!("{} has {} bytes", maps.display(), bytes.len()));
    }
    let mut area = Vec::new();
    let mut clusters = Vec::new();
    for chunk in bytes.chunks(n * n) {
        let map: Vec<bool> = chunk.iter().map(|&b| b != 0).collect();
        area.push(map.iter().filter(|&&c| c).count() as f64 / (n * n) as f64);
        clusters.push(clusters_of(&map, n));
    }
    Ok(Sweep {
        seconds,
        convolutions: None,
        area,
        clusters,
    })
}

/// A quantity a figure shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Quantity {
    /// Exponent α̂ of the area distribution (plateau + power-law MLE), Figs. 3 and 4a.
    Alpha,
    /// K(A*) (eq. 5), Figs. 4b and 5.
    KArchard,
    /// 𝒦(A*) (eq. 7), Figs. 4b and 5.
    KUpscaled,
    /// KS distance of the area distribution (CCDF, Fig. 4a; Appendix B).
    Ks,
    /// Contact fraction A_c/A (Fig. 2e).
    Area,
    /// Cluster count per λ_l² (Fig. 2f).
    Count,
}

impl Quantity {
    pub const ALL: [Quantity; 6] = [
        Quantity::Alpha,
        Quantity::KArchard,
        Quantity::KUpscaled,
        Quantity::Ks,
        Quantity::Area,
        Quantity::Count,
    ];

    /// Legend label (markup).
    pub fn label(self) -> &'static str {
        match self {
            Quantity::Alpha => "exponent α̂",
            Quantity::KArchard => "K, worst A*",
            Quantity::KUpscaled => "𝒦, worst A*",
            Quantity::Ks => "area distribution (KS)",
            Quantity::Area => "contact area A_c/A",
            Quantity::Count => "cluster count N",
        }
    }

    /// Short symbol (markup) for notes.
    pub fn symbol(self) -> &'static str {
        match self {
            Quantity::Alpha => "α̂",
            Quantity::KArchard => "K",
            Quantity::KUpscaled => "𝒦",
            Quantity::Ks => "KS",
            Quantity::Area => "A_c",
            Quantity::Count => "N",
        }
    }
}

/// Values of one quantity at its points (loads, thresholds), with the points' names.
pub type Values = Vec<(String, f64)>;

/// A sample of the figures' quantities: one realization, or several pooled.
pub struct Sample {
    /// Number of realizations pooled.
    pub realizations: usize,
    /// Box area in λ_l².
    pub box_area: f64,
    /// λ_s² in pixels.
    pub ls2_px: f64,
    pub loads: Vec<f64>,
    pub area: Vec<f64>,
    /// Cluster areas per load in units of λ_s².
    pub clusters: Vec<Vec<f64>>,
    /// The same in pixels (for the discrete MLE).
    pub clusters_px: Vec<Vec<u64>>,
}

impl Sample {
    pub fn pooled(setup: &Setup, loads: &[f64], sweeps: &[&Sweep]) -> Sample {
        let ls2_px = setup.lambda_s_over_dl * setup.lambda_s_over_dl;
        let r = sweeps.len() as f64;
        let area = (0..loads.len())
            .map(|l| sweeps.iter().map(|s| s.area[l]).sum::<f64>() / r)
            .collect();
        let clusters_px: Vec<Vec<u64>> = (0..loads.len())
            .map(|l| sweeps.iter().flat_map(|s| s.clusters[l].clone()).collect())
            .collect();
        Sample {
            realizations: sweeps.len(),
            box_area: setup.l_over_lambda_l * setup.l_over_lambda_l,
            ls2_px,
            loads: loads.to_vec(),
            area,
            clusters: clusters_px
                .iter()
                .map(|c| c.iter().map(|&a| a as f64 / ls2_px).collect())
                .collect(),
            clusters_px,
        }
    }

    /// The values of `q` (not KS) at its points; α̂ at `alpha_loads` (nearest loads).
    pub fn values(&self, q: Quantity, alpha_loads: &[f64]) -> Values {
        let name = |l: usize| format!("W/W0={:.4}", self.loads[l]);
        let loads = 0..self.loads.len();
        match q {
            Quantity::Area => loads.map(|l| (name(l), self.area[l])).collect(),
            Quantity::Count => loads
                .map(|l| {
                    let per_box = self.clusters[l].len() as f64 / self.realizations as f64;
                    (name(l), per_box / self.box_area)
                })
                .collect(),
            Quantity::Alpha => alpha_loads
                .iter()
                .map(|&w| {
                    let l = nearest_in_log(&self.loads, w).unwrap();
                    let a =
                        fit_plateau_power_law(&self.clusters_px[l]).map_or(f64::NAN, |f| f.alpha);
                    (name(l), a)
                })
                .collect(),
            Quantity::KArchard | Quantity::KUpscaled => loads
                .flat_map(|l| {
                    A_STAR_OVER_LS2.iter().map(move |&t| {
                        let w = wear_at(&self.clusters_px[l], t * self.ls2_px);
                        let v = if q == Quantity::KArchard {
                            w.k_archard
                        } else {
                            w.k_upscaled
                        };
                        (format!("{}, A*={t}λs²", name(l)), v)
                    })
                })
                .collect(),
            Quantity::Ks => Vec::new(),
        }
    }

    /// KS distance to `other` at each load (0 where either has no cluster).
    pub fn ks(&self, other: &Sample) -> Values {
        (0..self.loads.len())
            .map(|l| {
                let d = if self.clusters[l].is_empty() || other.clusters[l].is_empty() {
                    0.0
                } else {
                    ks_two_sample(&self.clusters[l], &other.clusters[l])
                };
                (format!("W/W0={:.4}", self.loads[l]), d)
            })
            .collect()
    }
}

/// Standard deviation between per-realization values, at each point.
/// NaN where fewer than two realizations have a finite value.
pub fn scatter(per_realization: &[Values]) -> Vec<f64> {
    (0..per_realization[0].len())
        .map(|p| {
            let vals: Vec<f64> = per_realization
                .iter()
                .map(|v| v[p].1)
                .filter(|v| v.is_finite())
                .collect();
            let m = vals.iter().sum::<f64>() / vals.len() as f64;
            if vals.len() < 2 {
                return f64::NAN;
            }
            let var =
                vals.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / (vals.len() as f64 - 1.0);
            var.sqrt()
        })
        .collect()
}

/// Largest |a − b| over points, and the largest |a − b| / scale. A point whose scale is 0
/// counts as `f64::INFINITY` when a and b differ (a change where nothing scatters). NaN for
/// both (undefined) when a value exists on one side only (a fit lost, or gained) or at no
/// point on either side.
pub fn worst(a: &Values, b: &Values, scale: &[f64]) -> (f64, f64) {
    let mut raw = 0.0f64;
    let mut scaled = 0.0f64;
    let mut compared = 0;
    for ((pa, pb), s) in a.iter().zip(b).zip(scale) {
        if pa.1.is_nan() != pb.1.is_nan() {
            return (f64::NAN, f64::NAN);
        }
        let d = (pa.1 - pb.1).abs();
        if !d.is_finite() {
            continue;
        }
        compared += 1;
        raw = raw.max(d);
        scaled = scaled.max(if d == 0.0 {
            0.0
        } else if *s > 0.0 {
            d / s
        } else {
            f64::INFINITY
        });
    }
    if compared == 0 {
        return (f64::NAN, f64::NAN);
    }
    (raw, scaled)
}

/// KS sampling noise √((n+m)/(nm)) of two samples of n and m clusters, at each load.
pub fn ks_noise(n: &[usize], m: &[usize]) -> Vec<f64> {
    n.iter()
        .zip(m)
        .map(|(&a, &b)| {
            if a == 0 || b == 0 {
                0.0
            } else {
                ((a + b) as f64 / (a * b) as f64).sqrt()
            }
        })
        .collect()
}
