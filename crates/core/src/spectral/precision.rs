//! The precision a 2-D transform runs in, as one sealed trait ([`Real`]: `f64` or `f32`),
//! and the per-thread working rows; its two implementations are in the sibling `real`.

use std::cell::RefCell;

use rustfft::num_complex::Complex;

use super::lines::{gather_plain, scatter_plain};

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
    fn untangle_forward(out: &mut [Complex<Self>], twiddles: &[Complex<Self>]);

    /// The tangling before a row's inverse complex FFT ([`super::halfcomplex`]).
    #[doc(hidden)]
    fn tangle_inverse(spectrum: &mut [Complex<Self>], twiddles: &[Complex<Self>]);

    /// Transpose a band of lines out: `dst[j·dst_stride + i] = src[i·src_stride + j]` for
    /// `i < count`, `j < width` (≤ [`Self::GATHER`]), prefetching [`super::lines::PREFETCH_ROWS`] source
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
