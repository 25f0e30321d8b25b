use std::f64::consts::PI;
use wearcoef::contact::elastic::ElasticOperator;
use wearcoef::contact::reference::{Hertz, Westergaard};
use wearcoef::contact::solver::{Ceiling, Solver, Status};
use wearcoef::grid::Grid;

#[allow(unused_imports)]
use super::*;

/// The Hertz contact of radius `a_target` of a paraboloid (R = 1, E* = 1) on an `n` grid of
/// the unit box: the reference and the heights.
fn hertz_case(n: usize, a_target: f64) -> (Hertz, Vec<f64>) {
    let (r_curv, e_star) = (1.0, 1.0);
    let load = 4.0 * a_target.powi(3) * e_star / (3.0 * r_curv);
    let hertz = Hertz {
        load,
        r_curv,
        e_star,
    };
    (hertz, paraboloid(n, r_curv))
}

/// A solved Hertz pressure `p` (`contact` nodes in contact) against `hertz`: contact radius
/// within 2 %, peak within 0.5 %, profile within 1.5 % (relative L2). Returns the largest
/// |Δp|/p0 inside 0.9 a.
fn check_hertz(p: &[f64], contact: usize, n: usize, hertz: &Hertz) -> f64 {
    let dx = 1.0 / n as f64;
    let a = hertz.contact_radius();
    let a_num = (contact as f64 * dx * dx / PI).sqrt();
    assert!(
        (a_num / a - 1.0).abs() <= 0.02,
        "contact radius {a_num} vs {a}"
    );
    let p_max = p.iter().cloned().fold(0.0, f64::max);
    assert!(
        (p_max / hertz.peak_pressure() - 1.0).abs() <= 0.005,
        "peak {p_max} vs {}",
        hertz.peak_pressure()
    );
    let (mut num, mut den, mut inner) = (0.0, 0.0, 0.0f64);
    for (i, pi) in p.iter().enumerate() {
        let (y, x) = (
            ((i / n) as f64 - (n / 2) as f64) * dx,
            ((i % n) as f64 - (n / 2) as f64) * dx,
        );
        let r = (x * x + y * y).sqrt();
        let exact = hertz.pressure(r);
        num += (pi - exact).powi(2);
        den += exact * exact;
        if r < 0.9 * a {
            inner = inner.max((pi - exact).abs() / hertz.peak_pressure());
        }
    }
    let l2 = (num / den).sqrt();
    assert!(l2 <= 0.015, "relative L2 {l2}");
    inner
}

#[test]
fn hertz_on_a_periodic_grid() {
    for pre in VARIANTS {
        // L/a = 10, a/Δ = 25.6 (VALIDATION §3a row N = 256).
        let n = 256;
        let (hertz, h) = hertz_case(n, 0.1);
        let op = ElasticOperator::new(Grid::unit(n).unwrap(), hertz.e_star);
        let mut solver = Solver::new(&op, &h).unwrap();
        let report = solver.solve(hertz.load, &cfgp(pre, 1e-12)).unwrap();
        assert_eq!(report.status, Status::Converged, "{report:?}");
        let inner = check_hertz(solver.pressure(), solver.contact_count(), n, &hertz);
        assert!(inner <= 0.005, "max |Δp|/p0 inside 0.9a: {inner}");
    }
}

/// Hertz on the free-boundary half-space (`PaddedOperator`): a contact of radius 0.3 L,
/// where the periodic images of the periodic operator would press on it. Contact radius,
/// peak pressure and the pressure profile within the periodic Hertz test's tolerances, and
/// the approach δ = a²/R (the absolute deflection at the centre, which only a non-periodic
/// half-space defines) within 1 %: the grid resolves a by 38 cells.
#[test]
fn hertz_on_the_free_boundary_half_space() {
    use wearcoef::contact::padded::PaddedOperator;
    use wearcoef::contact::solver::{NonNegative, Operator};
    for pre in VARIANTS {
        let n = 128;
        let (hertz, h) = hertz_case(n, 0.3);
        let op = PaddedOperator::new(Grid::unit(n).unwrap(), hertz.e_star);
        let mut solver = Solver::with_constraint(&op, &h, NonNegative).unwrap();
        let report = solver.solve(hertz.load, &cfgp(pre, 1e-12)).unwrap();
        assert_eq!(report.status, Status::Converged, "{report:?}");
        let p = solver.pressure().to_vec();
        check_hertz(&p, solver.contact_count(), n, &hertz);
        let mut u = vec![0.0; n * n];
        op.apply(&p, &mut u, &mut op.make_workspace());
        let (a, approach) = (hertz.contact_radius(), u[(n / 2) * n + n / 2]);
        assert!(
            (approach / (a * a / hertz.r_curv) - 1.0).abs() <= 0.01,
            "approach {approach} vs {}",
            a * a / hertz.r_curv
        );
    }
}

fn westergaard_surface(n: usize, h0: f64) -> Vec<f64> {
    (0..n * n)
        .map(|i| h0 * (2.0 * PI * (i % n) as f64 / n as f64).cos())
        .collect()
}

#[test]
fn westergaard_partial_contact() {
    for pre in VARIANTS {
        for (n, ratio) in [(256usize, 0.1), (256, 0.5), (512, 0.3), (256, 0.8)] {
            let w = Westergaard {
                amplitude: 0.01,
                wavelength: 1.0,
                e_star: 1.0,
            };
            let mean = ratio * w.full_contact_pressure();
            let h = westergaard_surface(n, w.amplitude);
            let op = ElasticOperator::new(Grid::unit(n).unwrap(), w.e_star);
            let mut solver = Solver::new(&op, &h).unwrap();
            let report = solver.solve(mean, &cfgp(pre, 1e-12)).unwrap();
            assert!(report.converged(), "{report:?}");
            let p = &solver.pressure()[..n]; // one row: the field is invariant along y
            for row in 1..n {
                assert_eq!(
                    &solver.pressure()[row * n..(row + 1) * n],
                    p,
                    "rows must agree"
                );
            }
            let dx = 1.0 / n as f64;
            let (mut num, mut den) = (0.0, 0.0);
            for (j, pj) in p.iter().enumerate() {
                let exact = w.pressure(j as f64 * dx, mean);
                num += (pj - exact).powi(2);
                den += exact * exact;
            }
            let l2 = (num / den).sqrt();
            assert!(l2 <= 0.006, "N = {n}, p̄/p* = {ratio}: L2 {l2}");
            let width = p.iter().filter(|&&v| v > 0.0).count() as f64 * dx;
            let exact_width = 2.0 * w.half_width(mean);
            assert!(
                (width - exact_width).abs() <= 2.0 * dx,
                "N = {n}: width {width} vs {exact_width}"
            );
            let p_max = p.iter().cloned().fold(0.0, f64::max);
            let exact_max = w.pressure(0.0, mean);
            assert!(
                (p_max / exact_max - 1.0).abs() <= 1e-3,
                "peak {p_max} vs {exact_max}"
            );
        }
    }
}

#[test]
fn westergaard_full_contact_is_exact() {
    for pre in VARIANTS {
        let n = 128;
        let w = Westergaard {
            amplitude: 0.01,
            wavelength: 1.0,
            e_star: 2.0,
        };
        let mean = 1.2 * w.full_contact_pressure();
        let h = westergaard_surface(n, w.amplitude);
        let op = ElasticOperator::new(Grid::unit(n).unwrap(), w.e_star);
        let mut solver = Solver::new(&op, &h).unwrap();
        let report = solver.solve(mean, &cfgp(pre, 1e-12)).unwrap();
        assert!(report.converged());
        for (i, p) in solver.pressure().iter().enumerate() {
            let exact = w.pressure((i % n) as f64 / n as f64, mean);
            assert!(
                (p - exact).abs() <= 1e-12 * mean,
                "node {i}: {p} vs {exact}"
            );
        }
        assert_eq!(solver.contact_count(), n * n);
    }
}

/// Westergaard's sinusoid in full contact under a ceiling `p_max` below its elastic peak
/// (docs/VALIDATION.md, a sinusoid with a ceiling): the crest saturates and
/// `p(x) = p_max − p_W(x − λ/2)`, with `p_W` Westergaard's partial-contact pressure of mean
/// `p_max − p̄` centred on the trough, valid while `p_max ≥ 2 √(p* (p_max − p̄))` (no node
/// leaves contact). The saturated arc is `λ − 2a`, `a` Westergaard's half-width. Tolerances
/// as for the partial-contact case, whose discretisation error this shares.
#[test]
fn westergaard_full_contact_under_a_ceiling() {
    let w = Westergaard {
        amplitude: 0.01,
        wavelength: 1.0,
        e_star: 1.0,
    };
    let p_star = w.full_contact_pressure();
    for pre in VARIANTS {
        for (n, max, mean) in [(256usize, 1.0, 0.9), (256, 1.5, 1.0), (512, 2.0, 1.9)] {
            let (max, mean) = (max * p_star, mean * p_star);
            assert!(max >= 2.0 * (p_star * (max - mean)).sqrt());
            let h = westergaard_surface(n, w.amplitude);
            let op = ElasticOperator::new(Grid::unit(n).unwrap(), w.e_star);
            let mut solver = Solver::with_constraint(&op, &h, Ceiling::new(max).unwrap()).unwrap();
            let report = solver.solve(mean, &cfgp(pre, 1e-12)).unwrap();
            assert!(report.converged(), "{report:?}");
            let p = &solver.pressure()[..n];
            for row in 1..n {
                assert_eq!(
                    &solver.pressure()[row * n..(row + 1) * n],
                    p,
                    "rows must agree"
                );
            }
            let dx = 1.0 / n as f64;
            let exact: Vec<f64> = (0..n)
                .map(|j| max - w.pressure(j as f64 * dx - 0.5, max - mean))
                .collect();
            let (mut num, mut den) = (0.0, 0.0);
            for (pj, e) in p.iter().zip(&exact) {
                num += (pj - e).powi(2);
                den += (max - e).powi(2);
            }
            let l2 = (num / den).sqrt();
            assert!(l2 <= 0.006, "N = {n}, p_max/p* = {}: L2 {l2}", max / p_star);
            let saturated = p.iter().filter(|&&v| v == max).count() as f64 * dx;
            let exact_saturated = 1.0 - 2.0 * w.half_width(max - mean);
            assert!(
                (saturated - exact_saturated).abs() <= 2.0 * dx,
                "N = {n}: saturated arc {saturated} vs {exact_saturated}"
            );
            assert_eq!(solver.contact_count(), n * n, "full contact");
            let lowest = p.iter().cloned().fold(f64::INFINITY, f64::min);
            let exact_lowest = max - w.pressure(0.0, max - mean);
            assert!(
                (lowest / exact_lowest - 1.0).abs() <= 2e-3,
                "trough {lowest} vs {exact_lowest}"
            );
        }
    }
}

#[test]
fn westergaard_mean_gap() {
    for pre in VARIANTS {
        let n = 512;
        let w = Westergaard {
            amplitude: 0.01,
            wavelength: 1.0,
            e_star: 1.0,
        };
        let h = westergaard_surface(n, w.amplitude);
        let op = ElasticOperator::new(Grid::unit(n).unwrap(), w.e_star);
        let mut solver = Solver::new(&op, &h).unwrap();
        for ratio in [0.2, 0.5] {
            let mean = ratio * w.full_contact_pressure();
            assert!(solver.solve(mean, &cfgp(pre, 1e-12)).unwrap().converged());
            let gap = solver.gap().sum::<f64>() / (n * n) as f64;
            let exact = w.mean_gap_over_2h0(mean) * 2.0 * w.amplitude;
            // VALIDATION §1.3: 1e-6 of 2h0 at N = 1024; at N = 512 the discretisation error is
            // about four times larger.
            assert!(
                (gap - exact).abs() <= 1e-5 * 2.0 * w.amplitude,
                "p̄/p* = {ratio}: {gap} vs {exact}"
            );
        }
    }
}

#[test]
fn eggbox_full_contact_threshold() {
    for pre in VARIANTS {
        let n = 128;
        let (d, e_star) = (0.01, 1.0);
        let k = 2.0 * PI;
        let h: Vec<f64> = (0..n * n)
            .map(|i| {
                let (y, x) = ((i / n) as f64 / n as f64, (i % n) as f64 / n as f64);
                d * (k * x).cos() * (k * y).cos()
            })
            .collect();
        let p_star = 2f64.sqrt() * PI * e_star * d; // λ = L = 1
        let op = ElasticOperator::new(Grid::unit(n).unwrap(), e_star);
        let mut solver = Solver::new(&op, &h).unwrap();
        assert!(solver
            .solve(1.02 * p_star, &cfgp(pre, 1e-12))
            .unwrap()
            .converged());
        assert_eq!(
            solver.contact_count(),
            n * n,
            "above p* the contact is complete"
        );
        for (i, p) in solver.pressure().iter().enumerate() {
            let (y, x) = ((i / n) as f64 / n as f64, (i % n) as f64 / n as f64);
            let exact = 1.02 * p_star + p_star * (k * x).cos() * (k * y).cos();
            assert!((p - exact).abs() <= 1e-12 * p_star, "{p} vs {exact}");
        }
        assert!(solver
            .solve(0.98 * p_star, &cfgp(pre, 1e-12))
            .unwrap()
            .converged());
        let fraction = solver.contact_count() as f64 / (n * n) as f64;
        assert!(
            fraction < 1.0 && fraction > 0.95,
            "below p* the contact is partial: {fraction}"
        );
    }
}
