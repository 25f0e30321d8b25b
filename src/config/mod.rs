//! `pipeline.yaml`: schema, validation and profile resolution.
//!
//! Unknown fields are rejected at parse time (serde `deny_unknown_fields`); every value is
//! then checked and the first invalid one is reported with its field path (e.g.
//! `studies.fig2.profiles.quick.lambda_s_over_dl`), the value and the allowed range.
//! Nothing is written before the whole file validates.

use std::path::Path;

use crate::contact::sweep::MAX_W_OVER_W0;
use crate::surface::{Method, SurfaceParams};

mod cluster;
mod error;
mod figures;
mod limits;
mod measured;
mod schema;
mod sizes;
mod study;
pub use cluster::ClusterConfig;
pub use error::ConfigError;
pub use figures::{ExponentLoads, FigureDecl, FigureKind};
pub use schema::{Material, Pipeline, Solver};
pub use study::{
    is_plain_name, Loads, MeasuredPlan, MeasuredStudy, Study, StudyPlan, StudyProfile, MAX_N,
    RESERVED_PROFILE_NAMES,
};

impl Pipeline {
    /// Read, parse and validate a file.
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        // At most 16 MiB (a pipeline file is a few KiB; /dev/zero is not one).
        const MAX_BYTES: u64 = 16 << 20;
        let read = |cause: String| ConfigError::Read {
            path: path.display().to_string(),
            cause,
        };
        let mut text = String::new();
        use std::io::Read as _;
        std::fs::File::open(path)
            .and_then(|f| f.take(MAX_BYTES + 1).read_to_string(&mut text))
            .map_err(|e| read(e.to_string()))?;
        if text.len() as u64 > MAX_BYTES {
            return Err(read(format!(
                "longer than {} MiB, which no pipeline file is",
                MAX_BYTES >> 20
            )));
        }
        Self::parse(&text, &path.display().to_string())
    }

    /// Parse and validate YAML text; `origin` names it in messages.
    pub fn parse(text: &str, origin: &str) -> Result<Self, ConfigError> {
        let pipeline: Pipeline = serde_saphyr::from_str(text).map_err(|e| ConfigError::Parse {
            path: origin.to_string(),
            message: limits::plain_yaml_error(&e.to_string()),
        })?;
        pipeline.validate(origin)?;
        Ok(pipeline)
    }

    fn validate(&self, origin: &str) -> Result<(), ConfigError> {
        let invalid = |field: String, value: String, allowed: &str| ConfigError::Invalid {
            path: origin.to_string(),
            field,
            value,
            allowed: allowed.to_string(),
        };
        if self.schema_version != 1 {
            return Err(invalid(
                "schema_version".into(),
                self.schema_version.to_string(),
                "only schema version 1 exists",
            ));
        }
        if let Err(why) =
            crate::ranges::E_STAR_PIPELINE.check("material.e_star", self.material.e_star)
        {
            return Err(invalid(
                "material.e_star".into(),
                crate::ranges::show(self.material.e_star),
                why.split_once(": ").map_or(why.as_str(), |(_, w)| w),
            ));
        }
        let tol = self.solver.tolerance;
        if !(tol.is_finite() && tol > 0.0 && tol < 1.0) {
            return Err(invalid(
                "solver.tolerance".into(),
                tol.to_string(),
                "must lie in (0, 1); 1e-10 is a sensible value",
            ));
        }
        if self.solver.max_iterations == 0 {
            return Err(invalid(
                "solver.max_iterations".into(),
                "0".into(),
                "must be ≥ 1 (a few thousand is ample)",
            ));
        }
        // Names become directory and file names (data/<profile>/, figures/<profile>/,
        // campaigns, figure files): a plain word, so nothing lands outside --data or --figures.
        let groups = [
            ("profiles", self.profiles.keys().collect::<Vec<_>>()),
            ("studies", self.studies.keys().collect()),
            ("figures", self.figures.keys().collect()),
        ];
        for (group, names) in groups {
            for name in names {
                if !is_plain_name(name) {
                    return Err(invalid(
                        format!("{group}.{name}"),
                        format!("{name:?}"),
                        "a name is 1 to 64 letters, digits, '_', '-' or '.', starting with a letter or digit (it becomes a directory or file name)",
                    ));
                }
                if group == "profiles" && RESERVED_PROFILE_NAMES.contains(&name.as_str()) {
                    return Err(invalid(
                        format!("profiles.{name}"),
                        format!("{name:?}"),
                        &format!(
                            "the data directory already uses {} for itself; rename the profile",
                            RESERVED_PROFILE_NAMES.join(", ")
                        ),
                    ));
                }
            }
        }
        if self.profiles.is_empty() {
            return Err(invalid(
                "profiles".into(),
                "{}".into(),
                "declare at least one profile",
            ));
        }
        if self.studies.is_empty() {
            return Err(invalid(
                "studies".into(),
                "{}".into(),
                "declare at least one study",
            ));
        }
        for (name, study) in &self.studies {
            for profile in study.profiles.keys() {
                if !self.profiles.contains_key(profile) {
                    return Err(invalid(
                        format!("studies.{name}.profiles.{profile}"),
                        profile.clone(),
                        &format!(
                            "not a declared profile; declare it under `profiles` or use one of: {}",
                            self.profile_names().join(", ")
                        ),
                    ));
                }
            }
        }
        self.cluster.validate(origin)?;
        for (name, fig) in &self.figures {
            fig.validate(name, origin, &self.studies, &self.profiles)?;
        }
        figures::check_file_names(&self.figures, origin)?;
        self.check_measured_figures(origin)?;
        for (name, study) in &self.studies {
            for profile in study.profiles.keys() {
                self.resolve_study(name, profile, origin)?;
            }
        }
        Ok(())
    }

    /// Declared profile names, sorted.
    pub fn profile_names(&self) -> Vec<String> {
        self.profiles.keys().cloned().collect()
    }

    /// Every study of `profile`, resolved, in name order.
    pub fn plan(&self, profile: &str, origin: &str) -> Result<Vec<StudyPlan>, ConfigError> {
        if !self.profiles.contains_key(profile) {
            return Err(ConfigError::UnknownProfile {
                path: origin.to_string(),
                profile: profile.to_string(),
                known: self.profile_names().join(", "),
            });
        }
        self.studies
            .iter()
            .filter(|(_, s)| s.profiles.contains_key(profile))
            .map(|(name, _)| self.resolve_study(name, profile, origin))
            .collect()
    }

    fn resolve_study(
        &self,
        name: &str,
        profile: &str,
        origin: &str,
    ) -> Result<StudyPlan, ConfigError> {
        let study = &self.studies[name];
        let sp = &study.profiles[profile];
        let base = format!("studies.{name}");
        let pbase = format!("{base}.profiles.{profile}");
        if let Some(m) = &study.measured {
            return self.resolve_measured(name, profile, m, origin);
        }
        let (hurst, ratio) = sizes::checked_spectrum(study, &base, origin)?;
        let seed = sizes::required(study.seed, format!("{base}.seed"), origin)?;
        let method = Method::parse(&study.method).ok_or_else(|| ConfigError::Invalid {
            path: origin.to_string(),
            field: format!("{base}.method"),
            value: study.method.clone(),
            allowed: "must be `filter` or `random-phase`".into(),
        })?;
        let (n, res, realizations) =
            sizes::checked_grid_side(study, sp, ratio, &base, &pbase, origin)?;
        let (loads, sweep, keep_pressure) = self.resolve_study_loads(name, profile, origin)?;
        self.check_hardness(name, profile, &loads, origin)?;
        limits::check_realizations(&pbase, realizations, loads.len(), profile, origin)?;
        let lambda_s_px = res;
        let lambda_l_px = res * ratio;
        let surface = SurfaceParams {
            n,
            hurst,
            lambda_l_px,
            lambda_s_px,
            rolloff_lambda_px: study.rolloff_over_lambda_l.map(|r| r * lambda_l_px),
            method,
            seed,
        };
        surface.validate().map_err(|e| ConfigError::Invalid {
            path: origin.to_string(),
            field: format!("{pbase} (surface {})", e.field),
            value: e.value,
            allowed: e.allowed,
        })?;
        Ok(StudyPlan {
            name: name.to_string(),
            profile: profile.to_string(),
            realizations,
            seed,
            surface,
            loads,
            keep_pressure,
            sweep,
            e_star: self.material.e_star,
            tolerance: sp.tolerance.unwrap_or(self.solver.tolerance),
            max_iterations: self.solver.max_iterations,
            // `.inf` is elastic contact, as if left out.
            hardness: study.hardness.filter(|h| *h != f64::INFINITY),
            measured: None,
        })
    }
}

impl Pipeline {
    /// The figures of `profile`, in name order.
    pub fn figures_of(&self, profile: &str) -> Vec<(&str, &FigureDecl)> {
        self.figures
            .iter()
            .filter(|(_, f)| f.profiles.iter().any(|p| p == profile))
            .map(|(n, f)| (n.as_str(), f))
            .collect()
    }

    /// The loads a study computes in `profile`: its own sweep, or its own values joined by
    /// the loads its figures ask for; whether they are a sweep; and the indices of the loads
    /// whose pressure a figure draws.
    fn resolve_study_loads(
        &self,
        name: &str,
        profile: &str,
        origin: &str,
    ) -> Result<(Vec<f64>, bool, Vec<usize>), ConfigError> {
        let study = &self.studies[name];
        let base = format!("studies.{name}");
        let (own, field) = match (&study.profiles[profile].loads, &study.loads) {
            (Some(l), _) => (Some(l), format!("{base}.profiles.{profile}.loads")),
            (None, Some(l)) => (Some(l), format!("{base}.loads")),
            (None, None) => (None, format!("{base}.loads")),
        };
        let sweep = own.is_some_and(|l| l.values.is_none());
        let mut loads = match own {
            Some(l) => resolve_loads(l, &field, origin)?,
            None => Vec::new(),
        };
        let figures = self.figures_of(profile);
        let asked: Vec<(&str, f64)> = figures
            .iter()
            .filter(|(_, f)| f.uses(name, profile))
            .flat_map(|(fname, f)| f.loads_for(name).into_iter().map(move |w| (*fname, w)))
            .collect();
        let invalid = |field: String, value: f64, allowed: String| ConfigError::Invalid {
            path: origin.to_string(),
            field,
            value: value.to_string(),
            allowed,
        };
        if sweep {
            let (lo, hi) = (loads[0], loads[loads.len() - 1]);
            for &(fname, w) in &asked {
                if !(w >= lo * (1.0 - 1e-9) && w <= hi * (1.0 + 1e-9)) {
                    return Err(invalid(
                        format!("figures.{fname}.loads"),
                        w,
                        format!("draws study '{name}', whose sweep in profile '{profile}' spans [{lo}, {hi}] ({field}): the load must lie within it"),
                    ));
                }
            }
        } else {
            for &(_, w) in &asked {
                if !loads.contains(&w) {
                    loads.push(w);
                }
            }
            loads.sort_by(f64::total_cmp);
        }
        if loads.is_empty() {
            return Err(invalid(
                field,
                f64::NAN,
                format!("study '{name}' has no loads in profile '{profile}': give it `loads`, or draw it in a figure that lists the loads it needs"),
            ));
        }
        let mut keep_pressure: Vec<usize> = figures
            .iter()
            .filter(|(_, f)| f.kind == FigureKind::Fig2 && f.uses(name, profile))
            .flat_map(|(_, f)| f.loads.iter())
            .map(|&w| crate::statistics::nearest_in_log(&loads, w).expect("loads are positive"))
            .collect();
        keep_pressure.sort_unstable();
        keep_pressure.dedup();
        Ok((loads, sweep, keep_pressure))
    }
}

fn resolve_loads(loads: &Loads, field: &str, origin: &str) -> Result<Vec<f64>, ConfigError> {
    let invalid = |sub: &str, value: String, allowed: &str| ConfigError::Invalid {
        path: origin.to_string(),
        field: format!("{field}{sub}"),
        value,
        allowed: allowed.to_string(),
    };
    let values = match (&loads.values, loads.min, loads.max, loads.count) {
        (Some(v), None, None, None) => {
            if loads.spacing.is_some() {
                return Err(invalid(
                    ".spacing",
                    loads.spacing.clone().unwrap_or_default(),
                    "only applies to min/max/count ranges",
                ));
            }
            v.clone()
        }
        (None, Some(min), Some(max), Some(count)) => {
            if !(min.is_finite() && min > 0.0) {
                return Err(invalid(
                    ".min",
                    min.to_string(),
                    "W/W0 must be finite and > 0",
                ));
            }
            if !(max.is_finite() && max > min) {
                return Err(invalid(
                    ".max",
                    max.to_string(),
                    &format!("must be finite and > min = {min}"),
                ));
            }
            if count < 2 {
                return Err(invalid(
                    ".count",
                    count.to_string(),
                    "a range needs at least 2 loads",
                ));
            }
            limits::check_load_count(count, field, origin)?;
            let spacing = loads.spacing.as_deref().unwrap_or("log");
            let m = (count - 1) as f64;
            match spacing {
                "log" => (0..count)
                    .map(|i| {
                        if i == 0 {
                            min
                        } else if i == count - 1 {
                            max
                        } else {
                            (min.ln() + (max.ln() - min.ln()) * i as f64 / m).exp()
                        }
                    })
                    .collect(),
                "linear" => (0..count)
                    .map(|i| {
                        if i == count - 1 {
                            max
                        } else {
                            min + (max - min) * i as f64 / m
                        }
                    })
                    .collect(),
                other => {
                    return Err(invalid(
                        ".spacing",
                        other.to_string(),
                        "must be `log` or `linear`",
                    ))
                }
            }
        }
        _ => return Err(invalid(
            "",
            "(incomplete)".into(),
            "give either `values: [..]` or all of `min`, `max`, `count` (and optionally `spacing`)",
        )),
    };
    if values.is_empty() {
        return Err(invalid(".values", "[]".into(), "give at least one load"));
    }
    for (i, &w) in values.iter().enumerate() {
        if !(w.is_finite() && w > 0.0 && w <= MAX_W_OVER_W0) {
            let field = match (&loads.values, i) {
                (Some(_), _) => format!(".values[{i}]"),
                (None, 0) => ".min".to_string(),
                (None, _) => ".max".to_string(),
            };
            return Err(invalid(
                &field,
                w.to_string(),
                &format!("every load W/W0 must be finite and in (0, {MAX_W_OVER_W0}] (contact is complete well before W/W0 = 10)"),
            ));
        }
        if i > 0 && w <= values[i - 1] {
            return Err(invalid(
                &format!(".values[{i}]"),
                w.to_string(),
                &format!(
                    "loads must be strictly increasing (previous value {})",
                    values[i - 1]
                ),
            ));
        }
    }
    Ok(values)
}
