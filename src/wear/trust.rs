//! The trust band of K(W) for a measured map: how far K and 𝒦 move under what the map
//! cannot tell. At each load (held as the same mean nominal pressure, so the same force per
//! area on every variant):
//! - **edge**: without the clusters cut by the map's border (their true areas are unknown);
//! - **d\***: at `A*` for d* scaled by the user's two factors (`--d-star-factors`);
//! - **pixel**: on the map coarsened ×2 (2 × 2 block means), solved again;
//! - **map size**: on the map's halves and quarters as windows, each solved alone, giving
//!   the smallest and largest K among them.
//!
//! The band is the range of all of these with K itself. The default K keeps the edge-cut
//! clusters (docs/CONVENTIONS.md says why).

use crate::clusters::{self, Boundary, Connectivity};
use crate::contact::interface::Interface;
use crate::contact::solver::SolverConfig;
use crate::contact::window::sweep_window;
use crate::statistics::{wear_at, WearAt};
use crate::topography::Topography;
use serde_json::{json, Value};

/// The band's settings: the physics of the run they vary.
pub struct Physics {
    pub e_star_pa: f64,
    pub hardness_pa: Option<f64>,
    pub a_star_m2: f64,
    pub cfg: SolverConfig,
}

/// K and 𝒦 with the edge-cut clusters left out, and at A* scaled by `a_star_scales`, from
/// one load's cluster areas and whether each touches the border (`a_star_px` the run's A*
/// in pixels).
pub fn edge_and_d_star(
    areas: &[u64],
    cut: &[bool],
    a_star_px: f64,
    a_star_scales: (f64, f64),
) -> Value {
    let inner: Vec<u64> = areas
        .iter()
        .zip(cut)
        .filter(|(_, &c)| !c)
        .map(|(&a, _)| a)
        .collect();
    let no_edge = (!inner.is_empty()).then(|| wear_at(&inner, a_star_px));
    let low = wear_at(areas, a_star_px * a_star_scales.0);
    let high = wear_at(areas, a_star_px * a_star_scales.1);
    json!({
        "k_archard_no_edge": no_edge.as_ref().map(|m| m.k_archard),
        "k_upscaled_no_edge": no_edge.as_ref().map(|m| m.k_upscaled),
        "k_archard_d_star_low": low.k_archard,
        "k_upscaled_d_star_low": low.k_upscaled,
        "k_archard_d_star_high": high.k_archard,
        "k_upscaled_d_star_high": high.k_upscaled,
    })
}

/// The map coarsened ×2: the mean of each 2 × 2 block (a last odd row or column dropped),
/// on pixels twice as large. None if it would have fewer than 2 × 2 pixels.
pub fn coarsened(map: &Topography) -> Option<Topography> {
    let (rows, cols) = (map.rows / 2, map.cols / 2);
    if rows < 2 || cols < 2 {
        return None;
    }
    let at = |r: usize, c: usize| map.heights[r * map.cols + c];
    let heights = (0..rows * cols)
        .map(|k| {
            let (r, c) = (2 * (k / cols), 2 * (k % cols));
            0.25 * (at(r, c) + at(r, c + 1) + at(r + 1, c) + at(r + 1, c + 1))
        })
        .collect();
    Topography::new(rows, cols, 2.0 * map.dx, 2.0 * map.dy, heights).ok()
}

/// The map's windows: `parts` = 2 halves across its longer side, or 4 quarters. Windows of
/// fewer than 2 × 2 pixels are left out.
pub fn windows(map: &Topography, parts: usize) -> Vec<Topography> {
    let (split_rows, split_cols) = match parts {
        2 if map.cols >= map.rows => (1, 2),
        2 => (2, 1),
        _ => (2, 2),
    };
    let (h, w) = (map.rows / split_rows, map.cols / split_cols);
    if h < 2 || w < 2 {
        return Vec::new();
    }
    let mut out = Vec::new();
    for i in 0..split_rows {
        for j in 0..split_cols {
            let heights = (0..h * w)
                .map(|k| map.heights[(i * h + k / w) * map.cols + j * w + k % w])
                .collect();
            if let Ok(t) = Topography::new(h, w, map.dx, map.dy, heights) {
                out.push(t);
            }
        }
    }
    out
}

/// K and 𝒦 of `map` at the mean nominal pressures `pressures_pa`, solved alone on its
/// free-boundary half-space and labelled without wrap-around.
pub fn solve(
    map: &Topography,
    pressures_pa: &[f64],
    physics: &Physics,
) -> Result<Vec<WearAt>, String> {
    let slope = map.rms_slope();
    let scale = physics.e_star_pa * slope;
    let loads: Vec<f64> = pressures_pa.iter().map(|p| p / scale).collect();
    let interface = Interface::from_hardness(physics.hardness_pa.map(|h| h / scale))
        .map_err(|e| e.to_string())?;
    let a_star_px = physics.a_star_m2 / (map.dx * map.dy);
    let mut out = Vec::with_capacity(loads.len());
    sweep_window(
        map,
        physics.e_star_pa,
        &loads,
        &physics.cfg,
        interface,
        |_, p, _| {
            let contact: Vec<bool> = p.iter().map(|&v| v > 0.0).collect();
            let l = clusters::label_with(
                &contact,
                map.rows,
                map.cols,
                Connectivity::Eight,
                Boundary::Open,
            )
            .map_err(|e| e.to_string())?;
            let areas: Vec<u64> = l.clusters.iter().map(|c| c.area_px).collect();
            out.push(wear_at(&areas, a_star_px));
            Ok(())
        },
    )
    .map_err(|e| e.to_string())?;
    Ok(out)
}

/// The band's solved rows (pixel, halves, quarters) added to each load's `rows`, and the
/// band's ends over every variant with K itself. A variant that cannot be solved (too
/// small, flat, not converged) is null, and said in the returned notes.
pub fn solved_rows(
    map: &Topography,
    pressures_pa: &[f64],
    physics: &Physics,
    rows: &mut [Value],
    mut progress: impl FnMut(),
) -> Vec<String> {
    let mut notes = Vec::new();
    let mut run = |name: &str, maps: Vec<Topography>| -> Option<Vec<Vec<WearAt>>> {
        if maps.is_empty() {
            notes.push(format!("{name}: the map is too small to split"));
            return None;
        }
        let mut all = Vec::new();
        for m in &maps {
            match solve(m, pressures_pa, physics) {
                Ok(k) => all.push(k),
                Err(e) => {
                    notes.push(format!("{name}: {e}"));
                    return None;
                }
            }
            progress();
        }
        Some(all)
    };
    let pixel = run("pixel ×2", coarsened(map).into_iter().collect());
    let halves = run("halves", windows(map, 2));
    let quarters = run("quarters", windows(map, 4));
    for (i, row) in rows.iter_mut().enumerate() {
        let pick = |v: &Option<Vec<Vec<WearAt>>>, f: fn(&WearAt) -> f64| -> Option<(f64, f64)> {
            v.as_ref().map(|all| {
                all.iter()
                    .map(|k| f(&k[i]))
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                        (a.min(x), b.max(x))
                    })
            })
        };
        for (kind, f) in [
            (
                "k_archard",
                (|m: &WearAt| m.k_archard) as fn(&WearAt) -> f64,
            ),
            ("k_upscaled", |m: &WearAt| m.k_upscaled),
        ] {
            row[format!("{kind}_pixel_x2")] = json!(pick(&pixel, f).map(|p| p.0));
            for (name, v) in [("halves", &halves), ("quarters", &quarters)] {
                let r = pick(v, f);
                row[format!("{kind}_{name}_min")] = json!(r.map(|p| p.0));
                row[format!("{kind}_{name}_max")] = json!(r.map(|p| p.1));
            }
            let ends = [
                "",
                "_no_edge",
                "_d_star_low",
                "_d_star_high",
                "_pixel_x2",
                "_halves_min",
                "_halves_max",
                "_quarters_min",
                "_quarters_max",
            ]
            .iter()
            .filter_map(|s| row[format!("{kind}{s}")].as_f64())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                (a.min(x), b.max(x))
            });
            row[format!("{kind}_band_low")] = json!(ends.0);
            row[format!("{kind}_band_high")] = json!(ends.1);
        }
    }
    notes
}

/// The band's solves at the loads `w_over_w0` (held as the mean pressures W/W0·rms
/// slope·E*, as the window states them, bit for bit) with a progress bar, added to `rows`;
/// none unless `solve` (`--no-trust-band`). Returns the record of the band for
/// preparation.json, with the factors on d* its edge and d* columns used.
pub fn band(
    map: &Topography,
    w_over_w0: &[f64],
    slope: f64,
    physics: Physics,
    d_star_factors: &[f64],
    solve: bool,
    rows: &mut [Value],
) -> Value {
    let notes = match solve {
        false => {
            vec!["not solved (--no-trust-band): pixel ×2, halves and quarters are null".to_string()]
        }
        true => {
            let bar = indicatif::ProgressBar::new(7).with_style(
                indicatif::ProgressStyle::with_template(
                    "trust band {bar:30} {pos}/{len} solves (pixel ×2, halves, quarters), {elapsed}",
                )
                .expect("a valid template"),
            );
            let pressures: Vec<f64> = w_over_w0
                .iter()
                .map(|w| w * slope * physics.e_star_pa)
                .collect();
            let notes = solved_rows(map, &pressures, &physics, rows, || bar.inc(1));
            bar.finish_and_clear();
            for n in &notes {
                crate::note!("note: trust band: {n}");
            }
            notes
        }
    };
    json!({
        "d_star_factors": d_star_factors,
        "variants": "K itself; without edge-cut clusters; at d* times each factor; the map coarsened ×2 (2 × 2 block means); its halves and quarters as windows (smallest and largest K); every load held at the same mean nominal pressure",
        "notes": notes,
    })
}

/// The loads table's columns of the band, in order.
pub const BAND_COLUMNS: [&str; 20] = [
    "k_archard_band_low",
    "k_archard_band_high",
    "k_upscaled_band_low",
    "k_upscaled_band_high",
    "k_archard_no_edge",
    "k_upscaled_no_edge",
    "k_archard_d_star_low",
    "k_archard_d_star_high",
    "k_upscaled_d_star_low",
    "k_upscaled_d_star_high",
    "k_archard_pixel_x2",
    "k_upscaled_pixel_x2",
    "k_archard_halves_min",
    "k_archard_halves_max",
    "k_upscaled_halves_min",
    "k_upscaled_halves_max",
    "k_archard_quarters_min",
    "k_archard_quarters_max",
    "k_upscaled_quarters_min",
    "k_upscaled_quarters_max",
];

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp(rows: usize, cols: usize) -> Topography {
        let heights = (0..rows * cols).map(|k| k as f64).collect();
        Topography::new(rows, cols, 1.0, 2.0, heights).unwrap()
    }

    #[test]
    fn coarsening_averages_blocks_and_doubles_the_pixel() {
        let c = coarsened(&ramp(5, 6)).unwrap();
        assert_eq!((c.rows, c.cols, c.dx, c.dy), (2, 3, 2.0, 4.0));
        // Block (0, 0): heights 0, 1, 6, 7.
        assert_eq!(c.heights[0], 3.5);
        // Block (1, 2): rows 2–3, columns 4–5: 16, 17, 22, 23.
        assert_eq!(c.heights[5], 19.5);
        assert!(coarsened(&ramp(3, 8)).is_none());
    }

    #[test]
    fn halves_split_the_longer_side_and_quarters_both() {
        let m = ramp(4, 6);
        let h = windows(&m, 2);
        assert_eq!(h.len(), 2);
        assert_eq!((h[0].rows, h[0].cols), (4, 3));
        assert_eq!(h[1].heights[0], 3.0);
        assert_eq!(h[1].heights[3], 9.0);
        let q = windows(&m, 4);
        assert_eq!(q.len(), 4);
        assert_eq!((q[3].rows, q[3].cols), (2, 3));
        assert_eq!(q[3].heights[0], 15.0);
        let tall = windows(&ramp(6, 4), 2);
        assert_eq!((tall[0].rows, tall[0].cols), (3, 4));
        assert!(windows(&ramp(3, 3), 4).is_empty());
    }
}
