//! `wearcoef wear`: one measured topography file to its wear coefficients. The map is read
//! and prepared (`topography`), pressed on the free-boundary half-space at each load W/W0
//! (`contact::window`), its contact clusters labelled without wrap-around, and per load the
//! counted K (eq. 5), 𝒦 (eq. 7), the wear rate (eq. 6) and α̂ are written in physical units
//! beside the dimensionless ones.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use polars::prelude::{DataFrame, ParquetWriter};
use serde_json::json;
use wearcoef::clusters::{self, Boundary, Connectivity};
use wearcoef::contact::solver::SolverConfig;
use wearcoef::contact::window::sweep_window;
use wearcoef::statistics::{wear_at, OMEGA};
use wearcoef::store::table::col;

use super::topography::{prepare, FillArg, PrepareArgs, Prepared};
use super::InputError;

#[derive(clap::Args)]
pub struct WearArgs {
    #[command(flatten)]
    pub prepare: PrepareArgs,
    /// The effective modulus E* = E/(1 − ν²) of the pair, with its unit: `210GPa`,
    /// `7e10Pa`, `500MPa`.
    #[arg(long)]
    pub e_star: String,
    /// The loads, comma separated, ascending: dimensionless W/W0 (`0.01,0.1`), with W0 =
    /// E*·rms slope·A and A the map's area; or forces (`0.5N,2N`; mN, uN, µN, kN); or mean
    /// nominal pressures on the map (`10MPa`; Pa, kPa, MPa, GPa). Each load is written as
    /// W/W0, in newtons and in pascals.
    #[arg(long, value_delimiter = ',', required = true)]
    pub loads: Vec<String>,
    /// The critical junction area A* with its unit (`2um2`, `1.5e-12m2`, `3000nm2`), or
    /// give --d-star.
    #[arg(long, conflicts_with = "d_star")]
    pub a_star: Option<String>,
    /// The critical length d* with its unit (`1.2um`): A* = π d*²/4.
    #[arg(long)]
    pub d_star: Option<String>,
    /// A hardness (pressure with its unit, `3GPa`): the pressure is capped at it
    /// (perfectly plastic junctions). Absent: elastic.
    #[arg(long)]
    pub hardness: Option<String>,
    /// The solver's relative tolerance.
    #[arg(long, default_value_t = 1e-8)]
    pub tolerance: f64,
    /// The trust band's factors on d* (comma separated, low then high): K and 𝒦 are also
    /// given at A* for d* times each (`k_archard_d_star_low`, `…_high`).
    #[arg(long, value_delimiter = ',', default_value = "0.5,2")]
    pub d_star_factors: Vec<f64>,
    /// Skip the trust band's solves (the map coarsened ×2, its two halves and four quarters:
    /// 2.25 times the map's nodes in all); its edge and d* columns are still written.
    #[arg(long)]
    pub no_trust_band: bool,
    /// Bootstrap resamples of α̂'s interval.
    #[arg(long, default_value_t = 200)]
    pub resamples: usize,
    /// Also write the contact pressure of every load: pressure.npy, float64 in Pa, shape
    /// (loads, rows, cols).
    #[arg(long)]
    pub pressure_maps: bool,
    /// The output directory (created; if it exists it must be empty).
    #[arg(short, long)]
    pub out: PathBuf,
}

/// `text` split into its number and its unit (both trimmed): the unit starts at the first
/// character that cannot be part of a number.
fn number_and_unit(text: &str) -> (&str, &str) {
    let t = text.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || matches!(c, '.' | 'e' | 'E' | '+' | '-')))
        .unwrap_or(t.len());
    (t[..split].trim(), t[split..].trim())
}

/// A value with a unit: `number` then one of `units` (name, factor to SI), spaces allowed.
fn quantity(
    option: &str,
    text: &str,
    units: &[(&str, f64)],
    what: &str,
) -> Result<f64, InputError> {
    let (number, unit) = number_and_unit(text);
    let names: Vec<&str> = units.iter().map(|(n, _)| *n).collect();
    let shown: String = text.chars().take(40).collect();
    let ellipsis = if text.chars().count() > 40 { "…" } else { "" };
    let bad = || {
        InputError(format!(
            "{option} {shown:?}{ellipsis}: {what} with its unit, one of {}",
            names.join(", ")
        ))
    };
    let value: f64 = number.parse().map_err(|_| bad())?;
    let factor = units
        .iter()
        .find(|(n, _)| *n == unit)
        .map(|(_, f)| *f)
        .ok_or_else(bad)?;
    let si = value * factor;
    if !(si.is_finite() && si > 0.0) {
        return Err(InputError(format!(
            "{option} {shown:?}{ellipsis}: must be finite and > 0"
        )));
    }
    Ok(si)
}

const PRESSURE: &[(&str, f64)] = &[("Pa", 1.0), ("kPa", 1e3), ("MPa", 1e6), ("GPa", 1e9)];
const FORCE: &[(&str, f64)] = &[
    ("N", 1.0),
    ("kN", 1e3),
    ("mN", 1e-3),
    ("uN", 1e-6),
    ("µN", 1e-6),
];

/// A load as given: dimensionless, a force, or a mean nominal pressure.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Load {
    Ratio(f64),
    Newtons(f64),
    Pascals(f64),
}

/// The load `text` (the `index`-th of --loads, from 1): a bare number is W/W0; a unit
/// makes it a force or a pressure.
fn load(index: usize, text: &str) -> Result<Load, InputError> {
    let option = format!("--loads (value {index})");
    if let Ok(w) = text.trim().parse::<f64>() {
        return Ok(Load::Ratio(w));
    }
    let (_, unit) = number_and_unit(text);
    if FORCE.iter().any(|(n, _)| *n == unit) {
        quantity(&option, text, FORCE, "a force").map(Load::Newtons)
    } else if PRESSURE.iter().any(|(n, _)| *n == unit) {
        quantity(&option, text, PRESSURE, "a pressure").map(Load::Pascals)
    } else {
        Err(InputError(format!(
            "{option} {text:?}: a load is W/W0 (a bare number, 0.05), a force (0.5N; N, kN, mN, uN) or a mean nominal pressure (10MPa; Pa, kPa, MPa, GPa)"
        )))
    }
}

/// The loads as W/W0 on a map of rms slope `slope` and area `area_m2` under `e_star_pa`
/// (W0 = E*·slope·A, so W/W0 = F/W0 = p/(E*·slope)), checked in range and ascending.
fn loads_over_w0(
    loads: &[Load],
    e_star_pa: f64,
    slope: f64,
    area_m2: f64,
) -> Result<Vec<f64>, InputError> {
    let w0 = e_star_pa * slope * area_m2;
    let ratios: Vec<f64> = loads
        .iter()
        .map(|l| match *l {
            Load::Ratio(w) => w,
            Load::Newtons(f) => f / w0,
            Load::Pascals(p) => p / (e_star_pa * slope),
        })
        .collect();
    let show = wearcoef::ranges::show;
    for (i, (&w, l)) in ratios.iter().zip(loads).enumerate() {
        let given = match *l {
            Load::Ratio(_) => String::new(),
            Load::Newtons(f) => format!(" ({} N on this map, W0 = {} N)", show(f), show(w0)),
            Load::Pascals(p) => format!(
                " ({} Pa on this map, E*·rms slope = {} Pa)",
                show(p),
                show(e_star_pa * slope)
            ),
        };
        wearcoef::ranges::W_OVER_W0
            .check(&format!("--loads (value {}){given}", i + 1), w)
            .map_err(InputError)?;
    }
    if let Some(i) = (1..ratios.len()).find(|&i| ratios[i] <= ratios[i - 1]) {
        return Err(InputError(format!(
            "--loads: value {} (W/W0 = {}) is not above value {i} (W/W0 = {}): give the loads ascending",
            i + 1,
            show(ratios[i]),
            show(ratios[i - 1])
        )));
    }
    Ok(ratios)
}
const LENGTH: &[(&str, f64)] = &[
    ("m", 1.0),
    ("mm", 1e-3),
    ("um", 1e-6),
    ("µm", 1e-6),
    ("nm", 1e-9),
];
const AREA: &[(&str, f64)] = &[
    ("m2", 1.0),
    ("mm2", 1e-6),
    ("um2", 1e-12),
    ("µm2", 1e-12),
    ("µm²", 1e-12),
    ("nm2", 1e-18),
];

/// The output directory, checked before any work: absent (it is created, whole, when the
/// run ends) or an existing empty directory; never anything else.
fn check_output_dir(out: &Path) -> Result<(), InputError> {
    match std::fs::read_dir(out) {
        Ok(mut entries) => {
            if entries.next().is_some() {
                return Err(InputError(format!(
                    "--out {}: exists and is not empty; name a new directory (nothing is overwritten)",
                    out.display()
                )));
            }
            Ok(())
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => super::check_dir("--out", out),
        Err(_) if out.exists() => Err(InputError(format!(
            "--out {}: exists and is not a directory; name a new directory",
            out.display()
        ))),
        Err(e) => Err(InputError(format!("--out {}: {e}", out.display()))),
    }
}

/// Refuse, in the user's units, a load whose mean pressure exceeds the hardness.
fn check_loads_below_hardness(
    loads: &[f64],
    hardness_pa: Option<f64>,
    e_star_pa: f64,
    slope: f64,
) -> Result<(), InputError> {
    let Some(h) = hardness_pa else { return Ok(()) };
    let show = wearcoef::ranges::show;
    for &w in loads {
        let p = w * e_star_pa * slope;
        if p > h {
            return Err(InputError(format!(
                "--loads {}: W/W0 = {} is a mean pressure of {} Pa (W/W0·E*·rms slope, rms slope {}), above --hardness {} Pa: a pressure capped at the hardness cannot carry it; lower the load below W/W0 = {} or raise the hardness",
                show(w), show(w), show(p), show(slope), show(h), show(h / (e_star_pa * slope))
            )));
        }
    }
    Ok(())
}

/// A float64 `.npy` of shape `shape` written one block of values at a time, so that the
/// pressure maps of a sweep are never all in memory.
struct NpyStream {
    file: std::io::BufWriter<std::fs::File>,
}

impl NpyStream {
    fn create(path: &Path, shape: &[usize]) -> std::io::Result<Self> {
        use std::io::Write;
        let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
        let mut dict = format!(
            "{{'descr': '<f8', 'fortran_order': False, 'shape': ({},), }}",
            dims.join(", ")
        );
        // Magic (6), version (2), length (2), the dict and a newline: a multiple of 64.
        while (10 + dict.len() + 1) % 64 != 0 {
            dict.push(' ');
        }
        dict.push('\n');
        let mut file = std::io::BufWriter::new(std::fs::File::create(path)?);
        file.write_all(b"\x93NUMPY\x01\x00")?;
        file.write_all(&(dict.len() as u16).to_le_bytes())?;
        file.write_all(dict.as_bytes())?;
        Ok(NpyStream { file })
    }

    fn push(&mut self, values: &[f64]) -> std::io::Result<()> {
        use std::io::Write;
        for v in values {
            self.file.write_all(&v.to_le_bytes())?;
        }
        Ok(())
    }

    fn finish(mut self) -> std::io::Result<()> {
        use std::io::Write;
        self.file.flush()?;
        self.file.get_ref().sync_all()
    }
}

/// The loads' rows and their clusters.
#[derive(Default)]
struct Tables {
    clusters: super::tools::ClusterRows,
    rows: Vec<serde_json::Value>,
}

/// The physical settings of `wear`, checked: E* (Pa), A* (m²), the hardness (Pa), the
/// loads as given.
fn settings(args: &WearArgs) -> Result<(f64, f64, Option<f64>, Vec<Load>), InputError> {
    let in_range =
        |r: &wearcoef::ranges::Range, option: &str, v: f64| r.check(option, v).map_err(InputError);
    let e_star = quantity("--e-star", &args.e_star, PRESSURE, "a modulus")?;
    in_range(&wearcoef::ranges::E_STAR_PA, "--e-star", e_star)?;
    let a_star_m2 =
        match (&args.a_star, &args.d_star) {
            (Some(a), _) => quantity("--a-star", a, AREA, "an area")?,
            (None, Some(d)) => {
                let d = quantity("--d-star", d, LENGTH, "a length")?;
                std::f64::consts::PI * d * d / 4.0
            }
            (None, None) => return Err(InputError(
                "give the critical junction size: --a-star AREA (2um2) or --d-star LENGTH (1.2um)"
                    .into(),
            )),
        };
    let hardness_pa = args
        .hardness
        .as_deref()
        .map(|h| quantity("--hardness", h, PRESSURE, "a hardness"))
        .transpose()?;
    if let Some(h) = hardness_pa {
        in_range(&wearcoef::ranges::HARDNESS_PA, "--hardness", h)?;
    }
    let loads = args
        .loads
        .iter()
        .enumerate()
        .map(|(i, t)| load(i + 1, t))
        .collect::<Result<Vec<_>, _>>()?;
    for (i, l) in loads.iter().enumerate() {
        if let Load::Ratio(w) = *l {
            in_range(
                &wearcoef::ranges::W_OVER_W0,
                &format!("--loads (value {})", i + 1),
                w,
            )?;
        }
    }
    in_range(&wearcoef::ranges::TOLERANCE, "--tolerance", args.tolerance)?;
    match args.d_star_factors[..] {
        [low, high] if low > 0.0 && low < high && high.is_finite() => {}
        _ => {
            return Err(InputError(format!(
                "--d-star-factors {:?}: two factors on d*, low then high, both > 0 (0.5,2 halves and doubles it)",
                args.d_star_factors
            )))
        }
    }
    wearcoef::ranges::RESAMPLES
        .check_count("--resamples", args.resamples as u64)
        .map_err(InputError)?;
    Ok((e_star, a_star_m2, hardness_pa, loads))
}

/// Refuse, before any work, a map whose solve needs more memory than the machine has.
fn check_wear_memory(map: &wearcoef::topography::Topography) -> Result<(), InputError> {
    // Measured: 126 MB peak for a 1000 × 750 map (square side 1000, padded 2000²), about
    // 120 bytes per node of the square; 160 leaves room for the tables.
    let side = map.rows.max(map.cols).next_multiple_of(2) as u64;
    super::check_memory(
        &format!(
            "the contact of a {} × {} map (solved in a square of {side}², padded to {}²)",
            map.rows,
            map.cols,
            2 * side
        ),
        160 * side * side,
        "crop or downsample the map",
    )
}

pub fn wear(args: WearArgs) -> anyhow::Result<ExitCode> {
    if args.prepare.preparation.fill == FillArg::Keep {
        return Err(InputError(
            "--fill keep: contact needs every height; choose --fill harmonic or none".into(),
        )
        .into());
    }
    let (e_star, a_star_m2, hardness_pa, given_loads) = settings(&args)?;
    check_output_dir(&args.out)?;
    let Prepared {
        map,
        mut report,
        psd,
    } = prepare(&args.prepare)?;
    check_wear_memory(&map)?;
    let (slope, loads) = map_loads(&map, &given_loads, e_star, hardness_pa)?;
    // Everything is written into a staging directory, moved onto --out when complete.
    let staged = wearcoef::io::atomic::StagedDir::new(&args.out)?;
    let dir = staged.path().to_path_buf();
    let pixel_m2 = map.dx * map.dy;
    let area_m2 = (map.rows * map.cols) as f64 * pixel_m2;
    let a_star_px = a_star_m2 / pixel_m2;
    let hardness = hardness_pa.map(|h| h / (e_star * slope));
    let cfg = SolverConfig {
        tolerance: args.tolerance,
        ..SolverConfig::default()
    };
    let area_scales = (
        args.d_star_factors[0].powi(2),
        args.d_star_factors[1].powi(2),
    );
    let bar = load_bar(loads.len());
    let mut tables = Tables::default();
    let (rows, cols) = (map.rows, map.cols);
    let mut pressures = match args.pressure_maps {
        true => Some(NpyStream::create(
            &dir.join("pressure.npy"),
            &[loads.len(), rows, cols],
        )?),
        false => None,
    };
    let (layout, _) = sweep_window(&map, e_star, &loads, &cfg, hardness, |i, p, r| {
        if let Some(stream) = pressures.as_mut() {
            stream.push(p).map_err(|e| {
                wearcoef::io::cannot_write(&args.out.join("pressure.npy"), &e.to_string())
            })?;
        }
        let contact: Vec<bool> = p.iter().map(|&v| v > 0.0).collect();
        let labelling =
            clusters::label_with(&contact, rows, cols, Connectivity::Eight, Boundary::Open)
                .map_err(|e| e.to_string())?;
        let areas: Vec<u64> = labelling.clusters.iter().map(|c| c.area_px).collect();
        let cut = labelling.touching_border();
        let touching = cut.iter().filter(|&&t| t).count();
        tables.clusters.push(i, &labelling);
        let m = wear_at(&areas, a_star_px);
        let fit = super::fit::fit_row(Some(i as u32), r.w_over_w0, &areas, 0, args.resamples, 0);
        let band = super::trust::edge_and_d_star(&areas, &cut, a_star_px, area_scales);
        let mut row = json!({
            "w_over_w0": r.w_over_w0,
            "force_n": r.w_over_w0 * e_star * slope * area_m2,
            "mean_pressure_pa": r.mean_pressure,
            "real_contact_area_um2": r.n_contact_px as f64 * pixel_m2 * 1e12,
            "area_fraction": r.area_fraction,
            "n_clusters": areas.len(),
            "n_clusters_touching_edge": touching,
            "largest_cluster_um2": areas.iter().max().copied().unwrap_or(0) as f64 * pixel_m2 * 1e12,
            "k_archard": m.k_archard,
            "k_upscaled": m.k_upscaled,
            "wear_rate_mm3_per_m": OMEGA * m.area_above_px * pixel_m2 * 1e9,
            "alpha": fit["alpha"], "alpha_ci95_low": fit["bootstrap_ci95_low"],
            "alpha_ci95_high": fit["bootstrap_ci95_high"],
            "alpha_plateau": fit["plateau"]["alpha"],
            "alpha_plateau_ci95_low": fit["plateau"]["profile_ci95_low"],
            "alpha_plateau_ci95_high": fit["plateau"]["profile_ci95_high"],
            "n_saturated_px": r.n_saturated_px,
            "iterations": r.report.iterations,
            "solver_error": r.report.error,
        });
        for (k, v) in band.as_object().expect("an object") {
            row[k] = v.clone();
        }
        tables.rows.push(row);
        bar.inc(1);
        Ok(())
    })?;
    bar.finish_and_clear();
    report["trust_band"] = super::trust::band(
        &map,
        &loads,
        slope,
        super::trust::Physics {
            e_star_pa: e_star,
            hardness_pa,
            a_star_m2,
            cfg,
        },
        &args.d_star_factors,
        !args.no_trust_band,
        &mut tables.rows,
    );
    report["contact"] = json!({
        "half_space": "free boundary (zero-padded), the map's outside never in contact",
        "e_star_pa": e_star, "hardness_pa": hardness_pa, "hardness_w_over_w0": hardness,
        "tolerance": args.tolerance, "layout": layout,
        "w0_n": e_star * slope * area_m2, "map_area_um2": area_m2 * 1e12,
        "a_star_um2": a_star_m2 * 1e12, "a_star_px": a_star_px,
        "clusters": "8-connected, no wrap-around; touches_edge marks clusters cut by the map's border",
        "program": wearcoef::store::table::program(),
    });
    pressures.map(NpyStream::finish).transpose()?;
    let drawn = write_run(&dir, tables, &report, &psd, pixel_m2, loads.len())?;
    staged.commit()?;
    if !drawn {
        return Ok(ExitCode::FAILURE);
    }
    say_written(loads.len(), rows, cols, &args.out)?;
    Ok(ExitCode::SUCCESS)
}

/// The map's rms slope and the loads as W/W0 on it, checked below the hardness.
fn map_loads(
    map: &wearcoef::topography::Topography,
    given: &[Load],
    e_star: f64,
    hardness_pa: Option<f64>,
) -> Result<(f64, Vec<f64>), InputError> {
    let slope = map.rms_slope();
    let area_m2 = (map.rows * map.cols) as f64 * map.dx * map.dy;
    let loads = loads_over_w0(given, e_star, slope, area_m2)?;
    check_loads_below_hardness(&loads, hardness_pa, e_star, slope)?;
    Ok((slope, loads))
}

/// The contact sweep's progress bar over `loads` loads.
fn load_bar(loads: usize) -> indicatif::ProgressBar {
    indicatif::ProgressBar::new(loads as u64).with_style(
        indicatif::ProgressStyle::with_template("contact {bar:30} {pos}/{len} loads, {elapsed}")
            .expect("a valid template"),
    )
}

/// The line that says what was written where.
fn say_written(loads: usize, rows: usize, cols: usize, out: &Path) -> anyhow::Result<()> {
    out!(
        "{} on a {rows} × {cols} map written to {} (index.html, loads.parquet, loads.csv, clusters.parquet, psd.parquet, preparation.json)",
        match loads {
            1 => "1 load".to_string(),
            n => format!("{n} loads"),
        },
        out.display()
    )?;
    Ok(())
}

/// The tables, then the page, into the staging directory `dir`. The tables are kept
/// whatever the page does: a page that cannot be drawn is a warning (and `Ok(false)`).
fn write_run(
    dir: &Path,
    tables: Tables,
    report: &serde_json::Value,
    psd: &[wearcoef::psd::PsdBin],
    pixel_m2: f64,
    loads: usize,
) -> anyhow::Result<bool> {
    let mut areas_um2 = vec![Vec::new(); loads];
    for (&i, &a) in tables.clusters.maps().iter().zip(tables.clusters.areas()) {
        areas_um2[i as usize].push(a as f64 * pixel_m2 * 1e12);
    }
    let rows_of_page = tables.rows.clone();
    let page = super::wear_page::Page {
        rows: &rows_of_page,
        areas_um2,
        psd,
        report,
    };
    let psd_table = wearcoef::stages::surface::psd_table(psd)?;
    write_outputs(dir, tables, report, psd_table, pixel_m2)?;
    let drawn = super::wear_page::write(&page, dir);
    if let Err(e) = &drawn {
        wearcoef::note!(
            "warning: the page (wear.png, wear.svg, index.html) could not be drawn: {e:#}; the tables are written"
        );
    }
    Ok(drawn.is_ok())
}

/// The loads table's columns, in order, with their JSON keys (all numbers; nulls where no
/// fit or elastic).
const LOAD_COLUMNS: [&str; 20] = [
    "w_over_w0",
    "force_n",
    "mean_pressure_pa",
    "real_contact_area_um2",
    "area_fraction",
    "n_clusters",
    "n_clusters_touching_edge",
    "largest_cluster_um2",
    "k_archard",
    "k_upscaled",
    "wear_rate_mm3_per_m",
    "alpha",
    "alpha_ci95_low",
    "alpha_ci95_high",
    "alpha_plateau",
    "alpha_plateau_ci95_low",
    "alpha_plateau_ci95_high",
    "n_saturated_px",
    "iterations",
    "solver_error",
];

/// The loads table's integer columns (counts).
const COUNT_COLUMNS: [&str; 4] = [
    "n_clusters",
    "n_clusters_touching_edge",
    "n_saturated_px",
    "iterations",
];

fn write_outputs(
    dir: &Path,
    t: Tables,
    report: &serde_json::Value,
    mut psd: DataFrame,
    pixel_m2: f64,
) -> anyhow::Result<()> {
    let n = t.rows.len();
    let mut columns = vec![col("load_index", (0..n as u32).collect::<Vec<_>>())];
    for name in LOAD_COLUMNS.into_iter().chain(super::trust::BAND_COLUMNS) {
        if COUNT_COLUMNS.contains(&name) {
            let values: Vec<Option<u64>> = t.rows.iter().map(|r| r[name].as_u64()).collect();
            columns.push(col(name, values));
        } else {
            let values: Vec<Option<f64>> = t.rows.iter().map(|r| r[name].as_f64()).collect();
            columns.push(col(name, values));
        }
    }
    let mut loads = DataFrame::new(n, columns)?;
    let area_um2: Vec<f64> = t
        .clusters
        .areas()
        .iter()
        .map(|&a| a as f64 * pixel_m2 * 1e12)
        .collect();
    let mut clusters = t.clusters.frame(true)?;
    clusters.with_column(col("area_um2", area_um2))?;
    let mut csv_text = csv::Writer::from_writer(Vec::new());
    let all = || LOAD_COLUMNS.into_iter().chain(super::trust::BAND_COLUMNS);
    csv_text.write_record(std::iter::once("load_index").chain(all()))?;
    for (i, r) in t.rows.iter().enumerate() {
        let cells = all().map(|name| match &r[name] {
            serde_json::Value::Number(v) => v.to_string(),
            _ => String::new(),
        });
        csv_text.write_record(std::iter::once(i.to_string()).chain(cells))?;
    }
    let parquet = |name: &str, df: &mut DataFrame| -> anyhow::Result<()> {
        ParquetWriter::new(std::fs::File::create(dir.join(name))?).finish(df)?;
        Ok(())
    };
    parquet("loads.parquet", &mut loads)?;
    parquet("clusters.parquet", &mut clusters)?;
    parquet("psd.parquet", &mut psd)?;
    std::fs::write(dir.join("loads.csv"), csv_text.into_inner()?)?;
    std::fs::write(
        dir.join("preparation.json"),
        serde_json::to_string_pretty(report)?,
    )?;
    Ok(())
}
