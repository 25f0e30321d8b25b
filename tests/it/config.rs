//! pipeline.yaml validation: every invalid value names its field path.

use wearcoef::config::{ConfigError, Pipeline};

const BASE: &str = r#"schema_version: 1
material: {e_star: 1.0}
solver: {tolerance: 1.0e-10, max_iterations: 1000}
profiles: {quick: "q", default: "d"}
studies:
  s:
    hurst: 0.8
    lambda_l_over_lambda_s: 8
    seed: 1
    loads: {min: 0.001, max: 0.06, count: 5}
    profiles:
      quick: {l_over_lambda_l: 2, lambda_s_over_dl: 4, realizations: 2}
"#;

fn field_of(text: &str) -> String {
    match Pipeline::parse(text, "test.yaml") {
        Err(ConfigError::Invalid { field, .. }) => field,
        Err(ConfigError::Parse { message, .. }) => format!("PARSE: {message}"),
        Err(other) => format!("OTHER: {other}"),
        Ok(_) => "OK".to_string(),
    }
}

#[test]
fn the_base_file_is_valid_and_resolves() {
    let p = Pipeline::parse(BASE, "test.yaml").unwrap();
    let plans = p.plan("quick", "test.yaml").unwrap();
    assert_eq!(plans.len(), 1);
    let plan = &plans[0];
    assert_eq!(plan.surface.n, 64);
    assert_eq!(plan.surface.lambda_s_px, 4.0);
    assert_eq!(plan.surface.lambda_l_px, 32.0);
    assert_eq!(plan.loads.len(), 5);
    assert_eq!(plan.loads[0], 0.001);
    assert_eq!(plan.loads[4], 0.06);
    let ratio = plan.loads[1] / plan.loads[0];
    for w in plan.loads.windows(2) {
        assert!((w[1] / w[0] / ratio - 1.0).abs() < 1e-12, "log spacing");
    }
    // A declared profile the study does not belong to has no studies.
    assert!(p.plan("default", "test.yaml").unwrap().is_empty());
}

#[test]
fn each_invalid_value_names_its_field() {
    let cases: &[(&str, &str, &str)] = &[
        ("hurst: 0.8", "hurst: 1.2", "studies.s.hurst"),
        ("hurst: 0.8", "hurst: 0.0", "studies.s.hurst"),
        (
            "lambda_s_over_dl: 4",
            "lambda_s_over_dl: 1.5",
            "studies.s.profiles.quick.lambda_s_over_dl",
        ),
        (
            "l_over_lambda_l: 2",
            "l_over_lambda_l: 0.5",
            "studies.s.profiles.quick.l_over_lambda_l",
        ),
        (
            "l_over_lambda_l: 2",
            "l_over_lambda_l: 2.1",
            "studies.s.profiles.quick.l_over_lambda_l",
        ),
        (
            "lambda_l_over_lambda_s: 8",
            "lambda_l_over_lambda_s: 1",
            "studies.s.lambda_l_over_lambda_s",
        ),
        (
            "realizations: 2",
            "realizations: 0",
            "studies.s.profiles.quick.realizations",
        ),
        ("min: 0.001", "min: -0.001", "studies.s.loads.min"),
        ("max: 0.06", "max: 0.0001", "studies.s.loads.max"),
        ("count: 5", "count: 1", "studies.s.loads.count"),
        (
            "{min: 0.001, max: 0.06, count: 5}",
            "{values: [0.01, 0.01]}",
            "studies.s.loads.values[1]",
        ),
        (
            "{min: 0.001, max: 0.06, count: 5}",
            "{values: [0.02, 0.01]}",
            "studies.s.loads.values[1]",
        ),
        (
            "{min: 0.001, max: 0.06, count: 5}",
            "{values: [0.0]}",
            "studies.s.loads.values[0]",
        ),
        (
            "{min: 0.001, max: 0.06, count: 5}",
            "{min: 0.001, max: 0.06}",
            "studies.s.loads",
        ),
        ("e_star: 1.0", "e_star: 0.0", "material.e_star"),
        ("tolerance: 1.0e-10", "tolerance: 2.0", "solver.tolerance"),
        (
            "realizations: 2",
            "realizations: 2, tolerance: 0.0",
            "studies.s.profiles.quick.tolerance",
        ),
        (
            "realizations: 2",
            "realizations: 2, tolerance: 1.0",
            "studies.s.profiles.quick.tolerance",
        ),
        (
            "max_iterations: 1000",
            "max_iterations: 0",
            "solver.max_iterations",
        ),
        ("quick: {l_over", "fast: {l_over", "studies.s.profiles.fast"),
        (
            "seed: 1",
            "seed: 1\n    method: spectral",
            "studies.s.method",
        ),
        (
            "seed: 1",
            "seed: 1\n    rolloff_over_lambda_l: 4",
            "studies.s.rolloff_over_lambda_l",
        ),
        ("schema_version: 1", "schema_version: 2", "schema_version"),
    ];
    for (from, to, field) in cases {
        assert!(BASE.contains(from), "test case pattern {from} not in base");
        let text = BASE.replacen(from, to, 1);
        assert_eq!(&field_of(&text), field, "replacing {from} by {to}");
    }
}

#[test]
fn a_profile_tolerance_replaces_the_solver_tolerance_for_that_profile_only() {
    let text = BASE.replacen(
        "      quick: {l_over_lambda_l: 2, lambda_s_over_dl: 4, realizations: 2}",
        "      quick: {l_over_lambda_l: 2, lambda_s_over_dl: 4, realizations: 2, tolerance: 1.0e-6}\n      default: {l_over_lambda_l: 2, lambda_s_over_dl: 4, realizations: 2}",
        1,
    );
    let p = Pipeline::parse(&text, "test.yaml").unwrap();
    assert_eq!(p.plan("quick", "test.yaml").unwrap()[0].tolerance, 1e-6);
    assert_eq!(p.plan("default", "test.yaml").unwrap()[0].tolerance, 1e-10);
}

#[test]
fn messages_state_the_allowed_range() {
    let text = BASE.replacen("lambda_s_over_dl: 4", "lambda_s_over_dl: 1", 1);
    let msg = Pipeline::parse(&text, "test.yaml").unwrap_err().to_string();
    assert!(msg.contains("test.yaml"), "{msg}");
    assert!(msg.contains("≥ 2"), "{msg}");
}

#[test]
fn unknown_fields_and_bad_types_are_rejected_at_parse_time() {
    for text in [
        BASE.replacen("hurst: 0.8", "hurst: 0.8\n    hurts: 0.7", 1),
        BASE.replacen("e_star: 1.0", "e_star: 1.0, nu: 0.3", 1),
        BASE.replacen("seed: 1", "seed: one", 1),
        "schema_version: 1\nmaterial: [".to_string(),
    ] {
        let f = field_of(&text);
        assert!(f.starts_with("PARSE"), "{f} for\n{text}");
    }
    let msg = field_of(&BASE.replacen("hurst: 0.8", "hurst: 0.8\n    hurts: 0.7", 1));
    assert!(msg.contains("hurts"), "the unknown field is named: {msg}");
}

#[test]
fn unknown_profile_is_an_error_listing_the_known_ones() {
    let p = Pipeline::parse(BASE, "test.yaml").unwrap();
    let msg = p.plan("paper", "test.yaml").unwrap_err().to_string();
    assert!(
        msg.contains("paper") && msg.contains("quick") && msg.contains("default"),
        "{msg}"
    );
}

#[test]
fn the_shipped_pipeline_is_valid_for_every_profile() {
    let path = crate::repo_root().join("pipeline.yaml");
    let p = Pipeline::load(&path).unwrap();
    for profile in [
        "quick",
        "default",
        "paper",
        "convergence128",
        "convergence128_h06",
        "convergence128_low",
        "load_resolution128",
        "realizations8",
    ] {
        let plans = p.plan(profile, "pipeline.yaml").unwrap();
        assert!(!plans.is_empty(), "{profile} has studies");
    }
    // The λ_l/λ_s = 128 convergence profiles: one Hurst exponent each (that of the default
    // study they check), the default's sizes among the candidates, and the rule's sizes
    // (L/λ_l ≥ 4, λ_s/Δl ≥ 8) as the largest grid, which the figure takes as its reference.
    let default = p.plan("default", "pipeline.yaml").unwrap();
    let sizes = |s: &wearcoef::config::StudyPlan| {
        let f = &s.surface;
        (f.n, f.n as f64 / f.lambda_l_px, f.lambda_s_px)
    };
    for (profile, checked) in [
        ("convergence128", "fig3_ll128"),
        ("convergence128_h06", "fig3_h06"),
        ("convergence128_low", "fig3_ll128"),
    ] {
        let conv = p.plan(profile, "pipeline.yaml").unwrap();
        let study = default.iter().find(|s| s.name == checked).unwrap();
        assert!(
            conv.iter().all(|s| s.name.starts_with("c128_")
                && s.surface.lambda_l_px / s.surface.lambda_s_px == 128.0
                && s.surface.hurst == study.surface.hurst),
            "{profile}"
        );
        assert!(conv.iter().any(|s| sizes(s) == sizes(study)), "{profile}");
        let reference = conv.iter().max_by_key(|s| s.surface.n).unwrap();
        let (n, l, r) = sizes(reference);
        assert!(
            l >= 4.0 && r >= 8.0,
            "{profile}: reference n = {n}: L/λ_l = {l}, λ_s/Δl = {r}"
        );
        assert_eq!(conv.iter().filter(|s| s.surface.n == n).count(), 1);
    }
}

/// A study of its own sweep (`s`) and one without loads (`t`), drawn by one figure.
fn with_figure(figure: &str) -> String {
    BASE.replace(
        "      quick: {l_over_lambda_l: 2, lambda_s_over_dl: 4, realizations: 2}\n",
        "      quick: {l_over_lambda_l: 2, lambda_s_over_dl: 4, realizations: 2}\n  t:\n    hurst: 0.7\n    lambda_l_over_lambda_s: 8\n    seed: 2\n    profiles:\n      quick: {l_over_lambda_l: 2, lambda_s_over_dl: 4, realizations: 1}\n",
    ) + "figures:\n" + figure
}

/// Figures name their studies: a study renamed (or never declared), or one without an entry
/// for a profile the figure is drawn in, is an error naming the figure, the study and the
/// fix, never a silently missing curve.
#[test]
fn a_figure_whose_study_is_missing_or_absent_from_a_profile_is_an_error() {
    let ok = "  f: {kind: fig3_fig4a, ratios: [s, t], loads: [0.005, 0.02], inset_load: 0.02, profiles: [quick]}\n";
    assert_eq!(field_of(&with_figure(ok)), "OK");
    let renamed = ok.replace("ratios: [s, t]", "ratios: [s, t8]");
    let err = Pipeline::parse(&with_figure(&renamed), "test.yaml")
        .unwrap_err()
        .to_string();
    assert!(err.contains("figures.f") && err.contains("'t8'"), "{err}");
    let absent = ok.replace("profiles: [quick]", "profiles: [quick, default]");
    let err = Pipeline::parse(&with_figure(&absent), "test.yaml")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("figures.f.profiles") && err.contains("studies.s.profiles.default"),
        "{err}"
    );
    // Left out explicitly, a study is not drawn in that profile; the figure still needs one.
    let omitted = absent.replace(
        "profiles: [quick, default]",
        "profiles: [quick, default], omit: {default: [s, t]}",
    );
    let err = Pipeline::parse(&with_figure(&omitted), "test.yaml")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("figures.f.omit") && err.contains("leaves 0 studies"),
        "{err}"
    );
    // A field the kind does not take.
    let extra = ok.replace("profiles: [quick]", "profiles: [quick], study: s");
    assert_eq!(field_of(&with_figure(&extra)), "figures.f.study");
}

/// A study without loads of its own computes exactly the loads its figures ask for; a sweep
/// keeps its loads (figures take the nearest), and a figure's load outside the sweep is an
/// error naming the figure's field.
#[test]
fn a_study_computes_the_loads_its_figures_ask_for() {
    let text = with_figure(
        "  f: {kind: fig3_fig4a, ratios: [s, t], loads: [0.02, 0.005], inset_load: 0.06, hurst: [t], profiles: [quick]}\n",
    );
    let p = Pipeline::parse(&text, "test.yaml").unwrap();
    let plans = p.plan("quick", "test.yaml").unwrap();
    let loads = |name: &str| plans.iter().find(|s| s.name == name).unwrap().loads.clone();
    assert_eq!(loads("t"), vec![0.005, 0.02, 0.06]);
    assert_eq!(loads("s").len(), 5, "the sweep is kept");
    let outside = text.replace("loads: [0.02, 0.005]", "loads: [0.02, 0.5]");
    assert_eq!(field_of(&outside), "figures.f.loads");
    // A study that no figure draws and that has no loads of its own has nothing to compute.
    let undrawn = text
        .replace("ratios: [s, t]", "ratios: [s]")
        .replace("hurst: [t], ", "");
    assert_eq!(field_of(&undrawn), "studies.t.loads");
}

/// The shipped pipeline: the studies drawn only in Figs. 3 and 4a compute exactly the loads
/// that figure asks for, and the inset studies only the inset's load, in the quick, default
/// and paper profiles; fig3_ll128 also feeds Figs. 4b and 5, so it sweeps.
#[test]
fn figure_3_studies_compute_only_the_loads_figure_3_draws() {
    let path = crate::repo_root().join("pipeline.yaml");
    let pipeline = Pipeline::load(&path).unwrap();
    let fig3 = &pipeline.figures["fig3_fig4a"];
    let inset = fig3.inset_load.unwrap();
    for profile in ["quick", "default", "paper"] {
        let plans = pipeline.plan(profile, "pipeline.yaml").unwrap();
        let loads = |name: &str| {
            plans
                .iter()
                .find(|s| s.name == name)
                .unwrap_or_else(|| panic!("{profile}: no study {name}"))
                .loads
                .clone()
        };
        for name in ["fig3_ll8", "fig3_ll32"] {
            assert_eq!(loads(name), fig3.loads, "{profile}: {name}");
        }
        for name in ["fig3_h06", "fig3_h07"] {
            assert_eq!(loads(name), vec![inset], "{profile}: {name}");
        }
        assert!(
            loads("fig3_ll128").len() > fig3.loads.len(),
            "{profile}: fig3_ll128 sweeps"
        );
    }
}

/// The load-resolution profile's `lr128_chosen` is exactly the default profile's fig3_ll128
/// (so its check is about the sweep Figs. 4b and 5 draw), and `lr128_fine` the same
/// realizations at more loads over the same range.
#[test]
fn load_resolution_studies_are_the_default_fig3_ll128_sweep_and_a_finer_one() {
    let path = crate::repo_root().join("pipeline.yaml");
    let pipeline = Pipeline::load(&path).unwrap();
    let default = pipeline.plan("default", "pipeline.yaml").unwrap();
    let check = pipeline
        .plan("load_resolution128", "pipeline.yaml")
        .unwrap();
    let find = |plans: &[wearcoef::config::StudyPlan], name: &str| {
        plans.iter().find(|s| s.name == name).cloned().unwrap()
    };
    let drawn = find(&default, "fig3_ll128");
    let chosen = find(&check, "lr128_chosen");
    let fine = find(&check, "lr128_fine");
    let same = |a: &wearcoef::config::StudyPlan, b: &wearcoef::config::StudyPlan| {
        let strip = |s: &wearcoef::config::StudyPlan| wearcoef::config::StudyPlan {
            name: String::new(),
            profile: String::new(),
            loads: Vec::new(),
            ..s.clone()
        };
        strip(a) == strip(b)
    };
    assert!(same(&drawn, &chosen) && drawn.loads == chosen.loads);
    // The fine sweep is the reference: the same surfaces, at a tolerance no looser.
    assert!(fine.tolerance <= drawn.tolerance);
    assert!(same(
        &drawn,
        &wearcoef::config::StudyPlan {
            tolerance: drawn.tolerance,
            ..fine.clone()
        }
    ));
    assert!(fine.loads.len() > chosen.loads.len());
    // The fine sweep lies inside the chosen one's range, so every fine load is judged.
    assert!(chosen.loads[0] <= fine.loads[0]);
    assert_eq!(chosen.loads.last(), fine.loads.last());
    // The Fig. 3 loads are on the chosen grid or within 1.5 % of it.
    for &t in &pipeline.figures["fig3_fig4a"].loads {
        let nearest = chosen.loads[wearcoef::statistics::nearest_in_log(&chosen.loads, t).unwrap()];
        assert!((nearest / t - 1.0).abs() < 0.015, "{t}: {nearest}");
    }
}
