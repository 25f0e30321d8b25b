//! The passes of an iteration over the fields, each fused with one half of an FFT
//! convolution where it can be, and reduced over the operator's fixed row blocks.

use rayon::prelude::*;

use super::rows::*;
use super::{SolveReport, Solver, MAX_SPARSE, RESYNC};

/// Totals of one update pass ([`Solver::update_from_transform`]).
#[derive(Debug, Default, Clone, Copy)]
pub(super) struct UpdateTotals {
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

impl Solver<'_> {
    /// Sum of `f(p_i)` over all nodes with fixed chunking.
    pub(super) fn chunked_sum(&mut self, f: impl Fn(f64) -> f64 + Sync) -> f64 {
        self.pressure
            .par_chunks(self.chunk)
            .zip(self.lane_sums.par_iter_mut())
            .for_each(|(pc, part)| part[0] = pc.iter().map(|&p| f(p)).sum());
        self.lane_sums.iter().map(|p| p[0]).sum()
    }

    /// `Σ max(p + c, 0)` and the number of nodes where `p + c > 0`, reduced over the fixed
    /// blocks.
    fn shifted_sum(&mut self, c: f64) -> (f64, f64) {
        self.pressure
            .par_chunks(self.chunk)
            .zip(self.offset_acc.par_iter_mut())
            .for_each(|(pc, [sums, counts])| {
                *sums = [0.0; LANES];
                *counts = [0.0; LANES];
                dispatch_offset_sums(c, pc, sums, counts);
            });
        self.offset_acc
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
            let (next_sum, next_count) = self.shifted_sum(next);
            let same_piece = next_count == count;
            (c, sum, count) = (next, next_sum, next_count);
            if same_piece {
                break;
            }
        }
        (c, sum)
    }

    /// `u ← s (u + K Δ)` for the changed nodes gathered in `self.sparse` (direct summation,
    /// row by row), `p ← s p`, and the gradient statistics ([`gradient_row`]) in the same pass.
    pub(super) fn sparse_update(&mut self, scale: f64, shift: f64) -> GradientStats {
        let (n, chunk, h) = (self.op.grid().n(), self.chunk, self.heights);
        let (op, loads) = (self.op, &self.sparse);
        self.pressure
            .par_chunks_mut(chunk)
            .zip(self.separation.par_chunks_mut(chunk))
            .zip(h.par_chunks(chunk))
            .zip(self.block_stats.par_iter_mut())
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
        GradientStats::merged(self.block_stats.iter().copied())
    }

    /// `u ← s K p`, `p ← s p` (an exact deflection, then the load correction), with the
    /// statistics ([`gradient_row`]) gathered as the rows of `K p` come out of the
    /// inverse FFT (one pass over the fields fewer than applying `K` and then scanning).
    pub(super) fn exact_deflection(&mut self, scale: f64, shift: f64) -> GradientStats {
        let (n, chunk) = (self.op.grid().n(), self.chunk);
        self.op.start_rows(
            self.pressure.par_chunks(chunk),
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
        scale: f64,
        shift: f64,
    ) -> GradientStats {
        let (n, chunk) = (self.op.grid().n(), self.chunk);
        self.op.start_rows(
            self.pressure.par_chunks(chunk),
            |rows: &mut &[f64], r, buf| {
                for (b, &p) in buf.iter_mut().zip(&rows[r * n..(r + 1) * n]) {
                    *b = (p + offset).max(0.0);
                }
            },
            &mut self.ws,
        );
        self.finish_deflection(false, Some(offset), scale, shift)
    }

    /// Second half of [`Self::exact_deflection`] (`add = false`: `u ← s K x`; with an
    /// `offset`, first `p ← max(p + offset, 0)`) and of [`Self::fft_correction`]
    /// (`add = true`: `u ← s (u + K x)`), with `p ← s p` and the
    /// gradient statistics ([`gradient_row`]) gathered as the rows of `K x` come out of the
    /// inverse FFT started by `start_rows`.
    pub(super) fn finish_deflection(
        &mut self,
        add: bool,
        offset: Option<f64>,
        scale: f64,
        shift: f64,
    ) -> GradientStats {
        let (n, chunk, h) = (self.op.grid().n(), self.chunk, self.heights);
        let blocks = self
            .pressure
            .par_chunks_mut(chunk)
            .zip(self.separation.par_chunks_mut(chunk))
            .zip(h.par_chunks(chunk))
            .zip(self.update_acc.par_iter_mut());
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
                    dispatch_gradient(shift, Some(scale), p, w, h, &mut acc.grad);
                } else {
                    if let Some(c) = offset {
                        p.iter_mut().for_each(|p| *p = (*p + c).max(0.0));
                    }
                    dispatch_exact(scale, p, w, kx, h);
                    dispatch_gradient(shift, None, p, w, h, &mut acc.grad);
                }
            },
            &mut self.ws,
        );
        self.update_gradient()
    }

    /// The gradient statistics gathered per block in `update_acc`.
    pub(super) fn update_gradient(&self) -> GradientStats {
        GradientStats::merged(self.update_acc.iter().map(|a| a.grad.finish()))
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
        let (n, chunk) = (self.op.grid().n(), self.chunk);
        let blocks = self
            .direction
            .par_chunks_mut(chunk)
            .zip(self.pressure.par_chunks(chunk))
            .zip(self.separation.par_chunks(chunk))
            .zip(self.lane_sums.par_iter_mut());
        let energy = self.op.start_rows(
            blocks,
            |(((tc, pc), wc), part), r, row| {
                if r == 0 {
                    **part = [0.0; LANES];
                }
                let at = r * n..(r + 1) * n;
                dispatch_direction(
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
        let numerator = self.lane_sums.iter().map(|p| p.iter().sum::<f64>()).sum();
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
        let (n, chunk) = (self.op.grid().n(), self.chunk);
        let args = UpdateArgs {
            tau,
            level,
            next_shift,
            readmit,
        };
        let blocks = self
            .pressure
            .par_chunks_mut(chunk)
            .zip(self.separation.par_chunks_mut(chunk))
            .zip(self.direction.par_chunks(chunk))
            .zip(self.update_acc.par_iter_mut())
            .zip(self.changes.par_iter_mut())
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
        for acc in &self.update_acc {
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
        self.sparse.clear();
        for (list, acc) in self.changes.iter().zip(&self.update_acc) {
            let count = acc.changed;
            if self.sparse.len() + count > MAX_SPARSE {
                return false;
            }
            self.sparse.extend_from_slice(&list[..count]);
        }
        true
    }

    /// Whether every block's list holds all of its changed nodes.
    pub(super) fn changes_listed(&self) -> bool {
        self.changes
            .iter()
            .zip(&self.update_acc)
            .all(|(list, acc)| list.len() == acc.changed)
    }

    /// `u ← s (u + K Δ)`, `p ← s p` for the changed nodes listed in `self.changes`, by one
    /// FFT convolution of the sparse field `Δ` (its rows without a change skip the forward
    /// row transform), with the gradient statistics ([`gradient_row`]) gathered as the rows
    /// of `K Δ` come out.
    pub(super) fn fft_correction(&mut self, scale: f64, shift: f64) -> GradientStats {
        let (n, chunk) = (self.op.grid().n(), self.chunk);
        self.op.start_rows(
            self.changes
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

    /// Record `min w`, the rigid-body level of the gap `w − min w` ([`Solver::gap`]; `w = u − h`
    /// must be exact).
    pub(super) fn finish_gap(&mut self) {
        self.gap_level = self
            .separation
            .par_iter()
            .copied()
            .reduce(|| f64::INFINITY, f64::min);
    }
}

avx2_dispatch! {
    /// Adds `max(p + c, 0)` and `[p + c > 0]` over `p` to the lane sums `sums` and `counts`
    /// (the load of an offset pressure, [`Solver::load_offset`]).
    fn dispatch_offset_sums(
        c: f64,
        p: &[f64],
        sums: &mut [f64; LANES],
        counts: &mut [f64; LANES],
    ) {
        let mut blocks = p.chunks_exact(LANES);
        for x in &mut blocks {
            for k in 0..LANES {
                let v = x[k] + c;
                sums[k] += if v > 0.0 { v } else { 0.0 };
                counts[k] += if v > 0.0 { 1.0 } else { 0.0 };
            }
        }
        for (k, &x) in blocks.remainder().iter().enumerate() {
            let v = x + c;
            sums[k] += if v > 0.0 { v } else { 0.0 };
            counts[k] += if v > 0.0 { 1.0 } else { 0.0 };
        }
    }
}

impl Solver<'_> {
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
