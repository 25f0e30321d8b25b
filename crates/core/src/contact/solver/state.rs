//! The solver's state: the fields it keeps between solves, the per-block sums of its passes,
//! the warm start and the parts chosen; and what a caller reads of the last solve.

use super::super::elastic::ElasticOperator;
use super::constraint::{Constraint, NonNegative};
use super::error::ContactError;
use super::history::History;
use super::operator::Operator;
use super::parts::Choice;
use super::preconditioner::Preconditioner;
use super::rows::{GradientStats, LANES};
use super::update::UpdateAcc;

/// A solver bound to one operator ([`ElasticOperator`] unless given), one surface and one
/// constraint on the pressure ([`NonNegative`] unless given); it keeps its fields between solves so that a load sweep
/// warm-starts each step from the previous solutions (extrapolated to the new load, or
/// scaled to it).
pub struct Solver<'a, C: Constraint = NonNegative, O: Operator = ElasticOperator> {
    pub(super) op: &'a O,
    pub(super) constraint: C,
    pub(super) heights: &'a [f64],
    pub(super) height_std: f64,
    pub(super) flat: bool,
    pub(super) ws: O::Workspace,
    /// `p`, `w = u − h`, `t` and the gap's level.
    pub(super) fields: NodeFields,
    /// The passes' per-block sums and lists.
    pub(super) blocks: BlockSums,
    /// The last solutions, for the next start.
    pub(super) warm: WarmStart,
    /// The preconditioner.
    pub(super) parts: Parts<C, O>,
}

impl<'a> Solver<'a> {
    /// [`Self::with_constraint`] for frictionless elastic contact, `p ≥ 0`.
    pub fn new(op: &'a ElasticOperator, heights: &'a [f64]) -> Result<Self, ContactError> {
        Self::with_constraint(op, heights, NonNegative)
    }
}

/// The fields over the nodes, kept between solves.
pub struct NodeFields {
    /// The pressure `p` of the last state (row-major).
    pub(super) pressure: Vec<f64>,
    /// `w = u − h`, the deflection minus the heights (the gap up to the rigid-body shift),
    /// stored instead of `u` so that the passes of an iteration need not read `h`.
    pub(super) separation: Vec<f64>,
    /// The search direction `t`.
    pub(super) direction: Vec<f64>,
    /// `min w` after a solve: the gap is `w − gap_level`.
    pub(super) gap_level: f64,
}

/// Per work block, the sums and lists of the passes (reduced in a fixed order, so that sums do not depend on the thread count).
pub struct BlockSums {
    /// Values per work block: the operator's fixed row blocks (`rows_per_block · n`), so
    /// that the passes fused with the FFT and the plain passes reduce over the same blocks
    /// and sums do not depend on the thread count.
    pub(super) chunk: usize,
    /// Per block: lane sums of the plain reductions (a sum, the line search's numerator).
    pub(super) lane_sums: Vec<[f64; LANES]>,
    /// Per block: gradient statistics of the passes not fused with an FFT.
    pub(super) block_stats: Vec<GradientStats>,
    /// Per block: accumulators of the update pass fused with the inverse FFT.
    pub(super) update_acc: Vec<UpdateAcc>,
    /// Per block: lane sums and counts of [`Solver::load_offset`].
    pub(super) offset_acc: Vec<[[f64; LANES]; 2]>,
    /// Per block: the nodes whose projection departed from the linear step, `(node, Δ)` in
    /// node order, up to the list's capacity (one node in [`CHANGES_PER_NODE`] of the
    /// block; never reallocated).
    pub(super) changes: Vec<Vec<(usize, f64)>>,
    /// Per block, under a ceiling: the pressures a load offset moves, and the sum of the
    /// others (`Solver::gather_moving`); empty until then.
    pub(super) moving: Vec<(Vec<f64>, f64)>,
    pub(super) sparse: Vec<(usize, f64)>,
}

/// What the next solve starts from: the last solutions and whether the deflection is exact for them.
pub struct WarmStart {
    pub(super) has_solution: bool,
    /// The mean pressure of the last solution (when `has_solution`).
    pub(super) solved_mean: f64,
    /// Under a ceiling, the nodes of positive pressure when the gap was last levelled
    /// (`Solver::finish_gap`, after every solve): the last solution's contact set.
    pub(super) solved_contact: usize,
    /// The solution before the last, for the extrapolated start.
    pub(super) history: History,
    /// Whether `separation` is `K p − h` for the current `pressure`, computed exactly (after
    /// a converged solve; not after [`Self::set_start`]).
    pub(super) separation_exact: bool,
}

/// The preconditioner chosen for the settings, and one set aside.
pub struct Parts<C, O: Operator> {
    /// The preconditioner (module `preconditioner`; none for the plain iteration), chosen
    /// at the first solve and again only when the settings that choose it change.
    pub(super) preconditioner: Option<Box<dyn Preconditioner<C, O>>>,
    pub(super) choice: Option<Choice>,
    /// The extended preconditioner, set aside for the rest of a solve that stagnated with
    /// it under a ceiling (`Solver::set_extension_aside`); restored at the next solve.
    pub(super) suspended: Option<Box<dyn Preconditioner<C, O>>>,
}

impl<C: Constraint, O: Operator> Solver<'_, C, O> {
    /// Standard deviation of the heights (the error's length scale).
    pub fn height_std(&self) -> f64 {
        self.height_std
    }

    /// Pressure of the last solve (row-major).
    pub fn pressure(&self) -> &[f64] {
        &self.fields.pressure
    }

    /// Gap `(K p − h) − min(K p − h)` of the last solve (row-major), computed as it is read.
    pub fn gap(&self) -> impl ExactSizeIterator<Item = f64> + '_ {
        let level = self.fields.gap_level;
        self.fields.separation.iter().map(move |&w| w - level)
    }

    /// Number of nodes in contact (`p > 0`) in the last solve.
    pub fn contact_count(&self) -> usize {
        self.fields.pressure.iter().filter(|&&p| p > 0.0).count()
    }

    /// The constraint's ceiling `p_max`, if it has one.
    pub fn ceiling(&self) -> Option<f64> {
        self.constraint.ceiling()
    }

    /// The ceiling and the number of nodes on it in the last solve, if the constraint has a
    /// ceiling: the fields a load's result reports for it.
    pub fn saturation(&self) -> Option<(f64, usize)> {
        self.constraint
            .ceiling()
            .map(|max| (max, self.saturated_count()))
    }

    /// Number of nodes on the constraint's ceiling (`p = p_max`; none when unbounded) in
    /// the last solve.
    pub fn saturated_count(&self) -> usize {
        let c = self.constraint;
        self.fields
            .pressure
            .iter()
            .filter(|&&p| c.saturated(p))
            .count()
    }

    /// The plastic displacement of the last solve (row-major): on the saturated nodes the
    /// interpenetration `−gap = ℓ − w ≥ 0` below the level of the unsaturated contact, 0
    /// elsewhere (everywhere when unbounded).
    pub fn plastic_displacement(&self) -> impl ExactSizeIterator<Item = f64> + '_ {
        let (c, level) = (self.constraint, self.fields.gap_level);
        self.fields
            .pressure
            .iter()
            .zip(&self.fields.separation)
            .map(move |(&p, &w)| {
                if c.saturated(p) {
                    (level - w).max(0.0)
                } else {
                    0.0
                }
            })
    }

    /// Start the next [`Self::solve`] from `pressure` (row-major, finite, ≥ 0, not all
    /// zero) instead of the previous solutions; it is scaled to the new load first, and the
    /// next solve does not extrapolate through it. For warm starts other than the sweep's
    /// own (compared in `cargo bench --bench warm_start`).
    pub fn set_start(&mut self, pressure: &[f64]) -> Result<(), ContactError> {
        let n = self.op.grid().n();
        if pressure.len() != self.fields.pressure.len() {
            return Err(ContactError::BadLength {
                expected: self.fields.pressure.len(),
                got: pressure.len(),
            });
        }
        if let Some((i, v)) = pressure
            .iter()
            .enumerate()
            .find(|(_, v)| !(v.is_finite() && **v >= 0.0))
        {
            return Err(ContactError::BadStart {
                row: i / n,
                col: i % n,
                value: *v,
            });
        }
        if pressure.iter().all(|&p| p == 0.0) {
            return Err(ContactError::BadConfig(
                "a start pressure must not be zero everywhere".into(),
            ));
        }
        self.fields.pressure.copy_from_slice(pressure);
        self.warm.history.forget();
        self.warm.has_solution = true;
        self.warm.separation_exact = false;
        Ok(())
    }
}
