//! Deflation of the preconditioner by the loads of large blocks, once the contact set has
//! settled ([`super::Extension::coarse_block`]).
//!
//! On a large box the extended preconditioner `M` still over-weights the slowest modes of
//! the restricted operator `A = P K P` (its largest Ritz value grows with the box), and the
//! settled phase of a load grows with it. The balancing form on a coarse space `Z̃` of the
//! free set's indicators on blocks of B × B nodes, each centred on F (`Z̃_a = P 1_{F ∩ a}`),
//!
//! `M_B = (I − Z̃ E⁻¹ W̃ᵀ) M (I − W̃ E⁻¹ Z̃ᵀ) + Z̃ E⁻¹ Z̃ᵀ`,
//!
//! gives the coarse modes their exact weight when `W̃ = A Z̃` and `E = Z̃ᵀ A Z̃`. Both would
//! take a convolution per block; here `W̃` is a model that needs none: the block's load on
//! F restricted to the centres of cells of 2c × 2c nodes (`c` the extension's cell; the
//! transpose of the bilinear interpolation), its deflection on the grid of those cells with
//! the exact cell-averaged kernel (`Π K Π`, the aliases of the fine multiplier summed),
//! interpolated bilinearly back to the nodes of F and centred there. `E` is the Gram
//! matrix of the restricted loads under `Π K Π` (positive semi-definite by construction,
//! projected off the constant block vector, `Σ_a Z̃_a = 0`), one coarse convolution per
//! block when the set settles; should its Cholesky factorisation fail, `E⁻¹ = 0` gives back
//! `M`. It is used only on contact sets that cover [`super::Extension::coarse_fraction`] of
//! the box (sparser ones lose iterations; docs/BENCHMARKS.md). `M_B` is symmetric and
//! positive for any `W̃` and positive `E` (it is `Xᵀ M X + Z̃ E⁻¹ Z̃ᵀ`, `X = I − W̃ E⁻¹
//! Z̃ᵀ`), so the model changes the rate, never the solution. Per iteration: a pass over `p`
//! and `w` for the interpolation weights, the bilinear correction of the input and the
//! restriction of the output in the preconditioner's own passes, three convolutions on the
//! coarse grid ((n/2c)² nodes) and two products with the dense `E⁻¹` (one row and column per
//! block). Memory: about n²/9 doubles, most of it the four interpolation weights per
//! extension cell.

use rayon::prelude::*;
use rustfft::num_complex::Complex;

use super::constraint::Constraint;
use super::level::{Level, OffBlock};
use super::operator::Operator;
use crate::spectral::{Fft2, Fft2Scratch};

/// The bilinear interpolation between the centres of the model cells (2c × 2c nodes, `m`
/// per side, periodic).
pub(super) struct Bilinear {
    /// Side of a model cell, in nodes.
    cell: usize,
    /// Model cells per side.
    m: usize,
    /// Per column: the model cell left of the node's position (wrapped) and the weight of
    /// the one right of it.
    col_cell: Vec<usize>,
    col_weight: Vec<f64>,
}

impl Bilinear {
    fn new(n: usize, cell: usize) -> Self {
        let m = n / cell;
        let (col_cell, col_weight) = (0..n).map(|j| Self::split(cell, m, j)).unzip();
        Self {
            cell,
            m,
            col_cell,
            col_weight,
        }
    }

    /// Node `i` along an axis lies at `(i + ½)/cell − ½` in units of model cells from the
    /// first cell's centre: the cell below it (wrapped) and the weight of the next.
    fn split(cell: usize, m: usize, i: usize) -> (usize, f64) {
        let (first, weight) = Self::unwrapped(cell, i);
        (first.rem_euclid(m as i64) as usize, weight)
    }

    fn unwrapped(cell: usize, i: usize) -> (i64, f64) {
        let shifted = i as i64 - (cell / 2) as i64;
        let c = cell as i64;
        (
            shifted.div_euclid(c),
            (shifted.rem_euclid(c) as f64 + 0.5) / cell as f64,
        )
    }

    /// Model cells per side.
    pub(super) fn cells(&self) -> usize {
        self.m
    }

    fn next(&self, j: usize) -> usize {
        if j + 1 == self.m {
            0
        } else {
            j + 1
        }
    }

    /// The first model row (unwrapped, may be −1) that rows `first..=last` reach, and how
    /// many.
    pub(super) fn rows_reached(&self, first: usize, last: usize) -> (i64, usize) {
        let low = Self::unwrapped(self.cell, first).0;
        let high = Self::unwrapped(self.cell, last).0 + 1;
        (low, (high - low + 1) as usize)
    }
}

/// The coarse-space deflation for one grid.
pub(super) struct Deflation {
    n: usize,
    /// The extension's cell (half a model cell), in nodes, and those cells per side.
    half: usize,
    m_half: usize,
    /// Model cells per block side, blocks per side.
    per_block: usize,
    blocks: usize,
    pub(super) bilinear: Bilinear,
    fft: Fft2<f64>,
    scratch: Fft2Scratch,
    spectrum: Vec<Complex<f64>>,
    /// `Π K Π` on the model cells for |kx|, |ky| ∈ 0..=m/2, with the pair's normalisation.
    multiplier: Vec<f64>,
    /// Whether the contact set has settled (the deflation is used).
    pub(super) on: bool,
    /// Whether `inverse` belongs to the current settled phase.
    built: bool,
    /// Per extension cell: the interpolation weights of its nodes in F towards the four
    /// model cells they lie between (rows below/above × columns left/right), exact in f32.
    weights: Vec<[f32; 4]>,
    /// Per model cell: the restriction of `1_F` (`R`), the coarse deflection `V` of the
    /// correction, and working values.
    restricted: Vec<f64>,
    field: Vec<f64>,
    work: [Vec<f64>; 2],
    /// Per extension cell: `Σ_F g` less the correction's sum, for the extension's values.
    pub(super) adjusted: Vec<f64>,
    /// The mean of the correction over F, subtracted with it.
    shift: f64,
    /// The number of nodes in F, from [`Self::prepare`].
    total: f64,
    /// `E⁻¹` (blocks² × blocks², dense), `E` and its Cholesky factor while it is built,
    /// and the per-block vectors.
    inverse: Vec<f64>,
    matrix: Vec<f64>,
    factor: Vec<f64>,
    /// Per block: the restriction of its part of F on the model cells it reaches (a square
    /// of `per_block + 2` cells from one before its first).
    regions: Vec<f64>,
    count: Vec<f64>,
    sums: Vec<f64>,
    rhs: Vec<f64>,
    y: Vec<f64>,
    v: Vec<f64>,
    omega: Vec<f64>,
}

impl Deflation {
    /// The deflation for `op`'s grid with blocks of `block` nodes and extension cells of
    /// `half` nodes, when the box holds at least 2 blocks per side and both divide it (the
    /// extension builds it on large boxes only, [`super::Extension::large_box`]).
    pub(super) fn new<O: Operator>(op: &O, block: usize, half: usize) -> Option<Self> {
        let n = op.grid().n();
        let cell = 2 * half;
        if block == 0 || !block.is_multiple_of(cell) || !n.is_multiple_of(block) || n / block < 2 {
            return None;
        }
        let m = n / cell;
        let blocks = n / block;
        let nb = blocks * blocks;
        let fft = Fft2::new(m);
        let scratch = fft.make_scratch();
        let spectrum = fft.make_spectrum();
        Some(Self {
            n,
            half,
            m_half: n / half,
            per_block: block / cell,
            blocks,
            bilinear: Bilinear::new(n, cell),
            fft,
            scratch,
            spectrum,
            multiplier: cell_multiplier(op, cell),
            on: false,
            built: false,
            weights: vec![[0.0; 4]; (n / half) * (n / half)],
            restricted: vec![0.0; m * m],
            field: vec![0.0; m * m],
            work: std::array::from_fn(|_| vec![0.0; m * m]),
            adjusted: vec![0.0; (n / half) * (n / half)],
            shift: 0.0,
            total: 0.0,
            inverse: vec![0.0; nb * nb],
            matrix: vec![0.0; nb * nb],
            factor: vec![0.0; nb * nb],
            regions: vec![0.0; nb * (block / cell + 2).pow(2)],
            count: vec![0.0; nb],
            sums: vec![0.0; nb],
            rhs: vec![0.0; nb],
            y: vec![0.0; nb],
            v: vec![0.0; nb],
            omega: vec![0.0; nb],
        })
    }

    /// Use the deflation from the next iteration on, or not (a new settled phase builds
    /// `E` anew); whether that changed it.
    pub(super) fn switch(&mut self, on: bool) -> bool {
        if on && !self.on {
            self.built = false;
        }
        std::mem::replace(&mut self.on, on) != on
    }

    /// `out = Π K Π x` on the model cells.
    fn convolve(&mut self, x: &[f64], out: &mut [f64]) {
        let m = self.bilinear.m;
        let h = m / 2 + 1;
        self.fft.forward(x, &mut self.spectrum, &mut self.scratch);
        for (kx, column) in self.spectrum.chunks_mut(m).enumerate() {
            for (iy, s) in column.iter_mut().enumerate() {
                *s *= self.multiplier[kx * h + iy.min(m - iy)];
            }
        }
        self.fft.inverse(&mut self.spectrum, out, &mut self.scratch);
    }

    /// The extension cell's four target model cells (rows below/above, columns left/right).
    fn targets(&self, ci: usize, cj: usize) -> [usize; 4] {
        let m = self.bilinear.m as i64;
        let r0 = (ci as i64 - 1).div_euclid(2).rem_euclid(m) as usize;
        let c0 = (cj as i64 - 1).div_euclid(2).rem_euclid(m) as usize;
        let (r1, c1) = (self.bilinear.next(r0), self.bilinear.next(c0));
        let m = m as usize;
        [r0 * m + c0, r0 * m + c1, r1 * m + c0, r1 * m + c1]
    }

    /// The block of an extension cell.
    fn block_of(&self, ci: usize, cj: usize) -> usize {
        let per = 2 * self.per_block;
        (ci / per) * self.blocks + cj / per
    }

    /// Before the preconditioner's input pass: the interpolation weights of F, the density,
    /// `y = E⁻¹ Z̃ᵀ g` (E built first in a new settled phase) and the coarse deflection of
    /// `Z̃ y`, and the cell sums of the corrected input for the extension's values.
    pub(super) fn prepare<C: Constraint>(
        &mut self,
        p: &[f64],
        w: &[f64],
        level: Level<C>,
        sum_g: &[f64],
        count: &[f64],
    ) {
        self.gather_weights(p, w, level);
        let mh = self.m_half;
        self.restricted.fill(0.0);
        let mut sum_block = std::mem::take(&mut self.sums);
        sum_block.fill(0.0);
        self.count.fill(0.0);
        for ci in 0..mh {
            for cj in 0..mh {
                let k = ci * mh + cj;
                for (t, wt) in self.targets(ci, cj).into_iter().zip(self.weights_of(k)) {
                    self.restricted[t] += wt;
                }
                let b = self.block_of(ci, cj);
                self.count[b] += count[k];
                sum_block[b] += sum_g[k];
            }
        }
        if !self.built {
            self.build();
        }
        let total: f64 = self.count.iter().sum();
        self.total = total;
        let total_g: f64 = sum_block.iter().sum();
        for ((r, &s), &k) in self.rhs.iter_mut().zip(&sum_block).zip(&self.count) {
            *r = s - k / total * total_g;
        }
        self.sums = sum_block;
        solve_dense(&self.inverse, &self.rhs, &mut self.y);
        let mut x = std::mem::take(&mut self.work[0]);
        self.block_field(&self.y, &mut x);
        let mut field = std::mem::take(&mut self.field);
        self.convolve(&x, &mut field);
        self.field = field;
        // ω_a = ⟨W̃_a, 1_F⟩ from Π K Π R (in the second working field).
        let restricted = std::mem::take(&mut self.restricted);
        let mut compliance = std::mem::take(&mut self.work[1]);
        self.convolve(&restricted, &mut compliance);
        self.shift = restricted
            .iter()
            .zip(&self.field)
            .map(|(r, v)| r * v)
            .sum::<f64>()
            / total;
        let mut omega = std::mem::take(&mut self.omega);
        self.block_dots(&compliance, &mut omega);
        self.omega = omega;
        self.restricted = restricted;
        self.work = [x, compliance];
        for ci in 0..mh {
            for cj in 0..mh {
                let k = ci * mh + cj;
                let interpolated = self.cell_dot(ci, cj, &self.field);
                self.adjusted[k] = sum_g[k] - (interpolated - self.shift * count[k]);
            }
        }
    }

    /// `x = interpᵀ(Σ_a Y_a 1_{F ∩ a}) / (2c)²` on the model cells: the block values
    /// `values` on F restricted to the cells' centres, as densities.
    fn block_field(&self, values: &[f64], x: &mut [f64]) {
        let mh = self.m_half;
        let area = (self.bilinear.cell * self.bilinear.cell) as f64;
        x.fill(0.0);
        for ci in 0..mh {
            for cj in 0..mh {
                let value = values[self.block_of(ci, cj)] / area;
                for (t, wt) in self
                    .targets(ci, cj)
                    .into_iter()
                    .zip(self.weights_of(ci * mh + cj))
                {
                    x[t] += wt * value;
                }
            }
        }
    }

    /// Per block a: `⟨interpᵀ 1_{F ∩ a}, field⟩ / (2c)²`.
    fn block_dots(&self, field: &[f64], out: &mut [f64]) {
        let area = (self.bilinear.cell * self.bilinear.cell) as f64;
        out.fill(0.0);
        for k in 0..self.weights.len() {
            let (ci, cj) = (k / self.m_half, k % self.m_half);
            out[self.block_of(ci, cj)] += self.cell_dot(ci, cj, field) / area;
        }
    }

    /// `⟨interpᵀ 1_{F ∩ I}, field⟩` for the extension cell I = (ci, cj): the sum of `field`
    /// interpolated on its nodes in F.
    fn cell_dot(&self, ci: usize, cj: usize, field: &[f64]) -> f64 {
        self.targets(ci, cj)
            .into_iter()
            .zip(self.weights_of(ci * self.m_half + cj))
            .map(|(t, wt)| wt * field[t])
            .sum()
    }

    /// The interpolation weights of extension cell `k`.
    fn weights_of(&self, k: usize) -> [f64; 4] {
        self.weights[k].map(f64::from)
    }

    /// The interpolation weights of F per extension cell, in parallel over rows of cells.
    /// Stored in single precision without rounding for the committed cells: a node's
    /// weights are multiples of 1/(2·2c) = 1/32, their products multiples of 1/1024, and a
    /// cell's sums of at most 64 of them need 16 bits of the mantissa's 24.
    fn gather_weights<C: Constraint>(&mut self, p: &[f64], w: &[f64], level: Level<C>) {
        let (n, half) = (self.n, self.half);
        let bilinear = &self.bilinear;
        self.weights
            .par_chunks_mut(self.m_half)
            .enumerate()
            .for_each(|(ci, cells)| {
                cells.fill([0.0; 4]);
                for i in ci * half..(ci + 1) * half {
                    let a = Bilinear::unwrapped(bilinear.cell, i).1;
                    let (pr, wr) = (&p[i * n..(i + 1) * n], &w[i * n..(i + 1) * n]);
                    for (cj, cell) in cells.iter_mut().enumerate() {
                        let (mut k, mut kb) = (0.0, 0.0);
                        for j in cj * half..(cj + 1) * half {
                            if level.free(pr[j], wr[j]) {
                                k += 1.0;
                                kb += bilinear.col_weight[j];
                            }
                        }
                        cell[0] += ((1.0 - a) * (k - kb)) as f32;
                        cell[1] += ((1.0 - a) * kb) as f32;
                        cell[2] += (a * (k - kb)) as f32;
                        cell[3] += (a * kb) as f32;
                    }
                }
            });
    }

    /// `E = Z̃ᵀ W̃` (symmetrised, on the mean-free block vectors) and its inverse: one
    /// coarse convolution per block.
    fn build(&mut self) {
        let (m, mh, nb) = (self.bilinear.m, self.m_half, self.count.len());
        let span = self.per_block + 2;
        let mut regions = std::mem::take(&mut self.regions);
        regions.fill(0.0);
        for ci in 0..mh {
            for cj in 0..mh {
                let b = self.block_of(ci, cj);
                let (bi, bj) = (b / self.blocks, b % self.blocks);
                let r0 = (ci as i64 - 1).div_euclid(2) - (bi * self.per_block) as i64 + 1;
                let c0 = (cj as i64 - 1).div_euclid(2) - (bj * self.per_block) as i64 + 1;
                let region = &mut regions[b * span * span..(b + 1) * span * span];
                let wts = self.weights_of(ci * mh + cj);
                for (k, wt) in wts.into_iter().enumerate() {
                    let (r, c) = (r0 as usize + k / 2, c0 as usize + k % 2);
                    region[r * span + c] += wt;
                }
            }
        }
        let mut e = std::mem::take(&mut self.matrix);
        let mut x = std::mem::take(&mut self.work[0]);
        let mut u = std::mem::take(&mut self.work[1]);
        let area = (self.bilinear.cell * self.bilinear.cell) as f64;
        let (blocks, per_block) = (self.blocks, self.per_block);
        let cell_of = move |a: usize, r: usize, c: usize| {
            let (ai, aj) = (a / blocks, a % blocks);
            let row = (ai * per_block + m + r - 1) % m;
            let col = (aj * per_block + m + c - 1) % m;
            row * m + col
        };
        for b in 0..nb {
            x.fill(0.0);
            let region = &regions[b * span * span..(b + 1) * span * span];
            for r in 0..span {
                for c in 0..span {
                    x[cell_of(b, r, c)] += region[r * span + c] / area;
                }
            }
            self.convolve(&x, &mut u);
            for a in 0..nb {
                let region = &regions[a * span * span..(a + 1) * span * span];
                let mut s = 0.0;
                for r in 0..span {
                    for c in 0..span {
                        s += region[r * span + c] * u[cell_of(a, r, c)];
                    }
                }
                e[a * nb + b] = s;
            }
        }
        self.work = [x, u];
        // A Gram matrix (symmetric to rounding, positive semi-definite), on the mean-free
        // block vectors (Σ_a Z̃_a = 0): projected off the constant, which gets the mean
        // diagonal instead.
        for a in 0..nb {
            for b in 0..a {
                let s = 0.5 * (e[a * nb + b] + e[b * nb + a]);
                e[a * nb + b] = s;
                e[b * nb + a] = s;
            }
        }
        let scale = (0..nb).map(|a| e[a * nb + a]).sum::<f64>() / nb as f64;
        for a in 0..nb {
            if self.count[a] == 0.0 {
                for b in 0..nb {
                    e[a * nb + b] = 0.0;
                    e[b * nb + a] = 0.0;
                }
                e[a * nb + a] = scale;
            }
        }
        project_constant(&mut e, nb, scale, &mut self.rhs);
        // Not positive definite to rounding (F's block vectors nearly dependent): no
        // deflation in this settled phase (E⁻¹ = 0 gives back M).
        if !invert_spd(&e, nb, &mut self.factor, &mut self.inverse, &mut self.v) {
            self.inverse.fill(0.0);
        }
        self.matrix = e;
        self.regions = regions;
        self.built = true;
    }

    /// One row of the preconditioner's input on F less the correction `W̃ y` there.
    pub(super) fn subtract_row<C: Constraint>(
        &self,
        i: usize,
        o: &mut [f32],
        p: &[f64],
        w: &[f64],
        level: Level<C>,
    ) {
        let b = &self.bilinear;
        let m = b.m;
        let (r0, a) = Bilinear::split(b.cell, m, i);
        let (v0, v1) = (
            &self.field[r0 * m..(r0 + 1) * m],
            &self.field[b.next(r0) * m..(b.next(r0) + 1) * m],
        );
        for (j, o) in o.iter_mut().enumerate() {
            if level.free(p[j], w[j]) {
                let (c0, c1, t) = (b.col_cell[j], b.next(b.col_cell[j]), b.col_weight[j]);
                let top = v0[c0] + t * (v0[c1] - v0[c0]);
                let bottom = v1[c0] + t * (v1[c1] - v1[c0]);
                let value = top + a * (bottom - top) - self.shift;
                *o = ((w[j] - level.mean) - value) as f32;
            }
        }
    }

    /// Adds the restriction of one output row on F to its block's model rows.
    pub(super) fn restrict_row<C: Constraint>(
        bilinear: &Bilinear,
        block: &mut OffBlock,
        i: usize,
        row: &[f32],
        p: &[f64],
        w: &[f64],
        level: Level<C>,
    ) {
        let (m, half) = (bilinear.m, bilinear.cell / 2);
        let (first, a) = Bilinear::unwrapped(bilinear.cell, i);
        let local = (first - block.restrict_low) as usize;
        let (below, above) = block.restrict[local * m..(local + 2) * m].split_at_mut(m);
        for (jc, ((yc, pc), wc)) in row
            .chunks(half)
            .zip(p.chunks(half))
            .zip(w.chunks(half))
            .enumerate()
        {
            let (mut s, mut sb) = (0.0, 0.0);
            for (o, ((&y, &pv), &wv)) in yc.iter().zip(pc).zip(wc).enumerate() {
                if level.free(pv, wv) {
                    s += y as f64;
                    sb += y as f64 * bilinear.col_weight[jc * half + o];
                }
            }
            let c0 = bilinear.col_cell[jc * half];
            let c1 = bilinear.next(c0);
            below[c0] += (1.0 - a) * (s - sb);
            below[c1] += (1.0 - a) * sb;
            above[c0] += a * (s - sb);
            above[c1] += a * sb;
        }
    }

    /// After the extension's correction `back` (per extension cell, on F): `v = E⁻¹ W̃ᵀ s`
    /// for the output `s` (the rows restricted in `blocks`, `z_sum` their sum over F, and
    /// `back`), and `back += y − v` per block.
    pub(super) fn finish(
        &mut self,
        back: &mut [f64],
        count: &[f64],
        z_sum: f64,
        blocks: &[OffBlock],
    ) {
        let (m, mh) = (self.bilinear.m, self.m_half);
        let mut t = std::mem::take(&mut self.work[0]);
        t.fill(0.0);
        for block in blocks {
            for (k, row) in block.restrict.chunks(m).enumerate() {
                let r = (block.restrict_low + k as i64).rem_euclid(m as i64) as usize;
                for (s, &v) in t[r * m..(r + 1) * m].iter_mut().zip(row) {
                    *s += v;
                }
            }
        }
        let mut s_sum = z_sum;
        for ci in 0..mh {
            for cj in 0..mh {
                let k = ci * mh + cj;
                s_sum += count[k] * back[k];
                for (target, wt) in self.targets(ci, cj).into_iter().zip(self.weights_of(k)) {
                    t[target] += back[k] * wt;
                }
            }
        }
        let mean = s_sum / self.total;
        let mut q = std::mem::take(&mut self.work[1]);
        self.convolve(&t, &mut q);
        let mut e = std::mem::take(&mut self.rhs);
        self.block_dots(&q, &mut e);
        for (e, &o) in e.iter_mut().zip(&self.omega) {
            *e -= mean * o;
        }
        self.work = [t, q];
        solve_dense(&self.inverse, &e, &mut self.v);
        self.rhs = e;
        for ci in 0..mh {
            for cj in 0..mh {
                let b = self.block_of(ci, cj);
                back[ci * mh + cj] += self.y[b] - self.v[b];
            }
        }
    }
}

/// `Π K Π` on cells of `cell` nodes as a multiplier of the coarse grid's unnormalised FFT
/// pair: `(1/(c² n²)) Σ K̂(q) |D(q)|²` over the fine wavevectors `q` that alias to the
/// coarse one, `D` the transform of a cell's indicator.
fn cell_multiplier<O: Operator>(op: &O, cell: usize) -> Vec<f64> {
    let grid = op.grid();
    let n = grid.n();
    let m = n / cell;
    let h = m / 2 + 1;
    let box_filter: Vec<f64> = (0..n)
        .map(|q| {
            if q == 0 {
                (cell * cell) as f64
            } else {
                let x = std::f64::consts::PI * q as f64 / n as f64;
                ((x * cell as f64).sin() / x.sin()).powi(2)
            }
        })
        .collect();
    let compliance = |qx: usize, qy: usize| {
        let (kx, ky) = (grid.wrapped_index(qx) as f64, grid.wrapped_index(qy) as f64);
        let k = (kx * kx + ky * ky).sqrt();
        if k > 0.0 {
            2.0 / (op.e_star() * grid.q_unit() * k)
        } else {
            0.0
        }
    };
    let norm = 1.0 / ((cell * cell) as f64 * (n * n) as f64);
    let mut out = vec![0.0; h * h];
    for kx in 0..h {
        for ky in 0..h {
            let mut s = 0.0;
            for ax in 0..cell {
                for ay in 0..cell {
                    let (qx, qy) = (kx + m * ax, ky + m * ay);
                    s += compliance(qx, qy) * box_filter[qx] * box_filter[qy];
                }
            }
            out[kx * h + ky] = s * norm;
        }
    }
    out
}

/// `e ← Π e Π + scale · 1 1ᵀ / k`, `Π = I − 1 1ᵀ / k` (`row`: k values of work): positive
/// definite when `e` is on the mean-free vectors, with the same inverse there.
fn project_constant(e: &mut [f64], k: usize, scale: f64, row: &mut [f64]) {
    for (a, r) in row.iter_mut().enumerate() {
        *r = e[a * k..(a + 1) * k].iter().sum::<f64>() / k as f64;
    }
    let all = row.iter().sum::<f64>() / k as f64;
    for a in 0..k {
        for b in 0..k {
            e[a * k + b] += all - row[a] - row[b] + scale / k as f64;
        }
    }
}

/// `inverse = e⁻¹` for a symmetric positive definite k × k matrix, by Cholesky (`l`: the
/// factor, `column`: k values of work); false when a pivot is not positive to rounding.
fn invert_spd(e: &[f64], k: usize, l: &mut [f64], inverse: &mut [f64], column: &mut [f64]) -> bool {
    l.fill(0.0);
    for i in 0..k {
        for j in 0..=i {
            let s = e[i * k + j] - (0..j).map(|t| l[i * k + t] * l[j * k + t]).sum::<f64>();
            if i == j {
                // Also false for NaN.
                if s.partial_cmp(&(1e-12 * e[i * k + i].abs())) != Some(std::cmp::Ordering::Greater)
                {
                    return false;
                }
                l[i * k + i] = s.sqrt();
            } else {
                l[i * k + j] = s / l[j * k + j];
            }
        }
    }
    for c in 0..k {
        // L Lᵀ x = e_c, forward then backward.
        for i in 0..k {
            let rhs = if i == c { 1.0 } else { 0.0 };
            column[i] =
                (rhs - (0..i).map(|t| l[i * k + t] * column[t]).sum::<f64>()) / l[i * k + i];
        }
        for i in (0..k).rev() {
            column[i] = (column[i] - (i + 1..k).map(|t| l[t * k + i] * column[t]).sum::<f64>())
                / l[i * k + i];
        }
        for i in 0..k {
            inverse[i * k + c] = column[i];
        }
    }
    true
}

/// `out = inverse · rhs`.
fn solve_dense(inverse: &[f64], rhs: &[f64], out: &mut [f64]) {
    let k = rhs.len();
    for (o, row) in out.iter_mut().zip(inverse.chunks(k)) {
        *o = row.iter().zip(rhs).map(|(a, b)| a * b).sum();
    }
}

#[cfg(test)]
mod tests;
