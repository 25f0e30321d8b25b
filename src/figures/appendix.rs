//! Figs. B.1 and B.2 (the CCDF of cluster areas as the box size or the discretisation
//! varies) and their convergence audit.

use super::common::{tolerance_line, CcdfTable, Drawn};
use super::plot::{Dash, Layout, LinePlot, Marker, Panels, Series, YAxis};
use crate::stages::audits::{ConvergenceRow, ConvergenceTable, CONVERGENCE_KS_TOLERANCE, TABLE};
use crate::stages::figures::StudyRef;
use crate::store::inputs::Inputs;

/// Figs. B.1 and B.2: the CCDF of cluster areas per setting. B.1 (one panel per setting):
/// every realization in grey and the ensemble mean in red, per load; B.2 (one panel per
/// load): the ensemble mean of each setting.
///
/// Inputs: each setting's statistics, then the settings audit.
pub fn appendix(
    inputs: &Inputs,
    figure: &str,
    quantity: &str,
    b1: bool,
    settings: &[StudyRef],
) -> anyhow::Result<Vec<(String, Drawn)>> {
    let tables = (0..settings.len())
        .map(|i| CcdfTable::read(inputs, i))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let plots = if b1 {
        box_panels(settings, &tables)
    } else {
        discretisation_panels(settings, &tables)
    };
    anyhow::ensure!(!plots.is_empty(), "{figure}: no setting to draw");
    let columns = plots.len().min(3);
    let mut out = vec![(
        figure.to_string(),
        Drawn::Panels(Panels {
            plots,
            layout: Layout::Grid { columns },
        }),
    )];
    let audit = settings.len();
    let frame = inputs.table(audit, "audits", TABLE)?;
    let table = ConvergenceTable::from_frame(&frame)?;
    out.push((
        format!("{figure}_convergence"),
        Drawn::Panels(convergence_plots(figure, quantity, settings, &table)),
    ));
    out.push((format!("{figure}_convergence"), Drawn::Table(frame)));
    out.push((
        "convergence".into(),
        Drawn::Result(inputs.of(audit, "audits")?.results.clone()),
    ));
    Ok(out)
}

/// Fig. B.1: one panel per box, every realization in grey and the ensemble mean per load; a
/// grid's free slot holds every box's ensemble mean at the largest load.
fn box_panels(settings: &[StudyRef], tables: &[CcdfTable]) -> Vec<LinePlot> {
    let mut plots = Vec::new();
    for (s, table) in settings.iter().zip(tables) {
        let mut plot = LinePlot::new(
            format!("Fig. B.1: {}", s.label),
            "A/λ_s^2",
            "P(A > a)",
            true,
            YAxis::Log,
        );
        let loads = table.loads();
        for (j, &(load_index, w)) in loads.iter().enumerate() {
            for (r_i, &r) in table.realizations().iter().enumerate() {
                let label = if j == 0 && r_i == 0 {
                    "each realization"
                } else {
                    ""
                };
                plot.series.push(Series {
                    rgb: Some((170, 170, 170)),
                    width: 1,
                    name: format!("realization {r}"),
                    study: Some(s.study.clone()),
                    w_over_w0: Some(w),
                    ..Series::line(label, table.curve(load_index, Some(r), false), 0)
                });
            }
        }
        for (j, &(load_index, w)) in loads.iter().enumerate() {
            plot.series.push(Series {
                rgb: Some((213, 94, 0)),
                tint: 0.6 * (loads.len() - 1 - j) as f64 / (loads.len().max(2) - 1) as f64,
                study: Some(s.study.clone()),
                w_over_w0: Some(w),
                ..Series::line(
                    format!("ensemble mean, W/W_0 = {w:.3}"),
                    table.curve(load_index, None, true),
                    3,
                )
            });
        }
        plots.push(plot);
    }
    // A grid with a free slot holds every box's ensemble mean at the largest load, the
    // convergence the panels show one by one.
    let (rows, cols) = super::plot::grid(plots.len(), 3);
    if rows * cols > plots.len() {
        let mut all = LinePlot::new(
            "Fig. B.1: every box, largest load",
            "A/λ_s^2",
            "P(A > a), ensemble mean",
            true,
            YAxis::Log,
        );
        for (c, (s, table)) in settings.iter().zip(tables).enumerate() {
            if let Some(&(load_index, w)) = table.loads().last() {
                all.series.push(Series {
                    study: Some(s.study.clone()),
                    w_over_w0: Some(w),
                    ..Series::line(
                        format!("{}, W/W_0 = {w:.3}", s.label),
                        table.curve(load_index, None, true),
                        c,
                    )
                });
            }
        }
        plots.push(all);
    }
    plots
}

/// Fig. B.2: one panel per load, the ensemble mean of each discretisation.
fn discretisation_panels(settings: &[StudyRef], tables: &[CcdfTable]) -> Vec<LinePlot> {
    let mut plots = Vec::new();
    let loads = tables.first().map(CcdfTable::loads).unwrap_or_default();
    for &(load_index, w) in &loads {
        let mut plot = LinePlot::new(
            format!("Fig. B.2: W/W_0 = {w:.3}"),
            "A/λ_s^2",
            "P(A > a), ensemble mean",
            true,
            YAxis::Log,
        );
        for (c, (s, table)) in settings.iter().zip(tables).enumerate() {
            plot.series.push(Series {
                study: Some(s.study.clone()),
                w_over_w0: Some(w),
                ..Series::line(s.label.clone(), table.curve(load_index, None, true), c)
            });
        }
        plots.push(plot);
    }
    plots
}

/// One curve of a convergence figure: KS distance (markers) and its 95 % critical value
/// (dashed, labelled `critical_label`) on `ks`, exponent difference on `da`, against `x(row)`.
pub(super) fn push_convergence_curves(
    ks: &mut LinePlot,
    da: &mut LinePlot,
    label: &str,
    critical_label: &str,
    rows: &[&ConvergenceRow],
    x: impl Fn(&ConvergenceRow) -> f64,
    color: usize,
) {
    let marker = Some(Marker::ALL[color % Marker::ALL.len()]);
    ks.series.push(Series {
        marker,
        ..Series::line(label, rows.iter().map(|r| (x(r), r.ks)).collect(), color)
    });
    ks.series.push(Series {
        dash: Dash::Dotted,
        width: 2,
        // A single point of a dotted line would not show.
        marker: (rows.len() == 1).then_some(Marker::Cross),
        name: format!("95 % critical value, {label}"),
        ..Series::line(
            critical_label,
            rows.iter().map(|r| (x(r), r.critical)).collect(),
            color,
        )
    });
    da.series.push(Series {
        marker,
        ..Series::line(
            label,
            rows.iter()
                .filter_map(|r| Some((x(r), r.alpha? - r.alpha_reference?)))
                .collect(),
            color,
        )
    });
}

/// The convergence figure: KS distance and exponent difference to the finest setting against
/// the setting (one curve per load), and KS distance of `r` realizations to all of them.
fn convergence_plots(
    figure: &str,
    name: &str,
    settings: &[StudyRef],
    table: &ConvergenceTable,
) -> Panels {
    // figB1 → Fig. B.1
    let title = match figure.strip_prefix("figB") {
        Some(n) => format!("Fig. B.{n}"),
        None => figure.to_string(),
    };
    let mut ks = LinePlot::new(
        format!("{title}: KS distance to the finest"),
        name,
        "KS distance",
        false,
        YAxis::Linear,
    );
    let mut da = LinePlot::new(
        format!("{title}: α − α(finest)"),
        name,
        "α − α(finest), plateau + power-law MLE",
        false,
        YAxis::Linear,
    );
    let mut real = LinePlot::new(
        format!("{title}: first r realizations vs all"),
        "realizations r",
        "max KS distance over loads",
        false,
        YAxis::Linear,
    );
    real.x_integer = true;
    let mut loads: Vec<(u32, f64)> = table
        .rows
        .iter()
        .filter(|r| r.kind == "setting")
        .map(|r| (r.load_index, r.w_over_w0))
        .collect();
    loads.sort_by(|a, b| a.1.total_cmp(&b.1));
    loads.dedup_by(|a, b| a.1 == b.1);
    for (c, &(_, w)) in loads.iter().enumerate() {
        let rows: Vec<&ConvergenceRow> = table
            .rows
            .iter()
            .filter(|r| r.kind == "setting" && r.w_over_w0 == w)
            .collect();
        let critical = if c == 0 { "95 % critical value" } else { "" };
        let label = format!("W/W_0 = {w:.3}");
        push_convergence_curves(&mut ks, &mut da, &label, critical, &rows, |r| r.setting, c);
    }
    if let (Some(lo), Some(hi)) = (settings.first(), settings.last()) {
        ks.series
            .push(tolerance_line(CONVERGENCE_KS_TOLERANCE, lo.value, hi.value));
    }
    for (c, s) in settings.iter().enumerate() {
        let by_r = table.max_ks_by_realizations(s.value);
        real.series.push(Series {
            marker: Some(Marker::ALL[c % Marker::ALL.len()]),
            ..Series::line(s.label.clone(), by_r, c + 4)
        });
    }
    let most_realizations = table
        .rows
        .iter()
        .map(|r| r.realizations as f64)
        .fold(1.0, f64::max);
    real.series.push(tolerance_line(
        CONVERGENCE_KS_TOLERANCE,
        1.0,
        20.0_f64.min(most_realizations),
    ));
    Panels {
        plots: vec![ks, da, real],
        layout: Layout::Grid { columns: 3 },
    }
}
