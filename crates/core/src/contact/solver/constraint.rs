//! The constraint on the pressure at each node: what the projection after a step keeps, which
//! nodes the conjugate gradient moves, and which may enter the free set.
//!
//! The solver is generic over it ([`super::Solver`]`<C>`): every pass that projects a
//! pressure or asks whether a node is in contact calls its methods, which inline into the
//! scalar and AVX2 row kernels alike, so a constraint costs nothing at run time and
//! [`NonNegative`] gives exactly the bits the solver always had. A new constraint implements
//! [`Constraint`] in a file of its own and is passed to [`super::Solver::with_constraint`];
//! the perfectly plastic ceiling `0 ≤ p ≤ p_max` (`ceiling.rs`) is one, and what a bounded
//! constraint changes beyond these methods is in `bounded.rs` (docs/ARCHITECTURE.md).

#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

/// The admissible set of the pressure at one node. The scalar and AVX2 forms must do the same
/// operations, so that both give the same bits (the row kernels' tests compare them); a
/// pressure of 0 must be inactive (the row kernels pad their tails with it).
pub trait Constraint: Copy + Send + Sync + PartialEq + std::fmt::Debug + 'static {
    /// The admissible pressure nearest to `p` (NaN maps to an admissible value).
    fn project(self, p: f64) -> f64;

    /// Whether a node of pressure `p` is active: in contact and free to move both ways. The
    /// conjugate gradient works on the active set; the gradient's statistics, the plain
    /// direction and the load offset's slope are taken over it.
    fn active(self, p: f64) -> bool;

    /// Whether the constraint has a ceiling `p ≤ p_max` ([`Self::ceiling`]). A bounded
    /// constraint is not positively homogeneous, so the solver never rescales its pressures:
    /// it restores the load by an offset `p ← P(p + c)` and measures the error on both
    /// bounds (`Solver::complementarity_error`). A compile-time constant: the unbounded
    /// solver's code is unchanged by it.
    const BOUNDED: bool = false;

    /// The ceiling `p_max` (`+∞` when unbounded).
    #[inline(always)]
    fn ceiling(self) -> f64 {
        f64::INFINITY
    }

    /// Whether a node of pressure `p` sits on the ceiling (never when unbounded).
    #[inline(always)]
    fn saturated(self, _p: f64) -> bool {
        false
    }

    /// Whether a node of pressure `p` and separation `w = u − h` is in the free set of the
    /// preconditioned iteration, given the level `mean` of the gradient and the entry
    /// threshold `entry ≤ mean`: the active nodes and those that interpenetrate.
    #[inline(always)]
    fn free(self, p: f64, w: f64, entry: f64, _mean: f64) -> bool {
        self.active(p) || w < entry
    }

    /// Whether a load offset moves a node of pressure `p` ([`Self::offset`]); `wide` asks
    /// for every node, where a constraint would move fewer.
    #[inline(always)]
    fn moves(self, _p: f64, _wide: bool) -> bool {
        true
    }

    /// A node of pressure `p` offset by `c` when the load is restored
    /// (`Solver::load_offset`): `P(p + c)` where it [`Self::moves`], which for `c ≤ 0`
    /// leaves the nodes at 0 there; `p` elsewhere.
    #[inline(always)]
    fn offset(self, p: f64, c: f64, wide: bool) -> f64 {
        // Both sides computed and selected (no branch on scattered nodes).
        let moved = self.project(p + c);
        if self.moves(p, wide) {
            moved
        } else {
            p
        }
    }

    /// The plain iteration's re-admission after the step: `kept` is the projected pressure,
    /// `gc = w − level` the gradient, `tau` the step. A node the projection left at 0 where
    /// the surfaces interpenetrate (`gc < 0`) re-enters with `−τ gc`; the others keep `kept`.
    #[inline(always)]
    fn readmit(self, kept: f64, gc: f64, tau: f64) -> f64 {
        if kept == 0.0 && gc < 0.0 {
            -tau * gc
        } else {
            kept
        }
    }

    /// [`Self::project`] on four lanes.
    ///
    /// # Safety
    /// AVX2 must be present; call it from a function compiled with AVX2, into which it
    /// inlines.
    #[cfg(target_arch = "x86_64")]
    unsafe fn project_avx2(self, p: __m256d) -> __m256d;

    /// [`Self::active`] on four lanes: all bits set where active, none elsewhere.
    ///
    /// # Safety
    /// As [`Self::project_avx2`].
    #[cfg(target_arch = "x86_64")]
    unsafe fn active_avx2(self, p: __m256d) -> __m256d;

    /// [`Self::free`] on four lanes, as a mask.
    ///
    /// # Safety
    /// As [`Self::project_avx2`].
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn free_avx2(self, p: __m256d, w: __m256d, entry: __m256d, _mean: __m256d) -> __m256d {
        // SAFETY: the caller guarantees AVX2.
        unsafe { _mm256_or_pd(self.active_avx2(p), _mm256_cmp_pd::<_CMP_LT_OQ>(w, entry)) }
    }

    /// [`Self::readmit`] on four lanes (`neg_tau` is `−τ`).
    ///
    /// # Safety
    /// As [`Self::project_avx2`].
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn readmit_avx2(self, kept: __m256d, gc: __m256d, neg_tau: __m256d) -> __m256d {
        // SAFETY: the caller guarantees AVX2.
        unsafe {
            let zero = _mm256_setzero_pd();
            let enter = _mm256_and_pd(
                _mm256_cmp_pd::<_CMP_EQ_OQ>(kept, zero),
                _mm256_cmp_pd::<_CMP_LT_OQ>(gc, zero),
            );
            _mm256_blendv_pd(kept, _mm256_mul_pd(neg_tau, gc), enter)
        }
    }
}

/// Frictionless elastic contact: `p ≥ 0`, every node of positive pressure active.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct NonNegative;

impl Constraint for NonNegative {
    #[inline(always)]
    fn project(self, p: f64) -> f64 {
        if p > 0.0 {
            p
        } else {
            0.0
        }
    }

    #[inline(always)]
    fn active(self, p: f64) -> bool {
        p > 0.0
    }

    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn project_avx2(self, p: __m256d) -> __m256d {
        // SAFETY: the caller guarantees AVX2. Where `p > 0` fails (NaN too) the mask is 0,
        // and so is the result, as in `project`.
        unsafe { _mm256_and_pd(_mm256_cmp_pd::<_CMP_GT_OQ>(p, _mm256_setzero_pd()), p) }
    }

    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn active_avx2(self, p: __m256d) -> __m256d {
        // SAFETY: the caller guarantees AVX2.
        unsafe { _mm256_cmp_pd::<_CMP_GT_OQ>(p, _mm256_setzero_pd()) }
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// Each AVX2 form gives the scalar form's bits on values either side of 0, ±0, ±∞ and NaN
    /// (the ceiling's own test calls [`check`] with ceilings among those values).
    #[test]
    fn vector_forms_match_the_scalar_ones() {
        super::super::test_support::require_vector_path();
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") {
            check(NonNegative);
        }
    }

    /// Every AVX2 form of `c` against its scalar form, bit for bit (AVX2 must be present).
    #[cfg(target_arch = "x86_64")]
    pub(in super::super) fn check<C: Constraint>(c: C) {
        let values = [
            -1.5,
            -0.0,
            0.0,
            1e-300,
            2.5,
            3.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            0.75,
            -0.25,
            1.0,
        ];
        let (entry, mean, tau) = (0.25, 0.5, 0.75);
        for p in values.chunks(4) {
            for w in values.chunks(4) {
                let (p, w): ([f64; 4], [f64; 4]) = (p.try_into().unwrap(), w.try_into().unwrap());
                let mut out = [[0.0; 4]; 4];
                // SAFETY: AVX2 is present (checked by the caller).
                unsafe { lanes(c, &p, &w, [entry, mean, tau], &mut out) };
                let [project, active, free, readmit] = out;
                for l in 0..4 {
                    let at = format!("{c:?} p {} w {}", p[l], w[l]);
                    assert_eq!(project[l].to_bits(), c.project(p[l]).to_bits(), "{at}");
                    assert_eq!(active[l].to_bits() != 0, c.active(p[l]), "{at}");
                    assert_eq!(
                        free[l].to_bits() != 0,
                        c.free(p[l], w[l], entry, mean),
                        "{at}"
                    );
                    // The re-admission takes a projected pressure and a gradient.
                    let kept = c.project(p[l]);
                    assert_eq!(
                        readmit[l].to_bits(),
                        c.readmit(kept, w[l], tau).to_bits(),
                        "{at}"
                    );
                }
            }
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn lanes<C: Constraint>(
        c: C,
        p: &[f64; 4],
        w: &[f64; 4],
        [entry, mean, tau]: [f64; 3],
        out: &mut [[f64; 4]; 4],
    ) {
        unsafe {
            let (pv, wv) = (_mm256_loadu_pd(p.as_ptr()), _mm256_loadu_pd(w.as_ptr()));
            let free = c.free_avx2(pv, wv, _mm256_set1_pd(entry), _mm256_set1_pd(mean));
            let kept = c.project_avx2(pv);
            let readmit = c.readmit_avx2(kept, wv, _mm256_set1_pd(-tau));
            for (o, v) in out
                .iter_mut()
                .zip([c.project_avx2(pv), c.active_avx2(pv), free, readmit])
            {
                _mm256_storeu_pd(o.as_mut_ptr(), v);
            }
        }
    }
}
