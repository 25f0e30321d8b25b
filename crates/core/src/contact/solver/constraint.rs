//! The constraint on the pressure at each node: what the projection after a step keeps, which
//! nodes the conjugate gradient moves, and which may enter the free set.
//!
//! The solver is generic over it ([`super::Solver`]`<C>`): every pass that projects a
//! pressure or asks whether a node is in contact calls its methods, which inline into the
//! scalar and AVX2 row kernels alike, so a constraint costs nothing at run time and
//! [`NonNegative`] gives exactly the bits the solver always had. A new constraint (the
//! perfectly plastic ceiling `0 ≤ p ≤ p_max` is the one to come) implements [`Constraint`]
//! in a file of its own and is passed to [`super::Solver::with_constraint`]; what it changes
//! beyond these methods (the error measure on saturated nodes) is named in
//! docs/ARCHITECTURE.md.

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

    /// Whether a node of pressure `p` and separation `w = u − h` is in the free set of the
    /// preconditioned iteration, given the entry threshold `entry` below the level: the active
    /// nodes and those that interpenetrate.
    #[inline(always)]
    fn free(self, p: f64, w: f64, entry: f64) -> bool {
        self.active(p) || w < entry
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
    unsafe fn free_avx2(self, p: __m256d, w: __m256d, entry: __m256d) -> __m256d {
        // SAFETY: the caller guarantees AVX2.
        unsafe { _mm256_or_pd(self.active_avx2(p), _mm256_cmp_pd::<_CMP_LT_OQ>(w, entry)) }
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
mod tests {
    use super::*;

    /// Each AVX2 form gives the scalar form's bits on values either side of 0, ±0, ±∞ and NaN.
    #[test]
    fn vector_forms_match_the_scalar_ones() {
        super::super::test_support::require_vector_path();
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") {
            let c = NonNegative;
            let values = [
                -1.5,
                -0.0,
                0.0,
                1e-300,
                2.5,
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::NAN,
            ];
            let entry = 0.25;
            for p in values.chunks(4) {
                for w in values.chunks(4) {
                    let (p, w): ([f64; 4], [f64; 4]) =
                        (p.try_into().unwrap(), w.try_into().unwrap());
                    let (mut project, mut active, mut free) = ([0.0; 4], [0.0; 4], [0.0; 4]);
                    // SAFETY: AVX2 is present (checked above).
                    unsafe { lanes(c, &p, &w, entry, &mut project, &mut active, &mut free) };
                    for l in 0..4 {
                        assert_eq!(project[l].to_bits(), c.project(p[l]).to_bits(), "{}", p[l]);
                        assert_eq!(active[l].to_bits() != 0, c.active(p[l]), "{}", p[l]);
                        assert_eq!(free[l].to_bits() != 0, c.free(p[l], w[l], entry));
                    }
                }
            }
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn lanes(
        c: NonNegative,
        p: &[f64; 4],
        w: &[f64; 4],
        entry: f64,
        project: &mut [f64; 4],
        active: &mut [f64; 4],
        free: &mut [f64; 4],
    ) {
        unsafe {
            let (pv, wv) = (_mm256_loadu_pd(p.as_ptr()), _mm256_loadu_pd(w.as_ptr()));
            _mm256_storeu_pd(project.as_mut_ptr(), c.project_avx2(pv));
            _mm256_storeu_pd(active.as_mut_ptr(), c.active_avx2(pv));
            _mm256_storeu_pd(
                free.as_mut_ptr(),
                c.free_avx2(pv, wv, _mm256_set1_pd(entry)),
            );
        }
    }
}
