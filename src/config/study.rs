//! A study as the pipeline file declares it and as a profile resolves it, and the names and
//! sizes every study obeys.

use std::collections::BTreeMap;

use serde::Deserialize;

use crate::surface::SurfaceParams;

/// A study: one set of surface parameters, a number of realizations and a load range, with
/// per-profile sizes.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Study {
    #[serde(default)]
    pub description: String,
    /// A measured study: topography files as its realizations, instead of a generated
    /// spectrum (then `hurst`, `lambda_l_over_lambda_s`, `seed`, `rolloff_over_lambda_l`
    /// and `method` are not given, nor the profiles' sizes).
    #[serde(default)]
    pub measured: Option<MeasuredStudy>,
    /// Hurst exponent H ∈ (0, 1) (a generated study).
    #[serde(default)]
    pub hurst: Option<f64>,
    /// Spectrum bandwidth λ_l/λ_s (a generated study).
    #[serde(default)]
    pub lambda_l_over_lambda_s: Option<f64>,
    /// Optional roll-off plateau: λ_r/λ_l > 1 (flat PSD between q_r and q_l).
    #[serde(default)]
    pub rolloff_over_lambda_l: Option<f64>,
    /// Surface generator: `filter` (default) or `random-phase`.
    #[serde(default = "default_method")]
    pub method: String,
    /// Study seed; realization i uses `surface::realization_seed(seed, i)` (a generated
    /// study).
    #[serde(default)]
    pub seed: Option<u64>,
    /// Loads W/W0 of the study's own, shared by all profiles unless a profile overrides
    /// them. A sweep (`min/max/count`) gives the figures that draw the study their nearest
    /// loads; listed values are joined by the loads the study's figures ask for. Without
    /// loads of its own, a study computes exactly what its figures ask for.
    #[serde(default)]
    pub loads: Option<Loads>,
    /// Perfectly plastic interface: the hardness 𝓗 at which the contact pressure saturates,
    /// in units of E*·h'_rms (the units of W/W0, so p̄/𝓗 = (W/W0)/hardness); every load must
    /// be ≤ it. Absent: elastic contact (and the elastic studies' store keys).
    #[serde(default)]
    pub hardness: Option<f64>,
    /// Profile name → sizes for that profile. A study without an entry for a profile is not
    /// part of that profile.
    pub profiles: BTreeMap<String, StudyProfile>,
}

fn default_method() -> String {
    "filter".to_string()
}

/// The files of a measured study and how they are prepared.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeasuredStudy {
    /// Topography files, one realization each, relative to the pipeline file's directory;
    /// all of one shape and pixel size. Keyed by content: moving a file keeps its results.
    pub files: Vec<String>,
    /// The unit of cluster areas λ_s, in pixels of the files (areas are also given per
    /// λ_s², and the thresholds A*/λ_s² are in it): `wearcoef topography FILE --json`
    /// reports the fitted one.
    pub lambda_s_over_dl: f64,
    /// Units where the files state none, form removed, missing points (defaults: the
    /// files' units, `form: plane`, `fill: none`).
    #[serde(default = "default_preparation")]
    pub preparation: crate::io::prepare::Preparation,
}

fn default_preparation() -> crate::io::prepare::Preparation {
    serde_json::from_value(serde_json::json!({})).expect("every preparation field has a default")
}

/// Per-profile sizes of a study.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyProfile {
    /// Box size over largest wavelength, L/λ_l (a generated study).
    #[serde(default)]
    pub l_over_lambda_l: Option<f64>,
    /// Resolution of the smallest wavelength, λ_s/Δl ≥ 2 (a generated study).
    #[serde(default)]
    pub lambda_s_over_dl: Option<f64>,
    /// Number of independent surface realizations ≥ 1 (a generated study; a measured one
    /// has one per file).
    #[serde(default)]
    pub realizations: Option<u32>,
    /// Loads for this profile, replacing the study's.
    #[serde(default)]
    pub loads: Option<Loads>,
    /// Solver tolerance for this profile, replacing `solver.tolerance`.
    #[serde(default)]
    pub tolerance: Option<f64>,
}

/// Loads W/W0 (dimensionless, W0 = E*·rms slope·L²), either listed or as a range.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Loads {
    /// Explicit increasing list.
    #[serde(default)]
    pub values: Option<Vec<f64>>,
    #[serde(default)]
    pub min: Option<f64>,
    #[serde(default)]
    pub max: Option<f64>,
    #[serde(default)]
    pub count: Option<u32>,
    /// `log` (default) or `linear`.
    #[serde(default)]
    pub spacing: Option<String>,
}

/// A study resolved for one profile: concrete grid sizes and loads.
#[derive(Debug, Clone, PartialEq)]
pub struct StudyPlan {
    pub name: String,
    pub profile: String,
    pub realizations: u32,
    pub seed: u64,
    /// Surface parameters of realization 0 (the seed is set per realization).
    pub surface: SurfaceParams,
    /// W/W0, strictly increasing.
    pub loads: Vec<f64>,
    /// Indices into `loads` whose pressure fields are stored (the maps a figure draws).
    pub keep_pressure: Vec<usize>,
    /// Whether `loads` is the study's own sweep (figures take their nearest loads from it).
    pub sweep: bool,
    /// Effective modulus E*.
    pub e_star: f64,
    /// Solver tolerance and iteration cap.
    pub tolerance: f64,
    pub max_iterations: u32,
    /// The hardness (units of W/W0), if the contact is perfectly plastic.
    pub hardness: Option<f64>,
    /// A measured study's files and preparation (then `surface` holds only
    /// `lambda_s_px`, and `n` is 0).
    pub measured: Option<MeasuredPlan>,
}

/// A measured study resolved: its files (relative to the working directory) and their
/// preparation.
#[derive(Debug, Clone, PartialEq)]
pub struct MeasuredPlan {
    pub files: Vec<std::path::PathBuf>,
    /// The fields of pipeline.yaml that name the files, in order (for messages).
    pub fields: Vec<String>,
    pub preparation: crate::io::prepare::Preparation,
}

impl StudyPlan {
    /// Surface parameters of realization `index`.
    pub fn surface_for(&self, index: u32) -> SurfaceParams {
        SurfaceParams {
            seed: crate::surface::realization_seed(self.seed, index as u64),
            ..self.surface.clone()
        }
    }
}

/// Directory names the store keeps for itself beside `data/<profile>/`.
pub const RESERVED_PROFILE_NAMES: [&str; 3] = ["cache", "failed", "campaigns"];

/// A profile, study or figure name: 1–64 ASCII letters, digits, `_`, `-` or `.`, starting
/// with a letter or digit (so never `.`, `..` or a hidden file).
pub fn is_plain_name(name: &str) -> bool {
    (1..=64).contains(&name.len())
        && name.starts_with(|c: char| c.is_ascii_alphanumeric())
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'))
}

/// Largest grid side accepted (memory guard: 65536² doubles are 32 GiB).
pub const MAX_N: usize = 32768;
