//! What the solver asks of the linear operator `u = K p` of the contact problem: the fused
//! halves of a convolution (so that the passes over the fields run inside them), its inverse
//! in single precision for the preconditioner, direct summation for a few point loads, and
//! its diagonal. [`ElasticOperator`] (the periodic half-space, FFT boundary elements) is
//! one; `crate::contact::padded::PaddedOperator` (the free-boundary half-space of a
//! measured surface, on a zero-padded grid) is another, given to
//! [`super::Solver::with_constraint`].

use rayon::prelude::*;

use crate::contact::elastic::{ElasticOperator, OperatorWorkspace};
use crate::grid::Grid;

/// The linear operator `u = K p` (symmetric positive semi-definite on the grid's nodes) as
/// the solver uses it. Every sum over the grid runs over the fixed row blocks of
/// [`Self::rows_per_block`] in order, so that results do not depend on the thread count.
pub trait Operator: Sync {
    /// The working memory of one solver's convolutions.
    type Workspace: Send;

    /// The square grid the fields live on.
    fn grid(&self) -> &Grid;

    /// The effective modulus `E*`: the block deflation's coarse model is the periodic
    /// half-space of this modulus on the grid.
    fn e_star(&self) -> f64;

    /// Working memory for [`Self::start_rows`] and the other halves.
    fn make_workspace(&self) -> Self::Workspace;

    /// Rows per work block: fields split with `par_chunks(rows_per_block · n)` give one
    /// state per block to the fused halves.
    fn rows_per_block(&self) -> usize;

    /// `K_ii`, the deflection at a node under a unit pressure on it alone.
    fn self_influence(&self) -> f64;

    /// First half of `K t`: the input produced row by row by `produce(state, row in block,
    /// row)`; returns `⟨t, K t⟩`. [`Self::finish_rows`] must follow before `ws` is reused.
    fn start_rows<S, I, F>(&self, blocks: I, produce: F, ws: &mut Self::Workspace) -> f64
    where
        S: Send,
        I: IndexedParallelIterator<Item = S>,
        F: Fn(&mut S, usize, &mut [f64]) + Sync;

    /// Second half of `K t`: each row of the result handed to `consume`, never stored.
    fn finish_rows<S, I, F>(&self, blocks: I, consume: F, ws: &mut Self::Workspace)
    where
        S: Send,
        I: IndexedParallelIterator<Item = S>,
        F: Fn(&mut S, usize, &[f64]) + Sync;

    /// [`Self::start_rows`] for an inverse of `K` in single precision (the preconditioner
    /// need only be a fixed symmetric positive operator); returns `⟨t, K⁻¹ t⟩`.
    fn start_rows_inverse<S, I, F>(&self, blocks: I, produce: F, ws: &mut Self::Workspace) -> f64
    where
        S: Send,
        I: IndexedParallelIterator<Item = S>,
        F: Fn(&mut S, usize, &mut [f32]) + Sync;

    /// Second half of [`Self::start_rows_inverse`].
    fn finish_rows_inverse<S, I, F>(&self, blocks: I, consume: F, ws: &mut Self::Workspace)
    where
        S: Send,
        I: IndexedParallelIterator<Item = S>,
        F: Fn(&mut S, usize, &[f32]) + Sync;

    /// Row `iy` of `K Δ` for a few point loads `(node, Δp)`, added to `row` in the order
    /// given.
    fn add_point_loads_row(&self, iy: usize, loads: &[(usize, f64)], row: &mut [f64]);
}

impl Operator for ElasticOperator {
    type Workspace = OperatorWorkspace;

    fn grid(&self) -> &Grid {
        ElasticOperator::grid(self)
    }

    fn e_star(&self) -> f64 {
        ElasticOperator::e_star(self)
    }

    fn make_workspace(&self) -> OperatorWorkspace {
        ElasticOperator::make_workspace(self)
    }

    fn rows_per_block(&self) -> usize {
        ElasticOperator::rows_per_block(self)
    }

    fn self_influence(&self) -> f64 {
        ElasticOperator::self_influence(self)
    }

    #[inline(always)]
    fn start_rows<S, I, F>(&self, blocks: I, produce: F, ws: &mut OperatorWorkspace) -> f64
    where
        S: Send,
        I: IndexedParallelIterator<Item = S>,
        F: Fn(&mut S, usize, &mut [f64]) + Sync,
    {
        ElasticOperator::start_rows(self, blocks, produce, ws)
    }

    #[inline(always)]
    fn finish_rows<S, I, F>(&self, blocks: I, consume: F, ws: &mut OperatorWorkspace)
    where
        S: Send,
        I: IndexedParallelIterator<Item = S>,
        F: Fn(&mut S, usize, &[f64]) + Sync,
    {
        ElasticOperator::finish_rows(self, blocks, consume, ws)
    }

    #[inline(always)]
    fn start_rows_inverse<S, I, F>(&self, blocks: I, produce: F, ws: &mut OperatorWorkspace) -> f64
    where
        S: Send,
        I: IndexedParallelIterator<Item = S>,
        F: Fn(&mut S, usize, &mut [f32]) + Sync,
    {
        ElasticOperator::start_rows_inverse(self, blocks, produce, ws)
    }

    #[inline(always)]
    fn finish_rows_inverse<S, I, F>(&self, blocks: I, consume: F, ws: &mut OperatorWorkspace)
    where
        S: Send,
        I: IndexedParallelIterator<Item = S>,
        F: Fn(&mut S, usize, &[f32]) + Sync,
    {
        ElasticOperator::finish_rows_inverse(self, blocks, consume, ws)
    }

    #[inline(always)]
    fn add_point_loads_row(&self, iy: usize, loads: &[(usize, f64)], row: &mut [f64]) {
        ElasticOperator::add_point_loads_row(self, iy, loads, row)
    }
}
