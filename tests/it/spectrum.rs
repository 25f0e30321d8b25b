//! The spectrum family (λ_l/λ_s varies): its K panels read the studies' own cluster tables,
//! which the test counts again from the clusters instances; its sign changes of dN/dA_c lie
//! where the statistics' dN/dA_c changes sign; and a λ_l/λ_s = 2048 study at the spectrum
//! profile's sizes (n = 32768) is planned with its memory and refused on this machine's
//! memory before any work.

use std::collections::BTreeMap;
use std::path::Path;

use polars::prelude::*;

use super::{f64s, run_in, stdout_json, table, workdir};

/// λ_l/λ_s of the three studies, at L/λ_l = 2 and λ_s = 4 px (n = 32, 64, 128).
const RATIOS: [u32; 3] = [4, 8, 16];
const LAMBDA_S_PX: f64 = 4.0;

fn pipeline() -> String {
    let mut text = String::from(
        "schema_version: 1\nmaterial: {e_star: 1.0}\nsolver: {tolerance: 1.0e-10, \
         max_iterations: 5000}\nprofiles: {t: \"test\"}\nstudies:\n",
    );
    for r in RATIOS {
        text += &format!(
            "  s{r}:\n    hurst: 0.8\n    lambda_l_over_lambda_s: {r}\n    seed: {r}\n    \
             loads: {{values: [0.005, 0.01, 0.02, 0.04, 0.06, 0.1, 0.2, 0.3]}}\n    \
             profiles:\n      t: {{l_over_lambda_l: 2, lambda_s_over_dl: 4, realizations: 2}}\n"
        );
    }
    text + "figures:\n  spectrum:\n    kind: spectrum\n    studies: [s16, s4, s8]\n    \
            loads: [0.02, 0.06]\n    profiles: [t]\n"
}

fn strings(df: &DataFrame, name: &str) -> Vec<String> {
    let c = df.column(name).unwrap().str().unwrap().clone();
    c.iter().map(|v| v.unwrap_or("").to_string()).collect()
}

/// (series, x, y) of each row of a figure's CSV.
fn csv_points(path: &Path) -> Vec<(String, f64, f64)> {
    let mut reader = csv::Reader::from_path(path).unwrap();
    let headers = reader.headers().unwrap().clone();
    let at = |name: &str| headers.iter().position(|h| h == name).unwrap();
    let (series, x, y) = (at("series"), at("x"), at("y"));
    reader
        .records()
        .map(|r| {
            let r = r.unwrap();
            (
                r[series].to_string(),
                r[x].parse().unwrap(),
                r[y].parse().unwrap(),
            )
        })
        .collect()
}

/// Each study's instance keys of `stage`, in plan order.
fn keys(dir: &Path, stage: &str) -> BTreeMap<String, Vec<String>> {
    let out = run_in(dir, &["plan", "--profile", "t", "--json"]);
    assert!(out.status.success(), "{out:?}");
    let mut keys: BTreeMap<String, Vec<String>> = BTreeMap::new();
    for i in stdout_json(&out)["instances"].as_array().unwrap() {
        if i["stage"] == stage {
            let study = i["studies"][0].as_str().unwrap().to_string();
            keys.entry(study)
                .or_default()
                .push(i["key"].as_str().unwrap().to_string());
        }
    }
    keys
}

/// P(A > a*) over the clusters of every realization of `study` at the load nearest 0.06,
/// counted from the clusters tables.
fn counted_k(dir: &Path, clusters: &[String], a_star_px: f64) -> f64 {
    let (mut above, mut all) = (0usize, 0usize);
    for key in clusters {
        let df = table(&dir.join(format!("data/cache/clusters/{key}/clusters.parquet")));
        let (w, area) = (f64s(&df, "w_over_w0"), f64s(&df, "area_px"));
        for (w, a) in w.iter().zip(&area) {
            if *w == 0.06 {
                all += 1;
                above += usize::from(*a > a_star_px);
            }
        }
    }
    assert!(all > 0, "no cluster at W/W0 = 0.06");
    above as f64 / all as f64
}

#[test]
fn spectrum_figure_reads_the_studies_cluster_tables() {
    let (_t, dir) = workdir(&pipeline());
    let out = run_in(&dir, &["run", "--profile", "t"]);
    assert!(out.status.success(), "{out:?}");
    let clusters = keys(&dir, "clusters");
    let figures = dir.join("figures").join("t");

    // K at A* = λ_l²/c from the pooled CCDF, and at A* = 2 and 8 λ_s² from the statistics,
    // both against a count of the clusters.
    let physical = csv_points(&figures.join("spectrum_k_physical.csv"));
    let mut checked = 0;
    for (series, x, y) in &physical {
        let Some(c) = series.strip_prefix("A* = λₗ²/") else {
            continue;
        };
        let c: f64 = c.parse().unwrap();
        let lambda_l_px = x * LAMBDA_S_PX;
        let study = format!("s{x}");
        let expected = counted_k(&dir, &clusters[&study], lambda_l_px * lambda_l_px / c);
        assert!(
            (y - expected).abs() <= 1e-12 * expected,
            "{series} at λ_l/λ_s = {x}: drawn {y}, counted {expected}"
        );
        checked += 1;
    }
    assert!(
        checked >= 6,
        "only {checked} physical K points: {physical:?}"
    );
    let k = csv_points(&figures.join("spectrum_k.csv"));
    for a_star in [2.0, 8.0] {
        let label = format!("A* = {a_star} λₛ²");
        let drawn: Vec<_> = k.iter().filter(|p| p.0 == label).collect();
        // In order of λ_l/λ_s, whatever the declaration's order.
        assert!(drawn.windows(2).all(|p| p[0].1 < p[1].1), "{drawn:?}");
        for r in RATIOS {
            let expected = counted_k(
                &dir,
                &clusters[&format!("s{r}")],
                a_star * LAMBDA_S_PX * LAMBDA_S_PX,
            );
            // The log axis leaves out K = 0 (no cluster above A*), and only that.
            match drawn.iter().find(|p| p.1 == f64::from(r)) {
                Some((_, _, y)) => {
                    assert!((y - expected).abs() <= 1e-12 * expected, "{label}, {r}")
                }
                None => assert_eq!(expected, 0.0, "{label}, λ_l/λ_s = {r} not drawn"),
            }
        }
    }

    // The sign change of dN/dA_c lies between a load where the statistics' dN/dA_c is
    // positive and the next, where it is not; none means positive at every load.
    let statistics = keys(&dir, "statistics");
    let transition = table(&figures.join("spectrum_transition.parquet"));
    let (studies, at) = (
        strings(&transition, "study"),
        f64s(&transition, "w_over_w0_sign_change"),
    );
    assert_eq!(studies, ["s4", "s8", "s16"]);
    for (study, at) in studies.iter().zip(at) {
        let key = &statistics[study][0];
        let loads = table(&dir.join(format!("data/cache/statistics/{key}/loads.parquet")));
        let (w, d) = (
            f64s(&loads, "w_over_w0"),
            f64s(&loads, "dn_dac_per_ls2_mean"),
        );
        // The loads where dN/dA_c is defined.
        let (w, d): (Vec<f64>, Vec<f64>) = w.into_iter().zip(d).filter(|p| p.1.is_finite()).unzip();
        if d.is_empty() {
            assert!(
                at.is_nan(),
                "{study}: no dN/dA_c defined, yet a change at {at}"
            );
            continue;
        }
        match d.iter().position(|&v| v <= 0.0) {
            None => assert_eq!(at, f64::INFINITY, "{study}: {d:?}"),
            Some(0) => assert_eq!(at, 0.0, "{study}: {d:?}"),
            Some(i) => assert!(
                w[i - 1] < at && at <= w[i] && d[i - 1] > 0.0,
                "{study}: change at {at}, loads {w:?}, dN/dA_c {d:?}"
            ),
        }
    }
    // The smallest spectrum merges within the sweep, so one change at least is found.
    assert!(at_least_one_finite(&transition), "{transition:?}");
}

fn at_least_one_finite(df: &DataFrame) -> bool {
    f64s(df, "w_over_w0_sign_change")
        .iter()
        .any(|v| v.is_finite() && *v > 0.0)
}

/// The repository's λ_l/λ_s = 2048 profile: its plan names a 32768² solve and what it costs,
/// and a run with this machine's 23.5 GiB is refused, naming both memories, before any work.
#[test]
fn a_32768_spectrum_is_planned_and_refused_here() {
    let root = super::repo_root();
    let config = root.join("pipeline.yaml");
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    let common = [
        "--profile",
        "spectrum2048",
        "--config",
        config.to_str().unwrap(),
        "--data",
        data.to_str().unwrap(),
    ];
    let out = run_in(tmp.path(), &[&["plan", "--json"][..], &common].concat());
    assert!(out.status.success(), "{out:?}");
    let plan = stdout_json(&out);
    let of = |stage: &str| -> Vec<serde_json::Value> {
        plan["instances"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|i| i["stage"] == stage)
            .cloned()
            .collect()
    };
    assert!(of("surface").iter().all(|i| i["params"]["n"] == 32768));
    let contact = of("contact");
    assert_eq!(contact.len(), 2);
    for i in &contact {
        let gib = i["estimate"]["peak_bytes"].as_f64().unwrap() / f64::from(1u32 << 30);
        // Seven n² doubles and more: 56 GiB at least, and not absurdly more.
        assert!((56.0..80.0).contains(&gib), "{gib} GiB");
        // Hours of CPU: 16 loads at 32768² are not a quick job.
        assert!(i["estimate"]["seconds"].as_f64().unwrap() > 3600.0, "{i}");
    }
    let machine = "25232932864"; // 23.5 GiB, this machine's /proc/meminfo
    let out = super::bin()
        .current_dir(tmp.path())
        .env("WEARCOEF_MEMORY_BYTES", machine)
        .args([&["run"][..], &common].concat())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("GiB, more than this machine's 23.5 GiB") && err.contains("wearcoef submit"),
        "{err}"
    );
    assert!(
        !data.join("cache").exists(),
        "work was done before the refusal"
    );
}
