//! The report's context: the sizes of the studies it describes (the profile's beside the
//! paper's), and the HTML escaping its pages use.

use std::collections::BTreeMap;

use crate::config::{FigureKind, Pipeline, StudyPlan};
use crate::format::number;

/// A study's sizes as the report's parameter table shows them.
#[derive(Debug, Clone, PartialEq)]
pub struct Sizes {
    pub hurst: f64,
    pub lambda_l_over_lambda_s: f64,
    pub l_over_lambda_l: f64,
    pub lambda_s_over_dl: f64,
    pub n: usize,
    pub realizations: u32,
    /// W/W₀ of the sweep, increasing.
    pub loads: Vec<f64>,
    pub tolerance: f64,
    /// Loads whose pressure field is kept (the maps of Fig. 2b–d), as W/W₀.
    pub kept_loads: Vec<f64>,
    /// A measured study (no spectrum, box or grid side: its files set them).
    pub measured: bool,
}

impl Sizes {
    pub fn of(p: &StudyPlan) -> Self {
        let s = &p.surface;
        Sizes {
            hurst: s.hurst,
            lambda_l_over_lambda_s: s.lambda_l_px / s.lambda_s_px,
            l_over_lambda_l: s.n as f64 / s.lambda_l_px,
            lambda_s_over_dl: s.lambda_s_px,
            n: s.n,
            realizations: p.realizations,
            loads: p.loads.clone(),
            tolerance: p.tolerance,
            kept_loads: p.keep_pressure.iter().map(|&i| p.loads[i]).collect(),
            measured: p.measured.is_some(),
        }
    }

    pub(super) fn loads_text(&self) -> String {
        match (self.loads.first(), self.loads.last()) {
            (Some(a), Some(b)) if self.loads.len() > 3 => {
                format!("{} in {}–{}", self.loads.len(), number(*a), number(*b))
            }
            _ => self
                .loads
                .iter()
                .map(|w| number(*w))
                .collect::<Vec<_>>()
                .join(", "),
        }
    }
}

/// What the report knows of the pipeline beside the store: each figure's description, kind
/// and declared loads, and the sizes of every study in this profile and in the paper's.
#[derive(Debug, Default)]
pub struct Context {
    pub descriptions: BTreeMap<String, String>,
    pub kinds: BTreeMap<String, FigureKind>,
    /// The loads a figure declares it draws (with its inset's), empty for all of a sweep.
    pub figure_loads: BTreeMap<String, Vec<f64>>,
    pub sizes: BTreeMap<String, Sizes>,
    /// The same studies in profile `paper` (the paper's own parameters), where they are.
    pub paper: BTreeMap<String, Sizes>,
}

impl Context {
    /// The context of `profile` in `pipeline` (`origin` names the file in errors).
    pub fn of(pipeline: &Pipeline, origin: &str, profile: &str) -> anyhow::Result<Self> {
        let mut c = Context::default();
        for (name, decl) in pipeline.figures_of(profile) {
            c.descriptions
                .insert(name.to_string(), decl.description.clone());
            c.kinds.insert(name.to_string(), decl.kind);
            let mut loads = decl.loads.clone();
            loads.extend(decl.inset_load);
            c.figure_loads.insert(name.to_string(), loads);
        }
        let sizes = |p: &str| -> anyhow::Result<BTreeMap<String, Sizes>> {
            Ok(pipeline
                .plan(p, origin)?
                .iter()
                .map(|s| (s.name.clone(), Sizes::of(s)))
                .collect())
        };
        c.sizes = sizes(profile)?;
        if pipeline.profiles.contains_key("paper") {
            c.paper = sizes("paper")?;
        }
        Ok(c)
    }
}

/// Text with `&`, `<`, `>` and `"` escaped for HTML.
pub fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}
