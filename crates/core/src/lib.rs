//! # wearcoef-core
//!
//! The numerical core of wearcoef (Frérot, Aghababaei & Molinari, JMPS 2018): everything that
//! computes physics or statistics, and nothing that reads or writes files, tables, YAML or
//! plots. Its dependencies are numerical crates only (rustfft, rayon, rand; libc for one
//! `madvise`, [`pages`]), so the compiler keeps it free of the application's IO and it
//! rebuilds in seconds.
//!
//! ## Module map
//! - [`grid`]: the periodic grid and its wavevectors.
//! - [`spectral`]: planned 2-D real FFTs with caller-owned scratch.
//! - [`pages`]: large working arrays on huge pages.
//! - [`surface`]: self-affine random surfaces by Fourier filtering.
//! - [`contact`]: the elastic operator, the Polonsky–Keer solver, load sweeps and analytic
//!   references.
//! - [`clusters`]: periodic labelling of contact maps.
//! - [`powerlaw`]: maximum-likelihood power-law exponents, their intervals and KS distances.
//! - [`statistics`]: wear coefficients, PDFs, CCDFs and confidence bands.
//! - [`analytic`]: Archard's model and the plateau + power-law model.
//!
//! ## Conventions in one page (details in docs/CONVENTIONS.md)
//! - Fields are `n × n`, row-major (row = y), on a periodic box of side `L`; the pipeline
//!   uses `L = 1`, so `Δl = 1/n`. Wavelengths in parameters are in grid spacings (`_px`).
//! - Wavevectors are angular, `q = 2π k/L`, `k` wrapped to `[−n/2, n/2)`.
//! - FFTs are unnormalised both ways (a forward/inverse pair multiplies by `n²`).
//! - Surfaces have zero mean and unit rms slope `sqrt(<|∇h|²>)`, computed spectrally.
//! - Loads are `W/W0` with `W0 = E* · rms slope · L²`.

pub mod analytic;
pub mod clusters;
pub mod contact;
pub mod grid;
pub mod pages;
pub mod powerlaw;
pub mod psd;
pub mod resample;
pub mod spectral;
pub mod statistics;
pub mod surface;
pub mod topography;
