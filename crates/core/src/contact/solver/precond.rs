//! The preconditioner `z = P K⁻¹ P g` and the preconditioned direction.

// Lane loops index several fixed-size arrays in lockstep; iterator chains would hide the
// structure the compiler vectorises.
#![allow(clippy::needless_range_loop)]

use rayon::prelude::*;

use super::rows::{avx2_dispatch, lanes, lanes_f32, padded, padded_f32, LANES};
use super::Solver;

impl Solver<'_> {
    /// The preconditioned gradient `z = P K⁻¹ P g` on the free set
    /// `F = {p > 0} ∪ {p = 0, g < 0}` (the contact set and the nodes that interpenetrate;
    /// `g = u − h − level`, `level` the mean of `u − h` over the contact set; `P`: zero off
    /// F, centred on F). The input pass reads `p`, `w` and `t`: it hands `g` on F (in single
    /// precision) to the transform, marks F in `z` (NaN off it) and sums `|F|`, `Σ g`,
    /// `Σ g t_old` and `Σ t_old` over F; `⟨g, K⁻¹ g⟩` is Parseval's sum inside the
    /// transform. The output pass reads the marks alone: it stores `K⁻¹ P g` on F as its
    /// rows leave the inverse FFT, and sums it. The centring is left to the direction pass,
    /// which subtracts the mean. Summed in a fixed order (four lanes per block, then the
    /// blocks in order), so bit-identical whatever the number of threads.
    pub(super) fn precondition(&mut self, level: f64) -> PreconditionSums {
        let (n, chunk) = (self.op.grid().n(), self.chunk);
        let produce = self
            .pressure
            .par_chunks(chunk)
            .zip(self.separation.par_chunks(chunk))
            .zip(self.direction.par_chunks(chunk))
            .zip(self.preconditioned.par_chunks_mut(chunk))
            .zip(self.precondition_acc.par_iter_mut());
        let g_dot_kg = self.op.start_rows_inverse(
            produce,
            |((((pc, wc), tc), zc), acc), r, row| {
                if r == 0 {
                    **acc = [[0.0; LANES]; 5];
                }
                let at = r * n..(r + 1) * n;
                dispatch_precondition_input(
                    level,
                    row,
                    &mut zc[at.clone()],
                    &pc[at.clone()],
                    &wc[at.clone()],
                    &tc[at],
                    acc,
                );
            },
            &mut self.ws,
        );
        self.op.finish_rows_inverse(
            self.preconditioned
                .par_chunks_mut(chunk)
                .zip(self.precondition_acc.par_iter_mut()),
            |(zc, acc), r, row| {
                let at = r * n..(r + 1) * n;
                dispatch_precondition_output(row, &mut zc[at], &mut acc[4]);
            },
            &mut self.ws,
        );
        let mut sums = [0.0; 5];
        for acc in &self.precondition_acc {
            for (s, lanes) in sums.iter_mut().zip(acc) {
                *s += lanes.iter().sum::<f64>();
            }
        }
        let [count, sg, sgt, st, sz] = sums;
        let (z_mean, t_mean) = if count > 0.0 {
            (sz / count, st / count)
        } else {
            (0.0, 0.0)
        };
        // Σ_F g (z − z̄) = ⟨g, K⁻¹ g⟩ − z̄ Σ_F g.
        PreconditionSums {
            z_mean,
            g_dot_z: g_dot_kg - z_mean * sg,
            g_dot_t_old: sgt,
            g_sum: sg,
            t_old_mean: t_mean,
        }
    }

    /// [`Self::direction_and_transform`] with the preconditioned gradient:
    /// `t ← (z − z̄_F) + β (t − t̄_F)` on the free set F, 0 elsewhere (`z` raw from
    /// [`Self::precondition`] on F and marked off it, so that F is read from `z` alone;
    /// `z̄_F = z_mean`, `t̄_F = direction_mean`), rounded to single precision and handed to
    /// the forward FFT as it is made. Returns `⟨t, K t⟩`.
    pub(super) fn preconditioned_direction_and_transform(
        &mut self,
        z_mean: f64,
        beta: f64,
        direction_mean: f64,
    ) -> f64 {
        let (n, chunk) = (self.op.grid().n(), self.chunk);
        let blocks = self
            .direction
            .par_chunks_mut(chunk)
            .zip(self.preconditioned.par_chunks(chunk));
        self.op.start_rows(
            blocks,
            |(tc, zc), r, row| {
                let at = r * n..(r + 1) * n;
                dispatch_preconditioned_direction(
                    [z_mean, beta, direction_mean],
                    &mut tc[at.clone()],
                    row,
                    &zc[at],
                );
            },
            &mut self.ws,
        )
    }
}

/// [`precondition_input_row`], with AVX2 intrinsics where the processor has them
/// ([`precondition_input_avx2`]). Same operations in the same order, so the same bits
/// either way.
fn dispatch_precondition_input(
    level: f64,
    o: &mut [f32],
    z: &mut [f32],
    p: &[f64],
    w: &[f64],
    t: &[f32],
    acc: &mut [[f64; LANES]; 5],
) {
    #[cfg(target_arch = "x86_64")]
    if std::is_x86_feature_detected!("avx2") {
        // SAFETY: the processor supports AVX2 (checked just above).
        unsafe { precondition_input_avx2(level, o, z, p, w, t, acc) };
        return;
    }
    precondition_input_row(level, o, z, p, w, t, acc)
}

/// One row of the preconditioner's input: `o = w − level` on the free set F, 0 elsewhere,
/// rounded to single precision; `z` marked (0 on F, NaN off it); `|F|`, `Σ g`, `Σ g t`,
/// `Σ t` over F added to `acc[..4]` (lane `k mod LANES` takes node `k`).
#[inline(always)]
fn precondition_input_row(
    level: f64,
    o: &mut [f32],
    z: &mut [f32],
    p: &[f64],
    w: &[f64],
    t: &[f32],
    acc: &mut [[f64; LANES]; 5],
) {
    let n = p.len();
    let whole = n - n % LANES;
    let mut block = |at: std::ops::Range<usize>, p: [f64; LANES], w: [f64; LANES], t| {
        let t: [f64; LANES] = t;
        for (k, i) in at.enumerate() {
            let on = free(p[k], w[k], level);
            let g = if on { w[k] - level } else { 0.0 };
            o[i] = g as f32;
            z[i] = if on { 0.0 } else { OFF_FREE_SET };
            acc[0][k] += if on { 1.0 } else { 0.0 };
            acc[1][k] += g;
            acc[2][k] += if on { g * t[k] } else { 0.0 };
            acc[3][k] += if on { t[k] } else { 0.0 };
        }
    };
    for i in (0..whole).step_by(LANES) {
        let at = i..i + LANES;
        block(
            at.clone(),
            lanes(&p[at.clone()]),
            lanes(&w[at.clone()]),
            lanes_f32(&t[at]),
        );
    }
    if whole < n {
        // Padding: p = 0 and w = +∞ put the extra lanes off F (and `at` stops at n).
        let at = whole..n;
        block(
            at.clone(),
            padded(&p[at.clone()], 0.0),
            padded(&w[at.clone()], f64::INFINITY),
            padded_f32(&t[at], 0.0),
        );
    }
}

/// [`precondition_input_row`] with AVX2 intrinsics, four nodes (one per accumulator lane)
/// at a time; the tail by the scalar code.
///
/// # Safety
/// AVX2 must be present.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn precondition_input_avx2(
    level: f64,
    o: &mut [f32],
    z: &mut [f32],
    p: &[f64],
    w: &[f64],
    t: &[f32],
    acc: &mut [[f64; LANES]; 5],
) {
    use std::arch::x86_64::*;
    const _: () = assert!(LANES == 4, "one AVX register of f64 per lane block");
    let n = p.len();
    assert!(o.len() == n && z.len() == n && w.len() == n && t.len() == n);
    let whole = n / LANES * LANES;
    let level_v = _mm256_set1_pd(level);
    let zero = _mm256_setzero_pd();
    let one = _mm256_set1_pd(1.0);
    let off = _mm_set1_ps(OFF_FREE_SET);
    let mut count = _mm256_loadu_pd(acc[0].as_ptr());
    let mut sg = _mm256_loadu_pd(acc[1].as_ptr());
    let mut sgt = _mm256_loadu_pd(acc[2].as_ptr());
    let mut st = _mm256_loadu_pd(acc[3].as_ptr());
    for i in (0..whole).step_by(LANES) {
        // SAFETY: i + LANES ≤ whole ≤ n, the length of every slice.
        let (pv, wv, tv) = unsafe {
            (
                _mm256_loadu_pd(p.as_ptr().add(i)),
                _mm256_loadu_pd(w.as_ptr().add(i)),
                _mm256_cvtps_pd(_mm_loadu_ps(t.as_ptr().add(i))),
            )
        };
        // `free`: p > 0 || w < level.
        let on = _mm256_or_pd(
            _mm256_cmp_pd::<_CMP_GT_OQ>(pv, zero),
            _mm256_cmp_pd::<_CMP_LT_OQ>(wv, level_v),
        );
        let g = _mm256_and_pd(on, _mm256_sub_pd(wv, level_v));
        // The mask as four 32-bit lanes: all ones where on.
        let on32 = _mm256_cvtpd_ps(_mm256_and_pd(on, one));
        let on_mask = _mm_cmpeq_ps(on32, _mm_set1_ps(1.0));
        // SAFETY: as for the loads.
        unsafe {
            _mm_storeu_ps(o.as_mut_ptr().add(i), _mm256_cvtpd_ps(g));
            _mm_storeu_ps(z.as_mut_ptr().add(i), _mm_andnot_ps(on_mask, off));
        }
        count = _mm256_add_pd(count, _mm256_and_pd(on, one));
        sg = _mm256_add_pd(sg, g);
        sgt = _mm256_add_pd(sgt, _mm256_and_pd(on, _mm256_mul_pd(g, tv)));
        st = _mm256_add_pd(st, _mm256_and_pd(on, tv));
    }
    _mm256_storeu_pd(acc[0].as_mut_ptr(), count);
    _mm256_storeu_pd(acc[1].as_mut_ptr(), sg);
    _mm256_storeu_pd(acc[2].as_mut_ptr(), sgt);
    _mm256_storeu_pd(acc[3].as_mut_ptr(), st);
    if whole < n {
        let at = whole..n;
        precondition_input_row(
            level,
            &mut o[at.clone()],
            &mut z[at.clone()],
            &p[at.clone()],
            &w[at.clone()],
            &t[at],
            acc,
        );
    }
}

/// [`precondition_output_row`], with AVX2 intrinsics where the processor has them
/// ([`precondition_output_avx2`]). Same operations in the same order, so the same bits
/// either way.
fn dispatch_precondition_output(row: &[f32], z: &mut [f32], acc: &mut [f64; LANES]) {
    #[cfg(target_arch = "x86_64")]
    if std::is_x86_feature_detected!("avx2") {
        // SAFETY: the processor supports AVX2 (checked just above).
        unsafe { precondition_output_avx2(row, z, acc) };
        return;
    }
    precondition_output_row(row, z, acc)
}

/// One row of `K⁻¹ P g` as it leaves the inverse FFT: stored in `z` on the free set F
/// (where the input pass left a number) and left marked off it; its sum over F added to
/// `acc` (lane `k mod LANES` takes node `k`).
#[inline(always)]
fn precondition_output_row(row: &[f32], z: &mut [f32], acc: &mut [f64; LANES]) {
    for (i, (z, &v)) in z.iter_mut().zip(row).enumerate() {
        let on = !z.is_nan();
        *z = if on { v } else { OFF_FREE_SET };
        acc[i % LANES] += if on { v as f64 } else { 0.0 };
    }
}

/// [`precondition_output_row`] with AVX2 intrinsics, four nodes at a time; the tail by the
/// scalar code.
///
/// # Safety
/// AVX2 must be present.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn precondition_output_avx2(row: &[f32], z: &mut [f32], acc: &mut [f64; LANES]) {
    use std::arch::x86_64::*;
    let n = row.len();
    assert!(z.len() == n);
    let whole = n / LANES * LANES;
    let mut sum = _mm256_loadu_pd(acc.as_ptr());
    for i in (0..whole).step_by(LANES) {
        // SAFETY: i + LANES ≤ whole ≤ n, the length of both slices.
        let (v, marks) = unsafe {
            (
                _mm_loadu_ps(row.as_ptr().add(i)),
                _mm_loadu_ps(z.as_ptr().add(i)),
            )
        };
        // On F where the mark is a number (ordered).
        let on = _mm_cmpord_ps(marks, marks);
        // Off F the mark is kept (NaN); on F the value is stored.
        let stored = _mm_blendv_ps(marks, v, on);
        // SAFETY: as for the loads.
        unsafe { _mm_storeu_ps(z.as_mut_ptr().add(i), stored) };
        let on64 = _mm256_castsi256_pd(_mm256_cvtepi32_epi64(_mm_castps_si128(on)));
        sum = _mm256_add_pd(sum, _mm256_and_pd(on64, _mm256_cvtps_pd(v)));
    }
    _mm256_storeu_pd(acc.as_mut_ptr(), sum);
    if whole < n {
        precondition_output_row(&row[whole..], &mut z[whole..], acc);
    }
}

avx2_dispatch! {
    /// One row of the preconditioned direction, with AVX2 where available:
    /// `t ← (z − z̄) + β (t − t̄)` on the free set F (where `z` is a number), 0 elsewhere
    /// (where [`dispatch_precondition_input`] marked it), rounded to single precision and
    /// copied into `row`.
    fn dispatch_preconditioned_direction(
        coefficients: [f64; 3],
        t: &mut [f32],
        row: &mut [f64],
        z: &[f32],
    ) {
        let [z_mean, beta, direction_mean] = coefficients;
        for ((t, o), &z) in t.iter_mut().zip(row.iter_mut()).zip(z) {
            *t = if !z.is_nan() {
                ((z as f64 - z_mean) + beta * (*t as f64 - direction_mean)) as f32
            } else {
                0.0
            };
            *o = *t as f64;
        }
    }
}

/// What `z` holds off the free set: NaN, which no value on F is (the inputs are finite; a
/// non-finite state ends the solve as `Stalled` before a direction is made from it).
const OFF_FREE_SET: f32 = f32::NAN;

/// Membership of the free set `F = {p > 0} ∪ {p = 0, w − level < 0}`: the contact set and
/// the nodes that interpenetrate, whose pressure the next step may raise.
#[inline(always)]
fn free(p: f64, w: f64, level: f64) -> bool {
    p > 0.0 || w < level
}

/// The sums of [`Solver::precondition`] over the free set `F`.
#[derive(Debug, Clone, Copy)]
pub(super) struct PreconditionSums {
    /// Mean of `z` over F.
    pub z_mean: f64,
    /// `⟨g, z − z̄⟩_F`, the preconditioned gradient's norm.
    pub g_dot_z: f64,
    /// `Σ_F g t_old`.
    pub g_dot_t_old: f64,
    /// `Σ_F g`.
    pub g_sum: f64,
    /// Mean of the previous direction over F.
    pub t_old_mean: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A pseudo-random sequence in [−1, 1).
    fn sequence(seed: u64) -> impl FnMut() -> f64 {
        let mut state = seed;
        move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        }
    }

    /// The AVX2 input and output passes (where the processor has them) give the scalar
    /// code's bits: the transform's input row, the marks and values of `z` and every lane of
    /// the sums, on rows with nodes in contact, off contact above and below the level, and a
    /// tail shorter than `LANES`. The input marks exactly F, the output stores the row on F.
    #[test]
    fn vector_passes_match_scalar_bits() {
        for len in [64usize, 39, 3] {
            let mut next = sequence(len as u64);
            let p: Vec<f64> = (0..len)
                .map(|i| if i % 3 == 0 { next().abs() } else { 0.0 })
                .collect();
            // Every third node off contact and above the level (off F), the others at random.
            let w: Vec<f64> = (0..len)
                .map(|i| next() + if i % 3 == 1 { 2.0 } else { 0.0 })
                .collect();
            let t: Vec<f32> = (0..len).map(|_| next() as f32).collect();
            let row: Vec<f32> = (0..len).map(|_| next() as f32).collect();
            let level = 0.1;
            let run = |vector: bool| {
                let (mut o, mut z) = (vec![0.0f32; len], vec![0.0f32; len]);
                let mut acc = [[0.5; LANES]; 5];
                if vector {
                    dispatch_precondition_input(level, &mut o, &mut z, &p, &w, &t, &mut acc);
                } else {
                    precondition_input_row(level, &mut o, &mut z, &p, &w, &t, &mut acc);
                }
                let marks = z.clone();
                if vector {
                    dispatch_precondition_output(&row, &mut z, &mut acc[4]);
                } else {
                    precondition_output_row(&row, &mut z, &mut acc[4]);
                }
                let bits32 = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                let acc_bits: Vec<u64> = acc.iter().flatten().map(|v| v.to_bits()).collect();
                (bits32(&o), bits32(&marks), bits32(&z), acc_bits)
            };
            let (scalar, vector) = (run(false), run(true));
            for i in 0..len {
                let on = free(p[i], w[i], level);
                let mark = f32::from_bits(scalar.1[i]);
                assert_eq!(
                    mark.is_nan(),
                    !on,
                    "node {i}: the mark is NaN exactly off F"
                );
                let z = f32::from_bits(scalar.2[i]);
                if on {
                    assert_eq!(z, row[i], "node {i}: z on F is the transform's value");
                    assert_eq!(f32::from_bits(scalar.0[i]), (w[i] - level) as f32);
                } else {
                    assert!(z.is_nan() && scalar.0[i] == 0, "node {i}: off F");
                }
            }
            let on = (0..len).filter(|&i| free(p[i], w[i], level)).count();
            assert!(on > 0 && on < len, "the row must have nodes on and off F");
            assert_eq!(scalar, vector, "len {len}");
        }
    }
}
