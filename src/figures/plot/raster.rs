//! Raster figures: a map drawn pixel by pixel, with a colour bar or a legend.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::colors::colormaps::ViridisRGB;

use std::path::Path;

use super::scene::{plot_err, write_scene, DrawResult, Scene};
use super::series::{AXIS_LABEL_PX, LEGEND_PX, RASTER_SIZE_PX, TICK_PX, TITLE_PX};
use super::text::{self, Align, TextLook};
use super::ticks::{number, snap_zero};

/// A colour bar beside a raster: values `lo … hi` mapped through viridis.
#[derive(Clone, Debug)]
pub struct ColorBar {
    pub lo: f64,
    pub hi: f64,
    pub label: String,
}

/// An sRGB colour.
pub type Rgb = (u8, u8, u8);

/// A raster image (row 0 at the top, as numpy's `imshow`) drawn on `[0, 1]²`.
pub struct RasterPlot {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    /// Rows × columns of RGB pixels.
    pub rows: usize,
    pub cols: usize,
    pub rgb: Vec<u8>,
    pub colorbar: Option<ColorBar>,
    /// Legend beside the image: (label, colour), text alone without a colour.
    pub legend: Vec<(String, Option<Rgb>)>,
}

/// Viridis colour of `t` in [0, 1].
pub fn viridis(t: f64) -> (u8, u8, u8) {
    let RGBColor(r, g, b) = ViridisRGB::get_color(t.clamp(0.0, 1.0));
    (r, g, b)
}

impl RasterPlot {
    /// Nearest-neighbour resampling of the raster to `w × h` pixels.
    pub(super) fn resampled(&self, w: u32, h: u32) -> Vec<u8> {
        let mut out = vec![0u8; (w * h * 3) as usize];
        for y in 0..h as usize {
            let r = (y * self.rows) / h as usize;
            for x in 0..w as usize {
                let c = (x * self.cols) / w as usize;
                let s = 3 * (r * self.cols + c);
                let d = 3 * (y * w as usize + x);
                out[d..d + 3].copy_from_slice(&self.rgb[s..s + 3]);
            }
        }
        out
    }

    /// Write `<stem>.png` and `<stem>.svg` in `dir`.
    pub fn write(&self, dir: &Path, stem: &str) -> DrawResult {
        anyhow::ensure!(
            self.rows > 0 && self.cols > 0 && self.rgb.len() == 3 * self.rows * self.cols,
            "raster '{}' has {} bytes for {}×{} pixels",
            self.title,
            self.rgb.len(),
            self.rows,
            self.cols
        );
        write_scene(dir, stem, RASTER_SIZE_PX, self)
    }

    pub(super) fn draw_on<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
        let (w, _) = root.dim_in_pixel();
        let (main, side) = root.split_horizontally(w - 160);
        let (mw0, _) = main.dim_in_pixel();
        text::draw(
            &main,
            &self.title,
            (mw0 as i32 / 2, 10),
            Align::Middle,
            TextLook::new(TITLE_PX),
        )?;
        let (_, main) = main.split_vertically(44);
        // Margins chosen so that the image area has the map's aspect, cols : rows (pixels
        // of the map are square).
        let (margin, x_area, y_area, top) = (18u32, 60u32, 80u32, 10u32);
        let (mw, mh) = main.dim_in_pixel();
        let pw = mw.saturating_sub(2 * margin + y_area);
        let ph = mh.saturating_sub(top + margin + x_area);
        let aspect = self.cols as f64 / self.rows as f64;
        let (extra_right, extra_bottom) = if pw as f64 > ph as f64 * aspect {
            (pw - (ph as f64 * aspect) as u32, 0)
        } else {
            (0, ph - (pw as f64 / aspect) as u32)
        };
        let mut builder = ChartBuilder::on(&main);
        builder
            .margin_left(margin)
            .margin_right(margin + extra_right)
            .margin_top(top)
            .margin_bottom(margin + extra_bottom)
            .x_label_area_size(x_area)
            .y_label_area_size(y_area);
        let mut chart = builder
            .build_cartesian_2d(0.0..1.0, 1.0..0.0)
            .map_err(plot_err)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_labels(6)
            .y_labels(6)
            .x_label_formatter(&|v| number(*v))
            .y_label_formatter(&|v| number(*v))
            .label_style(("sans-serif", TICK_PX))
            .draw()
            .map_err(plot_err)?;
        let (xr, yr) = chart.plotting_area().get_pixel_range();
        let (mx, my) = main.get_pixel_range();
        let base = root.get_base_pixel();
        text::draw(
            root,
            &self.x_label,
            (
                (xr.start + xr.end) / 2 - base.0,
                yr.end - base.1 + (TICK_PX * 1.9) as i32,
            ),
            Align::Middle,
            TextLook::new(AXIS_LABEL_PX),
        )?;
        text::draw(
            root,
            &self.y_label,
            (mx.start - base.0 + 8, (yr.start + yr.end) / 2 - base.1),
            Align::Middle,
            TextLook {
                upwards: true,
                ..TextLook::new(AXIS_LABEL_PX)
            },
        )?;
        let _ = my;
        let (pw, ph) = ((xr.end - xr.start) as u32, (yr.end - yr.start) as u32);
        let buffer = self.resampled(pw, ph);
        let element =
            BitMapElement::<(i32, i32)>::with_owned_buffer((xr.start, yr.start), (pw, ph), buffer)
                .ok_or_else(|| anyhow::anyhow!("raster buffer has the wrong size"))?;
        root.draw(&element).map_err(plot_err)?;
        self.draw_legend(root, w as i32 - 150, yr.start)?;
        if let Some(bar) = &self.colorbar {
            let below = (main.dim_in_pixel().1 as i32 - yr.end).max(0);
            draw_colorbar(root, &side, bar, (yr.start, below))?;
        }
        Ok(())
    }
}

impl RasterPlot {
    /// Legend entries beside the image from `(x, y0)` down: a coloured square and its label,
    /// or text alone.
    fn draw_legend<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        x: i32,
        y0: i32,
    ) -> DrawResult {
        let mut y = y0;
        for (label, color) in &self.legend {
            if let Some((r, g, b)) = color {
                let square = [(x, y), (x + 18, y + 18)];
                root.draw(&Rectangle::new(square, RGBColor(*r, *g, *b).filled()))
                    .map_err(plot_err)?;
                root.draw(&Rectangle::new(square, BLACK))
                    .map_err(plot_err)?;
            }
            let tx = if color.is_some() { x + 26 } else { x };
            text::draw(
                root,
                label,
                (tx, y + 3),
                Align::Start,
                TextLook::new(LEGEND_PX),
            )?;
            y += 30;
        }
        Ok(())
    }
}

/// The colour bar in `side`, its scale `(top, bottom)` margins aligned with the image's.
fn draw_colorbar<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    side: &DrawingArea<DB, Shift>,
    bar: &ColorBar,
    margins: (i32, i32),
) -> DrawResult {
    let base = root.get_base_pixel();
    let mut cb = ChartBuilder::on(side);
    cb.margin_top(margins.0)
        .margin_bottom(margins.1)
        .margin_right(10)
        .y_label_area_size(0)
        .right_y_label_area_size(100);
    let mut chart = cb
        .build_cartesian_2d(0.0..1.0, bar.lo..bar.hi)
        .map_err(plot_err)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_labels(8)
        .y_label_formatter(&|v| number(snap_zero(*v, bar.hi - bar.lo)))
        .label_style(("sans-serif", LEGEND_PX))
        .draw()
        .map_err(plot_err)?;
    let (_, sy) = chart.plotting_area().get_pixel_range();
    let (sx, _) = side.get_pixel_range();
    text::draw(
        root,
        &bar.label,
        (sx.end - base.0 - 24, (sy.start + sy.end) / 2 - base.1),
        Align::Middle,
        TextLook {
            upwards: true,
            ..TextLook::new(AXIS_LABEL_PX * 0.9)
        },
    )?;
    let steps = 256;
    let span = bar.hi - bar.lo;
    chart
        .draw_series((0..steps).map(|i| {
            let a = bar.lo + span * i as f64 / steps as f64;
            let b = bar.lo + span * (i + 1) as f64 / steps as f64;
            let (r, g, bl) = viridis((i as f64 + 0.5) / steps as f64);
            Rectangle::new([(0.0, a), (1.0, b)], RGBColor(r, g, bl).filled())
        }))
        .map_err(plot_err)?;
    Ok(())
}

impl Scene for RasterPlot {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
        self.draw_on(root)
    }
}
