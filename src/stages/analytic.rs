//! The analytic stage: the plateau + power-law model (paper Appendix A) fitted to one study
//! on its A* grid (`model.parquet`), the plateau of K that model predicts (`plateau.parquet`)
//! and the small-load area law `A_c/L² = κ W/W₀` (manifest results), or the model curves of
//! paper Fig. 6 (`fig6.parquet`).

use std::path::Path;

use polars::prelude::*;
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

use super::stage::Stage;
use crate::analytic::PlateauPowerLaw;
use crate::powerlaw::Estimator;
use crate::statistics as stats;
use crate::store::inputs::Inputs;
use crate::store::table::{col, f64_column, str_column, u32_column, write};

pub struct Analytic;

/// Paper Fig. 6: the exponent, and the thresholds `A*/A_s` of the model curves, whose cut-off
/// `A_m/A_s` runs over `10^0 … 10^12` in [`FIG6_POINTS`] logarithmic steps.
pub const FIG6_ALPHA: f64 = 1.5;
pub const FIG6_A_STAR_OVER_A_S: [f64; 5] = [0.5, 1.0, 10.0, 100.0, 1000.0];
pub const FIG6_POINTS: usize = 121;

/// The area–load slope as the manifest records it (`results.area_load_slope`), written here
/// and read back by Fig. 2e and the report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AreaLoadSlopeRecord {
    pub kappa: f64,
    /// None below 5 realizations (the means have no interval).
    pub kappa_ci95_correlated: Option<f64>,
    pub kappa_at_lowest_load: f64,
    pub kappa_at_highest_load: f64,
    pub w_over_w0_range: [f64; 2],
    pub loads: usize,
}

impl AreaLoadSlopeRecord {
    fn new(s: &stats::AreaLoadSlope) -> Self {
        Self {
            kappa: s.kappa,
            kappa_ci95_correlated: s.kappa_band.is_finite().then_some(s.kappa_band),
            kappa_at_lowest_load: s.kappa_at_lowest,
            kappa_at_highest_load: s.kappa_at_highest,
            w_over_w0_range: [s.lowest_load, s.highest_load],
            loads: s.loads,
        }
    }

    /// The record of an analytic instance's results; None where no load was in range (null),
    /// an error where the record is there but malformed.
    pub fn of(results: &Value) -> anyhow::Result<Option<Self>> {
        match results.get("area_load_slope") {
            None | Some(Value::Null) => Ok(None),
            Some(v) => Ok(Some(serde_json::from_value(v.clone()).map_err(|e| {
                anyhow::anyhow!("analytic results.area_load_slope is malformed ({e}): {v}")
            })?)),
        }
    }
}

/// Upper end of the paper's mild-wear load range (W/W₀ ∈ [0.001, 0.06], its Sec. 4): the
/// area–load slope is fitted, and the plateau of K taken, at loads up to it.
pub const MILD_WEAR_MAX_LOAD: f64 = 0.06;

/// What an analytic instance computes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "curves", deny_unknown_fields)]
pub enum AnalyticJob {
    /// The model fitted at every load of one study (input 0: its statistics), evaluated at
    /// the thresholds `a_star_over_ls2`.
    #[serde(rename = "fitted")]
    Fitted {
        lambda_s_px: f64,
        a_star_over_ls2: Vec<f64>,
    },
    /// K_PL and 𝒦_PL against `A_m/A_s` over `10^d0 … 10^d1` (`points` steps, plus the
    /// `A_m → ∞` limit), no input.
    #[serde(rename = "fig6")]
    Fig6 {
        alpha: f64,
        a_star_over_a_s: Vec<f64>,
        a_m_over_a_s_decades: [i32; 2],
        points: usize,
    },
}

impl AnalyticJob {
    /// The curves of paper Fig. 6.
    pub fn fig6() -> Self {
        Self::Fig6 {
            alpha: FIG6_ALPHA,
            a_star_over_a_s: FIG6_A_STAR_OVER_A_S.to_vec(),
            a_m_over_a_s_decades: [0, 12],
            points: FIG6_POINTS,
        }
    }
}

impl Stage for Analytic {
    const NAME: &'static str = "analytic";
    const VERSION: u32 = 3;
    type Job = AnalyticJob;

    fn compute(job: &AnalyticJob, inputs: &Inputs, dir: &Path) -> anyhow::Result<Value> {
        match job {
            AnalyticJob::Fitted {
                lambda_s_px,
                a_star_over_ls2,
            } => fitted_model(*lambda_s_px, a_star_over_ls2, inputs, dir),
            AnalyticJob::Fig6 {
                alpha,
                a_star_over_a_s,
                a_m_over_a_s_decades,
                points,
            } => fig6_curves(*alpha, a_star_over_a_s, *a_m_over_a_s_decades, *points, dir),
        }
    }
}

/// The analytic stage: the fitted plateau + power-law model of each load of a study on the
/// statistics' A* grid (`model.parquet`), or the model curves of Fig. 6 (`fig6.parquet`).
fn fitted_model(
    lambda_s_px: f64,
    a_star_over_ls2: &[f64],
    inputs: &Inputs,
    dir: &Path,
) -> anyhow::Result<Value> {
    let path = inputs.file(0, "statistics", "alpha.parquet")?;
    let df = crate::store::table::read(&path)?;
    let ls2 = lambda_s_px * lambda_s_px;
    let est = df.column("estimator")?.str()?.clone();
    let li = df.column("load_index")?.u32()?.clone();
    let w = df.column("w_over_w0")?.f64()?.clone();
    let alpha = df.column("alpha")?.f64()?.clone();
    let k_s = df.column("k_s_px")?.f64()?.clone();
    let k_m = df.column("k_max_px")?.f64()?.clone();
    let mut rows: (Vec<u32>, Vec<f64>, Vec<f64>) = Default::default();
    let mut fit: [Vec<Option<f64>>; 5] = Default::default();
    let mut fitted_loads = 0;
    for i in 0..df.height() {
        if est.get(i) != Some(Estimator::DiscretePlateauPowerLaw.name()) {
            continue;
        }
        let (Some(l), Some(wi)) = (li.get(i), w.get(i)) else {
            anyhow::bail!("{}: null load in row {i}", path.display());
        };
        let model = match (alpha.get(i), k_s.get(i), k_m.get(i)) {
            (Some(a), Some(s), Some(m)) => Some(PlateauPowerLaw::new(a, s, m)?),
            _ => None,
        };
        fitted_loads += usize::from(model.is_some());
        for &a_star in a_star_over_ls2 {
            rows.0.push(l);
            rows.1.push(wi);
            rows.2.push(a_star);
            let values = match &model {
                Some(m) => [
                    Some(m.alpha),
                    Some(m.a_s / ls2),
                    Some(m.a_m / ls2),
                    Some(m.k_archard(a_star * ls2)?),
                    Some(m.k_upscaled(a_star * ls2)?),
                ],
                None => [None; 5],
            };
            for (c, v) in fit.iter_mut().zip(values) {
                c.push(v);
            }
        }
    }
    let plateau_load = write_plateau(lambda_s_px, a_star_over_ls2, inputs, &df, dir)?;
    let slope = {
        let loads = inputs.table(0, "statistics", "loads.parquet")?;
        stats::area_load_slope(
            &f64_column(&loads, "w_over_w0")?,
            &f64_column(&loads, "area_fraction_mean")?,
            &f64_column(&loads, "area_fraction_ci95")?,
            MILD_WEAR_MAX_LOAD,
        )
    };
    let n = rows.0.len();
    let [a, s, m, k, kk] = fit;
    write(
        dir,
        "model.parquet",
        DataFrame::new(
            n,
            vec![
                col("load_index", rows.0),
                col("w_over_w0", rows.1),
                col("a_star_over_ls2", rows.2),
                Column::new("alpha".into(), a),
                Column::new("a_s_over_ls2".into(), s),
                Column::new("a_m_over_ls2".into(), m),
                Column::new("k_pl".into(), k),
                Column::new("k_upscaled_pl".into(), kk),
            ],
        )?,
    )?;
    Ok(json!({
        "fitted_loads": fitted_loads,
        "source_estimator": Estimator::DiscretePlateauPowerLaw.name(),
        "plateau_w_over_w0": plateau_load,
        "area_load_slope": slope.as_ref().map(AreaLoadSlopeRecord::new),
    }))
}

/// The plateau of Archard's K that the fitted model predicts, `K_PL(A*)` in the limit
/// `A_m → ∞`, from the fit at the largest load of the mild-wear range that has one, beside
/// the model at that load's own cut-off and the simulated K there: `plateau.parquet`.
/// Returns that load (None, and no rows, when no load up to [`MILD_WEAR_MAX_LOAD`] is fitted).
fn write_plateau(
    lambda_s_px: f64,
    a_star_over_ls2: &[f64],
    inputs: &Inputs,
    alpha_table: &DataFrame,
    dir: &Path,
) -> anyhow::Result<Option<f64>> {
    let wear = inputs.table(0, "statistics", "wear.parquet")?;
    let (load, table) = plateau_table(lambda_s_px, a_star_over_ls2, alpha_table, &wear)?;
    write(dir, "plateau.parquet", table)?;
    Ok(load)
}

/// [`write_plateau`]'s table from the statistics' `alpha.parquet` and `wear.parquet`.
fn plateau_table(
    lambda_s_px: f64,
    a_star_over_ls2: &[f64],
    alpha_table: &DataFrame,
    wear: &DataFrame,
) -> anyhow::Result<(Option<f64>, DataFrame)> {
    let ls2 = lambda_s_px * lambda_s_px;
    let est = str_column(alpha_table, "estimator")?;
    let li = u32_column(alpha_table, "load_index")?;
    let w = f64_column(alpha_table, "w_over_w0")?;
    let alpha = f64_column(alpha_table, "alpha")?;
    let k_s = f64_column(alpha_table, "k_s_px")?;
    let k_m = f64_column(alpha_table, "k_max_px")?;
    // The largest fitted load in range (NaN marks an unfitted load).
    let fit = (0..w.len())
        .filter(|&i| est[i] == Estimator::DiscretePlateauPowerLaw.name())
        .filter(|&i| w[i] <= MILD_WEAR_MAX_LOAD)
        .filter(|&i| alpha[i].is_finite() && k_s[i].is_finite() && k_m[i].is_finite())
        .max_by(|&a, &b| w[a].total_cmp(&w[b]));
    let (wl, wa, wk, wci) = (
        u32_column(wear, "load_index")?,
        f64_column(wear, "a_star_over_ls2")?,
        f64_column(wear, "k_archard_mean")?,
        f64_column(wear, "k_archard_ci95")?,
    );
    let mut cols: [Vec<f64>; 7] = Default::default();
    if let Some(i) = fit {
        let at_load = PlateauPowerLaw::new(alpha[i], k_s[i], k_m[i])?;
        let limit = PlateauPowerLaw::new(alpha[i], k_s[i], f64::INFINITY)?;
        for &a_star in a_star_over_ls2 {
            let j = (0..wl.len())
                .find(|&j| wl[j] == li[i] && (wa[j] - a_star).abs() <= 1e-12 * a_star.abs())
                .ok_or_else(|| {
                    anyhow::anyhow!(
                        "wear.parquet has no row at W/W0 = {} and A*/λs² = {a_star}",
                        w[i]
                    )
                })?;
            for (c, v) in cols.iter_mut().zip([
                a_star,
                w[i],
                alpha[i],
                limit.k_archard(a_star * ls2)?,
                at_load.k_archard(a_star * ls2)?,
                wk[j],
                wci[j],
            ]) {
                c.push(v);
            }
        }
    }
    let names = [
        "a_star_over_ls2",
        "w_over_w0",
        "alpha",
        "k_pl_plateau",
        "k_pl_at_load",
        "k_archard_mean",
        "k_archard_ci95",
    ];
    let n = cols[0].len();
    let columns = names
        .iter()
        .zip(cols)
        .map(|(name, v)| col(name, v))
        .collect();
    Ok((fit.map(|i| w[i]), DataFrame::new(n, columns)?))
}

/// K_PL and 𝒦_PL against `A_m/A_s` for α = 1.5 and several `A*/A_s` (paper Fig. 6), plus
/// the `A_m → ∞` limits as rows with `a_m_over_a_s = inf`.
fn fig6_curves(
    alpha: f64,
    a_star_over_a_s: &[f64],
    decades: [i32; 2],
    points: usize,
    dir: &Path,
) -> anyhow::Result<Value> {
    anyhow::ensure!(points >= 2, "points = {points}: need at least 2");
    let (lo, hi) = (decades[0] as f64, decades[1] as f64);
    let (mut a_star, mut a_m, mut k, mut kk) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for &s in a_star_over_a_s {
        let grid = (0..points)
            .map(|i| 10f64.powf(lo + (hi - lo) * i as f64 / (points - 1) as f64))
            .chain(std::iter::once(f64::INFINITY));
        for m in grid {
            let model = PlateauPowerLaw::new(alpha, 1.0, m)?;
            a_star.push(s);
            a_m.push(m);
            k.push(model.k_archard(s)?);
            kk.push(model.k_upscaled(s)?);
        }
    }
    let n = a_star.len();
    write(
        dir,
        "fig6.parquet",
        DataFrame::new(
            n,
            vec![
                col("alpha", vec![alpha; n]),
                col("a_star_over_a_s", a_star),
                col("a_m_over_a_s", a_m),
                col("k_pl", k),
                col("k_upscaled_pl", kk),
            ],
        )?,
    )?;
    Ok(json!({ "rows": n }))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The plateau comes from the largest fitted load up to W/W₀ = 0.06 (not an unfitted
    /// one, not one beyond), and is the model's A_m → ∞ limit (A.3) by hand.
    #[test]
    fn plateau_of_k_is_the_limit_at_the_largest_fitted_mild_load() {
        let mle = Estimator::DiscretePlateauPowerLaw.name();
        let (alpha, a_s_px, a_m_px) = (1.6, 200.0, 5.0e4);
        let alpha_table = df!(
            "estimator" => [mle, mle, mle, "other", mle],
            "load_index" => [0u32, 1, 2, 3, 3],
            "w_over_w0" => [0.01, 0.03, 0.05, 0.1, 0.1],
            "alpha" => [1.4, alpha, f64::NAN, 1.9, 1.9],
            "k_s_px" => [100.0, a_s_px, 300.0, 400.0, 400.0],
            "k_max_px" => [1.0e4, a_m_px, 1.0e5, 1.0e6, 1.0e6],
        )
        .unwrap();
        let a_star = [1.0, 8.0, 32.0];
        let wear = df!(
            "load_index" => [1u32, 1, 1, 0],
            "a_star_over_ls2" => [1.0, 8.0, 32.0, 1.0],
            "k_archard_mean" => [0.5, 0.1, 0.01, 0.9],
            "k_archard_ci95" => [0.05, 0.01, 0.001, 0.09],
        )
        .unwrap();
        let lambda_s_px = 8.0;
        let (load, t) = plateau_table(lambda_s_px, &a_star, &alpha_table, &wear).unwrap();
        assert_eq!(load, Some(0.03));
        let lim = f64_column(&t, "k_pl_plateau").unwrap();
        let at = f64_column(&t, "k_pl_at_load").unwrap();
        assert_eq!(f64_column(&t, "k_archard_mean").unwrap(), [0.5, 0.1, 0.01]);
        for (i, &s) in a_star.iter().enumerate() {
            let r = s * lambda_s_px * lambda_s_px / a_s_px;
            let want = if r <= 1.0 {
                1.0 - (alpha - 1.0) / alpha * r
            } else {
                r.powf(1.0 - alpha) / alpha
            };
            assert!(
                (lim[i] - want).abs() < 1e-14,
                "A* = {s}: {} vs {want}",
                lim[i]
            );
            assert!(at[i] < lim[i], "a finite cut-off removes tail mass");
        }
        // No fitted load in range: no load and no rows.
        let beyond = df!(
            "estimator" => [mle, mle],
            "load_index" => [0u32, 1],
            "w_over_w0" => [0.01, 0.1],
            "alpha" => [f64::NAN, 1.5],
            "k_s_px" => [100.0, 100.0],
            "k_max_px" => [1.0e4, 1.0e4],
        )
        .unwrap();
        let (load, t) = plateau_table(lambda_s_px, &a_star, &beyond, &wear).unwrap();
        assert_eq!((load, t.height()), (None, 0));
    }
}
