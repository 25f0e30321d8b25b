//! Figs. 4b, 5a and 5b (K, 𝒦 and the wear rate against the load, simulated and fitted), the
//! load-resolution audit of those curves, and Fig. 6 (the model's curves).

use polars::prelude::*;

use super::common::{tolerance_line, Drawn};
use super::plot::TENTATIVE_BELOW_CLUSTERS;
use super::plot::{Dash, LinePlot, Marker, Series, YAxis};
use crate::stages::audits::{FIG45_A_STAR, FIG45_CURVES, LOAD_RESOLUTION_TOLERANCE, TABLE};
use crate::store::inputs::Inputs;
use crate::store::table::{bool_column, f64_column, str_column, u64_column};

/// Fig. 6: K_PL and 𝒦_PL against A_m/A_s for α = 1.5 and several A*/A_s.
///
/// Input 0: the model curves (analytic stage, `fig6.parquet`).
pub fn fig6(inputs: &Inputs) -> anyhow::Result<Vec<(String, Drawn)>> {
    let df = &inputs.table(0, "analytic", "fig6.parquet")?;
    let s = f64_column(df, "a_star_over_a_s")?;
    let m = f64_column(df, "a_m_over_a_s")?;
    let k = f64_column(df, "k_pl")?;
    let kk = f64_column(df, "k_upscaled_pl")?;
    let alpha = f64_column(df, "alpha")?
        .first()
        .copied()
        .unwrap_or(f64::NAN);
    let mut thresholds: Vec<f64> = s.clone();
    thresholds.dedup();
    let mut plot = LinePlot::new(
        format!("Fig. 6: power-law model, α = {alpha}"),
        "A_m/A_s",
        "K_{PL} (solid), 𝒦_{PL} (dashed)",
        true,
        YAxis::Linear,
    );
    // The model's coefficients are probabilities.
    plot.y_bounds = Some((0.0, 1.0));
    for (name, values, dash) in [("K_{PL}", &k, Dash::Solid), ("𝒦_{PL}", &kk, Dash::Dashed)] {
        for (c, &t) in thresholds.iter().enumerate() {
            let points: Vec<(f64, f64)> = (0..s.len())
                .filter(|&i| s[i] == t && m[i].is_finite() && m[i] >= t)
                .map(|i| (m[i], values[i]))
                .collect();
            plot.series.push(Series {
                dash,
                ..Series::line(format!("{name}, A*/A_s = {t}"), points, c)
            });
        }
    }
    Ok(vec![("fig6".into(), Drawn::Line(plot))])
}

/// Fig. 4b: the y axis is linear up to this value and logarithmic above (as in the paper).
const FIG4B_LINEAR_UP_TO: f64 = 1e-5;

/// One series per threshold of `value` against W/W0 from a table with columns
/// `a_star_over_ls2` and `w_over_w0`: simulated values as markers joined by a thin line (a
/// marker shape per threshold) with the value's own 95 % band (columns `<value>_ci95_low`
/// and `<value>_ci95_high`, `_mean` dropped: over realizations, within the quantity's
/// bounds), the fitted model as dashed lines in the same colours under one legend entry.
fn per_threshold(
    df: &DataFrame,
    value: &str,
    label: &str,
    fitted: bool,
) -> anyhow::Result<Vec<Series>> {
    let a = f64_column(df, "a_star_over_ls2")?;
    let w = f64_column(df, "w_over_w0")?;
    let v = f64_column(df, value)?;
    let band = if fitted {
        None
    } else {
        let quantity = value.trim_end_matches("_mean");
        Some((
            f64_column(df, &format!("{quantity}_ci95_low"))?,
            f64_column(df, &format!("{quantity}_ci95_high"))?,
        ))
    };
    let hollow = if fitted {
        Vec::new()
    } else {
        tentative(df, value)?
    };
    let mut out: Vec<Series> = FIG45_A_STAR
        .iter()
        .enumerate()
        .map(|(c, &t)| {
            let points = (0..a.len())
                .filter(|&i| a[i] == t)
                .map(|i| (w[i], v[i]))
                .collect();
            if fitted {
                Series {
                    dash: Dash::Dashed,
                    name: format!("{label}, A* = {t} λ_s^2"),
                    a_star_over_ls2: Some(t),
                    ..Series::line(String::new(), points, c)
                }
            } else {
                let band = band
                    .as_ref()
                    .map(|(low, high)| {
                        (0..a.len())
                            .filter(|&i| a[i] == t && low[i].is_finite() && high[i].is_finite())
                            .map(|i| (w[i], low[i], high[i]))
                            .collect()
                    })
                    .unwrap_or_default();
                Series {
                    marker: Some(Marker::ALL[c % Marker::ALL.len()]),
                    hollow: (0..a.len())
                        .filter(|&i| a[i] == t)
                        .map(|i| hollow[i])
                        .collect(),
                    width: 1,
                    a_star_over_ls2: Some(t),
                    band,
                    ..Series::line(format!("{label}, A* = {t} λ_s^2"), points, c)
                }
            }
        })
        .collect();
    if fitted {
        out.push(Series {
            dash: Dash::Dashed,
            rgb: Some((90, 90, 90)),
            ..Series::line(format!("{label} (colour: A*)"), Vec::new(), 0)
        });
    }
    Ok(out)
}

/// Per row of a `wear.parquet`, whether `value` is tentative (drawn hollow): it rests on
/// fewer than [`TENTATIVE_BELOW_CLUSTERS`] clusters above A* (pooled over realizations),
/// or its 95 % interval reaches 0.
pub fn tentative(wear: &DataFrame, value: &str) -> anyhow::Result<Vec<bool>> {
    let quantity = value.trim_end_matches("_mean");
    let low = f64_column(wear, &format!("{quantity}_ci95_low"))?;
    let above = u64_column(wear, "clusters_above")?;
    Ok(low
        .iter()
        .zip(&above)
        .map(|(&l, &n)| n < TENTATIVE_BELOW_CLUSTERS || (l.is_finite() && l <= 0.0))
        .collect())
}

/// The legend entry of hollow markers, when `series` draw any.
pub fn hollow_key(series: &[Series]) -> Option<Series> {
    series
        .iter()
        .any(|s| s.hollow.iter().any(|&h| h))
        .then(|| Series {
            marker: Some(Marker::Circle),
            hollow: vec![true],
            width: 0,
            rgb: Some((90, 90, 90)),
            ..Series::line(
                format!(
                    "hollow: fewer than {TENTATIVE_BELOW_CLUSTERS} clusters above A*, or an interval reaching 0"
                ),
                Vec::new(),
                0,
            )
        })
}

/// Figs. 4b (K vs load), 5a (𝒦 vs load) and 5b (wear rate vs load), simulated (solid,
/// pooled over realizations) and from the fitted plateau + power-law model (dashed).
///
/// Input 0: the study's statistics; input 1: its fitted model (analytic).
/// `spectrum` names the surfaces in the titles (`λ_l/λ_s = 128`, or a measured study).
pub fn fig45(inputs: &Inputs, spectrum: &str) -> anyhow::Result<Vec<(String, Drawn)>> {
    let wear = &inputs.table(0, "statistics", "wear.parquet")?;
    let model = &inputs.table(1, "analytic", "model.parquet")?;
    let mut k = per_threshold(wear, "k_archard_pooled", "K", false)?;
    k.extend(per_threshold(model, "k_pl", "K_{PL} fit", true)?);
    let mut kk = per_threshold(wear, "k_upscaled_pooled", "𝒦", false)?;
    kk.extend(per_threshold(model, "k_upscaled_pl", "𝒦_{PL} fit", true)?);
    let mut rate = per_threshold(wear, "wear_rate_over_l2_mean", "R/L^2", false)?;
    let realizations = super::common::realizations_of(inputs, 0)?;
    let key = |what: &str| {
        Series::band_key(
            if realizations >= crate::resample::MIN_REALIZATIONS as u64 {
                format!(
                    "{what} {realizations} realizations; shaded: 95 % interval over realizations"
                )
            } else {
                format!(
                    "{what} {realizations} realizations; no interval (an interval needs {})",
                    crate::resample::MIN_REALIZATIONS
                )
            },
        )
    };
    k.push(key("markers: pooled over"));
    kk.push(key("markers: pooled over"));
    rate.push(key("markers: mean of"));
    for s in [&mut k, &mut kk, &mut rate] {
        if let Some(h) = hollow_key(s) {
            s.push(h);
        }
    }
    let plot = |title: &str, y: &str, y_axis: YAxis, series: Vec<Series>| {
        let mut p = LinePlot::new(title, "W/W_0", y, true, y_axis);
        p.series = series;
        if y_axis == YAxis::Linear {
            // 𝒦 = A_c*/A_c is a fraction of the contact area.
            p.y_bounds = Some((0.0, 1.0));
        }
        Drawn::Line(p)
    };
    Ok(vec![
        (
            "fig4b".into(),
            plot(
                &format!("Fig. 4b: Archard's wear coefficient, {spectrum}"),
                "K = P(A > A*)  (linear below 10^{−5})",
                YAxis::LinLog {
                    threshold: FIG4B_LINEAR_UP_TO,
                },
                k,
            ),
        ),
        (
            "fig5a".into(),
            plot(
                &format!("Fig. 5a: up-scaled wear coefficient, {spectrum}"),
                "𝒦 = A_c^*/A_c",
                YAxis::Linear,
                kk,
            ),
        ),
        (
            "fig5b".into(),
            plot(
                &format!("Fig. 5b: wear rate (ω = 1/3), {spectrum}"),
                "R/L^2",
                YAxis::Log,
                rate,
            ),
        ),
        (
            "fig45_dn_dac".into(),
            Drawn::Line(regime(inputs, spectrum)?),
        ),
    ])
}

/// The regime of Figs. 4b–5b: dN/dA_c over the study's sweep (positive: the contact area
/// grows by new clusters, the paper's mild-wear regime; negative: by merging), with the
/// cluster count N it is the slope of (input 0: the study's statistics).
fn regime(inputs: &Inputs, spectrum: &str) -> anyhow::Result<LinePlot> {
    let loads = inputs.table(0, "statistics", "loads.parquet")?;
    let w = f64_column(&loads, "w_over_w0")?;
    let dn = f64_column(&loads, "dn_dac_per_ls2_mean")?;
    let mut p = LinePlot::new(
        format!("Regime of Figs. 4b–5b: growth of the cluster count, {spectrum}"),
        "W/W_0",
        "dN/d(A_c/λ_s^2)",
        true,
        YAxis::Linear,
    );
    let (first, last) = (w[0], w[w.len() - 1]);
    p.series = vec![
        Series {
            marker: Some(Marker::Circle),
            ..Series::line(
                "dN/dA_c (mean of the realizations' central differences; > 0: nucleation)",
                w.iter().copied().zip(dn).collect(),
                0,
            )
        },
        Series {
            rgb: Some((0, 0, 0)),
            width: 1,
            name: "zero".into(),
            ..Series::line("", vec![(first, 0.0), (last, 0.0)], 0)
        },
    ];
    Ok(p)
}

/// The load-resolution audit of Figs. 4b and 5 drawn: per curve and load of the finer sweep,
/// the largest interpolation error over thresholds in units of the band (input 0: the audit).
pub fn load_resolution(inputs: &Inputs, figure: &str) -> anyhow::Result<Vec<(String, Drawn)>> {
    let audit = inputs.of(0, "audits")?;
    let table = inputs.table(0, "audits", TABLE)?;
    let curve = str_column(&table, "curve")?;
    let w = f64_column(&table, "w_over_w0")?;
    let error = f64_column(&table, "error_over_ci95")?;
    let at_transition = bool_column(&table, "at_transition")?;
    let mut fine_loads = w.clone();
    fine_loads.sort_by(f64::total_cmp);
    fine_loads.dedup();
    let judged: Vec<usize> = (0..w.len()).filter(|&i| !at_transition[i]).collect();
    let mut plot = LinePlot::new(
        "Figs. 4b, 5: fewer loads interpolated vs the finer sweep",
        "W/W_0",
        "|interpolated − value| / 95 % half-width (max over A*)",
        true,
        YAxis::Linear,
    );
    for (c, &(_, _, name, legend)) in FIG45_CURVES.iter().enumerate() {
        let mut points: Vec<(f64, f64)> = Vec::new();
        for &load in &fine_loads {
            let e = judged
                .iter()
                .filter(|&&i| curve[i] == name && w[i] == load)
                .map(|&i| error[i])
                .filter(|e| e.is_finite())
                .fold(f64::NEG_INFINITY, f64::max);
            if e.is_finite() {
                points.push((load, e));
            }
        }
        plot.series.push(Series {
            marker: Some(Marker::ALL[c % Marker::ALL.len()]),
            ..Series::line(legend, points, c)
        });
    }
    let (x0, x1) = (
        w.iter().copied().fold(f64::INFINITY, f64::min),
        w.iter().copied().fold(0.0f64, f64::max),
    );
    plot.series.push(Series {
        width: 1,
        ..tolerance_line(LOAD_RESOLUTION_TOLERANCE, x0, x1)
    });
    Ok(vec![
        (figure.into(), Drawn::Table(table)),
        (figure.into(), Drawn::Line(plot)),
        (
            "load_resolution".into(),
            Drawn::Result(audit.results.clone()),
        ),
    ])
}
