//! The ceiling's part in the solve ([`Complementarity`]): what the solver does differently
//! under `0 ≤ p ≤ p_max`. A bounded field is not positively homogeneous,
//! so the load is never restored by rescaling the pressures: every exact deflection first
//! brings the mean to `p̄` by the offset `p ← P(p + c)` (the nearest admissible field of
//! that mean), and between exact deflections the few nodes a step projects may move the
//! mean slightly, which the next exact deflection (at the latest the one that confirms
//! convergence) corrects. The error is measured on both bounds.

use rayon::prelude::*;

use super::super::complementarity::Complementarity;
use super::super::config::SolverConfig;
use super::super::constraint::Constraint;
use super::super::iteration::Iteration;
use super::super::load::{dispatch_offset_sums, RESYNC};
use super::super::operator::Operator;
use super::super::passes::{UpdateTotals, MAX_SPARSE};
use super::super::report::SolveReport;
use super::super::rows::{GradientStats, LANES};
use super::super::state::Solver;
use super::rules::Ceiling;

/// Newton steps allowed to find the load's offset (each a pass over `p`); bisection
/// safeguards them, so 64 halve the bracket below the rounding of any pressure.
const OFFSET_STEPS: usize = 64;

/// The load is restored once the offset pressures sum to it within this relative rounding
/// (far below any tolerance on the error, and above the rounding of a sum of 512² pressures,
/// measured at up to 2e-14: a tighter bound bisected to the end of the steps).
const OFFSET_ROUNDING: f64 = 1e-13;

/// After a step, the load is restored to this relative accuracy (the confirmation of
/// convergence restores it to [`OFFSET_ROUNDING`]): each Newton step is a pass over the
/// pressures, and requiring rounding level took about one more per restoration.
const STEP_ROUNDING: f64 = 1e-12;

/// The step of [`Solver::gap_start`], as a fraction of `1 / K_ii` (the pressure that closes
/// a unit gap at a node alone): on a 512² sweep at hardness 0.25 the fractions 0.25, 0.5
/// and 1 took 321, 314 and 320 iterations (docs/BENCHMARKS.md).
const GAP_STEP: f64 = 0.5;

impl<O: Operator> Solver<'_, Ceiling, O> {
    /// The complementarity error of a state with gradient statistics `stats` (of
    /// `g = w − shift`), in units of the load times σ_h (docs/CONVENTIONS.md), with
    /// `ℓ = min g` over the unsaturated nodes:
    /// `Σ_{p<p_max} p (g − ℓ) + p_max Σ_{p=p_max} (g − ℓ)⁺`, zero exactly when every node
    /// with `0 < p < p_max` is at the level, none at 0 is below it and none on the ceiling
    /// above it. The second sum takes a pass over the saturated nodes; it is made only when
    /// one of them is above the level and the first sum alone is within `tolerance` (else
    /// the error is above the tolerance whatever the second sum, and its largest term
    /// stands for it: the error returned is then a lower bound, never below the tolerance).
    fn bounded_error(&mut self, stats: &GradientStats, shift: f64, tolerance: f64) -> f64 {
        let max = self.constraint.max();
        let level = if stats.min_g.is_finite() {
            stats.min_g
        } else {
            stats.max_g_saturated
        };
        let unsaturated = stats.sum_pg - level * (stats.sum_p - max * stats.saturated_nodes);
        let scale = stats.sum_p * self.height_std;
        let violation = if stats.max_g_saturated <= level {
            0.0
        } else if unsaturated <= tolerance * scale {
            max * self.saturated_violation(shift + level)
        } else {
            max * (stats.max_g_saturated - level)
        };
        (unsaturated + violation) / scale
    }

    /// `Σ (w − level)⁺` over the saturated nodes, reduced over the fixed blocks.
    fn saturated_violation(&mut self, level: f64) -> f64 {
        let c = self.constraint;
        self.fields
            .pressure
            .par_chunks(self.blocks.chunk)
            .zip(self.fields.separation.par_chunks(self.blocks.chunk))
            .zip(self.blocks.lane_sums.par_iter_mut())
            .for_each(|((pc, wc), part)| {
                part[0] = pc
                    .iter()
                    .zip(wc)
                    .map(|(&p, &w)| {
                        if c.saturated(p) {
                            (w - level).max(0.0)
                        } else {
                            0.0
                        }
                    })
                    .sum();
            });
        self.blocks.lane_sums.iter().map(|p| p[0]).sum()
    }

    /// The level of the gradient that the search direction is centred on: its mean over the
    /// active set, or, where the ceiling left no node strictly between the bounds, the
    /// lowest unsaturated `g` (else the highest saturated one).
    fn bounded_level(&self, stats: &GradientStats) -> f64 {
        if stats.contact_nodes == 0.0 {
            if stats.min_g.is_finite() {
                stats.min_g
            } else {
                stats.max_g_saturated
            }
        } else {
            stats.mean_g()
        }
    }

    /// The offset `c` for which the pressures offset by it ([`Constraint::offset`]: only
    /// the active nodes move, within the bounds) sum to `load`, for pressures summing to
    /// `total`, and `false`; where the active nodes cannot take or give up that much, the
    /// offset of every node (the nearest admissible field of that mean) and `true`. The sum is piecewise linear and non-decreasing in `c`, with slope the
    /// number of nodes still active; Newton's method, kept inside a shrinking bracket by
    /// bisection, is exact once a step stays on one linear piece. `p` is not changed.
    fn bounded_offset(&mut self, load: f64, total: f64) -> (f64, bool) {
        if (total - load).abs() <= OFFSET_ROUNDING * load {
            return (0.0, false);
        }
        let narrow = self.offset_in(load, total, false);
        // The projection of every node reaches any load from 0 to n p_max.
        narrow.map_or_else(
            || (self.offset_in(load, total, true).unwrap_or(0.0), true),
            |c| (c, false),
        )
    }

    /// [`Self::bounded_offset`] with the nodes `wide` says ([`Constraint::offset`]): every
    /// node, by passes over `p`, or the active ones, gathered first ([`Self::gather_moving`]).
    fn offset_in(&mut self, load: f64, total: f64, wide: bool) -> Option<f64> {
        // Offsets of ±p_max take every moving node to a bound.
        let span = self.constraint.max();
        let within = OFFSET_ROUNDING * load;
        if wide {
            let slope = self.shifted_sum(0.0, true).1;
            return offset_to_load(load, total, slope, span, within, |c| {
                self.shifted_sum(c, true)
            });
        }
        let slope = self.gather_moving();
        offset_to_load(load, total, slope, span, within, |c| self.moving_sum(c))
    }

    /// Gathers, block by block, the pressures that a load offset moves ([`Constraint::offset`]:
    /// those off the bounds, the active ones and any a step left past a bound) into
    /// `self.blocks.moving`, beside the sum of the others. One pass over `p`, after which each
    /// offset's sum ([`Self::moving_sum`]) passes over the moving nodes only (a few percent
    /// to a third of them). Returns how many of them are active (the sum's slope at `c = 0`).
    fn gather_moving(&mut self) -> f64 {
        let constraint = self.constraint;
        let active: usize = self
            .fields
            .pressure
            .par_chunks(self.blocks.chunk)
            .zip(self.blocks.moving.par_iter_mut())
            .map(|(pc, (moving, fixed))| {
                moving.clear();
                let (mut rest, mut active) = ([0.0; 4], 0);
                for (k, &p) in pc.iter().enumerate() {
                    if constraint.moves(p, false) {
                        moving.push(p);
                        active += usize::from(constraint.active(p));
                    } else {
                        rest[k % 4] += p;
                    }
                }
                *fixed = rest.iter().sum();
                active
            })
            .sum();
        active as f64
    }

    /// The sum of the pressures with the moving ones ([`Self::gather_moving`]) offset by
    /// `c`, `P(x + c)`, and how many of those are active (the sum's slope in `c`), reduced
    /// over the fixed blocks.
    fn moving_sum(&mut self, c: f64) -> (f64, f64) {
        let constraint = self.constraint;
        self.blocks
            .moving
            .par_iter()
            .zip(self.blocks.offset_acc.par_iter_mut())
            .for_each(|((moving, fixed), [sums, counts])| {
                *sums = [0.0; LANES];
                *counts = [0.0; LANES];
                dispatch_offset_sums(constraint, c, true, moving, sums, counts);
                sums[0] += fixed;
            });
        self.blocks
            .offset_acc
            .iter()
            .fold((0.0, 0.0), |(s, k), [sums, counts]| {
                (s + sums.iter().sum::<f64>(), k + counts.iter().sum::<f64>())
            })
    }

    /// The exact deflection of the pressures offset to the mean `target` (their sum now
    /// `total`), with the gradient statistics of `g = w − shift`: one convolution. An offset
    /// moves every active pressure, so the next direction restarts (the old one is not
    /// conjugate to the new state: kept, it stalls the plain iteration).
    fn deflection_at_load(
        &mut self,
        target: f64,
        total: f64,
        shift: f64,
        restart: &mut bool,
    ) -> GradientStats {
        let load = target * self.fields.pressure.len() as f64;
        let (offset, wide) = self.bounded_offset(load, total);
        *restart |= offset != 0.0;
        self.offset_deflection(offset, wide, 1.0, shift)
    }

    /// The load restored under a ceiling: nothing to do where no node changed (the
    /// direction is centred, so the step kept the load), a direct correction of `u` for a
    /// few changed nodes (the mean moves by their projection until the next exact
    /// deflection), else the step's offset to the load ([`Self::step_offset`]) and the exact
    /// deflection.
    fn restore_bounded_load(
        &mut self,
        preconditioned: bool,
        totals: &UpdateTotals,
        linear_stats: GradientStats,
        target: f64,
        it: &mut Iteration,
        report: &mut SolveReport,
    ) -> GradientStats {
        let linear = it.linear_steps + 1 < RESYNC;
        let stats = if totals.changed == 0 && linear {
            linear_stats
        } else if totals.changed <= MAX_SPARSE && linear && self.gather_changes() {
            self.sparse_update(1.0, it.shift)
        } else {
            report.convolutions += 1;
            it.linear_steps = 0;
            let load = target * self.fields.pressure.len() as f64;
            return match self.step_offset(load, totals.sum_p, totals.contact_nodes) {
                Some(c) => {
                    // The preconditioned direction is kept across it, as across the elastic
                    // offset (restarting costs 1.2–1.3 times the iterations on a 512² sweep);
                    // the plain one restarts (kept, it stalls).
                    it.restart |= c != 0.0 && !preconditioned;
                    // The nodes off the bounds take the offset as the rows are read.
                    self.offset_deflection(c, false, 1.0, it.shift)
                }
                None => self.deflection_at_load(target, totals.sum_p, it.shift, &mut it.restart),
            };
        };
        it.linear_steps += 1;
        stats
    }

    /// The offset `c` that restores the load after a step, from the sum `total` and the
    /// number `active` of active nodes it left: each node the step projected onto a bound
    /// ([`Solver::changes`], all listed under a ceiling) is offset from where the step left it,
    /// `P(p − Δ + c)`, each active node from its pressure, `P(p + c)`, and the others (at 0 or
    /// on the ceiling, and not moved) stay. This is the projection of the step onto the load,
    /// restricted to the nodes the step moved: a node the step took far past a bound stays
    /// there, one it took just past comes back first. With `Some(c)`, each projected node is
    /// left where the step left it, off the bounds, so that the offset of the nodes off the
    /// bounds ([`Constraint::offset`], fused with the next deflection) applies `c`; with
    /// `None` (the load out of reach), `p` is as it was.
    fn step_offset(&mut self, load: f64, total: f64, active: f64) -> Option<f64> {
        if !self.changes_listed() {
            return None;
        }
        // Every moved node reaches a bound within p_max plus its distance past one.
        let past = self
            .blocks
            .changes
            .iter()
            .flatten()
            .fold(0.0f64, |m, &(_, d)| m.max(d.abs()));
        let span = self.constraint.max() + past;
        let within = STEP_ROUNDING * load;
        self.unproject_step(true);
        self.gather_moving();
        let offset = offset_to_load(load, total, active, span, within, |c| self.moving_sum(c));
        if offset.is_none() {
            self.unproject_step(false);
        }
        offset
    }

    /// With `unproject`, moves each listed node that the step left on a bound back to where
    /// the step took it, `p − Δ` (keeping its pressure in the list, whose `Δ` is spent: the
    /// next update pass clears it; NaN marks the nodes left as they were); without, puts
    /// those pressures back. A pass over the lists only.
    fn unproject_step(&mut self, unproject: bool) {
        let (constraint, chunk) = (self.constraint, self.blocks.chunk);
        self.fields
            .pressure
            .par_chunks_mut(chunk)
            .zip(self.blocks.changes.par_iter_mut())
            .enumerate()
            .for_each(|(b, (pc, list))| {
                let first = b * chunk;
                for (i, kept) in list.iter_mut() {
                    let p = &mut pc[*i - first];
                    if !unproject {
                        if !kept.is_nan() {
                            *p = *kept;
                        }
                    } else if constraint.active(*p) {
                        *kept = f64::NAN;
                    } else {
                        (*p, *kept) = (*p - *kept, *p);
                    }
                }
            });
    }

    /// Whether the last solution's contact set cannot carry the load `target` even at the
    /// ceiling (`target · n > p_max · #{p > 0}`): then no scaling of it, nor offset of its
    /// active nodes, reaches the load, and the start takes a projected gradient step
    /// instead ([`Self::gap_start`]).
    fn beyond_contact_set(&self, target: f64) -> bool {
        self.warm.has_solution
            && self.warm.separation_exact
            && target * self.fields.pressure.len() as f64
                > self.constraint.max() * self.warm.solved_contact as f64
    }

    /// The start under a ceiling: where the last solution's contact set can carry
    /// the load, that solution (extrapolated by [`Solver::warm_start`]) scaled to the load
    /// and projected, else the uniform pressure, offset to the load; where it cannot, the
    /// [`Self::gap_start`]. Then the exact deflection.
    fn bounded_start(&mut self, target: f64, report: &mut SolveReport) -> GradientStats {
        report.convolutions += 1;
        if self.beyond_contact_set(target) {
            return self.gap_start(target);
        }
        let len = self.fields.pressure.len();
        let previous_total: f64 = self.chunked_sum(|p| p);
        let c = self.constraint;
        if self.warm.has_solution && previous_total > 0.0 {
            let scale = target * len as f64 / previous_total;
            self.fields
                .pressure
                .par_iter_mut()
                .for_each(|p| *p = c.project(*p * scale));
        } else {
            self.fields.pressure.fill(target);
        }
        let total = self.chunked_sum(|p| p);
        self.deflection_at_load(target, total, 0.0, &mut false)
    }

    /// Records `min w` over the unsaturated nodes, the rigid-body level of the gap `w − min w`
    /// ([`Solver::gap`]; `w = u − h` must be exact), and the size of the contact set, in one
    /// pass; with every node saturated (the mean at the ceiling) the highest `w`, so that no
    /// node has a gap.
    fn finish_bounded_gap(&mut self) {
        let c = self.constraint;
        let (unsaturated, contact) = self
            .fields
            .pressure
            .par_iter()
            .zip(self.fields.separation.par_iter())
            .map(|(&p, &w)| {
                let level = if c.saturated(p) { f64::INFINITY } else { w };
                (level, usize::from(p > 0.0))
            })
            .reduce(
                || (f64::INFINITY, 0),
                |(w1, k1), (w2, k2)| (w1.min(w2), k1 + k2),
            );
        self.warm.solved_contact = contact;
        self.fields.gap_level = if unsaturated.is_finite() {
            unsaturated
        } else {
            self.fields
                .separation
                .par_iter()
                .copied()
                .reduce(|| f64::NEG_INFINITY, f64::max)
        };
    }

    /// The start of a load beyond the last solution's contact set (a load mostly carried
    /// on the ceiling grows by new contact, not by higher pressures): one projected
    /// gradient step from that solution, `P(p − τ (w − ℓ) + c)` with `ℓ` its level, the
    /// step `τ` [`GAP_STEP`] over the self-influence, and the offset `c` of every node that
    /// brings the mean to `target` (the nodes closest to contact enter first, the saturated
    /// ones stay). `w` must be exact for `p`.
    fn gap_start(&mut self, target: f64) -> GradientStats {
        let c = self.constraint;
        let (tau, level) = (GAP_STEP / self.op.self_influence(), self.fields.gap_level);
        self.fields
            .pressure
            .par_iter_mut()
            .zip(self.fields.separation.par_iter())
            .for_each(|(p, &w)| *p -= tau * (w - level));
        // The projected total, and the furthest step past a bound: offsets of ±(p_max + it)
        // take every node to a bound. Block by block, so that the sum's bits do not depend
        // on the thread count.
        let (total, past) = self
            .fields
            .pressure
            .par_chunks(self.blocks.chunk)
            .map(|pc| {
                pc.iter().fold((0.0, 0.0f64), |(sum, past), &x| {
                    let kept = c.project(x);
                    (sum + kept, past.max((x - kept).abs()))
                })
            })
            .collect::<Vec<_>>()
            .into_iter()
            .fold((0.0, 0.0f64), |(sum, past), (s, p)| (sum + s, past.max(p)));
        let load = target * self.fields.pressure.len() as f64;
        let slope = self.shifted_sum(0.0, true).1;
        let span = c.max() + past;
        let within = OFFSET_ROUNDING * load;
        match offset_to_load(load, total, slope, span, within, |o| {
            self.shifted_sum(o, true)
        }) {
            Some(offset) => self.offset_deflection(offset, true, 1.0, 0.0),
            // Every load from 0 to n p_max is within that reach; the uniform pressure
            // stands in should rounding say otherwise.
            None => {
                self.fields.pressure.fill(target);
                self.exact_deflection(1.0, 0.0)
            }
        }
    }
}

/// The ceiling's part in the solve: the error on both bounds, the level of a contact set
/// with no active node, the start by scaling or by a gradient step, the load restored by
/// offset, the extended preconditioner set aside where it stagnates, and the gap levelled on
/// the unsaturated nodes.
impl Complementarity for Ceiling {
    /// Every node the step projects (the restoration reads where the step left each).
    fn listed_changes(chunk: usize) -> usize {
        chunk
    }

    fn error<O: Operator>(
        s: &mut Solver<'_, Self, O>,
        stats: &GradientStats,
        shift: f64,
        tolerance: f64,
    ) -> f64 {
        s.bounded_error(stats, shift, tolerance)
    }

    fn level<O: Operator>(s: &Solver<'_, Self, O>, stats: &GradientStats) -> f64 {
        s.bounded_level(stats)
    }

    fn start<O: Operator>(
        s: &mut Solver<'_, Self, O>,
        target: f64,
        report: &mut SolveReport,
    ) -> GradientStats {
        s.bounded_start(target, report)
    }

    fn beyond_contact_set<O: Operator>(s: &Solver<'_, Self, O>, target: f64) -> bool {
        s.beyond_contact_set(target)
    }

    /// At the exact load by the offset (a rescaling would leave the bounds).
    fn confirm<O: Operator>(
        s: &mut Solver<'_, Self, O>,
        target: f64,
        stats: &GradientStats,
        it: &mut Iteration,
    ) -> GradientStats {
        s.deflection_at_load(target, stats.sum_p, it.shift, &mut it.restart)
    }

    fn restore_load<O: Operator>(
        s: &mut Solver<'_, Self, O>,
        cfg: &SolverConfig,
        totals: &UpdateTotals,
        linear_stats: GradientStats,
        target: f64,
        it: &mut Iteration,
        report: &mut SolveReport,
    ) -> GradientStats {
        s.restore_bounded_load(cfg.preconditioned, totals, linear_stats, target, it, report)
    }

    fn fall_back<O: Operator>(
        s: &mut Solver<'_, Self, O>,
        it: &mut Iteration,
        report: &SolveReport,
    ) {
        s.set_extension_aside(it, report);
    }

    fn finish_gap<O: Operator>(s: &mut Solver<'_, Self, O>) {
        s.finish_bounded_gap();
    }
}

/// The root `c` of `sum(c) = load` for a piecewise linear, non-decreasing `sum` (`eval(c)`
/// gives it and its slope, one pass over the pressures) with `sum(0) = total` of slope
/// `slope`, within `span` of 0, to `within`: Newton's method, kept inside a shrinking bracket
/// by bisection, exact once a step stays on one linear piece. `None` if the load lies out of
/// reach (`sum(±span)` on the same side of it as `total`).
fn offset_to_load(
    load: f64,
    total: f64,
    slope: f64,
    span: f64,
    within: f64,
    mut eval: impl FnMut(f64) -> (f64, f64),
) -> Option<f64> {
    let close = |sum: f64| (sum - load).abs() <= within;
    let below = total > load;
    let (mut low, mut high) = if below { (-span, 0.0) } else { (0.0, span) };
    // Whether the load lies within reach (`sum(±span)` on the other side of it), found by
    // one pass the first time Newton's step leaves the bracket: a load out of reach sends
    // every step there, and bisecting towards it would take all the steps.
    let mut reach: Option<bool> = None;
    let mut reachable = |eval: &mut dyn FnMut(f64) -> (f64, f64)| {
        *reach.get_or_insert_with(|| {
            let end = eval(if below { -span } else { span }).0;
            if below {
                end <= load
            } else {
                end >= load
            }
        })
    };
    let (mut c, mut sum, mut slope) = (0.0f64, total, slope);
    for _ in 0..OFFSET_STEPS {
        if close(sum) {
            return Some(c);
        }
        let newton = c - (sum - load) / slope;
        let next = if slope > 0.0 && newton > low && newton < high {
            newton
        } else if reachable(&mut eval) {
            0.5 * (low + high)
        } else {
            return None;
        };
        // The bracket has shrunk below the rounding of the pressures: the sum cannot come
        // closer than its own rounding.
        if next == c || high - low <= f64::EPSILON * span {
            break;
        }
        (c, (sum, slope)) = (next, eval(next));
        if sum > load {
            high = c;
        } else {
            low = c;
        }
    }
    // Not within `within` after the steps: the offset stands if the load lies within reach.
    reachable(&mut eval).then_some(c)
}
