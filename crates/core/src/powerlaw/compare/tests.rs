use rand::RngExt;
use rand_chacha::rand_core::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::*;

/// Neumaier's compensated sum (millions of terms to 1e-15).
fn compensated(terms: impl Iterator<Item = f64>) -> f64 {
    let (mut s, mut c) = (0.0f64, 0.0f64);
    for x in terms {
        let t = s + x;
        c += if s.abs() >= x.abs() {
            (s - t) + x
        } else {
            (x - t) + s
        };
        s = t;
    }
    s + c
}

#[test]
fn cutoff_normalisation_matches_direct_sums() {
    // Direct sums run until λ(j − a) > 40 (the rest below e^(−40) relative).
    for &(alpha, lambda, a) in &[
        (1.5, 1e-3, 1u64),
        (2.5, 1e-2, 10),
        (0.5, 1e-3, 5),
        (3.0, 0.3, 100),
        (1.2, 1e-4, 50),
        (0.1, 2.0, 3),
    ] {
        let end = a + (40.0 / lambda) as u64 + 300;
        let direct = compensated((a..end).map(|j| {
            let x = j as f64;
            (-alpha * (x / a as f64).ln() - lambda * (x - a as f64)).exp()
        }));
        let ours = cutoff_normalisation(alpha, lambda, a);
        assert!(
            ((ours - direct) / direct).abs() < 1e-12,
            "α {alpha}, λ {lambda}, a {a}: {ours} against {direct}"
        );
    }
}

#[test]
fn cutoff_normalisation_tends_to_the_power_laws() {
    for &(alpha, a) in &[(1.8, 1u64), (2.5, 40), (4.0, 300)] {
        let pl = discrete_normalisation(alpha, a, u64::MAX) * (a as f64).powf(alpha);
        let cut = cutoff_normalisation(alpha, (-40.0f64).exp(), a);
        assert!(
            ((cut - pl) / pl).abs() < 1e-10,
            "α {alpha}, a {a}: {cut} against {pl}"
        );
    }
}

/// `Σ_{k=a}^{K} p(k)` plus the mass above `K` must be 1.
fn total_mass(ln_p: &dyn Fn(f64) -> f64, a: u64, end: u64, ln_above: f64) -> f64 {
    compensated((a..=end).map(|k| ln_p(k as f64).exp())) + ln_above.exp()
}

#[test]
fn rounded_pmfs_are_normalised_on_both_sides_of_the_median() {
    // μ puts a − ½ below the median (both branches used) or above it.
    for &(mu, sigma, a) in &[(3.0, 1.5, 2u64), (1.0, 0.7, 20), (6.0, 0.2, 300)] {
        let p = lognormal_ln_pmf(mu, sigma, a as f64);
        let end = 20_000;
        let z = |x: f64| (x.ln() - mu) / (sigma * std::f64::consts::SQRT_2);
        let above = ln_erfc(z(end as f64 + 0.5)) - ln_erfc(z(a as f64 - 0.5));
        let t = total_mass(&p, a, end, above);
        assert!(
            (t - 1.0).abs() < 1e-12,
            "lognormal μ {mu} σ {sigma} a {a}: {t}"
        );
        // Against the plain formula where it is well conditioned.
        let q = |x: f64| 0.5 * libm::erfc(z(x));
        for k in [a, a + 1, a + 7, 2 * a + 50] {
            let plain = (q(k as f64 - 0.5) - q(k as f64 + 0.5)) / q(a as f64 - 0.5);
            let ours = p(k as f64).exp();
            assert!(
                ((ours - plain) / plain).abs() < 1e-10,
                "k {k}: {ours} against {plain}"
            );
        }
    }
    for &(lambda, beta, a) in &[(0.05, 0.5, 1u64), (0.01, 1.3, 10), (0.2, 0.3, 50)] {
        let p = stretched_ln_pmf(lambda, beta, a as f64);
        let end = 200_000;
        let ln_s = |x: f64| -(lambda * x).powf(beta);
        let above = ln_s(end as f64 + 0.5) - ln_s(a as f64 - 0.5);
        let t = total_mass(&p, a, end, above);
        assert!(
            (t - 1.0).abs() < 1e-12,
            "stretched λ {lambda} β {beta}: {t}"
        );
    }
    for &(alpha, lambda, a) in &[(1.5, 0.01, 1u64), (0.5, 0.002, 30)] {
        let p = cutoff_ln_pmf(alpha, lambda, a as f64);
        let t = total_mass(&p, a, a + (45.0 / lambda) as u64, f64::NEG_INFINITY);
        assert!((t - 1.0).abs() < 1e-12, "cut-off α {alpha} λ {lambda}: {t}");
    }
    let p = exponential_ln_pmf(0.01, 7.0);
    let t = total_mass(&p, 7, 7 + 5000, -0.01 * 5001.0);
    assert!((t - 1.0).abs() < 1e-12, "exponential: {t}");
}

#[test]
fn the_extreme_tail_of_erfc_stays_finite_and_continuous() {
    let below = ln_erfc(26.0 - 1e-9);
    let above = ln_erfc(26.0);
    assert!((below - above).abs() < 1e-6, "{below} against {above}");
    assert!(ln_erfc(1e3).is_finite() && ln_erfc(1e3) < -1e6);
    // Far in the lognormal's tail the rounded mass is still positive.
    let p = lognormal_ln_pmf(0.0, 0.1, 1.0);
    assert!(p(1e6).is_finite());
}

/// Samples of each distribution, discrete on `k ≥ a`.
fn sample(alt: Alternative, theta: [f64; 2], a: u64, n: usize, seed: u64) -> Vec<u64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let af = a as f64;
    let exp1 = |rng: &mut ChaCha8Rng| -(1.0 - rng.random::<f64>()).ln();
    let cutoff_table: Vec<f64> = if alt == Alternative::ExponentialCutoff {
        let p = cutoff_ln_pmf(theta[0], theta[1], af);
        let mut total = 0.0;
        (a..a + (45.0 / theta[1]) as u64)
            .map(|k| {
                total += p(k as f64).exp();
                total
            })
            .collect()
    } else {
        Vec::new()
    };
    (0..n)
        .map(|_| match alt {
            Alternative::Exponential => a + (exp1(&mut rng) / theta[0]).floor() as u64,
            Alternative::ExponentialCutoff => {
                // Inverse of the cumulative pmf, tabulated to where λ(k − a) = 45.
                let u = rng.random::<f64>();
                a + cutoff_table.partition_point(|&c| c < u) as u64
            }
            Alternative::Lognormal => loop {
                // Box–Muller; kept when at or above a − ½, then rounded.
                let (u, v) = (1.0 - rng.random::<f64>(), rng.random::<f64>());
                let g = (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos();
                let x = (theta[0] + theta[1] * g).exp();
                if x >= af - 0.5 {
                    break (x + 0.5).floor() as u64;
                }
            },
            Alternative::StretchedExponential => {
                let (l, b) = (theta[0], theta[1]);
                let x = ((l * (af - 0.5)).powf(b) + exp1(&mut rng)).powf(1.0 / b) / l;
                (x + 0.5).floor() as u64
            }
        })
        .collect()
}

#[test]
fn fits_recover_their_parameters_and_are_local_maxima() {
    let cases = [
        (Alternative::Exponential, [0.02, f64::NAN], 5u64),
        (Alternative::ExponentialCutoff, [1.7, 1e-3], 10),
        (Alternative::Lognormal, [3.0, 1.2], 4),
        (Alternative::StretchedExponential, [0.05, 0.6], 2),
    ];
    for (i, &(alt, theta, a)) in cases.iter().enumerate() {
        let data = sample(alt, theta, a, 20_000, 11 + i as u64);
        let c = compare_tail(&data, a).unwrap();
        let t = c
            .tests
            .iter()
            .find_map(|t| t.as_ref().ok().filter(|t| t.alternative == alt))
            .unwrap();
        // No nearby point is likelier (steps of 1e-3 relative in each parameter).
        let tail = build_tail(&data, a);
        let ll = |p: [f64; 2]| -> f64 {
            let f: Box<dyn Fn(f64) -> f64> = match alt {
                Alternative::Exponential => Box::new(exponential_ln_pmf(p[0], a as f64)),
                Alternative::ExponentialCutoff => Box::new(cutoff_ln_pmf(p[0], p[1], a as f64)),
                Alternative::Lognormal => Box::new(lognormal_ln_pmf(p[0], p[1], a as f64)),
                Alternative::StretchedExponential => {
                    Box::new(stretched_ln_pmf(p[0], p[1], a as f64))
                }
            };
            tail.sum(f)
        };
        let best = ll(t.parameters);
        assert!((best - t.loglikelihood).abs() < 1e-6 * best.abs());
        // Each parameter within 4 standard errors of the truth, from the inverse of the
        // observed information (the Hessian of −ln L by central differences).
        let p = t.parameters;
        let se: Vec<f64> = if theta[1].is_nan() {
            let h = 1e-3 * p[0];
            let d2 = (ll([p[0] + h, p[1]]) - 2.0 * best + ll([p[0] - h, p[1]])) / (h * h);
            vec![1.0 / (-d2).sqrt()]
        } else {
            let h = [1e-3 * p[0].abs(), 1e-3 * p[1].abs()];
            let at = |i: f64, j: f64| ll([p[0] + i * h[0], p[1] + j * h[1]]);
            let hxx = (at(1.0, 0.0) - 2.0 * best + at(-1.0, 0.0)) / (h[0] * h[0]);
            let hyy = (at(0.0, 1.0) - 2.0 * best + at(0.0, -1.0)) / (h[1] * h[1]);
            let hxy = (at(1.0, 1.0) - at(1.0, -1.0) - at(-1.0, 1.0) + at(-1.0, -1.0))
                / (4.0 * h[0] * h[1]);
            let det = hxx * hyy - hxy * hxy;
            vec![(-hyy / det).sqrt(), (-hxx / det).sqrt()]
        };
        for (j, se) in se.iter().enumerate() {
            assert!(
                (p[j] - theta[j]).abs() < 4.0 * se,
                "{}: {p:?} against {theta:?}, standard errors {se}",
                alt.name()
            );
        }
        for j in 0..2 {
            if theta[j].is_nan() {
                continue;
            }
            for s in [-1e-3, 1e-3] {
                let mut p = t.parameters;
                p[j] *= 1.0 + s;
                assert!(
                    ll(p) <= best + 1e-7,
                    "{}: {p:?} beats {:?}",
                    alt.name(),
                    t.parameters
                );
            }
        }
    }
}

fn build_tail(data: &[u64], a: u64) -> Tail {
    let mut v = data.to_vec();
    v.sort_unstable();
    Tail::of_sorted(&v, a)
}

#[test]
fn ratio_tests_tell_the_distributions_apart() {
    let get = |c: &TailComparison, alt: Alternative| {
        *c.tests
            .iter()
            .find_map(|t| t.as_ref().ok().filter(|t| t.alternative == alt))
            .unwrap()
    };
    // A lognormal tail: the lognormal is significantly likelier than the power law.
    let data = sample(Alternative::Lognormal, [3.0, 1.0], 10, 20_000, 5);
    let c = compare_tail(&data, 10).unwrap();
    let t = get(&c, Alternative::Lognormal);
    assert!(t.ratio < 0.0 && t.p_value < 1e-3, "{t:?}");
    // A geometric tail: the exponential wins.
    let data = sample(Alternative::Exponential, [0.05, f64::NAN], 10, 5_000, 6);
    let t = get(&compare_tail(&data, 10).unwrap(), Alternative::Exponential);
    assert!(t.ratio < 0.0 && t.p_value < 1e-3, "{t:?}");
    // A power-law tail (a Pareto variate rounded: the discrete power law to O(1/k²) at
    // k ≥ 20): the power law beats the exponential, and the cut-off is not significantly
    // better.
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let data: Vec<u64> = (0..5_000)
        .map(|_| {
            let x = 19.5 * (1.0 - rng.random::<f64>()).powf(-1.0 / 1.2);
            (x + 0.5).floor() as u64
        })
        .collect();
    let c = compare_tail(&data, 20).unwrap();
    let t = get(&c, Alternative::Exponential);
    assert!(t.ratio > 0.0 && t.p_value < 1e-3, "{t:?}");
    let t = get(&c, Alternative::ExponentialCutoff);
    assert!(t.ratio <= 1e-9 && t.p_value > 0.01, "{t:?}");
    assert!((c.alpha - 2.2).abs() < 0.1, "α {}", c.alpha);
    // The nested p-value is Wilks' χ²₁ tail and the normalised ratio R/(σ√n).
    assert!((t.p_value - libm::erfc(t.ratio.abs().sqrt())).abs() < 1e-15);
}
