//! The figures stage: one figure family of the paper (or one audit's chart) drawn from the
//! tables of its inputs, as PNG, SVG and CSV (module [`crate::figures`]). A run copies the
//! figures of its profile to `figures/<profile>/` next to the data directory.

use std::path::Path;

use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::stage::Stage;
use crate::figures::{self as draw};
use crate::store::inputs::Inputs;

/// One study as a figure shows it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyRef {
    pub study: String,
    /// Legend text, e.g. `λ_l/λ_s = 128`.
    pub label: String,
    /// The value the figure varies (λ_l/λ_s, H, L/λ_l, λ_s/Δl or the grid side n).
    pub value: f64,
    /// λ_s in grid spacings (areas per λ_s²).
    pub lambda_s_px: f64,
}

impl StudyRef {
    /// `label` with the study's name appended in brackets (escaped for label markup), to
    /// tell apart two studies that would share a label.
    pub fn named(&self) -> String {
        format!(
            "{} [{}]",
            self.label,
            crate::figures::plot::text::escape(&self.study)
        )
    }
}

pub struct Figures;

/// The threshold of Fig. 2: `A* = 2 λ_s²`.
pub const FIG2_A_STAR_OVER_LS2: f64 = 2.0;

/// Thresholds `A*/λ_l²` of the spectrum family's physical K panel: a fixed area on the scale
/// of the largest wavelength, which a wider spectrum holds fixed while λ_s shrinks.
pub const SPECTRUM_A_STAR_OVER_LL2: [f64; 3] = [1.0 / 512.0, 1.0 / 128.0, 1.0 / 32.0];

/// What a figures instance draws; the inputs each variant reads are listed with it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "draw", rename_all = "snake_case", deny_unknown_fields)]
pub enum FigureJob {
    /// Fig. 6. Input: the model curves (analytic).
    Fig6,
    /// Figs. 2a–d at the loads `(index, W/W0)` whose pressure the sweep keeps. Inputs: the
    /// surface and contact sweep of realization 0.
    Fig2Maps {
        maps: Vec<(usize, f64)>,
        lambda_s_px: f64,
        a_star_over_ls2: f64,
        /// A measured study's map: rows × cols in metres, clusters not wrapped. Absent
        /// (and not in the key) for a generated surface.
        #[serde(default, skip_serializing_if = "std::ops::Not::not")]
        measured: bool,
    },
    /// Figs. 2e–f with the loads of 2b–d marked, and the realization audit's chart. Inputs:
    /// the statistics, the audit, the analytic fit.
    Fig2ef { marked_loads: Vec<f64> },
    /// Figs. 3 and 4a. Inputs: the statistics of `ratios`, then of `hurst`.
    Fig3Fig4a {
        ratios: Vec<StudyRef>,
        hurst: Vec<StudyRef>,
        loads: Vec<f64>,
        inset_load: f64,
    },
    /// Figs. 4b, 5a, 5b of a study of spectrum `lambda_l_over_lambda_s` (0 for a measured
    /// study, which `measured` then names). Inputs: the statistics, the fitted model.
    Fig45 {
        lambda_l_over_lambda_s: f64,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        measured: Option<String>,
    },
    /// Fig. B.1 (`b1`) or B.2 and the convergence chart. Inputs: each setting's statistics,
    /// then the settings audit.
    Appendix {
        figure: String,
        quantity: String,
        b1: bool,
        settings: Vec<StudyRef>,
    },
    /// Grid sizes against the largest. Inputs: each setting's statistics, then the audit.
    Convergence {
        figure: String,
        hurst: f64,
        settings: Vec<StudyRef>,
    },
    /// The load-resolution chart. Input: the audit.
    LoadResolution { figure: String },
    /// The plastic family: α̂ against 1/𝓗 at `loads` (the `settings`' values), and K, 𝒦 and
    /// the saturated fraction over each sweep. Inputs: each setting's statistics, then each
    /// setting's contact sweeps (`realizations` of them per setting).
    Plastic {
        settings: Vec<StudyRef>,
        realizations: Vec<usize>,
        loads: Vec<f64>,
    },
    /// Spectra of several widths (`settings`' value: λ_l/λ_s, increasing): α̂ and the
    /// interval's upper end at `loads`, K and 𝒦 at `plateau_w_over_w0` at the thresholds
    /// `a_star_over_ls2` and (K) `a_star_over_ll2`. Inputs: each setting's statistics, then
    /// each setting's fitted model.
    Spectrum {
        settings: Vec<StudyRef>,
        loads: Vec<f64>,
        plateau_w_over_w0: f64,
        a_star_over_ls2: Vec<f64>,
        a_star_over_ll2: Vec<f64>,
    },
}

impl Stage for Figures {
    const NAME: &'static str = "figures";
    const VERSION: u32 = 12;
    type Job = FigureJob;

    fn compute(job: &FigureJob, inputs: &Inputs, dir: &Path) -> anyhow::Result<Value> {
        let drawn = match job {
            FigureJob::Fig6 => draw::fig45::fig6(inputs)?,
            FigureJob::Fig2Maps {
                maps,
                lambda_s_px,
                a_star_over_ls2,
                measured,
            } => draw::fig2::fig2_maps(inputs, maps, *lambda_s_px, *a_star_over_ls2, *measured)?,
            FigureJob::Fig2ef { marked_loads } => draw::fig2::fig2ef(inputs, marked_loads)?,
            FigureJob::Fig3Fig4a {
                ratios,
                hurst,
                loads,
                inset_load,
            } => draw::fig3_4a::fig34a(inputs, ratios, hurst, loads, *inset_load)?,
            FigureJob::Fig45 {
                lambda_l_over_lambda_s,
                measured,
            } => {
                let surface = match measured {
                    Some(name) => name.clone(),
                    None => format!(
                        "λ_l/λ_s = {}",
                        crate::figures::plot::number(*lambda_l_over_lambda_s)
                    ),
                };
                draw::fig45::fig45(inputs, &surface)?
            }
            FigureJob::Appendix {
                figure,
                quantity,
                b1,
                settings,
            } => draw::appendix::appendix(inputs, figure, quantity, *b1, settings)?,
            FigureJob::Convergence {
                figure,
                hurst,
                settings,
            } => draw::convergence::convergence(inputs, figure, *hurst, settings)?,
            FigureJob::LoadResolution { figure } => draw::fig45::load_resolution(inputs, figure)?,
            FigureJob::Plastic {
                settings,
                realizations,
                loads,
            } => draw::plastic::plastic(inputs, settings, realizations, loads)?,
            FigureJob::Spectrum {
                settings,
                loads,
                plateau_w_over_w0,
                a_star_over_ls2,
                a_star_over_ll2,
            } => draw::spectrum::spectrum(
                inputs,
                &draw::spectrum::SpectrumScene {
                    settings,
                    loads,
                    plateau_w_over_w0: *plateau_w_over_w0,
                    a_star_over_ls2,
                    a_star_over_ll2,
                },
            )?,
        };
        draw::write(drawn, dir)
    }
}
