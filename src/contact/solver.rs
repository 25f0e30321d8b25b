//! Polonsky–Keer constrained conjugate gradient under load control (mean pressure imposed),
//! pressure as the unknown (Polonsky & Keer 1999; Rey, Anciaux & Molinari 2017).
//!
//! Minimises `½⟨p, K p⟩ − ⟨p, h⟩` subject to `p ≥ 0` and `mean(p) = p̄`. The gap is
//! `g = (K p − h) − min(K p − h) ≥ 0`, zero in contact.
//!
//! **Convergence** (docs/CONVENTIONS.md): the dimensionless complementarity error
//! `err = Σ p_i g_i / (Σ p_i · σ_h)`, with `σ_h` the standard deviation of the heights about
//! their mean; it is zero only at the exact discrete solution. It is never larger than
//! Tamaas's measure (which divides by the `ddof = 1` deviation), so a tolerance here is at
//! least as strict as the same tolerance there.
//!
//! **Preconditioning** (the default, [`SolverConfig::preconditioned`]): the gradient on the
//! contact set is replaced by `z = P K⁻¹ P g` (`K⁻¹`: the multiplier `E*|q|/2`, 0 at q = 0;
//! `P`: zero off the contact set and centred on it), with `β = ⟨g, z⟩/⟨g, z⟩_old` — the
//! preconditioned conjugate gradient, projected as below. `K⁻¹` is the exact inverse in
//! full contact and approximates the inverse of the restricted operator elsewhere; the
//! iteration count then grows slowly with n (a 16-load 2048² sweep: 1090 iterations against
//! 5399), at one more convolution per iteration. `K⁻¹ P g` is summed over the contact set
//! as its rows leave the inverse FFT (its mean, `⟨g, z⟩` and `Σ g t_old`), so the direction
//! pass only subtracts the mean and the line-search numerator `⟨g, t⟩` follows from those
//! sums.
//!
//! **Cost.** One convolution (`K t`) per iteration (plus `K⁻¹ P g` when preconditioned).
//! A sweep's warm start scales the previous converged state, `p` and `K p` alike
//! (`K (s p) = s K p`), in one pass without a convolution.
//! The deflection is updated by linearity, `u ← s (u − τ K t + K Δ)` (stored as `w = u − h`,
//! so that the passes of an iteration read the heights only when the load is rescaled), where
//! `Δ` is the departure of the projected pressure from the linear step at the nodes that left
//! or re-entered the contact set: `K Δ` is summed directly when there are at most
//! [`MAX_SPARSE`] of them, otherwise convolved by FFT (the rows of `Δ` without a change skip
//! the forward row transform, as do the empty rows of every transformed field), and `u = K p`
//! is recomputed exactly every [`RESYNC`] steps, before convergence is declared, and when more
//! than one node in [`CHANGES_PER_NODE`] of a block changed. The
//! curvature `⟨t, K t⟩` comes from Parseval's identity inside the convolution. The search
//! direction is kept centred on the contact set (the projected conjugate gradient), so the
//! step preserves the load. The direction pass is fused with the forward FFT (each row of
//! `t` is handed to the transform as it is made) and the update pass with the inverse FFT
//! (each row of `K t` is consumed as it comes out, never stored): the line search needs
//! only `⟨t, K t⟩`, which is known before the inverse transform starts. Between the two, the
//! column transforms, the multiplier and Parseval's sum run per group of columns in cache
//! ([`crate::spectral::Fft2::convolve_start`]); an exact recomputation of `u = K p` gathers
//! the next gradient statistics from the rows of `K p` as they come out. All reductions use
//! the FFT's fixed row blocks, so results are bit-identical whatever the number of threads.
//!
//! **Defined behaviour where the method breaks down**:
//! - zero load: `p = 0`, no contact, converged in 0 iterations;
//! - flat surface (σ_h = 0): uniform `p = p̄`, full contact, converged in 0 iterations;
//! - single-node contact set: the centred gradient vanishes and the CG step is 0/0; the step
//!   falls back to a Jacobi-scaled steepest descent on the re-admitted nodes (`τ = 1/K_ii`),
//!   and a single-node solution that is the discrete optimum has error exactly 0;
//! - all pressure projected away: reset to the uniform pressure, restart;
//! - non-finite heights or loads, wrong lengths: an error before solving;
//! - no progress for `stall_window` iterations, or a non-finite error: `Stalled`;
//!   `max_iterations` reached: `MaxIterations`. Neither is ever a result that looks valid.

// Lane loops index several fixed-size arrays in lockstep; iterator chains would hide the
// structure the compiler vectorises.
#![allow(clippy::needless_range_loop)]

use rayon::prelude::*;

use super::elastic::{ElasticOperator, OperatorWorkspace};

/// Independent accumulators per reduction (breaks floating-point dependency chains; the
/// summation order stays fixed).
const LANES: usize = 4;

/// A block of `LANES` values.
#[inline(always)]
fn lanes(slice: &[f64]) -> [f64; LANES] {
    slice.try_into().expect("blocks of LANES values")
}

/// A block of up to `LANES` values (the tail of a row whose length is not a multiple of
/// `LANES`), padded with `fill`.
#[inline(always)]
fn padded(slice: &[f64], fill: f64) -> [f64; LANES] {
    let mut out = [fill; LANES];
    out[..slice.len()].copy_from_slice(slice);
    out
}

/// Per-lane accumulators of the gradient statistics `|S|, Σg, Σg², Σpg, Σp, min g`.
struct GradientLanes {
    n: [f64; LANES],
    sg: [f64; LANES],
    sg2: [f64; LANES],
    spg: [f64; LANES],
    sp: [f64; LANES],
    min: [f64; LANES],
}

impl GradientLanes {
    #[inline(always)]
    fn new() -> Self {
        Self {
            n: [0.0; LANES],
            sg: [0.0; LANES],
            sg2: [0.0; LANES],
            spg: [0.0; LANES],
            sp: [0.0; LANES],
            min: [f64::INFINITY; LANES],
        }
    }

    #[inline(always)]
    fn add(&mut self, p: &[f64; LANES], g: &[f64; LANES]) {
        for l in 0..LANES {
            let m = if p[l] > 0.0 { 1.0 } else { 0.0 };
            self.min[l] = if g[l] < self.min[l] {
                g[l]
            } else {
                self.min[l]
            };
            self.n[l] += m;
            self.sg[l] += m * g[l];
            self.sg2[l] += m * g[l] * g[l];
            self.spg[l] += p[l] * g[l];
            self.sp[l] += p[l];
        }
    }

    /// Add the first `k` lanes of `other` (the valid lanes of a padded tail block).
    #[inline(always)]
    fn merge_lanes(&mut self, other: &Self, k: usize) {
        for l in 0..k {
            self.n[l] += other.n[l];
            self.sg[l] += other.sg[l];
            self.sg2[l] += other.sg2[l];
            self.spg[l] += other.spg[l];
            self.sp[l] += other.sp[l];
            self.min[l] = self.min[l].min(other.min[l]);
        }
    }

    #[inline(always)]
    fn finish(&self) -> [f64; 6] {
        let sum = |a: &[f64; LANES]| a.iter().sum::<f64>();
        [
            sum(&self.n),
            sum(&self.sg),
            sum(&self.sg2),
            sum(&self.spg),
            sum(&self.sp),
            self.min.iter().fold(f64::INFINITY, |a, &b| a.min(b)),
        ]
    }
}

/// When at most this many nodes leave or re-enter the contact set in an iteration, the
/// deflection is corrected by direct summation (all nodes' kernel rows added row by row, in
/// the same pass as the next gradient statistics) instead of a new convolution. Limits of
/// 32–128 save 10–20 % of the convolutions but cost as much in summation
/// (docs/BENCHMARKS.md).
pub const MAX_SPARSE: usize = 6;
/// Exact recomputation of `u = K p` after this many linear updates.
pub const RESYNC: usize = 32;

/// The change lists hold up to one node in `CHANGES_PER_NODE` of each block; an update that
/// changes more recomputes `u = K p` instead of correcting it.
pub const CHANGES_PER_NODE: usize = 16;

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
}

impl Default for SolverConfig {
    fn default() -> Self {
        Self {
            tolerance: 1e-10,
            max_iterations: 5000,
            stall_window: 1000,
            preconditioned: true,
        }
    }
}

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

/// Invalid input to the solver.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ContactError {
    #[error("heights have {got} values but the grid has {expected} (n × n)")]
    BadLength { expected: usize, got: usize },
    #[error("height at row {row}, column {col} is {value}: heights must be finite")]
    NonFinite { row: usize, col: usize, value: f64 },
    #[error("start pressure at row {row}, column {col} is {value}: it must be finite and ≥ 0")]
    BadStart { row: usize, col: usize, value: f64 },
    #[error("mean pressure {0} is invalid: it must be finite and ≥ 0")]
    BadLoad(f64),
    #[error("solver settings invalid: {0}")]
    BadConfig(String),
}

/// A solver bound to one operator and one surface; it keeps its fields between solves so
/// that a load sweep warm-starts each step from the previous solution (scaled to the new
/// load).
pub struct Solver<'a> {
    op: &'a ElasticOperator,
    heights: &'a [f64],
    height_std: f64,
    flat: bool,
    ws: OperatorWorkspace,
    pressure: Vec<f64>,
    /// `w = u − h`, the deflection minus the heights (the gap up to the rigid-body shift),
    /// stored instead of `u` so that the passes of an iteration need not read `h`.
    separation: Vec<f64>,
    /// The search direction `t` during iterations; the gap after a solve.
    direction: Vec<f64>,
    /// Values per work block: the operator's fixed row blocks (`rows_per_block · n`), so
    /// that the passes fused with the FFT and the plain passes reduce over the same blocks
    /// and sums do not depend on the thread count.
    chunk: usize,
    partials: Vec<[f64; 6]>,
    /// Per block: accumulators of the update pass fused with the inverse FFT.
    update_acc: Vec<UpdateAcc>,
    /// Per-block lane sums of [`Solver::precondition`].
    precondition_acc: Vec<[[f64; LANES]; 5]>,
    /// Per block: the nodes whose projection departed from the linear step, `(node, Δ)` in
    /// node order, up to the list's capacity (one node in [`CHANGES_PER_NODE`] of the
    /// block; never reallocated).
    changes: Vec<Vec<(usize, f64)>>,
    sparse: Vec<(usize, f64)>,
    /// The preconditioned gradient `z` (allocated at the first preconditioned solve).
    preconditioned: Vec<f64>,
    has_solution: bool,
    /// Whether `separation` is `K p − h` for the current `pressure`, computed exactly (after
    /// a converged solve; not after [`Self::set_start`]).
    separation_exact: bool,
}

impl<'a> Solver<'a> {
    /// Check the surface and allocate every buffer: 4 n² doubles (the transform's rows, `p`,
    /// `w`, `t`), n²/8 for the lists of changed nodes, and one more n² at the first
    /// preconditioned solve (`z`); besides the heights and the operator's kernel (n²/2).
    pub fn new(op: &'a ElasticOperator, heights: &'a [f64]) -> Result<Self, ContactError> {
        let n = op.grid().n();
        let len = n * n;
        if heights.len() != len {
            return Err(ContactError::BadLength {
                expected: len,
                got: heights.len(),
            });
        }
        if let Some((i, v)) = heights.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(ContactError::NonFinite {
                row: i / n,
                col: i % n,
                value: *v,
            });
        }
        let mean = heights.iter().sum::<f64>() / len as f64;
        let height_std =
            (heights.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / len as f64).sqrt();
        let chunk = op.rows_per_block() * n;
        let blocks = len.div_ceil(chunk);
        let (lo, hi) = heights
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        Ok(Self {
            op,
            heights,
            height_std,
            flat: lo == hi,
            ws: op.make_workspace(),
            pressure: vec![0.0; len],
            separation: vec![0.0; len],
            direction: vec![0.0; len],
            chunk,
            partials: vec![[0.0; 6]; blocks],
            update_acc: (0..blocks).map(|_| UpdateAcc::new()).collect(),
            precondition_acc: vec![[[0.0; LANES]; 5]; blocks],
            changes: (0..blocks)
                .map(|_| Vec::with_capacity((chunk / CHANGES_PER_NODE).max(MAX_SPARSE)))
                .collect(),
            sparse: Vec::with_capacity(MAX_SPARSE),
            preconditioned: Vec::new(),
            has_solution: false,
            separation_exact: false,
        })
    }

    /// Standard deviation of the heights (the error's length scale).
    pub fn height_std(&self) -> f64 {
        self.height_std
    }

    /// Pressure of the last solve (row-major).
    pub fn pressure(&self) -> &[f64] {
        &self.pressure
    }

    /// Gap `(K p − h) − min(K p − h)` of the last solve (row-major).
    pub fn gap(&self) -> &[f64] {
        &self.direction
    }

    /// Number of nodes in contact (`p > 0`) in the last solve.
    pub fn contact_count(&self) -> usize {
        self.pressure.iter().filter(|&&p| p > 0.0).count()
    }

    /// Start the next [`Self::solve`] from `pressure` (row-major, finite, ≥ 0, not all
    /// zero) instead of the previous solution; like the previous solution, it is scaled to
    /// the new load first. For warm starts other than the sweep's own (e.g. extrapolation
    /// over loads, compared in `cargo bench --bench warm_start`).
    pub fn set_start(&mut self, pressure: &[f64]) -> Result<(), ContactError> {
        let n = self.op.grid().n();
        if pressure.len() != self.pressure.len() {
            return Err(ContactError::BadLength {
                expected: self.pressure.len(),
                got: pressure.len(),
            });
        }
        if let Some((i, v)) = pressure
            .iter()
            .enumerate()
            .find(|(_, v)| !(v.is_finite() && **v >= 0.0))
        {
            return Err(ContactError::BadStart {
                row: i / n,
                col: i % n,
                value: *v,
            });
        }
        if pressure.iter().all(|&p| p == 0.0) {
            return Err(ContactError::BadConfig(
                "a start pressure must not be zero everywhere".into(),
            ));
        }
        self.pressure.copy_from_slice(pressure);
        self.has_solution = true;
        self.separation_exact = false;
        Ok(())
    }

    /// Solve for the mean pressure `mean_pressure` (≥ 0), warm-starting from the previous
    /// solution scaled to the new load if there is one.
    pub fn solve(
        &mut self,
        mean_pressure: f64,
        cfg: &SolverConfig,
    ) -> Result<SolveReport, ContactError> {
        if !(mean_pressure.is_finite() && mean_pressure >= 0.0) {
            return Err(ContactError::BadLoad(mean_pressure));
        }
        if !(cfg.tolerance > 0.0 && cfg.tolerance.is_finite()) || cfg.max_iterations == 0 {
            return Err(ContactError::BadConfig(format!(
                "tolerance {} must be finite and > 0, max_iterations {} must be ≥ 1",
                cfg.tolerance, cfg.max_iterations
            )));
        }
        let len = self.pressure.len();
        if cfg.preconditioned && self.preconditioned.len() != len {
            self.preconditioned = vec![0.0; len];
        }
        let target = mean_pressure;
        let mut report = SolveReport {
            status: Status::Converged,
            iterations: 0,
            error: 0.0,
            error_history: Vec::with_capacity(cfg.max_iterations + 2),
            convolutions: 0,
            mean_pressure,
        };

        if target == 0.0 || self.flat {
            self.pressure.fill(target);
            // u = 0: w = −h.
            let h = self.heights;
            self.separation
                .par_iter_mut()
                .zip(h.par_iter())
                .for_each(|(w, &h)| *w = -h);
            self.finish_gap();
            self.has_solution = target > 0.0;
            self.separation_exact = true;
            report.error_history.push(0.0);
            return Ok(report);
        }

        // Start: the previous solution scaled to the new load, or uniform pressure, with the
        // gradient statistics of that state (every update below computes them in the pass
        // that makes the state). After a converged solve `w = K p − h` is exact, and
        // `K (s p) = s K p`, so the scaled start needs a pass, not a convolution.
        let previous_total: f64 = self.chunked_sum(|p| p);
        let warm = self.has_solution && previous_total > 0.0;
        let scale = if warm {
            target * len as f64 / previous_total
        } else {
            1.0
        };
        let mut stats = if warm && self.separation_exact {
            self.sparse.clear();
            self.sparse_update(scale, 0.0)
        } else {
            if warm {
                self.pressure.par_iter_mut().for_each(|p| *p *= scale);
            } else {
                self.pressure.fill(target);
            }
            report.convolutions += 1;
            self.exact_deflection(1.0, 0.0)
        };
        self.has_solution = false;
        self.separation_exact = false;

        let mut exact = true;
        let mut linear_steps = 0usize;
        let mut shift = 0.0f64;
        let mut restart = true;
        let mut g_norm_old = 0.0f64;
        let mut best = f64::INFINITY;
        let mut best_at = 0usize;
        let mut direction_mean = 0.0f64;
        let self_influence = self.op.self_influence();

        loop {
            // Gradient statistics on the contact set.
            let [n_s, sum_g, sum_g2, sum_pg, sum_p, min_g] = stats;
            let mean_g = sum_g / n_s;
            let g_norm = (sum_g2 - n_s * mean_g * mean_g).max(0.0);
            let error = (sum_pg - min_g * sum_p) / (sum_p * self.height_std);

            if error <= cfg.tolerance && !exact {
                // Confirm with an exact deflection (and the exact load) before declaring
                // convergence.
                stats = self.exact_deflection(target * len as f64 / sum_p, shift);
                report.convolutions += 1;
                exact = true;
                linear_steps = 0;
                continue;
            }
            report.error_history.push(error);
            report.error = error;
            if !error.is_finite() {
                report.status = Status::Stalled;
                break;
            }
            if error <= cfg.tolerance {
                report.status = Status::Converged;
                break;
            }
            if error < best {
                best = error;
                best_at = report.iterations;
            } else if report.iterations - best_at >= cfg.stall_window {
                report.status = Status::Stalled;
                break;
            }
            if report.iterations >= cfg.max_iterations {
                report.status = Status::MaxIterations;
                break;
            }
            report.iterations += 1;

            // Pass 2, fused with the forward FFT: conjugate direction on the contact set,
            // kept centred there; then K t and the curvature ⟨t, K t⟩ (Parseval).
            let level = shift + mean_g;
            // ⟨g, z⟩ replaces ⟨g, g⟩ in β when preconditioned.
            let preconditioned = if cfg.preconditioned {
                report.convolutions += 1;
                Some(self.precondition(level))
            } else {
                None
            };
            let g_dot = preconditioned.map_or(g_norm, |(_, g_dot, _, _)| g_dot);
            let beta = if restart || g_norm_old <= 0.0 {
                0.0
            } else {
                g_dot / g_norm_old
            };
            g_norm_old = g_dot;
            let (denominator, numerator) = match preconditioned {
                // Σ_S g t = ⟨g, z − z̄⟩ + β (Σ_S g t_old − t̄ Σ_S g), from the sums of
                // `precondition`, so the direction pass reads t, p and z only.
                Some((z_mean, g_dot, g_t_old, g_sum)) => (
                    self.preconditioned_direction_and_transform(z_mean, beta, direction_mean),
                    g_dot + beta * (g_t_old - direction_mean * g_sum),
                ),
                None => self.direction_and_transform(level, beta, direction_mean),
            };
            report.convolutions += 1;
            // Exact line search.
            let tau = if denominator > 0.0 && denominator.is_finite() && numerator.is_finite() {
                numerator / denominator
            } else {
                1.0 / self_influence
            };

            // Pass 3, fused with the inverse FFT: step, project, re-admit interpenetrating
            // nodes; speculatively update the deflection linearly (u − τ K t) and gather the
            // next gradient statistics.
            let new_shift = level;
            let ([total, kept_t, kept_n, readmitted, changed, _], linear_stats) =
                self.update_from_transform(tau, level, new_shift);
            direction_mean = if kept_n > 0.0 { kept_t / kept_n } else { 0.0 };
            restart = readmitted > 0.0;
            shift = new_shift;
            if total <= 0.0 {
                self.pressure.fill(target);
                stats = self.exact_deflection(1.0, shift);
                report.convolutions += 1;
                exact = true;
                restart = true;
                continue;
            }
            let scale = target * len as f64 / total;
            if changed == 0.0 && linear_steps + 1 < RESYNC {
                // Nothing left or entered the set: p and u are both exact linear updates and
                // the load is preserved (Σ_S t = 0) up to rounding, corrected at the next
                // exact step.
                stats = linear_stats;
                exact = false;
                linear_steps += 1;
            } else if changed as usize <= MAX_SPARSE
                && linear_steps + 1 < RESYNC
                && self.gather_changes()
            {
                stats = self.sparse_update(scale, shift);
                exact = false;
                linear_steps += 1;
            } else if linear_steps + 1 < RESYNC && self.changes_listed() {
                stats = self.fft_correction(scale, shift);
                report.convolutions += 1;
                exact = false;
                linear_steps += 1;
            } else {
                stats = self.exact_deflection(scale, shift);
                report.convolutions += 1;
                exact = true;
                linear_steps = 0;
            }
        }

        self.finish_gap();
        self.has_solution = report.status == Status::Converged;
        // A converged state was confirmed by an exact deflection (or is the flat or zero
        // solution, `w = −h`).
        self.separation_exact = self.has_solution;
        Ok(report)
    }

    /// Sum of `f(p_i)` over all nodes with fixed chunking.
    fn chunked_sum(&mut self, f: impl Fn(f64) -> f64 + Sync) -> f64 {
        self.pressure
            .par_chunks(self.chunk)
            .zip(self.partials.par_iter_mut())
            .for_each(|(pc, part)| part[0] = pc.iter().map(|&p| f(p)).sum());
        self.partials.iter().map(|p| p[0]).sum()
    }

    /// `u ← s (u + K Δ)` for the changed nodes gathered in `self.sparse` (direct summation,
    /// row by row), `p ← s p`, and the gradient statistics ([`gradient_row`]) in the same pass.
    fn sparse_update(&mut self, scale: f64, shift: f64) -> [f64; 6] {
        let (n, chunk, h) = (self.op.grid().n(), self.chunk, self.heights);
        let (op, loads) = (self.op, &self.sparse);
        self.pressure
            .par_chunks_mut(chunk)
            .zip(self.separation.par_chunks_mut(chunk))
            .zip(h.par_chunks(chunk))
            .zip(self.partials.par_iter_mut())
            .enumerate()
            .for_each(|(b, (((pc, wc), hc), part))| {
                let mut acc = GradientLanes::new();
                for (r, ((p, w), h)) in pc
                    .chunks_exact_mut(n)
                    .zip(wc.chunks_exact_mut(n))
                    .zip(hc.chunks_exact(n))
                    .enumerate()
                {
                    dispatch_sparse(
                        op,
                        b * (chunk / n) + r,
                        loads,
                        shift,
                        scale,
                        p,
                        w,
                        h,
                        &mut acc,
                    );
                }
                *part = acc.finish();
            });
        Self::sum_gradient(self.partials.iter().copied())
    }

    /// `u ← s K p`, `p ← s p` (an exact deflection, then the load correction), with the
    /// statistics ([`gradient_row`]) gathered as the rows of `K p` come out of the
    /// inverse FFT (one pass over the fields fewer than applying `K` and then scanning).
    fn exact_deflection(&mut self, scale: f64, shift: f64) -> [f64; 6] {
        let (n, chunk) = (self.op.grid().n(), self.chunk);
        self.op.start_rows(
            self.pressure.par_chunks(chunk),
            |rows: &mut &[f64], r, buf| buf.copy_from_slice(&rows[r * n..(r + 1) * n]),
            &mut self.ws,
        );
        self.finish_deflection(false, scale, shift)
    }

    /// Second half of [`Self::exact_deflection`] (`add = false`: `u ← s K x`) and of
    /// [`Self::fft_correction`] (`add = true`: `u ← s (u + K x)`), with `p ← s p` and the
    /// gradient statistics ([`gradient_row`]) gathered as the rows of `K x` come out of the
    /// inverse FFT started by `start_rows`.
    fn finish_deflection(&mut self, add: bool, scale: f64, shift: f64) -> [f64; 6] {
        let (n, chunk, h) = (self.op.grid().n(), self.chunk, self.heights);
        let blocks = self
            .pressure
            .par_chunks_mut(chunk)
            .zip(self.separation.par_chunks_mut(chunk))
            .zip(h.par_chunks(chunk))
            .zip(self.update_acc.par_iter_mut());
        self.op.finish_rows(
            blocks,
            |(((pc, wc), hc), acc), r, kx| {
                if r == 0 {
                    acc.grad = GradientLanes::new();
                }
                let at = r * n..(r + 1) * n;
                let (p, w, h) = (&mut pc[at.clone()], &mut wc[at.clone()], &hc[at]);
                if add {
                    for (w, k) in w.iter_mut().zip(kx) {
                        *w += k;
                    }
                    dispatch_gradient(shift, Some(scale), p, w, h, &mut acc.grad);
                } else {
                    dispatch_exact(scale, p, w, kx, h);
                    dispatch_gradient(shift, None, p, w, h, &mut acc.grad);
                }
            },
            &mut self.ws,
        );
        self.update_gradient()
    }

    /// The gradient statistics gathered per block in `update_acc`.
    fn update_gradient(&self) -> [f64; 6] {
        Self::sum_gradient(self.update_acc.iter().map(|a| a.grad.finish()))
    }

    /// Block statistics summed in block order (the minimum for the last entry).
    fn sum_gradient(partials: impl Iterator<Item = [f64; 6]>) -> [f64; 6] {
        let mut acc = [0.0, 0.0, 0.0, 0.0, 0.0, f64::INFINITY];
        for part in partials {
            for k in 0..5 {
                acc[k] += part[k];
            }
            acc[5] = acc[5].min(part[5]);
        }
        acc
    }

    /// Pass 2 fused with the first half of `K t`: `t ← (g − ḡ_S) + β (t − t̄_S)` on S, 0
    /// elsewhere (`g − ḡ_S = u − h − level`, `t̄_S = direction_mean`, the mean of the old
    /// direction over the current contact set, so that `Σ_S t = 0`), each row handed to the
    /// forward FFT as it is made. Returns `(⟨t, K t⟩, Σ_S (g − ḡ_S) t)`.
    fn direction_and_transform(
        &mut self,
        level: f64,
        beta: f64,
        direction_mean: f64,
    ) -> (f64, f64) {
        let (n, chunk) = (self.op.grid().n(), self.chunk);
        let blocks = self
            .direction
            .par_chunks_mut(chunk)
            .zip(self.pressure.par_chunks(chunk))
            .zip(self.separation.par_chunks(chunk))
            .zip(self.partials.par_iter_mut());
        let energy = self.op.start_rows(
            blocks,
            |(((tc, pc), wc), part), r, row| {
                if r == 0 {
                    **part = [0.0; 6];
                }
                let at = r * n..(r + 1) * n;
                dispatch_direction(
                    level,
                    beta,
                    direction_mean,
                    &mut tc[at.clone()],
                    &pc[at.clone()],
                    &wc[at],
                    row,
                    part,
                );
            },
            &mut self.ws,
        );
        let numerator = self
            .partials
            .iter()
            .map(|p| p[..LANES].iter().sum::<f64>())
            .sum();
        (energy, numerator)
    }

    /// The preconditioned gradient `z = P K⁻¹ P (g − ḡ_S)` (`P`: zero off the contact set
    /// S, centred on S; `g − ḡ_S = u − h − level`). Each row of `K⁻¹ P (g − ḡ_S)` is
    /// stored raw in `self.preconditioned` as it leaves the inverse FFT, and summed over S
    /// in the same pass: `Σ z`, `|S|`, `Σ g z`, `Σ g`, `Σ g t_old` (`g` centred). The
    /// centring is left to the direction pass, which subtracts the mean. Returns
    /// `(mean of z over S, ⟨g − ḡ_S, z − z̄_S⟩_S, Σ_S g t_old, Σ_S g)`. Summed in a fixed order
    /// (four lanes per block, then the blocks in order), so bit-identical whatever the number
    /// of threads.
    fn precondition(&mut self, level: f64) -> (f64, f64, f64, f64) {
        let (n, chunk) = (self.op.grid().n(), self.chunk);
        let produce = self
            .pressure
            .par_chunks(chunk)
            .zip(self.separation.par_chunks(chunk));
        self.op.start_rows_inverse(
            produce,
            |(pc, wc), r, row| {
                let at = r * n..(r + 1) * n;
                dispatch_precondition_input(level, row, &pc[at.clone()], &wc[at]);
            },
            &mut self.ws,
        );
        self.op.finish_rows(
            self.preconditioned
                .par_chunks_mut(chunk)
                .zip(self.pressure.par_chunks(chunk))
                .zip(self.separation.par_chunks(chunk))
                .zip(self.direction.par_chunks(chunk))
                .zip(self.precondition_acc.par_iter_mut()),
            |((((zc, pc), wc), tc), acc), r, row| {
                if r == 0 {
                    **acc = [[0.0; LANES]; 5];
                }
                let at = r * n..(r + 1) * n;
                dispatch_precondition_output(
                    level,
                    row,
                    &mut zc[at.clone()],
                    &pc[at.clone()],
                    &wc[at.clone()],
                    &tc[at],
                    acc,
                );
            },
            &mut self.ws,
        );
        let mut sums = [0.0; 5];
        for acc in &self.precondition_acc {
            for (s, lanes) in sums.iter_mut().zip(acc) {
                *s += lanes.iter().sum::<f64>();
            }
        }
        let [sz, count, sgz, sg, sgt] = sums;
        let mean = if count > 0.0 { sz / count } else { 0.0 };
        // Σ_S g (z − z̄) = Σ_S g z − z̄ Σ_S g (Σ_S g is zero up to rounding).
        (mean, sgz - mean * sg, sgt, sg)
    }

    /// [`Self::direction_and_transform`] with the preconditioned gradient:
    /// `t ← (z − z̄_S) + β (t − t̄_S)` on S, 0 elsewhere (`z` raw from
    /// [`Self::precondition`], `z̄_S = z_mean`), each row handed to the forward FFT as it is
    /// made. Returns `⟨t, K t⟩`.
    fn preconditioned_direction_and_transform(
        &mut self,
        z_mean: f64,
        beta: f64,
        direction_mean: f64,
    ) -> f64 {
        let (n, chunk) = (self.op.grid().n(), self.chunk);
        let blocks = self
            .direction
            .par_chunks_mut(chunk)
            .zip(self.pressure.par_chunks(chunk))
            .zip(self.preconditioned.par_chunks(chunk));
        self.op.start_rows(
            blocks,
            |((tc, pc), zc), r, row| {
                let at = r * n..(r + 1) * n;
                dispatch_preconditioned_direction(
                    z_mean,
                    beta,
                    direction_mean,
                    &mut tc[at.clone()],
                    row,
                    &pc[at.clone()],
                    &zc[at],
                );
            },
            &mut self.ws,
        )
    }

    /// Pass 3 fused with the second half of `K t` (whose rows arrive from the inverse FFT):
    /// `p ← max(p − τ t, 0)` on S; nodes with `p = 0` and `g − level < 0` are re-admitted
    /// with `p = −τ (g − level)`. Records the nodes where the result departs from the
    /// linear step. Also `u ← u − τ K t` and the gradient statistics of
    /// [`gradient_row`] for the new state with `g = u − h − next_shift` (exact if no
    /// node changed). Returns `[Σp, Σ t over the new S, |new S|, #re-admitted, #changed, 0]`
    /// and those statistics.
    fn update_from_transform(
        &mut self,
        tau: f64,
        level: f64,
        next_shift: f64,
    ) -> ([f64; 6], [f64; 6]) {
        let (n, chunk) = (self.op.grid().n(), self.chunk);
        let args = UpdateArgs {
            tau,
            level,
            next_shift,
        };
        let blocks = self
            .pressure
            .par_chunks_mut(chunk)
            .zip(self.separation.par_chunks_mut(chunk))
            .zip(self.direction.par_chunks(chunk))
            .zip(self.update_acc.par_iter_mut())
            .zip(self.changes.par_iter_mut())
            .enumerate();
        self.op.finish_rows(
            blocks,
            |(block, ((((pc, wc), tc), acc), changes)), r, kt| {
                if r == 0 {
                    **acc = UpdateAcc::new();
                    changes.clear();
                }
                let at = r * n..(r + 1) * n;
                dispatch_update(
                    &args,
                    *block * chunk + r * n,
                    &mut pc[at.clone()],
                    &mut wc[at.clone()],
                    &tc[at],
                    kt,
                    acc,
                    changes,
                );
            },
            &mut self.ws,
        );
        let mut totals = [0.0; 6];
        let mut stats = [0.0, 0.0, 0.0, 0.0, 0.0, f64::INFINITY];
        for acc in &self.update_acc {
            let s = acc.grad.finish();
            totals[0] += s[4];
            totals[1] += acc.kept_t.iter().sum::<f64>();
            totals[2] += s[0];
            totals[3] += acc.readmitted as f64;
            totals[4] += acc.changed as f64;
            for k in 0..5 {
                stats[k] += s[k];
            }
            stats[5] = stats[5].min(s[5]);
        }
        (totals, stats)
    }

    /// Collect the changed nodes of the last update in index order; false if there are
    /// more than [`MAX_SPARSE`] (then an FFT is needed).
    fn gather_changes(&mut self) -> bool {
        self.sparse.clear();
        for (list, acc) in self.changes.iter().zip(&self.update_acc) {
            let count = acc.changed;
            if self.sparse.len() + count > MAX_SPARSE {
                return false;
            }
            self.sparse.extend_from_slice(&list[..count]);
        }
        true
    }

    /// Whether every block's list holds all of its changed nodes.
    fn changes_listed(&self) -> bool {
        self.changes
            .iter()
            .zip(&self.update_acc)
            .all(|(list, acc)| list.len() == acc.changed)
    }

    /// `u ← s (u + K Δ)`, `p ← s p` for the changed nodes listed in `self.changes`, by one
    /// FFT convolution of the sparse field `Δ` (its rows without a change skip the forward
    /// row transform), with the gradient statistics ([`gradient_row`]) gathered as the rows
    /// of `K Δ` come out.
    fn fft_correction(&mut self, scale: f64, shift: f64) -> [f64; 6] {
        let (n, chunk) = (self.op.grid().n(), self.chunk);
        self.op.start_rows(
            self.changes
                .par_iter()
                .enumerate()
                .map(|(b, list)| (b * chunk, list.as_slice())),
            |(first, list): &mut (usize, &[(usize, f64)]), _r, row| {
                // Rows come in order: the list's leading entries below the row's end are
                // this row's.
                row.fill(0.0);
                let end = *first + n;
                let k = list.partition_point(|&(i, _)| i < end);
                for &(i, d) in &list[..k] {
                    row[i - *first] = d;
                }
                *list = &list[k..];
                *first = end;
            },
            &mut self.ws,
        );
        self.finish_deflection(true, scale, shift)
    }

    /// `direction ← w − min w` (the gap; `w = u − h` must be exact).
    fn finish_gap(&mut self) {
        let min = self
            .separation
            .par_iter()
            .copied()
            .reduce(|| f64::INFINITY, f64::min);
        self.direction
            .par_iter_mut()
            .zip(self.separation.par_iter())
            .for_each(|(g, &w)| *g = w - min);
    }
}

/// Define `$name`, which runs `$body` compiled with AVX2 where the processor has it and as
/// is elsewhere. IEEE arithmetic without fused multiply-add gives the same bits either way.
macro_rules! avx2_dispatch {
    ($(#[$attr:meta])* fn $name:ident($($arg:ident: $ty:ty),* $(,)?) $body:block) => {
        $(#[$attr])*
        #[allow(clippy::too_many_arguments)]
        fn $name($($arg: $ty),*) {
            #[inline(always)]
            #[allow(clippy::too_many_arguments)]
            fn body($($arg: $ty),*) $body
            #[cfg(target_arch = "x86_64")]
            {
                #[target_feature(enable = "avx2")]
                #[allow(clippy::too_many_arguments)]
                unsafe fn avx2($($arg: $ty),*) {
                    body($($arg),*)
                }
                if std::is_x86_feature_detected!("avx2") {
                    // SAFETY: the processor supports AVX2 (checked just above).
                    unsafe { avx2($($arg),*) };
                    return;
                }
            }
            body($($arg),*)
        }
    };
    // A named generic body (`#[inline(always)]`), compiled once more with AVX2.
    ($(#[$attr:meta])* fn $name:ident = $body:ident($($arg:ident: $ty:ty),* $(,)?);) => {
        avx2_dispatch! {
            $(#[$attr])*
            fn $name($($arg: $ty),*) { $body($($arg),*) }
        }
    };
}

avx2_dispatch! {
    /// [`gradient_row`] with AVX2 where available.
    fn dispatch_gradient = gradient_row(
        shift: f64,
        scale: Option<f64>,
        p: &mut [f64],
        w: &mut [f64],
        h: &[f64],
        acc: &mut GradientLanes,
    );
}

avx2_dispatch! {
    /// [`exact_row`] with AVX2 where available.
    fn dispatch_exact = exact_row(scale: f64, p: &mut [f64], w: &mut [f64], kx: &[f64], h: &[f64]);
}

avx2_dispatch! {
    /// [`direction_row`] with AVX2 where available.
    fn dispatch_direction = direction_row(
        level: f64,
        beta: f64,
        direction_mean: f64,
        t: &mut [f64],
        p: &[f64],
        w: &[f64],
        row: &mut [f64],
        part: &mut [f64; 6],
    );
}

avx2_dispatch! {
    /// [`update_row`] with AVX2 where available.
    fn dispatch_update = update_row(
        a: &UpdateArgs,
        base: usize,
        pc: &mut [f64],
        wc: &mut [f64],
        tc: &[f64],
        rc: &[f64],
        acc: &mut UpdateAcc,
        changes: &mut Vec<(usize, f64)>,
    );
}

avx2_dispatch! {
    /// One row of [`Solver::sparse_update`], with AVX2 where available: the point loads,
    /// then [`gradient_row`].
    fn dispatch_sparse(
        op: &ElasticOperator,
        iy: usize,
        loads: &[(usize, f64)],
        shift: f64,
        scale: f64,
        p: &mut [f64],
        w: &mut [f64],
        h: &[f64],
        acc: &mut GradientLanes,
    ) {
        op.add_point_loads_row(iy, loads, w);
        gradient_row(shift, Some(scale), p, w, h, acc);
    }
}

avx2_dispatch! {
    /// One row of the preconditioner's input, with AVX2 where available:
    /// `o = w − level` on S = {p > 0}, 0 elsewhere.
    fn dispatch_precondition_input(level: f64, o: &mut [f64], p: &[f64], w: &[f64]) {
        for ((o, &p), &w) in o.iter_mut().zip(p).zip(w) {
            *o = if p > 0.0 { w - level } else { 0.0 };
        }
    }
}

avx2_dispatch! {
    /// One row of `K⁻¹ P g` as it leaves the inverse FFT, with AVX2 where available: stored
    /// in `z`, and with `g = w − level`, `Σ z`, `|S|`, `Σ g z`, `Σ g`, `Σ g t` over
    /// S = {p > 0} added to `acc` (lane `k mod LANES` takes node `k`).
    fn dispatch_precondition_output(
        level: f64,
        row: &[f64],
        z: &mut [f64],
        p: &[f64],
        w: &[f64],
        t: &[f64],
        acc: &mut [[f64; LANES]; 5],
    ) {
        z.copy_from_slice(row);
        let n = row.len();
        let whole = n - n % LANES;
        for i in (0..whole).step_by(LANES) {
            let at = i..i + LANES;
            precondition_sums(
                level,
                &lanes(&row[at.clone()]),
                &lanes(&p[at.clone()]),
                &lanes(&w[at.clone()]),
                &lanes(&t[at]),
                acc,
            );
        }
        if whole < n {
            // Padding: p = 0 puts the extra lanes off S.
            let at = whole..n;
            precondition_sums(
                level,
                &padded(&row[at.clone()], 0.0),
                &padded(&p[at.clone()], 0.0),
                &padded(&w[at.clone()], 0.0),
                &padded(&t[at], 0.0),
                acc,
            );
        }
    }
}

/// [`dispatch_precondition_output`]'s sums for one block of [`LANES`] nodes.
#[inline(always)]
fn precondition_sums(
    level: f64,
    z: &[f64; LANES],
    p: &[f64; LANES],
    w: &[f64; LANES],
    t: &[f64; LANES],
    acc: &mut [[f64; LANES]; 5],
) {
    for k in 0..LANES {
        let on = p[k] > 0.0;
        let g = if on { w[k] - level } else { 0.0 };
        let zk = if on { z[k] } else { 0.0 };
        acc[0][k] += zk;
        acc[1][k] += if on { 1.0 } else { 0.0 };
        acc[2][k] += g * zk;
        acc[3][k] += g;
        acc[4][k] += if on { g * t[k] } else { 0.0 };
    }
}

avx2_dispatch! {
    /// One row of the preconditioned direction, with AVX2 where available:
    /// `t ← (z − z̄) + β (t − t̄)` on S = {p > 0}, 0 elsewhere, copied into `row`.
    fn dispatch_preconditioned_direction(
        z_mean: f64,
        beta: f64,
        direction_mean: f64,
        t: &mut [f64],
        row: &mut [f64],
        p: &[f64],
        z: &[f64],
    ) {
        for (((t, o), &p), &z) in t.iter_mut().zip(row.iter_mut()).zip(p).zip(z) {
            *t = if p > 0.0 {
                (z - z_mean) + beta * (*t - direction_mean)
            } else {
                0.0
            };
            *o = *t;
        }
    }
}

/// One row of the gradient statistics: if a scale `s ≠ 1` is given, `p ← s p` and
/// `u ← s u` (so `w = u − h ← s (w + h) − h`); then, with `g = w − shift`, `min g` over all
/// nodes and `|S|, Σg, Σg², Σpg, Σp` over the contact set `S = {p > 0}`, added to `acc`.
/// `h` is read only to scale.
#[inline(always)]
fn gradient_row(
    shift: f64,
    scale: Option<f64>,
    p: &mut [f64],
    w: &mut [f64],
    h: &[f64],
    acc: &mut GradientLanes,
) {
    if let Some(s) = scale.filter(|&s| s != 1.0) {
        for ((p, w), &h) in p.iter_mut().zip(w.iter_mut()).zip(h) {
            *p *= s;
            *w = s * (*w + h) - h;
        }
    }
    let gap = |w: &[f64; LANES]| {
        let mut g = [0.0; LANES];
        for l in 0..LANES {
            g[l] = w[l] - shift;
        }
        g
    };
    let whole = p.len() / LANES * LANES;
    for (p, w) in p[..whole].chunks_exact(LANES).zip(w.chunks_exact(LANES)) {
        acc.add(&lanes(p), &gap(&lanes(w)));
    }
    if whole < p.len() {
        // Tail of a row whose length is not a multiple of LANES: the padding (p = 0) is
        // off the contact set; only the valid lanes enter the minimum.
        let k = p.len() - whole;
        let mut tail = GradientLanes::new();
        let g = gap(&padded(&w[whole..], 0.0));
        tail.add(&padded(&p[whole..], 0.0), &g);
        acc.merge_lanes(&tail, k);
    }
}

/// One row of an exact recomputation: `w ← s K p − h` from the row `kx` of `K p`, `p ← s p`.
#[inline(always)]
fn exact_row(scale: f64, p: &mut [f64], w: &mut [f64], kx: &[f64], h: &[f64]) {
    for (((p, w), &k), &h) in p.iter_mut().zip(w.iter_mut()).zip(kx).zip(h) {
        *p *= scale;
        *w = scale * k - h;
    }
}

/// Direction update of one row (see [`Solver::direction_and_transform`]): writes `t` and
/// the FFT's input row, adds `(g − ḡ_S) t` to the lane sums `part[..LANES]`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn direction_row(
    level: f64,
    beta: f64,
    direction_mean: f64,
    t: &mut [f64],
    p: &[f64],
    w: &[f64],
    row: &mut [f64],
    part: &mut [f64; 6],
) {
    let mut num = [0.0f64; LANES];
    let body =
        |t: &mut [f64; LANES], p: &[f64; LANES], w: &[f64; LANES], num: &mut [f64; LANES]| {
            for l in 0..LANES {
                let m = if p[l] > 0.0 { 1.0 } else { 0.0 };
                let gc = w[l] - level;
                t[l] = m * (gc + beta * (t[l] - direction_mean));
                num[l] += gc * t[l];
            }
        };
    let whole = t.len() / LANES * LANES;
    for (((t, p), w), o) in t[..whole]
        .chunks_exact_mut(LANES)
        .zip(p.chunks_exact(LANES))
        .zip(w.chunks_exact(LANES))
        .zip(row.chunks_exact_mut(LANES))
    {
        let mut tn = lanes(t);
        body(&mut tn, &lanes(p), &lanes(w), &mut num);
        t.copy_from_slice(&tn);
        o.copy_from_slice(&tn);
    }
    if whole < t.len() {
        // Tail of a row whose length is not a multiple of LANES: padded with p = 0 (off S),
        // so the padding contributes exactly 0.
        let k = t.len() - whole;
        let mut tn = padded(&t[whole..], 0.0);
        body(
            &mut tn,
            &padded(&p[whole..], 0.0),
            &padded(&w[whole..], 0.0),
            &mut num,
        );
        t[whole..].copy_from_slice(&tn[..k]);
        row[whole..].copy_from_slice(&tn[..k]);
    }
    for l in 0..LANES {
        part[l] += num[l];
    }
}

/// Scalars of one update pass.
struct UpdateArgs {
    tau: f64,
    level: f64,
    next_shift: f64,
}

/// Accumulators of the update pass over one block.
struct UpdateAcc {
    grad: GradientLanes,
    kept_t: [f64; LANES],
    changed: usize,
    readmitted: usize,
}

impl UpdateAcc {
    fn new() -> Self {
        Self {
            grad: GradientLanes::new(),
            kept_t: [0.0; LANES],
            changed: 0,
            readmitted: 0,
        }
    }
}

/// One block of `LANES` nodes of the update pass; returns the departures from the linear
/// step (`Δ`), zero where the node stayed on its linear path.
#[inline(always)]
fn update_lanes(
    a: &UpdateArgs,
    pn: &mut [f64; LANES],
    wn: &mut [f64; LANES],
    t: &[f64; LANES],
    r: &[f64; LANES],
    acc: &mut UpdateAcc,
) -> [f64; LANES] {
    let (tau, level, next_shift) = (a.tau, a.level, a.next_shift);
    let mut g = [0.0; LANES];
    let mut delta = [0.0; LANES];
    for l in 0..LANES {
        let stepped = pn[l] - tau * t[l]; // t = 0 off S, so p stays 0 there
        let kept = if stepped > 0.0 { stepped } else { 0.0 };
        let gc = wn[l] - level;
        let new = if kept == 0.0 && gc < 0.0 {
            -tau * gc
        } else {
            kept
        };
        pn[l] = new;
        delta[l] = new - stepped;
        let m = if new > 0.0 { 1.0 } else { 0.0 };
        acc.kept_t[l] += m * t[l];
        wn[l] -= tau * r[l];
        g[l] = wn[l] - next_shift;
    }
    acc.grad.add(pn, &g);
    delta
}

/// Record the nodes of one lane block that left or (re-)entered the contact set.
#[inline(always)]
fn record_changes(
    delta: &[f64; LANES],
    pn: &[f64; LANES],
    first: usize,
    valid: usize,
    acc: &mut UpdateAcc,
    changes: &mut Vec<(usize, f64)>,
) {
    for l in 0..valid {
        if delta[l] != 0.0 {
            // Within the capacity reserved up front: no allocation.
            if changes.len() < changes.capacity() {
                changes.push((first + l, delta[l]));
            }
            acc.changed += 1;
            // Re-admitted: positive now although the linear step left it at ≤ 0.
            if pn[l] > 0.0 {
                acc.readmitted += 1;
            }
        }
    }
}

/// The update pass over one row (see [`Solver::update_from_transform`]); `base` is the
/// node index of the row's first value, `rc` the row of `K t`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn update_row(
    a: &UpdateArgs,
    base: usize,
    pc: &mut [f64],
    wc: &mut [f64],
    tc: &[f64],
    rc: &[f64],
    acc: &mut UpdateAcc,
    changes: &mut Vec<(usize, f64)>,
) {
    let whole = pc.len() / LANES * LANES;
    for (block, (((p, w), t), r)) in pc[..whole]
        .chunks_exact_mut(LANES)
        .zip(wc.chunks_exact_mut(LANES))
        .zip(tc.chunks_exact(LANES))
        .zip(rc.chunks_exact(LANES))
        .enumerate()
    {
        let (mut pn, mut wn) = (lanes(p), lanes(w));
        let delta = update_lanes(a, &mut pn, &mut wn, &lanes(t), &lanes(r), acc);
        p.copy_from_slice(&pn);
        w.copy_from_slice(&wn);
        // Rare path: a node left or (re-)entered the contact set.
        // Non-short-circuiting, so that the test is one vector comparison, not a branch
        // per lane.
        if delta.iter().fold(false, |any, &d| any | (d != 0.0)) {
            record_changes(&delta, &pn, base + block * LANES, LANES, acc, changes);
        }
    }
    if whole < pc.len() {
        // Tail of a row whose length is not a multiple of LANES. The padding (p = t = 0,
        // w − level = 0) stays off the contact set, is not re-admitted and has Δ = 0; only
        // the valid lanes are merged into the statistics.
        let k = pc.len() - whole;
        let (mut pn, mut wn) = (padded(&pc[whole..], 0.0), padded(&wc[whole..], a.level));
        let mut tail = UpdateAcc::new();
        let delta = update_lanes(
            a,
            &mut pn,
            &mut wn,
            &padded(&tc[whole..], 0.0),
            &padded(&rc[whole..], 0.0),
            &mut tail,
        );
        pc[whole..].copy_from_slice(&pn[..k]);
        wc[whole..].copy_from_slice(&wn[..k]);
        record_changes(&delta, &pn, base + whole, k, acc, changes);
        acc.grad.merge_lanes(&tail.grad, k);
        for l in 0..k {
            acc.kept_t[l] += tail.kept_t[l];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Grid;

    /// The FFT correction `u ← s (u + K Δ)` from the change lists equals an exact
    /// recomputation `u = s K (p + Δ)`, with the same gradient statistics, when `Δ` sits on a
    /// few rows (the others skip their forward row transform) or on many.
    #[test]
    fn fft_correction_equals_an_exact_recomputation() {
        let n = 64;
        let op = ElasticOperator::new(Grid::unit(n).unwrap(), 1.0);
        let heights: Vec<f64> = (0..n * n)
            .map(|i| ((i * 7919 % 1009) as f64 / 1009.0 - 0.5) * 0.01)
            .collect();
        // A pressure on rows 10–29 only; changes on rows 3, 12 and 40, or on every row.
        let start: Vec<f64> = (0..n * n)
            .map(|i| {
                let row = i / n;
                if (10..30).contains(&row) {
                    (i * 31 % 97) as f64 / 97.0
                } else {
                    0.0
                }
            })
            .collect();
        let few: Vec<(usize, f64)> = (0..40)
            .map(|k| {
                let row = [3, 12, 40][k % 3];
                (row * n + (k * 13) % n, 0.01 * (k as f64 + 1.0))
            })
            .collect();
        let many: Vec<(usize, f64)> = (0..n).map(|r| (r * n + (r * 5) % n, 0.02)).collect();
        for changes in [few, many] {
            let (scale, shift) = (0.9, 0.003);
            let mut solver = Solver::new(&op, &heights).unwrap();
            solver.pressure.copy_from_slice(&start);
            solver.exact_deflection(1.0, 0.0);
            let mut changed = start.clone();
            let mut sorted = changes.clone();
            sorted.sort_by_key(|c| c.0);
            sorted.dedup_by_key(|c| c.0);
            for list in &mut solver.changes {
                list.clear();
            }
            for acc in &mut solver.update_acc {
                acc.changed = 0;
            }
            for &(i, d) in &sorted {
                changed[i] += d;
                solver.pressure[i] += d;
                let b = i / solver.chunk;
                solver.changes[b].push((i, d));
                solver.update_acc[b].changed += 1;
            }
            assert!(solver.changes_listed());
            let stats = solver.fft_correction(scale, shift);

            let mut exact = Solver::new(&op, &heights).unwrap();
            exact.pressure.copy_from_slice(&changed);
            let expected = exact.exact_deflection(scale, shift);
            let u_max = exact.separation.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (i, (a, b)) in solver.separation.iter().zip(&exact.separation).enumerate() {
                assert!((a - b).abs() <= 1e-13 * u_max, "node {i}: {a} vs {b}");
            }
            assert_eq!(solver.pressure, exact.pressure);
            for k in 0..6 {
                let tol = 1e-11 * expected[k].abs().max(1e-300);
                assert!(
                    (stats[k] - expected[k]).abs() <= tol,
                    "statistic {k}: {} vs {}",
                    stats[k],
                    expected[k]
                );
            }
        }
    }

    /// A block that changed more nodes than its list holds forces an exact recomputation.
    #[test]
    fn overflowing_change_lists_are_detected() {
        let n = 32;
        let op = ElasticOperator::new(Grid::unit(n).unwrap(), 1.0);
        let heights: Vec<f64> = (0..n * n).map(|i| (i % 7) as f64).collect();
        let mut solver = Solver::new(&op, &heights).unwrap();
        let cap = solver.changes[0].capacity();
        for k in 0..cap {
            solver.changes[0].push((k, 1.0));
        }
        solver.update_acc[0].changed = cap;
        assert!(solver.changes_listed());
        solver.update_acc[0].changed = cap + 1;
        assert!(!solver.changes_listed());
    }
}
