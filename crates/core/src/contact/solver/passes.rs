//! The passes of an iteration over the fields, each fused with one half of an FFT
//! convolution where it can be, and reduced over the operator's fixed row blocks.

use rayon::prelude::*;

use super::constraint::Constraint;
use super::operator::Operator;
use super::rows::*;
use super::state::Solver;
use super::update::{dispatch_update, UpdateAcc, UpdateArgs};

/// When at most this many nodes leave or re-enter the contact set in an iteration, the
/// deflection is corrected by direct summation (all nodes' kernel rows added row by row, in
/// the same pass as the next gradient statistics) instead of a new convolution. Limits of
/// 32–128 save 10–20 % of the convolutions but cost as much in summation
/// (docs/BENCHMARKS.md).
pub(super) const MAX_SPARSE: usize = 6;

/// The change lists hold up to one node in `CHANGES_PER_NODE` of each block; an update that
/// changes more recomputes `u = K p` instead of correcting it.
pub(super) const CHANGES_PER_NODE: usize = 16;

/// Totals of one update pass ([`Solver::update_from_transform`]).
#[derive(Debug, Default, Clone, Copy)]
pub struct UpdateTotals {
    /// `Σp` after the step and projection.
    pub sum_p: f64,
    /// `Σ t` over the new contact set.
    pub sum_t_kept: f64,
    /// Size of the new contact set.
    pub contact_nodes: f64,
    /// Nodes re-admitted to the contact set.
    pub readmitted: usize,
    /// Nodes whose value departs from the linear step (left or (re-)entered the set).
    pub changed: usize,
}

impl<C: Constraint, O: Operator> Solver<'_, C, O> {
    /// Sum of `f(p_i)` over all nodes with fixed chunking.
    pub(super) fn chunked_sum(&mut self, f: impl Fn(f64) -> f64 + Sync) -> f64 {
        self.fields
            .pressure
            .par_chunks(self.blocks.chunk)
            .zip(self.blocks.lane_sums.par_iter_mut())
            .for_each(|(pc, part)| part[0] = pc.iter().map(|&p| f(p)).sum());
        self.blocks.lane_sums.iter().map(|p| p[0]).sum()
    }

    /// `u ← s (u + K Δ)` for the changed nodes gathered in `self.blocks.sparse` (direct summation,
    /// row by row), `p ← s p`, and the gradient statistics ([`gradient_row`]) in the same pass.
    pub(super) fn sparse_update(&mut self, scale: f64, shift: f64) -> GradientStats {
        let constraint = self.constraint;
        let (n, chunk, h) = (self.op.grid().n(), self.blocks.chunk, self.heights);
        let (op, loads) = (self.op, &self.blocks.sparse);
        self.fields
            .pressure
            .par_chunks_mut(chunk)
            .zip(self.fields.separation.par_chunks_mut(chunk))
            .zip(h.par_chunks(chunk))
            .zip(self.blocks.block_stats.par_iter_mut())
            .enumerate()
            .for_each(|(b, (((pc, wc), hc), part))| {
                let mut acc = GradientLanes::new();
                for (r, ((p, w), h)) in pc
                    .chunks_exact_mut(n)
                    .zip(wc.chunks_exact_mut(n))
                    .zip(hc.chunks_exact(n))
                    .enumerate()
                {
                    dispatch_sparse(
                        op,
                        constraint,
                        b * (chunk / n) + r,
                        loads,
                        shift,
                        scale,
                        p,
                        w,
                        h,
                        &mut acc,
                    );
                }
                *part = acc.finish();
            });
        GradientStats::merged(self.blocks.block_stats.iter().copied())
    }

    /// `u ← s K p`, `p ← s p` (an exact deflection, then the load correction), with the
    /// statistics ([`gradient_row`]) gathered as the rows of `K p` come out of the
    /// inverse FFT (one pass over the fields fewer than applying `K` and then scanning).
    pub(super) fn exact_deflection(&mut self, scale: f64, shift: f64) -> GradientStats {
        let (n, chunk) = (self.op.grid().n(), self.blocks.chunk);
        self.op.start_rows(
            self.fields.pressure.par_chunks(chunk),
            |rows: &mut &[f64], r, buf| buf.copy_from_slice(&rows[r * n..(r + 1) * n]),
            &mut self.ws,
        );
        self.finish_deflection(false, None, scale, shift)
    }

    /// [`Self::exact_deflection`] of the offset pressure: `p ← s max(p + c, 0)`,
    /// `u ← K p`, the offset applied as the rows enter the forward transform and again as
    /// they are finished (no pass of its own).
    pub(super) fn offset_deflection(
        &mut self,
        offset: f64,
        wide: bool,
        scale: f64,
        shift: f64,
    ) -> GradientStats {
        let constraint = self.constraint;
        let (n, chunk) = (self.op.grid().n(), self.blocks.chunk);
        self.op.start_rows(
            self.fields.pressure.par_chunks(chunk),
            |rows: &mut &[f64], r, buf| {
                for (b, &p) in buf.iter_mut().zip(&rows[r * n..(r + 1) * n]) {
                    *b = constraint.offset(p, offset, wide);
                }
            },
            &mut self.ws,
        );
        self.finish_deflection(false, Some((offset, wide)), scale, shift)
    }

    /// Second half of [`Self::exact_deflection`] (`add = false`: `u ← s K x`; with an
    /// `offset`, first `p ← max(p + offset, 0)`) and of [`Self::fft_correction`]
    /// (`add = true`: `u ← s (u + K x)`), with `p ← s p` and the
    /// gradient statistics ([`gradient_row`]) gathered as the rows of `K x` come out of the
    /// inverse FFT started by `start_rows`.
    pub(super) fn finish_deflection(
        &mut self,
        add: bool,
        offset: Option<(f64, bool)>,
        scale: f64,
        shift: f64,
    ) -> GradientStats {
        let constraint = self.constraint;
        let (n, chunk, h) = (self.op.grid().n(), self.blocks.chunk, self.heights);
        let blocks = self
            .fields
            .pressure
            .par_chunks_mut(chunk)
            .zip(self.fields.separation.par_chunks_mut(chunk))
            .zip(h.par_chunks(chunk))
            .zip(self.blocks.update_acc.par_iter_mut());
        self.op.finish_rows(
            blocks,
            |(((pc, wc), hc), acc), r, kx| {
                if r == 0 {
                    acc.grad = GradientLanes::new();
                }
                let at = r * n..(r + 1) * n;
                let (p, w, h) = (&mut pc[at.clone()], &mut wc[at.clone()], &hc[at]);
                if add {
                    for (w, k) in w.iter_mut().zip(kx) {
                        *w += k;
                    }
                    dispatch_gradient(constraint, shift, Some(scale), p, w, h, &mut acc.grad);
                } else {
                    if let Some((c, wide)) = offset {
                        p.iter_mut()
                            .for_each(|p| *p = constraint.offset(*p, c, wide));
                    }
                    dispatch_exact(scale, p, w, kx, h);
                    dispatch_gradient(constraint, shift, None, p, w, h, &mut acc.grad);
                }
            },
            &mut self.ws,
        );
        self.update_gradient()
    }

    /// The gradient statistics gathered per block in `update_acc`.
    pub(super) fn update_gradient(&self) -> GradientStats {
        GradientStats::merged(self.blocks.update_acc.iter().map(|a| a.grad.finish()))
    }

    /// Pass 2 fused with the first half of `K t`: `t ← (g − ḡ_S) + β (t − t̄_S)` on S, 0
    /// elsewhere (`g − ḡ_S = u − h − level`, `t̄_S = direction_mean`, the mean of the old
    /// direction over the current contact set, so that `Σ_S t = 0`), each row handed to the
    /// forward FFT as it is made. Returns `(⟨t, K t⟩, Σ_S (g − ḡ_S) t)`.
    pub(super) fn direction_and_transform(
        &mut self,
        level: f64,
        beta: f64,
        direction_mean: f64,
    ) -> (f64, f64) {
        let constraint = self.constraint;
        let (n, chunk) = (self.op.grid().n(), self.blocks.chunk);
        let blocks = self
            .fields
            .direction
            .par_chunks_mut(chunk)
            .zip(self.fields.pressure.par_chunks(chunk))
            .zip(self.fields.separation.par_chunks(chunk))
            .zip(self.blocks.lane_sums.par_iter_mut());
        let energy = self.op.start_rows(
            blocks,
            |(((tc, pc), wc), part), r, row| {
                if r == 0 {
                    **part = [0.0; LANES];
                }
                let at = r * n..(r + 1) * n;
                dispatch_direction(
                    constraint,
                    level,
                    beta,
                    direction_mean,
                    &mut tc[at.clone()],
                    &pc[at.clone()],
                    &wc[at],
                    row,
                    part,
                );
            },
            &mut self.ws,
        );
        let numerator = self
            .blocks
            .lane_sums
            .iter()
            .map(|p| p.iter().sum::<f64>())
            .sum();
        (energy, numerator)
    }

    /// Pass 3 fused with the second half of `K t` (whose rows arrive from the inverse FFT):
    /// `p ← max(p − τ t, 0)`; if `readmit`, nodes with `p = 0` and `g − level < 0` are
    /// re-admitted with `p = −τ (g − level)`. Records the nodes where the result departs from the
    /// linear step. Also `u ← u − τ K t` and the gradient statistics of
    /// [`gradient_row`] for the new state with `g = u − h − next_shift` (exact if no
    /// node changed). Returns the pass's totals and those statistics.
    pub(super) fn update_from_transform(
        &mut self,
        tau: f64,
        level: f64,
        next_shift: f64,
        readmit: bool,
    ) -> (UpdateTotals, GradientStats) {
        let (n, chunk) = (self.op.grid().n(), self.blocks.chunk);
        let args = UpdateArgs {
            tau,
            level,
            next_shift,
            readmit,
            constraint: self.constraint,
        };
        let blocks = self
            .fields
            .pressure
            .par_chunks_mut(chunk)
            .zip(self.fields.separation.par_chunks_mut(chunk))
            .zip(self.fields.direction.par_chunks(chunk))
            .zip(self.blocks.update_acc.par_iter_mut())
            .zip(self.blocks.changes.par_iter_mut())
            .enumerate();
        self.op.finish_rows(
            blocks,
            |(block, ((((pc, wc), tc), acc), changes)), r, kt| {
                if r == 0 {
                    **acc = UpdateAcc::new();
                    changes.clear();
                }
                let at = r * n..(r + 1) * n;
                dispatch_update(
                    &args,
                    *block * chunk + r * n,
                    &mut pc[at.clone()],
                    &mut wc[at.clone()],
                    &tc[at],
                    kt,
                    acc,
                    changes,
                );
            },
            &mut self.ws,
        );
        let mut totals = UpdateTotals::default();
        for acc in &self.blocks.update_acc {
            let s = acc.grad.finish();
            totals.sum_p += s.sum_p;
            totals.sum_t_kept += acc.kept_t.iter().sum::<f64>();
            totals.contact_nodes += s.contact_nodes;
            totals.readmitted += acc.readmitted;
            totals.changed += acc.changed;
        }
        (totals, self.update_gradient())
    }

    /// Collect the changed nodes of the last update in index order; false if there are
    /// more than [`MAX_SPARSE`] (then an FFT is needed).
    pub(super) fn gather_changes(&mut self) -> bool {
        self.blocks.sparse.clear();
        for (list, acc) in self.blocks.changes.iter().zip(&self.blocks.update_acc) {
            let count = acc.changed;
            if self.blocks.sparse.len() + count > MAX_SPARSE {
                return false;
            }
            self.blocks.sparse.extend_from_slice(&list[..count]);
        }
        true
    }

    /// Whether every block's list holds all of its changed nodes.
    pub(super) fn changes_listed(&self) -> bool {
        self.blocks
            .changes
            .iter()
            .zip(&self.blocks.update_acc)
            .all(|(list, acc)| list.len() == acc.changed)
    }

    /// `u ← s (u + K Δ)`, `p ← s p` for the changed nodes listed in `self.blocks.changes`, by one
    /// FFT convolution of the sparse field `Δ` (its rows without a change skip the forward
    /// row transform), with the gradient statistics ([`gradient_row`]) gathered as the rows
    /// of `K Δ` come out.
    pub(super) fn fft_correction(&mut self, scale: f64, shift: f64) -> GradientStats {
        let (n, chunk) = (self.op.grid().n(), self.blocks.chunk);
        self.op.start_rows(
            self.blocks
                .changes
                .par_iter()
                .enumerate()
                .map(|(b, list)| (b * chunk, list.as_slice())),
            |(first, list): &mut (usize, &[(usize, f64)]), _r, row| {
                // Rows come in order: the list's leading entries below the row's end are
                // this row's.
                row.fill(0.0);
                let end = *first + n;
                let k = list.partition_point(|&(i, _)| i < end);
                for &(i, d) in &list[..k] {
                    row[i - *first] = d;
                }
                *list = &list[k..];
                *first = end;
            },
            &mut self.ws,
        );
        self.finish_deflection(true, None, scale, shift)
    }

    /// `min w` over every node: the rigid-body level of the gap `w − min w` ([`Solver::gap`];
    /// `w = u − h` must be exact), as the elastic law records it after a solve.
    pub(super) fn lowest_separation(&self) -> f64 {
        self.fields
            .separation
            .par_iter()
            .copied()
            .reduce(|| f64::INFINITY, f64::min)
    }
}
