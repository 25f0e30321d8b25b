//! Periodic, isotropic, self-affine random surfaces by Fourier filtering.
//!
//! The power spectral density (up to a constant that the final normalisation removes) is
//!
//! ```text
//! C(q) ∝ (q/q_l)^(−2(1+H))   for q_l ≤ |q| ≤ q_s
//! C(q) ∝ 1                   for q_r ≤ |q| < q_l   (roll-off plateau, only if requested)
//! C(q) = 0                   elsewhere, in particular at q = 0 (zero mean)
//! ```
//!
//! with `q_l = 2π/λ_l`, `q_s = 2π/λ_s`, `q_r = 2π/λ_r`. All wavelengths are given in grid
//! spacings (`λ_px = λ/Δl`), so the integer wavenumber of a wavelength is `k = n/λ_px`.
//!
//! Two generators (see docs/CONVENTIONS.md):
//! - [`Method::Filter`] (default, Hu & Tonder): `H = sqrt(C) · FFT(white noise)`; Gaussian
//!   heights, each mode's power exponentially distributed about `C`.
//! - [`Method::RandomPhase`]: `H = sqrt(C) · e^{iφ}` with `φ` the phase of the FFT of real
//!   white noise (hence Hermitian); each mode has exactly the power `C`.
//!
//! The result is scaled so that the rms slope `sqrt(<|∇h|²>)`, computed spectrally, is 1.
//! Heights then carry the length unit of the box in which slopes are measured; the slope
//! itself is dimensionless and independent of the box size.

use rand_chacha::rand_core::SeedableRng;
use rand_chacha::ChaCha20Rng;
use rand_distr::{Distribution, StandardNormal};
use rustfft::num_complex::Complex64;

use crate::grid::Grid;
use crate::spectral::{Fft2, Fft2Scratch};

/// How random amplitudes are drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Fourier filtering of Gaussian white noise (random amplitude and phase).
    #[default]
    Filter,
    /// Exact amplitude `sqrt(C)`, random Hermitian phase.
    RandomPhase,
}

impl Method {
    /// The name used in files and on the command line.
    pub fn as_str(&self) -> &'static str {
        match self {
            Method::Filter => "filter",
            Method::RandomPhase => "random-phase",
        }
    }

    /// Parse `filter` or `random-phase`.
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "filter" => Some(Method::Filter),
            "random-phase" => Some(Method::RandomPhase),
            _ => None,
        }
    }
}

/// Parameters of one surface realization. Lengths in grid spacings Δl. Serialised with these
/// field names (the pipeline's surface stage hashes them as its job).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceParams {
    /// Nodes per side (`L/Δl`), even.
    pub n: usize,
    /// Hurst exponent H ∈ (0, 1).
    pub hurst: f64,
    /// Largest wavelength of the self-affine range, λ_l/Δl.
    pub lambda_l_px: f64,
    /// Smallest wavelength, λ_s/Δl ≥ 2 (Nyquist).
    pub lambda_s_px: f64,
    /// Optional roll-off: a flat PSD from λ_r down to λ_l (λ_l < λ_r ≤ L).
    pub rolloff_lambda_px: Option<f64>,
    /// Random generator.
    pub method: Method,
    /// Seed of the portable ChaCha20 stream.
    pub seed: u64,
}

/// An invalid surface parameter: the field, the value and what is allowed.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("{field} = {value}: {allowed}")]
pub struct SurfaceError {
    pub field: &'static str,
    pub value: String,
    pub allowed: String,
}

fn bad(field: &'static str, value: impl ToString, allowed: impl Into<String>) -> SurfaceError {
    SurfaceError {
        field,
        value: value.to_string(),
        allowed: allowed.into(),
    }
}

impl SurfaceParams {
    /// Check every parameter; the first violation is returned with its allowed range.
    pub fn validate(&self) -> Result<(), SurfaceError> {
        if self.n < 4 || !self.n.is_multiple_of(2) {
            return Err(bad("n", self.n, "must be an even integer ≥ 4"));
        }
        if !(self.hurst.is_finite() && self.hurst > 0.0 && self.hurst < 1.0) {
            return Err(bad(
                "hurst",
                self.hurst,
                "must lie in the open interval (0, 1)",
            ));
        }
        if !(self.lambda_s_px.is_finite() && self.lambda_s_px >= 2.0) {
            return Err(bad(
                "lambda_s_px",
                self.lambda_s_px,
                "λ_s must be at least 2 grid spacings (the Nyquist wavelength)",
            ));
        }
        let n = self.n as f64;
        if !(self.lambda_l_px.is_finite() && self.lambda_l_px <= n) {
            return Err(bad(
                "lambda_l_px",
                self.lambda_l_px,
                format!("λ_l must not exceed the box size L = {n} grid spacings"),
            ));
        }
        if self.lambda_l_px <= self.lambda_s_px {
            return Err(bad(
                "lambda_l_px",
                self.lambda_l_px,
                format!("λ_l must be larger than λ_s = {}", self.lambda_s_px),
            ));
        }
        if let Some(r) = self.rolloff_lambda_px {
            if !(r.is_finite() && r > self.lambda_l_px && r <= n) {
                return Err(bad(
                    "rolloff_lambda_px",
                    r,
                    format!(
                        "the roll-off wavelength must lie in (λ_l, L] = ({}, {n}]",
                        self.lambda_l_px
                    ),
                ));
            }
        }
        if !self.band_has_a_mode() {
            return Err(bad(
                "lambda_s_px",
                self.lambda_s_px,
                format!(
                    "the band from λ_l = {} to λ_s = {} grid spacings (wavenumbers {:.4} to {:.4} in units of 2π/L) holds no Fourier mode of the {n}² grid: widen the band (a smaller λ_s or a larger λ_l)",
                    self.rolloff_lambda_px.unwrap_or(self.lambda_l_px),
                    self.lambda_s_px,
                    self.k_r(),
                    self.k_s()
                ),
            ));
        }
        Ok(())
    }

    /// Whether some wavevector of the grid (|k_x|, |k_y| ≤ n/2, k ≠ 0) has a non-zero PSD:
    /// for each k_x, the smallest k_y at or above the band's lower edge is tested with
    /// [`SurfaceParams::psd_shape`] itself (and its neighbours, against rounding).
    pub fn band_has_a_mode(&self) -> bool {
        let (lo, hi) = (self.k_r(), self.k_s());
        let half = (self.n / 2) as i64;
        let top = (hi.ceil() as i64).min(half);
        (0..=top).any(|a| {
            let a2 = (a * a) as f64;
            let b0 = (lo * lo - a2).max(0.0).sqrt().floor() as i64;
            ((b0 - 1).max(0)..=(b0 + 2).min(half))
                .any(|b| self.psd_shape(((a * a + b * b) as f64).sqrt()) > 0.0)
        })
    }

    /// Integer wavenumber of λ_l, in units of 2π/L.
    pub fn k_l(&self) -> f64 {
        self.n as f64 / self.lambda_l_px
    }

    /// Integer wavenumber of λ_s, in units of 2π/L.
    pub fn k_s(&self) -> f64 {
        self.n as f64 / self.lambda_s_px
    }

    /// Wavenumber where the roll-off plateau starts (= k_l without roll-off).
    pub fn k_r(&self) -> f64 {
        self.rolloff_lambda_px
            .map_or(self.k_l(), |r| self.n as f64 / r)
    }

    /// Un-normalised PSD shape at wavenumber `k` (units of 2π/L). Band edges are inclusive
    /// to a relative 1e-9 so that `k = n/λ` computed in floating point keeps its mode.
    pub fn psd_shape(&self, k: f64) -> f64 {
        let eps = 1e-9;
        let (k_r, k_l, k_s) = (self.k_r(), self.k_l(), self.k_s());
        if k <= 0.0 || k > k_s * (1.0 + eps) || k < k_r * (1.0 - eps) {
            0.0
        } else if k < k_l * (1.0 - eps) {
            1.0
        } else {
            (k / k_l).powf(-2.0 * (1.0 + self.hurst))
        }
    }
}

/// Statistics of a generated surface, all computed from the final heights.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceStats {
    /// Mean height (zero by construction, to rounding).
    pub mean_height: f64,
    /// rms height sqrt(<h²>), in units of the box side L.
    pub rms_height: f64,
    /// rms slope sqrt(<|∇h|²>), spectral (1 by construction, to rounding).
    pub rms_slope: f64,
    /// Hurst exponent fitted to the radially averaged PSD over the self-affine band, if
    /// the band holds at least three interior integer shells.
    pub hurst_fit: Option<f64>,
}

/// A generated surface: row-major heights on an `n × n` unit-box grid plus its statistics.
#[derive(Debug, Clone)]
pub struct Surface {
    pub grid: Grid,
    pub heights: Vec<f64>,
    pub stats: SurfaceStats,
}

/// Seed of realization `index` of a study whose seed is `study_seed` (SplitMix64 of the
/// pair): distinct, reproducible and independent of the order in which realizations run.
pub fn realization_seed(study_seed: u64, index: u64) -> u64 {
    let mut z = study_seed
        ^ index
            .wrapping_mul(0x9e37_79b9_7f4a_7c15)
            .wrapping_add(0x6a09_e667_f3bc_c909);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Generate a surface on the unit box (L = 1, Δl = 1/n). Plans and scratch are the
/// caller's, so a batch of realizations allocates them once.
pub fn generate(
    params: &SurfaceParams,
    fft: &Fft2,
    scratch: &mut Fft2Scratch,
) -> Result<Surface, SurfaceError> {
    params.validate()?;
    let n = params.n;
    assert_eq!(fft.n(), n, "FFT plan size must match the surface");
    let grid = Grid::unit(n).expect("validated n");

    // White noise from a portable stream, in row-major order.
    let mut rng = ChaCha20Rng::seed_from_u64(params.seed);
    let noise: Vec<f64> = (0..n * n)
        .map(|_| StandardNormal.sample(&mut rng))
        .collect();

    let mut spectrum = fft.make_spectrum();
    fft.forward(&noise, &mut spectrum, scratch);
    drop(noise);

    let h = n / 2 + 1;
    for jx in 0..h {
        for iy in 0..n {
            let c = &mut spectrum[jx * n + iy];
            let amplitude = params.psd_shape(grid.k_norm(jx, iy)).sqrt();
            *c = match params.method {
                Method::Filter => *c * amplitude,
                Method::RandomPhase => {
                    let r = c.norm();
                    if r > 0.0 && amplitude > 0.0 {
                        *c * (amplitude / r)
                    } else {
                        Complex64::new(0.0, 0.0)
                    }
                }
            };
        }
    }
    spectrum[0] = Complex64::new(0.0, 0.0);

    let slope = rms_slope_from_spectrum(&grid, &spectrum);
    let scale = 1.0 / slope;
    let norm = 1.0 / (n * n) as f64;
    let mut heights = vec![0.0; n * n];
    fft.inverse(&mut spectrum, &mut heights, scratch);
    for v in heights.iter_mut() {
        *v *= scale * norm;
    }
    let mean = heights.iter().sum::<f64>() / (n * n) as f64;
    for v in heights.iter_mut() {
        *v -= mean;
    }

    let stats = measure(&grid, &heights, params.k_l(), params.k_s(), fft, scratch);
    Ok(Surface {
        grid,
        heights,
        stats,
    })
}

/// Realised statistics of a height field on `grid` (heights row-major), with the Hurst
/// exponent fitted over the band `[k_l, k_s]` (integer wavenumbers).
pub fn measure(
    grid: &Grid,
    heights: &[f64],
    k_l: f64,
    k_s: f64,
    fft: &Fft2,
    scratch: &mut Fft2Scratch,
) -> SurfaceStats {
    let count = heights.len() as f64;
    let mean_height = heights.iter().sum::<f64>() / count;
    let rms_height = (heights.iter().map(|v| v * v).sum::<f64>() / count).sqrt();
    let mut spectrum = fft.make_spectrum();
    fft.forward(heights, &mut spectrum, scratch);
    SurfaceStats {
        mean_height,
        rms_height,
        rms_slope: rms_slope_from_spectrum(grid, &spectrum),
        hurst_fit: fit_hurst(grid, &spectrum, k_l, k_s),
    }
}

/// rms slope sqrt(<|∇h|²>) of a row-major height field on `grid`, computed spectrally.
pub fn rms_slope(grid: &Grid, heights: &[f64]) -> f64 {
    let fft = Fft2::new(grid.n());
    let mut scratch = fft.make_scratch();
    let mut spectrum = fft.make_spectrum();
    fft.forward(heights, &mut spectrum, &mut scratch);
    rms_slope_from_spectrum(grid, &spectrum)
}

/// rms slope sqrt(<|∇h|²>) of the real field whose unnormalised half spectrum (kx-major)
/// is `spectrum`: `<|∇h|²> = Σ_k |q_k|² |H_k|² / n⁴` over the full spectrum (Parseval).
pub fn rms_slope_from_spectrum(grid: &Grid, spectrum: &[Complex64]) -> f64 {
    let n = grid.n();
    let mut sum = 0.0;
    for jx in 0..grid.half_len() {
        let w = grid.half_weight(jx);
        let row = &spectrum[jx * n..(jx + 1) * n];
        let mut s = 0.0;
        for (iy, c) in row.iter().enumerate() {
            let q = grid.q_norm(jx, iy);
            s += q * q * c.norm_sqr();
        }
        sum += w * s;
    }
    let n4 = (n as f64).powi(4);
    (sum / n4).sqrt()
}

/// Radially averaged PSD on integer shells `k = round(|k|)`: for each shell, the mean
/// `|k|` of its modes and the mean `|H_k|²`. Shells `0..=n/2`.
pub fn radial_psd(grid: &Grid, spectrum: &[Complex64]) -> Vec<(f64, f64, f64)> {
    let n = grid.n();
    let shells = n / 2 + 1;
    let mut acc = vec![(0.0f64, 0.0f64, 0.0f64); shells]; // (weight, Σ w|k|, Σ w|H|²)
    for jx in 0..grid.half_len() {
        let w = grid.half_weight(jx);
        for iy in 0..n {
            let k = grid.k_norm(jx, iy);
            let shell = k.round() as usize;
            if shell < shells {
                let e = &mut acc[shell];
                e.0 += w;
                e.1 += w * k;
                e.2 += w * spectrum[jx * n + iy].norm_sqr();
            }
        }
    }
    acc.into_iter()
        .map(|(w, sk, sp)| {
            if w > 0.0 {
                (w, sk / w, sp / w)
            } else {
                (0.0, 0.0, 0.0)
            }
        })
        .collect()
}

/// Hurst exponent from a least-squares line through `log PSD` against `log |k|` over the
/// integer shells strictly inside `(k_l, k_s)` (the edge shells are only partly filled).
/// `Ĥ = −slope/2 − 1`. `None` if fewer than three shells qualify.
pub fn fit_hurst(grid: &Grid, spectrum: &[Complex64], k_l: f64, k_s: f64) -> Option<f64> {
    let shells = radial_psd(grid, spectrum);
    let lo = k_l.floor() as usize + 1;
    let hi = (k_s.ceil() as usize)
        .saturating_sub(1)
        .min(shells.len() - 1);
    let points: Vec<(f64, f64)> = (lo..=hi)
        .filter(|&s| shells[s].0 > 0.0 && shells[s].2 > 0.0)
        .map(|s| (shells[s].1.ln(), shells[s].2.ln()))
        .collect();
    if points.len() < 3 {
        return None;
    }
    let m = points.len() as f64;
    let mx = points.iter().map(|p| p.0).sum::<f64>() / m;
    let my = points.iter().map(|p| p.1).sum::<f64>() / m;
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = points.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    let slope = sxy / sxx;
    Some(-slope / 2.0 - 1.0)
}
