//! A measured topography: heights on a rectangular grid with its pixel sizes, not periodic,
//! possibly with missing points, and its preparation before contact — the form removed
//! (mean, plane or curvature, by least squares) and the missing points counted. Lengths are
//! in metres (docs/CONVENTIONS.md); readers convert to them.

use thiserror::Error;

/// Heights `h[y · cols + x]` (metres, NaN where the instrument recorded nothing) with pixel
/// sizes `dx`, `dy` (metres).
#[derive(Debug, Clone, PartialEq)]
pub struct Topography {
    pub rows: usize,
    pub cols: usize,
    pub dx: f64,
    pub dy: f64,
    pub heights: Vec<f64>,
}

/// The form removed by [`Topography::remove_form`]: the least-squares polynomial in `x`,
/// `y` of that degree.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Form {
    /// The mean height (degree 0).
    Mean,
    /// A tilted plane `a + b x + c y` (degree 1, the usual levelling).
    Plane,
    /// A quadric `a + b x + c y + d x² + e x y + f y²` (degree 2: a curved sample).
    Curvature,
}

#[derive(Debug, Error, PartialEq)]
pub enum TopographyError {
    #[error("{rows} × {cols} heights given {got} values")]
    BadLength {
        rows: usize,
        cols: usize,
        got: usize,
    },
    #[error("pixel sizes must be finite and positive, got dx = {dx}, dy = {dy}")]
    BadPixel { dx: f64, dy: f64 },
    #[error(
        "{missing} of {total} points are missing (NaN), the first at row {row}, column {col}; \
         choose a fill rule, or crop them away"
    )]
    Missing {
        missing: usize,
        total: usize,
        row: usize,
        col: usize,
    },
    #[error("{value} at row {row}, column {col} is not a height (infinite)")]
    Infinite { row: usize, col: usize, value: f64 },
    #[error("the form cannot be fitted: {why}")]
    Singular { why: String },
}

impl Topography {
    /// Checks the shape and the pixel sizes; missing points (NaN) are allowed here and
    /// counted by [`Self::missing`].
    pub fn new(
        rows: usize,
        cols: usize,
        dx: f64,
        dy: f64,
        heights: Vec<f64>,
    ) -> Result<Self, TopographyError> {
        if heights.len() != rows * cols || rows == 0 || cols == 0 {
            return Err(TopographyError::BadLength {
                rows,
                cols,
                got: heights.len(),
            });
        }
        if !(dx.is_finite() && dx > 0.0 && dy.is_finite() && dy > 0.0) {
            return Err(TopographyError::BadPixel { dx, dy });
        }
        if let Some(i) = heights.iter().position(|h| h.is_infinite()) {
            return Err(TopographyError::Infinite {
                row: i / cols,
                col: i % cols,
                value: heights[i],
            });
        }
        Ok(Self {
            rows,
            cols,
            dx,
            dy,
            heights,
        })
    }

    /// How many points are missing (NaN).
    pub fn missing(&self) -> usize {
        self.heights.iter().filter(|h| h.is_nan()).count()
    }

    /// An error naming the count and the first missing point, if any is missing.
    pub fn refuse_missing(&self) -> Result<(), TopographyError> {
        match self.heights.iter().position(|h| h.is_nan()) {
            None => Ok(()),
            Some(i) => Err(TopographyError::Missing {
                missing: self.missing(),
                total: self.heights.len(),
                row: i / self.cols,
                col: i % self.cols,
            }),
        }
    }

    /// Subtracts the least-squares `form` fitted to the present points (missing ones stay
    /// missing) and returns its coefficients in the order of [`Form`]'s terms, for
    /// coordinates `x = (col − (cols − 1)/2)·dx`, `y = (row − (rows − 1)/2)·dy` (metres
    /// from the centre).
    pub fn remove_form(&mut self, form: Form) -> Result<Vec<f64>, TopographyError> {
        let terms = match form {
            Form::Mean => 1,
            Form::Plane => 3,
            Form::Curvature => 6,
        };
        let (cx, cy) = (
            0.5 * (self.cols - 1) as f64 * self.dx,
            0.5 * (self.rows - 1) as f64 * self.dy,
        );
        // Fitted in coordinates scaled to the half-widths (a well-conditioned system
        // whatever the unit), the coefficients converted back to metres at the end.
        let (sx, sy) = (cx.max(self.dx), cy.max(self.dy));
        let basis = |row: usize, col: usize| -> [f64; 6] {
            let (x, y) = (
                (col as f64 * self.dx - cx) / sx,
                (row as f64 * self.dy - cy) / sy,
            );
            [1.0, x, y, x * x, x * y, y * y]
        };
        // Normal equations, accumulated row by row in a fixed order.
        let mut a = vec![0.0; terms * terms];
        let mut b = vec![0.0; terms];
        for row in 0..self.rows {
            for col in 0..self.cols {
                let h = self.heights[row * self.cols + col];
                if h.is_nan() {
                    continue;
                }
                let f = basis(row, col);
                for i in 0..terms {
                    b[i] += f[i] * h;
                    for j in 0..terms {
                        a[i * terms + j] += f[i] * f[j];
                    }
                }
            }
        }
        let c =
            solve_symmetric(&mut a, &mut b, terms).ok_or_else(|| TopographyError::Singular {
                why: format!(
                    "{} present points do not determine a {form:?} (too few, or all on a line)",
                    self.heights.len() - self.missing()
                ),
            })?;
        for row in 0..self.rows {
            for col in 0..self.cols {
                let f = basis(row, col);
                let fit: f64 = (0..terms).map(|i| c[i] * f[i]).sum();
                self.heights[row * self.cols + col] -= fit;
            }
        }
        let unscale = [
            1.0,
            1.0 / sx,
            1.0 / sy,
            1.0 / (sx * sx),
            1.0 / (sx * sy),
            1.0 / (sy * sy),
        ];
        Ok(c.iter().zip(unscale).map(|(c, u)| c * u).collect())
    }

    /// Fills every missing point by harmonic (Laplace) interpolation from the present ones,
    /// as SurfaceTopography's `interpolate_undefined_data` does: each filled height is the
    /// pixel-size weighted mean of its 4 neighbours inside the map, solved by successive
    /// over-relaxation in node order (deterministic) until no height moves by more than
    /// 1e-12 of the present heights' range. Returns the number of points filled.
    pub fn fill_harmonic(&mut self) -> Result<usize, TopographyError> {
        let missing: Vec<usize> = (0..self.heights.len())
            .filter(|&i| self.heights[i].is_nan())
            .collect();
        let present = self.heights.len() - missing.len();
        if missing.is_empty() {
            return Ok(0);
        }
        if present == 0 {
            return Err(TopographyError::Singular {
                why: "every point is missing: nothing to fill from".into(),
            });
        }
        let (lo, hi) = self
            .heights
            .iter()
            .filter(|h| !h.is_nan())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &h| {
                (a.min(h), b.max(h))
            });
        let mean = self.heights.iter().filter(|h| !h.is_nan()).sum::<f64>() / present as f64;
        for &i in &missing {
            self.heights[i] = mean;
        }
        let (wx, wy) = (1.0 / (self.dx * self.dx), 1.0 / (self.dy * self.dy));
        let (rows, cols) = (self.rows, self.cols);
        let threshold = 1e-12 * (hi - lo).max(f64::MIN_POSITIVE);
        let omega = 1.9;
        for _ in 0..200_000 {
            let mut largest = 0.0f64;
            for &i in &missing {
                let (r, c) = (i / cols, i % cols);
                let (mut sum, mut weight) = (0.0, 0.0);
                for (ok, j, w) in [
                    (c > 0, i.wrapping_sub(1), wx),
                    (c + 1 < cols, i + 1, wx),
                    (r > 0, i.wrapping_sub(cols), wy),
                    (r + 1 < rows, i + cols, wy),
                ] {
                    if ok {
                        (sum, weight) = (sum + w * self.heights[j], weight + w);
                    }
                }
                let change = omega * (sum / weight - self.heights[i]);
                self.heights[i] += change;
                largest = largest.max(change.abs());
            }
            if largest <= threshold {
                return Ok(missing.len());
            }
        }
        Err(TopographyError::Singular {
            why: format!(
                "the harmonic fill of {} missing points did not settle; crop the largest gaps away",
                missing.len()
            ),
        })
    }

    /// The map on square pixels of the finer of `dx`, `dy`: heights linearly interpolated
    /// along the coarser axis at that spacing over the same extent (its first and last
    /// rows or columns kept), so that `(n − 1)·Δ_coarse / Δ_fine + 1` points, rounded down,
    /// replace its `n`. The finer axis is untouched; a square map is returned as it is.
    /// A missing neighbour makes the interpolated height missing.
    pub fn resampled_square(&self) -> Topography {
        let along_rows = self.dy > self.dx;
        let (coarse, fine, n) = if along_rows {
            (self.dy, self.dx, self.rows)
        } else {
            (self.dx, self.dy, self.cols)
        };
        if coarse == fine || n < 2 {
            return self.clone();
        }
        let ratio = coarse / fine;
        // The rounding guard keeps an exact multiple's last point.
        let m = ((n - 1) as f64 * ratio * (1.0 + 1e-12)).floor() as usize + 1;
        let at = |k: usize| -> (usize, f64) {
            // A point on a measured row keeps it (the ratio of two decimal sizes is rarely
            // exact in binary).
            let t = k as f64 / ratio;
            let t = if (t - t.round()).abs() < 1e-9 {
                t.round()
            } else {
                t
            };
            let i = (t.floor() as usize).min(n - 1);
            (i, t - i as f64)
        };
        let value = |a: f64, b: f64, w: f64| if w == 0.0 { a } else { (1.0 - w) * a + w * b };
        let (rows, cols) = if along_rows {
            (m, self.cols)
        } else {
            (self.rows, m)
        };
        let mut heights = Vec::with_capacity(rows * cols);
        for row in 0..rows {
            for col in 0..cols {
                let h = if along_rows {
                    let (i, w) = at(row);
                    let next = (i + 1).min(n - 1);
                    value(
                        self.heights[i * self.cols + col],
                        self.heights[next * self.cols + col],
                        w,
                    )
                } else {
                    let (i, w) = at(col);
                    let next = (i + 1).min(n - 1);
                    value(
                        self.heights[row * self.cols + i],
                        self.heights[row * self.cols + next],
                        w,
                    )
                };
                heights.push(h);
            }
        }
        Topography {
            rows,
            cols,
            dx: fine,
            dy: fine,
            heights,
        }
    }

    /// The rms slope `√⟨(∂h/∂x)² + (∂h/∂y)²⟩` by forward differences over the pairs of
    /// present neighbours (no wrap-around: the map is not periodic). Dimensionless.
    pub fn rms_slope(&self) -> f64 {
        let (mut sx, mut nx, mut sy, mut ny) = (0.0, 0usize, 0.0, 0usize);
        for row in 0..self.rows {
            for col in 0..self.cols {
                let h = self.heights[row * self.cols + col];
                if col + 1 < self.cols {
                    let d = (self.heights[row * self.cols + col + 1] - h) / self.dx;
                    if d.is_finite() {
                        (sx, nx) = (sx + d * d, nx + 1);
                    }
                }
                if row + 1 < self.rows {
                    let d = (self.heights[(row + 1) * self.cols + col] - h) / self.dy;
                    if d.is_finite() {
                        (sy, ny) = (sy + d * d, ny + 1);
                    }
                }
            }
        }
        let mean = |s: f64, n: usize| if n > 0 { s / n as f64 } else { 0.0 };
        (mean(sx, nx) + mean(sy, ny)).sqrt()
    }
}

/// Solves `A c = b` (`A` symmetric positive definite, `n × n`) by Cholesky; `None` if `A`
/// is singular to rounding.
fn solve_symmetric(a: &mut [f64], b: &mut [f64], n: usize) -> Option<Vec<f64>> {
    let scale = (0..n).map(|i| a[i * n + i]).fold(0.0f64, f64::max);
    for j in 0..n {
        let mut d = a[j * n + j];
        for k in 0..j {
            d -= a[j * n + k] * a[j * n + k];
        }
        // Also refuses a NaN pivot.
        if d.is_nan() || d <= 1e-12 * scale {
            return None;
        }
        let d = d.sqrt();
        a[j * n + j] = d;
        for i in j + 1..n {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = s / d;
        }
    }
    // L y = b, then Lᵀ c = y.
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= a[i * n + k] * b[k];
        }
        b[i] = s / a[i * n + i];
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            s -= a[k * n + i] * b[k];
        }
        b[i] = s / a[i * n + i];
    }
    Some(b.to_vec())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Resampling onto square pixels keeps the extent and the finer axis, reproduces a
    /// field linear along the coarser axis to rounding (linear interpolation is exact on
    /// it), keeps the measured rows where the grids meet, and leaves a square map alone.
    #[test]
    fn resampling_to_square_pixels_is_exact_on_a_linear_field() {
        let (rows, cols, dx, dy) = (7, 5, 0.5e-6, 1.25e-6);
        let f = |x: f64, y: f64| 3.0e-7 + 0.02 * x - 0.05 * y + 0.01 * (x * 1e7).sin() * 1e-7;
        let heights = (0..rows * cols)
            .map(|i| f((i % cols) as f64 * dx, (i / cols) as f64 * dy))
            .collect();
        let map = Topography::new(rows, cols, dx, dy, heights).unwrap();
        let square = map.resampled_square();
        // (7 − 1) × 2.5 + 1 = 16 rows over the same 7.5 µm.
        assert_eq!(
            (square.rows, square.cols, square.dx, square.dy),
            (16, 5, dx, dx)
        );
        for row in 0..square.rows {
            for col in 0..cols {
                let want = f(col as f64 * dx, row as f64 * dx);
                let got = square.heights[row * cols + col];
                // Linear in y: exact up to a few ulps of the 3e-7 m offset.
                assert!((got - want).abs() < 1e-20, "{row} {col}: {got} {want}");
            }
        }
        // Rows 0, 5, 10, 15 of the square map are rows 0, 2, 4, 6 of the measured one.
        for (new, old) in [(0, 0), (5, 2), (10, 4), (15, 6)] {
            assert_eq!(
                square.heights[new * cols..(new + 1) * cols],
                map.heights[old * cols..(old + 1) * cols]
            );
        }
        let transposed = Topography::new(cols, rows, dy, dx, vec![1.0; 35]).unwrap();
        let t = transposed.resampled_square();
        assert_eq!((t.rows, t.cols, t.dx, t.dy), (5, 16, dx, dx));
        let already = Topography::new(3, 4, dx, dx, (0..12).map(f64::from).collect()).unwrap();
        assert_eq!(already.resampled_square(), already);
    }

    /// A field with a known form added to a zero-mean pattern orthogonal to it is returned
    /// to that pattern, the form's coefficients recovered; missing points are left out of
    /// the fit and stay missing.
    fn pattern(rows: usize, cols: usize) -> Vec<f64> {
        // A product of sines with whole periods in both directions: orthogonal to 1, x, y
        // and the quadrics on the grid only approximately, so the fitted form is compared
        // with a tolerance; on the form alone it must be exact.
        (0..rows * cols)
            .map(|i| {
                let (r, c) = ((i / cols) as f64, (i % cols) as f64);
                1e-7 * (2.0 * std::f64::consts::PI * 3.0 * c / cols as f64).sin()
                    * (2.0 * std::f64::consts::PI * 2.0 * r / rows as f64).sin()
            })
            .collect()
    }

    #[test]
    fn removes_each_form_exactly() {
        let (rows, cols, dx, dy) = (30, 47, 2e-7, 3e-7);
        let truth = [4e-6, 0.02, -0.01, 3e3, -1e3, 2e3];
        for (form, terms) in [(Form::Mean, 1), (Form::Plane, 3), (Form::Curvature, 6)] {
            let (cx, cy) = (0.5 * (cols - 1) as f64 * dx, 0.5 * (rows - 1) as f64 * dy);
            let heights: Vec<f64> = (0..rows * cols)
                .map(|i| {
                    let (x, y) = ((i % cols) as f64 * dx - cx, (i / cols) as f64 * dy - cy);
                    let f = [1.0, x, y, x * x, x * y, y * y];
                    (0..terms).map(|k| truth[k] * f[k]).sum()
                })
                .collect();
            let mut t = Topography::new(rows, cols, dx, dy, heights).unwrap();
            t.heights[17] = f64::NAN;
            let c = t.remove_form(form).unwrap();
            for k in 0..terms {
                assert!(
                    (c[k] - truth[k]).abs() <= 1e-9 * truth[k].abs(),
                    "{form:?} term {k}: {} vs {}",
                    c[k],
                    truth[k]
                );
            }
            let worst = t
                .heights
                .iter()
                .filter(|h| !h.is_nan())
                .fold(0.0f64, |m, h| m.max(h.abs()));
            assert!(worst <= 1e-18, "{form:?}: residual {worst}");
            assert!(t.heights[17].is_nan());
        }
        // On a pattern plus a tilt, the plane removal leaves the pattern to within its
        // small overlap with the plane.
        let p = pattern(rows, cols);
        let tilted: Vec<f64> = p
            .iter()
            .enumerate()
            .map(|(i, v)| v + 0.05 * (i % cols) as f64 * dx)
            .collect();
        let mut t = Topography::new(rows, cols, dx, dy, tilted).unwrap();
        let c = t.remove_form(Form::Plane).unwrap();
        assert!((c[1] - 0.05).abs() < 1e-3, "slope {}", c[1]);
    }

    /// A plane's rms slope is the norm of its gradient; missing points and a singular fit
    /// are errors naming what is wrong.
    #[test]
    fn rms_slope_and_errors() {
        let (rows, cols) = (9, 12);
        let heights: Vec<f64> = (0..rows * cols)
            .map(|i| 0.3 * (i % cols) as f64 * 1e-6 - 0.4 * (i / cols) as f64 * 2e-6)
            .collect();
        let mut t = Topography::new(rows, cols, 1e-6, 2e-6, heights).unwrap();
        assert!((t.rms_slope() - 0.5).abs() < 1e-12, "{}", t.rms_slope());
        assert!(t.refuse_missing().is_ok());
        t.heights[2 * cols + 5] = f64::NAN;
        t.heights[7 * cols + 1] = f64::NAN;
        assert_eq!(
            t.refuse_missing(),
            Err(TopographyError::Missing {
                missing: 2,
                total: rows * cols,
                row: 2,
                col: 5
            })
        );
        assert!(
            (t.rms_slope() - 0.5).abs() < 1e-12,
            "missing pairs are skipped"
        );
        let line = Topography::new(1, 5, 1.0, 1.0, vec![0.0, 1.0, 2.0, 3.0, 4.0]).unwrap();
        assert!(matches!(
            line.clone().remove_form(Form::Plane),
            Err(TopographyError::Singular { .. })
        ));
        assert!(matches!(
            Topography::new(2, 2, 1.0, 1.0, vec![0.0, f64::INFINITY, 0.0, 0.0]),
            Err(TopographyError::Infinite { row: 0, col: 1, .. })
        ));
        assert!(matches!(
            Topography::new(2, 2, 0.0, 1.0, vec![0.0; 4]),
            Err(TopographyError::BadPixel { .. })
        ));
        assert!(matches!(
            Topography::new(2, 3, 1.0, 1.0, vec![0.0; 4]),
            Err(TopographyError::BadLength { .. })
        ));
    }

    /// The harmonic fill reproduces a discrete harmonic field (a tilted plane plus the saddle
    /// x² − y² on square pixels) at a lone missing point and in a 3 × 3 hole, to the
    /// fill's settling threshold; a point on an edge (where the fill has no neighbour
    /// outside) lies between its neighbours; a map with nothing present is an error.
    #[test]
    fn harmonic_fill_reproduces_harmonic_fields() {
        let (rows, cols, d) = (20, 24, 1e-6);
        let exact: Vec<f64> = (0..rows * cols)
            .map(|i| {
                let (y, x) = ((i / cols) as f64 - 9.5, (i % cols) as f64 - 11.5);
                1e-8 * (3.0 + 0.7 * x - 0.2 * y + 0.05 * (x * x - y * y))
            })
            .collect();
        let mut holed = exact.clone();
        let edge = 5;
        let mut gone = vec![3 * cols + 4];
        for r in 8..11 {
            for c in 14..17 {
                gone.push(r * cols + c);
            }
        }
        for &i in &gone {
            holed[i] = f64::NAN;
        }
        holed[edge] = f64::NAN;
        let mut t = Topography::new(rows, cols, d, d, holed).unwrap();
        assert_eq!(t.fill_harmonic(), Ok(gone.len() + 1));
        let around = [exact[edge - 1], exact[edge + 1], exact[edge + cols]];
        let (lo, hi) = around
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        assert!(lo <= t.heights[edge] && t.heights[edge] <= hi);
        let range = 1e-8 * 30.0;
        for &i in &gone {
            assert!(
                (t.heights[i] - exact[i]).abs() < 1e-9 * range,
                "point {i}: {} against {}",
                t.heights[i],
                exact[i]
            );
        }
        let mut empty = Topography::new(2, 2, d, d, vec![f64::NAN; 4]).unwrap();
        assert!(empty.fill_harmonic().is_err());
    }
}
