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
mod style;
pub mod text;
mod ticks;
pub use legend::Fractions;
pub use raster::{viridis, ColorBar, RasterPlot, Rgb};
use style::PALETTE;
pub use style::{Dash, Marker};
pub use ticks::{interval_text, number, power_of_ten, snap_zero};

/// Columns of a figure's data file: one row per drawn point, with what a reader filters on
/// (the panel's title, the curve, its study, load W/W₀ and threshold A*/λₛ² where it has
/// them) and the point with its axes' quantities, as plain Unicode, and the 95 % band drawn
/// around it where there is one (empty otherwise), and whether its marker is drawn hollow (a
/// tentative value: see [`Series::hollow`]). Every quantity of the figures is dimensionless
/// (normalised as its axis label says).
pub const DATA_COLUMNS: [&str; 12] = [
    "panel",
    "series",
    "study",
    "w_over_w0",
    "a_star_over_ls2",
    "x_quantity",
    "x",
    "y_quantity",
    "y",
    "y_ci95_low",
    "y_ci95_high",
    "hollow",
];

/// A value resting on fewer clusters than this is drawn hollow (and so is one whose 95 %
/// interval reaches 0).
pub use crate::statistics::TENTATIVE_BELOW_CLUSTERS;

/// The embedded text font's bytes.
pub(super) static FONT: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSans.ttf");
/// The embedded math font (DejaVu Math TeX Gyre, same licence), for the few mathematical
/// letters the text font lacks (𝒦).
pub(super) static MATH_FONT: &[u8] = include_bytes!("../../../assets/fonts/DejaVuMathTeXGyre.ttf");
/// Size of a single plot: 6.4 × 4.8 in at 150 dpi.
pub const SIZE_PX: (u32, u32) = (960, 720);
/// Size of a figure with an inset: 7.5 × 6 in at 150 dpi, so that the inset's text is read
/// at [`INSET_SCALE`] of the plot's.
pub const INSET_SIZE_PX: (u32, u32) = (1125, 900);
/// Text scale of an inset: its tick labels 14 px high.
pub const INSET_SCALE: f64 = 0.8;
/// Size of a raster figure (map with its colour bar or legend): 6.4 × 5.6 in at 150 dpi.
pub const RASTER_SIZE_PX: (u32, u32) = (960, 840);

/// Register the embedded fonts under the families the text module asks for.
fn ensure_font() -> anyhow::Result<()> {
    static DONE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let ok = *DONE.get_or_init(|| {
        plotters::style::register_font(text::TEXT_FAMILY, FontStyle::Normal, FONT).is_ok()
            && plotters::style::register_font(text::MATH_FAMILY, FontStyle::Normal, MATH_FONT)
                .is_ok()
    });
    anyhow::ensure!(ok, "the embedded fonts could not be registered");
    Ok(())
}

/// One curve.
#[derive(Clone)]
pub struct Series {
    /// Legend entry (label markup, see [`text`]); empty for curves left out of the legend.
    pub label: String,
    pub points: Vec<(f64, f64)>,
    /// Palette index (curves that belong together share a colour).
    pub color: usize,
    /// Colour overriding the palette.
    pub rgb: Option<(u8, u8, u8)>,
    /// Lightness shift towards white in [0, 1) (several loads of one family).
    pub tint: f64,
    pub dash: Dash,
    /// Line width in pixels (0: markers only).
    pub width: u32,
    /// Marker at each point.
    pub marker: Option<Marker>,
    /// Per point, whether its marker is drawn hollow: a tentative value (one resting on
    /// fewer than [`TENTATIVE_BELOW_CLUSTERS`] clusters, or whose interval reaches 0).
    /// Empty: every marker filled. A legend-only series (no points) with one `true` shows
    /// a hollow marker in the legend.
    pub hollow: Vec<bool>,
    /// The curve's name in the data file when it has no legend entry (e.g. a fit drawn under
    /// a shared entry).
    pub name: String,
    /// The study, load W/W₀ and threshold A*/λₛ² the curve belongs to, for the data file.
    pub study: Option<String>,
    pub w_over_w0: Option<f64>,
    pub a_star_over_ls2: Option<f64>,
    /// A 95 % band shaded around the curve in its colour: (x, low, high) per abscissa.
    pub band: Vec<(f64, f64, f64)>,
}

impl Default for Series {
    fn default() -> Self {
        Series {
            label: String::new(),
            points: Vec::new(),
            color: 0,
            rgb: None,
            tint: 0.0,
            dash: Dash::Solid,
            width: 2,
            marker: None,
            hollow: Vec::new(),
            name: String::new(),
            study: None,
            w_over_w0: None,
            a_star_over_ls2: None,
            band: Vec::new(),
        }
    }
}

impl Series {
    /// A solid line of palette colour `color`.
    pub fn line(label: impl Into<String>, points: Vec<(f64, f64)>, color: usize) -> Self {
        Series {
            label: label.into(),
            points,
            color,
            ..Series::default()
        }
    }

    /// A legend entry alone, its sample a grey shade: says what the bands of the plot are.
    pub fn band_key(label: impl Into<String>) -> Self {
        Series {
            rgb: Some((90, 90, 90)),
            width: 0,
            band: vec![(f64::NAN, f64::NAN, f64::NAN)],
            ..Series::line(label, Vec::new(), 0)
        }
    }

    /// The band's (low, high) at abscissa `x`, if the band has that abscissa.
    fn band_at(&self, x: f64) -> Option<(f64, f64)> {
        self.band.iter().find(|b| b.0 == x).map(|b| (b.1, b.2))
    }

    fn rgb_color(&self) -> RGBColor {
        let RGBColor(r, g, b) = match self.rgb {
            Some((r, g, b)) => RGBColor(r, g, b),
            None => PALETTE[self.color % PALETTE.len()],
        };
        let t = self.tint.clamp(0.0, 0.95);
        let mix = |c: u8| (c as f64 + t * (255.0 - c as f64)).round() as u8;
        RGBColor(mix(r), mix(g), mix(b))
    }
}

/// The y axis of a line plot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum YAxis {
    Linear,
    Log,
    /// Linear from 0 up to `threshold`, logarithmic above (paper Fig. 4b).
    LinLog {
        threshold: f64,
    },
}

/// A 2-D line plot. Title, axis labels and legend entries are label markup ([`text`]).
#[derive(Clone)]
pub struct LinePlot {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub x_log: bool,
    pub y_axis: YAxis,
    pub series: Vec<Series>,
    /// Abscissae marked by vertical dashed grey lines (e.g. the loads of Fig. 2b–d).
    pub x_marks: Vec<f64>,
    /// Where the legend goes.
    pub legend: LegendAt,
    /// Bounds the quantity on the y axis cannot leave (e.g. (0, 1) for a fraction): the
    /// axis, padded around the data, is clipped to them.
    pub y_bounds: Option<(f64, f64)>,
    /// The abscissa is a count (e.g. realizations): only whole-number ticks are labelled.
    pub x_integer: bool,
    /// On a logarithmic y axis, where values of exactly 0 are drawn: the tick there reads
    /// "exact" and a dotted line marks it (errors that vanish stay visible).
    pub y_floor: Option<f64>,
    /// Letters written at the top of the `x_marks` lines, in their order (e.g. "b", "c", "d").
    pub x_mark_labels: Vec<String>,
    /// Ordinates marked by horizontal dashed grey lines (e.g. a tolerance).
    pub y_marks: Vec<f64>,
    /// Short texts (label markup) written beside points (x, y), e.g. the setting of a point.
    pub notes: Vec<((f64, f64), String)>,
    /// Where a plot may have nothing to draw (a measured map in full contact, one cluster):
    /// why, written in the empty panel instead of failing. None: a plot with no point is an
    /// error (a figure of the pipeline always has data).
    pub when_empty: Option<String>,
}

impl LinePlot {
    /// A plot with no series yet, legend placed automatically.
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
        x_log: bool,
        y_axis: YAxis,
    ) -> Self {
        LinePlot {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            x_log,
            y_axis,
            series: Vec::new(),
            x_marks: Vec::new(),
            x_mark_labels: Vec::new(),
            legend: LegendAt::Auto,
            y_bounds: None,
            x_integer: false,
            y_floor: None,
            y_marks: Vec::new(),
            notes: Vec::new(),
            when_empty: None,
        }
    }
}

/// Where the legend goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LegendAt {
    /// In the first corner of the axes (upper right, upper left, lower right, lower left) where
    /// it covers no data, else below the axes.
    Auto,
    /// Below the axes.
    Below,
}

fn finite_on(x_log: bool, y_axis: YAxis) -> impl Fn(&(f64, f64)) -> bool {
    move |&(x, y)| {
        x.is_finite()
            && y.is_finite()
            && (!x_log || x > 0.0)
            && match y_axis {
                YAxis::Linear => true,
                YAxis::Log => y > 0.0,
                YAxis::LinLog { .. } => y >= 0.0,
            }
    }
}

type DrawResult = anyhow::Result<()>;

fn plot_err<E: std::fmt::Debug>(e: E) -> anyhow::Error {
    anyhow::anyhow!("plotting: {e:?}")
}

/// Text sizes in pixels of a plot at scale 1 (one font throughout).
const TITLE_PX: f64 = 23.0;
const AXIS_LABEL_PX: f64 = 21.0;
const TICK_PX: f64 = 18.0;
const LEGEND_PX: f64 = 17.0;

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

/// Something drawn on a drawing area of any backend.
trait Scene {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult;
}

impl Scene for LinePlot {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
        self.draw_on(root, 1.0, &[]).map(|_| ())
    }
}

impl Scene for Panels {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
        self.draw_on(root)
    }
}

impl Scene for RasterPlot {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
        self.draw_on(root)
    }
}

/// Render a scene to `<stem>.png` and `<stem>.svg` in `dir`.
fn write_scene(dir: &Path, stem: &str, size: (u32, u32), scene: &impl Scene) -> DrawResult {
    ensure_font()?;
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

#[cfg(test)]
mod tests;
