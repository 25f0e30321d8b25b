//! The surface stage: one self-affine random surface (`heights.npy`, unit rms slope, zero
//! mean) from its parameters and seed.

use std::path::Path;

use serde_json::{json, Value};

use super::{Inputs, Stage};
use crate::spectral::Fft2;
use crate::surface::{self, SurfaceParams};

pub struct Surface;

impl Stage for Surface {
    const NAME: &'static str = "surface";
    const VERSION: u32 = 1;
    type Job = SurfaceParams;

    fn compute(params: &SurfaceParams, _inputs: &Inputs, dir: &Path) -> anyhow::Result<Value> {
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
}
