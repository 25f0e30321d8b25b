//! The statistics stage's job (its key) and what its tables are computed from: one study's
//! cluster areas and per-realization summaries.

use serde::{Deserialize, Serialize};

use crate::powerlaw;
use crate::statistics as stats;

/// Thresholds `A*/λ_s²` at which the statistics stage evaluates `K`, `𝒦` and the wear
/// rate: powers of two from 1/4 to 1024 (the paper's Fig. 2 uses `A* = 2 λ_s²`).
pub const A_STAR_OVER_LS2: [f64; 13] = [
    0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0, 128.0, 256.0, 512.0, 1024.0,
];
/// Logarithmic bins of the area PDF (paper Fig. 3).
pub const PDF_BINS: usize = 20;
/// Resamples of the realizations behind each interval of a refitted estimate (α, pooled K
/// and 𝒦).
pub const BOOTSTRAP_RESAMPLES: usize = 200;

/// One study's statistics. Inputs: its realizations' clusters instances, in order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StatisticsJob {
    #[serde(rename = "loads_w_over_w0")]
    pub loads: Vec<f64>,
    /// Grid side.
    pub n: usize,
    /// λ_s in grid spacings (areas per λ_s²).
    pub lambda_s_px: f64,
    /// Seed of the bootstrap resampling.
    pub seed: u64,
    /// Thresholds A*/λ_s² of `wear.parquet`.
    pub a_star_over_ls2: Vec<f64>,
    /// Logarithmic bins of the PDF.
    pub pdf_bins: usize,
    /// Bootstrap resamples of α's interval.
    pub bootstrap_resamples: usize,
    /// Fewest clusters in a fitted tail.
    pub min_tail: usize,
    /// Wear-volume factor ω of the wear rate (volume = ω A^(3/2)).
    pub omega: f64,
    /// A measured study's maps: rows × cols pixels each (`n` is 0). Absent (and not in the
    /// key) for the `n × n` grid.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub map_pixels: Option<u64>,
    /// The load indices at which α̂'s intervals (refitted over resampled realizations) and
    /// the tail's goodness of fit are computed: the loads the profile's figures show them
    /// at. `None` (and not in the key): every load. Elsewhere `alpha.parquet` holds the
    /// point estimates only, and says why.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub exponent_interval_loads: Option<Vec<u32>>,
}

impl StatisticsJob {
    /// The job of a study with the stage's standard grid of thresholds, bins and resamples.
    pub fn standard(loads: Vec<f64>, n: usize, lambda_s_px: f64, seed: u64) -> Self {
        Self {
            loads,
            n,
            lambda_s_px,
            seed,
            a_star_over_ls2: A_STAR_OVER_LS2.to_vec(),
            pdf_bins: PDF_BINS,
            bootstrap_resamples: BOOTSTRAP_RESAMPLES,
            min_tail: powerlaw::MIN_TAIL,
            omega: stats::OMEGA,
            map_pixels: None,
            exponent_interval_loads: None,
        }
    }

    /// Whether α̂'s interval and tests are computed at load `l`.
    pub fn exponent_interval_at(&self, l: usize) -> bool {
        self.exponent_interval_loads
            .as_ref()
            .is_none_or(|v| v.contains(&(l as u32)))
    }
}

/// Areas (pixels) of the non-percolating clusters and summary per realization and load.
pub(super) struct Sample {
    /// `[realization][load]` areas of the clusters that do not wrap around the box.
    pub(super) areas: Vec<Vec<Vec<u64>>>,
    /// `[realization][load]`: pixels in contact (all clusters), cluster count (all),
    /// largest area (all), percolating clusters.
    pub(super) contact_px: Vec<Vec<u64>>,
    pub(super) count: Vec<Vec<u64>>,
    pub(super) largest: Vec<Vec<u64>>,
    pub(super) percolating: Vec<Vec<u64>>,
}

/// What the tables of one study are computed from.
pub(super) struct Study<'a> {
    pub(super) job: &'a StatisticsJob,
    pub(super) s: Sample,
    /// `[load]`: the non-percolating cluster areas of every realization together.
    pub(super) pooled: Vec<Vec<u64>>,
    pub(super) ls2: f64,
    pub(super) pixels: f64,
    pub(super) loads: usize,
    pub(super) realizations: usize,
}
