//! The free-set extension of the preconditioner (the default, [`super::SolverConfig::extension`]).
//!
//! `M = P K⁻¹ P` answers a slow modulation `f` of the gradient over the free set F with
//! `f · P K⁻¹ 1_F`, the stiff local response of each cluster, while the restricted operator
//! answers it with the compliance of the whole surface under a load of density φ (the local
//! fraction of F): the long modes are over-weighted by about φ L / a (a the cluster size), and
//! the iteration count grows with the contact fraction and the box. The extension gives the
//! surface off F the smoothed gradient, so that `K⁻¹` sees a slow modulation as a slow field:
//!
//! `M_E = P Eᵀ K⁻¹ E P`, `E = 1_F + γ (1 − 1_F) D⁻¹ S 1_F`, `Eᵀ = 1_F + γ 1_F S D⁻¹ (1 − 1_F)`,
//!
//! with `S = U G Uᵀ / c²` (`Uᵀ`: sums over cells of c × c nodes, `U`: the cell's value on its
//! nodes, `G`: a periodic Gaussian on the cells), `D = max(S 1_F, D_min)` the smoothed density
//! of F. `M_E` is symmetric and positive like `M` (the same `D` on both sides), equal to `M`
//! in full contact (`E = 1`), and costs one pass over `p` and `w` for the cell sums plus two
//! smoothings on the coarse grid (n/c per side) per iteration. The floor `D_min` fades the
//! extension out where F is sparse, where `M` is already accurate.

use rayon::prelude::*;

use super::precond::free;
use super::rows::avx2_dispatch;

/// Settings of the preconditioner's free-set extension.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Extension {
    /// Side of the coarse cells, in grid nodes (Δl).
    pub cell: usize,
    /// Standard deviation of the Gaussian smoothing, in grid nodes (Δl).
    pub sigma: f64,
    /// Weight γ of the extension (0 gives back `P K⁻¹ P`).
    pub weight: f64,
    /// Floor `D_min` of the smoothed density of the free set.
    pub density_floor: f64,
}

impl Default for Extension {
    /// The settings measured on the paper's spectrum and the bench surfaces at 1024²–4096²
    /// (docs/BENCHMARKS.md): γ = 0.7 saves a few more iterations at 1024² but makes one load
    /// at 2048² crawl (424 iterations in the replica), γ = 0.5 does not.
    fn default() -> Self {
        Self {
            cell: 8,
            sigma: 32.0,
            weight: 0.5,
            density_floor: 0.05,
        }
    }
}

impl Extension {
    /// A message naming the invalid setting, if any.
    pub(super) fn check(&self) -> Result<(), String> {
        if self.cell == 0 {
            return Err("extension cell must be ≥ 1 node".into());
        }
        if !(self.sigma.is_finite() && self.sigma > 0.0) {
            return Err(format!(
                "extension sigma {} must be finite and > 0",
                self.sigma
            ));
        }
        if !(self.weight.is_finite() && (0.0..=1.0).contains(&self.weight)) {
            return Err(format!(
                "extension weight {} must lie in [0, 1]",
                self.weight
            ));
        }
        if !(self.density_floor.is_finite() && self.density_floor > 0.0) {
            return Err(format!(
                "extension density floor {} must be finite and > 0",
                self.density_floor
            ));
        }
        Ok(())
    }
}

/// Per row block of the FFT: the sums of `y / D` off F over the cells its rows touch.
pub(super) struct OffBlock {
    first_row: usize,
    first_cell_row: usize,
    sums: Vec<f64>,
}

/// The coarse-grid state of the extension for one grid and settings.
pub(super) struct Coarse {
    pub(super) settings: Extension,
    n: usize,
    cell: usize,
    /// Cells per side.
    m: usize,
    /// The periodic Gaussian on the cells, offsets −h..=h.
    kernel: Vec<f64>,
    /// Per cell: `Σ_F g`.
    sum_g: Vec<f64>,
    /// Per cell: `|F|`.
    count: Vec<f64>,
    /// Per cell: the extension's value off F, `γ (G Uᵀ 1_F g / c²) / D`.
    value: Vec<f64>,
    /// Per cell: `D`.
    density: Vec<f64>,
    /// Per cell: `γ (G Uᵀ (1 − 1_F) y / D) / c²`, added to `K⁻¹ E g` on F.
    back: Vec<f64>,
    scratch: Vec<f64>,
    scratch2: Vec<f64>,
    pub(super) blocks: Vec<OffBlock>,
}

impl Coarse {
    pub(super) fn new(n: usize, rows_per_block: usize, settings: Extension) -> Self {
        let cell = settings.cell.min(n).max(1);
        let m = n.div_ceil(cell);
        let sigma_cells = settings.sigma / cell as f64;
        let h = ((4.0 * sigma_cells).ceil() as usize).min(m / 2);
        let mut kernel: Vec<f64> = (0..=2 * h)
            .map(|k| {
                let d = k as f64 - h as f64;
                (-0.5 * d * d / (sigma_cells * sigma_cells)).exp()
            })
            .collect();
        let total: f64 = kernel.iter().sum();
        kernel.iter_mut().for_each(|k| *k /= total);
        let blocks = (0..n.div_ceil(rows_per_block))
            .map(|b| {
                let first = b * rows_per_block;
                let last = ((b + 1) * rows_per_block).min(n) - 1;
                let cells = last / cell - first / cell + 1;
                OffBlock {
                    first_row: first,
                    first_cell_row: first / cell,
                    sums: vec![0.0; cells * m],
                }
            })
            .collect();
        Self {
            settings,
            n,
            cell,
            m,
            kernel,
            sum_g: vec![0.0; m * m],
            count: vec![0.0; m * m],
            value: vec![0.0; m * m],
            density: vec![0.0; m * m],
            back: vec![0.0; m * m],
            scratch: vec![0.0; m * m],
            scratch2: vec![0.0; m * m],
            blocks,
        }
    }

    /// The cell sums of `g = w − level` and of `1_F` over F, then `D` and the extension's
    /// values. One pass over `p` and `w`, in parallel over rows of cells (each summed in node
    /// order, so the same bits whatever the number of threads).
    pub(super) fn gather(&mut self, p: &[f64], w: &[f64], level: f64) {
        let (n, c, m) = (self.n, self.cell, self.m);
        self.sum_g
            .par_chunks_mut(m)
            .zip(self.count.par_chunks_mut(m))
            .enumerate()
            .for_each(|(ci, (sg, cnt))| {
                sg.fill(0.0);
                cnt.fill(0.0);
                for i in ci * c..((ci + 1) * c).min(n) {
                    let (pr, wr) = (&p[i * n..(i + 1) * n], &w[i * n..(i + 1) * n]);
                    dispatch_cell_sums(c, level, sg, cnt, pr, wr);
                }
            });
        let area = (c * c) as f64;
        let floor = self.settings.density_floor;
        let gamma = self.settings.weight;
        self.scratch2
            .iter_mut()
            .zip(&self.count)
            .for_each(|(s, &k)| *s = k / area);
        smooth(
            &self.kernel,
            m,
            &self.scratch2,
            &mut self.scratch,
            &mut self.density,
        );
        self.density.iter_mut().for_each(|d| *d = d.max(floor));
        self.scratch2
            .iter_mut()
            .zip(&self.sum_g)
            .for_each(|(s, &g)| *s = g / area);
        smooth(
            &self.kernel,
            m,
            &self.scratch2,
            &mut self.scratch,
            &mut self.value,
        );
        self.value
            .iter_mut()
            .zip(&self.density)
            .for_each(|(v, &d)| *v = gamma * *v / d);
    }

    /// One row of the preconditioner's input `E g`: `g` on F, the cell's extension value off
    /// it, in single precision.
    pub(super) fn input_row(&self, i: usize, o: &mut [f32], p: &[f64], w: &[f64], level: f64) {
        let (c, m) = (self.cell, self.m);
        let values = &self.value[(i / c) * m..(i / c + 1) * m];
        dispatch_input(c, values, level, o, p, w);
    }

    /// Adds one row of `K⁻¹ E g` off F, divided by `D`, to its block's cell sums.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn output_row(
        cell: usize,
        m: usize,
        density: &[f64],
        block: &mut OffBlock,
        r: usize,
        row: &[f32],
        p: &[f64],
        w: &[f64],
        level: f64,
    ) {
        let i = block.first_row + r;
        if r == 0 {
            block.sums.fill(0.0);
        }
        let local = i / cell - block.first_cell_row;
        let sums = &mut block.sums[local * m..(local + 1) * m];
        let dens = &density[(i / cell) * m..(i / cell + 1) * m];
        dispatch_off_sums(cell, dens, level, sums, row, p, w);
    }

    /// The cell size, cells per side and `D`, for [`Self::output_row`] while the blocks are
    /// borrowed.
    pub(super) fn output_parts(&mut self) -> (usize, usize, &[f64], &mut [OffBlock]) {
        (self.cell, self.m, &self.density, &mut self.blocks)
    }

    /// After the output pass: the correction on F per cell, and its sums
    /// `(Σ_F b, Σ_F g b)` (cells in order).
    pub(super) fn finish(&mut self) -> (f64, f64) {
        let m = self.m;
        self.scratch2.fill(0.0);
        for block in &self.blocks {
            let at = block.first_cell_row * m;
            for (s, &v) in self.scratch2[at..at + block.sums.len()]
                .iter_mut()
                .zip(&block.sums)
            {
                *s += v;
            }
        }
        let area = (self.cell * self.cell) as f64;
        self.scratch2.iter_mut().for_each(|s| *s /= area);
        smooth(
            &self.kernel,
            m,
            &self.scratch2,
            &mut self.scratch,
            &mut self.back,
        );
        let gamma = self.settings.weight;
        self.back.iter_mut().for_each(|b| *b *= gamma);
        let (mut sum_b, mut sum_gb) = (0.0, 0.0);
        for ((&b, &k), &g) in self.back.iter().zip(&self.count).zip(&self.sum_g) {
            sum_b += k * b;
            sum_gb += g * b;
        }
        (sum_b, sum_gb)
    }

    /// The correction on F of row `i`, per cell of the row.
    pub(super) fn back_row(&self, i: usize) -> &[f64] {
        let (c, m) = (self.cell, self.m);
        &self.back[(i / c) * m..(i / c + 1) * m]
    }

    pub(super) fn cell(&self) -> usize {
        self.cell
    }
}

avx2_dispatch! {
    /// Adds one row's sums of `g = w − level` and of `1_F` over each cell's nodes in F to
    /// `sum_g` and `count` (nodes in order within a cell; AVX2 where available, the same
    /// operations).
    fn dispatch_cell_sums(
        cell: usize,
        level: f64,
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
                if free(pv, wv, level) {
                    s += wv - level;
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
    fn dispatch_input(
        cell: usize,
        values: &[f64],
        level: f64,
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
                *o = if free(pv, wv, level) {
                    (wv - level) as f32
                } else {
                    v
                };
            }
        }
    }
}

avx2_dispatch! {
    /// Adds `Σ y / D` over the nodes of each cell of a row that are off F to `sums` (nodes
    /// in order within a cell).
    fn dispatch_off_sums(
        cell: usize,
        density: &[f64],
        level: f64,
        sums: &mut [f64],
        row: &[f32],
        p: &[f64],
        w: &[f64],
    ) {
        for (((yc, pc), wc), (s, &d)) in row
            .chunks(cell)
            .zip(p.chunks(cell))
            .zip(w.chunks(cell))
            .zip(sums.iter_mut().zip(density))
        {
            let mut acc = 0.0;
            for ((&y, &pv), &wv) in yc.iter().zip(pc).zip(wc) {
                if !free(pv, wv, level) {
                    acc += y as f64;
                }
            }
            *s += acc / d;
        }
    }
}

avx2_dispatch! {
    /// One row of the preconditioned direction with the extension's correction:
    /// `t ← (z + (b − z̄)) + β (t − t̄)` on F (where `z` is a number; `b` per cell), 0
    /// elsewhere, copied into `row` (AVX2 where available: the same operations per node).
    pub(super) fn dispatch_direction(
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
fn smooth(kernel: &[f64], m: usize, x: &[f64], tmp: &mut [f64], out: &mut [f64]) {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The smoothing is symmetric (⟨a, G b⟩ = ⟨G a, b⟩, to rounding) and keeps constants
    /// and sums (the kernel sums to 1), so `S = U G Uᵀ / c²` is symmetric and `M_E` with it.
    #[test]
    fn smoothing_is_symmetric_and_conservative() {
        let m = 12;
        let kernel = Coarse::new(96, 4, Extension::default()).kernel;
        assert!(kernel.len() <= m + 1);
        let mut state = 1u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let a: Vec<f64> = (0..m * m).map(|_| next()).collect();
        let b: Vec<f64> = (0..m * m).map(|_| next()).collect();
        let (mut tmp, mut ga, mut gb) = (vec![0.0; m * m], vec![0.0; m * m], vec![0.0; m * m]);
        smooth(&kernel, m, &a, &mut tmp, &mut ga);
        smooth(&kernel, m, &b, &mut tmp, &mut gb);
        let lhs: f64 = a.iter().zip(&gb).map(|(x, y)| x * y).sum();
        let rhs: f64 = ga.iter().zip(&b).map(|(x, y)| x * y).sum();
        assert!(
            (lhs - rhs).abs() <= 1e-14 * lhs.abs().max(1.0),
            "{lhs} {rhs}"
        );
        let (sa, sga): (f64, f64) = (a.iter().sum(), ga.iter().sum());
        assert!((sa - sga).abs() <= 1e-13, "{sa} {sga}");
        let ones = vec![1.0; m * m];
        smooth(&kernel, m, &ones, &mut tmp, &mut ga);
        assert!(ga.iter().all(|&v| (v - 1.0).abs() < 1e-14));
    }
}
