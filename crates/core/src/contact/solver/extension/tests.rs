use super::*;

/// The smoothing of either term is symmetric (⟨a, G b⟩ = ⟨G a, b⟩, to rounding) and
/// keeps constants and sums (the kernel sums to 1), so `S = U G Uᵀ / c²` is symmetric
/// and `M_E` with it.
#[test]
fn smoothing_is_symmetric_and_conservative() {
    let coarse = Coarse::new(96, 4, Extension::default());
    assert!(coarse.near.smoothing.kernel.len() < coarse.long.smoothing.kernel.len());
    for term in [&coarse.long, &coarse.near] {
        check_smoothing(&term.smoothing.kernel);
    }
}

/// The far term's smoothing on its own cells (sums over 3 × 3 shared cells, the Gaussian
/// on them, spread back) is symmetric, keeps sums and constants, and is constant over
/// each of its cells, like the shared cells' terms.
#[test]
fn far_smoothing_on_merged_cells_is_symmetric_and_conservative() {
    let m = 24;
    let mut term = Smoothing::new(64.0, 8, m, 3);
    assert_eq!(
        term.kernel.len(),
        2 * (m / 3 / 2) + 1,
        "σ spans the box: capped"
    );
    let mut narrow = Smoothing::new(8.0, 8, m, 3);
    assert!(narrow.kernel.len() < term.kernel.len());
    for term in [&mut term, &mut narrow] {
        let mut tmp = vec![0.0; m * m];
        check_operator(m, |x, out| term.apply(m, x, &mut tmp, out));
        let mut smoothed = vec![0.0; m * m];
        term.apply(m, &random(m * m, 3), &mut tmp, &mut smoothed);
        for i in 0..m {
            for j in 0..m {
                let corner = smoothed[(i / 3 * 3) * m + j / 3 * 3];
                assert_eq!(smoothed[i * m + j], corner, "cell ({i}, {j})");
            }
        }
    }
}

/// The far term is built on large boxes only, with a positive weight, and its cells must
/// tile the shared ones.
#[test]
fn far_term_only_on_boxes_that_hold_it() {
    let settings = Extension::default();
    let n_min = settings.large_box;
    let built = Coarse::new(n_min, 64, settings);
    assert_eq!(
        built.far.as_ref().map(|t| t.smoothing.merge),
        Some(settings.far_cell / settings.cell)
    );
    assert!(Coarse::new(n_min / 2, 64, settings).far.is_none());
    let weightless = Extension {
        far_weight: 0.0,
        ..settings
    };
    assert!(Coarse::new(n_min, 64, weightless).far.is_none());
    let untiled = Extension {
        far_cell: 12,
        ..settings
    };
    let message = untiled.check().unwrap_err();
    assert!(message.contains("far cell"), "{message}");
    let message = Extension {
        far_fraction: 1.5,
        ..settings
    }
    .check()
    .unwrap_err();
    assert!(message.contains("far fraction"), "{message}");
}

/// `len` values of the solver tests' reproducible sequence in [−1, 1).
fn random(len: usize, seed: u64) -> Vec<f64> {
    let mut next = super::super::test_support::sequence(seed);
    (0..len).map(|_| next()).collect()
}

/// The near term is switched on after an iteration that changed at most the settled
/// fraction of the contact set, off after one that changed more or before a load's
/// first iteration, never with weight 0 or in full contact; each switch is reported
/// (the direction restarts).
#[test]
fn near_term_follows_the_settled_contact_set() {
    let settings = Extension::default();
    let mut coarse = Coarse::new(128, 8, settings);
    let contact = 10_000.0;
    let settled = (settings.settled_fraction * contact) as usize;
    assert!(!coarse.settle(None) && !coarse.near_on);
    assert!(!coarse.settle(Some((settled + 1, contact))) && !coarse.near_on);
    assert!(coarse.settle(Some((settled, contact))) && coarse.near_on);
    assert!(!coarse.settle(Some((0, contact))) && coarse.near_on);
    assert!(coarse.settle(None) && !coarse.near_on);
    assert!(!coarse.settle(Some((0, (128 * 128) as f64))) && !coarse.near_on);
    let mut without = Coarse::new(
        128,
        8,
        Extension {
            near_weight: 0.0,
            ..settings
        },
    );
    assert!(!without.settle(Some((0, contact))) && !without.near_on);
}

/// The far term is switched on after an iteration that changed at most the far fraction of
/// the contact set (before the near term, whose fraction is smaller), off after one that
/// changed more or before a load's first; each switch of either term is reported; on a
/// box too small for the term it is never on.
#[test]
fn far_term_follows_the_contact_set_before_the_near_term() {
    let settings = Extension {
        far_sigma: 16.0,
        far_cell: 16,
        large_box: 128,
        ..Extension::default()
    };
    assert!(settings.settled_fraction < settings.far_fraction);
    let mut coarse = Coarse::new(128, 8, settings);
    assert!(coarse.far.is_some(), "a large box holds the far term");
    let contact = 10_000.0;
    let far = (settings.far_fraction * contact) as usize;
    let settled = (settings.settled_fraction * contact) as usize;
    assert!(!coarse.settle(None) && !coarse.far_on && !coarse.near_on);
    assert!(!coarse.settle(Some((far + 1, contact))) && !coarse.far_on);
    assert!(coarse.settle(Some((far, contact))) && coarse.far_on && !coarse.near_on);
    assert!(!coarse.settle(Some((settled + 1, contact))) && coarse.far_on && !coarse.near_on);
    assert!(coarse.settle(Some((settled, contact))) && coarse.far_on && coarse.near_on);
    assert!(coarse.settle(Some((far + 1, contact))) && !coarse.far_on && !coarse.near_on);
    assert!(coarse.settle(Some((0, contact))) && coarse.far_on && coarse.near_on);
    assert!(coarse.settle(None) && !coarse.far_on && !coarse.near_on);
    assert!(!coarse.settle(Some((0, (128 * 128) as f64))) && !coarse.far_on);
    let mut small = Coarse::new(64, 8, settings);
    assert!(small.far.is_none());
    assert!(!small.settle(Some((far, contact))) && !small.far_on);
}

fn check_smoothing(kernel: &[f64]) {
    let m = 12;
    assert!(kernel.len() <= m + 1);
    let mut tmp = vec![0.0; m * m];
    check_operator(m, |x, out| smooth(kernel, m, x, &mut tmp, out));
}

/// `apply` (x, out) on the m × m cells is symmetric to rounding, keeps sums and constants.
fn check_operator(m: usize, mut apply: impl FnMut(&[f64], &mut [f64])) {
    let (a, b) = (random(m * m, 1), random(m * m, 2));
    let (mut ga, mut gb) = (vec![0.0; m * m], vec![0.0; m * m]);
    apply(&a, &mut ga);
    apply(&b, &mut gb);
    let lhs: f64 = a.iter().zip(&gb).map(|(x, y)| x * y).sum();
    let rhs: f64 = ga.iter().zip(&b).map(|(x, y)| x * y).sum();
    assert!(
        (lhs - rhs).abs() <= 1e-14 * lhs.abs().max(1.0),
        "{lhs} {rhs}"
    );
    let (sa, sga): (f64, f64) = (a.iter().sum(), ga.iter().sum());
    assert!((sa - sga).abs() <= 1e-13, "{sa} {sga}");
    apply(&vec![1.0; m * m], &mut ga);
    assert!(ga.iter().all(|&v| (v - 1.0).abs() < 1e-14));
}

/// The deflation is built only on large boxes of at least 2 blocks per side and used with
/// the near term, once the contact set covers the coarse fraction of the box; switching it
/// alone is reported too (the direction restarts).
#[test]
fn deflation_follows_the_settled_and_dense_contact_set() {
    let n = 128;
    let op =
        crate::contact::elastic::ElasticOperator::new(crate::grid::Grid::unit(n).unwrap(), 1.0);
    let settings = Extension {
        coarse_block: 32,
        large_box: n,
        ..Extension::default()
    };
    for (small, why) in [
        (
            Extension {
                large_box: 2 * n,
                ..settings
            },
            "not a large box",
        ),
        (
            Extension {
                coarse_block: n,
                ..settings
            },
            "1 block per side",
        ),
    ] {
        let mut small = Coarse::new(n, 8, small);
        small.deflate(&op);
        assert!(small.deflation.is_none(), "{why}");
    }
    let mut coarse = Coarse::new(n, 8, settings);
    coarse.deflate(&op);
    let on = |c: &Coarse| c.deflation.as_ref().unwrap().on;
    let dense = settings.coarse_fraction * (n * n) as f64;
    let sparse = dense - 1.0;
    assert!(coarse.settle(Some((0, dense))) && coarse.near_on && on(&coarse));
    // Near stays on; the deflation alone goes off, then on again.
    assert!(coarse.settle(Some((0, sparse))) && coarse.near_on && !on(&coarse));
    assert!(coarse.settle(Some((0, dense))) && on(&coarse));
    assert!(coarse.settle(None) && !on(&coarse));
}
