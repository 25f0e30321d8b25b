//! Stage definitions: which instances a profile needs, their parameters (only those the
//! stage reads), and how each is computed into a temporary entry directory.

use std::path::Path;

use serde_json::{json, Value};

use polars::prelude::*;

use super::cluster_stages::{compute_analytic, compute_clusters, compute_statistics};
use super::hash::instance_key;
use super::store::Store;
use crate::clusters::Connectivity;
use crate::config::StudyPlan;
use crate::contact::elastic::ElasticOperator;
use crate::contact::solver::SolverConfig;
use crate::contact::sweep::{pack_contact, sweep, LoadResult};
use crate::grid::Grid;
use crate::spectral::Fft2;
use crate::surface::{self, SurfaceParams};

/// Stages in dependency order.
pub const STAGES: &[&str] = &[
    "surface",
    "contact",
    "clusters",
    "statistics",
    "analytic",
    "figures",
];

/// Version of the surface stage; bump when its algorithm or outputs change.
pub const SURFACE_VERSION: u32 = 1;
/// Version of the contact stage.
pub const CONTACT_VERSION: u32 = 5;
/// Version of the clusters stage.
pub const CLUSTERS_VERSION: u32 = 1;
/// Version of the statistics stage.
pub const STATISTICS_VERSION: u32 = 1;
/// Version of the analytic stage.
pub const ANALYTIC_VERSION: u32 = 1;
/// Version of the figures stage.
pub const FIGURES_VERSION: u32 = 13;

/// One study's statistics as a figure reads them.
#[derive(Debug, Clone)]
pub struct StudyRef {
    /// Legend text, e.g. `λ_l/λ_s = 128`.
    pub label: String,
    /// The value the figure varies (λ_l/λ_s, H, L/λ_l or λ_s/Δl), the number in `label`.
    pub value: f64,
    pub statistics_key: String,
    pub lambda_s_px: f64,
}

/// What a figures instance draws.
#[derive(Debug, Clone)]
pub enum FigureJob {
    /// Paper Fig. 6 from the analytic stage's model curves.
    Fig6 { analytic_key: String },
    /// Paper Fig. 2a–d: the surface and contact maps of realization 0 of study `fig2` at
    /// the loads whose pressure the study keeps (`(load index, W/W0)`).
    Fig2Maps {
        surface_key: String,
        contact_key: String,
        maps: Vec<(usize, f64)>,
        lambda_s_px: f64,
    },
    /// Paper Fig. 2e–f from the statistics of study `fig2`, the loads of Fig. 2b–d marked.
    Fig2ef {
        statistics_key: String,
        marked_loads: Vec<f64>,
    },
    /// Paper Fig. 3 (with its H inset) and Fig. 4a from the `fig3_*` studies.
    Fig34a {
        ratios: Vec<StudyRef>,
        hurst: Vec<StudyRef>,
    },
    /// Paper Figs. 4b, 5a, 5b from the statistics and fitted model of study `fig3_ll128`.
    Fig45 {
        statistics_key: String,
        analytic_key: String,
    },
    /// Paper Fig. B.1 (`figB1`, studies `b1_*`) or B.2 (`figB2`, studies `b2_*`).
    Appendix {
        figure: &'static str,
        settings: Vec<StudyRef>,
    },
    /// Convergence of the λ_l/λ_s = 128 sizes (`fig128_convergence`, studies `c128_*` of
    /// one Hurst exponent; `fig128_convergence_h<H>` per exponent when a profile has
    /// several): each setting against the last one, the reference (largest grid). `value`
    /// is the grid side n.
    Convergence128 {
        name: String,
        hurst: f64,
        settings: Vec<StudyRef>,
    },
    /// Load resolution of Figs. 4b and 5 (`fig45_load_resolution`, studies `lr128_*`): the
    /// curves of the sweep with fewer loads (`chosen`) interpolated at the loads of the other
    /// (`fine`), against its values and their 95 % bands.
    LoadResolution {
        fine_statistics_key: String,
        chosen_statistics_key: String,
    },
}

/// Paper Fig. 6: the exponent, and the thresholds `A*/A_s` of the model curves, whose cut-off
/// `A_m/A_s` runs over `10^0 … 10^12` in [`FIG6_POINTS`] logarithmic steps.
pub const FIG6_ALPHA: f64 = 1.5;
pub const FIG6_A_STAR_OVER_A_S: [f64; 5] = [0.5, 1.0, 10.0, 100.0, 1000.0];
pub const FIG6_POINTS: usize = 121;

/// Thresholds `A*/λ_s²` at which the statistics stage evaluates `K`, `𝒦` and the wear
/// rate: powers of two from 1/4 to 1024 (the paper's Fig. 2 uses `A* = 2 λ_s²`).
pub const A_STAR_OVER_LS2: [f64; 13] = [
    0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0, 128.0, 256.0, 512.0, 1024.0,
];
/// Logarithmic bins of the area PDF (paper Fig. 3).
pub const PDF_BINS: usize = 20;
/// Bootstrap resamples of the exponent's interval.
pub const BOOTSTRAP_RESAMPLES: usize = 200;

/// What a clusters instance computes.
#[derive(Debug, Clone)]
pub struct ClustersJob {
    pub contact_key: String,
    pub loads: Vec<f64>,
    pub n: usize,
    pub lambda_s_px: f64,
    pub realization: u32,
    pub connectivity: Connectivity,
}

/// What a statistics instance computes (one per study).
#[derive(Debug, Clone)]
pub struct StatisticsJob {
    /// Clusters instances, in realization order.
    pub clusters_keys: Vec<String>,
    pub loads: Vec<f64>,
    pub n: usize,
    pub lambda_s_px: f64,
    pub seed: u64,
}

/// What a contact instance computes.
#[derive(Debug, Clone)]
pub struct ContactJob {
    pub surface_key: String,
    pub loads: Vec<f64>,
    pub keep_pressure: Vec<usize>,
    pub e_star: f64,
    pub tolerance: f64,
    pub max_iterations: u32,
}

/// What an analytic instance computes: the fitted model of one study's statistics
/// (`statistics_key`), or, without input, the model curves of paper Fig. 6.
#[derive(Debug, Clone)]
pub struct AnalyticJob {
    pub statistics_key: Option<String>,
    pub lambda_s_px: f64,
}

/// What an instance computes.
#[derive(Debug, Clone)]
pub enum Job {
    Surface(SurfaceParams),
    Contact(ContactJob),
    Clusters(ClustersJob),
    Statistics(StatisticsJob),
    Analytic(AnalyticJob),
    Figure(FigureJob),
}

/// One stage instance of a profile.
#[derive(Debug, Clone)]
pub struct Instance {
    pub stage: &'static str,
    pub version: u32,
    pub params: Value,
    pub inputs: Vec<String>,
    pub key: String,
    /// Studies of the profile that use this instance (several studies may share one).
    pub studies: Vec<String>,
    pub realization: Option<u32>,
    pub job: Job,
}

/// Parameters the surface stage reads, as they enter its key.
pub fn surface_params_json(p: &SurfaceParams) -> Value {
    json!({
        "n": p.n,
        "hurst": p.hurst,
        "lambda_l_px": p.lambda_l_px,
        "lambda_s_px": p.lambda_s_px,
        "rolloff_lambda_px": p.rolloff_lambda_px,
        "method": p.method.as_str(),
        "seed": p.seed,
    })
}

/// Parameters the contact stage reads, as they enter its key.
pub fn contact_params_json(job: &ContactJob) -> Value {
    json!({
        "loads_w_over_w0": job.loads,
        "keep_pressure": job.keep_pressure,
        "e_star": job.e_star,
        "tolerance": job.tolerance,
        "max_iterations": job.max_iterations,
    })
}

/// Parameters the clusters stage reads, as they enter its key.
pub fn clusters_params_json(job: &ClustersJob) -> Value {
    json!({
        "loads_w_over_w0": job.loads,
        "n": job.n,
        "lambda_s_px": job.lambda_s_px,
        "realization": job.realization,
        "connectivity": job.connectivity.neighbours(),
    })
}

/// Parameters the statistics stage reads, as they enter its key.
pub fn statistics_params_json(job: &StatisticsJob) -> Value {
    json!({
        "loads_w_over_w0": job.loads,
        "n": job.n,
        "lambda_s_px": job.lambda_s_px,
        "seed": job.seed,
        "a_star_over_ls2": A_STAR_OVER_LS2,
        "pdf_bins": PDF_BINS,
        "bootstrap_resamples": BOOTSTRAP_RESAMPLES,
        "min_tail": crate::powerlaw::MIN_TAIL,
        "omega": crate::statistics::OMEGA,
    })
}

/// Add an instance, or record one more study for an existing one with the same key.
fn push_unique(out: &mut Vec<Instance>, inst: Instance) -> String {
    let key = inst.key.clone();
    if let Some(existing) = out.iter_mut().find(|i| i.key == key) {
        for s in inst.studies {
            if !existing.studies.contains(&s) {
                existing.studies.push(s);
            }
        }
    } else {
        out.push(inst);
    }
    key
}

/// Every instance the given studies need, deduplicated by key, in stage order.
pub fn instances(plans: &[StudyPlan]) -> Vec<Instance> {
    let mut out: Vec<Instance> = Vec::new();
    let mut keys: Vec<StudyKeys> = Vec::new();
    for plan in plans {
        let mut clusters_keys = Vec::new();
        let mut first_keys: Option<(String, String)> = None;
        for r in 0..plan.realizations {
            let params = plan.surface_for(r);
            let params_json = surface_params_json(&params);
            let surface_key = push_unique(
                &mut out,
                Instance {
                    stage: "surface",
                    version: SURFACE_VERSION,
                    key: instance_key("surface", SURFACE_VERSION, &params_json, &[]),
                    params: params_json,
                    inputs: Vec::new(),
                    studies: vec![plan.name.clone()],
                    realization: Some(r),
                    job: Job::Surface(params),
                },
            );
            let job = ContactJob {
                surface_key: surface_key.clone(),
                loads: plan.loads.clone(),
                keep_pressure: plan.keep_pressure.clone(),
                e_star: plan.e_star,
                tolerance: plan.tolerance,
                max_iterations: plan.max_iterations,
            };
            let params_json = contact_params_json(&job);
            let surface_key_0 = surface_key.clone();
            let inputs = vec![surface_key];
            let contact_key = push_unique(
                &mut out,
                Instance {
                    stage: "contact",
                    version: CONTACT_VERSION,
                    key: instance_key("contact", CONTACT_VERSION, &params_json, &inputs),
                    params: params_json,
                    inputs,
                    studies: vec![plan.name.clone()],
                    realization: Some(r),
                    job: Job::Contact(job),
                },
            );
            let job = ClustersJob {
                contact_key: contact_key.clone(),
                loads: plan.loads.clone(),
                n: plan.surface.n,
                lambda_s_px: plan.surface.lambda_s_px,
                realization: r,
                connectivity: Connectivity::Eight,
            };
            let params_json = clusters_params_json(&job);
            if first_keys.is_none() {
                first_keys = Some((surface_key_0, contact_key.clone()));
            }
            let inputs = vec![contact_key];
            clusters_keys.push(push_unique(
                &mut out,
                Instance {
                    stage: "clusters",
                    version: CLUSTERS_VERSION,
                    key: instance_key("clusters", CLUSTERS_VERSION, &params_json, &inputs),
                    params: params_json,
                    inputs,
                    studies: vec![plan.name.clone()],
                    realization: Some(r),
                    job: Job::Clusters(job),
                },
            ));
        }
        let job = StatisticsJob {
            clusters_keys: clusters_keys.clone(),
            loads: plan.loads.clone(),
            n: plan.surface.n,
            lambda_s_px: plan.surface.lambda_s_px,
            seed: plan.seed,
        };
        let params_json = statistics_params_json(&job);
        let statistics_key = push_unique(
            &mut out,
            Instance {
                stage: "statistics",
                version: STATISTICS_VERSION,
                key: instance_key(
                    "statistics",
                    STATISTICS_VERSION,
                    &params_json,
                    &clusters_keys,
                ),
                params: params_json,
                inputs: clusters_keys,
                studies: vec![plan.name.clone()],
                realization: None,
                job: Job::Statistics(job),
            },
        );
        let job = AnalyticJob {
            statistics_key: Some(statistics_key.clone()),
            lambda_s_px: plan.surface.lambda_s_px,
        };
        let params_json = analytic_params_json(&job);
        let inputs = vec![statistics_key.clone()];
        let analytic_key = push_unique(
            &mut out,
            Instance {
                stage: "analytic",
                version: ANALYTIC_VERSION,
                key: instance_key("analytic", ANALYTIC_VERSION, &params_json, &inputs),
                params: params_json,
                inputs,
                studies: vec![plan.name.clone()],
                realization: None,
                job: Job::Analytic(job),
            },
        );
        let (surface_key, contact_key) = first_keys.unwrap_or_default();
        keys.push(StudyKeys {
            plan,
            surface_key,
            contact_key,
            statistics_key,
            analytic_key,
        });
    }
    // The model curves of Fig. 6 need no simulation; listed under every study.
    if !plans.is_empty() {
        let job = AnalyticJob {
            statistics_key: None,
            lambda_s_px: 1.0,
        };
        let params_json = analytic_params_json(&job);
        let analytic_key = instance_key("analytic", ANALYTIC_VERSION, &params_json, &[]);
        let all_studies: Vec<String> = plans.iter().map(|p| p.name.clone()).collect();
        out.push(Instance {
            stage: "analytic",
            version: ANALYTIC_VERSION,
            key: analytic_key.clone(),
            params: params_json,
            inputs: Vec::new(),
            studies: all_studies.clone(),
            realization: None,
            job: Job::Analytic(job),
        });
        let params_json = json!({ "figure": "fig6" });
        let inputs = vec![analytic_key.clone()];
        out.push(Instance {
            stage: "figures",
            version: FIGURES_VERSION,
            key: instance_key("figures", FIGURES_VERSION, &params_json, &inputs),
            params: params_json,
            inputs,
            studies: all_studies,
            realization: None,
            job: Job::Figure(FigureJob::Fig6 { analytic_key }),
        });
    }
    out.extend(figure_instances(&keys));
    out
}

/// The keys of one study's instances that figures read.
struct StudyKeys<'a> {
    plan: &'a StudyPlan,
    /// Surface and contact of realization 0 (empty without realizations).
    surface_key: String,
    contact_key: String,
    statistics_key: String,
    analytic_key: String,
}

impl StudyKeys<'_> {
    /// `name = value` as the legend text.
    fn reference(&self, name: &str, value: f64) -> StudyRef {
        StudyRef {
            label: format!("{name} = {value}"),
            value,
            statistics_key: self.statistics_key.clone(),
            lambda_s_px: self.plan.surface.lambda_s_px,
        }
    }
}

/// A figures instance drawing `job` from `inputs`, listed under `studies`.
fn figure_instance(
    params: Value,
    inputs: Vec<String>,
    studies: Vec<String>,
    job: FigureJob,
) -> Instance {
    Instance {
        stage: "figures",
        version: FIGURES_VERSION,
        key: instance_key("figures", FIGURES_VERSION, &params, &inputs),
        params,
        inputs,
        studies,
        realization: None,
        job: Job::Figure(job),
    }
}

/// The figures instances of the paper figures whose studies are in the profile: Fig. 2 from
/// `fig2`, Figs. 3–4a from `fig3_ll*` (inset `fig3_h*` and `fig3_ll128`), Figs. 4b–5 from
/// `fig3_ll128`, Fig. B.1 from `b1_*`, B.2 from `b2_*` and the λ_l/λ_s = 128 convergence
/// figure from `c128_*`.
fn figure_instances(keys: &[StudyKeys]) -> Vec<Instance> {
    let mut out = Vec::new();
    let find = |name: &str| keys.iter().find(|k| k.plan.name == name);
    let names = |ks: &[&StudyKeys]| ks.iter().map(|k| k.plan.name.clone()).collect::<Vec<_>>();
    if let Some(k) = find("fig2") {
        let marked: Vec<(usize, f64)> = k
            .plan
            .keep_pressure
            .iter()
            .map(|&i| (i, k.plan.loads[i]))
            .collect();
        let lambda_s_px = k.plan.surface.lambda_s_px;
        if !k.contact_key.is_empty() && !marked.is_empty() {
            out.push(figure_instance(
                json!({ "figure": "fig2_maps", "maps": marked, "lambda_s_px": lambda_s_px,
                        "a_star_over_ls2": super::figures::FIG2_A_STAR_OVER_LS2 }),
                vec![k.surface_key.clone(), k.contact_key.clone()],
                vec![k.plan.name.clone()],
                FigureJob::Fig2Maps {
                    surface_key: k.surface_key.clone(),
                    contact_key: k.contact_key.clone(),
                    maps: marked.clone(),
                    lambda_s_px,
                },
            ));
        }
        let marked_loads: Vec<f64> = marked.iter().map(|m| m.1).collect();
        out.push(figure_instance(
            json!({ "figure": "fig2ef", "marked_loads": marked_loads }),
            vec![k.statistics_key.clone()],
            vec![k.plan.name.clone()],
            FigureJob::Fig2ef {
                statistics_key: k.statistics_key.clone(),
                marked_loads,
            },
        ));
    }
    let ratio = |k: &StudyKeys| k.plan.surface.lambda_l_px / k.plan.surface.lambda_s_px;
    let mut by_ratio: Vec<&StudyKeys> = keys
        .iter()
        .filter(|k| k.plan.name.starts_with("fig3_ll"))
        .collect();
    by_ratio.sort_by(|a, b| ratio(a).total_cmp(&ratio(b)));
    let mut by_hurst: Vec<&StudyKeys> = keys
        .iter()
        .filter(|k| k.plan.name.starts_with("fig3_h") || k.plan.name == "fig3_ll128")
        .collect();
    by_hurst.sort_by(|a, b| a.plan.surface.hurst.total_cmp(&b.plan.surface.hurst));
    if !by_ratio.is_empty() {
        let ratios: Vec<StudyRef> = by_ratio
            .iter()
            .map(|k| k.reference("λ_l/λ_s", ratio(k)))
            .collect();
        let hurst: Vec<StudyRef> = by_hurst
            .iter()
            .map(|k| k.reference("H", k.plan.surface.hurst))
            .collect();
        let mut inputs: Vec<String> = ratios.iter().map(|r| r.statistics_key.clone()).collect();
        inputs.extend(hurst.iter().map(|r| r.statistics_key.clone()));
        let label_list = |v: &[StudyRef]| v.iter().map(|r| r.label.clone()).collect::<Vec<_>>();
        let mut studies = names(&by_ratio);
        for n in names(&by_hurst) {
            if !studies.contains(&n) {
                studies.push(n);
            }
        }
        out.push(figure_instance(
            json!({ "figure": "fig3_fig4a", "ratios": label_list(&ratios),
                    "hurst": label_list(&hurst), "loads": [0.005, 0.02, 0.06] }),
            inputs,
            studies,
            FigureJob::Fig34a { ratios, hurst },
        ));
    }
    if let Some(k) = find("fig3_ll128") {
        out.push(figure_instance(
            json!({ "figure": "fig45" }),
            vec![k.statistics_key.clone(), k.analytic_key.clone()],
            vec![k.plan.name.clone()],
            FigureJob::Fig45 {
                statistics_key: k.statistics_key.clone(),
                analytic_key: k.analytic_key.clone(),
            },
        ));
    }
    for (figure, prefix) in [("figB1", "b1_"), ("figB2", "b2_")] {
        let mut settings: Vec<&StudyKeys> = keys
            .iter()
            .filter(|k| k.plan.name.starts_with(prefix))
            .collect();
        let setting = |k: &StudyKeys| {
            let s = &k.plan.surface;
            if figure == "figB1" {
                s.n as f64 / s.lambda_l_px
            } else {
                s.lambda_s_px
            }
        };
        settings.sort_by(|a, b| setting(a).total_cmp(&setting(b)));
        if settings.is_empty() {
            continue;
        }
        let refs: Vec<StudyRef> = settings
            .iter()
            .map(|k| {
                k.reference(
                    if figure == "figB1" {
                        "L/λ_l"
                    } else {
                        "λ_s/Δl"
                    },
                    setting(k),
                )
            })
            .collect();
        out.push(figure_instance(
            json!({ "figure": figure,
                    "settings": refs.iter().map(|r| r.label.clone()).collect::<Vec<_>>() }),
            refs.iter().map(|r| r.statistics_key.clone()).collect(),
            names(&settings),
            FigureJob::Appendix {
                figure,
                settings: refs,
            },
        ));
    }
    // The λ_l/λ_s = 128 convergence studies, one figure per Hurst exponent (the sizes are
    // compared on one surface family).
    let mut exponents: Vec<f64> = keys
        .iter()
        .filter(|k| k.plan.name.starts_with("c128_"))
        .map(|k| k.plan.surface.hurst)
        .collect();
    exponents.sort_by(f64::total_cmp);
    exponents.dedup();
    for &hurst in &exponents {
        let mut c128: Vec<&StudyKeys> = keys
            .iter()
            .filter(|k| k.plan.name.starts_with("c128_") && k.plan.surface.hurst == hurst)
            .collect();
        // Reference last: the largest grid, and of equal grids the finer discretisation.
        c128.sort_by(|a, b| {
            let (sa, sb) = (&a.plan.surface, &b.plan.surface);
            (sa.n, sa.lambda_s_px)
                .partial_cmp(&(sb.n, sb.lambda_s_px))
                .expect("finite sizes")
        });
        if c128.len() < 2 {
            continue;
        }
        let mut refs: Vec<StudyRef> = c128
            .iter()
            .map(|k| {
                let s = &k.plan.surface;
                StudyRef {
                    label: format!(
                        "L/λ_l = {}, λ_s/Δl = {} (n = {})",
                        s.n as f64 / s.lambda_l_px,
                        s.lambda_s_px,
                        s.n
                    ),
                    value: s.n as f64,
                    statistics_key: k.statistics_key.clone(),
                    lambda_s_px: s.lambda_s_px,
                }
            })
            .collect();
        // Two studies with the same sizes would share a label (the figure's key for a
        // setting): tell them apart by study name.
        for i in 0..refs.len() {
            if refs.iter().filter(|r| r.label == refs[i].label).count() > 1 {
                refs[i].label = format!("{} [{}]", refs[i].label, c128[i].plan.name);
            }
        }
        let name = if exponents.len() == 1 {
            "fig128_convergence".to_string()
        } else {
            format!("fig128_convergence_h{hurst}")
        };
        out.push(figure_instance(
            json!({ "figure": name, "hurst": hurst,
                    "settings": refs.iter().map(|r| r.label.clone()).collect::<Vec<_>>() }),
            refs.iter().map(|r| r.statistics_key.clone()).collect(),
            names(&c128),
            FigureJob::Convergence128 {
                name,
                hurst,
                settings: refs,
            },
        ));
    }
    // The load resolution of Figs. 4b and 5: two sweeps of the same realizations, the one
    // with more loads the reference.
    let mut sweeps: Vec<&StudyKeys> = keys
        .iter()
        .filter(|k| k.plan.name.starts_with("lr128_"))
        .collect();
    if sweeps.len() == 2 {
        sweeps.sort_by_key(|k| k.plan.loads.len());
        let (chosen, fine) = (sweeps[0], sweeps[1]);
        out.push(figure_instance(
            json!({ "figure": "fig45_load_resolution",
                    "fine": fine.plan.name, "chosen": chosen.plan.name }),
            vec![fine.statistics_key.clone(), chosen.statistics_key.clone()],
            names(&sweeps),
            FigureJob::LoadResolution {
                fine_statistics_key: fine.statistics_key.clone(),
                chosen_statistics_key: chosen.statistics_key.clone(),
            },
        ));
    }
    out
}

/// Parameters the analytic stage reads, as they enter its key.
pub fn analytic_params_json(job: &AnalyticJob) -> Value {
    match job.statistics_key {
        Some(_) => json!({
            "curves": "fitted",
            "lambda_s_px": job.lambda_s_px,
            "a_star_over_ls2": A_STAR_OVER_LS2,
        }),
        None => json!({
            "curves": "fig6",
            "alpha": FIG6_ALPHA,
            "a_star_over_a_s": FIG6_A_STAR_OVER_A_S,
            "a_m_over_a_s_decades": [0, 12],
            "points": FIG6_POINTS,
        }),
    }
}

/// Compute an instance into `dir`, reading its inputs from `store`; returns the stage's
/// results for the manifest.
pub fn compute(instance: &Instance, dir: &Path, store: &Store) -> anyhow::Result<Value> {
    match &instance.job {
        Job::Surface(params) => compute_surface(params, dir),
        Job::Contact(job) => compute_contact(job, dir, store),
        Job::Clusters(job) => compute_clusters(job, dir, store),
        Job::Statistics(job) => compute_statistics(job, dir, store),
        Job::Analytic(job) => compute_analytic(job, dir, store),
        Job::Figure(job) => super::figures::compute_figure(job, dir, store),
    }
}

/// File name of the packed contact map of load `index`.
pub fn contact_file(index: usize) -> String {
    format!("contact_{index:03}.npy")
}

/// File name of the pressure field of load `index`.
pub fn pressure_file(index: usize) -> String {
    format!("pressure_{index:03}.npy")
}

fn compute_contact(job: &ContactJob, dir: &Path, store: &Store) -> anyhow::Result<Value> {
    let manifest = store.lookup("surface", &job.surface_key)?.ok_or_else(|| {
        anyhow::anyhow!(
            "input surface {} is missing from the store",
            job.surface_key
        )
    })?;
    let path = store.read_output(&manifest, "heights.npy")?;
    let (n, heights) = crate::io::read_square_f64(&path)?;
    let grid = Grid::unit(n)?;
    let slope = surface::rms_slope(&grid, &heights);
    let op = ElasticOperator::new(grid, job.e_star);
    let cfg = SolverConfig {
        tolerance: job.tolerance,
        max_iterations: job.max_iterations as usize,
        ..SolverConfig::default()
    };
    let row_bytes = n.div_ceil(8);
    let results = sweep(
        &op,
        &heights,
        slope,
        &job.loads,
        &cfg,
        |index, solver, _| {
            let packed = pack_contact(solver.pressure(), n);
            crate::io::write_u8(&dir.join(contact_file(index)), &[n, row_bytes], packed)
                .map_err(|e| e.to_string())?;
            if job.keep_pressure.contains(&index) {
                crate::io::write_f64(
                    &dir.join(pressure_file(index)),
                    &[n, n],
                    solver.pressure().to_vec(),
                )
                .map_err(|e| e.to_string())?;
            }
            Ok(())
        },
    )?;
    let mut df = df_loads(&results)?;
    let file = std::fs::File::create(dir.join("loads.parquet"))?;
    ParquetWriter::new(file).finish(&mut df)?;
    Ok(json!({
        "n": n,
        "rms_slope": slope,
        "total_iterations": results.iter().map(|r| r.report.iterations).sum::<usize>(),
        "solve_seconds": results.iter().map(|r| r.seconds).collect::<Vec<_>>(),
    }))
}

fn df_loads(results: &[LoadResult]) -> PolarsResult<DataFrame> {
    DataFrame::new(
        results.len(),
        vec![
            Column::new(
                "load_index".into(),
                (0..results.len() as u32).collect::<Vec<_>>(),
            ),
            Column::new(
                "w_over_w0".into(),
                results.iter().map(|r| r.w_over_w0).collect::<Vec<_>>(),
            ),
            Column::new(
                "mean_pressure".into(),
                results.iter().map(|r| r.mean_pressure).collect::<Vec<_>>(),
            ),
            Column::new(
                "area_fraction".into(),
                results.iter().map(|r| r.area_fraction).collect::<Vec<_>>(),
            ),
            Column::new(
                "n_contact_px".into(),
                results
                    .iter()
                    .map(|r| r.n_contact_px as u64)
                    .collect::<Vec<_>>(),
            ),
            Column::new(
                "iterations".into(),
                results
                    .iter()
                    .map(|r| r.report.iterations as u32)
                    .collect::<Vec<_>>(),
            ),
            Column::new(
                "convolutions".into(),
                results
                    .iter()
                    .map(|r| r.report.convolutions as u32)
                    .collect::<Vec<_>>(),
            ),
            Column::new(
                "error".into(),
                results.iter().map(|r| r.report.error).collect::<Vec<_>>(),
            ),
            Column::new(
                "converged".into(),
                results
                    .iter()
                    .map(|r| r.report.converged())
                    .collect::<Vec<_>>(),
            ),
        ],
    )
}

fn compute_surface(params: &SurfaceParams, dir: &Path) -> anyhow::Result<Value> {
    let fft = Fft2::new(params.n);
    let mut scratch = fft.make_scratch();
    let s = surface::generate(params, &fft, &mut scratch)?;
    crate::io::write_heights(&dir.join("heights.npy"), s.grid.n(), s.heights)?;
    Ok(json!({
        "mean_height": s.stats.mean_height,
        "rms_height": s.stats.rms_height,
        "rms_slope": s.stats.rms_slope,
        "hurst_fit": s.stats.hurst_fit,
        "box_size": 1.0,
        "grid_spacing": s.grid.spacing(),
    }))
}
