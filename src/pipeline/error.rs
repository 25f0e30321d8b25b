//! The errors that are the user's: a usage error, and which errors are input errors.

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
