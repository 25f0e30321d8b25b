//! The cached stage graph around the stages of [`crate::stages`]: content keys ([`hash`]),
//! the artifact store ([`store`]), Parquet helpers ([`table`]), the plan ([`plan`]) with its
//! cost model ([`cost`]), the local executor ([`runner`]), the catalog ([`catalog`]), and
//! the cluster executor: a plan cut into job arrays ([`campaign`]) submitted to Slurm
//! ([`slurm`]).

pub mod campaign;
pub mod catalog;
pub mod cost;
pub mod gallery;
pub mod measured;
pub mod plan;
pub mod registry;
pub mod report;
pub mod runner;
pub mod slurm;
pub mod sources;
pub mod status;

/// A usage error (an unknown target, a plan that cannot run here): the command exits with
/// status 2.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct UsageError(pub String);
