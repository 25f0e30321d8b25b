//! The paper's p_PL (plateau, power law, cut-off; discrete), its joint maximum-likelihood
//! fit, and a 95 % profile-likelihood interval for α.

use super::fit::{checked_counts, golden_max, Estimator, FitError, MIN_TAIL};
use super::sums::moments;

/// Joint fit of the discrete `p_PL`: `P(k) ∝ 1` for `1 ≤ k ≤ k_s`, `∝ (k/k_s)^(−α)` for
/// `k_s < k ≤ k_m`, with `k_m = max k`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct PlateauFit {
    pub estimator: Estimator,
    pub alpha: f64,
    /// Plateau end `k_s` (pixels; continuous parameter).
    pub k_s: f64,
    /// Cut-off `k_m = max k` (pixels).
    pub k_m: u64,
    pub n: usize,
    pub log_likelihood: f64,
}

/// The range of α searched, and of `ln k_s` in steps of the scan.
const ALPHA_RANGE: (f64, f64) = (-5.0, 10.0);
const KS_STEPS: usize = 60;

/// The log-likelihood of a sample under `p_PL`, with what makes it cheap to evaluate.
struct Likelihood {
    sorted: Vec<u64>,
    /// Suffix sums of ln k over `sorted`.
    log_sum_above: Vec<f64>,
    k_m: u64,
}

impl Likelihood {
    fn new(data: &[u64]) -> Result<Self, FitError> {
        let sorted = checked_counts(data)?;
        let n = sorted.len();
        if n < MIN_TAIL {
            return Err(FitError::TooFew {
                n,
                needed: MIN_TAIL,
            });
        }
        let k_m = *sorted.last().expect("non-empty");
        if sorted[0] == k_m {
            return Err(FitError::TooFewDistinct { distinct: 1 });
        }
        if k_m < 4 {
            return Err(FitError::TooFewDistinct {
                distinct: k_m as usize,
            });
        }
        let mut log_sum_above = vec![0.0; n + 1];
        for i in (0..n).rev() {
            log_sum_above[i] = log_sum_above[i + 1] + (sorted[i] as f64).ln();
        }
        Ok(Self {
            sorted,
            log_sum_above,
            k_m,
        })
    }

    /// Log-likelihood at (α, k_s).
    fn at(&self, alpha: f64, k_s: f64) -> f64 {
        // Z = ⌊k_s⌋ + Σ_{k=⌊k_s⌋+1}^{k_m} (k/k_s)^(−α)
        let flat = (k_s.floor() as u64).min(self.k_m);
        let mut z = flat as f64;
        if flat < self.k_m {
            z += moments(alpha, flat + 1, self.k_m, k_s)[0];
        }
        // Σ over k_i > k_s of ln(k_i/k_s) = (Σ ln k_i over that suffix) − count · ln k_s
        let first = self.sorted.partition_point(|&k| (k as f64) <= k_s);
        let count = (self.sorted.len() - first) as f64;
        let sum_ln = self.log_sum_above[first];
        -(self.sorted.len() as f64) * z.ln() - alpha * (sum_ln - count * k_s.ln())
    }

    /// The range of `ln k_s` searched: `[0, ln(k_m/2)]`.
    fn ln_ks_range(&self) -> (f64, f64) {
        (0.0, (self.k_m as f64 / 2.0).ln())
    }

    /// The best α at a given k_s.
    fn best_alpha(&self, k_s: f64) -> f64 {
        golden_max(|a| self.at(a, k_s), ALPHA_RANGE.0, ALPHA_RANGE.1, 1e-10)
    }

    /// `max over k_s` of the log-likelihood at α (a scan in `ln k_s`, then golden-section
    /// refinement around the best step).
    fn profile(&self, alpha: f64) -> f64 {
        let (lo, hi) = self.ln_ks_range();
        let h = (hi - lo) / KS_STEPS as f64;
        let best = (0..=KS_STEPS)
            .map(|i| lo + h * i as f64)
            .map(|lk| (self.at(alpha, lk.exp()), lk))
            .fold(
                (f64::NEG_INFINITY, 0.0),
                |b, x| if x.0 > b.0 { x } else { b },
            );
        let lk = golden_max(
            |lk| self.at(alpha, lk.exp()),
            (best.1 - h).max(lo),
            (best.1 + h).min(hi),
            1e-9,
        );
        self.at(alpha, lk.exp()).max(best.0)
    }
}

/// Maximise the `p_PL` likelihood over `α ∈ [−5, 10]` and `k_s ∈ [1, k_m/2]` (profile
/// likelihood: a scan in `ln k_s`, then golden-section refinement in both).
pub fn fit_plateau_power_law(data: &[u64]) -> Result<PlateauFit, FitError> {
    let like = Likelihood::new(data)?;
    let ll = |a: f64, ks: f64| like.at(a, ks);
    let (ln_lo, ln_hi) = like.ln_ks_range();
    let mut best = (f64::NEG_INFINITY, 0.0, 0.0);
    for i in 0..=KS_STEPS {
        let ks = (ln_lo + (ln_hi - ln_lo) * i as f64 / KS_STEPS as f64).exp();
        let a = like.best_alpha(ks);
        let v = ll(a, ks);
        if v > best.0 {
            best = (v, a, ks.ln());
        }
    }
    let h = (ln_hi - ln_lo) / KS_STEPS as f64;
    let ln_ks = golden_max(
        |lk| ll(like.best_alpha(lk.exp()), lk.exp()),
        (best.2 - h).max(ln_lo),
        (best.2 + h).min(ln_hi),
        1e-9,
    );
    let k_s = ln_ks.exp();
    let alpha = like.best_alpha(k_s);
    Ok(PlateauFit {
        estimator: Estimator::DiscretePlateauPowerLaw,
        alpha,
        k_s,
        k_m: like.k_m,
        n: like.sorted.len(),
        log_likelihood: ll(alpha, k_s),
    })
}

/// A 95 % interval of α: its ends, and whether each is the edge of the range searched
/// (then the interval is open on that side and only bounded by the search).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct PlateauInterval {
    pub low: f64,
    pub high: f64,
    pub low_at_edge: bool,
    pub high_at_edge: bool,
}

/// Half the 95 % quantile of χ² with one degree of freedom: the drop of the profile
/// log-likelihood at the ends of a 95 % interval (Wilks).
pub const PROFILE_DROP_95: f64 = 0.5 * 3.841_458_820_694_124;

/// The 95 % profile-likelihood interval of α for `fit` (made from `data`): the α whose
/// log-likelihood, maximised over k_s, lies within [`PROFILE_DROP_95`] of the maximum.
/// Each end is bracketed by steps doubling away from α̂, then bisected to 1e-6.
pub fn plateau_alpha_interval(data: &[u64], fit: &PlateauFit) -> Result<PlateauInterval, FitError> {
    let like = Likelihood::new(data)?;
    let top = like.profile(fit.alpha).max(fit.log_likelihood);
    let below = |a: f64| top - like.profile(a) > PROFILE_DROP_95;
    let end = |direction: f64, edge: f64| -> (f64, bool) {
        // Bracket: `inside` within the interval, `outside` beyond it.
        let (mut inside, mut step) = (fit.alpha, 0.01);
        let mut outside = loop {
            let next = fit.alpha + direction * step;
            if direction * (next - edge) >= 0.0 {
                if !below(edge) {
                    return (edge, true);
                }
                break edge;
            }
            if below(next) {
                break next;
            }
            inside = next;
            step *= 2.0;
        };
        while (outside - inside).abs() > 1e-6 {
            let m = 0.5 * (inside + outside);
            if below(m) {
                outside = m;
            } else {
                inside = m;
            }
        }
        (0.5 * (inside + outside), false)
    };
    let (low, low_at_edge) = end(-1.0, ALPHA_RANGE.0);
    let (high, high_at_edge) = end(1.0, ALPHA_RANGE.1);
    Ok(PlateauInterval {
        low,
        high,
        low_at_edge,
        high_at_edge,
    })
}
