//! The 1-D real transforms along the rows of [`super::Fft2`]: a real row of even length `n`
//! is read as `n/2` complex values, transformed by a complex FFT of length `n/2` (rustfft)
//! and untangled into the `n/2 + 1` values of its half spectrum; the inverse tangles the
//! half spectrum first. This is realfft's algorithm, operation for operation (the same
//! twiddles, products and sums in the same order, so the results are bit-identical to
//! realfft's; a test checks it), with two differences that make the rows pass cheaper:
//! - where the inner FFT reads its input directly (rustfft's butterflies, i.e. `n ≤ 1024`
//!   in f64), the forward transform reads the caller's row without copying it first;
//! - the untangling and tangling passes run several pairs at a time in 256-bit registers
//!   (two in f64 where the processor has AVX, four in f32 with AVX2; the same operations,
//!   [`super::Real`]).

use std::sync::Arc;

use rustfft::{num_complex::Complex, Fft, FftPlanner};

use super::precision::Real;

/// Planned real-to-complex and complex-to-real transforms of rows of even length `n`.
pub(super) struct RealRows<T: Real> {
    n: usize,
    forward: Arc<dyn Fft<T>>,
    inverse: Arc<dyn Fft<T>>,
    /// The forward untangling twiddles, `exp(−2πi k/n) / 2` for `k = 1 ..` (one per pair).
    pub(super) forward_twiddles: Vec<Complex<T>>,
    /// The inverse tangling twiddles, `exp(+2πi k/n)` for `k = 1 ..`.
    pub(super) inverse_twiddles: Vec<Complex<T>>,
    /// Whether the inner forward FFT reads its input in place (no scratch of its own).
    reads_in_place: bool,
}

/// realfft's twiddle `exp(−2πi index/len)`, computed in f64 and rounded once to `T`.
fn twiddle<T: Real>(index: usize, len: usize) -> Complex<T> {
    let angle = -2f64 * std::f64::consts::PI / len as f64 * index as f64;
    Complex::new(T::narrow(angle.cos()), T::narrow(angle.sin()))
}

impl<T: Real> RealRows<T> {
    /// Plan the transforms of rows of length `n` (even, ≥ 2).
    pub(super) fn new(n: usize, planner: &mut FftPlanner<T>) -> Self {
        assert!(
            n >= 2 && n.is_multiple_of(2),
            "rows need an even length ≥ 2"
        );
        // One twiddle per pair (k, n/2 − k) with 0 < k < n/2 − k.
        let pairs = n.div_ceil(4) - 1;
        let half = T::narrow(0.5);
        let forward = planner.plan_fft_forward(n / 2);
        Self {
            n,
            reads_in_place: forward.get_immutable_scratch_len() == 0,
            inverse: planner.plan_fft_inverse(n / 2),
            forward,
            forward_twiddles: (1..=pairs).map(|k| twiddle::<T>(k, n) * half).collect(),
            inverse_twiddles: (1..=pairs).map(|k| twiddle::<T>(k, n).conj()).collect(),
        }
    }

    /// Scratch the transforms need (complex values).
    pub(super) fn scratch_len(&self) -> usize {
        [
            self.forward.get_immutable_scratch_len(),
            self.forward.get_outofplace_scratch_len(),
            self.inverse.get_outofplace_scratch_len(),
        ]
        .into_iter()
        .max()
        .unwrap_or(0)
    }

    /// Whether [`Self::forward_from`] reads its input row directly (else it needs it
    /// copied into a row it may overwrite, [`Self::forward`]).
    pub(super) fn reads_in_place(&self) -> bool {
        self.reads_in_place
    }

    /// Forward transform of the real row `row` (length `n`) into `out` (`n/2 + 1` values),
    /// `row` left unchanged. Only where [`Self::reads_in_place`]. A row of zeros (for the
    /// solver's fields, a row with no contact node) is not transformed: its spectrum is
    /// zeros, as in [`Self::forward`].
    pub(super) fn forward_from(
        &self,
        row: &[T],
        out: &mut [Complex<T>],
        scratch: &mut [Complex<T>],
    ) {
        debug_assert!(self.reads_in_place);
        let (n, h) = (self.n, self.n / 2);
        assert!(row.len() == n && out.len() == h + 1, "row lengths");
        if T::all_zero(row) {
            out.fill(Complex::new(T::zero(), T::zero()));
            return;
        }
        // SAFETY: `row` holds n = 2h values of T; Complex<T> is two T's (repr(C)), with
        // T's alignment.
        let packed = unsafe { std::slice::from_raw_parts(row.as_ptr() as *const Complex<T>, h) };
        self.forward
            .process_immutable_with_scratch(packed, &mut out[..h], scratch);
        T::untangle_forward(out, &self.forward_twiddles);
    }

    /// Forward transform of the real row `row` (length `n`) into `out` (`n/2 + 1` values);
    /// `row` is used as working memory and holds garbage afterwards. A row of zeros is not
    /// transformed: its spectrum is set to zeros (the transform would give ±0).
    pub(super) fn forward(
        &self,
        row: &mut [T],
        out: &mut [Complex<T>],
        scratch: &mut [Complex<T>],
    ) {
        let (n, h) = (self.n, self.n / 2);
        assert!(row.len() == n && out.len() == h + 1, "row lengths");
        if T::all_zero(row) {
            out.fill(Complex::new(T::zero(), T::zero()));
            return;
        }
        // SAFETY: as in `forward_from`, mutably.
        let packed =
            unsafe { std::slice::from_raw_parts_mut(row.as_mut_ptr() as *mut Complex<T>, h) };
        self.forward
            .process_outofplace_with_scratch(packed, &mut out[..h], scratch);
        T::untangle_forward(out, &self.forward_twiddles);
    }

    /// Inverse transform of the half spectrum `spectrum` (`n/2 + 1` values) into the real
    /// row `row`. The imaginary parts of the first and last values are taken as zero (the
    /// projection onto real rows); `spectrum` is working memory and holds garbage after.
    pub(super) fn inverse(
        &self,
        spectrum: &mut [Complex<T>],
        row: &mut [T],
        scratch: &mut [Complex<T>],
    ) {
        let (n, h) = (self.n, self.n / 2);
        assert!(row.len() == n && spectrum.len() == h + 1, "row lengths");
        spectrum[0].im = T::zero();
        spectrum[h].im = T::zero();
        T::tangle_inverse(spectrum, &self.inverse_twiddles);
        // SAFETY: as in `forward`.
        let packed =
            unsafe { std::slice::from_raw_parts_mut(row.as_mut_ptr() as *mut Complex<T>, h) };
        self.inverse
            .process_outofplace_with_scratch(&mut spectrum[..h], packed, scratch);
    }
}

/// The forward untangling: `out[..m]` (`m = out.len() − 1`) holds the complex FFT of the
/// packed row; afterwards `out` holds the row's half spectrum. Pair `k` (`1 ≤ k ≤
/// twiddles.len()`) combines `out[k]` and `out[m − k]` with `twiddles[k − 1]`.
pub(super) fn untangle_forward_plain<T: Real>(out: &mut [Complex<T>], twiddles: &[Complex<T>]) {
    untangle_forward_rest(out, twiddles, 1);
}

/// [`untangle_forward_plain`] from pair `first` on (the pairs before it already untangled,
/// by a vector loop), with the first, last and centre values. Those depend on no pair, and
/// no pair on them, so the order does not change a bit.
fn untangle_forward_rest<T: Real>(out: &mut [Complex<T>], twiddles: &[Complex<T>], first: usize) {
    let m = out.len() - 1;
    let zero = out[0];
    out[0] = Complex::new(zero.re + zero.im, T::zero());
    out[m] = Complex::new(zero.re - zero.im, T::zero());
    for k in first..=twiddles.len() {
        untangle_pair(out, k, m - k, twiddles[k - 1]);
    }
    if m.is_multiple_of(2) {
        out[m / 2].im = -out[m / 2].im;
    }
}

/// One pair of [`untangle_forward_plain`].
#[inline(always)]
pub(super) fn untangle_pair<T: Real>(
    out: &mut [Complex<T>],
    k: usize,
    mirror: usize,
    tw: Complex<T>,
) {
    let (a, b) = (out[k], out[mirror]);
    let (sum, diff) = (a + b, a - b);
    let half = T::narrow(0.5);
    let twiddled_real = sum.im * tw.re + diff.re * tw.im;
    let twiddled_imag = sum.im * tw.im - diff.re * tw.re;
    let (half_sum_re, half_diff_im) = (half * sum.re, half * diff.im);
    out[k] = Complex::new(half_sum_re + twiddled_real, half_diff_im + twiddled_imag);
    out[mirror] = Complex::new(half_sum_re - twiddled_real, twiddled_imag - half_diff_im);
}

/// The inverse tangling, in place: the half spectrum `spectrum` (imaginary parts of the
/// first and last values zero) becomes, in `spectrum[..m]`, the input of the complex
/// inverse FFT whose output is the packed real row.
pub(super) fn tangle_inverse_plain<T: Real>(spectrum: &mut [Complex<T>], twiddles: &[Complex<T>]) {
    tangle_inverse_rest(spectrum, twiddles, 1);
}

/// [`tangle_inverse_plain`] from pair `first` on, with the first and centre values (as
/// [`untangle_forward_rest`]).
fn tangle_inverse_rest<T: Real>(
    spectrum: &mut [Complex<T>],
    twiddles: &[Complex<T>],
    first: usize,
) {
    let m = spectrum.len() - 1;
    let (zero, last) = (spectrum[0], spectrum[m]);
    let (sum, diff) = (zero + last, zero - last);
    spectrum[0] = Complex::new(sum.re - sum.im, diff.re - diff.im);
    for k in first..=twiddles.len() {
        tangle_pair(spectrum, k, m - k, twiddles[k - 1]);
    }
    if m.is_multiple_of(2) {
        let centre = spectrum[m / 2];
        spectrum[m / 2] = (centre + centre).conj();
    }
}

/// One pair of [`tangle_inverse_plain`].
#[inline(always)]
pub(super) fn tangle_pair<T: Real>(
    spectrum: &mut [Complex<T>],
    k: usize,
    mirror: usize,
    tw: Complex<T>,
) {
    let (a, b) = (spectrum[k], spectrum[mirror]);
    let (sum, diff) = (a + b, a - b);
    let twiddled_real = sum.im * tw.re + diff.re * tw.im;
    let twiddled_imag = sum.im * tw.im - diff.re * tw.re;
    spectrum[k] = Complex::new(sum.re - twiddled_real, diff.im - twiddled_imag);
    spectrum[mirror] = Complex::new(sum.re + twiddled_real, -twiddled_imag - diff.im);
}

/// A 256-bit register of `WIDTH` complex values (two in f64, four in f32), with the few
/// operations the untangling and tangling need, each the same IEEE operation per lane as
/// the scalar code's. Only used inside functions compiled for AVX (f64) or AVX2 (f32).
#[cfg(target_arch = "x86_64")]
trait Lanes: Copy {
    type Real: Real;
    /// Complex values per register.
    const WIDTH: usize;
    unsafe fn load(p: *const Self::Real) -> Self;
    unsafe fn store(p: *mut Self::Real, v: Self);
    /// The complex values in reverse order.
    unsafe fn reversed(v: Self) -> Self;
    unsafe fn splat(x: Self::Real) -> Self;
    unsafe fn add(a: Self, b: Self) -> Self;
    unsafe fn sub(a: Self, b: Self) -> Self;
    unsafe fn mul(a: Self, b: Self) -> Self;
    /// Every real and imaginary part's sign flipped.
    unsafe fn neg(a: Self) -> Self;
    /// Each value's real part in both of its lanes.
    unsafe fn dup_re(v: Self) -> Self;
    /// Each value's imaginary part in both of its lanes.
    unsafe fn dup_im(v: Self) -> Self;
    /// Real parts from `re`, imaginary parts from `im`.
    unsafe fn join(re: Self, im: Self) -> Self;
}

#[cfg(target_arch = "x86_64")]
mod lanes {
    use std::arch::x86_64::*;

    /// Two f64 complex values (AVX).
    #[derive(Clone, Copy)]
    pub(super) struct F64x2(__m256d);
    /// Four f32 complex values (AVX2, for the reversal across lanes).
    #[derive(Clone, Copy)]
    pub(super) struct F32x4(__m256);

    impl crate::spectral::halfcomplex::Lanes for F64x2 {
        type Real = f64;
        const WIDTH: usize = 2;
        #[inline(always)]
        unsafe fn load(p: *const f64) -> Self {
            // SAFETY: the caller's bounds.
            Self(unsafe { _mm256_loadu_pd(p) })
        }
        #[inline(always)]
        unsafe fn store(p: *mut f64, v: Self) {
            // SAFETY: the caller's bounds.
            unsafe { _mm256_storeu_pd(p, v.0) }
        }
        #[inline(always)]
        unsafe fn reversed(v: Self) -> Self {
            Self(_mm256_permute2f128_pd::<0x01>(v.0, v.0))
        }
        #[inline(always)]
        unsafe fn splat(x: f64) -> Self {
            Self(_mm256_set1_pd(x))
        }
        #[inline(always)]
        unsafe fn add(a: Self, b: Self) -> Self {
            Self(_mm256_add_pd(a.0, b.0))
        }
        #[inline(always)]
        unsafe fn sub(a: Self, b: Self) -> Self {
            Self(_mm256_sub_pd(a.0, b.0))
        }
        #[inline(always)]
        unsafe fn mul(a: Self, b: Self) -> Self {
            Self(_mm256_mul_pd(a.0, b.0))
        }
        #[inline(always)]
        unsafe fn neg(a: Self) -> Self {
            Self(_mm256_xor_pd(a.0, _mm256_set1_pd(-0.0)))
        }
        #[inline(always)]
        unsafe fn dup_re(v: Self) -> Self {
            Self(_mm256_movedup_pd(v.0))
        }
        #[inline(always)]
        unsafe fn dup_im(v: Self) -> Self {
            Self(_mm256_permute_pd::<0b1111>(v.0))
        }
        #[inline(always)]
        unsafe fn join(re: Self, im: Self) -> Self {
            Self(_mm256_blend_pd::<0b1010>(re.0, im.0))
        }
    }

    impl crate::spectral::halfcomplex::Lanes for F32x4 {
        type Real = f32;
        const WIDTH: usize = 4;
        #[inline(always)]
        unsafe fn load(p: *const f32) -> Self {
            // SAFETY: the caller's bounds.
            Self(unsafe { _mm256_loadu_ps(p) })
        }
        #[inline(always)]
        unsafe fn store(p: *mut f32, v: Self) {
            // SAFETY: the caller's bounds.
            unsafe { _mm256_storeu_ps(p, v.0) }
        }
        #[inline(always)]
        unsafe fn reversed(v: Self) -> Self {
            // Each complex f32 value is one 64-bit lane: reverse the four.
            Self(_mm256_castpd_ps(_mm256_permute4x64_pd::<0b00_01_10_11>(
                _mm256_castps_pd(v.0),
            )))
        }
        #[inline(always)]
        unsafe fn splat(x: f32) -> Self {
            Self(_mm256_set1_ps(x))
        }
        #[inline(always)]
        unsafe fn add(a: Self, b: Self) -> Self {
            Self(_mm256_add_ps(a.0, b.0))
        }
        #[inline(always)]
        unsafe fn sub(a: Self, b: Self) -> Self {
            Self(_mm256_sub_ps(a.0, b.0))
        }
        #[inline(always)]
        unsafe fn mul(a: Self, b: Self) -> Self {
            Self(_mm256_mul_ps(a.0, b.0))
        }
        #[inline(always)]
        unsafe fn neg(a: Self) -> Self {
            Self(_mm256_xor_ps(a.0, _mm256_set1_ps(-0.0)))
        }
        #[inline(always)]
        unsafe fn dup_re(v: Self) -> Self {
            Self(_mm256_moveldup_ps(v.0))
        }
        #[inline(always)]
        unsafe fn dup_im(v: Self) -> Self {
            Self(_mm256_movehdup_ps(v.0))
        }
        #[inline(always)]
        unsafe fn join(re: Self, im: Self) -> Self {
            Self(_mm256_blend_ps::<0b1010_1010>(re.0, im.0))
        }
    }
}

/// Pairs `k .. k + W` of the untangling or tangling (`W = V::WIDTH`), loaded in registers:
/// the values `k ..`, their mirrors `m − k, m − k − 1, …` (in that order), and the products
/// of the twiddles shared by both loops. Returns `(sum, diff, twiddled_real,
/// twiddled_imag)` as [`untangle_pair`] and [`tangle_pair`] compute them, lane by lane.
///
/// # Safety
/// The register's instruction set must be present; values `k .. k + W` and `m − k − W + 1 ..
/// m − k + 1` of `p` (which must not overlap) and twiddles `k − 1 .. k − 1 + W` of `t` must
/// be valid.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn load_pairs<V: Lanes>(p: *const V::Real, t: *const V::Real, m: usize, k: usize) -> [V; 4] {
    // SAFETY: the caller's bounds.
    unsafe {
        let a = V::load(p.add(2 * k));
        let b = V::reversed(V::load(p.add(2 * (m - k + 1 - V::WIDTH))));
        let tw = V::load(t.add(2 * (k - 1)));
        let (sum, diff) = (V::add(a, b), V::sub(a, b));
        let (tw_re, tw_im) = (V::dup_re(tw), V::dup_im(tw));
        let (sum_im, diff_re) = (V::dup_im(sum), V::dup_re(diff));
        let twiddled_real = V::add(V::mul(sum_im, tw_re), V::mul(diff_re, tw_im));
        let twiddled_imag = V::sub(V::mul(sum_im, tw_im), V::mul(diff_re, tw_re));
        [sum, diff, twiddled_real, twiddled_imag]
    }
}

/// Store pairs `k .. k + W`: values `k ..` from the real parts `low_re` and imaginary parts
/// `low_im`, their mirrors `m − k, m − k − 1, …` from `high_re`, `high_im`.
///
/// # Safety
/// As for [`load_pairs`], with writes.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn store_pairs<V: Lanes>(
    p: *mut V::Real,
    m: usize,
    k: usize,
    [low_re, low_im, high_re, high_im]: [V; 4],
) {
    // SAFETY: the caller's bounds.
    unsafe {
        V::store(p.add(2 * k), V::join(low_re, low_im));
        V::store(
            p.add(2 * (m - k + 1 - V::WIDTH)),
            V::reversed(V::join(high_re, high_im)),
        );
    }
}

/// [`untangle_forward_plain`] `V::WIDTH` pairs at a time in registers (the same operations
/// in the same order), the last pairs by the plain loop.
///
/// # Safety
/// The register's instruction set must be present.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn untangle_forward_lanes<V: Lanes>(
    out: &mut [Complex<V::Real>],
    twiddles: &[Complex<V::Real>],
) {
    let m = out.len() - 1;
    let pairs = twiddles.len();
    assert!(
        2 * pairs < m || pairs == 0,
        "one twiddle per pair below the middle"
    );
    let (p, t) = (
        out.as_mut_ptr() as *mut V::Real,
        twiddles.as_ptr() as *const V::Real,
    );
    let mut k = 1;
    // SAFETY: the register's instruction set is the caller's; k + W − 1 ≤ pairs < m/2, so
    // values k .. k + W and their mirrors lie in `out` and do not overlap, and twiddles
    // k − 1 .. k − 1 + W lie in `twiddles`.
    unsafe {
        let half = V::splat(V::Real::narrow(0.5));
        while k + V::WIDTH - 1 <= pairs {
            let [sum, diff, twiddled_real, twiddled_imag] = load_pairs::<V>(p, t, m, k);
            let half_sum_re = V::mul(half, V::dup_re(sum));
            let half_diff_im = V::mul(half, V::dup_im(diff));
            store_pairs::<V>(
                p,
                m,
                k,
                [
                    V::add(half_sum_re, twiddled_real),
                    V::add(half_diff_im, twiddled_imag),
                    V::sub(half_sum_re, twiddled_real),
                    V::sub(twiddled_imag, half_diff_im),
                ],
            );
            k += V::WIDTH;
        }
    }
    untangle_forward_rest(out, twiddles, k);
}

/// [`tangle_inverse_plain`] `V::WIDTH` pairs at a time in registers (the same operations in
/// the same order; `−x − y` as a sign flip then a subtraction), the last pairs by the plain
/// loop.
///
/// # Safety
/// The register's instruction set must be present.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn tangle_inverse_lanes<V: Lanes>(
    spectrum: &mut [Complex<V::Real>],
    twiddles: &[Complex<V::Real>],
) {
    let m = spectrum.len() - 1;
    let pairs = twiddles.len();
    assert!(
        2 * pairs < m || pairs == 0,
        "one twiddle per pair below the middle"
    );
    let (p, t) = (
        spectrum.as_mut_ptr() as *mut V::Real,
        twiddles.as_ptr() as *const V::Real,
    );
    let mut k = 1;
    // SAFETY: as in `untangle_forward_lanes`.
    unsafe {
        while k + V::WIDTH - 1 <= pairs {
            let [sum, diff, twiddled_real, twiddled_imag] = load_pairs::<V>(p, t, m, k);
            let (sum_re, diff_im) = (V::dup_re(sum), V::dup_im(diff));
            store_pairs::<V>(
                p,
                m,
                k,
                [
                    V::sub(sum_re, twiddled_real),
                    V::sub(diff_im, twiddled_imag),
                    V::add(sum_re, twiddled_real),
                    V::sub(V::neg(twiddled_imag), diff_im),
                ],
            );
            k += V::WIDTH;
        }
    }
    tangle_inverse_rest(spectrum, twiddles, k);
}

/// [`untangle_forward_plain`] in f64, two pairs at a time in AVX registers.
///
/// # Safety
/// AVX must be present.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
pub(super) unsafe fn untangle_forward_avx(out: &mut [Complex<f64>], twiddles: &[Complex<f64>]) {
    // SAFETY: AVX is present (the caller's).
    unsafe { untangle_forward_lanes::<lanes::F64x2>(out, twiddles) }
}

/// [`tangle_inverse_plain`] in f64, two pairs at a time in AVX registers.
///
/// # Safety
/// AVX must be present.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
pub(super) unsafe fn tangle_inverse_avx(spectrum: &mut [Complex<f64>], twiddles: &[Complex<f64>]) {
    // SAFETY: AVX is present (the caller's).
    unsafe { tangle_inverse_lanes::<lanes::F64x2>(spectrum, twiddles) }
}

/// [`untangle_forward_plain`] in f32, four pairs at a time in AVX2 registers.
///
/// # Safety
/// AVX2 must be present.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub(super) unsafe fn untangle_forward_avx2_f32(
    out: &mut [Complex<f32>],
    twiddles: &[Complex<f32>],
) {
    // SAFETY: AVX2 is present (the caller's).
    unsafe { untangle_forward_lanes::<lanes::F32x4>(out, twiddles) }
}

/// [`tangle_inverse_plain`] in f32, four pairs at a time in AVX2 registers.
///
/// # Safety
/// AVX2 must be present.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub(super) unsafe fn tangle_inverse_avx2_f32(
    spectrum: &mut [Complex<f32>],
    twiddles: &[Complex<f32>],
) {
    // SAFETY: AVX2 is present (the caller's).
    unsafe { tangle_inverse_lanes::<lanes::F32x4>(spectrum, twiddles) }
}
