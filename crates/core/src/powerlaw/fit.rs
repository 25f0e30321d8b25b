//! The discrete and continuous power-law fits: the MLE at given bounds, `x_min` by the KS
//! criterion, the bootstrap interval (the module's documentation is in [`super`]).

use rand::RngExt;
use rand_chacha::rand_core::SeedableRng;
use rand_chacha::ChaCha8Rng;
use thiserror::Error;

use super::sums::{continuous_log_stats, discrete_log_stats, moments};

/// Fewest observations in a tail for a fit (Clauset et al. recommend ~50 for a
/// trustworthy exponent; below that the KS scan skips the candidate).
pub const MIN_TAIL: usize = 50;
/// Why a fit cannot be made.
#[derive(Debug, Error, PartialEq)]
pub enum FitError {
    #[error("no data to fit")]
    Empty,
    #[error("data contain {0}, but every value must be finite and ≥ 1 (pixel counts) or > 0 (continuous)")]
    BadValue(f64),
    #[error("the lower bound {lower} is above the largest value {max}")]
    LowerAboveMax { lower: f64, max: f64 },
    #[error("bounds are inconsistent: lower {lower}, upper {upper} (need 0 < lower < upper)")]
    BadBounds { lower: f64, upper: f64 },
    #[error("only {distinct} distinct value(s) in the fitted range; an exponent needs at least 2")]
    TooFewDistinct { distinct: usize },
    #[error("{n} observations in the fitted range, fewer than the {needed} needed")]
    TooFew { n: usize, needed: usize },
    #[error("the likelihood has no maximum at a finite exponent (all data at the lower bound, or α ≤ 1 without an upper bound)")]
    NoMaximum,
}

/// Which estimator produced a number (written next to every fitted exponent).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Estimator {
    /// Discrete power law on integers `[k_min, k_max]` (`k_max` may be infinite).
    DiscreteTruncated,
    /// Continuous power law on `[x_min, x_max]` (`x_max` may be infinite).
    ContinuousTruncated,
    /// Discrete plateau + power law + cut-off (`p_PL`), joint in `(α, k_s)`.
    DiscretePlateauPowerLaw,
}

impl Estimator {
    pub fn name(self) -> &'static str {
        match self {
            Self::DiscreteTruncated => "discrete_truncated_mle",
            Self::ContinuousTruncated => "continuous_truncated_mle",
            Self::DiscretePlateauPowerLaw => "discrete_plateau_power_law_mle",
        }
    }
}

/// A fitted exponent.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct PowerLawFit {
    pub estimator: Estimator,
    pub alpha: f64,
    /// Standard error from the Fisher information at the estimate.
    pub std_error: f64,
    pub lower: f64,
    /// `f64::INFINITY` when untruncated.
    pub upper: f64,
    /// Observations in `[lower, upper]`.
    pub n: usize,
    /// Largest distance between the empirical and fitted CDFs on the fitted range.
    pub ks_distance: f64,
}

/// Solve `mean_of(α) = target` for a strictly decreasing `mean_of` on `(lo, hi)`.
fn solve_decreasing(
    target: f64,
    mut lo: f64,
    mut hi: f64,
    stats: impl Fn(f64) -> (f64, f64),
) -> Result<f64, FitError> {
    // The root must be bracketed: mean(lo) > target > mean(hi).
    let (m_lo, _) = stats(lo);
    let (m_hi, _) = stats(hi);
    if !(m_lo > target && target > m_hi) {
        return Err(FitError::NoMaximum);
    }
    let mut alpha = 0.5 * (lo + hi);
    for _ in 0..200 {
        let (m, v) = stats(alpha);
        let f = m - target;
        if f > 0.0 {
            lo = alpha;
        } else {
            hi = alpha;
        }
        let newton = if v > 0.0 { alpha + f / v } else { f64::NAN };
        let next = if newton > lo && newton < hi {
            newton
        } else {
            0.5 * (lo + hi)
        };
        if (next - alpha).abs() <= 1e-14 * alpha.abs().max(1.0) || hi - lo <= 1e-14 {
            return Ok(next);
        }
        alpha = next;
    }
    Ok(alpha)
}

// ---------------------------------------------------------------------------------------
// Discrete power law.

/// Sorted pixel counts of a sample, checked.
pub(super) fn checked_counts(data: &[u64]) -> Result<Vec<u64>, FitError> {
    if data.is_empty() {
        return Err(FitError::Empty);
    }
    if let Some(&k) = data.iter().find(|&&k| k == 0) {
        return Err(FitError::BadValue(k as f64));
    }
    let mut v = data.to_vec();
    v.sort_unstable();
    Ok(v)
}

/// Discrete power-law MLE of `α` on `k_min ≤ k ≤ k_max` (`None`: no upper bound). Values
/// outside the range are ignored.
pub fn fit_discrete(data: &[u64], k_min: u64, k_max: Option<u64>) -> Result<PowerLawFit, FitError> {
    let sorted = checked_counts(data)?;
    fit_discrete_sorted(&sorted, k_min, k_max, 2)
}

fn fit_discrete_sorted(
    sorted: &[u64],
    k_min: u64,
    k_max: Option<u64>,
    needed: usize,
) -> Result<PowerLawFit, FitError> {
    let max = *sorted.last().ok_or(FitError::Empty)?;
    if k_min == 0 || k_max.is_some_and(|b| b <= k_min) {
        return Err(FitError::BadBounds {
            lower: k_min as f64,
            upper: k_max.map_or(f64::INFINITY, |b| b as f64),
        });
    }
    if k_min > max {
        return Err(FitError::LowerAboveMax {
            lower: k_min as f64,
            max: max as f64,
        });
    }
    let b = k_max.unwrap_or(u64::MAX);
    let start = sorted.partition_point(|&k| k < k_min);
    let end = sorted.partition_point(|&k| k <= b);
    let tail = &sorted[start..end];
    let n = tail.len();
    if n < needed {
        return Err(FitError::TooFew { n, needed });
    }
    let distinct = 1 + tail.windows(2).filter(|w| w[0] != w[1]).count();
    if distinct < 2 {
        return Err(FitError::TooFewDistinct { distinct });
    }
    let lk = (k_min as f64).ln();
    let target = tail.iter().map(|&k| (k as f64).ln() - lk).sum::<f64>() / n as f64;
    let stats = |a: f64| discrete_log_stats(a, k_min, b);
    let (lo, hi) = if k_max.is_some() {
        (-30.0, 30.0)
    } else {
        (1.0 + 1e-9, 30.0)
    };
    let alpha = solve_decreasing(target, lo, hi, stats)?;
    let (_, var) = stats(alpha);
    let ks = ks_discrete(tail, alpha, k_min, b);
    Ok(PowerLawFit {
        estimator: Estimator::DiscreteTruncated,
        alpha,
        std_error: 1.0 / (n as f64 * var).sqrt(),
        lower: k_min as f64,
        upper: k_max.map_or(f64::INFINITY, |b| b as f64),
        n,
        ks_distance: ks,
    })
}

/// KS distance between the empirical CDF of the sorted `tail` and the discrete power law.
fn ks_discrete(tail: &[u64], alpha: f64, a: u64, b: u64) -> f64 {
    let total = moments(alpha, a, b, a as f64)[0];
    let n = tail.len() as f64;
    let mut d = 0.0f64;
    let mut i = 0;
    let mut below = 0.0; // model mass of [a, previous distinct value]
    let mut prev = a - 1;
    while i < tail.len() {
        let k = tail[i];
        let j = tail[i..].partition_point(|&v| v == k) + i;
        // Model CDF just below k and at k.
        let gap = if k > prev + 1 {
            moments(alpha, prev + 1, k - 1, a as f64)[0]
        } else {
            0.0
        };
        let term = (-alpha * ((k as f64).ln() - (a as f64).ln())).exp();
        let before = (below + gap) / total;
        let at = (below + gap + term) / total;
        d = d.max((i as f64 / n - before).abs());
        d = d.max((j as f64 / n - at).abs());
        below += gap + term;
        prev = k;
        i = j;
    }
    d
}

/// A power-law tail with `x_min` chosen by the KS criterion.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct TailFit {
    pub fit: PowerLawFit,
    /// Candidates scanned.
    pub candidates: usize,
}

/// Most `k_min` candidates the KS scan tries: beyond, the candidates are thinned to a
/// logarithmic grid (every distinct value kept where they are sparser than the grid, i.e.
/// all small areas). With areas up to 10⁵ px the grid's ratio is 1.12: finer than the
/// KS criterion resolves, and it bounds the cost of a fit refitted in every resample.
pub const MAX_CANDIDATES: usize = 100;

/// Choose `k_min` by the KS criterion among the distinct values with at least
/// [`MIN_TAIL`] observations at or above them (at most [`MAX_CANDIDATES`] of them,
/// logarithmically spaced), fitting on `[k_min, k_max]` each time (`k_max`: `None` for
/// untruncated, else the cut-off, e.g. the largest value).
pub fn fit_discrete_tail(data: &[u64], k_max: Option<u64>) -> Result<TailFit, FitError> {
    let sorted = checked_counts(data)?;
    let b = k_max.unwrap_or(u64::MAX);
    let in_range = sorted.partition_point(|&k| k <= b);
    let mut all = Vec::new();
    let mut i = 0;
    while i < in_range {
        let k = sorted[i];
        if in_range - i < MIN_TAIL {
            break;
        }
        if k_max.is_none_or(|m| k < m) {
            all.push(k);
        }
        i += sorted[i..].partition_point(|&v| v == k);
    }
    let candidates = thin_to_log_grid(&all, MAX_CANDIDATES);
    let mut best: Option<PowerLawFit> = None;
    for &k in &candidates {
        if let Ok(fit) = fit_discrete_sorted(&sorted, k, k_max, MIN_TAIL) {
            if best.is_none_or(|b| fit.ks_distance < b.ks_distance) {
                best = Some(fit);
            }
        }
    }
    match best {
        Some(fit) => Ok(TailFit {
            fit,
            candidates: candidates.len(),
        }),
        None => Err(FitError::TooFew {
            n: in_range,
            needed: MIN_TAIL,
        }),
    }
}

/// [`fit_discrete_tail`] truncated at the sample's largest value (the MLE of an upper
/// bound): the fit of `alpha.parquet`'s truncated estimator, of `wearcoef fit`, and of each
/// of their resamples and synthetic samples.
pub fn fit_tail_at_max(data: &[u64]) -> Result<TailFit, FitError> {
    let m = data.iter().copied().max().ok_or(FitError::Empty)?;
    fit_discrete_tail(data, Some(m))
}

/// At most `most` of the ascending values `v` (all of them if they are no more): the first,
/// then each value at least one step of the logarithmic grid from `v[0]` to the last
/// above the previous kept one.
pub(super) fn thin_to_log_grid(v: &[u64], most: usize) -> Vec<u64> {
    if v.len() <= most || most < 2 {
        return v.to_vec();
    }
    let (l0, l1) = ((v[0] as f64).ln(), (v[v.len() - 1] as f64).ln());
    let step = (l1 - l0) / (most - 1) as f64;
    let mut out = vec![v[0]];
    let mut next = l0 + step;
    for &k in &v[1..] {
        let lk = (k as f64).ln();
        if lk >= next - 1e-12 {
            out.push(k);
            next = lk + step;
        }
    }
    out
}

/// Percentile bootstrap interval of the discrete MLE: resample the observations in
/// `[k_min, k_max]` with replacement `resamples` times (bounds fixed) and return the
/// (2.5 %, 97.5 %) quantiles of the refitted exponents. Deterministic for a seed.
pub fn bootstrap_discrete(
    data: &[u64],
    k_min: u64,
    k_max: Option<u64>,
    resamples: usize,
    seed: u64,
) -> Result<(f64, f64), FitError> {
    let sorted = checked_counts(data)?;
    let b = k_max.unwrap_or(u64::MAX);
    let tail: Vec<u64> = sorted
        .iter()
        .copied()
        .filter(|&k| k >= k_min && k <= b)
        .collect();
    // Validate once on the full tail.
    fit_discrete_sorted(&tail, k_min, k_max, 2)?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut alphas = Vec::with_capacity(resamples);
    let mut sample = vec![0u64; tail.len()];
    for _ in 0..resamples {
        for s in sample.iter_mut() {
            *s = tail[rng.random_range(0..tail.len())];
        }
        sample.sort_unstable();
        // A resample with a single distinct value has no finite MLE; it is skipped.
        if let Ok(fit) = fit_discrete_sorted(&sample, k_min, k_max, 2) {
            alphas.push(fit.alpha);
        }
    }
    if alphas.len() < resamples / 2 {
        return Err(FitError::NoMaximum);
    }
    alphas.sort_by(|a, b| a.total_cmp(b));
    Ok((quantile(&alphas, 0.025), quantile(&alphas, 0.975)))
}

/// Linear-interpolation quantile of sorted values.
fn quantile(sorted: &[f64], q: f64) -> f64 {
    let pos = q * (sorted.len() - 1) as f64;
    let (i, f) = (pos.floor() as usize, pos.fract());
    if i + 1 < sorted.len() {
        sorted[i] * (1.0 - f) + sorted[i + 1] * f
    } else {
        sorted[i]
    }
}

// ---------------------------------------------------------------------------------------
// Continuous power law.

/// Continuous power-law MLE on `[x_min, x_max]` (`None`: untruncated, closed form
/// `α = 1 + n / Σ ln(x/x_min)`). Values outside the range are ignored.
pub fn fit_continuous(
    data: &[f64],
    x_min: f64,
    x_max: Option<f64>,
) -> Result<PowerLawFit, FitError> {
    if data.is_empty() {
        return Err(FitError::Empty);
    }
    if let Some(&x) = data.iter().find(|x| !(x.is_finite() && **x > 0.0)) {
        return Err(FitError::BadValue(x));
    }
    let upper = x_max.unwrap_or(f64::INFINITY);
    if !(x_min > 0.0 && x_min.is_finite() && upper > x_min) {
        return Err(FitError::BadBounds {
            lower: x_min,
            upper,
        });
    }
    let max = data.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    if x_min > max {
        return Err(FitError::LowerAboveMax { lower: x_min, max });
    }
    let mut tail: Vec<f64> = data
        .iter()
        .copied()
        .filter(|&x| x >= x_min && x <= upper)
        .collect();
    let n = tail.len();
    if n < 2 {
        return Err(FitError::TooFew { n, needed: 2 });
    }
    tail.sort_by(|a, b| a.total_cmp(b));
    if tail[0] == tail[n - 1] {
        return Err(FitError::TooFewDistinct { distinct: 1 });
    }
    let target = tail.iter().map(|x| (x / x_min).ln()).sum::<f64>() / n as f64;
    let t = (upper / x_min).ln();
    let alpha = if t.is_infinite() {
        1.0 + 1.0 / target
    } else {
        solve_decreasing(target, -30.0, 30.0, |a| continuous_log_stats(a, t))?
    };
    let (_, var) = continuous_log_stats(alpha, t);
    // KS distance against the fitted CDF.
    let beta = alpha - 1.0;
    let cdf = |x: f64| {
        let u = (x / x_min).ln();
        if t.is_infinite() {
            -(-beta * u).exp_m1()
        } else if (beta * t).abs() < 1e-12 {
            u / t
        } else {
            (-beta * u).exp_m1() / (-beta * t).exp_m1()
        }
    };
    let ks = tail
        .iter()
        .enumerate()
        .map(|(i, &x)| {
            let c = cdf(x);
            (c - i as f64 / n as f64)
                .abs()
                .max(((i + 1) as f64 / n as f64 - c).abs())
        })
        .fold(0.0, f64::max);
    Ok(PowerLawFit {
        estimator: Estimator::ContinuousTruncated,
        alpha,
        std_error: 1.0 / (n as f64 * var).sqrt(),
        lower: x_min,
        upper,
        n,
        ks_distance: ks,
    })
}

/// Golden-section search for the maximum of a unimodal `f` on `[lo, hi]`.
pub(super) fn golden_max(f: impl Fn(f64) -> f64, mut lo: f64, mut hi: f64, tol: f64) -> f64 {
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let mut x1 = hi - g * (hi - lo);
    let mut x2 = lo + g * (hi - lo);
    let (mut f1, mut f2) = (f(x1), f(x2));
    while hi - lo > tol * (1.0 + lo.abs().max(hi.abs())) {
        if f1 < f2 {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + g * (hi - lo);
            f2 = f(x2);
        } else {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - g * (hi - lo);
            f1 = f(x1);
        }
    }
    0.5 * (lo + hi)
}
