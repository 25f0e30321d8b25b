//! Criterion benchmarks of the elastic operator and the contact solver on a 512² rough
//! surface, periodic and free-boundary (`PaddedOperator`, the same surface taken as a
//! measured, non-periodic one); the peer comparison with Tamaas is `make bench-peers`.

use criterion::{criterion_group, criterion_main, Criterion};
use wearcoef::contact::elastic::ElasticOperator;
use wearcoef::contact::padded::PaddedOperator;
use wearcoef::contact::solver::{NonNegative, Solver, SolverConfig};
use wearcoef::grid::Grid;
use wearcoef::spectral::Fft2;
use wearcoef::surface::{self, Method, SurfaceParams};

fn solver(c: &mut Criterion) {
    let n = 512;
    let fft = Fft2::new(n);
    let mut scratch = fft.make_scratch();
    let params = SurfaceParams {
        n,
        hurst: 0.8,
        lambda_l_px: 128.0,
        lambda_s_px: 8.0,
        rolloff_lambda_px: None,
        method: Method::Filter,
        seed: 1,
    };
    let h = surface::generate(&params, &fft, &mut scratch)
        .unwrap()
        .heights;
    let op = ElasticOperator::new(Grid::unit(n).unwrap(), 1.0);
    let padded = PaddedOperator::new(Grid::unit(n).unwrap(), 1.0);
    let mut ws = op.make_workspace();
    let mut out = vec![0.0; n * n];
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let mut group = c.benchmark_group(format!("threads{threads}"));
        group.sample_size(10);
        group.bench_function("operator_apply_512", |b| {
            pool.install(|| b.iter(|| op.apply(&h, &mut out, &mut ws)))
        });
        group.bench_function("fft_pair_512", |b| {
            let mut spec = fft.make_spectrum();
            pool.install(|| {
                b.iter(|| {
                    fft.forward(&h, &mut spec, &mut scratch);
                    fft.inverse(&mut spec, &mut out, &mut scratch);
                })
            })
        });
        group.bench_function("solve_512_w0.01_tol1e-10_cold", |b| {
            let cfg = SolverConfig {
                tolerance: 1e-10,
                ..SolverConfig::default()
            };
            pool.install(|| {
                b.iter(|| {
                    let mut s = Solver::new(&op, &h).unwrap();
                    s.solve(0.01, &cfg).unwrap()
                })
            })
        });
        group.bench_function("solve_512_w0.01_tol1e-10_cold_padded", |b| {
            let cfg = SolverConfig {
                tolerance: 1e-10,
                ..SolverConfig::default()
            };
            pool.install(|| {
                b.iter(|| {
                    let mut s = Solver::with_constraint(&padded, &h, NonNegative).unwrap();
                    s.solve(0.01, &cfg).unwrap()
                })
            })
        });
        group.finish();
    }
}

criterion_group!(benches, solver);
criterion_main!(benches);
