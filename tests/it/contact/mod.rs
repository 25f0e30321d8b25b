//! Contact solver against analytic solutions (VALIDATION.md §3) and its defined behaviour
//! where the method breaks down (§2.4).

use wearcoef::contact::elastic::ElasticOperator;
use wearcoef::contact::solver::{ContactError, Solver, SolverConfig, Status};
use wearcoef::grid::Grid;
use wearcoef::spectral::Fft2;
use wearcoef::surface::{self, Method, SurfaceParams};

mod analytic;
mod variants;

pub(super) fn cfg(tol: f64) -> SolverConfig {
    SolverConfig {
        tolerance: tol,
        ..SolverConfig::default()
    }
}

/// Both solver variants: plain and preconditioned (`SolverConfig::preconditioned`). The
/// analytic checks and the defined behaviour below hold for each.
pub(super) const VARIANTS: [bool; 2] = [false, true];

fn cfgp(preconditioned: bool, tol: f64) -> SolverConfig {
    SolverConfig {
        tolerance: tol,
        preconditioned,
        ..SolverConfig::default()
    }
}

/// ‖a − b‖ / ‖b‖ (Euclidean).
pub(super) fn relative_l2(a: &[f64], b: &[f64]) -> f64 {
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
pub(super) fn independent_error(op: &ElasticOperator, h: &[f64], p: &[f64]) -> f64 {
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

pub(super) fn rough_surface(n: usize, lambda_l_px: f64, lambda_s_px: f64, seed: u64) -> Vec<f64> {
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

/// `f` on a pool of `threads` threads.
pub(super) fn on_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}

/// Paraboloid h = −r²/(2R) centred on node (n/2, n/2) of a unit cell.
pub(super) fn paraboloid(n: usize, r_curv: f64) -> Vec<f64> {
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

/// The bits of the solver's pressures.
pub(super) fn pressure_bits(solver: &Solver) -> Vec<u64> {
    solver.pressure().iter().map(|p| p.to_bits()).collect()
}
