//! The periodic elastic half-space: deflection from pressure by a Fourier multiplier.
//!
//! For frictionless normal contact of a half-space with effective modulus `E*`,
//! `û(q) = 2 p̂(q) / (E* |q|)` with the angular wavevector `q` (VALIDATION.md §1.1). The
//! `q = 0` mode is set to zero: a uniform pressure gives no deflection, and the mean
//! deflection (undefined for a periodic half-space) is zero. Pressures are compressive
//! positive; `u` is the deflection into the solid. The discrete operator applies the
//! continuous kernel at the discrete wavevectors ("spectral" / point-value scheme, as
//! Tamaas), with the Nyquist index taken as `|k| = n/2`.

use rustfft::num_complex::Complex64;

use crate::grid::Grid;
use crate::spectral::{Fft2, Fft2Scratch};

/// The operator `u = K p` on one grid: planned FFTs and the multiplier, built once.
pub struct ElasticOperator {
    grid: Grid,
    e_star: f64,
    fft: Fft2,
    /// `2/(E*|q|) / n²` on the half spectrum (kx-major), 0 at q = 0; includes the
    /// normalisation of the unnormalised FFT pair.
    multiplier: Vec<f64>,
    /// Self-influence `K_ii = mean of the multiplier over the full spectrum · n²/n²`: the
    /// deflection of a node under a unit pressure on that node alone.
    self_influence: f64,
}

/// Working memory of [`ElasticOperator::apply`]; allocate once with
/// [`ElasticOperator::make_workspace`].
pub struct OperatorWorkspace {
    spectrum: Vec<Complex64>,
    scratch: Fft2Scratch,
}

impl ElasticOperator {
    /// Plan the operator for `grid` and effective modulus `e_star` (> 0).
    pub fn new(grid: Grid, e_star: f64) -> Self {
        assert!(
            e_star.is_finite() && e_star > 0.0,
            "E* must be finite and > 0"
        );
        let n = grid.n();
        let fft = Fft2::new(n);
        let norm = 1.0 / (n * n) as f64;
        let mut multiplier = vec![0.0; fft.spectrum_len()];
        let mut sum = 0.0;
        for jx in 0..grid.half_len() {
            let w = grid.half_weight(jx);
            for iy in 0..n {
                let q = grid.q_norm(jx, iy);
                let g = if q > 0.0 {
                    2.0 / (e_star * q) * norm
                } else {
                    0.0
                };
                multiplier[jx * n + iy] = g;
                sum += w * g;
            }
        }
        Self {
            grid,
            e_star,
            fft,
            multiplier,
            self_influence: sum,
        }
    }

    pub fn grid(&self) -> &Grid {
        &self.grid
    }

    pub fn e_star(&self) -> f64 {
        self.e_star
    }

    /// Deflection at a node per unit pressure applied on that node alone (`K_ii`).
    pub fn self_influence(&self) -> f64 {
        self.self_influence
    }

    pub fn make_workspace(&self) -> OperatorWorkspace {
        OperatorWorkspace {
            spectrum: self.fft.make_spectrum(),
            scratch: self.fft.make_scratch(),
        }
    }

    /// `output = K input` (row-major `n × n` fields). Allocates nothing.
    pub fn apply(&self, input: &[f64], output: &mut [f64], ws: &mut OperatorWorkspace) {
        self.fft.forward(input, &mut ws.spectrum, &mut ws.scratch);
        use rayon::prelude::*;
        ws.spectrum
            .par_chunks_mut(self.grid.n())
            .zip(self.multiplier.par_chunks(self.grid.n()))
            .for_each(|(s, m)| {
                for (c, g) in s.iter_mut().zip(m) {
                    *c *= *g;
                }
            });
        self.fft.inverse(&mut ws.spectrum, output, &mut ws.scratch);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
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
    }
}
