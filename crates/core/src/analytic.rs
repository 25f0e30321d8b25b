//! Closed-form wear models: Archard's multi-asperity law and the plateau + power-law
//! cluster-area model of the paper (Appendix A), in forms that stay accurate in double
//! precision everywhere, including the removable singularities at α = 1 and α = 2.
//!
//! **The model** (A.1): `p_PL(A) = C` on `[0, A_s]`, `C (A/A_s)^(−α)` on `(A_s, A_m]`, 0 above
//! `A_m`, with `C` normalising it. With `ℓ_m = ln(A_m/A_s)`, `ε = 1 − α`, `η = 2 − α` and
//! `E(e, x) = expm1(e x)/e` (`E(0, x) = x`, continuous in `e`):
//! - `C = 1 / (A_s (1 + E(ε, ℓ_m)))` (A.2; the printed form `(1−α)/(A_s^α A_m^(1−α) − α A_s)`
//!   is the same thing, singular-looking at α = 1);
//! - first moment `D = ∫ A p_PL dA = C A_s² (½ + E(η, ℓ_m))` (the printed (A.4) has `A_s`
//!   where `A_s²/2` belongs: VALIDATION.md §6.4);
//! - Archard's coefficient (A.3), the number fraction of clusters larger than `A*`:
//!   `K_PL = 1 − (A*/A_s)/(1 + E(ε, ℓ_m))` for `A* ≤ A_s`,
//!   `K_PL = (A*/A_s)^ε E(ε, ℓ*) / (1 + E(ε, ℓ_m))` for `A_s < A* ≤ A_m` (`ℓ* = ln(A_m/A*)`),
//!   0 above `A_m`;
//! - the up-scaled coefficient (A.5), the area fraction in clusters larger than `A*`:
//!   `𝒦_PL = 1 − (A*/A_s)² / (1 + 2 E(η, ℓ_m))` for `A* ≤ A_s`,
//!   `𝒦_PL = (A*/A_s)^η E(η, ℓ*) / (½ + E(η, ℓ_m))` for `A_s < A* ≤ A_m`, 0 above `A_m`.
//!
//! Each follows from integrating `p_PL` and `A p_PL` branch by branch (derivations in
//! docs/CONVENTIONS.md) and is tested against adaptive quadrature to 1e-12.
//!
//! **Limits `A_m → ∞`** (`a_m = f64::INFINITY`): for `α > 1`,
//! `K_PL → 1 − ((α−1)/α)(A*/A_s)` (`A* ≤ A_s`), `(A*/A_s)^(1−α)/α` (`A* ≥ A_s`); `→ 1` for
//! `α ≤ 1`. For `α > 2`, `𝒦_PL → 1 − ((α−2)/α)(A*/A_s)²`, `(2/α)(A*/A_s)^(2−α)`; `→ 1` for
//! `α ≤ 2`.
//!
//! **Archard's law** (eqs. 2–3, table 2): [`ArchardContact`] integrates the sphere
//! population of Archard's contact model, `A_c(W) = (b d/2)((p+1) W/(c d))^(2/(p+1))`, and
//! the wear rate (worn volume per sliding distance) is `R = K ω A_c` with the particle shape
//! factor `ω` (1/3 for hemispherical particles); for rigid-plastic spheres `A_c = W/𝓗` and
//! `R = K ω W/𝓗` (eq. 3). In the elastic regime of a self-affine surface,
//! `A_c = κ W/(E* h'_rms)` at small loads instead (VALIDATION.md §3d, §7).

use thiserror::Error;

/// Invalid model parameters.
#[derive(Debug, Error, PartialEq)]
pub enum ModelError {
    #[error("alpha = {0}: the exponent must be finite")]
    Alpha(f64),
    #[error("A_s = {0}: the plateau end must be finite and > 0")]
    PlateauEnd(f64),
    #[error("A_m = {a_m}: the cut-off must be ≥ A_s = {a_s} (or inf for the limit)")]
    CutOff { a_m: f64, a_s: f64 },
    #[error("A* = {0}: the critical area must be finite and ≥ 0")]
    Threshold(f64),
}

/// The plateau + power-law model of cluster areas (A.1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlateauPowerLaw {
    pub alpha: f64,
    /// End of the plateau, `A_s` (> 0).
    pub a_s: f64,
    /// Cut-off `A_m ≥ A_s`; `f64::INFINITY` for the limit.
    pub a_m: f64,
}

/// `expm1(e x)/e`, continuous through `e = 0` (where it is `x`).
fn e_fn(e: f64, x: f64) -> f64 {
    if e == 0.0 {
        x
    } else {
        let ex = e * x;
        if ex.abs() < 1e-300 {
            // e x underflows relative to e: expm1(ex)/e = x (1 + ex/2 + …).
            x
        } else {
            ex.exp_m1() / e
        }
    }
}

/// `ln(a/b)` for positive `a`, `b`: from the ratio when it neither over- nor underflows
/// (accurate when `a ≈ b`), else as a difference of logarithms (areas spanning more than
/// 10^308, e.g. `A_s = 1e-300`, `A_m = 1e300`).
fn ln_ratio(a: f64, b: f64) -> f64 {
    let ratio = a / b;
    if ratio.is_normal() {
        ratio.ln()
    } else {
        a.ln() - b.ln()
    }
}

/// `(A*/A_s)^e E(e, x) / (plateau + E(e, ℓ))` with `r = A*/A_s`, `ln(A*/A_s) + x = ℓ`: the
/// fraction of the `e`-th tail above `A*` (K with `e = ε`, `plateau = 1`; 𝒦 with `e = η`,
/// `plateau = ½`). Where `e ℓ > 700`, `E(e, ℓ)` would overflow: numerator and denominator
/// are then multiplied by `e·exp(−e ℓ)`, giving `E(−e, x) / (plateau·exp(−e ℓ) + E(−e, ℓ))`,
/// every term bounded. Elsewhere the direct form is used (bit for bit what earlier versions
/// computed), with `r^e` from `ln r` when `r` itself overflows.
fn tail_fraction(e: f64, r: f64, ln_r: f64, x: f64, ell: f64, plateau: f64) -> f64 {
    let fraction = if e > 0.0 && e * ell > 700.0 {
        e_fn(-e, x) / (plateau * (-e * ell).exp() + e_fn(-e, ell))
    } else {
        let r_e = if r.is_normal() {
            r.powf(e)
        } else {
            (e * ln_r).exp()
        };
        r_e * e_fn(e, x) / (plateau + e_fn(e, ell))
    };
    // A fraction; rounding may leave it a few ulps outside.
    fraction.clamp(0.0, 1.0)
}

impl PlateauPowerLaw {
    /// A validated model.
    pub fn new(alpha: f64, a_s: f64, a_m: f64) -> Result<Self, ModelError> {
        if !alpha.is_finite() {
            return Err(ModelError::Alpha(alpha));
        }
        if !(a_s.is_finite() && a_s > 0.0) {
            return Err(ModelError::PlateauEnd(a_s));
        }
        if a_m.is_nan() || a_m < a_s {
            return Err(ModelError::CutOff { a_m, a_s });
        }
        Ok(Self { alpha, a_s, a_m })
    }

    fn check_threshold(a_star: f64) -> Result<(), ModelError> {
        if a_star.is_finite() && a_star >= 0.0 {
            Ok(())
        } else {
            Err(ModelError::Threshold(a_star))
        }
    }

    fn ell_m(&self) -> f64 {
        ln_ratio(self.a_m, self.a_s)
    }

    /// Normalisation `C` (A.2); 0 in the limit `A_m → ∞` with `α ≤ 1`.
    pub fn c(&self) -> f64 {
        let eps = 1.0 - self.alpha;
        if self.a_m.is_infinite() {
            return if self.alpha > 1.0 {
                (self.alpha - 1.0) / (self.alpha * self.a_s)
            } else {
                0.0
            };
        }
        1.0 / (self.a_s * (1.0 + e_fn(eps, self.ell_m())))
    }

    /// Density `p_PL(A)`.
    pub fn density(&self, a: f64) -> f64 {
        if a < 0.0 || a > self.a_m {
            0.0
        } else if a <= self.a_s {
            self.c()
        } else {
            self.c() * (a / self.a_s).powf(-self.alpha)
        }
    }

    /// First moment `D = ∫ A p_PL dA` (the corrected (A.4)); infinite in the limit
    /// `A_m → ∞` with `α ≤ 2`.
    pub fn first_moment(&self) -> f64 {
        let eta = 2.0 - self.alpha;
        if self.a_m.is_infinite() {
            return if self.alpha > 2.0 {
                self.c() * self.a_s * self.a_s * (0.5 + 1.0 / (self.alpha - 2.0))
            } else {
                f64::INFINITY
            };
        }
        self.c() * self.a_s * self.a_s * (0.5 + e_fn(eta, self.ell_m()))
    }

    /// Archard's wear coefficient `K_PL(A*) = P(A > A*)` (A.3).
    pub fn k_archard(&self, a_star: f64) -> Result<f64, ModelError> {
        Self::check_threshold(a_star)?;
        let (alpha, a_s) = (self.alpha, self.a_s);
        let r = a_star / a_s;
        if self.a_m.is_infinite() {
            if alpha <= 1.0 {
                return Ok(1.0);
            }
            return Ok(if a_star <= a_s {
                1.0 - (alpha - 1.0) / alpha * r
            } else {
                r.powf(1.0 - alpha) / alpha
            });
        }
        if a_star >= self.a_m {
            return Ok(0.0);
        }
        let eps = 1.0 - alpha;
        let ell = self.ell_m();
        Ok(if a_star <= a_s {
            1.0 - r / (1.0 + e_fn(eps, ell))
        } else {
            let x = ln_ratio(self.a_m, a_star);
            tail_fraction(eps, r, ln_ratio(a_star, a_s), x, ell, 1.0)
        })
    }

    /// The up-scaled wear coefficient `𝒦_PL(A*) = A_c*/A_c` (A.5).
    pub fn k_upscaled(&self, a_star: f64) -> Result<f64, ModelError> {
        Self::check_threshold(a_star)?;
        let (alpha, a_s) = (self.alpha, self.a_s);
        let r = a_star / a_s;
        if self.a_m.is_infinite() {
            if alpha <= 2.0 {
                return Ok(1.0);
            }
            return Ok(if a_star <= a_s {
                1.0 - (alpha - 2.0) / alpha * r * r
            } else {
                2.0 / alpha * r.powf(2.0 - alpha)
            });
        }
        if a_star >= self.a_m {
            return Ok(0.0);
        }
        let eta = 2.0 - alpha;
        let ell = self.ell_m();
        Ok(if a_star <= a_s {
            1.0 - r * r / (1.0 + 2.0 * e_fn(eta, ell))
        } else {
            let x = ln_ratio(self.a_m, a_star);
            tail_fraction(eta, r, ln_ratio(a_star, a_s), x, ell, 0.5)
        })
    }
}

/// Archard's multi-asperity contact model (paper eq. 2 and table 2): spheres of radius `r`
/// whose summits are spread uniformly in depth with `d` spheres per unit depth (per unit
/// nominal area). A sphere pressed by `z` carries the area `b z` and the load `c z^p`;
/// integrating over the summits above the approach `δ`,
/// `A_c = ∫_0^δ b z d dz = b d δ²/2` and `W = ∫_0^δ c z^p d dz = c d δ^(p+1)/(p+1)`, so
/// `A_c(W) = (b d/2) ((p+1) W/(c d))^(2/(p+1))` and the wear rate is `R = K ω A_c` (eq. 2).
/// Units: lengths in any unit `u`, loads in force `F`; `d` in 1/u, `b` in u, `c` in
/// `F/u^p`, `A_c` in u², `R` in u³/u (volume per sliding distance).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArchardContact {
    /// Contact area per unit interference of one sphere.
    pub b: f64,
    /// Load coefficient of one sphere (`W_1 = c z^p`).
    pub c: f64,
    /// Load exponent.
    pub p: f64,
    /// Summits per unit depth.
    pub d: f64,
}

impl ArchardContact {
    /// Elastic spheres, table 2 as printed: `b = π r`, `c = 4.25 E √r`, `p = 3/2` (`E`
    /// Young's modulus; Hertz's own law with the effective modulus would read
    /// `c = (4/3) E* √r`: the factor is the paper's and only scales the load).
    pub fn elastic(radius: f64, young: f64, density: f64) -> Self {
        Self {
            b: std::f64::consts::PI * radius,
            c: 4.25 * young * radius.sqrt(),
            p: 1.5,
            d: density,
        }
    }

    /// Rigid-plastic spheres, table 2: `b = 2π r`, `c = 2π r 𝓗`, `p = 1` (`𝓗` hardness).
    pub fn plastic(radius: f64, hardness: f64, density: f64) -> Self {
        let tau = 2.0 * std::f64::consts::PI;
        Self {
            b: tau * radius,
            c: tau * radius * hardness,
            p: 1.0,
            d: density,
        }
    }

    /// Real contact area `A_c(W)` (eq. 2 without `K ω`).
    pub fn contact_area(&self, load: f64) -> f64 {
        0.5 * self.b
            * self.d
            * ((self.p + 1.0) * load / (self.c * self.d)).powf(2.0 / (self.p + 1.0))
    }

    /// Archard's wear rate `R = K ω A_c(W)` (eq. 2); for plastic spheres `= K ω W/𝓗` (eq. 3).
    pub fn wear_rate(&self, k: f64, omega: f64, load: f64) -> f64 {
        k * omega * self.contact_area(load)
    }
}

/// Archard's wear rate (worn volume per sliding distance) for a known real contact area:
/// `R = K ω A_c` (eq. 2).
pub fn archard_wear_rate(omega: f64, k: f64, contact_area: f64) -> f64 {
    omega * k * contact_area
}

/// Archard's law for a rigid-plastic contact, eq. (3): `R = K ω W/𝓗` (load over hardness
/// is the real contact area).
pub fn archard_wear_rate_plastic(omega: f64, k: f64, load: f64, hardness: f64) -> f64 {
    omega * k * load / hardness
}
