//! # wearcoef
//!
//! A reproducible pipeline for L. Frérot, R. Aghababaei, J.-F. Molinari, "A mechanistic
//! understanding of the wear coefficient: from single to multiple asperities contact",
//! J. Mech. Phys. Solids 114 (2018) 172–184.
//!
//! ## Module map
//! - Numerical core (no polars, YAML or plotting): [`grid`] (the periodic grid and its
//!   wavevectors), [`spectral`] (planned 2-D real FFTs), [`surface`] (self-affine random
//!   surfaces), [`contact`] (elastic operator and Polonsky–Keer solver), [`clusters`]
//!   (periodic labelling), [`powerlaw`] (maximum-likelihood exponents), [`statistics`]
//!   (wear coefficients, PDFs, CCDFs, confidence bands), [`analytic`] (Archard and the
//!   plateau + power-law model).
//! - Files: [`io`] (`.npy` fields).
//! - Pipeline: [`config`] (`pipeline.yaml`), [`pipeline`] (content keys, artifact store,
//!   runner, catalog).
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
pub mod config;
pub mod contact;
pub mod grid;
pub mod io;
pub mod pipeline;
pub mod powerlaw;
pub mod spectral;
pub mod statistics;
pub mod surface;
