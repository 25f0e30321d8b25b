//! The exponent table of a figure's section: α̂ by both estimators at the loads drawn, with
//! their intervals, α's systematic errors from the Appendix B audits, and what the tail is.

use std::fmt::Write as _;

use super::context::{escape, Context, Sizes};
use crate::config::FigureKind;
use crate::format::number;
use crate::pipeline::gallery::{FigureRecord, Provenance};
use crate::store::table::{f64_column, str_column};
use crate::store::Store;

/// α's systematic errors measured by the profile's Appendix B audits: per setting and load,
/// α at that setting less α at the family's reference (B.2: λ_s/Δl against the finest;
/// B.1: L/λ_l against the largest box), at λ_l/λ_s = 8, by the audits' estimator.
#[derive(Default)]
pub struct Systematic {
    /// (setting λ_s/Δl, W/W₀, Δα) of Fig. B.2's audit.
    discretisation: Vec<(f64, f64, f64)>,
    /// (setting L/λ_l, W/W₀, Δα) of Fig. B.1's audit.
    box_size: Vec<(f64, f64, f64)>,
}

impl Systematic {
    /// From the settings audits of the gallery's Appendix B figures, where it has them.
    pub(super) fn of(
        store: &Store,
        provenance: &Provenance,
        context: &Context,
    ) -> anyhow::Result<Self> {
        let mut out = Systematic::default();
        for f in &provenance.figures {
            let target = match context.kinds.get(&f.figure) {
                Some(FigureKind::AppendixB1) => &mut out.box_size,
                Some(FigureKind::AppendixB2) => &mut out.discretisation,
                _ => continue,
            };
            for d in f.drawn_from.iter().filter(|d| d.stage == "audits") {
                let Some(manifest) = store.lookup("audits", &d.key)? else {
                    continue;
                };
                let Ok(path) = store.read_output(&manifest, crate::stages::audits::TABLE) else {
                    continue;
                };
                let df = crate::store::table::read(&path)?;
                let (setting, w, diff) = (
                    f64_column(&df, "setting")?,
                    f64_column(&df, "w_over_w0")?,
                    f64_column(&df, "alpha_difference")?,
                );
                for i in 0..setting.len() {
                    if diff[i].is_finite() {
                        target.push((setting[i], w[i], diff[i]));
                    }
                }
            }
        }
        Ok(out)
    }

    /// Δα of `rows` at `setting`, at the load nearest to `load` (in ln W).
    fn at(rows: &[(f64, f64, f64)], setting: f64, load: f64) -> Option<f64> {
        rows.iter()
            .filter(|r| r.0 == setting)
            .min_by(|a, b| (a.1 / load).ln().abs().total_cmp(&(b.1 / load).ln().abs()))
            .map(|r| r.2)
    }

    /// The cell of a study with sizes `s` at `load`: "λ_s/Δl = 8: +0.06; L/λ_l = 2: −0.01"
    /// (a study at a family's reference setting: "the finest measured", "the largest").
    fn cell(&self, s: Option<&Sizes>, load: f64) -> String {
        let Some(s) = s.filter(|s| !s.measured) else {
            return String::new();
        };
        let part = |rows: &[(f64, f64, f64)], setting: f64, name: &str, reference: &str| {
            let largest = rows.iter().map(|r| r.0).fold(f64::NAN, f64::max);
            if setting == largest {
                Some(format!("{name} = {}: {reference}", number(setting)))
            } else {
                Self::at(rows, setting, load)
                    .map(|d| format!("{name} = {}: {d:+.2}", number(setting)))
            }
        };
        [
            part(
                &self.discretisation,
                s.lambda_s_over_dl,
                "λ<sub>s</sub>/Δl",
                "the finest measured",
            ),
            part(
                &self.box_size,
                s.l_over_lambda_l,
                "L/λ<sub>l</sub>",
                "the largest measured",
            ),
        ]
        .into_iter()
        .flatten()
        .collect::<Vec<_>>()
        .join("; ")
    }
}

/// One row per load of a statistics instance's exponents, the two estimators side by side
/// (α̂ and its 95 % interval), at the loads of the sweep nearest to `loads` (all when empty).
fn alpha_rows(
    store: &Store,
    key: &str,
    study: &str,
    loads: &[f64],
    systematic_at: &dyn Fn(f64) -> String,
    out: &mut String,
) -> anyhow::Result<()> {
    let Some(manifest) = store.lookup("statistics", key)? else {
        return Ok(());
    };
    let Ok(path) = store.read_output(&manifest, "alpha.parquet") else {
        return Ok(());
    };
    let df = crate::store::table::read(&path)?;
    let (w, est, a, lo, hi) = (
        f64_column(&df, "w_over_w0")?,
        str_column(&df, "estimator")?,
        f64_column(&df, "alpha")?,
        f64_column(&df, "ci95_low")?,
        f64_column(&df, "ci95_high")?,
    );
    // The truncated fit's goodness of fit and likelihood-ratio verdict, where computed.
    let gof = f64_column(&df, "gof_p").unwrap_or_else(|_| vec![f64::NAN; w.len()]);
    let verdict = str_column(&df, "tail_verdict").unwrap_or_else(|_| vec![String::new(); w.len()]);
    let method = str_column(&df, "ci95_method").unwrap_or_else(|_| vec![String::new(); w.len()]);
    let mut sweep: Vec<f64> = w.clone();
    sweep.sort_by(f64::total_cmp);
    sweep.dedup();
    let shown: Vec<f64> = if loads.is_empty() {
        sweep.clone()
    } else {
        let mut v: Vec<f64> = loads
            .iter()
            .filter_map(|&t| crate::statistics::nearest_in_log(&sweep, t).map(|i| sweep[i]))
            .collect();
        v.sort_by(f64::total_cmp);
        v.dedup();
        v
    };
    let cell = |load: f64, estimator: &str| -> String {
        match (0..w.len()).find(|&i| w[i] == load && est[i] == estimator) {
            Some(i) if a[i].is_finite() => {
                let ci = if lo[i].is_finite() && hi[i].is_finite() {
                    format!(" [{:.2}, {:.2}]", lo[i], hi[i])
                } else {
                    String::new()
                };
                format!("{:.2}{ci}", a[i])
            }
            _ => "–".into(),
        }
    };
    for load in shown {
        let tail = (0..w.len())
            .find(|&i| w[i] == load && est[i] == "discrete_truncated_mle")
            .map(|i| {
                let p = if gof[i].is_finite() {
                    format!("goodness of fit p = {:.2}", gof[i])
                } else if method[i] == crate::stages::statistics::alpha::NOT_SHOWN {
                    "point estimates only: no figure draws α at this load".to_string()
                } else {
                    "no goodness of fit".to_string()
                };
                if verdict[i].is_empty() {
                    p
                } else {
                    format!("{p}; {}", verdict[i])
                }
            })
            .unwrap_or_default();
        writeln!(
            out,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            escape(study),
            number(load),
            cell(load, "discrete_plateau_power_law_mle"),
            systematic_at(load),
            cell(load, "discrete_truncated_mle"),
            escape(&tail),
        )?;
    }
    Ok(())
}

/// The exponents α̂ of both estimators at the loads a figure draws (its declared loads; a
/// convergence figure's shared loads), for figures that draw exponents.
pub(super) fn exponents(
    h: &mut String,
    store: &Store,
    name: &str,
    records: &[&FigureRecord],
    studies: &[String],
    context: &Context,
    systematic: &Systematic,
) -> anyhow::Result<()> {
    if matches!(
        context.kinds.get(name),
        Some(FigureKind::Fig2 | FigureKind::Fig6) | None
    ) {
        return Ok(());
    }
    let mut loads = context.figure_loads.get(name).cloned().unwrap_or_default();
    if loads.is_empty() && context.kinds.get(name) == Some(&FigureKind::Convergence) {
        // A convergence figure compares its settings at the loads they share: the fewest.
        loads = studies
            .iter()
            .filter_map(|s| context.sizes.get(s))
            .map(|s| s.loads.clone())
            .min_by_key(|l| l.len())
            .unwrap_or_default();
    }
    let mut alphas = String::new();
    let mut seen: Vec<&str> = Vec::new();
    for d in records
        .iter()
        .flat_map(|r| &r.drawn_from)
        .filter(|d| d.stage == "statistics")
    {
        // A study drawn twice (Fig. 3's λ_l/λ_s = 128 is also its inset's H = 0.8) once.
        if seen.contains(&d.key.as_str()) {
            continue;
        }
        seen.push(&d.key);
        let sizes = d.studies.first().and_then(|s| context.sizes.get(s));
        let at = |load: f64| systematic.cell(sizes, load);
        alpha_rows(
            store,
            &d.key,
            &d.studies.join(", "),
            &loads,
            &at,
            &mut alphas,
        )?;
    }
    if !alphas.is_empty() {
        writeln!(
            h,
            "<details><summary>Exponents α̂ at the loads drawn</summary>\n<table>\n\
             <tr><th>study</th><th>W/W₀</th><th>plateau + power law (Appendix A's model) α̂ [95 %, statistical]</th>\
             <th>its systematic error: α at the study's λ<sub>s</sub>/Δl less α at the finest (Fig. B.2), at its L/λ<sub>l</sub> less at the largest box (Fig. B.1), both at λ<sub>l</sub>/λ<sub>s</sub> = 8</th>\
             <th>power law truncated at the largest area, above x<sub>min</sub>: α̂ [95 %]</th>\
             <th>the tail above x<sub>min</sub>: Clauset et al.'s goodness of fit; likelihood ratios against the power law</th></tr>\n{alphas}</table>\n</details>"
        )?;
    }
    Ok(())
}
