//! `wearcoef plan` and `wearcoef exec`: the DAG of a profile as JSON, with levels, what the
//! store holds and cost estimates; a plan that cannot fit in memory is refused before any
//! work; a plan file runs in slices.

use crate::{run_in, small_pipeline, stdout_json, workdir};

fn plan_json(dir: &std::path::Path, extra: &[&str]) -> serde_json::Value {
    let mut args = vec!["plan", "--profile", "t", "--json"];
    args.extend_from_slice(extra);
    let out = run_in(dir, &args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout_json(&out)
}

#[test]
fn plan_lists_every_instance_with_its_inputs_level_and_estimate() {
    let (_t, dir) = workdir(&small_pipeline(0.8, "x"));
    let plan = plan_json(&dir, &[]);
    let instances = plan["instances"].as_array().unwrap();
    // 5 surfaces, sweeps and cluster tables, 2 statistics and fitted models, the Fig. 6
    // curves and figure.
    assert_eq!(instances.len(), 21);
    assert_eq!(plan["totals"]["instances"], 21);
    let by_key: std::collections::BTreeMap<&str, &serde_json::Value> = instances
        .iter()
        .map(|i| (i["key"].as_str().unwrap(), i))
        .collect();
    for i in instances {
        for field in [
            "stage", "key", "params", "inputs", "level", "cached", "estimate",
        ] {
            assert!(i.get(field).is_some(), "{field} missing: {i}");
        }
        assert_eq!(i["cached"], false);
        assert!(i["estimate"]["seconds"].as_f64().unwrap() > 0.0, "{i}");
        assert!(i["estimate"]["peak_bytes"].as_u64().unwrap() > 0, "{i}");
        // Every input is planned, on a lower level.
        for input in i["inputs"].as_array().unwrap() {
            let from = by_key[input["key"].as_str().unwrap()];
            assert_eq!(from["stage"], input["stage"]);
            assert!(from["level"].as_u64() < i["level"].as_u64(), "{i}");
        }
    }
    let level = |stage: &str| -> Vec<u64> {
        let mut v: Vec<u64> = instances
            .iter()
            .filter(|i| i["stage"] == stage)
            .map(|i| i["level"].as_u64().unwrap())
            .collect();
        v.dedup();
        v
    };
    assert_eq!(level("surface"), [0]);
    assert_eq!(level("contact"), [1]);
    assert_eq!(level("statistics"), [3]);
    // After a run, the store holds every instance and the plan says so.
    assert!(run_in(&dir, &["run", "--profile", "t", "--quiet"])
        .status
        .success());
    let after = plan_json(&dir, &[]);
    assert_eq!(after["totals"]["cached"], 21);
    assert!(after["instances"]
        .as_array()
        .unwrap()
        .iter()
        .all(|i| i["cached"] == true));
}

/// A grid whose solve needs more memory than the machine has: `plan` shows it, `run`
/// refuses before computing anything, naming the instance (exit 2).
#[test]
fn a_run_that_cannot_fit_in_memory_is_refused_before_it_starts() {
    let text = small_pipeline(0.8, "x").replace(
        "      t: {l_over_lambda_l: 2, lambda_s_over_dl: 8, realizations: 2}",
        "      t: {l_over_lambda_l: 1024, lambda_s_over_dl: 8, realizations: 1}",
    );
    let (_t, dir) = workdir(&text);
    let plan = plan_json(&dir, &[]);
    let largest = plan["totals"]["largest_peak_bytes"].as_u64().unwrap();
    let memory = plan["totals"]["machine_memory_bytes"].as_u64().unwrap();
    assert!(
        largest > memory,
        "32768² does not fit: {largest} vs {memory}"
    );
    let out = run_in(&dir, &["run", "--profile", "t", "--quiet"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("contact instance") && err.contains("studies b"),
        "{err}"
    );
    assert!(!dir.join("data/cache").exists(), "nothing computed");
}

/// `exec` runs a plan file level by level and slice by slice, and the result is the same
/// store a `run` makes.
#[test]
fn exec_runs_a_plan_in_slices_to_the_same_store_as_run() {
    let (_t, dir) = workdir(&small_pipeline(0.8, "x"));
    let plan = plan_json(&dir, &["--out", "plan.json"]);
    let levels = plan["totals"]["levels"].as_u64().unwrap();
    // A level whose inputs are not in the store fails, naming the missing input.
    let early = run_in(
        &dir,
        &["exec", "--plan", "plan.json", "--level", "1", "--quiet"],
    );
    assert!(!early.status.success());
    assert!(String::from_utf8_lossy(&early.stderr).contains("missing from the store"));
    for level in 0..levels {
        for slice in ["0/2", "1/2"] {
            let level = level.to_string();
            let args = [
                "exec",
                "--plan",
                "plan.json",
                "--level",
                &level,
                "--slice",
                slice,
            ];
            let out = run_in(&dir, &[&args[..], &["--quiet"]].concat());
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
    }
    let run = run_in(&dir, &["run", "--profile", "t", "--quiet", "--json"]);
    assert!(run.status.success());
    assert_eq!(stdout_json(&run)["computed"], 0, "exec built everything");
    // A plan edited by hand is refused before any work.
    let text = std::fs::read_to_string(dir.join("plan.json")).unwrap();
    let edited = text.replacen("\"e_star\": 1.0", "\"e_star\": 2.0", 1);
    assert_ne!(text, edited);
    std::fs::write(dir.join("edited.json"), edited).unwrap();
    let out = run_in(&dir, &["exec", "--plan", "edited.json", "--quiet"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("does not match its parameters"), "{err}");
}

/// `plan --against` sets a saved plan's estimates beside what the manifests measured: per
/// stage, the CPU seconds summed over the stored instances (checked against the manifests
/// read here) and, for a run of one instance at a time, the largest peak memory.
#[test]
fn a_saved_plan_is_compared_with_what_the_store_measured() {
    let (_t, dir) = crate::workdir(&crate::small_pipeline(0.8, "x"));
    let out = crate::run_in(&dir, &["plan", "--profile", "t", "--out", "before.json"]);
    assert!(out.status.success());
    let out = crate::run_in(
        &dir,
        &[
            "run",
            "--profile",
            "t",
            "--quiet",
            "--jobs",
            "2",
            "--at-once",
            "1",
        ],
    );
    assert!(out.status.success());
    let out = crate::run_in(&dir, &["plan", "--against", "before.json", "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rows = crate::stdout_json(&out);
    let plan: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("before.json")).unwrap()).unwrap();
    for row in rows.as_array().unwrap() {
        let stage = row["stage"].as_str().unwrap();
        let (mut cpu, mut est, mut peak, mut n) = (0.0, 0.0, 0u64, 0);
        for inst in plan["instances"].as_array().unwrap() {
            if inst["stage"] != stage {
                continue;
            }
            let path = dir
                .join("data/cache")
                .join(stage)
                .join(inst["key"].as_str().unwrap());
            let m: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(path.join("manifest.json")).unwrap())
                    .unwrap();
            cpu += m["cpu_seconds"].as_f64().unwrap();
            est += inst["estimate"]["seconds"].as_f64().unwrap();
            peak = peak.max(m["peak_rss_bytes"].as_u64().unwrap());
            n += 1;
        }
        assert_eq!(row["planned"], n, "{stage}");
        assert_eq!(row["measured"], n, "{stage}");
        assert_eq!(row["peak_measured"], n, "{stage}");
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs().max(1e-12);
        assert!(
            close(row["measured_cpu_seconds"].as_f64().unwrap(), cpu),
            "{stage}: {row}"
        );
        assert!(
            close(row["estimated_cpu_seconds"].as_f64().unwrap(), est),
            "{stage}: {row}"
        );
        assert_eq!(row["measured_peak_bytes"], peak, "{stage}");
    }
    // Not a plan: exit 2 naming the option.
    std::fs::write(dir.join("junk.json"), "{}").unwrap();
    let out = crate::run_in(&dir, &["plan", "--against", "junk.json"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--against junk.json"));
}
