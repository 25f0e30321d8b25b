//! Fig. 3 (cluster-area PDF for several λ_l/λ_s and loads with the fitted power law; inset:
//! the Hurst exponent) and Fig. 4a (the CCDF of the same studies and loads).

use polars::prelude::*;

use super::plot::{Dash, Fractions, Layout, LinePlot, Marker, Panels, Series, YAxis};
use super::StudyRef;
use super::{pick_loads, rows_at, CcdfTable, Drawn};
use crate::pipeline::inputs::Inputs;
use crate::pipeline::table::{f64_column, loads_of, str_column, u64_column};

/// Fits of Fig. 3 are drawn only over at least this many decades of area.
pub const MIN_FIT_DECADES: f64 = 1.0;
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

/// Points of a fitted curve and its legend text.
type FittedLine = (Vec<(f64, f64)>, String);

/// The fitted discrete truncated power law at one load, drawn over its fitted range in the
/// units of the PDF (per λ_s², weighted by the fraction of clusters in the range), and its
/// legend text. `None` when there is no fit or when the fitted range spans less than
/// [`MIN_FIT_DECADES`] (the KS choice of `k_min` then sits in the cut-off, e.g. λ_l/λ_s = 8,
/// and its exponent is not that of the power-law interval).
fn fitted_power_law(
    alpha_table: &DataFrame,
    load_index: u32,
    clusters: u64,
    lambda_s_px: f64,
) -> anyhow::Result<Option<FittedLine>> {
    let est = str_column(alpha_table, "estimator")?;
    let alpha = f64_column(alpha_table, "alpha")?;
    let lo = f64_column(alpha_table, "bootstrap_ci95_low")?;
    let hi = f64_column(alpha_table, "bootstrap_ci95_high")?;
    let k_min = f64_column(alpha_table, "k_min_px")?;
    let k_max = f64_column(alpha_table, "k_max_px")?;
    let n_fit = u64_column(alpha_table, "n_fitted")?;
    let Some(i) = rows_at(alpha_table, load_index)?
        .into_iter()
        .find(|&i| est[i] == crate::powerlaw::Estimator::DiscreteTruncated.name())
    else {
        return Ok(None);
    };
    let (a, k0, k1) = (alpha[i], k_min[i], k_max[i]);
    if !(a.is_finite() && k0 >= 1.0 && k1 >= k0 * 10f64.powf(MIN_FIT_DECADES)) || clusters == 0 {
        return Ok(None);
    }
    let (k0, k1) = (k0 as u64, k1 as u64);
    let z = crate::powerlaw::discrete_normalisation(a, k0, k1);
    let weight = n_fit[i] as f64 / clusters as f64;
    let ls2 = lambda_s_px * lambda_s_px;
    let steps = 40;
    let points = (0..=steps)
        .map(|j| {
            let k = k0 as f64 * (k1 as f64 / k0 as f64).powf(j as f64 / steps as f64);
            (k / ls2, weight * k.powf(-a) / z * ls2)
        })
        .collect();
    let text = format!("α = {a:.2}, 95 % CI [{:.2}, {:.2}]", lo[i], hi[i]);
    Ok(Some((points, text)))
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
    let stats = |i: usize, file: &str| inputs.table(i, "statistics", file);
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
    // The fits of the studies told apart by colour and by dash.
    let fit_dashes = [Dash::Dashed, Dash::Dotted, Dash::LongDashed];
    for (c, study) in ratios.iter().enumerate() {
        let pdf = stats(c, "pdf.parquet")?;
        let alpha = stats(c, "alpha.parquet")?;
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
            let (points, clusters) = pdf_points(&pdf, load_index)?;
            let label = if last {
                format!("{} (W/W_0 = {load_list}, light → dark)", study.label)
            } else {
                String::new()
            };
            main.series.push(Series {
                tint,
                marker: Some(Marker::ALL[c % Marker::ALL.len()]),
                width: 1,
                label: label.clone(),
                points,
                color: c,
                ..about.clone()
            });
            ccdf_plot.series.push(Series {
                tint,
                label,
                points: ccdf.curve(load_index, None, false),
                color: c,
                ..about.clone()
            });
            if last {
                if let Some((fit, text)) =
                    fitted_power_law(&alpha, load_index, clusters, study.lambda_s_px)?
                {
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
    }
    let mut out = Vec::new();
    if hurst.is_empty() {
        out.push(("fig3".to_string(), Drawn::Line(main)));
    } else {
        let mut inset = LinePlot::new("λ_l/λ_s = 128", "A/λ_s^2", "p(A/λ_s^2)", true, YAxis::Log);
        for (c, study) in hurst.iter().enumerate() {
            let pdf = stats(ratios.len() + c, "pdf.parquet")?;
            if let Some(&(load_index, w)) = pick_loads(&loads_of(&pdf)?, &[inset_load]).first() {
                let (points, _) = pdf_points(&pdf, load_index)?;
                inset.series.push(Series {
                    marker: Some(Marker::ALL[(c + 3) % Marker::ALL.len()]),
                    width: 1,
                    study: Some(study.study.clone()),
                    w_over_w0: Some(w),
                    ..Series::line(format!("{} (W/W_0 = {w:.3})", study.label), points, c + 3)
                });
            }
        }
        out.push((
            "fig3".to_string(),
            Drawn::Panels(Panels {
                plots: vec![main, inset],
                // Lower left of the axes, where the PDFs (decreasing) leave room.
                layout: Layout::Inset {
                    rect: Fractions(0.0, 0.5, 0.46, 0.5),
                },
            }),
        ));
    }
    out.push(("fig4a".to_string(), Drawn::Line(ccdf_plot)));
    Ok(out)
}
