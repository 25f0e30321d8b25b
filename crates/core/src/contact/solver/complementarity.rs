//! What a constraint changes in the solve beyond its rules at a node ([`Constraint`]): the
//! error it is measured by, the level of the gradient, the start, how the load is restored
//! after a step and how a solution is levelled. Each is a method with the elastic law's
//! form as its default, which [`NonNegative`] takes as it is; a constraint whose field is
//! not positively homogeneous (the ceiling, `ceiling/`) supplies its own in its own folder.
//! The solve loop (`mod.rs`) and the start (`start.rs`) call them, and nothing else in the
//! solver asks which constraint it has.

use super::config::SolverConfig;
use super::constraint::{Constraint, NonNegative};
use super::iteration::Iteration;
use super::operator::Operator;
use super::passes::{UpdateTotals, CHANGES_PER_NODE};
use super::report::SolveReport;
use super::rows::GradientStats;
use super::state::Solver;

/// A constraint's part in the solve (module docs). Every method has the elastic default.
pub trait Complementarity: Constraint {
    /// How many changed nodes each block's list holds, for blocks of `chunk` nodes (a
    /// restoration that reads every projected node needs them all listed).
    fn listed_changes(chunk: usize) -> usize {
        chunk / CHANGES_PER_NODE
    }

    /// The complementarity error of a state with gradient statistics `stats` (of
    /// `g = w − shift`), in units of the load times σ_h: `Σ p (g − min g)`
    /// (docs/CONVENTIONS.md).
    fn error<O: Operator>(
        s: &mut Solver<'_, Self, O>,
        stats: &GradientStats,
        _shift: f64,
        _tolerance: f64,
    ) -> f64 {
        stats.error(s.height_std)
    }

    /// The level of the gradient that the search direction is centred on: its mean over the
    /// active set.
    fn level<O: Operator>(_s: &Solver<'_, Self, O>, stats: &GradientStats) -> f64 {
        stats.mean_g()
    }

    /// The start of a solve for the mean pressure `target`, with the gradient statistics of
    /// that state: the last solution scaled to the load ([`Solver::scaled_start`]).
    fn start<O: Operator>(
        s: &mut Solver<'_, Self, O>,
        target: f64,
        report: &mut SolveReport,
    ) -> GradientStats {
        s.scaled_start(target, report)
    }

    /// Whether the last solution cannot be carried to the load `target` by the start (so
    /// that nothing extrapolates through it): never for a homogeneous field.
    fn beyond_contact_set<O: Operator>(_s: &Solver<'_, Self, O>, _target: f64) -> bool {
        false
    }

    /// The exact deflection that confirms a state of error below the tolerance, at the
    /// exact load: the pressures rescaled to it.
    fn confirm<O: Operator>(
        s: &mut Solver<'_, Self, O>,
        target: f64,
        stats: &GradientStats,
        it: &mut Iteration,
    ) -> GradientStats {
        let len = s.fields.pressure.len() as f64;
        s.exact_deflection(target * len / stats.sum_p, it.shift)
    }

    /// After a step that left the load `totals.sum_p > 0`: the load `target` per node
    /// restored ([`Solver::restore_elastic_load`]: a uniform offset or a rescaling), and the next
    /// gradient's statistics.
    fn restore_load<O: Operator>(
        s: &mut Solver<'_, Self, O>,
        cfg: &SolverConfig,
        totals: &UpdateTotals,
        linear_stats: GradientStats,
        target: f64,
        it: &mut Iteration,
        report: &mut SolveReport,
    ) -> GradientStats {
        s.restore_elastic_load(cfg, totals, linear_stats, target, it, report)
    }

    /// Called before each iteration, to change the preconditioner where the iteration
    /// stagnates: nothing by default.
    fn fall_back<O: Operator>(
        _s: &mut Solver<'_, Self, O>,
        _it: &mut Iteration,
        _report: &SolveReport,
    ) {
    }

    /// Records the rigid-body level of the gap after a solve (`w = u − h` exact): `min w`
    /// ([`Solver::lowest_separation`]).
    fn finish_gap<O: Operator>(s: &mut Solver<'_, Self, O>) {
        s.fields.gap_level = s.lowest_separation();
    }
}

/// The elastic law: every default.
impl Complementarity for NonNegative {}
