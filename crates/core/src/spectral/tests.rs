use super::*;
use std::f64::consts::PI;

/// Naive 2-D DFT of a real field, returned in this module's kx-major half layout.
fn naive_half_dft(field: &[f64], n: usize) -> Vec<Complex64> {
    let h = n / 2 + 1;
    let mut out = vec![Complex64::new(0.0, 0.0); h * n];
    for kx in 0..h {
        for ky in 0..n {
            let mut acc = Complex64::new(0.0, 0.0);
            for iy in 0..n {
                for ix in 0..n {
                    let phase = -2.0 * PI * ((kx * ix + ky * iy) % n) as f64 / n as f64;
                    acc += field[iy * n + ix] * Complex64::new(phase.cos(), phase.sin());
                }
            }
            out[kx * n + ky] = acc;
        }
    }
    out
}

/// The per-thread working rows are taken again by a transform started from inside a
/// `produce` callback (on a one-thread pool every nested task runs on the same thread):
/// the nested call gets buffers of its own, and both results equal the same transforms
/// run one after the other.
#[test]
fn a_transform_nested_in_a_callback_gets_its_own_working_rows() {
    let n = 24;
    let fft = Fft2::new(n);
    let (a, b) = (
        pseudo_random_field(n),
        pseudo_random_field(n)
            .iter()
            .map(|v| v * v)
            .collect::<Vec<_>>(),
    );
    let mut scratch = fft.make_scratch();
    let (mut expected_a, mut expected_b) = (fft.make_spectrum(), fft.make_spectrum());
    fft.forward(&a, &mut expected_a, &mut scratch);
    fft.forward(&b, &mut expected_b, &mut scratch);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let nested = std::sync::Mutex::new((fft.make_scratch(), fft.make_spectrum(), 0usize));
    let mut got_a = fft.make_spectrum();
    pool.install(|| {
        let block_len = fft.rows_per_block() * n;
        fft.forward_rows(
            a.par_chunks(block_len),
            |rows: &mut &[f64], r, buf| {
                let mut guard = nested.lock().unwrap();
                let (inner_scratch, inner_out, calls) = &mut *guard;
                fft.forward(&b, inner_out, inner_scratch);
                *calls += 1;
                buf.copy_from_slice(&rows[r * n..(r + 1) * n]);
            },
            &mut got_a,
            &mut scratch,
        );
    });
    let (_, got_b, calls) = nested.into_inner().unwrap();
    assert_eq!(calls, n, "one nested transform per row");
    assert_eq!(got_a, expected_a);
    assert_eq!(got_b, expected_b);
}

/// The column gather and scatter of the fused convolution move exactly the values of
/// columns `kx0 ..` (the AVX path for full groups, of four in f64 and eight in f32, and the
/// plain loop for the last, narrower one), and scattering back what was gathered restores
/// the array.
#[test]
fn column_gather_and_scatter_move_the_right_values() {
    gather_and_scatter::<f64>();
    gather_and_scatter::<f32>();
}

/// The line transpose for any count of lines (the AVX path moves two lines at a time in f64
/// and four in f32, and leaves the rest to the plain loop), and strides that are not the
/// count: a full band ([`Real::GATHER`] values) out of lines `stride` apart and back.
#[test]
fn line_transpose_handles_odd_counts_and_any_stride() {
    fn check<T: Real>() {
        for (count, src_stride, dst_stride) in
            [(1, 8, 1), (6, 9, 7), (7, 9, 8), (8, 8, 11), (513, 10, 513)]
        {
            let src: Vec<Complex<T>> = (0..count * src_stride)
                .map(|i| Complex::new(T::narrow(i as f64), T::narrow(0.5 - i as f64)))
                .collect();
            let nan = T::narrow(f64::NAN);
            let mut dst = vec![Complex::new(nan, nan); T::GATHER * dst_stride];
            // SAFETY: count lines of src_stride ≥ GATHER values; GATHER lines of dst_stride
            // ≥ count values.
            unsafe {
                T::gather_lines(
                    src.as_ptr(),
                    src_stride,
                    count,
                    T::GATHER,
                    dst.as_mut_ptr(),
                    dst_stride,
                )
            };
            for i in 0..count {
                for j in 0..T::GATHER {
                    assert!(
                        dst[j * dst_stride + i] == src[i * src_stride + j],
                        "count {count}"
                    );
                }
            }
            let mut back = vec![Complex::new(nan, nan); count * src_stride];
            // SAFETY: as above, the other way.
            unsafe {
                T::scatter_lines(
                    back.as_mut_ptr(),
                    src_stride,
                    count,
                    T::GATHER,
                    dst.as_ptr(),
                    dst_stride,
                )
            };
            for i in 0..count {
                assert_eq!(
                    back[i * src_stride..i * src_stride + T::GATHER],
                    src[i * src_stride..i * src_stride + T::GATHER]
                );
            }
        }
    }
    check::<f64>();
    check::<f32>();
}

fn gather_and_scatter<T: Real>() {
    for n in [2, 6, 8, 10, 64] {
        let h = n / 2 + 1;
        let original: Vec<Complex<T>> = (0..n * h)
            .map(|i| Complex::new(T::narrow(i as f64), T::narrow(-(i as f64) - 0.5)))
            .collect();
        let mut rows = original.clone();
        for kx0 in (0..h).step_by(T::GATHER) {
            let w = T::GATHER.min(h - kx0);
            let nan = T::narrow(f64::NAN);
            let mut cols = vec![Complex::new(nan, nan); w * n];
            // SAFETY: `rows` holds n·h values and kx0 + w ≤ h.
            unsafe { T::gather_lines(rows.as_ptr().add(kx0), h, n, w, cols.as_mut_ptr(), n) };
            for j in 0..w {
                for r in 0..n {
                    assert!(
                        cols[j * n + r] == original[r * h + kx0 + j],
                        "n {n}, kx {}",
                        kx0 + j
                    );
                }
            }
            for c in cols.iter_mut() {
                *c = -*c;
            }
            // SAFETY: as above.
            unsafe { T::scatter_lines(rows.as_mut_ptr().add(kx0), h, n, w, cols.as_ptr(), n) };
        }
        let negated: Vec<Complex<T>> = original.iter().map(|c| -*c).collect();
        assert_eq!(
            rows, negated,
            "n {n}: every value scattered back once, to its place"
        );
    }
}

fn pseudo_random_field(n: usize) -> Vec<f64> {
    // A fixed, platform-independent sequence (LCG) is enough for a transform test.
    let mut state: u64 = 0x2545_f491_4f6c_dd1d;
    (0..n * n)
        .map(|_| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        })
        .collect()
}

/// Also with empty rows (zeros, some negative zeros), whose row transform is skipped. In
/// both precisions, against the naive DFT in double precision of the same (rounded) input:
/// to 1e-12 of the largest coefficient and a round trip to 1e-14 in f64; in f32 to 1e-5 of
/// each (relative rounding 2⁻²⁴ ≈ 6e-8 per operation, about log₂ n² operations deep).
#[test]
fn forward_matches_naive_dft_and_inverse_round_trips() {
    forward_and_round_trip::<f64>(1e-12, 1e-14);
    forward_and_round_trip::<f32>(1e-5, 1e-5);
}

fn forward_and_round_trip<T: Real>(spectrum_tolerance: f64, round_trip_tolerance: f64) {
    for (n, empty_rows) in [2usize, 4, 6, 8, 16, 30, 64, 96]
        .into_iter()
        .flat_map(|n| [(n, false), (n, true)])
    {
        let mut field = pseudo_random_field(n);
        if empty_rows {
            for (r, row) in field.chunks_exact_mut(n).enumerate() {
                if r % 3 != 2 {
                    row.fill(if r % 2 == 0 { 0.0 } else { -0.0 });
                }
            }
        }
        let input: Vec<T> = field.iter().map(|&v| T::narrow(v)).collect();
        let rounded: Vec<f64> = input.iter().map(|v| v.widen()).collect();
        let fft = Fft2::<T>::new(n);
        let mut scratch = fft.make_scratch();
        let mut spec = fft.make_spectrum();
        fft.forward(&input, &mut spec, &mut scratch);
        let reference = naive_half_dft(&rounded, n);
        let scale = reference.iter().map(|c| c.norm()).fold(1.0, f64::max);
        for (a, b) in spec.iter().zip(&reference) {
            let a = Complex64::new(a.re.widen(), a.im.widen());
            assert!(
                (a - b).norm() <= spectrum_tolerance * scale,
                "n={n}: {a} vs {b}"
            );
        }
        let mut back = vec![T::zero(); n * n];
        fft.inverse(&mut spec, &mut back, &mut scratch);
        let norm = (n * n) as f64;
        for (a, b) in back.iter().zip(&rounded) {
            assert!(
                (a.widen() / norm - b).abs() <= round_trip_tolerance,
                "n={n}: round trip {a:?} vs {b}"
            );
        }
    }
}

#[test]
fn zero_rows_are_recognised_at_every_position() {
    // ±0 anywhere is zero; one non-zero value (smallest subnormal, NaN, negative) at any
    // position, in a full group of eight or in the remainder, is not. In both precisions.
    fn check<T: Real + std::fmt::Display>(bads: [T; 4]) {
        for len in [1usize, 7, 8, 9, 16, 21] {
            let mut row = vec![T::zero(); len];
            assert!(T::all_zero(&row));
            row.iter_mut().step_by(2).for_each(|v| *v = -T::zero());
            assert!(T::all_zero(&row), "−0 counts as zero (len {len})");
            for i in 0..len {
                for bad in bads {
                    let mut r = row.clone();
                    r[i] = bad;
                    assert!(!T::all_zero(&r), "len {len}, value {bad} at {i}");
                }
            }
        }
    }
    check([f64::from_bits(1), f64::NAN, -3.5, f64::INFINITY]);
    check([f32::from_bits(1), f32::NAN, -3.5, f32::INFINITY]);
}

/// One scratch serves plans of both precisions in turn (the solver's K and its f32
/// preconditioner share it): each precision's pair run after the other's in the same scratch
/// gives the same bits as in a scratch of its own, whichever ran first.
#[test]
fn one_scratch_serves_both_precisions() {
    fn pair<T: Real>(fft: &Fft2<T>, input: &[T], scratch: &mut Fft2Scratch) -> Vec<T> {
        let mut spec = fft.make_spectrum();
        fft.forward(input, &mut spec, scratch);
        let mut back = vec![T::zero(); input.len()];
        fft.inverse(&mut spec, &mut back, scratch);
        back
    }
    let n = 30;
    let field = pseudo_random_field(n);
    let single: Vec<f32> = field.iter().map(|&v| v as f32).collect();
    let (fft, fft_single) = (Fft2::new(n), Fft2::<f32>::new(n));
    let expected = pair(&fft, &field, &mut fft.make_scratch());
    let expected_single = pair(&fft_single, &single, &mut fft_single.make_scratch());
    let mut shared = fft.make_scratch();
    assert_eq!(pair(&fft_single, &single, &mut shared), expected_single);
    assert_eq!(pair(&fft, &field, &mut shared), expected);
    assert_eq!(pair(&fft_single, &single, &mut shared), expected_single);
}

/// The row transforms are realfft's algorithm operation for operation: forward (reading the
/// row in place or from a copy, untangled by the plain loop or the AVX one) and inverse give
/// realfft's bits, in both precisions, for lengths with and without a centre value
/// (`n ≡ 0` and `2 mod 4`), with the inner FFT a butterfly (read in place) or a mixed
/// radix (copied).
#[test]
fn row_transforms_give_realfft_bits() {
    fn check<T: Real>(n: usize) {
        let mut real_planner = realfft::RealFftPlanner::<T>::new();
        let (r2c, c2r) = (
            real_planner.plan_fft_forward(n),
            real_planner.plan_fft_inverse(n),
        );
        let rows = RealRows::<T>::new(n, &mut FftPlanner::new());
        let zero = Complex::new(T::zero(), T::zero());
        let mut scratch = vec![
            zero;
            rows.scratch_len()
                .max(r2c.get_scratch_len())
                .max(c2r.get_scratch_len())
        ];
        let row: Vec<T> = (0..n)
            .map(|i| T::narrow((((i * 7919 + n) % 1013) as f64 / 1013.0 - 0.5) * 3.0))
            .collect();
        let bits = |v: &[Complex<T>]| -> Vec<(u64, u64)> {
            v.iter()
                .map(|c| (c.re.widen().to_bits(), c.im.widen().to_bits()))
                .collect()
        };
        let mut expected = vec![zero; n / 2 + 1];
        r2c.process_with_scratch(&mut row.clone(), &mut expected, &mut scratch)
            .unwrap();
        let mut got = vec![zero; n / 2 + 1];
        rows.forward(&mut row.clone(), &mut got, &mut scratch);
        assert_eq!(bits(&got), bits(&expected), "forward, n = {n}");
        if rows.reads_in_place() {
            let mut got = vec![zero; n / 2 + 1];
            rows.forward_from(&row, &mut got, &mut scratch);
            assert_eq!(bits(&got), bits(&expected), "forward in place, n = {n}");
        }
        // The plain untangling, whatever the precision's own path.
        let mut plain = vec![zero; n / 2 + 1];
        let mut packed = row.clone();
        // SAFETY: n values of T are n/2 complex values.
        let packed = unsafe {
            std::slice::from_raw_parts_mut(packed.as_mut_ptr() as *mut Complex<T>, n / 2)
        };
        FftPlanner::<T>::new()
            .plan_fft_forward(n / 2)
            .process_outofplace_with_scratch(packed, &mut plain[..n / 2], &mut scratch);
        halfcomplex::untangle_forward_plain(&mut plain, &rows.forward_twiddles);
        assert_eq!(bits(&plain), bits(&expected), "plain untangling, n = {n}");

        // Inverse of a spectrum with non-zero imaginary parts at both ends: realfft wants
        // them cleared, ours clears them.
        let mut spectrum = expected.clone();
        for (k, v) in spectrum.iter_mut().enumerate() {
            v.im = v.im + T::narrow(0.25 * k as f64);
        }
        spectrum[0].im = T::narrow(1.5);
        let mut cleared = spectrum.clone();
        cleared[0].im = T::zero();
        cleared[n / 2].im = T::zero();
        let mut expected_row = vec![T::zero(); n];
        c2r.process_with_scratch(&mut cleared.clone(), &mut expected_row, &mut scratch)
            .unwrap();
        let mut got_row = vec![T::zero(); n];
        rows.inverse(&mut spectrum.clone(), &mut got_row, &mut scratch);
        let row_bits = |v: &[T]| v.iter().map(|x| x.widen().to_bits()).collect::<Vec<_>>();
        assert_eq!(
            row_bits(&got_row),
            row_bits(&expected_row),
            "inverse, n = {n}"
        );
        let mut tangled = cleared.clone();
        halfcomplex::tangle_inverse_plain(&mut tangled, &rows.inverse_twiddles);
        let mut tangled_native = cleared;
        T::tangle_inverse(&mut tangled_native, &rows.inverse_twiddles);
        assert_eq!(
            bits(&tangled),
            bits(&tangled_native),
            "plain tangling, n = {n}"
        );
    }
    for n in [
        2, 4, 6, 8, 10, 12, 14, 16, 18, 30, 64, 100, 254, 256, 1024, 2048, 4096,
    ] {
        check::<f64>(n);
        check::<f32>(n);
    }
}

/// `forward` reads its rows in place where the inner FFT allows it; the result is the one
/// `forward_rows` gives through a working row (a grid with an all-zero row included).
#[test]
fn forward_in_place_equals_forward_through_rows() {
    let n = 64;
    let fft = Fft2::new(n);
    assert!(fft.rows.reads_in_place(), "n = 64 reads in place");
    let mut field = pseudo_random_field(n);
    field[5 * n..6 * n].fill(0.0);
    let mut scratch = fft.make_scratch();
    let (mut direct, mut through) = (fft.make_spectrum(), fft.make_spectrum());
    fft.forward(&field, &mut direct, &mut scratch);
    fft.forward_rows(
        field.par_chunks(fft.rows_per_block() * n),
        |rows: &mut &[f64], r, buf| buf.copy_from_slice(&rows[r * n..(r + 1) * n]),
        &mut through,
        &mut scratch,
    );
    let bits = |v: &[Complex64]| -> Vec<(u64, u64)> {
        v.iter().map(|c| (c.re.to_bits(), c.im.to_bits())).collect()
    };
    assert_eq!(bits(&direct), bits(&through));
}
