use rand::RngExt;
use rand_chacha::rand_core::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::fit::*;
use super::sums::{continuous_log_stats, moments};
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
    for &alpha in &[-5.0, -3.0, -0.5, 0.0, 0.999, 1.0, 1.5, 2.0, 2.7, 6.0, 10.0] {
        for &(a, b) in &[
            (1u64, 3000u64),
            (127, 128),
            (120, 150),
            (128, 151),
            (128, 152),
            (60, 300),
            (70, 20_757),
            (2, 20_757),
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

/// The KS scan's candidates: all of them when few; else at most the maximum, the smallest
/// kept, each kept value one grid step (in ln k) above the previous, and every small area
/// kept (they are sparser than the grid).
#[test]
fn candidates_thin_to_a_logarithmic_grid() {
    let few: Vec<u64> = (1..=80).collect();
    assert_eq!(thin_to_log_grid(&few, MAX_CANDIDATES), few);
    let many: Vec<u64> = (1..=100_000).step_by(7).collect();
    let kept = thin_to_log_grid(&many, MAX_CANDIDATES);
    assert!(
        kept.len() <= MAX_CANDIDATES && kept.len() > MAX_CANDIDATES / 2,
        "{}",
        kept.len()
    );
    assert_eq!(kept[0], 1);
    let step = ((99_996f64).ln() - 0.0) / (MAX_CANDIDATES - 1) as f64;
    assert!(kept
        .windows(2)
        .all(|w| (w[1] as f64).ln() - (w[0] as f64).ln() >= step - 1e-12));
    assert!(kept[..5] == [1, 8, 15, 22, 29]);
}

/// Clauset's goodness of fit: a sample drawn from a truncated discrete power law above a
/// uniform head (3000 values) is not rejected (p well above 0.1), a lognormal sample of 10⁴ is
/// (p ≤ 0.1: its curvature in log–log shows once the KS scan has to fit 50 or more
/// points of its tail); the p-value is the same on one thread and on several.
#[test]
fn goodness_of_fit_tells_a_power_law_from_a_lognormal() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    // Head uniform on 1..20, tail k^(−1.6) on [20, 5000] by inverse transform.
    let power: Vec<u64> = (0..3000)
        .map(|_| {
            if rng.random::<f64>() < 0.3 {
                rng.random_range(1..20)
            } else {
                let (lo, hi, e) = (20f64, 5000f64, -0.6f64);
                let u = rng.random::<f64>();
                ((lo.powf(e) + u * (hi.powf(e) - lo.powf(e))).powf(1.0 / e)).floor() as u64
            }
        })
        .collect();
    let lognormal: Vec<u64> = (0..10_000)
        .map(|_| {
            // Box–Muller: ln k ~ N(4, 0.8²).
            let (u, v) = (rng.random::<f64>().max(1e-300), rng.random::<f64>());
            let z = (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos();
            (4.0 + 0.8 * z).exp().ceil() as u64
        })
        .collect();
    let p_of = |d: &[u64]| {
        let fit = fit_tail_at_max(d).unwrap().fit;
        goodness_of_fit(d, &fit, 100, 9).unwrap().p_value
    };
    let p_power = p_of(&power);
    let p_lognormal = p_of(&lognormal);
    eprintln!("power law p = {p_power}, lognormal p = {p_lognormal}");
    assert!(p_power > 0.2, "power law p = {p_power}");
    assert!(p_lognormal <= REJECT_AT, "lognormal p = {p_lognormal}");
    let fit = fit_tail_at_max(&power).unwrap().fit;
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    assert_eq!(
        one.install(|| goodness_of_fit(&power, &fit, 100, 9)),
        goodness_of_fit(&power, &fit, 100, 9)
    );
}
