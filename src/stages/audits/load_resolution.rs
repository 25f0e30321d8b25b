//! The load-resolution audit: a sweep with fewer loads (the one a figure draws) against a
//! finer sweep of the same realizations, curve by curve (K, 𝒦, wear rate at each A* of
//! Figs. 4b and 5), interpolated linearly in ln W/W0 and judged against the finer sweep's
//! 95 % band.

use polars::prelude::*;
use serde_json::{json, Value};

use crate::store::table::f64_column;

/// Thresholds A*/λ_s² drawn in Figs. 4b and 5.
pub const FIG45_A_STAR: [f64; 5] = [2.0, 8.0, 32.0, 128.0, 512.0];

/// The curves of Figs. 4b, 5a and 5b: statistics column, the column of its 95 % band, the
/// name in the manifest and the legend.
pub const FIG45_CURVES: [(&str, &str, &str, &str); 3] = [
    (
        "k_archard_pooled",
        "k_archard_ci95",
        "k_archard",
        "K (Fig. 4b)",
    ),
    (
        "k_upscaled_pooled",
        "k_upscaled_ci95",
        "k_upscaled",
        "up-scaled K (Fig. 5a)",
    ),
    (
        "wear_rate_over_l2_mean",
        "wear_rate_over_l2_ci95",
        "wear_rate_over_l2",
        "R / L² (Fig. 5b)",
    ),
];
/// Load-resolution rule of Figs. 4b and 5: between two loads of the chosen sweep, its curve
/// interpolated linearly in ln W/W0 lies within this many 95 % half-widths (of the
/// realization mean) of the finer sweep's value, except where the interval brackets a curve's
/// departure from zero (located only to within one load step). The finer sweep's own
/// neighbours interpolated at each load are recorded beside it (how far the curve jumps
/// between neighbouring loads), not used by the rule.
pub const LOAD_RESOLUTION_TOLERANCE: f64 = 1.0;

/// One load of the finer sweep, for one curve and threshold.
#[derive(Debug, Clone, PartialEq)]
struct LoadResolutionRow {
    /// Index in `FIG45_CURVES`.
    curve: usize,
    a_star_over_ls2: f64,
    w_over_w0: f64,
    /// The finer sweep's value and its 95 % half-width.
    value: f64,
    ci95: f64,
    /// The chosen sweep's curve at this load.
    interpolated: f64,
    /// The chosen sweep's interval around this load has zero at one end only.
    at_transition: bool,
    /// The finer sweep's own neighbours (the loads before and after) interpolated at this
    /// load; NaN at its first and last load and where they bracket a departure from zero.
    neighbours: f64,
}

/// |estimate − value| in units of the 95 % half-width `ci95` (0 when they agree exactly,
/// infinite for a difference where the band is empty, NaN without a band or estimate).
fn error_over_band(estimate: f64, value: f64, ci95: f64) -> f64 {
    let error = (estimate - value).abs();
    if error == 0.0 {
        0.0
    } else {
        error / ci95
    }
}

impl LoadResolutionRow {
    fn error_over_ci95(&self) -> f64 {
        error_over_band(self.interpolated, self.value, self.ci95)
    }

    fn neighbour_error_over_ci95(&self) -> f64 {
        error_over_band(self.neighbours, self.value, self.ci95)
    }

    /// The rule at this row (rows at a transition are not judged; NaN fails).
    fn within_rule(&self) -> bool {
        self.error_over_ci95() <= LOAD_RESOLUTION_TOLERANCE
    }
}

/// A curve given at increasing loads `u` (values `z`), interpolated linearly in ln W at `w`:
/// `None` outside `[u_0, u_last]`; otherwise the value and whether the bracketing interval
/// has zero at exactly one end. A load equal to a node (to 1e-12) takes the node's value.
fn interpolate_in_log_load(u: &[f64], z: &[f64], w: f64) -> Option<(f64, bool)> {
    let (first, last) = (*u.first()?, *u.last()?);
    if w < first * (1.0 - 1e-12) || w > last * (1.0 + 1e-12) {
        return None;
    }
    if let Some(j) = u.iter().position(|&x| ((x - w) / w).abs() <= 1e-12) {
        return Some((z[j], false));
    }
    let b = u.partition_point(|&x| x < w);
    let a = b - 1;
    let t = (w / u[a]).ln() / (u[b] / u[a]).ln();
    Some((z[a] + t * (z[b] - z[a]), (z[a] == 0.0) != (z[b] == 0.0)))
}

/// One curve of a wear table: `(W/W0, value, 95 % half-width)` at threshold `a_star`, by load.
fn wear_curve(
    df: &DataFrame,
    column: &str,
    band: &str,
    a_star: f64,
) -> anyhow::Result<Vec<(f64, f64, f64)>> {
    let a = f64_column(df, "a_star_over_ls2")?;
    let w = f64_column(df, "w_over_w0")?;
    let v = f64_column(df, column)?;
    let c = f64_column(df, band)?;
    let mut out: Vec<(f64, f64, f64)> = (0..a.len())
        .filter(|&i| a[i] == a_star)
        .map(|i| (w[i], v[i], c[i]))
        .collect();
    out.sort_by(|x, y| x.0.total_cmp(&y.0));
    Ok(out)
}

/// Every curve of Figs. 4b and 5 of the `chosen` sweep at the loads of the `fine` sweep
/// within its range (both wear tables of the statistics stage).
fn load_resolution_rows(
    fine: &DataFrame,
    chosen: &DataFrame,
) -> anyhow::Result<Vec<LoadResolutionRow>> {
    let mut rows = Vec::new();
    for (curve, &(column, band, _, _)) in FIG45_CURVES.iter().enumerate() {
        for &a_star in &FIG45_A_STAR {
            let coarse = wear_curve(chosen, column, band, a_star)?;
            let u: Vec<f64> = coarse.iter().map(|p| p.0).collect();
            let z: Vec<f64> = coarse.iter().map(|p| p.1).collect();
            let own = wear_curve(fine, column, band, a_star)?;
            for (i, &(w, value, ci95)) in own.iter().enumerate() {
                let neighbours = match (i.checked_sub(1), own.get(i + 1)) {
                    (Some(before), Some(after)) => {
                        let (before, after) = (own[before], *after);
                        interpolate_in_log_load(&[before.0, after.0], &[before.1, after.1], w)
                            .filter(|&(_, transition)| !transition)
                            .map_or(f64::NAN, |(v, _)| v)
                    }
                    _ => f64::NAN,
                };
                if let Some((interpolated, at_transition)) = interpolate_in_log_load(&u, &z, w) {
                    rows.push(LoadResolutionRow {
                        curve,
                        a_star_over_ls2: a_star,
                        w_over_w0: w,
                        value,
                        ci95,
                        interpolated,
                        at_transition,
                        neighbours,
                    });
                }
            }
        }
    }
    Ok(rows)
}

/// Distinct loads of a wear table, increasing.
fn distinct_loads(df: &DataFrame) -> anyhow::Result<Vec<f64>> {
    let mut w = f64_column(df, "w_over_w0")?;
    w.sort_by(f64::total_cmp);
    w.dedup();
    Ok(w)
}

/// Load resolution of Figs. 4b and 5: the table of every judged point, and the rule's result.
pub(super) fn load_resolution(
    fine: &DataFrame,
    chosen: &DataFrame,
) -> anyhow::Result<(DataFrame, Value)> {
    let rows = load_resolution_rows(fine, chosen)?;
    anyhow::ensure!(
        !rows.is_empty(),
        "fig45_load_resolution: the two sweeps share no load range"
    );
    let fine_loads = distinct_loads(fine)?;
    let chosen_loads = distinct_loads(chosen)?;
    let largest_step = chosen_loads
        .windows(2)
        .map(|p| p[1] / p[0])
        .fold(1.0f64, f64::max);
    let judged = |r: &&LoadResolutionRow| !r.at_transition;
    let mut worst = serde_json::Map::new();
    for (curve, &(_, _, name, _)) in FIG45_CURVES.iter().enumerate() {
        // NaN (no band) and infinity (a difference where the band is empty) both count.
        let e = rows
            .iter()
            .filter(judged)
            .filter(|r| r.curve == curve)
            .map(|r| r.error_over_ci95())
            .fold(0.0f64, |m, x| {
                if x.is_nan() || m.is_nan() {
                    f64::NAN
                } else {
                    m.max(x)
                }
            });
        worst.insert(name.to_string(), json!(e));
    }
    let met = rows.iter().filter(judged).all(|r| r.within_rule());
    let transitions = rows.iter().filter(|r| r.at_transition).count();
    // The judged rows that miss the rule, with the finer sweep's own neighbour error there.
    let beyond_band: Vec<Value> = rows
        .iter()
        .filter(judged)
        .filter(|r| !r.within_rule())
        .map(|r| {
            json!({
                "curve": FIG45_CURVES[r.curve].2,
                "a_star_over_ls2": r.a_star_over_ls2,
                "w_over_w0": r.w_over_w0,
                "error_over_ci95": r.error_over_ci95(),
                "neighbour_error_over_ci95": r.neighbour_error_over_ci95(),
            })
        })
        .collect();
    let table = load_resolution_table(&rows)?;
    let result = json!({
        "tolerance_error_over_ci95": LOAD_RESOLUTION_TOLERANCE,
        "fine_loads": fine_loads.len(),
        "chosen_loads": chosen_loads.len(),
        "chosen_largest_load_ratio": largest_step,
        "points": rows.len(),
        "points_at_transition": transitions,
        "points_judged": rows.len() - transitions,
        "points_beyond_band": beyond_band,
        "max_error_over_ci95": worst,
        "rule_met": met,
    });
    Ok((table, result))
}

/// The audit's table: one row per judged point of the finer sweep (curve, threshold, load,
/// value and band, the interpolation and its error in bands, the neighbours' own).
fn load_resolution_table(rows: &[LoadResolutionRow]) -> anyhow::Result<DataFrame> {
    Ok(DataFrame::new(
        rows.len(),
        vec![
            Column::new(
                "curve".into(),
                rows.iter()
                    .map(|r| FIG45_CURVES[r.curve].2)
                    .collect::<Vec<&str>>(),
            ),
            Column::new(
                "a_star_over_ls2".into(),
                rows.iter().map(|r| r.a_star_over_ls2).collect::<Vec<f64>>(),
            ),
            Column::new(
                "w_over_w0".into(),
                rows.iter().map(|r| r.w_over_w0).collect::<Vec<f64>>(),
            ),
            Column::new(
                "value".into(),
                rows.iter().map(|r| r.value).collect::<Vec<f64>>(),
            ),
            Column::new(
                "ci95".into(),
                rows.iter().map(|r| r.ci95).collect::<Vec<f64>>(),
            ),
            Column::new(
                "interpolated".into(),
                rows.iter().map(|r| r.interpolated).collect::<Vec<f64>>(),
            ),
            Column::new(
                "error_over_ci95".into(),
                rows.iter()
                    .map(|r| r.error_over_ci95())
                    .collect::<Vec<f64>>(),
            ),
            Column::new(
                "at_transition".into(),
                rows.iter().map(|r| r.at_transition).collect::<Vec<bool>>(),
            ),
            Column::new(
                "neighbours".into(),
                rows.iter().map(|r| r.neighbours).collect::<Vec<f64>>(),
            ),
            Column::new(
                "neighbour_error_over_ci95".into(),
                rows.iter()
                    .map(|r| r.neighbour_error_over_ci95())
                    .collect::<Vec<f64>>(),
            ),
            Column::new(
                "within_rule".into(),
                rows.iter()
                    .map(|r| !r.at_transition && r.within_rule())
                    .collect::<Vec<bool>>(),
            ),
        ],
    )?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolation_in_log_load_is_exact_for_a_curve_linear_in_ln_w() {
        let u = [0.001, 0.004, 0.01];
        let z: Vec<f64> = u.iter().map(|w: &f64| 3.0 + 2.0 * w.ln()).collect();
        for w in [0.001, 0.0015, 0.003, 0.004, 0.007, 0.01] {
            let (v, t) = interpolate_in_log_load(&u, &z, w).unwrap();
            assert!((v - (3.0 + 2.0 * f64::ln(w))).abs() < 1e-12, "{w}");
            assert!(!t);
        }
        assert_eq!(interpolate_in_log_load(&u, &z, 0.0009), None);
        assert_eq!(interpolate_in_log_load(&u, &z, 0.011), None);
        // Halfway in ln W between a zero and a one: one half, flagged as a transition; the
        // node itself is not.
        let zero_then_one = [0.0, 0.0, 1.0];
        let mid = (0.004f64 * 0.01).sqrt();
        let (v, t) = interpolate_in_log_load(&u, &zero_then_one, mid).unwrap();
        assert!((v - 0.5).abs() < 1e-12 && t);
        assert_eq!(
            interpolate_in_log_load(&u, &zero_then_one, 0.004),
            Some((0.0, false))
        );
        assert!(
            !interpolate_in_log_load(&u, &zero_then_one, 0.002)
                .unwrap()
                .1
        );
    }

    /// A wear table with every column the load-resolution check reads: `value(w, a*)` and a
    /// constant band `ci95` for each curve.
    fn wear_table(loads: &[f64], value: &dyn Fn(f64, f64) -> f64, ci95: f64) -> DataFrame {
        let mut a = Vec::new();
        let mut w = Vec::new();
        for &l in loads {
            for t in FIG45_A_STAR {
                a.push(t);
                w.push(l);
            }
        }
        let v: Vec<f64> = w.iter().zip(&a).map(|(&w, &a)| value(w, a)).collect();
        let mut columns = vec![
            Column::new("a_star_over_ls2".into(), a.clone()),
            Column::new("w_over_w0".into(), w.clone()),
        ];
        for (column, band, _, _) in FIG45_CURVES {
            columns.push(Column::new(column.into(), v.clone()));
            columns.push(Column::new(band.into(), vec![ci95; v.len()]));
        }
        DataFrame::new(v.len(), columns).unwrap()
    }

    /// The rule on synthetic sweeps: a curve linear in ln W is resolved by any subset of its
    /// loads; a curve with curvature gives the analytic interpolation error, judged against
    /// the band; a departure from zero between two chosen loads is flagged, not judged.
    #[test]
    fn load_resolution_rule_measures_the_interpolation_error_against_the_band() {
        let fine: Vec<f64> = (0..9).map(|i| 0.001 * 2f64.powi(i)).collect();
        let chosen: Vec<f64> = fine.iter().step_by(2).copied().collect();
        let result = |v: &dyn Fn(f64, f64) -> f64, ci95: f64| {
            load_resolution(&wear_table(&fine, v, ci95), &wear_table(&chosen, v, ci95))
                .unwrap()
                .1
        };
        let linear = result(&|w, a| 1.0 + a * w.ln(), 1e-3);
        assert_eq!(linear["rule_met"], json!(true));
        assert_eq!(linear["points"], json!(3 * 5 * 9));
        assert_eq!(linear["points_at_transition"], json!(0));
        assert_eq!(linear["chosen_largest_load_ratio"], json!(4.0));
        // (ln W)²: the midpoint (in ln W) of an interval of width 2h = ln 4 is off by h².
        let h = 2f64.ln();
        let curved = |ci95: f64| result(&|w, _| w.ln().powi(2), ci95);
        let worst = curved(1.0)["max_error_over_ci95"]["k_archard"]
            .as_f64()
            .unwrap();
        assert!((worst - h * h).abs() < 1e-9, "{worst}");
        assert_eq!(curved(h * h * 1.01)["rule_met"], json!(true));
        let failed = curved(h * h * 0.99);
        assert_eq!(failed["rule_met"], json!(false));
        // The four fine loads between chosen ones, for 3 curves and 5 thresholds, each
        // beside a finer-sweep neighbour error of the same h² (the fine neighbours span the
        // same 2h here).
        let beyond = failed["points_beyond_band"].as_array().unwrap();
        assert_eq!(beyond.len(), 4 * 3 * 5);
        for b in beyond {
            let e = b["error_over_ci95"].as_f64().unwrap();
            let n = b["neighbour_error_over_ci95"].as_f64().unwrap();
            assert!((e - 1.0 / 0.99).abs() < 1e-9 && (n - e).abs() < 1e-9, "{b}");
        }
        // Zero up to 0.004, one from 0.008 (a fine load between two chosen ones: 0.016 is
        // chosen, 0.008 is not): flagged, and the rule holds although the band is empty.
        let step = result(&|w, _| if w > 0.005 { 1.0 } else { 0.0 }, 0.0);
        assert_eq!(step["points_at_transition"], json!(3 * 5));
        assert_eq!(step["rule_met"], json!(true));
    }
}
