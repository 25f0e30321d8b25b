//! Contact solver against analytic solutions (VALIDATION.md §3) and its defined behaviour
//! where the method breaks down (§2.4).

use std::f64::consts::PI;

use wearcoef::contact::elastic::ElasticOperator;
use wearcoef::contact::reference::{Hertz, Westergaard};
use wearcoef::contact::solver::{Ceiling, ContactError, Solver, SolverConfig, Status};
use wearcoef::grid::Grid;
use wearcoef::spectral::Fft2;
use wearcoef::surface::{self, Method, SurfaceParams};

fn cfg(tol: f64) -> SolverConfig {
    SolverConfig {
        tolerance: tol,
        ..SolverConfig::default()
    }
}

/// Both solver variants: plain and preconditioned (`SolverConfig::preconditioned`). The
/// analytic checks and the defined behaviour below hold for each.
const VARIANTS: [bool; 2] = [false, true];

fn cfgp(preconditioned: bool, tol: f64) -> SolverConfig {
    SolverConfig {
        tolerance: tol,
        preconditioned,
        ..SolverConfig::default()
    }
}

/// ‖a − b‖ / ‖b‖ (Euclidean).
fn relative_l2(a: &[f64], b: &[f64]) -> f64 {
    let norm: f64 = b.iter().map(|v| v * v).sum::<f64>().sqrt();
    let diff: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f64>()
        .sqrt();
    diff / norm
}

/// Complementarity error recomputed independently of the solver from its pressure.
fn independent_error(op: &ElasticOperator, h: &[f64], p: &[f64]) -> f64 {
    let n = op.grid().n();
    let mut ws = op.make_workspace();
    let mut u = vec![0.0; n * n];
    op.apply(p, &mut u, &mut ws);
    let g: Vec<f64> = u.iter().zip(h).map(|(u, h)| u - h).collect();
    let min = g.iter().cloned().fold(f64::INFINITY, f64::min);
    let mean_h = h.iter().sum::<f64>() / h.len() as f64;
    let std_h = (h.iter().map(|v| (v - mean_h).powi(2)).sum::<f64>() / h.len() as f64).sqrt();
    let sum_p: f64 = p.iter().sum();
    p.iter().zip(&g).map(|(p, g)| p * (g - min)).sum::<f64>() / (sum_p * std_h)
}

fn rough_surface(n: usize, lambda_l_px: f64, lambda_s_px: f64, seed: u64) -> Vec<f64> {
    let fft = Fft2::new(n);
    let mut scratch = fft.make_scratch();
    let p = SurfaceParams {
        n,
        hurst: 0.8,
        lambda_l_px,
        lambda_s_px,
        rolloff_lambda_px: None,
        method: Method::Filter,
        seed,
    };
    surface::generate(&p, &fft, &mut scratch).unwrap().heights
}

/// Paraboloid h = −r²/(2R) centred on node (n/2, n/2) of a unit cell.
fn paraboloid(n: usize, r_curv: f64) -> Vec<f64> {
    let dx = 1.0 / n as f64;
    (0..n * n)
        .map(|i| {
            let (y, x) = (
                ((i / n) as f64 - (n / 2) as f64) * dx,
                ((i % n) as f64 - (n / 2) as f64) * dx,
            );
            -(x * x + y * y) / (2.0 * r_curv)
        })
        .collect()
}

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

#[test]
fn rough_surface_load_balance_and_complementarity() {
    check_load_balance_and_complementarity(128, 64.0);
}

/// Rows whose length is not a multiple of the solver's 4-wide lanes (n = 30, 66) go
/// through the padded tail paths of the fused passes; one work block holds one row at
/// n = 30 and two at n = 66.
#[test]
fn load_balance_and_complementarity_with_ragged_rows() {
    check_load_balance_and_complementarity(30, 15.0);
    check_load_balance_and_complementarity(66, 33.0);
}

fn check_load_balance_and_complementarity(n: usize, lambda_l_px: f64) {
    let h = rough_surface(n, lambda_l_px, 4.0, 3);
    let op = ElasticOperator::new(Grid::unit(n).unwrap(), 1.0);
    for (pre, w) in VARIANTS
        .iter()
        .flat_map(|&pre| [0.001, 0.01, 0.05, 0.2].map(|w| (pre, w)))
    {
        // A fresh solver per variant's sweep start (the first load of each).
        let mut solver = Solver::new(&op, &h).unwrap();
        let mean = w; // rms slope 1, E* = 1: p̄ = W/W0
        let report = solver.solve(mean, &cfgp(pre, 1e-10)).unwrap();
        assert!(report.converged(), "{report:?}");
        let p = solver.pressure();
        let mean_p = p.iter().sum::<f64>() / p.len() as f64;
        assert!(
            (mean_p / mean - 1.0).abs() <= 1e-12,
            "load balance {mean_p} vs {mean}"
        );
        assert!(p.iter().all(|&v| v >= 0.0));
        assert!(solver.gap().all(|g| g >= 0.0));
        let err = independent_error(&op, &h, p);
        assert!(err <= 1e-10 * 1.01, "complementarity recomputed: {err}");
        assert!(
            (err - report.error).abs() <= 1e-12,
            "reported {} vs recomputed {err}",
            report.error
        );
    }
}

#[test]
fn warm_started_sweep_matches_cold_solves() {
    let n = 128;
    let h = rough_surface(n, 32.0, 4.0, 4);
    let op = ElasticOperator::new(Grid::unit(n).unwrap(), 1.0);
    let mut warm = Solver::new(&op, &h).unwrap();
    let (mut warm_iters, mut cold_iters) = (0, 0);
    for w in [0.005, 0.01, 0.02, 0.04] {
        let rw = warm.solve(w, &cfg(1e-11)).unwrap();
        let mut cold = Solver::new(&op, &h).unwrap();
        let rc = cold.solve(w, &cfg(1e-11)).unwrap();
        assert!(rw.converged() && rc.converged());
        warm_iters += rw.iterations;
        cold_iters += rc.iterations;
        assert_eq!(warm.contact_count(), cold.contact_count(), "W/W0 = {w}");
        let diff = relative_l2(warm.pressure(), cold.pressure());
        assert!(diff < 1e-8, "W/W0 = {w}: relative difference {diff}");
    }
    assert!(
        warm_iters < cold_iters,
        "warm start must save iterations: {warm_iters} vs {cold_iters}"
    );
}

/// The sweep's warm start scales the previous converged state, deflection included
/// (`K (s p) = s K p`), instead of recomputing `K p`; a start given by `set_start` is
/// recomputed. From the same pressure, both must see the same first state (the error of the
/// start to rounding), take the same steps and reach the same pressures, the sweep with one
/// convolution fewer.
#[test]
fn scaled_warm_start_equals_a_recomputed_start() {
    for n in [66, 128] {
        let h = rough_surface(n, n as f64 / 4.0, 4.0, 5);
        let op = ElasticOperator::new(Grid::unit(n).unwrap(), 1.0);
        for preconditioned in VARIANTS {
            let c = cfgp(preconditioned, 1e-11);
            let mut sweep = Solver::new(&op, &h).unwrap();
            assert!(sweep.solve(0.01, &c).unwrap().converged());
            let mut given = Solver::new(&op, &h).unwrap();
            given.set_start(sweep.pressure()).unwrap();
            let rs = sweep.solve(0.03, &c).unwrap();
            let rg = given.solve(0.03, &c).unwrap();
            assert!(rs.converged() && rg.converged());
            let (e0s, e0g) = (rs.error_history[0], rg.error_history[0]);
            assert!(
                (e0s - e0g).abs() <= 1e-12 * e0g,
                "n = {n}, preconditioned {preconditioned}: start errors {e0s} and {e0g}"
            );
            assert_eq!(rs.iterations, rg.iterations, "n = {n}, {preconditioned}");
            assert_eq!(
                rs.convolutions + 1,
                rg.convolutions,
                "n = {n}, {preconditioned}"
            );
            let diff = relative_l2(sweep.pressure(), given.pressure());
            assert!(
                diff < 1e-12,
                "n = {n}, {preconditioned}: pressures differ by {diff}"
            );
        }
    }
}

/// `Solver::set_start`: a start at the discrete solution is accepted as it is (the first
/// exact check converges, 0 iterations, same contact set); a start that is not a pressure
/// field is an error and leaves the solver usable.
#[test]
fn a_given_start_pressure_is_checked_and_used() {
    let n = 64;
    let h = rough_surface(n, 16.0, 4.0, 3);
    let op = ElasticOperator::new(Grid::unit(n).unwrap(), 1.0);
    let mut reference = Solver::new(&op, &h).unwrap();
    assert!(reference.solve(0.02, &cfg(1e-11)).unwrap().converged());
    let solution = reference.pressure().to_vec();

    let mut solver = Solver::new(&op, &h).unwrap();
    solver.set_start(&solution).unwrap();
    let report = solver.solve(0.02, &cfg(1e-11)).unwrap();
    assert!(report.converged());
    assert_eq!(
        report.iterations, 0,
        "a start at the solution needs no step"
    );
    assert_eq!(solver.contact_count(), reference.contact_count());

    let mut bad = solution.clone();
    bad[3 * n + 5] = -1e-3;
    assert_eq!(
        solver.set_start(&bad),
        Err(ContactError::BadStart {
            row: 3,
            col: 5,
            value: -1e-3
        })
    );
    bad[3 * n + 5] = f64::NAN;
    assert!(matches!(
        solver.set_start(&bad),
        Err(ContactError::BadStart { row: 3, col: 5, .. })
    ));
    assert!(matches!(
        solver.set_start(&solution[1..]),
        Err(ContactError::BadLength { .. })
    ));
    assert!(matches!(
        solver.set_start(&vec![0.0; n * n]),
        Err(ContactError::BadConfig(_))
    ));
    // The rejected starts changed nothing: the next solve starts from the solution.
    let report = solver.solve(0.02, &cfg(1e-11)).unwrap();
    assert!(report.converged() && report.iterations == 0);
}

#[test]
fn zero_load_gives_no_contact_and_no_nan() {
    for pre in VARIANTS {
        let h = rough_surface(64, 32.0, 4.0, 1);
        let op = ElasticOperator::new(Grid::unit(64).unwrap(), 1.0);
        let mut solver = Solver::new(&op, &h).unwrap();
        let r = solver.solve(0.0, &cfgp(pre, 1e-12)).unwrap();
        assert!(r.converged());
        assert_eq!(solver.contact_count(), 0);
        assert!(solver.pressure().iter().all(|&p| p == 0.0));
        let max_h = h.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        for (g, hi) in solver.gap().zip(&h) {
            assert!(
                (g - (max_h - hi)).abs() < 1e-15,
                "gap is the distance to the highest point"
            );
        }
    }
}

#[test]
fn tiny_load_on_one_node_is_exact() {
    for pre in VARIANTS {
        // 64² paraboloid, p̄ = 1e-8 E*: the Hertz radius is far below Δ, the apex node carries it all.
        let n = 64;
        let h = paraboloid(n, 1.0);
        let op = ElasticOperator::new(Grid::unit(n).unwrap(), 1.0);
        let mut solver = Solver::new(&op, &h).unwrap();
        let mean = 1e-8;
        let r = solver.solve(mean, &cfgp(pre, 1e-12)).unwrap();
        assert!(r.converged(), "{r:?}");
        assert!(r.error_history.iter().all(|e| e.is_finite()));
        assert_eq!(solver.contact_count(), 1);
        let apex = (n / 2) * n + n / 2;
        assert!((solver.pressure()[apex] / (mean * (n * n) as f64) - 1.0).abs() < 1e-12);
        assert_eq!(
            r.error, 0.0,
            "the single-node state is the exact discrete solution"
        );
    }
}

#[test]
fn flat_surface_gives_uniform_pressure() {
    for pre in VARIANTS {
        let n = 32;
        let h = vec![0.25; n * n];
        let op = ElasticOperator::new(Grid::unit(n).unwrap(), 1.0);
        let mut solver = Solver::new(&op, &h).unwrap();
        let r = solver.solve(0.3, &cfgp(pre, 1e-12)).unwrap();
        assert!(r.converged());
        assert!(solver.pressure().iter().all(|&p| p == 0.3));
        assert_eq!(solver.contact_count(), n * n);
        assert!(solver.gap().all(|g| g == 0.0));
    }
}

#[test]
fn rough_surface_in_full_contact() {
    for pre in VARIANTS {
        let n = 64;
        let h = rough_surface(n, 32.0, 4.0, 2);
        let op = ElasticOperator::new(Grid::unit(n).unwrap(), 1.0);
        let mut solver = Solver::new(&op, &h).unwrap();
        let r = solver.solve(5.0, &cfgp(pre, 1e-12)).unwrap();
        assert!(r.converged(), "{r:?}");
        assert_eq!(solver.contact_count(), n * n);
        // In full contact the gap vanishes: u − h is constant.
        let max_gap = solver.gap().fold(0.0, f64::max);
        let std_h = (h.iter().map(|v| v * v).sum::<f64>() / h.len() as f64).sqrt();
        assert!(max_gap <= 1e-10 * std_h, "gap {max_gap}");
    }
}

#[test]
fn invalid_input_is_an_error_before_solving() {
    let n = 16;
    let op = ElasticOperator::new(Grid::unit(n).unwrap(), 1.0);
    let mut h = vec![0.0; n * n];
    h[3 * n + 5] = f64::NAN;
    assert!(matches!(
        Solver::new(&op, &h),
        Err(ContactError::NonFinite { row: 3, col: 5, .. })
    ));
    h[3 * n + 5] = f64::INFINITY;
    assert!(matches!(
        Solver::new(&op, &h),
        Err(ContactError::NonFinite { .. })
    ));
    assert!(matches!(
        Solver::new(&op, &h[..10]),
        Err(ContactError::BadLength {
            expected: 256,
            got: 10
        })
    ));
    let ok = vec![0.0; n * n];
    let mut s = Solver::new(&op, &ok).unwrap();
    assert_eq!(
        s.solve(-1.0, &cfg(1e-10)).err(),
        Some(ContactError::BadLoad(-1.0))
    );
    assert!(matches!(
        s.solve(f64::NAN, &cfg(1e-10)),
        Err(ContactError::BadLoad(_))
    ));
}

#[test]
fn non_convergence_is_reported_not_hidden() {
    let n = 64;
    let h = rough_surface(n, 32.0, 4.0, 6);
    let op = ElasticOperator::new(Grid::unit(n).unwrap(), 1.0);
    let mut solver = Solver::new(&op, &h).unwrap();
    let r = solver
        .solve(
            0.05,
            &SolverConfig {
                tolerance: 1e-14,
                max_iterations: 3,
                stall_window: 1000,
                preconditioned: false,
                extension: None,
                offset_to_load: false,
                extrapolate_start: false,
            },
        )
        .unwrap();
    assert_eq!(r.status, Status::MaxIterations);
    assert!(!r.converged());
    assert!(r.error > 1e-14);
}

#[test]
fn identical_bits_for_one_and_two_threads() {
    let n = 256;
    let h = rough_surface(n, 64.0, 8.0, 9);
    for pre in VARIANTS {
        let run = |threads: usize| {
            on_threads(threads, || {
                let op = ElasticOperator::new(Grid::unit(n).unwrap(), 1.0);
                let mut solver = Solver::new(&op, &h).unwrap();
                // Three loads: the third starts from the extrapolated secant.
                let iterations: Vec<usize> = [0.02, 0.025, 0.03]
                    .iter()
                    .map(|&w| solver.solve(w, &cfgp(pre, 1e-10)).unwrap().iterations)
                    .collect();
                (iterations, pressure_bits(&solver))
            })
        };
        assert_eq!(run(1), run(2), "preconditioned: {pre}");
    }
}

/// The preconditioned solver reaches the plain one's solution on a rough surface sweep
/// (same contact set at every load, pressures within 1e-8 relative at tolerance 1e-11)
/// in fewer iterations: on this warm-started sweep the plain conjugate gradient needs 46 / 59
/// / 93 iterations and the preconditioned one 28 / 29 / 34 (measured 2026-11-23); the test
/// asserts a factor of at least 2 at W/W0 = 0.06, where it is 2.7.
#[test]
fn preconditioned_solver_matches_the_plain_one_in_fewer_iterations() {
    let n = 256;
    let h = rough_surface(n, 64.0, 8.0, 7);
    let op = ElasticOperator::new(Grid::unit(n).unwrap(), 1.0);
    let mut plain = Solver::new(&op, &h).unwrap();
    let mut pre = Solver::new(&op, &h).unwrap();
    for w in [0.001, 0.01, 0.06] {
        let rp = plain.solve(w, &cfgp(false, 1e-11)).unwrap();
        let rq = pre.solve(w, &cfgp(true, 1e-11)).unwrap();
        assert!(rp.converged() && rq.converged(), "{rp:?} {rq:?}");
        assert_eq!(plain.contact_count(), pre.contact_count(), "W/W0 = {w}");
        let diff = relative_l2(pre.pressure(), plain.pressure());
        assert!(diff < 1e-8, "W/W0 = {w}: relative difference {diff}");
        if w == 0.06 {
            assert!(
                rq.iterations as f64 * 2.0 < rp.iterations as f64,
                "W/W0 = {w}: {} preconditioned against {} plain iterations",
                rq.iterations,
                rp.iterations
            );
        }
    }
}

/// Small-load area–load slope κ = (A/A0)/(W/W0) on 512² H = 0.8 surfaces with λ_s = 8Δ
/// and λ_l = 128Δ (VALIDATION §3d: BEM setups give 2.2–2.5 with a seed-to-seed scatter of a
/// few percent; accept the ensemble mean in [2.0, 2.7]). The mean over three realizations is
/// tested, as one realization can stray (seed 21 gives 2.72 at W/W0 = 0.005).
#[test]
#[ignore = "slow in debug builds: run by `make test` in release (--include-ignored)"]
fn area_load_slope_at_small_loads() {
    let n = 512;
    let op = ElasticOperator::new(Grid::unit(n).unwrap(), 1.0);
    let loads = [0.005, 0.01, 0.02, 0.04];
    let mut mean = [0.0; 4];
    for seed in [1, 2, 3] {
        let h = rough_surface(n, 128.0, 8.0, seed);
        let mut solver = Solver::new(&op, &h).unwrap();
        for (k, w) in loads.iter().enumerate() {
            assert!(solver.solve(*w, &cfg(1e-8)).unwrap().converged());
            mean[k] += solver.contact_count() as f64 / (n * n) as f64 / w / 3.0;
        }
    }
    for (w, kappa) in loads.iter().zip(mean) {
        assert!((2.0..=2.7).contains(&kappa), "W/W0 = {w}: mean κ = {kappa}");
    }
    // κ decreases slightly with load (VALIDATION §3d).
    assert!(mean[0] > mean[3], "{mean:?}");
}

/// Two warm-started sweeps over the loads `loads` of the heights `h`, one per setting, at
/// tolerance 1e-12: at every load both converge with the same contact pixels and pressures
/// within 1e-6 of each other, and the first setting's pressure carries the load exactly and
/// passes the complementarity recomputed independently. Returns the two sweeps' iterations
/// and whether their pressures were bit for bit the same at every load.
fn compare_sweeps(
    op: &ElasticOperator,
    h: &[f64],
    first: &SolverConfig,
    second: &SolverConfig,
    loads: &[f64],
) -> (usize, usize, bool) {
    let (mut a, mut b) = (Solver::new(op, h).unwrap(), Solver::new(op, h).unwrap());
    let (mut iterations_a, mut iterations_b) = (0, 0);
    let mut identical = true;
    for &w in loads {
        let ra = a.solve(w, first).unwrap();
        let rb = b.solve(w, second).unwrap();
        assert!(ra.converged() && rb.converged(), "W/W0 {w}: {ra:?} {rb:?}");
        assert_eq!(a.contact_count(), b.contact_count(), "W/W0 {w}");
        identical &= a.pressure() == b.pressure();
        let d = relative_l2(a.pressure(), b.pressure());
        assert!(d <= 1e-6, "W/W0 {w}: pressures differ by {d}");
        let p = a.pressure();
        let mean_p = p.iter().sum::<f64>() / p.len() as f64;
        assert!((mean_p / w - 1.0).abs() <= 1e-12, "W/W0 {w}: load {mean_p}");
        let err = independent_error(op, h, p);
        assert!(
            err <= 1e-12 * 1.01,
            "W/W0 {w}: complementarity recomputed {err}"
        );
        iterations_a += ra.iterations;
        iterations_b += rb.iterations;
    }
    (iterations_a, iterations_b, identical)
}

/// [`compare_sweeps`] of the default settings against `without` (the default with one
/// feature off) on the rough surface `rough_surface(n, lambda_l_px, 4.0, seed)`, and the
/// default's iterations below `fraction` of `without`'s.
fn assert_default_saves_iterations(
    (n, lambda_l_px, seed): (usize, f64, u64),
    without: SolverConfig,
    loads: &[f64],
    fraction: f64,
) {
    let h = rough_surface(n, lambda_l_px, 4.0, seed);
    let op = ElasticOperator::new(Grid::unit(n).unwrap(), 1.0);
    let (with, without, _) = compare_sweeps(&op, &h, &cfg(1e-12), &without, loads);
    assert!(
        (with as f64) < fraction * without as f64,
        "{with} iterations with the default, {without} without the feature"
    );
}

/// The extension's near term (on once the contact set has settled) is what makes the
/// default take fewer iterations than the long term alone on a warm-started sweep over a
/// rough surface (measured: 138 against 166 at n = 128 through W/W0 = 0.01 … 0.1), with
/// the same contact pixels at every load and pressures within the tolerance's reach.
#[test]
fn near_term_saves_iterations_on_a_settled_contact_set() {
    use wearcoef::contact::solver::Extension;
    let long_only = SolverConfig {
        extension: Some(Extension {
            near_weight: 0.0,
            ..Extension::default()
        }),
        ..cfg(1e-12)
    };
    assert_default_saves_iterations(
        (128, 64.0, 3),
        long_only,
        &[0.01, 0.02, 0.03, 0.04, 0.05, 0.06, 0.08, 0.1],
        0.95,
    );
}

/// The extension's far term, on a box declared large (here σ_far = 16 nodes on 16² cells,
/// and the 256² box large, without the entry margin that comes with it), changes the
/// iteration but not the
/// solution: the same contact pixels at every load, pressures within the tolerance's reach,
/// the load exact and the complementarity recomputed independently (`compare_sweeps`); and
/// the pressures are not bit for bit those without it, so the term is in use.
#[test]
fn far_term_keeps_the_solution() {
    use wearcoef::contact::solver::Extension;
    // σ_far = 16 nodes on 16² cells.
    let mut small_far = Extension::default();
    (small_far.far_sigma, small_far.far_cell, small_far.large_box) = (16.0, 16, 256);
    small_far.entry_margin = 0.0;
    let without = Extension {
        far_weight: 0.0,
        ..small_far
    };
    let identical = compare_extensions(small_far, without, &[0.02, 0.04, 0.08]);
    assert!(!identical, "the far term left every pressure bit unchanged");
}

/// The deflation by the blocks' loads once the contact set has settled (on blocks of 64
/// nodes, so that the 256² box, declared large without the far term and the entry margin,
/// holds 4 × 4 of them) changes the iteration but not the solution (`compare_sweeps`, as
/// above), and not the bits between 1 and 2 threads.
#[test]
fn coarse_deflation_keeps_the_solution_and_the_bits() {
    use wearcoef::contact::solver::Extension;
    let deflated = Extension {
        coarse_block: 64,
        large_box: 256,
        far_weight: 0.0,
        entry_margin: 0.0,
        ..Extension::default()
    };
    let without = Extension {
        coarse_block: 0,
        ..deflated
    };
    keeps_the_solution_and_the_bits(deflated, without, "the deflation");
}

/// The free set's entry margin (forced on the 256² box by declaring it large, without the
/// far term that comes with large boxes) changes the iteration but not the solution
/// (`compare_sweeps`: the same contact pixels, pressures within the tolerance's reach,
/// complementarity recomputed independently), and not the bits between 1 and 2 threads.
#[test]
fn entry_margin_keeps_the_solution_and_the_bits() {
    use wearcoef::contact::solver::Extension;
    let default = Extension::default();
    assert!(default.entry_margin > 0.0 && default.large_box > 256);
    let margin = Extension {
        large_box: 256,
        far_weight: 0.0,
        ..default
    };
    let without = Extension {
        entry_margin: 0.0,
        ..margin
    };
    keeps_the_solution_and_the_bits(margin, without, "the entry margin");
}

/// [`compare_extensions`] of `with` against `without` on three loads must find the bits
/// changed (so `with` acts) and the solution kept, and a sweep with `with` must give the
/// same bits on 1 and 2 threads.
fn keeps_the_solution_and_the_bits(
    with: wearcoef::contact::solver::Extension,
    without: wearcoef::contact::solver::Extension,
    what: &str,
) {
    let loads = [0.02, 0.04, 0.08];
    let identical = compare_extensions(with, without, &loads);
    assert!(!identical, "{what} left every pressure bit unchanged");
    let config = SolverConfig {
        extension: Some(with),
        ..cfg(1e-12)
    };
    let (n, h) = extension_surface();
    let run = |threads: usize| {
        on_threads(threads, || {
            let op = ElasticOperator::new(Grid::unit(n).unwrap(), 1.0);
            let mut solver = Solver::new(&op, &h).unwrap();
            for &w in &loads {
                assert!(solver.solve(w, &config).unwrap().converged());
            }
            pressure_bits(&solver)
        })
    };
    assert!(
        run(1) == run(2),
        "{what}: the sweep differs between 1 and 2 threads"
    );
}

/// `f` on a pool of `threads` threads.
fn on_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}

/// The bits of the solver's pressures.
fn pressure_bits(solver: &Solver) -> Vec<u64> {
    solver.pressure().iter().map(|p| p.to_bits()).collect()
}

/// The rough 256² surface (L/λ_l = 2) of the extension's tests.
fn extension_surface() -> (usize, Vec<f64>) {
    (256, rough_surface(256, 128.0, 4.0, 7))
}

/// [`compare_sweeps`] of two settings of the extension at tolerance 1e-12 on
/// [`extension_surface`]; whether every pressure bit was the same.
fn compare_extensions(
    with: wearcoef::contact::solver::Extension,
    without: wearcoef::contact::solver::Extension,
    loads: &[f64],
) -> bool {
    let (n, h) = extension_surface();
    let config = |extension| SolverConfig {
        extension: Some(extension),
        ..cfg(1e-12)
    };
    let op = ElasticOperator::new(Grid::unit(n).unwrap(), 1.0);
    compare_sweeps(&op, &h, &config(with), &config(without), loads).2
}

/// Restoring the load by a uniform offset of the pressures (the default) reaches the
/// rescaling's solution in fewer iterations on a warm-started sweep over a rough surface:
/// the same contact pixels at every load, pressures within the tolerance's reach, the load
/// exact and the complementarity recomputed independently (measured 2026-11-26: 102 against
/// 111 iterations at n = 256, L/λ_l = 2, through W/W0 = 0.01 … 0.15; the gain grows with
/// the box, docs/BENCHMARKS.md).
#[test]
fn load_offset_reaches_the_rescaled_solution_in_fewer_iterations() {
    let rescaled = SolverConfig {
        offset_to_load: false,
        ..cfg(1e-12)
    };
    assert_default_saves_iterations(
        (256, 128.0, 5),
        rescaled,
        &[0.01, 0.03, 0.06, 0.1, 0.15],
        0.95,
    );
}

/// Starting each load from the secant through the last two solutions (the default) reaches
/// the scaled start's solution in fewer iterations on a warm-started sweep over a rough
/// surface, its loads 15 % apart like the paper's: the same contact pixels at every load,
/// pressures within the tolerance's reach, the load exact and the complementarity
/// recomputed independently, also at the last load, which turns back and is started from
/// the scaled solution (measured 2026-11-26: 216 against 228 iterations at n = 256,
/// L/λ_l = 2, tolerance 1e-12; the gain grows with the grid, 9 % at 1024² and 13 % at
/// 8192² on the paper's spectrum at 1e-10, docs/BENCHMARKS.md).
#[test]
fn extrapolated_start_reaches_the_scaled_solution_in_fewer_iterations() {
    let scaled = SolverConfig {
        extrapolate_start: false,
        ..cfg(1e-12)
    };
    let loads: Vec<f64> = (0..12)
        .map(|k| 0.01 * 1.15f64.powi(k))
        .chain([0.03])
        .collect();
    assert_default_saves_iterations((256, 128.0, 5), scaled, &loads, 0.97);
}

/// The preconditioner's free-set extension (the default) reaches the same solution as
/// `P K⁻¹ P` alone: at every load
/// of a warm-started sweep on a rough surface (ragged rows and a partial last cell at
/// n = 66), the same contact pixels, pressures within the tolerance's reach of the
/// default's, the load and complementarity recomputed independently; in full contact it is
/// the exact inverse like the default (the same iterations); invalid settings are an
/// error naming them.
#[test]
fn extended_preconditioner_reaches_the_same_solution() {
    use wearcoef::contact::solver::Extension;
    for (n, lambda_l_px) in [(128usize, 64.0), (66, 33.0)] {
        let h = rough_surface(n, lambda_l_px, 4.0, 3);
        let op = ElasticOperator::new(Grid::unit(n).unwrap(), 1.0);
        let extended = SolverConfig {
            extension: Some(Extension::default()),
            ..cfg(1e-12)
        };
        let alone = SolverConfig {
            extension: None,
            ..cfg(1e-12)
        };
        compare_sweeps(&op, &h, &extended, &alone, &[0.01, 0.05, 0.1, 0.2]);
        // From a uniform start in full contact F is every node, E = 1: the exact inverse
        // and the iterations of P K⁻¹ P alone.
        let full_default = Solver::new(&op, &h)
            .unwrap()
            .solve(5.0, &cfg(1e-12))
            .unwrap();
        let mut fresh = Solver::new(&op, &h).unwrap();
        let full = fresh.solve(5.0, &extended).unwrap();
        assert!(full.converged(), "{full:?}");
        assert_eq!(full.iterations, full_default.iterations, "{full:?}");
        assert_eq!(fresh.contact_count(), n * n);
    }
    let op = ElasticOperator::new(Grid::unit(16).unwrap(), 1.0);
    let h = rough_surface(16, 8.0, 4.0, 1);
    let mut solver = Solver::new(&op, &h).unwrap();
    let bad = SolverConfig {
        extension: Some(Extension {
            weight: 2.0,
            ..Extension::default()
        }),
        ..cfg(1e-8)
    };
    match solver.solve(0.1, &bad) {
        Err(ContactError::BadConfig(msg)) => assert!(msg.contains("weight"), "{msg}"),
        other => panic!("expected BadConfig, got {other:?}"),
    }
    let bad = SolverConfig {
        extension: Some(Extension {
            near_weight: -0.1,
            ..Extension::default()
        }),
        ..cfg(1e-8)
    };
    match solver.solve(0.1, &bad) {
        Err(ContactError::BadConfig(msg)) => assert!(msg.contains("near weight"), "{msg}"),
        other => panic!("expected BadConfig, got {other:?}"),
    }
    let bad = SolverConfig {
        extension: Some(Extension {
            entry_margin: f64::NAN,
            ..Extension::default()
        }),
        ..cfg(1e-8)
    };
    match solver.solve(0.1, &bad) {
        Err(ContactError::BadConfig(msg)) => assert!(msg.contains("entry margin"), "{msg}"),
        other => panic!("expected BadConfig, got {other:?}"),
    }
}
