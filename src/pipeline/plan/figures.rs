//! The figure and audit instances of each declared figure, from its studies' keys.

use super::builder::{Builder, StudyKeys};
use crate::config::{FigureDecl, FigureKind};
use crate::stages::analytic::{Analytic, AnalyticJob};
use crate::stages::audits::{AuditJob, Audits, Setting};
use crate::stages::figures::StudyRef;
use crate::stages::figures::{FigureJob, Figures};
use crate::stages::InputRef;

/// A study's reference in a figure: legend text `name = value`.
fn study_ref(k: &StudyKeys, label: String, value: f64) -> StudyRef {
    StudyRef {
        study: k.plan.name.clone(),
        label,
        value,
        lambda_s_px: k.plan.surface.lambda_s_px,
    }
}

/// One declared figure in one profile, with the studies' keys it draws from.
struct FigureContext<'a> {
    name: &'a str,
    decl: &'a FigureDecl,
    profile: &'a str,
    keys: &'a [StudyKeys<'a>],
}

impl<'a> FigureContext<'a> {
    fn find(&self, s: &str) -> anyhow::Result<&'a StudyKeys<'a>> {
        self.keys.iter().find(|k| k.plan.name == s).ok_or_else(|| {
            anyhow::anyhow!(
                "figure {}: study {s} is not in profile {}",
                self.name,
                self.profile
            )
        })
    }

    /// The studies of `list` the figure draws in this profile.
    fn used(&self, list: &[String]) -> anyhow::Result<Vec<&'a StudyKeys<'a>>> {
        self.decl
            .used(list, self.profile)
            .into_iter()
            .map(|s| self.find(s))
            .collect()
    }
}

fn names(ks: &[&StudyKeys]) -> Vec<String> {
    ks.iter().map(|k| k.plan.name.clone()).collect()
}

/// The audit and figure instances of one declared figure.
pub(super) fn figure_instances(
    b: &mut Builder,
    name: &str,
    decl: &FigureDecl,
    profile: &str,
    keys: &[StudyKeys],
) -> anyhow::Result<()> {
    let c = FigureContext {
        name,
        decl,
        profile,
        keys,
    };
    match decl.kind {
        FigureKind::Fig6 => fig6_instances(b, &c),
        FigureKind::Fig2 => fig2_instances(b, &c),
        FigureKind::Fig3Fig4a => fig3_instances(b, &c),
        FigureKind::Fig45 => fig45_instances(b, &c),
        FigureKind::AppendixB1 | FigureKind::AppendixB2 => appendix_instances(b, &c),
        FigureKind::Convergence => convergence_instances(b, &c),
        FigureKind::LoadResolution => load_resolution_instances(b, &c),
        FigureKind::Plastic => plastic_instances(b, &c),
        FigureKind::Spectrum => spectrum_instances(b, &c),
    }
}

fn fig6_instances(b: &mut Builder, c: &FigureContext) -> anyhow::Result<()> {
    let fig = Some(c.name);

    let model = b.add::<Analytic>(&AnalyticJob::fig6(), vec![], &[], None, None);
    b.add::<Figures>(&FigureJob::Fig6, vec![model], &[], None, fig);
    Ok(())
}

fn fig2_instances(b: &mut Builder, c: &FigureContext) -> anyhow::Result<()> {
    let (decl, fig) = (c.decl, Some(c.name));

    let k = c.find(decl.study.as_deref().unwrap_or_default())?;
    let studies = [k.plan.name.clone()];
    let maps: Vec<(usize, f64)> = k
        .plan
        .keep_pressure
        .iter()
        .map(|&i| (i, k.plan.loads[i]))
        .collect();
    let job = FigureJob::Fig2Maps {
        maps: maps.clone(),
        lambda_s_px: k.plan.surface.lambda_s_px,
        a_star_over_ls2: crate::stages::figures::FIG2_A_STAR_OVER_LS2,
        measured: k.plan.measured.is_some(),
    };
    let inputs = vec![k.surfaces[0].clone(), k.contacts[0].clone()];
    b.add::<Figures>(&job, inputs, &studies, None, fig);
    let audit = b.add::<Audits>(
        &AuditJob::realizations(),
        k.clusters.clone(),
        &studies,
        None,
        fig,
    );
    let job = FigureJob::Fig2ef {
        marked_loads: maps.iter().map(|m| m.1).collect(),
    };
    let inputs = vec![k.statistics.clone(), audit, k.analytic.clone()];
    b.add::<Figures>(&job, inputs, &studies, None, fig);
    Ok(())
}

fn fig3_instances(b: &mut Builder, c: &FigureContext) -> anyhow::Result<()> {
    let (decl, fig) = (c.decl, Some(c.name));

    let ratio = |k: &StudyKeys| k.plan.surface.lambda_l_px / k.plan.surface.lambda_s_px;
    let ratios = c.used(&decl.ratios)?;
    let hurst = c.used(&decl.hurst)?;
    let job = FigureJob::Fig3Fig4a {
        ratios: ratios
            .iter()
            .map(|k| study_ref(k, format!("λ_l/λ_s = {}", ratio(k)), ratio(k)))
            .collect(),
        hurst: hurst
            .iter()
            .map(|k| {
                let h = k.plan.surface.hurst;
                study_ref(k, format!("H = {h}"), h)
            })
            .collect(),
        loads: decl.loads.clone(),
        inset_load: decl.inset_load.unwrap_or_default(),
    };
    let inputs = ratios
        .iter()
        .chain(&hurst)
        .map(|k| k.statistics.clone())
        .collect();
    let mut studies = names(&ratios);
    for s in names(&hurst) {
        if !studies.contains(&s) {
            studies.push(s);
        }
    }
    b.add::<Figures>(&job, inputs, &studies, None, fig);
    Ok(())
}

fn fig45_instances(b: &mut Builder, c: &FigureContext) -> anyhow::Result<()> {
    let (decl, fig) = (c.decl, Some(c.name));

    let k = c.find(decl.study.as_deref().unwrap_or_default())?;
    let inputs = vec![k.statistics.clone(), k.analytic.clone()];
    let studies = std::slice::from_ref(&k.plan.name);
    let job = match &k.plan.measured {
        Some(m) => FigureJob::Fig45 {
            lambda_l_over_lambda_s: 0.0,
            measured: Some(format!(
                "measured ({} file{}, λ_s = {} px)",
                m.files.len(),
                if m.files.len() == 1 { "" } else { "s" },
                k.plan.surface.lambda_s_px
            )),
        },
        None => FigureJob::Fig45 {
            lambda_l_over_lambda_s: k.plan.surface.lambda_l_px / k.plan.surface.lambda_s_px,
            measured: None,
        },
    };
    b.add::<Figures>(&job, inputs, studies, None, fig);
    Ok(())
}

fn appendix_instances(b: &mut Builder, c: &FigureContext) -> anyhow::Result<()> {
    let (decl, fig) = (c.decl, Some(c.name));

    let b1 = decl.kind == FigureKind::AppendixB1;
    let setting = |k: &StudyKeys| {
        let s = &k.plan.surface;
        if b1 {
            s.n as f64 / s.lambda_l_px
        } else {
            s.lambda_s_px
        }
    };
    let quantity = if b1 { "L/λ_l" } else { "λ_s/Δl" };
    let mut studies = c.used(&decl.studies)?;
    studies.sort_by(|a, b| setting(a).total_cmp(&setting(b)));
    let refs: Vec<StudyRef> = studies
        .iter()
        .map(|k| study_ref(k, format!("{quantity} = {}", setting(k)), setting(k)))
        .collect();
    let audit = settings_audit(b, c.name, &studies, &refs);
    let mut inputs: Vec<InputRef> = studies.iter().map(|k| k.statistics.clone()).collect();
    inputs.push(audit);
    let job = FigureJob::Appendix {
        figure: c.name.to_string(),
        quantity: quantity.to_string(),
        b1,
        settings: refs,
    };
    b.add::<Figures>(&job, inputs, &names(&studies), None, fig);
    Ok(())
}

fn convergence_instances(b: &mut Builder, c: &FigureContext) -> anyhow::Result<()> {
    let (decl, fig) = (c.decl, Some(c.name));

    let mut studies = c.used(&decl.studies)?;
    // Reference last: the largest grid, and of equal grids the finer discretisation
    // (the declared order breaks remaining ties).
    studies.sort_by(|a, b| {
        let (sa, sb) = (&a.plan.surface, &b.plan.surface);
        (sa.n, sa.lambda_s_px)
            .partial_cmp(&(sb.n, sb.lambda_s_px))
            .expect("finite sizes")
    });
    let mut refs: Vec<StudyRef> = studies
        .iter()
        .map(|k| {
            let s = &k.plan.surface;
            let label = format!(
                "L/λ_l = {}, λ_s/Δl = {} (n = {})",
                s.n as f64 / s.lambda_l_px,
                s.lambda_s_px,
                s.n
            );
            study_ref(k, label, s.n as f64)
        })
        .collect();
    // Two studies with the same sizes would share a label: tell them apart by name.
    for i in 0..refs.len() {
        if refs.iter().filter(|r| r.label == refs[i].label).count() > 1 {
            refs[i].label = refs[i].named();
        }
    }
    let hurst = studies[0].plan.surface.hurst;
    let audit = settings_audit(b, c.name, &studies, &refs);
    let mut inputs: Vec<InputRef> = studies.iter().map(|k| k.statistics.clone()).collect();
    inputs.push(audit);
    let job = FigureJob::Convergence {
        figure: c.name.to_string(),
        hurst,
        settings: refs,
    };
    b.add::<Figures>(&job, inputs, &names(&studies), None, fig);
    Ok(())
}

fn load_resolution_instances(b: &mut Builder, c: &FigureContext) -> anyhow::Result<()> {
    let (decl, fig) = (c.decl, Some(c.name));

    let chosen = c.find(decl.chosen.as_deref().unwrap_or_default())?;
    let fine = c.find(decl.fine.as_deref().unwrap_or_default())?;
    let studies = names(&[fine, chosen]);
    let inputs = vec![fine.statistics.clone(), chosen.statistics.clone()];
    let audit = b.add::<Audits>(&AuditJob::load_resolution(), inputs, &studies, None, fig);
    let job = FigureJob::LoadResolution {
        figure: c.name.to_string(),
    };
    b.add::<Figures>(&job, vec![audit], &studies, None, fig);
    Ok(())
}

/// The plastic family: the settings ordered by 1/𝓗 (elastic first, at 0); inputs are
/// each setting's statistics, then each setting's contact sweeps (the saturated nodes).
fn plastic_instances(b: &mut Builder, c: &FigureContext) -> anyhow::Result<()> {
    let (decl, fig) = (c.decl, Some(c.name));

    let inverse = |k: &StudyKeys| k.plan.hardness.map_or(0.0, |h| 1.0 / h);
    let mut studies = c.used(&decl.studies)?;
    studies.sort_by(|a, b| inverse(a).total_cmp(&inverse(b)));
    let settings: Vec<StudyRef> = studies
        .iter()
        .map(|k| {
            let label = match k.plan.hardness {
                Some(h) => format!("𝓗 = {h}"),
                None => "elastic".to_string(),
            };
            study_ref(k, label, inverse(k))
        })
        .collect();
    let mut inputs: Vec<InputRef> = studies.iter().map(|k| k.statistics.clone()).collect();
    let realizations = studies.iter().map(|k| k.contacts.len()).collect();
    for k in &studies {
        inputs.extend(k.contacts.iter().cloned());
    }
    let job = FigureJob::Plastic {
        settings,
        realizations,
        loads: decl.loads.clone(),
    };
    b.add::<Figures>(&job, inputs, &names(&studies), None, fig);
    Ok(())
}

/// The spectrum family: the settings ordered by λ_l/λ_s; inputs are each setting's
/// statistics, then each setting's fitted model.
fn spectrum_instances(b: &mut Builder, c: &FigureContext) -> anyhow::Result<()> {
    let (decl, fig) = (c.decl, Some(c.name));

    let ratio = |k: &StudyKeys| k.plan.surface.lambda_l_px / k.plan.surface.lambda_s_px;
    let mut studies = c.used(&decl.studies)?;
    studies.sort_by(|a, b| ratio(a).total_cmp(&ratio(b)));
    let settings: Vec<StudyRef> = studies
        .iter()
        .map(|k| {
            let label = format!("λ_l/λ_s = {}", ratio(k));
            study_ref(k, label, ratio(k))
        })
        .collect();
    let mut inputs: Vec<InputRef> = studies.iter().map(|k| k.statistics.clone()).collect();
    inputs.extend(studies.iter().map(|k| k.analytic.clone()));
    let job = FigureJob::Spectrum {
        settings,
        loads: decl.loads.clone(),
        plateau_w_over_w0: crate::stages::analytic::MILD_WEAR_MAX_LOAD,
        a_star_over_ls2: crate::stages::audits::FIG45_A_STAR.to_vec(),
        a_star_over_ll2: crate::stages::figures::SPECTRUM_A_STAR_OVER_LL2.to_vec(),
    };
    b.add::<Figures>(&job, inputs, &names(&studies), None, fig);
    Ok(())
}

/// The convergence audit of settings (the last one the reference): inputs are each
/// setting's statistics followed by its clusters instances.
fn settings_audit(
    b: &mut Builder,
    name: &str,
    studies: &[&StudyKeys],
    refs: &[StudyRef],
) -> InputRef {
    let mut inputs = Vec::new();
    let mut settings = Vec::new();
    for (k, r) in studies.iter().zip(refs) {
        inputs.push(k.statistics.clone());
        inputs.extend(k.clusters.iter().cloned());
        settings.push(Setting {
            label: r.label.clone(),
            value: r.value,
            realizations: k.clusters.len(),
        });
    }
    let names: Vec<String> = studies.iter().map(|k| k.plan.name.clone()).collect();
    b.add::<Audits>(
        &AuditJob::settings(settings),
        inputs,
        &names,
        None,
        Some(name),
    )
}
