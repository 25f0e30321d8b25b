//! Speed–accuracy chart: `make speed-accuracy` writes `figures/speed_accuracy.{png,svg,csv}`
//! and prints, per family of studies, the tolerance the chart chooses.
//!
//! Every quantity a figure shows (α̂ at the loads of Fig. 3, K and 𝒦 at each A* of Figs. 4b
//! and 5 and each load, the KS distance of the area distribution, the contact area and the
//! cluster count) is compared with a reference, and its error is expressed in units of the
//! scatter between realizations that the studies already carry: the standard deviation
//! between realizations of the quantity divided by √R, where R is the number of
//! realizations (in boxes of this size) the studies average; for the KS distance the unit
//! is its sampling noise √((n+m)/(nm)). An error below 1 is smaller than what another set
//! of seeds would change.
//!
//! (a–c) Solver tolerance 10⁻⁴ … 10⁻¹⁰ against 10⁻¹² on the spectra of the default profile's
//!       studies (λ_l/λ_s = 8, 32, 128), a few realizations each; Tamaas (PyPI) at the
//!       same tolerances on the same first surface in (a). The chart's choice is the
//!       tolerance whose worst quantity stays below 1 with the fewest FFT pairs (the
//!       solver's work, counted exactly; the looser of equal counts).
//! (d–f) λ_s/Δl, L/λ_l and the realization count on the λ_l/λ_s = 8 spectrum at the
//!       Fig. 3 loads, against the finest setting (the pipeline's sizes are set by the
//!       convergence audits of Appendix B; these panels show the same trade-off at small
//!       size).
//!
//! Cost is wall time relative to a reference measured in the same run, so the chart does not
//! depend on the machine's speed. Errors of exactly 0 are drawn on the "exact" floor.

mod chart;
mod measure;

use std::path::{Path, PathBuf};

use measure::{ks_noise, ours, scatter, tamaas, worst, Quantity, Sample, Setup, Sweep};
use wearcoef::statistics::log_edges;

/// Tolerances of the chart, loosest first, and the reference.
const TOLERANCES: [f64; 7] = [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10];
const REFERENCE_TOLERANCE: f64 = 1e-12;
/// Tolerances at which Tamaas is run (its sweeps cost about ten of ours).
const TAMAAS_TOLERANCES: [f64; 4] = [1e-4, 1e-6, 1e-8, 1e-10];
/// The loads of Fig. 3 (where α̂ is read).
const FIG3_LOADS: [f64; 3] = [0.005, 0.02, 0.06];

/// One point of a panel: a setting, its cost and its errors.
pub struct Point {
    /// "wearcoef" or "Tamaas".
    pub code: &'static str,
    pub setting: f64,
    pub seconds: f64,
    /// FFT pairs of our solver over the setting's sweeps (None for the peer).
    pub convolutions: Option<usize>,
    /// Cost relative to the panel's reference.
    pub cost: f64,
    /// Per quantity and detail (e.g. one A*): largest raw error and largest error in units
    /// of the scatter.
    pub errors: Vec<(Quantity, String, f64, f64)>,
}

impl Point {
    /// The worst scaled error of `q` (all details); None where it is undefined (NaN: the
    /// quantity exists on one side only).
    pub fn error(&self, q: Quantity) -> Option<f64> {
        self.errors
            .iter()
            .filter(|e| e.0 == q && !e.3.is_nan())
            .map(|e| e.3)
            .reduce(f64::max)
    }

    /// The worst scaled error over the quantities that are defined.
    pub fn worst(&self) -> f64 {
        self.errors.iter().map(|e| e.3).fold(0.0, f64::max)
    }

    /// The quantities this setting cannot give although the reference does (or the reverse).
    pub fn undefined(&self) -> Vec<Quantity> {
        let mut q: Vec<Quantity> = self
            .errors
            .iter()
            .filter(|e| e.3.is_nan())
            .map(|e| e.0)
            .collect();
        q.dedup();
        q
    }
}

/// One panel: a knob, its settings and the setting the pipeline uses.
pub struct Panel {
    pub title: String,
    pub knob: &'static str,
    pub x_label: String,
    /// The pipeline's current setting.
    pub current: f64,
    /// The cheapest setting within the scatter (tolerance panels).
    pub choice: Option<f64>,
    pub points: Vec<Point>,
}

/// Errors of `sample` against `reference`, each quantity in units of `scales`.
fn errors(
    sample: &Sample,
    reference: &Sample,
    scales: &Scales,
) -> Vec<(Quantity, String, f64, f64)> {
    let mut out = Vec::new();
    for q in Quantity::ALL {
        if q == Quantity::Ks {
            let d = sample.ks(reference);
            let zero = vec![(String::new(), 0.0); d.len()];
            let (raw, scaled) = worst(&d, &zero, &scales.ks);
            out.push((q, String::new(), raw, scaled));
            continue;
        }
        let a = sample.values(q, &FIG3_LOADS);
        let b = reference.values(q, &FIG3_LOADS);
        let s = &scales.of[&q];
        if matches!(q, Quantity::KArchard | Quantity::KUpscaled) {
            for t in measure::A_STAR_OVER_LS2 {
                let tag = format!("A*={t}λs²");
                let pick = |v: &measure::Values| -> measure::Values {
                    v.iter().filter(|p| p.0.ends_with(&tag)).cloned().collect()
                };
                let sc: Vec<f64> = a
                    .iter()
                    .zip(s)
                    .filter(|(p, _)| p.0.ends_with(&tag))
                    .map(|(_, s)| *s)
                    .collect();
                let (raw, scaled) = worst(&pick(&a), &pick(&b), &sc);
                out.push((q, tag, raw, scaled));
            }
        } else {
            let (raw, scaled) = worst(&a, &b, s);
            out.push((q, String::new(), raw, scaled));
        }
    }
    out
}

/// The unit of each quantity's error at each of its points.
struct Scales {
    of: std::collections::BTreeMap<Quantity, Vec<f64>>,
    ks: Vec<f64>,
}

/// Scales from per-realization samples of the reference: the standard deviation between
/// them over √`equivalent` (the realizations the studies average); KS: the noise of two
/// samples of `equivalent` realizations each.
fn scales(per_realization: &[Sample], equivalent: f64) -> Scales {
    let mut of = std::collections::BTreeMap::new();
    for q in Quantity::ALL {
        if q == Quantity::Ks {
            continue;
        }
        let v: Vec<measure::Values> = per_realization
            .iter()
            .map(|s| s.values(q, &FIG3_LOADS))
            .collect();
        of.insert(q, with_fallback(scatter(&v), equivalent));
    }
    let loads = per_realization[0].loads.len();
    let counts: Vec<usize> = (0..loads)
        .map(|l| {
            let c: usize = per_realization.iter().map(|s| s.clusters[l].len()).sum();
            ((c as f64 / per_realization.len() as f64) * equivalent).round() as usize
        })
        .collect();
    Scales {
        of,
        ks: ks_noise(&counts, &counts),
    }
}

/// Scatter over √`equivalent`; a point where the realizations do not scatter (all zero, e.g.
/// K above the largest cluster) or where fewer than two could be fitted (α̂ with a handful of
/// clusters) takes the median unit of the quantity's other points, so a change there is
/// judged against the quantity's typical scatter rather than counted as infinite.
fn with_fallback(sigma: Vec<f64>, equivalent: f64) -> Vec<f64> {
    let mut good: Vec<f64> = sigma
        .iter()
        .copied()
        .filter(|s| s.is_finite() && *s > 0.0)
        .collect();
    good.sort_by(f64::total_cmp);
    let median = good.get(good.len() / 2).copied().unwrap_or(0.0);
    sigma
        .into_iter()
        .map(|s| if s.is_finite() && s > 0.0 { s } else { median } / equivalent.sqrt())
        .collect()
}

/// A family of studies sharing a spectrum and resolution, measured on `setup`: the default
/// profile's studies that carry the panel's choice (all at one tolerance; checked).
struct Family {
    title: &'static str,
    studies: &'static [&'static str],
    setup: Setup,
    seed: u64,
    loads: Vec<f64>,
    realizations: usize,
    /// Realizations of this box the studies average (the strictest of the family).
    equivalent: f64,
}

fn tolerance_panel(fam: &Family, current: f64, peer: Option<&(PathBuf, PathBuf)>) -> Panel {
    let n = fam.setup.n();
    let surfaces: Vec<Vec<f64>> = (0..fam.realizations as u64)
        .map(|i| fam.setup.heights(fam.seed + i))
        .collect();
    let sample = |s: &Sweep| Sample::pooled(&fam.setup, &fam.loads, &[s]);
    let refs: Vec<Sweep> = surfaces
        .iter()
        .map(|h| ours(h, n, &fam.loads, REFERENCE_TOLERANCE))
        .collect();
    let ref_samples: Vec<Sample> = refs.iter().map(sample).collect();
    let units = scales(&ref_samples, fam.equivalent);
    let ref_seconds: f64 = refs.iter().map(|s| s.seconds).sum();
    eprintln!(
        "{}: n = {n}, {} realizations, reference {REFERENCE_TOLERANCE:e}: {ref_seconds:.1} s",
        fam.title, fam.realizations
    );
    let mut points = Vec::new();
    for &tol in &TOLERANCES {
        let mut seconds = 0.0;
        let mut convolutions = 0;
        let mut errs: Vec<(Quantity, String, f64, f64)> = Vec::new();
        for (h, r) in surfaces.iter().zip(&ref_samples) {
            let s = ours(h, n, &fam.loads, tol);
            seconds += s.seconds;
            convolutions += s.convolutions.unwrap_or(0);
            merge(&mut errs, errors(&sample(&s), r, &units));
        }
        let p = Point {
            code: "wearcoef",
            setting: tol,
            seconds,
            convolutions: Some(convolutions),
            cost: seconds / ref_seconds,
            errors: errs,
        };
        eprintln!(
            "  tol {tol:e}: cost {:.3}, {convolutions} FFT pairs, worst error {:.3} scatter",
            p.cost,
            p.worst()
        );
        points.push(p);
    }
    if let Some((python, work)) = peer {
        for &tol in &TAMAAS_TOLERANCES {
            match tamaas(python, work, &surfaces[0], n, &fam.loads, tol) {
                Ok(s) => {
                    let p = Point {
                        code: "Tamaas",
                        setting: tol,
                        seconds: s.seconds,
                        convolutions: None,
                        cost: s.seconds / refs[0].seconds,
                        errors: errors(&sample(&s), &ref_samples[0], &units),
                    };
                    eprintln!(
                        "  Tamaas tol {tol:e}: cost {:.3}, worst error {:.3} scatter",
                        p.cost,
                        p.worst()
                    );
                    points.push(p);
                }
                Err(e) => panic!("Tamaas at {tol:e}: {e}"),
            }
        }
    }
    let choice = choose(&points);
    Panel {
        title: fam.title.to_string(),
        knob: "tolerance",
        x_label: "cost / cost at tolerance 10^{-12}".into(),
        current,
        choice,
        points,
    }
}

/// The chart's choice among our tolerances: of those whose worst quantity stays within the
/// scatter, the one whose sweeps took the fewest FFT pairs, and of equal counts the loosest.
/// The work is counted rather than timed so that the choice does not follow the timing noise
/// of seconds-long sweeps (a few per cent between neighbouring tolerances, more than the
/// difference between them); FFT pairs are most of an iteration's time at every size here.
fn choose(points: &[Point]) -> Option<f64> {
    points
        .iter()
        .filter(|p| p.code == "wearcoef" && p.worst() <= 1.0 && p.undefined().is_empty())
        .filter_map(|p| Some((p.convolutions?, p.setting)))
        .min_by(|a, b| a.0.cmp(&b.0).then(b.1.total_cmp(&a.1)))
        .map(|(_, setting)| setting)
}

/// Keep the larger error of each (quantity, detail).
fn merge(into: &mut Vec<(Quantity, String, f64, f64)>, new: Vec<(Quantity, String, f64, f64)>) {
    for e in new {
        match into.iter_mut().find(|x| x.0 == e.0 && x.1 == e.1) {
            Some(x) => {
                x.2 = x.2.max(e.2);
                x.3 = x.3.max(e.3);
            }
            None => into.push(e),
        }
    }
}

/// A discretisation knob on the λ_l/λ_s = 8 spectrum: each setting's pooled sample against
/// the finest, in units of the noise of that difference.
fn knob_panel(
    title: &str,
    knob: &'static str,
    x_label: &str,
    settings: &[(f64, Setup)],
    realizations: usize,
    tolerance: f64,
    current: f64,
) -> Panel {
    let loads = FIG3_LOADS.to_vec();
    let mut runs: Vec<(f64, Setup, Vec<Sweep>)> = Vec::new();
    for &(value, setup) in settings {
        let sweeps: Vec<Sweep> = (0..realizations as u64)
            .map(|i| ours(&setup.heights(9000 + i), setup.n(), &loads, tolerance))
            .collect();
        runs.push((value, setup, sweeps));
    }
    let (_, fine_setup, fine) = runs.last().unwrap();
    let fine_seconds: f64 = fine.iter().map(|s| s.seconds).sum();
    let fine_refs: Vec<&Sweep> = fine.iter().collect();
    let fine_pooled = Sample::pooled(fine_setup, &loads, &fine_refs);
    let fine_each: Vec<Sample> = fine
        .iter()
        .map(|s| Sample::pooled(fine_setup, &loads, &[s]))
        .collect();
    let mut points = Vec::new();
    for (value, setup, sweeps) in &runs[..runs.len() - 1] {
        let refs: Vec<&Sweep> = sweeps.iter().collect();
        let pooled = Sample::pooled(setup, &loads, &refs);
        let each: Vec<Sample> = sweeps
            .iter()
            .map(|s| Sample::pooled(setup, &loads, &[s]))
            .collect();
        let units = difference_scales(&each, &fine_each);
        let seconds: f64 = sweeps.iter().map(|s| s.seconds).sum();
        points.push(Point {
            code: "wearcoef",
            setting: *value,
            seconds,
            convolutions: sweeps.iter().map(|s| s.convolutions).sum(),
            cost: seconds / fine_seconds,
            errors: errors(&pooled, &fine_pooled, &units),
        });
        eprintln!(
            "{title}: {knob} = {value}: cost {:.3}, worst {:.3}",
            seconds / fine_seconds,
            points.last().unwrap().worst()
        );
    }
    Panel {
        title: title.to_string(),
        knob,
        x_label: x_label.to_string(),
        current,
        choice: None,
        points,
    }
}

/// The noise of the difference of two ensemble means: √(σ_a²/R_a + σ_b²/R_b) per point;
/// KS: √((n+m)/(nm)) with the pooled cluster counts.
fn difference_scales(a: &[Sample], b: &[Sample]) -> Scales {
    let (sa, sb) = (scales(a, a.len() as f64), scales(b, b.len() as f64));
    let of = sa
        .of
        .iter()
        .map(|(q, va)| {
            let vb = &sb.of[q];
            (*q, va.iter().zip(vb).map(|(x, y)| x.hypot(*y)).collect())
        })
        .collect();
    let count = |s: &[Sample]| -> Vec<usize> {
        (0..s[0].loads.len())
            .map(|l| s.iter().map(|x| x.clusters[l].len()).sum())
            .collect()
    };
    Scales {
        of,
        ks: ks_noise(&count(a), &count(b)),
    }
}

/// The realization count: the first r realizations pooled against all, in units of the
/// full ensemble's scatter σ/√R.
fn realizations_panel(setup: Setup, total: usize, tolerance: f64, current: f64) -> Panel {
    let loads = FIG3_LOADS.to_vec();
    let sweeps: Vec<Sweep> = (0..total as u64)
        .map(|i| ours(&setup.heights(7000 + i), setup.n(), &loads, tolerance))
        .collect();
    let all: Vec<&Sweep> = sweeps.iter().collect();
    let full = Sample::pooled(&setup, &loads, &all);
    let each: Vec<Sample> = sweeps
        .iter()
        .map(|s| Sample::pooled(&setup, &loads, &[s]))
        .collect();
    let units = scales(&each, total as f64);
    let total_seconds: f64 = sweeps.iter().map(|s| s.seconds).sum();
    let mut points = Vec::new();
    for r in [1usize, 2, 3, 4, 6, 8] {
        let first = Sample::pooled(&setup, &loads, &all[..r]);
        let seconds: f64 = sweeps[..r].iter().map(|s| s.seconds).sum();
        points.push(Point {
            code: "wearcoef",
            setting: r as f64,
            seconds,
            convolutions: sweeps[..r].iter().map(|s| s.convolutions).sum(),
            cost: seconds / total_seconds,
            errors: errors(&first, &full, &units),
        });
    }
    Panel {
        title: format!("(f) realizations r of {total} (λ_l/λ_s = 8, L/λ_l = 4)"),
        knob: "realizations",
        x_label: format!("cost / cost of {total} realizations"),
        current,
        choice: None,
        points,
    }
}

/// The default profile's solver tolerance of each study (pipeline.yaml, read once).
fn default_tolerances(config: &Path) -> std::collections::BTreeMap<String, f64> {
    let pipeline = wearcoef::config::Pipeline::load(config).expect("pipeline.yaml");
    pipeline
        .plan("default", &config.display().to_string())
        .expect("default profile")
        .into_iter()
        .map(|p| (p.name, p.tolerance))
        .collect()
}

fn main() {
    // `cargo bench` passes `--bench`; nothing else is read.
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let out_dir = root.join("figures");
    let config = root.join("pipeline.yaml");
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("target"));
    let python = std::env::var_os("WEARCOEF_PEERS_PYTHON")
        .map(PathBuf::from)
        .expect("WEARCOEF_PEERS_PYTHON is not set: run `make speed-accuracy` (it installs Tamaas from PyPI)");
    let work = target.join("speed-accuracy");
    std::fs::create_dir_all(&work).unwrap();
    let peer = (python, work);

    let fig3_128: Vec<f64> = log_edges(0.06 * 3f64.powf(-15.0 / 4.0), 0.06, 15);
    let mut fig2_loads = log_edges(0.001, 0.2, 9);
    fig2_loads.extend(FIG3_LOADS);
    fig2_loads.sort_by(f64::total_cmp);
    let h08 = |ratio: f64, box_: f64, res: f64| Setup {
        hurst: 0.8,
        lambda_l_over_lambda_s: ratio,
        l_over_lambda_l: box_,
        lambda_s_over_dl: res,
    };
    let families = [
        Family {
            title: "(a) tolerance, λ_l/λ_s = 8 (n = 512)",
            studies: &["fig2", "fig3_ll8", "b2_r8"],
            setup: h08(8.0, 8.0, 8.0),
            seed: 100,
            loads: fig2_loads,
            realizations: 4,
            // The strictest, b2_r8 (5 realizations of L/λ_l = 16, i.e. 20 boxes of
            // L/λ_l = 8), with a margin of 2.
            equivalent: 40.0,
        },
        Family {
            title: "(b) tolerance, λ_l/λ_s = 32 (n = 1024)",
            studies: &["fig3_ll32"],
            setup: h08(32.0, 4.0, 8.0),
            seed: 200,
            loads: FIG3_LOADS.to_vec(),
            realizations: 3,
            equivalent: 3.0,
        },
        Family {
            title: "(c) tolerance, λ_l/λ_s = 128 (n = 1024)",
            studies: &["fig3_ll128"],
            setup: h08(128.0, 1.0, 8.0),
            seed: 300,
            loads: fig3_128,
            realizations: 3,
            // fig3_ll128: 7 realizations of L/λ_l = 2, i.e. 28 boxes of L/λ_l = 1.
            equivalent: 28.0,
        },
    ];
    let tolerances = default_tolerances(&config);
    let current_tolerance = |study: &str| -> f64 {
        *tolerances
            .get(study)
            .unwrap_or_else(|| panic!("study {study} not in the default profile"))
    };
    let mut panels = Vec::new();
    for (i, fam) in families.iter().enumerate() {
        let current = current_tolerance(fam.studies[0]);
        for study in fam.studies {
            let own = current_tolerance(study);
            assert_eq!(
                own, current,
                "pipeline.yaml: {study} has tolerance {own:e}, {} has {current:e}; a family carries one choice",
                fam.studies[0]
            );
        }
        let panel = tolerance_panel(fam, current, (i == 0).then_some(&peer));
        println!(
            "{}: studies {}; pipeline.yaml {:e}; chart's choice {}",
            fam.title,
            fam.studies.join(", "),
            current,
            panel
                .choice
                .map_or("none within the scatter".to_string(), |c| format!("{c:e}"))
        );
        panels.push(panel);
    }
    let tol = current_tolerance("b2_r8");
    let res: Vec<(f64, Setup)> = [2.0, 4.0, 8.0, 16.0]
        .iter()
        .map(|&r| (r, h08(8.0, 4.0, r)))
        .collect();
    panels.push(knob_panel(
        "(d) λ_s/Δl against 16 (λ_l/λ_s = 8, L/λ_l = 4)",
        "lambda_s_over_dl",
        "cost / cost at λ_s/Δl = 16",
        &res,
        6,
        tol,
        8.0,
    ));
    let boxes: Vec<(f64, Setup)> = [1.0, 2.0, 4.0, 8.0, 16.0]
        .iter()
        .map(|&l| (l, h08(8.0, l, 8.0)))
        .collect();
    panels.push(knob_panel(
        "(e) L/λ_l against 16 (λ_l/λ_s = 8, λ_s/Δl = 8)",
        "l_over_lambda_l",
        "cost / cost at L/λ_l = 16",
        &boxes,
        6,
        tol,
        8.0,
    ));
    panels.push(realizations_panel(h08(8.0, 4.0, 8.0), 12, tol, 4.0));

    chart::write_csv(&out_dir.join("speed_accuracy.csv"), &panels).unwrap();
    chart::draw(&out_dir, &panels).unwrap();
    println!("\n{}", chart::markdown(&panels));
    eprintln!("wrote {}", out_dir.join("speed_accuracy.png").display());
}
