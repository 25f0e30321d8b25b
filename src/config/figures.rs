//! The `figures:` block of `pipeline.yaml`: which studies and loads each figure draws, and in
//! which profiles. A figure names its studies explicitly (no name prefixes), and a study
//! that a figure draws must belong to each of the figure's profiles (or be listed under the
//! figure's `omit` for that profile): a renamed or missing study is a configuration error,
//! never a silently missing curve.

use std::collections::BTreeMap;

use serde::Deserialize;

use super::error::ConfigError;
use super::study::Study;

/// What a figure declaration draws (each kind is one figure family of the paper, or one of
/// the project's audits drawn as a figure).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FigureKind {
    /// Fig. 6: model curves K_PL, 𝒦_PL against A_m/A_s; no study.
    Fig6,
    /// Figs. 2a–d (surface and contact maps of realization 0 at `maps`) and 2e–f (A_c,
    /// largest cluster, dN/dA_c over the sweep), with the realization-convergence audit of
    /// 2e–f; `study`.
    Fig2,
    /// Fig. 3 (area PDF at `loads`, inset: `hurst` studies at `inset_load`) and Fig. 4a
    /// (CCDF); `ratios`, `hurst`.
    Fig3Fig4a,
    /// Figs. 4b, 5a, 5b (K, 𝒦, wear rate over the sweep); `study`.
    Fig45,
    /// Fig. B.1 (box size L/λ_l varies) with its convergence audit; `studies`.
    AppendixB1,
    /// Fig. B.2 (discretisation λ_s/Δl varies) with its convergence audit; `studies`.
    AppendixB2,
    /// Convergence of grid sizes against the largest grid (the last study is the
    /// reference); `studies`.
    Convergence,
    /// Load resolution of a sweep (`chosen`) against a finer sweep of the same realizations
    /// (`fine`).
    LoadResolution,
    /// Not in the paper: the same surfaces under several hardnesses (`studies`, an elastic
    /// one among them or not): α̂ against 1/𝓗 at `loads`, and K, 𝒦 and the saturated
    /// fraction over the sweep for each 𝓗.
    Plastic,
    /// Not in the paper: the same statistics for spectra of several widths λ_l/λ_s
    /// (`studies`): α̂ at `loads`, K and 𝒦 at the end of the mild-wear range with the fitted
    /// model, the power-law interval's upper end, the end of the nucleation regime, and K at
    /// fixed A*/λ_l².
    Spectrum,
}

impl FigureKind {
    /// The kind's name in `pipeline.yaml`.
    pub fn name(self) -> &'static str {
        use FigureKind::*;
        match self {
            Fig6 => "fig6",
            Fig2 => "fig2",
            Fig3Fig4a => "fig3_fig4a",
            Fig45 => "fig45",
            AppendixB1 => "appendix_b1",
            AppendixB2 => "appendix_b2",
            Convergence => "convergence",
            LoadResolution => "load_resolution",
            Plastic => "plastic",
            Spectrum => "spectrum",
        }
    }
}

/// The loads at which a figure shows a study's α̂ with its interval
/// ([`FigureDecl::exponent_loads`]).
#[derive(Debug, Clone, PartialEq)]
pub enum ExponentLoads {
    Nowhere,
    /// The loads of the study's sweep nearest (in ln W) to these W/W0.
    Nearest(Vec<f64>),
    /// The loads nearest to those of the figure's study with the fewest loads.
    OfSparsestStudy,
}

/// One entry of the `figures:` block.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FigureDecl {
    pub kind: FigureKind,
    #[serde(default)]
    pub description: String,
    /// Profiles whose gallery holds this figure.
    pub profiles: Vec<String>,
    /// Profile → studies of this figure left out of that profile.
    #[serde(default)]
    pub omit: BTreeMap<String, Vec<String>>,
    /// The study (fig2, fig45).
    #[serde(default)]
    pub study: Option<String>,
    /// The studies compared (appendix_b1, appendix_b2, convergence), in drawing order.
    #[serde(default)]
    pub studies: Vec<String>,
    /// fig3_fig4a: the main panel's studies (λ_l/λ_s varies) and the inset's (H varies).
    #[serde(default)]
    pub ratios: Vec<String>,
    #[serde(default)]
    pub hurst: Vec<String>,
    /// Loads W/W0 the figure draws (fig2: the maps; fig3_fig4a: the PDFs and CCDFs;
    /// appendix: every setting's; plastic: α̂ against 𝓗). A study whose own loads are a sweep (`min/max/count`)
    /// gives its nearest load (in ln W); otherwise the study computes exactly these.
    #[serde(default)]
    pub loads: Vec<f64>,
    /// fig3_fig4a: the load of the inset.
    #[serde(default)]
    pub inset_load: Option<f64>,
    /// load_resolution: the sweep judged and the reference sweep.
    #[serde(default)]
    pub chosen: Option<String>,
    #[serde(default)]
    pub fine: Option<String>,
}

impl FigureDecl {
    /// Every study the declaration names, in declaration order (deduplicated).
    pub fn studies_named(&self) -> Vec<&str> {
        let mut out: Vec<&str> = Vec::new();
        let all = self
            .study
            .iter()
            .chain(&self.studies)
            .chain(&self.ratios)
            .chain(&self.hurst)
            .chain(&self.chosen)
            .chain(&self.fine);
        for s in all {
            if !out.contains(&s.as_str()) {
                out.push(s);
            }
        }
        out
    }

    /// Whether the figure uses `study` in `profile`.
    pub fn uses(&self, study: &str, profile: &str) -> bool {
        self.profiles.iter().any(|p| p == profile)
            && self.studies_named().contains(&study)
            && !self
                .omit
                .get(profile)
                .is_some_and(|o| o.iter().any(|s| s == study))
    }

    /// The studies of `list` used in `profile`, in order.
    pub fn used<'a>(&self, list: &'a [String], profile: &str) -> Vec<&'a str> {
        list.iter()
            .map(String::as_str)
            .filter(|s| self.uses(s, profile))
            .collect()
    }

    /// The loads this figure asks of `study` (W/W0; empty: the study's own).
    pub fn loads_for(&self, study: &str) -> Vec<f64> {
        let mut out = Vec::new();
        match self.kind {
            FigureKind::Fig3Fig4a => {
                if self.ratios.iter().any(|s| s == study) {
                    out.extend(&self.loads);
                }
                if self.hurst.iter().any(|s| s == study) {
                    out.extend(self.inset_load);
                }
            }
            FigureKind::Fig2 | FigureKind::AppendixB1 | FigureKind::AppendixB2 => {
                out.extend(&self.loads)
            }
            _ => {}
        }
        out
    }

    /// Where this figure (or its report section) shows `study`'s α̂ with its interval: the
    /// loads whose intervals and tail tests the statistics stage must compute.
    pub fn exponent_loads(&self, study: &str) -> ExponentLoads {
        use FigureKind::*;
        match self.kind {
            // Fig. 2 and Figs. 4b–5 draw no exponent; the model fits of Figs. 4b–5 use the
            // point estimates, computed at every load regardless.
            Fig6 | Fig2 | Fig45 | LoadResolution => ExponentLoads::Nowhere,
            Fig3Fig4a => ExponentLoads::Nearest(self.loads_for(study)),
            Plastic | Spectrum | AppendixB1 | AppendixB2 => {
                ExponentLoads::Nearest(self.loads.clone())
            }
            // A convergence figure's report compares its settings at the loads of the one
            // with the fewest.
            Convergence => ExponentLoads::OfSparsestStudy,
        }
    }

    /// Check the declaration's fields against its kind and the declared studies and
    /// profiles.
    pub(super) fn validate(
        &self,
        name: &str,
        origin: &str,
        studies: &BTreeMap<String, Study>,
        profiles: &BTreeMap<String, String>,
    ) -> Result<(), ConfigError> {
        self.check_fields(name, origin)?;
        self.check_loads(name, origin)?;
        self.check_profiles(name, origin, studies, profiles)?;
        self.check_lists(name, origin)
    }

    /// The fields its kind requires are given, and no other.
    fn check_fields(&self, name: &str, origin: &str) -> Result<(), ConfigError> {
        let invalid = |field: &str, value: String, allowed: String| {
            invalid_field(origin, name, field, value, allowed)
        };
        use FigureKind::*;
        let (study, list, fig3, pair) = match self.kind {
            Fig6 => (false, false, false, false),
            Fig2 | Fig45 => (true, false, false, false),
            AppendixB1 | AppendixB2 | Convergence | Plastic | Spectrum => {
                (false, true, false, false)
            }
            Fig3Fig4a => (false, false, true, false),
            LoadResolution => (false, false, false, true),
        };
        let fields = [
            (".study", self.study.is_some(), study),
            (".studies", !self.studies.is_empty(), list),
            (".ratios", !self.ratios.is_empty(), fig3),
            (".hurst", !self.hurst.is_empty(), false),
            (".inset_load", self.inset_load.is_some(), fig3),
            (".chosen", self.chosen.is_some(), pair),
            (".fine", self.fine.is_some(), pair),
        ];
        for (field, given, required) in fields {
            let allowed_here = required || (field == ".hurst" && fig3);
            if given && !allowed_here {
                return Err(invalid(
                    field,
                    "(given)".into(),
                    format!(
                        "a figure of kind {} takes no {}",
                        self.kind.name(),
                        &field[1..]
                    ),
                ));
            }
            if required && !given {
                return Err(invalid(
                    field,
                    "(missing)".into(),
                    format!(
                        "a figure of kind {} needs {}",
                        self.kind.name(),
                        &field[1..]
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The kinds that draw chosen loads list them, the others none; each in (0, max].
    fn check_loads(&self, name: &str, origin: &str) -> Result<(), ConfigError> {
        use FigureKind::*;
        let invalid = |field: &str, value: String, allowed: String| {
            invalid_field(origin, name, field, value, allowed)
        };
        let wants_loads = matches!(
            self.kind,
            Fig2 | Fig3Fig4a | AppendixB1 | AppendixB2 | Plastic | Spectrum
        );
        if wants_loads && self.loads.is_empty() {
            return Err(invalid(
                ".loads",
                "[]".into(),
                "list the loads W/W0 this figure draws".into(),
            ));
        }
        if !wants_loads && !self.loads.is_empty() {
            return Err(invalid(
                ".loads",
                format!("{:?}", self.loads),
                format!(
                    "a figure of kind {} draws its studies' own loads",
                    self.kind.name()
                ),
            ));
        }
        for (i, &w) in self.loads.iter().chain(&self.inset_load).enumerate() {
            if !(w.is_finite() && w > 0.0 && w <= crate::contact::sweep::MAX_W_OVER_W0) {
                return Err(invalid(
                    &format!(".loads[{i}]"),
                    w.to_string(),
                    format!(
                        "loads W/W0 must be finite and in (0, {}]",
                        crate::contact::sweep::MAX_W_OVER_W0
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Its profiles are declared, and every study it draws in one has an entry for it.
    fn check_profiles(
        &self,
        name: &str,
        origin: &str,
        studies: &BTreeMap<String, Study>,
        profiles: &BTreeMap<String, String>,
    ) -> Result<(), ConfigError> {
        let invalid = |field: &str, value: String, allowed: String| {
            invalid_field(origin, name, field, value, allowed)
        };
        if self.profiles.is_empty() {
            return Err(invalid(
                ".profiles",
                "[]".into(),
                "list the profiles whose gallery holds this figure".into(),
            ));
        }
        for p in self.profiles.iter().chain(self.omit.keys()) {
            if !profiles.contains_key(p) {
                return Err(invalid(
                    ".profiles",
                    p.clone(),
                    format!(
                        "not a declared profile; use one of: {}",
                        profiles.keys().cloned().collect::<Vec<_>>().join(", ")
                    ),
                ));
            }
        }
        for s in self.studies_named() {
            let Some(decl) = studies.get(s) else {
                return Err(invalid(
                    "",
                    s.to_string(),
                    format!(
                        "names study '{s}', which is not declared under `studies`; declare it or correct the name"
                    ),
                ));
            };
            for p in &self.profiles {
                if self.uses(s, p) && !decl.profiles.contains_key(p) {
                    return Err(invalid(
                        ".profiles",
                        p.clone(),
                        format!(
                            "draws study '{s}', which has no entry for profile '{p}': add studies.{s}.profiles.{p}, or list '{s}' under figures.{name}.omit.{p}"
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// No study or profile listed twice, a comparison of two different studies, omissions of
    /// studies it names, and enough studies left in each profile for its kind.
    fn check_lists(&self, name: &str, origin: &str) -> Result<(), ConfigError> {
        use FigureKind::*;
        let invalid = |field: &str, value: String, allowed: String| {
            invalid_field(origin, name, field, value, allowed)
        };
        for (field, list) in [
            (".studies", &self.studies),
            (".ratios", &self.ratios),
            (".hurst", &self.hurst),
            (".profiles", &self.profiles),
        ] {
            if let Some((i, s)) = list
                .iter()
                .enumerate()
                .find(|(i, s)| list[..*i].contains(s))
            {
                return Err(invalid(
                    &format!("{field}[{i}]"),
                    s.clone(),
                    "is listed twice; list each once".into(),
                ));
            }
        }
        if self.chosen.is_some() && self.chosen == self.fine {
            return Err(invalid(
                ".fine",
                self.fine.clone().unwrap_or_default(),
                "is also the chosen sweep; compare two different studies".into(),
            ));
        }
        for (p, omitted) in &self.omit {
            for s in omitted {
                if !self.studies_named().contains(&s.as_str()) {
                    return Err(invalid(
                        &format!(".omit.{p}"),
                        s.clone(),
                        "omits a study this figure does not name".into(),
                    ));
                }
            }
        }
        let min_used = match self.kind {
            Convergence | LoadResolution | Spectrum => 2,
            Fig6 => 0,
            _ => 1,
        };
        for p in &self.profiles {
            let used = self
                .studies_named()
                .into_iter()
                .filter(|s| self.uses(s, p))
                .count();
            if used < min_used {
                return Err(invalid(
                    ".omit",
                    p.clone(),
                    format!("leaves {used} studies in profile '{p}'; this kind needs {min_used}"),
                ));
            }
        }
        Ok(())
    }
}

/// The error for field `figures.<name><field>` of `origin`: its value and what is allowed.
fn invalid_field(
    origin: &str,
    name: &str,
    field: &str,
    value: String,
    allowed: String,
) -> ConfigError {
    ConfigError::Invalid {
        path: origin.to_string(),
        field: format!("figures.{name}{field}"),
        value,
        allowed,
    }
}

/// The stems of the files a figure writes (`<stem>.png`, `.svg`, `.csv`, …): fixed by its
/// kind, or its own name for the kinds named after the figure.
pub fn file_stems(name: &str, kind: FigureKind) -> Vec<String> {
    use FigureKind::*;
    let fixed: &[&str] = match kind {
        Fig6 => &["fig6"],
        Fig2 => &[
            "fig2a",
            "fig2b",
            "fig2c",
            "fig2d",
            "fig2e",
            "fig2f",
            "fig2_convergence",
        ],
        Fig3Fig4a => &["fig3", "fig4a"],
        Fig45 => &["fig4b", "fig5a", "fig5b", "fig45_dn_dac"],
        Plastic => &[
            "plastic_alpha",
            "plastic_k",
            "plastic_k_upscaled",
            "plastic_saturated",
        ],
        Spectrum => &[
            "spectrum_alpha",
            "spectrum_k",
            "spectrum_k_upscaled",
            "spectrum_interval",
            "spectrum_transition",
            "spectrum_k_physical",
        ],
        AppendixB1 | AppendixB2 | Convergence | LoadResolution => {
            return vec![name.to_string(), format!("{name}_convergence")]
        }
    };
    fixed.iter().map(|s| s.to_string()).collect()
}

/// No two figures of a profile write a file of the same name (two fig6 figures, or a
/// convergence figure called `fig4b` beside a fig45 figure).
pub(super) fn check_file_names(
    figures: &BTreeMap<String, FigureDecl>,
    origin: &str,
) -> Result<(), ConfigError> {
    let mut seen: BTreeMap<(String, String), &str> = BTreeMap::new();
    for (name, fig) in figures {
        for p in &fig.profiles {
            for stem in file_stems(name, fig.kind) {
                if let Some(other) = seen.insert((p.clone(), stem.clone()), name) {
                    return Err(ConfigError::Invalid {
                        path: origin.to_string(),
                        field: format!("figures.{name}"),
                        value: fig.kind.name().to_string(),
                        allowed: format!(
                            "figure '{other}' of profile '{p}' also writes {stem}.*: the same files; a profile holds one figure of each of the kinds fig2, fig3_fig4a, fig45, fig6, plastic, spectrum, and other figures are named so that their files differ"
                        ),
                    });
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::FigureKind::{self, *};

    #[test]
    fn each_kind_is_named_as_pipeline_yaml_spells_it() {
        for kind in [
            Fig6,
            Fig2,
            Fig3Fig4a,
            Fig45,
            AppendixB1,
            AppendixB2,
            Convergence,
            LoadResolution,
            Plastic,
            Spectrum,
        ] {
            let parsed: FigureKind = serde_saphyr::from_str(kind.name()).unwrap();
            assert_eq!(parsed, kind);
        }
    }
}
