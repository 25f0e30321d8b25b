//! Command-line contract: surface tool, exit codes and error messages.

use crate::{run_in, stdout_json, workdir};

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
        text.contains("10 computed") && text.contains("0 reused"),
        "{text}"
    );
}
