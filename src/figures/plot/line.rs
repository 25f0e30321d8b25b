//! Drawing a [`LinePlot`]: title, axes, curves, marks, axis labels and legend.

use std::path::Path;

use plotters::coord::combinators::{BindKeyPoints, WithKeyPoints};
use plotters::coord::ranged1d::{Ranged, ValueFormatter};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;

use super::legend::{covered_pixels, free_spot, Fractions, LegendBox, Rect};
use super::scene::{plot_err, write_scene, DrawResult, Scene};
use super::series::{
    finite_on, LegendAt, LinePlot, Series, YAxis, AXIS_LABEL_PX, DATA_COLUMNS, LEGEND_PX, SIZE_PX,
    TICK_PX, TITLE_PX,
};
use super::style::{draw_marker, draw_path, Dash, BAND_OPACITY};
use super::text::{self, Align, TextLook};
use super::ticks::{log_key_points, padded, snap_zero_on, LinLogCoord, Ticks};

/// Curves, marks and bands of a plot in pixels of its plotting area.
type PixelPaths = (
    Vec<Vec<(i32, i32)>>,
    Vec<Vec<(i32, i32)>>,
    Vec<Vec<(i32, i32)>>,
);

impl LinePlot {
    /// Finite points (positive on logarithmic axes) of every series, as drawn.
    fn points(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        let keep = finite_on(self.x_log, self.y_axis);
        self.series
            .iter()
            .flat_map(|s| {
                s.points
                    .iter()
                    .map(|&p| self.drawn_at(p))
                    .chain(s.band.iter().flat_map(|&(x, lo, hi)| [(x, lo), (x, hi)]))
            })
            .filter(move |p| keep(p))
            .chain(self.y_floor.map(|f| (f64::NAN, f)))
    }

    /// Where a point is drawn: a zero ordinate goes to the floor when there is one.
    fn drawn_at(&self, (x, y): (f64, f64)) -> (f64, f64) {
        match self.y_floor {
            Some(f) if y == 0.0 && self.y_axis == YAxis::Log => (x, f),
            _ => (x, y),
        }
    }

    fn extent(&self, pick: impl Fn((f64, f64)) -> f64) -> anyhow::Result<(f64, f64)> {
        let (lo, hi) = self
            .points()
            .map(pick)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v), b.max(v))
            });
        anyhow::ensure!(
            lo.is_finite(),
            "plot '{}' has no finite point",
            text::plain(&self.title)
        );
        Ok((lo, hi))
    }

    /// The y range clipped to the quantity's bounds.
    fn bounded(&self, (lo, hi): (f64, f64)) -> (f64, f64) {
        match self.y_bounds {
            Some((b0, b1)) => (lo.max(b0), hi.min(b1)),
            None => (lo, hi),
        }
    }

    /// Write `<stem>.png` and `<stem>.svg` in `dir`.
    pub fn write(&self, dir: &Path, stem: &str) -> DrawResult {
        write_scene(dir, stem, SIZE_PX, self)
    }

    /// Draw into `area` with text scaled by `scale`.
    /// `avoid`: rectangles the legend must not cover (e.g. an inset), as fractions (left, top,
    /// width, height) of the axes. Returns the axes' rectangle in pixels of `area`.
    pub(super) fn draw_on<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        scale: f64,
        avoid: &[Fractions],
    ) -> anyhow::Result<Rect> {
        if let (Err(_), Some(why)) = (self.extent(|p| p.0), &self.when_empty) {
            let title_h = self.draw_title(area, scale)?;
            let (w, h) = area.dim_in_pixel();
            text::draw(
                area,
                why,
                (w as i32 / 2, (h as i32 + title_h) / 2),
                Align::Middle,
                TextLook::new(TITLE_PX * scale * 0.8),
            )?;
            return Ok((0, title_h, w as i32, h as i32));
        }
        let (x0, x1) = self.extent(|p| p.0)?;
        let (x0, x1) = padded(x0, x1, self.x_log);
        let (y0, y1) = self.extent(|p| p.1)?;
        let x_ticks = if self.x_integer {
            Ticks::Integer
        } else if self.x_log {
            Ticks::log(x0, x1)
        } else {
            Ticks::Plain
        };
        let xr = x0..x1;
        let log_x = || -> WithKeyPoints<LogCoord<f64>> {
            xr.clone()
                .log_scale()
                .with_key_points(log_key_points(x0, x1))
        };
        let lin_x = || -> RangedCoordf64 { xr.clone().into() };
        match self.y_axis {
            YAxis::Log => {
                let (y0, y1) = self.bounded(padded(y0, y1, true));
                let yr = || -> WithKeyPoints<LogCoord<f64>> {
                    (y0..y1).log_scale().with_key_points(log_key_points(y0, y1))
                };
                let yt = Ticks::log(y0, y1);
                if self.x_log {
                    self.draw_chart(area, scale, log_x, yr, (x_ticks, yt), (y0, y1), avoid)
                } else {
                    self.draw_chart(area, scale, lin_x, yr, (x_ticks, yt), (y0, y1), avoid)
                }
            }
            YAxis::Linear => {
                let (y0, y1) = self.bounded(padded(y0, y1, false));
                let yr = || -> RangedCoordf64 { (y0..y1).into() };
                let ticks = (x_ticks, Ticks::Plain);
                if self.x_log {
                    self.draw_chart(area, scale, log_x, yr, ticks, (y0, y1), avoid)
                } else {
                    self.draw_chart(area, scale, lin_x, yr, ticks, (y0, y1), avoid)
                }
            }
            YAxis::LinLog { threshold } => {
                anyhow::ensure!(
                    threshold > 0.0,
                    "linear-log axis needs a positive threshold"
                );
                let hi = (y1 * 1.5).max(threshold * 2.0);
                let yr = || LinLogCoord { threshold, hi };
                let ticks = (x_ticks, Ticks::Powers);
                if self.x_log {
                    self.draw_chart(area, scale, log_x, yr, ticks, (0.0, hi), avoid)
                } else {
                    self.draw_chart(area, scale, lin_x, yr, ticks, (0.0, hi), avoid)
                }
            }
        }
    }

    /// Draw with the axes `x()` and `y()` (the y axis spanning `y_span`): title, axes with
    /// their labels, the curves, marks and legend.
    #[allow(clippy::too_many_arguments)]
    fn draw_chart<DB, X, Y>(
        &self,
        area: &DrawingArea<DB, Shift>,
        scale: f64,
        x: impl Fn() -> X,
        y: impl Fn() -> Y,
        ticks: (Ticks, Ticks),
        y_span: (f64, f64),
        avoid: &[Fractions],
    ) -> anyhow::Result<Rect>
    where
        DB: DrawingBackend,
        X: Ranged<ValueType = f64> + ValueFormatter<f64>,
        Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
    {
        let px = |v: f64| (v * scale).round().max(1.0) as i32;
        let title_h = self.draw_title(area, scale)?;
        let (_, body) = area.split_vertically(title_h);
        let entries: Vec<&Series> = self.series.iter().filter(|s| !s.label.is_empty()).collect();
        let legend = LegendBox::measure(area, &entries, scale);
        let x_area = px(TICK_PX + AXIS_LABEL_PX * 1.6 + 18.0);
        let y_area = px(TICK_PX * 4.0 + AXIS_LABEL_PX * 1.4 + 12.0);
        let build = |a: &DrawingArea<DB, Shift>| {
            ChartBuilder::on(a)
                .margin_top(px(4.0))
                .margin_right(px(26.0))
                .margin_left(px(6.0))
                .margin_bottom(px(4.0))
                .x_label_area_size(x_area)
                .y_label_area_size(y_area)
                .build_cartesian_2d(x(), y())
                .map_err(plot_err)
        };
        let marker_r = px(4.0).max(2);
        let margin = px(10.0);
        // Curves, marks and bands in pixels of the plotting area.
        let curves_of = |chart: &ChartContext<DB, Cartesian2d<X, Y>>| {
            self.pixel_paths(chart, x().range(), y_span)
        };
        // The legend inside the axes where it covers nothing, else below them.
        let spot = if entries.is_empty() || self.legend == LegendAt::Below {
            None
        } else {
            let probe = build(&body)?;
            let (curves, marks, bands) = curves_of(&probe);
            let all: Vec<Vec<(i32, i32)>> = curves.into_iter().chain(marks).chain(bands).collect();
            let pixels = covered_pixels(&all, 2.0);
            let (pw, ph) = probe.plotting_area().dim_in_pixel();
            let blocked: Vec<Rect> = avoid.iter().map(|f| f.within(pw, ph)).collect();
            free_spot(
                pw as i32,
                ph as i32,
                legend.size(entries.len(), 1),
                &pixels,
                &blocked,
                margin,
            )
        };
        let (chart_area, below) = if entries.is_empty() || spot.is_some() {
            (body, None)
        } else {
            let (bw, bh) = body.dim_in_pixel();
            let usable = bw as i32 - 2 * margin;
            let columns = (1..=entries.len())
                .rev()
                .find(|&c| legend.size(entries.len(), c).0 <= usable)
                .unwrap_or(1);
            let lh = legend.size(entries.len(), columns).1 + margin;
            let (top, bottom) = body.split_vertically(bh as i32 - lh);
            (top, Some((bottom, columns)))
        };
        let mut chart = build(&chart_area)?;
        let (xt, yt) = ticks;
        // Logarithmic axes bring their own ticks (log_key_points); linear ones about 7.
        let hint = 7;
        let (xs, ys) = (x().range(), y_span);
        let x_label = |v: &f64| xt.label(snap_zero_on(*v, xs.start, xs.end));
        let y_label = |v: &f64| match self.y_floor {
            Some(f) if (v / f - 1.0).abs() < 1e-9 => "exact".to_string(),
            _ => yt.label(snap_zero_on(*v, ys.0, ys.1)),
        };
        chart
            .configure_mesh()
            .disable_mesh()
            .x_labels(hint)
            .y_labels(hint)
            .x_label_formatter(&x_label)
            .y_label_formatter(&y_label)
            .set_all_tick_mark_size(px(6.0))
            .label_style(("sans-serif", TICK_PX * scale))
            .axis_style(BLACK.stroke_width(1))
            .draw()
            .map_err(plot_err)?;
        let plot = chart.plotting_area().strip_coord_spec();
        let (pw, ph) = plot.dim_in_pixel();
        // Box the axes (top and right edges).
        plot.draw(&PathElement::new(
            vec![(0, 0), (pw as i32 - 1, 0), (pw as i32 - 1, ph as i32 - 1)],
            BLACK.stroke_width(1),
        ))
        .map_err(plot_err)?;
        let (curves, marks, bands) = curves_of(&chart);
        self.draw_paths(&plot, (curves, marks, bands), scale, marker_r)?;
        self.draw_notes(&chart, &plot, scale)?;
        // Axis labels, outside the tick labels.
        let base = area.get_base_pixel();
        let (prx, pry) = plot.get_pixel_range();
        self.draw_axis_labels(area, (&prx, &pry), chart_area.get_pixel_range(), scale)?;
        legend.draw_placed(&plot, spot, below, &entries, marker_r)?;
        Ok((
            prx.start - base.0,
            pry.start - base.1,
            prx.end - base.0,
            pry.end - base.1,
        ))
    }

    /// The title, centred at the top; the height it takes.
    fn draw_title<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        scale: f64,
    ) -> anyhow::Result<i32> {
        let px = |v: f64| (v * scale).round().max(1.0) as i32;
        let (w, _) = area.dim_in_pixel();
        Ok(if self.title.is_empty() {
            px(12.0)
        } else {
            text::draw(
                area,
                &self.title,
                (w as i32 / 2, px(10.0)),
                Align::Middle,
                TextLook::new(TITLE_PX * scale),
            )?;
            px(TITLE_PX * 1.9)
        })
    }

    /// The hollow flags of the points of `s` that [`Self::pixel_paths`] keeps, in order.
    fn kept_hollow(&self, s: &Series) -> Vec<bool> {
        let keep = finite_on(self.x_log, self.y_axis);
        s.points
            .iter()
            .enumerate()
            .filter(|(_, &p)| keep(&self.drawn_at(p)))
            .map(|(i, _)| s.hollow.get(i).copied().unwrap_or(false))
            .collect()
    }

    /// The curves (points kept on the axes), the marks (`x_marks`, then `y_marks` and the
    /// floor across `xs`) and the bands (polygons: the upper edge forward, the lower back; a
    /// low end off a logarithmic axis drawn at the axis' bottom), in pixels of the plotting
    /// area of `chart`, whose y axis spans `y_span`.
    fn pixel_paths<DB, X, Y>(
        &self,
        chart: &ChartContext<DB, Cartesian2d<X, Y>>,
        xs: std::ops::Range<f64>,
        y_span: (f64, f64),
    ) -> PixelPaths
    where
        DB: DrawingBackend,
        X: Ranged<ValueType = f64> + ValueFormatter<f64>,
        Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
    {
        let keep = finite_on(self.x_log, self.y_axis);
        let base = chart.plotting_area().strip_coord_spec().get_base_pixel();
        let to_px = |p: &(f64, f64)| {
            let (a, b) = chart.backend_coord(p);
            (a - base.0, b - base.1)
        };
        let curves: Vec<Vec<(i32, i32)>> = self
            .series
            .iter()
            .map(|s| {
                s.points
                    .iter()
                    .map(|&p| self.drawn_at(p))
                    .filter(|p| keep(p))
                    .map(|p| to_px(&p))
                    .collect()
            })
            .collect();
        // Each band as a polygon: its upper edge forward, its lower edge back; a low
        // end off a logarithmic axis is drawn at the axis' bottom.
        let bands: Vec<Vec<(i32, i32)>> = self
            .series
            .iter()
            .map(|s| {
                let on_axis = |(x, y): (f64, f64)| {
                    if keep(&(x, y)) {
                        Some((x, y))
                    } else if x.is_finite() && y.is_finite() && (!self.x_log || x > 0.0) {
                        Some((x, y_span.0))
                    } else {
                        None
                    }
                };
                let upper = s.band.iter().filter_map(|&(x, _, hi)| on_axis((x, hi)));
                let lower: Vec<(f64, f64)> = s
                    .band
                    .iter()
                    .filter_map(|&(x, lo, _)| on_axis((x, lo)))
                    .collect();
                upper
                    .chain(lower.into_iter().rev())
                    .map(|p| to_px(&p))
                    .collect()
            })
            .collect();
        let marks: Vec<Vec<(i32, i32)>> = self
            .x_marks
            .iter()
            .map(|&xm| vec![to_px(&(xm, y_span.0)), to_px(&(xm, y_span.1))])
            .chain(
                self.y_marks
                    .iter()
                    .chain(&self.y_floor)
                    .map(|&ym| vec![to_px(&(xs.start, ym)), to_px(&(xs.end, ym))]),
            )
            .collect();
        (curves, marks, bands)
    }

    /// The bands (shaded), the marks (dashed, the floor dotted) lettered by
    /// `x_mark_labels`, then each curve's line and markers, on the plotting area `plot`.
    fn draw_paths<DB: DrawingBackend>(
        &self,
        plot: &DrawingArea<DB, Shift>,
        (curves, marks, bands): PixelPaths,
        scale: f64,
        marker_r: i32,
    ) -> DrawResult {
        let px = |v: f64| (v * scale).round().max(1.0) as i32;
        for (s, band) in self.series.iter().zip(bands) {
            if band.len() > 3 {
                plot.draw(&Polygon::new(
                    band,
                    s.rgb_color().mix(BAND_OPACITY).filled(),
                ))
                .map_err(plot_err)?;
            }
        }
        if !self.x_mark_labels.is_empty() {
            let grey = RGBColor(110, 110, 110);
            for (m, name) in marks.iter().zip(&self.x_mark_labels) {
                let top = m.iter().map(|p| p.1).min().unwrap_or(0).max(0);
                text::draw(
                    plot,
                    name,
                    (m[0].0 + px(4.0), top + px(3.0)),
                    Align::Start,
                    TextLook {
                        color: grey,
                        ..TextLook::new(LEGEND_PX * scale)
                    },
                )?;
            }
        }
        let floor_mark = marks.len() - usize::from(self.y_floor.is_some());
        for (i, m) in marks.into_iter().enumerate() {
            let dash = if i < floor_mark {
                Dash::Dashed
            } else {
                Dash::Dotted
            };
            draw_path(plot, m, dash, RGBColor(150, 150, 150).stroke_width(1))?;
        }
        for (s, pts) in self.series.iter().zip(curves) {
            let color = s.rgb_color();
            if s.width > 0 && pts.len() > 1 {
                draw_path(plot, pts.clone(), s.dash, color.stroke_width(s.width))?;
            }
            if let Some(m) = s.marker {
                let hollow = self.kept_hollow(s);
                for (i, &p) in pts.iter().enumerate() {
                    let h = hollow.get(i).copied().unwrap_or(false);
                    draw_marker(plot, m, p, marker_r, color, h)?;
                }
            }
        }
        Ok(())
    }

    /// The axis labels outside the tick labels: x centred under the plotting area (`prx`,
    /// `pry`), y upwards at the left of the chart's area (`ax`, `ay`).
    fn draw_axis_labels<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        (prx, pry): (&std::ops::Range<i32>, &std::ops::Range<i32>),
        (ax, ay): (std::ops::Range<i32>, std::ops::Range<i32>),
        scale: f64,
    ) -> DrawResult {
        let px = |v: f64| (v * scale).round().max(1.0) as i32;
        let base = area.get_base_pixel();
        let label_px = AXIS_LABEL_PX * scale;
        text::draw(
            area,
            &self.x_label,
            (
                (prx.start + prx.end) / 2 - base.0,
                ay.end - base.1 - px(4.0) - (1.05 * label_px) as i32,
            ),
            Align::Middle,
            TextLook::new(label_px),
        )?;
        text::draw(
            area,
            &self.y_label,
            (
                ax.start - base.0 + px(4.0) + (0.15 * label_px) as i32,
                (pry.start + pry.end) / 2 - base.1,
            ),
            Align::Middle,
            TextLook {
                upwards: true,
                ..TextLook::new(label_px)
            },
        )?;
        Ok(())
    }

    /// The notes written beside their points (grey, smaller), on the plotting area `plot`
    /// of `chart`.
    fn draw_notes<DB, X, Y>(
        &self,
        chart: &ChartContext<DB, Cartesian2d<X, Y>>,
        plot: &DrawingArea<DB, Shift>,
        scale: f64,
    ) -> DrawResult
    where
        DB: DrawingBackend,
        X: Ranged<ValueType = f64> + ValueFormatter<f64>,
        Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
    {
        let px = |v: f64| (v * scale).round().max(1.0) as i32;
        let keep = finite_on(self.x_log, self.y_axis);
        if !self.notes.is_empty() {
            let base = chart.plotting_area().strip_coord_spec().get_base_pixel();
            for (at, note) in &self.notes {
                let p = self.drawn_at(*at);
                if !keep(&p) {
                    continue;
                }
                let (a, b) = chart.backend_coord(&p);
                text::draw(
                    plot,
                    note,
                    (a - base.0 + px(7.0), b - base.1 - px(16.0)),
                    Align::Start,
                    TextLook {
                        color: RGBColor(90, 90, 90),
                        ..TextLook::new(LEGEND_PX * 0.85 * scale)
                    },
                )?;
            }
        }
        Ok(())
    }

    /// Rows `panel, series, x, y` of the plotted data.
    pub(super) fn data_rows(
        &self,
        panel: &str,
        out: &mut csv::Writer<std::fs::File>,
    ) -> DrawResult {
        let opt = |v: Option<f64>| v.map(|v| v.to_string()).unwrap_or_default();
        let (xq, yq) = (text::flat(&self.x_label), text::flat(&self.y_label));
        for s in &self.series {
            let series = text::flat(if s.label.is_empty() {
                &s.name
            } else {
                &s.label
            });
            let study = s.study.clone().unwrap_or_default();
            let (load, a_star) = (opt(s.w_over_w0), opt(s.a_star_over_ls2));
            for (i, (x, y)) in s.points.iter().enumerate() {
                let band = s.band_at(*x);
                let hollow = s.hollow.get(i).copied().unwrap_or(false);
                out.write_record([
                    panel,
                    &series,
                    &study,
                    &load,
                    &a_star,
                    &xq,
                    &x.to_string(),
                    &yq,
                    &y.to_string(),
                    &opt(band.map(|b| b.0)),
                    &opt(band.map(|b| b.1)),
                    if hollow { "true" } else { "false" },
                ])?;
            }
        }
        Ok(())
    }

    /// The plotted data as CSV beside the images, one row per drawn point ([`DATA_COLUMNS`]).
    pub fn write_data(&self, path: &Path) -> DrawResult {
        let mut w = csv::Writer::from_path(path)?;
        w.write_record(DATA_COLUMNS)?;
        self.data_rows(&text::flat(&self.title), &mut w)?;
        w.flush()?;
        Ok(())
    }
}

impl Scene for LinePlot {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult {
        self.draw_on(root, 1.0, &[]).map(|_| ())
    }
}
