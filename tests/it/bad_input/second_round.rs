//! The second hostile round, on what came with measured maps: `wear`, `topography`, a
//! `measured` study's files, `submit` and `campaign.sh`. Each class of defect has its
//! rows: data loss, wrong answers, aborts and hangs, silent accepts, unclear messages.

use std::path::Path;
use std::process::Command;

use super::{case, check, Case};
use crate::{bin, repo_root};

/// The options of `wear` every row shares, the map's units included.
const UNITS: &str = "--height-unit um --pixel-size 1";
const WEAR: &str = "--height-unit um --pixel-size 1 --e-star 1GPa --d-star 2um";

/// A rough 32 × 32 map (µm), scaled by `scale`.
fn rough(scale: f64) -> Vec<f64> {
    let n = 32;
    (0..n * n)
        .map(|i| {
            let (r, c) = ((i / n) as f64, (i % n) as f64);
            let k = std::f64::consts::TAU / 8.0;
            // A deterministic, non-periodic texture: two egg-boxes and a quadratic chirp.
            scale * ((k * r).cos() + (k * c).cos() + 0.3 * (0.37 * r * r + 0.71 * c).sin())
        })
        .collect()
}

fn npy(dir: &Path, name: &str, rows: usize, cols: usize, values: Vec<f64>) {
    wearcoef::io::write_f64(&dir.join(name), &[rows, cols], values).unwrap();
}

/// The measured inputs of this round's rows.
fn write_measured_inputs(dir: &Path) {
    npy(dir, "rough.npy", 32, 32, rough(1.0));
    npy(dir, "rough_e40.npy", 32, 32, rough(1e40));
    npy(dir, "rough_e-40.npy", 32, 32, rough(1e-40));
    npy(dir, "two.npy", 2, 2, vec![0.0, 1.0, 0.5, 0.2]);
    // A tilted plane: flat once the plane is removed.
    let tilt = (0..32 * 32)
        .map(|i| 0.01 * (i % 32) as f64 + 0.02 * (i / 32) as f64)
        .collect();
    npy(dir, "tilt.npy", 32, 32, tilt);
    let mut holes = rough(1.0);
    holes
        .iter_mut()
        .take(32 * 32 - 100)
        .for_each(|h| *h = f64::NAN);
    npy(dir, "holes.npy", 32, 32, holes);
    // Decimal commas between tabs.
    let comma: String = (0..6)
        .map(|r| {
            (0..6)
                .map(|c| format!("{:.4}", rough(1.0)[r * 32 + c]).replace('.', ","))
                .collect::<Vec<_>>()
                .join("\t")
                + "\n"
        })
        .collect();
    std::fs::write(dir.join("comma.txt"), comma).unwrap();
    let scan: String = (0..40)
        .map(|i| format!("{} {}\n", i as f64 * 0.1, (i as f64).sin()))
        .collect();
    std::fs::write(dir.join("scan.txt"), scan).unwrap();
    let xyz = |shift: f64| -> String {
        (0..5)
            .flat_map(|r| (0..6).map(move |c| (r, c)))
            .map(|(r, c)| {
                let x = c as f64 + if (r, c) == (3, 3) { shift } else { 0.0 };
                format!("{x} {r} {}\n", rough(1.0)[r * 32 + c])
            })
            .collect()
    };
    std::fs::write(dir.join("list.txt"), xyz(0.0)).unwrap();
    std::fs::write(dir.join("offgrid.xyz"), xyz(0.45)).unwrap();
    std::fs::write(
        dir.join("lie.sdf"),
        "aISO-1.0\nManufacID = x\nNumPoints = 4000000000\nNumProfiles = 4000000000\n\
         Xscale = 1e-6\nYscale = 1e-6\nZscale = 1e-6\nDataType = 7\n*\n1 2 3 4\n*\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("intlen.nc"),
        netcdf(&[(4, 32i32.to_be_bytes().to_vec())]),
    )
    .unwrap();
    std::fs::write(
        dir.join("neglen.nc"),
        netcdf(&[(6, (-3f64).to_be_bytes().to_vec())]),
    )
    .unwrap();
    let mut lie = netcdf(&[]);
    lie[24..28].copy_from_slice(&1_000_000_000u32.to_be_bytes());
    std::fs::write(dir.join("lie.nc"), lie).unwrap();
    let mut dims = netcdf(&[]);
    dims[12..16].copy_from_slice(&0x7fff_ffffu32.to_be_bytes());
    std::fs::write(dir.join("dims.nc"), dims).unwrap();
    x3p_bomb(&dir.join("bomb.x3p"), 4, 4, 64 << 20);
    x3p_bomb(&dir.join("huge.x3p"), 100_000, 100_000, 1024);
    std::os::unix::fs::symlink("/dev/zero", dir.join("zero.txt")).unwrap();
}

/// A NetCDF 3 map as SurfaceTopography lays it out: dimensions x (32) and y (32), the
/// variables x and y carrying `unit` (µm) and the given `length` attribute (type, bytes) on
/// both, and `heights` (float64, µm).
fn netcdf(length: &[(u32, Vec<u8>)]) -> Vec<u8> {
    let mut b = Vec::new();
    let name = |b: &mut Vec<u8>, s: &str| {
        b.extend((s.len() as u32).to_be_bytes());
        b.extend(s.as_bytes());
        b.resize(b.len().next_multiple_of(4), 0);
    };
    b.extend(b"CDF\x01");
    b.extend(0u32.to_be_bytes());
    b.extend(0x0Au32.to_be_bytes());
    b.extend(2u32.to_be_bytes());
    for d in ["x", "y"] {
        name(&mut b, d);
        b.extend(32u32.to_be_bytes());
    }
    b.extend([0u8; 8]);
    b.extend(0x0Bu32.to_be_bytes());
    b.extend(3u32.to_be_bytes());
    let mut offsets = Vec::new();
    let attrs = |b: &mut Vec<u8>| {
        b.extend(0x0Cu32.to_be_bytes());
        b.extend((1 + length.len() as u32).to_be_bytes());
        name(b, "unit");
        b.extend(2u32.to_be_bytes());
        b.extend(2u32.to_be_bytes());
        b.extend(b"um\0\0");
        for (t, raw) in length {
            name(b, "length");
            b.extend(t.to_be_bytes());
            b.extend(1u32.to_be_bytes());
            b.extend(raw);
            b.resize(b.len().next_multiple_of(4), 0);
        }
    };
    for (var, dim) in [("x", 0u32), ("y", 1)] {
        name(&mut b, var);
        b.extend(1u32.to_be_bytes());
        b.extend(dim.to_be_bytes());
        attrs(&mut b);
        b.extend(6u32.to_be_bytes());
        b.extend((32u32 * 8).to_be_bytes());
        offsets.push(b.len());
        b.extend(0u32.to_be_bytes());
    }
    name(&mut b, "heights");
    b.extend(2u32.to_be_bytes());
    b.extend(0u32.to_be_bytes());
    b.extend(1u32.to_be_bytes());
    attrs(&mut b);
    b.extend(6u32.to_be_bytes());
    b.extend((32u32 * 32 * 8).to_be_bytes());
    offsets.push(b.len());
    b.extend(0u32.to_be_bytes());
    let map = rough(1.0);
    for (k, at) in offsets.iter().enumerate() {
        let start = b.len() as u32;
        b[*at..at + 4].copy_from_slice(&start.to_be_bytes());
        if k < 2 {
            (0..32).for_each(|i| b.extend((i as f64).to_be_bytes()));
        } else {
            // x slowest: heights[x][y] = map[y][x].
            for x in 0..32 {
                for y in 0..32 {
                    b.extend(map[y * 32 + x].to_be_bytes());
                }
            }
        }
    }
    b
}

/// An X3P archive whose main.xml states `cols × rows` float64 points and whose data member
/// inflates to `bytes` zeros.
fn x3p_bomb(path: &Path, cols: usize, rows: usize, bytes: usize) {
    use std::io::Write;
    let xml = format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?><p:ISO5436_2 xmlns:p=\"http://www.opengps.eu/2008/ISO5436_2\">\
         <Record1><Revision>ISO5436 - 2000</Revision><FeatureType>SUR</FeatureType><Axes>\
         <CX><AxisType>I</AxisType><DataType>D</DataType><Increment>1e-6</Increment><Offset>0</Offset></CX>\
         <CY><AxisType>I</AxisType><DataType>D</DataType><Increment>1e-6</Increment><Offset>0</Offset></CY>\
         <CZ><AxisType>A</AxisType><DataType>D</DataType></CZ></Axes></Record1><Record3><MatrixDimension>\
         <SizeX>{cols}</SizeX><SizeY>{rows}</SizeY><SizeZ>1</SizeZ></MatrixDimension><DataLink>\
         <PointDataLink>bindata/data.bin</PointDataLink></DataLink></Record3></p:ISO5436_2>"
    );
    let mut zip = zip::ZipWriter::new(std::fs::File::create(path).unwrap());
    let deflate = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated)
        .large_file(true);
    zip.start_file("main.xml", deflate).unwrap();
    zip.write_all(xml.as_bytes()).unwrap();
    zip.start_file("bindata/data.bin", deflate).unwrap();
    let chunk = vec![0u8; 1 << 20];
    for _ in 0..bytes.div_ceil(1 << 20) {
        zip.write_all(&chunk[..(1 << 20).min(bytes)]).unwrap();
    }
    zip.finish().unwrap();
}

fn wear(name: &'static str, args: &str, code: i32, says: &[&'static str]) -> Case {
    Case {
        prepare: Some(write_measured_inputs),
        ..case(name, &format!("wear {WEAR} {args}"), code, says)
    }
}

/// A row whose command is given whole, with this round's inputs.
fn topography_like(name: &'static str, args: &str, code: i32, says: &[&'static str]) -> Case {
    Case {
        prepare: Some(write_measured_inputs),
        ..case(name, args, code, says)
    }
}

fn topography(name: &'static str, args: &str, code: i32, says: &[&'static str]) -> Case {
    Case {
        prepare: Some(write_measured_inputs),
        ..case(name, &format!("topography {args}"), code, says)
    }
}

/// Wrong answers that are now refused, each naming what the file or value is.
#[test]
fn measured_inputs_that_would_give_wrong_answers_are_refused() {
    let cases = [
        wear(
            "flat once the plane is removed",
            "--input tilt.npy --loads 0.01 -o out",
            2,
            &["tilt.npy", "flat once its plane is removed"],
        ),
        topography(
            "a line scan in a .txt",
            &format!("--input scan.txt {UNITS}"),
            2,
            &["scan.txt", "a line scan (x, z): 40 points"],
        ),
        topography_like(
            "E* that underflows the force",
            &format!(
                "wear {UNITS} --d-star 2um --input rough.npy --loads 0.01 -o out --e-star 1e-320Pa"
            ),
            2,
            &["--e-star", "[1, 1e13] Pa"],
        ),
        wear(
            "one resample",
            "--input rough.npy --loads 0.01 -o out --resamples 1",
            2,
            &["--resamples 1", "[40, 100000]"],
        ),
        topography(
            "negative NetCDF length",
            "--input neglen.nc",
            2,
            &["neglen.nc", "variable 'x' has length = -3"],
        ),
        topography(
            "x-y-z point off its grid",
            "--input offgrid.xyz --height-unit um",
            2,
            &["offgrid.xyz", "0.450 of a pixel off the grid"],
        ),
        wear(
            "a fill that invents the map",
            "--input holes.npy --fill harmonic --loads 0.1 -o out",
            2,
            &["holes.npy", "924 of 1024 points (90.2 %)", "crop the map"],
        ),
        wear(
            "load above the solver's range",
            "--input rough.npy --loads 101 -o out",
            2,
            &["--loads (value 1) 101", "[1e-12, 100]"],
        ),
        wear(
            "load above the hardness, in the user's units",
            "--input rough.npy --loads 0.5 --hardness 0.1GPa -o out",
            2,
            &[
                "--loads 0.5",
                "above --hardness 1e8 Pa",
                "lower the load below W/W0 =",
            ],
        ),
        wear(
            "a 300-digit hardness",
            &format!(
                "--input rough.npy --loads 0.5 --hardness 1{}GPa -o out",
                "0".repeat(300)
            ),
            2,
            &["--hardness", "must be finite"],
        ),
    ];
    for c in &cases {
        check(c);
    }
}

/// Headers that lie about their size, devices and zip bombs: exit 2 before allocating or
/// reading what they claim, also on a machine told to be small.
#[test]
fn lying_headers_devices_and_bombs_are_refused_before_allocating() {
    let small = vec![("WEARCOEF_MEMORY_BYTES", "200000000")];
    let cases = [
        topography(
            "NetCDF dimension count",
            "--input dims.nc",
            2,
            &["dims.nc", "2147483647 dimensions"],
        ),
        topography(
            "NetCDF dimension length",
            "--input lie.nc",
            2,
            &["lie.nc", "the header promises 32000000000 values"],
        ),
        topography(
            "text SDF size",
            "--input lie.sdf",
            2,
            &["lie.sdf", "the header promises 16000000000000000000 values"],
        ),
        Case {
            env: small.clone(),
            ..topography(
                "X3P zip bomb",
                "--input bomb.x3p",
                2,
                &["bomb.x3p", "holds more than", "zip bomb"],
            )
        },
        Case {
            env: small.clone(),
            ..topography(
                "X3P beyond memory",
                "--input huge.x3p",
                2,
                &[
                    "huge.x3p",
                    "100000 × 100000 points",
                    "WEARCOEF_MEMORY_BYTES",
                ],
            )
        },
        topography(
            "a device named .txt",
            &format!("--input zero.txt {UNITS}"),
            2,
            &["zero.txt", "is a device, not a regular file"],
        ),
        wear(
            "no resamples",
            "--input rough.npy --loads 0.01 -o out --resamples 0",
            2,
            &["--resamples 0"],
        ),
        wear(
            "ten billion resamples",
            "--input rough.npy --loads 0.01 -o out --resamples 10000000000",
            2,
            &["--resamples 1e10"],
        ),
    ];
    for c in &cases {
        check(c);
    }
}

/// Messages in the user's words: no Rust debug values, no list that contradicts itself.
#[test]
fn messages_speak_the_users_words() {
    let cases = [
        Case {
            never: vec!["ParseHeader", "IOErrorKind", "Err(", "Some("],
            ..topography("NetCDF error", "--input lie.nc", 2, &["lie.nc"])
        },
        Case {
            never: vec![", .npy,", ".npy (", "text matrix (.txt"],
            ..topography(
                "a .npy states no unit",
                "--input rough.npy",
                2,
                &["states no height unit", "Files that state theirs: .x3p"],
            )
        },
    ];
    for c in &cases {
        check(c);
    }
}

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

/// `campaign.sh`: bad arguments create nothing; a run.pid whose pid now belongs to another
/// process is not that process, and `stop` leaves it running.
#[test]
fn campaign_script_checks_arguments_and_process_identity() {
    let root = tempfile::tempdir().unwrap();
    let campaigns = root.path().join("campaigns");
    let script = repo_root().join("scripts/campaign.sh");
    let run = |args: &[&str]| {
        Command::new("bash")
            .arg(&script)
            .args(args)
            .env("WEARCOEF_CAMPAIGNS", &campaigns)
            .output()
            .unwrap()
    };
    for args in [
        &["start", "../outside"][..],
        &["stop", "nosuch"],
        &["bogus"],
        &["status", "a/b"],
    ] {
        let out = run(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        assert!(
            !campaigns.exists(),
            "{args:?} created {}",
            campaigns.display()
        );
        assert!(!root.path().join("outside").exists());
    }
    // A stale run.pid, old style (a pid alone) and new (pid, start time, binary), both
    // naming a process that is not the campaign.
    let mut other = Command::new("sleep").arg("60").spawn().unwrap();
    let dir = campaigns.join("quick");
    std::fs::create_dir_all(&dir).unwrap();
    let stat = std::fs::read_to_string(format!("/proc/{}/stat", other.id())).unwrap();
    let start = stat
        .rsplit_once(") ")
        .unwrap()
        .1
        .split(' ')
        .nth(19)
        .unwrap()
        .to_string();
    for pidfile in [
        format!("{}\n", other.id()),
        format!(
            "{} {start} {}/bin/wearcoef-0123456789ab\n",
            other.id(),
            dir.display()
        ),
    ] {
        std::fs::write(dir.join("run.pid"), &pidfile).unwrap();
        let out = run(&["stop", "quick"]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(String::from_utf8_lossy(&out.stdout).contains("not running"));
        assert!(
            other.try_wait().unwrap().is_none(),
            "{pidfile:?}: the other process was killed"
        );
    }
    other.kill().unwrap();
    other.wait().unwrap();
}
