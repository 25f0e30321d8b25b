//! The preconditioner `z = P K⁻¹ P g` and the preconditioned direction.

// Lane loops index several fixed-size arrays in lockstep; iterator chains would hide the
// structure the compiler vectorises.
#![allow(clippy::needless_range_loop)]

use rayon::prelude::*;

use super::rows::{avx2_dispatch, lanes, padded, LANES};
use super::Solver;

impl Solver<'_> {
    /// The preconditioned gradient `z = P K⁻¹ P (g − ḡ_S)` (`P`: zero off the contact set
    /// S, centred on S; `g − ḡ_S = u − h − level`). Each row of `K⁻¹ P (g − ḡ_S)` is
    /// stored raw in `self.preconditioned` as it leaves the inverse FFT, and summed over S
    /// in the same pass: `Σ z`, `|S|`, `Σ g z`, `Σ g`, `Σ g t_old` (`g` centred). The
    /// centring is left to the direction pass, which subtracts the mean. Returns
    /// `(mean of z over S, ⟨g − ḡ_S, z − z̄_S⟩_S, Σ_S g t_old, Σ_S g)`. Summed in a fixed order
    /// (four lanes per block, then the blocks in order), so bit-identical whatever the number
    /// of threads.
    pub(super) fn precondition(&mut self, level: f64) -> (f64, f64, f64, f64) {
        let (n, chunk) = (self.op.grid().n(), self.chunk);
        let produce = self
            .pressure
            .par_chunks(chunk)
            .zip(self.separation.par_chunks(chunk));
        self.op.start_rows_inverse(
            produce,
            |(pc, wc), r, row| {
                let at = r * n..(r + 1) * n;
                dispatch_precondition_input(level, row, &pc[at.clone()], &wc[at]);
            },
            &mut self.ws,
        );
        self.op.finish_rows(
            self.preconditioned
                .par_chunks_mut(chunk)
                .zip(self.pressure.par_chunks(chunk))
                .zip(self.separation.par_chunks(chunk))
                .zip(self.direction.par_chunks(chunk))
                .zip(self.precondition_acc.par_iter_mut()),
            |((((zc, pc), wc), tc), acc), r, row| {
                if r == 0 {
                    **acc = [[0.0; LANES]; 5];
                }
                let at = r * n..(r + 1) * n;
                dispatch_precondition_output(
                    level,
                    row,
                    &mut zc[at.clone()],
                    &pc[at.clone()],
                    &wc[at.clone()],
                    &tc[at],
                    acc,
                );
            },
            &mut self.ws,
        );
        let mut sums = [0.0; 5];
        for acc in &self.precondition_acc {
            for (s, lanes) in sums.iter_mut().zip(acc) {
                *s += lanes.iter().sum::<f64>();
            }
        }
        let [sz, count, sgz, sg, sgt] = sums;
        let mean = if count > 0.0 { sz / count } else { 0.0 };
        // Σ_S g (z − z̄) = Σ_S g z − z̄ Σ_S g (Σ_S g is zero up to rounding).
        (mean, sgz - mean * sg, sgt, sg)
    }

    /// [`Self::direction_and_transform`] with the preconditioned gradient:
    /// `t ← (z − z̄_S) + β (t − t̄_S)` on S, 0 elsewhere (`z` raw from
    /// [`Self::precondition`], `z̄_S = z_mean`), each row handed to the forward FFT as it is
    /// made. Returns `⟨t, K t⟩`.
    pub(super) fn preconditioned_direction_and_transform(
        &mut self,
        z_mean: f64,
        beta: f64,
        direction_mean: f64,
    ) -> f64 {
        let (n, chunk) = (self.op.grid().n(), self.chunk);
        let blocks = self
            .direction
            .par_chunks_mut(chunk)
            .zip(self.pressure.par_chunks(chunk))
            .zip(self.preconditioned.par_chunks(chunk));
        self.op.start_rows(
            blocks,
            |((tc, pc), zc), r, row| {
                let at = r * n..(r + 1) * n;
                dispatch_preconditioned_direction(
                    z_mean,
                    beta,
                    direction_mean,
                    &mut tc[at.clone()],
                    row,
                    &pc[at.clone()],
                    &zc[at],
                );
            },
            &mut self.ws,
        )
    }
}

avx2_dispatch! {
    /// One row of the preconditioner's input, with AVX2 where available:
    /// `o = w − level` on S = {p > 0}, 0 elsewhere.
    fn dispatch_precondition_input(level: f64, o: &mut [f64], p: &[f64], w: &[f64]) {
        for ((o, &p), &w) in o.iter_mut().zip(p).zip(w) {
            *o = if p > 0.0 { w - level } else { 0.0 };
        }
    }
}

avx2_dispatch! {
    /// One row of `K⁻¹ P g` as it leaves the inverse FFT, with AVX2 where available: stored
    /// in `z`, and with `g = w − level`, `Σ z`, `|S|`, `Σ g z`, `Σ g`, `Σ g t` over
    /// S = {p > 0} added to `acc` (lane `k mod LANES` takes node `k`).
    fn dispatch_precondition_output(
        level: f64,
        row: &[f64],
        z: &mut [f64],
        p: &[f64],
        w: &[f64],
        t: &[f64],
        acc: &mut [[f64; LANES]; 5],
    ) {
        z.copy_from_slice(row);
        let n = row.len();
        let whole = n - n % LANES;
        for i in (0..whole).step_by(LANES) {
            let at = i..i + LANES;
            precondition_sums(
                level,
                &lanes(&row[at.clone()]),
                &lanes(&p[at.clone()]),
                &lanes(&w[at.clone()]),
                &lanes(&t[at]),
                acc,
            );
        }
        if whole < n {
            // Padding: p = 0 puts the extra lanes off S.
            let at = whole..n;
            precondition_sums(
                level,
                &padded(&row[at.clone()], 0.0),
                &padded(&p[at.clone()], 0.0),
                &padded(&w[at.clone()], 0.0),
                &padded(&t[at], 0.0),
                acc,
            );
        }
    }
}

/// [`dispatch_precondition_output`]'s sums for one block of [`LANES`] nodes.
#[inline(always)]
fn precondition_sums(
    level: f64,
    z: &[f64; LANES],
    p: &[f64; LANES],
    w: &[f64; LANES],
    t: &[f64; LANES],
    acc: &mut [[f64; LANES]; 5],
) {
    for k in 0..LANES {
        let on = p[k] > 0.0;
        let g = if on { w[k] - level } else { 0.0 };
        let zk = if on { z[k] } else { 0.0 };
        acc[0][k] += zk;
        acc[1][k] += if on { 1.0 } else { 0.0 };
        acc[2][k] += g * zk;
        acc[3][k] += g;
        acc[4][k] += if on { g * t[k] } else { 0.0 };
    }
}

avx2_dispatch! {
    /// One row of the preconditioned direction, with AVX2 where available:
    /// `t ← (z − z̄) + β (t − t̄)` on S = {p > 0}, 0 elsewhere, copied into `row`.
    fn dispatch_preconditioned_direction(
        z_mean: f64,
        beta: f64,
        direction_mean: f64,
        t: &mut [f64],
        row: &mut [f64],
        p: &[f64],
        z: &[f64],
    ) {
        for (((t, o), &p), &z) in t.iter_mut().zip(row.iter_mut()).zip(p).zip(z) {
            *t = if p > 0.0 {
                (z - z_mean) + beta * (*t - direction_mean)
            } else {
                0.0
            };
            *o = *t;
        }
    }
}
