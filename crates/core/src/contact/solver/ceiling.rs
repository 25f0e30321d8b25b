//! The perfectly plastic interface: the pressure saturates at a ceiling, `0 ≤ p ≤ p_max`
//! (Stanley & Kato 1997; Almqvist et al. 2007), `p_max` the hardness.
//!
//! Complementarity at the solution, with `ℓ` the rigid-body level of `w = u − h`:
//! `p = 0 → w ≥ ℓ` (a gap), `0 < p < p_max → w = ℓ` (contact), `p = p_max → w ≤ ℓ` (the
//! interpenetration `ℓ − w` is the plastic displacement). The solver's error measure on both
//! bounds and its load restoration by offset are in `Solver::complementarity_error` and
//! `load.rs`; docs/CONVENTIONS.md states them.

#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

use super::constraint::Constraint;

use super::ContactError;

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
    const BOUNDED: bool = true;

    /// Written as two selects (as [`Self::project_avx2`]), which compile without branches.
    #[inline(always)]
    fn project(self, p: f64) -> f64 {
        let positive = if p > 0.0 { p } else { 0.0 };
        if positive < self.max {
            positive
        } else {
            self.max
        }
    }

    #[inline(always)]
    fn active(self, p: f64) -> bool {
        (p > 0.0) & (p < self.max)
    }

    #[inline(always)]
    fn ceiling(self) -> f64 {
        self.max
    }

    #[inline(always)]
    fn saturated(self, p: f64) -> bool {
        p >= self.max
    }

    /// The active nodes, those at 0 that interpenetrate by more than the margin
    /// (`w < entry`), and those on the ceiling whose gradient is positive (`w > mean`).
    #[inline(always)]
    fn free(self, p: f64, w: f64, entry: f64, mean: f64) -> bool {
        // Without branches (as `free_avx2`): the bounds are scattered over the grid.
        let saturated = p >= self.max;
        (saturated & (w > mean)) | (!saturated & ((p > 0.0) | (w < entry)))
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
    fn readmit(self, kept: f64, gc: f64, tau: f64) -> f64 {
        if kept == 0.0 && gc < 0.0 {
            self.project(-tau * gc)
        } else if kept >= self.max && gc > 0.0 {
            self.project(self.max - tau * gc)
        } else {
            kept
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn project_avx2(self, p: __m256d) -> __m256d {
        // SAFETY: the caller guarantees AVX2. `p > 0` fails for NaN, giving 0 as in
        // `project`; `min_pd(x, max)` is `if x < max { x } else { max }`.
        unsafe {
            let positive = _mm256_and_pd(_mm256_cmp_pd::<_CMP_GT_OQ>(p, _mm256_setzero_pd()), p);
            _mm256_min_pd(positive, _mm256_set1_pd(self.max))
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn active_avx2(self, p: __m256d) -> __m256d {
        // SAFETY: the caller guarantees AVX2.
        unsafe {
            _mm256_and_pd(
                _mm256_cmp_pd::<_CMP_GT_OQ>(p, _mm256_setzero_pd()),
                _mm256_cmp_pd::<_CMP_LT_OQ>(p, _mm256_set1_pd(self.max)),
            )
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn free_avx2(self, p: __m256d, w: __m256d, entry: __m256d, mean: __m256d) -> __m256d {
        // SAFETY: the caller guarantees AVX2.
        unsafe {
            let saturated = _mm256_cmp_pd::<_CMP_GE_OQ>(p, _mm256_set1_pd(self.max));
            let below = _mm256_or_pd(
                _mm256_cmp_pd::<_CMP_GT_OQ>(p, _mm256_setzero_pd()),
                _mm256_cmp_pd::<_CMP_LT_OQ>(w, entry),
            );
            _mm256_blendv_pd(below, _mm256_cmp_pd::<_CMP_GT_OQ>(w, mean), saturated)
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn readmit_avx2(self, kept: __m256d, gc: __m256d, neg_tau: __m256d) -> __m256d {
        // SAFETY: the caller guarantees AVX2.
        unsafe {
            let zero = _mm256_setzero_pd();
            let max = _mm256_set1_pd(self.max);
            let enter = _mm256_and_pd(
                _mm256_cmp_pd::<_CMP_EQ_OQ>(kept, zero),
                _mm256_cmp_pd::<_CMP_LT_OQ>(gc, zero),
            );
            let leave = _mm256_and_pd(
                _mm256_cmp_pd::<_CMP_GE_OQ>(kept, max),
                _mm256_cmp_pd::<_CMP_GT_OQ>(gc, zero),
            );
            let entered = self.project_avx2(_mm256_mul_pd(neg_tau, gc));
            let lowered = self.project_avx2(_mm256_add_pd(max, _mm256_mul_pd(neg_tau, gc)));
            _mm256_blendv_pd(_mm256_blendv_pd(kept, entered, enter), lowered, leave)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each AVX2 form gives the scalar form's bits (as `NonNegative`'s), for ceilings among
    /// the values tried and one below all but zero.
    #[test]
    fn vector_forms_match_the_scalar_ones() {
        super::super::test_support::require_vector_path();
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") {
            for max in [2.5, 1.0, 1e-300] {
                super::super::constraint::tests::check(Ceiling::new(max).unwrap());
            }
        }
    }
}
