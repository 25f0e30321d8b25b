//! Surface generation against its specification (VALIDATION.md §4).

use wearcoef::grid::Grid;
use wearcoef::spectral::Fft2;
use wearcoef::surface::{self, Method, SurfaceParams};

fn params(
    n: usize,
    lambda_l_px: f64,
    lambda_s_px: f64,
    hurst: f64,
    method: Method,
    seed: u64,
) -> SurfaceParams {
    SurfaceParams {
        n,
        hurst,
        lambda_l_px,
        lambda_s_px,
        rolloff_lambda_px: None,
        method,
        seed,
    }
}

fn generate(p: &SurfaceParams) -> surface::Surface {
    let fft = Fft2::new(p.n);
    let mut scratch = fft.make_scratch();
    surface::generate(p, &fft, &mut scratch).expect("valid parameters")
}

/// k ∈ [4, 128] on 512² (1.5 decades): filtered surface within 0.03 of H.
#[test]
fn filtered_surface_recovers_hurst_exponent() {
    for (seed, hurst) in [(1u64, 0.8), (2, 0.5)] {
        let s = generate(&params(512, 128.0, 4.0, hurst, Method::Filter, seed));
        let fit = s.stats.hurst_fit.expect("band has many shells");
        assert!((fit - hurst).abs() <= 0.03, "H = {hurst}: fitted {fit}");
    }
}

#[test]
fn random_phase_surface_recovers_hurst_exponent_tightly() {
    for hurst in [0.3, 0.8] {
        let s = generate(&params(512, 128.0, 4.0, hurst, Method::RandomPhase, 3));
        let fit = s.stats.hurst_fit.expect("band has many shells");
        assert!((fit - hurst).abs() <= 0.005, "H = {hurst}: fitted {fit}");
    }
}

#[test]
fn unit_rms_slope_and_zero_mean() {
    for method in [Method::Filter, Method::RandomPhase] {
        let s = generate(&params(256, 64.0, 8.0, 0.8, method, 11));
        assert!(
            (s.stats.rms_slope - 1.0).abs() <= 1e-12,
            "{method:?}: slope {}",
            s.stats.rms_slope
        );
        assert!(
            s.stats.mean_height.abs() <= 1e-12,
            "{method:?}: mean {}",
            s.stats.mean_height
        );
        // Independent check of the slope: finite differences are biased low by the sinc
        // factor of each mode (VALIDATION §4.1: 0.9955 for λ_s = 8Δ); for λ_s = 8Δ the
        // central-difference slope lies within a few percent below the spectral one.
        let n = 256;
        let dx = 1.0 / n as f64;
        let mut sum = 0.0;
        for i in 0..n {
            for j in 0..n {
                let h = |a: usize, b: usize| s.heights[(a % n) * n + (b % n)];
                let gx = (h(i, j + 1) - h(i, j + n - 1)) / (2.0 * dx);
                let gy = (h(i + 1, j) - h(i + n - 1, j)) / (2.0 * dx);
                sum += gx * gx + gy * gy;
            }
        }
        let fd = (sum / (n * n) as f64).sqrt();
        assert!(
            fd < 1.0 && fd > 0.93,
            "{method:?}: central-difference slope {fd}"
        );
    }
}

#[test]
fn no_energy_outside_the_band() {
    let p = params(128, 32.0, 8.0, 0.7, Method::Filter, 5);
    let s = generate(&p);
    let grid = Grid::unit(128).unwrap();
    let fft = Fft2::new(128);
    let mut scratch = fft.make_scratch();
    let mut spec = fft.make_spectrum();
    fft.forward(&s.heights, &mut spec, &mut scratch);
    let (k_l, k_s) = (p.k_l(), p.k_s());
    let max = spec.iter().map(|c| c.norm_sqr()).fold(0.0, f64::max);
    let mut inside = 0;
    for jx in 0..grid.half_len() {
        for iy in 0..128 {
            let k = grid.k_norm(jx, iy);
            let power = spec[jx * 128 + iy].norm_sqr();
            if k < k_l * (1.0 - 1e-9) || k > k_s * (1.0 + 1e-9) {
                assert!(
                    power <= 1e-26 * max,
                    "mode |k| = {k} outside [{k_l}, {k_s}] has power {power:e}"
                );
            } else if power > 0.0 {
                inside += 1;
            }
        }
    }
    assert!(inside > 100, "the band must carry the energy");
}

#[test]
fn rolloff_fills_the_plateau_flat() {
    let mut p = params(256, 32.0, 4.0, 0.8, Method::RandomPhase, 9);
    p.rolloff_lambda_px = Some(128.0);
    let s = generate(&p);
    let grid = Grid::unit(256).unwrap();
    let fft = Fft2::new(256);
    let mut scratch = fft.make_scratch();
    let mut spec = fft.make_spectrum();
    fft.forward(&s.heights, &mut spec, &mut scratch);
    let shells = surface::radial_psd(&grid, &spec);
    // Plateau between k_r = 2 and k_l = 8: equal power per mode (random phase = exact amplitude).
    let plateau: Vec<f64> = (3..=7).map(|k| shells[k].2).collect();
    for v in &plateau {
        assert!(
            (v / plateau[0] - 1.0).abs() < 1e-9,
            "plateau not flat: {plateau:?}"
        );
    }
    // Below the roll-off wavelength only rounding noise remains (|H|² ~ (1e-16)² relative).
    assert!(
        shells[1].2 <= 1e-24 * plateau[0],
        "PSD below k_r: {} vs plateau {}",
        shells[1].2,
        plateau[0]
    );
}

#[test]
fn identical_bytes_for_one_and_two_threads() {
    let p = params(512, 64.0, 8.0, 0.8, Method::Filter, 42);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| generate(&p));
    let two = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap()
        .install(|| generate(&p));
    let bits = |s: &surface::Surface| s.heights.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&one), bits(&two));
    assert_eq!(one.stats, two.stats);
}

#[test]
fn seeds_give_different_surfaces_and_realization_seeds_are_distinct() {
    let a = generate(&params(64, 32.0, 4.0, 0.8, Method::Filter, 1));
    let b = generate(&params(64, 32.0, 4.0, 0.8, Method::Filter, 2));
    assert_ne!(a.heights, b.heights);
    let seeds: std::collections::BTreeSet<u64> =
        (0..1000).map(|i| surface::realization_seed(5, i)).collect();
    assert_eq!(seeds.len(), 1000);
    assert_ne!(
        surface::realization_seed(5, 0),
        surface::realization_seed(6, 0)
    );
}

#[test]
fn invalid_parameters_name_their_field() {
    let ok = params(64, 32.0, 4.0, 0.8, Method::Filter, 1);
    let cases: Vec<(SurfaceParams, &str)> = vec![
        (
            SurfaceParams {
                hurst: 1.0,
                ..ok.clone()
            },
            "hurst",
        ),
        (
            SurfaceParams {
                hurst: 0.0,
                ..ok.clone()
            },
            "hurst",
        ),
        (
            SurfaceParams {
                hurst: f64::NAN,
                ..ok.clone()
            },
            "hurst",
        ),
        (
            SurfaceParams {
                lambda_s_px: 1.5,
                ..ok.clone()
            },
            "lambda_s_px",
        ),
        (
            SurfaceParams {
                lambda_l_px: 128.0,
                ..ok.clone()
            },
            "lambda_l_px",
        ),
        (
            SurfaceParams {
                lambda_l_px: 3.0,
                ..ok.clone()
            },
            "lambda_l_px",
        ),
        (
            SurfaceParams {
                n: 63,
                ..ok.clone()
            },
            "n",
        ),
        (
            SurfaceParams {
                rolloff_lambda_px: Some(16.0),
                ..ok.clone()
            },
            "rolloff_lambda_px",
        ),
    ];
    for (p, field) in cases {
        let err = p.validate().expect_err("invalid");
        assert_eq!(err.field, field, "{p:?}");
    }
    assert!(ok.validate().is_ok());
}

/// λ_s at the Nyquist limit (2Δl) is allowed and still gives a real, unit-slope field.
#[test]
fn coarsest_allowed_lambda_s_works() {
    let s = generate(&params(64, 16.0, 2.0, 0.8, Method::Filter, 4));
    assert!((s.stats.rms_slope - 1.0).abs() < 1e-12);
    assert!(s.heights.iter().all(|v| v.is_finite()));
}
