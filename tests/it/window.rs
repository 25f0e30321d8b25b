//! Contact of a measured map (`contact::window`): rectangular, odd-sided, in metres and
//! pascals, on the free-boundary half-space. A sphere in a 127 × 95 window against Hertz,
//! and against the same sphere solved on a 128 × 128 map with nothing to embed; a sphere on
//! rectangular pixels against Hertz's circle.

use std::f64::consts::PI;

use wearcoef::contact::interface::Interface;
use wearcoef::contact::reference::Hertz;
use wearcoef::contact::solver::SolverConfig;
use wearcoef::contact::window::sweep_window;
use wearcoef::topography::Topography;

const DX: f64 = 1e-6; // m
const R_CURV: f64 = 1e-3; // m
const E_STAR: f64 = 1e11; // Pa
const CENTRE: (usize, usize) = (63, 47); // row, column

fn sphere(rows: usize, cols: usize) -> Topography {
    sphere_on(rows, cols, DX, CENTRE)
}

/// The sphere on pixels `DX × dy`, centred on node `centre` (row, column).
fn sphere_on(rows: usize, cols: usize, dy: f64, centre: (usize, usize)) -> Topography {
    let heights = (0..rows * cols)
        .map(|i| {
            let y = ((i / cols) as f64 - centre.0 as f64) * dy;
            let x = ((i % cols) as f64 - centre.1 as f64) * DX;
            -(x * x + y * y) / (2.0 * R_CURV)
        })
        .collect();
    Topography::new(rows, cols, DX, dy, heights).unwrap()
}

/// The pressure (Pa) on the map under the total force `load` (N), and the contact count.
fn solve(map: &Topography, load: f64) -> (Vec<f64>, usize) {
    let pixel = map.dx * map.dy;
    let area = (map.rows * map.cols) as f64 * pixel;
    let w_over_w0 = load / (E_STAR * map.rms_slope() * area);
    let cfg = SolverConfig {
        tolerance: 1e-10,
        ..SolverConfig::default()
    };
    let mut pressure = Vec::new();
    let (_, results) = sweep_window(
        map,
        E_STAR,
        &[w_over_w0],
        &cfg,
        Interface::Elastic,
        |_, p, _| {
            pressure = p.to_vec();
            Ok(())
        },
    )
    .unwrap();
    let r = &results[0];
    let carried: f64 = pressure.iter().sum::<f64>() * pixel;
    assert!(
        (carried / load - 1.0).abs() < 1e-9,
        "load {carried} N against {load} N"
    );
    assert!((r.mean_pressure * area / load - 1.0).abs() < 1e-12);
    (pressure, r.n_contact_px)
}

/// Contact radius 30 pixels, 17 from the nearest edge of the window: Hertz's contact
/// radius within 2 %, peak within 0.5 % (the periodic Hertz test's tolerances, same
/// resolution); and the pressure equal, node by node to 1e-6 of the peak, to that of the
/// square map where the window's far nodes are real heights (a solve with nothing
/// embedded): the embedding changes nothing but the cost.
#[test]
fn a_rectangular_odd_window_is_the_free_boundary_solution() {
    let a = 30.0 * DX;
    let hertz = Hertz {
        load: 4.0 * a.powi(3) * E_STAR / (3.0 * R_CURV),
        r_curv: R_CURV,
        e_star: E_STAR,
    };
    let (rows, cols) = (127, 95);
    let (p, contact) = solve(&sphere(rows, cols), hertz.load);
    let a_num = (contact as f64 * DX * DX / PI).sqrt();
    assert!(
        (a_num / a - 1.0).abs() <= 0.02,
        "contact radius {a_num} vs {a}"
    );
    let peak = p.iter().cloned().fold(0.0, f64::max);
    assert!(
        (peak / hertz.peak_pressure() - 1.0).abs() <= 0.005,
        "peak {peak} Pa vs {} Pa",
        hertz.peak_pressure()
    );
    let (q, square_contact) = solve(&sphere(128, 128), hertz.load);
    assert_eq!(contact, square_contact);
    for r in 0..rows {
        for c in 0..cols {
            let (mine, theirs) = (p[r * cols + c], q[r * 128 + c]);
            assert!(
                (mine - theirs).abs() <= 1e-6 * peak,
                "({r}, {c}): {mine} Pa in the window, {theirs} Pa on the square"
            );
        }
    }
}

/// Pixels 2.466 times longer along y than along x (those of SurfaceTopography's x3p-2.x3p,
/// 0.128 × 0.315 µm) solved as measured: a sphere still touches in Hertz's circle. Contact
/// area `n·Δx·Δy` within 4 % of πa² and peak within 1 % (a is resolved by 24 pixels along y,
/// 60 along x: the tolerances of the square test at that coarser resolution); the extents
/// along x and along y each within two of their pixels of 2a: the circle, not an ellipse.
#[test]
fn rectangular_pixels_give_the_hertz_circle() {
    let aspect = 2.466;
    let dy = aspect * DX;
    let a = 60.0 * DX;
    let hertz = Hertz {
        load: 4.0 * a.powi(3) * E_STAR / (3.0 * R_CURV),
        r_curv: R_CURV,
        e_star: E_STAR,
    };
    let (rows, cols, centre) = (81, 161, (40, 80));
    let (p, contact) = solve(&sphere_on(rows, cols, dy, centre), hertz.load);
    let area = contact as f64 * DX * dy;
    assert!(
        (area / (PI * a * a) - 1.0).abs() <= 0.04,
        "contact area {area} m² vs {}",
        PI * a * a
    );
    let peak = p.iter().cloned().fold(0.0, f64::max);
    assert!(
        (peak / hertz.peak_pressure() - 1.0).abs() <= 0.01,
        "peak {peak} Pa vs {} Pa",
        hertz.peak_pressure()
    );
    let touching = |r: usize, c: usize| p[r * cols + c] > 0.0;
    let along_x = (0..cols).filter(|&c| touching(centre.0, c)).count() as f64 * DX;
    let along_y = (0..rows).filter(|&r| touching(r, centre.1)).count() as f64 * dy;
    assert!(
        (along_x - 2.0 * a).abs() <= 2.0 * DX,
        "extent along x {along_x} m vs {}",
        2.0 * a
    );
    assert!(
        (along_y - 2.0 * a).abs() <= 2.0 * dy,
        "extent along y {along_y} m vs {}",
        2.0 * a
    );
}

/// `wear --resample` puts a map of 1 × 2.466 µm pixels on square 1 µm ones (its 81 rows
/// over 80 × 2.466 µm become 198) and records what it was; the sphere's contact area under
/// Hertz's force is then πa² within the rectangular test's 4 %, the linear interpolation's
/// height error (Δy²/8R = 0.8 nm) being 5000 times smaller than the interference a²/R.
#[test]
fn resampled_on_request_the_sphere_keeps_its_hertz_area() {
    let dy = 2.466 * DX;
    let a = 60.0 * DX;
    let load = 4.0 * a.powi(3) * E_STAR / (3.0 * R_CURV);
    let map = sphere_on(81, 161, dy, (40, 80));
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let heights = ndarray::Array2::from_shape_vec((map.rows, map.cols), map.heights).unwrap();
    ndarray_npy::write_npy(d.join("sphere.npy"), &heights).unwrap();
    let out = super::run_in(
        d,
        &[
            "wear",
            "--input",
            "sphere.npy",
            "--height-unit",
            "m",
            "--pixel-size",
            "1e-6",
            "--pixel-size-y",
            "2.466e-6",
            "--form",
            "none",
            "--resample",
            "--e-star",
            "1e11Pa",
            "--d-star",
            "10um",
            "--loads",
            &format!("{load}N"),
            "--no-trust-band",
            "-o",
            "out",
        ],
    );
    assert!(out.status.success(), "{out:?}");
    let prep: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.join("out/preparation.json")).unwrap()).unwrap();
    assert_eq!(
        (prep["rows"].as_u64(), prep["cols"].as_u64()),
        (Some(198), Some(161))
    );
    assert_eq!(prep["pixel_size_y_m"], prep["pixel_size_x_m"]);
    assert_eq!(prep["resampled_from"]["rows"], 81);
    assert_eq!(prep["resampled_from"]["pixel_size_y_m"], 2.466e-6);
    let loads = super::table(&d.join("out/loads.parquet"));
    let area_um2 = super::f64s(&loads, "real_contact_area_um2")[0];
    let hertz_um2 = PI * a * a * 1e12;
    assert!(
        (area_um2 / hertz_um2 - 1.0).abs() <= 0.04,
        "{area_um2} µm² vs {hertz_um2}"
    );
}

/// A load far beyond full contact: the far nodes of the square stay out of contact (they
/// are sunk by the deflection of the largest load, not only by the height range, which a
/// smooth map under W/W0 = 50 presses through), and the window is in full contact.
#[test]
fn far_beyond_full_contact_the_embedding_holds() {
    for dy in [DX, 2.466 * DX] {
        let map = sphere_on(40, 50, dy, (20, 25));
        let cfg = SolverConfig {
            tolerance: 1e-10,
            ..SolverConfig::default()
        };
        let (_, results) = sweep_window(
            &map,
            E_STAR,
            &[0.5, 50.0],
            &cfg,
            Interface::Elastic,
            |_, _, _| Ok(()),
        )
        .unwrap_or_else(|e| panic!("pixels {DX} × {dy} m: {e}"));
        assert_eq!(results[1].n_contact_px, 40 * 50, "full contact");
        assert!(results[0].n_contact_px < 40 * 50);
    }
}

/// Heights that are not numbers are refused by name.
#[test]
fn window_refuses_what_it_cannot_solve() {
    let cfg = SolverConfig::default();
    let mut map = sphere(20, 30);
    map.heights[31] = f64::NAN;
    let e = sweep_window(
        &map,
        E_STAR,
        &[0.01],
        &cfg,
        Interface::Elastic,
        |_, _, _| Ok(()),
    )
    .unwrap_err();
    assert!(e.to_string().contains("row 1, column 1"), "{e}");
}
