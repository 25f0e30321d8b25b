use super::*;
use crate::contact::elastic::ElasticOperator;
use crate::grid::Grid;

/// The coarse convolution is `Π K Π`: the fine operator applied to a load constant on
/// each model cell, its deflection averaged over each.
#[test]
fn coarse_convolution_is_the_cell_averaged_operator() {
    let n = 256;
    let op = ElasticOperator::new(Grid::unit(n).unwrap(), 1.0);
    let mut d = Deflation::new(&op, 64, 8).unwrap();
    let (cell, m) = (16, n / 16);
    let x: Vec<f64> = (0..m * m)
        .map(|k| ((k * 7919 % 101) as f64) / 101.0)
        .collect();
    let mut coarse = vec![0.0; m * m];
    d.convolve(&x, &mut coarse);
    let fine: Vec<f64> = (0..n * n)
        .map(|i| x[(i / n / cell) * m + (i % n) / cell])
        .collect();
    let mut u = vec![0.0; n * n];
    op.apply(&fine, &mut u, &mut op.make_workspace());
    let mut averaged = vec![0.0; m * m];
    for (i, v) in u.iter().enumerate() {
        averaged[(i / n / cell) * m + (i % n) / cell] += v / (cell * cell) as f64;
    }
    let scale = averaged.iter().map(|v| v.abs()).fold(0.0, f64::max);
    for (k, (a, b)) in coarse.iter().zip(&averaged).enumerate() {
        assert!((a - b).abs() <= 1e-12 * scale, "cell {k}: {a} against {b}");
    }
}
