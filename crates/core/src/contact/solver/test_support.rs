//! Helpers of the solver's unit tests: a reproducible sequence and the AVX2 requirement on
//! CI. Imports nothing of the solver, so every part's tests may use it.

/// A reproducible pseudo-random sequence in [−1, 1) (a 64-bit LCG).
pub fn sequence(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

/// Fail, rather than compare the scalar code with itself, when CI runs on an x86-64
/// processor without AVX2 (the dispatch would never take the intrinsics path).
pub fn require_vector_path() {
    #[cfg(target_arch = "x86_64")]
    if std::env::var_os("CI").is_some() {
        assert!(
            std::is_x86_feature_detected!("avx2"),
            "CI is set but this processor has no AVX2: the intrinsics are not tested"
        );
    }
}
