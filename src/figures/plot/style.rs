//! Line dashes, markers and the palette.

use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;

use super::scene::{plot_err, DrawResult};

/// How a curve's line is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dash {
    Solid,
    Dashed,
    Dotted,
    /// Long dashes with short gaps.
    LongDashed,
}

/// The marker drawn at each point of a curve.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Marker {
    Circle,
    Square,
    Triangle,
    Diamond,
    /// A triangle pointing down.
    TriangleDown,
    Cross,
    /// A hollow circle twice the size of the others, around a point (a chosen setting).
    Ring,
}

impl Marker {
    /// Distinct markers for the curves of one figure, in order.
    pub const ALL: [Marker; 5] = [
        Marker::Circle,
        Marker::Square,
        Marker::Triangle,
        Marker::Diamond,
        Marker::TriangleDown,
    ];
}

/// Draw marker `m` of radius `r` at pixel `c` of `area`.
pub(super) fn draw_marker<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    m: Marker,
    c: (i32, i32),
    r: i32,
    color: RGBColor,
    hollow: bool,
) -> DrawResult {
    if hollow && !matches!(m, Marker::Cross | Marker::Ring) {
        // White inside, the colour as a 2-px outline.
        draw_marker(area, m, c, r, WHITE, false)?;
        return draw_outline(area, m, c, r, color);
    }
    let fill = color.filled();
    let (x, y) = c;
    match m {
        Marker::Circle => area.draw(&Circle::new(c, r, fill)),
        Marker::Square => area.draw(&Rectangle::new([(x - r, y - r), (x + r, y + r)], fill)),
        Marker::Triangle => area.draw(&Polygon::new(
            vec![(x, y - r - 1), (x + r + 1, y + r), (x - r - 1, y + r)],
            fill,
        )),
        Marker::Diamond => area.draw(&Polygon::new(
            vec![
                (x, y - r - 1),
                (x + r + 1, y),
                (x, y + r + 1),
                (x - r - 1, y),
            ],
            fill,
        )),
        Marker::TriangleDown => area.draw(&Polygon::new(
            vec![(x, y + r + 1), (x + r + 1, y - r), (x - r - 1, y - r)],
            fill,
        )),
        Marker::Cross => {
            let s = color.stroke_width(2);
            area.draw(&PathElement::new(vec![(x - r, y - r), (x + r, y + r)], s))
                .map_err(plot_err)?;
            area.draw(&PathElement::new(vec![(x - r, y + r), (x + r, y - r)], s))
        }
        Marker::Ring => area.draw(&Circle::new(c, 2 * r + 2, color.stroke_width(2))),
    }
    .map_err(plot_err)
}

/// The outline of a filled marker (Circle, Square, Triangles, Diamond).
fn draw_outline<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    m: Marker,
    c: (i32, i32),
    r: i32,
    color: RGBColor,
) -> DrawResult {
    let s = color.stroke_width(2);
    let (x, y) = c;
    let closed = |v: Vec<(i32, i32)>| {
        let mut v = v;
        v.push(v[0]);
        PathElement::new(v, s)
    };
    match m {
        Marker::Square => area.draw(&closed(vec![
            (x - r, y - r),
            (x + r, y - r),
            (x + r, y + r),
            (x - r, y + r),
        ])),
        Marker::Triangle => area.draw(&closed(vec![
            (x, y - r - 1),
            (x + r + 1, y + r),
            (x - r - 1, y + r),
        ])),
        Marker::Diamond => area.draw(&closed(vec![
            (x, y - r - 1),
            (x + r + 1, y),
            (x, y + r + 1),
            (x - r - 1, y),
        ])),
        Marker::TriangleDown => area.draw(&closed(vec![
            (x, y + r + 1),
            (x + r + 1, y - r),
            (x - r - 1, y - r),
        ])),
        _ => area.draw(&Circle::new(c, r, s)),
    }
    .map_err(plot_err)
}

/// Draw a polyline of pixels with `dash`.
pub(super) fn draw_path<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    pts: Vec<(i32, i32)>,
    dash: Dash,
    style: ShapeStyle,
) -> DrawResult {
    let (on, off) = match dash {
        Dash::Solid => return area.draw(&PathElement::new(pts, style)).map_err(plot_err),
        Dash::Dashed => (8, 5),
        Dash::Dotted => (2, 4),
        Dash::LongDashed => (16, 5),
    };
    area.draw(&DashedPathElement::new(pts, on, off, style))
        .map_err(plot_err)
}

/// Opacity of a 95 % band's fill (curves and legend samples).
pub(super) const BAND_OPACITY: f64 = 0.2;

/// Okabe & Ito's colour-blind-safe palette (yellow last: faint on white).
pub(super) const PALETTE: [RGBColor; 8] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
    RGBColor(0, 0, 0),
    RGBColor(240, 228, 66),
];
