//! Figures as PNG (150 dpi) and SVG with plotters, text in an embedded font (DejaVu Sans,
//! assets/fonts, Bitstream Vera licence) so no system font package is needed.
//!
//! Three kinds of scene: a line plot ([`LinePlot`], logarithmic, linear or linear-then-log
//! axes), several line plots side by side or one inset in another ([`Panels`]), and a raster
//! image with a colour bar or a colour legend ([`RasterPlot`]; the SVG embeds the same
//! raster as a PNG).

use std::ops::Range;
use std::path::Path;

use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, Ranged};
use plotters::coord::Shift;
use plotters::prelude::*;

mod raster;
pub use raster::{viridis, ColorBar, RasterPlot, Rgb};

/// The embedded font's bytes.
static FONT: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSans.ttf");
/// Size of a single plot: 6.4 × 4.8 in at 150 dpi.
pub const SIZE_PX: (u32, u32) = (960, 720);
/// Size of a raster figure (map with its colour bar or legend): 6.4 × 5.6 in at 150 dpi.
pub const RASTER_SIZE_PX: (u32, u32) = (960, 840);

/// Register the embedded font under the family plotters asks for ("sans-serif").
fn ensure_font() -> anyhow::Result<()> {
    static DONE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let ok = *DONE.get_or_init(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, FONT).is_ok()
    });
    anyhow::ensure!(ok, "the embedded font could not be registered");
    Ok(())
}

/// Tick labels: plain for moderate magnitudes, `1e6` style otherwise.
fn tick(v: &f64) -> String {
    let a = v.abs();
    if a < 1e-12 {
        return "0".into();
    }
    if (1e-3..1e4).contains(&a) {
        let s = format!("{v:.4}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    } else {
        let s = format!("{v:.1e}");
        s.replace(".0e", "e")
    }
}

/// [`tick`], or no label for a fractional value on an axis of whole numbers.
fn axis_tick(v: &f64, integer: bool) -> String {
    if integer && v.fract() != 0.0 {
        String::new()
    } else {
        tick(v)
    }
}

/// One curve.
#[derive(Clone)]
pub struct Series {
    /// Legend entry; empty for curves left out of the legend.
    pub label: String,
    pub points: Vec<(f64, f64)>,
    /// Palette index (curves that belong together share a colour).
    pub color: usize,
    /// Colour overriding the palette.
    pub rgb: Option<(u8, u8, u8)>,
    /// Lightness shift towards white in [0, 1) (several loads of one family).
    pub tint: f64,
    /// Dashed instead of solid.
    pub dashed: bool,
    /// Line width in pixels (0: markers only).
    pub width: u32,
    /// Draw a circle at each point.
    pub markers: bool,
}

impl Default for Series {
    fn default() -> Self {
        Series {
            label: String::new(),
            points: Vec::new(),
            color: 0,
            rgb: None,
            tint: 0.0,
            dashed: false,
            width: 2,
            markers: false,
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

/// A 2-D line plot.
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
    /// On a linear y axis, room left empty above the data for the legend, as a fraction of
    /// the data's range (0: none).
    pub y_headroom: f64,
    /// The abscissa is a count (e.g. realizations): only whole-number ticks are labelled.
    pub x_integer: bool,
}

impl LinePlot {
    /// A plot with no series yet, legend at the upper right.
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
            legend: LegendAt::UpperRight,
            y_headroom: 0.0,
            x_integer: false,
        }
    }
}

/// Corner of the legend box.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LegendAt {
    MiddleLeft,
    UpperLeft,
    UpperRight,
    LowerLeft,
    LowerRight,
}

impl LegendAt {
    fn position(self) -> SeriesLabelPosition {
        match self {
            LegendAt::MiddleLeft => SeriesLabelPosition::MiddleLeft,
            LegendAt::UpperLeft => SeriesLabelPosition::UpperLeft,
            LegendAt::UpperRight => SeriesLabelPosition::UpperRight,
            LegendAt::LowerLeft => SeriesLabelPosition::LowerLeft,
            LegendAt::LowerRight => SeriesLabelPosition::LowerRight,
        }
    }
}

const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

/// Linear from 0 to `threshold`, logarithmic above: `t(y) = y/threshold` below and
/// `1 + log10(y/threshold)` above, drawn linearly in `t`.
#[derive(Clone, Debug)]
struct LinLogCoord {
    threshold: f64,
    hi: f64,
}

impl LinLogCoord {
    fn t(&self, v: f64) -> f64 {
        if v <= self.threshold {
            v / self.threshold
        } else {
            1.0 + (v / self.threshold).log10()
        }
    }
}

impl Ranged for LinLogCoord {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        let f = self.t(*value) / self.t(self.hi);
        limit.0 + (f * (limit.1 - limit.0) as f64).round() as i32
    }

    fn key_points<H: KeyPointHint>(&self, _hint: H) -> Vec<f64> {
        let mut out = vec![0.0, self.threshold / 2.0, self.threshold];
        let mut v = self.threshold * 10.0;
        while v <= self.hi * (1.0 + 1e-12) {
            out.push(v);
            v *= 10.0;
        }
        out
    }

    fn range(&self) -> Range<f64> {
        0.0..self.hi
    }
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

fn padded(lo: f64, hi: f64, log: bool) -> (f64, f64) {
    if log {
        let (lo, hi) = if hi > lo {
            (lo, hi)
        } else {
            (lo / 2.0, hi * 2.0)
        };
        (lo / 1.2, hi * 1.2)
    } else {
        let pad = if hi > lo { 0.05 * (hi - lo) } else { 1.0 };
        (lo - pad, hi + pad)
    }
}

type DrawResult = anyhow::Result<()>;

fn plot_err<E: std::fmt::Debug>(e: E) -> anyhow::Error {
    anyhow::anyhow!("plotting: {e:?}")
}

impl LinePlot {
    /// Finite points (positive on logarithmic axes) of every series.
    fn points(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        let keep = finite_on(self.x_log, self.y_axis);
        self.series
            .iter()
            .flat_map(|s| s.points.iter().copied())
            .filter(move |p| keep(p))
    }

    fn extent(&self, pick: impl Fn((f64, f64)) -> f64) -> anyhow::Result<(f64, f64)> {
        let (lo, hi) = self
            .points()
            .map(pick)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v), b.max(v))
            });
        anyhow::ensure!(lo.is_finite(), "plot '{}' has no finite point", self.title);
        Ok((lo, hi))
    }

    /// Write `<stem>.png` and `<stem>.svg` in `dir`.
    pub fn write(&self, dir: &Path, stem: &str) -> DrawResult {
        write_scene(dir, stem, SIZE_PX, self)
    }

    /// Draw into `area` with fonts scaled by `scale`.
    fn draw_on<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>, scale: f64) -> DrawResult {
        let (x0, x1) = self.extent(|p| p.0)?;
        let (x0, x1) = padded(x0, x1, self.x_log);
        let (y0, y1) = self.extent(|p| p.1)?;
        let px = |v: f64| ((v * scale).round() as i32).max(8);
        let mut builder = ChartBuilder::on(area);
        builder
            .caption(&self.title, ("sans-serif", px(26.0)))
            .margin(px(18.0))
            .x_label_area_size(px(60.0))
            .y_label_area_size(px(90.0));
        let keep = finite_on(self.x_log, self.y_axis);
        let marker = ((3.0 * scale).round() as i32).max(2);
        let x_tick = |v: &f64| axis_tick(v, self.x_integer);
        macro_rules! finish {
            ($chart:expr, $ylo:expr, $yhi:expr) => {{
                let mut chart = $chart;
                chart
                    .configure_mesh()
                    .x_labels(6)
                    .y_labels(10)
                    .x_label_formatter(&x_tick)
                    .y_label_formatter(&tick)
                    .x_desc(&self.x_label)
                    .y_desc(&self.y_label)
                    .label_style(("sans-serif", px(18.0)))
                    .axis_desc_style(("sans-serif", px(20.0)))
                    .draw()
                    .map_err(plot_err)?;
                let grey = RGBColor(150, 150, 150);
                for &x in &self.x_marks {
                    chart
                        .draw_series(DashedLineSeries::new(
                            vec![(x, $ylo), (x, $yhi)],
                            6,
                            4,
                            grey.stroke_width(1),
                        ))
                        .map_err(plot_err)?;
                }
                let mut any_label = false;
                for s in &self.series {
                    let color = s.rgb_color();
                    let dashed = s.dashed;
                    let width = s.width;
                    let pts: Vec<(f64, f64)> =
                        s.points.iter().copied().filter(|p| keep(p)).collect();
                    let style = color.stroke_width(width.max(1));
                    if s.markers {
                        chart
                            .draw_series(
                                pts.iter().map(|&p| Circle::new(p, marker, color.filled())),
                            )
                            .map_err(plot_err)?;
                    }
                    if width > 0 {
                        let anno = if dashed {
                            chart
                                .draw_series(DashedLineSeries::new(pts, 8, 5, style))
                                .map_err(plot_err)?
                        } else {
                            chart
                                .draw_series(LineSeries::new(pts, style))
                                .map_err(plot_err)?
                        };
                        if !s.label.is_empty() {
                            any_label = true;
                            let markers = s.markers;
                            anno.label(s.label.as_str()).legend(move |(x, y)| {
                                let end = if dashed { x + 8 } else { x + 24 };
                                let line = PathElement::new(vec![(x, y), (end, y)], style);
                                let dot = Circle::new(
                                    (x + 12, y),
                                    if markers { 4 } else { 0 },
                                    color.filled(),
                                );
                                EmptyElement::at((0, 0)) + line + dot
                            });
                        }
                    } else if !s.label.is_empty() {
                        any_label = true;
                        let anno = chart
                            .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())
                            .map_err(plot_err)?;
                        anno.label(s.label.as_str())
                            .legend(move |(x, y)| Circle::new((x + 12, y), 4, color.filled()));
                    }
                }
                if any_label {
                    chart
                        .configure_series_labels()
                        .position(self.legend.position())
                        .label_font(("sans-serif", px(16.0)))
                        .background_style(WHITE.mix(0.85))
                        .border_style(BLACK)
                        .draw()
                        .map_err(plot_err)?;
                }
            }};
        }
        let x_range = x0..x1;
        match self.y_axis {
            YAxis::Log => {
                let (y0, y1) = padded(y0, y1, true);
                if self.x_log {
                    finish!(
                        builder
                            .build_cartesian_2d(x_range.log_scale(), (y0..y1).log_scale())
                            .map_err(plot_err)?,
                        y0,
                        y1
                    )
                } else {
                    finish!(
                        builder
                            .build_cartesian_2d(x_range, (y0..y1).log_scale())
                            .map_err(plot_err)?,
                        y0,
                        y1
                    )
                }
            }
            YAxis::Linear => {
                let (y0, y1) = padded(y0, y1 + self.y_headroom.max(0.0) * (y1 - y0), false);
                if self.x_log {
                    finish!(
                        builder
                            .build_cartesian_2d(x_range.log_scale(), y0..y1)
                            .map_err(plot_err)?,
                        y0,
                        y1
                    )
                } else {
                    finish!(
                        builder
                            .build_cartesian_2d(x_range, y0..y1)
                            .map_err(plot_err)?,
                        y0,
                        y1
                    )
                }
            }
            YAxis::LinLog { threshold } => {
                anyhow::ensure!(
                    threshold > 0.0,
                    "linear-log axis needs a positive threshold"
                );
                let y_coord = LinLogCoord {
                    threshold,
                    hi: (y1 * 1.5).max(threshold * 2.0),
                };
                let hi = y_coord.hi;
                if self.x_log {
                    finish!(
                        builder
                            .build_cartesian_2d(x_range.log_scale(), y_coord)
                            .map_err(plot_err)?,
                        0.0,
                        hi
                    )
                } else {
                    finish!(
                        builder
                            .build_cartesian_2d(x_range, y_coord)
                            .map_err(plot_err)?,
                        0.0,
                        hi
                    )
                }
            }
        }
        Ok(())
    }

    /// Rows `panel, series, x, y` of the plotted data.
    fn data_rows(&self, panel: &str, out: &mut csv::Writer<std::fs::File>) -> DrawResult {
        for s in &self.series {
            for (x, y) in &s.points {
                out.write_record([panel, &s.label, &x.to_string(), &y.to_string()])?;
            }
        }
        Ok(())
    }

    /// The plotted data as CSV (`series, <x label>, <y label>`), beside the images.
    pub fn write_data(&self, path: &Path) -> DrawResult {
        let mut w = csv::Writer::from_path(path)?;
        w.write_record(["series", &self.x_label, &self.y_label])?;
        for s in &self.series {
            for (x, y) in &s.points {
                w.write_record([s.label.clone(), x.to_string(), y.to_string()])?;
            }
        }
        w.flush()?;
        Ok(())
    }
}

/// Several line plots in one figure.
pub struct Panels {
    pub plots: Vec<LinePlot>,
    pub layout: Layout,
}

/// How [`Panels`] are arranged.
#[derive(Clone, Copy, Debug)]
pub enum Layout {
    /// Side by side in `columns` columns (rows as needed), each panel 640 × 560 px.
    Grid { columns: usize },
    /// The second plot inset in the first, at fractions (left, top, width, height) of it.
    Inset { rect: (f64, f64, f64, f64) },
}

impl Panels {
    /// Figure size in pixels.
    pub fn size(&self) -> (u32, u32) {
        match self.layout {
            Layout::Grid { columns } => {
                let cols = columns.clamp(1, self.plots.len().max(1));
                let rows = self.plots.len().div_ceil(cols).max(1);
                (640 * cols as u32, 560 * rows as u32)
            }
            Layout::Inset { .. } => SIZE_PX,
        }
    }

    /// Write `<stem>.png` and `<stem>.svg` in `dir`.
    pub fn write(&self, dir: &Path, stem: &str) -> DrawResult {
        write_scene(dir, stem, self.size(), self)
    }

    fn draw_on<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
        match self.layout {
            Layout::Grid { columns } => {
                let cols = columns.clamp(1, self.plots.len().max(1));
                let rows = self.plots.len().div_ceil(cols).max(1);
                let areas = root.split_evenly((rows, cols));
                for (plot, area) in self.plots.iter().zip(&areas) {
                    plot.draw_on(area, 0.8)?;
                }
                Ok(())
            }
            Layout::Inset {
                rect: (left, top, width, height),
            } => {
                anyhow::ensure!(self.plots.len() == 2, "an inset figure has two plots");
                self.plots[0].draw_on(root, 1.0)?;
                let (w, h) = root.dim_in_pixel();
                let inset = root.clone().shrink(
                    (
                        (left * w as f64).round() as i32,
                        (top * h as f64).round() as i32,
                    ),
                    (
                        (width * w as f64).round() as u32,
                        (height * h as f64).round() as u32,
                    ),
                );
                inset.fill(&WHITE).map_err(plot_err)?;
                self.plots[1].draw_on(&inset, 0.6)
            }
        }
    }

    /// The plotted data as CSV (`panel, series, x, y`; axis labels in the panel titles).
    pub fn write_data(&self, path: &Path) -> DrawResult {
        let mut w = csv::Writer::from_path(path)?;
        w.write_record(["panel", "series", "x", "y"])?;
        for p in &self.plots {
            let name = format!("{} [x: {}; y: {}]", p.title, p.x_label, p.y_label);
            p.data_rows(&name, &mut w)?;
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
        self.draw_on(root, 1.0)
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
