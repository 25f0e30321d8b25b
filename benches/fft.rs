//! Criterion benchmark of the 2-D real FFT pair (forward r2c + inverse c2r) at
//! N = 512 … 4096: in double precision with 1 and 2 threads, in single precision (the
//! solver's preconditioner) with 1. `make bench-fft` runs it next to FFTW and numpy on the
//! same sizes and writes the comparison tables.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use wearcoef::pages;
use wearcoef::spectral::{Fft2, Real};

fn fft_pair(c: &mut Criterion) {
    pairs::<f64>(c, "fft_pair", &[1, 2]);
    pairs::<f32>(c, "fft_pair_f32", &[1]);
}

fn pairs<T: Real>(c: &mut Criterion, name: &str, thread_counts: &[usize]) {
    let mut group = c.benchmark_group(name);
    group.sample_size(20);
    for n in [512usize, 1024, 2048, 4096] {
        let fft = Fft2::<T>::new(n);
        let mut scratch = fft.make_scratch();
        let mut spectrum = fft.make_spectrum();
        // On huge pages, as the plans' own scratch and spectrum, and as numpy gives the
        // arrays FFTW works on in the same run (benches/fft_numpy.py).
        let mut input = pages::filled(n * n, T::zero());
        for (i, v) in input.iter_mut().enumerate() {
            *v = T::narrow(((i * 7919) % 1013) as f64 / 1013.0 - 0.5);
        }
        let mut output = pages::filled(n * n, T::zero());
        for &threads in thread_counts {
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
