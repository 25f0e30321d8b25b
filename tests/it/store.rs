//! The artifact store and runner, through the CLI: reuse, selective recomputation,
//! verification, crash safety and concurrent runs.

use std::collections::BTreeMap;
use std::path::Path;
use std::time::{Duration, Instant};

use crate::{bin, run_in, small_pipeline, stdout_json, workdir};

fn run_json(dir: &Path, extra: &[&str]) -> serde_json::Value {
    let mut args = vec!["run", "--profile", "t", "--json", "--quiet"];
    args.extend_from_slice(extra);
    let out = run_in(dir, &args);
    assert!(
        out.status.success(),
        "run failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout_json(&out)
}

/// Every file under data/cache (relative to it), manifests excluded (they hold wall times).
fn artifacts(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    crate::files_under(&dir.join("data"), &["cache"])
        .into_iter()
        .map(|(k, v)| (k.trim_start_matches("cache/").to_string(), v))
        .collect()
}

#[test]
fn second_run_computes_nothing_and_one_changed_parameter_recomputes_only_its_instances() {
    let (_t, dir) = workdir(&small_pipeline(0.8, "first"));
    let first = run_json(&dir, &[]);
    assert_eq!(
        first["computed"], 21,
        "5 surfaces, 5 sweeps, 5 cluster tables, 2 statistics, 2 fitted models, Fig. 6 data and plot"
    );
    assert_eq!(first["reused"], 0);
    let keys_before: Vec<String> = std::fs::read_dir(dir.join("data/cache/surface"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .collect();

    let second = run_json(&dir, &[]);
    assert_eq!(second["computed"], 0);
    assert_eq!(second["reused"], 21);

    // A parameter no stage reads (a description) changes nothing.
    std::fs::write(dir.join("pipeline.yaml"), small_pipeline(0.8, "renamed")).unwrap();
    let third = run_json(&dir, &[]);
    assert_eq!(third["computed"], 0);

    // Study b's loads: only b's two contact sweeps, their cluster tables, b's statistics
    // and fitted model are rebuilt, not its surfaces.
    let text = small_pipeline(0.8, "renamed")
        .replace("loads: {values: [0.01]}", "loads: {values: [0.01, 0.03]}");
    std::fs::write(dir.join("pipeline.yaml"), &text).unwrap();
    let loads_changed = run_json(&dir, &[]);
    assert_eq!(loads_changed["computed"], 6);
    assert_eq!(loads_changed["reused"], 15);

    // Study b's Hurst exponent: b's two surfaces and everything downstream of them.
    std::fs::write(dir.join("pipeline.yaml"), small_pipeline(0.6, "renamed")).unwrap();
    let fourth = run_json(&dir, &[]);
    assert_eq!(fourth["computed"], 8);
    assert_eq!(fourth["reused"], 13);

    // The earlier keys are all still there (nothing was overwritten).
    for k in keys_before {
        assert!(dir
            .join("data/cache/surface")
            .join(&k)
            .join("manifest.json")
            .exists());
    }

    // Targets: a study name limits the run to that study.
    std::fs::write(dir.join("pipeline.yaml"), small_pipeline(0.5, "renamed")).unwrap();
    let only_a = run_json(&dir, &["a"]);
    assert_eq!(only_a["computed"], 0);
    // 3 surfaces, sweeps and cluster tables, the statistics and the fitted model of `a`
    // (the Fig. 6 model curves belong to no study).
    assert_eq!(only_a["instances"], 11);
    // A stage target builds that stage and what it needs, nothing downstream.
    let surfaces = run_json(&dir, &["surface"]);
    assert_eq!(surfaces["instances"], 5);
    assert_eq!(surfaces["computed"], 2);
    let bad = run_in(&dir, &["run", "--profile", "t", "nosuchstudy"]);
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("nosuchstudy"));
}

#[test]
fn status_reports_present_and_missing() {
    let (_t, dir) = workdir(&small_pipeline(0.8, "x"));
    let out = run_in(&dir, &["status", "--profile", "t", "--json"]);
    assert!(out.status.success());
    let before = stdout_json(&out);
    let missing: u64 = before["stages"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l["missing"].as_u64().unwrap())
        .sum();
    // The Fig. 6 curves and plot belong to no study.
    assert_eq!(
        missing, 19,
        "5 surfaces, 5 sweeps, 5 cluster tables, 2 statistics, 2 fitted models"
    );
    // Per stage, every instance once: those two as well.
    let per_stage: u64 = before["per_stage"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l["missing"].as_u64().unwrap())
        .sum();
    assert_eq!(per_stage, 21);
    assert_eq!(before["campaigns"], serde_json::json!([]));
    run_json(&dir, &["a"]);
    let after = stdout_json(&run_in(&dir, &["status", "--profile", "t", "--json"]));
    let lines = after["stages"].as_array().unwrap();
    let a = lines
        .iter()
        .find(|l| l["study"] == "a" && l["stage"] == "surface")
        .unwrap();
    let b = lines
        .iter()
        .find(|l| l["study"] == "b" && l["stage"] == "surface")
        .unwrap();
    assert_eq!(
        (a["present"].as_u64(), a["missing"].as_u64()),
        (Some(3), Some(0))
    );
    assert_eq!(
        (b["present"].as_u64(), b["missing"].as_u64()),
        (Some(0), Some(2))
    );
}

#[test]
fn verify_names_each_damaged_entry_and_clean_corrupt_removes_it() {
    let (_t, dir) = workdir(&small_pipeline(0.8, "x"));
    run_json(&dir, &[]);
    let ok = run_in(&dir, &["verify", "--json"]);
    assert!(ok.status.success());
    assert_eq!(stdout_json(&ok)["checked"], 21);

    let entries: Vec<_> = std::fs::read_dir(dir.join("data/cache/surface"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    // Flip one byte of one artifact (same size) and break another entry's manifest.
    let victim = entries[0].join("heights.npy");
    let mut bytes = std::fs::read(&victim).unwrap();
    let last = bytes.len() - 1;
    bytes[last] ^= 0x55;
    std::fs::write(&victim, bytes).unwrap();
    std::fs::write(entries[1].join("manifest.json"), "{ not json").unwrap();

    let bad = run_in(&dir, &["verify"]);
    assert!(!bad.status.success());
    let text = String::from_utf8_lossy(&bad.stdout);
    for damaged in &entries[..2] {
        let key = damaged.file_name().unwrap().to_string_lossy().to_string();
        assert!(
            text.lines()
                .any(|l| l.starts_with("MISMATCH") && l.contains(&key)),
            "{key} not named: {text}"
        );
    }
    assert!(text.contains("2 problem"), "{text}");

    // A run refuses to use a damaged entry and says how to fix it.
    let run = run_in(&dir, &["run", "--profile", "t", "--quiet"]);
    assert!(!run.status.success());
    assert!(String::from_utf8_lossy(&run.stderr).contains("clean --corrupt"));

    assert!(run_in(&dir, &["clean", "--corrupt"]).status.success());
    // Both damaged surfaces are rebuilt; their contact sweeps are intact and reused.
    let again = run_json(&dir, &[]);
    assert_eq!(again["computed"], 2);
    assert!(run_in(&dir, &["verify"]).status.success());
}

#[test]
fn sigkill_in_the_middle_of_a_stage_then_rerun_gives_the_uninterrupted_result() {
    let text = small_pipeline(0.8, "x");
    let (_t1, reference) = workdir(&text);
    run_json(&reference, &["--jobs", "1"]);

    let (_t2, dir) = workdir(&text);
    let mut child = bin()
        .current_dir(&dir)
        .args(["run", "--profile", "t", "--quiet", "--jobs", "1"])
        .env("WEARCOEF_DEBUG_PAUSE_BEFORE_COMMIT_MS", "5000")
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // Wait until a temporary entry has all its files (manifest included) but is not yet
    // renamed into place: the most dangerous moment to die.
    let stage_dir = dir.join("data/cache/surface");
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        let pending = std::fs::read_dir(&stage_dir)
            .ok()
            .into_iter()
            .flatten()
            .any(|e| {
                let p = e.unwrap().path();
                p.file_name()
                    .unwrap()
                    .to_string_lossy()
                    .starts_with(".tmp-")
                    && p.join("manifest.json").exists()
            });
        if pending {
            break;
        }
        assert!(Instant::now() < deadline, "no temporary entry appeared");
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap(); // SIGKILL on Unix
    child.wait().unwrap();

    // Nothing that looks complete was left behind.
    let complete = std::fs::read_dir(&stage_dir)
        .unwrap()
        .filter(|e| {
            !e.as_ref()
                .unwrap()
                .file_name()
                .to_string_lossy()
                .starts_with('.')
        })
        .count();
    assert_eq!(
        complete, 0,
        "a killed run must leave no complete-looking entry"
    );
    assert!(run_in(&dir, &["verify"]).status.success());

    let rerun = run_json(&dir, &[]);
    assert_eq!(rerun["computed"], 21);
    assert!(run_in(&dir, &["verify"]).status.success());
    assert_eq!(artifacts(&dir), artifacts(&reference));
    // The stale temporary directory of the dead process was cleaned up.
    let leftovers = std::fs::read_dir(&stage_dir)
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .unwrap()
                .file_name()
                .to_string_lossy()
                .starts_with(".tmp-")
        })
        .count();
    assert_eq!(leftovers, 0);
}

#[test]
fn two_concurrent_runs_on_one_store_both_succeed() {
    let (_t, dir) = workdir(&small_pipeline(0.8, "x"));
    let spawn = || {
        bin()
            .current_dir(&dir)
            .args(["run", "--profile", "t", "--quiet", "--jobs", "1"])
            .env("WEARCOEF_DEBUG_PAUSE_BEFORE_COMMIT_MS", "50")
            .output()
    };
    let (a, b) = std::thread::scope(|s| {
        let a = s.spawn(spawn);
        let b = s.spawn(spawn);
        (a.join().unwrap().unwrap(), b.join().unwrap().unwrap())
    });
    assert!(a.status.success(), "{}", String::from_utf8_lossy(&a.stderr));
    assert!(b.status.success(), "{}", String::from_utf8_lossy(&b.stderr));
    let v = run_in(&dir, &["verify", "--json"]);
    assert!(v.status.success());
    assert_eq!(stdout_json(&v)["checked"], 21);
    let again = run_json(&dir, &[]);
    assert_eq!(again["computed"], 0);
}

#[test]
fn identical_artifacts_for_one_and_two_threads() {
    let text = small_pipeline(0.8, "x");
    let (_t1, one) = workdir(&text);
    let (_t2, two) = workdir(&text);
    let out1 = bin()
        .current_dir(&one)
        .env("RAYON_NUM_THREADS", "1")
        .args(["run", "--profile", "t", "--quiet", "--jobs", "1"])
        .output()
        .unwrap();
    let out2 = bin()
        .current_dir(&two)
        .env("RAYON_NUM_THREADS", "2")
        .args(["run", "--profile", "t", "--quiet", "--jobs", "2"])
        .output()
        .unwrap();
    assert!(out1.status.success() && out2.status.success());
    assert_eq!(artifacts(&one), artifacts(&two));
}

/// A run of one target after a full run adds to the catalog and never truncates it: the
/// catalog keeps describing every stored instance of the profile.
#[test]
fn a_targeted_run_keeps_the_whole_catalog() {
    use polars::prelude::*;
    let (_t, dir) = workdir(&small_pipeline(0.8, "x"));
    let rows = |dir: &Path| {
        let file = std::fs::File::open(dir.join("data/t/index.parquet")).unwrap();
        let df = ParquetReader::new(file).finish().unwrap();
        let studies: std::collections::BTreeSet<String> = df
            .column("studies")
            .unwrap()
            .str()
            .unwrap()
            .iter()
            .flatten()
            .flat_map(|s| s.split_whitespace().map(String::from).collect::<Vec<_>>())
            .collect();
        (df.height(), studies)
    };
    run_json(&dir, &[]);
    let full = rows(&dir);
    assert!(full.1.contains("a") && full.1.contains("b"), "{full:?}");
    run_json(&dir, &["b"]);
    assert_eq!(rows(&dir), full);
    // A targeted run into an empty store lists what it stored (only b's instances).
    let (_t2, fresh) = workdir(&small_pipeline(0.8, "x"));
    run_json(&fresh, &["b"]);
    let partial = rows(&fresh);
    assert!(
        partial.0 < full.0 && !partial.1.contains("a"),
        "{partial:?}"
    );
}

#[test]
fn catalog_reads_back_with_typed_columns() {
    use polars::prelude::*;
    let (_t, dir) = workdir(&small_pipeline(0.8, "x"));
    run_json(&dir, &[]);
    let read = |name: &str| {
        let file = std::fs::File::open(dir.join("data/t").join(name)).unwrap();
        ParquetReader::new(file).finish().unwrap()
    };
    let df = read("index.parquet");
    // 5 surfaces; 5 sweeps, each with loads.parquet and one contact map per load
    // (study a: 3 realizations × 2 loads, study b: 2 × 1); 5 cluster tables with their
    // per-load summaries; 2 statistics entries of 5 tables each; 2 fitted models with
    // their plateau tables; the Fig. 6 curves and its PNG, SVG and CSV: each file once.
    assert_eq!(
        df.height(),
        5 + 5 + 3 * 2 + 2 + 5 * 2 + 2 * 5 + 2 * 2 + 1 + 3
    );
    for (name, dtype) in [
        ("profile", DataType::String),
        ("stage", DataType::String),
        ("studies", DataType::String),
        ("realization", DataType::UInt32),
        ("name", DataType::String),
        ("state", DataType::String),
        ("file", DataType::String),
        ("path", DataType::String),
        ("key", DataType::String),
        ("bytes", DataType::UInt64),
    ] {
        let col = df.column(name).unwrap_or_else(|_| panic!("column {name}"));
        assert_eq!(col.dtype(), &dtype, "{name}");
    }
    assert_eq!(
        df.width(),
        10,
        "index.parquet has only columns that apply to every file"
    );
    // Every path is relative to the store root and names a file there, whatever the
    // working directory.
    let paths = df.column("path").unwrap().str().unwrap().clone();
    for p in paths.iter() {
        let p = p.unwrap();
        assert!(!Path::new(p).is_absolute(), "{p}");
        assert!(dir.join("data").join(p).exists(), "{p}");
    }
    let csv = std::fs::read_to_string(dir.join("data/t/index.csv")).unwrap();
    assert_eq!(
        csv.lines().count(),
        1 + df.height(),
        "header + one row per artifact"
    );
    // Per-stage tables: one row per instance, parameters typed, the spectrum as ratios.
    let surfaces = read("index_surface.parquet");
    assert_eq!(surfaces.height(), 5);
    for (name, dtype) in [
        ("n", DataType::UInt64),
        ("hurst", DataType::Float64),
        ("seed", DataType::UInt64),
        ("rms_slope", DataType::Float64),
        ("hurst_fit", DataType::Float64),
        ("l_over_lambda_l", DataType::Float64),
        ("lambda_l_over_lambda_s", DataType::Float64),
        ("lambda_s_over_dl", DataType::Float64),
    ] {
        let col = surfaces
            .column(name)
            .unwrap_or_else(|_| panic!("column {name}"));
        assert_eq!(col.dtype(), &dtype, "{name}");
        assert_eq!(col.null_count(), 0, "{name}");
    }
    assert!(
        surfaces.column("rolloff_lambda_px").is_err(),
        "a parameter null for every instance is left out"
    );
    let n = surfaces.column("n").unwrap().u64().unwrap().clone();
    let ratios: Vec<f64> = [
        "l_over_lambda_l",
        "lambda_l_over_lambda_s",
        "lambda_s_over_dl",
    ]
    .iter()
    .map(|c| surfaces.column(c).unwrap().f64().unwrap().get(0).unwrap())
    .collect();
    assert_eq!(
        ratios.iter().product::<f64>(),
        n.get(0).unwrap() as f64,
        "L/λl · λl/λs · λs/Δl = n"
    );
    let contact = read("index_contact.parquet");
    assert_eq!(contact.height(), 5);
    assert_eq!(
        contact
            .column("realization")
            .unwrap()
            .u32()
            .unwrap()
            .null_count(),
        0
    );
    assert!(read("index_statistics.parquet")
        .column("realization")
        .is_err());
}

/// Keys must not drift between versions of the program unless a stage version or the salt
/// is bumped on purpose: this pins the key of one surface instance.
#[test]
fn cache_key_is_stable() {
    use wearcoef::stages::{keyed, surface::Surface, surface::SurfaceJob};
    let (_, key) = keyed::<Surface>(&SurfaceJob::Generated(key_fixture()), &[]);
    assert_eq!(
        key, PINNED_SURFACE_KEY,
        "surface keys changed: bump SURFACE_VERSION or the salt deliberately"
    );
}

/// The surface parameters whose key is pinned.
fn key_fixture() -> wearcoef::surface::SurfaceParams {
    wearcoef::surface::SurfaceParams {
        n: 64,
        hurst: 0.8,
        lambda_l_px: 32.0,
        lambda_s_px: 4.0,
        rolloff_lambda_px: None,
        method: wearcoef::surface::Method::Filter,
        seed: 1,
    }
}

const PINNED_SURFACE_KEY: &str = "8aa76b2801a9988576896a292e010b73809f1fcc17df8449f5e5ef3ed57c3342";

/// Every parameter the surface stage reads changes its key.
#[test]
fn every_surface_parameter_changes_the_key() {
    use wearcoef::stages::{keyed, surface::Surface, surface::SurfaceJob};
    use wearcoef::surface::{Method, SurfaceParams};
    let base = key_fixture();
    let key = |p: &SurfaceParams| keyed::<Surface>(&SurfaceJob::Generated(p.clone()), &[]).1;
    let variants = [
        SurfaceParams {
            n: 128,
            ..base.clone()
        },
        SurfaceParams {
            hurst: 0.8000000000000002,
            ..base.clone()
        },
        SurfaceParams {
            lambda_l_px: 16.0,
            ..base.clone()
        },
        SurfaceParams {
            lambda_s_px: 8.0,
            ..base.clone()
        },
        SurfaceParams {
            rolloff_lambda_px: Some(64.0),
            ..base.clone()
        },
        SurfaceParams {
            method: Method::RandomPhase,
            ..base.clone()
        },
        SurfaceParams {
            seed: 2,
            ..base.clone()
        },
    ];
    let mut keys = std::collections::BTreeSet::new();
    keys.insert(key(&base));
    for v in &variants {
        assert!(keys.insert(key(v)), "{v:?} did not change the key");
    }
}

#[test]
fn a_sweep_that_does_not_converge_stops_the_stage_and_stores_nothing() {
    let text = small_pipeline(0.8, "x").replace("max_iterations: 1000", "max_iterations: 2");
    let (_t, dir) = workdir(&text);
    let out = run_in(&dir, &["run", "--profile", "t", "--quiet", "--jobs", "1"]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("stage contact")
            && err.contains("realization")
            && err.contains("W/W0 = 0.01")
            && err.contains("did not converge"),
        "{err}"
    );
    let stored = std::fs::read_dir(dir.join("data/cache/contact"))
        .map(|d| {
            d.filter(|e| {
                !e.as_ref()
                    .unwrap()
                    .file_name()
                    .to_string_lossy()
                    .starts_with('.')
            })
            .count()
        })
        .unwrap_or(0);
    assert_eq!(
        stored, 0,
        "no contact entry may be stored for a failed sweep"
    );
    assert!(run_in(&dir, &["verify"]).status.success());
}

/// On a store shared by several machines, only this host's temporaries of dead processes
/// are removed: another host's may belong to a task still running there.
#[test]
fn clean_removes_only_this_hosts_dead_temporaries() {
    let (_t, dir) = workdir(&small_pipeline(0.8, "x"));
    let stage = dir.join("data/cache/surface");
    std::fs::create_dir_all(&stage).unwrap();
    let host = std::fs::read_to_string("/proc/sys/kernel/hostname")
        .unwrap()
        .trim()
        .to_string();
    // A pid that has just ended.
    let mut child = std::process::Command::new("true").spawn().unwrap();
    let dead = child.id();
    child.wait().unwrap();
    let key = "a".repeat(64);
    let here = stage.join(format!(".tmp-{key}-{host}-{dead}-1"));
    let there = stage.join(format!(".tmp-{key}-node-017.cluster-{dead}-1"));
    let alive = stage.join(format!(".tmp-{key}-{host}-{}-1", std::process::id()));
    for d in [&here, &there, &alive] {
        std::fs::create_dir(d).unwrap();
        std::fs::write(d.join("heights.npy"), b"partial").unwrap();
    }
    let out = run_in(&dir, &["clean", "--corrupt"]);
    assert!(out.status.success());
    assert!(!here.exists(), "this host's dead temporary is removed");
    assert!(there.exists(), "another host's is left alone");
    assert!(alive.exists(), "a live process's is left alone");
    // None of them looks like an entry.
    assert!(run_in(&dir, &["verify"]).status.success());
}
