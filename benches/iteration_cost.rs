//! Cost of one solver iteration in units of one FFT pair of our own, for the plain and the
//! preconditioned (default) iteration, measured so that the machine's drift cancels: each round times the 30-load
//! sweep (W/W0 log-spaced in [0.001, 0.06], tolerance 1e-8, warm-started, as
//! `make bench-peers`) and, right after each load's solve, a few plain FFT pairs
//! (`Fft2::forward` then `Fft2::inverse`, plans and buffers made once) on the same thread
//! pool; the ratio is taken per round. Prints, per grid size and thread count, the median and the range of
//! the per-round ratios, the convolutions per iteration and the mean iterations per load.
//!
//! `cargo bench --bench iteration_cost [-- ROUNDS [N ...]]` (defaults: 5 rounds,
//! N = 256 512 1024).

use std::time::Instant;

mod common;
use wearcoef::surface;

/// FFT pairs timed after each load's solve.
const PAIRS_PER_LOAD: usize = 8;

use wearcoef::contact::elastic::ElasticOperator;
use wearcoef::contact::solver::{Solver, SolverConfig};
use wearcoef::grid::Grid;
use wearcoef::spectral::Fft2;

fn main() {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let rounds = args.first().copied().unwrap_or(5).max(1);
    let sizes: Vec<usize> = if args.len() > 1 {
        args[1..].to_vec()
    } else {
        vec![256, 512, 1024]
    };
    println!("| N | iteration | threads | iteration / FFT pair (median) | range over {rounds} rounds | convolution / FFT pair (median) | convolutions / iteration | iterations / load |");
    println!("|---|---|---|---|---|---|---|---|");
    for &n in &sizes {
        let fft = Fft2::new(n);
        let mut scratch = fft.make_scratch();
        let heights = common::peers_surface(n);
        let grid = Grid::unit(n).expect("n is even");
        let op = ElasticOperator::new(grid, 1.0);
        let slope = surface::rms_slope(&grid, &heights);
        let loads = common::peers_loads();
        let mut spectrum = fft.make_spectrum();
        let mut ws = op.make_workspace();
        let mut out = vec![0.0; n * n];
        for (preconditioned, threads) in [(false, 1usize), (false, 2), (true, 1), (true, 2)] {
            let cfg = SolverConfig {
                tolerance: 1e-8,
                preconditioned,
                ..SolverConfig::default()
            };
            let variant = if preconditioned {
                "preconditioned"
            } else {
                "plain"
            };
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("a rayon pool");
            let mut ratios = Vec::with_capacity(rounds);
            let mut conv_ratios = Vec::with_capacity(rounds);
            let (mut iterations, mut convolutions) = (0usize, 0usize);
            pool.install(|| {
                for _ in 0..rounds {
                    let mut solver = Solver::new(&op, &heights).expect("finite heights");
                    let (mut its, mut convs) = (0usize, 0usize);
                    let (mut sweep, mut pairs_time, mut pairs) = (0.0f64, 0.0f64, 0usize);
                    for &w in &loads {
                        let start = Instant::now();
                        let report = solver.solve(w * slope, &cfg).expect("valid load");
                        sweep += start.elapsed().as_secs_f64();
                        assert!(report.converged(), "N={n}, W/W0={w}: {:?}", report.status);
                        its += report.iterations;
                        convs += report.convolutions;
                        // FFT pairs right after each load, so that drift cancels.
                        let start = Instant::now();
                        for _ in 0..PAIRS_PER_LOAD {
                            fft.forward(&heights, &mut spectrum, &mut scratch);
                            fft.inverse(&mut spectrum, &mut out, &mut scratch);
                        }
                        pairs_time += start.elapsed().as_secs_f64();
                        pairs += PAIRS_PER_LOAD;
                    }
                    let pair = pairs_time / pairs as f64;
                    // The solver's convolution (`K p`, fused) against the same pairs.
                    let (mut conv_time, mut pair_time) = (0.0f64, 0.0f64);
                    for _ in 0..loads.len() {
                        let start = Instant::now();
                        for _ in 0..PAIRS_PER_LOAD {
                            op.apply(&heights, &mut out, &mut ws);
                        }
                        conv_time += start.elapsed().as_secs_f64();
                        let start = Instant::now();
                        for _ in 0..PAIRS_PER_LOAD {
                            fft.forward(&heights, &mut spectrum, &mut scratch);
                            fft.inverse(&mut spectrum, &mut out, &mut scratch);
                        }
                        pair_time += start.elapsed().as_secs_f64();
                    }
                    conv_ratios.push(conv_time / pair_time);
                    ratios.push(sweep / its as f64 / pair);
                    iterations = its;
                    convolutions = convs;
                }
            });
            ratios.sort_by(f64::total_cmp);
            conv_ratios.sort_by(f64::total_cmp);
            println!(
                "| {n} | {variant} | {threads} | {:.2} | {:.2}–{:.2} | {:.2} | {:.2} | {:.1} |",
                ratios[ratios.len() / 2],
                ratios[0],
                ratios[ratios.len() - 1],
                conv_ratios[conv_ratios.len() / 2],
                convolutions as f64 / iterations as f64,
                iterations as f64 / loads.len() as f64
            );
        }
    }
}
