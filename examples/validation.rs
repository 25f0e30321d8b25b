//! The measured numbers of docs/VALIDATION.md: the contact solver against Hertz, Westergaard
//! and the egg-box, the small-load area coefficient κ of self-affine surfaces, the Hurst fit,
//! and the discrete truncated power-law MLE on synthetic samples. The tests assert the
//! tolerances; this prints the values behind them.
//!
//!     cargo run --release --example validation

use std::f64::consts::PI;

use rand::RngExt;
use rand_chacha::rand_core::SeedableRng;
use rand_chacha::ChaCha8Rng;
use wearcoef::contact::elastic::ElasticOperator;
use wearcoef::contact::reference::{Hertz, Westergaard};
use wearcoef::contact::solver::{Solver, SolverConfig};
use wearcoef::grid::Grid;
use wearcoef::powerlaw;
use wearcoef::spectral::Fft2;
use wearcoef::surface::{self, Method, SurfaceParams};

fn cfg(tolerance: f64) -> SolverConfig {
    SolverConfig {
        tolerance,
        ..SolverConfig::default()
    }
}

fn hertz() {
    println!("## Hertz (L/a = 10, tol 1e-12)");
    println!("| N | a/Δ | iterations | err a | err p_max | rel. L2(p) | max |Δp|/p0, r < 0.9a |");
    println!("|---|---|---|---|---|---|---|");
    for n in [128usize, 256, 512] {
        let (r_curv, e_star, a_target) = (1.0, 1.0, 0.1f64);
        let load = 4.0 * a_target.powi(3) * e_star / (3.0 * r_curv);
        let hertz = Hertz {
            load,
            r_curv,
            e_star,
        };
        let dx = 1.0 / n as f64;
        let xy = |i: usize| {
            (
                ((i % n) as f64 - (n / 2) as f64) * dx,
                ((i / n) as f64 - (n / 2) as f64) * dx,
            )
        };
        let h: Vec<f64> = (0..n * n)
            .map(|i| {
                let (x, y) = xy(i);
                -(x * x + y * y) / (2.0 * r_curv)
            })
            .collect();
        let op = ElasticOperator::new(Grid::unit(n).unwrap(), e_star);
        let mut solver = Solver::new(&op, &h).unwrap();
        let report = solver.solve(load, &cfg(1e-12)).unwrap();
        let p = solver.pressure();
        let a = hertz.contact_radius();
        let a_num = (solver.contact_count() as f64 * dx * dx / PI).sqrt();
        let p_max = p.iter().cloned().fold(0.0, f64::max);
        let (mut num, mut den, mut inner) = (0.0, 0.0, 0.0f64);
        for (i, pi) in p.iter().enumerate() {
            let (x, y) = xy(i);
            let r = (x * x + y * y).sqrt();
            let exact = hertz.pressure(r);
            num += (pi - exact).powi(2);
            den += exact * exact;
            if r < 0.9 * a {
                inner = inner.max((pi - exact).abs() / hertz.peak_pressure());
            }
        }
        println!(
            "| {n} | {:.1} | {} | {:+.2} % | {:+.3} % | {:.2} % | {:.2} % |",
            a / dx,
            report.iterations,
            100.0 * (a_num / a - 1.0),
            100.0 * (p_max / hertz.peak_pressure() - 1.0),
            100.0 * (num / den).sqrt(),
            100.0 * inner
        );
    }
}

fn westergaard() {
    println!("\n## Westergaard (tol 1e-12)");
    println!("| N | p̄/p* | iterations | width − 2a (in Δ) | rel. L2(p) | err p_max | mean gap error / 2h0 |");
    println!("|---|---|---|---|---|---|---|");
    let w = Westergaard {
        amplitude: 0.01,
        wavelength: 1.0,
        e_star: 1.0,
    };
    for n in [256usize, 1024] {
        let h: Vec<f64> = (0..n * n)
            .map(|i| w.amplitude * (2.0 * PI * (i % n) as f64 / n as f64).cos())
            .collect();
        let op = ElasticOperator::new(Grid::unit(n).unwrap(), w.e_star);
        let mut solver = Solver::new(&op, &h).unwrap();
        for ratio in [0.1, 0.3, 0.5, 0.8, 1.2] {
            let mean = ratio * w.full_contact_pressure();
            let report = solver.solve(mean, &cfg(1e-12)).unwrap();
            let dx = 1.0 / n as f64;
            let p = &solver.pressure()[..n];
            let (mut num, mut den) = (0.0, 0.0);
            for (j, pj) in p.iter().enumerate() {
                let exact = w.pressure(j as f64 * dx, mean);
                num += (pj - exact).powi(2);
                den += exact * exact;
            }
            let width = p.iter().filter(|&&v| v > 0.0).count() as f64 * dx;
            let exact_width = if ratio < 1.0 {
                2.0 * w.half_width(mean)
            } else {
                1.0
            };
            let p_max = p.iter().cloned().fold(0.0, f64::max);
            let gap = solver.gap().sum::<f64>() / (n * n) as f64;
            let gap_err = if ratio < 1.0 {
                format!(
                    "{:.1e}",
                    (gap - w.mean_gap_over_2h0(mean) * 2.0 * w.amplitude).abs()
                        / (2.0 * w.amplitude)
                )
            } else {
                "—".into()
            };
            println!(
                "| {n} | {ratio} | {} | {:+.1} | {:.3} % | {:+.1e} | {gap_err} |",
                report.iterations,
                (width - exact_width) / dx,
                100.0 * (num / den).sqrt(),
                p_max / w.pressure(0.0, mean) - 1.0,
            );
        }
    }
}

fn eggbox() {
    println!("\n## Egg-box h = D cos(kx) cos(ky), N = 256");
    let n = 256;
    let (d, e_star) = (0.01, 1.0);
    let k = 2.0 * PI;
    let h: Vec<f64> = (0..n * n)
        .map(|i| {
            let (y, x) = ((i / n) as f64 / n as f64, (i % n) as f64 / n as f64);
            d * (k * x).cos() * (k * y).cos()
        })
        .collect();
    let p_star = 2f64.sqrt() * PI * e_star * d;
    let op = ElasticOperator::new(Grid::unit(n).unwrap(), e_star);
    let mut solver = Solver::new(&op, &h).unwrap();
    for ratio in [0.98, 1.02] {
        let report = solver.solve(ratio * p_star, &cfg(1e-12)).unwrap();
        let min_p = solver
            .pressure()
            .iter()
            .cloned()
            .fold(f64::INFINITY, f64::min);
        println!(
            "- p̄/p* = {ratio}: contact fraction {:.4}, min p/p* = {:.4}, {} iterations",
            solver.contact_count() as f64 / (n * n) as f64,
            min_p / p_star,
            report.iterations
        );
    }
}

fn kappa_and_hurst() {
    println!("\n## κ = (A/A0)/(W/W0), 512², H = 0.8, λ_l = 128 Δ, λ_s = 8 Δ, tol 1e-10");
    println!("| seed | Ĥ (filter) | 0.005 | 0.01 | 0.02 | 0.04 |");
    println!("|---|---|---|---|---|---|");
    let n = 512;
    let fft = Fft2::new(n);
    let mut scratch = fft.make_scratch();
    for seed in 1..=3u64 {
        let p = SurfaceParams {
            n,
            hurst: 0.8,
            lambda_l_px: 128.0,
            lambda_s_px: 8.0,
            rolloff_lambda_px: None,
            method: Method::Filter,
            seed,
        };
        let s = surface::generate(&p, &fft, &mut scratch).unwrap();
        let loads = [0.005, 0.01, 0.02, 0.04];
        let (_, results) = wearcoef::contact::sweep::sweep_heights(
            &s.heights,
            n,
            1.0,
            &loads,
            &cfg(1e-10),
            |_, _, _| Ok(()),
        )
        .unwrap();
        let kappa: Vec<String> = results
            .iter()
            .map(|r| format!("{:.2}", r.area_fraction / r.w_over_w0))
            .collect();
        println!(
            "| {seed} | {:.3} | {} |",
            s.stats.hurst_fit.unwrap_or(f64::NAN),
            kappa.join(" | ")
        );
    }
}

/// Discrete power law on [k_min, k_max] by inverse CDF on the exact cumulative sums.
fn sample(alpha: f64, k_min: u64, k_max: u64, n: usize, rng: &mut ChaCha8Rng) -> Vec<u64> {
    let mut cdf = Vec::with_capacity((k_max - k_min + 1) as usize);
    let mut acc = 0.0;
    for k in k_min..=k_max {
        acc += (k as f64).powf(-alpha);
        cdf.push(acc);
    }
    (0..n)
        .map(|_| {
            let u: f64 = rng.random::<f64>() * acc;
            k_min + cdf.partition_point(|&c| c < u) as u64
        })
        .collect()
}

fn mle() {
    println!("\n## Discrete truncated MLE, α = 1.5 on [k_min, 10⁴], 200 samples of n = 1000");
    println!("| k_min | mean α̂ | std α̂ | mean Fisher SE |");
    println!("|---|---|---|---|");
    let mut rng = ChaCha8Rng::seed_from_u64(2018);
    for k_min in [1u64, 5, 20] {
        let fits: Vec<(f64, f64)> = (0..200)
            .map(|_| {
                let data = sample(1.5, k_min, 10_000, 1000, &mut rng);
                let f = powerlaw::fit_discrete(&data, k_min, Some(10_000)).unwrap();
                (f.alpha, f.std_error)
            })
            .collect();
        let m = fits.iter().map(|f| f.0).sum::<f64>() / fits.len() as f64;
        let sd =
            (fits.iter().map(|f| (f.0 - m).powi(2)).sum::<f64>() / (fits.len() - 1) as f64).sqrt();
        let se = fits.iter().map(|f| f.1).sum::<f64>() / fits.len() as f64;
        println!("| {k_min} | {m:.4} | {sd:.4} | {se:.4} |");
    }
}

fn main() {
    hertz();
    westergaard();
    eggbox();
    kappa_and_hurst();
    mle();
}
