//! Not in the paper: the same surfaces under several hardnesses 𝓗 (a perfectly plastic
//! interface). The exponent α̂ by both estimators against 1/𝓗 at fixed loads, with the
//! table of fits behind it; K and 𝒦 over each sweep at two thresholds; the fraction of the
//! contact area that is saturated. Every number is a stored one (statistics and contact
//! tables); the figure only picks and draws.

use polars::prelude::*;

use super::common::Drawn;
use super::plot::{Dash, LinePlot, Marker, Series, YAxis};
use crate::stages::figures::StudyRef;
use crate::store::inputs::Inputs;
use crate::store::table::{f64_column, str_column, u64_column};

/// The thresholds A*/λ_s² of K and 𝒦 drawn for each hardness: the paper's Fig. 2 threshold
/// (solid) and one of Figs. 4b–5 whose transition lies inside the sweep (dashed).
pub const PLASTIC_A_STAR: [f64; 2] = [2.0, 32.0];

/// The estimators of `alpha.parquet` drawn, with their legend names, line styles and markers.
const ESTIMATORS: [(&str, &str, Dash, Marker); 2] = [
    (
        "discrete_truncated_mle",
        "truncated power law",
        Dash::Solid,
        Marker::Circle,
    ),
    (
        "discrete_plateau_power_law_mle",
        "plateau + power law (Appendix A)",
        Dash::Dashed,
        Marker::Square,
    ),
];

/// The plastic family (inputs: each setting's statistics, then each setting's contact
/// sweeps, `realizations[s]` of them for setting `s`).
pub fn plastic(
    inputs: &Inputs,
    settings: &[StudyRef],
    realizations: &[usize],
    loads: &[f64],
) -> anyhow::Result<Vec<(String, Drawn)>> {
    let axis = AlphaAxis {
        title: "Cluster-area exponent under a hardness 𝓗 (0: elastic)",
        x_label: "E^* h'_{rms}/𝓗",
        x_log: false,
        x_column: "inverse_hardness",
    };
    let (alpha_plot, table) = alpha_against(inputs, settings, loads, &axis)?;
    let mut out = vec![
        ("plastic_alpha".to_string(), Drawn::Table(table)),
        ("plastic_alpha".to_string(), Drawn::Line(alpha_plot)),
    ];
    for (stem, column, title, y_label, y_axis) in [
        (
            "plastic_k",
            "k_archard_pooled",
            "Archard's wear coefficient under a hardness",
            "K = P(A > A*)",
            YAxis::Log,
        ),
        (
            "plastic_k_upscaled",
            "k_upscaled_pooled",
            "Up-scaled wear coefficient under a hardness",
            "𝒦 = A_c^*/A_c",
            YAxis::Linear,
        ),
    ] {
        let mut plot = LinePlot::new(title, "W/W_0", y_label, true, y_axis);
        if y_axis == YAxis::Linear {
            plot.y_bounds = Some((0.0, 1.0));
        }
        for (s, setting) in settings.iter().enumerate() {
            let wear = inputs.table(s, "statistics", "wear.parquet")?;
            let (a, w, v) = (
                f64_column(&wear, "a_star_over_ls2")?,
                f64_column(&wear, "w_over_w0")?,
                f64_column(&wear, column)?,
            );
            let (low, high) = (
                f64_column(&wear, &format!("{column}_ci95_low"))?,
                f64_column(&wear, &format!("{column}_ci95_high"))?,
            );
            let hollow = super::fig45::tentative(&wear, column)?;
            for (t, (&a_star, dash)) in PLASTIC_A_STAR
                .iter()
                .zip([Dash::Solid, Dash::Dashed])
                .enumerate()
            {
                let drawn: Vec<usize> = (0..a.len())
                    // A log axis cannot draw K = 0 (no cluster above A* yet).
                    .filter(|&i| a[i] == a_star && v[i].is_finite())
                    .filter(|&i| y_axis != YAxis::Log || v[i] > 0.0)
                    .collect();
                let points = drawn.iter().map(|&i| (w[i], v[i])).collect();
                plot.series.push(Series {
                    dash,
                    marker: Some(Marker::ALL[s % Marker::ALL.len()]),
                    hollow: drawn.iter().map(|&i| hollow[i]).collect(),
                    band: drawn
                        .iter()
                        .filter(|&&i| low[i].is_finite() && high[i].is_finite())
                        .map(|&i| (w[i], low[i], high[i]))
                        .collect(),
                    study: Some(setting.study.clone()),
                    a_star_over_ls2: Some(a_star),
                    // One legend entry per hardness; the dash says the threshold.
                    name: format!("{}, A* = {a_star} λ_s^2", setting.label),
                    ..Series::line(
                        if t == 0 {
                            setting.label.clone()
                        } else {
                            String::new()
                        },
                        points,
                        s,
                    )
                });
            }
        }
        for (&a_star, dash) in PLASTIC_A_STAR.iter().zip([Dash::Solid, Dash::Dashed]) {
            plot.series.push(Series {
                dash,
                rgb: Some((90, 90, 90)),
                ..Series::line(
                    format!("A* = {a_star} λ_s^2 (pooled over realizations)"),
                    Vec::new(),
                    0,
                )
            });
        }
        if let Some(h) = super::fig45::hollow_key(&plot.series) {
            plot.series.push(h);
        }
        out.push((stem.to_string(), Drawn::Line(plot)));
    }
    out.push((
        "plastic_saturated".to_string(),
        Drawn::Line(saturated(inputs, settings, realizations)?),
    ));
    Ok(out)
}

/// The abscissa of [`alpha_against`]: the settings' `value` (1/𝓗, λ_l/λ_s, …).
pub struct AlphaAxis {
    pub title: &'static str,
    pub x_label: &'static str,
    pub x_log: bool,
    /// The name of the setting's value in the table of fits.
    pub x_column: &'static str,
}

/// One fit of `alpha.parquet` drawn by [`alpha_against`]: a setting's estimator at one load.
struct AlphaFit {
    study: String,
    setting: f64,
    /// The load asked (`loads`) and the sweep's nearest one, solved.
    w_over_w0: f64,
    w_over_w0_solved: f64,
    estimator: String,
    alpha: f64,
    low: f64,
    high: f64,
    /// The upper end of the fitted range, in λ_s².
    k_max_over_ls2: f64,
    n_fitted: u64,
}

/// The fits of both estimators at the nearest load of each setting's sweep to each of
/// `loads`.
fn alpha_fits(
    inputs: &Inputs,
    settings: &[StudyRef],
    loads: &[f64],
) -> anyhow::Result<Vec<AlphaFit>> {
    let mut fits = Vec::new();
    for (s, setting) in settings.iter().enumerate() {
        let table = inputs.table(s, "statistics", "alpha.parquet")?;
        let (w, estimator) = (
            f64_column(&table, "w_over_w0")?,
            str_column(&table, "estimator")?,
        );
        let (a, low, high, k_max, n) = (
            f64_column(&table, "alpha")?,
            f64_column(&table, "ci95_low")?,
            f64_column(&table, "ci95_high")?,
            f64_column(&table, "k_max_px")?,
            u64_column(&table, "n_fitted")?,
        );
        let mut sweep: Vec<f64> = w.clone();
        sweep.dedup();
        let ls2 = setting.lambda_s_px * setting.lambda_s_px;
        for &target in loads {
            let Some(j) = crate::statistics::nearest_in_log(&sweep, target) else {
                continue;
            };
            for (name, _, _, _) in ESTIMATORS {
                if let Some(i) = (0..w.len()).find(|&i| w[i] == sweep[j] && estimator[i] == name) {
                    fits.push(AlphaFit {
                        study: setting.study.clone(),
                        setting: setting.value,
                        w_over_w0: target,
                        w_over_w0_solved: w[i],
                        estimator: name.to_string(),
                        alpha: a[i],
                        low: low[i],
                        high: high[i],
                        k_max_over_ls2: k_max[i] / ls2,
                        n_fitted: n[i],
                    });
                }
            }
        }
    }
    Ok(fits)
}

/// α̂ against the settings' value (1/𝓗, λ_l/λ_s) at each of `loads` (the nearest load of
/// each sweep) by both estimators, with their 95 % intervals, and the table of those fits.
/// Inputs: each setting's statistics, first.
pub fn alpha_against(
    inputs: &Inputs,
    settings: &[StudyRef],
    loads: &[f64],
    axis: &AlphaAxis,
) -> anyhow::Result<(LinePlot, DataFrame)> {
    let fits = alpha_fits(inputs, settings, loads)?;
    let mut plot = LinePlot::new(
        axis.title,
        axis.x_label,
        "α̂ (shaded: 95 % interval)",
        axis.x_log,
        YAxis::Linear,
    );
    for (c, &target) in loads.iter().enumerate() {
        for (name, legend, dash, marker) in ESTIMATORS {
            let picked: Vec<&AlphaFit> = fits
                .iter()
                .filter(|f| f.estimator == name && f.w_over_w0 == target && f.alpha.is_finite())
                .collect();
            plot.series.push(Series {
                dash,
                marker: Some(marker),
                w_over_w0: Some(target),
                band: picked
                    .iter()
                    .filter(|f| f.low.is_finite() && f.high.is_finite())
                    .map(|f| (f.setting, f.low, f.high))
                    .collect(),
                ..Series::line(
                    format!("W/W_0 = {}, {legend}", super::plot::number(target)),
                    picked.iter().map(|f| (f.setting, f.alpha)).collect(),
                    c,
                )
            });
        }
    }
    // A linear axis runs from 0 (plastic: the elastic end), a logarithmic one from the first.
    let x_min = match axis.x_log {
        true => settings
            .iter()
            .map(|s| s.value)
            .fold(f64::INFINITY, f64::min),
        false => 0.0,
    };
    let x_max = settings.iter().map(|s| s.value).fold(0.0f64, f64::max);
    plot.series.push(Series {
        rgb: Some((0, 0, 0)),
        dash: Dash::Dotted,
        width: 1,
        ..Series::line(
            "α = 2: above it 𝒦's limit falls below 1",
            vec![(x_min, 2.0), (x_max, 2.0)],
            0,
        )
    });
    let f64s = |name: &str, f: &dyn Fn(&AlphaFit) -> f64| {
        Column::new(name.into(), fits.iter().map(f).collect::<Vec<f64>>())
    };
    let strings = |name: &str, f: &dyn Fn(&AlphaFit) -> String| {
        Column::new(name.into(), fits.iter().map(f).collect::<Vec<String>>())
    };
    let table = DataFrame::new(
        fits.len(),
        vec![
            strings("study", &|f| f.study.clone()),
            f64s(axis.x_column, &|f| f.setting),
            f64s("w_over_w0", &|f| f.w_over_w0),
            f64s("w_over_w0_solved", &|f| f.w_over_w0_solved),
            strings("estimator", &|f| f.estimator.clone()),
            f64s("alpha", &|f| f.alpha),
            f64s("ci95_low", &|f| f.low),
            f64s("ci95_high", &|f| f.high),
            f64s("k_max_over_ls2", &|f| f.k_max_over_ls2),
            Column::new(
                "n_fitted".into(),
                fits.iter().map(|f| f.n_fitted).collect::<Vec<u64>>(),
            ),
        ],
    )?;
    Ok((plot, table))
}

/// The saturated share of the contact area over each sweep, the mean over its realizations.
fn saturated(
    inputs: &Inputs,
    settings: &[StudyRef],
    realizations: &[usize],
) -> anyhow::Result<LinePlot> {
    let mut plot = LinePlot::new(
        "Saturated share of the contact area (p = 𝓗)",
        "W/W_0",
        "A_{saturated}/A_c",
        true,
        YAxis::Linear,
    );
    plot.y_bounds = Some((0.0, 1.0));
    let mut next = settings.len();
    for (s, setting) in settings.iter().enumerate() {
        let mut sums: Vec<(f64, f64)> = Vec::new();
        for r in 0..realizations[s] {
            let loads = inputs.table(next + r, "contact", "loads.parquet")?;
            let w = f64_column(&loads, "w_over_w0")?;
            let contact = u64_column(&loads, "n_contact_px")?;
            // Elastic sweeps store no saturated column: none saturated.
            let saturated = if loads.column("n_saturated_px").is_ok() {
                u64_column(&loads, "n_saturated_px")?
            } else {
                vec![0; w.len()]
            };
            sums.resize(w.len(), (0.0, 0.0));
            for (i, sum) in sums.iter_mut().enumerate() {
                let share = if contact[i] > 0 {
                    saturated[i] as f64 / contact[i] as f64
                } else {
                    0.0
                };
                *sum = (w[i], sum.1 + share / realizations[s] as f64);
            }
        }
        next += realizations[s];
        plot.series.push(Series {
            marker: Some(Marker::ALL[s % Marker::ALL.len()]),
            study: Some(setting.study.clone()),
            ..Series::line(setting.label.clone(), sums, s)
        });
    }
    Ok(plot)
}
