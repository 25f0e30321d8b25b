//! The warm start of a sweep's next load, extrapolated linearly in the load from the last
//! two solutions.
//!
//! Scaling the last solution `p_k` to the next load (the start without a history) keeps its
//! contact set and shares the new load in proportion to the old; the contact set of the next
//! load is larger, and its load spreads differently. The secant through the last two
//! solutions, `x = p_k + r (p_k − p_{k−1})` with `r = (p̄ − p̄_k)/(p̄_k − p̄_{k−1})`, clipped at
//! 0, carries both trends on: on the paper's spectrum and loads it takes 9 % of the
//! iterations away at 1024² and 13 % at 8192² (docs/BENCHMARKS.md). Its mean before the
//! clipping is `p̄` exactly, so it is never zero everywhere. `p_{k−1}` is kept in bfloat16
//! (0.25 n² doubles): the start need not be exact, and its rounding (2⁻⁸ relative, 8 significant bits) is far
//! below the change between loads.

use half::bf16;

use super::constraint::Constraint;
use rayon::prelude::*;

/// The largest load ratio `r` extrapolated over: beyond twice the last step the secant
/// says little, and a sweep that turns back (`r ≤ 0`) starts from the scaled solution.
pub const MAX_LOAD_RATIO: f64 = 2.0;

/// The solution before the last, to extrapolate from.
pub(super) struct History {
    /// `p_{k−1}` in bfloat16 (allocated at a sweep's second load).
    pressure: Vec<bf16>,
    /// Its mean pressure, or `None` when there is no solution before the last.
    mean: Option<f64>,
}

impl History {
    pub(super) fn new() -> Self {
        Self {
            pressure: Vec::new(),
            mean: None,
        }
    }

    /// Drop the solution before the last (after a start set from outside, a solve that did
    /// not converge, or with extrapolation off).
    pub(super) fn forget(&mut self) {
        self.mean = None;
    }

    /// Turn the last solution `p` (mean `mean`, converged) into the start for the mean
    /// `target`, extrapolated from the solution before it if there is one and the load
    /// ratio is in `(0, MAX_LOAD_RATIO]` (projected by `constraint`: clipped at 0), and keep
    /// `p` as the solution before the next. Returns whether `p` changed (it then needs an
    /// exact deflection).
    pub(super) fn advance<C: Constraint>(
        &mut self,
        constraint: C,
        p: &mut [f64],
        mean: f64,
        target: f64,
    ) -> bool {
        if self.pressure.len() != p.len() {
            self.pressure = crate::pages::filled(p.len(), bf16::ZERO);
            self.mean = None;
        }
        let ratio = self
            .mean
            .map(|before| (target - mean) / (mean - before))
            .filter(|r| r.is_finite() && *r > 0.0 && *r <= MAX_LOAD_RATIO);
        match ratio {
            Some(r) => p
                .par_iter_mut()
                .zip(self.pressure.par_iter_mut())
                .for_each(|(p, kept)| {
                    let last = *p;
                    *p = constraint.project(last + r * (last - kept.to_f64()));
                    *kept = bf16::from_f64(last);
                }),
            None => p
                .par_iter()
                .zip(self.pressure.par_iter_mut())
                .for_each(|(&p, kept)| *kept = bf16::from_f64(p)),
        }
        self.mean = Some(mean);
        ratio.is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::super::constraint::NonNegative;
    use super::*;

    /// The secant through two states, checked node by node against the formula; the kept
    /// copy rounds to 2⁻⁸ relative (bfloat16 keeps 8 significant bits); a sweep that turns back is not extrapolated.
    #[test]
    fn extrapolates_the_secant_and_keeps_the_last_solution() {
        let before = [0.0, 1.0, 2.0, 0.5, 0.0];
        let last = [0.0, 1.5, 2.2, 0.2, 0.3];
        let mut history = History::new();
        let mut p = before.to_vec();
        assert!(!history.advance(NonNegative, &mut p, 0.7, 0.84));
        assert_eq!(p, before, "no history: the solution is left to be scaled");
        p.copy_from_slice(&last);
        // Means 0.7 then 0.84: the next load 0.98 is one step further, r = 1.
        assert!(history.advance(NonNegative, &mut p, 0.84, 0.98));
        for i in 0..5 {
            let expected = (last[i] + (last[i] - before[i])).max(0.0);
            assert!(
                (p[i] - expected).abs() <= 2f64.powi(-8) * before[i] + 1e-15,
                "node {i}"
            );
        }
        assert_eq!(p[3], 0.0, "clipped at 0");
        for (kept, &v) in history.pressure.iter().zip(&last) {
            assert!((kept.to_f64() - v).abs() <= 2f64.powi(-8) * v);
        }
        let start = p.clone();
        // The next load below the last: no extrapolation, the last solution kept.
        assert!(!history.advance(NonNegative, &mut p, 0.98, 0.9));
        assert_eq!(p, start);
        history.forget();
        assert!(!history.advance(NonNegative, &mut p, 0.98, 1.1));
    }
}
