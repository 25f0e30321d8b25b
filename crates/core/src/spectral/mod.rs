//! Planned 2-D real-to-complex FFTs on square periodic grids, in double precision
//! (`Fft2`, i.e. `Fft2<f64>`: every transform of the pipeline) or single precision
//! (`Fft2<f32>`: the contact solver's preconditioner; [`Real`]).
//!
//! Conventions (stated once here and in docs/CONVENTIONS.md):
//! - Forward: `H[k] = Σ_j h[j] exp(−2πi j·k/n)`, **not normalised** (as numpy `rfft2` and
//!   rustfft). Inverse: `h[j] = Σ_k H[k] exp(+2πi j·k/n)`, **also not normalised**: a forward
//!   then inverse pair multiplies by `n²`. Callers fold the `1/n²` into their multipliers.
//! - Layout of a [`Spectrum`]: the half spectrum kx ∈ `0..=n/2` (`n/2+1` values) times
//!   ky ∈ `0..n` (wrapped, see [`crate::grid::Grid::wrapped_index`]), stored **kx-major**:
//!   entry `(kx, ky)` at `kx * n + ky`. This is the transpose of numpy's `rfft2` layout and
//!   saves one transpose each way.
//! - Real fields are row-major `n × n` (row = y index `iy`, column = x index `ix`), so the
//!   r2c transform runs along x (contiguous) and kx is the half axis.
//!
//! Plans are built once per grid size ([`Fft2::new`]); the row-transformed data live in a
//! caller-owned [`Fft2Scratch`], and the few rows of working memory each 1-D transform
//! needs in per-thread buffers, allocated at a thread's first transform of that size and
//! reused after, so repeated transforms allocate nothing. Work is spread
//! over the current rayon pool by rows; the result does not depend on the thread count
//! (each 1-D transform is computed identically whatever thread runs it).

use std::sync::Arc;

use rayon::prelude::*;
use rustfft::{num_complex::Complex, num_complex::Complex64, Fft, FftPlanner};

mod halfcomplex;
mod lines;
mod precision;
mod real;
use halfcomplex::RealRows;
use lines::prefetch_row;
pub use precision::Real;
use precision::Work;

/// Upper bound on the number of independent work blocks.
const MAX_BLOCKS: usize = 64;

/// Run `f` with this thread's working buffers: a real row of `real` values, `complex` and
/// `columns` complex values. They are grown (allocated) only when the thread first needs
/// them at this size. Their contents on entry are unspecified; every user overwrites what it
/// reads, so results do not depend on which thread ran. If they are already in use on this
/// thread (a transform started from inside a `produce` or `consume` callback), this call
/// gets buffers of its own.
fn with_work<T: Real, R>(
    real: usize,
    complex: usize,
    columns: usize,
    f: impl FnOnce(&mut [T], &mut [Complex<T>], &mut [Complex<T>]) -> R,
) -> R {
    fn fit<T: Real>(w: &mut Work<T>, real: usize, complex: usize, columns: usize) {
        let zero = Complex::new(T::zero(), T::zero());
        if w.real_row.len() < real {
            w.real_row.resize(real, T::zero());
        }
        if w.complex.len() < complex {
            w.complex.resize(complex, zero);
        }
        if w.columns.len() < columns {
            w.columns.resize(columns, zero);
        }
    }
    T::with_thread_work(|cell| match cell.try_borrow_mut() {
        Ok(mut w) => {
            fit(&mut w, real, complex, columns);
            let w = &mut *w;
            f(
                &mut w.real_row[..real],
                &mut w.complex[..complex],
                &mut w.columns[..columns],
            )
        }
        Err(_) => {
            let mut w = Work::default();
            fit(&mut w, real, complex, columns);
            f(&mut w.real_row, &mut w.complex, &mut w.columns)
        }
    })
}

/// Planned forward and inverse 2-D real FFTs for an `n × n` grid.
pub struct Fft2<T: Real = f64> {
    n: usize,
    /// The real transforms along x.
    rows: RealRows<T>,
    col_forward: Arc<dyn Fft<T>>,
    col_inverse: Arc<dyn Fft<T>>,
    /// Scratch length of the 1-D transforms (the largest of the four plans').
    complex_len: usize,
}

/// Working memory for one [`Fft2`]; reuse it across calls. Its storage is double
/// precision and sized for it, so that one scratch serves the plans of either precision
/// for the same `n` (an `f32` transform uses the first half of the bytes).
pub struct Fft2Scratch {
    n: usize,
    /// Row-transformed data, `n` rows of `n/2+1` (y-major) values of `Complex<T>`, between
    /// the two passes.
    rows: Vec<Complex64>,
}

impl Fft2Scratch {
    /// The row-transformed data as `n (n/2 + 1)` values of `Complex<T>`.
    fn rows_mut<T: Real>(&mut self) -> &mut [Complex<T>] {
        let len = self.n * (self.n / 2 + 1);
        const {
            assert!(
                std::mem::size_of::<Complex<T>>() <= std::mem::size_of::<Complex64>()
                    && std::mem::align_of::<Complex<T>>() <= std::mem::align_of::<Complex64>()
            )
        };
        // SAFETY: the storage holds `len` values of Complex64, at least as large and as
        // aligned as Complex<T> (checked above); T is f32 or f64 (the sealed `Real`), for
        // which every bit pattern is a valid value; the borrow of `self` is held.
        unsafe { std::slice::from_raw_parts_mut(self.rows.as_mut_ptr() as *mut Complex<T>, len) }
    }
}

impl<T: Real> Fft2<T> {
    /// Plan the transforms for an `n × n` grid (`n` even, ≥ 2).
    ///
    /// # Panics
    /// If `n` is odd or below 2 (a [`crate::grid::Grid`] never is).
    pub fn new(n: usize) -> Self {
        assert!(
            n >= 2 && n.is_multiple_of(2),
            "Fft2 needs an even n ≥ 2, got {n}"
        );
        let mut planner = FftPlanner::<T>::new();
        let rows = RealRows::new(n, &mut planner);
        let (col_forward, col_inverse) = (planner.plan_fft_forward(n), planner.plan_fft_inverse(n));
        let complex_len = [
            rows.scratch_len(),
            col_forward.get_inplace_scratch_len(),
            col_inverse.get_inplace_scratch_len(),
        ]
        .into_iter()
        .max()
        .unwrap_or(0)
        .max(1);
        Self {
            n,
            rows,
            col_forward,
            col_inverse,
            complex_len,
        }
    }

    /// Nodes per side.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Length of a half spectrum, `(n/2 + 1) · n`.
    pub fn spectrum_len(&self) -> usize {
        (self.n / 2 + 1) * self.n
    }

    /// A zeroed half spectrum in this plan's layout.
    pub fn make_spectrum(&self) -> Vec<Complex<T>> {
        crate::pages::filled(self.spectrum_len(), Complex::new(T::zero(), T::zero()))
    }

    /// Allocate the scratch these plans need: `(n/2 + 1)·n` complex values (about `n²`
    /// doubles). Each thread of the current rayon pool also gets (here, once) a few rows of
    /// its own (about `11 n` doubles, see [`with_work`]), whatever the number of work blocks;
    /// a thread of another pool allocates them at its first transform.
    pub fn make_scratch(&self) -> Fft2Scratch {
        let n = self.n;
        self.prepare_threads();
        Fft2Scratch {
            n,
            rows: crate::pages::filled(n * (n / 2 + 1), Complex64::new(0.0, 0.0)),
        }
    }

    /// Give every thread of the current rayon pool its working rows for these plans now
    /// (about `11 n` values), so that no thread allocates them during the transforms that
    /// follow (e.g. in a solver's iterations). [`Self::make_scratch`] does this; a plan that
    /// shares another plan's scratch calls it itself.
    pub fn prepare_threads(&self) {
        let n = self.n;
        rayon::broadcast(|_| with_work::<T, _>(n, self.complex_len, T::GATHER * n, |_, _, _| ()));
    }

    /// Groups of [`Real::GATHER`] columns of the half spectrum.
    fn column_groups(n: usize) -> usize {
        (n / 2 + 1).div_ceil(T::GATHER)
    }

    /// Column groups per work block in [`Self::convolve_start`].
    fn groups_per_block(n: usize, blocks: usize) -> usize {
        Self::column_groups(n).div_ceil(blocks)
    }

    /// Rows per work block: the fixed decomposition of a field into
    /// [`Self::block_count`] blocks of `rows_per_block · n` values (the last may be
    /// shorter). It depends on `n` only, never on the thread count, so callers that reduce
    /// per block ([`Self::forward_rows`], [`Self::inverse_rows`]) stay deterministic.
    pub fn rows_per_block(&self) -> usize {
        self.n.div_ceil(self.n.min(MAX_BLOCKS))
    }

    /// Number of work blocks (see [`Self::rows_per_block`]).
    pub fn block_count(&self) -> usize {
        self.n.div_ceil(self.rows_per_block())
    }

    /// Forward transform of the real row-major field `input` (length `n²`) into `output`
    /// (length [`Self::spectrum_len`], kx-major). Not normalised.
    pub fn forward(&self, input: &[T], output: &mut [Complex<T>], scratch: &mut Fft2Scratch) {
        assert_eq!(
            input.len(),
            self.n * self.n,
            "real field must have n² values"
        );
        let n = self.n;
        let block_len = self.rows_per_block() * n;
        if !self.rows.reads_in_place() {
            self.forward_rows(
                input.par_chunks(block_len),
                |rows: &mut &[T], r, buf| buf.copy_from_slice(&rows[r * n..(r + 1) * n]),
                output,
                scratch,
            );
            return;
        }
        // The row transforms read `input` in place (no copy into a working row), the next
        // row prefetched while one is transformed (the inner FFT's first pass reads by
        // strides): the same transforms of the same values as through `forward_rows`.
        self.check(n * n, output.len(), scratch);
        let h = n / 2 + 1;
        let len = self.rows.scratch_len();
        scratch
            .rows_mut::<T>()
            .par_chunks_mut(self.rows_per_block() * h)
            .zip(input.par_chunks(block_len))
            .for_each(|(rows_out, rows_in)| {
                with_work(0, len, 0, |_, complex, _| {
                    for (r, (row_out, row_in)) in rows_out
                        .chunks_exact_mut(h)
                        .zip(rows_in.chunks_exact(n))
                        .enumerate()
                    {
                        if let Some(next) = rows_in.get((r + 1) * n..(r + 2) * n) {
                            prefetch_row(next);
                        }
                        self.rows.forward_from(row_in, row_out, complex);
                    }
                });
            });
        self.forward_columns(output, scratch);
    }

    /// Forward transform of a field produced row by row, so that a pass over other fields
    /// can be fused with the transform's first stage. `blocks` yields one state per work
    /// block (exactly [`Self::block_count`] of them, e.g. fields split with
    /// `par_chunks(rows_per_block · n)`); `produce(state, r, row)` must fill `row` (length
    /// `n`) with row `r` of that block, and is called for `r = 0, 1, …` in order within a
    /// block (blocks run in parallel).
    pub fn forward_rows<S, I, F>(
        &self,
        blocks: I,
        produce: F,
        output: &mut [Complex<T>],
        scratch: &mut Fft2Scratch,
    ) where
        S: Send,
        I: IndexedParallelIterator<Item = S>,
        F: Fn(&mut S, usize, &mut [T]) + Sync,
    {
        let n = self.n;
        self.check(n * n, output.len(), scratch);
        assert_eq!(blocks.len(), self.block_count(), "one state per work block");
        // 1. r2c along x for every row y.
        self.r2c_rows(blocks, produce, scratch);
        // 2. the columns.
        self.forward_columns(output, scratch);
    }

    /// The column pass of a forward transform, from the row-transformed `scratch.rows` into
    /// the kx-major `output`: columns [`Real::GATHER`] at a time, gathered from the rows straight into
    /// their place in the kx-major output (one cache line per row, prefetched), then
    /// transformed along y while in cache. No separate transpose pass: the rows, 16 (n/2 + 1)
    /// bytes apart, are walked once per column group, not once per transpose tile.
    fn forward_columns(&self, output: &mut [Complex<T>], scratch: &mut Fft2Scratch) {
        let (n, h) = (self.n, self.n / 2 + 1);
        let rows = SharedRows(scratch.rows_mut::<T>().as_mut_ptr());
        self.for_each_column_group(output, &self.col_forward, |kx0, cols, complex| {
            // SAFETY: columns kx0.. < h of the rows are only read here, and nothing writes
            // `scratch.rows` during this loop.
            unsafe {
                T::gather_lines(
                    rows.get().add(kx0),
                    h,
                    n,
                    cols.len() / n,
                    cols.as_mut_ptr(),
                    n,
                )
            };
            for col in cols.chunks_exact_mut(n) {
                self.col_forward.process_with_scratch(col, complex);
            }
        });
    }

    /// Run `each(kx0, columns, fft scratch)` on every group of [`Real::GATHER`] columns of the kx-major
    /// `data` (n values per column), the groups split over the fixed work blocks, with the
    /// in-place scratch of `fft` per thread.
    fn for_each_column_group(
        &self,
        data: &mut [Complex<T>],
        fft: &Arc<dyn Fft<T>>,
        each: impl Fn(usize, &mut [Complex<T>], &mut [Complex<T>]) + Sync,
    ) {
        let n = self.n;
        let gpb = Self::groups_per_block(n, self.block_count());
        let len = fft.get_inplace_scratch_len();
        data.par_chunks_mut(gpb * T::GATHER * n)
            .enumerate()
            .for_each(|(b, block)| {
                with_work(0, len, 0, |_, complex, _| {
                    for (g, cols) in block.chunks_mut(T::GATHER * n).enumerate() {
                        each((b * gpb + g) * T::GATHER, cols, complex);
                    }
                });
            });
    }

    /// Inverse transform of the half spectrum `spectrum` into the real field `output`.
    /// Not normalised (the pair multiplies by `n²`). `spectrum` is used as working memory
    /// and holds garbage afterwards. The imaginary parts of the self-conjugate columns
    /// (kx = 0 and kx = n/2) are discarded, i.e. the spectrum is projected onto the
    /// Hermitian (real-field) subspace.
    pub fn inverse(
        &self,
        spectrum: &mut [Complex<T>],
        output: &mut [T],
        scratch: &mut Fft2Scratch,
    ) {
        assert_eq!(
            output.len(),
            self.n * self.n,
            "real field must have n² values"
        );
        let n = self.n;
        let h = n / 2 + 1;
        self.check(n * n, spectrum.len(), scratch);
        self.inverse_columns(spectrum, scratch);
        // c2r straight into the output rows (no row buffer to copy from, unlike
        // `inverse_rows`; the same transform of the same values).
        let rpb = self.rows_per_block();
        let len = self.rows.scratch_len();
        scratch
            .rows_mut::<T>()
            .par_chunks_mut(rpb * h)
            .zip(output.par_chunks_mut(rpb * n))
            .for_each(|(rows_in, rows_out)| {
                with_work(0, len, 0, |_, complex, _| {
                    for (row_in, row_out) in rows_in
                        .chunks_exact_mut(h)
                        .zip(rows_out.chunks_exact_mut(n))
                    {
                        self.rows.inverse(row_in, row_out, complex);
                    }
                });
            });
    }

    /// Inverse transform whose result is handed over row by row instead of stored, so that
    /// a pass over other fields can be fused with the transform's last stage (see
    /// [`Self::forward_rows`] for `blocks`). `consume(state, r, row)` receives row `r`
    /// (length `n`) of the block, in order within a block. Same normalisation and
    /// Hermitian projection as [`Self::inverse`].
    pub fn inverse_rows<S, I, F>(
        &self,
        spectrum: &mut [Complex<T>],
        blocks: I,
        consume: F,
        scratch: &mut Fft2Scratch,
    ) where
        S: Send,
        I: IndexedParallelIterator<Item = S>,
        F: Fn(&mut S, usize, &[T]) + Sync,
    {
        self.check(self.n * self.n, spectrum.len(), scratch);
        assert_eq!(blocks.len(), self.block_count(), "one state per work block");
        // 1. inverse complex FFT along y for every kx, into the rows.
        self.inverse_columns(spectrum, scratch);
        // 2. c2r along x for every row.
        self.c2r_rows(blocks, consume, scratch);
    }

    /// Inverse complex FFT along y of every column kx of `spectrum`, [`Real::GATHER`] columns at a
    /// time, each group scattered into `scratch.rows` while in cache (no separate transpose
    /// pass). `spectrum` holds garbage afterwards.
    fn inverse_columns(&self, spectrum: &mut [Complex<T>], scratch: &mut Fft2Scratch) {
        let n = self.n;
        let h = n / 2 + 1;
        let rows = SharedRows(scratch.rows_mut::<T>().as_mut_ptr());
        self.for_each_column_group(spectrum, &self.col_inverse, |kx0, cols, complex| {
            for col in cols.chunks_exact_mut(n) {
                self.col_inverse.process_with_scratch(col, complex);
            }
            // SAFETY: columns kx0.. < h belong to this group alone, and nothing else
            // touches `scratch.rows` during this loop.
            unsafe {
                T::scatter_lines(rows.get().add(kx0), h, n, cols.len() / n, cols.as_ptr(), n)
            };
        });
    }

    /// First half of a convolution fused with the transforms: the real field is produced
    /// row by row (as in [`Self::forward_rows`]) and transformed along x; then, in place in
    /// the scratch, each group of [`Real::GATHER`] columns `kx` is gathered (one cache line per
    /// row), transformed along y, handed to `column(kx, values)` (the values by wrapped
    /// `ky`, to be multiplied in place by a Fourier multiplier; what it returns is stored in
    /// `column_values[kx]`), transformed back along y while still in cache and written
    /// back. [`Self::convolve_finish`] must follow before `scratch` is used again.
    /// Compared with [`Self::forward`], a multiplier pass and [`Self::inverse`], this does
    /// without the spectrum buffer, a column scatter and gather between the two transforms
    /// and a pass over the spectrum for the multiplier, and gives bit-identical results:
    /// every 1-D transform and product is the same computation on the same values.
    pub fn convolve_start<S, I, F, C>(
        &self,
        blocks: I,
        produce: F,
        column: C,
        column_values: &mut [f64],
        scratch: &mut Fft2Scratch,
    ) where
        S: Send,
        I: IndexedParallelIterator<Item = S>,
        F: Fn(&mut S, usize, &mut [T]) + Sync,
        C: Fn(usize, &mut [Complex<T>]) -> f64 + Sync,
    {
        let n = self.n;
        let h = n / 2 + 1;
        assert_eq!(scratch.n, n, "scratch was made for another grid size");
        assert_eq!(column_values.len(), h, "one value per column kx");
        assert_eq!(blocks.len(), self.block_count(), "one state per work block");
        // 1. r2c along x for every row y.
        self.r2c_rows(blocks, produce, scratch);
        // 2. columns, in place, T::GATHER at a time; block b takes groups b·gpb.. .
        let gpb = Self::groups_per_block(n, self.block_count());
        let rows = SharedRows(scratch.rows_mut::<T>().as_mut_ptr());
        column_values
            .par_chunks_mut(gpb * T::GATHER)
            .enumerate()
            .for_each(|(b, values)| {
                with_work(0, self.complex_len, T::GATHER * n, |_, complex, columns| {
                    for (g, values) in values.chunks_mut(T::GATHER).enumerate() {
                        let kx0 = (b * gpb + g) * T::GATHER;
                        let width = values.len();
                        let cols = &mut columns[..width * n];
                        // SAFETY: columns kx0..kx0 + width (< h) belong to this group
                        // alone, and nothing else touches `scratch.rows` during this loop.
                        unsafe {
                            T::gather_lines(
                                rows.get().add(kx0),
                                h,
                                n,
                                cols.len() / n,
                                cols.as_mut_ptr(),
                                n,
                            )
                        };
                        for (j, col) in cols.chunks_exact_mut(n).enumerate() {
                            let len = self.col_forward.get_inplace_scratch_len();
                            self.col_forward
                                .process_with_scratch(col, &mut complex[..len]);
                            values[j] = column(kx0 + j, col);
                            let len = self.col_inverse.get_inplace_scratch_len();
                            self.col_inverse
                                .process_with_scratch(col, &mut complex[..len]);
                        }
                        // SAFETY: as for the gather above.
                        unsafe {
                            T::scatter_lines(
                                rows.get().add(kx0),
                                h,
                                n,
                                cols.len() / n,
                                cols.as_ptr(),
                                n,
                            )
                        };
                    }
                });
            });
    }

    /// Second half of a convolution started by [`Self::convolve_start`]: c2r along x, each
    /// row of the result handed to `consume` as in [`Self::inverse_rows`] (same
    /// normalisation and Hermitian projection).
    pub fn convolve_finish<S, I, F>(&self, blocks: I, consume: F, scratch: &mut Fft2Scratch)
    where
        S: Send,
        I: IndexedParallelIterator<Item = S>,
        F: Fn(&mut S, usize, &[T]) + Sync,
    {
        assert_eq!(scratch.n, self.n, "scratch was made for another grid size");
        assert_eq!(blocks.len(), self.block_count(), "one state per work block");
        self.c2r_rows(blocks, consume, scratch);
    }

    /// r2c along x of every row made by `produce`, into `scratch.rows`.
    fn r2c_rows<S, I, F>(&self, blocks: I, produce: F, scratch: &mut Fft2Scratch)
    where
        S: Send,
        I: IndexedParallelIterator<Item = S>,
        F: Fn(&mut S, usize, &mut [T]) + Sync,
    {
        let h = self.n / 2 + 1;
        let rpb = self.rows_per_block();
        let len = self.rows.scratch_len();
        scratch
            .rows_mut::<T>()
            .par_chunks_mut(rpb * h)
            .zip(blocks)
            .for_each(|(rows_out, mut state)| {
                with_work(self.n, len, 0, |real_row, complex, _| {
                    for (r, row_out) in rows_out.chunks_exact_mut(h).enumerate() {
                        produce(&mut state, r, real_row);
                        self.rows.forward(real_row, row_out, complex);
                    }
                });
            });
    }

    /// c2r along x for every row of `scratch.rows`, each result row handed to `consume`.
    fn c2r_rows<S, I, F>(&self, blocks: I, consume: F, scratch: &mut Fft2Scratch)
    where
        S: Send,
        I: IndexedParallelIterator<Item = S>,
        F: Fn(&mut S, usize, &[T]) + Sync,
    {
        let h = self.n / 2 + 1;
        let rpb = self.rows_per_block();
        let len = self.rows.scratch_len();
        scratch
            .rows_mut::<T>()
            .par_chunks_mut(rpb * h)
            .zip(blocks)
            .for_each(|(rows_in, mut state)| {
                with_work(self.n, len, 0, |real_row, complex, _| {
                    for (r, row_in) in rows_in.chunks_exact_mut(h).enumerate() {
                        self.rows.inverse(row_in, real_row, complex);
                        consume(&mut state, r, real_row);
                    }
                });
            });
    }

    fn check(&self, real_len: usize, spec_len: usize, scratch: &Fft2Scratch) {
        assert_eq!(real_len, self.n * self.n, "real field must have n² values");
        assert_eq!(
            spec_len,
            self.spectrum_len(),
            "spectrum must have (n/2+1)·n values"
        );
        assert_eq!(scratch.n, self.n, "scratch was made for another grid size");
    }
}

/// The row-transformed data shared by the column tasks of [`Fft2::forward_rows`],
/// [`Fft2::inverse_rows`] and [`Fft2::convolve_start`], each of which reads or writes only its
/// own columns.
struct SharedRows<T>(*mut Complex<T>);

// SAFETY: the tasks access disjoint elements (see `convolve_start`).
unsafe impl<T> Send for SharedRows<T> {}
unsafe impl<T> Sync for SharedRows<T> {}

impl<T> SharedRows<T> {
    /// The pointer (a method, so that closures capture the whole wrapper).
    fn get(&self) -> *mut Complex<T> {
        self.0
    }
}

#[cfg(test)]
mod tests;
