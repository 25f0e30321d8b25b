//! The constraint on the pressure at each node: what the projection after a step keeps, which
//! nodes the conjugate gradient moves, and which may enter the free set.
//!
//! The solver is generic over it ([`super::Solver`]`<C>`): every pass that projects a
//! pressure or asks whether a node is in contact calls its rules, written once over lanes
//! ([`Lanes`]) and inlined into the scalar and AVX2 row kernels alike, so a constraint costs
//! nothing at run time and [`NonNegative`] gives exactly the bits the solver always had. A
//! new constraint implements [`Constraint`] and its part in the solve
//! ([`super::complementarity::Complementarity`]) in a folder of its own, as the perfectly
//! plastic ceiling `0 ≤ p ≤ p_max` does (`ceiling/`), and is passed to
//! [`super::Solver::with_constraint`] (docs/ARCHITECTURE.md).

use super::lanes::Lanes;

/// The admissible set of the pressure at one node. Each rule is written once, generic over
/// [`Lanes`]: the scalar code runs it on one `f64`, the AVX2 kernels on four lanes, and both
/// give the same bits (the rules' test, [`tests::check`], compares them). The load offset's
/// rules ([`Self::moves`], [`Self::offset`]) run only in scalar passes and take one `f64`. A
/// pressure of 0 must be inactive (the row kernels pad their tails with it).
pub trait Constraint: Copy + Send + Sync + PartialEq + std::fmt::Debug + 'static {
    /// The admissible pressure nearest to `p` (NaN maps to an admissible value).
    fn project<V: Lanes>(self, p: V) -> V;

    /// Whether a node of pressure `p` is active: in contact and free to move both ways. The
    /// conjugate gradient works on the active set; the gradient's statistics, the plain
    /// direction and the load offset's slope are taken over it.
    fn active<V: Lanes>(self, p: V) -> V::Mask;

    /// The ceiling `p_max` of the pressure, if it has one.
    #[inline(always)]
    fn ceiling(self) -> Option<f64> {
        None
    }

    /// Whether a node of pressure `p` sits on the ceiling (never without one).
    #[inline(always)]
    fn saturated<V: Lanes>(self, p: V) -> V::Mask {
        p.none()
    }

    /// Whether a node of pressure `p` and separation `w = u − h` is in the free set of the
    /// preconditioned iteration, given the level `mean` of the gradient and the entry
    /// threshold `entry ≤ mean`: the active nodes and those that interpenetrate.
    #[inline(always)]
    fn free<V: Lanes>(self, p: V, w: V, entry: V, _mean: V) -> V::Mask {
        self.active(p) | w.lt(entry)
    }

    /// Whether a load offset moves a node of pressure `p` ([`Self::offset`]); `wide` asks
    /// for every node, where a constraint would move fewer.
    #[inline(always)]
    fn moves(self, _p: f64, _wide: bool) -> bool {
        true
    }

    /// A node of pressure `p` offset by `c` when the load is restored
    /// (`Solver::load_offset`): `P(p + c)` where it [`Self::moves`], which for `c ≤ 0`
    /// leaves the nodes at 0 there; `p` elsewhere.
    #[inline(always)]
    fn offset(self, p: f64, c: f64, wide: bool) -> f64 {
        // Both sides computed and selected (no branch on scattered nodes).
        let moved = self.project(p + c);
        if self.moves(p, wide) {
            moved
        } else {
            p
        }
    }

    /// The plain iteration's re-admission after the step: `kept` is the projected pressure,
    /// `gc = w − level` the gradient, `neg_tau` the step `−τ`. A node the projection left at
    /// 0 where the surfaces interpenetrate (`gc < 0`) re-enters with `−τ gc`; the others keep
    /// `kept`.
    #[inline(always)]
    fn readmit<V: Lanes>(self, kept: V, gc: V, neg_tau: V) -> V {
        let zero = kept.splat(0.0);
        V::select(kept.eq(zero) & gc.lt(zero), neg_tau * gc, kept)
    }

    /// Adds a node of pressure `p` and gradient `g` to the sums that the error and the level
    /// of the gradient are made of, beyond those over the active set: `min g` and `Σpg` over
    /// every node (`sums`' saturated sums are a bounded constraint's own).
    #[inline(always)]
    fn add_to_level<V: Lanes>(self, p: V, g: V, sums: LevelSums<'_, V>) {
        *sums.min = g.min(*sums.min);
        *sums.spg = *sums.spg + p * g;
    }
}

/// The accumulators [`Constraint::add_to_level`] adds a node to, one lane's (or four's):
/// `min g` and `Σpg` over the nodes a constraint says, and over its saturated nodes their
/// number, `Σg` and `max g`.
pub struct LevelSums<'a, V> {
    pub min: &'a mut V,
    pub spg: &'a mut V,
    pub sat_n: &'a mut V,
    pub sat_g: &'a mut V,
    pub sat_max: &'a mut V,
}

/// Frictionless elastic contact: `p ≥ 0`, every node of positive pressure active.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct NonNegative;

impl Constraint for NonNegative {
    /// `0` where `p > 0` fails (NaN too).
    #[inline(always)]
    fn project<V: Lanes>(self, p: V) -> V {
        p.keep(p.gt(p.splat(0.0)))
    }

    #[inline(always)]
    fn active<V: Lanes>(self, p: V) -> V::Mask {
        p.gt(p.splat(0.0))
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// Each rule on four lanes gives its scalar form's bits on values either side of 0, ±0,
    /// ±∞ and NaN (the ceiling's own test calls [`check`] with ceilings among those values).
    #[test]
    fn vector_forms_match_the_scalar_ones() {
        super::super::test_support::require_vector_path();
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") {
            check(NonNegative);
        }
    }

    /// Every rule of `c` on four lanes against its scalar form, bit for bit (AVX2 must be
    /// present).
    #[cfg(target_arch = "x86_64")]
    pub(in super::super) fn check<C: Constraint>(c: C) {
        let values = [
            -1.5,
            -0.0,
            0.0,
            1e-300,
            2.5,
            3.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            0.75,
            -0.25,
            1.0,
        ];
        let (entry, mean, tau) = (0.25, 0.5, 0.75);
        for p in values.chunks(4) {
            for w in values.chunks(4) {
                let (p, w): ([f64; 4], [f64; 4]) = (p.try_into().unwrap(), w.try_into().unwrap());
                // SAFETY: AVX2 is present (checked by the caller).
                let vector = unsafe { lanes(c, &p, &w, [entry, mean, tau]) };
                for l in 0..4 {
                    let at = format!("{c:?} p {} w {}", p[l], w[l]);
                    let mut sums = [1.0, 0.5, 2.0, -1.0, 0.25];
                    let [min, spg, sat_n, sat_g, sat_max] = &mut sums;
                    let level = LevelSums {
                        min,
                        spg,
                        sat_n,
                        sat_g,
                        sat_max,
                    };
                    c.add_to_level(p[l], w[l], level);
                    // The re-admission takes a projected pressure and a gradient.
                    let kept = c.project(p[l]);
                    let mask = |b: bool| if b { f64::from_bits(u64::MAX) } else { 0.0 };
                    let scalar = [
                        c.project(p[l]),
                        mask(c.active(p[l])),
                        mask(c.free(p[l], w[l], entry, mean)),
                        c.readmit(kept, w[l], -tau),
                        mask(c.saturated(p[l])),
                    ]
                    .into_iter()
                    .chain(sums);
                    for (k, (s, v)) in scalar.zip(&vector).enumerate() {
                        assert_eq!(s.to_bits(), v[l].to_bits(), "{at}: rule {k}");
                    }
                }
            }
        }
    }

    /// The rules on four lanes: project, active, free, readmit, saturated, then the five
    /// level sums after adding each lane to `[1, 0.5, 2, −1, 0.25]`.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn lanes<C: Constraint>(
        c: C,
        p: &[f64; 4],
        w: &[f64; 4],
        [entry, mean, tau]: [f64; 3],
    ) -> [[f64; 4]; 10] {
        use super::super::lanes::F64x4;
        use std::arch::x86_64::*;
        // SAFETY: AVX2 is present (this function's contract).
        let (pv, wv) = unsafe {
            (
                F64x4::from_raw(_mm256_loadu_pd(p.as_ptr())),
                F64x4::from_raw(_mm256_loadu_pd(w.as_ptr())),
            )
        };
        let mut sums = [1.0, 0.5, 2.0, -1.0, 0.25].map(|x| pv.splat(x));
        let [min, spg, sat_n, sat_g, sat_max] = &mut sums;
        c.add_to_level(
            pv,
            wv,
            LevelSums {
                min,
                spg,
                sat_n,
                sat_g,
                sat_max,
            },
        );
        let kept = c.project(pv);
        let rules = [
            c.project(pv),
            pv.splat(0.0),
            pv.splat(0.0),
            c.readmit(kept, wv, pv.splat(-tau)),
            pv.splat(0.0),
        ];
        let masks = [
            c.active(pv),
            c.free(pv, wv, pv.splat(entry), pv.splat(mean)),
            c.saturated(pv),
        ];
        let mut out = [[0.0; 4]; 10];
        let registers = rules
            .iter()
            .map(|v| v.raw())
            .chain(sums.iter().map(|v| v.raw()));
        for (o, v) in out.iter_mut().zip(registers) {
            // SAFETY: AVX2 is present; `o` holds four values.
            unsafe { _mm256_storeu_pd(o.as_mut_ptr(), v) };
        }
        for (k, m) in [1, 2, 4].into_iter().zip(masks) {
            // SAFETY: as above.
            unsafe { _mm256_storeu_pd(out[k].as_mut_ptr(), m.raw()) };
        }
        out
    }
}
