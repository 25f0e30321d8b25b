//! One load's cluster areas fitted, as the JSON rows that `wearcoef fit --json` prints and
//! `wear` tabulates: the truncated power law above x_min with its bootstrap interval and
//! Clauset et al.'s tests, and the plateau + power law of Appendix A.

use serde_json::json;

/// The truncated power law fitted to one load's areas, with its bootstrap interval, as JSON.
pub fn fit_row(
    load: Option<u32>,
    w: f64,
    data: &[u64],
    excluded: usize,
    resamples: usize,
    seed: u64,
) -> serde_json::Value {
    use crate::powerlaw;
    let mut row = match powerlaw::fit_tail_at_max(data) {
        Ok(t) => {
            let (f, m) = (t.fit, t.fit.upper as u64);
            let ci =
                powerlaw::bootstrap_discrete(data, f.lower as u64, Some(m), resamples, seed).ok();
            let gof = powerlaw::goodness_of_fit(data, &f, resamples, seed ^ 1).ok();
            json!({
                "load_index": load, "w_over_w0": (w.is_finite()).then_some(w),
                "clusters": data.len(), "percolating_left_out": excluded,
                "alpha": f.alpha, "std_error": f.std_error,
                "bootstrap_ci95_low": ci.map(|c| c.0), "bootstrap_ci95_high": ci.map(|c| c.1),
                "x_min_px": f.lower, "x_max_px": f.upper, "n_fitted": f.n,
                "ks_distance": f.ks_distance, "x_min_candidates": t.candidates,
                "gof_p": gof.map(|g| g.p_value), "gof_samples": gof.map(|g| g.samples),
                "tail_tests": tail_tests_json(data, f.lower as u64),
            })
        }
        Err(e) => json!({
            "load_index": load, "w_over_w0": (w.is_finite()).then_some(w),
            "clusters": data.len(), "percolating_left_out": excluded,
            "alpha": null, "note": format!("no fit: {e}"),
        }),
    };
    // The plateau + power law (Appendix A's model): its α, 95 % profile-likelihood interval, and the
    // plateau's end A_s and cut-off A_m that `wearcoef model` takes.
    row["plateau"] = match powerlaw::fit_plateau_power_law(data) {
        Ok(p) => {
            let ci = powerlaw::plateau_alpha_interval(data, &p).ok();
            json!({
                "alpha": p.alpha,
                "profile_ci95_low": ci.map(|c| c.low), "profile_ci95_high": ci.map(|c| c.high),
                "a_s_px": p.k_s, "a_m_px": p.k_m, "n_fitted": p.n,
            })
        }
        Err(e) => json!({"alpha": null, "note": format!("no fit: {e}")}),
    };
    row
}

/// The likelihood-ratio tests of the power law above `k_min` against its alternatives, as
/// JSON: per alternative its fitted parameters, `R` (positive favours the power law), `R`
/// normalised and its p-value; and what the tail is by them.
pub fn tail_tests_json(data: &[u64], k_min: u64) -> serde_json::Value {
    use crate::powerlaw;
    match powerlaw::compare_tail(data, k_min) {
        Ok(c) => {
            let mut tests = serde_json::Map::new();
            for (alt, t) in powerlaw::Alternative::ALL.iter().zip(&c.tests) {
                let v = match t {
                    Ok(t) => {
                        let mut params = serde_json::Map::new();
                        for (name, v) in alt.parameter_names().iter().zip(t.parameters) {
                            if !name.is_empty() {
                                params.insert(name.to_string(), json!(v));
                            }
                        }
                        json!({
                            "parameters": params, "loglikelihood": t.loglikelihood,
                            "ratio": t.ratio, "normalised_ratio": t.normalised_ratio,
                            "p": t.p_value, "nested": alt.nested(),
                        })
                    }
                    Err(e) => json!({"note": format!("no fit: {e}")}),
                };
                tests.insert(alt.name().to_string(), v);
            }
            json!({
                "k_min_px": c.k_min, "n": c.n, "alpha_power_law": c.alpha,
                "loglikelihood": c.loglikelihood, "tests": tests,
                "verdict": powerlaw::tail_verdict(&c),
            })
        }
        Err(e) => json!({"note": format!("no test: {e}")}),
    }
}
