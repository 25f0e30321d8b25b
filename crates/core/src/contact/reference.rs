//! Analytic reference solutions used to validate the contact solver (VALIDATION.md §3).

use std::f64::consts::PI;

/// Hertz contact of a paraboloid of radius `r_curv` pressed with force `load` on a
/// half-space of effective modulus `e_star` (Johnson 1985, ch. 4).
#[derive(Debug, Clone, Copy)]
pub struct Hertz {
    pub load: f64,
    pub r_curv: f64,
    pub e_star: f64,
}

impl Hertz {
    /// Contact radius `a = (3 W R / (4 E*))^(1/3)`.
    pub fn contact_radius(&self) -> f64 {
        (3.0 * self.load * self.r_curv / (4.0 * self.e_star)).cbrt()
    }

    /// Peak pressure `p0 = 3W/(2πa²)`.
    pub fn peak_pressure(&self) -> f64 {
        let a = self.contact_radius();
        3.0 * self.load / (2.0 * PI * a * a)
    }

    /// Pressure at distance `r` from the axis: `p0 sqrt(1 − r²/a²)` inside, 0 outside.
    pub fn pressure(&self, r: f64) -> f64 {
        let a = self.contact_radius();
        if r >= a {
            0.0
        } else {
            self.peak_pressure() * (1.0 - (r / a).powi(2)).sqrt()
        }
    }
}

/// Westergaard's periodic wavy contact: `h = h0 cos(2πx/λ)` on a half-plane (plane strain).
#[derive(Debug, Clone, Copy)]
pub struct Westergaard {
    pub amplitude: f64,
    pub wavelength: f64,
    pub e_star: f64,
}

impl Westergaard {
    /// Full-contact pressure `p* = π E* h0 / λ`.
    pub fn full_contact_pressure(&self) -> f64 {
        PI * self.e_star * self.amplitude / self.wavelength
    }

    /// Contact half-width for mean pressure `mean` (< p*): `a = (λ/π) asin(sqrt(p̄/p*))`.
    pub fn half_width(&self, mean: f64) -> f64 {
        let ratio = (mean / self.full_contact_pressure()).min(1.0);
        self.wavelength / PI * ratio.sqrt().asin()
    }

    /// Pressure at `x` (distance from the crest, any real) for mean pressure `mean`.
    pub fn pressure(&self, x: f64, mean: f64) -> f64 {
        let lambda = self.wavelength;
        let p_star = self.full_contact_pressure();
        if mean >= p_star {
            return mean + p_star * (2.0 * PI * x / lambda).cos();
        }
        let a = self.half_width(mean);
        // Fold x into [−λ/2, λ/2).
        let x = x - lambda * (x / lambda).round();
        if x.abs() >= a {
            return 0.0;
        }
        let sa = (PI * a / lambda).sin();
        let sx = (PI * x / lambda).sin();
        2.0 * mean * (PI * x / lambda).cos() / (sa * sa) * (sa * sa - sx * sx).max(0.0).sqrt()
    }

    /// Mean gap over 2h0 for mean pressure below p*:
    /// `½cos²(πa/λ) + sin²(πa/λ) ln sin(πa/λ)`.
    pub fn mean_gap_over_2h0(&self, mean: f64) -> f64 {
        let s = (PI * self.half_width(mean) / self.wavelength).sin();
        let c2 = 1.0 - s * s;
        0.5 * c2 + s * s * s.ln()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Simpson's rule on a smooth integrand over [a, b] with m (even) intervals.
    fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64, m: usize) -> f64 {
        let h = (b - a) / m as f64;
        let mut s = f(a) + f(b);
        for i in 1..m {
            s += f(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
        }
        s * h / 3.0
    }

    #[test]
    fn hertz_pressure_integrates_to_the_load() {
        let h = Hertz {
            load: 2.5,
            r_curv: 0.7,
            e_star: 3.0,
        };
        let a = h.contact_radius();
        // ∫ p 2πr dr with r = a sin θ removes the edge singularity of the derivative.
        let total = simpson(
            |t| h.pressure(a * t.sin()) * 2.0 * PI * a * t.sin() * a * t.cos(),
            0.0,
            PI / 2.0,
            2000,
        );
        assert!((total / h.load - 1.0).abs() < 1e-10, "{total}");
        assert!(
            (h.peak_pressure() - 2.0 * h.e_star * a / (PI * h.r_curv)).abs()
                < 1e-12 * h.peak_pressure()
        );
    }

    #[test]
    fn westergaard_pressure_averages_to_the_mean() {
        let w = Westergaard {
            amplitude: 0.01,
            wavelength: 1.0,
            e_star: 2.0,
        };
        let p_star = w.full_contact_pressure();
        for ratio in [0.05, 0.2, 0.5, 0.9, 1.3] {
            let mean = ratio * p_star;
            let avg = if ratio < 1.0 {
                // x = a sin θ on [−a, a] removes the square-root edges.
                let a = w.half_width(mean);
                simpson(
                    |t| w.pressure(a * t.sin(), mean) * a * t.cos(),
                    -PI / 2.0,
                    PI / 2.0,
                    4000,
                ) / w.wavelength
            } else {
                simpson(|x| w.pressure(x, mean), -0.5, 0.5, 4000)
            };
            assert!(
                (avg / mean - 1.0).abs() < 1e-9,
                "ratio {ratio}: {avg} vs {mean}"
            );
        }
    }
}
