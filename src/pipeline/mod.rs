//! The cached stage graph around the stages of [`crate::stages`]: content keys ([`hash`]),
//! the artifact store ([`store`]), Parquet helpers ([`table`]), the plan ([`plan`]) with its
//! cost model ([`cost`]), the local executor ([`runner`]), the catalog ([`catalog`]), and
//! the cluster executor: a plan cut into job arrays ([`campaign`]) submitted to Slurm
//! ([`slurm`]).

pub mod campaign;
pub mod catalog;
pub mod cost;
mod error;
pub mod gallery;
pub mod measured;
pub mod plan;
pub mod registry;
pub mod report;
pub mod runner;
pub mod slurm;
pub mod sources;
pub mod status;

pub use error::{is_input_error, UsageError};
