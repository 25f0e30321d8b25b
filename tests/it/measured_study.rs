//! A `measured` study in pipeline.yaml: topography files as realizations, through the same
//! stages as a generated spectrum (surface → contact on the free-boundary half-space →
//! clusters without wrap-around → statistics → fig45), keyed by the files' content.

use std::path::Path;

use ndarray::{s, Array2};
use polars::prelude::*;

use super::{f64s, run_in, stdout_json, table};

const LOADS: [f64; 3] = [0.01, 0.03, 0.1];

/// A 100 × 120 map in µm (pixel 0.5 µm, λ_s = 4 px): a corner of a generated surface.
fn write_map(dir: &Path, name: &str, seed: u32) {
    let full = dir.join(format!("full{seed}.npy"));
    let out = run_in(
        dir,
        &[
            "surface",
            "--n",
            "128",
            "--lambda-l-px",
            "64",
            "--lambda-s-px",
            "4",
            "--hurst",
            "0.8",
            "--seed",
            &seed.to_string(),
            "-o",
            full.to_str().unwrap(),
        ],
    );
    assert!(out.status.success(), "{out:?}");
    let heights: Array2<f64> = ndarray_npy::read_npy(&full).unwrap();
    let map = heights.slice(s![..100, ..120]).mapv(|h| 0.5 * h);
    ndarray_npy::write_npy(dir.join(name), &map).unwrap();
}

fn pipeline(files: &str, extra: &str, figure_kind: &str) -> String {
    format!(
        r#"schema_version: 1
material: {{e_star: 1.0}}
solver: {{tolerance: 1.0e-10, max_iterations: 5000}}
profiles: {{m: "measured"}}
studies:
  rough:
{extra}    measured:
      files: [{files}]
      lambda_s_over_dl: 4
      preparation: {{height_unit: um, pixel_size: 0.5}}
    loads: {{values: [0.01, 0.03, 0.1]}}
    profiles: {{m: {{}}}}
figures:
  k:
    kind: {figure_kind}
    profiles: [m]
"#
    )
}

/// `wearcoef run --profile m` in `d`, into `d/data` and `d/figs`.
fn run_m(d: &Path) -> std::process::Output {
    run_in(
        d,
        &[
            "run",
            "--profile",
            "m",
            "--data",
            "data",
            "--figures",
            "figs",
        ],
    )
}

/// The single entry of `stage` in the store (the study has one of each but surfaces and
/// sweeps).
fn entries(data: &Path, stage: &str) -> Vec<std::path::PathBuf> {
    let mut v: Vec<_> = std::fs::read_dir(data.join("cache").join(stage))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| !p.file_name().unwrap().to_string_lossy().starts_with('.'))
        .collect();
    v.sort();
    v
}

fn surface_keys(dir: &Path) -> Vec<String> {
    let out = run_in(dir, &["plan", "--profile", "m", "--json"]);
    assert!(out.status.success(), "{out:?}");
    let plan = stdout_json(&out);
    plan["instances"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|i| i["stage"] == "surface")
        .map(|i| i["key"].as_str().unwrap().to_string())
        .collect()
}

/// One file through the pipeline gives, load by load, the K, 𝒦, contact fraction and cluster
/// count that `wearcoef wear` gives on the same file (A* = 2 λ_s² = 8 µm²): two paths to one
/// number, which agree bit for bit. Clusters carry `touches_edge`, the maps are the file's
/// shape, and fig45 is drawn.
#[test]
fn measured_study_agrees_with_wear_on_the_same_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::create_dir(d.join("maps")).unwrap();
    write_map(d, "maps/one.npy", 3);
    std::fs::write(
        d.join("pipeline.yaml"),
        pipeline("maps/one.npy", "", "fig45\n    study: rough"),
    )
    .unwrap();
    let out = run_m(d);
    assert!(out.status.success(), "{out:?}");
    for f in ["fig4b.png", "fig5a.svg", "fig5b.csv", "index.html"] {
        assert!(d.join("figs/m").join(f).is_file(), "{f}");
    }
    let data = d.join("data");
    let surface = &entries(&data, "surface")[0];
    assert!(surface.join("topography.npy").is_file() && surface.join("psd.parquet").is_file());
    let contact = &entries(&data, "contact")[0];
    let (rows, cols, _, _) =
        wearcoef::io::read_contact_map(&contact.join("contact_000.npy")).unwrap();
    assert_eq!((rows, cols), (100, 120));
    let clusters = table(&entries(&data, "clusters")[0].join("clusters.parquet"));
    let edge = clusters.column("touches_edge").unwrap().bool().unwrap();
    assert!(
        edge.any() && !edge.all(),
        "some clusters touch the border, not all"
    );
    let wear_table = table(&entries(&data, "statistics")[0].join("wear.parquet"));
    let at = wear_table
        .column("a_star_over_ls2")
        .unwrap()
        .f64()
        .unwrap()
        .equal(2.0);
    let ours = wear_table.filter(&at).unwrap();

    let out = run_in(
        d,
        &[
            "wear",
            "--input",
            "maps/one.npy",
            "--height-unit",
            "um",
            "--pixel-size",
            "0.5",
            "--e-star",
            "1Pa",
            "--loads",
            "0.01,0.03,0.1",
            "--a-star",
            "8um2",
            "-o",
            "w",
        ],
    );
    assert!(out.status.success(), "{out:?}");
    let theirs = table(&d.join("w/loads.parquet"));
    assert_eq!(f64s(&ours, "w_over_w0"), LOADS.to_vec());
    assert_eq!(f64s(&ours, "k_archard_pooled"), f64s(&theirs, "k_archard"));
    assert_eq!(
        f64s(&ours, "k_upscaled_pooled"),
        f64s(&theirs, "k_upscaled")
    );
    let per_load = table(&entries(&data, "clusters")[0].join("loads.parquet"));
    assert_eq!(
        f64s(&per_load, "area_fraction"),
        f64s(&theirs, "area_fraction")
    );
    assert_eq!(f64s(&per_load, "n_clusters"), f64s(&theirs, "n_clusters"));
    assert!(f64s(&ours, "k_archard_pooled")
        .iter()
        .all(|&k| k > 0.0 && k < 1.0));
}

/// The key is the files' content: moving a file keeps every key, changing one height
/// changes its surface's key only, and a file changed after the plan was made is refused.
#[test]
fn measured_files_are_keyed_by_content() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_map(d, "a.npy", 1);
    write_map(d, "b.npy", 2);
    std::fs::write(
        d.join("pipeline.yaml"),
        pipeline("a.npy, b.npy", "", "fig45\n    study: rough"),
    )
    .unwrap();
    let before = surface_keys(d);
    assert_eq!(before.len(), 2);
    std::fs::create_dir(d.join("moved")).unwrap();
    std::fs::rename(d.join("a.npy"), d.join("moved/a2.npy")).unwrap();
    let text = pipeline("moved/a2.npy, b.npy", "", "fig45\n    study: rough");
    std::fs::write(d.join("pipeline.yaml"), &text).unwrap();
    assert_eq!(surface_keys(d), before, "moving a file keeps its key");

    let mut map: Array2<f64> = ndarray_npy::read_npy(d.join("b.npy")).unwrap();
    map[[5, 5]] += 1e-3;
    ndarray_npy::write_npy(d.join("b.npy"), &map).unwrap();
    let after = surface_keys(d);
    assert_eq!(after[0], before[0]);
    assert_ne!(after[1], before[1], "a changed height changes the key");

    let out = run_in(d, &["plan", "--profile", "m", "--out", "plan.json"]);
    assert!(out.status.success(), "{out:?}");
    map[[5, 5]] -= 2e-3;
    ndarray_npy::write_npy(d.join("b.npy"), &map).unwrap();
    let out = run_m(d);
    assert!(out.status.success(), "a run plans anew: {out:?}");
    let out = run_in(d, &["exec", "--plan", "plan.json", "--data", "data2"]);
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && e.contains("changed after the plan was made"),
        "{e}"
    );
}

/// A measured file's warnings name it by its path, not by the hash its stage is keyed by:
/// a map with 10 % of its points missing, filled, warns so when run.
#[test]
fn measured_warnings_name_the_file_by_its_path() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_map(d, "holes.npy", 4);
    let mut map: Array2<f64> = ndarray_npy::read_npy(d.join("holes.npy")).unwrap();
    map.slice_mut(s![20..40, 30..90]).fill(f64::NAN);
    ndarray_npy::write_npy(d.join("holes.npy"), &map).unwrap();
    let text = pipeline("holes.npy", "", "fig45\n    study: rough")
        .replace("pixel_size: 0.5}", "pixel_size: 0.5, fill: harmonic}");
    std::fs::write(d.join("pipeline.yaml"), text).unwrap();
    let out = run_m(d);
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{e}");
    let path = std::path::absolute(d.join("holes.npy")).unwrap();
    assert!(
        e.contains(&format!(
            "warning: {}: 1200 of 12000 points",
            path.display()
        )),
        "{e}"
    );
    assert!(!e.contains("SHA-256"), "{e}");
}

/// A measured study refuses a generated study's fields, a figure other than fig2 or fig45,
/// an empty list, a missing file, a file that needs a unit, a pixel size or a fill rule
/// its preparation does not give, and `resample` (rectangular pixels are solved as
/// measured; only `wear` resamples, when asked), each naming the field, before any work;
/// nothing is written.
#[test]
fn measured_study_errors_name_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_map(d, "a.npy", 1);
    let mut holes: Array2<f64> = ndarray_npy::read_npy(d.join("a.npy")).unwrap();
    for (r, c) in [(3, 4), (50, 60), (99, 119)] {
        holes[[r, c]] = f64::NAN;
    }
    ndarray_npy::write_npy(d.join("holes.npy"), &holes).unwrap();
    for (text, says) in [
        (
            pipeline("a.npy", "    hurst: 0.8\n", "fig45\n    study: rough"),
            "studies.rough.hurst",
        ),
        (
            pipeline(
                "a.npy",
                "",
                "appendix_b1\n    studies: [rough]\n    loads: [0.03]",
            ),
            "only `fig2` and `fig45` figures draw",
        ),
        (
            pipeline("", "", "fig45\n    study: rough"),
            "studies.rough.measured.files",
        ),
        (
            pipeline("gone.npy", "", "fig45\n    study: rough"),
            "studies.rough.measured.files[0]",
        ),
        (
            pipeline("a.npy", "", "fig45\n    study: rough").replace(
                "{height_unit: um, pixel_size: 0.5}",
                "{pixel_size: 0.5, pixel_unit: um}",
            ),
            "set studies.rough.measured.preparation.height_unit",
        ),
        (
            pipeline("a.npy", "", "fig45\n    study: rough")
                .replace("{height_unit: um, pixel_size: 0.5}", "{height_unit: um}"),
            "set studies.rough.measured.preparation.pixel_size",
        ),
        (
            pipeline("holes.npy", "", "fig45\n    study: rough"),
            "3 of 12000 points are missing: set studies.rough.measured.preparation.fill",
        ),
        (
            pipeline("a.npy", "", "fig45\n    study: rough")
                .replace("pixel_size: 0.5}", "pixel_size: 0.5, resample: true}"),
            "unknown field `resample`",
        ),
    ] {
        std::fs::write(d.join("pipeline.yaml"), &text).unwrap();
        let out = run_m(d);
        let e = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{text}\n{e}");
        assert!(e.contains(says), "{says}: {e}");
        assert!(!d.join("data/cache").exists(), "{text}");
    }
}

/// The repository's own measured study (two X3P files written by SurfaceTopography) runs
/// from pipeline.yaml: its plane is removed, its 10 missing points per file filled, and its
/// figures drawn.
#[test]
fn the_repositorys_measured_example_runs() {
    let dir = tempfile::tempdir().unwrap();
    let config = super::repo_root().join("pipeline.yaml");
    let out = run_in(
        dir.path(),
        &[
            "run",
            "--profile",
            "measured",
            "--config",
            config.to_str().unwrap(),
            "--data",
            "data",
            "--figures",
            "figs",
        ],
    );
    assert!(out.status.success(), "{out:?}");
    let surfaces = entries(&dir.path().join("data"), "surface");
    assert_eq!(surfaces.len(), 2);
    for s in &surfaces {
        let m: serde_json::Value =
            serde_json::from_slice(&std::fs::read(s.join("manifest.json")).unwrap()).unwrap();
        let r = &m["results"];
        assert_eq!(
            (r["rows"].as_u64(), r["cols"].as_u64()),
            (Some(144), Some(192))
        );
        assert_eq!(r["missing_points"], 10);
        assert_eq!(r["filled_points"], 10);
        assert_eq!(r["form_removed"], "plane");
        assert!(s.join("topography.x3p").is_file());
    }
    for f in ["fig2a.png", "fig2d.png", "fig2e.png", "fig4b.png"] {
        assert!(dir.path().join("figs/measured").join(f).is_file(), "{f}");
    }
    // The report describes the measured map, not the generated Fig. 2 surface.
    let report = std::fs::read_to_string(dir.path().join("figs/measured/index.html")).unwrap();
    assert!(report.contains("The measured study's first file as prepared for contact"));
    assert!(!report.contains("One realization of the Fig. 2 surface"));
}

/// Under a hardness, a measured map's saturated maps mark exactly the nodes the solver
/// counts at the ceiling, for moduli E* at which (𝓗·E*)·h'_rms exceeds (𝓗·h'_rms)·E* by
/// rounding on this map (h'_rms = 0.00774): the stage's ceiling is the window's to the bit.
#[test]
fn measured_saturated_maps_match_the_solvers_count() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_map(d, "a.npy", 1);
    for e_star in ["1.2", "2.8", "4.1"] {
        let text = pipeline("a.npy", "    hardness: 0.45\n", "fig45\n    study: rough")
            .replace("e_star: 1.0", &format!("e_star: {e_star}"))
            .replace("values: [0.01, 0.03, 0.1]", "values: [0.05, 0.2]");
        std::fs::write(d.join("pipeline.yaml"), text).unwrap();
        let _ = std::fs::remove_dir_all(d.join("data"));
        let out = run_m(d);
        assert!(out.status.success(), "{out:?}");
        let contact = &entries(&d.join("data"), "contact")[0];
        let counted = f64s(&table(&contact.join("loads.parquet")), "n_saturated_px");
        for (i, &n) in counted.iter().enumerate() {
            let path = contact.join(format!("saturated_{i:03}.npy"));
            let (_, _, map, _) = wearcoef::io::read_contact_map(&path).unwrap();
            let marked = map.iter().filter(|&&b| b).count() as f64;
            assert!(n > 0.0, "E* = {e_star}, load {i}: nothing saturated");
            assert_eq!(marked, n, "E* = {e_star}, load {i}");
        }
    }
}
