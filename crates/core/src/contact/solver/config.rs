//! The solver's settings.

use super::extension::Extension;

/// Solver settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverConfig {
    /// Threshold on the complementarity error.
    pub tolerance: f64,
    /// Iteration cap.
    pub max_iterations: usize,
    /// Declare `Stalled` when the error has not reached a new minimum for this many
    /// iterations.
    pub stall_window: usize,
    /// Precondition the conjugate gradient with the inverse elastic operator restricted to
    /// the contact set, `z = P K⁻¹ P g` (`P`: zero off the set, centred on it): one more
    /// convolution per iteration, and an iteration count that grows much more slowly with
    /// n (3.3 times faster for a 16-load 2048² sweep; docs/BENCHMARKS.md). Same fixed point
    /// and error measure. The default; `false` is the plain Polonsky–Keer iteration.
    pub preconditioned: bool,
    /// Extend the preconditioner's input off the free set by the smoothed gradient
    /// ([`Extension`]; used only when `preconditioned`): fewer iterations where the
    /// contact fraction is large, at a pass and two coarse smoothings per iteration. On
    /// (`Extension::default()`) by default; `None` gives `P K⁻¹ P` alone.
    pub extension: Option<Extension>,
    /// Restore the load after the projection `p ← max(p − τ t, 0)` by a uniform offset of
    /// the pressures, `p ← max(p + c, 0)` with `c ≤ 0` such that the mean is `p̄` (the
    /// nearest point of `{p ≥ 0, mean p = p̄}`), instead of rescaling them by one factor;
    /// used (when `preconditioned`) in the iterations that change more than [`super::passes::MAX_SPARSE`]
    /// nodes of the contact set, which convolve anyway. Rescaling takes the load the
    /// clipped nodes gave up from every pressure of the box, the largest most, which on a
    /// moving contact set perturbs the whole box; the offset takes the same amount from
    /// each. The default (`true`); `false` rescales.
    pub offset_to_load: bool,
    /// Start each load of a sweep from the secant through the last two solutions
    /// (extrapolated linearly in the load, clipped at 0; solver/history.rs) instead of the last
    /// one scaled: about 10 % fewer iterations on rough surfaces, for 0.25 n² doubles and
    /// one convolution per load. The default (`true`).
    pub extrapolate_start: bool,
}

impl Default for SolverConfig {
    fn default() -> Self {
        Self {
            tolerance: 1e-10,
            max_iterations: 5000,
            stall_window: 1000,
            preconditioned: true,
            extension: Some(Extension::default()),
            offset_to_load: true,
            extrapolate_start: true,
        }
    }
}
