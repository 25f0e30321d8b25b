//! Cluster-area statistics of one load: PDF in logarithmic bins, exact CCDF, the wear
//! coefficients `K` (eq. 5) and `𝒦` (eq. 7), the wear rate (eq. 6), and ensemble means
//! with confidence bands. Areas are pixel counts here; callers convert to `A/λ_s²`.
//!
//! Definitions (docs/CONVENTIONS.md):
//! - `K(A*) = P(A > A*)`, the fraction of clusters larger than `A*` (Archard's
//!   interpretation, eq. 5, the CCDF);
//! - `𝒦(A*) = Σ_{A_i > A*} A_i / Σ A_i`, the fraction of the contact area in clusters
//!   larger than `A*` (eq. 7);
//! - wear rate `R(A*) = ω Σ_{A_i > A*} A_i` with `ω = 1/3` (eq. 6, hemispherical
//!   particles), an area (volume per sliding distance).
//! - PDF of areas in logarithmic bins: bin `[e_j, e_{j+1})` holds the integer areas
//!   `⌈e_j⌉ … ⌈e_{j+1}⌉ − 1`; its density is `count / (N · m_j)` with `m_j` the number of
//!   integers in the bin (the discrete-aware width), so it estimates `P(A = k)` per pixel
//!   of area and integrates to 1 over all bins. Bins without an integer are dropped.

/// Shape factor of the wear rate (hemispherical wear particles).
pub const OMEGA: f64 = 1.0 / 3.0;

/// The wear measures of one sample of cluster areas at a threshold `A*`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WearAt {
    /// `K = P(A > A*)`.
    pub k_archard: f64,
    /// `𝒦 = A_c*/A_c`.
    pub k_upscaled: f64,
    /// `A_c* = Σ_{A > A*} A` (pixels).
    pub area_above_px: f64,
}

/// `K`, `𝒦` and `A_c*` of the areas (pixels) at threshold `a_star_px`. An empty sample
/// gives zeros (no cluster: no wear).
pub fn wear_at(areas_px: &[u64], a_star_px: f64) -> WearAt {
    let total: f64 = areas_px.iter().map(|&a| a as f64).sum();
    let (mut count, mut above) = (0usize, 0.0f64);
    for &a in areas_px {
        if a as f64 > a_star_px {
            count += 1;
            above += a as f64;
        }
    }
    if areas_px.is_empty() {
        return WearAt {
            k_archard: 0.0,
            k_upscaled: 0.0,
            area_above_px: 0.0,
        };
    }
    WearAt {
        k_archard: count as f64 / areas_px.len() as f64,
        k_upscaled: if total > 0.0 { above / total } else { 0.0 },
        area_above_px: above,
    }
}

/// Exact CCDF steps: for each distinct area `a` (ascending), `P(A > a)`.
pub fn ccdf_steps(areas_px: &[u64]) -> Vec<(u64, f64)> {
    let mut sorted = areas_px.to_vec();
    sorted.sort_unstable();
    let n = sorted.len() as f64;
    let mut out = Vec::new();
    let mut i = 0;
    while i < sorted.len() {
        let a = sorted[i];
        let j = i + sorted[i..].partition_point(|&v| v == a);
        out.push((a, (sorted.len() - j) as f64 / n));
        i = j;
    }
    out
}

/// `count` logarithmic bin edges from `lo` to `hi` (> lo > 0), `count + 1` values.
pub fn log_edges(lo: f64, hi: f64, count: usize) -> Vec<f64> {
    let (a, b) = (lo.ln(), hi.ln());
    let mut edges: Vec<f64> = (0..=count)
        .map(|i| (a + (b - a) * i as f64 / count as f64).exp())
        .collect();
    // exp(ln x) may miss x by an ulp; the end edges are exact.
    edges[0] = lo;
    edges[count] = hi;
    edges
}

/// A K, 𝒦 or wear rate resting on fewer clusters above A* than this (pooled over
/// realizations) is tentative: drawn hollow, flagged in the report, and no verdict rests on
/// it (so is one whose 95 % interval reaches 0).
pub const TENTATIVE_BELOW_CLUSTERS: u64 = 10;

/// Index of the positive value of `values` nearest to `target` (> 0) in log scale,
/// i.e. minimising `|ln(v / target)|` (the first on a tie); `None` if no value is positive.
/// Used wherever a requested load is matched to a sweep's loads.
pub fn nearest_in_log(values: &[f64], target: f64) -> Option<usize> {
    values
        .iter()
        .enumerate()
        .filter(|(_, v)| **v > 0.0)
        .min_by(|a, b| {
            let da = (a.1 / target).ln().abs();
            let db = (b.1 / target).ln().abs();
            da.total_cmp(&db)
        })
        .map(|(i, _)| i)
}

/// One bin of the area PDF.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PdfBin {
    pub lower_px: f64,
    pub upper_px: f64,
    /// Integers in the bin (its discrete width).
    pub width_px: u64,
    /// Geometric centre `sqrt(lower · upper)`.
    pub centre_px: f64,
    pub count: u64,
    /// `count / (N · width)`.
    pub density_per_px: f64,
}

/// PDF of the areas in the bins given by `edges` (the last bin includes its upper edge).
pub fn log_binned_pdf(areas_px: &[u64], edges: &[f64]) -> Vec<PdfBin> {
    let n = areas_px.len() as f64;
    let mut out = Vec::new();
    for (j, w) in edges.windows(2).enumerate() {
        let last = j + 2 == edges.len();
        let first_int = w[0].ceil() as u64;
        let end_int = if last {
            w[1].floor() as u64 + 1
        } else {
            w[1].ceil() as u64
        };
        if end_int <= first_int {
            continue;
        }
        let count = areas_px
            .iter()
            .filter(|&&a| a >= first_int && a < end_int)
            .count() as u64;
        let width = end_int - first_int;
        out.push(PdfBin {
            lower_px: w[0],
            upper_px: w[1],
            width_px: width,
            centre_px: (w[0] * w[1]).sqrt(),
            count,
            density_per_px: if n > 0.0 {
                count as f64 / (n * width as f64)
            } else {
                0.0
            },
        });
    }
    out
}

/// Mean, standard deviation (ddof = 1) and half-width of the two-sided 95 % confidence
/// interval of the mean (Student t with `n − 1` degrees of freedom) of `values`. With one
/// value the deviation and half-width are NaN (no spread can be estimated), never 0.
pub fn mean_band(values: &[f64]) -> (f64, f64, f64) {
    let n = values.len();
    if n == 0 {
        return (f64::NAN, f64::NAN, f64::NAN);
    }
    let mean = values.iter().sum::<f64>() / n as f64;
    if n == 1 {
        return (mean, f64::NAN, f64::NAN);
    }
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    let sd = var.sqrt();
    (mean, sd, student_t_975(n - 1) * sd / (n as f64).sqrt())
}

pub use crate::resample::student_t_975;

/// Central finite differences `dy/dx` at each point (one-sided at the ends); NaN where
/// two abscissae coincide or fewer than two points are given.
pub fn derivative(x: &[f64], y: &[f64]) -> Vec<f64> {
    let n = x.len();
    (0..n)
        .map(|i| {
            if n < 2 {
                return f64::NAN;
            }
            let (a, b) = if i == 0 {
                (0, 1)
            } else if i + 1 == n {
                (n - 2, n - 1)
            } else {
                (i - 1, i + 1)
            };
            let dx = x[b] - x[a];
            if dx == 0.0 {
                f64::NAN
            } else {
                (y[b] - y[a]) / dx
            }
        })
        .collect()
}

/// The small-load law `A_c/L² = κ W/W₀` fitted to ensemble means: least squares through the
/// origin over the loads `0 < W/W₀ ≤ max_load`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AreaLoadSlope {
    /// `κ = Σ wᵢ aᵢ / Σ wᵢ²`.
    pub kappa: f64,
    /// Half-width of κ's 95 % band if every load's mean moved by its own half-width together
    /// (the loads of one realization are correlated, so this bounds the independent case).
    pub kappa_band: f64,
    /// `aᵢ/wᵢ` at the lowest and the highest load of the fit: κ drifts down with load.
    pub kappa_at_lowest: f64,
    pub kappa_at_highest: f64,
    pub lowest_load: f64,
    pub highest_load: f64,
    pub loads: usize,
}

/// [`AreaLoadSlope`] of mean areas `area` (with 95 % half-widths `band`) at loads `w`; `None`
/// when no load lies in `(0, max_load]` or an area there is not finite. Without a band at
/// one of those loads (fewer than 5 realizations), κ has none either (`kappa_band` NaN).
pub fn area_load_slope(
    w: &[f64],
    area: &[f64],
    band: &[f64],
    max_load: f64,
) -> Option<AreaLoadSlope> {
    let kept: Vec<usize> = (0..w.len().min(area.len()).min(band.len()))
        .filter(|&i| w[i] > 0.0 && w[i] <= max_load)
        .collect();
    if kept.is_empty() || kept.iter().any(|&i| !area[i].is_finite()) {
        return None;
    }
    let ww: f64 = kept.iter().map(|&i| w[i] * w[i]).sum();
    let slope = |v: &[f64]| kept.iter().map(|&i| w[i] * v[i]).sum::<f64>() / ww;
    let lo = *kept.iter().min_by(|&&a, &&b| w[a].total_cmp(&w[b]))?;
    let hi = *kept.iter().max_by(|&&a, &&b| w[a].total_cmp(&w[b]))?;
    Some(AreaLoadSlope {
        kappa: slope(area),
        kappa_band: if kept.iter().all(|&i| band[i].is_finite()) {
            slope(band)
        } else {
            f64::NAN
        },
        kappa_at_lowest: area[lo] / w[lo],
        kappa_at_highest: area[hi] / w[hi],
        lowest_load: w[lo],
        highest_load: w[hi],
        loads: kept.len(),
    })
}

/// Two-sample Kolmogorov–Smirnov distance `sup_x |F_a(x) − F_b(x)|` between the empirical
/// distribution functions of two samples (ties handled: both functions are evaluated after
/// every occurrence of a value). 0 when either sample is empty.
pub fn ks_two_sample(a: &[f64], b: &[f64]) -> f64 {
    if a.is_empty() || b.is_empty() {
        return 0.0;
    }
    let mut a = a.to_vec();
    let mut b = b.to_vec();
    a.sort_by(f64::total_cmp);
    b.sort_by(f64::total_cmp);
    let (n, m) = (a.len() as f64, b.len() as f64);
    let (mut i, mut j, mut d) = (0usize, 0usize, 0.0f64);
    while i < a.len() || j < b.len() {
        // The next distinct value of the union, then every copy of it in both samples.
        let x = match (a.get(i), b.get(j)) {
            (Some(&u), Some(&v)) => u.min(v),
            (Some(&u), None) => u,
            (None, Some(&v)) => v,
            (None, None) => break,
        };
        while i < a.len() && a[i] <= x {
            i += 1;
        }
        while j < b.len() && b[j] <= x {
            j += 1;
        }
        d = d.max((i as f64 / n - j as f64 / m).abs());
    }
    d
}

/// Asymptotic 95 % critical value of the two-sample KS distance for sample sizes `n` and
/// `m`: `c(0.05) sqrt((n + m)/(n m))` with `c(0.05) = sqrt(−ln(0.025)/2) = 1.3581`. Two
/// samples of one distribution exceed it with probability ≈ 5 % (continuous data; discrete
/// data exceed it less often, so it is conservative). Infinite for an empty sample.
pub fn ks_critical_95(n: usize, m: usize) -> f64 {
    if n == 0 || m == 0 {
        return f64::INFINITY;
    }
    let c = (-(0.025f64).ln() / 2.0).sqrt();
    c * ((n + m) as f64 / (n as f64 * m as f64)).sqrt()
}

#[cfg(test)]
mod tests {
    #[test]
    fn nearest_in_log_is_nearest_by_ratio_not_by_difference() {
        let loads = [0.001, 0.01, 0.1];
        // 0.004 is nearer to 0.001 by difference but to 0.01 by ratio (2.5 < 4).
        assert_eq!(nearest_in_log(&loads, 0.004), Some(1));
        assert_eq!(nearest_in_log(&loads, 0.002), Some(0));
        assert_eq!(nearest_in_log(&loads, 5.0), Some(2));
        // Non-positive values are never chosen; none left gives None.
        assert_eq!(nearest_in_log(&[0.0, -1.0, 0.5], 1e-3), Some(2));
        assert_eq!(nearest_in_log(&[0.0, -1.0], 1.0), None);
    }

    use super::*;

    #[test]
    fn wear_measures_by_hand() {
        let areas = [1u64, 1, 2, 4, 8];
        let w = wear_at(&areas, 1.5);
        assert_eq!(w.k_archard, 3.0 / 5.0);
        assert_eq!(w.k_upscaled, 14.0 / 16.0);
        assert_eq!(w.area_above_px, 14.0);
        let w = wear_at(&areas, 8.0);
        assert_eq!((w.k_archard, w.k_upscaled), (0.0, 0.0));
        let w = wear_at(&areas, 0.0);
        assert_eq!((w.k_archard, w.k_upscaled), (1.0, 1.0));
        assert_eq!(wear_at(&[], 1.0).k_upscaled, 0.0);
    }

    #[test]
    fn area_load_slope_recovers_a_linear_law_and_its_drift() {
        // Exactly linear: κ = 2.3 at every load; the band of a band proportional to w is its
        // constant. Loads above the cut and at zero are ignored.
        let w = [0.0, 0.001, 0.01, 0.05, 0.2];
        let a: Vec<f64> = w
            .iter()
            .map(|x| 2.3 * x + if *x > 0.1 { 1.0 } else { 0.0 })
            .collect();
        let band: Vec<f64> = w.iter().map(|x| 0.1 * x).collect();
        let s = area_load_slope(&w, &a, &band, 0.06).unwrap();
        assert!((s.kappa - 2.3).abs() < 1e-14, "{s:?}");
        assert!((s.kappa_band - 0.1).abs() < 1e-15);
        assert_eq!((s.loads, s.lowest_load, s.highest_load), (3, 0.001, 0.05));
        // a = w (2 − 10 w): κ(w) falls with load; the fit by hand.
        let a: Vec<f64> = w.iter().map(|x| x * (2.0 - 10.0 * x)).collect();
        let s = area_load_slope(&w, &a, &band, 0.06).unwrap();
        let (num, den) = w[1..4].iter().fold((0.0, 0.0), |(n, d), x| {
            (n + x * x * (2.0 - 10.0 * x), d + x * x)
        });
        assert!((s.kappa - num / den).abs() < 1e-14);
        assert!(
            (s.kappa_at_lowest - 1.99).abs() < 1e-12 && (s.kappa_at_highest - 1.5).abs() < 1e-12
        );
        // Nothing in range, or a NaN area in range: no fit; a NaN band: κ without a band.
        assert_eq!(area_load_slope(&w, &a, &band, 1e-4), None);
        let mut nan = a.clone();
        nan[2] = f64::NAN;
        assert_eq!(area_load_slope(&w, &nan, &band, 0.06), None);
        let mut no_band = band.clone();
        no_band[2] = f64::NAN;
        let s = area_load_slope(&w, &a, &no_band, 0.06).unwrap();
        assert!((s.kappa - num / den).abs() < 1e-14 && s.kappa_band.is_nan());
    }

    #[test]
    fn ccdf_steps_by_hand() {
        assert_eq!(
            ccdf_steps(&[3, 1, 3, 2]),
            vec![(1, 0.75), (2, 0.5), (3, 0.0)]
        );
    }

    #[test]
    fn binned_pdf_integrates_to_one_over_integers() {
        let areas: Vec<u64> = (1..=500u64).map(|k| 1 + (k * k) % 997).collect();
        let bins = log_binned_pdf(&areas, &log_edges(1.0, 997.0, 20));
        let total: f64 = bins
            .iter()
            .map(|b| b.density_per_px * b.width_px as f64)
            .sum();
        assert!((total - 1.0).abs() < 1e-12, "{total}");
        // Bins partition the integers 1..=997 without overlap.
        let widths: u64 = bins.iter().map(|b| b.width_px).sum();
        assert_eq!(widths, 997);
    }

    #[test]
    fn student_t_quantiles() {
        assert!((student_t_975(1) - 12.7062).abs() < 1e-4);
        assert!((student_t_975(31) - 2.0395).abs() < 2e-4);
        assert!((student_t_975(120) - 1.9799).abs() < 2e-4);
        assert!((student_t_975(100_000) - 1.96).abs() < 1e-4);
        let (m, sd, half) = mean_band(&[1.0, 2.0, 3.0]);
        assert_eq!((m, sd), (2.0, 1.0));
        assert!((half - 4.302_652_729_749_464 / 3f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn derivative_of_a_line_and_a_parabola() {
        let x = [0.0, 1.0, 3.0, 4.0];
        let d = derivative(&x, &x.map(|v| 2.0 * v + 1.0));
        assert!(d.iter().all(|&v| (v - 2.0).abs() < 1e-15));
        let d = derivative(&[0.0, 1.0, 2.0], &[0.0, 1.0, 4.0]);
        assert_eq!(d[1], 2.0);
    }

    #[test]
    fn ks_two_sample_matches_a_brute_force_supremum_with_ties() {
        let mut state = 12345u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 33) % 40
        };
        for trial in 0..200 {
            let n = 1 + trial % 37;
            let m = 1 + (trial * 7) % 23;
            let a: Vec<f64> = (0..n).map(|_| next() as f64).collect();
            let b: Vec<f64> = (0..m).map(|_| (next() + trial as u64 % 5) as f64).collect();
            let cdf =
                |s: &[f64], x: f64| s.iter().filter(|&&v| v <= x).count() as f64 / s.len() as f64;
            let brute = a
                .iter()
                .chain(&b)
                .map(|&x| (cdf(&a, x) - cdf(&b, x)).abs())
                .fold(0.0, f64::max);
            assert!(
                (ks_two_sample(&a, &b) - brute).abs() < 1e-15,
                "trial {trial}"
            );
            assert_eq!(ks_two_sample(&a, &b), ks_two_sample(&b, &a));
        }
        assert_eq!(ks_two_sample(&[1.0, 2.0, 2.0], &[2.0, 1.0, 2.0]), 0.0);
        assert_eq!(ks_two_sample(&[1.0, 2.0], &[3.0, 4.0, 5.0]), 1.0);
        assert_eq!(ks_two_sample(&[], &[1.0]), 0.0);
    }

    #[test]
    fn ks_critical_value_is_the_asymptotic_formula() {
        // Kolmogorov's c(0.05) = 1.35810 (tables); equal sizes n: c·sqrt(2/n).
        assert!((ks_critical_95(100, 100) - 1.358_101 * (0.02f64).sqrt()).abs() < 1e-6);
        assert!(ks_critical_95(0, 5).is_infinite());
    }
}
