//! The plain line transposes of the column passes and their prefetch hints (no effect on
//! results): what both precisions share.

use rustfft::num_complex::Complex;

/// How many rows ahead the column gather of [`super::Fft2::convolve_start`] prefetches.
pub(super) const PREFETCH_ROWS: usize = 16;

/// A hint that the cache line holding `at` will be read soon (no effect on results; a
/// no-op off x86-64).
#[inline(always)]
pub(super) fn prefetch<T>(at: *const Complex<T>) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch never faults, whatever the address.
    unsafe {
        std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(at as *const i8);
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = at;
}

/// A hint that the real row `row` will be read soon, one prefetch per cache line.
#[inline(always)]
pub(super) fn prefetch_row<T>(row: &[T]) {
    let step = 64 / std::mem::size_of::<T>();
    for i in (0..row.len()).step_by(step) {
        prefetch(row[i..].as_ptr() as *const Complex<T>);
    }
}

/// Prefetch the source line [`PREFETCH_ROWS`] ahead of line `i` (lines are more than a
/// 4 KiB page apart from 512² on in f64, which the hardware prefetchers do not follow).
#[inline(always)]
pub(super) fn prefetch_ahead<T>(
    src: *const Complex<T>,
    stride: usize,
    count: usize,
    width: usize,
    i: usize,
) {
    if i + PREFETCH_ROWS < count {
        prefetch(src.wrapping_add((i + PREFETCH_ROWS) * stride));
        prefetch(src.wrapping_add((i + PREFETCH_ROWS) * stride + width - 1));
    }
}

/// [`super::Real::gather_lines`] one value at a time, from line `first` on.
///
/// # Safety
/// As for [`super::Real::gather_lines`].
pub(super) unsafe fn gather_plain<T: Copy>(
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

/// [`super::Real::scatter_lines`] one value at a time, from line `first` on.
///
/// # Safety
/// As for [`super::Real::scatter_lines`].
pub(super) unsafe fn scatter_plain<T: Copy>(
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
