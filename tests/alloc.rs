//! No allocation inside the solver's iteration loop: with a counting allocator,
//! two solves with fresh solvers on the same two-thread pool, one taking many more
//! iterations than the other, must allocate exactly as often. Its own test binary, so that
//! no other test's allocations are counted (and one pool, so that no pool's threads are
//! being torn down, which allocates, while another solve is counted).

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use wearcoef::contact::elastic::ElasticOperator;
use wearcoef::contact::solver::{Solver, SolverConfig};
use wearcoef::grid::Grid;
use wearcoef::spectral::Fft2;
use wearcoef::surface::{self, Method, SurfaceParams};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards to the system allocator, only counting calls.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: the caller's contract is passed on unchanged.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: as above.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: as above.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Allocations made by one solve (after the set-up) and its iteration count, on `pool` with
/// a new operator and solver.
fn allocations_of_a_solve(
    pool: &rayon::ThreadPool,
    heights: &[f64],
    n: usize,
    preconditioned: bool,
    tol: f64,
) -> (usize, usize) {
    pool.install(|| {
        let op = ElasticOperator::new(Grid::unit(n).unwrap(), 1.0);
        let mut solver = Solver::new(&op, heights).unwrap();
        let cfg = SolverConfig {
            tolerance: tol,
            preconditioned,
            ..SolverConfig::default()
        };
        if preconditioned {
            // The preconditioned gradient's field is allocated at the first preconditioned
            // solve, before its loop; a first solve at another load allocates it.
            assert!(solver.solve(0.001, &cfg).unwrap().converged());
        }
        let before = ALLOCATIONS.load(Ordering::SeqCst);
        let report = solver.solve(0.02, &cfg).unwrap();
        let after = ALLOCATIONS.load(Ordering::SeqCst);
        assert!(report.converged());
        (after - before, report.iterations)
    })
}

#[test]
fn the_iteration_loop_allocates_nothing() {
    let n = 128;
    let fft = Fft2::new(n);
    let mut scratch = fft.make_scratch();
    let params = SurfaceParams {
        n,
        hurst: 0.8,
        lambda_l_px: 32.0,
        lambda_s_px: 4.0,
        rolloff_lambda_px: None,
        method: Method::Filter,
        seed: 9,
    };
    let heights = surface::generate(&params, &fft, &mut scratch)
        .unwrap()
        .heights;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    for preconditioned in [false, true] {
        let (few, few_iterations) =
            allocations_of_a_solve(&pool, &heights, n, preconditioned, 1e-3);
        let (many, many_iterations) =
            allocations_of_a_solve(&pool, &heights, n, preconditioned, 1e-11);
        assert!(
            many_iterations >= few_iterations + 10,
            "the tolerances must give different iteration counts: {few_iterations}, {many_iterations}"
        );
        assert_eq!(
            few, many,
            "preconditioned {preconditioned}: {few} allocations in {few_iterations} iterations, \
             {many} in {many_iterations}"
        );
    }
}
