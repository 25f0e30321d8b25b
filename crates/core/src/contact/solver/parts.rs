//! The one place where a solve's parts are chosen from its settings.

use super::config::SolverConfig;
use super::constraint::Constraint;
use super::extension::Extended;
use super::extension::Extension;
use super::operator::Operator;
use super::preconditioner::Preconditioner;
use super::restricted::Restricted;

/// The settings that decide a solve's preconditioner: it is chosen anew only when they
/// change, so that a sweep keeps its part (and the state of its layers) from load to load.
pub(super) type Choice = (bool, Option<Extension>);

/// The settings of `cfg` that choose the preconditioner.
pub(super) fn choice(cfg: &SolverConfig) -> Choice {
    (cfg.preconditioned, cfg.extension)
}

/// The preconditioner a solve with `cfg` uses on `op`'s grid: none (the plain iteration),
/// `P K⁻¹ P`, or that extended off the free set.
pub(super) fn choose<C: Constraint, O: Operator>(
    cfg: &SolverConfig,
    op: &O,
) -> Option<Box<dyn Preconditioner<C, O>>> {
    match choice(cfg) {
        (false, _) => None,
        (true, None) => Some(Box::new(Restricted::new(op))),
        (true, Some(settings)) => Some(Box::new(Extended::new(op, settings))),
    }
}
