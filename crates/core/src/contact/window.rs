//! Contact of a measured map: rectangular, of any size, not periodic. The map (the window)
//! is placed in the corner of a square of even side `s = max(rows, cols)` (rounded up to
//! even) on the free-boundary half-space ([`PaddedOperator`], zero-padded to `2s`). The
//! nodes of the square outside the window are held far below the lowest height (twice the
//! window's height range), so they never touch: their pressure is zero, as beyond the
//! window, and the solution on the window is the free-boundary one of the window alone.
//! Every load is checked for it after the solve.
//!
//! The solver's error is relative to the standard deviation of the square's heights, which
//! the far nodes inflate; the tolerance is scaled by the ratio of the window's deviation
//! to the square's, so that it means what it means for the window alone.
//!
//! Pixels are `Δx × Δy` as measured: the square is `s` nodes on a side, `s·Δx` by `s·Δy`,
//! and the half-space's kernel is that of a `Δx × Δy` pixel, so that rectangular pixels are
//! solved without resampling.
//!
//! Loads are `W/W0` with `W0 = E*·rms slope·A`, `A = rows·cols·Δx·Δy` the window's area and
//! the rms slope that of the map without wrap-around ([`Topography::rms_slope`]): the
//! window's mean pressure is `p̄ = (W/W0)·E*·rms slope`. Solved in units where the square
//! is the unit box and `E* = 1`; pressures are returned in the unit of the `e_star` given.

use super::interface::Interface;
use super::padded::PaddedOperator;
use super::solver::{ContactError, SolveReport, SolverConfig};
use super::sweep::{
    check_loads_carried, check_rms_slope, LoadResult, Solved, SweepError, SweepTask,
};
use crate::grid::Grid;
use crate::topography::Topography;

/// One solved load of a window.
#[derive(Debug, Clone, serde::Serialize)]
pub struct WindowLoad {
    /// Dimensionless load `W/W0`.
    pub w_over_w0: f64,
    /// Mean pressure on the window `p̄ = (W/W0)·E*·rms slope`, in the unit of E*.
    pub mean_pressure: f64,
    /// Nodes of the window with `p > 0`.
    pub n_contact_px: usize,
    /// `n_contact_px / (rows·cols)`.
    pub area_fraction: f64,
    /// Under a hardness: nodes at the pressure ceiling.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub n_saturated_px: Option<usize>,
    /// The solve's report, its errors rescaled to the window's height deviation (comparable
    /// with the tolerance requested) and its mean pressure the window's.
    pub report: SolveReport,
    pub seconds: f64,
}

/// How a window is solved (for the record of a run).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct WindowLayout {
    /// Side of the square the window is placed in (even).
    pub square_side: usize,
    /// Side of the zero-padded FFT grid (`2·square_side`).
    pub padded_side: usize,
    /// The solver tolerance applied on the square (the requested one times the ratio of
    /// the window's height deviation to the square's).
    pub square_tolerance: f64,
    /// The map's rms slope (dimensionless), which sets `W0`.
    pub rms_slope: f64,
}

/// The contact of `map` (no missing point; pixels `dx × dy`, square or not) at every load `W/W0` of `loads`
/// on the free-boundary half-space of modulus `e_star`, under `interface` (perfectly plastic:
/// capped at `hardness·E*·rms slope`, the hardness in the units of W/W0). After each converged load,
/// `on_load(index, window pressure row-major rows × cols, result)`.
pub fn sweep_window(
    map: &Topography,
    e_star: f64,
    loads: &[f64],
    cfg: &SolverConfig,
    interface: Interface,
    mut on_load: impl FnMut(usize, &[f64], &WindowLoad) -> Result<(), String>,
) -> Result<(WindowLayout, Vec<WindowLoad>), SweepError> {
    sweep_window_solved(map, e_star, loads, cfg, interface, |i, s, r| {
        on_load(i, s.pressure, r)
    })
}

/// [`sweep_window`] handing on each load as [`Solved`]: the window's pressure (unit of
/// E*) and, when asked, its gap (unit of the map's heights), row-major `rows × cols`.
pub fn sweep_window_solved(
    map: &Topography,
    e_star: f64,
    loads: &[f64],
    cfg: &SolverConfig,
    interface: Interface,
    mut on_load: impl FnMut(usize, &Solved, &WindowLoad) -> Result<(), String>,
) -> Result<(WindowLayout, Vec<WindowLoad>), SweepError> {
    let (rows, cols) = (map.rows, map.cols);
    check_map(map, e_star)?;
    check_loads_carried(interface, loads)?;
    let slope = map.rms_slope();
    check_rms_slope(slope)?;
    let largest = loads.iter().copied().fold(0.0, f64::max);
    let (side, mut square, tolerance_scale) = embed(map, largest * slope);
    // The contact problem is linear in the heights: solved on heights scaled by an exact
    // power of two that brings the rms slope near 1 (bit for bit the same contact set,
    // pressures scaled back exactly), so that heights in any unit from 1e-150 to 1e150
    // converge alike. Slopes within [2^-20, 2^20] are solved as they are.
    let exponent = slope.log2().round();
    let unscale = if exponent.abs() > 20.0 {
        2f64.powi(exponent as i32)
    } else {
        1.0
    };
    square.iter_mut().for_each(|h| *h /= unscale);
    let solve_slope = slope / unscale;
    let mut square_cfg = *cfg;
    square_cfg.tolerance = cfg.tolerance * tolerance_scale;
    let layout = WindowLayout {
        square_side: side,
        padded_side: 2 * side,
        square_tolerance: square_cfg.tolerance,
        rms_slope: slope,
    };
    // The square's mean pressure carries the window's load: p̄_square = p̄ · A / A_square.
    let share = (rows * cols) as f64 / (side * side) as f64;
    let square_loads: Vec<f64> = loads.iter().map(|w| w * share).collect();
    let op = PaddedOperator::with_aspect(Grid::unit(side)?, 1.0, map.dy / map.dx);
    let mut window = vec![0.0; rows * cols];
    let to_window_error = cfg.tolerance / square_cfg.tolerance;
    // A square's length (its side is 1) in the map's height unit, solved heights unscaled.
    let to_height = unscale * side as f64 * map.dx;
    let mut pass_on = |i: usize, square: &Solved, r: &LoadResult| {
        let p = square.pressure;
        let mut touching = 0usize;
        for (k, &v) in p.iter().enumerate() {
            let (row, col) = (k / side, k % side);
            if row < rows && col < cols {
                window[row * cols + col] = v * unscale * e_star;
            } else if v > 0.0 {
                touching += 1;
            }
        }
        if touching > 0 {
            return Err(format!(
                "load {i}: {touching} nodes outside the map took pressure; the window's embedding failed"
            ));
        }
        let n_contact_px = window.iter().filter(|&&v| v > 0.0).count();
        let mut report = r.report.clone();
        report.error *= to_window_error;
        report
            .error_history
            .iter_mut()
            .for_each(|e| *e *= to_window_error);
        report.mean_pressure = loads[i] * slope * e_star;
        let result = WindowLoad {
            w_over_w0: loads[i],
            mean_pressure: loads[i] * slope * e_star,
            n_contact_px,
            area_fraction: n_contact_px as f64 / (rows * cols) as f64,
            n_saturated_px: r.n_saturated_px,
            report,
            seconds: r.seconds,
        };
        let gap = || {
            let g = square.gap();
            (0..rows * cols)
                .map(|k| g[(k / cols) * side + k % cols] * to_height)
                .collect()
        };
        on_load(i, &Solved::new(&window, &gap), &result)?;
        Ok(result)
    };
    let mut out = Vec::with_capacity(loads.len());
    let mut each = |i: usize, s: &Solved, r: &LoadResult| {
        out.push(pass_on(i, s, r)?);
        Ok(())
    };
    let task = SweepTask {
        op: &op,
        heights: &square,
        slope: solve_slope,
        loads: &square_loads,
        cfg: &square_cfg,
        gap_scale: 1.0,
        on_load: |i, p: &[f64], gap: &dyn Fn() -> Vec<f64>, r: &LoadResult| {
            each(i, &Solved::new(p, gap), r)
        },
    };
    interface.dispatch(|h| h * solve_slope, task)??;
    Ok((layout, out))
}

/// The map in the corner of the square of even side `s` nodes (lengths divided by `s·Δx`),
/// the rest held far below; and the ratio of the window's height deviation to the
/// square's, which scales the tolerance.
///
/// "Far" is twice the window's height range below its lowest point, or, when the largest
/// mean pressure `pressure` (in units of E*) presses deeper, three times the deflection
/// scale `p̄·ℓ/E*` of the square's longer side ℓ (a uniform pressure on a square of side ℓ
/// sinks its centre by 1.12 p̄ℓ/E*): the rigid approach exceeds the height range by at most
/// the largest deflection, so no far node can touch even in full contact. Below that load
/// the heights are those of a range-only depth, bit for bit.
fn embed(map: &Topography, pressure: f64) -> (usize, Vec<f64>, f64) {
    let (rows, cols) = (map.rows, map.cols);
    let side = rows.max(cols).max(2).next_multiple_of(2);
    let to_unit = 1.0 / (side as f64 * map.dx);
    let (lo, hi) = map
        .heights
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &h| {
            (a.min(h), b.max(h))
        });
    let range = (hi - lo).max(f64::MIN_POSITIVE);
    let sink = 3.0 * pressure * (map.dy / map.dx).max(1.0);
    let far = if 2.0 * range * to_unit >= sink {
        (lo - 2.0 * range) * to_unit
    } else {
        lo * to_unit - sink
    };
    let mut square = vec![far; side * side];
    for r in 0..rows {
        for c in 0..cols {
            square[r * side + c] = map.heights[r * cols + c] * to_unit;
        }
    }
    let deviation = |v: &[f64]| {
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        (v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / v.len() as f64).sqrt()
    };
    let (window_dev, square_dev) = (deviation(&map.heights) * to_unit, deviation(&square));
    let scale = if square_dev > 0.0 && window_dev > 0.0 {
        window_dev / square_dev
    } else {
        1.0
    };
    (side, square, scale)
}

/// Pixel sides positive, every height a number, E* a positive modulus.
fn check_map(map: &Topography, e_star: f64) -> Result<(), SweepError> {
    let cols = map.cols;
    if !(map.dx.is_finite() && map.dx > 0.0 && map.dy.is_finite() && map.dy > 0.0) {
        return Err(ContactError::BadConfig(format!(
            "pixels of {:e} × {:e} m: each side must be finite and > 0",
            map.dx, map.dy
        ))
        .into());
    }
    if let Some(i) = map.heights.iter().position(|h| !h.is_finite()) {
        return Err(ContactError::NonFinite {
            row: i / cols,
            col: i % cols,
            value: map.heights[i],
        }
        .into());
    }
    if !(e_star.is_finite() && e_star > 0.0) {
        return Err(
            ContactError::BadConfig(format!("E* = {e_star}: must be finite and > 0")).into(),
        );
    }
    Ok(())
}
