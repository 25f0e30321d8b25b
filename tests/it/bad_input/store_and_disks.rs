use crate::{bin, small_pipeline};
use std::path::Path;
use std::process::{Command, Output};

/// A cached input whose bytes no longer match its manifest is never used: the run stops,
/// names the file and the fix, and computes nothing from it.
#[test]
fn a_damaged_store_entry_is_never_reused() {
    for damage in ["flip a byte", "truncate"] {
        let (_t, dir) = crate::workdir(&small_pipeline(0.8, "x"));
        let first = crate::run_in(&dir, &["run", "--profile", "t", "--quiet"]);
        assert!(first.status.success());
        let surfaces: Vec<_> = std::fs::read_dir(dir.join("data/cache/surface"))
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        // Damage every surface and drop every sweep that was built on one.
        for s in &surfaces {
            let heights = s.join("heights.npy");
            let mut bytes = std::fs::read(&heights).unwrap();
            match damage {
                "flip a byte" => *bytes.last_mut().unwrap() ^= 0x40,
                _ => bytes.truncate(bytes.len() - 8),
            }
            std::fs::write(&heights, bytes).unwrap();
        }
        std::fs::remove_dir_all(dir.join("data/cache/contact")).unwrap();
        let out = crate::run_in(&dir, &["run", "--profile", "t", "--quiet"]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{damage}: {stderr}");
        assert!(
            stderr.contains("heights.npy") && stderr.contains("clean --corrupt"),
            "{damage}: {stderr}"
        );
        let sweeps = std::fs::read_dir(dir.join("data/cache/contact"))
            .map(|d| d.count())
            .unwrap_or(0);
        assert_eq!(
            sweeps, 0,
            "{damage}: a sweep was computed from a damaged surface"
        );
        assert!(
            !dir.join("data/failed").exists(),
            "{damage}: a damaged input is not the sweep's failure"
        );
    }
}

/// `sh` with a tmpfs of `size` mounted at `mount` in a private mount namespace (it vanishes
/// with the command): runs `script`, which sees the mount point as $1. Needs root or
/// unprivileged user namespaces; `None` where neither exists (a failure when CI is set).
fn with_small_disk(mount: &Path, size: &str, script: &str) -> Option<Output> {
    let root = unsafe { libc::geteuid() } == 0;
    let mut cmd = Command::new("unshare");
    cmd.arg(if root { "-m" } else { "-rm" });
    cmd.args(["sh", "-c"])
        .arg(format!(
            "mount -t tmpfs -o size={size} tmpfs \"$1\" || exit 97\n{script}"
        ))
        .arg("sh")
        .arg(mount)
        .env("WEARCOEF", env!("CARGO_BIN_EXE_wearcoef"));
    let out = cmd.output().ok().filter(|o| o.status.code() != Some(97));
    if out.is_none() {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI is set and no tmpfs can be mounted in a private namespace (unshare, root)"
        );
        eprintln!("skipped: no tmpfs can be mounted here (run as root, or allow user namespaces)");
    }
    out
}

/// A full disk is an error naming the user's path, never a panic, and leaves no partial
/// file, no temporary and no failure record behind; a full standard output likewise.
#[test]
fn full_disks_and_full_pipes_are_errors_without_partial_files() {
    let dir = tempfile::tempdir().unwrap();
    let mount = dir.path().join("disk");
    std::fs::create_dir(&mount).unwrap();
    std::fs::write(dir.path().join("pipeline.yaml"), small_pipeline(0.8, "x")).unwrap();
    // A 512 KiB surface onto 64 KiB; then a whole run onto 100 KiB. Each lists what is left.
    let script = r#"
cd "$1/.."
"$WEARCOEF" surface --n 256 --lambda-l-px 64 --lambda-s-px 4 --hurst 0.8 -o "$1/h.npy"
echo "surface exit $?"
echo "left: $(ls -A "$1")"
"$WEARCOEF" run --profile t --data "$1/data" --figures "$1/figures" --quiet --jobs 1
echo "run exit $?"
echo "temporaries: $(find "$1" -name '.*' ! -name .checked | wc -l)"
echo "failure records: $(find "$1" -path '*failed*' -name '*.json' | wc -l)"
"#;
    let Some(out) = with_small_disk(&mount, "100k", script) else {
        return;
    };
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    let all = format!("stdout:\n{stdout}\nstderr:\n{stderr}");
    assert!(!stderr.contains("panicked"), "{all}");
    assert!(stdout.contains("surface exit 1"), "{all}");
    assert!(
        stderr.contains(&format!("cannot write {}/h.npy", mount.display()))
            && stderr.contains("No space left on device"),
        "{all}"
    );
    assert!(
        stdout.contains("left: \n"),
        "a partial surface is left: {all}"
    );
    assert!(stdout.contains("run exit 1"), "{all}");
    assert!(!stderr.contains(".tmp-"), "names a temporary: {all}");
    assert!(stderr.contains("bytes free: make room"), "{all}");
    assert!(stdout.contains("temporaries: 0"), "{all}");
    assert!(stdout.contains("failure records: 0"), "{all}");

    // Standard output on a full device.
    let out = bin()
        .current_dir(dir.path())
        .args([
            "model", "--alpha", "1.5", "--a-s", "1", "--a-m", "100", "--a-star", "10",
        ])
        .stdout(std::fs::File::create("/dev/full").unwrap())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("No space left on device") && !stderr.contains("panicked"));
}
