//! What the preconditioner's layers share: the level of the gradient and the free set it
//! defines ([`Level`]), and the per-block sums off the free set that the extension
//! fills and the deflation restricts ([`OffBlock`]). The layers import this module and not
//! each other's internals.

use super::constraint::Constraint;

/// The level of the gradient `g = w − mean` on the free set (the mean of `w = u − h` over
/// the contact set), the free set's entry threshold `entry ≤ mean` (a node off the contact
/// set joins F where `w < entry`; `entry = mean − margin`, with the margin of
/// [`super::Extension::entry_margin`] on large boxes and 0 elsewhere), and the constraint
/// that says which nodes are in contact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Level<C> {
    pub mean: f64,
    pub entry: f64,
    pub constraint: C,
}

impl<C: Constraint> Level<C> {
    /// Membership of the free set `F = {active} ∪ {w < entry}`: the contact set and the
    /// nodes that interpenetrate (by more than the margin), whose pressure the next step may
    /// raise ([`Constraint::free`]).
    #[inline(always)]
    pub(super) fn free(self, p: f64, w: f64) -> bool {
        self.constraint.free(p, w, self.entry, self.mean)
    }
}

/// Per row block of the FFT: the sums of `y / D` off F over the cells its rows touch.
pub(super) struct OffBlock {
    pub(super) first_row: usize,
    pub(super) first_cell_row: usize,
    pub(super) sums: Vec<f64>,
    /// With the deflation: the restriction of the output on F to the model rows from
    /// `restrict_low` (unwrapped) that the block's rows reach.
    pub(super) restrict_low: i64,
    pub(super) restrict: Vec<f64>,
}
