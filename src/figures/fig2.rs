//! Fig. 2: the surface and contact maps of one realization (2a–d), contact area, largest
//! cluster and dN/dA_c over the sweep (2e–f), and the realization audit of 2e–f.

use super::common::{tolerance_line, Drawn, NpyData};
use super::plot::{
    viridis, ColorBar, Dash, Layout, LinePlot, Marker, Panels, RasterPlot, Series, YAxis,
};
use crate::clusters::{label_with, Boundary, Connectivity};
use crate::stages::analytic::AreaLoadSlopeRecord;
use crate::stages::audits::{FIG2_CURVE_TOLERANCE, TABLE};
use crate::stages::contact::contact_file;
use crate::store::inputs::Inputs;
use crate::store::table::{f64_column, u32_column};

/// Fig. 2e (A_c and the largest cluster, one panel each, with their 95 % bands) and 2f
/// (dN/dA_c) against W/W0; the loads of the contact maps (Fig. 2b–d) marked by dashed lines
/// lettered b, c, d.
/// With the small-load law `A_c/L² = κ W/W₀` fitted by the analytic stage drawn dashed over
/// its fitted range.
/// Input 0: the study's statistics; input 1: its realization audit; input 2: its analytic fit.
pub fn fig2ef(inputs: &Inputs, marked_loads: &[f64]) -> anyhow::Result<Vec<(String, Drawn)>> {
    let df = inputs.table(0, "statistics", "loads.parquet")?;
    let df = &df;
    let w = f64_column(df, "w_over_w0")?;
    let dn = f64_column(df, "dn_dac_per_ls2_mean")?;
    let realizations = super::common::realizations_of(inputs, 0)?;
    let ensemble = if realizations >= crate::resample::MIN_REALIZATIONS as u64 {
        format!("mean of {realizations} realizations, shaded: 95 % interval")
    } else {
        format!(
            "mean of {realizations} realizations; no interval (an interval needs {})",
            crate::resample::MIN_REALIZATIONS
        )
    };
    // One panel per quantity (they differ by three decades and have different units).
    let panel = |title: &str, y_label: &str, column: &str, color: usize| {
        let mean = f64_column(df, &format!("{column}_mean"))?;
        let (low, high) = (
            f64_column(df, &format!("{column}_ci95_low"))?,
            f64_column(df, &format!("{column}_ci95_high"))?,
        );
        let mut p = LinePlot::new(title, "W/W_0", y_label, true, YAxis::Log);
        p.x_marks = marked_loads.to_vec();
        p.x_mark_labels = ["b", "c", "d"].iter().map(|s| s.to_string()).collect();
        p.series = vec![
            Series {
                band: (0..w.len())
                    .filter(|&i| low[i].is_finite() && high[i].is_finite())
                    .map(|i| (w[i], low[i], high[i]))
                    .collect(),
                ..Series::line(
                    format!("{y_label} ({ensemble})"),
                    w.iter().copied().zip(mean).collect(),
                    color,
                )
            },
            Series {
                dash: Dash::Dashed,
                rgb: Some((150, 150, 150)),
                width: 1,
                ..Series::line("loads of the maps of Fig. 2b, c, d", Vec::new(), 0)
            },
        ];
        anyhow::Ok(p)
    };
    let mut area = panel("Fig. 2e: contact area", "A_c/L^2", "area_fraction", 0)?;
    if let Some(fit) = AreaLoadSlopeRecord::of(&inputs.of(2, "analytic")?.results)? {
        let ([lo, hi], kappa) = (fit.w_over_w0_range, fit.kappa);
        anyhow::ensure!(
            kappa.is_finite() && lo.is_finite() && hi.is_finite(),
            "analytic area_load_slope is not finite: {fit:?}"
        );
        area.series.push(Series {
            dash: Dash::Dashed,
            rgb: Some((0, 0, 0)),
            width: 1,
            ..Series::line(
                format!(
                    "κ W/W_0, κ = {kappa:.2} (fit for W/W_0 ≤ {})",
                    (hi * 1e4).round() / 1e4
                ),
                vec![(lo, kappa * lo), (hi, kappa * hi)],
                0,
            )
        });
    }
    let largest = panel(
        "Fig. 2e: largest cluster",
        "largest cluster A/λ_s^2",
        "largest_area_over_ls2",
        1,
    )?;
    let e = Panels {
        plots: vec![area, largest],
        layout: Layout::Grid { columns: 1 },
    };
    let mut f = LinePlot::new(
        "Fig. 2f: growth of the cluster count",
        "W/W_0",
        "dN/d(A_c/λ_s^2)",
        true,
        YAxis::Linear,
    );
    f.x_marks = marked_loads.to_vec();
    f.x_mark_labels = ["b", "c", "d"].iter().map(|s| s.to_string()).collect();
    let (dn_low, dn_high) = (
        f64_column(df, "dn_dac_per_ls2_ci95_low")?,
        f64_column(df, "dn_dac_per_ls2_ci95_high")?,
    );
    f.series = vec![
        Series {
            band: (0..w.len())
                .filter(|&i| dn_low[i].is_finite() && dn_high[i].is_finite())
                .map(|i| (w[i], dn_low[i], dn_high[i]))
                .collect(),
            ..Series::line(
                format!("dN/dA_c ({ensemble}; each realization's central differences)"),
                w.iter().copied().zip(dn).collect(),
                0,
            )
        },
        Series {
            rgb: Some((0, 0, 0)),
            width: 1,
            name: "zero".into(),
            ..Series::line("", vec![(w[0], 0.0), (w[w.len() - 1], 0.0)], 0)
        },
    ];
    let mut out = vec![
        ("fig2e".into(), Drawn::Panels(e)),
        ("fig2f".into(), Drawn::Line(f)),
    ];
    out.extend(fig2_convergence(inputs)?);
    Ok(out)
}

/// Colours of the contact maps of Fig. 2b–d.
const OUT_OF_CONTACT: (u8, u8, u8) = (0, 0, 0);
const SMALL_CLUSTER: (u8, u8, u8) = (255, 215, 0);
const LARGE_CLUSTER: (u8, u8, u8) = (220, 30, 30);
/// Fig. 2a (the surface of realization 0) and 2b–d (its contact maps at the kept loads,
/// clusters with `A ≤ A*` yellow and `A > A*` red on black).
/// Inputs: the surface and the contact sweep of realization 0. A `measured` map is drawn
/// in its own rows × cols, heights in metres, its clusters not joined across the border.
pub fn fig2_maps(
    inputs: &Inputs,
    maps: &[(usize, f64)],
    lambda_s_px: f64,
    a_star_over_ls2: f64,
    measured: bool,
) -> anyhow::Result<Vec<(String, Drawn)>> {
    let heights_file = inputs.file(0, "surface", "heights.npy")?;
    let (rows_h, cols_h, heights) = if measured {
        crate::io::read_map_npy(&heights_file)?
    } else {
        let (n, heights) = crate::io::read_square_f64(&heights_file)?;
        (n, n, heights)
    };
    let (boundary, axis, height_label) = if measured {
        (Boundary::Open, ("x/L_x", "y/L_y"), "height (m)")
    } else {
        (
            Boundary::Periodic,
            ("x/L", "y/L"),
            "height h/L (rms slope 1)",
        )
    };
    let (lo, hi) = heights
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let span = if hi > lo { hi - lo } else { 1.0 };
    let rgb: Vec<u8> = heights
        .iter()
        .flat_map(|&h| {
            let (r, g, b) = viridis((h - lo) / span);
            [r, g, b]
        })
        .collect();
    let mut out = vec![(
        "fig2a".to_string(),
        Drawn::Raster(
            RasterPlot {
                title: "Fig. 2a: rough surface (realization 0)".into(),
                x_label: axis.0.into(),
                y_label: axis.1.into(),
                rows: rows_h,
                cols: cols_h,
                rgb,
                colorbar: Some(ColorBar {
                    lo,
                    hi,
                    label: height_label.into(),
                }),
                legend: Vec::new(),
            },
            NpyData::F64(vec![rows_h, cols_h], heights),
        ),
    )];
    let a_star_px = a_star_over_ls2 * lambda_s_px * lambda_s_px;
    for (panel, &(index, w)) in ["b", "c", "d"].iter().zip(maps) {
        let path = inputs.file(1, "contact", &contact_file(index))?;
        let (rows, cols, map, _) = crate::io::read_contact_map(&path)?;
        let lab = label_with(&map, rows, cols, Connectivity::Eight, boundary)?;
        // 0: out of contact, 1: A ≤ A*, 2: A > A*.
        let class: Vec<u8> = lab
            .labels
            .iter()
            .map(|&id| match id {
                0 => 0,
                id if lab.clusters[id as usize - 1].area_px as f64 > a_star_px => 2,
                _ => 1,
            })
            .collect();
        let rgb = class
            .iter()
            .flat_map(|&c| {
                let (r, g, b) = [OUT_OF_CONTACT, SMALL_CLUSTER, LARGE_CLUSTER][c as usize];
                [r, g, b]
            })
            .collect();
        out.push((
            format!("fig2{panel}"),
            Drawn::Raster(
                RasterPlot {
                    title: format!("Fig. 2{panel}: contact clusters at W/W_0 = {w:.3}"),
                    x_label: axis.0.into(),
                    y_label: axis.1.into(),
                    rows,
                    cols,
                    rgb,
                    colorbar: None,
                    legend: vec![
                        ("A ≤ A*".into(), Some(SMALL_CLUSTER)),
                        ("A > A*".into(), Some(LARGE_CLUSTER)),
                        ("out of contact".into(), Some(OUT_OF_CONTACT)),
                        (format!("A* = {a_star_over_ls2} λ_s^2"), None),
                    ],
                },
                NpyData::U8(vec![rows, cols], class),
            ),
        ));
    }
    Ok(out)
}

/// The realization audit of Fig. 2e–f drawn: the largest deviation over loads of the first-r
/// means from the full ensemble's, per quantity (input 1).
fn fig2_convergence(inputs: &Inputs) -> anyhow::Result<Vec<(String, Drawn)>> {
    let audit = inputs.of(1, "audits")?;
    let Ok(path) = inputs.file(1, "audits", TABLE) else {
        // Fewer than two realizations: the audit has a verdict and no table.
        return Ok(vec![(
            "convergence".into(),
            Drawn::Result(audit.results.clone()),
        )]);
    };
    let table = crate::store::table::read(&path)?;
    let realizations: Vec<f64> = u32_column(&table, "realizations")?
        .into_iter()
        .map(|r| r.unwrap_or(0) as f64)
        .collect();
    let total = realizations.iter().copied().fold(2.0, f64::max);
    let deviation = |name: &str| -> anyhow::Result<Vec<f64>> {
        f64_column(&table, &format!("{name}_max_rel_deviation"))
    };
    let rows: Vec<(f64, [f64; 3])> = {
        let (a, c, l) = (
            deviation("area")?,
            deviation("count")?,
            deviation("largest")?,
        );
        (0..realizations.len())
            .map(|i| (realizations[i], [a[i], c[i], l[i]]))
            .collect()
    };
    let mut plot = LinePlot::new(
        "Fig. 2e–f: first r realizations vs all",
        "realizations r",
        "max relative deviation of the mean over loads",
        false,
        YAxis::Log,
    );
    plot.x_integer = true;
    let labels = [
        "A_c (Fig. 2e)",
        "largest cluster (Fig. 2e)",
        "N (Fig. 2f: dN/dA_c)",
    ];
    for (c, (q, label)) in [0usize, 2, 1].iter().zip(labels).enumerate() {
        plot.series.push(Series {
            marker: Some(Marker::ALL[c]),
            ..Series::line(
                label,
                rows.iter()
                    .filter(|x| x.1[*q] > 0.0)
                    .map(|x| (x.0, x.1[*q]))
                    .collect(),
                c,
            )
        });
    }
    plot.series.push(Series {
        width: 1,
        ..tolerance_line(FIG2_CURVE_TOLERANCE, 2.0, total)
    });
    Ok(vec![
        ("fig2_convergence".into(), Drawn::Table(table)),
        ("fig2_convergence".into(), Drawn::Line(plot)),
        ("convergence".into(), Drawn::Result(audit.results.clone())),
    ])
}
