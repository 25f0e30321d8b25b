//! Every count a user can type is bounded by what this machine can do, and refused before
//! any work (never an abort on allocation, never thousands of threads).

use super::{case, check, Case};
use crate::small_pipeline;

fn with(from: &str, to: &str) -> Option<String> {
    let base = small_pipeline(0.8, "x");
    assert!(base.contains(from), "{from}");
    Some(base.replace(from, to))
}

#[test]
fn counts_beyond_the_machine_are_refused_before_any_work() {
    let cases = [
        case(
            "a thousand jobs",
            "run --profile t --jobs 1000000",
            2,
            &["--jobs 1000000", "threads", "choose at most"],
        ),
        Case {
            before: vec!["plan --profile t --out p.json"],
            ..case(
                "a level the plan does not have",
                "exec --plan p.json --level 99",
                2,
                &["--level 99", "levels 0 to 4"],
            )
        },
        case(
            "exec on a million threads",
            "exec --plan p.json --jobs 100000 --at-once 100000",
            2,
            &["--jobs 100000 --at-once 100000", "threads"],
        ),
        Case {
            pipeline: with("realizations: 3", "realizations: 4000000000"),
            ..case(
                "four billion realizations",
                "run --profile t",
                2,
                &[
                    "studies.a.profiles.t.realizations",
                    "more than this machine's memory allows a plan",
                ],
            )
        },
        Case {
            pipeline: with(
                "loads: {values: [0.01, 0.02]}",
                "loads: {min: 0.01, max: 0.02, count: 4000000000}",
            ),
            ..case(
                "four billion loads",
                "plan --profile t",
                2,
                &["loads.count", "4000000000", "fit in this machine's memory"],
            )
        },
        Case {
            pipeline: with("max_iterations: 1000", "max_iterations: 4000000000"),
            ..case(
                "an iteration cap that is no cap (allowed: nothing is reserved for it)",
                "plan --profile t",
                0,
                &[],
            )
        },
        Case {
            env: vec![("RAYON_NUM_THREADS", "20000")],
            ..case(
                "twenty thousand solver threads",
                "solve --json --surface ok.npy --loads 0.01",
                2,
                &["RAYON_NUM_THREADS=\"20000\"", "from 1 to"],
            )
        },
        Case {
            env: vec![("RAYON_NUM_THREADS", "two")],
            ..case(
                "threads that are not a number",
                "solve --json --surface ok.npy --loads 0.01",
                2,
                &["RAYON_NUM_THREADS=\"two\""],
            )
        },
        case(
            "solve with an iteration cap of 2^64 − 1",
            "solve --json --surface ok.npy --loads 0.01 --max-iter 18446744073709551615",
            0,
            &[],
        ),
    ];
    for c in &cases {
        check(c);
    }
}

/// Instances run side by side only as many at a time as the largest fits in memory: on a
/// machine of 3 GiB, whose largest instances are estimated at 1 GiB, `--jobs 64` runs three.
#[test]
fn instances_at_once_are_bounded_by_memory() {
    let (_t, dir) = crate::workdir(&small_pipeline(0.8, "x"));
    let out = crate::bin()
        .current_dir(&dir)
        .args(["run", "--profile", "t", "--jobs", "64"])
        .env("WEARCOEF_MEMORY_BYTES", "3221225472")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("instance(s) at once instead of 64"),
        "{stderr}"
    );
}

/// A directory this user cannot write is refused before any work, naming it (run as an
/// unprivileged user; root may write anywhere).
#[test]
fn an_unwritable_directory_is_named() {
    let root = tempfile::tempdir().unwrap();
    use std::os::unix::fs::PermissionsExt;
    let open = root.path().join("open");
    std::fs::create_dir(&open).unwrap();
    for p in [root.path(), open.as_path()] {
        std::fs::set_permissions(p, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
    let is_root = unsafe { libc::geteuid() } == 0;
    if is_root && !std::path::Path::new("/usr/bin/setpriv").exists() {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI is set and setpriv is missing"
        );
        eprintln!("skipped: no setpriv to drop root");
        return;
    }
    let mut cmd = if is_root {
        let mut c = std::process::Command::new("setpriv");
        c.args(["--reuid=65534", "--regid=65534", "--clear-groups"])
            .arg(env!("CARGO_BIN_EXE_wearcoef"));
        c
    } else {
        std::fs::set_permissions(&open, std::fs::Permissions::from_mode(0o555)).unwrap();
        crate::bin()
    };
    let out = cmd
        .current_dir(&open)
        .args([
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
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("--output h.npy") && stderr.contains("cannot be written by this user"),
        "{stderr}"
    );
    assert!(!open.join("h.npy").exists());
}
