//! Row kernels of the solver's passes: lane-blocked loops with fixed summation order,
//! compiled once more with AVX2 and chosen at run time (same bits either way).

// Lane loops index several fixed-size arrays in lockstep; iterator chains would hide the
// structure the compiler vectorises.
#![allow(clippy::needless_range_loop)]

use super::super::elastic::ElasticOperator;

/// Independent accumulators per reduction (breaks floating-point dependency chains; the
/// summation order stays fixed).
pub(super) const LANES: usize = 4;

/// A block of `LANES` values.
#[inline(always)]
pub(super) fn lanes(slice: &[f64]) -> [f64; LANES] {
    slice.try_into().expect("blocks of LANES values")
}

/// A block of up to `LANES` values (the tail of a row whose length is not a multiple of
/// `LANES`), padded with `fill`.
#[inline(always)]
pub(super) fn padded(slice: &[f64], fill: f64) -> [f64; LANES] {
    let mut out = [fill; LANES];
    out[..slice.len()].copy_from_slice(slice);
    out
}

/// Per-lane accumulators of the gradient statistics `|S|, Σg, Σg², Σpg, Σp, min g`.
pub(super) struct GradientLanes {
    n: [f64; LANES],
    sg: [f64; LANES],
    sg2: [f64; LANES],
    spg: [f64; LANES],
    sp: [f64; LANES],
    min: [f64; LANES],
}

impl GradientLanes {
    #[inline(always)]
    pub(super) fn new() -> Self {
        Self {
            n: [0.0; LANES],
            sg: [0.0; LANES],
            sg2: [0.0; LANES],
            spg: [0.0; LANES],
            sp: [0.0; LANES],
            min: [f64::INFINITY; LANES],
        }
    }

    #[inline(always)]
    pub(super) fn add(&mut self, p: &[f64; LANES], g: &[f64; LANES]) {
        for l in 0..LANES {
            let m = if p[l] > 0.0 { 1.0 } else { 0.0 };
            self.min[l] = if g[l] < self.min[l] {
                g[l]
            } else {
                self.min[l]
            };
            self.n[l] += m;
            self.sg[l] += m * g[l];
            self.sg2[l] += m * g[l] * g[l];
            self.spg[l] += p[l] * g[l];
            self.sp[l] += p[l];
        }
    }

    /// Add the first `k` lanes of `other` (the valid lanes of a padded tail block).
    #[inline(always)]
    pub(super) fn merge_lanes(&mut self, other: &Self, k: usize) {
        for l in 0..k {
            self.n[l] += other.n[l];
            self.sg[l] += other.sg[l];
            self.sg2[l] += other.sg2[l];
            self.spg[l] += other.spg[l];
            self.sp[l] += other.sp[l];
            self.min[l] = self.min[l].min(other.min[l]);
        }
    }

    /// The lanes summed in lane order.
    #[inline(always)]
    pub(super) fn finish(&self) -> GradientStats {
        let sum = |a: &[f64; LANES]| a.iter().sum::<f64>();
        GradientStats {
            contact_nodes: sum(&self.n),
            sum_g: sum(&self.sg),
            sum_g2: sum(&self.sg2),
            sum_pg: sum(&self.spg),
            sum_p: sum(&self.sp),
            min_g: self.min.iter().fold(f64::INFINITY, |a, &b| a.min(b)),
        }
    }
}

/// Statistics of the gradient `g = w − shift` of one state: over the contact set
/// `S = {p > 0}` its size, `Σg`, `Σg²`, `Σpg` and `Σp`, and `min g` over all nodes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct GradientStats {
    pub contact_nodes: f64,
    pub sum_g: f64,
    pub sum_g2: f64,
    pub sum_pg: f64,
    pub sum_p: f64,
    pub min_g: f64,
}

impl GradientStats {
    /// Nothing summed yet (the minimum of an empty set is +∞).
    pub(super) const EMPTY: Self = Self {
        contact_nodes: 0.0,
        sum_g: 0.0,
        sum_g2: 0.0,
        sum_pg: 0.0,
        sum_p: 0.0,
        min_g: f64::INFINITY,
    };

    /// Block statistics merged in the order given (sums added, minima taken).
    pub(super) fn merged(blocks: impl Iterator<Item = Self>) -> Self {
        let mut acc = Self::EMPTY;
        for b in blocks {
            acc.contact_nodes += b.contact_nodes;
            acc.sum_g += b.sum_g;
            acc.sum_g2 += b.sum_g2;
            acc.sum_pg += b.sum_pg;
            acc.sum_p += b.sum_p;
            acc.min_g = acc.min_g.min(b.min_g);
        }
        acc
    }
}

/// Define `$name`, which runs `$body` compiled with AVX2 where the processor has it and as
/// is elsewhere. IEEE arithmetic without fused multiply-add gives the same bits either way.
macro_rules! avx2_dispatch {
    ($(#[$attr:meta])* $vis:vis fn $name:ident($($arg:ident: $ty:ty),* $(,)?) $body:block) => {
        $(#[$attr])*
        #[allow(clippy::too_many_arguments)]
        $vis fn $name($($arg: $ty),*) {
            #[inline(always)]
            #[allow(clippy::too_many_arguments)]
            fn body($($arg: $ty),*) $body
            #[cfg(target_arch = "x86_64")]
            {
                #[target_feature(enable = "avx2")]
                #[allow(clippy::too_many_arguments)]
                unsafe fn avx2($($arg: $ty),*) {
                    body($($arg),*)
                }
                if std::is_x86_feature_detected!("avx2") {
                    // SAFETY: the processor supports AVX2 (checked just above).
                    unsafe { avx2($($arg),*) };
                    return;
                }
            }
            body($($arg),*)
        }
    };
    // A scalar body and an AVX2 one written with intrinsics (an `unsafe fn` with
    // `#[target_feature(enable = "avx2")]`), chosen at run time.
    ($(#[$attr:meta])* $vis:vis fn $name:ident = $scalar:ident / $avx2:ident($($arg:ident: $ty:ty),* $(,)?);) => {
        $(#[$attr])*
        #[allow(clippy::too_many_arguments)]
        $vis fn $name($($arg: $ty),*) {
            #[cfg(target_arch = "x86_64")]
            if std::is_x86_feature_detected!("avx2") {
                // SAFETY: the processor supports AVX2 (checked just above).
                unsafe { $avx2($($arg),*) };
                return;
            }
            $scalar($($arg),*)
        }
    };
    // A named generic body (`#[inline(always)]`), compiled once more with AVX2.
    ($(#[$attr:meta])* $vis:vis fn $name:ident = $body:ident($($arg:ident: $ty:ty),* $(,)?);) => {
        avx2_dispatch! {
            $(#[$attr])*
            $vis fn $name($($arg: $ty),*) { $body($($arg),*) }
        }
    };
}

pub(super) use avx2_dispatch;

avx2_dispatch! {
    /// [`gradient_row`] with AVX2 where available.
    pub(super) fn dispatch_gradient = gradient_row(
        shift: f64,
        scale: Option<f64>,
        p: &mut [f64],
        w: &mut [f64],
        h: &[f64],
        acc: &mut GradientLanes,
    );
}

avx2_dispatch! {
    /// [`exact_row`] with AVX2 where available.
    pub(super) fn dispatch_exact = exact_row(scale: f64, p: &mut [f64], w: &mut [f64], kx: &[f64], h: &[f64]);
}

avx2_dispatch! {
    /// [`direction_row`] with AVX2 where available.
    pub(super) fn dispatch_direction = direction_row(
        level: f64,
        beta: f64,
        direction_mean: f64,
        t: &mut [f64],
        p: &[f64],
        w: &[f64],
        row: &mut [f64],
        part: &mut [f64; LANES],
    );
}

avx2_dispatch! {
    /// [`update_row`], with AVX2 intrinsics where the processor has them ([`update_row_avx2`]:
    /// the compiler leaves this loop scalar, and it was the solver's costliest pass). Same
    /// operations in the same order, so the same bits either way.
    pub(super) fn dispatch_update = update_row / update_row_avx2(
        a: &UpdateArgs,
        base: usize,
        pc: &mut [f64],
        wc: &mut [f64],
        tc: &[f64],
        rc: &[f64],
        acc: &mut UpdateAcc,
        changes: &mut Vec<(usize, f64)>,
    );
}

avx2_dispatch! {
    /// One row of [`Solver::sparse_update`], with AVX2 where available: the point loads,
    /// then [`gradient_row`].
    pub(super) fn dispatch_sparse(
        op: &ElasticOperator,
        iy: usize,
        loads: &[(usize, f64)],
        shift: f64,
        scale: f64,
        p: &mut [f64],
        w: &mut [f64],
        h: &[f64],
        acc: &mut GradientLanes,
    ) {
        op.add_point_loads_row(iy, loads, w);
        gradient_row(shift, Some(scale), p, w, h, acc);
    }
}

/// One row of the gradient statistics: if a scale `s ≠ 1` is given, `p ← s p` and
/// `u ← s u` (so `w = u − h ← s (w + h) − h`); then, with `g = w − shift`, `min g` over all
/// nodes and `|S|, Σg, Σg², Σpg, Σp` over the contact set `S = {p > 0}`, added to `acc`.
/// `h` is read only to scale.
#[inline(always)]
fn gradient_row(
    shift: f64,
    scale: Option<f64>,
    p: &mut [f64],
    w: &mut [f64],
    h: &[f64],
    acc: &mut GradientLanes,
) {
    if let Some(s) = scale.filter(|&s| s != 1.0) {
        for ((p, w), &h) in p.iter_mut().zip(w.iter_mut()).zip(h) {
            *p *= s;
            *w = s * (*w + h) - h;
        }
    }
    let gap = |w: &[f64; LANES]| {
        let mut g = [0.0; LANES];
        for l in 0..LANES {
            g[l] = w[l] - shift;
        }
        g
    };
    let whole = p.len() / LANES * LANES;
    for (p, w) in p[..whole].chunks_exact(LANES).zip(w.chunks_exact(LANES)) {
        acc.add(&lanes(p), &gap(&lanes(w)));
    }
    if whole < p.len() {
        // Tail of a row whose length is not a multiple of LANES: the padding (p = 0) is
        // off the contact set; only the valid lanes enter the minimum.
        let k = p.len() - whole;
        let mut tail = GradientLanes::new();
        let g = gap(&padded(&w[whole..], 0.0));
        tail.add(&padded(&p[whole..], 0.0), &g);
        acc.merge_lanes(&tail, k);
    }
}

/// One row of an exact recomputation: `w ← s K p − h` from the row `kx` of `K p`, `p ← s p`.
#[inline(always)]
fn exact_row(scale: f64, p: &mut [f64], w: &mut [f64], kx: &[f64], h: &[f64]) {
    for (((p, w), &k), &h) in p.iter_mut().zip(w.iter_mut()).zip(kx).zip(h) {
        *p *= scale;
        *w = scale * k - h;
    }
}

/// Direction update of one row (see [`Solver::direction_and_transform`]): writes `t` and
/// the FFT's input row, adds `(g − ḡ_S) t` to the lane sums `part[..LANES]`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn direction_row(
    level: f64,
    beta: f64,
    direction_mean: f64,
    t: &mut [f64],
    p: &[f64],
    w: &[f64],
    row: &mut [f64],
    part: &mut [f64; LANES],
) {
    let mut num = [0.0f64; LANES];
    let body =
        |t: &mut [f64; LANES], p: &[f64; LANES], w: &[f64; LANES], num: &mut [f64; LANES]| {
            for l in 0..LANES {
                let m = if p[l] > 0.0 { 1.0 } else { 0.0 };
                let gc = w[l] - level;
                t[l] = m * (gc + beta * (t[l] - direction_mean));
                num[l] += gc * t[l];
            }
        };
    let whole = t.len() / LANES * LANES;
    for (((t, p), w), o) in t[..whole]
        .chunks_exact_mut(LANES)
        .zip(p.chunks_exact(LANES))
        .zip(w.chunks_exact(LANES))
        .zip(row.chunks_exact_mut(LANES))
    {
        let mut tn = lanes(t);
        body(&mut tn, &lanes(p), &lanes(w), &mut num);
        t.copy_from_slice(&tn);
        o.copy_from_slice(&tn);
    }
    if whole < t.len() {
        // Tail of a row whose length is not a multiple of LANES: padded with p = 0 (off S),
        // so the padding contributes exactly 0.
        let k = t.len() - whole;
        let mut tn = padded(&t[whole..], 0.0);
        body(
            &mut tn,
            &padded(&p[whole..], 0.0),
            &padded(&w[whole..], 0.0),
            &mut num,
        );
        t[whole..].copy_from_slice(&tn[..k]);
        row[whole..].copy_from_slice(&tn[..k]);
    }
    for l in 0..LANES {
        part[l] += num[l];
    }
}

/// Scalars of one update pass.
pub(super) struct UpdateArgs {
    pub tau: f64,
    pub level: f64,
    pub next_shift: f64,
    /// Re-admit interpenetrating nodes off the contact set with `p = −τ (w − level)` (the
    /// plain iteration, whose direction is zero off the contact set; the preconditioned
    /// one raises them through its direction on the free set instead).
    pub readmit: bool,
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
fn update_lanes(
    a: &UpdateArgs,
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
        let kept = if stepped > 0.0 { stepped } else { 0.0 };
        let gc = wn[l] - level;
        let new = if a.readmit && kept == 0.0 && gc < 0.0 {
            -tau * gc
        } else {
            kept
        };
        pn[l] = new;
        delta[l] = new - stepped;
        let m = if new > 0.0 { 1.0 } else { 0.0 };
        acc.kept_t[l] += m * t[l];
        wn[l] -= tau * r[l];
        g[l] = wn[l] - next_shift;
    }
    acc.grad.add(pn, &g);
    delta
}

/// Record the nodes of one lane block that left or (re-)entered the contact set.
#[inline(always)]
fn record_changes(
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
            // Re-admitted: positive now although the linear step left it at ≤ 0.
            if pn[l] > 0.0 {
                acc.readmitted += 1;
            }
        }
    }
}

/// The update pass over one row (see [`Solver::update_from_transform`]); `base` is the
/// node index of the row's first value, `rc` the row of `K t`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn update_row(
    a: &UpdateArgs,
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
            record_changes(&delta, &pn, base + block * LANES, LANES, acc, changes);
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
        record_changes(&delta, &pn, base + whole, k, acc, changes);
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
unsafe fn update_row_avx2(
    a: &UpdateArgs,
    base: usize,
    pc: &mut [f64],
    wc: &mut [f64],
    tc: &[f64],
    rc: &[f64],
    acc: &mut UpdateAcc,
    changes: &mut Vec<(usize, f64)>,
) {
    use std::arch::x86_64::*;
    const _: () = assert!(LANES == 4, "one AVX register of f64 per lane block");
    let len = pc.len();
    assert!(wc.len() == len && tc.len() == len && rc.len() == len);
    let whole = len / LANES * LANES;
    let tau = _mm256_set1_pd(a.tau);
    let neg_tau = _mm256_set1_pd(-a.tau);
    let level = _mm256_set1_pd(a.level);
    let next_shift = _mm256_set1_pd(a.next_shift);
    let zero = _mm256_setzero_pd();
    let one = _mm256_set1_pd(1.0);
    let readmit = a.readmit;
    let g = &mut acc.grad;
    let mut n = _mm256_loadu_pd(g.n.as_ptr());
    let mut sg = _mm256_loadu_pd(g.sg.as_ptr());
    let mut sg2 = _mm256_loadu_pd(g.sg2.as_ptr());
    let mut spg = _mm256_loadu_pd(g.spg.as_ptr());
    let mut sp = _mm256_loadu_pd(g.sp.as_ptr());
    let mut min = _mm256_loadu_pd(g.min.as_ptr());
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
        let kept = _mm256_and_pd(_mm256_cmp_pd::<_CMP_GT_OQ>(stepped, zero), stepped);
        let gc = _mm256_sub_pd(w, level);
        let new = if readmit {
            let enter = _mm256_and_pd(
                _mm256_cmp_pd::<_CMP_EQ_OQ>(kept, zero),
                _mm256_cmp_pd::<_CMP_LT_OQ>(gc, zero),
            );
            _mm256_blendv_pd(kept, _mm256_mul_pd(neg_tau, gc), enter)
        } else {
            kept
        };
        let delta = _mm256_sub_pd(new, stepped);
        let m = _mm256_and_pd(_mm256_cmp_pd::<_CMP_GT_OQ>(new, zero), one);
        kept_t = _mm256_add_pd(kept_t, _mm256_mul_pd(m, t));
        let w_new = _mm256_sub_pd(w, _mm256_mul_pd(tau, r));
        let gn = _mm256_sub_pd(w_new, next_shift);
        // GradientLanes::add: `if g < min { g } else { min }` is exactly `min_pd(g, min)`.
        min = _mm256_min_pd(gn, min);
        n = _mm256_add_pd(n, m);
        let mg = _mm256_mul_pd(m, gn);
        sg = _mm256_add_pd(sg, mg);
        sg2 = _mm256_add_pd(sg2, _mm256_mul_pd(mg, gn));
        spg = _mm256_add_pd(spg, _mm256_mul_pd(new, gn));
        sp = _mm256_add_pd(sp, new);
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
            record_changes(&d, &pn, base + i, LANES, acc, changes);
        }
    }
    let g = &mut acc.grad;
    _mm256_storeu_pd(g.n.as_mut_ptr(), n);
    _mm256_storeu_pd(g.sg.as_mut_ptr(), sg);
    _mm256_storeu_pd(g.sg2.as_mut_ptr(), sg2);
    _mm256_storeu_pd(g.spg.as_mut_ptr(), spg);
    _mm256_storeu_pd(g.sp.as_mut_ptr(), sp);
    _mm256_storeu_pd(g.min.as_mut_ptr(), min);
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
    /// pressures, separations, every accumulator lane and the list of changed nodes.
    #[test]
    fn vector_update_matches_scalar_bits() {
        require_vector_path();
        for (len, readmit) in [(64, false), (64, true), (39, false), (39, true), (3, true)] {
            let (p0, w0, t, r) = row(len, len as u64 + readmit as u64);
            let args = UpdateArgs {
                tau: 0.7,
                level: 0.1,
                next_shift: -0.05,
                readmit,
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
                let lanes = [g.n, g.sg, g.sg2, g.spg, g.sp, g.min, acc.kept_t];
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
            assert_eq!(scalar, vector, "len {len}, readmit {readmit}");
        }
    }
}
