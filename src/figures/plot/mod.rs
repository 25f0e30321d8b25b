//! Figures as PNG (150 dpi) and SVG with plotters, text in an embedded font (DejaVu Sans,
//! and DejaVu Math TeX Gyre for 𝒦; assets/fonts, Bitstream Vera licence) so no system font
//! package is needed. Labels are markup with sub- and superscripts ([`text`]); tick labels
//! are numbers with powers of ten as 10ⁿ; curves use Okabe & Ito's colour-blind-safe palette.
//!
//! Three kinds of scene: a line plot ([`LinePlot`], logarithmic, linear or linear-then-log
//! axes), several line plots side by side or one inset in another ([`Panels`]), and a raster
//! image with a colour bar or a colour legend ([`RasterPlot`]; the SVG embeds the same
//! raster as a PNG).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

mod legend;
mod line;
mod raster;
mod scene;
mod series;
mod style;
pub mod text;
mod ticks;
pub use legend::Fractions;
pub use raster::{viridis, ColorBar, RasterPlot, Rgb};
use scene::{plot_err, write_scene, DrawResult, Scene};
pub use series::{
    LegendAt, LinePlot, Series, YAxis, DATA_COLUMNS, INSET_SCALE, INSET_SIZE_PX, RASTER_SIZE_PX,
    SIZE_PX,
};
pub use style::{Dash, Marker};
pub use ticks::{interval_text, number, power_of_ten, snap_zero};

/// A value resting on fewer clusters than this is drawn hollow (and so is one whose 95 %
/// interval reaches 0).
pub use crate::statistics::TENTATIVE_BELOW_CLUSTERS;

/// Several line plots in one figure.
pub struct Panels {
    pub plots: Vec<LinePlot>,
    pub layout: Layout,
}

/// How [`Panels`] are arranged.
#[derive(Clone, Copy, Debug)]
pub enum Layout {
    /// Side by side in at most `columns` columns, each panel 640 × 560 px: as few rows as
    /// that allows, then as few columns as fill them (4 panels in 2 × 2, not 3 + 1).
    Grid { columns: usize },
    /// The second plot inset in the first, at fractions of the first one's axes, its text at
    /// [`INSET_SCALE`] of the first's, on a figure of [`INSET_SIZE_PX`].
    Inset { rect: Fractions },
}

/// (rows, columns) of `n` panels in at most `columns` columns: the fewest rows, then the
/// fewest columns that hold `n` in them, so that no row is left mostly empty.
pub fn grid(n: usize, columns: usize) -> (usize, usize) {
    let n = n.max(1);
    let rows = n.div_ceil(columns.clamp(1, n));
    (rows, n.div_ceil(rows))
}

impl Panels {
    /// Figure size in pixels.
    pub fn size(&self) -> (u32, u32) {
        match self.layout {
            Layout::Grid { columns } => {
                let (rows, cols) = grid(self.plots.len(), columns);
                (640 * cols as u32, 560 * rows as u32)
            }
            Layout::Inset { .. } => INSET_SIZE_PX,
        }
    }

    /// Write `<stem>.png` and `<stem>.svg` in `dir`.
    pub fn write(&self, dir: &Path, stem: &str) -> DrawResult {
        write_scene(dir, stem, self.size(), self)
    }

    fn draw_on<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
        match self.layout {
            Layout::Grid { columns } => {
                let areas = root.split_evenly(grid(self.plots.len(), columns));
                for (plot, area) in self.plots.iter().zip(&areas) {
                    plot.draw_on(area, 0.8, &[])?;
                }
                Ok(())
            }
            Layout::Inset { rect } => {
                anyhow::ensure!(self.plots.len() == 2, "an inset figure has two plots");
                let axes = self.plots[0].draw_on(root, 1.0, &[rect])?;
                let (w, h) = ((axes.2 - axes.0) as u32, (axes.3 - axes.1) as u32);
                let r = rect.within(w, h);
                let inset = root.clone().shrink(
                    (axes.0 + r.0, axes.1 + r.1),
                    ((r.2 - r.0) as u32, (r.3 - r.1) as u32),
                );
                inset.fill(&WHITE).map_err(plot_err)?;
                self.plots[1].draw_on(&inset, INSET_SCALE, &[]).map(|_| ())
            }
        }
    }

    /// The plotted data as CSV, one row per drawn point of every panel ([`DATA_COLUMNS`]).
    pub fn write_data(&self, path: &Path) -> DrawResult {
        let mut w = csv::Writer::from_path(path)?;
        w.write_record(DATA_COLUMNS)?;
        for p in &self.plots {
            p.data_rows(&text::flat(&p.title), &mut w)?;
        }
        w.flush()?;
        Ok(())
    }
}

impl Scene for Panels {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
        self.draw_on(root)
    }
}

#[cfg(test)]
mod tests;
