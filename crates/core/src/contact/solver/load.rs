//! The load restored after a step: the projection `p ← max(p − τ t, 0)` sheds load, and
//! the pressures are brought back to the mean `p̄` by a uniform offset (the nearest point of
//! `{p ≥ 0, mean p = p̄}`, where the step changed many nodes) or a rescaling (where it changed
//! few, keeping `p` and `u` linear); then the deflection, the cheapest exact way.

use rayon::prelude::*;

use super::config::SolverConfig;
use super::constraint::Constraint;
use super::iteration::Iteration;
use super::operator::Operator;
use super::passes::{UpdateTotals, MAX_SPARSE};
use super::report::SolveReport;
use super::rows::*;
use super::state::Solver;

/// Exact recomputation of `u = K p` after this many linear updates.
pub(super) const RESYNC: usize = 32;

impl<C: Constraint, O: Operator> Solver<'_, C, O> {
    /// After a step that left the load `totals.sum_p > 0`, the elastic law's restoration
    /// ([`super::complementarity::Complementarity::restore_load`]): the load `target` per node restored,
    /// by a uniform offset of the pressures where the step changed many nodes (`u = K p`
    /// recomputed: one convolution, as a correction of that many changes would take), else
    /// by a rescaling with `u` updated linearly or exactly; the next gradient's statistics.
    /// When the load is below the rounding of the largest pressures (W/W0 ≈ 1e-20) the
    /// offset's sum cancels to zero, and the rescaling restores it instead.
    pub(super) fn restore_elastic_load(
        &mut self,
        cfg: &SolverConfig,
        totals: &UpdateTotals,
        linear_stats: GradientStats,
        target: f64,
        it: &mut Iteration,
        report: &mut SolveReport,
    ) -> GradientStats {
        let total = totals.sum_p;
        let load = target * self.fields.pressure.len() as f64;
        let offset = (cfg.preconditioned
            && cfg.offset_to_load
            && totals.changed > MAX_SPARSE
            && total > load)
            .then(|| self.load_offset(load, total, totals.contact_nodes))
            .filter(|&(_, shifted)| shifted > 0.0);
        if let Some((offset, shifted)) = offset {
            report.convolutions += 1;
            it.linear_steps = 0;
            self.offset_deflection(offset, false, load / shifted, it.shift)
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

    /// `Σ max(p + c, 0)` and the number of nodes where `p + c > 0` (the constraint's
    /// projection and active set), reduced over the fixed blocks.
    pub(super) fn shifted_sum(&mut self, c: f64, wide: bool) -> (f64, f64) {
        let constraint = self.constraint;
        self.fields
            .pressure
            .par_chunks(self.blocks.chunk)
            .zip(self.blocks.offset_acc.par_iter_mut())
            .for_each(|(pc, [sums, counts])| {
                *sums = [0.0; LANES];
                *counts = [0.0; LANES];
                dispatch_offset_sums(constraint, c, wide, pc, sums, counts);
            });
        self.blocks
            .offset_acc
            .iter()
            .fold((0.0, 0.0), |(s, k), [sums, counts]| {
                (s + sums.iter().sum::<f64>(), k + counts.iter().sum::<f64>())
            })
    }

    /// The offset `c ≤ 0` for which `Σ max(p + c, 0)` is `load`, for pressures summing to
    /// `total > load` on `count` positive nodes, and that sum (`load` up to rounding):
    /// Newton's method on the convex, piecewise linear `Σ max(p + c, 0)`, which from
    /// `c = 0` approaches the root from above and is exact once a step keeps the same nodes
    /// positive (one to three passes over `p` in 95 % of the paper 1024² sweep's offsets). `p` is not changed.
    pub(super) fn load_offset(&mut self, load: f64, total: f64, count: f64) -> (f64, f64) {
        let (mut c, mut sum, mut count) = (0.0f64, total, count);
        for _ in 0..64 {
            if sum <= load || count <= 0.0 {
                break;
            }
            let next = c - (sum - load) / count;
            let (next_sum, next_count) = self.shifted_sum(next, false);
            let same_piece = next_count == count;
            (c, sum, count) = (next, next_sum, next_count);
            if same_piece {
                break;
            }
        }
        (c, sum)
    }

    /// The deflection after an update pass, the cheapest way that stays exact: the linear
    /// update itself when no node changed, a direct correction for a few changed nodes, an
    /// FFT correction for more, or an exact recomputation (every [`RESYNC`] steps, and when
    /// a block changed more nodes than its list holds). `linear_steps` counts the updates
    /// since the last exact one (0 after one).
    pub(super) fn next_deflection(
        &mut self,
        totals: &UpdateTotals,
        linear_stats: GradientStats,
        scale: f64,
        shift: f64,
        linear_steps: &mut usize,
        report: &mut SolveReport,
    ) -> GradientStats {
        let linear = *linear_steps + 1 < RESYNC;
        let stats = if totals.changed == 0 && linear {
            // Nothing left or entered the set: p and u are both exact linear updates and
            // the load is preserved (Σ_S t = 0) up to rounding, corrected at the next exact
            // step.
            linear_stats
        } else if totals.changed <= MAX_SPARSE && linear && self.gather_changes() {
            self.sparse_update(scale, shift)
        } else if linear && self.changes_listed() {
            report.convolutions += 1;
            self.fft_correction(scale, shift)
        } else {
            report.convolutions += 1;
            *linear_steps = 0;
            return self.exact_deflection(scale, shift);
        };
        *linear_steps += 1;
        stats
    }
}

avx2_dispatch! {
    /// Adds the offset pressure ([`Constraint::offset`]) and whether it is active (for
    /// `p ≥ 0`: `max(p + c, 0)` and `[p + c > 0]`) over `p` to the lane sums `sums` and `counts` (the load of an offset
    /// pressure and its slope in `c`, [`Solver::load_offset`]).
    pub(super) fn dispatch_offset_sums<C: Constraint>(
        constraint: C,
        c: f64,
        wide: bool,
        p: &[f64],
        sums: &mut [f64; LANES],
        counts: &mut [f64; LANES],
    ) {
        let mut blocks = p.chunks_exact(LANES);
        for x in &mut blocks {
            for k in 0..LANES {
                let v = constraint.offset(x[k], c, wide);
                sums[k] += v;
                counts[k] += if constraint.active(v) { 1.0 } else { 0.0 };
            }
        }
        for (k, &x) in blocks.remainder().iter().enumerate() {
            let v = constraint.offset(x, c, wide);
            sums[k] += v;
            counts[k] += if constraint.active(v) { 1.0 } else { 0.0 };
        }
    }
}
