//! A store that checks what it reuses: an entry whose manifest is not its own, whose files
//! changed after they were stored, or that was computed from an input that has changed
//! since, is never reused as it is; the repair path (`clean --corrupt`, then `run`) ends
//! with every artifact equal to a clean run's.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::{run_in, small_pipeline, workdir};

const RUN: [&str; 4] = ["run", "--profile", "t", "--quiet"];

/// Every file under data/cache and figures/, manifests excluded.
fn artifacts(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    crate::files_under(dir, &["data/cache", "figures"])
}

fn entries(dir: &Path, stage: &str) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir.join("data/cache").join(stage))
        .map(|r| r.map(|e| e.unwrap().path()).collect())
        .unwrap_or_default();
    v.sort();
    v
}

fn stderr(out: &std::process::Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// A clean run's artifacts, for comparison.
fn reference() -> BTreeMap<String, Vec<u8>> {
    let (_t, dir) = workdir(&small_pipeline(0.8, "x"));
    assert!(run_in(&dir, &RUN).status.success());
    artifacts(&dir)
}

#[test]
fn swapped_entries_stop_the_run_and_the_repair_leaves_no_poisoned_descendant() {
    let expected = reference();
    let (_t, dir) = workdir(&small_pipeline(0.8, "x"));
    assert!(run_in(&dir, &RUN).status.success());
    // Swap two surfaces, and drop everything computed after them.
    let s = entries(&dir, "surface");
    let tmp = dir.join("data/cache/surface/swap");
    std::fs::rename(&s[0], &tmp).unwrap();
    std::fs::rename(&s[1], &s[0]).unwrap();
    std::fs::rename(&tmp, &s[1]).unwrap();
    for stage in ["contact", "clusters", "statistics", "figures"] {
        let _ = std::fs::remove_dir_all(dir.join("data/cache").join(stage));
    }
    let out = run_in(&dir, &RUN);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(
        err.contains("manifest names surface/") && err.contains("clean --corrupt"),
        "{err}"
    );
    assert!(
        entries(&dir, "contact").is_empty(),
        "computed from a swapped surface"
    );
    // verify names both; clean --corrupt removes them; the run rebuilds them.
    let verify = run_in(&dir, &["verify"]);
    assert_eq!(verify.status.code(), Some(1));
    let listed = String::from_utf8_lossy(&verify.stdout);
    assert_eq!(
        listed.matches("manifest names surface/").count(),
        2,
        "{listed}"
    );
    assert!(run_in(&dir, &["clean", "--corrupt"]).status.success());
    assert!(run_in(&dir, &RUN).status.success());
    assert!(run_in(&dir, &["verify"]).status.success());
    assert_eq!(artifacts(&dir), expected);
}

#[test]
fn a_byte_changed_in_a_stored_file_stops_the_run_even_with_everything_downstream_stored() {
    let (_t, dir) = workdir(&small_pipeline(0.8, "x"));
    assert!(run_in(&dir, &RUN).status.success());
    let heights = entries(&dir, "surface")[0].join("heights.npy");
    let mut bytes = std::fs::read(&heights).unwrap();
    *bytes.last_mut().unwrap() ^= 0x01;
    std::fs::write(&heights, bytes).unwrap();
    for command in [
        &RUN[..],
        &["status", "--profile", "t"],
        &["plan", "--profile", "t"],
    ] {
        let out = run_in(&dir, command);
        assert_eq!(out.status.code(), Some(1), "{command:?}: {}", stderr(&out));
        let err = stderr(&out);
        assert!(
            err.contains("heights.npy") && err.contains("changed after it was stored"),
            "{command:?}: {err}"
        );
    }
}

#[test]
fn an_entry_computed_from_content_that_changed_since_is_recomputed() {
    let expected = reference();
    let (_t, dir) = workdir(&small_pipeline(0.8, "x"));
    assert!(run_in(&dir, &RUN).status.success());
    // Make one sweep look computed from other heights than its surface holds now (as one
    // computed from a damaged surface that was later rebuilt would).
    let sweep = entries(&dir, "contact")[0].clone();
    let path = sweep.join("manifest.json");
    let mut m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let digests = m["input_digests"]
        .as_object_mut()
        .expect("digests recorded");
    assert_eq!(digests.len(), 1);
    for v in digests.values_mut() {
        *v = serde_json::json!("0".repeat(64));
    }
    std::fs::write(&path, serde_json::to_string_pretty(&m).unwrap()).unwrap();
    let manifests = |stage: &str| -> Vec<String> {
        entries(&dir, stage)
            .iter()
            .map(|e| std::fs::read_to_string(e.join("manifest.json")).unwrap())
            .collect()
    };
    let clusters_before = manifests("clusters");
    let verify = run_in(&dir, &["verify"]);
    assert_eq!(verify.status.code(), Some(1));
    let listed = String::from_utf8_lossy(&verify.stdout);
    assert!(
        listed.contains("whose content has changed since"),
        "{listed}"
    );
    let dry = run_in(&dir, &["run", "--profile", "t", "--dry-run"]);
    assert!(String::from_utf8_lossy(&dry.stdout).contains("outdated"));
    // The run recomputes it and replaces it; what follows from it, which the recomputed
    // sweep gives the same content (timings aside), is kept as it was.
    assert!(run_in(&dir, &RUN).status.success());
    assert!(run_in(&dir, &["verify"]).status.success());
    assert_eq!(artifacts(&dir), expected);
    assert_eq!(manifests("clusters"), clusters_before);
}

/// The content digest an entry's descendants record is the same for every computation of
/// the entry: two stores built apart agree on every entry's digest (timings differ).
#[test]
fn content_digests_do_not_depend_on_timings() {
    use wearcoef::store::Manifest;
    let digests = || -> BTreeMap<String, String> {
        let (_t, dir) = workdir(&small_pipeline(0.8, "x"));
        assert!(run_in(&dir, &RUN).status.success());
        [
            "surface",
            "contact",
            "clusters",
            "statistics",
            "analytic",
            "figures",
        ]
        .iter()
        .flat_map(|s| entries(&dir, s))
        .map(|e| {
            let m: Manifest =
                serde_json::from_str(&std::fs::read_to_string(e.join("manifest.json")).unwrap())
                    .unwrap();
            (m.key.clone(), m.content_digest())
        })
        .collect()
    };
    let (a, b) = (digests(), digests());
    assert!(a.len() > 10);
    assert_eq!(a, b);
}

/// Temporaries of killed processes (a catalog, a gallery file, a failure record, a solve's
/// output) go with the next command that writes there; a live process's stay.
#[test]
fn temporaries_of_dead_processes_are_removed() {
    let (_t, dir) = workdir(&small_pipeline(0.8, "x"));
    assert!(run_in(&dir, &RUN).status.success());
    // 4194399 is above the kernel's largest pid: no process has it.
    let dead = [
        "data/t/.index.csv.tmp-4194399",
        "figures/t/.fig6.png.tmp-4194399",
        ".p.npy.tmp-4194399",
    ];
    std::fs::create_dir_all(dir.join("data/failed/contact")).unwrap();
    let record = "data/failed/contact/.abc.json.tmp-4194399";
    let live = format!("data/t/.index.csv.tmp-{}", std::process::id());
    for f in dead.iter().chain([&record]).chain([&live.as_str()]) {
        std::fs::write(dir.join(f), b"partial").unwrap();
    }
    assert!(run_in(&dir, &RUN).status.success());
    for f in &dead[..2] {
        assert!(!dir.join(f).exists(), "{f} left by run");
    }
    assert!(
        dir.join(&live).exists(),
        "a live process's temporary was removed"
    );
    std::fs::write(dir.join(dead[0]), b"partial").unwrap();
    let gc = run_in(&dir, &["gc"]);
    assert!(gc.status.success(), "{}", stderr(&gc));
    assert!(!dir.join(dead[0]).exists() && !dir.join(record).exists());
    // A solve writing p.npy removes the temporary a killed solve left for it.
    let surf = run_in(
        &dir,
        &[
            "surface",
            "--n",
            "16",
            "--lambda-l-px",
            "8",
            "--lambda-s-px",
            "2",
            "--hurst",
            "0.8",
            "-o",
            "h.npy",
        ],
    );
    assert!(surf.status.success());
    let solve = run_in(
        &dir,
        &[
            "solve",
            "--surface",
            "h.npy",
            "--loads",
            "0.05",
            "--pressure-out",
            "p.npy",
        ],
    );
    assert!(solve.status.success(), "{}", stderr(&solve));
    assert!(!dir.join(dead[2]).exists() && dir.join("p.npy").is_file());
}

/// A run removes from a gallery only the figure files its last record lists: a user's file
/// of the same kinds in the same directory stays.
#[test]
fn a_gallery_keeps_files_it_did_not_write() {
    let (_t, dir) = workdir(&small_pipeline(0.8, "x"));
    std::fs::create_dir_all(dir.join("figures/t")).unwrap();
    std::fs::write(dir.join("figures/t/my_measurements.csv"), "x,y\n1,2\n").unwrap();
    assert!(run_in(&dir, &RUN).status.success());
    assert!(run_in(&dir, &RUN).status.success());
    assert!(dir.join("figures/t/my_measurements.csv").is_file());
    assert!(dir.join("figures/t/fig6.png").is_file());
}

/// `run --at-once 1` computes one instance at a time, and each manifest then records that
/// instance's peak memory (a process running several at once records none).
#[test]
fn one_instance_at_a_time_records_its_peak_memory() {
    let peaks = |dir: &Path| -> Vec<Option<u64>> {
        ["surface", "contact", "clusters"]
            .iter()
            .flat_map(|s| entries(dir, s))
            .map(|e| {
                let m: serde_json::Value = serde_json::from_str(
                    &std::fs::read_to_string(e.join("manifest.json")).unwrap(),
                )
                .unwrap();
                m["peak_rss_bytes"].as_u64()
            })
            .collect()
    };
    let (_t, alone) = workdir(&small_pipeline(0.8, "x"));
    let out = run_in(
        &alone,
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
    assert!(out.status.success(), "{}", stderr(&out));
    let p = peaks(&alone);
    assert!(!p.is_empty());
    // At least the memory of the program itself, at most this machine's.
    let memory = wearcoef::machine::memory_bytes().unwrap();
    assert!(
        p.iter()
            .all(|b| b.is_some_and(|b| b > 1 << 20 && b < memory)),
        "{p:?}"
    );
    let (_t, together) = workdir(&small_pipeline(0.8, "x"));
    let out = run_in(
        &together,
        &["run", "--profile", "t", "--quiet", "--jobs", "2"],
    );
    assert!(out.status.success());
    assert!(peaks(&together).iter().any(Option::is_none));
}

/// A forged manifest listing an output outside its entry (`../x`) is a damaged entry: it is
/// never read or copied anywhere.
#[test]
fn a_manifest_naming_a_file_outside_its_entry_is_damaged() {
    let (_t, dir) = workdir(&small_pipeline(0.8, "x"));
    assert!(run_in(&dir, &RUN).status.success());
    let fig = entries(&dir, "figures")[0].clone();
    let path = fig.join("manifest.json");
    let mut m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let outputs = m["outputs"].as_object_mut().unwrap();
    let (_, first) = outputs
        .iter()
        .next()
        .map(|(k, v)| (k.clone(), v.clone()))
        .unwrap();
    outputs.insert("../../../../escaped.png".into(), first);
    std::fs::write(&path, serde_json::to_string_pretty(&m).unwrap()).unwrap();
    let out = run_in(&dir, &RUN);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("not a plain file name"),
        "{}",
        stderr(&out)
    );
    assert!(!dir.join("escaped.png").exists() && !dir.join("figures/escaped.png").exists());
    let verify = run_in(&dir, &["verify"]);
    assert!(String::from_utf8_lossy(&verify.stdout).contains("not a plain file name"));
}
