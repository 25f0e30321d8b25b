//! x-y-z lists (`.xyz`): one point per line, `x y z` separated by white space, commas or
//! semicolons, on a regular grid in any order, as Gwyddion's XYZ export and most instrument
//! software write them. A comment header may state the units as Gwyddion writes them
//! (`# Lateral units: µm`, `# Value units: m`); without it the positions and heights share
//! one unit, the one the user states. Read as SurfaceTopography's `XYZReader` reads a map:
//! the x spacing is the distance between the two smallest x, the y spacing likewise, every
//! point is binned to its nearest grid node, and a grid with a node empty or filled twice
//! is refused. A height of `nan` is a missing point.

#[cfg(test)]
use std::path::Path;

use super::measured::{length_unit_m, MeasuredMap, Source};
use super::text::{Table, GRID_TOLERANCE_PX};

/// One axis of the grid: its spacing and the bin of every point. A point farther than
/// [`GRID_TOLERANCE_PX`] of a pixel from its node is refused, not snapped.
fn axis(values: &[f64], name: &str) -> Result<(usize, Vec<usize>, f64), String> {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    sorted.dedup();
    let (origin, spacing) = match sorted.as_slice() {
        [a, b, ..] => (*a, b - a),
        _ => {
            return Err(format!(
                "every point has the same {name}: a map needs two or more"
            ))
        }
    };
    let mut bins = Vec::with_capacity(values.len());
    for (k, v) in values.iter().enumerate() {
        let at = (v - origin) / spacing;
        let node = at.round();
        if (at - node).abs() > GRID_TOLERANCE_PX {
            return Err(format!(
                "point {} has {name} = {v}, {:.3} of a pixel off the grid of spacing {spacing} (from the two smallest {name}); points within {GRID_TOLERANCE_PX} of a pixel of a node are on it: not a regular grid",
                k + 1,
                (at - node).abs()
            ));
        }
        bins.push(node as usize);
    }
    let count = bins.iter().max().map_or(0, |m| m + 1);
    Ok((count, bins, spacing))
}

/// The units of a Gwyddion comment header, in metres per unit.
fn header_units(line: &str, lateral: &mut Option<f64>, value: &mut Option<f64>) {
    let body = line.trim_start_matches('#').trim();
    if let Some((key, unit)) = body.split_once(':') {
        let unit = length_unit_m(unit.trim());
        match key.trim() {
            "Lateral units" => *lateral = unit,
            "Value units" => *value = unit,
            _ => {}
        }
    }
}

/// Read an x-y-z list from its file (for the tests; the reader sniffs the content first).
#[cfg(test)]
pub(super) fn read(path: &Path) -> Result<MeasuredMap, String> {
    let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
    let table = super::text::table(&super::text::decode(&bytes)?)?;
    if table.cols == 2 {
        return Err("two columns, a line scan; contact needs a map (x y z)".into());
    }
    if table.cols != 3 {
        return Err(format!(
            "{} columns are not three numbers x y z",
            table.cols
        ));
    }
    from_table(&table)
}

/// An x-y-z list from its table of three columns.
pub(super) fn from_table(table: &Table) -> Result<MeasuredMap, String> {
    let (mut lateral, mut value) = (None, None);
    for line in &table.header {
        if line.starts_with('#') {
            header_units(line, &mut lateral, &mut value);
        }
    }
    let column =
        |k: usize| -> Vec<f64> { table.values.iter().skip(k).step_by(3).copied().collect() };
    let (x, y, z) = (column(0), column(1), column(2));
    if let Some(k) = x
        .iter()
        .zip(&y)
        .position(|(a, b)| !(a.is_finite() && b.is_finite()))
    {
        return Err(format!("point {}: its position is not a finite x y", k + 1));
    }
    if z.is_empty() {
        return Err("holds no point (x y z per line)".into());
    }
    let (cols, col_of, dx) = axis(&x, "x")?;
    let (rows, row_of, dy) = axis(&y, "y")?;
    if rows.saturating_mul(cols) != z.len() {
        return Err(format!(
            "{} points on a grid of {rows} × {cols} nodes (spacing {dx} × {dy}, from the two smallest x and y): not a regular grid",
            z.len()
        ));
    }
    let mut heights = vec![f64::NAN; rows * cols];
    let mut filled = vec![false; rows * cols];
    for (k, (&r, &c)) in row_of.iter().zip(&col_of).enumerate() {
        let node = r * cols + c;
        if filled[node] {
            return Err(format!(
                "points {} and another fall on one grid node (x = {}, y = {}): not a regular grid of spacing {dx} × {dy}",
                k + 1,
                x[k],
                y[k]
            ));
        }
        filled[node] = true;
        heights[node] = z[k];
    }
    if let Some(node) = filled.iter().position(|f| !f) {
        return Err(format!(
            "the grid of {rows} × {cols} nodes (spacing {dx} × {dy}) has no point at row {}, column {}: not a regular grid",
            node / cols,
            node % cols
        ));
    }
    let (height_unit_m, pixel_m, pixel_file_units) = match (lateral, value) {
        (Some(l), Some(v)) => (Some(v), Some((dx * l, dy * l)), None),
        _ => (None, None, Some((dx, dy))),
    };
    Ok(MeasuredMap {
        rows,
        cols,
        heights: heights
            .iter()
            .map(|h| h * height_unit_m.unwrap_or(1.0))
            .collect(),
        height_unit_m,
        pixel_m,
        pixel_file_units,
        source: Source::Xyz,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(text: &str) -> (tempfile::TempDir, std::path::PathBuf) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.xyz");
        std::fs::write(&path, text).unwrap();
        (dir, path)
    }

    /// Points in any order land on their nodes, rows along y; units from the header.
    #[test]
    fn a_shuffled_grid_with_units() {
        let (_d, path) = write(
            "# Channel: Height\n# Lateral units: µm\n# Value units: nm\n\
             0.5 0 2\n0 0 1\n0 0.25 3\n0.5 0.25 nan\n1.0 0 5\n1.0 0.25 6\n",
        );
        let m = read(&path).unwrap();
        assert_eq!((m.rows, m.cols), (2, 3));
        assert_eq!(m.pixel_m, Some((0.5e-6, 0.25e-6)));
        assert_eq!(m.height_unit_m, Some(1e-9));
        let expected = [1.0, 2.0, 5.0, 3.0, f64::NAN, 6.0].map(|v| v * 1e-9);
        for (a, b) in m.heights.iter().zip(expected) {
            assert!(a == &b || (a.is_nan() && b.is_nan()), "{a} against {b}");
        }
    }

    /// Without units, the spacing is kept in the file's unit; gaps, doubles and line scans
    /// are refused, each saying why.
    #[test]
    fn unitless_and_broken_grids() {
        let (_d, path) = write("0 0 1\n2 0 1\n0 3 1\n2 3 1\n");
        let m = read(&path).unwrap();
        assert_eq!((m.pixel_m, m.pixel_file_units), (None, Some((2.0, 3.0))));
        for (text, says) in [
            ("0 0 1\n1 0 1\n0 1 1\n", "3 points on a grid of 2 × 2"),
            ("0 0 1\n1 0 1\n0 1 1\n0 1 2\n", "fall on one grid node"),
            (
                "0 0 1\n1e-9 0 1\n1000 0 1\n0 1 1\n1e-9 1 1\n1000 1 1\n",
                "not a regular grid",
            ),
            ("0 1\n1 2\n", "line scan"),
            (
                "0 0 1\n1 0 1\n0 1 1\n1.45 1 1\n",
                "0.450 of a pixel off the grid",
            ),
        ] {
            let (_d, path) = write(text);
            let e = read(&path).unwrap_err();
            assert!(e.contains(says), "{text:?}: {e}");
        }
    }
}
