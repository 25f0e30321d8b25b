//! Measured maps read from plain files: `.npy` of any 2-D shape in float32 or float64 (C or
//! Fortran order), and text matrices; each bad file refused naming it and what is wrong.

use ndarray::{Array2, ShapeBuilder};
use wearcoef::io::{read_map_npy, read_map_text};

/// A 5 × 7 map with a missing point: row-major values `(r, c) ↦ r − 0.25 c`.
fn expected() -> Vec<f64> {
    let mut v: Vec<f64> = (0..35)
        .map(|i| (i / 7) as f64 - 0.25 * (i % 7) as f64)
        .collect();
    v[9] = f64::NAN;
    v
}

fn same(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(x, y)| x == y || (x.is_nan() && y.is_nan()))
}

#[test]
fn npy_maps_of_any_shape_and_float_type() {
    let dir = tempfile::tempdir().unwrap();
    let want = expected();
    let c64 = Array2::from_shape_vec((5, 7), want.clone()).unwrap();
    let f64_fortran = {
        let mut a = Array2::<f64>::zeros((5, 7).f());
        a.assign(&c64);
        a
    };
    let c32 = c64.mapv(|v| v as f32);
    for (name, write) in [
        (
            "c64.npy",
            Box::new(|p: &std::path::Path| ndarray_npy::write_npy(p, &c64))
                as Box<dyn Fn(&std::path::Path) -> Result<(), ndarray_npy::WriteNpyError>>,
        ),
        (
            "f64.npy",
            Box::new(|p: &std::path::Path| ndarray_npy::write_npy(p, &f64_fortran)),
        ),
        (
            "c32.npy",
            Box::new(|p: &std::path::Path| ndarray_npy::write_npy(p, &c32)),
        ),
    ] {
        let path = dir.path().join(name);
        write(&path).unwrap();
        let (rows, cols, values) = read_map_npy(&path).unwrap();
        assert_eq!((rows, cols), (5, 7), "{name}");
        assert!(same(&values, &want), "{name}: {values:?}");
    }
    // A 3-D array and integers are refused, naming the file and what it holds.
    let cube = dir.path().join("cube.npy");
    ndarray_npy::write_npy(&cube, &ndarray::Array3::<f64>::zeros((2, 3, 4))).unwrap();
    let e = read_map_npy(&cube).unwrap_err().to_string();
    assert!(
        e.contains("cube.npy") && e.contains("shape (2, 3, 4)"),
        "{e}"
    );
    let ints = dir.path().join("ints.npy");
    ndarray_npy::write_npy(&ints, &Array2::<i32>::zeros((3, 3))).unwrap();
    let e = read_map_npy(&ints).unwrap_err().to_string();
    assert!(
        e.contains("ints.npy") && e.contains("not float32 or float64"),
        "{e}"
    );
}

#[test]
fn text_matrices_with_comments_separators_and_missing_points() {
    let dir = tempfile::tempdir().unwrap();
    let want = expected();
    let mut text = String::from("# a profilometer export\n% units: m\n\n");
    for r in 0..5 {
        let row: Vec<String> = (0..7)
            .map(|c| {
                let v = want[r * 7 + c];
                if v.is_nan() {
                    "NaN".to_string()
                } else {
                    format!("{v}")
                }
            })
            .collect();
        // Mixed separators, as exports write them.
        text += &row.join(if r % 2 == 0 { "\t" } else { ", " });
        text += "\n";
    }
    let path = dir.path().join("map.txt");
    std::fs::write(&path, &text).unwrap();
    let (rows, cols, values) = read_map_text(&path).unwrap();
    assert_eq!((rows, cols), (5, 7));
    assert!(same(&values, &want), "{values:?}");
    for (name, body, says) in [
        (
            "ragged.txt",
            "1 2 3\n4 5\n",
            "line 2 has 2 values where the rows before have 3",
        ),
        ("word.txt", "1 2\n3 x\n", "line 2: 'x' is not a number"),
        ("inf.txt", "1 inf\n", "'inf' is not a height"),
        ("empty.txt", "# nothing\n", "holds no heights"),
    ] {
        let path = dir.path().join(name);
        std::fs::write(&path, body).unwrap();
        let e = read_map_text(&path).unwrap_err().to_string();
        assert!(e.contains(name) && e.contains(says), "{name}: {e}");
    }
}

/// `wearcoef topography`: a tilted map in µm with 0.5 µm pixels has its plane removed (the
/// tilt recovered as a slope, the prepared heights in metres), and its rms slope is that of
/// the pattern left; a missing point, or a format not read, is exit 2 naming the file.
#[test]
fn topography_command_states_units_and_removes_the_plane() {
    use crate::{run_in, stdout_json};
    let dir = tempfile::tempdir().unwrap();
    let (rows, cols) = (40, 60);
    // Heights in µm: a tilt of 0.01 µm per pixel in x plus ridges along x, ±0.1 µm in rows
    // of the pattern + − − + (orthogonal to 1, x and y on 40 rows, so the plane fit is the
    // tilt alone).
    let pattern = |r: usize| if matches!(r % 4, 0 | 3) { 0.1 } else { -0.1 };
    let mut map = Array2::<f64>::zeros((rows, cols));
    for ((r, c), v) in map.indexed_iter_mut() {
        *v = 0.01 * c as f64 + pattern(r);
    }
    ndarray_npy::write_npy(dir.path().join("map.npy"), &map).unwrap();
    let out = run_in(
        dir.path(),
        &[
            "topography",
            "--input",
            "map.npy",
            "--height-unit",
            "um",
            "--pixel-size",
            "0.5",
            "-o",
            "prep.npy",
            "--json",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v = stdout_json(&out);
    let slope_x = v["form_coefficients_m"][1].as_f64().unwrap();
    assert!((slope_x - 0.02).abs() < 1e-12, "tilt {slope_x}");
    // Left: the ridges. Of the 39 pairs of rows 0.5 µm apart, 20 differ by 0.2 µm, none
    // along x: rms slope √(20 · 0.4² / 39).
    let rms_slope = v["rms_slope"].as_f64().unwrap();
    let expected = (20.0 * 0.16 / 39.0f64).sqrt();
    assert!(
        (rms_slope - expected).abs() < 1e-9,
        "rms slope {rms_slope} vs {expected}"
    );
    let prepared: Array2<f64> = ndarray_npy::read_npy(dir.path().join("prep.npy")).unwrap();
    assert_eq!(prepared.dim(), (rows, cols));
    assert!(
        (prepared[[0, 0]] - 0.1e-6).abs() < 1e-15,
        "{}",
        prepared[[0, 0]]
    );
    let mut holes = map.clone();
    holes[[3, 4]] = f64::NAN;
    ndarray_npy::write_npy(dir.path().join("holes.npy"), &holes).unwrap();
    std::fs::write(dir.path().join("map.x3p"), b"PK").unwrap();
    for (file, says) in [
        ("holes.npy", "1 of 2400 points are missing"),
        ("map.x3p", "is named .x3p but holds text"),
    ] {
        let out = run_in(
            dir.path(),
            &[
                "topography",
                "--input",
                file,
                "--height-unit",
                "um",
                "--pixel-size",
                "0.5",
            ],
        );
        assert_eq!(out.status.code(), Some(2), "{file}");
        let e = String::from_utf8_lossy(&out.stderr);
        assert!(e.contains(file) && e.contains(says), "{e}");
    }
}

/// `wearcoef wear`: settings without a unit, a map with missing points and no fill rule,
/// and an output directory that is not empty are each an input error (exit 2) naming what
/// to fix, before any work, with nothing written; a valid run fills a new directory (no
/// staging directory of the page left behind), byte for byte the same on 1 and 2 threads.
#[test]
fn wear_refuses_bad_settings_and_writes_nothing() {
    use crate::run_in;
    let dir = tempfile::tempdir().unwrap();
    let (rows, cols) = (30, 40);
    let mut map = Array2::<f64>::zeros((rows, cols));
    for ((r, c), v) in map.indexed_iter_mut() {
        let (x, y) = (c as f64, r as f64);
        *v = 0.05 * ((0.7 * x).sin() + (0.9 * y + 0.3 * x).cos() + (0.31 * x * y).sin());
    }
    ndarray_npy::write_npy(dir.path().join("map.npy"), &map).unwrap();
    map[[4, 5]] = f64::NAN;
    ndarray_npy::write_npy(dir.path().join("holes.npy"), &map).unwrap();
    std::fs::create_dir(dir.path().join("full")).unwrap();
    std::fs::write(dir.path().join("full/keep.txt"), "mine").unwrap();
    let base = |input: &'static str, out: &'static str, e_star: &'static str| {
        vec![
            "wear",
            "--input",
            input,
            "--height-unit",
            "um",
            "--pixel-size",
            "0.5",
            "--e-star",
            e_star,
            "--loads",
            "0.02,0.05",
            "--d-star",
            "1um",
            "-o",
            out,
        ]
    };
    for (args, says) in [
        (
            base("map.npy", "a", "100"),
            "--e-star \"100\": a modulus with its unit",
        ),
        (base("holes.npy", "b", "100GPa"), "--fill harmonic"),
        (base("map.npy", "full", "100GPa"), "exists and is not empty"),
    ] {
        let out = run_in(dir.path(), &args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let e = String::from_utf8_lossy(&out.stderr);
        assert!(e.contains(says), "{e}");
    }
    assert!(!dir.path().join("a").exists() && !dir.path().join("b").exists());
    let kept: Vec<_> = std::fs::read_dir(dir.path().join("full"))
        .unwrap()
        .collect();
    assert_eq!(kept.len(), 1);
    // Two runs, on one thread and on two: the same bytes in every file.
    for (threads, out_dir) in [("1", "c"), ("2", "d")] {
        let mut args = base("map.npy", out_dir, "100GPa");
        args.push("--pressure-maps");
        let out = crate::bin()
            .current_dir(dir.path())
            .env("RAYON_NUM_THREADS", threads)
            .args(&args)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let mut written: Vec<String> = std::fs::read_dir(dir.path().join("c"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    written.sort();
    assert_eq!(
        written,
        [
            "clusters.parquet",
            "index.html",
            "loads.csv",
            "loads.parquet",
            "preparation.json",
            "pressure.npy",
            "psd.parquet",
            "wear.png",
            "wear.svg"
        ]
    );
    for name in &written {
        let read = |d: &str| std::fs::read(dir.path().join(d).join(name)).unwrap();
        assert!(
            read("c") == read("d"),
            "{name} differs between 1 and 2 threads"
        );
    }
}
