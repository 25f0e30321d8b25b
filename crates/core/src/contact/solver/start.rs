//! The start of a solve: the exact solution where there is nothing to solve (zero load, a
//! flat surface), else the previous solutions carried to the new load (extrapolated from the
//! last two, or the last one scaled), else a uniform pressure.

use rayon::prelude::*;

use super::complementarity::Complementarity;
use super::config::SolverConfig;
use super::operator::Operator;
use super::report::SolveReport;
use super::rows::GradientStats;
use super::state::Solver;

impl<C: Complementarity, O: Operator> Solver<'_, C, O> {
    /// The start of a load after a converged one: extrapolated from the last two solutions
    /// ([`SolverConfig::extrapolate_start`]), else the history is forgotten (and
    /// the start scales the last solution, or under a ceiling may step from it).
    pub(super) fn warm_start(&mut self, target: f64, cfg: &SolverConfig) {
        if cfg.extrapolate_start
            && self.warm.has_solution
            && self.warm.separation_exact
            && !C::beyond_contact_set(self, target)
        {
            if self.warm.history.advance(
                self.constraint,
                &mut self.fields.pressure,
                self.warm.solved_mean,
                target,
            ) {
                self.warm.separation_exact = false;
            }
        } else {
            self.warm.history.forget();
        }
    }

    /// The exact solution at zero load or on a flat surface: uniform `p = target`, `u = 0`.
    pub(super) fn uniform_solution(&mut self, target: f64) {
        self.fields.pressure.fill(target);
        // u = 0: w = −h.
        let h = self.heights;
        self.fields
            .separation
            .par_iter_mut()
            .zip(h.par_iter())
            .for_each(|(w, &h)| *w = -h);
        C::finish_gap(self);
        self.warm.has_solution = target > 0.0;
        self.warm.solved_mean = target;
        self.warm.separation_exact = true;
    }

    /// The elastic start of a solve ([`Complementarity::start`]): the previous solution
    /// scaled to the new load, or uniform pressure, with the gradient statistics of that
    /// state (every update computes them in the pass that makes the state). After a
    /// converged solve `w = K p − h` is exact, and `K (s p) = s K p`, so the scaled start
    /// needs a pass, not a convolution.
    pub(super) fn scaled_start(&mut self, target: f64, report: &mut SolveReport) -> GradientStats {
        let len = self.fields.pressure.len();
        let previous_total: f64 = self.chunked_sum(|p| p);
        let warm = self.warm.has_solution && previous_total > 0.0;
        let scale = if warm {
            target * len as f64 / previous_total
        } else {
            1.0
        };
        if warm && self.warm.separation_exact {
            self.blocks.sparse.clear();
            self.sparse_update(scale, 0.0)
        } else {
            if warm {
                self.fields
                    .pressure
                    .par_iter_mut()
                    .for_each(|p| *p *= scale);
            } else {
                self.fields.pressure.fill(target);
            }
            report.convolutions += 1;
            self.exact_deflection(1.0, 0.0)
        }
    }
}
