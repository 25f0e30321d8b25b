//! The cached stage graph: content keys ([`hash`]), the artifact store ([`store`]), stage
//! definitions ([`stages`]), the runner ([`runner`]) and the catalog ([`catalog`]).
//!
//! This is the only part of the library that touches polars; the numerical modules know
//! nothing of it.

pub mod catalog;
mod cluster_stages;
mod figures;
pub mod hash;
pub mod plot;
pub mod runner;
pub mod stages;
pub mod store;
