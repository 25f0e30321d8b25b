//! The restricted preconditioner `z = P K⁻¹ P g` (`P`: zero off the free set F, centred on
//! it), its passes, and the preconditioned direction: the part every other preconditioner
//! builds on ([`Restricted::input`], [`Restricted::output`],
//! [`Restricted::transformed_direction`] take the rows a layer changes).

// Lane loops index several fixed-size arrays in lockstep; iterator chains would hide the
// structure the compiler vectorises.
#![allow(clippy::needless_range_loop)]

use rayon::prelude::*;

use super::constraint::Constraint;
#[cfg(target_arch = "x86_64")]
use super::lanes::F64x4;
use super::level::Level;
use super::operator::Operator;
use super::preconditioner::{Coefficients, Fields, PreconditionSums, Preconditioner};
use super::rows::{avx2_dispatch, lanes, padded, LANES};

/// `z = P K⁻¹ P g`: the preconditioned gradient, and the per-block sums of its output pass.
pub(super) struct Restricted {
    /// `K⁻¹ P g` on F, in single precision like the transform that makes it, NaN off F
    /// ([`OFF_FREE_SET`]), so that the direction pass reads F from `z` alone.
    z: Vec<f32>,
    /// Per block: the lane sums of the output pass (see [`Restricted::output`]).
    acc: Vec<[[f64; LANES]; 6]>,
}

impl Restricted {
    /// `z` and the sums for `op`'s grid (n²/2 doubles' worth for `z`).
    pub(super) fn new<O: Operator>(op: &O) -> Self {
        let n = op.grid().n();
        let blocks = n.div_ceil(op.rows_per_block());
        Self {
            z: crate::pages::filled(n * n, 0.0),
            acc: vec![[[0.0; LANES]; 6]; blocks],
        }
    }

    /// Starts the inverse convolution of the preconditioner's input, each row `o` made by
    /// `make(i, o, p, w)` from row `i` of `p` and `w` (`P g` here; a layer's `E g`).
    pub(super) fn input<O: Operator, M>(fields: &mut Fields<'_, O>, make: M)
    where
        M: Fn(usize, &mut [f32], &[f64], &[f64]) + Sync,
    {
        let (n, chunk) = (fields.op.grid().n(), fields.chunk);
        let rows = fields.op.rows_per_block();
        let produce = fields
            .pressure
            .par_chunks(chunk)
            .zip(fields.separation.par_chunks(chunk))
            .enumerate();
        fields.op.start_rows_inverse(
            produce,
            |(b, (pc, wc)), r, row| {
                let at = r * n..(r + 1) * n;
                make(*b * rows + r, row, &pc[at.clone()], &wc[at]);
            },
            fields.ws,
        );
    }

    /// Finishes the inverse convolution: each row of `K⁻¹ x` stored raw in `z` on F (NaN
    /// off it) as it leaves the transform and summed over F in the same pass: `Σ z`, `|F|`,
    /// `Σ g z`, `Σ g`, `Σ g t_old`, `Σ t_old`, returned in that order. The centring is left
    /// to the direction pass, which subtracts the mean. Each row is then handed to
    /// `after(block, r, row, p, w)` with its block's item of `blocks` (a layer's sums off
    /// F). Summed in a fixed order (four lanes per block, then the blocks in order), so
    /// bit-identical whatever the number of threads.
    pub(super) fn output<C: Constraint, O: Operator, B, I, A>(
        &mut self,
        fields: &mut Fields<'_, O>,
        level: Level<C>,
        blocks: I,
        after: A,
    ) -> [f64; 6]
    where
        B: Send,
        I: IndexedParallelIterator<Item = B>,
        A: Fn(&mut B, usize, &[f32], &[f64], &[f64]) + Sync,
    {
        let (n, chunk) = (fields.op.grid().n(), fields.chunk);
        fields.op.finish_rows_inverse(
            self.z
                .par_chunks_mut(chunk)
                .zip(fields.pressure.par_chunks(chunk))
                .zip(fields.separation.par_chunks(chunk))
                .zip(fields.direction.par_chunks(chunk))
                .zip(self.acc.par_iter_mut())
                .zip(blocks),
            |(((((zc, pc), wc), tc), acc), block), r, row| {
                if r == 0 {
                    **acc = [[0.0; LANES]; 6];
                }
                let at = r * n..(r + 1) * n;
                let (p, w) = (&pc[at.clone()], &wc[at.clone()]);
                dispatch_precondition_output(level, row, &mut zc[at.clone()], p, w, &tc[at], acc);
                after(block, r, row, p, w);
            },
            fields.ws,
        );
        let mut sums = [0.0; 6];
        for acc in &self.acc {
            for (s, lanes) in sums.iter_mut().zip(acc) {
                *s += lanes.iter().sum::<f64>();
            }
        }
        sums
    }

    /// The direction made row by row from `z` by `make(i, t, row, z)` (row `i` of `t`
    /// updated and copied into the FFT's input `row`; `z` NaN off F), handed to the forward
    /// FFT of `K t`. Returns `⟨t, K t⟩`.
    pub(super) fn transformed_direction<O: Operator, M>(
        &self,
        fields: &mut Fields<'_, O>,
        make: M,
    ) -> f64
    where
        M: Fn(usize, &mut [f64], &mut [f64], &[f32]) + Sync,
    {
        let (n, chunk) = (fields.op.grid().n(), fields.chunk);
        let rows = fields.op.rows_per_block();
        let blocks = fields
            .direction
            .par_chunks_mut(chunk)
            .zip(self.z.par_chunks(chunk))
            .enumerate();
        fields.op.start_rows(
            blocks,
            |(b, (tc, zc)), r, row| {
                let at = r * n..(r + 1) * n;
                make(*b * rows + r, &mut tc[at.clone()], row, &zc[at]);
            },
            fields.ws,
        )
    }
}

impl<C: Constraint, O: Operator> Preconditioner<C, O> for Restricted {
    fn precondition(&mut self, fields: &mut Fields<'_, O>, level: Level<C>) -> PreconditionSums {
        Self::input(fields, |_, row, p, w| {
            dispatch_precondition_input(level, row, p, w)
        });
        let blocks = (0..self.acc.len()).into_par_iter().map(|_| ());
        let sums = self.output(fields, level, blocks, |_, _, _, _, _| {});
        PreconditionSums::new(sums, 0.0, 0.0)
    }

    fn direction(&mut self, fields: &mut Fields<'_, O>, coefficients: Coefficients) -> f64 {
        self.transformed_direction(fields, |_, t, row, z| {
            dispatch_preconditioned_direction(coefficients, t, row, z)
        })
    }
}

avx2_dispatch! {
    /// One row of the preconditioner's input, with AVX2 where available:
    /// `o = w − level.mean` on the free set F, 0 elsewhere, rounded to single precision.
    fn dispatch_precondition_input<C: Constraint>(level: Level<C>, o: &mut [f32], p: &[f64], w: &[f64]) {
        for ((o, &p), &w) in o.iter_mut().zip(p).zip(w) {
            *o = if level.free(p, w) { (w - level.mean) as f32 } else { 0.0 };
        }
    }
}

avx2_dispatch! {
    /// [`precondition_output_row`], with AVX2 intrinsics where the processor has them
    /// ([`precondition_output_avx2`]: one pass over the row instead of two, the sums kept in
    /// registers). Same operations in the same order, so the same bits either way.
    fn dispatch_precondition_output<C: Constraint> = precondition_output_row / precondition_output_avx2(
        level: Level<C>,
        row: &[f32],
        z: &mut [f32],
        p: &[f64],
        w: &[f64],
        t: &[f64],
        acc: &mut [[f64; LANES]; 6],
    );
}

/// [`precondition_output_row`] with AVX2 intrinsics, four nodes (one per accumulator lane)
/// at a time; the tail by the scalar code.
///
/// # Safety
/// AVX2 must be present (the slices' lengths are checked).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn precondition_output_avx2<C: Constraint>(
    level: Level<C>,
    row: &[f32],
    z: &mut [f32],
    p: &[f64],
    w: &[f64],
    t: &[f64],
    acc: &mut [[f64; LANES]; 6],
) {
    use std::arch::x86_64::*;
    const _: () = assert!(LANES == 4, "one AVX register of f64 per lane block");
    let n = row.len();
    assert!(z.len() == n && p.len() == n && w.len() == n && t.len() == n);
    let whole = n / LANES * LANES;
    let level_v = _mm256_set1_pd(level.mean);
    let entry_v = _mm256_set1_pd(level.entry);
    let zero = _mm256_setzero_pd();
    let one = _mm256_set1_pd(1.0);
    let off = _mm256_set1_pd(OFF_FREE_SET as f64);
    let mut sums = [zero; 6];
    for (s, lanes) in sums.iter_mut().zip(acc.iter()) {
        *s = _mm256_loadu_pd(lanes.as_ptr());
    }
    let [mut sz, mut count, mut sgz, mut sg, mut sgt, mut st] = sums;
    for i in (0..whole).step_by(LANES) {
        // SAFETY: i + LANES ≤ whole ≤ n, the length of every slice.
        let (v, pv, wv, tv) = unsafe {
            (
                _mm256_cvtps_pd(_mm_loadu_ps(row.as_ptr().add(i))),
                _mm256_loadu_pd(p.as_ptr().add(i)),
                _mm256_loadu_pd(w.as_ptr().add(i)),
                _mm256_loadu_pd(t.as_ptr().add(i)),
            )
        };
        // `Level::free`, by the constraint's rule on four lanes.
        // SAFETY: AVX2 is present (this function's contract).
        let (p4, w4) = unsafe { (F64x4::from_raw(pv), F64x4::from_raw(wv)) };
        // SAFETY: as above.
        let (entry4, level4) = unsafe { (F64x4::from_raw(entry_v), F64x4::from_raw(level_v)) };
        let on = level.constraint.free(p4, w4, entry4, level4).raw();
        // z on F (v, exactly the f32 value), NaN off it.
        let stored = _mm256_cvtpd_ps(_mm256_blendv_pd(off, v, on));
        // SAFETY: as for the loads.
        unsafe { _mm_storeu_ps(z.as_mut_ptr().add(i), stored) };
        let g = _mm256_and_pd(on, _mm256_sub_pd(wv, level_v));
        let zk = _mm256_and_pd(on, v);
        sz = _mm256_add_pd(sz, zk);
        count = _mm256_add_pd(count, _mm256_and_pd(on, one));
        sgz = _mm256_add_pd(sgz, _mm256_mul_pd(g, zk));
        sg = _mm256_add_pd(sg, g);
        sgt = _mm256_add_pd(sgt, _mm256_and_pd(on, _mm256_mul_pd(g, tv)));
        st = _mm256_add_pd(st, _mm256_and_pd(on, tv));
    }
    for (lanes, s) in acc.iter_mut().zip([sz, count, sgz, sg, sgt, st]) {
        _mm256_storeu_pd(lanes.as_mut_ptr(), s);
    }
    if whole < n {
        let at = whole..n;
        precondition_output_row(
            level,
            &row[at.clone()],
            &mut z[at.clone()],
            &p[at.clone()],
            &w[at.clone()],
            &t[at],
            acc,
        );
    }
}

/// One row of `K⁻¹ P g` as it leaves the inverse FFT: stored
/// in `z` on the free set F and marked off it (NaN, [`OFF_FREE_SET`]), so that the
/// direction pass needs neither `p` nor `w`; and with `g = w − level.mean`, `Σ z`, `|F|`,
/// `Σ g z`, `Σ g`, `Σ g t`, `Σ t` over F added to `acc` (lane `k mod LANES` takes node `k`).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn precondition_output_row<C: Constraint>(
    level: Level<C>,
    row: &[f32],
    z: &mut [f32],
    p: &[f64],
    w: &[f64],
    t: &[f64],
    acc: &mut [[f64; LANES]; 6],
) {
    for (((z, &v), &p), &w) in z.iter_mut().zip(row).zip(p).zip(w) {
        *z = if level.free(p, w) { v } else { OFF_FREE_SET };
    }
    let n = row.len();
    let whole = n - n % LANES;
    for i in (0..whole).step_by(LANES) {
        let at = i..i + LANES;
        precondition_sums(
            level,
            &widened(&row[at.clone()]),
            &lanes(&p[at.clone()]),
            &lanes(&w[at.clone()]),
            &lanes(&t[at]),
            acc,
        );
    }
    if whole < n {
        // Padding: p = 0 and w = +∞ put the extra lanes off F.
        let at = whole..n;
        precondition_sums(
            level,
            &widened(&row[at.clone()]),
            &padded(&p[at.clone()], 0.0),
            &padded(&w[at.clone()], f64::INFINITY),
            &padded(&t[at], 0.0),
            acc,
        );
    }
}

/// Up to [`LANES`] single-precision values in double precision (exactly), 0 past the end.
#[inline(always)]
fn widened(slice: &[f32]) -> [f64; LANES] {
    let mut out = [0.0; LANES];
    for (o, &v) in out.iter_mut().zip(slice) {
        *o = v as f64;
    }
    out
}

/// [`dispatch_precondition_output`]'s sums for one block of [`LANES`] nodes.
#[inline(always)]
fn precondition_sums<C: Constraint>(
    level: Level<C>,
    z: &[f64; LANES],
    p: &[f64; LANES],
    w: &[f64; LANES],
    t: &[f64; LANES],
    acc: &mut [[f64; LANES]; 6],
) {
    for k in 0..LANES {
        let on = level.free(p[k], w[k]);
        let g = if on { w[k] - level.mean } else { 0.0 };
        let zk = if on { z[k] } else { 0.0 };
        acc[0][k] += zk;
        acc[1][k] += if on { 1.0 } else { 0.0 };
        acc[2][k] += g * zk;
        acc[3][k] += g;
        acc[4][k] += if on { g * t[k] } else { 0.0 };
        acc[5][k] += if on { t[k] } else { 0.0 };
    }
}

avx2_dispatch! {
    /// One row of the preconditioned direction, with AVX2 where available:
    /// `t ← (z − z̄) + β (t − t̄)` on the free set F (where `z` is a number), 0 elsewhere
    /// (where [`dispatch_precondition_output`] marked it), copied into `row`.
    fn dispatch_preconditioned_direction(
        coefficients: [f64; 3],
        t: &mut [f64],
        row: &mut [f64],
        z: &[f32],
    ) {
        let [z_mean, beta, direction_mean] = coefficients;
        for ((t, o), &z) in t.iter_mut().zip(row.iter_mut()).zip(z) {
            *t = if !z.is_nan() {
                (z as f64 - z_mean) + beta * (*t - direction_mean)
            } else {
                0.0
            };
            *o = *t;
        }
    }
}

/// What `z` holds off the free set: NaN, which no value on F is (the inputs are finite; a
/// non-finite state ends the solve as `Stalled` before a direction is made from it).
const OFF_FREE_SET: f32 = f32::NAN;

#[cfg(test)]
mod tests {
    use super::super::test_support::{require_vector_path, sequence};
    use super::*;

    /// The AVX2 output pass (where the processor has it) gives the scalar code's bits: `z`
    /// (values on F, NaN off it) and every lane of the six sums, on rows with nodes in
    /// contact, off contact above and below the level, and a tail shorter than `LANES`.
    #[test]
    fn vector_output_matches_scalar_bits() {
        require_vector_path();
        for len in [64usize, 39, 3] {
            let mut next = sequence(len as u64);
            let row: Vec<f32> = (0..len).map(|_| next() as f32).collect();
            let p: Vec<f64> = (0..len)
                .map(|i| if i % 3 == 0 { next().abs() } else { 0.0 })
                .collect();
            // Every third node off contact and above the level (off F), the others at random.
            let w: Vec<f64> = (0..len)
                .map(|i| next() + if i % 3 == 1 { 2.0 } else { 0.0 })
                .collect();
            let t: Vec<f64> = (0..len).map(|_| next()).collect();
            // An entry threshold below the mean: nodes off contact with w between the two
            // are off F, and g = w − mean on F.
            let level = Level {
                mean: 0.1,
                entry: -0.2,
                constraint: super::super::constraint::NonNegative,
            };
            let run = |vector: bool| {
                let mut z = vec![0.0f32; len];
                let mut acc = [[0.5; LANES]; 6];
                if vector {
                    dispatch_precondition_output(level, &row, &mut z, &p, &w, &t, &mut acc);
                } else {
                    precondition_output_row(level, &row, &mut z, &p, &w, &t, &mut acc);
                }
                let z_bits: Vec<u32> = z.iter().map(|v| v.to_bits()).collect();
                let acc_bits: Vec<u64> = acc.iter().flatten().map(|v| v.to_bits()).collect();
                (z_bits, acc_bits)
            };
            let (scalar, vector) = (run(false), run(true));
            let off = scalar
                .0
                .iter()
                .filter(|&&b| f32::from_bits(b).is_nan())
                .count();
            assert!(off > 0 && off < len, "the row must have nodes on and off F");
            assert_eq!(scalar, vector, "len {len}");
            let between =
                (0..len).filter(|&i| p[i] == 0.0 && w[i] > level.entry && w[i] < level.mean);
            assert!(
                between.clone().count() > 0,
                "no node between the entry and the mean"
            );
            assert!(between
                .into_iter()
                .all(|i| f32::from_bits(scalar.0[i]).is_nan()));
            let sum_g: f64 = (0..len)
                .filter(|&i| p[i] > 0.0 || w[i] < level.entry)
                .map(|i| w[i] - level.mean)
                .sum();
            let lanes_sum: f64 = (0..LANES)
                .map(|l| f64::from_bits(vector.1[3 * LANES + l]) - 0.5)
                .sum();
            assert!(
                (lanes_sum - sum_g).abs() < 1e-12,
                "Σ_F g {lanes_sum} against {sum_g}"
            );
        }
    }
}
