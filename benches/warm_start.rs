//! Warm starts of a load sweep compared: each step started from the previous solution,
//! scaled or extrapolated, measured. The 30-load sweep of
//! `make bench-peers` (H = 0.8, λ_l = n/4, λ_s = 8 px, W/W0 log-spaced in [0.001, 0.06],
//! tolerance 1e-8) is solved with four starts for each load:
//! - `scaled`: the previous solution scaled to the new load
//!   (`SolverConfig::extrapolate_start` off);
//! - `cold`: uniform pressure (a new solver per load);
//! - `linear`: `p_k + r (p_k − p_{k−1})` clipped at 0, `r = (W − W_k)/(W_k − W_{k−1})`
//!   (what `Solver::solve` does by default, `p_{k−1}` kept in bfloat16);
//! - `geometric`: per node `p_k (p_k/p_{k−1})^r` with `r = ln(W/W_k)/ln(W_k/W_{k−1})`
//!   where both are positive, `p_k W/W_k` elsewhere (a power law in the load per node);
//! - `nested`: the same load solved first on the grid of n/2 (the heights at every other
//!   node, a sweep of its own with scaled starts), its pressure injected into the 2 × 2
//!   fine nodes of each coarse node; the coarse iterations are counted apart (each costs
//!   about a quarter of a fine one) and their time is included;
//!
//! each then scaled to the load by the solver. Prints, per grid size, iterations and
//! convolutions per load, the sweep time relative to `scaled` (same process, strategies
//! alternating per round, median over rounds) and whether every load ends with the same
//! contact pixel count as `scaled`.
//!
//! `cargo bench --bench warm_start [-- ROUNDS [N ...]]` (defaults: 1 round, N = 256 512).

use std::time::Instant;

mod common;
use wearcoef::surface;

use wearcoef::contact::elastic::ElasticOperator;
use wearcoef::contact::solver::{Solver, SolverConfig};
use wearcoef::grid::Grid;

#[derive(Clone, Copy, PartialEq)]
enum Start {
    Scaled,
    Cold,
    Linear,
    Geometric,
    Nested,
}

impl Start {
    const ALL: [Start; 5] = [
        Start::Scaled,
        Start::Cold,
        Start::Linear,
        Start::Geometric,
        Start::Nested,
    ];

    fn name(self) -> &'static str {
        match self {
            Start::Scaled => "scaled",
            Start::Cold => "cold (uniform)",
            Start::Linear => "linear extrapolation (default)",
            Start::Geometric => "geometric extrapolation",
            Start::Nested => "nested (n/2 first)",
        }
    }
}

/// Totals of one sweep: iterations, convolutions, seconds, contact pixel counts per load.
struct Sweep {
    iterations: usize,
    /// Iterations on the grid of n/2 (nested starts only).
    coarse_iterations: usize,
    convolutions: usize,
    seconds: f64,
    pixels: Vec<usize>,
}

fn sweep(op: &ElasticOperator, heights: &[f64], means: &[f64], start: Start) -> Sweep {
    // The solver's own start extrapolates; every other start is set from outside (which
    // the solver then scales to the load) or scaled.
    let cfg = SolverConfig {
        tolerance: 1e-8,
        extrapolate_start: start == Start::Linear,
        ..SolverConfig::default()
    };
    let mut solver = Solver::new(op, heights).expect("finite heights");
    let mut previous: Option<(f64, Vec<f64>)> = None;
    let mut guess = vec![0.0; heights.len()];
    // The nested start's coarse problem: every other node's height on the grid of n/2.
    let n = (heights.len() as f64).sqrt() as usize;
    let m = n / 2;
    let coarse_heights: Vec<f64> = (0..m * m)
        .map(|k| heights[2 * (k / m) * n + 2 * (k % m)])
        .collect();
    let coarse_op = ElasticOperator::new(Grid::unit(m).expect("n/2 is even"), 1.0);
    let mut coarse = Solver::new(&coarse_op, &coarse_heights).expect("finite heights");
    let mut out = Sweep {
        iterations: 0,
        coarse_iterations: 0,
        convolutions: 0,
        seconds: 0.0,
        pixels: Vec::with_capacity(means.len()),
    };
    let mut last_load = 0.0;
    for &load in means {
        let begin = Instant::now();
        let extrapolate = start == Start::Geometric;
        if start == Start::Cold {
            solver = Solver::new(op, heights).expect("finite heights");
        } else if extrapolate && last_load > 0.0 {
            let mut made = false;
            if let Some((prev_load, prev)) = &previous {
                let p = solver.pressure();
                let r = (load / last_load).ln() / (last_load / prev_load).ln();
                for ((g, &pk), &pj) in guess.iter_mut().zip(p).zip(prev) {
                    *g = if pk > 0.0 && pj > 0.0 {
                        pk * (pk / pj).powf(r)
                    } else {
                        pk * load / last_load
                    };
                }
                made = guess.iter().any(|&g| g > 0.0);
            }
            // Keep p_k (the solver's pressure) before the start replaces it.
            let kept = previous.get_or_insert_with(|| (0.0, vec![0.0; heights.len()]));
            kept.0 = last_load;
            kept.1.copy_from_slice(solver.pressure());
            if made {
                solver.set_start(&guess).expect("a valid start");
            }
        }
        if start == Start::Nested {
            let report = coarse.solve(load, &cfg).expect("valid load");
            assert!(
                report.converged(),
                "coarse load {load}: {:?}",
                report.status
            );
            out.coarse_iterations += report.iterations;
            let pc = coarse.pressure();
            for (k, g) in guess.iter_mut().enumerate() {
                *g = pc[(k / n) / 2 * m + (k % n) / 2];
            }
            solver.set_start(&guess).expect("a valid start");
        }
        let report = solver.solve(load, &cfg).expect("valid load");
        out.seconds += begin.elapsed().as_secs_f64();
        assert!(report.converged(), "load {load}: {:?}", report.status);
        out.iterations += report.iterations;
        out.convolutions += report.convolutions;
        out.pixels.push(solver.contact_count());
        last_load = load;
    }
    out
}

fn main() {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let rounds = args.first().copied().unwrap_or(1).max(1);
    let sizes: Vec<usize> = if args.len() > 1 {
        args[1..].to_vec()
    } else {
        vec![256, 512]
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .build()
        .expect("a rayon pool");
    println!(
        "threads: {} (RAYON_NUM_THREADS), rounds: {rounds}",
        pool.current_num_threads()
    );
    println!("| N | start | iterations / load | convolutions / load | coarse iterations / load | sweep time / scaled (median) | same pixel counts as scaled |");
    println!("|---|---|---|---|---|---|---|");
    for &n in &sizes {
        let heights = common::peers_surface(n);
        let grid = Grid::unit(n).expect("n is even");
        let op = ElasticOperator::new(grid, 1.0);
        let slope = surface::rms_slope(&grid, &heights);
        let means: Vec<f64> = common::peers_loads().iter().map(|w| w * slope).collect();
        let mut ratios: Vec<Vec<f64>> = vec![Vec::new(); Start::ALL.len()];
        let mut last: Vec<Option<Sweep>> = Start::ALL.iter().map(|_| None).collect();
        for _ in 0..rounds {
            // Inside the pool, as the pipeline's solves: a caller outside it would wait
            // for every parallel pass on a third thread.
            let runs: Vec<Sweep> = pool.install(|| {
                Start::ALL
                    .iter()
                    .map(|&s| {
                        let run = sweep(&op, &heights, &means, s);
                        eprintln!("N = {n}, {}: {:.1} s", s.name(), run.seconds);
                        run
                    })
                    .collect()
            });
            for (k, run) in runs.into_iter().enumerate() {
                ratios[k].push(0.0);
                last[k] = Some(run);
            }
            let base = last[0].as_ref().expect("scaled ran").seconds;
            for (k, r) in ratios.iter_mut().enumerate() {
                *r.last_mut().expect("pushed") = last[k].as_ref().expect("ran").seconds / base;
            }
        }
        let loads = means.len() as f64;
        let base_pixels = last[0].as_ref().expect("scaled ran").pixels.clone();
        for (k, start) in Start::ALL.iter().enumerate() {
            let run = last[k].as_ref().expect("ran");
            let mut r = ratios[k].clone();
            r.sort_by(f64::total_cmp);
            println!(
                "| {n} | {} | {:.1} | {:.1} | {:.1} | {:.2} | {} |",
                start.name(),
                run.iterations as f64 / loads,
                run.convolutions as f64 / loads,
                run.coarse_iterations as f64 / loads,
                r[r.len() / 2],
                if run.pixels == base_pixels {
                    "yes"
                } else {
                    "no"
                }
            );
        }
    }
}
