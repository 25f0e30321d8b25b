//! Audit verdicts in words: the report's sentences for the settings (convergence),
//! realization and load-resolution audits, from their manifests' results.

use std::fmt::Write as _;

use serde_json::Value;

use super::context::escape;
use crate::format::number;
use crate::pipeline::gallery::FigureRecord;
use crate::store::Store;

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

/// A settings (convergence) audit's verdict in words.
fn settings_sentences(r: &Value) -> String {
    let tolerance = f(&r["tolerance"]);
    let mut out = format!(
        "Reference: {} (KS tolerance {}).",
        escape(r["reference"].as_str().unwrap_or("?")),
        number(tolerance)
    );
    for s in r["settings"].as_array().into_iter().flatten() {
        let by_load: Vec<String> = s["ks_by_load"]
            .as_array()
            .into_iter()
            .flatten()
            .zip(s["ks_critical_95_by_load"].as_array().into_iter().flatten())
            .map(|(k, c)| {
                format!(
                    "{:.3} at W/W₀ = {} (critical {:.3})",
                    f(&k[1]),
                    number(f(&k[0])),
                    f(&c[1])
                )
            })
            .collect();
        let within = s["within_tolerance"].as_bool().unwrap_or(false);
        let _ = write!(
            out,
            " {}: KS {}; {} the tolerance at every load{}.",
            escape(s["setting"].as_str().unwrap_or("?")),
            by_load.join(", "),
            if within { "within" } else { "not within" },
            if s["below_critical_at_every_load"].as_bool() == Some(true) {
                ", and not distinguishable from the reference by its realizations"
            } else {
                ""
            }
        );
    }
    if let Some(v) = r["smallest_converged_setting"].as_f64() {
        let _ = write!(
            out,
            " The rule's choice (smallest setting within the tolerance from there on): {}.",
            number(v)
        );
    }
    if let Some(m) = r["smallest_converged_realizations_by_setting"].as_object() {
        let mut by_setting: Vec<(f64, &str, u64)> = m
            .iter()
            .map(|(k, v)| {
                (
                    k.parse().unwrap_or(f64::NAN),
                    k.as_str(),
                    v.as_u64().unwrap_or(0),
                )
            })
            .collect();
        by_setting.sort_by(|a, b| a.0.total_cmp(&b.0));
        let parts: Vec<String> = by_setting
            .iter()
            .map(|(_, k, v)| format!("{k}: {v}"))
            .collect();
        let _ = write!(
            out,
            " Realizations from which the first r stay within the tolerance of all: {}.",
            escape(&parts.join("; "))
        );
    }
    out
}

/// A realization audit's verdict (Fig. 2e–f) in words.
fn realization_sentences(r: &Value) -> String {
    let ci = &r["max_rel_ci95_at_all_realizations"];
    format!(
        "The means of the first r of {} realizations stay within {} % of all of them at every \
         load, and the load of N's peak within {} load step(s), from r = {}. At all {}, the \
         95 % half-widths reach ±{:.0} % for A<sub>c</sub>, ±{:.0} % for N and ±{:.0} % for the \
         largest cluster. N peaks at W/W₀ = {}.",
        r["realizations"].as_u64().unwrap_or(0),
        number(100.0 * f(&r["tolerance_rel_deviation"])),
        r["tolerance_peak_load_steps"].as_u64().unwrap_or(0),
        r["smallest_converged_realizations"]
            .as_u64()
            .map_or("none".to_string(), |v| v.to_string()),
        r["realizations"].as_u64().unwrap_or(0),
        100.0 * f(&ci["area"]),
        100.0 * f(&ci["count"]),
        100.0 * f(&ci["largest"]),
        number(f(&r["count_peak_w_over_w0"]))
    )
}

/// A load-resolution audit's verdict in words.
fn load_resolution_sentences(r: &Value) -> String {
    let e = &r["max_error_over_ci95"];
    let mut out = format!(
        "The {} loads interpolated against {} loads of the same realizations: {} of {} \
         points within the 95 % band ({} at transitions not judged); largest error in bands: \
         K {:.2}, 𝒦 {:.2}, wear rate {:.2}. Rule {}.",
        r["chosen_loads"].as_u64().unwrap_or(0),
        r["fine_loads"].as_u64().unwrap_or(0),
        r["points_judged"].as_u64().unwrap_or(0)
            - r["points_beyond_band"]
                .as_array()
                .map_or(0, |a| a.len() as u64),
        r["points_judged"].as_u64().unwrap_or(0),
        r["points_at_transition"].as_u64().unwrap_or(0),
        f(&e["k_archard"]),
        f(&e["k_upscaled"]),
        f(&e["wear_rate_over_l2"]),
        if r["rule_met"].as_bool() == Some(true) {
            "met"
        } else {
            "not met at every point"
        }
    );
    for p in r["points_beyond_band"].as_array().into_iter().flatten() {
        let _ = write!(
            out,
            " Beyond: {} at A* = {} λ<sub>s</sub>², W/W₀ = {} ({:.2} bands; the finer sweep's \
             neighbouring loads miss it by {:.2}).",
            escape(p["curve"].as_str().unwrap_or("?")),
            number(f(&p["a_star_over_ls2"])),
            number(f(&p["w_over_w0"])),
            f(&p["error_over_ci95"]),
            f(&p["neighbour_error_over_ci95"])
        );
    }
    out
}

/// The audit verdicts among a figure's inputs, as paragraphs of sentences.
pub(super) fn audit_lines(
    store: &Store,
    fig: &FigureRecord,
    out: &mut String,
) -> anyhow::Result<()> {
    for d in fig.drawn_from.iter().filter(|d| d.stage == "audits") {
        let Some(m) = store.lookup("audits", &d.key)? else {
            continue;
        };
        let r = &m.results;
        let text = match m.params["audit"].as_str() {
            Some("settings") => settings_sentences(r),
            Some("realizations") => realization_sentences(r),
            Some("load_resolution") => load_resolution_sentences(r),
            _ => escape(&r.to_string()),
        };
        writeln!(out, "<p>{text}</p>")?;
    }
    Ok(())
}
