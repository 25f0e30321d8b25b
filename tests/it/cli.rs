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
        text.contains("21 computed") && text.contains("0 reused"),
        "{text}"
    );
}

fn write_surface(dir: &std::path::Path, n: usize) -> std::path::PathBuf {
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

#[test]
fn solve_command_prints_one_object_per_load_and_writes_fields() {
    let dir = tempfile::tempdir().unwrap();
    write_surface(dir.path(), 64);
    let out = run_in(
        dir.path(),
        &[
            "solve",
            "--surface",
            "h.npy",
            "--loads",
            "0.001,0.01,0.06",
            "--tol",
            "1e-9",
            "--pressure-out",
            "p.npy",
            "--contact-out",
            "c.npy",
            "--json",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rows = stdout_json(&out);
    let rows = rows.as_array().unwrap();
    assert_eq!(rows.len(), 3);
    for (row, w) in rows.iter().zip([0.001, 0.01, 0.06]) {
        for key in [
            "w_over_w0",
            "mean_pressure",
            "area_fraction",
            "n_contact_px",
            "iterations",
            "error",
            "converged",
            "seconds",
        ] {
            assert!(row.get(key).is_some(), "missing {key}");
        }
        assert_eq!(row["w_over_w0"].as_f64().unwrap(), w);
        assert!(row["converged"].as_bool().unwrap());
        assert!(row["error"].as_f64().unwrap() <= 1e-9);
        // Unit rms slope and E* = 1: the mean pressure equals W/W0.
        assert!((row["mean_pressure"].as_f64().unwrap() / w - 1.0).abs() < 1e-12);
    }
    // The area grows with the load.
    let areas: Vec<f64> = rows
        .iter()
        .map(|r| r["area_fraction"].as_f64().unwrap())
        .collect();
    assert!(areas[0] < areas[1] && areas[1] < areas[2]);
    // Stacked fields (loads, n, n); contact = pressure > 0 and its count matches the JSON.
    let bytes = std::fs::read(dir.path().join("c.npy")).unwrap();
    let header = String::from_utf8_lossy(&bytes[..128]).to_string();
    assert!(
        header.contains("'descr': '|u1'") && header.contains("(3, 64, 64)"),
        "{header}"
    );
    let data = &bytes[bytes.len() - 3 * 64 * 64..];
    for (k, row) in rows.iter().enumerate() {
        let count = data[k * 4096..(k + 1) * 4096]
            .iter()
            .filter(|&&b| b == 1)
            .count();
        assert_eq!(count as u64, row["n_contact_px"].as_u64().unwrap());
    }
    let p = std::fs::read(dir.path().join("p.npy")).unwrap();
    assert!(String::from_utf8_lossy(&p[..128]).contains("(3, 64, 64)"));
}

/// `--scale-start` starts each load from the last solution scaled instead of the default's
/// extrapolation through the last two: the same contact maps at every load, in more
/// iterations (measured 2026-11-26 on this 128² surface: 121 against 130 for the ten loads,
/// 15 % apart).
#[test]
fn solve_command_scale_start_gives_the_same_maps_in_more_iterations() {
    let dir = tempfile::tempdir().unwrap();
    write_surface(dir.path(), 128);
    let solve = |extra: &[&str], maps: &str| {
        let mut args = vec![
            "solve",
            "--surface",
            "h.npy",
            "--loads",
            "0.01,0.0115,0.013225,0.0152087,0.0174901,0.0201136,0.0231306,0.0266002,0.0305902,0.0351788",
            "--tol",
            "1e-10",
            "--json",
            "--contact-out",
            maps,
        ];
        args.extend_from_slice(extra);
        let out = run_in(dir.path(), &args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let rows = stdout_json(&out);
        rows.as_array()
            .unwrap()
            .iter()
            .map(|r| r["iterations"].as_u64().unwrap())
            .sum::<u64>()
    };
    let extrapolated = solve(&[], "c.npy");
    let scaled = solve(&["--scale-start"], "c_scaled.npy");
    assert_eq!(
        std::fs::read(dir.path().join("c.npy")).unwrap(),
        std::fs::read(dir.path().join("c_scaled.npy")).unwrap()
    );
    assert!(
        extrapolated < scaled,
        "{extrapolated} iterations extrapolated, {scaled} scaled"
    );
}

/// `--large-box N` declares boxes of N nodes per side and more large: on this 128² surface
/// `--large-box 128` turns on the extension's far term and the entry margin, which changes
/// the pressures' bits but not the solution (the same contact maps at every load), while a
/// gate above the box (256, as the default 4096) gives the default's bits exactly.
#[test]
fn solve_command_large_box_sets_where_the_large_box_layers_act() {
    let dir = tempfile::tempdir().unwrap();
    write_surface(dir.path(), 128);
    let solve = |extra: &[&str], name: &str| {
        let (maps, pressures) = (format!("c_{name}.npy"), format!("p_{name}.npy"));
        let mut args = vec![
            "solve",
            "--surface",
            "h.npy",
            "--loads",
            "0.02,0.04,0.08",
            "--tol",
            "1e-10",
            "--contact-out",
            &maps,
            "--pressure-out",
            &pressures,
        ];
        args.extend_from_slice(extra);
        let out = run_in(dir.path(), &args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let read = |f: &str| std::fs::read(dir.path().join(f)).unwrap();
        (read(&maps), read(&pressures))
    };
    let default = solve(&[], "default");
    let above = solve(&["--large-box", "256"], "above");
    let large = solve(&["--large-box", "128"], "large");
    assert_eq!(above, default, "a gate above the box changed the bits");
    assert_ne!(
        large.1, default.1,
        "--large-box 128 left every pressure bit unchanged"
    );
    assert_eq!(
        large.0, default.0,
        "--large-box 128 changed the contact maps"
    );
}

/// `--hardness`: `inf` is elastic contact with its exact bits; a finite hardness caps every
/// pressure at `hardness·E*·rms slope` (the same units as the loads), reached at some nodes
/// and reported as `n_saturated_px`, with the mean pressure unchanged; a load above the
/// hardness, or a hardness that is not > 0, is refused before any work, naming the flag.
#[test]
fn solve_command_hardness_caps_the_pressure() {
    let dir = tempfile::tempdir().unwrap();
    write_surface(dir.path(), 64);
    let solve = |extra: &[&str], name: &str| {
        let pressures = format!("p_{name}.npy");
        let mut args = vec![
            "solve",
            "--surface",
            "h.npy",
            "--loads",
            "0.02,0.05",
            "--tol",
            "1e-10",
            "--pressure-out",
            &pressures,
            "--json",
        ];
        args.extend_from_slice(extra);
        let out = run_in(dir.path(), &args);
        (out, dir.path().join(pressures))
    };
    let read =
        |path: &std::path::Path| -> ndarray::Array3<f64> { ndarray_npy::read_npy(path).unwrap() };
    let (elastic, elastic_p) = solve(&[], "elastic");
    let (infinite, infinite_p) = solve(&["--hardness", "inf"], "inf");
    assert!(elastic.status.success() && infinite.status.success());
    assert_eq!(
        read(&elastic_p),
        read(&infinite_p),
        "--hardness inf changed the bits"
    );
    assert!(stdout_json(&infinite)[0].get("n_saturated_px").is_none());

    let (capped, capped_p) = solve(&["--hardness", "0.1"], "capped");
    assert!(
        capped.status.success(),
        "{}",
        String::from_utf8_lossy(&capped.stderr)
    );
    let rows = stdout_json(&capped);
    let pressures = read(&capped_p);
    for (k, row) in rows.as_array().unwrap().iter().enumerate() {
        let (w, mean) = (
            row["w_over_w0"].as_f64().unwrap(),
            row["mean_pressure"].as_f64().unwrap(),
        );
        // mean = W/W0·E*·slope, so the hardness is 0.1 · mean / (W/W0) in pressure units.
        let ceiling = 0.1 * mean / w;
        let field = pressures.index_axis(ndarray::Axis(0), k);
        let top = field.iter().fold(0.0f64, |m, &p| m.max(p));
        assert!(
            (top - ceiling).abs() <= 1e-12 * ceiling,
            "load {k}: peak {top} vs {ceiling}"
        );
        let at_top = field.iter().filter(|&&p| p == top).count();
        assert_eq!(row["n_saturated_px"].as_u64().unwrap() as usize, at_top);
        assert!(at_top > 0);
        let got = field.mean().unwrap();
        assert!(
            (got - mean).abs() <= 1e-12 * mean,
            "load {k}: mean {got} vs {mean}"
        );
    }

    let (above, above_p) = solve(&["--hardness", "0.03"], "above");
    assert_eq!(above.status.code(), Some(2));
    let err = String::from_utf8_lossy(&above.stderr);
    assert!(
        err.contains("--hardness 0.03") && err.contains("0.05"),
        "{err}"
    );
    assert!(!above_p.exists());
    let (plain, plain_p) = solve(&["--hardness", "0.1", "--plain-cg"], "plain");
    assert_eq!(plain.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&plain.stderr).contains("--plain-cg with --hardness"));
    assert!(!plain_p.exists());
    for bad in ["0", "-1", "nan"] {
        let flag = format!("--hardness={bad}");
        let (out, path) = solve(&[&flag], "bad");
        assert_eq!(out.status.code(), Some(2), "--hardness {bad}");
        assert!(String::from_utf8_lossy(&out.stderr).contains("--hardness"));
        assert!(!path.exists());
    }
}

#[test]
fn solve_command_fails_loudly_when_a_load_does_not_converge() {
    let dir = tempfile::tempdir().unwrap();
    write_surface(dir.path(), 64);
    let out = run_in(
        dir.path(),
        &[
            "solve",
            "--surface",
            "h.npy",
            "--loads",
            "0.01",
            "--tol",
            "1e-14",
            "--max-iter",
            "3",
            "--pressure-out",
            "p.npy",
        ],
    );
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("did not converge") && err.contains("W/W0 = 0.01"),
        "{err}"
    );
    assert!(
        !dir.path().join("p.npy").exists(),
        "no field written for a failed solve"
    );
}

#[test]
fn solve_command_rejects_bad_surfaces_with_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    // NaN height.
    let mut h = vec![0.0; 16 * 16];
    h[17] = f64::NAN;
    wearcoef::io::write_f64(&dir.path().join("nan.npy"), &[16, 16], h).unwrap();
    let out = run_in(
        dir.path(),
        &["solve", "--json", "--surface", "nan.npy", "--loads", "0.01"],
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("row 1, column 1"));
    // Non-square.
    wearcoef::io::write_f64(&dir.path().join("rect.npy"), &[16, 8], vec![0.0; 128]).unwrap();
    let out = run_in(
        dir.path(),
        &[
            "solve",
            "--json",
            "--surface",
            "rect.npy",
            "--loads",
            "0.01",
        ],
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("square"));
    // Not a .npy file at all.
    std::fs::write(dir.path().join("junk.npy"), b"not numpy").unwrap();
    let out = run_in(
        dir.path(),
        &[
            "solve",
            "--json",
            "--surface",
            "junk.npy",
            "--loads",
            "0.01",
        ],
    );
    assert_eq!(out.status.code(), Some(2));
    // Negative load.
    write_surface(dir.path(), 32);
    let out = run_in(
        dir.path(),
        &["solve", "--json", "--surface", "h.npy", "--loads", "-0.01"],
    );
    assert_eq!(out.status.code(), Some(2));
}

/// The same map as bool, uint8 0/1 and the contact stage's bit-packed rows gives the same
/// clusters; areas are sorted in descending order; bad maps exit 2.
#[test]
fn clusters_command_reads_every_map_format() {
    use ndarray::Array2;
    let dir = tempfile::tempdir().unwrap();
    let n = 12;
    // A 2×3 block, a pixel linked diagonally to it, a lone pixel, and a pair across the
    // left–right edge.
    let mut map = vec![false; n * n];
    for (y, x) in [
        (2, 2),
        (2, 3),
        (2, 4),
        (3, 2),
        (3, 3),
        (3, 4),
        (4, 5),
        (8, 8),
        (6, 0),
        (6, 11),
    ] {
        map[y * n + x] = true;
    }
    let as_u8: Vec<u8> = map.iter().map(|&b| b as u8).collect();
    let bool_path = dir.path().join("bool.npy");
    ndarray_npy::write_npy(
        &bool_path,
        &Array2::from_shape_vec((n, n), map.clone()).unwrap(),
    )
    .unwrap();
    let u8_path = dir.path().join("u8.npy");
    wearcoef::io::write_u8(&u8_path, &[n, n], as_u8.clone()).unwrap();
    let pressure: Vec<f64> = as_u8.iter().map(|&v| v as f64).collect();
    let packed = wearcoef::contact::sweep::pack_contact(&pressure, n);
    let packed_path = dir.path().join("packed.npy");
    wearcoef::io::write_u8(&packed_path, &[n, n.div_ceil(8)], packed).unwrap();

    for path in [&bool_path, &u8_path, &packed_path] {
        let out = run_in(
            dir.path(),
            &["clusters", "--contact", path.to_str().unwrap(), "--json"],
        );
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v = stdout_json(&out);
        assert_eq!(v["n_clusters"], 3, "{path:?}: {v}");
        assert_eq!(v["areas_px"], serde_json::json!([7, 2, 1]));
        assert_eq!(v["percolating"], false);
        let out = run_in(
            dir.path(),
            &[
                "clusters",
                "--contact",
                path.to_str().unwrap(),
                "--connectivity",
                "4",
                "--json",
            ],
        );
        assert_eq!(
            stdout_json(&out)["areas_px"],
            serde_json::json!([6, 2, 1, 1])
        );
    }

    // A full row wraps around the box.
    let mut band = vec![0u8; n * n];
    band[5 * n..6 * n].fill(1);
    let band_path = dir.path().join("band.npy");
    wearcoef::io::write_u8(&band_path, &[n, n], band).unwrap();
    let out = run_in(
        dir.path(),
        &[
            "clusters",
            "--contact",
            band_path.to_str().unwrap(),
            "--json",
        ],
    );
    assert_eq!(stdout_json(&out)["percolating"], true);

    // Values other than 0/1, a float map, a missing file, a bad connectivity: exit 2.
    let bad = dir.path().join("bad.npy");
    let mut values = as_u8;
    values[7] = 2;
    wearcoef::io::write_u8(&bad, &[n, n], values).unwrap();
    let floats = dir.path().join("floats.npy");
    wearcoef::io::write_f64(&floats, &[n, n], vec![0.0; n * n]).unwrap();
    for args in [
        vec!["clusters", "--contact", bad.to_str().unwrap()],
        vec!["clusters", "--contact", floats.to_str().unwrap()],
        vec!["clusters", "--contact", "missing.npy"],
        vec![
            "clusters",
            "--contact",
            u8_path.to_str().unwrap(),
            "--connectivity",
            "6",
        ],
    ] {
        let out = run_in(dir.path(), &args);
        assert_eq!(
            out.status.code(),
            Some(2),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(!out.stderr.is_empty());
    }
}

#[test]
fn model_command_prints_both_coefficients_and_rejects_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let out = run_in(
        dir.path(),
        &[
            "model", "--alpha", "2.5", "--a-s", "3", "--a-m", "inf", "--a-star", "30", "--json",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v = stdout_json(&out);
    // VALIDATION.md §6.6: the A_m → ∞ limits at A_s = 3, A* = 30.
    assert!(
        (v["K"].as_f64().unwrap() - 0.012_649_11).abs() < 1e-8,
        "{v}"
    );
    assert!(
        (v["K_upscaled"].as_f64().unwrap() - 0.252_982_2).abs() < 1e-7,
        "{v}"
    );
    for args in [
        [
            "--alpha", "1.5", "--a-s", "0", "--a-m", "10", "--a-star", "1",
        ],
        [
            "--alpha", "1.5", "--a-s", "2", "--a-m", "1", "--a-star", "1",
        ],
        [
            "--alpha", "1.5", "--a-s", "2", "--a-m", "10", "--a-star", "-1",
        ],
        [
            "--alpha", "nan", "--a-s", "2", "--a-m", "10", "--a-star", "1",
        ],
    ] {
        let mut all = vec!["model"];
        all.extend_from_slice(&args);
        let out = run_in(dir.path(), &all);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        assert!(!out.stderr.is_empty());
    }
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

/// `clusters` reads the stack that `solve --contact-out` writes for several loads: one
/// result per map, each equal to the labelling of that load's map solved alone (the first
/// load of a sweep is solved from the same start as a one-load solve).
#[test]
fn clusters_reads_a_stack_of_maps_from_solve() {
    let dir = tempfile::tempdir().unwrap();
    write_surface(dir.path(), 64);
    for (loads, file) in [("0.02", "one.npy"), ("0.02,0.05", "two.npy")] {
        let out = run_in(
            dir.path(),
            &[
                "solve",
                "--surface",
                "h.npy",
                "--loads",
                loads,
                "--contact-out",
                file,
            ],
        );
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let clusters = |file: &str| {
        let out = run_in(dir.path(), &["clusters", "--contact", file, "--json"]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        stdout_json(&out)
    };
    let one = clusters("one.npy");
    let two = clusters("two.npy");
    let maps = two.as_array().expect("a stack gives an array");
    assert_eq!(maps.len(), 2);
    assert_eq!(maps[0]["map_index"], 0);
    assert_eq!(maps[0]["areas_px"], one["areas_px"]);
    assert_eq!(maps[0]["n_clusters"], one["n_clusters"]);
    // More load, more contact.
    let total = |m: &serde_json::Value| -> u64 {
        m["areas_px"]
            .as_array()
            .unwrap()
            .iter()
            .map(|a| a.as_u64().unwrap())
            .sum()
    };
    assert!(total(&maps[1]) > total(&maps[0]));
    // A stack holding something other than 0/1 is refused, naming where.
    let bad = dir.path().join("bad.npy");
    let mut stack = ndarray::Array3::<u8>::zeros((2, 4, 4));
    stack[[1, 2, 3]] = 7;
    ndarray_npy::write_npy(&bad, &stack).unwrap();
    let out = run_in(dir.path(), &["clusters", "--contact", "bad.npy"]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("found 7 in map 1, row 2, column 3"),
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

/// The single-stage tools chain: `solve --contact-out` → `clusters --out` → `fit`, whose
/// table has one row per cluster of each map (the areas `--json` prints), which `fit` reads
/// as it is and also with pandas' int64 `load_index`, reporting the paper's A_s and the
/// counted K and 𝒦 at `--a-star`, each recomputed here from the table; a table not named
/// `.parquet` is refused with exit 2 and nothing written.
#[test]
fn clusters_table_feeds_fit_with_a_s_and_counted_coefficients() {
    use polars::prelude::*;
    let dir = tempfile::tempdir().unwrap();
    write_surface(dir.path(), 128);
    let run = |args: &[&str]| {
        let out = run_in(dir.path(), args);
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        out
    };
    run(&[
        "solve",
        "--surface",
        "h.npy",
        "--loads",
        "0.02,0.06",
        "--contact-out",
        "maps.npy",
    ]);
    let printed = stdout_json(&run(&[
        "clusters",
        "--contact",
        "maps.npy",
        "--json",
        "--out",
        "clusters.parquet",
    ]));
    let table =
        ParquetReader::new(std::fs::File::open(dir.path().join("clusters.parquet")).unwrap())
            .finish()
            .unwrap();
    let index: Vec<u32> = table
        .column("load_index")
        .unwrap()
        .u32()
        .unwrap()
        .into_no_null_iter()
        .collect();
    let area: Vec<u64> = table
        .column("area_px")
        .unwrap()
        .u64()
        .unwrap()
        .into_no_null_iter()
        .collect();
    let percolating: Vec<bool> = table
        .column("percolating")
        .unwrap()
        .bool()
        .unwrap()
        .iter()
        .map(|v| v.unwrap())
        .collect();
    for (m, map) in printed.as_array().unwrap().iter().enumerate() {
        let mut mine: Vec<u64> = (0..area.len())
            .filter(|&i| index[i] == m as u32)
            .map(|i| area[i])
            .collect();
        mine.sort_unstable_by(|a, b| b.cmp(a));
        let listed: Vec<u64> = map["areas_px"]
            .as_array()
            .unwrap()
            .iter()
            .map(|a| a.as_u64().unwrap())
            .collect();
        assert_eq!(mine, listed, "map {m}");
    }
    // pandas writes whole numbers as int64.
    let mut wide = table.clone();
    let cast = wide
        .column("load_index")
        .unwrap()
        .cast(&DataType::Int64)
        .unwrap();
    wide.with_column(cast).unwrap();
    ParquetWriter::new(std::fs::File::create(dir.path().join("int64.parquet")).unwrap())
        .finish(&mut wide)
        .unwrap();
    let fits = |file: &str| {
        stdout_json(&run(&[
            "fit", "--areas", file, "--a-star", "4,40", "--json",
        ]))
    };
    let (fit, fit64) = (fits("clusters.parquet"), fits("int64.parquet"));
    assert_eq!(fit, fit64, "int64 load_index reads the same");
    for (m, row) in fit.as_array().unwrap().iter().enumerate() {
        assert_eq!(row["load_index"], m as u64);
        let kept: Vec<u64> = (0..area.len())
            .filter(|&i| index[i] == m as u32 && !percolating[i])
            .map(|i| area[i])
            .collect();
        let total: u64 = kept.iter().sum();
        for wear in row["wear"].as_array().unwrap() {
            let a_star = wear["a_star_px"].as_f64().unwrap();
            let above: Vec<u64> = kept
                .iter()
                .copied()
                .filter(|&a| a as f64 > a_star)
                .collect();
            let k = above.len() as f64 / kept.len() as f64;
            let kk = above.iter().sum::<u64>() as f64 / total as f64;
            assert_eq!(
                wear["k_archard"].as_f64().unwrap(),
                k,
                "map {m}, A* {a_star}"
            );
            assert!((wear["k_upscaled"].as_f64().unwrap() - kk).abs() <= 1e-15);
        }
        // The plateau's end lies within the sample, its cut-off is the largest cluster.
        let plateau = &row["plateau"];
        let a_s = plateau["a_s_px"].as_f64().unwrap();
        assert_eq!(
            plateau["a_m_px"].as_u64().unwrap(),
            *kept.iter().max().unwrap()
        );
        assert!(
            a_s >= 1.0 && a_s < plateau["a_m_px"].as_f64().unwrap(),
            "{plateau}"
        );
        let (low, high) = (
            plateau["profile_ci95_low"].as_f64().unwrap(),
            plateau["profile_ci95_high"].as_f64().unwrap(),
        );
        assert!(
            low < plateau["alpha"].as_f64().unwrap() && plateau["alpha"].as_f64().unwrap() < high
        );
    }
    let out = run_in(
        dir.path(),
        &["clusters", "--contact", "maps.npy", "--out", "clusters.csv"],
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--out clusters.csv"));
    assert!(!dir.path().join("clusters.csv").exists());
}
