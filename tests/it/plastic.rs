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
    for (hardness, says) in [("0.015", "W/W0 = 0.02"), ("0", "must be finite and > 0")] {
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
