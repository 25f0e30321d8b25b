//! `wearcoef` command line: parse, call the library, map errors to exit codes
//! (0 success, 1 failure, 2 invalid input or configuration).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context;
use clap::{Parser, Subcommand, ValueEnum};
use serde_json::json;

mod cli;

use wearcoef::analytic::{ModelError, PlateauPowerLaw};
use wearcoef::clusters::{self, Connectivity};
use wearcoef::config::{ConfigError, Pipeline};
use wearcoef::contact::solver::SolverConfig;
use wearcoef::contact::sweep::{sweep_heights, SweepError};
use wearcoef::grid::Grid;
use wearcoef::pipeline::runner::{self, RunOptions};
use wearcoef::pipeline::store::Store;
use wearcoef::pipeline::UsageError;
use wearcoef::spectral::Fft2;
use wearcoef::surface::{self, Method, SurfaceError, SurfaceParams};

#[derive(Parser)]
#[command(
    name = "wearcoef",
    version,
    about = "Rough contact, cluster statistics and wear coefficients (Frérot et al., JMPS 2018), rebuilt reproducibly"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(clap::Args, Clone)]
struct StoreArgs {
    /// Pipeline description.
    #[arg(long, default_value = "pipeline.yaml")]
    config: PathBuf,
    /// Data directory (artifact store and catalogs).
    #[arg(long, default_value = "data")]
    data: PathBuf,
}

#[derive(Subcommand)]
enum Command {
    /// Build what is missing for a profile (targets: stage or study names; default all).
    Run {
        targets: Vec<String>,
        #[command(flatten)]
        store: StoreArgs,
        /// Profile declared in the pipeline file.
        #[arg(long, default_value = "default")]
        profile: String,
        /// Worker threads [default: number of cores].
        #[arg(long)]
        jobs: Option<usize>,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
        /// Print the summary as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Print the plan of a profile: every stage instance (stage, key, job, inputs, level,
    /// whether the store holds it, estimated seconds and peak bytes) and its totals
    /// (core-hours, largest memory). Targets: stage, study or figure names.
    Plan {
        targets: Vec<String>,
        #[command(flatten)]
        store: StoreArgs,
        #[arg(long, default_value = "default")]
        profile: String,
        /// Print the whole plan as one JSON object.
        #[arg(long)]
        json: bool,
        /// Also write the plan (JSON) to this file, for `wearcoef exec`.
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Run instances of a plan file whose inputs are in the store: all, one level
    /// (`--level`), or one slice of them (`--slice I/K`, the I-th of K, 0-based).
    Exec {
        /// Plan written by `wearcoef plan --out`.
        #[arg(long)]
        plan: PathBuf,
        #[arg(long, default_value = "data")]
        data: PathBuf,
        #[arg(long)]
        level: Option<usize>,
        #[arg(long, value_parser = cli::plan::parse_slice)]
        slice: Option<(usize, usize)>,
        #[arg(long)]
        jobs: Option<usize>,
        #[arg(long)]
        quiet: bool,
    },
    /// Show what is present or missing for a profile.
    Status {
        #[command(flatten)]
        store: StoreArgs,
        #[arg(long, default_value = "default")]
        profile: String,
        #[arg(long)]
        json: bool,
    },
    /// Re-hash every artifact against its manifest; exit 1 on any mismatch.
    Verify {
        #[arg(long, default_value = "data")]
        data: PathBuf,
        #[arg(long)]
        json: bool,
    },
    /// Remove the data directory, or with --corrupt only the entries that fail `verify`.
    Clean {
        #[arg(long, default_value = "data")]
        data: PathBuf,
        #[arg(long)]
        corrupt: bool,
    },
    /// Solve the contact of a surface file at one or several loads.
    Solve(SolveArgs),
    /// Wear coefficients of the plateau + power-law model of cluster areas (paper
    /// Appendix A): K (Archard, number fraction of clusters above A*) and K_upscaled (𝒦,
    /// area fraction). Areas in any one unit.
    Model {
        /// Power-law exponent α.
        #[arg(long, allow_hyphen_values = true)]
        alpha: f64,
        /// End of the plateau A_s (> 0).
        #[arg(long)]
        a_s: f64,
        /// Cut-off A_m (≥ A_s), or `inf` for the limit A_m → ∞.
        #[arg(long)]
        a_m: f64,
        /// Critical area A* (≥ 0).
        #[arg(long, allow_hyphen_values = true)]
        a_star: f64,
        /// Print `{"K", "K_upscaled"}` as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Label the contact clusters of a map on the periodic torus.
    Clusters {
        /// Contact map: bool or uint8 0/1 `.npy` (rows, cols), or the project's bit-packed
        /// uint8 (n, ceil(n/8)) from the contact stage.
        #[arg(long)]
        contact: PathBuf,
        /// Neighbours that link pixels: 8 (edges and corners, the paper's) or 4 (edges).
        #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(4..=8))]
        connectivity: u32,
        /// Print `{"n_clusters", "areas_px" (descending), "percolating"}` as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Generate one self-affine surface into a .npy file (lengths in grid spacings).
    Surface {
        /// Grid nodes per side (even).
        #[arg(long)]
        n: usize,
        /// Largest wavelength λ_l in grid spacings.
        #[arg(long)]
        lambda_l_px: f64,
        /// Smallest wavelength λ_s in grid spacings (≥ 2).
        #[arg(long)]
        lambda_s_px: f64,
        /// Hurst exponent in (0, 1).
        #[arg(long)]
        hurst: f64,
        /// Seed of the random stream.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Roll-off wavelength λ_r in grid spacings (flat PSD between λ_l and λ_r).
        #[arg(long)]
        rolloff_lambda_px: Option<f64>,
        #[arg(long, value_enum, default_value_t = MethodArg::Filter)]
        method: MethodArg,
        /// Output file (float64 .npy, C order).
        #[arg(short, long)]
        output: PathBuf,
        /// Print the realised statistics as JSON.
        #[arg(long)]
        json: bool,
    },
}

#[derive(clap::Args)]
struct SolveArgs {
    /// Heights (float64 .npy, square, taken as they are; periodic box of side 1).
    #[arg(long)]
    surface: PathBuf,
    /// Loads W/W0, comma separated, solved in this order as one warm-started sweep
    /// (W0 = E*·spectral rms slope·L²).
    #[arg(long, value_delimiter = ',', required = true)]
    loads: Vec<f64>,
    /// Tolerance on the complementarity error (docs/CONVENTIONS.md).
    #[arg(long, default_value_t = 1e-8)]
    tol: f64,
    /// Iteration cap per load.
    #[arg(long, default_value_t = 5000)]
    max_iter: usize,
    /// Effective modulus E* (pressures are written in its unit).
    #[arg(long, default_value_t = 1.0)]
    e_star: f64,
    /// Use the plain Polonsky–Keer conjugate gradient instead of the default preconditioned
    /// one (same solution; more iterations on large grids, one convolution each).
    #[arg(long)]
    plain_cg: bool,
    /// Pressure output: (n, n) float64 for one load, (loads, n, n) for several.
    #[arg(long)]
    pressure_out: Option<PathBuf>,
    /// Contact-map output: uint8 0/1, (n, n) for one load, (loads, n, n) for several.
    #[arg(long)]
    contact_out: Option<PathBuf>,
    /// Print one JSON object per load, as a JSON array.
    #[arg(long)]
    json: bool,
}

#[derive(Clone, Copy, ValueEnum)]
enum MethodArg {
    Filter,
    RandomPhase,
}

/// An error that means "your input is wrong" (exit 2).
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
struct InputError(String);

fn main() -> ExitCode {
    let cli = Cli::parse();
    match dispatch(cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            let is_input = e.chain().any(|c| {
                c.downcast_ref::<ConfigError>().is_some()
                    || c.downcast_ref::<SurfaceError>().is_some()
                    || c.downcast_ref::<InputError>().is_some()
                    || c.downcast_ref::<UsageError>().is_some()
                    || c.downcast_ref::<wearcoef::io::IoError>().is_some()
                    || matches!(
                        c.downcast_ref::<SweepError>(),
                        Some(SweepError::Input(_)) | Some(SweepError::BadLoad { .. })
                    )
            });
            ExitCode::from(if is_input { 2 } else { 1 })
        }
    }
}

fn load(path: &Path) -> anyhow::Result<Pipeline> {
    Ok(Pipeline::load(path)?)
}

fn dispatch(cli: Cli) -> anyhow::Result<ExitCode> {
    match cli.command {
        Command::Run {
            targets,
            store,
            profile,
            jobs,
            quiet,
            json,
        } => {
            let pipeline = load(&store.config)?;
            let jobs =
                jobs.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
            if jobs == 0 {
                return Err(InputError("--jobs must be ≥ 1".into()).into());
            }
            let opts = RunOptions {
                profile,
                targets,
                jobs,
                quiet,
            };
            let origin = store.config.display().to_string();
            let summary = runner::run(&pipeline, &origin, &Store::new(&store.data), &opts)?;
            if json {
                println!("{}", serde_json::to_string(&summary)?);
            } else {
                println!("{summary}");
            }
        }
        Command::Plan {
            targets,
            store,
            profile,
            json,
            out,
        } => {
            let pipeline = load(&store.config)?;
            let origin = store.config.display().to_string();
            let plan = cli::plan::make_plan(&pipeline, &origin, &store.data, &profile, &targets)?;
            cli::plan::print_plan(&plan, json, out.as_ref())?;
        }
        Command::Exec {
            plan,
            data,
            level,
            slice,
            jobs,
            quiet,
        } => {
            let jobs =
                jobs.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
            let done = cli::plan::exec(&plan, &data, level, slice, jobs.max(1), quiet)?;
            println!("{done}");
        }
        Command::Status {
            store,
            profile,
            json,
        } => {
            let pipeline = load(&store.config)?;
            let origin = store.config.display().to_string();
            let lines = runner::status(&pipeline, &origin, &Store::new(&store.data), &profile)?;
            if json {
                println!(
                    "{}",
                    serde_json::to_string(&json!({"profile": profile, "stages": lines}))?
                );
            } else {
                println!(
                    "{:<10} {:<24} {:>8} {:>8}",
                    "stage", "study", "present", "missing"
                );
                for l in &lines {
                    println!(
                        "{:<10} {:<24} {:>8} {:>8}",
                        l.stage, l.study, l.present, l.missing
                    );
                }
            }
        }
        Command::Verify { data, json } => {
            let store = Store::new(&data);
            let (checked, problems) = store.verify()?;
            if json {
                println!(
                    "{}",
                    serde_json::to_string(&json!({"checked": checked, "problems": problems}))?
                );
            } else {
                for p in &problems {
                    println!("MISMATCH {}: {}", p.path, p.reason);
                }
                println!("verified {checked} entries: {} problem(s)", problems.len());
            }
            if !problems.is_empty() {
                return Ok(ExitCode::from(1));
            }
        }
        Command::Clean { data, corrupt } => {
            let store = Store::new(&data);
            if corrupt {
                let removed = store.remove_corrupt()?;
                let stale = store.remove_stale_temporaries()?;
                println!(
                    "removed {} corrupt entries and {stale} stale temporary directories",
                    removed.len()
                );
            } else {
                store.remove_all()?;
                println!("removed {}", data.display());
            }
        }
        Command::Solve(args) => solve(args)?,
        Command::Model {
            alpha,
            a_s,
            a_m,
            a_star,
            json,
        } => {
            let bad = |e: ModelError| InputError(e.to_string());
            let model = PlateauPowerLaw::new(alpha, a_s, a_m).map_err(bad)?;
            let k = model.k_archard(a_star).map_err(bad)?;
            let kk = model.k_upscaled(a_star).map_err(bad)?;
            if json {
                println!(
                    "{}",
                    serde_json::to_string(&json!({"K": k, "K_upscaled": kk}))?
                );
            } else {
                println!(
                    "K = {k} (Archard, P(A > A*)), K_upscaled = {kk} (area fraction above A*)"
                );
            }
        }
        Command::Clusters {
            contact,
            connectivity,
            json,
        } => {
            let conn = Connectivity::from_neighbours(connectivity).ok_or_else(|| {
                InputError(format!("--connectivity must be 4 or 8, got {connectivity}"))
            })?;
            let (rows, cols, map, format) = wearcoef::io::read_contact_map(&contact)?;
            let labelling = clusters::label(&map, rows, cols, conn)
                .map_err(|e| InputError(format!("{}: {e}", contact.display())))?;
            let mut areas: Vec<u64> = labelling.clusters.iter().map(|c| c.area_px).collect();
            areas.sort_unstable_by(|a, b| b.cmp(a));
            let percolating = labelling.clusters.iter().any(|c| c.percolating());
            if json {
                let out = json!({
                    "n_clusters": labelling.clusters.len(),
                    "areas_px": areas,
                    "percolating": percolating,
                });
                println!("{}", serde_json::to_string(&out)?);
            } else {
                let in_contact: u64 = areas.iter().sum();
                println!(
                    "{rows} × {cols} map ({format:?}), {connectivity}-connected: {} clusters, \
                     {in_contact} pixels in contact, largest {} px{}",
                    areas.len(),
                    areas.first().copied().unwrap_or(0),
                    if percolating {
                        ", a cluster wraps around the periodic box (percolating)"
                    } else {
                        ""
                    }
                );
            }
        }
        Command::Surface {
            n,
            lambda_l_px,
            lambda_s_px,
            hurst,
            seed,
            rolloff_lambda_px,
            method,
            output,
            json,
        } => {
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
                println!("{}", serde_json::to_string(&out)?);
            }
        }
    }
    std::io::stdout().flush().ok();
    Ok(ExitCode::SUCCESS)
}

/// `wearcoef solve`, run on a worker of its own rayon pool (RAYON_NUM_THREADS threads): the
/// solver's parallel loops then start on a pool thread instead of being injected from the
/// main thread and waited for (a wake-up and a sleep per loop, several per iteration), and
/// every buffer is allocated by the same thread, so memory freed by one stage (the slope's
/// transform, the operator's set-up) is reused by the next instead of sitting in another
/// thread's allocator arena.
fn solve(args: SolveArgs) -> anyhow::Result<()> {
    rayon::ThreadPoolBuilder::new()
        .build()?
        .install(|| solve_on_pool(args))
}

fn solve_on_pool(args: SolveArgs) -> anyhow::Result<()> {
    if let Some((i, w)) = args
        .loads
        .iter()
        .enumerate()
        .find(|(_, w)| !(w.is_finite() && **w >= 0.0))
    {
        return Err(InputError(format!(
            "--loads: load {} is {w}; loads W/W0 must be finite and ≥ 0",
            i + 1
        ))
        .into());
    }
    let (n, heights) = wearcoef::io::read_square_f64(&args.surface)?;
    if n < 2 || n % 2 != 0 {
        return Err(InputError(format!(
            "{}: the grid side must be even and ≥ 2, got {n}",
            args.surface.display()
        ))
        .into());
    }
    if !(args.e_star.is_finite() && args.e_star > 0.0) {
        return Err(InputError(format!("--e-star {} must be finite and > 0", args.e_star)).into());
    }
    if !(args.tol.is_finite() && args.tol > 0.0) || args.max_iter == 0 {
        return Err(InputError("--tol must be finite and > 0 and --max-iter ≥ 1".into()).into());
    }
    Grid::unit(n)?;
    if let Some((i, v)) = heights.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(InputError(format!(
            "{}: height at row {}, column {} is {v}; heights must be finite",
            args.surface.display(),
            i / n,
            i % n
        ))
        .into());
    }
    let cfg = SolverConfig {
        tolerance: args.tol,
        max_iterations: args.max_iter,
        preconditioned: !args.plain_cg,
        ..SolverConfig::default()
    };
    let keep_fields = args.pressure_out.is_some() || args.contact_out.is_some();
    let mut pressures = Vec::new();
    let mut contacts = Vec::new();
    let (_, results) = sweep_heights(
        &heights,
        n,
        args.e_star,
        &args.loads,
        &cfg,
        |_, solver, _| {
            if keep_fields {
                pressures.extend_from_slice(solver.pressure());
                contacts.extend(solver.pressure().iter().map(|&p| u8::from(p > 0.0)));
            }
            Ok(())
        },
    )?;
    let shape: Vec<usize> = if args.loads.len() == 1 {
        vec![n, n]
    } else {
        vec![args.loads.len(), n, n]
    };
    if let Some(path) = &args.pressure_out {
        write_atomically(path, |tmp| {
            Ok(wearcoef::io::write_f64(tmp, &shape, pressures)?)
        })?;
    }
    if let Some(path) = &args.contact_out {
        write_atomically(path, |tmp| {
            Ok(wearcoef::io::write_u8(tmp, &shape, contacts)?)
        })?;
    }
    if args.json {
        let rows: Vec<_> = results
            .iter()
            .map(|r| {
                json!({
                    "w_over_w0": r.w_over_w0,
                    "mean_pressure": r.mean_pressure,
                    "area_fraction": r.area_fraction,
                    "n_contact_px": r.n_contact_px,
                    "iterations": r.report.iterations,
                    "convolutions": r.report.convolutions,
                    "error": r.report.error,
                    "converged": r.report.converged(),
                    "seconds": r.seconds,
                    "peak_rss_bytes": peak_rss_bytes(),
                })
            })
            .collect();
        println!("{}", serde_json::to_string(&rows)?);
    }
    Ok(())
}

/// The process's peak resident memory (`VmHWM` of /proc/self/status, Linux), if known.
fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Write through a temporary sibling file and rename, so a failure leaves no partial file.
pub(crate) fn write_atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path.file_name().context("output path has no file name")?;
    let tmp = dir.join(format!(
        ".{}.tmp-{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    let result = write(&tmp).and_then(|_| {
        std::fs::rename(&tmp, path).with_context(|| format!("cannot write {}", path.display()))
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}
