//! The configuration's error: a YAML syntax or schema problem, or an invalid value named by
//! its field path.

/// A configuration error: a YAML syntax/schema problem or an invalid value.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    #[error(
        "--config {path}: cannot be read ({cause}); name a pipeline file (default: pipeline.yaml)"
    )]
    Read { path: String, cause: String },
    #[error("{path}: {message}")]
    Parse { path: String, message: String },
    #[error("{path}: {field} = {value}: {allowed}")]
    Invalid {
        path: String,
        field: String,
        value: String,
        allowed: String,
    },
    #[error("{path}: unknown profile '{profile}'; declared profiles: {known}")]
    UnknownProfile {
        path: String,
        profile: String,
        known: String,
    },
}
