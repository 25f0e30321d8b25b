//! # wearcoef
//!
//! A reproducible pipeline for L. Frérot, R. Aghababaei, J.-F. Molinari, "A mechanistic
//! understanding of the wear coefficient: from single to multiple asperities contact",
//! J. Mech. Phys. Solids 114 (2018) 172–184.
//!
//! The physics and statistics live in the `wearcoef-core` crate (re-exported here under the
//! same module names); this crate is the application around it:
//! In layers, each importing only its own and lower ones (checked by `tests/it/layout.rs`):
//! 1. [`io`] (`.npy` fields, measured files, atomic writes), [`machine`], [`format`] (numbers
//!    for readers), [`ranges`] (the accepted range of every number a user types), [`units`]
//!    (quantities typed with their unit), [`tail`] (a load's areas fitted, as JSON rows);
//! 2. [`store`]: content keys, the artifact store, Parquet tables, a stage's inputs;
//!    [`config`]: `pipeline.yaml` (studies, profiles, figures); [`solve`]: the periodic
//!    solve's options, checks and sweep;
//! 3. [`stages`]: the stage contract and one module per stage; [`figures`]: drawing the
//!    paper's figures from stored tables (the figures stage's work);
//! 4. [`pipeline`]: the registry, plan and cost model, executor, catalog, gallery, report,
//!    Slurm; [`wear`]: one measured map to its wear coefficients and trust band (the
//!    command line's `wear` and the Python package's).

pub use wearcoef_core::{
    analytic, clusters, contact, grid, pages, powerlaw, psd, resample, spectral, statistics,
    surface, topography,
};

/// `eprintln!` that never panics: a closed standard error (`wearcoef run 2>&1 | head -1`)
/// loses the line instead of aborting the command.
#[macro_export]
macro_rules! note {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr().lock(), $($arg)*);
    }};
}

pub mod config;
pub mod figures;
pub mod format;
pub mod io;
pub mod machine;
pub mod pipeline;
pub mod ranges;
pub mod solve;
pub mod stages;
pub mod store;
pub mod tail;
pub mod units;
pub mod wear;
