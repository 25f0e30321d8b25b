//! The periodic elastic half-space: deflection from pressure by a Fourier multiplier.
//!
//! For frictionless normal contact of a half-space with effective modulus `E*`,
//! `û(q) = 2 p̂(q) / (E* |q|)` with the angular wavevector `q` (VALIDATION.md §1.1). The
//! `q = 0` mode is set to zero: a uniform pressure gives no deflection, and the mean
//! deflection (undefined for a periodic half-space) is zero. Pressures are compressive
//! positive; `u` is the deflection into the solid. The discrete operator applies the
//! continuous kernel at the discrete wavevectors ("spectral" / point-value scheme, as
//! Tamaas), with the Nyquist index taken as `|k| = n/2`.

use rayon::prelude::*;
use rustfft::num_complex::Complex;

use crate::grid::Grid;
use crate::spectral::{Fft2, Fft2Scratch, Real};

/// The operator `u = K p` on one grid: planned FFTs and the multiplier, built once.
pub struct ElasticOperator {
    grid: Grid,
    e_star: f64,
    fft: Fft2,
    /// Single-precision plans for the inverse operator (the solver's preconditioner), run
    /// in the same scratch as `fft`.
    fft_single: Fft2<f32>,
    /// `2/(E*|q|) / n²` for kx ∈ 0..=n/2 and |ky| ∈ 0..=n/2 (the multiplier depends on
    /// |ky| only), row-major by kx; 0 at q = 0. Includes the `1/n²` of the FFT pair.
    multiplier: Vec<f64>,
    /// Response to a unit pressure on node (0, 0), by periodic row distance and column
    /// offset: `kernel_rows[|dy| * n + dx]` for `|dy| ∈ 0..=n/2`, `dx ∈ 0..n` (`(n/2+1) · n`
    /// values; the response is even in both directions, `K(dx) = K(n − dx)`, symmetrised
    /// exactly), so that a point load adds two ascending runs to a row.
    kernel_rows: Vec<f64>,
}

/// Working memory of [`ElasticOperator::apply`]; allocate once with
/// [`ElasticOperator::make_workspace`].
pub struct OperatorWorkspace {
    scratch: Fft2Scratch,
    partials: Vec<f64>,
}

impl OperatorWorkspace {
    /// A workspace of `scratch` and `columns` partial sums (one per half-spectrum column).
    pub(crate) fn new(scratch: Fft2Scratch, columns: usize) -> Self {
        Self {
            scratch,
            partials: vec![0.0; columns],
        }
    }

    pub(crate) fn scratch_mut(&mut self) -> &mut Fft2Scratch {
        &mut self.scratch
    }

    /// The partial sums (`columns` of them) and the scratch.
    pub(crate) fn parts_mut(&mut self, columns: usize) -> (&mut [f64], &mut Fft2Scratch) {
        debug_assert_eq!(self.partials.len(), columns);
        (&mut self.partials, &mut self.scratch)
    }
}

impl ElasticOperator {
    /// Plan the operator for `grid` and effective modulus `e_star` (> 0).
    pub fn new(grid: Grid, e_star: f64) -> Self {
        assert!(
            e_star.is_finite() && e_star > 0.0,
            "E* must be finite and > 0"
        );
        let n = grid.n();
        let h = grid.half_len();
        let fft = Fft2::new(n);
        let fft_single = Fft2::<f32>::new(n);
        let norm = 1.0 / (n * n) as f64;
        let mut multiplier = vec![0.0; h * h];
        for jx in 0..h {
            for ky in 0..h {
                let q = grid.q_norm(jx, ky);
                multiplier[jx * h + ky] = if q > 0.0 {
                    2.0 / (e_star * q) * norm
                } else {
                    0.0
                };
            }
        }
        let mut op = Self {
            grid,
            e_star,
            fft,
            fft_single,
            multiplier,
            kernel_rows: Vec::new(),
        };
        let mut ws = op.make_workspace();
        let mut unit = vec![0.0; n * n];
        unit[0] = 1.0;
        let mut response = vec![0.0; n * n];
        op.apply(&unit, &mut response, &mut ws);
        op.kernel_rows = (0..h * n)
            .map(|i| {
                let (dy, dx) = (i / n, i % n);
                response[dy * n + dx.min(n - dx)]
            })
            .collect();
        op
    }

    pub fn grid(&self) -> &Grid {
        &self.grid
    }

    pub fn e_star(&self) -> f64 {
        self.e_star
    }

    /// Deflection at a node per unit pressure applied on that node alone (`K_ii`).
    pub fn self_influence(&self) -> f64 {
        self.kernel_rows[0]
    }

    pub fn make_workspace(&self) -> OperatorWorkspace {
        self.fft_single.prepare_threads();
        OperatorWorkspace {
            scratch: self.fft.make_scratch(),
            partials: vec![0.0; self.grid.half_len()],
        }
    }

    /// `output = K input` (row-major `n × n` fields). Allocates nothing.
    pub fn apply(&self, input: &[f64], output: &mut [f64], ws: &mut OperatorWorkspace) {
        self.apply_with_energy(input, output, ws);
    }

    /// `output = K input`, returning `Σ_i input_i output_i` computed by Parseval in the
    /// spectral domain at no extra memory traffic (fixed summation order).
    pub fn apply_with_energy(
        &self,
        input: &[f64],
        output: &mut [f64],
        ws: &mut OperatorWorkspace,
    ) -> f64 {
        let n = self.grid.n();
        assert_eq!(input.len(), n * n, "input must have n² values");
        assert_eq!(output.len(), n * n, "output must have n² values");
        let block_len = self.rows_per_block() * n;
        let energy = self.start_rows(
            input.par_chunks(block_len),
            |rows: &mut &[f64], r, buf| buf.copy_from_slice(&rows[r * n..(r + 1) * n]),
            ws,
        );
        self.finish_rows(
            output.par_chunks_mut(block_len),
            |rows: &mut &mut [f64], r, row| rows[r * n..(r + 1) * n].copy_from_slice(row),
            ws,
        );
        energy
    }

    /// Rows per work block of the fused passes ([`Fft2::rows_per_block`]): fields split
    /// with `par_chunks(rows_per_block · n)` give one state per block.
    pub fn rows_per_block(&self) -> usize {
        self.fft.rows_per_block()
    }

    /// First half of a fused application of `K` ([`Fft2::convolve_start`]): the input
    /// field is produced row by row by `produce`, transformed, multiplied and transformed
    /// back along y; returns `⟨t, K t⟩` (Parseval). The result stays in `ws` for
    /// [`Self::finish_rows`], which must follow before `ws` is used again.
    pub fn start_rows<S, I, F>(&self, blocks: I, produce: F, ws: &mut OperatorWorkspace) -> f64
    where
        S: Send,
        I: IndexedParallelIterator<Item = S>,
        F: Fn(&mut S, usize, &mut [f64]) + Sync,
    {
        self.start_rows_with(&self.fft, blocks, produce, ws, |m| m)
    }

    /// [`Self::start_rows`] for the inverse operator `K⁻¹` (multiplier `E*|q|/2`, 0 at
    /// q = 0), the Fourier preconditioner of the solver, **in single precision**: the rows
    /// `produce` fills are `f32`, and so are those [`Self::finish_rows_inverse`] hands over.
    /// A preconditioner need only be a fixed symmetric positive operator, and this one's
    /// rounding (relative 10⁻⁷) leaves the solver's iteration counts unchanged while its
    /// transforms take about 0.6 of the time (docs/BENCHMARKS.md). Returns `⟨t, K⁻¹ t⟩`.
    pub fn start_rows_inverse<S, I, F>(
        &self,
        blocks: I,
        produce: F,
        ws: &mut OperatorWorkspace,
    ) -> f64
    where
        S: Send,
        I: IndexedParallelIterator<Item = S>,
        F: Fn(&mut S, usize, &mut [f32]) + Sync,
    {
        let n = self.grid.n() as f64;
        // The stored multiplier carries the FFT pair's 1/n²: (E*|q|/2)/n² = n⁻⁴ / m.
        let norm2 = 1.0 / (n * n * n * n);
        self.start_rows_with(&self.fft_single, blocks, produce, ws, move |m| {
            if m > 0.0 {
                norm2 / m
            } else {
                0.0
            }
        })
    }

    /// Second half of [`Self::start_rows_inverse`]: `K⁻¹ t` row by row, in `f32`.
    pub fn finish_rows_inverse<S, I, F>(&self, blocks: I, consume: F, ws: &mut OperatorWorkspace)
    where
        S: Send,
        I: IndexedParallelIterator<Item = S>,
        F: Fn(&mut S, usize, &[f32]) + Sync,
    {
        self.fft_single
            .convolve_finish(blocks, consume, &mut ws.scratch);
    }

    /// The fused first half with the multiplier `gain(m)` of the stored `m`.
    fn start_rows_with<T: Real, S, I, F>(
        &self,
        fft: &Fft2<T>,
        blocks: I,
        produce: F,
        ws: &mut OperatorWorkspace,
        gain: impl Fn(f64) -> f64 + Sync,
    ) -> f64
    where
        S: Send,
        I: IndexedParallelIterator<Item = S>,
        F: Fn(&mut S, usize, &mut [T]) + Sync,
    {
        let h = self.grid.half_len();
        fft.convolve_start(
            blocks,
            produce,
            |jx, col| {
                let m = &self.multiplier[jx * h..(jx + 1) * h];
                self.grid.half_weight(jx) * multiply_column(col, m, &gain)
            },
            &mut ws.partials,
            &mut ws.scratch,
        );
        ws.partials.iter().sum()
    }

    /// Second half of a fused application of `K` started by [`Self::start_rows`]: the
    /// result `K t` is handed to `consume` row by row (see [`Fft2::convolve_finish`])
    /// instead of being stored.
    pub fn finish_rows<S, I, F>(&self, blocks: I, consume: F, ws: &mut OperatorWorkspace)
    where
        S: Send,
        I: IndexedParallelIterator<Item = S>,
        F: Fn(&mut S, usize, &[f64]) + Sync,
    {
        self.fft.convolve_finish(blocks, consume, &mut ws.scratch);
    }

    /// `output += K Δ` for a few point loads `(node index, Δp)`, by direct summation of the
    /// real-space response (cost: one pass over the field per load). Loads are added in
    /// the order given, so the result does not depend on the thread count.
    pub fn add_point_loads(&self, loads: &[(usize, f64)], output: &mut [f64]) {
        let n = self.grid.n();
        output
            .par_chunks_mut(n)
            .enumerate()
            .for_each(|(iy, row)| self.add_point_loads_row(iy, loads, row));
    }

    /// Row `iy` of [`Self::add_point_loads`]: each load adds `Δp · K(ix − jx, iy − jy)` to
    /// every value of the row, loads in the order given, as two ascending runs of the
    /// kernel row (vectorised).
    #[inline(always)]
    pub fn add_point_loads_row(&self, iy: usize, loads: &[(usize, f64)], row: &mut [f64]) {
        let n = self.grid.n();
        debug_assert_eq!(row.len(), n);
        for &(node, dp) in loads {
            let (jy, jx) = (node / n, node % n);
            let d = (iy + n - jy) % n;
            let k = &self.kernel_rows[d.min(n - d) * n..(d.min(n - d) + 1) * n];
            // Column ix is at periodic offset (ix − jx) mod n: k[0 … n − jx) for ix ≥ jx,
            // k[n − jx … n) for ix < jx.
            let (before, after) = row.split_at_mut(jx);
            for (v, kv) in after.iter_mut().zip(k) {
                *v += dp * kv;
            }
            for (v, kv) in before.iter_mut().zip(&k[n - jx..]) {
                *v += dp * kv;
            }
        }
    }
}

/// Multiply one column of the half spectrum (`ky` wrapped, length `n`) by `gain(m)` of the
/// stored multiplier `m` (indexed by `|ky|`, length `n/2 + 1`) and return `Σ gain·|c|²`.
/// The column is taken as two runs, `ky = 0 … n/2` (ascending `m`) and `ky = n/2+1 … n−1`
/// (`m[n/2−1] … m[1]`), and the sum in four interleaved partial sums, so that the loop
/// vectorises; the order is fixed, so the result does not depend on the thread count.
#[inline(always)]
pub(crate) fn multiply_column<T: Real>(
    col: &mut [Complex<T>],
    m: &[f64],
    gain: &impl Fn(f64) -> f64,
) -> f64 {
    let n = col.len();
    let half = n / 2;
    debug_assert_eq!(m.len(), half + 1);
    let (low, high) = col.split_at_mut(half + 1);
    let mut acc = [0.0f64; 4];
    multiply_run(low, m.iter().copied(), gain, &mut acc);
    multiply_run(high, m[1..half].iter().rev().copied(), gain, &mut acc);
    (acc[0] + acc[1]) + (acc[2] + acc[3])
}

/// One run of [`multiply_column`]: value `k` of `col` goes with `k`-th `m` and partial
/// sum `k mod 4` (in double precision whatever `T`; the gain is rounded to `T`).
#[inline(always)]
fn multiply_run<T: Real>(
    col: &mut [Complex<T>],
    mut m: impl Iterator<Item = f64>,
    gain: &impl Fn(f64) -> f64,
    acc: &mut [f64; 4],
) {
    let mut groups = col.chunks_exact_mut(4);
    for group in &mut groups {
        for (c, a) in group.iter_mut().zip(acc.iter_mut()) {
            let g = gain(m.next().unwrap_or(0.0));
            *a += g * c.norm_sqr().widen();
            *c = c.scale(T::narrow(g));
        }
    }
    for (c, a) in groups.into_remainder().iter_mut().zip(acc.iter_mut()) {
        let g = gain(m.next().unwrap_or(0.0));
        *a += g * c.norm_sqr().widen();
        *c = c.scale(T::narrow(g));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rustfft::num_complex::Complex64;
    use std::f64::consts::PI;

    /// A single Fourier mode p = cos(2π(a x + b y)/L) deflects by 2/(E*|q|) times itself.
    #[test]
    fn single_fourier_modes_are_exact() {
        let n = 64;
        let grid = Grid::new(n, 2.5).unwrap();
        let e_star = 3.0;
        let op = ElasticOperator::new(grid, e_star);
        let mut ws = op.make_workspace();
        for (a, b) in [(1i64, 0i64), (0, 3), (5, -7), (32, 0), (13, 31), (-32, 32)] {
            let q = 2.0 * PI / grid.size() * ((a * a + b * b) as f64).sqrt();
            let dx = grid.spacing();
            let p: Vec<f64> = (0..n * n)
                .map(|i| {
                    let (iy, ix) = ((i / n) as f64, (i % n) as f64);
                    (2.0 * PI * (a as f64 * ix + b as f64 * iy) * dx / grid.size()).cos()
                })
                .collect();
            let mut u = vec![0.0; n * n];
            op.apply(&p, &mut u, &mut ws);
            let expected = 2.0 / (e_star * q);
            for (ui, pi) in u.iter().zip(&p) {
                assert!(
                    (ui - expected * pi).abs() <= 1e-12 * expected,
                    "mode ({a},{b})"
                );
            }
        }
    }

    /// The fused convolution (columns transformed, multiplied and transformed back in
    /// cache) gives the same bits as the unfused one: forward FFT, multiplier pass, inverse
    /// FFT, with the energy summed per column in the same order.
    #[test]
    fn fused_convolution_is_bit_identical_to_the_unfused_one() {
        for n in [2usize, 6, 8, 30, 64, 130] {
            let grid = Grid::unit(n).unwrap();
            let op = ElasticOperator::new(grid, 1.3);
            let mut ws = op.make_workspace();
            let mut state: u64 = 7 + n as u64;
            let p: Vec<f64> = (0..n * n)
                .map(|_| {
                    state = state
                        .wrapping_mul(6364136223846793005)
                        .wrapping_add(1442695040888963407);
                    (state >> 11) as f64 / (1u64 << 53) as f64 - 0.25
                })
                .collect();
            let mut fused = vec![0.0; n * n];
            let fused_energy = op.apply_with_energy(&p, &mut fused, &mut ws);

            let fft = Fft2::new(n);
            let mut scratch = fft.make_scratch();
            let mut spectrum = fft.make_spectrum();
            fft.forward(&p, &mut spectrum, &mut scratch);
            let h = grid.half_len();
            let mut energy = 0.0;
            for (jx, col) in spectrum.chunks_exact_mut(n).enumerate() {
                let m = &op.multiplier[jx * h..(jx + 1) * h];
                energy += grid.half_weight(jx) * multiply_column(col, m, &|g| g);
            }
            let mut unfused = vec![0.0; n * n];
            fft.inverse(&mut spectrum, &mut unfused, &mut scratch);
            assert_eq!(fused_energy.to_bits(), energy.to_bits(), "n={n}: energy");
            for (i, (a, b)) in fused.iter().zip(&unfused).enumerate() {
                assert_eq!(a.to_bits(), b.to_bits(), "n={n}, node {i}: {a} vs {b}");
            }
        }
    }

    /// The two-run column product gives each value the multiplier of its |ky| (exactly)
    /// and the naive energy up to rounding, for even lengths with and without remainders.
    #[test]
    fn column_multiplication_matches_the_wrapped_index_loop() {
        for n in [2usize, 4, 6, 8, 10, 12, 30, 64] {
            let half = n / 2;
            let m: Vec<f64> = (0..=half).map(|k| 1.0 + 0.37 * k as f64).collect();
            let col: Vec<Complex64> = (0..n)
                .map(|i| Complex64::new(0.3 + i as f64, 1.7 - 0.2 * i as f64))
                .collect();
            let gain = |g: f64| 2.0 / g;
            let mut fast = col.clone();
            let energy = multiply_column(&mut fast, &m, &gain);
            let mut naive_energy = 0.0;
            for (iy, (c, f)) in col.iter().zip(&fast).enumerate() {
                let g = gain(m[iy.min(n - iy)]);
                assert_eq!(*f, *c * g, "n={n}, ky index {iy}");
                naive_energy += g * c.norm_sqr();
            }
            assert!(
                (energy - naive_energy).abs() <= 1e-14 * naive_energy,
                "n={n}: {energy} vs {naive_energy}"
            );
        }
    }

    /// The single-precision inverse operator undoes `K`: `K⁻¹ K p = p − mean(p)` within
    /// f32 rounding (a few 10⁻⁷ relative per operation; the bound 10⁻⁵ of the largest value
    /// leaves room for the ~2 log₂ n rounding steps of two transforms), and its Parseval sum
    /// is `⟨t, K⁻¹ t⟩` computed in real space to the same accuracy.
    #[test]
    fn single_precision_inverse_undoes_the_operator() {
        let n = 64;
        let op = ElasticOperator::new(Grid::new(n, 3.0).unwrap(), 1.7);
        let mut ws = op.make_workspace();
        let p: Vec<f64> = (0..n * n)
            .map(|i| ((i * 7919 % 1013) as f64 / 1013.0 - 0.3).max(0.0))
            .collect();
        let mean = p.iter().sum::<f64>() / (n * n) as f64;
        let mut u = vec![0.0; n * n];
        op.apply(&p, &mut u, &mut ws);
        let block = op.rows_per_block() * n;
        let energy = op.start_rows_inverse(
            u.par_chunks(block),
            |rows: &mut &[f64], r, row: &mut [f32]| {
                for (o, &v) in row.iter_mut().zip(&rows[r * n..(r + 1) * n]) {
                    *o = v as f32;
                }
            },
            &mut ws,
        );
        let mut back = vec![0.0f32; n * n];
        op.finish_rows_inverse(
            back.par_chunks_mut(block),
            |rows: &mut &mut [f32], r, row: &[f32]| rows[r * n..(r + 1) * n].copy_from_slice(row),
            &mut ws,
        );
        let largest = p.iter().fold(0.0f64, |a, &v| a.max(v));
        for (i, (&b, &q)) in back.iter().zip(&p).enumerate() {
            assert!(
                (b as f64 - (q - mean)).abs() <= 1e-5 * largest,
                "node {i}: {b} vs {}",
                q - mean
            );
        }
        // ⟨u, K⁻¹ u⟩ = ⟨u, p − p̄⟩ = ⟨u, p⟩ (u has zero mean).
        let direct: f64 = u.iter().zip(&p).map(|(a, b)| a * b).sum();
        assert!(
            (energy - direct).abs() <= 1e-5 * direct.abs(),
            "{energy} vs {direct}"
        );
    }

    #[test]
    fn uniform_pressure_gives_no_deflection() {
        let grid = Grid::unit(32).unwrap();
        let op = ElasticOperator::new(grid, 1.0);
        let mut ws = op.make_workspace();
        let p = vec![0.7; 32 * 32];
        let mut u = vec![1.0; 32 * 32];
        op.apply(&p, &mut u, &mut ws);
        assert!(u.iter().all(|v| v.abs() < 1e-15));
    }

    #[test]
    fn self_influence_matches_a_point_load() {
        let n = 32;
        let op = ElasticOperator::new(Grid::unit(n).unwrap(), 2.0);
        let mut ws = op.make_workspace();
        let mut p = vec![0.0; n * n];
        p[5 * n + 9] = 1.0;
        let mut u = vec![0.0; n * n];
        op.apply(&p, &mut u, &mut ws);
        assert!((u[5 * n + 9] - op.self_influence()).abs() < 1e-14 * op.self_influence());
        // The same response by direct summation of the real-space kernel.
        let mut direct = vec![0.0; n * n];
        op.add_point_loads(&[(5 * n + 9, 1.0)], &mut direct);
        for (a, b) in u.iter().zip(&direct) {
            assert!((a - b).abs() <= 1e-15 * op.self_influence(), "{a} vs {b}");
        }
    }

    #[test]
    fn parseval_energy_matches_the_real_space_product() {
        let n = 32;
        let op = ElasticOperator::new(Grid::unit(n).unwrap(), 1.5);
        let mut ws = op.make_workspace();
        let p: Vec<f64> = (0..n * n)
            .map(|i| ((i * 37 % 101) as f64 / 101.0 - 0.3).max(0.0))
            .collect();
        let mut u = vec![0.0; n * n];
        let energy = op.apply_with_energy(&p, &mut u, &mut ws);
        let direct: f64 = p.iter().zip(&u).map(|(a, b)| a * b).sum();
        assert!(
            (energy - direct).abs() <= 1e-13 * direct.abs(),
            "{energy} vs {direct}"
        );
        // Several point loads by direct summation equal the FFT convolution.
        let loads = [(3usize, 0.5), (n * n - 1, -1.25), (17 * n + 30, 2.0)];
        let mut sparse = vec![0.0; n * n];
        for &(i, v) in &loads {
            sparse[i] = v;
        }
        op.apply(&sparse, &mut u, &mut ws);
        let mut direct = vec![0.0; n * n];
        op.add_point_loads(&loads, &mut direct);
        for (a, b) in u.iter().zip(&direct) {
            assert!((a - b).abs() <= 1e-14 * op.self_influence());
        }
    }
}
