//! Unit tests of the solver's internal passes.

use super::rows::GradientStats;
use super::*;
use crate::contact::elastic::ElasticOperator;
use crate::grid::Grid;

/// The FFT correction `u ← s (u + K Δ)` from the change lists equals an exact
/// recomputation `u = s K (p + Δ)`, with the same gradient statistics, when `Δ` sits on a
/// few rows (the others skip their forward row transform) or on many.
#[test]
fn fft_correction_equals_an_exact_recomputation() {
    let n = 64;
    let op = ElasticOperator::new(Grid::unit(n).unwrap(), 1.0);
    let heights: Vec<f64> = (0..n * n)
        .map(|i| ((i * 7919 % 1009) as f64 / 1009.0 - 0.5) * 0.01)
        .collect();
    // A pressure on rows 10–29 only; changes on rows 3, 12 and 40, or on every row.
    let start: Vec<f64> = (0..n * n)
        .map(|i| {
            let row = i / n;
            if (10..30).contains(&row) {
                (i * 31 % 97) as f64 / 97.0
            } else {
                0.0
            }
        })
        .collect();
    let few: Vec<(usize, f64)> = (0..40)
        .map(|k| {
            let row = [3, 12, 40][k % 3];
            (row * n + (k * 13) % n, 0.01 * (k as f64 + 1.0))
        })
        .collect();
    let many: Vec<(usize, f64)> = (0..n).map(|r| (r * n + (r * 5) % n, 0.02)).collect();
    for changes in [few, many] {
        let (scale, shift) = (0.9, 0.003);
        let mut solver = Solver::new(&op, &heights).unwrap();
        solver.fields.pressure.copy_from_slice(&start);
        solver.exact_deflection(1.0, 0.0);
        let mut changed = start.clone();
        let mut sorted = changes.clone();
        sorted.sort_by_key(|c| c.0);
        sorted.dedup_by_key(|c| c.0);
        for list in &mut solver.blocks.changes {
            list.clear();
        }
        for acc in &mut solver.blocks.update_acc {
            acc.changed = 0;
        }
        for &(i, d) in &sorted {
            changed[i] += d;
            solver.fields.pressure[i] += d;
            let b = i / solver.blocks.chunk;
            solver.blocks.changes[b].push((i, d));
            solver.blocks.update_acc[b].changed += 1;
        }
        assert!(solver.changes_listed());
        let stats = solver.fft_correction(scale, shift);

        let mut exact = Solver::new(&op, &heights).unwrap();
        exact.fields.pressure.copy_from_slice(&changed);
        let expected = exact.exact_deflection(scale, shift);
        let u_max = exact
            .fields
            .separation
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        for (i, (a, b)) in solver
            .fields
            .separation
            .iter()
            .zip(&exact.fields.separation)
            .enumerate()
        {
            assert!((a - b).abs() <= 1e-13 * u_max, "node {i}: {a} vs {b}");
        }
        assert_eq!(solver.fields.pressure, exact.fields.pressure);
        let fields = |s: &GradientStats| {
            [
                ("contact_nodes", s.contact_nodes),
                ("sum_g", s.sum_g),
                ("sum_g2", s.sum_g2),
                ("sum_pg", s.sum_pg),
                ("sum_p", s.sum_p),
                ("min_g", s.min_g),
            ]
        };
        for ((name, got), (_, want)) in fields(&stats).into_iter().zip(fields(&expected)) {
            let tol = 1e-11 * want.abs().max(1e-300);
            assert!(
                (got - want).abs() <= tol,
                "statistic {name}: {got} vs {want}"
            );
        }
    }
}

/// A block that changed more nodes than its list holds forces an exact recomputation.
#[test]
fn overflowing_change_lists_are_detected() {
    let n = 32;
    let op = ElasticOperator::new(Grid::unit(n).unwrap(), 1.0);
    let heights: Vec<f64> = (0..n * n).map(|i| (i % 7) as f64).collect();
    let mut solver = Solver::new(&op, &heights).unwrap();
    let cap = solver.blocks.changes[0].capacity();
    for k in 0..cap {
        solver.blocks.changes[0].push((k, 1.0));
    }
    solver.blocks.update_acc[0].changed = cap;
    assert!(solver.changes_listed());
    solver.blocks.update_acc[0].changed = cap + 1;
    assert!(!solver.changes_listed());
}

/// The load offset `c` of [`Solver::load_offset`] (Newton's method from above) is the one a
/// sort gives: with the values in decreasing order `x_(1) ≥ x_(2) ≥ …`, the largest `k` for
/// which `c_k = (load − Σ_{j ≤ k} x_(j)) / k` leaves `x_(k) + c_k > 0`. Random pressures
/// with zeros and ties, loads that keep most nodes or leave one; the offset pressure sums to
/// the load.
#[test]
fn load_offset_matches_a_sorted_projection() {
    let n = 32;
    let op = ElasticOperator::new(Grid::unit(n).unwrap(), 1.0);
    let heights = vec![0.0; n * n];
    let mut next = super::test_support::sequence(11);
    for (case, keep) in [0.999, 0.9, 0.5, 0.1, 1e-3].into_iter().enumerate() {
        let mut solver = Solver::new(&op, &heights).unwrap();
        for p in solver.fields.pressure.iter_mut() {
            let v = next();
            // A third of the nodes at zero, some ties (values on a coarse lattice).
            *p = if v < -1.0 / 3.0 {
                0.0
            } else {
                ((v + 1.0) * 32.0).floor() / 16.0
            };
        }
        let total: f64 = solver.fields.pressure.iter().sum();
        let count = solver.fields.pressure.iter().filter(|&&p| p > 0.0).count() as f64;
        let load = keep * total;
        let (c, sum) = solver.load_offset(load, total, count);
        let mut sorted: Vec<f64> = solver
            .fields
            .pressure
            .iter()
            .copied()
            .filter(|&p| p > 0.0)
            .collect();
        sorted.sort_by(|a, b| b.total_cmp(a));
        let (mut prefix, mut expected) = (0.0, 0.0);
        for (k, &x) in sorted.iter().enumerate() {
            prefix += x;
            let ck = (load - prefix) / (k + 1) as f64;
            if x + ck > 0.0 {
                expected = ck;
            }
        }
        assert!(c <= 0.0, "case {case}: offset {c}");
        assert!(
            (c - expected).abs() <= 1e-12 * sorted[0],
            "case {case}: offset {c}, sorted {expected}"
        );
        let recomputed: f64 = solver
            .fields
            .pressure
            .iter()
            .map(|p| (p + c).max(0.0))
            .sum();
        assert!(
            (sum / load - 1.0).abs() <= 1e-12,
            "case {case}: {sum} vs {load}"
        );
        assert!((recomputed / load - 1.0).abs() <= 1e-12, "case {case}");
    }
}

/// `z = M x` for `x` on the contact set `contact` (the extended preconditioner with
/// `settings`, settled), through its own passes.
fn preconditioned(
    op: &ElasticOperator,
    settings: Extension,
    contact: &[bool],
    x: &[f64],
) -> Vec<f64> {
    use super::preconditioner::{Fields, Preconditioner};
    let n = op.grid().n();
    let heights = vec![0.0; n * n];
    let mut solver = Solver::new(op, &heights).unwrap();
    for i in 0..n * n {
        (solver.fields.pressure[i], solver.fields.separation[i]) =
            if contact[i] { (1.0, x[i]) } else { (0.0, 1e3) };
    }
    let mut part = extension::Extended::new(op, settings);
    let count = contact.iter().filter(|&&c| c).count();
    Preconditioner::<NonNegative, ElasticOperator>::settle(&mut part, Some((0, count as f64)));
    let mut fields = Fields {
        op,
        ws: &mut solver.ws,
        chunk: solver.blocks.chunk,
        pressure: &solver.fields.pressure,
        separation: &solver.fields.separation,
        direction: &mut solver.fields.direction,
    };
    let level = super::level::Level {
        mean: 0.0,
        entry: 0.0,
        constraint: NonNegative,
    };
    let sums = part.precondition(&mut fields, level);
    Preconditioner::<NonNegative, ElasticOperator>::direction(
        &mut part,
        &mut fields,
        [sums.z_mean, 0.0, 0.0],
    );
    solver.fields.direction.clone()
}

/// The preconditioner deflated by the blocks' loads (`M_B = Xᵀ M X + Z̃ E⁻¹ Z̃ᵀ`) is
/// symmetric on the contact set like `M` itself, to the single precision of `K⁻¹`
/// (⟨x₁, M x₂⟩ = ⟨M x₁, x₂⟩ within 1e-5), and differs from `M`.
#[test]
fn deflated_preconditioner_is_symmetric() {
    let n = 128;
    let op = ElasticOperator::new(Grid::unit(n).unwrap(), 1.0);
    let contact: Vec<bool> = (0..n * n)
        .map(|i| {
            let (r, c) = ((i / n) as f64, (i % n) as f64);
            ((r * 0.31).sin() + (c * 0.23).cos() + (r * c * 0.0007).sin()) > 1.2
        })
        .collect();
    let inside = contact.iter().filter(|&&c| c).count() as f64;
    // Random values on the contact set, centred there.
    let field = |seed: u64| -> Vec<f64> {
        let mut next = super::test_support::sequence(seed);
        let mut x: Vec<f64> = contact
            .iter()
            .map(|&c| {
                let v = next();
                if c {
                    v
                } else {
                    0.0
                }
            })
            .collect();
        let mean = x.iter().sum::<f64>() / inside;
        for (v, &c) in x.iter_mut().zip(&contact) {
            if c {
                *v -= mean;
            }
        }
        x
    };
    let (x1, x2) = (field(1), field(2));
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(a, b)| a * b).sum::<f64>();
    let mut outputs = Vec::new();
    for block in [0, 32] {
        // The box declared large for the deflation, without the far term that comes with
        // it (on 2 × 2 far cells it is not symmetric to 1e-5).
        let settings = Extension {
            coarse_block: block,
            large_box: n,
            far_weight: 0.0,
            ..Extension::default()
        };
        let z1 = preconditioned(&op, settings, &contact, &x1);
        let z2 = preconditioned(&op, settings, &contact, &x2);
        let (a, b) = (dot(&x1, &z2), dot(&z1, &x2));
        assert!(
            (a - b).abs() <= 1e-5 * a.abs().max(b.abs()),
            "blocks of {block}: {a} against {b}"
        );
        outputs.push(z1);
    }
    let change = outputs[0]
        .iter()
        .zip(&outputs[1])
        .map(|(a, b)| (a - b) * (a - b))
        .sum::<f64>()
        / dot(&outputs[0], &outputs[0]);
    assert!(change > 1e-4, "the deflation changed M x by {change}");
}
