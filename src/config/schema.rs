//! The pipeline file's top level: the file, its material and its solver settings.

use std::collections::BTreeMap;

use serde::Deserialize;

use super::cluster::ClusterConfig;
use super::figures::FigureDecl;
use super::study::Study;

/// The whole file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Pipeline {
    /// Schema version of this file; only 1 exists.
    pub schema_version: u32,
    pub material: Material,
    pub solver: Solver,
    /// Profile name → one-line description.
    pub profiles: BTreeMap<String, String>,
    /// Study name → study.
    pub studies: BTreeMap<String, Study>,
    /// Figure name → what it draws (see [`FigureDecl`]).
    #[serde(default)]
    pub figures: BTreeMap<String, FigureDecl>,
    /// How `wearcoef submit` sizes Slurm arrays (defaults when absent).
    #[serde(default)]
    pub cluster: ClusterConfig,
}

/// Elastic constants.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Effective modulus E* = E/(1 − ν²), the stress unit of every pressure written.
    pub e_star: f64,
}

/// Contact-solver settings shared by all studies.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Solver {
    /// Convergence threshold on the dimensionless error of docs/CONVENTIONS.md.
    pub tolerance: f64,
    /// Iteration cap; reaching it is an error, never a result.
    pub max_iterations: u32,
}
