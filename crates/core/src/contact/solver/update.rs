//! The update pass's row kernels: the step `p ← P(p − τ t)` projected by the constraint, the
//! linear update of the deflection `u ← u − τ K t`, the next gradient's statistics and the
//! nodes whose projection departed from the linear step, in one pass over the rows of `K t`
//! as they leave the inverse FFT. The AVX2 form beside the scalar one it must match bit for
//! bit.

// Lane loops index several fixed-size arrays in lockstep; iterator chains would hide the
// structure the compiler vectorises.
#![allow(clippy::needless_range_loop)]

#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

use super::constraint::Constraint;
#[cfg(target_arch = "x86_64")]
use super::constraint::LevelSums;
#[cfg(target_arch = "x86_64")]
use super::lanes::F64x4;
use super::rows::{avx2_dispatch, lanes, padded, GradientLanes, LANES};

avx2_dispatch! {
    /// [`update_row`], with AVX2 intrinsics where the processor has them ([`update_row_avx2`]:
    /// the compiler leaves this loop scalar, and it was the solver's costliest pass). Same
    /// operations in the same order, so the same bits either way.
    pub(super) fn dispatch_update<C: Constraint> = update_row / update_row_avx2(
        a: &UpdateArgs<C>,
        base: usize,
        pc: &mut [f64],
        wc: &mut [f64],
        tc: &[f64],
        rc: &[f64],
        acc: &mut UpdateAcc,
        changes: &mut Vec<(usize, f64)>,
    );
}

/// Scalars of one update pass, and the constraint its projection keeps.
pub(super) struct UpdateArgs<C> {
    pub tau: f64,
    pub level: f64,
    pub next_shift: f64,
    /// Re-admit interpenetrating nodes off the contact set with `p = −τ (w − level)` (the
    /// plain iteration, whose direction is zero off the contact set; the preconditioned
    /// one raises them through its direction on the free set instead).
    pub readmit: bool,
    pub constraint: C,
}

/// Accumulators of the update pass over one block.
pub(super) struct UpdateAcc {
    pub grad: GradientLanes,
    pub kept_t: [f64; LANES],
    pub changed: usize,
    pub readmitted: usize,
}

impl UpdateAcc {
    pub(super) fn new() -> Self {
        Self {
            grad: GradientLanes::new(),
            kept_t: [0.0; LANES],
            changed: 0,
            readmitted: 0,
        }
    }
}

/// One block of `LANES` nodes of the update pass; returns the departures from the linear
/// step (`Δ`), zero where the node stayed on its linear path.
#[inline(always)]
fn update_lanes<C: Constraint>(
    a: &UpdateArgs<C>,
    pn: &mut [f64; LANES],
    wn: &mut [f64; LANES],
    t: &[f64; LANES],
    r: &[f64; LANES],
    acc: &mut UpdateAcc,
) -> [f64; LANES] {
    let (tau, level, next_shift) = (a.tau, a.level, a.next_shift);
    let mut g = [0.0; LANES];
    let mut delta = [0.0; LANES];
    for l in 0..LANES {
        let stepped = pn[l] - tau * t[l]; // t = 0 off S, so p stays 0 there
        let kept = a.constraint.project(stepped);
        let gc = wn[l] - level;
        let new = if a.readmit {
            a.constraint.readmit(kept, gc, -tau)
        } else {
            kept
        };
        pn[l] = new;
        delta[l] = new - stepped;
        let m = if a.constraint.active(new) { 1.0 } else { 0.0 };
        acc.kept_t[l] += m * t[l];
        wn[l] -= tau * r[l];
        g[l] = wn[l] - next_shift;
    }
    acc.grad.add(a.constraint, pn, &g);
    delta
}

/// Record the nodes of one lane block that left or (re-)entered the contact set.
#[inline(always)]
fn record_changes<C: Constraint>(
    c: C,
    delta: &[f64; LANES],
    pn: &[f64; LANES],
    first: usize,
    valid: usize,
    acc: &mut UpdateAcc,
    changes: &mut Vec<(usize, f64)>,
) {
    for l in 0..valid {
        if delta[l] != 0.0 {
            // Within the capacity reserved up front: no allocation.
            if changes.len() < changes.capacity() {
                changes.push((first + l, delta[l]));
            }
            acc.changed += 1;
            // Re-admitted: active now although the linear step left it at ≤ 0.
            if c.active(pn[l]) {
                acc.readmitted += 1;
            }
        }
    }
}

/// The update pass over one row (see [`Solver::update_from_transform`]); `base` is the
/// node index of the row's first value, `rc` the row of `K t`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn update_row<C: Constraint>(
    a: &UpdateArgs<C>,
    base: usize,
    pc: &mut [f64],
    wc: &mut [f64],
    tc: &[f64],
    rc: &[f64],
    acc: &mut UpdateAcc,
    changes: &mut Vec<(usize, f64)>,
) {
    let whole = pc.len() / LANES * LANES;
    for (block, (((p, w), t), r)) in pc[..whole]
        .chunks_exact_mut(LANES)
        .zip(wc.chunks_exact_mut(LANES))
        .zip(tc.chunks_exact(LANES))
        .zip(rc.chunks_exact(LANES))
        .enumerate()
    {
        let (mut pn, mut wn) = (lanes(p), lanes(w));
        let delta = update_lanes(a, &mut pn, &mut wn, &lanes(t), &lanes(r), acc);
        p.copy_from_slice(&pn);
        w.copy_from_slice(&wn);
        // Rare path: a node left or (re-)entered the contact set.
        // Non-short-circuiting, so that the test is one vector comparison, not a branch
        // per lane.
        if delta.iter().fold(false, |any, &d| any | (d != 0.0)) {
            record_changes(
                a.constraint,
                &delta,
                &pn,
                base + block * LANES,
                LANES,
                acc,
                changes,
            );
        }
    }
    if whole < pc.len() {
        // Tail of a row whose length is not a multiple of LANES. The padding (p = t = 0,
        // w − level = 0) stays off the contact set, is not re-admitted and has Δ = 0; only
        // the valid lanes are merged into the statistics.
        let k = pc.len() - whole;
        let (mut pn, mut wn) = (padded(&pc[whole..], 0.0), padded(&wc[whole..], a.level));
        let mut tail = UpdateAcc::new();
        let delta = update_lanes(
            a,
            &mut pn,
            &mut wn,
            &padded(&tc[whole..], 0.0),
            &padded(&rc[whole..], 0.0),
            &mut tail,
        );
        pc[whole..].copy_from_slice(&pn[..k]);
        wc[whole..].copy_from_slice(&wn[..k]);
        record_changes(a.constraint, &delta, &pn, base + whole, k, acc, changes);
        acc.grad.merge_lanes(&tail.grad, k);
        for l in 0..k {
            acc.kept_t[l] += tail.kept_t[l];
        }
    }
}

/// [`update_row`] with AVX2 intrinsics: [`update_lanes`] on four lanes at once (one lane
/// per accumulator lane, so the sums are the scalar code's), the tail by the scalar code.
///
/// # Safety
/// AVX2 must be present (the slices' lengths are checked).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[allow(clippy::too_many_arguments)]
unsafe fn update_row_avx2<C: Constraint>(
    a: &UpdateArgs<C>,
    base: usize,
    pc: &mut [f64],
    wc: &mut [f64],
    tc: &[f64],
    rc: &[f64],
    acc: &mut UpdateAcc,
    changes: &mut Vec<(usize, f64)>,
) {
    const _: () = assert!(LANES == 4, "one AVX register of f64 per lane block");
    let len = pc.len();
    assert!(wc.len() == len && tc.len() == len && rc.len() == len);
    let whole = len / LANES * LANES;
    let tau = _mm256_set1_pd(a.tau);
    // SAFETY: AVX2 is present (this function's contract).
    let neg_tau = unsafe { F64x4::from_raw(_mm256_set1_pd(-a.tau)) };
    let level = _mm256_set1_pd(a.level);
    let next_shift = _mm256_set1_pd(a.next_shift);
    let zero = _mm256_setzero_pd();
    let one = _mm256_set1_pd(1.0);
    let readmit = a.readmit;
    // SAFETY: AVX2 is present (this function's contract).
    let mut g = unsafe { GradientRegs::load(&acc.grad) };
    let mut kept_t = _mm256_loadu_pd(acc.kept_t.as_ptr());
    let (pp, wp, tp, rp) = (pc.as_mut_ptr(), wc.as_mut_ptr(), tc.as_ptr(), rc.as_ptr());
    for i in (0..whole).step_by(LANES) {
        // SAFETY: i + LANES ≤ whole ≤ len, the length of all four slices.
        let (p, w, t, r) = unsafe {
            (
                _mm256_loadu_pd(pp.add(i)),
                _mm256_loadu_pd(wp.add(i)),
                _mm256_loadu_pd(tp.add(i)),
                _mm256_loadu_pd(rp.add(i)),
            )
        };
        // The operations of `update_lanes`, in its order.
        let stepped = _mm256_sub_pd(p, _mm256_mul_pd(tau, t));
        // SAFETY: AVX2 is present (this function's contract).
        let stepped_v = unsafe { F64x4::from_raw(stepped) };
        let kept = a.constraint.project(stepped_v);
        let gc = _mm256_sub_pd(w, level);
        let new = if readmit {
            // SAFETY: as above.
            a.constraint
                .readmit(kept, unsafe { F64x4::from_raw(gc) }, neg_tau)
        } else {
            kept
        };
        let active = a.constraint.active(new);
        let new = new.raw();
        let delta = _mm256_sub_pd(new, stepped);
        let m = _mm256_and_pd(active.raw(), one);
        kept_t = _mm256_add_pd(kept_t, _mm256_mul_pd(m, t));
        let w_new = _mm256_sub_pd(w, _mm256_mul_pd(tau, r));
        let gn = _mm256_sub_pd(w_new, next_shift);
        // SAFETY: as above.
        unsafe { g.add(a.constraint, new, gn, m) };
        // SAFETY: as for the loads.
        unsafe {
            _mm256_storeu_pd(pp.add(i), new);
            _mm256_storeu_pd(wp.add(i), w_new);
        }
        // Rare path: a node left or (re-)entered the contact set (`delta != 0`, NaN
        // included, as in the scalar code).
        if _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_NEQ_UQ>(delta, zero)) != 0 {
            let (mut d, mut pn) = ([0.0; LANES], [0.0; LANES]);
            _mm256_storeu_pd(d.as_mut_ptr(), delta);
            _mm256_storeu_pd(pn.as_mut_ptr(), new);
            record_changes(a.constraint, &d, &pn, base + i, LANES, acc, changes);
        }
    }
    // SAFETY: as above.
    unsafe { g.store(&mut acc.grad) };
    _mm256_storeu_pd(acc.kept_t.as_mut_ptr(), kept_t);
    if whole < len {
        let at = whole..len;
        update_row(
            a,
            base + whole,
            &mut pc[at.clone()],
            &mut wc[at.clone()],
            &tc[at.clone()],
            &rc[at],
            acc,
            changes,
        );
    }
}

/// [`GradientLanes`] in AVX2 registers, one accumulator lane per register lane.
#[cfg(target_arch = "x86_64")]
struct GradientRegs {
    n: __m256d,
    sg: __m256d,
    sg2: __m256d,
    spg: __m256d,
    sp: __m256d,
    min: __m256d,
    sat_n: __m256d,
    sat_g: __m256d,
    sat_max: __m256d,
}

#[cfg(target_arch = "x86_64")]
impl GradientRegs {
    /// # Safety
    /// AVX2 must be present; called from a function compiled with it, into which it inlines.
    #[inline(always)]
    unsafe fn load(g: &GradientLanes) -> Self {
        // SAFETY: the caller guarantees AVX2; each array holds LANES = 4 values.
        unsafe {
            Self {
                n: _mm256_loadu_pd(g.n.as_ptr()),
                sg: _mm256_loadu_pd(g.sg.as_ptr()),
                sg2: _mm256_loadu_pd(g.sg2.as_ptr()),
                spg: _mm256_loadu_pd(g.spg.as_ptr()),
                sp: _mm256_loadu_pd(g.sp.as_ptr()),
                min: _mm256_loadu_pd(g.min.as_ptr()),
                sat_n: _mm256_loadu_pd(g.sat_n.as_ptr()),
                sat_g: _mm256_loadu_pd(g.sat_g.as_ptr()),
                sat_max: _mm256_loadu_pd(g.sat_max.as_ptr()),
            }
        }
    }

    /// # Safety
    /// As [`Self::load`].
    #[inline(always)]
    unsafe fn store(&self, g: &mut GradientLanes) {
        // SAFETY: as in `load`.
        unsafe {
            _mm256_storeu_pd(g.n.as_mut_ptr(), self.n);
            _mm256_storeu_pd(g.sg.as_mut_ptr(), self.sg);
            _mm256_storeu_pd(g.sg2.as_mut_ptr(), self.sg2);
            _mm256_storeu_pd(g.spg.as_mut_ptr(), self.spg);
            _mm256_storeu_pd(g.sp.as_mut_ptr(), self.sp);
            _mm256_storeu_pd(g.min.as_mut_ptr(), self.min);
            _mm256_storeu_pd(g.sat_n.as_mut_ptr(), self.sat_n);
            _mm256_storeu_pd(g.sat_g.as_mut_ptr(), self.sat_g);
            _mm256_storeu_pd(g.sat_max.as_mut_ptr(), self.sat_max);
        }
    }

    /// [`GradientLanes::add`] on four lanes: pressure `new`, gradient `gn`, active mask `m`
    /// (1.0 where active); the constraint's sums ([`Constraint::add_to_level`]) by its rule
    /// on four lanes.
    ///
    /// # Safety
    /// As [`Self::load`].
    #[inline(always)]
    unsafe fn add<C: Constraint>(&mut self, c: C, new: __m256d, gn: __m256d, m: __m256d) {
        // SAFETY: as in `load`.
        unsafe {
            self.n = _mm256_add_pd(self.n, m);
            let mg = _mm256_mul_pd(m, gn);
            self.sg = _mm256_add_pd(self.sg, mg);
            self.sg2 = _mm256_add_pd(self.sg2, _mm256_mul_pd(mg, gn));
            let mut min = F64x4::from_raw(self.min);
            let mut spg = F64x4::from_raw(self.spg);
            let mut sat_n = F64x4::from_raw(self.sat_n);
            let mut sat_g = F64x4::from_raw(self.sat_g);
            let mut sat_max = F64x4::from_raw(self.sat_max);
            c.add_to_level(
                F64x4::from_raw(new),
                F64x4::from_raw(gn),
                LevelSums {
                    min: &mut min,
                    spg: &mut spg,
                    sat_n: &mut sat_n,
                    sat_g: &mut sat_g,
                    sat_max: &mut sat_max,
                },
            );
            (self.min, self.spg, self.sat_n) = (min.raw(), spg.raw(), sat_n.raw());
            (self.sat_g, self.sat_max) = (sat_g.raw(), sat_max.raw());
            self.sp = _mm256_add_pd(self.sp, new);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_support::{require_vector_path, sequence};
    use super::*;

    /// A row exercising every branch of the update: nodes in contact that stay, leave
    /// (stepped below 0) or sit exactly on 0, nodes off contact above and below the level,
    /// and a tail shorter than `LANES`.
    fn row(len: usize, seed: u64) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
        let mut next = sequence(seed);
        let (mut p, mut w, mut t, mut r) = (vec![], vec![], vec![], vec![]);
        for i in 0..len {
            p.push(if i % 3 == 0 { 0.0 } else { next().abs() });
            w.push(next());
            t.push(if i % 7 == 0 { 0.0 } else { next() });
            r.push(next());
        }
        (p, w, t, r)
    }

    /// The AVX2 update (where the processor has it) gives the scalar code's bits: the
    /// pressures, separations, every accumulator lane and the list of changed nodes; for the
    /// elastic constraint and for a ceiling low enough to saturate some nodes.
    #[test]
    fn vector_update_matches_scalar_bits() {
        require_vector_path();
        check(super::super::constraint::NonNegative);
        check(super::super::ceiling::Ceiling::new(0.5).unwrap());
    }

    fn check<C: Constraint>(constraint: C) {
        for (len, readmit) in [(64, false), (64, true), (39, false), (39, true), (3, true)] {
            let (p0, w0, t, r) = row(len, len as u64 + readmit as u64);
            let p0: Vec<f64> = p0.iter().map(|&p| constraint.project(p)).collect();
            let args = UpdateArgs {
                tau: 0.7,
                level: 0.1,
                next_shift: -0.05,
                readmit,
                constraint,
            };
            let run = |vector: bool| {
                let (mut p, mut w) = (p0.clone(), w0.clone());
                let mut acc = UpdateAcc::new();
                let mut changes = Vec::with_capacity(len);
                if vector {
                    dispatch_update(&args, 100, &mut p, &mut w, &t, &r, &mut acc, &mut changes);
                } else {
                    update_row(&args, 100, &mut p, &mut w, &t, &r, &mut acc, &mut changes);
                }
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                let g = &acc.grad;
                let lanes = [
                    g.n, g.sg, g.sg2, g.spg, g.sp, g.min, g.sat_n, g.sat_g, g.sat_max, acc.kept_t,
                ];
                (
                    bits(&p),
                    bits(&w),
                    lanes.iter().map(|l| bits(l)).collect::<Vec<_>>(),
                    (acc.changed, acc.readmitted),
                    changes
                        .iter()
                        .map(|&(i, d)| (i, d.to_bits()))
                        .collect::<Vec<_>>(),
                )
            };
            let (scalar, vector) = (run(false), run(true));
            assert!(scalar.3 .0 > 0, "the row must change some nodes");
            assert!(
                !readmit || scalar.3 .1 > 0,
                "with re-admission the row must re-admit some nodes"
            );
            if constraint.ceiling().is_some() && len > 8 {
                let saturated = scalar
                    .0
                    .iter()
                    .filter(|&&b| f64::from_bits(b) == 0.5)
                    .count();
                assert!(saturated > 0, "the row must saturate some nodes");
            }
            assert_eq!(
                scalar, vector,
                "{constraint:?}, len {len}, readmit {readmit}"
            );
        }
    }
}
