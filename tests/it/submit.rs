//! `wearcoef submit` without a scheduler: the dry run's batch scripts, run by bash task by
//! task, build the same store as `run` (so the arrays, their chunks and slices cover every
//! instance); resources appear in the scripts; without sbatch a real submission is refused;
//! the `cluster:` block is validated. The real Slurm test is tests/slurm/run.sh.

use std::path::{Path, PathBuf};

use crate::{bin, run_in, small_pipeline, stdout_json, workdir};

/// Run wearcoef in `dir` without a Slurm cluster (a developer's SLURM_CONF removed).
fn no_slurm(dir: &Path, args: &[&str]) -> std::process::Output {
    bin()
        .current_dir(dir)
        .args(args)
        .env_remove("SLURM_CONF")
        .output()
        .expect("wearcoef runs")
}

fn the_campaign(dir: &Path) -> (PathBuf, serde_json::Value) {
    let base = dir.join("data/campaigns/t");
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(&base)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(dirs.len(), 1, "{dirs:?}");
    let d = dirs.pop().unwrap();
    let text = std::fs::read_to_string(d.join("campaign.json")).unwrap();
    (d, serde_json::from_str(&text).unwrap())
}

#[test]
fn dry_run_scripts_run_by_bash_build_the_same_store_as_run() {
    let (_t, dir) = workdir(&small_pipeline(0.8, "x"));
    // Arrays of at most 2 tasks and one instance per task: chunks with offsets.
    let out = no_slurm(
        &dir,
        &[
            "submit",
            "--profile",
            "t",
            "--dry-run",
            "--solve-cpus",
            "2",
            "--task-minutes",
            "1e-9",
            "--max-array-size",
            "2",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let printed = String::from_utf8_lossy(&out.stdout);
    assert!(printed.contains("#SBATCH --array=0-"), "{printed}");
    assert!(printed.contains("dry run, nothing submitted"), "{printed}");
    assert!(
        !dir.join("data/cache").exists(),
        "a dry run computes nothing"
    );
    let (cdir, campaign) = the_campaign(&dir);
    assert!(cdir.to_string_lossy().ends_with("-dry-run"));
    assert_eq!(campaign["submitted"], false);
    assert_eq!(campaign["instances"], 21);
    let mut keys = Vec::new();
    let mut scripts: Vec<(u64, PathBuf, u64)> = Vec::new();
    for a in campaign["arrays"].as_array().unwrap() {
        let spec = &a["spec"];
        let plan: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(a["plan"].as_str().unwrap()).unwrap())
                .unwrap();
        let instances = plan["instances"].as_array().unwrap();
        assert_eq!(instances.len() as u64, spec["instances"].as_u64().unwrap());
        assert_eq!(spec["tasks"], spec["instances"], "one instance per task");
        for i in instances {
            assert_eq!(i["level"], spec["level"]);
            keys.push(i["key"].as_str().unwrap().to_string());
        }
        let mut covered = 0;
        for c in a["chunks"].as_array().unwrap() {
            let len = c["chunk"]["len"].as_u64().unwrap();
            assert!(len <= 2, "chunked at --max-array-size");
            assert_eq!(c["chunk"]["offset"].as_u64().unwrap(), covered);
            covered += len;
            let path = PathBuf::from(c["script"].as_str().unwrap());
            let text = std::fs::read_to_string(&path).unwrap();
            let r = &spec["resources"];
            for line in [
                format!("#SBATCH --array=0-{}\n", len - 1),
                format!("#SBATCH --cpus-per-task={}\n", r["cpus"]),
                format!("#SBATCH --mem={}M\n", r["memory_mib"]),
                "#SBATCH --kill-on-invalid-dep=yes\n".to_string(),
            ] {
                assert!(text.contains(&line), "{line} not in {text}");
            }
            assert!(text.contains("#SBATCH --time=0-00:10:00\n"), "{text}");
            scripts.push((spec["level"].as_u64().unwrap(), path, len));
        }
        assert_eq!(covered, spec["tasks"].as_u64().unwrap());
    }
    let total = keys.len();
    keys.sort();
    keys.dedup();
    assert_eq!((keys.len(), total), (21, 21), "every instance exactly once");
    assert!(
        scripts.iter().any(|s| s.2 == 2) && scripts.len() > 8,
        "some arrays were chunked: {scripts:?}"
    );
    // What Slurm would do: level after level, every task of every chunk.
    scripts.sort();
    for (_, script, len) in &scripts {
        for task in 0..*len {
            let out = std::process::Command::new("bash")
                .arg(script)
                .current_dir(&dir)
                .env("SLURM_ARRAY_TASK_ID", task.to_string())
                .env("SLURM_CPUS_PER_TASK", "1")
                .output()
                .unwrap();
            assert!(
                out.status.success(),
                "{}: {}",
                script.display(),
                String::from_utf8_lossy(&out.stderr)
            );
            let done = stdout_json(&out);
            assert!(done["peak_rss_bytes"].as_u64().unwrap() > 0);
        }
    }
    assert!(
        !dir.join("data/t/index.parquet").exists(),
        "tasks never write the catalog"
    );
    let run = run_in(&dir, &["run", "--profile", "t", "--quiet", "--json"]);
    assert!(run.status.success());
    assert_eq!(
        stdout_json(&run)["computed"],
        0,
        "the scripts built everything"
    );
    assert!(dir.join("data/t/index.parquet").exists());
    let again = no_slurm(&dir, &["submit", "--profile", "t", "--dry-run"]);
    assert!(String::from_utf8_lossy(&again.stdout).contains("nothing to submit"));
}

#[test]
fn a_real_submission_without_sbatch_is_refused_and_writes_nothing() {
    let (_t, dir) = workdir(&small_pipeline(0.8, "x"));
    let out = bin()
        .current_dir(&dir)
        .args(["submit", "--profile", "t"])
        .env("PATH", "/nonexistent")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("sbatch is not available"), "{err}");
    assert!(!dir.join("data/campaigns").exists());
}

#[test]
fn cluster_settings_are_validated_naming_the_field() {
    for (block, field) in [
        ("cluster: {memory_safety: 0.5}", "cluster.memory_safety"),
        ("cluster: {solve_cpus: 0}", "cluster.solve_cpus"),
        ("cluster: {partition: \"a b\"}", "cluster.partition"),
        ("cluster: {max_array_size: 1}", "cluster.max_array_size"),
        ("cluster: {memory: 4}", "memory"),
    ] {
        let (_t, dir) = workdir(&format!("{}{block}\n", small_pipeline(0.8, "x")));
        let out = no_slurm(&dir, &["submit", "--profile", "t", "--dry-run"]);
        assert_eq!(out.status.code(), Some(2), "{block}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(field), "{block}: {err}");
        assert!(!dir.join("data/campaigns").exists(), "{block}");
    }
    // The command line is checked the same way.
    let (_t, dir) = workdir(&small_pipeline(0.8, "x"));
    let out = no_slurm(
        &dir,
        &[
            "submit",
            "--profile",
            "t",
            "--dry-run",
            "--time-safety",
            "0.9",
        ],
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("cluster.time_safety"));
}
