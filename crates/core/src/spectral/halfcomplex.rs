//! The 1-D real transforms along the rows of [`super::Fft2`]: a real row of even length `n`
//! is read as `n/2` complex values, transformed by a complex FFT of length `n/2` (rustfft)
//! and untangled into the `n/2 + 1` values of its half spectrum; the inverse tangles the
//! half spectrum first. This is realfft's algorithm, operation for operation (the same
//! twiddles, products and sums in the same order, so the results are bit-identical to
//! realfft's; a test checks it), with two differences that make the rows pass cheaper:
//! - where the inner FFT reads its input directly (rustfft's butterflies, i.e. `n ≤ 1024`
//!   in f64), the forward transform reads the caller's row without copying it first;
//! - in f64 the untangling and tangling passes run two values at a time in 256-bit
//!   registers where the processor has AVX (the same operations; [`super::Real`]).

use std::sync::Arc;

use rustfft::{num_complex::Complex, Fft, FftPlanner};

use super::Real;

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
    /// `row` left unchanged. Only where [`Self::reads_in_place`].
    pub(super) fn forward_from(
        &self,
        row: &[T],
        out: &mut [Complex<T>],
        scratch: &mut [Complex<T>],
    ) {
        debug_assert!(self.reads_in_place);
        let (n, h) = (self.n, self.n / 2);
        assert!(row.len() == n && out.len() == h + 1, "row lengths");
        // SAFETY: `row` holds n = 2h values of T; Complex<T> is two T's (repr(C)), with
        // T's alignment.
        let packed = unsafe { std::slice::from_raw_parts(row.as_ptr() as *const Complex<T>, h) };
        self.forward
            .process_immutable_with_scratch(packed, &mut out[..h], scratch);
        T::untangle_forward(out, &self.forward_twiddles);
    }

    /// Forward transform of the real row `row` (length `n`) into `out` (`n/2 + 1` values);
    /// `row` is used as working memory and holds garbage afterwards.
    pub(super) fn forward(
        &self,
        row: &mut [T],
        out: &mut [Complex<T>],
        scratch: &mut [Complex<T>],
    ) {
        let (n, h) = (self.n, self.n / 2);
        assert!(row.len() == n && out.len() == h + 1, "row lengths");
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
    let m = out.len() - 1;
    let first = out[0];
    out[0] = Complex::new(first.re + first.im, T::zero());
    out[m] = Complex::new(first.re - first.im, T::zero());
    for (k, &tw) in (1..).zip(twiddles) {
        untangle_pair(out, k, m - k, tw);
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
    let m = spectrum.len() - 1;
    let (first, last) = (spectrum[0], spectrum[m]);
    let (sum, diff) = (first + last, first - last);
    spectrum[0] = Complex::new(sum.re - sum.im, diff.re - diff.im);
    for (k, &tw) in (1..).zip(twiddles) {
        tangle_pair(spectrum, k, m - k, tw);
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

/// Pairs `k, k + 1` of the f64 untangling or tangling, loaded in 256-bit registers: the
/// values `k, k + 1`, their mirrors `m − k, m − k − 1` (in that order), and the products of
/// the twiddles shared by both loops. Returns `(sum, diff, twiddled_real, twiddled_imag)`,
/// two complex values each, as [`untangle_pair`] and [`tangle_pair`] compute them.
///
/// # Safety
/// AVX must be present; values `k − 1 .. m − k + 1` of `p` and twiddles `k − 1, k` of `t`
/// must be valid, and `k + 1 < m − k − 1`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
#[inline]
unsafe fn load_pairs(
    p: *const f64,
    t: *const f64,
    m: usize,
    k: usize,
) -> [std::arch::x86_64::__m256d; 4] {
    use std::arch::x86_64::*;
    // SAFETY: the caller's bounds.
    unsafe {
        let a = _mm256_loadu_pd(p.add(2 * k));
        let b = _mm256_loadu_pd(p.add(2 * (m - k - 1)));
        let b = _mm256_permute2f128_pd::<0x01>(b, b);
        let tw = _mm256_loadu_pd(t.add(2 * (k - 1)));
        let (sum, diff) = (_mm256_add_pd(a, b), _mm256_sub_pd(a, b));
        let (tw_re, tw_im) = (_mm256_movedup_pd(tw), _mm256_permute_pd::<0b1111>(tw));
        let (sum_im, diff_re) = (_mm256_permute_pd::<0b1111>(sum), _mm256_movedup_pd(diff));
        let twiddled_real =
            _mm256_add_pd(_mm256_mul_pd(sum_im, tw_re), _mm256_mul_pd(diff_re, tw_im));
        let twiddled_imag =
            _mm256_sub_pd(_mm256_mul_pd(sum_im, tw_im), _mm256_mul_pd(diff_re, tw_re));
        [sum, diff, twiddled_real, twiddled_imag]
    }
}

/// Store pairs `k, k + 1` of the f64 untangling or tangling: the real parts from `*_re`,
/// the imaginary parts from `*_im`, `low` at `k, k + 1` and `high` at `m − k, m − k − 1`.
///
/// # Safety
/// As for [`load_pairs`], with writes.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
#[inline]
unsafe fn store_pairs(
    p: *mut f64,
    m: usize,
    k: usize,
    [low_re, low_im, high_re, high_im]: [std::arch::x86_64::__m256d; 4],
) {
    use std::arch::x86_64::*;
    let low = _mm256_blend_pd::<0b1010>(low_re, low_im);
    let high = _mm256_blend_pd::<0b1010>(high_re, high_im);
    // SAFETY: the caller's bounds.
    unsafe {
        _mm256_storeu_pd(p.add(2 * k), low);
        _mm256_storeu_pd(
            p.add(2 * (m - k - 1)),
            _mm256_permute2f128_pd::<0x01>(high, high),
        );
    }
}

/// [`untangle_forward_plain`] in f64, pairs `k, k + 1` at a time in 256-bit registers (the
/// same operations in the same order).
///
/// # Safety
/// AVX must be present.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
pub(super) unsafe fn untangle_forward_avx(out: &mut [Complex<f64>], twiddles: &[Complex<f64>]) {
    use std::arch::x86_64::*;
    let m = out.len() - 1;
    let pairs = twiddles.len();
    assert!(
        2 * pairs < m || pairs == 0,
        "one twiddle per pair below the middle"
    );
    let first = out[0];
    out[0] = Complex::new(first.re + first.im, 0.0);
    out[m] = Complex::new(first.re - first.im, 0.0);
    let (p, t) = (
        out.as_mut_ptr() as *mut f64,
        twiddles.as_ptr() as *const f64,
    );
    let half = _mm256_set1_pd(0.5);
    let mut k = 1;
    while k < pairs {
        // SAFETY: k + 1 ≤ pairs < m/2, so values k, k + 1 and m − k − 1, m − k lie in `out`
        // and do not overlap; twiddles k − 1 and k lie in `twiddles`.
        unsafe {
            let [sum, diff, twiddled_real, twiddled_imag] = load_pairs(p, t, m, k);
            let half_sum_re = _mm256_mul_pd(half, _mm256_movedup_pd(sum));
            let half_diff_im = _mm256_mul_pd(half, _mm256_permute_pd::<0b1111>(diff));
            store_pairs(
                p,
                m,
                k,
                [
                    _mm256_add_pd(half_sum_re, twiddled_real),
                    _mm256_add_pd(half_diff_im, twiddled_imag),
                    _mm256_sub_pd(half_sum_re, twiddled_real),
                    _mm256_sub_pd(twiddled_imag, half_diff_im),
                ],
            );
        }
        k += 2;
    }
    if k == pairs {
        untangle_pair(out, k, m - k, twiddles[k - 1]);
    }
    if m.is_multiple_of(2) {
        out[m / 2].im = -out[m / 2].im;
    }
}

/// [`tangle_inverse_plain`] in f64, pairs `k, k + 1` at a time in 256-bit registers (the
/// same operations in the same order; `−x − y` as a sign flip then a subtraction).
///
/// # Safety
/// AVX must be present.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
pub(super) unsafe fn tangle_inverse_avx(spectrum: &mut [Complex<f64>], twiddles: &[Complex<f64>]) {
    use std::arch::x86_64::*;
    let m = spectrum.len() - 1;
    let pairs = twiddles.len();
    assert!(
        2 * pairs < m || pairs == 0,
        "one twiddle per pair below the middle"
    );
    let (first, last) = (spectrum[0], spectrum[m]);
    let (sum, diff) = (first + last, first - last);
    spectrum[0] = Complex::new(sum.re - sum.im, diff.re - diff.im);
    let (p, t) = (
        spectrum.as_mut_ptr() as *mut f64,
        twiddles.as_ptr() as *const f64,
    );
    let sign = _mm256_set1_pd(-0.0);
    let mut k = 1;
    while k < pairs {
        // SAFETY: as in `untangle_forward_avx`.
        unsafe {
            let [sum, diff, twiddled_real, twiddled_imag] = load_pairs(p, t, m, k);
            let (sum_re, diff_im) = (_mm256_movedup_pd(sum), _mm256_permute_pd::<0b1111>(diff));
            store_pairs(
                p,
                m,
                k,
                [
                    _mm256_sub_pd(sum_re, twiddled_real),
                    _mm256_sub_pd(diff_im, twiddled_imag),
                    _mm256_add_pd(sum_re, twiddled_real),
                    _mm256_sub_pd(_mm256_xor_pd(twiddled_imag, sign), diff_im),
                ],
            );
        }
        k += 2;
    }
    if k == pairs {
        tangle_pair(spectrum, k, m - k, twiddles[k - 1]);
    }
    if m.is_multiple_of(2) {
        let centre = spectrum[m / 2];
        spectrum[m / 2] = (centre + centre).conj();
    }
}
