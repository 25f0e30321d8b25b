//! A gallery's report: `figures/<profile>/index.html`, one self-contained page (images beside
//! it, no network) with one section per figure: its parameters beside the paper's, each image
//! with a caption saying what it shows, the numbers behind it (exponents at the loads it draws
//! with their intervals, fits, audit verdicts in words) and the store instances it was drawn
//! from.

use std::fmt::Write as _;
use std::path::Path;

mod context;
mod exponents;
mod verdicts;

pub use context::{escape, Context, Sizes};
use exponents::{exponents, Systematic};
use verdicts::audit_lines;

use super::gallery::{FigureRecord, Provenance};
use crate::config::FigureKind;
use crate::format::number;
use crate::stages::analytic::AreaLoadSlopeRecord;
use crate::store::table::f64_column;
use crate::store::Store;

/// What a figure (by file stem) shows and where it departs from the paper: trusted HTML
/// (subscripts as `<sub>`), written into the page as it is.
/// The captions that differ for a measured study's maps (no spectrum, not periodic, no
/// claim about where its cluster count peaks).
fn measured_caption(stem: &str) -> Option<&'static str> {
    Some(match stem {
        "fig2a" => "The measured study's first file as prepared for contact (form removed, missing points filled as its preparation says), heights in metres, axes in units of the map's sides.",
        "fig2b" => "Contact clusters of that map at the lowest of the three marked loads (dashed line b in Fig. 2e), labelled without wrap-around: yellow A ≤ A*, red A > A*, black out of contact (A* = 2 λ<sub>s</sub>², λ<sub>s</sub> as the study states it).",
        "fig2d" => "The same map at the highest marked load (line d in Fig. 2e).",
        _ => return None,
    })
}

pub fn caption(stem: &str) -> &'static str {
    match stem {
        "fig2a" => "One realization of the Fig. 2 surface (H = 0.8, λ<sub>l</sub>/λ<sub>s</sub> = 8), heights in units of L scaled to unit rms slope. As in the paper.",
        "fig2b" => "Contact clusters of that realization at the lowest of the three marked loads (dashed line b in Fig. 2e): yellow A ≤ A*, red A > A*, black out of contact (A* = 2 λ<sub>s</sub>², as in the paper). Few, small clusters.",
        "fig2c" => "The same realization at the middle marked load (line c in Fig. 2e): more clusters, and the first larger than A*.",
        "fig2d" => "The same realization at the highest marked load (line d in Fig. 2e), past the peak of the cluster count (Fig. 2f): clusters merge.",
        "fig2e" => "Contact area A<sub>c</sub>/L² (top) and the largest cluster (bottom) against load: ensemble means with their 95 % bands; dashed vertical lines b, c, d mark the loads of Figs. 2b–d. Not in the paper: the small-load law A<sub>c</sub>/L² = κ W/W₀ fitted up to W/W₀ = 0.06 (black dashes; κ below). The paper draws both on one plot.",
        "fig2f" => "dN/dA<sub>c</sub> by central differences of the ensemble means: positive where contact grows by new clusters, negative where clusters merge.",
        "fig2_convergence" => "Not in the paper: how far the first r realizations' means of Figs. 2e–f are from all of them (the realization audit), against its 5 % tolerance.",
        "fig3" => "Pooled PDF of cluster areas for λ<sub>l</sub>/λ<sub>s</sub> = 8, 32, 128 (H = 0.8) at three loads, with the plateau + power law (the model of Appendix A; the paper says only “a maximum likelihood estimator”) fitted by maximum likelihood at the largest load (dashes, one per spectrum) and its 95 % interval over realizations; the α̂ of the power law truncated at the largest area above x<sub>min</sub> is named beside it, or “rejected” where its goodness of fit rejects it. Inset: H = 0.6, 0.7, 0.8 on equal boxes at one load.",
        "fig4a" => "K(A*) = P(A > A*), the pooled complementary distribution, for the studies and loads of Fig. 3.",
        "fig4b" => "Archard's wear coefficient K against load for five A*: simulated (markers, pooled over realizations; shaded: the 95 % band of the realizations' mean), and the plateau + power-law model fitted to the same distributions (dashes, same colours). The y axis is linear below 10⁻⁵, as in the paper.",
        "fig5a" => "The up-scaled coefficient 𝒦 = A<sub>c</sub>*/A<sub>c</sub> against load, simulated (with 95 % bands) and fitted, for the A* of Fig. 4b. Bounded by 1.",
        "fig5b" => "Wear rate R/L² (ω = 1/3) against load for the A* of Fig. 4b: realizations' mean with its 95 % band.",
        "fig45_dn_dac" => "Not in the paper: dN/dA<sub>c</sub> on the spectrum of Figs. 4b–5b, the regime they are drawn in (positive: contact grows by new clusters, the mild-wear regime the paper assumes; negative: by merging).",
        "fig6" => "The power-law model alone (no simulation): K<sub>PL</sub> and 𝒦<sub>PL</sub> against A<sub>m</sub>/A<sub>s</sub> for α = 1.5, as in the paper.",
        "figB1" => "CCDF of cluster areas as the box grows (L/λ<sub>l</sub>), each realization in grey and the ensemble means per load. The paper goes to L/λ<sub>l</sub> = 16 with 20 realizations; this profile's largest box and counts are in the table below.",
        "figB2" => "Ensemble-mean CCDF as the discretisation λ<sub>s</sub>/Δl is refined, per load.",
        "figB1_convergence" | "figB2_convergence" => "Not in the paper: KS distance and exponent difference of each setting to the finest, and of the first r realizations to all, against the 0.05 tolerance that decides the sizes used elsewhere.",
        "fig128_discretisation" => "Not in the paper: the λ<sub>l</sub>/λ<sub>s</sub> = 128 study of Figs. 3–5 against one discretisation finer (λ<sub>s</sub>/Δl = 16): KS distance of the pooled areas with its 95 % critical value, exponent difference, ensemble CCDFs, realizations.",
        s if s.starts_with("fig128_convergence") => "Not in the paper: the λ<sub>l</sub>/λ<sub>s</sub> = 128 sizes against the convergence rule's reference (KS distance of the pooled areas, exponent difference, ensemble CCDFs, realizations).",
        "plastic_alpha" => "Not in the paper: the cluster-area exponent α̂ of one λ<sub>l</sub>/λ<sub>s</sub> = 128 surface (fig3_ll128's first, at its sizes) under a perfectly plastic interface of hardness 𝓗, against E*h'<sub>rms</sub>/𝓗 (0: elastic), at three loads, by both estimators with their 95 % intervals over realizations (none below 5 realizations). The dotted line is α = 2, above which the power-law model's 𝒦 tends to a limit below 1 (the paper's §5 question).",
        "plastic_k" => "Not in the paper: Archard's K = P(A > A*) against load for each hardness, at A* = 2 λ<sub>s</sub>² (solid) and 32 λ<sub>s</sub>² (dashed); one realization, so no band.",
        "plastic_k_upscaled" => "Not in the paper: the up-scaled 𝒦 = A<sub>c</sub>*/A<sub>c</sub> against load for each hardness, at the two A* of the K panel.",
        "plastic_saturated" => "Not in the paper: the share of the contact area where the pressure sits on the hardness, against load.",
        "spectrum_alpha" => "Not in the paper (its §5 postulate): the cluster-area exponent α̂ against the spectrum's width λ<sub>l</sub>/λ<sub>s</sub> = 8 … 1024 (H = 0.8, L/λ<sub>l</sub> = 2, λ<sub>s</sub>/Δl = 8, up to 16384² grids), at three loads, by both estimators with their 95 % intervals. The paper stopped at 128.",
        "spectrum_k" => "Not in the paper: Archard's K = P(A > A*) at W/W₀ = 0.06, the end of the mild-wear range, against λ<sub>l</sub>/λ<sub>s</sub> at the A* of Fig. 4b (pooled over realizations, 95 % band of their mean), with the plateau + power-law model fitted at the same load (dashes). K = 0 (no cluster above A*) is not drawn.",
        "spectrum_k_upscaled" => "Not in the paper: the up-scaled 𝒦 = A<sub>c</sub>*/A<sub>c</sub> at W/W₀ = 0.06 against λ<sub>l</sub>/λ<sub>s</sub>, at the A* of Fig. 4b, simulated and fitted.",
        "spectrum_interval" => "Not in the paper: the upper end of the power-law interval against λ<sub>l</sub>/λ<sub>s</sub> at three loads: the largest cluster (mean over realizations, 95 % band) and the cut-off A<sub>m</sub> of the fitted plateau + power-law model (dashes).",
        "spectrum_transition" => "Not in the paper: the load where dN/dA<sub>c</sub> changes sign (the end of the nucleation regime, interpolated in ln W) against λ<sub>l</sub>/λ<sub>s</sub>; a triangle at the sweep's highest load means dN/dA<sub>c</sub> stays positive over the whole sweep.",
        "spectrum_k_physical" => "Not in the paper: K at W/W₀ = 0.06 for thresholds fixed on the scale of λ<sub>l</sub> (A* = λ<sub>l</sub>²/512, /128, /32), read from the pooled exact CCDF: a fixed material and a fixed largest wavelength, with a spectrum widened by shrinking λ<sub>s</sub>. K = 0 is not drawn.",
        s if s.contains("load_resolution") => "Not in the paper: Figs. 4b and 5 from fewer loads, interpolated, against a finer sweep of the same realizations, in units of the 95 % band.",
        _ => "",
    }
}

/// The plateau of K and the area–load slope of an analytic instance: table rows (A*/λₛ²,
/// load, α̂, K_PL plateau, K_PL at the load, simulated K with its interval and counts) and a
/// sentence on κ.
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
            "<li>{}: κ = {:.3}{} (least squares through the origin over {} loads, \
             W/W₀ = {}–{}); A<sub>c</sub>/(L² W/W₀) = {:.3} at the lowest load, {:.3} at \
             the highest.</li>",
            escape(study),
            s.kappa,
            s.kappa_ci95_correlated.map_or_else(
                || " (no interval: fewer than 5 realizations)".to_string(),
                |b| format!(" ± {b:.3}")
            ),
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
    let df = crate::store::table::read(&path)?;
    let c = |name: &str| f64_column(&df, name);
    let (a, w, alpha, lim, at) = (
        c("a_star_over_ls2")?,
        c("w_over_w0")?,
        c("alpha")?,
        c("k_pl_plateau")?,
        c("k_pl_at_load")?,
    );
    let simulated = SimulatedK::of_inputs(store, &manifest.inputs)?;
    for i in 0..a.len() {
        writeln!(
            plateau,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{:.3}</td><td>{}</td><td>{}</td>\
             <td>{}</td></tr>",
            escape(study),
            number(a[i]),
            number(w[i]),
            alpha[i],
            number(lim[i]),
            number(at[i]),
            simulated.cell(a[i], w[i]),
        )?;
    }
    Ok(())
}

/// The simulated K of a statistics instance's `wear.parquet`, per (A*/λₛ², W/W₀): pooled, its
/// interval over realizations (clipped to [0, 1]) and the clusters above A* behind it.
struct SimulatedK {
    rows: Vec<SimulatedRow>,
}

struct SimulatedRow {
    a_star_over_ls2: f64,
    w_over_w0: f64,
    pooled: f64,
    low: f64,
    high: f64,
    clusters: u64,
    fewest_in_a_realization: u64,
}

impl SimulatedK {
    /// From the first of `inputs` that is a statistics instance with a wear table.
    fn of_inputs(store: &Store, inputs: &[String]) -> anyhow::Result<Self> {
        for key in inputs {
            let Some(m) = store.lookup("statistics", key)? else {
                continue;
            };
            let Ok(path) = store.read_output(&m, "wear.parquet") else {
                continue;
            };
            let df = crate::store::table::read(&path)?;
            let c = |name: &str| f64_column(&df, name);
            let (a, w, k, lo, hi, n, fewest) = (
                c("a_star_over_ls2")?,
                c("w_over_w0")?,
                c("k_archard_pooled")?,
                c("k_archard_pooled_ci95_low")?,
                c("k_archard_pooled_ci95_high")?,
                crate::store::table::u64_column(&df, "clusters_above")?,
                crate::store::table::u64_column(&df, "clusters_above_smallest_realization")?,
            );
            let rows = (0..a.len())
                .map(|i| SimulatedRow {
                    a_star_over_ls2: a[i],
                    w_over_w0: w[i],
                    pooled: k[i],
                    low: lo[i],
                    high: hi[i],
                    clusters: n[i],
                    fewest_in_a_realization: fewest[i],
                })
                .collect();
            return Ok(Self { rows });
        }
        Ok(Self { rows: Vec::new() })
    }

    /// "0.0127 [0.0111, 0.0143]; 95 clusters, fewest in a realization 11" (no interval
    /// below 5 realizations), or "–" where the table has no such row.
    fn cell(&self, a_star_over_ls2: f64, w_over_w0: f64) -> String {
        let Some(r) = self
            .rows
            .iter()
            .find(|r| r.a_star_over_ls2 == a_star_over_ls2 && r.w_over_w0 == w_over_w0)
        else {
            return "–".into();
        };
        let interval = if r.low.is_finite() && r.high.is_finite() {
            format!(" [{}, {}]", number(r.low), number(r.high))
        } else {
            String::new()
        };
        // Drawn hollow in the figures: a K on few clusters, or whose interval reaches 0.
        let tentative = r.pooled > 0.0
            && (r.clusters < crate::statistics::TENTATIVE_BELOW_CLUSTERS || r.low <= 0.0);
        format!(
            "{}{interval}; {} clusters, fewest in a realization {}{}",
            number(r.pooled),
            r.clusters,
            r.fewest_in_a_realization,
            if tentative { " (tentative)" } else { "" }
        )
    }
}

/// The parameter table of a figure's studies: this profile's sizes beside the paper's.
fn parameter_table(context: &Context, studies: &[String]) -> String {
    let mut rows = String::new();
    for study in studies {
        let Some(s) = context.sizes.get(study) else {
            continue;
        };
        let paper = context.paper.get(study);
        // A measured study's files set these: the cell says so.
        let generated = |text: String| {
            if s.measured {
                "measured".to_string()
            } else {
                text
            }
        };
        let cell = |ours: String, theirs: Option<String>| match theirs {
            Some(t) if t != ours => format!("<b>{ours}</b> (paper {t})"),
            Some(_) => ours,
            None => ours,
        };
        let _ = writeln!(
            rows,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>\
             <td>{}</td><td>{}</td></tr>",
            escape(study),
            generated(number(s.hurst)),
            generated(number(s.lambda_l_over_lambda_s)),
            generated(cell(
                number(s.l_over_lambda_l),
                paper.map(|p| number(p.l_over_lambda_l))
            )),
            cell(
                number(s.lambda_s_over_dl),
                paper.map(|p| number(p.lambda_s_over_dl))
            ),
            generated(cell(s.n.to_string(), paper.map(|p| p.n.to_string()))),
            cell(
                s.realizations.to_string(),
                paper.map(|p| p.realizations.to_string())
            ),
            cell(s.loads_text(), paper.map(Sizes::loads_text)),
            cell(
                format!("{:e}", s.tolerance),
                paper.map(|p| format!("{:e}", p.tolerance))
            ),
        );
    }
    if rows.is_empty() {
        return rows;
    }
    format!(
        "<table>\n<tr><th>study</th><th>H</th><th>λ<sub>l</sub>/λ<sub>s</sub></th>\
         <th>L/λ<sub>l</sub></th><th>λ<sub>s</sub>/Δl</th><th>n</th><th>realizations</th>\
         <th>loads W/W₀</th><th>solver tolerance</th></tr>\n{rows}</table>\n\
         <p>Bold: departs from the paper's value (in parentheses; profile <code>paper</code>). \
         Studies without one are not in the paper.</p>"
    )
}

/// The page of a gallery.
pub fn render(store: &Store, provenance: &Provenance, context: &Context) -> anyhow::Result<String> {
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
         figcaption{{margin:0.3em 0 1em}}\nh2 code{{font-size:70%;color:#555}}\n</style>\n\
         </head>\n<body>\n\
         <h1>Figures of profile <code>{profile}</code></h1>\n\
         <p>Frérot, Aghababaei &amp; Molinari, “A mechanistic understanding of the wear \
         coefficient” (JMPS 2018), rebuilt by wearcoef. Each figure names the store instances it \
         was drawn from (<code>provenance.json</code> beside this page; the catalog maps keys to \
         files). How each number compares with the paper's: docs/FIDELITY.md.</p>"
    )?;
    // One section per declared figure (a figure may have several instances, e.g. Fig. 2's
    // maps and curves): the paper's figures first, then the audits' own.
    let mut names: Vec<&str> = provenance
        .figures
        .iter()
        .map(|f| f.figure.as_str())
        .collect();
    names.dedup();
    names.sort_by_key(|n| {
        let audit = matches!(
            context.kinds.get(*n),
            Some(FigureKind::Convergence | FigureKind::LoadResolution)
        );
        (audit, n.to_string())
    });
    names.dedup();
    let systematic = Systematic::of(store, provenance, context)?;
    for name in names {
        let records: Vec<&FigureRecord> = provenance
            .figures
            .iter()
            .filter(|f| f.figure == name)
            .collect();
        section(&mut h, store, name, &records, context, &systematic)?;
    }
    writeln!(h, "</body>\n</html>")?;
    Ok(h)
}

/// The studies a figure was drawn from, in order of first appearance.
fn studies_of(records: &[&FigureRecord]) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for d in records.iter().flat_map(|r| &r.drawn_from) {
        for s in &d.studies {
            if !out.contains(s) {
                out.push(s.clone());
            }
        }
    }
    out
}

/// One figure's section: heading, parameters, images with captions, exponents, fits, audit
/// verdicts and the instances it was drawn from.
fn section(
    h: &mut String,
    store: &Store,
    name: &str,
    records: &[&FigureRecord],
    context: &Context,
    systematic: &Systematic,
) -> anyhow::Result<()> {
    let desc = context.descriptions.get(name).cloned().unwrap_or_default();
    let heading = if desc.is_empty() { name } else { desc.as_str() };
    writeln!(
        h,
        "<section id=\"{0}\">\n<h2>{1} <code>{0}</code></h2>",
        escape(name),
        escape(heading)
    )?;
    let studies = studies_of(records);
    h.push_str(&parameter_table(context, &studies));
    images(h, records, &studies, context)?;
    exponents(h, store, name, records, &studies, context, systematic)?;
    fits(h, store, records)?;
    let mut audits = String::new();
    for fig in records {
        audit_lines(store, fig, &mut audits)?;
    }
    if !audits.is_empty() {
        writeln!(h, "<h3>Audit verdicts</h3>\n{audits}")?;
    }
    drawn_from(h, records)?;
    writeln!(h, "</section>")?;
    Ok(())
}

/// Each image of a figure with its caption and links to its data and vector files; the maps
/// of Fig. 2b–d with their study's kept loads.
fn images(
    h: &mut String,
    records: &[&FigureRecord],
    studies: &[String],
    context: &Context,
) -> anyhow::Result<()> {
    let kept: Vec<f64> = studies
        .iter()
        .filter_map(|s| context.sizes.get(s))
        .flat_map(|s| s.kept_loads.clone())
        .collect();
    let measured = studies
        .iter()
        .any(|s| context.sizes.get(s).is_some_and(|z| z.measured));
    for fig in records {
        for file in fig.files.iter().filter(|f| f.ends_with(".png")) {
            let stem = file.trim_end_matches(".png");
            // Links to the files beside the image that exist: its data, its vector version.
            let links: Vec<String> = [("csv", "data"), ("npy", "data"), ("svg", "vector")]
                .iter()
                .map(|(ext, what)| (format!("{stem}.{ext}"), what))
                .filter(|(f, _)| fig.files.contains(f))
                .map(|(f, what)| format!("{what}: <a href=\"{0}\">{0}</a>", escape(&f)))
                .collect();
            let load = ["fig2b", "fig2c", "fig2d"]
                .iter()
                .position(|m| *m == stem)
                .and_then(|i| kept.get(i))
                .map(|w| format!(" W/W₀ = {}.", number(*w)))
                .unwrap_or_default();
            writeln!(
                h,
                "<figure>\n<img src=\"{0}\" alt=\"{1}\">\n<figcaption><b>{1}.</b> {2}{load} {3}.\
                 </figcaption>\n</figure>",
                escape(file),
                escape(stem),
                measured
                    .then(|| measured_caption(stem))
                    .flatten()
                    .unwrap_or_else(|| caption(stem)),
                links.join("; ")
            )?;
        }
    }
    Ok(())
}

/// The analytic fits a figure was drawn from: the area–load slope and the plateau of K.
fn fits(h: &mut String, store: &Store, records: &[&FigureRecord]) -> anyhow::Result<()> {
    let (mut plateau, mut slopes) = (String::new(), String::new());
    for d in records
        .iter()
        .flat_map(|r| &r.drawn_from)
        .filter(|d| d.stage == "analytic")
    {
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
            "<details><summary>Plateau of K</summary>\n\
             <p>K<sub>PL</sub>(A*) in the limit A<sub>m</sub> → ∞ from the power-law fit \
             (α̂, A<sub>s</sub>) at the largest load up to W/W₀ = {max}, beside the model at \
             that load's cut-off A<sub>m</sub> \
             and the simulated K there (pooled over realizations, its 95 % interval over \
             them, and the clusters above A* behind it).</p>\n<table>\n\
             <tr><th>study</th><th>A*/λₛ²</th><th>W/W₀</th><th>α̂</th>\
             <th>K<sub>PL</sub> plateau</th><th>K<sub>PL</sub> at W</th><th>simulated K at W</th></tr>\n\
             {plateau}</table>\n</details>"
        )?;
    }
    Ok(())
}

/// The store instances a figure was drawn from, its own first.
fn drawn_from(h: &mut String, records: &[&FigureRecord]) -> anyhow::Result<()> {
    writeln!(
        h,
        "<details><summary>Drawn from</summary>\n<table>\n\
         <tr><th>stage</th><th>key</th><th>studies</th></tr>"
    )?;
    for fig in records {
        writeln!(
            h,
            "<tr><td>figures</td><td><code>{}</code></td><td></td></tr>",
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
    }
    writeln!(h, "</table>\n</details>")?;
    Ok(())
}

/// Write the page as `index.html` in `dir`, through a temporary file.
pub fn write(
    store: &Store,
    dir: &Path,
    provenance: &Provenance,
    context: &Context,
) -> anyhow::Result<()> {
    let page = render(store, provenance, context)?;
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
