//! What every scene shares: the drawing result, plotting errors, and the writer of a scene
//! to PNG and SVG.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::text;

pub(super) type DrawResult = anyhow::Result<()>;

pub(super) fn plot_err<E: std::fmt::Debug>(e: E) -> anyhow::Error {
    anyhow::anyhow!("plotting: {e:?}")
}

/// Something drawn on a drawing area of any backend.
pub(super) trait Scene {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult;
}

/// Render a scene to `<stem>.png` and `<stem>.svg` in `dir`.
pub(super) fn write_scene(
    dir: &Path,
    stem: &str,
    size: (u32, u32),
    scene: &impl Scene,
) -> DrawResult {
    text::ensure_font()?;
    let png = dir.join(format!("{stem}.png"));
    {
        let _raster = text::Glyphwise::on();
        let root = BitMapBackend::new(&png, size).into_drawing_area();
        root.fill(&WHITE).map_err(plot_err)?;
        scene.draw(&root)?;
        root.present().map_err(plot_err)?;
    }
    let svg = dir.join(format!("{stem}.svg"));
    {
        let root = SVGBackend::new(&svg, size).into_drawing_area();
        root.fill(&WHITE).map_err(plot_err)?;
        scene.draw(&root)?;
        root.present().map_err(plot_err)?;
    }
    Ok(())
}
