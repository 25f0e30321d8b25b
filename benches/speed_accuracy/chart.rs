//! The chart and its data file.

use std::path::Path;

use wearcoef::figures::plot::{
    power_of_ten, Dash, Layout, LegendAt, LinePlot, Marker, Panels, Series, YAxis,
};

use wearcoef::figures::plot::text::flat;

use crate::measure::Quantity;
use crate::{Panel, Point};

/// One row per (panel, code, setting, quantity, detail).
pub fn write_csv(path: &Path, panels: &[Panel]) -> anyhow::Result<()> {
    let mut w = csv::Writer::from_path(path)?;
    w.write_record([
        "panel",
        "knob",
        "code",
        "setting",
        "quantity",
        "detail",
        "error",
        "error_over_scatter",
        "seconds",
        "fft_pairs",
        "cost_relative_to_reference",
        "pipeline_setting",
        "chart_choice",
    ])?;
    for p in panels {
        for pt in &p.points {
            for (q, detail, raw, scaled) in &pt.errors {
                w.write_record([
                    p.title.clone(),
                    p.knob.to_string(),
                    pt.code.to_string(),
                    pt.setting.to_string(),
                    flat(q.label()),
                    detail.clone(),
                    raw.to_string(),
                    scaled.to_string(),
                    pt.seconds.to_string(),
                    pt.convolutions.map(|c| c.to_string()).unwrap_or_default(),
                    pt.cost.to_string(),
                    (pt.code == "wearcoef" && pt.setting == p.current).to_string(),
                    (pt.code == "wearcoef" && Some(pt.setting) == p.choice).to_string(),
                ])?;
            }
        }
    }
    w.flush()?;
    Ok(())
}

/// The setting as a short label: tolerances as powers of ten, others as numbers.
fn setting_label(knob: &str, v: f64) -> String {
    if knob == "tolerance" {
        power_of_ten(v.log10().round() as i32)
    } else {
        wearcoef::figures::plot::number(v)
    }
}

/// Largest finite value drawn (infinite errors are drawn there).
const CEILING: f64 = 1e3;

fn shown(e: f64) -> f64 {
    if e.is_finite() {
        e
    } else {
        CEILING
    }
}

/// The non-dominated points (cost, worst error) in order of cost, as a step line.
fn pareto(points: &[&Point]) -> Vec<(f64, f64)> {
    let mut sorted: Vec<(f64, f64)> = points.iter().map(|p| (p.cost, shown(p.worst()))).collect();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let mut front: Vec<(f64, f64)> = Vec::new();
    for p in sorted {
        if front.last().is_none_or(|l| p.1 < l.1) {
            front.push(p);
        }
    }
    let mut steps = Vec::new();
    for (i, p) in front.iter().enumerate() {
        if i > 0 {
            steps.push((p.0, front[i - 1].1));
        }
        steps.push(*p);
    }
    steps
}

/// Write each point's setting beside it; of the points whose error is exactly 0, only the
/// cheapest (the others sit beside it on the floor).
fn note_settings(lp: &mut LinePlot, knob: &str, points: &[&Point]) {
    let mut sorted: Vec<&&Point> = points.iter().collect();
    sorted.sort_by(|a, b| a.cost.total_cmp(&b.cost));
    let mut floor_noted = false;
    for x in sorted {
        if x.worst() == 0.0 {
            if floor_noted {
                continue;
            }
            floor_noted = true;
        }
        let mut note = setting_label(knob, x.setting);
        let lost = x.undefined();
        if !lost.is_empty() {
            let names: Vec<&str> = lost.iter().map(|q| q.symbol()).collect();
            note = format!("{note} (no {})", names.join(", "));
        }
        lp.notes.push(((x.cost, shown(x.worst())), note));
    }
}

fn plot(p: &Panel) -> LinePlot {
    let mut lp = LinePlot::new(
        p.title.clone(),
        p.x_label.clone(),
        "error / scatter between realizations",
        true,
        YAxis::Log,
    );
    let ours: Vec<&Point> = p.points.iter().filter(|x| x.code == "wearcoef").collect();
    let smallest = p
        .points
        .iter()
        .flat_map(|x| x.errors.iter().map(|e| e.3))
        .filter(|e| *e > 0.0)
        .fold(f64::INFINITY, f64::min);
    let floor = if smallest.is_finite() {
        10f64.powf(smallest.log10().floor() - 1.0)
    } else {
        1e-3
    };
    lp.y_floor = Some(floor.min(0.1));
    lp.y_marks = vec![1.0];
    lp.legend = LegendAt::Below;
    for (c, q) in Quantity::ALL.iter().enumerate() {
        let mut pts: Vec<(f64, f64)> = ours
            .iter()
            .filter_map(|x| x.error(*q).map(|e| (x.cost, shown(e))))
            .collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        lp.series.push(Series {
            marker: Some(Marker::ALL[c % Marker::ALL.len()]),
            width: 1,
            dash: Dash::Dotted,
            ..Series::line(q.label(), pts, c)
        });
    }
    lp.series.push(Series {
        width: 2,
        rgb: Some((0, 0, 0)),
        ..Series::line("Pareto front (worst quantity)", pareto(&ours), 0)
    });
    let peer: Vec<&Point> = p.points.iter().filter(|x| x.code == "Tamaas").collect();
    if !peer.is_empty() {
        let mut pts: Vec<(f64, f64)> = peer.iter().map(|x| (x.cost, shown(x.worst()))).collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        lp.series.push(Series {
            marker: Some(Marker::Cross),
            width: 1,
            dash: Dash::Dashed,
            rgb: Some((110, 110, 110)),
            ..Series::line("Tamaas (PyPI), worst quantity", pts, 0)
        });
    }
    note_settings(&mut lp, p.knob, &peer);
    let front = pareto(&ours);
    let on_front: Vec<&Point> = ours
        .iter()
        .copied()
        .filter(|x| front.contains(&(x.cost, shown(x.worst()))))
        .collect();
    note_settings(&mut lp, p.knob, &on_front);
    let mark = |setting: f64| -> Vec<(f64, f64)> {
        ours.iter()
            .filter(|x| x.setting == setting)
            .map(|x| (x.cost, shown(x.worst())))
            .collect()
    };
    let current = setting_label(p.knob, p.current);
    let label = if p.choice == Some(p.current) {
        format!("pipeline.yaml = chart's choice: {current}")
    } else {
        format!("pipeline.yaml: {current}")
    };
    lp.series.push(Series {
        marker: Some(Marker::Ring),
        width: 0,
        rgb: Some((0, 0, 0)),
        ..Series::line(label, mark(p.current), 0)
    });
    if let Some(c) = p.choice.filter(|c| *c != p.current) {
        lp.series.push(Series {
            marker: Some(Marker::Ring),
            width: 0,
            rgb: Some((213, 94, 0)),
            ..Series::line(
                format!("chart's choice: {}", setting_label(p.knob, c)),
                mark(c),
                1,
            )
        });
    }
    lp
}

pub fn draw(dir: &Path, panels: &[Panel]) -> anyhow::Result<()> {
    let figure = Panels {
        plots: panels.iter().map(plot).collect(),
        layout: Layout::Grid { columns: 3 },
    };
    figure.write(dir, "speed_accuracy")
}

/// The panels as Markdown tables (printed by `make speed-accuracy`; docs/BENCHMARKS.md quotes
/// them): per setting its cost, FFT pairs, worst error and each quantity's error, in units of
/// the scatter ("exact": 0; "none": undefined where the reference has a value).
pub fn markdown(panels: &[Panel]) -> String {
    let mut out = String::new();
    for p in panels {
        out.push_str(&format!("{}\n\n", p.title));
        out.push_str("| code | setting | cost / reference | FFT pairs | worst error / scatter | worst quantity |");
        for q in Quantity::ALL {
            out.push_str(&format!(" {} |", flat(q.symbol())));
        }
        out.push_str("\n|---|---|---|---|---|---|");
        out.push_str(&"---|".repeat(Quantity::ALL.len()));
        out.push('\n');
        for pt in &p.points {
            let ours = pt.code == "wearcoef";
            let mark = match (
                ours && pt.setting == p.current,
                ours && Some(pt.setting) == p.choice,
            ) {
                (true, true) => " (pipeline.yaml = chart)",
                (true, false) => " (pipeline.yaml)",
                (false, true) => " (chart)",
                _ => "",
            };
            let worst = pt.worst();
            let worst_q = pt
                .errors
                .iter()
                .filter(|e| !e.3.is_nan() && e.3 == worst && worst > 0.0)
                .map(|e| flat(e.0.label()))
                .next()
                .unwrap_or_else(|| "—".into());
            out.push_str(&format!(
                "| {} | {}{mark} | {:.3} | {} | {} | {worst_q} |",
                pt.code,
                flat(&setting_label(p.knob, pt.setting)),
                pt.cost,
                pt.convolutions.map_or("—".into(), |c| c.to_string()),
                error_text(worst),
            ));
            for q in Quantity::ALL {
                let cell = if pt.undefined().contains(&q) {
                    "none".to_string()
                } else {
                    pt.error(q).map_or("—".into(), error_text)
                };
                out.push_str(&format!(" {cell} |"));
            }
            out.push('\n');
        }
        out.push('\n');
    }
    out
}

/// An error in scatter units with two significant digits; 0 as "exact".
fn error_text(e: f64) -> String {
    if e == 0.0 {
        "exact".into()
    } else if e >= 10.0 {
        format!("{e:.0}")
    } else {
        let digits = (1 - e.log10().floor() as i32).max(0) as usize;
        format!("{e:.digits$}")
    }
}
