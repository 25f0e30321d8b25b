//! Power-law fits of cluster areas by maximum likelihood (Clauset, Shalizi & Newman 2009;
//! VALIDATION.md §5).
//!
//! Cluster areas are pixel counts `k ≥ 1`, so the main estimator is the **discrete**
//! power law `P(k) = k^(−α) / Z(α)` on the integers `k_min ≤ k ≤ k_max` (doubly truncated;
//! `k_max = ∞` allowed for `α > 1`), `Z(α) = Σ_{k=k_min}^{k_max} k^(−α)`. The continuous
//! power law on `[x_min, x_max]` is provided for continuous data and for comparison.
//!
//! - The MLE solves `E_α[ln k] = mean(ln k_i)` (the score equation); `E_α[ln k]` is strictly
//!   decreasing in `α`, so the root is unique and found by safeguarded Newton steps. With a
//!   finite upper bound, any real `α` is admissible (also `α ≤ 1`).
//! - Standard error from the Fisher information, `SE = 1/sqrt(n Var_α[ln k])`.
//! - `x_min` by the Kolmogorov–Smirnov criterion: the candidate (a distinct value with at
//!   least [`MIN_TAIL`] observations at or above it) minimising the largest distance
//!   between the empirical and fitted CDFs of the tail.
//! - Bootstrap: resample the tail with replacement (bounds fixed), refit, percentile
//!   interval. Deterministic for a given seed.
//! - The paper's plateau + power law `p_PL` (flat up to `k_s`, `(k/k_s)^(−α)` from there
//!   to `k_m`), fitted jointly in `(α, k_s)` with `k_m = max k` (the MLE of an upper
//!   bound), discrete as well.
//!
//! Sums `Σ k^(−α) (ln k)^m` are exact for `k <` [`EXACT_LIMIT`] and continued beyond by the
//! Euler–Maclaurin formula (integral by Gauss–Legendre quadrature in
//! `ln k`, end corrections up to the first derivative); the neglected remainder is below
//! `1e-14` relative for `|α| ≤ 20` (tested against direct summation).

use rand::RngExt;
use rand_chacha::rand_core::SeedableRng;
use rand_chacha::ChaCha8Rng;
use thiserror::Error;

/// Fewest observations in a tail for a fit (Clauset et al. recommend ~50 for a
/// trustworthy exponent; below that the KS scan skips the candidate).
pub const MIN_TAIL: usize = 50;
/// Sums run exactly over `k < EXACT_LIMIT` and continue by Euler–Maclaurin from there (the
/// neglected remainder is ~`α³(α−1)/(720 k⁴)` relative, below 2e-12 at `k = 1024`).
pub const EXACT_LIMIT: u64 = 1024;

/// `ln k` for `k < EXACT_LIMIT`, computed once.
fn ln_table() -> &'static [f64] {
    static TABLE: std::sync::OnceLock<Vec<f64>> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| (0..EXACT_LIMIT).map(|k| (k.max(1) as f64).ln()).collect())
}

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

// ---------------------------------------------------------------------------------------
// Sums and integrals of k^(−α) (ln k)^m.

/// Gauss–Legendre nodes and weights on [−1, 1], 16 points.
const GL_X: [f64; 8] = [
    0.095_012_509_837_637_44,
    0.281_603_550_779_258_9,
    0.458_016_777_657_227_4,
    0.617_876_244_402_643_8,
    0.755_404_408_355_003,
    0.865_631_202_387_831_8,
    0.944_575_023_073_232_6,
    0.989_400_934_991_649_9,
];
const GL_W: [f64; 8] = [
    0.189_450_610_455_068_5,
    0.182_603_415_044_923_6,
    0.169_156_519_395_002_5,
    0.149_595_988_816_576_7,
    0.124_628_971_255_533_9,
    0.095_158_511_682_492_78,
    0.062_253_523_938_647_89,
    0.027_152_459_411_754_09,
];

/// `[Σ w_k, Σ w_k u_k, Σ w_k u_k²]` with `w_k = (k/k0)^(−α)`, `u_k = ln(k/k0)`, over the
/// integers `a ≤ k ≤ b` (`b` may be `u64::MAX` for ∞, then `α > 1` is required). `k0 ≥ 1`
/// is a reference scale that keeps the terms in range.
fn moments(alpha: f64, a: u64, b: u64, k0: f64) -> [f64; 3] {
    debug_assert!(a >= 1 && a <= b);
    let lk0 = k0.ln();
    let mut s = [0.0f64; 3];
    let table = ln_table();
    // Exact terms a ..= exact_end: all of a short range (fewer than SHORT_RANGE terms),
    // else those below EXACT_LIMIT (possibly none).
    const SHORT_RANGE: u64 = 256;
    let exact_end = if b - a < SHORT_RANGE {
        b
    } else if a >= EXACT_LIMIT {
        a - 1
    } else {
        b.min(EXACT_LIMIT - 1)
    };
    for k in a..=exact_end {
        let lk = if k < EXACT_LIMIT {
            table[k as usize]
        } else {
            (k as f64).ln()
        };
        let u = lk - lk0;
        let w = (-alpha * u).exp();
        s[0] += w;
        s[1] += w * u;
        s[2] += w * u * u;
    }
    if exact_end == b {
        return s;
    }
    // Euler–Maclaurin on [c, b] with c = exact_end + 1:
    // Σ f = ∫ f + (f(c) + f(b))/2 + (f'(b) − f'(c))/12 + …
    let c = (exact_end + 1) as f64;
    let f_and_df = |x: f64| -> ([f64; 3], [f64; 3]) {
        let u = x.ln() - lk0;
        let w = (-alpha * u).exp();
        let f = [w, w * u, w * u * u];
        // d/dx [e^{−αu} u^m] = e^{−αu} (m u^{m−1} − α u^m) / x
        let df = [
            -alpha * w / x,
            w * (1.0 - alpha * u) / x,
            w * (2.0 * u - alpha * u * u) / x,
        ];
        (f, df)
    };
    let (fc, dfc) = f_and_df(c);
    let integral = if b == u64::MAX {
        tail_integral(alpha, c, lk0)
    } else {
        log_quadrature(alpha, c, b as f64, lk0)
    };
    for m in 0..3 {
        s[m] += integral[m] + 0.5 * fc[m] - dfc[m] / 12.0;
    }
    if b != u64::MAX {
        let (fb, dfb) = f_and_df(b as f64);
        for m in 0..3 {
            s[m] += 0.5 * fb[m] + dfb[m] / 12.0;
        }
    }
    s
}

/// `∫_c^d e^{−α u} u^m dx` (`u = ln(x/k0)`, m = 0, 1, 2) by composite Gauss–Legendre in
/// `t = ln x` (the integrand `e^{(1−α)u} u^m k0` is smooth there).
fn log_quadrature(alpha: f64, c: f64, d: f64, lk0: f64) -> [f64; 3] {
    let (t0, t1) = (c.ln(), d.ln());
    // Panels narrow enough that |1 − α| · half-width ≤ 1.5 (error far below 1e-15).
    let panels = (((t1 - t0) * (1.0 - alpha).abs().max(1.0) / 3.0).ceil() as usize).max(4);
    let h = (t1 - t0) / panels as f64;
    let mut s = [0.0f64; 3];
    for p in 0..panels {
        let mid = t0 + (p as f64 + 0.5) * h;
        for (x, w) in GL_X.iter().zip(&GL_W) {
            for sign in [-1.0, 1.0] {
                let t = mid + sign * x * 0.5 * h;
                let u = t - lk0;
                let g = ((1.0 - alpha) * u).exp() * lk0.exp() * w * 0.5 * h;
                s[0] += g;
                s[1] += g * u;
                s[2] += g * u * u;
            }
        }
    }
    s
}

/// `∫_c^∞ e^{−α u} u^m dx` for `α > 1` in closed form: with `β = α − 1` and `v = ln(c/k0)`,
/// `k0 e^{−β v} [1/β, v/β + 1/β², v²/β + 2v/β² + 2/β³]`.
fn tail_integral(alpha: f64, c: f64, lk0: f64) -> [f64; 3] {
    let beta = alpha - 1.0;
    let v = c.ln() - lk0;
    let e = (-beta * v).exp() * lk0.exp();
    [
        e / beta,
        e * (v / beta + 1.0 / (beta * beta)),
        e * (v * v / beta + 2.0 * v / (beta * beta) + 2.0 / (beta * beta * beta)),
    ]
}

/// Normalisation of the discrete power law on `[k_min, k_max]` (integers, `1 ≤ k_min ≤
/// k_max`; `k_max = u64::MAX` for ∞, then `α > 1`): `Σ_{k = k_min}^{k_max} k^(−α)`, by the
/// same summation as the fits (exact terms, then the Euler–Maclaurin continuation).
pub fn discrete_normalisation(alpha: f64, k_min: u64, k_max: u64) -> f64 {
    assert!(
        k_min >= 1 && k_min <= k_max,
        "need 1 ≤ k_min ≤ k_max, got [{k_min}, {k_max}]"
    );
    moments(alpha, k_min, k_max, k_min as f64)[0] * (k_min as f64).powf(-alpha)
}

/// Mean and variance of `ln(k/k0)` under the discrete power law on `[a, b]`.
fn discrete_log_stats(alpha: f64, a: u64, b: u64) -> (f64, f64) {
    let s = moments(alpha, a, b, a as f64);
    let mean = s[1] / s[0];
    (mean, (s[2] / s[0] - mean * mean).max(0.0))
}

/// Mean and variance of `ln(x/x_min)` under the continuous power law on
/// `[x_min, x_min e^T]` (`T = ∞` allowed for `α > 1`).
fn continuous_log_stats(alpha: f64, t: f64) -> (f64, f64) {
    let beta = alpha - 1.0;
    if t.is_infinite() {
        return (1.0 / beta, 1.0 / (beta * beta));
    }
    let z = beta * t;
    if z.abs() < 1e-4 {
        // Series about β = 0: uniform in u on [0, T] plus first-order tilt.
        let mean = t / 2.0 - z * t / 12.0;
        let var = t * t / 12.0 - z * z * t * t / 240.0;
        return (mean, var);
    }
    // E[u] = 1/β − T/(e^{βT} − 1); Var = 1/β² − T² e^{βT}/(e^{βT} − 1)².
    let em1 = z.exp_m1();
    let mean = 1.0 / beta - t / em1;
    let var = 1.0 / (beta * beta) - t * t * (em1 + 1.0) / (em1 * em1);
    (mean, var.max(0.0))
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
fn checked_counts(data: &[u64]) -> Result<Vec<u64>, FitError> {
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

/// Choose `k_min` by the KS criterion among the distinct values with at least
/// [`MIN_TAIL`] observations at or above them, fitting on `[k_min, k_max]` each time
/// (`k_max`: `None` for untruncated, else the cut-off, e.g. the largest value).
pub fn fit_discrete_tail(data: &[u64], k_max: Option<u64>) -> Result<TailFit, FitError> {
    let sorted = checked_counts(data)?;
    let b = k_max.unwrap_or(u64::MAX);
    let in_range = sorted.partition_point(|&k| k <= b);
    let mut best: Option<PowerLawFit> = None;
    let mut candidates = 0;
    let mut i = 0;
    while i < in_range {
        let k = sorted[i];
        if in_range - i < MIN_TAIL {
            break;
        }
        if k_max.is_none_or(|m| k < m) {
            candidates += 1;
            if let Ok(fit) = fit_discrete_sorted(&sorted, k, k_max, MIN_TAIL) {
                if best.is_none_or(|b| fit.ks_distance < b.ks_distance) {
                    best = Some(fit);
                }
            }
        }
        i += sorted[i..].partition_point(|&v| v == k);
    }
    match best {
        Some(fit) => Ok(TailFit { fit, candidates }),
        None => Err(FitError::TooFew {
            n: in_range,
            needed: MIN_TAIL,
        }),
    }
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

// ---------------------------------------------------------------------------------------
// The paper's p_PL: plateau, power law, cut-off (discrete).

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

/// Log-likelihood of the discrete `p_PL` for sorted data (all in `[1, k_m]`).
fn plateau_log_likelihood(
    sorted: &[u64],
    log_sum_above: &[f64],
    alpha: f64,
    k_s: f64,
    k_m: u64,
) -> f64 {
    // Z = ⌊k_s⌋ + Σ_{k=⌊k_s⌋+1}^{k_m} (k/k_s)^(−α)
    let flat = (k_s.floor() as u64).min(k_m);
    let mut z = flat as f64;
    if flat < k_m {
        z += moments(alpha, flat + 1, k_m, k_s)[0];
    }
    // Σ over k_i > k_s of ln(k_i/k_s) = (Σ ln k_i over that suffix) − count · ln k_s
    let first = sorted.partition_point(|&k| (k as f64) <= k_s);
    let count = (sorted.len() - first) as f64;
    let sum_ln = log_sum_above[first];
    -(sorted.len() as f64) * z.ln() - alpha * (sum_ln - count * k_s.ln())
}

/// Maximise the `p_PL` likelihood over `α ∈ [−5, 10]` and `k_s ∈ [1, k_m/2]` (profile
/// likelihood: a scan in `ln k_s`, then golden-section refinement in both).
pub fn fit_plateau_power_law(data: &[u64]) -> Result<PlateauFit, FitError> {
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
    // Suffix sums of ln k.
    let mut log_sum_above = vec![0.0; n + 1];
    for i in (0..n).rev() {
        log_sum_above[i] = log_sum_above[i + 1] + (sorted[i] as f64).ln();
    }
    let ll = |a: f64, ks: f64| plateau_log_likelihood(&sorted, &log_sum_above, a, ks, k_m);
    let best_alpha = |ks: f64| golden_max(|a| ll(a, ks), -5.0, 10.0, 1e-10);
    let (ln_lo, ln_hi) = (0.0f64, (k_m as f64 / 2.0).ln());
    let steps = 60;
    let mut best = (f64::NEG_INFINITY, 0.0, 0.0);
    for i in 0..=steps {
        let ks = (ln_lo + (ln_hi - ln_lo) * i as f64 / steps as f64).exp();
        let a = best_alpha(ks);
        let v = ll(a, ks);
        if v > best.0 {
            best = (v, a, ks.ln());
        }
    }
    let h = (ln_hi - ln_lo) / steps as f64;
    let ln_ks = golden_max(
        |lk| ll(best_alpha(lk.exp()), lk.exp()),
        (best.2 - h).max(ln_lo),
        (best.2 + h).min(ln_hi),
        1e-9,
    );
    let k_s = ln_ks.exp();
    let alpha = best_alpha(k_s);
    Ok(PlateauFit {
        estimator: Estimator::DiscretePlateauPowerLaw,
        alpha,
        k_s,
        k_m,
        n,
        log_likelihood: ll(alpha, k_s),
    })
}

/// Golden-section search for the maximum of a unimodal `f` on `[lo, hi]`.
fn golden_max(f: impl Fn(f64) -> f64, mut lo: f64, mut hi: f64, tol: f64) -> f64 {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Direct summation of the moments (with `u = ln k − ln k0`, as `moments` defines it:
    /// the test checks the continuation, not the rounding of `ln(k/k0)` for k near k0).
    fn direct(alpha: f64, a: u64, b: u64, k0: f64) -> [f64; 3] {
        // Kahan summation: up to 10⁶ terms, naive rounding would exceed the tolerance.
        let (mut s, mut c) = ([0.0f64; 3], [0.0f64; 3]);
        for k in a..=b {
            let u = (k as f64).ln() - k0.ln();
            let w = (-alpha * u).exp();
            for (m, term) in [w, w * u, w * u * u].into_iter().enumerate() {
                let y = term - c[m];
                let t = s[m] + y;
                c[m] = (t - s[m]) - y;
                s[m] = t;
            }
        }
        s
    }

    #[test]
    fn euler_maclaurin_continuation_matches_direct_sums() {
        for &alpha in &[-3.0, -0.5, 0.0, 0.999, 1.0, 1.5, 2.0, 2.7, 6.0] {
            for &(a, b) in &[
                (1u64, 3000u64),
                (5, 200_000),
                (40, 1_000_000),
                (1023, 1025),
                (1500, 400_000),
                (5000, 5000),
                (5000, 5001),
            ] {
                let fast = moments(alpha, a, b, a as f64);
                let slow = direct(alpha, a, b, a as f64);
                for m in 0..3 {
                    let rel = (fast[m] - slow[m]).abs() / slow[m].abs().max(1e-300);
                    assert!(
                        rel < 2e-12,
                        "α={alpha} [{a},{b}] m={m}: {} vs {}",
                        fast[m],
                        slow[m]
                    );
                }
            }
        }
    }

    #[test]
    fn discrete_normalisation_matches_direct_sums() {
        for &alpha in &[1.0, 1.7, 2.0, 2.4] {
            for &(a, b) in &[(1u64, 1u64), (1, 900), (3, 250_000), (12, 40_000)] {
                let slow = direct(alpha, a, b, 1.0)[0];
                let fast = discrete_normalisation(alpha, a, b);
                assert!(
                    (fast - slow).abs() <= 2e-12 * slow,
                    "α={alpha} [{a},{b}]: {fast} vs {slow}"
                );
            }
        }
        let z2 = discrete_normalisation(2.0, 1, u64::MAX);
        assert!((z2 - std::f64::consts::PI.powi(2) / 6.0).abs() < 1e-13);
    }

    #[test]
    fn infinite_tail_matches_a_long_sum_plus_its_integral() {
        // Σ_{k≥1} k^(−α) = ζ(α); ζ(2) = π²/6, ζ(3) = 1.2020569031595942.
        let z2 = moments(2.0, 1, u64::MAX, 1.0)[0];
        assert!((z2 - std::f64::consts::PI.powi(2) / 6.0).abs() < 1e-13);
        let z3 = moments(3.0, 1, u64::MAX, 1.0)[0];
        assert!((z3 - 1.202_056_903_159_594_2).abs() < 1e-14);
        // −ζ'(2) = Σ ln k / k² = 0.9375482543158437
        let d2 = moments(2.0, 1, u64::MAX, 1.0)[1];
        assert!((d2 - 0.937_548_254_315_843_7).abs() < 1e-13, "{d2}");
    }

    #[test]
    fn continuous_log_stats_match_quadrature() {
        for &alpha in &[0.5, 1.0 + 1e-6, 1.5, 2.5] {
            let t = (1e3f64).ln();
            let (mean, var) = continuous_log_stats(alpha, t);
            // Midpoint rule in u on [0, T] with weight e^{(1−α)u}.
            let m = 200_000;
            let (mut s0, mut s1, mut s2) = (0.0, 0.0, 0.0);
            for i in 0..m {
                let u = (i as f64 + 0.5) * t / m as f64;
                let w = ((1.0 - alpha) * u).exp();
                s0 += w;
                s1 += w * u;
                s2 += w * u * u;
            }
            let qm = s1 / s0;
            let qv = s2 / s0 - qm * qm;
            assert!((mean - qm).abs() < 1e-8, "α={alpha}: {mean} vs {qm}");
            assert!((var - qv).abs() < 1e-7, "α={alpha}: {var} vs {qv}");
        }
    }
}
