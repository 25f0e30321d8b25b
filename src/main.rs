//! `wearcoef` command line: parse, call the library, map errors to exit codes
//! (0 success, 1 failure, 2 invalid input or configuration).

use std::io::Write;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod cli;

use cli::checks::InputError;

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

#[derive(Subcommand)]
enum Command {
    /// Build what is missing for a profile (targets: stage or study names; default all).
    Run(cli::store::RunArgs),

    /// Print the plan of a profile: every stage instance (stage, key, job, inputs, level,
    /// whether the store holds it, estimated seconds and peak bytes) and its totals
    /// (core-hours, largest memory). Targets: stage, study or figure names.
    Plan(cli::plan::PlanArgs),

    /// Run instances of a plan file whose inputs are in the store: all, one level
    /// (`--level`), or one slice of them (`--slice I/K`, the I-th of K, 0-based).
    Exec(cli::plan::ExecArgs),

    /// Submit what is missing for a profile to Slurm: one job array per plan level, stage
    /// and memory class (resources from the cost model), chained with afterok, each task
    /// running `wearcoef exec` on its slice. --dry-run prints the scripts.
    Submit(cli::submit::SubmitArgs),

    /// Show what is present or missing for a profile, and the Slurm jobs of its campaigns.
    Status(cli::store::StatusArgs),

    /// The catalog of a profile from the store as it is: one row per file, or with --stage
    /// one row per instance with its parameters and results (CSV or Parquet).
    Catalog(cli::store::CatalogArgs),

    /// Remove store entries that no profile of the pipeline file references (--dry-run lists
    /// them).
    Gc(cli::store::GcArgs),

    /// Re-hash every artifact against its manifest; exit 1 on any mismatch.
    Verify(cli::store::VerifyArgs),

    /// Remove the data directory, or with --corrupt only the entries that fail `verify`.
    Clean(cli::store::CleanArgs),

    /// Solve the contact of a surface file at one or several loads.
    Solve(cli::tools::SolveArgs),

    /// Wear coefficients of the plateau + power-law model of cluster areas (paper
    /// Appendix A): K (Archard, number fraction of clusters above A*) and K_upscaled (𝒦,
    /// area fraction). Areas in any one unit.
    Model(cli::tools::ModelArgs),

    /// Fit α to a table of cluster areas, per load: the discrete power law truncated at the
    /// largest area by maximum likelihood (x_min by the KS criterion, a bootstrap 95 %
    /// interval, Clauset et al.'s goodness of fit and likelihood-ratio tests against a
    /// cut-off, lognormal, exponential and stretched exponential tail) and the plateau +
    /// power law of Appendix A (profile-likelihood interval, A_s, A_m); with several
    /// realizations, intervals over them; with --a-star the counted K and 𝒦.
    Fit(cli::fit::FitArgs),

    /// Label the contact clusters of a map, or of each map of a stack, on the periodic torus
    /// or with open edges (--open, a measured surface); --out: one Parquet row per cluster.
    Clusters(cli::tools::ClustersArgs),

    /// Generate one self-affine surface into a .npy file (lengths in grid spacings).
    Surface(cli::tools::SurfaceArgs),

    /// Prepare a measured map: read it (any format of --input), state its units, refuse
    /// or fill missing points, remove its form (mean, plane or curvature) and report its rms
    /// height and slope; -o writes the prepared heights in metres.
    Topography(cli::topography::TopographyArgs),
    /// A measured map to its wear coefficients in one command: prepared as `topography`
    /// does, pressed on the free-boundary half-space at each load, its clusters labelled;
    /// per load K, 𝒦, the wear rate and α̂ in physical units (loads.parquet/.csv,
    /// clusters.parquet, preparation.json).
    Wear(cli::wear::WearArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match check_environment()
        .map_err(anyhow::Error::from)
        .and_then(|_| dispatch(cli))
    {
        Ok(code) => code,
        Err(e) => {
            // The reader closed the pipe (`wearcoef status | head -1`): it has what it wanted.
            let broken = |io: &std::io::Error| io.kind() == std::io::ErrorKind::BrokenPipe;
            let closed_pipe = e.chain().any(|c| {
                c.downcast_ref::<std::io::Error>().is_some_and(broken)
                    || c.downcast_ref::<csv::Error>()
                        .is_some_and(|e| matches!(e.kind(), csv::ErrorKind::Io(io) if broken(io)))
            });
            if closed_pipe {
                return ExitCode::SUCCESS;
            }
            wearcoef::note!("error: {e:#}");
            let is_input = wearcoef::pipeline::is_input_error(&e);
            ExitCode::from(if is_input { 2 } else { 1 })
        }
    }
}

/// The environment's counts are bounded like the command line's: `RAYON_NUM_THREADS` (the
/// threads of `solve`, `surface`, `clusters`) is a whole number, 0 meaning one per core, and
/// at most what this machine allows the program.
fn check_environment() -> Result<(), InputError> {
    let Ok(value) = std::env::var("RAYON_NUM_THREADS") else {
        return Ok(());
    };
    let max = wearcoef::machine::max_threads();
    match value.trim().parse::<usize>() {
        Ok(n) if n <= max => Ok(()),
        _ => Err(InputError(format!(
            "RAYON_NUM_THREADS={value:?}: a whole number of threads from 1 to {max} (0 or unset: one per core)"
        ))),
    }
}

fn dispatch(cli: Cli) -> anyhow::Result<ExitCode> {
    let code = match cli.command {
        Command::Run(args) => cli::store::run(args),
        Command::Plan(args) => cli::plan::plan(args),
        Command::Exec(args) => cli::plan::exec(args),
        Command::Submit(args) => cli::submit::submit(args),
        Command::Status(args) => cli::store::status(args),
        Command::Verify(args) => cli::store::verify(args),
        Command::Catalog(args) => cli::store::catalog(args),
        Command::Gc(args) => cli::store::gc(args),
        Command::Clean(args) => cli::store::clean(args),
        Command::Solve(args) => cli::tools::solve(args),
        Command::Model(args) => cli::tools::model(args),
        Command::Clusters(args) => cli::tools::clusters(args),
        Command::Fit(args) => cli::fit::fit(args),
        Command::Surface(args) => cli::tools::surface(args),
        Command::Topography(args) => cli::topography::topography(args),
        Command::Wear(args) => cli::wear::wear(args),
    }?;
    std::io::stdout().flush().ok();
    Ok(code)
}
