//! The parts of one iteration of [`Solver::solve`]: the state an iteration hands to the next
//! ([`Iteration`]), the verdict on the error, the search direction and the load restored
//! after a step. `solve` itself reads as the algorithm; each part here is one step of it, in
//! the order `solve` calls them, with exactly the operations it always did.

use super::config::SolverConfig;
use super::constraint::Constraint;
use super::level::Level;
use super::operator::Operator;
use super::parts;
use super::passes::UpdateTotals;
use super::preconditioner::{Fields, Preconditioner};
use super::report::{SolveReport, Status};
use super::restricted::Restricted;
use super::rows::GradientStats;
use super::state::Solver;

/// The preconditioned iteration keeps its conjugate direction unless more than this
/// fraction of the contact set left or entered it in the last step (restarting at every
/// change, as the plain iteration does, costs 28 % more iterations on the paper's spectrum at
/// 1024²; docs/BENCHMARKS.md).
pub(super) const RESTART_FRACTION: f64 = 0.03;

/// A kept conjugate direction must descend at least this fraction as steeply as the
/// preconditioned gradient, `⟨g, t⟩ ≥ DESCENT_FRACTION ⟨g, z⟩`; otherwise the iteration
/// restarts.
pub(super) const DESCENT_FRACTION: f64 = 0.5;

/// Iterations without a new least error after which a bounded solve gives up the extended
/// preconditioner for `P K⁻¹ P` ([`Solver::set_extension_aside`]); converging solves make a new least
/// error every few iterations.
pub(super) const FALLBACK_WINDOW: usize = 10;

/// What one iteration of [`Solver::solve`] hands to the next.
pub struct Iteration {
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

impl<C: Constraint, O: Operator> Solver<'_, C, O> {
    /// The preconditioner a solve with `cfg` uses ([`parts::choose`]), chosen anew
    /// only when the settings that choose it changed: a sweep keeps its part, and the state
    /// of the part's layers, from load to load.
    pub(super) fn prepare_parts(&mut self, cfg: &SolverConfig) {
        if let Some(extended) = self.parts.suspended.take() {
            self.parts.preconditioner = Some(extended);
        }
        let choice = parts::choice(cfg);
        if self.parts.choice != Some(choice) {
            self.parts.preconditioner = parts::choose(cfg, self.op);
            self.parts.choice = Some(choice);
        }
    }

    /// Once the error has not improved for [`FALLBACK_WINDOW`] iterations
    /// with the extended preconditioner, sets it aside for the rest of the solve and goes on
    /// with `P K⁻¹ P` from a fresh direction (the ceiling's
    /// [`super::complementarity::Complementarity::fall_back`]). Where a large part of the contact set is
    /// saturated, the extension's long modes can make each step move a quarter of the
    /// active set across the bounds and back, and the error cycles near 5e-3 for good
    /// (a 1024² surface of one λ_l at 𝓗 = 0.5, W/W0 = 0.035: the `it` test
    /// `extension_stagnation_under_a_ceiling_falls_back`); `P K⁻¹ P` converges there.
    pub(super) fn set_extension_aside(&mut self, it: &mut Iteration, report: &SolveReport) {
        let extended = matches!(self.parts.choice, Some((true, Some(_))));
        if extended
            && self.parts.suspended.is_none()
            && report.iterations - it.best_at >= FALLBACK_WINDOW
        {
            let restricted: Box<dyn Preconditioner<C, O>> = Box::new(Restricted::new(self.op));
            self.parts.suspended = self.parts.preconditioner.replace(restricted);
            it.restart = true;
        }
    }

    /// The exact line search's step `⟨g, t⟩ / ⟨t, K t⟩`; where that is not a finite positive
    /// ratio (a direction of no curvature), the Jacobi step `1 / K_ii`.
    pub(super) fn step_length(&self, denominator: f64, numerator: f64) -> f64 {
        if denominator > 0.0 && denominator.is_finite() && numerator.is_finite() {
            numerator / denominator
        } else {
            1.0 / self.op.self_influence()
        }
    }

    /// After a step that projected all pressure away: the uniform pressure `target`, its
    /// exact deflection, and a fresh direction.
    pub(super) fn restart_uniform(
        &mut self,
        target: f64,
        it: &mut Iteration,
        report: &mut SolveReport,
    ) -> GradientStats {
        self.fields.pressure.fill(target);
        let stats = self.exact_deflection(1.0, it.shift);
        report.convolutions += 1;
        (it.exact, it.restart, it.changes) = (true, true, None);
        stats
    }

    /// The search direction from the gradient at `level` (mean of `w` on the contact set;
    /// `g_norm` its `⟨g, g⟩`): preconditioned on the free set when the solve has a
    /// preconditioner ([`Solver::prepare_parts`]), conjugate to
    /// the last one unless the iteration restarts or it would barely descend
    /// ([`DESCENT_FRACTION`]), then transformed. Returns `(⟨t, K t⟩, ⟨g, t⟩)` for the exact
    /// line search.
    pub(super) fn search_direction(
        &mut self,
        level: f64,
        error: f64,
        g_norm: f64,
        it: &mut Iteration,
        report: &mut SolveReport,
    ) -> (f64, f64) {
        // ⟨g, z⟩ replaces ⟨g, g⟩ in β when preconditioned.
        let (height_std, constraint) = (self.height_std, self.constraint);
        let mut fields = Fields {
            op: self.op,
            ws: &mut self.ws,
            chunk: self.blocks.chunk,
            pressure: &self.fields.pressure,
            separation: &self.fields.separation,
            direction: &mut self.fields.direction,
        };
        let mut preconditioner = self.parts.preconditioner.as_deref_mut();
        let preconditioned = preconditioner.as_mut().map(|part| {
            // The part may switch its layers as the contact set settles; the direction
            // restarts when it does. A node joins F below the level less the part's margin.
            it.restart |= part.settle(it.changes);
            let entry = level - part.entry_margin(error * height_std);
            report.convolutions += 1;
            part.precondition(
                &mut fields,
                Level {
                    mean: level,
                    entry,
                    constraint,
                },
            )
        });
        let g_dot = preconditioned.map_or(g_norm, |sums| sums.g_dot_z);
        let mut beta = if it.restart || it.g_norm_old <= 0.0 {
            0.0
        } else {
            g_dot / it.g_norm_old
        };
        it.g_norm_old = g_dot;
        match preconditioned.zip(preconditioner) {
            Some((sums, part)) => {
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
                    part.direction(&mut fields, [sums.z_mean, beta, direction_mean]),
                    conjugate(beta),
                )
            }
            None => self.direction_and_transform(level, beta, it.direction_mean),
        }
    }
}
