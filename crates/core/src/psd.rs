//! The radially averaged power spectral density of a measured (non-periodic) map, as
//! SurfaceTopography computes it, and the self-affine fit of it (H, λ_l, λ_s).
//!
//! `C(q) = |Δx Δy Σ h_ij w_ij e^{−i q·r_ij}|² / (L_x L_y)` (m⁴ for heights in metres), with
//! the radial Hann window `w = (1 + cos(π r / r_max))/2` for `r < r_max = min(L_x, L_y)/2`,
//! `r` measured from node `(rows/2, cols/2)` (integer division), scaled so that
//! `⟨w²⟩ = 1`; averaged over the wavevectors `|q|` in each bin of `edges`, up to the
//! smaller Nyquist wavevector `π min(1/Δx, 1/Δy)`. Wavevectors are angular (rad/m).

use rustfft::num_complex::Complex;
use rustfft::FftPlanner;

use crate::topography::Topography;

/// One bin of the radial average.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct PsdBin {
    /// The bin's edges (rad/m).
    pub q_low: f64,
    pub q_high: f64,
    /// The mean `|q|` of the wavevectors in the bin (rad/m).
    pub q_mean: f64,
    /// The mean `C` over them (m⁴).
    pub c: f64,
    /// How many wavevectors.
    pub count: usize,
}

/// Logarithmic bin edges, `per_decade` per decade, from half a bin below the map's
/// fundamental `2π/max(L)` (so that no edge falls on the lattice of wavevectors along an
/// axis, `2πk/L` with k a power of ten) to past the smaller Nyquist wavevector.
pub fn log_edges(map: &Topography, per_decade: usize) -> Vec<f64> {
    let (lx, ly) = (map.cols as f64 * map.dx, map.rows as f64 * map.dy);
    let lo = 2.0 * std::f64::consts::PI / lx.max(ly) * 10f64.powf(-0.5 / per_decade as f64);
    let hi = std::f64::consts::PI * (1.0 / map.dx).min(1.0 / map.dy);
    let steps = ((hi / lo).log10() * per_decade as f64).ceil().max(1.0) as usize;
    (0..=steps)
        .map(|k| lo * 10f64.powf(k as f64 / per_decade as f64))
        .collect()
}

/// The radially averaged PSD of `map` (no missing point) over the bins of `edges`
/// (ascending); empty bins are left out.
pub fn radial_psd(map: &Topography, edges: &[f64]) -> Vec<PsdBin> {
    let (rows, cols, dx, dy) = (map.rows, map.cols, map.dx, map.dy);
    let (lx, ly) = (cols as f64 * dx, rows as f64 * dy);
    let r_max = 0.5 * lx.min(ly);
    let window: Vec<f64> = (0..rows * cols)
        .map(|k| {
            let x = ((k % cols) as f64 - (cols / 2) as f64) * dx;
            let y = ((k / cols) as f64 - (rows / 2) as f64) * dy;
            let r = x.hypot(y);
            if r > r_max {
                0.0
            } else {
                0.5 + 0.5 * (std::f64::consts::PI * r / r_max).cos()
            }
        })
        .collect();
    let norm = ((rows * cols) as f64 / window.iter().map(|w| w * w).sum::<f64>()).sqrt();
    let mut field: Vec<Complex<f64>> = map
        .heights
        .iter()
        .zip(&window)
        .map(|(h, w)| Complex::new(h * w * norm, 0.0))
        .collect();
    let mut planner = FftPlanner::new();
    let along_x = planner.plan_fft_forward(cols);
    for row in field.chunks_exact_mut(cols) {
        along_x.process(row);
    }
    let along_y = planner.plan_fft_forward(rows);
    let mut column = vec![Complex::new(0.0, 0.0); rows];
    for c in 0..cols {
        for r in 0..rows {
            column[r] = field[r * cols + c];
        }
        along_y.process(&mut column);
        for r in 0..rows {
            field[r * cols + c] = column[r];
        }
    }
    let q_max = std::f64::consts::PI * (1.0 / dx).min(1.0 / dy);
    let bins = edges.len().saturating_sub(1);
    let (mut sum_c, mut sum_q, mut count) = (vec![0.0; bins], vec![0.0; bins], vec![0usize; bins]);
    let scale = (dx * dy) * (dx * dy) / (lx * ly);
    let wrapped = |k: usize, n: usize| {
        if k <= n / 2 {
            k as f64
        } else {
            k as f64 - n as f64
        }
    };
    for r in 0..rows {
        let qy = 2.0 * std::f64::consts::PI * wrapped(r, rows) / ly;
        for c in 0..cols {
            let qx = 2.0 * std::f64::consts::PI * wrapped(c, cols) / lx;
            let q = qx.hypot(qy);
            if q == 0.0 || q > q_max {
                continue;
            }
            let j = edges.partition_point(|&e| e <= q);
            if j == 0 || j > bins {
                continue;
            }
            sum_c[j - 1] += field[r * cols + c].norm_sqr() * scale;
            sum_q[j - 1] += q;
            count[j - 1] += 1;
        }
    }
    (0..bins)
        .filter(|&j| count[j] > 0)
        .map(|j| PsdBin {
            q_low: edges[j],
            q_high: edges[j + 1],
            q_mean: sum_q[j] / count[j] as f64,
            c: sum_c[j] / count[j] as f64,
            count: count[j],
        })
        .collect()
}

/// The self-affine fit of a PSD: `C ∝ q^{−2(1+H)}` between `2π/λ_l` and `2π/λ_s`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SelfAffineFit {
    pub hurst: f64,
    /// The largest and smallest wavelengths of the fitted range (m).
    pub lambda_l_m: f64,
    pub lambda_s_m: f64,
    /// The largest |log10 C − fit| over the range.
    pub max_log10_residual: f64,
    pub bins: usize,
}

/// The widest run of at least `MIN_BINS` consecutive bins on which one straight line in
/// log q – log C stays within a factor 2 of every bin (|residual| ≤ log10 2), fitted by
/// least squares; the widest found first from the low-q end on ties. None if no run of
/// `MIN_BINS` bins is straight.
pub fn fit_self_affine(bins: &[PsdBin]) -> Option<SelfAffineFit> {
    fit_run(bins).map(|(fit, _, _)| fit)
}

/// [`fit_self_affine`], with where its run starts among the bins of positive power and how
/// many such bins there are.
fn fit_run(bins: &[PsdBin]) -> Option<(SelfAffineFit, usize, usize)> {
    const MIN_BINS: usize = 5;
    let pts: Vec<(f64, f64)> = bins
        .iter()
        .filter(|b| b.c > 0.0)
        .map(|b| (b.q_mean.log10(), b.c.log10()))
        .collect();
    let line = |s: &[(f64, f64)]| {
        let n = s.len() as f64;
        let (mx, my) = (
            s.iter().map(|p| p.0).sum::<f64>() / n,
            s.iter().map(|p| p.1).sum::<f64>() / n,
        );
        let sxx: f64 = s.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
        let sxy: f64 = s.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
        let slope = sxy / sxx;
        let worst = s
            .iter()
            .map(|p| (p.1 - (my + slope * (p.0 - mx))).abs())
            .fold(0.0f64, f64::max);
        (slope, worst)
    };
    for width in (MIN_BINS..=pts.len()).rev() {
        for start in 0..=pts.len() - width {
            let run = &pts[start..start + width];
            let (slope, worst) = line(run);
            if worst <= 2f64.log10() && slope < -2.0 {
                let tau = std::f64::consts::TAU;
                let fit = SelfAffineFit {
                    hurst: -slope / 2.0 - 1.0,
                    lambda_l_m: tau / 10f64.powf(run[0].0),
                    lambda_s_m: tau / 10f64.powf(run[width - 1].0),
                    max_log10_residual: worst,
                    bins: width,
                };
                return Some((fit, start, pts.len()));
            }
        }
    }
    None
}

/// What a measured spectrum resolves. The straightest power-law run of the PSD
/// ([`fit_self_affine`]) is a self-affine range only if its H lies in (0, 1); its ends are
/// λ_l and λ_s only where the spectrum rolls off beyond them: a run that reaches the last
/// bin (the pixel) shows no λ_s, one that starts at the first (the map) no λ_l. What is not
/// resolved is None, with the reason in `not_resolved`.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct Resolved {
    /// The straightest run's wavelengths, longest and shortest (m), when there is a run.
    pub run_lambda_long_m: Option<f64>,
    pub run_lambda_short_m: Option<f64>,
    /// The run's bins and its largest |log10 C − fit|.
    pub bins: usize,
    pub max_log10_residual: Option<f64>,
    /// The run's exponent read as H = −slope/2 − 1, whether or not it is in (0, 1).
    pub run_hurst: Option<f64>,
    pub hurst: Option<f64>,
    pub lambda_l_m: Option<f64>,
    pub lambda_s_m: Option<f64>,
    pub not_resolved: Vec<String>,
}

/// What `bins` resolve (see [`Resolved`]).
pub fn resolve(bins: &[PsdBin]) -> Resolved {
    let Some((fit, start, total)) = fit_run(bins) else {
        return Resolved {
            not_resolved: vec![
                "H, λ_l and λ_s: no run of 5 bins of the PSD follows a power law within a factor 2"
                    .into(),
            ],
            ..Resolved::default()
        };
    };
    let mut r = Resolved {
        run_lambda_long_m: Some(fit.lambda_l_m),
        run_lambda_short_m: Some(fit.lambda_s_m),
        bins: fit.bins,
        max_log10_residual: Some(fit.max_log10_residual),
        run_hurst: Some(fit.hurst),
        ..Resolved::default()
    };
    if !(fit.hurst > 0.0 && fit.hurst < 1.0) {
        r.not_resolved.push(format!(
            "H, λ_l and λ_s: the straightest run of the PSD ({} bins) falls as q^{:.2}, H = {:.2}, outside (0, 1): not a self-affine range (an instrument's smoothing or an unremoved form steepens a spectrum)",
            fit.bins,
            -2.0 * (1.0 + fit.hurst),
            fit.hurst
        ));
        return r;
    }
    r.hurst = Some(fit.hurst);
    if start == 0 {
        r.not_resolved.push(
            "λ_l: the power law starts at the map's longest wavelength; no roll-off shows within the map".into(),
        );
    } else {
        r.lambda_l_m = Some(fit.lambda_l_m);
    }
    if start + fit.bins == total {
        r.not_resolved.push(
            "λ_s: the power law runs to the pixel; no roll-off shows above it, so the roughness may continue below the pixel".into(),
        );
    } else {
        r.lambda_s_m = Some(fit.lambda_s_m);
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A single cosine of wavevector q0 along x on a periodic-compatible map with the
    /// window: the PSD peaks in the bin of q0, and Parseval holds for the windowed field,
    /// `⟨(h w)²⟩ = ∫ C d²q/(2π)² = Σ_q C/(Lx Ly)` (⟨w²⟩ = 1, and the cosine's ⟨h²⟩ is
    /// nearly ⟨(h w)²⟩ when the window varies slowly on its period).
    #[test]
    fn a_cosine_peaks_at_its_wavevector_and_parseval_holds() {
        let (rows, cols, d) = (64, 96, 1e-6);
        let k = 12.0;
        let heights: Vec<f64> = (0..rows * cols)
            .map(|i| 1e-7 * (std::f64::consts::TAU * k * (i % cols) as f64 / cols as f64).cos())
            .collect();
        let map = Topography::new(rows, cols, d, d, heights).unwrap();
        let edges = log_edges(&map, 10);
        let psd = radial_psd(&map, &edges);
        let q0 = std::f64::consts::TAU * k / (cols as f64 * d);
        let peak = psd.iter().max_by(|a, b| a.c.total_cmp(&b.c)).unwrap();
        assert!(
            peak.q_low <= q0 && q0 < peak.q_high,
            "{peak:?} against q0 {q0}"
        );
        let (lx, ly) = (cols as f64 * d, rows as f64 * d);
        let dq2 = 1.0 / (lx * ly);
        let total: f64 = psd.iter().map(|b| b.c * b.count as f64 * dq2).sum();
        // The window spreads some power beyond the Nyquist circle and below the first
        // edge; nearly all of it is inside for a cosine well inside the band.
        let mean_square = 0.5e-14;
        assert!(
            (total / mean_square - 1.0).abs() < 0.05,
            "{total} against {mean_square}"
        );
    }

    /// A PSD that is exactly self-affine between two wavevectors and falls steeply
    /// outside is fitted to its H and to those wavevectors within a bin.
    #[test]
    fn self_affine_fit_recovers_h_and_the_range() {
        let hurst = 0.7;
        let (ql, qs) = (1e4, 1e6);
        let bins: Vec<PsdBin> = (0..40)
            .map(|j| {
                let q = 1e3 * 10f64.powf(j as f64 / 10.0);
                let c = if q < ql {
                    ql.powf(-2.0 * (1.0 + hurst)) * 0.1
                } else if q > qs {
                    qs.powf(-2.0 * (1.0 + hurst)) * (q / qs).powi(-12)
                } else {
                    q.powf(-2.0 * (1.0 + hurst))
                };
                PsdBin {
                    q_low: q,
                    q_high: q,
                    q_mean: q,
                    c,
                    count: 1,
                }
            })
            .collect();
        let fit = fit_self_affine(&bins).unwrap();
        assert!((fit.hurst - hurst).abs() < 1e-9, "{fit:?}");
        let r = resolve(&bins);
        assert_eq!(
            (r.hurst, r.lambda_l_m, r.lambda_s_m),
            (Some(fit.hurst), Some(fit.lambda_l_m), Some(fit.lambda_s_m)),
            "{r:?}"
        );
        assert!(r.not_resolved.is_empty(), "{r:?}");
        // Cut at the roll-off: the power law runs to the last bin, λ_s is not resolved.
        let cut: Vec<PsdBin> = bins.iter().filter(|b| b.q_mean <= qs).cloned().collect();
        let r = resolve(&cut);
        assert_eq!((r.hurst, r.lambda_s_m), (Some(fit.hurst), None), "{r:?}");
        assert!(r.lambda_l_m.is_some() && r.not_resolved[0].starts_with("λ_s"));
        // The same run twice as steep: H = 2.4, not a self-affine range.
        let steep: Vec<PsdBin> = bins.iter().map(|b| PsdBin { c: b.c * b.c, ..*b }).collect();
        let r = resolve(&steep);
        assert_eq!(
            (r.hurst, r.lambda_l_m, r.lambda_s_m),
            (None, None, None),
            "{r:?}"
        );
        assert!(r.run_hurst.unwrap() > 1.0 && r.not_resolved[0].contains("outside (0, 1)"));
        let tau = std::f64::consts::TAU;
        assert!(
            (fit.lambda_l_m * ql / tau).log10().abs() <= 0.1 + 1e-12,
            "{fit:?}"
        );
        assert!(
            (fit.lambda_s_m * qs / tau).log10().abs() <= 0.1 + 1e-12,
            "{fit:?}"
        );
    }
}
