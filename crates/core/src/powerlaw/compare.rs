//! Likelihood-ratio tests of the discrete power law above `k_min` against other
//! distributions of the same tail (Clauset, Shalizi & Newman 2009, §5; Vuong 1989), as the
//! `powerlaw` package (PyPI 2.0.0) makes them, with exact maximum-likelihood fits.
//!
//! Every distribution is discrete on the integers `k ≥ k_min`:
//! - the power law `k^(−α) / ζ(α, k_min)`;
//! - the power law with an exponential cut-off `k^(−α) e^(−λk) / Σ_{j ≥ k_min} j^(−α) e^(−λj)`
//!   (`powerlaw`'s "truncated power law"; it contains the power law at `λ = 0`, so the test
//!   is nested);
//! - the exponential `(1 − e^(−λ)) e^(−λ(k − k_min))`;
//! - the lognormal and the stretched exponential `S(x) = e^(−(λx)^β)` discretised as
//!   `powerlaw` does ("round"): `p(k) = (S(k − ½) − S(k + ½)) / S(k_min − ½)` with `S` the
//!   continuous survival function.
//!
//! With `d_i = ln p_PL(k_i) − ln p_alt(k_i)`, `R = Σ d_i` (positive: the power law is the
//! likelier), `σ²` the (population) variance of the `d_i`, the normalised ratio is
//! `R / (σ √n)`. Its p-value is Vuong's `erfc(|R| / (σ √(2n)))` for the non-nested
//! alternatives and, for the nested cut-off, `P(χ²₁ > 2|R|) = erfc(√|R|)` (Wilks).
//! A small p says the sign of `R` is significant.

use super::fit::{checked_counts, fit_discrete, FitError};
use super::sums::discrete_normalisation;

/// The distributions the power law is tested against.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Alternative {
    ExponentialCutoff,
    Lognormal,
    Exponential,
    StretchedExponential,
}

impl Alternative {
    pub const ALL: [Alternative; 4] = [
        Self::ExponentialCutoff,
        Self::Lognormal,
        Self::Exponential,
        Self::StretchedExponential,
    ];

    /// The name in tables and JSON.
    pub fn name(self) -> &'static str {
        match self {
            Self::ExponentialCutoff => "exponential_cutoff",
            Self::Lognormal => "lognormal",
            Self::Exponential => "exponential",
            Self::StretchedExponential => "stretched_exponential",
        }
    }

    /// The names of [`Comparison::parameters`] (an empty name: unused).
    pub fn parameter_names(self) -> [&'static str; 2] {
        match self {
            Self::ExponentialCutoff => ["alpha", "lambda"],
            Self::Lognormal => ["mu", "sigma"],
            Self::Exponential => ["lambda", ""],
            Self::StretchedExponential => ["lambda", "beta"],
        }
    }

    /// Whether the power law is a special case of it (the χ² test applies).
    pub fn nested(self) -> bool {
        self == Self::ExponentialCutoff
    }
}

/// The power law against one alternative.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Comparison {
    pub alternative: Alternative,
    /// The alternative's maximum-likelihood parameters (named by
    /// [`Alternative::parameter_names`]; NaN where unused). λ in 1/pixel, μ in ln(pixel).
    pub parameters: [f64; 2],
    /// The alternative's log-likelihood of the tail.
    pub loglikelihood: f64,
    /// `R = Σ (ln p_PL − ln p_alt)`: positive favours the power law.
    pub ratio: f64,
    /// `R / (σ √n)`.
    pub normalised_ratio: f64,
    /// The significance of the sign of `R`.
    pub p_value: f64,
}

/// The tests of one tail.
#[derive(Debug, PartialEq)]
pub struct TailComparison {
    pub k_min: u64,
    /// Observations at or above `k_min`.
    pub n: usize,
    /// The untruncated power law's exponent above `k_min` and its log-likelihood.
    pub alpha: f64,
    pub loglikelihood: f64,
    pub tests: Vec<Result<Comparison, FitError>>,
}

/// A ratio's sign is taken as significant below this p-value (Clauset et al. 2009, §5).
pub const SIGNIFICANT_AT: f64 = 0.1;

impl Comparison {
    /// `Some(true)`: the power law is significantly likelier; `Some(false)`: the
    /// alternative is; `None`: the data do not tell them apart.
    pub fn favours_power_law(&self) -> Option<bool> {
        (self.p_value < SIGNIFICANT_AT && self.ratio != 0.0).then_some(self.ratio > 0.0)
    }
}

/// What the tests say of the tail, in words: the alternatives significantly likelier than
/// the power law, those it beats, and those it cannot be told from.
pub fn tail_verdict(c: &TailComparison) -> String {
    let mut better = Vec::new();
    let mut worse = Vec::new();
    let mut tied = Vec::new();
    for t in c.tests.iter().flatten() {
        let name = t.alternative.name().replace('_', " ");
        let text = format!(
            "{name} (R/σ√n = {:.2}, p = {:.1e})",
            t.normalised_ratio, t.p_value
        );
        match t.favours_power_law() {
            Some(false) => better.push(text),
            Some(true) => worse.push(name),
            None => tied.push(name),
        }
    }
    let mut parts = Vec::new();
    if !better.is_empty() {
        parts.push(format!(
            "likelier than the power law: {}",
            better.join(", ")
        ));
    }
    if !worse.is_empty() {
        parts.push(format!("less likely: {}", worse.join(", ")));
    }
    if !tied.is_empty() {
        parts.push(format!(
            "not told apart (p ≥ {SIGNIFICANT_AT}): {}",
            tied.join(", ")
        ));
    }
    parts.join("; ")
}

/// The tail `k ≥ k_min` of a sample as distinct values and their counts.
struct Tail {
    k_min: u64,
    values: Vec<(f64, f64)>,
    n: usize,
}

impl Tail {
    /// The values `k ≥ k_min` of a sorted sample.
    fn of_sorted(sorted: &[u64], k_min: u64) -> Self {
        let tail = &sorted[sorted.partition_point(|&k| k < k_min)..];
        let mut values: Vec<(f64, f64)> = Vec::new();
        for &k in tail {
            match values.last_mut() {
                Some(last) if last.0 == k as f64 => last.1 += 1.0,
                _ => values.push((k as f64, 1.0)),
            }
        }
        Tail {
            k_min,
            values,
            n: tail.len(),
        }
    }

    /// `Σ count · f(k)`.
    fn sum(&self, f: impl Fn(f64) -> f64) -> f64 {
        self.values.iter().map(|&(k, c)| c * f(k)).sum()
    }
}

/// Tests the discrete power law above `k_min` against each [`Alternative`] on `data` (pixel
/// counts; values below `k_min` are ignored).
pub fn compare_tail(data: &[u64], k_min: u64) -> Result<TailComparison, FitError> {
    let sorted = checked_counts(data)?;
    let pl = fit_discrete(&sorted, k_min, None)?;
    let tail = Tail::of_sorted(&sorted, k_min);
    let ln_z = discrete_normalisation(pl.alpha, k_min, u64::MAX).ln();
    let ln_pl = |k: f64| -pl.alpha * k.ln() - ln_z;
    let tests = Alternative::ALL
        .iter()
        .map(|&alt| {
            let (parameters, ln_p) = fit_alternative(&tail, alt, pl.alpha)?;
            Ok(ratio_test(&tail, alt, parameters, &ln_pl, &*ln_p))
        })
        .collect();
    Ok(TailComparison {
        k_min,
        n: tail.n,
        alpha: pl.alpha,
        loglikelihood: tail.sum(ln_pl),
        tests,
    })
}

/// `R`, its normalised value and its p-value from the per-value log-likelihoods.
fn ratio_test(
    tail: &Tail,
    alternative: Alternative,
    parameters: [f64; 2],
    ln_pl: &dyn Fn(f64) -> f64,
    ln_alt: &dyn Fn(f64) -> f64,
) -> Comparison {
    let n = tail.n as f64;
    let d: Vec<(f64, f64)> = tail
        .values
        .iter()
        .map(|&(k, c)| (ln_pl(k) - ln_alt(k), c))
        .collect();
    let ratio: f64 = d.iter().map(|&(x, c)| c * x).sum();
    let mean = ratio / n;
    let variance = d.iter().map(|&(x, c)| c * (x - mean).powi(2)).sum::<f64>() / n;
    let sd = variance.sqrt();
    let p_value = if alternative.nested() {
        libm::erfc(ratio.abs().sqrt())
    } else {
        libm::erfc(ratio.abs() / (sd * (2.0 * n).sqrt()))
    };
    Comparison {
        alternative,
        parameters,
        loglikelihood: tail.sum(ln_alt),
        ratio,
        normalised_ratio: ratio / (sd * n.sqrt()),
        p_value,
    }
}

/// A per-value log-pmf.
type LogPmf = Box<dyn Fn(f64) -> f64>;

/// The maximum-likelihood parameters of `alt` on the tail and its log-pmf there.
fn fit_alternative(
    tail: &Tail,
    alt: Alternative,
    alpha_pl: f64,
) -> Result<([f64; 2], LogPmf), FitError> {
    let a = tail.k_min as f64;
    let mean = tail.sum(|k| k) / tail.n as f64;
    let excess = mean - a;
    if excess <= 0.0 {
        return Err(FitError::TooFewDistinct { distinct: 1 });
    }
    let neg = |f: &dyn Fn(f64) -> f64| -tail.sum(f);
    match alt {
        Alternative::Exponential => {
            // The score equation E[k − k_min] = e^(−λ)/(1 − e^(−λ)) = mean excess.
            let lambda = (1.0 / excess).ln_1p();
            Ok(([lambda, f64::NAN], Box::new(exponential_ln_pmf(lambda, a))))
        }
        Alternative::ExponentialCutoff => {
            // (α, ln λ); λ below e^(−40) is the power law to double precision for any area
            // this project meets (λ·k < 1e-9 for k < 2^24).
            let cost = |x: &[f64; 2]| {
                if x[0] <= 0.0 || x[0] > 50.0 || !x[1].is_finite() {
                    return f64::INFINITY;
                }
                let f = cutoff_ln_pmf(x[0], x[1].max(LN_LAMBDA_FLOOR).exp(), a);
                neg(&f)
            };
            let start = [alpha_pl, (1.0 / mean).ln()];
            let (x, _) = minimise(&cost, start, [0.1, 1.0]);
            let lambda = x[1].max(LN_LAMBDA_FLOOR).exp();
            Ok(([x[0], lambda], Box::new(cutoff_ln_pmf(x[0], lambda, a))))
        }
        Alternative::Lognormal => {
            // (μ, ln σ), from the moments of ln k.
            let m = tail.sum(f64::ln) / tail.n as f64;
            let s = (tail.sum(|k| (k.ln() - m).powi(2)) / tail.n as f64).sqrt();
            let cost = |x: &[f64; 2]| {
                if !(x[0].is_finite() && x[1].is_finite() && x[1].abs() < 20.0) {
                    return f64::INFINITY;
                }
                neg(&lognormal_ln_pmf(x[0], x[1].exp(), a))
            };
            let (x, _) = minimise(&cost, [m, s.max(1e-3).ln()], [0.5, 0.3]);
            Ok((
                [x[0], x[1].exp()],
                Box::new(lognormal_ln_pmf(x[0], x[1].exp(), a)),
            ))
        }
        Alternative::StretchedExponential => {
            // (ln λ, ln β), from the exponential (β = 1).
            let cost = |x: &[f64; 2]| {
                if !(x[0].is_finite() && x[1].is_finite() && x[1].abs() < 10.0 && x[0] < 50.0) {
                    return f64::INFINITY;
                }
                neg(&stretched_ln_pmf(x[0].exp(), x[1].exp(), a))
            };
            let (x, _) = minimise(&cost, [(1.0 / mean).ln(), 0.0], [1.0, 0.3]);
            let (lambda, beta) = (x[0].exp(), x[1].exp());
            Ok(([lambda, beta], Box::new(stretched_ln_pmf(lambda, beta, a))))
        }
    }
}

/// Below this `ln λ` the cut-off is taken as `e^(−40)`.
const LN_LAMBDA_FLOOR: f64 = -40.0;

/// `ln p(k)` of the discrete exponential above `a`.
fn exponential_ln_pmf(lambda: f64, a: f64) -> impl Fn(f64) -> f64 {
    let c = (-(-lambda).exp_m1()).ln();
    move |k| c - lambda * (k - a)
}

/// `ln p(k)` of the discrete power law with exponential cut-off above `a`.
fn cutoff_ln_pmf(alpha: f64, lambda: f64, a: f64) -> impl Fn(f64) -> f64 {
    let ln_s = cutoff_normalisation(alpha, lambda, a as u64).ln();
    let la = a.ln();
    move |k| -alpha * (k.ln() - la) - lambda * (k - a) - ln_s
}

/// Terms summed exactly before the Euler–Maclaurin continuation of
/// [`cutoff_normalisation`].
const CUTOFF_EXACT_TERMS: u64 = 256;

/// `Σ_{j ≥ a} (j/a)^(−α) e^(−λ(j − a))` (`α > 0`, `λ > 0`): the first
/// [`CUTOFF_EXACT_TERMS`] terms exactly, the rest by Euler–Maclaurin from `c = a + 256`
/// (B₂ and B₄; `f⁽ʲ⁾/f` is `O((α/c + λ)^j)`, so the neglected B₆ term is below 1e-16 of
/// the sum for λ ≤ 1, and for λ > 1 the whole continuation is below `e^(−256)`), its
/// integral `∫_c^∞ f` by Gauss–Legendre panels in `t = ln x` up to where `λx` reaches 745.
pub fn cutoff_normalisation(alpha: f64, lambda: f64, a: u64) -> f64 {
    assert!(a >= 1 && alpha > 0.0 && lambda > 0.0);
    let (af, la) = (a as f64, (a as f64).ln());
    let f = |x: f64| (-alpha * (x.ln() - la) - lambda * (x - af)).exp();
    let mut s: f64 = (a..a + CUTOFF_EXACT_TERMS).map(|j| f(j as f64)).sum();
    let c = (a + CUTOFF_EXACT_TERMS) as f64;
    let fc = f(c);
    if fc < 1e-300 {
        return s;
    }
    // g = ln f: g′ = −α/x − λ, g″ = α/x², g‴ = −2α/x³; f′ = f g′,
    // f‴ = f (g′³ + 3 g′ g″ + g‴).
    let (g1, g2, g3) = (
        -alpha / c - lambda,
        alpha / (c * c),
        -2.0 * alpha / (c * c * c),
    );
    let d1 = fc * g1;
    let d3 = fc * (g1 * g1 * g1 + 3.0 * g1 * g2 + g3);
    s += cutoff_tail_integral(alpha, lambda, af, c) + 0.5 * fc - d1 / 12.0 + d3 / 720.0;
    s
}

/// `∫_c^∞ (x/a)^(−α) e^(−λ(x − a)) dx` by 16-point Gauss–Legendre panels of width 1/4 in
/// `t = ln x`, to where `λx = 745` (the integrand is below e^(−745) of its value at `a`).
fn cutoff_tail_integral(alpha: f64, lambda: f64, a: f64, c: f64) -> f64 {
    let (t0, t1) = (c.ln(), (745.0 / lambda).ln().max(c.ln()));
    let la = a.ln();
    let g = |t: f64| ((1.0 - alpha) * t + alpha * la - lambda * (t.exp() - a)).exp();
    let panels = ((t1 - t0) / 0.25).ceil().max(1.0) as usize;
    let h = (t1 - t0) / panels as f64;
    let mut s = 0.0;
    for p in 0..panels {
        let mid = t0 + (p as f64 + 0.5) * h;
        for (x, w) in super::sums::GL_X.iter().zip(&super::sums::GL_W) {
            s += w * 0.5 * h * (g(mid - x * 0.5 * h) + g(mid + x * 0.5 * h));
        }
    }
    s
}

/// `ln erfc(z)`, accurate also where `erfc` underflows (asymptotic series beyond 26).
fn ln_erfc(z: f64) -> f64 {
    if z < 26.0 {
        libm::erfc(z).ln()
    } else {
        let r = 1.0 / (2.0 * z * z);
        -z * z - (z * std::f64::consts::PI.sqrt()).ln()
            + (1.0 - r + 3.0 * r * r - 15.0 * r * r * r).ln()
    }
}

/// `ln(e^x − e^y)` for `x > y`.
fn ln_diff_exp(x: f64, y: f64) -> f64 {
    x + (-(y - x).exp_m1()).ln()
}

/// `ln p(k)` of the lognormal discretised by rounding, above `a`.
fn lognormal_ln_pmf(mu: f64, sigma: f64, a: f64) -> impl Fn(f64) -> f64 {
    let z = move |x: f64| (x.ln() - mu) / (sigma * std::f64::consts::SQRT_2);
    // ln S(x) = ln(erfc(z)/2), ln F(x) = ln(erfc(−z)/2) (the ln 2 cancels in p).
    let ln_norm = ln_erfc(z(a - 0.5));
    move |k| {
        let (lo, hi) = (z(k - 0.5), z(k + 0.5));
        let ln_mass = if hi <= 0.0 {
            // Both below the median: S(lo) − S(hi) = F(hi) − F(lo), without cancellation.
            ln_diff_exp(ln_erfc(-hi), ln_erfc(-lo))
        } else {
            ln_diff_exp(ln_erfc(lo), ln_erfc(hi))
        };
        ln_mass - ln_norm
    }
}

/// `ln p(k)` of the stretched exponential discretised by rounding, above `a`.
fn stretched_ln_pmf(lambda: f64, beta: f64, a: f64) -> impl Fn(f64) -> f64 {
    let ln_s = move |x: f64| -(lambda * x).powf(beta);
    let ln_norm = ln_s(a - 0.5);
    move |k| ln_diff_exp(ln_s(k - 0.5), ln_s(k + 0.5)) - ln_norm
}

/// The minimum of `f` by Nelder–Mead from `x0` (initial steps `step`), restarted from the
/// best point until a restart improves `f` by less than 1e-10.
fn minimise(f: &dyn Fn(&[f64; 2]) -> f64, x0: [f64; 2], step: [f64; 2]) -> ([f64; 2], f64) {
    let (mut x, mut fx) = nelder_mead(f, x0, step);
    for _ in 0..20 {
        let (y, fy) = nelder_mead(f, x, step);
        let better = fx - fy;
        if fy < fx {
            (x, fx) = (y, fy);
        }
        if better.abs() < 1e-10 * (1.0 + fx.abs()) {
            break;
        }
    }
    (x, fx)
}

/// One Nelder–Mead descent (reflection 1, expansion 2, contraction ½, shrink ½) until the
/// simplex's values agree to 1e-12 relative and its vertices to 1e-7, or 2000 steps.
fn nelder_mead(f: &dyn Fn(&[f64; 2]) -> f64, x0: [f64; 2], step: [f64; 2]) -> ([f64; 2], f64) {
    let mut s: Vec<([f64; 2], f64)> = [x0, [x0[0] + step[0], x0[1]], [x0[0], x0[1] + step[1]]]
        .into_iter()
        .map(|p| (p, f(&p)))
        .collect();
    let lerp =
        |p: &[f64; 2], q: &[f64; 2], t: f64| [p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])];
    for _ in 0..2000 {
        s.sort_by(|a, b| a.1.total_cmp(&b.1));
        let spread = (s[2].1 - s[0].1).abs();
        let size = s[1..]
            .iter()
            .map(|v| (v.0[0] - s[0].0[0]).abs().max((v.0[1] - s[0].0[1]).abs()))
            .fold(0.0, f64::max);
        // Converged, or on a plateau (a parameter beyond where it matters).
        if spread == 0.0 || (spread <= 1e-12 * (1.0 + s[0].1.abs()) && size < 1e-7) {
            break;
        }
        let centre = lerp(&s[0].0, &s[1].0, 0.5);
        let worst = s[2];
        let r = lerp(&centre, &worst.0, -1.0);
        let fr = f(&r);
        if fr < s[0].1 {
            let e = lerp(&centre, &worst.0, -2.0);
            let fe = f(&e);
            s[2] = if fe < fr { (e, fe) } else { (r, fr) };
        } else if fr < s[1].1 {
            s[2] = (r, fr);
        } else {
            let c = if fr < worst.1 {
                lerp(&centre, &r, 0.5)
            } else {
                lerp(&centre, &worst.0, 0.5)
            };
            let fc = f(&c);
            if fc < worst.1.min(fr) {
                s[2] = (c, fc);
            } else {
                let best = s[0].0;
                for v in s.iter_mut().skip(1) {
                    v.0 = lerp(&best, &v.0, 0.5);
                    v.1 = f(&v.0);
                }
            }
        }
    }
    s.sort_by(|a, b| a.1.total_cmp(&b.1));
    (s[0].0, s[0].1)
}

#[cfg(test)]
mod tests;
