//! Not in the paper: its §5 postulate, that a wider spectrum (smaller λ_s at fixed λ_l)
//! lowers the wear coefficient towards the experimental 10⁻⁵. The same surfaces' statistics
//! for λ_l/λ_s from 8 to 1024: α̂ by both estimators, K and 𝒦 at the end of the mild-wear
//! range at fixed A*/λ_s² with the fitted power-law model beside them, the upper end of the
//! power-law interval (largest cluster, fitted cut-off), the load where dN/dA_c changes sign,
//! and K at fixed A*/λ_l² (a fixed material on a wider spectrum). Every number is a stored one
//! (statistics and analytic tables); the figure only picks, interpolates and draws.

use polars::prelude::*;

use super::common::Drawn;
use super::plastic::{alpha_against, AlphaAxis};
use super::plot::{Dash, LinePlot, Marker, Series, YAxis, TENTATIVE_BELOW_CLUSTERS};
use crate::stages::figures::StudyRef;
use crate::store::inputs::Inputs;
use crate::store::table::{f64_column, u32_column, u64_column};

/// What the spectrum figure draws, besides its settings (ordered by λ_l/λ_s).
pub struct SpectrumScene<'a> {
    pub settings: &'a [StudyRef],
    /// Loads W/W0 of the α̂ and interval panels.
    pub loads: &'a [f64],
    /// The load of the K and 𝒦 panels (the end of the mild-wear range).
    pub plateau_w_over_w0: f64,
    pub a_star_over_ls2: &'a [f64],
    pub a_star_over_ll2: &'a [f64],
}

/// The spectrum family. Inputs: each setting's statistics, then each setting's fitted model
/// (analytic), in the order of `settings`.
pub fn spectrum(inputs: &Inputs, scene: &SpectrumScene) -> anyhow::Result<Vec<(String, Drawn)>> {
    let axis = AlphaAxis {
        title: "Cluster-area exponent against the spectrum's width",
        x_label: "λ_l/λ_s",
        x_log: true,
        x_column: "lambda_l_over_lambda_s",
    };
    let (alpha_plot, alpha_table) = alpha_against(inputs, scene.settings, scene.loads, &axis)?;
    let (transition_plot, transition_table) = transition(inputs, scene.settings)?;
    let mut out = vec![
        ("spectrum_alpha".to_string(), Drawn::Table(alpha_table)),
        ("spectrum_alpha".to_string(), Drawn::Line(alpha_plot)),
    ];
    for upscaled in [false, true] {
        let stem = if upscaled {
            "spectrum_k_upscaled"
        } else {
            "spectrum_k"
        };
        out.push((
            stem.to_string(),
            Drawn::Line(at_plateau(inputs, scene, upscaled)?),
        ));
    }
    out.push((
        "spectrum_interval".to_string(),
        Drawn::Line(interval(inputs, scene)?),
    ));
    out.push((
        "spectrum_transition".to_string(),
        Drawn::Table(transition_table),
    ));
    out.push((
        "spectrum_transition".to_string(),
        Drawn::Line(transition_plot),
    ));
    out.push((
        "spectrum_k_physical".to_string(),
        Drawn::Line(physical(inputs, scene)?),
    ));
    Ok(out)
}

/// The row indices of `w` at the sweep's load nearest (in ln W) to `target`, and that load.
fn rows_near(w: &[f64], target: f64) -> Option<(Vec<usize>, f64)> {
    let mut sweep = w.to_vec();
    sweep.dedup();
    let j = crate::statistics::nearest_in_log(&sweep, target)?;
    let solved = sweep[j];
    Some(((0..w.len()).filter(|&i| w[i] == solved).collect(), solved))
}

/// K (or 𝒦) pooled over realizations at the plateau load against λ_l/λ_s, one curve per
/// A*/λ_s² with its 95 % band, and the fitted power-law model's value dashed beside it.
fn at_plateau(inputs: &Inputs, scene: &SpectrumScene, upscaled: bool) -> anyhow::Result<LinePlot> {
    let (quantity, model_column, title, y_label, y_axis) = if upscaled {
        (
            "k_upscaled",
            "k_upscaled_pl",
            "Up-scaled wear coefficient against the spectrum's width",
            "𝒦 = A_c^*/A_c",
            YAxis::Linear,
        )
    } else {
        (
            "k_archard",
            "k_pl",
            "Archard's wear coefficient against the spectrum's width",
            "K = P(A > A*)",
            YAxis::Log,
        )
    };
    let w_plateau = scene.plateau_w_over_w0;
    let mut plot = LinePlot::new(
        format!("{title}, W/W_0 = {}", super::plot::number(w_plateau)),
        "λ_l/λ_s",
        y_label,
        true,
        y_axis,
    );
    if upscaled {
        plot.y_bounds = Some((0.0, 1.0));
    }
    let n = scene.settings.len();
    let mut measured = vec![Vec::new(); scene.a_star_over_ls2.len()];
    let mut hollow = vec![Vec::new(); scene.a_star_over_ls2.len()];
    let mut bands = vec![Vec::new(); scene.a_star_over_ls2.len()];
    let mut fitted = vec![Vec::new(); scene.a_star_over_ls2.len()];
    for (s, setting) in scene.settings.iter().enumerate() {
        let wear = inputs.table(s, "statistics", "wear.parquet")?;
        let (a, w) = (
            f64_column(&wear, "a_star_over_ls2")?,
            f64_column(&wear, "w_over_w0")?,
        );
        let pooled = f64_column(&wear, &format!("{quantity}_pooled"))?;
        let (low, high) = (
            f64_column(&wear, &format!("{quantity}_pooled_ci95_low"))?,
            f64_column(&wear, &format!("{quantity}_pooled_ci95_high"))?,
        );
        let tentative = super::fig45::tentative(&wear, &format!("{quantity}_pooled"))?;
        let model = inputs.table(n + s, "analytic", "model.parquet")?;
        let (ma, mw, mv) = (
            f64_column(&model, "a_star_over_ls2")?,
            f64_column(&model, "w_over_w0")?,
            f64_column(&model, model_column)?,
        );
        let x = setting.value;
        // The rows at the plateau load, found once for every threshold.
        let rows = rows_near(&w, w_plateau).map_or_else(Vec::new, |r| r.0);
        let model_rows = rows_near(&mw, w_plateau).map_or_else(Vec::new, |r| r.0);
        for (t, &a_star) in scene.a_star_over_ls2.iter().enumerate() {
            // A log axis cannot draw K = 0 (no cluster above A*); the CSV of fig45 has it.
            let drawable = |v: f64| v.is_finite() && (y_axis != YAxis::Log || v > 0.0);
            for i in rows.iter().copied().filter(|&i| a[i] == a_star) {
                if drawable(pooled[i]) {
                    measured[t].push((x, pooled[i]));
                    hollow[t].push(tentative[i]);
                }
                if high[i].is_finite() && (y_axis != YAxis::Log || low[i] > 0.0) {
                    bands[t].push((x, low[i], high[i]));
                }
            }
            for i in model_rows.iter().copied().filter(|&i| ma[i] == a_star) {
                if drawable(mv[i]) {
                    fitted[t].push((x, mv[i]));
                }
            }
        }
    }
    let symbol = if upscaled { "𝒦" } else { "K" };
    for (t, &a_star) in scene.a_star_over_ls2.iter().enumerate() {
        plot.series.push(Series {
            marker: Some(Marker::ALL[t % Marker::ALL.len()]),
            hollow: std::mem::take(&mut hollow[t]),
            a_star_over_ls2: Some(a_star),
            w_over_w0: Some(w_plateau),
            band: std::mem::take(&mut bands[t]),
            ..Series::line(
                format!("A* = {} λ_s^2", super::plot::number(a_star)),
                std::mem::take(&mut measured[t]),
                t,
            )
        });
        plot.series.push(Series {
            dash: Dash::Dashed,
            a_star_over_ls2: Some(a_star),
            w_over_w0: Some(w_plateau),
            name: format!(
                "{symbol}_{{PL}} fit, A* = {} λ_s^2",
                super::plot::number(a_star)
            ),
            ..Series::line(String::new(), std::mem::take(&mut fitted[t]), t)
        });
    }
    plot.series.push(Series {
        dash: Dash::Dashed,
        rgb: Some((90, 90, 90)),
        ..Series::line(
            format!("{symbol}_{{PL}}: the power-law model fitted at this load"),
            Vec::new(),
            0,
        )
    });
    plot.series.push(Series::band_key(
        "pooled over realizations; shaded: 95 % interval over realizations",
    ));
    if let Some(h) = super::fig45::hollow_key(&plot.series) {
        plot.series.push(h);
    }
    Ok(plot)
}

/// The upper end of the power-law interval against λ_l/λ_s at each load: the largest
/// cluster (mean over realizations, 95 % band) and the fitted model's cut-off A_m.
fn interval(inputs: &Inputs, scene: &SpectrumScene) -> anyhow::Result<LinePlot> {
    let mut plot = LinePlot::new(
        "Upper end of the power-law interval against the spectrum's width",
        "λ_l/λ_s",
        "A/λ_s^2",
        true,
        YAxis::Log,
    );
    let n = scene.settings.len();
    // Per drawn load: the largest cluster, its band and the fitted cut-off of each setting.
    type Curves = (Vec<(f64, f64)>, Vec<(f64, f64, f64)>, Vec<(f64, f64)>);
    let mut curves: Vec<Curves> = vec![Default::default(); scene.loads.len()];
    for (s, setting) in scene.settings.iter().enumerate() {
        // Each table read once per setting, whatever the number of loads drawn.
        let loads = inputs.table(s, "statistics", "loads.parquet")?;
        let w = f64_column(&loads, "w_over_w0")?;
        let mean = f64_column(&loads, "largest_area_over_ls2_mean")?;
        let (low, high) = (
            f64_column(&loads, "largest_area_over_ls2_ci95_low")?,
            f64_column(&loads, "largest_area_over_ls2_ci95_high")?,
        );
        let model = inputs.table(n + s, "analytic", "model.parquet")?;
        let (mw, a_m) = (
            f64_column(&model, "w_over_w0")?,
            f64_column(&model, "a_m_over_ls2")?,
        );
        for (&target, (largest, band, cut_off)) in scene.loads.iter().zip(curves.iter_mut()) {
            if let Some((rows, _)) = rows_near(&w, target) {
                for i in rows.into_iter().filter(|&i| mean[i] > 0.0) {
                    largest.push((setting.value, mean[i]));
                    if high[i].is_finite() && low[i] > 0.0 {
                        band.push((setting.value, low[i], high[i]));
                    }
                }
            }
            if let Some((rows, _)) = rows_near(&mw, target) {
                if let Some(&i) = rows.iter().find(|&&i| a_m[i].is_finite() && a_m[i] > 0.0) {
                    cut_off.push((setting.value, a_m[i]));
                }
            }
        }
    }
    for (c, (&target, (largest, band, cut_off))) in scene.loads.iter().zip(curves).enumerate() {
        let load = super::plot::number(target);
        plot.series.push(Series {
            marker: Some(Marker::ALL[c % Marker::ALL.len()]),
            w_over_w0: Some(target),
            band,
            ..Series::line(format!("W/W_0 = {load}: largest cluster"), largest, c)
        });
        plot.series.push(Series {
            dash: Dash::Dashed,
            marker: Some(Marker::ALL[c % Marker::ALL.len()]),
            w_over_w0: Some(target),
            ..Series::line(format!("W/W_0 = {load}: fitted cut-off A_m"), cut_off, c)
        });
    }
    plot.series.push(Series::band_key(
        "largest cluster: mean over realizations; shaded: 95 % band",
    ));
    Ok(plot)
}

/// Where one sweep's dN/dA_c changes sign: the load (interpolated in ln W between the last
/// positive and the first non-positive value), or none over the sweep.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SignChange {
    At(f64),
    /// Non-positive from the lowest load.
    BelowLowest,
    /// Positive at every load.
    AboveHighest,
    /// dN/dA_c defined at no load.
    Undefined,
}

/// The sign change of `dn_dac` over the increasing loads `w`, at the loads where it is
/// defined (finite: NaN where the contact area does not change between neighbours).
pub fn sign_change(w: &[f64], dn_dac: &[f64]) -> SignChange {
    let (w, d): (Vec<f64>, Vec<f64>) = w
        .iter()
        .zip(dn_dac)
        .filter(|p| p.1.is_finite())
        .map(|(&w, &d)| (w, d))
        .unzip();
    if d.is_empty() {
        return SignChange::Undefined;
    }
    match d.iter().position(|&v| v <= 0.0) {
        None => SignChange::AboveHighest,
        Some(0) => SignChange::BelowLowest,
        Some(i) => {
            let (d0, d1) = (d[i - 1], d[i]);
            let t = d0 / (d0 - d1);
            SignChange::At((w[i - 1].ln() + t * (w[i].ln() - w[i - 1].ln())).exp())
        }
    }
}

/// The load where dN/dA_c changes sign against λ_l/λ_s; a sweep positive throughout is
/// drawn at its highest load with an upward triangle ("later than this"), and the table
/// of every setting.
fn transition(inputs: &Inputs, settings: &[StudyRef]) -> anyhow::Result<(LinePlot, DataFrame)> {
    let mut plot = LinePlot::new(
        "End of the nucleation regime against the spectrum's width",
        "λ_l/λ_s",
        "W/W_0 where dN/dA_c changes sign",
        true,
        YAxis::Log,
    );
    let (mut at, mut later, mut earlier) = (Vec::new(), Vec::new(), Vec::new());
    let mut studies: Vec<String> = Vec::new();
    // λ_l/λ_s, the sign change, the lowest and the highest load of each sweep.
    let mut rows: [Vec<f64>; 4] = Default::default();
    for (s, setting) in settings.iter().enumerate() {
        let loads = inputs.table(s, "statistics", "loads.parquet")?;
        let order = u32_column(&loads, "load_index")?;
        anyhow::ensure!(
            order.windows(2).all(|p| p[0] < p[1]),
            "statistics loads.parquet of '{}' is not in load order",
            setting.study
        );
        let w = f64_column(&loads, "w_over_w0")?;
        let d = f64_column(&loads, "dn_dac_per_ls2_mean")?;
        let (lowest, highest) = (w[0], w[w.len() - 1]);
        let change = sign_change(&w, &d);
        let value = match change {
            SignChange::At(v) => {
                at.push((setting.value, v));
                v
            }
            SignChange::AboveHighest => {
                later.push((setting.value, highest));
                f64::INFINITY
            }
            SignChange::BelowLowest => {
                earlier.push((setting.value, lowest));
                0.0
            }
            SignChange::Undefined => f64::NAN,
        };
        studies.push(setting.study.clone());
        for (column, v) in rows.iter_mut().zip([setting.value, value, lowest, highest]) {
            column.push(v);
        }
    }
    for (points, label, marker, color) in [
        (at, "sign change (interpolated in ln W)", Marker::Circle, 0),
        (
            later,
            "positive at every load: later than the highest (drawn there)",
            Marker::Triangle,
            1,
        ),
        (
            earlier,
            "negative from the lowest load (drawn there)",
            Marker::Cross,
            2,
        ),
    ] {
        if !points.is_empty() {
            plot.series.push(Series {
                width: 0,
                marker: Some(marker),
                ..Series::line(label, points, color)
            });
        }
    }
    let mut columns = vec![Column::new("study".into(), studies)];
    for (name, values) in [
        "lambda_l_over_lambda_s",
        "w_over_w0_sign_change",
        "w_over_w0_lowest",
        "w_over_w0_highest",
    ]
    .into_iter()
    .zip(rows)
    {
        columns.push(Column::new(name.into(), values));
    }
    let table = DataFrame::new(settings.len(), columns)?;
    Ok((plot, table))
}

/// `P(A > x)` from exact CCDF steps `(a, P(A > a))` at increasing distinct areas: the step
/// of the largest `a ≤ x`, or 1 below the smallest.
pub fn ccdf_at(steps: &[(f64, f64)], x: f64) -> f64 {
    match steps.iter().rposition(|&(a, _)| a <= x) {
        Some(i) => steps[i].1,
        None => 1.0,
    }
}

/// K at fixed A*/λ_l² (so A*/λ_s² = A*/λ_l² · (λ_l/λ_s)²) at the plateau load against
/// λ_l/λ_s, from the pooled CCDF, with the band of the realizations' mean CCDF.
fn physical(inputs: &Inputs, scene: &SpectrumScene) -> anyhow::Result<LinePlot> {
    let w_plateau = scene.plateau_w_over_w0;
    let mut plot = LinePlot::new(
        format!(
            "K at a fixed area on the scale of λ_l, W/W_0 = {}",
            super::plot::number(w_plateau)
        ),
        "λ_l/λ_s",
        "K = P(A > A*)",
        true,
        YAxis::Log,
    );
    // Per threshold: the points, the band and which points are tentative.
    let mut curves = vec![(Vec::new(), Vec::new(), Vec::new()); scene.a_star_over_ll2.len()];
    for (s, setting) in scene.settings.iter().enumerate() {
        let table = super::common::CcdfTable::read(inputs, s)?;
        let Some(&(index, _)) = super::common::pick_loads(&table.loads(), &[w_plateau]).first()
        else {
            continue;
        };
        let pooled = table.curve(index, None, false);
        // The clusters pooled at that load (percolating ones left out, as in the CCDF):
        // K·N of them lie above A*.
        let alpha = inputs.table(s, "statistics", "alpha.parquet")?;
        let pooled_count = u32_column(&alpha, "load_index")?
            .iter()
            .zip(u64_column(&alpha, "clusters")?)
            .find(|(l, _)| **l == Some(index))
            .map_or(0, |(_, n)| n);
        // The band's edges are steps too, at each distinct area.
        let rows: Vec<usize> = (0..table.ccdf.len())
            .filter(|&i| table.load_index[i] == Some(index) && table.realization[i].is_none())
            .collect();
        let edge = |v: &[f64]| -> Vec<(f64, f64)> {
            rows.iter()
                .map(|&i| (table.area_over_ls2[i], v[i]))
                .collect()
        };
        let (low_edge, high_edge) = (edge(&table.ccdf_ci95_low), edge(&table.ccdf_ci95_high));
        for (t, &c) in scene.a_star_over_ll2.iter().enumerate() {
            let a_star_over_ls2 = c * setting.value * setting.value;
            let k = ccdf_at(&pooled, a_star_over_ls2);
            let (low, high) = (
                ccdf_at(&low_edge, a_star_over_ls2),
                ccdf_at(&high_edge, a_star_over_ls2),
            );
            if k > 0.0 {
                curves[t].0.push((setting.value, k));
                let above = (k * pooled_count as f64).round() as u64;
                curves[t]
                    .2
                    .push(above < TENTATIVE_BELOW_CLUSTERS || low.is_nan() || low <= 0.0);
            }
            if low > 0.0 && high.is_finite() {
                // A probability: the band of the mean stops at 1.
                curves[t].1.push((setting.value, low, high.min(1.0)));
            }
        }
    }
    for (t, ((points, band, hollow), &c)) in
        curves.into_iter().zip(scene.a_star_over_ll2).enumerate()
    {
        plot.series.push(Series {
            marker: Some(Marker::ALL[t % Marker::ALL.len()]),
            hollow,
            w_over_w0: Some(w_plateau),
            band,
            ..Series::line(
                format!("A* = λ_l^2/{}", super::plot::number(1.0 / c)),
                points,
                t,
            )
        });
    }
    plot.series.push(Series::band_key(
        "pooled over realizations; shaded: 95 % band of their mean",
    ));
    if let Some(h) = super::fig45::hollow_key(&plot.series) {
        plot.series.push(h);
    }
    Ok(plot)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sign_change_interpolates_in_log_load() {
        let w = [0.01, 0.02, 0.04];
        // +1 at 0.02, −1 at 0.04: zero halfway in ln W, at √(0.02·0.04).
        let SignChange::At(v) = sign_change(&w, &[2.0, 1.0, -1.0]) else {
            panic!("no sign change found");
        };
        assert!((v - (0.02f64 * 0.04).sqrt()).abs() < 1e-15);
        assert_eq!(sign_change(&w, &[1.0, 1.0, 0.5]), SignChange::AboveHighest);
        assert_eq!(sign_change(&w, &[-1.0, 1.0, 0.5]), SignChange::BelowLowest);
        // Exactly zero counts as the change, at that load.
        let SignChange::At(v) = sign_change(&w, &[1.0, 0.0, -1.0]) else {
            panic!("no sign change found");
        };
        assert!((v - 0.02).abs() < 1e-15);
        // Undefined loads are skipped; none defined, no answer.
        let SignChange::At(v) = sign_change(&w, &[1.0, f64::NAN, -1.0]) else {
            panic!("no sign change found");
        };
        assert!((v - (0.01f64 * 0.04).sqrt()).abs() < 1e-15);
        assert_eq!(sign_change(&w, &[f64::NAN; 3]), SignChange::Undefined);
    }

    #[test]
    fn ccdf_at_reads_the_step_at_or_below() {
        // Areas 1, 2, 5 with P(A > a) = 0.6, 0.2, 0.
        let steps = [(1.0, 0.6), (2.0, 0.2), (5.0, 0.0)];
        assert_eq!(ccdf_at(&steps, 0.5), 1.0);
        assert_eq!(ccdf_at(&steps, 1.0), 0.6);
        assert_eq!(ccdf_at(&steps, 4.9), 0.2);
        assert_eq!(ccdf_at(&steps, 7.0), 0.0);
    }
}
