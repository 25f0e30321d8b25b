//! The store commands a user drives: `run --dry-run`, `run --force`, `run --figures`, `gc`,
//! `status` with totals and keys, `verify` of results and catalogs, `catalog`; each from a
//! directory other than the one holding the pipeline file.

use std::path::Path;

use crate::{bin, small_pipeline, stdout_json, workdir};

/// Run `wearcoef` in a directory that is neither the store's nor the pipeline file's, with
/// both named by absolute paths.
fn elsewhere(dir: &Path, args: &[&str]) -> std::process::Output {
    let other = tempfile::tempdir().unwrap();
    let config = dir.join("pipeline.yaml");
    let data = dir.join("data");
    let mut full: Vec<&str> = args.to_vec();
    let (c, d) = (config.to_str().unwrap(), data.to_str().unwrap());
    let sub = full.remove(0);
    let mut v = vec![sub];
    match sub {
        "verify" => v.extend(["--data", d]),
        _ => v.extend(["--config", c, "--data", d]),
    }
    v.extend(full);
    bin().current_dir(other.path()).args(&v).output().unwrap()
}

fn ok(out: &std::process::Output) -> String {
    assert!(
        out.status.success(),
        "exit {:?}\nstdout: {}\nstderr: {}",
        out.status.code(),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).to_string()
}

fn run_full(dir: &Path) {
    let figures = dir.join("figures");
    ok(&elsewhere(
        dir,
        &[
            "run",
            "--profile",
            "t",
            "--quiet",
            "--figures",
            figures.to_str().unwrap(),
        ],
    ));
}

#[test]
fn dry_run_says_why_and_computes_nothing() {
    let (_t, dir) = workdir(&small_pipeline(0.8, "x"));
    // Into an empty store: everything is missing, and nothing is written.
    let out = elsewhere(&dir, &["run", "--profile", "t", "--dry-run", "--json"]);
    let pending = stdout_json(&out);
    let pending = pending.as_array().unwrap();
    assert_eq!(pending.len(), 5 + 5 + 5 + 2 + 2 + 1 + 1, "{pending:?}");
    assert!(pending.iter().all(|p| p["reason"] == "missing"));
    assert!(
        !dir.join("data/cache").exists(),
        "a dry run wrote to the store"
    );
    run_full(&dir);
    let out = elsewhere(&dir, &["run", "--profile", "t", "--dry-run", "--json"]);
    assert_eq!(stdout_json(&out).as_array().unwrap().len(), 0);
    // A changed parameter of study b: its surfaces and everything after them, with the reason.
    std::fs::write(dir.join("pipeline.yaml"), small_pipeline(0.7, "x")).unwrap();
    let out = elsewhere(&dir, &["run", "--profile", "t", "--dry-run", "--json"]);
    let pending = stdout_json(&out);
    let pending = pending.as_array().unwrap();
    let surfaces: Vec<_> = pending.iter().filter(|p| p["stage"] == "surface").collect();
    assert_eq!(surfaces.len(), 2, "{pending:?}");
    for s in &surfaces {
        assert_eq!(s["reason"], "changed parameter: hurst 0.8 → 0.7", "{s}");
    }
    let contact: Vec<_> = pending.iter().filter(|p| p["stage"] == "contact").collect();
    assert_eq!(contact.len(), 2);
    assert!(contact.iter().all(|p| p["reason"] == "input changed"));
    assert!(pending.iter().all(
        |p| p["studies"].as_array().unwrap().iter().all(|s| s == "b") || p["stage"] == "figures"
    ));
    // The text form names the reason too.
    let text = ok(&elsewhere(&dir, &["run", "--profile", "t", "--dry-run"]));
    assert!(
        text.contains("changed parameter: hurst 0.8 → 0.7"),
        "{text}"
    );
    assert!(text.contains("would compute"), "{text}");
}

#[test]
fn force_recomputes_a_stage_and_what_follows_it_with_identical_results() {
    let (_t, dir) = workdir(&small_pipeline(0.8, "x"));
    run_full(&dir);
    let stats = dir.join("data/cache/statistics");
    let before = std::fs::read_dir(&stats).unwrap().count();
    let manifest = |key: &std::ffi::OsStr| {
        std::fs::read_to_string(stats.join(key).join("manifest.json")).unwrap()
    };
    let keys: Vec<_> = std::fs::read_dir(&stats)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    let old: Vec<String> = keys.iter().map(|k| manifest(k)).collect();
    let out = elsewhere(
        &dir,
        &[
            "run",
            "--profile",
            "t",
            "--quiet",
            "--json",
            "--force",
            "statistics",
        ],
    );
    let summary = stdout_json(&out);
    // 2 statistics, 2 analytic (downstream), Fig. 6 (its model curves are not downstream).
    assert_eq!(summary["computed"], 4, "{summary}");
    assert_eq!(std::fs::read_dir(&stats).unwrap().count(), before);
    for (k, o) in keys.iter().zip(&old) {
        let new = manifest(k);
        assert_ne!(&new, o, "statistics entry {k:?} was not recomputed");
        let v: serde_json::Value = serde_json::from_str(&new).unwrap();
        let w: serde_json::Value = serde_json::from_str(o).unwrap();
        assert_eq!(v["outputs"], w["outputs"], "recomputed files differ");
    }
    let out = elsewhere(&dir, &["run", "--profile", "t", "--force", "nosuchstage"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--force nosuchstage"));
    assert!(ok(&elsewhere(&dir, &["verify"])).contains("0 problem(s)"));
}

#[test]
fn figures_go_where_asked_and_nothing_else_leaves_the_data_directory() {
    let (_t, dir) = workdir(&small_pipeline(0.8, "x"));
    run_full(&dir);
    assert!(dir.join("figures/t/fig6.png").is_file());
    assert!(dir.join("figures/t/provenance.json").is_file());
    let mut top: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .collect();
    top.sort();
    assert_eq!(top, ["data", "figures", "pipeline.yaml"]);
}

#[test]
fn gc_removes_only_what_no_profile_references() {
    let (_t, dir) = workdir(&small_pipeline(0.8, "x"));
    run_full(&dir);
    let count = |stage: &str| {
        std::fs::read_dir(dir.join("data/cache").join(stage)).map_or(0, |d| d.count())
    };
    // Nothing to collect while the profile references everything.
    let out = stdout_json(&elsewhere(&dir, &["gc", "--json"]));
    assert_eq!(out["entries"].as_array().unwrap().len(), 0, "{out}");
    // Study b changes: its old instances are garbage once the new ones exist.
    std::fs::write(dir.join("pipeline.yaml"), small_pipeline(0.7, "x")).unwrap();
    run_full(&dir);
    assert_eq!(count("surface"), 7);
    let dry = stdout_json(&elsewhere(&dir, &["gc", "--dry-run", "--json"]));
    let listed = dry["entries"].as_array().unwrap();
    // b's 2 surfaces, 2 sweeps, 2 labellings, its statistics and its model (Fig. 6 draws
    // only the shared model curves).
    assert_eq!(listed.len(), 2 + 2 + 2 + 1 + 1, "{dry}");
    assert_eq!(count("surface"), 7, "a dry run removed something");
    let done = stdout_json(&elsewhere(&dir, &["gc", "--json"]));
    assert_eq!(done["entries"], dry["entries"]);
    assert_eq!(count("surface"), 5);
    // What is left is exactly the profile, complete and intact.
    let status = stdout_json(&elsewhere(&dir, &["status", "--profile", "t", "--json"]));
    assert_eq!(status["totals"]["missing"], 0, "{status}");
    assert!(ok(&elsewhere(&dir, &["verify"])).contains("0 problem(s)"));
}

#[test]
fn status_counts_each_instance_once_and_lists_keys() {
    let (_t, dir) = workdir(&small_pipeline(0.8, "x"));
    let s = stdout_json(&elsewhere(&dir, &["status", "--profile", "t", "--json"]));
    let total = 5 + 5 + 5 + 2 + 2 + 1 + 1;
    assert_eq!(s["totals"]["missing"], total, "{s}");
    assert_eq!(s["totals"]["present"], 0);
    assert_eq!(s["instances"].as_array().unwrap().len(), total);
    run_full(&dir);
    let s = stdout_json(&elsewhere(&dir, &["status", "--profile", "t", "--json"]));
    assert_eq!(s["totals"]["present"], total);
    for i in s["instances"].as_array().unwrap() {
        let key = i["key"].as_str().unwrap();
        let stage = i["stage"].as_str().unwrap();
        assert!(dir.join("data/cache").join(stage).join(key).is_dir(), "{i}");
        assert_eq!(i["state"], "present");
    }
    let text = ok(&elsewhere(&dir, &["status", "--profile", "t", "--keys"]));
    assert!(text
        .lines()
        .any(|l| l.starts_with("total") && l.contains(&total.to_string())));
    let key = s["instances"][0]["key"].as_str().unwrap();
    assert!(text.contains(key), "{text}");
}

#[test]
fn verify_catches_an_edited_result_and_a_stale_catalog() {
    let (_t, dir) = workdir(&small_pipeline(0.8, "x"));
    run_full(&dir);
    assert!(ok(&elsewhere(&dir, &["verify"])).contains("0 problem(s)"));
    // An edited fitted value in a manifest.
    let stats = dir.join("data/cache/statistics");
    let entry = std::fs::read_dir(&stats)
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .path();
    let path = entry.join("manifest.json");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut m: serde_json::Value = serde_json::from_str(&text).unwrap();
    let results = m["results"].as_object_mut().unwrap();
    let (name, value) = results
        .iter_mut()
        .find(|(_, v)| v.is_number())
        .expect("a numeric result");
    let name = name.clone();
    *value = serde_json::json!(value.as_f64().unwrap() + 1.0);
    std::fs::write(&path, serde_json::to_string_pretty(&m).unwrap()).unwrap();
    let out = elsewhere(&dir, &["verify"]);
    assert_eq!(
        out.status.code(),
        Some(1),
        "edited result {name} passed verify"
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("a result was edited"));
    std::fs::write(&path, text).unwrap();
    assert!(ok(&elsewhere(&dir, &["verify"])).contains("0 problem(s)"));
    // A catalog that names an entry the store no longer has.
    let fig6 = std::fs::read_dir(dir.join("data/cache/figures"))
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .path();
    std::fs::remove_dir_all(&fig6).unwrap();
    let out = elsewhere(&dir, &["verify"]);
    assert_eq!(out.status.code(), Some(1));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("index.parquet") && stdout.contains("no such entry"),
        "{stdout}"
    );
}

#[test]
fn catalog_command_writes_csv_and_parquet_from_any_directory() {
    use polars::prelude::*;
    let (_t, dir) = workdir(&small_pipeline(0.8, "x"));
    run_full(&dir);
    let csv = ok(&elsewhere(&dir, &["catalog", "--profile", "t"]));
    let index = std::fs::read_to_string(dir.join("data/t/index.csv")).unwrap();
    assert_eq!(csv, index, "the command prints the catalog the run wrote");
    let out = dir.join("contact.parquet");
    ok(&elsewhere(
        &dir,
        &[
            "catalog",
            "--profile",
            "t",
            "--stage",
            "contact",
            "--format",
            "parquet",
            "--output",
            out.to_str().unwrap(),
        ],
    ));
    let df = ParquetReader::new(std::fs::File::open(&out).unwrap())
        .finish()
        .unwrap();
    assert_eq!(df.height(), 5);
    assert!(df.column("tolerance").is_ok() && df.column("lambda_s_over_dl").is_ok());
    for bad in [
        vec!["catalog", "--profile", "t", "--format", "parquet"],
        vec!["catalog", "--profile", "t", "--stage", "nosuch"],
        vec![
            "catalog",
            "--profile",
            "t",
            "--output",
            "/no/such/dir/x.csv",
        ],
    ] {
        let out = elsewhere(&dir, &bad);
        assert_eq!(out.status.code(), Some(2), "{bad:?}");
    }
}

/// A solve that does not converge is stored as a failure: the run exits 1 after computing
/// everything that does not depend on it, `status` and the catalog show it, the next run
/// does not retry it unless asked, and a changed parameter computes it afresh.
#[test]
fn a_failed_solve_is_data_not_a_valid_looking_result() {
    use polars::prelude::*;
    let failing = small_pipeline(0.8, "x").replace("max_iterations: 1000", "max_iterations: 1");
    let (_t, dir) = workdir(&failing);
    let figures = dir.join("figures");
    let run = |extra: &[&str]| {
        let mut args = vec!["run", "--profile", "t", "--quiet", "--figures"];
        args.push(figures.to_str().unwrap());
        args.extend(extra);
        elsewhere(&dir, &args)
    };
    let out = run(&[]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("5 instance(s) failed") && stderr.contains("did not converge"),
        "{stderr}"
    );
    assert!(
        !dir.join("data/cache/contact").exists()
            || std::fs::read_dir(dir.join("data/cache/contact"))
                .unwrap()
                .count()
                == 0,
        "a failed sweep was stored as an entry"
    );
    let records: Vec<_> = std::fs::read_dir(dir.join("data/failed/contact"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(records.len(), 5);
    let record: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&records[0]).unwrap()).unwrap();
    assert_eq!(
        record["report"]["solver_status"], "MaxIterations",
        "{record}"
    );
    assert!(record["report"]["last_error"].as_f64().unwrap() > 1e-10);
    // Independent work went on: the surfaces and the Fig. 6 model curves are stored.
    assert_eq!(
        std::fs::read_dir(dir.join("data/cache/surface"))
            .unwrap()
            .count(),
        5
    );
    // status: failed instances with their error; totals count them.
    let s = stdout_json(&elsewhere(&dir, &["status", "--profile", "t", "--json"]));
    assert_eq!(s["totals"]["failed"], 5, "{}", s["totals"]);
    let failed: Vec<_> = s["instances"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|i| i["state"] == "failed")
        .collect();
    assert_eq!(failed.len(), 5);
    assert!(failed
        .iter()
        .all(|i| i["stage"] == "contact"
            && i["error"].as_str().unwrap().contains("did not converge")));
    let text = ok(&elsewhere(&dir, &["status", "--profile", "t"]));
    assert!(text.contains("FAILED stage contact"), "{text}");
    // The catalog lists them, with the solver's report.
    let read = |name: &str| {
        ParquetReader::new(std::fs::File::open(dir.join("data/t").join(name)).unwrap())
            .finish()
            .unwrap()
    };
    let files = read("index.parquet");
    let states = files.column("state").unwrap().str().unwrap().clone();
    let paths = files.column("path").unwrap().str().unwrap().clone();
    let failed: Vec<&str> = states
        .iter()
        .zip(paths.iter())
        .filter(|(s, _)| *s == Some("failed"))
        .map(|(_, p)| p.unwrap())
        .collect();
    assert_eq!(failed.len(), 5);
    for p in failed {
        assert!(
            p.starts_with("failed/contact/") && dir.join("data").join(p).is_file(),
            "{p}"
        );
    }
    let contact = read("index_contact.parquet");
    assert_eq!(contact.height(), 5);
    assert!(contact
        .column("failure")
        .unwrap()
        .str()
        .unwrap()
        .iter()
        .all(|f| f.unwrap().contains("did not converge")));
    assert!(contact.column("last_error").is_ok());
    // Not retried by default: the records stay as they were.
    let before: Vec<String> = records
        .iter()
        .map(|p| std::fs::read_to_string(p).unwrap())
        .collect();
    let out = run(&[]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("not retried"));
    let after: Vec<String> = records
        .iter()
        .map(|p| std::fs::read_to_string(p).unwrap())
        .collect();
    assert_eq!(
        before, after,
        "a recorded failure was retried without --retry-failed"
    );
    // Retried when asked (it fails again, and says so afresh).
    let out = run(&["--retry-failed"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("5 instance(s) failed"));
    // A changed parameter gives new keys: computed, and the run succeeds.
    std::fs::write(dir.join("pipeline.yaml"), small_pipeline(0.8, "x")).unwrap();
    let out = run(&[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let s = stdout_json(&elsewhere(&dir, &["status", "--profile", "t", "--json"]));
    assert_eq!(s["totals"]["failed"], 0);
    assert_eq!(s["totals"]["missing"], 0);
    // The stale failure records belong to no profile now: gc removes them.
    let gc = stdout_json(&elsewhere(&dir, &["gc", "--json"]));
    assert_eq!(
        gc["entries"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|e| e["failed"] == true)
            .count(),
        5,
        "{gc}"
    );
    assert_eq!(
        std::fs::read_dir(dir.join("data/failed/contact"))
            .unwrap()
            .count(),
        0
    );
}

/// `fit --areas` recovers the exponent of areas drawn from a known discrete power law
/// (α = 1.5 on [1, 10⁴], inverse-CDF sampling), per load, leaving percolating clusters out;
/// bad tables are refused with exit 2.
#[test]
fn fit_recovers_a_known_exponent_from_a_table_of_areas() {
    use polars::prelude::*;
    use rand::{RngExt, SeedableRng};
    let dir = tempfile::tempdir().unwrap();
    let alpha = 1.5;
    let k_max = 10_000u64;
    let weights: Vec<f64> = (1..=k_max).map(|k| (k as f64).powf(-alpha)).collect();
    let total: f64 = weights.iter().sum();
    let mut cdf = Vec::with_capacity(weights.len());
    let mut acc = 0.0;
    for w in &weights {
        acc += w / total;
        cdf.push(acc);
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let (mut load, mut area, mut perc) = (Vec::new(), Vec::new(), Vec::new());
    for l in 0..2u32 {
        for _ in 0..4000 {
            let u: f64 = rng.random();
            let k = cdf.partition_point(|&c| c < u) as u64 + 1;
            load.push(l);
            area.push(k.min(k_max));
            perc.push(false);
        }
        // One huge percolating cluster per load, which must not enter the fit.
        load.push(l);
        area.push(1_000_000);
        perc.push(true);
    }
    let mut df = DataFrame::new(
        load.len(),
        vec![
            Column::new("load_index".into(), load),
            Column::new("area_px".into(), area),
            Column::new("percolating".into(), perc),
        ],
    )
    .unwrap();
    let path = dir.path().join("areas.parquet");
    ParquetWriter::new(std::fs::File::create(&path).unwrap())
        .finish(&mut df)
        .unwrap();
    let out = bin()
        .args(["fit", "--areas", path.to_str().unwrap(), "--json"])
        .output()
        .unwrap();
    let fits = stdout_json(&out);
    let fits = fits.as_array().unwrap();
    assert_eq!(fits.len(), 2);
    for f in fits {
        let a = f["alpha"].as_f64().unwrap();
        let se = f["std_error"].as_f64().unwrap();
        assert!((a - alpha).abs() < 4.0 * se, "{f}");
        assert!(se < 0.05, "{f}");
        let (lo, hi) = (
            f["bootstrap_ci95_low"].as_f64().unwrap(),
            f["bootstrap_ci95_high"].as_f64().unwrap(),
        );
        assert!(lo < a && a < hi, "{f}");
        assert_eq!(f["percolating_left_out"], 1);
        assert!(f["x_min_px"].as_f64().unwrap() >= 1.0);
        assert!(f["x_max_px"].as_f64().unwrap() <= k_max as f64, "{f}");
    }
    // Bad input: exit 2, naming the problem.
    let csv = dir.path().join("areas.csv");
    std::fs::write(&csv, "area_px\n1\n").unwrap();
    let mut bad_values =
        DataFrame::new(2, vec![Column::new("area_px".into(), vec![1.5f64, 2.0])]).unwrap();
    let frac = dir.path().join("frac.parquet");
    ParquetWriter::new(std::fs::File::create(&frac).unwrap())
        .finish(&mut bad_values)
        .unwrap();
    for (args, says) in [
        (vec!["fit", "--areas", csv.to_str().unwrap()], "parquet"),
        (
            vec!["fit", "--areas", path.to_str().unwrap(), "--column", "nope"],
            "no column 'nope'",
        ),
        (
            vec!["fit", "--areas", frac.to_str().unwrap()],
            "whole numbers",
        ),
        (
            vec!["fit", "--areas", path.to_str().unwrap(), "--resamples", "2"],
            "--resamples",
        ),
    ] {
        let out = bin().args(&args).output().unwrap();
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        assert!(
            String::from_utf8_lossy(&out.stderr).contains(says),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

/// `fit` with a realization column: intervals over whole realizations for α by both
/// estimators and for K, 𝒦 at each A* (inside [0, 1]), with the counts behind each; a
/// table of 4 realizations gets none and says why. Ten realizations whose exponents differ
/// (α_r from 1.4 to 1.9): the two halves' intervals overlap, and each is wider than the
/// interval that resamples clusters as if independent.
#[test]
fn fit_gives_intervals_over_realizations() {
    use polars::prelude::*;
    use rand::{RngExt, SeedableRng};
    let dir = tempfile::tempdir().unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let (mut realization, mut area) = (Vec::new(), Vec::new());
    for r in 0..10i64 {
        let alpha = 1.4 + 0.5 * (r as f64 * 0.618).fract();
        for _ in 0..400 {
            let u: f64 = rng.random();
            // Continuous Pareto above 1, floored: a discrete tail of exponent ≈ α.
            let x = (1.0 - u).powf(-1.0 / (alpha - 1.0)).floor().min(1e6) as u64;
            realization.push(r);
            area.push(x.max(1));
        }
    }
    let write = |name: &str, keep: &dyn Fn(i64) -> bool| {
        let rows: Vec<usize> = (0..area.len()).filter(|&i| keep(realization[i])).collect();
        let mut df = DataFrame::new(
            rows.len(),
            vec![
                Column::new(
                    "realization".into(),
                    rows.iter().map(|&i| realization[i]).collect::<Vec<_>>(),
                ),
                Column::new(
                    "area_px".into(),
                    rows.iter().map(|&i| area[i]).collect::<Vec<_>>(),
                ),
            ],
        )
        .unwrap();
        let path = dir.path().join(name);
        ParquetWriter::new(std::fs::File::create(&path).unwrap())
            .finish(&mut df)
            .unwrap();
        path
    };
    let halves = [
        write("a.parquet", &|r| r < 5),
        write("b.parquet", &|r| r >= 5),
    ];
    let four = write("four.parquet", &|r| r < 4);
    let fit = |path: &Path| -> serde_json::Value {
        let out = bin()
            .args([
                "fit",
                "--areas",
                path.to_str().unwrap(),
                "--a-star",
                "5,50",
                "--json",
            ])
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        stdout_json(&out)[0].clone()
    };
    let mut intervals = Vec::new();
    for path in &halves {
        let row = fit(path);
        assert_eq!(row["realizations"], 5);
        assert_eq!(row["ci95_method"], "realization_bootstrap_t");
        assert_eq!(row["plateau"]["ci95_method"], "realization_bootstrap_t");
        let (lo, hi) = (
            row["realization_ci95_low"].as_f64().unwrap(),
            row["realization_ci95_high"].as_f64().unwrap(),
        );
        let alpha = row["alpha"].as_f64().unwrap();
        assert!(lo < alpha && alpha < hi, "{lo} {alpha} {hi}");
        // Clauset's p-value of the power law above x_min is given, from as many samples.
        let p = row["gof_p"].as_f64().unwrap();
        assert!((0.0..=1.0).contains(&p) && row["gof_samples"].as_u64() > Some(0));
        let (blo, bhi) = (
            row["bootstrap_ci95_low"].as_f64().unwrap(),
            row["bootstrap_ci95_high"].as_f64().unwrap(),
        );
        assert!(
            hi - lo > bhi - blo,
            "over realizations [{lo}, {hi}], clusters [{blo}, {bhi}]"
        );
        for m in row["wear"].as_array().unwrap() {
            for k in ["k_archard", "k_upscaled"] {
                let (l, h) = (
                    m[format!("{k}_ci95_low")].as_f64().unwrap(),
                    m[format!("{k}_ci95_high")].as_f64().unwrap(),
                );
                assert!(
                    (0.0..=1.0).contains(&l) && (0.0..=1.0).contains(&h) && l <= h,
                    "{m}"
                );
            }
            assert!(
                m["clusters_above"].as_u64().unwrap()
                    >= m["clusters_above_smallest_realization"].as_u64().unwrap()
            );
        }
        intervals.push((lo, hi));
    }
    assert!(
        intervals[0].0 <= intervals[1].1 && intervals[1].0 <= intervals[0].1,
        "{intervals:?}"
    );
    let row = fit(&four);
    assert_eq!(row["realizations"], 4);
    assert_eq!(
        row["ci95_method"],
        "none: 4 realizations (an interval needs 5)"
    );
    assert!(row["realization_ci95_low"].is_null());
    assert_eq!(
        row["wear"][0]["k_archard_ci95_method"],
        "none: 4 realizations (an interval needs 5)"
    );
}
