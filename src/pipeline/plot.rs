//! Line plots as PNG (150 dpi) and SVG with plotters, text in an embedded font
//! (DejaVu Sans, assets/fonts, Bitstream Vera licence) so no system font package is needed.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

/// The embedded font's bytes.
static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");
/// Figure size: 6.4 × 4.8 in at 150 dpi.
pub const SIZE_PX: (u32, u32) = (960, 720);

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
    if a == 0.0 || (1e-3..1e4).contains(&a) {
        let s = format!("{v:.4}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    } else {
        format!("{v:.0e}")
    }
}

/// One curve.
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    /// Palette index (curves that belong together share a colour).
    pub color: usize,
    /// Dashed instead of solid.
    pub dashed: bool,
}

/// A 2-D line plot.
pub struct LinePlot {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub x_log: bool,
    pub y_log: bool,
    pub series: Vec<Series>,
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

impl LinePlot {
    /// Finite points (positive on logarithmic axes) of every series.
    fn points(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.series
            .iter()
            .flat_map(|s| s.points.iter().copied())
            .filter(|&(x, y)| {
                x.is_finite()
                    && y.is_finite()
                    && (!self.x_log || x > 0.0)
                    && (!self.y_log || y > 0.0)
            })
    }

    fn range(&self, pick: impl Fn((f64, f64)) -> f64, log: bool) -> anyhow::Result<(f64, f64)> {
        let (lo, hi) = self
            .points()
            .map(pick)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v), b.max(v))
            });
        anyhow::ensure!(lo.is_finite(), "plot '{}' has no finite point", self.title);
        Ok(if log {
            let (lo, hi) = if hi > lo {
                (lo, hi)
            } else {
                (lo / 2.0, hi * 2.0)
            };
            (lo / 1.2, hi * 1.2)
        } else {
            let pad = if hi > lo { 0.05 * (hi - lo) } else { 1.0 };
            (lo - pad, hi + pad)
        })
    }

    /// Write `<stem>.png` and `<stem>.svg` in `dir`.
    pub fn write(&self, dir: &Path, stem: &str) -> anyhow::Result<()> {
        ensure_font()?;
        let png = dir.join(format!("{stem}.png"));
        self.draw(BitMapBackend::new(&png, SIZE_PX).into_drawing_area())?;
        let svg = dir.join(format!("{stem}.svg"));
        self.draw(SVGBackend::new(&svg, SIZE_PX).into_drawing_area())?;
        Ok(())
    }

    fn draw<DB: DrawingBackend>(&self, root: DrawingArea<DB, Shift>) -> anyhow::Result<()> {
        let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow::anyhow!("plotting: {e:?}");
        root.fill(&WHITE).map_err(err)?;
        let (x0, x1) = self.range(|p| p.0, self.x_log)?;
        let (y0, y1) = self.range(|p| p.1, self.y_log)?;
        let mut builder = ChartBuilder::on(&root);
        builder
            .caption(&self.title, ("sans-serif", 26))
            .margin(18)
            .x_label_area_size(60)
            .y_label_area_size(90);
        macro_rules! finish {
            ($chart:expr) => {{
                let mut chart = $chart;
                chart
                    .configure_mesh()
                    .x_labels(6)
                    .y_labels(10)
                    .x_label_formatter(&tick)
                    .y_label_formatter(&tick)
                    .x_desc(&self.x_label)
                    .y_desc(&self.y_label)
                    .label_style(("sans-serif", 18))
                    .axis_desc_style(("sans-serif", 20))
                    .draw()
                    .map_err(err)?;
                for s in &self.series {
                    let color = PALETTE[s.color % PALETTE.len()];
                    let dashed = s.dashed;
                    let pts: Vec<(f64, f64)> = s
                        .points
                        .iter()
                        .copied()
                        .filter(|&(x, y)| {
                            x.is_finite()
                                && y.is_finite()
                                && (!self.x_log || x > 0.0)
                                && (!self.y_log || y > 0.0)
                        })
                        .collect();
                    let anno = if dashed {
                        chart
                            .draw_series(DashedLineSeries::new(pts, 8, 5, color.stroke_width(2)))
                            .map_err(err)?
                    } else {
                        chart
                            .draw_series(LineSeries::new(pts, color.stroke_width(2)))
                            .map_err(err)?
                    };
                    anno.label(s.label.as_str()).legend(move |(x, y)| {
                        if dashed {
                            PathElement::new(vec![(x, y), (x + 8, y)], color.stroke_width(2))
                        } else {
                            PathElement::new(vec![(x, y), (x + 24, y)], color.stroke_width(2))
                        }
                    });
                }
                chart
                    .configure_series_labels()
                    .label_font(("sans-serif", 16))
                    .background_style(WHITE.mix(0.85))
                    .border_style(BLACK)
                    .draw()
                    .map_err(err)?;
            }};
        }
        match (self.x_log, self.y_log) {
            (true, true) => finish!(builder
                .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
                .map_err(err)?),
            (true, false) => finish!(builder
                .build_cartesian_2d((x0..x1).log_scale(), y0..y1)
                .map_err(err)?),
            (false, true) => finish!(builder
                .build_cartesian_2d(x0..x1, (y0..y1).log_scale())
                .map_err(err)?),
            (false, false) => finish!(builder.build_cartesian_2d(x0..x1, y0..y1).map_err(err)?),
        }
        root.present().map_err(err)?;
        Ok(())
    }

    /// The plotted data as CSV (`series, x, y`), beside the images.
    pub fn write_data(&self, path: &Path) -> anyhow::Result<()> {
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
