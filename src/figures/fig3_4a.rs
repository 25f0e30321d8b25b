//! Fig. 3 (cluster-area PDF for several λ_l/λ_s and loads with the fitted power law; inset:
//! the Hurst exponent) and Fig. 4a (the CCDF of the same studies and loads).

use polars::prelude::*;

use super::common::{pick_loads, rows_at, CcdfTable, Drawn};
use super::plot::{Dash, Fractions, Layout, LinePlot, Marker, Panels, Series, YAxis};
use crate::stages::figures::StudyRef;
use crate::store::inputs::Inputs;
use crate::store::table::{f64_column, loads_of, str_column, u64_column};

/// Tints of the loads of one family, lightest for the smallest load.
const LOAD_TINTS: [f64; 3] = [0.6, 0.3, 0.0];

/// The pooled PDF of one study at one load: `(A/λ_s², p)` per bin with clusters.
fn pdf_points(pdf: &DataFrame, load_index: u32) -> anyhow::Result<(Vec<(f64, f64)>, u64)> {
    let rows = rows_at(pdf, load_index)?;
    let x = f64_column(pdf, "centre_over_ls2")?;
    let p = f64_column(pdf, "pdf_pooled")?;
    let count = u64_column(pdf, "count_pooled")?;
    let total = rows.iter().map(|&i| count[i]).sum();
    Ok((
        rows.iter()
            .filter(|&&i| count[i] > 0)
            .map(|&i| (x[i], p[i]))
            .collect(),
        total,
    ))
}

/// The 95 % band of the realizations' mean PDF of one study at one load, where its lower
/// edge is positive (the logarithmic axis cannot draw the rest).
fn pdf_band(pdf: &DataFrame, load_index: u32) -> anyhow::Result<Vec<(f64, f64, f64)>> {
    let rows = rows_at(pdf, load_index)?;
    let x = f64_column(pdf, "centre_over_ls2")?;
    let (low, high) = (
        f64_column(pdf, "pdf_ci95_low")?,
        f64_column(pdf, "pdf_ci95_high")?,
    );
    Ok(rows
        .iter()
        .map(|&i| (x[i], low[i], high[i]))
        .filter(|b| b.1 > 0.0 && b.2.is_finite())
        .collect())
}

/// Points of a fitted curve and its legend text.
type FittedLine = (Vec<(f64, f64)>, String);

/// The plateau + power law (Appendix A's model) fitted at one load (`p_PL`: flat to `k_s`, `(k/k_s)^(−α)`
/// to the largest area `k_m`), drawn over `[1, k_m]` in the units of the PDF (per λ_s²), and
/// its legend: α̂ with its 95 % interval over realizations (or why it has none), and the truncated power law's
/// α̂ beside it (the other estimator, docs/VALIDATION.md). `None` without a fit.
fn fitted_plateau(
    alpha_table: &DataFrame,
    load_index: u32,
    lambda_s_px: f64,
) -> anyhow::Result<Option<FittedLine>> {
    use crate::powerlaw::Estimator;
    let est = str_column(alpha_table, "estimator")?;
    let alpha = f64_column(alpha_table, "alpha")?;
    let lo = f64_column(alpha_table, "ci95_low")?;
    let hi = f64_column(alpha_table, "ci95_high")?;
    let k_s = f64_column(alpha_table, "k_s_px")?;
    let k_max = f64_column(alpha_table, "k_max_px")?;
    let rows = rows_at(alpha_table, load_index)?;
    let row = |e: Estimator| rows.iter().copied().find(|&i| est[i] == e.name());
    let Some(i) = row(Estimator::DiscretePlateauPowerLaw) else {
        return Ok(None);
    };
    let (a, ks, km) = (alpha[i], k_s[i], k_max[i]);
    if !(a.is_finite() && ks >= 1.0 && km > ks) {
        return Ok(None);
    }
    // Z = ⌊k_s⌋ + k_s^α Σ_{⌊k_s⌋ < k ≤ k_m} k^(−α)
    let flat = ks.floor();
    let z =
        flat + ks.powf(a) * crate::powerlaw::discrete_normalisation(a, flat as u64 + 1, km as u64);
    let ls2 = lambda_s_px * lambda_s_px;
    let steps = 60;
    let points = (0..=steps)
        .map(|j| {
            let k = km.powf(j as f64 / steps as f64);
            let w = if k <= ks { 1.0 } else { (k / ks).powf(-a) };
            (k / ls2, w / z * ls2)
        })
        .collect();
    // The truncated power law's α̂ only where its own goodness of fit does not reject it.
    let gof = f64_column(alpha_table, "gof_p")?;
    let truncated = row(Estimator::DiscreteTruncated)
        .filter(|&j| alpha[j].is_finite())
        .map_or(String::new(), |j| {
            if gof[j].is_nan() {
                format!("; truncated power law: α = {:.2} (not tested)", alpha[j])
            } else if gof[j] > crate::powerlaw::REJECT_AT {
                format!("; truncated power law: α = {:.2}", alpha[j])
            } else {
                format!("; truncated power law rejected (p = {:.2})", gof[j])
            }
        });
    let interval = if lo[i].is_finite() && hi[i].is_finite() {
        format!("95 % CI {}", super::plot::interval_text(lo[i], hi[i]))
    } else {
        let why = str_column(alpha_table, "ci95_method")?;
        format!(
            "no interval: {}",
            why[i]
                .trim_start_matches("none: ")
                .replace(" (", ", ")
                .replace(')', "")
        )
    };
    let text = format!("plateau + power law, α = {a:.2}, {interval}{truncated}");
    Ok(Some((points, text)))
}

/// One spectrum's curves (input `c`, study `study`) at the loads of its sweep nearest to
/// `loads`: its PDFs on Fig. 3 with the plateau + power law fitted at the largest, its CCDFs
/// on Fig. 4a, the largest load's with its 95 % band.
fn study_curves(
    inputs: &Inputs,
    c: usize,
    study: &StudyRef,
    loads: &[f64],
    main: &mut LinePlot,
    ccdf_plot: &mut LinePlot,
) -> anyhow::Result<()> {
    // The fits of the studies told apart by colour and by dash.
    let fit_dashes = [Dash::Dashed, Dash::Dotted, Dash::LongDashed];
    let pdf = inputs.table(c, "statistics", "pdf.parquet")?;
    let alpha = inputs.table(c, "statistics", "alpha.parquet")?;
    let ccdf = CcdfTable::read(inputs, c)?;
    let picked = pick_loads(&loads_of(&pdf)?, loads);
    let load_list = picked
        .iter()
        .map(|l| format!("{:.3}", l.1))
        .collect::<Vec<_>>()
        .join(", ");
    for (j, &(load_index, w)) in picked.iter().enumerate() {
        let last = j + 1 == picked.len();
        let about = Series {
            name: format!("{} (W/W_0 = {w:.3})", study.label),
            study: Some(study.study.clone()),
            w_over_w0: Some(w),
            ..Series::default()
        };
        let tint = LOAD_TINTS[LOAD_TINTS.len() - picked.len() + j];
        let (points, _) = pdf_points(&pdf, load_index)?;
        // Fig. 3 names the loads in each study's entry; Fig. 4a gives each load's shade an
        // entry of its own (below), where the curves of one study are told apart by it.
        let (label, ccdf_label) = if last {
            (
                format!("{} (W/W_0 = {load_list}, light → dark)", study.label),
                study.label.clone(),
            )
        } else {
            (String::new(), String::new())
        };
        // The largest load of each study carries its 95 % band (one band per spectrum
        // keeps the curves readable).
        let (pdf_shade, ccdf_shade) = if last {
            (pdf_band(&pdf, load_index)?, ccdf.band(load_index))
        } else {
            (Vec::new(), Vec::new())
        };
        main.series.push(Series {
            tint,
            marker: Some(Marker::ALL[c % Marker::ALL.len()]),
            width: 1,
            label: label.clone(),
            points,
            color: c,
            band: pdf_shade,
            ..about.clone()
        });
        ccdf_plot.series.push(Series {
            tint,
            label: ccdf_label,
            points: ccdf.curve(load_index, None, false),
            color: c,
            band: ccdf_shade,
            ..about.clone()
        });
        if last {
            if let Some((fit, text)) = fitted_plateau(&alpha, load_index, study.lambda_s_px)? {
                main.series.push(Series {
                    dash: fit_dashes[c % fit_dashes.len()],
                    width: 3,
                    label: format!("{} fit: {text}", study.label),
                    points: fit,
                    color: c,
                    ..about.clone()
                });
            }
        }
    }
    Ok(())
}

/// Fig. 4a's legend of the loads, told apart by shade (each study draws its sweep's nearest
/// loads): one entry each, in grey, lightest for the smallest.
fn load_shades(loads: &[f64]) -> Vec<Series> {
    let mut asked = loads.to_vec();
    asked.sort_by(f64::total_cmp);
    asked.dedup();
    asked
        .iter()
        .enumerate()
        .take(LOAD_TINTS.len())
        .map(|(j, w)| Series {
            label: format!("W/W_0 ≈ {w}"),
            rgb: Some((60, 60, 60)),
            tint: LOAD_TINTS[LOAD_TINTS.len() - asked.len().min(LOAD_TINTS.len()) + j],
            width: 3,
            name: "load shade".into(),
            ..Series::default()
        })
        .collect()
}

/// The inset of Fig. 3: the PDF of each Hurst study (inputs from `first` on) at the load of
/// its sweep nearest to `inset_load`.
fn inset_plot(
    inputs: &Inputs,
    first: usize,
    hurst: &[StudyRef],
    inset_load: f64,
) -> anyhow::Result<LinePlot> {
    let mut inset = LinePlot::new(
        format!("λ_l/λ_s = 128, W/W_0 ≈ {inset_load}"),
        "A/λ_s^2",
        "p(A/λ_s^2)",
        true,
        YAxis::Log,
    );
    for (c, study) in hurst.iter().enumerate() {
        let pdf = inputs.table(first + c, "statistics", "pdf.parquet")?;
        if let Some(&(load_index, w)) = pick_loads(&loads_of(&pdf)?, &[inset_load]).first() {
            let (points, _) = pdf_points(&pdf, load_index)?;
            inset.series.push(Series {
                marker: Some(Marker::ALL[(c + 3) % Marker::ALL.len()]),
                width: 1,
                study: Some(study.study.clone()),
                w_over_w0: Some(w),
                ..Series::line(study.label.clone(), points, c + 3)
            });
        }
    }
    Ok(inset)
}

/// Fig. 3 (PDF of A/λ_s² for several λ_l/λ_s and loads, fitted power law; inset: H) and
/// Fig. 4a (CCDF for the same studies and loads).
///
/// Inputs: the statistics of `ratios`, then of `hurst`, in order.
pub fn fig34a(
    inputs: &Inputs,
    ratios: &[StudyRef],
    hurst: &[StudyRef],
    loads: &[f64],
    inset_load: f64,
) -> anyhow::Result<Vec<(String, Drawn)>> {
    let mut main = LinePlot::new(
        "Fig. 3: cluster-area PDF, H = 0.8",
        "A/λ_s^2",
        "p(A/λ_s^2)",
        true,
        YAxis::Log,
    );
    let mut ccdf_plot = LinePlot::new(
        "Fig. 4a: K(A*) = P(A > A*), H = 0.8",
        "A*/λ_s^2",
        "P(A > A*)",
        true,
        YAxis::Log,
    );
    for (c, study) in ratios.iter().enumerate() {
        study_curves(inputs, c, study, loads, &mut main, &mut ccdf_plot)?;
    }
    ccdf_plot.series.extend(load_shades(loads));
    let key = Series::band_key(
        "shaded: 95 % band of the realizations' mean at the largest load (where > 0)",
    );
    main.series.push(key.clone());
    ccdf_plot.series.push(key);
    let mut out = Vec::new();
    if hurst.is_empty() {
        out.push(("fig3".to_string(), Drawn::Line(main)));
    } else {
        let inset = inset_plot(inputs, ratios.len(), hurst, inset_load)?;
        out.push((
            "fig3".to_string(),
            Drawn::Panels(Panels {
                plots: vec![main, inset],
                // Lower left of the axes, where the PDFs (decreasing) leave room.
                layout: Layout::Inset {
                    rect: Fractions(0.0, 0.42, 0.5, 0.58),
                },
            }),
        ));
    }
    out.push(("fig4a".to_string(), Drawn::Line(ccdf_plot)));
    Ok(out)
}
