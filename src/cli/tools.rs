//! Single-stage tools on plain files: `solve`, `model`, `clusters`, `surface`.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::ValueEnum;
use serde_json::json;

use wearcoef::solve::SolveOptions;
use wearcoef::store::cluster_table::ClusterRows;

use super::checks::{check_memory, check_outputs, write_atomically, InputError};
use wearcoef::analytic::{ModelError, PlateauPowerLaw};
use wearcoef::clusters::{self, Connectivity};
use wearcoef::grid::Grid;
use wearcoef::spectral::Fft2;
use wearcoef::surface::{self, Method, SurfaceParams};

#[derive(clap::Args)]
pub struct SolveArgs {
    /// Heights (float64 .npy, square, taken as they are; periodic box of side 1).
    #[arg(long)]
    pub surface: PathBuf,
    /// Loads W/W0, comma separated, solved in this order as one warm-started sweep
    /// (W0 = E*·spectral rms slope·L²).
    #[arg(long, value_delimiter = ',', required = true)]
    pub loads: Vec<f64>,
    #[command(flatten)]
    pub options: SolveOptions,
    /// Pressure output: (n, n) float64 for one load, (loads, n, n) for several.
    #[arg(long)]
    pub pressure_out: Option<PathBuf>,
    /// Contact-map output: uint8 0/1, (n, n) for one load, (loads, n, n) for several.
    #[arg(long)]
    pub contact_out: Option<PathBuf>,
    /// Gap output, in the heights' unit: (n, n) float64 for one load, (loads, n, n) for
    /// several; 0 on the contact (under --hardness, minus the plastic displacement on the
    /// saturated nodes).
    #[arg(long)]
    pub gap_out: Option<PathBuf>,
    /// The heights are one map that is not periodic (a box of side 1, pixels 1/n): solved
    /// on the free-boundary half-space as `wear` solves a measured map, W0 from the map's
    /// rms slope without wrap-around.
    #[arg(long)]
    pub non_periodic: bool,
    /// Print one JSON object per load, as a JSON array.
    #[arg(long)]
    pub json: bool,
}

#[derive(Clone, Copy, ValueEnum)]
pub enum MethodArg {
    Filter,
    RandomPhase,
}

#[derive(clap::Args)]
pub struct ModelArgs {
    /// Power-law exponent α.
    #[arg(long, allow_hyphen_values = true)]
    pub alpha: f64,
    /// End of the plateau A_s (> 0).
    #[arg(long)]
    pub a_s: f64,
    /// Cut-off A_m (≥ A_s), or `inf` for the limit A_m → ∞.
    #[arg(long)]
    pub a_m: f64,
    /// Critical area A* (≥ 0).
    #[arg(long, allow_hyphen_values = true)]
    pub a_star: f64,
    /// Print `{"K", "K_upscaled"}` as JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn model(args: ModelArgs) -> anyhow::Result<ExitCode> {
    let ModelArgs {
        alpha,
        a_s,
        a_m,
        a_star,
        json,
    } = args;
    let bad = |e: ModelError| InputError(e.to_string());
    let model = PlateauPowerLaw::new(alpha, a_s, a_m).map_err(bad)?;
    let k = model.k_archard(a_star).map_err(bad)?;
    let kk = model.k_upscaled(a_star).map_err(bad)?;
    if json {
        out!(
            "{}",
            serde_json::to_string(&json!({"K": k, "K_upscaled": kk}))?
        )?;
    } else {
        out!("K = {k} (Archard, P(A > A*)), K_upscaled = {kk} (area fraction above A*)")?;
    }
    Ok(ExitCode::SUCCESS)
}

#[derive(clap::Args)]
pub struct ClustersArgs {
    /// Contact map: bool or uint8 0/1 `.npy` (rows, cols), the project's bit-packed uint8
    /// (n, ceil(n/8)) from the contact stage, or a uint8 0/1 stack (loads, rows, cols) as
    /// `solve --contact-out` writes for several loads (one result per map).
    #[arg(long)]
    pub contact: PathBuf,
    /// Neighbours that link pixels: 8 (edges and corners, the paper's) or 4 (edges).
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(4..=8))]
    pub connectivity: u32,
    /// Print `{"n_clusters", "areas_px" (descending), "percolating"}` as JSON (for a stack,
    /// an array of them with `map_index`).
    #[arg(long)]
    pub json: bool,
    /// Also write one row per cluster to this Parquet table, the clusters stage's columns:
    /// `load_index` (the map's index in a stack, 0 for one map), `cluster_id`, `area_px`,
    /// `perimeter_px`, `extent_x_px`, `extent_y_px`, `wraps_x`, `wraps_y` (the cluster joins
    /// itself across that edge of the periodic box), `percolating`, and with `--open`
    /// `touches_edge` (a pixel on the map's border: a cluster the window may have cut);
    /// `wearcoef fit --areas` reads it as it is.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// The map's edges are open (a measured, non-periodic surface): clusters never join
    /// across them and never wrap; by default the map is one period of a periodic field.
    #[arg(long)]
    pub open: bool,
}

/// The cluster table written (atomically) to `path`.
fn write_cluster_table(
    table: ClusterRows,
    path: &std::path::Path,
    open: bool,
) -> anyhow::Result<()> {
    use polars::prelude::ParquetWriter;
    let mut df = table.frame(open)?;
    write_atomically(path, |tmp| {
        ParquetWriter::new(std::fs::File::create(tmp)?).finish(&mut df)?;
        Ok(())
    })
}

pub fn clusters(args: ClustersArgs) -> anyhow::Result<ExitCode> {
    let ClustersArgs {
        contact,
        connectivity,
        json,
        out,
        open,
    } = args;
    let boundary = if open {
        clusters::Boundary::Open
    } else {
        clusters::Boundary::Periodic
    };
    let conn = Connectivity::from_neighbours(connectivity)
        .ok_or_else(|| InputError(format!("--connectivity must be 4 or 8, got {connectivity}")))?;
    if let Some(path) = &out {
        super::checks::check_output_named(
            "--out",
            path,
            "parquet",
            "the table is Parquet",
            &[("--contact", &contact)],
        )?;
    }
    // One map, or a stack of maps (one per load of a `solve --contact-out` sweep): one
    // result per map, a JSON array for a stack.
    let (_, shape) = wearcoef::io::npy_header(&contact)?;
    let pixels: u64 = shape.iter().map(|&d| d as u64).product();
    let map_pixels = match shape[..] {
        [rows, cols] if cols == rows.div_ceil(8) && cols != rows => (rows as u64).pow(2),
        [.., rows, cols] => rows as u64 * cols as u64,
        _ => pixels,
    };
    check_memory(
        &format!("labelling {}", contact.display()),
        // the file's bytes and the maps as booleans, then one labelling (cost model: 17 B/px)
        (2 * pixels.max(map_pixels)).saturating_add(map_pixels.saturating_mul(17)),
        "label a smaller map",
    )?;
    let maps = wearcoef::io::read_contact_maps(&contact)?;
    let stacked = maps.len() > 1;
    let mut results = Vec::new();
    let mut table = ClusterRows::default();
    for (index, (rows, cols, map, format)) in maps.into_iter().enumerate() {
        let labelling = clusters::label_with(&map, rows, cols, conn, boundary)
            .map_err(|e| InputError(format!("{}: {e}", contact.display())))?;
        table.push(index, &labelling);
        let mut areas: Vec<u64> = labelling.clusters.iter().map(|c| c.area_px).collect();
        areas.sort_unstable_by(|a, b| b.cmp(a));
        let percolating = labelling.clusters.iter().any(|c| c.percolating());
        if json {
            let mut row = json!({
                "n_clusters": labelling.clusters.len(),
                "areas_px": areas,
                "percolating": percolating,
            });
            if stacked {
                row["map_index"] = json!(index);
            }
            results.push(row);
        } else {
            let in_contact: u64 = areas.iter().sum();
            out!(
                "{}{rows} × {cols} map ({format:?}), {connectivity}-connected: {} clusters, \
                 {in_contact} pixels in contact, largest {} px{}",
                if stacked {
                    format!("map {index}: ")
                } else {
                    String::new()
                },
                areas.len(),
                areas.first().copied().unwrap_or(0),
                if percolating {
                    ", a cluster wraps around the periodic box (percolating)"
                } else {
                    ""
                }
            )?;
        }
    }
    if json {
        let doc = if stacked {
            serde_json::Value::Array(results)
        } else {
            results.remove(0)
        };
        out!("{}", serde_json::to_string(&doc)?)?;
    }
    if let Some(path) = &out {
        write_cluster_table(table, path, open)?;
    }
    Ok(ExitCode::SUCCESS)
}

#[derive(clap::Args)]
pub struct SurfaceArgs {
    /// Grid nodes per side (even).
    #[arg(long)]
    pub n: usize,
    /// Largest wavelength λ_l in grid spacings.
    #[arg(long)]
    pub lambda_l_px: f64,
    /// Smallest wavelength λ_s in grid spacings (≥ 2).
    #[arg(long)]
    pub lambda_s_px: f64,
    /// Hurst exponent in (0, 1).
    #[arg(long)]
    pub hurst: f64,
    /// Seed of the random stream.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Roll-off wavelength λ_r in grid spacings (flat PSD between λ_l and λ_r).
    #[arg(long)]
    pub rolloff_lambda_px: Option<f64>,
    #[arg(long, value_enum, default_value_t = MethodArg::Filter)]
    pub method: MethodArg,
    /// Output file (float64 .npy, C order).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Print the realised statistics as JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn surface(args: SurfaceArgs) -> anyhow::Result<ExitCode> {
    let SurfaceArgs {
        n,
        lambda_l_px,
        lambda_s_px,
        hurst,
        seed,
        rolloff_lambda_px,
        method,
        output,
        json,
    } = args;
    let params = SurfaceParams {
        n,
        hurst,
        lambda_l_px,
        lambda_s_px,
        rolloff_lambda_px,
        method: match method {
            MethodArg::Filter => Method::Filter,
            MethodArg::RandomPhase => Method::RandomPhase,
        },
        seed,
    };
    params.validate()?;
    if n > wearcoef::config::MAX_N {
        return Err(InputError(format!(
            "--n {n}: at most {} grid nodes per side (as in pipeline.yaml)",
            wearcoef::config::MAX_N
        ))
        .into());
    }
    check_outputs(&[("--output", &output)], &[])?;
    let nodes = (n * n) as u64;
    check_memory(
        &format!("a {n}² surface"),
        6 * 8 * nodes,
        "choose a smaller --n",
    )?;
    let fft = Fft2::new(n);
    let mut scratch = fft.make_scratch();
    let s = surface::generate(&params, &fft, &mut scratch)?;
    write_atomically(&output, |tmp| {
        Ok(wearcoef::io::write_heights(tmp, n, s.heights.clone())?)
    })?;
    if json {
        let out = json!({
            "n": n,
            "hurst": hurst,
            "lambda_l_px": lambda_l_px,
            "lambda_s_px": lambda_s_px,
            "rolloff_lambda_px": rolloff_lambda_px,
            "method": params.method.as_str(),
            "seed": seed,
            "mean_height": s.stats.mean_height,
            "rms_height": s.stats.rms_height,
            "rms_slope": s.stats.rms_slope,
            "hurst_fit": s.stats.hurst_fit,
            "output": output.display().to_string(),
        });
        out!("{}", serde_json::to_string(&out)?)?;
    }
    Ok(ExitCode::SUCCESS)
}

/// `wearcoef solve`, run on a worker of its own rayon pool (RAYON_NUM_THREADS threads): the
/// solver's parallel loops then start on a pool thread instead of being injected from the
/// main thread and waited for (a wake-up and a sleep per loop, several per iteration), and
/// every buffer is allocated by the same thread, so memory freed by one stage (the slope's
/// transform, the operator's set-up) is reused by the next instead of sitting in another
/// thread's allocator arena.
pub fn solve(args: SolveArgs) -> anyhow::Result<ExitCode> {
    rayon::ThreadPoolBuilder::new()
        .build()?
        .install(|| solve_on_pool(args))?;
    Ok(ExitCode::SUCCESS)
}

fn solve_on_pool(args: SolveArgs) -> anyhow::Result<()> {
    // The options first, each error naming its flag, then the surface.
    args.options.config(&args.loads)?;
    let (n, heights) = read_checked_surface(&args)?;
    let keep_fields = args.pressure_out.is_some() || args.contact_out.is_some();
    let keep_gaps = args.gap_out.is_some();
    let mut pressures = Vec::new();
    let mut contacts = Vec::new();
    let mut gaps = Vec::new();
    let each = |_, solved: &wearcoef::contact::sweep::Solved| {
        if keep_fields {
            pressures.extend_from_slice(solved.pressure);
            contacts.extend(solved.pressure.iter().map(|&p| u8::from(p > 0.0)));
        }
        if keep_gaps {
            gaps.extend(solved.gap());
        }
        Ok(())
    };
    let results = if args.non_periodic {
        wearcoef::solve::sweep_free(&heights, n, &args.loads, &args.options, each)?
    } else {
        wearcoef::solve::sweep(&heights, n, &args.loads, &args.options, each)?
    };
    let shape: Vec<usize> = if args.loads.len() == 1 {
        vec![n, n]
    } else {
        vec![args.loads.len(), n, n]
    };
    // Both outputs or neither: each is written to its temporary, then both are renamed.
    let mut files: Vec<(&std::path::Path, wearcoef::io::atomic::FileWriter)> = Vec::new();
    if let Some(path) = &args.pressure_out {
        let shape = shape.clone();
        files.push((
            path,
            Box::new(move |tmp| Ok(wearcoef::io::write_f64(tmp, &shape, pressures)?)),
        ));
    }
    if let Some(path) = &args.contact_out {
        let shape = shape.clone();
        files.push((
            path,
            Box::new(move |tmp| Ok(wearcoef::io::write_u8(tmp, &shape, contacts)?)),
        ));
    }
    if let Some(path) = &args.gap_out {
        let shape = shape.clone();
        files.push((
            path,
            Box::new(move |tmp| Ok(wearcoef::io::write_f64(tmp, &shape, gaps)?)),
        ));
    }
    wearcoef::io::atomic::write_all_atomically(files)?;
    if args.json {
        out!(
            "{}",
            serde_json::to_string(&wearcoef::solve::json_rows(&results))?
        )?;
    }
    Ok(())
}

/// The outputs checked, then the surface: its header against the memory a sweep of it needs,
/// then its heights (square, even side, finite).
fn read_checked_surface(args: &SolveArgs) -> anyhow::Result<(usize, Vec<f64>)> {
    let mut outputs: Vec<(&str, &std::path::Path)> = Vec::new();
    if let Some(p) = &args.pressure_out {
        outputs.push(("--pressure-out", p));
    }
    if let Some(p) = &args.contact_out {
        outputs.push(("--contact-out", p));
    }
    if let Some(p) = &args.gap_out {
        outputs.push(("--gap-out", p));
    }
    if outputs.is_empty() && !args.json {
        return Err(InputError(
            "nothing to write: give --pressure-out FILE, --contact-out FILE, --gap-out FILE or --json (a solve that keeps nothing is not run)".into(),
        )
        .into());
    }
    check_outputs(&outputs, &[("--surface", &args.surface)])?;
    // The grid side from the header, checked against the file's size, before anything large
    // is read or allocated.
    let (_, shape) = wearcoef::io::npy_header(&args.surface)?;
    if let [rows, cols] = shape[..] {
        if rows == cols && rows > wearcoef::config::MAX_N {
            return Err(InputError(format!(
                "{}: {rows} × {cols} heights; at most {} grid nodes per side",
                args.surface.display(),
                wearcoef::config::MAX_N
            ))
            .into());
        }
        let nodes = (rows as u64).saturating_mul(cols as u64);
        let loads = args.loads.len() as u64;
        let fields = if args.pressure_out.is_some() {
            8 * loads
        } else {
            0
        } + if args.contact_out.is_some() { loads } else { 0 }
            + if args.gap_out.is_some() { 8 * loads } else { 0 };
        // Not periodic: the solver's fields live on the zero-padded square, 4 times the nodes.
        let solver = if args.non_periodic { 4 * 60 } else { 60 };
        check_memory(
            &format!("a {rows} × {cols} sweep of {loads} loads"),
            nodes.saturating_mul(solver + fields),
            "solve a smaller surface, or fewer loads with --pressure-out/--contact-out/--gap-out",
        )?;
    }
    let (n, heights) = wearcoef::io::read_square_f64(&args.surface)?;
    wearcoef::solve::check_heights(&args.surface.display().to_string(), n, &heights)?;
    Grid::unit(n)?;
    Ok((n, heights))
}
