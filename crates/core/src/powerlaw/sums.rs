//! Sums and integrals of `k^(−α) (ln k)^m`: exact terms below [`EXACT_LIMIT`], then the
//! Euler–Maclaurin continuation with its integral by Gauss–Legendre quadrature in `ln k`.

/// Sums run exactly over `k < EXACT_LIMIT` and continue by Euler–Maclaurin from there, with
/// the end corrections of B₂, B₄ and B₆ (the neglected remainder is about
/// `α(α+1)…(α+6)/(1209600 k⁷)` relative: 1e-16 at α = 2, 1e-13 at α = 10 for `k = 128`).
pub const EXACT_LIMIT: u64 = 128;

/// A range of fewer terms than this is summed exactly wherever it lies (cheaper than the
/// quadrature of the continuation).
const SHORT_RANGE: u64 = 24;

/// `f⁽ʲ⁾(x)` for `j = 0 … 5` of `f = e^{−αu} u^m`, `u = ln(x/k0)`, `m = 0, 1, 2`
/// (`[m][j]`): with `f⁽ʲ⁾ = e^{−αu} x^{−j} P_j(u)`, `P_0 = u^m` and
/// `P_{j+1} = P_j′ − (α + j) P_j` (polynomials of degree ≤ 2 in `u`).
fn derivatives(alpha: f64, x: f64, lk0: f64) -> [[f64; 6]; 3] {
    let u = x.ln() - lk0;
    let w = (-alpha * u).exp();
    let mut out = [[0.0; 6]; 3];
    for (m, row) in out.iter_mut().enumerate() {
        let mut p = [0.0f64; 3];
        p[m] = 1.0;
        let mut scale = w;
        for (j, d) in row.iter_mut().enumerate() {
            *d = scale * (p[0] + u * (p[1] + u * p[2]));
            let s = alpha + j as f64;
            p = [p[1] - s * p[0], 2.0 * p[2] - s * p[1], -s * p[2]];
            scale /= x;
        }
    }
    out
}

/// `ln k` for `k < EXACT_LIMIT`, computed once.
fn ln_table() -> &'static [f64] {
    static TABLE: std::sync::OnceLock<Vec<f64>> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| (0..EXACT_LIMIT).map(|k| (k.max(1) as f64).ln()).collect())
}

/// Gauss–Legendre nodes and weights on [−1, 1], 16 points.
pub(super) const GL_X: [f64; 8] = [
    0.095_012_509_837_637_44,
    0.281_603_550_779_258_9,
    0.458_016_777_657_227_4,
    0.617_876_244_402_643_8,
    0.755_404_408_355_003,
    0.865_631_202_387_831_8,
    0.944_575_023_073_232_6,
    0.989_400_934_991_649_9,
];
pub(super) const GL_W: [f64; 8] = [
    0.189_450_610_455_068_5,
    0.182_603_415_044_923_6,
    0.169_156_519_395_002_5,
    0.149_595_988_816_576_7,
    0.124_628_971_255_533_9,
    0.095_158_511_682_492_78,
    0.062_253_523_938_647_89,
    0.027_152_459_411_754_09,
];

/// `[Σ w_k, Σ w_k u_k, Σ w_k u_k²]` with `w_k = (k/k0)^(−α)`, `u_k = ln(k/k0)`, over the
/// integers `a ≤ k ≤ b` (`b` may be `u64::MAX` for ∞, then `α > 1` is required). `k0 ≥ 1`
/// is a reference scale that keeps the terms in range.
pub(super) fn moments(alpha: f64, a: u64, b: u64, k0: f64) -> [f64; 3] {
    debug_assert!(a >= 1 && a <= b);
    let lk0 = k0.ln();
    let mut s = [0.0f64; 3];
    let table = ln_table();
    // Exact terms a ..= exact_end: all of a short range, else those below EXACT_LIMIT
    // (possibly none).
    let exact_end = if b - a < SHORT_RANGE {
        b
    } else if a >= EXACT_LIMIT {
        a - 1
    } else {
        b.min(EXACT_LIMIT - 1)
    };
    for k in a..=exact_end {
        let lk = if k < EXACT_LIMIT {
            table[k as usize]
        } else {
            (k as f64).ln()
        };
        let u = lk - lk0;
        let w = (-alpha * u).exp();
        s[0] += w;
        s[1] += w * u;
        s[2] += w * u * u;
    }
    if exact_end == b {
        return s;
    }
    // Euler–Maclaurin on [c, b] with c = exact_end + 1:
    // Σ f = ∫ f + (f(c) + f(b))/2 + Σ_p B_2p/(2p)! (f^(2p−1)(b) − f^(2p−1)(c)), p = 1, 2, 3.
    const B: [(usize, f64); 3] = [(1, 1.0 / 12.0), (3, -1.0 / 720.0), (5, 1.0 / 30240.0)];
    let c = (exact_end + 1) as f64;
    let integral = if b == u64::MAX {
        tail_integral(alpha, c, lk0)
    } else {
        log_quadrature(alpha, c, b as f64, lk0)
    };
    let dc = derivatives(alpha, c, lk0);
    for m in 0..3 {
        s[m] += integral[m] + 0.5 * dc[m][0] - B.iter().map(|&(j, b)| b * dc[m][j]).sum::<f64>();
    }
    if b != u64::MAX {
        let db = derivatives(alpha, b as f64, lk0);
        for m in 0..3 {
            s[m] += 0.5 * db[m][0] + B.iter().map(|&(j, b)| b * db[m][j]).sum::<f64>();
        }
    }
    s
}

/// `∫_c^d e^{−α u} u^m dx` (`u = ln(x/k0)`, m = 0, 1, 2) by composite Gauss–Legendre in
/// `t = ln x` (the integrand `e^{(1−α)u} u^m k0` is smooth there).
pub(super) fn log_quadrature(alpha: f64, c: f64, d: f64, lk0: f64) -> [f64; 3] {
    let (t0, t1) = (c.ln(), d.ln());
    // Panels narrow enough that |1 − α| · half-width ≤ 1.5 (error far below 1e-15).
    let panels = (((t1 - t0) * (1.0 - alpha).abs().max(1.0) / 3.0).ceil() as usize).max(1);
    let h = (t1 - t0) / panels as f64;
    let mut s = [0.0f64; 3];
    for p in 0..panels {
        let mid = t0 + (p as f64 + 0.5) * h;
        for (x, w) in GL_X.iter().zip(&GL_W) {
            for sign in [-1.0, 1.0] {
                let t = mid + sign * x * 0.5 * h;
                let u = t - lk0;
                let g = ((1.0 - alpha) * u).exp() * lk0.exp() * w * 0.5 * h;
                s[0] += g;
                s[1] += g * u;
                s[2] += g * u * u;
            }
        }
    }
    s
}

/// `∫_c^∞ e^{−α u} u^m dx` for `α > 1` in closed form: with `β = α − 1` and `v = ln(c/k0)`,
/// `k0 e^{−β v} [1/β, v/β + 1/β², v²/β + 2v/β² + 2/β³]`.
pub(super) fn tail_integral(alpha: f64, c: f64, lk0: f64) -> [f64; 3] {
    let beta = alpha - 1.0;
    let v = c.ln() - lk0;
    let e = (-beta * v).exp() * lk0.exp();
    [
        e / beta,
        e * (v / beta + 1.0 / (beta * beta)),
        e * (v * v / beta + 2.0 * v / (beta * beta) + 2.0 / (beta * beta * beta)),
    ]
}

/// Normalisation of the discrete power law on `[k_min, k_max]` (integers, `1 ≤ k_min ≤
/// k_max`; `k_max = u64::MAX` for ∞, then `α > 1`): `Σ_{k = k_min}^{k_max} k^(−α)`, by the
/// same summation as the fits (exact terms, then the Euler–Maclaurin continuation).
pub fn discrete_normalisation(alpha: f64, k_min: u64, k_max: u64) -> f64 {
    assert!(
        k_min >= 1 && k_min <= k_max,
        "need 1 ≤ k_min ≤ k_max, got [{k_min}, {k_max}]"
    );
    moments(alpha, k_min, k_max, k_min as f64)[0] * (k_min as f64).powf(-alpha)
}

/// Mean and variance of `ln(k/k0)` under the discrete power law on `[a, b]`.
pub(super) fn discrete_log_stats(alpha: f64, a: u64, b: u64) -> (f64, f64) {
    let s = moments(alpha, a, b, a as f64);
    let mean = s[1] / s[0];
    (mean, (s[2] / s[0] - mean * mean).max(0.0))
}

/// Mean and variance of `ln(x/x_min)` under the continuous power law on
/// `[x_min, x_min e^T]` (`T = ∞` allowed for `α > 1`).
pub(super) fn continuous_log_stats(alpha: f64, t: f64) -> (f64, f64) {
    let beta = alpha - 1.0;
    if t.is_infinite() {
        return (1.0 / beta, 1.0 / (beta * beta));
    }
    let z = beta * t;
    if z.abs() < 1e-4 {
        // Series about β = 0: uniform in u on [0, T] plus first-order tilt.
        let mean = t / 2.0 - z * t / 12.0;
        let var = t * t / 12.0 - z * z * t * t / 240.0;
        return (mean, var);
    }
    // E[u] = 1/β − T/(e^{βT} − 1); Var = 1/β² − T² e^{βT}/(e^{βT} − 1)².
    let em1 = z.exp_m1();
    let mean = 1.0 / beta - t / em1;
    let var = 1.0 / (beta * beta) - t * t * (em1 + 1.0) / (em1 * em1);
    (mean, var.max(0.0))
}
