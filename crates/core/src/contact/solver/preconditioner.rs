//! The preconditioner's contract.
//!
//! A preconditioner turns the gradient `g = w − level` on the free set F into `z = M g`
//! (`M` symmetric positive on F, centred there by the direction pass) and makes the search
//! direction `t = (z − z̄_F) + β (t − t̄_F)` on F from it, 0 elsewhere, each row handed to the
//! forward FFT of `K t` as it is made. The solver asks nothing else of it: the step, the
//! projection, the load and the error are the same whatever `M` is. Two parts implement it:
//! `Restricted` (`P K⁻¹ P`, module `restricted`) and `Extended` (`P Eᵀ K⁻¹ E P` with its
//! near and far terms and the block deflation as layers, module `extension`); the plain
//! Polonsky–Keer iteration is "no preconditioner". A new one is a type implementing
//! [`Preconditioner`] in a file of its own, and one arm of `parts::choose`.

use super::constraint::Constraint;
use super::level::Level;
use super::operator::Operator;

/// The solver's fields a preconditioner reads, and the direction it writes, lent for one
/// call.
pub(super) struct Fields<'f, O: Operator> {
    pub op: &'f O,
    pub ws: &'f mut O::Workspace,
    /// Values per work block (the operator's fixed row blocks; every reduction sums over
    /// them in order, so that the bits do not depend on the thread count).
    pub chunk: usize,
    /// `p`, and `w = u − h` (the gradient is `w − level.mean` on F).
    pub pressure: &'f [f64],
    pub separation: &'f [f64],
    /// The search direction `t`: the previous one on entry to [`Preconditioner::direction`].
    pub direction: &'f mut [f64],
}

/// The coefficients of the preconditioned direction `t ← (z − z_mean) + β (t − t_mean)`:
/// `[z_mean, β, t_mean]`, the means over F of `z` and of the previous direction.
pub(super) type Coefficients = [f64; 3];

/// A preconditioner of the constrained conjugate gradient.
pub(super) trait Preconditioner<C: Constraint, O: Operator>: Send {
    /// Called before each iteration with the last iteration's change to the contact set
    /// (`(nodes changed, contact nodes)`; `None` before a load's first iteration), so that a
    /// preconditioner may switch its layers as the set settles. Returns whether `M` changed,
    /// which restarts the conjugate direction.
    fn settle(&mut self, _changes: Option<(usize, f64)>) -> bool {
        false
    }

    /// How far below the contact set's level a node off it must interpenetrate to join F,
    /// for an iteration whose error times σ_h is `error_scale` ([`Level::entry`]).
    fn entry_margin(&self, _error_scale: f64) -> f64 {
        0.0
    }

    /// `z = M g` on `F = {p > 0} ∪ {p = 0, w < level.entry}` with `g = w − level.mean`, kept
    /// for [`Self::direction`], and its sums over F. One inverse convolution.
    fn precondition(&mut self, fields: &mut Fields<'_, O>, level: Level<C>) -> PreconditionSums;

    /// The direction from the last [`Self::precondition`]: `t ← (z − z̄) + β (t − t̄)` on F,
    /// 0 elsewhere, each row handed to the forward FFT of `K t`. Returns `⟨t, K t⟩`.
    fn direction(&mut self, fields: &mut Fields<'_, O>, coefficients: Coefficients) -> f64;
}

/// The sums of [`Preconditioner::precondition`] over the free set `F`.
#[derive(Debug, Clone, Copy)]
pub(super) struct PreconditionSums {
    /// Mean of `z` over F.
    pub z_mean: f64,
    /// `⟨g, z − z̄⟩_F`, the preconditioned gradient's norm.
    pub g_dot_z: f64,
    /// `Σ_F g t_old`.
    pub g_dot_t_old: f64,
    /// `Σ_F g`.
    pub g_sum: f64,
    /// Mean of the previous direction over F.
    pub t_old_mean: f64,
}

impl PreconditionSums {
    /// From the output pass's sums `[Σ_F z, |F|, Σ_F g z, Σ_F g, Σ_F g t, Σ_F t]`, with a
    /// layer's correction `b` on F (`Σ_F b`, `Σ_F g b`; 0 without one).
    pub(super) fn new(sums: [f64; 6], sum_b: f64, sum_gb: f64) -> Self {
        let [sz, count, sgz, sg, sgt, st] = sums;
        let (sz, sgz) = (sz + sum_b, sgz + sum_gb);
        let (z_mean, t_mean) = if count > 0.0 {
            (sz / count, st / count)
        } else {
            (0.0, 0.0)
        };
        // Σ_F g (z − z̄) = Σ_F g z − z̄ Σ_F g.
        Self {
            z_mean,
            g_dot_z: sgz - z_mean * sg,
            g_dot_t_old: sgt,
            g_sum: sg,
            t_old_mean: t_mean,
        }
    }
}
