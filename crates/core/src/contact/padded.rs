//! The free-boundary (non-periodic) elastic half-space on a square grid of nodes: a measured
//! surface is not periodic, so the deflection of each node is the Boussinesq response to the
//! pressure of every pixel of the grid alone, with nothing beyond it. The influence of a
//! pixel (uniform pressure on a Δx × Δy rectangle, Love's closed form; square pixels are the
//! case Δy = Δx, and an instrument's rectangular pixels are solved as measured, without
//! resampling) is convolved by FFT on
//! a grid of twice the side, the pressure zero-padded (Hockney's method, as ContactMechanics
//! does): on the `2n` torus, two nodes of the `n` window are never more than `n − 1` apart,
//! so the circular convolution is the free-space one on the window.
//!
//! For a rigid flat punch or a sphere this is the classical boundary-element half-space
//! (VALIDATION.md); unlike the periodic operator its uniform pressure deflects the surface,
//! and its mean deflection is defined. [`PaddedOperator`] implements the solver's
//! [`Operator`]; its preconditioner inverse is that of the padded circulant restricted to the
//! window, symmetric and positive as the solver needs.

use rayon::prelude::*;

use crate::contact::elastic::{multiply_column, OperatorWorkspace};
use crate::contact::solver::Operator;
use crate::grid::Grid;
use crate::spectral::{Fft2, Fft2Scratch, Real};

/// `u = K p` on the `n × n` window of a free-boundary half-space.
pub struct PaddedOperator {
    grid: Grid,
    /// The padded `2n` grid (the half spectrum's column weights).
    padded: Grid,
    e_star: f64,
    /// Plans on the padded `2n` grid (double, and single for the inverse).
    fft: Fft2,
    fft_single: Fft2<f32>,
    /// The padded circulant's eigenvalues over `(2n)²` (the FFT pair's norm), by `kx ∈
    /// 0..=n` and `|ky| ∈ 0..=n`, row-major by kx.
    multiplier: Vec<f64>,
    /// The response at offset `(|dy|, |dx|)`, both in `0..n`, to a unit pressure on one
    /// pixel: `kernel[|dy| · n + |dx|]`.
    kernel: Vec<f64>,
}

/// Love's closed form: `∫∫ dA / r` over the `sx × sy` rectangle centred on the origin, seen
/// from `(x, y)` in its plane (the deflection is this times `p / (π E*)`).
pub fn rectangle_integral(x: f64, y: f64, sx: f64, sy: f64) -> f64 {
    // Even in x and y: evaluate in the first quadrant, where the logarithms' arguments are
    // computed without cancellation.
    let (x, y, a, b) = (x.abs(), y.abs(), 0.5 * sx, 0.5 * sy);
    // ln(u + √(u² + v²)), written for u < 0 as ln(v² / (√(u² + v²) − u)).
    let log_sum = |u: f64, v: f64| {
        let r = u.hypot(v);
        if u >= 0.0 {
            (u + r).ln()
        } else {
            (v * v / (r - u)).ln()
        }
    };
    let f = |u: f64, v: f64| {
        let first = if u == 0.0 { 0.0 } else { u * log_sum(v, u) };
        let second = if v == 0.0 { 0.0 } else { v * log_sum(u, v) };
        first + second
    };
    f(x + a, y + b) - f(x + a, y - b) - f(x - a, y + b) + f(x - a, y - b)
}

impl PaddedOperator {
    /// The operator on `grid`'s window of square pixels (its spacing is the pixel side) for
    /// the effective modulus `e_star` (> 0).
    pub fn new(grid: Grid, e_star: f64) -> Self {
        Self::with_aspect(grid, e_star, 1.0)
    }

    /// The operator on `grid`'s window of rectangular pixels: `Δx` is the grid's spacing
    /// and `Δy = aspect · Δx` (`aspect` finite and > 0). Node `(i, j)` sits at
    /// `(j Δx, i Δy)`; the kernel is Love's integral over the `Δx × Δy` pixel.
    pub fn with_aspect(grid: Grid, e_star: f64, aspect: f64) -> Self {
        assert!(
            e_star.is_finite() && e_star > 0.0,
            "E* must be finite and > 0"
        );
        assert!(
            aspect.is_finite() && aspect > 0.0,
            "the pixel aspect Δy/Δx must be finite and > 0"
        );
        let n = grid.n();
        let (sx, sy) = (grid.spacing(), grid.spacing() * aspect);
        let scale = 1.0 / (std::f64::consts::PI * e_star);
        let kernel: Vec<f64> = (0..n * n)
            .into_par_iter()
            .map(|i| {
                let (dy, dx) = ((i / n) as f64, (i % n) as f64);
                scale * rectangle_integral(dx * sx, dy * sy, sx, sy)
            })
            .collect();
        // The kernel on the 2n torus (offsets beyond n − 1 never pair two nodes of the
        // window; offset n takes the value at n − 1), transformed: real and even.
        let big = 2 * n;
        let fft = Fft2::new(big);
        let wrap = |k: usize| if k <= n { k.min(n - 1) } else { big - k };
        let torus: Vec<f64> = (0..big * big)
            .map(|i| kernel[wrap(i / big) * n + wrap(i % big)])
            .collect();
        let mut spectrum = fft.make_spectrum();
        fft.forward(&torus, &mut spectrum, &mut fft.make_scratch());
        let h = n + 1;
        let norm = 1.0 / (big * big) as f64;
        let mut multiplier = vec![0.0; h * h];
        for jx in 0..h {
            for ky in 0..h {
                multiplier[jx * h + ky] = spectrum[jx * big + ky].re * norm;
            }
        }
        Self {
            grid,
            padded: Grid::unit(big).expect("an even side"),
            e_star,
            fft,
            fft_single: Fft2::new(big),
            multiplier,
            kernel,
        }
    }

    /// The smallest eigenvalue of the padded circulant, relative to the largest: positive,
    /// so that the operator and its preconditioner inverse are positive definite.
    pub fn smallest_eigenvalue_ratio(&self) -> f64 {
        let (min, max) = self
            .multiplier
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), &m| (a.min(m), b.max(m)));
        min / max
    }

    /// `output = K input` on the window (row-major `n × n`), returning `⟨input, K input⟩`.
    pub fn apply(&self, input: &[f64], output: &mut [f64], ws: &mut OperatorWorkspace) -> f64 {
        let n = self.grid.n();
        assert_eq!(input.len(), n * n);
        assert_eq!(output.len(), n * n);
        let block = self.rows_per_block() * n;
        let energy = Operator::start_rows(
            self,
            input.par_chunks(block),
            |rows: &mut &[f64], r, buf| buf.copy_from_slice(&rows[r * n..(r + 1) * n]),
            ws,
        );
        Operator::finish_rows(
            self,
            output.par_chunks_mut(block),
            |rows: &mut &mut [f64], r, row| rows[r * n..(r + 1) * n].copy_from_slice(row),
            ws,
        );
        energy
    }

    /// The window's blocks followed by the padding's, each tagged with its block index:
    /// the padded transform takes one state per block of the `2n` grid.
    fn padded_blocks<S: Send, I: IndexedParallelIterator<Item = S>>(
        &self,
        blocks: I,
    ) -> impl IndexedParallelIterator<Item = (usize, Option<S>)> {
        let total = self.fft.block_count();
        let given = blocks.len();
        assert!(given <= total, "more blocks than the padded grid has");
        blocks
            .map(Some)
            .chain((given..total).into_par_iter().map(|_| None))
            .enumerate()
    }

    fn start_with<T: Real, S, I, F>(
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
        let (n, rpb, h) = (self.grid.n(), self.rows_per_block(), self.grid.n() + 1);
        let big = &self.padded;
        let (partials, scratch) = ws.parts_mut(h);
        fft.convolve_start(
            self.padded_blocks(blocks),
            |(b, state): &mut (usize, Option<S>), r, row: &mut [T]| {
                row.fill(T::zero());
                if let Some(s) = state {
                    if *b * rpb + r < n {
                        produce(s, r, &mut row[..n]);
                    }
                }
            },
            |jx, col| {
                let m = &self.multiplier[jx * h..(jx + 1) * h];
                big.half_weight(jx) * multiply_column(col, m, &gain)
            },
            partials,
            scratch,
        );
        partials.iter().sum()
    }

    fn finish_with<T: Real, S, I, F>(
        &self,
        fft: &Fft2<T>,
        blocks: I,
        consume: F,
        scratch: &mut Fft2Scratch,
    ) where
        S: Send,
        I: IndexedParallelIterator<Item = S>,
        F: Fn(&mut S, usize, &[T]) + Sync,
    {
        let (n, rpb) = (self.grid.n(), self.rows_per_block());
        fft.convolve_finish(
            self.padded_blocks(blocks),
            |(b, state): &mut (usize, Option<S>), r, row: &[T]| {
                if let Some(s) = state {
                    if *b * rpb + r < n {
                        consume(s, r, &row[..n]);
                    }
                }
            },
            scratch,
        );
    }
}

impl Operator for PaddedOperator {
    type Workspace = OperatorWorkspace;

    fn grid(&self) -> &Grid {
        &self.grid
    }

    fn e_star(&self) -> f64 {
        self.e_star
    }

    fn make_workspace(&self) -> OperatorWorkspace {
        self.fft_single.prepare_threads();
        OperatorWorkspace::new(self.fft.make_scratch(), self.grid.n() + 1)
    }

    fn rows_per_block(&self) -> usize {
        self.fft.rows_per_block()
    }

    fn self_influence(&self) -> f64 {
        self.kernel[0]
    }

    fn start_rows<S, I, F>(&self, blocks: I, produce: F, ws: &mut OperatorWorkspace) -> f64
    where
        S: Send,
        I: IndexedParallelIterator<Item = S>,
        F: Fn(&mut S, usize, &mut [f64]) + Sync,
    {
        self.start_with(&self.fft, blocks, produce, ws, |m| m)
    }

    fn finish_rows<S, I, F>(&self, blocks: I, consume: F, ws: &mut OperatorWorkspace)
    where
        S: Send,
        I: IndexedParallelIterator<Item = S>,
        F: Fn(&mut S, usize, &[f64]) + Sync,
    {
        self.finish_with(&self.fft, blocks, consume, ws.scratch_mut());
    }

    fn start_rows_inverse<S, I, F>(&self, blocks: I, produce: F, ws: &mut OperatorWorkspace) -> f64
    where
        S: Send,
        I: IndexedParallelIterator<Item = S>,
        F: Fn(&mut S, usize, &mut [f32]) + Sync,
    {
        // The stored eigenvalue carries the pair's 1/N²: the inverse's is N⁻⁴ / m.
        let big = (2 * self.grid.n()) as f64;
        let norm2 = 1.0 / (big * big * big * big);
        self.start_with(&self.fft_single, blocks, produce, ws, move |m| {
            if m > 0.0 {
                norm2 / m
            } else {
                0.0
            }
        })
    }

    fn finish_rows_inverse<S, I, F>(&self, blocks: I, consume: F, ws: &mut OperatorWorkspace)
    where
        S: Send,
        I: IndexedParallelIterator<Item = S>,
        F: Fn(&mut S, usize, &[f32]) + Sync,
    {
        self.finish_with(&self.fft_single, blocks, consume, ws.scratch_mut());
    }

    fn add_point_loads_row(&self, iy: usize, loads: &[(usize, f64)], row: &mut [f64]) {
        let n = self.grid.n();
        for &(node, dp) in loads {
            let (jy, jx) = (node / n, node % n);
            let k = &self.kernel[iy.abs_diff(jy) * n..(iy.abs_diff(jy) + 1) * n];
            for (ix, v) in row.iter_mut().enumerate() {
                *v += dp * k[ix.abs_diff(jx)];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Love's formula against a midpoint quadrature of 1/r over the square (away from the
    /// singularity), and at the centre against the closed form 4 s ln(1 + √2).
    #[test]
    fn rectangle_integral_matches_quadrature() {
        let s = 0.3;
        let centre = rectangle_integral(0.0, 0.0, s, s);
        let exact = 4.0 * s * (1.0 + 2f64.sqrt()).ln();
        assert!((centre / exact - 1.0).abs() < 1e-14, "{centre} vs {exact}");
        for (x, y) in [(0.3, 0.0), (0.6, 0.3), (1.5, -0.9), (-3.0, 12.0)] {
            let m = 400;
            let h = s / m as f64;
            let mut sum = 0.0;
            for i in 0..m {
                for j in 0..m {
                    let (u, v) = (
                        -0.5 * s + (i as f64 + 0.5) * h,
                        -0.5 * s + (j as f64 + 0.5) * h,
                    );
                    sum += h * h / (x - u).hypot(y - v);
                }
            }
            let closed = rectangle_integral(x, y, s, s);
            assert!(
                (closed / sum - 1.0).abs() < 2e-6,
                "({x}, {y}): {closed} vs {sum}"
            );
        }
    }

    /// The padded convolution equals direct summation of the kernel over the window (an
    /// independent method) for a random field, on sides whose blocks end inside the window
    /// and whose padded blocks straddle it; and its energy is ⟨p, K p⟩.
    #[test]
    fn padded_convolution_is_the_free_space_sum() {
        for (n, aspect) in [(6usize, 1.0), (16, 1.0), (70, 1.0), (16, 2.466), (70, 0.37)] {
            let op = PaddedOperator::with_aspect(Grid::unit(n).unwrap(), 1.7, aspect);
            assert!(op.smallest_eigenvalue_ratio() > 0.0);
            let mut state = 12345u64;
            let p: Vec<f64> = (0..n * n)
                .map(|_| {
                    state = state
                        .wrapping_mul(6364136223846793005)
                        .wrapping_add(1442695040888963407);
                    (state >> 11) as f64 / (1u64 << 53) as f64
                })
                .collect();
            let mut ws = op.make_workspace();
            let mut u = vec![0.0; n * n];
            let energy = op.apply(&p, &mut u, &mut ws);
            let loads: Vec<(usize, f64)> = p.iter().copied().enumerate().collect();
            let mut direct = vec![0.0; n];
            let mut dot = 0.0;
            for iy in 0..n {
                direct.fill(0.0);
                op.add_point_loads_row(iy, &loads, &mut direct);
                for ix in 0..n {
                    let (a, b) = (u[iy * n + ix], direct[ix]);
                    assert!(
                        (a - b).abs() <= 1e-12 * b.abs(),
                        "n = {n}, aspect {aspect}, ({iy}, {ix}): {a} vs {b}"
                    );
                    dot += p[iy * n + ix] * b;
                }
            }
            assert!((energy / dot - 1.0).abs() < 1e-12, "{energy} vs {dot}");
        }
    }
}
