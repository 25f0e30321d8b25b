//! The error of reading or writing a field file.

/// Errors reading or writing field files.
#[derive(Debug, thiserror::Error)]
pub enum IoError {
    #[error("{path}: {message}")]
    File { path: String, message: String },
}
