//! The ceiling's rules at a node, written once over lanes ([`Lanes`]).

use super::super::constraint::{Constraint, LevelSums};
use super::super::error::ContactError;
use super::super::lanes::{Lanes, Mask};

/// `0 ≤ p ≤ p_max`: the nodes strictly between the bounds are active (the conjugate
/// gradient moves them); a node on the ceiling is saturated, and joins the free set of the
/// preconditioned iteration (or is re-admitted by the plain one) where its gradient would
/// lower its pressure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ceiling {
    max: f64,
}

impl Ceiling {
    /// The ceiling `p_max` (finite, > 0), in the units of the pressure.
    pub fn new(max: f64) -> Result<Self, ContactError> {
        if max.is_finite() && max > 0.0 {
            Ok(Self { max })
        } else {
            Err(ContactError::BadConfig(format!(
                "pressure ceiling {max} must be finite and > 0 (an unbounded pressure is \
                 the elastic constraint, NonNegative)"
            )))
        }
    }

    /// `p_max`.
    pub fn max(self) -> f64 {
        self.max
    }
}

impl Constraint for Ceiling {
    /// Two selects: `P(p) = min(p⁺, p_max)`, `0` for NaN.
    #[inline(always)]
    fn project<V: Lanes>(self, p: V) -> V {
        p.keep(p.gt(p.splat(0.0))).min(p.splat(self.max))
    }

    #[inline(always)]
    fn active<V: Lanes>(self, p: V) -> V::Mask {
        p.gt(p.splat(0.0)) & p.lt(p.splat(self.max))
    }

    #[inline(always)]
    fn ceiling(self) -> Option<f64> {
        Some(self.max)
    }

    #[inline(always)]
    fn saturated<V: Lanes>(self, p: V) -> V::Mask {
        p.ge(p.splat(self.max))
    }

    /// The active nodes, those at 0 that interpenetrate by more than the margin
    /// (`w < entry`), and those on the ceiling whose gradient is positive (`w > mean`).
    #[inline(always)]
    fn free<V: Lanes>(self, p: V, w: V, entry: V, mean: V) -> V::Mask {
        let below = p.gt(p.splat(0.0)) | w.lt(entry);
        self.saturated(p).select(w.gt(mean), below)
    }

    /// Only the nodes off the bounds move (in an admissible field, the active ones), unless
    /// `wide`: a node at 0 stays out of contact and one on the ceiling stays saturated
    /// (moving them by the offset would undo the iteration's last step on them at every
    /// restoration, and it cycles). `wide` is every node, for when the active nodes cannot
    /// carry the load.
    #[inline(always)]
    fn moves(self, p: f64, wide: bool) -> bool {
        wide | ((p != 0.0) & (p != self.max))
    }

    /// Also lowers a node the projection left on the ceiling where its gradient is positive
    /// (`gc > 0`), to `P(p_max − τ gc)`; a re-admitted node at 0 enters at `P(−τ gc)`.
    #[inline(always)]
    fn readmit<V: Lanes>(self, kept: V, gc: V, neg_tau: V) -> V {
        let (zero, max) = (kept.splat(0.0), kept.splat(self.max));
        let enter = kept.eq(zero) & gc.lt(zero);
        let leave = kept.ge(max) & gc.gt(zero);
        let step = neg_tau * gc;
        let entered = V::select(enter, self.project(step), kept);
        V::select(leave, self.project(max + step), entered)
    }

    /// A saturated node enters the saturated sums, the others the minimum (the level is
    /// that of the unsaturated nodes) and `Σpg`; adding `+0` in the lanes a sum skips leaves
    /// it as it was (no sum here is ever `−0`).
    #[inline(always)]
    fn add_to_level<V: Lanes>(self, p: V, g: V, sums: LevelSums<'_, V>) {
        let sat = self.saturated(p);
        *sums.sat_n = *sums.sat_n + p.splat(1.0).keep(sat);
        *sums.sat_g = *sums.sat_g + g.keep(sat);
        *sums.sat_max = V::select(sat, g.max(*sums.sat_max), *sums.sat_max);
        *sums.min = V::select(sat, *sums.min, g.min(*sums.min));
        *sums.spg = *sums.spg + (p * g).clear(sat);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each rule on four lanes gives the scalar form's bits (as `NonNegative`'s), for
    /// ceilings among the values tried and one below all but zero.
    #[test]
    fn vector_forms_match_the_scalar_ones() {
        super::super::super::test_support::require_vector_path();
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") {
            for max in [2.5, 1.0, 1e-300] {
                super::super::super::constraint::tests::check(Ceiling::new(max).unwrap());
            }
        }
    }
}
