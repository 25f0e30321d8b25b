//! A measured map to its wear coefficients, for `wearcoef wear` and the Python package
//! alike: the prepared map pressed on the free-boundary half-space at each load W/W0
//! (`contact::window`), its contact clusters labelled without wrap-around, and per load the
//! counted K (eq. 5), 𝒦 (eq. 7), the wear rate (eq. 6) and α̂ in physical units beside the
//! dimensionless ones, with the trust band ([`trust`]); the tables and the page ([`page`])
//! written by [`Wear::write`].

pub mod page;
pub mod trust;

use std::path::Path;

use polars::prelude::{DataFrame, ParquetWriter};
use serde_json::json;

use crate::clusters::{self, Boundary, Connectivity};
use crate::contact::interface::Interface;
use crate::contact::solver::SolverConfig;
use crate::contact::window::sweep_window;
use crate::io::prepare::Prepared;
use crate::psd::PsdBin;
use crate::ranges::InputError;
use crate::statistics::{wear_at, OMEGA};
use crate::store::cluster_table::ClusterRows;
use crate::store::table::col;
use crate::topography::Topography;
use crate::units::{number_and_unit, quantity, AREA, FORCE, LENGTH, PRESSURE};

/// The physics of a run as a user types it (each quantity with its unit), the command
/// line's options and the Python package's keywords.
#[derive(clap::Args, Debug, Clone)]
pub struct WearOptions {
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
}

/// The physical settings of a run, checked and in SI units.
#[derive(Debug, Clone)]
pub struct Settings {
    pub e_star_pa: f64,
    pub a_star_m2: f64,
    pub hardness_pa: Option<f64>,
    /// The loads as given (W/W0, forces or pressures).
    pub loads: Vec<Load>,
    pub tolerance: f64,
    /// The trust band's factors on d*, low then high.
    pub d_star_factors: [f64; 2],
    /// Whether the trust band's solves run.
    pub trust_band: bool,
    pub resamples: usize,
}

impl Settings {
    /// The options checked, each error naming its option.
    pub fn new(args: &WearOptions) -> Result<Settings, InputError> {
        let in_range =
            |r: &crate::ranges::Range, option: &str, v: f64| r.check(option, v).map_err(InputError);
        let e_star = quantity("--e-star", &args.e_star, PRESSURE, "a modulus")?;
        in_range(&crate::ranges::E_STAR_PA, "--e-star", e_star)?;
        let a_star_m2 = match (&args.a_star, &args.d_star) {
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
            in_range(&crate::ranges::HARDNESS_PA, "--hardness", h)?;
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
                    &crate::ranges::W_OVER_W0,
                    &format!("--loads (value {})", i + 1),
                    w,
                )?;
            }
        }
        in_range(&crate::ranges::TOLERANCE, "--tolerance", args.tolerance)?;
        match args.d_star_factors[..] {
        [low, high] if low > 0.0 && low < high && high.is_finite() => {}
        _ => {
            return Err(InputError(format!(
                "--d-star-factors {:?}: two factors on d*, low then high, both > 0 (0.5,2 halves and doubles it)",
                args.d_star_factors
            )))
        }
    }
        crate::ranges::RESAMPLES
            .check_count("--resamples", args.resamples as u64)
            .map_err(InputError)?;
        Ok(Settings {
            e_star_pa: e_star,
            a_star_m2,
            hardness_pa,
            loads,
            tolerance: args.tolerance,
            d_star_factors: [args.d_star_factors[0], args.d_star_factors[1]],
            trust_band: !args.no_trust_band,
            resamples: args.resamples,
        })
    }
}

/// A load as given: dimensionless, a force, or a mean nominal pressure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Load {
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
    let show = crate::ranges::show;
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
        crate::ranges::W_OVER_W0
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
/// Refuse, in the user's units, a load whose mean pressure exceeds the hardness.
fn check_loads_below_hardness(
    loads: &[f64],
    hardness_pa: Option<f64>,
    e_star_pa: f64,
    slope: f64,
) -> Result<(), InputError> {
    let Some(h) = hardness_pa else { return Ok(()) };
    let show = crate::ranges::show;
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

/// Refuse, before any work, a map whose solve needs more memory than the machine has.
pub fn check_memory(map: &Topography) -> Result<(), InputError> {
    // Measured: 126 MB peak for a 1000 × 750 map (square side 1000, padded 2000²), about
    // 120 bytes per node of the square; 160 leaves room for the tables.
    let side = map.rows.max(map.cols).next_multiple_of(2) as u64;
    crate::machine::check_memory(
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

/// The map's rms slope and the loads as W/W0 on it, checked below the hardness.
fn map_loads(
    map: &Topography,
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

/// A run: the loads' rows (JSON, one per load, with the trust band's columns), the
/// clusters of every load, the preparation's record completed with the contact's, and the
/// map's PSD.
pub struct Wear {
    pub rows: Vec<serde_json::Value>,
    pub clusters: ClusterRows,
    pub report: serde_json::Value,
    pub psd: Vec<PsdBin>,
    /// The pixel's area, m².
    pub pixel_m2: f64,
}

/// Press the prepared map at each load of `s`: `on_pressure` receives each load's
/// pressure field (Pa, row-major) as it is solved, `progress` is called once per load
/// solved.
pub fn compute(
    prepared: Prepared,
    s: &Settings,
    on_pressure: &mut dyn FnMut(&[f64]) -> Result<(), String>,
    progress: &dyn Fn(),
) -> anyhow::Result<Wear> {
    let Prepared {
        map,
        mut report,
        psd,
    } = prepared;
    if map.missing() > 0 {
        return Err(InputError(format!(
            "{} points are missing: contact needs every height; fill them (harmonic) or crop",
            map.missing()
        ))
        .into());
    }
    check_memory(&map)?;
    let (e_star, a_star_m2, hardness_pa) = (s.e_star_pa, s.a_star_m2, s.hardness_pa);
    let (slope, loads) = map_loads(&map, &s.loads, e_star, hardness_pa)?;
    let pixel_m2 = map.dx * map.dy;
    let area_m2 = (map.rows * map.cols) as f64 * pixel_m2;
    let a_star_px = a_star_m2 / pixel_m2;
    let interface = Interface::from_hardness(hardness_pa.map(|h| h / (e_star * slope)))?;
    let cfg = SolverConfig {
        tolerance: s.tolerance,
        ..SolverConfig::default()
    };
    let area_scales = (s.d_star_factors[0].powi(2), s.d_star_factors[1].powi(2));
    let mut rows_out = Vec::new();
    let mut cluster_rows = ClusterRows::default();
    let (rows, cols) = (map.rows, map.cols);
    let (layout, _) = sweep_window(&map, e_star, &loads, &cfg, interface, |i, p, r| {
        on_pressure(p)?;
        let contact: Vec<bool> = p.iter().map(|&v| v > 0.0).collect();
        let labelling =
            clusters::label_with(&contact, rows, cols, Connectivity::Eight, Boundary::Open)
                .map_err(|e| e.to_string())?;
        let areas: Vec<u64> = labelling.clusters.iter().map(|c| c.area_px).collect();
        let cut = labelling.touching_border();
        let touching = cut.iter().filter(|&&t| t).count();
        cluster_rows.push(i, &labelling);
        let m = wear_at(&areas, a_star_px);
        let fit = crate::tail::fit_row(Some(i as u32), r.w_over_w0, &areas, 0, s.resamples, 0);
        let band = trust::edge_and_d_star(&areas, &cut, a_star_px, area_scales);
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
        rows_out.push(row);
        progress();
        Ok(())
    })?;
    report["trust_band"] = trust::band(
        &map,
        &loads,
        slope,
        trust::Physics {
            e_star_pa: e_star,
            hardness_pa,
            a_star_m2,
            cfg,
        },
        &s.d_star_factors,
        s.trust_band,
        &mut rows_out,
    );
    report["contact"] = json!({
        "half_space": "free boundary (zero-padded), the map's outside never in contact",
        "e_star_pa": e_star, "hardness_pa": hardness_pa, "hardness_w_over_w0": interface.hardness(),
        "tolerance": s.tolerance, "layout": layout,
        "w0_n": e_star * slope * area_m2, "map_area_um2": area_m2 * 1e12,
        "a_star_um2": a_star_m2 * 1e12, "a_star_px": a_star_px,
        "clusters": "8-connected, no wrap-around; touches_edge marks clusters cut by the map's border",
        "program": crate::store::table::program(),
    });
    Ok(Wear {
        rows: rows_out,
        clusters: cluster_rows,
        report,
        psd,
        pixel_m2,
    })
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

impl Wear {
    /// The tables: loads (one row per load), clusters (one row per cluster, with
    /// `area_um2`) and the PSD, as `wear` writes them to Parquet.
    pub fn frames(&self) -> anyhow::Result<[DataFrame; 3]> {
        let n = self.rows.len();
        let mut columns = vec![col("load_index", (0..n as u32).collect::<Vec<_>>())];
        for name in LOAD_COLUMNS.into_iter().chain(trust::BAND_COLUMNS) {
            if COUNT_COLUMNS.contains(&name) {
                let values: Vec<Option<u64>> = self.rows.iter().map(|r| r[name].as_u64()).collect();
                columns.push(col(name, values));
            } else {
                let values: Vec<Option<f64>> = self.rows.iter().map(|r| r[name].as_f64()).collect();
                columns.push(col(name, values));
            }
        }
        let loads = DataFrame::new(n, columns)?;
        let area_um2: Vec<f64> = self
            .clusters
            .areas()
            .iter()
            .map(|&a| a as f64 * self.pixel_m2 * 1e12)
            .collect();
        let mut clusters = self.clusters.frame(true)?;
        clusters.with_column(col("area_um2", area_um2))?;
        let psd = crate::stages::surface::psd_table(&self.psd)?;
        Ok([loads, clusters, psd])
    }

    /// The loads table as CSV text (numbers in shortest round-trip form, empty where null).
    pub fn loads_csv(&self) -> anyhow::Result<Vec<u8>> {
        let mut csv_text = csv::Writer::from_writer(Vec::new());
        let all = || LOAD_COLUMNS.into_iter().chain(trust::BAND_COLUMNS);
        csv_text.write_record(std::iter::once("load_index").chain(all()))?;
        for (i, r) in self.rows.iter().enumerate() {
            let cells = all().map(|name| match &r[name] {
                serde_json::Value::Number(v) => v.to_string(),
                _ => String::new(),
            });
            csv_text.write_record(std::iter::once(i.to_string()).chain(cells))?;
        }
        Ok(csv_text.into_inner()?)
    }

    /// The tables, then the page, into `dir`: loads.parquet, loads.csv, clusters.parquet,
    /// psd.parquet, preparation.json, then wear.png, wear.svg and index.html. The tables
    /// are kept whatever the page does: a page that cannot be drawn is a warning (and
    /// `Ok(false)`).
    pub fn write(&self, dir: &Path) -> anyhow::Result<bool> {
        let [mut loads, mut clusters, mut psd] = self.frames()?;
        let parquet = |name: &str, df: &mut DataFrame| -> anyhow::Result<()> {
            ParquetWriter::new(std::fs::File::create(dir.join(name))?).finish(df)?;
            Ok(())
        };
        parquet("loads.parquet", &mut loads)?;
        parquet("clusters.parquet", &mut clusters)?;
        parquet("psd.parquet", &mut psd)?;
        std::fs::write(dir.join("loads.csv"), self.loads_csv()?)?;
        std::fs::write(
            dir.join("preparation.json"),
            serde_json::to_string_pretty(&self.report)?,
        )?;
        let mut areas_um2 = vec![Vec::new(); self.rows.len()];
        for (&i, &a) in self.clusters.maps().iter().zip(self.clusters.areas()) {
            areas_um2[i as usize].push(a as f64 * self.pixel_m2 * 1e12);
        }
        let page = page::Page {
            rows: &self.rows,
            areas_um2,
            psd: &self.psd,
            report: &self.report,
        };
        let drawn = page::write(&page, dir);
        if let Err(e) = &drawn {
            crate::note!(
                "warning: the page (wear.png, wear.svg, index.html) could not be drawn: {e:#}; the tables are written"
            );
        }
        Ok(drawn.is_ok())
    }
}
