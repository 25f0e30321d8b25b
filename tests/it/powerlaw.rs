//! Power-law estimators on synthetic samples with a known exponent (VALIDATION.md §5).

use rand::RngExt;
use rand_chacha::rand_core::SeedableRng;
use rand_chacha::ChaCha8Rng;
use wearcoef::powerlaw::{
    bootstrap_discrete, fit_continuous, fit_discrete, fit_discrete_tail, fit_plateau_power_law,
    plateau_alpha_interval, FitError,
};

fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

/// Continuous power law on [x_min, x_max] (x_max = ∞ allowed) by inverting its CDF.
fn continuous_sample(r: &mut ChaCha8Rng, n: usize, alpha: f64, x_min: f64, x_max: f64) -> Vec<f64> {
    let tail = (x_max / x_min).powf(1.0 - alpha); // 0 when untruncated and α > 1
    (0..n)
        .map(|_| {
            let u: f64 = r.random();
            x_min * (1.0 - u * (1.0 - tail)).powf(1.0 / (1.0 - alpha))
        })
        .collect()
}

/// Discrete power law on the integers [k_min, k_max] by inverting a tabulated CDF.
fn discrete_sample(r: &mut ChaCha8Rng, n: usize, alpha: f64, k_min: u64, k_max: u64) -> Vec<u64> {
    let mut cdf: Vec<f64> = (k_min..=k_max).map(|k| (k as f64).powf(-alpha)).collect();
    for i in 1..cdf.len() {
        cdf[i] += cdf[i - 1];
    }
    let total = *cdf.last().unwrap();
    (0..n)
        .map(|_| {
            let u: f64 = r.random::<f64>() * total;
            k_min + cdf.partition_point(|&c| c < u) as u64
        })
        .collect()
}

/// Discrete power law on k ≥ k_min without bound: Devroye's exact Zipf rejection sampler
/// (Devroye 1986, X.6) for k ≥ 1, then rejection of k < k_min.
fn zipf_sample(r: &mut ChaCha8Rng, n: usize, alpha: f64, k_min: u64) -> Vec<u64> {
    let b = 2f64.powf(alpha - 1.0);
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let u: f64 = 1.0 - r.random::<f64>();
        let v: f64 = r.random();
        let x = u.powf(-1.0 / (alpha - 1.0)).floor();
        if x.is_nan() || x >= 1e15 {
            continue;
        }
        let t = (1.0 + 1.0 / x).powf(alpha - 1.0);
        if v * x * (t - 1.0) / (b - 1.0) <= t / b && x as u64 >= k_min {
            out.push(x as u64);
        }
    }
    out
}

/// Discrete p_PL: flat on [1, k_s], (k/k_s)^(−α) on (k_s, k_m].
fn plateau_sample(r: &mut ChaCha8Rng, n: usize, alpha: f64, k_s: f64, k_m: u64) -> Vec<u64> {
    let mut cdf: Vec<f64> = (1..=k_m)
        .map(|k| {
            let k = k as f64;
            if k <= k_s {
                1.0
            } else {
                (k / k_s).powf(-alpha)
            }
        })
        .collect();
    for i in 1..cdf.len() {
        cdf[i] += cdf[i - 1];
    }
    let total = *cdf.last().unwrap();
    (0..n)
        .map(|_| {
            let u = r.random::<f64>() * total;
            1 + cdf.partition_point(|&c| c < u) as u64
        })
        .collect()
}

/// Mean of `fits` replicate estimates and check each is within 3 SE of the truth.
fn check_recovery(label: &str, alpha: f64, estimates: &[(f64, f64)]) {
    for &(a, se) in estimates {
        assert!(
            (a - alpha).abs() <= 3.0 * se,
            "{label}: α̂ = {a} ± {se}, true {alpha}"
        );
    }
    let mean = estimates.iter().map(|e| e.0).sum::<f64>() / estimates.len() as f64;
    assert!(
        (mean - alpha).abs() <= 0.01,
        "{label}: mean α̂ = {mean} over {} replicates, true {alpha}",
        estimates.len()
    );
}

const N: usize = 10_000;
const REPLICATES: usize = 12;

#[test]
fn continuous_estimators_recover_alpha_without_bias() {
    let mut r = rng(1);
    for &(alpha, x_max) in &[
        (1.5, f64::INFINITY),
        (2.5, f64::INFINITY),
        (1.5, 1e3),
        (1.05, 1e3),
        (1.95, 1e4),
    ] {
        let est: Vec<(f64, f64)> = (0..REPLICATES)
            .map(|_| {
                let s = continuous_sample(&mut r, N, alpha, 1.0, x_max);
                let upper = x_max.is_finite().then_some(x_max);
                let f = fit_continuous(&s, 1.0, upper).unwrap();
                (f.alpha, f.std_error)
            })
            .collect();
        check_recovery(&format!("continuous α={alpha} x_max={x_max}"), alpha, &est);
    }
}

#[test]
fn discrete_estimators_recover_alpha_without_bias() {
    let mut r = rng(2);
    // Truncated on [k_min, k_max], including α near 1 and 2 and α < 1 (allowed with a
    // finite upper bound).
    for &(alpha, k_min, k_max) in &[
        (1.5, 1u64, 10_000u64),
        (1.5, 5, 10_000),
        (1.02, 1, 5_000),
        (1.98, 2, 20_000),
        (0.7, 1, 3_000),
    ] {
        let est: Vec<(f64, f64)> = (0..REPLICATES)
            .map(|_| {
                let s = discrete_sample(&mut r, N, alpha, k_min, k_max);
                let f = fit_discrete(&s, k_min, Some(k_max)).unwrap();
                (f.alpha, f.std_error)
            })
            .collect();
        check_recovery(
            &format!("discrete α={alpha} [{k_min}, {k_max}]"),
            alpha,
            &est,
        );
    }
    // Untruncated (Hurwitz zeta normalisation), k ≥ k_min.
    for &(alpha, k_min) in &[(1.5, 1u64), (2.5, 1), (1.8, 6)] {
        let est: Vec<(f64, f64)> = (0..REPLICATES)
            .map(|_| {
                let s = zipf_sample(&mut r, N, alpha, k_min);
                let f = fit_discrete(&s, k_min, None).unwrap();
                (f.alpha, f.std_error)
            })
            .collect();
        check_recovery(&format!("zipf α={alpha} k≥{k_min}"), alpha, &est);
    }
}

/// The Wald interval α̂ ± 1.96 SE covers the true exponent in about 95 % of draws
/// (400 draws: binomial SD 1.1 %, the band is ±3 SD).
#[test]
fn standard_error_intervals_cover_about_95_percent() {
    let mut r = rng(3);
    let draws = 400;
    let covered = (0..draws)
        .filter(|_| {
            let s = discrete_sample(&mut r, 1000, 1.5, 1, 2000);
            let f = fit_discrete(&s, 1, Some(2000)).unwrap();
            (f.alpha - 1.5).abs() <= 1.96 * f.std_error
        })
        .count();
    let rate = covered as f64 / draws as f64;
    assert!((0.917..=0.983).contains(&rate), "coverage {rate}");
}

/// Bootstrap percentile intervals: about 95 % coverage (150 draws of 200 resamples:
/// binomial SD 1.8 %, band ±3 SD). Slow in debug builds: run in release by `make test`.
#[test]
#[ignore]
fn bootstrap_intervals_cover_about_95_percent() {
    let mut r = rng(4);
    let draws = 150;
    let mut covered = 0;
    for d in 0..draws {
        let s = discrete_sample(&mut r, 1000, 1.5, 1, 2000);
        let (lo, hi) = bootstrap_discrete(&s, 1, Some(2000), 200, d).unwrap();
        if lo <= 1.5 && 1.5 <= hi {
            covered += 1;
        }
    }
    let rate = covered as f64 / draws as f64;
    assert!((0.896..=1.0).contains(&rate), "coverage {rate}");
}

#[test]
fn bootstrap_interval_agrees_with_the_standard_error() {
    let mut r = rng(5);
    let s = discrete_sample(&mut r, 2000, 1.5, 1, 5000);
    let f = fit_discrete(&s, 1, Some(5000)).unwrap();
    let (lo, hi) = bootstrap_discrete(&s, 1, Some(5000), 300, 9).unwrap();
    let wald = 2.0 * 1.96 * f.std_error;
    assert!(lo < f.alpha && f.alpha < hi);
    assert!(
        ((hi - lo) / wald - 1.0).abs() < 0.25,
        "bootstrap width {} vs 2·1.96·SE {wald}",
        hi - lo
    );
    // Deterministic for a seed.
    assert_eq!(
        bootstrap_discrete(&s, 1, Some(5000), 300, 9).unwrap(),
        (lo, hi)
    );
}

/// On a plateau + power law sample the KS-chosen k_min lands near the plateau's end, and
/// the truncated discrete fit above it recovers α.
#[test]
fn ks_lower_bound_finds_the_start_of_the_power_law() {
    let mut r = rng(6);
    let s = plateau_sample(&mut r, N, 1.5, 10.0, 10_000);
    let k_max = *s.iter().max().unwrap();
    let tail = fit_discrete_tail(&s, Some(k_max)).unwrap();
    assert!(
        (5.0..=30.0).contains(&tail.fit.lower),
        "k_min = {}",
        tail.fit.lower
    );
    assert!(
        (tail.fit.alpha - 1.5).abs() <= 3.0 * tail.fit.std_error,
        "α̂ = {} ± {}",
        tail.fit.alpha,
        tail.fit.std_error
    );
}

#[test]
fn plateau_power_law_joint_fit_recovers_alpha_and_plateau() {
    let mut r = rng(7);
    let mut alphas = Vec::new();
    for _ in 0..4 {
        let s = plateau_sample(&mut r, N, 1.5, 10.0, 10_000);
        let f = fit_plateau_power_law(&s).unwrap();
        assert!((f.alpha - 1.5).abs() < 0.04, "α̂ = {}", f.alpha);
        assert!((f.k_s / 10.0 - 1.0).abs() < 0.15, "k_s = {}", f.k_s);
        alphas.push(f.alpha);
    }
    let mean = alphas.iter().sum::<f64>() / alphas.len() as f64;
    assert!((mean - 1.5).abs() < 0.015, "mean α̂ = {mean}");
}

/// The 95 % profile-likelihood interval of the plateau fit covers the true α at its nominal
/// rate on samples of the paper's p_PL (α = 1.5, plateau to 10 px, cut-off 10⁴ px, 1000
/// clusters, the cut-off estimated by the largest): 200 samples, so the coverage of a
/// correct interval lies in [0.90, 0.99] with probability 0.998 (binomial, ±3σ).
#[test]
#[ignore = "about a minute in a debug build; make test runs it in release (--include-ignored)"]
fn plateau_interval_covers_the_true_alpha_at_its_nominal_rate() {
    let mut r = rng(11);
    let trials = 200;
    let mut covered = 0;
    let (mut widths, mut alphas) = (Vec::new(), Vec::new());
    for _ in 0..trials {
        let s = plateau_sample(&mut r, 1000, 1.5, 10.0, 10_000);
        let f = fit_plateau_power_law(&s).unwrap();
        let i = plateau_alpha_interval(&s, &f).unwrap();
        assert!(
            i.low < f.alpha && f.alpha < i.high,
            "{i:?} around {}",
            f.alpha
        );
        assert!(!i.low_at_edge && !i.high_at_edge, "{i:?}");
        covered += usize::from(i.low <= 1.5 && 1.5 <= i.high);
        widths.push(i.high - i.low);
        alphas.push(f.alpha);
    }
    let coverage = covered as f64 / trials as f64;
    assert!((0.90..=0.99).contains(&coverage), "coverage {coverage}");
    // Its width is that of a Gaussian interval of the estimates' own scatter, 2 × 1.96 σ(α̂)
    // (σ from 200 samples: ±10 %; the likelihood's curvature varies from sample to sample).
    let mean = alphas.iter().sum::<f64>() / trials as f64;
    let sd = (alphas.iter().map(|a| (a - mean).powi(2)).sum::<f64>() / (trials - 1) as f64).sqrt();
    widths.sort_by(f64::total_cmp);
    let median = widths[trials / 2];
    eprintln!(
        "coverage {coverage}, median width {median}, 3.92 σ(α̂) = {}",
        3.92 * sd
    );
    assert!(
        (median / (3.92 * sd) - 1.0).abs() < 0.3,
        "median width {median}, σ(α̂) {sd}"
    );
}

#[test]
fn degenerate_samples_are_errors_not_nan() {
    assert_eq!(fit_discrete(&[], 1, None), Err(FitError::Empty));
    assert!(matches!(
        fit_discrete(&[7, 7, 7, 7], 1, Some(100)),
        Err(FitError::TooFewDistinct { distinct: 1 })
    ));
    assert!(matches!(
        fit_discrete(&[3], 1, Some(100)),
        Err(FitError::TooFew { .. })
    ));
    assert!(matches!(
        fit_discrete(&[1, 2, 3, 40], 50, None),
        Err(FitError::LowerAboveMax { .. })
    ));
    assert!(matches!(
        fit_discrete(&[0, 2, 3], 1, None),
        Err(FitError::BadValue(_))
    ));
    assert!(matches!(
        fit_continuous(&[2.0, 2.0, 2.0], 1.0, None),
        Err(FitError::TooFewDistinct { .. })
    ));
    assert!(matches!(
        fit_continuous(&[1.0, f64::NAN], 1.0, None),
        Err(FitError::BadValue(_))
    ));
    assert!(matches!(
        fit_continuous(&[1.5, 2.0, 3.0], 5.0, None),
        Err(FitError::LowerAboveMax { .. })
    ));
    assert!(fit_plateau_power_law(&[5; 100]).is_err());
    assert!(fit_discrete_tail(&[1, 2, 3], None).is_err());
}
