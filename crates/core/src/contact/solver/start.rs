//! The start of a solve: the exact solution where there is nothing to solve (zero load, a
//! flat surface), else the previous solutions carried to the new load (extrapolated from the
//! last two, or the last one scaled), else a uniform pressure.

use rayon::prelude::*;

use super::constraint::Constraint;
use super::operator::Operator;
use super::rows::GradientStats;
use super::{SolveReport, Solver, SolverConfig};

impl<C: Constraint, O: Operator> Solver<'_, C, O> {
    /// The start of a load after a converged one: extrapolated from the last two solutions
    /// ([`SolverConfig::extrapolate_start`]), else the history is forgotten (and
    /// [`Solver::start`] scales the last solution, or under a ceiling may step from it).
    pub(super) fn warm_start(&mut self, target: f64, cfg: &SolverConfig) {
        if cfg.extrapolate_start
            && self.has_solution
            && self.separation_exact
            && !self.beyond_contact_set(target)
        {
            if self.history.advance(
                self.constraint,
                &mut self.pressure,
                self.solved_mean,
                target,
            ) {
                self.separation_exact = false;
            }
        } else {
            self.history.forget();
        }
    }

    /// The exact solution at zero load or on a flat surface: uniform `p = target`, `u = 0`.
    pub(super) fn uniform_solution(&mut self, target: f64) {
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
    pub(super) fn start(&mut self, target: f64, report: &mut SolveReport) -> GradientStats {
        if C::BOUNDED {
            return self.bounded_start(target, report);
        }
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
