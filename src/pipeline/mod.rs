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

/// Whether `e` is the user's input being wrong (a setting, a file, a load), not a failure of
/// the program: the command line exits with 2 for it, the Python package raises `ValueError`.
pub fn is_input_error(e: &anyhow::Error) -> bool {
    use crate::contact::sweep::SweepError;
    e.chain().any(|c| {
        c.downcast_ref::<crate::config::ConfigError>().is_some()
            || c.downcast_ref::<crate::surface::SurfaceError>().is_some()
            || c.downcast_ref::<crate::ranges::InputError>().is_some()
            || c.downcast_ref::<UsageError>().is_some()
            || c.downcast_ref::<crate::io::IoError>().is_some()
            || matches!(
                c.downcast_ref::<SweepError>(),
                Some(SweepError::Input(_))
                    | Some(SweepError::BadLoad { .. })
                    | Some(SweepError::DegenerateSurface { .. })
            )
    })
}
