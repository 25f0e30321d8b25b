//! The convergence figure of a family of grid sizes against the largest (the reference):
//! KS distance and exponent difference against the load, ensemble CCDFs at the largest load,
//! and the realization curves, all from the settings audit.

use super::appendix::push_convergence_curves;
use super::common::{tolerance_line, CcdfTable, Drawn};
use super::plot::{Layout, LinePlot, Marker, Panels, Series, YAxis};
use crate::stages::audits::{ConvergenceTable, CONVERGENCE_KS_TOLERANCE, TABLE};
use crate::stages::figures::StudyRef;
use crate::store::inputs::Inputs;

/// The λ_l/λ_s = 128 convergence figure: KS distance and exponent difference of each
/// setting's pooled cluster areas to the reference's (the last setting, the sizes the
/// Appendix B rule asks for) against W/W0; the ensemble CCDFs at the largest load; the KS
/// distance of the first r realizations of each setting to all of them. Also the table and,
/// per setting, the largest KS distance over loads and whether it is within
/// [`CONVERGENCE_KS_TOLERANCE`].
///
/// Inputs: each setting's statistics, then the settings audit.
pub fn convergence(
    inputs: &Inputs,
    name: &str,
    hurst: f64,
    settings: &[StudyRef],
) -> anyhow::Result<Vec<(String, Drawn)>> {
    anyhow::ensure!(
        settings.len() >= 2,
        "{name}: needs a setting and a reference"
    );
    let audit = settings.len();
    let frame = inputs.table(audit, "audits", TABLE)?;
    let table = ConvergenceTable::from_frame(&frame)?;
    let reference = settings.last().expect("two settings or more");
    let candidates = &settings[..settings.len() - 1];
    let setting_rows = |label: &str| table.setting_rows(label);
    let title = format!("λ_l/λ_s = 128, H = {hurst}");
    let mut ks = LinePlot::new(
        format!("{title}: KS distance to {}", reference.label),
        "W/W_0",
        "KS distance (pooled A/λ_s^2)",
        true,
        YAxis::Linear,
    );
    let mut da = LinePlot::new(
        format!("{title}: α − α(reference)"),
        "W/W_0",
        "α − α(reference), plateau + power-law MLE",
        true,
        YAxis::Linear,
    );
    for (c, s) in candidates.iter().enumerate() {
        let rows = setting_rows(&s.label);
        let critical = if c == 0 { "95 % critical values" } else { "" };
        push_convergence_curves(
            &mut ks,
            &mut da,
            &s.label,
            critical,
            &rows,
            |r| r.w_over_w0,
            c,
        );
    }
    let loads: Vec<f64> = setting_rows(&candidates[0].label)
        .iter()
        .map(|r| r.w_over_w0)
        .collect();
    if let (Some(&lo), Some(&hi)) = (loads.first(), loads.last()) {
        // One load (profile convergence128_low): a line of zero length would not show.
        let (lo, hi) = if lo < hi {
            (lo, hi)
        } else {
            (lo / 2.0, hi * 2.0)
        };
        ks.series
            .push(tolerance_line(CONVERGENCE_KS_TOLERANCE, lo, hi));
    }
    // Ensemble-mean CCDFs at the largest load, reference in black.
    let tables = (0..settings.len())
        .map(|i| CcdfTable::read(inputs, i))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let mut ccdf = LinePlot::new(
        format!("{title}: ensemble CCDF at the largest load"),
        "A/λ_s^2",
        "P(A > a), ensemble mean",
        true,
        YAxis::Log,
    );
    for (c, (s, t)) in settings.iter().zip(&tables).enumerate() {
        let Some(&(load_index, w)) = t.loads().last() else {
            continue;
        };
        let is_reference = c + 1 == settings.len();
        ccdf.series.push(Series {
            rgb: is_reference.then_some((0, 0, 0)),
            study: Some(s.study.clone()),
            w_over_w0: Some(w),
            ..Series::line(
                format!("{}, W/W_0 = {w:.3}", s.label),
                t.curve(load_index, None, true),
                c,
            )
        });
    }
    let mut real = LinePlot::new(
        format!("{title}: first r realizations vs all"),
        "realizations r",
        "max KS distance over loads",
        false,
        YAxis::Linear,
    );
    real.x_integer = true;
    for (c, s) in settings.iter().enumerate() {
        let by_r = table.max_ks("realizations", &|r| {
            (r.study == s.label).then_some(r.realizations as f64)
        });
        real.series.push(Series {
            marker: Some(Marker::ALL[c % Marker::ALL.len()]),
            ..Series::line(s.label.clone(), by_r, c)
        });
    }
    Ok(vec![
        (
            name.into(),
            Drawn::Panels(Panels {
                plots: vec![ks, da, ccdf, real],
                layout: Layout::Grid { columns: 2 },
            }),
        ),
        (name.into(), Drawn::Table(frame)),
        (
            "convergence".into(),
            Drawn::Result(inputs.of(audit, "audits")?.results.clone()),
        ),
    ])
}
