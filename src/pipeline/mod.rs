//! The cached stage graph around the stages of [`crate::stages`]: content keys ([`hash`]),
//! the artifact store ([`store`]), Parquet helpers ([`table`]), the plan ([`plan`]) with its
//! cost model ([`cost`]), the local executor ([`runner`]) and the catalog ([`catalog`]).

pub mod catalog;
pub mod cost;
pub mod hash;
pub mod inputs;
pub mod plan;
pub mod registry;
pub mod runner;
pub mod store;
pub mod table;

/// A usage error (an unknown target, a plan that cannot run here): the command exits with
/// status 2.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct UsageError(pub String);
