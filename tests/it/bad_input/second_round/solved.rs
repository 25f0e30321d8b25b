use super::{case, check, Case};
use crate::bin;
use std::path::Path;

use super::*;

/// Output of `wearcoef wear`, read back: the tables of a run that worked.
fn loads_of(dir: &Path) -> polars::prelude::DataFrame {
    crate::table(&dir.join("loads.parquet"))
}

fn run_ok(dir: &Path, args: &str) {
    let out = bin()
        .current_dir(dir)
        .args(args.split_whitespace())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "wearcoef {args}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// What used to be read or solved wrongly now gives the right numbers: decimal commas, an
/// x-y-z list in a .txt, NetCDF integer lengths, heights ×1e±40 (the same contact set as
/// ×1), a 2 × 2 map and the documented extreme loads (written, exit 0).
#[test]
fn measured_inputs_are_read_and_solved_right() {
    use crate::f64s as f64_column;
    let dir = tempfile::tempdir().unwrap();
    write_measured_inputs(dir.path());
    let json = |args: &str| -> serde_json::Value {
        let out = bin()
            .current_dir(dir.path())
            .args(args.split_whitespace())
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{args}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        crate::stdout_json(&out)
    };
    // Decimal commas: 6 × 6 values, the first row read as numbers, not split in two.
    let r = json(&format!(
        "topography --input comma.txt {UNITS} --form none --json"
    ));
    assert_eq!((r["rows"].as_u64(), r["cols"].as_u64()), (Some(6), Some(6)));
    // An x-y-z list named .txt: a 5 × 6 grid of 1 µm pixels (its positions in µm).
    let r = json("topography --input list.txt --height-unit um --json");
    assert_eq!((r["rows"].as_u64(), r["cols"].as_u64()), (Some(5), Some(6)));
    assert_eq!(r["format"], "xyz");
    assert_eq!(r["pixel_size_x_m"].as_f64(), Some(1e-6));
    // NetCDF: an int32 `length` of 32 µm over 32 points.
    let r = json("topography --input intlen.nc --json");
    assert_eq!(r["pixel_size_x_m"].as_f64(), Some(1e-6));
    // The same map at three scales: the same contact, pressures scaled exactly.
    for (name, scale) in [("rough", 1.0), ("rough_e40", 1e40), ("rough_e-40", 1e-40)] {
        run_ok(
            dir.path(),
            &format!("wear {WEAR} --input {name}.npy --loads 0.01,0.1 -o {name}"),
        );
        let loads = loads_of(&dir.path().join(name));
        let reference = loads_of(&dir.path().join("rough"));
        for column in ["area_fraction", "k_archard", "k_upscaled"] {
            assert_eq!(
                f64_column(&loads, column),
                f64_column(&reference, column),
                "{name} {column}"
            );
        }
        let (p, p0) = (
            f64_column(&loads, "mean_pressure_pa"),
            f64_column(&reference, "mean_pressure_pa"),
        );
        for (a, b) in p.iter().zip(&p0) {
            assert!(
                ((a / scale) / b - 1.0).abs() < 1e-12,
                "{name}: {a} against {b}"
            );
        }
    }
    // A 2 × 2 map and the extreme loads: tables and page written, exit 0.
    run_ok(
        dir.path(),
        &format!("wear {WEAR} --input two.npy --loads 0.01,1 -o two"),
    );
    run_ok(
        dir.path(),
        &format!("wear {WEAR} --input rough.npy --loads 1e-12,100 -o extreme"),
    );
    for out in ["two", "extreme"] {
        for file in [
            "loads.parquet",
            "clusters.parquet",
            "wear.png",
            "index.html",
        ] {
            assert!(dir.path().join(out).join(file).is_file(), "{out}/{file}");
        }
    }
    let full = loads_of(&dir.path().join("extreme"));
    assert_eq!(
        f64_column(&full, "area_fraction")[1],
        1.0,
        "W/W0 = 100 is full contact"
    );
}

/// Loads given as forces or as mean nominal pressures are the same loads as W/W0: the forces
/// and pressures of a W/W0 run, given back with their units, give W/W0 to 1e-12 and the same
/// contact; loads out of order or of an unknown unit are refused before any work.
#[test]
fn loads_as_forces_and_pressures() {
    use crate::f64s as f64_column;
    let dir = tempfile::tempdir().unwrap();
    write_measured_inputs(dir.path());
    run_ok(
        dir.path(),
        &format!("wear {WEAR} --input rough.npy --loads 0.01,0.1 -o ratio"),
    );
    let reference = loads_of(&dir.path().join("ratio"));
    let (forces, pressures) = (
        f64_column(&reference, "force_n"),
        f64_column(&reference, "mean_pressure_pa"),
    );
    let as_given = |values: &[f64], unit: &str| {
        values
            .iter()
            .map(|v| format!("{v:e}{unit}"))
            .collect::<Vec<_>>()
            .join(",")
    };
    for (name, loads, column, values) in [
        ("force", as_given(&forces, "N"), "force_n", &forces),
        (
            "pressure",
            as_given(&pressures, "Pa"),
            "mean_pressure_pa",
            &pressures,
        ),
    ] {
        run_ok(
            dir.path(),
            &format!("wear {WEAR} --input rough.npy --loads {loads} -o {name}"),
        );
        let got = loads_of(&dir.path().join(name));
        for (a, b) in f64_column(&got, "w_over_w0").iter().zip([0.01, 0.1]) {
            assert!((a / b - 1.0).abs() < 1e-12, "{name}: W/W0 {a} against {b}");
        }
        for (a, b) in f64_column(&got, column).iter().zip(values.iter()) {
            assert!(
                (a / b - 1.0).abs() < 1e-12,
                "{name}: {column} {a} against {b}"
            );
        }
        assert_eq!(
            f64_column(&got, "area_fraction"),
            f64_column(&reference, "area_fraction"),
            "{name}"
        );
    }
    for (loads, said) in [
        ("0.1,0.01", "give the loads ascending"),
        ("5kg", "a force (0.5N; N, kN, mN, uN)"),
        ("1e9N", "N on this map, W0 = "),
    ] {
        let out = bin()
            .current_dir(dir.path())
            .args(
                format!("wear {WEAR} --input rough.npy --loads {loads} -o bad").split_whitespace(),
            )
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{loads}: {err}");
        assert!(err.contains(said), "{loads}: {err}");
        assert!(
            !dir.path().join("bad").exists(),
            "{loads}: output left behind"
        );
    }
}

/// Two `wear` runs into one new directory: one lands whole, the other fails and leaves it
/// as the first wrote it (never a mixture, never both exit 0).
#[test]
fn two_runs_into_one_directory_never_mix() {
    let dir = tempfile::tempdir().unwrap();
    write_measured_inputs(dir.path());
    let start = |loads: &str| {
        bin()
            .current_dir(dir.path())
            .args(
                format!("wear {WEAR} --input rough.npy --loads {loads} -o out").split_whitespace(),
            )
            .output()
    };
    let (a, b) = std::thread::scope(|s| {
        let a = s.spawn(|| start("0.01"));
        let b = s.spawn(|| start("0.01,0.02,0.05"));
        (a.join().unwrap().unwrap(), b.join().unwrap().unwrap())
    });
    let codes = (a.status.success(), b.status.success());
    let n = loads_of(&dir.path().join("out")).height();
    match codes {
        (true, false) => assert_eq!(n, 1),
        (false, true) => assert_eq!(n, 3),
        _ => panic!(
            "exactly one run must land: {codes:?}; {} / {}",
            String::from_utf8_lossy(&a.stderr),
            String::from_utf8_lossy(&b.stderr)
        ),
    }
    let loser = if codes.0 { &b } else { &a };
    let stderr = String::from_utf8_lossy(&loser.stderr);
    assert!(
        stderr.contains("filled by another process") || stderr.contains("exists and is not empty"),
        "{stderr}"
    );
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().contains(".tmp-"))
        .collect();
    assert!(left.is_empty(), "staging left behind: {left:?}");
}

/// A measured study's pipeline, its files named as given.
fn measured_pipeline(files: &str, preparation: &str, extra: &str) -> String {
    format!(
        "schema_version: 1\nmaterial: {{e_star: 1.0}}\nsolver: {{tolerance: 1.0e-10, max_iterations: 5000}}\n\
         profiles: {{t: \"test\"}}\nstudies:\n  m:\n    description: \"m\"\n    measured:\n      \
         files: {files}\n      lambda_s_over_dl: 8\n      preparation: {preparation}\n    \
         loads: {{min: 0.005, max: 0.1, count: 3}}\n{extra}    profiles:\n      t: {{}}\nfigures: {{}}\n"
    )
}

fn study(
    name: &'static str,
    files: &str,
    prep: &str,
    args: &str,
    code: i32,
    says: &[&'static str],
) -> Case {
    Case {
        pipeline: Some(measured_pipeline(files, prep, "")),
        prepare: Some(write_measured_inputs),
        ..case(name, args, code, says)
    }
}

/// A measured study's files and preparation are checked when the plan is made: nothing is
/// recorded under failed/ as if the solver had failed, and no input is ever overwritten.
#[test]
fn measured_studies_are_checked_when_the_plan_is_made() {
    let units = "{height_unit: um, pixel_size: 1}";
    let cases = [
        study(
            "a file listed twice",
            "[rough.npy, ./rough.npy]",
            units,
            "plan --profile t",
            2,
            &[
                "studies.m.measured.files[1]",
                "holds the same bytes as studies.m.measured.files[0]",
            ],
        ),
        study(
            "a negative pixel size",
            "[rough.npy]",
            "{height_unit: um, pixel_size: -1}",
            "run --profile t",
            2,
            &[
                "studies.m.measured.files[0]",
                "pixel_size: -1",
                "[1e-15, 1] m",
            ],
        ),
        study(
            "pixels 100 times longer than wide",
            "[rough.npy]",
            "{height_unit: um, pixel_size: 1, pixel_size_y: 100}",
            "run --profile t",
            2,
            &["studies.m.measured.files[0]", "100 times longer than wide"],
        ),
        study(
            "a device",
            "[/dev/zero]",
            units,
            "plan --profile t",
            2,
            &["studies.m.measured.files[0]", "is a device"],
        ),
        study(
            "a flat map",
            "[tilt.npy]",
            units,
            "run --profile t",
            2,
            &[
                "studies.m.measured.files[0]",
                "flat once its plane is removed",
            ],
        ),
        study(
            "plan --out onto a measured file",
            "[rough.npy]",
            units,
            "plan --profile t --out rough.npy",
            2,
            &["--out rough.npy", "studies.m.measured.files[0] reads"],
        ),
        // ok.npy (a smooth egg-box) exists before the run that makes the store.
        Case {
            before: vec!["run --profile t"],
            ..study(
                "catalog -o onto a measured file",
                "[ok.npy]",
                units,
                "catalog --profile t -o ./ok.npy",
                2,
                &["--output ./ok.npy", "studies.m.measured.files[0] reads"],
            )
        },
        Case {
            pipeline: Some(measured_pipeline("[rough.npy]", units, "")),
            prepare: Some(write_measured_inputs),
            ..case(
                "submit --qos with a quote",
                "submit --profile t --dry-run --qos \"",
                2,
                &["--qos", "a Slurm name"],
            )
        },
        Case {
            pipeline: Some(measured_pipeline("[rough.npy]", units, "")),
            prepare: Some(write_measured_inputs),
            ..case(
                "submit --account $(id)",
                "submit --profile t --dry-run --account $(id)",
                2,
                &["--account \"$(id)\"", "a Slurm name"],
            )
        },
        Case {
            pipeline: Some(measured_pipeline("[rough.npy]", units, "")),
            prepare: Some(write_measured_inputs),
            ..case(
                "submit --memory-safety 1e20",
                "submit --profile t --dry-run --memory-safety 1e20",
                2,
                &["--memory-safety 1e20", "[1, 100]"],
            )
        },
    ];
    for c in &cases {
        check(c);
    }
    // `hardness: .inf` is elastic, as documented: the same keys as no hardness.
    let dir = tempfile::tempdir().unwrap();
    write_measured_inputs(dir.path());
    let plan = |extra: &str| {
        std::fs::write(
            dir.path().join("pipeline.yaml"),
            measured_pipeline("[rough.npy]", units, extra),
        )
        .unwrap();
        let out = bin()
            .current_dir(dir.path())
            .args(["plan", "--profile", "t", "--json"])
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        crate::stdout_json(&out)["instances"].clone()
    };
    assert_eq!(plan("    hardness: .inf\n"), plan(""));
}
