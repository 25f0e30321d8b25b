//! The audits stage: checks of whether a figure's sizes, realizations and loads are enough,
//! each a Parquet table (named after the figure it audits) and a verdict in the manifest's
//! results. Figures draw these tables; they compute nothing themselves.
//! - `realizations`: the realization rule of an ensemble-mean curve figure (Fig. 2e–f).
//! - `settings`: the Appendix B rule (KS distance and exponent to the finest setting; first
//!   `r` realizations against all).
//! - `load_resolution`: a sweep's curves interpolated between its loads against a finer
//!   sweep's band (Figs. 4b and 5).

use std::path::Path;

use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::stage::Stage;
use crate::store::inputs::Inputs;

mod load_resolution;
mod realizations;
mod settings;

pub use load_resolution::{FIG45_A_STAR, FIG45_CURVES, LOAD_RESOLUTION_TOLERANCE};
pub use realizations::{FIG2_CURVE_TOLERANCE, FIG2_PEAK_TOLERANCE_STEPS};
pub use settings::{
    ConvergenceRow, ConvergenceTable, Setting, CONVERGENCE_ESTIMATOR, CONVERGENCE_KS_TOLERANCE,
};

pub struct Audits;

/// What an audit checks.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "audit", rename_all = "snake_case", deny_unknown_fields)]
pub enum AuditJob {
    /// Inputs: the clusters instances of every realization of one study.
    Realizations {
        curve_tolerance: f64,
        peak_tolerance_steps: usize,
    },
    /// Inputs: per setting, its statistics then its clusters instances.
    Settings {
        settings: Vec<Setting>,
        ks_tolerance: f64,
        alpha_estimator: String,
    },
    /// Inputs: the finer sweep's statistics, then the chosen sweep's.
    LoadResolution {
        tolerance: f64,
        a_star_over_ls2: Vec<f64>,
    },
}

impl AuditJob {
    pub fn realizations() -> Self {
        Self::Realizations {
            curve_tolerance: FIG2_CURVE_TOLERANCE,
            peak_tolerance_steps: FIG2_PEAK_TOLERANCE_STEPS,
        }
    }

    pub fn settings(settings: Vec<Setting>) -> Self {
        Self::Settings {
            settings,
            ks_tolerance: CONVERGENCE_KS_TOLERANCE,
            alpha_estimator: CONVERGENCE_ESTIMATOR.name().to_string(),
        }
    }

    pub fn load_resolution() -> Self {
        Self::LoadResolution {
            tolerance: LOAD_RESOLUTION_TOLERANCE,
            a_star_over_ls2: FIG45_A_STAR.to_vec(),
        }
    }
}

/// Name of an audit's table.
pub const TABLE: &str = "audit.parquet";

impl Stage for Audits {
    const NAME: &'static str = "audits";
    const VERSION: u32 = 2;
    type Job = AuditJob;

    fn compute(job: &AuditJob, inputs: &Inputs, dir: &Path) -> anyhow::Result<Value> {
        let (table, result) = match job {
            AuditJob::Realizations {
                curve_tolerance,
                peak_tolerance_steps,
            } => realizations::realizations(*curve_tolerance, *peak_tolerance_steps, inputs)?,
            AuditJob::Settings {
                settings,
                ks_tolerance,
                alpha_estimator,
            } => {
                anyhow::ensure!(
                    *ks_tolerance == CONVERGENCE_KS_TOLERANCE
                        && alpha_estimator == CONVERGENCE_ESTIMATOR.name(),
                    "this build audits with KS tolerance {CONVERGENCE_KS_TOLERANCE} and the {} exponent",
                    CONVERGENCE_ESTIMATOR.name()
                );
                let (t, r) = settings::settings(inputs, settings)?;
                (Some(t), r)
            }
            AuditJob::LoadResolution {
                tolerance,
                a_star_over_ls2,
            } => {
                anyhow::ensure!(
                    *tolerance == LOAD_RESOLUTION_TOLERANCE
                        && a_star_over_ls2.as_slice() == FIG45_A_STAR,
                    "this build judges load resolution with tolerance {LOAD_RESOLUTION_TOLERANCE} at A*/λ_s² = {FIG45_A_STAR:?}"
                );
                let fine = inputs.table(0, "statistics", "wear.parquet")?;
                let chosen = inputs.table(1, "statistics", "wear.parquet")?;
                let (t, r) = load_resolution::load_resolution(&fine, &chosen)?;
                (Some(t), r)
            }
        };
        if let Some(t) = table {
            crate::store::table::write(dir, TABLE, t)?;
        }
        Ok(result)
    }
}
