//! The two precisions of [`super::Fft2`]: `f64` (every transform of the pipeline) and `f32`
//! (the contact solver's preconditioner, where single precision costs no iterations and
//! about 0.6 of the time; docs/BENCHMARKS.md). What differs between them lives here: the
//! per-thread working rows, the zero-row test and the column gather and scatter.

use std::cell::RefCell;

use rustfft::num_complex::{Complex, Complex64};

use super::{halfcomplex, prefetch, PREFETCH_ROWS};

/// A floating-point type the 2-D transforms run in: `f64` or `f32` (sealed).
pub trait Real: rustfft::FftNum + Default + sealed::Sealed {
    /// Columns the column passes gather together: one 64-byte cache line of complex values
    /// per row (4 in f64, 8 in f32).
    #[doc(hidden)]
    const GATHER: usize = 64 / (2 * std::mem::size_of::<Self>());

    /// The value in double precision (exact).
    fn widen(self) -> f64;

    /// The nearest value of this type to `v`.
    fn narrow(v: f64) -> Self;

    /// Run `f` with this thread's working rows of this precision.
    #[doc(hidden)]
    fn with_thread_work<R>(f: impl FnOnce(&RefCell<Work<Self>>) -> R) -> R;

    /// The bit pattern without its sign bit (0 exactly for ±0).
    #[doc(hidden)]
    fn magnitude_bits(self) -> u64;

    /// Whether every value of `row` is ±0, scanning eight values at a time (the bit patterns
    /// without their sign bit are OR-ed, which vectorises; an early exit per group).
    #[doc(hidden)]
    fn all_zero(row: &[Self]) -> bool {
        let mut groups = row.chunks_exact(8);
        for group in &mut groups {
            if group.iter().fold(0u64, |acc, v| acc | v.magnitude_bits()) != 0 {
                return false;
            }
        }
        groups.remainder().iter().all(|v| v.magnitude_bits() == 0)
    }

    /// The untangling after a row's forward complex FFT ([`super::halfcomplex`]).
    #[doc(hidden)]
    fn untangle_forward(out: &mut [Complex<Self>], twiddles: &[Complex<Self>]) {
        halfcomplex::untangle_forward_plain(out, twiddles)
    }

    /// The tangling before a row's inverse complex FFT ([`super::halfcomplex`]).
    #[doc(hidden)]
    fn tangle_inverse(spectrum: &mut [Complex<Self>], twiddles: &[Complex<Self>]) {
        halfcomplex::tangle_inverse_plain(spectrum, twiddles)
    }

    /// Transpose a band of lines out: `dst[j·dst_stride + i] = src[i·src_stride + j]` for
    /// `i < count`, `j < width` (≤ [`Self::GATHER`]), prefetching [`PREFETCH_ROWS`] source
    /// lines ahead. The column pass gathers columns `kx0 ..` of the rows this way (`src` at
    /// column `kx0`, stride `n/2 + 1`, `count = n`); the inverse row pass of a pair gathers
    /// rows `y0 ..` of the kx-major spectrum (`src` at `y0`, stride `n`, `count = n/2 + 1`).
    /// A full band goes through [`Self::band_vector`] where it can.
    ///
    /// # Safety
    /// `src` must be valid for reads and `dst` for writes at every index above, the two
    /// must not overlap, and no other thread may write those values meanwhile.
    #[doc(hidden)]
    unsafe fn gather_lines(
        src: *const Complex<Self>,
        src_stride: usize,
        count: usize,
        width: usize,
        dst: *mut Complex<Self>,
        dst_stride: usize,
    ) {
        // SAFETY: the caller's bounds; a gather only reads the lines.
        if width == Self::GATHER
            && unsafe {
                Self::band_vector(src.cast_mut(), src_stride, count, dst, dst_stride, true)
            }
        {
            return;
        }
        // SAFETY: the caller's bounds.
        unsafe { gather_plain(src, src_stride, count, width, dst, dst_stride, 0) }
    }

    /// The inverse of [`Self::gather_lines`]: `dst[i·dst_stride + j] = src[j·src_stride +
    /// i]` for `i < count`, `j < width`.
    ///
    /// # Safety
    /// As for [`Self::gather_lines`].
    #[doc(hidden)]
    unsafe fn scatter_lines(
        dst: *mut Complex<Self>,
        dst_stride: usize,
        count: usize,
        width: usize,
        src: *const Complex<Self>,
        src_stride: usize,
    ) {
        // SAFETY: the caller's bounds; a scatter only reads the band.
        if width == Self::GATHER
            && unsafe {
                Self::band_vector(dst, dst_stride, count, src.cast_mut(), src_stride, false)
            }
        {
            return;
        }
        // SAFETY: the caller's bounds.
        unsafe { scatter_plain(dst, dst_stride, count, width, src, src_stride, 0) }
    }

    /// Move a full band ([`Self::GATHER`] values per line) between `count` lines
    /// `line_stride` apart and the band's [`Self::GATHER`] lines `band_stride` apart, in
    /// vector registers: out of the lines if `gather`, into them otherwise. Returns false,
    /// having moved nothing, where the processor lacks the instructions (the default).
    ///
    /// # Safety
    /// The bounds of [`Self::gather_lines`] (gather) or [`Self::scatter_lines`] (scatter);
    /// only the destination side is written.
    #[doc(hidden)]
    unsafe fn band_vector(
        lines: *mut Complex<Self>,
        line_stride: usize,
        count: usize,
        band: *mut Complex<Self>,
        band_stride: usize,
        gather: bool,
    ) -> bool {
        let _ = (lines, line_stride, count, band, band_stride, gather);
        false
    }
}

mod sealed {
    pub trait Sealed {}
    impl Sealed for f64 {}
    impl Sealed for f32 {}
}

/// Working rows of the 1-D transforms, one set per thread and precision (not per work
/// block: a block's task runs on one thread from start to end, and 64 blocks' worth of rows
/// would cost 11·64·n doubles, more than 2 n² at n = 256).
#[doc(hidden)]
pub struct Work<T> {
    pub(super) real_row: Vec<T>,
    pub(super) complex: Vec<Complex<T>>,
    pub(super) columns: Vec<Complex<T>>,
}

impl<T> Default for Work<T> {
    fn default() -> Self {
        Self {
            real_row: Vec::new(),
            complex: Vec::new(),
            columns: Vec::new(),
        }
    }
}

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

/// Prefetch the source line [`PREFETCH_ROWS`] ahead of line `i` (lines are more than a
/// 4 KiB page apart from 512² on in f64, which the hardware prefetchers do not follow).
#[inline(always)]
fn prefetch_ahead<T>(src: *const Complex<T>, stride: usize, count: usize, width: usize, i: usize) {
    if i + PREFETCH_ROWS < count {
        prefetch(src.wrapping_add((i + PREFETCH_ROWS) * stride));
        prefetch(src.wrapping_add((i + PREFETCH_ROWS) * stride + width - 1));
    }
}

/// [`Real::gather_lines`] one value at a time, from line `first` on.
///
/// # Safety
/// As for [`Real::gather_lines`].
unsafe fn gather_plain<T: Copy>(
    src: *const Complex<T>,
    src_stride: usize,
    count: usize,
    width: usize,
    dst: *mut Complex<T>,
    dst_stride: usize,
    first: usize,
) {
    for i in first..count {
        prefetch_ahead(src, src_stride, count, width, i);
        for j in 0..width {
            // SAFETY: the caller's bounds.
            unsafe {
                dst.add(j * dst_stride + i)
                    .write(src.add(i * src_stride + j).read())
            };
        }
    }
}

/// [`Real::scatter_lines`] one value at a time, from line `first` on.
///
/// # Safety
/// As for [`Real::scatter_lines`].
unsafe fn scatter_plain<T: Copy>(
    dst: *mut Complex<T>,
    dst_stride: usize,
    count: usize,
    width: usize,
    src: *const Complex<T>,
    src_stride: usize,
    first: usize,
) {
    for i in first..count {
        for j in 0..width {
            // SAFETY: the caller's bounds.
            unsafe {
                dst.add(i * dst_stride + j)
                    .write(src.add(j * src_stride + i).read())
            };
        }
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
