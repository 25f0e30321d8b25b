//! The page of a `wear` run: one figure of three panels (K and 𝒦 against the force, the
//! PSD with its self-affine fit, the clusters' area CCDF at each load) and `index.html`
//! showing it beside the loads table and the preparation.

use std::path::Path;

use crate::figures::plot::{Dash, Layout, LinePlot, Marker, Panels, Series, YAxis};
use crate::psd::PsdBin;

/// What the page shows, gathered from the run.
pub struct Page<'a> {
    pub rows: &'a [serde_json::Value],
    /// Cluster areas (µm²) per load.
    pub areas_um2: Vec<Vec<f64>>,
    pub psd: &'a [PsdBin],
    pub report: &'a serde_json::Value,
}

fn coefficients(p: &Page) -> LinePlot {
    let mut plot = LinePlot::new(
        "Wear coefficients",
        "normal force W (N)",
        "coefficient",
        false,
        YAxis::Linear,
    );
    let at = |key: &str| -> Vec<(f64, f64)> {
        p.rows
            .iter()
            .filter_map(|r| Some((r["force_n"].as_f64()?, r[key].as_f64()?)))
            .collect()
    };
    // The trust band (edge, d*, pixel, map size) shaded around each, where it was solved.
    let band = |kind: &str| -> Vec<(f64, f64, f64)> {
        p.rows
            .iter()
            .filter_map(|r| {
                Some((
                    r["force_n"].as_f64()?,
                    r[format!("{kind}_band_low")].as_f64()?,
                    r[format!("{kind}_band_high")].as_f64()?,
                ))
            })
            .collect()
    };
    plot.series.push(Series {
        marker: Some(Marker::Circle),
        band: band("k_archard"),
        ..Series::line("K (eq. 5), shaded: its trust band", at("k_archard"), 0)
    });
    plot.series.push(Series {
        marker: Some(Marker::Square),
        band: band("k_upscaled"),
        ..Series::line("𝒦 (eq. 7), shaded: its trust band", at("k_upscaled"), 1)
    });
    plot.y_bounds = Some((0.0, 1.0));
    plot.when_empty = Some("no load has a cluster: K and 𝒦 are undefined".into());
    plot
}

fn spectrum(p: &Page) -> LinePlot {
    let mut plot = LinePlot::new(
        "Radially averaged PSD",
        "q (rad/m)",
        "C (m^4)",
        true,
        YAxis::Log,
    );
    // Bins 12 decades below the largest are at the double FFT's rounding floor (a
    // generated spectrum with nothing past λ_s): left out of the plot, kept in psd.parquet.
    let top = p.psd.iter().fold(0.0f64, |a, b| a.max(b.c));
    let points = p
        .psd
        .iter()
        .filter(|b| b.c > 1e-12 * top)
        .map(|b| (b.q_mean, b.c))
        .collect();
    plot.series.push(Series {
        marker: Some(Marker::Circle),
        width: 0,
        ..Series::line("measured", points, 0)
    });
    plot.when_empty = Some("the map is too small for a PSD bin".into());
    let fit = &p.report["psd_fit"];
    if let (Some(h), Some(ll), Some(ls)) = (
        fit["hurst"].as_f64(),
        fit["run_lambda_long_m"].as_f64(),
        fit["run_lambda_short_m"].as_f64(),
    ) {
        let tau = std::f64::consts::TAU;
        let (ql, qs) = (tau / ll, tau / ls);
        // The fitted line through the bins of its range (least squares in log–log).
        let inside: Vec<&PsdBin> = p
            .psd
            .iter()
            .filter(|b| b.q_mean >= ql * 0.999 && b.q_mean <= qs * 1.001)
            .collect();
        let n = inside.len().max(1) as f64;
        let log_c0 = inside
            .iter()
            .map(|b| b.c.log10() + 2.0 * (1.0 + h) * b.q_mean.log10())
            .sum::<f64>()
            / n;
        let line = |q: f64| 10f64.powf(log_c0 - 2.0 * (1.0 + h) * q.log10());
        plot.series.push(Series {
            dash: Dash::Dashed,
            ..Series::line(
                format!("H = {h:.2}"),
                vec![(ql, line(ql)), (qs, line(qs))],
                1,
            )
        });
    }
    plot
}

fn ccdf(p: &Page) -> LinePlot {
    let mut plot = LinePlot::new("Cluster areas", "A (µm^2)", "P(area > A)", true, YAxis::Log);
    plot.when_empty = Some(
        "no load has two clusters or more: no distribution to draw (full contact, one cluster or none)"
            .into(),
    );
    for (i, (areas, r)) in p.areas_um2.iter().zip(p.rows).enumerate() {
        let mut a = areas.clone();
        a.sort_by(f64::total_cmp);
        let n = a.len() as f64;
        let points = a
            .iter()
            .enumerate()
            .filter(|(k, _)| *k + 1 < a.len())
            .map(|(k, &v)| (v, (n - k as f64 - 1.0) / n))
            .collect();
        let w = r["w_over_w0"].as_f64().unwrap_or(f64::NAN);
        let force = r["force_n"].as_f64().unwrap_or(f64::NAN);
        plot.series.push(Series {
            tint: 0.6 * i as f64 / p.areas_um2.len().max(1) as f64,
            ..Series::line(
                format!(
                    "W = {} N (W/W_0 = {})",
                    crate::ranges::show(force),
                    crate::ranges::show(w)
                ),
                points,
                0,
            )
        });
    }
    plot
}

/// Draw `wear.png`/`wear.svg` and `index.html` into `dir`.
pub fn write(p: &Page, dir: &Path) -> anyhow::Result<()> {
    let panels = Panels {
        plots: vec![coefficients(p), spectrum(p), ccdf(p)],
        layout: Layout::Grid { columns: 3 },
    };
    panels.write(dir, "wear")?;
    let cell = |v: &serde_json::Value| match v.as_f64() {
        // Counts as integers (149, not 149.0000).
        Some(_) if v.is_u64() => v.to_string(),
        Some(x) if x != 0.0 && (x.abs() < 1e-3 || x.abs() >= 1e5) => format!("{x:.4e}"),
        Some(x) => format!("{x:.4}"),
        None => "–".into(),
    };
    let keys = [
        ("force_n", "W (N)"),
        ("w_over_w0", "W/W0"),
        ("real_contact_area_um2", "A_c (µm²)"),
        ("n_clusters", "clusters"),
        ("k_archard", "K"),
        ("k_archard_band_low", "K band: low"),
        ("k_archard_band_high", "high"),
        ("k_upscaled", "𝒦"),
        ("k_upscaled_band_low", "𝒦 band: low"),
        ("k_upscaled_band_high", "high"),
        ("wear_rate_mm3_per_m", "wear rate (mm³/m)"),
        ("alpha", "α̂"),
    ];
    let head: String = keys.iter().map(|(_, h)| format!("<th>{h}</th>")).collect();
    let body: String = p
        .rows
        .iter()
        .map(|r| {
            let cells: String = keys
                .iter()
                .map(|(k, _)| format!("<td>{}</td>", cell(&r[*k])))
                .collect();
            format!("<tr>{cells}</tr>\n")
        })
        .collect();
    let escape = |s: &str| {
        s.replace('&', "&amp;")
            .replace('<', "&lt;")
            .replace('>', "&gt;")
    };
    let warnings: String = p.report["warnings"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|w| w.as_str())
        .map(|w| format!("<p class=\"warn\">Warning: {}</p>\n", escape(w)))
        .collect();
    let html = format!(
        "<!doctype html>\n<html><head><meta charset=\"utf-8\"><title>wearcoef wear: {input}</title>\n\
         <style>body{{font-family:sans-serif;max-width:1960px;margin:1em}}table{{border-collapse:collapse}}\
         td,th{{border:1px solid #ccc;padding:2px 8px;text-align:right}}.warn{{color:#a00}}</style></head>\n\
         <body><h1>Wear coefficients of {input}</h1>\n{warnings}\
         <p><img src=\"wear.png\" alt=\"K and 𝒦 against the force, the PSD, the cluster-area CCDF\" width=\"1920\"></p>\n\
         <table><tr>{head}</tr>\n{body}</table>\n\
         <p>The band of K and 𝒦 is their range over what the map cannot tell: without the clusters \
         cut by its edge, at d* times each of the factors of <code>--d-star-factors</code>, on the \
         map coarsened ×2, and on its halves and quarters solved alone, at the same mean pressure \
         (loads.parquet has every variant: <code>k_archard_no_edge</code>, \
         <code>…_d_star_low/_high</code>, <code>…_pixel_x2</code>, \
         <code>…_halves_min/_max</code>, <code>…_quarters_min/_max</code>).</p>\n\
         <p>Tables: loads.parquet, loads.csv, clusters.parquet, psd.parquet. What was done:</p>\n\
         <pre>{prep}</pre>\n</body></html>\n",
        input = escape(p.report["input"].as_str().unwrap_or("")),
        prep = escape(&serde_json::to_string_pretty(p.report)?),
    );
    std::fs::write(dir.join("index.html"), html)?;
    Ok(())
}
