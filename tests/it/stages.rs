//! The clusters and statistics stages against independent recomputations from the
//! stored contact maps and cluster tables.

use std::collections::BTreeMap;
use std::path::Path;

use polars::prelude::*;
use wearcoef::clusters::Connectivity;
use wearcoef::statistics::OMEGA;

use crate::{run_in, small_pipeline, workdir};

fn read(path: &Path) -> DataFrame {
    ParquetReader::new(std::fs::File::open(path).unwrap())
        .finish()
        .unwrap()
}

fn f64s(df: &DataFrame, name: &str) -> Vec<f64> {
    df.column(name)
        .unwrap()
        .f64()
        .unwrap()
        .iter()
        .map(|v| v.unwrap_or(f64::NAN))
        .collect()
}

fn u64s(df: &DataFrame, name: &str) -> Vec<u64> {
    let c = df.column(name).unwrap().cast(&DataType::UInt64).unwrap();
    c.u64().unwrap().iter().map(|v| v.unwrap()).collect()
}

fn manifest(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("manifest.json")).unwrap()).unwrap()
}

fn entries(root: &Path, stage: &str) -> Vec<std::path::PathBuf> {
    let mut v: Vec<_> = std::fs::read_dir(root.join("data/cache").join(stage))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| !p.file_name().unwrap().to_string_lossy().starts_with('.'))
        .collect();
    v.sort();
    v
}

/// The two-study test pipeline, built.
fn built_small_pipeline() -> (tempfile::TempDir, std::path::PathBuf) {
    let (t, dir) = workdir(&small_pipeline(0.8, "x"));
    let out = run_in(&dir, &["run", "--profile", "t", "--quiet"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    (t, dir)
}

#[test]
fn cluster_tables_match_the_contact_maps_and_statistics_match_the_tables() {
    let (_t, dir) = built_small_pipeline();

    // Clusters: each table equals a breadth-first search on the stored contact maps, and
    // the areas add up to the solver's contact pixel counts.
    let mut areas_by_key: BTreeMap<String, Vec<Vec<u64>>> = BTreeMap::new();
    let mut n_grid = 0;
    for entry in entries(&dir, "clusters") {
        let m = manifest(&entry);
        let contact = dir
            .join("data/cache/contact")
            .join(m["inputs"][0].as_str().unwrap());
        let contact_loads = read(&contact.join("loads.parquet"));
        let n_contact = u64s(&contact_loads, "n_contact_px");
        let table = read(&entry.join("clusters.parquet"));
        let load_index = u64s(&table, "load_index");
        let area = u64s(&table, "area_px");
        let mut per_load = vec![Vec::new(); n_contact.len()];
        for (l, a) in load_index.iter().zip(&area) {
            per_load[*l as usize].push(*a);
        }
        for (l, areas) in per_load.iter_mut().enumerate() {
            let (rows, cols, map, _) =
                wearcoef::io::read_contact_map(&contact.join(format!("contact_{l:03}.npy")))
                    .unwrap();
            n_grid = rows;
            let (_, reference) = crate::clusters::bfs(&map, rows, cols, Connectivity::Eight);
            let mut expected: Vec<u64> = reference.iter().map(|c| c.area_px).collect();
            expected.sort_unstable();
            areas.sort_unstable();
            assert_eq!(*areas, expected, "{entry:?} load {l}");
            assert_eq!(
                areas.iter().sum::<u64>(),
                n_contact[l],
                "{entry:?} load {l}"
            );
        }
        areas_by_key.insert(
            entry.file_name().unwrap().to_string_lossy().to_string(),
            per_load,
        );
    }

    // Statistics: recompute K, 𝒦, the wear rate and A_c from the tables.
    for entry in entries(&dir, "statistics") {
        let m = manifest(&entry);
        let keys: Vec<String> = m["inputs"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_str().unwrap().to_string())
            .collect();
        let lambda_s = m["params"]["lambda_s_px"].as_f64().unwrap();
        let ls2 = lambda_s * lambda_s;
        let pixels = (n_grid * n_grid) as f64;
        let samples: Vec<&Vec<Vec<u64>>> = keys.iter().map(|k| &areas_by_key[k]).collect();
        let wear = read(&entry.join("wear.parquet"));
        let li = u64s(&wear, "load_index");
        let a_star = f64s(&wear, "a_star_over_ls2");
        let k_pooled = f64s(&wear, "k_archard_pooled");
        let kk_pooled = f64s(&wear, "k_upscaled_pooled");
        let k_mean = f64s(&wear, "k_archard_mean");
        let rate = f64s(&wear, "wear_rate_over_l2_mean");
        assert!(!li.is_empty());
        for i in 0..li.len() {
            let l = li[i] as usize;
            let threshold = a_star[i] * ls2;
            let pooled: Vec<u64> = samples.iter().flat_map(|s| s[l].iter().copied()).collect();
            let above: Vec<u64> = pooled
                .iter()
                .copied()
                .filter(|&a| a as f64 > threshold)
                .collect();
            let k = above.len() as f64 / pooled.len() as f64;
            let kk = above.iter().sum::<u64>() as f64 / pooled.iter().sum::<u64>() as f64;
            assert!((k_pooled[i] - k).abs() < 1e-15, "K at row {i}");
            assert!((kk_pooled[i] - kk).abs() < 1e-15, "𝒦 at row {i}");
            let per: Vec<(f64, f64)> = samples
                .iter()
                .map(|s| {
                    let a = &s[l];
                    let up: Vec<u64> = a
                        .iter()
                        .copied()
                        .filter(|&x| x as f64 > threshold)
                        .collect();
                    (
                        if a.is_empty() {
                            0.0
                        } else {
                            up.len() as f64 / a.len() as f64
                        },
                        OMEGA * up.iter().sum::<u64>() as f64 / pixels,
                    )
                })
                .collect();
            let n = per.len() as f64;
            assert!((k_mean[i] - per.iter().map(|p| p.0).sum::<f64>() / n).abs() < 1e-15);
            assert!((rate[i] - per.iter().map(|p| p.1).sum::<f64>() / n).abs() < 1e-15);
        }
        // Contact area and the PDF's normalisation (per λ_s², bins of `width_px` integers).
        let loads = read(&entry.join("loads.parquet"));
        let fraction = f64s(&loads, "area_fraction_mean");
        for (l, f) in fraction.iter().enumerate() {
            let expected = samples
                .iter()
                .map(|s| s[l].iter().sum::<u64>() as f64 / pixels)
                .sum::<f64>()
                / samples.len() as f64;
            assert!((f - expected).abs() < 1e-15);
        }
        let pdf = read(&entry.join("pdf.parquet"));
        let pl = u64s(&pdf, "load_index");
        let dens = f64s(&pdf, "pdf_pooled");
        let width = u64s(&pdf, "width_px");
        let mut mass = vec![0.0; fraction.len()];
        for i in 0..pl.len() {
            mass[pl[i] as usize] += dens[i] * width[i] as f64 / ls2;
        }
        for (l, m) in mass.iter().enumerate() {
            let any = samples.iter().any(|s| !s[l].is_empty());
            if any {
                assert!((m - 1.0).abs() < 1e-12, "PDF mass at load {l}: {m}");
            }
        }
        // CCDF: pooled steps and the mean of the realizations' own CCDFs.
        let ccdf = read(&entry.join("ccdf.parquet"));
        let cl = u64s(&ccdf, "load_index");
        let ca = u64s(&ccdf, "area_px");
        let cp = f64s(&ccdf, "ccdf");
        let cm = f64s(&ccdf, "ccdf_mean");
        let creal = ccdf.column("realization").unwrap().u32().unwrap().clone();
        let mut pooled_rows = 0;
        for i in 0..ccdf.height() {
            if creal.get(i).is_some() {
                continue;
            }
            pooled_rows += 1;
            let (l, a) = (cl[i] as usize, ca[i]);
            let pooled: Vec<u64> = samples.iter().flat_map(|s| s[l].iter().copied()).collect();
            let above = pooled.iter().filter(|&&x| x > a).count() as f64;
            assert!((cp[i] - above / pooled.len() as f64).abs() < 1e-15);
            let per: Vec<f64> = samples
                .iter()
                .filter(|s| !s[l].is_empty())
                .map(|s| s[l].iter().filter(|&&x| x > a).count() as f64 / s[l].len() as f64)
                .collect();
            let mean = per.iter().sum::<f64>() / per.len() as f64;
            assert!((cm[i] - mean).abs() < 1e-15, "CCDF mean at row {i}");
        }
        assert!(pooled_rows > 0);
        // Every exponent row names its estimator; a missing fit says why.
        let alpha = read(&entry.join("alpha.parquet"));
        let est = alpha.column("estimator").unwrap().str().unwrap().clone();
        let note = alpha.column("note").unwrap().str().unwrap().clone();
        let values = alpha.column("alpha").unwrap().f64().unwrap().clone();
        for i in 0..alpha.height() {
            assert!(est.get(i).unwrap().ends_with("_mle"));
            match values.get(i) {
                Some(a) => assert!(a.is_finite()),
                None => assert!(note.get(i).unwrap().starts_with("no fit:")),
            }
        }
    }
}

#[test]
fn analytic_stage_evaluates_the_fitted_model_and_the_fig6_curves() {
    let (_t, dir) = built_small_pipeline();
    let mut fitted_files = 0;
    for entry in entries(&dir, "analytic") {
        let m = manifest(&entry);
        if entry.join("fig6.parquet").exists() {
            // A_m → ∞ rows against the limits of VALIDATION.md §6.6 (α = 1.5 < 2: 𝒦 → 1).
            let df = read(&entry.join("fig6.parquet"));
            let s = f64s(&df, "a_star_over_a_s");
            let am = f64s(&df, "a_m_over_a_s");
            let k = f64s(&df, "k_pl");
            let kk = f64s(&df, "k_upscaled_pl");
            let mut limits = 0;
            for i in 0..df.height() {
                assert!((0.0..=1.0).contains(&k[i]) && kk[i] >= k[i] - 1e-15);
                if am[i].is_infinite() {
                    let want = if s[i] <= 1.0 {
                        1.0 - (0.5 / 1.5) * s[i]
                    } else {
                        s[i].powf(-0.5) / 1.5
                    };
                    assert!((k[i] - want).abs() < 1e-14, "K limit at A*/A_s = {}", s[i]);
                    assert_eq!(kk[i], 1.0);
                    limits += 1;
                }
            }
            assert_eq!(limits, 5);
            continue;
        }
        fitted_files += 1;
        // The fitted parameters are the statistics stage's p_PL fit, load by load.
        let stats = dir
            .join("data/cache/statistics")
            .join(m["inputs"][0].as_str().unwrap())
            .join("alpha.parquet");
        let alpha = read(&stats);
        let est = alpha.column("estimator").unwrap().str().unwrap().clone();
        let fit_alpha = alpha.column("alpha").unwrap().f64().unwrap().clone();
        let fit_load = u64s(&alpha, "load_index");
        let model = read(&entry.join("model.parquet"));
        let ml = u64s(&model, "load_index");
        let ma = model.column("alpha").unwrap().f64().unwrap().clone();
        let k = model.column("k_pl").unwrap().f64().unwrap().clone();
        let kk = model
            .column("k_upscaled_pl")
            .unwrap()
            .f64()
            .unwrap()
            .clone();
        for (i, &load) in ml.iter().enumerate() {
            let row = (0..alpha.height())
                .find(|&j| {
                    fit_load[j] == load && est.get(j) == Some("discrete_plateau_power_law_mle")
                })
                .unwrap();
            assert_eq!(ma.get(i), fit_alpha.get(row));
            if let (Some(k), Some(kk)) = (k.get(i), kk.get(i)) {
                assert!((0.0..=1.0).contains(&k) && kk >= k - 1e-15);
            } else {
                assert!(
                    fit_alpha.get(row).is_none(),
                    "a fitted load must have a model"
                );
            }
        }
    }
    assert_eq!(fitted_files, 2);
}

/// The plateau of K is the model's `A_m → ∞` limit (A.3) at the fitted α and A_s of the
/// largest load up to W/W₀ = 0.06, the area–load slope is the least-squares κ of the mean
/// areas, and the report shows both.
#[test]
fn analytic_stage_gives_the_plateau_of_k_and_the_area_load_slope() {
    // The test pipeline with Fig. 2 (whose report shows κ) declared too.
    let text = small_pipeline(0.8, "x").replace(
        "figures:\n",
        "figures:\n  fig2: {kind: fig2, study: a, loads: [0.01, 0.02], profiles: [t]}\n",
    );
    assert!(text.contains("kind: fig2"));
    let (_t, dir) = workdir(&text);
    let out = run_in(&dir, &["run", "--profile", "t", "--quiet"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut checked = 0;
    for entry in entries(&dir, "analytic") {
        if entry.join("fig6.parquet").exists() {
            continue;
        }
        let m = manifest(&entry);
        let stats = dir
            .join("data/cache/statistics")
            .join(m["inputs"][0].as_str().unwrap());
        // κ by hand from the per-load table.
        let loads = read(&stats.join("loads.parquet"));
        let (w, a) = (
            f64s(&loads, "w_over_w0"),
            f64s(&loads, "area_fraction_mean"),
        );
        let (mut wa, mut ww) = (0.0, 0.0);
        for i in 0..w.len() {
            if w[i] <= 0.06 {
                wa += w[i] * a[i];
                ww += w[i] * w[i];
            }
        }
        let slope = &m["results"]["area_load_slope"];
        let kappa = slope["kappa"].as_f64().unwrap();
        assert!((kappa - wa / ww).abs() <= 1e-12 * kappa, "{slope}");
        // Its band needs the realizations' intervals: none below 5 realizations.
        let realizations = loads.column("realizations").unwrap().u32().unwrap().get(0);
        match slope["kappa_ci95_correlated"].as_f64() {
            Some(band) => assert!(band > 0.0 && realizations >= Some(5), "{slope}"),
            None => assert!(realizations < Some(5), "{slope}"),
        }
        // The plateau from the alpha table's fit at the recorded load; none when no load up
        // to 0.06 has a fit (these small studies: too few clusters), and then no rows.
        let alpha = read(&stats.join("alpha.parquet"));
        let plateau = read(&entry.join("plateau.parquet"));
        let Some(at) = m["results"]["plateau_w_over_w0"].as_f64() else {
            let (a, w) = (f64s(&alpha, "alpha"), f64s(&alpha, "w_over_w0"));
            assert!(a.iter().zip(&w).all(|(a, w)| a.is_nan() || *w > 0.06));
            assert_eq!(plateau.height(), 0);
            checked += 1;
            continue;
        };
        assert!(at <= 0.06);
        let est = alpha.column("estimator").unwrap().str().unwrap().clone();
        let (aw, al, ks) = (
            f64s(&alpha, "w_over_w0"),
            f64s(&alpha, "alpha"),
            f64s(&alpha, "k_s_px"),
        );
        let row = (0..alpha.height())
            .find(|&j| aw[j] == at && est.get(j) == Some("discrete_plateau_power_law_mle"))
            .unwrap();
        // Every fitted load above it lies beyond 0.06.
        assert!((0..alpha.height()).all(|j| {
            est.get(j) != Some("discrete_plateau_power_law_mle")
                || !al[j].is_finite()
                || aw[j] <= at
                || aw[j] > 0.06
        }));
        let (a_star, lim, at_load) = (
            f64s(&plateau, "a_star_over_ls2"),
            f64s(&plateau, "k_pl_plateau"),
            f64s(&plateau, "k_pl_at_load"),
        );
        assert!(!a_star.is_empty());
        let lambda_s_px = m["job"]["lambda_s_px"].as_f64().unwrap();
        let (alpha, a_s) = (al[row], ks[row]);
        for i in 0..a_star.len() {
            let r = a_star[i] * lambda_s_px * lambda_s_px / a_s;
            let want = if r <= 1.0 {
                1.0 - (alpha - 1.0) / alpha * r
            } else {
                r.powf(1.0 - alpha) / alpha
            };
            assert!((lim[i] - want).abs() < 1e-12, "A*/λs² = {}", a_star[i]);
            // A finite cut-off removes tail: K at the load's A_m is below the limit.
            assert!(at_load[i] <= lim[i] + 1e-12);
        }
        checked += 1;
    }
    assert_eq!(checked, 2);
    let page = std::fs::read_to_string(dir.join("figures/t/index.html")).unwrap();
    assert!(
        page.contains("Area–load slope") && page.contains("κ = "),
        "{page}"
    );
}

/// Width and height from a PNG's IHDR chunk (after the 8-byte signature).
fn png_size(bytes: &[u8]) -> (u32, u32) {
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "not a PNG");
    assert_eq!(&bytes[12..16], b"IHDR");
    let be = |b: &[u8]| u32::from_be_bytes([b[0], b[1], b[2], b[3]]);
    (be(&bytes[16..20]), be(&bytes[20..24]))
}

/// The text elements of an SVG: (text, font size).
fn svg_texts(svg: &str) -> Vec<(String, f64)> {
    let mut out = Vec::new();
    let mut rest = svg;
    while let Some(i) = rest.find("<text") {
        let tag_end = i + rest[i..].find('>').unwrap();
        let tag = &rest[i..tag_end];
        let size = tag
            .split("font-size=\"")
            .nth(1)
            .and_then(|s| s.split('"').next())
            .and_then(|s| s.parse().ok())
            .unwrap_or(0.0);
        let end = tag_end + rest[tag_end..].find("</text>").unwrap();
        let text = rest[tag_end + 1..end]
            .trim()
            .replace("&lt;", "<")
            .replace("&gt;", ">")
            .replace("&amp;", "&");
        out.push((text, size));
        rest = &rest[end..];
    }
    out
}

#[test]
fn figures_are_valid_images_with_their_data_copied_beside_the_data_directory() {
    let (_t, dir) = built_small_pipeline();
    let out = dir.join("figures/t");
    let png = std::fs::read(out.join("fig6.png")).unwrap();
    // 6.4 × 4.8 in at 150 dpi.
    assert_eq!(png_size(&png), (960, 720));
    let svg = std::fs::read_to_string(out.join("fig6.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    // The axis label "A_m/A_s" drawn with its subscripts as separate, smaller text.
    let texts = svg_texts(&svg);
    let at = texts.iter().position(|t| t.0 == "A").expect("label 'A'");
    assert_eq!(texts[at + 1].0, "m");
    assert!(texts[at + 1].1 < texts[at].1, "subscript smaller");
    // Every label of every figure: no markup left and no e-notation.
    let mut svgs = 0;
    for entry in std::fs::read_dir(&out).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "svg") {
            svgs += 1;
            for (t, _) in svg_texts(&std::fs::read_to_string(&path).unwrap()) {
                let e_notation = t.as_bytes().windows(3).any(|w| {
                    w[0].is_ascii_digit() && w[1] == b'e' && (w[2] == b'-' || w[2].is_ascii_digit())
                });
                assert!(
                    !t.contains('_') && !t.contains('^') && !e_notation,
                    "{}: label '{t}'",
                    path.display()
                );
            }
        }
    }
    assert!(svgs >= 1, "{svgs} figures");
    // The plotted data: 5 thresholds × 2 coefficients, points with A_m ≥ A* only, one row
    // per point with its curve and axes named.
    let mut csv = csv::Reader::from_path(out.join("fig6.csv")).unwrap();
    let header: Vec<String> = csv.headers().unwrap().iter().map(String::from).collect();
    assert_eq!(header, wearcoef::figures::plot::DATA_COLUMNS);
    let rows: Vec<csv::StringRecord> = csv.records().map(|r| r.unwrap()).collect();
    assert!(rows.len() > 500, "{} rows", rows.len());
    for r in &rows {
        assert!(!r[1].is_empty(), "a row without its curve: {r:?}");
        assert_eq!(&r[5], "Aₘ/Aₛ");
        let y: f64 = r[8].parse().unwrap();
        assert!((0.0..=1.0).contains(&y));
    }
}

/// A convergence figure compares exactly the studies its declaration names: a profile of
/// one exponent with one figure, a profile of two exponents with one figure each (the same
/// sizes at two exponents would otherwise share labels, which then get the study name).
#[test]
#[ignore = "four 256²/512² sweeps, slow in debug builds: run by `make test` in release"]
fn convergence_figures_draw_the_studies_they_declare() {
    let entry = |name: &str, hurst: f64, l: u32, seed: u32, both: bool| {
        let size = format!("{{l_over_lambda_l: {l}, lambda_s_over_dl: 2, realizations: 1}}");
        let mut profiles = format!("      two: {size}\n");
        if both {
            profiles.push_str(&format!("      one: {size}\n"));
        }
        format!(
            "  {name}:\n    hurst: {hurst}\n    lambda_l_over_lambda_s: 128\n    seed: {seed}\n    \
             loads: {{values: [0.06]}}\n    profiles:\n{profiles}"
        )
    };
    let figure = |name: &str, studies: &str, profile: &str| {
        format!("  {name}: {{kind: convergence, studies: [{studies}], profiles: [{profile}]}}\n")
    };
    let text = format!(
        "schema_version: 1\nmaterial: {{e_star: 1.0}}\nsolver: {{tolerance: 1.0e-10, max_iterations: 2000}}\n\
         profiles: {{one: \"H = 0.8\", two: \"H = 0.6 and 0.8\"}}\nstudies:\n{}{}{}{}figures:\n{}{}{}",
        entry("c128_a8", 0.8, 1, 1, true),
        entry("c128_b8", 0.8, 2, 2, true),
        entry("c128_a6", 0.6, 1, 3, false),
        entry("c128_b6", 0.6, 2, 4, false),
        figure("fig128_convergence", "c128_a8, c128_b8", "one"),
        figure("fig128_convergence_h0.8", "c128_a8, c128_b8", "two"),
        figure("fig128_convergence_h0.6", "c128_a6, c128_b6", "two"),
    );
    let (_t, dir) = workdir(&text);
    for profile in ["one", "two"] {
        let out = run_in(&dir, &["run", "--profile", profile, "--quiet"]);
        assert!(
            out.status.success(),
            "{profile}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let drawn = |profile: &str| -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir.join("figures").join(profile))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|f| f.starts_with("fig128") && f.ends_with(".parquet"))
            .collect();
        v.sort();
        v
    };
    assert_eq!(drawn("one"), ["fig128_convergence.parquet"]);
    assert_eq!(
        drawn("two"),
        [
            "fig128_convergence_h0.6.parquet",
            "fig128_convergence_h0.8.parquet"
        ]
    );
    let table = |profile: &str, file: &str| read(&dir.join("figures").join(profile).join(file));
    let one = table("one", "fig128_convergence.parquet");
    let h08 = table("two", "fig128_convergence_h0.8.parquet");
    let h06 = table("two", "fig128_convergence_h0.6.parquet");
    // The H = 0.8 figure of the mixed profile is the single-exponent one.
    // (bitwise: α is NaN where a box holds too few clusters to fit it).
    for column in ["ks_distance", "ks_critical_95", "alpha_difference"] {
        let bits =
            |df: &DataFrame| -> Vec<u64> { f64s(df, column).iter().map(|v| v.to_bits()).collect() };
        assert_eq!(bits(&one), bits(&h08), "{column}");
    }
    assert_eq!(u64s(&one, "n_clusters"), u64s(&h08, "n_clusters"));
    for df in [&h08, &h06] {
        let labels = df.column("study").unwrap().str().unwrap();
        assert!(labels.iter().all(|l| !l.unwrap().contains('[')));
    }
    assert_ne!(
        u64s(&h06, "n_clusters_reference"),
        u64s(&h08, "n_clusters_reference"),
        "the H = 0.6 figure compares the H = 0.6 studies"
    );
}
