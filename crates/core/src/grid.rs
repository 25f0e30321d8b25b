//! The periodic computational grid.
//!
//! A [`Grid`] is an `n × n` square of nodes spanning a periodic box of side `size`
//! (the period `L`). Node `(i, j)` (row `i` along y, column `j` along x) sits at
//! `(x, y) = (j Δl, i Δl)` with `Δl = L / n`. Heights, pressures and gaps are stored
//! row-major (C order), `value[i * n + j]`.
//!
//! Wavevectors are angular: `q = 2π k / L` with the integer index `k` wrapped to
//! `[-n/2, n/2)`; the Nyquist index `n/2` is given `|k| = n/2` (its sign does not matter
//! for the isotropic quantities used here). See docs/CONVENTIONS.md.

use std::f64::consts::PI;

/// Error for a grid that cannot be built.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum GridError {
    #[error("grid size n must be an even integer ≥ 2, got {0}")]
    BadSize(usize),
    #[error("box size L must be finite and > 0, got {0}")]
    BadLength(f64),
}

/// A square periodic grid of `n × n` nodes over a box of side `size`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grid {
    n: usize,
    size: f64,
}

impl Grid {
    /// A grid of `n × n` nodes (n even) over a periodic box of side `size`.
    pub fn new(n: usize, size: f64) -> Result<Self, GridError> {
        if n < 2 || !n.is_multiple_of(2) {
            return Err(GridError::BadSize(n));
        }
        if !(size.is_finite() && size > 0.0) {
            return Err(GridError::BadLength(size));
        }
        Ok(Self { n, size })
    }

    /// The unit box (`L = 1`, `Δl = 1/n`), used for files that carry no length unit.
    pub fn unit(n: usize) -> Result<Self, GridError> {
        Self::new(n, 1.0)
    }

    /// Nodes per side.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Box side `L` (the period).
    pub fn size(&self) -> f64 {
        self.size
    }

    /// Grid spacing `Δl = L / n`.
    pub fn spacing(&self) -> f64 {
        self.size / self.n as f64
    }

    /// Number of nodes `n²`.
    pub fn len(&self) -> usize {
        self.n * self.n
    }

    /// Always false: a grid has at least 2 × 2 nodes.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Number of columns of the real-to-complex half spectrum (`n/2 + 1`).
    pub fn half_len(&self) -> usize {
        self.n / 2 + 1
    }

    /// Signed integer wavenumber of index `i` along one axis, wrapped to `[-n/2, n/2)`.
    pub fn wrapped_index(&self, i: usize) -> i64 {
        let n = self.n as i64;
        let i = i as i64;
        if i < n / 2 {
            i
        } else {
            i - n
        }
    }

    /// The fundamental angular wavenumber `2π / L`.
    pub fn q_unit(&self) -> f64 {
        2.0 * PI / self.size
    }

    /// `|k|` in units of `2π/L` for half-spectrum entry (kx = `jx` ∈ 0..=n/2, row `iy`).
    pub fn k_norm(&self, jx: usize, iy: usize) -> f64 {
        let ky = self.wrapped_index(iy) as f64;
        let kx = jx as f64;
        (kx * kx + ky * ky).sqrt()
    }

    /// Angular `|q|` for half-spectrum entry (kx = `jx`, row `iy`).
    pub fn q_norm(&self, jx: usize, iy: usize) -> f64 {
        self.q_unit() * self.k_norm(jx, iy)
    }

    /// Multiplicity of half-spectrum column `jx` in the full spectrum: columns 0 and n/2 are
    /// their own mirror images (weight 1), every other column stands for itself and its
    /// conjugate (weight 2). Use it to turn a half-spectrum sum into a full Parseval sum.
    pub fn half_weight(&self, jx: usize) -> f64 {
        if jx == 0 || jx == self.n / 2 {
            1.0
        } else {
            2.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_odd_and_tiny_sizes() {
        assert_eq!(Grid::new(3, 1.0), Err(GridError::BadSize(3)));
        assert_eq!(Grid::new(0, 1.0), Err(GridError::BadSize(0)));
        assert!(matches!(Grid::new(4, -1.0), Err(GridError::BadLength(_))));
        assert!(matches!(
            Grid::new(4, f64::NAN),
            Err(GridError::BadLength(_))
        ));
    }

    #[test]
    fn wraps_indices_and_counts_half_spectrum_weights() {
        let g = Grid::new(8, 2.0).unwrap();
        let wrapped: Vec<i64> = (0..8).map(|i| g.wrapped_index(i)).collect();
        assert_eq!(wrapped, vec![0, 1, 2, 3, -4, -3, -2, -1]);
        assert_eq!(g.spacing(), 0.25);
        // Half-spectrum weights reproduce the full count n².
        let total: f64 = (0..g.half_len()).map(|j| g.half_weight(j) * 8.0).sum();
        assert_eq!(total, 64.0);
        assert!((g.q_norm(3, 4) - PI * 5.0).abs() < 1e-12);
    }
}
