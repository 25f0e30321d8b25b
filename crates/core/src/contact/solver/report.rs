//! What one solve reports.

/// How a solve ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Status {
    Converged,
    MaxIterations,
    Stalled,
}

/// What happened during one solve.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SolveReport {
    pub status: Status,
    /// CG iterations (each with one or two convolutions).
    pub iterations: usize,
    /// Final complementarity error.
    pub error: f64,
    /// Error before each iteration's update, then the final one.
    pub error_history: Vec<f64>,
    /// Number of applications of the elastic operator (FFT pairs).
    pub convolutions: usize,
    /// Imposed mean pressure (units of E*·… as given).
    pub mean_pressure: f64,
}

impl SolveReport {
    pub fn converged(&self) -> bool {
        self.status == Status::Converged
    }
}
