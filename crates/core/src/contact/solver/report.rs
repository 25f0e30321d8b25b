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
    /// A solve of `mean_pressure` not yet begun: converged in 0 iterations until the
    /// iteration says otherwise, its history sized for up to `max_iterations`.
    pub(super) fn new(mean_pressure: f64, max_iterations: usize) -> Self {
        Self {
            status: Status::Converged,
            iterations: 0,
            error: 0.0,
            error_history: Vec::with_capacity(max_iterations.min(4096) + 2),
            convolutions: 0,
            mean_pressure,
        }
    }

    pub fn converged(&self) -> bool {
        self.status == Status::Converged
    }
}
