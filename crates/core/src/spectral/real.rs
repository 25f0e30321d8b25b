//! The two precisions of [`super::Fft2`]: `f64` (every transform of the pipeline) and `f32`
//! (the contact solver's preconditioner, where single precision costs no iterations and
//! about 0.6 of the time; docs/BENCHMARKS.md). What differs between them lives here: the
//! per-thread working rows, the zero-row test and the column gather and scatter.

use std::cell::RefCell;

use rustfft::num_complex::{Complex, Complex64};

use super::halfcomplex;
use super::lines::{gather_plain, prefetch_ahead, scatter_plain};
use super::precision::{Real, Work};

thread_local! {
    static WORK_F64: RefCell<Work<f64>> = RefCell::new(Work::default());
    static WORK_F32: RefCell<Work<f32>> = RefCell::new(Work::default());
}

impl Real for f64 {
    #[inline(always)]
    fn widen(self) -> f64 {
        self
    }

    #[inline(always)]
    fn narrow(v: f64) -> Self {
        v
    }

    fn with_thread_work<R>(f: impl FnOnce(&RefCell<Work<Self>>) -> R) -> R {
        WORK_F64.with(f)
    }

    #[inline(always)]
    fn magnitude_bits(self) -> u64 {
        self.to_bits() << 1
    }

    /// Two pairs at a time in 256-bit registers where the processor has AVX (the same
    /// operations, so the same values).
    fn untangle_forward(out: &mut [Complex64], twiddles: &[Complex64]) {
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx") {
            // SAFETY: AVX is present (checked).
            unsafe { halfcomplex::untangle_forward_avx(out, twiddles) };
            return;
        }
        halfcomplex::untangle_forward_plain(out, twiddles)
    }

    /// As [`Self::untangle_forward`].
    fn tangle_inverse(spectrum: &mut [Complex64], twiddles: &[Complex64]) {
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx") {
            // SAFETY: AVX is present (checked).
            unsafe { halfcomplex::tangle_inverse_avx(spectrum, twiddles) };
            return;
        }
        halfcomplex::tangle_inverse_plain(spectrum, twiddles)
    }

    /// A band of four (a 64-byte cache line of each line) is moved two lines at a time in 256-bit
    /// registers where the processor has AVX; the values moved are the same either way.
    unsafe fn band_vector(
        lines: *mut Complex64,
        line_stride: usize,
        count: usize,
        band: *mut Complex64,
        band_stride: usize,
        gather: bool,
    ) -> bool {
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx") {
            // SAFETY: AVX is present (checked); the bounds are the caller's.
            unsafe {
                if gather {
                    gather4_avx(lines, line_stride, count, band, band_stride)
                } else {
                    scatter4_avx(lines, line_stride, count, band, band_stride)
                }
            };
            return true;
        }
        let _ = (lines, line_stride, count, band, band_stride, gather);
        false
    }
}

impl Real for f32 {
    #[inline(always)]
    fn widen(self) -> f64 {
        self as f64
    }

    #[inline(always)]
    fn narrow(v: f64) -> Self {
        v as f32
    }

    fn with_thread_work<R>(f: impl FnOnce(&RefCell<Work<Self>>) -> R) -> R {
        WORK_F32.with(f)
    }

    /// Four pairs at a time in 256-bit registers where the processor has AVX2 (the same
    /// operations, so the same values).
    fn untangle_forward(out: &mut [Complex<f32>], twiddles: &[Complex<f32>]) {
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") {
            // SAFETY: AVX2 is present (checked).
            unsafe { halfcomplex::untangle_forward_avx2_f32(out, twiddles) };
            return;
        }
        halfcomplex::untangle_forward_plain(out, twiddles)
    }

    /// As [`Self::untangle_forward`].
    fn tangle_inverse(spectrum: &mut [Complex<f32>], twiddles: &[Complex<f32>]) {
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") {
            // SAFETY: AVX2 is present (checked).
            unsafe { halfcomplex::tangle_inverse_avx2_f32(spectrum, twiddles) };
            return;
        }
        halfcomplex::tangle_inverse_plain(spectrum, twiddles)
    }

    #[inline(always)]
    fn magnitude_bits(self) -> u64 {
        u64::from(self.to_bits() << 1)
    }

    /// A band of eight (a 64-byte cache line of each line) is moved four lines at a time in 256-bit
    /// registers where the processor has AVX; the values moved are the same either way.
    unsafe fn band_vector(
        lines: *mut Complex<f32>,
        line_stride: usize,
        count: usize,
        band: *mut Complex<f32>,
        band_stride: usize,
        gather: bool,
    ) -> bool {
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx") {
            // SAFETY: AVX is present (checked); the bounds are the caller's.
            unsafe { transpose8_avx_f32(lines, line_stride, count, band, band_stride, gather) };
            return true;
        }
        let _ = (lines, line_stride, count, band, band_stride, gather);
        false
    }
}

/// [`Real::gather_lines`] in f64 for a band of four, two source lines at a time: each
/// line's four values are two 256-bit loads, regrouped with 128-bit lane permutes; an odd
/// last line by the plain loop.
///
/// # Safety
/// AVX must be present; the bounds of [`Real::gather_lines`].
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn gather4_avx(
    src: *const Complex64,
    src_stride: usize,
    count: usize,
    dst: *mut Complex64,
    dst_stride: usize,
) {
    use std::arch::x86_64::{_mm256_loadu_pd, _mm256_permute2f128_pd, _mm256_storeu_pd};
    let d = dst as *mut f64;
    let pairs = count / 2 * 2;
    for i in (0..pairs).step_by(2) {
        prefetch_ahead(src, src_stride, count, 4, i);
        prefetch_ahead(src, src_stride, count, 4, i + 1);
        // SAFETY: lines i and i + 1 < count (the caller's bounds); value (i, j) goes to
        // 2(j·dst_stride + i) doubles from `dst`.
        unsafe {
            let a = src.add(i * src_stride) as *const f64;
            let b = src.add((i + 1) * src_stride) as *const f64;
            let (a01, a23) = (_mm256_loadu_pd(a), _mm256_loadu_pd(a.add(4)));
            let (b01, b23) = (_mm256_loadu_pd(b), _mm256_loadu_pd(b.add(4)));
            _mm256_storeu_pd(d.add(2 * i), _mm256_permute2f128_pd::<0x20>(a01, b01));
            _mm256_storeu_pd(
                d.add(2 * (dst_stride + i)),
                _mm256_permute2f128_pd::<0x31>(a01, b01),
            );
            _mm256_storeu_pd(
                d.add(2 * (2 * dst_stride + i)),
                _mm256_permute2f128_pd::<0x20>(a23, b23),
            );
            _mm256_storeu_pd(
                d.add(2 * (3 * dst_stride + i)),
                _mm256_permute2f128_pd::<0x31>(a23, b23),
            );
        }
    }
    // SAFETY: the caller's bounds.
    unsafe { gather_plain(src, src_stride, count, 4, dst, dst_stride, pairs) }
}

/// [`Real::scatter_lines`] in f64 for a band of four, two destination lines at a time; an
/// odd last line by the plain loop.
///
/// # Safety
/// AVX must be present; the bounds of [`Real::scatter_lines`].
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn scatter4_avx(
    dst: *mut Complex64,
    dst_stride: usize,
    count: usize,
    src: *const Complex64,
    src_stride: usize,
) {
    use std::arch::x86_64::{_mm256_loadu_pd, _mm256_permute2f128_pd, _mm256_storeu_pd};
    let c = src as *const f64;
    let pairs = count / 2 * 2;
    for i in (0..pairs).step_by(2) {
        // SAFETY: as in `gather4_avx`.
        unsafe {
            let c0 = _mm256_loadu_pd(c.add(2 * i));
            let c1 = _mm256_loadu_pd(c.add(2 * (src_stride + i)));
            let c2 = _mm256_loadu_pd(c.add(2 * (2 * src_stride + i)));
            let c3 = _mm256_loadu_pd(c.add(2 * (3 * src_stride + i)));
            let a = dst.add(i * dst_stride) as *mut f64;
            let b = dst.add((i + 1) * dst_stride) as *mut f64;
            _mm256_storeu_pd(a, _mm256_permute2f128_pd::<0x20>(c0, c1));
            _mm256_storeu_pd(a.add(4), _mm256_permute2f128_pd::<0x20>(c2, c3));
            _mm256_storeu_pd(b, _mm256_permute2f128_pd::<0x31>(c0, c1));
            _mm256_storeu_pd(b.add(4), _mm256_permute2f128_pd::<0x31>(c2, c3));
        }
    }
    // SAFETY: the caller's bounds.
    unsafe { scatter_plain(dst, dst_stride, count, 4, src, src_stride, pairs) }
}

/// [`Real::band_vector`] in f32: a band of eight, four lines at a time. A complex f32 value
/// is one 64-bit lane, so each 4 × 4 block of values is transposed in 256-bit registers by
/// two rounds of lane shuffles (unpack within 128-bit halves, then exchange the halves); the
/// transpose is its own inverse, so a gather and a scatter differ only in which side is
/// loaded. An incomplete last block goes to the plain loop.
///
/// # Safety
/// AVX must be present; the bounds of [`Real::band_vector`].
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn transpose8_avx_f32(
    lines: *mut Complex<f32>,
    line_stride: usize,
    count: usize,
    band: *mut Complex<f32>,
    band_stride: usize,
    gather: bool,
) {
    use std::arch::x86_64::{
        __m256d, _mm256_loadu_pd, _mm256_permute2f128_pd, _mm256_storeu_pd, _mm256_unpackhi_pd,
        _mm256_unpacklo_pd,
    };
    /// Transpose the 4 × 4 block of 64-bit values whose rows are `r`.
    #[inline(always)]
    unsafe fn block(r: [__m256d; 4]) -> [__m256d; 4] {
        let t0 = _mm256_unpacklo_pd(r[0], r[1]);
        let t1 = _mm256_unpackhi_pd(r[0], r[1]);
        let t2 = _mm256_unpacklo_pd(r[2], r[3]);
        let t3 = _mm256_unpackhi_pd(r[2], r[3]);
        [
            _mm256_permute2f128_pd::<0x20>(t0, t2),
            _mm256_permute2f128_pd::<0x20>(t1, t3),
            _mm256_permute2f128_pd::<0x31>(t0, t2),
            _mm256_permute2f128_pd::<0x31>(t1, t3),
        ]
    }
    const W: usize = 8;
    let quads = count / 4 * 4;
    for i in (0..quads).step_by(4) {
        if gather {
            for k in 0..4 {
                prefetch_ahead(lines, line_stride, count, W, i + k);
            }
        }
        for half in 0..2 {
            // Values half·4.. of lines i..i + 4, and values i..i + 4 of band lines half·4..,
            // as f64 lanes.
            let on_lines: [*mut f64; 4] = std::array::from_fn(|k| {
                lines.wrapping_add((i + k) * line_stride + half * 4) as *mut f64
            });
            let on_band: [*mut f64; 4] = std::array::from_fn(|j| {
                band.wrapping_add((half * 4 + j) * band_stride + i) as *mut f64
            });
            let (from, to) = if gather {
                (on_lines, on_band)
            } else {
                (on_band, on_lines)
            };
            // SAFETY: lines i..i + 4 < count at values < W, band lines < W at values
            // i..i + 4 < count (the caller's bounds); only the destination side is written.
            unsafe {
                let t = block(from.map(|p| _mm256_loadu_pd(p)));
                for (p, v) in to.into_iter().zip(t) {
                    _mm256_storeu_pd(p, v);
                }
            }
        }
    }
    // SAFETY: the caller's bounds.
    unsafe {
        if gather {
            gather_plain(lines, line_stride, count, W, band, band_stride, quads)
        } else {
            scatter_plain(lines, line_stride, count, W, band, band_stride, quads)
        }
    }
}
