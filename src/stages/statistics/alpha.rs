//! `alpha.parquet`: the exponent α per load by both estimators, each with its interval
//! over realizations (refitted in every resample).

use std::path::Path;

use polars::prelude::*;

use super::job::{StatisticsJob, Study};
use crate::powerlaw::{self, Estimator};
use crate::resample::{self, NoInterval};
use crate::store::table::{col, write};

/// One row of `alpha.parquet`: one estimator at one load (`None`: not fitted, or not an
/// output of that estimator).
#[derive(Default)]
struct AlphaRow {
    alpha: Option<f64>,
    std_error: Option<f64>,
    ci95: Option<(f64, f64)>,
    ci95_method: Option<String>,
    k_min: Option<f64>,
    k_max: Option<f64>,
    k_s: Option<f64>,
    n_fitted: Option<u64>,
    ks_distance: Option<f64>,
    /// Clauset et al.'s goodness-of-fit p-value (truncated power law only).
    gof_p: Option<f64>,
    /// The likelihood-ratio tests of the power law above k_min (truncated power law only).
    tail: Option<powerlaw::TailComparison>,
    note: String,
}

impl AlphaRow {
    /// The interval over realizations of the estimate (refitted in each resample), or
    /// why there is none.
    fn with_interval(mut self, ci: Result<resample::Interval, NoInterval>) -> Self {
        match ci {
            Ok(c) => {
                self.ci95 = Some((c.low, c.high));
                self.std_error = Some(c.std_error);
                self.ci95_method = Some(resample::METHOD.to_string());
            }
            Err(e) => self.ci95_method = Some(e.reason()),
        }
        self
    }
}

/// Why a row has its point estimate only.
pub const NOT_SHOWN: &str =
    "not computed: no figure of the profile shows α at this load (wearcoef fit gives it)";

/// A row with its point estimate only: no figure shows its interval or tests.
fn point_only(row: AlphaRow) -> AlphaRow {
    AlphaRow {
        ci95_method: Some(NOT_SHOWN.to_string()),
        ..row
    }
}

/// The pooled areas of the realizations drawn.
fn pool(drawn: &[&Vec<u64>]) -> Vec<u64> {
    drawn.iter().flat_map(|v| v.iter().copied()).collect()
}

/// The discrete truncated MLE at load `l`: k_min by the KS criterion, k_max the largest
/// area; its interval resamples whole realizations and refits k_min and k_max each time.
fn truncated_row(job: &StatisticsJob, l: usize, per: &[Vec<u64>], areas: &[u64]) -> AlphaRow {
    match powerlaw::fit_tail_at_max(areas) {
        Ok(t) if !job.exponent_interval_at(l) => point_only(AlphaRow {
            alpha: Some(t.fit.alpha),
            k_min: Some(t.fit.lower),
            k_max: Some(t.fit.upper),
            n_fitted: Some(t.fit.n as u64),
            ks_distance: Some(t.fit.ks_distance),
            ..AlphaRow::default()
        }),
        Ok(t) => {
            let f = t.fit;
            let ci = resample::over_realizations(
                per,
                &|d: &[&Vec<u64>]| {
                    powerlaw::fit_tail_at_max(&pool(d))
                        .ok()
                        .map(|t| t.fit.alpha)
                },
                job.bootstrap_resamples,
                job.seed ^ (l as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15),
                None,
            );
            let gof = powerlaw::goodness_of_fit(
                areas,
                &f,
                job.bootstrap_resamples,
                job.seed ^ (l as u64 + 2).wrapping_mul(0x94d0_49bb_1331_11eb),
            );
            AlphaRow {
                tail: powerlaw::compare_tail(areas, f.lower as u64).ok(),
                alpha: Some(f.alpha),
                k_min: Some(f.lower),
                k_max: Some(f.upper),
                n_fitted: Some(f.n as u64),
                ks_distance: Some(f.ks_distance),
                gof_p: gof.as_ref().ok().map(|g| g.p_value),
                note: match gof {
                    Ok(g) if g.p_value <= powerlaw::REJECT_AT => format!(
                        "the power law is rejected above k_min: goodness-of-fit p = {} ≤ {} ({} synthetic samples)",
                        g.p_value,
                        powerlaw::REJECT_AT,
                        g.samples
                    ),
                    Ok(_) => String::new(),
                    Err(e) => format!("no goodness of fit: {e}"),
                },
                ..AlphaRow::default()
            }
            .with_interval(ci)
        }
        Err(e) => AlphaRow {
            note: format!("no fit: {e}"),
            ..AlphaRow::default()
        },
    }
}

/// The plateau + power law (the model of Appendix A) fitted jointly; its interval
/// resamples whole realizations and refits A_s and A_m each time.
fn plateau_row(job: &StatisticsJob, l: usize, per: &[Vec<u64>], areas: &[u64]) -> AlphaRow {
    match powerlaw::fit_plateau_power_law(areas) {
        Ok(f) if !job.exponent_interval_at(l) => point_only(AlphaRow {
            alpha: Some(f.alpha),
            k_max: Some(f.k_m as f64),
            k_s: Some(f.k_s),
            n_fitted: Some(f.n as u64),
            ..AlphaRow::default()
        }),
        Ok(f) => {
            let ci = resample::over_realizations(
                per,
                &|d: &[&Vec<u64>]| {
                    powerlaw::fit_plateau_power_law(&pool(d))
                        .ok()
                        .map(|f| f.alpha)
                },
                job.bootstrap_resamples,
                job.seed ^ (l as u64 + 1).wrapping_mul(0xbf58_476d_1ce4_e5b9),
                None,
            );
            AlphaRow {
                alpha: Some(f.alpha),
                k_max: Some(f.k_m as f64),
                k_s: Some(f.k_s),
                n_fitted: Some(f.n as u64),
                ..AlphaRow::default()
            }
            .with_interval(ci)
        }
        Err(e) => AlphaRow {
            note: format!("no fit: {e}"),
            ..AlphaRow::default()
        },
    }
}

/// One row per load and estimator; a fit that cannot be made leaves nulls and says why.
/// Returns the number of loads the truncated power law was fitted at.
pub(super) fn write_alpha(study: &Study, dir: &Path) -> anyhow::Result<usize> {
    let Study {
        job,
        s,
        pooled,
        ls2,
        ..
    } = study;
    let ls2 = *ls2;
    let mut rows: Vec<(usize, Estimator, AlphaRow)> = Vec::new();
    for (l, areas) in pooled.iter().enumerate() {
        let per: Vec<Vec<u64>> = s.areas.iter().map(|r| r[l].clone()).collect();
        rows.push((
            l,
            Estimator::DiscreteTruncated,
            truncated_row(job, l, &per, areas),
        ));
        rows.push((
            l,
            Estimator::DiscretePlateauPowerLaw,
            plateau_row(job, l, &per, areas),
        ));
    }
    let fitted = rows
        .iter()
        .filter(|r| r.1 == Estimator::DiscreteTruncated && r.2.alpha.is_some())
        .count();
    let opt =
        |f: &dyn Fn(&AlphaRow) -> Option<f64>| rows.iter().map(|r| f(&r.2)).collect::<Vec<_>>();
    let n = rows.len();
    // Per alternative: the normalised ratio R/(σ√n) (positive favours the power law) and
    // its p-value.
    let mut tests: Vec<Column> = Vec::new();
    for (i, alt) in powerlaw::Alternative::ALL.iter().enumerate() {
        let test = |r: &AlphaRow| {
            r.tail
                .as_ref()
                .and_then(|t| t.tests[i].as_ref().ok())
                .copied()
        };
        tests.push(Column::new(
            format!("lr_{}_normalised_ratio", alt.name()).into(),
            opt(&|r| test(r).map(|t| t.normalised_ratio)),
        ));
        tests.push(Column::new(
            format!("lr_{}_p", alt.name()).into(),
            opt(&|r| test(r).map(|t| t.p_value)),
        ));
    }
    let mut table = DataFrame::new(
        n,
        vec![
            col(
                "load_index",
                rows.iter().map(|r| r.0 as u32).collect::<Vec<u32>>(),
            ),
            col(
                "w_over_w0",
                rows.iter().map(|r| job.loads[r.0]).collect::<Vec<f64>>(),
            ),
            col(
                "estimator",
                rows.iter()
                    .map(|r| r.1.name().to_string())
                    .collect::<Vec<String>>(),
            ),
            Column::new("alpha".into(), opt(&|r| r.alpha)),
            Column::new("std_error".into(), opt(&|r| r.std_error)),
            Column::new("ci95_low".into(), opt(&|r| r.ci95.map(|c| c.0))),
            Column::new("ci95_high".into(), opt(&|r| r.ci95.map(|c| c.1))),
            Column::new(
                "ci95_method".into(),
                rows.iter()
                    .map(|r| r.2.ci95_method.clone())
                    .collect::<Vec<Option<String>>>(),
            ),
            Column::new("k_min_px".into(), opt(&|r| r.k_min)),
            Column::new("k_max_px".into(), opt(&|r| r.k_max)),
            Column::new("k_s_px".into(), opt(&|r| r.k_s)),
            Column::new("k_s_over_ls2".into(), opt(&|r| r.k_s.map(|k| k / ls2))),
            Column::new(
                "n_fitted".into(),
                rows.iter()
                    .map(|r| r.2.n_fitted)
                    .collect::<Vec<Option<u64>>>(),
            ),
            Column::new("ks_distance".into(), opt(&|r| r.ks_distance)),
            Column::new("gof_p".into(), opt(&|r| r.gof_p)),
            Column::new(
                "alpha_above_k_min".into(),
                opt(&|r| r.tail.as_ref().map(|t| t.alpha)),
            ),
            col(
                "clusters",
                rows.iter()
                    .map(|r| pooled[r.0].len() as u64)
                    .collect::<Vec<u64>>(),
            ),
            col("realizations", vec![s.areas.len() as u32; n]),
            Column::new(
                "tail_verdict".into(),
                rows.iter()
                    .map(|r| r.2.tail.as_ref().map(powerlaw::tail_verdict))
                    .collect::<Vec<Option<String>>>(),
            ),
            col(
                "note",
                rows.iter()
                    .map(|r| r.2.note.clone())
                    .collect::<Vec<String>>(),
            ),
        ],
    )?;
    for c in tests {
        table.with_column(c)?;
    }
    write(dir, "alpha.parquet", table)?;
    Ok(fitted)
}
