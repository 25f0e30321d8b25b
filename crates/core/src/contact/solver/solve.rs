//! The solve loop ([`Solver::solve`]): start, then search direction, step and projection,
//! load restored, until the error is below the tolerance (confirmed by an exact deflection)
//! or the iteration stalls.

use super::complementarity::Complementarity;
use super::config::SolverConfig;
use super::error::ContactError;
use super::iteration::Iteration;
use super::operator::Operator;
use super::report::{SolveReport, Status};
use super::state::Solver;

impl<C: Complementarity, O: Operator> Solver<'_, C, O> {
    /// Solve for the mean pressure `mean_pressure` (≥ 0), warm-starting from the previous
    /// solutions if there are any: extrapolated from the last two
    /// ([`SolverConfig::extrapolate_start`]) or the last one, scaled to the new load.
    pub fn solve(
        &mut self,
        mean_pressure: f64,
        cfg: &SolverConfig,
    ) -> Result<SolveReport, ContactError> {
        check_request(mean_pressure, cfg)?;
        if let Some(ceiling) = self.constraint.ceiling().filter(|&c| mean_pressure > c) {
            return Err(ContactError::AboveCeiling {
                mean: mean_pressure,
                ceiling,
            });
        }
        self.prepare_parts(cfg);
        let target = mean_pressure;
        let mut report = SolveReport::new(mean_pressure, cfg.max_iterations);
        // At the ceiling's mean the only admissible field is uniform: every node saturated.
        if target == 0.0 || self.flat || Some(target) == self.constraint.ceiling() {
            self.uniform_solution(target);
            report.error_history.push(0.0);
            return Ok(report);
        }
        self.warm_start(target, cfg);
        let mut stats = C::start(self, target, &mut report);
        self.warm.has_solution = false;
        self.warm.separation_exact = false;
        let len = self.fields.pressure.len() as f64;
        let mut it = Iteration::new();
        loop {
            // The error from the gradient's statistics on the contact set.
            let error = C::error(self, &stats, it.shift, cfg.tolerance);
            if error <= cfg.tolerance && !it.exact {
                // Confirm with an exact deflection (and the exact load) before declaring
                // convergence.
                stats = C::confirm(self, target, &stats, &mut it);
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
            C::fall_back(self, &mut it, &report);
            report.iterations += 1;
            // The direction (fused with the forward FFT), then K t and the curvature ⟨t, K t⟩
            // (Parseval), and the exact line search.
            let level = it.shift + C::level(self, &stats);
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
                let stats = C::restore_load(
                    self,
                    cfg,
                    &totals,
                    linear_stats,
                    target,
                    &mut it,
                    &mut report,
                );
                it.exact = it.linear_steps == 0;
                stats
            } else {
                self.restart_uniform(target, &mut it, &mut report)
            };
        }
        C::finish_gap(self);
        self.warm.has_solution = report.status == Status::Converged;
        self.warm.solved_mean = target;
        // A converged state was confirmed by an exact deflection (or is the flat or zero
        // solution, `w = −h`).
        self.warm.separation_exact = self.warm.has_solution;
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
