//! Closed-form K_PL, 𝒦_PL, C and D against adaptive quadrature of p_PL (VALIDATION.md §6).

use wearcoef::analytic::{archard_wear_rate_plastic, ArchardContact, ModelError, PlateauPowerLaw};

/// Adaptive Gauss–Legendre (10 points) of `f` on `[a, b]`: split until the two halves agree
/// with the whole to `rtol` of the running scale.
fn integrate(f: &dyn Fn(f64) -> f64, a: f64, b: f64, rtol: f64) -> f64 {
    const X: [f64; 5] = [
        0.148_874_338_981_631_22,
        0.433_395_394_129_247_2,
        0.679_409_568_299_024_4,
        0.865_063_366_688_984_5,
        0.973_906_528_517_171_7,
    ];
    const W: [f64; 5] = [
        0.295_524_224_714_752_87,
        0.269_266_719_309_996_35,
        0.219_086_362_515_982_04,
        0.149_451_349_150_580_6,
        0.066_671_344_308_688_14,
    ];
    let gl = |a: f64, b: f64| {
        let (m, h) = (0.5 * (a + b), 0.5 * (b - a));
        X.iter()
            .zip(&W)
            .map(|(x, w)| w * (f(m - h * x) + f(m + h * x)))
            .sum::<f64>()
            * h
    };
    fn rec(gl: &dyn Fn(f64, f64) -> f64, a: f64, b: f64, whole: f64, rtol: f64, depth: u32) -> f64 {
        let m = 0.5 * (a + b);
        let (l, r) = (gl(a, m), gl(m, b));
        if depth == 0 || (l + r - whole).abs() <= rtol * (l + r).abs() {
            return l + r;
        }
        rec(gl, a, m, l, rtol, depth - 1) + rec(gl, m, b, r, rtol, depth - 1)
    }
    if b <= a {
        return 0.0;
    }
    rec(&gl, a, b, gl(a, b), rtol, 40)
}

/// `∫_lo^hi A^m (A/A_s)^(−α) dA` on the power-law branch, integrated in `t = ln A` (the
/// integrand is smooth there even when `hi/lo` is 10¹²).
fn power_segment(alpha: f64, a_s: f64, lo: f64, hi: f64, m: i32) -> f64 {
    let f = |t: f64| {
        let a = t.exp();
        a.powi(m) * (a / a_s).powf(-alpha) * a
    };
    integrate(&f, lo.ln(), hi.ln(), 1e-15)
}

/// Reference (K, 𝒦, C, D) by quadrature, split at A_s and A_m.
fn reference(alpha: f64, a_s: f64, a_m: f64, a_star: f64) -> (f64, f64, f64, f64) {
    let plateau =
        |lo: f64, hi: f64, m: i32| integrate(&|a: f64| a.powi(m), lo.min(a_s), hi.min(a_s), 1e-15);
    let mass = plateau(0.0, a_s, 0) + power_segment(alpha, a_s, a_s, a_m, 0);
    let c = 1.0 / mass;
    let d = c * (plateau(0.0, a_s, 1) + power_segment(alpha, a_s, a_s, a_m, 1));
    if a_star >= a_m {
        return (0.0, 0.0, c, d);
    }
    let lo = a_star.max(a_s);
    let k = c * (plateau(a_star, a_s, 0) + power_segment(alpha, a_s, lo, a_m, 0));
    let kk = c * (plateau(a_star, a_s, 1) + power_segment(alpha, a_s, lo, a_m, 1)) / d;
    (k, kk, c, d)
}

const ALPHAS: [f64; 11] = [
    0.5,
    1.0,
    1.0 - 1e-10,
    1.0 + 1e-10,
    1.2,
    1.5,
    2.0,
    2.0 - 1e-10,
    2.0 + 1e-10,
    2.5,
    3.5,
];

#[test]
fn closed_forms_match_quadrature_on_every_branch() {
    let mut checked = 0;
    for &alpha in &ALPHAS {
        for &(a_s, a_m) in &[(2.0, 5000.0), (0.3, 40.0), (1.0, 1e12)] {
            let model = PlateauPowerLaw::new(alpha, a_s, a_m).unwrap();
            // A* on the plateau, at its end, on the power law, at and above the cut-off.
            for &a_star in &[
                0.0,
                0.4 * a_s,
                a_s,
                3.0 * a_s,
                (a_s * a_m).sqrt(),
                0.5 * a_m,
                a_m,
                2.0 * a_m,
            ] {
                let (k, kk, c, d) = reference(alpha, a_s, a_m, a_star);
                let close =
                    |got: f64, want: f64| (got - want).abs() <= 1e-12 * want.abs().max(1e-300);
                assert!(
                    close(model.c(), c),
                    "C α={alpha} A_s={a_s} A_m={a_m}: {} vs {c}",
                    model.c()
                );
                assert!(
                    close(model.first_moment(), d),
                    "D α={alpha}: {} vs {d}",
                    model.first_moment()
                );
                let got_k = model.k_archard(a_star).unwrap();
                let got_kk = model.k_upscaled(a_star).unwrap();
                assert!(
                    close(got_k, k) || (k == 0.0 && got_k == 0.0),
                    "K α={alpha} A_s={a_s} A_m={a_m} A*={a_star}: {got_k} vs {k}"
                );
                assert!(
                    close(got_kk, kk) || (kk == 0.0 && got_kk == 0.0),
                    "𝒦 α={alpha} A_s={a_s} A_m={a_m} A*={a_star}: {got_kk} vs {kk}"
                );
                checked += 1;
            }
        }
    }
    assert_eq!(checked, ALPHAS.len() * 3 * 8);
}

/// VALIDATION.md §6.4: the printed (A.4), D = C (A_s + …), is wrong; the corrected first
/// moment is not that one (this test fails if the misprint is reintroduced).
#[test]
fn first_moment_is_not_the_misprinted_one() {
    let (alpha, a_s, a_m) = (1.5, 1.0, 100.0);
    let model = PlateauPowerLaw::new(alpha, a_s, a_m).unwrap();
    let c = model.c();
    let printed = c
        * (a_s + a_s.powf(alpha) / (2.0 - alpha) * (a_m.powf(2.0 - alpha) - a_s.powf(2.0 - alpha)));
    assert!((model.first_moment() / printed - 0.9737).abs() < 1e-4);
}

#[test]
fn coefficients_are_fractions_decreasing_and_upscaled_dominates() {
    for &alpha in &ALPHAS {
        let model = PlateauPowerLaw::new(alpha, 1.5, 1e6).unwrap();
        let mut prev = (1.0f64, 1.0f64);
        for i in 0..=200 {
            let a_star = 1e-3 * 10f64.powf(i as f64 * 0.05); // 1e-3 … 1e7
            let k = model.k_archard(a_star).unwrap();
            let kk = model.k_upscaled(a_star).unwrap();
            assert!(
                (0.0..=1.0).contains(&k) && (0.0..=1.0).contains(&kk),
                "α={alpha} A*={a_star}"
            );
            assert!(
                k <= prev.0 + 1e-15 && kk <= prev.1 + 1e-15,
                "not decreasing at α={alpha} A*={a_star}"
            );
            // Large clusters carry more than their share of the area (Chebyshev's sum
            // inequality): 𝒦 ≥ K for every A*.
            assert!(kk >= k - 1e-15, "α={alpha} A*={a_star}: 𝒦 {kk} < K {k}");
            prev = (k, kk);
        }
    }
}

#[test]
fn infinite_cut_off_limits_match_a_huge_cut_off() {
    for &alpha in &[0.5, 1.5, 2.5, 3.5] {
        let a_s = 3.0;
        let limit = PlateauPowerLaw::new(alpha, a_s, f64::INFINITY).unwrap();
        let huge = PlateauPowerLaw::new(alpha, a_s, 1e30).unwrap();
        for &a_star in &[0.0, 1.0, 3.0, 30.0, 1e4] {
            let (kl, kh) = (
                limit.k_archard(a_star).unwrap(),
                huge.k_archard(a_star).unwrap(),
            );
            let (ul, uh) = (
                limit.k_upscaled(a_star).unwrap(),
                huge.k_upscaled(a_star).unwrap(),
            );
            assert!(
                (kl - kh).abs() <= 1e-12 * kl.max(1e-300),
                "K α={alpha} A*={a_star}: {kl} vs {kh}"
            );
            assert!(
                (ul - uh).abs() <= 1e-12 * ul.max(1e-300),
                "𝒦 α={alpha} A*={a_star}: {ul} vs {uh}"
            );
        }
    }
    // VALIDATION.md §6.6 examples at A_s = 3, A* = 30.
    let m = PlateauPowerLaw::new(1.5, 3.0, f64::INFINITY).unwrap();
    assert!((m.k_archard(30.0).unwrap() - 0.210_818_5).abs() < 1e-7);
    assert_eq!(m.k_upscaled(30.0).unwrap(), 1.0);
    let m = PlateauPowerLaw::new(2.5, 3.0, f64::INFINITY).unwrap();
    assert!((m.k_archard(30.0).unwrap() - 0.012_649_11).abs() < 1e-8);
    assert!((m.k_upscaled(30.0).unwrap() - 0.252_982_2).abs() < 1e-7);
}

#[test]
fn near_singular_exponents_are_continuous() {
    // The naive (A.3) loses 7 digits at α = 1 + 1e-10 (VALIDATION.md §6.7); the stable
    // form agrees with α = 1 exactly to within the O(1e-10) change of the function.
    for &(a, b) in &[
        (1.0, 1.0 + 1e-10),
        (1.0, 1.0 - 1e-10),
        (2.0, 2.0 + 1e-10),
        (2.0, 2.0 - 1e-10),
    ] {
        let (m1, m2) = (
            PlateauPowerLaw::new(a, 2.0, 5000.0).unwrap(),
            PlateauPowerLaw::new(b, 2.0, 5000.0).unwrap(),
        );
        for &a_star in &[1.0, 2.0, 50.0, 4000.0] {
            assert!((m1.k_archard(a_star).unwrap() - m2.k_archard(a_star).unwrap()).abs() < 1e-8);
            assert!((m1.k_upscaled(a_star).unwrap() - m2.k_upscaled(a_star).unwrap()).abs() < 1e-8);
        }
    }
    // VALIDATION.md §6.5 golden value.
    let m = PlateauPowerLaw::new(1.0, 2.0, 5000.0).unwrap();
    assert!((m.k_archard(1.0).unwrap() - 0.943_336_650_853_265).abs() < 1e-14);
}

#[test]
fn invalid_parameters_are_errors() {
    assert_eq!(
        PlateauPowerLaw::new(1.5, 0.0, 10.0),
        Err(ModelError::PlateauEnd(0.0))
    );
    assert!(matches!(
        PlateauPowerLaw::new(1.5, 2.0, 1.0),
        Err(ModelError::CutOff { .. })
    ));
    assert!(matches!(
        PlateauPowerLaw::new(f64::NAN, 2.0, 10.0),
        Err(ModelError::Alpha(_))
    ));
    assert!(matches!(
        PlateauPowerLaw::new(1.5, 2.0, f64::NAN),
        Err(ModelError::CutOff { .. })
    ));
    let m = PlateauPowerLaw::new(1.5, 2.0, 10.0).unwrap();
    assert_eq!(m.k_archard(-1.0), Err(ModelError::Threshold(-1.0)));
    assert!(m.k_upscaled(f64::INFINITY).is_err());
}

/// Eq. (2) against the sum over the sphere population done by quadrature: summits spread
/// uniformly in depth, each carrying `b z` of area and `c z^p` of load at interference `z`.
#[test]
fn archard_contact_area_matches_quadrature_over_the_spheres() {
    for model in [
        ArchardContact::elastic(2.0e-6, 200e9, 3.0e7),
        ArchardContact::plastic(2.0e-6, 3.0e9, 3.0e7),
    ] {
        for &delta in &[1e-9, 3.7e-8, 5e-7] {
            let area = integrate(&|z: f64| model.b * z * model.d, 0.0, delta, 1e-15);
            let load = integrate(
                &|z: f64| model.c * z.powf(model.p) * model.d,
                0.0,
                delta,
                1e-15,
            );
            let got = model.contact_area(load);
            assert!(
                (got / area - 1.0).abs() < 1e-12,
                "p = {}: {got} vs {area}",
                model.p
            );
        }
    }
    // Rigid-plastic: eq. (2) reduces to eq. (3), A_c = W/𝓗.
    let (h, w) = (3.0e9, 42.0);
    let plastic = ArchardContact::plastic(5e-6, h, 1e8);
    let (k, omega) = (1e-4, 1.0 / 3.0);
    let r = plastic.wear_rate(k, omega, w);
    assert!((r / archard_wear_rate_plastic(omega, k, w, h) - 1.0).abs() < 1e-14);
    // Elastic: A_c ∝ W^(4/5), not linear (the paper's point about Archard's model).
    let elastic = ArchardContact::elastic(5e-6, 200e9, 1e8);
    let ratio = elastic.contact_area(2.0 * w) / elastic.contact_area(w);
    assert!((ratio - 2f64.powf(0.8)).abs() < 1e-14);
}

/// Areas spanning more than the doubles' range (A_s = 1e-300, A_m = 1e300: A_m/A_s
/// overflows) stay exact: against quadrature in u = ln(A/A_s), with both integrals scaled
/// by exp(−e ℓ) when the exponent e grows (so the reference never overflows either).
#[test]
fn areas_spanning_more_than_the_double_range_stay_exact() {
    let (a_s, a_m) = (1e-300_f64, 1e300_f64);
    let ell = a_m.ln() - a_s.ln();
    // Fraction above A* of the e-th tail, (plateau mass `p`): reference by quadrature.
    // Composite 10-point Gauss–Legendre on panels of width ≤ 0.5/|e| (e·width ≤ ½: the
    // exponential is resolved to rounding on each panel).
    let composite = |f: &dyn Fn(f64) -> f64, a: f64, b: f64, e: f64| {
        let panels = ((b - a) * 2.0 * e.abs().max(1.0)).ceil().max(1.0) as usize;
        let h = (b - a) / panels as f64;
        (0..panels)
            .map(|i| integrate(f, a + i as f64 * h, a + (i + 1) as f64 * h, 1.0))
            .sum::<f64>()
    };
    let reference = |e: f64, a_star: f64, p: f64| {
        let lo = a_star.ln() - a_s.ln();
        let shift = if e > 0.0 { e * ell } else { 0.0 };
        let f = |u: f64| (e * u - shift).exp();
        let num = composite(&f, lo, ell, e);
        let den = p * (-shift).exp() + composite(&f, 0.0, ell, e);
        num / den
    };
    let mut checked = 0;
    for &alpha in &[-3.0, 0.5, 1.0, 1.0 + 1e-7, 1.5, 2.0, 2.0 - 1e-7, 2.5, 4.0] {
        let model = PlateauPowerLaw::new(alpha, a_s, a_m).unwrap();
        for &a_star in &[1e-250, 1.0, 1e250] {
            let k = model.k_archard(a_star).unwrap();
            let kk = model.k_upscaled(a_star).unwrap();
            let (want_k, want_kk) = (
                reference(1.0 - alpha, a_star, 1.0),
                reference(2.0 - alpha, a_star, 0.5),
            );
            for (name, got, want) in [("K", k, want_k), ("𝒦", kk, want_kk)] {
                assert!(
                    got.is_finite() && (0.0..=1.0).contains(&got),
                    "{name} α={alpha} A*={a_star}: {got}"
                );
                assert!(
                    (got - want).abs() <= 1e-10 * want.abs() || (got - want).abs() < 1e-300,
                    "{name} α={alpha} A*={a_star}: {got} vs quadrature {want}"
                );
            }
            checked += 1;
        }
    }
    assert_eq!(checked, 27);
}
