//! The line plot and its curves: what a plot holds, its sizes and the columns of its data
//! file (drawn by the sibling `line`).

use plotters::prelude::*;

use super::style::{Dash, Marker, PALETTE};

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

/// Size of a single plot: 6.4 × 4.8 in at 150 dpi.
pub const SIZE_PX: (u32, u32) = (960, 720);
/// Size of a figure with an inset: 7.5 × 6 in at 150 dpi, so that the inset's text is read
/// at [`INSET_SCALE`] of the plot's.
pub const INSET_SIZE_PX: (u32, u32) = (1125, 900);
/// Text scale of an inset: its tick labels 14 px high.
pub const INSET_SCALE: f64 = 0.8;
/// Size of a raster figure (map with its colour bar or legend): 6.4 × 5.6 in at 150 dpi.
pub const RASTER_SIZE_PX: (u32, u32) = (960, 840);

/// Text sizes in pixels of a plot at scale 1 (one font throughout).
pub(super) const TITLE_PX: f64 = 23.0;
pub(super) const AXIS_LABEL_PX: f64 = 21.0;
pub(super) const TICK_PX: f64 = 18.0;
pub(super) const LEGEND_PX: f64 = 17.0;

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
    pub(super) fn band_at(&self, x: f64) -> Option<(f64, f64)> {
        self.band.iter().find(|b| b.0 == x).map(|b| (b.1, b.2))
    }

    pub(super) fn rgb_color(&self) -> RGBColor {
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

pub(super) fn finite_on(x_log: bool, y_axis: YAxis) -> impl Fn(&(f64, f64)) -> bool {
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
