use crate::{run_in, stdout_json};

use super::*;

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
