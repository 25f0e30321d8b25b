//! The extension's passes over rows of nodes (AVX2 where the processor has it, the same
//! operations in the same order) and the Gaussian smoothing on the grid of cells.

use rayon::prelude::*;

use super::super::constraint::Constraint;
use super::super::level::Level;
use super::super::rows::avx2_dispatch;

avx2_dispatch! {
    /// Adds one row's sums of `g = w − level` and of `1_F` over each cell's nodes in F to
    /// `sum_g` and `count` (nodes in order within a cell; AVX2 where available, the same
    /// operations).
    pub(in super::super) fn dispatch_cell_sums<C: Constraint>(
        cell: usize,
        level: Level<C>,
        sum_g: &mut [f64],
        count: &mut [f64],
        p: &[f64],
        w: &[f64],
    ) {
        for (((pc, wc), sg), cnt) in p
            .chunks(cell)
            .zip(w.chunks(cell))
            .zip(sum_g.iter_mut())
            .zip(count.iter_mut())
        {
            let (mut s, mut k) = (0.0, 0.0);
            for (&pv, &wv) in pc.iter().zip(wc) {
                if level.free(pv, wv) {
                    s += wv - level.mean;
                    k += 1.0;
                }
            }
            *sg += s;
            *cnt += k;
        }
    }
}

avx2_dispatch! {
    /// One row of `E g`: `g = w − level` on F, the cell's value off it, in single precision
    /// (AVX2 where available; a selection, so the same bits either way).
    pub(in super::super) fn dispatch_input<C: Constraint>(
        cell: usize,
        values: &[f64],
        level: Level<C>,
        o: &mut [f32],
        p: &[f64],
        w: &[f64],
    ) {
        for (((oc, pc), wc), &v) in o
            .chunks_mut(cell)
            .zip(p.chunks(cell))
            .zip(w.chunks(cell))
            .zip(values)
        {
            let v = v as f32;
            for ((o, &pv), &wv) in oc.iter_mut().zip(pc).zip(wc) {
                *o = if level.free(pv, wv) {
                    (wv - level.mean) as f32
                } else {
                    v
                };
            }
        }
    }
}

avx2_dispatch! {
    /// Adds `Σ y` over the nodes of each cell of a row that are off F to `sums` (nodes in
    /// order within a cell).
    pub(in super::super) fn dispatch_off_sums<C: Constraint>(
        cell: usize,
        level: Level<C>,
        sums: &mut [f64],
        row: &[f32],
        p: &[f64],
        w: &[f64],
    ) {
        for (((yc, pc), wc), s) in row
            .chunks(cell)
            .zip(p.chunks(cell))
            .zip(w.chunks(cell))
            .zip(sums.iter_mut())
        {
            let mut acc = 0.0;
            for ((&y, &pv), &wv) in yc.iter().zip(pc).zip(wc) {
                if !level.free(pv, wv) {
                    acc += y as f64;
                }
            }
            *s += acc;
        }
    }
}

avx2_dispatch! {
    /// One row of the preconditioned direction with the extension's correction:
    /// `t ← (z + (b − z̄)) + β (t − t̄)` on F (where `z` is a number; `b` per cell), 0
    /// elsewhere, copied into `row` (AVX2 where available: the same operations per node).
    pub(in super::super) fn dispatch_direction(
        cell: usize,
        back: &[f64],
        coefficients: [f64; 3],
        t: &mut [f64],
        row: &mut [f64],
        z: &[f32],
    ) {
        let [z_mean, beta, direction_mean] = coefficients;
        for (((tc, oc), zc), &bc) in t
            .chunks_mut(cell)
            .zip(row.chunks_mut(cell))
            .zip(z.chunks(cell))
            .zip(back)
        {
            let shift = bc - z_mean;
            for ((t, o), &z) in tc.iter_mut().zip(oc.iter_mut()).zip(zc) {
                *t = if !z.is_nan() {
                    (z as f64 + shift) + beta * (*t - direction_mean)
                } else {
                    0.0
                };
                *o = *t;
            }
        }
    }
}

/// `out = G x` on the periodic m × m grid of cells, rows then columns (`tmp` between).
pub(super) fn smooth(kernel: &[f64], m: usize, x: &[f64], tmp: &mut [f64], out: &mut [f64]) {
    let h = kernel.len() / 2;
    tmp.par_chunks_mut(m)
        .zip(x.par_chunks(m))
        .for_each(|(o, xr)| {
            o.fill(0.0);
            for (k, &kv) in kernel.iter().enumerate() {
                add_shifted(o, xr, (k + m * (h + 1) - h) % m, kv);
            }
        });
    out.par_chunks_mut(m).enumerate().for_each(|(i, o)| {
        o.fill(0.0);
        for (k, &kv) in kernel.iter().enumerate() {
            let src = &tmp[((i + m * (h + 1) + k - h) % m) * m..][..m];
            for (o, &v) in o.iter_mut().zip(src) {
                *o += kv * v;
            }
        }
    });
}

/// `o[j] += weight · x[(j + shift) mod m]`, in two runs without a modulo.
fn add_shifted(o: &mut [f64], x: &[f64], shift: usize, weight: f64) {
    let m = o.len();
    let (head, tail) = o.split_at_mut(m - shift);
    for (o, &v) in head.iter_mut().zip(&x[shift..]) {
        *o += weight * v;
    }
    for (o, &v) in tail.iter_mut().zip(&x[..shift]) {
        *o += weight * v;
    }
}
