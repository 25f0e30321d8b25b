//! A `measured` study resolved: topography files as realizations instead of a generated
//! spectrum; and the hardness check both kinds share.

use std::path::{Path, PathBuf};

use super::error::ConfigError;
use super::figures::FigureKind;
use super::schema::Pipeline;
use super::study::{MeasuredPlan, MeasuredStudy, StudyPlan};
use crate::surface::{Method, SurfaceParams};

impl Pipeline {
    /// Every file outside the store that this pipeline reads, with its field: the measured
    /// studies' topography files (paths relative to the pipeline file at `origin`). An
    /// output of any command must be none of them, nor the pipeline file itself.
    pub fn read_files(&self, origin: &str) -> Vec<(String, PathBuf)> {
        let dir = Path::new(origin).parent().unwrap_or(Path::new(""));
        self.studies
            .iter()
            .filter_map(|(name, s)| s.measured.as_ref().map(|m| (name, m)))
            .flat_map(|(name, m)| {
                m.files
                    .iter()
                    .enumerate()
                    .map(move |(i, f)| (format!("studies.{name}.measured.files[{i}]"), dir.join(f)))
            })
            .collect()
    }

    /// A measured study is drawn by `fig2` and `fig45` only: the other figures compare
    /// generated spectra (λ_l/λ_s, H, L/λ_l, λ_s/Δl) or hardnesses.
    pub(super) fn check_measured_figures(&self, origin: &str) -> Result<(), ConfigError> {
        for (fname, fig) in &self.figures {
            for (sname, study) in &self.studies {
                let drawn = fig.profiles.iter().any(|p| fig.uses(sname, p));
                let allowed = matches!(fig.kind, FigureKind::Fig2 | FigureKind::Fig45);
                if study.measured.is_some() && drawn && !allowed {
                    return Err(ConfigError::Invalid {
                        path: origin.to_string(),
                        field: format!("figures.{fname}"),
                        value: sname.clone(),
                        allowed: format!("draws the measured study '{sname}', which only `fig2` and `fig45` figures draw (the maps, A_c, N and dN/dA_c; K, 𝒦 and the wear rate against load)"),
                    });
                }
            }
        }
        Ok(())
    }

    /// A study's hardness checked: finite, > 0 and not below any of its loads.
    pub(super) fn check_hardness(
        &self,
        name: &str,
        profile: &str,
        loads: &[f64],
        origin: &str,
    ) -> Result<(), ConfigError> {
        let Some(h) = self.studies[name].hardness else {
            return Ok(());
        };
        if h == f64::INFINITY {
            // No ceiling: elastic contact, as documented.
            return Ok(());
        }
        let invalid = |value: String, allowed: String| ConfigError::Invalid {
            path: origin.to_string(),
            field: format!("studies.{name}.hardness"),
            value,
            allowed,
        };
        if !(h.is_finite() && h > 0.0) {
            return Err(invalid(
                crate::ranges::show(h),
                "must be > 0 (in units of E*·rms slope, as W/W0), or .inf or left out for elastic contact".into(),
            ));
        }
        if let Some(w) = loads.iter().find(|&&w| w > h) {
            return Err(invalid(
                crate::ranges::show(h),
                format!("is below the load W/W0 = {w} of profile {profile}: a pressure capped at the hardness cannot carry a mean above it; raise the hardness or lower the loads")
            ));
        }
        Ok(())
    }

    /// A measured study in one profile: its files (relative to the pipeline file), λ_s/Δl,
    /// loads and hardness checked; the generated study's fields refused.
    pub(super) fn resolve_measured(
        &self,
        name: &str,
        profile: &str,
        m: &MeasuredStudy,
        origin: &str,
    ) -> Result<StudyPlan, ConfigError> {
        let study = &self.studies[name];
        let sp = &study.profiles[profile];
        let base = format!("studies.{name}");
        let invalid = |field: String, value: String, allowed: &str| ConfigError::Invalid {
            path: origin.to_string(),
            field,
            value,
            allowed: allowed.to_string(),
        };
        let pbase = format!("{base}.profiles.{profile}");
        let generated_only = [
            ("hurst", study.hurst.map(|v| v.to_string())),
            (
                "lambda_l_over_lambda_s",
                study.lambda_l_over_lambda_s.map(|v| v.to_string()),
            ),
            ("seed", study.seed.map(|v| v.to_string())),
            (
                "rolloff_over_lambda_l",
                study.rolloff_over_lambda_l.map(|v| v.to_string()),
            ),
            (
                "method",
                (study.method != "filter").then(|| study.method.clone()),
            ),
        ];
        let sized = [
            ("l_over_lambda_l", sp.l_over_lambda_l.map(|v| v.to_string())),
            (
                "lambda_s_over_dl",
                sp.lambda_s_over_dl.map(|v| v.to_string()),
            ),
            ("realizations", sp.realizations.map(|v| v.to_string())),
        ];
        let given = generated_only
            .into_iter()
            .map(|(f, v)| (format!("{base}.{f}"), v))
            .chain(sized.into_iter().map(|(f, v)| (format!("{pbase}.{f}"), v)));
        for (field, value) in given {
            if let Some(value) = value {
                return Err(invalid(field, value, "a measured study takes its surfaces from its files: leave this out (λ_s/Δl is measured.lambda_s_over_dl, one realization per file)"));
            }
        }
        if m.files.is_empty() {
            return Err(invalid(
                format!("{base}.measured.files"),
                "[]".into(),
                "list at least one topography file",
            ));
        }
        let res = m.lambda_s_over_dl;
        if !(res.is_finite() && res >= 2.0) {
            return Err(invalid(
                format!("{base}.measured.lambda_s_over_dl"),
                res.to_string(),
                "λ_s/Δl must be finite and ≥ 2 (`wearcoef topography FILE --json` reports the fitted one)",
            ));
        }
        if m.preparation.fill == crate::io::prepare::FillArg::Keep {
            return Err(invalid(
                format!("{base}.measured.preparation.fill"),
                "keep".into(),
                "contact needs every height: choose `harmonic` or `none`",
            ));
        }
        let dir = Path::new(origin).parent().unwrap_or(Path::new(""));
        let files: Vec<PathBuf> = m.files.iter().map(|f| dir.join(f)).collect();
        let (loads, sweep, keep_pressure) = self.resolve_study_loads(name, profile, origin)?;
        self.check_hardness(name, profile, &loads, origin)?;
        let count = files.len() as u32;
        super::limits::check_realizations(&pbase, count, loads.len(), profile, origin)?;
        Ok(StudyPlan {
            name: name.to_string(),
            profile: profile.to_string(),
            realizations: count,
            seed: 0,
            surface: SurfaceParams {
                n: 0,
                hurst: 0.0,
                lambda_l_px: 0.0,
                lambda_s_px: res,
                rolloff_lambda_px: None,
                method: Method::Filter,
                seed: 0,
            },
            loads,
            keep_pressure,
            sweep,
            e_star: self.material.e_star,
            tolerance: sp.tolerance.unwrap_or(self.solver.tolerance),
            max_iterations: self.solver.max_iterations,
            // `.inf` is elastic contact, as if left out.
            hardness: study.hardness.filter(|h| *h != f64::INFINITY),
            measured: Some(MeasuredPlan {
                files,
                fields: (0..m.files.len())
                    .map(|i| format!("{base}.measured.files[{i}]"))
                    .collect(),
                preparation: m.preparation.clone(),
            }),
        })
    }
}
