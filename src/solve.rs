//! The periodic solve as `wearcoef solve` and the Python package's `solve` run it: the
//! solver's options as a user gives them (each checked, its error naming the option), the
//! sweep over the loads, and its per-load summary as JSON.

use serde_json::json;

use crate::contact::interface::Interface;
use crate::contact::solver::{Extension, SolverConfig};
use crate::contact::sweep::{sweep_heights_solved, LoadResult, Solved, MAX_W_OVER_W0};
use crate::contact::window::sweep_window_solved;
use crate::ranges::InputError;
use crate::topography::Topography;

/// The solver's options of a periodic solve (the command line's flags, the Python
/// package's keywords).
#[derive(clap::Args, Debug, Clone)]
pub struct SolveOptions {
    /// Tolerance on the complementarity error (docs/CONVENTIONS.md).
    #[arg(long, default_value_t = 1e-8)]
    pub tol: f64,
    /// Iteration cap per load.
    #[arg(long, default_value_t = 5000)]
    pub max_iter: usize,
    /// Effective modulus E* (pressures are written in its unit).
    #[arg(long, default_value_t = 1.0)]
    pub e_star: f64,
    /// Perfectly plastic interface: the pressure saturates at the hardness 𝓗, given in
    /// units of E*·rms slope like the loads (so p̄/𝓗 = (W/W0)/hardness; every load must be
    /// ≤ it). Absent (or inf): elastic contact. Not with --plain-cg.
    #[arg(long)]
    pub hardness: Option<f64>,
    /// Use the plain Polonsky–Keer conjugate gradient instead of the default preconditioned
    /// one (same solution; more iterations on large grids, one convolution each).
    #[arg(long)]
    pub plain_cg: bool,
    /// Precondition with `P K⁻¹ P` alone, without the default's extension off the free set
    /// by the smoothed gradient and its near term (the same solution in 1.6–1.8 times the
    /// iterations on rough surfaces; docs/BENCHMARKS.md).
    #[arg(long, conflicts_with = "plain_cg")]
    pub no_extension: bool,
    /// Deflate the preconditioner by the loads of blocks of this many nodes per side once
    /// the contact set has settled and covers at least 2 % of the box (a multiple of 16,
    /// used on large boxes, see --large-box, that it divides into at least 2 blocks per
    /// side; 0: never; docs/BENCHMARKS.md).
    #[arg(long, default_value_t = 1024, conflicts_with_all = ["plain_cg", "no_extension"])]
    pub coarse_block: usize,
    /// On large boxes, let a node off the contact set join the free set only where it
    /// interpenetrates by more than this times the current error times the heights'
    /// standard deviation (in [0, 1]; 0: every interpenetrating node joins, as on smaller
    /// boxes; docs/BENCHMARKS.md).
    #[arg(long, default_value_t = 0.1, conflicts_with_all = ["plain_cg", "no_extension"])]
    pub entry_margin: f64,
    /// The smallest grid side, in nodes, that counts as a large box: the extension's far
    /// term, the block deflation and the entry margin are used from it on (the same
    /// solution either way; docs/BENCHMARKS.md).
    #[arg(long, default_value_t = 4096, conflicts_with_all = ["plain_cg", "no_extension"])]
    pub large_box: usize,
    /// Restore the load after each projection by rescaling every pressure instead of the
    /// default's uniform offset of the contact pressures (the same solution in about 1.1
    /// times the iterations; docs/BENCHMARKS.md).
    #[arg(long, conflicts_with = "plain_cg")]
    pub scale_to_load: bool,
    /// Start each load from the last solution scaled to it, instead of the default's
    /// extrapolation from the last two (the same solution in about 1.1 times the
    /// iterations; docs/BENCHMARKS.md).
    #[arg(long)]
    pub scale_start: bool,
}

impl Default for SolveOptions {
    /// The command line's defaults.
    fn default() -> SolveOptions {
        SolveOptions {
            tol: 1e-8,
            max_iter: 5000,
            e_star: 1.0,
            hardness: None,
            plain_cg: false,
            no_extension: false,
            coarse_block: 1024,
            entry_margin: 0.1,
            large_box: 4096,
            scale_to_load: false,
            scale_start: false,
        }
    }
}

impl SolveOptions {
    /// The interface `--hardness` asks for, checked once (its message names the flag).
    pub fn interface(&self) -> Result<Interface, InputError> {
        Interface::from_hardness(self.hardness).map_err(|_| {
            InputError(format!(
                "--hardness {} must be > 0 (in units of E*·rms slope, as the loads; omit it, or give inf, for elastic contact)",
                self.hardness.unwrap_or(f64::NAN)
            ))
        })
    }

    /// The solver's configuration for `loads` (W/W0), every option checked.
    pub fn config(&self, loads: &[f64]) -> Result<SolverConfig, InputError> {
        let extension = extension(self, loads)?;
        Ok(SolverConfig {
            tolerance: self.tol,
            max_iterations: self.max_iter,
            preconditioned: !self.plain_cg,
            extension: (!self.no_extension).then_some(extension),
            offset_to_load: !self.scale_to_load,
            extrapolate_start: !self.scale_start,
            ..SolverConfig::default()
        })
    }
}

/// Square heights of side `n` (row-major, periodic box of side 1), checked: an even side
/// from 2 to [`crate::config::MAX_N`] and finite heights; `name` names them in errors.
pub fn check_heights(name: &str, n: usize, heights: &[f64]) -> Result<(), InputError> {
    if n < 2 || !n.is_multiple_of(2) || heights.len() != n * n {
        return Err(InputError(format!(
            "{name}: the grid side must be even and ≥ 2, got {n}"
        )));
    }
    if n > crate::config::MAX_N {
        return Err(InputError(format!(
            "{name}: {n} × {n} heights; at most {} grid nodes per side",
            crate::config::MAX_N
        )));
    }
    if let Some((i, v)) = heights.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(InputError(format!(
            "{name}: height at row {}, column {} is {v}; heights must be finite",
            i / n,
            i % n
        )));
    }
    Ok(())
}

/// The sweep over `loads` of the checked heights, periodic: `each` receives every load's
/// fields as it is solved (pressure in units of E*, gap in the heights' unit).
pub fn sweep(
    heights: &[f64],
    n: usize,
    loads: &[f64],
    options: &SolveOptions,
    mut each: impl FnMut(usize, &Solved) -> Result<(), String>,
) -> anyhow::Result<Vec<LoadResult>> {
    let cfg = options.config(loads)?;
    let (_, results) = sweep_heights_solved(
        heights,
        n,
        options.e_star,
        loads,
        &cfg,
        options.interface()?,
        |i, solved, _| each(i, solved),
    )?;
    Ok(results)
}

/// The sweep over `loads` of the checked square heights of side `n` as a map that is not
/// periodic: one box of side 1 (pixels 1/n, in the heights' unit) on the free-boundary
/// half-space, as `wear` solves a measured map; `W0 = E*·rms slope·L²` with the rms slope
/// of the map without wrap-around. `each` as for [`sweep`].
pub fn sweep_free(
    heights: &[f64],
    n: usize,
    loads: &[f64],
    options: &SolveOptions,
    mut each: impl FnMut(usize, &Solved) -> Result<(), String>,
) -> anyhow::Result<Vec<LoadResult>> {
    let cfg = options.config(loads)?;
    let interface = options.interface()?;
    let pixel = 1.0 / n as f64;
    let map = Topography::new(n, n, pixel, pixel, heights.to_vec())?;
    let (layout, results) = sweep_window_solved(
        &map,
        options.e_star,
        loads,
        &cfg,
        interface,
        |i, solved, _| each(i, solved),
    )?;
    Ok(results
        .into_iter()
        .map(|r| LoadResult {
            w_over_w0: r.w_over_w0,
            mean_pressure: r.mean_pressure,
            area_fraction: r.area_fraction,
            n_contact_px: r.n_contact_px,
            n_saturated_px: r.n_saturated_px,
            ceiling: interface
                .hardness()
                .map(|h| h * options.e_star * layout.rms_slope),
            report: r.report,
            seconds: r.seconds,
        })
        .collect())
}

/// `solve`'s numeric flags checked one by one (each error names its flag); the extension they
/// ask for.
fn extension(args: &SolveOptions, loads: &[f64]) -> Result<Extension, InputError> {
    if let Some((i, w)) = loads
        .iter()
        .enumerate()
        .find(|(_, w)| !(w.is_finite() && **w >= 0.0))
    {
        return Err(InputError(format!(
            "--loads: load {} is {w}; loads W/W0 must be finite and ≥ 0",
            i + 1
        )));
    }
    if let Some((i, w)) = loads.iter().enumerate().find(|(_, w)| **w > MAX_W_OVER_W0) {
        return Err(InputError(format!(
            "--loads: load {} is {w:e}; W/W0 must be ≤ {MAX_W_OVER_W0} (contact is complete well before W/W0 = 10; larger loads only lose digits to rounding)",
            i + 1
                )));
    }
    let interface = args.interface()?;
    if args.plain_cg && !interface.is_elastic() {
        return Err(InputError(
            "--plain-cg with --hardness: the plain iteration stalls under a pressure ceiling on rough surfaces (512², hardness 1 and 0.5, docs/VALIDATION.md); drop --plain-cg for the default preconditioned iteration".into(),
        ));
    }
    if let (Some((i, w)), Some(h)) = (interface.first_load_above(loads), interface.hardness()) {
        return Err(InputError(format!(
            "--loads: load {} is {w}, above --hardness {h}: a pressure capped at the hardness cannot carry a mean above it",
            i + 1
        )));
    }
    if !(args.e_star.is_finite() && args.e_star > 0.0) {
        return Err(InputError(format!(
            "--e-star {} must be finite and > 0",
            args.e_star
        )));
    }
    if !(args.tol.is_finite() && args.tol > 0.0 && args.tol < 1.0) {
        return Err(InputError(format!(
            "--tol {}: the tolerance must lie in (0, 1), as in pipeline.yaml (1e-8 is the default)",
            args.tol
        )));
    }
    if args.max_iter == 0 {
        return Err(InputError(
            "--max-iter 0: at least one iteration is needed".into(),
        ));
    }
    // Each flag checked on the default with that flag alone changed, so the error names it.
    let block = Extension {
        coarse_block: args.coarse_block,
        ..Default::default()
    };
    block
        .check()
        .map_err(|e| InputError(format!("--coarse-block {}: {e}", args.coarse_block)))?;
    let margin = Extension {
        entry_margin: args.entry_margin,
        ..Default::default()
    };
    margin.check().map_err(|e| {
        InputError(format!(
            "--entry-margin {}: {e} (0.1 is the default, 0 turns it off)",
            args.entry_margin
        ))
    })?;
    Ok(Extension {
        coarse_block: args.coarse_block,
        large_box: args.large_box,
        ..margin
    })
}

/// One JSON object per load of a `solve`.
pub fn json_rows(results: &[LoadResult]) -> Vec<serde_json::Value> {
    results
        .iter()
        .map(|r| {
            let mut row = json!({
                "w_over_w0": r.w_over_w0,
                "mean_pressure": r.mean_pressure,
                "area_fraction": r.area_fraction,
                "n_contact_px": r.n_contact_px,
                "iterations": r.report.iterations,
                "convolutions": r.report.convolutions,
                "error": r.report.error,
                "converged": r.report.converged(),
                "seconds": r.seconds,
                "peak_rss_bytes": crate::machine::peak_rss_bytes(),
            });
            if let Some(saturated) = r.n_saturated_px {
                row["n_saturated_px"] = json!(saturated);
            }
            row
        })
        .collect()
}
