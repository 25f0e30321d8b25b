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
fn count_axes_label_whole_numbers_only() {
    assert_eq!(axis_tick(&2.0, true), "2");
    assert_eq!(axis_tick(&20.0, true), "20");
    assert_eq!(axis_tick(&1.5, true), "");
    assert_eq!(axis_tick(&1.5, false), "1.5");
    assert_eq!(axis_tick(&0.001, false), "0.001");
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
