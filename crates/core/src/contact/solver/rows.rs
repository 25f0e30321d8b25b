//! Row kernels of the solver's passes: lane-blocked loops with fixed summation order,
//! compiled once more with AVX2 and chosen at run time (same bits either way).

// Lane loops index several fixed-size arrays in lockstep; iterator chains would hide the
// structure the compiler vectorises.
#![allow(clippy::needless_range_loop)]

use super::constraint::{Constraint, LevelSums};
use super::operator::Operator;

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

/// Per-lane accumulators of the gradient statistics `|S|, Σg, Σg², Σpg, Σp, min g` (`S`:
/// the active set of the constraint).
pub(super) struct GradientLanes {
    pub(super) n: [f64; LANES],
    pub(super) sg: [f64; LANES],
    pub(super) sg2: [f64; LANES],
    pub(super) spg: [f64; LANES],
    pub(super) sp: [f64; LANES],
    pub(super) min: [f64; LANES],
    /// A bounded constraint's saturated nodes ([`Constraint::add_to_level`]): their count,
    /// `Σg` and `max g` (untouched when unbounded).
    pub(super) sat_n: [f64; LANES],
    pub(super) sat_g: [f64; LANES],
    pub(super) sat_max: [f64; LANES],
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
            sat_n: [0.0; LANES],
            sat_g: [0.0; LANES],
            sat_max: [f64::NEG_INFINITY; LANES],
        }
    }

    #[inline(always)]
    pub(super) fn add<C: Constraint>(&mut self, c: C, p: &[f64; LANES], g: &[f64; LANES]) {
        for l in 0..LANES {
            let m = if c.active(p[l]) { 1.0 } else { 0.0 };
            c.add_to_level(
                p[l],
                g[l],
                LevelSums {
                    min: &mut self.min[l],
                    spg: &mut self.spg[l],
                    sat_n: &mut self.sat_n[l],
                    sat_g: &mut self.sat_g[l],
                    sat_max: &mut self.sat_max[l],
                },
            );
            self.n[l] += m;
            self.sg[l] += m * g[l];
            self.sg2[l] += m * g[l] * g[l];
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
            self.sat_n[l] += other.sat_n[l];
            self.sat_g[l] += other.sat_g[l];
            self.sat_max[l] = self.sat_max[l].max(other.sat_max[l]);
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
            saturated_nodes: sum(&self.sat_n),
            sum_g_saturated: sum(&self.sat_g),
            max_g_saturated: self
                .sat_max
                .iter()
                .fold(f64::NEG_INFINITY, |a, &b| a.max(b)),
        }
    }
}

/// Statistics of the gradient `g = w − shift` of one state: over the active set `S`
/// (`p > 0`, or `0 < p < p_max` under a ceiling) its size, `Σg` and `Σg²`; `Σp` over all
/// nodes; `Σpg` and `min g` over the unsaturated nodes (all of them when unbounded); and over
/// the saturated ones their number, `Σg` and `max g`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GradientStats {
    pub contact_nodes: f64,
    pub sum_g: f64,
    pub sum_g2: f64,
    pub sum_pg: f64,
    pub sum_p: f64,
    pub min_g: f64,
    pub saturated_nodes: f64,
    pub sum_g_saturated: f64,
    pub max_g_saturated: f64,
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
        saturated_nodes: 0.0,
        sum_g_saturated: 0.0,
        max_g_saturated: f64::NEG_INFINITY,
    };

    /// The complementarity error `(Σpg − min g Σp) / (Σp σ_h)` (docs/CONVENTIONS.md), with
    /// `height_std` the heights' σ_h: `Σ p (g − min g)`, the work of the pressure on the
    /// gap, in units of the load times σ_h.
    pub(super) fn error(&self, height_std: f64) -> f64 {
        (self.sum_pg - self.min_g * self.sum_p) / (self.sum_p * height_std)
    }

    /// The gradient's mean over the contact set.
    pub(super) fn mean_g(&self) -> f64 {
        self.sum_g / self.contact_nodes
    }

    /// `⟨g − ḡ, g − ḡ⟩` over the contact set (≥ 0): the plain iteration's `β` denominator.
    pub(super) fn g_norm(&self) -> f64 {
        let mean_g = self.mean_g();
        (self.sum_g2 - self.contact_nodes * mean_g * mean_g).max(0.0)
    }

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
            acc.saturated_nodes += b.saturated_nodes;
            acc.sum_g_saturated += b.sum_g_saturated;
            acc.max_g_saturated = acc.max_g_saturated.max(b.max_g_saturated);
        }
        acc
    }
}

/// Define `$name`, which runs `$body` compiled with AVX2 where the processor has it and as
/// is elsewhere. IEEE arithmetic without fused multiply-add gives the same bits either way.
macro_rules! avx2_dispatch {
    // Each form below, generic over type parameters (a constraint, an operator): the inner
    // functions declare them again and are called with them.
    ($(#[$attr:meta])* $vis:vis fn $name:ident<$($g:ident: $bound:path),+>($($arg:ident: $ty:ty),* $(,)?) $body:block) => {
        $(#[$attr])*
        #[allow(clippy::too_many_arguments)]
        $vis fn $name<$($g: $bound),+>($($arg: $ty),*) {
            #[inline(always)]
            #[allow(clippy::too_many_arguments)]
            fn body<$($g: $bound),+>($($arg: $ty),*) $body
            #[cfg(target_arch = "x86_64")]
            {
                #[target_feature(enable = "avx2")]
                #[allow(clippy::too_many_arguments)]
                unsafe fn avx2<$($g: $bound),+>($($arg: $ty),*) {
                    body::<$($g),+>($($arg),*)
                }
                if std::is_x86_feature_detected!("avx2") {
                    // SAFETY: the processor supports AVX2 (checked just above).
                    unsafe { avx2::<$($g),+>($($arg),*) };
                    return;
                }
            }
            body::<$($g),+>($($arg),*)
        }
    };
    ($(#[$attr:meta])* $vis:vis fn $name:ident<$($g:ident: $bound:path),+> = $scalar:ident / $avx2:ident($($arg:ident: $ty:ty),* $(,)?);) => {
        $(#[$attr])*
        #[allow(clippy::too_many_arguments)]
        $vis fn $name<$($g: $bound),+>($($arg: $ty),*) {
            #[cfg(target_arch = "x86_64")]
            if std::is_x86_feature_detected!("avx2") {
                // SAFETY: the processor supports AVX2 (checked just above).
                unsafe { $avx2::<$($g),+>($($arg),*) };
                return;
            }
            $scalar::<$($g),+>($($arg),*)
        }
    };
    ($(#[$attr:meta])* $vis:vis fn $name:ident<$($g:ident: $bound:path),+> = $body:ident($($arg:ident: $ty:ty),* $(,)?);) => {
        avx2_dispatch! {
            $(#[$attr])*
            $vis fn $name<$($g: $bound),+>($($arg: $ty),*) { $body::<$($g),+>($($arg),*) }
        }
    };
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
    pub(super) fn dispatch_gradient<C: Constraint> = gradient_row(
        constraint: C,
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
    pub(super) fn dispatch_direction<C: Constraint> = direction_row(
        constraint: C,
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
    /// One row of [`Solver::sparse_update`], with AVX2 where available: the point loads,
    /// then [`gradient_row`].
    pub(super) fn dispatch_sparse<C: Constraint, O: Operator>(
        op: &O,
        constraint: C,
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
        gradient_row(constraint, shift, Some(scale), p, w, h, acc);
    }
}

/// One row of the gradient statistics: if a scale `s ≠ 1` is given, `p ← s p` and
/// `u ← s u` (so `w = u − h ← s (w + h) − h`); then, with `g = w − shift`, `min g` over all
/// nodes and `|S|, Σg, Σg², Σpg, Σp` over the constraint's active set `S` (`p > 0`), added
/// to `acc`. `h` is read only to scale.
#[inline(always)]
fn gradient_row<C: Constraint>(
    c: C,
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
        acc.add(c, &lanes(p), &gap(&lanes(w)));
    }
    if whole < p.len() {
        // Tail of a row whose length is not a multiple of LANES: the padding (p = 0) is
        // off the contact set; only the valid lanes enter the minimum.
        let k = p.len() - whole;
        let mut tail = GradientLanes::new();
        let g = gap(&padded(&w[whole..], 0.0));
        tail.add(c, &padded(&p[whole..], 0.0), &g);
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
fn direction_row<C: Constraint>(
    c: C,
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
                let m = if c.active(p[l]) { 1.0 } else { 0.0 };
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
