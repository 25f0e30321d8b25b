use plotters::coord::ranged1d::Ranged;

use super::legend::{covered_pixels, free_spot};
use super::ticks::{log_key_points, padded, snap_zero_on, LinLogCoord, Ticks};
use super::*;

#[test]
fn linear_then_log_axis_is_continuous_and_monotonic() {
    let c = LinLogCoord {
        threshold: 1e-5,
        hi: 1.0,
    };
    // Linear part: proportional; log part: one unit per decade; continuous at the joint.
    assert_eq!(c.t(0.0), 0.0);
    assert!((c.t(5e-6) - 0.5).abs() < 1e-15);
    assert!((c.t(1e-5) - 1.0).abs() < 1e-15);
    assert!((c.t(1e-5 * (1.0 + 1e-12)) - 1.0).abs() < 1e-11);
    assert!((c.t(1e-3) - 3.0).abs() < 1e-12);
    let pixels: Vec<i32> = [0.0, 2e-6, 1e-5, 1e-4, 1e-2, 1.0]
        .iter()
        .map(|v| c.map(v, (500, 0)))
        .collect();
    assert_eq!(pixels.first(), Some(&500));
    assert_eq!(pixels.last(), Some(&0));
    assert!(pixels.windows(2).all(|w| w[1] < w[0]), "{pixels:?}");
    assert_eq!(
        c.key_points(10usize),
        vec![0.0, 5e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 1.0]
    );
}

#[test]
fn tick_labels_are_numbers_and_powers_of_ten_without_e_notation() {
    assert_eq!(Ticks::Integer.label(2.0), "2");
    assert_eq!(Ticks::Integer.label(20.0), "20");
    assert_eq!(Ticks::Integer.label(1.5), "");
    assert_eq!(Ticks::Plain.label(1.5), "1.5");
    assert_eq!(Ticks::Plain.label(0.001), "0.001");
    assert_eq!(Ticks::Plain.label(-0.25), "−0.25");
    assert_eq!(Ticks::Plain.label(5e-6), "5×10⁻⁶");
    assert_eq!(Ticks::Plain.label(2.5e5), "2.5×10⁵");
    assert_eq!(Ticks::Plain.label(1e-4), "10⁻⁴");
    // Decades: powers labelled, the minor ticks between them not.
    assert_eq!(Ticks::Decades.label(1e-4), "10⁻⁴");
    assert_eq!(Ticks::Decades.label(1.0), "10⁰");
    assert_eq!(Ticks::Decades.label(1e12), "10¹²");
    assert_eq!(Ticks::Decades.label(3e-4), "");
    assert_eq!(Ticks::OneTwoFive.label(0.02), "0.02");
    assert_eq!(Ticks::OneTwoFive.label(0.03), "");
    assert_eq!(Ticks::Powers.label(0.0), "0");
    assert_eq!(Ticks::Powers.label(5e-6), "5×10⁻⁶");
    assert_eq!(Ticks::Powers.label(1e-3), "10⁻³");
    assert_eq!(Ticks::log(1e-5, 2e-3), Ticks::Decades);
    assert_eq!(Ticks::log(0.01, 0.1), Ticks::OneTwoFive);
    assert_eq!(Ticks::log(0.011, 0.3), Ticks::OneTwoFive);
    assert_eq!(Ticks::log(0.025, 0.07), Ticks::Plain);
    assert_eq!(
        log_key_points(0.025, 0.07),
        vec![0.03, 0.04, 0.05, 0.06, 0.07]
    );
    assert_eq!(log_key_points(0.5, 20.0).len(), 5 + 9 + 2);
    assert_eq!(number(snap_zero(-1.39e-17, 0.2)), "0");
    assert_eq!(number(snap_zero(1e-6, 1e-5)), "10⁻⁶");
    // Only an axis that holds 0 snaps to it: on 0.5 … 10¹² (Fig. 6) the tick 1 is 10⁰.
    assert_eq!(snap_zero_on(-1.39e-17, 0.0, 0.2), 0.0);
    let decades = Ticks::log(0.5, 1e12);
    assert_eq!(decades.label(snap_zero_on(1.0, 0.5, 1e12)), "10⁰");
    assert_eq!(decades.label(snap_zero_on(1000.0, 0.5, 1e12)), "10³");
    // Rounding that carries the mantissa to 10 moves the exponent.
    assert_eq!(number(9.9999e-6), "10⁻⁵");
}

#[test]
fn log_axes_snap_to_nearby_powers_of_ten() {
    let (lo, hi) = padded(1.3e-3, 0.8, true);
    assert_eq!((lo, hi), (1e-3, 1.0));
    // Data just above a power of ten keeps its margin rather than gain a decade.
    let (lo, _) = padded(1.1e-3, 0.8, true);
    assert!((lo - 1.1e-3 / 1.15).abs() < 1e-15);
    // Far from a power: only the margin.
    let (lo, hi) = padded(4e-3, 0.4, true);
    assert!((lo - 4e-3 / 1.15).abs() < 1e-15 && (hi - 0.46).abs() < 1e-12);
}

#[test]
fn the_legend_goes_where_no_data_is() {
    // A curve along the top edge: the upper corners are taken, the lower right is free.
    let curve = vec![(0, 5), (400, 5)];
    let px = covered_pixels(&[curve], 2.0);
    assert_eq!(
        free_spot(400, 300, (100, 60), &px, &[], 10),
        Some((290, 230))
    );
    // A diagonal from lower left to upper right leaves the upper left free.
    let diag = covered_pixels(&[vec![(0, 300), (400, 0)]], 2.0);
    assert_eq!(
        free_spot(400, 300, (100, 60), &diag, &[], 10),
        Some((10, 10))
    );
    // An inset in the lower right moves it to the lower left.
    assert_eq!(
        free_spot(400, 300, (100, 60), &px, &[(250, 150, 400, 300)], 10),
        Some((10, 230))
    );
    // Data everywhere: nowhere inside.
    let full: Vec<(i32, i32)> = (0..40)
        .flat_map(|i| (0..30).map(move |j| (10 * i, 10 * j)))
        .collect();
    assert_eq!(free_spot(400, 300, (100, 60), &full, &[], 10), None);
}

#[test]
fn raster_resampling_keeps_every_pixel_when_enlarging() {
    let raster = RasterPlot {
        title: String::new(),
        x_label: String::new(),
        y_label: String::new(),
        rows: 2,
        cols: 3,
        rgb: (0..18).collect(),
        colorbar: None,
        legend: Vec::new(),
    };
    let out = raster.resampled(6, 4);
    // Each source pixel (r, c) fills the 2×2 block at (2r, 2c).
    for y in 0..4 {
        for x in 0..6 {
            let (r, c) = (y / 2, x / 2);
            let d = 3 * (y * 6 + x);
            assert_eq!(out[d], (3 * (r * 3 + c)) as u8);
        }
    }
}

#[test]
fn panels_fill_their_rows() {
    // (panels, at most columns) → (rows, columns): the fewest rows, then no row mostly empty.
    for (n, max, want) in [
        (1, 3, (1, 1)),
        (2, 3, (1, 2)),
        (3, 3, (1, 3)),
        (4, 3, (2, 2)),
        (5, 3, (2, 3)),
        (6, 3, (2, 3)),
        (7, 3, (3, 3)),
        (4, 1, (4, 1)),
    ] {
        let (rows, cols) = grid(n, max);
        assert_eq!((rows, cols), want, "{n} panels, at most {max} columns");
        assert!(
            rows * cols >= n && rows * cols - n < cols,
            "{n}: a row left empty"
        );
    }
}
