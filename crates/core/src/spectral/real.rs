//! The two precisions of [`super::Fft2`]: `f64` (every transform of the pipeline) and `f32`
//! (the contact solver's preconditioner, where single precision costs no iterations and
//! about 0.6 of the time; docs/BENCHMARKS.md). What differs between them lives here: the
//! per-thread working rows, the zero-row test and the column gather and scatter.

use std::cell::RefCell;

use rustfft::num_complex::{Complex, Complex64};

use super::{prefetch, GATHER, PREFETCH_ROWS};

/// A floating-point type the 2-D transforms run in: `f64` or `f32` (sealed).
pub trait Real: rustfft::FftNum + Default + sealed::Sealed {
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

    /// Copy columns `kx0 .. kx0 + w` of the row-major `n × h` array at `rows` into `cols`
    /// (`w = cols.len() / n ≤ GATHER` columns one after the other), prefetching
    /// [`PREFETCH_ROWS`] rows ahead.
    ///
    /// # Safety
    /// `rows` must be valid for reads of `n·h` values, `kx0 + w ≤ h`, and no other thread
    /// may write those columns meanwhile.
    #[doc(hidden)]
    unsafe fn gather_columns(
        rows: *const Complex<Self>,
        n: usize,
        h: usize,
        kx0: usize,
        cols: &mut [Complex<Self>],
    ) {
        // SAFETY: the caller's bounds.
        unsafe { gather_plain(rows, n, h, kx0, cols) }
    }

    /// The inverse of [`Self::gather_columns`]: `cols` written back into columns `kx0 ..`.
    ///
    /// # Safety
    /// As for [`Self::gather_columns`], with writes.
    #[doc(hidden)]
    unsafe fn scatter_columns(
        rows: *mut Complex<Self>,
        n: usize,
        h: usize,
        kx0: usize,
        cols: &[Complex<Self>],
    ) {
        // SAFETY: the caller's bounds.
        unsafe { scatter_plain(rows, n, h, kx0, cols) }
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

    /// A group of four columns (one 64-byte line per row) is moved two rows at a time in
    /// 256-bit registers where the processor has AVX; the values moved are the same either
    /// way.
    unsafe fn gather_columns(
        rows: *const Complex64,
        n: usize,
        h: usize,
        kx0: usize,
        cols: &mut [Complex64],
    ) {
        #[cfg(target_arch = "x86_64")]
        if cols.len() == GATHER * n && n.is_multiple_of(2) && std::is_x86_feature_detected!("avx") {
            // SAFETY: AVX is present (checked); the bounds are the caller's.
            unsafe { gather4_avx(rows, n, h, kx0, cols) };
            return;
        }
        // SAFETY: the caller's bounds.
        unsafe { gather_plain(rows, n, h, kx0, cols) }
    }

    unsafe fn scatter_columns(
        rows: *mut Complex64,
        n: usize,
        h: usize,
        kx0: usize,
        cols: &[Complex64],
    ) {
        #[cfg(target_arch = "x86_64")]
        if cols.len() == GATHER * n && n.is_multiple_of(2) && std::is_x86_feature_detected!("avx") {
            // SAFETY: AVX is present (checked); the bounds are the caller's.
            unsafe { scatter4_avx(rows, h, kx0, cols) };
            return;
        }
        // SAFETY: the caller's bounds.
        unsafe { scatter_plain(rows, n, h, kx0, cols) }
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

    #[inline(always)]
    fn magnitude_bits(self) -> u64 {
        u64::from(self.to_bits() << 1)
    }
}

/// Prefetch the gather's rows [`PREFETCH_ROWS`] ahead of row `r`: rows are `h` complex
/// values apart (more than a 4 KiB page from 512² on in f64), which the hardware
/// prefetchers do not follow.
#[inline(always)]
fn prefetch_ahead<T>(rows: *const Complex<T>, n: usize, h: usize, kx0: usize, w: usize, r: usize) {
    if r + PREFETCH_ROWS < n {
        prefetch(rows.wrapping_add((r + PREFETCH_ROWS) * h + kx0));
        prefetch(rows.wrapping_add((r + PREFETCH_ROWS) * h + kx0 + w - 1));
    }
}

/// [`Real::gather_columns`], one value at a time.
///
/// # Safety
/// As for [`Real::gather_columns`].
unsafe fn gather_plain<T: Copy>(
    rows: *const Complex<T>,
    n: usize,
    h: usize,
    kx0: usize,
    cols: &mut [Complex<T>],
) {
    let w = cols.len() / n;
    for r in 0..n {
        prefetch_ahead(rows, n, h, kx0, w, r);
        for j in 0..w {
            // SAFETY: `r·h + kx0 + j < n·h` (the caller's bounds).
            cols[j * n + r] = unsafe { rows.add(r * h + kx0 + j).read() };
        }
    }
}

/// [`Real::scatter_columns`], one value at a time.
///
/// # Safety
/// As for [`Real::scatter_columns`].
unsafe fn scatter_plain<T: Copy>(
    rows: *mut Complex<T>,
    n: usize,
    h: usize,
    kx0: usize,
    cols: &[Complex<T>],
) {
    let w = cols.len() / n;
    for r in 0..n {
        for j in 0..w {
            // SAFETY: `r·h + kx0 + j < n·h` (the caller's bounds).
            unsafe { rows.add(r * h + kx0 + j).write(cols[j * n + r]) };
        }
    }
}

/// [`Real::gather_columns`] in f64 for four columns and an even `n`, two rows at a time: each row's four
/// values are two 256-bit loads, regrouped by column with 128-bit lane permutes.
///
/// # Safety
/// AVX must be present; the bounds of [`Real::gather_columns`].
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn gather4_avx(
    rows: *const Complex64,
    n: usize,
    h: usize,
    kx0: usize,
    cols: &mut [Complex64],
) {
    use std::arch::x86_64::{_mm256_loadu_pd, _mm256_permute2f128_pd, _mm256_storeu_pd};
    let c = cols.as_mut_ptr() as *mut f64;
    for r in (0..n).step_by(2) {
        prefetch_ahead(rows, n, h, kx0, GATHER, r);
        prefetch_ahead(rows, n, h, kx0, GATHER, r + 1);
        // SAFETY: rows r and r + 1 < n, columns kx0..kx0 + 4 ≤ h (the caller's bounds);
        // column j's values r, r + 1 are at 2(j·n + r) doubles in `cols`.
        unsafe {
            let a = rows.add(r * h + kx0) as *const f64;
            let b = rows.add((r + 1) * h + kx0) as *const f64;
            let (a01, a23) = (_mm256_loadu_pd(a), _mm256_loadu_pd(a.add(4)));
            let (b01, b23) = (_mm256_loadu_pd(b), _mm256_loadu_pd(b.add(4)));
            _mm256_storeu_pd(c.add(2 * r), _mm256_permute2f128_pd::<0x20>(a01, b01));
            _mm256_storeu_pd(c.add(2 * (n + r)), _mm256_permute2f128_pd::<0x31>(a01, b01));
            _mm256_storeu_pd(
                c.add(2 * (2 * n + r)),
                _mm256_permute2f128_pd::<0x20>(a23, b23),
            );
            _mm256_storeu_pd(
                c.add(2 * (3 * n + r)),
                _mm256_permute2f128_pd::<0x31>(a23, b23),
            );
        }
    }
}

/// [`Real::scatter_columns`] in f64 for four columns and an even `n`, two rows at a time.
///
/// # Safety
/// AVX must be present; the bounds of [`Real::scatter_columns`].
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn scatter4_avx(rows: *mut Complex64, h: usize, kx0: usize, cols: &[Complex64]) {
    use std::arch::x86_64::{_mm256_loadu_pd, _mm256_permute2f128_pd, _mm256_storeu_pd};
    let n = cols.len() / GATHER;
    let c = cols.as_ptr() as *const f64;
    for r in (0..n).step_by(2) {
        // SAFETY: as in `gather4_avx`.
        unsafe {
            let c0 = _mm256_loadu_pd(c.add(2 * r));
            let c1 = _mm256_loadu_pd(c.add(2 * (n + r)));
            let c2 = _mm256_loadu_pd(c.add(2 * (2 * n + r)));
            let c3 = _mm256_loadu_pd(c.add(2 * (3 * n + r)));
            let a = rows.add(r * h + kx0) as *mut f64;
            let b = rows.add((r + 1) * h + kx0) as *mut f64;
            _mm256_storeu_pd(a, _mm256_permute2f128_pd::<0x20>(c0, c1));
            _mm256_storeu_pd(a.add(4), _mm256_permute2f128_pd::<0x20>(c2, c3));
            _mm256_storeu_pd(b, _mm256_permute2f128_pd::<0x31>(c0, c1));
            _mm256_storeu_pd(b.add(4), _mm256_permute2f128_pd::<0x31>(c2, c3));
        }
    }
}
