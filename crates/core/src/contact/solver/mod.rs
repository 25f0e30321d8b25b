//! Polonsky–Keer constrained conjugate gradient under load control (mean pressure imposed),
//! pressure as the unknown (Polonsky & Keer 1999; Rey, Anciaux & Molinari 2017).
//!
//! Minimises `½⟨p, K p⟩ − ⟨p, h⟩` subject to `p ≥ 0` and `mean(p) = p̄`. The gap is
//! `g = (K p − h) − min(K p − h) ≥ 0`, zero in contact.
//!
//! **Convergence** (docs/CONVENTIONS.md): the dimensionless complementarity error
//! `err = Σ p_i g_i / (Σ p_i · σ_h)`, with `σ_h` the standard deviation of the heights about
//! their mean; it is zero only at the exact discrete solution. It is never larger than
//! Tamaas's measure (which divides by the `ddof = 1` deviation), so a tolerance here is at
//! least as strict as the same tolerance there.
//!
//! **Preconditioning** (the default, [`SolverConfig::preconditioned`]): the gradient is
//! replaced by `z = P K⁻¹ P g` on the free set `F` (`K⁻¹`: the multiplier `E*|q|/2`, 0 at
//! q = 0; `P`: zero off F and centred on it), with `β = ⟨g, z⟩/⟨g, z⟩_old` — the
//! preconditioned conjugate gradient, projected as below. `F` is the contact set and the
//! nodes off it that interpenetrate (`g` below the contact set's mean level; on boxes of
//! 4096² and more, by more than a margin that falls with the error,
//! [`Extension::entry_margin`]: 5 % fewer iterations at 8192²): the direction
//! raises their pressure with the same preconditioned step, instead of re-admitting them
//! one by one afterwards as the plain iteration does, and the conjugate direction is kept
//! unless more than [`RESTART_FRACTION`] of the contact set changed (or the direction would
//! barely descend, [`DESCENT_FRACTION`]). Together these halve the iterations spent finding
//! the contact set (28 % fewer in all on the paper's spectrum at 1024², 38 % at 2048²;
//! docs/BENCHMARKS.md). `K⁻¹` is the exact inverse in full contact and approximates the
//! inverse of the restricted operator elsewhere; the iteration count then grows slowly with
//! n, at one more convolution per iteration. That convolution runs in single precision
//! ([`ElasticOperator::start_rows_inverse`]; `z` is stored as `f32`): the preconditioner is a
//! fixed positive operator either way, the iteration counts are those of `f64`, and the
//! transforms take about 0.6 of the time. Everything that defines the solution (`p`, `u`,
//! `K t`, `K Δ`, the exact recomputation, every sum) stays in `f64`; a correction `K Δ` in
//! `f32` was tried and stalls the iteration near 10⁻⁸. `K⁻¹ P g` is summed over F as its
//! rows leave the inverse FFT (its mean, `⟨g, z⟩`, `Σ g t_old` and the old direction's mean)
//! and stored on F only, NaN marking the nodes off it, so the direction pass reads `t` and
//! `z` alone (not `p` and `w`: 8 % less time per sweep at 1024²), only subtracts the means,
//! and the line-search numerator `⟨g, t⟩` follows from those sums.
//!
//! **Extension** (the default, [`SolverConfig::extension`], module `extension`): the
//! preconditioner's input extended off F by the smoothed gradient, `P Eᵀ K⁻¹ E P`, which
//! weighs slow modulations over F as the whole surface does, at a pass and a few coarse
//! smoothings per iteration and no convolution; a second, near term continues the gradient
//! across the clusters' edges once the contact set has settled (the direction restarts
//! when it is switched on or off), and on boxes of 4096² and more a third, far one once the
//! direction is no longer restarted. Together 38–44 % fewer iterations than `P K⁻¹ P` alone
//! on the paper spectrum's 30-load sweeps at 1024²–4096² (docs/BENCHMARKS.md). On the same
//! large boxes the settled phase of a dense contact set is deflated by the loads of blocks
//! of 1024² nodes (module `deflation`): 6 % fewer iterations at 8192².
//!
//! **Load** (the default, [`SolverConfig::offset_to_load`]): after the projection, the load
//! is restored by a uniform offset of the pressures, `p ← max(p + c, 0)` (`c ≤ 0`, found by
//! Newton's method, mostly in one to three passes), the nearest point of `{p ≥ 0, mean p = p̄}`,
//! wherever the step changed more than [`MAX_SPARSE`] nodes of the contact set (`u = K p`
//! is then recomputed, one convolution, as a correction of that many changes needs); where
//! it changed fewer, by the rescaling `p ← s p` that keeps `p` and `u` linear. Rescaling
//! gives the clipped load back to every node in proportion to its pressure, the largest
//! most, which on a moving contact set perturbs the whole box: the offset takes 8–13 %
//! fewer iterations on the paper spectrum's sweeps, more in larger boxes
//! (docs/BENCHMARKS.md).
//!
//! **Cost.** One convolution (`K t`) per iteration (plus `K⁻¹ P g` when preconditioned).
//! A sweep's warm start extrapolates the last two converged states linearly in the load
//! ([`SolverConfig::extrapolate_start`], one convolution for `K p`); the first warm load, or
//! with it off, scales the previous state, `p` and `K p` alike (`K (s p) = s K p`), in one
//! pass without a convolution.
//! The deflection is updated by linearity, `u ← s (u − τ K t + K Δ)` (stored as `w = u − h`,
//! so that the passes of an iteration read the heights only when the load is rescaled), where
//! `Δ` is the departure of the projected pressure from the linear step at the nodes that left
//! or re-entered the contact set: `K Δ` is summed directly when there are at most
//! [`MAX_SPARSE`] of them, otherwise convolved by FFT (the rows of `Δ` without a change skip
//! the forward row transform, as do the empty rows of every transformed field), and `u = K p`
//! is recomputed exactly every [`RESYNC`] steps, before convergence is declared, and when more
//! than one node in [`CHANGES_PER_NODE`] of a block changed. The
//! curvature `⟨t, K t⟩` comes from Parseval's identity inside the convolution. The search
//! direction is kept centred on the contact set (the projected conjugate gradient), so the
//! step preserves the load. The direction pass is fused with the forward FFT (each row of
//! `t` is handed to the transform as it is made) and the update pass with the inverse FFT
//! (each row of `K t` is consumed as it comes out, never stored): the line search needs
//! only `⟨t, K t⟩`, which is known before the inverse transform starts. Between the two, the
//! column transforms, the multiplier and Parseval's sum run per group of columns in cache
//! ([`crate::spectral::Fft2::convolve_start`]); an exact recomputation of `u = K p` gathers
//! the next gradient statistics from the rows of `K p` as they come out. All reductions use
//! the FFT's fixed row blocks, so results are bit-identical whatever the number of threads.
//! The update pass and the preconditioner's output pass are written in AVX2 intrinsics where
//! the processor has them (one vector lane per accumulator lane: the same operations in the
//! same order as their scalar code, which unit tests compare bit for bit); the compiler had
//! left the update pass scalar, 15 % of a 1024² sweep's time (docs/BENCHMARKS.md).
//!
//! **Defined behaviour where the method breaks down**:
//! - zero load: `p = 0`, no contact, converged in 0 iterations;
//! - flat surface (σ_h = 0): uniform `p = p̄`, full contact, converged in 0 iterations;
//! - single-node contact set: in the plain iteration the centred gradient vanishes and the
//!   CG step is 0/0; the step falls back to a Jacobi-scaled steepest descent on the
//!   re-admitted nodes (`τ = 1/K_ii`). In the preconditioned one the free set also holds
//!   the interpenetrating nodes, so the gradient vanishes only when no node interpenetrates;
//!   either way a single-node solution that is the discrete optimum has error exactly 0;
//! - all pressure projected away: reset to the uniform pressure, restart;
//! - non-finite heights or loads, wrong lengths: an error before solving;
//! - no progress for `stall_window` iterations, or a non-finite error: `Stalled`;
//!   `max_iterations` reached: `MaxIterations`. Neither is ever a result that looks valid.

mod deflation;
mod extension;
mod history;
mod iteration;
mod level;
mod passes;
mod precond;
mod report;
mod rows;
#[cfg(test)]
mod test_support;
#[cfg(test)]
mod tests;

use rayon::prelude::*;

use super::elastic::{ElasticOperator, OperatorWorkspace};
pub use extension::Extension;
use iteration::Iteration;
pub use report::{SolveReport, Status};
use rows::{GradientStats, UpdateAcc, LANES};

/// When at most this many nodes leave or re-enter the contact set in an iteration, the
/// deflection is corrected by direct summation (all nodes' kernel rows added row by row, in
/// the same pass as the next gradient statistics) instead of a new convolution. Limits of
/// 32–128 save 10–20 % of the convolutions but cost as much in summation
/// (docs/BENCHMARKS.md).
pub const MAX_SPARSE: usize = 6;
/// The preconditioned iteration keeps its conjugate direction unless more than this
/// fraction of the contact set left or entered it in the last step (restarting at every
/// change, as the plain iteration does, costs 28 % more iterations on the paper's spectrum at
/// 1024²; docs/BENCHMARKS.md).
pub const RESTART_FRACTION: f64 = 0.03;

/// A kept conjugate direction must descend at least this fraction as steeply as the
/// preconditioned gradient, `⟨g, t⟩ ≥ DESCENT_FRACTION ⟨g, z⟩`; otherwise the iteration
/// restarts.
pub const DESCENT_FRACTION: f64 = 0.5;

/// Exact recomputation of `u = K p` after this many linear updates.
pub const RESYNC: usize = 32;

/// The change lists hold up to one node in `CHANGES_PER_NODE` of each block; an update that
/// changes more recomputes `u = K p` instead of correcting it.
pub const CHANGES_PER_NODE: usize = 16;

/// Solver settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverConfig {
    /// Threshold on the complementarity error.
    pub tolerance: f64,
    /// Iteration cap.
    pub max_iterations: usize,
    /// Declare `Stalled` when the error has not reached a new minimum for this many
    /// iterations.
    pub stall_window: usize,
    /// Precondition the conjugate gradient with the inverse elastic operator restricted to
    /// the contact set, `z = P K⁻¹ P g` (`P`: zero off the set, centred on it): one more
    /// convolution per iteration, and an iteration count that grows much more slowly with
    /// n (3.3 times faster for a 16-load 2048² sweep; docs/BENCHMARKS.md). Same fixed point
    /// and error measure. The default; `false` is the plain Polonsky–Keer iteration.
    pub preconditioned: bool,
    /// Extend the preconditioner's input off the free set by the smoothed gradient
    /// ([`Extension`]; used only when `preconditioned`): fewer iterations where the
    /// contact fraction is large, at a pass and two coarse smoothings per iteration. On
    /// (`Extension::default()`) by default; `None` gives `P K⁻¹ P` alone.
    pub extension: Option<Extension>,
    /// Restore the load after the projection `p ← max(p − τ t, 0)` by a uniform offset of
    /// the pressures, `p ← max(p + c, 0)` with `c ≤ 0` such that the mean is `p̄` (the
    /// nearest point of `{p ≥ 0, mean p = p̄}`), instead of rescaling them by one factor;
    /// used (when `preconditioned`) in the iterations that change more than [`MAX_SPARSE`]
    /// nodes of the contact set, which convolve anyway. Rescaling takes the load the
    /// clipped nodes gave up from every pressure of the box, the largest most, which on a
    /// moving contact set perturbs the whole box; the offset takes the same amount from
    /// each. The default (`true`); `false` rescales.
    pub offset_to_load: bool,
    /// Start each load of a sweep from the secant through the last two solutions
    /// (extrapolated linearly in the load, clipped at 0; solver/history.rs) instead of the last
    /// one scaled: about 10 % fewer iterations on rough surfaces, for 0.25 n² doubles and
    /// one convolution per load. The default (`true`).
    pub extrapolate_start: bool,
}

impl Default for SolverConfig {
    fn default() -> Self {
        Self {
            tolerance: 1e-10,
            max_iterations: 5000,
            stall_window: 1000,
            preconditioned: true,
            extension: Some(Extension::default()),
            offset_to_load: true,
            extrapolate_start: true,
        }
    }
}

/// Invalid input to the solver.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ContactError {
    #[error("heights have {got} values but the grid has {expected} (n × n)")]
    BadLength { expected: usize, got: usize },
    #[error("height at row {row}, column {col} is {value}: heights must be finite")]
    NonFinite { row: usize, col: usize, value: f64 },
    #[error("start pressure at row {row}, column {col} is {value}: it must be finite and ≥ 0")]
    BadStart { row: usize, col: usize, value: f64 },
    #[error("mean pressure {0} is invalid: it must be finite and ≥ 0")]
    BadLoad(f64),
    #[error("solver settings invalid: {0}")]
    BadConfig(String),
}

/// A solver bound to one operator and one surface; it keeps its fields between solves so
/// that a load sweep warm-starts each step from the previous solutions (extrapolated to the
/// new load, or scaled to it).
pub struct Solver<'a> {
    op: &'a ElasticOperator,
    heights: &'a [f64],
    height_std: f64,
    flat: bool,
    ws: OperatorWorkspace,
    pressure: Vec<f64>,
    /// `w = u − h`, the deflection minus the heights (the gap up to the rigid-body shift),
    /// stored instead of `u` so that the passes of an iteration need not read `h`.
    separation: Vec<f64>,
    /// The search direction `t`.
    direction: Vec<f64>,
    /// `min w` after a solve: the gap is `w − gap_level`.
    gap_level: f64,
    /// Values per work block: the operator's fixed row blocks (`rows_per_block · n`), so
    /// that the passes fused with the FFT and the plain passes reduce over the same blocks
    /// and sums do not depend on the thread count.
    chunk: usize,
    /// Per block: lane sums of the plain reductions (a sum, the line search's numerator).
    lane_sums: Vec<[f64; LANES]>,
    /// Per block: gradient statistics of the passes not fused with an FFT.
    block_stats: Vec<GradientStats>,
    /// Per block: accumulators of the update pass fused with the inverse FFT.
    update_acc: Vec<UpdateAcc>,
    /// Per-block lane sums of [`Solver::precondition`].
    precondition_acc: Vec<[[f64; LANES]; 6]>,
    /// Per block: lane sums and counts of [`Solver::load_offset`].
    offset_acc: Vec<[[f64; LANES]; 2]>,
    /// Per block: the nodes whose projection departed from the linear step, `(node, Δ)` in
    /// node order, up to the list's capacity (one node in [`CHANGES_PER_NODE`] of the
    /// block; never reallocated).
    changes: Vec<Vec<(usize, f64)>>,
    sparse: Vec<(usize, f64)>,
    /// The preconditioned gradient `z`, in single precision like the transform that makes
    /// it (allocated at the first preconditioned solve).
    preconditioned: Vec<f32>,
    /// The coarse-grid state of the preconditioner's extension, when it is on.
    coarse: Option<extension::Coarse>,
    has_solution: bool,
    /// The mean pressure of the last solution (when `has_solution`).
    solved_mean: f64,
    /// The solution before the last, for the extrapolated start.
    history: history::History,
    /// Whether `separation` is `K p − h` for the current `pressure`, computed exactly (after
    /// a converged solve; not after [`Self::set_start`]).
    separation_exact: bool,
}

impl<'a> Solver<'a> {
    /// Check the surface and allocate every buffer: 4 n² doubles (the transform's rows, `p`,
    /// `w`, `t`), n²/8 for the lists of changed nodes, and n²/2 more at the first
    /// preconditioned solve (`z`, single precision), n²/4 at a sweep's second load (the
    /// solution before the last, bfloat16); besides the heights and the operator's
    /// kernel (n²/2).
    pub fn new(op: &'a ElasticOperator, heights: &'a [f64]) -> Result<Self, ContactError> {
        let n = op.grid().n();
        let len = n * n;
        if heights.len() != len {
            return Err(ContactError::BadLength {
                expected: len,
                got: heights.len(),
            });
        }
        if let Some((i, v)) = heights.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(ContactError::NonFinite {
                row: i / n,
                col: i % n,
                value: *v,
            });
        }
        let mean = heights.iter().sum::<f64>() / len as f64;
        let height_std =
            (heights.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / len as f64).sqrt();
        let chunk = op.rows_per_block() * n;
        let blocks = len.div_ceil(chunk);
        let (lo, hi) = heights
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        Ok(Self {
            op,
            heights,
            height_std,
            flat: lo == hi,
            ws: op.make_workspace(),
            pressure: crate::pages::filled(len, 0.0),
            separation: crate::pages::filled(len, 0.0),
            direction: crate::pages::filled(len, 0.0),
            gap_level: 0.0,
            chunk,
            lane_sums: vec![[0.0; LANES]; blocks],
            block_stats: vec![GradientStats::EMPTY; blocks],
            update_acc: (0..blocks).map(|_| UpdateAcc::new()).collect(),
            precondition_acc: vec![[[0.0; LANES]; 6]; blocks],
            offset_acc: vec![[[0.0; LANES]; 2]; blocks],
            changes: (0..blocks)
                .map(|_| Vec::with_capacity((chunk / CHANGES_PER_NODE).max(MAX_SPARSE)))
                .collect(),
            sparse: Vec::with_capacity(MAX_SPARSE),
            preconditioned: Vec::new(),
            coarse: None,
            has_solution: false,
            solved_mean: 0.0,
            history: history::History::new(),
            separation_exact: false,
        })
    }

    /// Standard deviation of the heights (the error's length scale).
    pub fn height_std(&self) -> f64 {
        self.height_std
    }

    /// Pressure of the last solve (row-major).
    pub fn pressure(&self) -> &[f64] {
        &self.pressure
    }

    /// Gap `(K p − h) − min(K p − h)` of the last solve (row-major), computed as it is read.
    pub fn gap(&self) -> impl ExactSizeIterator<Item = f64> + '_ {
        let level = self.gap_level;
        self.separation.iter().map(move |&w| w - level)
    }

    /// Number of nodes in contact (`p > 0`) in the last solve.
    pub fn contact_count(&self) -> usize {
        self.pressure.iter().filter(|&&p| p > 0.0).count()
    }

    /// Start the next [`Self::solve`] from `pressure` (row-major, finite, ≥ 0, not all
    /// zero) instead of the previous solutions; it is scaled to the new load first, and the
    /// next solve does not extrapolate through it. For warm starts other than the sweep's
    /// own (compared in `cargo bench --bench warm_start`).
    pub fn set_start(&mut self, pressure: &[f64]) -> Result<(), ContactError> {
        let n = self.op.grid().n();
        if pressure.len() != self.pressure.len() {
            return Err(ContactError::BadLength {
                expected: self.pressure.len(),
                got: pressure.len(),
            });
        }
        if let Some((i, v)) = pressure
            .iter()
            .enumerate()
            .find(|(_, v)| !(v.is_finite() && **v >= 0.0))
        {
            return Err(ContactError::BadStart {
                row: i / n,
                col: i % n,
                value: *v,
            });
        }
        if pressure.iter().all(|&p| p == 0.0) {
            return Err(ContactError::BadConfig(
                "a start pressure must not be zero everywhere".into(),
            ));
        }
        self.pressure.copy_from_slice(pressure);
        self.history.forget();
        self.has_solution = true;
        self.separation_exact = false;
        Ok(())
    }

    /// Solve for the mean pressure `mean_pressure` (≥ 0), warm-starting from the previous
    /// solutions if there are any: extrapolated from the last two
    /// ([`SolverConfig::extrapolate_start`]) or the last one, scaled to the new load.
    pub fn solve(
        &mut self,
        mean_pressure: f64,
        cfg: &SolverConfig,
    ) -> Result<SolveReport, ContactError> {
        check_request(mean_pressure, cfg)?;
        self.prepare_parts(cfg);
        let target = mean_pressure;
        let mut report = SolveReport {
            status: Status::Converged,
            iterations: 0,
            error: 0.0,
            error_history: Vec::with_capacity(cfg.max_iterations.min(4096) + 2),
            convolutions: 0,
            mean_pressure,
        };
        if target == 0.0 || self.flat {
            self.uniform_solution(target);
            report.error_history.push(0.0);
            return Ok(report);
        }
        self.warm_start(target, cfg);
        let mut stats = self.start(target, &mut report);
        self.has_solution = false;
        self.separation_exact = false;
        let len = self.pressure.len() as f64;
        let self_influence = self.op.self_influence();
        let mut it = Iteration::new();
        loop {
            // The error from the gradient's statistics on the contact set.
            let GradientStats {
                contact_nodes: n_s,
                sum_g,
                sum_g2,
                sum_pg,
                sum_p,
                min_g,
            } = stats;
            let mean_g = sum_g / n_s;
            let g_norm = (sum_g2 - n_s * mean_g * mean_g).max(0.0);
            let error = (sum_pg - min_g * sum_p) / (sum_p * self.height_std);
            if error <= cfg.tolerance && !it.exact {
                // Confirm with an exact deflection (and the exact load) before declaring
                // convergence.
                stats = self.exact_deflection(target * len / sum_p, it.shift);
                report.convolutions += 1;
                it.exact = true;
                it.linear_steps = 0;
                continue;
            }
            if let Some(status) = it.verdict(error, cfg, &mut report) {
                report.status = status;
                break;
            }
            report.iterations += 1;
            // The direction (fused with the forward FFT), then K t and the curvature ⟨t, K t⟩
            // (Parseval), and the exact line search.
            let level = it.shift + mean_g;
            let (denominator, numerator) =
                self.search_direction(cfg, level, error, g_norm, &mut it, &mut report);
            report.convolutions += 1;
            let tau = if denominator > 0.0 && denominator.is_finite() && numerator.is_finite() {
                numerator / denominator
            } else {
                1.0 / self_influence
            };
            // Fused with the inverse FFT: step, project, re-admit interpenetrating nodes;
            // speculatively update the deflection linearly (u − τ K t) and gather the next
            // gradient statistics.
            let (totals, linear_stats) =
                self.update_from_transform(tau, level, level, !cfg.preconditioned);
            it.after_step(&totals, cfg, level);
            if totals.sum_p <= 0.0 {
                self.pressure.fill(target);
                stats = self.exact_deflection(1.0, it.shift);
                report.convolutions += 1;
                it.exact = true;
                it.restart = true;
                it.changes = None;
                continue;
            }
            stats = self.restore_load(cfg, &totals, linear_stats, target, &mut it, &mut report);
            it.exact = it.linear_steps == 0;
        }
        self.finish_gap();
        self.has_solution = report.status == Status::Converged;
        self.solved_mean = target;
        // A converged state was confirmed by an exact deflection (or is the flat or zero
        // solution, `w = −h`).
        self.separation_exact = self.has_solution;
        Ok(report)
    }
}

/// An error for a load or settings the solver cannot take.
fn check_request(mean_pressure: f64, cfg: &SolverConfig) -> Result<(), ContactError> {
    if !(mean_pressure.is_finite() && mean_pressure >= 0.0) {
        return Err(ContactError::BadLoad(mean_pressure));
    }
    if !(cfg.tolerance > 0.0 && cfg.tolerance.is_finite()) || cfg.max_iterations == 0 {
        return Err(ContactError::BadConfig(format!(
            "tolerance {} must be finite and > 0, max_iterations {} must be ≥ 1",
            cfg.tolerance, cfg.max_iterations
        )));
    }
    if let Some(extension) = &cfg.extension {
        extension.check().map_err(ContactError::BadConfig)?;
    }
    Ok(())
}

impl Solver<'_> {
    /// The exact solution at zero load or on a flat surface: uniform `p = target`, `u = 0`.
    fn uniform_solution(&mut self, target: f64) {
        self.pressure.fill(target);
        // u = 0: w = −h.
        let h = self.heights;
        self.separation
            .par_iter_mut()
            .zip(h.par_iter())
            .for_each(|(w, &h)| *w = -h);
        self.finish_gap();
        self.has_solution = target > 0.0;
        self.solved_mean = target;
        self.separation_exact = true;
    }

    /// The start of a solve: the previous solution scaled to the new load, or uniform
    /// pressure, with the gradient statistics of that state (every update computes them in
    /// the pass that makes the state). After a converged solve `w = K p − h` is exact, and
    /// `K (s p) = s K p`, so the scaled start needs a pass, not a convolution.
    fn start(&mut self, target: f64, report: &mut SolveReport) -> GradientStats {
        let len = self.pressure.len();
        let previous_total: f64 = self.chunked_sum(|p| p);
        let warm = self.has_solution && previous_total > 0.0;
        let scale = if warm {
            target * len as f64 / previous_total
        } else {
            1.0
        };
        if warm && self.separation_exact {
            self.sparse.clear();
            self.sparse_update(scale, 0.0)
        } else {
            if warm {
                self.pressure.par_iter_mut().for_each(|p| *p *= scale);
            } else {
                self.pressure.fill(target);
            }
            report.convolutions += 1;
            self.exact_deflection(1.0, 0.0)
        }
    }
}
