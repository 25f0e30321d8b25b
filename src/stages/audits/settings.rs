//! The settings audit (Appendix B rule): each setting's pooled cluster areas against the
//! reference's (the last setting) by the two-sample KS distance and the plateau + power-law
//! exponent, per load; and the first `r` realizations of each setting against all of them.
//! Inputs: per setting, its statistics then its clusters instances.

use polars::prelude::*;
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

use crate::store::inputs::Inputs;
use crate::store::table::{bool_column, f64_column, loads_of, str_column, u32_column, u64_column};

/// One compared setting.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Setting {
    /// Legend text, e.g. `L/λ_l = 4`.
    pub label: String,
    /// The value that varies (L/λ_l, λ_s/Δl, or the grid side n).
    pub value: f64,
    /// Its realizations (clusters inputs after its statistics).
    pub realizations: usize,
}

/// Largest KS distance to the reference (over loads) below which a setting, or a number of
/// realizations, counts as converged (Appendix B studies; docs/SIZES.md).
pub const CONVERGENCE_KS_TOLERANCE: f64 = 0.05;
/// Exponent compared between settings: the plateau + power-law fit over the whole
/// distribution (the free-`x_min` tail fit of λ_l/λ_s = 8 surfaces lands in the cut-off).
pub const CONVERGENCE_ESTIMATOR: crate::powerlaw::Estimator =
    crate::powerlaw::Estimator::DiscretePlateauPowerLaw;

/// Cluster areas (A/λ_s², percolating clusters left out as in the statistics stage) of one
/// study: `[realization][load]`, and the loads `(load_index, W/W0)`.
type StudyAreas = (Vec<Vec<Vec<f64>>>, Vec<(u32, f64)>);

/// Inputs `first` (the setting's statistics) and `first + 1 ..= first + realizations` (its
/// clusters instances).
fn study_areas(inputs: &Inputs, first: usize, realizations: usize) -> anyhow::Result<StudyAreas> {
    let loads = loads_of(&inputs.table(first, "statistics", "loads.parquet")?)?;
    let mut out = Vec::new();
    for r in 0..realizations {
        let df = inputs.table(first + 1 + r, "clusters", "clusters.parquet")?;
        let idx = u32_column(&df, "load_index")?;
        let area = f64_column(&df, "area_over_ls2")?;
        let perc = bool_column(&df, "percolating")?;
        let mut per_load = vec![Vec::new(); loads.len()];
        for i in 0..area.len() {
            if perc[i] {
                continue;
            }
            if let Some(l) = loads.iter().position(|l| Some(l.0) == idx[i]) {
                per_load[l].push(area[i]);
            }
        }
        out.push(per_load);
    }
    Ok((out, loads))
}

/// One row of the convergence table.
#[derive(Debug, Clone, PartialEq)]
pub struct ConvergenceRow {
    /// `setting` (against the reference) or `realizations` (first r against all).
    pub kind: String,
    /// The setting's label.
    pub study: String,
    pub setting: f64,
    pub realizations: u32,
    pub load_index: u32,
    pub w_over_w0: f64,
    pub n_clusters: u64,
    pub n_reference: u64,
    pub ks: f64,
    pub critical: f64,
    pub alpha: Option<f64>,
    pub alpha_reference: Option<f64>,
}

/// The KS and exponent comparisons of a settings audit.
pub struct ConvergenceTable {
    pub rows: Vec<ConvergenceRow>,
}

impl ConvergenceTable {
    pub fn frame(&self) -> anyhow::Result<DataFrame> {
        let r = &self.rows;
        let col_f = |name: &str, f: &dyn Fn(&ConvergenceRow) -> f64| {
            Column::new(name.into(), r.iter().map(f).collect::<Vec<f64>>())
        };
        let col_o = |name: &str, f: &dyn Fn(&ConvergenceRow) -> Option<f64>| {
            Column::new(name.into(), r.iter().map(f).collect::<Vec<Option<f64>>>())
        };
        Ok(DataFrame::new(
            r.len(),
            vec![
                Column::new(
                    "kind".into(),
                    r.iter().map(|x| x.kind.as_str()).collect::<Vec<_>>(),
                ),
                Column::new(
                    "study".into(),
                    r.iter().map(|x| x.study.as_str()).collect::<Vec<_>>(),
                ),
                col_f("setting", &|x| x.setting),
                Column::new(
                    "realizations".into(),
                    r.iter().map(|x| x.realizations).collect::<Vec<u32>>(),
                ),
                Column::new(
                    "load_index".into(),
                    r.iter().map(|x| x.load_index).collect::<Vec<u32>>(),
                ),
                col_f("w_over_w0", &|x| x.w_over_w0),
                Column::new(
                    "n_clusters".into(),
                    r.iter().map(|x| x.n_clusters).collect::<Vec<u64>>(),
                ),
                Column::new(
                    "n_clusters_reference".into(),
                    r.iter().map(|x| x.n_reference).collect::<Vec<u64>>(),
                ),
                col_f("ks_distance", &|x| x.ks),
                col_f("ks_critical_95", &|x| x.critical),
                col_o("alpha", &|x| x.alpha),
                col_o("alpha_reference", &|x| x.alpha_reference),
                col_o(
                    "alpha_difference",
                    &|x| match (x.alpha, x.alpha_reference) {
                        (Some(a), Some(b)) => Some(a - b),
                        _ => None,
                    },
                ),
                Column::new(
                    "alpha_estimator".into(),
                    vec![CONVERGENCE_ESTIMATOR.name(); r.len()],
                ),
            ],
        )?)
    }

    /// Read back a table written by [`Self::frame`].
    pub fn from_frame(df: &DataFrame) -> anyhow::Result<Self> {
        let kind = str_column(df, "kind")?;
        let study = str_column(df, "study")?;
        let setting = f64_column(df, "setting")?;
        let realizations = u32_column(df, "realizations")?;
        let load_index = u32_column(df, "load_index")?;
        let w = f64_column(df, "w_over_w0")?;
        let n = u64_column(df, "n_clusters")?;
        let n_ref = u64_column(df, "n_clusters_reference")?;
        let ks = f64_column(df, "ks_distance")?;
        let critical = f64_column(df, "ks_critical_95")?;
        let alpha = f64_column(df, "alpha")?;
        let alpha_ref = f64_column(df, "alpha_reference")?;
        let finite = |v: f64| v.is_finite().then_some(v);
        let rows = (0..df.height())
            .map(|i| ConvergenceRow {
                kind: kind[i].clone(),
                study: study[i].clone(),
                setting: setting[i],
                realizations: realizations[i].unwrap_or(0),
                load_index: load_index[i].unwrap_or(0),
                w_over_w0: w[i],
                n_clusters: n[i],
                n_reference: n_ref[i],
                ks: ks[i],
                critical: critical[i],
                alpha: finite(alpha[i]),
                alpha_reference: finite(alpha_ref[i]),
            })
            .collect();
        Ok(Self { rows })
    }

    /// Largest KS distance over loads of the rows of `kind`, per abscissa `pick(row)` (rows
    /// where it is `None` left out), in increasing abscissa.
    pub fn max_ks(
        &self,
        kind: &str,
        pick: &dyn Fn(&ConvergenceRow) -> Option<f64>,
    ) -> Vec<(f64, f64)> {
        let mut m: Vec<(f64, f64)> = Vec::new();
        for r in self.rows.iter().filter(|r| r.kind == kind) {
            let Some(x) = pick(r) else { continue };
            match m.iter_mut().find(|e| e.0 == x) {
                Some(e) => e.1 = e.1.max(r.ks),
                None => m.push((x, r.ks)),
            }
        }
        m.sort_by(|a, b| a.0.total_cmp(&b.0));
        m
    }

    /// The realization curve of one setting: largest KS over loads against `r`.
    pub fn max_ks_by_realizations(&self, setting: f64) -> Vec<(f64, f64)> {
        self.max_ks("realizations", &|r| {
            (r.setting == setting).then_some(r.realizations as f64)
        })
    }

    /// The smallest setting whose KS distance to the finest is within the tolerance at every
    /// load, and per setting the smallest number of realizations whose pooled ensemble is
    /// within the tolerance of the full one at every load.
    fn choice(&self) -> Value {
        let settings = self.max_ks("setting", &|r| Some(r.setting));
        // The smallest value from which every larger one is within the tolerance.
        let first_converged = |curve: &[(f64, f64)]| {
            (0..curve.len())
                .find(|&i| curve[i..].iter().all(|e| e.1 <= CONVERGENCE_KS_TOLERANCE))
                .map(|i| curve[i].0)
        };
        let chosen_setting = first_converged(&settings);
        let mut per_setting = serde_json::Map::new();
        let mut values: Vec<f64> = settings.iter().map(|e| e.0).collect();
        values.dedup();
        for s in values {
            let chosen = first_converged(&self.max_ks_by_realizations(s)).map(|r| r as u32);
            per_setting.insert(format!("{s}"), json!(chosen));
        }
        json!({
            "tolerance": CONVERGENCE_KS_TOLERANCE,
            "alpha_estimator": CONVERGENCE_ESTIMATOR.name(),
            "max_ks_by_setting": settings,
            "smallest_converged_setting": chosen_setting,
            "smallest_converged_realizations_by_setting": per_setting,
        })
    }
}

/// KS distance and exponent difference of each setting to the finest (last) setting per load,
/// and of the first `r` realizations of each setting to all of them.
fn convergence_table(inputs: &Inputs, settings: &[Setting]) -> anyhow::Result<ConvergenceTable> {
    let mut data = Vec::new();
    let mut first = 0;
    for s in settings {
        let (areas, loads) = study_areas(inputs, first, s.realizations)?;
        let alpha = inputs.table(first, "statistics", "alpha.parquet")?;
        first += 1 + s.realizations;
        let est = str_column(&alpha, "estimator")?;
        let a = f64_column(&alpha, "alpha")?;
        let idx = u32_column(&alpha, "load_index")?;
        let alpha_at = |l: u32| {
            (0..a.len())
                .find(|&i| idx[i] == Some(l) && est[i] == CONVERGENCE_ESTIMATOR.name())
                .map(|i| a[i])
                .filter(|v| v.is_finite())
        };
        let alphas: Vec<Option<f64>> = loads.iter().map(|l| alpha_at(l.0)).collect();
        data.push((areas, loads, alphas));
    }
    let pooled = |areas: &[Vec<Vec<f64>>], r: usize, l: usize| -> Vec<f64> {
        areas[..r]
            .iter()
            .flat_map(|x| x[l].iter().copied())
            .collect()
    };
    let mut rows = Vec::new();
    let Some((ref_areas, ref_loads, ref_alpha)) = data.last() else {
        return Ok(ConvergenceTable { rows });
    };
    for (s, (areas, loads, alphas)) in settings.iter().zip(&data) {
        let setting = s.value;
        for (l, &(load_index, w)) in loads.iter().enumerate() {
            let all = pooled(areas, areas.len(), l);
            if let Some(rl) = ref_loads.iter().position(|x| (x.1 - w).abs() <= 1e-12 * w) {
                let reference = pooled(ref_areas, ref_areas.len(), rl);
                rows.push(ConvergenceRow {
                    kind: "setting".into(),
                    study: s.label.clone(),
                    setting,
                    realizations: areas.len() as u32,
                    load_index,
                    w_over_w0: w,
                    n_clusters: all.len() as u64,
                    n_reference: reference.len() as u64,
                    ks: crate::statistics::ks_two_sample(&all, &reference),
                    critical: crate::statistics::ks_critical_95(all.len(), reference.len()),
                    alpha: alphas[l],
                    alpha_reference: ref_alpha[rl],
                });
            }
            for r in 1..=areas.len() {
                let part = pooled(areas, r, l);
                rows.push(ConvergenceRow {
                    kind: "realizations".into(),
                    study: s.label.clone(),
                    setting,
                    realizations: r as u32,
                    load_index,
                    w_over_w0: w,
                    n_clusters: part.len() as u64,
                    n_reference: all.len() as u64,
                    ks: crate::statistics::ks_two_sample(&part, &all),
                    critical: crate::statistics::ks_critical_95(part.len(), all.len()),
                    alpha: None,
                    alpha_reference: None,
                });
            }
        }
    }
    Ok(ConvergenceTable { rows })
}

impl ConvergenceTable {
    /// The rows comparing setting `label` to the reference, by load.
    pub fn setting_rows(&self, label: &str) -> Vec<&ConvergenceRow> {
        let mut rows: Vec<&ConvergenceRow> = self
            .rows
            .iter()
            .filter(|r| r.kind == "setting" && r.study == label)
            .collect();
        rows.sort_by(|a, b| a.w_over_w0.total_cmp(&b.w_over_w0));
        rows
    }

    /// Per setting but the reference: its largest KS distance over loads and the loads within
    /// the tolerance.
    fn summary(&self, settings: &[Setting]) -> Vec<Value> {
        let candidates = &settings[..settings.len().saturating_sub(1)];
        candidates
            .iter()
            .map(|s| {
                let rows = self.setting_rows(&s.label);
                let max_ks = rows.iter().map(|r| r.ks).fold(0.0, f64::max);
                json!({
                    "setting": s.label,
                    "value": s.value,
                    "realizations": s.realizations,
                    "max_ks_over_loads": max_ks,
                    "ks_by_load": rows.iter().map(|r| (r.w_over_w0, r.ks)).collect::<Vec<_>>(),
                    "ks_critical_95_by_load": rows.iter().map(|r| (r.w_over_w0, r.critical)).collect::<Vec<_>>(),
                    "within_tolerance": !rows.is_empty() && max_ks <= CONVERGENCE_KS_TOLERANCE,
                    "loads_within_tolerance": rows
                        .iter()
                        .filter(|r| r.ks <= CONVERGENCE_KS_TOLERANCE)
                        .map(|r| r.w_over_w0)
                        .collect::<Vec<_>>(),
                    "below_critical_at_every_load": !rows.is_empty()
                        && rows.iter().all(|r| r.ks <= r.critical),
                })
            })
            .collect()
    }
}

/// The audit's table and results.
pub(super) fn settings(
    inputs: &Inputs,
    settings: &[Setting],
) -> anyhow::Result<(DataFrame, Value)> {
    anyhow::ensure!(
        !settings.is_empty(),
        "a settings audit needs at least one setting"
    );
    let expected: usize = settings.iter().map(|s| 1 + s.realizations).sum();
    anyhow::ensure!(
        inputs.len() == expected,
        "the settings audit lists {expected} inputs but was given {}",
        inputs.len()
    );
    let table = convergence_table(inputs, settings)?;
    let mut result = table.choice();
    result["reference"] = json!(settings.last().map(|s| s.label.clone()));
    result["settings"] = json!(table.summary(settings));
    Ok((table.frame()?, result))
}
