//! Tests of the solve under a pressure ceiling (`mod.rs`, `law.rs`): the optimality
//! conditions checked node by node against a deflection computed apart from the solver, a
//! discrete solution known in closed form, the limits (ceiling above every elastic pressure,
//! mean at the ceiling, mean above it) and bit-identity across thread counts.

use super::super::*;
use crate::contact::elastic::ElasticOperator;
use crate::grid::Grid;
use crate::spectral::Fft2;
use crate::surface::{self, Method, SurfaceParams};

const E_STAR: f64 = 1.0;

/// A 64² self-affine surface (H = 0.8, λ_l = 32 Δl, λ_s = 4 Δl) and its rms slope.
fn rough(seed: u64) -> (ElasticOperator, Vec<f64>, f64) {
    let n = 64;
    let params = SurfaceParams {
        n,
        hurst: 0.8,
        lambda_l_px: 32.0,
        lambda_s_px: 4.0,
        rolloff_lambda_px: None,
        method: Method::Filter,
        seed,
    };
    let fft = Fft2::new(n);
    let s = surface::generate(&params, &fft, &mut fft.make_scratch()).unwrap();
    let slope = surface::rms_slope(&s.grid, &s.heights);
    (ElasticOperator::new(s.grid, E_STAR), s.heights, slope)
}

fn config(preconditioned: bool) -> SolverConfig {
    SolverConfig {
        tolerance: 1e-12,
        preconditioned,
        ..SolverConfig::default()
    }
}

/// The optimality conditions of `min ½⟨p, K p⟩ − ⟨p, h⟩` on `0 ≤ p ≤ p_max`, `mean p = p̄`,
/// with `u = K p` computed here by the operator (not the solver's own `w`): with `ℓ` the
/// mean of `w = u − h` over the nodes strictly between the bounds, every such node is at
/// `ℓ`, every node at 0 above it and every node on the ceiling below it, within `slack`
/// (a length); returns the saturated count and the largest violation found.
fn check_optimality(
    op: &ElasticOperator,
    heights: &[f64],
    p: &[f64],
    mean: f64,
    max: f64,
    slack: f64,
) -> usize {
    let len = p.len();
    assert!(
        p.iter().all(|&v| (0.0..=max).contains(&v)),
        "outside [0, p_max]"
    );
    let total: f64 = p.iter().sum();
    assert!(
        (total / len as f64 - mean).abs() <= 1e-11 * mean,
        "mean {} vs {mean}",
        total / len as f64
    );
    let mut u = vec![0.0; len];
    op.apply(p, &mut u, &mut op.make_workspace());
    let w: Vec<f64> = u.iter().zip(heights).map(|(u, h)| u - h).collect();
    let between: Vec<f64> = (0..len)
        .filter(|&i| p[i] > 0.0 && p[i] < max)
        .map(|i| w[i])
        .collect();
    assert!(!between.is_empty(), "no node strictly between the bounds");
    let level = between.iter().sum::<f64>() / between.len() as f64;
    for i in 0..len {
        let d = w[i] - level;
        if p[i] == 0.0 {
            assert!(d >= -slack, "node {i} at 0 below the level by {}", -d);
        } else if p[i] == max {
            assert!(d <= slack, "node {i} on the ceiling above the level by {d}");
        } else {
            assert!(d.abs() <= slack, "node {i} in contact off the level by {d}");
        }
    }
    p.iter().filter(|&&v| v == max).count()
}

/// On a rough surface, for ceilings from above most contact pressures to below most of
/// them, both iterations converge to a field meeting the optimality conditions node by
/// node, with a deflection the solver did not compute. The slack, 1e-6 σ_h, is what an error
/// of 1e-12 (a work `Σ p |g|` of 1e-12 p̄ n² σ_h) allows at a node of pressure ~1e-6 p̄.
#[test]
fn rough_surface_meets_the_optimality_conditions() {
    let (op, h, slope) = rough(11);
    let mean = 0.05 * E_STAR * slope;
    for hardness in [1.0, 0.3, 0.1] {
        let max = hardness * E_STAR * slope;
        for preconditioned in [true, false] {
            let mut solver = Solver::with_constraint(&op, &h, Ceiling::new(max).unwrap()).unwrap();
            let report = solver.solve(mean, &config(preconditioned)).unwrap();
            assert_eq!(
                report.status,
                Status::Converged,
                "hardness {hardness}: {report:?}"
            );
            let slack = 1e-6 * solver.height_std();
            let saturated = check_optimality(&op, &h, solver.pressure(), mean, max, slack);
            assert_eq!(saturated, solver.saturated_count());
            if hardness <= 0.3 {
                assert!(saturated > 0, "hardness {hardness}: nothing saturated");
            }
        }
    }
}

/// A sweep of loads warm-started under a ceiling converges at each load to the optimality
/// conditions, from both starts: the last solution scaled, projected and offset, and (for a
/// load its contact set cannot carry at the ceiling) one projected gradient step from it.
#[test]
fn warm_sweep_under_a_ceiling() {
    let (op, h, slope) = rough(12);
    let mut starts = [0, 0];
    for hardness in [0.2, 2.0] {
        let max = hardness * E_STAR * slope;
        let mut solver = Solver::with_constraint(&op, &h, Ceiling::new(max).unwrap()).unwrap();
        for load in [0.002, 0.004, 0.01, 0.02, 0.05, 0.1, 0.15] {
            let mean = load * E_STAR * slope;
            starts[usize::from(Ceiling::beyond_contact_set(&solver, mean))] += 1;
            let report = solver.solve(mean, &config(true)).unwrap();
            assert_eq!(
                report.status,
                Status::Converged,
                "hardness {hardness}, W/W0 {load}: {report:?}"
            );
            check_optimality(
                &op,
                &h,
                solver.pressure(),
                mean,
                max,
                1e-6 * solver.height_std(),
            );
        }
    }
    // Each sweep's first load starts from the uniform pressure: it counts with the scaled.
    assert!(
        starts[0] >= 3 && starts[1] >= 1,
        "scaled / step starts: {starts:?}"
    );
}

/// k spikes of distinct heights far above a flat floor, apart by more than the elastic
/// deflections: under the load `(k − 1) p_max + r` the k − 1 highest saturate, the lowest
/// carries `r` alone, and the plastic displacement of spike i is
/// `(h_i − h_k) − (u_i − u_k)` with `u = K p` of that field — known without the solver.
#[test]
fn spikes_saturate_from_the_highest() {
    let n = 32;
    let op = ElasticOperator::new(Grid::unit(n).unwrap(), E_STAR);
    let spikes = [(5, 5), (5, 21), (21, 5), (21, 21), (13, 13)];
    let mut h = vec![0.0; n * n];
    for (k, &(i, j)) in spikes.iter().enumerate() {
        h[i * n + j] = 1.0 - 0.1 * k as f64;
    }
    let max = 1e-3;
    for r in [0.25 * max, 0.9 * max] {
        let k = spikes.len();
        let mean = ((k - 1) as f64 * max + r) / (n * n) as f64;
        let mut expected = vec![0.0; n * n];
        for &(i, j) in &spikes[..k - 1] {
            expected[i * n + j] = max;
        }
        let (ik, jk) = spikes[k - 1];
        expected[ik * n + jk] = r;
        for preconditioned in [true, false] {
            let mut solver = Solver::with_constraint(&op, &h, Ceiling::new(max).unwrap()).unwrap();
            let report = solver.solve(mean, &config(preconditioned)).unwrap();
            assert_eq!(report.status, Status::Converged, "{report:?}");
            for (i, (&got, &want)) in solver.pressure().iter().zip(&expected).enumerate() {
                assert!(
                    (got - want).abs() <= 1e-9 * max,
                    "node {i}: {got} vs {want}"
                );
            }
            assert_eq!(solver.saturated_count(), k - 1);
            let mut u = vec![0.0; n * n];
            op.apply(&expected, &mut u, &mut op.make_workspace());
            let plastic: Vec<f64> = solver.plastic_displacement().collect();
            let last = ik * n + jk;
            for &(i, j) in &spikes[..k - 1] {
                let at = i * n + j;
                let want = (h[at] - h[last]) - (u[at] - u[last]);
                assert!(want > 0.0);
                assert!(
                    (plastic[at] - want).abs() <= 1e-9 * want,
                    "spike {at}: {} vs {want}",
                    plastic[at]
                );
            }
            assert_eq!(plastic.iter().filter(|&&d| d > 0.0).count(), k - 1);
        }
    }
}

/// A ceiling above every pressure of the elastic solution changes nothing: the same contact
/// set and the same pressures to the tolerance (the iterations differ: the elastic one
/// rescales the load, the bounded one offsets it).
#[test]
fn a_ceiling_that_never_bites_is_elastic() {
    let (op, h, slope) = rough(13);
    let mean = 0.05 * E_STAR * slope;
    let mut elastic = Solver::new(&op, &h).unwrap();
    assert_eq!(
        elastic.solve(mean, &config(true)).unwrap().status,
        Status::Converged
    );
    let peak = elastic.pressure().iter().fold(0.0f64, |m, &p| m.max(p));
    let mut bounded = Solver::with_constraint(&op, &h, Ceiling::new(1.01 * peak).unwrap()).unwrap();
    assert_eq!(
        bounded.solve(mean, &config(true)).unwrap().status,
        Status::Converged
    );
    assert_eq!(bounded.saturated_count(), 0);
    for (i, (a, b)) in elastic
        .pressure()
        .iter()
        .zip(bounded.pressure())
        .enumerate()
    {
        assert!((a - b).abs() <= 1e-6 * peak, "node {i}: {a} vs {b}");
        // Membership is decided by the tolerance for the nodes of nearly no pressure.
        let clear = 1e-6 * peak;
        assert!(
            !(*a > clear && *b == 0.0 || *b > clear && *a == 0.0),
            "node {i}: {a} vs {b}"
        );
    }
}

/// The mean at the ceiling is full contact at the ceiling, every node saturated, in no
/// iteration; a mean above it is refused, naming both numbers.
#[test]
fn the_mean_at_and_above_the_ceiling() {
    let (op, h, slope) = rough(14);
    let max = 0.1 * E_STAR * slope;
    let mut solver = Solver::with_constraint(&op, &h, Ceiling::new(max).unwrap()).unwrap();
    let report = solver.solve(max, &config(true)).unwrap();
    assert_eq!(report.status, Status::Converged);
    assert_eq!(report.iterations, 0);
    assert!(solver.pressure().iter().all(|&p| p == max));
    assert_eq!(solver.saturated_count(), h.len());
    assert!(solver.plastic_displacement().all(|d| d >= 0.0));
    let above = max * (1.0 + 1e-9);
    let err = solver.solve(above, &config(true)).unwrap_err();
    assert_eq!(
        err,
        ContactError::AboveCeiling {
            mean: above,
            ceiling: max
        }
    );
    let text = err.to_string();
    assert!(
        text.contains(&above.to_string()) && text.contains(&max.to_string()),
        "{text}"
    );
    for bad in [0.0, -1.0, f64::INFINITY, f64::NAN] {
        assert!(Ceiling::new(bad).is_err(), "{bad}");
    }
}

/// One and two threads give the same bits under a ceiling (sweep of three loads).
#[test]
fn thread_counts_give_the_same_bits() {
    let (op, h, slope) = rough(15);
    let max = 0.15 * E_STAR * slope;
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut solver = Solver::with_constraint(&op, &h, Ceiling::new(max).unwrap()).unwrap();
            let mut out = Vec::new();
            for load in [0.02, 0.05, 0.1] {
                let report = solver.solve(load * E_STAR * slope, &config(true)).unwrap();
                assert_eq!(report.status, Status::Converged);
                out.extend(solver.pressure().iter().map(|p| p.to_bits()));
                out.push(report.error.to_bits());
            }
            out
        })
    };
    assert_eq!(run(1), run(2));
}
