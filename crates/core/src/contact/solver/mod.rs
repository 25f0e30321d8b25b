//! Polonsky–Keer constrained conjugate gradient under load control (mean pressure imposed),
//! pressure as the unknown (Polonsky & Keer 1999; Rey, Anciaux & Molinari 2017).
//!
//! Minimises `½⟨p, K p⟩ − ⟨p, h⟩` subject to a constraint on each node's pressure (`p ≥ 0`,
//! [`NonNegative`], unless [`Solver::with_constraint`] says otherwise) and `mean(p) = p̄`.
//! The gap is `g = (K p − h) − min(K p − h) ≥ 0`, zero in contact.
//!
//! **Convergence** (docs/CONVENTIONS.md): the dimensionless complementarity error
//! `err = Σ p_i g_i / (Σ p_i · σ_h)`, with `σ_h` the standard deviation of the heights about
//! their mean; it is zero only at the exact discrete solution, and never larger than
//! Tamaas's measure (which divides by the `ddof = 1` deviation), so a tolerance here is at
//! least as strict as the same tolerance there. Under a ceiling it is measured on both
//! bounds (`bounded.rs`).
//!
//! **The iteration** ([`Solver::solve`]): start (`start.rs`: the exact solution at zero load
//! or on a flat surface, else the last solutions carried to the new load); then, until the
//! error is below the tolerance (confirmed by an exact deflection) or the iteration stalls:
//! the search direction (`iteration.rs`: the gradient, preconditioned on the free set when a
//! preconditioner is chosen, conjugate to the last one unless the iteration restarts), fused
//! with the forward FFT of `K t`; the exact line search from the curvature `⟨t, K t⟩`
//! (Parseval, inside the convolution); the step and the projection by the constraint, fused
//! with the inverse FFT (`passes.rs`, `update.rs`), which also updates the deflection
//! linearly and gathers the next gradient's statistics; and the load restored (`load.rs`:
//! a uniform offset of the pressures or a rescaling, then the cheapest exact deflection).
//!
//! **Parts.** An [`Operator`] (`operator.rs`) is `K`: today the periodic half-space,
//! [`ElasticOperator`]. A [`Constraint`] (`constraint.rs`) says what the projection keeps and
//! which nodes are in contact. A preconditioner (`preconditioner.rs`, chosen in one place,
//! `parts.rs`, from [`SolverConfig`]) is none (the plain iteration), `P K⁻¹ P` on the free set
//! (`restricted.rs`), or that extended off the free set by the smoothed gradient with its near
//! and far terms and the block deflation as layers (`extension.rs`, `deflation.rs`); the far
//! term, the deflation and the free set's entry margin are used on large boxes only
//! ([`Extension::large_box`]). docs/ARCHITECTURE.md says how to add either part.
//!
//! **Exactness.** Every field the solver keeps and every convolution by `K` is `f64`; only
//! the preconditioned gradient `z = K⁻¹ P g` is `f32`, a rounding of the preconditioner, not
//! of the problem. All reductions use the FFT's fixed row blocks, so results are
//! bit-identical whatever the number of threads; the AVX2 row kernels do the scalar code's
//! operations in its order (unit tests compare them bit for bit). The deflection `u = K p` is
//! recomputed exactly every 32 linear updates (`load::RESYNC`) and before convergence is
//! declared.
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
//! - under a ceiling `p_max` ([`Ceiling`]): a mean pressure of `p_max` is the uniform field
//!   `p_max`, every node saturated, in 0 iterations; a mean above it is an error before
//!   solving ([`ContactError::AboveCeiling`]), naming both;
//! - no progress for `stall_window` iterations, or a non-finite error: `Stalled`;
//!   `max_iterations` reached: `MaxIterations`. Neither is ever a result that looks valid.
//!
//! Measurements of each part (iterations saved, cost per iteration): docs/ARCHITECTURE.md and
//! docs/BENCHMARKS.md.

mod bounded;
mod ceiling;
#[cfg(test)]
mod ceiling_tests;
mod constraint;
mod deflation;
mod extension;
mod history;
mod iteration;
mod level;
mod load;
mod operator;
mod parts;
mod passes;
mod preconditioner;
mod report;
mod restricted;
mod rows;
mod start;
#[cfg(test)]
mod test_support;
#[cfg(test)]
mod tests;
mod update;

use super::elastic::ElasticOperator;
pub use ceiling::Ceiling;
pub use constraint::{Constraint, NonNegative};
pub use extension::Extension;
use iteration::Iteration;
pub use operator::Operator;
use passes::{CHANGES_PER_NODE, MAX_SPARSE};
pub use report::{SolveReport, Status};
use rows::{GradientStats, LANES};
use update::UpdateAcc;

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
    #[error(
        "mean pressure {mean} is above the pressure ceiling {ceiling}: no pressure field \
         bounded by the ceiling carries it (lower the load or raise the hardness)"
    )]
    AboveCeiling { mean: f64, ceiling: f64 },
    #[error("solver settings invalid: {0}")]
    BadConfig(String),
}

/// A solver bound to one operator ([`ElasticOperator`] unless given), one surface and one
/// constraint on the pressure ([`NonNegative`] unless given); it keeps its fields between solves so that a load sweep
/// warm-starts each step from the previous solutions (extrapolated to the new load, or
/// scaled to it).
pub struct Solver<'a, C: Constraint = NonNegative, O: Operator = ElasticOperator> {
    op: &'a O,
    constraint: C,
    heights: &'a [f64],
    height_std: f64,
    flat: bool,
    ws: O::Workspace,
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
    /// Per block: lane sums and counts of [`Solver::load_offset`].
    offset_acc: Vec<[[f64; LANES]; 2]>,
    /// Per block: the nodes whose projection departed from the linear step, `(node, Δ)` in
    /// node order, up to the list's capacity (one node in [`CHANGES_PER_NODE`] of the
    /// block; never reallocated).
    changes: Vec<Vec<(usize, f64)>>,
    /// Per block, under a ceiling: the pressures a load offset moves, and the sum of the
    /// others (`Solver::gather_moving`); empty until then.
    moving: Vec<(Vec<f64>, f64)>,
    sparse: Vec<(usize, f64)>,
    /// The preconditioner (module `preconditioner`; none for the plain iteration), chosen
    /// at the first solve and again only when the settings that choose it change.
    preconditioner: Option<Box<dyn preconditioner::Preconditioner<C, O>>>,
    choice: Option<parts::Choice>,
    /// The extended preconditioner, set aside for the rest of a solve that stagnated with
    /// it under a ceiling (`Solver::fall_back`); restored at the next solve.
    suspended: Option<Box<dyn preconditioner::Preconditioner<C, O>>>,
    has_solution: bool,
    /// The mean pressure of the last solution (when `has_solution`).
    solved_mean: f64,
    /// Under a ceiling, the nodes of positive pressure when the gap was last levelled
    /// (`Solver::finish_gap`, after every solve): the last solution's contact set.
    solved_contact: usize,
    /// The solution before the last, for the extrapolated start.
    history: history::History,
    /// Whether `separation` is `K p − h` for the current `pressure`, computed exactly (after
    /// a converged solve; not after [`Self::set_start`]).
    separation_exact: bool,
}

impl<'a> Solver<'a> {
    /// [`Self::with_constraint`] for frictionless elastic contact, `p ≥ 0`.
    pub fn new(op: &'a ElasticOperator, heights: &'a [f64]) -> Result<Self, ContactError> {
        Self::with_constraint(op, heights, NonNegative)
    }
}

impl<'a, C: Constraint, O: Operator> Solver<'a, C, O> {
    /// Check the surface and allocate every buffer: 4 n² doubles (the transform's rows, `p`,
    /// `w`, `t`), n²/8 for the lists of changed nodes, and n²/2 more at the first
    /// preconditioned solve (`z`, single precision), n²/4 at a sweep's second load (the
    /// solution before the last, bfloat16); besides the heights and the operator's
    /// kernel (n²/2).
    pub fn with_constraint(
        op: &'a O,
        heights: &'a [f64],
        constraint: C,
    ) -> Result<Self, ContactError> {
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
            constraint,
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
            offset_acc: vec![[[0.0; LANES]; 2]; blocks],
            // Under a ceiling the load restoration reads where the step left every node it
            // projected: the lists hold them all.
            changes: (0..blocks)
                .map(|_| {
                    let listed = if C::BOUNDED {
                        chunk
                    } else {
                        chunk / CHANGES_PER_NODE
                    };
                    Vec::with_capacity(listed.max(MAX_SPARSE))
                })
                .collect(),
            moving: vec![(Vec::new(), 0.0); if C::BOUNDED { blocks } else { 0 }],
            sparse: Vec::with_capacity(MAX_SPARSE),
            preconditioner: None,
            choice: None,
            suspended: None,
            has_solution: false,
            solved_mean: 0.0,
            solved_contact: 0,
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

    /// The constraint's ceiling `p_max` (`+∞` when unbounded).
    pub fn ceiling(&self) -> f64 {
        self.constraint.ceiling()
    }

    /// Number of nodes on the constraint's ceiling (`p = p_max`; none when unbounded) in
    /// the last solve.
    pub fn saturated_count(&self) -> usize {
        let c = self.constraint;
        self.pressure.iter().filter(|&&p| c.saturated(p)).count()
    }

    /// The plastic displacement of the last solve (row-major): on the saturated nodes the
    /// interpenetration `−gap = ℓ − w ≥ 0` below the level of the unsaturated contact, 0
    /// elsewhere (everywhere when unbounded).
    pub fn plastic_displacement(&self) -> impl ExactSizeIterator<Item = f64> + '_ {
        let (c, level) = (self.constraint, self.gap_level);
        self.pressure
            .iter()
            .zip(&self.separation)
            .map(move |(&p, &w)| {
                if c.saturated(p) {
                    (level - w).max(0.0)
                } else {
                    0.0
                }
            })
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
        let ceiling = self.constraint.ceiling();
        if mean_pressure > ceiling {
            return Err(ContactError::AboveCeiling {
                mean: mean_pressure,
                ceiling,
            });
        }
        self.prepare_parts(cfg);
        let target = mean_pressure;
        let mut report = SolveReport::new(mean_pressure, cfg.max_iterations);
        // At the ceiling's mean the only admissible field is uniform: every node saturated.
        if target == 0.0 || self.flat || target == ceiling {
            self.uniform_solution(target);
            report.error_history.push(0.0);
            return Ok(report);
        }
        self.warm_start(target, cfg);
        let mut stats = self.start(target, &mut report);
        self.has_solution = false;
        self.separation_exact = false;
        let len = self.pressure.len() as f64;
        let mut it = Iteration::new();
        loop {
            // The error from the gradient's statistics on the contact set.
            let error = self.complementarity_error(&stats, it.shift, cfg.tolerance);
            if error <= cfg.tolerance && !it.exact {
                // Confirm with an exact deflection (and the exact load) before declaring
                // convergence.
                stats = if C::BOUNDED {
                    self.deflection_at_load(target, stats.sum_p, it.shift, &mut it.restart)
                } else {
                    self.exact_deflection(target * len / stats.sum_p, it.shift)
                };
                report.convolutions += 1;
                (it.exact, it.linear_steps) = (true, 0);
                continue;
            }
            if let Some(status) = it.verdict(error, cfg, &mut report) {
                // A state that does not carry the load is no solution, whatever its error.
                let off_load = (stats.sum_p - target * len).abs() > LOAD_ROUNDING * target * len;
                report.status = if status == Status::Converged && off_load {
                    Status::Stalled
                } else {
                    status
                };
                break;
            }
            self.fall_back(&mut it, &report);
            report.iterations += 1;
            // The direction (fused with the forward FFT), then K t and the curvature ⟨t, K t⟩
            // (Parseval), and the exact line search.
            let level = it.shift + self.gradient_level(&stats);
            let (denominator, numerator) =
                self.search_direction(level, error, stats.g_norm(), &mut it, &mut report);
            report.convolutions += 1;
            let tau = self.step_length(denominator, numerator);
            // Fused with the inverse FFT: step, project, re-admit interpenetrating nodes;
            // speculatively update the deflection linearly (u − τ K t) and gather the next
            // gradient statistics.
            let (totals, linear_stats) =
                self.update_from_transform(tau, level, level, !cfg.preconditioned);
            it.after_step(&totals, cfg, level);
            stats = if totals.sum_p > 0.0 {
                let stats =
                    self.restore_load(cfg, &totals, linear_stats, target, &mut it, &mut report);
                it.exact = it.linear_steps == 0;
                stats
            } else {
                self.restart_uniform(target, &mut it, &mut report)
            };
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

/// A converged state carries the load to this relative rounding (every exact state is
/// brought to it to 1e-12 or closer); beyond it the solve reports a stall, never convergence.
const LOAD_ROUNDING: f64 = 1e-10;

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
