//! Criterion benchmark of the 2-D real FFT pair (forward r2c + inverse c2r) at
//! N = 512 … 4096 with 1 and 2 threads. `make bench-fft` runs it next to numpy's
//! rfft2/irfft2 on the same sizes and writes the comparison table.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use wearcoef::spectral::Fft2;

fn fft_pair(c: &mut Criterion) {
    let mut group = c.benchmark_group("fft_pair");
    group.sample_size(20);
    for n in [512usize, 1024, 2048, 4096] {
        let fft = Fft2::new(n);
        let mut scratch = fft.make_scratch();
        let mut spectrum = fft.make_spectrum();
        let input: Vec<f64> = (0..n * n)
            .map(|i| ((i * 7919) % 1013) as f64 / 1013.0 - 0.5)
            .collect();
        let mut output = vec![0.0; n * n];
        for threads in [1usize, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            group.bench_with_input(
                BenchmarkId::new(format!("threads{threads}"), n),
                &n,
                |b, _| {
                    pool.install(|| {
                        b.iter(|| {
                            fft.forward(&input, &mut spectrum, &mut scratch);
                            fft.inverse(&mut spectrum, &mut output, &mut scratch);
                        })
                    })
                },
            );
        }
    }
    group.finish();
}

criterion_group!(benches, fft_pair);
criterion_main!(benches);
