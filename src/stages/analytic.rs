//! The analytic stage: the plateau + power-law model (paper Appendix A) fitted to one study
//! on its A* grid (`model.parquet`), or the model curves of paper Fig. 6 (`fig6.parquet`).

use std::path::Path;

use polars::prelude::*;
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

use super::{Inputs, Stage};
use crate::analytic::PlateauPowerLaw;
use crate::pipeline::table::{col, write};
use crate::powerlaw::Estimator;

pub struct Analytic;

/// Paper Fig. 6: the exponent, and the thresholds `A*/A_s` of the model curves, whose cut-off
/// `A_m/A_s` runs over `10^0 … 10^12` in [`FIG6_POINTS`] logarithmic steps.
pub const FIG6_ALPHA: f64 = 1.5;
pub const FIG6_A_STAR_OVER_A_S: [f64; 5] = [0.5, 1.0, 10.0, 100.0, 1000.0];
pub const FIG6_POINTS: usize = 121;

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
    const VERSION: u32 = 1;
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
    let df = crate::pipeline::table::read(&path)?;
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
    Ok(
        json!({ "fitted_loads": fitted_loads, "source_estimator": Estimator::DiscretePlateauPowerLaw.name() }),
    )
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
