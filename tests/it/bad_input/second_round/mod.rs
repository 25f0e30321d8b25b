//! The second hostile round, on what came with measured maps: `wear`, `topography`, a
//! `measured` study's files, `submit` and `campaign.sh`. Each class of defect has its
//! rows: data loss, wrong answers, aborts and hangs, silent accepts, unclear messages.

use std::path::Path;
use std::process::Command;

use super::{case, check, Case};
use crate::repo_root;

mod solved;

/// The options of `wear` every row shares, the map's units included.
pub(super) const UNITS: &str = "--height-unit um --pixel-size 1";
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

pub(super) fn npy(dir: &Path, name: &str, rows: usize, cols: usize, values: Vec<f64>) {
    wearcoef::io::write_f64(&dir.join(name), &[rows, cols], values).unwrap();
}

/// The measured inputs of this round's rows.
pub(super) fn write_measured_inputs(dir: &Path) {
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

pub(super) fn wear(name: &'static str, args: &str, code: i32, says: &[&'static str]) -> Case {
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

pub(super) fn topography(name: &'static str, args: &str, code: i32, says: &[&'static str]) -> Case {
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
