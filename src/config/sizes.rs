//! A study's sizes checked against what a surface and a grid can be, each error naming the
//! field of pipeline.yaml and the range it must lie in.

use super::error::ConfigError;
use super::study::{Study, StudyProfile, MAX_N};

/// A field a generated study must give.
pub(super) fn required<T: Copy>(
    value: Option<T>,
    field: String,
    origin: &str,
) -> Result<T, ConfigError> {
    value.ok_or_else(|| ConfigError::Invalid {
        path: origin.to_string(),
        field,
        value: "(missing)".into(),
        allowed: "a generated study gives it (or the study is `measured`, from topography files)"
            .into(),
    })
}

/// A study's spectrum checked: 0 < H < 1 and λ_l/λ_s > 1; returns (H, λ_l/λ_s).
pub(super) fn checked_spectrum(
    study: &Study,
    base: &str,
    origin: &str,
) -> Result<(f64, f64), ConfigError> {
    let invalid = |field: String, value: f64, allowed: String| ConfigError::Invalid {
        path: origin.to_string(),
        field,
        value: value.to_string(),
        allowed,
    };
    let hurst = required(study.hurst, format!("{base}.hurst"), origin)?;
    if !(hurst.is_finite() && hurst > 0.0 && hurst < 1.0) {
        return Err(invalid(
            format!("{base}.hurst"),
            hurst,
            "the Hurst exponent must lie in the open interval (0, 1)".into(),
        ));
    }
    let ratio = required(
        study.lambda_l_over_lambda_s,
        format!("{base}.lambda_l_over_lambda_s"),
        origin,
    )?;
    if !(ratio.is_finite() && ratio > 1.0) {
        return Err(invalid(
            format!("{base}.lambda_l_over_lambda_s"),
            ratio,
            "λ_l/λ_s must be finite and > 1 (λ_l > λ_s)".into(),
        ));
    }
    Ok((hurst, ratio))
}

/// A study's sizes in one profile checked (roll-off, tolerance, λ_s/Δl, L/λ_l, realizations)
/// and its grid side n = (L/λ_l)·(λ_l/λ_s)·(λ_s/Δl), an even integer in [4, MAX_N]; returns
/// (n, λ_s/Δl, realizations).
pub(super) fn checked_grid_side(
    study: &Study,
    sp: &StudyProfile,
    ratio: f64,
    base: &str,
    pbase: &str,
    origin: &str,
) -> Result<(usize, f64, u32), ConfigError> {
    let invalid = |field: String, value: f64, allowed: String| ConfigError::Invalid {
        path: origin.to_string(),
        field,
        value: value.to_string(),
        allowed,
    };
    let box_ratio = required(
        sp.l_over_lambda_l,
        format!("{pbase}.l_over_lambda_l"),
        origin,
    )?;
    let res = required(
        sp.lambda_s_over_dl,
        format!("{pbase}.lambda_s_over_dl"),
        origin,
    )?;
    let realizations = required(sp.realizations, format!("{pbase}.realizations"), origin)?;
    if let Some(r) = study.rolloff_over_lambda_l {
        if !(r.is_finite() && r > 1.0 && r <= box_ratio) {
            return Err(invalid(
                format!("{base}.rolloff_over_lambda_l"),
                r,
                format!("λ_r/λ_l must lie in (1, L/λ_l = {box_ratio}]"),
            ));
        }
    }
    if let Some(tol) = sp.tolerance {
        if !(tol.is_finite() && tol > 0.0 && tol < 1.0) {
            return Err(invalid(
                format!("{pbase}.tolerance"),
                tol,
                "must lie in (0, 1), or be left out to use solver.tolerance".into(),
            ));
        }
    }
    if !(res.is_finite() && res >= 2.0) {
        return Err(invalid(
            format!("{pbase}.lambda_s_over_dl"),
            res,
            "λ_s/Δl must be ≥ 2: the smallest wavelength needs at least two grid spacings (Nyquist)".into(),
        ));
    }
    if !(box_ratio.is_finite() && box_ratio >= 1.0) {
        return Err(invalid(
            format!("{pbase}.l_over_lambda_l"),
            box_ratio,
            "L/λ_l must be ≥ 1: the largest wavelength cannot exceed the box".into(),
        ));
    }
    if realizations == 0 {
        return Err(invalid(
            format!("{pbase}.realizations"),
            0.0,
            "must be ≥ 1".into(),
        ));
    }
    let n_real = box_ratio * ratio * res;
    let n = n_real.round();
    if (n_real - n).abs() > 1e-9 * n_real.max(1.0) {
        return Err(invalid(
            format!("{pbase}.l_over_lambda_l"),
            box_ratio,
            format!(
                "the grid L/Δl = (L/λ_l)·(λ_l/λ_s)·(λ_s/Δl) = {box_ratio}·{ratio}·{res} = {n_real} is not an integer; choose ratios whose product is an even integer"
            ),
        ));
    }
    let n = n as usize;
    if !n.is_multiple_of(2) || !(4..=MAX_N).contains(&n) {
        return Err(invalid(
            format!("{pbase}.l_over_lambda_l"),
            box_ratio,
            format!("the grid L/Δl = {n} must be an even integer in [4, {MAX_N}]"),
        ));
    }
    Ok((n, res, realizations))
}
