//! Load sweeps: one surface, a list of loads W/W0 solved in the order given, each step
//! warm-started from the previous solutions (extrapolated linearly in the load from the last
//! two, the first warm step scaled from the last one).

use super::elastic::ElasticOperator;
use super::interface::{ConstraintTask, Interface};
use super::solver::{Complementarity, ContactError, Operator, SolveReport, Solver, SolverConfig};
use crate::grid::{Grid, GridError};

/// One solved load.
#[derive(Debug, Clone, serde::Serialize)]
pub struct LoadResult {
    /// Dimensionless load W/W0, W0 = E*·rms slope·L².
    pub w_over_w0: f64,
    /// Imposed mean pressure p̄ = (W/W0)·E*·rms slope, in the unit of E*.
    pub mean_pressure: f64,
    /// Fraction of nodes with p > 0.
    pub area_fraction: f64,
    /// Number of nodes with p > 0.
    pub n_contact_px: usize,
    /// Under a hardness: the number of nodes at the hardness (saturated); absent when
    /// elastic.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub n_saturated_px: Option<usize>,
    /// Under a hardness: the pressure ceiling `𝓗 = hardness·E*·rms slope`, in the unit of
    /// E* (a saturated node's pressure is exactly it); absent when elastic.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ceiling: Option<f64>,
    pub report: SolveReport,
    /// Wall time of this solve.
    pub seconds: f64,
}

/// A sweep that could not be completed.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    #[error(transparent)]
    Input(#[from] ContactError),
    #[error("load {index} (W/W0 = {}) did not converge: {status:?} after {iterations} iterations, error {error:e} > tolerance {tolerance:e}", Num(*w_over_w0))]
    NotConverged {
        index: usize,
        w_over_w0: f64,
        status: super::solver::Status,
        iterations: usize,
        error: f64,
        tolerance: f64,
    },
    #[error("load {index}: W/W0 = {} is above the hardness {}: no pressure capped at the hardness carries a mean pressure above it (lower the load or raise the hardness)", Num(*w_over_w0), Num(*hardness))]
    AboveHardness {
        index: usize,
        w_over_w0: f64,
        hardness: f64,
    },
    #[error("load {index}: W/W0 = {} must be finite and in [0, {MAX_W_OVER_W0}] (past W/W0 ≈ 10 the contact is complete; larger loads only lose digits to rounding)", Num(*value))]
    BadLoad { index: usize, value: f64 },
    #[error("the surface's rms slope is {rms_slope:e}, so the reference load W0 = E*·rms slope·L² is {}: a flat or constant surface has no W/W0 scale, and heights whose squares under- or overflow (rms slope outside [{MIN_RMS_SLOPE:e}, {MAX_RMS_SLOPE:e}]) cannot be solved accurately; rescale the heights (the pipeline normalises them to unit rms slope)", if *rms_slope == 0.0 { "zero" } else if rms_slope.is_finite() { "out of the solvable range" } else { "not finite" })]
    DegenerateSurface { rms_slope: f64 },
    #[error("{0}")]
    Callback(String),
    #[error(transparent)]
    Grid(#[from] GridError),
}

/// The contact of a square height field (row-major, side `n`, on the unit box) at every
/// load W/W0 of `loads`, with W0 = E*·rms slope·L² from the heights' own rms slope: the
/// operator is built, then [`sweep`] runs. Returns the rms slope and the loads' results.
pub fn sweep_heights(
    heights: &[f64],
    n: usize,
    e_star: f64,
    loads: &[f64],
    cfg: &SolverConfig,
    on_load: impl FnMut(usize, &[f64], &LoadResult) -> Result<(), String>,
) -> Result<(f64, Vec<LoadResult>), SweepError> {
    sweep_heights_under(heights, n, e_star, loads, cfg, Interface::Elastic, on_load)
}

/// [`sweep_heights`] under `interface`: perfectly plastic, the
/// pressure is capped at `𝓗 = hardness·E*·rms slope` (hardness in the units of W/W0, so that
/// `p̄/𝓗 = (W/W0)/hardness`); a load above the hardness is refused before any work.
/// `None` (or `+∞`) is elastic contact, with exactly the elastic solver's bits.
pub fn sweep_heights_under(
    heights: &[f64],
    n: usize,
    e_star: f64,
    loads: &[f64],
    cfg: &SolverConfig,
    interface: Interface,
    mut on_load: impl FnMut(usize, &[f64], &LoadResult) -> Result<(), String>,
) -> Result<(f64, Vec<LoadResult>), SweepError> {
    sweep_heights_solved(heights, n, e_star, loads, cfg, interface, |i, s, r| {
        on_load(i, s.pressure, r)
    })
}

/// A converged load as a sweep hands it on: its fields row-major, in the caller's units.
pub struct Solved<'a> {
    /// Contact pressure, in the unit of E*.
    pub pressure: &'a [f64],
    gap: &'a dyn Fn() -> Vec<f64>,
}

impl<'a> Solved<'a> {
    /// The fields of a load: its pressure, and its gap computed by `gap` when asked.
    pub(super) fn new(pressure: &'a [f64], gap: &'a dyn Fn() -> Vec<f64>) -> Solved<'a> {
        Solved { pressure, gap }
    }

    /// The gap between the rigid surface and the deformed half-space, `(u − h) − min(u − h)`
    /// with the minimum over the nodes below the ceiling, in the unit of the heights: 0 on
    /// the contact, > 0 off it; under a hardness, minus the plastic displacement on the
    /// saturated nodes (≤ 0). Computed when asked (one pass over the nodes).
    pub fn gap(&self) -> Vec<f64> {
        (self.gap)()
    }
}

/// [`sweep_heights_under`] handing on each load as [`Solved`], so that its gap can
/// be read as well as its pressure (the same bits of pressure).
pub fn sweep_heights_solved(
    heights: &[f64],
    n: usize,
    e_star: f64,
    loads: &[f64],
    cfg: &SolverConfig,
    interface: Interface,
    mut on_load: impl FnMut(usize, &Solved, &LoadResult) -> Result<(), String>,
) -> Result<(f64, Vec<LoadResult>), SweepError> {
    check_loads_carried(interface, loads)?;
    if heights.len() != n * n {
        return Err(ContactError::BadLength {
            expected: n * n,
            got: heights.len(),
        }
        .into());
    }
    let grid = Grid::unit(n)?;
    let slope = crate::surface::rms_slope(&grid, heights);
    check_rms_slope(slope)?;
    let largest = loads.iter().fold(0.0f64, |a, &w| a.max(w));
    if !(e_star.is_finite() && e_star > 0.0 && (largest * (e_star * slope)).is_finite()) {
        return Err(ContactError::BadConfig(format!(
            "E* = {e_star:e} with an rms slope of {slope:e}: the mean pressure W/W0·E*·rms slope must be a finite number; choose the units of E* and of the heights so that both are nearer 1"
        ))
        .into());
    }
    // The pressures are written in the user's units: the smallest mean pressure must be a
    // number with all its digits (not subnormal).
    let smallest = loads
        .iter()
        .filter(|&&w| w > 0.0)
        .fold(f64::INFINITY, |a, &w| a.min(w));
    if smallest.is_finite() && smallest * (e_star * slope) < f64::MIN_POSITIVE * 1024.0 {
        return Err(ContactError::BadConfig(format!(
            "W/W0 = {} with E* = {e_star:e} and an rms slope of {slope:e}: the mean pressure W/W0·E*·rms slope = {:e} is below the smallest double with all its digits; choose the units of E* and of the heights so that both are nearer 1",
            Num(smallest),
            smallest * (e_star * slope)
        ))
        .into());
    }
    // Solved in units where the rms slope and E* lie within a factor √2 of 1: dividing by
    // powers of two is exact, so the pipeline's surfaces (unit slope, E* = 1) are solved
    // exactly as given, and any other scale as if it were theirs.
    let (to_h, to_e) = (nearest_power_of_two(slope), nearest_power_of_two(e_star));
    let to_p = to_h * to_e;
    let scaled: std::borrow::Cow<[f64]> = if to_h == 1.0 {
        std::borrow::Cow::Borrowed(heights)
    } else {
        heights.iter().map(|h| h / to_h).collect()
    };
    let op = ElasticOperator::new(grid, e_star / to_e);
    let mut pressure = Vec::new();
    let mut pass_on = |i, solved: &[f64], gap: &dyn Fn() -> Vec<f64>, r: &LoadResult| {
        let r = LoadResult {
            mean_pressure: r.mean_pressure * to_p,
            ceiling: r.ceiling.map(|c| c * to_p),
            ..r.clone()
        };
        if to_p != 1.0 {
            pressure.clear();
            pressure.extend(solved.iter().map(|p| p * to_p));
        }
        let field: &[f64] = if to_p == 1.0 { solved } else { &pressure };
        on_load(i, &Solved::new(field, gap), &r)
    };
    let slope_solved = slope / to_h;
    let task = SweepTask {
        op: &op,
        heights: &scaled,
        slope: slope_solved,
        loads,
        cfg,
        gap_scale: to_h,
        on_load: &mut pass_on,
    };
    // In the solved units: p_max = hardness·E*·slope, E* and slope both scaled.
    let mut results = interface.dispatch(|h| h * op.e_star() * slope_solved, task)??;
    for r in &mut results {
        r.mean_pressure *= to_p;
        r.ceiling = r.ceiling.map(|c| c * to_p);
        r.report.mean_pressure *= to_p;
    }
    Ok((slope, results))
}

/// A load the interface cannot carry (a mean pressure above the hardness), refused before
/// any work.
pub(super) fn check_loads_carried(interface: Interface, loads: &[f64]) -> Result<(), SweepError> {
    match (interface.first_load_above(loads), interface.hardness()) {
        (Some((index, w_over_w0)), Some(hardness)) => Err(SweepError::AboveHardness {
            index,
            w_over_w0,
            hardness,
        }),
        _ => Ok(()),
    }
}

/// One [`sweep`] under the constraint an [`Interface`] dispatches to: each converged load's
/// pressure and, on demand, its gap (times `gap_scale`) handed to `on_load`.
pub(super) struct SweepTask<'a, O, F> {
    pub op: &'a O,
    pub heights: &'a [f64],
    pub slope: f64,
    pub loads: &'a [f64],
    pub cfg: &'a SolverConfig,
    pub gap_scale: f64,
    pub on_load: F,
}

impl<O, F> ConstraintTask for SweepTask<'_, O, F>
where
    O: Operator,
    F: FnMut(usize, &[f64], &dyn Fn() -> Vec<f64>, &LoadResult) -> Result<(), String>,
{
    type Output = Result<Vec<LoadResult>, SweepError>;

    fn run<C: Complementarity>(mut self, constraint: C) -> Self::Output {
        let scale = self.gap_scale;
        sweep(
            self.op,
            self.heights,
            self.slope,
            self.loads,
            self.cfg,
            constraint,
            |i, s, r| {
                // `g · 1` is `g`, bit for bit: one form for every scale.
                let gap = || -> Vec<f64> { s.gap().map(|g| g * scale).collect() };
                (self.on_load)(i, s.pressure(), &gap, r)
            },
        )
    }
}

/// `2^k` with `k` the integer nearest `log2 x` (x finite and > 0).
fn nearest_power_of_two(x: f64) -> f64 {
    2f64.powi(x.log2().round() as i32)
}

/// A number for a message: plain when of moderate size, else in scientific notation (never
/// hundreds of digits of 1e-300).
pub struct Num(pub f64);

impl std::fmt::Display for Num {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let a = self.0.abs();
        if a == 0.0 || !a.is_finite() || (1e-4..1e6).contains(&a) {
            write!(f, "{}", self.0)
        } else {
            write!(f, "{:e}", self.0)
        }
    }
}

/// Largest load W/W0 a sweep accepts. Contact is complete well before W/W0 = 10 on a surface
/// of unit rms slope; far beyond it the pressure's mean swamps its fluctuation, and the
/// complementarity error stalls at rounding level (≈ 1e-8 at W/W0 = 1e8 on a 16² grid).
pub const MAX_W_OVER_W0: f64 = 100.0;

/// Smallest rms slope a sweep accepts: squares of pressures and gaps (∝ slope²) stay far
/// from underflow.
pub const MIN_RMS_SLOPE: f64 = 1e-150;
/// Largest rms slope a sweep accepts: their squares stay far from overflow.
pub const MAX_RMS_SLOPE: f64 = 1e150;

/// A surface whose rms slope gives no usable W0 (flat, constant, under- or overflowing
/// heights) is an input error, never an empty "converged" contact.
pub fn check_rms_slope(rms_slope: f64) -> Result<(), SweepError> {
    if (MIN_RMS_SLOPE..=MAX_RMS_SLOPE).contains(&rms_slope) {
        Ok(())
    } else {
        Err(SweepError::DegenerateSurface { rms_slope })
    }
}

/// Solve every load of `loads` (W/W0) on `heights` with rms slope `rms_slope`. After each
/// converged load, `on_load(index, solver, result)` may store fields; the first load that
/// does not converge stops the sweep with an error (nothing is passed on for it).
#[allow(clippy::too_many_arguments)]
pub fn sweep<C: Complementarity, O: Operator>(
    op: &O,
    heights: &[f64],
    rms_slope: f64,
    loads: &[f64],
    cfg: &SolverConfig,
    constraint: C,
    mut on_load: impl FnMut(usize, &Solver<C, O>, &LoadResult) -> Result<(), String>,
) -> Result<Vec<LoadResult>, SweepError> {
    if let Some((index, &value)) = loads
        .iter()
        .enumerate()
        .find(|(_, w)| !(0.0..=MAX_W_OVER_W0).contains(*w))
    {
        return Err(SweepError::BadLoad { index, value });
    }
    check_rms_slope(rms_slope)?;
    let mut solver = Solver::with_constraint(op, heights, constraint)?;
    let nodes = heights.len() as f64;
    let mut out = Vec::with_capacity(loads.len());
    for (index, &w) in loads.iter().enumerate() {
        let mean_pressure = w * op.e_star() * rms_slope;
        let start = std::time::Instant::now();
        let report = solver.solve(mean_pressure, cfg)?;
        let seconds = start.elapsed().as_secs_f64();
        if !report.converged() {
            return Err(SweepError::NotConverged {
                index,
                w_over_w0: w,
                status: report.status,
                iterations: report.iterations,
                error: report.error,
                tolerance: cfg.tolerance,
            });
        }
        let n_contact_px = solver.contact_count();
        let saturation = solver.saturation();
        let result = LoadResult {
            w_over_w0: w,
            mean_pressure,
            area_fraction: n_contact_px as f64 / nodes,
            n_contact_px,
            n_saturated_px: saturation.map(|(_, count)| count),
            ceiling: saturation.map(|(max, _)| max),
            report,
            seconds,
        };
        on_load(index, &solver, &result).map_err(SweepError::Callback)?;
        out.push(result);
    }
    Ok(out)
}

/// Pack a contact map (`p > 0`) row by row into bits, numpy `packbits` convention: each row
/// of `n` nodes becomes `ceil(n/8)` bytes, most significant bit first, the last byte padded
/// with zeros. `numpy.unpackbits(a, axis=1, count=n).astype(bool)` recovers the map.
pub fn pack_contact(pressure: &[f64], n: usize) -> Vec<u8> {
    let row_bytes = n.div_ceil(8);
    let mut out = vec![0u8; n * row_bytes];
    for (row, chunk) in pressure.chunks_exact(n).enumerate() {
        for (col, &p) in chunk.iter().enumerate() {
            if p > 0.0 {
                out[row * row_bytes + col / 8] |= 0x80 >> (col % 8);
            }
        }
    }
    out
}

/// Inverse of [`pack_contact`]: `n × n` booleans, row-major.
pub fn unpack_contact(bytes: &[u8], n: usize) -> Vec<bool> {
    let row_bytes = n.div_ceil(8);
    (0..n * n)
        .map(|i| {
            let (row, col) = (i / n, i % n);
            bytes[row * row_bytes + col / 8] & (0x80 >> (col % 8)) != 0
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packing_round_trips_and_follows_numpy_bit_order() {
        let n = 10;
        let pressure: Vec<f64> = (0..n * n)
            .map(|i| if (i * 7) % 3 == 0 { 1.0 } else { 0.0 })
            .collect();
        let packed = pack_contact(&pressure, n);
        assert_eq!(packed.len(), n * 2);
        let map = unpack_contact(&packed, n);
        for (p, m) in pressure.iter().zip(&map) {
            assert_eq!(*p > 0.0, *m);
        }
        // Row 0: nodes 0, 3, 6, 9 in contact → 0b1001_0010, 0b0100_0000.
        assert_eq!(&packed[..2], &[0b1001_0010, 0b0100_0000]);
    }
}
