//! Goodness of fit of the power law above `k_min` (Clauset, Shalizi & Newman 2009, §4.1):
//! the KS distance of the data to its fit against those of synthetic samples drawn from the
//! fit (the tail) and from the data themselves (below `k_min`), each refitted as the data
//! were (its own `k_min` by the KS scan, its own largest value as the cut-off). The p-value
//! is the share of synthetic samples that fit worse than the data; Clauset et al. reject
//! the power law when it is ≤ 0.1.

use rand::RngExt;
use rand_chacha::rand_core::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::fit::{checked_counts, fit_tail_at_max, FitError, PowerLawFit};

/// The widest fitted range `[k_min, k_max]` sampled from (its cumulative table is held in
/// memory: 8 bytes a value).
pub const MAX_SAMPLED_RANGE: u64 = 1 << 24;

/// Below this p-value the power law is rejected (Clauset et al. 2009).
pub const REJECT_AT: f64 = 0.1;

/// The p-value of the fit and how many synthetic samples it rests on.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct GoodnessOfFit {
    pub p_value: f64,
    pub samples: usize,
}

/// The p-value of `fit` (from [`fit_tail_at_max`] on `data`) by `samples` synthetic samples, seeded by `seed` (the same on any number of
/// threads). A synthetic sample that cannot be fitted counts as fitting worse.
pub fn goodness_of_fit(
    data: &[u64],
    fit: &PowerLawFit,
    samples: usize,
    seed: u64,
) -> Result<GoodnessOfFit, FitError> {
    let sorted = checked_counts(data)?;
    let (a, b) = (fit.lower as u64, fit.upper as u64);
    if !fit.upper.is_finite() || b < a || b - a > MAX_SAMPLED_RANGE {
        return Err(FitError::BadBounds {
            lower: fit.lower,
            upper: fit.upper,
        });
    }
    // Cumulative weights of k^(−α) on [a, b], relative to a^(−α).
    let la = (a as f64).ln();
    let mut cumulative = Vec::with_capacity((b - a + 1) as usize);
    let mut total = 0.0;
    for k in a..=b {
        total += (-fit.alpha * ((k as f64).ln() - la)).exp();
        cumulative.push(total);
    }
    let below = &sorted[..sorted.partition_point(|&k| k < a)];
    let n = sorted.len();
    let tail_share = 1.0 - below.len() as f64 / n as f64;
    let worse = (0..samples)
        .into_par_iter()
        .filter(|&i| {
            let mut rng = ChaCha8Rng::seed_from_u64(
                seed ^ (i as u64 + 1).wrapping_mul(0xD1B5_4A32_D192_ED03),
            );
            let synthetic: Vec<u64> = (0..n)
                .map(|_| {
                    if below.is_empty() || rng.random::<f64>() < tail_share {
                        let u = rng.random::<f64>() * total;
                        a + cumulative
                            .partition_point(|&c| c < u)
                            .min(cumulative.len() - 1) as u64
                    } else {
                        below[rng.random_range(0..below.len())]
                    }
                })
                .collect();
            fit_tail_at_max(&synthetic).map_or(true, |t| t.fit.ks_distance >= fit.ks_distance)
        })
        .count();
    Ok(GoodnessOfFit {
        p_value: worse as f64 / samples as f64,
        samples,
    })
}
