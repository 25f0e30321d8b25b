//! Studies with a `hardness`: the contact stage under a pressure ceiling stores the saturated
//! map of every load beside its contact map, while the elastic studies keep their store keys;
//! a hardness below a study's loads is refused before any work.

use crate::{files_under, run_in, stdout_json, workdir};

fn pipeline(plastic: Option<&str>) -> String {
    let study = |name: &str, extra: &str| {
        format!(
            "  {name}:\n    hurst: 0.8\n    lambda_l_over_lambda_s: 4\n    seed: 7\n{extra}    \
             loads: {{values: [0.01, 0.02]}}\n    profiles:\n      \
             t: {{l_over_lambda_l: 2, lambda_s_over_dl: 8, realizations: 2}}\n"
        )
    };
    let mut text = String::from(
        "schema_version: 1\nmaterial: {e_star: 1.0}\nsolver: {tolerance: 1.0e-10, \
         max_iterations: 1000}\nprofiles: {t: \"test\"}\nstudies:\n",
    );
    text += &study("a", "");
    if let Some(h) = plastic {
        text += &study("p", &format!("    hardness: {h}\n"));
    }
    text + "figures: {}\n"
}

/// The `stage` instances' keys of each study in the plan of `text`.
fn stage_keys(text: &str, stage: &str) -> std::collections::BTreeMap<String, Vec<String>> {
    let (_t, dir) = workdir(text);
    let out = run_in(&dir, &["plan", "--profile", "t", "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut keys: std::collections::BTreeMap<String, Vec<String>> = Default::default();
    for i in stdout_json(&out)["instances"].as_array().unwrap() {
        if i["stage"] == stage {
            for s in i["studies"].as_array().unwrap() {
                let key = i["key"].as_str().unwrap().to_string();
                keys.entry(s.as_str().unwrap().to_string())
                    .or_default()
                    .push(key);
            }
        }
    }
    keys
}

#[test]
fn a_hardness_leaves_elastic_keys_and_stores_saturated_maps() {
    for stage in ["contact", "clusters"] {
        let elastic = stage_keys(&pipeline(None), stage);
        let both = stage_keys(&pipeline(Some("0.05")), stage);
        assert_eq!(
            elastic["a"], both["a"],
            "an elastic study's {stage} keys changed"
        );
        // The same surfaces under a hardness are other instances.
        assert!(both["p"].iter().all(|k| !both["a"].contains(k)));
    }
    let both = stage_keys(&pipeline(Some("0.05")), "contact");
    let labelled = stage_keys(&pipeline(Some("0.05")), "clusters");

    let (_t, dir) = workdir(&pipeline(Some("0.05")));
    let out = run_in(&dir, &["run", "--profile", "t"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let files = files_under(&dir, &["data"]);
    let bits = |bytes: &[u8]| -> Vec<bool> {
        // A packed .npy of uint8: the payload follows the header's newline.
        let start = bytes.iter().position(|&b| b == b'\n').unwrap() + 1;
        bytes[start..]
            .iter()
            .flat_map(|b| (0..8).map(move |k| b & (0x80 >> k) != 0))
            .collect()
    };
    for key in &both["p"] {
        for load in 0..2 {
            let at = |name: &str| {
                let path = format!("data/cache/contact/{key}/{name}_{load:03}.npy");
                files.get(&path).unwrap_or_else(|| panic!("{path} missing"))
            };
            let (contact, saturated) = (bits(at("contact")), bits(at("saturated")));
            let count = saturated.iter().filter(|&&s| s).count();
            assert!(
                count > 0,
                "{key} load {load}: nothing saturated at W/W0/𝓗 ≥ 0.2"
            );
            assert!(
                contact.iter().zip(&saturated).all(|(&c, &s)| c || !s),
                "{key} load {load}: a saturated node out of contact"
            );
        }
    }
    for key in &both["a"] {
        let prefix = format!("data/cache/contact/{key}/");
        assert!(
            !files
                .keys()
                .any(|f| f.starts_with(&prefix) && f.contains("saturated")),
            "an elastic instance holds a saturated map"
        );
    }
    // The saturated clusters, a second table beside the contact clusters, under a hardness
    // only.
    for (study, expected) in [("p", true), ("a", false)] {
        for key in &labelled[study] {
            let table = format!("data/cache/clusters/{key}/saturated_clusters.parquet");
            assert_eq!(files.contains_key(&table), expected, "{table}");
            assert!(files.contains_key(&format!("data/cache/clusters/{key}/clusters.parquet")));
        }
    }
}

#[test]
fn a_hardness_below_a_load_is_refused_naming_the_field() {
    for (hardness, says) in [("0.015", "W/W0 = 0.02"), ("0", "must be > 0")] {
        let (_t, dir) = workdir(&pipeline(Some(hardness)));
        let out = run_in(&dir, &["run", "--profile", "t"]);
        assert_eq!(out.status.code(), Some(2), "hardness {hardness}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("studies.p.hardness") && err.contains(says),
            "{err}"
        );
        assert!(!dir.join("data").join("cache").exists(), "work was done");
    }
}

/// Where most of the contact set is saturated, the extended preconditioner's steps can carry
/// a quarter of the active set across the bounds and back at every iteration: on this
/// 1024² surface of one λ_l (λ_s = 8 Δl, H = 0.8, seed 3) at 𝓗 = 0.5 and W/W0 = 0.035 the
/// error cycled near 5e-3 until the stall window ended the solve. The bounded solve now sets
/// the extension aside when its error stops improving, and converges: the state carries the
/// load, lies within the bounds, and meets each bound's condition node by node within a
/// slack far below what the cycling state missed it by.
#[test]
#[ignore = "a 1024² solve, slow in debug builds: run by `make test` in release"]
fn extension_stagnation_under_a_ceiling_falls_back() {
    use wearcoef::contact::elastic::ElasticOperator;
    use wearcoef::contact::solver::{Ceiling, Solver, SolverConfig};
    use wearcoef::grid::Grid;
    use wearcoef::spectral::Fft2;
    use wearcoef::surface::{self, Method, SurfaceParams};

    let (n, max, mean) = (1024, 0.5, 0.035);
    let fft = Fft2::new(n);
    let params = SurfaceParams {
        n,
        hurst: 0.8,
        lambda_l_px: 1024.0,
        lambda_s_px: 8.0,
        rolloff_lambda_px: None,
        method: Method::Filter,
        seed: 3,
    };
    let h = surface::generate(&params, &fft, &mut fft.make_scratch())
        .unwrap()
        .heights;
    let op = ElasticOperator::new(Grid::unit(n).unwrap(), 1.0);
    let mut solver = Solver::with_constraint(&op, &h, Ceiling::new(max).unwrap()).unwrap();
    let cfg = SolverConfig {
        tolerance: 1e-6,
        ..SolverConfig::default()
    };
    assert!(cfg.preconditioned && cfg.extension.is_some(), "the default");
    let report = solver.solve(mean, &cfg).unwrap();
    assert!(report.converged(), "{report:?}");
    assert!(report.iterations <= 100, "{} iterations", report.iterations);
    let p = solver.pressure();
    assert!(p.iter().all(|&v| (0.0..=max).contains(&v)));
    let total: f64 = p.iter().sum();
    assert!((total / (n * n) as f64 / mean - 1.0).abs() <= 1e-10);
    let saturated = p.iter().filter(|&&v| v == max).count();
    assert!(2 * saturated > solver.contact_count(), "mostly saturated");
    // The separation recomputed, measured from the level of the nodes between the bounds.
    let mut u = vec![0.0; n * n];
    op.apply(p, &mut u, &mut op.make_workspace());
    let w: Vec<f64> = u.iter().zip(&h).map(|(u, h)| u - h).collect();
    let between: Vec<f64> = (0..n * n)
        .filter(|&i| p[i] > 0.0 && p[i] < max)
        .map(|i| w[i])
        .collect();
    let level = between.iter().sum::<f64>() / between.len() as f64;
    let std_h = (h.iter().map(|v| v * v).sum::<f64>() / h.len() as f64).sqrt();
    let (mut below, mut above, mut off) = (0.0f64, 0.0f64, 0.0f64);
    for i in 0..n * n {
        let d = (w[i] - level) / std_h;
        if p[i] == 0.0 {
            below = below.max(-d);
        } else if p[i] == max {
            above = above.max(d);
        } else {
            off = off.max(d.abs());
        }
    }
    // Measured: 0, 0 and 3.5e-6 std h; the slack keeps a factor 30 of margin and lies 50
    // times below the error the cycling state kept (5e-3).
    const SLACK: f64 = 1e-4;
    for (what, v) in [("gap", below), ("ceiling", above), ("contact", off)] {
        assert!(v <= SLACK, "{what} condition violated by {v:e} std h");
    }
}
