//! Criterion benchmark of periodic cluster labelling (8-connectivity, with areas,
//! perimeters, extents and winding) on 1024² and 4096² maps with 1 % and 20 % of the
//! pixels in contact. The maps are the top 1 % / 20 % of a self-affine surface (H = 0.8,
//! λ_l = n/4, λ_s = 8 px, seed 1), whose clusters look like contact clusters. Each map is
//! also written to `$CARGO_TARGET_DIR/label-maps/map_<n>_<percent>.npy` (bool) so that
//! `make bench-labelling` can time scipy.ndimage.label on the very same maps.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};

mod common;
use wearcoef::clusters::{label, Connectivity};

/// Pixels of the `fraction` highest heights (exactly ⌊fraction · n²⌋ of them).
fn top_fraction(heights: &[f64], fraction: f64) -> Vec<bool> {
    let k = (fraction * heights.len() as f64) as usize;
    let mut sorted = heights.to_vec();
    let idx = heights.len() - k;
    let (_, threshold, _) = sorted.select_nth_unstable_by(idx, |a, b| a.total_cmp(b));
    let threshold = *threshold;
    heights.iter().map(|&h| h >= threshold).collect()
}

fn labelling(c: &mut Criterion) {
    let dir = std::path::PathBuf::from(
        std::env::var("CARGO_TARGET_DIR").unwrap_or_else(|_| "target".into()),
    )
    .join("label-maps");
    std::fs::create_dir_all(&dir).unwrap();
    let mut group = c.benchmark_group("label8");
    group.sample_size(10);
    for n in [1024usize, 4096] {
        let h = common::peers_surface(n);
        for percent in [1u32, 20] {
            let map = top_fraction(&h, percent as f64 / 100.0);
            let array = ndarray::Array2::from_shape_vec((n, n), map.clone()).unwrap();
            ndarray_npy::write_npy(dir.join(format!("map_{n}_{percent}.npy")), &array).unwrap();
            group.bench_with_input(
                BenchmarkId::new(format!("percent{percent}"), n),
                &map,
                |b, map| b.iter(|| label(map, n, n, Connectivity::Eight).unwrap()),
            );
        }
    }
    group.finish();
}

criterion_group!(benches, labelling);
criterion_main!(benches);
