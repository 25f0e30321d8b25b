//! The parts of one iteration of [`Solver::solve`]: the state an iteration hands to the next
//! ([`Iteration`]), the verdict on the error, the search direction and the load restored
//! after a step. `solve` itself reads as the algorithm; each part here is one step of it, in
//! the order `solve` calls them, with exactly the operations it always did.

use super::level::Level;
use super::passes::UpdateTotals;
use super::rows::GradientStats;
use super::{
    extension, SolveReport, Solver, SolverConfig, Status, DESCENT_FRACTION, MAX_SPARSE,
    RESTART_FRACTION,
};

/// What one iteration of [`Solver::solve`] hands to the next.
pub(super) struct Iteration {
    /// The deflection `u = K p` was last computed exactly (not updated linearly).
    pub exact: bool,
    /// Linear updates of `u` since the last exact one.
    pub linear_steps: usize,
    /// The level the separation is measured from (the last gradient's mean).
    pub shift: f64,
    /// The next direction starts afresh (β = 0).
    pub restart: bool,
    /// The last iteration's changes to the contact set and its size (none yet).
    pub changes: Option<(usize, f64)>,
    /// The previous `⟨g, z⟩` (or `⟨g, g⟩` unpreconditioned), β's denominator.
    pub g_norm_old: f64,
    /// The smallest error so far and the iteration it was reached at (the stall test).
    pub best: f64,
    pub best_at: usize,
    /// The mean of the previous direction over the set it is centred on.
    pub direction_mean: f64,
}

impl Iteration {
    pub fn new() -> Self {
        Iteration {
            exact: true,
            linear_steps: 0,
            shift: 0.0,
            restart: true,
            changes: None,
            g_norm_old: 0.0,
            best: f64::INFINITY,
            best_at: 0,
            direction_mean: 0.0,
        }
    }

    /// Record `error` (confirmed by an exact deflection when below the tolerance): the status
    /// that ends the solve, if any — a non-finite error, convergence, no progress over
    /// [`SolverConfig::stall_window`] iterations, or the iteration limit.
    pub fn verdict(
        &mut self,
        error: f64,
        cfg: &SolverConfig,
        report: &mut SolveReport,
    ) -> Option<Status> {
        report.error_history.push(error);
        report.error = error;
        if !error.is_finite() {
            return Some(Status::Stalled);
        }
        if error <= cfg.tolerance {
            return Some(Status::Converged);
        }
        if error < self.best {
            self.best = error;
            self.best_at = report.iterations;
        } else if report.iterations - self.best_at >= cfg.stall_window {
            return Some(Status::Stalled);
        }
        if report.iterations >= cfg.max_iterations {
            return Some(Status::MaxIterations);
        }
        None
    }

    /// After the step: the new direction's mean, whether the next one restarts (the plain
    /// iteration whenever a node is re-admitted, as Polonsky & Keer; the preconditioned one
    /// only when the free set changed by more than [`RESTART_FRACTION`] of the contact set),
    /// the changes and the level.
    pub fn after_step(&mut self, totals: &UpdateTotals, cfg: &SolverConfig, level: f64) {
        self.direction_mean = if totals.contact_nodes > 0.0 {
            totals.sum_t_kept / totals.contact_nodes
        } else {
            0.0
        };
        self.restart = if cfg.preconditioned {
            totals.changed as f64 > RESTART_FRACTION * totals.contact_nodes
        } else {
            totals.readmitted > 0
        };
        self.changes = Some((totals.changed, totals.contact_nodes));
        self.shift = level;
    }
}

impl Solver<'_> {
    /// Fields and parts a solve with `cfg` needs: the preconditioned gradient's field, and the
    /// extension's coarse space, made anew when its settings changed.
    pub(super) fn prepare_parts(&mut self, cfg: &SolverConfig) {
        let len = self.pressure.len();
        if cfg.preconditioned && self.preconditioned.len() != len {
            self.preconditioned = crate::pages::filled(len, 0.0);
        }
        match cfg.extension.filter(|_| cfg.preconditioned) {
            Some(settings) => {
                if self.coarse.as_ref().map(|c| c.settings) != Some(settings) {
                    let n = self.op.grid().n();
                    let mut coarse = extension::Coarse::new(n, self.op.rows_per_block(), settings);
                    coarse.deflate(self.op);
                    self.coarse = Some(coarse);
                }
            }
            None => self.coarse = None,
        }
    }

    /// The start of a load after a converged one: extrapolated from the last two solutions
    /// ([`SolverConfig::extrapolate_start`]), else the history is forgotten (and
    /// [`Solver::start`] scales the last solution).
    pub(super) fn warm_start(&mut self, target: f64, cfg: &SolverConfig) {
        if cfg.extrapolate_start && self.has_solution && self.separation_exact {
            if self
                .history
                .advance(&mut self.pressure, self.solved_mean, target)
            {
                self.separation_exact = false;
            }
        } else {
            self.history.forget();
        }
    }

    /// The search direction from the gradient at `level` (mean of `w` on the contact set;
    /// `g_norm` its `⟨g, g⟩`): preconditioned on the free set when `cfg` says so, conjugate to
    /// the last one unless the iteration restarts or it would barely descend
    /// ([`DESCENT_FRACTION`]), then transformed. Returns `(⟨t, K t⟩, ⟨g, t⟩)` for the exact
    /// line search.
    pub(super) fn search_direction(
        &mut self,
        cfg: &SolverConfig,
        level: f64,
        error: f64,
        g_norm: f64,
        it: &mut Iteration,
        report: &mut SolveReport,
    ) -> (f64, f64) {
        // ⟨g, z⟩ replaces ⟨g, g⟩ in β when preconditioned.
        let preconditioned = if cfg.preconditioned {
            // The extension's near term is used once the contact set has settled; the
            // direction restarts when the preconditioner changes. On large boxes a node
            // joins F only below the level less a margin that falls with the error.
            let mut entry = level;
            if let Some(coarse) = self.coarse.as_mut() {
                it.restart |= coarse.settle(it.changes);
                entry -= coarse.entry_margin(error * self.height_std);
            }
            report.convolutions += 1;
            Some(self.precondition(Level { mean: level, entry }))
        } else {
            None
        };
        let g_dot = preconditioned.map_or(g_norm, |sums| sums.g_dot_z);
        let mut beta = if it.restart || it.g_norm_old <= 0.0 {
            0.0
        } else {
            g_dot / it.g_norm_old
        };
        it.g_norm_old = g_dot;
        match preconditioned {
            Some(sums) => {
                // The old direction is centred on the current free set.
                it.direction_mean = sums.t_old_mean;
                let direction_mean = it.direction_mean;
                // Σ_F g t = ⟨g, z − z̄⟩ + β (Σ_F g t_old − t̄ Σ_F g), from the sums of
                // `precondition`, so the direction pass need not sum.
                let conjugate = |beta: f64| {
                    sums.g_dot_z + beta * (sums.g_dot_t_old - direction_mean * sums.g_sum)
                };
                // A conjugate direction kept across changes of the set may descend little or
                // not at all: then restart from the preconditioned gradient.
                if conjugate(beta) < DESCENT_FRACTION * sums.g_dot_z {
                    beta = 0.0;
                }
                (
                    self.preconditioned_direction_and_transform(sums.z_mean, beta, direction_mean),
                    conjugate(beta),
                )
            }
            None => self.direction_and_transform(level, beta, it.direction_mean),
        }
    }

    /// After a step that left the load `totals.sum_p > 0`: the load `target` per node restored,
    /// by a uniform offset of the pressures where the step changed many nodes (`u = K p`
    /// recomputed: one convolution, as a correction of that many changes would take), else
    /// by a rescaling with `u` updated linearly or exactly; the next gradient's statistics.
    /// When the load is below the rounding of the largest pressures (W/W0 ≈ 1e-20) the
    /// offset's sum cancels to zero, and the rescaling restores it instead.
    pub(super) fn restore_load(
        &mut self,
        cfg: &SolverConfig,
        totals: &UpdateTotals,
        linear_stats: GradientStats,
        target: f64,
        it: &mut Iteration,
        report: &mut SolveReport,
    ) -> GradientStats {
        let total = totals.sum_p;
        let load = target * self.pressure.len() as f64;
        let offset = (cfg.preconditioned
            && cfg.offset_to_load
            && totals.changed > MAX_SPARSE
            && total > load)
            .then(|| self.load_offset(load, total, totals.contact_nodes))
            .filter(|&(_, shifted)| shifted > 0.0);
        if let Some((offset, shifted)) = offset {
            report.convolutions += 1;
            it.linear_steps = 0;
            self.offset_deflection(offset, load / shifted, it.shift)
        } else {
            self.next_deflection(
                totals,
                linear_stats,
                load / total,
                it.shift,
                &mut it.linear_steps,
                report,
            )
        }
    }
}
