//! Speed–accuracy chart: `make speed-accuracy` writes
//! `figures/speed_accuracy.{png,svg,csv}`.
//!
//! (a) Solver tolerance 1e-4 … 1e-12 on one 512² surface (H = 0.8, λ_l/λ_s = 16,
//!     λ_s/Δl = 8), the 30-load sweep of the paper (W/W0 log-spaced in [0.001, 0.06]):
//!     largest relative L2 error over loads of the pressure field, largest relative error of
//!     the contact area and of the cluster count, and the
//!     error of the exponent (plateau + power-law MLE at the largest load), against a 1e-13
//!     reference.
//! (b) Discretisation λ_s/Δl = 2, 4, 8, 16 (λ_l/λ_s = 8, L/λ_l = 4, n = 64 … 512, four
//!     realizations each, tolerance 1e-10): KS distance between the cluster areas (A/λ_s²)
//!     pooled over realizations and loads and those of the finest grid, and the exponent
//!     difference (plateau + power-law MLE at the largest load).
//!
//! Cost is the wall time of the sweep with cluster labelling, divided by the reference's
//! (measured in the same run), so the chart does not depend on the machine's speed; the CSV
//! also has the seconds. Points with an error of exactly 0 cannot be drawn on logarithmic
//! axes; they are in the CSV. The pipeline's defaults (tolerance 1e-10, λ_s/Δl = 8) are marked.

use std::path::PathBuf;
use std::time::Instant;

use wearcoef::clusters::{label, Connectivity};
use wearcoef::contact::elastic::ElasticOperator;
use wearcoef::contact::solver::SolverConfig;
use wearcoef::contact::sweep::sweep;
use wearcoef::figures::plot::{Layout, LinePlot, Marker, Panels, Series, YAxis};
use wearcoef::grid::Grid;
use wearcoef::powerlaw::fit_plateau_power_law;
use wearcoef::spectral::Fft2;
use wearcoef::statistics::{ks_critical_95, ks_two_sample, log_edges};
use wearcoef::surface::{self, Method, SurfaceParams};

const LOADS: usize = 30;
const DEFAULT_TOLERANCE: f64 = 1e-10;
const DEFAULT_LAMBDA_S_OVER_DL: f64 = 8.0;

/// The paper's sweep: W/W0 log-spaced in [0.001, 0.06].
fn loads() -> Vec<f64> {
    log_edges(0.001, 0.06, LOADS - 1)
}

fn heights(n: usize, lambda_l_px: f64, lambda_s_px: f64, seed: u64) -> Vec<f64> {
    let fft = Fft2::new(n);
    let mut scratch = fft.make_scratch();
    let p = SurfaceParams {
        n,
        hurst: 0.8,
        lambda_l_px,
        lambda_s_px,
        rolloff_lambda_px: None,
        method: Method::Filter,
        seed,
    };
    surface::generate(&p, &fft, &mut scratch).unwrap().heights
}

/// One sweep: seconds (solves and labelling) and, per load, the contact fraction and the
/// non-percolating cluster areas in pixels.
struct Sweep {
    seconds: f64,
    area: Vec<f64>,
    clusters: Vec<Vec<u64>>,
    /// Pressure fields per load (kept only when asked).
    pressures: Vec<Vec<f64>>,
}

fn run(h: &[f64], n: usize, tolerance: f64, keep: bool) -> Result<Sweep, String> {
    let grid = Grid::unit(n).unwrap();
    let slope = surface::rms_slope(&grid, h);
    let op = ElasticOperator::new(grid, 1.0);
    let cfg = SolverConfig {
        tolerance,
        max_iterations: 20000,
        ..SolverConfig::default()
    };
    let mut clusters = Vec::new();
    let mut pressures = Vec::new();
    let start = Instant::now();
    let results = sweep(&op, h, slope, &loads(), &cfg, |_, solver, _| {
        if keep {
            pressures.push(solver.pressure().to_vec());
        }
        let map: Vec<bool> = solver.pressure().iter().map(|&p| p > 0.0).collect();
        let l = label(&map, n, n, Connectivity::Eight).map_err(|e| e.to_string())?;
        clusters.push(
            l.clusters
                .iter()
                .filter(|c| !c.percolating())
                .map(|c| c.area_px)
                .collect(),
        );
        Ok(())
    })
    .map_err(|e| e.to_string())?;
    Ok(Sweep {
        seconds: start.elapsed().as_secs_f64(),
        area: results.iter().map(|r| r.area_fraction).collect(),
        clusters,
        pressures,
    })
}

fn alpha(areas: &[u64]) -> f64 {
    fit_plateau_power_law(areas).map_or(f64::NAN, |f| f.alpha)
}

fn max_rel(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| {
            if *y == 0.0 {
                x.abs()
            } else {
                (x - y).abs() / y.abs()
            }
        })
        .fold(0.0, f64::max)
}

struct Row {
    part: &'static str,
    setting: f64,
    seconds: f64,
    relative_cost: f64,
    errors: Vec<(&'static str, f64)>,
}

fn main() {
    // `cargo bench` passes `--bench`; nothing else is read.
    let out_dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("figures");
    std::fs::create_dir_all(&out_dir).unwrap();
    let mut rows: Vec<Row> = Vec::new();

    // (a) Tolerance.
    let n = 512;
    let h = heights(n, 128.0, 8.0, 1);
    let (ref_tol, reference) = match run(&h, n, 1e-13, true) {
        Ok(s) => (1e-13, s),
        Err(e) => {
            eprintln!("reference at 1e-13 failed ({e}); using 1e-12");
            (1e-12, run(&h, n, 1e-12, true).expect("reference sweep"))
        }
    };
    let last = LOADS - 1;
    let ref_alpha = alpha(&reference.clusters[last]);
    let ref_counts: Vec<f64> = reference.clusters.iter().map(|c| c.len() as f64).collect();
    eprintln!("(a) reference tol {ref_tol:e}: {:.2} s", reference.seconds);
    for k in 4..=12 {
        let tol = 10f64.powi(-k);
        if tol <= ref_tol {
            continue;
        }
        let s = run(&h, n, tol, true).expect("sweep");
        let pressure = s
            .pressures
            .iter()
            .zip(&reference.pressures)
            .map(|(p, q)| {
                let num: f64 = p.iter().zip(q).map(|(a, b)| (a - b) * (a - b)).sum();
                let den: f64 = q.iter().map(|b| b * b).sum();
                (num / den).sqrt()
            })
            .fold(0.0, f64::max);
        let counts: Vec<f64> = s.clusters.iter().map(|c| c.len() as f64).collect();
        let row = Row {
            part: "tolerance",
            setting: tol,
            seconds: s.seconds,
            relative_cost: s.seconds / reference.seconds,
            errors: vec![
                ("pressure (relative L2)", pressure),
                ("contact area", max_rel(&s.area, &reference.area)),
                ("cluster count", max_rel(&counts, &ref_counts)),
                ("exponent α", (alpha(&s.clusters[last]) - ref_alpha).abs()),
            ],
        };
        eprintln!(
            "(a) tol {tol:e}: {:.2} s, errors {:?}",
            s.seconds, row.errors
        );
        rows.push(row);
    }

    // (b) Discretisation.
    let realizations = 4u64;
    let settings = [2.0f64, 4.0, 8.0, 16.0];
    let mut runs = Vec::new();
    for &r in &settings {
        let n = (4.0 * 8.0 * r) as usize;
        let ls2 = r * r;
        let mut seconds = 0.0;
        let mut pooled_px: Vec<Vec<u64>> = vec![Vec::new(); LOADS];
        for seed in 1..=realizations {
            let h = heights(n, 8.0 * r, r, seed);
            let s = run(&h, n, DEFAULT_TOLERANCE, false).expect("sweep");
            seconds += s.seconds;
            for (l, c) in s.clusters.into_iter().enumerate() {
                pooled_px[l].extend(c);
            }
        }
        let pooled: Vec<Vec<f64>> = pooled_px
            .iter()
            .map(|c| c.iter().map(|&a| a as f64 / ls2).collect())
            .collect();
        eprintln!("(b) λ_s/Δl = {r}: n = {n}, {seconds:.2} s");
        runs.push((r, seconds, pooled, alpha(&pooled_px[last])));
    }
    let (_, finest_seconds, finest, finest_alpha) = runs.last().cloned().unwrap();
    // Areas pooled over all loads and realizations: per-load samples of a few hundred
    // clusters at the smallest loads would make a maximum over loads mostly sampling noise.
    let all = |p: &[Vec<f64>]| p.iter().flatten().copied().collect::<Vec<f64>>();
    let finest_all = all(&finest);
    for (r, seconds, pooled, a) in &runs[..runs.len() - 1] {
        let sample = all(pooled);
        let ks = ks_two_sample(&sample, &finest_all);
        eprintln!(
            "(b) λ_s/Δl = {r}: KS {ks:.3} (95 % critical {:.3}), |Δα| {:.3}",
            ks_critical_95(sample.len(), finest_all.len()),
            (a - finest_alpha).abs()
        );
        rows.push(Row {
            part: "discretisation",
            setting: *r,
            seconds: *seconds,
            relative_cost: seconds / finest_seconds,
            errors: vec![
                ("CCDF (KS distance)", ks),
                ("exponent α", (a - finest_alpha).abs()),
            ],
        });
    }

    // Data.
    let mut w = csv::Writer::from_path(out_dir.join("speed_accuracy.csv")).unwrap();
    w.write_record([
        "part",
        "setting",
        "metric",
        "error",
        "seconds",
        "cost_relative_to_reference",
    ])
    .unwrap();
    for r in &rows {
        for (m, e) in &r.errors {
            w.write_record([
                r.part.to_string(),
                r.setting.to_string(),
                m.to_string(),
                e.to_string(),
                r.seconds.to_string(),
                r.relative_cost.to_string(),
            ])
            .unwrap();
        }
    }
    w.flush().unwrap();

    // Chart.
    let panel = |part: &str, title: &str, default: f64| {
        let mut p = LinePlot::new(
            title,
            "error against the reference",
            "cost / cost of the reference",
            true,
            YAxis::Log,
        );
        let part_rows: Vec<&Row> = rows.iter().filter(|r| r.part == part).collect();
        let metrics: Vec<&str> = part_rows
            .first()
            .map(|r| r.errors.iter().map(|e| e.0).collect())
            .unwrap_or_default();
        for (c, m) in metrics.iter().enumerate() {
            let pts: Vec<(f64, f64)> = part_rows
                .iter()
                .filter_map(|r| {
                    let e = r.errors.iter().find(|e| e.0 == *m)?.1;
                    (e > 0.0).then_some((e, r.relative_cost))
                })
                .collect();
            p.series.push(Series {
                marker: Some(Marker::ALL[c % Marker::ALL.len()]),
                ..Series::line(m.to_string(), pts, c)
            });
        }
        let marked: Vec<(f64, f64)> = part_rows
            .iter()
            .filter(|r| r.setting == default)
            .flat_map(|r| {
                r.errors
                    .iter()
                    .filter(|e| e.1 > 0.0)
                    .map(|e| (e.1, r.relative_cost))
            })
            .collect();
        p.series.push(Series {
            marker: Some(Marker::Circle),
            width: 0,
            rgb: Some((0, 0, 0)),
            ..Series::line("default setting", marked, 0)
        });
        p
    };
    let a = panel(
        "tolerance",
        "(a) solver tolerance 1e-4 … 1e-12 (default 1e-10)",
        DEFAULT_TOLERANCE,
    );
    let b = panel(
        "discretisation",
        "(b) λ_s/Δl = 2, 4, 8 vs 16 (default 8)",
        DEFAULT_LAMBDA_S_OVER_DL,
    );
    Panels {
        plots: vec![a, b],
        layout: Layout::Grid { columns: 2 },
    }
    .write(&out_dir, "speed_accuracy")
    .unwrap();
    eprintln!("wrote {}", out_dir.join("speed_accuracy.png").display());
}
