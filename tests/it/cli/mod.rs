//! Command-line contract: surface tool, exit codes and error messages.

use crate::{run_in, stdout_json, workdir};

mod solve;
mod tables;

#[test]
fn surface_command_writes_npy_and_reports_statistics() {
    let dir = tempfile::tempdir().unwrap();
    let out = run_in(
        dir.path(),
        &[
            "surface",
            "--n",
            "128",
            "--lambda-l-px",
            "32",
            "--lambda-s-px",
            "4",
            "--hurst",
            "0.8",
            "--seed",
            "1",
            "-o",
            "h.npy",
            "--json",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let j = stdout_json(&out);
    assert!((j["rms_slope"].as_f64().unwrap() - 1.0).abs() < 1e-12);
    let (n, heights) = wearcoef::io::read_square_f64(&dir.path().join("h.npy")).unwrap();
    assert_eq!(n, 128);
    let rms = (heights.iter().map(|v| v * v).sum::<f64>() / heights.len() as f64).sqrt();
    assert!((rms - j["rms_height"].as_f64().unwrap()).abs() < 1e-15);
    // numpy's header: float64 little endian, C order, shape (128, 128).
    let bytes = std::fs::read(dir.path().join("h.npy")).unwrap();
    let header = String::from_utf8_lossy(&bytes[..128]);
    assert!(
        header.contains("'descr': '<f8'")
            && header.contains("'fortran_order': False")
            && header.contains("(128, 128)"),
        "{header}"
    );
}

#[test]
fn surface_command_rejects_bad_parameters_with_exit_2_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = run_in(
        dir.path(),
        &[
            "surface",
            "--n",
            "128",
            "--lambda-l-px",
            "32",
            "--lambda-s-px",
            "1",
            "--hurst",
            "0.8",
            "-o",
            "h.npy",
        ],
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("lambda_s_px"));
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        0,
        "no file written"
    );
}

#[test]
fn invalid_pipeline_exits_2_names_the_field_and_writes_nothing() {
    let text = crate::small_pipeline(0.8, "x").replace(
        "lambda_s_over_dl: 8, realizations: 3",
        "lambda_s_over_dl: 1, realizations: 3",
    );
    let (_t, dir) = workdir(&text);
    let out = run_in(&dir, &["run", "--profile", "t"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("studies.a.profiles.t.lambda_s_over_dl"),
        "{err}"
    );
    assert!(!dir.join("data").exists(), "nothing written");

    let out = run_in(&dir, &["run", "--profile", "nosuch"]);
    assert_eq!(out.status.code(), Some(2));

    let (_t2, dir2) = workdir(&crate::small_pipeline(0.8, "x"));
    let out = run_in(&dir2, &["run", "--profile", "nosuch"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("unknown profile"));
    assert!(!dir2.join("data").exists());
}

#[test]
fn run_prints_a_one_line_summary() {
    let (_t, dir) = workdir(&crate::small_pipeline(0.8, "x"));
    let out = run_in(&dir, &["run", "--profile", "t"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(text.trim().lines().count(), 1, "{text}");
    assert!(
        text.contains("21 computed") && text.contains("0 reused"),
        "{text}"
    );
}

pub(super) fn write_surface(dir: &std::path::Path, n: usize) -> std::path::PathBuf {
    let out = run_in(
        dir,
        &[
            "surface",
            "--n",
            &n.to_string(),
            "--lambda-l-px",
            "32",
            "--lambda-s-px",
            "4",
            "--hurst",
            "0.8",
            "--seed",
            "3",
            "-o",
            "h.npy",
        ],
    );
    assert!(out.status.success());
    dir.join("h.npy")
}

/// A reader that closes the pipe early ends the command cleanly: exit 0, no panic message.
#[test]
fn closed_stdout_pipe_exits_0_without_a_panic() {
    let (_t, dir) = workdir(&crate::small_pipeline(0.8, "x"));
    let mut child = crate::bin()
        .current_dir(&dir)
        .args(["status", "--profile", "t"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Close the read end before the command writes its first line.
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

/// Usage errors exit 2: an unknown target, and `verify` of a directory that holds no store.
#[test]
fn unknown_target_and_missing_store_exit_2() {
    let (_t, dir) = workdir(&crate::small_pipeline(0.8, "x"));
    let out = run_in(&dir, &["run", "--profile", "t", "nosuchtarget"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("unknown target 'nosuchtarget'"));
    let out = run_in(&dir, &["verify", "--data", "no/such/dir"]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("--data no/such/dir") && stderr.contains("no store"),
        "{stderr}"
    );
}

/// Off a terminal (a log file, CI), a run writes one plain progress line per computed
/// instance to stderr, naming its stage and study; `--quiet` writes none.
#[test]
fn a_run_into_a_log_prints_one_line_per_instance() {
    let (_t, dir) = workdir(&crate::small_pipeline(0.8, "x"));
    let out = run_in(&dir, &["run", "--profile", "t", "--json"]);
    assert!(out.status.success());
    let computed = stdout_json(&out)["computed"].as_u64().unwrap() as usize;
    let stderr = String::from_utf8_lossy(&out.stderr);
    let lines: Vec<&str> = stderr.lines().filter(|l| l.starts_with("done ")).collect();
    assert_eq!(lines.len(), computed, "{stderr}");
    assert!(
        lines
            .iter()
            .any(|l| l.starts_with("done contact a r0 ") && l.contains(" s (")),
        "{stderr}"
    );
    let (_t2, quiet) = workdir(&crate::small_pipeline(0.8, "x"));
    let out = run_in(&quiet, &["run", "--profile", "t", "--quiet"]);
    assert!(out.status.success());
    assert!(!String::from_utf8_lossy(&out.stderr).contains("done "));
}

/// `catalog | head -1`, also with `2>&1`: a reader that closes the pipe, on standard output
/// and standard error alike, ends the command with exit 0 and no panic.
#[test]
fn catalog_into_a_closed_pipe_exits_0() {
    let (_t, dir) = workdir(&crate::small_pipeline(0.8, "x"));
    assert!(run_in(&dir, &["run", "--profile", "t", "--quiet"])
        .status
        .success());
    for close_stderr in [false, true] {
        let mut child = crate::bin()
            .current_dir(&dir)
            .args(["catalog", "--profile", "t"])
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stdout.take());
        if close_stderr {
            drop(child.stderr.take());
        }
        let out = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(
            out.status.code(),
            Some(0),
            "stderr closed: {close_stderr}: {stderr}"
        );
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
}
