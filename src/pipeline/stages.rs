//! Stage definitions: which instances a profile needs, their parameters (only those the
//! stage reads), and how each is computed into a temporary entry directory.

use std::path::Path;

use serde_json::{json, Value};

use super::hash::instance_key;
use crate::config::StudyPlan;
use crate::spectral::Fft2;
use crate::surface::{self, SurfaceParams};

/// Stages in dependency order.
pub const STAGES: &[&str] = &["surface"];

/// Version of the surface stage; bump when its algorithm or outputs change.
pub const SURFACE_VERSION: u32 = 1;

/// What an instance computes.
#[derive(Debug, Clone)]
pub enum Job {
    Surface(SurfaceParams),
}

/// One stage instance of a profile.
#[derive(Debug, Clone)]
pub struct Instance {
    pub stage: &'static str,
    pub version: u32,
    pub params: Value,
    pub inputs: Vec<String>,
    pub key: String,
    /// Studies of the profile that use this instance (several studies may share one).
    pub studies: Vec<String>,
    pub realization: Option<u32>,
    pub job: Job,
}

/// Parameters the surface stage reads, as they enter its key.
pub fn surface_params_json(p: &SurfaceParams) -> Value {
    json!({
        "n": p.n,
        "hurst": p.hurst,
        "lambda_l_px": p.lambda_l_px,
        "lambda_s_px": p.lambda_s_px,
        "rolloff_lambda_px": p.rolloff_lambda_px,
        "method": p.method.as_str(),
        "seed": p.seed,
    })
}

/// Every instance the given studies need, deduplicated by key, in stage order.
pub fn instances(plans: &[StudyPlan]) -> Vec<Instance> {
    let mut out: Vec<Instance> = Vec::new();
    for plan in plans {
        for r in 0..plan.realizations {
            let params = plan.surface_for(r);
            let params_json = surface_params_json(&params);
            let key = instance_key("surface", SURFACE_VERSION, &params_json, &[]);
            if let Some(existing) = out.iter_mut().find(|i| i.key == key) {
                if !existing.studies.contains(&plan.name) {
                    existing.studies.push(plan.name.clone());
                }
                continue;
            }
            out.push(Instance {
                stage: "surface",
                version: SURFACE_VERSION,
                params: params_json,
                inputs: Vec::new(),
                key,
                studies: vec![plan.name.clone()],
                realization: Some(r),
                job: Job::Surface(params),
            });
        }
    }
    out
}

/// Compute an instance into `dir`; returns the stage's results for the manifest.
pub fn compute(instance: &Instance, dir: &Path) -> anyhow::Result<Value> {
    match &instance.job {
        Job::Surface(params) => compute_surface(params, dir),
    }
}

fn compute_surface(params: &SurfaceParams, dir: &Path) -> anyhow::Result<Value> {
    let fft = Fft2::new(params.n);
    let mut scratch = fft.make_scratch();
    let s = surface::generate(params, &fft, &mut scratch)?;
    crate::io::write_heights(&dir.join("heights.npy"), s.grid.n(), s.heights)?;
    Ok(json!({
        "mean_height": s.stats.mean_height,
        "rms_height": s.stats.rms_height,
        "rms_slope": s.stats.rms_slope,
        "hurst_fit": s.stats.hurst_fit,
        "box_size": 1.0,
        "grid_spacing": s.grid.spacing(),
    }))
}
