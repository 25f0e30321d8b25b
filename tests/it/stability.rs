//! Stability where methods fail: each case asserts the behaviour that
//! docs/CONVENTIONS.md ("Stability where methods fail") states for it.

use std::path::Path;

use polars::prelude::*;

use crate::{run_in, stdout_json, workdir};

fn read(path: &Path) -> DataFrame {
    ParquetReader::new(std::fs::File::open(path).unwrap())
        .finish()
        .unwrap()
}

fn entry(dir: &Path, stage: &str) -> std::path::PathBuf {
    let mut v: Vec<_> = std::fs::read_dir(dir.join("data/cache").join(stage))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    v.sort();
    assert_eq!(v.len(), 1, "one {stage} entry expected");
    v.pop().unwrap()
}

fn u64_col(df: &DataFrame, name: &str) -> Vec<Option<u64>> {
    let c = df.column(name).unwrap().cast(&DataType::UInt64).unwrap();
    c.u64().unwrap().iter().collect()
}

fn f64_col(df: &DataFrame, name: &str) -> Vec<Option<f64>> {
    df.column(name).unwrap().f64().unwrap().iter().collect()
}

/// One study on a 64² grid loaded from a few clusters to beyond percolation.
const HIGH_LOAD: &str = r#"schema_version: 1
material: {e_star: 1.0}
solver: {tolerance: 1.0e-10, max_iterations: 2000}
profiles: {t: "test"}
studies:
  s:
    hurst: 0.8
    lambda_l_over_lambda_s: 4
    seed: 11
    loads: {values: [0.002, 0.6, 1.5]}
    profiles:
      t: {l_over_lambda_l: 2, lambda_s_over_dl: 8, realizations: 1}
"#;

#[test]
fn percolation_at_high_load_is_flagged_excluded_from_the_distribution_and_counted_in_the_area() {
    let (_t, dir) = workdir(HIGH_LOAD);
    let out = run_in(&dir, &["run", "--profile", "t", "--quiet"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let clusters = read(&entry(&dir, "clusters").join("clusters.parquet"));
    let loads = read(&entry(&dir, "clusters").join("loads.parquet"));
    let n_perc = u64_col(&loads, "n_percolating");
    assert_eq!(
        n_perc[0],
        Some(0),
        "a few isolated clusters at W/W0 = 0.002"
    );
    assert!(
        n_perc[2].unwrap() >= 1,
        "W/W0 = 1.5 must percolate: {n_perc:?}"
    );
    // The percolating cluster is in the table, flagged, and its area is in A_c.
    let idx = u64_col(&clusters, "load_index");
    let area = u64_col(&clusters, "area_px");
    let perc: Vec<bool> = clusters
        .column("percolating")
        .unwrap()
        .bool()
        .unwrap()
        .iter()
        .map(|v| v.unwrap())
        .collect();
    let fraction = f64_col(&loads, "area_fraction");
    let idx = &idx;
    let at = |l: u64| (0..idx.len()).filter(move |&i| idx[i] == Some(l));
    let total: u64 = at(2).map(|i| area[i].unwrap()).sum();
    assert!(((total as f64 / 4096.0) - fraction[2].unwrap()).abs() < 1e-15);
    let flagged = at(2).filter(|&i| perc[i]).count() as u64;
    assert_eq!(Some(flagged), n_perc[2]);
    // The statistics stage leaves it out of the area distribution: the PDF counts only the
    // non-percolating clusters, and reports the realization as percolating.
    let stats = entry(&dir, "statistics");
    let pdf = read(&stats.join("pdf.parquet"));
    let pidx = u64_col(&pdf, "load_index");
    let count = u64_col(&pdf, "count_pooled");
    let pooled: u64 = (0..pidx.len())
        .filter(|&i| pidx[i] == Some(2))
        .map(|i| count[i].unwrap())
        .sum();
    assert_eq!(pooled, at(2).count() as u64 - flagged);
    let sl = read(&stats.join("loads.parquet"));
    assert_eq!(u64_col(&sl, "realizations_percolating")[2], Some(1));
    // Too few clusters for a tail fit at the smallest load: no exponent, and a note why.
    let alpha = read(&stats.join("alpha.parquet"));
    let a = f64_col(&alpha, "alpha");
    let aidx = u64_col(&alpha, "load_index");
    let note: Vec<Option<String>> = alpha
        .column("note")
        .unwrap()
        .str()
        .unwrap()
        .iter()
        .map(|v| v.map(str::to_string))
        .collect();
    for i in (0..a.len()).filter(|&i| aidx[i] == Some(0)) {
        assert!(a[i].is_none(), "no exponent from a handful of clusters");
        assert!(
            note[i].as_deref().is_some_and(|n| !n.is_empty()),
            "{note:?}"
        );
    }
}

#[test]
fn extreme_hurst_exponents_give_valid_surfaces_and_converged_contact() {
    let t = tempfile::tempdir().unwrap();
    for hurst in ["0.05", "0.95"] {
        let out = run_in(
            t.path(),
            &[
                "surface",
                "--n",
                "128",
                "--lambda-l-px",
                "32",
                "--lambda-s-px",
                "2",
                "--hurst",
                hurst,
                "--seed",
                "5",
                "-o",
                "h.npy",
                "--json",
            ],
        );
        assert!(out.status.success(), "H = {hurst}");
        let s = stdout_json(&out);
        assert!((s["rms_slope"].as_f64().unwrap() - 1.0).abs() < 1e-12);
        assert!(s["mean_height"].as_f64().unwrap().abs() < 1e-12);
        let fit = s["hurst_fit"].as_f64().unwrap();
        let h: f64 = hurst.parse().unwrap();
        // 32/2 = 16 wavelengths: 1.2 decades of shells; the filter's random amplitudes
        // scatter the fit by a few hundredths (surface::filtered_surface_recovers_…).
        assert!((fit - h).abs() < 0.1, "H = {hurst}: fitted {fit}");
        let out = run_in(
            t.path(),
            &[
                "solve",
                "--surface",
                "h.npy",
                "--loads",
                "0.0001,0.01,0.2,2",
                "--json",
            ],
        );
        assert!(
            out.status.success(),
            "H = {hurst}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v = stdout_json(&out);
        for load in v.as_array().unwrap() {
            assert_eq!(load["converged"], true, "H = {hurst}: {load}");
            let w = load["w_over_w0"].as_f64().unwrap();
            let p = load["mean_pressure"].as_f64().unwrap();
            assert!((p - w).abs() <= 1e-12 * w, "load balance: {p} vs {w}");
            let a = load["area_fraction"].as_f64().unwrap();
            assert!(a > 0.0 && a <= 1.0);
        }
    }
}

#[test]
fn loads_outside_a_study_range_are_errors_naming_the_field() {
    // A figure drawing a map at a load the study's sweep does not reach.
    let text = HIGH_LOAD.replace(
        "    loads: {values: [0.002, 0.6, 1.5]}",
        "    loads: {min: 0.002, max: 1.5, count: 3}",
    ) + "figures:\n  maps: {kind: fig2, study: s, loads: [3.0], profiles: [t]}\n";
    let (_t, dir) = workdir(&text);
    let out = run_in(&dir, &["run", "--profile", "t", "--quiet"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("figures.maps.loads"), "{err}");
    assert!(err.contains("[0.002, 1.5]"), "{err}");
    assert!(!dir.join("data/cache").exists(), "nothing stored");
    // Negative and non-finite loads on the command line.
    for loads in ["-0.01", "nan", "0.01,inf"] {
        let out = run_in(
            &dir,
            &[
                "solve",
                "--json",
                "--surface",
                "missing.npy",
                "--loads",
                loads,
            ],
        );
        assert!(!out.status.success(), "{loads}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("--loads"), "{loads}: {err}");
    }
}

/// Units do not change the answer: the default and the plain solver agree, and converge,
/// at loads down to W/W0 = 1e-300, moduli of 1e±40 and heights scaled by 1e±40 (every value
/// the CLI accepts); the contact set is that of the unit problem and the mean pressure is
/// the imposed one.
#[test]
fn the_answer_does_not_depend_on_units_or_on_the_solver() {
    use wearcoef::contact::solver::SolverConfig;
    use wearcoef::contact::sweep::sweep_heights;
    use wearcoef::spectral::Fft2;
    use wearcoef::surface::{self, Method, SurfaceParams};
    let n = 64;
    let params = SurfaceParams {
        n,
        hurst: 0.8,
        lambda_l_px: 32.0,
        lambda_s_px: 4.0,
        rolloff_lambda_px: None,
        method: Method::Filter,
        seed: 5,
    };
    let fft = Fft2::new(n);
    let heights = surface::generate(&params, &fft, &mut fft.make_scratch())
        .unwrap()
        .heights;
    let solve = |scale: f64, e_star: f64, w: f64, preconditioned: bool| {
        let h: Vec<f64> = heights.iter().map(|v| v * scale).collect();
        let cfg = SolverConfig {
            tolerance: 1e-9,
            preconditioned,
            ..SolverConfig::default()
        };
        let mut map = Vec::new();
        let mut total = 0.0;
        let (slope, results) = sweep_heights(&h, n, e_star, &[w], &cfg, |_, p, _| {
            map = p.iter().map(|&v| v > 0.0).collect::<Vec<bool>>();
            total = p.iter().sum::<f64>();
            Ok(())
        })
        .unwrap_or_else(|e| {
            panic!(
                "scale {scale:e}, E* {e_star:e}, W/W0 {w:e}, preconditioned {preconditioned}: {e}"
            )
        });
        let imposed = w * (e_star * slope);
        let mean = total / (n * n) as f64;
        assert!(
            (mean / imposed - 1.0).abs() < 1e-12,
            "scale {scale:e}, E* {e_star:e}, W/W0 {w:e}: mean pressure {mean:e} against {imposed:e}"
        );
        assert!(results[0].report.converged());
        map
    };
    for w in [1e-300, 1e-25, 1e-3, 0.05] {
        let unit = solve(1.0, 1.0, w, true);
        for (scale, e_star) in [
            (1.0, 1.0),
            (1e40, 1.0),
            (1e-40, 1.0),
            (1.0, 1e40),
            (1.0, 1e-40),
            (1e40, 1e-40),
        ] {
            if w * (scale * e_star) < f64::MIN_POSITIVE * 1024.0 {
                // Pressures below the doubles' full precision: refused, naming the fix.
                let h: Vec<f64> = heights.iter().map(|v| v * scale).collect();
                let cfg = SolverConfig::default();
                let e = sweep_heights(&h, n, e_star, &[w], &cfg, |_, _, _| Ok(())).unwrap_err();
                assert!(e.to_string().contains("nearer 1"), "{e}");
                continue;
            }
            for preconditioned in [true, false] {
                let map = solve(scale, e_star, w, preconditioned);
                let differ = map.iter().zip(&unit).filter(|(a, b)| a != b).count();
                assert!(
                    differ <= 1,
                    "scale {scale:e}, E* {e_star:e}, W/W0 {w:e}, preconditioned {preconditioned}: {differ} nodes differ from the unit problem's contact set"
                );
            }
        }
    }
}
