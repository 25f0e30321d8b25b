//! The preconditioner `z = P K⁻¹ P g` and the preconditioned direction.

// Lane loops index several fixed-size arrays in lockstep; iterator chains would hide the
// structure the compiler vectorises.
#![allow(clippy::needless_range_loop)]

use rayon::iter::Either;
use rayon::prelude::*;

use super::level::{free, Level};
use super::rows::{avx2_dispatch, lanes, padded, LANES};
use super::Solver;

impl Solver<'_> {
    /// The preconditioned gradient `z = P K⁻¹ P g` on the free set
    /// `F = {p > 0} ∪ {p = 0, u − h < entry}` (the contact set and the nodes that
    /// interpenetrate, [`Level`]; `g = u − h − mean`, `mean` that of `u − h` over the
    /// contact set; `P`: zero off
    /// F, centred on F). Each row of `K⁻¹ P g` is stored raw in `self.preconditioned` as it
    /// leaves the inverse FFT, and summed over F in the same pass: `Σ z`, `|F|`, `Σ g z`,
    /// `Σ g`, `Σ g t_old`, `Σ t_old`. The centring is left to the direction pass, which
    /// subtracts the mean. Summed in a fixed order (four lanes per block, then the blocks
    /// in order), so bit-identical whatever the number of threads. With the free-set
    /// extension (module `extension`) the input is `E g` instead of `P g`, and the values
    /// of `K⁻¹ E g` off F are summed per cell for the correction `Σ γ S D⁻¹ (1 − 1_F) y` that
    /// the direction pass adds on F.
    pub(super) fn precondition(&mut self, level: Level) -> PreconditionSums {
        let (n, chunk) = (self.op.grid().n(), self.chunk);
        let rows = self.op.rows_per_block();
        let mut coarse = self.coarse.take();
        if let Some(c) = coarse.as_mut() {
            c.gather(&self.pressure, &self.separation, level);
        }
        {
            let coarse = coarse.as_ref();
            let produce = self
                .pressure
                .par_chunks(chunk)
                .zip(self.separation.par_chunks(chunk))
                .enumerate();
            self.op.start_rows_inverse(
                produce,
                |(b, (pc, wc)), r, row| {
                    let at = r * n..(r + 1) * n;
                    let (p, w) = (&pc[at.clone()], &wc[at]);
                    match coarse {
                        Some(c) => c.input_row(*b * rows + r, row, p, w, level),
                        None => dispatch_precondition_input(level, row, p, w),
                    }
                },
                &mut self.ws,
            );
        }
        let blocks = self.precondition_acc.len();
        let (extension, off_blocks) = match coarse.as_mut() {
            Some(c) => {
                let (cell, m, bilinear, off) = c.output_parts();
                (
                    Some((cell, m, bilinear)),
                    Either::Left(off.par_iter_mut().map(Some)),
                )
            }
            None => (
                None,
                Either::Right((0..blocks).into_par_iter().map(|_| None)),
            ),
        };
        self.op.finish_rows_inverse(
            self.preconditioned
                .par_chunks_mut(chunk)
                .zip(self.pressure.par_chunks(chunk))
                .zip(self.separation.par_chunks(chunk))
                .zip(self.direction.par_chunks(chunk))
                .zip(self.precondition_acc.par_iter_mut())
                .zip(off_blocks),
            |(((((zc, pc), wc), tc), acc), block), r, row| {
                if r == 0 {
                    **acc = [[0.0; LANES]; 6];
                }
                let at = r * n..(r + 1) * n;
                let (p, w) = (&pc[at.clone()], &wc[at.clone()]);
                dispatch_precondition_output(level, row, &mut zc[at.clone()], p, w, &tc[at], acc);
                if let (Some((cell, m, bilinear)), Some(block)) = (extension, block) {
                    super::extension::Coarse::output_row(
                        cell, m, bilinear, block, r, row, p, w, level,
                    );
                }
            },
            &mut self.ws,
        );
        let sums = self.output_sums();
        let (sum_b, sum_gb) = coarse.as_mut().map_or((0.0, 0.0), |c| c.finish(sums[0]));
        self.coarse = coarse;
        PreconditionSums::new(sums, sum_b, sum_gb)
    }

    /// The sums of the output pass over the blocks in order: `Σ_F z`, `|F|`, `Σ_F g z`,
    /// `Σ_F g`, `Σ_F g t`, `Σ_F t`.
    fn output_sums(&self) -> [f64; 6] {
        let mut sums = [0.0; 6];
        for acc in &self.precondition_acc {
            for (s, lanes) in sums.iter_mut().zip(acc) {
                *s += lanes.iter().sum::<f64>();
            }
        }
        sums
    }

    /// [`Self::direction_and_transform`] with the preconditioned gradient:
    /// `t ← (z − z̄_F) + β (t − t̄_F)` on the free set F, 0 elsewhere (`z` raw from
    /// [`Self::precondition`] on F and marked off it, so that F is read from `z` alone;
    /// `z̄_F = z_mean`, `t̄_F = direction_mean`), each row handed to the forward FFT as it is
    /// made. Returns `⟨t, K t⟩`.
    pub(super) fn preconditioned_direction_and_transform(
        &mut self,
        z_mean: f64,
        beta: f64,
        direction_mean: f64,
    ) -> f64 {
        let (n, chunk) = (self.op.grid().n(), self.chunk);
        if let Some(coarse) = &self.coarse {
            let rows = self.op.rows_per_block();
            let c = coarse.cell();
            let blocks = self
                .direction
                .par_chunks_mut(chunk)
                .zip(self.preconditioned.par_chunks(chunk))
                .enumerate();
            return self.op.start_rows(
                blocks,
                |(b, (tc, zc)), r, row| {
                    let at = r * n..(r + 1) * n;
                    let back = coarse.back_row(*b * rows + r);
                    super::extension::dispatch_direction(
                        c,
                        back,
                        [z_mean, beta, direction_mean],
                        &mut tc[at.clone()],
                        row,
                        &zc[at],
                    );
                },
                &mut self.ws,
            );
        }
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

avx2_dispatch! {
    /// One row of the preconditioner's input, with AVX2 where available:
    /// `o = w − level.mean` on the free set F, 0 elsewhere, rounded to single precision.
    fn dispatch_precondition_input(level: Level, o: &mut [f32], p: &[f64], w: &[f64]) {
        for ((o, &p), &w) in o.iter_mut().zip(p).zip(w) {
            *o = if free(p, w, level) { (w - level.mean) as f32 } else { 0.0 };
        }
    }
}

avx2_dispatch! {
    /// [`precondition_output_row`], with AVX2 intrinsics where the processor has them
    /// ([`precondition_output_avx2`]: one pass over the row instead of two, the sums kept in
    /// registers). Same operations in the same order, so the same bits either way.
    fn dispatch_precondition_output = precondition_output_row / precondition_output_avx2(
        level: Level,
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
unsafe fn precondition_output_avx2(
    level: Level,
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
        // `free`: p > 0 || w < entry.
        let on = _mm256_or_pd(
            _mm256_cmp_pd::<_CMP_GT_OQ>(pv, zero),
            _mm256_cmp_pd::<_CMP_LT_OQ>(wv, entry_v),
        );
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
fn precondition_output_row(
    level: Level,
    row: &[f32],
    z: &mut [f32],
    p: &[f64],
    w: &[f64],
    t: &[f64],
    acc: &mut [[f64; LANES]; 6],
) {
    for (((z, &v), &p), &w) in z.iter_mut().zip(row).zip(p).zip(w) {
        *z = if free(p, w, level) { v } else { OFF_FREE_SET };
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
fn precondition_sums(
    level: Level,
    z: &[f64; LANES],
    p: &[f64; LANES],
    w: &[f64; LANES],
    t: &[f64; LANES],
    acc: &mut [[f64; LANES]; 6],
) {
    for k in 0..LANES {
        let on = free(p[k], w[k], level);
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

impl PreconditionSums {
    /// From the output pass's sums ([`Solver::output_sums`]) with the extension's correction
    /// `b` on F (`Σ_F b`, `Σ_F g b`; 0 without it).
    fn new(sums: [f64; 6], sum_b: f64, sum_gb: f64) -> Self {
        let [sz, count, sgz, sg, sgt, st] = sums;
        let (sz, sgz) = (sz + sum_b, sgz + sum_gb);
        let (z_mean, t_mean) = if count > 0.0 {
            (sz / count, st / count)
        } else {
            (0.0, 0.0)
        };
        // Σ_F g (z − z̄) = Σ_F g z − z̄ Σ_F g.
        Self {
            z_mean,
            g_dot_z: sgz - z_mean * sg,
            g_dot_t_old: sgt,
            g_sum: sg,
            t_old_mean: t_mean,
        }
    }
}

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
