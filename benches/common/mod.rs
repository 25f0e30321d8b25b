//! What several benches share: the surface of `make bench-peers` and its load sweep.

#![allow(dead_code)] // each bench uses a part

use wearcoef::spectral::Fft2;
use wearcoef::statistics::log_edges;
use wearcoef::surface::{self, Method, SurfaceParams};

/// The benchmark surface at `n × n` (as `benches/peers/run.sh` makes it): H = 0.8,
/// λ_l = n/4, λ_s = 8 px, seed 1, Fourier filtering.
pub fn peers_surface(n: usize) -> Vec<f64> {
    let fft = Fft2::new(n);
    let mut scratch = fft.make_scratch();
    let params = SurfaceParams {
        n,
        hurst: 0.8,
        lambda_l_px: n as f64 / 4.0,
        lambda_s_px: 8.0,
        rolloff_lambda_px: None,
        method: Method::Filter,
        seed: 1,
    };
    surface::generate(&params, &fft, &mut scratch)
        .expect("valid surface parameters")
        .heights
}

/// The 30 loads W/W0 of the sweep, log-spaced in [0.001, 0.06].
pub fn peers_loads() -> Vec<f64> {
    log_edges(0.001, 0.06, 29)
}
