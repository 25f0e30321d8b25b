//! The realization audit of an ensemble-mean curve figure (Fig. 2e–f): are the realizations
//! enough? Per `r`, the largest deviation of the mean over the first `r` realizations from
//! the mean over all, its 95 % band, and where the mean cluster count peaks.

use polars::prelude::*;
use serde_json::{json, Value};

use crate::store::inputs::Inputs;
use crate::store::table::{f64_column, loads_of, u32_column};

/// Per realization and load, the quantities behind Fig. 2e–f: contact area `A_c/λ_s²`,
/// cluster count `N` and largest cluster `A/λ_s²`, all clusters counted (percolating ones
/// included), as in the statistics stage's `loads.parquet`. Returns `[realization][load]`
/// and the loads.
type StudyCurves = (Vec<Vec<[f64; 3]>>, Vec<(u32, f64)>);

fn study_curves(inputs: &Inputs) -> anyhow::Result<StudyCurves> {
    let loads = loads_of(&inputs.table(0, "clusters", "loads.parquet")?)?;
    let mut out = Vec::new();
    for r in 0..inputs.len() {
        let df = inputs.table(r, "clusters", "clusters.parquet")?;
        let idx = u32_column(&df, "load_index")?;
        let area = f64_column(&df, "area_over_ls2")?;
        let mut per_load = vec![[0.0f64; 3]; loads.len()];
        for (i, a) in area.iter().enumerate() {
            if let Some(l) = loads.iter().position(|l| Some(l.0) == idx[i]) {
                let v = &mut per_load[l];
                v[0] += a;
                v[1] += 1.0;
                v[2] = v[2].max(*a);
            }
        }
        out.push(per_load);
    }
    Ok((out, loads))
}

/// Largest relative deviation (over loads) of the ensemble-mean curves of Fig. 2e–f over the
/// first `r` realizations from the means over all of them, below which `r` realizations
/// count as enough (the same 5 % as the Appendix B rule's KS tolerance).
pub const FIG2_CURVE_TOLERANCE: f64 = 0.05;
/// Largest shift, in load steps, of the load where the mean cluster count peaks (where
/// dN/dA_c of Fig. 2f changes sign) from the full ensemble's.
pub const FIG2_PEAK_TOLERANCE_STEPS: usize = 1;

/// One row of the Fig. 2 realization-convergence table (first `r` realizations).
struct Fig2ConvergenceRow {
    realizations: u32,
    /// Per quantity (A_c, N, largest): largest relative deviation over loads of the mean of
    /// the first `r` realizations from the mean of all.
    deviation: [f64; 3],
    /// Per quantity: largest relative half-width over loads of the 95 % band of the mean of
    /// the first `r` realizations (Student t).
    band: [f64; 3],
    /// Position in the loads and W/W0 where the mean cluster count of the first `r`
    /// realizations peaks.
    peak_index: usize,
    peak_w: f64,
}

/// Realization convergence of Fig. 2e–f: per `r = 2 … R`, the deviations of the first-`r`
/// mean curves from the full ensemble's, their 95 % bands and the load where the mean cluster
/// count peaks. Drawn as `fig2_convergence` (table `.parquet`, chart) with the rule's result
/// in the manifest.
pub(super) fn realizations(
    curve_tolerance: f64,
    peak_tolerance_steps: usize,
    inputs: &Inputs,
) -> anyhow::Result<(Option<DataFrame>, Value)> {
    let (curves, loads) = study_curves(inputs)?;
    let total = curves.len();
    if total < 2 || loads.is_empty() {
        return Ok((
            None,
            json!({ "note": "fewer than 2 realizations: no convergence curve" }),
        ));
    }
    let means = |r: usize| -> Vec<[(f64, f64); 3]> {
        (0..loads.len())
            .map(|l| {
                let band = |q: usize| {
                    let v: Vec<f64> = curves[..r].iter().map(|c| c[l][q]).collect();
                    let (m, _, half) = crate::statistics::mean_band(&v);
                    (m, half)
                };
                [band(0), band(1), band(2)]
            })
            .collect()
    };
    let peak = |m: &[[(f64, f64); 3]]| {
        (0..m.len())
            .max_by(|&a, &b| m[a][1].0.total_cmp(&m[b][1].0).then(b.cmp(&a)))
            .unwrap_or(0)
    };
    let all = means(total);
    let all_peak = peak(&all);
    let mut rows = Vec::new();
    for r in 2..=total {
        let m = means(r);
        let mut deviation = [0.0f64; 3];
        let mut band = [0.0f64; 3];
        for (l, ml) in m.iter().enumerate() {
            for q in 0..3 {
                let reference = all[l][q].0;
                if reference > 0.0 {
                    deviation[q] = deviation[q].max((ml[q].0 - reference).abs() / reference);
                }
                if ml[q].0 > 0.0 && ml[q].1.is_finite() {
                    band[q] = band[q].max(ml[q].1 / ml[q].0);
                }
            }
        }
        let p = peak(&m);
        rows.push(Fig2ConvergenceRow {
            realizations: r as u32,
            deviation,
            band,
            peak_index: p,
            peak_w: loads[p].1,
        });
    }
    let ok = |row: &Fig2ConvergenceRow| {
        row.deviation.iter().all(|&d| d <= curve_tolerance)
            && row.peak_index.abs_diff(all_peak) <= peak_tolerance_steps
    };
    // The smallest r from which every larger count also meets the rule.
    let chosen = (0..rows.len())
        .find(|&i| rows[i..].iter().all(ok))
        .map(|i| rows[i].realizations);
    let names = ["area", "count", "largest"];
    let f64_col = |name: String, f: &dyn Fn(&Fig2ConvergenceRow) -> f64| {
        Column::new(name.into(), rows.iter().map(f).collect::<Vec<f64>>())
    };
    let mut columns = vec![Column::new(
        "realizations".into(),
        rows.iter().map(|x| x.realizations).collect::<Vec<u32>>(),
    )];
    for (q, name) in names.iter().enumerate() {
        columns.push(f64_col(format!("{name}_max_rel_deviation"), &|x| {
            x.deviation[q]
        }));
    }
    for (q, name) in names.iter().enumerate() {
        columns.push(f64_col(format!("{name}_max_rel_ci95"), &|x| x.band[q]));
    }
    columns.push(Column::new(
        "count_peak_load_index".into(),
        rows.iter()
            .map(|x| loads[x.peak_index].0)
            .collect::<Vec<u32>>(),
    ));
    columns.push(f64_col("count_peak_w_over_w0".into(), &|x| x.peak_w));
    let table = DataFrame::new(rows.len(), columns)?;

    let last = rows.last().expect("at least one row");
    let result = json!({
        "tolerance_rel_deviation": curve_tolerance,
        "tolerance_peak_load_steps": peak_tolerance_steps,
        "realizations": total,
        "smallest_converged_realizations": chosen,
        "count_peak_w_over_w0": loads[all_peak].1,
        "max_rel_ci95_at_all_realizations": {
            "area": last.band[0],
            "count": last.band[1],
            "largest": last.band[2],
        },
    });
    Ok((Some(table), result))
}
