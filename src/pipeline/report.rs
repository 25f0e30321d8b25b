//! A gallery's report: `figures/<profile>/index.html`, one self-contained page (images beside
//! it, no network) with every figure, a caption saying what it shows and where it departs from
//! the paper, the numbers behind it (exponents with their intervals, audit verdicts) and the
//! store instances it was drawn from.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use super::gallery::{FigureRecord, Provenance};
use super::store::Store;
use super::table::{f64_column, str_column};
use crate::figures::plot::number;
use crate::stages::analytic::AreaLoadSlopeRecord;

/// Text with `&`, `<`, `>` and `"` escaped for HTML.
pub fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// What a figure (by file stem) shows and where it departs from the paper: trusted HTML
/// (subscripts as `<sub>`), written into the page as it is.
pub fn caption(stem: &str) -> &'static str {
    match stem {
        "fig2a" => "One realization of the Fig. 2 surface (H = 0.8, λ<sub>l</sub>/λ<sub>s</sub> = 8), heights in units of L scaled to unit rms slope. As in the paper.",
        "fig2b" | "fig2c" | "fig2d" => "Contact clusters of that realization at one load: yellow A ≤ A*, red A > A*, black out of contact (A* = 2 λ<sub>s</sub>², as in the paper). The load is the sweep's nearest to the paper's marked loads.",
        "fig2e" => "Contact area A<sub>c</sub>/L² and the largest cluster against load, ensemble means; dashed vertical lines mark the loads of Figs. 2b–d. Not in the paper: the small-load law A<sub>c</sub>/L² = κ W/W₀ fitted up to W/W₀ = 0.06 (black dashes; κ below). The paper uses 40 realizations and 50 loads; this profile's counts are in the table below.",
        "fig2f" => "dN/dA<sub>c</sub> by central differences of the ensemble means: positive where contact grows by new clusters, negative where clusters merge.",
        "fig2_convergence" => "Not in the paper: how far the first r realizations' means of Figs. 2e–f are from all of them (the realization audit), against its 5 % tolerance.",
        "fig3" => "Pooled PDF of cluster areas for λ<sub>l</sub>/λ<sub>s</sub> = 8, 32, 128 (H = 0.8) at three loads, with the discrete truncated power law fitted by maximum likelihood at the largest load (dashes, one per spectrum; drawn only over at least a decade). Inset: H = 0.6, 0.7, 0.8. The paper draws L/λ<sub>l</sub> = λ<sub>s</sub>/Δl = 8 with 20 realizations; this profile's sizes are those its convergence audits accept (below).",
        "fig4a" => "K(A*) = P(A > A*), the pooled complementary distribution, for the studies and loads of Fig. 3.",
        "fig4b" => "Archard's wear coefficient K against load for five A*: simulated (markers), and the plateau + power-law model fitted to the same distributions (dashes, same colours). The y axis is linear below 10⁻⁵, as in the paper.",
        "fig5a" => "The up-scaled coefficient 𝒦 = A<sub>c</sub>*/A<sub>c</sub> against load, simulated and fitted, for the A* of Fig. 4b. Bounded by 1.",
        "fig5b" => "Wear rate R/L² (ω = 1/3) against load for the A* of Fig. 4b.",
        "fig6" => "The power-law model alone (no simulation): K<sub>PL</sub> and 𝒦<sub>PL</sub> against A<sub>m</sub>/A<sub>s</sub> for α = 1.5, as in the paper.",
        "figB1" => "CCDF of cluster areas as the box grows (L/λ<sub>l</sub>), each realization in grey and the ensemble means per load. The paper goes to L/λ<sub>l</sub> = 16 with 20 realizations; this profile's largest box and counts are in the table below.",
        "figB2" => "Ensemble-mean CCDF as the discretisation λ<sub>s</sub>/Δl is refined, per load.",
        "figB1_convergence" | "figB2_convergence" => "Not in the paper: KS distance and exponent difference of each setting to the finest, and of the first r realizations to all, against the 0.05 tolerance that decides the sizes used elsewhere.",
        s if s.starts_with("fig128_convergence") => "Not in the paper: the λ<sub>l</sub>/λ<sub>s</sub> = 128 sizes against the convergence rule's reference (KS distance of the pooled areas, exponent difference, ensemble CCDFs, realizations).",
        s if s.contains("load_resolution") => "Not in the paper: Figs. 4b and 5 from fewer loads, interpolated, against a finer sweep of the same realizations, in units of the 95 % band.",
        _ => "",
    }
}

/// Rows (study, W/W₀, estimator, α, 95 % interval) of a statistics instance's exponents.
fn alpha_rows(store: &Store, key: &str, study: &str, out: &mut String) -> anyhow::Result<()> {
    let Some(manifest) = store.lookup("statistics", key)? else {
        return Ok(());
    };
    let Ok(path) = store.read_output(&manifest, "alpha.parquet") else {
        return Ok(());
    };
    let df = super::table::read(&path)?;
    let (w, est, a, lo, hi) = (
        f64_column(&df, "w_over_w0")?,
        str_column(&df, "estimator")?,
        f64_column(&df, "alpha")?,
        f64_column(&df, "ci95_low")?,
        f64_column(&df, "ci95_high")?,
    );
    for i in 0..w.len() {
        let ci = if lo[i].is_finite() && hi[i].is_finite() {
            format!("[{:.3}, {:.3}]", lo[i], hi[i])
        } else {
            "–".into()
        };
        writeln!(
            out,
            "<tr><td>{}</td><td>{:.4}</td><td>{}</td><td>{:.3}</td><td>{ci}</td></tr>",
            escape(study),
            w[i],
            escape(&est[i]),
            a[i]
        )?;
    }
    Ok(())
}

/// The plateau of K and the area–load slope of an analytic instance: table rows (A*/λₛ²,
/// load, α̂, K_PL plateau, K_PL at the load, simulated K ± band) and a sentence on κ.
fn analytic_lines(
    store: &Store,
    key: &str,
    study: &str,
    plateau: &mut String,
    slopes: &mut String,
) -> anyhow::Result<()> {
    let Some(manifest) = store.lookup("analytic", key)? else {
        return Ok(());
    };
    if let Some(s) = AreaLoadSlopeRecord::of(&manifest.results)? {
        writeln!(
            slopes,
            "<li>{}: κ = {:.3} ± {:.3} (least squares through the origin over {} loads, \
             W/W₀ = {}–{}); A<sub>c</sub>/(L² W/W₀) = {:.3} at the lowest load, {:.3} at \
             the highest.</li>",
            escape(study),
            s.kappa,
            s.kappa_ci95_correlated,
            s.loads,
            number(s.w_over_w0_range[0]),
            number(s.w_over_w0_range[1]),
            s.kappa_at_lowest_load,
            s.kappa_at_highest_load,
        )?;
    }
    let Ok(path) = store.read_output(&manifest, "plateau.parquet") else {
        return Ok(());
    };
    let df = super::table::read(&path)?;
    let c = |name: &str| f64_column(&df, name);
    let (a, w, alpha, lim, at, k, ci) = (
        c("a_star_over_ls2")?,
        c("w_over_w0")?,
        c("alpha")?,
        c("k_pl_plateau")?,
        c("k_pl_at_load")?,
        c("k_archard_mean")?,
        c("k_archard_ci95")?,
    );
    for i in 0..a.len() {
        writeln!(
            plateau,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{:.3}</td><td>{}</td><td>{}</td>\
             <td>{} ± {}</td></tr>",
            escape(study),
            number(a[i]),
            number(w[i]),
            alpha[i],
            number(lim[i]),
            number(at[i]),
            number(k[i]),
            number(ci[i])
        )?;
    }
    Ok(())
}

/// The audit verdicts among a figure's inputs, as `name: value` lines.
fn audit_lines(store: &Store, fig: &FigureRecord, out: &mut String) -> anyhow::Result<()> {
    for d in fig.drawn_from.iter().filter(|d| d.stage == "audits") {
        let Some(m) = store.lookup("audits", &d.key)? else {
            continue;
        };
        if let Some(obj) = m.results.as_object() {
            for (k, v) in obj {
                writeln!(
                    out,
                    "<tr><td>audit {}</td><td>{}</td><td><code>{}</code></td></tr>",
                    escape(&d.key[..12.min(d.key.len())]),
                    escape(k),
                    escape(&v.to_string())
                )?;
            }
        }
    }
    Ok(())
}

/// The page of a gallery.
pub fn render(
    store: &Store,
    provenance: &Provenance,
    descriptions: &BTreeMap<String, String>,
) -> anyhow::Result<String> {
    let mut h = String::new();
    let profile = escape(&provenance.profile);
    writeln!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <title>wearcoef: profile {profile}</title>\n<style>\n\
         body{{font-family:sans-serif;max-width:1000px;margin:2em auto;padding:0 1em;line-height:1.4}}\n\
         img{{max-width:100%;border:1px solid #ddd}}\n\
         table{{border-collapse:collapse;font-size:90%;margin:0.5em 0}}\n\
         td,th{{border:1px solid #ccc;padding:2px 6px;text-align:left}}\n\
         figcaption{{margin:0.3em 0 1em}}\n</style>\n</head>\n<body>\n\
         <h1>Figures of profile <code>{profile}</code></h1>\n\
         <p>Frérot, Aghababaei &amp; Molinari, “A mechanistic understanding of the wear \
         coefficient” (JMPS 2018), rebuilt by wearcoef. Each figure names the store instances it \
         was drawn from (<code>provenance.json</code> beside this page; the catalog maps keys to \
         files).</p>"
    )?;
    // The paper's figures first (by name: 2, 3–4a, 4b–5, 6, B.1, B.2), then the audits' own.
    let mut figures: Vec<&FigureRecord> = provenance.figures.iter().collect();
    figures.sort_by_key(|f| {
        let audit = f.figure.contains("convergence") || f.figure.contains("load_resolution");
        (audit, f.figure.clone())
    });
    for fig in figures {
        let desc = descriptions.get(&fig.figure).cloned().unwrap_or_default();
        writeln!(
            h,
            "<section id=\"f{2}\">\n<h2>{0}</h2>\n<p>{1}</p>",
            escape(&fig.figure),
            escape(&desc),
            escape(&fig.key[..12.min(fig.key.len())])
        )?;
        for file in fig.files.iter().filter(|f| f.ends_with(".png")) {
            let stem = file.trim_end_matches(".png");
            // Links to the files beside the image that exist: its data, its vector version.
            let links: Vec<String> = [("csv", "data"), ("npy", "data"), ("svg", "vector")]
                .iter()
                .map(|(ext, what)| (format!("{stem}.{ext}"), what))
                .filter(|(f, _)| fig.files.contains(f))
                .map(|(f, what)| format!("{what}: <a href=\"{0}\">{0}</a>", escape(&f)))
                .collect();
            writeln!(
                h,
                "<figure>\n<img src=\"{0}\" alt=\"{1}\">\n<figcaption><b>{1}.</b> {2} {3}.\
                 </figcaption>\n</figure>",
                escape(file),
                escape(stem),
                caption(stem),
                links.join("; ")
            )?;
        }
        let mut alphas = String::new();
        for d in fig.drawn_from.iter().filter(|d| d.stage == "statistics") {
            alpha_rows(store, &d.key, &d.studies.join(", "), &mut alphas)?;
        }
        if !alphas.is_empty() {
            writeln!(
                h,
                "<details><summary>Exponents α̂ behind it</summary>\n<table>\n\
                 <tr><th>study</th><th>W/W₀</th><th>estimator</th><th>α̂</th>\
                 <th>bootstrap 95 % CI</th></tr>\n{alphas}</table>\n</details>"
            )?;
        }
        let (mut plateau, mut slopes) = (String::new(), String::new());
        for d in fig.drawn_from.iter().filter(|d| d.stage == "analytic") {
            analytic_lines(
                store,
                &d.key,
                &d.studies.join(", "),
                &mut plateau,
                &mut slopes,
            )?;
        }
        let max = number(crate::stages::analytic::MILD_WEAR_MAX_LOAD);
        if !slopes.is_empty() {
            writeln!(
                h,
                "<p>Area–load slope: the small-load law A<sub>c</sub>/L² = κ W/W₀ \
                 (W₀ = E* h′<sub>rms</sub> L²) \
                 fitted to the ensemble means up to W/W₀ = {max}. The ± is the 95 % band if \
                 every load's mean moved together (a bound).</p>\n<ul>\n{slopes}</ul>"
            )?;
        }
        if !plateau.is_empty() {
            writeln!(
                h,
                "<details open><summary>Plateau of K</summary>\n\
                 <p>K<sub>PL</sub>(A*) in the limit A<sub>m</sub> → ∞ from the power-law fit \
                 (α̂, A<sub>s</sub>) at the largest load up to W/W₀ = {max}, beside the model at \
                 that load's cut-off A<sub>m</sub> \
                 and the simulated K (ensemble mean ± 95 % band) there.</p>\n<table>\n\
                 <tr><th>study</th><th>A*/λₛ²</th><th>W/W₀</th><th>α̂</th>\
                 <th>K<sub>PL</sub> plateau</th><th>K<sub>PL</sub> at W</th><th>simulated K at W</th></tr>\n\
                 {plateau}</table>\n</details>"
            )?;
        }
        let mut audits = String::new();
        audit_lines(store, fig, &mut audits)?;
        if !audits.is_empty() {
            writeln!(
                h,
                "<details><summary>Audit verdicts</summary>\n<table>\n{audits}</table>\n</details>"
            )?;
        }
        writeln!(
            h,
            "<details><summary>Drawn from</summary>\n<table>\n\
             <tr><th>stage</th><th>key</th><th>studies</th></tr>\n\
             <tr><td>figures</td><td><code>{}</code></td><td></td></tr>",
            escape(&fig.key)
        )?;
        for d in &fig.drawn_from {
            writeln!(
                h,
                "<tr><td>{}</td><td><code>{}</code></td><td>{}</td></tr>",
                escape(&d.stage),
                escape(&d.key),
                escape(&d.studies.join(", "))
            )?;
        }
        writeln!(h, "</table>\n</details>\n</section>")?;
    }
    writeln!(h, "</body>\n</html>")?;
    Ok(h)
}

/// Write the page as `index.html` in `dir`, through a temporary file.
pub fn write(
    store: &Store,
    dir: &Path,
    provenance: &Provenance,
    descriptions: &BTreeMap<String, String>,
) -> anyhow::Result<()> {
    let page = render(store, provenance, descriptions)?;
    crate::io::atomic::write_atomically(&dir.join("index.html"), |tmp| {
        Ok(std::fs::write(tmp, page)?)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_is_escaped_and_every_paper_figure_has_a_caption() {
        assert_eq!(escape("a<b & \"c\">"), "a&lt;b &amp; &quot;c&quot;&gt;");
        for stem in [
            "fig2a", "fig2b", "fig2e", "fig2f", "fig3", "fig4a", "fig4b", "fig5a", "fig5b", "fig6",
            "figB1", "figB2",
        ] {
            let c = caption(stem);
            assert!(!c.is_empty(), "{stem}");
            // Trusted HTML: subscripts only, balanced, no ASCII subscript left.
            let tags = c.matches('<').count();
            let (open, close) = (c.matches("<sub>").count(), c.matches("</sub>").count());
            assert!(open == close && tags == open + close, "{stem}: {c}");
            assert!(!c.contains('_') && !c.contains('&'), "{stem}: {c}");
        }
    }
}
