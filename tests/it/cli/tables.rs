use crate::{run_in, stdout_json};

use super::*;

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
