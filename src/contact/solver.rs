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
//! **Cost.** One convolution (`K t`) per iteration, plus one more only in iterations whose
//! projection changed the contact set; otherwise the deflection is updated by linearity,
//! `u ← s (u − τ K t)`, and recomputed exactly every [`RESYNC`] such steps and before
//! convergence is declared. All reductions use a fixed chunking, so results are bit-identical
//! whatever the number of threads.
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

use rayon::prelude::*;

use super::elastic::{ElasticOperator, OperatorWorkspace};

/// Elements per reduction chunk (fixed, so sums do not depend on the thread count).
const CHUNK: usize = 8192;
/// Independent accumulators per reduction (breaks floating-point dependency chains; the
/// summation order stays fixed).
const LANES: usize = 8;
/// Exact recomputation of `u = K p` after this many linear updates.
pub const RESYNC: usize = 32;

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
}

impl Default for SolverConfig {
    fn default() -> Self {
        Self {
            tolerance: 1e-10,
            max_iterations: 5000,
            stall_window: 1000,
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
    deflection: Vec<f64>,
    direction: Vec<f64>,
    /// `K t` during iterations; the gap after a solve.
    work: Vec<f64>,
    partials: Vec<[f64; 6]>,
    has_solution: bool,
}

#[derive(Clone, Copy)]
enum Pending {
    /// `u` is exactly `K p`.
    Exact,
    /// `p ← s p`, `u ← s u` (after an exact convolution of the unscaled `p`).
    Scale(f64),
    /// `p ← s p`, `u ← s (u − τ K t)` (linear update, no projection happened).
    Linear { tau: f64, scale: f64 },
}

impl<'a> Solver<'a> {
    /// Check the surface and allocate every buffer (about 7.5 n² doubles with the
    /// operator's, besides the heights).
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
            deflection: vec![0.0; len],
            direction: vec![0.0; len],
            work: vec![0.0; len],
            partials: vec![[0.0; 6]; len.div_ceil(CHUNK)],
            has_solution: false,
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
        &self.work
    }

    /// Number of nodes in contact (`p > 0`) in the last solve.
    pub fn contact_count(&self) -> usize {
        self.pressure.iter().filter(|&&p| p > 0.0).count()
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
            self.deflection.fill(0.0);
            self.finish_gap();
            self.has_solution = target > 0.0;
            report.error_history.push(0.0);
            return Ok(report);
        }

        // Start: the previous solution scaled to the new load, or uniform pressure.
        let previous_total: f64 = self.chunked_sum(|p| p);
        if self.has_solution && previous_total > 0.0 {
            let s = target * len as f64 / previous_total;
            self.pressure.par_iter_mut().for_each(|p| *p *= s);
        } else {
            self.pressure.fill(target);
        }
        self.has_solution = false;
        self.op
            .apply(&self.pressure, &mut self.deflection, &mut self.ws);
        report.convolutions += 1;

        let mut pending = Pending::Exact;
        let mut exact = true;
        let mut linear_steps = 0usize;
        let mut shift = 0.0f64;
        let mut restart = true;
        let mut g_norm_old = 0.0f64;
        let mut best = f64::INFINITY;
        let mut best_at = 0usize;
        let self_influence = self.op.self_influence();

        loop {
            // Pass 1: apply the pending update; gradient statistics on the contact set.
            let s1 = self.pass_gradient(pending, shift);
            pending = Pending::Exact;
            let [n_s, sum_g, sum_g2, sum_pg, sum_p, min_g] = s1;
            let mean_g = sum_g / n_s;
            let g_norm = (sum_g2 - n_s * mean_g * mean_g).max(0.0);
            let error = (sum_pg - min_g * sum_p) / (sum_p * self.height_std);

            if error <= cfg.tolerance && !exact {
                // Confirm with an exact deflection before declaring convergence.
                self.op
                    .apply(&self.pressure, &mut self.deflection, &mut self.ws);
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

            // Pass 2: conjugate direction on the contact set.
            let beta = if restart || g_norm_old <= 0.0 {
                0.0
            } else {
                g_norm / g_norm_old
            };
            g_norm_old = g_norm;
            let numerator = self.pass_direction(shift + mean_g, beta);

            // K t, then the exact line search with the direction's image centred on S.
            self.op.apply(&self.direction, &mut self.work, &mut self.ws);
            report.convolutions += 1;
            let [sum_r, sum_rt, sum_t, _, _, _] = self.pass_curvature();
            let denominator = sum_rt - sum_r / n_s * sum_t;
            let tau = if denominator > 0.0 && denominator.is_finite() && numerator.is_finite() {
                numerator / denominator
            } else {
                1.0 / self_influence
            };

            // Pass 4: step, project, re-admit interpenetrating nodes.
            let [total, clipped, readmitted, _, _, _] = self.pass_update(tau, shift + mean_g);
            restart = readmitted > 0.0;
            shift += mean_g;
            if total <= 0.0 {
                self.pressure.fill(target);
                self.op
                    .apply(&self.pressure, &mut self.deflection, &mut self.ws);
                report.convolutions += 1;
                exact = true;
                restart = true;
                continue;
            }
            let scale = target * len as f64 / total;
            if clipped > 0.0 || readmitted > 0.0 || linear_steps + 1 >= RESYNC {
                self.op
                    .apply(&self.pressure, &mut self.deflection, &mut self.ws);
                report.convolutions += 1;
                pending = Pending::Scale(scale);
                exact = true;
                linear_steps = 0;
            } else {
                pending = Pending::Linear { tau, scale };
                exact = false;
                linear_steps += 1;
            }
        }

        self.finish_gap();
        self.has_solution = report.status == Status::Converged;
        Ok(report)
    }

    /// Sum of `f(p_i)` over all nodes with fixed chunking.
    fn chunked_sum(&mut self, f: impl Fn(f64) -> f64 + Sync) -> f64 {
        self.pressure
            .par_chunks(CHUNK)
            .zip(self.partials.par_iter_mut())
            .for_each(|(pc, part)| part[0] = pc.iter().map(|&p| f(p)).sum());
        self.partials.iter().map(|p| p[0]).sum()
    }

    /// Apply `pending`, then over all nodes: `min(g)`, and over the contact set `S = {p > 0}`:
    /// `|S|, Σg, Σg², Σpg, Σp`, with `g = u − h − shift`.
    fn pass_gradient(&mut self, pending: Pending, shift: f64) -> [f64; 6] {
        let h = self.heights;
        self.pressure
            .par_chunks_mut(CHUNK)
            .zip(self.deflection.par_chunks_mut(CHUNK))
            .zip(h.par_chunks(CHUNK))
            .zip(self.work.par_chunks(CHUNK))
            .zip(self.partials.par_iter_mut())
            .for_each(|((((pc, uc), hc), rc), part)| {
                match pending {
                    Pending::Exact => {}
                    Pending::Scale(s) => {
                        for (p, u) in pc.iter_mut().zip(uc.iter_mut()) {
                            *p *= s;
                            *u *= s;
                        }
                    }
                    Pending::Linear { tau, scale } => {
                        for ((p, u), r) in pc.iter_mut().zip(uc.iter_mut()).zip(rc) {
                            *p *= scale;
                            *u = scale * (*u - tau * r);
                        }
                    }
                }
                let (mut n, mut sg, mut sg2, mut spg, mut sp) = (
                    [0.0f64; LANES],
                    [0.0; LANES],
                    [0.0; LANES],
                    [0.0; LANES],
                    [0.0; LANES],
                );
                let mut min = [f64::INFINITY; LANES];
                let mut step = |p: &[f64], u: &[f64], h: &[f64]| {
                    for l in 0..p.len() {
                        let g = u[l] - h[l] - shift;
                        let m = if p[l] > 0.0 { 1.0 } else { 0.0 };
                        min[l] = if g < min[l] { g } else { min[l] };
                        n[l] += m;
                        sg[l] += m * g;
                        sg2[l] += m * g * g;
                        spg[l] += p[l] * g;
                        sp[l] += p[l];
                    }
                };
                let (pe, ue, he) = (
                    pc.chunks_exact(LANES),
                    uc.chunks_exact(LANES),
                    hc.chunks_exact(LANES),
                );
                let (pr, ur, hr) = (pe.remainder(), ue.remainder(), he.remainder());
                for ((p, u), h) in pe.zip(ue).zip(he) {
                    let (p, u, h): (&[f64; LANES], &[f64; LANES], &[f64; LANES]) = (
                        p.try_into().unwrap(),
                        u.try_into().unwrap(),
                        h.try_into().unwrap(),
                    );
                    step(p, u, h);
                }
                step(pr, ur, hr);
                let sum = |a: [f64; LANES]| a.iter().sum::<f64>();
                *part = [
                    sum(n),
                    sum(sg),
                    sum(sg2),
                    sum(spg),
                    sum(sp),
                    min.iter().fold(f64::INFINITY, |a, &b| a.min(b)),
                ];
            });
        let mut acc = [0.0, 0.0, 0.0, 0.0, 0.0, f64::INFINITY];
        for part in &self.partials {
            for k in 0..5 {
                acc[k] += part[k];
            }
            acc[5] = acc[5].min(part[5]);
        }
        acc
    }

    /// `t ← (g − ḡ_S) + β t` on S, 0 elsewhere; returns `Σ_S (g − ḡ_S) t`.
    fn pass_direction(&mut self, level: f64, beta: f64) -> f64 {
        let h = self.heights;
        self.direction
            .par_chunks_mut(CHUNK)
            .zip(self.pressure.par_chunks(CHUNK))
            .zip(self.deflection.par_chunks(CHUNK))
            .zip(h.par_chunks(CHUNK))
            .zip(self.partials.par_iter_mut())
            .for_each(|((((tc, pc), uc), hc), part)| {
                let mut num = [0.0f64; LANES];
                let mut step = |t: &mut [f64], p: &[f64], u: &[f64], h: &[f64]| {
                    for l in 0..t.len() {
                        let m = if p[l] > 0.0 { 1.0 } else { 0.0 };
                        let gc = u[l] - h[l] - level;
                        let tn = m * (gc + beta * t[l]);
                        t[l] = tn;
                        num[l] += gc * tn;
                    }
                };
                let mut te = tc.chunks_exact_mut(LANES);
                let (pe, ue, he) = (
                    pc.chunks_exact(LANES),
                    uc.chunks_exact(LANES),
                    hc.chunks_exact(LANES),
                );
                let (pr, ur, hr) = (pe.remainder(), ue.remainder(), he.remainder());
                for (((t, p), u), h) in (&mut te).zip(pe).zip(ue).zip(he) {
                    let t: &mut [f64; LANES] = t.try_into().unwrap();
                    let (p, u, h): (&[f64; LANES], &[f64; LANES], &[f64; LANES]) = (
                        p.try_into().unwrap(),
                        u.try_into().unwrap(),
                        h.try_into().unwrap(),
                    );
                    step(t, p, u, h);
                }
                step(te.into_remainder(), pr, ur, hr);
                part[0] = num.iter().sum();
            });
        self.partials.iter().map(|p| p[0]).sum()
    }

    /// Over S: `Σ r, Σ r t, Σ t` with `r = K t` in `work` (t is 0 off S).
    fn pass_curvature(&mut self) -> [f64; 6] {
        self.work
            .par_chunks(CHUNK)
            .zip(self.direction.par_chunks(CHUNK))
            .zip(self.pressure.par_chunks(CHUNK))
            .zip(self.partials.par_iter_mut())
            .for_each(|(((rc, tc), pc), part)| {
                let (mut sr, mut srt, mut st) = ([0.0f64; LANES], [0.0; LANES], [0.0; LANES]);
                let mut step = |r: &[f64], t: &[f64], p: &[f64]| {
                    for l in 0..r.len() {
                        let m = if p[l] > 0.0 { 1.0 } else { 0.0 };
                        sr[l] += m * r[l];
                        srt[l] += r[l] * t[l];
                        st[l] += t[l];
                    }
                };
                let (re, te, pe) = (
                    rc.chunks_exact(LANES),
                    tc.chunks_exact(LANES),
                    pc.chunks_exact(LANES),
                );
                let (rr, tr, pr) = (re.remainder(), te.remainder(), pe.remainder());
                for ((r, t), p) in re.zip(te).zip(pe) {
                    let (r, t, p): (&[f64; LANES], &[f64; LANES], &[f64; LANES]) = (
                        r.try_into().unwrap(),
                        t.try_into().unwrap(),
                        p.try_into().unwrap(),
                    );
                    step(r, t, p);
                }
                step(rr, tr, pr);
                let sum = |a: [f64; LANES]| a.iter().sum::<f64>();
                *part = [sum(sr), sum(srt), sum(st), 0.0, 0.0, 0.0];
            });
        let mut acc = [0.0; 6];
        for part in &self.partials {
            for k in 0..3 {
                acc[k] += part[k];
            }
        }
        acc
    }

    /// `p ← max(p − τ t, 0)` on S; nodes with `p = 0` and `g − level < 0` are re-admitted
    /// with `p = −τ (g − level)`. Returns `[Σp, #clipped, #re-admitted, …]`.
    fn pass_update(&mut self, tau: f64, level: f64) -> [f64; 6] {
        let h = self.heights;
        self.pressure
            .par_chunks_mut(CHUNK)
            .zip(self.direction.par_chunks(CHUNK))
            .zip(self.deflection.par_chunks(CHUNK))
            .zip(h.par_chunks(CHUNK))
            .zip(self.partials.par_iter_mut())
            .for_each(|((((pc, tc), uc), hc), part)| {
                let (mut total, mut clipped, mut readmitted) =
                    ([0.0f64; LANES], [0.0; LANES], [0.0; LANES]);
                let mut step = |p: &mut [f64], t: &[f64], u: &[f64], h: &[f64]| {
                    for l in 0..p.len() {
                        let old = p[l];
                        let stepped = old - tau * t[l]; // t = 0 off S, so p stays 0 there
                        let kept = if stepped > 0.0 { stepped } else { 0.0 };
                        let gc = u[l] - h[l] - level;
                        let readmit = kept == 0.0 && gc < 0.0;
                        let new = if readmit { -tau * gc } else { kept };
                        p[l] = new;
                        total[l] += new;
                        clipped[l] += if old > 0.0 && stepped <= 0.0 {
                            1.0
                        } else {
                            0.0
                        };
                        readmitted[l] += if readmit { 1.0 } else { 0.0 };
                    }
                };
                let mut pe = pc.chunks_exact_mut(LANES);
                let (te, ue, he) = (
                    tc.chunks_exact(LANES),
                    uc.chunks_exact(LANES),
                    hc.chunks_exact(LANES),
                );
                let (tr, ur, hr) = (te.remainder(), ue.remainder(), he.remainder());
                for (((p, t), u), h) in (&mut pe).zip(te).zip(ue).zip(he) {
                    let p: &mut [f64; LANES] = p.try_into().unwrap();
                    let (t, u, h): (&[f64; LANES], &[f64; LANES], &[f64; LANES]) = (
                        t.try_into().unwrap(),
                        u.try_into().unwrap(),
                        h.try_into().unwrap(),
                    );
                    step(p, t, u, h);
                }
                step(pe.into_remainder(), tr, ur, hr);
                let sum = |a: [f64; LANES]| a.iter().sum::<f64>();
                *part = [sum(total), sum(clipped), sum(readmitted), 0.0, 0.0, 0.0];
            });
        let mut acc = [0.0; 6];
        for part in &self.partials {
            for k in 0..3 {
                acc[k] += part[k];
            }
        }
        acc
    }

    /// `work ← (u − h) − min(u − h)` (the gap; `u` must be exact).
    fn finish_gap(&mut self) {
        let h = self.heights;
        let min = self
            .deflection
            .par_iter()
            .zip(h.par_iter())
            .map(|(u, h)| u - h)
            .reduce(|| f64::INFINITY, f64::min);
        self.work
            .par_iter_mut()
            .zip(self.deflection.par_iter())
            .zip(h.par_iter())
            .for_each(|((g, u), h)| *g = (u - h) - min);
    }
}
