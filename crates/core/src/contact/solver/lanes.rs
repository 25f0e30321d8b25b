//! Values on vector lanes, the one form in which a constraint writes each rule it applies at
//! a node ([`super::constraint::Constraint`]): generic over [`Lanes`], a rule compiles to
//! the scalar code with `f64` (one node; the row kernels compiled once more with AVX2
//! vectorise it) and to AVX2 intrinsics with [`F64x4`] (four nodes), and both do the same
//! IEEE operations in the same order, so that they give the same bits (the constraints' tests
//! compare them). Imports nothing of the solver.

use std::ops::{Add, BitAnd, BitOr, Mul, Not, Sub};

#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

/// Which lanes a comparison held on: `bool` for one value, a lane mask for four.
pub trait Mask: Copy + BitAnd<Output = Self> + BitOr<Output = Self> + Not<Output = Self> {
    /// `a` on the lanes set, `b` on the others.
    fn select(self, a: Self, b: Self) -> Self;
}

/// Values of `f64` on one or more lanes. Each method's scalar form is the expression its
/// doc gives; the vector forms are the instructions that compute exactly that per lane.
pub trait Lanes:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + std::fmt::Debug
{
    type Mask: Mask;

    /// `x` on every lane of a value like `self` (made from a value, so that a vector one
    /// exists only where its instructions do).
    fn splat(self, x: f64) -> Self;

    /// The mask set on no lane.
    fn none(self) -> Self::Mask;

    /// `if self < o { self } else { o }` (`o` where either is NaN).
    fn min(self, o: Self) -> Self;

    /// `if self > o { self } else { o }` (`o` where either is NaN).
    fn max(self, o: Self) -> Self;

    /// `self > o` (false where either is NaN).
    fn gt(self, o: Self) -> Self::Mask;

    /// `self < o`.
    fn lt(self, o: Self) -> Self::Mask;

    /// `self >= o`.
    fn ge(self, o: Self) -> Self::Mask;

    /// `self == o`.
    fn eq(self, o: Self) -> Self::Mask;

    /// `if m { self } else { 0.0 }` (`+0`).
    fn keep(self, m: Self::Mask) -> Self;

    /// `if m { 0.0 } else { self }` (`+0`).
    fn clear(self, m: Self::Mask) -> Self;

    /// `if m { a } else { b }`.
    fn select(m: Self::Mask, a: Self, b: Self) -> Self;
}

impl Mask for bool {
    /// Written without a branch: the nodes are scattered over the grid.
    #[inline(always)]
    fn select(self, a: Self, b: Self) -> Self {
        (self & a) | (!self & b)
    }
}

impl Lanes for f64 {
    type Mask = bool;

    #[inline(always)]
    fn splat(self, x: f64) -> Self {
        x
    }

    #[inline(always)]
    fn none(self) -> bool {
        false
    }

    #[inline(always)]
    fn min(self, o: Self) -> Self {
        if self < o {
            self
        } else {
            o
        }
    }

    #[inline(always)]
    fn max(self, o: Self) -> Self {
        if self > o {
            self
        } else {
            o
        }
    }

    #[inline(always)]
    fn gt(self, o: Self) -> bool {
        self > o
    }

    #[inline(always)]
    fn lt(self, o: Self) -> bool {
        self < o
    }

    #[inline(always)]
    fn ge(self, o: Self) -> bool {
        self >= o
    }

    #[inline(always)]
    fn eq(self, o: Self) -> bool {
        self == o
    }

    #[inline(always)]
    fn keep(self, m: bool) -> Self {
        if m {
            self
        } else {
            0.0
        }
    }

    #[inline(always)]
    fn clear(self, m: bool) -> Self {
        if m {
            0.0
        } else {
            self
        }
    }

    #[inline(always)]
    fn select(m: bool, a: Self, b: Self) -> Self {
        if m {
            a
        } else {
            b
        }
    }
}

// The AVX2 forms. A value of these types exists only where AVX2 is present (made by the
// unsafe `F64x4::from_raw`, or from one that exists), so their safe methods may use the
// intrinsics; they inline into the row kernels compiled with AVX2.

/// Four `f64` lanes in an AVX register.
#[cfg(target_arch = "x86_64")]
#[derive(Debug, Clone, Copy)]
pub struct F64x4(__m256d);

/// A mask of four lanes: all bits set where it holds, none elsewhere.
#[cfg(target_arch = "x86_64")]
#[derive(Debug, Clone, Copy)]
pub struct M64x4(__m256d);

#[cfg(target_arch = "x86_64")]
impl F64x4 {
    /// # Safety
    /// AVX2 must be present.
    #[inline(always)]
    pub unsafe fn from_raw(v: __m256d) -> Self {
        Self(v)
    }

    /// The register.
    #[inline(always)]
    pub fn raw(self) -> __m256d {
        self.0
    }
}

#[cfg(target_arch = "x86_64")]
impl M64x4 {
    /// The register.
    #[inline(always)]
    pub fn raw(self) -> __m256d {
        self.0
    }
}

// SAFETY (every `unsafe` block below): a value of these types exists only where AVX2
// is present (the types' contract).
#[cfg(target_arch = "x86_64")]
macro_rules! op {
    ($ty:ty, $trait:ident, $method:ident, $intrinsic:ident) => {
        impl $trait for $ty {
            type Output = Self;
            #[inline(always)]
            fn $method(self, o: Self) -> Self {
                Self(unsafe { $intrinsic(self.0, o.0) })
            }
        }
    };
}
#[cfg(target_arch = "x86_64")]
op!(F64x4, Add, add, _mm256_add_pd);
#[cfg(target_arch = "x86_64")]
op!(F64x4, Sub, sub, _mm256_sub_pd);
#[cfg(target_arch = "x86_64")]
op!(F64x4, Mul, mul, _mm256_mul_pd);
#[cfg(target_arch = "x86_64")]
op!(M64x4, BitAnd, bitand, _mm256_and_pd);
#[cfg(target_arch = "x86_64")]
op!(M64x4, BitOr, bitor, _mm256_or_pd);

#[cfg(target_arch = "x86_64")]
impl Not for M64x4 {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        Self(unsafe { _mm256_xor_pd(self.0, _mm256_castsi256_pd(_mm256_set1_epi64x(-1))) })
    }
}

#[cfg(target_arch = "x86_64")]
impl Mask for M64x4 {
    #[inline(always)]
    fn select(self, a: Self, b: Self) -> Self {
        Self(unsafe { _mm256_blendv_pd(b.0, a.0, self.0) })
    }
}

#[cfg(target_arch = "x86_64")]
impl Lanes for F64x4 {
    type Mask = M64x4;

    #[inline(always)]
    fn splat(self, x: f64) -> Self {
        Self(unsafe { _mm256_set1_pd(x) })
    }

    #[inline(always)]
    fn none(self) -> M64x4 {
        M64x4(unsafe { _mm256_setzero_pd() })
    }

    /// `min_pd(a, b)` is `if a < b { a } else { b }`.
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        Self(unsafe { _mm256_min_pd(self.0, o.0) })
    }

    /// `max_pd(a, b)` is `if a > b { a } else { b }`.
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        Self(unsafe { _mm256_max_pd(self.0, o.0) })
    }

    #[inline(always)]
    fn gt(self, o: Self) -> M64x4 {
        M64x4(unsafe { _mm256_cmp_pd::<_CMP_GT_OQ>(self.0, o.0) })
    }

    #[inline(always)]
    fn lt(self, o: Self) -> M64x4 {
        M64x4(unsafe { _mm256_cmp_pd::<_CMP_LT_OQ>(self.0, o.0) })
    }

    #[inline(always)]
    fn ge(self, o: Self) -> M64x4 {
        M64x4(unsafe { _mm256_cmp_pd::<_CMP_GE_OQ>(self.0, o.0) })
    }

    #[inline(always)]
    fn eq(self, o: Self) -> M64x4 {
        M64x4(unsafe { _mm256_cmp_pd::<_CMP_EQ_OQ>(self.0, o.0) })
    }

    #[inline(always)]
    fn keep(self, m: M64x4) -> Self {
        Self(unsafe { _mm256_and_pd(m.0, self.0) })
    }

    #[inline(always)]
    fn clear(self, m: M64x4) -> Self {
        Self(unsafe { _mm256_andnot_pd(m.0, self.0) })
    }

    #[inline(always)]
    fn select(m: M64x4, a: Self, b: Self) -> Self {
        Self(unsafe { _mm256_blendv_pd(b.0, a.0, m.0) })
    }
}
