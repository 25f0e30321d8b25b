//! The legend: its size, where it covers no data, and its drawing.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::scene::{plot_err, DrawResult};
use super::series::{Series, LEGEND_PX};
use super::style::{draw_marker, draw_path, BAND_OPACITY};
use super::text::{self, Align, TextLook};

/// Size of the legend: one row per entry, a line sample then the label.
pub(super) struct LegendBox {
    /// Width of the line sample.
    sample: i32,
    /// Width and height of one entry.
    entry: (i32, i32),
    padding: i32,
    text_px: f64,
}

impl LegendBox {
    pub(super) fn measure<DB: DrawingBackend>(
        area: &DrawingArea<DB, Shift>,
        entries: &[&Series],
        scale: f64,
    ) -> Self {
        let text_px = (LEGEND_PX * scale).max(9.0);
        let sample = (34.0 * scale).round() as i32;
        let gap = (8.0 * scale).round() as i32;
        let widest = entries
            .iter()
            .map(|s| text::width(area, &s.label, text_px))
            .max()
            .unwrap_or(0);
        LegendBox {
            sample,
            entry: (sample + gap + widest, (text_px * 1.45).round() as i32),
            padding: (7.0 * scale).round() as i32,
            text_px,
        }
    }

    /// Size of the box holding `n` entries in `columns` columns.
    pub(super) fn size(&self, n: usize, columns: usize) -> (i32, i32) {
        let columns = columns.max(1);
        let rows = n.div_ceil(columns) as i32;
        let gap = if columns > 1 { self.padding * 3 } else { 0 };
        (
            columns as i32 * self.entry.0 + (columns as i32 - 1) * gap + 2 * self.padding,
            rows * self.entry.1 + 2 * self.padding,
        )
    }

    /// Draw the entries at `spot` inside the plotting area `plot`, or else centred in the
    /// strip `below` the axes in its number of columns.
    pub(super) fn draw_placed<DB: DrawingBackend>(
        &self,
        plot: &DrawingArea<DB, Shift>,
        spot: Option<(i32, i32)>,
        below: Option<(DrawingArea<DB, Shift>, usize)>,
        entries: &[&Series],
        marker_r: i32,
    ) -> DrawResult {
        match (spot, below) {
            (Some(at), _) => self.draw(plot, entries, 1, at, marker_r)?,
            (None, Some((strip, columns))) => {
                let (sw, _) = strip.dim_in_pixel();
                let (lw, _) = self.size(entries.len(), columns);
                self.draw(
                    &strip,
                    entries,
                    columns,
                    ((sw as i32 - lw) / 2, 0),
                    marker_r,
                )?
            }
            _ => {}
        }
        Ok(())
    }

    /// Draw the entries in `columns` columns, box's top-left corner at `at` of `area`.
    pub(super) fn draw<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        entries: &[&Series],
        columns: usize,
        at: (i32, i32),
        marker_r: i32,
    ) -> DrawResult {
        let (w, h) = self.size(entries.len(), columns);
        let (x0, y0) = at;
        area.draw(&Rectangle::new(
            [(x0, y0), (x0 + w, y0 + h)],
            WHITE.filled(),
        ))
        .map_err(plot_err)?;
        area.draw(&Rectangle::new(
            [(x0, y0), (x0 + w, y0 + h)],
            RGBColor(160, 160, 160).stroke_width(1),
        ))
        .map_err(plot_err)?;
        let rows = entries.len().div_ceil(columns.max(1));
        let gap = if columns > 1 { self.padding * 3 } else { 0 };
        for (i, s) in entries.iter().enumerate() {
            let (col, row) = ((i / rows) as i32, (i % rows) as i32);
            let x = x0 + self.padding + col * (self.entry.0 + gap);
            let yc = y0 + self.padding + row * self.entry.1 + self.entry.1 / 2;
            let color = s.rgb_color();
            if !s.band.is_empty() {
                let half = (0.35 * self.text_px).round() as i32;
                area.draw(&Rectangle::new(
                    [(x, yc - half), (x + self.sample, yc + half)],
                    color.mix(BAND_OPACITY).filled(),
                ))
                .map_err(plot_err)?;
            }
            if s.width > 0 {
                let style = color.stroke_width(s.width);
                draw_path(area, vec![(x, yc), (x + self.sample, yc)], s.dash, style)?;
            }
            if let Some(m) = s.marker {
                let hollow = !s.hollow.is_empty() && s.hollow.iter().all(|&h| h);
                draw_marker(area, m, (x + self.sample / 2, yc), marker_r, color, hollow)?;
            }
            let top = yc - (0.2 * self.text_px).round() as i32;
            text::draw(
                area,
                &s.label,
                (
                    x + self.sample + (8.0 * self.text_px / LEGEND_PX) as i32,
                    top,
                ),
                Align::Start,
                TextLook::new(self.text_px),
            )?;
        }
        Ok(())
    }
}

/// Pixels (relative to the plotting area) covered by the curves and marks of a plot.
pub(super) fn covered_pixels(curves: &[Vec<(i32, i32)>], step: f64) -> Vec<(i32, i32)> {
    let mut out = Vec::new();
    for c in curves {
        out.extend(c.iter().copied());
        for w in c.windows(2) {
            let (a, b) = (w[0], w[1]);
            let len = (((b.0 - a.0) as f64).powi(2) + ((b.1 - a.1) as f64).powi(2)).sqrt();
            let k = (len / step).ceil() as i32;
            for j in 1..k {
                let t = j as f64 / k as f64;
                out.push((
                    a.0 + ((b.0 - a.0) as f64 * t).round() as i32,
                    a.1 + ((b.1 - a.1) as f64 * t).round() as i32,
                ));
            }
        }
    }
    out
}

/// A rectangle of pixels `(x0, y0, x1, y1)`.
pub(super) type Rect = (i32, i32, i32, i32);

/// A rectangle as fractions (left, top, width, height) of another.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fractions(pub f64, pub f64, pub f64, pub f64);

impl Fractions {
    /// The rectangle in pixels of a `w × h` one.
    pub(super) fn within(self, w: u32, h: u32) -> Rect {
        let at = |f: f64, side: u32| (f * side as f64).round() as i32;
        (
            at(self.0, w),
            at(self.1, h),
            at(self.0 + self.2, w),
            at(self.1 + self.3, h),
        )
    }
}

/// The first place inside a `w × h` plotting area where a `size` box covers none of
/// `pixels` and no `blocked` rectangle (kept `margin` away from them and the axes): upper right, upper left, lower right,
/// lower left, upper middle, lower middle.
pub(super) fn free_spot(
    w: i32,
    h: i32,
    size: (i32, i32),
    pixels: &[(i32, i32)],
    blocked: &[Rect],
    margin: i32,
) -> Option<(i32, i32)> {
    let (bw, bh) = size;
    if bw + 2 * margin > w || bh + 2 * margin > h {
        return None;
    }
    let (left, right, mid) = (margin, w - margin - bw, (w - bw) / 2);
    let (top, bottom) = (margin, h - margin - bh);
    [
        (right, top),
        (left, top),
        (right, bottom),
        (left, bottom),
        (mid, top),
        (mid, bottom),
    ]
    .into_iter()
    .find(|&(x, y)| {
        let (x0, y0, x1, y1) = (x - margin, y - margin, x + bw + margin, y + bh + margin);
        !pixels
            .iter()
            .any(|&(px, py)| px >= x0 && px <= x1 && py >= y0 && py <= y1)
            && !blocked
                .iter()
                .any(|b| b.0 < x1 && b.2 > x0 && b.1 < y1 && b.3 > y0)
    })
}
