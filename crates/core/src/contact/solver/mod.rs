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
//! bounds (`ceiling/law.rs`).
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
//! which nodes are in contact, and its [`Complementarity`] (`complementarity.rs`) how the
//! solve measures, starts and restores the load under it. A preconditioner (`preconditioner.rs`, chosen in one place,
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

mod ceiling;
mod complementarity;
mod config;
mod constraint;
mod deflation;
mod error;
mod extension;
mod history;
mod iteration;
mod lanes;
mod level;
mod load;
mod operator;
mod parts;
mod passes;
mod preconditioner;
mod report;
mod restricted;
mod rows;
mod setup;
mod solve;
mod start;
mod state;
#[cfg(test)]
mod test_support;
#[cfg(test)]
mod tests;
mod update;

pub use ceiling::Ceiling;
pub use complementarity::Complementarity;
pub use config::SolverConfig;
pub use constraint::{Constraint, NonNegative};
pub use error::ContactError;
pub use extension::Extension;
pub use operator::Operator;
pub use report::{SolveReport, Status};
pub use state::Solver;
